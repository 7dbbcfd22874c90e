/*
 * gdca_loop.c - the closed chain's boundary equations (gdca_loop.h).
 */
#include "gdca_loop.h"

#include <math.h>

#include "dense.h"
#include "gdca_tree.h"

#define NB (2 * CTC_DENSE_MAX)

/* relative pivot below which the scaled system counts as singular */
#define BOUNDARY_PIVOT_MIN 1e-13

/* column c of S (identity when s is NULL) */
static inline double s_at(const gdca_end *e, int dim, int row, int c)
{
    return e->s ? e->s[c * dim + row] : (double)(row == c);
}

int gdca_loop_boundary(int dim, const double *h, const gdca_end *e1, const gdca_end *e2, double *f1,
                       double *f2, double *a1, double *a2, double *cond)
{
    const double *h11 = h + H11(dim), *h12 = h + H12(dim), *h22 = h + H22(dim);
    const double *h13 = h + H13(dim), *h23 = h + H23(dim);
    const int n1 = e1->ns, n2 = e2->ns, nb = n1 + n2;
    double hs[NB * 2 * CTC_DENSE_MAX]; /* per unknown: the accelerations (A1; A2) it causes */
    double b[NB * NB], r[NB], x[NB], scale[NB], t[CTC_DENSE_MAX];

    /* residual accelerations with x = 0: r1 = a1 - A1(Fo), r2 = a2 + A2(Fo) */
    double g1[CTC_DENSE_MAX], g2[CTC_DENSE_MAX], m2[CTC_DENSE_MAX];
    for (int i = 0; i < dim; i++) m2[i] = -e2->fo[i];
    ctc_dense_mulv(dim, dim, h11, e1->fo, g1);
    ctc_dense_mulv(dim, dim, h12, m2, t);
    for (int i = 0; i < dim; i++) g1[i] = e1->a[i] - (g1[i] + t[i] + h13[i]);
    ctc_dense_tmulv(dim, dim, h12, e1->fo, g2);
    ctc_dense_mulv(dim, dim, h22, m2, t);
    for (int i = 0; i < dim; i++) g2[i] = e2->a[i] + (g2[i] + t[i] + h23[i]);

    /* B = [S1^T h11 S1, -S1^T h12 S2; -S2^T h21 S1, S2^T h22 S2]: the accelerations of unit
       loads in the unknown directions, taken with the signs of F1 = S1 x1, F2 = -S2 x2 */
    for (int c = 0; c < nb; c++) {
        double col[CTC_DENSE_MAX], up[CTC_DENSE_MAX], lo[CTC_DENSE_MAX];
        const gdca_end *e = c < n1 ? e1 : e2;
        int cc = c < n1 ? c : c - n1;
        for (int i = 0; i < dim; i++) col[i] = s_at(e, dim, i, cc);
        if (c < n1) { /* F1 = col: A1 = h11 col, A2 = h21 col */
            ctc_dense_mulv(dim, dim, h11, col, up);
            ctc_dense_tmulv(dim, dim, h12, col, lo);
        } else { /* F2 = -col: A1 = -h12 col, A2 = -h22 col */
            ctc_dense_mulv(dim, dim, h12, col, up);
            ctc_dense_mulv(dim, dim, h22, col, lo);
            for (int i = 0; i < dim; i++) up[i] = -up[i], lo[i] = -lo[i];
        }
        for (int i = 0; i < dim; i++) {
            hs[c * 2 * dim + i] = up[i];
            hs[c * 2 * dim + dim + i] = lo[i];
        }
    }
    for (int a = 0; a < nb; a++) {
        /* row a: end 1 rows are S1^T A1, end 2 rows are -S2^T A2 (so that B is symmetric) */
        const gdca_end *e = a < n1 ? e1 : e2;
        int ca = a < n1 ? a : a - n1, off = a < n1 ? 0 : dim;
        double sg = a < n1 ? 1.0 : -1.0;
        for (int c = 0; c < nb; c++) {
            double s = 0;
            for (int i = 0; i < dim; i++) s += s_at(e, dim, i, ca) * hs[c * 2 * dim + off + i];
            b[a * nb + c] = sg * s;
        }
        double s = 0;
        const double *g = a < n1 ? g1 : g2;
        for (int i = 0; i < dim; i++) s += s_at(e, dim, i, ca) * g[i];
        if (a >= n1 && e2->off) s -= e2->off[ca];
        r[a] = s;
    }

    /* symmetric scaling, Cholesky, condition estimate from the pivots */
    int ok = 1;
    for (int a = 0; a < nb; a++) {
        double dgl = b[a * nb + a];
        if (!(dgl > 0)) ok = 0;
        scale[a] = dgl > 0 ? 1.0 / sqrt(dgl) : 1.0;
    }
    for (int a = 0; ok && a < nb; a++) {
        for (int c = 0; c < nb; c++) b[a * nb + c] *= scale[a] * scale[c];
        r[a] *= scale[a];
    }
    if (ok && ctc_dense_cholesky(nb, b) != 0) ok = 0;
    double pmin = INFINITY, pmax = 0;
    for (int a = 0; ok && a < nb; a++) {
        double p = b[a * nb + a];
        pmin = fmin(pmin, p);
        pmax = fmax(pmax, p);
    }
    if (ok && !(pmin > BOUNDARY_PIVOT_MIN * pmax)) ok = 0;
    if (!ok) {
        *cond = INFINITY;
        for (int i = 0; i < dim; i++) f1[i] = f2[i] = a1[i] = a2[i] = NAN;
        return -1;
    }
    *cond = nb ? (pmax / pmin) * (pmax / pmin) : 1.0;
    for (int a = 0; a < nb; a++) x[a] = r[a];
    ctc_dense_lsolve(nb, b, x);
    ctc_dense_ltsolve(nb, b, x);
    for (int a = 0; a < nb; a++) x[a] *= scale[a];

    /* the loads and the handles' accelerations */
    for (int i = 0; i < dim; i++) {
        double s1 = e1->fo[i], s2 = e2->fo[i];
        for (int c = 0; c < n1; c++) s1 += s_at(e1, dim, i, c) * x[c];
        for (int c = 0; c < n2; c++) s2 += s_at(e2, dim, i, c) * x[n1 + c];
        f1[i] = s1;
        f2[i] = -s2;
    }
    ctc_dense_mulv(dim, dim, h11, f1, a1);
    ctc_dense_mulv(dim, dim, h12, f2, t);
    for (int i = 0; i < dim; i++) a1[i] += t[i] + h13[i];
    ctc_dense_tmulv(dim, dim, h12, f1, a2);
    ctc_dense_mulv(dim, dim, h22, f2, t);
    for (int i = 0; i < dim; i++) a2[i] += t[i] + h23[i];
    return 0;
}
