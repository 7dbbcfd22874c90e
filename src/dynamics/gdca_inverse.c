/*
 * gdca_inverse.c - inverse dynamics for computed torque control by iGDCA, in composite form
 * (paper section 4; DESIGN.md section 4).
 *
 * In the inverse problem every joint acceleration is commanded (u = qdd_d - w, Eq. 19), so each
 * assembly of the tree moves as a rigid composite whose internal motion is known. Its handle
 * equations (Eq. 32-33) therefore factor through one composite spatial inertia I about its
 * handle 1, a bias load w, the handle-to-handle vector r12 and an acceleration offset c:
 *
 *     I A1 + w = F1 + T(r12)^T F2,         A2 = T(r12) A1 + c,
 *     i.e.  psi11 = I^-1,  psi12 = I^-1 T^T,  psi22 = T I^-1 T^T,  psi13 = -I^-1 w,
 *           psi23 = T psi13 + c,
 *
 * with the rigid transfer T(r) = [1 0; -[r]x 1] (A at a point r further on: a + alpha x r; its
 * transpose moves a load's moment: tau + r x f). Eliminating the joint load between L and R
 * (A1^R = A2^L + P u + beta = T(r12^L) A1 + e, e = c^L + P u + beta) gives the assembly
 *
 *     I = I^L + T^T I^R T,   w = w^L + T^T (I^R e + w^R),   r12 = r12^L + r12^R,
 *     c = T(r12^R) e + c^R,                                         T = T(r12^L),
 *
 * which is the paper's Eq. 34-39 rewritten by the Woodbury identity: composite inertias add,
 * where the literal form (gdca_inverse_mobility.c) subtracts mobilities of very different size
 * and loses digits on long chains. The root takes A1 = P u + beta from the ground (Eq. 44-46)
 * and F2 = 0 at the free end; the disassembly passes (A1, F2) down and recovers each joint load
 *     F = I^R A1^R + w^R - T(r12^R)^T F2,     driving force f = P^T F   (Eq. 51-52).
 * A body's record: I = T(rho)^T M_c T(rho), w = T(rho)^T (M_c kappa - b), rho = c_m - handle 1,
 * kappa = (0; w x (w x rho)), b = (-w x I_c w; m g), c = (0; w x (w x r12)).
 *
 * On a branched tree (model.c, "the plan of a branched tree") a light child c of body k, its
 * subtree's record (I^S, w^S) assembled with its tip free, moves with A1^S = T(r) A1(k) + e,
 * r = c - handle 1 of k, e = (0; w x (w x r)) + P u + beta, and loads k at c with
 * F = I^S A1^S + w^S, so the RAKE node's record is k's with
 *     I += T(r)^T I^S T(r),   w += T(r)^T (I^S e + w^S)
 * (c and r12 are k's own), summed over k's light children through SUM nodes; the disassembly
 * hands A1(k) down and recovers F and the driving force P^T F of each light child's joint.
 *
 * The body records, and the nodes of one tree height, are independent: a body writes its own
 * record; a node's assembly its own record and its joint's offset e; its disassembly its joint's
 * load and driving force and its two children's (A1, F2). gdca_par.c may therefore split them
 * over threads (ctc_data_set_threads) with bitwise the serial results; the root stays on the
 * caller's thread. Nothing is inverted, so d->singular_joint stays -1.
 *
 * The body records and each node's I and r12 depend on the state only; w, c and e also on u.
 * The refinement of the forward pass (gdca_refine.h) calls this pass again at the same state,
 * so the first pass after ctc_handles stamps the records (d->icomp_stamp = d->handles_stamp)
 * and later ones recompute only w, c and e, with bitwise the same results.
 */
#include "gdca.h"
#include "gdca_inverse_loop.h"

#include "dense.h"
#include "gdca_par.h"
#include "gdca_tree.h"
#include "spatial.h"

/* offsets in a composite record */
#define CI(dim) 0
#define CW(dim) ((dim) * (dim))
#define CC(dim) ((dim) * (dim) + (dim))
#define CR(dim) ((dim) * (dim) + 2 * (dim))

