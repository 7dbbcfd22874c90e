/*
 * traj.h - desired trajectories of one joint coordinate with exact derivatives.
 *
 * A trajectory gives q_d(t), its rate and its acceleration in closed form (no finite
 * differences), as computed torque control needs qdd_d exactly (DESIGN.md section 6). Units are
 * the coordinate's: rad (revolute) or m (prismatic), per s and per s^2; t in s.
 *
 *   constant    q = value
 *   sine        q = offset + amplitude sin(2 pi t / period + phase)
 *   cosine      q = offset + amplitude cos(2 pi t / period + phase)
 *   polynomial  q = sum_i coef[i] t^i, i = 0..ncoef-1 (ncoef <= CTC_TRAJ_MAX_COEF)
 *   min_jerk    from q0 at t0 to q1 at t1 with zero rate and acceleration at both ends:
 *               q = q0 + (q1 - q0)(10 s^3 - 15 s^4 + 6 s^5), s = (t - t0)/(t1 - t0);
 *               q0 before t0 and q1 after t1 (so q, qd, qdd are continuous everywhere)
 *   spline      cubic spline through (times[i], values[i]), i = 0..n-1, n >= 2, strictly
 *               increasing times; boundary "clamped" (zero rate at both ends, the default: the
 *               motion starts and ends at rest) or "natural" (zero acceleration at both ends);
 *               before times[0] and after times[n-1] it holds the end value with zero rate
 *               and acceleration ("clamped") or continues along the end tangent ("natural").
 *
 * A spline owns its knots and coefficients (allocated by ctc_traj_spline, freed by
 * ctc_traj_free); the other types own nothing. Evaluation is pure, allocates nothing and is
 * thread-safe.
 */
#ifndef CTC_TRAJ_H
#define CTC_TRAJ_H

#include <stddef.h>

#include "status.h"

#define CTC_TRAJ_MAX_COEF 16
#define CTC_TRAJ_MAX_KNOTS 100000

typedef enum ctc_traj_type {
    CTC_TRAJ_CONSTANT,
    CTC_TRAJ_SINE,
    CTC_TRAJ_COSINE,
    CTC_TRAJ_POLYNOMIAL,
    CTC_TRAJ_MIN_JERK,
    CTC_TRAJ_SPLINE,
} ctc_traj_type;

typedef enum ctc_spline_boundary {
    CTC_SPLINE_CLAMPED,
    CTC_SPLINE_NATURAL,
} ctc_spline_boundary;

typedef struct ctc_traj {
    ctc_traj_type type;
    double value;                    /* constant */
    double amplitude, period, phase; /* sine, cosine: period > 0 (s), phase in rad */
    double offset;                   /* sine, cosine */
    int ncoef;                       /* polynomial: 1..CTC_TRAJ_MAX_COEF */
    double coef[CTC_TRAJ_MAX_COEF];  /* polynomial, coef[i] multiplies t^i */
    double q0, q1, t0, t1;           /* min_jerk: t1 > t0 */
    int nknots;                      /* spline */
    ctc_spline_boundary boundary;    /* spline */
    double *knots;                   /* spline (nknots x 5): t, a, b, c, d of the piece
                                        q = a + b s + c s^2 + d s^3, s = t - t_i; the last
                                        row is the end: t, value, rate, half the
                                        acceleration from the left, 0; owned */
} ctc_traj;

/* Checks a non-spline trajectory's parameters: finite numbers, period > 0, 1 <= ncoef <=
 * CTC_TRAJ_MAX_COEF, t1 > t0, and a peak position, rate and acceleration that do not overflow.
 * The message starts with the type and names the parameter as the job format does (coefficients,
 * from, to, start, end), e.g. "sine: period must be positive and finite (got 0 s)" or
 * "min_jerk: end (1 s) must be after start (2 s)". Splines are checked by ctc_traj_spline; here
 * a spline only needs knots and a known boundary. */
ctc_status ctc_traj_check(const ctc_traj *tr, char *err, size_t errlen);

/* Makes *out a cubic spline through n knots (times strictly increasing, all finite,
 * 2 <= n <= CTC_TRAJ_MAX_KNOTS), solving the tridiagonal system once (O(n)). *out owns the knot
 * array afterwards (ctc_traj_free); it is written only on success and is not freed first.
 * CTC_EINVAL with a message naming the knot, e.g. "spline: times[3] = 1 is not after
 * times[2] = 1", also when values too far apart on close knots overflow the coefficients;
 * CTC_ENOMEM when the knot array cannot be allocated. */
ctc_status ctc_traj_spline(int n, const double *times, const double *values,
                           ctc_spline_boundary boundary, ctc_traj *out, char *err, size_t errlen);

/* Frees what tr owns (a spline's knots; the other types own nothing) and leaves it a constant 0,
 * so freeing twice is harmless; NULL is allowed. */
void ctc_traj_free(ctc_traj *tr);

/* The desired position, rate and acceleration at time t: out = (q, qd, qdd). tr must have
 * passed ctc_traj_check. A spline finds its piece by binary search (O(log n)) and returns each
 * knot's value exactly; at t_0 and t_{n-1} it gives its own end values (a clamped spline's end
 * acceleration need not be 0), outside them the end line. */
void ctc_traj_eval(const ctc_traj *tr, double t, double out[3]);

#endif
