/*
 * test_ctrl.c - controller design (src/control/ctrl_pid.c, ctrl_poles.c, ctrl_lqr.c) against the
 * paper's gains and against oracles that share no code with the library:
 *  - closed-loop poles: the eigenvalues of the companion matrix (LAPACK dgeev, a QR algorithm,
 *    where the library uses Newton's method and deflation), the backward error |p(root)|, and
 *    round trips through pole placement;
 *  - LQR: the closed-loop cost matrix P_K of the returned gains, from the Lyapunov equation
 *    (A - B K)^T P + P (A - B K) + Q + lambda K^T K = 0 solved here as a 9x9 Kronecker system;
 *    the optimum is the fixed point B^T P_K / lambda = K (policy improvement), P_K solves the
 *    Riccati equation, and every other stabilising gain has a larger cost (P_K' - P_K >= 0);
 *  - LQR: the return-difference identity. With (sI - A)^-1 B = (1/s^3, 1/s^2, 1/s)^T the optimal
 *    closed-loop polynomial p(s) = s^3 + kv s^2 + kp s + ki satisfies
 *        lambda p(s) p(-s) = -lambda s^6 + (1, -s, s^2) Q (1, s, s^2)^T,
 *    i.e. ki^2 = Q00 / lambda, kp^2 - 2 kv ki = (Q11 - 2 Q02) / lambda and
 *    kv^2 - 2 kp = Q22 / lambda, and p is the Hurwitz factor; for Q = diag(q, 0, 0) that is the
 *    Butterworth polynomial (s + w)(s^2 + w s + w^2), w = (q / lambda)^(1/6);
 *  - every rejection with its exact message.
 */
#include <criterion/criterion.h>
#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "ctrl.h"

#define ERRLEN 512

/* ---- helpers ---- */

static unsigned long long rng_state = 0x9E3779B97F4A7C15ULL;

/* uniform in [0, 1) (xorshift64*) */
static double uniform(void)
{
    rng_state ^= rng_state >> 12;
    rng_state ^= rng_state << 25;
    rng_state ^= rng_state >> 27;
    return (double)((rng_state * 2685821657736338717ULL) >> 11) * 0x1.0p-53;
}

static double uniform_in(double lo, double hi)
{
    return lo + (hi - lo) * uniform();
}

/* solves the n x n system M x = b (row-major, destroyed) by Gaussian elimination with partial
 * pivoting; the answer replaces b. Returns 0 if M is singular. */
static int gauss_solve(int n, double *m, double *b)
{
    for (int c = 0; c < n; c++) {
        int piv = c;
        for (int r = c + 1; r < n; r++) {
            if (fabs(m[r * n + c]) > fabs(m[piv * n + c])) piv = r;
        }
        if (m[piv * n + c] == 0.0) return 0;
        if (piv != c) {
            for (int j = 0; j < n; j++) {
                double t = m[c * n + j];
                m[c * n + j] = m[piv * n + j];
                m[piv * n + j] = t;
            }
            double t = b[c];
            b[c] = b[piv];
            b[piv] = t;
        }
        for (int r = c + 1; r < n; r++) {
            double f = m[r * n + c] / m[c * n + c];
            for (int j = c; j < n; j++) m[r * n + j] -= f * m[c * n + j];
            b[r] -= f * b[c];
        }
    }
    for (int r = n - 1; r >= 0; r--) {
        double s = b[r];
        for (int j = r + 1; j < n; j++) s -= m[r * n + j] * b[j];
        b[r] = s / m[r * n + r];
    }
    return 1;
}

/* closed-loop matrix A - B K of E = (int e, e, de/dt): the companion matrix of
 * s^3 + kv s^2 + kp s + ki */
static void closed_loop_matrix(const ctc_gains *g, double ac[9])
{
    const double a[9] = {0, 1, 0, 0, 0, 1, 0, 0, 0};
    for (int i = 0; i < 9; i++) ac[i] = a[i];
    ac[6] = -g->ki;
    ac[7] = -g->kp;
    ac[8] = -g->kv;
}

/* the cost matrix of the gains: (A - B K)^T P + P (A - B K) + Q + lambda K^T K = 0, solved as a
 * 9x9 linear system in the entries of P (column 3a+b of the operator is its image of E_ab) */
static void lyapunov_cost(const double q[9], double lambda, const ctc_gains *g, double p[9])
{
    double ac[9], op[81], rhs[9];
    const double k[3] = {g->ki, g->kp, g->kv};
    closed_loop_matrix(g, ac);
    for (int ab = 0; ab < 9; ab++) {
        int a = ab / 3, b = ab % 3;
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) {
                /* (Ac^T E_ab)[i][j] = Ac[a][i] [j == b]; (E_ab Ac)[i][j] = [i == a] Ac[b][j] */
                op[(3 * i + j) * 9 + ab] =
                    (j == b ? ac[3 * a + i] : 0) + (i == a ? ac[3 * b + j] : 0);
            }
        }
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) rhs[3 * i + j] = -(q[3 * i + j] + lambda * k[i] * k[j]);
    }
    cr_assert(gauss_solve(9, op, rhs), "the Lyapunov operator is singular");
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) p[3 * i + j] = 0.5 * (rhs[3 * i + j] + rhs[3 * j + i]);
    }
}

static double frobenius(const double *x, int n)
{
    double s = 0;
    for (int i = 0; i < n; i++) s += x[i] * x[i];
    return sqrt(s);
}

/* the Riccati residual R = A^T P + P A - P B B^T P / lambda + Q and the norms of its terms */
static void riccati_residual(const double q[9], double lambda, const double p[9], double *r_norm,
                             double *terms_norm)
{
    double lyap[9], quad[9], r[9];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            /* (A^T P)[i][j] = P[i-1][j], (P A)[i][j] = P[i][j-1] */
            lyap[3 * i + j] = (i > 0 ? p[3 * (i - 1) + j] : 0) + (j > 0 ? p[3 * i + j - 1] : 0);
            quad[3 * i + j] = p[3 * i + 2] * p[3 * j + 2] / lambda;
            r[3 * i + j] = lyap[3 * i + j] - quad[3 * i + j] + q[3 * i + j];
        }
    }
    *r_norm = frobenius(r, 9);
    *terms_norm = frobenius(lyap, 9) + frobenius(quad, 9) + frobenius(q, 9);
}

static int hurwitz(const ctc_gains *g)
{
    return g->ki > 0 && g->kp > 0 && g->kv > 0 && g->ki < g->kv * g->kp;
}