/* out = T(r)^T S T(r) for symmetric S (dim x dim), written by blocks (about 110 flops for dim 6,
 * against 684 for dense products). Spatial, with S = [A B; B^T C] and X = -[r]x (T = [1 0; X 1]):
 *     T^T S T = [A + B X + (B X)^T + X^T C X,  B + (C X)^T;  B^T + C X,  C],
 * where row i of M X is r x (row i of M) and column j of X^T Y is r x (column j of Y).
 * Planar, with S = [a b^T; b C] and X = (-r_y, r_x):
 *     T^T S T = [a + 2 b.X + X.(C X),  (b + C X)^T;  b + C X,  C].
 * out may alias nothing. */
static inline void congruence(int dim, const double r[3], const double *s, double *out)
{
    if (dim == 3) {
        const double x0 = -r[1], x1 = r[0];
        const double cx0 = s[4] * x0 + s[5] * x1, cx1 = s[7] * x0 + s[8] * x1;
        const double b0 = s[3] + cx0, b1 = s[6] + cx1;
        out[0] = s[0] + 2 * (s[3] * x0 + s[6] * x1) + (x0 * cx0 + x1 * cx1);
        out[1] = out[3] = b0;
        out[2] = out[6] = b1;
        out[4] = s[4];
        out[5] = out[7] = s[5];
        out[8] = s[8];
        return;
    }
    double bx[9], cx[9], xcx[9];
    for (int i = 0; i < 3; i++) {
        ctc_v3_cross(bx + 3 * i, r, s + 6 * i + 3);       /* row i of B X */
        ctc_v3_cross(cx + 3 * i, r, s + 6 * (i + 3) + 3); /* row i of C X */
    }
    for (int j = 0; j < 3; j++) { /* column j of X^T (C X) */
        double col[3] = {cx[j], cx[3 + j], cx[6 + j]}, t[3];
        ctc_v3_cross(t, r, col);
        xcx[j] = t[0], xcx[3 + j] = t[1], xcx[6 + j] = t[2];
    }
    for (int i = 0; i < 3; i++) {
        for (int j = i; j < 3; j++) { /* top left, symmetric */
            double v = s[6 * i + j] + bx[3 * i + j] + bx[3 * j + i] + xcx[3 * i + j];
            out[6 * i + j] = out[6 * j + i] = v;
        }
        for (int j = 0; j < 3; j++) { /* top right B + (C X)^T, and its transpose */
            double v = s[6 * i + 3 + j] + cx[3 * j + i];
            out[6 * i + 3 + j] = out[6 * (3 + j) + i] = v;
        }
        for (int j = 0; j < 3; j++) out[6 * (3 + i) + 3 + j] = s[6 * (3 + i) + 3 + j];
    }
}

