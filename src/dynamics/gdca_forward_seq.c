/*
 * gdca_forward_seq.c - forward GDCA in the sequential assembly order: two runs of single-body
 * assemblies, one from the free tip and one from the grounded base, that meet at the middle
 * joint (gdca_forward_seq.h).
 *
 * The tree: with r = (n - 1) / 2, the tip run joins body i to the assembly S_{i+1} of the bodies
 * after it, for i = n-2 down to r (S_i = i : S_{i+1}, S_{n-1} = body n-1); the base run joins the
 * assembly B_{k-1} of the ground and bodies 0..k-1 to body k at joint k, for k = 0 up to r - 1
 * (B_k = B_{k-1} : k, B_{-1} = the ground); the root joins B_{r-1} to S_r at joint r. Both runs
 * join consecutive bodies, so they hold while every body k's parent is k - 1 (model.h
 * body_parent: a chain; gdca_forward_order_seq takes this order on chains only), which each
 * assembly asserts. Every S_i
 * holds the free tip (its F2 = 0) and every B_k the ground (joint 0 included, no handle 1), so of
 * their handle equations (data.h) only
 *     S_i:  A1 = h11 F1 + h13,        B_k:  A2 = h22 F2 + h23
 * are ever used: no assembly forms h12, and each forms one of h11, h22 - about half a balanced
 * tree node's work. The two runs are independent until the root, and the loop interleaves them:
 * a run is a chain of dependent steps (each joint's factor needs the assembly before it), and
 * the two halves' chains overlap in the processor.
 *
 * At each joint (gdca_tree.h, Eq. 27 and 34-39 with F2^R = 0, or with no F1^L), with
 *     K = h11^R + h22^L,   W = E E^T = D (D^T K D)^-1 D^T,
 *     z = W (b23^L - b13^R + beta - K P f) + P f:
 *     tip, joint j = i + 1, L = body i, R = S_{i+1}:
 *         h11(S_i) = h11^L - A A^T,  A = h12^L E,      h13(S_i) = h13^L - h12^L z
 *     base, joint k, L = B_{k-1}, R = body k:
 *         h22(B_k) = h22^R - B B^T,  B = h21^R E,      h23(B_k) = h23^R + h21^R z
 *     root, joint r, L = B_{r-1} (the ground: h22 = h23 = 0), R = S_r:  F_r = z_r.
 * The disassembly from the root outwards, with F_k the load on the right part at joint k:
 *     tip:   F_j = W h21^L F_i + z_j,        base:  F_k = W h12^R F_{k+1} + z_k,
 * and qdd = P^T (A1^R - A2^L - beta) with A1^R - A2^L = K F - s + b13^R - b23^L, s the product
 * just formed (h21^L F_i, or h12^R F_{k+1}). Each S_i's record keeps h11, h13 in their slots and
 * K of joint i + 1 in its h22 slot; each B_k's keeps h22, h23 and K of joint k in its h11 slot.
 * The order is the balanced tree's algebra on another binary tree, so the two agree to rounding
 * (and are about equally accurate: bench/NOTEBOOK.md, "Accuracy: both orders"); it has no
 * parallel depth to offer, which is why a pass split over threads takes the balanced tree.
 *
 * In spatial form the products that read a matrix by rows run on 6-vectors (gdca_tree.h): those
 * with the symmetric K, h11 and h22 (K P f and the hinge factor's K n for revolute and prismatic
 * joints), those with h12^T, and the base run's downdate. The products with h12 itself (the tip
 * run's downdate and h13, the base run's disassembly) read its columns and stay scalar (a
 * transposed copy of h12 costs the handles more than it saves: bench/NOTEBOOK.md, "Latest").
 *
 * The refinement's correction (gdca_refine.h) is this pass in a bias-free mode (correct =
 * GDCA_FWD_CORRECT, gdca_forward_joint.h), as in gdca_forward.c: bodies' h13 = h23 = 0, beta = 0,
 * E, K and the records' matrices reused, the vectors recomputed into the records' bias slots,
 * d->fwd_z and d->tload (the correction's own joint loads, which are added to d->jnt_load). The
 * reference form's pass (GDCA_FWD_BIASFREE; gdca.h ctc_gdca_forward_from) is bias-free too but
 * forms E, K and the matrices as the full pass does, and writes its loads.
 */
