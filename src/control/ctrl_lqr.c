/*
 * ctrl_lqr.c - LQR gains of one coordinate's error state (ctrl.h; paper section 6.3, Eq. 78-80).
 *
 * The state E = (int e, e, de/dt) is a chain of three integrators, A = [[0,1,0],[0,0,1],[0,0,0]],
 * B = (0,0,1)^T, and the cost int(E^T Q E + lambda w^2) dt is minimised by K = B^T P / lambda,
 * with P the stabilising solution of the algebraic Riccati equation
 *     A^T P + P A - P B B^T P / lambda + Q = 0.
 * The steps:
 *  1. Validation. Q must be finite, symmetric and positive semidefinite, lambda finite and
 *     positive. A's only eigenvalue is 0 with eigenvector (1,0,0), and (A, B) is controllable,
 *     so a stabilising solution exists exactly when Q (1,0,0)^T != 0, i.e. Q[0][0] > 0 for a
 *     PSD Q; Q[0][0] = 0 leaves the integral state's mode unobserved and puts a pair of
 *     Hamiltonian eigenvalues on the imaginary axis, and is rejected as such.
 *  2. Scaling. Time is scaled by alpha = 2^a and the state by D = diag(alpha^2, alpha, 1)
 *     (x = D E, tau = alpha t), which turns the problem into the same chain with lambda = 1 and
 *     Q~ = D^-1 Q D^-1 / (lambda alpha^2), i.e. Q~[i][j] = Q[i][j] / (lambda alpha^(6-i-j)).
 *     a is chosen so that the largest of Q~[0][0], Q~[1][1], Q~[2][2] lies in (2^-6, 1], which
 *     makes the fastest closed-loop pole of order 1; all scalings are powers of two (exact).
 *     Back in the original units K = (alpha^3 k~0, alpha^2 k~1, alpha k~2),
 *     P[i][j] = lambda alpha^(5-i-j) P~[i][j] and the Riccati residual is
 *     R[i][j] = lambda alpha^(6-i-j) R~[i][j].
 *  3. Schur method. The Hamiltonian H = [[A, -B B^T], [-Q~, -A^T]] (6x6) is balanced by a
 *     diagonal similarity T^-1 H T (LAPACK dgebal, powers of two), so that small eigenvalues are
 *     not lost in the rounding of large entries, then brought to real Schur form with its stable
 *     eigenvalues first (LAPACK dgees with a select function). Its eigenvalues are +- the
 *     closed-loop poles; any within AXIS_RTOL of the imaginary axis, relative to the largest,
 *     cannot be told apart from the axis in double precision, and the input is rejected. The
 *     first three Schur vectors [V1; V2] span the balanced stable invariant subspace; with
 *     X = V2 V1^-1 (V1 must be well conditioned), P~[i][j] = t[3+i] X[i][j] / t[j] undoes the
 *     balancing, and the scaled gains are the last row of the symmetrised P~.
 *  4. Newton-Kleinman polish. Each step solves the Lyapunov equation of the current closed loop
 *     Ac = A - B K: Ac^T P + P Ac + Q~ + K^T K = 0, and takes K = B^T P. For the integrator chain
 *     this Lyapunov equation is solvable by hand: writing P's last column as the new gain, the
 *     off-diagonal entries give P[0][0] = k0 k1 - Q01, P[0][1] = k0 k2 - Q02,
 *     P[1][1] = k1 k2 - k0 - Q12, and the diagonal entries are one Newton step on the three
 *     remaining Riccati equations
 *         F0 = k0^2 - Q00 = 0,  F1 = k1^2 - 2 k0 k2 - (Q11 - 2 Q02) = 0,  F2 = k2^2 - 2 k1 - Q22 =
 * 0 (the coefficients of the spectral factorisation p(s) p(-s) = -s^6 + Q22 s^4
 *     - (Q11 - 2 Q02) s^2 + Q00 of the closed-loop polynomial p). The Schur solution is accurate
 *     to rounding relative to the largest entry of P~; the polish makes each gain accurate
 *     relative to itself, which matters when the poles are spread over decades (small lambda
 *     makes ki tiny in the scaled units). Kleinman's iteration keeps the loop stable at every
 *     step; it stops when a step changes no gain by more than NEWTON_STEP_RTOL relative, or when
 *     steps below NEWTON_STALL_RTOL stop shrinking (rounding noise).
 *  5. Checks. The final gains must pass the Routh-Hurwitz test (ki, kp, kv > 0, ki < kv kp) and
 *     be finite and nonzero after unscaling, and the Riccati equation's relative residual for
 *     the P that they define (step 4's formulas), in the original units,
 *         ||R||_F / (||A^T P + P A||_F + ||P B B^T P||_F / lambda + ||Q||_F),
 *     must be at most RESIDUAL_MAX. The residual is measured against the size of the equation's
 *     terms, not of Q alone: for large lambda the terms are far larger than Q and cancel, and
 *     rounding P to double precision already leaves a residual of eps times their size.
 * Nothing is allocated: LAPACK's workspace lives on the stack (the _work entry points with
 * column-major storage, which LAPACKE does not copy).
 */
