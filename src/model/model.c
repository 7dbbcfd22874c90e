/*
 * model.c - building, validating and describing a kinematic tree (model.h).
 *
 * The builder copies the spec, checks every number (finite, masses not negative, inertias
 * symmetric, positive semidefinite and, on bodies with mass, satisfying the triangle inequality of
 * principal moments, axes of non-zero length), decides the form (planar when every joint moves in
 * one plane and gravity lies in it, DESIGN.md section 3; per joint, so a tree needs nothing more),
 * precomputes what the kinematics and handle passes need per body (a singular body's augmented
 * inertia, model.h "singular bodies", and then the mass matrix's check at a generic
 * configuration), records the topology (each body's parent,
 * lambda(k), from the spec's parent array, and its children), and lays out the assembly plan of
 * GDCA, nodes stored by height so that the nodes of one height are independent of each other.
 * A chain's plan is the balanced binary tree (paper section 3, Fig. 3): bodies [first, last]
 * split at the middle, depth ceil(log2 n); a loop closed on body b splits the root at joint b + 1
 * instead (at most one level more), so that the loop's bodies form one subtree. A branched tree's
 * plan joins each heavy path as a chain and rakes the light subtrees into their parents ("the
 * plan of a branched tree" below). A loop on a tree lies on the spine, the path from the ground to
 * the tip: its heavy children are forced along it and the root path's top node splits at the
 * loop's first joint, so the loop's bodies form one subtree as on a chain. Last, when bodies sit
 * on fixed joints, it builds the reduced model of the dynamics passes, each such body merged into
 * its parent's (model.h "merged bodies"; "merged bodies" below).
 */
#include "model.h"

#include <assert.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "data.h"
#include "dense.h"
#include "kinematics.h"
#include "loop.h"
#include "oracle.h"
#include "spatial.h"

/* relative tolerance under which axes count as (anti)parallel */
#define AXIS_ALIGN_TOL 1e-12

const char *ctc_form_name(ctc_form f)
{
    switch (f) {
    case CTC_FORM_AUTO:
        return "auto";
    case CTC_FORM_PLANAR:
        return "planar";
    case CTC_FORM_SPATIAL:
        return "spatial";
    }
    return "unknown";
}

static int all_finite(const double *x, int n, int *bad)
{
    for (int i = 0; i < n; i++) {
        if (!isfinite(x[i])) {
            *bad = i;
            return 0;
        }
    }
    return 1;
}

/* The kinds that may close a loop, as a list for a message: "revolute, prismatic or
 * spherical". */
static void loop_closing_names(char *out, size_t len)
{
    int count = 0, seen = 0;
    for (int t = 0; t < CTC_JOINT_NTYPES; t++) count += ctc_joint_classes[t].loop_closing;
    out[0] = '\0';
    for (int t = 0; t < CTC_JOINT_NTYPES; t++) {
        if (!ctc_joint_classes[t].loop_closing) continue;
        size_t used = strlen(out);
        const char *sep = seen == 0 ? "" : seen == count - 1 ? " or " : ", ";
        snprintf(out + used, len - used, "%s%s", sep, ctc_joint_classes[t].name);
        seen++;
    }
}

/* Checks one body's numbers; writes its principal moments (ascending) into eig. lumped: the body
 * is a composite of merged bodies (model.h "merged bodies"), whose massless parts' lumped inertias
 * need not satisfy the triangle inequality, so neither need it. */
static ctc_status check_body(const ctc_body_spec *b, int k, int lumped, double eig[3], char *err,
                             size_t errlen)
{
    int bad;
    if (!isfinite(b->mass)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "body %d: mass is not finite", k);
    }
    if (b->mass < 0) {
        return ctc_fail(CTC_EINVAL, err, errlen, "body %d: mass must not be negative (got %g kg)",
                        k, b->mass);
    }
    if (!all_finite(b->com, 3, &bad)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "body %d: com[%d] is not finite", k, bad);
    }
    if (!all_finite(b->inertia, 9, &bad)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "body %d: inertia[%d][%d] is not finite", k,
                        bad / 3, bad % 3);
    }

    /* symmetric, to rounding */
    const double *in = b->inertia;
    double scale = 0;
    for (int i = 0; i < 9; i++) scale = fmax(scale, fabs(in[i]));
    for (int i = 0; i < 3; i++) {
        for (int j = i + 1; j < 3; j++) {
            if (fabs(in[3 * i + j] - in[3 * j + i]) > 1e-9 * scale) {
                return ctc_fail(CTC_EINVAL, err, errlen,
                                "body %d: inertia is not symmetric (inertia[%d][%d] = %g, "
                                "inertia[%d][%d] = %g)",
                                k, i, j, in[3 * i + j], j, i, in[3 * j + i]);
            }
        }
    }

    /* principal moments: none negative; with mass, the triangle inequality (zero moments are a
       singular body's, model.h) */
    ctc_sym3_eigenvalues(in, eig);
    double tol = CTC_INERTIA_ZERO_REL * eig[2];
    if (eig[0] < -tol) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "body %d: inertia is not positive definite (principal moment %g kg m^2)", k,
                        eig[0]);
    }
    if (b->mass > 0 && !lumped && eig[0] + eig[1] < eig[2] * (1.0 - 1e-9)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "body %d: inertia violates the triangle inequality (principal moments "
                        "%g + %g < %g kg m^2)",
                        k, eig[0], eig[1], eig[2]);
    }
    return CTC_OK;
}

static ctc_status check_joint(const ctc_joint_spec *j, int k, char *err, size_t errlen)
{
    int bad;
    const ctc_joint_class *c = ctc_joint_class_of(j->type);
    if (c == NULL) {
        return ctc_fail(CTC_EINVAL, err, errlen, "joint %d: unknown joint type %d", k,
                        (int)j->type);
    }
    if (!all_finite(j->location, 3, &bad)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "joint %d: location[%d] is not finite", k, bad);
    }
    if (c->needs_axis) {
        if (!all_finite(j->axis, 3, &bad)) {
            return ctc_fail(CTC_EINVAL, err, errlen, "joint %d: axis[%d] is not finite", k, bad);
        }
        if (!(ctc_v3_norm(j->axis) > 1e-12)) {
            return ctc_fail(CTC_EINVAL, err, errlen, "joint %d: axis has zero length", k);
        }
    }
    return CTC_OK;
}

/* Chooses the plane normal n a planar chain would move in (unit, largest component positive):
 * the first revolute axis; else the normal of two prismatic axes, or of one and gravity. */
static void plane_normal(const ctc_model *m, double n[3])
{
    const double *u = NULL;
    ctc_v3_set(n, 0, 0, 1);
    for (int k = 0; k < m->njoints; k++) {
        const ctc_joint_spec *j = &m->joints[k];
        if (j->type == CTC_JOINT_REVOLUTE) {
            ctc_v3_copy(n, j->axis);
            u = NULL;
            break;
        }
        if (j->type != CTC_JOINT_PRISMATIC) continue;
        if (u == NULL) {
            u = j->axis;
            continue;
        }
        double c[3];
        ctc_v3_cross(c, u, j->axis);
        if (ctc_v3_norm(c) > AXIS_ALIGN_TOL) {
            ctc_v3_scale(n, c, 1.0 / ctc_v3_norm(c));
            u = NULL;
            break;
        }
    }
    if (u != NULL) { /* only parallel prismatic axes: use gravity, else any normal */
        double c[3], n2[3];
        ctc_v3_cross(c, u, m->gravity);
        if (ctc_v3_norm(c) > AXIS_ALIGN_TOL * ctc_v3_norm(m->gravity)) {
            ctc_v3_scale(n, c, 1.0 / ctc_v3_norm(c));
        } else {
            ctc_v3_normals(u, n, n2);
        }
    }
    int big = 0;
    for (int i = 1; i < 3; i++) {
        if (fabs(n[i]) > fabs(n[big])) big = i;
    }
    if (n[big] < 0) ctc_v3_scale(n, n, -1.0);
}