#include "gdca_forward_seq.h"

#include <assert.h>

#include "gdca_forward_joint.h"

/* what one pass shares: the model, the data, the forces and the results, and the middle joint */
typedef struct seq_args {
    const ctc_model *m;
    ctc_data *d;
    const double *f; /* (nv) driving forces; correct: the force residual */
    double *qacc;    /* (nv) accelerations; correct: their correction */
    int r;           /* the root joint: (n - 1) / 2 */
} seq_args;

/* body k's record */
static inline const double *seq_body(const seq_args *a, int k)
{
    return a->d->hbody + (size_t)k * a->d->hsize;
}

/* the record of S_i (i >= r: the tip's body record for i = n - 1) or B_k (k < r): node slot i */
static inline double *seq_part(const seq_args *a, int i)
{
    if (i == a->m->nbodies - 1) return a->d->hbody + (size_t)i * a->d->hsize;
    return a->d->hfwd + (size_t)i * a->d->hsize;
}

/* a body's bias h13 or h23 (at offset off): zero in the correction */
static inline const double *seq_body_bias(const seq_args *a, int k, int off, const int correct)
{
    return correct ? gdca_zero6 : seq_body(a, k) + off;
}

/* h13 of S_i: the tip body's own is zero in the correction */
static inline const double *seq_tip_bias(const seq_args *a, int i, const int dim, const int correct)
{
    if (i == a->m->nbodies - 1) return seq_body_bias(a, i, H13(dim), correct);
    return seq_part(a, i) + H13(dim);
}

/* h23 of B_k, the ground's (k < 0) zero */
static inline const double *seq_base_bias(const seq_args *a, int k, const int dim)
{
    return k < 0 ? gdca_zero6 : seq_part(a, k) + H23(dim);
}

/* out = h - X X^T with X = M E (trans = 0: the tip run, M = h12^L) or M^T E (trans = 1: the base
   run, M = h12^R), E (dim x nc) the factor of joint j, its zeros skipped for the joint types
   gdca_joint_factor_typed specialises; the base run's spatial hinges by M's rows as 6-vectors */
static inline void seq_downdate_joint(const seq_args *a, int j, const double *h, const double *mm,
                                      int trans, const double *e, double *out, const int dim)
{
    const ctc_joint_type type = a->m->joints[j].type;
    double x[CTC_DENSE_MAX * CTC_DENSE_MAX];
    const int u = gdca_hinge_u(dim, type);
    if (trans && u >= 0) {
        gdca_downdate_hinge_t(h, mm, e, u, out);
        return;
    }
    if (gdca_joint_factor_is_typed(dim, type)) { /* nc = dim - 1, a constant */
        gdca_mul_E_typed(dim, type, dim - 1, mm, trans, e, x);
        gdca_downdate(dim, dim - 1, h, x, out);
        return;
    }
    const int nc = dim - a->m->jnt_nv[j];
    gdca_mul_E(dim, nc, mm, trans, e, x);
    gdca_downdate(dim, nc, h, x, out);
}

/* the tip run's assembly of S_i = i : S_{i+1} at joint j = i + 1 (correct: E and K reused): K,
   E, z, h11 and h13; returns j if D^T K D was not positive definite, else -1 */
static inline int seq_tip_assemble(const seq_args *a, int i, const int dim, const int correct)
{
    ctc_data *d = a->d;
    const int j = i + 1;
    assert(a->m->body_parent[j] == i);
    const double *left = seq_body(a, i), *right = seq_part(a, j);
    const double *b13l = seq_body_bias(a, i, H13(dim), correct);
    double *out = d->hfwd + (size_t)i * d->hsize, t[CTC_DENSE_MAX];
    const int st =
        forward_joint(a->m, d, j, left, right, seq_body_bias(a, i, H23(dim), correct),
                      seq_tip_bias(a, j, dim, correct), gdca_forward_beta(a->d, j, dim, correct),
                      a->f, correct != GDCA_FWD_CORRECT, out + H22(dim), dim);
    const double *e = d->fwd_E + dim * dim * j, *z = d->fwd_z + dim * j;
    if (correct != GDCA_FWD_CORRECT) {
        seq_downdate_joint(a, j, left + H11(dim), left + H12(dim), 0, e, out + H11(dim), dim);
    }
    ctc_dense_mulv(dim, dim, left + H12(dim), z, t);
    for (int r = 0; r < dim; r++) out[H13(dim) + r] = b13l[r] - t[r];
    return st != 0 ? j : -1;
}