/* body k's composite record from the kinematics and handle offsets in d */
static inline void body_record(const ctc_model *m, const ctc_data *d, int k, double *rec,
                               const int dim)
{
    const double *r1 = d->hr + 6 * k, *r2 = r1 + 3, *w = d->omega + 3 * k;
    double *c = rec + CC(dim), *r12 = rec + CR(dim);
    double *in = rec + CI(dim), rho[3], load[6];
    ctc_v3_scale(rho, r1, -1.0);
    ctc_v3_sub(r12, r2, r1);

    if (dim == 3) {
        const ctc_planar_body *b = &m->planar[k];
        const double *g = m->plane_gravity;
        double w2 = w[2] * w[2];
        /* I = T(rho)^T diag(J, m, m) T(rho) = [J + m |rho|^2, m X^T; m X, m 1], X = (-rho_y,
           rho_x) */
        in[0] = b->inertia + b->mass * (rho[0] * rho[0] + rho[1] * rho[1]);
        in[1] = in[3] = -b->mass * rho[1];
        in[2] = in[6] = b->mass * rho[0];
        in[4] = in[8] = b->mass;
        in[5] = in[7] = 0;
        load[0] = 0;
        load[1] = b->mass * (-w2 * rho[0] - g[0]);
        load[2] = b->mass * (-w2 * rho[1] - g[1]);
        c[0] = 0;
        c[1] = -w2 * r12[0];
        c[2] = -w2 * r12[1];
    } else {
        const ctc_body_spec *b = &m->bodies[k];
        double iw[9], wr[3], wwr[3], iww[3];
        ctc_m3_rotate_sym(iw, d->xrot + 9 * k, b->inertia);
        /* I = T(rho)^T diag(I_c, m 1) T(rho)
             = [I_c + m (|rho|^2 1 - rho rho^T), m [rho]x; -m [rho]x, m 1] */
        const double m0 = b->mass, rr = ctc_v3_dot(rho, rho);
        const double mr[3] = {m0 * rho[0], m0 * rho[1], m0 * rho[2]};
        for (int i = 0; i < 3; i++) {
            for (int j = i; j < 3; j++) {
                double v = iw[3 * i + j] + ((i == j ? m0 * rr : 0) - mr[i] * rho[j]);
                in[6 * i + j] = in[6 * j + i] = v;
            }
            for (int j = 0; j < 3; j++) in[6 * (3 + i) + 3 + j] = i == j ? m0 : 0;
        }
        /* m [rho]x in the top right block, its transpose -m [rho]x in the bottom left */
        const double sk[9] = {0, -mr[2], mr[1], mr[2], 0, -mr[0], -mr[1], mr[0], 0};
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) {
                in[6 * i + 3 + j] = sk[3 * i + j];
                in[6 * (3 + j) + i] = sk[3 * i + j];
            }
        }
        /* M_c kappa - b = (w x I w; m (w x (w x rho) - g)) */
        ctc_m3_mulv(iww, iw, w);
        ctc_v3_cross(load, w, iww);
        ctc_v3_cross(wr, w, rho);
        ctc_v3_cross(wwr, w, wr);
        ctc_v3_sub(load + 3, wwr, m->gravity);
        ctc_v3_scale(load + 3, load + 3, b->mass);
        ctc_v3_cross(wr, w, r12);
        ctc_v3_set(c, 0, 0, 0);
        ctc_v3_cross(c + 3, w, wr);
    }
    ctc_transfer_force(dim, rho, load, rec + CW(dim));
}

static inline double *record(const ctc_data *d, int a)
{
    return d->icomp + (size_t)a * d->csize;
}

/* When the composite inverse pass splits over threads (gdca_par.h): the least items (bodies,
 * nodes of one tree height) per chunk, and the least chain length from which a split is tried:
 * where the split pass first beat the serial one on 2 threads (bench/NOTEBOOK.md, "Parallel
 * assembly", "The thresholds"); from there the evaluation gate measures whether it pays
 * (data.h ctc_eval_gate). */
#define INVERSE_GRAIN_PLANAR 16
#define INVERSE_GRAIN_SPATIAL 4
#define INVERSE_MIN_BODIES_PLANAR 1024
#define INVERSE_MIN_BODIES_SPATIAL 256

/* what the stages of one inverse pass share (gdca_par.h) */
typedef struct inverse_args {
    const ctc_model *m;
    ctc_data *d;
    const double *u;
    double *f;
    int keep; /* 1: the body records and the nodes' I and r12 are those of this state */
} inverse_args;

/* f_j = P^T F of joint j */
static inline void inverse_drive(const ctc_model *m, const ctc_data *d, int j, double *f,
                                 const int dim)
{
    const double *P = d->jnt_P + 3 * dim * j, *load = d->jnt_load_inv + dim * j;
    for (int col = 0; col < m->jnt_nv[j]; col++) {
        double x = 0;
        for (int r = 0; r < dim; r++) x += P[col * dim + r] * load[r];
        f[m->jnt_vadr[j] + col] = x;
    }
}

