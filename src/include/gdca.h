/*
 * gdca.h - forward dynamics by the Generalized Divide-and-Conquer Algorithm and inverse dynamics
 * for computed torque control by the inverse GDCA (paper sections 3-4, DESIGN.md section 4).
 *
 * Both work on a binary assembly tree of the bodies without forming the mass matrix (on a branched
 * kinematic tree, the plan of model.c: each heavy path assembled as a chain, each light subtree
 * raked into its parent as an articulated body, gdca_rake.h): an assembly
 * pass from the leaves to the root eliminates the load at each joint, the ground and free-end
 * boundary conditions are solved at the root, and a disassembly pass from the root to the leaves
 * recovers every joint load. Work is O(n). On the balanced tree (model.h) the nodes of one tree
 * height are independent (O(log n) depth with O(n) processors). An open chain's (or tree's)
 * forward pass takes the sequential order instead unless it is to split over threads
 * (gdca_forward_order_seq): single bodies joined from the free tip and from the grounded base,
 * about half the arithmetic (gdca_forward_seq.h; a tree's paths from their tips only).
 *
 * A model with merged bodies (model.h, fixed joints) is computed on its reduced model m->dyn with
 * d->dyn (data.h ctc_data_dyn_begin): the same coordinate vectors in and out, d's settings and
 * threads, and the results (joint loads, singular_joint, ...) copied back in m's numbering.
 *
 * Call order for one state: ctc_kinematics(m, d, q, v), ctc_handles(m, d), then any number of
 * ctc_gdca_inverse and ctc_gdca_forward calls, which share the body-level records (Eq. 42-43).
 * The composite inverse keeps the parts of its records that depend on the state only (composite
 * inertias) from its first call at a state to the next ctc_handles, so a new state needs both
 * ctc_kinematics and ctc_handles before either pass.
 * Neither allocates (except that the first pass that splits over threads starts the data's workers,
 * data.h); both assume a validated model. If a joint's matrix K = h11(right) + h22(left) is not
 * numerically positive definite (it always is for a valid model unless the numbers overflow),
 * d->singular_joint names the joint and the results are NaN.
 *
 * Loop models (model.h, paper section 5): forces and accelerations are extended vectors (nvx:
 * the chain's coordinates, then the closing joint's). The forward pass constrains both terminal
 * handles - joint 0 to the ground and the closing joint n from the tip to the ground - and
 * solves the two sets of boundary equations together (the paper's reference [48]); dependent
 * joints carry no driving force (f of their coordinates is ignored). A loop closed on body b
 * instead of the ground is solved the same way one level down the tree: the root splits at
 * joint b + 1, and the root solve couples the parts' records through joints 0, b + 1 and the
 * closing joint (gdca_loop.h). The paper's inverse pass
 * (ctc_gdca_inverse_mobility) assembles across a dependent joint with the forward, projected rule
 * (its acceleration is unknown) and across an independent joint with the commanded acceleration
 * (Eq. 19), solves the boundary case of the terminal joints (Eq. 55-65: both independent, one of
 * each, both dependent) and stops the disassembly where every independent joint's load is known
 * (Fig. 4). ctc_gdca_inverse gets the same forces from the open chain's composite pass and one
 * dim x dim solve at the closing joint (gdca_inverse_loop.h), which keeps full accuracy on long
 * loops. Both fill f for the independent coordinates and 0 for the dependent ones, and record a
 * condition estimate of their solve in d->loop_cond; when it is singular (the independent joints
 * cannot drive the loop, or its constraints are redundant) d->singular_joint = n and the results
 * are NaN.
 */
#ifndef CTC_GDCA_H
#define CTC_GDCA_H

#include "data.h"

/* Forward dynamics: joint accelerations qacc (nv, nvx for loops; rad/s^2, m/s^2) from the
 * driving forces f (nv, nvx for loops; N m, N) applied by each joint, gravity included. Also fills
 * d->jnt_load (the whole load on body k at joint k: constraint plus drive). The literal pass of
 * DESIGN.md section 4; on long or stiffly proportioned chains, open or closed, and with singular
 * or slender bodies, refined by the composite inverse's residual (gdca_refine.h;
 * d->opt.fwd_refine, d->fwd_refine_done). With d->opt.fwd_form = CTC_FWD_REFERENCE an open model
 * takes the reference form of ctc_gdca_forward_from with a_ref = 0 instead, its f_ref = N(q, v)
 * from one composite inverse. Overwrites d->jnt_load_inv where it refines or takes the reference
 * form. On a model with singular or slender bodies the refinement corrects qacc but not the
 * constraint part of d->jnt_load, which keeps the augmented inertias' error (up to about 1e-4 of
 * the largest load on rods of moment ratio 1e-12; test_gdca_forward): exact loads are those of
 * ctc_gdca_inverse(m, d, qacc, ...) at the result, in d->jnt_load_inv. qacc may not alias f. */
