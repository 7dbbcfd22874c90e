/*
 * oracle_internal.h - the oracle's workspace layout and the joint model shared by rnea.c, aba.c
 * and crba.c. Not part of the public API (see oracle.h).
 *
 * Per body k the workspace holds, in body k's coordinates (Featherstone's notation):
 *   X_k  = k_X_p, the 6x6 motion transform from the parent's frame, p = lambda(k) =
 *          m->body_parent[k] (the world's for p = -1);
 *   S_k  = the joint's motion subspace (6 x nv_k), constant in the child's frame for every joint
 *          type here, so the joint's own velocity-product term S'_k qdot_k is zero;
 *   v_k  = body velocity, c_k = v_k x (S_k qdot_k) its velocity-product acceleration;
 *   I_k  = the body's spatial inertia about the frame origin (constant, made once).
 * The other arrays are scratch for one algorithm each.
 */
#ifndef CTC_ORACLE_INTERNAL_H
#define CTC_ORACLE_INTERNAL_H

#include "model.h"
#include "oracle.h"

struct ctc_oracle {
    int nbodies;
    double *inertia;     /* (n x 36) I_k, spatial inertia about body k's origin, body frame */
    double *xform;       /* (n x 36) X_k = k_X_lambda(k), row-major */
    double *subspace;    /* (n x 18) S_k: column j of joint k is subspace[18 k + 6 j .. +5] */
    double *vel;         /* (n x 6) v_k */
    double *bias;        /* (n x 6) c_k = v_k x (S_k qdot_k) */
    double *acc;         /* (n x 6) a_k, spatial acceleration including -g of the ground */
    double *force;       /* (n x 6) RNEA: force transmitted across joint k onto body k */
    double *art_inertia; /* (n x 36) ABA: articulated inertia I^A_k; CRBA: composite I^c_k */
    double *art_bias;    /* (n x 6) ABA: articulated bias force p^A_k */
    double *art_u;       /* (n x 18) ABA: U_k = I^A_k S_k, same layout as subspace */
    double *art_dchol;   /* (n x 9) ABA: Cholesky factor of D_k = S_k^T U_k (nv_k x nv_k) */
    double *art_tau;     /* (n x 3) ABA: u_k = tau_k - S_k^T p^A_k */
};

/* Joint k's motion transform X (6x6, k_X_lambda(k)) and motion subspace S (nv_k columns of 6,
 * layout as in the workspace) at coordinates q (nq; only joint k's are read). */
void ctc_oracle_joint_model(const ctc_model *m, int k, const double *q, double xform[36],
                            double subspace[18]);

/* Forward pass shared by all three algorithms: fills o->xform and o->subspace for every body at
 * q (nq) and, when v (nv) is not NULL, the velocities o->vel and velocity-product terms o->bias:
 *     v_k = X_k v_lambda(k) + S_k qdot_k,   c_k = v_k x (S_k qdot_k),   v_ground = 0. */
void ctc_oracle_forward_pass(const ctc_model *m, ctc_oracle *o, const double *q, const double *v);

#endif