/* the records of bodies lo..hi-1 */
static inline void inverse_bodies(const inverse_args *a, int lo, int hi, const int dim)
{
    for (int k = lo; k < hi; k++) body_record(a->m, a->d, k, record(a->d, k), dim);
}

/* r = joint c's centre - body k's handle 1 and e = (0; w x (w x r)) + P u + beta of joint c: a
   light child's subtree moves with A1 = T(r) A1(k) + e (model.c, "the plan of a branched tree") */
static inline void inverse_light_offset(const inverse_args *a, int k, int c, double r[3], double *e,
                                        const int dim)
{
    const ctc_model *m = a->m;
    const ctc_data *d = a->d;
    const double *w = d->omega + 3 * k, *P = d->jnt_P + 3 * dim * c, *beta = d->jnt_beta + dim * c;
    const double *uc = a->u + m->jnt_vadr[c];
    ctc_v3_sub(r, d->xpos + 3 * c, d->xpos + 3 * k);
    if (dim == 3) {
        const double w2 = w[2] * w[2];
        r[2] = 0;
        e[0] = 0, e[1] = -w2 * r[0], e[2] = -w2 * r[1];
    } else {
        double wr[3];
        ctc_v3_cross(wr, w, r);
        ctc_v3_set(e, 0, 0, 0);
        ctc_v3_cross(e + 3, w, wr);
    }
    for (int i = 0; i < dim; i++) e[i] += beta[i];
    for (int col = 0; col < m->jnt_nv[c]; col++) {
        for (int i = 0; i < dim; i++) e[i] += P[col * dim + i] * uc[col];
    }
}

/* the terms of operand x of a SUM or RAKE node of body k, added to in (unless keep) and w (add
   = 0: written): a light child c's (c >= 0) T(r)^T I^S T(r) and T(r)^T (I^S e + w^S), keeping e
   in icomp_e, or a SUM node's partial sums */
static inline void inverse_operand(const inverse_args *a, int k, int x, int c, double *in,
                                   double *w, int add, const int dim)
{
    ctc_data *d = a->d;
    const double *S = record(d, x);
    double ts[CTC_DENSE_MAX * CTC_DENSE_MAX], tw[CTC_DENSE_MAX];
    const double *ps = S + CI(dim), *pw = S + CW(dim);
    if (c >= 0) {
        double r[3], ie[CTC_DENSE_MAX], *e = d->icomp_e + dim * c;
        inverse_light_offset(a, k, c, r, e, dim);
        if (!a->keep) congruence(dim, r, S + CI(dim), ts);
        gdca_tmulv(dim, S + CI(dim), e, ie);
        for (int i = 0; i < dim; i++) ie[i] += S[CW(dim) + i];
        ctc_transfer_force(dim, r, ie, tw);
        ps = ts, pw = tw;
    }
    for (int i = 0; !a->keep && i < dim * dim; i++) in[i] = add ? in[i] + ps[i] : ps[i];
    for (int i = 0; i < dim; i++) w[i] = add ? w[i] + pw[i] : pw[i];
}

/* a SUM node's partial sums, or a RAKE node's record: body k's with its light children's
   composite inertias and biases added (c and r12 are k's own) */
static inline void inverse_rake_node(const inverse_args *a, const ctc_tree_node *node, double *N,
                                     const int dim)
{
    const ctc_data *d = a->d;
    const int k = node->body;
    if (node->kind == CTC_NODE_SUM) {
        inverse_operand(a, k, node->left, node->ljoint, N + CI(dim), N + CW(dim), 0, dim);
        inverse_operand(a, k, node->right, node->rjoint, N + CI(dim), N + CW(dim), 1, dim);
        return;
    }
    const double *B = record(d, k);
    if (!a->keep) {
        for (int i = 0; i < dim * dim; i++) N[CI(dim) + i] = B[CI(dim) + i];
        for (int i = 0; i < 3; i++) N[CR(dim) + i] = B[CR(dim) + i];
    }
    for (int i = 0; i < dim; i++) {
        N[CW(dim) + i] = B[CW(dim) + i];
        N[CC(dim) + i] = B[CC(dim) + i];
    }
    inverse_operand(a, k, node->left, node->ljoint, N + CI(dim), N + CW(dim), 1, dim);
}

