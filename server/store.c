/*
 * store.c - the service's SQLite storage (store.h): one connection per store, its statements
 * prepared once, the schema created or checked at open.
 *
 * Connections. Each store owns one sqlite3 connection in WAL mode (readers never block the
 * writer and the writer never blocks readers), synchronous=NORMAL (a commit survives a crash of
 * the process; a power cut may lose the last commits but never corrupts the file), foreign keys
 * on (a job's series go with it, ON DELETE CASCADE) and a busy timeout of STORE_BUSY_MS, which
 * callers shorten with store_set_busy_timeout (the service: 0.3 s on HTTP threads, 1 s per try
 * in the workers, which retry; none for progress). Every statement is prepared once at open
 * (SQLITE_PREPARE_PERSISTENT), bound with sqlite3_bind_* (no value is ever written into SQL
 * text) and reset and unbound after each use, so no statement holds a read snapshot between
 * calls. Writes of more than one statement run in BEGIN IMMEDIATE transactions: the write lock
 * is taken first, so a transaction never has to upgrade a stale read snapshot (which SQLite
 * would answer with SQLITE_BUSY at once).
 *
 * Schema. PRAGMA user_version holds the schema's version. store_open reads it: the current
 * version needs nothing; a newer one, or version 0 with tables of someone else, is refused and
 * the file left untouched; version 0 on an empty database runs the migrations in one BEGIN
 * IMMEDIATE transaction, reading the version again once it holds the write lock, so two
 * connections that open a new database at once migrate it once. migrations[v] takes version v
 * to v + 1. Statuses are stored by name ("queued", ...) so that the file reads in the sqlite3
 * shell and does not depend on the order of store_status. Job ids come from AUTOINCREMENT: they
 * increase and are never reused, even after the newest job is deleted (a client's old URL never
 * names a new job).
 *
 * Counts. Version 2 adds job_counts, one row per status kept exact by triggers on jobs in the
 * transaction of each insert, delete and status change, whoever writes (the workers, the HTTP
 * threads, another process): store_count reads its six rows, in time independent of the number
 * of jobs (GET /api/health runs it on every call). A family's counts are a GROUP BY over its
 * members that version 4's index jobs_by_family_status (family_id, status) answers alone.
 *
 * Series. store_finish writes one series row per recorded channel, "t" (width 1) first, with the
 * samples as nsamples x width float64, row-major, little-endian: the result's own arrays are
 * bound as blobs with no copy, which needs a little-endian host with IEEE 754 doubles (checked
 * at compile time below). The rows and the job's final status, message, metrics, e_max and
 * wall_s go in one transaction, so a job is either finished with all its series or unfinished
 * with none. store_get_series copies the blobs back (memcpy: a blob need not be aligned) into a
 * new ctc_sim_result and checks every row's size against its width and sample count, so a
 * damaged row is an error, never an out-of-bounds read. A reader that must not hold a whole
 * series (the service's GET of one) reads its shape with store_get_series_info (the same checks,
 * the sizes from length(data), which SQLite answers from the record header without reading the
 * blob) and then its samples in ranges through sqlite3_blob handles, inside a deferred read
 * transaction (store_series_begin .. store_series_end): one snapshot, which writers never wait
 * for. Each row is found by its key (job_id, channel), never by a rowid remembered from an
 * earlier read, since a deleted job's rowids may be taken by the next one.
 *
 * Faults and health. Every public call starts with call_begin, which clears the call's fault
 * and notes sqlite3_total_changes64; db_err, the one place a database failure becomes a message,
 * records the fault from sqlite3_extended_errcode (the first one of the call, with its message).
 * Public writes are thin wrappers that end in write_end, which tells an attached store_health
 * (store.h) what happened: a transient fault, or a success that changed rows. The state is one
 * struct behind a mutex, so every thread reads the same answer in O(1). A full database is
 * cleared only by a write that adds rows or frees room, or by store_probe measuring at least
 * STORE_ROOM_BYTES free on the disk and under the size cap (PRAGMA max_page_count); other faults
 * by any write that changed rows, the probe's included (it rewrites one count with its value).
 * store_reserve allocates the -wal file's blocks past its end (fallocate FALLOC_FL_KEEP_SIZE):
 * SQLite never sees them, but its appends use them, so on a full disk a delete still commits.
 *
 * Errors are the message of the failing step prefixed with what was being done and the job's
 * id ("cannot finish job 3: no such job", "job 3: storing series tau: disk I/O error").
 */
#define _GNU_SOURCE /* fallocate and FALLOC_FL_KEEP_SIZE (store_reserve) */

#include "store.h"

#include <errno.h>
#include <fcntl.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>
#include <sqlite3.h>

#include "store_common.h"
#include "store_pg.h"

/* series blobs are the host's doubles byte for byte: they must be IEEE 754 binary64 and
 * little-endian, as on x86_64 and little-endian ARM */
#if !defined(__BYTE_ORDER__) || __BYTE_ORDER__ != __ORDER_LITTLE_ENDIAN__ ||                       \
    (defined(__FLOAT_WORD_ORDER__) && __FLOAT_WORD_ORDER__ != __ORDER_LITTLE_ENDIAN__)
#error "store.c writes series as the host's doubles and needs a little-endian machine"
#endif
_Static_assert(sizeof(double) == 8 && DBL_MANT_DIG == 53 && FLT_RADIX == 2,
               "store.c writes series as IEEE 754 binary64 doubles");

#define STORE_BUSY_MS 5000         /* how long a connection waits for another's lock */
#define STORE_ROOM_BYTES (1 << 20) /* free bytes that make a full database writable again */
#define STORE_WAL_RETRY_MS 10      /* the pause between tries to switch a new file to WAL */

/* migrations[v] takes the schema from version v to v + 1 (run in one transaction) */
static const char *const migrations[STORE_SCHEMA_VERSION] = {
    /* 0 -> 1: jobs and their series */
    "CREATE TABLE jobs ("
    "  id INTEGER PRIMARY KEY AUTOINCREMENT,"
    "  name TEXT NOT NULL,"
    "  preset TEXT,"
    "  status TEXT NOT NULL DEFAULT 'queued' CHECK (status IN ('queued', 'running', 'done',"
    "    'failed', 'diverged', 'cancelled')),"
    "  progress REAL NOT NULL DEFAULT 0,"
    "  created REAL NOT NULL,"
    "  started REAL NOT NULL DEFAULT 0,"
    "  finished REAL NOT NULL DEFAULT 0,"
    "  nbodies INTEGER NOT NULL,"
    "  nv INTEGER NOT NULL,"
    "  controller TEXT NOT NULL,"
    "  spec TEXT NOT NULL,"
    "  metrics TEXT,"
    "  message TEXT,"
    "  e_max REAL,"
    "  wall_s REAL);"
    "CREATE INDEX jobs_by_status ON jobs (status);"
    "CREATE TABLE series ("
    "  job_id INTEGER NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,"
    "  channel TEXT NOT NULL,"
    "  width INTEGER NOT NULL CHECK (width > 0),"
    "  nsamples INTEGER NOT NULL CHECK (nsamples >= 0),"
    "  data BLOB NOT NULL,"
    "  PRIMARY KEY (job_id, channel));"
    "PRAGMA user_version = 1;",
    /* 1 -> 2: the number of jobs in each status, kept by triggers in the transaction of every
     * insert, delete and status change, so that counting (health) reads six rows, not the table */
    "CREATE TABLE job_counts ("
    "  status TEXT PRIMARY KEY,"
    "  n INTEGER NOT NULL CHECK (n >= 0)) WITHOUT ROWID;"
    "INSERT INTO job_counts (status, n) VALUES ('queued', 0), ('running', 0), ('done', 0),"
    "  ('failed', 0), ('diverged', 0), ('cancelled', 0);"
    "UPDATE job_counts SET n = (SELECT count(*) FROM jobs WHERE jobs.status = job_counts.status);"
    "CREATE TRIGGER job_counts_insert AFTER INSERT ON jobs BEGIN"
    "  UPDATE job_counts SET n = n + 1 WHERE status = NEW.status; END;"
    "CREATE TRIGGER job_counts_delete AFTER DELETE ON jobs BEGIN"
    "  UPDATE job_counts SET n = n - 1 WHERE status = OLD.status; END;"
    "CREATE TRIGGER job_counts_update AFTER UPDATE OF status ON jobs"
    "  WHEN OLD.status <> NEW.status BEGIN"
    "  UPDATE job_counts SET n = n - 1 WHERE status = OLD.status;"
    "  UPDATE job_counts SET n = n + 1 WHERE status = NEW.status; END;"
    "PRAGMA user_version = 2;",
    /* 2 -> 3: families of jobs (family.h); a member is an ordinary job that names its family,
     * its number in it, its replica and its axis values. Jobs stored before have none */
    "CREATE TABLE families ("
    "  id INTEGER PRIMARY KEY AUTOINCREMENT,"
    "  name TEXT NOT NULL,"
    "  spec TEXT NOT NULL,"
    "  axes TEXT NOT NULL,"
    "  members INTEGER NOT NULL CHECK (members >= 0),"
    "  created REAL NOT NULL);"
    "ALTER TABLE jobs ADD COLUMN family_id INTEGER REFERENCES families (id);"
    "ALTER TABLE jobs ADD COLUMN family_member INTEGER;"
    "ALTER TABLE jobs ADD COLUMN family_replica INTEGER;"
    "ALTER TABLE jobs ADD COLUMN family_values TEXT;"
    "CREATE INDEX jobs_by_family ON jobs (family_id, family_member) WHERE family_id IS NOT NULL;"
    "PRAGMA user_version = 3;",
    /* 3 -> 4: a family's status counts (store_family_get, every GET of a family) read this
     * covering index, its rows already grouped, instead of each member's row: 0.4 ms instead of
     * 14-22 ms for 10,000 members (bench figures in the commit) */
    ("CREATE INDEX jobs_by_family_status ON jobs (family_id, status) WHERE family_id IS NOT NULL;"
     "PRAGMA user_version = 4;"),
};

/* the statements of a connection, prepared once at open */
typedef enum stmt_id {
    ST_BEGIN,
    ST_COMMIT,
    ST_ROLLBACK,
    ST_INSERT,
    ST_STATUS_OF,
    ST_START,
    ST_PROGRESS,
    ST_REQUEUE,
    ST_RECOVER_IDS,
    ST_RECOVER_SERIES,
    ST_RECOVER_JOBS,
    ST_FINISH,
    ST_SERIES_DELETE,
    ST_SERIES_INSERT,
    ST_GET,
    ST_LIST_ANY,
    ST_LIST_STATUS,
    ST_SEARCH,
    ST_SERIES_GET,
    ST_SERIES_INFO,
    ST_SERIES_ROW,
    ST_BEGIN_READ,
    ST_DELETE,
    ST_COUNT,
    ST_PROBE,
    ST_FAMILY_INSERT,
    ST_MEMBER_INSERT,
    ST_FAMILY_GET,
    ST_FAMILY_LIST,
    ST_FAMILY_COUNTS,
    ST_FAMILY_MEMBERS,
    ST_FAMILY_ACTIVE,
    ST_FAMILY_DELETE_JOBS,
    ST_FAMILY_DELETE,
    ST_FAMILY_OF,
    ST_FAMILY_CANCEL,
    ST_NSTMT
} stmt_id;

/* the columns of a row as store_job holds them; store_get adds spec and metrics */
#define JOB_COLUMNS                                                                                \
    "id, name, preset, status, progress, created, started, finished, nbodies, nv, controller, "    \
    "message, e_max, wall_s, family_id, " SUMMARY_COLUMNS
/* the summaries a list shows, read from the stored JSON (no column of their own, so the schema
   stays as it is): metrics.e_final and metrics.e_rms as JSON text, reduced in C (read_job; for
   4096 coordinates SQLite's json_each took 4 ms a row, json_extract 0.7 ms), and the tags of
   the normalised job, as JSON text */
