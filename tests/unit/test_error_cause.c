/*
 * test_error_cause.c - the tracking error by cause (sim.h metrics.err_cause, sim_causes.c):
 * zeros without a cause; a sampled run's sampling share against the closed form of the zero-order
 * hold; the rows' definitions on a run with all three causes.
 *
 * Closed form. A rotor about the vertical (a constant inertia, no gravity torque, no velocity
 * product) held at q_d = 0 by computed torque with PD (kp = 100, kv = 20) and an exact model has
 * e'' = -w: continuously w = kp e + kv de, so e(t) = (e0 + (de0 + 10 e0) t) exp(-10 t); sampled
 * with period T and zero-order hold, w_k = kp e_k + kv de_k is held over [t_k, t_k + T), so
 *     e(t_k + s) = e_k + de_k s - w_k s^2 / 2,   de(t_k + s) = de_k - w_k s
 * exactly. The sampling share is the RMS over the output samples of the difference of the two,
 * computed here; the runs integrate with rtol 1e-11, so the bound is 1e-9 rad.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "sim.h"
#include "job_fixture.h"

static const double *row(const ctc_sim_result *r, int cause)
{
    return r->metrics.err_cause + (size_t)cause * (size_t)r->nind;
}

Test(error_cause, a_run_without_a_cause_reports_zeros)
{
    job *j = fixture_parse_ok("{'preset':'triple_pendulum_pid','duration':1,"
                              "'plant':{'torque_limit':50,'viscous':0.1}}");
    ctc_sim_result *r = fixture_run_done(&j->spec);
    cr_assert_not_null(r->metrics.err_cause);
    for (int c = 0; c < CTC_NCAUSES; c++)
        for (int i = 0; i < r->nind; i++) cr_expect_eq(row(r, c)[i], 0, "cause %d, joint %d", c, i);
    ctc_sim_result_free(r);
    job_free(j);
    j = fixture_parse_ok("{'preset':'triple_pendulum_passive','duration':0.1}");
    r = fixture_run_done(&j->spec);
    cr_expect_null(r->metrics.err_cause, "a passive run tracks nothing");
    ctc_sim_result_free(r);
    job_free(j);
}

/* the closed forms above at time t: continuous, and sampled with period T from e0 (de0 = 0) */
static double e_continuous(double e0, double t)
{
    return e0 * (1 + 10 * t) * exp(-10 * t);
}

static double e_sampled(double e0, double period, double t)
{
    double e = e0, de = 0;
    const long k = (long)floor(t / period + 1e-9);
    for (long i = 0; i < k; i++) {
        const double w = 100 * e + 20 * de;
        e += de * period - w * period * period / 2;
        de -= w * period;
    }
    const double s = t - (double)k * period, w = 100 * e + 20 * de;
    return e + de * s - w * s * s / 2;
}

Test(error_cause, sampling_share_matches_the_closed_form_zero_order_hold)
{
    const double period = 0.02, e0 = -0.3;
    job *j = fixture_parse_ok(
        "{'scene':{'gravity':[0,0,0],'q0':[0.3],'bodies':[{'mass':2,'com':[0.1,0,0],"
        "'inertia':[0.05,0.05,0.05],'joint':{'type':'revolute','axis':[0,0,1]}}]},"
        "'controller':{'type':'pd','kp':100,'kv':20,'sample_period':0.02},"
        "'trajectory':{'type':'constant','value':0},'duration':1.5,'output':{'interval':0.005},"
        "'plant':{'noise_q':0.001,'noise_v':0.01,'resolution':0.0005}," FIXTURE_INTEG "}");
    /* sampling alone first: the same run with exact sensors */
    j->plant[0].noise_q = j->plant[0].noise_v = j->plant[0].resolution = 0;
    ctc_sim_result *r = fixture_run_done(&j->spec);
    double sum = 0, dev = 0;
    for (int s = 0; s < r->nsamples; s++) {
        const double d = e_sampled(e0, period, r->t[s]) - e_continuous(e0, r->t[s]);
        sum += d * d;
        dev = fmax(dev, fabs(r->ch[CTC_CH_E][s] - e_sampled(e0, period, r->t[s])));
    }
    const double share = sqrt(sum / r->nsamples);
    cr_expect_leq(dev, 1e-9, "the run is the zero-order hold's: %.3e rad", dev);
    cr_expect_leq(fabs(row(r, CTC_CAUSE_SAMPLING)[0] - share), 1e-9,
                  "sampling share %.12g rad, closed form %.12g rad", row(r, CTC_CAUSE_SAMPLING)[0],
                  share);
    cr_expect_gt(share, 1e-3, "50 Hz is slow enough to show");
    cr_expect_eq(row(r, CTC_CAUSE_TOTAL)[0], row(r, CTC_CAUSE_SAMPLING)[0],
                 "the only cause is the whole");
    cr_expect_eq(row(r, CTC_CAUSE_NOISE)[0], 0);
    cr_expect_eq(row(r, CTC_CAUSE_MODEL)[0], 0);
    cr_log_info("sampling share %.12g rad, closed form %.12g rad", row(r, CTC_CAUSE_SAMPLING)[0],
                share);
    ctc_sim_result_free(r);
    job_free(j);
}

