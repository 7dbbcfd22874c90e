/*
 * gdca_forward.c - forward dynamics by GDCA (paper section 3; DESIGN.md section 4).
 *
 * The driving forces f are known, so at joint j the load on the right part is
 * F = D lambda + P f with the constraint multipliers lambda unknown. Eliminating the joint
 * acceleration with D^T (Eq. 15) gives
 *     C = D^T K D,  W = D C^-1 D^T,  K = h11^R + h22^L,
 *     Y = h23^L - h13^R + beta - K P f,   F = W (h21^L F1 - h12^R F2 + Y) + P f,
 * which gdca_tree.h turns into the assembled record. At the root, joint 0 joins the ground (at
 * rest, no record: h22 = h23 = 0) to the whole chain, whose free end carries F2 = 0. In the
 * disassembly each node's joint load gives its acceleration
 *     qdd = P^T (A1^R - A2^L - beta),
 *     A1^R = h11^R F + h12^R F2 + h13^R,   A2^L = h21^L F1 - h22^L F + h23^L.
 * A loop model's root has both handles jointed to the ground (gdca_loop.h): joint 0 and the
 * closing joint, each with its constraint load unknown and its driving force known; dependent
 * joints' driving forces are taken as zero. A loop closed on body b splits the tree's root at
 * joint b + 1, and the root solve takes that node's two parts with joints 0, b + 1 and the
 * closing joint together.
 *
 * The refinement's correction (gdca_refine.h) is this pass in a bias-free mode (correct =
 * GDCA_FWD_CORRECT, gdca_forward_joint.h): every body's h13 = h23 = 0 and every beta = 0, the
 * driving forces replaced by the force residual, the factors E and the assembled matrices reused,
 * so that only the vectors are recomputed, by the same kernels and on the same threads. The
 * reference form (gdca.h ctc_gdca_forward_from) is the same bias-free pass forming its own
 * factors and matrices (GDCA_FWD_BIASFREE): with f_ref = M a_ref + N from the composite inverse,
 *     M qdd + N = f  <=>  M (qdd - a_ref) = f - f_ref,
 * so qdd = a_ref + dq with dq the bias-free pass's solution for the forces f - f_ref; its joint
 * loads are those of M dq = f - f_ref alone, and the whole loads add the reference's, which the
 * composite inverse recorded (d->jnt_load_inv): the loads are linear in (qdd, f) once the state's
 * velocity and gravity terms are all on the reference's side.
 *
 * On a branched tree the plan's SUM and RAKE nodes rake each light subtree into its parent body
 * (gdca_rake.h): its root joint is solved as a chain's ground joint is, with the parent's point
 * in place of the ground, and its articulated terms added to the parent's inertia; their
 * disassembly gives the joint's load and acceleration and the subtree's terminal loads (F, 0).
 * Each ground child's subtree is joined to the ground at the root.
 *
 * This file is the pass over the model's tree (balanced; its root split at a loop's first joint
 * when the loop closes on a body: model.h), which loop models and passes split over threads
 * take (gdca_forward_order_seq below); other open-chain passes take the sequential order
 * (gdca_forward_seq.c), with the per-joint kernels of gdca_forward_joint.h in common. The nodes of
 * one tree height are independent: each node's assembly writes only its own record and its joint's
 * E and z, its disassembly only its joint's load and acceleration and its two children's terminal
 * loads, so gdca_par.c may split a height over threads (ctc_data_set_threads) with bitwise the
 * serial results; the root stays on the caller's thread.
 */
#include "gdca.h"

#include <math.h>
#include <string.h>

#include "gdca_forward_joint.h"
#include "gdca_forward_seq.h"
#include "gdca_inverse_loop.h"
#include "gdca_loop.h"
#include "gdca_par.h"
#include "gdca_rake.h"
#include "gdca_refine.h"
#include "gdca_tree.h"
#include "handles.h"

/* When the forward pass splits over threads (gdca_par.h): the least nodes per chunk of one tree
 * height, and the least chain length. Open chains take the tree on threads only from
 * FORWARD_TREE_MIN_BODIES_* below, so the least lengths here act on loop models and on a forced
 * tree order (d->opt.fwd_order). Each is where a split CTC evaluation first gains on 2 threads:
 * bench/NOTEBOOK.md, "Parallel assembly" ("The thresholds"). */
#define FORWARD_GRAIN_PLANAR 2
#define FORWARD_GRAIN_SPATIAL 2
#define FORWARD_MIN_BODIES_PLANAR 512
#define FORWARD_MIN_BODIES_SPATIAL 128

