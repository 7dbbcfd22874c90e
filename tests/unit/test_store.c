/*
 * test_store.c - the service's SQLite storage (server/store.c): schema creation and refusal,
 * concurrency between connections, the job life cycle, atomic finishing, recovery, listing,
 * deletion and the series round trip.
 *
 * Oracles, each apart from the code under test:
 *  - the database file itself, read through a second, raw sqlite3 connection opened here: the
 *    schema version, the journal mode, the rows of the series table, PRAGMA integrity_check;
 *  - the library's own result: a real run (job_parse + ctc_sim_run) is stored, read back, and
 *    both are printed by result_out.c; the CSV and JSON texts must be byte-identical and the
 *    arrays bit-identical (memcmp, so NaN, -0 and infinities count too);
 *  - the clock: created, started and finished lie between readings taken around the calls;
 *  - a real SQLite failure in the middle of store_finish, raised by a trigger on the series
 *    table, to prove the transaction leaves nothing behind.
 * Error paths assert the exact message. Every test works in its own mkdtemp directory under
 * /tmp, removed at the end.
 */
#include <criterion/criterion.h>
#include <ctype.h>
#include <dirent.h>
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include <sqlite3.h>

#include "job_json.h"
#include "result_out.h"
#include "store.h"

#define NTHREAD_JOBS 200
#define NOPENERS 8

static char tmpdir[64];

/* ---- fixture: a fresh directory per test ---- */

static void setup(void)
{
    snprintf(tmpdir, sizeof tmpdir, "/tmp/ctcsim-store-XXXXXX");
    cr_assert_not_null(mkdtemp(tmpdir), "mkdtemp failed");
}

static void teardown(void)
{
    char path[512];
    DIR *d = opendir(tmpdir);
    if (!d) return;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (strcmp(e->d_name, ".") == 0 || strcmp(e->d_name, "..") == 0) continue;
        snprintf(path, sizeof path, "%s/%s", tmpdir, e->d_name);
        unlink(path);
    }
    closedir(d);
    rmdir(tmpdir);
}

TestSuite(store, .init = setup, .fini = teardown);

/* ---- helpers ---- */

static void path_of(char *buf, size_t len, const char *name)
{
    snprintf(buf, len, "%s/%s", tmpdir, name);
}

static double wall_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static store *open_ok(const char *path)
{
    store *s = NULL;
    char err[512] = "";
    cr_assert_eq(store_open(path, &s, err, sizeof err), 0, "store_open %s: %s", path, err);
    cr_assert_not_null(s);
    return s;
}

/* a new store in the test's folder: its path (ctcsim.db there) into path (len bytes), opened */
static store *open_new(char *path, size_t len)
{
    path_of(path, len, "ctcsim.db");
    return open_ok(path);
}

static int64_t insert_job(store *s, const char *name)
{
    int64_t id = 0;
    char err[512] = "";
    cr_assert_eq(
        store_insert(s, name, NULL, 3, 3, "pid", "{\"name\": \"x\"}", &id, err, sizeof err), 0,
        "store_insert: %s", err);
    return id;
}

/* a job taken through start and finish with r (may be NULL) */
static int64_t finished_job(store *s, const char *name, store_status st, const ctc_sim_result *r)
{
    char err[512] = "";
    int64_t id = insert_job(s, name);
    cr_assert_eq(store_start(s, id, err, sizeof err), 0, "store_start: %s", err);
    cr_assert_eq(store_finish(s, id, st, NULL, "{}", r, err, sizeof err), 0, "store_finish: %s",
                 err);
    return id;
}

/* raw connection for looking at the file apart from store.c */
static sqlite3 *raw_open(const char *path)
{
    sqlite3 *db = NULL;
    cr_assert_eq(sqlite3_open(path, &db), SQLITE_OK, "sqlite3_open %s", path);
    sqlite3_busy_timeout(db, 5000);
    return db;
}

static void raw_exec(const char *path, const char *sql)
{
    sqlite3 *db = raw_open(path);
    char *why = NULL;
    int rc = sqlite3_exec(db, sql, NULL, NULL, &why);
    cr_assert_eq(rc, SQLITE_OK, "%s: %s", sql, why ? why : "");
    sqlite3_free(why);
    sqlite3_close(db);
}

/* sql prepared on a raw connection (the test fails when it does not prepare) */
static sqlite3_stmt *raw_prepare(sqlite3 *db, const char *sql)
{
    sqlite3_stmt *q = NULL;
    cr_assert_eq(sqlite3_prepare_v2(db, sql, -1, &q, NULL), SQLITE_OK, "%s: %s", sql,
                 sqlite3_errmsg(db));
    return q;
}

/* the first column of the first row of sql, with ?1 bound to arg when sql has a parameter;
 * text goes to buf (may be NULL) */
static long long raw_query(const char *path, const char *sql, long long arg, char *buf, size_t len)
{
    sqlite3 *db = raw_open(path);
    sqlite3_stmt *q = raw_prepare(db, sql);
    if (sqlite3_bind_parameter_count(q) > 0) sqlite3_bind_int64(q, 1, arg);
    cr_assert_eq(sqlite3_step(q), SQLITE_ROW, "%s: no row", sql);
    long long v = sqlite3_column_int64(q, 0);
    if (buf) snprintf(buf, len, "%s", (const char *)sqlite3_column_text(q, 0));
    sqlite3_finalize(q);
    sqlite3_close(db);
    return v;
}

static long long raw_int(const char *path, const char *sql, long long arg)
{
    return raw_query(path, sql, arg, NULL, 0);
}

static void assert_integrity(const char *path)
{
    char text[256];
    raw_query(path, "PRAGMA integrity_check", 0, text, sizeof text);
    cr_assert_str_eq(text, "ok");
}

/* closes s and checks that its file at path passes SQLite's integrity check */
static void close_intact(store *s, const char *path)
{
    store_close(s);
    assert_integrity(path);
}

/* a hand-made result: nsamples samples of t, q (nq wide), tau (nv wide) and energy, with
 * e_max when given; every array malloc'd so ctc_sim_result_free frees it */
static ctc_sim_result *make_result(int nsamples, int nq, int nv, const double *e_max)
{
    ctc_sim_result *r = calloc(1, sizeof *r);
    cr_assert_not_null(r);
    r->nq = nq, r->nv = nv, r->nsamples = nsamples;
    r->channels = CTC_CH_BIT(CTC_CH_Q) | CTC_CH_BIT(CTC_CH_TAU) | CTC_CH_BIT(CTC_CH_ENERGY);
    r->width[CTC_CH_Q] = nq;
    r->width[CTC_CH_TAU] = nv;
    r->width[CTC_CH_ENERGY] = 2;
    r->t = malloc(sizeof(double) * (size_t)(nsamples + 1));
    for (int j = 0; j < nsamples; j++) r->t[j] = 0.01 * j;
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (!r->width[c]) continue;
        size_t count = (size_t)nsamples * (size_t)r->width[c];
        r->ch[c] = malloc(sizeof(double) * (count + 1));
        for (size_t k = 0; k < count; k++) r->ch[c][k] = c + 0.25 * (double)k;
    }
    r->metrics.nv = nv;
    r->metrics.wall_s = 0.125;
    r->metrics.diverged_joint = -1;
    if (e_max) {
        r->metrics.e_max = malloc(sizeof(double) * (size_t)nv);
        memcpy(r->metrics.e_max, e_max, sizeof(double) * (size_t)nv);
    }
    return r;
}

/* the CSV (or series JSON) that result_out.c prints for r */
static char *printed(const ctc_sim_result *r, const result_select *sel, int json)
{
    char *buf = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&buf, &len);
    cr_assert_not_null(f);
    int rc = json ? result_write_series_json(f, r, sel) : result_write_csv(f, r, sel);
    cr_assert_eq(rc, 0);
    fclose(f);
    return buf;
}

/* the two results hold the same series, bit for bit */
static void assert_same_series(const ctc_sim_result *a, const ctc_sim_result *b)
{
    cr_assert_eq(b->nsamples, a->nsamples);
    cr_assert_eq(b->channels, a->channels);
    cr_assert_eq(b->nq, a->nq);
    cr_assert_eq(b->nv, a->nv);
    cr_assert_eq(b->metrics.nv, a->nv);
    cr_assert_eq(memcmp(b->t, a->t, sizeof(double) * (size_t)a->nsamples), 0, "t differs");
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        cr_assert_eq(b->width[c], a->width[c], "width of %s", ctc_channel_name((ctc_channel)c));
        if (!a->ch[c]) {
            cr_assert_null(b->ch[c], "%s appeared", ctc_channel_name((ctc_channel)c));
            continue;
        }
        cr_assert_not_null(b->ch[c], "%s is missing", ctc_channel_name((ctc_channel)c));
        size_t bytes = sizeof(double) * (size_t)a->nsamples * (size_t)a->width[c];
        cr_assert_eq(memcmp(b->ch[c], a->ch[c], bytes), 0, "%s differs",
                     ctc_channel_name((ctc_channel)c));
    }
}

/* ---- opening and the schema ---- */

Test(store, open_creates_the_current_schema_in_wal_mode)
{
    char path[256], mode[32];
    long counts[STORE_NSTATUS];
    char err[512] = "";
    store *s = open_new(path, sizeof path);
    cr_assert_eq(access(path, F_OK), 0, "the file was not created");
    cr_assert_eq(raw_int(path, "PRAGMA user_version", 0), STORE_SCHEMA_VERSION);
    raw_query(path, "PRAGMA journal_mode", 0, mode, sizeof mode);
    cr_assert_str_eq(mode, "wal");
    cr_assert_eq(raw_int(path,
                         "SELECT count(*) FROM sqlite_master WHERE type = 'table' AND name IN "
                         "('jobs', 'series')",
                         0),
                 2);
    cr_assert_eq(store_count(s, counts, err, sizeof err), 0, "%s", err);
    for (int i = 0; i < STORE_NSTATUS; i++) cr_assert_eq(counts[i], 0);
    store_close(s);
    store_close(NULL);
    assert_integrity(path);
}

Test(store, reopening_keeps_the_data_and_migrates_nothing)
{
    char path[256], before[8192], after[8192];
    char err[512] = "";
    store_job j;
    store *s = open_new(path, sizeof path);
    int64_t id = insert_job(s, "kept");
    store_close(s);
    const char *dump = "SELECT group_concat(type || ' ' || name || ' ' || ifnull(sql, ''), '; ') "
                       "FROM sqlite_master";
    raw_query(path, dump, 0, before, sizeof before);

    /* twice, the second while the first is still open */
    store *a = open_ok(path);
    store *b = open_ok(path);
    raw_query(path, dump, 0, after, sizeof after);
    cr_assert_str_eq(after, before);
    cr_assert_eq(raw_int(path, "PRAGMA user_version", 0), STORE_SCHEMA_VERSION);
    cr_assert_eq(store_get(b, id, &j, err, sizeof err), 0, "%s", err);
    cr_assert_str_eq(j.name, "kept");
    store_job_clear(&j);
    store_close(a);
    store_close(b);
    assert_integrity(path);
}

typedef struct opener {
    const char *path;
    pthread_barrier_t *go;
    int rc;
    char err[512];
} opener;

