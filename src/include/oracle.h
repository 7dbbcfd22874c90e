/*
 * oracle.h - the independent dynamics oracle: recursive Newton-Euler (inverse dynamics),
 * articulated-body (forward dynamics) and composite-rigid-body (mass matrix) algorithms.
 *
 * The oracle exists to check the GDCA code (gdca*.c) and to be its serial baseline in benchmarks,
 * so it shares nothing with it: it follows Featherstone, Rigid Body Dynamics Algorithms (2008),
 * ch. 5-7, with Plücker spatial vectors in each body's own coordinates and 6x6 motion and force
 * transforms between neighbouring bodies (plucker.h), where GDCA uses handle accelerations in
 * world coordinates. It always works in full 3-D and ignores the model's form, so it is the
 * oracle for planar chains as well; it never inverts a body's inertia, so planar chains of
 * slender rods (singular inertia about the rod axis) are fine, provided every joint-space
 * articulated inertia D = S^T I^A S is positive definite (true for any chain that can move).
 *
 * Conventions are those of model.h: body k's frame has its origin at joint k's centre and is
 * parallel to the world's at q = 0; joint k maps its parent's frame, lambda(k) =
 * m->body_parent[k] (the world's for -1), to body k's frame by a translation to the joint's
 * location followed by the joint's motion. q (nq), v (nv), vdot (nv) and tau (nv) are laid out by
 * m->jnt_qadr / m->jnt_vadr; a spherical joint's 4 coordinates are a quaternion (w, x, y, z),
 * normalised here before use (q itself is not changed), its 3 velocities the child's angular
 * velocity relative to the parent in the child's frame, and its 3 forces the torque vector in the
 * child's frame. Gravity m->gravity is included everywhere, as a fictitious acceleration -g of the
 * ground. SI units throughout.
 *
 * Reads only nbodies, nq, nv, gravity, bodies, joints, jnt_qadr, jnt_vadr, jnt_nq, jnt_nv and
 * body_parent of the model, and walks the tree that body_parent describes (a chain is the tree
 * with parents k - 1), so that it also serves trees. Thread safety: the model is read-only and may
 * be shared; a workspace belongs to one thread at a time, so give each thread its own. The compute
 * calls allocate nothing.
 */
#ifndef CTC_ORACLE_H
#define CTC_ORACLE_H

#include "model.h"

/* Scratch memory and per-body constants of the oracle, sized for one model. */
typedef struct ctc_oracle ctc_oracle;

/* Makes a workspace for model m (which must outlive it and not change), precomputing each body's
 * 6x6 spatial inertia. Returns NULL when an allocation fails. The caller owns the result and
 * frees it with ctc_oracle_free. */
ctc_oracle *ctc_oracle_new(const ctc_model *m);

/* Frees a workspace; NULL is allowed. */
void ctc_oracle_free(ctc_oracle *o);

/* Inverse dynamics by the recursive Newton-Euler algorithm (Featherstone 5.3), O(n):
 *     tau = M(q) vdot + C(q, v) v + G(q)
 * i.e. the generalised forces (nv) that produce the accelerations vdot (nv) at state q (nq),
 * v (nv) under gravity. o must have been made from m. All arrays are the caller's. */
void ctc_oracle_rnea(const ctc_model *m, ctc_oracle *o, const double *q, const double *v,
                     const double *vdot, double *tau);

/* Forward dynamics by the articulated-body algorithm (Featherstone 7.3), O(n):
 *     vdot = M(q)^{-1} (tau - C(q, v) v - G(q))
 * for generalised forces tau (nv) at state q (nq), v (nv) under gravity; writes vdot (nv).
 * o must have been made from m. All arrays are the caller's. */
void ctc_oracle_aba(const ctc_model *m, ctc_oracle *o, const double *q, const double *v,
                    const double *tau, double *vdot);

/* Joint-space mass matrix M(q) by the composite-rigid-body algorithm (Featherstone 6.2), O(n d)
 * for depth d (O(n^2) for a chain): with I^c_i the composite inertia of i's subtree in body i's
 * frame,
 *     M_ji = S_j^T (i_X_j)^T I^c_i S_i   for j an ancestor of i or i,   M_ij = M_ji^T,
 * every other block zero, so that the kinetic energy is 1/2 v^T M v. Writes M (nv x nv, row-major,
 * symmetric, both triangles filled) for positions q (nq). o must have been made from m. All arrays
 * are the caller's. */
void ctc_oracle_mass_matrix(const ctc_model *m, ctc_oracle *o, const double *q, double *mass);

#endif
