/*
 * pool.h - a small persistent team of threads that share the chunks of one job stage by stage,
 * each stage starting when the one before is done (internal to the library; used by
 * gdca_par.c).
 *
 * A pool of k threads is the caller's thread (thread 0) and k - 1 workers started once by
 * ctc_pool_new and kept until ctc_pool_free. ctc_pool_run(p, job) runs the job's stages in
 * order; a stage is a range of chunks, each chunk runs exactly once, and a chunk starts only
 * when every chunk of the earlier stages is done (a level barrier); the writes of a done chunk
 * are visible to every chunk that starts after it. The run returns when all chunks are done.
 *
 * Who runs which chunk: the m chunks of a stage belong to the threads in contiguous blocks
 * (chunk j to thread j k / m), so that with one chunk per thread and the same split at every
 * stage a thread keeps working on the same part of the data. A thread first runs its own
 * chunks, then takes any chunk of the stage that nobody has claimed once the stage could start,
 * at once if its owner has not joined the run, else after its owner has let GRACE_NS pass: the
 * owner is late (not yet woken, or descheduled by the
 * operating system). So nobody waits for a thread that holds no chunk, and a run never waits for
 * its workers to check in or out. Claims carry the run's generation, so a worker that wakes up
 * after its run is over cannot claim a chunk of the next one; it touches the job only after a
 * successful claim, while the caller is still waiting for that chunk. On a machine shared with
 * other programs this matters: a barrier that every thread must reach costs a whole time slice
 * whenever one of them is descheduled (bench/NOTEBOOK.md, "Parallel assembly").
 *
 * Waiting (for a chunk's dependencies, for the end of a run, and in an idle worker for the next
 * run) can go in three phases: a busy spin with the CPU's pause hint up to spin_ns, then spinning
 * with sched_yield up to block_ns, then blocking on a condition variable. The thread that ends a
 * wait (a chunk done, a run started) makes a system call (a broadcast) only when some thread has
 * blocked, so warm threads pay none. The defaults spin for 5 us, about what the chunks of one
 * stage take to finish one after another, and then block without yielding: a yield or an early
 * block hands the core to another program, a long spin keeps it from the thread being waited
 * for. A pool with more threads than the machine has online CPUs yields at once and blocks after
 * 100 us, since its own threads compete for the cores. The policies' costs per stage:
 * bench/NOTEBOOK.md, "Parallel assembly" ("Level barrier", "Oversubscription").
 *
 * A pool belongs to one thread at a time (the one calling ctc_pool_run); it is not reentrant.
 *
 * Whether a job should run on the pool at all is a matter of measured cost, not of a length
 * rule: a split pays only where the work of a stage outweighs the hand-offs, which depends on
 * the machine, its load and the thread count. A gate (ctc_pool_gate) times the first runs of one
 * kind of job alone and split, alternately, then takes the faster way for the next
 * CTC_POOL_GATE_RECHECK runs (alone from where a split it took stops paying) before it measures
 * again; ctc_pool_gate_choose is its decision from the timings alone, so that it is tested
 * without a clock. The GDCA passes keep one gate per data, for whole evaluations (data.h
 * ctc_eval_gate).
 */
#ifndef CTC_POOL_H
#define CTC_POOL_H

/* the most threads a pool (and a ctc_data, data.h) may have, the caller's included */
#define CTC_MAX_THREADS 64

/* Default waiting phases, ns: pause-spin until CTC_POOL_SPIN_NS, then sched_yield, and block
 * after CTC_POOL_BLOCK_NS (bench_parallel measures the choices: bench/NOTEBOOK.md, "Parallel
 * assembly"). */
#ifndef CTC_POOL_SPIN_NS
#define CTC_POOL_SPIN_NS 5000
#endif
#ifndef CTC_POOL_BLOCK_NS
#define CTC_POOL_BLOCK_NS 5000
#endif

typedef struct ctc_pool ctc_pool;

/* the most stages and chunks of one job (a larger job runs on the caller's thread alone) */
#define CTC_POOL_MAX_STAGES 256
#define CTC_POOL_MAX_CHUNKS 4096

/* One job: stage s is the chunks stage_first[s] .. stage_first[s + 1] - 1 (stage_first has
 * nstages + 1 nondecreasing entries from 0); work(ctx, i) does chunk i, from any of the pool's
 * threads, only during the run. */
typedef struct ctc_pool_job {
    int nstages;
    const int *stage_first;
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

/* Runs the job's stages on p's threads, the caller's included, and returns when every chunk is
 * done (above). */
void ctc_pool_run(ctc_pool *p, const ctc_pool_job *job);

/* A gate's timings per way before it decides, taken in blocks of CTC_POOL_GATE_BLOCK runs of one
 * way: the first run of each block, the one after a change of way, is not counted (a pool's
 * start; a run alone that fetches what a split left in other cores' caches, or a split whose
 * workers fetch what a run alone left in the caller's; each way's steady cost is what counts).
 * The split must be faster by CTC_POOL_GATE_MARGIN of the time alone (medians) to be taken, and
 * stays taken only while the median of its latest CTC_POOL_GATE_SAMPLES timings is (else the
 * gate runs alone); after CTC_POOL_GATE_RECHECK decided runs the gate measures again. */
#define CTC_POOL_GATE_SAMPLES 6
#define CTC_POOL_GATE_BLOCK 3
#define CTC_POOL_GATE_MARGIN 0.05
#define CTC_POOL_GATE_RECHECK 4096

/* One gate: how one kind of job runs. All zero (a zeroed struct) is a gate that measures. */
typedef struct ctc_pool_gate {
    int decided;                        /* 1: way holds the decision */
    int way;                            /* when decided: 0 alone, 1 split */
    long runs;                          /* runs since the gate last started measuring */
    int nt[2];                          /* timings kept per way (0 alone, 1 split) */
    double t[2][CTC_POOL_GATE_SAMPLES]; /* s, the kept timings */
} ctc_pool_gate;

/* The decision from timings: 1 (split) when the median of the nsplit split timings is below
 * (1 - CTC_POOL_GATE_MARGIN) times the median of the nalone timings alone, else 0 (alone; also
 * when either list is empty). Deterministic: the same timings give the same decision, whatever
 * their order. The arrays are not changed; at most CTC_POOL_GATE_SAMPLES of each are read. */
int ctc_pool_gate_choose(const double *alone, int nalone, const double *split, int nsplit);

/* The way the next run of the gate's job takes: 1 split, 0 alone. While measuring, the runs go
 * in blocks of CTC_POOL_GATE_BLOCK, alone, split, split, alone, alone, split, ... (ABBA, so that
 * a slow drift of the machine weighs on both ways alike). */
int ctc_pool_gate_way(const ctc_pool_gate *g);

/* Records a run that took `way` and lasted s seconds; decides once both ways have
 * CTC_POOL_GATE_SAMPLES timings, and measures again after CTC_POOL_GATE_RECHECK decided runs. A
 * split it decided on that stops paying by its latest timings (a split's cost can change after
 * the measurement: the workers' waiting, other programs on the cores) is dropped: the gate runs
 * alone for the next CTC_POOL_GATE_RECHECK runs. */
void ctc_pool_gate_record(ctc_pool_gate *g, int way, double s);

/* Seconds on the monotonic clock, to time a gate's runs. */
double ctc_pool_clock(void);

#endif
