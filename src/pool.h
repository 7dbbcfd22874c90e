/*
 * pool.h - a small persistent team of threads that share the chunks of one job, chunks of a
 * later stage starting only when the earlier stages are done (internal to the library; used by
 * gdca_par.c).
 *
 * A pool of k threads is the caller's thread and k - 1 workers started once by ctc_pool_new and
 * kept until ctc_pool_free. ctc_pool_run(p, job) runs the job's chunks 0..nchunks-1, each exactly
 * once, on whichever thread claims it, and returns when all are done. Chunks are claimed in
 * increasing order; chunk i starts only when need(i) chunks are done, where need is
 * nondecreasing and need(i) <= i: with the chunks grouped into stages, need(i) = the first chunk
 * of i's stage makes every stage wait for the whole previous one (a level barrier), because the
 * done chunks are always all the earlier stages' plus some of the current one's. The writes of
 * a done chunk are visible to every chunk that starts after it.
 *
 * Nobody waits for a thread that holds no chunk: a worker that is late (not yet woken, or
 * descheduled by the operating system) simply finds the chunks taken by the others, and a run
 * never waits for its workers to check in or out. Claims carry the run's generation, so a worker
 * that wakes up after its run is over cannot claim a chunk of the next one; it touches the job
 * only after a successful claim, while the caller is still waiting for that chunk. On a machine
 * shared with other programs this matters: a barrier that every thread must reach costs a whole
 * time slice whenever one of them is descheduled (bench/README.md, "Parallel assembly").
 *
 * Waiting (for a chunk's dependencies, for the end of a run, and in an idle worker for the next
 * run) goes in three phases so that warm threads pay no system call and idle ones cost no CPU
 * for long: a busy spin with the CPU's pause hint up to spin_ns (a few microseconds, about what a
 * stage's chunks take to finish one after the other), then spinning with sched_yield up to
 * block_ns, so that a thread waiting for one that shares its core hands the core over, then
 * blocking on a condition variable. The thread that ends a wait (a chunk done, a run started)
 * makes a system call (a broadcast) only when some thread has blocked. A pool with more threads
 * than the machine has online CPUs yields at once (spin_ns = 0).
 *
 * A pool belongs to one thread at a time (the one calling ctc_pool_run); it is not reentrant.
 */
#ifndef CTC_POOL_H
#define CTC_POOL_H

/* the most threads a pool (and a ctc_data, data.h) may have, the caller's included */
#define CTC_MAX_THREADS 64

/* Default waiting phases, ns: pause-spin until CTC_POOL_SPIN_NS, then sched_yield, and block
 * after CTC_POOL_BLOCK_NS (bench_parallel measures them; bench/README.md). */
#ifndef CTC_POOL_SPIN_NS
#define CTC_POOL_SPIN_NS 5000
#endif
#ifndef CTC_POOL_BLOCK_NS
#define CTC_POOL_BLOCK_NS 100000
#endif

typedef struct ctc_pool ctc_pool;

/* One job: nchunks chunks (>= 0); work(ctx, i) does chunk i; need(ctx, i) is the number of
 * chunks that must be done before chunk i starts (nondecreasing in i, <= i). Both are called
 * only for chunks of a run in progress, from any of the pool's threads. */
typedef struct ctc_pool_job {
    int nchunks;
    int (*need)(void *ctx, int chunk);
    void (*work)(void *ctx, int chunk);
    void *ctx;
} ctc_pool_job;

/* Starts a pool of nthreads threads (2..CTC_MAX_THREADS; the caller's thread is one of them, so
 * nthreads - 1 workers are created). Returns NULL when nthreads is out of range, memory runs out
 * or a thread cannot be created (nothing is left running). Free with ctc_pool_free. */
ctc_pool *ctc_pool_new(int nthreads);

/* Stops and joins the workers and frees p; NULL is allowed. Not during a ctc_pool_run. */
void ctc_pool_free(ctc_pool *p);

/* The number of threads, the caller's included. */
int ctc_pool_threads(const ctc_pool *p);

/* Sets the waiting phases (ns): pause-spin up to spin_ns, then yield-spin up to block_ns, then
 * block; block_ns < 0 never blocks (not even an idle worker between runs: for measurements
 * only); spin_ns < 0 restores the new pool's phases. Between runs; a waiting thread picks the
 * new phases up as it waits. */
void ctc_pool_set_wait(ctc_pool *p, long spin_ns, long block_ns);

/* Runs the job's chunks on p's threads, the caller's included, and returns when every chunk is
 * done (pool.h above). */
void ctc_pool_run(ctc_pool *p, const ctc_pool_job *job);

#endif
