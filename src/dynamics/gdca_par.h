/*
 * gdca_par.h - one GDCA pass over the model's assembly tree (balanced; for a loop closed on a body,
 * the root splits at the loop's first joint: model.h loop_first; a branched tree's plan of JOIN,
 * SUM and RAKE nodes, model.c), one tree height at a time, with
 * the nodes of a height split over the threads of the data's pool (internal to the library; used by
 * gdca_forward.c, gdca_inverse.c and gdca_inverse_mobility.c).
 *
 * A pass is four kinds of work (DESIGN.md section 4): an optional per-body stage, the assembly
 * from the leaves to the root, the root's boundary solve, and the disassembly from the root to
 * the leaves. The nodes of one height depend only on lower heights in the assembly and only on
 * higher ones in the disassembly (model.h: m->tree is ordered by height, height_start gives each
 * height's contiguous range), so the stages run in the order
 *     bodies, assembly heights 1 .. H, root, disassembly heights H .. 1
 * (heights up to H - 1 when the root callback takes the top node: root_takes_top)
 * and the items of one stage are cut into contiguous chunks that the threads of the data's pool
 * run, each thread the same part of every stage unless it is late (pool.h): a stage of c items
 * gets min(c / grain, threads) chunks, and one with fewer than two runs whole on one thread, as
 * does the root always (a loop model's root solve is special and small); consecutive stages
 * that do not split run as one piece. A chunk starts once every chunk of the earlier stages is
 * done. A pass none of whose stages splits, a chain of fewer than min_bodies bodies, or a data
 * with threads = 1 runs without the pool on the caller's thread.
 *
 * A gated pass that could split runs split only where that is measured to pay: the data's
 * evaluation gate (data.h ctc_eval_gate, pool.h ctc_pool_gate) times its first evaluations with
 * every such pass alone and with every one split, in turn, then takes the faster way, so that
 * threads never make an evaluation slower than one thread does (beyond the few it measures).
 * Both ways give bitwise the same results. A pass that is not gated (its caller has decided), or
 * a data with d->opt.par_grain > 0 or d->opt.par_split (a forced split, for tests and
 * benchmarks), splits whenever its plan does.
 *
 * The pass's callbacks must write only what belongs to the items they are given (a node's own
 * record, its joint's solution, the loads of its two children; a body's record), so that the
 * result does not depend on the split: every item does the same arithmetic in the same order
 * whatever the threads, and the results are bitwise those of the serial pass. The one quantity
 * shared between nodes, the first joint whose matrix is singular, is reduced deterministically:
 * the assembly callback returns the first tree index of its range whose joint failed, the
 * smallest over all ranges is taken, and d->singular_joint is set to its joint (or -1) before
 * the root callback runs - the joint the serial pass, which visits the nodes in index order,
 * would have named first.
 */
#ifndef CTC_GDCA_PAR_H
#define CTC_GDCA_PAR_H

#include "data.h"

typedef struct gdca_par_pass {
    void *ctx; /* passed to every callback */
    /* bodies lo..hi-1 (NULL: no per-body stage) */
    void (*bodies)(void *ctx, int lo, int hi);
    /* tree nodes lo..hi-1 in increasing order; returns the first of them whose joint's matrix
       was singular, or -1 */
    int (*assemble)(void *ctx, int lo, int hi);
    /* the root's boundary solve, after d->singular_joint is set from the assembly */
    void (*root)(void *ctx);
    /* tree nodes hi-1 down to lo */
    void (*disassemble)(void *ctx, int lo, int hi);
    int root_takes_top; /* 1: for a loop closed on a body (model.h loop_first > 0) the root
                           callback solves the tree's top node itself from its two parts
                           (gdca_loop.h), so the assembly and the disassembly stop below it */
    int grain;      /* the least items per chunk: a stage of fewer than 2 grain items runs whole */
    int min_bodies; /* chains of fewer bodies run the whole pass serially: below it the pass is
                       too short for a second thread to pay (d->opt.par_grain > 0 overrides both) */
    int gated;      /* 1: the evaluation gate decides whether the pass splits (ctc_data_eval_split);
                       0: it splits whenever the plan does (the caller has decided) */
} gdca_par_pass;

/* Runs bodies(ctx, lo, hi) over all of m's bodies, for per-body work whose bodies do not depend
 * on one another (the handles), where d has threads and m at least min_bodies bodies (and as
 * many as threads): where the evaluation's way is to split (ctc_data_eval_split), as contiguous
 * ranges [n j / c, n (j + 1) / c) on d's pool, range j on the thread that takes chunk j of a
 * pass's body stage (so a pass that follows finds its bodies in the same cores' caches), else
 * in one call on the caller's thread. Returns 1 when it ran them, 0 (nothing run) where d or m
 * is too small: the caller then runs them itself. The results do not depend on the way. */
int gdca_par_bodies(const ctc_model *m, ctc_data *d, void (*bodies)(void *ctx, int lo, int hi),
                    void *ctx, int min_bodies);

/* Runs the pass on the threads d allows (data.h: ctc_data_set_threads), starting d's pool at the
 * first pass that splits a stage. Without a pool (threads = 1, or it could not be started) the
 * pass runs serially, with the same results. */
void gdca_par_run(const ctc_model *m, ctc_data *d, const gdca_par_pass *pass);

#endif
