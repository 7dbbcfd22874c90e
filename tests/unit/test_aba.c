/*
 * test_aba.c - the oracle's articulated-body forward dynamics (src/reference/aba.c) against closed
 * forms (rod pendulum, slider, Lagrangian double pendulum), as the inverse of recursive
 * Newton-Euler on random spatial chains and planar rod chains, against a dense solve with the CRBA
 * mass matrix, and against merged bodies for fixed joints.
 */
#include <criterion/criterion.h>
#include <math.h>

#include "model_fixture.h"
#include "oracle.h"
#include "oracle_fixture.h"

Test(aba, matches_closed_form_rod_pendulum)
{
    /* qdd = (tau - m g L/2 sin q) / (m L^2 / 3) */
    const double mass = 2.0, len = 1.5;
    ctc_model *m;
    ctc_oracle *o = fx_make_rods(1, &mass, &len, &m);
    double worst = 0.0;

    for (int i = 0; i <= 24; i++) {
        double q = -FX_PI + i * (2.0 * FX_PI / 24.0), v = 0.7 * i - 3.0, tau = 4.0 - 0.3 * i, a;
        double want = (tau - mass * FX_G * 0.5 * len * sin(q)) / (mass * len * len / 3.0);
        ctc_oracle_aba(m, o, &q, &v, &tau, &a);
        double err = fabs(a - want) / fmax(1.0, fabs(want));
        worst = fmax(worst, err);
        cr_assert_leq(err, 1e-13, "q = %g: qdd = %.17g, closed form %.17g", q, a, want);
    }
    cr_log_info("aba rod pendulum: worst relative error %.2e (tolerance 1e-13)", worst);
    fx_release(m, o);
}

Test(aba, matches_closed_form_prismatic_slider)
{
    /* qdd = tau / m - 9.81 along +y */
    fx_chain c = {.n = 1, .gravity = {0.0, -FX_G, 0.0}};
    c.bodies[0] = (ctc_body_spec){
        .mass = 3.0, .com = {0.1, 0.2, -0.1}, .inertia = {0.2, 0, 0, 0, 0.3, 0, 0, 0, 0.4}};
    c.joints[0] = (ctc_joint_spec){
        .type = CTC_JOINT_PRISMATIC, .axis = {0.0, 1.0, 0.0}, .location = {0.3, -0.2, 0.1}};
    ctc_model *m;
    ctc_oracle *o = fx_make(&c, CTC_FORM_AUTO, &m);

    for (int i = 0; i <= 10; i++) {
        double q = 0.1 * i - 0.5, v = 0.3 * i - 1.0, tau = 10.0 * i - 20.0, a;
        double want = tau / 3.0 - FX_G;
        ctc_oracle_aba(m, o, &q, &v, &tau, &a);
        cr_assert_leq(fabs(a - want), 1e-13 * fmax(1.0, fabs(want)),
                      "qdd = %.17g, closed form %.17g", a, want);
    }
    fx_release(m, o);
}

Test(aba, matches_lagrangian_double_pendulum)
{
    /* qdd = M^{-1} (tau - h(q, v)) with M and h written out in the fixture */
    const double mass[2] = {1.3, 0.7}, len[2] = {1.1, 0.8};
    ctc_model *m;
    ctc_oracle *o = fx_make_rods(2, mass, len, &m);
    fx_rng rng = {12};
    double worst = 0.0;

    for (int s = 0; s < 200; s++) {
        /* q as for two joints of any type: fx_random_state's spherical branch writes four, and gcc
           -O3 warns about it though the pendulum's joints are revolute */
        double q[8], v[2], tau[2], a[2], mm[4], bias[2], want[2];
        const double zero[2] = {0.0, 0.0};
        fx_random_state(&rng, m, q, v, tau);
        fx_double_pendulum(mass, len, q, v, zero, mm, bias);
        double det = mm[0] * mm[3] - mm[1] * mm[2];
        double r0 = tau[0] - bias[0], r1 = tau[1] - bias[1];
        want[0] = (mm[3] * r0 - mm[1] * r1) / det;
        want[1] = (mm[0] * r1 - mm[2] * r0) / det;
        ctc_oracle_aba(m, o, q, v, tau, a);
        double err = fx_rel_diff(2, a, want);
        worst = fmax(worst, err);
        cr_assert_leq(err, 1e-12, "sample %d: qdd = (%.17g, %.17g), Lagrangian (%.17g, %.17g)", s,
                      a[0], a[1], want[0], want[1]);
    }
    cr_log_info("aba double pendulum: worst relative error %.2e (tolerance 1e-12)", worst);
    fx_release(m, o);
}

