/*
 * integ_dopri5.c - the adaptive Dormand-Prince 5(4) method with FSAL, PI step-size control, an
 * automatic first step and the method's 4th-order continuous extension (integrator.h).
 *
 * References: J. R. Dormand and P. J. Prince, "A family of embedded Runge-Kutta formulae",
 * J. Comput. Appl. Math. 6 (1980) (the tableau); E. Hairer, S. P. Norsett and G. Wanner, Solving
 * Ordinary Differential Equations I, 2nd ed., sections II.4 (error norm, starting step size),
 * II.6 (dense output), and K. Gustafsson, M. Lundh and G. Soderlind, "A PI stepsize control
 * for the numerical solution of ordinary differential equations", BIT 28 (1988).
 *
 * A step from (t, y) with step h: seven stages k1..k7 at t + c_i h, where k1 = f(t, y) is the
 * previous step's k7 (first same as last) and k7 = f(t + h, y_new). The 5th-order solution is
 * kept (local extrapolation): y_new = y + h sum b_i k_i, and the error estimate is the difference
 * to the embedded 4th-order solution, err_i = h sum e_i k_i with e = b - b_hat. The step is
 * accepted when
 *     E = || err_i / (atol + rtol max(|y_i|, |y_new_i|)) ||_rms <= 1.
 * The next step size is h / q with q = E^alpha / E_old^beta / safety clamped to [1/10, 5]
 * (alpha = 1/5 - 0.75 beta, beta = 0.04, safety 0.9, E_old the previous accepted step's error,
 * at least 1e-4): at most a 10-fold growth and a 5-fold cut. A rejected step is retried with
 * h / min(5, E^alpha / safety), and the step after a rejection may not grow. A step whose error
 * estimate or new state is not finite is retried with a fifth of its size, at most
 * CTC_DOPRI5_MAX_NONFINITE times in a row.
 *
 * Stiffness (E. Hairer and G. Wanner, Solving Ordinary Differential Equations II, 2nd ed.,
 * section IV.2, "Automatic stiffness detection", as in their DOPRI5 code; the idea is Shampine's,
 * ACM TOMS 3, 1977). Stages 6 and 7 are both evaluated at t + h, at y6 (stage 6's argument) and
 * at y_new, so rho = ||k7 - k6|| / ||y_new - y6|| estimates the largest |lambda| of the Jacobian
 * (a power iteration for free). DOPRI5's stability region meets the negative real axis at
 * about -3.31, so h rho > 3.25 on an accepted step says that stability, not accuracy, holds the
 * step down. Such steps are counted; six steps in a row below the bound clear the count, and
 * the 15th counted step confirms stiffness (Hairer's numbers). Hairer's code then returns (or
 * only warns, if asked to); we stop only when, in addition, reaching tstop at that step would
 * take more than CTC_DOPRI5_STIFF_STEPS_LEFT further steps, so a stiff run that would end soon
 * is finished. (Hairer's code tests every 1000th step, and every step while a count is open, to
 * save the quotient; it costs two n-vector norms, so we test every step.) The step is then not
 * accepted and the message names it: "stiff: step size below the stability limit, h = ... s at
 * t = ... s ...: use \"method\": \"bdf\"". The counts survive a reset: stiffness belongs to the
 * system. A high-gain CTC run at a tight rtol can be expensive without tripping this test:
 * order reduction on the fast error dynamics keeps h rho well under 3.25 (bench/NOTEBOOK.md,
 * "Stiff gains").
 *
 * Dense output on [t0, t0 + h] with theta = (s - t0) / h, theta1 = 1 - theta:
 *     y(s) = y0 + theta (dy + theta1 (h k1 - dy + theta (dy - h k7 - (h k1 - dy)
 *                                                        + theta1 h sum d_i k_i)))
 * with dy = y_new - y0, which matches y and f at both ends and is of order 4 (Hairer et al.,
 * section II.6). It is evaluated on demand from k1, k3..k6, k7 of the last accepted step, which
 * are kept for it (a pointer swap), so a step pays nothing for it.
 */
#include <math.h>
#include <string.h>

#include "integrator_internal.h"

#define CTC_DOPRI5_MAX_NONFINITE 10

/* stiffness test: bound on h rho, counted steps to confirm, uncounted steps in a row to clear,
 * and the steps still to go to tstop (at the current h) beyond which a confirmed stiff run stops */
#define CTC_DOPRI5_STIFF_H_RHO 3.25
#define CTC_DOPRI5_STIFF_CONFIRM 15
#define CTC_DOPRI5_STIFF_CLEAR 6
#define CTC_DOPRI5_STIFF_STEPS_LEFT 1e5