/* The least chain length from which an open chain's forward pass may take the balanced tree,
 * split over threads, instead of the sequential order on one thread (gdca_forward_seq.h), when
 * the data has two threads or more; from there the evaluation gate (data.h ctc_eval_gate) times
 * both ways and takes the faster. Half the length where a CTC evaluation on 2
 * threads first gained over the sequential order on a loaded 2-core machine (bench/NOTEBOOK.md,
 * "Threads against the sequential order"), so that a quieter or wider machine can gain below it. */
#define FORWARD_TREE_MIN_BODIES_PLANAR 2048
#define FORWARD_TREE_MIN_BODIES_SPATIAL 512

/* What the stages of one forward pass share (gdca_par.h). The same pass, with correct = 1 (a
 * constant in each stage function, so each mode compiles without the other's branches), is
 * the refinement's bias-free correction (gdca_refine.h): every body's h13 = h23 = 0 and every
 * beta = 0, the factors E and the records' matrices h11, h12, h22 are those of the full pass just
 * made, and only the vectors are recomputed: z, the nodes' biases (b13, b23, held in the node
 * records' h13, h23), the joint loads (added to d->jnt_load) and the accelerations. */
typedef struct forward_args {
    const ctc_model *m;
    ctc_data *d;
    const double *f; /* (nv; nvx for loops) driving forces; correct: the force residual r */
    double *qacc;    /* (nv; nvx for loops) accelerations; correct: their correction M^-1 r */
} forward_args;

/* the bias h13 (which = 0) or h23 (which = 1) of assembly index x: its record's, but zero for a
   body in the correction */
static inline const double *forward_bias(const forward_args *a, int x, int which, const int dim,
                                         const int correct)
{
    if (correct && x < a->m->nbodies) return gdca_zero6;
    return ctc_data_handles(a->m, a->d, x, 0) + (which ? H23(dim) : H13(dim));
}

/* the boundary joint k's end of a loop model's root problem (gdca_loop.h): its load is unknown
 * along D, its driving force (correct: its force residual) known */
static inline gdca_end forward_end(const forward_args *a, int k, double *pf, const double *off,
                                   const int dim, const int correct)
{
    const ctc_model *m = a->m;
    const ctc_data *d = a->d;
    gdca_joint_map(dim, m->jnt_nv[k], d->jnt_P + 3 * dim * k, a->f + m->jnt_vadr[k], pf);
    return (gdca_end){d->jnt_D + dim * dim * k, dim - m->jnt_nv[k], pf,
                      gdca_forward_beta(a->d, k, dim, correct), off};
}

/* the condition estimate a loop model's forward pass records: its root solve's, which on a model
 * with augmented bodies (model.h "singular bodies") carries their augmented mobility (about 1e5
 * for a massless tip that only the closure holds) rather than the loop's; there the dependent
 * joints' kinematic estimate (gdca_inverse_loop.h) when it is defined */
static inline double forward_loop_cond(const ctc_model *m, const ctc_data *d, double root)
{
    if (m->nsingular == 0) return root;
    const double kin = gdca_loop_dependent_cond(m, d);
    return isnan(kin) ? root : kin;
}

/* a loop model's root (gdca_loop.h): the loop's record R, joint 0 and the closing joint n on the
 * ground; or, for a loop on body b, the root's two parts L (bodies 0..b) and R with joints 0,
 * b + 1 and n, whose loads it hands to the parts' disassembly (the pass leaves the top node to
 * it: gdca_par.h root_takes_top). The closure's right-hand side is the Baumgarte term, or in the
 * correction minus the closure residual d->loop_rho (gdca_refine.h). */
static inline void forward_loop_root(const forward_args *a, const int dim, const int correct)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int n = m->nbodies, j = m->loop_first;
    const int left = j > 0 ? m->tree[m->ntree - 1].left : -1;
    const int right = j > 0 ? m->tree[m->ntree - 1].right : m->root;
    double pf0[CTC_DENSE_MAX], pfj[CTC_DENSE_MAX], pfn[CTC_DENSE_MAX], off[CTC_DENSE_MAX];
    gdca_loop_sol s;

    if (correct) {
        for (int c = 0; c < dim - m->jnt_nv[n]; c++) off[c] = -d->loop_rho[c];
    } else {
        gdca_loop_offset(m, d, off);
    }
    gdca_loop_root p = {
        .dim = dim,
        .l = left >= 0 ? ctc_data_handles(m, d, left, 0) : NULL,
        .r = ctc_data_handles(m, d, right, 0),
        .shift = d->loop_r,
        .gam = correct ? gdca_zero6 : d->loop_gam,
        .e0 = forward_end(a, 0, pf0, NULL, dim, correct),
        .ej = forward_end(a, j, pfj, NULL, dim, correct),
        .en = forward_end(a, n, pfn, off, dim, correct),
        .rb = {forward_bias(a, right, 0, dim, correct), forward_bias(a, right, 1, dim, correct)}};
    if (left >= 0) {
        p.lb[0] = forward_bias(a, left, 0, dim, correct);
        p.lb[1] = forward_bias(a, left, 1, dim, correct);
    }
    if (gdca_loop_solve(&p, &s) != 0 && d->singular_joint < 0) d->singular_joint = n;
    if (!correct) d->loop_cond = forward_loop_cond(m, d, s.cond);
    gdca_loop_hand_down(m, &s, d->loop_r, correct, d->tload, d->jnt_load);
    if (j > 0) {
        forward_accel(m, d, 0, s.al1, gdca_zero6, gdca_forward_beta(a->d, 0, dim, correct), a->qacc,
                      dim);
    }
    forward_accel(m, d, j, s.ar1, j > 0 ? s.al2 : gdca_zero6,
                  gdca_forward_beta(a->d, j, dim, correct), a->qacc, dim);
    /* A(child) = A2 + P qdd + beta */
    forward_accel(m, d, n, s.ab, s.ar2, gdca_forward_beta(a->d, n, dim, correct), a->qacc, dim);
}

