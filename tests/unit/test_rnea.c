/*
 * test_rnea.c - the oracle's recursive Newton-Euler inverse dynamics (src/reference/rnea.c) against
 * closed forms (rod pendulum, slider, Lagrangian double pendulum), against Lagrange's equations
 * worked from world-frame energies on random spatial chains, and against merged bodies for fixed
 * joints.
 */
#include <criterion/criterion.h>
#include <math.h>

#include "model_fixture.h"
#include "oracle.h"
#include "oracle_fixture.h"

Test(rnea, matches_closed_form_rod_pendulum)
{
    /* tau = m L^2/3 qdd + m g L/2 sin q for a rod hung from a revolute z joint */
    const double mass = 2.0, len = 1.5;
    ctc_model *m;
    ctc_oracle *o = fx_make_rods(1, &mass, &len, &m);
    double worst = 0.0;

    for (int i = 0; i <= 24; i++) {
        double q = -FX_PI + i * (2.0 * FX_PI / 24.0), v = 0.7 * i - 3.0, a = 1.3 - 0.4 * i, tau;
        double want = mass * len * len / 3.0 * a + mass * FX_G * 0.5 * len * sin(q);
        ctc_oracle_rnea(m, o, &q, &v, &a, &tau);
        double err = fabs(tau - want) / fmax(1.0, fabs(want));
        worst = fmax(worst, err);
        cr_assert_leq(err, 1e-13, "q = %g: tau = %.17g, closed form %.17g", q, tau, want);
    }
    cr_log_info("rnea rod pendulum: worst relative error %.2e (tolerance 1e-13)", worst);
    fx_release(m, o);
}

Test(rnea, matches_closed_form_prismatic_slider)
{
    /* tau = m (qdd - g . a): along +y, and along a tilted axis */
    const double axes[2][3] = {{0.0, 1.0, 0.0}, {1.0, 1.0, 0.0}};
    for (int t = 0; t < 2; t++) {
        fx_chain c = {.n = 1, .gravity = {0.0, -FX_G, 0.0}};
        c.bodies[0] = (ctc_body_spec){
            .mass = 3.0, .com = {0.1, 0.2, -0.1}, .inertia = {0.2, 0, 0, 0, 0.3, 0, 0, 0, 0.4}};
        c.joints[0] = (ctc_joint_spec){.type = CTC_JOINT_PRISMATIC,
                                       .axis = {axes[t][0], axes[t][1], axes[t][2]},
                                       .location = {0.3, -0.2, 0.1}};
        ctc_model *m;
        ctc_oracle *o = fx_make(&c, CTC_FORM_AUTO, &m);
        double ga = -FX_G * axes[t][1] / sqrt(axes[t][0] * axes[t][0] + axes[t][1] * axes[t][1]);

        for (int i = 0; i <= 10; i++) {
            double q = 0.1 * i - 0.5, v = 0.3 * i - 1.0, a = 2.0 - 0.5 * i, tau;
            double want = 3.0 * (a - ga);
            ctc_oracle_rnea(m, o, &q, &v, &a, &tau);
            cr_assert_leq(fabs(tau - want), 1e-13 * fmax(1.0, fabs(want)),
                          "axis %d: tau = %.17g, closed form %.17g", t, tau, want);
        }
        fx_release(m, o);
    }
}

Test(rnea, matches_lagrangian_double_pendulum)
{
    const double mass[2] = {1.3, 0.7}, len[2] = {1.1, 0.8};
    ctc_model *m;
    ctc_oracle *o = fx_make_rods(2, mass, len, &m);
    fx_rng rng = {11};
    double worst = 0.0;

    for (int s = 0; s < 200; s++) {
        /* q as for two joints of any type: fx_random_state's spherical branch writes four, and gcc
           -O3 warns about it though the pendulum's joints are revolute */
        double q[8], v[2], a[2], tau[2], want[2], mm[4];
        fx_random_state(&rng, m, q, v, a);
        fx_double_pendulum(mass, len, q, v, a, mm, want);
        ctc_oracle_rnea(m, o, q, v, a, tau);
        double err = fx_rel_diff(2, tau, want);
        worst = fmax(worst, err);
        cr_assert_leq(err, 1e-13, "sample %d: tau = (%.17g, %.17g), Lagrangian (%.17g, %.17g)", s,
                      tau[0], tau[1], want[0], want[1]);
    }
    cr_log_info("rnea double pendulum: worst relative error %.2e (tolerance 1e-13)", worst);
    fx_release(m, o);
}

