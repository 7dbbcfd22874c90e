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
 * joints' driving forces are taken as zero.
 *
 * The nodes of one tree height are independent: each node's assembly writes only its own record
 * and its joint's E and z, its disassembly only its joint's load and acceleration and its two
 * children's terminal loads, so gdca_par.c may split a height over threads (ctc_data_set_threads)
 * with bitwise the serial results; the root stays on the caller's thread.
 */
#include "gdca.h"

#include <math.h>
#include <string.h>

#include "gdca_loop.h"
#include "gdca_par.h"
#include "gdca_refine.h"
#include "gdca_tree.h"

/* the factor E of W = E E^T and z = W Y + P f of joint j between left (NULL: ground) and right;
 * returns 0, or -1 when D^T K D is not positive definite (the results are then NaN) */
static inline int forward_joint(const ctc_model *m, ctc_data *d, int j, const double *left,
                                const double *right, const double *f, const int dim)
{
    const int nv = m->jnt_nv[j];
    double *e = d->fwd_E + dim * dim * j, *z = d->fwd_z + dim * j;
    double k[CTC_DENSE_MAX * CTC_DENSE_MAX], y[CTC_DENSE_MAX], pf[CTC_DENSE_MAX];
    double kpf[CTC_DENSE_MAX];

    gdca_joint_K(dim, left, right, k);
    int st = gdca_joint_factor(dim, k, d->jnt_D + dim * dim * j, dim - nv, e);
    gdca_joint_map(dim, nv, d->jnt_P + 3 * dim * j, f + m->jnt_vadr[j], pf);
    ctc_dense_mulv(dim, dim, k, pf, kpf);
    gdca_joint_Y0(dim, left, right, d->jnt_beta + dim * j, y);
    for (int i = 0; i < dim; i++) y[i] -= kpf[i];
    gdca_factor_apply(dim, dim - nv, e, y, z);
    for (int i = 0; i < dim; i++) z[i] += pf[i];
    return st;
}

/* qdd_j = P^T (A1^R - A2^L - beta) written into qacc */
static inline void forward_qacc(const ctc_model *m, const ctc_data *d, int j, const double *a1r,
                                const double *a2l, double *qacc, const int dim)
{
    const double *P = d->jnt_P + 3 * dim * j, *beta = d->jnt_beta + dim * j;
    for (int c = 0; c < m->jnt_nv[j]; c++) {
        double s = 0;
        for (int i = 0; i < dim; i++) s += P[c * dim + i] * (a1r[i] - a2l[i] - beta[i]);
        qacc[m->jnt_vadr[j] + c] = s;
    }
}

/* a loop model's root: joint 0 and the closing joint n both join the ground (gdca_loop.h) */
static inline void forward_loop_root(const ctc_model *m, ctc_data *d, const double *f, double *qacc,
                                     const int dim)
{
    const int n = m->nbodies;
    const double *root = ctc_data_handles(m, d, m->root, 0);
    double *tl = d->tload + (size_t)m->root * 2 * dim;
    double pf1[CTC_DENSE_MAX], pf2[CTC_DENSE_MAX], a1[CTC_DENSE_MAX], a2[CTC_DENSE_MAX];
    double off[CTC_DENSE_MAX];
    static const double rest[CTC_DENSE_MAX] = {0, 0, 0, 0, 0, 0};
    const int nc2 = dim - m->jnt_nv[n];

    gdca_joint_map(dim, m->jnt_nv[0], d->jnt_P, f, pf1);
    gdca_joint_map(dim, m->jnt_nv[n], d->jnt_P + 3 * dim * n, f + m->jnt_vadr[n], pf2);
    for (int c = 0; c < nc2; c++) {
        off[c] = 2 * d->baumgarte[0] * d->loop_dphi[c] +
                 d->baumgarte[1] * d->baumgarte[1] * d->loop_phi[c];
    }
    gdca_end e1 = {d->jnt_D, dim - m->jnt_nv[0], pf1, d->jnt_beta, NULL};
    gdca_end e2 = {d->jnt_D + dim * dim * n, nc2, pf2, d->jnt_beta + dim * n, off};
    if (gdca_loop_boundary(dim, root, &e1, &e2, tl, tl + dim, a1, a2, &d->loop_cond) != 0) {
        if (d->singular_joint < 0) d->singular_joint = n;
    }
    for (int i = 0; i < dim; i++) {
        d->jnt_load[i] = tl[i];
        d->jnt_load[dim * n + i] = -tl[dim + i];
    }
    forward_qacc(m, d, 0, a1, rest, qacc, dim);
    forward_qacc(m, d, n, rest, a2, qacc, dim); /* A(ground) = 0 = A2 + P qdd + beta */
}

