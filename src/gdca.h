/*
 * gdca.h - forward dynamics by the Generalized Divide-and-Conquer Algorithm and inverse dynamics
 * for computed torque control by the inverse GDCA (paper sections 3-4, DESIGN.md section 4).
 *
 * Both work on one balanced binary tree of the bodies (model.h) without forming the mass matrix:
 * an assembly pass from the leaves to the root eliminates the load at each joint, the ground
 * and free-end boundary conditions are solved at the root, and a disassembly pass from the root
 * to the leaves recovers every joint load. Work is O(n); the nodes of one tree height are
 * independent (O(log n) depth with O(n) processors).
 *
 * Call order for one state: ctc_kinematics(m, d, q, v), ctc_handles(m, d), then any number of
 * ctc_gdca_inverse and ctc_gdca_forward calls, which share the body-level records (Eq. 42-43).
 * Neither allocates; both assume a validated model. If a joint's matrix K = h11(right) +
 * h22(left) is not numerically positive definite (it always is for a valid model unless the
 * numbers overflow), d->singular_joint names the joint and the results are NaN.
 */
#ifndef CTC_GDCA_H
#define CTC_GDCA_H

#include "data.h"

/* Forward dynamics: joint accelerations qacc (nv; rad/s^2, m/s^2) from the driving forces f
 * (nv; N m, N) applied by each joint, gravity included. Also fills d->jnt_load (the whole load
 * on body k at joint k: constraint plus drive). qacc may not alias f. */
void ctc_gdca_forward(const ctc_model *m, ctc_data *d, const double *f, double *qacc);

/* Inverse dynamics for CTC (iGDCA): the driving forces f (nv; N m, N) that make the joint
 * accelerations equal the commanded u (nv), i.e. f = M(q) u + N(q, v) (paper Eq. 18, 44-54).
 * Each assembly's handle equations are held in composite form (gdca_inverse.c), which is
 * algebraically the paper's Eq. 32-39 and keeps full accuracy on long chains. Needs
 * ctc_kinematics and ctc_handles for the state. Also fills d->jnt_load_inv. f may not alias u. */
void ctc_gdca_inverse(const ctc_model *m, ctc_data *d, const double *u, double *f);

/* The same driving forces by the paper's iGDCA in its literal mobility form (Eq. 26-39), which
 * shares the body records with the forward pass (Eq. 42-43) but loses accuracy on long or
 * stiffly proportioned chains (about eps cond(M)); for comparison and benchmarks. */
void ctc_gdca_inverse_mobility(const ctc_model *m, ctc_data *d, const double *u, double *f);

#endif
