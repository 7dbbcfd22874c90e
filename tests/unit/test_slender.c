/*
 * test_slender.c - slender bodies (model.h "slender bodies"): forward dynamics of spatial chains
 * whose accuracy does not depend on a body's own moment ratio (issue 18, part 1).
 *
 * The chain is tests/support's test_chain_slender_rods: 1 kg, 1 m rods, hinges alternating about
 * z and y, whose joint-space mass matrix is well conditioned however thin the rods are. Oracles:
 * a dense solve of M(q) qdd = f - N(q, v) with the composite-rigid-body M and the Newton-Euler N
 * of oracle.h (neither inverts a body's inertia) by Cholesky (tests/support/linalg.h), and, for
 * a whole run, the conservation of energy of a passive chain. Last, the refinement's step rule
 * on a chain whose M(q) is ill conditioned (gdca_refine.h). Errors are max |difference| /
 * max |reference| over the coordinates, the largest over the states. Bounds are the issue's
 * target, the values measured here (gcc -O3) beside them.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "chains.h"
#include "ctc.h"
#include "linalg.h"
#include "loop.h"
#include "loop_oracle.h"
#include "model_fixture.h"
#include "oracle.h"
#include "sim.h"
#include "run_fixture.h"

/* the largest error of ctc_gdca_forward's qdd against the dense solve over `states` random states
   (q uniform, v in [-1, 1] rad/s, f in [-5, 5] N m) of n rods of moment ratio `ratio` */
static double forward_vs_dense(int n, double ratio, int states, ctc_model **out)
{
    test_chain *c = test_chain_slender_rods(n, ratio);
    ctc_model *m = build(&c->spec);
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    cr_assert(d != NULL && o != NULL);
    const int nv = m->nv;
    double *buf = calloc((size_t)m->nq + 6 * (size_t)nv + (size_t)nv * nv, sizeof(double));
    cr_assert(buf != NULL);
    double *q = buf, *v = q + m->nq, *f = v + nv, *a = f + nv, *ref = a + nv, *b = ref + nv,
           *zero = b + nv, *mm = zero + nv;
    uint64_t rng = 1800 + (uint64_t)n;
    double worst = 0;
    for (int s = 0; s < states; s++) {
        test_random_state(m, &rng, 1.0, q, v);
        for (int i = 0; i < nv; i++) f[i] = test_uniform(&rng, -5, 5);
        ctc_oracle_mass_matrix(m, o, q, mm);
        ctc_oracle_rnea(m, o, q, v, zero, b);
        for (int i = 0; i < nv; i++) b[i] = f[i] - b[i];
        cr_assert_eq(test_solve_spd(mm, nv, b, ref), 0, "M(q) is positive definite");
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        cr_assert(test_all_finite(a, nv), "n = %d, ratio %g: qdd is finite", n, ratio);
        worst = fmax(worst, test_rel_err(a, ref, nv));
    }
    free(buf);
    ctc_oracle_free(o);
    ctc_data_free(d);
    test_chain_free(c);
    *out = m;
    return worst;
}

static const double ratios[] = {1, 1e-2, 2e-3, 5e-4, 1e-4, 1e-6, 1.2e-8, 1e-10, 2e-12, 1e-12};

static void check_sweep(int n, int states, double bound)
{
    for (size_t i = 0; i < sizeof ratios / sizeof *ratios; i++) {
        ctc_model *m = NULL;
        double err = forward_vs_dense(n, ratios[i], states, &m);
        /* the kind of each rod: singular at or under CTC_INERTIA_ZERO_REL, slender under
           CTC_SLENDER_RATIO, else plain */
        const int singular = ratios[i] <= CTC_INERTIA_ZERO_REL;
        const int slender = !singular && ratios[i] < CTC_SLENDER_RATIO;
        cr_expect_eq(m->nsingular, singular ? n : 0, "ratio %g", ratios[i]);
        cr_expect_eq(m->nslender, slender ? n : 0, "ratio %g", ratios[i]);
        cr_expect_eq(m->fwd_bodies == m->bodies, !singular && !slender, "ratio %g", ratios[i]);
        cr_expect_lt(err, bound, "n = %d, moment ratio %g: qdd off the dense solve by %g", n,
                     ratios[i], err);
        ctc_model_free(m);
    }
}

Test(slender, forward_matches_the_dense_solve_at_every_moment_ratio_on_2_rods)
{
    check_sweep(2, 40,
                1e-10); /* measured (200 states): <= 1.6e-12 at ratio 1e-2, <= 8.2e-15 slender */
}

