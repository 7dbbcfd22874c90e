/*
 * gdca_forward_seq.h - the sequential assembly order of forward GDCA (internal to the library;
 * ctc_gdca_forward and the refinement's correction call it).
 *
 * GDCA may assemble the bodies along any binary tree; the balanced one (model.h) has the least
 * depth, which is what a pass split over threads needs (gdca_par.h). On one thread the depth buys
 * nothing, and the order that joins each body to the assembly of the bodies after it, from the
 * free tip down to the base, does about half the arithmetic: every assembly of that order holds
 * the free end, so only its handle-1 equations are ever formed (gdca_forward_seq.c), and the
 * same from the grounded base. An open chain's forward pass takes it unless the pass is to split
 * over threads (gdca_forward_order_seq: two threads or more, a least length, and the measured
 * choice of the evaluation gate, data.h ctc_eval_gate); loop models,
 * whose root solves the loop's boundary equations together (gdca_loop.h), always take the tree.
 * A branched tree's sequential order is the tip run along every heavy path, its light subtrees
 * raked into their parents as they are met (gdca_forward_tseq.c).
 */
#ifndef CTC_GDCA_FORWARD_SEQ_H
#define CTC_GDCA_FORWARD_SEQ_H

#include "data.h"

/* 1 if the forward pass of m with d's settings (options.h fwd_order, threads) may take the
 * balanced tree split over threads instead of the sequential order: an open model, fwd_order
 * CTC_ORDER_AUTO, two threads or more and a length from which the tree was measured to gain
 * (gdca_forward.c). Whether it does is then the evaluation gate's measured choice (data.h
 * ctc_eval_gate, fwd_split). */
int gdca_forward_tree_candidate(const ctc_model *m, const ctc_data *d);

/* 1 if the forward pass of m with d's settings (options.h fwd_order) and the gate's choice for
 * the last ctc_gdca_forward (d->fwd_split) takes the sequential order, 0 for the balanced tree;
 * the refinement's correction asks it for the order of the pass it corrects */
int gdca_forward_order_seq(const ctc_model *m, const ctc_data *d);

/* The forward pass on an open chain in the sequential order, in mode `mode`
 * (gdca_forward_joint.h): as ctc_gdca_forward without the refinement (GDCA_FWD_FULL), its
 * bias-free correction (GDCA_FWD_CORRECT; gdca_refine.h), which reuses the factors and records of
 * the full pass just made at this state, or the reference form's bias-free pass
 * (GDCA_FWD_BIASFREE; gdca.h ctc_gdca_forward_from), which forms them. Serial. Fills
 * d->jnt_load (GDCA_FWD_CORRECT: adds to it; GDCA_FWD_BIASFREE: the pass's loads plus
 * d->jnt_load_inv, the reference's), d->singular_joint, d->fwd_E, d->fwd_z, the forward
 * node records (S_i: h11, h13 and K in the h22 slot; B_k: h22, h23 and K in the h11 slot) and
 * d->tload. qacc may not alias f. */
void gdca_forward_seq(const ctc_model *m, ctc_data *d, const double *f, double *qacc, int mode);

/* The same on a branched tree (model.h chain = 0; gdca_forward_tseq.c): each heavy path in the
 * tip run, its light subtrees raked in as they are met. Serial. Fills d->jnt_load
 * (GDCA_FWD_CORRECT: adds to it; GDCA_FWD_BIASFREE: plus d->jnt_load_inv), d->singular_joint (the
 * lowest singular joint), d->fwd_E, d->fwd_z, d->rake, the forward records (2n slots: S_k's h11,
 * h13 and its heavy joint's K at slot k, the raked R_k at n + k) and d->tload. qacc may not alias
 * f. */
void gdca_forward_seq_tree(const ctc_model *m, ctc_data *d, const double *f, double *qacc,
                           int mode);

#endif
