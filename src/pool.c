/*
 * pool.c - the persistent thread team of pool.h: POSIX threads, C11 atomics, chunks claimed
 * from a generation-tagged ticket, and spin-yield-block waiting.
 *
 * Three counters drive everything. run_gen advances once per ctc_pool_run; an idle worker that
 * has seen generation g waits for g + 1. ticket holds (run generation << 32) | the next chunk to
 * claim: a thread claims chunk i of run g by a compare-and-swap from (g, i) to (g, i + 1), so a
 * worker still holding an older generation can never claim, and after the last chunk is done
 * the caller closes the ticket ((g, 0xffffffff)) before it touches the job fields again. done
 * counts the chunks finished in the current run; a claimed chunk waits until done reaches its
 * need, and the caller returns when done reaches nchunks.
 *
 * Memory order: the job's fields (need, work, ctx) are plain; the caller writes them before it
 * stores the new ticket, and a worker reads them only after a compare-and-swap on the ticket
 * succeeded, which reads from that store or from the claims after it (a release sequence), so it
 * sees them; the caller rewrites them only after every chunk, hence every claim, is done. A
 * chunk's writes are released by its increment of done and acquired by whoever waits for done.
 * Every atomic operation here is sequentially consistent, which the blocking handshake needs.
 *
 * Blocking: a waiter first counts itself in sleepers, then takes the mutex and re-checks its
 * condition before waiting on the condition variable; whoever advances a counter first advances
 * it, then reads sleepers and broadcasts under the mutex only if it is non-zero. Either the
 * releaser sees the sleeper (and the broadcast reaches it, the re-check being under the same
 * mutex) or the sleeper sees the new value; no wake-up is lost, and while nobody sleeps no
 * system call is made.
 *
 * The counters live on their own cache lines so that spinning on one does not slow the updates
 * of another.
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
#define CLOSED 0xffffffffULL /* the ticket's chunk index once a run is over */

struct ctc_pool {
    alignas(CACHE_LINE) atomic_ullong ticket; /* (run generation << 32) | next chunk */
    alignas(CACHE_LINE) atomic_ulong done;    /* chunks done in the current run */
    alignas(CACHE_LINE) atomic_ulong run_gen; /* runs started */
    alignas(CACHE_LINE) atomic_int sleepers;  /* threads blocked */
    atomic_int stop;                          /* 1: workers exit at the next run */
    atomic_int nchunks;                       /* the current run's */
    atomic_long spin_ns, block_ns;            /* the waiting phases */
    long spin_default;                        /* spin_ns of a new pool */
    int nthreads;
    /* the current run's job: valid while one of its chunks is claimed */
    int (*need)(void *ctx, int chunk);
    void (*work)(void *ctx, int chunk);
    void *ctx;
    pthread_mutex_t lock;
    pthread_cond_t wake;      /* broadcast when a counter advances and someone sleeps */
    pthread_t *workers;       /* (nthreads - 1) */
    struct pool_worker *args; /* (nthreads - 1) */
};

/* a worker's argument */
struct pool_worker {
    ctc_pool *pool;
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

/* Waits until *x >= target: pause-spin, yield-spin, then block (pool.h). */
static void wait_until(ctc_pool *p, atomic_ulong *x, unsigned long target)
{
    long long t0 = 0;
    int yielding = 0;
    for (unsigned i = 1;; i++) {
        if (atomic_load(x) >= target) return;
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
    while (atomic_load(x) < target) pthread_cond_wait(&p->wake, &p->lock);
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

static unsigned long long ticket_tag(unsigned long gen)
{
    return (unsigned long long)(gen & 0xffffffffUL) << 32;
}

/* claims and does chunks of run gen until none is left or the run is over */
static void claim_chunks(ctc_pool *p, unsigned long gen)
{
    const unsigned long long tag = ticket_tag(gen);
    for (;;) {
        unsigned long long t = atomic_load(&p->ticket);
        if ((t & ~CLOSED) != tag) return; /* another run's ticket */
        unsigned long long i = t & CLOSED;
        if (i >= (unsigned long long)atomic_load(&p->nchunks)) return; /* all claimed */
        if (!atomic_compare_exchange_weak(&p->ticket, &t, t + 1)) continue;
        int need = p->need(p->ctx, (int)i);
        if (need > 0) wait_until(p, &p->done, (unsigned long)need);
        p->work(p->ctx, (int)i);
        atomic_fetch_add(&p->done, 1);
        wake_sleepers(p);
    }
}

static void *worker_main(void *arg)
{
    ctc_pool *p = ((struct pool_worker *)arg)->pool;
    unsigned long seen = 0; /* the last run seen */
    for (;;) {
        wait_until(p, &p->run_gen, seen + 1);
        seen = atomic_load(&p->run_gen);
        if (atomic_load(&p->stop)) return NULL;
        claim_chunks(p, seen);
    }
}

ctc_pool *ctc_pool_new(int nthreads)
{
    if (nthreads < 2 || nthreads > CTC_MAX_THREADS) return NULL;
    size_t size = (sizeof(ctc_pool) + CACHE_LINE - 1) / CACHE_LINE * CACHE_LINE;
    ctc_pool *p = aligned_alloc(CACHE_LINE, size);
    if (p == NULL) return NULL;
    memset(p, 0, size);
    atomic_init(&p->ticket, ticket_tag(0) | CLOSED);
    atomic_init(&p->done, 0);
    atomic_init(&p->run_gen, 0);
    atomic_init(&p->sleepers, 0);
    atomic_init(&p->stop, 0);
    atomic_init(&p->nchunks, 0);
    long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
    p->spin_default = ncpu > 0 && nthreads > ncpu ? 0 : CTC_POOL_SPIN_NS;
    atomic_init(&p->spin_ns, p->spin_default);
    atomic_init(&p->block_ns, CTC_POOL_BLOCK_NS);
    p->nthreads = nthreads;
    p->workers = calloc((size_t)nthreads - 1, sizeof *p->workers);
    p->args = calloc((size_t)nthreads - 1, sizeof *p->args);
    if (p->workers == NULL || p->args == NULL) goto fail_alloc;
    if (pthread_mutex_init(&p->lock, NULL) != 0) goto fail_alloc;
    if (pthread_cond_init(&p->wake, NULL) != 0) {
        pthread_mutex_destroy(&p->lock);
        goto fail_alloc;
    }
    for (int t = 1; t < nthreads; t++) {
        p->args[t - 1].pool = p;
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
    atomic_fetch_add(&p->run_gen, 1);
    wake_sleepers(p);
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
    if (spin_ns < 0) { /* the defaults */
        spin_ns = p->spin_default;
        block_ns = CTC_POOL_BLOCK_NS;
    }
    atomic_store_explicit(&p->spin_ns, spin_ns, memory_order_relaxed);
    atomic_store_explicit(&p->block_ns, block_ns, memory_order_relaxed);
}

void ctc_pool_run(ctc_pool *p, const ctc_pool_job *job)
{
    if (job->nchunks <= 0) return;
    const unsigned long gen = atomic_load(&p->run_gen) + 1;
    p->need = job->need;
    p->work = job->work;
    p->ctx = job->ctx;
    atomic_store(&p->nchunks, job->nchunks);
    atomic_store(&p->done, 0);
    atomic_store(&p->ticket, ticket_tag(gen));
    atomic_store(&p->run_gen, gen);
    wake_sleepers(p);
    claim_chunks(p, gen);
    wait_until(p, &p->done, (unsigned long)job->nchunks);
    atomic_store(&p->ticket, ticket_tag(gen) | CLOSED);
}
