/*
 * gdca_inverse_mobility.c - the paper's iGDCA in its literal mobility form (paper section 4).
 *
 * The reference implementation of Eq. 26-54, compared with the composite form (gdca_inverse.c)
 * in the tests and benchmarks. It shares the body records with the forward pass
 * (Eq. 42-43), but each assembled mobility of a rigid composite is a small difference of its
 * parts' larger ones (Eq. 34, 38), so its error grows with that ratio: about eps cond(M) on
 * long chains, 2e-10 already on Featherstone's 16-body coil.
 *
 * The joint accelerations are commanded (u = qdd_d - w, Eq. 19), so the acceleration constraint
 * A1^R = A2^L + P u + beta needs no projection and the whole joint load F (constraint and drive)
 * is the unknown (Eq. 26-31):
 *     X = K^-1,  K = h11^R + h22^L (symmetric positive definite: Cholesky),
 *     Y' = h23^L - h13^R + beta + P u,   F = X (h21^L F1 - h12^R F2 + Y'),
 * assembled by the shared rule of gdca_tree.h (Eq. 34-39). At the root the ground joint gives
 * F1 = (h11)^-1 (P u + beta - h13) (Eq. 46). The disassembly recovers each joint's load and its
 * driving force f = P^T F (Eq. 51-52: D^T P = 0, P^T P = 1).
 *
 * Its records are the forward pass's, built from the model's fwd_bodies: on a model with
 * augmented bodies (a singular body, which has no inverse inertia, or a slender one; model.h)
 * they describe other bodies, and the forces were off by 1e-7 to 1e-5 (bench/NOTEBOOK.md, "Issue
 * 18, the rest"), so there the public entry gives the composite form's forces (gdca.h).
 *
 * Loop models (paper section 5): ctc_gdca_inverse uses this form for them only when their
 * dependent coordinates do not number dim (gdca_inverse_loop.h); it is the paper's
 * closed-chain iGDCA. Across a dependent joint the acceleration
 * is unknown, so the joint is assembled with the forward, projected rule and no driving force:
 *     W = D (D^T K D)^-1 D^T,   F = W (h21^L F1 - h12^R F2 + h23^L - h13^R + beta);
 * across an independent one with the commanded acceleration as above. The root's boundary
 * joints (0 and the closing joint, and b + 1 for a loop closed on body b: gdca_loop.h) are
 * solved together, each end's case (independent or dependent terminal
 * joint, Eq. 55-65) choosing its unknowns. The disassembly visits only the nodes on the way to
 * an independent joint (model.h inv_need, Fig. 4); the loads of the others are not needed.
 *
 * As in the forward pass, the nodes of one tree height write disjoint slots (their records,
 * their joints' E, z, load and driving force, their children's terminal loads), so gdca_par.c
 * may split a height over threads (ctc_data_set_threads) with bitwise the serial results; the
 * root, a loop model's included, stays on the caller's thread.
 */
#include "gdca.h"

#include <math.h>
#include <string.h>

#include "gdca_loop.h"
#include "gdca_par.h"
#include "gdca_rake.h"
#include "gdca_tree.h"
#include "handles.h"

/* the factor's column count of joint j: dim across an independent joint, dim - nv otherwise */
static inline int inverse_nc(const ctc_model *m, int j, const int dim)
{
    return m->jnt_indep[j] ? dim : dim - m->jnt_nv[j];
}

/* the factor E of X = E E^T = K^-1 and z = X Y' of joint j between left (NULL: ground) and right;
 * returns 0, or -1 when the matrix to factor is not positive definite (the results are NaN) */
