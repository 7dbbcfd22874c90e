/*
 * test_traj.c - desired trajectories (src/control/traj.c) against independent oracles: closed forms
 * written out here (sinusoids, power sums, the minimum-jerk quintic), central finite differences
 * of the position and rate the module returns, a second spline construction (second-derivative
 * form solved by dense Gaussian elimination with pivoting), a linear search for the spline's
 * piece, the fourth-order convergence of a clamped spline, and the exact message of every
 * invalid argument.
 */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "traj.h"

#define PI 3.14159265358979323846
#define FD_STEP 1e-5    /* s, central differences */
#define FD_TOL 1e-6     /* relative to the largest |qd| (|qdd|) over the samples */
#define EXACT_TOL 1e-12 /* relative, closed forms evaluated two ways */

/* ---- helpers ---- */

/* splitmix64: a uniform number in [lo, hi) */
static double uniform(uint64_t *state, double lo, double hi)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return lo + (hi - lo) * (double)(z >> 11) * 0x1.0p-53;
}

static ctc_traj sinusoid(ctc_traj_type type, double amplitude, double period, double phase,
                         double offset)
{
    return (ctc_traj){
        .type = type, .amplitude = amplitude, .period = period, .phase = phase, .offset = offset};
}

static ctc_traj min_jerk(double q0, double q1, double t0, double t1)
{
    return (ctc_traj){.type = CTC_TRAJ_MIN_JERK, .q0 = q0, .q1 = q1, .t0 = t0, .t1 = t1};
}

/* qd and qdd against central differences of the q and qd that tr returns, at nt times */
static void expect_rates_match_differences(const ctc_traj *tr, int nt, const double *ts,
                                           const char *what)
{
    double scale_v = DBL_MIN, scale_a = DBL_MIN, x[3];
    for (int i = 0; i < nt; i++) {
        ctc_traj_eval(tr, ts[i], x);
        scale_v = fmax(scale_v, fabs(x[1]));
        scale_a = fmax(scale_a, fabs(x[2]));
    }
    for (int i = 0; i < nt; i++) {
        double plus[3], minus[3];
        ctc_traj_eval(tr, ts[i], x);
        ctc_traj_eval(tr, ts[i] + FD_STEP, plus);
        ctc_traj_eval(tr, ts[i] - FD_STEP, minus);
        double fd_v = (plus[0] - minus[0]) / (2 * FD_STEP);
        double fd_a = (plus[1] - minus[1]) / (2 * FD_STEP);
        cr_assert_leq(fabs(fd_v - x[1]), FD_TOL * scale_v,
                      "%s, t = %g: qd = %.15g, differences of q give %.15g", what, ts[i], x[1],
                      fd_v);
        cr_assert_leq(fabs(fd_a - x[2]), FD_TOL * scale_a,
                      "%s, t = %g: qdd = %.15g, differences of qd give %.15g", what, ts[i], x[2],
                      fd_a);
    }
}

static void expect_close(const double got[3], const double want[3], double tol, const char *what,
                         double t)
{
    static const char *names[3] = {"q", "qd", "qdd"};
    for (int j = 0; j < 3; j++) {
        cr_assert_leq(fabs(got[j] - want[j]), tol, "%s, t = %.17g: %s = %.17g, want %.17g", what, t,
                      names[j], got[j], want[j]);
    }
}

static ctc_traj make_spline(int n, const double *times, const double *values,
                            ctc_spline_boundary boundary)
{
    char err[160] = "";
    ctc_traj tr;
    cr_assert_eq(ctc_traj_spline(n, times, values, boundary, &tr, err, sizeof err), CTC_OK, "%s",
                 err);
    return tr;
}

/* n random knots: spacings in [0.05, 1.5) s from t = -1, values in [-2, 2) */
static void random_knots(uint64_t *rng, int n, double *times, double *values)
{
    double t = -1.0;
    for (int i = 0; i < n; i++) {
        times[i] = t;
        values[i] = uniform(rng, -2, 2);
        t += uniform(rng, 0.05, 1.5);
    }
}

/* ---- constant and sinusoids ---- */

Test(traj, constant_holds_its_value_at_rest)
{
    ctc_traj tr = {.type = CTC_TRAJ_CONSTANT, .value = -0.75};
    const double ts[4] = {-3.0, 0.0, 1.5, 1e6};
    cr_assert_eq(ctc_traj_check(&tr, NULL, 0), CTC_OK);
    for (int i = 0; i < 4; i++) {
        double x[3];
        ctc_traj_eval(&tr, ts[i], x);
        cr_assert(x[0] == -0.75 && x[1] == 0 && x[2] == 0, "t = %g: (%g, %g, %g)", ts[i], x[0],
                  x[1], x[2]);
    }
}

Test(traj, sinusoids_match_their_closed_forms)
{
    /* q = c + A sin(w t + p), qd = A w cos(.), qdd = -A w^2 sin(.), and the cosine likewise */
    const double amp = 0.6, period = 1.5, phase = 0.3, offset = -0.2, w = 2 * PI / period;
    ctc_traj s = sinusoid(CTC_TRAJ_SINE, amp, period, phase, offset);
    ctc_traj c = sinusoid(CTC_TRAJ_COSINE, amp, period, phase, offset);
    cr_assert_eq(ctc_traj_check(&s, NULL, 0), CTC_OK);
    cr_assert_eq(ctc_traj_check(&c, NULL, 0), CTC_OK);
    const double tol = EXACT_TOL * amp * w * w * 10; /* the angle's rounding grows with |t| */
    for (int i = 0; i <= 400; i++) {
        double t = -20.0 + i * 0.3;
        double a = w * t + phase, xs[3], xc[3];
        const double ws[3] = {offset + amp * sin(a), amp * w * cos(a), -amp * w * w * sin(a)};
        const double wc[3] = {offset + amp * cos(a), -amp * w * sin(a), -amp * w * w * cos(a)};
        ctc_traj_eval(&s, t, xs);
        ctc_traj_eval(&c, t, xc);
        expect_close(xs, ws, tol, "sine", t);
        expect_close(xc, wc, tol, "cosine", t);
    }
}