/* nodes */
static const double C2 = 1.0 / 5, C3 = 3.0 / 10, C4 = 4.0 / 5, C5 = 8.0 / 9;

/* coupling coefficients a_ij */
static const double A21 = 1.0 / 5;
static const double A31 = 3.0 / 40, A32 = 9.0 / 40;
static const double A41 = 44.0 / 45, A42 = -56.0 / 15, A43 = 32.0 / 9;
static const double A51 = 19372.0 / 6561, A52 = -25360.0 / 2187, A53 = 64448.0 / 6561,
                    A54 = -212.0 / 729;
static const double A61 = 9017.0 / 3168, A62 = -355.0 / 33, A63 = 46732.0 / 5247, A64 = 49.0 / 176,
                    A65 = -5103.0 / 18656;

/* 5th-order weights b_i (b2 = b7 = 0), also the coupling coefficients of stage 7 */
static const double B1 = 35.0 / 384, B3 = 500.0 / 1113, B4 = 125.0 / 192, B5 = -2187.0 / 6784,
                    B6 = 11.0 / 84;

/* error weights e_i = b_i - b_hat_i (e2 = 0) */
static const double E1 = 71.0 / 57600, E3 = -71.0 / 16695, E4 = 71.0 / 1920, E5 = -17253.0 / 339200,
                    E6 = 22.0 / 525, E7 = -1.0 / 40;

/* dense output weights d_i (d2 = 0) */
static const double D1 = -12715105075.0 / 11282082432.0, D3 = 87487479700.0 / 32700410799.0,
                    D4 = -10690763975.0 / 1880347072.0, D5 = 701980252875.0 / 199316789632.0,
                    D6 = -1453857185.0 / 822651844.0, D7 = 69997945.0 / 29380423.0;

/* step-size controller */
static const double BETA = 0.04, SAFETY = 0.9;
static const double Q_MIN = 0.1, Q_MAX = 5.0; /* h_new = h / q: growth <= 10, cut <= 5 */

static void swap(double **a, double **b)
{
    double *tmp = *a;
    *a = *b;
    *b = tmp;
}

void ctc_dopri5_reset(ctc_integrator *it)
{
    if (it->h == 0 && it->spec.initial_step > 0) it->h = it->spec.initial_step;
    if (it->spec.max_step > 0 && it->h > it->spec.max_step) it->h = it->spec.max_step;
}

/* ||v / (atol + rtol |y|)||_rms */
static double weighted_rms(int n, const double *v, const double *y, double atol, double rtol)
{
    double s = 0;
    for (int i = 0; i < n; i++) {
        double r = v[i] / (atol + rtol * fabs(y[i]));
        s += r * r;
    }
    return sqrt(s / n);
}

/* Hairer's starting step size (Solving ODEs I, II.4): an explicit Euler step of h0 = 0.01
 * ||y0|| / ||f0|| estimates ||y''|| from the change of f, and h1 makes the local error of a
 * 5th-order step 0.01 with that estimate; h = min(100 h0, h1, hmax). One evaluation of f. */
static int initial_step(ctc_integrator *it, double hmax, double *h_out, char *err, size_t errlen)
{
    const int n = it->n;
    const double atol = it->spec.atol, rtol = it->spec.rtol;
    const double d0 = weighted_rms(n, it->y, it->y, atol, rtol);
    const double d1 = weighted_rms(n, it->f, it->y, atol, rtol);
    double h0 = (d0 < 1e-5 || d1 < 1e-5) ? 1e-6 : 0.01 * d0 / d1;
    if (h0 > hmax) h0 = hmax;

    /* f after an Euler step of h0 */
    for (int i = 0; i < n; i++) it->y_stage[i] = it->y[i] + h0 * it->f[i];
    int rc = ctc_integ_call_rhs(it, it->t + h0, it->y_stage, it->f_new);
    if (rc != 0) return ctc_integ_fail_rhs(rc, it->t + h0, err, errlen);
    for (int i = 0; i < n; i++) it->y_new[i] = it->f_new[i] - it->f[i];
    const double d2 = weighted_rms(n, it->y_new, it->y, atol, rtol) / h0;

    const double dmax = fmax(d1, d2);
    const double h1 = dmax <= 1e-15 ? fmax(1e-6, 1e-3 * h0) : pow(0.01 / dmax, 1.0 / 5);
    double h = fmin(100 * h0, h1);
    if (!(h <= hmax)) h = hmax;
    *h_out = h;
    return 0;
}