/* light child c's terms for body k's rake (gdca_rake.h), its subtree assembled at x: joint c's
   E and z as a root joint's (the full pass factors it), then s (NULL: not formed) and b; returns
   as forward_joint */
static inline int forward_light(const forward_args *a, int k, int c, int x, double *s, double *b,
                                const int dim, const int correct)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    double r[3], kappa[CTC_DENSE_MAX];
    int st =
        forward_joint(m, d, c, NULL, ctc_data_handles(m, d, x, 0), gdca_zero6,
                      forward_bias(a, x, 0, dim, correct), gdca_forward_beta(d, c, dim, correct),
                      a->f, correct != GDCA_FWD_CORRECT, NULL, dim);
    gdca_rake_point(d, k, c, dim, r, kappa);
    gdca_rake_light(dim, (int)m->joints[c].type, dim - m->jnt_nv[c], d->fwd_E + dim * dim * c, r,
                    correct ? NULL : kappa, d->fwd_z + dim * c, s, b);
    return st;
}

/* the terms of operand x (a light child's subtree when c >= 0, else a SUM node's partial sums)
   of a SUM or RAKE node of body k, added to s and b (add = 0: written) */
static inline int forward_operand(const forward_args *a, int k, int x, int c, double *s, double *b,
                                  int add, const int dim, const int correct)
{
    double ts[CTC_DENSE_MAX * CTC_DENSE_MAX], tb[CTC_DENSE_MAX];
    const double *ps = ts, *pb = tb;
    int st = 0;
    if (c >= 0) {
        st = forward_light(a, k, c, x, correct == GDCA_FWD_CORRECT ? NULL : ts, tb, dim, correct);
    } else {
        const double *rec = ctc_data_handles(a->m, a->d, x, 0);
        ps = rec + H11(dim), pb = rec + H13(dim);
    }
    for (int i = 0; correct != GDCA_FWD_CORRECT && i < dim * dim; i++)
        s[i] = add ? s[i] + ps[i] : ps[i];
    for (int i = 0; i < dim; i++) b[i] = add ? b[i] + pb[i] : pb[i];
    return st;
}

/* a SUM node's partial sums, or a RAKE node's pseudo-body record (gdca_rake.h); returns -1, or
   0 when a light child's joint (or the pseudo-body's inertia) is singular */
static inline int forward_rake_node(const forward_args *a, const ctc_tree_node *node, double *out,
                                    const int dim, const int correct)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int k = node->body;
    int st = forward_operand(a, k, node->left, node->ljoint, out + H11(dim), out + H13(dim), 0, dim,
                             correct);
    if (node->kind == CTC_NODE_SUM) {
        st |= forward_operand(a, k, node->right, node->rjoint, out + H11(dim), out + H13(dim), 1,
                              dim, correct);
        return st;
    }
    double mm[CTC_DENSE_MAX * CTC_DENSE_MAX], b[CTC_DENSE_MAX], sb[CTC_DENSE_MAX];
    double s[CTC_DENSE_MAX * CTC_DENSE_MAX], k1[CTC_DENSE_MAX], k2[CTC_DENSE_MAX];
    st |= forward_operand(a, k, node->left, node->ljoint, s, sb, 0, dim, correct);
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
    st |= gdca_rake_record(dim, mm, b, d->hr + 6 * k, d->hr + 6 * k + 3, correct ? NULL : k1,
                           correct ? NULL : k2, gdca_rake_slot(d, k, dim), out,
                           correct != GDCA_FWD_CORRECT);
    return st;
}

