/*
 * store_pg.h - the PostgreSQL backend of store.h, and what only a shared job queue needs: claims
 * under a lease, heartbeats and notifications.
 *
 * store_open hands a path that store_pg_url accepts ("postgres://..." or "postgresql://...", a
 * libpq connection URI) to store_pg_open; every public store.h call on such a store forwards to
 * the store_pg_* function of the same name, which keeps the store.h contract with the
 * differences listed here:
 *   - one store is one libpq connection, opened with connect_timeout 5 s and lock_timeout
 *     STORE_PG_LOCK_MS; the busy timeout of store_set_busy_timeout is recorded (a connection set
 *     to 0 reports no lock failures to health) but PostgreSQL's own lock_timeout is not changed;
 *   - store_set_max_size accepts only 0 (PostgreSQL's size is the server's business), and
 *     store_reserve fails ("PostgreSQL keeps its own write-ahead log");
 *   - store_recover queues only the running jobs whose lease has expired (a running job under a
 *     live lease belongs to a live worker, possibly on another machine), and returns the ids of
 *     every queued job;
 *   - store_count_vm_steps is 0 (SQLite's measure; job_counts is read the same way);
 *   - faults come from SQLSTATE: connection lost (class 08, 57P01-57P03, or a connection libpq
 *     reports bad) is STORE_FAULT_IO, serialization failure, deadlock, lock or connection-slot
 *     shortage (40001, 40P01, 55P03, 53300) STORE_FAULT_LOCKED, disk full (53100)
 *     STORE_FAULT_FULL, a read-only transaction (25006) STORE_FAULT_READONLY, anything else
 *     STORE_FAULT_OTHER; they reach the same store_health. A call that finds its connection
 *     lost reconnects first (PQreset, then the session's settings and LISTEN again), so a
 *     caller that retries transient faults with backoff reconnects with backoff.
 *
 * Schema: the table schema_version(version) holds STORE_PG_SCHEMA_VERSION and the migrations run
 * in one transaction under an advisory lock, so processes that start together migrate once; a
 * database with tables but no schema_version, or a newer version, is refused untouched. The
 * tables are SQLite's (store.h), with BIGINT ids, DOUBLE PRECISION reals and BYTEA data, plus
 * three columns of jobs for claims: worker (the claim's owner), lease_until (s since the epoch on
 * the database's clock) and cancel_requested. Version 2 adds job_counts, kept by a trigger that
 * also sends NOTIFY ctcsim_jobs with "ID STATUS" on every insert and status change (delivered at
 * commit, so a listener never hears of a status it cannot read). Version 3 adds SQLite's
 * families (the families table, jobs' family_id, family_member, family_replica and
 * family_values; the jobs stored before keep their rows, with no family), and the claims' lanes
 * table (lane: 0 for the single jobs, else a family id; served: when a job of it was last
 * claimed, on the database's clock). Version 4 adds SQLite's jobs_by_family_status (family_id,
 * status), which a family's status counts read with an index-only scan. A family is stored
 * with one INSERT of all its members (json_to_recordset), so 10,000 members cost one round trip.
 *
 * Claims. A worker claims the oldest job that is queued, or running under a lease that has
 * expired, with SELECT ... FOR UPDATE SKIP LOCKED (concurrent claims never wait for each other
 * nor take the same job), marking it running under an owner token unique to the claim and a lease
 * of lease_s. While it runs the job it calls store_pg_heartbeat, which renews the lease and says
 * whether a cancel was requested or the lease was lost. store_finish, store_progress and
 * store_requeue of a running job succeed only for the connection whose claim holds it (the job's
 * worker column is its token), so a worker whose lease expired and was claimed elsewhere cannot
 * store a second result: exactly one result per job.
 *
 * Not thread-safe: one store per thread, as store.h.
 */
#ifndef STORE_PG_H
#define STORE_PG_H

#include <stddef.h>
#include <stdint.h>

#include "store.h"

