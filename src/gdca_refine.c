/*
 * gdca_refine.c - the bias-free correction pass of forward GDCA (gdca_refine.h).
 *
 * With every body's h13 = h23 = 0 and every beta = 0, the forward pass of gdca_forward.c keeps
 * its matrices (they depend on the state only) and its vectors obey, at the joint j between L
 * and R with the joint forces r,
 *     y = b23^L - b13^R - K P r,   z = E E^T y + P r,      K = h11^R + h22^L,
 *     b13 = b13^L - h12^L z,       b23 = b23^R + h21^R z,  (the record of L:R; bodies: b = 0)
 * and at the root, the ground joint 0 and the free end F2 = 0. The disassembly is that of the
 * forward pass with b in place of h13, h23 and beta = 0. The node records' own h13, h23 hold b
 * afterwards: the full pass has no further use for them.
 */
#include "gdca_refine.h"

#include "gdca.h"
#include "gdca_tree.h"

int gdca_refine_steps(const ctc_model *m, const ctc_data *d)
{
    if (m->has_loop) return 0;
    if (d->fwd_refine >= 0) return d->fwd_refine;
    int needed = m->nbodies >= CTC_REFINE_MIN_BODIES || m->mass_ratio >= CTC_REFINE_MASS_RATIO;
    return needed ? CTC_REFINE_MAX_STEPS : 0;
}

/* the bias b13 (which = 0) or b23 (which = 1) of assembly a: zero for a body */
static inline const double *bias(const ctc_model *m, const ctc_data *d, int a, int which,
                                 const double *zero)
{
    if (a < m->nbodies) return zero;
    return ctc_data_handles(m, d, a, 0) + (which ? H23(d->dim) : H13(d->dim));
}

/* z = E E^T (b23^L - b13^R - K P r) + P r of joint j (left NULL: the ground) */
static inline void correct_joint(const ctc_model *m, ctc_data *d, int j, const double *left,
                                 const double *right, const double *b23l, const double *b13r,
                                 const double *r, double *z, const int dim)
{
    const int nv = m->jnt_nv[j];
    double pr[CTC_DENSE_MAX], y[CTC_DENSE_MAX], t[CTC_DENSE_MAX];

    gdca_joint_map(dim, nv, d->jnt_P + 3 * dim * j, r + m->jnt_vadr[j], pr);
    ctc_dense_mulv(dim, dim, right + H11(dim), pr, y);
    if (left != NULL) {
        ctc_dense_mulv(dim, dim, left + H22(dim), pr, t);
        for (int i = 0; i < dim; i++) y[i] += t[i];
    }
    for (int i = 0; i < dim; i++) y[i] = b23l[i] - b13r[i] - y[i];
    gdca_factor_apply(dim, dim - nv, d->fwd_E + dim * dim * j, y, z);
    for (int i = 0; i < dim; i++) z[i] += pr[i];
}

/* dq_j = P^T (A1^R - A2^L) */
static inline void correct_qacc(const ctc_model *m, const ctc_data *d, int j, const double *a1r,
                                const double *a2l, double *dq, const int dim)
{
    const double *P = d->jnt_P + 3 * dim * j;
    for (int c = 0; c < m->jnt_nv[j]; c++) {
        double s = 0;
        for (int i = 0; i < dim; i++) s += P[c * dim + i] * (a1r[i] - a2l[i]);
        dq[m->jnt_vadr[j] + c] = s;
    }
}