/* a light child c's disassembly from its parent k's motion x (gdca_rake.h): its joint's load,
   acceleration, and its subtree's terminal loads (F_c, 0) at x's assembly index sub */
static inline void forward_light_down(const forward_args *a, int k, int c, int sub, const double *x,
                                      const int dim, const int correct)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const double *rec = ctc_data_handles(m, d, sub, 0),
                 *b13 = forward_bias(a, sub, 0, dim, correct);
    double r[3], kappa[CTC_DENSE_MAX], ac[CTC_DENSE_MAX], fc[CTC_DENSE_MAX], a1[CTC_DENSE_MAX];
    double *tl = d->tload + (size_t)sub * 2 * dim, *load = d->jnt_load + dim * c;
    gdca_rake_point(d, k, c, dim, r, kappa);
    gdca_rake_child_load(dim, (int)m->joints[c].type, dim - m->jnt_nv[c], d->fwd_E + dim * dim * c,
                         d->fwd_z + dim * c, r, correct ? NULL : kappa, x, ac, fc);
    ctc_dense_mulv(dim, dim, rec + H11(dim), fc, a1);
    for (int i = 0; i < dim; i++) {
        a1[i] += b13[i];
        tl[i] = fc[i];
        tl[dim + i] = 0;
        load[i] = correct == GDCA_FWD_CORRECT ? load[i] + fc[i] : fc[i];
    }
    forward_accel(m, d, c, a1, ac, gdca_forward_beta(d, c, dim, correct), a->qacc, dim);
}

/* a SUM or RAKE node's disassembly: the raked body's motion X (a RAKE's from its loads, a SUM's
   from its parent node), handed to each operand */
static inline void forward_rake_down(const forward_args *a, int i, const int dim, const int correct)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const ctc_tree_node *node = &m->tree[i];
    const int k = node->body;
    const double *tl = d->tload + (size_t)(m->nbodies + i) * 2 * dim;
    double x[CTC_DENSE_MAX];
    if (node->kind == CTC_NODE_RAKE) {
        gdca_rake_motion(dim, gdca_rake_slot(d, k, dim), d->hr + 6 * k, d->hr + 6 * k + 3, tl,
                         tl + dim, x);
    } else {
        for (int r = 0; r < dim; r++) x[r] = tl[r];
    }
    const int ops = node->kind == CTC_NODE_SUM ? 2 : 1;
    for (int o = 0; o < ops; o++) {
        const int sub = o ? node->right : node->left, c = o ? node->rjoint : node->ljoint;
        if (c >= 0) {
            forward_light_down(a, k, c, sub, x, dim, correct);
        } else {
            double *t = d->tload + (size_t)sub * 2 * dim;
            for (int r = 0; r < dim; r++) t[r] = x[r];
        }
    }
}

/* assembly of tree nodes lo..hi-1, children before parents; returns the first node whose joint
   is singular, or -1 */
static inline int forward_assemble(const forward_args *a, int lo, int hi, const int dim,
                                   const int correct, const int tree)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int hs = d->hsize;
    int first = -1;
    for (int i = lo; i < hi; i++) {
        const ctc_tree_node *node = &m->tree[i];
        if (tree && node->kind != CTC_NODE_JOIN) {
            if (forward_rake_node(a, node, d->hfwd + (size_t)i * hs, dim, correct) != 0 &&
                first < 0) {
                first = i;
            }
            continue;
        }
        const double *left = ctc_data_handles(m, d, node->left, 0);
        const double *right = ctc_data_handles(m, d, node->right, 0);
        const int j = node->joint, nc = dim - m->jnt_nv[j];
        const double *e = d->fwd_E + dim * dim * j, *z = d->fwd_z + dim * j;
        double *out = d->hfwd + (size_t)i * hs;
        if (forward_joint(m, d, j, left, right, forward_bias(a, node->left, 1, dim, correct),
                          forward_bias(a, node->right, 0, dim, correct),
                          gdca_forward_beta(a->d, j, dim, correct), a->f,
                          correct != GDCA_FWD_CORRECT, NULL, dim) != 0 &&
            first < 0) {
            first = i;
        }
        if (correct != GDCA_FWD_CORRECT) gdca_assemble(dim, nc, left, right, e, z, out);
        if (correct) { /* the biases again, from the bodies' zero ones */
            gdca_assemble_bias(dim, left, right, forward_bias(a, node->left, 0, dim, correct),
                               forward_bias(a, node->right, 1, dim, correct), z, out);
        }
    }
    return first;
}

