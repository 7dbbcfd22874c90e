/*
 * test_integrator.c - the three integrators (src/integrate/integrator.c, integ_rk4.c,
 * integ_dopri5.c, integ_bdf.c) against closed-form solutions of test equations, convergence orders
 * measured by halving the step, published reference values (Robertson's kinetics), one method
 * against another, and the exact message of every failure.
 *
 * Test equations and their solutions:
 *   oscillator  y0' = y1, y1' = -y0, y(0) = (1, 0):        y = (cos t, -sin t)
 *   riccati     y' = y^2, y(0) = 1:                         y = 1 / (1 - t), blows up at t = 1
 *   kepler      q'' = -q / |q|^3, eccentricity e, started at perihelion: period 2 pi, energy
 *               -1/2 conserved
 *   stiff       y' = -lambda (y - cos t) - sin t, y(0) = 1: y = cos t for any lambda
 *   robertson   the classic stiff chemical kinetics (Robertson 1966), y(40) known to 7 digits
 */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "integrator.h"

#define ERRLEN 256
#define TWO_PI 6.283185307179586476925

/* what the test right-hand sides share: a call counter, and a way to make them fail */
typedef struct problem {
    long calls;
    double fail_after; /* the rhs returns fail_code when t > fail_after */
    int fail_code;
    double failed_at;       /* the t of the first failing call */
    double nan_after;       /* the rhs returns NaN derivatives (and 0) when t > nan_after */
    double lambda;          /* stiff: stiffness */
    int mode;               /* switch: which right-hand side is in force */
    long projections;       /* projection calls that moved the state */
    long proj_calls;        /* projection calls */
    double proj_fail_after; /* the projection returns 7 when t > this (0 = never) */
} problem;

static problem problem_default(void)
{
    return (problem){.fail_after = INFINITY, .nan_after = INFINITY, .failed_at = NAN};
}

/* counts the call; returns non-zero when the problem says this call fails */
static int common(double t, problem *p, int n, double *ydot)
{
    p->calls++;
    if (t > p->fail_after) {
        if (isnan(p->failed_at)) p->failed_at = t;
        return p->fail_code;
    }
    if (t > p->nan_after) {
        for (int i = 0; i < n; i++) ydot[i] = NAN;
        return 1;
    }
    return 0;
}

static int oscillator(double t, const double *y, double *ydot, void *ctx)
{
    int rc = common(t, ctx, 2, ydot);
    if (rc == 1) return 0;
    if (rc != 0) return rc;
    ydot[0] = y[1];
    ydot[1] = -y[0];
    return 0;
}

static int riccati(double t, const double *y, double *ydot, void *ctx)
{
    int rc = common(t, ctx, 1, ydot);
    if (rc == 1) return 0;
    if (rc != 0) return rc;
    ydot[0] = y[0] * y[0];
    return 0;
}

static int kepler(double t, const double *y, double *ydot, void *ctx)
{
    (void)t;
    ((problem *)ctx)->calls++;
    double r2 = y[0] * y[0] + y[1] * y[1], r3 = r2 * sqrt(r2);
    ydot[0] = y[2];
    ydot[1] = y[3];
    ydot[2] = -y[0] / r3;
    ydot[3] = -y[1] / r3;
    return 0;
}

static int stiff(double t, const double *y, double *ydot, void *ctx)
{
    problem *p = ctx;
    int rc = common(t, p, 1, ydot);
    if (rc == 1) return 0;
    if (rc != 0) return rc;
    ydot[0] = -p->lambda * (y[0] - cos(t)) - sin(t);
    return 0;
}

static int robertson(double t, const double *y, double *ydot, void *ctx)
{
    (void)t;
    ((problem *)ctx)->calls++;
    ydot[0] = -0.04 * y[0] + 1e4 * y[1] * y[2];
    ydot[2] = 3e7 * y[1] * y[1];
    ydot[1] = -ydot[0] - ydot[2];
    return 0;
}

/* mode 0: y' = 1; mode 1: y' = -y (a right-hand side that changes at a known time) */
static int switched(double t, const double *y, double *ydot, void *ctx)
{
    problem *p = ctx;
    int rc = common(t, p, 1, ydot);
    if (rc == 1) return 0;
    if (rc != 0) return rc;
    ydot[0] = p->mode == 0 ? 1.0 : -y[0];
    return 0;
}

static ctc_integ_spec rk4_spec(double h)
{
    return (ctc_integ_spec){.method = CTC_INTEG_RK4, .step = h};
}

static ctc_integ_spec adaptive_spec(ctc_integ_method m, double rtol, double atol)
{
    return (ctc_integ_spec){.method = m, .rtol = rtol, .atol = atol};
}

static ctc_integrator *make(const ctc_integ_spec *spec, int n, ctc_ode_rhs rhs, problem *p)
{
    char err[ERRLEN] = "";
    ctc_integrator *it = NULL;
    ctc_status st = ctc_integrator_new(spec, n, rhs, p, &it, err, sizeof err);
    cr_assert_eq(st, CTC_OK, "ctc_integrator_new: %s", err);
    cr_assert_not_null(it);
    return it;
}

/* an integrator of spec on the oscillator (context p), reset at t = 0 to y = (1, 0), on the
 * solution (cos t, -sin t); the caller frees it */
static ctc_integrator *start_oscillator(const ctc_integ_spec *spec, problem *p)
{
    static const double y0[2] = {1, 0};
    ctc_integrator *it = make(spec, 2, oscillator, p);
    cr_assert_eq(ctc_integrator_reset(it, 0, y0), 0);
    return it;
}

/* steps to t_end (tstop = t_end); asserts success and that no step passes t_end */
static void run_to(ctc_integrator *it, double t_end)
{
    char err[ERRLEN] = "";
    while (ctc_integrator_time(it) < t_end) {
        int rc = ctc_integrator_step(it, t_end, err, sizeof err);
        cr_assert_eq(rc, 0, "step failed (%d) at t = %.17g: %s", rc, ctc_integrator_time(it), err);
        cr_assert_leq(ctc_integrator_time(it), t_end);
    }
    cr_assert(ctc_integrator_time(it) == t_end, "ended at %a, want %a", ctc_integrator_time(it),
              t_end);
}

static double oscillator_error(const ctc_integrator *it)
{
    double t = ctc_integrator_time(it);
    const double *y = ctc_integrator_state(it);
    return fmax(fabs(y[0] - cos(t)), fabs(y[1] + sin(t)));
}

/* ---- rk4 ---- */

/* Halving the step from 2h to h took the error from prev to e: asserts the ratio prev / e lies
 * in (lo, hi), the order's 2^p with a margin (what names the error in the message). */
static void expect_halving_ratio(double prev, double e, double lo, double hi, double h,
                                 const char *what)
{
    double ratio = prev / e;
    cr_assert(ratio > lo && ratio < hi, "h = %g: %s %.3e, ratio %.3f not in (%g, %g)", h, what, e,
              ratio, lo, hi);
}