/* When the forward pass splits over threads (gdca_par.h): the least nodes per chunk of one tree
 * height, and the least chain length. From bench_parallel on 2 threads, idle machine
 * (bench/README.md, "Parallel assembly"): grain 1 did best at every n and 2 within 3% (2 keeps
 * chunks of two nodes for larger thread counts); the split pass alone beat the serial one from
 * n = 256 planar (1.15x) and n = 64 spatial (1.39x), but a CTC evaluation, whose serial
 * kinematics and handles leave the records in the caller's cache, gained only from 512 planar
 * (0.80x at 256, 0.98-1.0x at 512, 1.32x at 1024 with the inverse split too) and 128 spatial
 * (1.10x). */
#define FORWARD_GRAIN_PLANAR 2
#define FORWARD_GRAIN_SPATIAL 2
#define FORWARD_MIN_BODIES_PLANAR 512
#define FORWARD_MIN_BODIES_SPATIAL 128

/* what the stages of one forward pass share (gdca_par.h) */
typedef struct forward_args {
    const ctc_model *m;
    ctc_data *d;
    const double *f;
    double *qacc;
} forward_args;

/* assembly of tree nodes lo..hi-1, children before parents; returns the first node whose joint
   is singular, or -1 */
static inline int forward_assemble(const forward_args *a, int lo, int hi, const int dim)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int hs = d->hsize;
    int first = -1;
    for (int i = lo; i < hi; i++) {
        const ctc_tree_node *node = &m->tree[i];
        const double *left = ctc_data_handles(m, d, node->left, 0);
        const double *right = ctc_data_handles(m, d, node->right, 0);
        int j = node->joint;
        if (forward_joint(m, d, j, left, right, a->f, dim) != 0 && first < 0) first = i;
        gdca_assemble(dim, dim - m->jnt_nv[j], left, right, d->fwd_E + dim * dim * j,
                      d->fwd_z + dim * j, d->hfwd + (size_t)i * hs);
    }
    return first;
}

/* the root: a loop model's, or the ground joint 0 with the free end's load F2 = 0 */
static inline void forward_root(const forward_args *a, const int dim)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    if (m->has_loop) {
        forward_loop_root(m, d, a->f, a->qacc, dim);
        return;
    }
    const double *root = ctc_data_handles(m, d, m->root, 0);
    double *tl = d->tload + (size_t)m->root * 2 * dim, a1[CTC_DENSE_MAX];
    static const double rest[CTC_DENSE_MAX] = {0, 0, 0, 0, 0, 0};
    if (forward_joint(m, d, 0, NULL, root, a->f, dim) != 0 && d->singular_joint < 0) {
        d->singular_joint = 0;
    }
    for (int i = 0; i < dim; i++) {
        tl[i] = d->fwd_z[i];
        tl[dim + i] = 0;
        d->jnt_load[i] = tl[i];
    }
    ctc_dense_mulv(dim, dim, root + H11(dim), tl, a1);
    for (int i = 0; i < dim; i++) a1[i] += root[H13(dim) + i];
    forward_qacc(m, d, 0, a1, rest, a->qacc, dim);
}

/* disassembly of tree nodes hi-1 down to lo, parents before children: each writes its joint's
   load and acceleration and its children's terminal loads */
static inline void forward_disassemble(const forward_args *a, int lo, int hi, const int dim)
{
    const ctc_model *m = a->m;
    ctc_data *d = a->d;
    const int n = m->nbodies;
    for (int i = hi - 1; i >= lo; i--) {
        const ctc_tree_node *node = &m->tree[i];
        const double *left = ctc_data_handles(m, d, node->left, 0);
        const double *right = ctc_data_handles(m, d, node->right, 0);
        const double *f1 = d->tload + (size_t)(n + i) * 2 * dim, *f2 = f1 + dim;
        int j = node->joint;
        double *fj = d->jnt_load + dim * j, a1r[CTC_DENSE_MAX], a2l[CTC_DENSE_MAX];
        double t[CTC_DENSE_MAX];
        gdca_joint_load(dim, dim - m->jnt_nv[j], left, right, d->fwd_E + dim * dim * j,
                        d->fwd_z + dim * j, f1, f2, fj);

        /* A1^R = h11^R F + h12^R F2 + h13^R,  A2^L = h21^L F1 - h22^L F + h23^L */
        ctc_dense_mulv(dim, dim, right + H11(dim), fj, a1r);
        ctc_dense_mulv(dim, dim, right + H12(dim), f2, t);
        for (int r = 0; r < dim; r++) a1r[r] += t[r] + right[H13(dim) + r];
        ctc_dense_tmulv(dim, dim, left + H12(dim), f1, a2l);
        ctc_dense_mulv(dim, dim, left + H22(dim), fj, t);
        for (int r = 0; r < dim; r++) a2l[r] += left[H23(dim) + r] - t[r];
        forward_qacc(m, d, j, a1r, a2l, a->qacc, dim);

        gdca_pass_loads(dim, d->tload, node, f1, f2, fj);
    }
}

