/*
 * test_jobq.c - the job queue and its workers (server/jobq.c) against a real database in a
 * temporary directory (server/store.c).
 *
 * Jobs are made the way the service makes them: a preset request parsed by job_json, stored
 * queued with its normalised JSON (store_insert), then submitted. Oracles, each apart from the
 * code under test:
 *  - a direct ctc_sim_run of the stored spec: the series a worker stores must equal it bit for
 *    bit (the run is deterministic and the store keeps float64);
 *  - the database, read through a connection of the test's own: statuses, progress, messages
 *    and metrics as the workers wrote them, and counts by status (each of 100 jobs done once);
 *  - wall-clock bounds: a cancelled run stops within a step (well under a second of a run that
 *    would take a minute), jobq_wait's timeout holds.
 * Families are made as POST /api/families makes them (family_expand, store_family_insert); the
 * order of the workers' turns is read back from the jobs' stored start times.
 * The long job is the paper's triple pendulum under RK4 with a 10 us step for 60 s of simulated
 * time (about a minute of work, 10 us a step), so cancellation is polled often and no test lets
 * it finish. The file runs in about 6 s (17 s under AddressSanitizer), 5.5 s of it a lock held
 * past every busy timeout.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>
#include <sqlite3.h>

#include "family.h"
#include "job_json.h"
#include "jobq.h"
#include "sim.h"
#include "store.h"

#define LONG_JOB                                                                                   \
    "{\"preset\": \"triple_pendulum_pd\", \"duration\": 60, \"integrator\": {\"method\": "         \
    "\"rk4\", \"step\": 1e-5}}"
#define SHORT_JOB "{\"preset\": \"triple_pendulum_pd\", \"duration\": 0.05}"
#define WAIT_S 20.0 /* s: generous bound for jobs that take milliseconds */

/* the temporary database and the test's own connection to it */
static char dir[64];
static char db_path[128];
static store *db;

static void setup(void)
{
    snprintf(dir, sizeof dir, "/tmp/test_jobq_XXXXXX");
    cr_assert_not_null(mkdtemp(dir), "mkdtemp failed");
    snprintf(db_path, sizeof db_path, "%s/jobs.db", dir);
    char err[256] = "";
    cr_assert_eq(store_open(db_path, &db, err, sizeof err), 0, "store_open: %s", err);
}

static void teardown(void)
{
    store_close(db);
    db = NULL;
    const char *suffix[] = {"", "-wal", "-shm", "-journal"};
    char path[160];
    for (int i = 0; i < 4; i++) {
        snprintf(path, sizeof path, "%s%s", db_path, suffix[i]);
        unlink(path);
    }
    rmdir(dir);
}

TestSuite(jobq, .init = setup, .fini = teardown);

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static void sleep_s(double s)
{
    struct timespec ts = {.tv_sec = (time_t)s, .tv_nsec = (long)((s - floor(s)) * 1e9)};
    nanosleep(&ts, NULL);
}

/* Stores a job request as POST /api/jobs does: parsed, normalised, inserted queued. */
static int64_t insert_job(const char *request)
{
    job *j = NULL;
    job_error jerr;
    cr_assert_eq(job_parse(request, strlen(request), &j, &jerr), 0, "%s: %s: %s", request,
                 jerr.field, jerr.message);
    char *spec = cJSON_PrintUnformatted(j->normalised);
    cr_assert_not_null(spec);
    int64_t id = 0;
    char err[256] = "";
    int rc = store_insert(db, j->name, j->preset, j->spec.chain.nbodies, j->nv,
                          ctc_ctrl_type_name(j->spec.controller), spec, &id, err, sizeof err);
    cr_assert_eq(rc, 0, "store_insert: %s", err);
    cJSON_free(spec);
    job_free(j);
    return id;
}

static int64_t submit_job(jobq *q, const char *request)
{
    int64_t id = insert_job(request);
    cr_assert_eq(jobq_submit(q, id), 0, "job %lld was not queued", (long long)id);
    return id;
}

static jobq *start_queue(int workers, int max_queue, double job_time_limit)
{
    jobq_config cfg = {.db_path = db_path,
                       .workers = workers,
                       .max_queue = max_queue,
                       .job_time_limit = job_time_limit};
    jobq *q = NULL;
    char err[256] = "";
    cr_assert_eq(jobq_start(&cfg, &q, err, sizeof err), 0, "jobq_start: %s", err);
    cr_assert_not_null(q);
    return q;
}

/* The job's row as stored now (clear it with store_job_clear). */
static store_job get_row(int64_t id)
{
    store_job row;
    char err[256] = "";
    cr_assert_eq(store_get(db, id, &row, err, sizeof err), 0, "store_get %lld: %s", (long long)id,
                 err);
    return row;
}

static store_status get_status(int64_t id)
{
    store_job row = get_row(id);
    store_status st = row.status;
    store_job_clear(&row);
    return st;
}

/* Polls the database until the job has the status; fails the test after timeout_s. */
static void await_status(int64_t id, store_status st, double timeout_s)
{
    double t0 = now();
    while (get_status(id) != st) {
        cr_assert_lt(now() - t0, timeout_s, "job %lld did not become %s within %g s", (long long)id,
                     store_status_name(st), timeout_s);
        sleep_s(0.001);
    }
}

