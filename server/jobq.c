/*
 * jobq.c - the bounded job queue and its worker threads (jobq.h).
 *
 * Fair turns. Single jobs wait in the ring; the members of each family (family.h) wait in their
 * family's lane, made when the family is submitted and dropped when it empties. Workers take
 * jobs in turn from the ring and from each lane, one job at a time (round-robin over the places
 * that have jobs), so a single job posted behind a family of 10^4 members waits for at most one
 * member of each family, not for the family, and two families share the workers evenly. Within a
 * place the order is first in, first out. Lanes are not bounded by max_queue (the service bounds
 * a family's size by --max-family instead).
 *
 * The queue is a ring of job ids under one mutex, with two condition variables: `work` (an id was
 * queued, or the queue is stopping) wakes idle workers, and `finished` (a job left the queue or a
 * worker) wakes jobq_wait. The ring holds max_queue ids, or more when start-up recovery brings
 * back more jobs than that; jobq_submit refuses while it holds max_queue or more, so the ring
 * never has to grow after jobq_start. Ids are the store's row ids, which are positive; a worker
 * slot holding 0 is idle.
 *
 * Each worker owns one database connection (opened by jobq_start, so a database that cannot be
 * opened fails the start rather than a thread) and a slot that records the job it runs and a
 * cancel flag. A worker pops an id under the lock and does everything else outside it:
 * store_start (which refuses a job that is no longer queued, so an id queued twice runs once),
 * store_get and job_parse of the stored spec, ctc_sim_run with three hooks, and store_finish
 * with the status, the metrics JSON (result_out.h) and the series in one transaction. The hooks
 * run on the worker's thread between integrator steps: `progress` writes the fraction done at
 * most every JOBQ_PROGRESS_INTERVAL s of monotonic time, `cancelled` reads the slot's cancel
 * flag and the queue's stopping flag, both C11 atomics, so polling costs two loads per step, and
 * `recorded` publishes the run's result and its count of final samples in the slot under the
 * lock, after each sample. jobq_live_read copies those samples under the same lock (a running
 * job's series so far); the slot lets go of the result only after store_finish has stored it,
 * so a reader that finds it gone finds the series in the store.
 *
 * A run that stopped because the queue is stopping (and not because its job was cancelled) is put
 * back to queued with store_requeue and restarts from t = 0 at the next jobq_start; the ids still
 * in the ring are simply dropped, their rows being queued already. The `done` counter counts the
 * jobs a worker brought to a final status; a job jobq_cancel takes out of the ring is recorded by
 * the caller and not counted here.
 *
 * Database faults. Each store call of a worker goes through a loop (the *_retrying functions):
 * while store_last_fault is transient the worker pauses (JOBQ_RETRY_FIRST doubling to
 * JOBQ_RETRY_MAX, in slices of at most JOBQ_RETRY_SLICE so that jobq_stop is not held up) and
 * tries again; it stops trying when the call succeeds, fails for a reason that is not the
 * database's (the job was cancelled or deleted meanwhile: then there is nothing to record), or
 * the queue stops (the row stays queued or running and the next start recovers it). Each
 * connection waits JOBQ_BUSY_MS for a lock per try, except for progress writes, which do not
 * wait: a simulation is never slowed by a lock held elsewhere. A result whose series meets a full
 * database is recorded failed without its series, with SQLite's reason ("could not store the
 * result: database or disk is full"); any other result that cannot be stored likewise, with its
 * error. Cancellation stays correct during the retries because the slot keeps the job until the
 * worker is done with it: jobq_cancel sets the flag, and the worker's writes are conditional on
 * the job's stored status (store_start needs it queued, store_finish queued or running).
 *
 * Room on a full disk. jobq_start reserves disk for the write-ahead log (store_reserve), so that
 * when the disk fills a DELETE still commits and frees pages for new jobs: JOBQ_LOG_RESERVE, about
 * the log's size between two automatic checkpoints, or half of it and half again while the disk
 * refuses, down to JOBQ_LOG_RESERVE_MIN (a file system without fallocate gets none).
 *
 * What a worker cannot hand to anyone goes to stderr, prefixed "jobq: job ID:": the first failed
 * try of each call and then every JOBQ_RETRY_LOG-th.
 */
#include "jobq.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include <cjson/cJSON.h>

#include "job_json.h"
#include "result_out.h"
#include "sim.h"
#include "store.h"
#include "store_pg.h"

#define JOBQ_MAX_WAIT 1e9            /* s: longer waits are cut to this (about 31 years) */
#define JOBQ_RETRY_SLICE 0.05        /* s: a pause is slept in slices this long, stopping checked */
#define JOBQ_RETRY_LOG 20            /* after the first failed try, one in this many is logged */
#define JOBQ_LOG_RESERVE (4LL << 20) /* bytes: about SQLite's auto-checkpoint of 1000 pages */
#define JOBQ_LOG_RESERVE_MIN (256LL << 10) /* bytes: the least tried on a nearly full disk */
/* start-up recovery waits this many tries for a write lock held by another process (a backup, an
   sqlite3 shell), each try waiting the store's busy timeout (STORE_BUSY_MS, 5 s) and then a
   pause of 1 s: about a minute, after which the start fails as before */
#define JOBQ_START_TRIES 10

/* what became of a popped job */
typedef enum worker_outcome {
    OUTCOME_SKIPPED = 0, /* not run: no longer queued, or the database failed */
    OUTCOME_FINISHED,    /* stored with a final status */
    OUTCOME_REQUEUED,    /* interrupted by jobq_stop and put back to queued */
} worker_outcome;

/* the waiting members of one family, oldest first */
typedef struct jobq_lane {
    int64_t family;
    int64_t *ids; /* (cap) ids[head .. head + count) */
    long cap, head, count;
} jobq_lane;

typedef struct jobq_worker {
    jobq *q;
    store *db; /* this worker's connection; used by its thread only while it runs */
    pthread_t thread;
    int64_t running;   /* id of the job in hand, 0 = idle (guarded by q->lock) */
    int64_t family;    /* the family of the job in hand, 0 = none (guarded by q->lock) */
    atomic_int cancel; /* set by jobq_cancel for the job in hand, cleared at each pop */
    /* the job in hand, for the hooks (worker thread only) */
    int64_t job_id;
    double last_progress; /* monotonic s of the last progress write (or of the start) */
    /* the run's result while it runs, for jobq_live_*: its first live_n samples are final
       (guarded by q->lock; NULL when nothing is recorded yet or the result is gone) */
    const ctc_sim_result *live;
    int live_n;
    int lost; /* a shared queue: the job's lease was taken over (store nothing) */
} jobq_worker;

