/*
 * gdca_refine.h - iterative refinement of forward GDCA on long or stiffly proportioned chains,
 * open or closed (internal to the library; ctc_gdca_forward calls it).
 *
 * The forward pass assembles each node's bias terms h13, h23 from the bodies' velocity and
 * gravity terms and the driving forces. In a CTC step the forces nearly balance those terms, so
 * the assembled biases are differences of large numbers and the accelerations lose digits in
 * proportion to the chain's conditioning (bench/NOTEBOOK.md, "Hard cases").
 * The refinement measures how far the result misses the equations of motion with the composite
 * inverse pass, which is accurate to rounding because composite inertias add,
 *     r = f - (M(q) qdd + N(q, v))            (ctc_gdca_inverse of qdd),
 * and corrects qdd by the forward pass's own operator on r with every bias term zero:
 *     dq = M^-1 r,   qdd <- qdd + dq.
 * That correction pass is the forward pass in a bias-free mode, in the order the forward pass
 * took (gdca_forward.c, gdca_forward_seq.c): it reuses the joint factors E and the assembled
 * matrices of the forward pass just made, so it costs vector work only, and the composite inverse
 * at the same state keeps its composite inertias (gdca_inverse.c). The forward operator's
 * relative error on a bias-free right-hand side is many orders smaller than on the cancelling
 * one, so one step brings the accelerations to the accuracy of the forces' residual. A loop
 * model's residual and correction include the closing joint's load and the closure
 * (gdca_refine_residual).
 *
 * The reference form (gdca.h ctc_gdca_forward_from) starts where a refinement step would: its
 * reference's forces f_ref come from the composite inverse, and its pass is the bias-free one
 * (forming its own factors), so an evenly proportioned chain needs no step after it at any
 * length; a stiffly proportioned chain (the bias-free pass itself loses digits to the mass
 * ratio) and a model with augmented bodies keep their steps (gdca_refine_steps_ref).
 */
#ifndef CTC_GDCA_REFINE_H
#define CTC_GDCA_REFINE_H

#include "data.h"

/* By default (d->opt.fwd_refine < 0) a chain is refined when it has at least CTC_REFINE_MIN_BODIES
 * bodies, or its body masses or inertias span a ratio of CTC_REFINE_MASS_RATIO or more (model.h
 * mass_ratio). A stiffly proportioned chain gets up to CTC_REFINE_MAX_STEPS steps (each recovers
 * digits the literal pass lost: test_hard, test_loop), a long evenly proportioned one gets one
 * (its round trip is then at the articulated-body oracle's own), a short even one none. Within
 * that cap, gdca_refine_step decides after each step (delta = max |w dq| / max |qdd|, the step's
 * change relative to the result). The correction pass of a model without augmented bodies is
 * M^-1 itself up to rounding, so its steps stop once a correction is below CTC_REFINE_CONVERGED of
 * the accelerations (the next would be smaller by the bias-free pass's own relative error, far
 * below rounding of the result), or shrinks by less than a factor CTC_REFINE_STALL (the residual
 * has reached its rounding level). A model with singular or slender bodies corrects with the
 * augmented inertias' M_aug^-1, whose steps converge at the rate of the augmentation's share of
 * M, slowly where M(q) is ill conditioned; its steps follow that rate:
 *   - the first step ends the refinement when delta <= CTC_REFINE_CONVERGED, as above;
 *   - from the second step, the ratio lambda = dq . dq_last / |dq_last|^2 of the correction to the
 *     last one estimates the rate (the iteration is linear: its slowest mode soon dominates). The
 *     refinement ends once delta <= CTC_REFINE_TOL and the corrections still to come, a
 *     geometric series at that rate, delta |lambda| / (1 - |lambda|), are at most CTC_REFINE_TAIL
 *     (delta bounds a slower mode that the second step's ratio, still the first mode's, cannot
 *     show), or once |lambda| >= 1 / CTC_REFINE_SLOW_STALL (a step gains too little: rounding);
 *   - when two successive ratios agree to CTC_REFINE_RATE_AGREE and CTC_REFINE_EXTRAP_MIN <=
 *     |lambda| <= CTC_REFINE_EXTRAP_MAX, one mode dominates the error and the step is
 *     extrapolated: qdd += dq / (1 - lambda) removes that mode at once (the sum of its geometric
 *     series), and the next step checks what is left.
 * On ill-conditioned M(q) (256 slender rods of alternating 1 kg and 1 g, cond(M) ~ 3e9) the
 * slowest mode has lambda of -0.3 to -0.7, where the first rule alone stopped with 4e-8 of qdd
 * left. The exact pass's steps past its rounding level are noise, which the same rate rule would
 * follow to the cap (random planar rods, n >= 256: a third step that changes nothing). Measured:
 * bench/NOTEBOOK.md, "Hard cases", "Closed chains" and "Refinement that converges". */