/* the return-difference identities (file comment) to a relative tol, and p Hurwitz */
static void expect_spectral_factor(const double q[9], double lambda, const ctc_gains *g, double tol,
                                   const char *what)
{
    double c0 = q[0] / lambda, c2 = (q[4] - 2 * q[2]) / lambda, c4 = q[8] / lambda;
    cr_assert(hurwitz(g), "%s: gains (%g, %g, %g) not Hurwitz", what, g->ki, g->kp, g->kv);
    cr_assert_leq(fabs(g->ki * g->ki - c0), tol * c0, "%s: ki^2 = %.17g, want %.17g", what,
                  g->ki * g->ki, c0);
    double s2 = g->kp * g->kp - 2 * g->kv * g->ki;
    double s2_size =
        g->kp * g->kp + 2 * g->kv * g->ki + fabs(q[4] / lambda) + fabs(2 * q[2] / lambda);
    cr_assert_leq(fabs(s2 - c2), tol * s2_size, "%s: kp^2 - 2 kv ki = %.17g, want %.17g", what, s2,
                  c2);
    double s4 = g->kv * g->kv - 2 * g->kp;
    double s4_size = g->kv * g->kv + 2 * g->kp + c4;
    cr_assert_leq(fabs(s4 - c4), tol * s4_size, "%s: kv^2 - 2 kp = %.17g, want %.17g", what, s4,
                  c4);
}

/* The LQR gains of (q, lambda); fails the test unless ctc_ctrl_lqr succeeds with a residual of
 * at most 1e-10 and the gains are the spectral factor to 1e-12 (expect_spectral_factor). what and
 * t name the case in the messages. */
static ctc_gains lqr_checked(const double q[9], double lambda, const char *what, int t)
{
    char err[ERRLEN] = "";
    ctc_gains g;
    double residual;
    cr_assert_eq(ctc_ctrl_lqr(q, lambda, &g, &residual, err, sizeof err), CTC_OK,
                 "%s %d (lambda %g): %s", what, t, lambda, err);
    cr_assert_leq(residual, 1e-10, "%s %d (lambda %g): residual %g", what, t, lambda, residual);
    expect_spectral_factor(q, lambda, &g, 1e-12, what);
    return g;
}

/* a random positive semidefinite Q = G G^T of the given rank with Q[0][0] > 0, its rows and
 * columns scaled by random powers of ten up to 10^spread */
static void random_psd(int rank, double spread, double q[9])
{
    double g[9] = {0}, d[3];
    for (int i = 0; i < 3; i++) {
        for (int k = 0; k < rank; k++) g[3 * i + k] = uniform_in(-1, 1);
        d[i] = pow(10.0, uniform_in(-spread, spread));
    }
    if (fabs(g[0]) < 0.1) g[0] = 0.5;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            double s = 0;
            for (int k = 0; k < 3; k++) s += g[3 * i + k] * g[3 * j + k];
            q[3 * i + j] = d[i] * d[j] * s;
        }
    }
    /* exactly symmetric */
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < i; j++) q[3 * i + j] = q[3 * j + i];
    }
}

/* the roots of s^3 + kv s^2 + kp s + ki as eigenvalues of the companion matrix (LAPACK dgeev) */
static void companion_roots(const ctc_gains *g, double re[3], double im[3])
{
    double ac[9], colmajor[9], work[64];
    closed_loop_matrix(g, ac);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) colmajor[i + 3 * j] = ac[3 * i + j];
    }
    lapack_int info = LAPACKE_dgeev_work(LAPACK_COL_MAJOR, 'N', 'N', 3, colmajor, 3, re, im, NULL,
                                         1, NULL, 1, work, 64);
    cr_assert_eq(info, 0, "dgeev info %d", (int)info);
}

/* every root in (re, im) lies within tol of a distinct root in (want_re, want_im) */
static void expect_same_roots(const double re[3], const double im[3], const double want_re[3],
                              const double want_im[3], double tol, const char *what)
{
    int used[3] = {0, 0, 0};
    for (int i = 0; i < 3; i++) {
        int best = -1;
        double best_d = INFINITY;
        for (int j = 0; j < 3; j++) {
            double d = hypot(re[i] - want_re[j], im[i] - want_im[j]);
            if (!used[j] && d < best_d) {
                best = j;
                best_d = d;
            }
        }
        cr_assert(best >= 0);
        used[best] = 1;
        cr_assert_leq(best_d, tol,
                      "%s: root %.17g%+.17gi is %g from the nearest wanted %.17g%+.17gi", what,
                      re[i], im[i], best_d, want_re[best], want_im[best]);
    }
}

/* |p(z)| over sum |c_k| |z|^k: the relative backward error of a root of the monic cubic */
static double backward_error(const ctc_gains *g, double re, double im)
{
    double zk_re = 1, zk_im = 0; /* z^k, starting at k = 0 */
    const double c[4] = {g->ki, g->kp, g->kv, 1};
    double pr = 0, pi = 0, size = 0;
    for (int k = 0; k < 4; k++) {
        pr += c[k] * zk_re;
        pi += c[k] * zk_im;
        size += fabs(c[k]) * hypot(zk_re, zk_im);
        double next_re = zk_re * re - zk_im * im, next_im = zk_re * im + zk_im * re;
        zk_re = next_re;
        zk_im = next_im;
    }
    return hypot(pr, pi) / size;
}

/* ---- PD and PID ---- */

Test(ctrl, pid_accepts_the_paper_gains)
{
    char err[ERRLEN] = "";
    ctc_gains g;
    cr_assert_eq(ctc_ctrl_pid(100, 20, 250, &g, err, sizeof err), CTC_OK, "%s", err);
    cr_assert(g.kp == 100 && g.kv == 20 && g.ki == 250);
    cr_assert_eq(ctc_ctrl_pid(100, 20, 0, &g, err, sizeof err), CTC_OK, "%s", err);
    cr_assert(g.kp == 100 && g.kv == 20 && g.ki == 0);
}

Test(ctrl, pid_routh_bound_matches_the_closed_loop_poles)
{
    /* below kv kp every pole is in the left half plane; at it a pair is on the imaginary axis
     * (s^3 + kv s^2 + kp s + kv kp = (s + kv)(s^2 + kp)); above it the pair crosses */
    char err[ERRLEN] = "";
    ctc_gains g;
    double re[3], im[3];
    cr_assert_eq(ctc_ctrl_pid(100, 2, 199.9, &g, err, sizeof err), CTC_OK, "%s", err);
    ctc_ctrl_closed_loop_poles(&g, re, im);
    for (int j = 0; j < 3; j++) cr_assert_lt(re[j], 0, "pole %d: %g%+gi", j, re[j], im[j]);

    ctc_gains boundary = {.ki = 200, .kp = 100, .kv = 2};
    ctc_ctrl_closed_loop_poles(&boundary, re, im);
    const double want_re[3] = {-2, 0, 0}, want_im[3] = {0, -10, 10};
    expect_same_roots(re, im, want_re, want_im, 1e-12 * 10, "ki = kv kp");

    ctc_gains above = {.ki = 200.1, .kp = 100, .kv = 2};
    ctc_ctrl_closed_loop_poles(&above, re, im);
    cr_assert_gt(re[2], 0, "ki > kv kp should have an unstable pole, got %g", re[2]);
}