static void *open_at_once(void *arg)
{
    opener *o = arg;
    store *s = NULL;
    pthread_barrier_wait(o->go);
    o->rc = store_open(o->path, &s, o->err, sizeof o->err);
    store_close(s);
    return NULL;
}

Test(store, connections_opening_a_new_database_at_once_migrate_it_once)
{
    char path[256];
    pthread_t th[NOPENERS];
    opener o[NOPENERS];
    pthread_barrier_t go;
    path_of(path, sizeof path, "new.db");
    pthread_barrier_init(&go, NULL, NOPENERS);
    for (int i = 0; i < NOPENERS; i++) {
        o[i] = (opener){.path = path, .go = &go};
        cr_assert_eq(pthread_create(&th[i], NULL, open_at_once, &o[i]), 0);
    }
    for (int i = 0; i < NOPENERS; i++) pthread_join(th[i], NULL);
    pthread_barrier_destroy(&go);
    /* a second migration would have failed with "table jobs already exists" */
    for (int i = 0; i < NOPENERS; i++) cr_assert_eq(o[i].rc, 0, "opener %d: %s", i, o[i].err);
    cr_assert_eq(raw_int(path, "PRAGMA user_version", 0), STORE_SCHEMA_VERSION);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM sqlite_master WHERE name = 'jobs'", 0), 1);
    assert_integrity(path);
}

typedef struct inserter {
    const char *path;
    int which;
    pthread_barrier_t *go;
    int64_t ids[NTHREAD_JOBS];
    int rc;
    char err[512];
} inserter;

static void *insert_many(void *arg)
{
    inserter *w = arg;
    store *s = NULL;
    char name[64];
    w->rc = store_open(w->path, &s, w->err, sizeof w->err);
    pthread_barrier_wait(w->go);
    for (int i = 0; w->rc == 0 && i < NTHREAD_JOBS; i++) {
        snprintf(name, sizeof name, "thread %d job %d", w->which, i);
        w->rc = store_insert(s, name, "triple_pendulum_pd", 3, 3, "pd", "{}", &w->ids[i], w->err,
                             sizeof w->err);
    }
    store_close(s);
    return NULL;
}

static int cmp_id(const void *a, const void *b)
{
    int64_t x = *(const int64_t *)a, y = *(const int64_t *)b;
    return (x > y) - (x < y);
}

Test(store, two_connections_in_two_threads_insert_400_distinct_jobs)
{
    char path[256], name[64];
    char err[512] = "";
    pthread_t th[2];
    inserter w[2];
    pthread_barrier_t go;
    int64_t all[2 * NTHREAD_JOBS];
    path_of(path, sizeof path, "ctcsim.db");
    store_close(open_ok(path));
    pthread_barrier_init(&go, NULL, 2);
    for (int i = 0; i < 2; i++) {
        memset(&w[i], 0, sizeof w[i]);
        w[i].path = path, w[i].which = i, w[i].go = &go;
        cr_assert_eq(pthread_create(&th[i], NULL, insert_many, &w[i]), 0);
    }
    for (int i = 0; i < 2; i++) pthread_join(th[i], NULL);
    pthread_barrier_destroy(&go);
    for (int i = 0; i < 2; i++) cr_assert_eq(w[i].rc, 0, "thread %d: %s", i, w[i].err);

    /* distinct ids, increasing within each thread, each row holding its own name */
    store *s = open_ok(path);
    for (int i = 0; i < 2; i++)
        for (int k = 0; k < NTHREAD_JOBS; k++) {
            store_job j;
            all[i * NTHREAD_JOBS + k] = w[i].ids[k];
            if (k > 0) cr_assert_gt(w[i].ids[k], w[i].ids[k - 1]);
            cr_assert_eq(store_get(s, w[i].ids[k], &j, err, sizeof err), 0, "%s", err);
            snprintf(name, sizeof name, "thread %d job %d", i, k);
            cr_assert_str_eq(j.name, name);
            store_job_clear(&j);
        }
    qsort(all, 2 * NTHREAD_JOBS, sizeof all[0], cmp_id);
    for (int k = 1; k < 2 * NTHREAD_JOBS; k++) cr_assert_neq(all[k], all[k - 1]);

    store_job *rows = NULL;
    int n = 0;
    cr_assert_eq(store_list(s, 0, -1, 1000, &rows, &n, err, sizeof err), 0, "%s", err);
    cr_assert_eq(n, 2 * NTHREAD_JOBS);
    for (int k = 0; k < n; k++) cr_assert_eq(rows[k].id, all[n - 1 - k]);
    store_jobs_free(rows, n);
    long counts[STORE_NSTATUS];
    cr_assert_eq(store_count(s, counts, err, sizeof err), 0, "%s", err);
    cr_assert_eq(counts[STORE_QUEUED], 2 * NTHREAD_JOBS);
    close_intact(s, path);
}

/* store_open must fail with exactly want (the path's "%s" filled in) and return no store */
static void assert_open_fails(const char *path, const char *want_fmt)
{
    char want[1024], err[1024] = "";
    store *s = (store *)&err; /* any non-NULL value: store_open must clear it */
    snprintf(want, sizeof want, want_fmt, path);
    cr_assert_eq(store_open(path, &s, err, sizeof err), -1);
    cr_assert_null(s);
    cr_assert_str_eq(err, want);
}

Test(store, refuses_a_file_that_is_not_sqlite)
{
    char path[256], back[256] = "";
    const char text[] = "name,mass\nlink,1.0\nthis is a CSV file, not a database\n";
    path_of(path, sizeof path, "notes.csv");
    FILE *f = fopen(path, "w");
    cr_assert_not_null(f);
    fputs(text, f);
    fclose(f);
    assert_open_fails(path, "cannot open database %s: file is not a database");
    /* left untouched */
    f = fopen(path, "r");
    size_t n = fread(back, 1, sizeof back - 1, f);
    fclose(f);
    back[n] = '\0';
    cr_assert_str_eq(back, text);
}

/* ---- counting ---- */

/* store_count against the oracle: count(*) over the table for each status, on a raw connection */
static void assert_counts_match_the_table(store *s, const char *path)
{
    long counts[STORE_NSTATUS];
    char err[512] = "";
    cr_assert_eq(store_count(s, counts, err, sizeof err), 0, "%s", err);
    sqlite3 *db = raw_open(path);
    sqlite3_stmt *q = raw_prepare(db, "SELECT count(*) FROM jobs WHERE status = ?1");
    for (int st = 0; st < STORE_NSTATUS; st++) {
        sqlite3_bind_text(q, 1, store_status_name((store_status)st), -1, SQLITE_STATIC);
        cr_assert_eq(sqlite3_step(q), SQLITE_ROW);
        cr_assert_eq(counts[st], sqlite3_column_int64(q, 0), "%s: %ld, the table has %lld",
                     store_status_name((store_status)st), counts[st],
                     (long long)sqlite3_column_int64(q, 0));
        sqlite3_reset(q);
    }
    sqlite3_finalize(q);
    sqlite3_close(db);
}

Test(store, counting_5000_jobs_reads_the_counts_not_the_table)
{
    /* 5,000 jobs written by another connection in all six statuses: the counts stay exact
     * through inserts, status changes and deletes, and store_count's work (SQLite VM steps)
     * does not grow with the table (a scan takes several steps a row, > 5,000 here) */
    char path[256], err[512] = "";
    store *s = open_new(path, sizeof path);
    raw_exec(path, "BEGIN;"
                   "WITH RECURSIVE k(i) AS (SELECT 0 UNION ALL SELECT i + 1 FROM k WHERE i < 4999)"
                   "INSERT INTO jobs (name, status, created, nbodies, nv, controller, spec)"
                   "  SELECT 'j' || i, CASE i % 6 WHEN 0 THEN 'queued' WHEN 1 THEN 'running'"
                   "    WHEN 2 THEN 'done' WHEN 3 THEN 'failed' WHEN 4 THEN 'diverged'"
                   "    ELSE 'cancelled' END, 0, 1, 1, 'none', '{}' FROM k;"
                   "COMMIT;");
    assert_counts_match_the_table(s, path);
    long small = store_count_vm_steps(s);
    cr_assert_gt(small, 0);
    cr_assert_lt(small, 200, "store_count took %ld VM steps over 5,000 jobs", small);

    raw_exec(path, "UPDATE jobs SET status = 'done' WHERE status = 'running' AND id % 2 = 0;"
                   "UPDATE jobs SET name = 'renamed' WHERE status = 'queued';"
                   "DELETE FROM jobs WHERE status = 'failed' AND id % 3 = 0;");
    int64_t id = insert_job(s, "one more");
    cr_assert_eq(store_start(s, id, err, sizeof err), 0, "%s", err);
    assert_counts_match_the_table(s, path);
    cr_assert_eq(store_count_vm_steps(s), small, "the same six rows, the same work");
    store_close(s);
}

/* the jobs and series tables as version 1 of store.c created them */
#define V1_TABLES                                                                                  \
    "CREATE TABLE jobs (id INTEGER PRIMARY KEY AUTOINCREMENT, name TEXT NOT NULL,"                 \
    "  preset TEXT, status TEXT NOT NULL DEFAULT 'queued' CHECK (status IN ('queued',"             \
    "  'running', 'done', 'failed', 'diverged', 'cancelled')),"                                    \
    "  progress REAL NOT NULL DEFAULT 0, created REAL NOT NULL,"                                   \
    "  started REAL NOT NULL DEFAULT 0, finished REAL NOT NULL DEFAULT 0,"                         \
    "  nbodies INTEGER NOT NULL, nv INTEGER NOT NULL, controller TEXT NOT NULL,"                   \
    "  spec TEXT NOT NULL, metrics TEXT, message TEXT, e_max REAL, wall_s REAL);"                  \
    "CREATE INDEX jobs_by_status ON jobs (status);"                                                \
    "CREATE TABLE series (job_id INTEGER NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,"         \
    "  channel TEXT NOT NULL, width INTEGER NOT NULL CHECK (width > 0),"                           \
    "  nsamples INTEGER NOT NULL CHECK (nsamples >= 0), data BLOB NOT NULL,"                       \
    "  PRIMARY KEY (job_id, channel));"

Test(store, a_version_1_database_is_migrated_with_its_counts)
{
    /* a version 1 file (jobs and series, no job_counts) with jobs in it: open adds the counts,
     * taken from the table once, and keeps them after */
    char path[256], err[512] = "";
    path_of(path, sizeof path, "ctcsim.db");
    raw_exec(path, V1_TABLES
             "INSERT INTO jobs (name, status, created, nbodies, nv, controller, spec) VALUES"
             "  ('a', 'done', 0, 1, 1, 'none', '{}'), ('b', 'done', 0, 1, 1, 'none', '{}'),"
             "  ('c', 'queued', 0, 1, 1, 'none', '{}'), ('d', 'failed', 0, 1, 1, 'none', '{}');"
             "PRAGMA user_version = 1;");
    store *s = open_ok(path);
    cr_assert_eq(raw_int(path, "PRAGMA user_version", 0), STORE_SCHEMA_VERSION);
    long counts[STORE_NSTATUS];
    cr_assert_eq(store_count(s, counts, err, sizeof err), 0, "%s", err);
    cr_assert(counts[STORE_DONE] == 2 && counts[STORE_QUEUED] == 1 && counts[STORE_FAILED] == 1 &&
              counts[STORE_RUNNING] == 0);
    finished_job(s, "e", STORE_DIVERGED, NULL);
    assert_counts_match_the_table(s, path);
    store_close(s);
}