#define SUMMARY_COLUMNS                                                                            \
    "json_extract(jobs.metrics, '$.e_final'), json_extract(jobs.metrics, '$.e_rms'), "             \
    "json_extract(jobs.spec, '$.tags')"
/* a search: ?4 a lowercase text in the name, preset, controller or a tag; ?5 a tag */
#define SEARCH_WHERE                                                                               \
    "(?4 IS NULL OR instr(lower(name), ?4) OR instr(lower(ifnull(preset, '')), ?4) OR "            \
    "instr(lower(controller), ?4) OR EXISTS (SELECT 1 FROM json_each(jobs.spec, '$.tags') "        \
    "WHERE instr(lower(value), ?4))) AND (?5 IS NULL OR EXISTS (SELECT 1 FROM "                    \
    "json_each(jobs.spec, '$.tags') WHERE value = ?5))"
#define ACTIVE "status IN ('queued', 'running')"

static const char *const stmt_sql[ST_NSTMT] = {
    [ST_BEGIN] = "BEGIN IMMEDIATE",
    [ST_COMMIT] = "COMMIT",
    [ST_ROLLBACK] = "ROLLBACK",
    [ST_INSERT] = "INSERT INTO jobs (name, preset, status, progress, created, nbodies, nv, "
                  "controller, spec) VALUES (?1, ?2, 'queued', 0, ?3, ?4, ?5, ?6, ?7)",
    [ST_STATUS_OF] = "SELECT status FROM jobs WHERE id = ?1",
    [ST_START] = "UPDATE jobs SET status = 'running', started = ?2, progress = 0 "
                 "WHERE id = ?1 AND status = 'queued'",
    [ST_PROGRESS] = "UPDATE jobs SET progress = ?2 WHERE id = ?1 AND status = 'running'",
    [ST_REQUEUE] = "UPDATE jobs SET status = 'queued', progress = 0, started = 0 "
                   "WHERE id = ?1 AND status = 'running'",
    [ST_RECOVER_IDS] = "SELECT id FROM jobs WHERE " ACTIVE " ORDER BY id",
    [ST_RECOVER_SERIES] =
        "DELETE FROM series WHERE job_id IN (SELECT id FROM jobs WHERE " ACTIVE ")",
    [ST_RECOVER_JOBS] = "UPDATE jobs SET status = 'queued', progress = 0, started = 0 "
                        "WHERE " ACTIVE,
    [ST_FINISH] = "UPDATE jobs SET status = ?2, message = ?3, metrics = ?4, e_max = ?5, "
                  "wall_s = ?6, finished = ?7, "
                  "progress = CASE WHEN ?2 = 'done' THEN 1 ELSE progress END "
                  "WHERE id = ?1 AND " ACTIVE,
    [ST_SERIES_DELETE] = "DELETE FROM series WHERE job_id = ?1",
    [ST_SERIES_INSERT] = "INSERT INTO series (job_id, channel, width, nsamples, data) "
                         "VALUES (?1, ?2, ?3, ?4, ?5)",
    [ST_GET] = "SELECT " JOB_COLUMNS ", spec, metrics FROM jobs WHERE id = ?1",
    [ST_LIST_ANY] = "SELECT " JOB_COLUMNS " FROM jobs WHERE id < ?1 ORDER BY id DESC LIMIT ?2",
    [ST_LIST_STATUS] = "SELECT " JOB_COLUMNS " FROM jobs WHERE status = ?3 AND id < ?1 "
                       "ORDER BY id DESC LIMIT ?2",
    [ST_SEARCH] = "SELECT " JOB_COLUMNS " FROM jobs WHERE id < ?1 AND (?3 IS NULL OR status = ?3) "
                  "AND " SEARCH_WHERE " ORDER BY id DESC LIMIT ?2",
    [ST_SERIES_GET] = "SELECT s.channel, s.width, s.nsamples, s.data, j.nv "
                      "FROM series AS s JOIN jobs AS j ON j.id = s.job_id WHERE s.job_id = ?1",
    /* length() of a blob reads its size from the record header, not its pages */
    [ST_SERIES_INFO] = "SELECT s.channel, s.width, s.nsamples, length(s.data), j.nv "
                       "FROM series AS s JOIN jobs AS j ON j.id = s.job_id WHERE s.job_id = ?1",
    [ST_SERIES_ROW] = "SELECT rowid FROM series WHERE job_id = ?1 AND channel = ?2",
    [ST_BEGIN_READ] = "BEGIN",
    [ST_DELETE] = "DELETE FROM jobs WHERE id = ?1",
    [ST_COUNT] = "SELECT status, n FROM job_counts",
    [ST_PROBE] = "UPDATE job_counts SET n = n WHERE status = 'queued'",
    [ST_FAMILY_INSERT] = "INSERT INTO families (name, spec, axes, members, created) "
                         "VALUES (?1, ?2, ?3, ?4, ?5)",
    [ST_MEMBER_INSERT] =
        "INSERT INTO jobs (name, preset, status, progress, created, nbodies, nv, controller, "
        "spec, family_id, family_member, family_replica, family_values) "
        "VALUES (?1, ?2, 'queued', 0, ?3, ?4, ?5, ?6, ?7, ?8, ?9, ?10, ?11)",
#define FAMILY_COLUMNS "id, name, spec, axes, members, created"
    [ST_FAMILY_GET] = "SELECT " FAMILY_COLUMNS " FROM families WHERE id = ?1",
    [ST_FAMILY_LIST] = "SELECT " FAMILY_COLUMNS " FROM families WHERE id < ?1 "
                       "ORDER BY id DESC LIMIT ?2",
    [ST_FAMILY_COUNTS] = "SELECT status, count(*) FROM jobs WHERE family_id = ?1 GROUP BY status",
    [ST_FAMILY_MEMBERS] = "SELECT id, family_member, family_replica, status, family_values, "
                          "metrics, message FROM jobs WHERE family_id = ?1 ORDER BY family_member",
    [ST_FAMILY_ACTIVE] = "SELECT id FROM jobs WHERE family_id = ?1 AND " ACTIVE " ORDER BY id",
    [ST_FAMILY_DELETE_JOBS] = "DELETE FROM jobs WHERE family_id = ?1",
    [ST_FAMILY_DELETE] = "DELETE FROM families WHERE id = ?1",
    [ST_FAMILY_OF] = "SELECT family_id FROM jobs WHERE id = ?1",
    [ST_FAMILY_CANCEL] = "UPDATE jobs SET status = 'cancelled', message = ?2, finished = ?3 "
                         "WHERE family_id = ?1 AND status = 'queued'",
};

struct store {
    store_pg *pg; /* non-NULL: a PostgreSQL store, every call forwards to it (store_pg.h) */
    sqlite3 *db;
    sqlite3_stmt *stmt[ST_NSTMT];
    long count_vm_steps;          /* SQLite VM steps of the last store_count */
    int busy_ms;                  /* the busy timeout set on db */
    store_fault fault;            /* of the current (or last) call */
    char fault_msg[256];          /* its message, when fault is not NONE */
    sqlite3_int64 changes_before; /* sqlite3_total_changes64 when the current call began */
    store_health *health;         /* NULL = not attached */
    /* between store_series_begin and store_series_end: the read transaction, and the blob
       handles opened on the series rows of job blob_job (t, then the channels) */
    int reading;
    int64_t blob_job;
    sqlite3_blob *blob[CTC_NCHANNELS + 1];
};

struct store_health {
    pthread_mutex_t lock;
    store_state state;
    double last_probe; /* monotonic s of the last store_health_probe_due that said 1 */
};

static const char *const status_names[STORE_NSTATUS] = {
    "queued", "running", "done", "failed", "diverged", "cancelled",
};

const char *store_status_name(store_status st)
{
    return (unsigned)st < STORE_NSTATUS ? status_names[st] : "unknown";
}

int store_status_parse(const char *name)
{
    for (int i = 0; name && i < STORE_NSTATUS; i++)
        if (strcmp(name, status_names[i]) == 0) return i;
    return -1;
}

/* ---- helpers ---- */

#define set_err store_set_err /* store_common.h */

/* the fault of an SQLite result code (primary or extended) */
static store_fault fault_of(int code)
{
    switch (code & 0xff) {
    case SQLITE_OK:
    case SQLITE_ROW:
    case SQLITE_DONE:
        return STORE_FAULT_NONE;
    case SQLITE_BUSY:
    case SQLITE_LOCKED:
        return STORE_FAULT_LOCKED;
    case SQLITE_FULL:
        return STORE_FAULT_FULL;
    case SQLITE_READONLY:
        return STORE_FAULT_READONLY;
    case SQLITE_IOERR:
        return STORE_FAULT_IO;
    default:
        return STORE_FAULT_OTHER;
    }
}

/* "WHAT: sqlite's message", with WHAT formatted; call before resetting the failed statement.
 * Records the call's fault from SQLite's last error code. */