Test(traj, cosine_is_the_sine_a_quarter_turn_ahead)
{
    /* cos(x) = sin(x + pi/2): the cosine with phase p equals the sine with phase p + pi/2, and
       the sine a quarter period later equals the cosine now */
    const double period = 2.5, phase = -0.4;
    ctc_traj c = sinusoid(CTC_TRAJ_COSINE, 1.3, period, phase, 0.1);
    ctc_traj s_phase = sinusoid(CTC_TRAJ_SINE, 1.3, period, phase + PI / 2, 0.1);
    ctc_traj s = sinusoid(CTC_TRAJ_SINE, 1.3, period, phase, 0.1);
    for (int i = 0; i <= 100; i++) {
        double t = -3.0 + i * 0.077, xc[3], xp[3], xs[3];
        ctc_traj_eval(&c, t, xc);
        ctc_traj_eval(&s_phase, t, xp);
        ctc_traj_eval(&s, t + period / 4, xs);
        expect_close(xp, xc, 1e-12 * 1.3 * 7, "sine with phase + pi/2 vs cosine", t);
        expect_close(xs, xc, 1e-12 * 1.3 * 7, "sine a quarter period later vs cosine", t);
    }

    /* at t = 0, phase 0: the sine starts at its offset rising at A w, the cosine at its peak */
    ctc_traj s0 = sinusoid(CTC_TRAJ_SINE, 2.0, 4.0, 0.0, 0.5);
    ctc_traj c0 = sinusoid(CTC_TRAJ_COSINE, 2.0, 4.0, 0.0, 0.5);
    double x[3];
    ctc_traj_eval(&s0, 0.0, x);
    expect_close(x, (double[3]){0.5, 2.0 * PI / 2, 0}, 1e-15, "sine at 0", 0);
    ctc_traj_eval(&c0, 0.0, x);
    expect_close(x, (double[3]){2.5, 0, -2.0 * (PI / 2) * (PI / 2)}, 1e-15, "cosine at 0", 0);
}

Test(traj, sinusoids_repeat_every_period)
{
    ctc_traj s = sinusoid(CTC_TRAJ_SINE, 0.6, 1.5, 0.2, 0.0);
    for (int i = 0; i < 50; i++) {
        double t = 0.031 * i, x[3], y[3];
        ctc_traj_eval(&s, t, x);
        ctc_traj_eval(&s, t + 1000 * 1.5, y);
        expect_close(y, x, 1e-11, "a thousand periods later", t);
        ctc_traj_eval(&s, t - 7 * 1.5, y);
        expect_close(y, x, 1e-12, "seven periods earlier", t);
    }
}

Test(traj, sinusoid_rates_match_finite_differences)
{
    double ts[60];
    for (int i = 0; i < 60; i++) ts[i] = -4.0 + i * 0.173;
    ctc_traj s = sinusoid(CTC_TRAJ_SINE, 0.6, 1.5, 0.0, 0.0);
    ctc_traj c = sinusoid(CTC_TRAJ_COSINE, 2.0, 0.7, 1.1, -3.0);
    expect_rates_match_differences(&s, 60, ts, "sine");
    expect_rates_match_differences(&c, 60, ts, "cosine");
}

/* ---- polynomial ---- */

/* sum_i c_i t^i and its first two derivatives term by term with pow(); scale[j] = the sum of
   the |terms| of derivative j, the size of its rounding error */
static void power_sum(int n, const double *c, double t, double out[3], double scale[3])
{
    for (int j = 0; j < 3; j++) out[j] = scale[j] = 0;
    for (int i = 0; i < n; i++) {
        double term[3] = {c[i] * pow(t, i), 0, 0};
        if (i >= 1) term[1] = i * c[i] * pow(t, i - 1);
        if (i >= 2) term[2] = i * (i - 1) * c[i] * pow(t, i - 2);
        for (int j = 0; j < 3; j++) {
            out[j] += term[j];
            scale[j] += fabs(term[j]);
        }
    }
}

Test(traj, polynomial_matches_its_power_sum_and_derivatives)
{
    uint64_t rng = 11;
    const int sizes[4] = {1, 2, 5, CTC_TRAJ_MAX_COEF};
    for (int k = 0; k < 4; k++) {
        ctc_traj tr = {.type = CTC_TRAJ_POLYNOMIAL, .ncoef = sizes[k]};
        for (int i = 0; i < sizes[k]; i++) tr.coef[i] = uniform(&rng, -1, 1);
        cr_assert_eq(ctc_traj_check(&tr, NULL, 0), CTC_OK);
        for (int j = 0; j <= 40; j++) {
            double t = -1.3 + j * 0.065, x[3], want[3], scale[3];
            ctc_traj_eval(&tr, t, x);
            power_sum(sizes[k], tr.coef, t, want, scale);
            for (int d = 0; d < 3; d++) {
                cr_assert_leq(fabs(x[d] - want[d]), EXACT_TOL * fmax(1.0, scale[d]),
                              "%d coefficients, t = %g: derivative %d = %.17g, want %.17g",
                              sizes[k], t, d, x[d], want[d]);
            }
        }
    }
}

Test(traj, polynomial_rates_match_finite_differences)
{
    /* q = 1 - 2 t + 0.5 t^2 + t^3 - 0.3 t^5 + 0.01 t^9 */
    ctc_traj tr = {
        .type = CTC_TRAJ_POLYNOMIAL, .ncoef = 10, .coef = {1, -2, 0.5, 1, 0, -0.3, 0, 0, 0, 0.01}};
    double ts[41];
    for (int i = 0; i <= 40; i++) ts[i] = -2.0 + i * 0.1;
    expect_rates_match_differences(&tr, 41, ts, "polynomial of degree 9");
}