#include "ctrl.h"

#include <float.h>
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>

/* |Q[i][j] - Q[j][i]| allowed, relative to the largest |Q| entry */
#define SYMMETRY_RTOL 1e-12
/* negative eigenvalues of Q allowed, relative to the largest in magnitude */
#define PSD_RTOL 1e-12
/* Hamiltonian eigenvalues this close to the imaginary axis, relative to the largest, are taken to
 * be on it */
#define AXIS_RTOL 1e-15
/* reciprocal condition number (1-norm) below which V1 is taken to be singular */
#define V1_RCOND_MIN 1e-13
/* the largest accepted relative Riccati residual */
#define RESIDUAL_MAX 1e-10
/* the polish: at most this many steps; it ends when no gain changes by more than STEP_RTOL
 * relative, or after MAX_STALL steps below STALL_RTOL that do not shrink (rounding noise) */
#define NEWTON_MAX_STEPS 100
#define NEWTON_STEP_RTOL (4 * DBL_EPSILON)
#define NEWTON_STALL_RTOL 1e-8
#define NEWTON_MAX_STALL 3
/* LAPACK workspace (doubles), more than dgees, dsyev and dgecon need for n = 6 */
#define LWORK 256

/* select function for dgees: the stable (left half plane) eigenvalues come first */
static lapack_logical select_stable(const double *wr, const double *wi)
{
    (void)wi;
    return *wr < 0.0;
}

/* Frobenius norm of n numbers, safe against overflow */
static double frobenius(const double *x, int n)
{
    double m = 0;
    for (int i = 0; i < n; i++) m = fmax(m, fabs(x[i]));
    if (m == 0 || !isfinite(m)) return m;
    double s = 0;
    for (int i = 0; i < n; i++) s += (x[i] / m) * (x[i] / m);
    return m * sqrt(s);
}

/* whether the gains (k0, k1, k2) = (ki, kp, kv) make s^3 + k2 s^2 + k1 s + k0 Hurwitz */
static int routh_stable(const double k[3])
{
    return k[0] > 0 && k[1] > 0 && k[2] > 0 && k[0] < k[1] * k[2] && isfinite(k[1] * k[2]);
}

/* P (3x3, row-major, symmetric) of the scaled problem whose last row is the gain k: the entries
 * the off-diagonal Riccati equations fix (file comment, step 4) */
static void p_from_gains(const double q[9], const double k[3], double p[9])
{
    p[0] = k[0] * k[1] - q[1];
    p[1] = p[3] = k[0] * k[2] - q[2];
    p[2] = p[6] = k[0];
    p[4] = k[1] * k[2] - k[0] - q[5];
    p[5] = p[7] = k[1];
    p[8] = k[2];
}

/* the terms of the scaled Riccati equation (lambda = 1) for P, all 3x3 row-major:
 * lyap = A^T P + P A and quad = P B B^T P, so that the residual is lyap - quad + Q */
static void riccati_terms_scaled(const double p[9], double lyap[9], double quad[9])
{
    static const double a[9] = {0, 1, 0, 0, 0, 1, 0, 0, 0};
    static const double b[3] = {0, 0, 1};
    double pb[3];
    for (int i = 0; i < 3; i++) {
        pb[i] = 0;
        for (int k = 0; k < 3; k++) pb[i] += p[3 * i + k] * b[k];
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            double s = 0;
            for (int k = 0; k < 3; k++)
                s += a[3 * k + i] * p[3 * k + j] + p[3 * i + k] * a[3 * k + j];
            lyap[3 * i + j] = s;
            quad[3 * i + j] = pb[i] * pb[j];
        }
    }
}

/* the scaling of step 2: Q~[i][j] = Q[i][j] / (lambda 2^(a (6-i-j))), with lambda = mlam 2^elam */
typedef struct lqr_scaling {
    int a;
    int elam;
    double mlam;
} lqr_scaling;

/* a scaled Riccati term's entry [i][j] in the original units (times lambda alpha^(6-i-j)), up to
 * a factor common to all entries, which the relative residual cancels; it is chosen so that the
 * largest weight is 1 (only negligible entries can underflow, none can overflow) */