static void db_err(store *s, char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static void db_err(store *s, char *err, size_t errlen, const char *fmt, ...)
{
    char what[256];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    if (s->fault == STORE_FAULT_NONE) {
        s->fault = fault_of(sqlite3_extended_errcode(s->db));
        /* an error code that says nothing (a misuse) is still the database's failure */
        if (s->fault == STORE_FAULT_NONE) s->fault = STORE_FAULT_OTHER;
        set_err(s->fault_msg, sizeof s->fault_msg, "%s: %s", what, sqlite3_errmsg(s->db));
    }
    set_err(err, errlen, "%s: %s", what, sqlite3_errmsg(s->db));
}

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double monotonic_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* ---- faults and health ---- */

store_fault store_last_fault(const store *s)
{
    if (s->pg) return store_pg_last_fault(s->pg);
    return s->fault;
}

int store_fault_transient(store_fault f)
{
    return f == STORE_FAULT_LOCKED || f == STORE_FAULT_FULL || f == STORE_FAULT_READONLY ||
           f == STORE_FAULT_IO;
}

const char *store_fault_name(store_fault f)
{
    static const char *const names[STORE_NFAULT] = {"ok",       "locked",   "full",
                                                    "readonly", "io_error", "error"};
    return (unsigned)f < STORE_NFAULT ? names[f] : "error";
}

const char *store_fault_text(store_fault f)
{
    static const int codes[STORE_NFAULT] = {SQLITE_OK,       SQLITE_BUSY,  SQLITE_FULL,
                                            SQLITE_READONLY, SQLITE_IOERR, SQLITE_ERROR};
    return sqlite3_errstr((unsigned)f < STORE_NFAULT ? codes[f] : SQLITE_ERROR);
}

store_health *store_health_new(void)
{
    store_health *h = calloc(1, sizeof *h);
    if (!h) return NULL;
    if (pthread_mutex_init(&h->lock, NULL) != 0) {
        free(h);
        return NULL;
    }
    h->last_probe = -INFINITY;
    return h;
}

void store_health_free(store_health *h)
{
    if (!h) return;
    pthread_mutex_destroy(&h->lock);
    free(h);
}

void store_attach(store *s, store_health *h)
{
    if (s->pg) store_pg_attach(s->pg, h);
    s->health = h;
}

void store_health_read(store_health *h, store_state *out)
{
    pthread_mutex_lock(&h->lock);
    *out = h->state;
    pthread_mutex_unlock(&h->lock);
}

int store_health_probe_due(store_health *h, double interval_s)
{
    int due = 0;
    double t = monotonic_s();
    pthread_mutex_lock(&h->lock);
    if (h->state.fault != STORE_FAULT_NONE && t - h->last_probe >= interval_s) {
        h->last_probe = t;
        due = 1;
    }
    pthread_mutex_unlock(&h->lock);
    return due;
}

/* the start of a public call: no fault yet, and the changes so far (to see whether it wrote) */
static void call_begin(store *s)
{
    s->fault = STORE_FAULT_NONE;
    s->fault_msg[0] = '\0';
    s->changes_before = sqlite3_total_changes64(s->db);
}

/* a transient fault seen by a write: the state takes it (its time and message kept while the
 * same fault lasts) */
static void health_fault(store_health *h, store_fault f, const char *message)
{
    double t = now_s();
    pthread_mutex_lock(&h->lock);
    if (h->state.fault != f) {
        h->state.fault = f;
        h->state.since = t;
        snprintf(h->state.message, sizeof h->state.message, "%s", message);
    }
    h->state.failures++;
    pthread_mutex_unlock(&h->lock);
}

/* a write that worked: the state clears, except a full database when the write proved no room
 * (room 0) */
static void health_ok(store_health *h, int room)
{
    double t = now_s();
    pthread_mutex_lock(&h->lock);
    if (room || h->state.fault != STORE_FAULT_FULL) {
        h->state.fault = STORE_FAULT_NONE;
        h->state.since = 0;
        h->state.failures = 0;
        h->state.message[0] = '\0';
    }
    h->state.last_ok = t;
    pthread_mutex_unlock(&h->lock);
}

void store_health_report_fault(store_health *h, store_fault f, const char *message)
{
    health_fault(h, f, message);
}

void store_health_report_ok(store_health *h, int room)
{
    health_ok(h, room);
}

store_pg *store_pg_of(store *s)
{
    return s->pg;
}

/* the end of a public write call: its outcome told to the health state (a transient fault sets
 * it; a call that changed rows without a fault clears it, except a full database, which only a
 * call that could have met it clears: one that adds rows or frees room, said by room); rc */
static int write_end(store *s, int rc, int room)
{
    if (!s->health) return rc;
    if (store_fault_transient(s->fault) && !(s->fault == STORE_FAULT_LOCKED && s->busy_ms == 0))
        health_fault(s->health, s->fault, s->fault_msg);
    else if (s->fault == STORE_FAULT_NONE && sqlite3_total_changes64(s->db) != s->changes_before)
        health_ok(s->health, room);
    return rc;
}

/* makes a statement ready for its next use: no snapshot held, no pointer into the caller kept */
static void release(sqlite3_stmt *st)
{
    sqlite3_reset(st);
    sqlite3_clear_bindings(st);
}

/* runs a statement without parameters or rows (BEGIN IMMEDIATE, COMMIT, ROLLBACK, the
 * recovery updates) and resets it; SQLITE_OK or the failing result code (the message stays in
 * sqlite3_errmsg) */
static int tx_step(store *s, stmt_id which)
{
    int rc = sqlite3_step(s->stmt[which]);
    sqlite3_reset(s->stmt[which]);
    return rc == SQLITE_DONE ? SQLITE_OK : rc;
}

/* undoes an open transaction, if SQLite has not already rolled it back itself */
static void tx_rollback(store *s)
{
    if (!sqlite3_get_autocommit(s->db)) tx_step(s, ST_ROLLBACK);
}

/* a job's status by id: 1 when there is no such job, 0 with *st, -1 on error */
static int status_of(store *s, int64_t id, store_status *st, char *err, size_t errlen)
{
    sqlite3_stmt *q = s->stmt[ST_STATUS_OF];
    int rc = -1;
    sqlite3_bind_int64(q, 1, id);
    int step = sqlite3_step(q);
    if (step == SQLITE_DONE) {
        rc = 1;
        goto done;
    }
    if (step != SQLITE_ROW) {
        db_err(s, err, errlen, "job %lld: reading its status", (long long)id);
        goto done;
    }
    int parsed = store_status_parse((const char *)sqlite3_column_text(q, 0));
    if (parsed < 0) {
        set_err(err, errlen, "job %lld has an unknown status '%s'", (long long)id,
                (const char *)sqlite3_column_text(q, 0));
        goto done;
    }
    *st = (store_status)parsed;
    rc = 0;
done:
    release(q);
    return rc;
}

/* the reason an update that needs a running job changed nothing (store_not_running_err) */
static void not_running_err(store *s, int64_t id, const char *what, char *err, size_t errlen)
{
    store_status st = STORE_QUEUED;
    int found = status_of(s, id, &st, err, errlen);
    store_not_running_err(id, what, found, st, err, errlen);
}

/* column i as a new string, or NULL for SQL NULL; -1 when out of memory */
static int dup_column(sqlite3_stmt *q, int i, char **out)
{
    *out = NULL;
    if (sqlite3_column_type(q, i) == SQLITE_NULL) return 0;
    const char *text = (const char *)sqlite3_column_text(q, i);
    if (!text) return -1;
    *out = strdup(text);
    return *out ? 0 : -1;
}

/* a REAL column that may be NULL (NaN then) */
static double real_or_nan(sqlite3_stmt *q, int i)
{
    return sqlite3_column_type(q, i) == SQLITE_NULL ? NAN : sqlite3_column_double(q, i);
}

/* j->e_final = max |e_final| and j->e_rms = sqrt(mean e_rms^2) over the coordinates, from the
 * JSON arrays in columns 15 and 16 (NaN when absent, unreadable or without a finite entry;
 * non-finite entries, written as null, are left out) */
static void summarise_errors(sqlite3_stmt *q, store_job *j)
{
    store_summarise_errors((const char *)sqlite3_column_text(q, 15),
                           (const char *)sqlite3_column_text(q, 16), &j->e_final, &j->e_rms);
}

void store_summarise_errors(const char *e_final, const char *e_rms, double *final_out,
                            double *rms_out)
{
    *final_out = *rms_out = NAN;
    for (int c = 15; c <= 16; c++) {
        const char *text = c == 15 ? e_final : e_rms;
        cJSON *a = text ? cJSON_Parse(text) : NULL;
        double acc = 0;
        int n = 0;
        for (const cJSON *v = cJSON_IsArray(a) ? a->child : NULL; v; v = v->next) {
            if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) continue;
            double x = fabs(v->valuedouble);
            acc = c == 15 ? (n == 0 || x > acc ? x : acc) : acc + x * x;
            n++;
        }
        cJSON_Delete(a);
        if (n > 0 && c == 15) *final_out = acc;
        if (n > 0 && c == 16) *rms_out = sqrt(acc / n);
    }
}

/* fills j from the current row of a JOB_COLUMNS query (spec and metrics follow when
 * with_spec); 0, or -1 with a message (j is then cleared) */
static int read_job(sqlite3_stmt *q, int with_spec, store_job *j, char *err, size_t errlen)
{
    int rc = -1;
    memset(j, 0, sizeof *j);
    j->id = sqlite3_column_int64(q, 0);
    int status = store_status_parse((const char *)sqlite3_column_text(q, 3));
    if (status < 0) {
        set_err(err, errlen, "job %lld has an unknown status '%s'", (long long)j->id,
                (const char *)sqlite3_column_text(q, 3));
        goto done;
    }
    j->status = (store_status)status;
    j->progress = sqlite3_column_double(q, 4);
    j->created = sqlite3_column_double(q, 5);
    j->started = sqlite3_column_double(q, 6);
    j->finished = sqlite3_column_double(q, 7);
    j->nbodies = sqlite3_column_int(q, 8);
    j->nv = sqlite3_column_int(q, 9);
    j->e_max = real_or_nan(q, 12);
    j->wall_s = real_or_nan(q, 13);
    j->family = sqlite3_column_type(q, 14) == SQLITE_NULL ? 0 : sqlite3_column_int64(q, 14);
    summarise_errors(q, j);
    if (dup_column(q, 1, &j->name) || dup_column(q, 2, &j->preset) ||
        dup_column(q, 10, &j->controller) || dup_column(q, 11, &j->message) ||
        dup_column(q, 17, &j->tags) ||
        (with_spec && (dup_column(q, 18, &j->spec) || dup_column(q, 19, &j->metrics)))) {
        set_err(err, errlen, "job %lld: out of memory", (long long)j->id);
        goto done;
    }
    rc = 0;
done:
    if (rc) store_job_clear(j);
    return rc;
}

/* ---- opening ---- */

/* the message for a failed sqlite3_open_v2 (db may be NULL: out of memory) */
static void open_err(sqlite3 *db, const char *path, char *err, size_t errlen)
{
    if (!db) {
        set_err(err, errlen, "cannot open database %s: out of memory", path);
        return;
    }
    int sys = sqlite3_system_errno(db);
    /* the usual cause: the directory named in the path is missing (looked at, since some file
     * systems answer ENOENT for a file they will not create in a directory that exists) */
    const char *slash = strrchr(path, '/');
    char dir[4096];
    struct stat st;
    if (sys == ENOENT && slash && (size_t)(slash - path) < sizeof dir) {
        size_t dirlen = slash == path ? 1 : (size_t)(slash - path);
        memcpy(dir, path, dirlen);
        dir[dirlen] = '\0';
        if (stat(dir, &st) != 0 && errno == ENOENT) {
            set_err(err, errlen, "cannot open database %s: directory %s does not exist", path, dir);
            return;
        }
        /* SQLite retries read-only after EACCES and reports that attempt's ENOENT */
        if (access(dir, W_OK | X_OK) != 0) {
            set_err(err, errlen, "cannot open database %s: cannot create it in directory %s (%s)",
                    path, dir, strerror(errno));
            return;
        }
    }
    if (sys)
        set_err(err, errlen, "cannot open database %s: %s (%s)", path, sqlite3_errmsg(db),
                strerror(sys));
    else
        set_err(err, errlen, "cannot open database %s: %s", path, sqlite3_errmsg(db));
}

/* runs a single-row pragma or query and reads its first column as an integer or as text
 * (text: NULL when not wanted); SQLite's result code */
static int query_one(sqlite3 *db, const char *sql, int *value, char *text, size_t textlen)
{
    sqlite3_stmt *q = NULL;
    int rc = sqlite3_prepare_v2(db, sql, -1, &q, NULL);
    if (rc != SQLITE_OK) goto done;
    rc = sqlite3_step(q);
    if (rc != SQLITE_ROW) goto done;
    if (value) *value = sqlite3_column_int(q, 0);
    if (text) snprintf(text, textlen, "%s", (const char *)sqlite3_column_text(q, 0));
    rc = SQLITE_OK;
done:
    sqlite3_finalize(q);
    return rc;
}

/* reads the schema version and the number of objects that are not SQLite's own, both from one
 * snapshot (a read transaction): read apart, another connection's migration could commit between
 * them and make a new ctcsim database look foreign */
static int read_schema(sqlite3 *db, int *version, int *objects)
{
    int own = sqlite3_get_autocommit(db); /* not already inside the migration's transaction */
    int rc = own ? sqlite3_exec(db, "BEGIN", NULL, NULL, NULL) : SQLITE_OK;
    if (rc != SQLITE_OK) return rc;
    rc = query_one(db, "PRAGMA user_version", version, NULL, 0);
    if (rc == SQLITE_OK)
        rc = query_one(db,
                       "SELECT count(*) FROM sqlite_master WHERE name NOT LIKE 'sqlite\\_%' "
                       "ESCAPE '\\'",
                       objects, NULL, 0);
    if (own) sqlite3_exec(db, rc == SQLITE_OK ? "COMMIT" : "ROLLBACK", NULL, NULL, NULL);
    return rc;
}

/* 1 with a message when a database of this version and content is not ours to touch */
static int refused(int version, int objects, const char *path, char *err, size_t errlen)
{
    if (version > STORE_SCHEMA_VERSION) {
        set_err(err, errlen,
                "database %s has schema version %d, newer than this ctcsim (%d): upgrade ctcsim",
                path, version, STORE_SCHEMA_VERSION);
        return 1;
    }
    if (version < 0) {
        set_err(err, errlen, "database %s is not a ctcsim database (schema version %d)", path,
                version);
        return 1;
    }
    if (version == 0 && objects > 0) {
        set_err(err, errlen,
                "database %s is not a ctcsim database (it has tables but no ctcsim schema "
                "version)",
                path);
        return 1;
    }
    return 0;
}