void ctc_gdca_forward(const ctc_model *m, ctc_data *d, const double *f, double *qacc);

/* Forward dynamics in the reference form: for any reference acceleration a_ref,
 *     M qdd + N = f   <=>   qdd = a_ref + M^-1 (f - f_ref),   f_ref = M a_ref + N,
 * so qacc (nv; rad/s^2, m/s^2) = a_ref + dq with M dq = f - f_ref solved by the forward pass in
 * its bias-free mode (every body's h13 = h23 = 0, every beta = 0: the velocity and gravity terms
 * are in f_ref and nothing cancels, so dq's error is relative to |f - f_ref|, not to the forces'
 * size; gdca_forward_joint.h). f_ref (nv; N m, N) must be what ctc_gdca_inverse(m, d, a_ref,
 * f_ref) returned on this d at this state, its d->jnt_load_inv untouched since: d->jnt_load is
 * the bias-free pass's loads plus those, the whole loads as ctc_gdca_forward gives them (with
 * its caveat for singular or slender bodies). a_ref
 * (nv) may be NULL for 0. In a CTC step with an exact model, a_ref = u and f_ref = the
 * controller's iGDCA(u), so the pass costs one bias-free sweep (sim_rhs.c). A model with singular
 * or slender bodies solves with augmented inertias, and its result is refined as ctc_gdca_forward
 * refines (gdca_refine.h gdca_refine_steps_ref); others are refined only if d->opt.fwd_refine >= 0
 * asks for steps. A loop model, or d->opt.fwd_form = CTC_FWD_LITERAL, takes ctc_gdca_forward(m,
 * d, f, qacc) instead (a_ref and f_ref unused). qacc may not alias f, a_ref or f_ref. */
void ctc_gdca_forward_from(const ctc_model *m, ctc_data *d, const double *f, const double *a_ref,
                           const double *f_ref, double *qacc);

/* Inverse dynamics for CTC (iGDCA): the driving forces f (nv, nvx for loops; N m, N) that make
 * the (independent) joint accelerations equal the commanded u (nv, nvx for loops), i.e. f = M(q) u
 * + N(q, v) (paper Eq. 18, 44-54). Each assembly's handle equations are held in composite form
 * (gdca_inverse.c), which is algebraically the paper's Eq. 32-39 and keeps full accuracy on long
 * chains. Needs ctc_kinematics and ctc_handles for the state. Also fills d->jnt_load_inv. f may not
 * alias u. */
void ctc_gdca_inverse(const ctc_model *m, ctc_data *d, const double *u, double *f);

/* The same driving forces by the paper's iGDCA in its literal mobility form (Eq. 26-39), which
 * shares the body records with the forward pass (Eq. 42-43) but loses accuracy on long or
 * stiffly proportioned chains (about eps cond(M)); for comparison and benchmarks. For loop models
 * it is the paper's closed-chain iGDCA with the mixed assembly rule and the early stop
 * (d->opt.inv_full = 1 turns the early stop off); ctc_gdca_inverse uses it only for loops whose
 * dependent coordinates do not number dim (passive ones).
 *
 * The literal form needs every body's inverse inertia (Eq. 42-43): a singular body (a point mass,
 * a massless body; model.h "singular bodies") has none, and the forward pass's records, which this
 * form shares, hold an augmented one instead, as they do for slender bodies; its forces would be
 * those of the augmented bodies (off by 1e-7 to 1e-5 of the largest). So on a model with augmented
 * bodies (m->fwd_bodies != m->bodies) it returns ctc_gdca_inverse's forces, bitwise, which are
 * exact there; except on a loop whose dependent coordinates do not number dim, which
 * ctc_gdca_inverse itself sends here: there the literal pass runs on the augmented records (a
 * passive loop's forces are all 0 either way; a run refuses any other such loop, loop.h). */
void ctc_gdca_inverse_mobility(const ctc_model *m, ctc_data *d, const double *u, double *f);

#endif