static inline int inverse_joint(const ctc_model *m, ctc_data *d, int j, const double *left,
                                const double *right, const double *u, const int dim)
{
    double *e = d->inv_E + dim * dim * j, *z = d->inv_z + dim * j;
    double k[CTC_DENSE_MAX * CTC_DENSE_MAX], y[CTC_DENSE_MAX], pu[CTC_DENSE_MAX];
    const int indep = m->jnt_indep[j], nc = inverse_nc(m, j, dim);

    gdca_joint_K(dim, left, right, k);
    int st = gdca_joint_factor(dim, k, indep ? NULL : d->jnt_D + dim * dim * j, nc, e);
    gdca_joint_Y0(dim, left, right, d->jnt_beta + dim * j, y);
    if (indep) {
        gdca_joint_map(dim, m->jnt_nv[j], d->jnt_P + 3 * dim * j, u + m->jnt_vadr[j], pu);
        for (int i = 0; i < dim; i++) y[i] += pu[i];
    }
    gdca_factor_apply(dim, nc, e, y, z);
    return st;
}

/* joint k's end of a loop model's root problem (gdca_loop.h): an independent joint's whole load
 * is unknown and its acceleration commanded (Eq. 55-65); a dependent one's load is unknown along D
 * and it has no driving force. a (dim) is filled. */
static inline gdca_end mobility_end(const ctc_model *m, const ctc_data *d, int k, const double *u,
                                    double *a, const int dim)
{
    memcpy(a, d->jnt_beta + dim * k, (size_t)dim * sizeof *a);
    if (!m->jnt_indep[k])
        return (gdca_end){d->jnt_D + dim * dim * k, dim - m->jnt_nv[k], gdca_zero6, a, NULL};
    double pu[CTC_DENSE_MAX];
    gdca_joint_map(dim, m->jnt_nv[k], d->jnt_P + 3 * dim * k, u + m->jnt_vadr[k], pu);
    for (int i = 0; i < dim; i++) a[i] += pu[i];
    return (gdca_end){NULL, dim, gdca_zero6, a, NULL};
}

/* a loop model's root: the loop's record with joint 0 and the closing joint on the ground, or,
 * for a loop on body b, the root's two parts with joints 0, b + 1 and n (gdca_forward.c) */
static inline void inverse_loop_root(const ctc_model *m, ctc_data *d, const double *u,
                                     const int dim)
{
    const int n = m->nbodies, j = m->loop_first;
    const ctc_tree_node *top = &m->tree[m->ntree - 1];
    double a0[CTC_DENSE_MAX], aj[CTC_DENSE_MAX], an[CTC_DENSE_MAX];
    gdca_loop_sol s;
    gdca_loop_root p = {.dim = dim,
                        .l = j > 0 ? ctc_data_handles(m, d, top->left, 1) : NULL,
                        .r = ctc_data_handles(m, d, j > 0 ? top->right : m->root, 1),
                        .shift = d->loop_r,
                        .gam = d->loop_gam,
                        .e0 = mobility_end(m, d, 0, u, a0, dim),
                        .ej = mobility_end(m, d, j, u, aj, dim),
                        .en = mobility_end(m, d, n, u, an, dim)};
    if (gdca_loop_solve(&p, &s) != 0 && d->singular_joint < 0) d->singular_joint = n;
    d->loop_cond = s.cond;
    gdca_loop_hand_down(m, &s, d->loop_r, 0, d->tload, d->jnt_load_inv);
}

/* f_j = P^T F */
static inline void inverse_drive(const ctc_model *m, const ctc_data *d, int j, const double *load,
                                 double *f, const int dim)
{
    const double *P = d->jnt_P + 3 * dim * j;
    for (int c = 0; c < m->jnt_nv[j]; c++) {
        double s = 0;
        for (int i = 0; i < dim; i++) s += P[c * dim + i] * load[i];
        f[m->jnt_vadr[j] + c] = s;
    }
}

/* When the mobility-form inverse pass splits over threads (gdca_par.h): its nodes cost about
 * what the forward pass's do, so it takes the forward pass's values (gdca_forward.c;
 * bench/NOTEBOOK.md, "Parallel assembly"). */
#define MOBILITY_GRAIN_PLANAR 2
#define MOBILITY_GRAIN_SPATIAL 2
#define MOBILITY_MIN_BODIES_PLANAR 512
#define MOBILITY_MIN_BODIES_SPATIAL 128