struct jobq {
    jobq_config config; /* config.db_path points to db_path */
    char *db_path;
    pthread_mutex_t lock;
    pthread_cond_t work;     /* an id was queued, or stopping */
    pthread_cond_t finished; /* a job left the ring or a slot; CLOCK_MONOTONIC */
    int64_t *ring;           /* (cap) ids, count of them from head, oldest first: single jobs */
    int cap, head, count;
    jobq_lane *lanes; /* (nlanes) one per family with members waiting, oldest first */
    int nlanes, lanes_cap;
    long lane_jobs; /* the members waiting in every lane */
    int turn;       /* the next place to serve: 0 = the ring, i = lanes[i - 1] */
    long done;
    atomic_int stopping;
    jobq_worker *workers; /* (config.workers) */
    int nstarted;         /* threads running */
    int sync_ready;       /* lock and conditions initialised */
    /* a shared queue (PostgreSQL): the queue is the database (jobq.h) */
    int shared;
    store *ctl;               /* for space, cancel and counts, under ctl_lock */
    pthread_mutex_t ctl_lock; /* initialised with the other sync objects */
    pthread_t listener;       /* follows the jobs in pending (config.listen) */
    int listener_started;
    int64_t *pending; /* (cap_pending) jobs submitted here and not yet seen final, under lock */
    int npending, cap_pending;
    int64_t *watched; /* (cap_watched) jobs not submitted here that jobq_wait waits for (a
                         family's members, another API process's jobs): one entry per waiting
                         call, all of an id's dropped when it is seen final; under lock */
    int nwatched, cap_watched;
};

static double monotonic_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static int fail(char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static int fail(char *err, size_t errlen, const char *fmt, ...)
{
    if (err && errlen) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err, errlen, fmt, ap);
        va_end(ap);
    }
    return -1;
}

/* ---- the ring (caller holds q->lock) ---- */

static void ring_push(jobq *q, int64_t id)
{
    q->ring[(q->head + q->count) % q->cap] = id;
    q->count++;
}

static int64_t ring_pop(jobq *q)
{
    int64_t id = q->ring[q->head];
    q->head = (q->head + 1) % q->cap;
    q->count--;
    return id;
}

/* Position (0 = oldest) of id in the ring, or -1. */
static int ring_find(const jobq *q, int64_t id)
{
    for (int i = 0; i < q->count; i++)
        if (q->ring[(q->head + i) % q->cap] == id) return i;
    return -1;
}

/* Removes the entry at position pos, keeping the others in order. */
static void ring_remove(jobq *q, int pos)
{
    for (int i = pos; i + 1 < q->count; i++)
        q->ring[(q->head + i) % q->cap] = q->ring[(q->head + i + 1) % q->cap];
    q->count--;
}

/* ---- the families' lanes (caller holds q->lock) ---- */

/* The lane of family, or NULL. */
static jobq_lane *lane_of(jobq *q, int64_t family)
{
    for (int i = 0; i < q->nlanes; i++)
        if (q->lanes[i].family == family) return &q->lanes[i];
    return NULL;
}

/* Appends n ids to the lane of family (made when absent); 0, or -1 out of memory. */
static int lane_push(jobq *q, int64_t family, const int64_t *ids, long n)
{
    jobq_lane *l = lane_of(q, family);
    if (!l) {
        if (q->nlanes == q->lanes_cap) {
            int grow = q->lanes_cap ? 2 * q->lanes_cap : 4;
            jobq_lane *bigger = realloc(q->lanes, (size_t)grow * sizeof *bigger);
            if (!bigger) return -1;
            q->lanes = bigger;
            q->lanes_cap = grow;
        }
        l = &q->lanes[q->nlanes];
        memset(l, 0, sizeof *l);
        l->family = family;
        q->nlanes++;
    }
    if (l->head + l->count + n > l->cap) {
        /* compact, then grow */
        if (l->head > 0 && l->count > 0)
            memmove(l->ids, l->ids + l->head, (size_t)l->count * sizeof *l->ids);
        l->head = 0;
        if (l->count + n > l->cap) {
            long grow = l->count + n > 2 * l->cap ? l->count + n : 2 * l->cap;
            int64_t *bigger = realloc(l->ids, (size_t)grow * sizeof *bigger);
            if (!bigger) {
                if (l->count == 0) q->nlanes--; /* the lane just made: no longer */
                return -1;
            }
            l->ids = bigger;
            l->cap = grow;
        }
    }
    memcpy(l->ids + l->head + l->count, ids, (size_t)n * sizeof *ids);
    l->count += n;
    q->lane_jobs += n;
    return 0;
}

/* Removes lane i (empty or not), keeping the others in order and the turn on the same place. */
static void lane_drop(jobq *q, int i)
{
    q->lane_jobs -= q->lanes[i].count;
    free(q->lanes[i].ids);
    memmove(&q->lanes[i], &q->lanes[i + 1], (size_t)(q->nlanes - i - 1) * sizeof *q->lanes);
    q->nlanes--;
    if (q->turn > i + 1) q->turn--;
    if (q->turn > q->nlanes) q->turn = 0;
}

/* Jobs waiting, single and in families. */
static long waiting(const jobq *q)
{
    return q->count + q->lane_jobs;
}

/* Pops the next job in turn: the ring and each family's lane take turns, one job each, so a
 * single job waits for at most one job of each family. *family receives its family (0: none).
 * The caller checks that a job waits. */
static int64_t next_job(jobq *q, int64_t *family)
{
    for (int k = 0; k <= q->nlanes; k++) {
        int place = (q->turn + k) % (q->nlanes + 1);
        if (place == 0) {
            if (q->count == 0) continue;
            q->turn = 1 % (q->nlanes + 1);
            *family = 0;
            return ring_pop(q);
        }
        jobq_lane *l = &q->lanes[place - 1];
        if (l->count == 0) continue;
        int64_t id = l->ids[l->head++];
        l->count--;
        q->lane_jobs--;
        *family = l->family;
        q->turn = (place + 1) % (q->nlanes + 1);
        if (l->count == 0) {
            /* the lane goes; the turn stays on the place after it */
            q->turn = place;
            lane_drop(q, place - 1);
            if (q->turn > q->nlanes) q->turn = 0;
        }
        return id;
    }
    *family = 0;
    return 0;
}

/* Takes id out of a lane; 1 when it was there. */
static int lanes_remove(jobq *q, int64_t id)
{
    for (int i = 0; i < q->nlanes; i++) {
        jobq_lane *l = &q->lanes[i];
        for (long k = 0; k < l->count; k++)
            if (l->ids[l->head + k] == id) {
                memmove(&l->ids[l->head + k], &l->ids[l->head + k + 1],
                        (size_t)(l->count - k - 1) * sizeof *l->ids);
                l->count--;
                q->lane_jobs--;
                if (l->count == 0) lane_drop(q, i);
                return 1;
            }
    }
    return 0;
}

/* Whether id waits in a lane. */
static int lanes_find(const jobq *q, int64_t id)
{
    for (int i = 0; i < q->nlanes; i++)
        for (long k = 0; k < q->lanes[i].count; k++)
            if (q->lanes[i].ids[q->lanes[i].head + k] == id) return 1;
    return 0;
}

/* The worker whose slot holds id, or NULL (never an idle one: ids are positive). */
static jobq_worker *slot_find(jobq *q, int64_t id)
{
    for (int i = 0; id > 0 && i < q->nstarted; i++)
        if (q->workers[i].running == id) return &q->workers[i];
    return NULL;
}

/* Whether id is queued or running here. */
static int job_here(jobq *q, int64_t id)
{
    return ring_find(q, id) >= 0 || lanes_find(q, id) || slot_find(q, id) != NULL;
}

/* ---- the simulation's hooks (worker thread) ---- */