/* Returns 1 if the chain moves in the plane normal to n; otherwise 0 and why in why. */
static int chain_is_planar(const ctc_model *m, const double n[3], char *why, size_t whylen)
{
    for (int k = 0; k < m->njoints; k++) {
        const ctc_joint_spec *j = &m->joints[k];
        double c[3];
        if (!ctc_joint_classes[j->type].planar) {
            ctc_fail(CTC_EINVAL, why, whylen, "joint %d: a %s joint moves out of any plane", k,
                     ctc_joint_type_name(j->type));
            return 0;
        }
        /* how each planar kind's axis lies in the plane */
        if (j->type == CTC_JOINT_REVOLUTE) {
            ctc_v3_cross(c, j->axis, n);
            if (ctc_v3_norm(c) > AXIS_ALIGN_TOL) {
                ctc_fail(CTC_EINVAL, why, whylen,
                         "joint %d: revolute axis is not normal to the plane of motion", k);
                return 0;
            }
        } else if (j->type == CTC_JOINT_PRISMATIC) {
            if (fabs(ctc_v3_dot(j->axis, n)) > AXIS_ALIGN_TOL) {
                ctc_fail(CTC_EINVAL, why, whylen,
                         "joint %d: prismatic axis is not in the plane of motion", k);
                return 0;
            }
        }
    }
    if (fabs(ctc_v3_dot(m->gravity, n)) > AXIS_ALIGN_TOL * ctc_v3_norm(m->gravity)) {
        ctc_fail(CTC_EINVAL, why, whylen, "gravity is not in the plane of motion");
        return 0;
    }
    return 1;
}

/* Fills the plane's basis and each body's planar data (form PLANAR). */
static ctc_status setup_planar(ctc_model *m, const double n[3], char *err, size_t errlen)
{
    double *e1 = m->plane_e1, *e2 = m->plane_e2;
    ctc_v3_copy(m->plane_n, n);

    /* e1: the world axis after n's largest component, made normal to n; e2 = n x e1 */
    int big = 0;
    for (int i = 1; i < 3; i++) {
        if (fabs(n[i]) > fabs(n[big])) big = i;
    }
    double a[3] = {0, 0, 0};
    a[(big + 1) % 3] = 1.0;
    ctc_v3_addscl(e1, a, n, -ctc_v3_dot(a, n));
    ctc_v3_scale(e1, e1, 1.0 / ctc_v3_norm(e1));
    ctc_v3_cross(e2, n, e1);
    m->plane_gravity[0] = ctc_v3_dot(m->gravity, e1);
    m->plane_gravity[1] = ctc_v3_dot(m->gravity, e2);

    m->planar = calloc((size_t)m->nbodies, sizeof *m->planar);
    if (m->planar == NULL) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    for (int k = 0; k < m->nbodies; k++) {
        const ctc_body_spec *b = &m->bodies[k];
        const ctc_joint_spec *j = &m->joints[k];
        ctc_planar_body *p = &m->planar[k];
        double in[3];
        ctc_m3_mulv(in, b->inertia, n);
        const ctc_body_spec *fb = &m->fwd_bodies[k];
        p->mass = b->mass;
        p->inertia = ctc_v3_dot(n, in);
        ctc_m3_mulv(in, fb->inertia, n);
        p->fwd_mass = fb->mass;
        p->fwd_inertia = ctc_v3_dot(n, in);
        p->com[0] = ctc_v3_dot(b->com, e1);
        p->com[1] = ctc_v3_dot(b->com, e2);
        p->loc[0] = ctc_v3_dot(j->location, e1);
        p->loc[1] = ctc_v3_dot(j->location, e2);
        p->axis[0] = ctc_v3_dot(j->axis, e1);
        p->axis[1] = ctc_v3_dot(j->axis, e2);
        p->sign = ctc_v3_dot(j->axis, n) < 0 ? -1.0 : 1.0;
    }
    if (m->has_loop) {
        const ctc_joint_spec *j = &m->joints[m->nbodies];
        ctc_planar_body *p = &m->loop_planar;
        p->loc[0] = ctc_v3_dot(j->location, e1);
        p->loc[1] = ctc_v3_dot(j->location, e2);
        p->axis[0] = ctc_v3_dot(j->axis, e1);
        p->axis[1] = ctc_v3_dot(j->axis, e2);
        p->sign = ctc_v3_dot(j->axis, n) < 0 ? -1.0 : 1.0;
        m->loop_anchor2[0] = ctc_v3_dot(m->loop_anchor, e1);
        m->loop_anchor2[1] = ctc_v3_dot(m->loop_anchor, e2);
    }
    return CTC_OK;
}

/* The topology from the parent array body_parent (filled by the caller): the children of each
 * body and of the ground as first-child / next-sibling lists in increasing order (model.h). Walks
 * the bodies from the tip down, pushing each onto the front of its parent's list. */
static void build_topology(ctc_model *m)
{
    m->ground_child = -1;
    for (int k = 0; k < m->nbodies; k++) m->body_child[k] = -1;
    for (int k = m->nbodies - 1; k >= 0; k--) {
        int p = m->body_parent[k];
        int *first = p < 0 ? &m->ground_child : &m->body_child[p];
        m->body_sibling[k] = *first;
        *first = k;
    }
}

/* Builds the subtree of bodies [first, last] into tmp (post-order); returns its assembly index
 * in tmp's numbering (n + position in tmp) or the body index for a leaf. */
static int build_subtree(ctc_model *m, ctc_tree_node *tmp, int *count, int first, int last, int mid)
{
    if (first == last) return first;
    if (mid <= first) mid = first + (last - first + 1) / 2; /* the right part starts at mid */
    /* the assembly tree splits a chain of consecutive bodies: joint mid joins the left part's
       last body (mid - 1, its handle 2) to the right part's first (mid, its handle 1), which
       holds only while body mid's parent is mid - 1 (a chain: build_tree) */
    assert(m->body_parent[mid] == mid - 1);
    int left = build_subtree(m, tmp, count, first, mid - 1, 0);
    int right = build_subtree(m, tmp, count, mid, last, 0);
    int hl = left < m->nbodies ? 0 : tmp[left - m->nbodies].height;
    int hr = right < m->nbodies ? 0 : tmp[right - m->nbodies].height;
    ctc_tree_node *node = &tmp[*count];
    node->left = left;
    node->right = right;
    node->joint = mid;
    node->first = first;
    node->last = last;
    node->kind = CTC_NODE_JOIN;
    node->body = node->ljoint = node->rjoint = -1;
    node->height = 1 + (hl > hr ? hl : hr);
    return m->nbodies + (*count)++;
}

/* ---- the plan of a branched tree ----
 *
 * GDCA joins two-handle assemblies; a body with several children has more handles than two. The
 * plan reduces a tree to chains by heavy-path decomposition (Sleator and Tarjan's heavy-light
 * split): a body's heavy child is its child with the largest subtree (ties: the lowest index),
 * the heavy children link the bodies into paths, and each path is a chain whose bodies' handle 2
 * is the heavy child's joint (handles.c). A light child c of body k heads a path of its own; once
 * that path is assembled, with its tip free (F2 = 0), its handle-1 equation A1 = h11 F + h13
 * (h11 its inverse articulated inertia) is an articulated body seen through joint c. Joint c
 * gives, exactly as the root joint of a chain does (DESIGN.md section 4 with the ground replaced
 * by body k's point c, whose acceleration A_c is left free), the load on the subtree
 *     F_c = W_c A_c + z_c,   W_c = D (D^T h11 D)^-1 D^T,   z_c = W_c (beta - h13 - h11 P f) + P f,
 * W_c being the subtree's articulated inertia projected through the joint (Featherstone's
 * Ia - Ia P (P^T Ia P)^-1 P^T Ia, Ia = h11^-1; the inverse passes: W_c = Ia, all of the motion
 * prescribed). Body k's Newton-Euler equations about its centre of mass, M X = b + sum_i T_i^T F_i
 * (X = (alpha, a_com), T_i the transfer to handle i), with -F_c acting at c and
 * A_c = T_c X + kappa_c, become
 *     M' X = b' + T_1^T F_1 + T_2^T F_2,   M' = M + sum_c T_c^T W_c T_c,
 *     b' = b - sum_c T_c^T (W_c kappa_c + z_c),
 * a pseudo-body (a RAKE node) whose handle equations h_ij = T_i M'^-1 T_j^T,
 * h_i3 = T_i M'^-1 b' + kappa_i take the place of body k's in its path (gdca_rake.h). The sums
 * over k's light children run over a binary tree of SUM nodes, so a star's rake is O(log n)
 * deep too. Disassembly reverses it: the pseudo-body's loads give X, then each light child's
 * F_c, its joint's acceleration, and its path's disassembly as a chain's from its root.
 *
 * Each path is split into a binary tree of JOIN nodes weighted by what hangs from each of its
 * bodies (the body and its light subtrees, size[k] - size[heavy]): the left part is the longest
 * prefix whose weight is at most half the segment's. An element's depth in its path's tree is then
 * O(log(W / w)) for a segment of weight W and an element of weight w, and a light subtree weighs
 * at most half its parent's, so the plan's height is O(log n) for chains, stars, binary and
 * random trees alike (a biased search tree's argument). Work stays O(n): every body is a leaf of
 * one path, every light child one operand of one SUM or RAKE node. A chain keeps its balanced
 * split at the middle (build_subtree), which this rule gives for unit weights. */