#define CTC_REFINE_MIN_BODIES 64
#define CTC_REFINE_MASS_RATIO 100.0
#define CTC_REFINE_MAX_STEPS 3
#define CTC_REFINE_CONVERGED 1e-8
#define CTC_REFINE_STALL 10.0
#define CTC_REFINE_TOL 1e-9
#define CTC_REFINE_TAIL 1e-11
#define CTC_REFINE_SLOW_STALL 1.1
#define CTC_REFINE_RATE_AGREE 0.25
#define CTC_REFINE_EXTRAP_MIN 0.2
#define CTC_REFINE_EXTRAP_MAX 0.8

/* On an open chain of CTC_REFINE_CHECK_MIN_BODIES bodies or more, whose conditioning approaches
 * 1 / rounding, the refinement never makes the residual larger: before each step past the
 * first, the residual of the last step's result (which the step computes anyway) is compared
 * with the one before it (max |r|), and if it did not shrink, or is not finite, the last step is
 * undone - the accelerations and d->jnt_load restored bitwise - and the refinement stops
 * (d->fwd_refine_undone = 1); the last step is checked too, by one more residual pass (a repeat
 * of the composite inverse, which keeps its composite inertias: 14% of a CTC right-hand
 * side), after which d->jnt_load_inv holds that pass's loads. Shorter chains were measured to
 * shrink the residual at every step, and the guard's copies would cost them 1-3% of a right-hand
 * side (bench/NOTEBOOK.md, "Long chains to 65536"). The residual is the backward error: a step
 * can still fit the equations better and the exact accelerations worse, which no residual can
 * see; the round trip of the longest chains is compared with the oracle's in test_hard. Loop
 * models keep their own stopping rules (their residual includes the closure, and the correction
 * moves the closing load with qacc). */
#define CTC_REFINE_CHECK_MIN_BODIES 16384

/* A model with a singular or a slender body (model.h "singular bodies", "slender bodies")
 * computes its forward handle equations with augmented inertias, and the refinement removes that
 * error: it gets up to
 * CTC_REFINE_SINGULAR_STEPS steps, or d->opt.fwd_refine if that is more (each shrinks the error
 * by about the augmentation's share, 1e-6 to 1e-5 for a singular body and about 1e-4 for a
 * slender one; the stopping rules above end it after two where M(q) is well conditioned). */
#define CTC_REFINE_SINGULAR_STEPS 6

/* The most refinement steps ctc_gdca_forward makes on model m with settings d: d->opt.fwd_refine
 * when >= 0, else by the rule above CTC_REFINE_MAX_STEPS (mass ratio), 1 (length) or 0. */
int gdca_refine_steps(const ctc_model *m, const ctc_data *d);

