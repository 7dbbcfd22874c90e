/*
 * oracle.c - the oracle's workspace and its joint model (Featherstone, Rigid Body Dynamics
 * Algorithms, 2008, ch. 4: joint transform X_J, motion subspace S and velocity-product term).
 *
 * Joint k joins frame p (its parent body's, p = lambda(k) = m->body_parent[k], or the world's for
 * p = -1) to body k's frame. The
 * child's origin lies at r = location (+ displacement along the axis) in p's coordinates and its
 * axes are rotated by R relative to p's (x_p = R x_child + r), so the motion transform is
 *     X_k = k_X_p = [E 0; -E[r]x E],   E = R^T.
 * Per joint type, with a the unit axis in p's frame:
 *     revolute     R = rot(a, q),  r = location;           S = (a; 0)
 *     prismatic    R = 1,          r = location + q a;     S = (0; a)
 *     cylindrical  R = rot(a, q0), r = location + q1 a;    S = [(a; 0) (0; a)]
 *     spherical    R = R(quat),    r = location;           S = [1_3; 0]
 *     fixed        R = 1,          r = location;           no columns
 * (a rotation about a leaves a unchanged, so a has the same coordinates in the child's frame).
 * Each S is constant in the child's frame, so the joint's velocity-product term is zero and body
 * k's acceleration bias reduces to c_k = v_k x (S_k qdot_k) (Featherstone eq. 5.7's c_J = 0).
 */
#include "oracle.h"

#include <stdlib.h>
#include <string.h>

#include "oracle_internal.h"
#include "plucker.h"

ctc_oracle *ctc_oracle_new(const ctc_model *m)
{
    int n = m->nbodies;
    /* doubles per body over every array of the workspace */
    size_t per_body = 36 + 36 + 18 + 6 + 6 + 6 + 6 + 36 + 6 + 18 + 9 + 3;
    ctc_oracle *o = malloc(sizeof(*o));
    double *block = malloc((size_t)n * per_body * sizeof(double));

    if (o == NULL || block == NULL) {
        free(o);
        free(block);
        return NULL;
    }
    memset(block, 0, (size_t)n * per_body * sizeof(double));

    /* carve the one block into the per-body arrays */
    o->nbodies = n;
    o->inertia = block;
    o->xform = o->inertia + 36 * (size_t)n;
    o->subspace = o->xform + 36 * (size_t)n;
    o->vel = o->subspace + 18 * (size_t)n;
    o->bias = o->vel + 6 * (size_t)n;
    o->acc = o->bias + 6 * (size_t)n;
    o->force = o->acc + 6 * (size_t)n;
    o->art_inertia = o->force + 6 * (size_t)n;
    o->art_bias = o->art_inertia + 36 * (size_t)n;
    o->art_u = o->art_bias + 6 * (size_t)n;
    o->art_dchol = o->art_u + 18 * (size_t)n;
    o->art_tau = o->art_dchol + 9 * (size_t)n;

    /* constant spatial inertias about each body's origin */
    for (int k = 0; k < n; k++) {
        const ctc_body_spec *b = &m->bodies[k];
        plk_body_inertia(b->mass, b->com, b->inertia, o->inertia + 36 * (size_t)k);
    }
    return o;
}

void ctc_oracle_free(ctc_oracle *o)
{
    if (o == NULL) {
        return;
    }
    free(o->inertia); /* the start of the one block */
    free(o);
}

void ctc_oracle_joint_model(const ctc_model *m, int k, const double *q, double xform[36],
                            double subspace[18])
{
    const ctc_joint_spec *j = &m->joints[k];
    const double *qk = q + m->jnt_qadr[k];
    const double *a = j->axis;
    double rot[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}; /* R: child axes in the parent's frame */
    double r[3] = {j->location[0], j->location[1], j->location[2]};
    double e[9];

    memset(subspace, 0, 18 * sizeof(double));

    /* joint motion: R, r and the subspace columns */
    switch (j->type) {
    case CTC_JOINT_REVOLUTE:
        plk_rot_axis_angle(a, qk[0], rot);
        subspace[0] = a[0];
        subspace[1] = a[1];
        subspace[2] = a[2];
        break;
    case CTC_JOINT_PRISMATIC:
        for (int i = 0; i < 3; i++) {
            r[i] += qk[0] * a[i];
        }
        subspace[3] = a[0];
        subspace[4] = a[1];
        subspace[5] = a[2];
        break;
    case CTC_JOINT_CYLINDRICAL:
        plk_rot_axis_angle(a, qk[0], rot);
        for (int i = 0; i < 3; i++) {
            r[i] += qk[1] * a[i];
        }
        subspace[0] = a[0];
        subspace[1] = a[1];
        subspace[2] = a[2];
        subspace[6 + 3] = a[0];
        subspace[6 + 4] = a[1];
        subspace[6 + 5] = a[2];
        break;
    case CTC_JOINT_SPHERICAL:
        plk_rot_quat(qk, rot);
        subspace[0] = 1.0;
        subspace[6 + 1] = 1.0;
        subspace[12 + 2] = 1.0;
        break;
    case CTC_JOINT_FIXED:
        break;
    }

    /* E = R^T, then X = [E 0; -E[r]x E] */
    for (int i = 0; i < 3; i++) {
        for (int c = 0; c < 3; c++) {
            e[3 * i + c] = rot[3 * c + i];
        }
    }
    plk_motion_xform(e, r, xform);
}

void ctc_oracle_forward_pass(const ctc_model *m, ctc_oracle *o, const double *q, const double *v)
{
    for (int k = 0; k < m->nbodies; k++) {
        double *x = o->xform + 36 * (size_t)k;
        double *s = o->subspace + 18 * (size_t)k;
        double *vk = o->vel + 6 * (size_t)k;
        double *ck = o->bias + 6 * (size_t)k;
        double vj[6] = {0, 0, 0, 0, 0, 0};

        ctc_oracle_joint_model(m, k, q, x, s);
        if (v == NULL) {
            continue;
        }

        /* joint velocity vJ = S qdot */
        const double *qd = v + m->jnt_vadr[k];
        for (int c = 0; c < m->jnt_nv[k]; c++) {
            for (int i = 0; i < 6; i++) {
                vj[i] += s[6 * c + i] * qd[c];
            }
        }

        /* v_k = X_k v_p + vJ, p = lambda(k) (the ground is at rest) */
        const int p = m->body_parent[k];
        if (p < 0) {
            memcpy(vk, vj, sizeof(vj));
        } else {
            plk_mat6_vec(x, o->vel + 6 * (size_t)p, vk);
            for (int i = 0; i < 6; i++) {
                vk[i] += vj[i];
            }
        }

        /* c_k = v_k x vJ (the joint's own term S' qdot is zero) */
        plk_cross_motion(vk, vj, ck);
    }
}