static void hook_progress(void *ctx, double fraction)
{
    jobq_worker *w = ctx;
    double t = monotonic_now();
    if (t - w->last_progress < JOBQ_PROGRESS_INTERVAL) return;
    w->last_progress = t;
    if (w->q->shared) {
        /* the heartbeat: the lease renewed with the progress; a cancel or a lost lease stops
           the run at its next step (a failed write is followed by the next one) */
        char why[256];
        int cancel = 0;
        int rc = store_pg_heartbeat(w->db, w->job_id, fraction, w->q->config.lease_s, &cancel, why,
                                    sizeof why);
        if (rc == 1) {
            fprintf(stderr, "jobq: %s; stopping it\n", why);
            w->lost = 1;
        }
        if (rc == 1 || (rc == 0 && cancel)) atomic_store(&w->cancel, 1);
        return;
    }
    /* progress is a hint: it does not wait for a lock, and a failed write is followed by the
     * next one rather than retried */
    char err[256];
    store_set_busy_timeout(w->db, 0);
    (void)store_progress(w->db, w->job_id, fraction, err, sizeof err);
    store_set_busy_timeout(w->db, JOBQ_BUSY_MS);
}

/* publishes the samples recorded so far (jobq_live_read copies them under the same lock) */
static void hook_recorded(void *ctx, const ctc_sim_result *r)
{
    jobq_worker *w = ctx;
    pthread_mutex_lock(&w->q->lock);
    w->live = r;
    w->live_n = r->nsamples;
    pthread_mutex_unlock(&w->q->lock);
}

/* the result is about to be freed: no more reads of it */
static void live_end(jobq_worker *w)
{
    pthread_mutex_lock(&w->q->lock);
    w->live = NULL;
    w->live_n = 0;
    pthread_mutex_unlock(&w->q->lock);
}

static int hook_cancelled(void *ctx)
{
    jobq_worker *w = ctx;
    return atomic_load_explicit(&w->cancel, memory_order_relaxed) ||
           atomic_load_explicit(&w->q->stopping, memory_order_relaxed);
}

/* ---- one job (worker thread, without the lock) ---- */

static store_status store_status_of(ctc_run_status st)
{
    switch (st) {
    case CTC_RUN_DONE:
        return STORE_DONE;
    case CTC_RUN_DIVERGED:
        return STORE_DIVERGED;
    case CTC_RUN_CANCELLED:
        return STORE_CANCELLED;
    case CTC_RUN_FAILED:
    case CTC_RUN_TIMEOUT:
    case CTC_RUN_SINGULAR: /* the message says why; the store keeps no status of its own */
        break;
    }
    return STORE_FAILED;
}

/* After a failed store call of job id: 1 when it should be tried again (its fault is transient:
 * the pause for this attempt, 0-based, has been slept), 0 when not (a fault that is not the
 * database's, or the queue is stopping). Logs the first failure and every JOBQ_RETRY_LOG-th. */
static int retry_after_pause(jobq_worker *w, int64_t id, int attempt, const char *what,
                             const char *err)
{
    store_fault f = store_last_fault(w->db);
    if (!store_fault_transient(f)) return 0;
    if (attempt % JOBQ_RETRY_LOG == 0)
        fprintf(stderr, "jobq: job %lld: %s (try %d, retrying): %s\n", (long long)id, what,
                attempt + 1, err);
    double pause = JOBQ_RETRY_FIRST * ldexp(1.0, attempt < 30 ? attempt : 30);
    if (pause > JOBQ_RETRY_MAX) pause = JOBQ_RETRY_MAX;
    for (double left = pause; left > 0; left -= JOBQ_RETRY_SLICE) {
        if (atomic_load(&w->q->stopping)) return 0;
        double slice = left < JOBQ_RETRY_SLICE ? left : JOBQ_RETRY_SLICE;
        struct timespec ts = {.tv_sec = 0, .tv_nsec = (long)(slice * 1e9)};
        while (nanosleep(&ts, &ts) != 0 && errno == EINTR) continue;
    }
    return !atomic_load(&w->q->stopping);
}

/* store_start, retried while the fault is transient (store_start's return codes) */
static int start_retrying(jobq_worker *w, int64_t id, char *err, size_t errlen)
{
    for (int attempt = 0;; attempt++) {
        int rc = store_start(w->db, id, err, errlen);
        if (rc >= 0 || !retry_after_pause(w, id, attempt, "marking it running", err)) return rc;
    }
}

/* store_get, retried while the fault is transient (store_get's return codes) */
static int get_retrying(jobq_worker *w, int64_t id, store_job *row, char *err, size_t errlen)
{
    for (int attempt = 0;; attempt++) {
        int rc = store_get(w->db, id, row, err, errlen);
        if (rc >= 0 || !retry_after_pause(w, id, attempt, "reading the job", err)) return rc;
    }
}

/* store_finish, retried while the fault is transient; a result meeting a full database is not
 * retried (-1 with STORE_FAULT_FULL left in store_last_fault) */
static int finish_retrying(jobq_worker *w, int64_t id, store_status status, const char *message,
                           const char *metrics, const ctc_sim_result *r, char *err, size_t errlen)
{
    for (int attempt = 0;; attempt++) {
        if (store_finish(w->db, id, status, message, metrics, r, err, errlen) == 0) return 0;
        if (r && store_last_fault(w->db) == STORE_FAULT_FULL) return -1;
        if (!retry_after_pause(w, id, attempt, "storing the result", err)) return -1;
    }
}

/* Stores a final status; a result that cannot be stored (a full database, or an error that is
 * not transient) is recorded failed without its series instead. */
static worker_outcome finish(jobq_worker *w, int64_t id, store_status status, const char *message,
                             const char *metrics, const ctc_sim_result *r)
{
    char err[512], why[768];
    if (finish_retrying(w, id, status, message, metrics, r, err, sizeof err) == 0)
        return OUTCOME_FINISHED;
    store_fault f = store_last_fault(w->db);
    /* without a result there is nothing smaller to store; a transient fault other than a full
     * database ends the retries only when the queue stops (the next start recovers the job) */
    if (!r || (store_fault_transient(f) && f != STORE_FAULT_FULL)) {
        fprintf(stderr, "jobq: job %lld: storing the result: %s\n", (long long)id, err);
        return OUTCOME_SKIPPED;
    }
    if (f == STORE_FAULT_FULL)
        snprintf(why, sizeof why, "could not store the result: %s", store_fault_text(f));
    else
        snprintf(why, sizeof why, "could not store the result: %s", err);
    fprintf(stderr, "jobq: job %lld: %s; recording it failed\n", (long long)id, err);
    if (finish_retrying(w, id, STORE_FAILED, why, NULL, NULL, err, sizeof err) == 0)
        return OUTCOME_FINISHED;
    fprintf(stderr, "jobq: job %lld: recording the failure: %s\n", (long long)id, err);
    return OUTCOME_SKIPPED;
}