/* The most refinement steps after the reference form (gdca.h ctc_gdca_forward_from): a model
 * with singular or slender bodies gets gdca_refine_steps (its bias-free pass solves with the
 * augmented inertias, M_aug^-1, and the steps remove that error); any other none unless
 * d->opt.fwd_refine >= 0 asks for that many, since its bias-free pass is M^-1 itself up to
 * rounding relative to |f - f_ref|, with nothing to cancel. */
int gdca_refine_steps_ref(const ctc_model *m, const ctc_data *d);
/* (Both judge m->dyn, the model the passes run on, when m merges bodies: model.h.) */

/* 1 if ctc_gdca_forward on m with d's settings takes the reference form with a_ref = 0: only
 * when d->opt.fwd_form = CTC_FWD_REFERENCE, and never on a loop model. With a_ref = 0 the
 * bias-free pass solves M qdd = f - N, whose right-hand side is as large as the literal pass's,
 * and the balanced tree's order then misses the backward error of the literal pass refined
 * (autoTree n = 1024: 1.3e-8 against 1e-10 of the forces) and slender ill-conditioned chains
 * converge worse (bench/NOTEBOOK.md, "The reference form (issue 26)"), so the default keeps the
 * literal pass; the reference form pays where a_ref is close to the answer (sim_rhs.c). */
int gdca_forward_takes_ref(const ctc_model *m, const ctc_data *d);

/* What the step rule keeps between the steps of one ctc_gdca_forward; zero it before the first. */
typedef struct gdca_refine_rule {
    int augmented;   /* the model has singular or slender bodies: the rate rule (set it first) */
    int steps;       /* steps seen */
    double last;     /* the last step's max |w dq| */
    double lambda;   /* the last step's ratio (0 before the second step) */
    int extrapolate; /* the last step was extrapolated */
} gdca_refine_rule;

/* One step of the rule above: adds w dq to qacc (nvx; w = 1, or 1 / (1 - lambda) when an
 * augmented model's step is extrapolated), keeps dq in dq_last (nvx; augmented models only) for
 * the next step, and returns 1 when the refinement should stop, else 0. */
int gdca_refine_step(gdca_refine_rule *rule, int nvx, const double *dq, double *dq_last,
                     double *qacc);

/* The residual of the forward pass's accelerations qacc (nv; nvx for a loop model) under the
 * driving forces f (the same length, a loop's dependent entries zero), from the composite inverse
 * pass (gdca_inverse_loop.h): r (the same length; N m, N) = f - (M qacc + N) for an open chain.
 * A loop model's equations also carry the closing joint's load F (d->jnt_load at joint n, on its
 * child) and the closure, so the chain's r = f - (M qacc + N) - J^T F over the loop's
 * coordinates (gdca_inverse_loop.h), the closing joint's r = 0 (its force P_n^T F = f_n holds by
 * construction), and the closure's residual goes to d->loop_rho (data.h); the closing joint's
 * accelerations in qacc are replaced by those of the accurate pass, P_n^T (A_child - A_t -
 * beta_n). The correction then solves the bias-free loop problem with that closure residual as
 * its right-hand side (gdca_forward.c: loop models take the balanced tree), so (qacc, F) move
 * together towards the solution of the
 * constrained equations. Uses the composite records and d->tload. */
void gdca_refine_residual(const ctc_model *m, ctc_data *d, const double *f, double *qacc,
                          double *r);

/* The correction dq (nv, nvx for loops; rad/s^2, m/s^2) = M^-1 r for joint forces r (N m, N),
 * by the forward pass with all bias terms zero in the order the last ctc_gdca_forward took
 * (gdca_forward.c, gdca_forward_seq.c), reusing its factors and records at this state; a loop
 * model's right-hand side includes -d->loop_rho. Splits over the data's threads as the forward
 * pass does, with bitwise the serial results. Adds the correction's joint loads to d->jnt_load,
 * and overwrites the bias parts of the forward node records, d->fwd_z and d->tload. dq may not
 * alias r. */
void gdca_forward_correct(const ctc_model *m, ctc_data *d, const double *r, double *dq);

#endif
