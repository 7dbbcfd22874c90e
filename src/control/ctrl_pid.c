/*
 * ctrl_pid.c - PD and PID gains, gains from a damping ratio and a time constant, and the
 * closed-loop poles of any gains (ctrl.h; paper Appendix B, Eq. 86-96).
 *
 * With an exact model the tracking error obeys e''' + kv e'' + kp e' + ki e = 0, so a gain
 * triple is acceptable exactly when s^3 + kv s^2 + kp s + ki is Hurwitz. For a monic cubic the
 * Routh array reduces that to kv > 0, kp > 0, ki > 0 and kv kp > ki; PD (ki = 0) is the quadratic
 * s^2 + kv s + kp times s, whose extra root at 0 belongs to the integral state, which is only
 * recorded. The damping-ratio design is Eq. 92-94: s^2 + 2 zeta wn s + wn^2 with wn = 1 / tau.
 *
 * The poles are found without LAPACK, so that every root has a backward error at rounding level
 * and well-separated roots keep their accuracy relative to their own size however far apart
 * their magnitudes are:
 *  1. scale s by a power of two (exact) so that every coefficient of the monic cubic is at most 1
 *     in magnitude; then all roots lie in |x| < 2 and p(-2) < 0 < p(2);
 *  2. find one real root by Newton's method safeguarded with bisection on [-2, 2];
 *  3. divide it out, forward (from the leading coefficient) when it is the smallest root and
 *     backward (from the constant) otherwise, which is the stable order of each recurrence;
 *  4. solve the remaining quadratic without cancellation and polish its roots with Newton steps
 *     on the full cubic, keeping a step only when it reduces |p| and stays well inside the gap to
 *     the other roots (so two close roots cannot collapse into one).
 */
#include "ctrl.h"

#include <complex.h>
#include <float.h>
#include <math.h>

/* Routh-Hurwitz check of validated positive kp, kv and ki >= 0; PD (ki = 0) needs nothing more,
 * even where kv kp underflows */
static ctc_status check_routh(double kp, double kv, double ki, char *err, size_t errlen)
{
    double kvkp = kv * kp;
    if (ki != 0 && !(ki < kvkp)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "ki = %.15g must be below kv*kp = %.15g (Routh-Hurwitz: the closed-loop "
                        "error dynamics would be unstable)",
                        ki, kvkp);
    }
    return CTC_OK;
}

ctc_status ctc_ctrl_pid(double kp, double kv, double ki, ctc_gains *out, char *err, size_t errlen)
{
    if (!isfinite(kp) || !(kp > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "kp must be positive and finite (got %g)", kp);
    }
    if (!isfinite(kv) || !(kv > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "kv must be positive and finite (got %g)", kv);
    }
    if (!isfinite(ki) || !(ki >= 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "ki must be non-negative and finite (got %g; 0 gives PD)", ki);
    }
    ctc_status st = check_routh(kp, kv, ki, err, errlen);
    if (st != CTC_OK) return st;
    out->ki = ki;
    out->kp = kp;
    out->kv = kv;
    return CTC_OK;
}

ctc_status ctc_ctrl_zeta_tau(double zeta, double tau, double ki, ctc_gains *out, char *err,
                             size_t errlen)
{
    if (!isfinite(zeta) || !(zeta > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "zeta must be positive and finite (got %g)", zeta);
    }
    if (!isfinite(tau) || !(tau > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "tau must be positive and finite (got %g s)", tau);
    }

    /* Eq. 92-94: wn = 1 / tau, kp = wn^2, kv = 2 zeta wn */
    double wn = 1.0 / tau;
    double kp = wn * wn, kv = 2.0 * zeta * wn;
    if (!isfinite(kp)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "tau = %g s is too small: kp = 1/tau^2 overflows",
                        tau);
    }
    if (!(kp > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "tau = %g s is too large: kp = 1/tau^2 underflows to zero", tau);
    }
    if (!isfinite(kv) || !(kv > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "zeta = %g and tau = %g s give kv = 2 zeta/tau = %g, which must be "
                        "positive and finite",
                        zeta, tau, kv);
    }
    return ctc_ctrl_pid(kp, kv, ki, out, err, errlen);
}

/* ---- roots of s^3 + a s^2 + b s + c ---- */

/* p(x) and p'(x) of the monic cubic at a real x (Horner) */
static void cubic_eval(double a, double b, double c, double x, double *p, double *dp)
{
    *p = ((x + a) * x + b) * x + c;
    *dp = (3.0 * x + 2.0 * a) * x + b;
}

/* a real root of the monic cubic whose coefficients are at most 1 in magnitude: Newton's method,
 * falling back to bisection whenever a step would leave the bracket [lo, hi] or would not halve
 * it fast enough; p(lo) < 0 < p(hi) throughout */
static double cubic_real_root(double a, double b, double c)
{
    double lo = -2.0, hi = 2.0; /* p(-2) <= -1 and p(2) >= 1 when |a|, |b|, |c| <= 1 */
    double x = 0.0, step = hi - lo, step_before = step;
    double p, dp;
    cubic_eval(a, b, c, x, &p, &dp);
    for (int iter = 0; iter < 200 && p != 0.0; iter++) {
        int newton_leaves = ((x - hi) * dp - p) * ((x - lo) * dp - p) > 0.0;
        int newton_slow = fabs(2.0 * p) > fabs(step_before * dp);
        step_before = step;
        if (newton_leaves || newton_slow) {
            step = 0.5 * (hi - lo);
            x = lo + step;
        } else {
            step = p / dp;
            x -= step;
        }
        if (fabs(step) <= DBL_EPSILON * fabs(x) || hi - lo <= DBL_EPSILON * fmax(-lo, hi)) break;
        cubic_eval(a, b, c, x, &p, &dp);
        if (p < 0)
            lo = x;
        else
            hi = x;
    }
    return x;
}

