/*
 * test_stiff.c - stiff problems: DOPRI5's stiffness stop (integ_dopri5.c) and what the methods do
 * with the triple pendulum at high gains, from the job format through to the reported status.
 *
 * Oracles, written here apart from the code under test:
 *  - the Prothero-Robinson equation y' = -lambda (y - cos t) - sin t, y(0) = 1, whose solution
 *    is cos t for every lambda, and whose Jacobian is -lambda exactly;
 *  - DOPRI5's stability boundary on the negative real axis, the root of |R(-x)| = 1 for the
 *    method's stability polynomial R(z) = 1 + z + z^2/2 + z^3/6 + z^4/24 + z^5/120 + z^6/600
 *    (Hairer and Wanner, Solving ODEs II, section IV.2), found by bisection;
 *  - the closed-form error of computed torque control with an exact model and no disturbance:
 *    each coordinate's e = q_d - q obeys e'' + kv e' + kp e = 0, critically damped here
 *    (kv = 2 sqrt(kp)): e(t) = (e0 + (de0 + w e0) t) exp(-w t) with w = sqrt(kp).
 * Every run is short enough for the sanitizer build (well under a second each).
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "integrator.h"
#include "job_json.h"
#include "result_out.h"
#include "sim.h"

#define ERRLEN 256
#define PI 3.14159265358979323846

/* ---- the integrator alone ---- */

typedef struct pr_problem {
    double lambda; /* 1/s */
} pr_problem;

static int prothero_robinson(double t, const double *y, double *ydot, void *ctx)
{
    const pr_problem *p = ctx;
    ydot[0] = -p->lambda * (y[0] - cos(t)) - sin(t);
    return 0;
}

/* an integrator of spec's method on the Prothero-Robinson problem p, started at y(0) = 1 (on the
 * solution cos t); the caller frees it */
static ctc_integrator *pr_start(const ctc_integ_spec *spec, pr_problem *p)
{
    ctc_integrator *it = NULL;
    char err[ERRLEN] = "";
    cr_assert_eq(ctc_integrator_new(spec, 1, prothero_robinson, p, &it, err, sizeof err), CTC_OK,
                 "%s", err);
    const double y0 = 1;
    cr_assert_eq(ctc_integrator_reset(it, 0, &y0), 0);
    return it;
}

static int oscillator(double t, const double *y, double *ydot, void *ctx)
{
    (void)t;
    (void)ctx;
    ydot[0] = y[1];
    ydot[1] = -y[0];
    return 0;
}

/* DOPRI5's stability polynomial at real z */
static double dopri5_r(double z)
{
    return 1 + z * (1 + z * (1.0 / 2 + z * (1.0 / 6 + z * (1.0 / 24 + z * (1.0 / 120 + z / 600)))));
}