typedef struct plan_ctx {
    ctc_model *m;
    ctc_tree_node *tmp; /* the nodes in post-order */
    int count;
    int *size;      /* (n) subtree sizes */
    int *seg;       /* scratch (2n + 1): the assembly indices of the leaves or operands in hand */
    int *segb;      /* their bodies (a path's) or light children (a rake's) */
    long long *pre; /* prefix sums of their weights */
    int split;      /* a loop's first joint (model.h loop_first) where the spine's top node splits;
                       -1 once split, or none */
} plan_ctx;

static int plan_height(const plan_ctx *p, int a)
{
    return a < p->m->nbodies ? 0 : p->tmp[a - p->m->nbodies].height;
}

/* appends a node (its height from its operands); returns its assembly index */
static int plan_emit(plan_ctx *p, ctc_tree_node node)
{
    int h = plan_height(p, node.left);
    if (node.right >= 0 && plan_height(p, node.right) > h) h = plan_height(p, node.right);
    node.height = 1 + h;
    p->tmp[p->count] = node;
    return p->m->nbodies + p->count++;
}

/* the split of scratch elements lo..hi (lo < hi): the largest mid in lo+1..hi whose left part
   lo..mid-1 weighs at most half of lo..hi, or lo + 1 */
static int plan_split(const plan_ctx *p, int lo, int hi)
{
    const long long *pre = p->pre;
    int a = lo + 1, b = hi;
    if (2 * (pre[a] - pre[lo]) > pre[hi + 1] - pre[lo]) return a;
    while (a < b) {
        int mid = a + (b - a + 1) / 2;
        if (2 * (pre[mid] - pre[lo]) <= pre[hi + 1] - pre[lo]) {
            a = mid;
        } else {
            b = mid - 1;
        }
    }
    return a;
}

/* JOIN nodes over the path segment in scratch lo..hi; returns its assembly index */
static int plan_join(plan_ctx *p, int lo, int hi)
{
    if (lo == hi) return p->seg[lo];
    int mid = plan_split(p, lo, hi);
    if (p->split > 0 && p->segb[lo] == p->m->ground_child) { /* the spine's top: split there */
        for (int i = lo + 1; i <= hi; i++) {
            if (p->segb[i] == p->split) mid = i;
        }
        p->split = -1;
    }
    int left = plan_join(p, lo, mid - 1), right = plan_join(p, mid, hi);
    ctc_tree_node node = {.left = left,
                          .right = right,
                          .joint = p->segb[mid],
                          .first = p->segb[lo],
                          .last = p->segb[hi],
                          .kind = CTC_NODE_JOIN,
                          .body = -1,
                          .ljoint = -1,
                          .rjoint = -1};
    return plan_emit(p, node);
}

/* the first light child's joint under operand (a, j) */
static int plan_first_joint(const plan_ctx *p, int a, int j)
{
    return j >= 0 ? j : p->tmp[a - p->m->nbodies].joint;
}

/* SUM nodes over body k's light children in scratch lo..hi; returns the operand's assembly index
   and, in *joint, the light child when the operand is one subtree (else -1) */
static int plan_sum(plan_ctx *p, int k, int lo, int hi, int *joint)
{
    if (lo == hi) {
        *joint = p->segb[lo];
        return p->seg[lo];
    }
    int mid = plan_split(p, lo, hi), jl, jr;
    int left = plan_sum(p, k, lo, mid - 1, &jl), right = plan_sum(p, k, mid, hi, &jr);
    ctc_tree_node node = {.left = left,
                          .right = right,
                          .joint = plan_first_joint(p, left, jl),
                          .first = k,
                          .last = k,
                          .kind = CTC_NODE_SUM,
                          .body = k,
                          .ljoint = jl,
                          .rjoint = jr};
    *joint = -1;
    return plan_emit(p, node);
}

static void plan_prefix(plan_ctx *p, int lo, int hi, const long long *w)
{
    p->pre[lo] = 0;
    for (int i = lo; i <= hi; i++) p->pre[i + 1] = p->pre[i] + w[i - lo];
}

/* the path headed by body head and everything hanging from it, with scratch from top; returns
   its assembly index */
static int plan_path(plan_ctx *p, int head, int top)
{
    const ctc_model *m = p->m;
    int len = 0;
    for (int k = head; k >= 0; k = m->body_heavy[k]) len++;
    const int lo = top;
    top += len;
    long long wbuf[64], *w = len <= 64 ? wbuf : malloc((size_t)len * sizeof *w);
    if (w == NULL) return -1;
    int i = lo;
    for (int k = head; k >= 0; k = m->body_heavy[k], i++) {
        const int heavy = m->body_heavy[k];
        int leaf = k, nl = 0;
        for (int c = m->body_child[k]; c >= 0; c = m->body_sibling[c]) nl += c != heavy;
        if (nl > 0) { /* the light children's paths, then their rake */
            long long lbuf[64], *lw = nl <= 64 ? lbuf : malloc((size_t)nl * sizeof *lw);
            if (lw == NULL) leaf = -1;
            int t = top;
            for (int c = m->body_child[k]; lw != NULL && c >= 0; c = m->body_sibling[c]) {
                if (c == heavy) continue;
                p->seg[t] = plan_path(p, c, top + nl);
                if (p->seg[t] < 0) leaf = -1;
                p->segb[t] = c;
                lw[t - top] = p->size[c];
                t++;
            }
            if (leaf >= 0) {
                int jop;
                plan_prefix(p, top, top + nl - 1, lw);
                int op = plan_sum(p, k, top, top + nl - 1, &jop);
                ctc_tree_node node = {.left = op,
                                      .right = -1,
                                      .joint = plan_first_joint(p, op, jop),
                                      .first = k,
                                      .last = k,
                                      .kind = CTC_NODE_RAKE,
                                      .body = k,
                                      .ljoint = jop,
                                      .rjoint = -1};
                leaf = plan_emit(p, node);
            }
            if (lw != lbuf) free(lw);
            if (leaf < 0) {
                if (w != wbuf) free(w);
                return -1;
            }
        }
        p->seg[i] = leaf;
        p->segb[i] = k;
        w[i - lo] = p->size[k] - (heavy >= 0 ? p->size[heavy] : 0);
    }
    plan_prefix(p, lo, lo + len - 1, w);
    if (w != wbuf) free(w);
    return plan_join(p, lo, lo + len - 1);
}

/* each body's heavy child (and the subtree sizes into size) */
static void plan_heavy(ctc_model *m, int *size)
{
    const int n = m->nbodies;
    for (int k = 0; k < n; k++) size[k] = 1, m->body_heavy[k] = -1;
    for (int k = n - 1; k >= 0; k--) {
        for (int c = m->body_child[k]; c >= 0; c = m->body_sibling[c]) {
            if (m->body_heavy[k] < 0 || size[c] > size[m->body_heavy[k]]) m->body_heavy[k] = c;
        }
        if (m->body_parent[k] >= 0) size[m->body_parent[k]] += size[k];
    }
    /* a loop's spine is one path, so that the loop's bodies assemble as a chain's (model.h) */
    for (int k = n - 1; m->has_loop && m->body_parent[k] >= 0; k = m->body_parent[k]) {
        m->body_heavy[m->body_parent[k]] = k;
    }
}

/* Lays out the plan with nodes sorted by height (stable), children before parents: a chain's
 * balanced tree (a loop closed on a body b splits its root at joint b + 1, model.h, so its two
 * parts are whole subtrees), or a branched tree's plan above. */
