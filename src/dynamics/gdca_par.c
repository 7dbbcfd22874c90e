/*
 * gdca_par.c - the plan of a GDCA pass over the assembly tree, run serially or as the stages of
 * a job on the data's pool (gdca_par.h, pool.h).
 *
 * The stages (bodies, assembly heights 1..H, root, disassembly heights H..1) become the pool's
 * stages: a stage of c items that splits is cut into min(c / grain, threads) chunks, contiguous
 * ranges [c j / m, c (j + 1) / m) of its items. The pool gives chunk j of every stage to the
 * same thread, so a thread's chunk at one height mostly reads what its own chunk at the height
 * below wrote (the nodes of one height are stored left to right along the chain, and the left
 * half of one height has its children in the left half of the heights below). A run of
 * consecutive stages that do not split becomes one stage of one chunk, done by one thread in
 * stage order without waiting between them. A gated pass (gdca_par.h) asks the data's evaluation
 * gate which way to take, and marks where its run ended, so that the gate times the evaluation
 * up to its last pass that could split (data.h ctc_eval_gate).
 */
#include "gdca_par.h"

#include <assert.h>
#include <limits.h>
#include <stdatomic.h>

#include "pool.h"

#define MAX_STAGES                                                                                 \
    64 /* bodies, 2 x 21 heights (CTC_MAX_BODIES = 10^6 < 2^20, and one more height when a loop    \
          closed on a body splits the root), root */

enum { STAGE_BODIES, STAGE_ASSEMBLE, STAGE_ROOT, STAGE_DISASSEMBLE };

/* one stage of the pass, or a run of consecutive stages that do not split (a group) */
typedef struct par_stage {
    int kind;    /* STAGE_*; a group of several stages has nchunks = 1 and last > index */
    int lo, hi;  /* the items [lo, hi) */
    int nchunks; /* 1: not split */
    int first;   /* its first chunk, or the group's */
    int last;    /* the group's last stage (its own index when alone) */
} par_stage;

typedef struct par_plan {
    const ctc_model *m;
    ctc_data *d;
    const gdca_par_pass *pass;
    int nthreads, grain;
    int nstages;
    par_stage stage[MAX_STAGES];
    int ngroups;
    int group[MAX_STAGES];           /* the first stage of each group (a split stage is alone) */
    int group_first[MAX_STAGES + 1]; /* the first chunk of each group, then the chunk count */
    atomic_int first_singular;       /* the least tree index whose joint failed; INT_MAX: none */
} par_plan;

/* the chunks a stage of count items is cut into: 1 when it does not pay to split */
static int stage_chunks(const par_plan *r, int count)
{
    int u = count / r->grain;
    if (u < 2 || r->nthreads < 2) return 1;
    return u < r->nthreads ? u : r->nthreads;
}

static void add_stage(par_plan *r, int kind, int lo, int hi)
{
    assert(r->nstages < MAX_STAGES);
    par_stage *s = &r->stage[r->nstages++];
    s->kind = kind;
    s->lo = lo;
    s->hi = hi;
    s->nchunks = kind == STAGE_ROOT ? 1 : stage_chunks(r, hi - lo);
}

/* the tree heights the assembly and the disassembly cover: all, or all but the top one (its only
   node the root) when the root callback takes it (gdca_par.h root_takes_top) */
static int pass_heights(const ctc_model *m, const gdca_par_pass *pass)
{
    return m->height - (pass->root_takes_top && m->loop_first > 0);
}

/* the stages of the pass, grouped and numbered; returns the number of chunks */
static int plan_pass(par_plan *r)
{
    const ctc_model *m = r->m;
    const int *hs = m->height_start;
    const int top = pass_heights(m, r->pass);
    r->nstages = 0;
    if (r->pass->bodies) add_stage(r, STAGE_BODIES, 0, m->nbodies);
    for (int h = 1; h <= top; h++) add_stage(r, STAGE_ASSEMBLE, hs[h - 1], hs[h]);
    add_stage(r, STAGE_ROOT, 0, 1);
    for (int h = top; h >= 1; h--) add_stage(r, STAGE_DISASSEMBLE, hs[h - 1], hs[h]);

    int chunks = 0;
    r->ngroups = 0;
    for (int i = 0; i < r->nstages; i++) {
        par_stage *s = &r->stage[i];
        s->last = i;
        if (s->nchunks == 1) { /* join the following stages that do not split either */
            while (s->last + 1 < r->nstages && r->stage[s->last + 1].nchunks == 1) s->last++;
        }
        s->first = chunks;
        r->group_first[r->ngroups] = chunks;
        chunks += s->nchunks;
        r->group[r->ngroups++] = i;
        i = s->last;
    }
    r->group_first[r->ngroups] = chunks;
    return chunks;
}

/* d->singular_joint from the assembly's first singular tree index */
static void set_singular(const ctc_model *m, ctc_data *d, int first)
{
    d->singular_joint = first >= 0 && first < m->ntree ? m->tree[first].joint : -1;
}