/* what the stages of one inverse pass share (gdca_par.h) */
typedef struct mobility_args {
    const ctc_model *m;
    ctc_data *d;
    const double *u;
    double *f;
} mobility_args;

/* the terms of operand x of a SUM or RAKE node of body k (gdca_rake.h), added to s and b (add =
   0: written): a light child c's (c >= 0; its joint solved as a root's, X = K^-1), or a SUM
   node's partial sums; returns as inverse_joint */
static inline int mobility_operand(const mobility_args *a, int k, int x, int c, double *s,
                                   double *b, int add, const int dim)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    double ts[CTC_DENSE_MAX * CTC_DENSE_MAX], tb[CTC_DENSE_MAX];
    const double *ps = ts, *pb = tb;
    int st = 0;
    if (c >= 0) {
        double r[3], kappa[CTC_DENSE_MAX];
        st = inverse_joint(m, d, c, NULL, ctc_data_handles(m, d, x, 1), a->u, dim);
        gdca_rake_point(d, k, c, dim, r, kappa);
        gdca_rake_light(dim, -1, inverse_nc(m, c, dim), d->inv_E + dim * dim * c, r, kappa,
                        d->inv_z + dim * c, ts, tb);
    } else {
        const double *rec = ctc_data_handles(m, d, x, 1);
        ps = rec + H11(dim), pb = rec + H13(dim);
    }
    for (int i = 0; i < dim * dim; i++) s[i] = add ? s[i] + ps[i] : ps[i];
    for (int i = 0; i < dim; i++) b[i] = add ? b[i] + pb[i] : pb[i];
    return st;
}

/* a SUM node's partial sums, or a RAKE node's pseudo-body record (gdca_rake.h) */
static inline int mobility_rake_node(const mobility_args *a, const ctc_tree_node *node, double *out,
                                     const int dim)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int k = node->body;
    if (node->kind == CTC_NODE_SUM) {
        int st = mobility_operand(a, k, node->left, node->ljoint, out + H11(dim), out + H13(dim), 0,
                                  dim);
        return st | mobility_operand(a, k, node->right, node->rjoint, out + H11(dim),
                                     out + H13(dim), 1, dim);
    }
    double mm[CTC_DENSE_MAX * CTC_DENSE_MAX], b[CTC_DENSE_MAX], sb[CTC_DENSE_MAX];
    double s[CTC_DENSE_MAX * CTC_DENSE_MAX], k1[CTC_DENSE_MAX], k2[CTC_DENSE_MAX];
    int st = mobility_operand(a, k, node->left, node->ljoint, s, sb, 0, dim);
    gdca_rake_body(m, d, k, dim, mm, b);
    for (int i = 0; i < dim * dim; i++) mm[i] += s[i];
    for (int i = 0; i < dim; i++) b[i] -= sb[i];
    gdca_rake_kappa(d, k, dim, d->hr + 6 * k, k1);
    gdca_rake_kappa(d, k, dim, d->hr + 6 * k + 3, k2);
    return st | gdca_rake_record(dim, mm, b, d->hr + 6 * k, d->hr + 6 * k + 3, k1, k2,
                                 gdca_rake_slot(d, k, dim), out, 1);
}

/* a SUM or RAKE node's disassembly: body k's motion X handed to each operand; a light child's
   joint gets its load F_c = X A_c + z and driving force, its subtree the loads (F_c, 0) */
static inline void mobility_rake_down(const mobility_args *a, int i, const int dim)
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
        double *t = d->tload + (size_t)sub * 2 * dim;
        if (c < 0) {
            for (int r = 0; r < dim; r++) t[r] = x[r];
            continue;
        }
        double r3[3], kappa[CTC_DENSE_MAX], ac[CTC_DENSE_MAX], *fc = d->jnt_load_inv + dim * c;
        gdca_rake_point(d, k, c, dim, r3, kappa);
        gdca_rake_child_load(dim, -1, inverse_nc(m, c, dim), d->inv_E + dim * dim * c,
                             d->inv_z + dim * c, r3, kappa, x, ac, fc);
        for (int r = 0; r < dim; r++) {
            t[r] = fc[r];
            t[dim + r] = 0;
        }
        inverse_drive(m, d, c, fc, a->f, dim);
    }
}