static ctc_status build_tree(ctc_model *m, char *err, size_t errlen)
{
    int n = m->nbodies;
    m->ntree = n - 1;
    m->height = 0;
    m->root = 0;
    int nroots = 0;
    for (int g = m->ground_child; g >= 0; g = m->body_sibling[g]) nroots++;
    m->nroots = nroots;
    m->root_joint = malloc((size_t)nroots * sizeof(int));
    m->root_asm = malloc((size_t)nroots * sizeof(int));
    m->tree = calloc((size_t)(n > 1 ? n - 1 : 1), sizeof *m->tree);
    ctc_tree_node *tmp = calloc((size_t)(n > 1 ? n - 1 : 1), sizeof *tmp);
    int *where = calloc((size_t)(n > 1 ? n - 1 : 1), sizeof *where);
    int *scratch = malloc((size_t)(6 * n + 3) * sizeof(int));
    long long *pre = malloc((size_t)(2 * n + 2) * sizeof *pre);
    if (m->tree == NULL || tmp == NULL || where == NULL || scratch == NULL || pre == NULL ||
        m->root_joint == NULL || m->root_asm == NULL) {
        free(tmp);
        free(where);
        free(scratch);
        free(pre);
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }
    int count = 0, root;
    plan_ctx p = {m, tmp, 0, scratch, scratch + n, scratch + 3 * n + 1, pre, m->loop_first};
    plan_heavy(m, p.size);
    if (m->chain) {
        root = build_subtree(m, tmp, &count, 0, n - 1, m->loop_first);
        m->root_joint[0] = 0;
        m->root_asm[0] = root;
    } else {
        int i = 0;
        root = -1;
        for (int g = m->ground_child; g >= 0; g = m->body_sibling[g], i++) {
            m->root_joint[i] = g;
            m->root_asm[i] = plan_path(&p, g, 0);
            if (m->root_asm[i] < 0) root = -2;
        }
        if (root == -2) {
            free(tmp);
            free(where);
            free(scratch);
            free(pre);
            return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        }
        count = p.count;
        m->ntree = count;
        root = m->root_asm[0];
        for (i = 0; i < nroots; i++) {
            int h = plan_height(&p, m->root_asm[i]);
            if (h > m->height) m->height = h;
        }
    }
    free(scratch);
    free(pre);
    if (m->chain && root >= n) m->height = tmp[root - n].height;
    m->height_start = calloc((size_t)m->height + 2, sizeof *m->height_start);
    if (m->height_start == NULL) {
        free(tmp);
        free(where);
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }

    /* counting sort by height; height_start[h] ends height h */
    for (int i = 0; i < count; i++) m->height_start[tmp[i].height]++;
    for (int h = 1; h <= m->height + 1; h++) m->height_start[h] += m->height_start[h - 1];
    int *fill = calloc((size_t)m->height + 2, sizeof *fill);
    if (fill == NULL) {
        free(tmp);
        free(where);
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }
    for (int i = 0; i < count; i++) {
        int h = tmp[i].height;
        where[i] = m->height_start[h - 1] + fill[h]++;
    }
    for (int i = 0; i < count; i++) {
        ctc_tree_node node = tmp[i];
        if (node.left >= n) node.left = n + where[node.left - n];
        if (node.right >= n) node.right = n + where[node.right - n];
        m->tree[where[i]] = node;
    }
    m->root = root < n ? root : n + where[root - n];
    for (int i = 0; i < nroots; i++) {
        if (m->root_asm[i] >= n) m->root_asm[i] = n + where[m->root_asm[i] - n];
    }
    m->loop_body_asm = m->loop_body;
    for (int i = 0; m->loop_body >= 0 && i < count; i++) {
        const ctc_tree_node *node = &m->tree[i];
        if (node->kind == CTC_NODE_RAKE && node->body == m->loop_body) m->loop_body_asm = n + i;
    }
    free(fill);
    free(tmp);
    free(where);
    return CTC_OK;
}

/* Counts the independent coordinates, lists them, computes the Gruebler-Kutzbach mobility and
 * marks the tree nodes the pruned inverse disassembly must visit: a node whose joint is
 * independent, or one with such a node below it (Fig. 4). */
static ctc_status setup_independent(ctc_model *m, char *err, size_t errlen)
{
    m->nvx = m->nv + (m->has_loop ? m->jnt_nv[m->nbodies] : 0);
    m->mobility = m->has_loop ? m->nvx - m->dim : m->nv;
    m->nind = 0;
    for (int k = 0; k < m->njoints; k++) m->nind += m->jnt_indep[k] ? m->jnt_nv[k] : 0;
    m->ind_joint = malloc(((size_t)m->nind + 1) * sizeof(int));
    m->ind_coord = malloc(((size_t)m->nind + 1) * sizeof(int));
    m->inv_need = calloc((size_t)m->ntree + 1, 1);
    if (!m->ind_joint || !m->ind_coord || !m->inv_need) {
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }
    int i = 0;
    for (int k = 0; k < m->njoints; k++) {
        for (int c = 0; m->jnt_indep[k] && c < m->jnt_nv[k]; c++, i++) {
            m->ind_joint[i] = k;
            m->ind_coord[i] = m->jnt_vadr[k] + c;
        }
    }
    for (int t = 0; t < m->ntree; t++) { /* children come before parents */
        const ctc_tree_node *node = &m->tree[t];
        int need = m->jnt_indep[node->joint];
        if (node->left >= m->nbodies) need |= m->inv_need[node->left - m->nbodies];
        if (node->right >= m->nbodies) need |= m->inv_need[node->right - m->nbodies];
        m->inv_need[t] = (unsigned char)need;
    }
    return CTC_OK;
}

/* the spec's own checks, before anything is allocated */
static ctc_status check_chain_spec(const ctc_chain_spec *spec, char *err, size_t errlen)
{
    int bad;
    if (spec == NULL) return ctc_fail(CTC_EINVAL, err, errlen, "chain: no spec given");
    int n = spec->nbodies;
    if (n < 1 || n > CTC_MAX_BODIES) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "chain: number of bodies must be between 1 and %d (got %d)", CTC_MAX_BODIES,
                        n);
    }
    if (spec->bodies == NULL || spec->joints == NULL) {
        return ctc_fail(CTC_EINVAL, err, errlen, "chain: bodies and joints must be given");
    }
    if (!all_finite(spec->gravity, 3, &bad)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "gravity[%d] is not finite", bad);
    }
    if (spec->form != CTC_FORM_AUTO && spec->form != CTC_FORM_PLANAR &&
        spec->form != CTC_FORM_SPATIAL) {
        return ctc_fail(CTC_EINVAL, err, errlen, "chain: unknown form %d", (int)spec->form);
    }
    for (int k = 0; spec->parent != NULL && k < n; k++) {
        if (spec->parent[k] < -1 || spec->parent[k] >= k) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "body %d: parent must be a body before it (-1 for the ground), got %d",
                            k, spec->parent[k]);
        }
    }
    if (spec->loop && n < 2) {
        return ctc_fail(CTC_EINVAL, err, errlen, "loop: a loop needs at least 2 bodies (got %d)",
                        n);
    }
    return CTC_OK;
}

/* a model with its arrays allocated for n bodies (and the closing joint), the specs' bodies and
   joints copied in; NULL when out of memory */
static ctc_model *model_alloc(const ctc_chain_spec *spec)
{
    const int n = spec->nbodies;
    ctc_model *m = calloc(1, sizeof *m);
    if (m == NULL) return NULL;
    m->nbodies = n;
    m->loop_body = -1;
    m->has_loop = spec->loop != NULL;
    int nj = m->njoints = n + m->has_loop;
    ctc_v3_copy(m->gravity, spec->gravity);
    m->bodies = malloc((size_t)n * sizeof *m->bodies);
    m->joints = malloc((size_t)nj * sizeof *m->joints);
    m->jnt_qadr = malloc((size_t)nj * sizeof(int));
    m->jnt_vadr = malloc((size_t)nj * sizeof(int));
    m->jnt_nq = malloc((size_t)nj * sizeof(int));
    m->jnt_nv = malloc((size_t)nj * sizeof(int));
    m->jnt_indep = malloc((size_t)nj);
    m->jnt_loop = calloc((size_t)nj, 1);
    m->body_inertia_inv = calloc((size_t)n * 9, sizeof(double));
    m->jnt_perp = calloc((size_t)nj * 6, sizeof(double));
    m->body_parent = malloc((size_t)n * sizeof(int));
    m->body_child = malloc((size_t)n * sizeof(int));
    m->body_sibling = malloc((size_t)n * sizeof(int));
    m->body_heavy = malloc((size_t)n * sizeof(int));
    if (m->body_heavy == NULL || m->bodies == NULL || m->joints == NULL || m->jnt_qadr == NULL ||
        m->jnt_vadr == NULL || m->jnt_nq == NULL || m->jnt_nv == NULL || m->jnt_indep == NULL ||
        m->jnt_loop == NULL || m->body_inertia_inv == NULL || m->jnt_perp == NULL ||
        m->body_parent == NULL || m->body_child == NULL || m->body_sibling == NULL) {
        ctc_model_free(m);
        return NULL;
    }
    memcpy(m->bodies, spec->bodies, (size_t)n * sizeof *m->bodies);
    memcpy(m->joints, spec->joints, (size_t)n * sizeof *m->joints);
    return m;
}