/* Runs job id to a final status, or puts it back to queued when the queue stops under it. */
static worker_outcome run_job(jobq_worker *w, int64_t id)
{
    jobq *q = w->q;
    char err[512], why[1600];
    store_job row = {0};
    job *j = NULL;
    ctc_sim_result *r = NULL;
    char *metrics = NULL;
    worker_outcome outcome = OUTCOME_SKIPPED;

    /* a stop between the pop and here leaves the job queued, as it is stored */
    if (atomic_load(&q->stopping) && !q->shared) return OUTCOME_SKIPPED;
    /* a shared queue's claim has marked it running already */
    int rc = q->shared ? 0 : start_retrying(w, id, err, sizeof err);
    if (rc == 1) return OUTCOME_SKIPPED; /* cancelled or deleted meanwhile */
    if (rc != 0) {
        fprintf(stderr, "jobq: job %lld: marking it running: %s\n", (long long)id, err);
        return OUTCOME_SKIPPED;
    }

    /* the stored spec, validated at submission; it should parse again */
    rc = get_retrying(w, id, &row, err, sizeof err);
    if (rc == 1) goto cleanup; /* deleted under us: nothing to record */
    if (rc != 0) {
        snprintf(why, sizeof why, "reading the job: %s", err);
        outcome = finish(w, id, STORE_FAILED, why, NULL, NULL);
        goto cleanup;
    }
    job_error jerr;
    const char *spec = row.spec ? row.spec : "";
    if (job_parse(spec, strlen(spec), &j, &jerr) != 0) {
        snprintf(why, sizeof why, "the stored job no longer parses: %s%s%.600s", jerr.field,
                 jerr.field[0] ? ": " : "", jerr.message);
        outcome = finish(w, id, STORE_FAILED, why, NULL, NULL);
        goto cleanup;
    }

    /* the configured limit caps the job's own */
    double cap = q->config.job_time_limit;
    if (cap > 0 && (j->spec.wall_limit <= 0 || cap < j->spec.wall_limit)) j->spec.wall_limit = cap;

    /* cancelled between the pop and here: nothing ran, nothing to keep */
    if (atomic_load(&w->cancel)) {
        outcome = finish(w, id, STORE_CANCELLED, "cancelled before it started", NULL, NULL);
        goto cleanup;
    }

    w->job_id = id;
    w->lost = 0;
    w->last_progress = monotonic_now();
    ctc_sim_hooks hooks = {.ctx = w,
                           .progress = hook_progress,
                           .cancelled = hook_cancelled,
                           .recorded = hook_recorded};
    if (ctc_sim_run(&j->spec, &hooks, &r, err, sizeof err) != CTC_OK) {
        outcome = finish(w, id, STORE_FAILED, err, NULL, NULL);
        goto cleanup;
    }

    /* a shared queue's lease taken over: the job's result is its new holder's */
    if (w->lost) goto cleanup;
    /* stopped by jobq_stop rather than by a cancel: back to queued, to restart from t = 0 */
    if (r->status == CTC_RUN_CANCELLED && !atomic_load(&w->cancel) && atomic_load(&q->stopping)) {
        if (store_requeue(w->db, id, err, sizeof err) == 0) {
            outcome = OUTCOME_REQUEUED;
        } else {
            /* still running in the database: the next start recovers it all the same */
            fprintf(stderr, "jobq: job %lld: putting it back to queued: %s\n", (long long)id, err);
        }
        goto cleanup;
    }

    /* a run that stopped early keeps how far it got (the throttled progress writes may not have
       said it): the job list shows it; a failed write leaves the last one, a hint as ever */
    if (r->status != CTC_RUN_DONE && j->spec.duration > 0 && isfinite(r->metrics.t_end)) {
        double reached = fmin(1, fmax(0, r->metrics.t_end / j->spec.duration));
        (void)store_progress(w->db, id, reached, err, sizeof err);
    }

    cJSON *m = result_metrics_json(r, j);
    metrics = m ? cJSON_PrintUnformatted(m) : NULL;
    cJSON_Delete(m);
    outcome = finish(w, id, store_status_of(r->status), r->message, metrics, r);

cleanup:
    cJSON_free(metrics);
    live_end(w); /* after finish stored the series: a reader cut off here finds it there */
    ctc_sim_result_free(r);
    job_free(j);
    store_job_clear(&row);
    return outcome;
}

/* ---- the workers ---- */

static void *worker_main(void *arg)
{
    jobq_worker *w = arg;
    jobq *q = w->q;
    pthread_mutex_lock(&q->lock);
    for (;;) {
        /* wait while empty; stop without taking more once stopping */
        while (waiting(q) == 0 && !atomic_load(&q->stopping)) pthread_cond_wait(&q->work, &q->lock);
        if (atomic_load(&q->stopping)) break;
        int64_t id = next_job(q, &w->family);
        w->running = id;
        atomic_store(&w->cancel, 0);
        pthread_mutex_unlock(&q->lock);

        worker_outcome outcome = run_job(w, id);
        if (q->config.left) q->config.left(q->config.left_arg, id);

        /* the slot is free again; jobq_wait may be waiting for this job */
        pthread_mutex_lock(&q->lock);
        w->running = 0;
        w->family = 0;
        if (outcome == OUTCOME_FINISHED) q->done++;
        pthread_cond_broadcast(&q->finished);
    }
    pthread_mutex_unlock(&q->lock);
    return NULL;
}

/* Sleeps up to seconds in slices, returning early when the queue stops. */
static void pause_unless_stopping(jobq *q, double seconds)
{
    for (double left = seconds; left > 0 && !atomic_load(&q->stopping); left -= JOBQ_RETRY_SLICE) {
        double slice = left < JOBQ_RETRY_SLICE ? left : JOBQ_RETRY_SLICE;
        struct timespec ts = {.tv_sec = 0, .tv_nsec = (long)(slice * 1e9)};
        nanosleep(&ts, NULL);
    }
}

static void ignore_note(void *arg, int64_t id, int status)
{
    (void)arg, (void)id, (void)status;
}

/* A worker of a shared queue: claims, runs, and claims again; idle, it waits for a notification
 * or JOBQ_CLAIM_IDLE s. A claim that fails for a transient fault (the connection lost, say)
 * pauses claiming, the pause doubling from JOBQ_RETRY_FIRST to JOBQ_RETRY_MAX; the next claim
 * reconnects. */
static void *claim_main(void *arg)
{
    jobq_worker *w = arg;
    jobq *q = w->q;
    char err[512];
    int failures = 0;
    while (!atomic_load(&q->stopping)) {
        int64_t id = 0;
        int cancel = 0;
        int rc = store_pg_claim(w->db, q->config.lease_s, &id, &cancel, err, sizeof err);
        if (rc < 0) {
            if (failures % JOBQ_RETRY_LOG == 0)
                fprintf(stderr, "jobq: claiming a job (try %d, paused): %s\n", failures + 1, err);
            double pause = JOBQ_RETRY_FIRST * ldexp(1.0, failures < 30 ? failures : 30);
            if (!store_fault_transient(store_last_fault(w->db)) || pause > JOBQ_RETRY_MAX)
                pause = JOBQ_RETRY_MAX;
            failures++;
            pause_unless_stopping(q, pause);
            continue;
        }
        if (failures > 0) fprintf(stderr, "jobq: claiming again after %d failed tries\n", failures);
        failures = 0;
        if (rc == 1) {
            /* nothing to claim: a notification (a new job, a change) or the idle time */
            if (store_pg_notifications(w->db, JOBQ_CLAIM_IDLE, ignore_note, NULL, err, sizeof err) <
                0) {
                fprintf(stderr, "jobq: waiting for jobs (paused): %s\n", err);
                failures++;
                pause_unless_stopping(q, JOBQ_RETRY_FIRST);
            }
            continue;
        }
        pthread_mutex_lock(&q->lock);
        w->running = id;
        atomic_store(&w->cancel, cancel);
        pthread_mutex_unlock(&q->lock);

        worker_outcome outcome = run_job(w, id);

        pthread_mutex_lock(&q->lock);
        w->running = 0;
        if (outcome == OUTCOME_FINISHED) q->done++;
        pthread_cond_broadcast(&q->finished);
        pthread_mutex_unlock(&q->lock);
    }
    return NULL;
}

