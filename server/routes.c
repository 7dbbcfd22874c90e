/*
 * routes.c - the service's endpoints (routes.h, whose top comment is the API reference): one
 * small handler per route, in the order of the table at the end.
 *
 * Handlers are linear: parse the path and query or reply 400, parse the body or reply its error,
 * do the work through the store (store.h) and the queue (jobq.h), reply. Each HTTP thread has its
 * own store connection, opened on its first use and kept in a pthread key whose destructor closes
 * it when libmicrohttpd ends the thread; a connection that reports an error is closed at once, so
 * the next request opens a fresh one.
 *
 * A POST body of more than ROUTES_INLINE_BODY bytes (64 KiB; a job's parse costs about 0.1 s per
 * MB) is parsed off the HTTP threads (run_post): the handler copies it and defers the whole POST
 * (http_defer), which then waits there too for ?wait; it takes one of the --max-waiters places
 * and of the client's --max-waiters-per-client, and past them is answered at once, 503 BUSY or
 * 429 TOO_MANY_REQUESTS, so an HTTP thread parses at most 64 KiB for a request. Each client
 * address may have --max-jobs-per-client jobs queued or running (client_count.h; its place taken
 * before the job is stored and given back by the queue's `left` hook), past which 429
 * TOO_MANY_JOBS.
 *
 * A new job is validated in full (job_parse runs ctc_sim_check) before it is stored, stored before
 * it is queued, and answered 202 only once it is both: a job that cannot be queued is recorded
 * cancelled and deleted again, and the client gets 503. ?wait defers the reply (http_defer): a
 * thread of the HTTP layer waits in short slices of jobq_wait, so the HTTP thread goes on serving
 * its other connections and a shutdown is held up by a waiting client for one slice at most; that
 * thread opens a store connection of its own, closed when it ends. (Should even the few bytes of
 * the wait's state not be had, the job is answered at once, 202, as without ?wait.) At most
 * --max-waiters clients wait at once; past them a ?wait is answered at once too, 202 with the
 * job's current row, so a flood of waiters never blocks an HTTP thread.
 *
 * Job rows are built from store_job in one place (job_row), so lists, single jobs and the replies
 * of POST and DELETE show the same fields.
 *
 * A series is streamed (http_reply_stream): the handler reads its shape only
 * (store_get_series_info), checks the selection, and hands a series_stream to the reply; each
 * piece of the body (HTTP_STREAM_BLOCK bytes at most) is then made on the HTTP thread that
 * serves the connection, from samples read through that thread's store connection in one short
 * read transaction per piece (store_series_begin .. end). So a reader holds a few windows of
 * samples, never the series, and no snapshot between pieces - a slow client holds up neither
 * WAL checkpoints nor a deletion, which the next piece reports, cutting the reply short. A
 * running job's samples so far (?partial=1) are read the same way from its worker's result
 * (jobq_live_read), and from the store should the job finish while they are being sent.
 * Replies of more than ROUTES_LARGE_SERIES values hold one of --max-series-streams places from
 * the handler until the reply is freed (sent, failed, the client gone or the server stopped);
 * past them the answer is 503 TOO_MANY_STREAMS, since each costs its HTTP thread time while
 * memory no longer grows with it.
 *
 * Database waits. An HTTP thread serves many connections, so it never waits long for the
 * database: its connection's busy timeout is ROUTES_BUSY_MS, and a write that meets a lock held
 * longer (another process's transaction), a full disk or a read-only file is answered 503 with
 * a code naming the fault and Retry-After (database_failed), the connection kept. Reads need no
 * wait: in WAL mode a reader never waits for the writer. Health reads the shared store_health
 * (store.h) and six rows of counts; while a fault lasts it probes, with one write that changes
 * nothing, at most every ROUTES_PROBE_INTERVAL s, so the state clears even when no other write
 * comes.
 */
#include "routes.h"

#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <microhttpd.h>

#include "client_count.h"
#include "family.h"
#include "job_json.h"
#include "presets.h"
#include "result_out.h"
#include "series_stream.h"
#include "store.h"

#define ROUTES_LIST_DEFAULT 50
#define ROUTES_LIST_MAX 200
#define ROUTES_EVERY_MAX 1000000
#define ROUTES_MAX_POINTS_MAX 1000000000
/* values (samples x columns, t included) of a series reply past which it counts against
   --max-series-streams: about 20 MB of text, a few tenths of a second of an HTTP thread. The
   page's plots ask for about 2 samples a pixel of at most 24 coordinates, well below it */
#define ROUTES_LARGE_SERIES 1048576
#define ROUTES_RETRY_AFTER 5   /* s, with 503 QUEUE_FULL, TOO_MANY_STREAMS and SHUTTING_DOWN */
#define ROUTES_WAIT_SLICE 0.25 /* s of one jobq_wait while a client waits */
/* bytes of a POST body parsed on the HTTP thread; larger ones are parsed off it (run_post) */
#define ROUTES_INLINE_BODY (64 * 1024)
#define ROUTES_BUSY_MS 300        /* ms an HTTP thread's write waits for another's lock */
#define ROUTES_PROBE_INTERVAL 1.0 /* s between health's probes while the database is at fault */

/* ---- the thread's store connection ---- */

static pthread_key_t store_key;
static pthread_once_t store_once = PTHREAD_ONCE_INIT;
static int store_key_ok;

static void store_key_destroy(void *s)
{
    store_close(s);
}

static void store_key_make(void)
{
    store_key_ok = pthread_key_create(&store_key, store_key_destroy) == 0;
}

/* This thread's connection, opened on first use; NULL after replying 503. */
static store *thread_store(const routes_ctx *ctx, http_reply *rep)
{
    pthread_once(&store_once, store_key_make);
    if (!store_key_ok) {
        http_reply_error(rep, 503, "DATABASE_ERROR", "",
                         "no thread-local storage for the database");
        return NULL;
    }
    store *s = pthread_getspecific(store_key);
    if (s) return s;
    char err[256] = "";
    if (store_open(ctx->db_path, &s, err, sizeof err) != 0 ||
        (ctx->db_max_size > 0 && store_set_max_size(s, ctx->db_max_size, err, sizeof err) != 0)) {
        store_close(s);
        fprintf(stderr, "ctcsim-server: database: %s\n", err);
        http_reply_error(rep, 503, "DATABASE_ERROR", "", "the database cannot be opened: %s", err);
        return NULL;
    }
    store_set_busy_timeout(s, ROUTES_BUSY_MS);
    store_attach(s, ctx->health);
    if (pthread_setspecific(store_key, s) != 0) {
        store_close(s);
        http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        return NULL;
    }
    return s;
}

/* After a failed store call on this thread's connection: logs it and replies 503. A transient
 * fault (store.h) gets its own code and Retry-After, and the connection is kept; any other drops
 * the connection (the next request opens a fresh one) and is DATABASE_ERROR. */
static void database_failed(http_reply *rep, const char *what, const char *err)
{
    static const struct {
        const char *code;
        int retry_after; /* s */
    } faults[STORE_NFAULT] = {
        [STORE_FAULT_LOCKED] = {"DATABASE_BUSY", 1},
        [STORE_FAULT_FULL] = {"DATABASE_FULL", 30},
        [STORE_FAULT_READONLY] = {"DATABASE_READONLY", 30},
        [STORE_FAULT_IO] = {"DATABASE_IO_ERROR", 30},
    };
    store *s = pthread_getspecific(store_key);
    store_fault f = s ? store_last_fault(s) : STORE_FAULT_OTHER;
    fprintf(stderr, "ctcsim-server: database: %s: %s\n", what, err);
    if (store_fault_transient(f)) {
        rep->retry_after = faults[f].retry_after;
        http_reply_error(rep, 503, faults[f].code, "", "the database cannot take this now (%s): %s",
                         what, err);
        return;
    }
    http_reply_error(rep, 503, "DATABASE_ERROR", "", "the database failed (%s): %s", what, err);
    if (s) {
        pthread_setspecific(store_key, NULL);
        store_close(s);
    }
}

/* ---- parsing the request ---- */

/* A decimal integer from min to max, digits only; 0, or -1 when text is not one. */
static int parse_integer(const char *text, long long min, long long max, long long *out)
{
    if (!text || !*text || strspn(text, "0123456789") != strlen(text)) return -1;
    errno = 0;
    long long x = strtoll(text, NULL, 10);
    if (errno == ERANGE || x < min || x > max) return -1;
    *out = x;
    return 0;
}

/* The job id of the path; 0, or -1 after replying 400 INVALID_ID. */
static int path_id(const http_request *req, http_reply *rep, int64_t *id)
{
    long long x;
    if (parse_integer(req->params[0], 1, INT64_MAX, &x) != 0) {
        http_reply_error(rep, 400, "INVALID_ID", "id",
                         "a job id is a positive integer (got \"%s\")", req->params[0]);
        return -1;
    }
    *id = x;
    return 0;
}

