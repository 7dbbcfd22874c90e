/*
 * test_gdca_forward.c - GDCA forward dynamics against the articulated-body oracle and closed forms,
 * in both assembly orders (the balanced tree and the sequential order, gdca_forward_seq.h).
 *
 * Tolerance: 1e-10 relative to the largest acceleration, widened to 1e-14 cond(M) for chains whose
 * mass matrix is ill conditioned (any forward-dynamics method loses that much; see the oracle's
 * own round trip).
 */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "ctc.h"
#include "gdca_forward_joint.h"
#include "gdca_forward_seq.h"
#include "gdca_refine.h"
#include "gdca_tree.h"
#include "linalg.h"
#include "loop_oracle.h"
#include "oracle.h"
#include "spatial.h"
#include "model_fixture.h"
#include "gdca_fixture.h"

static double tolerance(double cond)
{
    return fmax(1e-10, 1e-14 * cond);
}

/* the two assembly orders of an open chain's forward pass (options.h fwd_order) */
static const int orders[] = {CTC_ORDER_TREE, CTC_ORDER_SEQ};
static const char *const order_names[] = {"tree", "sequential"};

/* asserts qacc of GDCA in the given order matches ABA at `trials` random states */
static void forward_vs_aba_in(const ctc_model *m, uint64_t seed, int trials, int order)
{
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    int nv = m->nv;
    double *q = calloc((size_t)m->nq, sizeof(double)), *v = calloc((size_t)nv + 1, sizeof(double));
    double *f = calloc((size_t)nv + 1, sizeof(double)), *a = calloc((size_t)nv + 1, sizeof(double));
    double *ref = calloc((size_t)nv + 1, sizeof(double));
    double *mass = calloc((size_t)nv * nv + 1, sizeof(double));
    cr_assert(d && o && q && v && f && a && ref && mass);
    d->opt.fwd_order = orders[order];
    cr_assert_eq(gdca_forward_order_seq(m, d), order);
    uint64_t rng = seed;
    for (int t = 0; t < trials; t++) {
        test_random_state(m, &rng, 2.0, q, v);
        for (int i = 0; i < nv; i++) f[i] = test_uniform(&rng, -5, 5);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        cr_assert_eq(d->singular_joint, -1);
        ctc_oracle_aba(m, o, q, v, f, ref);
        ctc_oracle_mass_matrix(m, o, q, mass);
        double cond = nv ? test_cond_spd(mass, nv) : 1.0;
        double err = test_rel_err(a, ref, nv);
        cr_assert(err <= tolerance(cond),
                  "%s, n=%d trial %d: error %.3g > tolerance %.3g (cond %.3g)", order_names[order],
                  m->nbodies, t, err, tolerance(cond), cond);
    }
    free(q), free(v), free(f), free(a), free(ref), free(mass);
    ctc_oracle_free(o);
    ctc_data_free(d);
}

/* forward_vs_aba_in in both orders */
static void forward_vs_aba(const ctc_model *m, uint64_t seed, int trials)
{
    for (int order = 0; order < 2; order++) forward_vs_aba_in(m, seed, trials, order);
}

static const int sizes[] = {1, 2, 3, 7, 16, 64, 257};
#define NSIZES ((int)(sizeof sizes / sizeof sizes[0]))