/* The forward error of any solve grows with the condition number of M, which reaches 1e7 on
 * random 64-body chains; so the accelerations are held to 1e-10 relative, or to 1e-14 cond(M)
 * (about 50 eps cond(M)) where that is larger. cond(M) is estimated from the CRBA matrix. */
static double accel_tolerance(const ctc_model *m, ctc_oracle *o, const double *q)
{
    static double mm[FX_MAX_NV * FX_MAX_NV];
    ctc_oracle_mass_matrix(m, o, q, mm);
    double cond = fx_condition_number(m->nv, mm);
    cr_assert_gt(cond, 0.0, "M is not positive definite");
    return fmax(1e-10, 1e-14 * cond);
}

Test(aba, inverts_rnea_on_random_spatial_chains)
{
    /* ABA(q, v, RNEA(q, v, a)) = a and RNEA(q, v, ABA(q, v, tau)) = tau */
    const int sizes[] = {1, 2, 3, 7, 16, 64};
    fx_rng rng = {31337};
    double worst_a = 0.0, worst_ratio = 0.0, worst_tau = 0.0;

    for (size_t si = 0; si < sizeof(sizes) / sizeof(sizes[0]); si++) {
        for (int seed = 0; seed < 20; seed++) {
            ctc_model *m;
            ctc_oracle *o = fx_make_random(&rng, sizes[si], CTC_FORM_SPATIAL, &m);
            int nv = m->nv;
            double q[FX_MAX_NQ], v[FX_MAX_NV], a[FX_MAX_NV], tau[FX_MAX_NV];
            double back[FX_MAX_NV];

            fx_random_state(&rng, m, q, v, a);
            double tol = accel_tolerance(m, o, q);
            ctc_oracle_rnea(m, o, q, v, a, tau);
            ctc_oracle_aba(m, o, q, v, tau, back);
            double err = fx_rel_diff(nv, back, a);
            worst_a = fmax(worst_a, err);
            worst_ratio = fmax(worst_ratio, err / tol);
            cr_assert_leq(err, tol, "n = %d, seed %d: ABA(RNEA(a)) - a = %.3e relative > %.1e",
                          sizes[si], seed, err, tol);

            /* the other way round, from random forces: backward stable, 1e-10 always */
            fx_random_state(&rng, m, q, v, tau);
            ctc_oracle_aba(m, o, q, v, tau, a);
            ctc_oracle_rnea(m, o, q, v, a, back);
            err = fx_rel_diff(nv, back, tau);
            worst_tau = fmax(worst_tau, err);
            cr_assert_leq(err, 1e-10, "n = %d, seed %d: RNEA(ABA(tau)) - tau = %.3e relative",
                          sizes[si], seed, err);
            fx_release(m, o);
        }
    }
    cr_log_info("aba(rnea(a)): worst relative error %.2e, worst error/tolerance %.2e; "
                "rnea(aba(tau)): worst %.2e (tolerance 1e-10)",
                worst_a, worst_ratio, worst_tau);
}

Test(aba, inverts_rnea_on_planar_rod_chains)
{
    /* slender rods: singular body inertias, still D = S^T I^A S > 0 */
    fx_rng rng = {4};
    double worst = 0.0;

    for (int n = 1; n <= 16; n++) {
        double mass[FX_MAX_BODIES], len[FX_MAX_BODIES];
        for (int k = 0; k < n; k++) {
            mass[k] = fx_uniform(&rng, 0.1, 10.0);
            len[k] = fx_uniform(&rng, 0.2, 1.5);
        }
        ctc_model *m;
        ctc_oracle *o = fx_make_rods(n, mass, len, &m);
        double q[FX_MAX_NQ], v[FX_MAX_NV], a[FX_MAX_NV], tau[FX_MAX_NV], back[FX_MAX_NV];

        cr_assert_eq(m->form, CTC_FORM_PLANAR);
        fx_random_state(&rng, m, q, v, a);
        ctc_oracle_rnea(m, o, q, v, a, tau);
        ctc_oracle_aba(m, o, q, v, tau, back);
        double err = fx_rel_diff(n, back, a);
        worst = fmax(worst, err);
        cr_assert_leq(err, 1e-10, "n = %d: relative error %.3e", n, err);
        fx_release(m, o);
    }
    cr_log_info("aba/rnea on rod chains: worst relative error %.2e (tolerance 1e-10)", worst);
}