Test(slender, forward_matches_the_dense_solve_at_every_moment_ratio_on_16_rods)
{
    check_sweep(16, 40, 1e-10); /* measured (200 states): <= 1.0e-12 at 1e-2, <= 1.2e-13
                                   slender, 8.8e-14 at ratio 1; unaugmented, 1e-2 at 1e-10 */
}

/* 256 rods: the dense solve itself is the limit there (thick rods, ratio 1: 7.2e-11, NOTEBOOK
 * "Slender bodies"), so the bound is 1e-9; unaugmented, 256 rods lost the joint factor's positive
 * definiteness at ratio 1e-6 (NaN). 4096 rods are in bench_accuracy. */
Test(slender, forward_matches_the_dense_solve_at_every_moment_ratio_on_256_rods)
{
    check_sweep(256, 4, 1e-9);
}

/* Where M(q) itself is ill conditioned the refinement converges slowly: 256 rods of moment ratio
 * 1e-10 with masses (and inertias) alternating 1 kg and 1 g, v in [-5, 5] rad/s, cond(M) up to
 * about 3e9, where ABA and the dense solve agree to 9e-12. The step rule (gdca_refine.h) goes on
 * while the corrections shrink and extrapolates a dominant slow mode: every one of 100 states
 * within 1e-9 of the dense solve (measured: worst 1.9e-10, 2 to 6 steps, 2.9 on average). The
 * rule before it stopped once one step shrank the correction by less than 10 times, leaving 8 of
 * these states over 1e-9, the worst at 4.2e-8. */
Test(slender, refinement_converges_on_an_ill_conditioned_chain)
{
    const int n = 256, states = 100;
    test_chain *c = test_chain_slender_rods(n, 1e-10);
    double factor[256];
    for (int k = 0; k < n; k++) factor[k] = k % 2 ? 1e-3 : 1.0;
    test_chain_scale_bodies(c, factor);
    ctc_model *m = build(&c->spec);
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    cr_assert(d != NULL && o != NULL);
    const int nv = m->nv;
    double *buf = calloc((size_t)m->nq + 6 * (size_t)nv + (size_t)nv * nv, sizeof(double));
    cr_assert(buf != NULL);
    double *q = buf, *v = q + m->nq, *f = v + nv, *a = f + nv, *ref = a + nv, *b = ref + nv,
           *zero = b + nv, *mm = zero + nv;
    uint64_t rng = 1800 + (uint64_t)n;
    double worst = 0;
    int over = 0, steps = 0, most = 0;
    for (int s = 0; s < states; s++) {
        test_random_state(m, &rng, 5.0, q, v);
        for (int i = 0; i < nv; i++) f[i] = test_uniform(&rng, -5, 5);
        ctc_oracle_mass_matrix(m, o, q, mm);
        ctc_oracle_rnea(m, o, q, v, zero, b);
        for (int i = 0; i < nv; i++) b[i] = f[i] - b[i];
        cr_assert_eq(test_solve_spd(mm, nv, b, ref), 0, "M(q) is positive definite");
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        cr_assert(test_all_finite(a, nv), "state %d: qdd is finite", s);
        const double err = test_rel_err(a, ref, nv);
        worst = fmax(worst, err);
        over += err > 1e-9;
        steps += d->fwd_refine_done;
        most = d->fwd_refine_done > most ? d->fwd_refine_done : most;
    }
    cr_expect_eq(over, 0, "%d of %d states over 1e-9 of the dense solve, the worst %g", over,
                 states, worst);
    cr_log_info("worst %g, %.2f steps on average, at most %d\n", worst, (double)steps / states,
                most);
    free(buf);
    ctc_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
}

/* A slender body's forward inertia gets CTC_SLENDER_AUGMENT_REL times its largest moment on
   every principal moment (the principal axes kept), its mass nothing; the model's own bodies
   are as given; a loop model's alike. */