/* An integer query parameter (def when absent); 0, or -1 after replying 400 INVALID_QUERY. */
static int query_integer(const http_request *req, http_reply *rep, const char *key, long long min,
                         long long max, long long def, long long *out)
{
    const char *text = http_query(req, key);
    *out = def;
    if (!text) return 0;
    if (parse_integer(text, min, max, out) != 0) {
        http_reply_error(rep, 400, "INVALID_QUERY", key,
                         "%s must be an integer from %lld to %lld (got \"%s\")", key, min, max,
                         text);
        return -1;
    }
    return 0;
}

/* The body must be declared JSON (parameters such as charset allowed); 0, or -1 after 415. */
static int body_is_json(const http_request *req, http_reply *rep)
{
    const char *type = http_header(req, "Content-Type");
    const char *want = "application/json";
    size_t n = strlen(want);
    if (type) {
        while (*type == ' ' || *type == '\t') type++;
        if (strncasecmp(type, want, n) == 0 &&
            (type[n] == 0 || type[n] == ';' || type[n] == ' ' || type[n] == '\t'))
            return 0;
    }
    http_reply_error(rep, 415, "UNSUPPORTED_MEDIA_TYPE", "",
                     "the body must be JSON with Content-Type: application/json (got %s%s%s)",
                     type ? "\"" : "", type ? type : "none", type ? "\"" : "");
    return -1;
}

/* Parses the body as a job that this server accepts; NULL after replying the parser's error, or
   400 INVALID_FIELD when it asks for more threads than the server allows. */
static job *body_job(const char *body, size_t len, http_reply *rep, const routes_ctx *ctx)
{
    job *j = NULL;
    job_error e = {0};
    if (job_parse(body, len, &j, &e) == 0) {
        if (j->spec.threads <= ctx->job_threads) return j;
        http_reply_error(rep, 400, "INVALID_FIELD", "threads",
                         "must be at most %d on this server (its --job-threads; got %d)",
                         ctx->job_threads, j->spec.threads);
        job_free(j);
        return NULL;
    }
    if (e.code == JOB_NO_MEMORY)
        http_reply_error(rep, 503, "NO_MEMORY", e.field, "%s", e.message);
    else
        http_reply_error(rep, 400, job_error_code_name(e.code), e.field, "%s", e.message);
    return NULL;
}

/* ---- replies ---- */

/* An ISO 8601 UTC time with milliseconds, or null for 0 (not yet). */
static cJSON *time_json(double t)
{
    if (!(t > 0) || !isfinite(t)) return cJSON_CreateNull();
    double whole = floor(t);
    long ms = lround((t - whole) * 1000.0);
    if (ms >= 1000) {
        whole += 1;
        ms -= 1000;
    }
    time_t secs = (time_t)whole;
    struct tm tm;
    char text[64];
    if (!gmtime_r(&secs, &tm)) return cJSON_CreateNull();
    size_t n = strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%S", &tm);
    snprintf(text + n, sizeof text - n, ".%03ldZ", ms);
    return cJSON_CreateString(text);
}

static cJSON *number_or_null(double x)
{
    return isfinite(x) ? cJSON_CreateNumber(x) : cJSON_CreateNull();
}

static cJSON *string_or_null(const char *s)
{
    return s ? cJSON_CreateString(s) : cJSON_CreateNull();
}

static void job_location(char *buf, size_t len, int64_t id)
{
    snprintf(buf, len, "/api/jobs/%" PRId64, id);
}

/* The row of a job as lists show it (routes.h); NULL when out of memory. */
static cJSON *job_row(const store_job *j)
{
    char location[64];
    job_location(location, sizeof location, j->id);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "id", (double)j->id);
    cJSON_AddItemToObject(o, "name", string_or_null(j->name));
    cJSON_AddItemToObject(o, "preset", string_or_null(j->preset));
    cJSON_AddStringToObject(o, "status", store_status_name(j->status));
    cJSON_AddNumberToObject(o, "progress", isfinite(j->progress) ? j->progress : 0);
    cJSON_AddItemToObject(o, "created", time_json(j->created));
    cJSON_AddItemToObject(o, "started", time_json(j->started));
    cJSON_AddItemToObject(o, "finished", time_json(j->finished));
    cJSON *scene = cJSON_AddObjectToObject(o, "scene");
    cJSON_AddNumberToObject(scene, "bodies", j->nbodies);
    cJSON_AddNumberToObject(scene, "coordinates", j->nv);
    cJSON_AddItemToObject(o, "controller", string_or_null(j->controller));
    cJSON_AddItemToObject(o, "e_max", number_or_null(j->e_max));
    cJSON_AddItemToObject(o, "wall_s", number_or_null(j->wall_s));
    cJSON_AddItemToObject(o, "e_final", number_or_null(j->e_final));
    cJSON_AddItemToObject(o, "e_rms", number_or_null(j->e_rms));
    cJSON *tags = j->tags ? cJSON_Parse(j->tags) : NULL;
    if (!cJSON_IsArray(tags)) {
        cJSON_Delete(tags);
        tags = cJSON_CreateArray();
    }
    cJSON_AddItemToObject(o, "tags", tags);
    cJSON_AddItemToObject(
        o, "family", j->family > 0 ? cJSON_CreateNumber((double)j->family) : cJSON_CreateNull());
    cJSON_AddStringToObject(o, "location", location);
    /* cJSON's adders fail quietly: check the last of each kind once */
    if (!o || !scene || !cJSON_GetObjectItemCaseSensitive(o, "location")) {
        cJSON_Delete(o);
        return NULL;
    }
    return o;
}

/* A stored JSON text parsed back, or null (none, or unreadable). */
static cJSON *stored_json(const char *text)
{
    cJSON *doc = text ? cJSON_Parse(text) : NULL;
    return doc ? doc : cJSON_CreateNull();
}

/* The whole job: its row, the normalised spec, the metrics and the message. */
static cJSON *job_full(const store_job *j)
{
    cJSON *o = job_row(j);
    if (!o) return NULL;
    cJSON_AddItemToObject(o, "spec", stored_json(j->spec));
    cJSON_AddItemToObject(o, "metrics", stored_json(j->metrics));
    cJSON_AddItemToObject(o, "message",
                          string_or_null(j->message && j->message[0] ? j->message : NULL));
    cJSON_AddNullToObject(o, "queue_position"); /* GET /api/jobs/{id} fills it in */
    if (!cJSON_GetObjectItemCaseSensitive(o, "queue_position")) {
        cJSON_Delete(o);
        return NULL;
    }
    return o;
}

static void reply_job(http_reply *rep, int status, const store_job *j, int full)
{
    http_reply_json(rep, status, full ? job_full(j) : job_row(j));
}

static int job_finished(store_status st)
{
    return st != STORE_QUEUED && st != STORE_RUNNING;
}

/* ---- POST /api/jobs ---- */

static double monotonic_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ?wait=S: 0 when absent, else 0 < S <= max_wait; 0, or -1 after replying 400. */
static int query_wait(const http_request *req, http_reply *rep, const routes_ctx *ctx, double *wait)
{
    const char *text = http_query(req, "wait");
    *wait = 0;
    if (!text) return 0;
    char *end;
    double s = strtod(text, &end);
    if (end == text || *end || !(s > 0 && s <= ctx->max_wait)) {
        http_reply_error(rep, 400, "INVALID_QUERY", "wait",
                         "wait must be a number of seconds, more than 0 and at most %g (got "
                         "\"%s\")",
                         ctx->max_wait, text);
        return -1;
    }
    *wait = s;
    return 0;
}

/* Waits up to wait s for the job to leave the queue and the workers, in slices, giving up at
 * shutdown. Returns 1 when it did. */
static int wait_for_job(const routes_ctx *ctx, int64_t id, double wait)
{
    double deadline = monotonic_now() + wait;
    for (;;) {
        double left = deadline - monotonic_now();
        if (left <= 0 || atomic_load(&ctx->stopping)) return 0;
        if (jobq_wait(ctx->queue, id, left < ROUTES_WAIT_SLICE ? left : ROUTES_WAIT_SLICE) == 0)
            return 1;
    }
}

/* The answer to POST /api/jobs once the job is queued: 200 with the whole job when it has
 * finished (waited is 1 and it has), else 202 with its row; Location either way. */
static void reply_new_job(http_reply *rep, const routes_ctx *ctx, int64_t id, int waited)
{
    char err[256] = "";
    store_job row = {0};
    store *s = thread_store(ctx, rep);
    int got = s ? store_get(s, id, &row, err, sizeof err) : -1;
    job_location(rep->location, sizeof rep->location, id);
    if (got != 0) {
        /* queued all the same: say so with what is known */
        if (s) fprintf(stderr, "ctcsim-server: database: reading job %" PRId64 ": %s\n", id, err);
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "id", (double)id);
        cJSON_AddStringToObject(o, "location", rep->location);
        http_reply_json(rep, 202, o);
        return;
    }
    int finished = waited && job_finished(row.status);
    reply_job(rep, finished ? 200 : 202, &row, finished);
    store_job_clear(&row);
}

/* ?wait: what the deferred part of POST /api/jobs needs. */
typedef struct job_wait {
    const routes_ctx *ctx;
    int64_t id;
    double wait; /* s */
} job_wait;

