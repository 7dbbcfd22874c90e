/*
 * gdca_tree.h - the kernels that forward GDCA and inverse GDCA share (internal to the library).
 *
 * At a joint between a left assembly L (its handle 2) and a right assembly R (its handle 1), both
 * passes solve the joint load in the form
 *     F = G (h21^L F1^L - h12^R F2^R) + z                      (DESIGN.md section 4, Eq. 27)
 * (forward: G = W = D (D^T K D)^-1 D^T, z = W Y + P f; mobility inverse: G = X = K^-1,
 * z = X Y', with K = h11^R + h22^L), so the assembled record of L:R is the same function of
 * (G, z); G is symmetric positive semidefinite and is kept as its factor E, G = E E^T:
 *     h11 = h11^L - h12^L G h21^L     h12 = h12^L G h12^R     h13 = h13^L - h12^L z
 *     h22 = h22^R - h21^R G h12^R                             h23 = h23^R + h21^R z
 * (Eq. 34-39). The functions take the dimension as an argument (the joint factors specialised to
 * one form and joint type excepted) and are meant to be inlined into CTC_SPECIALISE wrappers with
 * a constant 3 or 6.
 *
 * The kernels that skip a typed joint factor's zeros (gdca_mul_hinge, gdca_factor_apply_hinge
 * and their planar forms) sum the dense products' non-zero terms in the dense order, so they give
 * the dense products' numbers (but for the sign of a zero) where the compiler does not contract
 * products and sums into fused multiply-adds, as gcc does not in ISO C mode (-std=c11). A build
 * that contracts (make bench: -ffp-contract=fast) may round the two shapes of loop differently,
 * within the products' rounding (test_gdca_forward).
 *
 * In spatial form the kernels that the sequential order and the composite inverse spend most of
 * their time in work on 6-vectors and 4-vectors (simd.h): sums of 6 x 6 blocks (gdca_add_sq),
 * products A^T x by A's rows (gdca_tmulv; A x for the symmetric K, h11, h22 and composite
 * inertias), and the sequential order's downdate (gdca_downdate_hinge_t). Without them these
 * stay scalar, since the builds turn gcc's vectoriser off (Makefile, OPT_DEFAULT). They round
 * otherwise than the scalar loops, within the products' rounding (test_dense).
 */
#ifndef CTC_GDCA_TREE_H
#define CTC_GDCA_TREE_H

#include <stddef.h>

#include "dense.h"
#include "model.h"
#include "simd.h"
#include "spatial.h"

/* offsets of the blocks of a handle-equation record (data.h) */
#define H11(dim) 0
#define H12(dim) ((dim) * (dim))
#define H22(dim) (2 * (dim) * (dim))
#define H13(dim) (3 * (dim) * (dim))
#define H23(dim) (3 * (dim) * (dim) + (dim))

/* a zero vector: the ground's acceleration, and bias terms left out */
static const double gdca_zero6[CTC_DENSE_MAX] = {0, 0, 0, 0, 0, 0};

/* y = A^T x, A (dim x dim), by A's rows as 6-vectors in spatial form (simd.h); for a symmetric A
 * (K, h11, h22, composite inertias) it is A x read by rows */
static inline void gdca_tmulv(int dim, const double *a, const double *x, double *y)
{
    if (dim == 6) {
        ctc_v6_tmulv(a, x, y);
    } else {
        ctc_dense_tmulv(dim, dim, a, x, y);
    }
}

/* out = a + b (dim x dim), in spatial form as 4-vectors (simd.h) */
static inline void gdca_add_sq(int dim, const double *a, const double *b, double *out)
{
    if (dim == 6) {
        ctc_v36_add(a, b, out);
    } else {
        for (int i = 0; i < dim * dim; i++) out[i] = a[i] + b[i];
    }
}

/* K = h11^R + h22^L; a NULL left is the ground (h22 = 0) */
static inline void gdca_joint_K(int dim, const double *left, const double *right, double *k)
{
    if (left != NULL) {
        gdca_add_sq(dim, right + H11(dim), left + H22(dim), k);
    } else {
        for (int i = 0; i < dim * dim; i++) k[i] = right[H11(dim) + i];
    }
}

