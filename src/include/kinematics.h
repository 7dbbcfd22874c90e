/*
 * kinematics.h - the kinematics pass: poses, velocities and each joint's maps P, D and beta.
 *
 * From base to tip, each body after its parent p = lambda(k) = m->body_parent[k] (model.h), for
 * the state (q, v), computes each body's frame (origin = handle 1, the centre of joint k),
 * orientation, centre of mass, angular velocity and origin velocity, and each joint's free-motion
 * map P (orthonormal columns), its orthogonal complement D and the velocity-product term beta of
 * the acceleration constraint (paper Eq. 14, DESIGN.md section 4):
 *
 *     A1(body k) = A2(body p) + P qdd_k + beta_k,
 *
 * where A2(body p) is the acceleration of the material point of body p at joint k's centre (the
 * ground: at rest). With w = omega(p) the parent's angular velocity and u the axis in world
 * coordinates:
 *     revolute     P = (u; 0)             beta = (w x u qd; 0)
 *     prismatic    P = (0; u)             beta = (0; 2 w x u qd)          (Coriolis)
 *     cylindrical  P = [(u; 0), (0; u)]   beta = (w x u qd0; 2 w x u qd1)
 *     spherical    P = (R_k; 0)           beta = (w x omega_rel; 0)   omega_rel = R_k v_k
 *     fixed        P = none               beta = 0
 * Planar form: the same in the plane's coordinates (omega_z, v_x, v_y); beta vanishes for
 * revolute joints there.
 */
#ifndef CTC_KINEMATICS_H
#define CTC_KINEMATICS_H

#include "data.h"

/* Computes the kinematics of state q (nq, rad / m / quaternions) and v (nv, rad/s / m/s) into
 * d's kinematics and joint arrays (data.h), for every body of m; with merged bodies (model.h),
 * also the reduced model's into d->dyn, copied from them. Assumes a validated model; allocates
 * nothing. */
void ctc_kinematics(const ctc_model *m, ctc_data *d, const double *q, const double *v);

/* The world position x (m) and velocity xd (m/s) of the point p (m, in body k's frame, whose
 * origin is joint k's centre) of body k, from d's kinematics (ctc_kinematics):
 *     x = xpos_k + R_k p,   xd = xvel_k + omega_k x (R_k p)
 * In planar form the plane's coordinates are turned into the world's (x e1 + y e2 + z n), the
 * normal component being the sum of the joint locations' along n on the path from the ground
 * plus p's (constant: every motion lies in the plane). 0 <= k < nbodies. Pure. */
void ctc_kinematics_point(const ctc_model *m, const ctc_data *d, int k, const double p[3],
                          double x[3], double xd[3]);

/* The rotation R (row-major 3 x 3) that maps body k's frame to the world's, from d's
 * kinematics: xrot_k in spatial form; in planar form B R_z(angle_k) B^T with B = [e1 e2 n] the
 * plane's axes as columns (a body's frame is parallel to the world's at q = 0, model.h), so a
 * vector's component along n is unchanged. 0 <= k < nbodies. Pure. */
void ctc_kinematics_body_rotation(const ctc_model *m, const ctc_data *d, int k, double rot[9]);

/* The unit quaternion (w, x, y, z) of the rotation rot (row-major 3 x 3, proper orthogonal), with
 * w >= 0 (of q and -q, the one with the non-negative scalar part; on w = 0 the first non-zero of
 * x, y, z positive), by Shepperd's method (the largest of 4 w^2, 4 x^2, 4 y^2, 4 z^2 first; J.
 * Guidance and Control 1(3), 1978). Pure. */
void ctc_rotation_quaternion(const double rot[9], double quat[4]);

#endif
