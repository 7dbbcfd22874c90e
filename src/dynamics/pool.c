/*
 * pool.c - the persistent thread team of pool.h: POSIX threads, C11 atomics, chunks claimed by
 * generation-tagged flags, and spin-yield-block waiting.
 *
 * Counters and flags. run_gen advances once per ctc_pool_run; an idle worker that has seen run
 * g waits for g + 1. Each chunk has a claim flag: the caller sets flag[i] = 2 g for the chunks
 * of run g before it publishes g in run_gen, and a thread claims chunk i of run g by a
 * compare-and-swap from 2 g to 2 g + 1. A worker that still holds an older generation can
 * therefore never claim a chunk of a newer run (every chunk of its own run was claimed before
 * that run ended). done counts the chunks finished in the current run; a chunk of a stage
 * waits until done reaches the stage's first chunk, and the caller returns when done reaches
 * the number of chunks. Claims of a stage are only tried after every chunk of the stages before
 * was claimed, so the done chunks are always all the chunks of the earlier stages plus some of
 * the current one: done >= first chunk of a stage means the earlier stages are done.
 *
 * Memory order: the job's work and ctx are plain fields; the caller writes them before it
 * publishes the run, and a worker reads them only after a claim of that run succeeded, hence
 * while the caller still waits for its chunk; they are rewritten only after every chunk is done.
 * The stage table is atomic because a late worker may read it while the next run rewrites it
 * (what it reads then only leads to failed claims). A chunk's writes are released by its
 * increment of done and acquired by whoever waits for done. The operations are sequentially
 * consistent where the blocking handshake needs it.
 *
 * Blocking: a waiter first counts itself in sleepers, then takes the mutex and re-checks its
 * condition before waiting on the condition variable; whoever advances a counter first advances
 * it, then reads sleepers and broadcasts under the mutex only if it is non-zero. Either the
 * releaser sees the sleeper (and the broadcast reaches it, the re-check being under the same
 * mutex) or the sleeper sees the new value; no wake-up is lost, and while nobody sleeps no
 * system call is made.
 */
#include "pool.h"

#include <pthread.h>
#include <sched.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#define CACHE_LINE 64
#define GRACE_NS 2000 /* ns a thread leaves an unclaimed chunk to its owner once it could start */
#define OVERSUBSCRIBED_YIELD_NS 100000 /* ns an oversubscribed pool yields before it blocks */

struct ctc_pool {
    alignas(CACHE_LINE) atomic_ulong done;    /* chunks done in the current run */
    alignas(CACHE_LINE) atomic_ulong run_gen; /* runs started */
    alignas(CACHE_LINE) atomic_int sleepers;  /* threads blocked */
    atomic_int stop;                          /* 1: workers exit at the next run */
    atomic_long spin_ns, block_ns;            /* the waiting phases */
    long spin_default, block_default;         /* the phases of a new pool */
    int nthreads;
    /* the current run's job: work and ctx valid while one of its chunks is claimed */
    void (*work)(void *ctx, int chunk);
    void *ctx;
    atomic_int nstages;
    atomic_int stage_first[CTC_POOL_MAX_STAGES + 1];
    atomic_ullong *flags;   /* (CTC_POOL_MAX_CHUNKS) 2 gen (unclaimed in run gen) or 2 gen + 1 */
    struct pool_seen *seen; /* (nthreads) the run each thread has joined */
    pthread_mutex_t lock;
    pthread_cond_t wake;      /* broadcast when a counter advances and someone sleeps */
    pthread_t *workers;       /* (nthreads - 1) */
    struct pool_worker *args; /* (nthreads - 1) */
};

/* the last run a thread has joined, on a cache line of its own */
struct pool_seen {
    alignas(CACHE_LINE) atomic_ulong gen;
};

/* a worker's argument: its pool and its thread number 1..nthreads-1 */
struct pool_worker {
    ctc_pool *pool;
    int tid;
};

/* the CPU's hint that this is a spin-wait loop */
static inline void cpu_relax(void)
{
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__))
    __builtin_ia32_pause();
#elif defined(__GNUC__) && defined(__aarch64__)
    __asm__ __volatile__("yield");
#endif
}

static long long now_ns(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (long long)ts.tv_sec * 1000000000LL + ts.tv_nsec;
}