/* out = P x (dim): the motion (or load) of a joint's coordinates x (nv) through its map P (column
 * c at p[c dim]) - P qdd, P u, P f */
static inline void gdca_joint_map(int dim, int nv, const double *p, const double *x, double *out)
{
    for (int i = 0; i < dim; i++) out[i] = 0;
    for (int c = 0; c < nv; c++) {
        for (int i = 0; i < dim; i++) out[i] += p[c * dim + i] * x[c];
    }
}

/* Y0 = h23^L - h13^R + beta (the part of Y common to both passes) */
static inline void gdca_joint_Y0(int dim, const double *left, const double *right,
                                 const double *beta, double *y)
{
    for (int i = 0; i < dim; i++) {
        y[i] = (left ? left[H23(dim) + i] : 0.0) - right[H13(dim) + i] + beta[i];
    }
}

/* L^-1 (li, nc x nc lower triangular, row-major; the upper triangle is not written) of the
 * Cholesky factor L of the symmetric positive definite C = L L^T (nc x nc, row-major; its lower
 * triangle is read and overwritten as scratch). By way of C = U diag(d) U^T with U unit lower
 * triangular: each pivot d_j takes one division and no square root, so no root lies on the chain
 * of dependent operations through the pivots; then L^-1 = diag(d)^-1/2 U^-1, whose nc roots are
 * independent of one another. Returns 0, or -1 if a pivot is not positive. 1 <= nc <= 6.
 *
 * Every loop is unrolled whole (the pragmas, which gcc and clang both read). Where nc is a
 * constant, as in the hinge and planar factors, every index then is one too, and c, w, rd and li
 * stay in registers instead of memory: 10% fewer instructions in a spatial CTC right-hand side
 * at n = 2 (bench/NOTEBOOK.md, "Spatial n = 2 and 4"). rd's zeros only tell the compiler that it
 * is written before it is read. */
static inline int gdca_chol_inv(int nc, double *c, double *li)
{
    double rd[CTC_DENSE_MAX] = {0}, w[CTC_DENSE_MAX * CTC_DENSE_MAX];
    if (nc < 1 || nc > CTC_DENSE_MAX) __builtin_unreachable();
#pragma GCC unroll 6
    for (int j = 0; j < nc; j++) {
        /* with w_ik = U_ik d_k kept from column k (the numerator before its division):
           d_j = C_jj - sum_k U_jk w_jk, w_ij = C_ij - sum_k U_ik w_jk, U_ij = w_ij / d_j */
        double p = c[j * nc + j];
#pragma GCC unroll 6
        for (int k = 0; k < j; k++) p -= c[j * nc + k] * w[j * nc + k];
        if (!(p > 0)) return -1;
        rd[j] = 1.0 / p;
#pragma GCC unroll 6
        for (int i = j + 1; i < nc; i++) {
            double t = c[i * nc + j];
#pragma GCC unroll 6
            for (int k = 0; k < j; k++) t -= c[i * nc + k] * w[j * nc + k];
            w[i * nc + j] = t;
            c[i * nc + j] = t * rd[j];
        }
    }
#pragma GCC unroll 6
    /* U^-1 by rows: (U^-1)_ij = -(U_ij + sum_{k=j+1}^{i-1} U_ik (U^-1)_kj), j < i */
    for (int i = 1; i < nc; i++) {
#pragma GCC unroll 6
        for (int j = 0; j < i; j++) {
            double t = c[i * nc + j];
#pragma GCC unroll 6
            for (int k = j + 1; k < i; k++) t += c[i * nc + k] * li[k * nc + j];
            li[i * nc + j] = -t;
        }
    }
#pragma GCC unroll 6
    /* row i times 1 / sqrt(d_i) */
    for (int i = 0; i < nc; i++) {
        const double s = sqrt(rd[i]);
        li[i * nc + i] = s;
#pragma GCC unroll 6
        for (int j = 0; j < i; j++) li[i * nc + j] *= s;
    }
    return 0;
}

/* The factor E (dim x nc, row-major with row stride nc) of G = E E^T = D (D^T K D)^-1 D^T, for D
 * (dim x nc, column c at d[c dim]) with orthonormal columns, or D = identity when d is NULL (then
 * E E^T = K^-1). With D^T K D = L L^T (Cholesky), E = D L^-T, from L^-1 formed once. K (dim x
 * dim) symmetric positive definite. Returns 0, or -1 if D^T K D is not positive definite (E is
 * then NaN). G itself is never formed: every product with it goes through E, and only E E^T
 * matters, so the order of D's columns is free. */