/* ground child j's joint to its subtree, assembled at x, whose free end carries F2 = 0 */
static inline void forward_root_joint(const forward_args *a, int j, int x, const int dim,
                                      const int correct)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const double *root = ctc_data_handles(m, d, x, 0);
    const double *b13 = forward_bias(a, x, 0, dim, correct),
                 *beta = gdca_forward_beta(a->d, j, dim, correct);
    double *tl = d->tload + (size_t)x * 2 * dim, a1[CTC_DENSE_MAX], *load = d->jnt_load + dim * j;
    if (forward_joint(m, d, j, NULL, root, gdca_zero6, b13, beta, a->f, correct != GDCA_FWD_CORRECT,
                      NULL, dim) != 0 &&
        d->singular_joint < 0) {
        d->singular_joint = j;
    }
    for (int r = 0; r < dim; r++) {
        tl[r] = d->fwd_z[dim * j + r];
        tl[dim + r] = 0;
        load[r] = correct == GDCA_FWD_CORRECT ? load[r] + tl[r] : tl[r];
    }
    ctc_dense_mulv(dim, dim, root + H11(dim), tl, a1);
    for (int r = 0; r < dim; r++) a1[r] += b13[r];
    forward_accel(m, d, j, a1, gdca_zero6, beta, a->qacc, dim);
}

/* the root: a loop model's, or the ground joint 0 with the free end's load F2 = 0 */
static inline void forward_root(const forward_args *a, const int dim, const int correct)
{
    const ctc_model *m = a->m;
    if (m->has_loop) {
        forward_loop_root(a, dim, correct);
        return;
    }
    if (m->chain) {
        forward_root_joint(a, 0, m->root, dim, correct);
        return;
    }
    for (int i = 0; i < m->nroots; i++) {
        forward_root_joint(a, m->root_joint[i], m->root_asm[i], dim, correct);
    }
}

/* disassembly of tree nodes hi-1 down to lo, parents before children: each writes its joint's
   load and acceleration and its children's terminal loads */
static inline void forward_disassemble(const forward_args *a, int lo, int hi, const int dim,
                                       const int correct, const int tree)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int n = m->nbodies;
    for (int i = hi - 1; i >= lo; i--) {
        const ctc_tree_node *node = &m->tree[i];
        if (tree && node->kind != CTC_NODE_JOIN) {
            forward_rake_down(a, i, dim, correct);
            continue;
        }
        const double *left = ctc_data_handles(m, d, node->left, 0);
        const double *right = ctc_data_handles(m, d, node->right, 0);
        const double *f1 = d->tload + (size_t)(n + i) * 2 * dim, *f2 = f1 + dim;
        const double *b23l = forward_bias(a, node->left, 1, dim, correct);
        const double *b13r = forward_bias(a, node->right, 0, dim, correct);
        const int j = node->joint;
        double *load = d->jnt_load + dim * j, fj[CTC_DENSE_MAX], a1r[CTC_DENSE_MAX];
        double a2l[CTC_DENSE_MAX], t[CTC_DENSE_MAX];
        gdca_joint_load(dim, dim - m->jnt_nv[j], left, right, d->fwd_E + dim * dim * j,
                        d->fwd_z + dim * j, f1, f2, fj);

        /* A1^R = h11^R F + h12^R F2 + h13^R,  A2^L = h21^L F1 - h22^L F + h23^L */
        ctc_dense_mulv(dim, dim, right + H11(dim), fj, a1r);
        ctc_dense_mulv(dim, dim, right + H12(dim), f2, t);
        for (int r = 0; r < dim; r++) a1r[r] += t[r] + b13r[r];
        ctc_dense_tmulv(dim, dim, left + H12(dim), f1, a2l);
        ctc_dense_mulv(dim, dim, left + H22(dim), fj, t);
        for (int r = 0; r < dim; r++) a2l[r] += b23l[r] - t[r];
        forward_accel(m, d, j, a1r, a2l, gdca_forward_beta(a->d, j, dim, correct), a->qacc, dim);

        for (int r = 0; r < dim; r++)
            load[r] = correct == GDCA_FWD_CORRECT ? load[r] + fj[r] : fj[r];
        gdca_pass_loads(dim, d->tload, node, f1, f2, fj);
    }
}

/* the stages specialised to the planar and the spatial form, full and correction, and for a
   chain's tree (JOIN nodes only) or a branched tree's plan */
#define FORWARD_STAGES(name, dim, correct, tree)                                                   \
    static CTC_SPECIALISE int assemble_##name(void *a, int lo, int hi)                             \
    {                                                                                              \
        return forward_assemble(a, lo, hi, dim, correct, tree);                                    \
    }                                                                                              \
    static CTC_SPECIALISE void disassemble_##name(void *a, int lo, int hi)                         \
    {                                                                                              \
        forward_disassemble(a, lo, hi, dim, correct, tree);                                        \
    }

