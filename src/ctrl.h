/*
 * ctrl.h - controller design for computed torque control: PD, PID, pole placement and LQR gains
 * of one joint coordinate (paper section 6 and Appendix B, DESIGN.md section 6).
 *
 * Every controller ctcsim offers is a linear state feedback on the coordinate's tracking error
 * state E = (integral of e, e, de/dt), with e = q_d - q:
 *
 *     commanded acceleration  u = qdd_d + w,    w = ki * int(e) + kp * e + kv * de/dt.
 *
 * With an exact model the inverse dynamics make qdd = u, so the error obeys the linear law
 * e''' + kv e'' + kp e' + ki e = 0 (d/dt of e'' + kv e' + kp e + ki int(e) = 0), whose
 * characteristic polynomial is s^3 + kv s^2 + kp s + ki. PD is ki = 0, where the law reduces to
 * e'' + kv e' + kp e = 0 (s^2 + kv s + kp) and the integral state is only recorded. The design
 * functions turn the user's parameters into (ki, kp, kv) and reject any that do not make the
 * polynomial Hurwitz (every root strictly in the left half plane), with a message saying why.
 *
 * Pole placement and LQR use the paper's state space (Eq. 71-80) with
 * A = [[0,1,0],[0,0,1],[0,0,0]], B = (0,0,1)^T and K = (ki, kp, kv). Since e'' = qdd_d - qdd = -w,
 *     dE/dt = A E - B w,  w = K E,  so  dE/dt = (A - B K) E,
 * the companion matrix of s^3 + kv s^2 + kp s + ki; the paper writes dE/dt = A E + B w' with
 * w' = K' E and K' = -K. The LQR cost and Riccati equation do not depend on the sign of B.
 *
 * Units: gains in s^-3, s^-2, s^-1; poles in s^-1; tau in s.
 * All functions are pure and thread-safe and none allocates (ctc_ctrl_lqr keeps LAPACK's
 * workspace on the stack). The design functions write *out only on success; on failure they
 * return the status and, when err is not NULL, a message of at most errlen bytes naming the
 * parameter and the reason (CTC_EINVAL: the input is invalid or has no acceptable gains;
 * CTC_ESINGULAR: ctc_ctrl_lqr's numerics failed on input that passed validation).
 */
#ifndef CTC_CTRL_H
#define CTC_CTRL_H

#include <stddef.h>

#include "status.h"

/* The feedback gains of one coordinate: w = ki int(e) + kp e + kv de/dt. */
typedef struct ctc_gains {
    double ki; /* s^-3 */
    double kp; /* s^-2 */
    double kv; /* s^-1 */
} ctc_gains;

/* PD (ki = 0) or PID gains as given. Requires finite kp > 0, kv > 0 and 0 <= ki < kv kp (Routh:
 * s^3 + kv s^2 + kp s + ki is stable iff all are positive and ki < kv kp; Appendix B, Eq. 96).
 * Errors name the gain, e.g. "kp must be positive and finite (got -1)" or "ki = 250 must be
 * below kv*kp = 200 (Routh-Hurwitz: the closed-loop error dynamics would be unstable)". */
ctc_status ctc_ctrl_pid(double kp, double kv, double ki, ctc_gains *out, char *err, size_t errlen);

/* Gains from a damping ratio zeta > 0 and a time constant tau > 0 (Appendix B, Eq. 92-94):
 * wn = 1 / tau, kp = wn^2, kv = 2 zeta wn, plus the given ki >= 0 (0 for PD), then checked as
 * ctc_ctrl_pid does. A tau so small or large that kp or kv overflows or underflows is
 * rejected. */
ctc_status ctc_ctrl_zeta_tau(double zeta, double tau, double ki, ctc_gains *out, char *err,
                             size_t errlen);

/* Exact gains that place the closed-loop poles at mu_j = re[j] + i im[j] (j = 0..2):
 * (s - mu0)(s - mu1)(s - mu2) = s^3 + kv s^2 + kp s + ki. Each pole must be finite with
 * re < 0 (strictly in the left half plane) and complex poles must come in conjugate pairs
 * (a pole with im != 0 needs another with the same re and -im, to 1e-12 relative to its
 * modulus), e.g. "pole 2 (0.5) is not strictly in the left half plane", "pole 0 (-1+2i) has no
 * conjugate partner". Poles whose gains overflow, underflow or fail the Routh test in double
 * precision (a pair within rounding of the imaginary axis) are rejected too. */
ctc_status ctc_ctrl_poles(const double re[3], const double im[3], ctc_gains *out, char *err,
                          size_t errlen);

/* LQR gains minimising int(E^T Q E + lambda w^2) dt (Eq. 78-80): K = B^T P / lambda with P the
 * stabilising solution of A^T P + P A - P B B^T P / lambda + Q = 0, found from the ordered real
 * Schur form of the (scaled and balanced) Hamiltonian [[A, -B B^T / lambda], [-Q, -A^T]] (LAPACK
 * dgees) and polished by Newton-Kleinman steps, so that each gain is accurate relative to itself
 * over a wide range of lambda (tested from 1e-8 to 1e8). Q (3x3, row-major) must be finite,
 * symmetric (to 1e-12 relative to its largest entry) and positive semidefinite (to 1e-12
 * relative); lambda finite and > 0. Input for which no stabilising solution exists (a mode of A
 * on the imaginary axis that Q does not observe: Q[0][0] = 0 leaves the integral state
 * unpenalised) is rejected with a message saying so, as is input whose Hamiltonian has
 * eigenvalues within 1e-15 (relative) of the imaginary axis. *residual (may be NULL) receives
 * the relative Riccati residual
 *     ||R||_F / (||A^T P + P A||_F + ||P B B^T P||_F / lambda + ||Q||_F),
 *     R = A^T P + P A - P B B^T P / lambda + Q,
 * measured against the size of the equation's terms (for large lambda they dwarf Q and cancel);
 * it is checked to be <= 1e-10 and is NaN when the solve stopped before it. Note ki is always
 * sqrt(Q[0][0] / lambda). Example: Q = I, lambda = 0.01 gives K = (10, 18.2674, 11.6848). */
ctc_status ctc_ctrl_lqr(const double Q[9], double lambda, ctc_gains *out, double *residual,
                        char *err, size_t errlen);

/* The closed-loop poles of g: the three roots of s^3 + kv s^2 + kp s + ki (re[j] + i im[j]),
 * sorted by real part then imaginary part; a conjugate pair is exactly symmetric. For PD
 * (ki = 0) one pole is 0, the recorded integral state's. Each root has a backward error at
 * rounding level; well separated roots are accurate relative to their own size even when their
 * magnitudes differ by many decades. Gains with a non-finite member give NaN poles. */
void ctc_ctrl_closed_loop_poles(const ctc_gains *g, double re[3], double im[3]);

#endif
