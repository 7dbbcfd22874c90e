/*
 * gdca_forward_tseq.c - forward GDCA on a branched tree in the sequential order: every heavy path
 * assembled from its free tip, body by body, with each light subtree raked into its parent as it
 * is met (gdca_forward_seq.h).
 *
 * A chain's sequential order (gdca_forward_seq.c) joins single bodies from the free tip and from
 * the grounded base; on a tree the tip run alone serves every path, and needs no plan. Let S_k be
 * the assembly of body k and all its descendants, R_k body k with its light children's subtrees
 * raked in (gdca_rake.h; body k itself when it has none) and h its heavy child:
 *     S_k = R_k : S_h   at joint h,        S_k = R_k   for a leaf.
 * Every S_k holds free tips only, so of its handle equations only A1 = h11 F1 + h13 is used: by
 * the next tip-run step (Eq. 34, 36 with F2^R = 0, gdca_forward_seq.c) and by k's parent's rake,
 * which joins S_c of a light child c to the parent's point c exactly as a root joint is joined
 * to the ground. Bodies come after their parents (model.h), so a pass over k = n-1 .. 0 finds
 * every S_c and S_h it needs made. The ground children's S_g are joined to the ground at the
 * root: F_g = z_g. The disassembly runs k = 0 .. n-1 with F_k (the load on S_k at joint k) known:
 *     F_h = W_h h21(R_k) F_k + z_h,   qdd_h = P^T (K F_h - h21(R_k) F_k + h13(S_h) - h23(R_k) -
 * beta), then R_k's motion X from its loads (F_k, -F_h) gives each light child's load and
 * acceleration (gdca_rake.h). The order is the balanced plan's algebra on another binary tree: the
 * two agree to rounding. It is serial; a pass split over threads takes the plan (gdca_forward.c).
 *
 * Records (d->hfwd, 2n slots for a tree): slot k holds S_k's h11, h13 and K of joint h in its h22
 * slot; slot n + k holds R_k's whole record when k has light children. Joint loads go to
 * d->tload at [dim k] and then to d->jnt_load. The refinement's bias-free correction (correct =
 * GDCA_FWD_CORRECT) reuses E, K, the records' matrices and each R_k's M'^-1, as in
 * gdca_forward_seq.c; the reference form's bias-free pass (GDCA_FWD_BIASFREE) forms them.
 */
#include "gdca_forward_seq.h"

#include "gdca_forward_joint.h"
#include "gdca_rake.h"

typedef struct tseq_args {
    const ctc_model *m;
    ctc_data *d;
    const double *f; /* (nv) driving forces; correct: the force residual */
    double *qacc;    /* (nv) accelerations; correct: their correction */
} tseq_args;

/* 1 if body k has a light child */
static inline int tseq_raked(const ctc_model *m, int k)
{
    const int c = m->body_child[k];
    return c >= 0 && m->body_sibling[c] >= 0;
}

/* R_k's record: the raked slot, or body k's */
static inline double *tseq_R(const tseq_args *a, int k)
{
    const ctc_model *m = a->m;
    if (tseq_raked(m, k)) return a->d->hfwd + (size_t)(m->nbodies + k) * a->d->hsize;
    return a->d->hbody + (size_t)k * a->d->hsize;
}

/* R_k's h13 (off = H13) or h23 (H23): a plain body's are zero in the correction */
static inline const double *tseq_R_bias(const tseq_args *a, int k, int off, const int correct)
{
    if (correct && !tseq_raked(a->m, k)) return gdca_zero6;
    return tseq_R(a, k) + off;
}

/* S_k's record (its h11 and h13): slot k, or R_k's for a leaf */
static inline double *tseq_S(const tseq_args *a, int k)
{
    if (a->m->body_heavy[k] < 0) return tseq_R(a, k);
    return a->d->hfwd + (size_t)k * a->d->hsize;
}

static inline const double *tseq_S_bias(const tseq_args *a, int k, const int dim, const int correct)
{
    if (a->m->body_heavy[k] < 0) return tseq_R_bias(a, k, H13(dim), correct);
    return tseq_S(a, k) + H13(dim);
}

/* the lower of two joints, -1 meaning none */
static inline int tseq_first(int x, int y)
{
    if (x < 0) return y;
    return y < 0 || x < y ? x : y;
}

/* R_k from body k and its light children's S_c (their joints solved as root joints); returns the
   first singular joint or -1 */
