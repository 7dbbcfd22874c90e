/*
 * routes.h - the service's endpoints: one handler per route (routes.c). This comment is the API's
 * reference; api/openapi.yaml documents the same for clients and is served at /api/openapi.yaml.
 *
 * Conventions. Bodies are JSON (POST needs Content-Type application/json, charset allowed, else
 * 415). Ids are positive integers (else 400 INVALID_ID, field "id"). Times are ISO 8601 UTC
 * strings with milliseconds ("2026-11-21T02:30:00.123Z") or null. Coordinates and joints are
 * numbered from 0, as in the job's arrays. A text reply (JSON, CSV) goes in gzip to a client whose
 * Accept-Encoding admits it when it is HTTP_GZIP_MIN bytes or more or streamed, and says "Vary:
 * Accept-Encoding" (http_gzip.h); a float32 series goes as it is. Errors are {"error": {"code",
 * "message", "field"}} (field "" when none) with these statuses and codes:
 *   400 INVALID_JSON, MISSING_FIELD, UNKNOWN_FIELD, INVALID_FIELD, LIMIT_EXCEEDED (job_json.h),
 *       INVALID_ID, INVALID_QUERY (field = the query parameter), MISSING_HOST (an HTTP/1.1
 *       request without Host), BAD_FRAMING (field = the header: two Content-Length or
 *       Transfer-Encoding headers, both, or a Content-Length not a number; http.c)
 *   401 UNAUTHORIZED (with --token: POST and DELETE need "Authorization: Bearer TOKEN")
 *   404 NOT_FOUND (route, job or file), UNKNOWN_PRESET (400 inside a job body, 404 as a path)
 *   405 METHOD_NOT_ALLOWED (with Allow)   409 NOT_FINISHED (series of an unfinished job),
 *       ALREADY_FINISHED (a cancel of a finished job)
 *   413 BODY_TOO_LARGE, FAMILY_TOO_LARGE (POST /api/families past --max-family)
 *   415 UNSUPPORTED_MEDIA_TYPE
 *   421 HOST_NOT_ALLOWED (the Host header names a host not in --allowed-hosts; http.h)
 *   429 TOO_MANY_JOBS (with Retry-After: the client's address has --max-jobs-per-client jobs
 *       queued or running; the loopback address counts like any other), TOO_MANY_REQUESTS (with
 *       Retry-After: a body over 64 KiB past the client's --max-waiters-per-client)
 *   501 UNSUPPORTED_TRANSFER_ENCODING (a Transfer-Encoding other than chunked)
 *   503 QUEUE_FULL, TOO_MANY_STREAMS (both with Retry-After), NO_MEMORY, DATABASE_ERROR,
 *       SHUTTING_DOWN, BUSY (with Retry-After: a body over 64 KiB, parsed off the HTTP threads,
 *       past --max-waiters), and when a write cannot be made now (with Retry-After):
 *       DATABASE_BUSY (another connection or process held the write lock past ROUTES_BUSY_MS),
 *       DATABASE_FULL (disk or --db-max-size full: DELETE of finished jobs still works and frees
 *       room), DATABASE_READONLY, DATABASE_IO_ERROR
 *
 * A job row (lists and single jobs):
 *   {"id", "name", "preset" (or null), "status" ("queued", "running", "done", "failed",
 *    "diverged", "cancelled"), "progress" (0..1), "created", "started", "finished",
 *    "scene": {"bodies", "coordinates"}, "controller", "e_max" (max tracking error over the
 *    coordinates, or null; for a CTC run, the initial error), "wall_s" (or null), "e_final"
 *    (max over the coordinates of |e| at the end, or null), "e_rms" (the RMS of e over the run
 *    and the coordinates: the root of the mean of metrics.e_rms squared, or null), "tags" (the
 *    job's tags, [] when none), "family" (the family it belongs to, or null),
 *    "location": "/api/jobs/ID"}
 *
 * POST /api/jobs             body: a job or {"preset": ...} (job_json.h). Validates first (400
 *                            with the parser's code, field and message; a "threads" above the
 *                            server's --job-threads is 400 INVALID_FIELD too). Stores it
 *                            queued, then 202 {row} with Location. ?wait=S (0 < S <= 300)
 *                            holds the answer until the job finishes: then 200 {job} as
 *                            GET /api/jobs/{id}, or 202 {row} if S ran out.
 * GET  /api/jobs             ?limit=N (1..200, default 50) &cursor=ID (rows with id < ID)
 *                            &status=S &q=TEXT (1..200 bytes: in the name, preset,
 *                            controller or a tag, ASCII case ignored) &tag=T (1..40 bytes: a
 *                            tag exactly; 400 INVALID_QUERY naming q or tag otherwise)
 *                            -> 200 {"jobs": [rows], "next_cursor": ID or null}
 * GET  /api/jobs/{id}        200 {row + "spec": normalised job, "metrics": {...} or null
 *                            (result_out.h), "message": text or null, "queue_position": 1 for
 *                            the next to start, 2, ..., or null unless queued here}; ?brief=1:
 *                            without spec and metrics (a running job's page polls it)
 * GET  /api/jobs/{id}/series ?channels=q,tau (default: all recorded) &joints=0,2 (coordinate
 *                            indices; default all) &every=N (default 1) &max_points=N (2..1e9:
 *                            at most N samples, first and last included, by the smallest stride
 *                            that does it, or every if larger) &format=json|csv|f32 (default
 *                            json) &reduce=stride|minmax (f32 only; series_stream.h) &from=K
 *                            (samples from K on) &partial=1 (a running job: the samples its
 *                            worker has recorded so far, jobq_live_read). json: the series
 *                            object of `ctcsim run --format json`; csv: exactly the CSV of
 *                            `ctcsim run`; f32: float32 binary with a JSON header. Streamed
 *                            (chunked), a piece at a time from the store; cut short (closed
 *                            without the last chunk) if the job is deleted meanwhile. A reply of
 *                            more than ROUTES_LARGE_SERIES values counts against
 *                            --max-series-streams: past them 503 TOO_MANY_STREAMS. 409
 *                            NOT_FINISHED while queued or running; 404 if the job has no series
 *                            (cancelled before it ran).
 * DELETE /api/jobs/{id}      queued: cancelled, 200 {job}; running: cancel requested, 202 {row}
 *                            (the worker stops at its next step and records "cancelled");
 *                            finished: deleted with its series, 204.
 * POST /api/jobs/{id}/cancel queued or running: as DELETE; finished: 409 ALREADY_FINISHED, the
 *                            job left as it is (a cancel never deletes).
 * POST /api/validate         200 {"valid": true, "spec": normalised job} or the 400 error.
 * POST /api/families         body: a family (family.h). Every member is expanded and validated
 *                            before anything is stored (off the HTTP threads, taking one of
 *                            --max-waiters: past them 503 BUSY); a bad member is 400 with the
 *                            axis values and the member's error ("axis integrator.rtol = -1
 *                            (member 1): integrator: rtol must be in (0, 1) (got -1)"), more
 *                            than --max-family members 413 FAMILY_TOO_LARGE. The family and
 *                            its members are stored in one transaction, the members queued in
 *                            the family's lane (jobq.h: served in turn with single jobs and
 *                            the other families), then 202 {"id", "name", "members",
 *                            "first_job", "location": "/api/families/ID"} with Location. A
 *                            family's members do not count against --max-jobs-per-client.
 * GET  /api/families         ?limit=N (1..200, default 50) &cursor=ID -> 200 {"families":
 *                            [{"id", "name", "members", "created", "axes": [paths], "counts":
 *                            {status: n}, "location"}], "next_cursor"}
 * GET  /api/families/{id}    200 {family row + "spec": the family's document, "table":
 *                            {"columns", "rows": [{"member", "replica", "job", "values",
 *                            "status", "message", metrics...}]}} (family.h's table);
 *                            ?format=csv or Accept: text/csv: the table as CSV (text/csv).
 * DELETE /api/families/{id}  members queued or running: the queued ones cancelled, the
 *                            running ones asked to stop; 202 {family row} while some run,
 *                            200 when none does. Every member finished: the family and its
 *                            members deleted with their series, 204 (so a second DELETE
 *                            deletes what the first cancelled).
 * GET  /api/presets          200 {"presets": [{"name", "summary", "params": [...]}]}
 * GET  /api/presets/{name}   200 the preset's job document; query parameters are its params
 *                            (?n=16); 404 UNKNOWN_PRESET; 400 INVALID_QUERY for a bad param.
 * GET  /api/health           200 {"status": "ok", "version", "workers", "busy", "queued",
 *                            "database": {"state": "ok"}, "jobs": {status: count}}, in O(1)
 *                            and without waiting for any lock. While the service's writes
 *                            meet a fault (store.h, one state for the whole process): 503 with
 *                            "status" "degraded" (state "locked") or "error" (state "full",
 *                            "readonly", "io_error"), and "database": {"state", "since" (ISO
 *                            time of the first failed write), "message", "failures" (writes
 *                            failed since)}; the fault clears at the next write that succeeds
 *                            (health itself tries one that changes nothing at most every
 *                            ROUTES_PROBE_INTERVAL s while it lasts). 503 with "status" "error"
 *                            and state "error" when the job counts cannot be read ("jobs": {}).
 * GET  /api/openapi.yaml     the API description (application/yaml).
 * GET  / and other paths      static files from the web root (http.h).
 */