/* ---- minimum jerk ---- */

Test(traj, min_jerk_starts_and_ends_at_rest_and_is_symmetric)
{
    const double q0 = 0.4, q1 = -1.1, t0 = 0.5, t1 = 2.5, dist = q1 - q0, dur = t1 - t0;
    ctc_traj tr = min_jerk(q0, q1, t0, t1);
    cr_assert_eq(ctc_traj_check(&tr, NULL, 0), CTC_OK);
    double x[3];

    /* at and beyond both ends: the end value at rest, exactly */
    const double before[3] = {-1e9, 0.0, t0}, after[3] = {t1, 3.0, 1e9};
    for (int i = 0; i < 3; i++) {
        ctc_traj_eval(&tr, before[i], x);
        cr_assert(x[0] == q0 && x[1] == 0 && x[2] == 0, "t = %g: (%g, %g, %g)", before[i], x[0],
                  x[1], x[2]);
        ctc_traj_eval(&tr, after[i], x);
        cr_assert(x[0] == q1 && x[1] == 0 && x[2] == 0, "t = %g: (%g, %g, %g)", after[i], x[0],
                  x[1], x[2]);
    }

    /* midway: half the distance, the peak rate 15/8 dist/dur, no acceleration */
    ctc_traj_eval(&tr, (t0 + t1) / 2, x);
    expect_close(x, (double[3]){(q0 + q1) / 2, 1.875 * dist / dur, 0}, 1e-15, "midpoint",
                 (t0 + t1) / 2);

    /* point symmetry about the midpoint: q(t0 + u) + q(t1 - u) = q0 + q1, equal rates,
       opposite accelerations */
    for (int i = 1; i < 20; i++) {
        double u = dur * i / 40.0, a[3], b[3];
        ctc_traj_eval(&tr, t0 + u, a);
        ctc_traj_eval(&tr, t1 - u, b);
        cr_assert_leq(fabs(a[0] + b[0] - (q0 + q1)), 1e-15 * 4, "q symmetry at u = %g", u);
        cr_assert_leq(fabs(a[1] - b[1]), 1e-14, "qd symmetry at u = %g", u);
        cr_assert_leq(fabs(a[2] + b[2]), 1e-13, "qdd symmetry at u = %g", u);
    }
}

Test(traj, min_jerk_matches_the_quintic_and_its_derivatives)
{
    /* closed form in s = (t - t0)/T: p = 10 s^3 - 15 s^4 + 6 s^5, expanded in powers of s */
    const double q0 = -0.3, q1 = 2.2, t0 = -1.0, t1 = 0.6, dist = q1 - q0, dur = t1 - t0;
    ctc_traj tr = min_jerk(q0, q1, t0, t1);
    for (int i = 0; i <= 64; i++) {
        double t = t0 + dur * i / 64.0, s = (t - t0) / dur, x[3];
        double p = 10 * pow(s, 3) - 15 * pow(s, 4) + 6 * pow(s, 5);
        double dp = 30 * pow(s, 2) - 60 * pow(s, 3) + 30 * pow(s, 4);
        double ddp = 60 * s - 180 * pow(s, 2) + 120 * pow(s, 3);
        const double want[3] = {q0 + dist * p, dist * dp / dur, dist * ddp / (dur * dur)};
        ctc_traj_eval(&tr, t, x);
        expect_close(x, want, 1e-13 * fabs(dist) / (dur * dur) * 10, "min_jerk", t);
    }
}

Test(traj, min_jerk_is_twice_continuously_differentiable_at_both_ends)
{
    /* just inside an end, at a distance u: |q - q_end| = 10 D (u/T)^3 + O(u^4),
       |qd| = 30 D/T (u/T)^2 + O(u^3), |qdd| = 60 D/T^2 (u/T) + O(u^2), so each jump shrinks to
       zero with u; just outside the values are exactly the end's */
    const double q0 = 1.0, q1 = 4.0, t0 = 2.0, t1 = 3.5, dist = q1 - q0, dur = t1 - t0;
    ctc_traj tr = min_jerk(q0, q1, t0, t1);
    for (int k = 3; k <= 8; k++) {
        double r = pow(10.0, -k), u = r * dur, in0[3], out0[3], in1[3], out1[3];
        ctc_traj_eval(&tr, t0 + u, in0);
        ctc_traj_eval(&tr, t0 - u, out0);
        ctc_traj_eval(&tr, t1 - u, in1);
        ctc_traj_eval(&tr, t1 + u, out1);
        const double bound[3] = {10.5 * dist * r * r * r + 8 * DBL_EPSILON * q1,
                                 30.5 * dist / dur * r * r, 60.5 * dist / (dur * dur) * r};
        for (int j = 0; j < 3; j++) {
            cr_assert_leq(fabs(in0[j] - out0[j]), bound[j], "jump of %s at t0 across %g s: %g",
                          j == 0   ? "q"
                          : j == 1 ? "qd"
                                   : "qdd",
                          u, in0[j] - out0[j]);
            cr_assert_leq(fabs(in1[j] - out1[j]), bound[j], "jump of %s at t1 across %g s: %g",
                          j == 0   ? "q"
                          : j == 1 ? "qd"
                                   : "qdd",
                          u, in1[j] - out1[j]);
        }
    }
}