Test(slender, only_the_forward_inertia_of_a_slender_body_is_augmented)
{
    test_chain *c = test_chain_slender_rods(3, 1e-6);
    c->bodies[1].inertia[0] = 1.0 / 12; /* body 1: a thick rod */
    ctc_model *m = build(&c->spec);
    cr_assert_eq(m->nslender, 2);
    const double add = CTC_SLENDER_AUGMENT_REL / 12;
    for (int k = 0; k < 3; k++) {
        const ctc_body_spec *b = &m->bodies[k], *fb = &m->fwd_bodies[k];
        cr_expect_eq(fb->mass, b->mass);
        for (int e = 0; e < 9; e++) {
            double want = b->inertia[e] + (k != 1 && e % 4 == 0 ? add : 0);
            cr_expect(fabs(fb->inertia[e] - want) <= 1e-15 * (1.0 / 12), "body %d entry %d", k, e);
        }
    }
    cr_expect_eq(m->bodies[0].inertia[0], 1e-6 / 12, "the model's body is as given");
    ctc_model_free(m);
    test_chain_free(c);

    /* six such rods, bent, closed on the ground by a spherical joint at the tip's end */
    c = test_chain_slender_rods(6, 1e-6);
    ctc_loop_spec loop = {.joint = {.type = CTC_JOINT_SPHERICAL, .location = {1, 0, 0}}};
    c->spec.loop = &loop;
    double q0[6];
    for (int i = 0; i < 6; i++) q0[i] = 0.5 * sin(i + 1.0);
    char err[256] = "";
    cr_assert_eq(test_loop_anchor(&c->spec, q0, -1, loop.anchor, err, sizeof err), CTC_OK, "%s",
                 err);
    m = build(&c->spec);
    cr_expect_eq(m->nslender, 6, "a loop model augments its slender bodies");
    for (int k = 0; k < 6; k++) {
        cr_expect_eq(m->fwd_bodies[k].mass, m->bodies[k].mass);
        cr_expect(fabs(m->fwd_bodies[k].inertia[0] - m->bodies[k].inertia[0] - add) <= 1e-15 / 12,
                  "body %d", k);
    }
    ctc_model_free(m);
    test_chain_free(c);
}

/* A passive 16-rod chain (axial moment 1e-9 kg m^2, moment ratio 1.2e-8) released from a
 * bent pose (q_i = 0.3 sin(i + 1) rad, v_i = cos(i + 1) rad/s) for 3 s, DOPRI5 at rtol 1e-12:
 * energy conserved to 1e-9 relative (sim.h energy_drift), in no more than twice the steps of the
 * same chain of thick rods (ratio 1). */
static long passive_run(double ratio, double *drift)
{
    test_chain *c = test_chain_slender_rods(16, ratio);
    double q0[16], v0[16];
    for (int i = 0; i < 16; i++) q0[i] = 0.3 * sin(i + 1.0), v0[i] = cos(i + 1.0);
    ctc_sim_spec spec = fixture_passive_spec(
        &c->spec, q0, v0,
        (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-12, .atol = 1e-12}, 3.0, 0.01);
    ctc_sim_result *res = fixture_run_done(&spec);
    *drift = res->metrics.energy_drift;
    long steps = res->metrics.steps;
    ctc_sim_result_free(res);
    test_chain_free(c);
    return steps;
}

Test(slender, passive_16_rod_chain_conserves_energy_in_the_steps_of_thick_rods)
{
    double thin_drift, thick_drift;
    long thin = passive_run(1e-9 * 12, &thin_drift), thick = passive_run(1, &thick_drift);
    cr_expect_leq(thin_drift, 1e-9, "energy drift %g", thin_drift);
    cr_expect_leq(thin, 2 * thick, "%ld steps, thick rods %ld", thin, thick);
    cr_log_info("slender: drift %g in %ld steps; thick: drift %g in %ld steps\n", thin_drift, thin,
                thick_drift, thick);
}

/* Slender bodies in a loop (issue 18): tests/support's spatial loop (test_loop_spatial, seed 11;
 * a spherical closing joint, joints n/4, n/2, 3n/4 and the closing joint dependent) with each
 * box's inertia replaced by a rod's, transverse moments 0.0075 kg m^2 and the axial one `ratio`
 * times that. Against the loop oracle (tests/support/loop_oracle.h: the open chain's CRBA M and
 * RNEA h with the closure's multipliers, which inverts no body): forward qdd for random forces on
 * the independent coordinates, and the round trip GDCA(iGDCA(u)) against the commands u, beside
 * the oracle's own round trip (its inverse, then its forward). States: 16 rods near q0 (within
 * 0.01 rad, put onto the closure), 256 rods at q0 with random rates (v in [-1, 1] projected). */