static inline int tseq_rake(const tseq_args *a, int k, const int dim, const int correct)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    double s[CTC_DENSE_MAX * CTC_DENSE_MAX] = {0}, sb[CTC_DENSE_MAX] = {0};
    double ts[CTC_DENSE_MAX * CTC_DENSE_MAX], tb[CTC_DENSE_MAX], r[3], kappa[CTC_DENSE_MAX];
    int singular = -1;
    for (int c = m->body_child[k]; c >= 0; c = m->body_sibling[c]) {
        if (c == m->body_heavy[k]) continue;
        if (forward_joint(m, d, c, NULL, tseq_S(a, c), gdca_zero6, tseq_S_bias(a, c, dim, correct),
                          gdca_forward_beta(d, c, dim, correct), a->f, correct != GDCA_FWD_CORRECT,
                          NULL, dim) != 0) {
            singular = tseq_first(singular, c);
        }
        gdca_rake_point(d, k, c, dim, r, kappa);
        gdca_rake_light(dim, (int)m->joints[c].type, dim - m->jnt_nv[c], d->fwd_E + dim * dim * c,
                        r, correct ? NULL : kappa, d->fwd_z + dim * c,
                        correct == GDCA_FWD_CORRECT ? NULL : ts, tb);
        for (int i = 0; correct != GDCA_FWD_CORRECT && i < dim * dim; i++) s[i] += ts[i];
        for (int i = 0; i < dim; i++) sb[i] += tb[i];
    }
    double mm[CTC_DENSE_MAX * CTC_DENSE_MAX], b[CTC_DENSE_MAX], k1[CTC_DENSE_MAX];
    double k2[CTC_DENSE_MAX];
    if (correct != GDCA_FWD_CORRECT) {
        gdca_rake_body(m, d, k, dim, mm, b);
        for (int i = 0; i < dim * dim; i++) mm[i] += s[i];
    }
    if (correct) {
        for (int i = 0; i < dim; i++) b[i] = -sb[i];
    } else {
        for (int i = 0; i < dim; i++) b[i] -= sb[i];
        gdca_rake_kappa(d, k, dim, d->hr + 6 * k, k1);
        gdca_rake_kappa(d, k, dim, d->hr + 6 * k + 3, k2);
    }
    if (gdca_rake_record(dim, mm, b, d->hr + 6 * k, d->hr + 6 * k + 3, correct ? NULL : k1,
                         correct ? NULL : k2, gdca_rake_slot(d, k, dim), tseq_R(a, k),
                         correct != GDCA_FWD_CORRECT) != 0) {
        singular = tseq_first(singular, m->body_child[k]);
    }
    return singular;
}

/* S_k = R_k : S_h at joint h (correct: E and K reused): K, E, z, h11 and h13; returns h if D^T K D
   was not positive definite, else -1 */
static inline int tseq_assemble(const tseq_args *a, int k, int h, const int dim, const int correct)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const double *left = tseq_R(a, k), *b13l = tseq_R_bias(a, k, H13(dim), correct);
    double *out = d->hfwd + (size_t)k * d->hsize, t[CTC_DENSE_MAX],
           x[CTC_DENSE_MAX * CTC_DENSE_MAX];
    const int st =
        forward_joint(m, d, h, left, tseq_S(a, h), tseq_R_bias(a, k, H23(dim), correct),
                      tseq_S_bias(a, h, dim, correct), gdca_forward_beta(d, h, dim, correct), a->f,
                      correct != GDCA_FWD_CORRECT, out + H22(dim), dim);
    const double *e = d->fwd_E + dim * dim * h, *z = d->fwd_z + dim * h;
    if (correct != GDCA_FWD_CORRECT) {
        const ctc_joint_type type = m->joints[h].type;
        if (gdca_joint_factor_is_typed(dim, type)) { /* nc = dim - 1, a constant */
            gdca_mul_E_typed(dim, type, dim - 1, left + H12(dim), 0, e, x);
            gdca_downdate(dim, dim - 1, left + H11(dim), x, out + H11(dim));
        } else {
            const int nc = dim - m->jnt_nv[h];
            gdca_mul_E(dim, nc, left + H12(dim), 0, e, x);
            gdca_downdate(dim, nc, left + H11(dim), x, out + H11(dim));
        }
    }
    ctc_dense_mulv(dim, dim, left + H12(dim), z, t);
    for (int r = 0; r < dim; r++) out[H13(dim) + r] = b13l[r] - t[r];
    return st != 0 ? h : -1;
}

/* body k's disassembly from F_k: its heavy child's load and acceleration, then its light
   children's through R_k's motion */