Test(traj, min_jerk_rates_match_finite_differences)
{
    /* inside the blend and outside it, not within two steps of its ends (where q''' jumps) */
    ctc_traj tr = min_jerk(0.2, -0.9, 1.0, 1.8);
    double ts[36];
    for (int i = 0; i < 30; i++) ts[i] = 1.0 + 0.8 * (i + 0.5) / 30;
    const double outside[6] = {-1.0, 0.5, 0.999, 1.801, 2.0, 10.0};
    for (int i = 0; i < 6; i++) ts[30 + i] = outside[i];
    expect_rates_match_differences(&tr, 36, ts, "min_jerk");
}

/* ---- splines: an independent construction ---- */

/* solves the dense n x n system a x = b (row-major, both overwritten) by Gaussian elimination
   with partial pivoting */
static void dense_solve(int n, double *a, double *b)
{
    for (int col = 0; col < n; col++) {
        int piv = col;
        for (int r = col + 1; r < n; r++) {
            if (fabs(a[r * n + col]) > fabs(a[piv * n + col])) piv = r;
        }
        for (int c = 0; c < n; c++) {
            double tmp = a[col * n + c];
            a[col * n + c] = a[piv * n + c];
            a[piv * n + c] = tmp;
        }
        double tb = b[col];
        b[col] = b[piv];
        b[piv] = tb;
        for (int r = col + 1; r < n; r++) {
            double f = a[r * n + col] / a[col * n + col];
            for (int c = col; c < n; c++) a[r * n + c] -= f * a[col * n + c];
            b[r] -= f * b[col];
        }
    }
    for (int r = n - 1; r >= 0; r--) {
        double s = b[r];
        for (int c = r + 1; c < n; c++) s -= a[r * n + c] * b[c];
        b[r] = s / a[r * n + r];
    }
}

#define ORACLE_MAX 16

/* the spline in second-derivative form: knot accelerations acc[i] from
   h_{i-1} M_{i-1} + 2 (h_{i-1} + h_i) M_i + h_i M_{i+1} = 6 (d_i - d_{i-1}) with M = 0 at natural
   ends or the end rate = 0 at clamped ends */
static void oracle_accelerations(int n, const double *t, const double *y,
                                 ctc_spline_boundary boundary, double *acc)
{
    double a[ORACLE_MAX * ORACLE_MAX] = {0};
    for (int i = 1; i < n - 1; i++) {
        double hl = t[i] - t[i - 1], hr = t[i + 1] - t[i];
        a[i * n + i - 1] = hl;
        a[i * n + i] = 2 * (hl + hr);
        a[i * n + i + 1] = hr;
        acc[i] = 6 * ((y[i + 1] - y[i]) / hr - (y[i] - y[i - 1]) / hl);
    }
    double h0 = t[1] - t[0], hn = t[n - 1] - t[n - 2];
    if (boundary == CTC_SPLINE_NATURAL) {
        a[0] = 1;
        acc[0] = 0;
        a[(n - 1) * n + n - 1] = 1;
        acc[n - 1] = 0;
    } else {
        a[0] = 2 * h0;
        a[1] = h0;
        acc[0] = 6 * (y[1] - y[0]) / h0;
        a[(n - 1) * n + n - 2] = hn;
        a[(n - 1) * n + n - 1] = 2 * hn;
        acc[n - 1] = -6 * (y[n - 1] - y[n - 2]) / hn;
    }
    dense_solve(n, a, acc);
}

/* evaluates the second-derivative form at t in [t_0, t_{n-1}] */
static void oracle_eval(int n, const double *t, const double *y, const double *acc, double x,
                        double out[3])
{
    int i = 0;
    while (i < n - 2 && x >= t[i + 1]) i++;
    double h = t[i + 1] - t[i], a = t[i + 1] - x, b = x - t[i];
    double cl = y[i] / h - acc[i] * h / 6, cr = y[i + 1] / h - acc[i + 1] * h / 6;
    out[0] = acc[i] * a * a * a / (6 * h) + acc[i + 1] * b * b * b / (6 * h) + cl * a + cr * b;
    out[1] = -acc[i] * a * a / (2 * h) + acc[i + 1] * b * b / (2 * h) - cl + cr;
    out[2] = (acc[i] * a + acc[i + 1] * b) / h;
}

Test(traj, spline_matches_the_second_derivative_form_solved_densely)
{
    uint64_t rng = 2024;
    const ctc_spline_boundary kinds[2] = {CTC_SPLINE_CLAMPED, CTC_SPLINE_NATURAL};
    for (int trial = 0; trial < 20; trial++) {
        int n = 2 + trial % (ORACLE_MAX - 1);
        double t[ORACLE_MAX], y[ORACLE_MAX], acc[ORACLE_MAX];
        random_knots(&rng, n, t, y);
        for (int k = 0; k < 2; k++) {
            ctc_traj tr = make_spline(n, t, y, kinds[k]);
            oracle_accelerations(n, t, y, kinds[k], acc);
            double scale = 1;
            for (int i = 0; i < n; i++) scale = fmax(scale, fabs(acc[i]));
            for (int j = 0; j <= 200; j++) {
                double x = t[0] + (t[n - 1] - t[0]) * uniform(&rng, 0, 1), got[3], want[3];
                if (j == 200) x = t[n - 1];
                ctc_traj_eval(&tr, x, got);
                oracle_eval(n, t, y, acc, x, want);
                expect_close(got, want, 1e-11 * scale,
                             kinds[k] == CTC_SPLINE_CLAMPED ? "clamped" : "natural", x);
            }
            ctc_traj_free(&tr);
        }
    }
}

/* ---- splines: defining properties ---- */