/* Runs off libmicrohttpd's threads (http_defer): waits, then answers. */
static void finish_wait(http_reply *rep, void *arg)
{
    job_wait *w = arg;
    reply_new_job(rep, w->ctx, w->id, wait_for_job(w->ctx, w->id, w->wait));
    free(w);
}

/* A POST whose body is parsed off the HTTP threads (http_defer): what the deferred part needs,
 * the body copied (a request's strings last for the handler's call only). */
typedef struct deferred_post {
    const routes_ctx *ctx;
    char client[CLIENT_KEY_MAX];
    char *body;
    size_t len;
    double wait; /* s, POST /api/jobs?wait */
    void (*work)(http_reply *rep, const routes_ctx *ctx, const char *client, const char *body,
                 size_t len, double wait, int deferred);
} deferred_post;

static void finish_post(http_reply *rep, void *arg)
{
    deferred_post *d = arg;
    d->work(rep, d->ctx, d->client, d->body, d->len, d->wait, 1);
    free(d->body);
    free(d);
}

static void run_post_at(const http_request *req, http_reply *rep, const routes_ctx *ctx,
                        double wait, long inline_max,
                        void (*work)(http_reply *rep, const routes_ctx *ctx, const char *client,
                                     const char *body, size_t len, double wait, int deferred));

/* Runs work(...) here for a body up to ROUTES_INLINE_BODY bytes, else on a thread of the HTTP
 * layer (http_defer); past the places for those, 503 BUSY or, past the client's, 429
 * TOO_MANY_REQUESTS, both with Retry-After. */
static void run_post(const http_request *req, http_reply *rep, const routes_ctx *ctx, double wait,
                     void (*work)(http_reply *rep, const routes_ctx *ctx, const char *client,
                                  const char *body, size_t len, double wait, int deferred))
{
    run_post_at(req, rep, ctx, wait, ROUTES_INLINE_BODY, work);
}

/* run_post with the largest body parsed here: inline_max bytes (-1: none, always deferred) */
static void run_post_at(const http_request *req, http_reply *rep, const routes_ctx *ctx,
                        double wait, long inline_max,
                        void (*work)(http_reply *rep, const routes_ctx *ctx, const char *client,
                                     const char *body, size_t len, double wait, int deferred))
{
    char client[CLIENT_KEY_MAX];
    http_client(req, client, sizeof client);
    if (inline_max >= 0 && req->body_len <= (size_t)inline_max) {
        work(rep, ctx, client, req->body, req->body_len, wait, 0);
        return;
    }
    deferred_post *d = malloc(sizeof *d);
    char *copy = malloc(req->body_len + 1);
    if (!d || !copy) {
        free(d);
        free(copy);
        http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory for the request body");
        return;
    }
    memcpy(copy, req->body, req->body_len + 1);
    *d =
        (deferred_post){.ctx = ctx, .body = copy, .len = req->body_len, .wait = wait, .work = work};
    memcpy(d->client, client, sizeof client);
    int rc = http_defer(rep, finish_post, d);
    if (rc == 0) return;
    free(copy);
    free(d);
    rep->retry_after = ROUTES_RETRY_AFTER;
    if (rc == -2)
        http_reply_error(rep, 429, "TOO_MANY_REQUESTS", "",
                         "this client (%s) has as many requests being answered off the HTTP "
                         "threads as it may (--max-waiters-per-client); try again in a few seconds",
                         client);
    else if (inline_max >= 0)
        http_reply_error(rep, 503, "BUSY", "",
                         "every place for a body of more than %ld bytes is taken (--max-waiters); "
                         "try again in a few seconds",
                         inline_max);
    else
        http_reply_error(rep, 503, "BUSY", "",
                         "every place for a request answered off the HTTP threads is taken "
                         "(--max-waiters); try again in a few seconds");
}

/* POST /api/jobs once the request is checked: parse, the client's place, store, queue, reply
 * (or wait: here when deferred already, else by http_defer). */
static void post_job_work(http_reply *rep, const routes_ctx *ctx, const char *client,
                          const char *body, size_t len, double wait, int deferred)
{
    char err[256] = "";
    job *j = body_job(body, len, rep, ctx);
    if (!j) return;
    char *spec = NULL;
    store *s = NULL;
    int reserved = 0;

    /* the client's place among its jobs, held from here (reserved) until the job has its id */
    int held = client_count_take(ctx->jobs_by_client, client, ctx->max_jobs_per_client);
    if (held != 0) {
        if (held == 1) {
            rep->retry_after = ROUTES_RETRY_AFTER;
            http_reply_error(rep, 429, "TOO_MANY_JOBS", "",
                             "this client (%s) has %u jobs queued or running, the most one client "
                             "may have (--max-jobs-per-client); try again once one has finished",
                             client, ctx->max_jobs_per_client);
        } else {
            http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        }
        goto done;
    }
    reserved = 1;
    if (jobq_space(ctx->queue) <= 0) {
        rep->retry_after = ROUTES_RETRY_AFTER;
        http_reply_error(rep, 503, "QUEUE_FULL", "",
                         "the queue is full; try again in a few seconds");
        goto done;
    }
    if (!(s = thread_store(ctx, rep))) goto done;
    if (!(spec = cJSON_PrintUnformatted(j->normalised))) {
        http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        goto done;
    }

    /* stored first, then queued: a job answered 202 is in the database */
    int64_t id;
    int stored =
        store_insert_bounded(s, ctx->max_queue, j->name, j->preset, j->spec.chain.nbodies, j->nv,
                             ctc_ctrl_type_name(j->spec.controller), spec, &id, err, sizeof err);
    if (stored == 2) {
        rep->retry_after = ROUTES_RETRY_AFTER;
        http_reply_error(rep, 503, "QUEUE_FULL", "",
                         "the queue is full; try again in a few seconds");
        goto done;
    }
    if (stored != 0) {
        database_failed(rep, "storing the job", err);
        goto done;
    }
    /* the reserved place becomes the job's, given back when it leaves the workers
       (routes_job_left); before it is queued, since it may leave at once */
    int rc = client_count_take_id(ctx->jobs_by_client, client, id, 0) == 0 ? 0 : -1;
    client_count_give(ctx->jobs_by_client, client);
    reserved = 0;
    if (rc == 0 && (rc = jobq_submit(ctx->queue, id)) != 0)
        client_count_give_id(ctx->jobs_by_client, id);
    if (rc != 0) {
        const char *why = rc == 1   ? "the queue was full"
                          : rc == 2 ? "the server was shutting down"
                                    : "out of memory";
        if (store_finish(s, id, STORE_CANCELLED, why, NULL, NULL, err, sizeof err) != 0 ||
            store_delete(s, id, err, sizeof err) < 0)
            fprintf(stderr, "ctcsim-server: database: withdrawing job %" PRId64 ": %s\n", id, err);
        rep->retry_after = ROUTES_RETRY_AFTER;
        if (rc == 1)
            http_reply_error(rep, 503, "QUEUE_FULL", "",
                             "the queue is full; try again in a few seconds");
        else if (rc == 2)
            http_reply_error(rep, 503, "SHUTTING_DOWN", "", "the server is shutting down");
        else
            http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        goto done;
    }

    /* ?wait: answered from a thread that may block, so this one serves others meanwhile */
    if (wait > 0 && deferred) {
        reply_new_job(rep, ctx, id, wait_for_job(ctx, id, wait));
        goto done;
    }
    job_wait *w = wait > 0 ? malloc(sizeof *w) : NULL;
    if (w) *w = (job_wait){.ctx = ctx, .id = id, .wait = wait};
    if (!w || http_defer(rep, finish_wait, w) != 0) {
        /* no wait, or every waiting place taken (--max-waiters): 202 with the job as it is */
        free(w);
        reply_new_job(rep, ctx, id, 0);
    }
done:
    if (reserved) client_count_give(ctx->jobs_by_client, client);
    free(spec);
    job_free(j);
}

static void post_jobs(const http_request *req, http_reply *rep, void *arg)
{
    routes_ctx *ctx = arg;
    double wait;
    if (atomic_load(&ctx->stopping)) {
        rep->retry_after = ROUTES_RETRY_AFTER;
        http_reply_error(rep, 503, "SHUTTING_DOWN", "", "the server is shutting down");
        return;
    }
    if (body_is_json(req, rep) != 0 || query_wait(req, rep, ctx, &wait) != 0) return;
    run_post(req, rep, ctx, wait, post_job_work);
}

void routes_job_left(void *arg, int64_t id)
{
    routes_ctx *ctx = arg;
    client_count_give_id(ctx->jobs_by_client, id);
}

/* ---- lists (GET /api/jobs, GET /api/families) ---- */

/* ?limit (1..ROUTES_LIST_MAX, default ROUTES_LIST_DEFAULT) and ?cursor (an id: the rows below it;
 * 0 when absent) of a list; 0, or -1 after replying 400 INVALID_QUERY. */
static int query_page(const http_request *req, http_reply *rep, long long *limit, long long *cursor)
{
    if (query_integer(req, rep, "limit", 1, ROUTES_LIST_MAX, ROUTES_LIST_DEFAULT, limit) != 0)
        return -1;
    return query_integer(req, rep, "cursor", 1, INT64_MAX, 0, cursor);
}

