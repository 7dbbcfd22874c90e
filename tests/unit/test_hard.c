/*
 * test_hard.c - numerical hard cases of the dynamics, each against an independent oracle or a
 * closed form: extreme mass and inertia ratios, a nearly massless tip body, high spin rates and
 * a closed chain driven into a singular configuration.
 *
 * Oracles: the articulated-body (ABA) and recursive Newton-Euler (RNEA) algorithms of oracle.h,
 * which share nothing with the GDCA code; the round trip GDCA(iGDCA(u)) = u; conservation of
 * energy in a passive run. Errors are max |difference| / max |reference| unless stated.
 *
 * Every bound is the largest value measured here (gcc 12.2, -O3 -fno-tree-vectorize) times a
 * margin of 100, rounded up to 1, 2 or 5 times a power of ten, and the measured value is written
 * beside it. The round trips are shown beside the oracle's own, ABA(RNEA(u)), in brackets: with
 * the refinement of the forward pass (gdca_refine.h), which every chain here with a mass ratio of
 * 100 or more gets, GDCA's round trip is within a factor 5 of the oracle's (asserted: 10);
 * unrefined (d->opt.fwd_refine = 0) it is up to 1e7 times larger (4.1e-3 against 2.6e-10 for
 * alternating 1 kg and 1 mg rods, n = 32). The two-body spin cases are not refined by default
 * (they are short and evenly proportioned) and keep the unrefined forward pass's 6.6e-9.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "ctc.h"
#include "gdca_refine.h"
#include "job_json.h"
#include "linalg.h"
#include "oracle.h"
#include "sim.h"
#include "spatial.h"
#include "model_fixture.h"
#include "run_fixture.h"

#define MAXV 96 /* velocity coordinates of the largest chain here (32 spatial joints) */

/* the worst errors of one chain over a few random states */
typedef struct dyn_errors {
    double fwd;    /* GDCA vs ABA, random driving forces in [-5, 5] */
    double inv;    /* composite iGDCA vs RNEA, random u in [-1, 1] */
    double rt;     /* GDCA(iGDCA(u)) vs u */
    double rt_aba; /* ABA(RNEA(u)) vs u: what the oracle itself achieves, for the messages */
} dyn_errors;

/* GDCA and iGDCA against the oracle at `trials` random states (speeds up to vmax) of model m;
 * asserts every result finite and no singular joint */
static dyn_errors measure(const ctc_model *m, uint64_t seed, int trials, double vmax)
{
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    cr_assert(d && o);
    int nv = m->nv;
    cr_assert_leq(nv, MAXV);
    double q[4 * MAXV], v[MAXV], f[MAXV], a[MAXV], ref[MAXV], u[MAXV], fi[MAXV];
    dyn_errors e = {0};
    uint64_t rng = seed;
    for (int t = 0; t < trials; t++) {
        test_random_state(m, &rng, vmax, q, v);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        for (int i = 0; i < nv; i++) f[i] = test_uniform(&rng, -5, 5);
        ctc_gdca_forward(m, d, f, a);
        ctc_oracle_aba(m, o, q, v, f, ref);
        cr_assert(d->singular_joint == -1 && test_all_finite(a, nv) && test_all_finite(ref, nv),
                  "n = %d trial %d: forward not finite (singular joint %d)", m->nbodies, t,
                  d->singular_joint);
        e.fwd = fmax(e.fwd, test_rel_err(a, ref, nv));

        for (int i = 0; i < nv; i++) u[i] = test_uniform(&rng, -1, 1);
        ctc_gdca_inverse(m, d, u, fi);
        ctc_oracle_rnea(m, o, q, v, u, f);
        cr_assert(test_all_finite(fi, nv) && test_all_finite(f, nv),
                  "n = %d trial %d: inverse not finite", m->nbodies, t);
        e.inv = fmax(e.inv, test_rel_err(fi, f, nv));
        ctc_gdca_forward(m, d, fi, a);
        cr_assert(test_all_finite(a, nv), "n = %d trial %d: round trip not finite", m->nbodies, t);
        e.rt = fmax(e.rt, test_rel_err(a, u, nv));
        ctc_oracle_aba(m, o, q, v, f, ref);
        e.rt_aba = fmax(e.rt_aba, test_rel_err(ref, u, nv));
    }
    ctc_oracle_free(o);
    ctc_data_free(d);
    return e;
}