#ifndef ROUTES_H
#define ROUTES_H

#include <stdatomic.h>
#include <stdint.h>

#include "client_count.h"
#include "http.h"
#include "jobq.h"

#define CTCSIM_VERSION "0.3.0"

/* What the handlers share; one for the whole server. */
typedef struct routes_ctx {
    jobq *queue;
    const char *db_path;          /* each HTTP thread opens its own connection on first use; it is
                                     closed when the thread exits (a pthread key destructor) */
    const char *api_dir;          /* directory holding openapi.yaml */
    double max_wait;              /* s, the largest ?wait= accepted (300) */
    int job_threads;              /* the most "threads" a job may ask for (--job-threads) */
    client_count *jobs_by_client; /* each client address's queued and running jobs */
    unsigned max_jobs_per_client; /* past them POST /api/jobs answers 429 (0 = no limit) */
    long max_queue;               /* queued single jobs at most (--max-queue); past them POST
                                     /api/jobs answers 503 QUEUE_FULL (the insert checks it on
                                     PostgreSQL, the queue on SQLite: store_insert_bounded) */
    long max_family;              /* members of one family at most (--max-family); past them
                                     POST /api/families answers 413 */
    long long db_max_size;        /* bytes each connection may grow the database to; 0 = no cap */
    struct store_health *health;  /* the database's state, shared with the workers (store.h) */
    atomic_int stopping;          /* set at shutdown (read by the HTTP threads, hence atomic): POST
                                     /api/jobs answers 503 SHUTTING_DOWN */

    /* large series replies (routes.c): past max_series_streams (--max-series-streams) sent at
       once, 503 TOO_MANY_STREAMS; < 1 = no limit */
    int max_series_streams;
    atomic_int series_streams; /* being sent */
} routes_ctx;

/* The route table, terminated by {NULL}. Handlers expect a routes_ctx as their ctx. */
extern const http_route routes_table[];

/* The queue's `left` hook (jobq_config): the job's place among its client's jobs is free again.
 * arg is the routes_ctx. */
void routes_job_left(void *arg, int64_t id);

#endif