static void slender_loop(int n, double ratio, int states, double *fwd, double *rt, double *ort,
                         int *nslender)
{
    test_loop *l = test_loop_spatial(n, 11);
    cr_assert(l != NULL);
    const double it = 0.3 * 0.3 / 12;
    for (int k = 0; k < n; k++) {
        double *in = l->bodies[k].inertia;
        for (int i = 0; i < 9; i++) in[i] = 0;
        in[0] = ratio * it, in[4] = in[8] = it;
    }
    ctc_model *m = build(&l->spec);
    ctc_data *d = ctc_data_new(m);
    loop_oracle *o = loop_oracle_new(&l->spec);
    cr_assert(d != NULL && o != NULL);
    const int nq = m->nq, nv = m->nv, nvx = m->nvx;
    double *buf = calloc((size_t)nq + (size_t)nv + 6 * (size_t)nvx, sizeof(double));
    cr_assert(buf != NULL);
    double *q = buf, *v = q + nq, *f = v + nv, *a = f + nvx, *ref = a + nvx, *u = ref + nvx,
           *fu = u + nvx, *fo = fu + nvx;
    const double pert = n > 64 ? 0 : 0.01;
    uint64_t rng = 1818;
    *fwd = *rt = *ort = 0;
    for (int t = 0; t < states; t++) {
        for (int i = 0; i < nq; i++) q[i] = l->q0[i] + test_uniform(&rng, -pert, pert);
        for (int i = 0; i < nv; i++) v[i] = test_uniform(&rng, -1, 1);
        char err[256] = "";
        cr_assert_eq(ctc_loop_assemble(m, d, q, v, 1e-12, 20, NULL, err, sizeof err), CTC_OK,
                     "state %d: %s", t, err);
        for (int i = 0; i < nvx; i++) f[i] = u[i] = 0;
        for (int i = 0; i < m->nind; i++) f[m->ind_coord[i]] = test_uniform(&rng, -5, 5);
        for (int i = 0; i < m->nind; i++) u[m->ind_coord[i]] = test_uniform(&rng, -1, 1);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        cr_assert(test_all_finite(a, nvx), "n = %d, ratio %g: qdd is finite", n, ratio);
        cr_assert_eq(loop_oracle_forward(o, q, v, f, ref, NULL), 0);
        *fwd = fmax(*fwd, test_rel_err(a, ref, nvx));
        /* the round trips, over the independent coordinates */
        ctc_gdca_inverse(m, d, u, fu);
        ctc_gdca_forward(m, d, fu, a);
        cr_assert_eq(loop_oracle_inverse(o, q, v, u, fo, NULL), 0);
        cr_assert_eq(loop_oracle_forward(o, q, v, fo, ref, NULL), 0);
        double e = 0, eo = 0, us = 0;
        for (int i = 0; i < m->nind; i++) {
            const int c = m->ind_coord[i];
            e = fmax(e, fabs(a[c] - u[c])), eo = fmax(eo, fabs(ref[c] - u[c]));
            us = fmax(us, fabs(u[c]));
        }
        *rt = fmax(*rt, e / us), *ort = fmax(*ort, eo / us);
    }
    *nslender = m->nslender;
    free(buf);
    loop_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
    test_loop_free(l);
}

/* Slender rods in a loop are augmented and refined as on an open chain (model.h "slender
 * bodies"). Measured (gcc -O3), 16 rods, 20 states: forward 9e-14 to 2.0e-13 against the oracle
 * for ratios 2e-3 to 1e-10 (thick rods 8.1e-14), round trip 7e-13 to 1.0e-12 (the oracle's own
 * 1.2e-12 to 1.7e-12); unaugmented (as before), 1e-10 gave 5.6e-5 and a round trip of 5.5e-2.
 * 256 rods, 3 states: forward 1.8e-11 to 4.7e-11 (thick 1.9e-11), the round trip at the loop's
 * own floor, 1.5e-2 to 6.4e-2 against the oracle's 4e-2 to 4.3e-2 (thick rods: 2.5e-2 against
 * 7.2e-2); unaugmented, 1e-6 gave a round trip of 3.5e3 and 1e-10 a forward error of 5.4e-3. */
Test(slender, slender_rods_in_a_loop_match_the_loop_oracle)
{
    static const double loop_ratios[] = {2e-3, 1e-6, 1e-10};
    for (int i = 0; i < 3; i++) {
        double fwd, rt, ort;
        int ns;
        slender_loop(16, loop_ratios[i], 20, &fwd, &rt, &ort, &ns);
        cr_log_info("16 rods, ratio %g: forward %.1e, round trip %.1e (oracle's %.1e)\n",
                    loop_ratios[i], fwd, rt, ort);
        cr_expect_eq(ns, 16, "ratio %g: every rod is slender", loop_ratios[i]);
        cr_expect_lt(fwd, 1e-11, "16 rods, ratio %g: forward %g", loop_ratios[i], fwd);
        cr_expect_lt(rt, 1e-10, "16 rods, ratio %g: round trip %g", loop_ratios[i], rt);
    }
    double fwd, rt, ort;
    int ns;
    slender_loop(256, 1e-10, 3, &fwd, &rt, &ort, &ns);
    cr_log_info("256 rods, ratio 1e-10: forward %.1e, round trip %.1e (oracle's %.1e)\n", fwd, rt,
                ort);
    cr_expect_lt(fwd, 1e-9, "256 rods: forward %g", fwd);
    cr_expect_lt(rt, 4 * ort, "256 rods: round trip %g, the oracle's %g", rt, ort);
}
