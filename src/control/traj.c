/*
 * traj.c - desired trajectories of one coordinate (traj.h): closed-form position, rate and
 * acceleration of a constant, a sinusoid, a polynomial, a minimum-jerk blend and a cubic spline.
 *
 * Sinusoids reduce t modulo the period before forming the angle, so the phase stays accurate at
 * large t. A polynomial's q, qd and qdd come out of one Horner pass. The minimum-jerk blend is
 * p(s) = 10 s^3 - 15 s^4 + 6 s^5 of s = (t - t0)/T, T = t1 - t0, with p'(s) = 30 s^2 (1 - s)^2 and
 * p''(s) = 60 s (1 - s)(1 - 2 s); both vanish at s = 0 and s = 1, so holding q0 before t0 and q1
 * after t1 keeps q, qd and qdd continuous.
 *
 * Splines are built in slope form. The unknowns are the knot rates m_i; each piece is the cubic
 * Hermite interpolant of (y_i, m_i) and (y_{i+1}, m_{i+1}), so q and qd are continuous by
 * construction, and continuity of qdd at the interior knots gives, with h_i = t_{i+1} - t_i and
 * the chord slopes d_i = (y_{i+1} - y_i)/h_i,
 *     h_i m_{i-1} + 2 (h_{i-1} + h_i) m_i + h_{i-1} m_{i+1} = 3 (h_i d_{i-1} + h_{i-1} d_i).
 * Clamped ends fix m_0 = m_{n-1} = 0; natural ends ask for zero acceleration, which reads
 * 2 m_0 + m_1 = 3 d_0 and m_{n-2} + 2 m_{n-1} = 3 d_{n-2}. Every row is strictly diagonally
 * dominant, so the Thomas algorithm (Gaussian elimination without pivoting on the three
 * diagonals) is stable; it runs in place in the knot array. Piece i, q = a + b s + c s^2 + d s^3
 * with s = t - t_i, then has
 *     a = y_i,  b = m_i,  c = (3 d_i - 2 m_i - m_{i+1})/h_i,  d = (m_i + m_{i+1} - 2 d_i)/h_i^2.
 * The last row (t_{n-1}, y_{n-1}, m_{n-1}, qdd(t_{n-1}^-)/2, 0) gives the value at t_{n-1} itself
 * (so every knot is interpolated exactly), and its a and b, like row 0's, give the straight line
 * used outside [t_0, t_{n-1}]; a clamped spline has zero end rates, so that line is constant.
 * Evaluation finds the piece by binary search: O(log n), nothing allocated.
 */
#include "traj.h"

#include <math.h>
#include <stdlib.h>

#include "spatial.h"

#define KNOT_COLS 5 /* t, a, b, c, d */

static const char *type_name(ctc_traj_type type)
{
    switch (type) {
    case CTC_TRAJ_CONSTANT:
        return "constant";
    case CTC_TRAJ_SINE:
        return "sine";
    case CTC_TRAJ_COSINE:
        return "cosine";
    case CTC_TRAJ_POLYNOMIAL:
        return "polynomial";
    case CTC_TRAJ_MIN_JERK:
        return "min_jerk";
    case CTC_TRAJ_SPLINE:
        return "spline";
    }
    return "unknown";
}

/* CTC_EINVAL with "<type>: <what> must be finite (got <x><unit>)" unless x is finite */
static ctc_status check_finite(const char *type, const char *what, double x, const char *unit,
                               char *err, size_t errlen)
{
    if (isfinite(x)) return CTC_OK;
    return ctc_fail(CTC_EINVAL, err, errlen, "%s: %s must be finite (got %g%s)", type, what, x,
                    unit);
}

static ctc_status check_sinusoid(const ctc_traj *tr, char *err, size_t errlen)
{
    const char *type = type_name(tr->type);
    ctc_status st = check_finite(type, "amplitude", tr->amplitude, "", err, errlen);
    if (st != CTC_OK) return st;
    if (!isfinite(tr->period) || !(tr->period > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "%s: period must be positive and finite (got %g s)", type, tr->period);
    }
    st = check_finite(type, "phase", tr->phase, " rad", err, errlen);
    if (st == CTC_OK) st = check_finite(type, "offset", tr->offset, "", err, errlen);
    if (st != CTC_OK) return st;

    /* the largest |q| and |qdd| must be representable */
    if (!isfinite(fabs(tr->offset) + fabs(tr->amplitude))) {
        return ctc_fail(CTC_EINVAL, err, errlen, "%s: offset + amplitude overflows", type);
    }
    double w = 2 * CTC_PI / tr->period;
    if (!isfinite(w) || !isfinite(fabs(tr->amplitude) * w * w)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "%s: period %g s is too short (the acceleration overflows)", type,
                        tr->period);
    }
    return CTC_OK;
}

