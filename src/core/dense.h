/*
 * dense.h - small dense matrix kernels of runtime size (at most 6), for the GDCA tree passes.
 *
 * The GDCA passes are written once for both forms and instantiated with a constant dimension
 * (3 planar, 6 spatial) by wrappers marked CTC_SPECIALISE, which inline every kernel below so the
 * compiler sees constant loop bounds and unrolls them. Matrices are row-major; "sym" results
 * are computed in the upper triangle and mirrored, so they are exactly symmetric. Outputs never
 * alias inputs unless a function says so. Nothing here allocates.
 */
#ifndef CTC_DENSE_H
#define CTC_DENSE_H

#include <math.h>

#include "clones.h"

#define CTC_DENSE_MAX 6

/* y = A x, A (r x c) */
static inline void ctc_dense_mulv(int r, int c, const double *a, const double *x, double *y)
{
    for (int i = 0; i < r; i++) {
        double s = 0;
        for (int j = 0; j < c; j++) s += a[i * c + j] * x[j];
        y[i] = s;
    }
}

/* y = A^T x, A (r x c), y (c). Each y_j is summed in a register, column by column: summing
 * rows into y in memory costs a store and a reload per term when c is not a constant (and a
 * memset call to clear y), and gives the same sums in the same order. */
static inline void ctc_dense_tmulv(int r, int c, const double *a, const double *x, double *y)
{
    for (int j = 0; j < c; j++) {
        double s = 0;
        for (int i = 0; i < r; i++) s += a[i * c + j] * x[i];
        y[j] = s;
    }
}

/* In-place Cholesky factorisation A = L L^T of the symmetric positive definite A (n x n); the
 * lower triangle receives L (the upper is left as it was). Returns 0, or -1 if a pivot is not
 * positive (A not numerically positive definite). */
static inline int ctc_dense_cholesky(int n, double *a)
{
    for (int j = 0; j < n; j++) {
        double d = a[j * n + j];
        for (int k = 0; k < j; k++) d -= a[j * n + k] * a[j * n + k];
        if (!(d > 0)) return -1;
        d = sqrt(d);
        a[j * n + j] = d;
        for (int i = j + 1; i < n; i++) {
            double s = a[i * n + j];
            for (int k = 0; k < j; k++) s -= a[i * n + k] * a[j * n + k];
            a[i * n + j] = s / d;
        }
    }
    return 0;
}

/* Solves L y = b in place (b := L^-1 b), L lower triangular (n x n) from ctc_dense_cholesky. */
static inline void ctc_dense_lsolve(int n, const double *l, double *b)
{
    for (int i = 0; i < n; i++) {
        double s = b[i];
        for (int k = 0; k < i; k++) s -= l[i * n + k] * b[k];
        b[i] = s / l[i * n + i];
    }
}

/* Solves L^T x = y in place (y := L^-T y). */
static inline void ctc_dense_ltsolve(int n, const double *l, double *y)
{
    for (int i = n - 1; i >= 0; i--) {
        double s = y[i];
        for (int k = i + 1; k < n; k++) s -= l[k * n + i] * y[k];
        y[i] = s / l[i * n + i];
    }
}

#endif