static inline int gdca_joint_factor_nc(int dim, const double *k, const double *d, int nc, double *e)
{
    double c[CTC_DENSE_MAX * CTC_DENSE_MAX], kd[CTC_DENSE_MAX * CTC_DENSE_MAX];
    double li[CTC_DENSE_MAX * CTC_DENSE_MAX];

    if (nc == 0) return 0; /* a joint that constrains nothing carries no constraint load */
    /* C = D^T K D; with D = I it is K */
    if (d == NULL) {
        for (int i = 0; i < dim * dim; i++) c[i] = k[i];
    } else {
        for (int c0 = 0; c0 < nc; c0++) { /* kd column c0 = K d_c0 */
            ctc_dense_mulv(dim, dim, k, d + c0 * dim, kd + c0 * dim);
        }
        for (int a = 0; a < nc; a++) {
            for (int b = a; b < nc; b++) {
                double s = 0;
                for (int i = 0; i < dim; i++) s += d[a * dim + i] * kd[b * dim + i];
                c[a * nc + b] = s;
                c[b * nc + a] = s;
            }
        }
    }
    if (gdca_chol_inv(nc, c, li) != 0) {
        for (int i = 0; i < dim * nc; i++) e[i] = NAN;
        return -1;
    }
    /* E_rc = sum_{k <= c} D_rk (L^-1)_ck */
    for (int r = 0; r < dim; r++) {
        for (int c0 = 0; c0 < nc; c0++) {
            double s = 0;
            if (d == NULL) {
                s = r <= c0 ? li[c0 * nc + r] : 0.0;
            } else {
                for (int k0 = 0; k0 <= c0; k0++) s += d[k0 * dim + r] * li[c0 * nc + k0];
            }
            e[r * nc + c0] = s;
        }
    }
    return 0;
}

/* gdca_joint_factor_nc with nc = dim - 1 (single-freedom joints) made a constant, so that its
 * loops unroll */
static inline int gdca_joint_factor(int dim, const double *k, const double *d, int nc, double *e)
{
    if (nc == dim - 1) return gdca_joint_factor_nc(dim, k, d, dim - 1, e);
    return gdca_joint_factor_nc(dim, k, d, nc, e);
}

/* E for D = [unit columns e_u, e_u+1, e_u+2; (n1 at rows g..g+2), (n2 at rows g..g+2)] (dim 6,
 * nc 5; {u, g} = {3, 0} for a revolute joint, whose D's columns n1, n2 are angular, and {0, 3}
 * for a prismatic one), the columns taken in that order: D^T K D picks K's block (u, u) and the
 * products K (n_a at g), so that K D costs 2 products with 3 columns of K instead of 5 full
 * ones, and E's rows u..u+2 are L^-T's. Returns as gdca_joint_factor. */
static inline int gdca_joint_factor_hinge(const double *k, const double *n1, const double *n2,
                                          int u, int g, double *e)
{
    double c[25], li[25], kn[2][6];
    const double *n[2] = {n1, n2};

    for (int a = 0; a < 2; a++) { /* kn_a = K (n_a at rows g), by K's rows g..g+2 (K = K^T) */
        ctc_v6 acc, row;
        ctc_v6_load(&row, k + 6 * g);
        ctc_v6_scale(&acc, n[a][0], &row);
        for (int i = 1; i < 3; i++) {
            ctc_v6_load(&row, k + 6 * (g + i));
            ctc_v6_madd(&acc, n[a][i], &row);
        }
        ctc_v6_store(kn[a], &acc);
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) c[5 * i + j] = k[6 * (u + i) + u + j];
        for (int a = 0; a < 2; a++) c[5 * i + 3 + a] = c[5 * (3 + a) + i] = kn[a][u + i];
    }
    for (int a = 0; a < 2; a++) {
        for (int b = a; b < 2; b++) {
            const double *kb = kn[b] + g;
            c[5 * (3 + a) + 3 + b] = c[5 * (3 + b) + 3 + a] =
                n[a][0] * kb[0] + n[a][1] * kb[1] + n[a][2] * kb[2];
        }
    }
    if (gdca_chol_inv(5, c, li) != 0) {
        for (int i = 0; i < 30; i++) e[i] = NAN;
        return -1;
    }
    for (int i = 0; i < 3; i++) { /* rows u + i: D's row is e_i^T */
        double *er = e + 5 * (u + i);
        for (int c0 = 0; c0 < 5; c0++) er[c0] = c0 >= i ? li[5 * c0 + i] : 0.0;
    }
    for (int r = 0; r < 3; r++) { /* rows g + r: D's row is (0, 0, 0, n1_r, n2_r) */
        double *er = e + 5 * (g + r);
        er[0] = er[1] = er[2] = 0;
        er[3] = n1[r] * li[5 * 3 + 3];
        er[4] = n1[r] * li[5 * 4 + 3] + n2[r] * li[5 * 4 + 4];
    }
    return 0;
}