/* Waits until *x >= target, or until a run other than gen has started (gen 0: no such
 * condition): pause-spin, yield-spin, then block (pool.h). */
static void wait_until(ctc_pool *p, atomic_ulong *x, unsigned long target, unsigned long gen)
{
    long long t0 = 0;
    int yielding = 0;
    for (unsigned i = 1;; i++) {
        if (atomic_load(x) >= target || (gen && atomic_load(&p->run_gen) != gen)) return;
        if (!yielding) {
            cpu_relax();
            if ((i & 31) != 0) continue; /* the clock is read every 32 rounds */
            long long t = now_ns();
            if (t0 == 0) t0 = t;
            yielding = t - t0 >= atomic_load_explicit(&p->spin_ns, memory_order_relaxed);
        } else {
            long block = atomic_load_explicit(&p->block_ns, memory_order_relaxed);
            if (block >= 0 && now_ns() - t0 >= block) break;
            sched_yield();
        }
    }
    atomic_fetch_add(&p->sleepers, 1);
    pthread_mutex_lock(&p->lock);
    while (atomic_load(x) < target && !(gen && atomic_load(&p->run_gen) != gen)) {
        pthread_cond_wait(&p->wake, &p->lock);
    }
    pthread_mutex_unlock(&p->lock);
    atomic_fetch_sub(&p->sleepers, 1);
}

/* wakes the blocked threads, if any, after a counter advanced */
static void wake_sleepers(ctc_pool *p)
{
    if (atomic_load(&p->sleepers) > 0) {
        pthread_mutex_lock(&p->lock);
        pthread_cond_broadcast(&p->wake);
        pthread_mutex_unlock(&p->lock);
    }
}

/* claims chunk i of the run whose flags read 2 gen when unclaimed */
static int try_claim(ctc_pool *p, int i, unsigned long long unclaimed)
{
    unsigned long long v = unclaimed;
    return atomic_load(&p->flags[i]) == unclaimed &&
           atomic_compare_exchange_strong(&p->flags[i], &v, unclaimed + 1);
}

/* runs claimed chunk i of a stage that starts at chunk first */
static void run_chunk(ctc_pool *p, int i, int first)
{
    if (first > 0) wait_until(p, &p->done, (unsigned long)first, 0);
    p->work(p->ctx, i);
    atomic_fetch_add(&p->done, 1);
    wake_sleepers(p);
}

/* Thread tid's part of run gen: in each stage its own chunks, then the ones their late owners
 * leave unclaimed; returns at the end of the stages, or as soon as it sees another run's. */
static void run_stages(ctc_pool *p, unsigned long gen, int tid)
{
    const unsigned long long unclaimed = 2ULL * gen;
    const int nthreads = p->nthreads, nstages = atomic_load(&p->nstages);
    atomic_store(&p->seen[tid].gen, gen);
    if (nstages < 0 || nstages > CTC_POOL_MAX_STAGES) return; /* another run's table */
    for (int s = 0; s < nstages; s++) {
        const int a = atomic_load(&p->stage_first[s]), b = atomic_load(&p->stage_first[s + 1]);
        if (a < 0 || b < a || b > CTC_POOL_MAX_CHUNKS) return; /* another run's table */
        const int m = b - a;
        /* my chunks: j with j nthreads / m == tid */
        const int j0 = (tid * m + nthreads - 1) / nthreads;
        const int j1 = ((tid + 1) * m + nthreads - 1) / nthreads;
        for (int j = j0; j < j1; j++) {
            if (try_claim(p, a + j, unclaimed)) run_chunk(p, a + j, a);
        }
        /* the others', once the stage could start, and after GRACE_NS if their owner has
           joined the run (it is then most likely just finishing its chunk before) */
        for (int d = 1; d < m + 1 && m > j1 - j0; d++) {
            const int j = (j1 - 1 + d + m) % m;
            if (j >= j0 && j < j1) continue;
            if (atomic_load(&p->flags[a + j]) != unclaimed) continue;
            if (a > 0) wait_until(p, &p->done, (unsigned long)a, gen);
            if (atomic_load(&p->seen[j * nthreads / m].gen) == (unsigned long)gen) {
                long long t0 = now_ns();
                while (atomic_load(&p->flags[a + j]) == unclaimed && now_ns() - t0 < GRACE_NS) {
                    cpu_relax();
                }
            }
            if (try_claim(p, a + j, unclaimed)) run_chunk(p, a + j, a);
        }
        if (atomic_load(&p->run_gen) != gen) return;
    }
}