int ctc_dopri5_step(ctc_integrator *it, double tstop, char *err, size_t errlen)
{
    const int n = it->n;
    const double t = it->t, atol = it->spec.atol, rtol = it->spec.rtol;
    const double hmax =
        it->spec.max_step > 0 && isfinite(it->spec.max_step) ? it->spec.max_step : 0.0;
    const double *y = it->y, *k1 = it->f;
    double *k2 = it->k_work[0], *k3 = it->k_work[1], *k4 = it->k_work[2], *k5 = it->k_work[3],
           *k6 = it->k_work[4];
    double *ys = it->y_stage, *y_new = it->y_new, *k7 = it->f_new;
    int rc;

    /* the first step after the first reset, without initial_step: choose it */
    if (it->h == 0) {
        double bound = tstop - t;
        if (hmax > 0 && hmax < bound) bound = hmax;
        rc = initial_step(it, bound, &it->h, err, errlen);
        if (rc != 0) return rc;
    }

    double h = it->h; /* the step the controller wants; the one taken may be cut by tstop */
    double hs = h, err_norm = 0, t_stage = t;
    int rejected_here = 0, nonfinite = 0, lands = 0;
    for (;;) {
        if (ctc_integ_below_roundoff(h, t)) {
            it->h = h;
            return ctc_integ_fail_roundoff(h, t, err, errlen);
        }
        if (h < it->spec.min_step && h < tstop - t) {
            it->h = h;
            return ctc_integ_fail_min_step(h, t, it->spec.min_step, err, errlen);
        }
        hs = ctc_integ_clip_step(t, tstop, h, hmax, &lands);
        const double t_new = lands ? tstop : t + hs;

        /* stages 2 to 6 */
        for (int i = 0; i < n; i++) ys[i] = y[i] + hs * A21 * k1[i];
        if ((rc = ctc_integ_call_rhs(it, t_stage = t + C2 * hs, ys, k2)) != 0) break;
        for (int i = 0; i < n; i++) ys[i] = y[i] + hs * (A31 * k1[i] + A32 * k2[i]);
        if ((rc = ctc_integ_call_rhs(it, t_stage = t + C3 * hs, ys, k3)) != 0) break;
        for (int i = 0; i < n; i++) ys[i] = y[i] + hs * (A41 * k1[i] + A42 * k2[i] + A43 * k3[i]);
        if ((rc = ctc_integ_call_rhs(it, t_stage = t + C4 * hs, ys, k4)) != 0) break;
        for (int i = 0; i < n; i++) {
            ys[i] = y[i] + hs * (A51 * k1[i] + A52 * k2[i] + A53 * k3[i] + A54 * k4[i]);
        }
        if ((rc = ctc_integ_call_rhs(it, t_stage = t + C5 * hs, ys, k5)) != 0) break;
        for (int i = 0; i < n; i++) {
            ys[i] =
                y[i] + hs * (A61 * k1[i] + A62 * k2[i] + A63 * k3[i] + A64 * k4[i] + A65 * k5[i]);
        }
        if ((rc = ctc_integ_call_rhs(it, t_stage = t_new, ys, k6)) != 0) break;

        /* the 5th-order solution and stage 7 at it (the next step's k1); nan_probe stays 0
         * unless some y_new_i is infinite or NaN (0 * inf = NaN; IEEE arithmetic, no -ffast-math),
         * and the loop vectorises */
        double nan_probe = 0;
        for (int i = 0; i < n; i++) {
            y_new[i] = y[i] + hs * (B1 * k1[i] + B3 * k3[i] + B4 * k4[i] + B5 * k5[i] + B6 * k6[i]);
            nan_probe += 0.0 * y_new[i];
        }
        if ((rc = ctc_integ_call_rhs(it, t_stage = t_new, y_new, k7)) != 0) break;

        /* the stiffness quotient's two squared norms, while ys still holds stage 6's argument */
        double dk_sq = 0, dy_sq = 0;
        for (int i = 0; i < n; i++) {
            double dk = k7[i] - k6[i], dy = y_new[i] - ys[i];
            dk_sq += dk * dk;
            dy_sq += dy * dy;
        }

        /* error estimate: the scaled errors into ys (free now) in a loop that vectorises, then
         * their rms for the test; the max-norm of the raw errors for the statistics */
        double err_max = 0;
        for (int i = 0; i < n; i++) {
            double e =
                hs * (E1 * k1[i] + E3 * k3[i] + E4 * k4[i] + E5 * k5[i] + E6 * k6[i] + E7 * k7[i]);
            double a = fabs(y[i]), b = fabs(y_new[i]), abs_e = fabs(e);
            ys[i] = e / (atol + rtol * (a > b ? a : b));
            err_max = abs_e > err_max ? abs_e : err_max;
        }
        double sum = 0;
        for (int i = 0; i < n; i++) sum += ys[i] * ys[i];
        err_norm = sqrt(sum / n);

        /* a non-finite state or estimate: retry much smaller, a few times */
        if (nan_probe != 0 || !isfinite(err_norm)) {
            it->stats.rejected++;
            rejected_here = 1;
            if (++nonfinite >= CTC_DOPRI5_MAX_NONFINITE) {
                it->h = 0.2 * hs;
                ctc_fail(CTC_EINVAL, err, errlen,
                         "solution not finite at t = %.10g s after %d step size reductions (last "
                         "step %.3g s)",
                         t, nonfinite, hs);
                return -1;
            }
            h = 0.2 * hs;
            continue;
        }

        if (err_norm <= 1.0) {
            /* stiffness: count the steps held down by stability; stop a long stiff run */
            const double h_rho = dy_sq > 0 ? hs * sqrt(dk_sq / dy_sq) : 0.0;
            if (h_rho > CTC_DOPRI5_STIFF_H_RHO) {
                it->stiff_miss = 0;
                if (it->stiff_hits < CTC_DOPRI5_STIFF_CONFIRM) it->stiff_hits++;
                if (it->stiff_hits == CTC_DOPRI5_STIFF_CONFIRM &&
                    tstop - t_new > CTC_DOPRI5_STIFF_STEPS_LEFT * hs) {
                    it->h = hs;
                    ctc_fail(CTC_EINVAL, err, errlen,
                             "stiff: step size below the stability limit, h = %.3g s at t = "
                             "%.10g s (h |lambda| > %g on %d steps), %.2g steps short of t = "
                             "%.10g s: use \"method\": \"bdf\"",
                             hs, t, CTC_DOPRI5_STIFF_H_RHO, it->stiff_hits, (tstop - t) / hs,
                             tstop);
                    return -1;
                }
            } else if (it->stiff_miss < CTC_DOPRI5_STIFF_CLEAR &&
                       ++it->stiff_miss == CTC_DOPRI5_STIFF_CLEAR) {
                it->stiff_hits = 0;
            }

            /* accepted: PI control of the next step size */
            double q = pow(err_norm, 0.2 - 0.75 * BETA) / pow(it->err_old, BETA) / SAFETY;
            q = fmin(Q_MAX, fmax(Q_MIN, q));
            double h_next = hs / q;
            if (rejected_here) {
                h_next = fmin(h_next, hs);
            } else if (hs < h && h_next > hs) {
                /* the step was cut to meet tstop and went well: resume the size wanted */
                h_next = fmax(h_next, h);
            }
            if (hmax > 0) h_next = fmin(h_next, hmax);
            it->err_old = fmax(err_norm, 1e-4);
            it->h = h_next;

            /* rotate new -> current -> previous; keep this step's k3..k6 for dense output */
            swap(&it->y_prev, &it->y);
            swap(&it->y, &it->y_new);
            swap(&it->f_prev, &it->f);
            swap(&it->f, &it->f_new);
            for (int s = 0; s < CTC_DOPRI5_KEPT_STAGES; s++)
                swap(&it->k_kept[s], &it->k_work[s + 1]);
            it->t_prev = t;
            it->t = t_new;
            it->stats.steps++;
            it->stats.h_last = hs;
            it->stats.err_estimate += err_max;
            return 0;
        }

        /* rejected: cut by the error alone, at most 5-fold */
        it->stats.rejected++;
        rejected_here = 1;
        h = hs / fmin(Q_MAX, pow(err_norm, 0.2 - 0.75 * BETA) / SAFETY);
    }

    /* the rhs failed at one of the stages: nothing of this step is kept */
    it->h = h;
    return ctc_integ_fail_rhs(rc, t_stage, err, errlen);
}

void ctc_dopri5_dense(const ctc_integrator *it, double t, double *y)
{
    const double h = it->t - it->t_prev;
    const double th = (t - it->t_prev) / h, th1 = 1.0 - th;
    const double *y0 = it->y_prev, *y1 = it->y, *k1 = it->f_prev, *k7 = it->f;
    const double *k3 = it->k_kept[0], *k4 = it->k_kept[1], *k5 = it->k_kept[2], *k6 = it->k_kept[3];
    for (int i = 0; i < it->n; i++) {
        double dy = y1[i] - y0[i];
        double slope0 = h * k1[i] - dy;
        double curv = dy - h * k7[i] - slope0;
        double tail =
            h * (D1 * k1[i] + D3 * k3[i] + D4 * k4[i] + D5 * k5[i] + D6 * k6[i] + D7 * k7[i]);
        y[i] = y0[i] + th * (dy + th1 * (slope0 + th * (curv + th1 * tail)));
    }
}