/* Position of id among the jobs followed here, or -1 (caller holds q->lock). */
static int pending_find(const jobq *q, int64_t id)
{
    for (int i = 0; i < q->npending; i++)
        if (q->pending[i] == id) return i;
    return -1;
}

/* Stops following id: 1 when it was followed (the caller calls `left`), else 0. */
static int pending_drop(jobq *q, int64_t id)
{
    pthread_mutex_lock(&q->lock);
    int pos = pending_find(q, id);
    if (pos >= 0) {
        q->pending[pos] = q->pending[--q->npending];
        pthread_cond_broadcast(&q->finished);
    }
    pthread_mutex_unlock(&q->lock);
    return pos >= 0;
}

/* Position of an entry of id among the watched jobs, or -1 (caller holds q->lock). */
static int watched_find(const jobq *q, int64_t id)
{
    for (int i = 0; i < q->nwatched; i++)
        if (q->watched[i] == id) return i;
    return -1;
}

/* Adds one entry of id to the watched jobs; 0, or -1 out of memory (caller holds q->lock). */
static int watched_add(jobq *q, int64_t id)
{
    if (q->nwatched == q->cap_watched) {
        int cap = q->cap_watched ? 2 * q->cap_watched : 16;
        int64_t *grown = realloc(q->watched, (size_t)cap * sizeof *grown);
        if (!grown) return -1;
        q->watched = grown, q->cap_watched = cap;
    }
    q->watched[q->nwatched++] = id;
    return 0;
}

/* Removes one entry of id from the watched jobs, if any (caller holds q->lock). */
static void watched_remove_one(jobq *q, int64_t id)
{
    int pos = watched_find(q, id);
    if (pos >= 0) q->watched[pos] = q->watched[--q->nwatched];
}

/* Drops every entry of id, a job seen final, and wakes its waiters. */
static void watched_drop(jobq *q, int64_t id)
{
    pthread_mutex_lock(&q->lock);
    int dropped = 0;
    for (int pos; (pos = watched_find(q, id)) >= 0; dropped = 1)
        q->watched[pos] = q->watched[--q->nwatched];
    if (dropped) pthread_cond_broadcast(&q->finished);
    pthread_mutex_unlock(&q->lock);
}

/* a notification on the listener's connection: a job that reached a final status leaves */
static void listener_note(void *arg, int64_t id, int status)
{
    jobq *q = arg;
    if (status < STORE_DONE) return;
    watched_drop(q, id);
    if (pending_drop(q, id) && q->config.left) q->config.left(q->config.left_arg, id);
}

/* One query for the statuses of the jobs followed and watched here; those final or gone leave.
 * 0 or -1. */
static int listener_reconcile(jobq *q, store *db, char *err, size_t errlen)
{
    pthread_mutex_lock(&q->lock);
    int n = q->npending + q->nwatched;
    int64_t *ids = n ? malloc((size_t)n * sizeof *ids) : NULL;
    int *st = n ? malloc((size_t)n * sizeof *st) : NULL;
    if (ids) {
        memcpy(ids, q->pending, (size_t)q->npending * sizeof *ids);
        if (q->nwatched) memcpy(ids + q->npending, q->watched, (size_t)q->nwatched * sizeof *ids);
    }
    pthread_mutex_unlock(&q->lock);
    int rc = 0;
    if (n && (!ids || !st)) {
        snprintf(err, errlen, "out of memory");
        rc = -1;
    } else if (n && store_pg_statuses(db, ids, n, st, err, errlen) != 0) {
        rc = -1;
    }
    for (int i = 0; rc == 0 && i < n; i++)
        if (st[i] < 0 || st[i] >= STORE_DONE) listener_note(q, ids[i], STORE_DONE);
    free(ids);
    free(st);
    return rc;
}

/* The listener of a shared queue (config.listen): wakes jobq_wait and calls `left` for the jobs
 * submitted here as their notifications come, reading their statuses every JOBQ_RECONCILE s and
 * after its connection was lost (reconnecting with the retry pause). */
static void *listener_main(void *arg)
{
    jobq *q = arg;
    char err[512];
    store *db = NULL;
    int failures = 0;
    double last = 0;
    while (!atomic_load(&q->stopping)) {
        if (!db && (store_open(q->db_path, &db, err, sizeof err) != 0 ||
                    store_pg_listen(db, err, sizeof err) != 0)) {
            store_close(db);
            db = NULL;
        }
        int ok = db != NULL;
        /* listening from here on: what finished before is read, once now and then regularly */
        if (ok && (last == 0 || monotonic_now() - last >= JOBQ_RECONCILE)) {
            ok = listener_reconcile(q, db, err, sizeof err) == 0;
            last = monotonic_now();
        }
        if (ok) ok = store_pg_notifications(db, 0.25, listener_note, q, err, sizeof err) >= 0;
        if (ok) {
            failures = 0;
            continue;
        }
        if (failures % JOBQ_RETRY_LOG == 0)
            fprintf(stderr, "jobq: listening for finished jobs (try %d): %s\n", failures + 1, err);
        failures++;
        last = 0; /* read the statuses again once back */
        double pause = JOBQ_RETRY_FIRST * ldexp(1.0, failures < 30 ? failures : 30);
        pause_unless_stopping(q, pause < JOBQ_RETRY_MAX ? pause : JOBQ_RETRY_MAX);
    }
    store_close(db);
    return NULL;
}

/* Stops and joins the started workers, closes every connection and frees q (jobq_stop, and a
 * jobq_start that failed half way). */
static void jobq_free(jobq *q)
{
    if (q->sync_ready) {
        pthread_mutex_lock(&q->lock);
        atomic_store(&q->stopping, 1);
        pthread_cond_broadcast(&q->work);
        pthread_cond_broadcast(&q->finished);
        pthread_mutex_unlock(&q->lock);
    }
    for (int i = 0; i < q->nstarted; i++) pthread_join(q->workers[i].thread, NULL);
    if (q->listener_started) pthread_join(q->listener, NULL);
    for (int i = 0; q->workers && i < q->config.workers; i++) store_close(q->workers[i].db);
    store_close(q->ctl);
    free(q->pending);
    free(q->watched);
    if (q->sync_ready) {
        pthread_mutex_destroy(&q->ctl_lock);
        pthread_cond_destroy(&q->finished);
        pthread_cond_destroy(&q->work);
        pthread_mutex_destroy(&q->lock);
    }
    free(q->workers);
    for (int i = 0; i < q->nlanes; i++) free(q->lanes[i].ids);
    free(q->lanes);
    free(q->ring);
    free(q->db_path);
    free(q);
}