/* brings the schema to STORE_SCHEMA_VERSION, or refuses a database that is not ctcsim's */
static int migrate(sqlite3 *db, const char *path, char *err, size_t errlen)
{
    int rc = -1, in_tx = 0, version = 0, objects = 0;
    /* the common case, and every refusal, without taking the write lock */
    if (read_schema(db, &version, &objects) != SQLITE_OK) {
        set_err(err, errlen, "cannot open database %s: %s", path, sqlite3_errmsg(db));
        goto done;
    }
    if (refused(version, objects, path, err, errlen)) goto done;
    if (version == STORE_SCHEMA_VERSION) {
        rc = 0;
        goto done;
    }
    if (sqlite3_exec(db, "BEGIN IMMEDIATE", NULL, NULL, NULL) != SQLITE_OK) {
        set_err(err, errlen, "database %s: cannot lock it to create the schema: %s", path,
                sqlite3_errmsg(db));
        goto done;
    }
    in_tx = 1;
    /* again under the write lock: another connection may have migrated it meanwhile */
    if (read_schema(db, &version, &objects) != SQLITE_OK) {
        set_err(err, errlen, "cannot open database %s: %s", path, sqlite3_errmsg(db));
        goto done;
    }
    if (refused(version, objects, path, err, errlen)) goto done;
    for (int v = version; v < STORE_SCHEMA_VERSION; v++) {
        char *why = NULL;
        if (sqlite3_exec(db, migrations[v], NULL, NULL, &why) != SQLITE_OK) {
            set_err(err, errlen, "database %s: migrating the schema from version %d to %d: %s",
                    path, v, v + 1, why ? why : sqlite3_errmsg(db));
            sqlite3_free(why);
            goto done;
        }
    }
    if (sqlite3_exec(db, "COMMIT", NULL, NULL, NULL) != SQLITE_OK) {
        set_err(err, errlen, "database %s: committing the schema: %s", path, sqlite3_errmsg(db));
        goto done;
    }
    in_tx = 0;
    rc = 0;
done:
    if (in_tx && !sqlite3_get_autocommit(db)) sqlite3_exec(db, "ROLLBACK", NULL, NULL, NULL);
    return rc;
}

int store_open(const char *path, store **out, char *err, size_t errlen)
{
    int rc = -1;
    char mode[16] = "";
    store *s = NULL;
    *out = NULL;
    if (!path || !*path) {
        set_err(err, errlen, "cannot open database: the path is empty");
        goto done;
    }
    s = calloc(1, sizeof *s);
    if (!s) {
        set_err(err, errlen, "cannot open database %s: out of memory", path);
        goto done;
    }
    if (store_pg_url(path)) {
        rc = store_pg_open(path, &s->pg, err, errlen);
        goto done;
    }
    if (sqlite3_open_v2(path, &s->db, SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE, NULL) !=
        SQLITE_OK) {
        open_err(s->db, path, err, errlen);
        goto done;
    }
    /* SQLite falls back to read-only when it may not write the file: the service must write */
    if (sqlite3_db_readonly(s->db, "main") == 1) {
        set_err(err, errlen, "cannot open database %s for writing (read-only file or directory)",
                path);
        goto done;
    }
    store_set_busy_timeout(s, STORE_BUSY_MS);
    /* the first read of the file: a file that is not SQLite's fails here */
    /* Switching a new database to WAL takes its exclusive lock for a moment, and a connection
       that asks meanwhile (several processes opening a new file at once) gets SQLITE_BUSY without
       its busy handler being called: try again, within the busy timeout */
    int wal;
    for (int waited_ms = 0;; waited_ms += STORE_WAL_RETRY_MS) {
        wal = query_one(s->db, "PRAGMA journal_mode = WAL", NULL, mode, sizeof mode);
        if ((wal & 0xff) != SQLITE_BUSY || waited_ms >= s->busy_ms) break;
        sqlite3_sleep(STORE_WAL_RETRY_MS);
    }
    if ((wal & 0xff) == SQLITE_READONLY || (wal & 0xff) == SQLITE_CANTOPEN) {
        /* the file is writable but WAL mode cannot create its two files beside it */
        set_err(err, errlen,
                "cannot open database %s: %s (WAL mode needs to create %s-wal and %s-shm in its "
                "directory)",
                path, sqlite3_errmsg(s->db), path, path);
        goto done;
    }
    if (wal != SQLITE_OK) {
        set_err(err, errlen, "cannot open database %s: %s", path, sqlite3_errmsg(s->db));
        goto done;
    }
    if (strcmp(mode, "wal") != 0 && strcmp(mode, "memory") != 0) {
        set_err(err, errlen, "database %s: cannot use WAL mode (journal mode stays '%s')", path,
                mode);
        goto done;
    }
    if (sqlite3_exec(s->db, "PRAGMA synchronous = NORMAL; PRAGMA foreign_keys = ON", NULL, NULL,
                     NULL) != SQLITE_OK) {
        set_err(err, errlen, "database %s: %s", path, sqlite3_errmsg(s->db));
        goto done;
    }
    if (migrate(s->db, path, err, errlen)) goto done;
    for (int i = 0; i < ST_NSTMT; i++)
        if (sqlite3_prepare_v3(s->db, stmt_sql[i], -1, SQLITE_PREPARE_PERSISTENT, &s->stmt[i],
                               NULL) != SQLITE_OK) {
            set_err(err, errlen, "database %s: its schema is not ctcsim's: %s", path,
                    sqlite3_errmsg(s->db));
            goto done;
        }
    rc = 0;
done:
    if (rc)
        store_close(s);
    else
        *out = s;
    return rc;
}

void store_set_busy_timeout(store *s, int ms)
{
    if (s->pg) {
        store_pg_set_busy_timeout(s->pg, ms);
        return;
    }
    s->busy_ms = ms > 0 ? ms : 0;
    sqlite3_busy_timeout(s->db, s->busy_ms);
}

int store_set_max_size(store *s, long long max_bytes, char *err, size_t errlen)
{
    if (s->pg) return store_pg_set_max_size(s->pg, max_bytes, err, errlen);
    int page = 0, count = 0;
    char sql[64];
    call_begin(s);
    if (max_bytes < 0) {
        set_err(err, errlen, "the database's size limit must be >= 0 bytes (got %lld)", max_bytes);
        return -1;
    }
    if (query_one(s->db, "PRAGMA page_size", &page, NULL, 0) != SQLITE_OK || page <= 0) {
        db_err(s, err, errlen, "reading the database's page size");
        return -1;
    }
    /* uncapped: SQLite's default SQLITE_MAX_PAGE_COUNT; a cap under one page is one page */
    long long pages = max_bytes ? max_bytes / page : 1073741823LL;
    snprintf(sql, sizeof sql, "PRAGMA max_page_count = %lld", pages > 0 ? pages : 1);
    if (query_one(s->db, sql, &count, NULL, 0) != SQLITE_OK) {
        db_err(s, err, errlen, "setting the database's size limit");
        return -1;
    }
    return 0;
}

/* the bytes writes may still add: the disk's free space for unprivileged users, and under the
 * size cap the pages neither used nor past it (free pages inside the file count); -1 when
 * unknown */
static long long room_bytes(store *s)
{
    int page = 0, count = 0, free_pages = 0, max_pages = 0;
    const char *path = sqlite3_db_filename(s->db, "main");
    struct statvfs fs;
    if (!path || !*path || statvfs(path, &fs) != 0 ||
        query_one(s->db, "PRAGMA page_size", &page, NULL, 0) != SQLITE_OK ||
        query_one(s->db, "PRAGMA page_count", &count, NULL, 0) != SQLITE_OK ||
        query_one(s->db, "PRAGMA freelist_count", &free_pages, NULL, 0) != SQLITE_OK ||
        query_one(s->db, "PRAGMA max_page_count", &max_pages, NULL, 0) != SQLITE_OK)
        return -1;
    long long disk = (long long)fs.f_bavail * (long long)fs.f_frsize;
    long long cap = ((long long)max_pages - count + free_pages) * page;
    return disk < cap ? disk : cap;
}

int store_probe(store *s, char *err, size_t errlen)
{
    if (s->pg) return store_pg_probe(s->pg, err, errlen);
    int rc = -1, in_tx = 0;
    store_state st = {.fault = STORE_FAULT_NONE};
    call_begin(s);
    if (s->health) store_health_read(s->health, &st);
    /* a full database: a write in place may work on a full disk, so the room is measured */
    if (st.fault == STORE_FAULT_FULL) {
        long long room = room_bytes(s);
        if (room >= STORE_ROOM_BYTES) {
            health_ok(s->health, 1);
            return 0;
        }
        set_err(err, errlen, "probing the database: %lld bytes free, %d needed", room,
                STORE_ROOM_BYTES);
        health_fault(s->health, STORE_FAULT_FULL, err ? err : "");
        return -1;
    }
    if (tx_step(s, ST_BEGIN) != SQLITE_OK) {
        db_err(s, err, errlen, "probing the database");
        goto done;
    }
    in_tx = 1;
    if (tx_step(s, ST_PROBE) != SQLITE_OK || tx_step(s, ST_COMMIT) != SQLITE_OK) {
        db_err(s, err, errlen, "probing the database");
        goto done;
    }
    in_tx = 0;
    rc = 0;
done:
    if (in_tx) tx_rollback(s);
    return write_end(s, rc, 0);
}

int store_reserve(store *s, long long bytes, char *err, size_t errlen)
{
    if (s->pg) return store_pg_reserve(s->pg, bytes, err, errlen);
    const char *db = sqlite3_db_filename(s->db, "main");
    const char *wal = db && *db ? sqlite3_filename_wal(db) : NULL;
    call_begin(s);
    if (!wal || !*wal) {
        set_err(err, errlen, "reserving room for the log: the database has no file");
        return -1;
    }
    int fd = open(wal, O_WRONLY | O_CLOEXEC);
    if (fd < 0) {
        set_err(err, errlen, "reserving room for the log: %s: %s", wal, strerror(errno));
        return -1;
    }
    /* the blocks past the end are allocated, the size SQLite sees is left as it is */
    int rc = 0;
    while (fallocate(fd, FALLOC_FL_KEEP_SIZE, 0, (off_t)bytes) != 0) {
        if (errno == EINTR) continue;
        set_err(err, errlen, "reserving %lld bytes for the log %s: %s", bytes, wal,
                strerror(errno));
        rc = -1;
        break;
    }
    close(fd);
    return rc;
}

void store_close(store *s)
{
    if (!s) return;
    store_pg_close(s->pg);
    if (s->pg) {
        free(s);
        return;
    }
    store_series_end(s);
    for (int i = 0; i < ST_NSTMT; i++) sqlite3_finalize(s->stmt[i]);
    sqlite3_close(s->db);
    free(s);
}

/* ---- jobs ---- */

static int insert_job(store *s, const char *name, const char *preset, int nbodies, int nv,
                      const char *controller, const char *spec, int64_t *id, char *err,
                      size_t errlen)
{
    sqlite3_stmt *q = s->stmt[ST_INSERT];
    int rc = -1;
    if (store_check_job(name, controller, spec, nbodies, nv, err, errlen) != 0) goto done;
    if (sqlite3_bind_text(q, 1, name, -1, SQLITE_STATIC) != SQLITE_OK ||
        (preset ? sqlite3_bind_text(q, 2, preset, -1, SQLITE_STATIC) : sqlite3_bind_null(q, 2)) !=
            SQLITE_OK ||
        sqlite3_bind_double(q, 3, now_s()) != SQLITE_OK ||
        sqlite3_bind_int(q, 4, nbodies) != SQLITE_OK || sqlite3_bind_int(q, 5, nv) != SQLITE_OK ||
        sqlite3_bind_text(q, 6, controller, -1, SQLITE_STATIC) != SQLITE_OK ||
        sqlite3_bind_text(q, 7, spec, -1, SQLITE_STATIC) != SQLITE_OK ||
        sqlite3_step(q) != SQLITE_DONE) {
        db_err(s, err, errlen, "cannot store job '%s'", name);
        goto done;
    }
    *id = sqlite3_last_insert_rowid(s->db);
    rc = 0;
done:
    release(q);
    return rc;
}

int store_insert(store *s, const char *name, const char *preset, int nbodies, int nv,
                 const char *controller, const char *spec, int64_t *id, char *err, size_t errlen)
{
    return store_insert_bounded(s, 0, name, preset, nbodies, nv, controller, spec, id, err, errlen);
}