/* the schema of version 2 as that version of store.c created it (migrations 0 -> 1 -> 2) */
static const char v2_schema[] = V1_TABLES
    "CREATE TABLE job_counts (status TEXT PRIMARY KEY, n INTEGER NOT NULL CHECK (n >= 0))"
    "  WITHOUT ROWID;"
    "INSERT INTO job_counts (status, n) VALUES ('queued', 0), ('running', 0), ('done', 0),"
    "  ('failed', 0), ('diverged', 0), ('cancelled', 0);"
    "CREATE TRIGGER job_counts_insert AFTER INSERT ON jobs BEGIN"
    "  UPDATE job_counts SET n = n + 1 WHERE status = NEW.status; END;"
    "CREATE TRIGGER job_counts_delete AFTER DELETE ON jobs BEGIN"
    "  UPDATE job_counts SET n = n - 1 WHERE status = OLD.status; END;"
    "CREATE TRIGGER job_counts_update AFTER UPDATE OF status ON jobs"
    "  WHEN OLD.status <> NEW.status BEGIN"
    "  UPDATE job_counts SET n = n - 1 WHERE status = OLD.status;"
    "  UPDATE job_counts SET n = n + 1 WHERE status = NEW.status; END;"
    "PRAGMA user_version = 2;";

Test(store, a_version_2_database_is_migrated_and_keeps_every_job)
{
    /* a version 2 file with jobs of every kind, one with a series: open adds families and the
     * members' columns, and every old job reads back as it was, in no family */
    char path[256], err[512] = "";
    path_of(path, sizeof path, "ctcsim.db");
    raw_exec(path, v2_schema);
    raw_exec(path,
             "INSERT INTO jobs (name, preset, status, progress, created, started, finished,"
             "  nbodies, nv, controller, spec, metrics, message, e_max, wall_s) VALUES"
             "  ('old done', 'triple_pendulum_pid', 'done', 1, 100.5, 101, 102, 3, 3, 'pid',"
             "   '{\"name\": \"old done\"}', '{\"steps\": 7}', NULL, 0.25, 1.5),"
             "  ('old queued', NULL, 'queued', 0, 103, 0, 0, 2, 2, 'pd', '{}', NULL, NULL, NULL,"
             "   NULL),"
             "  ('old failed', NULL, 'failed', 0.5, 104, 105, 106, 1, 1, 'none', '{}', NULL,"
             "   'it broke', NULL, 2);"
             "INSERT INTO series (job_id, channel, width, nsamples, data) VALUES"
             "  (1, 't', 1, 1, x'0000000000000000');");
    store *s = open_ok(path);
    cr_assert_eq(raw_int(path, "PRAGMA user_version", 0), STORE_SCHEMA_VERSION);
    assert_integrity(path);

    store_job j;
    cr_assert_eq(store_get(s, 1, &j, err, sizeof err), 0, "%s", err);
    cr_assert_str_eq(j.name, "old done");
    cr_assert_str_eq(j.preset, "triple_pendulum_pid");
    cr_assert_eq(j.status, STORE_DONE);
    cr_assert(j.created == 100.5 && j.started == 101 && j.finished == 102);
    cr_assert(j.nbodies == 3 && j.nv == 3 && j.e_max == 0.25 && j.wall_s == 1.5);
    cr_assert_str_eq(j.spec, "{\"name\": \"old done\"}");
    cr_assert_str_eq(j.metrics, "{\"steps\": 7}");
    cr_assert_eq(j.family, 0);
    store_job_clear(&j);
    cr_assert_eq(store_get(s, 3, &j, err, sizeof err), 0, "%s", err);
    cr_assert_str_eq(j.message, "it broke");
    cr_assert_eq(j.family, 0);
    store_job_clear(&j);
    store_series_info info;
    cr_assert_eq(store_get_series_info(s, 1, &info, err, sizeof err), 0, "%s", err);
    cr_assert_eq(info.nsamples, 1);

    /* the old queued job is recovered as before; counts are the table's */
    int64_t *ids = NULL;
    int n = 0;
    cr_assert_eq(store_recover(s, &ids, &n, err, sizeof err), 0, "%s", err);
    cr_assert(n == 1 && ids[0] == 2);
    int64_t fam = -1;
    cr_assert_eq(store_job_families(s, ids, n, &fam, err, sizeof err), 0, "%s", err);
    cr_assert_eq(fam, 0);
    free(ids);
    assert_counts_match_the_table(s, path);

    /* and a family can be stored beside them, its ids after theirs */
    store_new_member m = {
        .name = "m", .controller = "pd", .spec = "{}", .nbodies = 1, .nv = 1, .values = "[1]"};
    int64_t family_id = 0, member = 0;
    cr_assert_eq(
        store_family_insert(s, "f", "{}", "[\"n\"]", &m, 1, &family_id, &member, err, sizeof err),
        0, "%s", err);
    cr_assert(family_id == 1 && member == 4);
    close_intact(s, path);
}

/* n members of one family, member i with values [i] */
static int64_t insert_family(store *s, long n, int64_t *ids)
{
    char err[512] = "";
    store_new_member *m = calloc((size_t)n + 1, sizeof *m);
    char(*names)[32] = calloc((size_t)n + 1, sizeof *names);
    char(*values)[32] = calloc((size_t)n + 1, sizeof *values);
    cr_assert(m && names && values);
    for (long i = 0; i < n; i++) {
        snprintf(names[i], sizeof names[i], "member %ld", i);
        snprintf(values[i], sizeof values[i], "[%ld]", i);
        m[i] = (store_new_member){.name = names[i],
                                  .preset = i % 2 ? "p" : NULL,
                                  .controller = "pd",
                                  .spec = "{\"s\": 1}",
                                  .nbodies = 2,
                                  .nv = 2,
                                  .index = i,
                                  .replica = (int)(i % 3),
                                  .values = values[i]};
    }
    int64_t id = 0;
    cr_assert_eq(store_family_insert(s, "sweep", "{\"base\": {}}", "[\"controller.kp\"]", m, n, &id,
                                     ids, err, sizeof err),
                 0, "%s", err);
    free(m);
    free(names);
    free(values);
    return id;
}

Test(store, a_family_round_trips_with_its_members_counts_and_table)
{
    char path[256], err[512] = "";
    store *s = open_new(path, sizeof path);
    int64_t lone = insert_job(s, "alone");
    int64_t ids[5];
    double before = wall_now();
    int64_t fam = insert_family(s, 5, ids);
    double after = wall_now();
    for (int i = 0; i < 5; i++)
        cr_assert_eq(ids[i], lone + 1 + i, "member %d has id %lld", i, (long long)ids[i]);
    /* the members are ordinary jobs that name their family; the lone job names none */
    store_job j;
    cr_assert_eq(store_get(s, ids[3], &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.family, fam);
    cr_assert_str_eq(j.name, "member 3");
    cr_assert_str_eq(j.preset, "p");
    cr_assert_eq(j.status, STORE_QUEUED);
    store_job_clear(&j);
    cr_assert_eq(store_get(s, lone, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.family, 0);
    store_job_clear(&j);

    /* two members run: the counts and the member table follow */
    cr_assert_eq(store_start(s, ids[0], err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_finish(s, ids[0], STORE_DONE, NULL, "{\"steps\": 9}", NULL, err, sizeof err),
                 0, "%s", err);
    cr_assert_eq(store_start(s, ids[1], err, sizeof err), 0, "%s", err);
    store_family f;
    cr_assert_eq(store_family_get(s, fam, &f, err, sizeof err), 0, "%s", err);
    cr_assert_str_eq(f.name, "sweep");
    cr_assert_str_eq(f.spec, "{\"base\": {}}");
    cr_assert_str_eq(f.axes, "[\"controller.kp\"]");
    cr_assert_eq(f.members, 5);
    cr_assert(f.created >= before && f.created <= after);
    cr_assert(f.counts[STORE_DONE] == 1 && f.counts[STORE_RUNNING] == 1 &&
              f.counts[STORE_QUEUED] == 3 && f.counts[STORE_CANCELLED] == 0);
    store_family_clear(&f);
    store_member *rows = NULL;
    long n = 0;
    cr_assert_eq(store_family_members(s, fam, &rows, &n, err, sizeof err), 0, "%s", err);
    cr_assert_eq(n, 5);
    for (long i = 0; i < n; i++) {
        char want[32];
        snprintf(want, sizeof want, "[%ld]", i);
        cr_assert(rows[i].job == ids[i] && rows[i].index == i && rows[i].replica == i % 3);
        cr_assert_str_eq(rows[i].values, want);
    }
    cr_assert_str_eq(rows[0].metrics, "{\"steps\": 9}");
    cr_assert_null(rows[1].metrics);
    cr_assert_eq(rows[1].status, STORE_RUNNING);
    store_members_free(rows, n);

    /* the active members; a cancel records the queued ones and leaves the running one */
    int64_t *active = NULL;
    cr_assert_eq(store_family_active(s, fam, &active, &n, err, sizeof err), 0, "%s", err);
    cr_assert(n == 4 && active[0] == ids[1]);
    free(active);
    cr_assert_eq(store_family_delete(s, fam, err, sizeof err), 2);
    cr_assert_eq(store_family_cancel(s, fam, "cancelled by request", &n, err, sizeof err), 0, "%s",
                 err);
    cr_assert_eq(n, 3);
    cr_assert_eq(store_start(s, ids[4], err, sizeof err), 1, "a cancelled member does not start");
    cr_assert_eq(store_family_delete(s, fam, err, sizeof err), 2, "a member still runs");
    cr_assert_eq(store_finish(s, ids[1], STORE_CANCELLED, "cancelled", NULL, NULL, err, sizeof err),
                 0, "%s", err);
    assert_counts_match_the_table(s, path);

    /* deleted whole: the family, its members; the lone job stays */
    cr_assert_eq(store_family_delete(s, fam, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_family_get(s, fam, &f, err, sizeof err), 1);
    cr_assert_eq(store_family_delete(s, fam, err, sizeof err), 1);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM jobs", 0), 1);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM families", 0), 0);
    assert_counts_match_the_table(s, path);
    close_intact(s, path);
}

Test(store, families_list_newest_first_with_counts_and_ten_thousand_members_insert_at_once)
{
    char path[256], err[512] = "";
    store *s = open_new(path, sizeof path);
    int64_t *ids = calloc(10000, sizeof *ids);
    cr_assert_not_null(ids);
    int64_t a = insert_family(s, 2, ids);
    int64_t b = insert_family(s, 10000, ids);
    int64_t c = insert_family(s, 0, ids);
    cr_assert_eq(ids[9999] - ids[0], 9999, "the members' ids increase with their index");
    store_family *rows = NULL;
    int n = 0;
    cr_assert_eq(store_family_list(s, 0, 2, &rows, &n, err, sizeof err), 0, "%s", err);
    cr_assert(n == 2 && rows[0].id == c && rows[1].id == b);
    cr_assert_null(rows[0].spec, "lists leave the spec out");
    cr_assert(rows[1].members == 10000 && rows[1].counts[STORE_QUEUED] == 10000);
    store_families_free(rows, n);
    cr_assert_eq(store_family_list(s, b, 10, &rows, &n, err, sizeof err), 0, "%s", err);
    cr_assert(n == 1 && rows[0].id == a && rows[0].counts[STORE_QUEUED] == 2);
    store_families_free(rows, n);
    cr_assert_eq(store_family_list(s, 0, 0, &rows, &n, err, sizeof err), -1);
    cr_assert_str_eq(err, "limit must be between 1 and 1000 (got 0)");

    /* recovery sorts the members from the single jobs */
    int64_t lone = insert_job(s, "alone");
    int64_t *rec = NULL, fams[10003];
    cr_assert_eq(store_recover(s, &rec, &n, err, sizeof err), 0, "%s", err);
    cr_assert_eq(n, 10003);
    cr_assert_eq(store_job_families(s, rec, n, fams, err, sizeof err), 0, "%s", err);
    cr_assert(fams[0] == a && fams[1] == a && fams[2] == b && fams[10001] == b);
    cr_assert(rec[10002] == lone && fams[10002] == 0);
    free(rec);
    free(ids);
    assert_counts_match_the_table(s, path);
    store_close(s);
}

Test(store, a_familys_counts_read_the_covering_index_alone)
{
    /* the plan of the counts' statement (store.c's ST_FAMILY_COUNTS), as SQLite makes it on a
     * database that store_open made: a search of jobs_by_family_status with no table rows
     * read, and no temporary tree for the grouping (the index gives the rows grouped) */
    char path[256];
    path_of(path, sizeof path, "ctcsim.db");
    store_close(open_ok(path));
    sqlite3 *db = raw_open(path);
    sqlite3_stmt *q = raw_prepare(db, "EXPLAIN QUERY PLAN SELECT status, count(*) FROM jobs WHERE "
                                      "family_id = ?1 GROUP BY status");
    char plan[1024] = "";
    size_t used = 0;
    while (sqlite3_step(q) == SQLITE_ROW && used < sizeof plan)
        used += (size_t)snprintf(plan + used, sizeof plan - used, "%s;",
                                 (const char *)sqlite3_column_text(q, 3));
    sqlite3_finalize(q);
    sqlite3_close(db);
    cr_assert_str_eq(plan, "SEARCH jobs USING COVERING INDEX jobs_by_family_status (family_id=?);");
}

Test(store, refuses_a_newer_schema)
{
    char path[256];
    path_of(path, sizeof path, "ctcsim.db");
    raw_exec(path, "CREATE TABLE jobs (id INTEGER PRIMARY KEY, future TEXT); "
                   "PRAGMA user_version = 7;");
    assert_open_fails(path, "database %s has schema version 7, newer than this ctcsim (4): "
                            "upgrade ctcsim");
    cr_assert_eq(raw_int(path, "PRAGMA user_version", 0), 7);
}

Test(store, refuses_a_database_that_is_not_ctcsims)
{
    char path[256];
    path_of(path, sizeof path, "other.db");
    raw_exec(path, "CREATE TABLE notes (body TEXT); INSERT INTO notes VALUES ('keep me');");
    assert_open_fails(path, "database %s is not a ctcsim database (it has tables but no ctcsim "
                            "schema version)");
    /* left untouched: no schema added, the other program's rows still there */
    cr_assert_eq(raw_int(path, "PRAGMA user_version", 0), 0);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM sqlite_master WHERE name = 'jobs'", 0), 0);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM notes WHERE body = 'keep me'", 0), 1);
}