/* E of a planar revolute joint, D = [(0, 1, 0), (0, 0, 1)]: D^T K D is K's lower right 2 x 2
 * block, and E = D L^-T has a zero first row. Returns as gdca_joint_factor. */
static inline int gdca_joint_factor_planar_revolute(const double *k, double *e)
{
    double c[4] = {k[4], k[5], k[7], k[8]}, li[4];
    if (gdca_chol_inv(2, c, li) != 0) {
        for (int i = 0; i < 6; i++) e[i] = NAN;
        return -1;
    }
    e[0] = e[1] = 0;
    e[2] = li[0], e[3] = li[2];
    e[4] = 0, e[5] = li[3];
    return 0;
}

/* E of joint j of type `type` with D from the kinematics (kinematics.c: revolute and prismatic
 * joints' D columns are laid out as gdca_joint_factor_hinge and
 * gdca_joint_factor_planar_revolute assume), by the specialised forms where they apply */
static inline int gdca_joint_factor_typed(int dim, ctc_joint_type type, const double *k,
                                          const double *d, int nc, double *e)
{
    if (dim == 3 && type == CTC_JOINT_REVOLUTE) return gdca_joint_factor_planar_revolute(k, e);
    if (dim == 6 && type == CTC_JOINT_REVOLUTE) {
        return gdca_joint_factor_hinge(k, d, d + 6, 3, 0, e);
    }
    if (dim == 6 && type == CTC_JOINT_PRISMATIC) {
        return gdca_joint_factor_hinge(k, d + 18 + 3, d + 24 + 3, 0, 3, e);
    }
    return gdca_joint_factor(dim, k, d, nc, e);
}

/* out = G x = E (E^T x), x and out (dim); out may not alias x */
static inline void gdca_factor_apply_nc(int dim, int nc, const double *e, const double *x,
                                        double *out)
{
    double t[CTC_DENSE_MAX];
    ctc_dense_tmulv(dim, nc, e, x, t);
    ctc_dense_mulv(dim, nc, e, t, out);
}

/* gdca_factor_apply_nc with nc = dim - 1 made a constant */
static inline void gdca_factor_apply(int dim, int nc, const double *e, const double *x, double *out)
{
    if (nc == dim - 1) {
        gdca_factor_apply_nc(dim, dim - 1, e, x, out);
    } else {
        gdca_factor_apply_nc(dim, nc, e, x, out);
    }
}

/* x = M E (trans = 0) or M^T E (trans = 1) (6 x 5), M (6 x 6), for E of
 * gdca_joint_factor_hinge with its zeros skipped: E's columns 0..2 are non-zero only in rows
 * u..u+c, so 108 multiply-adds instead of 180. Each sum runs over increasing rows of E, as the
 * dense product's. */
static inline void gdca_mul_hinge(const double *mm, int trans, const double *e, int u, double *x)
{
    for (int i = 0; i < 6; i++) {
        double mi[6];
        for (int k = 0; k < 6; k++) mi[k] = trans ? mm[6 * k + i] : mm[6 * i + k];
        double *xi = x + 5 * i;
        xi[0] = mi[u] * e[5 * u];
        xi[1] = mi[u] * e[5 * u + 1] + mi[u + 1] * e[5 * (u + 1) + 1];
        xi[2] =
            mi[u] * e[5 * u + 2] + mi[u + 1] * e[5 * (u + 1) + 2] + mi[u + 2] * e[5 * (u + 2) + 2];
        for (int c = 3; c < 5; c++) {
            double t = 0;
            for (int k = 0; k < 6; k++) t += mi[k] * e[5 * k + c];
            xi[c] = t;
        }
    }
}