int store_insert_bounded(store *s, long max_queued, const char *name, const char *preset,
                         int nbodies, int nv, const char *controller, const char *spec, int64_t *id,
                         char *err, size_t errlen)
{
    if (s->pg)
        return store_pg_insert(s->pg, max_queued, name, preset, nbodies, nv, controller, spec, id,
                               err, errlen);
    /* SQLite: one process owns the file, and its queue holds the bound (jobq_submit) */
    call_begin(s);
    return write_end(s, insert_job(s, name, preset, nbodies, nv, controller, spec, id, err, errlen),
                     1);
}

static int recover_jobs(store *s, int64_t **ids, int *n, char *err, size_t errlen)
{
    sqlite3_stmt *sel = s->stmt[ST_RECOVER_IDS];
    int rc = -1, in_tx = 0, count = 0, cap = 16, step;
    int64_t *list = malloc((size_t)cap * sizeof *list);
    *ids = NULL;
    *n = 0;
    if (!list) {
        set_err(err, errlen, "recovering jobs: out of memory");
        goto done;
    }
    if (tx_step(s, ST_BEGIN) != SQLITE_OK) {
        db_err(s, err, errlen, "recovering jobs");
        goto done;
    }
    in_tx = 1;
    /* the unfinished jobs, oldest first */
    while ((step = sqlite3_step(sel)) == SQLITE_ROW) {
        if (count == cap) {
            int64_t *grown =
                cap <= INT_MAX / 2 ? realloc(list, 2 * (size_t)cap * sizeof *list) : NULL;
            if (!grown) {
                set_err(err, errlen, "recovering jobs: out of memory");
                goto done;
            }
            list = grown;
            cap *= 2;
        }
        list[count++] = sqlite3_column_int64(sel, 0);
    }
    if (step != SQLITE_DONE) {
        db_err(s, err, errlen, "recovering jobs");
        goto done;
    }
    sqlite3_reset(sel);
    /* a running job restarts from t = 0: drop any series it left, then queue them all */
    if (tx_step(s, ST_RECOVER_SERIES) != SQLITE_OK || tx_step(s, ST_RECOVER_JOBS) != SQLITE_OK) {
        db_err(s, err, errlen, "recovering jobs");
        goto done;
    }
    if (tx_step(s, ST_COMMIT) != SQLITE_OK) {
        db_err(s, err, errlen, "recovering jobs");
        goto done;
    }
    in_tx = 0;
    *ids = list;
    *n = count;
    list = NULL;
    rc = 0;
done:
    sqlite3_reset(sel);
    if (in_tx) tx_rollback(s);
    free(list);
    return rc;
}

int store_recover(store *s, int64_t **ids, int *n, char *err, size_t errlen)
{
    if (s->pg) return store_pg_recover(s->pg, ids, n, err, errlen);
    call_begin(s);
    return write_end(s, recover_jobs(s, ids, n, err, errlen), 0);
}

static int start_job(store *s, int64_t id, char *err, size_t errlen)
{
    sqlite3_stmt *q = s->stmt[ST_START];
    int rc = -1;
    sqlite3_bind_int64(q, 1, id);
    sqlite3_bind_double(q, 2, now_s());
    if (sqlite3_step(q) != SQLITE_DONE) {
        db_err(s, err, errlen, "cannot start job %lld", (long long)id);
        goto done;
    }
    rc = sqlite3_changes(s->db) == 1 ? 0 : 1;
done:
    release(q);
    return rc;
}

int store_start(store *s, int64_t id, char *err, size_t errlen)
{
    if (s->pg) return store_pg_start(s->pg, id, err, errlen);
    call_begin(s);
    return write_end(s, start_job(s, id, err, errlen), 0);
}

static int record_progress(store *s, int64_t id, double progress, char *err, size_t errlen)
{
    sqlite3_stmt *q = s->stmt[ST_PROGRESS];
    int rc = -1;
    if (isnan(progress)) {
        set_err(err, errlen, "job %lld: progress is NaN", (long long)id);
        goto done;
    }
    /* a fraction a rounding error past 0..1 is still a fraction */
    sqlite3_bind_int64(q, 1, id);
    sqlite3_bind_double(q, 2, fmin(fmax(progress, 0.0), 1.0));
    if (sqlite3_step(q) != SQLITE_DONE) {
        db_err(s, err, errlen, "job %lld: cannot record progress", (long long)id);
        goto done;
    }
    if (sqlite3_changes(s->db) != 1) {
        release(q);
        not_running_err(s, id, "record progress of", err, errlen);
        goto done;
    }
    rc = 0;
done:
    release(q);
    return rc;
}

int store_progress(store *s, int64_t id, double progress, char *err, size_t errlen)
{
    if (s->pg) return store_pg_progress(s->pg, id, progress, err, errlen);
    call_begin(s);
    return write_end(s, record_progress(s, id, progress, err, errlen), 0);
}

static int requeue_job(store *s, int64_t id, char *err, size_t errlen)
{
    sqlite3_stmt *q = s->stmt[ST_REQUEUE];
    int rc = -1;
    sqlite3_bind_int64(q, 1, id);
    if (sqlite3_step(q) != SQLITE_DONE) {
        db_err(s, err, errlen, "cannot requeue job %lld", (long long)id);
        goto done;
    }
    if (sqlite3_changes(s->db) != 1) {
        release(q);
        not_running_err(s, id, "requeue", err, errlen);
        goto done;
    }
    rc = 0;
done:
    release(q);
    return rc;
}

int store_requeue(store *s, int64_t id, char *err, size_t errlen)
{
    if (s->pg) return store_pg_requeue(s->pg, id, err, errlen);
    call_begin(s);
    return write_end(s, requeue_job(s, id, err, errlen), 0);
}

/* the largest finite-or-infinite entry of the run's e_max, NaN when there is none */
static double result_e_max(const ctc_sim_result *r)
{
    double m = NAN;
    if (!r || !r->metrics.e_max) return m;
    for (int i = 0; i < r->metrics.nv; i++)
        if (!isnan(r->metrics.e_max[i]) && (isnan(m) || r->metrics.e_max[i] > m))
            m = r->metrics.e_max[i];
    return m;
}

/* binds a REAL that may be NaN (stored as NULL) */
static int bind_real(sqlite3_stmt *q, int i, double x)
{
    return isnan(x) ? sqlite3_bind_null(q, i) : sqlite3_bind_double(q, i, x);
}

/* writes one series row; data holds nsamples x width doubles */
static int put_series(store *s, int64_t id, const char *channel, int width, int nsamples,
                      const double *data, char *err, size_t errlen)
{
    sqlite3_stmt *q = s->stmt[ST_SERIES_INSERT];
    int rc = -1;
    sqlite3_uint64 bytes = (sqlite3_uint64)nsamples * (sqlite3_uint64)width * sizeof(double);
    /* a zero-length blob needs a non-NULL pointer (NULL would bind SQL NULL) */
    const void *blob = data ? (const void *)data : (const void *)"";
    if (sqlite3_bind_int64(q, 1, id) != SQLITE_OK ||
        sqlite3_bind_text(q, 2, channel, -1, SQLITE_STATIC) != SQLITE_OK ||
        sqlite3_bind_int(q, 3, width) != SQLITE_OK ||
        sqlite3_bind_int(q, 4, nsamples) != SQLITE_OK ||
        sqlite3_bind_blob64(q, 5, blob, bytes, SQLITE_STATIC) != SQLITE_OK ||
        sqlite3_step(q) != SQLITE_DONE) {
        db_err(s, err, errlen, "job %lld: storing series %s", (long long)id, channel);
        goto done;
    }
    rc = 0;
done:
    release(q);
    return rc;
}

static int finish_job(store *s, int64_t id, store_status status, const char *message,
                      const char *metrics, const ctc_sim_result *r, char *err, size_t errlen)
{
    sqlite3_stmt *q = s->stmt[ST_FINISH];
    sqlite3_stmt *del = s->stmt[ST_SERIES_DELETE];
    int rc = -1, in_tx = 0;
    if (store_check_finish(id, status, r, err, errlen) != 0) goto done;
    if (tx_step(s, ST_BEGIN) != SQLITE_OK) {
        db_err(s, err, errlen, "cannot finish job %lld", (long long)id);
        goto done;
    }
    in_tx = 1;
    /* the final status, only for a job still queued or running */
    if (sqlite3_bind_int64(q, 1, id) != SQLITE_OK ||
        sqlite3_bind_text(q, 2, store_status_name(status), -1, SQLITE_STATIC) != SQLITE_OK ||
        (message && *message ? sqlite3_bind_text(q, 3, message, -1, SQLITE_STATIC)
                             : sqlite3_bind_null(q, 3)) != SQLITE_OK ||
        (metrics ? sqlite3_bind_text(q, 4, metrics, -1, SQLITE_STATIC) : sqlite3_bind_null(q, 4)) !=
            SQLITE_OK ||
        bind_real(q, 5, result_e_max(r)) != SQLITE_OK ||
        bind_real(q, 6, r ? r->metrics.wall_s : NAN) != SQLITE_OK ||
        sqlite3_bind_double(q, 7, now_s()) != SQLITE_OK || sqlite3_step(q) != SQLITE_DONE) {
        db_err(s, err, errlen, "cannot finish job %lld", (long long)id);
        goto done;
    }
    if (sqlite3_changes(s->db) != 1) {
        store_status st = STORE_QUEUED;
        int found = status_of(s, id, &st, err, errlen);
        store_not_finishable_err(id, found, st, err, errlen);
        goto done;
    }
    /* the series: t, then every recorded channel, replacing any rows left behind */
    sqlite3_bind_int64(del, 1, id);
    if (sqlite3_step(del) != SQLITE_DONE) {
        db_err(s, err, errlen, "job %lld: clearing its series", (long long)id);
        goto done;
    }
    if (r) {
        if (put_series(s, id, "t", 1, r->nsamples, r->t, err, errlen)) goto done;
        for (int c = 0; c < CTC_NCHANNELS; c++) {
            if (!r->ch[c] || r->width[c] <= 0) continue;
            if (put_series(s, id, ctc_channel_name((ctc_channel)c), r->width[c], r->nsamples,
                           r->ch[c], err, errlen))
                goto done;
        }
    }
    if (tx_step(s, ST_COMMIT) != SQLITE_OK) {
        db_err(s, err, errlen, "cannot finish job %lld", (long long)id);
        goto done;
    }
    in_tx = 0;
    rc = 0;
done:
    release(q);
    release(del);
    if (in_tx) tx_rollback(s);
    return rc;
}

int store_finish(store *s, int64_t id, store_status status, const char *message,
                 const char *metrics, const ctc_sim_result *r, char *err, size_t errlen)
{
    if (s->pg) return store_pg_finish(s->pg, id, status, message, metrics, r, err, errlen);
    call_begin(s);
    return write_end(s, finish_job(s, id, status, message, metrics, r, err, errlen), r != NULL);
}

int store_get(store *s, int64_t id, store_job *out, char *err, size_t errlen)
{
    if (s->pg) return store_pg_get(s->pg, id, out, err, errlen);
    call_begin(s);
    sqlite3_stmt *q = s->stmt[ST_GET];
    int rc = -1;
    memset(out, 0, sizeof *out);
    sqlite3_bind_int64(q, 1, id);
    int step = sqlite3_step(q);
    if (step == SQLITE_DONE) {
        rc = 1;
        goto done;
    }
    if (step != SQLITE_ROW) {
        db_err(s, err, errlen, "cannot read job %lld", (long long)id);
        goto done;
    }
    if (read_job(q, 1, out, err, errlen)) goto done;
    rc = 0;
done:
    release(q);
    return rc;
}

void store_job_clear(store_job *j)
{
    if (!j) return;
    free(j->name);
    free(j->preset);
    free(j->controller);
    free(j->spec);
    free(j->metrics);
    free(j->message);
    free(j->tags);
    memset(j, 0, sizeof *j);
}