static void *worker_main(void *arg)
{
    const struct pool_worker *w = arg;
    ctc_pool *p = w->pool;
    unsigned long seen = 0; /* the last run seen */
    for (;;) {
        wait_until(p, &p->run_gen, seen + 1, 0);
        seen = atomic_load(&p->run_gen);
        if (atomic_load(&p->stop)) return NULL;
        run_stages(p, seen, w->tid);
    }
}

ctc_pool *ctc_pool_new(int nthreads)
{
    if (nthreads < 2 || nthreads > CTC_MAX_THREADS) return NULL;
    size_t size = (sizeof(ctc_pool) + CACHE_LINE - 1) / CACHE_LINE * CACHE_LINE;
    ctc_pool *p = aligned_alloc(CACHE_LINE, size);
    if (p == NULL) return NULL;
    memset(p, 0, size);
    atomic_init(&p->done, 0);
    atomic_init(&p->run_gen, 0);
    atomic_init(&p->sleepers, 0);
    atomic_init(&p->stop, 0);
    atomic_init(&p->nstages, 0);
    for (int i = 0; i <= CTC_POOL_MAX_STAGES; i++) atomic_init(&p->stage_first[i], 0);
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    int oversubscribed = ncpu > 0 && nthreads > ncpu;
    p->spin_default = oversubscribed ? 0 : CTC_POOL_SPIN_NS;
    p->block_default = oversubscribed ? OVERSUBSCRIBED_YIELD_NS : CTC_POOL_BLOCK_NS;
    atomic_init(&p->spin_ns, p->spin_default);
    atomic_init(&p->block_ns, p->block_default);
    p->nthreads = nthreads;
    p->workers = calloc((size_t)nthreads - 1, sizeof *p->workers);
    p->args = calloc((size_t)nthreads - 1, sizeof *p->args);
    p->flags = calloc(CTC_POOL_MAX_CHUNKS, sizeof *p->flags);
    p->seen = aligned_alloc(CACHE_LINE, (size_t)nthreads * sizeof *p->seen);
    if (p->workers == NULL || p->args == NULL || p->flags == NULL || p->seen == NULL)
        goto fail_alloc;
    for (int t = 0; t < nthreads; t++) atomic_init(&p->seen[t].gen, 0);
    for (int i = 0; i < CTC_POOL_MAX_CHUNKS; i++) atomic_init(&p->flags[i], 1); /* run 0: claimed */
    if (pthread_mutex_init(&p->lock, NULL) != 0) goto fail_alloc;
    if (pthread_cond_init(&p->wake, NULL) != 0) {
        pthread_mutex_destroy(&p->lock);
        goto fail_alloc;
    }
    for (int t = 1; t < nthreads; t++) {
        p->args[t - 1] = (struct pool_worker){p, t};
        if (pthread_create(&p->workers[t - 1], NULL, worker_main, &p->args[t - 1]) != 0) {
            p->nthreads = t; /* the ones started */
            ctc_pool_free(p);
            return NULL;
        }
    }
    return p;

fail_alloc:
    free(p->workers);
    free(p->args);
    free(p->flags);
    free(p->seen);
    free(p);
    return NULL;
}

void ctc_pool_free(ctc_pool *p)
{
    if (p == NULL) return;
    atomic_store(&p->stop, 1);
    atomic_fetch_add(&p->run_gen, 1);
    wake_sleepers(p);
    for (int t = 1; t < p->nthreads; t++) pthread_join(p->workers[t - 1], NULL);
    pthread_cond_destroy(&p->wake);
    pthread_mutex_destroy(&p->lock);
    free(p->workers);
    free(p->args);
    free(p->flags);
    free(p->seen);
    free(p);
}

int ctc_pool_threads(const ctc_pool *p)
{
    return p->nthreads;
}

