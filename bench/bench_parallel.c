/*
 * bench_parallel.c - the GDCA passes with each tree height split over threads (gdca_par.h,
 * ctc_data_set_threads) against the same passes on one thread, and what the threads' meeting
 * points cost.
 *
 * Three parts, each printed as a table:
 *   barrier   the pool's level barrier (pool.h), with 2 threads and with each count of
 *             CTC_BENCH_THREADS: a job of BARRIERS stages of one chunk of CHUNK_NS busy work
 *             per thread, each stage needing the one before, per stage, for several waiting
 *             policies (ctc_pool_set_wait), the default first; POSIX pthread_barrier_wait on as
 *             many plain threads (CHUNK_NS of work, then a crossing) for comparison; and one run
 *             of one stage on warm workers and on blocked ones (after 2 ms idle).
 *   grain     for each pass (GDCA forward, composite iGDCA), form and n = 64, 128, ..., 4096,
 *             on 2 threads: the time of one pass as the grain varies (d->opt.par_grain: a stage
 *             of c items is cut into at most c / grain chunks, and runs whole below 2; no least
 *             chain length), and serially. The grains that do best at the larger n, and the least n
 *             where a split beats the serial pass, are the thresholds written into
 *             gdca_forward.c and gdca_inverse.c.
 *   speed-up  planar rod chains and spatial revolute chains (the chains of bench_dynamics) of
 *             n = 64, 128, ..., max_n bodies: one GDCA forward pass, one composite iGDCA pass
 *             and one CTC right-hand side (kinematics + handles + iGDCA + GDCA; kinematics and
 *             handles stay serial), on 1 thread and on each count of CTC_BENCH_THREADS (default
 *             2), with the measured grains, the forward pass in the balanced tree's order;
 *             speed-up = time on 1 thread / time on k threads, from the same run. Each thread
 *             count has its own ctc_data (and pool). Beside them the forward pass and the CTC
 *             evaluation on 1 thread in the sequential order, which an unthreaded forward pass
 *             takes (gdca_forward_seq.h), and "vs seq" = that time / time on k threads: where
 *             the split tree beats it, the library may take the tree on threads. The split
 *             columns force the split (options.h par_split); a last table times one CTC
 *             evaluation with the library's defaults on each count, whose gate chooses between
 *             one thread and the split by measured cost (pool.h ctc_pool_gate), against one
 *             thread, with the gate's choice and the pass depth against log2 n; it is timed
 *             once the gate has decided (a simulation's steady state), and prints how many
 *             evaluations that took.
 *             The same speed-up table follows for Featherstone's autoTree (branching factors 2 and
 *             4, planar and spatial, n = 1024, 4096, 16384), whose plan (model.c) splits as the
 *             chains' tree does and whose sequential order is the tip runs (gdca_forward_tseq.c),
 *             with each tree's pass depth (the plan's height) beside log2 n.
 * Before timing, the results on k threads are checked bitwise against 1 thread; a mismatch ends
 * the run with status 1. Every timing of a case first runs round-robin for WARM_S. Batches of
 * all timings of one chain are interleaved, each batch starting one timing further on; each
 * timing runs untimed for SETTLE_S (at least once) before it is timed, so that the workers are
 * warm and the caches hold the timing's own data; the figures are medians over the batches.
 *
 * Usage: bench_parallel [max_n] [batches] [parts]     (default 65536, 11 and bgct)
 *        parts: any of b (barrier), g (grain), c (speed-up on chains), t (speed-up on trees)
 * Environment: CTC_BENCH_THREADS="2,4,8" thread counts beside 1 (default "2", each 2..64);
 *              CTC_BENCH_QUICK=1: max_n 4096 and 5 batches unless given;
 *              CTC_BENCH_MIN_N: the least n of the chains' speed-up table (default 64);
 *              CTC_BENCH_WAIT="spin_ns,block_ns": the waiting phases of the passes' pools
 *              (ctc_pool_set_wait; default: the pool's own).
 */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "chains.h"
#include "ctc.h"
#include "pool.h"

#define MAXK 8        /* thread counts beside 1 */
#define SETTLE_S 5e-3 /* s, untimed runs before each timing in a batch */
#define BATCH_S 2e-3  /* s, the least length of one timed batch of the slowest timing */
#define BARRIERS 4000 /* stages (or crossings) per barrier timing, in runs of up to 200 */
#define CHUNK_NS 1000 /* ns, the busy work of one chunk in the barrier timings */