static void run_range(par_plan *r, int kind, int lo, int hi)
{
    const gdca_par_pass *p = r->pass;
    switch (kind) {
    case STAGE_BODIES:
        p->bodies(p->ctx, lo, hi);
        break;
    case STAGE_ASSEMBLE: {
        int f = p->assemble(p->ctx, lo, hi), cur = atomic_load(&r->first_singular);
        while (f >= 0 && f < cur && !atomic_compare_exchange_weak(&r->first_singular, &cur, f)) {
        }
        break;
    }
    case STAGE_ROOT:
        set_singular(r->m, r->d, atomic_load(&r->first_singular));
        p->root(p->ctx);
        break;
    default:
        p->disassemble(p->ctx, lo, hi);
        break;
    }
}

/* the group that chunk c belongs to (its first stage) */
static const par_stage *chunk_group(const par_plan *r, int c)
{
    int lo = 0, hi = r->ngroups - 1;
    while (lo < hi) { /* the last group whose first chunk is <= c */
        int mid = (lo + hi + 1) / 2;
        if (r->stage[r->group[mid]].first <= c)
            lo = mid;
        else
            hi = mid - 1;
    }
    return &r->stage[r->group[lo]];
}

/* the pool's callback: chunk c of the plan */
static void chunk_work(void *arg, int c)
{
    par_plan *r = arg;
    const par_stage *s = chunk_group(r, c);
    if (s->nchunks == 1) { /* a stage or a group of stages that do not split */
        for (int i = (int)(s - r->stage); i <= s->last; i++) {
            run_range(r, r->stage[i].kind, r->stage[i].lo, r->stage[i].hi);
        }
        return;
    }
    const long long count = s->hi - s->lo;
    const int j = c - s->first;
    run_range(r, s->kind, s->lo + (int)(count * j / s->nchunks),
              s->lo + (int)(count * (j + 1) / s->nchunks));
}

/* d's pool (or its owner's), started on first use; NULL when d is serial or it cannot start */
static ctc_pool *data_pool(ctc_data *d)
{
    ctc_data *o = d->pool_owner ? d->pool_owner : d;
    if (o->threads < 2) return NULL;
    if (o->pool == NULL && !o->pool_failed) {
        o->pool = ctc_pool_new(o->threads);
        o->pool_failed = o->pool == NULL;
    }
    return o->pool;
}

/* the pass on the caller's thread: the same callbacks over whole ranges, in the same order */
static void run_serial(const ctc_model *m, ctc_data *d, const gdca_par_pass *pass)
{
    const int nodes = m->height_start[pass_heights(m, pass)];
    if (pass->bodies) pass->bodies(pass->ctx, 0, m->nbodies);
    set_singular(m, d, pass->assemble(pass->ctx, 0, nodes));
    pass->root(pass->ctx);
    pass->disassemble(pass->ctx, 0, nodes);
}

void gdca_par_run(const ctc_model *m, ctc_data *d, const gdca_par_pass *pass)
{
    const ctc_data *o = d->pool_owner ? d->pool_owner : d;
    if (o->threads > 1 && (d->opt.par_grain > 0 || m->nbodies >= pass->min_bodies)) {
        par_plan r = {.m = m, .d = d, .pass = pass, .nthreads = o->threads};
        r.grain = d->opt.par_grain > 0 ? d->opt.par_grain : pass->grain;
        if (r.grain < 1) r.grain = 1;
        atomic_init(&r.first_singular, INT_MAX);
        int chunks = plan_pass(&r);
        ctc_pool *pool = chunks > 1 ? data_pool(d) : NULL;
        if (pool != NULL) {
            const int split = !pass->gated || ctc_data_eval_split(d);
            if (split) {
                ctc_pool_job job = {r.ngroups, r.group_first, chunk_work, &r};
                ctc_pool_run(pool, &job);
            } else {
                run_serial(m, d, pass);
            }
            if (pass->gated) ctc_data_eval_pass_done(d);
            return;
        }
    }
    run_serial(m, d, pass);
}

/* gdca_par_bodies' job: chunk c is the bodies [n c / nchunks, n (c + 1) / nchunks) */
typedef struct bodies_job {
    void (*bodies)(void *ctx, int lo, int hi);
    void *ctx;
    long long n;
    int nchunks;
} bodies_job;

static void bodies_work(void *arg, int c)
{
    const bodies_job *b = arg;
    b->bodies(b->ctx, (int)(b->n * c / b->nchunks), (int)(b->n * (c + 1) / b->nchunks));
}

int gdca_par_bodies(const ctc_model *m, ctc_data *d, void (*bodies)(void *ctx, int lo, int hi),
                    void *ctx, int min_bodies)
{
    const ctc_data *o = d->pool_owner ? d->pool_owner : d;
    if (o->threads < 2 || m->nbodies < min_bodies || m->nbodies < o->threads) return 0;
    ctc_pool *pool = ctc_data_eval_split(d) ? data_pool(d) : NULL;
    if (pool != NULL) {
        bodies_job b = {bodies, ctx, m->nbodies, o->threads};
        const int first[2] = {0, b.nchunks};
        const ctc_pool_job job = {1, first, bodies_work, &b};
        ctc_pool_run(pool, &job);
    } else {
        bodies(ctx, 0, m->nbodies);
    }
    ctc_data_eval_pass_done(d);
    return 1;
}