/* assembly of tree nodes lo..hi-1, children before parents; returns the first node whose joint
   is singular, or -1 */
static inline int mobility_assemble(const mobility_args *a, int lo, int hi, const int dim,
                                    const int tree)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int hs = d->hsize;
    int first = -1;
    for (int i = lo; i < hi; i++) {
        const ctc_tree_node *node = &m->tree[i];
        if (tree && node->kind != CTC_NODE_JOIN) {
            if (mobility_rake_node(a, node, d->hinv + (size_t)i * hs, dim) != 0 && first < 0) {
                first = i;
            }
            continue;
        }
        const double *left = ctc_data_handles(m, d, node->left, 1);
        const double *right = ctc_data_handles(m, d, node->right, 1);
        int j = node->joint;
        if (inverse_joint(m, d, j, left, right, a->u, dim) != 0 && first < 0) first = i;
        gdca_assemble(dim, inverse_nc(m, j, dim), left, right, d->inv_E + dim * dim * j,
                      d->inv_z + dim * j, d->hinv + (size_t)i * hs);
    }
    return first;
}

/* ground child j's joint to its subtree, assembled at x, whose free end carries F2 = 0 */
static inline void mobility_root_joint(const mobility_args *a, int j, int x, const int dim)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const double *root = ctc_data_handles(m, d, x, 1);
    double *t = d->tload + (size_t)x * 2 * dim;
    if (inverse_joint(m, d, j, NULL, root, a->u, dim) != 0 && d->singular_joint < 0) {
        d->singular_joint = j;
    }
    for (int r = 0; r < dim; r++) {
        t[r] = d->inv_z[dim * j + r];
        t[dim + r] = 0;
        d->jnt_load_inv[dim * j + r] = t[r];
    }
    inverse_drive(m, d, j, t, a->f, dim);
}

/* the root: a loop model's, or the ground joint 0 with the free end's load F2 = 0 */
static inline void mobility_root(const mobility_args *a, const int dim)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int n = m->nbodies;
    double *f = a->f;
    if (m->has_loop) {
        inverse_loop_root(m, d, a->u, dim);
        for (int j = 0; j < m->nvx; j++) f[j] = 0; /* dependent coordinates */
        int bound[3] = {0, m->loop_first, n};
        for (int b = 0; b < 3; b++) {
            int k = bound[b];
            if (m->jnt_indep[k]) inverse_drive(m, d, k, d->jnt_load_inv + dim * k, f, dim);
        }
        return;
    }
    if (m->chain) {
        mobility_root_joint(a, 0, m->root, dim);
        return;
    }
    for (int i = 0; i < m->nroots; i++)
        mobility_root_joint(a, m->root_joint[i], m->root_asm[i], dim);
}

/* disassembly of tree nodes hi-1 down to lo, parents before children; a loop model's stops
   where no independent joint is left below (Fig. 4) */
static inline void mobility_disassemble(const mobility_args *a, int lo, int hi, const int dim,
                                        const int tree)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int n = m->nbodies;
    const int prune = m->has_loop && !d->opt.inv_full;
    for (int i = hi - 1; i >= lo; i--) {
        if (prune && !m->inv_need[i]) continue;
        const ctc_tree_node *node = &m->tree[i];
        if (tree && node->kind != CTC_NODE_JOIN) {
            mobility_rake_down(a, i, dim);
            continue;
        }
        const double *left = ctc_data_handles(m, d, node->left, 1);
        const double *right = ctc_data_handles(m, d, node->right, 1);
        const double *f1 = d->tload + (size_t)(n + i) * 2 * dim, *f2 = f1 + dim;
        int j = node->joint;
        double *fj = d->jnt_load_inv + dim * j;
        gdca_joint_load(dim, inverse_nc(m, j, dim), left, right, d->inv_E + dim * dim * j,
                        d->inv_z + dim * j, f1, f2, fj);
        if (m->jnt_indep[j]) inverse_drive(m, d, j, fj, a->f, dim);
        gdca_pass_loads(dim, d->tload, node, f1, f2, fj);
    }
}