Test(ctrl, pid_rejects_ki_at_or_above_kv_kp_with_exact_message)
{
    char err[ERRLEN] = "";
    ctc_gains g = {.ki = -7, .kp = -7, .kv = -7};
    cr_assert_eq(ctc_ctrl_pid(100, 2, 250, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "ki = 250 must be below kv*kp = 200 (Routh-Hurwitz: the closed-loop "
                          "error dynamics would be unstable)");
    cr_assert(g.ki == -7 && g.kp == -7 && g.kv == -7, "out must be untouched on failure");
    cr_assert_eq(ctc_ctrl_pid(100, 2, 200, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "ki = 200 must be below kv*kp = 200 (Routh-Hurwitz: the closed-loop "
                          "error dynamics would be unstable)");
}

Test(ctrl, pid_rejects_invalid_gains_with_exact_messages)
{
    char err[ERRLEN] = "";
    ctc_gains g;
    cr_assert_eq(ctc_ctrl_pid(-1, 20, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "kp must be positive and finite (got -1)");
    cr_assert_eq(ctc_ctrl_pid(NAN, 20, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "kp must be positive and finite (got nan)");
    cr_assert_eq(ctc_ctrl_pid(100, 0, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "kv must be positive and finite (got 0)");
    cr_assert_eq(ctc_ctrl_pid(100, INFINITY, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "kv must be positive and finite (got inf)");
    cr_assert_eq(ctc_ctrl_pid(100, 20, -1, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "ki must be non-negative and finite (got -1; 0 gives PD)");
    cr_assert_eq(ctc_ctrl_pid(100, 20, INFINITY, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "ki must be non-negative and finite (got inf; 0 gives PD)");
    /* a NULL buffer is allowed */
    cr_assert_eq(ctc_ctrl_pid(-1, 20, 0, &g, NULL, 0), CTC_EINVAL);
}

/* ---- zeta and tau ---- */

Test(ctrl, zeta_tau_gives_kp_one_over_tau_squared_and_kv_two_zeta_over_tau)
{
    char err[ERRLEN] = "";
    ctc_gains g;
    cr_assert_eq(ctc_ctrl_zeta_tau(0.7, 0.1, 0, &g, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_leq(fabs(g.kp - 100), 1e-12, "kp = %.17g", g.kp);
    cr_assert_leq(fabs(g.kv - 14), 1e-12, "kv = %.17g", g.kv);
    cr_assert_eq(g.ki, 0);

    /* the PD poles: 0 (integral state) and -zeta wn +- i wn sqrt(1 - zeta^2), wn = 1/tau */
    const double zeta = 0.3, tau = 0.25, wn = 1 / tau;
    cr_assert_eq(ctc_ctrl_zeta_tau(zeta, tau, 0, &g, err, sizeof err), CTC_OK, "%s", err);
    double re[3], im[3];
    ctc_ctrl_closed_loop_poles(&g, re, im);
    const double wd = wn * sqrt(1 - zeta * zeta);
    const double want_re[3] = {0, -zeta * wn, -zeta * wn}, want_im[3] = {0, -wd, wd};
    expect_same_roots(re, im, want_re, want_im, 1e-13 * wn, "zeta 0.3, tau 0.25");

    /* with an integral gain */
    cr_assert_eq(ctc_ctrl_zeta_tau(1.0, 0.05, 3000, &g, err, sizeof err), CTC_OK, "%s", err);
    cr_assert(fabs(g.kp - 400) <= 1e-12 && fabs(g.kv - 40) <= 1e-13 && g.ki == 3000);
}

Test(ctrl, zeta_tau_rejects_invalid_input_with_exact_messages)
{
    char err[ERRLEN] = "";
    ctc_gains g;
    cr_assert_eq(ctc_ctrl_zeta_tau(0, 0.1, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "zeta must be positive and finite (got 0)");
    cr_assert_eq(ctc_ctrl_zeta_tau(NAN, 0.1, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "zeta must be positive and finite (got nan)");
    cr_assert_eq(ctc_ctrl_zeta_tau(0.7, -1, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "tau must be positive and finite (got -1 s)");
    cr_assert_eq(ctc_ctrl_zeta_tau(0.7, 1e-200, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "tau = 1e-200 s is too small: kp = 1/tau^2 overflows");
    cr_assert_eq(ctc_ctrl_zeta_tau(0.7, 1e200, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "tau = 1e+200 s is too large: kp = 1/tau^2 underflows to zero");
    cr_assert_eq(ctc_ctrl_zeta_tau(1e300, 1e-10, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "zeta = 1e+300 and tau = 1e-10 s give kv = 2 zeta/tau = inf, which must "
                          "be positive and finite");
    cr_assert_eq(ctc_ctrl_zeta_tau(0x1p-1074, 10, 0, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "zeta = 4.94066e-324 and tau = 10 s give kv = 2 zeta/tau = 0, which must "
                          "be positive and finite");
    /* PD needs no Routh bound, even where kv kp = 2e-330 underflows */
    cr_assert_eq(ctc_ctrl_zeta_tau(1e-300, 1e10, 0, &g, err, sizeof err), CTC_OK, "%s", err);
    cr_assert(g.kv > 0 && g.kp > 0 && g.ki == 0);
    /* kv kp = 14 * 100 = 1400 */
    cr_assert_eq(ctc_ctrl_zeta_tau(0.7, 0.1, 1400, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "ki = 1400 must be below kv*kp = 1400 (Routh-Hurwitz: the closed-loop "
                          "error dynamics would be unstable)");
    cr_assert_eq(ctc_ctrl_zeta_tau(0.7, 0.1, -2, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "ki must be non-negative and finite (got -2; 0 gives PD)");
}

/* ---- pole placement ---- */

Test(ctrl, poles_give_the_paper_gains_and_come_back)
{
    char err[ERRLEN] = "";
    ctc_gains g;
    const double re[3] = {-2, -2.1, -2.2}, im[3] = {0, 0, 0};
    cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_leq(fabs(g.ki - 9.24), 1e-13, "ki = %.17g", g.ki);
    cr_assert_leq(fabs(g.kp - 13.22), 1e-13, "kp = %.17g", g.kp);
    cr_assert_leq(fabs(g.kv - 6.3), 1e-14, "kv = %.17g", g.kv);

    /* sorted by real part */
    double back_re[3], back_im[3];
    ctc_ctrl_closed_loop_poles(&g, back_re, back_im);
    const double want[3] = {-2.2, -2.1, -2};
    for (int j = 0; j < 3; j++) {
        cr_assert_leq(fabs(back_re[j] - want[j]), 1e-10, "pole %d: %.17g, want %g", j, back_re[j],
                      want[j]);
        cr_assert_eq(back_im[j], 0, "pole %d: im %g", j, back_im[j]);
    }
}

Test(ctrl, poles_place_a_complex_conjugate_pair)
{
    /* (s^2 + 2 s + 5)(s + 3) = s^3 + 5 s^2 + 11 s + 15 */
    char err[ERRLEN] = "";
    ctc_gains g;
    const double re[3] = {-1, -3, -1}, im[3] = {2, 0, -2};
    cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_OK, "%s", err);
    cr_assert(g.ki == 15 && g.kp == 11 && g.kv == 5, "gains (%.17g, %.17g, %.17g)", g.ki, g.kp,
              g.kv);

    double back_re[3], back_im[3];
    ctc_ctrl_closed_loop_poles(&g, back_re, back_im);
    const double want_re[3] = {-3, -1, -1}, want_im[3] = {0, -2, 2};
    for (int j = 0; j < 3; j++) {
        cr_assert_leq(hypot(back_re[j] - want_re[j], back_im[j] - want_im[j]), 1e-13,
                      "pole %d: %.17g%+.17gi", j, back_re[j], back_im[j]);
    }
    cr_assert_eq(back_re[1], back_re[2], "a conjugate pair must be exactly symmetric");
    cr_assert_eq(back_im[1], -back_im[2]);

    /* partners match to 1e-12 of the pole's modulus (sqrt(5)): 1e-13 passes, 1e-11 does not */
    const double near_re[3] = {-1, -3, -1 + 1e-13}, near_im[3] = {2, 0, -2};
    cr_assert_eq(ctc_ctrl_poles(near_re, near_im, &g, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_leq(fabs(g.ki - 15), 1e-11);
    const double far_re[3] = {-1, -3, -1}, far_im[3] = {2, 0, -2 - 1e-11};
    cr_assert_eq(ctc_ctrl_poles(far_re, far_im, &g, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "pole 0 (-1+2i) has no conjugate partner");
}

Test(ctrl, poles_round_trip_on_random_stable_sets)
{
    /* random real triples and pairs with a real pole, magnitudes within a factor 100 and
     * separated by at least 5% of the largest: each comes back to 1e-10 of the largest */
    char err[ERRLEN] = "";
    for (int t = 0; t < 500; t++) {
        double scale = pow(10, uniform_in(-3, 3));
        double re[3], im[3] = {0, 0, 0};
        int ok;
        do {
            if (t % 2 == 0) {
                for (int j = 0; j < 3; j++) re[j] = -scale * pow(10, uniform_in(0, 2));
            } else {
                re[0] = re[1] = -scale * pow(10, uniform_in(0, 2));
                im[0] = scale * pow(10, uniform_in(0, 2));
                im[1] = -im[0];
                re[2] = -scale * pow(10, uniform_in(0, 2));
            }
            double big = 0;
            for (int j = 0; j < 3; j++) big = fmax(big, hypot(re[j], im[j]));
            ok = 1;
            for (int i = 0; i < 3; i++) {
                for (int j = i + 1; j < 3; j++) {
                    if (hypot(re[i] - re[j], im[i] - im[j]) < 0.05 * big) ok = 0;
                }
            }
        } while (!ok);
        ctc_gains g;
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_OK, "%s", err);
        double big = 0;
        for (int j = 0; j < 3; j++) big = fmax(big, hypot(re[j], im[j]));
        double back_re[3], back_im[3];
        ctc_ctrl_closed_loop_poles(&g, back_re, back_im);
        expect_same_roots(back_re, back_im, re, im, 1e-10 * big, "random poles");
    }
}

Test(ctrl, poles_reject_invalid_poles_with_exact_messages)
{
    char err[ERRLEN] = "";
    ctc_gains g = {.ki = -7, .kp = -7, .kv = -7};
    {
        const double re[3] = {-1, -2, 0.5}, im[3] = {0, 0, 0};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "pole 2 (0.5) is not strictly in the left half plane");
    }
    {
        const double re[3] = {-1, 0, 0}, im[3] = {0, 2, -2};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "pole 1 (0+2i) is not strictly in the left half plane");
    }
    {
        const double re[3] = {-1, NAN, -2}, im[3] = {0, 0, 0};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "pole 1 (nan) is not finite");
    }
    {
        const double re[3] = {-1, -2, -3}, im[3] = {0, 0, INFINITY};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "pole 2 (-3+infi) is not finite");
    }
    {
        /* the second +2i cannot share the first's partner */
        const double re[3] = {-1, -1, -1}, im[3] = {2, -2, 2};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "pole 2 (-1+2i) has no conjugate partner");
    }
    {
        const double re[3] = {-1, -3, -1.5}, im[3] = {2, 0, -2};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "pole 0 (-1+2i) has no conjugate partner");
    }
    {
        const double re[3] = {-1e110, -1e110, -1e110}, im[3] = {0, 0, 0};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "the poles are too far from the origin: the gains (ki, kp, kv) = "
                              "(inf, 3e+220, 3e+110) overflow");
    }
    {
        const double re[3] = {-1e-110, -1e-110, -1e-110}, im[3] = {0, 0, 0};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "the poles are too close to the origin: the gains (ki, kp, kv) = "
                              "(0, 3e-220, 3e-110) underflow to zero");
    }
    {
        /* a pair 1e-17 from the axis: kv kp = ki once rounded */
        const double re[3] = {-1e-17, -1, -1e-17}, im[3] = {1, 0, -1};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "the gains (ki, kp, kv) = (1, 1, 1) fail the Routh-Hurwitz test in "
                              "double precision: the poles are too close to the imaginary axis");
    }
    cr_assert(g.ki == -7 && g.kp == -7 && g.kv == -7, "out must be untouched on failure");
}

/* ---- closed-loop poles ---- */

Test(ctrl, closed_loop_poles_match_companion_eigenvalues)
{
    /* random cubics (stable or not) against LAPACK's eigenvalues of the companion matrix, and
     * every root's backward error at rounding level */
    for (int t = 0; t < 2000; t++) {
        double s = pow(10, uniform_in(-4, 4));
        ctc_gains g = {.ki = s * s * s * uniform_in(-1, 1),
                       .kp = s * s * uniform_in(-1, 1),
                       .kv = s * uniform_in(-1, 1)};
        double re[3], im[3], want_re[3], want_im[3];
        ctc_ctrl_closed_loop_poles(&g, re, im);
        companion_roots(&g, want_re, want_im);
        for (int j = 0; j < 3; j++) {
            cr_assert_leq(backward_error(&g, re[j], im[j]), 1e-15,
                          "root %.17g%+.17gi of (%g, %g, %g): backward error %g", re[j], im[j],
                          g.ki, g.kp, g.kv, backward_error(&g, re[j], im[j]));
        }
        /* sorted, and pairs exactly conjugate */
        for (int j = 0; j < 2; j++) {
            cr_assert(re[j] < re[j + 1] || (re[j] == re[j + 1] && im[j] <= im[j + 1]),
                      "not sorted");
        }
        int complex_roots = 0;
        for (int j = 0; j < 3; j++) complex_roots += im[j] != 0;
        if (complex_roots) {
            cr_assert_eq(complex_roots, 2);
            int a = im[0] != 0 ? 0 : 1;
            cr_assert(re[a] == re[a + 1] && im[a] == -im[a + 1], "pair not exactly conjugate");
        }
        /* where the roots are separated by more than 1e-3 of the scale s they are well
         * conditioned, and agree with the eigenvalues to 1e-9 s */
        double d0 = hypot(re[0] - re[1], im[0] - im[1]), d1 = hypot(re[1] - re[2], im[1] - im[2]);
        double d2 = hypot(re[0] - re[2], im[0] - im[2]);
        double gap = fmin(d0, fmin(d1, d2));
        if (gap > 1e-3 * s) expect_same_roots(re, im, want_re, want_im, 1e-9 * s, "random cubic");
    }
}

Test(ctrl, closed_loop_poles_of_pd_include_zero)
{
    /* s (s^2 + kv s + kp): 0 exactly and the quadratic's roots */
    ctc_gains g = {.ki = 0, .kp = 100, .kv = 20};
    double re[3], im[3];
    ctc_ctrl_closed_loop_poles(&g, re, im);
    cr_assert(re[2] == 0 && im[2] == 0, "largest real part %g%+gi, want 0", re[2], im[2]);
    /* critically damped: the double root -10 to sqrt(eps) */
    cr_assert_leq(fabs(re[0] + 10), 1e-6);
    cr_assert_leq(fabs(re[1] + 10), 1e-6);

    ctc_gains under = {.ki = 0, .kp = 100, .kv = 12};
    ctc_ctrl_closed_loop_poles(&under, re, im);
    const double want_re[3] = {0, -6, -6}, want_im[3] = {0, -8, 8};
    expect_same_roots(re, im, want_re, want_im, 1e-13, "s (s^2 + 12 s + 100)");
}

Test(ctrl, closed_loop_poles_keep_relative_accuracy_over_wide_spreads)
{
    /* poles at -1e-6, -1 and -1e6 (and a pair 1e6 apart from the real pole): each to 1e-12
     * relative to itself */
    char err[ERRLEN] = "";
    ctc_gains g;
    {
        const double re[3] = {-1e-6, -1, -1e6}, im[3] = {0, 0, 0};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_OK, "%s", err);
        double back_re[3], back_im[3];
        ctc_ctrl_closed_loop_poles(&g, back_re, back_im);
        const double want[3] = {-1e6, -1, -1e-6};
        for (int j = 0; j < 3; j++) {
            cr_assert_leq(fabs(back_re[j] - want[j]), 1e-12 * fabs(want[j]), "pole %d: %.17g", j,
                          back_re[j]);
        }
    }
    {
        const double re[3] = {-3e-4, -2e3, -3e-4}, im[3] = {4e-4, 0, -4e-4};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_OK, "%s", err);
        double back_re[3], back_im[3];
        ctc_ctrl_closed_loop_poles(&g, back_re, back_im);
        const double want_re[3] = {-2e3, -3e-4, -3e-4}, want_im[3] = {0, -4e-4, 4e-4};
        for (int j = 0; j < 3; j++) {
            double mag = hypot(want_re[j], want_im[j]);
            cr_assert_leq(hypot(back_re[j] - want_re[j], back_im[j] - want_im[j]), 1e-12 * mag,
                          "pole %d: %.17g%+.17gi", j, back_re[j], back_im[j]);
        }
    }
    {
        /* huge and tiny scales stay finite */
        const double re[3] = {-1e100, -2e100, -3e100}, im[3] = {0, 0, 0};
        cr_assert_eq(ctc_ctrl_poles(re, im, &g, err, sizeof err), CTC_OK, "%s", err);
        double back_re[3], back_im[3];
        ctc_ctrl_closed_loop_poles(&g, back_re, back_im);
        for (int j = 0; j < 3; j++) {
            double want = -3e100 + 1e100 * j;
            cr_assert_leq(fabs(back_re[j] - want), 1e-10 * fabs(want), "pole %d: %.17g", j,
                          back_re[j]);
        }
    }
}

Test(ctrl, closed_loop_poles_of_a_triple_root)
{
    /* (s + 2)^3: a triple root is only determined to about eps^(1/3) */
    ctc_gains g = {.ki = 8, .kp = 12, .kv = 6};
    double re[3], im[3];
    ctc_ctrl_closed_loop_poles(&g, re, im);
    for (int j = 0; j < 3; j++) {
        cr_assert_leq(hypot(re[j] + 2, im[j]), 1e-4, "root %d: %.17g%+.17gi", j, re[j], im[j]);
        cr_assert_leq(backward_error(&g, re[j], im[j]), 1e-15);
    }
}

Test(ctrl, closed_loop_poles_of_non_finite_gains_are_nan)
{
    ctc_gains g = {.ki = 1, .kp = NAN, .kv = 1};
    double re[3], im[3];
    ctc_ctrl_closed_loop_poles(&g, re, im);
    for (int j = 0; j < 3; j++) cr_assert(isnan(re[j]) && isnan(im[j]));
}

/* ---- LQR ---- */

Test(ctrl, lqr_matches_paper_gains)
{
    char err[ERRLEN] = "";
    const double q[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    ctc_gains g;
    double residual = -1;
    cr_assert_eq(ctc_ctrl_lqr(q, 0.01, &g, &residual, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_leq(fabs(g.ki - 10), 1e-4, "ki = %.17g", g.ki);
    cr_assert_leq(fabs(g.kp - 18.2674), 1e-4, "kp = %.17g", g.kp);
    cr_assert_leq(fabs(g.kv - 11.6848), 1e-4, "kv = %.17g", g.kv);
    cr_assert_leq(residual, 1e-10, "reported residual %g", residual);
    cr_assert_geq(residual, 0);

    /* the cost matrix of these gains solves the Riccati equation, here also relative to
     * max(1, ||Q||_F), and is their own policy improvement */
    double p[9], r_norm, terms_norm;
    lyapunov_cost(q, 0.01, &g, p);
    riccati_residual(q, 0.01, p, &r_norm, &terms_norm);
    cr_assert_leq(r_norm / fmax(1, frobenius(q, 9)), 1e-10, "Riccati residual %g", r_norm);
    const double k[3] = {g.ki, g.kp, g.kv};
    for (int j = 0; j < 3; j++) {
        cr_assert_leq(fabs(p[6 + j] / 0.01 - k[j]), 1e-10 * k[j], "B^T P / lambda [%d] = %.17g", j,
                      p[6 + j] / 0.01);
    }
    expect_spectral_factor(q, 0.01, &g, 1e-14, "Q = I, lambda = 0.01");
}

Test(ctrl, lqr_with_only_the_integral_weight_is_butterworth)
{
    /* Q = diag(q, 0, 0): p(s) = (s + w)(s^2 + w s + w^2), K = (w^3, 2 w^2, 2 w) */
    char err[ERRLEN] = "";
    const double cases[][2] = {{64, 1}, {1, 1e-8}, {1, 1e8}, {3, 0.7}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const double q[9] = {cases[c][0], 0, 0, 0, 0, 0, 0, 0, 0};
        double lambda = cases[c][1], w = pow(cases[c][0] / lambda, 1.0 / 6);
        ctc_gains g;
        double residual;
        cr_assert_eq(ctc_ctrl_lqr(q, lambda, &g, &residual, err, sizeof err), CTC_OK, "%s", err);
        cr_assert_leq(fabs(g.ki - w * w * w), 1e-14 * w * w * w, "ki = %.17g", g.ki);
        cr_assert_leq(fabs(g.kp - 2 * w * w), 1e-14 * w * w, "kp = %.17g", g.kp);
        cr_assert_leq(fabs(g.kv - 2 * w), 1e-14 * w, "kv = %.17g", g.kv);
        cr_assert_leq(residual, 1e-10);
    }
}

Test(ctrl, lqr_gains_are_their_own_policy_improvement_on_random_psd_q)
{
    /* for random Q of rank 1..3 and lambda in [1e-3, 1e3]: B^T P_K / lambda = K, P_K solves the
     * Riccati equation, and the return-difference identities hold */
    for (int t = 0; t < 300; t++) {
        double q[9];
        random_psd(1 + t % 3, 1.0, q);
        double lambda = pow(10, uniform_in(-3, 3));
        ctc_gains g = lqr_checked(q, lambda, "random Q", t);

        double p[9], r_norm, terms_norm;
        lyapunov_cost(q, lambda, &g, p);
        riccati_residual(q, lambda, p, &r_norm, &terms_norm);
        cr_assert_leq(r_norm, 1e-9 * terms_norm, "case %d: Riccati residual %g of terms %g", t,
                      r_norm, terms_norm);
        const double k[3] = {g.ki, g.kp, g.kv};
        for (int j = 0; j < 3; j++) {
            cr_assert_leq(fabs(p[6 + j] / lambda - k[j]), 1e-8 * k[j],
                          "case %d: B^T P / lambda [%d] = %.17g, K = %.17g", t, j,
                          p[6 + j] / lambda, k[j]);
        }
    }
}

Test(ctrl, lqr_gains_cost_less_than_perturbed_stabilising_gains)
{
    /* the optimal cost matrix is the least: P_K' - P_K >= 0 for every stabilising K', checked
     * on random initial states for gains perturbed by up to 10% */
    char err[ERRLEN] = "";
    for (int t = 0; t < 40; t++) {
        double q[9];
        random_psd(1 + t % 3, 0.5, q);
        double lambda = pow(10, uniform_in(-2, 2));
        ctc_gains g;
        cr_assert_eq(ctc_ctrl_lqr(q, lambda, &g, NULL, err, sizeof err), CTC_OK, "%s", err);
        double p[9];
        lyapunov_cost(q, lambda, &g, p);
        for (int k = 0; k < 10; k++) {
            ctc_gains h = {.ki = g.ki * (1 + uniform_in(-0.1, 0.1)),
                           .kp = g.kp * (1 + uniform_in(-0.1, 0.1)),
                           .kv = g.kv * (1 + uniform_in(-0.1, 0.1))};
            if (!hurwitz(&h)) continue;
            double ph[9];
            lyapunov_cost(q, lambda, &h, ph);
            for (int x0 = 0; x0 < 5; x0++) {
                double e[3] = {uniform_in(-1, 1), uniform_in(-1, 1), uniform_in(-1, 1)};
                double jopt = 0, jh = 0;
                for (int i = 0; i < 3; i++) {
                    for (int j = 0; j < 3; j++) {
                        jopt += e[i] * p[3 * i + j] * e[j];
                        jh += e[i] * ph[3 * i + j] * e[j];
                    }
                }
                cr_assert_geq(jh, jopt * (1 - 1e-10),
                              "case %d: perturbed cost %.17g < optimal %.17g", t, jh, jopt);
            }
        }
    }
}

Test(ctrl, lqr_handles_lambda_from_1e_minus_8_to_1e8)
{
    /* Q = I and a fixed full Q over sixteen decades of lambda: ki = sqrt(Q00 / lambda) to
     * rounding, the return-difference identities to 1e-12, residual <= 1e-10, stable poles */
    const double identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    const double full[9] = {2, 0.5, -0.3, 0.5, 1, 0.2, -0.3, 0.2, 0.5};
    const double *qs[2] = {identity, full};
    for (int c = 0; c < 2; c++) {
        for (int e = -8; e <= 8; e++) {
            double lambda = pow(10, e);
            ctc_gains g = lqr_checked(qs[c], lambda, "lambda sweep, Q", c);
            double want_ki = sqrt(qs[c][0] / lambda);
            cr_assert_leq(fabs(g.ki - want_ki), 4e-16 * want_ki, "lambda 1e%d: ki = %.17g", e,
                          g.ki);
            double re[3], im[3];
            ctc_ctrl_closed_loop_poles(&g, re, im);
            cr_assert_lt(re[2], 0, "lambda 1e%d: pole %g%+gi", e, re[2], im[2]);
        }
    }
}

Test(ctrl, lqr_accepts_random_psd_q_over_wide_scales)
{
    /* Q of rank 1..3 with rows scaled over 10^+-3, lambda over 10^+-8: every solve succeeds,
     * with a small residual and gains that are the Hurwitz spectral factor */
    for (int t = 0; t < 1000; t++) {
        double q[9];
        random_psd(1 + t % 3, 3.0, q);
        double lambda = pow(10, uniform_in(-8, 8));
        lqr_checked(q, lambda, "wide random Q", t);
    }
}

Test(ctrl, lqr_symmetrises_q_within_tolerance)
{
    char err[ERRLEN] = "";
    const double q[9] = {1, 0.3, 0, 0.3 * (1 + 1e-14), 1, 0, 0, 0, 1};
    const double sym[9] = {1, 0.3 * (1 + 0.5e-14), 0, 0.3 * (1 + 0.5e-14), 1, 0, 0, 0, 1};
    ctc_gains g, h;
    cr_assert_eq(ctc_ctrl_lqr(q, 0.1, &g, NULL, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_eq(ctc_ctrl_lqr(sym, 0.1, &h, NULL, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_leq(fabs(g.kp - h.kp), 1e-14 * h.kp);
    cr_assert_leq(fabs(g.kv - h.kv), 1e-14 * h.kv);
}

Test(ctrl, lqr_rejects_invalid_input_with_exact_messages)
{
    char err[ERRLEN] = "";
    const double id[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    ctc_gains g = {.ki = -7, .kp = -7, .kv = -7};
    double residual = 0;

    cr_assert_eq(ctc_ctrl_lqr(id, 0, &g, &residual, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "lambda must be positive and finite (got 0)");
    cr_assert(isnan(residual), "residual must be NaN on failure, got %g", residual);
    cr_assert_eq(ctc_ctrl_lqr(id, -1, &g, NULL, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "lambda must be positive and finite (got -1)");
    cr_assert_eq(ctc_ctrl_lqr(id, NAN, &g, NULL, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "lambda must be positive and finite (got nan)");
    {
        const double q[9] = {1, 0, 0, 0, 1, INFINITY, 0, 0, 1};
        cr_assert_eq(ctc_ctrl_lqr(q, 1, &g, NULL, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "Q[1][2] is not finite (got inf)");
    }
    {
        const double q[9] = {1, 1, 0, 0, 1, 0, 0, 0, 1};
        cr_assert_eq(ctc_ctrl_lqr(q, 1, &g, NULL, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "Q is not symmetric (Q[0][1] = 1 but Q[1][0] = 0)");
    }
    {
        const double q[9] = {1, 0, 0, 0, -1, 0, 0, 0, 1};
        cr_assert_eq(ctc_ctrl_lqr(q, 1, &g, NULL, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "Q is not positive semidefinite (eigenvalue -1)");
    }
    {
        /* Q[0][0] = 0 with a nonzero Q[0][1] is indefinite */
        const double q[9] = {0, 1, 0, 1, 1, 0, 0, 0, 1};
        cr_assert_eq(ctc_ctrl_lqr(q, 1, &g, NULL, err, sizeof err), CTC_EINVAL);
        char want[ERRLEN];
        snprintf(want, sizeof want, "Q is not positive semidefinite (eigenvalue %g)",
                 (1 - sqrt(5)) / 2);
        cr_assert_str_eq(err, want);
    }
    {
        const double q[9] = {0, 0, 0, 0, 1, 0, 0, 0, 1};
        cr_assert_eq(ctc_ctrl_lqr(q, 0.01, &g, &residual, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "no stabilising Riccati solution: Q does not penalise the integral "
                              "state's mode at s = 0 (Q[0][0] = 0, so the Hamiltonian has "
                              "eigenvalues on the imaginary axis)");
        cr_assert(isnan(residual));
    }
    {
        /* the integral pole at about sqrt(1e-40) = 1e-20 next to poles of order 1 */
        const double q[9] = {1e-40, 0, 0, 0, 1, 0, 0, 0, 1};
        cr_assert_eq(ctc_ctrl_lqr(q, 1, &g, NULL, err, sizeof err), CTC_EINVAL);
        cr_assert_str_eq(err, "no stabilising Riccati solution in double precision: Q[0][0] = "
                              "1e-40 is too small next to the other weights and lambda = 1 (the "
                              "Hamiltonian has eigenvalues within 1e-15 of the imaginary axis, "
                              "relative to its largest)");
    }
    {
        /* ki = sqrt(1e300 / 4.9e-324) overflows (lambda is the smallest subnormal) */
        const double q[9] = {1e300, 0, 0, 0, 0, 0, 0, 0, 0};
        double lambda = 0x1p-1074;
        cr_assert_eq(ctc_ctrl_lqr(q, lambda, &g, NULL, err, sizeof err), CTC_EINVAL);
        double w = exp((log(1e300) - log(lambda)) / 6);
        char want[ERRLEN];
        snprintf(want, sizeof want,
                 "the LQR gains (ki, kp, kv) = (inf, %g, %g) are not representable in double "
                 "precision: Q / lambda is too large or too small",
                 2 * w * w, 2 * w);
        cr_assert_str_eq(err, want);
    }
    cr_assert(g.ki == -7 && g.kp == -7 && g.kv == -7, "out must be untouched on failure");
}

/* ---- the table of controller classes ---- */

Test(ctrl, every_class_in_the_table_has_a_unique_name_and_its_index)
{
    for (int t = 0; t < CTC_CTRL_NTYPES; t++) {
        const ctc_ctrl_class *c = ctc_ctrl_classes[t];
        cr_assert_not_null(c, "row %d", t);
        cr_assert_not_null(c->name, "row %d", t);
        cr_assert_gt(strlen(c->name), 0, "row %d", t);
        cr_expect_eq(ctc_ctrl_class_of((ctc_ctrl_type)t), c);
        cr_expect_eq(ctc_ctrl_type_of(c->name), t, "\"%s\"", c->name);
        for (int u = 0; u < t; u++)
            cr_expect_neq(strcmp(ctc_ctrl_classes[u]->name, c->name), 0, "rows %d and %d: \"%s\"",
                          u, t, c->name);
        /* a row's masks name only known parameters, and what it requires it accepts */
        cr_expect_eq(c->params & ~((1u << CTC_CP_COUNT) - 1u), 0u, "\"%s\"", c->name);
        cr_expect_eq(c->required & ~c->params, 0u, "\"%s\"", c->name);
        cr_expect(c->nstate == 0 || c->nstate == 1, "\"%s\": nstate %d", c->name, c->nstate);
        /* an active kind with a closed-loop hook designs its gains and keeps the integral */
        if (c->closed_loop) cr_expect(c->design && c->law && c->nstate == 1, "\"%s\"", c->name);
    }
    /* the names jobs use, in the enum's order */
    const char *names[] = {"none", "pd",       "pid",        "poles",
                           "lqr",  "joint_pd", "pd_gravity", "feedforward"};
    for (int t = 0; t < CTC_CTRL_NTYPES; t++) cr_expect_str_eq(ctc_ctrl_classes[t]->name, names[t]);
    cr_expect_null(ctc_ctrl_class_of((ctc_ctrl_type)CTC_CTRL_NTYPES));
    cr_expect_eq(ctc_ctrl_type_of("PD"), -1);
    cr_expect_eq(ctc_ctrl_type_of(NULL), -1);
    /* none is passive: no law, no gains, no state */
    const ctc_ctrl_class *none = ctc_ctrl_classes[CTC_CTRL_NONE];
    cr_expect(!none->law && !none->design && !none->closed_loop && none->nstate == 0);
}

Test(ctrl, parameter_names_are_the_job_keys_in_bit_order)
{
    const char *keys[CTC_CP_COUNT] = {"kp", "kv", "ki", "zeta", "tau", "poles", "Q", "lambda"};
    for (int i = 0; i < CTC_CP_COUNT; i++) cr_expect_str_eq(ctc_ctrl_param_name(1u << i), keys[i]);
    cr_expect_null(ctc_ctrl_param_name(0));
    cr_expect_null(ctc_ctrl_param_name(CTC_CP_KP | CTC_CP_KV));
    cr_expect_null(ctc_ctrl_param_name(1u << CTC_CP_COUNT));
}

/* the gains of the class of kind t from p, asserting success */
static ctc_gains class_design(ctc_ctrl_type t, const ctc_ctrl_params *p)
{
    char err[ERRLEN] = "";
    ctc_gains g = {-1, -1, -1};
    const ctc_ctrl_class *c = ctc_ctrl_class_of(t);
    cr_assert(c && c->design);
    cr_assert_eq(c->design(p, &g, err, sizeof err), CTC_OK, "%s: %s", c->name, err);
    return g;
}

Test(ctrl, each_class_designs_the_papers_gains)
{
    /* PD and PID (section 7.1): kp 100, kv 20, ki 250; or from zeta and tau (Eq. 92-94) */
    ctc_ctrl_params p = {
        .given = CTC_CP_KP | CTC_CP_KV | CTC_CP_KI, .kp = 100, .kv = 20, .ki = 250};
    ctc_gains g = class_design(CTC_CTRL_PD, &p);
    cr_expect(g.ki == 0 && g.kp == 100 && g.kv == 20, "pd (%g, %g, %g)", g.ki, g.kp, g.kv);
    g = class_design(CTC_CTRL_PID, &p);
    cr_expect(g.ki == 250 && g.kp == 100 && g.kv == 20, "pid (%g, %g, %g)", g.ki, g.kp, g.kv);
    p = (ctc_ctrl_params){.given = CTC_CP_ZETA | CTC_CP_TAU, .zeta = 1, .tau = 0.1};
    g = class_design(CTC_CTRL_PD, &p);
    cr_expect(fabs(g.kp - 100) <= 1e-12 && fabs(g.kv - 20) <= 1e-12, "(%g, %g)", g.kp, g.kv);

    /* poles (-2, -2.1, -2.2): K = (9.24, 13.22, 6.3) (section 7.1) */
    p = (ctc_ctrl_params){.given = CTC_CP_POLES, .re = {-2, -2.1, -2.2}};
    g = class_design(CTC_CTRL_POLES, &p);
    cr_expect_leq(fabs(g.ki - 9.24), 1e-12, "ki = %.17g", g.ki);
    cr_expect_leq(fabs(g.kp - 13.22), 1e-12, "kp = %.17g", g.kp);
    cr_expect_leq(fabs(g.kv - 6.3), 1e-12, "kv = %.17g", g.kv);

    /* LQR with Q = I, lambda = 0.01: K = (10, 18.2674, 11.6848) (Appendix B) */
    p = (ctc_ctrl_params){
        .given = CTC_CP_Q | CTC_CP_LAMBDA, .Q = {1, 0, 0, 0, 1, 0, 0, 0, 1}, .lambda = 0.01};
    g = class_design(CTC_CTRL_LQR, &p);
    cr_expect_leq(fabs(g.ki - 10), 1e-4, "ki = %.17g", g.ki);
    cr_expect_leq(fabs(g.kp - 18.2674), 1e-4, "kp = %.17g", g.kp);
    cr_expect_leq(fabs(g.kv - 11.6848), 1e-4, "kv = %.17g", g.kv);
}

Test(ctrl, a_class_design_rejects_bad_parameters_with_the_design_functions_message)
{
    char err[ERRLEN] = "";
    ctc_gains g = {7, 7, 7};
    ctc_ctrl_params p = {.given = CTC_CP_KP | CTC_CP_KV | CTC_CP_KI, .kp = 1, .kv = 2, .ki = 5};
    cr_assert_eq(ctc_ctrl_class_of(CTC_CTRL_PID)->design(&p, &g, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "ki = 5 must be below kv*kp = 2 (Routh-Hurwitz: the closed-loop error "
                          "dynamics would be unstable)");
    cr_expect(g.ki == 7 && g.kp == 7 && g.kv == 7, "gains written on failure");
}

Test(ctrl, the_linear_law_is_the_feedback_of_each_coordinates_gains)
{
    const ctc_gains g[2] = {{.ki = 3, .kp = 5, .kv = 7}, {.ki = 0, .kp = 11, .kv = 13}};
    const double des[6] = {1, 2, 99, -1, 0.5, 99}, qi[2] = {0.25, -2}, vi[2] = {4, 1};
    const double xi[2] = {0.125, 8};
    const ctc_ctrl_eval in = {.nind = 2, .qi = qi, .vi = vi, .des = des, .xi = xi, .gains = g};
    double w[2];
    ctc_ctrl_linear_law(&in, w);
    cr_expect_eq(w[0], 3 * 0.125 + 5 * (1 - 0.25) + 7 * (2 - 4.0));
    cr_expect_eq(w[1], 0 * 8 + 11 * (-1 + 2.0) + 13 * (0.5 - 1));
    double a[9];
    ctc_ctrl_linear_closed_loop(&g[0], a);
    const double ac[9] = {0, 1, 0, 0, 0, 1, -3, -5, -7};
    for (int i = 0; i < 9; i++) cr_expect_eq(a[i], ac[i], "Ac[%d]", i);
}
