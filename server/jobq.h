/*
 * jobq.h - the bounded job queue and its worker threads.
 *
 * HTTP threads submit job ids (the job row is already stored as queued, store.h); N worker
 * threads pop them in order, each with its own database connection, and for each job: mark it
 * running, parse its stored spec (job_json.h; the model is built once per job), run it
 * (ctc_sim_run) with progress written to the database at most every JOBQ_PROGRESS_INTERVAL s and
 * cancellation polled between steps, then store the result, status and series in one transaction.
 * A per-job wall-time limit from the configuration caps the job's own limits.wall_time.
 *
 * A worker never drops a job. Every store write it makes (marking the job running, storing the
 * result, marking it failed or cancelled) and the read of its spec are retried while the store's
 * fault is transient (store.h: locked, full, read-only, I/O error), with a pause that doubles from
 * JOBQ_RETRY_FIRST to JOBQ_RETRY_MAX seconds, until they succeed, fail for good, or the queue
 * stops (then the job stays queued or running in the database and the next start recovers it).
 * A result whose series does not fit (STORE_FAULT_FULL) is not retried: the job is recorded
 * failed, "could not store the result: database or disk is full", as soon as that small write is
 * accepted. Progress writes do not wait for locks at all (a missed one is followed by the next).
 * A worker holds no lock of the queue's while it waits.
 *
 * The queue is a mutex + condition variable ring (wait while empty, pop under the lock, work
 * outside it), with one lane per family of jobs beside it: workers serve the ring and the lanes
 * in turn, one job each, so a family's members never hold up a single job for longer than one
 * member's run per family (jobq.c). jobq_stop stops taking jobs, asks running ones to stop at their
 * next step, puts them back to queued in the database (they restart from t = 0 at the next start),
 * and joins the workers. A job answered 202 is therefore never lost: it is in the database before
 * it is queued.
 *
 * Shared queue (PostgreSQL, store_pg.h). When db_path names a PostgreSQL database the queue is
 * the database: the ring is not used, and each worker claims the oldest claimable job itself
 * (store_pg_claim, FOR UPDATE SKIP LOCKED) under a lease of config.lease_s, renewed by a
 * heartbeat at each progress write (at most every JOBQ_PROGRESS_INTERVAL s); an idle worker
 * waits for the database's notification of a change (LISTEN) or JOBQ_CLAIM_IDLE s, whichever
 * comes first, and claims again, which also takes over a job whose lease expired (its worker
 * died). A worker whose claim fails for a transient fault (the connection lost included) stops
 * claiming and tries again after the retry pause, reconnecting; one that learns at a heartbeat
 * that its lease was taken over stops the job and stores nothing (the new holder's result is the
 * job's one result). Any number of processes on any machines may run workers on one database.
 * With config.listen, one thread of the process listens for the notifications of finished jobs
 * on a connection of its own: jobq_wait and the `left` hook follow the jobs submitted through
 * this process (jobq_submit) without a query per waiting request; every JOBQ_RECONCILE s, and
 * after the listening connection was lost, it reads the status of those jobs in one query, so a
 * notification missed while disconnected delays nothing for long. jobq_space, jobq_cancel,
 * jobq_position and the counters of jobq_get_stats then read the database (one small query each,
 * on a connection the process shares under a lock): jobq_space bounds the queued single jobs,
 * jobq_position counts places in the claims' turns (store_pg_queue_position), queued and busy
 * are the whole database's queued and running jobs, workers this process's. Families need no
 * lanes here: the claim itself serves the single jobs and each family in turn, across every
 * worker process (store_pg_claim); jobq_submit_family only checks that the queue is not
 * stopping (its members are not followed; jobq_wait watches a job it was not given, a member
 * or another API process's job, while it waits: one status read, then the notifications), and
 * jobq_cancel_family flags the family's active members in the database (store_pg_request_cancel_
 * family), handing back no ids. jobq_live_info and jobq_live_read know only the jobs this
 * process's workers run: an API process without workers has no live samples to give.
 *
 * All functions are thread-safe unless they say otherwise.
 */
#ifndef JOBQ_H
#define JOBQ_H

#include <stddef.h>
#include <stdint.h>

#include "store.h"

#define JOBQ_PROGRESS_INTERVAL 0.25 /* s between progress writes of one job */
#define JOBQ_BUSY_MS 1000           /* ms one worker write waits for a lock before it is retried */
#define JOBQ_RETRY_FIRST 0.01       /* s, the first pause before a retry */
#define JOBQ_RETRY_MAX 2.0          /* s, the longest pause between retries */
#define JOBQ_CLAIM_IDLE 1.0         /* s an idle worker of a shared queue waits before claiming */
#define JOBQ_RECONCILE 5.0          /* s between the listener's reads of its jobs' statuses */

struct store_health;

typedef struct jobq jobq;