/* Replies 200 {key: [the first limit rows], "next_cursor": the last shown row's id, or null when
 * n <= limit}: the store was asked for limit + 1 rows, so one more tells that a next page exists.
 * row(rows, i, &id) makes row i's JSON (NULL out of memory) and gives its id; the reply is
 * NO_MEMORY when any part could not be made. */
static void reply_page(http_reply *rep, const char *key, const void *rows, int n, long long limit,
                       cJSON *(*row)(const void *rows, int i, int64_t *id))
{
    cJSON *o = cJSON_CreateObject();
    cJSON *list = cJSON_AddArrayToObject(o, key);
    int shown = n > limit ? (int)limit : n;
    int64_t last = 0;
    for (int i = 0; i < shown; i++) cJSON_AddItemToArray(list, row(rows, i, &last));
    if (n > limit)
        cJSON_AddNumberToObject(o, "next_cursor", (double)last);
    else
        cJSON_AddNullToObject(o, "next_cursor");
    int complete = list && cJSON_GetArraySize(list) == shown &&
                   cJSON_GetObjectItemCaseSensitive(o, "next_cursor");
    if (!complete) {
        cJSON_Delete(o);
        o = NULL;
    }
    http_reply_json(rep, 200, o);
}

/* ---- GET /api/jobs ---- */

/* reply_page's row of the job list */
static cJSON *job_list_row(const void *rows, int i, int64_t *id)
{
    const store_job *j = (const store_job *)rows + i;
    *id = j->id;
    return job_row(j);
}

static void get_jobs(const http_request *req, http_reply *rep, void *arg)
{
    routes_ctx *ctx = arg;
    long long limit, cursor;
    if (query_page(req, rep, &limit, &cursor) != 0) return;
    int status = -1;
    const char *st = http_query(req, "status");
    if (st && (status = store_status_parse(st)) < 0) {
        http_reply_error(rep, 400, "INVALID_QUERY", "status",
                         "status must be one of queued, running, done, failed, diverged, "
                         "cancelled (got \"%s\")",
                         st);
        return;
    }
    /* a search: q, a text in the name, preset, controller or a tag; tag, one tag exactly */
    store_filter f = {
        .status = status, .text = http_query(req, "q"), .tag = http_query(req, "tag")};
    if (f.text && f.text[0] == '\0') f.text = NULL;
    if (f.text && strlen(f.text) > JOB_MAX_NAME) {
        http_reply_error(rep, 400, "INVALID_QUERY", "q",
                         "q must be at most %d bytes long (got %zu)", JOB_MAX_NAME, strlen(f.text));
        return;
    }
    if (f.tag && (f.tag[0] == '\0' || strlen(f.tag) > JOB_MAX_TAG)) {
        http_reply_error(rep, 400, "INVALID_QUERY", "tag",
                         "tag must be 1 to %d bytes long (got %zu)", JOB_MAX_TAG, strlen(f.tag));
        return;
    }
    store *s = thread_store(ctx, rep);
    if (!s) return;

    /* one row more than asked tells whether there is a next page */
    store_job *rows = NULL;
    int n = 0;
    char err[256] = "";
    int failed = f.text || f.tag
                     ? store_search(s, cursor, &f, (int)limit + 1, &rows, &n, err, sizeof err)
                     : store_list(s, cursor, status, (int)limit + 1, &rows, &n, err, sizeof err);
    if (failed != 0) {
        database_failed(rep, "listing jobs", err);
        return;
    }
    reply_page(rep, "jobs", rows, n, limit, job_list_row);
    store_jobs_free(rows, n);
}

/* ---- GET /api/jobs/{id} ---- */

/* Reads the job of the path; 0 with *row filled, or -1 after replying (400, 404, 503). */
static int path_job(const http_request *req, http_reply *rep, const routes_ctx *ctx, store_job *row)
{
    int64_t id;
    if (path_id(req, rep, &id) != 0) return -1;
    store *s = thread_store(ctx, rep);
    if (!s) return -1;
    char err[256] = "";
    int rc = store_get(s, id, row, err, sizeof err);
    if (rc == 1) http_reply_error(rep, 404, "NOT_FOUND", "id", "no job %" PRId64, id);
    if (rc < 0) database_failed(rep, "reading a job", err);
    return rc == 0 ? 0 : -1;
}

/* The answer to GET /api/jobs/{id} for a row read: 200 with the whole job (full) or its brief
 * form, and queue_position. */
static void reply_get_job(http_reply *rep, const routes_ctx *ctx, const store_job *row, int full)
{
    cJSON *o = full ? job_full(row) : job_row(row);
    if (o && !full)
        cJSON_AddItemToObject(
            o, "message", string_or_null(row->message && row->message[0] ? row->message : NULL));
    int pos = row->status == STORE_QUEUED ? jobq_position(ctx->queue, row->id) : 0;
    cJSON *place = pos > 0 ? cJSON_CreateNumber(pos) : cJSON_CreateNull();
    if (o && !(full ? cJSON_ReplaceItemInObjectCaseSensitive(o, "queue_position", place)
                    : cJSON_AddItemToObject(o, "queue_position", place))) {
        cJSON_Delete(o); /* place, not taken, is deleted below */
        o = NULL;
    }
    if (!o) cJSON_Delete(place);
    http_reply_json(rep, 200, o);
}

/* GET /api/jobs/{id}?wait: what its deferred part needs. */
typedef struct get_wait {
    const routes_ctx *ctx;
    int64_t id;
    int full;
    double wait; /* s */
} get_wait;

/* Runs off libmicrohttpd's threads (http_defer): waits for the job, reads it again, answers. */
static void finish_get_wait(http_reply *rep, void *arg)
{
    get_wait *w = arg;
    (void)wait_for_job(w->ctx, w->id, w->wait);
    store_job row = {0};
    char err[256] = "";
    store *s = thread_store(w->ctx, rep);
    int rc = s ? store_get(s, w->id, &row, err, sizeof err) : -1;
    if (rc == 0) reply_get_job(rep, w->ctx, &row, w->full);
    if (rc == 1) http_reply_error(rep, 404, "NOT_FOUND", "id", "no job %" PRId64, w->id);
    if (rc < 0 && s) database_failed(rep, "reading a job", err);
    store_job_clear(&row);
    free(w);
}

/* GET /api/jobs/{id}: the whole job, with queue_position (1 = next to start; null unless it
 * waits in this server's queue); ?brief=1 leaves out spec and metrics (a running job's page
 * polls it every second); ?wait=S holds the answer while the job is queued or running, up to S
 * (off the HTTP threads, in one of the --max-waiters places; past them answered at once). */
static void get_job(const http_request *req, http_reply *rep, void *arg)
{
    routes_ctx *ctx = arg;
    store_job row = {0};
    double wait;
    const char *brief = http_query(req, "brief");
    if (brief && strcmp(brief, "0") != 0 && strcmp(brief, "1") != 0) {
        http_reply_error(rep, 400, "INVALID_QUERY", "brief", "brief must be 0 or 1 (got \"%s\")",
                         brief);
        return;
    }
    if (query_wait(req, rep, ctx, &wait) != 0 || path_job(req, rep, ctx, &row) != 0) return;
    int full = !brief || strcmp(brief, "0") == 0;
    get_wait *w = wait > 0 && !job_finished(row.status) ? malloc(sizeof *w) : NULL;
    if (w) *w = (get_wait){.ctx = ctx, .id = row.id, .full = full, .wait = wait};
    if (w && http_defer(rep, finish_get_wait, w) == 0) {
        store_job_clear(&row);
        return;
    }
    free(w); /* no wait, or every waiting place taken: the job as it is */
    reply_get_job(rep, ctx, &row, full);
    store_job_clear(&row);
}

/* ---- GET /api/jobs/{id}/series ---- */

/* The channel names of a mask, ", "-separated, into buf. */
static void channel_names(char *buf, size_t len, unsigned mask)
{
    size_t used = 0;
    buf[0] = 0;
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (!(mask & CTC_CH_BIT(c)) || used >= len) continue;
        used += (size_t)snprintf(buf + used, len - used, "%s%s", used ? ", " : "",
                                 ctc_channel_name((ctc_channel)c));
    }
}

/* ?joints=0,2: the coordinate indices, checked against nv later; *count < 0 when absent. The
 * list is at most as long as the text. 0, or -1 after replying 400. */
static int query_joints(const http_request *req, http_reply *rep, long **list, int *count)
{
    const char *text = http_query(req, "joints");
    *list = NULL;
    *count = -1;
    if (!text) return 0;
    size_t len = strlen(text);
    long *out = malloc((len / 2 + 1) * sizeof *out);
    char *copy = strdup(text);
    if (!out || !copy) {
        free(out);
        free(copy);
        http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        return -1;
    }
    int n = 0;
    char *p = copy;
    for (;;) {
        char *comma = strchr(p, ',');
        if (comma) *comma = 0;
        long long x;
        if (parse_integer(p, 0, JOB_MAX_BODIES * 6LL, &x) != 0) {
            http_reply_error(rep, 400, "INVALID_QUERY", "joints",
                             "joints must be a comma-separated list of coordinate indices "
                             "from 0 (got \"%s\")",
                             text);
            free(out);
            free(copy);
            return -1;
        }
        out[n++] = (long)x;
        if (!comma) break;
        p = comma + 1;
    }
    free(copy);
    *list = out;
    *count = n;
    return 0;
}

