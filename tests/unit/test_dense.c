/*
 * test_dense.c - the small dense kernels of src/core/dense.h and the assembly's downdate
 * (gdca_tree.h) against plain products written here, and the Cholesky solve against the systems it
 * was made from.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "chains.h"
#include "dense.h"
#include "gdca_tree.h"

#define N CTC_DENSE_MAX

static void random_matrix(uint64_t *rng, int r, int c, double *a)
{
    for (int i = 0; i < r * c; i++) a[i] = test_uniform(rng, -1, 1);
}

/* C = A B (plain), A (n x n) */
static void plain_mul(int n, const double *a, const double *b, double *c)
{
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) {
            double s = 0;
            for (int k = 0; k < n; k++) s += a[i * n + k] * b[k * n + j];
            c[i * n + j] = s;
        }
    }
}

static void transpose(int n, const double *a, double *t)
{
    for (int i = 0; i < n; i++) {
        for (int j = 0; j < n; j++) t[j * n + i] = a[i * n + j];
    }
}

static double max_abs_diff(int n, const double *a, const double *b)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(a[i] - b[i]));
    return s;
}

static double max_abs(int n, const double *a)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(a[i]));
    return s;
}

/* random SPD A = B B^T + c 1, c in [0.01, 1] (condition number up to a few hundred) */
static void random_spd(uint64_t *rng, int n, double *a)
{
    double b[N * N], bt[N * N];
    random_matrix(rng, n, n, b);
    transpose(n, b, bt);
    plain_mul(n, b, bt, a);
    double c = test_uniform(rng, 0.01, 1.0);
    for (int i = 0; i < n; i++) a[i * n + i] += c;
}

Test(dense, cholesky_solves_random_spd_systems)
{
    /* A x = b through L L^T: x to 1e-12 relative; L L^T reproduces A to 1e-14; the upper
       triangle is left as it was */
    uint64_t rng = 1;
    double worst = 0;
    for (int n = 1; n <= N; n++) {
        for (int t = 0; t < 200; t++) {
            double a[N * N], l[N * N], x[N], b[N];
            random_spd(&rng, n, a);
            random_matrix(&rng, n, 1, x);
            for (int i = 0; i < n; i++) {
                b[i] = 0;
                for (int j = 0; j < n; j++) b[i] += a[i * n + j] * x[j];
            }
            memcpy(l, a, sizeof(double) * (size_t)(n * n));
            cr_assert_eq(ctc_dense_cholesky(n, l), 0, "n = %d, trial %d: not factored", n, t);
            for (int i = 0; i < n; i++) {
                for (int j = i + 1; j < n; j++) {
                    cr_assert_eq(l[i * n + j], a[i * n + j], "upper triangle changed");
                }
            }
            for (int i = 0; i < n; i++) {
                for (int j = 0; j <= i; j++) {
                    double s = 0;
                    for (int k = 0; k <= j; k++) s += l[i * n + k] * l[j * n + k];
                    cr_assert_leq(fabs(s - a[i * n + j]), 1e-14 * max_abs(n * n, a),
                                  "n = %d: (L L^T)[%d][%d] = %.17g, A = %.17g", n, i, j, s,
                                  a[i * n + j]);
                }
            }
            ctc_dense_lsolve(n, l, b);
            ctc_dense_ltsolve(n, l, b);
            double e = max_abs_diff(n, b, x) / max_abs(n, x);
            worst = fmax(worst, e);
            cr_assert_leq(e, 1e-12, "n = %d, trial %d: solution error %.3e", n, t, e);
        }
    }
    cr_log_info("cholesky solves: worst relative error %.2e (tolerance 1e-12)", worst);
}

Test(dense, lsolve_and_ltsolve_invert_l_and_its_transpose)
{
    /* L y = b and L^T z = b checked by multiplying back */
    uint64_t rng = 2;
    for (int n = 1; n <= N; n++) {
        double a[N * N], b[N], y[N], z[N];
        random_spd(&rng, n, a);
        cr_assert_eq(ctc_dense_cholesky(n, a), 0);
        random_matrix(&rng, n, 1, b);
        memcpy(y, b, sizeof y);
        memcpy(z, b, sizeof z);
        ctc_dense_lsolve(n, a, y);
        ctc_dense_ltsolve(n, a, z);
        for (int i = 0; i < n; i++) {
            double ly = 0, ltz = 0;
            for (int k = 0; k <= i; k++) ly += a[i * n + k] * y[k];
            for (int k = i; k < n; k++) ltz += a[k * n + i] * z[k];
            cr_assert_leq(fabs(ly - b[i]), 1e-12, "n = %d: (L y)[%d] = %.17g, b = %.17g", n, i, ly,
                          b[i]);
            cr_assert_leq(fabs(ltz - b[i]), 1e-12, "n = %d: (L^T z)[%d] = %.17g, b = %.17g", n, i,
                          ltz, b[i]);
        }
    }
}