static ctc_status check_polynomial(const ctc_traj *tr, char *err, size_t errlen)
{
    if (tr->ncoef < 1 || tr->ncoef > CTC_TRAJ_MAX_COEF) {
        return ctc_fail(CTC_EINVAL, err, errlen, "polynomial: needs 1 to %d coefficients (got %d)",
                        CTC_TRAJ_MAX_COEF, tr->ncoef);
    }
    for (int i = 0; i < tr->ncoef; i++) {
        if (!isfinite(tr->coef[i])) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "polynomial: coefficients[%d] must be finite (got %g)", i, tr->coef[i]);
        }
    }
    return CTC_OK;
}

static ctc_status check_min_jerk(const ctc_traj *tr, char *err, size_t errlen)
{
    ctc_status st = check_finite("min_jerk", "from", tr->q0, "", err, errlen);
    if (st == CTC_OK) st = check_finite("min_jerk", "to", tr->q1, "", err, errlen);
    if (st == CTC_OK) st = check_finite("min_jerk", "start", tr->t0, " s", err, errlen);
    if (st == CTC_OK) st = check_finite("min_jerk", "end", tr->t1, " s", err, errlen);
    if (st != CTC_OK) return st;
    if (!(tr->t1 > tr->t0)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "min_jerk: end (%g s) must be after start (%g s)",
                        tr->t1, tr->t0);
    }

    /* the duration, the distance and the peak acceleration must be representable */
    double duration = tr->t1 - tr->t0, distance = tr->q1 - tr->q0;
    if (!isfinite(duration)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "min_jerk: end - start overflows");
    }
    if (!isfinite(distance)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "min_jerk: to - from overflows");
    }
    if (!isfinite(60 * (fabs(distance) / duration / duration))) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "min_jerk: the acceleration overflows (to - from too large for end - "
                        "start = %g s)",
                        duration);
    }
    return CTC_OK;
}

static ctc_status check_boundary(ctc_spline_boundary boundary, char *err, size_t errlen)
{
    if (boundary == CTC_SPLINE_CLAMPED || boundary == CTC_SPLINE_NATURAL) return CTC_OK;
    return ctc_fail(CTC_EINVAL, err, errlen,
                    "spline: unknown boundary %d (want clamped or natural)", (int)boundary);
}

ctc_status ctc_traj_check(const ctc_traj *tr, char *err, size_t errlen)
{
    if (tr == NULL) return ctc_fail(CTC_EINVAL, err, errlen, "trajectory is NULL");
    switch (tr->type) {
    case CTC_TRAJ_CONSTANT:
        return check_finite("constant", "value", tr->value, "", err, errlen);
    case CTC_TRAJ_SINE:
    case CTC_TRAJ_COSINE:
        return check_sinusoid(tr, err, errlen);
    case CTC_TRAJ_POLYNOMIAL:
        return check_polynomial(tr, err, errlen);
    case CTC_TRAJ_MIN_JERK:
        return check_min_jerk(tr, err, errlen);
    case CTC_TRAJ_SPLINE:
        if (tr->knots == NULL || tr->nknots < 2 || tr->nknots > CTC_TRAJ_MAX_KNOTS) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "spline: has no knots (make it with ctc_traj_spline)");
        }
        return check_boundary(tr->boundary, err, errlen);
    }
    return ctc_fail(CTC_EINVAL, err, errlen, "unknown trajectory type %d", (int)tr->type);
}

/* checks the knots; CTC_OK when they are finite, strictly increasing and finitely spaced */
static ctc_status check_knots(int n, const double *times, const double *values, char *err,
                              size_t errlen)
{
    for (int i = 0; i < n; i++) {
        if (!isfinite(times[i])) {
            return ctc_fail(CTC_EINVAL, err, errlen, "spline: times[%d] must be finite (got %g s)",
                            i, times[i]);
        }
        if (!isfinite(values[i])) {
            return ctc_fail(CTC_EINVAL, err, errlen, "spline: values[%d] must be finite (got %g)",
                            i, values[i]);
        }
        if (i == 0) continue;
        if (!(times[i] > times[i - 1])) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "spline: times[%d] = %g is not after times[%d] = %g", i, times[i],
                            i - 1, times[i - 1]);
        }
        if (!isfinite(times[i] - times[i - 1])) {
            return ctc_fail(CTC_EINVAL, err, errlen, "spline: times[%d] - times[%d] overflows", i,
                            i - 1);
        }
    }
    return CTC_OK;
}