FORWARD_STAGES(planar, 3, GDCA_FWD_FULL, 0)
FORWARD_STAGES(spatial, 6, GDCA_FWD_FULL, 0)
FORWARD_STAGES(correct_planar, 3, GDCA_FWD_CORRECT, 0)
FORWARD_STAGES(correct_spatial, 6, GDCA_FWD_CORRECT, 0)
FORWARD_STAGES(biasfree_planar, 3, GDCA_FWD_BIASFREE, 0)
FORWARD_STAGES(biasfree_spatial, 6, GDCA_FWD_BIASFREE, 0)
FORWARD_STAGES(planar_tree, 3, GDCA_FWD_FULL, 1)
FORWARD_STAGES(spatial_tree, 6, GDCA_FWD_FULL, 1)
FORWARD_STAGES(correct_planar_tree, 3, GDCA_FWD_CORRECT, 1)
FORWARD_STAGES(correct_spatial_tree, 6, GDCA_FWD_CORRECT, 1)
FORWARD_STAGES(biasfree_planar_tree, 3, GDCA_FWD_BIASFREE, 1)
FORWARD_STAGES(biasfree_spatial_tree, 6, GDCA_FWD_BIASFREE, 1)

#define FORWARD_ROOT(name, dim, mode)                                                              \
    static CTC_SPECIALISE void root_##name(void *a)                                                \
    {                                                                                              \
        forward_root(a, dim, mode);                                                                \
    }

FORWARD_ROOT(planar, 3, GDCA_FWD_FULL)
FORWARD_ROOT(spatial, 6, GDCA_FWD_FULL)
FORWARD_ROOT(correct_planar, 3, GDCA_FWD_CORRECT)
FORWARD_ROOT(correct_spatial, 6, GDCA_FWD_CORRECT)
FORWARD_ROOT(biasfree_planar, 3, GDCA_FWD_BIASFREE)
FORWARD_ROOT(biasfree_spatial, 6, GDCA_FWD_BIASFREE)

/* the stage functions by [spatial][mode][tree] */
static int (*const forward_assemble_fn[2][3][2])(void *, int, int) = {
    {{assemble_planar, assemble_planar_tree},
     {assemble_correct_planar, assemble_correct_planar_tree},
     {assemble_biasfree_planar, assemble_biasfree_planar_tree}},
    {{assemble_spatial, assemble_spatial_tree},
     {assemble_correct_spatial, assemble_correct_spatial_tree},
     {assemble_biasfree_spatial, assemble_biasfree_spatial_tree}}};
static void (*const forward_disassemble_fn[2][3][2])(void *, int, int) = {
    {{disassemble_planar, disassemble_planar_tree},
     {disassemble_correct_planar, disassemble_correct_planar_tree},
     {disassemble_biasfree_planar, disassemble_biasfree_planar_tree}},
    {{disassemble_spatial, disassemble_spatial_tree},
     {disassemble_correct_spatial, disassemble_correct_spatial_tree},
     {disassemble_biasfree_spatial, disassemble_biasfree_spatial_tree}}};
static void (*const forward_root_fn[2][3])(void *) = {
    {root_planar, root_correct_planar, root_biasfree_planar},
    {root_spatial, root_correct_spatial, root_biasfree_spatial}};

/* assembly and disassembly over the plan, serial or a height at a time (gdca_par.h), in mode
   `correct` (gdca_forward_joint.h) */
static void forward_plan(const ctc_model *m, ctc_data *d, const double *f, double *qacc,
                         int correct)
{
    forward_args a = {m, d, f, qacc};
    const int sp = m->form != CTC_FORM_PLANAR, tree = !m->chain;
    gdca_par_pass pass = {.ctx = &a,
                          .assemble = forward_assemble_fn[sp][correct][tree],
                          .root = forward_root_fn[sp][correct],
                          .disassemble = forward_disassemble_fn[sp][correct][tree],
                          .grain = sp ? FORWARD_GRAIN_SPATIAL : FORWARD_GRAIN_PLANAR,
                          .root_takes_top = 1,
                          .min_bodies =
                              sp ? FORWARD_MIN_BODIES_SPATIAL : FORWARD_MIN_BODIES_PLANAR};
    /* a loop model's pass is gated here; an open model's tree order was chosen by the gate */
    pass.gated = m->has_loop;
    gdca_par_run(m, d, &pass);
}

int gdca_forward_tree_candidate(const ctc_model *m, const ctc_data *d)
{
    if (m->has_loop || d->opt.fwd_order != CTC_ORDER_AUTO) return 0;
    const ctc_data *o = d->pool_owner != NULL ? d->pool_owner : d;
    const int min = m->form == CTC_FORM_PLANAR ? FORWARD_TREE_MIN_BODIES_PLANAR
                                               : FORWARD_TREE_MIN_BODIES_SPATIAL;
    return o->threads >= 2 && m->nbodies >= min;
}