/* A series being sent (http_reply_stream): the stream, made on the HTTP thread that serves the
 * connection, one read transaction of that thread's store connection per piece. */
typedef struct series_download {
    routes_ctx *ctx;
    int64_t id;
    int live;                 /* read from the running job's worker (jobq_live_read) */
    int from;                 /* the first sample sent (?from) */
    int width[CTC_NCHANNELS]; /* of each channel, to offset reads by from samples */
    series_stream *stream;
    int counted;   /* holds one of ctx->max_series_streams */
    store *s;      /* the connection of the piece being made */
    int gone;      /* a read found the series deleted */
    char err[256]; /* why a read failed */
} series_download;

static int download_read(void *arg, int channel, uint64_t offset, void *buf, size_t len)
{
    series_download *d = arg;
    uint64_t width = channel < 0 ? 1 : (uint64_t)d->width[channel];
    offset += (uint64_t)d->from * width * sizeof(double);
    if (d->live) {
        int live = jobq_live_read(d->ctx->queue, d->id, channel, offset, buf, len);
        if (live < 0)
            snprintf(d->err, sizeof d->err, "job %" PRId64 ": a read past the samples recorded",
                     d->id);
        if (live != 1) return live;
        d->live = 0; /* finished meanwhile: its series is in the store now */
    }
    int rc = store_series_read(d->s, d->id, channel, offset, buf, len, d->err, sizeof d->err);
    if (rc == 1) d->gone = 1;
    return rc;
}

/* the next piece of the body (http_stream_fn); a failure cuts the reply short */
static ptrdiff_t download_body(void *arg, char *buf, size_t max)
{
    series_download *d = arg;
    http_reply ignored = {.fd = -1};
    ptrdiff_t n = -1;
    d->s = thread_store(d->ctx, &ignored);
    if (!d->s) {
        fprintf(stderr, "ctcsim-server: series of job %" PRId64 ": no database connection\n",
                d->id);
    } else if (store_series_begin(d->s, d->err, sizeof d->err) != 0) {
        database_failed(&ignored, "reading a series", d->err);
    } else {
        n = series_stream_fill(d->stream, buf, max);
        store_series_end(d->s);
        if (n < 0 && d->gone)
            fprintf(stderr, "ctcsim-server: %s while it was being sent; the reply is cut short\n",
                    d->err);
        else if (n < 0)
            database_failed(&ignored, "reading a series", d->err);
    }
    free(ignored.body);
    d->s = NULL;
    return n;
}

static void download_free(void *arg)
{
    series_download *d = arg;
    if (d->counted) atomic_fetch_sub(&d->ctx->series_streams, 1);
    series_stream_free(d->stream);
    free(d);
}

static void get_series(const http_request *req, http_reply *rep, void *arg)
{
    routes_ctx *ctx = arg;
    char err[256] = "";
    long *joints = NULL;
    char *coords = NULL;
    series_download *d = NULL;
    store_job row = {0};
    int have_row = 0;

    /* the query, before touching the database */
    int64_t id;
    if (path_id(req, rep, &id) != 0) return;
    unsigned mask = 0;
    const char *channels = http_query(req, "channels");
    if (channels) {
        char bad[64];
        if (!*channels || result_parse_channels(channels, &mask, bad, sizeof bad) != 0) {
            http_reply_error(rep, 400, "INVALID_QUERY", "channels",
                             "unknown channel \"%s\" (the channels are q, qdot, q_des, qdot_des, "
                             "e, tau, w, energy)",
                             *channels ? bad : "");
            return;
        }
    }
    long long every, max_points;
    if (query_integer(req, rep, "every", 1, ROUTES_EVERY_MAX, 1, &every) != 0) return;
    if (query_integer(req, rep, "max_points", 2, ROUTES_MAX_POINTS_MAX, 0, &max_points) != 0)
        return;
    const char *format = http_query(req, "format");
    if (!format) format = "json";
    if (strcmp(format, "json") != 0 && strcmp(format, "csv") != 0 && strcmp(format, "f32") != 0) {
        http_reply_error(rep, 400, "INVALID_QUERY", "format",
                         "format must be json, csv or f32 (got \"%s\")", format);
        return;
    }
    series_format fmt = strcmp(format, "csv") == 0   ? SERIES_CSV
                        : strcmp(format, "f32") == 0 ? SERIES_F32
                                                     : SERIES_JSON;
    const char *reduce = http_query(req, "reduce");
    if (reduce && strcmp(reduce, "stride") != 0 && strcmp(reduce, "minmax") != 0) {
        http_reply_error(rep, 400, "INVALID_QUERY", "reduce",
                         "reduce must be stride or minmax (got \"%s\")", reduce);
        return;
    }
    if (reduce && strcmp(reduce, "minmax") == 0) {
        if (fmt != SERIES_F32) {
            http_reply_error(rep, 400, "INVALID_QUERY", "reduce",
                             "reduce=minmax needs format=f32 (got format=%s)", format);
            return;
        }
        fmt = SERIES_F32_MINMAX;
    }
    long long from, partial;
    if (query_integer(req, rep, "from", 0, INT32_MAX, 0, &from) != 0) return;
    if (query_integer(req, rep, "partial", 0, 1, 0, &partial) != 0) return;
    int njoints;
    if (query_joints(req, rep, &joints, &njoints) != 0) return;

    /* the job: finished, with a series, whose shape is read without its samples; or running,
       with ?partial=1, the samples its worker has recorded so far */
    if (path_job(req, rep, ctx, &row) != 0) goto done;
    have_row = 1;
    store_series_info info;
    int live = 0;
    if (!job_finished(row.status)) {
        live = partial && row.status == STORE_RUNNING && jobq_live_info(ctx->queue, id, &info) == 0;
        if (!live && partial && row.status == STORE_RUNNING && jobq_shared(ctx->queue)) {
            /* the samples so far live in the worker process that runs the job */
            http_reply_error(rep, 409, "NOT_FINISHED", "id",
                             "job %" PRId64 " is running in another worker process of the "
                             "cluster, which alone holds the samples recorded so far; its series "
                             "is here once it has finished",
                             id);
            goto done;
        }
        if (!live && partial) {
            http_reply_error(rep, 409, "NOT_FINISHED", "id",
                             "job %" PRId64 " is %s and has recorded no samples yet", id,
                             store_status_name(row.status));
            goto done;
        }
        if (!live) {
            http_reply_error(rep, 409, "NOT_FINISHED", "id",
                             "job %" PRId64 " is %s; its series is there once it has finished "
                             "(?partial=1: the samples recorded so far)",
                             id, store_status_name(row.status));
            goto done;
        }
    }
    store *s = thread_store(ctx, rep);
    if (!s) goto done;
    int rc = live ? 0 : store_get_series_info(s, id, &info, err, sizeof err);
    if (rc == 1) {
        http_reply_error(rep, 404, "NOT_FOUND", "id",
                         "job %" PRId64 " has no series (it was %s before it ran)", id,
                         store_status_name(row.status));
        goto done;
    }
    if (rc < 0) {
        database_failed(rep, "reading a series", err);
        goto done;
    }

    /* the selection, checked against what was recorded */
    unsigned missing = mask & ~info.channels;
    if (missing) {
        char names[128], recorded[128];
        channel_names(names, sizeof names, missing);
        channel_names(recorded, sizeof recorded, info.channels);
        http_reply_error(rep, 400, "INVALID_QUERY", "channels",
                         "job %" PRId64 " did not record %s (it recorded %s)", id, names, recorded);
        goto done;
    }
    if (njoints >= 0) {
        coords = calloc((size_t)info.nv + 1, 1);
        if (!coords) {
            http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
            goto done;
        }
        for (int i = 0; i < njoints; i++) {
            if (joints[i] >= info.nv) {
                http_reply_error(rep, 400, "INVALID_QUERY", "joints",
                                 "coordinate %ld is out of range (job %" PRId64
                                 " has %d coordinates, 0 to %d)",
                                 joints[i], id, info.nv, info.nv - 1);
                goto done;
            }
            if (coords[joints[i]]) {
                http_reply_error(rep, 400, "INVALID_QUERY", "joints",
                                 "coordinate %ld is listed twice", joints[i]);
                goto done;
            }
            coords[joints[i]] = 1;
        }
    }

    if (from > info.nsamples) {
        http_reply_error(rep, 400, "INVALID_QUERY", "from",
                         "from must be at most the number of samples, %d (got %lld)", info.nsamples,
                         from);
        goto done;
    }

    /* streamed as the command line writes it, a piece at a time, from sample `from` on */
    series_layout lay = {.nsamples = info.nsamples - (int)from, .nv = info.nv};
    memcpy(lay.width, info.width, sizeof lay.width);
    result_select sel = {.channels = mask,
                         .every =
                             fmt == SERIES_F32_MINMAX
                                 ? series_stream_buckets_stride(lay.nsamples, every, max_points)
                                 : series_stream_stride(lay.nsamples, every, max_points),
                         .coords = coords};
    d = calloc(1, sizeof *d);
    if (d) d->stream = series_stream_new(&lay, &sel, fmt, download_read, d);
    if (!d || !d->stream) {
        http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        goto done;
    }
    d->ctx = ctx;
    d->id = id;
    d->live = live;
    d->from = (int)from;
    memcpy(d->width, info.width, sizeof d->width);
    uint64_t values = series_stream_values(d->stream);
    if (values > ROUTES_LARGE_SERIES) {
        int open = atomic_fetch_add(&ctx->series_streams, 1);
        if (ctx->max_series_streams > 0 && open >= ctx->max_series_streams) {
            atomic_fetch_sub(&ctx->series_streams, 1);
            http_reply_error(rep, 503, "TOO_MANY_STREAMS", "",
                             "%d large series are being sent, the most this server sends at "
                             "once; try again later, or ask for fewer values (this one has "
                             "%llu; max_points, every, channels or joints make it smaller)",
                             open, (unsigned long long)values);
            rep->retry_after = ROUTES_RETRY_AFTER;
            goto done;
        }
        d->counted = 1;
    }
    http_reply_stream(rep, 200,
                      fmt == SERIES_CSV    ? "text/csv; charset=utf-8"
                      : fmt == SERIES_JSON ? "application/json"
                                           : "application/octet-stream",
                      download_body, download_free, d);
    d = NULL; /* the reply's */
done:
    if (d) download_free(d);
    if (have_row) store_job_clear(&row);
    free(coords);
    free(joints);
}