/* a SUM or RAKE node's disassembly: body k's A1 handed to each operand; a light child's subtree
   gets A1 = T(r) A1(k) + e and F2 = 0, its joint the load F = I^S A1 + w^S */
static inline void inverse_rake_down(const inverse_args *a, int i, const int dim)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const ctc_tree_node *node = &m->tree[i];
    const double *a1 = d->tload + (size_t)(m->nbodies + i) * 2 * dim;
    const int ops = node->kind == CTC_NODE_SUM ? 2 : 1;
    for (int o = 0; o < ops; o++) {
        const int sub = o ? node->right : node->left, c = o ? node->rjoint : node->ljoint;
        double *t = d->tload + (size_t)sub * 2 * dim;
        if (c < 0) {
            for (int r = 0; r < dim; r++) t[r] = a1[r];
            continue;
        }
        const double *S = record(d, sub), *e = d->icomp_e + dim * c;
        double r3[3], *load = d->jnt_load_inv + dim * c;
        ctc_v3_sub(r3, d->xpos + 3 * c, d->xpos + 3 * node->body);
        if (dim == 3) r3[2] = 0;
        ctc_transfer_motion(dim, r3, a1, t);
        for (int r = 0; r < dim; r++) t[r] += e[r];
        gdca_tmulv(dim, S + CI(dim), t, load);
        for (int r = 0; r < dim; r++) {
            load[r] += S[CW(dim) + r];
            t[dim + r] = 0;
        }
        inverse_drive(m, d, c, a->f, dim);
    }
}

/* assembly of tree nodes lo..hi-1, children before parents; nothing is inverted, so no joint
   is singular: returns -1 */
static inline int inverse_assemble(const inverse_args *a, int lo, int hi, const int dim,
                                   const int tree)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int n = m->nbodies;
    for (int i = lo; i < hi; i++) {
        const ctc_tree_node *node = &m->tree[i];
        if (tree && node->kind != CTC_NODE_JOIN) {
            inverse_rake_node(a, node, record(d, n + i), dim);
            continue;
        }
        const double *L = record(d, node->left), *R = record(d, node->right);
        double *N = record(d, n + i), *e = d->icomp_e + dim * node->joint;
        const double *P = d->jnt_P + 3 * dim * node->joint, *beta = d->jnt_beta + dim * node->joint;
        const double *uj = a->u + m->jnt_vadr[node->joint];
        double s[CTC_DENSE_MAX * CTC_DENSE_MAX];
        double ie[CTC_DENSE_MAX], tf[CTC_DENSE_MAX];

        /* e = c^L + P u + beta */
        for (int r = 0; r < dim; r++) e[r] = L[CC(dim) + r] + beta[r];
        for (int col = 0; col < m->jnt_nv[node->joint]; col++) {
            for (int r = 0; r < dim; r++) e[r] += P[col * dim + r] * uj[col];
        }

        /* I = I^L + T^T I^R T (the state's: kept while a->keep),  w = w^L + T^T (I^R e + w^R) */
        if (!a->keep) {
            congruence(dim, L + CR(dim), R + CI(dim), s);
            gdca_add_sq(dim, L + CI(dim), s, N + CI(dim));
            ctc_v3_add(N + CR(dim), L + CR(dim), R + CR(dim));
        }
        gdca_tmulv(dim, R + CI(dim), e, ie); /* I is symmetric */
        for (int r = 0; r < dim; r++) ie[r] += R[CW(dim) + r];
        ctc_transfer_force(dim, L + CR(dim), ie, tf);
        for (int r = 0; r < dim; r++) N[CW(dim) + r] = L[CW(dim) + r] + tf[r];

        /* c = T(r12^R) e + c^R (r12 = r12^L + r12^R above) */
        ctc_transfer_motion(dim, R + CR(dim), e, tf);
        for (int r = 0; r < dim; r++) N[CC(dim) + r] = tf[r] + R[CC(dim) + r];
    }
    return -1;
}

