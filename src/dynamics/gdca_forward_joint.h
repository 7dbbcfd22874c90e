/*
 * gdca_forward_joint.h - the per-joint kernels of forward GDCA that its two assembly orders share
 * (internal to the library): the balanced tree (gdca_forward.c) and the sequential order
 * (gdca_forward_seq.c). Both are meant to be inlined into CTC_SPECIALISE wrappers
 * with a constant dim, like gdca_tree.h.
 */
#ifndef CTC_GDCA_FORWARD_JOINT_H
#define CTC_GDCA_FORWARD_JOINT_H

#include "data.h"
#include "gdca_tree.h"

/* The modes of one forward pass, a constant in each specialised stage function (the argument
 * named `correct` in gdca_forward.c, gdca_forward_seq.c, gdca_forward_tseq.c):
 *   GDCA_FWD_FULL:     the pass of DESIGN.md section 4: the factors E, K and the assembled
 *                      matrices formed, the bodies' h13, h23 and the joints' beta taken;
 *   GDCA_FWD_CORRECT:  the refinement's correction (gdca_refine.h): every body's h13 = h23 = 0
 *                      and every beta = 0, the factors and matrices of the full pass just made
 *                      reused, the joint loads added to d->jnt_load;
 *   GDCA_FWD_BIASFREE: the reference form's pass (gdca.h ctc_gdca_forward_from): bias-free as
 *                      the correction, but forming the factors and matrices itself, the joint
 *                      loads written (the sequential passes write them plus d->jnt_load_inv,
 *                      the reference's, in the same sweep; gdca_forward_seq.h).
 * So a mode is bias-free when it is not GDCA_FWD_FULL and forms its factors when it is not
 * GDCA_FWD_CORRECT. */
enum { GDCA_FWD_FULL = 0, GDCA_FWD_CORRECT = 1, GDCA_FWD_BIASFREE = 2 };

/* out = A x for A (dim x dim) symmetric (K, h11, h22) and x = P f, the motion or load along a
 * joint of type `type`: in spatial form a revolute joint's P is (axis; 0) and a prismatic one's
 * (0; axis), so half of x is zero and its columns of A are skipped (18 multiply-adds of 36); the
 * three columns left are read as A's rows, as 6-vectors (simd.h). The sums run over them in
 * increasing order, as the dense product's (gdca_tree.h says when the numbers are the same). */
static inline void forward_mulv_joint(int dim, ctc_joint_type type, const double *a,
                                      const double *x, double *out)
{
    const int u = gdca_hinge_u(dim, type);
    if (u >= 0) {
        const int c0 = 3 - u; /* P's non-zero half */
        ctc_v6 acc, row;      /* A's columns c0..c0+2 as its rows: A is symmetric */
        ctc_v6_load(&row, a + 6 * c0);
        ctc_v6_scale(&acc, x[c0], &row);
        for (int k = 1; k < 3; k++) {
            ctc_v6_load(&row, a + 6 * (c0 + k));
            ctc_v6_madd(&acc, x[c0 + k], &row);
        }
        ctc_v6_store(out, &acc);
        return;
    }
    ctc_dense_mulv(dim, dim, a, x, out);
}

/* E and z of joint j between left (NULL: ground) and right: z = W Y + P f with
 * Y = b23^L - b13^R + beta - K P f, W = E E^T, K = h11^R + h22^L. The full pass (factor = 1) forms
 * K and the factor E of W from the records and is given their h13, h23 (b23l, b13r) and the
 * joint's beta; the correction (factor = 0) reuses E, is given its own bias vectors and beta = 0,
 * and does not form K. kk (dim x dim) may be NULL; if not, the full pass stores K there and the
 * correction takes K P f from it, else K P f = h11^R P f + h22^L P f. Returns 0, or -1 when
 * D^T K D is not positive definite (the results are then NaN). */
static inline int forward_joint(const ctc_model *m, ctc_data *d, int j, const double *left,
                                const double *right, const double *b23l, const double *b13r,
                                const double *beta, const double *f, int factor, double *kk,
                                const int dim)
{
    const int nv = m->jnt_nv[j];
    double *e = d->fwd_E + dim * dim * j, *z = d->fwd_z + dim * j;
    double kloc[CTC_DENSE_MAX * CTC_DENSE_MAX], y[CTC_DENSE_MAX], pf[CTC_DENSE_MAX];
    double kpf[CTC_DENSE_MAX];
    double *k = kk != NULL ? kk : kloc;
    int st = 0;

    const ctc_joint_type type = m->joints[j].type;
    gdca_joint_map(dim, nv, d->jnt_P + 3 * dim * j, f + m->jnt_vadr[j], pf);
    if (factor) {
        gdca_joint_K(dim, left, right, k);
        st = gdca_joint_factor_typed(dim, type, k, d->jnt_D + dim * dim * j, dim - nv, e);
        forward_mulv_joint(dim, type, k, pf, kpf);
    } else if (kk != NULL) {
        forward_mulv_joint(dim, type, kk, pf, kpf);
    } else { /* K P f = h11^R P f + h22^L P f, without forming K */
        forward_mulv_joint(dim, type, right + H11(dim), pf, kpf);
        if (left != NULL) {
            forward_mulv_joint(dim, type, left + H22(dim), pf, y);
            for (int i = 0; i < dim; i++) kpf[i] += y[i];
        }
    }
    for (int i = 0; i < dim; i++) {
        y[i] = b23l[i] - b13r[i] + beta[i];
        y[i] -= kpf[i];
    }
    gdca_factor_apply_typed(dim, type, dim - nv, e, y, z);
    for (int i = 0; i < dim; i++) z[i] += pf[i];
    return st;
}

/* joint j's beta: zero in the bias-free modes */
static inline const double *gdca_forward_beta(const ctc_data *d, int j, const int dim,
                                              const int correct)
{
    return correct ? gdca_zero6 : d->jnt_beta + dim * j;
}

/* qdd_j = P^T (A1^R - A2^L - beta) written into qacc, for the given beta */
static inline void forward_accel(const ctc_model *m, const ctc_data *d, int j, const double *a1r,
                                 const double *a2l, const double *beta, double *qacc, const int dim)
{
    const double *P = d->jnt_P + 3 * dim * j;
    for (int c = 0; c < m->jnt_nv[j]; c++) {
        double s = 0;
        for (int i = 0; i < dim; i++) s += P[c * dim + i] * (a1r[i] - a2l[i] - beta[i]);
        qacc[m->jnt_vadr[j] + c] = s;
    }
}

#endif