/* ---- DELETE /api/jobs/{id} and POST /api/jobs/{id}/cancel ---- */

/* Cancels the queued or running job of *row and replies: 202 with its row when its worker will
 * record it cancelled, 200 with the whole job when it was recorded cancelled here. Returns 0
 * after replying, or 1 when the job turned out finished meanwhile (*row then holds it, nothing
 * replied). */
static int cancel_running(http_reply *rep, routes_ctx *ctx, store *s, store_job *row)
{
    char err[256] = "";
    int64_t id = row->id;
    int rc = jobq_cancel(ctx->queue, id);
    if (rc == 2) { /* running: its worker records it cancelled */
        reply_job(rep, 202, row, 0);
        return 0;
    }
    /* taken out of the queue (1), or held by no worker here (0): record it ourselves,
       unless it finished meanwhile */
    store_job_clear(row);
    if (store_get(s, id, row, err, sizeof err) != 0) {
        database_failed(rep, "reading a job", err);
        return 0;
    }
    if (rc != 1 && job_finished(row->status)) return 1;
    if (store_finish(s, id, STORE_CANCELLED, "cancelled by request", NULL, NULL, err, sizeof err) !=
        0) {
        /* still queued in the database: back in the queue, so no job is stranded */
        if (rc == 1 && jobq_submit(ctx->queue, id) != 0)
            fprintf(stderr, "ctcsim-server: job %" PRId64 " stays queued until the next start\n",
                    id);
        database_failed(rep, "cancelling a job", err);
        return 0;
    }
    store_job_clear(row);
    if (store_get(s, id, row, err, sizeof err) != 0) {
        database_failed(rep, "reading a job", err);
        return 0;
    }
    reply_job(rep, 200, row, 1);
    return 0;
}

/* POST /api/jobs/{id}/cancel: a queued or running job is cancelled as DELETE does; a finished
 * one is left as it is, 409 ALREADY_FINISHED, so a cancel never deletes. */
static void post_cancel(const http_request *req, http_reply *rep, void *arg)
{
    routes_ctx *ctx = arg;
    store_job row = {0};
    if (path_job(req, rep, ctx, &row) != 0) return;
    store *s = thread_store(ctx, rep);
    if (s && (job_finished(row.status) || cancel_running(rep, ctx, s, &row) == 1))
        http_reply_error(rep, 409, "ALREADY_FINISHED", "id",
                         "job %" PRId64 " is %s: there is nothing to cancel (DELETE deletes it)",
                         row.id, store_status_name(row.status));
    store_job_clear(&row);
}

static void delete_job(const http_request *req, http_reply *rep, void *arg)
{
    routes_ctx *ctx = arg;
    char err[256] = "";
    store_job row = {0};
    if (path_job(req, rep, ctx, &row) != 0) return;
    store *s = thread_store(ctx, rep);
    if (!s) goto done;
    int64_t id = row.id;
    if (!job_finished(row.status) && cancel_running(rep, ctx, s, &row) == 0) goto done;

    /* finished: deleted with its series */
    int rc = store_delete(s, id, err, sizeof err);
    if (rc == 0) {
        http_reply_buffer(rep, 204, NULL, NULL, 0);
    } else if (rc == 1) {
        http_reply_error(rep, 404, "NOT_FOUND", "id", "no job %" PRId64, id);
    } else if (rc == 2) {
        http_reply_error(rep, 409, "NOT_FINISHED", "id",
                         "job %" PRId64 " was queued again meanwhile; cancel it first", id);
    } else {
        database_failed(rep, "deleting a job", err);
    }
done:
    store_job_clear(&row);
}

/* ---- POST /api/validate ---- */

static void validate_work(http_reply *rep, const routes_ctx *ctx, const char *client,
                          const char *body, size_t len, double wait, int deferred)
{
    (void)client;
    (void)wait;
    (void)deferred;
    job *j = body_job(body, len, rep, ctx);
    if (!j) return;
    cJSON *o = cJSON_CreateObject();
    cJSON_AddBoolToObject(o, "valid", 1);
    if (!cJSON_AddItemToObject(o, "spec", cJSON_Duplicate(j->normalised, 1))) {
        cJSON_Delete(o);
        o = NULL;
    }
    job_free(j);
    http_reply_json(rep, 200, o);
}

static void post_validate(const http_request *req, http_reply *rep, void *arg)
{
    if (body_is_json(req, rep) != 0) return;
    run_post(req, rep, arg, 0, validate_work);
}

/* ---- GET /api/presets, /api/presets/{name} ---- */

static void get_presets(const http_request *req, http_reply *rep, void *arg)
{
    (void)req;
    (void)arg;
    int count = 0;
    const preset *p = presets_list(&count);
    cJSON *o = cJSON_CreateObject();
    cJSON *list = cJSON_AddArrayToObject(o, "presets");
    for (int i = 0; i < count; i++) {
        cJSON *e = cJSON_CreateObject();
        cJSON_AddStringToObject(e, "name", p[i].name);
        cJSON_AddStringToObject(e, "summary", p[i].summary);
        cJSON *params = cJSON_AddArrayToObject(e, "params");
        for (int k = 0; p[i].params && p[i].params[k]; k++)
            cJSON_AddItemToArray(params, cJSON_CreateString(p[i].params[k]));
        cJSON_AddItemToArray(list, e);
    }
    if (!list || cJSON_GetArraySize(list) != count) {
        cJSON_Delete(o);
        o = NULL;
    }
    http_reply_json(rep, 200, o);
}

/* What the query-string walk collects for a preset. */
typedef struct preset_query {
    const preset *preset;
    cJSON *request; /* {key: value} */
    char bad[128];  /* the first key the preset does not take */
    int failed;     /* out of memory */
} preset_query;

static enum MHD_Result collect_param(void *cls, enum MHD_ValueKind kind, const char *key,
                                     const char *value)
{
    (void)kind;
    preset_query *q = cls;
    int known = 0;
    for (int k = 0; q->preset->params && q->preset->params[k]; k++)
        if (strcmp(key, q->preset->params[k]) == 0) known = 1;
    if (!known) {
        if (!q->bad[0]) snprintf(q->bad, sizeof q->bad, "%s", key);
        return MHD_YES;
    }
    /* the value as JSON (?n=16), else as a string */
    cJSON *v = value ? cJSON_ParseWithOpts(value, NULL, 1) : NULL;
    if (!v) v = cJSON_CreateString(value ? value : "");
    if (!v || !cJSON_AddItemToObject(q->request, key, v)) {
        cJSON_Delete(v);
        q->failed = 1;
    }
    return MHD_YES;
}

static void get_preset(const http_request *req, http_reply *rep, void *arg)
{
    (void)arg;
    const char *name = req->params[0];
    preset_query q = {.preset = presets_find(name)};
    if (!q.preset) {
        http_reply_error(rep, 404, "UNKNOWN_PRESET", "name",
                         "no preset \"%s\" (GET /api/presets lists them)", name);
        return;
    }
    q.request = cJSON_CreateObject();
    if (q.request) MHD_get_connection_values(req->conn, MHD_GET_ARGUMENT_KIND, collect_param, &q);
    if (!q.request || q.failed) {
        http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
    } else if (q.bad[0]) {
        char takes[128] = "";
        for (int k = 0; q.preset->params && q.preset->params[k]; k++) {
            size_t used = strlen(takes);
            snprintf(takes + used, sizeof takes - used, "%s%s", k ? ", " : "", q.preset->params[k]);
        }
        if (takes[0])
            http_reply_error(rep, 400, "INVALID_QUERY", q.bad,
                             "preset %s has no parameter \"%s\" (it takes: %s)", name, q.bad,
                             takes);
        else
            http_reply_error(rep, 400, "INVALID_QUERY", q.bad,
                             "preset %s takes no parameters (got \"%s\")", name, q.bad);
    } else {
        job_error e = {0};
        cJSON *doc = q.preset->build(q.request, &e);
        if (doc)
            http_reply_json(rep, 200, doc);
        else if (e.code == JOB_NO_MEMORY)
            http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        else
            http_reply_error(rep, 400, "INVALID_QUERY", e.field, "%s", e.message);
    }
    cJSON_Delete(q.request);
}