/* the root of ground child j's subtree, assembled at x: A1 = P u + beta of joint j,
   F1 = I A1 + w (free end: F2 = 0) */
static inline void inverse_root_joint(const inverse_args *a, int j, int x, const int dim)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const double *root = record(d, x), *P = d->jnt_P + 3 * dim * j, *u = a->u + m->jnt_vadr[j];
    double *tl = d->tload + (size_t)x * 2 * dim, *load = d->jnt_load_inv + dim * j;
    for (int r = 0; r < dim; r++) tl[r] = d->jnt_beta[dim * j + r];
    for (int col = 0; col < m->jnt_nv[j]; col++) {
        for (int r = 0; r < dim; r++) tl[r] += P[col * dim + r] * u[col];
    }
    for (int r = 0; r < dim; r++) tl[dim + r] = 0;
    gdca_tmulv(dim, root + CI(dim), tl, load);
    for (int r = 0; r < dim; r++) load[r] += root[CW(dim) + r];
    inverse_drive(m, d, j, a->f, dim);
}

/* the root: a chain's ground joint 0, or each ground child's of a tree */
static inline void inverse_root(const inverse_args *a, const int dim)
{
    const ctc_model *m = a->m;
    if (m->chain) {
        inverse_root_joint(a, 0, m->root, dim);
        return;
    }
    for (int i = 0; i < m->nroots; i++)
        inverse_root_joint(a, m->root_joint[i], m->root_asm[i], dim);
}

/* disassembly of tree nodes hi-1 down to lo, parents before children:
   F = I^R A1^R + w^R - T(r12^R)^T F2, and the joint's driving force f = P^T F */
static inline void inverse_disassemble(const inverse_args *a, int lo, int hi, const int dim,
                                       const int tree)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int n = m->nbodies;
    for (int i = hi - 1; i >= lo; i--) {
        const ctc_tree_node *node = &m->tree[i];
        if (tree && node->kind != CTC_NODE_JOIN) {
            inverse_rake_down(a, i, dim);
            continue;
        }
        const double *L = record(d, node->left), *R = record(d, node->right);
        const double *a1 = d->tload + (size_t)(n + i) * 2 * dim, *f2 = a1 + dim;
        double *tlL = d->tload + (size_t)node->left * 2 * dim;
        double *tlR = d->tload + (size_t)node->right * 2 * dim;
        double *load = d->jnt_load_inv + dim * node->joint, tf[CTC_DENSE_MAX];
        const double *e = d->icomp_e + dim * node->joint;

        ctc_transfer_motion(dim, L + CR(dim), a1, tlR); /* A1^R */
        for (int r = 0; r < dim; r++) tlR[r] += e[r];
        gdca_tmulv(dim, R + CI(dim), tlR, load);
        ctc_transfer_force(dim, R + CR(dim), f2, tf);
        for (int r = 0; r < dim; r++) {
            load[r] += R[CW(dim) + r] - tf[r];
            tlR[dim + r] = f2[r];
            tlL[r] = a1[r];
            tlL[dim + r] = -load[r];
        }
        inverse_drive(m, d, node->joint, a->f, dim);
    }
}

/* the stages specialised to the planar and the spatial form */
static CTC_SPECIALISE void bodies_planar(void *a, int lo, int hi)
{
    inverse_bodies(a, lo, hi, 3);
}

static CTC_SPECIALISE void bodies_spatial(void *a, int lo, int hi)
{
    inverse_bodies(a, lo, hi, 6);
}

static CTC_SPECIALISE int assemble_planar(void *a, int lo, int hi)
{
    return inverse_assemble(a, lo, hi, 3, 0);
}

static CTC_SPECIALISE int assemble_spatial(void *a, int lo, int hi)
{
    return inverse_assemble(a, lo, hi, 6, 0);
}

static CTC_SPECIALISE int assemble_planar_tree(void *a, int lo, int hi)
{
    return inverse_assemble(a, lo, hi, 3, 1);
}