Test(traj, spline_interpolates_every_knot_exactly)
{
    /* exactly, not to rounding: at a knot the piece starting there is evaluated at s = 0 */
    uint64_t rng = 5;
    double t[40], y[40];
    random_knots(&rng, 40, t, y);
    for (int k = 0; k < 2; k++) {
        ctc_traj tr = make_spline(40, t, y, k == 0 ? CTC_SPLINE_CLAMPED : CTC_SPLINE_NATURAL);
        for (int i = 0; i < 40; i++) {
            double x[3];
            ctc_traj_eval(&tr, t[i], x);
            cr_assert_eq(x[0], y[i], "knot %d: q = %.17g, value %.17g", i, x[0], y[i]);
        }
        ctc_traj_free(&tr);
    }
}

Test(traj, spline_is_twice_continuously_differentiable_at_interior_knots)
{
    /* the left limit (one ulp before the knot) against the value at the knot */
    uint64_t rng = 77;
    double t[30], y[30];
    random_knots(&rng, 30, t, y);
    for (int k = 0; k < 2; k++) {
        ctc_traj tr = make_spline(30, t, y, k == 0 ? CTC_SPLINE_CLAMPED : CTC_SPLINE_NATURAL);
        double scale[3] = {1, 1, 1}, left[30][3], right[30][3];
        for (int i = 1; i < 29; i++) {
            ctc_traj_eval(&tr, nextafter(t[i], -INFINITY), left[i]);
            ctc_traj_eval(&tr, t[i], right[i]);
            for (int j = 0; j < 3; j++) scale[j] = fmax(scale[j], fabs(right[i][j]));
        }
        for (int i = 1; i < 29; i++) {
            for (int j = 0; j < 3; j++) {
                cr_assert_leq(fabs(left[i][j] - right[i][j]), 1e-9 * scale[j],
                              "%s knot %d, derivative %d: left %.17g, right %.17g",
                              k == 0 ? "clamped" : "natural", i, j, left[i][j], right[i][j]);
            }
        }
        ctc_traj_free(&tr);
    }
}

Test(traj, clamped_spline_starts_and_ends_at_rest_and_holds_outside)
{
    uint64_t rng = 9;
    double t[12], y[12], x[3];
    random_knots(&rng, 12, t, y);
    ctc_traj tr = make_spline(12, t, y, CTC_SPLINE_CLAMPED);
    ctc_traj_eval(&tr, t[0], x);
    cr_assert(x[0] == y[0] && x[1] == 0, "start: q = %.17g, qd = %g", x[0], x[1]);
    ctc_traj_eval(&tr, t[11], x);
    cr_assert(x[0] == y[11] && x[1] == 0, "end: q = %.17g, qd = %g", x[0], x[1]);

    /* outside: the end value, no rate, no acceleration */
    const double before[3] = {-INFINITY, t[0] - 100, nextafter(t[0], -INFINITY)};
    const double after[3] = {nextafter(t[11], INFINITY), t[11] + 3, INFINITY};
    for (int i = 0; i < 3; i++) {
        ctc_traj_eval(&tr, before[i], x);
        cr_assert(x[0] == y[0] && x[1] == 0 && x[2] == 0, "t = %g: (%g, %g, %g)", before[i], x[0],
                  x[1], x[2]);
        ctc_traj_eval(&tr, after[i], x);
        cr_assert(x[0] == y[11] && x[1] == 0 && x[2] == 0, "t = %g: (%g, %g, %g)", after[i], x[0],
                  x[1], x[2]);
    }
    ctc_traj_free(&tr);
}

Test(traj, natural_spline_has_no_end_acceleration_and_continues_along_the_end_tangent)
{
    uint64_t rng = 31;
    double t[15], y[15], x0[3], x1[3], x[3];
    random_knots(&rng, 15, t, y);
    ctc_traj tr = make_spline(15, t, y, CTC_SPLINE_NATURAL);

    /* the largest |qdd| over the knots sets the scale of "zero" */
    double scale = 1;
    for (int i = 0; i < 15; i++) {
        ctc_traj_eval(&tr, t[i], x);
        scale = fmax(scale, fabs(x[2]));
    }
    ctc_traj_eval(&tr, t[0], x0);
    ctc_traj_eval(&tr, t[14], x1);
    cr_assert_leq(fabs(x0[2]), 1e-12 * scale, "qdd at the start: %g", x0[2]);
    cr_assert_leq(fabs(x1[2]), 1e-12 * scale, "qdd at the end: %g", x1[2]);
    ctc_traj_eval(&tr, nextafter(t[14], -INFINITY), x);
    cr_assert_leq(fabs(x[2]), 1e-9 * scale, "qdd just before the end: %g", x[2]);

    /* outside: the tangent line at the end, rate continuous */
    for (int i = 1; i <= 5; i++) {
        double d = 0.7 * i;
        ctc_traj_eval(&tr, t[0] - d, x);
        expect_close(x, (double[3]){y[0] - x0[1] * d, x0[1], 0}, 1e-13 * (1 + d * fabs(x0[1])),
                     "before the start", t[0] - d);
        ctc_traj_eval(&tr, t[14] + d, x);
        expect_close(x, (double[3]){y[14] + x1[1] * d, x1[1], 0}, 1e-13 * (1 + d * fabs(x1[1])),
                     "after the end", t[14] + d);
    }
    ctc_traj_free(&tr);
}

Test(traj, natural_spline_reproduces_a_straight_line)
{
    /* a line has no acceleration anywhere, so it is its own natural spline */
    uint64_t rng = 3;
    double t[25], y[25];
    random_knots(&rng, 25, t, y);
    for (int i = 0; i < 25; i++) y[i] = 2.0 - 3.0 * t[i];
    ctc_traj tr = make_spline(25, t, y, CTC_SPLINE_NATURAL);
    for (int j = 0; j <= 300; j++) {
        double x = t[0] - 2 + (t[24] - t[0] + 4) * j / 300.0, got[3];
        ctc_traj_eval(&tr, x, got);
        expect_close(got, (double[3]){2.0 - 3.0 * x, -3.0, 0}, 1e-12 * (1 + fabs(x)), "line", x);
    }
    ctc_traj_free(&tr);
}