/* out = G x = E (E^T x) for E of gdca_joint_factor_hinge, its zeros skipped (36 multiply-adds
 * instead of 60), in the dense order; out may not alias x */
static inline void gdca_factor_apply_hinge(const double *e, int u, const double *x, double *out)
{
    double t[5];
    t[0] = e[5 * u] * x[u];
    t[1] = e[5 * u + 1] * x[u] + e[5 * (u + 1) + 1] * x[u + 1];
    t[2] = e[5 * u + 2] * x[u] + e[5 * (u + 1) + 2] * x[u + 1] + e[5 * (u + 2) + 2] * x[u + 2];
    for (int c = 3; c < 5; c++) {
        double s = 0;
        for (int k = 0; k < 6; k++) s += e[5 * k + c] * x[k];
        t[c] = s;
    }
    for (int r = 0; r < 3; r++) { /* rows g + r: non-zero at columns 3, 4 */
        const int g = u == 0 ? 3 : 0;
        out[g + r] = e[5 * (g + r) + 3] * t[3] + e[5 * (g + r) + 4] * t[4];
    }
    const double *eu = e + 5 * u; /* rows u + i: non-zero from column i */
    out[u] = eu[0] * t[0] + eu[1] * t[1] + eu[2] * t[2] + eu[3] * t[3] + eu[4] * t[4];
    out[u + 1] = eu[6] * t[1] + eu[7] * t[2] + eu[8] * t[3] + eu[9] * t[4];
    out[u + 2] = eu[12] * t[2] + eu[13] * t[3] + eu[14] * t[4];
}

/* x = M E or M^T E (3 x 2) for E of gdca_joint_factor_planar_revolute (first row zero, e[4] =
 * 0) */
static inline void gdca_mul_planar_revolute(const double *mm, int trans, const double *e, double *x)
{
    for (int i = 0; i < 3; i++) {
        const double m1 = trans ? mm[3 + i] : mm[3 * i + 1], m2 = trans ? mm[6 + i] : mm[3 * i + 2];
        x[2 * i] = m1 * e[2];
        x[2 * i + 1] = m1 * e[3] + m2 * e[5];
    }
}

/* out = G x for E of gdca_joint_factor_planar_revolute, its zeros skipped, in the dense order
 */
static inline void gdca_factor_apply_planar_revolute(const double *e, const double *x, double *out)
{
    const double t0 = e[2] * x[1], t1 = e[3] * x[1] + e[5] * x[2];
    out[0] = 0;
    out[1] = e[2] * t0 + e[3] * t1;
    out[2] = e[5] * t1;
}

/* 1 if gdca_joint_factor_typed makes a specialised factor (nc = dim - 1) for joints of type
   `type` in form dim */
static inline int gdca_joint_factor_is_typed(int dim, ctc_joint_type type)
{
    return type == CTC_JOINT_REVOLUTE || (dim == 6 && type == CTC_JOINT_PRISMATIC);
}

/* For a spatial hinge (a revolute or prismatic joint in spatial form), the first row u of the
 * unit columns of its constraint basis D (gdca_joint_factor_hinge): 3 for a revolute joint, whose
 * unit columns are forces, 0 for a prismatic one; its motion map P is non-zero in the other half,
 * rows 3 - u .. 5 - u. -1 for any other joint or form. */
static inline int gdca_hinge_u(int dim, ctc_joint_type type)
{
    if (dim != 6) return -1;
    return type == CTC_JOINT_REVOLUTE ? 3 : type == CTC_JOINT_PRISMATIC ? 0 : -1;
}

/* out = G x for the E that gdca_joint_factor_typed made for a joint of type `type` */
static inline void gdca_factor_apply_typed(int dim, ctc_joint_type type, int nc, const double *e,
                                           const double *x, double *out)
{
    /* u a constant in each call, so that the hinge's indices are */
    if (dim == 3 && type == CTC_JOINT_REVOLUTE) {
        gdca_factor_apply_planar_revolute(e, x, out);
    } else if (gdca_hinge_u(dim, type) == 3) {
        gdca_factor_apply_hinge(e, 3, x, out);
    } else if (gdca_hinge_u(dim, type) == 0) {
        gdca_factor_apply_hinge(e, 0, x, out);
    } else {
        gdca_factor_apply(dim, nc, e, x, out);
    }
}

