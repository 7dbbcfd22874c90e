/*
 * gdca_inverse_loop.c - a closed chain's CTC inverse dynamics from the open chain's composite
 * iGDCA and one dim x dim solve at the closing joint (gdca_inverse_loop.h).
 */
#include "gdca_inverse_loop.h"

#include <math.h>
#include <string.h>

#include "dense.h"
#include "gdca.h"
#include "gdca_loop.h"
#include "gdca_tree.h"
#include "loop.h"

/* B's column for dependent coordinate (k, c): J_k at p_t, or P_n's column for the closing joint */
static void dependent_column(const ctc_model *m, const ctc_data *d, int k, int c, double *col)
{
    if (k < m->nbodies) {
        ctc_loop_coord_twist(m, d, k, c, col);
    } else {
        memcpy(col, d->jnt_P + 3 * m->dim * k + c * m->dim, (size_t)m->dim * sizeof *col);
    }
}

/* LU factors of a (n x n, row-major) with partial pivoting, in place; -1 if a pivot vanishes */
static int lu_factor(int n, double *a, int *piv)
{
    double amax = 0;
    for (int i = 0; i < n * n; i++) amax = fmax(amax, fabs(a[i]));
    for (int k = 0; k < n; k++) {
        int p = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(a[i * n + k]) > fabs(a[p * n + k])) p = i;
        piv[k] = p;
        if (!(fabs(a[p * n + k]) > 1e-300 + 1e-15 * amax)) return -1;
        if (p != k) {
            for (int j = 0; j < n; j++) {
                double t = a[k * n + j];
                a[k * n + j] = a[p * n + j];
                a[p * n + j] = t;
            }
        }
        for (int i = k + 1; i < n; i++) {
            double l = a[i * n + k] /= a[k * n + k];
            for (int j = k + 1; j < n; j++) a[i * n + j] -= l * a[k * n + j];
        }
    }
    return 0;
}

/* solves A x = b (transpose = 0) or A^T x = b (transpose = 1) in place from lu_factor's output */
static void lu_solve(int n, const double *lu, const int *piv, int transpose, double *b)
{
    if (!transpose) {
        for (int k = 0; k < n; k++) {
            double t = b[k];
            b[k] = b[piv[k]];
            b[piv[k]] = t;
        }
        for (int i = 1; i < n; i++)
            for (int j = 0; j < i; j++) b[i] -= lu[i * n + j] * b[j];
        for (int i = n - 1; i >= 0; i--) {
            for (int j = i + 1; j < n; j++) b[i] -= lu[i * n + j] * b[j];
            b[i] /= lu[i * n + i];
        }
        return;
    }
    for (int i = 0; i < n; i++) { /* U^T y = b */
        for (int j = 0; j < i; j++) b[i] -= lu[j * n + i] * b[j];
        b[i] /= lu[i * n + i];
    }
    for (int i = n - 1; i >= 0; i--) /* L^T z = y */
        for (int j = i + 1; j < n; j++) b[i] -= lu[j * n + i] * b[j];
    for (int k = n - 1; k >= 0; k--) {
        double t = b[k];
        b[k] = b[piv[k]];
        b[piv[k]] = t;
    }
}

/* 1-norm condition estimate of s B s' (s, s' the equilibrating row and column scales), from its
 * LU factors and its 1-norm: the exact ||A^-1||_1 by n solves (n <= 6) */
static double lu_cond1(int n, const double *lu, const int *piv, double anorm)
{
    double inorm = 0;
    for (int j = 0; j < n; j++) {
        double e[CTC_DENSE_MAX] = {0}, s = 0;
        e[j] = 1;
        lu_solve(n, lu, piv, 0, e);
        for (int i = 0; i < n; i++) s += fabs(e[i]);
        inorm = fmax(inorm, s);
    }
    return anorm * inorm;
}

/* B (dim x dim; column j: dependent coordinate j, (dep_k[j], dep_c[j])) equilibrated by rows rs
 * then columns cs, and its LU factors with pivots piv; returns the 1-norm condition estimate of
 * the equilibrated B, or INFINITY when it is singular. Needs exactly dim dependent coordinates. */
static double dependent_factor(const ctc_model *m, const ctc_data *d, double *b, int *piv,
                               double *rs, double *cs, int *dep_k, int *dep_c)
{
    const int n = m->nbodies, dim = m->dim;
    int nd = 0;
    for (int k = 0; k <= n; k++) {
        for (int c = 0; !m->jnt_indep[k] && c < m->jnt_nv[k]; c++) {
            double col[CTC_DENSE_MAX];
            dependent_column(m, d, k, c, col);
            for (int r = 0; r < dim; r++) b[r * dim + nd] = col[r];
            dep_k[nd] = k, dep_c[nd] = c, nd++;
        }
    }
    for (int r = 0; r < dim; r++) {
        double s = 0;
        for (int j = 0; j < dim; j++) s = fmax(s, fabs(b[r * dim + j]));
        rs[r] = s > 0 ? 1.0 / s : 1.0;
        for (int j = 0; j < dim; j++) b[r * dim + j] *= rs[r];
    }
    double bnorm = 0;
    for (int j = 0; j < dim; j++) {
        double s = 0, sum = 0;
        for (int r = 0; r < dim; r++) s = fmax(s, fabs(b[r * dim + j]));
        cs[j] = s > 0 ? 1.0 / s : 1.0;
        for (int r = 0; r < dim; r++) sum += fabs(b[r * dim + j] *= cs[j]);
        bnorm = fmax(bnorm, sum);
    }
    if (lu_factor(dim, b, piv) != 0) return INFINITY;
    return lu_cond1(dim, b, piv, bnorm);
}