/* the stages specialised to the planar and the spatial form */
static CTC_SPECIALISE int assemble_planar(void *a, int lo, int hi)
{
    return mobility_assemble(a, lo, hi, 3, 0);
}

static CTC_SPECIALISE int assemble_planar_tree(void *a, int lo, int hi)
{
    return mobility_assemble(a, lo, hi, 3, 1);
}

static CTC_SPECIALISE int assemble_spatial(void *a, int lo, int hi)
{
    return mobility_assemble(a, lo, hi, 6, 0);
}

static CTC_SPECIALISE int assemble_spatial_tree(void *a, int lo, int hi)
{
    return mobility_assemble(a, lo, hi, 6, 1);
}

static CTC_SPECIALISE void root_planar(void *a)
{
    mobility_root(a, 3);
}

static CTC_SPECIALISE void root_spatial(void *a)
{
    mobility_root(a, 6);
}

static CTC_SPECIALISE void disassemble_planar(void *a, int lo, int hi)
{
    mobility_disassemble(a, lo, hi, 3, 0);
}

static CTC_SPECIALISE void disassemble_planar_tree(void *a, int lo, int hi)
{
    mobility_disassemble(a, lo, hi, 3, 1);
}

static CTC_SPECIALISE void disassemble_spatial(void *a, int lo, int hi)
{
    mobility_disassemble(a, lo, hi, 6, 0);
}

static CTC_SPECIALISE void disassemble_spatial_tree(void *a, int lo, int hi)
{
    mobility_disassemble(a, lo, hi, 6, 1);
}

void ctc_gdca_inverse_mobility(const ctc_model *m, ctc_data *d, const double *u, double *f)
{
    if (m->dyn != NULL) { /* merged bodies (model.h): the reduced model's pass, the same vectors */
        ctc_gdca_inverse_mobility(m->dyn, ctc_data_dyn_begin(m, d), u, f);
        ctc_data_dyn_end(m, d);
        return;
    }
    /* augmented bodies (model.h "singular bodies", "slender bodies"): no literal form (gdca.h) */
    if (m->fwd_bodies != m->bodies && !(m->has_loop && m->nvx - m->nind != m->dim)) {
        ctc_gdca_inverse(m, d, u, f);
        return;
    }
    ctc_handles_bias(m, d); /* the pass takes the bodies' bias terms */
    mobility_args a = {m, d, u, f};
    const int planar = m->form == CTC_FORM_PLANAR;
    gdca_par_pass pass = {
        .ctx = &a,
        .assemble = planar ? (m->chain ? assemble_planar : assemble_planar_tree)
                           : (m->chain ? assemble_spatial : assemble_spatial_tree),
        .root = planar ? root_planar : root_spatial,
        .disassemble = planar ? (m->chain ? disassemble_planar : disassemble_planar_tree)
                              : (m->chain ? disassemble_spatial : disassemble_spatial_tree),
        .grain = planar ? MOBILITY_GRAIN_PLANAR : MOBILITY_GRAIN_SPATIAL,
        .root_takes_top = 1,
        .min_bodies = planar ? MOBILITY_MIN_BODIES_PLANAR : MOBILITY_MIN_BODIES_SPATIAL,
        .gated = 1,
    };
    gdca_par_run(m, d, &pass);
    if (m->has_loop && d->singular_joint >= 0) {
        for (int j = 0; j < m->nvx; j++) f[j] = NAN;
    }
}
