/*
 * pool.c - the persistent thread team of pool.h: POSIX threads, C11 atomics, a generation
 * barrier and spin-yield-block waiting.
 *
 * Two generation counters drive everything. run_gen advances once per ctc_pool_run: a worker
 * that has seen generation g waits for g + 1, then calls the job. bar_gen advances once per
 * barrier: each arriving thread reads it, increments bar_count, and the last to arrive (count
 * k - 1 before its increment) resets the count and advances bar_gen, which releases the others.
 * A thread reads the next barrier's count only after it has seen bar_gen advance, so the reset
 * is never lost. The job's function and context are plain fields written before run_gen
 * advances (sequentially consistent store) and read after it is seen advanced, and rewritten
 * only after the closing barrier of the run, when every worker has read them.
 *
 * Blocking uses the usual two-sided handshake: a waiter first counts itself in *_sleepers,
 * then takes the mutex and re-checks the generation before waiting on the condition variable;
 * the releaser first advances the generation, then reads *_sleepers and broadcasts under the
 * mutex only if it is non-zero. With sequentially consistent operations on both sides either the
 * releaser sees the sleeper (and the broadcast reaches it, the re-check being under the same
 * mutex) or the sleeper sees the new generation; no wake-up is lost and an all-warm barrier makes
 * no system call.
 *
 * The hot counters live on their own cache lines so that spinning on one does not slow the
 * updates of another.
 */
#include "pool.h"

#include <pthread.h>
#include <sched.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#define CACHE_LINE 64

struct ctc_pool {
    alignas(CACHE_LINE) atomic_ulong bar_gen; /* barriers completed */
    alignas(CACHE_LINE) atomic_int bar_count; /* threads arrived at the current barrier */
    alignas(CACHE_LINE) atomic_ulong run_gen; /* runs started */
    alignas(CACHE_LINE) atomic_int sleepers;  /* threads blocked (barrier or idle) */
    atomic_int stop;                          /* 1: workers exit at the next run */
    int nthreads;
    long spin_ns, block_ns;
    void (*fn)(void *ctx, int tid); /* the current run's job */
    void *ctx;
    pthread_mutex_t lock;
    pthread_cond_t wake;      /* broadcast when a generation advances and someone sleeps */
    pthread_t *workers;       /* (nthreads - 1) */
    struct pool_worker *args; /* (nthreads - 1) */
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

/* Waits until *gen differs from seen: pause-spin, yield-spin, then block (pool.h). */
static void wait_for_change(ctc_pool *p, atomic_ulong *gen, unsigned long seen)
{
    long long t0 = 0;
    int yielding = p->spin_ns == 0;
    for (unsigned i = 1;; i++) {
        if (atomic_load_explicit(gen, memory_order_acquire) != seen) return;
        if (!yielding) {
            cpu_relax();
            if ((i & 31) != 0) continue; /* the clock is read every 32 rounds */
            long long t = now_ns();
            if (t0 == 0) t0 = t;
            yielding = t - t0 >= p->spin_ns;
        } else {
            if (p->block_ns >= 0) {
                long long t = now_ns();
                if (t0 == 0) t0 = t;
                if (t - t0 >= p->block_ns) break;
            }
            sched_yield();
        }
    }
    atomic_fetch_add(&p->sleepers, 1);
    pthread_mutex_lock(&p->lock);
    while (atomic_load(gen) == seen) pthread_cond_wait(&p->wake, &p->lock);
    pthread_mutex_unlock(&p->lock);
    atomic_fetch_sub(&p->sleepers, 1);
}

/* Advances *gen (sequentially consistent) and wakes the blocked threads, if any. */
static void advance(ctc_pool *p, atomic_ulong *gen)
{
    atomic_fetch_add(gen, 1);
    if (atomic_load(&p->sleepers) > 0) {
        pthread_mutex_lock(&p->lock);
        pthread_cond_broadcast(&p->wake);
        pthread_mutex_unlock(&p->lock);
    }
}

void ctc_pool_barrier(ctc_pool *p)
{
    unsigned long g = atomic_load(&p->bar_gen);
    if (atomic_fetch_add(&p->bar_count, 1) == p->nthreads - 1) {
        atomic_store_explicit(&p->bar_count, 0, memory_order_relaxed);
        advance(p, &p->bar_gen);
        return;
    }
    wait_for_change(p, &p->bar_gen, g);
}

static void *worker_main(void *arg)
{
    const struct pool_worker *w = arg;
    ctc_pool *p = w->pool;
    unsigned long seen = 0; /* runs seen */
    for (;;) {
        wait_for_change(p, &p->run_gen, seen);
        seen++; /* the caller starts no run before this one's closing barrier */
        if (atomic_load(&p->stop)) return NULL;
        p->fn(p->ctx, w->tid);
        ctc_pool_barrier(p);
    }
}

ctc_pool *ctc_pool_new(int nthreads)
{
    if (nthreads < 2 || nthreads > CTC_MAX_THREADS) return NULL;
    size_t size = (sizeof(ctc_pool) + CACHE_LINE - 1) / CACHE_LINE * CACHE_LINE;
    ctc_pool *p = aligned_alloc(CACHE_LINE, size);
    if (p == NULL) return NULL;
    memset(p, 0, size);
    atomic_init(&p->bar_gen, 0);
    atomic_init(&p->bar_count, 0);
    atomic_init(&p->run_gen, 0);
    atomic_init(&p->sleepers, 0);
    atomic_init(&p->stop, 0);
    p->nthreads = nthreads;
    p->spin_ns = CTC_POOL_SPIN_NS;
    p->block_ns = CTC_POOL_BLOCK_NS;
    p->workers = calloc((size_t)nthreads - 1, sizeof *p->workers);
    p->args = calloc((size_t)nthreads - 1, sizeof *p->args);
    if (p->workers == NULL || p->args == NULL) goto fail_alloc;
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
    free(p);
    return NULL;
}

void ctc_pool_free(ctc_pool *p)
{
    if (p == NULL) return;
    atomic_store(&p->stop, 1);
    advance(p, &p->run_gen);
    for (int t = 1; t < p->nthreads; t++) pthread_join(p->workers[t - 1], NULL);
    pthread_cond_destroy(&p->wake);
    pthread_mutex_destroy(&p->lock);
    free(p->workers);
    free(p->args);
    free(p);
}

int ctc_pool_threads(const ctc_pool *p)
{
    return p->nthreads;
}

void ctc_pool_set_wait(ctc_pool *p, long spin_ns, long block_ns)
{
    p->spin_ns = spin_ns < 0 ? 0 : spin_ns;
    p->block_ns = block_ns;
}

void ctc_pool_run(ctc_pool *p, void (*fn)(void *ctx, int tid), void *ctx)
{
    p->fn = fn;
    p->ctx = ctx;
    advance(p, &p->run_gen);
    fn(ctx, 0);
    ctc_pool_barrier(p);
}