static inline void correct_pass(const ctc_model *m, ctc_data *d, const double *r, double *dq,
                                const int dim)
{
    static const double zero[CTC_DENSE_MAX] = {0, 0, 0, 0, 0, 0};
    const int n = m->nbodies;

    /* assembly, children before parents: only the bias vectors change */
    for (int i = 0; i < m->ntree; i++) {
        const ctc_tree_node *node = &m->tree[i];
        const double *left = ctc_data_handles(m, d, node->left, 0);
        const double *right = ctc_data_handles(m, d, node->right, 0);
        double *out = ctc_data_handles(m, d, n + i, 0), *z = d->fwd_z + dim * node->joint;
        const double *b13l = bias(m, d, node->left, 0, zero);
        const double *b23r = bias(m, d, node->right, 1, zero);
        double t[CTC_DENSE_MAX];

        correct_joint(m, d, node->joint, left, right, bias(m, d, node->left, 1, zero),
                      bias(m, d, node->right, 0, zero), r, z, dim);
        /* b13 = b13^L - h12^L z and b23 = b23^R + h21^R z; out may not be either child */
        ctc_dense_mulv(dim, dim, left + H12(dim), z, t);
        for (int k = 0; k < dim; k++) out[H13(dim) + k] = b13l[k] - t[k];
        ctc_dense_tmulv(dim, dim, right + H12(dim), z, t);
        for (int k = 0; k < dim; k++) out[H23(dim) + k] = b23r[k] + t[k];
    }

    /* root: the ground joint 0 (y = -b13 - K P r) and the free end F2 = 0 */
    const double *root = ctc_data_handles(m, d, m->root, 0);
    const double *b13root = bias(m, d, m->root, 0, zero);
    double *tl = d->tload + (size_t)m->root * 2 * dim, a1[CTC_DENSE_MAX];
    correct_joint(m, d, 0, NULL, root, zero, b13root, r, d->fwd_z, dim);
    for (int i = 0; i < dim; i++) {
        tl[i] = d->fwd_z[i];
        tl[dim + i] = 0;
        d->jnt_load[i] += tl[i];
    }
    ctc_dense_mulv(dim, dim, root + H11(dim), tl, a1);
    for (int i = 0; i < dim; i++) a1[i] += b13root[i];
    correct_qacc(m, d, 0, a1, zero, dq, dim);

    /* disassembly, parents before children */
    for (int i = m->ntree - 1; i >= 0; i--) {
        const ctc_tree_node *node = &m->tree[i];
        const double *left = ctc_data_handles(m, d, node->left, 0);
        const double *right = ctc_data_handles(m, d, node->right, 0);
        const double *f1 = d->tload + (size_t)(n + i) * 2 * dim, *f2 = f1 + dim;
        const double *b23l = bias(m, d, node->left, 1, zero);
        const double *b13r = bias(m, d, node->right, 0, zero);
        const int j = node->joint;
        double fj[CTC_DENSE_MAX], a1r[CTC_DENSE_MAX], a2l[CTC_DENSE_MAX], t[CTC_DENSE_MAX];

        gdca_joint_load(dim, dim - m->jnt_nv[j], left, right, d->fwd_E + dim * dim * j,
                        d->fwd_z + dim * j, f1, f2, fj);
        /* A1^R = h11^R F + h12^R F2 + b13^R,  A2^L = h21^L F1 - h22^L F + b23^L */
        ctc_dense_mulv(dim, dim, right + H11(dim), fj, a1r);
        ctc_dense_mulv(dim, dim, right + H12(dim), f2, t);
        for (int k = 0; k < dim; k++) a1r[k] += t[k] + b13r[k];
        ctc_dense_tmulv(dim, dim, left + H12(dim), f1, a2l);
        ctc_dense_mulv(dim, dim, left + H22(dim), fj, t);
        for (int k = 0; k < dim; k++) a2l[k] += b23l[k] - t[k];
        correct_qacc(m, d, j, a1r, a2l, dq, dim);

        for (int k = 0; k < dim; k++) d->jnt_load[dim * j + k] += fj[k];
        gdca_pass_loads(dim, d->tload, node, f1, f2, fj);
    }
}

static CTC_SPECIALISE void correct_planar(const ctc_model *m, ctc_data *d, const double *r,
                                          double *dq)
{
    correct_pass(m, d, r, dq, 3);
}

static CTC_SPECIALISE void correct_spatial(const ctc_model *m, ctc_data *d, const double *r,
                                           double *dq)
{
    correct_pass(m, d, r, dq, 6);
}

void gdca_forward_correct(const ctc_model *m, ctc_data *d, const double *r, double *dq)
{
    if (m->form == CTC_FORM_PLANAR) {
        correct_planar(m, d, r, dq);
    } else {
        correct_spatial(m, d, r, dq);
    }
}