/* the loop's spine (model.h): the path from the ground to the tip, which must pass through the
 * body the loop closes on; marks the loop's joints (jnt_loop: those on the spine after
 * loop_body, and the closing joint) and sets loop_first, the spine's body after loop_body */
static ctc_status setup_spine(ctc_model *m, char *err, size_t errlen)
{
    const int n = m->nbodies, b = m->loop_body;
    int k = n - 1;
    m->jnt_loop[n] = 1;
    for (; k >= 0 && m->body_parent[k] != b; k = m->body_parent[k]) m->jnt_loop[k] = 1;
    if (k < 0) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "loop: body %d is not on the path from the ground to the tip (body %d); "
                        "a loop between two branches is not supported yet",
                        b, n - 1);
    }
    m->jnt_loop[k] = 1;
    m->loop_first = k;
    if (m->ground_child >= 0 && m->body_sibling[m->ground_child] >= 0) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "loop: a loop on a tree with several bodies on the ground (bodies %d and "
                        "%d) is not supported yet",
                        m->ground_child, m->body_sibling[m->ground_child]);
    }
    return CTC_OK;
}

/* the closing joint of a loop model: its kind, anchor and the body it closes on */
static ctc_status setup_loop(ctc_model *m, const ctc_loop_spec *lp, char *err, size_t errlen)
{
    const int n = m->nbodies;
    int bad;
    m->joints[n] = lp->joint;
    const ctc_joint_class *lc = ctc_joint_class_of(lp->joint.type);
    if (lc == NULL || !lc->loop_closing) {
        char kinds[128];
        loop_closing_names(kinds, sizeof kinds);
        return ctc_fail(CTC_EINVAL, err, errlen, "loop: the closing joint must be %s (got %s)",
                        kinds, lc ? lc->name : "an unknown type");
    }
    if (!all_finite(lp->anchor, 3, &bad)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "loop: anchor[%d] is not finite", bad);
    }
    ctc_v3_copy(m->loop_anchor, lp->anchor);
    if (lp->on_body) {
        if (lp->body < 0 || lp->body > n - 2) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "loop: the body the loop closes on must be one of bodies 0..%d "
                            "(before the tip, body %d) (got %d)",
                            n - 2, n - 1, lp->body);
        }
        m->loop_body = lp->body;
    }
    return setup_spine(m, err, errlen);
}

/* which joints are independent (driven): all of an open chain's; on a loop, every joint outside
   it unless every joint is dependent (a passive run) */
static ctc_status setup_actuation(ctc_model *m, const unsigned char *independent, char *err,
                                  size_t errlen)
{
    int any_indep = 0;
    for (int k = 0; k < m->njoints; k++) {
        m->jnt_indep[k] = independent ? independent[k] != 0 : 1;
        any_indep |= m->jnt_indep[k];
        if (!m->has_loop && !m->jnt_indep[k]) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "joint %d: an open chain is fully actuated: every joint is "
                            "independent",
                            k);
        }
    }
    for (int k = 0; any_indep && m->has_loop && k < m->nbodies; k++) {
        if (!m->jnt_indep[k] && !m->jnt_loop[k]) {
            char where[48] = "the ground";
            if (m->loop_body >= 0) snprintf(where, sizeof where, "body %d", m->loop_body);
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "loop: joint %d is outside the loop (which closes on %s), so "
                            "nothing determines its motion: mark it independent (or every joint "
                            "dependent, for a passive run)",
                            k, where);
        }
    }
    return CTC_OK;
}

/* validates each body and joint, makes inertias exactly symmetric, normalises axes and counts the
   coordinates; moments (n x 3) gets each body's principal moments, ascending */
static ctc_status setup_bodies_and_joints(ctc_model *m, double *moments, int lumped, char *err,
                                          size_t errlen)
{
    const int n = m->nbodies;
    ctc_status st;
    for (int k = 0; k < m->njoints; k++) {
        if ((st = check_joint(&m->joints[k], k, err, errlen)) != CTC_OK) return st;
        if (k < n &&
            (st = check_body(&m->bodies[k], k, lumped, &moments[3 * k], err, errlen)) != CTC_OK) {
            return st;
        }
        if (k < n) {
            double *in = m->bodies[k].inertia; /* symmetric to 1e-9: make it exact */
            for (int a = 0; a < 3; a++) {
                for (int b = a + 1; b < 3; b++) {
                    in[3 * a + b] = in[3 * b + a] = 0.5 * (in[3 * a + b] + in[3 * b + a]);
                }
            }
        }
        ctc_joint_spec *j = &m->joints[k];
        if (ctc_joint_classes[j->type].needs_axis) {
            ctc_v3_scale(j->axis, j->axis, 1.0 / ctc_v3_norm(j->axis));
            ctc_v3_normals(j->axis, &m->jnt_perp[6 * k], &m->jnt_perp[6 * k + 3]);
        } else {
            ctc_v3_set(j->axis, 0, 0, 0);
        }
        m->jnt_qadr[k] = m->nq;
        m->jnt_vadr[k] = m->nv;
        m->jnt_nq[k] = ctc_joint_nq(j->type);
        m->jnt_nv[k] = ctc_joint_nv(j->type);
        if (k < n) { /* the closing joint's coordinates are extended ones, not state */
            m->nq += m->jnt_nq[k];
            m->nv += m->jnt_nv[k];
        }
    }
    return CTC_OK;
}

/* the spread of masses and inertias over the chain (gdca_refine.h decides on it) */
static void setup_mass_ratio(ctc_model *m)
{
    double mlo = INFINITY, mhi = 0, tlo = INFINITY, thi = 0;
    for (int k = 0; k < m->nbodies; k++) {
        const ctc_body_spec *b = &m->bodies[k];
        double tr = b->inertia[0] + b->inertia[4] + b->inertia[8];
        if (b->mass > 0) mlo = fmin(mlo, b->mass), mhi = fmax(mhi, b->mass);
        if (tr > 0) tlo = fmin(tlo, tr), thi = fmax(thi, tr);
    }
    m->mass_ratio = fmax(mhi > 0 ? mhi / mlo : 1.0, thi > 0 ? thi / tlo : 1.0);
}

/* 1 when body k of a spatial model (n == NULL: spatial form) is slender (model.h "slender
 * bodies"): not singular, smallest principal moment under CTC_SLENDER_RATIO times its largest */
static int is_slender(const ctc_model *m, const double *moments, const double *n, int k)
{
    const double *e = &moments[3 * k];
    return n == NULL && !(m->body_singular != NULL && m->body_singular[k]) &&
           e[0] < CTC_SLENDER_RATIO * e[2];
}

/* Marks the singular bodies of form `form` (model.h "singular bodies"; n: the plane normal in
 * planar form) and the slender ones (model.h "slender bodies": spatial models only, each of
 * their principal moments gets CTC_SLENDER_AUGMENT_REL times the largest) and makes fwd_bodies: a
 * singular body's principal moments each get CTC_SINGULAR_AUGMENT_REL times J_ref, the smallest
 * positive J_own(j) = m_j |c_j|^2 + tr(I_j) / 2 (its inertia about its own joint's centre, c_j from
 * the body's origin) over the body and its descendants, and a massless body's mass
 * CTC_SINGULAR_AUGMENT_REL times the smallest positive mass among them; a subtree with none (a
 * massless tip, which only a loop's closure can hold: the mass-matrix check refuses it on an open
 * model) takes the whole model's smallest (1 kg m^2, 1 kg when the model has none). The smallest of
 * the subtree, not its sum, bounds the augmentation's share of the joint-space inertia on a long
 * chain of point masses too (bench/NOTEBOOK.md, "Singular bodies"). */