Test(traj, two_knot_splines_are_the_smoothstep_cubic_and_the_chord)
{
    /* clamped: y0 + D (3 s^2 - 2 s^3), s = (t - t0)/h; natural: the straight chord */
    const double t[2] = {0.5, 2.5}, y[2] = {1.0, -3.0}, h = 2.0, dist = -4.0;
    ctc_traj clamped = make_spline(2, t, y, CTC_SPLINE_CLAMPED);
    ctc_traj natural = make_spline(2, t, y, CTC_SPLINE_NATURAL);
    for (int j = 0; j <= 50; j++) {
        double x = t[0] + h * j / 50.0, s = (x - t[0]) / h, got[3];
        const double want_c[3] = {y[0] + dist * (3 * s * s - 2 * s * s * s),
                                  dist * (6 * s - 6 * s * s) / h, dist * (6 - 12 * s) / (h * h)};
        ctc_traj_eval(&clamped, x, got);
        expect_close(got, want_c, 1e-14, "clamped, 2 knots", x);
        ctc_traj_eval(&natural, x, got);
        expect_close(got, (double[3]){y[0] + dist * s, dist / h, 0}, 1e-14, "natural, 2 knots", x);
    }
    ctc_traj_free(&clamped);
    ctc_traj_free(&natural);
}

Test(traj, spline_rates_match_finite_differences)
{
    /* samples inside the pieces, away from the knots where q''' jumps */
    uint64_t rng = 8;
    double t[10], y[10], ts[36];
    random_knots(&rng, 10, t, y);
    const double fractions[4] = {0.1, 0.37, 0.5, 0.81};
    for (int i = 0; i < 9; i++) {
        for (int j = 0; j < 4; j++) ts[4 * i + j] = t[i] + fractions[j] * (t[i + 1] - t[i]);
    }
    for (int k = 0; k < 2; k++) {
        ctc_traj tr = make_spline(10, t, y, k == 0 ? CTC_SPLINE_CLAMPED : CTC_SPLINE_NATURAL);
        expect_rates_match_differences(&tr, 36, ts, k == 0 ? "clamped" : "natural");
        ctc_traj_free(&tr);
    }
}

Test(traj, clamped_spline_converges_at_fourth_order)
{
    /* cos(pi t) on [0, 1] has zero end slopes, so the clamped spline is the complete spline,
       whose error is O(h^4): halving h divides the largest error by about 16 */
    double prev = 0;
    for (int level = 0; level < 4; level++) {
        int intervals = 8 << level, n = intervals + 1;
        double t[65], y[65];
        for (int i = 0; i < n; i++) {
            t[i] = (double)i / intervals;
            y[i] = cos(PI * t[i]);
        }
        ctc_traj tr = make_spline(n, t, y, CTC_SPLINE_CLAMPED);
        double worst = 0;
        for (int j = 0; j <= 64 * 40; j++) {
            double x = j / (64.0 * 40), got[3];
            ctc_traj_eval(&tr, x, got);
            worst = fmax(worst, fabs(got[0] - cos(PI * x)));
        }
        ctc_traj_free(&tr);
        cr_assert_leq(worst, 5.0 / 384 * pow(PI, 4) * pow(1.0 / intervals, 4),
                      "h = 1/%d: error %g above the bound 5/384 h^4 max|f''''|", intervals, worst);
        if (level > 0) {
            double ratio = prev / worst;
            cr_assert(ratio > 12 && ratio < 20, "h = 1/%d: error %g, ratio %g to h = 1/%d",
                      intervals, worst, ratio, intervals / 2);
        }
        prev = worst;
    }
}

Test(traj, spline_binary_search_finds_the_piece_a_linear_search_finds)
{
    /* strongly non-uniform knots: spacings from 1e-3 to 10 s */
    enum { N = 200 };
    uint64_t rng = 41;
    double t[N], y[N];
    t[0] = -50;
    for (int i = 0; i < N; i++) {
        if (i > 0) t[i] = t[i - 1] + pow(10.0, uniform(&rng, -3, 1));
        y[i] = uniform(&rng, -1, 1);
    }
    ctc_traj tr = make_spline(N, t, y, CTC_SPLINE_NATURAL);
    for (int j = 0; j < 5000; j++) {
        /* random times, and every knot itself */
        double x = j < N ? t[j] : uniform(&rng, t[0], t[N - 1]);
        int piece = 0;
        while (piece < N - 1 && tr.knots[5 * (piece + 1)] <= x) piece++;
        const double *row = tr.knots + 5 * piece;
        double s = x - row[0], got[3];
        const double want[3] = {row[1] + row[2] * s + row[3] * s * s + row[4] * s * s * s,
                                row[2] + 2 * row[3] * s + 3 * row[4] * s * s,
                                2 * row[3] + 6 * row[4] * s};
        ctc_traj_eval(&tr, x, got);
        /* the two orders of summation differ by rounding: a few ulps of the largest term */
        double b = fabs(row[2]), c = fabs(row[3]), d = fabs(row[4]), as = fabs(s);
        double scale = fabs(row[1]) + b * as + c * as * as + d * as * as * as + b + 2 * c * as +
                       3 * d * as * as + 2 * c + 6 * d * as;
        expect_close(got, want, 1e-14 * scale, "piece from a linear search", x);
    }
    ctc_traj_free(&tr);
}