/* The lock and the two conditions; `finished` waits on the monotonic clock. */
static int init_sync(jobq *q, char *err, size_t errlen)
{
    pthread_condattr_t attr;
    int rc = pthread_condattr_init(&attr);
    if (rc != 0) return fail(err, errlen, "condition attributes: %s", strerror(rc));
    rc = pthread_condattr_setclock(&attr, CLOCK_MONOTONIC);
    if (rc != 0) {
        pthread_condattr_destroy(&attr);
        return fail(err, errlen, "condition clock: %s", strerror(rc));
    }
    rc = pthread_mutex_init(&q->lock, NULL);
    if (rc == 0 && (rc = pthread_mutex_init(&q->ctl_lock, NULL)) != 0)
        pthread_mutex_destroy(&q->lock);
    if (rc == 0) {
        rc = pthread_cond_init(&q->work, NULL);
        if (rc == 0) {
            rc = pthread_cond_init(&q->finished, &attr);
            if (rc != 0) pthread_cond_destroy(&q->work);
        }
        if (rc != 0) {
            pthread_mutex_destroy(&q->ctl_lock);
            pthread_mutex_destroy(&q->lock);
        }
    }
    pthread_condattr_destroy(&attr);
    if (rc != 0) return fail(err, errlen, "queue lock: %s", strerror(rc));
    q->sync_ready = 1;
    return 0;
}

int jobq_start(const jobq_config *config, jobq **out, char *err, size_t errlen)
{
    *out = NULL;
    if (!config->db_path || !config->db_path[0])
        return fail(err, errlen, "db_path must name the database file");
    int shared = store_pg_url(config->db_path);
    if (config->workers < (shared ? 0 : 1))
        return fail(err, errlen, "workers must be >= %d (got %d)", shared ? 0 : 1, config->workers);
    if (shared && !(config->lease_s >= 1 && config->lease_s <= 86400))
        return fail(err, errlen, "the lease must be from 1 to 86400 s (got %g s)", config->lease_s);
    if (config->max_queue < 1)
        return fail(err, errlen, "max_queue must be >= 1 (got %d)", config->max_queue);
    if (!(config->job_time_limit >= 0) || isinf(config->job_time_limit))
        return fail(err, errlen, "job_time_limit must be >= 0 and finite (got %g s)",
                    config->job_time_limit);

    int rc = -1;
    store *db = NULL;
    int64_t *ids = NULL, *families = NULL;
    int nids = 0;
    char why[512];
    jobq *q = calloc(1, sizeof *q);
    if (!q) return fail(err, errlen, "out of memory");
    q->config = *config;
    atomic_init(&q->stopping, 0);
    q->db_path = strdup(config->db_path);
    q->shared = shared;
    q->workers = calloc((size_t)(config->workers > 0 ? config->workers : 1), sizeof *q->workers);
    if (!q->db_path || !q->workers) {
        fail(err, errlen, "out of memory");
        goto cleanup;
    }
    q->config.db_path = q->db_path;
    if (init_sync(q, err, errlen) != 0) goto cleanup;

    /* recovery: what the database holds as queued or running is queued again, oldest first. A
       lock held elsewhere is waited for (JOBQ_START_TRIES), so a server restarted under a backup
       starts late rather than not at all; any other failure fails the start at once. */
    for (int attempt = 1;; attempt++) {
        if (store_open(q->db_path, &db, why, sizeof why) == 0 &&
            store_recover(db, &ids, &nids, why, sizeof why) == 0)
            break;
        /* store_open's failures carry SQLite's message; store_recover's fault is the store's */
        int locked = db ? store_last_fault(db) == STORE_FAULT_LOCKED
                        : strstr(why, store_fault_text(STORE_FAULT_LOCKED)) != NULL;
        store_close(db);
        db = NULL;
        if (!locked || attempt >= JOBQ_START_TRIES) {
            fail(err, errlen, "recovering jobs: %s", why);
            goto cleanup;
        }
        fprintf(stderr, "jobq: recovering jobs (try %d of %d, waiting for the lock): %s\n", attempt,
                JOBQ_START_TRIES, why);
        struct timespec pause = {.tv_sec = 1, .tv_nsec = 0};
        while (nanosleep(&pause, &pause) != 0 && errno == EINTR) continue;
    }
    /* a shared queue's jobs stay in the database, which the workers claim from */
    if (shared) nids = 0;
    /* the members of families go back to their family's lane, the others to the ring */
    families = calloc(nids > 0 ? (size_t)nids : 1, sizeof *families);
    if (!families) {
        fail(err, errlen, "out of memory for %d recovered jobs", nids);
        goto cleanup;
    }
    if (nids > 0 && store_job_families(db, ids, nids, families, why, sizeof why) != 0) {
        fail(err, errlen, "recovering jobs: %s", why);
        goto cleanup;
    }
    int singles = 0;
    for (int i = 0; i < nids; i++) singles += families[i] == 0;
    q->cap = singles > config->max_queue ? singles : config->max_queue;
    q->ring = malloc((size_t)q->cap * sizeof *q->ring);
    if (!q->ring) {
        fail(err, errlen, "out of memory for a queue of %d jobs", q->cap);
        goto cleanup;
    }
    for (int i = 0; i < nids; i++) {
        if (families[i] == 0) {
            ring_push(q, ids[i]);
        } else if (lane_push(q, families[i], &ids[i], 1) != 0) {
            fail(err, errlen, "out of memory for the recovered members of family %lld",
                 (long long)families[i]);
            goto cleanup;
        }
    }
    if (shared) {
        q->ctl = db; /* recovery's connection serves space, cancel and counts from here on */
        db = NULL;
    }

    /* one connection per worker, opened here so that a failure fails the start */
    for (int i = 0; i < config->workers; i++) {
        jobq_worker *w = &q->workers[i];
        w->q = q;
        atomic_init(&w->cancel, 0);
        if (store_open(q->db_path, &w->db, why, sizeof why) != 0 ||
            (config->db_max_size > 0 &&
             store_set_max_size(w->db, config->db_max_size, why, sizeof why) != 0)) {
            fail(err, errlen, "worker %d: %s", i, why);
            goto cleanup;
        }
        store_set_busy_timeout(w->db, JOBQ_BUSY_MS);
        store_attach(w->db, config->health);
        if (shared && store_pg_listen(w->db, why, sizeof why) != 0) {
            fail(err, errlen, "worker %d: %s", i, why);
            goto cleanup;
        }
    }

    /* room for the log on a full disk, so that DELETE can still free space: as much of
     * JOBQ_LOG_RESERVE as the disk gives (the log lives while the workers' connections do) */
    long long reserve = JOBQ_LOG_RESERVE;
    while (!shared && store_reserve(q->workers[0].db, reserve, why, sizeof why) != 0 &&
           reserve > JOBQ_LOG_RESERVE_MIN)
        reserve /= 2;

    /* the threads inherit the caller's signal mask (main.c blocks SIGINT and SIGTERM first) */
    for (int i = 0; i < config->workers; i++) {
        int e = pthread_create(&q->workers[i].thread, NULL, shared ? claim_main : worker_main,
                               &q->workers[i]);
        if (e != 0) {
            fail(err, errlen, "starting worker %d: %s", i, strerror(e));
            break;
        }
        pthread_mutex_lock(&q->lock);
        q->nstarted++;
        pthread_mutex_unlock(&q->lock);
    }
    if (q->nstarted < config->workers) goto cleanup;
    if (shared && config->listen) {
        int e = pthread_create(&q->listener, NULL, listener_main, q);
        if (e != 0) {
            fail(err, errlen, "starting the listener: %s", strerror(e));
            goto cleanup;
        }
        q->listener_started = 1;
    }

    *out = q;
    q = NULL;
    rc = 0;

cleanup:
    if (q) jobq_free(q);
    store_close(db);
    free(ids);
    free(families);
    return rc;
}