/* How step_rows reads a list: each element's size, the reader of one row (0, or -1 with err),
 * and the free of n elements read (those a failed read left half filled included). */
typedef struct row_reader {
    size_t size;
    int (*read)(sqlite3_stmt *q, void *elem, char *err, size_t errlen);
    void (*free_rows)(void *rows, long n);
} row_reader;

/* Steps the bound statement q to its end, reading each row with rr->read into a zeroed element of
 * a new array grown as needed: 0 with *rows (free with rr->free_rows) and *n, or -1 with err
 * ("WHAT: out of memory", or the database's message after what) and nothing handed out. */
static int step_rows(store *s, sqlite3_stmt *q, const row_reader *rr, void **rows, long *n,
                     const char *what, char *err, size_t errlen)
{
    int rc = -1, step;
    long count = 0, cap = 0;
    char *list = NULL;
    *rows = NULL;
    *n = 0;
    while ((step = sqlite3_step(q)) == SQLITE_ROW) {
        if (count == cap) {
            long grow = cap ? 2 * cap : 64;
            char *bigger = realloc(list, (size_t)grow * rr->size);
            if (!bigger) {
                set_err(err, errlen, "%s: out of memory", what);
                goto done;
            }
            list = bigger;
            cap = grow;
        }
        void *elem = list + (size_t)count * rr->size;
        memset(elem, 0, rr->size);
        count++;
        if (rr->read(q, elem, err, errlen) != 0) goto done;
    }
    if (step != SQLITE_DONE) {
        db_err(s, err, errlen, "%s", what);
        goto done;
    }
    *rows = list;
    *n = count;
    list = NULL;
    rc = 0;
done:
    if (list) rr->free_rows(list, count);
    return rc;
}

static int job_row_read(sqlite3_stmt *q, void *elem, char *err, size_t errlen)
{
    return read_job(q, 0, elem, err, errlen);
}

static void job_rows_free(void *rows, long n)
{
    store_jobs_free(rows, (int)n);
}

static const row_reader job_rows = {sizeof(store_job), job_row_read, job_rows_free};

/* the rows of the bound list statement q (at most limit), into *rows and *n; 0 or -1 */
static int list_rows(store *s, sqlite3_stmt *q, store_job **rows, int *n, char *err, size_t errlen)
{
    void *list;
    long count;
    if (step_rows(s, q, &job_rows, &list, &count, "listing jobs", err, errlen) != 0) return -1;
    *rows = list;
    *n = (int)count;
    return 0;
}

int store_list(store *s, int64_t before, int status, int limit, store_job **rows, int *n, char *err,
               size_t errlen)
{
    if (s->pg) return store_pg_list(s->pg, before, status, limit, rows, n, err, errlen);
    call_begin(s);
    sqlite3_stmt *q = s->stmt[status < 0 ? ST_LIST_ANY : ST_LIST_STATUS];
    int rc = -1;
    *rows = NULL;
    *n = 0;
    if (store_check_list(before, status, limit, err, errlen) != 0) goto done;
    /* id < INT64_MAX is every id: the one statement serves "from the newest" too */
    sqlite3_bind_int64(q, 1, before > 0 ? before : INT64_MAX);
    sqlite3_bind_int(q, 2, limit);
    if (status >= 0) sqlite3_bind_text(q, 3, store_status_name(status), -1, SQLITE_STATIC);
    rc = list_rows(s, q, rows, n, err, errlen);
done:
    release(q);
    return rc;
}

int store_search(store *s, int64_t before, const store_filter *f, int limit, store_job **rows,
                 int *n, char *err, size_t errlen)
{
    if (s->pg) return store_pg_search(s->pg, before, f, limit, rows, n, err, errlen);
    call_begin(s);
    sqlite3_stmt *q = s->stmt[ST_SEARCH];
    int rc = -1;
    char *text = NULL;
    *rows = NULL;
    *n = 0;
    if (store_check_list(before, f->status, limit, err, errlen) != 0) goto done;
    if (f->text) {
        /* lower() of SQLite folds ASCII only: so does this */
        if (!(text = strdup(f->text))) {
            set_err(err, errlen, "listing jobs: out of memory");
            goto done;
        }
        for (char *c = text; *c; c++)
            if (*c >= 'A' && *c <= 'Z') *c = (char)(*c - 'A' + 'a');
    }
    sqlite3_bind_int64(q, 1, before > 0 ? before : INT64_MAX);
    sqlite3_bind_int(q, 2, limit);
    if (f->status >= 0) sqlite3_bind_text(q, 3, store_status_name(f->status), -1, SQLITE_STATIC);
    if (text) sqlite3_bind_text(q, 4, text, -1, SQLITE_STATIC);
    if (f->tag) sqlite3_bind_text(q, 5, f->tag, -1, SQLITE_STATIC);
    rc = list_rows(s, q, rows, n, err, errlen);
done:
    release(q);
    free(text);
    return rc;
}

void store_jobs_free(store_job *rows, int n)
{
    for (int i = 0; rows && i < n; i++) store_job_clear(&rows[i]);
    free(rows);
}

/* the channel index of a series row's name, -1 for "t", -2 if unknown */
static int channel_of(const char *name)
{
    if (strcmp(name, "t") == 0) return -1;
    for (int c = 0; c < CTC_NCHANNELS; c++)
        if (strcmp(name, ctc_channel_name((ctc_channel)c)) == 0) return c;
    return -2;
}

/* the width a channel must have in a job of nv coordinates whose controller's channels have
 * nind columns (0: any - q, whose nq may differ from nv with spherical joints, and the first of
 * the controller's channels, which sets nind: nv of an open chain, fewer of a loop) */
static int expected_width(int c, int nv, int nind)
{
    return c == -1                                  ? 1
           : c == CTC_CH_ENERGY || c == CTC_CH_LOOP ? 2
           : c == CTC_CH_EE                         ? 6
           : c == CTC_CH_POSE                       ? 0
           : c == CTC_CH_QD                         ? nv
           : c == CTC_CH_Q                          ? 0
                                                    : nind;
}

/* What the rows of a job's series read so far say: the job's nv, the width of the controller's
 * channels (0 until the first), the samples per row (-1 until the first). */
typedef struct series_rows {
    int64_t id;
    int nv, nind, nsamples;
} series_rows;

/* Checks one series row against its job and the rows before it - every row before its samples
 * are touched, so a damaged one is an error, never an out-of-bounds read. *c receives its
 * channel (-1 for t). 0, or -1 with a message. */
static int check_series_row(series_rows *rows, const char *name, int width, sqlite3_int64 nsamples,
                            sqlite3_int64 bytes, int *c, char *err, size_t errlen)
{
    long long id = (long long)rows->id;
    *c = channel_of(name ? name : "");
    if (*c == -2) {
        set_err(err, errlen, "job %lld: series has an unknown channel '%s'", id, name ? name : "");
        return -1;
    }
    int want = expected_width(*c, rows->nv, rows->nind);
    if (width < 1 || (want && width != want)) {
        set_err(err, errlen, "job %lld: series %s has width %d, expected %d", id, name, width,
                want);
        return -1;
    }
    if (*c >= 0 && *c != CTC_CH_Q && *c != CTC_CH_QD && *c != CTC_CH_ENERGY && *c != CTC_CH_LOOP &&
        *c != CTC_CH_EE && *c != CTC_CH_POSE && rows->nind == 0) {
        /* the first of the controller's channels: at most one column per coordinate */
        if (width > rows->nv) {
            set_err(err, errlen, "job %lld: series %s has width %d, expected at most %d", id, name,
                    width, rows->nv);
            return -1;
        }
        rows->nind = width;
    }
    if (nsamples < 0 || nsamples > INT_MAX || (rows->nsamples >= 0 && nsamples != rows->nsamples)) {
        set_err(err, errlen, "job %lld: series %s has %lld samples, the others %d", id, name,
                (long long)nsamples, rows->nsamples);
        return -1;
    }
    if ((sqlite3_uint64)bytes != (sqlite3_uint64)nsamples * (sqlite3_uint64)width * 8u) {
        set_err(err, errlen,
                "job %lld: series %s holds %lld bytes, expected %lld (%lld samples x %d "
                "values x 8)",
                id, name, (long long)bytes, (long long)nsamples * width * 8, (long long)nsamples,
                width);
        return -1;
    }
    rows->nsamples = (int)nsamples;
    return 0;
}

int store_series_check_row(int64_t id, int *nv, int *nind, int *nsamples, const char *name,
                           int width, int64_t row_nsamples, int64_t bytes, int *c, char *err,
                           size_t errlen)
{
    series_rows rows = {.id = id, .nv = *nv, .nind = *nind, .nsamples = *nsamples};
    int rc = check_series_row(&rows, name, width, row_nsamples, bytes, c, err, errlen);
    *nind = rows.nind;
    *nsamples = rows.nsamples;
    return rc;
}

int store_get_series(store *s, int64_t id, ctc_sim_result **out, char *err, size_t errlen)
{
    if (s->pg) return store_pg_get_series(s->pg, id, out, err, errlen);
    call_begin(s);
    sqlite3_stmt *q = s->stmt[ST_SERIES_GET];
    ctc_sim_result *r = NULL;
    series_rows rows = {.id = id, .nsamples = -1};
    int rc = -1, step;
    *out = NULL;
    sqlite3_bind_int64(q, 1, id);
    /* one statement, one snapshot: the rows are consistent with each other and with the job */
    while ((step = sqlite3_step(q)) == SQLITE_ROW) {
        const char *name = (const char *)sqlite3_column_text(q, 0);
        const void *blob = sqlite3_column_blob(q, 3);
        sqlite3_int64 bytes = sqlite3_column_bytes(q, 3);
        int c;
        if (!r) {
            rows.nv = sqlite3_column_int(q, 4);
            r = calloc(1, sizeof *r);
            if (!r) {
                set_err(err, errlen, "job %lld: reading its series: out of memory", (long long)id);
                goto done;
            }
        }
        if (check_series_row(&rows, name, sqlite3_column_int(q, 1), sqlite3_column_int64(q, 2),
                             bytes, &c, err, errlen))
            goto done;
        /* malloc(0) may be NULL: keep at least one value so that NULL means "out of memory" */
        double *data = malloc(bytes > 0 ? (size_t)bytes : sizeof(double));
        if (!data) {
            set_err(err, errlen, "job %lld: reading series %s: out of memory", (long long)id, name);
            goto done;
        }
        if (bytes > 0) memcpy(data, blob, (size_t)bytes);
        if (c == -1) {
            r->t = data;
        } else {
            r->ch[c] = data;
            r->width[c] = sqlite3_column_int(q, 1);
            r->channels |= CTC_CH_BIT(c);
        }
    }
    if (step != SQLITE_DONE) {
        db_err(s, err, errlen, "job %lld: reading its series", (long long)id);
        goto done;
    }
    if (!r) {
        rc = 1;
        goto done;
    }
    if (!r->t) {
        set_err(err, errlen, "job %lld: series has no t", (long long)id);
        goto done;
    }
    /* nq is q's width; with q not recorded it is taken as nv (they differ only with spherical
     * joints, and then only q has width nq) */
    r->nsamples = rows.nsamples;
    r->nv = rows.nv;
    r->nq = r->width[CTC_CH_Q] ? r->width[CTC_CH_Q] : rows.nv;
    r->metrics.nv = rows.nv;
    *out = r;
    r = NULL;
    rc = 0;
done:
    release(q);
    ctc_sim_result_free(r);
    return rc;
}

