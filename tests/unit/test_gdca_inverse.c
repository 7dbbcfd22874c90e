/*
 * test_gdca_inverse.c - iGDCA inverse dynamics against recursive Newton-Euler, closed forms and
 * the forward GDCA (round trip).
 *
 * The composite form (ctc_gdca_inverse) must agree with RNEA to 1e-10 relative to the largest
 * driving force on every chain, however long (it stays within 6e-14 up to the 1024-body coil).
 * The paper's literal mobility form (ctc_gdca_inverse_mobility) subtracts mobilities of rigid
 * composites, so its error grows like eps cond(M) (8e-8 on 257 random rods with
 * cond(M) = 1.3e9, 2e-10 on the 16-body coil); it is held to max(1e-9, 1e-13 cond(M)). The round
 * trip forward(inverse(u)) = u carries the forward pass's error: max(1e-10, 1e-14 cond(M)).
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "ctc.h"
#include "linalg.h"
#include "oracle.h"
#include "spatial.h"
#include "model_fixture.h"
#include "gdca_fixture.h"

typedef void (*inverse_fn)(const ctc_model *, ctc_data *, const double *, double *);

static double composite_tolerance(double cond)
{
    (void)cond;
    return 1e-10;
}

static double mobility_tolerance(double cond)
{
    return fmax(1e-9, 1e-13 * cond);
}

static double round_trip_tolerance(double cond)
{
    return fmax(1e-10, 1e-14 * cond);
}

/* f of an inverse vs RNEA, and forward(inverse(u)) vs u when round_trip, at random states */
static void check_inverse(const ctc_model *m, inverse_fn inverse, double (*tolerance)(double),
                          uint64_t seed, int trials, int round_trip)
{
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    int nv = m->nv;
    double *q = calloc((size_t)m->nq + 1, sizeof(double)), *v = calloc((size_t)nv + 1, 8);
    double *u = calloc((size_t)nv + 1, 8), *f = calloc((size_t)nv + 1, 8);
    double *ref = calloc((size_t)nv + 1, 8), *a = calloc((size_t)nv + 1, 8);
    double *mass = calloc((size_t)nv * nv + 1, 8);
    cr_assert(d && o && q && v && u && f && ref && a && mass);
    uint64_t rng = seed;
    for (int t = 0; t < trials; t++) {
        test_random_state(m, &rng, 2.0, q, v);
        for (int i = 0; i < nv; i++) u[i] = test_uniform(&rng, -5, 5);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        inverse(m, d, u, f);
        cr_assert_eq(d->singular_joint, -1);
        ctc_oracle_rnea(m, o, q, v, u, ref);
        ctc_oracle_mass_matrix(m, o, q, mass);
        double cond = nv ? test_cond_spd(mass, nv) : 1.0;
        double err = test_rel_err(f, ref, nv);
        cr_assert(err <= tolerance(cond), "n=%d trial %d: error %.3g > tolerance %.3g (cond %.3g)",
                  m->nbodies, t, err, tolerance(cond), cond);
        if (round_trip) {
            ctc_gdca_forward(m, d, f, a);
            err = test_rel_err(a, u, nv);
            cr_assert(err <= round_trip_tolerance(cond),
                      "n=%d trial %d: round trip %.3g > %.3g (cond %.3g)", m->nbodies, t, err,
                      round_trip_tolerance(cond), cond);
        }
    }
    free(q), free(v), free(u), free(f), free(ref), free(a), free(mass);
    ctc_oracle_free(o);
    ctc_data_free(d);
}

static const int sizes[] = {1, 2, 3, 7, 16, 64, 257};
#define NSIZES ((int)(sizeof sizes / sizeof sizes[0]))