/* the base run's assembly of B_k = B_{k-1} : k at joint k: K, E, z, h22 and h23; returns k if
   singular, else -1 */
static inline int seq_base_assemble(const seq_args *a, int k, const int dim, const int correct)
{
    ctc_data *d = a->d;
    assert(a->m->body_parent[k] == k - 1);
    const double *left = k > 0 ? seq_part(a, k - 1) : NULL, *right = seq_body(a, k);
    const double *b23r = seq_body_bias(a, k, H23(dim), correct);
    double *out = d->hfwd + (size_t)k * d->hsize, t[CTC_DENSE_MAX];
    const int st = forward_joint(a->m, d, k, left, right, seq_base_bias(a, k - 1, dim),
                                 seq_body_bias(a, k, H13(dim), correct),
                                 gdca_forward_beta(a->d, k, dim, correct), a->f,
                                 correct != GDCA_FWD_CORRECT, out + H11(dim), dim);
    const double *e = d->fwd_E + dim * dim * k, *z = d->fwd_z + dim * k;
    if (correct != GDCA_FWD_CORRECT) {
        seq_downdate_joint(a, k, right + H22(dim), right + H12(dim), 1, e, out + H22(dim), dim);
    }
    gdca_tmulv(dim, right + H12(dim), z, t);
    for (int r = 0; r < dim; r++) out[H23(dim) + r] = b23r[r] + t[r];
    return st != 0 ? k : -1;
}

/* qdd_j = P^T (K F - s + b13^R - b23^L - beta) for the stored K */
static inline void seq_accel(const seq_args *a, int j, const double *kk, const double *fj,
                             const double *s, const double *b13r, const double *b23l, const int dim,
                             const int correct)
{
    double x[CTC_DENSE_MAX];
    gdca_tmulv(dim, kk, fj, x); /* K is symmetric */
    for (int r = 0; r < dim; r++) x[r] += b13r[r] - b23l[r] - s[r];
    forward_accel(a->m, a->d, j, x, gdca_zero6, gdca_forward_beta(a->d, j, dim, correct), a->qacc,
                  dim);
}

/* the tip run's disassembly at joint j = i + 1: F_j from F_i */
static inline void seq_tip_disassemble(const seq_args *a, int i, const int dim, const int correct)
{
    ctc_data *d = a->d;
    const int j = i + 1;
    const double *left = seq_body(a, i), *fi = d->tload + dim * i;
    double *fj = d->tload + dim * j, s[CTC_DENSE_MAX];
    gdca_tmulv(dim, left + H12(dim), fi, s);
    gdca_factor_apply_typed(dim, a->m->joints[j].type, dim - a->m->jnt_nv[j],
                            d->fwd_E + dim * dim * j, s, fj);
    for (int r = 0; r < dim; r++) fj[r] += d->fwd_z[dim * j + r];
    seq_accel(a, j, d->hfwd + (size_t)i * d->hsize + H22(dim), fj, s,
              seq_tip_bias(a, j, dim, correct), seq_body_bias(a, i, H23(dim), correct), dim,
              correct);
}

/* the base run's disassembly at joint k: F_k from F_{k+1} */
static inline void seq_base_disassemble(const seq_args *a, int k, const int dim, const int correct)
{
    ctc_data *d = a->d;
    const double *right = seq_body(a, k), *fn = d->tload + dim * (k + 1);
    double *fk = d->tload + dim * k, s[CTC_DENSE_MAX];
    ctc_dense_mulv(dim, dim, right + H12(dim), fn, s);
    gdca_factor_apply_typed(dim, a->m->joints[k].type, dim - a->m->jnt_nv[k],
                            d->fwd_E + dim * dim * k, s, fk);
    for (int r = 0; r < dim; r++) fk[r] += d->fwd_z[dim * k + r];
    seq_accel(a, k, d->hfwd + (size_t)k * d->hsize + H11(dim), fk, s,
              seq_body_bias(a, k, H13(dim), correct), seq_base_bias(a, k - 1, dim), dim, correct);
}

/* the root, joint r between B_{r-1} (the ground for r = 0) and S_r: F_r = z_r; returns r if
   singular, else -1 */