/* x > 0 where |R(-x)| first reaches 1: the stability interval is [-x, 0] */
static double dopri5_real_boundary(void)
{
    double lo = 1, hi = 5; /* |R(-1)| < 1 < |R(-5)| */
    cr_assert(fabs(dopri5_r(-lo)) < 1 && fabs(dopri5_r(-hi)) > 1);
    for (int i = 0; i < 60; i++) {
        double mid = 0.5 * (lo + hi);
        if (fabs(dopri5_r(-mid)) < 1) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    return lo;
}

Test(stiff, dopri5_stops_a_long_stiff_run_at_its_stability_limit)
{
    /* lambda = 1e7 and 10 s to go: about 3e7 steps at the stability limit */
    pr_problem p = {.lambda = 1e7};
    ctc_integ_spec spec = {.method = CTC_INTEG_DOPRI5, .rtol = 1e-6, .atol = 1e-8};
    ctc_integrator *it = pr_start(&spec, &p);
    char err[ERRLEN] = "";
    const double t_end = 10;
    int rc = 0;
    double worst = 0;
    while (rc == 0 && ctc_integrator_stats(it)->steps < 100000) {
        rc = ctc_integrator_step(it, t_end, err, sizeof err);
        double t = ctc_integrator_time(it);
        worst = fmax(worst, fabs(ctc_integrator_state(it)[0] - cos(t)));
    }
    cr_assert_eq(rc, -1, "no stop after %ld steps", ctc_integrator_stats(it)->steps);

    /* the message: the step and the time (the last accepted step's end), the advice */
    double h = NAN, t_msg = NAN;
    const char *prefix = "stiff: step size below the stability limit, h = ";
    cr_assert(strncmp(err, prefix, strlen(prefix)) == 0, "message: %s", err);
    cr_assert_eq(sscanf(err + strlen(prefix), "%lg s at t = %lg s", &h, &t_msg), 2, "%s", err);
    const double t_now = ctc_integrator_time(it);
    char want[ERRLEN];
    snprintf(want, sizeof want, " s at t = %.10g s (h |lambda| > 3.25 on 15 steps), ", t_now);
    cr_assert(strstr(err, want) != NULL, "message: %s", err);
    const char *tail = "steps short of t = 10 s: use \"method\": \"bdf\"";
    cr_assert_str_eq(err + strlen(err) - strlen(tail), tail);

    /* the step it names sits at DOPRI5's stability boundary (|R(-x)| = 1 at x = 3.307) */
    const double boundary = dopri5_real_boundary();
    cr_assert(fabs(boundary - 3.307) < 1e-3, "boundary %.6f", boundary);
    cr_assert(h * p.lambda > 3.25 && h * p.lambda < 1.05 * boundary, "h lambda = %g", h * p.lambda);

    /* it stopped soon, not after crawling, and what it had done was right */
    cr_assert_lt(ctc_integrator_stats(it)->steps, 1000);
    cr_assert_leq(worst, 10 * spec.rtol, "error %g", worst);
    ctc_integrator_free(it);
}

Test(stiff, dopri5_finishes_a_stiff_run_that_ends_soon)
{
    /* lambda = 1e5 over 0.5 s: stiff (h held near 3.3e-5 s), but only ~1.5e4 steps in all */
    pr_problem p = {.lambda = 1e5};
    ctc_integ_spec spec = {.method = CTC_INTEG_DOPRI5, .rtol = 1e-6, .atol = 1e-8};
    ctc_integrator *it = pr_start(&spec, &p);
    char err[ERRLEN] = "";
    const double t_end = 0.5;
    double worst = 0;
    while (ctc_integrator_time(it) < t_end) {
        cr_assert_eq(ctc_integrator_step(it, t_end, err, sizeof err), 0, "%s", err);
        double t = ctc_integrator_time(it);
        worst = fmax(worst, fabs(ctc_integrator_state(it)[0] - cos(t)));
    }
    const ctc_integ_stats *st = ctc_integrator_stats(it);
    /* its steps were set by stability: about t_end lambda / 3.3 of them */
    cr_assert(st->steps > 0.8 * t_end * p.lambda / dopri5_real_boundary(), "%ld steps", st->steps);
    cr_assert_leq(worst, 10 * spec.rtol, "error %g", worst);
    ctc_integrator_free(it);
}

Test(stiff, dopri5_does_not_take_a_loosely_solved_oscillator_for_stiff)
{
    /* y'' = -y at rtol 1e-3: long steps (h ~ 0.5 s, eigenvalues +-i) on a run of 1e6 s, so only
     * the quotient's bound, not the steps to go, keeps it from stopping; 20000 steps of it */
    ctc_integ_spec spec = {.method = CTC_INTEG_DOPRI5, .rtol = 1e-3, .atol = 1e-6};
    ctc_integrator *it = NULL;
    char err[ERRLEN] = "";
    cr_assert_eq(ctc_integrator_new(&spec, 2, oscillator, NULL, &it, err, sizeof err), CTC_OK);
    const double y0[2] = {1, 0};
    cr_assert_eq(ctc_integrator_reset(it, 0, y0), 0);
    double h_max = 0;
    for (int k = 0; k < 20000; k++) {
        cr_assert_eq(ctc_integrator_step(it, 1e6, err, sizeof err), 0, "step %d: %s", k, err);
        h_max = fmax(h_max, ctc_integrator_stats(it)->h_last);
    }
    cr_assert_gt(h_max, 0.3, "h_max %g: the steps were too short to test anything", h_max);
    ctc_integrator_free(it);
}

/* ---- whole runs: the triple pendulum preset at high gains ---- */

/* The paper's triple pendulum (preset triple_pendulum_pd) with kp, kv = 2 sqrt(kp), no
 * disturbance, and the integrator given as JSON. */
static job *stiff_job(double kp, double duration, const char *integrator)
{
    char text[1024];
    snprintf(text, sizeof text,
             "{\"preset\": \"triple_pendulum_pd\", \"controller\": {\"kp\": %.17g, \"kv\": %.17g}, "
             "\"disturbance\": {\"type\": \"none\"}, \"duration\": %g, \"integrator\": %s}",
             kp, 2 * sqrt(kp), duration, integrator);
    job *j = NULL;
    job_error jerr = {0};
    cr_assert_eq(job_parse(text, strlen(text), &j, &jerr), 0, "%s: %s", jerr.field, jerr.message);
    return j;
}

static ctc_sim_result *run_job(const job *j)
{
    ctc_sim_result *r = NULL;
    char err[ERRLEN] = "";
    cr_assert_eq(ctc_sim_run(&j->spec, NULL, &r, err, sizeof err), CTC_OK, "%s", err);
    return r;
}

/* max over the samples and joints of |q - (q_d - e_closed)|: the distance from the exact
 * closed-loop motion of a critically damped PD with an exact model */
static double closed_form_deviation(const ctc_sim_result *r, double kp)
{
    const double w = sqrt(kp), a = 0.6, omega = 2 * PI / 1.5;
    const double q0[3] = {5 * PI / 6, 3 * PI / 4, 2 * PI / 3}; /* the preset's start, at rest */
    double worst = 0;
    for (int k = 0; k < r->nsamples; k++) {
        const double t = r->t[k];
        for (int i = 0; i < 3; i++) {
            /* q_d: sine on joints 0 and 2, cosine on joint 1 (Eq. 81-82) */
            double qd = i == 1 ? a * cos(omega * t) : a * sin(omega * t);
            double qd0 = i == 1 ? a : 0, vd0 = i == 1 ? 0 : a * omega;
            double e0 = qd0 - q0[i], de0 = vd0;
            double e = (e0 + (de0 + w * e0) * t) * exp(-w * t);
            worst = fmax(worst, fabs(r->ch[CTC_CH_Q][3 * k + i] - (qd - e)));
        }
    }
    return worst;
}

/* Runs j, a stiff_job of gain kp, and expects it done and on the closed form to tol rad; the
 * caller frees the result. */
static ctc_sim_result *expect_closed_form_run(const job *j, double kp, double tol)
{
    ctc_sim_result *r = run_job(j);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
    double dev = closed_form_deviation(r, kp);
    cr_assert_leq(dev, tol, "deviation %g rad", dev);
    return r;
}

Test(stiff, dopri5_finishes_the_triple_pendulum_at_kp_1e6_on_the_closed_form)
{
    /* poles at -1000 (double): steps held near 2e-4 s at rtol 1e-8 (accuracy on the fast error
     * dynamics, not stability, which would allow 3.3e-3 s), so it finishes */
    job *j = stiff_job(1e6, 1, "{\"method\": \"dopri5\", \"rtol\": 1e-8, \"atol\": 1e-10}");
    ctc_sim_result *r = expect_closed_form_run(j, 1e6, 1e-7);
    ctc_sim_result_free(r);
    job_free(j);
}

Test(stiff, bdf_finishes_the_triple_pendulum_at_kp_1e6_on_the_closed_form)
{
    job *j = stiff_job(1e6, 5, "{\"method\": \"bdf\", \"rtol\": 1e-8, \"atol\": 1e-10}");
    ctc_sim_result *r = expect_closed_form_run(j, 1e6, 1e-7);
    cr_assert_lt(r->metrics.steps, 5000, "%ld steps", r->metrics.steps);
    ctc_sim_result_free(r);
    job_free(j);
}

Test(stiff, dopri5_stops_as_stiff_at_kp_1e10_and_the_job_reports_it_failed)
{
    /* poles at -1e5 and a loose rtol: the steps sit at the stability limit (~3e-5 s), 5 s to
     * go is ~2e5 of them, so the run stops early, as failed, with the advice to use bdf */
    job *j = stiff_job(1e10, 5, "{\"method\": \"dopri5\", \"rtol\": 1e-4, \"atol\": 1e-6}");
    ctc_sim_result *r = run_job(j);
    cr_assert_eq(r->status, CTC_RUN_FAILED, "status %s: %s", ctc_run_status_name(r->status),
                 r->message);
    const char *prefix = "integrator: stiff: step size below the stability limit, h = ";
    cr_assert(strncmp(r->message, prefix, strlen(prefix)) == 0, "message: %s", r->message);
    double h = NAN, t = NAN;
    cr_assert_eq(sscanf(r->message + strlen(prefix), "%lg s at t = %lg s", &h, &t), 2);
    cr_assert(fabs(t - r->metrics.t_end) <= 1e-9 * fmax(1, t), "t %g, t_end %g", t,
              r->metrics.t_end);
    /* at or below the stability limit of the double pole at -1e5 */
    cr_assert(h > 0 && h * 1e5 < 1.05 * dopri5_real_boundary(), "h = %g s", h);
    cr_assert_lt(r->metrics.t_end, 1, "stopped late, at t = %g s", r->metrics.t_end);
    const char *tail = "steps short of t = 5 s: use \"method\": \"bdf\"";
    cr_assert(strstr(r->message, tail) != NULL, "message: %s", r->message);

    /* the service and the command line report it as "failed" with the same message */
    cJSON *m = result_metrics_json(r, j);
    cr_assert(m != NULL);
    cr_assert_str_eq(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(m, "status")), "failed");
    cr_assert_str_eq(cJSON_GetStringValue(cJSON_GetObjectItemCaseSensitive(m, "message")),
                     r->message);
    cJSON_Delete(m);
    ctc_sim_result_free(r);
    job_free(j);
}

Test(stiff, bdf_finishes_the_run_dopri5_stopped_on_the_closed_form)
{
    job *j = stiff_job(1e10, 5, "{\"method\": \"bdf\", \"rtol\": 1e-4, \"atol\": 1e-6}");
    ctc_sim_result *r = expect_closed_form_run(j, 1e10, 1e-4);
    ctc_sim_result_free(r);
    job_free(j);
}