Test(gdca_inverse, matches_rnea_on_random_planar_rod_chains)
{
    for (int i = 0; i < NSIZES; i++) {
        test_chain *c = test_chain_random_planar(sizes[i], 600 + (uint64_t)i, 0, 1);
        ctc_model *m = build(&c->spec);
        check_inverse(m, ctc_gdca_inverse, composite_tolerance, 20 + (uint64_t)i, 2, 0);
        check_inverse(m, ctc_gdca_inverse_mobility, mobility_tolerance, 20 + (uint64_t)i, 1, 0);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(gdca_inverse, matches_rnea_on_random_planar_chains_with_prismatic_joints)
{
    for (int i = 0; i < NSIZES; i++) {
        test_chain *c = test_chain_random_planar(sizes[i], 700 + (uint64_t)i, 1, 0);
        ctc_model *m = build(&c->spec);
        check_inverse(m, ctc_gdca_inverse, composite_tolerance, 21 + (uint64_t)i, 2, 0);
        check_inverse(m, ctc_gdca_inverse_mobility, mobility_tolerance, 21 + (uint64_t)i, 1, 0);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(gdca_inverse, matches_rnea_on_random_spatial_chains_of_every_joint_type)
{
    for (int i = 0; i < NSIZES; i++) {
        test_chain *c = test_chain_random_spatial(sizes[i], 800 + (uint64_t)i, TEST_ALL_JOINTS);
        ctc_model *m = build(&c->spec);
        check_inverse(m, ctc_gdca_inverse, composite_tolerance, 22 + (uint64_t)i, 2, 0);
        check_inverse(m, ctc_gdca_inverse_mobility, mobility_tolerance, 22 + (uint64_t)i, 1, 0);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(gdca_inverse, matches_rnea_on_featherstones_coil, .timeout = 120)
{
    const int n[] = {16, 256, 1024};
    for (int i = 0; i < 3; i++) {
        test_chain *c = test_chain_coil(n[i]);
        ctc_model *m = build(&c->spec);
        check_inverse(m, ctc_gdca_inverse, composite_tolerance, 23, 1, 0);
        check_inverse(m, ctc_gdca_inverse_mobility, mobility_tolerance, 23, 1, 0);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(gdca_inverse, forward_of_inverse_returns_the_commanded_accelerations)
{
    for (int i = 0; i < NSIZES - 1; i++) {
        test_chain *c = test_chain_random_planar(sizes[i], 900 + (uint64_t)i, 1, 1);
        ctc_model *m = build(&c->spec);
        check_inverse(m, ctc_gdca_inverse, composite_tolerance, 24 + (uint64_t)i, 3, 1);
        ctc_model_free(m);
        test_chain_free(c);
        c = test_chain_random_spatial(sizes[i], 950 + (uint64_t)i, TEST_ALL_JOINTS);
        m = build(&c->spec);
        check_inverse(m, ctc_gdca_inverse, composite_tolerance, 25 + (uint64_t)i, 3, 1);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(gdca_inverse, planar_and_spatial_forms_agree)
{
    for (int i = 0; i < 5; i++) {
        test_chain *c = test_chain_random_planar(sizes[i], 1000 + (uint64_t)i, 1, 0);
        double err = fixture_planar_vs_spatial(c, ctc_gdca_inverse, 26 + (uint64_t)i);
        cr_assert(err < 1e-12, "n=%d: planar vs spatial %.3g", sizes[i], err);
        test_chain_free(c);
    }
}

/* two-link arm of uniform rods: f = M(q) u + C(q, v) + G(q), written out */
Test(gdca_inverse, planar_double_pendulum_matches_textbook_equations)
{
    const double l1 = 1.0, l2 = 0.6, m1 = 1.0, m2 = 2.0, g = 9.81;
    test_chain *c = test_chain_rod_pendulum(2, l1, m1);
    double end[3] = {0, -l2, 0};
    ctc_shape_rod(m2, end, &c->bodies[1], NULL, 0);
    ctc_model *m = build(&c->spec);
    ctc_data *d = ctc_data_new(m);
    uint64_t rng = 27;
    for (int t = 0; t < 50; t++) {
        double q[2], v[2], u[2], f[2];
        for (int i = 0; i < 2; i++) {
            q[i] = test_uniform(&rng, -CTC_PI, CTC_PI);
            v[i] = test_uniform(&rng, -3, 3);
            u[i] = test_uniform(&rng, -10, 10);
        }
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_inverse(m, d, u, f);
        double fm[2];
        ctc_gdca_inverse_mobility(m, d, u, fm);
        double lc1 = l1 / 2, lc2 = l2 / 2, i1 = m1 * l1 * l1 / 12, i2 = m2 * l2 * l2 / 12;
        double m11 =
            i1 + i2 + m1 * lc1 * lc1 + m2 * (l1 * l1 + lc2 * lc2 + 2 * l1 * lc2 * cos(q[1]));
        double m12 = i2 + m2 * (lc2 * lc2 + l1 * lc2 * cos(q[1])), m22 = i2 + m2 * lc2 * lc2;
        double h = m2 * l1 * lc2 * sin(q[1]);
        double expect[2] = {
            m11 * u[0] + m12 * u[1] - h * (2 * v[0] * v[1] + v[1] * v[1]) +
                g * (m1 * lc1 * sin(q[0]) + m2 * (l1 * sin(q[0]) + lc2 * sin(q[0] + q[1]))),
            m12 * u[0] + m22 * u[1] + h * v[0] * v[0] + g * m2 * lc2 * sin(q[0] + q[1])};
        cr_assert(test_rel_err(f, expect, 2) < 1e-12, "trial %d: (%.17g, %.17g) vs (%.17g, %.17g)",
                  t, f[0], f[1], expect[0], expect[1]);
        cr_assert(test_rel_err(fm, expect, 2) < 1e-12, "trial %d (mobility form)", t);
    }
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
}

Test(gdca_inverse, leaves_the_shared_body_records_to_the_forward_pass)
{
    /* Eq. 42-43: forward after inverse on the same records equals forward on fresh records */
    test_chain *c = test_chain_random_spatial(9, 1100, TEST_ALL_JOINTS);
    ctc_model *m = build(&c->spec);
    ctc_data *d = ctc_data_new(m);
    int nv = m->nv;
    double q[64], v[64], u[64], f[64], a1[64], a2[64];
    uint64_t rng = 28;
    test_random_state(m, &rng, 2.0, q, v);
    for (int i = 0; i < nv; i++) u[i] = test_uniform(&rng, -5, 5);
    ctc_kinematics(m, d, q, v);
    ctc_handles(m, d);
    ctc_gdca_forward(m, d, u, a1);
    ctc_gdca_inverse(m, d, u, f);
    ctc_gdca_inverse_mobility(m, d, u, f);
    ctc_gdca_forward(m, d, u, a2);
    for (int i = 0; i < nv; i++) cr_assert_eq(a1[i], a2[i], "coordinate %d changed", i);
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
}

/* the composite inverse keeps the state-only parts of its records between calls at one state
 * (data.h, handles_stamp): a second call with other accelerations must give bitwise what a fresh
 * data gives, and a new state (ctc_kinematics, ctc_handles) must not see the old records */
static void check_kept_records(const ctc_model *m, uint64_t seed)
{
    ctc_data *d = ctc_data_new(m), *fresh = ctc_data_new(m);
    int nv = m->nv;
    double *q = calloc((size_t)m->nq + 1, 8), *v = calloc((size_t)nv + 1, 8);
    double *u = calloc((size_t)nv + 1, 8), *f = calloc((size_t)nv + 1, 8);
    double *ref = calloc((size_t)nv + 1, 8);
    cr_assert(d && fresh && q && v && u && f && ref);
    uint64_t rng = seed;
    for (int state = 0; state < 2; state++) {
        test_random_state(m, &rng, 2.0, q, v);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        for (int call = 0; call < 3; call++) {
            for (int i = 0; i < nv; i++) u[i] = test_uniform(&rng, -5, 5);
            ctc_gdca_inverse(m, d, u, f);
            ctc_data_free(fresh);
            fresh = ctc_data_new(m);
            cr_assert_not_null(fresh);
            ctc_kinematics(m, fresh, q, v);
            ctc_handles(m, fresh);
            ctc_gdca_inverse(m, fresh, u, ref);
            for (int i = 0; i < nv; i++) {
                cr_assert(memcmp(&f[i], &ref[i], sizeof f[i]) == 0,
                          "n=%d state %d call %d: f[%d] = %.17g, fresh data %.17g", m->nbodies,
                          state, call, i, f[i], ref[i]);
            }
        }
    }
    ctc_data_free(d), ctc_data_free(fresh);
    free(q), free(v), free(u), free(f), free(ref);
}

Test(gdca_inverse, later_calls_at_one_state_keep_the_composite_inertias_bitwise)
{
    for (int n = 1; n <= 33; n += 8) {
        test_chain *cp = test_chain_random_planar(n, 90 + (uint64_t)n, 1, 0);
        test_chain *cs = test_chain_random_spatial(n, 91 + (uint64_t)n, TEST_ALL_JOINTS);
        ctc_model *mp = build(&cp->spec), *ms = build(&cs->spec);
        check_kept_records(mp, 5 + (uint64_t)n);
        check_kept_records(ms, 6 + (uint64_t)n);
        ctc_model_free(mp), ctc_model_free(ms);
        test_chain_free(cp), test_chain_free(cs);
    }
}