static double unscale_term(const lqr_scaling *sc, double x, int i, int j)
{
    return ldexp(x, sc->a * (4 - i - j) - 4 * abs(sc->a));
}

/* the relative residual of the Riccati equation for the P that the scaled gains k define
 * (p_from_gains), in the original units: ||R||_F / (||A^T P + P A||_F + ||P B B^T P||_F / lambda
 * + ||Q||_F) with R = A^T P + P A - P B B^T P / lambda + Q */
static double residual_of_gains(const lqr_scaling *sc, const double qt[9], const double k[3])
{
    double p[9], lyap[9], quad[9], r[9], q[9];
    p_from_gains(qt, k, p);
    riccati_terms_scaled(p, lyap, quad);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            int ij = 3 * i + j;
            r[ij] = unscale_term(sc, lyap[ij] - quad[ij] + qt[ij], i, j);
            lyap[ij] = unscale_term(sc, lyap[ij], i, j);
            quad[ij] = unscale_term(sc, quad[ij], i, j);
            q[ij] = unscale_term(sc, qt[ij], i, j);
        }
    }
    double scale = frobenius(lyap, 9) + frobenius(quad, 9) + frobenius(q, 9);
    double res = frobenius(r, 9) / scale;
    return isnan(res) ? INFINITY : res;
}

/* one Newton-Kleinman step (file comment, step 4): J dk = -F, with
 * J = [[2 k0, 0, 0], [-2 k2, 2 k1, -2 k0], [0, -2, 2 k2]], solved by elimination; the pivot
 * k1 k2 - k0 is positive for stabilising gains */
static void newton_kleinman_step(const double qt[9], const double k[3], double next[3])
{
    double f0 = k[0] * k[0] - qt[0];
    double f1 = k[1] * k[1] - 2.0 * k[0] * k[2] - (qt[4] - 2.0 * qt[2]);
    double f2 = k[2] * k[2] - 2.0 * k[1] - qt[8];
    double d0 = -f0 / (2.0 * k[0]);
    double d2 = (-f1 + 2.0 * k[2] * d0 - k[1] * f2) / (2.0 * (k[1] * k[2] - k[0]));
    double d1 = k[2] * d2 + 0.5 * f2;
    next[0] = k[0] + d0;
    next[1] = k[1] + d1;
    next[2] = k[2] + d2;
}

/* checks lambda and Q (step 1) and writes the symmetrised Q into qs */
static ctc_status validate(const double q[9], double lambda, double qs[9], char *err, size_t errlen)
{
    if (!isfinite(lambda) || !(lambda > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "lambda must be positive and finite (got %g)",
                        lambda);
    }
    double qmax = 0;
    for (int i = 0; i < 9; i++) {
        if (!isfinite(q[i])) {
            return ctc_fail(CTC_EINVAL, err, errlen, "Q[%d][%d] is not finite (got %g)", i / 3,
                            i % 3, q[i]);
        }
        qmax = fmax(qmax, fabs(q[i]));
    }
    for (int i = 0; i < 3; i++) {
        for (int j = i + 1; j < 3; j++) {
            double qij = q[3 * i + j], qji = q[3 * j + i];
            if (fabs(qij - qji) > SYMMETRY_RTOL * qmax) {
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "Q is not symmetric (Q[%d][%d] = %g but Q[%d][%d] = %g)", i, j, qij,
                                j, i, qji);
            }
        }
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) qs[3 * i + j] = 0.5 * (q[3 * i + j] + q[3 * j + i]);
    }

    /* positive semidefinite: the smallest eigenvalue of the symmetric part */
    double eig_in[9], w[3], work[LWORK];
    for (int i = 0; i < 9; i++) eig_in[i] = qs[i];
    lapack_int info = LAPACKE_dsyev_work(LAPACK_COL_MAJOR, 'N', 'U', 3, eig_in, 3, w, work, LWORK);
    if (info != 0) {
        return ctc_fail(CTC_ESINGULAR, err, errlen,
                        "the eigenvalues of Q did not converge (LAPACK dsyev info %d)", (int)info);
    }
    double wmax = fmax(fabs(w[0]), fabs(w[2]));
    if (w[0] < -PSD_RTOL * wmax) {
        return ctc_fail(CTC_EINVAL, err, errlen, "Q is not positive semidefinite (eigenvalue %g)",
                        w[0]);
    }

    /* a stabilising solution needs Q to observe the integral state */
    if (!(qs[0] > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "no stabilising Riccati solution: Q does not penalise the integral "
                        "state's mode at s = 0 (Q[0][0] = %g, so the Hamiltonian has eigenvalues "
                        "on the imaginary axis)",
                        qs[0]);
    }
    return CTC_OK;
}