/* up to two Newton steps on the cubic from the approximate root z; a step is kept only when it
 * lowers |p| and moves z by less than a third of gap (the distance to the nearest other root) */
static double complex cubic_polish(double a, double b, double c, double complex z, double gap)
{
    for (int iter = 0; iter < 2; iter++) {
        double complex p = ((z + a) * z + b) * z + c;
        double complex dp = (3.0 * z + 2.0 * a) * z + b;
        if (p == 0.0 || dp == 0.0) break;
        double complex next = z - p / dp;
        double complex pn = ((next + a) * next + b) * next + c;
        if (!(cabs(next - z) < gap / 3.0) || !(cabs(pn) < cabs(p))) break;
        z = next;
    }
    return z;
}

/* sorts the three roots by real part, then imaginary part */
static void sort_roots(double re[3], double im[3])
{
    for (int i = 1; i < 3; i++) {
        for (int j = i; j > 0; j--) {
            int before = re[j] < re[j - 1] || (re[j] == re[j - 1] && im[j] < im[j - 1]);
            if (!before) break;
            double tr = re[j], ti = im[j];
            re[j] = re[j - 1];
            im[j] = im[j - 1];
            re[j - 1] = tr;
            im[j - 1] = ti;
        }
    }
}

void ctc_ctrl_closed_loop_poles(const ctc_gains *g, double re[3], double im[3])
{
    double a = g->kv, b = g->kp, c = g->ki;
    for (int j = 0; j < 3; j++) im[j] = 0.0;
    if (!isfinite(a) || !isfinite(b) || !isfinite(c)) {
        for (int j = 0; j < 3; j++) re[j] = im[j] = NAN;
        return;
    }

    /* scale s = 2^e x so that every coefficient of the cubic in x is below 1 in magnitude */
    double m = fmax(fabs(a), fmax(sqrt(fabs(b)), cbrt(fabs(c))));
    if (m == 0.0) {
        for (int j = 0; j < 3; j++) re[j] = 0.0;
        return;
    }
    int e;
    frexp(m, &e); /* m < 2^e */
    a = ldexp(a, -e);
    b = ldexp(b, -2 * e);
    c = ldexp(c, -3 * e);

    /* one real root, divided out in the stable direction: forward when it is the smallest */
    double r = cubic_real_root(a, b, c);
    double p, q; /* x^3 + a x^2 + b x + c = (x - r)(x^2 + p x + q) */
    if (r == 0.0 || fabs(r) * r * r <= fabs(c)) {
        p = a + r;
        q = b + r * p;
    } else {
        q = -c / r;
        p = (q - b) / r;
    }

    /* the quadratic's roots without cancellation, then polished on the cubic */
    double disc = p * p - 4.0 * q;
    double x[3] = {r, 0, 0}, y[3] = {0, 0, 0};
    if (disc >= 0) {
        double t = -0.5 * (p + copysign(sqrt(disc), p));
        double x1 = t, x2 = t != 0.0 ? q / t : 0.0;
        double gap1 = fmin(fabs(x1 - r), fabs(x1 - x2)), gap2 = fmin(fabs(x2 - r), fabs(x1 - x2));
        x[1] = creal(cubic_polish(a, b, c, x1, gap1));
        x[2] = creal(cubic_polish(a, b, c, x2, gap2));
    } else {
        double complex z = -0.5 * p + 0.5 * sqrt(-disc) * I;
        double gap = fmin(cabs(z - r), 2.0 * cimag(z));
        z = cubic_polish(a, b, c, z, gap);
        x[1] = x[2] = creal(z);
        y[1] = -fabs(cimag(z));
        y[2] = fabs(cimag(z));
    }

    /* back to s */
    for (int j = 0; j < 3; j++) {
        re[j] = ldexp(x[j], e);
        im[j] = ldexp(y[j], e);
    }
    sort_roots(re, im);
}

/* ---- the pd and pid classes (ctrl.h): gains from "kp" and "kv" or from "zeta" and "tau" ---- */

static ctc_status design_pd_pid(const ctc_ctrl_params *p, double ki, ctc_gains *out, char *err,
                                size_t errlen)
{
    return (p->given & CTC_CP_KP) ? ctc_ctrl_pid(p->kp, p->kv, ki, out, err, errlen)
                                  : ctc_ctrl_zeta_tau(p->zeta, p->tau, ki, out, err, errlen);
}

static ctc_status design_pd(const ctc_ctrl_params *p, ctc_gains *out, char *err, size_t errlen)
{
    return design_pd_pid(p, 0.0, out, err, errlen);
}

static ctc_status design_pid(const ctc_ctrl_params *p, ctc_gains *out, char *err, size_t errlen)
{
    return design_pd_pid(p, p->ki, out, err, errlen);
}

const ctc_ctrl_class ctc_ctrl_class_pd = {
    .name = "pd",
    .params = CTC_CP_KP | CTC_CP_KV | CTC_CP_ZETA | CTC_CP_TAU,
    .gain_pair = 1,
    .nstate = 1, /* recorded only: ki = 0 */
    .design = design_pd,
    .law = ctc_ctrl_linear_law,
    .closed_loop = ctc_ctrl_linear_closed_loop,
};

const ctc_ctrl_class ctc_ctrl_class_pid = {
    .name = "pid",
    .params = CTC_CP_KP | CTC_CP_KV | CTC_CP_KI | CTC_CP_ZETA | CTC_CP_TAU,
    .required = CTC_CP_KI,
    .gain_pair = 1,
    .nstate = 1,
    .design = design_pid,
    .law = ctc_ctrl_linear_law,
    .closed_loop = ctc_ctrl_linear_closed_loop,
};