static inline void tseq_disassemble(const tseq_args *a, int k, const int dim, const int correct)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int h = m->body_heavy[k];
    const double *left = tseq_R(a, k), *fk = d->tload + dim * k;
    double nfh[CTC_DENSE_MAX] = {0, 0, 0, 0, 0, 0};
    if (h >= 0) {
        double *fh = d->tload + dim * h, s[CTC_DENSE_MAX], x[CTC_DENSE_MAX];
        gdca_tmulv(dim, left + H12(dim), fk, s);
        gdca_factor_apply_typed(dim, m->joints[h].type, dim - m->jnt_nv[h],
                                d->fwd_E + dim * dim * h, s, fh);
        for (int r = 0; r < dim; r++) fh[r] += d->fwd_z[dim * h + r];
        /* qdd_h = P^T (K F_h - s + h13(S_h) - h23(R_k) - beta) */
        const double *b13r = tseq_S_bias(a, h, dim, correct);
        const double *b23l = tseq_R_bias(a, k, H23(dim), correct);
        gdca_tmulv(dim, d->hfwd + (size_t)k * d->hsize + H22(dim), fh, x); /* K is symmetric */
        for (int r = 0; r < dim; r++) {
            x[r] += b13r[r] - b23l[r] - s[r];
            nfh[r] = -fh[r];
        }
        forward_accel(m, d, h, x, gdca_zero6, gdca_forward_beta(d, h, dim, correct), a->qacc, dim);
    }
    if (!tseq_raked(m, k)) return;
    double xk[CTC_DENSE_MAX];
    gdca_rake_motion(dim, gdca_rake_slot(d, k, dim), d->hr + 6 * k, d->hr + 6 * k + 3, fk, nfh, xk);
    for (int c = m->body_child[k]; c >= 0; c = m->body_sibling[c]) {
        if (c == h) continue;
        const double *sc = tseq_S(a, c), *b13 = tseq_S_bias(a, c, dim, correct);
        double r[3], kappa[CTC_DENSE_MAX], ac[CTC_DENSE_MAX], a1[CTC_DENSE_MAX];
        double *fc = d->tload + dim * c;
        gdca_rake_point(d, k, c, dim, r, kappa);
        gdca_rake_child_load(dim, (int)m->joints[c].type, dim - m->jnt_nv[c],
                             d->fwd_E + dim * dim * c, d->fwd_z + dim * c, r,
                             correct ? NULL : kappa, xk, ac, fc);
        gdca_tmulv(dim, sc + H11(dim), fc, a1); /* h11 is symmetric */
        for (int i = 0; i < dim; i++) a1[i] += b13[i];
        forward_accel(m, d, c, a1, ac, gdca_forward_beta(d, c, dim, correct), a->qacc, dim);
    }
}

static inline void tseq_pass(const tseq_args *a, const int dim, const int correct)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int n = m->nbodies;
    int singular = -1;
    for (int k = n - 1; k >= 0; k--) {
        if (tseq_raked(m, k)) singular = tseq_first(singular, tseq_rake(a, k, dim, correct));
        if (m->body_heavy[k] >= 0) {
            singular = tseq_first(singular, tseq_assemble(a, k, m->body_heavy[k], dim, correct));
        }
    }
    for (int g = m->ground_child; g >= 0; g = m->body_sibling[g]) { /* the root: F_g = z_g */
        const double *sg = tseq_S(a, g), *b13 = tseq_S_bias(a, g, dim, correct);
        double *fg = d->tload + dim * g, a1[CTC_DENSE_MAX];
        if (forward_joint(m, d, g, NULL, sg, gdca_zero6, b13, gdca_forward_beta(d, g, dim, correct),
                          a->f, correct != GDCA_FWD_CORRECT, NULL, dim) != 0) {
            singular = tseq_first(singular, g);
        }
        for (int i = 0; i < dim; i++) fg[i] = d->fwd_z[dim * g + i];
        gdca_tmulv(dim, sg + H11(dim), fg, a1);
        for (int i = 0; i < dim; i++) a1[i] += b13[i];
        forward_accel(m, d, g, a1, gdca_zero6, gdca_forward_beta(d, g, dim, correct), a->qacc, dim);
    }
    d->singular_joint = singular;
    for (int k = 0; k < n; k++) tseq_disassemble(a, k, dim, correct);
    for (int i = 0; i < dim * n; i++) {
        d->jnt_load[i] = correct == GDCA_FWD_CORRECT    ? d->jnt_load[i] + d->tload[i]
                         : correct == GDCA_FWD_BIASFREE ? d->tload[i] + d->jnt_load_inv[i]
                                                        : d->tload[i];
    }
}

/* the pass specialised by form and mode (gdca_forward_joint.h) */
#define TSEQ_PASS(name, dim, mode)                                                                 \
    static CTC_SPECIALISE void tseq_##name(const tseq_args *a)                                     \
    {                                                                                              \
        tseq_pass(a, dim, mode);                                                                   \
    }

TSEQ_PASS(planar, 3, GDCA_FWD_FULL)
TSEQ_PASS(spatial, 6, GDCA_FWD_FULL)
TSEQ_PASS(correct_planar, 3, GDCA_FWD_CORRECT)
TSEQ_PASS(correct_spatial, 6, GDCA_FWD_CORRECT)
TSEQ_PASS(biasfree_planar, 3, GDCA_FWD_BIASFREE)
TSEQ_PASS(biasfree_spatial, 6, GDCA_FWD_BIASFREE)

/* by [spatial][mode] */
static void (*const tseq_fn[2][3])(const tseq_args *) = {
    {tseq_planar, tseq_correct_planar, tseq_biasfree_planar},
    {tseq_spatial, tseq_correct_spatial, tseq_biasfree_spatial}};

void gdca_forward_seq_tree(const ctc_model *m, ctc_data *d, const double *f, double *qacc, int mode)
{
    const tseq_args a = {m, d, f, qacc};
    tseq_fn[m->form != CTC_FORM_PLANAR][mode](&a);
}