#define STORE_PG_SCHEMA_VERSION 4
#define STORE_PG_LOCK_MS 5000          /* lock_timeout of every connection */
#define STORE_PG_CHANNEL "ctcsim_jobs" /* the NOTIFY channel of job status changes */

typedef struct store_pg store_pg;

/* 1 when path names a PostgreSQL database (a postgres:// or postgresql:// URI), else 0. */
int store_pg_url(const char *path);

/* The URI with its password replaced by "***", for messages and logs (out, outlen bytes). */
void store_pg_redact(const char *url, char *out, size_t outlen);

/* The PostgreSQL connection of a store, or NULL for an SQLite one. */
store_pg *store_pg_of(store *s);

/* Claims a job for lease_s seconds (> 0): a running job whose lease expired if there is one,
 * else the oldest queued job of the lane served least recently (lanes: the single jobs, and each
 * family; the lanes table records when each last had a job claimed), so that a family's members
 * and the single jobs take turns across every worker process, as jobq's lanes do on SQLite.
 * *id receives it and *cancel whether a cancel was requested before it started. Returns 0 with a
 * job, 1 when there is none, -1 on error (store_last_fault says whether to retry). */
int store_pg_claim(store *s, double lease_s, int64_t *id, int *cancel, char *err, size_t errlen);

/* Renews the lease of the claimed job id for lease_s and records its progress (0..1). Returns 0
 * (with *cancel: a cancel was requested), 1 when the claim is lost (the lease expired and another
 * worker took the job, or it was deleted), -1 on error. */
int store_pg_heartbeat(store *s, int64_t id, double progress, double lease_s, int *cancel,
                       char *err, size_t errlen);

/* Asks the worker holding job id to stop: 2 when the job is running (its worker will record it
 * cancelled at its next heartbeat), 1 when it is queued (flagged; the caller records it
 * cancelled), 0 when it is neither, -1 on error. */
int store_pg_request_cancel(store *s, int64_t id, char *err, size_t errlen);

/* Asks the workers holding family id's running members to stop, and keeps its queued members
 * from being claimed (the caller records them cancelled, store_family_cancel): the number of
 * running members flagged, or -1 on error. */
int store_pg_request_cancel_family(store *s, int64_t id, char *err, size_t errlen);

/* Job id's place in the database's queue, as the claims' fair turns serve it: k jobs of its own
 * lane (the single jobs, or its family) are ahead of it, and min(k, count) of each other lane's,
 * so the place is 1 + k + that sum (where the turn stands is not counted: at most one job per
 * lane off). 0 when the job is not claimable (running, finished, or its cancel asked), -1 on
 * error. */
int store_pg_queue_position(store *s, int64_t id, char *err, size_t errlen);

/* The single jobs (no family's members) queued and claimable, into *n: what a server's
 * max_queue bounds (a family's members are bounded by --max-family instead, as on SQLite). */
int store_pg_queued_singles(store *s, long *n, char *err, size_t errlen);

/* Starts listening on STORE_PG_CHANNEL (again after every reconnect). */
int store_pg_listen(store *s, char *err, size_t errlen);

/* Waits up to timeout_s for notifications and calls fn(arg, id, status) for each "ID STATUS"
 * received (status as store_status_parse reads it). Returns the number received, or -1 when
 * the connection failed (reconnected at the next call). */
int store_pg_notifications(store *s, double timeout_s,
                           void (*fn)(void *arg, int64_t id, int status), void *arg, char *err,
                           size_t errlen);

/* The final-or-not status of each of n ids: out[i] = its status, or -1 when there is no such job.
 * 0 or -1. */
int store_pg_statuses(store *s, const int64_t *ids, int n, int *out, char *err, size_t errlen);