/* The bias vectors of the record of L:R (out) from the biases b13^L and b23^R (the records' own
 * h13^L and h23^R, or other bias vectors through the same matrices: gdca_refine.h) and z:
 *     h13 = b13^L - h12^L z,   h23 = b23^R + h21^R z.   out may not be left or right. */
static inline void gdca_assemble_bias(int dim, const double *left, const double *right,
                                      const double *b13l, const double *b23r, const double *z,
                                      double *out)
{
    double t[CTC_DENSE_MAX];
    ctc_dense_mulv(dim, dim, left + H12(dim), z, t);
    for (int i = 0; i < dim; i++) out[H13(dim) + i] = b13l[i] - t[i];
    ctc_dense_tmulv(dim, dim, right + H12(dim), z, t);
    for (int i = 0; i < dim; i++) out[H23(dim) + i] = b23r[i] + t[i];
}

/* x = M E (trans = 0) or M^T E (trans = 1) (dim x nc), M (dim x dim), E (dim x nc) */
static inline void gdca_mul_E(int dim, int nc, const double *mm, int trans, const double *e,
                              double *x)
{
    for (int i = 0; i < dim; i++) {
        for (int c = 0; c < nc; c++) {
            double s = 0;
            for (int k = 0; k < dim; k++) {
                s += (trans ? mm[k * dim + i] : mm[i * dim + k]) * e[k * nc + c];
            }
            x[i * nc + c] = s;
        }
    }
}

/* x = M E or M^T E for the E that gdca_joint_factor_typed made for a joint of type `type`, its
   zeros skipped where that factor is specialised (the dense product's numbers) */
static inline void gdca_mul_E_typed(int dim, ctc_joint_type type, int nc, const double *mm,
                                    int trans, const double *e, double *x)
{
    const int u = gdca_hinge_u(dim, type);
    if (u >= 0) {
        gdca_mul_hinge(mm, trans, e, u, x);
    } else if (dim == 3 && type == CTC_JOINT_REVOLUTE) {
        gdca_mul_planar_revolute(mm, trans, e, x);
    } else {
        gdca_mul_E(dim, nc, mm, trans, e, x);
    }
}

/* out (dim x dim, symmetric) = h - X X^T for X (dim x nc): the upper triangle computed,
   mirrored; out may be h */
static inline void gdca_downdate(int dim, int nc, const double *h, const double *x, double *out)
{
    for (int i = 0; i < dim; i++) {
        for (int j = i; j < dim; j++) {
            double s = 0;
            for (int c = 0; c < nc; c++) s += x[i * nc + c] * x[j * nc + c];
            out[i * dim + j] = out[j * dim + i] = h[i * dim + j] - s;
        }
    }
}

/* out (6 x 6, symmetric) = h - X X^T with X = M^T E, for E of gdca_joint_factor_hinge (nc 5, u
 * as there): the columns of X formed as 6-vectors (simd.h) from the rows of M and E's non-zero
 * entries, then each row of out as h's row less five multiples of them. out[i][j] and out[j][i]
 * take the same products in the same order, so out is exactly symmetric. out may be h. */
static inline void gdca_downdate_hinge_t(const double *h, const double *mm, const double *e, int u,
                                         double *out)
{
    const int g = 3 - u;
    double xt[30];
    ctc_v6 r[6], x[5];
    for (int k = 0; k < 6; k++) ctc_v6_load(&r[k], mm + 6 * k);
    for (int c = 0; c < 5; c++) {
        ctc_v6_scale(&x[c], e[5 * u + c], &r[u]);
        for (int i = 1; i < 3 && i <= c; i++) ctc_v6_madd(&x[c], e[5 * (u + i) + c], &r[u + i]);
        if (c >= 3) {
            for (int i = 0; i < 3; i++) ctc_v6_madd(&x[c], e[5 * (g + i) + c], &r[g + i]);
        }
        ctc_v6_store(xt + 6 * c, &x[c]);
    }
    for (int i = 0; i < 6; i++) {
        ctc_v6 o;
        ctc_v6_load(&o, h + 6 * i);
        for (int c = 0; c < 5; c++) ctc_v6_msub(&o, xt[6 * c + i], &x[c]);
        ctc_v6_store(out + 6 * i, &o);
    }
}