Test(traj, spline_with_the_most_knots_builds_and_evaluates)
{
    /* cos t on [0, 32 pi]: zero slope at both ends, h ~ 1e-3, error 5/384 h^4 ~ 1e-14 */
    const int n = CTC_TRAJ_MAX_KNOTS;
    double *t = malloc(sizeof(double) * n), *y = malloc(sizeof(double) * n);
    cr_assert(t != NULL && y != NULL);
    for (int i = 0; i < n; i++) {
        t[i] = 32 * PI * i / (n - 1);
        y[i] = cos(t[i]);
    }
    ctc_traj tr = make_spline(n, t, y, CTC_SPLINE_CLAMPED);
    cr_assert_eq(tr.nknots, n);
    cr_assert_eq(ctc_traj_check(&tr, NULL, 0), CTC_OK);
    for (int i = 0; i < n - 1; i += 7) {
        double x = t[i] + 0.3 * (t[i + 1] - t[i]), got[3];
        ctc_traj_eval(&tr, x, got);
        expect_close(got, (double[3]){cos(x), -sin(x), -cos(x)}, 1e-6, "cos t", x);
        cr_assert_leq(fabs(got[0] - cos(x)), 1e-12, "t = %.17g: q = %.17g, cos = %.17g", x, got[0],
                      cos(x));
        ctc_traj_eval(&tr, t[i], got);
        cr_assert_eq(got[0], y[i], "knot %d", i);
    }
    ctc_traj_free(&tr);
    free(t);
    free(y);
}

/* ---- ownership ---- */

Test(traj, free_leaves_a_constant_zero_and_accepts_null)
{
    const double t[3] = {0, 1, 2}, y[3] = {1, 2, 0};
    ctc_traj tr = make_spline(3, t, y, CTC_SPLINE_NATURAL);
    cr_assert_not_null(tr.knots);
    ctc_traj_free(&tr);
    cr_assert_eq(tr.type, CTC_TRAJ_CONSTANT);
    cr_assert_null(tr.knots);
    cr_assert_eq(tr.nknots, 0);
    double x[3];
    ctc_traj_eval(&tr, 1.5, x);
    cr_assert(x[0] == 0 && x[1] == 0 && x[2] == 0);
    ctc_traj_free(&tr); /* a second time: nothing left to free */
    ctc_traj_free(NULL);

    /* any other type owns nothing: free only resets it */
    ctc_traj s = sinusoid(CTC_TRAJ_SINE, 1, 1, 0, 0);
    ctc_traj_free(&s);
    cr_assert_eq(s.type, CTC_TRAJ_CONSTANT);
    cr_assert_eq(s.amplitude, 0);
}

/* ---- invalid arguments ---- */

static void expect_error(ctc_status st, const char *err, const char *want)
{
    cr_assert_eq(st, CTC_EINVAL, "status %s for \"%s\"", ctc_status_name(st), want);
    cr_assert_str_eq(err, want);
}

static void expect_check_error(ctc_traj tr, const char *want)
{
    char err[160];
    expect_error(ctc_traj_check(&tr, err, sizeof err), err, want);
}

Test(traj, check_rejects_invalid_parameters_with_exact_messages)
{
    char err[160];
    expect_error(ctc_traj_check(NULL, err, sizeof err), err, "trajectory is NULL");
    expect_check_error((ctc_traj){.type = (ctc_traj_type)42}, "unknown trajectory type 42");
    expect_check_error((ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = NAN},
                       "constant: value must be finite (got nan)");

    /* sinusoids */
    expect_check_error(sinusoid(CTC_TRAJ_SINE, 1, 0, 0, 0),
                       "sine: period must be positive and finite (got 0 s)");
    expect_check_error(sinusoid(CTC_TRAJ_COSINE, 1, -1.5, 0, 0),
                       "cosine: period must be positive and finite (got -1.5 s)");
    expect_check_error(sinusoid(CTC_TRAJ_SINE, 1, INFINITY, 0, 0),
                       "sine: period must be positive and finite (got inf s)");
    expect_check_error(sinusoid(CTC_TRAJ_SINE, 1, NAN, 0, 0),
                       "sine: period must be positive and finite (got nan s)");
    expect_check_error(sinusoid(CTC_TRAJ_SINE, NAN, 1, 0, 0),
                       "sine: amplitude must be finite (got nan)");
    expect_check_error(sinusoid(CTC_TRAJ_COSINE, 1, 1, -INFINITY, 0),
                       "cosine: phase must be finite (got -inf rad)");
    expect_check_error(sinusoid(CTC_TRAJ_SINE, 1, 1, 0, INFINITY),
                       "sine: offset must be finite (got inf)");
    expect_check_error(sinusoid(CTC_TRAJ_SINE, 1e308, 1, 0, 1e308),
                       "sine: offset + amplitude overflows");
    expect_check_error(sinusoid(CTC_TRAJ_SINE, 1, 1e-160, 0, 0),
                       "sine: period 1e-160 s is too short (the acceleration overflows)");
    expect_check_error(sinusoid(CTC_TRAJ_COSINE, 0, 1e-310, 0, 0),
                       "cosine: period 1e-310 s is too short (the acceleration overflows)");

    /* polynomials */
    expect_check_error((ctc_traj){.type = CTC_TRAJ_POLYNOMIAL, .ncoef = 0},
                       "polynomial: needs 1 to 16 coefficients (got 0)");
    expect_check_error((ctc_traj){.type = CTC_TRAJ_POLYNOMIAL, .ncoef = 17},
                       "polynomial: needs 1 to 16 coefficients (got 17)");
    expect_check_error((ctc_traj){.type = CTC_TRAJ_POLYNOMIAL, .ncoef = 4, .coef = {1, 2, 3, NAN}},
                       "polynomial: coefficients[3] must be finite (got nan)");

    /* minimum jerk */
    expect_check_error(min_jerk(NAN, 1, 0, 1), "min_jerk: from must be finite (got nan)");
    expect_check_error(min_jerk(0, -INFINITY, 0, 1), "min_jerk: to must be finite (got -inf)");
    expect_check_error(min_jerk(0, 1, NAN, 1), "min_jerk: start must be finite (got nan s)");
    expect_check_error(min_jerk(0, 1, 0, INFINITY), "min_jerk: end must be finite (got inf s)");
    expect_check_error(min_jerk(0, 1, 2, 1), "min_jerk: end (1 s) must be after start (2 s)");
    expect_check_error(min_jerk(0, 1, 2, 2), "min_jerk: end (2 s) must be after start (2 s)");
    expect_check_error(min_jerk(0, 1, -1e308, 1e308), "min_jerk: end - start overflows");
    expect_check_error(min_jerk(-1e308, 1e308, 0, 1), "min_jerk: to - from overflows");
    expect_check_error(min_jerk(0, 1e300, 0, 1e-10),
                       "min_jerk: the acceleration overflows (to - from too large for end - start "
                       "= 1e-10 s)");

    /* a spline not made by ctc_traj_spline */
    expect_check_error((ctc_traj){.type = CTC_TRAJ_SPLINE, .nknots = 4},
                       "spline: has no knots (make it with ctc_traj_spline)");
    double knots[10] = {0, 1, 0, 0, 0, 1, 2, 0, 0, 0};
    expect_check_error(
        (ctc_traj){.type = CTC_TRAJ_SPLINE, .nknots = 2, .knots = knots, .boundary = 3},
        "spline: unknown boundary 3 (want clamped or natural)");
    cr_assert_eq(ctc_traj_check(&(ctc_traj){.type = CTC_TRAJ_SPLINE, .nknots = 2, .knots = knots},
                                err, sizeof err),
                 CTC_OK);
}

