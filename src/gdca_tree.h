/*
 * gdca_tree.h - the kernels that forward GDCA and inverse GDCA share (internal to the library).
 *
 * At a joint between a left assembly L (its handle 2) and a right assembly R (its handle 1), both
 * passes solve the joint load in the form
 *     F = G (h21^L F1^L - h12^R F2^R) + z                      (DESIGN.md section 4, Eq. 27)
 * (forward: G = W = D (D^T K D)^-1 D^T, z = W Y + P f; inverse: G = X = K^-1, z = X Y', with
 * K = h11^R + h22^L), so the assembled record of L:R is the same function of (G, z):
 *     h11 = h11^L - h12^L G h21^L     h12 = h12^L G h12^R     h13 = h13^L - h12^L z
 *     h22 = h22^R - h21^R G h12^R                             h23 = h23^R + h21^R z
 * (Eq. 34-39). All functions take the dimension as an argument and are meant to be inlined into
 * CTC_SPECIALISE wrappers with a constant 3 or 6.
 */
#ifndef CTC_GDCA_TREE_H
#define CTC_GDCA_TREE_H

#include "dense.h"

/* offsets of the blocks of a handle-equation record (data.h) */
#define H11(dim) 0
#define H12(dim) ((dim) * (dim))
#define H22(dim) (2 * (dim) * (dim))
#define H13(dim) (3 * (dim) * (dim))
#define H23(dim) (3 * (dim) * (dim) + (dim))

/* K = h11^R + h22^L; a NULL left is the ground (h22 = 0) */
static inline void gdca_joint_K(int dim, const double *left, const double *right, double *k)
{
    for (int i = 0; i < dim * dim; i++) {
        k[i] = right[H11(dim) + i] + (left ? left[H22(dim) + i] : 0.0);
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

/* G = D C^-1 D^T with C = D^T K D, for D (dim x nc, column c at d[c dim]) with orthonormal
 * columns, or D = identity when d is NULL (then G = K^-1). K (dim x dim) symmetric positive
 * definite. Returns 0, or -1 if C is not positive definite (G then NaN). */
static inline int gdca_projected_inverse(int dim, const double *k, const double *d, int nc,
                                         double *g)
{
    double c[CTC_DENSE_MAX * CTC_DENSE_MAX], kd[CTC_DENSE_MAX * CTC_DENSE_MAX];
    double e[CTC_DENSE_MAX * CTC_DENSE_MAX];

    if (nc == 0) { /* the joint constrains nothing: no load can pass */
        for (int i = 0; i < dim * dim; i++) g[i] = 0;
        return 0;
    }
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
    if (ctc_dense_cholesky(nc, c) != 0) {
        for (int i = 0; i < dim * dim; i++) g[i] = NAN;
        return -1;
    }
    /* E = D L^-T: row r of E solves L e = (row r of D)^T; G = E E^T */
    for (int r = 0; r < dim; r++) {
        double *er = e + r * nc;
        for (int c0 = 0; c0 < nc; c0++) {
            er[c0] = d ? d[c0 * dim + r] : (double)(c0 == r);
        }
        ctc_dense_lsolve(nc, c, er);
    }
    for (int a = 0; a < dim; a++) {
        for (int b = a; b < dim; b++) {
            double s = 0;
            for (int i = 0; i < nc; i++) s += e[a * nc + i] * e[b * nc + i];
            g[a * dim + b] = s;
            g[b * dim + a] = s;
        }
    }
    return 0;
}

/* The record of L:R (out) from the records of L and R and the joint's G and z (Eq. 34-39). */
static inline void gdca_assemble(int dim, const double *left, const double *right,
                                 const double *g, const double *z, double *out)
{
    double a[CTC_DENSE_MAX * CTC_DENSE_MAX], b[CTC_DENSE_MAX * CTC_DENSE_MAX];
    const double *l12 = left + H12(dim), *r12 = right + H12(dim);

    ctc_dense_mul(dim, l12, g, a);    /* A = h12^L G */
    ctc_dense_mul_tn(dim, r12, g, b); /* B = h21^R G = (h12^R)^T G */
    ctc_dense_sym_sub_nt(dim, left + H11(dim), a, l12, out + H11(dim)); /* h11^L - A h21^L */
    ctc_dense_mul(dim, a, r12, out + H12(dim));                          /* A h12^R */
    ctc_dense_sym_sub(dim, right + H22(dim), b, r12, out + H22(dim));  /* h22^R - B h12^R */

    double t[CTC_DENSE_MAX];
    ctc_dense_mulv(dim, dim, l12, z, t); /* h13 = h13^L - h12^L z */
    for (int i = 0; i < dim; i++) out[H13(dim) + i] = left[H13(dim) + i] - t[i];
    ctc_dense_tmulv(dim, dim, r12, z, t); /* h23 = h23^R + h21^R z */
    for (int i = 0; i < dim; i++) out[H23(dim) + i] = right[H23(dim) + i] + t[i];
}

/* The joint load F = G (h21^L F1 - h12^R F2) + z from the terminal loads F1 (on L's handle 1)
 * and F2 (on R's handle 2) of the assembly L:R (Eq. 27). */
static inline void gdca_joint_load(int dim, const double *left, const double *right,
                                   const double *g, const double *z, const double *f1,
                                   const double *f2, double *f)
{
    double s[CTC_DENSE_MAX], t[CTC_DENSE_MAX];
    ctc_dense_tmulv(dim, dim, left + H12(dim), f1, s);
    ctc_dense_mulv(dim, dim, right + H12(dim), f2, t);
    for (int i = 0; i < dim; i++) s[i] -= t[i];
    ctc_dense_mulv(dim, dim, g, s, f);
    for (int i = 0; i < dim; i++) f[i] += z[i];
}

#endif