Test(gdca_forward, matches_aba_on_random_planar_rod_chains)
{
    for (int i = 0; i < NSIZES; i++) {
        test_chain *c = test_chain_random_planar(sizes[i], 100 + (uint64_t)i, 0, 1);
        ctc_model *m = build(&c->spec);
        cr_assert_eq(m->form, CTC_FORM_PLANAR);
        forward_vs_aba(m, 7 + (uint64_t)i, sizes[i] > 100 ? 1 : 3);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(gdca_forward, matches_aba_on_random_planar_chains_with_prismatic_joints)
{
    for (int i = 0; i < NSIZES; i++) {
        test_chain *c = test_chain_random_planar(sizes[i], 200 + (uint64_t)i, 1, 0);
        ctc_model *m = build(&c->spec);
        cr_assert_eq(m->form, CTC_FORM_PLANAR);
        forward_vs_aba(m, 8 + (uint64_t)i, sizes[i] > 100 ? 1 : 3);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(gdca_forward, matches_aba_on_random_spatial_chains_of_every_joint_type)
{
    for (int i = 0; i < NSIZES; i++) {
        test_chain *c = test_chain_random_spatial(sizes[i], 300 + (uint64_t)i, TEST_ALL_JOINTS);
        ctc_model *m = build(&c->spec);
        cr_assert_eq(m->form, CTC_FORM_SPATIAL);
        forward_vs_aba(m, 9 + (uint64_t)i, sizes[i] > 100 ? 1 : 3);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(gdca_forward, matches_aba_on_each_joint_type_alone)
{
    for (int t = 0; t < 5; t++) {
        test_chain *c = test_chain_random_spatial(5, 400 + (uint64_t)t, 1u << t);
        ctc_model *m = build(&c->spec);
        forward_vs_aba(m, 10 + (uint64_t)t, 3);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(gdca_forward, matches_aba_on_featherstones_coil, .timeout = 120)
{
    const int n[] = {16, 256, 1024};
    for (int i = 0; i < 3; i++) {
        test_chain *c = test_chain_coil(n[i]);
        ctc_model *m = build(&c->spec);
        cr_assert_eq(m->form, CTC_FORM_SPATIAL);
        forward_vs_aba(m, 11, 1);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(gdca_forward, planar_and_spatial_forms_agree)
{
    for (int i = 0; i < 5; i++) {
        test_chain *c = test_chain_random_planar(sizes[i], 500 + (uint64_t)i, 1, 0);
        double err = fixture_planar_vs_spatial(c, ctc_gdca_forward, 12 + (uint64_t)i);
        cr_assert(err < 1e-11, "n=%d: planar vs spatial %.3g", sizes[i], err);
        test_chain_free(c);
    }
}

/* The joint loads of the forward pass (d->jnt_load: the whole load on body k at joint k) against
 * those of the composite inverse pass (gdca_inverse.c, composite inertias: another formulation)
 * at the forward pass's own accelerations, in both orders, on planar and spatial chains of every
 * joint type: each within 1e-9 of the largest load, and the inverse's forces within 1e-8 of the
 * forward pass's (the round trip; its worst, planar n = 257, is about 1e-9). */
Test(gdca_forward, joint_loads_match_the_composite_inverses_at_the_same_accelerations)
{
    for (int form = 0; form < 2; form++) {
        for (int i = 0; i < NSIZES; i++) {
            test_chain *c =
                form ? test_chain_random_spatial(sizes[i], 520 + (uint64_t)i, TEST_ALL_JOINTS)
                     : test_chain_random_planar(sizes[i], 540 + (uint64_t)i, 1, 0);
            ctc_model *m = build(&c->spec);
            const int nv = m->nv, nl = m->dim * m->nbodies;
            double *q = calloc((size_t)m->nq, sizeof(double));
            double *v = calloc((size_t)nv, sizeof(double)), *f = calloc((size_t)nv, sizeof(double));
            double *a = calloc((size_t)nv, sizeof(double)), *g = calloc((size_t)nv, sizeof(double));
            cr_assert(q && v && f && a && g);
            uint64_t rng = 31 + (uint64_t)i;
            test_random_state(m, &rng, 2.0, q, v);
            for (int k = 0; k < nv; k++) f[k] = test_uniform(&rng, -5, 5);
            for (int order = 0; order < 2; order++) {
                ctc_data *d = ctc_data_new(m);
                cr_assert_not_null(d);
                d->opt.fwd_order = orders[order];
                ctc_kinematics(m, d, q, v);
                ctc_handles(m, d);
                ctc_gdca_forward(m, d, f, a);
                ctc_gdca_inverse(m, d, a, g);
                double big = 0, diff = 0;
                for (int k = 0; k < nl; k++) {
                    big = fmax(big, fabs(d->jnt_load_inv[k]));
                    diff = fmax(diff, fabs(d->jnt_load[k] - d->jnt_load_inv[k]));
                }
                cr_assert(diff <= 1e-9 * big, "%s %s n = %d: loads differ by %.3g of %.3g",
                          form ? "spatial" : "planar", order_names[order], m->nbodies, diff, big);
                cr_assert(test_rel_err(g, f, nv) < 1e-8, "%s %s n = %d: f round trip %.3g",
                          form ? "spatial" : "planar", order_names[order], m->nbodies,
                          test_rel_err(g, f, nv));
                ctc_data_free(d);
            }
            free(q), free(v), free(f), free(a), free(g);
            ctc_model_free(m);
            test_chain_free(c);
        }
    }
}

/* single rod pendulum: qdd = (tau - m g (L/2) sin q) / (m L^2 / 3) */
Test(gdca_forward, single_rod_pendulum_matches_closed_form)
{
    const double mass = 2.5, len = 0.8, g = 9.81;
    test_chain *c = test_chain_rod_pendulum(1, len, mass);
    ctc_model *m = build(&c->spec);
    ctc_data *d = ctc_data_new(m);
    for (int t = 0; t < 20; t++) {
        double q = -3 + 0.3 * t, v = 1.5 - 0.2 * t, tau = 0.7 * t - 4, a;
        ctc_kinematics(m, d, &q, &v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, &tau, &a);
        double expect = (tau - mass * g * len / 2 * sin(q)) / (mass * len * len / 3);
        cr_assert_float_eq(a, expect, 1e-12 * fmax(1, fabs(expect)), "q=%g: %.17g vs %.17g", q, a,
                           expect);
    }
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
}

/* the textbook two-link arm with uniform rods, relative angles from the downward vertical */
static void double_pendulum_terms(const double l[2], const double m[2], const double q[2],
                                  const double v[2], double mass[4], double bias[2])
{
    const double g = 9.81, lc1 = l[0] / 2, lc2 = l[1] / 2;
    const double i1 = m[0] * l[0] * l[0] / 12, i2 = m[1] * l[1] * l[1] / 12;
    double c2 = cos(q[1]), s2 = sin(q[1]);
    mass[0] = i1 + i2 + m[0] * lc1 * lc1 + m[1] * (l[0] * l[0] + lc2 * lc2 + 2 * l[0] * lc2 * c2);
    mass[1] = mass[2] = i2 + m[1] * (lc2 * lc2 + l[0] * lc2 * c2);
    mass[3] = i2 + m[1] * lc2 * lc2;
    double h = m[1] * l[0] * lc2 * s2;
    bias[0] = -h * (2 * v[0] * v[1] + v[1] * v[1]) +
              g * (m[0] * lc1 * sin(q[0]) + m[1] * (l[0] * sin(q[0]) + lc2 * sin(q[0] + q[1])));
    bias[1] = h * v[0] * v[0] + g * m[1] * lc2 * sin(q[0] + q[1]);
}

Test(gdca_forward, planar_double_pendulum_matches_textbook_equations)
{
    const double l[2] = {1.0, 0.6}, mb[2] = {1.0, 2.0};
    test_chain *c = test_chain_rod_pendulum(2, 1.0, 1.0);
    double end[3] = {0, -l[1], 0};
    ctc_shape_rod(mb[1], end, &c->bodies[1], NULL, 0);
    ctc_model *m = build(&c->spec);
    ctc_data *d = ctc_data_new(m);
    uint64_t rng = 13;
    for (int t = 0; t < 50; t++) {
        double q[2], v[2], f[2], a[2], mass[4], bias[2];
        for (int i = 0; i < 2; i++) {
            q[i] = test_uniform(&rng, -CTC_PI, CTC_PI);
            v[i] = test_uniform(&rng, -3, 3);
            f[i] = test_uniform(&rng, -10, 10);
        }
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        double_pendulum_terms(l, mb, q, v, mass, bias);
        double r0 = f[0] - bias[0], r1 = f[1] - bias[1];
        double det = mass[0] * mass[3] - mass[1] * mass[2];
        double expect[2] = {(mass[3] * r0 - mass[1] * r1) / det,
                            (mass[0] * r1 - mass[2] * r0) / det};
        cr_assert(test_rel_err(a, expect, 2) < 1e-12, "trial %d: (%.17g, %.17g) vs (%.17g, %.17g)",
                  t, a[0], a[1], expect[0], expect[1]);
    }
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
}

Test(gdca_forward, joint_loads_balance_gravity_of_a_chain_at_rest)
{
    /* hanging straight down at rest with zero torque: the load at joint k carries the weight of
     * bodies k..n-1, no moment, and nothing accelerates */
    test_chain *c = test_chain_rod_pendulum(6, 0.5, 1.5);
    ctc_model *m = build(&c->spec);
    for (int order = 0; order < 2; order++) {
        ctc_data *d = ctc_data_new(m);
        double q[6] = {0}, v[6] = {0}, f[6] = {0}, a[6];
        d->opt.fwd_order = orders[order];
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        for (int k = 0; k < 6; k++) {
            cr_assert(fabs(a[k]) < 1e-12);
            const double *load = d->jnt_load + 3 * k;
            cr_assert(fabs(load[0]) < 1e-12 && fabs(load[1]) < 1e-12);
            cr_assert_float_eq(load[2], 1.5 * 9.81 * (6 - k), 1e-11);
        }
        ctc_data_free(d);
    }
    ctc_model_free(m);
    test_chain_free(c);
}

/* ---- refinement (gdca_refine.h) ---- */

/* The correction pass alone solves M dq = r: against the mass matrix of the composite-rigid-body
 * oracle, factored by Cholesky, for random r on planar and spatial chains. Its joint loads are
 * those of the bias-free problem, added to d->jnt_load: a zero r must leave them unchanged. */
Test(gdca_forward, correction_pass_solves_the_mass_matrix)
{
    for (int fo = 0; fo < 4; fo++) {
        const int form = fo / 2, order = fo % 2;
        test_chain *c = form ? test_chain_random_spatial(23, 61, TEST_ALL_JOINTS)
                             : test_chain_random_planar(23, 61, 1, 0);
        ctc_model *m = build(&c->spec);
        ctc_data *d = ctc_data_new(m);
        ctc_oracle *o = ctc_oracle_new(m);
        const int nv = m->nv;
        double *q = calloc((size_t)m->nq, sizeof(double)), *v = calloc((size_t)nv, sizeof(double));
        double *f = calloc((size_t)nv, sizeof(double)), *a = calloc((size_t)nv, sizeof(double));
        double *r = calloc((size_t)nv, sizeof(double)), *dq = calloc((size_t)nv, sizeof(double));
        double *ref = calloc((size_t)nv, sizeof(double));
        double *mass = calloc((size_t)nv * (size_t)nv, sizeof(double));
        double *load = calloc((size_t)m->dim * (size_t)m->nbodies, sizeof(double));
        cr_assert(q && v && f && a && r && dq && ref && mass && load);
        d->opt.fwd_order = orders[order];
        uint64_t rng = 62;
        test_random_state(m, &rng, 2.0, q, v);
        for (int i = 0; i < nv; i++) f[i] = test_uniform(&rng, -5, 5);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        d->opt.fwd_refine = 0;
        ctc_gdca_forward(m, d, f, a); /* the factors the correction reuses */

        for (int i = 0; i < m->dim * m->nbodies; i++) load[i] = d->jnt_load[i];
        gdca_forward_correct(m, d, r, dq); /* r = 0 */
        for (int i = 0; i < nv; i++) cr_assert_eq(dq[i], 0.0);
        for (int i = 0; i < m->dim * m->nbodies; i++) cr_assert_eq(d->jnt_load[i], load[i]);

        for (int i = 0; i < nv; i++) r[i] = test_uniform(&rng, -5, 5);
        gdca_forward_correct(m, d, r, dq);
        ctc_oracle_mass_matrix(m, o, q, mass);
        cr_assert_eq(test_solve_spd(mass, nv, r, ref), 0);
        double err = test_rel_err(dq, ref, nv);
        cr_assert(err < 1e-11, "%s, %s: M^-1 r off by %.3g", form ? "spatial" : "planar",
                  order_names[order], err);

        free(q), free(v), free(f), free(a), free(r), free(dq), free(ref), free(mass), free(load);
        ctc_oracle_free(o);
        ctc_data_free(d);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

/* The round trip GDCA(iGDCA(u)) on CTC forces, which nearly cancel gravity and the velocity
 * terms: refined (the default on these chains: one step, the coil being evenly proportioned),
 * it is within a factor 5 of the oracle's own round trip ABA(RNEA(u)), the accuracy the
 * conditioning allows; unrefined it is far worse (coil n = 256: 1.1e-4 against the oracle's
 * 1.7e-8, refined 3.1e-8). */
Test(gdca_forward, refinement_brings_the_round_trip_to_the_oracles_own, .timeout = 120)
{
    const int coil_n[] = {256, 1024};
    for (int so = 0; so < 4; so++) {
        const int s = so / 2, order = so % 2;
        test_chain *c = test_chain_coil(coil_n[s]);
        ctc_model *m = build(&c->spec);
        ctc_data *d = ctc_data_new(m);
        ctc_oracle *o = ctc_oracle_new(m);
        const int nv = m->nv;
        double *q = calloc((size_t)m->nq, sizeof(double)), *v = calloc((size_t)nv, sizeof(double));
        double *u = calloc((size_t)nv, sizeof(double)), *f = calloc((size_t)nv, sizeof(double));
        double *a = calloc((size_t)nv, sizeof(double)), *b = calloc((size_t)nv, sizeof(double));
        cr_assert(q && v && u && f && a && b);
        d->opt.fwd_order = orders[order];
        uint64_t rng = 7;
        test_random_state(m, &rng, 2.0, q, v);
        for (int i = 0; i < nv; i++) u[i] = test_uniform(&rng, -1, 1);

        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_inverse(m, d, u, f);
        ctc_gdca_forward(m, d, f, a);
        cr_assert_eq(d->fwd_refine_done, 1);
        double refined = test_rel_err(a, u, nv);
        d->opt.fwd_refine = 0;
        ctc_gdca_forward(m, d, f, a);
        double plain = test_rel_err(a, u, nv);
        ctc_oracle_rnea(m, o, q, v, u, f);
        ctc_oracle_aba(m, o, q, v, f, b);
        double oracle = test_rel_err(b, u, nv);
        cr_assert(refined <= 5 * oracle + 1e-14, "%s, n = %d: refined %.3g, the oracle's %.3g",
                  order_names[order], coil_n[s], refined, oracle);
        cr_assert(plain > 100 * refined, "%s, n = %d: unrefined %.3g, refined %.3g",
                  order_names[order], coil_n[s], plain, refined);

        free(q), free(v), free(u), free(f), free(a), free(b);
        ctc_oracle_free(o);
        ctc_data_free(d);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

/* Expects got (r x c) to equal want within the rounding of the products that formed them: each
 * entry within 16 eps times bound's (the same product of the operands' absolute values). The
 * typed kernels sum the dense products' non-zero terms in the same order, so without
 * contraction into FMAs (gcc's default in ISO C mode) they give the same numbers; a build that
 * contracts (make bench: -ffp-contract=fast) may round the two shapes of loop differently. */
static void expect_same_products(const char *what, int j, int r, int c, const double *got,
                                 const double *want, const double *bound)
{
    for (int i = 0; i < r * c; i++) {
        cr_expect(fabs(got[i] - want[i]) <= 16 * DBL_EPSILON * bound[i],
                  "%s, joint %d entry %d: %.17g against %.17g", what, j, i, got[i], want[i]);
    }
}

/* y = |A| |x|, A (r x c): the bound of A x's rounding */
static void abs_mulv(int r, int c, const double *a, const double *x, double *y)
{
    for (int i = 0; i < r; i++) {
        y[i] = 0;
        for (int k = 0; k < c; k++) y[i] += fabs(a[i * c + k]) * fabs(x[k]);
    }
}

/* W = E E^T (dim x dim) of a factor E (dim x nc) */
static void factor_product(int dim, int nc, const double *e, double *w)
{
    for (int i = 0; i < dim; i++) {
        for (int j = 0; j < dim; j++) {
            double s = 0;
            for (int c = 0; c < nc; c++) s += e[i * nc + c] * e[j * nc + c];
            w[i * dim + j] = s;
        }
    }
}

/* The joint factors specialised by joint type (planar revolute, spatial revolute and prismatic:
 * D's unit columns picked out of K) against the general D (D^T K D)^-1 D^T, on the D of the
 * kinematics and random symmetric positive definite K */
static void typed_factor_vs_general(const ctc_model *m, uint64_t seed)
{
    const int dim = m->dim;
    ctc_data *d = ctc_data_new(m);
    double *q = calloc((size_t)m->nq, sizeof(double)), *v = calloc((size_t)m->nv, sizeof(double));
    cr_assert(d && q && v);
    uint64_t rng = seed;
    test_random_state(m, &rng, 1.0, q, v);
    ctc_kinematics(m, d, q, v);
    for (int j = 0; j < m->nbodies; j++) {
        double a[36], k[36], e1[36], e2[36], w1[36], w2[36];
        for (int i = 0; i < dim * dim; i++) a[i] = test_uniform(&rng, -1, 1);
        for (int i = 0; i < dim; i++) { /* K = A A^T + 0.1 I */
            for (int c = 0; c < dim; c++) {
                double s = i == c ? 0.1 : 0;
                for (int l = 0; l < dim; l++) s += a[i * dim + l] * a[c * dim + l];
                k[i * dim + c] = s;
            }
        }
        const double *dj = d->jnt_D + dim * dim * j;
        const int nc = dim - m->jnt_nv[j];
        cr_assert_eq(gdca_joint_factor_typed(dim, m->joints[j].type, k, dj, nc, e1), 0);
        cr_assert_eq(gdca_joint_factor(dim, k, dj, nc, e2), 0);
        factor_product(dim, nc, e1, w1);
        factor_product(dim, nc, e2, w2);
        double err = test_rel_err(w1, w2, dim * dim);
        cr_expect(err < 1e-13, "%s joint %d (type %d): E E^T differs by %.3g",
                  dim == 3 ? "planar" : "spatial", j, (int)m->joints[j].type, err);

        /* the products that skip the typed factor's zeros give the dense products' numbers, to
           their rounding where the build contracts (expect_same_products) */
        double x[6], g1[6], g2[6], p1[36], p2[36], bound[36], et_x[6];
        for (int i = 0; i < dim; i++) x[i] = test_uniform(&rng, -1, 1);
        gdca_factor_apply_typed(dim, m->joints[j].type, nc, e1, x, g1);
        gdca_factor_apply(dim, nc, e1, x, g2);
        for (int c = 0; c < nc; c++) { /* |E|^T |x|, then |E| of it */
            et_x[c] = 0;
            for (int i = 0; i < dim; i++) et_x[c] += fabs(e1[i * nc + c]) * fabs(x[i]);
        }
        abs_mulv(dim, nc, e1, et_x, bound);
        expect_same_products("G x", j, dim, 1, g1, g2, bound);
        double pf[6], y1[6], y2[6];
        gdca_joint_map(dim, m->jnt_nv[j], d->jnt_P + 3 * dim * j, x, pf);
        if (dim == 6) { /* in planar form forward_mulv_joint is the dense product itself */
            forward_mulv_joint(dim, m->joints[j].type, k, pf, y1);
            ctc_dense_mulv(dim, dim, k, pf, y2);
            abs_mulv(dim, dim, k, pf, bound);
            expect_same_products("K P f", j, dim, 1, y1, y2, bound);
        }
        const ctc_joint_type t = m->joints[j].type;
        for (int trans = 0; trans < 2; trans++) {
            if (gdca_hinge_u(dim, t) >= 0) {
                gdca_mul_hinge(a, trans, e1, gdca_hinge_u(dim, t), p1);
            } else if (dim == 3 && t == CTC_JOINT_REVOLUTE) {
                gdca_mul_planar_revolute(a, trans, e1, p1);
            } else {
                continue;
            }
            for (int i = 0; i < dim; i++) { /* the dense M E or M^T E */
                for (int c = 0; c < nc; c++) {
                    double sum = 0, abs_sum = 0;
                    for (int l = 0; l < dim; l++) {
                        const double mil = trans ? a[l * dim + i] : a[i * dim + l];
                        sum += mil * e1[l * nc + c];
                        abs_sum += fabs(mil) * fabs(e1[l * nc + c]);
                    }
                    p2[i * nc + c] = sum;
                    bound[i * nc + c] = abs_sum;
                }
            }
            expect_same_products(trans ? "M^T E" : "M E", j, dim, nc, p1, p2, bound);
        }
    }
    ctc_data_free(d);
    free(q), free(v);
}

Test(gdca_forward, joint_factors_by_type_and_their_products_match_the_general_ones)
{
    unsigned hinge = (1u << CTC_JOINT_REVOLUTE) | (1u << CTC_JOINT_PRISMATIC);
    test_chain *cs = test_chain_random_spatial(24, 77, hinge);
    test_chain *cp = test_chain_random_planar(24, 78, 1, 0);
    ctc_model *ms = build(&cs->spec), *mp = build(&cp->spec);
    typed_factor_vs_general(ms, 5);
    typed_factor_vs_general(mp, 6);
    ctc_model_free(ms), ctc_model_free(mp);
    test_chain_free(cs), test_chain_free(cp);
}

/* A new data block takes the library's rules (options.h), and its options, not its state, choose
 * the assembly order: an open chain on one thread takes the sequential order by rule, the tree
 * when told, and a loop model always the tree. */
Test(gdca_forward, new_data_takes_the_default_options_and_they_choose_the_order)
{
    test_chain *c = test_chain_rod_pendulum(8, 0.5, 1.0);
    ctc_model *m = build(&c->spec);
    ctc_data *d = ctc_data_new(m);
    const ctc_options def = ctc_options_default();
    cr_assert_eq(def.fwd_order, CTC_ORDER_AUTO);
    cr_assert_eq(def.fwd_refine, -1);
    cr_assert_eq(def.inv_full, 0);
    cr_assert_eq(def.par_grain, 0);
    cr_assert_eq(d->opt.fwd_order, def.fwd_order);
    cr_assert_eq(d->opt.fwd_refine, def.fwd_refine);
    cr_assert_eq(d->opt.inv_full, def.inv_full);
    cr_assert_eq(d->opt.par_grain, def.par_grain);
    cr_assert_eq(def.par_split, 0);
    cr_assert_eq(d->opt.par_split, def.par_split);

    cr_expect_eq(gdca_forward_order_seq(m, d), 1, "an open chain on one thread: sequential");
    d->opt.fwd_order = CTC_ORDER_TREE;
    cr_expect_eq(gdca_forward_order_seq(m, d), 0, "told the tree");
    d->opt.fwd_order = CTC_ORDER_SEQ;
    cr_expect_eq(gdca_forward_order_seq(m, d), 1, "told the sequential order");
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
}

/* ---- the reference form (gdca.h ctc_gdca_forward_from) ---- */

/* x = M^-1 b by Cholesky (tests/support/linalg.h), then two steps of iterative refinement whose
 * residual b - M x is summed in long double: the dense oracle's own solve is then accurate to
 * the rounding of M and b themselves */
static void dense_solve(const double *mm, int n, const double *b, double *x)
{
    double *r = calloc((size_t)n + 1, sizeof *r), *dx = calloc((size_t)n + 1, sizeof *dx);
    cr_assert(r && dx);
    cr_assert_eq(test_solve_spd(mm, n, b, x), 0, "M(q) is positive definite");
    for (int it = 0; it < 2; it++) {
        for (int i = 0; i < n; i++) {
            long double s = b[i];
            for (int k = 0; k < n; k++) s -= (long double)mm[i * n + k] * x[k];
            r[i] = (double)s;
        }
        cr_assert_eq(test_solve_spd(mm, n, r, dx), 0);
        for (int i = 0; i < n; i++) x[i] += dx[i];
    }
    free(r), free(dx);
}

/* What one reference-form check measured over its states, in the forward pass's order `order`
 * (options.h fwd_order): the largest error of qdd against the
 * dense solve of M(q) qdd = f - N(q, v) (CRBA's M, RNEA's N: oracle.h), with f = tau(u) + delta
 * (delta of 1e-3 .. 1 of max |tau|, tau = ctc_gdca_inverse(u)) and a_ref = u, and with a wrong
 * reference (a_ref = u +- 1e-4 max |qdd|, f_ref still tau(u)), which must miss by that much; the
 * largest difference of d->jnt_load from the composite inverse's loads at the result, relative to
 * the largest load. */
typedef struct from_errors {
    double err, wrong, load;
} from_errors;

static from_errors forward_from_vs_dense(const ctc_model *m, int states, double vmax, uint64_t seed,
                                         int order)
{
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    cr_assert(d != NULL);
    d->opt.fwd_order = order;
    const int nv = m->nv, nl = m->dim * m->nbodies;
    double *buf = calloc((size_t)m->nq + 9 * (size_t)nv + (size_t)nv * nv + 1, sizeof(double));
    cr_assert(d && o && buf);
    double *q = buf, *v = q + m->nq, *u = v + nv, *tau = u + nv, *f = tau + nv, *a = f + nv;
    double *ref = a + nv, *bias = ref + nv, *zero = bias + nv, *uw = zero + nv, *mm = uw + nv;
    from_errors e = {0, INFINITY, 0};
    uint64_t rng = seed;
    for (int s = 0; s < states; s++) {
        test_random_state(m, &rng, vmax, q, v);
        for (int i = 0; i < nv; i++) u[i] = test_uniform(&rng, -5, 5);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_inverse(m, d, u, tau);
        double tmax = 0, scale = pow(10, -3 + s % 4);
        for (int i = 0; i < nv; i++) tmax = fmax(tmax, fabs(tau[i]));
        for (int i = 0; i < nv; i++) f[i] = tau[i] + scale * tmax * test_uniform(&rng, -1, 1);
        ctc_oracle_mass_matrix(m, o, q, mm);
        ctc_oracle_rnea(m, o, q, v, zero, bias);
        for (int i = 0; i < nv; i++) bias[i] = f[i] - bias[i];
        dense_solve(mm, nv, bias, ref);

        ctc_gdca_forward_from(m, d, f, u, tau, a);
        cr_assert(d->singular_joint == -1 && test_all_finite(a, nv), "n = %d: not finite",
                  m->nbodies);
        e.err = fmax(e.err, test_rel_err(a, ref, nv));
        ctc_gdca_inverse(m, d, a, zero); /* its loads at the result; zero is overwritten */
        double big = 0, diff = 0;
        for (int k = 0; k < nl; k++) {
            big = fmax(big, fabs(d->jnt_load_inv[k]));
            diff = fmax(diff, fabs(d->jnt_load[k] - d->jnt_load_inv[k]));
        }
        e.load = fmax(e.load, diff / big);
        for (int i = 0; i < nv; i++) zero[i] = 0;

        /* a wrong reference: f_ref = tau(u) but a_ref off u (a refined model's residual pass
           corrects any reference: nothing to see there) */
        if (gdca_refine_steps_ref(m, d) > 0) {
            e.wrong = NAN;
            continue;
        }
        double rmax = 0;
        for (int i = 0; i < nv; i++) rmax = fmax(rmax, fabs(ref[i]));
        for (int i = 0; i < nv; i++) uw[i] = u[i] + 1e-4 * rmax * (i % 2 ? 1 : -1);
        ctc_gdca_inverse(m, d, u, tau);
        ctc_gdca_forward_from(m, d, f, uw, tau, a);
        e.wrong = fmin(e.wrong, test_rel_err(a, ref, nv));
    }
    free(buf);
    ctc_oracle_free(o);
    ctc_data_free(d);
    return e;
}

/* the checks every reference-form case makes: qdd within bound of the dense solve; the joint
   loads the whole loads, within load_bound of the largest (1e-9 as the literal pass's test above;
   a model with singular or slender bodies has its bodies' loads from the augmented inertias, in
   the literal pass as here: 3e-5 of the largest on 16 rods of ratio 1e-6); and, unless the model
   is refined, a wrong reference off by more than 100 times the bound (so the check can fail) */
static void expect_from(const char *what, const from_errors *e, double bound, double load_bound)
{
    cr_expect_leq(e->err, bound, "%s: qdd off the dense solve by %.3g > %.3g", what, e->err, bound);
    cr_expect_leq(e->load, load_bound, "%s: joint loads off the inverse's by %.3g", what, e->load);
    if (!isnan(e->wrong)) {
        cr_expect_gt(e->wrong, 100 * bound, "%s: a wrong reference still within %.3g", what,
                     e->wrong);
    }
}

/* On random spatial and planar chains of every joint type, n = 2 to 32: qdd of the reference
 * form within 1e-12 of the dense solve up to n = 16 (the level) and 5e-12 at n = 32,
 * where the dense solve's own rounding of M and N (cond(M) up to 5e5 here) is of that order and
 * the literal pass is as far off (measured, gcc -O3: spatial 3.9e-15 (n = 2) to 2.4e-13 (16),
 * 1.0e-12 (32); planar 9.3e-13 (16), 4.2e-12 (32); literal pass 6.0e-13 and 1.0e-12). */
Test(gdca_forward, reference_form_matches_the_dense_solve_on_random_chains)
{
    static const int sizes_from[] = {2, 3, 4, 8, 16, 32};
    for (int form = 0; form < 2; form++) {
        for (int i = 0; i < 6; i++) {
            const int n = sizes_from[i];
            test_chain *c = form ? test_chain_random_spatial(n, 700 + (uint64_t)n, TEST_ALL_JOINTS)
                                 : test_chain_random_planar(n, 720 + (uint64_t)n, 1, 0);
            ctc_model *m = build(&c->spec);
            for (int order = 0; order < 2; order++) {
                from_errors e = forward_from_vs_dense(m, 16, 2.0, 30 + (uint64_t)n, orders[order]);
                char what[64];
                snprintf(what, sizeof what, "%s %s n = %d", form ? "spatial" : "planar",
                         order_names[order], n);
                expect_from(what, &e, n <= 16 ? 1e-12 : 5e-12, 1e-9);
            }
            ctc_model_free(m);
            test_chain_free(c);
        }
    }
}

/* Slender rods (model.h "slender bodies": the bias-free pass solves with augmented inertias and
 * the refinement removes that error, gdca_refine_steps_ref) at moment ratios 1 to 1e-12, on 2,
 * 16 and 256 rods, and a chain of point masses in both forms (every body singular): within
 * 1e-10 of the dense solve, the slender tests' level (test_slender.c; 256 rods: the dense
 * solve's own 3.6e-11). The joint loads of 256 rods: 1.0e-8 of the largest where no body is
 * augmented, 1.1e-4 at ratio 1e-12 (the augmented inertias' loads, expect_from). */
Test(gdca_forward, reference_form_matches_the_dense_solve_on_slender_rods_and_point_masses)
{
    static const double ratios[] = {1, 1e-2, 1e-6, 1e-10, 1e-12};
    static const int rods[] = {2, 16, 256};
    for (int r = 0; r < 3; r++) {
        for (int i = 0; i < 5; i++) {
            test_chain *c = test_chain_slender_rods(rods[r], ratios[i]);
            ctc_model *m = build(&c->spec);
            from_errors e = forward_from_vs_dense(m, rods[r] > 16 ? 4 : 12, 1.0, 90 + (uint64_t)r,
                                                  CTC_ORDER_AUTO);
            char what[64];
            snprintf(what, sizeof what, "%d rods, ratio %g", rods[r], ratios[i]);
            expect_from(what, &e, 1e-10, ratios[i] < 1e-2 ? 5e-4 : 5e-8);
            ctc_model_free(m);
            test_chain_free(c);
        }
    }
    for (int spatial = 0; spatial < 2; spatial++) {
        enum { N = 32 };
        test_chain *c = test_chain_rod_pendulum(N, 1.0, 1.0);
        for (int k = 0; k < N; k++) {
            memset(c->bodies[k].inertia, 0, sizeof c->bodies[k].inertia);
            ctc_v3_set(c->bodies[k].com, 0, -1, 0);
            if (spatial && (k & 1)) ctc_v3_set(c->joints[k].axis, 1, 0, 0);
        }
        ctc_model *m = build(&c->spec);
        cr_assert_eq(m->nsingular, N);
        from_errors e = forward_from_vs_dense(m, 12, 2.0, 77, CTC_ORDER_AUTO);
        expect_from(spatial ? "spatial point masses" : "planar point masses", &e, 1e-10, 5e-4);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

/* Branched trees (Featherstone's autoTree, planar and spatial, branching 2 and 4) in both orders
 * of the bias-free pass (the plan with its raked subtrees, and the sequential order): within
 * 1e-10 of the dense solve. */
Test(gdca_forward, reference_form_matches_the_dense_solve_on_trees)
{
    static const double bfs[] = {2, 4};
    for (int sk = 0; sk < 2; sk++) {
        for (int b = 0; b < 2; b++) {
            test_chain *c = test_auto_tree(48, bfs[b], sk ? 0.3 : 0, 0.9);
            ctc_model *m = build(&c->spec);
            cr_assert_eq(m->chain, 0);
            for (int order = 0; order < 2; order++) {
                from_errors e = forward_from_vs_dense(m, 8, 2.0, 55 + (uint64_t)b, orders[order]);
                char what[80];
                snprintf(what, sizeof what, "autoTree %s bf %g, %s", sk ? "spatial" : "planar",
                         bfs[b], order_names[order]);
                expect_from(what, &e, 1e-10, 1e-9);
            }
            ctc_model_free(m);
            test_chain_free(c);
        }
    }
}

/* A loop model takes the literal pass from either entry point (gdca.h): ctc_gdca_forward_from
 * on the five-bar at its closed q0, with a reference that is not its tau, gives bitwise
 * ctc_gdca_forward's accelerations and loads. */
Test(gdca_forward, reference_form_falls_back_to_the_literal_pass_on_a_loop)
{
    loop_scene *s = loop_scene_five_bar();
    ctc_model *m = build(&s->spec);
    ctc_data *d = ctc_data_new(m);
    cr_assert(d != NULL && m->has_loop);
    const int nvx = m->nvx, nl = m->dim * m->njoints;
    double v[16] = {0}, f[16] = {0}, a[16], b[16], aref[16], fref[16], load[96];
    cr_assert(nvx <= 16 && nl <= 96);
    uint64_t rng = 5;
    for (int i = 0; i < nvx; i++) {
        f[i] = test_uniform(&rng, -5, 5);
        aref[i] = test_uniform(&rng, -5, 5);
        fref[i] = test_uniform(&rng, -5, 5);
    }
    ctc_kinematics(m, d, s->q0, v);
    ctc_handles(m, d);
    ctc_gdca_forward(m, d, f, a);
    memcpy(load, d->jnt_load, (size_t)nl * sizeof *load);
    ctc_gdca_forward_from(m, d, f, aref, fref, b);
    cr_assert(test_all_finite(a, nvx));
    cr_assert_eq(memcmp(a, b, (size_t)nvx * sizeof *a), 0, "accelerations differ");
    cr_assert_eq(memcmp(load, d->jnt_load, (size_t)nl * sizeof *load), 0, "loads differ");
    ctc_data_free(d);
    ctc_model_free(m);
    free(s);
}