Test(integrator, rk4_converges_at_fourth_order_on_the_oscillator)
{
    /* global error at t = 5 for h = 0.1, 0.05, 0.025, 0.0125: ratio 2^4 = 16 */
    double prev = NAN;
    for (int k = 0; k < 4; k++) {
        double h = 0.1 / (1 << k);
        problem p = problem_default();
        ctc_integ_spec spec = rk4_spec(h);
        ctc_integrator *it = start_oscillator(&spec, &p);
        run_to(it, 5.0);
        double e = oscillator_error(it);
        const ctc_integ_stats *st = ctc_integrator_stats(it);
        cr_assert_eq(st->steps, 50L << k, "h = %g: %ld steps, want %ld", h, st->steps, 50L << k);
        cr_assert_eq(st->rhs_evals, 1 + 4 * st->steps, "h = %g: %ld evaluations", h, st->rhs_evals);
        cr_assert_eq(st->rejected, 0);
        cr_assert(isnan(st->err_estimate), "rk4 has no error estimate (got %g)", st->err_estimate);
        cr_assert_leq(fabs(st->h_last - h), 1e-9 * h, "h_last %.17g, want %.17g", st->h_last, h);
        if (k > 0) expect_halving_ratio(prev, e, 14, 18, h, "error");
        prev = e;
        ctc_integrator_free(it);
    }
}

/* max error of the dense output at 9 points inside each step of an oscillator run to t_end */
static double dense_error_inside_steps(ctc_integrator *it, double t_end, double *node_error)
{
    char err[ERRLEN] = "";
    double worst = 0, worst_node = 0, y[2];
    while (ctc_integrator_time(it) < t_end) {
        double t0 = ctc_integrator_time(it);
        cr_assert_eq(ctc_integrator_step(it, t_end, err, sizeof err), 0, "%s", err);
        double t1 = ctc_integrator_time(it);
        for (int j = 1; j <= 9; j++) {
            double s = t0 + 0.1 * j * (t1 - t0);
            ctc_integrator_dense(it, s, y);
            worst = fmax(worst, fmax(fabs(y[0] - cos(s)), fabs(y[1] + sin(s))));
        }
        worst_node = fmax(worst_node, oscillator_error(it));
    }
    if (node_error != NULL) *node_error = worst_node;
    return worst;
}

Test(integrator, rk4_dense_output_is_fourth_order_between_steps)
{
    /* the cubic Hermite interpolant's error is O(h^4), like the nodes': ratio 16 */
    double prev = NAN;
    for (int k = 0; k < 4; k++) {
        double h = 0.2 / (1 << k);
        problem p = problem_default();
        ctc_integ_spec spec = rk4_spec(h);
        ctc_integrator *it = start_oscillator(&spec, &p);
        double e = dense_error_inside_steps(it, 4.0, NULL);
        if (k > 0) expect_halving_ratio(prev, e, 14, 18, h, "dense error");
        prev = e;
        ctc_integrator_free(it);
    }
}

/* One step of size h from the exact value y(0) = 1 of y' = y^2 (the riccati problem) by spec's
 * method, whose first step must be h (checked: one step to reach h): the largest error of the
 * dense output at the 9 points s = 0.1 j h inside the step against the solution 1 / (1 - s). */
static double riccati_dense_error_in_one_step(const ctc_integ_spec *spec, double h)
{
    double y0 = 1, y[1], e = 0;
    problem p = problem_default();
    ctc_integrator *it = make(spec, 1, riccati, &p);
    cr_assert_eq(ctc_integrator_reset(it, 0, &y0), 0);
    run_to(it, h);
    cr_assert_eq(ctc_integrator_stats(it)->steps, 1);
    for (int j = 1; j <= 9; j++) {
        double s = 0.1 * j * h;
        ctc_integrator_dense(it, s, y);
        e = fmax(e, fabs(y[0] - 1 / (1 - s)));
    }
    ctc_integrator_free(it);
    return e;
}

Test(integrator, rk4_dense_output_has_third_order_local_accuracy_in_one_step)
{
    /* one step from the exact value: the interpolant is off by O(h^4) inside the step while
     * the step's end is off by O(h^5) only; y' = y^2 is not linear, so nothing cancels.
     * (From h = 0.2 the ratios are 22, 18.6, 17.2, 16.6, 16.3, 16.1: h = 0.025 is in the
     * asymptotic range.) */
    double prev = NAN;
    for (int k = 0; k < 4; k++) {
        double h = 0.025 / (1 << k);
        ctc_integ_spec spec = rk4_spec(h);
        double e = riccati_dense_error_in_one_step(&spec, h);
        if (k > 0) expect_halving_ratio(prev, e, 14, 18, h, "local dense error");
        prev = e;
    }
}

/* ---- dopri5 ---- */

Test(integrator, dopri5_meets_the_tolerance_on_the_oscillator)
{
    /* error at t = 10 within 10 rtol, and fewer steps as the tolerance loosens */
    long prev_steps = 0;
    for (int k = 10; k >= 6; k--) {
        double rtol = pow(10, -k);
        problem p = problem_default();
        ctc_integ_spec spec = adaptive_spec(CTC_INTEG_DOPRI5, rtol, rtol);
        ctc_integrator *it = start_oscillator(&spec, &p);
        run_to(it, 10.0);
        double e = oscillator_error(it);
        const ctc_integ_stats *st = ctc_integrator_stats(it);
        cr_assert_leq(e, 10 * rtol, "rtol %g: error %.3e", rtol, e);
        if (prev_steps > 0) {
            cr_assert_lt(st->steps, prev_steps, "rtol %g: %ld steps, not fewer than %ld", rtol,
                         st->steps, prev_steps);
        }
        /* FSAL: 6 evaluations an attempt, plus reset's and the starting step's one each */
        cr_assert_eq(st->rhs_evals, 2 + 6 * (st->steps + st->rejected), "%ld evaluations",
                     st->rhs_evals);
        cr_assert_eq(st->rhs_evals, p.calls);
        /* the sum of local error estimates bounds the (non-growing) global error */
        cr_assert(st->err_estimate > 0 && st->err_estimate >= e, "estimate %g, error %g",
                  st->err_estimate, e);
        prev_steps = st->steps;
        ctc_integrator_free(it);
    }
}

/* Tolerances set after the reset act from the next step: on the oscillator, dopri5 and bdf set
 * from 1e-10 to 1e-6 take the steps (within one) and reach the error of an integrator made at
 * 1e-6; rk4 and out-of-range values are refused with messages. */