void ctc_pool_set_wait(ctc_pool *p, long spin_ns, long block_ns)
{
    if (spin_ns < 0) { /* the defaults */
        spin_ns = p->spin_default;
        block_ns = p->block_default;
    }
    atomic_store_explicit(&p->spin_ns, spin_ns, memory_order_relaxed);
    atomic_store_explicit(&p->block_ns, block_ns, memory_order_relaxed);
}

void ctc_pool_run(ctc_pool *p, const ctc_pool_job *job)
{
    const int ns = job->nstages, nchunks = ns > 0 ? job->stage_first[ns] : 0;
    if (nchunks <= 0) return;
    if (ns > CTC_POOL_MAX_STAGES || nchunks > CTC_POOL_MAX_CHUNKS) { /* too large: alone */
        for (int i = 0; i < nchunks; i++) job->work(job->ctx, i);
        return;
    }
    const unsigned long gen = atomic_load(&p->run_gen) + 1;
    p->work = job->work;
    p->ctx = job->ctx;
    atomic_store(&p->nstages, ns);
    for (int s = 0; s <= ns; s++) atomic_store(&p->stage_first[s], job->stage_first[s]);
    for (int i = 0; i < nchunks; i++) {
        atomic_store_explicit(&p->flags[i], 2ULL * gen, memory_order_relaxed);
    }
    atomic_store(&p->done, 0);
    atomic_store(&p->run_gen, gen); /* publishes all of the above */
    wake_sleepers(p);
    run_stages(p, gen, 0);
    wait_until(p, &p->done, (unsigned long)nchunks, 0);
}

/* ---- the gate: alone or split, by measured cost ---- */

static int cmp_seconds(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* the median of n <= CTC_POOL_GATE_SAMPLES timings (the mean of the middle two for even n) */
static double median(const double *t, int n)
{
    double s[CTC_POOL_GATE_SAMPLES];
    memcpy(s, t, (size_t)n * sizeof *s);
    qsort(s, (size_t)n, sizeof *s, cmp_seconds);
    return n % 2 ? s[n / 2] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
}

int ctc_pool_gate_choose(const double *alone, int nalone, const double *split, int nsplit)
{
    if (nalone > CTC_POOL_GATE_SAMPLES) nalone = CTC_POOL_GATE_SAMPLES;
    if (nsplit > CTC_POOL_GATE_SAMPLES) nsplit = CTC_POOL_GATE_SAMPLES;
    if (nalone < 1 || nsplit < 1) return 0;
    return median(split, nsplit) < (1 - CTC_POOL_GATE_MARGIN) * median(alone, nalone);
}

int ctc_pool_gate_way(const ctc_pool_gate *g)
{
    if (g->decided) return g->way;
    const long block = g->runs / CTC_POOL_GATE_BLOCK; /* blocks alone, split, split, alone, ... */
    return (int)(((block + 1) >> 1) & 1);
}

void ctc_pool_gate_record(ctc_pool_gate *g, int way, double s)
{
    g->runs++;
    if (g->decided) {
        if (g->runs >= CTC_POOL_GATE_RECHECK) {
            *g = (ctc_pool_gate){0};
        } else if (g->way == 1) {
            /* the split's latest timings replace its oldest: once their median no longer pays
               against the timings alone, alone until the recheck (measuring again at once
               could take a split whose cost swings back and forth again and again) */
            g->t[1][(g->runs - 1) % CTC_POOL_GATE_SAMPLES] = s;
            if (!ctc_pool_gate_choose(g->t[0], g->nt[0], g->t[1], g->nt[1])) {
                g->way = 0;
                g->runs = 0;
            }
        }
        return;
    }
    /* the first run of each block follows a change of way (or is the first): not timed */
    if ((g->runs - 1) % CTC_POOL_GATE_BLOCK != 0 && g->nt[way] < CTC_POOL_GATE_SAMPLES)
        g->t[way][g->nt[way]++] = s;
    if (g->nt[0] == CTC_POOL_GATE_SAMPLES && g->nt[1] == CTC_POOL_GATE_SAMPLES) {
        g->way = ctc_pool_gate_choose(g->t[0], g->nt[0], g->t[1], g->nt[1]);
        g->decided = 1;
        g->runs = 0;
    }
}

double ctc_pool_clock(void)
{
    return 1e-9 * (double)now_ns();
}