/* ---- mass and inertia ratios between neighbouring bodies ---- */

/* How the bodies of a random chain are scaled: "alternating" multiplies every other body's mass
 * and inertia by ratio (heavy / light neighbours, ratio 1e-6 ... 1e6 between each pair);
 * "geometric" scales body k by ratio^(k / (n - 1)), so mass and inertia grow (ratio > 1) or
 * shrink by a constant factor from the base to the tip and differ by ratio end to end. */
typedef struct ratio_case {
    int spatial;   /* 0: planar rods (planar form), 1: spatial chain of every joint type */
    int geometric; /* 0: alternating, 1: geometric */
    double ratio;
    double fwd_bound, inv_bound, rt_bound; /* 100x the worst measured over n = 8, 16, 32 */
} ratio_case;

static void check_ratio_case(const ratio_case *rc)
{
    static const int sizes[] = {8, 16, 32};
    for (int s = 0; s < 3; s++) {
        int n = sizes[s];
        double factor[32];
        for (int k = 0; k < n; k++)
            factor[k] =
                rc->geometric ? pow(rc->ratio, (double)k / (n - 1)) : (k % 2 ? rc->ratio : 1.0);
        test_chain *c = rc->spatial
                            ? test_chain_random_spatial(n, 40 + (uint64_t)n, TEST_ALL_JOINTS)
                            : test_chain_random_planar(n, 40 + (uint64_t)n, 0, 1);
        test_chain_scale_bodies(c, factor);
        ctc_model *m = build(&c->spec);
        cr_assert_eq(m->form, rc->spatial ? CTC_FORM_SPATIAL : CTC_FORM_PLANAR);
        dyn_errors e = measure(m, 5, 5, 2.0);
        const char *what = rc->geometric ? "geometric" : "alternating";
        const char *form = rc->spatial ? "spatial" : "planar";
        cr_expect_leq(e.fwd, rc->fwd_bound, "%s %s %g, n = %d: GDCA vs ABA %.3g > %.3g", form, what,
                      rc->ratio, n, e.fwd, rc->fwd_bound);
        cr_expect_leq(e.inv, rc->inv_bound, "%s %s %g, n = %d: iGDCA vs RNEA %.3g > %.3g", form,
                      what, rc->ratio, n, e.inv, rc->inv_bound);
        cr_expect_leq(e.rt, rc->rt_bound,
                      "%s %s %g, n = %d: round trip %.3g > %.3g (the oracle's own: %.3g)", form,
                      what, rc->ratio, n, e.rt, rc->rt_bound, e.rt_aba);
        cr_expect_leq(e.rt, 10 * e.rt_aba + 1e-15,
                      "%s %s %g, n = %d: round trip %.3g, 10 times the oracle's own %.3g", form,
                      what, rc->ratio, n, e.rt, e.rt_aba);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

/* bounds: GDCA vs ABA, iGDCA vs RNEA, round trip; measured maxima over n = 8, 16, 32 in the
 * comments, with the oracle's own round trip in brackets */
Test(hard, alternating_heavy_and_light_planar_bodies_match_the_oracle)
{
    const ratio_case cases[] = {
        /* 1.1e-15, 2.7e-15, 2.5e-10 (2.6e-10) */
        {0, 0, 1e-6, 2e-13, 5e-13, 5e-8},
        /* 1.7e-13, 2.7e-15, 4.3e-10 (2.6e-10) */
        {0, 0, 1e-3, 2e-11, 5e-13, 5e-8},
        /* 2.3e-13, 4.3e-15, 1.8e-10 (2.8e-10) */
        {0, 0, 1e3, 5e-11, 5e-13, 2e-8},
        /* 1.4e-13, 2.9e-15, 2.6e-10 (1.3e-10) */
        {0, 0, 1e6, 2e-11, 5e-13, 5e-8},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) check_ratio_case(&cases[i]);
}

Test(hard, alternating_heavy_and_light_spatial_bodies_match_the_oracle)
{
    const ratio_case cases[] = {
        /* 1.9e-10, 4.8e-15, 4.3e-9 (1.0e-8) */
        {1, 0, 1e-6, 2e-8, 5e-13, 5e-7},
        /* 1.8e-13, 4.7e-15, 1.1e-11 (4.2e-12) */
        {1, 0, 1e-3, 2e-11, 5e-13, 2e-9},
        /* 8.7e-13, 3.8e-15, 2.5e-11 (4.8e-11) */
        {1, 0, 1e3, 1e-10, 5e-13, 5e-9},
        /* 5.9e-10, 4.0e-15, 2.1e-8 (1.8e-8) */
        {1, 0, 1e6, 1e-7, 5e-13, 5e-6},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) check_ratio_case(&cases[i]);
}

Test(hard, geometrically_growing_and_shrinking_bodies_match_the_oracle)
{
    const ratio_case cases[] = {
        /* planar, lighter towards the tip: 2.1e-14, 1.2e-15, 3.8e-12 (1.5e-12) */
        {0, 1, 1e-6, 5e-12, 2e-13, 5e-10},
        /* planar, heavier towards the tip: 1.1e-9, 5.1e-15, 3.1e-6 (1.4e-6) */
        {0, 1, 1e6, 2e-7, 1e-12, 5e-4},
        /* spatial, lighter towards the tip: 6.0e-15, 1.0e-15, 9.1e-13 (4.0e-13) */
        {1, 1, 1e-6, 1e-12, 2e-13, 1e-10},
        /* spatial, heavier towards the tip: 1.1e-8, 6.0e-15, 2.7e-7 (1.7e-7) */
        {1, 1, 1e6, 2e-6, 1e-12, 5e-5},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) check_ratio_case(&cases[i]);
}

/* ---- a nearly massless tip ---- */

/* bounds of the light-tip checks (measured values in the tests' comments) */
typedef struct light_tip_bounds {
    double free_tip;   /* GDCA vs ABA componentwise, no driving torque on the tip */
    double driven_tip; /* the same with a random torque on the tip too */
    double inv;        /* iGDCA vs RNEA */
    double tip_force;  /* the tip's driving force, iGDCA vs RNEA relative to itself */
} light_tip_bounds;

/* A 3-link chain whose tip body has mass 1e-9 kg and its inertia scaled by the same factor: the
 * tip's acceleration is finite and agrees with ABA, component by component (each relative to
 * itself), with and without a driving torque on the tip; the iGDCA driving forces agree with
 * RNEA, the tip's (about 1e-9 of the others) relative to itself. 20 random states. */
static void check_light_tip(int spatial, const light_tip_bounds *b)
{
    test_chain *c = spatial ? test_chain_random_spatial(3, 61, 1u << CTC_JOINT_REVOLUTE)
                            : test_chain_random_planar(3, 61, 0, 1);
    double factor[3] = {1, 1, 1e-9 / c->bodies[2].mass};
    test_chain_scale_bodies(c, factor);
    cr_assert_float_eq(c->bodies[2].mass, 1e-9, 1e-24);
    ctc_model *m = build(&c->spec);
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    double q[3], v[3], f[3], a[3], ref[3], u[3], fi[3], fr[3];
    double worst_free = 0, worst_driven = 0, worst_inv = 0, worst_tip_inv = 0;
    uint64_t rng = 62;
    for (int t = 0; t < 20; t++) {
        test_random_state(m, &rng, 2.0, q, v);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        for (int driven = 0; driven < 2; driven++) {
            for (int i = 0; i < 3; i++) f[i] = test_uniform(&rng, -5, 5);
            if (!driven) f[2] = 0; /* the tip swings freely */
            ctc_gdca_forward(m, d, f, a);
            ctc_oracle_aba(m, o, q, v, f, ref);
            cr_assert(test_all_finite(a, 3) && d->singular_joint == -1, "trial %d: not finite", t);
            double e = 0;
            for (int i = 0; i < 3; i++) e = fmax(e, fabs(a[i] - ref[i]) / fabs(ref[i]));
            if (driven)
                worst_driven = fmax(worst_driven, e);
            else
                worst_free = fmax(worst_free, e);
        }
        for (int i = 0; i < 3; i++) u[i] = test_uniform(&rng, -1, 1);
        ctc_gdca_inverse(m, d, u, fi);
        ctc_oracle_rnea(m, o, q, v, u, fr);
        worst_inv = fmax(worst_inv, test_rel_err(fi, fr, 3));
        worst_tip_inv = fmax(worst_tip_inv, fabs(fi[2] - fr[2]) / fabs(fr[2]));
    }
    cr_expect_leq(worst_free, b->free_tip, "free tip: componentwise GDCA vs ABA %.3g > %.3g",
                  worst_free, b->free_tip);
    cr_expect_leq(worst_driven, b->driven_tip, "driven tip: componentwise GDCA vs ABA %.3g > %.3g",
                  worst_driven, b->driven_tip);
    cr_expect_leq(worst_inv, b->inv, "iGDCA vs RNEA %.3g > %.3g", worst_inv, b->inv);
    cr_expect_leq(worst_tip_inv, b->tip_force, "tip force, iGDCA vs RNEA %.3g > %.3g",
                  worst_tip_inv, b->tip_force);
    ctc_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
}

Test(hard, nearly_massless_planar_tip_stays_finite_and_matches_the_oracle)
{
    /* measured 2.3e-12, 3.1e-13, 6.5e-16, 2.4e-15 */
    const light_tip_bounds b = {5e-10, 5e-11, 1e-13, 5e-13};
    check_light_tip(0, &b);
}

Test(hard, nearly_massless_spatial_tip_stays_finite_and_matches_the_oracle)
{
    /* measured 5.0e-14, 4.3e-14, 2.5e-15, 5.2e-15 */
    const light_tip_bounds b = {5e-12, 5e-12, 5e-13, 1e-12};
    check_light_tip(1, &b);
}

/* ---- high spin rates ---- */

/* The paper's spatial double pendulum with revolute joints (axes z and y: not parallel) or with
 * spherical joints, every velocity coordinate +-100 rad/s: the gyroscopic and centripetal terms
 * dominate gravity by far. GDCA and iGDCA against the oracle at 20 random configurations; the
 * round trip loses what the forward pass loses when f nearly balances velocity terms 1e4 times
 * the inertial ones (the oracle's own round trip is printed on failure). bounds: GDCA vs ABA,
 * iGDCA vs RNEA, round trip. */
static void check_spin(ctc_joint_type type, const double bounds[3])
{
    test_chain *c = test_chain_spatial_double_pendulum(type);
    ctc_model *m = build(&c->spec);
    cr_assert_eq(m->form, CTC_FORM_SPATIAL);
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    int nv = m->nv;
    double q[8], v[6], f[6], a[6], ref[6], u[6], fi[6], fr[6];
    double worst_fwd = 0, worst_inv = 0, worst_rt = 0, worst_rt_aba = 0;
    uint64_t rng = 71;
    for (int t = 0; t < 20; t++) {
        test_random_state(m, &rng, 1.0, q, v);
        for (int i = 0; i < nv; i++) v[i] = test_uniform(&rng, 0, 1) < 0.5 ? -100 : 100;
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        for (int i = 0; i < nv; i++) f[i] = test_uniform(&rng, -5, 5);
        ctc_gdca_forward(m, d, f, a);
        ctc_oracle_aba(m, o, q, v, f, ref);
        cr_assert(test_all_finite(a, nv) && d->singular_joint == -1, "trial %d: not finite", t);
        worst_fwd = fmax(worst_fwd, test_rel_err(a, ref, nv));
        for (int i = 0; i < nv; i++) u[i] = test_uniform(&rng, -1, 1);
        ctc_gdca_inverse(m, d, u, fi);
        ctc_oracle_rnea(m, o, q, v, u, fr);
        worst_inv = fmax(worst_inv, test_rel_err(fi, fr, nv));
        cr_assert(test_all_finite(fi, nv), "trial %d: inverse not finite", t);
        ctc_gdca_forward(m, d, fi, a);
        worst_rt = fmax(worst_rt, test_rel_err(a, u, nv));
        ctc_oracle_aba(m, o, q, v, fr, ref);
        worst_rt_aba = fmax(worst_rt_aba, test_rel_err(ref, u, nv));
    }
    cr_expect_leq(worst_fwd, bounds[0], "GDCA vs ABA %.3g > %.3g", worst_fwd, bounds[0]);
    cr_expect_leq(worst_inv, bounds[1], "iGDCA vs RNEA %.3g > %.3g", worst_inv, bounds[1]);
    cr_expect_leq(worst_rt, bounds[2], "round trip %.3g > %.3g (the oracle's own: %.3g)", worst_rt,
                  bounds[2], worst_rt_aba);
    ctc_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
}

Test(hard, spinning_revolute_double_pendulum_matches_the_oracle)
{
    /* measured 3.9e-14, 3.8e-16, 6.6e-9 (the oracle's round trip: 4.3e-11) */
    check_spin(CTC_JOINT_REVOLUTE, (const double[]){5e-12, 5e-14, 1e-6});
}

Test(hard, spinning_spherical_double_pendulum_matches_the_oracle)
{
    /* measured 9.7e-14, 2.4e-15, 6.6e-9 (the oracle's round trip: 1.2e-9) */
    check_spin(CTC_JOINT_SPHERICAL, (const double[]){1e-11, 5e-13, 1e-6});
}

/* A passive 0.1 s run from +-100 rad/s on every coordinate, DOPRI5 at rtol 1e-10, atol 1e-12:
 * the energy (over 1e4 J, nearly all kinetic) is conserved to bound, relative (sim.h
 * energy_drift). */
static void check_spin_energy(ctc_joint_type type, double bound)
{
    test_chain *c = test_chain_spatial_double_pendulum(type);
    double q0[8], v0[6];
    int nv = type == CTC_JOINT_SPHERICAL ? 6 : 2;
    ctc_model *m = build(&c->spec);
    ctc_model_q_zero(m, q0);
    ctc_model_free(m);
    for (int i = 0; i < nv; i++) v0[i] = i % 2 ? -100 : 100;
    ctc_sim_spec spec = fixture_passive_spec(
        &c->spec, q0, v0,
        (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-10, .atol = 1e-12}, 0.1, 0.001);
    ctc_sim_result *res = fixture_run_done(&spec);
    double ke = 0;
    for (int j = 0; j < res->nsamples; j++) ke = fmax(ke, res->ch[CTC_CH_ENERGY][2 * j]);
    cr_expect_gt(ke, 1e4, "it spins: kinetic energy %g J", ke);
    cr_expect_leq(res->metrics.energy_drift, bound, "energy drift %g > %g",
                  res->metrics.energy_drift, bound);
    ctc_sim_result_free(res);
    test_chain_free(c);
}

Test(hard, spinning_revolute_double_pendulum_conserves_energy)
{
    check_spin_energy(CTC_JOINT_REVOLUTE, 5e-9); /* measured 3.5e-11 (527 steps) */
}

Test(hard, spinning_spherical_double_pendulum_conserves_energy)
{
    check_spin_energy(CTC_JOINT_SPHERICAL, 5e-9); /* measured 4.4e-11 (790 steps) */
}

/* ---- a closed chain driven into a singular configuration ---- */

/* The preset five_bar_pd (paper section 7.2) with its set point moved to (pi/2, 0, 0): rods 1-3
 * stretch out along +x, which puts the end of rod 3 2.9 m from the second ground pivot, beyond
 * the reach of rods 4 and 5 (2 m). On the way the two passive rods straighten into one line
 * (joint 4's angle goes to 0), where the independent joints can no longer drive the loop: the
 * dependent joints' speeds and the driving torques grow without bound. The run must stop there
 * cleanly as "singular", with its condition estimate in the metrics, and every recorded torque
 * a plausible number (below 1e6 N m: the largest before the singularity is about 1e4 N m), never
 * the 1e15 of a solve past it. */
Test(hard, five_bar_driven_into_a_straightened_dyad_stops_as_singular)
{
    static const char text[] = "{\"preset\": \"five_bar_pd\", \"duration\": 2, \"trajectory\": ["
                               "{\"type\": \"constant\", \"value\": 1.5707963267948966},"
                               "{\"type\": \"constant\", \"value\": 0},"
                               "{\"type\": \"constant\", \"value\": 0}]}";
    job *j = NULL;
    job_error jerr = {0};
    cr_assert_eq(job_parse(text, strlen(text), &j, &jerr), 0, "%s: %s", jerr.field, jerr.message);
    ctc_sim_result *res = NULL;
    char err[512] = "";
    cr_assert_eq(ctc_sim_run(&j->spec, NULL, &res, err, sizeof err), CTC_OK, "%s", err);

    /* it stops before the end, as singular, and the metrics carry the condition estimate that
       stopped it, not only those of the samples before: a user reads why the run stopped from
       its metrics. Near the straightened dyad the dependent joints' speeds grow like
       1 / distance and pass the speed bound while the estimate is about 6e4 (from 5 at the
       start: sim.c, singular_divergence) */
    cr_expect_eq(res->status, CTC_RUN_SINGULAR, "status %s: %s", ctc_run_status_name(res->status),
                 res->message);
    cr_expect(strstr(res->message, "condition estimate") != NULL, "message: %s", res->message);
    cr_expect_lt(res->metrics.t_end, 2.0);
    cr_expect(isfinite(res->metrics.loop_cond_max) && res->metrics.loop_cond_max > 1e4,
              "metrics.loop_cond_max %g", res->metrics.loop_cond_max);

    /* the recorded output: finite, torques bounded, and the run came near the singular
       configuration (joint 4 within 0.5 rad of straight at some sample) */
    cr_assert_geq(res->nsamples, 2);
    cr_assert(res->ch[CTC_CH_TAU] && res->ch[CTC_CH_Q]);
    double tau_max = 0, q4_min = INFINITY;
    for (int s = 0; s < res->nsamples; s++) {
        const double *tau = res->ch[CTC_CH_TAU] + (size_t)s * (size_t)res->width[CTC_CH_TAU];
        const double *q = res->ch[CTC_CH_Q] + (size_t)s * (size_t)res->nq;
        cr_assert(test_all_finite(tau, res->width[CTC_CH_TAU]) && test_all_finite(q, res->nq),
                  "sample %d (t = %g s) not finite", s, res->t[s]);
        for (int i = 0; i < res->width[CTC_CH_TAU]; i++) tau_max = fmax(tau_max, fabs(tau[i]));
        q4_min = fmin(q4_min, fabs(remainder(q[4], 2 * CTC_PI)));
    }
    cr_expect_lt(tau_max, 1e6, "recorded |tau| up to %g N m", tau_max);
    cr_expect_lt(q4_min, 0.5, "joint 4 only reached %g rad from straight", q4_min);
    ctc_sim_result_free(res);
    job_free(j);
}

/* ---- long chains to 65536 bodies ---- */

/* max |f - iGDCA(qacc)| / max |f|: the backward error of qacc by the composite inverse */
static double backward(const ctc_model *m, ctc_data *d, const double *f, const double *qacc,
                       double *scratch)
{
    ctc_gdca_inverse(m, d, qacc, scratch);
    double r = 0, big = 0;
    for (int i = 0; i < m->nv; i++) {
        r = fmax(r, fabs(f[i] - scratch[i]));
        big = fmax(big, fabs(f[i]));
    }
    return r / big;
}

/* On planar chains of 16384 and 65536 bodies (random rods, and a uniform rod pendulum), where
 * M's condition number approaches 1 / rounding: GDCA's round trip GDCA(iGDCA(u)) within 10 times
 * the oracle's ABA(RNEA(u)) (measured against the oracle's: rods 4.8e-4 / 2.2e-4 and 3.5e-2 /
 * 2.4e-2, random 3.8e-2 / 1.9e-2 and 1.8 / 1.3, at most 2.2 times; the accelerations of the
 * longest random chain keep no digit in either solver), and the refinement's backward error never
 * larger after a step than before it (gdca_refine.h: a step that grows it is undone). */
Test(hard, long_planar_chains_round_trip_near_the_oracle_and_refinement_never_grows_the_residual,
     .timeout = 120)
{
    static const int sizes[] = {16384, 65536};
    for (int kind = 0; kind < 2; kind++) {
        for (int i = 0; i < 2; i++) {
            const int n = sizes[i];
            test_chain *c = kind ? test_chain_rod_pendulum(n, 10.0 / n, 0.1)
                                 : test_chain_random_planar(n, 7, 0, 1);
            ctc_model *m = build(&c->spec);
            ctc_data *d = ctc_data_new(m);
            ctc_oracle *o = ctc_oracle_new(m);
            const size_t nv = (size_t)m->nv;
            double *buf = calloc((size_t)m->nq + 6 * nv, sizeof(double));
            cr_assert(d && o && buf);
            double *q = buf, *v = q + m->nq, *u = v + nv, *f = u + nv, *a = f + nv;
            double *ref = a + nv, *scratch = ref + nv;
            uint64_t rng = 11;
            test_random_state(m, &rng, 1.0, q, v);
            for (size_t k = 0; k < nv; k++) u[k] = test_uniform(&rng, -1, 1);
            ctc_kinematics(m, d, q, v);
            ctc_handles(m, d);
            ctc_oracle_rnea(m, o, q, v, u, ref);
            ctc_oracle_aba(m, o, q, v, ref, a);
            const double rt_aba = test_rel_err(a, u, n);
            ctc_gdca_inverse(m, d, u, f);
            ctc_gdca_forward(m, d, f, a);
            const double rt = test_rel_err(a, u, n);
            cr_expect(rt <= 10 * rt_aba, "%s n = %d: round trip %.3g, the oracle's %.3g",
                      kind ? "rods" : "random", n, rt, rt_aba);
            double before = INFINITY;
            for (int steps = 0; steps <= CTC_REFINE_MAX_STEPS; steps++) {
                d->opt.fwd_refine = steps;
                ctc_gdca_inverse(m, d, u, f);
                ctc_gdca_forward(m, d, f, a);
                double bwd = backward(m, d, f, a, scratch);
                cr_expect(bwd <= before, "%s n = %d: %d steps: backward error %.3g, before %.3g",
                          kind ? "rods" : "random", n, steps, bwd, before);
                cr_expect(isfinite(bwd));
                before = bwd;
            }
            free(buf);
            ctc_oracle_free(o);
            ctc_data_free(d);
            ctc_model_free(m);
            test_chain_free(c);
        }
    }
}