/* the scaling of step 2 from the diagonal of Q / lambda */
static void choose_scaling(const double qs[9], double lambda, lqr_scaling *sc)
{
    double e = -INFINITY;
    for (int i = 0; i < 3; i++) {
        double qii = qs[4 * i];
        if (qii > 0) e = fmax(e, (log2(qii) - log2(lambda)) / (6 - 2 * i));
    }
    sc->a = (int)ceil(e); /* finite: qs[0] > 0 */
    sc->mlam = frexp(lambda, &sc->elam);
}

/* the stabilising P~ of the scaled problem by the ordered Schur method (step 3); returns its
 * last row, the scaled gains, in k */
static ctc_status schur_gains(const double qt[9], const double q[9], double lambda, double k[3],
                              char *err, size_t errlen)
{
    /* H = [[A, -B B^T], [-Q~, -A^T]], column-major */
    double h[36] = {0};
    h[0 + 6 * 1] = 1.0;  /* A[0][1] */
    h[1 + 6 * 2] = 1.0;  /* A[1][2] */
    h[2 + 6 * 5] = -1.0; /* -B B^T [2][2] */
    h[4 + 6 * 3] = -1.0; /* -A^T[1][0] */
    h[5 + 6 * 4] = -1.0; /* -A^T[2][1] */
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) h[(3 + i) + 6 * j] = -qt[3 * i + j];
    }

    /* balance: Hb = T^-1 H T with a diagonal T of powers of two (rows and columns of similar
     * norm), so that small eigenvalues are not swamped by rounding of large entries */
    double t[6];
    lapack_int ilo, ihi;
    lapack_int info = LAPACKE_dgebal_work(LAPACK_COL_MAJOR, 'S', 6, h, 6, &ilo, &ihi, t);
    if (info != 0) {
        return ctc_fail(CTC_ESINGULAR, err, errlen,
                        "balancing the Hamiltonian failed (LAPACK dgebal info %d)", (int)info);
    }

    /* real Schur form with the stable eigenvalues first */
    double wr[6], wi[6], z[36], work[LWORK];
    lapack_logical bwork[6];
    lapack_int sdim = 0;
    info = LAPACKE_dgees_work(LAPACK_COL_MAJOR, 'V', 'S', select_stable, 6, h, 6, &sdim, wr, wi, z,
                              6, work, LWORK, bwork);
    if (info < 0 || (info > 0 && info <= 6)) {
        return ctc_fail(CTC_ESINGULAR, err, errlen,
                        "the Schur decomposition of the Hamiltonian did not converge (LAPACK "
                        "dgees info %d)",
                        (int)info);
    }

    /* no eigenvalue may sit on (or within rounding of) the imaginary axis */
    double rho = 0, re_min = INFINITY;
    for (int j = 0; j < 6; j++) {
        rho = fmax(rho, hypot(wr[j], wi[j]));
        re_min = fmin(re_min, fabs(wr[j]));
    }
    if (!(re_min > AXIS_RTOL * rho) || sdim != 3) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "no stabilising Riccati solution in double precision: Q[0][0] = %g is "
                        "too small next to the other weights and lambda = %g (the Hamiltonian "
                        "has eigenvalues within %g of the imaginary axis, relative to its "
                        "largest)",
                        q[0], lambda, AXIS_RTOL);
    }
    if (info != 0) {
        return ctc_fail(CTC_ESINGULAR, err, errlen,
                        "the Hamiltonian's stable eigenvalues could not be ordered first (LAPACK "
                        "dgees info %d)",
                        (int)info);
    }

    /* X = V2 V1^-1 from the balanced stable Schur vectors [V1; V2]: solve V1^T Y = V2^T, Y = X^T */
    double v1[9], x[9], cwork[12], anorm = 0, rcond = 0;
    lapack_int ipiv[3], iwork[3];
    for (int j = 0; j < 3; j++) {
        double colsum = 0;
        for (int i = 0; i < 3; i++) {
            v1[i + 3 * j] = z[i + 6 * j];
            x[i + 3 * j] = z[(3 + j) + 6 * i];
            colsum += fabs(v1[i + 3 * j]);
        }
        anorm = fmax(anorm, colsum);
    }
    info = LAPACKE_dgetrf_work(LAPACK_COL_MAJOR, 3, 3, v1, 3, ipiv);
    if (info == 0) {
        info = LAPACKE_dgecon_work(LAPACK_COL_MAJOR, '1', 3, v1, 3, anorm, &rcond, cwork, iwork);
    }
    if (info != 0 || !(rcond >= V1_RCOND_MIN)) {
        return ctc_fail(CTC_ESINGULAR, err, errlen,
                        "no stabilising Riccati solution: U1 of the stable invariant subspace "
                        "[U1; U2] is singular (reciprocal condition %g)",
                        info != 0 ? 0.0 : rcond);
    }
    LAPACKE_dgetrs_work(LAPACK_COL_MAJOR, 'T', 3, 3, v1, 3, ipiv, x, 3);

    /* undo the balancing, P~[i][j] = t[3+i] X[i][j] / t[j] (x[i + 3 j] = Y[i][j] = X[j][i]), take
     * K~ = B^T P~: the last row of the symmetrised P~ */
    for (int j = 0; j < 3; j++) {
        double p2j = t[3 + 2] * x[j + 3 * 2] / t[j], pj2 = t[3 + j] * x[2 + 3 * j] / t[2];
        k[j] = 0.5 * (p2j + pj2);
    }
    return CTC_OK;
}