Test(aba, matches_mass_matrix_solve_on_random_spatial_chains)
{
    /* qdd = M^{-1} (tau - RNEA(q, v, 0)) with M from CRBA, by dense Cholesky; tolerance as
     * above */
    const int sizes[] = {1, 2, 3, 7, 16, 64};
    fx_rng rng = {99};
    double worst = 0.0, worst_ratio = 0.0;
    static double mm[FX_MAX_NV * FX_MAX_NV];

    for (size_t si = 0; si < sizeof(sizes) / sizeof(sizes[0]); si++) {
        for (int seed = 0; seed < 10; seed++) {
            ctc_model *m;
            ctc_oracle *o = fx_make_random(&rng, sizes[si], CTC_FORM_SPATIAL, &m);
            int nv = m->nv;
            double q[FX_MAX_NQ], v[FX_MAX_NV], tau[FX_MAX_NV], a[FX_MAX_NV];
            double zero[FX_MAX_NV] = {0}, bias[FX_MAX_NV], want[FX_MAX_NV];

            fx_random_state(&rng, m, q, v, tau);
            double tol = accel_tolerance(m, o, q);
            ctc_oracle_aba(m, o, q, v, tau, a);
            ctc_oracle_rnea(m, o, q, v, zero, bias);
            ctc_oracle_mass_matrix(m, o, q, mm);
            cr_assert(fx_cholesky(nv, mm), "n = %d: M is not positive definite", sizes[si]);
            for (int i = 0; i < nv; i++) {
                want[i] = tau[i] - bias[i];
            }
            fx_cholesky_solve(nv, mm, want, want);
            double err = fx_rel_diff(nv, a, want);
            worst = fmax(worst, err);
            worst_ratio = fmax(worst_ratio, err / tol);
            cr_assert_leq(err, tol, "n = %d, seed %d: relative error %.3e > %.1e", sizes[si], seed,
                          err, tol);
            fx_release(m, o);
        }
    }
    cr_log_info("aba vs CRBA solve: worst relative error %.2e, worst error/tolerance %.2e", worst,
                worst_ratio);
}

Test(aba, fixed_joint_equals_merged_body)
{
    fx_rng rng = {78};
    double worst = fx_check_fixed_equals_merged(&rng, ctc_oracle_aba, 1e-11);
    cr_log_info("aba fixed vs merged: worst relative difference %.2e (tolerance 1e-11)", worst);
}

Test(aba, walks_the_parents_on_a_branched_tree)
{
    /* qdd = M^{-1} (tau - h(q, v)) on a Y tree made by hand from a chain's model (two rods hung
       from one), M and h in closed form from two double pendulums sharing joint 0 */
    const double mass[3] = {1.3, 0.7, 0.9}, len[3] = {1.1, 0.8, 0.6};
    ctc_model *m;
    ctc_oracle *o = fx_make_y_tree(mass, len, &m);
    fx_rng rng = {22};
    double worst = 0.0;

    for (int s = 0; s < 200; s++) {
        double q[12], v[3], tau[3], a[3], mm[9], bias[3], r[3], want[3];
        const double zero[3] = {0.0, 0.0, 0.0};
        fx_random_state(&rng, m, q, v, tau);
        fx_y_tree(mass, len, q, v, zero, mm, bias);
        for (int i = 0; i < 3; i++) r[i] = tau[i] - bias[i];
        cr_assert(fx_cholesky(3, mm), "sample %d: M is not positive definite", s);
        fx_cholesky_solve(3, mm, r, want);
        ctc_oracle_aba(m, o, q, v, tau, a);
        double err = fx_rel_diff(3, a, want);
        worst = fmax(worst, err);
        cr_assert_leq(err, 1e-12,
                      "sample %d: qdd = (%.17g, %.17g, %.17g), closed form (%.17g, %.17g, %.17g)",
                      s, a[0], a[1], a[2], want[0], want[1], want[2]);
    }
    cr_log_info("aba Y tree: worst relative error %.2e (tolerance 1e-12)", worst);
    fx_release(m, o);
}
