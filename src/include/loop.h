/*
 * loop.h - the kinematics of a loop's closing joint: its coordinates, its maps P, D and beta, the
 * closure residuals and their Jacobian, and putting a state back onto the closure (paper section
 * 5, DESIGN.md section 5).
 *
 * The closing joint n joins the tip body n-1 (parent) to its child, the ground or body b
 * (model.h). With the tip's point p_t (the joint's centre on the tip) and the anchor p_a (on the
 * child), both in the world, the closure asks that the child's side moves relative to the tip's
 * only along P_n:
 *
 *     pose error   delta = (rotation error; p_a - p_t)
 *     residual     phi  = D_n^T delta                        (nc = dim - nv_n components; m, rad)
 *     rate         dphi = D_n^T (V_a - V_t)                  (V_t, V_a: the tip's and the child's
 *                                                             twists at p_t; m/s, rad/s)
 *     acceleration D_n^T (A_t + beta_n - A_a) = 0            (classical accelerations at p_t)
 *
 * The ground is at rest (V_a = A_a = 0). The rotation error is, for a revolute closing joint,
 * u_t x u_a, the misalignment of the axis carried by the tip (u_t = R_t a) from the same axis
 * carried by the child (u_a = R_a a, because the child's frame is Rot(a, q_n) of the tip's); for
 * a prismatic one the rotation vector of R_a R_t^T (the child's orientation relative to the tip);
 * a spherical one has none. Planar form: revolute none, prismatic the tip's angle relative to
 * the child, wrapped to (-pi, pi], negated. phi = 0 is the loop closed; its derivative along the
 * motion is dphi to first order. beta_n is a chain joint's (kinematics.h) with the tip as parent:
 * (w_t x w_rel; 2 w_t x u qd_n), w_rel the child's angular velocity relative to the tip.
 *
 * The closing joint's coordinate and rate (revolute: angle and rate about the axis; prismatic:
 * displacement along it; spherical: the child's orientation relative to the tip as a
 * quaternion, and the relative angular velocity in the child's frame) are computed from the
 * chain's state, not integrated.
 *
 * Loop Jacobian: the relative twist at p_t is V_t - V_a = sum_k J_k v_k over the loop's chain
 * coordinates (model.h jnt_loop: joints loop_first..n-1 on a chain, the spine's after b on a
 * tree; the joints from the ground to b move the tip and the child alike, and a branch off the
 * spine moves neither), J_k their unit twists moved to p_t; the closure's Jacobian is
 * G = -D_n^T J (nc x nv). Newton's method on the dependent coordinates uses G restricted to them.
 */
#ifndef CTC_LOOP_H
#define CTC_LOOP_H

#include <stddef.h>

#include "data.h"
#include "status.h"

/* Condition number of the dependent coordinates' twist matrix (linear rows divided by the loop's
 * size) beyond which ctc_loop_check calls a configuration singular. */
#define CTC_LOOP_SINGULAR_COND 1e8

/* Fills the closing joint's entries of d (after the chain's part of ctc_kinematics, which calls
 * this itself for loop models): jnt_P, jnt_D, jnt_beta at index n, d->loop_q, d->loop_v, and the
 * residuals d->loop_phi, d->loop_dphi. Nothing for open chains. */
void ctc_loop_kinematics(const ctc_model *m, ctc_data *d);

/* The unit twist tw (dim) of chain coordinate c of joint k (k < n) at the closing joint's point
 * on the tip, d->loop_pt: the tip's velocity there per unit rate of that coordinate, and (its
 * transpose) the coordinate's generalised force per unit load at that point. For a joint of the
 * loop (m->jnt_loop[k]) it is also the twist relative to the closing joint's child. Needs the
 * state's ctc_kinematics. */
void ctc_loop_coord_twist(const ctc_model *m, const ctc_data *d, int k, int c, double *tw);

/* Max-norms of the position residual (m or rad) and the velocity residual (m/s or rad/s) of the
 * state last given to ctc_kinematics; 0 and 0 for an open chain. */
void ctc_loop_residual_norms(const ctc_model *m, const ctc_data *d, double *pos, double *vel);

/* What putting a state onto the closure did. */
typedef struct ctc_loop_fix {
    int iterations;                 /* Newton iterations on the positions */
    double dq_max;                  /* largest change of a position coordinate (rad, m) */
    double dv_max;                  /* largest change of a velocity coordinate (rad/s, m/s) */
    double res_before, res_after;   /* position residual max-norm before and after */
    double vres_before, vres_after; /* velocity residual max-norm before and after */
} ctc_loop_fix;

/* Puts (q (nq), v (nv)) onto the closure in place: Newton's method moves the dependent chain
 * coordinates only (the independent ones are exact), by the smallest correction (least-norm
 * step when the closing joint is itself independent and leaves them a freedom), until the
 * position residual is below tol (m, rad; > 0) or max_iter iterations; then the dependent
 * velocities are solved so that the velocity residual vanishes. d is scratch (the kinematics of
 * the result are left in it). Returns CTC_OK and fills fix (may be NULL); CTC_EINVAL with a
 * message when Newton does not converge ("the loop does not close from q0: residual 0.31 m
 * after 50 Newton iterations") or the dependent coordinates cannot move the closure
 * (singular). Allocates nothing beyond a few stack arrays of dim x dim. */
ctc_status ctc_loop_assemble(const ctc_model *m, ctc_data *d, double *q, double *v, double tol,
                             int max_iter, ctc_loop_fix *fix, char *err, size_t errlen);

/* Checks a loop model at the state q (nq): the independent coordinates' count equals the
 * mobility by Gruebler-Kutzbach and by the rank of the loop Jacobian at q; the dependent
 * coordinates (those of the closing joint included) determine the loop (their twist matrix has
 * full rank dim). Messages name the counts, e.g. "loop mobility is 3 (Gruebler-Kutzbach: 6 joint
 * freedoms - 3) but 2 coordinates are independent"; "the loop is over-constrained at q0: ..."
 * or "the dependent joints cannot move the loop at q0 (singular configuration; condition
 * number 3e+16)". *cond (may be NULL) gets the condition number of the dependent twist matrix.
 * CTC_OK for open chains. */
ctc_status ctc_loop_check(const ctc_model *m, ctc_data *d, const double *q, double *cond, char *err,
                          size_t errlen);

#endif