Test(rnea, matches_lagrange_equations_on_random_spatial_chains)
{
    /* tau = d/dt dT/dxdot - dT/dx + dV/dx from world-frame energies, central step 1e-5 */
    const int sizes[] = {1, 2, 3, 5, 7, 16};
    fx_rng rng = {2024};
    double worst = 0.0;

    for (size_t si = 0; si < sizeof(sizes) / sizeof(sizes[0]); si++) {
        for (int seed = 0; seed < 4; seed++) {
            ctc_model *m;
            ctc_oracle *o = fx_make_random(&rng, sizes[si], CTC_FORM_SPATIAL, &m);
            double q[FX_MAX_NQ], v[FX_MAX_NV], a[FX_MAX_NV], tau[FX_MAX_NV], want[FX_MAX_NV];

            fx_random_state(&rng, m, q, v, a);
            ctc_oracle_rnea(m, o, q, v, a, tau);
            fx_lagrange_inverse(m, q, v, a, 1e-5, want);
            double err = fx_rel_diff(m->nv, tau, want);
            worst = fmax(worst, err);
            cr_assert_leq(err, 1e-7, "n = %d, seed %d: relative error %.3e", sizes[si], seed, err);
            fx_release(m, o);
        }
    }
    cr_log_info("rnea vs Lagrange: worst relative error %.2e (tolerance 1e-7)", worst);
}

Test(rnea, fixed_joint_equals_merged_body)
{
    /* the fixed joint at the base, in the middle and at the tip of a 5-body chain */
    fx_rng rng = {77};
    double worst = fx_check_fixed_equals_merged(&rng, ctc_oracle_rnea, 1e-12);
    cr_log_info("rnea fixed vs merged: worst relative difference %.2e (tolerance 1e-12)", worst);
}

Test(rnea, normalises_spherical_quaternions)
{
    /* scaling every quaternion by 2.5 changes nothing */
    fx_rng rng = {5};
    ctc_model *m;
    ctc_oracle *o = fx_make_random(&rng, 7, CTC_FORM_SPATIAL, &m);
    double q[FX_MAX_NQ], v[FX_MAX_NV], a[FX_MAX_NV], t1[FX_MAX_NV], t2[FX_MAX_NV];

    fx_random_state(&rng, m, q, v, a);
    ctc_oracle_rnea(m, o, q, v, a, t1);
    for (int k = 0; k < m->nbodies; k++) {
        if (m->joints[k].type == CTC_JOINT_SPHERICAL) {
            for (int i = 0; i < 4; i++) {
                q[m->jnt_qadr[k] + i] *= 2.5;
            }
        }
    }
    ctc_oracle_rnea(m, o, q, v, a, t2);
    cr_assert_leq(fx_max_abs_diff(m->nv, t1, t2), 1e-13 * fmax(1.0, fx_max_abs(m->nv, t1)));
    fx_release(m, o);
}

Test(rnea, free_accepts_null)
{
    ctc_oracle_free(NULL);
}

Test(rnea, walks_the_parents_on_a_branched_tree)
{
    /* the oracle walks lambda(k) (model.h body_parent), not k - 1: on a Y tree made by hand from
       a chain's model, two rods hung from one, it matches the closed form of two double
       pendulums sharing joint 0; read as the chain it was built as, it would not */
    const double mass[3] = {1.3, 0.7, 0.9}, len[3] = {1.1, 0.8, 0.6};
    const int parent[3] = FX_Y_PARENTS;
    fx_chain c;
    fx_rod_y(mass, len, &c);
    ctc_model *m;
    ctc_oracle *o = fx_make(&c, CTC_FORM_AUTO, &m);
    fx_rng rng = {21};
    double worst = 0.0, chain_gap = 0.0;

    for (int s = 0; s < 200; s++) {
        double q[12], v[3], a[3], tau[3], want[3], mm[9];
        fx_random_state(&rng, m, q, v, a);
        fixture_set_parents(m, parent);
        fx_y_tree(mass, len, q, v, a, mm, want);
        ctc_oracle_rnea(m, o, q, v, a, tau);
        double err = fx_rel_diff(3, tau, want);
        worst = fmax(worst, err);
        cr_assert_leq(err, 1e-13,
                      "sample %d: tau = (%.17g, %.17g, %.17g), closed form (%.17g, %.17g, %.17g)",
                      s, tau[0], tau[1], tau[2], want[0], want[1], want[2]);
        const int chain[3] = {-1, 0, 1}; /* the test can fail: the chain's torques differ */
        fixture_set_parents(m, chain);
        ctc_oracle_rnea(m, o, q, v, a, tau);
        chain_gap = fmax(chain_gap, fx_rel_diff(3, tau, want));
    }
    cr_assert_gt(chain_gap, 1e-3, "the chain's parents give the tree's torques");
    cr_log_info("rnea Y tree: worst relative error %.2e (tolerance 1e-13)", worst);
    fx_release(m, o);
}