/* A number from the stored metrics JSON. */
static double metric(const store_job *row, const char *key)
{
    cr_assert_not_null(row->metrics, "job %lld has no metrics", (long long)row->id);
    cJSON *m = cJSON_Parse(row->metrics);
    cr_assert_not_null(m, "metrics are not JSON: %s", row->metrics);
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(m, key);
    cr_assert(cJSON_IsNumber(v), "metrics.%s is not a number", key);
    double x = v->valuedouble;
    cJSON_Delete(m);
    return x;
}

/* The stored series of job id against a direct run of its stored spec, bit for bit. */
static void assert_series_match_direct_run(int64_t id)
{
    store_job row = get_row(id);
    job *j = NULL;
    job_error jerr;
    cr_assert_eq(job_parse(row.spec, strlen(row.spec), &j, &jerr), 0, "%s", jerr.message);
    ctc_sim_result *want = NULL, *got = NULL;
    char err[256] = "";
    cr_assert_eq(ctc_sim_run(&j->spec, NULL, &want, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_eq(store_get_series(db, id, &got, err, sizeof err), 0, "store_get_series: %s", err);

    cr_assert_eq(got->nsamples, want->nsamples, "job %lld: samples", (long long)id);
    cr_assert_eq(got->nq, want->nq);
    cr_assert_eq(got->nv, want->nv);
    cr_assert_eq(got->channels, want->channels);
    size_t n = (size_t)want->nsamples;
    cr_assert(memcmp(got->t, want->t, n * sizeof(double)) == 0, "job %lld: t differs",
              (long long)id);
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (!want->ch[c]) continue;
        cr_assert_eq(got->width[c], want->width[c], "channel %s", ctc_channel_name(c));
        cr_assert_not_null(got->ch[c], "channel %s missing", ctc_channel_name(c));
        size_t size = n * (size_t)want->width[c] * sizeof(double);
        cr_assert(memcmp(got->ch[c], want->ch[c], size) == 0, "job %lld: %s differs", (long long)id,
                  ctc_channel_name(c));
    }
    ctc_sim_result_free(want);
    ctc_sim_result_free(got);
    job_free(j);
    store_job_clear(&row);
}

/* Waits until the queue has one job running and none waiting. */
static void await_busy(jobq *q)
{
    double t0 = now();
    jobq_stats s;
    for (jobq_get_stats(q, &s); s.busy != 1 || s.queued != 0; jobq_get_stats(q, &s)) {
        cr_assert_lt(now() - t0, WAIT_S, "the worker never took the job");
        sleep_s(0.001);
    }
}

Test(jobq, jobs_run_to_done_with_the_series_of_a_direct_run)
{
    const char *requests[] = {
        "{\"preset\": \"triple_pendulum_pd\", \"duration\": 0.5}",
        "{\"preset\": \"triple_pendulum_lqr\", \"duration\": 0.5}",
        "{\"preset\": \"triple_pendulum_passive\", \"duration\": 0.5}",
        "{\"preset\": \"spatial_double_pendulum_pid\", \"duration\": 0.5}",
        ("{\"preset\": \"n_link_pendulum\", \"n\": 16, \"duration\": 0.5, "
         "\"integrator\": {\"method\": \"bdf\"}}"),
    };
    enum { N = sizeof requests / sizeof requests[0] };
    jobq *q = start_queue(2, 8, 0);
    int64_t ids[N];
    for (int i = 0; i < N; i++) ids[i] = submit_job(q, requests[i]);
    for (int i = 0; i < N; i++) cr_assert_eq(jobq_wait(q, ids[i], WAIT_S), 0, "%s", requests[i]);

    for (int i = 0; i < N; i++) {
        store_job row = get_row(ids[i]);
        cr_assert_eq(row.status, STORE_DONE, "%s: %s", requests[i], store_status_name(row.status));
        cr_assert_eq(row.progress, 1.0);
        cr_assert(row.started > 0 && row.finished >= row.started);
        cr_assert_eq(metric(&row, "t_end"), 0.5);
        cr_assert(strstr(row.metrics, "\"status\":\"done\""), "%s", row.metrics);
        store_job_clear(&row);
        assert_series_match_direct_run(ids[i]);
    }
    jobq_stats s;
    jobq_get_stats(q, &s);
    cr_assert_eq(s.workers, 2);
    cr_assert_eq(s.busy, 0);
    cr_assert_eq(s.queued, 0);
    cr_assert_eq(s.done, N);
    jobq_stop(q);
}

Test(jobq, run_statuses_map_to_stored_statuses_and_the_time_limit_caps_the_jobs_own)
{
    /* a passive pendulum that passes its speed bound at once diverges */
    jobq *q = start_queue(1, 8, 0.05);
    int64_t diverged = submit_job(q, "{\"preset\": \"triple_pendulum_passive\", \"duration\": 5, "
                                     "\"limits\": {\"max_speed\": 0.5}}");
    /* the queue's 0.05 s caps the job's 10 s; the job's own 0.03 s stays */
    int64_t capped = submit_job(q, "{\"preset\": \"triple_pendulum_pd\", \"duration\": 60, "
                                   "\"integrator\": {\"method\": \"rk4\", \"step\": 1e-5}, "
                                   "\"limits\": {\"wall_time\": 10}}");
    int64_t own = submit_job(q, "{\"preset\": \"triple_pendulum_pd\", \"duration\": 60, "
                                "\"integrator\": {\"method\": \"rk4\", \"step\": 1e-5}, "
                                "\"limits\": {\"wall_time\": 0.03}}");
    int64_t unlimited = submit_job(q, LONG_JOB);
    cr_assert_eq(jobq_wait(q, diverged, WAIT_S), 0);
    cr_assert_eq(jobq_wait(q, capped, WAIT_S), 0);
    cr_assert_eq(jobq_wait(q, own, WAIT_S), 0);

    store_job row = get_row(diverged);
    cr_assert_eq(row.status, STORE_DIVERGED, "%s", store_status_name(row.status));
    cr_assert_not_null(row.message);
    cr_assert(strstr(row.message, "exceeds the bound 0.5"), "%s", row.message);
    cr_assert(strstr(row.metrics, "\"status\":\"diverged\""), "%s", row.metrics);
    store_job_clear(&row);

    row = get_row(capped);
    cr_assert_eq(row.status, STORE_FAILED, "%s", store_status_name(row.status));
    cr_assert(strncmp(row.message, "wall-time limit of 0.05 s reached at t = ", 41) == 0, "%s",
              row.message);
    cr_assert(strstr(row.metrics, "\"status\":\"timeout\""), "%s", row.metrics);
    cr_assert_lt(metric(&row, "t_end"), 60);
    store_job_clear(&row);

    row = get_row(own);
    cr_assert_eq(row.status, STORE_FAILED, "%s", store_status_name(row.status));
    cr_assert(strncmp(row.message, "wall-time limit of 0.03 s reached at t = ", 41) == 0, "%s",
              row.message);
    store_job_clear(&row);

    /* the fourth, with no limit of its own, is capped too */
    cr_assert_eq(jobq_wait(q, unlimited, WAIT_S), 0);
    row = get_row(unlimited);
    cr_assert_eq(row.status, STORE_FAILED, "%s", store_status_name(row.status));
    cr_assert(strncmp(row.message, "wall-time limit of 0.05 s", 25) == 0, "%s", row.message);
    store_job_clear(&row);
    jobq_stop(q);
}

Test(jobq, a_stored_job_that_no_longer_parses_fails_with_the_parsers_message)
{
    int64_t id = 0;
    char err[256] = "";
    cr_assert_eq(
        store_insert(db, "broken", NULL, 1, 1, "pd", "{\"duration\": 1}", &id, err, sizeof err), 0,
        "%s", err);
    jobq *q = start_queue(1, 4, 0);
    cr_assert_eq(jobq_submit(q, id), 0);
    cr_assert_eq(jobq_wait(q, id, WAIT_S), 0);
    store_job row = get_row(id);
    cr_assert_eq(row.status, STORE_FAILED, "%s", store_status_name(row.status));
    cr_assert_str_eq(row.message, "the stored job no longer parses: scene: is required");
    store_job_clear(&row);
    jobq_stop(q);
}

Test(jobq, submit_beyond_max_queue_returns_1_and_space_counts_free_places)
{
    jobq *q = start_queue(1, 2, 0);
    cr_assert_eq(jobq_space(q), 2);
    int64_t running = submit_job(q, LONG_JOB);
    await_busy(q);
    cr_assert_eq(jobq_space(q), 2);
    int64_t a = submit_job(q, SHORT_JOB);
    cr_assert_eq(jobq_space(q), 1);
    int64_t b = submit_job(q, SHORT_JOB);
    cr_assert_eq(jobq_space(q), 0);
    int64_t c = insert_job(SHORT_JOB);
    cr_assert_eq(jobq_submit(q, c), 1, "a full queue took a job");

    jobq_stats s;
    jobq_get_stats(q, &s);
    cr_assert_eq(s.busy, 1);
    cr_assert_eq(s.queued, 2);

    /* taking one out makes room */
    cr_assert_eq(jobq_cancel(q, a), 1);
    cr_assert_eq(jobq_space(q), 1);
    cr_assert_eq(jobq_submit(q, c), 0);
    cr_assert_eq(jobq_cancel(q, running), 2);
    cr_assert_eq(jobq_wait(q, running, WAIT_S), 0);
    cr_assert_eq(jobq_wait(q, b, WAIT_S), 0);
    cr_assert_eq(jobq_wait(q, c, WAIT_S), 0);
    cr_assert_eq(get_status(running), STORE_CANCELLED);
    cr_assert_eq(get_status(b), STORE_DONE);
    cr_assert_eq(get_status(c), STORE_DONE);
    cr_assert_eq(get_status(a), STORE_QUEUED, "the queue itself records nothing for a");
    jobq_stop(q);
}

Test(jobq, a_cancelled_queued_job_is_never_run)
{
    jobq *q = start_queue(1, 4, 0);
    int64_t running = submit_job(q, LONG_JOB);
    await_busy(q);
    int64_t queued = submit_job(q, SHORT_JOB);
    int64_t after = submit_job(q, SHORT_JOB);
    cr_assert_eq(jobq_cancel(q, queued), 1);
    cr_assert_eq(jobq_cancel(q, queued), 0, "cancelled twice");
    cr_assert_eq(jobq_wait(q, queued, 0), 0, "a cancelled job is no longer here");

    /* the caller records it, as DELETE /api/jobs/{id} does */
    char err[256] = "";
    cr_assert_eq(
        store_finish(db, queued, STORE_CANCELLED, "cancelled", NULL, NULL, err, sizeof err), 0,
        "%s", err);
    cr_assert_eq(jobq_cancel(q, running), 2);
    cr_assert_eq(jobq_wait(q, after, WAIT_S), 0);

    store_job row = get_row(queued);
    cr_assert_eq(row.status, STORE_CANCELLED);
    cr_assert_eq(row.started, 0, "the cancelled job was started");
    store_job_clear(&row);
    ctc_sim_result *r = NULL;
    cr_assert_eq(store_get_series(db, queued, &r, err, sizeof err), 1, "it has a series");
    cr_assert_eq(get_status(after), STORE_DONE);
    jobq_stats s;
    jobq_get_stats(q, &s);
    cr_assert_eq(s.done, 2, "the worker finished %ld jobs", s.done);
    cr_assert_eq(jobq_cancel(q, 12345), 0, "an unknown job");
    jobq_stop(q);
}

Test(jobq, a_cancelled_running_job_stops_at_its_next_step)
{
    jobq *q = start_queue(1, 4, 0);
    int64_t id = submit_job(q, LONG_JOB);
    await_status(id, STORE_RUNNING, WAIT_S);
    sleep_s(0.05);

    double t0 = now();
    cr_assert_eq(jobq_cancel(q, id), 2);
    cr_assert_eq(jobq_wait(q, id, WAIT_S), 0);
    double took = now() - t0;
    cr_assert_lt(took, 1.0, "the cancelled run took %g s to stop", took);

    store_job row = get_row(id);
    cr_assert_eq(row.status, STORE_CANCELLED, "%s", store_status_name(row.status));
    cr_assert(strncmp(row.message, "cancelled at t = ", 17) == 0, "%s", row.message);
    double t_end = metric(&row, "t_end");
    cr_assert(t_end > 0 && t_end < 60, "t_end %g", t_end);
    store_job_clear(&row);

    /* the samples up to the cancel are kept */
    ctc_sim_result *r = NULL;
    char err[256] = "";
    cr_assert_eq(store_get_series(db, id, &r, err, sizeof err), 0, "%s", err);
    cr_assert(r->nsamples >= 1 && r->nsamples < 6001, "%d samples", r->nsamples);
    ctc_sim_result_free(r);
    jobq_stop(q);
}

Test(jobq, wait_returns_1_on_timeout_and_0_once_the_job_is_finished)
{
    jobq *q = start_queue(1, 4, 0);
    int64_t id = submit_job(q, LONG_JOB);
    double t0 = now();
    cr_assert_eq(jobq_wait(q, id, 0.1), 1);
    double took = now() - t0;
    cr_assert(took >= 0.1 && took < 1.0, "a 0.1 s wait took %g s", took);
    cr_assert_eq(jobq_wait(q, id, 0), 1, "a zero wait on a running job");

    cr_assert_eq(jobq_cancel(q, id), 2);
    cr_assert_eq(jobq_wait(q, id, WAIT_S), 0);
    cr_assert_eq(get_status(id), STORE_CANCELLED);
    t0 = now();
    cr_assert_eq(jobq_wait(q, id, WAIT_S), 0, "a finished job");
    cr_assert_eq(jobq_wait(q, 12345, WAIT_S), 0, "a job never queued");
    cr_assert_lt(now() - t0, 0.5, "waits on jobs that are not here returned late");
    jobq_stop(q);
}

Test(jobq, progress_is_written_while_a_job_runs)
{
    jobq *q = start_queue(1, 4, 0);
    int64_t id = submit_job(q, LONG_JOB);
    await_status(id, STORE_RUNNING, WAIT_S);
    double t0 = now();
    store_job row = get_row(id);
    while (row.progress == 0) {
        store_job_clear(&row);
        cr_assert_lt(now() - t0, WAIT_S, "no progress written");
        sleep_s(0.002);
        row = get_row(id);
    }
    double first = now() - t0, p0 = row.progress;
    cr_assert_eq(row.status, STORE_RUNNING);
    cr_assert(p0 > 0 && p0 < 1, "progress %g", p0);
    store_job_clear(&row);
    /* not before the interval: the job started at most one poll before t0 */
    cr_assert_gt(first, JOBQ_PROGRESS_INTERVAL - 0.05, "progress after %g s", first);

    /* and it keeps moving */
    sleep_s(2.5 * JOBQ_PROGRESS_INTERVAL);
    row = get_row(id);
    double later = row.progress;
    store_job_clear(&row);
    cr_assert_gt(later, p0, "progress stayed at %g", p0);
    cr_assert_eq(jobq_cancel(q, id), 2);
    cr_assert_eq(jobq_wait(q, id, WAIT_S), 0);
    jobq_stop(q);
}

/* the write lock, held by a raw connection as another process would, until raw_unlock */
static sqlite3 *raw_lock(void)
{
    sqlite3 *raw = NULL;
    cr_assert_eq(sqlite3_open(db_path, &raw), SQLITE_OK);
    char *why = NULL;
    cr_assert_eq(
        sqlite3_exec(raw, "BEGIN IMMEDIATE; UPDATE job_counts SET n = n", NULL, NULL, &why),
        SQLITE_OK, "locking: %s", why ? why : "");
    return raw;
}

static void raw_unlock(sqlite3 *raw)
{
    cr_assert_eq(sqlite3_exec(raw, "COMMIT", NULL, NULL, NULL), SQLITE_OK);
    sqlite3_close(raw);
}

Test(jobq, a_lock_held_past_every_busy_timeout_delays_a_job_but_never_drops_it)
{
    jobq *q = start_queue(1, 4, 0);
    int64_t id = insert_job(SHORT_JOB);
    /* held longer than a connection waits (5 s by default): the worker cannot mark it running */
    sqlite3 *raw = raw_lock();
    cr_assert_eq(jobq_submit(q, id), 0);
    sleep_s(5.5);
    store_job row = get_row(id);
    cr_assert_eq(row.status, STORE_QUEUED, "%s under the lock", store_status_name(row.status));
    store_job_clear(&row);
    raw_unlock(raw);
    cr_assert_eq(jobq_wait(q, id, WAIT_S), 0);
    row = get_row(id);
    cr_assert_eq(row.status, STORE_DONE, "job %lld is %s: %s", (long long)id,
                 store_status_name(row.status), row.message ? row.message : "");
    store_job_clear(&row);
    jobq_stop(q);
}

Test(jobq, stop_requeues_the_running_job_and_the_next_start_finishes_it)
{
    /* 600 000 rk4 steps (0.8 s of work on a 2-core EPYC VM with the FMA kernels, several under
       ASan): long enough to write progress and be stopped on any machine, short enough to run
       again */
    const char *request = "{\"preset\": \"triple_pendulum_pd\", \"duration\": 3, "
                          "\"integrator\": {\"method\": \"rk4\", \"step\": 5e-6}}";
    jobq *q = start_queue(1, 4, 0);
    int64_t running = submit_job(q, request);
    int64_t waiting = submit_job(q, SHORT_JOB);
    double t0 = now();
    for (;;) {
        store_job row = get_row(running);
        double p = row.progress;
        store_job_clear(&row);
        if (p > 0) break;
        cr_assert_lt(now() - t0, WAIT_S, "no progress written");
        sleep_s(0.002);
    }
    t0 = now();
    jobq_stop(q);
    cr_assert_lt(now() - t0, 1.0, "stopping took %g s", now() - t0);

    store_job row = get_row(running);
    cr_assert_eq(row.status, STORE_QUEUED, "%s", store_status_name(row.status));
    cr_assert_eq(row.progress, 0);
    cr_assert_null(row.metrics);
    store_job_clear(&row);
    cr_assert_eq(get_status(waiting), STORE_QUEUED);

    /* a new start recovers both, oldest first, and runs them to the end */
    q = start_queue(1, 4, 0);
    cr_assert_eq(jobq_wait(q, running, WAIT_S), 0);
    cr_assert_eq(jobq_wait(q, waiting, WAIT_S), 0);
    row = get_row(running);
    cr_assert_eq(row.status, STORE_DONE, "%s", store_status_name(row.status));
    cr_assert_eq(metric(&row, "t_end"), 3.0);
    store_job_clear(&row);
    cr_assert_eq(get_status(waiting), STORE_DONE);
    assert_series_match_direct_run(running);
    jobq_stats s;
    jobq_get_stats(q, &s);
    cr_assert_eq(s.done, 2);
    jobq_stop(q);
}

Test(jobq, recovery_queues_more_jobs_than_max_queue)
{
    enum { N = 5 };
    int64_t ids[N];
    for (int i = 0; i < N; i++) ids[i] = insert_job(SHORT_JOB);
    jobq *q = start_queue(1, 2, 0);
    for (int i = 0; i < N; i++) cr_assert_eq(jobq_wait(q, ids[i], WAIT_S), 0);
    for (int i = 0; i < N; i++) cr_assert_eq(get_status(ids[i]), STORE_DONE);
    jobq_stats s;
    jobq_get_stats(q, &s);
    cr_assert_eq(s.done, N);
    cr_assert_eq(jobq_space(q), 2);
    jobq_stop(q);
}

Test(jobq, four_workers_run_a_hundred_jobs_each_exactly_once)
{
    enum { N = 100 };
    jobq *q = start_queue(4, 8, 0);
    int64_t ids[N];
    for (int i = 0; i < N; i++) {
        ids[i] = insert_job(SHORT_JOB);
        /* a full queue answers 1: wait for a place, as a client retries after 503 */
        int rc;
        double t0 = now();
        while ((rc = jobq_submit(q, ids[i])) == 1) {
            cr_assert_lt(now() - t0, WAIT_S, "the queue never drained");
            sleep_s(0.0005);
        }
        cr_assert_eq(rc, 0);
    }
    for (int i = 0; i < N; i++) cr_assert_eq(jobq_wait(q, ids[i], WAIT_S), 0);

    jobq_stats s;
    jobq_get_stats(q, &s);
    cr_assert_eq(s.done, N, "%ld jobs finished", s.done);
    cr_assert_eq(s.busy, 0);
    cr_assert_eq(s.queued, 0);
    long counts[STORE_NSTATUS];
    char err[256] = "";
    cr_assert_eq(store_count(db, counts, err, sizeof err), 0, "%s", err);
    cr_assert_eq(counts[STORE_DONE], N);
    for (int st = 0; st < STORE_NSTATUS; st++)
        if (st != STORE_DONE)
            cr_assert_eq(counts[st], 0, "%ld %s", counts[st], store_status_name(st));
    for (int i = 0; i < N; i++) {
        ctc_sim_result *r = NULL;
        cr_assert_eq(store_get_series(db, ids[i], &r, err, sizeof err), 0, "%s", err);
        cr_assert_eq(r->nsamples, 6, "job %lld has %d samples", (long long)ids[i], r->nsamples);
        ctc_sim_result_free(r);
    }
    jobq_stop(q);
}

/* one client thread of the test below: submits its jobs through its own connection, as an HTTP
 * thread does, and cancels every third once it has submitted the next (recording the cancel
 * itself when the job was still queued, as DELETE does) */
enum { CLIENTS = 4, CLIENT_JOBS = 25 };

typedef struct client {
    jobq *q;
    const char *spec;
    int64_t ids[CLIENT_JOBS];
    int cancel_rc[CLIENT_JOBS]; /* jobq_cancel's answer, -1 = not cancelled */
    char error[256];            /* the first failure, "" if none */
} client;

static void *client_main(void *arg)
{
    client *c = arg;
    store *s = NULL;
    if (store_open(db_path, &s, c->error, sizeof c->error) != 0) return NULL;
    for (int i = 0; i < CLIENT_JOBS && !c->error[0]; i++) {
        c->cancel_rc[i] = -1;
        if (store_insert(s, "client", "triple_pendulum_pd", 3, 3, "pd", c->spec, &c->ids[i],
                         c->error, sizeof c->error) != 0)
            break;
        int rc;
        while ((rc = jobq_submit(c->q, c->ids[i])) == 1) sleep_s(0.0005);
        if (rc != 0) {
            snprintf(c->error, sizeof c->error, "submit answered %d", rc);
            break;
        }
        /* the counters are read from client threads too, as GET /api/health does */
        jobq_stats st;
        jobq_get_stats(c->q, &st);
        if (i % 3 != 1) continue;
        /* the previous job: queued, running or finished by now */
        int64_t prev = c->ids[i - 1];
        c->cancel_rc[i - 1] = jobq_cancel(c->q, prev);
        if (c->cancel_rc[i - 1] == 1)
            store_finish(s, prev, STORE_CANCELLED, "cancelled", NULL, NULL, c->error,
                         sizeof c->error);
    }
    store_close(s);
    return NULL;
}

Test(jobq, concurrent_clients_submit_and_cancel_and_every_job_ends_once)
{
    job *j = NULL;
    job_error jerr;
    cr_assert_eq(job_parse(SHORT_JOB, strlen(SHORT_JOB), &j, &jerr), 0, "%s", jerr.message);
    char *spec = cJSON_PrintUnformatted(j->normalised);
    /* a short queue keeps the previous job as likely queued as running or finished */
    jobq *q = start_queue(2, 4, 0);
    client clients[CLIENTS];
    pthread_t threads[CLIENTS];
    for (int k = 0; k < CLIENTS; k++) {
        clients[k] = (client){.q = q, .spec = spec};
        cr_assert_eq(pthread_create(&threads[k], NULL, client_main, &clients[k]), 0);
    }
    for (int k = 0; k < CLIENTS; k++) pthread_join(threads[k], NULL);

    /* queued when cancelled: recorded by the client and never started; running when cancelled:
       cancelled by the worker, or done if the run ended first; otherwise done */
    long removed = 0;
    for (int k = 0; k < CLIENTS; k++) {
        cr_assert_str_eq(clients[k].error, "", "client %d: %s", k, clients[k].error);
        for (int i = 0; i < CLIENT_JOBS; i++) {
            int64_t id = clients[k].ids[i];
            int rc = clients[k].cancel_rc[i];
            cr_assert_eq(jobq_wait(q, id, WAIT_S), 0);
            store_job row = get_row(id);
            if (rc == 1) {
                removed++;
                cr_assert_eq(row.status, STORE_CANCELLED);
                cr_assert_eq(row.started, 0, "job %lld was started", (long long)id);
            } else if (rc == 2) {
                cr_assert(row.status == STORE_CANCELLED || row.status == STORE_DONE, "%s",
                          store_status_name(row.status));
            } else {
                cr_assert_eq(row.status, STORE_DONE, "job %lld (cancel answered %d): %s",
                             (long long)id, rc, store_status_name(row.status));
            }
            store_job_clear(&row);
        }
    }
    jobq_stats s;
    jobq_get_stats(q, &s);
    cr_assert_eq(s.done, CLIENTS * CLIENT_JOBS - removed, "%ld finished, %ld taken out", s.done,
                 removed);
    long counts[STORE_NSTATUS];
    char err[256] = "";
    cr_assert_eq(store_count(db, counts, err, sizeof err), 0, "%s", err);
    cr_assert_eq(counts[STORE_DONE] + counts[STORE_CANCELLED], CLIENTS * CLIENT_JOBS);
    jobq_stop(q);
    cJSON_free(spec);
    job_free(j);
}

Test(jobq, start_refuses_a_bad_config_with_a_message)
{
    jobq_stop(NULL); /* allowed, and does nothing */
    jobq_config cfg = {.db_path = db_path, .workers = 1, .max_queue = 1};
    char err[256] = "";
    jobq *q = NULL;
    cfg.workers = 0;
    cr_assert_eq(jobq_start(&cfg, &q, err, sizeof err), -1);
    cr_assert_str_eq(err, "workers must be >= 1 (got 0)");
    cr_assert_null(q);
    cfg.workers = 1, cfg.max_queue = 0;
    cr_assert_eq(jobq_start(&cfg, &q, err, sizeof err), -1);
    cr_assert_str_eq(err, "max_queue must be >= 1 (got 0)");
    cfg.max_queue = 1, cfg.job_time_limit = -1;
    cr_assert_eq(jobq_start(&cfg, &q, err, sizeof err), -1);
    cr_assert_str_eq(err, "job_time_limit must be >= 0 and finite (got -1 s)");
    cfg.job_time_limit = NAN;
    cr_assert_eq(jobq_start(&cfg, &q, err, sizeof err), -1);
    cr_assert_str_eq(err, "job_time_limit must be >= 0 and finite (got nan s)");
    cfg.job_time_limit = 0, cfg.db_path = NULL;
    cr_assert_eq(jobq_start(&cfg, &q, err, sizeof err), -1);
    cr_assert_str_eq(err, "db_path must name the database file");

    /* the database is opened before any thread starts, so a bad path fails the start */
    char missing[160], want[512];
    snprintf(missing, sizeof missing, "%s/missing/jobs.db", dir);
    cfg.db_path = missing;
    cr_assert_eq(jobq_start(&cfg, &q, err, sizeof err), -1);
    snprintf(want, sizeof want,
             "recovering jobs: cannot open database %s: directory %s/missing does not exist",
             missing, dir);
    cr_assert_str_eq(err, want);
    cr_assert_null(q);
}

/* What the `left` hook saw: each job id, in order, under a lock of its own. */
typedef struct left_log {
    pthread_mutex_t lock;
    int64_t ids[16];
    int n;
} left_log;

static void log_left(void *arg, int64_t id)
{
    left_log *log = arg;
    pthread_mutex_lock(&log->lock);
    if (log->n < 16) log->ids[log->n] = id;
    log->n++;
    pthread_mutex_unlock(&log->lock);
}

Test(jobq, left_is_called_once_for_each_job_that_leaves_finished_or_cancelled)
{
    left_log log = {.lock = PTHREAD_MUTEX_INITIALIZER};
    jobq_config cfg = {
        .db_path = db_path, .workers = 1, .max_queue = 4, .left = log_left, .left_arg = &log};
    jobq *q = NULL;
    char err[256] = "";
    cr_assert_eq(jobq_start(&cfg, &q, err, sizeof err), 0, "jobq_start: %s", err);
    int64_t running = submit_job(q, LONG_JOB);
    await_busy(q);
    int64_t queued = submit_job(q, SHORT_JOB);
    int64_t after = submit_job(q, SHORT_JOB);
    cr_assert_eq(jobq_cancel(q, queued), 1);
    cr_assert_eq(log.n, 1, "a job cancelled in the queue leaves at once");
    cr_assert_eq(log.ids[0], queued);
    cr_assert_eq(jobq_cancel(q, queued), 0);
    cr_assert_eq(jobq_cancel(q, running), 2);
    cr_assert_eq(jobq_wait(q, after, WAIT_S), 0);
    jobq_stop(q);
    /* the running job left when its worker stopped it, then the last one when it finished */
    cr_assert_eq(log.n, 3, "left was called %d times", log.n);
    cr_assert_eq(log.ids[1], running);
    cr_assert_eq(log.ids[2], after);
}

/* ---- families' lanes ---- */

/* Stores a family of n members of the request base (a kp axis), as POST /api/families does;
 * their ids into ids (n). The family's id. */
static int64_t insert_family(const char *base, int n, int64_t *ids)
{
    char text[1024], err[256] = "";
    snprintf(text, sizeof text,
             "{\"base\": %s, \"axes\": [{\"path\": \"controller.kp\", \"linspace\": [50, 150, "
             "%d]}]}",
             base, n);
    family *f = NULL;
    family_error ferr;
    cr_assert_eq(family_expand(text, strlen(text), 100000, &f, &ferr), 0, "%s", ferr.message);
    store_new_member *m = calloc((size_t)n, sizeof *m);
    cr_assert_not_null(m);
    for (int i = 0; i < n; i++)
        m[i] = (store_new_member){.name = f->members[i].name,
                                  .preset = f->members[i].preset,
                                  .controller = f->members[i].controller,
                                  .spec = f->members[i].spec,
                                  .nbodies = f->members[i].nbodies,
                                  .nv = f->members[i].nv,
                                  .index = i,
                                  .values = f->members[i].values};
    int64_t id = 0;
    cr_assert_eq(
        store_family_insert(db, f->name, f->doc, f->paths, m, n, &id, ids, err, sizeof err), 0,
        "%s", err);
    free(m);
    family_free(f);
    return id;
}

typedef struct started_job {
    double started;
    int place; /* 0 single, 1 family A, 2 family B */
} started_job;

static int by_start(const void *a, const void *b)
{
    double x = ((const started_job *)a)->started, y = ((const started_job *)b)->started;
    return (x > y) - (x < y);
}

Test(jobq, single_jobs_and_each_family_take_turns_one_job_each)
{
    /* everything stored before the start, then recovered: the one worker's order is the turns'
       order alone */
    enum { NA = 6, NB = 3, NS = 4, N = NA + NB + NS };
    int64_t a[NA], b[NB], single[NS];
    started_job runs[N];
    insert_family(SHORT_JOB, NA, a);
    for (int i = 0; i < NS; i++) single[i] = insert_job(SHORT_JOB);
    insert_family(SHORT_JOB, NB, b);
    jobq *q = start_queue(1, 1, 0);
    jobq_stats st;
    jobq_get_stats(q, &st);
    cr_assert_eq(st.queued + st.busy + st.done, N, "every job recovered");
    int k = 0;
    for (int i = 0; i < NA; i++) runs[k++].place = 1;
    for (int i = 0; i < NB; i++) runs[k++].place = 2;
    for (int i = 0; i < NS; i++) runs[k++].place = 0;
    const int64_t *ids[3] = {single, a, b};
    const int count[3] = {NS, NA, NB};
    k = 0;
    for (int p = 1; p <= 2; p++)
        for (int i = 0; i < count[p]; i++, k++) {
            cr_assert_eq(jobq_wait(q, ids[p][i], WAIT_S), 0);
            store_job row = get_row(ids[p][i]);
            cr_assert_eq(row.status, STORE_DONE);
            cr_assert_eq(row.family, p == 1 ? 1 : 2);
            runs[k].started = row.started;
            store_job_clear(&row);
        }
    for (int i = 0; i < NS; i++, k++) {
        cr_assert_eq(jobq_wait(q, single[i], WAIT_S), 0);
        store_job row = get_row(single[i]);
        cr_assert_eq(row.family, 0);
        runs[k].started = row.started;
        store_job_clear(&row);
    }
    jobq_stop(q);
    qsort(runs, N, sizeof runs[0], by_start);
    /* single, A, B, single, A, B, single, A, B, single, A, then A's last two */
    const int want[N] = {0, 1, 2, 0, 1, 2, 0, 1, 2, 0, 1, 1, 1};
    for (int i = 0; i < N; i++)
        cr_assert_eq(runs[i].place, want[i], "run %d was from place %d, not %d", i, runs[i].place,
                     want[i]);
}

Test(jobq, cancelling_a_family_takes_its_queue_and_stops_its_running_member)
{
    int64_t ids[3];
    int64_t fam = insert_family(LONG_JOB, 3, ids);
    int64_t other = insert_job(SHORT_JOB);
    jobq *q = start_queue(1, 4, 0);
    /* the single job first, then the family's first member runs */
    await_status(ids[0], STORE_RUNNING, WAIT_S);
    int64_t *removed = NULL;
    long n = 0;
    double t0 = now();
    cr_assert_eq(jobq_cancel_family(q, fam, &removed, &n), 1, "one member was running");
    cr_assert(n == 2 && removed[0] == ids[1] && removed[1] == ids[2]);
    free(removed);
    char err[256] = "";
    long cancelled = 0;
    cr_assert_eq(store_family_cancel(db, fam, "cancelled by request", &cancelled, err, sizeof err),
                 0, "%s", err);
    cr_assert_eq(cancelled, 2);
    cr_assert_eq(jobq_wait(q, ids[0], WAIT_S), 0);
    cr_assert(now() - t0 < 5, "the running member stopped within a step");
    cr_assert_eq(get_status(ids[0]), STORE_CANCELLED);
    cr_assert_eq(get_status(ids[1]), STORE_CANCELLED);
    cr_assert_eq(get_status(other), STORE_DONE);
    jobq_stats st;
    jobq_get_stats(q, &st);
    cr_assert(st.queued == 0 && st.busy == 0);
    /* a family no longer queued: nothing to take */
    cr_assert_eq(jobq_cancel_family(q, fam, &removed, &n), 0);
    cr_assert(n == 0 && removed == NULL);
    jobq_stop(q);
}