Test(dense, cholesky_rejects_indefinite_and_singular_matrices)
{
    /* exact cases (every pivot computed without rounding) */
    const double indef2[4] = {1, 0, 0, -1};
    const double indef3[9] = {2, 1, 0, 1, -3, 0, 0, 0, 1};
    const double neg1[1] = {-2};
    const double zero1[1] = {0};
    const double sing2[4] = {1, 2, 2, 4};                /* v v^T, v = (1, 2) */
    const double sing3[9] = {1, 0, 1, 0, 1, 1, 1, 1, 2}; /* rank 2: last pivot 0 */
    const double saddle[4] = {0, 1, 1, 0};
    const double nan2[4] = {1, 0, 0, NAN};
    struct {
        const char *name;
        int n;
        const double *a;
    } cases[] = {{"indefinite 2x2", 2, indef2}, {"indefinite 3x3", 3, indef3},
                 {"negative 1x1", 1, neg1},     {"zero 1x1", 1, zero1},
                 {"singular 2x2", 2, sing2},    {"singular 3x3", 3, sing3},
                 {"saddle 2x2", 2, saddle},     {"NaN pivot", 2, nan2}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        double a[N * N];
        memcpy(a, cases[c].a, sizeof(double) * (size_t)(cases[c].n * cases[c].n));
        cr_assert_eq(ctc_dense_cholesky(cases[c].n, a), -1, "%s: accepted", cases[c].name);
    }

    /* random matrices with one negative eigenvalue: Q diag(-1, 1, ...) Q^T */
    uint64_t rng = 3;
    for (int n = 1; n <= N; n++) {
        double b[N * N], bt[N * N], d[N * N] = {0}, t[N * N], a[N * N];
        random_matrix(&rng, n, n, b); /* a congruence B D B^T keeps the inertia of D */
        transpose(n, b, bt);
        for (int i = 0; i < n; i++) d[i * n + i] = i == 0 ? -1.0 : 1.0;
        plain_mul(n, b, d, t);
        plain_mul(n, t, bt, a);
        cr_assert_eq(ctc_dense_cholesky(n, a), -1, "n = %d: indefinite matrix accepted", n);
    }
}

Test(dense, matrix_vector_products_match_hand_worked_values)
{
    /* a 2 x 3 example worked by hand */
    const double r[6] = {1, 2, 3, 4, 5, 6}, x3[3] = {1, -1, 2}, x2[2] = {2, -1};
    double y2[2], y3[3];
    ctc_dense_mulv(2, 3, r, x3, y2);
    cr_assert(y2[0] == 5 && y2[1] == 11, "mulv: (%g %g), want (5 11)", y2[0], y2[1]);
    ctc_dense_tmulv(2, 3, r, x2, y3);
    cr_assert(y3[0] == -2 && y3[1] == -1 && y3[2] == 0, "tmulv: (%g %g %g), want (-2 -1 0)", y3[0],
              y3[1], y3[2]);
}

Test(dense, the_vector_kernels_match_plain_products)
{
    /* gdca_tmulv (6-vectors in spatial form, simd.h; the dense kernel in planar form) and
       gdca_add_sq (4-vectors, spatial form) against plain loops written here */
    uint64_t rng = 9;
    for (int dim = 3; dim <= 6; dim += 3) {
        for (int trial = 0; trial < 20; trial++) {
            double a[N * N], b[N * N], x[N], y[N], want[N * N], got[N * N];
            random_matrix(&rng, dim, dim, a);
            random_matrix(&rng, dim, dim, b);
            random_matrix(&rng, dim, 1, x);
            gdca_tmulv(dim, a, x, y);
            for (int j = 0; j < dim; j++) {
                want[j] = 0;
                for (int i = 0; i < dim; i++) want[j] += a[i * dim + j] * x[i];
            }
            cr_assert_leq(max_abs_diff(dim, y, want), 1e-15, "A^T x, dim %d", dim);
            if (dim == 6) { /* in planar form gdca_add_sq is this very loop */
                gdca_add_sq(dim, a, b, got);
                for (int i = 0; i < 36; i++)
                    cr_assert_eq(got[i], a[i] + b[i], "A + B, entry %d", i);
            }
        }
    }
}

