/*
 * handles.h - the body-level handle equations, computed once per state (paper Eq. 8-13, 42-43).
 *
 * For body k with mass m, centre of mass c, inertia I_c and inverse I_c^-1 (world frame),
 * angular velocity w, handle i at r_i = handle - c (handle 1 = joint k, handle 2 = the joint of
 * its heavy child, m->body_heavy[k], which is k+1 in a chain; a tree's light children are raked in
 * by the passes, gdca_rake.h;
 * a body without a child has its handle 2 at its centre of mass, where no load acts, or in a loop
 * model the tip has it at the closing joint's centre on it, d->loop_pt):
 *
 *     A_i = sum_j h_ij F_j + h_i3,     h_ij = T_i M^-1 T_j^T,
 *     h_i3 = T_i M^-1 b + (0; w x (w x r_i)),     b = (-w x I_c w; m g)
 *     T_i = [1 0; -[r_i]x 1],   M = diag(I_c, m 1)
 *
 * In planar form T_i = [1 0 0; -r_y 1 0; r_x 0 1], M = diag(J, m, m) and w x (w x r) = -w^2 r.
 * The same records serve the inverse and the forward passes (the paper's psi = eta, Eq. 42-43),
 * and do not depend on the driving forces.
 */
#ifndef CTC_HANDLES_H
#define CTC_HANDLES_H

#include "data.h"

/* Fills d->hr and the matrices h11, h12, h22 of d->hbody from the kinematics in d
 * (ctc_kinematics first; with merged bodies, model.h, the reduced model's records in d->dyn
 * instead, from its kinematics there), and marks d as holding a new state (d->handles_stamp), so
 * that the composite inverse recomputes the parts of its records that it keeps between calls at
 * one state (gdca.h) and the bias terms are recomputed when asked for. Allocates nothing. */
void ctc_handles(const ctc_model *m, ctc_data *d);

/* Fills the bias terms h13 and h23 of d->hbody for the state of the last ctc_handles, unless they
 * already hold them (d->hbias_stamp). Only the passes that take the bias terms from the records
 * need them, and call this first: the literal forward pass (gdca.h ctc_gdca_forward, and its loop
 * form) and the mobility-form inverse. The reference form's bias-free pass, its correction and
 * the composite inverse do without, which saves a CTC right-hand side on a spatial chain about
 * 5% of its instructions (bench/NOTEBOOK.md, "Spatial n = 2 and 4"). Allocates nothing. */
void ctc_handles_bias(const ctc_model *m, ctc_data *d);

#endif