double gdca_loop_dependent_cond(const ctc_model *m, const ctc_data *d)
{
    double b[CTC_DENSE_MAX * CTC_DENSE_MAX], rs[CTC_DENSE_MAX], cs[CTC_DENSE_MAX];
    int piv[CTC_DENSE_MAX], dep_k[CTC_DENSE_MAX], dep_c[CTC_DENSE_MAX];
    if (m->nvx - m->nind != m->dim) return NAN;
    return dependent_factor(m, d, b, piv, rs, cs, dep_k, dep_c);
}

static void fail(const ctc_model *m, ctc_data *d, double *f)
{
    for (int i = 0; i < m->nvx; i++) f[i] = NAN;
    d->loop_cond = INFINITY;
    if (d->singular_joint < 0) d->singular_joint = m->nbodies;
}

void gdca_inverse_closing_accel(const ctc_model *m, const ctc_data *d, double *rel)
{
    const int dim = m->dim;
    double at[CTC_DENSE_MAX], ab[CTC_DENSE_MAX] = {0, 0, 0, 0, 0, 0};
    gdca_inverse_handle2_accel(m, d, m->nbodies - 1, at);
    if (m->loop_body >= 0) { /* the child's acceleration at p_t, from its handle 2's */
        double a1[CTC_DENSE_MAX];
        gdca_inverse_handle2_accel(m, d, m->loop_body_asm, a1);
        gdca_loop_shift_accel(dim, d->loop_r, d->loop_gam, a1, ab);
    }
    for (int r = 0; r < dim; r++) rel[r] = ab[r] - at[r];
}

void gdca_inverse_loop(const ctc_model *m, ctc_data *d, const double *u, double *f)
{
    const int n = m->nbodies, dim = m->dim, nv = m->nv;
    if (m->nvx - m->nind != dim) { /* not one dependent coordinate per constraint */
        ctc_gdca_inverse_mobility(m, d, u, f);
        return;
    }
    double *qdd = d->xbuf, *tau = d->xbuf + m->nvx;
    int dep_k[CTC_DENSE_MAX], dep_c[CTC_DENSE_MAX];
    double b[CTC_DENSE_MAX * CTC_DENSE_MAX], rs[CTC_DENSE_MAX], cs[CTC_DENSE_MAX];
    int piv[CTC_DENSE_MAX];
    d->singular_joint = -1;
    for (int k = 0; k <= n; k++) {
        for (int c = 0; c < m->jnt_nv[k]; c++) {
            const int i = m->jnt_vadr[k] + c;
            qdd[i] = m->jnt_indep[k] ? u[i] : 0.0;
        }
    }
    double cond = dependent_factor(m, d, b, piv, rs, cs, dep_k, dep_c);
    if (!isfinite(cond)) {
        fail(m, d, f);
        return;
    }
    d->loop_cond = cond;

    /* 1. the closure: B x = -(P_n qdd_n + beta_n - (A_child - A_t)) at u0; with B = R^-1 Bs C^-1,
       x = C y and Bs y = R rhs */
    double rel[CTC_DENSE_MAX], pu[CTC_DENSE_MAX], y[CTC_DENSE_MAX];
    gdca_inverse_composite(m, d, qdd, tau);
    gdca_inverse_closing_accel(m, d, rel);
    gdca_joint_map(dim, m->jnt_nv[n], d->jnt_P + 3 * dim * n, qdd + nv, pu);
    for (int r = 0; r < dim; r++) y[r] = -rs[r] * (pu[r] + d->jnt_beta[dim * n + r] - rel[r]);
    lu_solve(dim, b, piv, 0, y);
    for (int j = 0; j < dim; j++) qdd[m->jnt_vadr[dep_k[j]] + dep_c[j]] = cs[j] * y[j];

    /* 2. tau = M qdd + N of the open chain with every acceleration known */
    gdca_inverse_composite(m, d, qdd, tau);

    /* 3. B^T F = (-tau_k; 0): with B^T = C^-1 Bs^T R^-1, F = R z and Bs^T z = C rhs */
    double z[CTC_DENSE_MAX], load[CTC_DENSE_MAX];
    for (int j = 0; j < dim; j++) {
        z[j] = dep_k[j] < n ? -cs[j] * tau[m->jnt_vadr[dep_k[j]] + dep_c[j]] : 0.0;
    }
    lu_solve(dim, b, piv, 1, z);
    for (int r = 0; r < dim; r++) load[r] = rs[r] * z[r];

    /* the balance: F moved from p_t to joint k's centre, s_k = T(p_t - x_k)^T F, adds to the load
       of every joint of the loop, and J_k^T F = P_k^T s_k to an independent one's driving force:
       f_k = tau_k + P_k^T s_k in the loop, f_n = P_n^T F */
    memcpy(d->jnt_load_inv + dim * n, load, (size_t)dim * sizeof *load);
    for (int k = 0; k <= n; k++) {
        double s[CTC_DENSE_MAX] = {0, 0, 0, 0, 0, 0};
        if (k == n) {
            memcpy(s, load, (size_t)dim * sizeof *load);
        } else if (m->jnt_loop[k]) {
            double *lk = d->jnt_load_inv + dim * k, r[3];
            for (int a = 0; a < 3; a++) r[a] = d->loop_pt[a] - d->xpos[3 * k + a];
            ctc_transfer_force(dim, r, load, s);
            for (int a = 0; a < dim; a++) lk[a] += s[a];
        }
        const double *P = d->jnt_P + 3 * dim * k;
        for (int c = 0; c < m->jnt_nv[k]; c++) {
            const int i = m->jnt_vadr[k] + c;
            double fi = k < n ? tau[i] : 0.0;
            for (int a = 0; a < dim; a++) fi += P[c * dim + a] * s[a];
            f[i] = m->jnt_indep[k] ? fi : 0.0;
        }
    }
}
