/*
 * gdca_inverse_loop.h - inverse dynamics of a closed chain for CTC from the open chain's
 * composite iGDCA (internal to the library; ctc_gdca_inverse calls it for loop models).
 *
 * The paper's iGDCA for loops (gdca_inverse_mobility.c) assembles across dependent joints with the
 * projected rule, whose mobilities are differences of large numbers: on loops of hundreds of
 * bodies its forces lose up to 8 digits (bench/NOTEBOOK.md, "Closed chains"). This pass gets the
 * same forces from the open chain's composite pass, which is accurate to rounding, plus one
 * small solve at the closing joint. With the closing joint's load F (on its child, the ground or
 * body b, at the tip's point p_t; the tip bears -F), J_k the unit twist of chain coordinate k at
 * p_t and tau = M(q) qdd + N(q, v) of the open chain:
 *
 *   closure     A_t(qdd) + P_n qdd_n + beta_n = A_b(qdd)    (A_b: the child's acceleration at
 *                                                              p_t, zero on the ground; dim
 *                                                              equations)
 *   balance     f_k = tau_k + J_k^T F (the loop's joints, model.h jnt_loop),  f_n = P_n^T F,
 *               f_k = tau_k (joints 0..b, which F and -F load alike)
 *
 * With every independent coordinate commanded (qdd = u there) and every dependent one unforced
 * (f = 0 there), and exactly dim dependent coordinates (a valid single loop), both are square:
 *   1. the composite pass with the dependent accelerations 0 gives A_t(u0) and A_b(u0); the
 *      closure, linear in the dependent accelerations x (all in the loop, which J_k moves relative
 *      to the child), gives B x = -(A_t(u0) - A_b(u0) + P_n u_n + beta_n), the columns of B
 *      being J_k (dependent chain coordinates) and P_n's (dependent closing coordinates);
 *   2. the composite pass with those accelerations gives tau;
 *   3. B^T F = (-tau_k; 0) over the dependent coordinates gives F, and the balance f.
 * That is two O(n) passes and one dim x dim factorisation (two solves with it, and dim more for
 * the condition estimate), with no mobility differences. Loops whose
 * dependent count is not dim (passive ones, nind = 0) go to the mobility form.
 */
#ifndef CTC_GDCA_INVERSE_LOOP_H
#define CTC_GDCA_INVERSE_LOOP_H

#include "data.h"

/* The driving forces f (nvx) of a loop model for commanded accelerations u (nvx) of its
 * independent coordinates, as described above (0 for the dependent coordinates). Fills
 * d->jnt_load_inv for every joint, the closing joint's with F, and d->loop_cond with the
 * condition estimate of B after equilibration. A singular B gives NaN forces and
 * d->singular_joint = n, and leaves d->jnt_load_inv as it was. Uses d->xbuf. */
void gdca_inverse_loop(const ctc_model *m, ctc_data *d, const double *u, double *f);

/* The 1-norm condition estimate of B (above: the dependent coordinates' unit twists at p_t and
 * the closing joint's dependent columns), equilibrated by rows then columns, at the state of the
 * last ctc_kinematics: how well the dependent joints determine the loop, a kinematic measure that
 * no body's inertia enters; INFINITY when B is singular, NaN when the dependent coordinates do
 * not number dim. gdca_inverse_loop records the same value in d->loop_cond. */
double gdca_loop_dependent_cond(const ctc_model *m, const ctc_data *d);

/* The open chain's composite iGDCA (gdca_inverse.c) on the chain's coordinates: f (nv) =
 * M(q) u + N(q, v) for u (nv), free tip; for a loop model the closing joint is ignored. */
void gdca_inverse_composite(const ctc_model *m, ctc_data *d, const double *u, double *f);

/* The classical acceleration at its handle 2 (dim) of the body that assembly index k stands for
 * (a body, or its RAKE node: model.h loop_body_asm) after the last gdca_inverse_composite. */
void gdca_inverse_handle2_accel(const ctc_model *m, const ctc_data *d, int k, double *a);

/* rel (dim) = A_child - A_t after the last gdca_inverse_composite of a loop model: the closing
 * joint's child's classical acceleration at p_t (zero on the ground) less the tip's there. */
void gdca_inverse_closing_accel(const ctc_model *m, const ctc_data *d, double *rel);

#endif