Test(integrator, tolerances_set_after_the_reset_act_from_the_next_step)
{
    const double y0[2] = {1, 0};
    for (int m = CTC_INTEG_DOPRI5; m <= CTC_INTEG_BDF; m++) {
        problem p1 = problem_default(), p2 = problem_default();
        ctc_integ_spec tight = adaptive_spec((ctc_integ_method)m, 1e-10, 1e-10);
        ctc_integ_spec loose = adaptive_spec((ctc_integ_method)m, 1e-6, 1e-6);
        ctc_integrator *a = make(&tight, 2, oscillator, &p1), *b = make(&loose, 2, oscillator, &p2);
        cr_assert_eq(ctc_integrator_reset(a, 0, y0), 0);
        cr_assert_eq(ctc_integrator_reset(b, 0, y0), 0);
        char err[ERRLEN] = "";
        cr_assert_eq(ctc_integrator_set_tolerances(a, 1e-6, 1e-6, err, sizeof err), CTC_OK, "%s",
                     err);
        run_to(a, 10.0);
        run_to(b, 10.0);
        long sa = ctc_integrator_stats(a)->steps, sb = ctc_integrator_stats(b)->steps;
        cr_expect(labs(sa - sb) <= 1 + sb / 10, "%s: %ld steps against %ld",
                  ctc_integ_method_name((ctc_integ_method)m), sa, sb);
        cr_expect_leq(oscillator_error(a), 10 * fmax(oscillator_error(b), 1e-6));
        cr_expect_eq(ctc_integrator_set_tolerances(a, 2, 1e-6, err, sizeof err), CTC_EINVAL);
        cr_expect_str_eq(err, "rtol must be in (0, 1) (got 2)");
        cr_expect_eq(ctc_integrator_set_tolerances(a, 1e-6, 0, err, sizeof err), CTC_EINVAL);
        cr_expect_str_eq(err, "atol must be positive and finite (got 0)");
        ctc_integrator_free(a);
        ctc_integrator_free(b);
    }
    problem p = problem_default();
    ctc_integ_spec spec = rk4_spec(0.01);
    ctc_integrator *it = make(&spec, 2, oscillator, &p);
    char err[ERRLEN] = "";
    cr_expect_eq(ctc_integrator_set_tolerances(it, 1e-6, 1e-6, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "rk4 has no tolerances");
    ctc_integrator_free(it);
}

Test(integrator, dopri5_meets_the_tolerance_on_the_riccati_equation)
{
    /* y' = y^2 on [0, 0.9]: y(0.9) = 10, with |y'''''| growing fast towards the pole */
    long prev_steps = 0;
    for (int k = 10; k >= 6; k--) {
        double rtol = pow(10, -k), y0 = 1;
        problem p = problem_default();
        ctc_integ_spec spec = adaptive_spec(CTC_INTEG_DOPRI5, rtol, rtol);
        ctc_integrator *it = make(&spec, 1, riccati, &p);
        cr_assert_eq(ctc_integrator_reset(it, 0, &y0), 0);
        run_to(it, 0.9);
        double rel = fabs(ctc_integrator_state(it)[0] - 1 / (1 - 0.9)) / 10;
        long steps = ctc_integrator_stats(it)->steps;
        cr_assert_leq(rel, 10 * rtol, "rtol %g: relative error %.3e", rtol, rel);
        if (prev_steps > 0) cr_assert_lt(steps, prev_steps, "rtol %g: %ld steps", rtol, steps);
        prev_steps = steps;
        ctc_integrator_free(it);
    }
}

Test(integrator, dopri5_follows_an_eccentric_kepler_orbit)
{
    /* e = 0.5 from perihelion: after one period 2 pi the state is back at the start, and the
     * energy -1/2 is conserved. The tolerance bounds the local error; the global error of this
     * orbit, mostly a phase error from the fast passage through perihelion, measures 100-230
     * rtol for rtol 1e-6 ... 1e-12 (atol = rtol), the energy error 0-11 rtol. */
    const double e = 0.5, y0[4] = {1 - e, 0, 0, sqrt((1 + e) / (1 - e))};
    for (int k = 10; k >= 7; k--) {
        double rtol = pow(10, -k);
        problem p = problem_default();
        ctc_integ_spec spec = adaptive_spec(CTC_INTEG_DOPRI5, rtol, rtol);
        ctc_integrator *it = make(&spec, 4, kepler, &p);
        cr_assert_eq(ctc_integrator_reset(it, 0, y0), 0);
        run_to(it, TWO_PI);
        const double *y = ctc_integrator_state(it);
        double dist = 0;
        for (int i = 0; i < 4; i++) dist = fmax(dist, fabs(y[i] - y0[i]));
        double energy = 0.5 * (y[2] * y[2] + y[3] * y[3]) - 1 / hypot(y[0], y[1]);
        cr_assert_leq(dist, 300 * rtol, "rtol %g: distance from the start %.3e", rtol, dist);
        cr_assert_leq(fabs(energy + 0.5), 20 * rtol, "rtol %g: energy %.15f", rtol, energy);
        ctc_integrator_free(it);
    }
}

Test(integrator, dopri5_dense_output_is_fourth_order)
{
    /* one step of fixed size h (initial_step = max_step = h, loose tolerances) from the exact
     * value of y' = y^2: the continuous extension's local error is O(h^5), ratio 32 (a 3rd-order
     * interpolant would give 16). From h = 0.2 the ratios are 43, 37, 34, 33.0, 32.4; below
     * h = 0.006 the error nears round-off. */
    double prev = NAN;
    for (int k = 0; k < 3; k++) {
        double h = 0.025 / (1 << k);
        ctc_integ_spec spec = adaptive_spec(CTC_INTEG_DOPRI5, 0.5, 1e3);
        spec.initial_step = h;
        spec.max_step = h;
        double e = riccati_dense_error_in_one_step(&spec, h);
        if (k > 0) expect_halving_ratio(prev, e, 28, 36, h, "dense error");
        prev = e;
    }
}

Test(integrator, dopri5_dense_output_matches_the_solution_inside_steps)
{
    for (int k = 9; k >= 6; k--) {
        double rtol = pow(10, -k), node_error;
        problem p = problem_default();
        ctc_integ_spec spec = adaptive_spec(CTC_INTEG_DOPRI5, rtol, rtol);
        ctc_integrator *it = start_oscillator(&spec, &p);
        double e = dense_error_inside_steps(it, 10.0, &node_error);
        cr_assert_leq(e, 10 * rtol, "rtol %g: dense error %.3e (at the steps' ends %.3e)", rtol, e,
                      node_error);
        ctc_integrator_free(it);
    }
}

Test(integrator, dopri5_reset_keeps_the_step_size)
{
    /* the automatic starting step costs one evaluation, at the first step only; a reset later
     * keeps the step size, so the step after it costs 6 per attempt and nothing more */
    problem p = problem_default();
    ctc_integ_spec spec = adaptive_spec(CTC_INTEG_DOPRI5, 1e-8, 1e-8);
    ctc_integrator *it = start_oscillator(&spec, &p);
    char err[ERRLEN] = "";
    for (int i = 0; i < 5; i++) cr_assert_eq(ctc_integrator_step(it, 10, err, sizeof err), 0);
    const ctc_integ_stats *st = ctc_integrator_stats(it);
    cr_assert_eq(st->rhs_evals, 2 + 6 * (st->steps + st->rejected));
    double y[2], t = ctc_integrator_time(it), h_before = st->h_last;
    memcpy(y, ctc_integrator_state(it), sizeof y);
    cr_assert_eq(ctc_integrator_reset(it, t, y), 0);
    long evals = st->rhs_evals, steps = st->steps, rejected = st->rejected;
    cr_assert_eq(evals, 3 + 6 * (steps + rejected), "reset evaluates f once");
    cr_assert_eq(ctc_integrator_step(it, 10, err, sizeof err), 0);
    cr_assert_eq(st->steps, steps + 1, "stats are kept across a reset");
    cr_assert_eq(st->rhs_evals - evals, 6 * (1 + st->rejected - rejected));
    cr_assert_geq(st->h_last, 0.5 * h_before, "h %g after the reset, %g before", st->h_last,
                  h_before);
    ctc_integrator_free(it);
}

Test(integrator, dopri5_bounds_the_step_by_max_step)
{
    problem p = problem_default();
    ctc_integ_spec spec = adaptive_spec(CTC_INTEG_DOPRI5, 1e-3, 1e-3);
    spec.max_step = 0.01;
    ctc_integrator *it = start_oscillator(&spec, &p);
    char err[ERRLEN] = "";
    while (ctc_integrator_time(it) < 1) {
        cr_assert_eq(ctc_integrator_step(it, 1, err, sizeof err), 0, "%s", err);
        cr_assert_leq(ctc_integrator_stats(it)->h_last, 0.01);
    }
    cr_assert_geq(ctc_integrator_stats(it)->steps, 100);
    ctc_integrator_free(it);
}

/* ---- bdf ---- */

Test(integrator, bdf_solves_a_stiff_problem_in_far_fewer_steps_than_dopri5)
{
    /* lambda = 1e5: dopri5's steps are held to its stability bound ~3.3 / lambda, while BDF's
     * follow the smooth solution cos t */
    const double rtol = 1e-6, atol = 1e-8, t_end = 2.0, y0 = 1;
    long steps[2];
    for (int m = 0; m < 2; m++) {
        ctc_integ_method method = m == 0 ? CTC_INTEG_BDF : CTC_INTEG_DOPRI5;
        problem p = problem_default();
        p.lambda = 1e5;
        ctc_integ_spec spec = adaptive_spec(method, rtol, atol);
        spec.max_steps = 200000; /* fail, rather than crawl, if the step control breaks */
        ctc_integrator *it = make(&spec, 1, stiff, &p);
        cr_assert_eq(ctc_integrator_reset(it, 0, &y0), 0);
        double worst = 0, y[1];
        char err[ERRLEN] = "";
        while (ctc_integrator_time(it) < t_end) {
            double t0 = ctc_integrator_time(it);
            cr_assert_eq(ctc_integrator_step(it, t_end, err, sizeof err), 0, "%s", err);
            double t1 = ctc_integrator_time(it);
            worst = fmax(worst, fabs(ctc_integrator_state(it)[0] - cos(t1)));
            ctc_integrator_dense(it, 0.5 * (t0 + t1), y);
            worst = fmax(worst, fabs(y[0] - cos(0.5 * (t0 + t1))));
        }
        const ctc_integ_stats *st = ctc_integrator_stats(it);
        cr_assert_leq(worst, 10 * rtol, "%s: error %.3e (steps and midpoints)",
                      ctc_integ_method_name(method), worst);
        cr_assert_eq(st->rhs_evals, p.calls, "%s: %ld evaluations counted, %ld made",
                     ctc_integ_method_name(method), st->rhs_evals, p.calls);
        steps[m] = st->steps;
        if (method == CTC_INTEG_BDF) {
            cr_assert_gt(st->jac_evals, 0);
            cr_assert(st->err_estimate > 0 && st->err_estimate < 1e-3, "estimate %g",
                      st->err_estimate);
        } else {
            cr_assert_eq(st->jac_evals, 0);
        }
        ctc_integrator_free(it);
    }
    cr_assert_lt(steps[0], 500, "bdf took %ld steps", steps[0]);
    cr_assert_gt(steps[1], 50000, "dopri5 took %ld steps", steps[1]);
    cr_assert_lt(100 * steps[0], steps[1], "bdf %ld steps, dopri5 %ld", steps[0], steps[1]);
}

Test(integrator, bdf_matches_robertsons_reference_solution)
{
    /* y(40) = (7.158271e-01, 9.185535e-06, 2.841638e-01), 7 digits as printed by CVODE's
     * cvRoberts_dns example; also against dopri5 at rtol 1e-12 (a different method, which needs
     * ~100 times the steps); y1 + y2 + y3 = 1 is kept */
    const double want[3] = {7.158271e-01, 9.185535e-06, 2.841638e-01}, y0[3] = {1, 0, 0};
    double got[2][3];
    long steps[2];
    for (int m = 0; m < 2; m++) {
        problem p = problem_default();
        ctc_integ_spec spec = m == 0 ? adaptive_spec(CTC_INTEG_BDF, 1e-8, 1e-14)
                                     : adaptive_spec(CTC_INTEG_DOPRI5, 1e-12, 1e-16);
        spec.max_steps = 200000;
        ctc_integrator *it = make(&spec, 3, robertson, &p);
        cr_assert_eq(ctc_integrator_reset(it, 0, y0), 0);
        run_to(it, 40.0);
        memcpy(got[m], ctc_integrator_state(it), sizeof got[m]);
        steps[m] = ctc_integrator_stats(it)->steps;
        cr_assert_eq(ctc_integrator_stats(it)->rhs_evals, p.calls);
        ctc_integrator_free(it);
    }
    for (int i = 0; i < 3; i++) {
        cr_assert_leq(fabs(got[0][i] - want[i]), 6e-7 * want[i], "bdf y%d = %.10e, want %.6e",
                      i + 1, got[0][i], want[i]);
        cr_assert_leq(fabs(got[1][i] - want[i]), 6e-7 * want[i], "dopri5 y%d = %.10e", i + 1,
                      got[1][i]);
        cr_assert_leq(fabs(got[0][i] - got[1][i]), 2e-7 * want[i], "y%d: bdf %.10e dopri5 %.10e",
                      i + 1, got[0][i], got[1][i]);
    }
    cr_assert_leq(fabs(got[0][0] + got[0][1] + got[0][2] - 1), 1e-10);
    cr_assert_lt(10 * steps[0], steps[1], "bdf %ld steps, dopri5 %ld", steps[0], steps[1]);
}

/* y0' = -lambda (y0 - u) + cos t, y1' = -y1 + u, with the input u switched between 0 and 1 at
 * t = 1, 2, ...: a stiff forced system with jumps */
static int forced(double t, const double *y, double *ydot, void *ctx)
{
    problem *p = ctx;
    p->calls++;
    ydot[0] = -p->lambda * (y[0] - p->mode) + cos(t);
    ydot[1] = -y[1] + p->mode;
    return 0;
}

Test(integrator, bdf_restarts_after_each_jump_of_a_stiff_forced_system)
{
    /* After each jump, y0's transient decays as exp(-lambda t), gone (e^-1e4) by the next
     * integer time, where y0 = u + (lambda cos t + sin t) / (1 + lambda^2) exactly; y1 relaxes
     * to u with exp(-(t - k)). A restart from a step that suited the smooth stretch before the
     * jump would fail CVODE's error test at order 1 again and again. */
    const double lambda = 1e4, rtol = 1e-6;
    problem p = problem_default();
    p.lambda = lambda;
    ctc_integ_spec spec = adaptive_spec(CTC_INTEG_BDF, rtol, 1e-9);
    ctc_integrator *it = make(&spec, 2, forced, &p);
    double y[2] = {0, 0}, y1_exact = 0;
    cr_assert_eq(ctc_integrator_reset(it, 0, y), 0);
    for (int k = 1; k <= 10; k++) {
        run_to(it, k);
        const double *yk = ctc_integrator_state(it);
        y1_exact = p.mode + (y1_exact - p.mode) * exp(-1.0);
        double y0_exact = p.mode + (lambda * cos(k) + sin(k)) / (1 + lambda * lambda);
        cr_assert_leq(fabs(yk[0] - y0_exact), 10 * rtol, "t = %d: y0 %.9f, want %.9f", k, yk[0],
                      y0_exact);
        cr_assert_leq(fabs(yk[1] - y1_exact), 10 * rtol, "t = %d: y1 %.9f, want %.9f", k, yk[1],
                      y1_exact);
        p.mode = k % 2;
        memcpy(y, yk, sizeof y);
        cr_assert_eq(ctc_integrator_reset(it, k, y), 0);
    }
    const ctc_integ_stats *st = ctc_integrator_stats(it);
    cr_assert_eq(st->rhs_evals, p.calls);
    cr_assert_lt(st->steps, 3000, "%ld steps", st->steps);
    ctc_integrator_free(it);
}

/* ---- all methods ---- */

static ctc_integ_spec method_spec(int m)
{
    switch (m) {
    case 0:
        return rk4_spec(0.03);
    case 1:
        return adaptive_spec(CTC_INTEG_DOPRI5, 1e-8, 1e-8);
    default:
        return adaptive_spec(CTC_INTEG_BDF, 1e-8, 1e-8);
    }
}

/* the oscillator's invariant |y| = 1: y scaled back onto the unit circle when off by > 1e-13 */
static int onto_circle(double t, double *y, void *ctx)
{
    problem *p = ctx;
    p->proj_calls++;
    if (p->proj_fail_after > 0 && t > p->proj_fail_after) return 7;
    double r = hypot(y[0], y[1]);
    if (fabs(r - 1) <= 1e-13) return 0;
    y[0] /= r, y[1] /= r;
    p->projections++;
    return 0;
}

Test(integrator, bdf_projects_inside_its_steps_and_keeps_its_history)
{
    /* CVODE's projection keeps its order and step size: the run takes about the steps it takes
       without projection and ends each step on the invariant. Projecting between steps and
       restarting (ctc_integrator_reset) instead goes back to order 1 after every step. Measured
       here: 262 steps in-step, 225 without projection, 249,126 projecting between steps; the
       errors at t = 20 were 3.3e-6, 3.1e-5 and 3.0e-6 */
    const double rtol = 1e-6, t_end = 20;
    long steps[3];
    double err[3];
    for (int mode = 0; mode < 3; mode++) { /* none, in-step, between steps with restarts */
        problem p = problem_default();
        ctc_integ_spec spec = adaptive_spec(CTC_INTEG_BDF, rtol, 1e-9);
        ctc_integrator *it = make(&spec, 2, oscillator, &p);
        char msg[ERRLEN] = "";
        if (mode == 1) cr_assert_eq(ctc_integrator_set_projection(it, onto_circle, msg, ERRLEN), 0);
        double y[2] = {1, 0}, worst_r = 0;
        cr_assert_eq(ctc_integrator_reset(it, 0, y), 0);
        while (ctc_integrator_time(it) < t_end) {
            cr_assert_eq(ctc_integrator_step(it, t_end, msg, sizeof msg), 0, "%s", msg);
            const double *yk = ctc_integrator_state(it);
            double t = ctc_integrator_time(it);
            if (mode == 2) {
                memcpy(y, yk, sizeof y);
                long before = p.projections;
                onto_circle(t, y, &p);
                if (p.projections > before) cr_assert_eq(ctc_integrator_reset(it, t, y), 0);
            } else if (mode == 1) {
                worst_r = fmax(worst_r, fabs(hypot(yk[0], yk[1]) - 1));
            }
        }
        const double *yk = ctc_integrator_state(it);
        err[mode] = fmax(fabs(yk[0] - cos(t_end)), fabs(yk[1] + sin(t_end)));
        steps[mode] = ctc_integrator_stats(it)->steps;
        if (mode == 1) {
            cr_expect_leq(worst_r, 1e-13, "|y| - 1 at a step's end: %g", worst_r);
            cr_expect_gt(p.projections, steps[1] / 2, "%ld projections in %ld steps", p.projections,
                         steps[1]);
            cr_expect_geq(p.proj_calls, steps[1]);
        }
        cr_assert_eq(ctc_integrator_stats(it)->rhs_evals, p.calls);
        ctc_integrator_free(it);
    }
    cr_expect_leq(steps[1], steps[0] + steps[0] / 2, "in-step %ld steps, none %ld", steps[1],
                  steps[0]);
    cr_expect_gt(steps[2], 3 * steps[1], "restarts %ld steps, in-step %ld", steps[2], steps[1]);
    cr_expect_leq(err[1], 2 * err[0] + 1e-6, "error in-step %g, none %g", err[1], err[0]);
}

Test(integrator, a_failed_projection_stops_the_step_and_only_bdf_projects)
{
    problem p = problem_default();
    p.proj_fail_after = 0.5;
    ctc_integ_spec spec = adaptive_spec(CTC_INTEG_BDF, 1e-6, 1e-9);
    ctc_integrator *it = make(&spec, 2, oscillator, &p);
    char msg[ERRLEN] = "";
    cr_assert_eq(ctc_integrator_set_projection(it, onto_circle, msg, ERRLEN), CTC_OK);
    double y[2] = {1, 0};
    cr_assert_eq(ctc_integrator_reset(it, 0, y), 0);
    int rc = 0;
    while (rc == 0 && ctc_integrator_time(it) < 2) rc = ctc_integrator_step(it, 2, msg, ERRLEN);
    cr_assert_eq(rc, 7);
    cr_expect(strstr(msg, "projection failed (returned 7) at t = ") == msg, "%s", msg);
    cr_expect_leq(ctc_integrator_time(it), 0.5, "state stays at the last accepted step");
    ctc_integrator_free(it);

    for (int m = 0; m < 2; m++) {
        ctc_integ_spec es = method_spec(m);
        it = make(&es, 2, oscillator, &p);
        cr_assert_eq(ctc_integrator_set_projection(it, onto_circle, msg, ERRLEN), CTC_EINVAL);
        char want[ERRLEN];
        snprintf(want, sizeof want, "in-step projection needs method bdf (this integrator is %s)",
                 m ? "dopri5" : "rk4");
        cr_expect_str_eq(msg, want);
        ctc_integrator_free(it);
    }
}

/* NULL turns the projection off, also on a bdf integrator that never had one, and a run after
   it is not projected */
Test(integrator, a_null_projection_turns_it_off)
{
    problem p = problem_default();
    p.proj_fail_after = 0.5; /* a projection called after t = 0.5 would fail the run */
    ctc_integ_spec spec = adaptive_spec(CTC_INTEG_BDF, 1e-6, 1e-9);
    ctc_integrator *it = make(&spec, 2, oscillator, &p);
    char msg[ERRLEN] = "";
    cr_assert_eq(ctc_integrator_set_projection(it, NULL, msg, ERRLEN), CTC_OK, "%s", msg);
    cr_assert_eq(ctc_integrator_set_projection(it, onto_circle, msg, ERRLEN), CTC_OK, "%s", msg);
    cr_assert_eq(ctc_integrator_set_projection(it, NULL, msg, ERRLEN), CTC_OK, "%s", msg);
    double y[2] = {1, 0};
    cr_assert_eq(ctc_integrator_reset(it, 0, y), 0);
    int rc = 0;
    while (rc == 0 && ctc_integrator_time(it) < 2) rc = ctc_integrator_step(it, 2, msg, ERRLEN);
    cr_expect_eq(rc, 0, "%s", msg);
    ctc_integrator_free(it);
}

Test(integrator, every_method_lands_exactly_on_tstop)
{
    /* output times k / 10 (not multiples of rk4's 0.03, and 0.1 + 0.2 != 0.3 in binary): every
     * step ends at or before its tstop, and the last one on it, bit for bit */
    for (int m = 0; m < 3; m++) {
        problem p = problem_default();
        ctc_integ_spec spec = method_spec(m);
        ctc_integrator *it = start_oscillator(&spec, &p);
        char err[ERRLEN] = "";
        for (int k = 1; k <= 30; k++) {
            double tstop = k == 3 ? 0.1 + 0.2 : k / 10.0;
            while (ctc_integrator_time(it) < tstop) {
                double t0 = ctc_integrator_time(it);
                cr_assert_eq(ctc_integrator_step(it, tstop, err, sizeof err), 0, "%s", err);
                double t1 = ctc_integrator_time(it);
                cr_assert_leq(t1, tstop, "%s: step to %a passed tstop %a",
                              ctc_integ_method_name(spec.method), t1, tstop);
                if (m == 0) {
                    cr_assert_leq(t1 - t0, 1.01 * 0.03 + 1e-15, "rk4 step %g", t1 - t0);
                    /* 0.03, 0.03, then 0.04 left: two steps of 0.02, not 0.03 and 0.01 */
                    cr_assert_geq(t1 - t0, 0.015, "rk4 step %g is a sliver", t1 - t0);
                }
            }
            cr_assert(ctc_integrator_time(it) == tstop, "%s: at %a, want %a",
                      ctc_integ_method_name(spec.method), ctc_integrator_time(it), tstop);
        }
        cr_assert_leq(oscillator_error(it), 1e-6, "%s: error %g",
                      ctc_integ_method_name(spec.method), oscillator_error(it));
        ctc_integrator_free(it);
    }
}

Test(integrator, a_step_ends_on_tstop_where_t_plus_the_remainder_rounds_elsewhere)
{
    /* for these two times t0 + (tstop - t0) != tstop in binary: one step from t0 covering the
     * whole distance must still end on tstop itself */
    const double t0 = 0.1180799059133742, tstop = 0.6681396787422725, y0[2] = {1, 0};
    volatile double remainder = tstop - t0;
    cr_assert(t0 + remainder != tstop, "the times no longer show the rounding");
    for (int m = 0; m < 3; m++) {
        problem p = problem_default();
        ctc_integ_spec spec = method_spec(m);
        spec.step = 0.6;
        if (m == 1) spec = adaptive_spec(CTC_INTEG_DOPRI5, 0.5, 1e3), spec.initial_step = 1;
        ctc_integrator *it = make(&spec, 2, oscillator, &p);
        char err[ERRLEN] = "";
        cr_assert_eq(ctc_integrator_reset(it, t0, y0), 0);
        while (ctc_integrator_time(it) < tstop) {
            cr_assert_eq(ctc_integrator_step(it, tstop, err, sizeof err), 0, "%s", err);
        }
        cr_assert(ctc_integrator_time(it) == tstop, "%s: at %a, want %a",
                  ctc_integ_method_name(spec.method), ctc_integrator_time(it), tstop);
        if (m < 2) cr_assert_eq(ctc_integrator_stats(it)->steps, 1);
        ctc_integrator_free(it);
    }
}

Test(integrator, dense_output_at_the_end_of_the_step_is_the_state)
{
    for (int m = 0; m < 3; m++) {
        problem p = problem_default();
        ctc_integ_spec spec = method_spec(m);
        ctc_integrator *it = start_oscillator(&spec, &p);
        char err[ERRLEN] = "";
        double y[2];
        ctc_integrator_dense(it, 0, y);
        cr_assert(y[0] == 1 && y[1] == 0, "after reset: (%g, %g)", y[0], y[1]);
        for (int i = 0; i < 7; i++) {
            cr_assert_eq(ctc_integrator_step(it, 0.7, err, sizeof err), 0, "%s", err);
            ctc_integrator_dense(it, ctc_integrator_time(it), y);
            cr_assert(memcmp(y, ctc_integrator_state(it), sizeof y) == 0, "%s: step %d",
                      ctc_integ_method_name(spec.method), i);
        }
        ctc_integrator_free(it);
    }
}

Test(integrator, every_method_restarts_cleanly_after_a_discontinuity)
{
    /* y' = 1 from y(0) = 0 to t = 1; then the rhs switches to y' = -y and the caller doubles
     * y, so y = 2 exp(-(t - 1)) on [1, 3]. A stale first stage (dopri5's FSAL, rk4's k1) or
     * stale history (bdf) would carry the old slope +1 into the new phase. */
    for (int m = 0; m < 3; m++) {
        problem p = problem_default();
        ctc_integ_spec spec = method_spec(m);
        spec.step = 0.01;
        ctc_integrator *it = make(&spec, 1, switched, &p);
        double y = 0;
        cr_assert_eq(ctc_integrator_reset(it, 0, &y), 0);
        run_to(it, 1.0);
        cr_assert_leq(fabs(ctc_integrator_state(it)[0] - 1), 1e-12);
        long steps = ctc_integrator_stats(it)->steps;

        p.mode = 1;
        y = 2 * ctc_integrator_state(it)[0];
        cr_assert_eq(ctc_integrator_reset(it, 1.0, &y), 0);
        cr_assert_eq(ctc_integrator_stats(it)->steps, steps, "reset keeps the statistics");
        run_to(it, 3.0);
        double e = fabs(ctc_integrator_state(it)[0] - 2 * exp(-2.0));
        /* rk4 h = 0.01: ~5e-11; dopri5 and bdf at rtol 1e-8: ~2e-9 and ~1.5e-7 (BDF's global
         * error runs to 10-20 rtol) */
        const double bound[3] = {1e-9, 1e-7, 1e-6};
        cr_assert_leq(e, bound[m], "%s: error %.3e after the restart",
                      ctc_integ_method_name(spec.method), e);
        cr_assert_eq(ctc_integrator_stats(it)->rhs_evals, p.calls, "%s: evaluations",
                     ctc_integ_method_name(spec.method));
        ctc_integrator_free(it);
    }
}

Test(integrator, rhs_failure_is_returned_and_the_state_stays_at_the_last_step)
{
    const double y0[2] = {1, 0};
    for (int m = 0; m < 3; m++) {
        problem p = problem_default();
        p.fail_after = 0.55;
        p.fail_code = 7;
        ctc_integ_spec spec = method_spec(m);
        ctc_integrator *it = make(&spec, 2, oscillator, &p);
        const char *name = ctc_integ_method_name(spec.method);
        char err[ERRLEN] = "", want[ERRLEN];
        cr_assert_eq(ctc_integrator_reset(it, 0, y0), 0);
        double t = 0, y[2];
        int rc = 0;
        long steps = 0;
        while (rc == 0) {
            t = ctc_integrator_time(it);
            memcpy(y, ctc_integrator_state(it), sizeof y);
            steps = ctc_integrator_stats(it)->steps;
            rc = ctc_integrator_step(it, 1.0, err, sizeof err);
        }
        cr_assert_eq(rc, 7, "%s: returned %d: %s", name, rc, err);
        cr_assert(t <= 0.55 && ctc_integrator_time(it) == t, "%s: time %.17g, was %.17g", name,
                  ctc_integrator_time(it), t);
        cr_assert(memcmp(y, ctc_integrator_state(it), sizeof y) == 0, "%s: state changed", name);
        cr_assert_eq(ctc_integrator_stats(it)->steps, steps);
        snprintf(want, sizeof want, "right-hand side failed (returned 7) at t = %.10g s",
                 p.failed_at);
        cr_assert_str_eq(err, want, "%s", name);
        cr_assert_eq(ctc_integrator_stats(it)->rhs_evals, p.calls, "%s", name);

        /* the dense output of the last accepted step is intact */
        double yd[2];
        ctc_integrator_dense(it, t, yd);
        cr_assert(memcmp(y, yd, sizeof y) == 0, "%s", name);

        /* once the rhs recovers, stepping goes on from there */
        p.fail_after = INFINITY;
        run_to(it, 1.0);
        cr_assert_leq(oscillator_error(it), 1e-6, "%s: error %g", name, oscillator_error(it));
        ctc_integrator_free(it);
    }
}

Test(integrator, rhs_failure_at_reset_is_returned_and_blocks_stepping)
{
    const double y0[2] = {1, 0};
    for (int m = 0; m < 3; m++) {
        problem p = problem_default();
        p.fail_after = -1;
        p.fail_code = -3;
        ctc_integ_spec spec = method_spec(m);
        ctc_integrator *it = make(&spec, 2, oscillator, &p);
        char err[ERRLEN] = "";
        cr_assert_eq(ctc_integrator_reset(it, 0, y0), -3);
        cr_assert_eq(ctc_integrator_step(it, 1, err, sizeof err), -1);
        cr_assert_str_eq(err, "no state to step from: reset was not called or failed");
        ctc_integrator_free(it);
    }
}

Test(integrator, step_size_underflow_is_reported)
{
    /* a step of 1e-17 s at t = 1 s moves t by less than 16 ulp */
    char err[ERRLEN] = "";
    const double y0[2] = {1, 0};
    for (int m = 0; m < 3; m++) {
        problem p = problem_default();
        ctc_integ_spec spec = method_spec(m);
        spec.step = 1e-17;
        spec.initial_step = 1e-17;
        spec.max_step = 1e-17;
        ctc_integrator *it = make(&spec, 2, oscillator, &p);
        cr_assert_eq(ctc_integrator_reset(it, 1.0, y0), 0);
        cr_assert_eq(ctc_integrator_step(it, 2.0, err, sizeof err), -1, "%s",
                     ctc_integ_method_name(spec.method));
        cr_assert_str_eq(err, "step size 1e-17 s at t = 1 s fell below the round-off limit");
        cr_assert(ctc_integrator_time(it) == 1.0);
        cr_assert_eq(ctc_integrator_stats(it)->steps, 0);
        ctc_integrator_free(it);
    }
}

Test(integrator, dopri5_stops_at_the_pole_of_the_riccati_equation)
{
    /* y = 1 / (1 - t) has a pole at t = 1: the step shrinks until it underflows there */
    char err[ERRLEN] = "", want[ERRLEN];
    double y0 = 1, h, t;
    problem p = problem_default();
    ctc_integ_spec spec = adaptive_spec(CTC_INTEG_DOPRI5, 1e-8, 1e-8);
    ctc_integrator *it = make(&spec, 1, riccati, &p);
    cr_assert_eq(ctc_integrator_reset(it, 0, &y0), 0);
    int rc = 0;
    while (rc == 0) rc = ctc_integrator_step(it, 2.0, err, sizeof err);
    cr_assert_eq(rc, -1, "%s", err);
    cr_assert_eq(sscanf(err, "step size %lg s at t = %lg s", &h, &t), 2, "message: %s", err);
    snprintf(want, sizeof want, "step size %.3g s at t = %.10g s fell below the round-off limit", h,
             t);
    cr_assert_str_eq(err, want);
    /* the numerical solution's pole is off the exact one by about the tolerance */
    double t_now = ctc_integrator_time(it);
    cr_assert(fabs(t - 1) < 1e-6 && fabs(t - t_now) <= 1e-9, "stopped at t = %.17g", t_now);
    cr_assert_lt(h, 16 * DBL_EPSILON * t_now * 1.001, "h = %g", h);
    ctc_integrator_free(it);
}

Test(integrator, adaptive_methods_stop_where_the_step_falls_below_min_step)
{
    /* y = 1 / (1 - t): near the pole the error control wants h ~ (1 - t) times a constant, so a
     * floor of 1e-4 s stops both methods a little before t = 1, at a step they wanted below it
     * and long before the round-off limit */
    for (int m = 0; m < 2; m++) {
        char err[ERRLEN] = "", want[ERRLEN];
        double y0 = 1, h, t;
        problem p = problem_default();
        ctc_integ_spec spec = adaptive_spec(m == 0 ? CTC_INTEG_DOPRI5 : CTC_INTEG_BDF, 1e-6, 1e-6);
        spec.min_step = 1e-4;
        ctc_integrator *it = make(&spec, 1, riccati, &p);
        cr_assert_eq(ctc_integrator_reset(it, 0, &y0), 0);
        int rc = 0;
        while (rc == 0) rc = ctc_integrator_step(it, 2.0, err, sizeof err);
        cr_assert_eq(rc, -1, "%s: %s", ctc_integ_method_name(spec.method), err);
        cr_assert_eq(sscanf(err, "step size %lg s at t = %lg s", &h, &t), 2, "message: %s", err);
        snprintf(want, sizeof want,
                 "step size %.3g s at t = %.10g s fell below min_step (0.0001 s): the problem "
                 "needs a smaller step, looser tolerances or \"method\": \"bdf\"",
                 h, t);
        cr_assert_str_eq(err, want);
        cr_assert_leq(h, 1e-4 * (1 + 1e-12), "h = %g", h);
        cr_assert(t > 0.99 && t < 1, "%s stopped at t = %.17g", ctc_integ_method_name(spec.method),
                  t);
        cr_assert_geq(ctc_integrator_stats(it)->h_last, 1e-4 * (1 - 1e-12), "%s h_last %g",
                      ctc_integ_method_name(spec.method), ctc_integrator_stats(it)->h_last);
        ctc_integrator_free(it);
    }
}

Test(integrator, min_step_spares_the_step_cut_short_to_land_on_tstop)
{
    /* a smooth oscillator with a floor of 0.01 s: the last step to tstop = 1.0005 s is shorter
     * than the floor and still taken */
    for (int m = 0; m < 2; m++) {
        char err[ERRLEN] = "";
        problem p = problem_default();
        ctc_integ_spec spec = adaptive_spec(m == 0 ? CTC_INTEG_DOPRI5 : CTC_INTEG_BDF, 1e-3, 1e-3);
        spec.min_step = 0.01;
        ctc_integrator *it = start_oscillator(&spec, &p);
        while (ctc_integrator_time(it) < 1.0005) {
            cr_assert_eq(ctc_integrator_step(it, 1.0005, err, sizeof err), 0, "%s", err);
        }
        cr_assert(ctc_integrator_time(it) == 1.0005);
        ctc_integrator_free(it);
    }
}

Test(integrator, dopri5_gives_up_on_a_non_finite_solution)
{
    /* the rhs returns NaN for every t > 0: each attempt is cut to a fifth; the 10th fails */
    char err[ERRLEN] = "";
    problem p = problem_default();
    p.nan_after = 0;
    ctc_integ_spec spec = adaptive_spec(CTC_INTEG_DOPRI5, 1e-6, 1e-6);
    spec.initial_step = 0.1;
    ctc_integrator *it = start_oscillator(&spec, &p);
    cr_assert_eq(ctc_integrator_step(it, 1.0, err, sizeof err), -1);
    cr_assert_str_eq(err, "solution not finite at t = 0 s after 10 step size reductions (last "
                          "step 5.12e-08 s)");
    const ctc_integ_stats *st = ctc_integrator_stats(it);
    cr_assert_eq(st->rejected, 10);
    cr_assert_eq(st->steps, 0);
    cr_assert_eq(st->rhs_evals, 1 + 60);
    cr_assert(ctc_integrator_time(it) == 0 && ctc_integrator_state(it)[0] == 1);
    ctc_integrator_free(it);
}

Test(integrator, max_steps_is_enforced)
{
    char err[ERRLEN] = "", want[ERRLEN];
    for (int m = 0; m < 3; m++) {
        problem p = problem_default();
        ctc_integ_spec spec = method_spec(m);
        spec.step = 0.1;
        spec.max_steps = 5;
        ctc_integrator *it = start_oscillator(&spec, &p);
        for (int i = 0; i < 5; i++) {
            cr_assert_eq(ctc_integrator_step(it, 10.0, err, sizeof err), 0, "%s", err);
        }
        double t = ctc_integrator_time(it);
        cr_assert_eq(ctc_integrator_step(it, 10.0, err, sizeof err), -1);
        snprintf(want, sizeof want, "max_steps (5) reached at t = %.10g s", t);
        cr_assert_str_eq(err, want, "%s", ctc_integ_method_name(spec.method));
        cr_assert(ctc_integrator_time(it) == t);
        if (m == 0) cr_assert_str_eq(err, "max_steps (5) reached at t = 0.5 s");
        ctc_integrator_free(it);
    }
}

Test(integrator, step_rejects_a_tstop_not_after_the_current_time)
{
    char err[ERRLEN] = "";
    const double y0[2] = {1, 0};
    problem p = problem_default();
    ctc_integ_spec spec = rk4_spec(0.1);
    ctc_integrator *it = make(&spec, 2, oscillator, &p);
    cr_assert_eq(ctc_integrator_step(it, 1.0, err, sizeof err), -1);
    cr_assert_str_eq(err, "no state to step from: reset was not called or failed");
    cr_assert_eq(ctc_integrator_reset(it, 0.5, y0), 0);
    cr_assert_eq(ctc_integrator_step(it, 0.5, err, sizeof err), -1);
    cr_assert_str_eq(err, "tstop must be finite and after the current time 0.5 s (got 0.5 s)");
    cr_assert_eq(ctc_integrator_step(it, NAN, err, sizeof err), -1);
    cr_assert_str_eq(err, "tstop must be finite and after the current time 0.5 s (got nan s)");
    cr_assert_eq(ctc_integrator_step(it, INFINITY, err, sizeof err), -1);
    cr_assert_str_eq(err, "tstop must be finite and after the current time 0.5 s (got inf s)");
    cr_assert_eq(ctc_integrator_stats(it)->rhs_evals, 1);
    ctc_integrator_free(it);
}

/* ---- spec check and construction ---- */

static void expect_check(const ctc_integ_spec *spec, const char *want)
{
    char err[ERRLEN] = "";
    cr_assert_eq(ctc_integ_check(spec, err, sizeof err), CTC_EINVAL, "accepted, want \"%s\"", want);
    cr_assert_str_eq(err, want);

    /* ctc_integrator_new refuses it with the same message and makes nothing */
    ctc_integrator *it = (ctc_integrator *)&err; /* not NULL */
    problem p = problem_default();
    char err2[ERRLEN] = "";
    cr_assert_eq(ctc_integrator_new(spec, 2, oscillator, &p, &it, err2, sizeof err2), CTC_EINVAL);
    cr_assert_str_eq(err2, want);
    cr_assert_null(it);
}

Test(integrator, check_rejects_each_bad_field_with_its_message)
{
    ctc_integ_spec s = rk4_spec(0);
    expect_check(&s, "step must be positive and finite (got 0 s)");
    s.step = -0.1;
    expect_check(&s, "step must be positive and finite (got -0.1 s)");
    s.step = NAN;
    expect_check(&s, "step must be positive and finite (got nan s)");
    s.step = INFINITY;
    expect_check(&s, "step must be positive and finite (got inf s)");

    for (int m = 1; m <= 2; m++) {
        ctc_integ_method method = m == 1 ? CTC_INTEG_DOPRI5 : CTC_INTEG_BDF;
        s = adaptive_spec(method, 2, 1e-6);
        expect_check(&s, "rtol must be in (0, 1) (got 2)");
        s.rtol = 0;
        expect_check(&s, "rtol must be in (0, 1) (got 0)");
        s.rtol = 1;
        expect_check(&s, "rtol must be in (0, 1) (got 1)");
        s.rtol = NAN;
        expect_check(&s, "rtol must be in (0, 1) (got nan)");
        s = adaptive_spec(method, 1e-6, -1);
        expect_check(&s, "atol must be positive and finite (got -1)");
        s.atol = 0;
        expect_check(&s, "atol must be positive and finite (got 0)");
        s.atol = INFINITY;
        expect_check(&s, "atol must be positive and finite (got inf)");
        s = adaptive_spec(method, 1e-6, 1e-6);
        s.initial_step = -1;
        expect_check(&s, "initial_step must be >= 0 and finite (got -1 s)");
        s.initial_step = NAN;
        expect_check(&s, "initial_step must be >= 0 and finite (got nan s)");
        s = adaptive_spec(method, 1e-6, 1e-6);
        s.max_step = -1;
        expect_check(&s, "max_step must be >= 0 (got -1 s)");
        s.max_step = NAN;
        expect_check(&s, "max_step must be >= 0 (got nan s)");
        s.max_step = 0;
        s.min_step = -1;
        expect_check(&s, "min_step must be >= 0 and finite (got -1 s)");
        s.min_step = INFINITY;
        expect_check(&s, "min_step must be >= 0 and finite (got inf s)");
        s.min_step = 0.2;
        s.max_step = 0.1;
        expect_check(&s, "min_step must not exceed max_step (got 0.2 s > 0.1 s)");
        s.min_step = 0;
        s.max_step = 0;
        s = adaptive_spec(method, 1e-6, 1e-6);
        s.max_steps = -5;
        expect_check(&s, "max_steps must be >= 0 (got -5)");
    }
    s = rk4_spec(0.1);
    s.max_steps = -1;
    expect_check(&s, "max_steps must be >= 0 (got -1)");
    s.method = (ctc_integ_method)7;
    expect_check(&s, "unknown integration method 7");

    char err[ERRLEN] = "";
    cr_assert_eq(ctc_integ_check(NULL, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "integrator spec is NULL");
}

Test(integrator, check_accepts_good_specs_and_ignores_other_methods_fields)
{
    char err[ERRLEN] = "";
    ctc_integ_spec s = rk4_spec(1e-3); /* rtol, atol = 0: not rk4's */
    cr_assert_eq(ctc_integ_check(&s, err, sizeof err), CTC_OK, "%s", err);
    s = adaptive_spec(CTC_INTEG_DOPRI5, 1e-6, 1e-9); /* step = 0: not dopri5's */
    s.max_step = INFINITY;
    s.max_steps = 100;
    cr_assert_eq(ctc_integ_check(&s, err, sizeof err), CTC_OK, "%s", err);
    s.method = CTC_INTEG_BDF;
    s.initial_step = 1e-4;
    cr_assert_eq(ctc_integ_check(&s, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_eq(ctc_integ_check(&s, NULL, 0), CTC_OK);
}

Test(integrator, new_rejects_bad_arguments)
{
    char err[ERRLEN] = "";
    problem p = problem_default();
    ctc_integ_spec s = rk4_spec(0.1);
    ctc_integrator *it = NULL;
    cr_assert_eq(ctc_integrator_new(&s, 0, oscillator, &p, &it, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "n must be >= 1 (got 0)");
    cr_assert_null(it);
    cr_assert_eq(ctc_integrator_new(&s, 2, NULL, &p, &it, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "rhs is NULL");
    cr_assert_null(it);
    cr_assert_eq(ctc_integrator_new(&s, 2, oscillator, &p, NULL, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "out is NULL");
    cr_assert_eq(ctc_integrator_new(NULL, 2, oscillator, &p, &it, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "integrator spec is NULL");
    ctc_integrator_free(NULL);
}

Test(integrator, method_names)
{
    cr_assert_str_eq(ctc_integ_method_name(CTC_INTEG_RK4), "rk4");
    cr_assert_str_eq(ctc_integ_method_name(CTC_INTEG_DOPRI5), "dopri5");
    cr_assert_str_eq(ctc_integ_method_name(CTC_INTEG_BDF), "bdf");
    cr_assert_str_eq(ctc_integ_method_name((ctc_integ_method)9), "unknown");
}