/* the stages specialised to the planar and the spatial form */
static CTC_SPECIALISE int assemble_planar(void *a, int lo, int hi)
{
    return forward_assemble(a, lo, hi, 3);
}

static CTC_SPECIALISE int assemble_spatial(void *a, int lo, int hi)
{
    return forward_assemble(a, lo, hi, 6);
}

static CTC_SPECIALISE void root_planar(void *a)
{
    forward_root(a, 3);
}

static CTC_SPECIALISE void root_spatial(void *a)
{
    forward_root(a, 6);
}

static CTC_SPECIALISE void disassemble_planar(void *a, int lo, int hi)
{
    forward_disassemble(a, lo, hi, 3);
}

static CTC_SPECIALISE void disassemble_spatial(void *a, int lo, int hi)
{
    forward_disassemble(a, lo, hi, 6);
}

/* assembly and disassembly over the tree, serial or a tree height at a time (gdca_par.h) */
static void forward_planar(const ctc_model *m, ctc_data *d, const double *f, double *qacc)
{
    forward_args a = {m, d, f, qacc};
    gdca_par_pass pass = {.ctx = &a,
                          .assemble = assemble_planar,
                          .root = root_planar,
                          .disassemble = disassemble_planar,
                          .grain = FORWARD_GRAIN_PLANAR,
                          .min_bodies = FORWARD_MIN_BODIES_PLANAR};
    gdca_par_run(m, d, &pass);
}

static void forward_spatial(const ctc_model *m, ctc_data *d, const double *f, double *qacc)
{
    forward_args a = {m, d, f, qacc};
    gdca_par_pass pass = {.ctx = &a,
                          .assemble = assemble_spatial,
                          .root = root_spatial,
                          .disassemble = disassemble_spatial,
                          .grain = FORWARD_GRAIN_SPATIAL,
                          .min_bodies = FORWARD_MIN_BODIES_SPATIAL};
    gdca_par_run(m, d, &pass);
}

void ctc_gdca_forward(const ctc_model *m, ctc_data *d, const double *f, double *qacc)
{
    if (m->has_loop) { /* dependent joints carry no driving force */
        double *fm = d->xbuf;
        memset(fm, 0, (size_t)m->nvx * sizeof *fm);
        for (int i = 0; i < m->nind; i++) fm[m->ind_coord[i]] = f[m->ind_coord[i]];
        f = fm;
    }
    if (m->form == CTC_FORM_PLANAR) {
        forward_planar(m, d, f, qacc);
    } else {
        forward_spatial(m, d, f, qacc);
    }

    /* refinement (gdca_refine.h): r = f - (M qacc + N) by the composite inverse, qacc += M^-1 r,
       until the correction converges or stalls */
    const int steps = gdca_refine_steps(m, d);
    double *r = d->fwd_res, *dq = d->fwd_res + m->nv, last = INFINITY;
    d->fwd_refine_done = 0;
    for (int s = 0; s < steps && d->singular_joint < 0; s++) {
        ctc_gdca_inverse(m, d, qacc, r);
        for (int i = 0; i < m->nv; i++) r[i] = f[i] - r[i];
        gdca_forward_correct(m, d, r, dq);
        /* the largest |qacc| and |dq|: plain comparisons, not libm's fmax (a call each); a NaN
           is skipped either way */
        double amax = 0, dmax = 0;
        for (int i = 0; i < m->nv; i++) {
            qacc[i] += dq[i];
            double aa = fabs(qacc[i]), ad = fabs(dq[i]);
            if (aa > amax) amax = aa;
            if (ad > dmax) dmax = ad;
        }
        d->fwd_refine_done++;
        if (dmax <= CTC_REFINE_CONVERGED * amax || dmax * CTC_REFINE_STALL > last) break;
        last = dmax;
    }
}