#define IDLE_NS 2000000L /* ns between two runs of the blocked-start timing */
#define WARM_S                                                                                     \
    0.1 /* s, every timing of a new case round-robin before the batches: new                       \
           worker threads start on the caller's core and the scheduler takes                       \
           tens of milliseconds to spread them (seen on the 2-core machine) */

enum { P_FWD, P_INV, P_CTC, NP }; /* the passes timed */
static const char *const pass_names[NP] = {"GDCA fwd", "iGDCA", "ctc"};

static int nk = 1;                          /* thread counts beside 1 */
static long wait_spin = -1, wait_block = 0; /* CTC_BENCH_WAIT for the passes' pools */
static int kthreads[MAXK] = {2};            /* and the counts */

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double loadavg(void)
{
    double l = -1;
    FILE *f = fopen("/proc/loadavg", "r");
    if (f) {
        if (fscanf(f, "%lf", &l) != 1) l = -1;
        fclose(f);
    }
    return l;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

static volatile double sink;

/* ---- medians over interleaved batches ---- */

/* Medians (s per call) of ntim timings of run(ctx, w), w = 0..ntim-1: batches interleaved, each
 * timing settled for SETTLE_S (at least one call), reps calls per batch so that a batch of the
 * slowest timing lasts BATCH_S. */
static void measure(void (*run)(void *ctx, int w), void *ctx, int ntim, int batches, double *med)
{
    for (double t0 = now(); now() - t0 < WARM_S;) {
        for (int w = 0; w < ntim; w++) run(ctx, w);
    }
    int reps = 1;
    for (int w = 0; w < ntim; w++) { /* the slowest timing's calls per BATCH_S */
        double t0 = now();
        int calls = 0;
        while (now() - t0 < BATCH_S || calls < 1) {
            run(ctx, w);
            calls++;
        }
        if (w == 0 || calls < reps) reps = calls;
    }
    double *samples = malloc(sizeof(double) * (size_t)batches * (size_t)ntim);
    if (!samples) abort();
    for (int b = 0; b < batches; b++) {
        for (int i = 0; i < ntim; i++) {
            int w = (b + i) % ntim;
            double s = now();
            do {
                run(ctx, w);
            } while (now() - s < SETTLE_S);
            s = now();
            for (int r = 0; r < reps; r++) run(ctx, w);
            samples[w * batches + b] = (now() - s) / reps;
        }
    }
    for (int w = 0; w < ntim; w++) {
        qsort(samples + w * batches, (size_t)batches, sizeof(double), cmp_double);
        med[w] = samples[w * batches + batches / 2];
    }
    free(samples);
}

/* ---- the level barrier ---- */

/* waiting policies of the barrier table (ctc_pool_set_wait; spin -1: the pool's default) */
static const struct {
    const char *name;
    long spin_ns, block_ns;
} policies[] = {
    {"default (spin 5 us, block)", -1, 0},
    {"spin 5 us, yield to 100 us, block", 5000, 100000},
    {"spin 50 us, block", 50000, 50000},
    {"spin, never block", 1000000000L, -1},
    {"yield at once, block at 100 us", 0, 100000},
    {"block at once", 0, 0},
};
#define NPOL ((int)(sizeof policies / sizeof *policies))
enum { B_POSIX = NPOL, B_RUN_WARM, B_RUN_COLD, NB };

typedef struct barrier_case {
    ctc_pool *pool; /* its waiting phases set for each timing */
    int nthreads;
    int nstages;                        /* stages per run: BARRIERS / runs */
    int first[CTC_POOL_MAX_STAGES + 1]; /* stage s: chunks s nthreads .. (s + 1) nthreads - 1 */
    volatile double slot[CTC_MAX_THREADS * 8]; /* a chunk's result, a cache line apart */
    pthread_barrier_t posix;
    pthread_t *posix_threads;
    /* POSIX: the helpers wait on go_gen, then cross BARRIERS barriers with the caller */
    pthread_mutex_t lock;
    pthread_cond_t go;
    int go_gen, stop;
} barrier_case;

static long chunk_iters = 1000; /* busy-loop rounds of CHUNK_NS, calibrated in main */

static double busy(long iters)
{
    double x = 0;
    for (long i = 0; i < iters; i++) x = x * 0.999999 + 1e-9 * (double)i;
    return x;
}

static void calibrate_chunk(void)
{
    double best = 1e9;
    for (int r = 0; r < 5; r++) {
        double t = now();
        sink += busy(1000000);
        t = now() - t;
        if (t < best) best = t;
    }
    chunk_iters = (long)(1000000 * CHUNK_NS * 1e-9 / best);
    if (chunk_iters < 1) chunk_iters = 1;
}

static void stage_work(void *arg, int c)
{
    barrier_case *b = arg;
    b->slot[(c % b->nthreads) * 8] += busy(chunk_iters);
}

/* a POSIX helper thread's case and its index t (its result slot) */
typedef struct posix_arg {
    barrier_case *c;
    int t;
} posix_arg;

static void *posix_helper(void *arg)
{
    barrier_case *c = ((posix_arg *)arg)->c;
    const int t = ((posix_arg *)arg)->t;
    int seen = 0;
    for (;;) {
        pthread_mutex_lock(&c->lock);
        while (c->go_gen == seen && !c->stop) pthread_cond_wait(&c->go, &c->lock);
        seen = c->go_gen;
        int stop = c->stop;
        pthread_mutex_unlock(&c->lock);
        if (stop) return NULL;
        for (int i = 0; i < BARRIERS; i++) {
            c->slot[8 * t] += busy(chunk_iters);
            pthread_barrier_wait(&c->posix);
        }
    }
}

/* one timing of the barrier table: BARRIERS stages, or one run of one stage on warm workers */
static void run_barrier(void *arg, int w)
{
    barrier_case *c = arg;
    ctc_pool_job stages = {c->nstages, c->first, stage_work, c};
    ctc_pool_job one = {1, c->first, stage_work, c};
    if (w < NPOL) { /* a policy, then back to the pool's default */
        ctc_pool_set_wait(c->pool, policies[w].spin_ns, policies[w].block_ns);
        for (int r = 0; r < BARRIERS / c->nstages; r++) ctc_pool_run(c->pool, &stages);
        ctc_pool_set_wait(c->pool, -1, 0);
        return;
    }
    switch (w) {
    case B_POSIX:
        pthread_mutex_lock(&c->lock);
        c->go_gen++;
        pthread_cond_broadcast(&c->go);
        pthread_mutex_unlock(&c->lock);
        for (int i = 0; i < BARRIERS; i++) {
            c->slot[0] += busy(chunk_iters);
            pthread_barrier_wait(&c->posix);
        }
        break;
    default:
        ctc_pool_run(c->pool, &one);
        break;
    }
}

static void bench_barrier(int nthreads, int batches)
{
    barrier_case c = {.nthreads = nthreads};
    c.nstages = CTC_POOL_MAX_CHUNKS / nthreads;
    if (c.nstages > 200) c.nstages = 200; /* a divisor of BARRIERS */
    while (BARRIERS % c.nstages) c.nstages--;
    for (int st = 0; st <= c.nstages; st++) c.first[st] = st * nthreads;
    c.pool = ctc_pool_new(nthreads);
    if (!c.pool) abort();
    c.posix_threads = calloc((size_t)nthreads, sizeof *c.posix_threads);
    if (!c.posix_threads || pthread_barrier_init(&c.posix, NULL, (unsigned)nthreads) != 0 ||
        pthread_mutex_init(&c.lock, NULL) != 0 || pthread_cond_init(&c.go, NULL) != 0)
        abort();
    posix_arg args[CTC_MAX_THREADS];
    for (int t = 1; t < nthreads; t++) {
        args[t] = (posix_arg){&c, t};
        if (pthread_create(&c.posix_threads[t], NULL, posix_helper, &args[t]) != 0) abort();
    }

    double med[NB];
    measure(run_barrier, &c, B_RUN_COLD, batches, med); /* all but the cold start, below */

    /* the cold start: median of single one-stage runs, each after IDLE_NS idle (every worker
       has blocked by then) */
    ctc_pool_job one = {1, c.first, stage_work, &c};
    int runs = 2 * batches + 1;
    double *cold = malloc(sizeof(double) * (size_t)runs);
    if (!cold) abort();
    for (int r = 0; r < runs; r++) {
        struct timespec idle = {0, IDLE_NS};
        nanosleep(&idle, NULL);
        double t = now();
        ctc_pool_run(c.pool, &one);
        cold[r] = now() - t;
    }
    qsort(cold, (size_t)runs, sizeof(double), cmp_double);
    med[B_RUN_COLD] = cold[runs / 2];
    free(cold);

    for (int w = 0; w < NPOL; w++) {
        printf("| %7d | %-42s | %7.0f |\n", nthreads, policies[w].name, 1e9 * med[w] / BARRIERS);
    }
    printf("| %7d | %-42s | %7.0f |\n", nthreads, "pthread_barrier_wait (plain threads)",
           1e9 * med[B_POSIX] / BARRIERS);
    printf("| %7d | %-42s | %7.0f |\n", nthreads, "one run of one stage, warm",
           1e9 * med[B_RUN_WARM]);
    printf("| %7d | %-42s | %7.0f |\n", nthreads, "one run of one stage, after 2 ms idle",
           1e9 * med[B_RUN_COLD]);

    pthread_mutex_lock(&c.lock);
    c.stop = 1;
    pthread_cond_broadcast(&c.go);
    pthread_mutex_unlock(&c.lock);
    for (int t = 1; t < nthreads; t++) pthread_join(c.posix_threads[t], NULL);
    pthread_barrier_destroy(&c.posix);
    pthread_cond_destroy(&c.go);
    pthread_mutex_destroy(&c.lock);
    free(c.posix_threads);
    ctc_pool_free(c.pool);
}

/* ---- chains ---- */

typedef struct chain_case {
    const ctc_model *m;
    ctc_data *d[2 * MAXK + 2]; /* d[0] serial, d[i] on kthreads[i - 1] threads, all with the
                                  forward pass in the balanced tree's order and every pass
                                  split (options.h par_split); d[nk + 1] serial in the
                                  sequential order (gdca_forward_seq.h); d[nk + 1 + i] on
                                  kthreads[i - 1] threads with the library's defaults (the
                                  gate chooses: data.h ctc_eval_gate) */
    double *q, *v, *u;
    double *f[2 * MAXK + 2], *a[2 * MAXK + 2];
} chain_case;

static void run_pass(const ctc_model *m, ctc_data *d, int pass, const double *q, const double *v,
                     const double *u, double *f, double *a)
{
    switch (pass) {
    case P_FWD:
        ctc_gdca_forward(m, d, f, a);
        break;
    case P_INV:
        d->icomp_stamp = 0; /* a first pass at the state, as in bench_dynamics */
        ctc_gdca_inverse(m, d, u, f);
        break;
    default:
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_inverse(m, d, u, f);
        ctc_gdca_forward(m, d, f, a);
        break;
    }
}

/* timing w of the speed-up table: pass w % NP on data w / NP */
static void run_speedup(void *arg, int w)
{
    chain_case *c = arg;
    int k = w / NP;
    if (k == nk + 1 && w % NP == P_INV) return; /* the order is the forward pass's: not timed */
    if (k > nk + 1 && w % NP != P_CTC) return;  /* the defaults: one CTC evaluation only */
    run_pass(c->m, c->d[k], w % NP, c->q, c->v, c->u, c->f[k], c->a[k]);
    sink += c->a[k][0];
}

static ctc_model *build(const test_chain *chain)
{
    char err[256];
    ctc_model *m = NULL;
    if (ctc_model_build(&chain->spec, &m, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "bench_parallel: n = %d: %s\n", chain->spec.nbodies, err);
        exit(1);
    }
    return m;
}

/* a case with data on 1 thread (d[0]) and on threads[k - 1] threads (d[k], k = 1..nthreads), the
 * forward pass in the balanced tree's order, and on 1 thread in the sequential order
 * (d[nthreads + 1]); its state and results */
static chain_case *case_new(const ctc_model *m, const int *threads, int nthreads)
{
    const int ndata = 2 + 2 * nthreads;
    chain_case *c = calloc(1, sizeof *c);
    if (!c) abort();
    c->m = m;
    size_t nq = (size_t)m->nq, nv = (size_t)m->nv;
    c->q = calloc(nq, sizeof(double)), c->v = calloc(nv, sizeof(double));
    c->u = calloc(nv, sizeof(double));
    if (!c->q || !c->v || !c->u) abort();
    uint64_t rng = 11;
    test_random_state(m, &rng, 1.0, c->q, c->v);
    for (size_t i = 0; i < nv; i++) c->u[i] = test_uniform(&rng, -1, 1);
    for (int k = 0; k < ndata; k++) {
        c->d[k] = ctc_data_new(m);
        c->f[k] = calloc(nv, sizeof(double)), c->a[k] = calloc(nv, sizeof(double));
        if (!c->d[k] || !c->f[k] || !c->a[k]) abort();
        const int kt = k > 0 && k <= nthreads ? threads[k - 1]
                       : k > nthreads + 1     ? threads[k - nthreads - 2]
                                              : 1;
        if (kt > 1 && ctc_data_set_threads(c->d[k], kt, NULL, 0) != CTC_OK) abort();
        if (k <= nthreads + 1) {
            c->d[k]->opt.fwd_order = k <= nthreads ? CTC_ORDER_TREE : CTC_ORDER_SEQ;
            c->d[k]->opt.par_split = 1;
        }
    }
    return c;
}

static void case_free(chain_case *c)
{
    for (int k = 0; k < 2 * MAXK + 2; k++) {
        ctc_data_free(c->d[k]);
        free(c->f[k]), free(c->a[k]);
    }
    free(c->q), free(c->v), free(c->u);
    free(c);
}

/* the results of data k against data 0, bitwise, after a CTC evaluation; 0 when equal */
static int check_bitwise(chain_case *c, int k)
{
    const ctc_model *m = c->m;
    run_pass(m, c->d[0], P_CTC, c->q, c->v, c->u, c->f[0], c->a[0]);
    run_pass(m, c->d[k], P_CTC, c->q, c->v, c->u, c->f[k], c->a[k]);
    size_t nv = (size_t)m->nv * sizeof(double);
    return memcmp(c->f[0], c->f[k], nv) != 0 || memcmp(c->a[0], c->a[k], nv) != 0;
}

/* ---- the grain sweep ---- */

static const int sweep[] = {1, 2, 4, 8, 16, 32, 64, 128, 0}; /* 0: serial */
#define NSWEEP ((int)(sizeof sweep / sizeof *sweep))

typedef struct sweep_case {
    chain_case *c;
    int pass;
} sweep_case;

static void run_sweep(void *arg, int w)
{
    sweep_case *s = arg;
    chain_case *c = s->c;
    ctc_data *d = c->d[1];
    d->opt.par_grain = sweep[w] ? sweep[w] : c->m->nbodies; /* a grain of n splits nothing */
    run_pass(c->m, d, s->pass, c->q, c->v, c->u, c->f[1], c->a[1]);
    sink += c->a[1][0] + c->f[1][0];
}

static void bench_sweep(const char *label, test_chain *chain, int batches)
{
    ctc_model *m = build(chain);
    static const int two[1] = {2};
    chain_case *c = case_new(m, two, 1);
    c->d[1]->opt.par_grain = 1; /* so that the pool starts */
    run_pass(m, c->d[1], P_CTC, c->q, c->v, c->u, c->f[1], c->a[1]);
    if (c->d[1]->pool) ctc_pool_set_wait(c->d[1]->pool, wait_spin, wait_block);
    for (int pass = P_FWD; pass <= P_INV; pass++) {
        sweep_case s = {c, pass};
        double med[NSWEEP];
        measure(run_sweep, &s, NSWEEP, batches, med);
        int best = 0;
        for (int g = 1; g < NSWEEP; g++)
            if (med[g] < med[best]) best = g;
        printf("| %-7s | %5d | %-8s |", label, m->nbodies, pass_names[pass]);
        for (int g = 0; g < NSWEEP; g++) printf(" %8.1f |", 1e6 * med[g]);
        if (sweep[best])
            printf(" %4d |\n", sweep[best]);
        else
            printf(" serial |\n");
    }
    case_free(c);
    ctc_model_free(m);
}

/* ---- the speed-up table ---- */

#define MAXROWS 32

typedef struct speed_row {
    char label[8];
    int n;
    int height;                 /* the depth of the split passes: the plan's height (model.h) */
    double t[2 * MAXK + 2][NP]; /* s per call: 1 thread, each count, 1 thread sequential, each
                                   count with the defaults (ctc only) */
    int way[MAXK];              /* the defaults' choice on each count (gate_state) */
    int settle[MAXK];           /* the CTC evaluations on each count until its gate had decided */
} speed_row;

/* the evaluation gate's state for the table: -2 never used (no pass had a split to weigh: the
   chain is too short to cut), -1 measuring, 0 alone, 1 split */
static int gate_state(const ctc_pool_gate *g)
{
    if (g->decided) return g->way;
    return g->runs == 0 && g->nt[0] == 0 && g->nt[1] == 0 ? -2 : -1;
}

/* Runs CTC evaluations on the defaults' data of count k (kthreads[k]) until its evaluation gate
 * (data.h ctc_eval_gate) is not measuring, so that the table times the library's steady state (a
 * simulation evaluates thousands of right-hand sides; the gate decides after its blocks give
 * CTC_POOL_GATE_SAMPLES timings of each way, 18 evaluations, each recorded when the next one
 * starts: pool.h); returns the evaluations it took, at most SETTLE_MAX_CALLS */
#define SETTLE_MAX_CALLS 200
static int settle_gates(chain_case *c, int k)
{
    ctc_data *d = c->d[nk + 2 + k];
    for (int calls = 0; calls < SETTLE_MAX_CALLS; calls++) {
        if (calls > 1 && gate_state(&d->eval.gate) != -1) return calls;
        run_speedup(c, (nk + 2 + k) * NP + P_CTC);
    }
    return SETTLE_MAX_CALLS;
}

static int bench_speedup(const char *label, test_chain *chain, int batches, speed_row *row)
{
    ctc_model *m = build(chain);
    chain_case *c = case_new(m, kthreads, nk);
    int failed = 0;
    for (int k = 1; k <= nk; k++) {
        if (check_bitwise(c, k)) {
            fprintf(stderr, "bench_parallel: %s n = %d: %d threads change the results\n", label,
                    m->nbodies, kthreads[k - 1]);
            failed = 1;
        }
    }
    for (int k = 1; k <= nk; k++)
        if (c->d[k]->pool) ctc_pool_set_wait(c->d[k]->pool, wait_spin, wait_block);
    for (int k = 0; k < nk; k++) row->settle[k] = settle_gates(c, k);
    double med[(2 * MAXK + 2) * NP];
    measure(run_speedup, c, (2 + 2 * nk) * NP, batches, med);
    for (int k = 0; k < nk; k++) {
        row->way[k] = gate_state(&c->d[nk + 2 + k]->eval.gate);
    }
    for (int k = nk + 2; k < 2 * nk + 2; k++) row->t[k][P_CTC] = med[k * NP + P_CTC];
    snprintf(row->label, sizeof row->label, "%s", label);
    row->n = m->nbodies;
    row->height = m->height;
    for (int k = 0; k <= nk; k++)
        for (int p = 0; p < NP; p++) row->t[k][p] = med[k * NP + p];
    for (int p = 0; p < NP; p++) row->t[nk + 1][p] = med[(nk + 1) * NP + p];
    case_free(c);
    ctc_model_free(m);
    return failed;
}

/* the sequential order is a forward-pass setting: the iGDCA pass has no column of it */
static int has_seq(int p)
{
    return p != P_INV;
}

/* where k threads start to pay: the least n of chain label from which every larger n of the
   table runs at least 5% faster on k threads than on 1 (the tree on 1 thread, or seq = 1: the
   sequential order) */
static void print_pays(const speed_row *rows, int nrows, int k, int p, const char *label, int seq)
{
    int from = -1;
    for (int i = nrows - 1; i >= 0; i--) {
        if (strcmp(rows[i].label, label) != 0) continue;
        if (rows[i].t[seq ? nk + 1 : 0][p] >= 1.05 * rows[i].t[k][p])
            from = rows[i].n;
        else
            break;
    }
    printf("- %d threads, %s, %s, against %s: ", kthreads[k - 1], pass_names[p], label,
           seq ? "the sequential order" : "the tree on 1 thread");
    if (from > 0)
        printf("n >= %d\n", from);
    else
        printf("none in the table\n");
}

/* the speed-up table; trees = 1 adds each row's pass depth (the plan's height) and log2 n, and
   leaves out where threads pay (the library's thresholds are the chains') */
static void print_speedup(const speed_row *rows, int nrows, int trees)
{
    printf("| chain   |     n |");
    if (trees) printf(" height | log2 n |");
    for (int p = 0; p < NP; p++) {
        printf(" %s 1T (us) |", pass_names[p]);
        for (int k = 0; k < nk; k++) printf(" %dT (us) | speed-up |", kthreads[k]);
        if (has_seq(p)) {
            printf(" %s 1T seq (us) |", pass_names[p]);
            for (int k = 0; k < nk; k++) printf(" %dT vs seq |", kthreads[k]);
        }
    }
    printf("\n| ------- | ----: |");
    if (trees) printf(" -----: | -----: |");
    for (int p = 0; p < NP; p++) {
        printf(" ---------: |");
        for (int k = 0; k < nk; k++) printf(" --------: | ----: |");
        if (has_seq(p)) {
            printf(" ---------: |");
            for (int k = 0; k < nk; k++) printf(" ----: |");
        }
    }
    printf("\n");
    for (int i = 0; i < nrows; i++) {
        const speed_row *r = &rows[i];
        printf("| %-7s | %5d |", r->label, r->n);
        if (trees) printf(" %6d | %6.1f |", r->height, log2((double)r->n));
        for (int p = 0; p < NP; p++) {
            printf(" %10.1f |", 1e6 * r->t[0][p]);
            for (int k = 1; k <= nk; k++) {
                printf(" %9.1f | %5.2f |", 1e6 * r->t[k][p], r->t[0][p] / r->t[k][p]);
            }
            if (has_seq(p)) {
                printf(" %10.1f |", 1e6 * r->t[nk + 1][p]);
                for (int k = 1; k <= nk; k++) printf(" %5.2f |", r->t[nk + 1][p] / r->t[k][p]);
            }
        }
        printf("\n");
    }
    if (trees) return;

    printf("\nThe least n from which every larger n of the table runs at least 5%% faster on k "
           "threads (the tree) than on 1 thread:\n\n");
    for (int k = 1; k <= nk; k++) {
        for (int p = 0; p < NP; p++) {
            for (int seq = 0; seq <= has_seq(p); seq++) {
                print_pays(rows, nrows, k, p, "planar", seq);
                print_pays(rows, nrows, k, p, "spatial", seq);
            }
        }
    }
}

/* the library's defaults on k threads against one thread (the sequential order): one CTC
   evaluation, with the gate's choice and the pass depth (the plan's height) beside log2 n */
static void print_defaults(const speed_row *rows, int nrows)
{
    static const char *const way_names[] = {"unused", "measuring", "alone", "split"};
    printf("| chain   |     n | height | log2 n | ctc 1T seq (us) |");
    for (int k = 0; k < nk; k++)
        printf(" %dT auto (us) | 1T / %dT | way | settled |", kthreads[k], kthreads[k]);
    printf("\n| ------- | ----: | -----: | -----: | --------: |");
    for (int k = 0; k < nk; k++) printf(" ------: | ----: | ---- | ---: |");
    printf("\n");
    for (int i = 0; i < nrows; i++) {
        const speed_row *r = &rows[i];
        printf("| %-7s | %5d | %6d | %6.1f | %9.1f |", r->label, r->n, r->height,
               log2((double)r->n), 1e6 * r->t[nk + 1][P_CTC]);
        for (int k = 0; k < nk; k++) {
            double t = r->t[nk + 2 + k][P_CTC];
            printf(" %7.1f | %5.2f | %s | %4d |", 1e6 * t, r->t[nk + 1][P_CTC] / t,
                   way_names[r->way[k] + 2], r->settle[k]);
        }
        printf("\n");
    }
}

/* ---- main ---- */

/* CTC_BENCH_THREADS: a comma-separated list of thread counts 2..64 */
static void parse_threads(const char *s)
{
    if (!s || !*s) return;
    nk = 0;
    while (*s && nk < MAXK) {
        char *end;
        long k = strtol(s, &end, 10);
        if (end == s || k < 2 || k > CTC_MAX_THREADS) {
            fprintf(stderr,
                    "bench_parallel: CTC_BENCH_THREADS: thread counts 2..%d, e.g. "
                    "\"2,4,8\"\n",
                    CTC_MAX_THREADS);
            exit(2);
        }
        kthreads[nk++] = (int)k;
        s = *end == ',' ? end + 1 : end;
        if (*end && *end != ',') break;
    }
    if (nk == 0) nk = 1, kthreads[0] = 2;
}

int main(int argc, char **argv)
{
    const char *quick = getenv("CTC_BENCH_QUICK");
    int is_quick = quick && *quick && strcmp(quick, "0") != 0;
    int max_n = argc > 1 ? atoi(argv[1]) : is_quick ? 4096 : 65536;
    const char *min_env = getenv("CTC_BENCH_MIN_N");
    int min_n = min_env ? atoi(min_env) : 64;
    if (min_n < 64) min_n = 64;
    int batches = argc > 2 ? atoi(argv[2]) : is_quick ? 5 : 11;
    const char *parts = argc > 3 ? argv[3] : "bgct";
    if (max_n < 64 || batches < 1 || !*parts || strspn(parts, "bgct") != strlen(parts)) {
        fprintf(stderr, "usage: bench_parallel [max_n >= 64] [batches >= 1] [parts: any of "
                        "b g c t]\n");
        return 2;
    }
    parse_threads(getenv("CTC_BENCH_THREADS"));
    const char *wait = getenv("CTC_BENCH_WAIT");
    if (wait && sscanf(wait, "%ld,%ld", &wait_spin, &wait_block) != 2) {
        fprintf(stderr,
                "bench_parallel: CTC_BENCH_WAIT: \"spin_ns,block_ns\", e.g. \"5000,5000\"\n");
        return 2;
    }
    double load0 = loadavg(), t0 = now();
    printf("GDCA passes split over threads. Medians of %d interleaved batches. Load average at the "
           "start: %.2f. Waiting of the passes' pools: %s.\n\n",
           batches, load0, wait ? wait : "default");

    speed_row rows[MAXROWS];
    int failed = 0;
    if (strchr(parts, 'b')) {
        calibrate_chunk();
        printf(
            "Level barrier: ns per stage of one %d ns chunk per thread, each stage waiting for the "
            "one before (pthread_barrier: %d ns of work, then a crossing), and one run of one "
            "stage (ns); %d ns is the ideal:\n\n",
            CHUNK_NS, CHUNK_NS, CHUNK_NS);
        printf("| threads | waiting | ns per stage |\n| ------: | ------- | -----------: |\n");
        bench_barrier(2, batches);
        for (int k = 0; k < nk; k++)
            if (kthreads[k] != 2) bench_barrier(kthreads[k], batches);
    }
    if (strchr(parts, 'g')) {
        printf("\nGrain sweep, 2 threads: one pass (us) as the grain varies, and the best:\n\n");
        printf("| chain   |     n | pass     |");
        for (int g = 0; g < NSWEEP; g++) {
            if (sweep[g])
                printf(" %8d |", sweep[g]);
            else
                printf("   serial |");
        }
        printf(" best |\n| ------- | ----: | -------- |");
        for (int g = 0; g < NSWEEP; g++) printf(" -------: |");
        printf(" ---: |\n");
        static const int sweep_n[] = {64, 128, 256, 512, 1024, 2048, 4096};
        for (int form = 0; form < 2; form++) {
            for (int i = 0; i < 7 && sweep_n[i] <= max_n; i++) {
                test_chain *c =
                    form ? test_chain_random_spatial(sweep_n[i], 7, 1u << CTC_JOINT_REVOLUTE)
                         : test_chain_random_planar(sweep_n[i], 7, 0, 1);
                bench_sweep(form ? "spatial" : "planar", c, batches);
                test_chain_free(c);
            }
        }
    }
    if (strchr(parts, 'c')) {
        int nrows = 0;
        printf(
            "\nOne pass and one CTC right-hand side on 1 thread and on k threads (us), speed-up = "
            "1 thread / k threads:\n\n");
        for (int form = 0; form < 2; form++) {
            for (int n = min_n; n <= max_n && nrows < MAXROWS; n *= 2) {
                test_chain *c = form ? test_chain_random_spatial(n, 7, 1u << CTC_JOINT_REVOLUTE)
                                     : test_chain_random_planar(n, 7, 0, 1);
                failed |= bench_speedup(form ? "spatial" : "planar", c, batches, &rows[nrows++]);
                test_chain_free(c);
            }
        }
        print_speedup(rows, nrows, 0);
        printf("\nThe library's defaults on k threads (the evaluation gate times whole "
               "evaluations with every pass alone and with every pass split, then takes the "
               "faster: data.h ctc_eval_gate) against 1 thread (the sequential order), one CTC "
               "right-hand side, once the gate has decided (settled: the evaluations that took); "
               "its way (unused: no pass had a split to weigh), and the split passes' depth (the "
               "tree's height) beside log2 n:\n\n");
        print_defaults(rows, nrows);
    }
    if (strchr(parts, 't')) {
        printf("\nThe same on Featherstone's autoTree (taper 1; pl: planar, no skew; sp: spatial, "
               "skew 0.5 rad; bf: branching factor): the plan split over threads against the plan "
               "and the sequential tip runs on 1 thread:\n\n");
        int nrows = 0;
        for (int form = 0; form < 2; form++) {
            for (int bf = 2; bf <= 4; bf += 2) {
                for (int n = 1024; n <= max_n && n <= 16384 && nrows < MAXROWS; n *= 4) {
                    char label[8];
                    snprintf(label, sizeof label, "%s bf%d", form ? "sp" : "pl", bf);
                    test_chain *c = test_auto_tree(n, bf, form ? 0.5 : 0.0, 1.0);
                    failed |= bench_speedup(label, c, batches, &rows[nrows++]);
                    test_chain_free(c);
                }
            }
        }
        print_speedup(rows, nrows, 1);
    }
    printf("\nLoad average at the end: %.2f; %.0f s in all.\n", loadavg(), now() - t0);
    if (failed) return 1;
    return sink == 12345.678 ? 1 : 0;
}