/* a shared queue's submission: the job is in the database already (its insert notified the
 * workers); this process follows it when it listens */
static int shared_submit(jobq *q, int64_t id)
{
    int rc = 0;
    pthread_mutex_lock(&q->lock);
    if (atomic_load(&q->stopping)) {
        rc = 2;
    } else if (q->config.listen && q->npending == q->cap_pending) {
        int cap = q->cap_pending ? 2 * q->cap_pending : 64;
        int64_t *grown = cap > 0 ? realloc(q->pending, (size_t)cap * sizeof *grown) : NULL;
        if (grown)
            q->pending = grown, q->cap_pending = cap;
        else
            rc = 3;
    }
    if (rc == 0 && q->config.listen) q->pending[q->npending++] = id;
    pthread_mutex_unlock(&q->lock);
    return rc;
}

/* a shared queue's counts of the whole database, read on the control connection; 0 or -1 */
static int shared_counts(jobq *q, long counts[STORE_NSTATUS])
{
    char err[256];
    pthread_mutex_lock(&q->ctl_lock);
    int rc = store_count(q->ctl, counts, err, sizeof err);
    pthread_mutex_unlock(&q->ctl_lock);
    return rc;
}

int jobq_submit(jobq *q, int64_t id)
{
    if (q->shared) return shared_submit(q, id);
    int rc = 0;
    pthread_mutex_lock(&q->lock);
    if (atomic_load(&q->stopping)) {
        rc = 2;
    } else if (q->count >= q->config.max_queue) {
        rc = 1;
    } else {
        ring_push(q, id);
        pthread_cond_signal(&q->work);
    }
    pthread_mutex_unlock(&q->lock);
    return rc;
}

int jobq_submit_family(jobq *q, int64_t family, const int64_t *ids, long n)
{
    int rc = 0;
    pthread_mutex_lock(&q->lock);
    if (q->shared) {
        /* the members are in the database, which the workers claim from in fair turns; they are
           not followed here (jobq_wait watches one while it waits for it) */
        rc = atomic_load(&q->stopping) ? 2 : 0;
    } else if (atomic_load(&q->stopping))
        rc = 2;
    else if (n > 0 && lane_push(q, family, ids, n) != 0)
        rc = -1;
    else
        pthread_cond_broadcast(&q->work);
    pthread_mutex_unlock(&q->lock);
    return rc;
}

int jobq_cancel_family(jobq *q, int64_t family, int64_t **removed, long *n)
{
    int running = 0;
    *removed = NULL;
    *n = 0;
    if (q->shared) {
        /* flagged in the database: the queued members are no longer claimed (the caller records
           them cancelled), the running ones stop at their worker's next heartbeat */
        char err[256];
        pthread_mutex_lock(&q->ctl_lock);
        running = store_pg_request_cancel_family(q->ctl, family, err, sizeof err);
        pthread_mutex_unlock(&q->ctl_lock);
        if (running < 0) fprintf(stderr, "jobq: family %lld: %s\n", (long long)family, err);
        return running < 0 ? 0 : running;
    }
    pthread_mutex_lock(&q->lock);
    jobq_lane *l = lane_of(q, family);
    if (l) {
        /* the lane's ids are handed to the caller, the lane goes */
        if (l->head > 0 && l->count > 0)
            memmove(l->ids, l->ids + l->head, (size_t)l->count * sizeof *l->ids);
        *removed = l->ids;
        *n = l->count;
        q->lane_jobs -= l->count;
        l->ids = NULL;
        l->count = 0;
        lane_drop(q, (int)(l - q->lanes));
        pthread_cond_broadcast(&q->finished);
    }
    for (int i = 0; i < q->nstarted; i++)
        if (q->workers[i].running && q->workers[i].family == family) {
            atomic_store(&q->workers[i].cancel, 1);
            running++;
        }
    pthread_mutex_unlock(&q->lock);
    for (long i = 0; q->config.left && i < *n; i++)
        q->config.left(q->config.left_arg, (*removed)[i]);
    return running;
}

int jobq_space(jobq *q)
{
    if (q->shared) {
        /* the database's queued single jobs against the bound (a family's members are not
           bounded by it, as on SQLite); a failed read lets the insert say why */
        long queued = 0;
        char err[256];
        if (atomic_load(&q->stopping)) return 0;
        pthread_mutex_lock(&q->ctl_lock);
        int rc = store_pg_queued_singles(q->ctl, &queued, err, sizeof err);
        pthread_mutex_unlock(&q->ctl_lock);
        if (rc != 0) return 1;
        long space = q->config.max_queue - queued;
        return space > 0 ? (int)(space < INT_MAX ? space : INT_MAX) : 0;
    }
    pthread_mutex_lock(&q->lock);
    int space = atomic_load(&q->stopping) ? 0 : q->config.max_queue - q->count;
    pthread_mutex_unlock(&q->lock);
    return space > 0 ? space : 0;
}

int jobq_cancel(jobq *q, int64_t id)
{
    if (q->shared) {
        /* flagged in the database: a running job's worker sees it at its next heartbeat, a
           queued one is no longer claimed and the caller records it */
        char err[256];
        pthread_mutex_lock(&q->ctl_lock);
        int rc = store_pg_request_cancel(q->ctl, id, err, sizeof err);
        pthread_mutex_unlock(&q->ctl_lock);
        if (rc < 0) fprintf(stderr, "jobq: job %lld: %s\n", (long long)id, err);
        if (rc == 1 && pending_drop(q, id) && q->config.left)
            q->config.left(q->config.left_arg, id);
        return rc < 0 ? 0 : rc;
    }
    int rc = 0;
    pthread_mutex_lock(&q->lock);
    int pos = ring_find(q, id);
    int in_lane = pos < 0 && lanes_remove(q, id);
    jobq_worker *w = pos < 0 && !in_lane ? slot_find(q, id) : NULL;
    if (pos >= 0 || in_lane) {
        /* the caller records it cancelled; jobq_wait need not wait for it any longer */
        if (pos >= 0) ring_remove(q, pos);
        pthread_cond_broadcast(&q->finished);
        rc = 1;
    } else if (w) {
        /* under the lock, so the flag cannot land on the worker's next job */
        atomic_store(&w->cancel, 1);
        rc = 2;
    }
    pthread_mutex_unlock(&q->lock);
    if (rc == 1 && q->config.left) q->config.left(q->config.left_arg, id);
    return rc;
}

