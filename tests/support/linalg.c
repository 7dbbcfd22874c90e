/*
 * linalg.c - condition-number estimate, SPD solve and relative error for tests (linalg.h).
 */
#include "linalg.h"

#include <math.h>
#include <stdlib.h>

double test_rel_err(const double *a, const double *b, int n)
{
    double e = 0, s = 0;
    for (int i = 0; i < n; i++) {
        e = fmax(e, fabs(a[i] - b[i]));
        s = fmax(s, fabs(b[i]));
    }
    return e / (s > 0 ? s : 1.0);
}

int test_solve_spd(const double *m, int n, const double *b, double *x)
{
    double *l = malloc(sizeof(double) * (size_t)n * (size_t)n);
    if (!l) return -1;
    /* M = L L^T, lower triangle of l */
    for (int j = 0; j < n; j++) {
        for (int i = j; i < n; i++) {
            double s = m[i * n + j];
            for (int k = 0; k < j; k++) s -= l[i * n + k] * l[j * n + k];
            if (i == j) {
                if (!(s > 0)) {
                    free(l);
                    return -1;
                }
                l[j * n + j] = sqrt(s);
            } else {
                l[i * n + j] = s / l[j * n + j];
            }
        }
    }
    /* forward then backward substitution */
    for (int i = 0; i < n; i++) {
        double s = b[i];
        for (int k = 0; k < i; k++) s -= l[i * n + k] * x[k];
        x[i] = s / l[i * n + i];
    }
    for (int i = n - 1; i >= 0; i--) {
        double s = x[i];
        for (int k = i + 1; k < n; k++) s -= l[k * n + i] * x[k];
        x[i] = s / l[i * n + i];
    }
    free(l);
    return 0;
}

static void normalise(double *x, int n, double *norm)
{
    double s = 0;
    for (int i = 0; i < n; i++) s += x[i] * x[i];
    s = sqrt(s);
    for (int i = 0; i < n; i++) x[i] /= s;
    *norm = s;
}

double test_cond_spd(const double *m, int n)
{
    double *l = malloc(sizeof(double) * (size_t)n * (size_t)n);
    double *x = malloc(sizeof(double) * (size_t)n), *y = malloc(sizeof(double) * (size_t)n);
    double cond = INFINITY, lmax = 0, inv_lmin = 0;
    if (l == NULL || x == NULL || y == NULL) goto done;

    /* Cholesky M = L L^T */
    for (int i = 0; i < n * n; i++) l[i] = m[i];
    for (int j = 0; j < n; j++) {
        double d = l[j * n + j];
        for (int k = 0; k < j; k++) d -= l[j * n + k] * l[j * n + k];
        if (!(d > 0)) goto done;
        d = sqrt(d);
        l[j * n + j] = d;
        for (int i = j + 1; i < n; i++) {
            double s = l[i * n + j];
            for (int k = 0; k < j; k++) s -= l[i * n + k] * l[j * n + k];
            l[i * n + j] = s / d;
        }
    }

    /* power iteration: largest eigenvalue */
    for (int i = 0; i < n; i++) x[i] = 1.0 + 0.1 * (i % 7);
    normalise(x, n, &lmax);
    for (int it = 0; it < 200; it++) {
        for (int i = 0; i < n; i++) {
            double s = 0;
            for (int j = 0; j < n; j++) s += m[i * n + j] * x[j];
            y[i] = s;
        }
        normalise(y, n, &lmax);
        double *t = x;
        x = y, y = t;
    }

    /* inverse iteration: largest eigenvalue of M^-1 */
    for (int i = 0; i < n; i++) x[i] = 1.0 + 0.1 * (i % 5);
    normalise(x, n, &inv_lmin);
    for (int it = 0; it < 200; it++) {
        for (int i = 0; i < n; i++) { /* L z = x */
            double s = x[i];
            for (int k = 0; k < i; k++) s -= l[i * n + k] * y[k];
            y[i] = s / l[i * n + i];
        }
        for (int i = n - 1; i >= 0; i--) { /* L^T y = z */
            double s = y[i];
            for (int k = i + 1; k < n; k++) s -= l[k * n + i] * y[k];
            y[i] = s / l[i * n + i];
        }
        normalise(y, n, &inv_lmin);
        double *t = x;
        x = y, y = t;
    }
    cond = lmax * inv_lmin;

done:
    free(l);
    free(x);
    free(y);
    return cond;
}

int test_all_finite(const double *x, int n)
{
    for (int i = 0; i < n; i++) {
        if (!isfinite(x[i])) return 0;
    }
    return 1;
}