int store_get_series_info(store *s, int64_t id, store_series_info *out, char *err, size_t errlen)
{
    if (s->pg) return store_pg_get_series_info(s->pg, id, out, err, errlen);
    call_begin(s);
    sqlite3_stmt *q = s->stmt[ST_SERIES_INFO];
    series_rows rows = {.id = id, .nsamples = -1};
    int rc = -1, step, found = 0, have_t = 0;
    memset(out, 0, sizeof *out);
    sqlite3_bind_int64(q, 1, id);
    while ((step = sqlite3_step(q)) == SQLITE_ROW) {
        const char *name = (const char *)sqlite3_column_text(q, 0);
        int width = sqlite3_column_int(q, 1);
        sqlite3_int64 bytes = sqlite3_column_int64(q, 3);
        int c;
        if (!found) rows.nv = sqlite3_column_int(q, 4);
        found = 1;
        if (check_series_row(&rows, name, width, sqlite3_column_int64(q, 2), bytes, &c, err,
                             errlen))
            goto done;
        if (c == -1) {
            have_t = 1;
        } else {
            out->width[c] = width;
            out->channels |= CTC_CH_BIT(c);
        }
        out->bytes += bytes;
    }
    if (step != SQLITE_DONE) {
        db_err(s, err, errlen, "job %lld: reading its series", (long long)id);
        goto done;
    }
    if (!found) {
        rc = 1;
        goto done;
    }
    if (!have_t) {
        set_err(err, errlen, "job %lld: series has no t", (long long)id);
        goto done;
    }
    out->nsamples = rows.nsamples;
    out->nv = rows.nv;
    out->nq = out->width[CTC_CH_Q] ? out->width[CTC_CH_Q] : rows.nv;
    rc = 0;
done:
    release(q);
    if (rc) memset(out, 0, sizeof *out);
    return rc;
}

int store_series_begin(store *s, char *err, size_t errlen)
{
    if (s->pg) return store_pg_series_begin(s->pg, err, errlen);
    call_begin(s);
    if (s->reading) {
        set_err(err, errlen, "reading a series: a read is already under way");
        return -1;
    }
    if (tx_step(s, ST_BEGIN_READ) != SQLITE_OK) {
        db_err(s, err, errlen, "reading a series");
        return -1;
    }
    s->reading = 1;
    s->blob_job = 0;
    return 0;
}

/* closes the blob handles of a read */
static void close_blobs(store *s)
{
    for (int k = 0; k <= CTC_NCHANNELS; k++) {
        sqlite3_blob_close(s->blob[k]);
        s->blob[k] = NULL;
    }
}

int store_series_read(store *s, int64_t id, int channel, uint64_t offset, void *buf, size_t len,
                      char *err, size_t errlen)
{
    if (s->pg) return store_pg_series_read(s->pg, id, channel, offset, buf, len, err, errlen);
    call_begin(s);
    const char *name = channel < 0 ? "t" : ctc_channel_name((ctc_channel)channel);
    if (!s->reading || channel < -1 || channel >= CTC_NCHANNELS) {
        set_err(err, errlen, "job %lld: reading series %s: %s", (long long)id, name,
                s->reading ? "no such channel" : "not inside store_series_begin");
        return -1;
    }
    if (s->blob_job != id) {
        close_blobs(s);
        s->blob_job = id;
    }
    sqlite3_blob **blob = &s->blob[channel + 1];
    if (!*blob) {
        /* the row by its key, in this read's snapshot: a rowid alone could name a row that
           another job took after this one was deleted */
        sqlite3_stmt *q = s->stmt[ST_SERIES_ROW];
        sqlite3_bind_int64(q, 1, id);
        sqlite3_bind_text(q, 2, name, -1, SQLITE_STATIC);
        int step = sqlite3_step(q);
        sqlite3_int64 rowid = step == SQLITE_ROW ? sqlite3_column_int64(q, 0) : 0;
        if (step != SQLITE_ROW && step != SQLITE_DONE)
            db_err(s, err, errlen, "job %lld: reading series %s", (long long)id, name);
        release(q);
        if (step == SQLITE_DONE) {
            set_err(err, errlen, "job %lld: series %s is gone", (long long)id, name);
            return 1;
        }
        if (step != SQLITE_ROW) return -1;
        if (sqlite3_blob_open(s->db, "main", "series", "data", rowid, 0, blob) != SQLITE_OK) {
            db_err(s, err, errlen, "job %lld: reading series %s", (long long)id, name);
            sqlite3_blob_close(*blob);
            *blob = NULL;
            return -1;
        }
    }
    int bytes = sqlite3_blob_bytes(*blob);
    if (offset > (uint64_t)bytes || len > (uint64_t)bytes - offset) {
        set_err(err, errlen,
                "job %lld: series %s holds %d bytes, not the %zu asked for at byte %llu",
                (long long)id, name, bytes, len, (unsigned long long)offset);
        return -1;
    }
    if (sqlite3_blob_read(*blob, buf, (int)len, (int)offset) != SQLITE_OK) {
        db_err(s, err, errlen, "job %lld: reading series %s", (long long)id, name);
        return -1;
    }
    return 0;
}

void store_series_end(store *s)
{
    if (s && s->pg) {
        store_pg_series_end(s->pg);
        return;
    }
    if (!s || !s->reading) return;
    close_blobs(s);
    if (!sqlite3_get_autocommit(s->db) && tx_step(s, ST_COMMIT) != SQLITE_OK) tx_rollback(s);
    s->reading = 0;
}

static int delete_job(store *s, int64_t id, char *err, size_t errlen)
{
    sqlite3_stmt *q = s->stmt[ST_DELETE];
    int rc = -1, in_tx = 0;
    store_status st;
    if (tx_step(s, ST_BEGIN) != SQLITE_OK) {
        db_err(s, err, errlen, "cannot delete job %lld", (long long)id);
        goto done;
    }
    in_tx = 1;
    /* only a finished job goes; its series rows follow by ON DELETE CASCADE */
    int found = status_of(s, id, &st, err, errlen);
    if (found != 0) {
        rc = found;
        goto done;
    }
    if (st == STORE_QUEUED || st == STORE_RUNNING) {
        rc = 2;
        goto done;
    }
    sqlite3_bind_int64(q, 1, id);
    if (sqlite3_step(q) != SQLITE_DONE) {
        db_err(s, err, errlen, "cannot delete job %lld", (long long)id);
        goto done;
    }
    if (tx_step(s, ST_COMMIT) != SQLITE_OK) {
        db_err(s, err, errlen, "cannot delete job %lld", (long long)id);
        goto done;
    }
    in_tx = 0;
    rc = 0;
done:
    release(q);
    if (in_tx) tx_rollback(s);
    return rc;
}

int store_delete(store *s, int64_t id, char *err, size_t errlen)
{
    if (s->pg) return store_pg_delete(s->pg, id, err, errlen);
    call_begin(s);
    return write_end(s, delete_job(s, id, err, errlen), 1);
}

int store_count(store *s, long counts[STORE_NSTATUS], char *err, size_t errlen)
{
    if (s->pg) return store_pg_count(s->pg, counts, err, errlen);
    call_begin(s);
    sqlite3_stmt *q = s->stmt[ST_COUNT];
    int rc = -1, step;
    for (int i = 0; i < STORE_NSTATUS; i++) counts[i] = 0;
    while ((step = sqlite3_step(q)) == SQLITE_ROW) {
        const char *name = (const char *)sqlite3_column_text(q, 0);
        int st = store_status_parse(name);
        if (st < 0) {
            set_err(err, errlen, "counting jobs: unknown status '%s'", name ? name : "");
            goto done;
        }
        counts[st] = (long)sqlite3_column_int64(q, 1);
    }
    if (step != SQLITE_DONE) {
        db_err(s, err, errlen, "counting jobs");
        goto done;
    }
    rc = 0;
done:
    s->count_vm_steps = sqlite3_stmt_status(q, SQLITE_STMTSTATUS_VM_STEP, 1);
    release(q);
    return rc;
}

long store_count_vm_steps(const store *s)
{
    if (s->pg) return 0;
    return s->count_vm_steps;
}

/* ---- families ---- */

static int insert_family(store *s, const char *name, const char *spec, const char *axes,
                         const store_new_member *members, long n, int64_t *family_id, int64_t *ids,
                         char *err, size_t errlen)
{
    sqlite3_stmt *fq = s->stmt[ST_FAMILY_INSERT], *mq = s->stmt[ST_MEMBER_INSERT];
    int rc = -1, in_tx = 0;
    double now = now_s();
    if (store_check_family(name, spec, axes, n, err, errlen) != 0) return -1;
    if (tx_step(s, ST_BEGIN) != SQLITE_OK) {
        db_err(s, err, errlen, "cannot store family '%s'", name);
        goto done;
    }
    in_tx = 1;
    if (sqlite3_bind_text(fq, 1, name, -1, SQLITE_STATIC) != SQLITE_OK ||
        sqlite3_bind_text(fq, 2, spec, -1, SQLITE_STATIC) != SQLITE_OK ||
        sqlite3_bind_text(fq, 3, axes, -1, SQLITE_STATIC) != SQLITE_OK ||
        sqlite3_bind_int64(fq, 4, n) != SQLITE_OK || sqlite3_bind_double(fq, 5, now) != SQLITE_OK ||
        sqlite3_step(fq) != SQLITE_DONE) {
        db_err(s, err, errlen, "cannot store family '%s'", name);
        goto done;
    }
    *family_id = sqlite3_last_insert_rowid(s->db);
    for (long i = 0; i < n; i++) {
        const store_new_member *m = &members[i];
        if (!m->name || !m->controller || !m->spec || !m->values || m->nbodies < 1 || m->nv < 0) {
            set_err(err, errlen, "cannot store member %ld of family '%s': a field is missing", i,
                    name);
            goto done;
        }
        if (sqlite3_bind_text(mq, 1, m->name, -1, SQLITE_STATIC) != SQLITE_OK ||
            (m->preset ? sqlite3_bind_text(mq, 2, m->preset, -1, SQLITE_STATIC)
                       : sqlite3_bind_null(mq, 2)) != SQLITE_OK ||
            sqlite3_bind_double(mq, 3, now) != SQLITE_OK ||
            sqlite3_bind_int(mq, 4, m->nbodies) != SQLITE_OK ||
            sqlite3_bind_int(mq, 5, m->nv) != SQLITE_OK ||
            sqlite3_bind_text(mq, 6, m->controller, -1, SQLITE_STATIC) != SQLITE_OK ||
            sqlite3_bind_text(mq, 7, m->spec, -1, SQLITE_STATIC) != SQLITE_OK ||
            sqlite3_bind_int64(mq, 8, *family_id) != SQLITE_OK ||
            sqlite3_bind_int64(mq, 9, m->index) != SQLITE_OK ||
            sqlite3_bind_int(mq, 10, m->replica) != SQLITE_OK ||
            sqlite3_bind_text(mq, 11, m->values, -1, SQLITE_STATIC) != SQLITE_OK ||
            sqlite3_step(mq) != SQLITE_DONE) {
            db_err(s, err, errlen, "cannot store member %ld of family '%s'", i, name);
            goto done;
        }
        ids[i] = sqlite3_last_insert_rowid(s->db);
        release(mq);
    }
    if (tx_step(s, ST_COMMIT) != SQLITE_OK) {
        db_err(s, err, errlen, "cannot store family '%s'", name);
        goto done;
    }
    in_tx = 0;
    rc = 0;
done:
    release(fq);
    release(mq);
    if (in_tx) tx_rollback(s);
    return rc;
}

int store_family_insert(store *s, const char *name, const char *spec, const char *axes,
                        const store_new_member *members, long n, int64_t *family_id, int64_t *ids,
                        char *err, size_t errlen)
{
    if (s->pg)
        return store_pg_family_insert(s->pg, name, spec, axes, members, n, family_id, ids, err,
                                      errlen);
    call_begin(s);
    return write_end(s, insert_family(s, name, spec, axes, members, n, family_id, ids, err, errlen),
                     1);
}

/* the status counts of family f->id into f->counts */
static int family_counts(store *s, store_family *f, char *err, size_t errlen)
{
    sqlite3_stmt *q = s->stmt[ST_FAMILY_COUNTS];
    int rc = -1, step;
    for (int i = 0; i < STORE_NSTATUS; i++) f->counts[i] = 0;
    sqlite3_bind_int64(q, 1, f->id);
    while ((step = sqlite3_step(q)) == SQLITE_ROW) {
        int st = store_status_parse((const char *)sqlite3_column_text(q, 0));
        if (st >= 0) f->counts[st] = (long)sqlite3_column_int64(q, 1);
    }
    if (step != SQLITE_DONE) {
        db_err(s, err, errlen, "counting the members of family %lld", (long long)f->id);
        goto done;
    }
    rc = 0;
done:
    release(q);
    return rc;
}