Test(traj, spline_rejects_invalid_knots_with_exact_messages_and_leaves_out_alone)
{
    char err[200];
    const double t[5] = {0, 1, 2, 3, 4}, y[5] = {0, 1, 0, 1, 0};
    ctc_traj out = {.type = CTC_TRAJ_CONSTANT, .value = 7.5};
    const ctc_spline_boundary clamped = CTC_SPLINE_CLAMPED;

    expect_error(ctc_traj_spline(1, t, y, clamped, &out, err, sizeof err), err,
                 "spline: needs 2 to 100000 knots (got 1)");
    expect_error(ctc_traj_spline(-3, t, y, clamped, &out, err, sizeof err), err,
                 "spline: needs 2 to 100000 knots (got -3)");
    expect_error(
        ctc_traj_spline(CTC_TRAJ_MAX_KNOTS + 1, NULL, NULL, clamped, &out, err, sizeof err), err,
        "spline: needs 2 to 100000 knots (got 100001)");
    expect_error(ctc_traj_spline(5, NULL, y, clamped, &out, err, sizeof err), err,
                 "spline: times is NULL");
    expect_error(ctc_traj_spline(5, t, NULL, clamped, &out, err, sizeof err), err,
                 "spline: values is NULL");
    expect_error(ctc_traj_spline(5, t, y, clamped, NULL, err, sizeof err), err,
                 "spline: out is NULL");
    expect_error(ctc_traj_spline(5, t, y, (ctc_spline_boundary)9, &out, err, sizeof err), err,
                 "spline: unknown boundary 9 (want clamped or natural)");

    const double t_nan[5] = {0, 1, NAN, 3, 4}, y_inf[5] = {0, 1, -INFINITY, 1, 0};
    const double t_tie[5] = {0, 1, 2, 2, 4}, t_back[5] = {0, 1, 2, 3, 2.5};
    const double t_wide[2] = {-1e308, 1e308}, t_close[3] = {0, 1e-10, 1};
    const double y_far[3] = {1e300, -1e300, 0};
    expect_error(ctc_traj_spline(5, t_nan, y, clamped, &out, err, sizeof err), err,
                 "spline: times[2] must be finite (got nan s)");
    expect_error(ctc_traj_spline(5, t, y_inf, clamped, &out, err, sizeof err), err,
                 "spline: values[2] must be finite (got -inf)");
    expect_error(ctc_traj_spline(5, t_tie, y, clamped, &out, err, sizeof err), err,
                 "spline: times[3] = 2 is not after times[2] = 2");
    expect_error(ctc_traj_spline(5, t_back, y, CTC_SPLINE_NATURAL, &out, err, sizeof err), err,
                 "spline: times[4] = 2.5 is not after times[3] = 3");
    expect_error(ctc_traj_spline(2, t_wide, y, clamped, &out, err, sizeof err), err,
                 "spline: times[1] - times[0] overflows");
    const double t_wide2[3] = {-1.7e308, -1e308, 1e308};
    expect_error(ctc_traj_spline(3, t_wide2, y, clamped, &out, err, sizeof err), err,
                 "spline: times[2] - times[1] overflows");
    expect_error(ctc_traj_spline(3, t_close, y_far, CTC_SPLINE_NATURAL, &out, err, sizeof err), err,
                 "spline: coefficients overflow at times[0] = 0 (values too far apart for the knot "
                 "spacing)");

    /* nothing was written to out */
    cr_assert_eq(out.type, CTC_TRAJ_CONSTANT);
    cr_assert_eq(out.value, 7.5);
    cr_assert_null(out.knots);
}

Test(traj, error_buffer_may_be_null_or_short)
{
    ctc_traj tr = sinusoid(CTC_TRAJ_SINE, 1, 0, 0, 0);
    char err[8];
    memset(err, 'x', sizeof err);
    cr_assert_eq(ctc_traj_check(&tr, NULL, 0), CTC_EINVAL);
    cr_assert_eq(ctc_traj_check(&tr, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "sine: p");
    const double t[2] = {1, 0}, y[2] = {0, 0};
    ctc_traj out;
    cr_assert_eq(ctc_traj_spline(2, t, y, CTC_SPLINE_CLAMPED, &out, NULL, 0), CTC_EINVAL);
}