Test(dense, the_hinge_downdate_matches_plain_products)
{
    /* gdca_downdate_hinge_t: h - X X^T with X = A^T E and E of a hinge's factor (zero entries
       where gdca_joint_factor_hinge leaves them: rows u..u+2 below their diagonal, rows g..g+2
       in columns 0..2), against plain products, to rounding; exactly symmetric, also in place */
    uint64_t rng = 11;
    for (int u = 0; u <= 3; u += 3) {
        const int g = 3 - u;
        for (int trial = 0; trial < 20; trial++) {
            double a[36], e[30], h[36], x[30], want[36], got[36];
            random_matrix(&rng, 6, 6, a);
            random_matrix(&rng, 6, 5, e);
            for (int i = 0; i < 3; i++) {
                for (int c = 0; c < i; c++) e[5 * (u + i) + c] = 0;
                for (int c = 0; c < 3; c++) e[5 * (g + i) + c] = 0;
            }
            for (int i = 0; i < 6; i++) {
                for (int j = i; j < 6; j++) h[6 * i + j] = h[6 * j + i] = test_uniform(&rng, -1, 1);
            }
            for (int i = 0; i < 6; i++) { /* X = A^T E */
                for (int c = 0; c < 5; c++) {
                    double s = 0;
                    for (int k = 0; k < 6; k++) s += a[6 * k + i] * e[5 * k + c];
                    x[5 * i + c] = s;
                }
            }
            for (int i = 0; i < 6; i++) {
                for (int j = 0; j < 6; j++) {
                    double s = 0;
                    for (int c = 0; c < 5; c++) s += x[5 * i + c] * x[5 * j + c];
                    want[6 * i + j] = h[6 * i + j] - s;
                }
            }
            for (int in_place = 0; in_place < 2; in_place++) {
                if (in_place) {
                    memcpy(got, h, sizeof got);
                    gdca_downdate_hinge_t(got, a, e, u, got);
                } else {
                    gdca_downdate_hinge_t(h, a, e, u, got);
                }
                double err = max_abs_diff(36, got, want);
                cr_assert_leq(err, 1e-14, "u = %d%s: differs by %.3e", u,
                              in_place ? " in place" : "", err);
                for (int i = 0; i < 6; i++) {
                    for (int j = 0; j < 6; j++) {
                        cr_assert_eq(got[6 * i + j], got[6 * j + i], "u = %d: not symmetric", u);
                    }
                }
            }
        }
    }
}

Test(dense, the_assembly_downdate_matches_plain_products)
{
    /* gdca_downdate (gdca_tree.h): h - X X^T for X (n x nc), h symmetric; the result matches the
       plain product to rounding and is exactly symmetric, also when out aliases h */
    uint64_t rng = 5;
    for (int n = 1; n <= N; n++) {
        for (int nc = 1; nc <= n; nc++) {
            double x[N * N], xt[N * N], h[N * N], want[N * N], got[N * N], prod[N * N];
            random_matrix(&rng, n, nc, x);
            for (int i = 0; i < n; i++) {
                for (int c = 0; c < nc; c++) xt[c * n + i] = x[i * nc + c];
                for (int j = i; j < n; j++) h[i * n + j] = h[j * n + i] = test_uniform(&rng, -1, 1);
            }
            for (int i = 0; i < n; i++) {
                for (int j = 0; j < n; j++) {
                    double t = 0;
                    for (int c = 0; c < nc; c++) t += x[i * nc + c] * xt[c * n + j];
                    prod[i * n + j] = t;
                }
            }
            for (int i = 0; i < n * n; i++) want[i] = h[i] - prod[i];
            for (int in_place = 0; in_place < 2; in_place++) {
                if (in_place) {
                    memcpy(got, h, sizeof got);
                    gdca_downdate(n, nc, got, x, got);
                } else {
                    memset(got, 0, sizeof got);
                    gdca_downdate(n, nc, h, x, got);
                }
                double e = max_abs_diff(n * n, got, want);
                cr_assert_leq(e, 1e-14, "n = %d, nc = %d%s: differs by %.3e", n, nc,
                              in_place ? " in place" : "", e);
                for (int i = 0; i < n; i++) {
                    for (int j = 0; j < n; j++) {
                        cr_assert_eq(got[i * n + j], got[j * n + i], "n = %d: not symmetric", n);
                    }
                }
            }
        }
    }
}