int gdca_forward_order_seq(const ctc_model *m, const ctc_data *d)
{
    if (m->has_loop || d->opt.fwd_order == CTC_ORDER_TREE) return 0;
    if (d->opt.fwd_order == CTC_ORDER_SEQ) return 1;
    return !(gdca_forward_tree_candidate(m, d) && d->fwd_split);
}

void gdca_forward_correct(const ctc_model *m, ctc_data *d, const double *r, double *dq)
{
    if (m->dyn != NULL) { /* merged bodies (model.h): the reduced model's pass, the same vectors */
        gdca_forward_correct(m->dyn, ctc_data_dyn_begin(m, d), r, dq);
        ctc_data_dyn_end(m, d);
        return;
    }
    if (gdca_forward_order_seq(m, d)) {
        (m->chain ? gdca_forward_seq : gdca_forward_seq_tree)(m, d, r, dq, GDCA_FWD_CORRECT);
    } else {
        forward_plan(m, d, r, dq, GDCA_FWD_CORRECT);
    }
}

/* the accelerations and the joint loads before a refinement step, to undo it */
static void keep_before_step(const ctc_model *m, ctc_data *d, const double *qacc)
{
    memcpy(d->fwd_res + 3 * m->nvx, qacc, (size_t)m->nvx * sizeof *qacc);
    memcpy(d->fwd_load_prev, d->jnt_load, (size_t)m->njoints * (size_t)m->dim * sizeof(double));
}

/* The refinement's guard on a long open chain (gdca_refine.h): 0 when the residual r of qacc is
 * below *rlast, the residual before the last step (then *rlast becomes it); else (it grew, or
 * is not finite) 1, after undoing the last step, if one was made: qacc and d->jnt_load as
 * before it. */
static int refine_undo_if_grown(const ctc_model *m, ctc_data *d, double *qacc, const double *r,
                                double *rlast)
{
    double rmax = 0;
    for (int i = 0; i < m->nv; i++) {
        double a = fabs(r[i]);
        if (!(a <= rmax)) rmax = a; /* a NaN stays, as an infinity would */
        if (rmax != rmax) break;
    }
    if (rmax < *rlast) {
        *rlast = rmax;
        return 0;
    }
    if (d->fwd_refine_done > 0) {
        memcpy(qacc, d->fwd_res + 3 * m->nvx, (size_t)m->nvx * sizeof *qacc);
        memcpy(d->jnt_load, d->fwd_load_prev, (size_t)m->njoints * (size_t)m->dim * sizeof(double));
        d->fwd_refine_done--;
        d->fwd_refine_undone = 1;
    }
    return 1;
}

/* The forward order of the next pass: where the tree on threads may pay, the evaluation's way
 * (data.h ctc_eval_gate) chooses between it and the sequential order. Records it in
 * d->fwd_split, for the pass and its correction. Returns 1 when it asked the gate, so that the
 * caller marks the end of the pass (ctc_data_eval_pass_done), else 0. */
static int forward_order(const ctc_model *m, ctc_data *d)
{
    const int candidate = gdca_forward_tree_candidate(m, d);
    d->fwd_split = candidate && ctc_data_eval_split(d);
    return candidate;
}

/* One pass in mode `mode` (gdca_forward_joint.h) in the order of the setting, or of
 * d->fwd_split (forward_order). Returns 1 when the pass took the sequential order
 * (gdca_forward_order_seq: the setting, or no split taken), 0 for the plan. */
static int forward_pass(const ctc_model *m, ctc_data *d, const double *f, double *qacc, int mode)
{
    /* gdca_forward_order_seq, with d->fwd_split (which implies candidate) set */
    const int seq = !m->has_loop && d->opt.fwd_order != CTC_ORDER_TREE &&
                    (d->opt.fwd_order == CTC_ORDER_SEQ || !d->fwd_split);
    if (seq) {
        (m->chain ? gdca_forward_seq : gdca_forward_seq_tree)(m, d, f, qacc, mode);
    } else {
        forward_plan(m, d, f, qacc, mode);
    }
    return seq;
}

/* The refinement (gdca_refine.h) of qacc under the forces f, at most `steps` steps: r = f -
 * (M qacc + N) by the composite inverse, qacc += w M^-1 r, until the step rule
 * (gdca_refine_step) stops it; on a long open chain a step whose residual grew is undone, and
 * the last step is checked by one more residual */