Test(error_cause, every_cause_has_its_share_and_the_same_seed_the_same_shares)
{
    const char *text =
        "{'scene':{'gravity':[0,-9.81,0],'bodies':[" FIXTURE_ROD "," FIXTURE_ROD2 "]},"
        "'controller':{'type':'pd','kp':100,'kv':20,'sample_period':0.005,'seed':7,"
        "'model':{'payload':{'body':1,'mass':0.5,'point':[0,-1,0]}}},"
        "'trajectory':{'type':'sine','amplitude':0.6,'period':1.5},'duration':2,"
        "'plant':{'noise_q':0.002}," FIXTURE_INTEG "}";
    job *j = fixture_parse_ok(text);
    ctc_sim_result *r = fixture_run_done(&j->spec), *again = fixture_run_done(&j->spec);
    for (int c = 0; c < CTC_NCAUSES; c++)
        for (int i = 0; i < 2; i++) {
            cr_expect_gt(row(r, c)[i], 1e-5, "cause %d, joint %d: %g", c, i, row(r, c)[i]);
            cr_expect_eq(row(r, c)[i], row(again, c)[i], "the same seed, the same share");
        }
    cr_log_info("joint 1: sampling %.3e, noise %.3e, model %.3e, total %.3e rad", row(r, 0)[1],
                row(r, 1)[1], row(r, 2)[1], row(r, 3)[1]);
    /* the model's share is the same measured from the run with only the model error, whose
       own total it is */
    ctc_sim_result_free(again);
    j->spec.sample_period = 0;
    j->plant[0].noise_q = j->plant[1].noise_q = 0; /* read by a sampled controller only */
    again = fixture_run_done(&j->spec);
    for (int i = 0; i < 2; i++) {
        cr_expect_eq(row(again, CTC_CAUSE_MODEL)[i], row(r, CTC_CAUSE_MODEL)[i]);
        cr_expect_eq(row(again, CTC_CAUSE_TOTAL)[i], row(again, CTC_CAUSE_MODEL)[i]);
        cr_expect_eq(row(again, CTC_CAUSE_SAMPLING)[i], 0);
        cr_expect_eq(row(again, CTC_CAUSE_NOISE)[i], 0);
    }
    ctc_sim_result_free(again);
    ctc_sim_result_free(r);
    job_free(j);
}

Test(error_cause, a_run_stopped_early_has_no_shares)
{
    job *j = fixture_parse_ok("{'preset':'triple_pendulum_pid_50hz','duration':1}");
    j->spec.max_speed = 0.1; /* the start's speeds pass it within the first steps */
    ctc_sim_result *r = NULL;
    char err[256] = "";
    cr_assert_eq(ctc_sim_run(&j->spec, NULL, &r, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_eq(r->status, CTC_RUN_DIVERGED, "%s", r->message);
    for (int c = 0; c < CTC_NCAUSES; c++)
        for (int i = 0; i < r->nind; i++)
            cr_expect(isnan(row(r, c)[i]), "cause %d, joint %d: %g", c, i, row(r, c)[i]);
    ctc_sim_result_free(r);
    job_free(j);
}