/* ---- the store.h calls, forwarded by store.c (same contracts, see above) ---- */
int store_pg_open(const char *url, store_pg **out, char *err, size_t errlen);
void store_pg_close(store_pg *p);
void store_pg_set_busy_timeout(store_pg *p, int ms);
int store_pg_set_max_size(store_pg *p, long long max_bytes, char *err, size_t errlen);
store_fault store_pg_last_fault(const store_pg *p);
void store_pg_attach(store_pg *p, store_health *h);
int store_pg_probe(store_pg *p, char *err, size_t errlen);
int store_pg_reserve(store_pg *p, long long bytes, char *err, size_t errlen);
int store_pg_insert(store_pg *p, long max_queued, const char *name, const char *preset, int nbodies,
                    int nv, const char *controller, const char *spec, int64_t *id, char *err,
                    size_t errlen);
int store_pg_recover(store_pg *p, int64_t **ids, int *n, char *err, size_t errlen);
int store_pg_start(store_pg *p, int64_t id, char *err, size_t errlen);
int store_pg_progress(store_pg *p, int64_t id, double progress, char *err, size_t errlen);
int store_pg_requeue(store_pg *p, int64_t id, char *err, size_t errlen);
int store_pg_finish(store_pg *p, int64_t id, store_status status, const char *message,
                    const char *metrics, const ctc_sim_result *r, char *err, size_t errlen);
int store_pg_get(store_pg *p, int64_t id, store_job *out, char *err, size_t errlen);
int store_pg_list(store_pg *p, int64_t before, int status, int limit, store_job **rows, int *n,
                  char *err, size_t errlen);
int store_pg_get_series(store_pg *p, int64_t id, ctc_sim_result **out, char *err, size_t errlen);
int store_pg_get_series_info(store_pg *p, int64_t id, store_series_info *out, char *err,
                             size_t errlen);
int store_pg_series_begin(store_pg *p, char *err, size_t errlen);
int store_pg_series_read(store_pg *p, int64_t id, int channel, uint64_t offset, void *buf,
                         size_t len, char *err, size_t errlen);
void store_pg_series_end(store_pg *p);
int store_pg_delete(store_pg *p, int64_t id, char *err, size_t errlen);
int store_pg_count(store_pg *p, long counts[STORE_NSTATUS], char *err, size_t errlen);
int store_pg_search(store_pg *p, int64_t before, const store_filter *f, int limit, store_job **rows,
                    int *n, char *err, size_t errlen);
int store_pg_family_insert(store_pg *p, const char *name, const char *spec, const char *axes,
                           const store_new_member *members, long n, int64_t *family_id,
                           int64_t *ids, char *err, size_t errlen);
int store_pg_family_get(store_pg *p, int64_t id, store_family *out, char *err, size_t errlen);
int store_pg_family_list(store_pg *p, int64_t before, int limit, store_family **rows, int *n,
                         char *err, size_t errlen);
int store_pg_family_members(store_pg *p, int64_t id, store_member **rows, long *n, char *err,
                            size_t errlen);
int store_pg_family_active(store_pg *p, int64_t id, int64_t **ids, long *n, char *err,
                           size_t errlen);
int store_pg_family_cancel(store_pg *p, int64_t id, const char *message, long *n, char *err,
                           size_t errlen);
int store_pg_family_delete(store_pg *p, int64_t id, char *err, size_t errlen);
int store_pg_job_families(store_pg *p, const int64_t *ids, int n, int64_t *families, char *err,
                          size_t errlen);

/* store.c's health reports, for the PostgreSQL calls (store.h, "Health") */
void store_health_report_fault(store_health *h, store_fault f, const char *message);
void store_health_report_ok(store_health *h, int room);

/* store.c's series checks, shared so both backends refuse a damaged row with the same message */
int store_series_check_row(int64_t id, int *nv, int *nind, int *nsamples, const char *name,
                           int width, int64_t row_nsamples, int64_t bytes, int *c, char *err,
                           size_t errlen);

/* store.c's list summaries: *final_out = max |x| over the JSON array e_final, *rms_out = the
 * root of the mean of x^2 over the JSON array e_rms (either NULL or not an array: NaN; entries
 * that are not finite numbers are left out), so both backends list the same e_final and e_rms */
void store_summarise_errors(const char *e_final, const char *e_rms, double *final_out,
                            double *rms_out);

#endif