int jobq_live_info(jobq *q, int64_t id, store_series_info *out)
{
    int rc = 1;
    pthread_mutex_lock(&q->lock);
    jobq_worker *w = slot_find(q, id);
    if (w && w->live && w->live_n > 0) {
        const ctc_sim_result *r = w->live;
        memset(out, 0, sizeof *out);
        out->nsamples = w->live_n;
        out->nq = r->nq;
        out->nv = r->nv;
        out->channels = r->channels;
        out->bytes = (int64_t)w->live_n * (int64_t)sizeof(double);
        for (int c = 0; c < CTC_NCHANNELS; c++) {
            out->width[c] = r->ch[c] ? r->width[c] : 0;
            out->bytes += (int64_t)w->live_n * out->width[c] * (int64_t)sizeof(double);
        }
        rc = 0;
    }
    pthread_mutex_unlock(&q->lock);
    return rc;
}

int jobq_shared(const jobq *q)
{
    return q->shared;
}

int jobq_live_read(jobq *q, int64_t id, int channel, uint64_t offset, void *buf, size_t len)
{
    int rc = 1;
    pthread_mutex_lock(&q->lock);
    jobq_worker *w = slot_find(q, id);
    if (w && w->live && channel >= -1 && channel < CTC_NCHANNELS) {
        const ctc_sim_result *r = w->live;
        const double *base = channel < 0 ? r->t : r->ch[channel];
        uint64_t width = channel < 0 ? 1 : (uint64_t)r->width[channel];
        uint64_t size = (uint64_t)w->live_n * width * sizeof(double);
        rc = -1;
        if (base && offset <= size && len <= size - offset) {
            memcpy(buf, (const char *)base + offset, len);
            rc = 0;
        }
    }
    pthread_mutex_unlock(&q->lock);
    return rc;
}

/* The number of waiting jobs ahead of the k-th (0-based) of its place (the ring when self is
   NULL, else lane self) while workers serve every place in turn: k of its own place and
   min(count, k) of each other one (where the turn stands is ignored: at most one job off per
   place). Caller holds q->lock. */
static long ahead_in_turns(const jobq *q, long k, const jobq_lane *self)
{
    long ahead = k;
    if (self != NULL) ahead += q->count < k ? q->count : k;
    for (int i = 0; i < q->nlanes; i++)
        if (&q->lanes[i] != self) ahead += q->lanes[i].count < k ? q->lanes[i].count : k;
    return ahead;
}

int jobq_position(jobq *q, int64_t id)
{
    if (q->shared) {
        /* the database's queue, in the claims' turns */
        char err[256];
        pthread_mutex_lock(&q->ctl_lock);
        int pos = store_pg_queue_position(q->ctl, id, err, sizeof err);
        pthread_mutex_unlock(&q->ctl_lock);
        if (pos < 0) fprintf(stderr, "jobq: job %lld: %s\n", (long long)id, err);
        return pos < 0 ? 0 : pos;
    }
    pthread_mutex_lock(&q->lock);
    long ahead = -1;
    int pos = ring_find(q, id);
    if (pos >= 0) ahead = ahead_in_turns(q, pos, NULL);
    for (int i = 0; ahead < 0 && i < q->nlanes; i++) {
        const jobq_lane *l = &q->lanes[i];
        for (long k = 0; k < l->count; k++)
            if (l->ids[l->head + k] == id) {
                ahead = ahead_in_turns(q, k, l);
                break;
            }
    }
    pthread_mutex_unlock(&q->lock);
    if (ahead < 0) return 0;
    return ahead >= INT_MAX - 1 ? INT_MAX : (int)ahead + 1;
}

/* jobq_wait on a shared queue. A job submitted here is followed already (pending); any other (a
 * family's member, a job another API process took) is watched for this call: its entry is
 * added before its status is read, so the notification of a job finishing after that read
 * drops it, and one finished before is seen by the read. Without a listener nothing is
 * followed: 0 at once. */
static int shared_wait(jobq *q, int64_t id, const struct timespec *deadline)
{
    if (!q->config.listen) return 0;
    pthread_mutex_lock(&q->lock);
    int followed = pending_find(q, id) >= 0;
    int watching = !followed && watched_add(q, id) == 0;
    pthread_mutex_unlock(&q->lock);
    if (!followed && !watching) return 0; /* out of memory: answered as it is */
    if (watching) {
        int status = -1;
        char err[256];
        pthread_mutex_lock(&q->ctl_lock);
        int rc = store_pg_statuses(q->ctl, &id, 1, &status, err, sizeof err);
        pthread_mutex_unlock(&q->ctl_lock);
        if (rc == 0 && (status < 0 || status >= STORE_DONE)) {
            pthread_mutex_lock(&q->lock);
            watched_remove_one(q, id);
            pthread_mutex_unlock(&q->lock);
            return 0;
        }
        /* a failed read: the notification, the listener's next read or the deadline ends it */
    }
    pthread_mutex_lock(&q->lock);
    int here = followed ? pending_find(q, id) >= 0 : watched_find(q, id) >= 0;
    while (here) {
        int e = pthread_cond_timedwait(&q->finished, &q->lock, deadline);
        here = followed ? pending_find(q, id) >= 0 : watched_find(q, id) >= 0;
        if (e == ETIMEDOUT) break;
    }
    if (watching && here) watched_remove_one(q, id);
    pthread_mutex_unlock(&q->lock);
    return here ? 1 : 0;
}

int jobq_wait(jobq *q, int64_t id, double timeout_s)
{
    /* the deadline on the monotonic clock, which `finished` waits on */
    if (!(timeout_s > 0)) timeout_s = 0;
    if (timeout_s > JOBQ_MAX_WAIT) timeout_s = JOBQ_MAX_WAIT;
    struct timespec deadline;
    clock_gettime(CLOCK_MONOTONIC, &deadline);
    double whole = floor(timeout_s);
    deadline.tv_sec += (time_t)whole;
    deadline.tv_nsec += (long)((timeout_s - whole) * 1e9);
    if (deadline.tv_nsec >= 1000000000L) {
        deadline.tv_sec++;
        deadline.tv_nsec -= 1000000000L;
    }

    if (q->shared) return shared_wait(q, id, &deadline);
    pthread_mutex_lock(&q->lock);
    int here = job_here(q, id);
    while (here) {
        int e = pthread_cond_timedwait(&q->finished, &q->lock, &deadline);
        here = job_here(q, id);
        if (e == ETIMEDOUT) break;
    }
    pthread_mutex_unlock(&q->lock);
    return here ? 1 : 0;
}

void jobq_get_stats(jobq *q, jobq_stats *out)
{
    pthread_mutex_lock(&q->lock);
    out->workers = q->config.workers;
    out->busy = 0;
    for (int i = 0; i < q->nstarted; i++) out->busy += q->workers[i].running != 0;
    out->queued = (int)waiting(q);
    out->done = q->done;
    pthread_mutex_unlock(&q->lock);
    long counts[STORE_NSTATUS];
    if (q->shared && shared_counts(q, counts) == 0) {
        out->busy = (int)counts[STORE_RUNNING];
        out->queued = (int)counts[STORE_QUEUED];
    }
}

void jobq_stop(jobq *q)
{
    if (!q) return;
    jobq_free(q);
}