static ctc_status setup_singular(ctc_model *m, const double *moments, const double *n, char *err,
                                 size_t errlen)
{
    const int nb = m->nbodies;
    double mhi = 0;
    for (int k = 0; k < nb; k++) mhi = fmax(mhi, m->bodies[k].mass);
    m->nsingular = 0;
    m->fwd_bodies = m->bodies;
    for (int k = 0; k < nb; k++) {
        const ctc_body_spec *b = &m->bodies[k];
        const double *e = &moments[3 * k];
        int sing = !(b->mass > CTC_MASS_ZERO_REL * mhi);
        if (n == NULL) {
            sing |= e[0] <= CTC_INERTIA_ZERO_REL * e[2];
        } else {
            double in[3];
            ctc_m3_mulv(in, b->inertia, n);
            sing |= !(ctc_v3_dot(n, in) >
                      CTC_INERTIA_ZERO_REL * fabs(b->inertia[0] + b->inertia[4] + b->inertia[8]));
        }
        if (!sing) continue;
        if (m->body_singular == NULL) {
            m->body_singular = calloc((size_t)nb, 1);
            if (m->body_singular == NULL) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        }
        m->body_singular[k] = 1;
        m->nsingular++;
    }
    m->nslender = 0;
    for (int k = 0; k < nb; k++) m->nslender += is_slender(m, moments, n, k);
    if (m->nsingular == 0 && m->nslender == 0) return CTC_OK;

    /* J_ref and m_ref of each subtree, children before parents (body_parent[k] < k) */
    double *ref = malloc((size_t)nb * 2 * sizeof(double));
    m->fwd_bodies = malloc((size_t)nb * sizeof *m->fwd_bodies);
    if (ref == NULL || m->fwd_bodies == NULL) {
        free(ref);
        if (m->fwd_bodies == NULL) m->fwd_bodies = m->bodies;
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }
    memcpy(m->fwd_bodies, m->bodies, (size_t)nb * sizeof *m->bodies);
    double *jref = ref, *mref = ref + nb;
    for (int k = 0; k < nb; k++) jref[k] = mref[k] = INFINITY;
    for (int k = nb - 1; k >= 0; k--) {
        const ctc_body_spec *b = &m->bodies[k];
        const double own = b->mass * ctc_v3_dot(b->com, b->com) +
                           0.5 * (b->inertia[0] + b->inertia[4] + b->inertia[8]);
        if (own > 0) jref[k] = fmin(jref[k], own);
        if (b->mass > 0) mref[k] = fmin(mref[k], b->mass);
        const int par = m->body_parent[k];
        if (par >= 0) jref[par] = fmin(jref[par], jref[k]), mref[par] = fmin(mref[par], mref[k]);
    }
    for (int k = 0; k < nb; k++) {
        if (!is_slender(m, moments, n, k)) continue;
        const double add = CTC_SLENDER_AUGMENT_REL * moments[3 * k + 2];
        for (int a = 0; a < 3; a++) m->fwd_bodies[k].inertia[4 * a] += add;
    }
    double jall = INFINITY, mall = INFINITY; /* over the whole model */
    for (int k = 0; k < nb; k++) {
        if (m->body_parent[k] < 0) jall = fmin(jall, jref[k]), mall = fmin(mall, mref[k]);
    }
    if (!isfinite(jall)) jall = 1.0;
    if (!isfinite(mall)) mall = 1.0;
    for (int k = 0; k < nb && m->nsingular > 0; k++) {
        if (!m->body_singular[k]) continue;
        ctc_body_spec *fb = &m->fwd_bodies[k];
        const double js = isfinite(jref[k]) ? jref[k] : jall,
                     ms = isfinite(mref[k]) ? mref[k] : mall;
        if (!(fb->mass > CTC_MASS_ZERO_REL * mhi)) fb->mass += CTC_SINGULAR_AUGMENT_REL * ms;
        for (int a = 0; a < 3; a++) fb->inertia[4 * a] += CTC_SINGULAR_AUGMENT_REL * js;
    }
    free(ref);
    return CTC_OK;
}

/* A loop model's closure at q (nq): adds rho G_s^T G_s to mm (nv x nv), G the closure's Jacobian
 * over the chain's coordinates (loop.h: G = -D_n^T J, zero columns outside the loop), each row
 * scaled to a largest entry of 1 (G_s: the same null space), rho = the largest diagonal entry of
 * mm. For M positive semidefinite, M + rho G^T G is positive definite exactly when M is on the
 * closure's tangent space, ker G (x^T (M + rho G^T G) x = 0 asks M x = 0 and G x = 0), so the
 * same LDL^T tests the loop's reduced mass matrix Z^T M Z (Z a basis of ker G) and still names a
 * joint in coordinate order. */
static ctc_status add_closure(const ctc_model *m, const double *q, double *mm, double rho,
                              char *err, size_t errlen)
{
    const int nv = m->nv, dim = m->dim, nc = dim - m->jnt_nv[m->nbodies];
    ctc_data *d = ctc_data_new(m);
    double *g = calloc((size_t)nc * nv + (size_t)nv, sizeof(double));
    if (d == NULL || g == NULL) {
        ctc_data_free(d);
        free(g);
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }
    double *v = g + (size_t)nc * nv;
    ctc_kinematics(m, d, q, v);
    const double *D = d->jnt_D + dim * dim * m->nbodies;
    for (int k = 0; k < m->nbodies; k++) {
        for (int c = 0; m->jnt_loop[k] && c < m->jnt_nv[k]; c++) {
            double tw[CTC_DENSE_MAX];
            ctc_loop_coord_twist(m, d, k, c, tw);
            for (int a = 0; a < nc; a++) {
                double s = 0;
                for (int i = 0; i < dim; i++) s += D[a * dim + i] * tw[i];
                g[a * nv + m->jnt_vadr[k] + c] = s;
            }
        }
    }
    ctc_data_free(d);
    for (int a = 0; a < nc; a++) {
        double s = 0;
        for (int i = 0; i < nv; i++) s = fmax(s, fabs(g[a * nv + i]));
        for (int i = 0; s > 0 && i < nv; i++) g[a * nv + i] /= s;
    }
    for (int i = 0; i < nv; i++)
        for (int j = 0; j < nv; j++) {
            double s = 0;
            for (int a = 0; a < nc; a++) s += g[a * nv + i] * g[a * nv + j];
            mm[i * nv + j] += rho * s;
        }
    free(g);
    return CTC_OK;
}

/* A model with a singular body: refuses it unless the joint-space mass matrix is positive
 * definite at a generic configuration (model.h "singular bodies"), on a loop model on the
 * closure's tangent space (add_closure), by an LDL^T factorisation in coordinate order: a pivot at
 * or under CTC_MASS_MATRIX_PIVOT_REL times its own diagonal entry (an entry at rounding level,
 * 1e-15 of the largest, counts as 0) means the coordinate
 * moves no mass or inertia that the coordinates before it do not (and, on a loop, that the
 * closure does not hold it). */
static ctc_status check_mass_matrix(const ctc_model *m, char *err, size_t errlen)
{
    const int nv = m->nv;
    if (m->nsingular == 0 || nv == 0) return CTC_OK;
    /* every singular body merged into one with mass and inertia (model.h "merged bodies"): each
       body the passes see has a positive definite inertia, so M(q) is positive definite */
    if (m->dyn != NULL && m->dyn->nsingular == 0) return CTC_OK;
    ctc_oracle *o = ctc_oracle_new(m);
    double *q = malloc(((size_t)m->nq + (size_t)nv * nv) * sizeof(double));
    if (o == NULL || q == NULL) {
        ctc_oracle_free(o);
        free(q);
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }
    double *mm = q + m->nq, dmax = 0;
    for (int i = 0; i < m->nq; i++) q[i] = sin(i + 1.0);
    for (int k = 0; k < m->nbodies; k++) {
        if (m->joints[k].type != CTC_JOINT_SPHERICAL) continue;
        double *qk = q + m->jnt_qadr[k];
        qk[0] = 1, qk[1] = 0.1 * sin(m->jnt_qadr[k] + 1.0), qk[2] = 0.2, qk[3] = 0.3;
    }
    ctc_model_q_normalize(m, q);
    ctc_oracle_mass_matrix(m, o, q, mm);
    ctc_oracle_free(o);
    for (int i = 0; i < nv; i++) dmax = fmax(dmax, mm[i * nv + i]);
    ctc_status st = m->has_loop ? add_closure(m, q, mm, dmax, err, errlen) : CTC_OK;

    /* LDL^T in place, lower triangle: mm[i][j] = L_ij d_j, mm[i][i] = d_i; each pivot relative
       to its own diagonal entry (the share of coordinate i's inertia that the coordinates before
       it leave), so that a long chain's tip, whose entries are far under the base's, is judged
       alike (4096 point masses: the tip's entry is 6e-11 of the largest) */
    for (int i = 0; i < nv && st == CTC_OK; i++) {
        const double diag = mm[i * nv + i];
        for (int j = 0; j <= i; j++) {
            double s = mm[i * nv + j];
            for (int l = 0; l < j; l++) s -= mm[i * nv + l] * mm[j * nv + l] / mm[l * nv + l];
            mm[i * nv + j] = s;
        }
        const double rel = diag > 1e-15 * dmax ? mm[i * nv + i] / diag : 0;
        if (!(rel > CTC_MASS_MATRIX_PIVOT_REL)) {
            int k = 0;
            while (k + 1 < m->nbodies && m->jnt_vadr[k + 1] <= i) k++;
            st =
                ctc_fail(CTC_EINVAL, err, errlen,
                         "body %d: the %sjoint-space mass matrix is singular: joint %d (%s) moves "
                         "no mass or inertia that the joints before it do not%s (relative pivot "
                         "%.3g <= %g); body %d and the bodies beyond it need mass off the joint's "
                         "axis or inertia about it",
                         k, m->has_loop ? "loop's " : "", k, ctc_joint_type_name(m->joints[k].type),
                         m->has_loop ? ", nor does the loop's closure hold it" : "", rel,
                         CTC_MASS_MATRIX_PIVOT_REL, k);
        }
    }
    free(q);
    return st;
}

