/*
 * gdca_par.c - the stage schedule of a GDCA pass over the assembly tree, serial or split over the
 * threads of the data's pool (gdca_par.h).
 *
 * Every thread walks the same list of stages (bodies, assembly heights 1..H, root, disassembly
 * heights H..1) and decides the same way, from the stage's size alone, whether the stage is
 * split and where the barriers go, so the threads meet at every barrier the same number of times
 * without talking to each other. A split stage of c items over u threads gives thread t the
 * items [c t / u, c (t + 1) / u) of its range: contiguous, so that a thread's nodes at one height
 * mostly read the records its own nodes wrote at the height below (the nodes of one height are
 * stored left to right along the chain).
 */
#include "gdca_par.h"

#include "pool.h"

enum { STAGE_BODIES, STAGE_ASSEMBLE, STAGE_ROOT, STAGE_DISASSEMBLE };

typedef struct par_region {
    const ctc_model *m;
    ctc_data *d;
    const gdca_par_pass *pass;
    ctc_pool *pool; /* NULL: serial */
    int nthreads;
    int grain;
    int first[CTC_MAX_THREADS]; /* per thread: the first tree index with a singular joint, or -1 */
} par_region;

/* the threads a stage of count items uses (< 2: serial) */
static int stage_threads(const par_region *r, int count)
{
    int u = count / r->grain;
    return u < r->nthreads ? u : r->nthreads;
}

/* d->singular_joint from the assembly's first singular tree index over all threads */
static void reduce_singular(const par_region *r)
{
    int first = -1;
    for (int t = 0; t < r->nthreads; t++) {
        if (r->first[t] >= 0 && (first < 0 || r->first[t] < first)) first = r->first[t];
    }
    r->d->singular_joint = first >= 0 ? r->m->tree[first].joint : -1;
}

static void run_range(par_region *r, int tid, int kind, int lo, int hi)
{
    const gdca_par_pass *p = r->pass;
    switch (kind) {
    case STAGE_BODIES:
        p->bodies(p->ctx, lo, hi);
        break;
    case STAGE_ASSEMBLE: {
        int f = p->assemble(p->ctx, lo, hi);
        if (f >= 0 && (r->first[tid] < 0 || f < r->first[tid])) r->first[tid] = f;
        break;
    }
    case STAGE_ROOT:
        reduce_singular(r);
        p->root(p->ctx);
        break;
    default:
        p->disassemble(p->ctx, lo, hi);
        break;
    }
}

/* One stage in thread tid. *prev says whether the previous stage was split (-1: none before):
 * the threads meet at a barrier first when this stage or that one is split. */
static void run_stage(par_region *r, int tid, int kind, int lo, int hi, int *prev)
{
    const int c = hi - lo, u = kind == STAGE_ROOT ? 1 : stage_threads(r, c);
    const int split = u > 1;
    if (*prev >= 0 && (split || *prev)) ctc_pool_barrier(r->pool);
    *prev = split;
    if (split) {
        if (tid < u) {
            run_range(r, tid, kind, lo + (int)((long long)c * tid / u),
                      lo + (int)((long long)c * (tid + 1) / u));
        }
    } else if (tid == 0 && c > 0) {
        run_range(r, tid, kind, lo, hi);
    }
}

/* the whole pass in thread tid (the job of a pool run) */
static void run_region(void *arg, int tid)
{
    par_region *r = arg;
    const ctc_model *m = r->m;
    const int *hs = m->height_start;
    int prev = -1;
    if (r->pass->bodies) run_stage(r, tid, STAGE_BODIES, 0, m->nbodies, &prev);
    for (int h = 1; h <= m->height; h++) run_stage(r, tid, STAGE_ASSEMBLE, hs[h - 1], hs[h], &prev);
    run_stage(r, tid, STAGE_ROOT, 0, 1, &prev);
    for (int h = m->height; h >= 1; h--) {
        run_stage(r, tid, STAGE_DISASSEMBLE, hs[h - 1], hs[h], &prev);
    }
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

void gdca_par_run(const ctc_model *m, ctc_data *d, const gdca_par_pass *pass)
{
    const ctc_data *o = d->pool_owner ? d->pool_owner : d;
    par_region r = {.m = m, .d = d, .pass = pass, .nthreads = o->threads};
    r.grain = d->par_grain > 0 ? d->par_grain : pass->grain;
    if (r.grain < 1) r.grain = 1;
    for (int t = 0; t < CTC_MAX_THREADS; t++) r.first[t] = -1;

    /* split only when some stage is large enough: the largest are the bodies and height 1 */
    int split = 0;
    if (r.nthreads > 1) {
        split = pass->bodies && stage_threads(&r, m->nbodies) > 1;
        for (int h = 1; h <= m->height && !split; h++) {
            split = stage_threads(&r, m->height_start[h] - m->height_start[h - 1]) > 1;
        }
    }
    if (split) r.pool = data_pool(d);
    if (r.pool != NULL) {
        r.nthreads = ctc_pool_threads(r.pool);
        ctc_pool_run(r.pool, run_region, &r);
        return;
    }

    /* serial: the same callbacks over whole ranges, in the same order */
    if (pass->bodies) pass->bodies(pass->ctx, 0, m->nbodies);
    r.first[0] = pass->assemble(pass->ctx, 0, m->ntree);
    r.nthreads = 1;
    reduce_singular(&r);
    pass->root(pass->ctx);
    pass->disassemble(pass->ctx, 0, m->ntree);
}