/* The record of L:R (out) from the records of L and R and the joint's factor E (G = E E^T) and
 * z (Eq. 34-39): with A = h12^L E and B = h21^R E,
 *     h11 = h11^L - A A^T,   h12 = A B^T,   h22 = h22^R - B B^T,
 *     h13 = h13^L - h12^L z,   h23 = h23^R + h21^R z. */
static inline void gdca_assemble_nc(int dim, int nc, const double *left, const double *right,
                                    const double *e, const double *z, double *out)
{
    double a[CTC_DENSE_MAX * CTC_DENSE_MAX], b[CTC_DENSE_MAX * CTC_DENSE_MAX];

    gdca_mul_E(dim, nc, left + H12(dim), 0, e, a);  /* A = h12^L E */
    gdca_mul_E(dim, nc, right + H12(dim), 1, e, b); /* B = (h12^R)^T E */
    gdca_downdate(dim, nc, left + H11(dim), a, out + H11(dim));
    gdca_downdate(dim, nc, right + H22(dim), b, out + H22(dim));
    for (int i = 0; i < dim; i++) {
        for (int j = 0; j < dim; j++) {
            double s12 = 0;
            for (int c = 0; c < nc; c++) s12 += a[i * nc + c] * b[j * nc + c];
            out[H12(dim) + i * dim + j] = s12;
        }
    }

    gdca_assemble_bias(dim, left, right, left + H13(dim), right + H23(dim), z, out);
}

/* gdca_assemble_nc with nc made a constant in each branch, so that the loops unroll */
static inline void gdca_assemble(int dim, int nc, const double *left, const double *right,
                                 const double *e, const double *z, double *out)
{
    switch (nc) {
    case 1:
        gdca_assemble_nc(dim, 1, left, right, e, z, out);
        break;
    case 2:
        gdca_assemble_nc(dim, 2, left, right, e, z, out);
        break;
    case 3:
        gdca_assemble_nc(dim, 3, left, right, e, z, out);
        break;
    case 4:
        gdca_assemble_nc(dim, 4, left, right, e, z, out);
        break;
    case 5:
        gdca_assemble_nc(dim, 5, left, right, e, z, out);
        break;
    case 6:
        gdca_assemble_nc(dim, 6, left, right, e, z, out);
        break;
    default:
        gdca_assemble_nc(dim, 0, left, right, e, z, out);
        break;
    }
}

/* The joint load F = E E^T (h21^L F1 - h12^R F2) + z from the terminal loads F1 (on L's handle 1)
 * and F2 (on R's handle 2) of the assembly L:R (Eq. 27). */
static inline void gdca_joint_load(int dim, int nc, const double *left, const double *right,
                                   const double *e, const double *z, const double *f1,
                                   const double *f2, double *f)
{
    double s[CTC_DENSE_MAX], t[CTC_DENSE_MAX];
    ctc_dense_tmulv(dim, dim, left + H12(dim), f1, s);
    ctc_dense_mulv(dim, dim, right + H12(dim), f2, t);
    for (int i = 0; i < dim; i++) s[i] -= t[i];
    gdca_factor_apply(dim, nc, e, s, f);
    for (int i = 0; i < dim; i++) f[i] += z[i];
}

/* The children's terminal loads in tload ((2n - 1) x 2 dim, by assembly index): the left part
 * carries (F1, -F), the right part (F, F2), F being the load on the right part at the joint. */
static inline void gdca_pass_loads(int dim, double *tload, const ctc_tree_node *node,
                                   const double *f1, const double *f2, const double *f)
{
    double *tl = tload + (size_t)node->left * 2 * dim, *tr = tload + (size_t)node->right * 2 * dim;
    for (int r = 0; r < dim; r++) {
        tl[r] = f1[r];
        tl[dim + r] = -f[r];
        tr[r] = f[r];
        tr[dim + r] = f2[r];
    }
}

#endif