/* spatial form: the inverse of each body's forward inertia (fwd_bodies: a singular body's is
   augmented, setup_singular) */
static void setup_spatial(ctc_model *m)
{
    for (int k = 0; k < m->nbodies; k++) {
        /* inverse by cofactors; a principal moment is over CTC_INERTIA_ZERO_REL of the largest */
        const double *a = m->fwd_bodies[k].inertia;
        double *inv = &m->body_inertia_inv[9 * k];
        double c00 = a[4] * a[8] - a[5] * a[7], c01 = a[5] * a[6] - a[3] * a[8],
               c02 = a[3] * a[7] - a[4] * a[6];
        double det = a[0] * c00 + a[1] * c01 + a[2] * c02;
        inv[0] = c00 / det;
        inv[1] = (a[2] * a[7] - a[1] * a[8]) / det;
        inv[2] = (a[1] * a[5] - a[2] * a[4]) / det;
        inv[3] = c01 / det;
        inv[4] = (a[0] * a[8] - a[2] * a[6]) / det;
        inv[5] = (a[2] * a[3] - a[0] * a[5]) / det;
        inv[6] = c02 / det;
        inv[7] = (a[1] * a[6] - a[0] * a[7]) / det;
        inv[8] = (a[0] * a[4] - a[1] * a[3]) / det;
    }
}

/* the form: planar when the chain moves in one plane with gravity in it (and the spec allows),
   else spatial; model only what the scene needs */
static ctc_status setup_form(ctc_model *m, ctc_form requested, const double *moments, char *err,
                             size_t errlen)
{
    double normal[3];
    char why[160] = "";
    plane_normal(m, normal);
    int planar = chain_is_planar(m, normal, why, sizeof why);
    if (requested == CTC_FORM_PLANAR && !planar) {
        return ctc_fail(CTC_EINVAL, err, errlen, "chain: planar form requested but %s", why);
    }
    m->form = (planar && requested != CTC_FORM_SPATIAL) ? CTC_FORM_PLANAR : CTC_FORM_SPATIAL;
    m->dim = m->form == CTC_FORM_PLANAR ? 3 : 6;
    const int planar_form = m->form == CTC_FORM_PLANAR;
    ctc_status st = setup_singular(m, moments, planar_form ? normal : NULL, err, errlen);
    if (st != CTC_OK) return st;
    if (planar_form) return setup_planar(m, normal, err, errlen);
    setup_spatial(m);
    return CTC_OK;
}

static ctc_status model_build(const ctc_chain_spec *spec, int reduced, ctc_model **out, char *err,
                              size_t errlen);

/* ---- merged bodies (model.h) ----
 *
 * Which bodies merge: body k on a fixed joint goes into its parent's target (the parent itself,
 * or the body the parent went into), or is welded to the world when its parent is the ground.
 * Fixed joints only translate (model.h: a body's axes are parallel to its parent's at zero
 * coordinates, and a fixed joint has none), so every frame merged into a target is parallel to
 * the target's and differs by the offset off[k], the sum of the fixed joints' locations on the
 * way. A loop model keeps what its conventions need (model.h loop fields): bodies fixed to the
 * ground stay (one body on the ground for a tree's spine), and the tip stays unless it merges
 * into the last body that stays, which is then the reduced model's tip. Fills target (n: the
 * target's index, -1 welded) and off (n x 3); returns the number of bodies that stay, or 0 when
 * no body merges (or none would stay) and the model is its own dynamics. */
static int dyn_targets(const ctc_model *m, int *target, double *off)
{
    const int n = m->nbodies;
    int merged = 0, last = -1;
    for (int k = 0; k < n; k++) {
        const int par = m->body_parent[k];
        const ctc_joint_spec *j = &m->joints[k];
        int merge = j->type == CTC_JOINT_FIXED && !(m->has_loop && par < 0);
        if (merge && m->has_loop && k == n - 1) merge = target[par] == last && last >= 0;
        if (merge && par >= 0) {
            target[k] = target[par];
            for (int a = 0; a < 3; a++) off[3 * k + a] = off[3 * par + a] + j->location[a];
        } else if (merge) {
            target[k] = -1;
            ctc_v3_copy(&off[3 * k], j->location);
        } else {
            target[k] = k;
            ctc_v3_set(&off[3 * k], 0, 0, 0);
            last = k;
        }
        merged += merge;
    }
    if (m->has_loop && m->loop_body >= 0 && target[m->loop_body] == target[n - 1]) return 0;
    return merged > 0 && merged < n ? n - merged : 0;
}

/* The composites (nd) of the bodies merged into each target t (t itself and every k with
 * target[k] = t), db[index[t]], in t's frame: masses added, the centre of mass their weighted
 * mean, the inertias moved to it by the parallel-axis theorem, I = sum_k I_k + m_k (|r_k|^2 1 -
 * r_k r_k^T), r_k = off_k + c_k - c. Without mass the centre of mass is t's own and the inertias
 * add as lumped ones. Two passes over the bodies. */
static void dyn_composites(const ctc_model *m, const int *target, const int *index,
                           const double *off, ctc_body_spec *db, int nd)
{
    memset(db, 0, (size_t)nd * sizeof *db);
    for (int k = 0; k < m->nbodies; k++) { /* masses, and mass-weighted centres in com */
        if (target[k] < 0) continue;
        const ctc_body_spec *b = &m->bodies[k];
        ctc_body_spec *c = &db[index[target[k]]];
        c->mass += b->mass;
        for (int a = 0; a < 3; a++) c->com[a] += b->mass * (off[3 * k + a] + b->com[a]);
    }
    for (int k = 0; k < m->nbodies; k++) { /* a target comes before its merged bodies */
        if (target[k] < 0) continue;
        const ctc_body_spec *b = &m->bodies[k];
        ctc_body_spec *c = &db[index[target[k]]];
        if (target[k] == k) {
            if (c->mass > 0) {
                ctc_v3_scale(c->com, c->com, 1.0 / c->mass);
            } else {
                ctc_v3_copy(c->com, b->com);
            }
        }
        double r[3];
        for (int a = 0; a < 3; a++) r[a] = off[3 * k + a] + b->com[a] - c->com[a];
        const double rr = ctc_v3_dot(r, r);
        for (int a = 0; a < 3; a++) {
            for (int e = 0; e < 3; e++) {
                c->inertia[3 * a + e] +=
                    b->inertia[3 * a + e] + b->mass * ((a == e ? rr : 0.0) - r[a] * r[e]);
            }
        }
    }
}

/* Builds m->dyn, the reduced model of the dynamics passes, when a body merges (dyn_targets), and
 * the maps between the two numberings (model.h "merged bodies"). The reduced spec: one composite
 * body per target, in the bodies' order; each joint that stays keeps its type and axis, its
 * location moved into its new parent's frame by the offset of its old parent; a loop's closing
 * joint moves by the tip's offset and its anchor on a body by that body's; the form is m's. */