/* ---- families: POST, GET, DELETE /api/families ---- */

static void family_location(char *buf, size_t len, int64_t id)
{
    snprintf(buf, len, "/api/families/%" PRId64, id);
}

/* The row of a family as lists show it: {"id", "name", "members", "created", "counts": {status:
 * n}, "location"}; NULL when out of memory. */
static cJSON *family_row_json(const store_family *f)
{
    char location[64];
    family_location(location, sizeof location, f->id);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "id", (double)f->id);
    cJSON_AddItemToObject(o, "name", string_or_null(f->name));
    cJSON_AddNumberToObject(o, "members", (double)f->members);
    cJSON_AddItemToObject(o, "created", time_json(f->created));
    cJSON_AddItemToObject(o, "axes", stored_json(f->axes));
    cJSON *counts = cJSON_AddObjectToObject(o, "counts");
    for (int i = 0; i < STORE_NSTATUS; i++)
        cJSON_AddNumberToObject(counts, store_status_name((store_status)i), (double)f->counts[i]);
    cJSON_AddStringToObject(o, "location", location);
    if (!o || !counts || !cJSON_GetObjectItemCaseSensitive(o, "location")) {
        cJSON_Delete(o);
        return NULL;
    }
    return o;
}

/* POST /api/families once the request is checked: expand and validate every member, store the
 * family whole, queue its members in its lane, 202. Runs off the HTTP threads (deferred). */
static void post_family_work(http_reply *rep, const routes_ctx *ctx, const char *client,
                             const char *body, size_t len, double wait, int deferred)
{
    (void)client;
    (void)wait;
    (void)deferred;
    char err[256] = "";
    family *f = NULL;
    family_error ferr;
    store_new_member *members = NULL;
    int64_t *ids = NULL, family_id = 0;
    if (family_expand(body, len, ctx->max_family, &f, &ferr) != 0) {
        http_reply_error(rep, ferr.status, ferr.code, ferr.field, "%s", ferr.message);
        return;
    }
    for (long i = 0; i < f->nmembers; i++)
        if (f->members[i].threads > ctx->job_threads) {
            http_reply_error(rep, 400, "INVALID_FIELD", "base.threads",
                             "must be at most %d on this server (its --job-threads; got %d)",
                             ctx->job_threads, f->members[i].threads);
            goto done;
        }
    members = calloc((size_t)f->nmembers + 1, sizeof *members);
    ids = calloc((size_t)f->nmembers + 1, sizeof *ids);
    if (!members || !ids) {
        http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        goto done;
    }
    for (long i = 0; i < f->nmembers; i++) {
        const family_member *m = &f->members[i];
        members[i] = (store_new_member){.name = m->name,
                                        .preset = m->preset,
                                        .controller = m->controller,
                                        .spec = m->spec,
                                        .nbodies = m->nbodies,
                                        .nv = m->nv,
                                        .index = m->index,
                                        .replica = m->replica,
                                        .values = m->values};
    }
    store *s = thread_store(ctx, rep);
    if (!s) goto done;
    /* stored whole first, then queued: a family answered 202 is in the database */
    if (store_family_insert(s, f->name, f->doc, f->paths, members, f->nmembers, &family_id, ids,
                            err, sizeof err) != 0) {
        database_failed(rep, "storing the family", err);
        goto done;
    }
    int rc = jobq_submit_family(ctx->queue, family_id, ids, f->nmembers);
    if (rc != 0) {
        long n = 0;
        if (store_family_cancel(s, family_id,
                                rc == 2 ? "the server was shutting down" : "out of memory", &n, err,
                                sizeof err) != 0 ||
            store_family_delete(s, family_id, err, sizeof err) < 0)
            fprintf(stderr, "ctcsim-server: database: withdrawing family %" PRId64 ": %s\n",
                    family_id, err);
        rep->retry_after = ROUTES_RETRY_AFTER;
        if (rc == 2)
            http_reply_error(rep, 503, "SHUTTING_DOWN", "", "the server is shutting down");
        else
            http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        goto done;
    }
    family_location(rep->location, sizeof rep->location, family_id);
    cJSON *o = cJSON_CreateObject();
    cJSON_AddNumberToObject(o, "id", (double)family_id);
    cJSON_AddStringToObject(o, "name", f->name);
    cJSON_AddNumberToObject(o, "members", (double)f->nmembers);
    cJSON_AddItemToObject(
        o, "first_job", f->nmembers > 0 ? cJSON_CreateNumber((double)ids[0]) : cJSON_CreateNull());
    cJSON_AddStringToObject(o, "location", rep->location);
    if (!cJSON_GetObjectItemCaseSensitive(o, "location")) {
        cJSON_Delete(o);
        o = NULL;
    }
    http_reply_json(rep, 202, o);
done:
    free(members);
    free(ids);
    family_free(f);
}

static void post_families(const http_request *req, http_reply *rep, void *arg)
{
    routes_ctx *ctx = arg;
    if (atomic_load(&ctx->stopping)) {
        rep->retry_after = ROUTES_RETRY_AFTER;
        http_reply_error(rep, 503, "SHUTTING_DOWN", "", "the server is shutting down");
        return;
    }
    if (body_is_json(req, rep) != 0) return;
    /* the expansion validates every member: off the HTTP threads, whatever the body's size */
    run_post_at(req, rep, ctx, 0, -1, post_family_work);
}

/* reply_page's row of the family list */
static cJSON *family_list_row(const void *rows, int i, int64_t *id)
{
    const store_family *f = (const store_family *)rows + i;
    *id = f->id;
    return family_row_json(f);
}

static void get_families(const http_request *req, http_reply *rep, void *arg)
{
    routes_ctx *ctx = arg;
    long long limit, cursor;
    if (query_page(req, rep, &limit, &cursor) != 0) return;
    store *s = thread_store(ctx, rep);
    if (!s) return;
    store_family *rows = NULL;
    int n = 0;
    char err[256] = "";
    if (store_family_list(s, cursor, (int)limit + 1, &rows, &n, err, sizeof err) != 0) {
        database_failed(rep, "listing families", err);
        return;
    }
    reply_page(rep, "families", rows, n, limit, family_list_row);
    store_families_free(rows, n);
}

/* The family id of the path; 0, or -1 after replying 400 INVALID_ID. */
static int path_family_id(const http_request *req, http_reply *rep, int64_t *id)
{
    long long x;
    if (parse_integer(req->params[0], 1, INT64_MAX, &x) != 0) {
        http_reply_error(rep, 400, "INVALID_ID", "id",
                         "a family id is a positive integer (got \"%s\")", req->params[0]);
        return -1;
    }
    *id = x;
    return 0;
}

/* Reads the family of the path; 0 with *row filled, or -1 after replying (400, 404, 503). */
static int path_family(const http_request *req, http_reply *rep, const routes_ctx *ctx,
                       store_family *row)
{
    int64_t id;
    if (path_family_id(req, rep, &id) != 0) return -1;
    store *s = thread_store(ctx, rep);
    if (!s) return -1;
    char err[256] = "";
    int rc = store_family_get(s, id, row, err, sizeof err);
    if (rc == 1) http_reply_error(rep, 404, "NOT_FOUND", "id", "no family %" PRId64, id);
    if (rc < 0) database_failed(rep, "reading a family", err);
    return rc == 0 ? 0 : -1;
}

/* ?format=json|csv, or Accept: text/csv; 1 for CSV, 0 for JSON, -1 after replying 400 */
static int query_table_format(const http_request *req, http_reply *rep)
{
    const char *format = http_query(req, "format");
    if (format) {
        if (strcmp(format, "csv") == 0) return 1;
        if (strcmp(format, "json") == 0) return 0;
        http_reply_error(rep, 400, "INVALID_QUERY", "format",
                         "format must be json or csv (got \"%s\")", format);
        return -1;
    }
    const char *accept = http_header(req, "Accept");
    return accept && strstr(accept, "text/csv") ? 1 : 0;
}