static void forward_refine(const ctc_model *m, ctc_data *d, const double *f, double *qacc,
                           int steps)
{
    const int guard = !m->has_loop && m->nbodies >= CTC_REFINE_CHECK_MIN_BODIES;
    double *r = d->fwd_res, *dq = d->fwd_res + m->nvx, *dq_last = d->fwd_res + 2 * m->nvx;
    d->fwd_refine_done = 0;
    d->fwd_refine_undone = 0;
    if (steps <= 0) return;
    double rlast = INFINITY;
    gdca_refine_rule rule = {.augmented = m->nsingular > 0 || m->nslender > 0};
    for (int s = 0; s < steps && d->singular_joint < 0; s++) {
        gdca_refine_residual(m, d, f, qacc, r);
        if (guard && refine_undo_if_grown(m, d, qacc, r, &rlast)) return;
        if (guard) keep_before_step(m, d, qacc);
        gdca_forward_correct(m, d, r, dq);
        d->fwd_refine_done++;
        if (gdca_refine_step(&rule, m->nvx, dq, dq_last, qacc)) break;
    }
    if (guard && d->fwd_refine_done > 0 && d->singular_joint < 0) {
        gdca_refine_residual(m, d, f, qacc, r);
        refine_undo_if_grown(m, d, qacc, r, &rlast);
    }
}

/* The reference form (gdca.h ctc_gdca_forward_from) on an open model: qacc = a_ref (NULL: 0) +
 * M^-1 (f - f_ref) by the bias-free pass, d->jnt_load = the pass's loads + d->jnt_load_inv (the
 * reference's), then the refinement the rule gives the reference form (gdca_refine_steps_ref) */
static void forward_reference(const ctc_model *m, ctc_data *d, const double *f, const double *a_ref,
                              const double *f_ref, double *qacc)
{
    double *r = d->fwd_res;
    const int nv = m->nv;
    for (int i = 0; i < nv; i++) r[i] = f[i] - f_ref[i];
    const int gated = forward_order(m, d);
    const int seq = forward_pass(m, d, r, qacc, GDCA_FWD_BIASFREE);
    for (int i = 0; a_ref != NULL && i < nv; i++) qacc[i] += a_ref[i];
    /* the sequential passes added the reference's loads in their own sweep */
    const size_t nl = (size_t)m->nbodies * (size_t)m->dim;
    for (size_t i = 0; !seq && i < nl; i++) d->jnt_load[i] += d->jnt_load_inv[i];
    forward_refine(m, d, f, qacc, gdca_refine_steps_ref(m, d));
    if (gated) ctc_data_eval_pass_done(d);
}

int gdca_forward_takes_ref(const ctc_model *m, const ctc_data *d)
{
    return !m->has_loop && d->opt.fwd_form == CTC_FWD_REFERENCE;
}

void ctc_gdca_forward(const ctc_model *m, ctc_data *d, const double *f, double *qacc)
{
    if (m->dyn != NULL) { /* merged bodies (model.h): the reduced model's pass, the same vectors */
        ctc_gdca_forward(m->dyn, ctc_data_dyn_begin(m, d), f, qacc);
        ctc_data_dyn_end(m, d);
        return;
    }
    /* the reference form with a_ref = 0: f_ref = N(q, v) by the composite inverse */
    if (gdca_forward_takes_ref(m, d)) {
        double *zero = d->fwd_res + m->nvx, *f_ref = d->fwd_res + 2 * m->nvx;
        memset(zero, 0, (size_t)m->nv * sizeof *zero);
        ctc_gdca_inverse(m, d, zero, f_ref);
        forward_reference(m, d, f, NULL, f_ref, qacc);
        return;
    }
    ctc_handles_bias(m, d); /* the full pass takes the bodies' bias terms */
    if (m->has_loop) {      /* dependent joints carry no driving force */
        double *fm = d->xbuf;
        memset(fm, 0, (size_t)m->nvx * sizeof *fm);
        for (int i = 0; i < m->nind; i++) fm[m->ind_coord[i]] = f[m->ind_coord[i]];
        f = fm;
    }
    const int gated = forward_order(m, d);
    forward_pass(m, d, f, qacc, GDCA_FWD_FULL);
    forward_refine(m, d, f, qacc, gdca_refine_steps(m, d));
    if (gated) ctc_data_eval_pass_done(d);
}

void ctc_gdca_forward_from(const ctc_model *m, ctc_data *d, const double *f, const double *a_ref,
                           const double *f_ref, double *qacc)
{
    if (m->dyn != NULL) { /* merged bodies: as above (f_ref's loads are the reduced model's) */
        ctc_gdca_forward_from(m->dyn, ctc_data_dyn_begin(m, d), f, a_ref, f_ref, qacc);
        ctc_data_dyn_end(m, d);
        return;
    }
    if (m->has_loop || d->opt.fwd_form == CTC_FWD_LITERAL) {
        ctc_gdca_forward(m, d, f, qacc);
        return;
    }
    forward_reference(m, d, f, a_ref, f_ref, qacc);
}