static ctc_status setup_dyn(ctc_model *m, const ctc_chain_spec *spec, char *err, size_t errlen)
{
    const int n = m->nbodies;
    int *target = malloc((size_t)n * 2 * sizeof(int));
    double *off = malloc((size_t)n * 3 * sizeof(double));
    if (target == NULL || off == NULL) {
        free(target);
        free(off);
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }
    const int nd = dyn_targets(m, target, off);
    if (nd == 0) {
        free(target);
        free(off);
        return CTC_OK;
    }
    int *index = target + n; /* a target's body in the reduced model */
    ctc_body_spec *db = malloc((size_t)nd * sizeof *db);
    ctc_joint_spec *dj = malloc((size_t)nd * sizeof *dj);
    int *dpar = malloc((size_t)nd * sizeof *dpar);
    unsigned char *dind = malloc((size_t)nd + 1);
    m->body_dyn = malloc((size_t)n * sizeof(int));
    m->body_dyn_off = malloc((size_t)n * 3 * sizeof(double));
    m->dyn_body = malloc((size_t)nd * sizeof(int));
    ctc_status st = CTC_OK;
    if (db == NULL || dj == NULL || dpar == NULL || dind == NULL || m->body_dyn == NULL ||
        m->body_dyn_off == NULL || m->dyn_body == NULL) {
        st = ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        goto done;
    }
    int j = 0;
    for (int k = 0; k < n; k++) {
        index[k] = -1;
        if (target[k] != k) continue;
        const int par = m->body_parent[k];
        index[k] = j;
        m->dyn_body[j] = k;
        dj[j] = m->joints[k];
        if (par >= 0) {
            for (int a = 0; a < 3; a++) dj[j].location[a] += off[3 * par + a];
        }
        dpar[j] = par < 0 || target[par] < 0 ? -1 : index[target[par]];
        dind[j] = m->jnt_indep[k];
        j++;
    }
    dyn_composites(m, target, index, off, db, nd);
    for (int k = 0; k < n; k++) {
        m->body_dyn[k] = target[k] < 0 ? -1 : index[target[k]];
        ctc_v3_copy(&m->body_dyn_off[3 * k], &off[3 * k]);
    }
    ctc_loop_spec loop;
    ctc_chain_spec ds = {.nbodies = nd,
                         .bodies = db,
                         .joints = dj,
                         .parent = dpar,
                         .form = m->form,
                         .independent = m->has_loop ? dind : NULL};
    ctc_v3_copy(ds.gravity, spec->gravity);
    if (m->has_loop) {
        loop = *spec->loop;
        for (int a = 0; a < 3; a++) loop.joint.location[a] += off[3 * (n - 1) + a];
        if (loop.on_body) {
            for (int a = 0; a < 3; a++) loop.anchor[a] += off[3 * loop.body + a];
            loop.body = m->body_dyn[loop.body];
        }
        dind[nd] = m->jnt_indep[n];
        ds.loop = &loop;
    }
    st = model_build(&ds, 1, &m->dyn, err, errlen);

done:
    free(db);
    free(dj);
    free(dpar);
    free(dind);
    free(target);
    free(off);
    return st;
}

/* ctc_model_build; reduced: spec is the reduced model of a built one (setup_dyn), whose checks
   that model has passed (the mass matrix's) and which merges nothing further */
static ctc_status model_build(const ctc_chain_spec *spec, int reduced, ctc_model **out, char *err,
                              size_t errlen)
{
    ctc_status st;
    *out = NULL;
    if ((st = check_chain_spec(spec, err, errlen)) != CTC_OK) return st;
    const int n = spec->nbodies;
    ctc_model *m = model_alloc(spec);
    double *moments = malloc((size_t)n * 3 * sizeof(double));
    if (m == NULL || moments == NULL) {
        st = ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
        goto fail;
    }
    m->chain = 1;
    for (int k = 0; k < n; k++) {
        m->body_parent[k] = spec->parent != NULL ? spec->parent[k] : k - 1;
        m->chain &= m->body_parent[k] == k - 1;
    }
    build_topology(m);
    if (m->has_loop && (st = setup_loop(m, spec->loop, err, errlen)) != CTC_OK) goto fail;
    if ((st = setup_actuation(m, spec->independent, err, errlen)) != CTC_OK) goto fail;
    if ((st = setup_bodies_and_joints(m, moments, reduced, err, errlen)) != CTC_OK) goto fail;
    setup_mass_ratio(m);
    if ((st = setup_form(m, spec->form, moments, err, errlen)) != CTC_OK) goto fail;
    if ((st = build_tree(m, err, errlen)) != CTC_OK) goto fail;
    if ((st = setup_independent(m, err, errlen)) != CTC_OK) goto fail;
    if (!reduced && (st = setup_dyn(m, spec, err, errlen)) != CTC_OK) goto fail;
    if (!reduced && (st = check_mass_matrix(m, err, errlen)) != CTC_OK) goto fail;
    free(moments);
    *out = m;
    return CTC_OK;

fail:
    free(moments);
    ctc_model_free(m);
    return st;
}

ctc_status ctc_model_build(const ctc_chain_spec *spec, ctc_model **out, char *err, size_t errlen)
{
    return model_build(spec, 0, out, err, errlen);
}

void ctc_model_free(ctc_model *m)
{
    if (m == NULL) return;
    ctc_model_free(m->dyn);
    free(m->body_dyn);
    free(m->body_dyn_off);
    free(m->dyn_body);
    if (m->fwd_bodies != m->bodies) free(m->fwd_bodies);
    free(m->body_singular);
    free(m->bodies);
    free(m->joints);
    free(m->jnt_qadr);
    free(m->jnt_vadr);
    free(m->jnt_nq);
    free(m->jnt_nv);
    free(m->body_inertia_inv);
    free(m->jnt_perp);
    free(m->body_parent);
    free(m->body_child);
    free(m->body_sibling);
    free(m->body_heavy);
    free(m->root_joint);
    free(m->root_asm);
    free(m->planar);
    free(m->tree);
    free(m->height_start);
    free(m->jnt_indep);
    free(m->jnt_loop);
    free(m->ind_joint);
    free(m->ind_coord);
    free(m->inv_need);
    free(m);
}

void ctc_model_q_zero(const ctc_model *m, double *q)
{
    for (int i = 0; i < m->nq; i++) q[i] = 0;
    for (int k = 0; k < m->nbodies; k++) {
        if (m->joints[k].type == CTC_JOINT_SPHERICAL) q[m->jnt_qadr[k]] = 1.0;
    }
}

void ctc_model_q_add(const ctc_model *m, double *q, const double *dv, double s)
{
    for (int k = 0; k < m->nbodies; k++) {
        double *qk = q + m->jnt_qadr[k];
        const double *vk = dv + m->jnt_vadr[k];
        if (m->joints[k].type != CTC_JOINT_SPHERICAL) {
            for (int i = 0; i < m->jnt_nv[k]; i++) qk[i] += s * vk[i];
            continue;
        }
        /* quat (x) exp(s dv / 2), dv in the child frame */
        double r[3] = {s * vk[0], s * vk[1], s * vk[2]};
        double th = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        double c = cos(0.5 * th), sn = th > 1e-300 ? sin(0.5 * th) / th : 0.5;
        double b[4] = {c, sn * r[0], sn * r[1], sn * r[2]};
        double a[4] = {qk[0], qk[1], qk[2], qk[3]};
        qk[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
        qk[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
        qk[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
        qk[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
    }
    ctc_model_q_normalize(m, q);
}

void ctc_model_q_rate(const ctc_model *m, const double *q, const double *v, double *qdot)
{
    for (int k = 0; k < m->nbodies; k++) {
        const double *qk = q + m->jnt_qadr[k];
        const double *vk = v + m->jnt_vadr[k];
        double *dk = qdot + m->jnt_qadr[k];
        if (m->joints[k].type != CTC_JOINT_SPHERICAL) {
            for (int i = 0; i < m->jnt_nv[k]; i++) dk[i] = vk[i];
            continue;
        }
        /* quat' = 0.5 quat (x) (0, w), w in the child frame */
        double w = qk[0], x = qk[1], y = qk[2], z = qk[3];
        dk[0] = 0.5 * (-x * vk[0] - y * vk[1] - z * vk[2]);
        dk[1] = 0.5 * (w * vk[0] + y * vk[2] - z * vk[1]);
        dk[2] = 0.5 * (w * vk[1] + z * vk[0] - x * vk[2]);
        dk[3] = 0.5 * (w * vk[2] + x * vk[1] - y * vk[0]);
    }
}

void ctc_model_q_normalize(const ctc_model *m, double *q)
{
    for (int k = 0; k < m->nbodies; k++) {
        if (m->joints[k].type != CTC_JOINT_SPHERICAL) continue;
        double *qk = q + m->jnt_qadr[k];
        double nrm = sqrt(qk[0] * qk[0] + qk[1] * qk[1] + qk[2] * qk[2] + qk[3] * qk[3]);
        if (nrm > 0) {
            for (int i = 0; i < 4; i++) qk[i] /= nrm;
        } else {
            qk[0] = 1, qk[1] = qk[2] = qk[3] = 0;
        }
    }
}