static void get_family(const http_request *req, http_reply *rep, void *arg)
{
    routes_ctx *ctx = arg;
    store_family row = {0};
    store_member *members = NULL;
    family_row *rows = NULL;
    cJSON **values = NULL, **metrics = NULL, *paths = NULL;
    long n = 0;
    char err[256] = "";
    int csv = query_table_format(req, rep);
    if (csv < 0 || path_family(req, rep, ctx, &row) != 0) return;
    store *s = thread_store(ctx, rep);
    if (!s) goto done;
    if (store_family_members(s, row.id, &members, &n, err, sizeof err) != 0) {
        database_failed(rep, "reading a family's members", err);
        goto done;
    }
    rows = calloc((size_t)n + 1, sizeof *rows);
    values = calloc((size_t)n + 1, sizeof *values);
    metrics = calloc((size_t)n + 1, sizeof *metrics);
    paths = cJSON_Parse(row.axes ? row.axes : "[]");
    if (!rows || !values || !metrics || !paths) {
        http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
        goto done;
    }
    for (long i = 0; i < n; i++) {
        values[i] = members[i].values ? cJSON_Parse(members[i].values) : NULL;
        metrics[i] = members[i].metrics ? cJSON_Parse(members[i].metrics) : NULL;
        rows[i] = (family_row){.job = members[i].job,
                               .index = members[i].index,
                               .replica = members[i].replica,
                               .status = store_status_name(members[i].status),
                               .values = values[i],
                               .metrics = metrics[i],
                               .message = members[i].message};
    }
    if (csv) {
        char *text = NULL;
        size_t len = 0;
        FILE *mem = open_memstream(&text, &len);
        int wrc = mem ? family_write_csv(mem, paths, rows, n) : -1;
        if (mem && fclose(mem) != 0) wrc = -1;
        if (wrc != 0) {
            free(text);
            http_reply_error(rep, 503, "NO_MEMORY", "", "out of memory");
            goto done;
        }
        http_reply_buffer(rep, 200, "text/csv; charset=utf-8", text, len);
        goto done;
    }
    cJSON *o = family_row_json(&row);
    cJSON *table = family_table_json(paths, rows, n);
    if (!o || !table || !cJSON_AddItemToObject(o, "spec", stored_json(row.spec)) ||
        !cJSON_AddItemToObject(o, "table", table)) {
        cJSON_Delete(o);
        cJSON_Delete(table);
        o = NULL;
    }
    http_reply_json(rep, 200, o);
done:
    for (long i = 0; values && metrics && i < n; i++) {
        cJSON_Delete(values[i]);
        cJSON_Delete(metrics[i]);
    }
    free(values);
    free(metrics);
    free(rows);
    cJSON_Delete(paths);
    store_members_free(members, n);
    store_family_clear(&row);
}

/* DELETE /api/families/{id}: a family with members queued or running has them cancelled (200
 * with its row when none runs any more, 202 while running members stop); a family whose
 * members have all finished is deleted with them, 204. */
static void delete_family(const http_request *req, http_reply *rep, void *arg)
{
    routes_ctx *ctx = arg;
    char err[256] = "";
    store_family row = {0};
    if (path_family(req, rep, ctx, &row) != 0) return;
    store *s = thread_store(ctx, rep);
    if (!s) goto done;
    int64_t id = row.id;
    if (row.counts[STORE_QUEUED] + row.counts[STORE_RUNNING] > 0) {
        int64_t *removed = NULL;
        long nremoved = 0, ncancelled = 0;
        int running = jobq_cancel_family(ctx->queue, id, &removed, &nremoved);
        int rc = store_family_cancel(s, id, "cancelled by request", &ncancelled, err, sizeof err);
        if (rc != 0) {
            /* still queued in the database: back in their lane, so no member is stranded */
            if (nremoved > 0 && jobq_submit_family(ctx->queue, id, removed, nremoved) != 0)
                fprintf(stderr,
                        "ctcsim-server: family %" PRId64 " stays queued until the next start\n",
                        id);
            free(removed);
            database_failed(rep, "cancelling a family", err);
            goto done;
        }
        free(removed);
        store_family_clear(&row);
        if (store_family_get(s, id, &row, err, sizeof err) != 0) {
            database_failed(rep, "reading a family", err);
            goto done;
        }
        http_reply_json(rep, running > 0 || row.counts[STORE_RUNNING] > 0 ? 202 : 200,
                        family_row_json(&row));
        goto done;
    }
    int rc = store_family_delete(s, id, err, sizeof err);
    if (rc == 0)
        http_reply_buffer(rep, 204, NULL, NULL, 0);
    else if (rc == 1)
        http_reply_error(rep, 404, "NOT_FOUND", "id", "no family %" PRId64, id);
    else if (rc == 2)
        http_reply_error(rep, 409, "NOT_FINISHED", "id",
                         "family %" PRId64 " has members queued again meanwhile; cancel them first",
                         id);
    else
        database_failed(rep, "deleting a family", err);
done:
    store_family_clear(&row);
}

/* ---- GET /api/health ---- */

/* The database's state as health shows it: {"state"} when writes work, with "since",
 * "message" and "failures" while a fault lasts. */
static cJSON *database_json(const store_state *st)
{
    cJSON *d = cJSON_CreateObject();
    cJSON_AddStringToObject(d, "state", store_fault_name(st->fault));
    if (st->fault != STORE_FAULT_NONE) {
        cJSON_AddItemToObject(d, "since", time_json(st->since));
        cJSON_AddStringToObject(d, "message", st->message);
        cJSON_AddNumberToObject(d, "failures", (double)st->failures);
    }
    return d;
}

static void get_health(const http_request *req, http_reply *rep, void *arg)
{
    (void)req;
    routes_ctx *ctx = arg;
    jobq_stats stats = {0};
    jobq_get_stats(ctx->queue, &stats);
    long counts[STORE_NSTATUS] = {0};
    char err[256] = "";
    http_reply ignored = {.fd = -1};
    store *s = thread_store(ctx, &ignored);
    int readable = s && store_count(s, counts, err, sizeof err) == 0;
    if (s && !readable) database_failed(&ignored, "counting jobs", err);
    free(ignored.body);

    /* the writes' shared state; while at fault, a probe may learn that it has passed */
    store_state st = {.fault = STORE_FAULT_NONE};
    if (ctx->health) {
        /* without waiting: a probe that meets a lock leaves the state as it is */
        if (readable && store_health_probe_due(ctx->health, ROUTES_PROBE_INTERVAL)) {
            store_set_busy_timeout(s, 0);
            (void)store_probe(s, err, sizeof err);
            store_set_busy_timeout(s, ROUTES_BUSY_MS);
        }
        store_health_read(ctx->health, &st);
    }
    if (!readable && st.fault == STORE_FAULT_NONE) {
        st.fault = STORE_FAULT_OTHER;
        snprintf(st.message, sizeof st.message, "%s", s ? err : "the database cannot be opened");
        st.since = 0;
    }
    const char *status = st.fault == STORE_FAULT_NONE     ? "ok"
                         : st.fault == STORE_FAULT_LOCKED ? "degraded"
                                                          : "error";

    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "status", status);
    cJSON_AddStringToObject(o, "version", CTCSIM_VERSION);
    cJSON_AddNumberToObject(o, "workers", stats.workers);
    cJSON_AddNumberToObject(o, "busy", stats.busy);
    cJSON_AddNumberToObject(o, "queued", stats.queued);
    cJSON_AddItemToObject(o, "database", database_json(&st));
    cJSON *jobs = cJSON_AddObjectToObject(o, "jobs"); /* {} when the counts cannot be read */
    for (int i = 0; readable && i < STORE_NSTATUS; i++)
        cJSON_AddNumberToObject(jobs, store_status_name((store_status)i), (double)counts[i]);
    if (!cJSON_GetObjectItemCaseSensitive(o, "jobs") ||
        !cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(o, "database"),
                                          "state")) {
        cJSON_Delete(o);
        o = NULL;
    }
    http_reply_json(rep, st.fault == STORE_FAULT_NONE ? 200 : 503, o);
}

/* ---- GET /api/openapi.yaml ---- */

static void get_openapi(const http_request *req, http_reply *rep, void *arg)
{
    (void)req;
    routes_ctx *ctx = arg;
    char path[4096];
    snprintf(path, sizeof path, "%s/openapi.yaml", ctx->api_dir ? ctx->api_dir : "api");
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    struct stat st;
    if (fd < 0 || fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        if (fd >= 0) close(fd);
        http_reply_error(rep, 404, "NOT_FOUND", "",
                         "this server has no API description (openapi.yaml is missing)");
        return;
    }
    rep->status = 200;
    rep->content_type = "application/yaml";
    rep->fd = fd;
    rep->fd_size = (uint64_t)st.st_size;
}

/* ---- the table ---- */

const http_route routes_table[] = {
    {"GET", "/api/jobs", get_jobs},
    {"POST", "/api/jobs", post_jobs},
    {"GET", "/api/jobs/{id}", get_job},
    {"DELETE", "/api/jobs/{id}", delete_job},
    {"POST", "/api/jobs/{id}/cancel", post_cancel},
    {"GET", "/api/jobs/{id}/series", get_series},
    {"POST", "/api/validate", post_validate},
    {"GET", "/api/presets", get_presets},
    {"GET", "/api/presets/{name}", get_preset},
    {"GET", "/api/families", get_families},
    {"POST", "/api/families", post_families},
    {"GET", "/api/families/{id}", get_family},
    {"DELETE", "/api/families/{id}", delete_family},
    {"GET", "/api/health", get_health},
    {"GET", "/api/openapi.yaml", get_openapi},
    {NULL, NULL, NULL},
};
