/*
 * options.h - how the GDCA passes compute, apart from what they compute on.
 *
 * A ctc_options holds the settings of the passes of one ctc_data (data.h d->opt): the forward
 * pass's assembly order and refinement, the inverse pass's early stop on loops, and the least
 * work a thread of a split stage takes. They choose among computations that agree to rounding
 * (the orders, the grain) or trade a little accuracy for time (the refinement, the early stop);
 * none of them changes the equations solved. Production code keeps the defaults, which the
 * library picks by rule from the model and the thread count; tests and benchmarks set them to
 * compare the alternatives on one model. ctc_data_new fills d->opt with ctc_options_default();
 * change a field between passes, never during one.
 */
#ifndef CTC_OPTIONS_H
#define CTC_OPTIONS_H

/* the forward pass's assembly orders of an open chain or tree (gdca_forward_seq.h) */
enum {
    CTC_ORDER_AUTO = 0, /* by rule and measure: on two threads or more from a least length on,
                           the balanced tree split or the sequential order, whichever the
                           evaluation gate times faster (data.h ctc_eval_gate,
                           gdca_forward_order_seq); else the
                           sequential order */
    CTC_ORDER_TREE = 1, /* the balanced assembly tree, a branched tree's plan (gdca_forward.c) */
    CTC_ORDER_SEQ = 2   /* the sequential order (gdca_forward_seq.c, a branched tree's
                           gdca_forward_tseq.c); loops take the tree */
};

/* the forward pass's form on an open model (gdca.h ctc_gdca_forward_from) */
enum {
    CTC_FWD_AUTO = 0,     /* ctc_gdca_forward_from: the reference form; ctc_gdca_forward: the
                             literal pass (gdca_refine.h gdca_forward_takes_ref) */
    CTC_FWD_LITERAL = 1,  /* the literal pass with its bias terms, refined by rule (both entry
                             points; ctc_gdca_forward_from ignores its reference) */
    CTC_FWD_REFERENCE = 2 /* the reference form everywhere (ctc_gdca_forward: a_ref = 0) */
};

typedef struct ctc_options {
    int fwd_order;  /* CTC_ORDER_*: the forward pass's assembly order on an open chain or tree */
    int fwd_refine; /* most refinement steps of ctc_gdca_forward (gdca_refine.h): -1 = its rule
                       (CTC_REFINE_MAX_STEPS on stiffly proportioned chains, one on long ones,
                       else none); >= 0: at most that many */
    int fwd_form;   /* CTC_FWD_*: literal pass or reference form; loop models always take the
                       literal pass */
    int inv_full;   /* 1: the mobility-form inverse pass of a loop model disassembles every node
                       (no early stop once every driving force is known); 0 = the early stop */
    int par_grain;  /* the least items per chunk of a split stage of a pass (one tree height, or
                       the bodies; gdca_par.h), and no least chain length; 0 = the pass's
                       measured values */
    int par_split;  /* 1: a pass whose plan splits runs split, without asking the evaluation
                       gate whether that pays (tests and benchmarks time the split itself; on an
                       open model with fwd_order AUTO the forward pass then takes the tree
                       wherever it may); 0 = by the gate (data.h ctc_eval_gate, gdca_par.h) */
} ctc_options;

/* The defaults: every choice by the library's rule. */
static inline ctc_options ctc_options_default(void)
{
    return (ctc_options){.fwd_order = CTC_ORDER_AUTO,
                         .fwd_refine = -1,
                         .fwd_form = CTC_FWD_AUTO,
                         .inv_full = 0,
                         .par_grain = 0,
                         .par_split = 0};
}

#endif