typedef struct jobq_config {
    const char *db_path;   /* the database each worker opens */
    int workers;           /* >= 1; >= 0 on a shared queue (PostgreSQL) */
    double lease_s;        /* s, a shared queue's lease of a claimed job (>= 1) */
    int listen;            /* a shared queue: follow submitted jobs (jobq_wait, `left`) */
    int max_queue;         /* >= 1: jobs waiting (not running) at most */
    double job_time_limit; /* s of wall time per job; 0 = none */
    /* called with each job that leaves the queue and the workers (finished, cancelled while
       queued, or put back at shutdown), on the thread that removed it and outside the queue's
       lock; NULL = none. It must not call back into the queue. */
    void (*left)(void *arg, int64_t id);
    void *left_arg;
    long long db_max_size; /* bytes the workers may grow the database to (store_set_max_size); 0 =
                              no cap */
    struct store_health *health; /* the state the workers' writes report to (store.h), or NULL */
} jobq_config;

typedef struct jobq_stats {
    int workers;
    int busy;   /* workers running a job */
    int queued; /* jobs waiting, single and in families */
    long done;  /* jobs finished since start (any final status) */
} jobq_stats;

/* Starts the workers. Opens a connection for recovery, re-queues every job the database holds as
 * queued or running (store_recover; these may exceed max_queue), and starts the threads. Returns
 * 0, or -1 with a message. The config is copied (db_path too). */
int jobq_start(const jobq_config *config, jobq **out, char *err, size_t errlen);

/* Queues a stored job. Returns 0, 1 when the queue is full (the caller answers 503 and should
 * mark the stored job cancelled or delete it), or 2 when the queue is stopping. */
int jobq_submit(jobq *q, int64_t id);

/* Queues the n stored members ids[0..n) of a family, in order, in that family's lane (made when
 * absent; the lanes are not bounded by max_queue). Returns 0, 2 when the queue is stopping, or
 * -1 out of memory (nothing queued). */
int jobq_submit_family(jobq *q, int64_t family, const int64_t *ids, long n);

/* Cancels a family: takes every member waiting in its lane out of the queue, handing their ids
 * to the caller (*removed, a new array to free(), of *n; the caller records them cancelled;
 * `left` is called for each), and asks the workers running its members to stop at their next
 * step (they record them cancelled). Returns the number of members asked to stop. */
int jobq_cancel_family(jobq *q, int64_t family, int64_t **removed, long *n);

/* Free places in the queue now (a hint for the caller before it stores a job). */
int jobq_space(jobq *q);

/* Cancels a job: removes it from the queue if it waits there (returns 1: the caller records it
 * cancelled), or asks the worker running it to stop at its next step (returns 2: the worker
 * records it cancelled). Returns 0 if the job is neither queued nor running here. */
int jobq_cancel(jobq *q, int64_t id);

/* The shape of what job id's run has recorded so far, while a worker here runs it: 0 with *out
 * filled as store_get_series_info fills it (out->nsamples samples, all final), or 1 when no
 * worker here runs it or it has recorded no sample yet. */
int jobq_live_info(jobq *q, int64_t id, store_series_info *out);

/* 1 when the queue is a PostgreSQL database shared by worker processes (jobs may run in
 * another process, whose live samples this one cannot read), else 0. */
int jobq_shared(const jobq *q);

/* Copies len bytes at offset (store.h's layout: per channel, samples x width float64; -1 = t)
 * of the samples job id's run has recorded so far. Returns 0; 1 when no worker here runs it
 * any more (once finished, its series is in the store: the worker stores it before letting go
 * of the run); -1 when the bytes lie past the samples recorded or the channel is not. Holds
 * the queue's lock for the copy: callers read a few KiB at a time. */
int jobq_live_read(jobq *q, int64_t id, int channel, uint64_t offset, void *buf, size_t len);

/* The job's place in the queue: 1 for the next to start, 0 when it does not wait there
 * (running, finished, or queued in the database only). Workers serve the single jobs and each
 * family's lane in turn, so a job k-th in its place has k of its place ahead of it and up to k
 * of every other place: the place counts those (exact up to where the turn stands, one job per
 * place). */
int jobq_position(jobq *q, int64_t id);

/* Waits until the job is no longer queued or running here, or timeout_s passes. Returns 0 when it
 * finished (or was never here), 1 on timeout. A shared queue waits for any job of the database,
 * a family's member or another process's too, when it listens (config.listen); without a
 * listener it returns 0 at once. */
int jobq_wait(jobq *q, int64_t id, double timeout_s);

/* Current counters. */
void jobq_get_stats(jobq *q, jobq_stats *out);

/* Stops taking jobs, makes running jobs stop at their next step and re-queues them in the
 * database, joins the workers and frees q. Queued jobs stay queued in the database. NULL is
 * allowed. Not thread-safe with other calls on q (call it once, at shutdown). */
void jobq_stop(jobq *q);

#endif