/* solves for the knot rates m_i by the Thomas algorithm; k holds t and y in columns 0 and 1 and
   receives m in column 2 (column 3 is scratch) */
static void solve_knot_rates(int n, ctc_spline_boundary boundary, double *k)
{
    /* forward sweep: row i is lower m_{i-1} + diag m_i + upper m_{i+1} = rhs; the reduced
       upper coefficient goes to column 3, the reduced right side to column 2 */
    for (int i = 0; i < n; i++) {
        double *row = k + KNOT_COLS * i;
        /* a clamped end keeps this identity row: m = 0 */
        double lower = 0, diag = 1, upper = 0, rhs = 0;
        if (i > 0 && i < n - 1) {
            double hl = row[0] - row[-KNOT_COLS], hr = row[KNOT_COLS] - row[0];
            double dl = (row[1] - row[1 - KNOT_COLS]) / hl;
            double dr = (row[KNOT_COLS + 1] - row[1]) / hr;
            lower = hr;
            diag = 2 * (hl + hr);
            upper = hl;
            rhs = 3 * (hr * dl + hl * dr);
        } else if (boundary == CTC_SPLINE_NATURAL && i == 0) {
            diag = 2;
            upper = 1;
            rhs = 3 * (row[KNOT_COLS + 1] - row[1]) / (row[KNOT_COLS] - row[0]);
        } else if (boundary == CTC_SPLINE_NATURAL) {
            lower = 1;
            diag = 2;
            rhs = 3 * (row[1] - row[1 - KNOT_COLS]) / (row[0] - row[-KNOT_COLS]);
        }
        /* eliminate m_{i-1} with the previous reduced row */
        if (i > 0) {
            diag -= lower * row[3 - KNOT_COLS];
            rhs -= lower * row[2 - KNOT_COLS];
        }
        row[3] = upper / diag;
        row[2] = rhs / diag;
    }

    /* back substitution */
    for (int i = n - 2; i >= 0; i--) {
        double *row = k + KNOT_COLS * i;
        row[2] -= row[3] * row[KNOT_COLS + 2];
    }
}

ctc_status ctc_traj_spline(int n, const double *times, const double *values,
                           ctc_spline_boundary boundary, ctc_traj *out, char *err, size_t errlen)
{
    if (n < 2 || n > CTC_TRAJ_MAX_KNOTS) {
        return ctc_fail(CTC_EINVAL, err, errlen, "spline: needs 2 to %d knots (got %d)",
                        CTC_TRAJ_MAX_KNOTS, n);
    }
    if (times == NULL) return ctc_fail(CTC_EINVAL, err, errlen, "spline: times is NULL");
    if (values == NULL) return ctc_fail(CTC_EINVAL, err, errlen, "spline: values is NULL");
    if (out == NULL) return ctc_fail(CTC_EINVAL, err, errlen, "spline: out is NULL");
    ctc_status st = check_boundary(boundary, err, errlen);
    if (st != CTC_OK) return st;
    st = check_knots(n, times, values, err, errlen);
    if (st != CTC_OK) return st;

    double *k = malloc(sizeof(double) * KNOT_COLS * (size_t)n);
    if (k == NULL) {
        return ctc_fail(CTC_ENOMEM, err, errlen, "spline: out of memory for %d knots", n);
    }
    for (int i = 0; i < n; i++) {
        k[KNOT_COLS * i] = times[i];
        k[KNOT_COLS * i + 1] = values[i];
    }
    solve_knot_rates(n, boundary, k);

    /* piece coefficients from the end values and rates of each interval (Hermite form) */
    for (int i = 0; i < n - 1; i++) {
        double *row = k + KNOT_COLS * i;
        double h = row[KNOT_COLS] - row[0];
        double chord = (row[KNOT_COLS + 1] - row[1]) / h;
        double m0 = row[2], m1 = row[KNOT_COLS + 2];
        row[3] = (3 * chord - 2 * m0 - m1) / h;
        row[4] = (m0 + m1 - 2 * chord) / h / h;
    }

    /* the last row: half the acceleration at t_{n-1} from the left, and no cubic term */
    double *last = k + KNOT_COLS * (n - 1), *prev = last - KNOT_COLS;
    last[3] = prev[3] + 3 * prev[4] * (last[0] - prev[0]);
    last[4] = 0;

    /* values far apart on close knots give coefficients that overflow */
    for (int i = 0; i < n; i++) {
        const double *row = k + KNOT_COLS * i;
        if (!isfinite(row[2]) || !isfinite(row[3]) || !isfinite(row[4])) {
            free(k);
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "spline: coefficients overflow at times[%d] = %g (values too far "
                            "apart for the knot spacing)",
                            i, times[i]);
        }
    }

    *out = (ctc_traj){.type = CTC_TRAJ_SPLINE, .nknots = n, .boundary = boundary, .knots = k};
    return CTC_OK;
}