static inline int seq_root(const seq_args *a, const int dim, const int correct)
{
    ctc_data *d = a->d;
    const int r = a->r;
    const double *left = r > 0 ? seq_part(a, r - 1) : NULL, *right = seq_part(a, r);
    const double *b23l = seq_base_bias(a, r - 1, dim), *b13r = seq_tip_bias(a, r, dim, correct);
    double *fr = d->tload + dim * r, a1[CTC_DENSE_MAX], a2[CTC_DENSE_MAX];
    int st =
        forward_joint(a->m, d, r, left, right, b23l, b13r, gdca_forward_beta(a->d, r, dim, correct),
                      a->f, correct != GDCA_FWD_CORRECT, NULL, dim);
    for (int i = 0; i < dim; i++) fr[i] = d->fwd_z[dim * r + i];
    /* A1^R = h11^R F + h13^R,  A2^L = -h22^L F + h23^L */
    gdca_tmulv(dim, right + H11(dim), fr, a1); /* h11 and h22 are symmetric */
    for (int i = 0; i < dim; i++) a1[i] += b13r[i];
    if (left != NULL) {
        gdca_tmulv(dim, left + H22(dim), fr, a2);
        for (int i = 0; i < dim; i++) a2[i] = b23l[i] - a2[i];
    } else {
        for (int i = 0; i < dim; i++) a2[i] = 0;
    }
    forward_accel(a->m, d, r, a1, a2, gdca_forward_beta(a->d, r, dim, correct), a->qacc, dim);
    return st != 0 ? r : -1;
}

/* the lower of two joints, -1 meaning none */
static inline int seq_first(int x, int y)
{
    if (x < 0) return y;
    return y < 0 || x < y ? x : y;
}

static inline void seq_pass(const seq_args *a, const int dim, const int correct)
{
    ctc_data *d = a->d;
    const int n = a->m->nbodies, r = a->r, ntip = n - 1 - r;
    int singular = -1;

    /* the two runs interleaved: tip node n - 2 - t and base node t; ntip >= r */
    for (int t = 0; t < ntip; t++) {
        singular = seq_first(singular, seq_tip_assemble(a, n - 2 - t, dim, correct));
        if (t < r) singular = seq_first(singular, seq_base_assemble(a, t, dim, correct));
    }
    d->singular_joint = seq_first(singular, seq_root(a, dim, correct));
    for (int t = 0; t < ntip; t++) {
        seq_tip_disassemble(a, r + t, dim, correct);
        if (t < r) seq_base_disassemble(a, r - 1 - t, dim, correct);
    }
    for (int i = 0; i < dim * n; i++) {
        d->jnt_load[i] = correct == GDCA_FWD_CORRECT    ? d->jnt_load[i] + d->tload[i]
                         : correct == GDCA_FWD_BIASFREE ? d->tload[i] + d->jnt_load_inv[i]
                                                        : d->tload[i];
    }
}

/* the pass specialised by form and mode (gdca_forward_joint.h) */
#define SEQ_PASS(name, dim, mode)                                                                  \
    static CTC_SPECIALISE void seq_##name(const seq_args *a)                                       \
    {                                                                                              \
        seq_pass(a, dim, mode);                                                                    \
    }

SEQ_PASS(planar, 3, GDCA_FWD_FULL)
SEQ_PASS(spatial, 6, GDCA_FWD_FULL)
SEQ_PASS(correct_planar, 3, GDCA_FWD_CORRECT)
SEQ_PASS(correct_spatial, 6, GDCA_FWD_CORRECT)
SEQ_PASS(biasfree_planar, 3, GDCA_FWD_BIASFREE)
SEQ_PASS(biasfree_spatial, 6, GDCA_FWD_BIASFREE)

/* by [spatial][mode] */
static void (*const seq_fn[2][3])(const seq_args *) = {
    {seq_planar, seq_correct_planar, seq_biasfree_planar},
    {seq_spatial, seq_correct_spatial, seq_biasfree_spatial}};

void gdca_forward_seq(const ctc_model *m, ctc_data *d, const double *f, double *qacc, int mode)
{
    const seq_args a = {m, d, f, qacc, (m->nbodies - 1) / 2};
    seq_fn[m->form != CTC_FORM_PLANAR][mode](&a);
}