/* fills f from the current row of a FAMILY_COLUMNS query (the spec when with_spec) */
static int read_family(sqlite3_stmt *q, int with_spec, store_family *f, char *err, size_t errlen)
{
    memset(f, 0, sizeof *f);
    f->id = sqlite3_column_int64(q, 0);
    f->members = (long)sqlite3_column_int64(q, 4);
    f->created = sqlite3_column_double(q, 5);
    if (dup_column(q, 1, &f->name) || dup_column(q, 3, &f->axes) ||
        (with_spec && dup_column(q, 2, &f->spec))) {
        set_err(err, errlen, "family %lld: out of memory", (long long)f->id);
        store_family_clear(f);
        return -1;
    }
    return 0;
}

void store_family_clear(store_family *f)
{
    if (!f) return;
    free(f->name);
    free(f->spec);
    free(f->axes);
    memset(f, 0, sizeof *f);
}

int store_family_get(store *s, int64_t id, store_family *out, char *err, size_t errlen)
{
    if (s->pg) return store_pg_family_get(s->pg, id, out, err, errlen);
    call_begin(s);
    sqlite3_stmt *q = s->stmt[ST_FAMILY_GET];
    int rc = -1, in_tx = 0;
    memset(out, 0, sizeof *out);
    /* the row and its counts from one snapshot */
    if (tx_step(s, ST_BEGIN_READ) != SQLITE_OK) {
        db_err(s, err, errlen, "cannot read family %lld", (long long)id);
        goto done;
    }
    in_tx = 1;
    sqlite3_bind_int64(q, 1, id);
    int step = sqlite3_step(q);
    if (step == SQLITE_DONE) {
        rc = 1;
        goto done;
    }
    if (step != SQLITE_ROW) {
        db_err(s, err, errlen, "cannot read family %lld", (long long)id);
        goto done;
    }
    if (read_family(q, 1, out, err, errlen)) goto done;
    release(q);
    if (family_counts(s, out, err, errlen)) {
        store_family_clear(out);
        goto done;
    }
    rc = 0;
done:
    release(q);
    if (in_tx) tx_rollback(s);
    return rc;
}

/* step_rows's reader of a family row (FAMILY_COLUMNS, no spec); its counts come after */
static int family_row_read(sqlite3_stmt *q, void *elem, char *err, size_t errlen)
{
    return read_family(q, 0, elem, err, errlen);
}

static void family_rows_free(void *rows, long n)
{
    store_families_free(rows, (int)n);
}

static const row_reader family_list_rows = {sizeof(store_family), family_row_read,
                                            family_rows_free};

int store_family_list(store *s, int64_t before, int limit, store_family **rows, int *n, char *err,
                      size_t errlen)
{
    if (s->pg) return store_pg_family_list(s->pg, before, limit, rows, n, err, errlen);
    call_begin(s);
    sqlite3_stmt *q = s->stmt[ST_FAMILY_LIST];
    int rc = -1, in_tx = 0;
    void *list = NULL;
    long count = 0;
    *rows = NULL;
    *n = 0;
    if (store_check_limit(limit, err, errlen) != 0) goto done;
    /* the rows and their counts from one snapshot */
    if (tx_step(s, ST_BEGIN_READ) != SQLITE_OK) {
        db_err(s, err, errlen, "listing families");
        goto done;
    }
    in_tx = 1;
    sqlite3_bind_int64(q, 1, before > 0 ? before : INT64_MAX);
    sqlite3_bind_int(q, 2, limit);
    if (step_rows(s, q, &family_list_rows, &list, &count, "listing families", err, errlen) != 0)
        goto done;
    release(q);
    for (long i = 0; i < count; i++)
        if (family_counts(s, (store_family *)list + i, err, errlen)) goto done;
    *rows = list;
    *n = (int)count;
    list = NULL;
    rc = 0;
done:
    release(q);
    if (in_tx) tx_rollback(s);
    store_families_free(list, (int)count);
    return rc;
}

void store_families_free(store_family *rows, int n)
{
    for (int i = 0; rows && i < n; i++) store_family_clear(&rows[i]);
    free(rows);
}

/* step_rows's reader of a member: ST_FAMILY_MEMBERS's columns */
static int member_row_read(sqlite3_stmt *q, void *elem, char *err, size_t errlen)
{
    store_member *m = elem;
    m->job = sqlite3_column_int64(q, 0);
    m->index = (long)sqlite3_column_int64(q, 1);
    m->replica = sqlite3_column_int(q, 2);
    int st = store_status_parse((const char *)sqlite3_column_text(q, 3));
    m->status = st < 0 ? STORE_FAILED : (store_status)st;
    if (dup_column(q, 4, &m->values) || dup_column(q, 5, &m->metrics) ||
        dup_column(q, 6, &m->message)) {
        set_err(err, errlen, "job %lld: out of memory", (long long)m->job);
        return -1;
    }
    return 0;
}

static void member_rows_free(void *rows, long n)
{
    store_members_free(rows, n);
}

static const row_reader member_rows = {sizeof(store_member), member_row_read, member_rows_free};

/* step_rows's reader of an id (column 0) */
static int id_row_read(sqlite3_stmt *q, void *elem, char *err, size_t errlen)
{
    (void)err, (void)errlen;
    *(int64_t *)elem = sqlite3_column_int64(q, 0);
    return 0;
}

static void id_rows_free(void *rows, long n)
{
    (void)n;
    free(rows);
}

static const row_reader id_rows = {sizeof(int64_t), id_row_read, id_rows_free};

/* the rows of a family's statement (ST_FAMILY_MEMBERS, ST_FAMILY_ACTIVE) with ?1 = id */
static int family_rows(store *s, stmt_id which, const row_reader *rr, int64_t id, void **rows,
                       long *n, char *err, size_t errlen)
{
    sqlite3_stmt *q = s->stmt[which];
    char what[64];
    snprintf(what, sizeof what, "reading the members of family %lld", (long long)id);
    sqlite3_bind_int64(q, 1, id);
    int rc = step_rows(s, q, rr, rows, n, what, err, errlen);
    release(q);
    return rc;
}

int store_family_members(store *s, int64_t id, store_member **rows, long *n, char *err,
                         size_t errlen)
{
    if (s->pg) return store_pg_family_members(s->pg, id, rows, n, err, errlen);
    call_begin(s);
    void *list;
    int rc = family_rows(s, ST_FAMILY_MEMBERS, &member_rows, id, &list, n, err, errlen);
    *rows = list;
    return rc;
}

void store_members_free(store_member *rows, long n)
{
    for (long i = 0; rows && i < n; i++) {
        free(rows[i].values);
        free(rows[i].metrics);
        free(rows[i].message);
    }
    free(rows);
}

int store_family_active(store *s, int64_t id, int64_t **ids, long *n, char *err, size_t errlen)
{
    if (s->pg) return store_pg_family_active(s->pg, id, ids, n, err, errlen);
    call_begin(s);
    void *list;
    int rc = family_rows(s, ST_FAMILY_ACTIVE, &id_rows, id, &list, n, err, errlen);
    *ids = list;
    return rc;
}

static int delete_family(store *s, int64_t id, char *err, size_t errlen)
{
    sqlite3_stmt *get = s->stmt[ST_FAMILY_GET], *active = s->stmt[ST_FAMILY_ACTIVE];
    int rc = -1, in_tx = 0;
    if (tx_step(s, ST_BEGIN) != SQLITE_OK) {
        db_err(s, err, errlen, "cannot delete family %lld", (long long)id);
        goto done;
    }
    in_tx = 1;
    sqlite3_bind_int64(get, 1, id);
    int step = sqlite3_step(get);
    if (step == SQLITE_DONE) {
        rc = 1;
        goto done;
    }
    if (step != SQLITE_ROW) {
        db_err(s, err, errlen, "cannot delete family %lld", (long long)id);
        goto done;
    }
    sqlite3_bind_int64(active, 1, id);
    step = sqlite3_step(active);
    if (step == SQLITE_ROW) {
        rc = 2;
        goto done;
    }
    if (step != SQLITE_DONE) {
        db_err(s, err, errlen, "cannot delete family %lld", (long long)id);
        goto done;
    }
    release(get);
    release(active);
    /* the members first (their series follow by ON DELETE CASCADE), then the family */
    sqlite3_bind_int64(s->stmt[ST_FAMILY_DELETE_JOBS], 1, id);
    sqlite3_bind_int64(s->stmt[ST_FAMILY_DELETE], 1, id);
    if (tx_step(s, ST_FAMILY_DELETE_JOBS) != SQLITE_OK ||
        tx_step(s, ST_FAMILY_DELETE) != SQLITE_OK || tx_step(s, ST_COMMIT) != SQLITE_OK) {
        db_err(s, err, errlen, "cannot delete family %lld", (long long)id);
        goto done;
    }
    in_tx = 0;
    rc = 0;
done:
    release(get);
    release(active);
    sqlite3_clear_bindings(s->stmt[ST_FAMILY_DELETE_JOBS]);
    sqlite3_clear_bindings(s->stmt[ST_FAMILY_DELETE]);
    if (in_tx) tx_rollback(s);
    return rc;
}

int store_family_delete(store *s, int64_t id, char *err, size_t errlen)
{
    if (s->pg) return store_pg_family_delete(s->pg, id, err, errlen);
    call_begin(s);
    return write_end(s, delete_family(s, id, err, errlen), 1);
}

int store_job_families(store *s, const int64_t *ids, int n, int64_t *families, char *err,
                       size_t errlen)
{
    if (s->pg) return store_pg_job_families(s->pg, ids, n, families, err, errlen);
    call_begin(s);
    sqlite3_stmt *q = s->stmt[ST_FAMILY_OF];
    int rc = -1;
    if (tx_step(s, ST_BEGIN_READ) != SQLITE_OK) {
        db_err(s, err, errlen, "reading the jobs' families");
        return -1;
    }
    for (int i = 0; i < n; i++) {
        sqlite3_bind_int64(q, 1, ids[i]);
        int step = sqlite3_step(q);
        if (step != SQLITE_ROW && step != SQLITE_DONE) {
            db_err(s, err, errlen, "reading the family of job %lld", (long long)ids[i]);
            goto done;
        }
        families[i] = step == SQLITE_ROW && sqlite3_column_type(q, 0) != SQLITE_NULL
                          ? sqlite3_column_int64(q, 0)
                          : 0;
        release(q);
    }
    rc = 0;
done:
    release(q);
    tx_rollback(s);
    return rc;
}

static int cancel_family(store *s, int64_t id, const char *message, long *n, char *err,
                         size_t errlen)
{
    sqlite3_stmt *q = s->stmt[ST_FAMILY_CANCEL];
    int rc = -1;
    *n = 0;
    if (sqlite3_bind_int64(q, 1, id) != SQLITE_OK ||
        (message ? sqlite3_bind_text(q, 2, message, -1, SQLITE_STATIC) : sqlite3_bind_null(q, 2)) !=
            SQLITE_OK ||
        sqlite3_bind_double(q, 3, now_s()) != SQLITE_OK || sqlite3_step(q) != SQLITE_DONE) {
        db_err(s, err, errlen, "cannot cancel family %lld", (long long)id);
        goto done;
    }
    *n = (long)sqlite3_changes64(s->db);
    rc = 0;
done:
    release(q);
    return rc;
}

int store_family_cancel(store *s, int64_t id, const char *message, long *n, char *err,
                        size_t errlen)
{
    if (s->pg) return store_pg_family_cancel(s->pg, id, message, n, err, errlen);
    call_begin(s);
    return write_end(s, cancel_family(s, id, message, n, err, errlen), 0);
}