static CTC_SPECIALISE int assemble_spatial_tree(void *a, int lo, int hi)
{
    return inverse_assemble(a, lo, hi, 6, 1);
}

static CTC_SPECIALISE void root_planar(void *a)
{
    inverse_root(a, 3);
}

static CTC_SPECIALISE void root_spatial(void *a)
{
    inverse_root(a, 6);
}

static CTC_SPECIALISE void disassemble_planar(void *a, int lo, int hi)
{
    inverse_disassemble(a, lo, hi, 3, 0);
}

static CTC_SPECIALISE void disassemble_spatial(void *a, int lo, int hi)
{
    inverse_disassemble(a, lo, hi, 6, 0);
}

static CTC_SPECIALISE void disassemble_planar_tree(void *a, int lo, int hi)
{
    inverse_disassemble(a, lo, hi, 3, 1);
}

static CTC_SPECIALISE void disassemble_spatial_tree(void *a, int lo, int hi)
{
    inverse_disassemble(a, lo, hi, 6, 1);
}

/* body records, assembly and disassembly, serial or a tree height at a time (gdca_par.h) */
static void inverse_planar(const ctc_model *m, ctc_data *d, const double *u, double *f, int keep)
{
    inverse_args a = {m, d, u, f, keep};
    gdca_par_pass pass = {.ctx = &a,
                          .bodies = keep ? NULL : bodies_planar,
                          .assemble = m->chain ? assemble_planar : assemble_planar_tree,
                          .root = root_planar,
                          .disassemble = m->chain ? disassemble_planar : disassemble_planar_tree,
                          .grain = INVERSE_GRAIN_PLANAR,
                          .min_bodies = INVERSE_MIN_BODIES_PLANAR,
                          .gated = 1};
    gdca_par_run(m, d, &pass);
}

static void inverse_spatial(const ctc_model *m, ctc_data *d, const double *u, double *f, int keep)
{
    inverse_args a = {m, d, u, f, keep};
    gdca_par_pass pass = {.ctx = &a,
                          .bodies = keep ? NULL : bodies_spatial,
                          .assemble = m->chain ? assemble_spatial : assemble_spatial_tree,
                          .root = root_spatial,
                          .disassemble = m->chain ? disassemble_spatial : disassemble_spatial_tree,
                          .grain = INVERSE_GRAIN_SPATIAL,
                          .min_bodies = INVERSE_MIN_BODIES_SPATIAL,
                          .gated = 1};
    gdca_par_run(m, d, &pass);
}

void gdca_inverse_composite(const ctc_model *m, ctc_data *d, const double *u, double *f)
{
    const int keep = d->icomp_stamp == d->handles_stamp;
    if (m->form == CTC_FORM_PLANAR) {
        inverse_planar(m, d, u, f, keep);
    } else {
        inverse_spatial(m, d, u, f, keep);
    }
    d->icomp_stamp = d->handles_stamp;
}

void gdca_inverse_handle2_accel(const ctc_model *m, const ctc_data *d, int k, double *a)
{
    const int dim = m->dim;
    const double *rec = record(d, k), *a1 = d->tload + (size_t)k * 2 * dim;
    ctc_transfer_motion(dim, rec + CR(dim), a1, a);
    for (int r = 0; r < dim; r++) a[r] += rec[CC(dim) + r];
}

void ctc_gdca_inverse(const ctc_model *m, ctc_data *d, const double *u, double *f)
{
    if (m->dyn != NULL) { /* merged bodies (model.h): the reduced model's pass, the same vectors */
        ctc_gdca_inverse(m->dyn, ctc_data_dyn_begin(m, d), u, f);
        ctc_data_dyn_end(m, d);
        return;
    }
    if (m->has_loop) { /* gdca_inverse_loop.h: the open chain's composite pass, then the loop */
        gdca_inverse_loop(m, d, u, f);
        return;
    }
    gdca_inverse_composite(m, d, u, f);
}