ctc_status ctc_ctrl_lqr(const double Q[9], double lambda, ctc_gains *out, double *residual,
                        char *err, size_t errlen)
{
    if (residual != NULL) *residual = NAN;
    double qs[9];
    ctc_status st = validate(Q, lambda, qs, err, errlen);
    if (st != CTC_OK) return st;

    /* scaled weights Q~ */
    lqr_scaling sc;
    choose_scaling(qs, lambda, &sc);
    double qt[9];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            qt[3 * i + j] = ldexp(qs[3 * i + j], -sc.elam - sc.a * (6 - i - j)) / sc.mlam;
        }
    }

    double k[3];
    st = schur_gains(qt, Q, lambda, k, err, errlen);
    if (st != CTC_OK) return st;
    if (!routh_stable(k)) {
        return ctc_fail(CTC_ESINGULAR, err, errlen,
                        "the Schur solution's scaled gains (%g, %g, %g) do not stabilise the loop",
                        k[0], k[1], k[2]);
    }

    /* Newton-Kleinman polish until the steps are at rounding level: each step keeps the loop
     * stable (Kleinman), and near the solution it converges quadratically */
    double step_prev = INFINITY;
    int stall = 0;
    for (int step = 0; step < NEWTON_MAX_STEPS && stall < NEWTON_MAX_STALL; step++) {
        double next[3], rel_step = 0;
        newton_kleinman_step(qt, k, next);
        if (!routh_stable(next)) break;
        for (int j = 0; j < 3; j++) {
            rel_step = fmax(rel_step, fabs(next[j] - k[j]) / fabs(next[j]));
            k[j] = next[j];
        }
        if (rel_step <= NEWTON_STEP_RTOL) break;
        if (rel_step < NEWTON_STALL_RTOL && rel_step >= step_prev) stall++;
        step_prev = rel_step;
    }
    double res = residual_of_gains(&sc, qt, k);

    /* back to the original units */
    double ki = ldexp(k[0], 3 * sc.a), kp = ldexp(k[1], 2 * sc.a), kv = ldexp(k[2], sc.a);
    if (!isfinite(ki) || !isfinite(kp) || !isfinite(kv) || !(ki > 0) || !(kp > 0) || !(kv > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "the LQR gains (ki, kp, kv) = (%g, %g, %g) are not representable in "
                        "double precision: Q / lambda is too large or too small",
                        ki, kp, kv);
    }
    if (residual != NULL) *residual = res;
    if (!(res <= RESIDUAL_MAX)) {
        return ctc_fail(CTC_ESINGULAR, err, errlen,
                        "the Riccati residual %g exceeds %g: the problem is too ill-conditioned",
                        res, RESIDUAL_MAX);
    }
    out->ki = ki;
    out->kp = kp;
    out->kv = kv;
    return CTC_OK;
}

/* ---- the lqr class (ctrl.h) ---- */

static ctc_status design_lqr(const ctc_ctrl_params *p, ctc_gains *out, char *err, size_t errlen)
{
    return ctc_ctrl_lqr(p->Q, p->lambda, out, NULL, err, errlen);
}

const ctc_ctrl_class ctc_ctrl_class_lqr = {
    .name = "lqr",
    .params = CTC_CP_Q | CTC_CP_LAMBDA,
    .required = CTC_CP_Q | CTC_CP_LAMBDA,
    .nstate = 1,
    .design = design_lqr,
    .law = ctc_ctrl_linear_law,
    .closed_loop = ctc_ctrl_linear_closed_loop,
};
