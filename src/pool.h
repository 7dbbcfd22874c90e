/*
 * pool.h - a small persistent team of threads that run one function together, with a barrier
 * between the steps of that function (internal to the library; used by gdca_par.c).
 *
 * A pool of k threads is the caller's thread (thread 0) and k - 1 workers started once by
 * ctc_pool_new and kept until ctc_pool_free. ctc_pool_run(p, fn, ctx) has every thread call
 * fn(ctx, tid), tid = 0..k-1, and returns when all have returned; inside fn the threads meet at
 * ctc_pool_barrier, which returns in each thread once all k have reached it (the writes made
 * before it by any thread are visible after it to every thread).
 *
 * Waiting, in the barrier and in an idle worker waiting for the next run, goes in three phases
 * so that warm threads pay no system call and cold ones cost no CPU: a busy spin with the CPU's
 * pause hint for spin_ns, then spinning with sched_yield (so that on an oversubscribed machine a
 * waiter hands its core to the thread it waits for) until block_ns, then blocking on a condition
 * variable. The releasing thread makes a system call (a broadcast) only when some thread has
 * blocked. Both barriers and runs are counted by generation numbers on C11 atomics (a barrier
 * whose generation advances is the sense-reversing barrier without per-thread state), so one
 * barrier is one atomic increment per thread plus one store by the last to arrive.
 *
 * A pool belongs to one thread at a time (the one calling ctc_pool_run); it is not reentrant.
 */
#ifndef CTC_POOL_H
#define CTC_POOL_H

/* the most threads a pool (and a ctc_data, data.h) may have, the caller's included */
#define CTC_MAX_THREADS 64

/* Default waiting phases, ns: pause-spin until CTC_POOL_SPIN_NS, then spin with sched_yield,
 * and block after CTC_POOL_BLOCK_NS (bench_parallel measures them; bench/README.md). */
#ifndef CTC_POOL_SPIN_NS
#define CTC_POOL_SPIN_NS 20000
#endif
#ifndef CTC_POOL_BLOCK_NS
#define CTC_POOL_BLOCK_NS 200000
#endif

typedef struct ctc_pool ctc_pool;

/* Starts a pool of nthreads threads (2..CTC_MAX_THREADS; the caller's thread is one of them, so
 * nthreads - 1 workers are created). Returns NULL when nthreads is out of range, memory runs out
 * or a thread cannot be created (nothing is left running). Free with ctc_pool_free. */
ctc_pool *ctc_pool_new(int nthreads);

/* Stops and joins the workers and frees p; NULL is allowed. Not during a ctc_pool_run. */
void ctc_pool_free(ctc_pool *p);

/* The number of threads, the caller's included. */
int ctc_pool_threads(const ctc_pool *p);

/* Sets the waiting phases (ns, >= 0): pause-spin up to spin_ns, then yield-spin up to block_ns,
 * then block; block_ns < 0 never blocks. For measurements; the defaults are CTC_POOL_SPIN_NS and
 * CTC_POOL_BLOCK_NS. Not during a ctc_pool_run. */
void ctc_pool_set_wait(ctc_pool *p, long spin_ns, long block_ns);

/* Calls fn(ctx, tid) on every thread of p, tid = 0 on the caller's, and returns when every call
 * has returned. fn must call ctc_pool_barrier the same number of times in every thread. */
void ctc_pool_run(ctc_pool *p, void (*fn)(void *ctx, int tid), void *ctx);

/* Inside a ctc_pool_run: returns once every thread of p has called it (this time). */
void ctc_pool_barrier(ctc_pool *p);

#endif