Test(store, refuses_a_path_in_a_missing_directory_and_an_empty_path)
{
    char path[256], want[600], err[512] = "";
    store *s = NULL;
    path_of(path, sizeof path, "missing/ctcsim.db");
    snprintf(want, sizeof want, "cannot open database %s: directory %s/missing does not exist",
             path, tmpdir);
    cr_assert_eq(store_open(path, &s, err, sizeof err), -1);
    cr_assert_null(s);
    cr_assert_str_eq(err, want);
    cr_assert_eq(store_open("", &s, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot open database: the path is empty");
    /* err may be NULL */
    cr_assert_eq(store_open(path, &s, NULL, 0), -1);
}

/* ---- the job life cycle ---- */

Test(store, a_job_round_trips_every_field_through_its_life)
{
    char path[256], err[512] = "";
    const char *spec = "{\"name\":\"triple\",\"duration\":5}";
    const char *metrics = "{\"status\":\"diverged\",\"nv\":3}";
    const char *why = "t = 1.284 s: joint 2 speed 3.1e+06 rad/s exceeds the bound 1e+06";
    double e_max[3] = {0.25, NAN, 2.5};
    store_job j;
    int64_t id;
    store *s = open_new(path, sizeof path);

    /* inserted: queued, nothing measured yet */
    double t0 = wall_now();
    cr_assert_eq(
        store_insert(s, "triple", "triple_pendulum_pid", 3, 4, "pid", spec, &id, err, sizeof err),
        0, "%s", err);
    double t1 = wall_now();
    cr_assert_eq(store_get(s, id, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.id, id);
    cr_assert_str_eq(j.name, "triple");
    cr_assert_str_eq(j.preset, "triple_pendulum_pid");
    cr_assert_eq(j.status, STORE_QUEUED);
    cr_assert_eq(j.progress, 0.0);
    cr_assert(j.created >= t0 && j.created <= t1, "created %f not in [%f, %f]", j.created, t0, t1);
    cr_assert_eq(j.started, 0.0);
    cr_assert_eq(j.finished, 0.0);
    cr_assert_eq(j.nbodies, 3);
    cr_assert_eq(j.nv, 4);
    cr_assert_str_eq(j.controller, "pid");
    cr_assert_str_eq(j.spec, spec);
    cr_assert_null(j.metrics);
    cr_assert_null(j.message);
    cr_assert(isnan(j.e_max) && isnan(j.wall_s));
    store_job_clear(&j);
    cr_assert_null(j.name);

    /* started, then progressing (clamped into 0..1) */
    t0 = wall_now();
    cr_assert_eq(store_start(s, id, err, sizeof err), 0, "%s", err);
    t1 = wall_now();
    cr_assert_eq(store_progress(s, id, 0.5, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_get(s, id, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.status, STORE_RUNNING);
    cr_assert(j.started >= t0 && j.started <= t1);
    cr_assert_eq(j.progress, 0.5);
    store_job_clear(&j);
    cr_assert_eq(store_progress(s, id, 1.0000000001, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_get(s, id, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.progress, 1.0);
    store_job_clear(&j);
    cr_assert_eq(store_progress(s, id, NAN, err, sizeof err), -1);
    char want[128];
    snprintf(want, sizeof want, "job %lld: progress is NaN", (long long)id);
    cr_assert_str_eq(err, want);
    cr_assert_eq(store_progress(s, id, 0.75, err, sizeof err), 0, "%s", err);

    /* diverged: message, metrics, e_max over the finite entries, wall_s; progress kept */
    ctc_sim_result *r = make_result(4, 4, 3, e_max);
    t0 = wall_now();
    cr_assert_eq(store_finish(s, id, STORE_DIVERGED, why, metrics, r, err, sizeof err), 0, "%s",
                 err);
    t1 = wall_now();
    cr_assert_eq(store_get(s, id, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.status, STORE_DIVERGED);
    cr_assert_str_eq(j.message, why);
    cr_assert_str_eq(j.metrics, metrics);
    cr_assert_eq(j.e_max, 2.5);
    cr_assert_eq(j.wall_s, 0.125);
    cr_assert_eq(j.progress, 0.75);
    cr_assert(j.finished >= t0 && j.finished <= t1);
    cr_assert_str_eq(j.spec, spec);
    store_job_clear(&j);
    ctc_sim_result_free(r);

    /* done without a series: progress 1, "" message stored as none, no e_max, no wall_s */
    int64_t id2 = insert_job(s, "plain");
    cr_assert_eq(store_start(s, id2, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_finish(s, id2, STORE_DONE, "", "{}", NULL, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_get(s, id2, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.status, STORE_DONE);
    cr_assert_null(j.preset);
    cr_assert_null(j.message);
    cr_assert_str_eq(j.metrics, "{}");
    cr_assert_eq(j.progress, 1.0);
    cr_assert(isnan(j.e_max) && isnan(j.wall_s));
    store_job_clear(&j);
    cr_assert_gt(id2, id);

    cr_assert_eq(store_get(s, id2 + 100, &j, err, sizeof err), 1);
    close_intact(s, path);
}

/* the call's return and message, with the id filled into want_fmt */
#define assert_fails_with(call, ret, want_fmt, id)                                                 \
    do {                                                                                           \
        char want_[256];                                                                           \
        snprintf(want_, sizeof want_, want_fmt, (long long)(id));                                  \
        err[0] = '\0';                                                                             \
        cr_assert_eq((call), (ret));                                                               \
        cr_assert_str_eq(err, want_);                                                              \
    } while (0)

Test(store, transitions_refuse_jobs_in_the_wrong_state)
{
    char path[256], err[512] = "";
    store_job j;
    store *s = open_new(path, sizeof path);
    int64_t id = insert_job(s, "a");
    int64_t none = id + 1000;

    /* start: 1 unless queued */
    cr_assert_eq(store_start(s, none, err, sizeof err), 1);
    assert_fails_with(store_progress(s, id, 0.5, err, sizeof err), -1,
                      "cannot record progress of job %lld: it is queued, not running", id);
    assert_fails_with(store_progress(s, none, 0.5, err, sizeof err), -1,
                      "cannot record progress of job %lld: no such job", none);
    assert_fails_with(store_requeue(s, id, err, sizeof err), -1,
                      "cannot requeue job %lld: it is queued, not running", id);
    cr_assert_eq(store_start(s, id, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_start(s, id, err, sizeof err), 1);

    /* requeue: back to queued, progress and start undone */
    cr_assert_eq(store_progress(s, id, 0.3, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_requeue(s, id, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_get(s, id, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.status, STORE_QUEUED);
    cr_assert_eq(j.progress, 0.0);
    cr_assert_eq(j.started, 0.0);
    store_job_clear(&j);

    /* finish: a final status, once, of a job that exists */
    assert_fails_with(store_finish(s, id, STORE_RUNNING, NULL, NULL, NULL, err, sizeof err), -1,
                      "cannot finish job %lld as running: the status must be done, failed, "
                      "diverged or cancelled",
                      id);
    assert_fails_with(
        store_finish(s, id, (store_status)42, NULL, NULL, NULL, err, sizeof err), -1,
        "cannot finish job %lld as unknown: the status must be done, failed, diverged or "
        "cancelled",
        id);
    cr_assert_eq(
        store_finish(s, id, STORE_CANCELLED, "cancelled while queued", NULL, NULL, err, sizeof err),
        0, "%s", err);
    assert_fails_with(store_finish(s, id, STORE_DONE, NULL, "{}", NULL, err, sizeof err), -1,
                      "cannot finish job %lld: it is already cancelled", id);
    assert_fails_with(store_progress(s, id, 0.5, err, sizeof err), -1,
                      "cannot record progress of job %lld: it is cancelled, not running", id);
    cr_assert_eq(store_get(s, id, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.status, STORE_CANCELLED);
    cr_assert_str_eq(j.message, "cancelled while queued");
    cr_assert_null(j.metrics);
    store_job_clear(&j);

    /* an unknown id leaves nothing behind: no job row, no series row */
    ctc_sim_result *r = make_result(3, 3, 3, NULL);
    assert_fails_with(store_finish(s, none, STORE_DONE, NULL, "{}", r, err, sizeof err), -1,
                      "cannot finish job %lld: no such job", none);
    ctc_sim_result_free(r);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM series", 0), 0);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM jobs", 0), 1);

    /* bad arguments are messages, not crashes */
    int64_t out;
    cr_assert_eq(store_insert(s, NULL, NULL, 1, 1, "pd", "{}", &out, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot store a job without a name");
    cr_assert_eq(store_insert(s, "x", NULL, 0, 1, "pd", "{}", &out, err, sizeof err), -1);
    cr_assert_str_eq(err, "cannot store a job of 0 bodies and 1 coordinates");
    close_intact(s, path);
}

Test(store, a_finish_whose_series_fails_rolls_back_everything)
{
    char path[256], err[512] = "", want[256];
    store_job j;
    ctc_sim_result *got = NULL;
    store *s = open_new(path, sizeof path);
    int64_t id = insert_job(s, "doomed");
    cr_assert_eq(store_start(s, id, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_progress(s, id, 0.5, err, sizeof err), 0, "%s", err);

    /* a real SQLite failure on the third series row (t and q are written before tau) */
    raw_exec(path, "CREATE TRIGGER fail_tau BEFORE INSERT ON series WHEN NEW.channel = 'tau' "
                   "BEGIN SELECT RAISE(ABORT, 'simulated disk full'); END;");
    ctc_sim_result *r = make_result(5, 3, 3, (double[]){1, 2, 3});
    cr_assert_eq(store_finish(s, id, STORE_DONE, NULL, "{\"status\":\"done\"}", r, err, sizeof err),
                 -1);
    snprintf(want, sizeof want, "job %lld: storing series tau: simulated disk full", (long long)id);
    cr_assert_str_eq(err, want);

    /* nothing of the finish remains: still running, no series rows at all */
    cr_assert_eq(store_get(s, id, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.status, STORE_RUNNING);
    cr_assert_eq(j.progress, 0.5);
    cr_assert_eq(j.finished, 0.0);
    cr_assert_null(j.metrics);
    cr_assert(isnan(j.e_max) && isnan(j.wall_s));
    store_job_clear(&j);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM series", 0), 0);
    cr_assert_eq(store_get_series(s, id, &got, err, sizeof err), 1);
    cr_assert_null(got);

    /* no transaction was left open: another connection writes at once */
    store *other = open_ok(path);
    double t0 = wall_now();
    insert_job(other, "after");
    cr_assert_lt(wall_now() - t0, 1.0, "the other connection waited for a lock");
    store_close(other);

    /* and the same finish succeeds once the failure is gone */
    raw_exec(path, "DROP TRIGGER fail_tau;");
    cr_assert_eq(store_finish(s, id, STORE_DONE, NULL, "{\"status\":\"done\"}", r, err, sizeof err),
                 0, "%s", err);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM series WHERE job_id = ?1", id), 4);
    cr_assert_eq(store_get_series(s, id, &got, err, sizeof err), 0, "%s", err);
    assert_same_series(r, got);
    ctc_sim_result_free(got);
    ctc_sim_result_free(r);
    close_intact(s, path);
}

Test(store, recover_requeues_unfinished_jobs_and_drops_their_partial_series)
{
    char path[256], err[512] = "";
    int64_t *ids = NULL;
    int n = -1;
    store_job j;
    store *s = open_new(path, sizeof path);
    ctc_sim_result *r = make_result(3, 3, 3, NULL);

    /* nothing to recover in an empty database */
    cr_assert_eq(store_recover(s, &ids, &n, err, sizeof err), 0, "%s", err);
    cr_assert_eq(n, 0);
    free(ids);

    int64_t queued = insert_job(s, "queued");
    int64_t running = insert_job(s, "running");
    cr_assert_eq(store_start(s, running, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_progress(s, running, 0.5, err, sizeof err), 0, "%s", err);
    int64_t done = finished_job(s, "done", STORE_DONE, r);
    int64_t cancelled = insert_job(s, "cancelled");
    cr_assert_eq(store_finish(s, cancelled, STORE_CANCELLED, NULL, NULL, NULL, err, sizeof err), 0,
                 "%s", err);
    int64_t crashed = insert_job(s, "crashed");
    cr_assert_eq(store_start(s, crashed, err, sizeof err), 0, "%s", err);
    /* a partial series, as a crash of some earlier version might have left */
    sqlite3 *db = raw_open(path);
    sqlite3_stmt *q = raw_prepare(db, "INSERT INTO series (job_id, channel, width, nsamples, data) "
                                      "VALUES (?1, 't', 1, 0, x'')");
    sqlite3_bind_int64(q, 1, crashed);
    cr_assert_eq(sqlite3_step(q), SQLITE_DONE);
    sqlite3_finalize(q);
    sqlite3_close(db);

    /* twice: the second finds the same jobs, now all queued */
    for (int pass = 0; pass < 2; pass++) {
        cr_assert_eq(store_recover(s, &ids, &n, err, sizeof err), 0, "%s", err);
        cr_assert_eq(n, 3);
        cr_assert_eq(ids[0], queued);
        cr_assert_eq(ids[1], running);
        cr_assert_eq(ids[2], crashed);
        free(ids);
        for (int k = 0; k < 3; k++) {
            int64_t id = k == 0 ? queued : k == 1 ? running : crashed;
            cr_assert_eq(store_get(s, id, &j, err, sizeof err), 0, "%s", err);
            cr_assert_eq(j.status, STORE_QUEUED);
            cr_assert_eq(j.progress, 0.0);
            cr_assert_eq(j.started, 0.0);
            store_job_clear(&j);
        }
    }
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM series WHERE job_id = ?1", crashed), 0);

    /* finished jobs are untouched */
    cr_assert_eq(store_get(s, done, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.status, STORE_DONE);
    cr_assert_eq(j.progress, 1.0);
    cr_assert_gt(j.started, 0.0);
    store_job_clear(&j);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM series WHERE job_id = ?1", done), 4);
    cr_assert_eq(store_get(s, cancelled, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.status, STORE_CANCELLED);
    store_job_clear(&j);
    ctc_sim_result_free(r);
    close_intact(s, path);
}

/* the jobs of search_finds_..., as inserted: name, preset, controller, tags (JSON or NULL) */
static const struct {
    const char *name, *preset, *controller, *tags;
} search_jobs[] = {
    {"triple_pendulum_pid, kp = 400", "triple_pendulum_pid", "pid", "[\"sweep\", \"kp\"]"},
    {"Five-bar", "five_bar_lqr", "lqr", NULL},
    {"mine", NULL, "pd", "[\"Sweep-2\"]"},
    {"PID tuned", NULL, "pid", "[]"},
    {"other", "n_link_pendulum", "pd", "[\"sweep\"]"},
};

/* whether hay holds needle, ASCII case ignored (a plain double loop) */
static int contains_ci(const char *hay, const char *needle)
{
    size_t n = strlen(needle);
    for (const char *h = hay; *h; h++) {
        size_t i = 0;
        while (i < n && h[i] && tolower((unsigned char)h[i]) == tolower((unsigned char)needle[i]))
            i++;
        if (i == n) return 1;
    }
    return n == 0;
}

/* the naive oracle: does job k match text (ASCII case ignored) and tag */
static int search_match(int k, const char *text, const char *tag)
{
    if (text) {
        int hit = contains_ci(search_jobs[k].name, text) ||
                  (search_jobs[k].preset && contains_ci(search_jobs[k].preset, text)) ||
                  contains_ci(search_jobs[k].controller, text);
        cJSON *tags = search_jobs[k].tags ? cJSON_Parse(search_jobs[k].tags) : NULL;
        for (cJSON *t = tags ? tags->child : NULL; t && !hit; t = t->next)
            hit = contains_ci(t->valuestring, text);
        cJSON_Delete(tags);
        if (!hit) return 0;
    }
    if (tag) {
        int hit = 0;
        cJSON *tags = search_jobs[k].tags ? cJSON_Parse(search_jobs[k].tags) : NULL;
        for (cJSON *t = tags ? tags->child : NULL; t && !hit; t = t->next)
            hit = strcmp(t->valuestring, tag) == 0;
        cJSON_Delete(tags);
        if (!hit) return 0;
    }
    return 1;
}

Test(store, search_finds_text_in_name_preset_controller_and_tags_and_a_tag_exactly)
{
    char path[256], err[512] = "";
    int64_t ids[5];
    store *s = open_new(path, sizeof path);
    for (int k = 0; k < 5; k++) {
        char spec[256];
        if (search_jobs[k].tags)
            snprintf(spec, sizeof spec, "{\"name\": \"x\", \"tags\": %s}", search_jobs[k].tags);
        else
            snprintf(spec, sizeof spec, "{\"name\": \"x\"}");
        cr_assert_eq(store_insert(s, search_jobs[k].name, search_jobs[k].preset, 3, 3,
                                  search_jobs[k].controller, spec, &ids[k], err, sizeof err),
                     0, "%s", err);
    }
    /* job 0 finished with per-coordinate errors: the summaries the list shows */
    cr_assert_eq(store_start(s, ids[0], err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_finish(s, ids[0], STORE_DONE, NULL,
                              "{\"e_final\": [0.001, -0.004, null], \"e_rms\": [0.3, 0.4, 0]}",
                              NULL, err, sizeof err),
                 0, "%s", err);

    const char *texts[] = {NULL, "sweep", "PID", "pendulum", "kp", "LQR", "nothing", "%", "_"};
    const char *tags[] = {NULL, "sweep", "Sweep-2", "kp", "swe"};
    for (size_t a = 0; a < sizeof texts / sizeof *texts; a++) {
        for (size_t b = 0; b < sizeof tags / sizeof *tags; b++) {
            store_filter f = {.status = -1, .text = texts[a], .tag = tags[b]};
            store_job *rows = NULL;
            int n = 0;
            cr_assert_eq(store_search(s, 0, &f, 100, &rows, &n, err, sizeof err), 0, "%s", err);
            int want = 0;
            for (int k = 4; k >= 0; k--) {
                if (!search_match(k, texts[a], tags[b])) continue;
                cr_assert_lt(want, n, "q=%s tag=%s: job %d missing", texts[a], tags[b], k);
                cr_assert_eq(rows[want].id, ids[k], "q=%s tag=%s: newest first", texts[a], tags[b]);
                want++;
            }
            cr_assert_eq(n, want, "q=%s tag=%s: %d rows, the oracle %d", texts[a], tags[b], n,
                         want);
            store_jobs_free(rows, n);
        }
    }

    /* the summaries: max |e_final|, the root of the mean of e_rms^2, the tags as JSON */
    store_job *rows = NULL;
    int n = 0;
    cr_assert_eq(store_list(s, 0, -1, 10, &rows, &n, err, sizeof err), 0, "%s", err);
    cr_assert_eq(n, 5);
    cr_assert_eq(rows[4].id, ids[0]);
    cr_assert_float_eq(rows[4].e_final, 0.004, 1e-15);
    cr_assert_float_eq(rows[4].e_rms, sqrt((0.09 + 0.16) / 3), 1e-15);
    cJSON *t = cJSON_Parse(rows[4].tags);
    cr_assert(cJSON_IsArray(t) && cJSON_GetArraySize(t) == 2, "tags %s", rows[4].tags);
    cJSON_Delete(t);
    cr_assert(isnan(rows[0].e_final) && isnan(rows[0].e_rms), "no metrics: NaN");
    cr_assert_null(rows[3].tags, "no tags: NULL");
    store_jobs_free(rows, n);

    /* with a status */
    store_filter f = {.status = STORE_DONE, .text = "pid", .tag = NULL};
    cr_assert_eq(store_search(s, 0, &f, 10, &rows, &n, err, sizeof err), 0, "%s", err);
    cr_assert_eq(n, 1);
    cr_assert_eq(rows[0].id, ids[0]);
    store_jobs_free(rows, n);
    f = (store_filter){.status = -1, .text = "x", .tag = NULL};
    cr_assert_eq(store_search(s, 0, &f, 1001, &rows, &n, err, sizeof err), -1);
    cr_assert_str_eq(err, "limit must be between 1 and 1000 (got 1001)");
    store_close(s);
}

Test(store, list_pages_newest_first_with_a_status_filter)
{
    char path[256], err[512] = "", name[32];
    int64_t ids[25];
    store_job *rows = NULL;
    int n = 0;
    long counts[STORE_NSTATUS];
    store *s = open_new(path, sizeof path);
    /* job k: done when k % 3 == 0, running when k % 5 == 0 (and not done), else queued */
    for (int k = 0; k < 25; k++) {
        snprintf(name, sizeof name, "job %d", k);
        if (k % 3 == 0) {
            ids[k] = finished_job(s, name, STORE_DONE, NULL);
            continue;
        }
        ids[k] = insert_job(s, name);
        if (k % 5 == 0) cr_assert_eq(store_start(s, ids[k], err, sizeof err), 0, "%s", err);
    }

    /* pages of 10 through everything, each row light (no spec, no metrics) */
    int seen = 0;
    int64_t cursor = 0;
    for (int page = 0; page < 3; page++) {
        cr_assert_eq(store_list(s, cursor, -1, 10, &rows, &n, err, sizeof err), 0, "%s", err);
        cr_assert_eq(n, page < 2 ? 10 : 5);
        for (int i = 0; i < n; i++, seen++) {
            int k = 24 - seen;
            snprintf(name, sizeof name, "job %d", k);
            cr_assert_eq(rows[i].id, ids[k]);
            cr_assert_str_eq(rows[i].name, name);
            cr_assert_str_eq(rows[i].controller, "pid");
            cr_assert_eq(rows[i].nbodies, 3);
            cr_assert_null(rows[i].spec);
            cr_assert_null(rows[i].metrics);
            cr_assert_eq(rows[i].status, k % 3 == 0   ? STORE_DONE
                                         : k % 5 == 0 ? STORE_RUNNING
                                                      : STORE_QUEUED);
        }
        cursor = rows[n - 1].id;
        store_jobs_free(rows, n);
    }
    cr_assert_eq(seen, 25);
    cr_assert_eq(store_list(s, ids[0], -1, 10, &rows, &n, err, sizeof err), 0, "%s", err);
    cr_assert_eq(n, 0);
    store_jobs_free(rows, n);

    /* done only, below job 20: 18, 15, 12 */
    cr_assert_eq(store_list(s, ids[20], STORE_DONE, 3, &rows, &n, err, sizeof err), 0, "%s", err);
    cr_assert_eq(n, 3);
    cr_assert_eq(rows[0].id, ids[18]);
    cr_assert_eq(rows[1].id, ids[15]);
    cr_assert_eq(rows[2].id, ids[12]);
    for (int i = 0; i < n; i++) cr_assert_eq(rows[i].status, STORE_DONE);
    store_jobs_free(rows, n);
    cr_assert_eq(store_list(s, 0, STORE_RUNNING, 1000, &rows, &n, err, sizeof err), 0, "%s", err);
    cr_assert_eq(n, 3); /* 5, 10, 20 */
    cr_assert_eq(rows[0].id, ids[20]);
    cr_assert_eq(rows[2].id, ids[5]);
    store_jobs_free(rows, n);
    cr_assert_eq(store_count(s, counts, err, sizeof err), 0, "%s", err);
    cr_assert_eq(counts[STORE_DONE], 9);
    cr_assert_eq(counts[STORE_RUNNING], 3);
    cr_assert_eq(counts[STORE_QUEUED], 13);
    cr_assert_eq(counts[STORE_FAILED] + counts[STORE_DIVERGED] + counts[STORE_CANCELLED], 0);

    /* limits */
    cr_assert_eq(store_list(s, 0, -1, 0, &rows, &n, err, sizeof err), -1);
    cr_assert_str_eq(err, "limit must be between 1 and 1000 (got 0)");
    cr_assert_eq(store_list(s, 0, -1, 1001, &rows, &n, err, sizeof err), -1);
    cr_assert_str_eq(err, "limit must be between 1 and 1000 (got 1001)");
    cr_assert_eq(store_list(s, -4, -1, 10, &rows, &n, err, sizeof err), -1);
    cr_assert_str_eq(err, "before must be 0 or a job id (got -4)");
    cr_assert_eq(store_list(s, 0, STORE_NSTATUS, 10, &rows, &n, err, sizeof err), -1);
    cr_assert_str_eq(err, "unknown job status 6");
    cr_assert_null(rows);
    cr_assert_eq(n, 0);
    close_intact(s, path);
}

Test(store, delete_removes_only_finished_jobs_with_their_series)
{
    char path[256], err[512] = "";
    store_job j;
    ctc_sim_result *got = NULL;
    store *s = open_new(path, sizeof path);
    ctc_sim_result *r = make_result(6, 3, 3, NULL);
    int64_t queued = insert_job(s, "queued");
    int64_t running = insert_job(s, "running");
    cr_assert_eq(store_start(s, running, err, sizeof err), 0, "%s", err);
    int64_t kept = finished_job(s, "kept", STORE_FAILED, r);
    int64_t done = finished_job(s, "done", STORE_DONE, r);

    cr_assert_eq(store_delete(s, done + 1, err, sizeof err), 1);
    cr_assert_eq(store_delete(s, queued, err, sizeof err), 2);
    cr_assert_eq(store_delete(s, running, err, sizeof err), 2);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM series WHERE job_id = ?1", done), 4);
    cr_assert_eq(store_delete(s, done, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_delete(s, done, err, sizeof err), 1);

    /* gone with its series (ON DELETE CASCADE); the others stay */
    cr_assert_eq(store_get(s, done, &j, err, sizeof err), 1);
    cr_assert_eq(store_get_series(s, done, &got, err, sizeof err), 1);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM series WHERE job_id = ?1", done), 0);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM series WHERE job_id = ?1", kept), 4);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM jobs", 0), 3);

    /* ids are never reused, even the newest one's */
    cr_assert_gt(insert_job(s, "next"), done);
    ctc_sim_result_free(r);
    close_intact(s, path);
}

/* ---- series ---- */

/* runs text as a job, stores the run and reads its series back; compares every printout */
static void round_trip_run(const char *text)
{
    char path[256], err[512] = "";
    job *jb = NULL;
    job_error je;
    ctc_sim_result *r = NULL, *got = NULL;
    store_job row;
    int64_t id;
    path_of(path, sizeof path, "ctcsim.db");
    cr_assert_eq(job_parse(text, strlen(text), &jb, &je), 0, "%s: %s", je.field, je.message);
    cr_assert_eq(ctc_sim_run(&jb->spec, NULL, &r, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_eq(r->status, CTC_RUN_DONE);
    cr_assert_gt(r->nsamples, 10);
    cJSON *m = result_metrics_json(r, jb);
    char *metrics = cJSON_PrintUnformatted(m);
    char *spec = cJSON_PrintUnformatted(jb->normalised);

    store *s = open_ok(path);
    cr_assert_eq(store_insert(s, jb->name, jb->preset, jb->spec.chain.nbodies, jb->nv,
                              ctc_ctrl_type_name(jb->spec.controller), spec, &id, err, sizeof err),
                 0, "%s", err);
    cr_assert_eq(store_start(s, id, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_finish(s, id, STORE_DONE, r->message, metrics, r, err, sizeof err), 0, "%s",
                 err);
    store_close(s);

    /* read back through a new connection */
    s = open_ok(path);
    cr_assert_eq(store_get_series(s, id, &got, err, sizeof err), 0, "%s", err);
    assert_same_series(r, got);

    /* the printouts: everything, and a selection of channels, coordinates and samples */
    char coords[3] = {1, 0, 1};
    result_select sel = {
        .channels = CTC_CH_BIT(CTC_CH_Q) | CTC_CH_BIT(CTC_CH_TAU), .every = 3, .coords = coords};
    for (int json = 0; json < 2; json++) {
        char *want = printed(r, NULL, json), *have = printed(got, NULL, json);
        cr_assert_str_eq(have, want);
        free(want);
        free(have);
        want = printed(r, &sel, json), have = printed(got, &sel, json);
        cr_assert_str_eq(have, want);
        free(want);
        free(have);
    }

    /* the row's figures come from the result itself */
    double e_max = NAN;
    for (int i = 0; r->metrics.e_max && i < r->metrics.nv; i++)
        e_max = isnan(e_max) || r->metrics.e_max[i] > e_max ? r->metrics.e_max[i] : e_max;
    cr_assert_eq(store_get(s, id, &row, err, sizeof err), 0, "%s", err);
    cr_assert_str_eq(row.metrics, metrics);
    cr_assert_str_eq(row.spec, spec);
    cr_assert_eq(row.wall_s, r->metrics.wall_s);
    if (isnan(e_max))
        cr_assert(isnan(row.e_max), "e_max %g for a passive run", row.e_max);
    else
        cr_assert_eq(row.e_max, e_max);
    store_job_clear(&row);
    close_intact(s, path);

    ctc_sim_result_free(got);
    ctc_sim_result_free(r);
    cJSON_Delete(m);
    free(metrics);
    free(spec);
    job_free(jb);
}

Test(store, a_stored_run_prints_byte_identical_csv_and_json)
{
    round_trip_run("{\"preset\": \"triple_pendulum_pid\", \"duration\": 0.2}");
}

Test(store, a_stored_passive_run_keeps_its_energy_channel)
{
    round_trip_run("{\"preset\": \"triple_pendulum_passive\", \"duration\": 0.2}");
}

Test(store, series_keep_every_bit_of_non_finite_and_signed_zero_values)
{
    char path[256], err[512] = "";
    ctc_sim_result *got = NULL;
    store *s = open_new(path, sizeof path);

    /* odd values in every channel, including a NaN with a payload */
    ctc_sim_result *r = make_result(4, 4, 3, NULL);
    uint64_t payload = 0x7ff8dead0000beefULL;
    double odd[6] = {-0.0, INFINITY, -INFINITY, 4.9406564584124654e-324, DBL_MAX, 0};
    memcpy(&odd[5], &payload, sizeof payload);
    for (int c = 0; c < CTC_NCHANNELS; c++)
        for (int k = 0; r->ch[c] && k < 4 * r->width[c]; k++) r->ch[c][k] = odd[(k + c) % 6];
    r->t[3] = nextafter(r->t[3], 1.0);
    int64_t id = finished_job(s, "odd", STORE_DONE, r);
    cr_assert_eq(store_get_series(s, id, &got, err, sizeof err), 0, "%s", err);
    assert_same_series(r, got);
    char *want = printed(r, NULL, 0), *have = printed(got, NULL, 0);
    cr_assert_str_eq(have, want);
    free(want);
    free(have);
    ctc_sim_result_free(got);
    ctc_sim_result_free(r);

    /* a run stopped before its first sample: empty series, still a series */
    r = make_result(0, 3, 3, NULL);
    id = finished_job(s, "empty", STORE_FAILED, r);
    cr_assert_eq(store_get_series(s, id, &got, err, sizeof err), 0, "%s", err);
    cr_assert_eq(got->nsamples, 0);
    cr_assert_eq(got->width[CTC_CH_TAU], 3);
    ctc_sim_result_free(got);
    ctc_sim_result_free(r);
    close_intact(s, path);
}

Test(store, series_are_absent_until_a_run_is_stored)
{
    char path[256], err[512] = "";
    ctc_sim_result *got = NULL;
    store *s = open_new(path, sizeof path);
    int64_t queued = insert_job(s, "queued");
    int64_t running = insert_job(s, "running");
    cr_assert_eq(store_start(s, running, err, sizeof err), 0, "%s", err);
    int64_t cancelled = insert_job(s, "cancelled");
    cr_assert_eq(store_finish(s, cancelled, STORE_CANCELLED, NULL, NULL, NULL, err, sizeof err), 0,
                 "%s", err);
    cr_assert_eq(store_get_series(s, queued, &got, err, sizeof err), 1);
    cr_assert_eq(store_get_series(s, running, &got, err, sizeof err), 1);
    cr_assert_eq(store_get_series(s, cancelled, &got, err, sizeof err), 1);
    cr_assert_eq(store_get_series(s, cancelled + 1, &got, err, sizeof err), 1);
    cr_assert_null(got);
    store_close(s);
}

/* both readers of a series refuse it with the message want */
static void assert_damaged(store *s, int64_t id, const char *want)
{
    char err[512] = "";
    ctc_sim_result *got = NULL;
    store_series_info info;
    cr_assert_eq(store_get_series(s, id, &got, err, sizeof err), -1);
    cr_assert_str_eq(err, want);
    cr_assert_null(got);
    err[0] = 0;
    cr_assert_eq(store_get_series_info(s, id, &info, err, sizeof err), -1);
    cr_assert_str_eq(err, want, "store_get_series_info");
    cr_assert_eq(info.nsamples, 0, "a refused series left its shape behind");
}

Test(store, a_damaged_series_row_is_an_error_not_a_crash)
{
    char path[256], want[256];
    store *s = open_new(path, sizeof path);
    ctc_sim_result *r = make_result(2, 3, 3, NULL);
    int64_t id = finished_job(s, "damaged", STORE_DONE, r);
    ctc_sim_result_free(r);

    raw_exec(path, "UPDATE series SET data = x'00' WHERE channel = 'q'");
    snprintf(want, sizeof want,
             "job %lld: series q holds 1 bytes, expected 48 (2 samples x 3 values x 8)",
             (long long)id);
    assert_damaged(s, id, want);

    raw_exec(path, "UPDATE series SET width = 3, data = zeroblob(48) WHERE channel = 'energy'");
    raw_exec(path, "DELETE FROM series WHERE channel = 'q'");
    snprintf(want, sizeof want, "job %lld: series energy has width 3, expected 2", (long long)id);
    assert_damaged(s, id, want);
    raw_exec(path, "UPDATE series SET width = 2, data = zeroblob(32) WHERE channel = 'energy'");

    raw_exec(path, "UPDATE series SET width = 4, data = zeroblob(64) WHERE channel = 'tau'");
    snprintf(want, sizeof want, "job %lld: series tau has width 4, expected at most 3",
             (long long)id);
    assert_damaged(s, id, want);
    raw_exec(path, "UPDATE series SET width = 3, data = zeroblob(48) WHERE channel = 'tau'");

    raw_exec(path, "UPDATE series SET channel = 'torque' WHERE channel = 'tau'");
    snprintf(want, sizeof want, "job %lld: series has an unknown channel 'torque'", (long long)id);
    assert_damaged(s, id, want);

    raw_exec(path, "UPDATE series SET channel = 'tau' WHERE channel = 'torque'");
    raw_exec(path, "DELETE FROM series WHERE channel = 't'");
    snprintf(want, sizeof want, "job %lld: series has no t", (long long)id);
    assert_damaged(s, id, want);
    store_close(s);
}

/* reads channel c (-1 = t) of job id in pieces of piece bytes, each in a read of its own */
static double *read_in_pieces(store *s, int64_t id, int c, size_t bytes, size_t piece)
{
    char err[512] = "";
    unsigned char *out = malloc(bytes + 1);
    for (size_t off = 0; off < bytes; off += piece) {
        size_t len = bytes - off < piece ? bytes - off : piece;
        cr_assert_eq(store_series_begin(s, err, sizeof err), 0, "%s", err);
        cr_assert_eq(store_series_read(s, id, c, off, out + off, len, err, sizeof err), 0, "%s",
                     err);
        store_series_end(s);
    }
    return (double *)(void *)out;
}

Test(store, a_series_read_in_pieces_has_its_shape_and_every_bit)
{
    char path[256], err[512] = "";
    store *s = open_new(path, sizeof path);
    /* 3001 samples, q 4 wide, tau 3 wide: rows of several SQLite overflow pages */
    ctc_sim_result *r = make_result(3001, 4, 3, NULL);
    r->ch[CTC_CH_Q][5] = NAN, r->ch[CTC_CH_Q][6] = -0.0, r->ch[CTC_CH_TAU][7] = -INFINITY;
    int64_t id = finished_job(s, "pieces", STORE_DONE, r);
    store_series_info info;
    cr_assert_eq(store_get_series_info(s, id, &info, err, sizeof err), 0, "%s", err);
    cr_assert_eq(info.nsamples, 3001);
    cr_assert_eq(info.nq, 4);
    cr_assert_eq(info.nv, 3);
    cr_assert_eq(info.channels, r->channels);
    cr_assert_eq(info.bytes, 3001LL * (1 + 4 + 3 + 2) * 8);
    for (int c = 0; c < CTC_NCHANNELS; c++) cr_assert_eq(info.width[c], r->width[c]);
    cr_assert_eq(store_get_series_info(s, id + 1, &info, err, sizeof err), 1, "no such job");

    static const size_t pieces[] = {8, 1000, 16384, 1 << 20};
    for (size_t p = 0; p < sizeof pieces / sizeof pieces[0]; p++)
        for (int c = -1; c < CTC_NCHANNELS; c++) {
            if (c >= 0 && !r->width[c]) continue;
            const double *want = c < 0 ? r->t : r->ch[c];
            size_t bytes = (size_t)r->nsamples * (size_t)(c < 0 ? 1 : r->width[c]) * 8;
            double *got = read_in_pieces(s, id, c, bytes, pieces[p]);
            cr_assert_eq(memcmp(got, want, bytes), 0, "channel %d in pieces of %zu", c, pieces[p]);
            free(got);
        }

    /* several pieces in one read; a read past the end is refused */
    double x[2];
    cr_assert_eq(store_series_begin(s, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_series_begin(s, err, sizeof err), -1);
    cr_assert_str_eq(err, "reading a series: a read is already under way");
    cr_assert_eq(store_series_read(s, id, CTC_CH_TAU, 8 * 7, x, 8, err, sizeof err), 0, "%s", err);
    cr_assert(isinf(x[0]) && x[0] < 0);
    cr_assert_eq(store_series_read(s, id, -1, 8 * 3000, x, 8, err, sizeof err), 0, "%s", err);
    cr_assert_eq(x[0], r->t[3000]);
    cr_assert_eq(store_series_read(s, id, -1, 8 * 3000, x, 16, err, sizeof err), -1);
    char want[256];
    snprintf(want, sizeof want,
             "job %lld: series t holds 24008 bytes, not the 16 asked for at byte 24000",
             (long long)id);
    cr_assert_str_eq(err, want);
    cr_assert_eq(store_series_read(s, id, CTC_CH_W, 0, x, 8, err, sizeof err), 1);
    snprintf(want, sizeof want, "job %lld: series w is gone", (long long)id);
    cr_assert_str_eq(err, want);
    store_series_end(s);
    store_series_end(s);
    cr_assert_eq(store_series_read(s, id, -1, 0, x, 8, err, sizeof err), -1);
    snprintf(want, sizeof want, "job %lld: reading series t: not inside store_series_begin",
             (long long)id);
    cr_assert_str_eq(err, want);
    ctc_sim_result_free(r);
    store_close(s);
}

Test(store, a_read_keeps_its_snapshot_and_the_next_one_sees_a_deletion)
{
    char path[256], err[512] = "", want[256];
    path_of(path, sizeof path, "ctcsim.db");
    store *s = open_ok(path), *other = open_ok(path);
    ctc_sim_result *r = make_result(2000, 3, 3, NULL);
    int64_t id = finished_job(s, "deleted", STORE_DONE, r);
    double x;

    /* a deletion by another connection does not wait for the read, nor change what it reads */
    cr_assert_eq(store_series_begin(s, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_series_read(s, id, -1, 8 * 1999, &x, 8, err, sizeof err), 0, "%s", err);
    double t0 = wall_now();
    cr_assert_eq(store_delete(other, id, err, sizeof err), 0, "%s", err);
    cr_assert_lt(wall_now() - t0, 1.0, "the deletion waited for the reader");
    cr_assert_eq(store_series_read(s, id, CTC_CH_Q, 8 * 5999, &x, 8, err, sizeof err), 0, "%s",
                 err);
    cr_assert_eq(x, r->ch[CTC_CH_Q][5999]);
    store_series_end(s);

    /* the next read reports it gone, and so does a job whose rowids another job took over */
    cr_assert_eq(store_series_begin(s, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_series_read(s, id, CTC_CH_Q, 0, &x, 8, err, sizeof err), 1);
    snprintf(want, sizeof want, "job %lld: series q is gone", (long long)id);
    cr_assert_str_eq(err, want);
    store_series_end(s);
    int64_t next = finished_job(other, "next", STORE_DONE, r);
    cr_assert_gt(next, id);
    cr_assert_eq(store_series_begin(s, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_series_read(s, id, -1, 0, &x, 8, err, sizeof err), 1);
    cr_assert_eq(store_series_read(s, next, -1, 8, &x, 8, err, sizeof err), 0, "%s", err);
    cr_assert_eq(x, r->t[1]);
    /* closing in the middle of a read ends it */
    store_close(s);
    store_close(other);
    ctc_sim_result_free(r);
    assert_integrity(path);
}

/* ---- faults and the shared health state ---- */

/* a raw connection holding the write lock (BEGIN IMMEDIATE and a write) until raw_release */
static sqlite3 *raw_lock(const char *path)
{
    sqlite3 *db = raw_open(path);
    char *why = NULL;
    cr_assert_eq(sqlite3_exec(db, "BEGIN IMMEDIATE; UPDATE job_counts SET n = n", NULL, NULL, &why),
                 SQLITE_OK, "locking: %s", why ? why : "");
    return db;
}

static void raw_release(sqlite3 *db)
{
    cr_assert_eq(sqlite3_exec(db, "COMMIT", NULL, NULL, NULL), SQLITE_OK);
    sqlite3_close(db);
}

Test(store, a_write_lock_held_elsewhere_is_a_transient_fault_that_health_reports_and_clears)
{
    char path[256], err[512] = "";
    int64_t id = 0;
    long counts[STORE_NSTATUS];
    store *s = open_new(path, sizeof path);
    store_health *h = store_health_new();
    cr_assert_not_null(h);
    store_attach(s, h);
    store_set_busy_timeout(s, 50);
    store_state st;
    store_health_read(h, &st);
    cr_assert_eq(st.fault, STORE_FAULT_NONE);
    cr_assert_eq(st.since, 0);

    /* another connection (as another process would) holds the write lock */
    sqlite3 *lock = raw_lock(path);
    double t0 = wall_now();
    cr_assert_eq(store_insert(s, "blocked", NULL, 3, 3, "pid", "{}", &id, err, sizeof err), -1);
    double t1 = wall_now();
    cr_assert_str_eq(err, "cannot store job 'blocked': database is locked");
    cr_assert_eq(store_last_fault(s), STORE_FAULT_LOCKED);
    cr_assert(store_fault_transient(STORE_FAULT_LOCKED));
    /* the busy timeout (50 ms) bounds the wait */
    cr_assert_lt(t1 - t0, 1.0, "waited %.3f s", t1 - t0);
    store_health_read(h, &st);
    cr_assert_eq(st.fault, STORE_FAULT_LOCKED);
    cr_assert_str_eq(store_fault_name(st.fault), "locked");
    cr_assert_str_eq(st.message, "cannot store job 'blocked': database is locked");
    cr_assert(st.since >= t0 && st.since <= t1, "since %.3f outside [%.3f, %.3f]", st.since, t0,
              t1);
    cr_assert_eq(st.failures, 1);

    /* reads do not wait for the writer (WAL), and a read clears no fault */
    cr_assert_eq(store_count(s, counts, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_last_fault(s), STORE_FAULT_NONE);
    /* a second failure keeps the first one's time and message */
    cr_assert_eq(store_insert(s, "again", NULL, 3, 3, "pid", "{}", &id, err, sizeof err), -1);
    store_health_read(h, &st);
    cr_assert_eq(st.failures, 2);
    cr_assert_str_eq(st.message, "cannot store job 'blocked': database is locked");
    cr_assert(st.since <= t1);

    /* the probe cannot write either; once the lock goes, it can, and the state clears */
    cr_assert(store_health_probe_due(h, 0.0));
    cr_assert_eq(store_probe(s, err, sizeof err), -1);
    cr_assert_str_eq(err, "probing the database: database is locked");
    raw_release(lock);
    cr_assert_eq(store_probe(s, err, sizeof err), 0, "%s", err);
    store_health_read(h, &st);
    cr_assert_eq(st.fault, STORE_FAULT_NONE);
    cr_assert_str_eq(st.message, "");
    cr_assert_eq(st.failures, 0);
    cr_assert_geq(st.last_ok, t1);
    cr_assert_eq(raw_int(path, "SELECT sum(n) FROM job_counts", 0), 0, "the probe changed a count");
    cr_assert_eq(store_insert(s, "free", NULL, 3, 3, "pid", "{}", &id, err, sizeof err), 0, "%s",
                 err);
    store_close(s);
    store_health_free(h);
}

Test(store, a_connection_that_does_not_wait_reports_no_lock_to_health)
{
    char path[256], err[512] = "";
    store *s = open_new(path, sizeof path);
    int64_t id = insert_job(s, "running");
    cr_assert_eq(store_start(s, id, err, sizeof err), 0, "%s", err);
    store_health *h = store_health_new();
    store_attach(s, h);
    store_set_busy_timeout(s, 0);
    sqlite3 *lock = raw_lock(path);
    cr_assert_eq(store_progress(s, id, 0.5, err, sizeof err), -1);
    cr_assert_eq(store_last_fault(s), STORE_FAULT_LOCKED);
    store_state st;
    store_health_read(h, &st);
    cr_assert_eq(st.fault, STORE_FAULT_NONE, "a no-wait write reported %s",
                 store_fault_name(st.fault));
    cr_assert_eq(store_health_probe_due(h, 0.0), 0);
    raw_release(lock);
    store_close(s);
    store_health_free(h);
}

Test(store, a_full_database_fails_the_series_keeps_what_is_stored_and_a_delete_frees_room)
{
    char path[256], err[512] = "";
    store_job j;
    store *s = open_new(path, sizeof path);
    store_health *h = store_health_new();
    store_attach(s, h);
    ctc_sim_result *small = make_result(50, 3, 3, NULL);
    int64_t kept = finished_job(s, "kept", STORE_DONE, small);
    int64_t freed = finished_job(s, "freed", STORE_DONE, small);
    ctc_sim_result *big = make_result(20000, 3, 3, NULL); /* 1.3 MB of series */

    /* the cap: the file as it is and 16 pages more */
    long long size = raw_int(path, "PRAGMA page_count", 0) * raw_int(path, "PRAGMA page_size", 0);
    cr_assert_eq(store_set_max_size(s, size + 16 * 4096, err, sizeof err), 0, "%s", err);
    int64_t id = insert_job(s, "big");
    cr_assert_eq(store_start(s, id, err, sizeof err), 0, "%s", err);
    cr_assert_eq(store_finish(s, id, STORE_DONE, NULL, "{}", big, err, sizeof err), -1);
    cr_assert_eq(store_last_fault(s), STORE_FAULT_FULL, "%s", err);
    char want[128];
    snprintf(want, sizeof want, "job %lld: storing series t: database or disk is full",
             (long long)id);
    cr_assert_str_eq(err, want);
    cr_assert_str_eq(store_fault_text(STORE_FAULT_FULL), "database or disk is full");
    store_state st;
    store_health_read(h, &st);
    cr_assert_eq(st.fault, STORE_FAULT_FULL);
    cr_assert_str_eq(store_fault_name(st.fault), "full");

    /* nothing of the failed finish stayed; an update in place works but does not clear "full" */
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM series WHERE job_id = ?1", id), 0);
    cr_assert_eq(store_progress(s, id, 0.5, err, sizeof err), 0, "%s", err);
    store_health_read(h, &st);
    cr_assert_eq(st.fault, STORE_FAULT_FULL);
    /* the probe measures the room left under the cap: less than 1 MiB */
    cr_assert_eq(store_probe(s, err, sizeof err), -1);
    cr_assert(strstr(err, "bytes free, 1048576 needed"), "%s", err);

    /* recorded failed without its series: a small write that fits */
    cr_assert_eq(store_finish(s, id, STORE_FAILED, "could not store the result", NULL, NULL, err,
                              sizeof err),
                 0, "%s", err);
    /* a delete frees pages, and clears the state */
    cr_assert_eq(store_delete(s, freed, err, sizeof err), 0, "%s", err);
    store_health_read(h, &st);
    cr_assert_eq(st.fault, STORE_FAULT_NONE);
    cr_assert_geq(raw_int(path, "PRAGMA freelist_count", 0), 1);
    insert_job(s, "after");
    cr_assert_eq(store_get(s, kept, &j, err, sizeof err), 0, "%s", err);
    cr_assert_eq(j.status, STORE_DONE);
    store_job_clear(&j);
    ctc_sim_result *got = NULL;
    cr_assert_eq(store_get_series(s, kept, &got, err, sizeof err), 0, "%s", err);
    assert_same_series(small, got);
    assert_integrity(path);

    /* the cap lifted: the big result fits */
    cr_assert_eq(store_set_max_size(s, 0, err, sizeof err), 0, "%s", err);
    finished_job(s, "big again", STORE_DONE, big);
    cr_assert_eq(store_set_max_size(s, -1, err, sizeof err), -1);
    cr_assert_str_eq(err, "the database's size limit must be >= 0 bytes (got -1)");
    ctc_sim_result_free(got);
    ctc_sim_result_free(small);
    ctc_sim_result_free(big);
    store_close(s);
    store_health_free(h);
}

Test(store, reserve_allocates_the_logs_blocks_without_changing_its_size)
{
    char path[256], wal[300], err[512] = "";
    path_of(path, sizeof path, "ctcsim.db");
    snprintf(wal, sizeof wal, "%s-wal", path);
    store *s = open_ok(path);
    insert_job(s, "one");
    struct stat before, after;
    cr_assert_eq(stat(wal, &before), 0);
    cr_assert_eq(store_reserve(s, 1 << 20, err, sizeof err), 0, "%s", err);
    cr_assert_eq(stat(wal, &after), 0);
    cr_assert_eq(after.st_size, before.st_size);
    cr_assert_geq((long long)after.st_blocks * 512, 1 << 20, "%lld blocks",
                  (long long)after.st_blocks);
    /* the log still reads: the reserved blocks lie past its end */
    insert_job(s, "two");
    close_intact(s, path);
    cr_assert_eq(raw_int(path, "SELECT count(*) FROM jobs", 0), 2);
}

Test(store, fault_names_and_texts)
{
    const char *names[STORE_NFAULT] = {"ok", "locked", "full", "readonly", "io_error", "error"};
    for (int f = 0; f < STORE_NFAULT; f++)
        cr_assert_str_eq(store_fault_name((store_fault)f), names[f]);
    cr_assert_str_eq(store_fault_text(STORE_FAULT_LOCKED), "database is locked");
    cr_assert_str_eq(store_fault_text(STORE_FAULT_READONLY),
                     "attempt to write a readonly database");
    cr_assert_str_eq(store_fault_text(STORE_FAULT_IO), "disk I/O error");
    cr_assert_eq(store_fault_transient(STORE_FAULT_NONE), 0);
    cr_assert_eq(store_fault_transient(STORE_FAULT_OTHER), 0);
    cr_assert(store_fault_transient(STORE_FAULT_FULL) && store_fault_transient(STORE_FAULT_IO) &&
              store_fault_transient(STORE_FAULT_READONLY));
}

Test(store, status_names_round_trip)
{
    const char *names[STORE_NSTATUS] = {"queued", "running",  "done",
                                        "failed", "diverged", "cancelled"};
    for (int i = 0; i < STORE_NSTATUS; i++) {
        cr_assert_str_eq(store_status_name((store_status)i), names[i]);
        cr_assert_eq(store_status_parse(names[i]), i);
    }
    cr_assert_str_eq(store_status_name(STORE_NSTATUS), "unknown");
    cr_assert_eq(store_status_parse("Done"), -1);
    cr_assert_eq(store_status_parse(""), -1);
    cr_assert_eq(store_status_parse(NULL), -1);
}