void ctc_traj_free(ctc_traj *tr)
{
    if (tr == NULL) return;
    if (tr->type == CTC_TRAJ_SPLINE) free(tr->knots);
    *tr = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = 0};
}

/* offset + amplitude sin or cos of (2 pi t / period + phase), t reduced modulo the period */
static void eval_sinusoid(const ctc_traj *tr, double t, int cosine, double out[3])
{
    double w = 2 * CTC_PI / tr->period;
    double angle = w * fmod(t, tr->period) + tr->phase;
    double s = sin(angle), c = cos(angle), a = tr->amplitude;
    if (cosine) {
        out[0] = tr->offset + a * c;
        out[1] = -a * w * s;
        out[2] = -a * w * w * c;
    } else {
        out[0] = tr->offset + a * s;
        out[1] = a * w * c;
        out[2] = -a * w * w * s;
    }
}

/* Horner's scheme carrying the first derivative and half the second along */
static void eval_polynomial(const ctc_traj *tr, double t, double out[3])
{
    double p = 0, dp = 0, half_ddp = 0;
    for (int i = tr->ncoef - 1; i >= 0; i--) {
        half_ddp = half_ddp * t + dp;
        dp = dp * t + p;
        p = p * t + tr->coef[i];
    }
    out[0] = p;
    out[1] = dp;
    out[2] = 2 * half_ddp;
}

static void eval_min_jerk(const ctc_traj *tr, double t, double out[3])
{
    /* at rest outside [t0, t1] (a NaN t falls through and gives NaN) */
    if (t <= tr->t0 || t >= tr->t1) {
        out[0] = t <= tr->t0 ? tr->q0 : tr->q1;
        out[1] = 0;
        out[2] = 0;
        return;
    }
    double duration = tr->t1 - tr->t0, distance = tr->q1 - tr->q0;
    double s = (t - tr->t0) / duration, r = 1 - s;
    out[0] = tr->q0 + distance * s * s * s * (10 + s * (-15 + 6 * s));
    out[1] = distance / duration * 30 * s * s * r * r;
    out[2] = distance / duration / duration * 60 * s * r * (1 - 2 * s);
}

/* the piece containing t: binary search for the last knot at or before t */
static const double *spline_row(const double *k, int n, double t)
{
    int lo = 0, hi = n - 1;
    while (hi - lo > 1) {
        int mid = lo + (hi - lo) / 2;
        if (t >= k[KNOT_COLS * mid]) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    /* t == t_{n-1} takes the last row, which carries the end values exactly */
    if (t >= k[KNOT_COLS * hi]) lo = hi;
    return k + KNOT_COLS * lo;
}

static void eval_spline(const ctc_traj *tr, double t, double out[3])
{
    const double *k = tr->knots;
    const double *last = k + KNOT_COLS * (tr->nknots - 1);

    /* outside the knots: the line along the end rate (constant when the rate is zero) */
    if (t < k[0] || t > last[0]) {
        const double *row = t < k[0] ? k : last;
        out[0] = row[2] == 0 ? row[1] : row[1] + row[2] * (t - row[0]);
        out[1] = row[2];
        out[2] = 0;
        return;
    }

    const double *row = spline_row(k, tr->nknots, t);
    double s = t - row[0], b = row[2], c = row[3], d = row[4];
    out[0] = row[1] + s * (b + s * (c + s * d));
    out[1] = b + s * (2 * c + s * 3 * d);
    out[2] = 2 * c + 6 * d * s;
}

void ctc_traj_eval(const ctc_traj *tr, double t, double out[3])
{
    switch (tr->type) {
    case CTC_TRAJ_CONSTANT:
        out[0] = tr->value;
        out[1] = 0;
        out[2] = 0;
        return;
    case CTC_TRAJ_SINE:
        eval_sinusoid(tr, t, 0, out);
        return;
    case CTC_TRAJ_COSINE:
        eval_sinusoid(tr, t, 1, out);
        return;
    case CTC_TRAJ_POLYNOMIAL:
        eval_polynomial(tr, t, out);
        return;
    case CTC_TRAJ_MIN_JERK:
        eval_min_jerk(tr, t, out);
        return;
    case CTC_TRAJ_SPLINE:
        eval_spline(tr, t, out);
        return;
    }
    /* an unchecked, unknown type: make it visible */
    out[0] = out[1] = out[2] = NAN;
}
