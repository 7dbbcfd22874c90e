/*
 * store_pg.c - the PostgreSQL backend of store.h (store_pg.h): one libpq connection per store,
 * the schema migrated under an advisory lock, claims under a lease for worker processes.
 *
 * Statements. Every statement is sent with PQexecParams (parameters as text, never written into
 * SQL text; series blobs as binary parameters), so nothing is prepared per connection and a
 * reconnect (PQreset) needs only the session's settings again: lock_timeout and, on a
 * listening connection, LISTEN. Results are text, except the series', which come back binary
 * (the blob's bytes as they are, the integers cast to int4 in network order) so that a sample
 * is never printed and parsed. Reals go out as "%.17g" and come back in PostgreSQL's shortest
 * exact form (extra_float_digits 1, the default since version 12), so they round-trip; NaN is
 * stored as NULL as on SQLite. Times of rows are the writer's clock, as on SQLite; leases are
 * the database's clock (extract(epoch from clock_timestamp())), so that workers on machines whose
 * clocks differ agree on when a lease has expired.
 *
 * Transactions. A write of more than one statement runs inside BEGIN .. COMMIT at the default
 * isolation (read committed); the updates that move a job between statuses say which status
 * they need in their WHERE clause, so a concurrent change shows as zero rows changed, as on
 * SQLite. store_series_begin opens a REPEATABLE READ READ ONLY transaction (one snapshot) and
 * store_series_read reads one range of a row with substring() (the column's storage is
 * EXTERNAL, uncompressed, so PostgreSQL reads only the chunks of the range).
 *
 * Families (schema version 3) are SQLite's tables and contracts; a family's members go in with
 * one INSERT .. SELECT from json_to_recordset, so 10,000 members cost one round trip, and read
 * back in the order of their ids, each checked to be the member of its place. The claim serves
 * lanes in turn (store_pg.h, "Claims"): a skip scan of the partial index jobs_queued_lanes finds
 * each lane's oldest claimable jobs with one index probe per lane, and the lanes table says which
 * lane was served least recently, so a claim costs O(lanes log n), not a scan of the queue.
 *
 * Faults and health are store.c's (store_health_report_*), with the classification of
 * store_pg.h; a call on a connection libpq reports bad first tries PQreset once.
 *
 * Errors: the message of the failing step prefixed with what was being done and the job's id,
 * as on SQLite ("cannot finish job 3: no such job"); libpq's message with its line end trimmed.
 */
#define _GNU_SOURCE /* gethostname's HOST_NAME_MAX, endian.h */

#include "store_pg.h"
#include "store_common.h"

#include <endian.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <poll.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>
#include <unistd.h>

#include <cjson/cJSON.h>
#include <libpq-fe.h>

/* migrations[v] takes the schema from version v to v + 1, in one transaction */
static const char *const migrations[STORE_PG_SCHEMA_VERSION] = {
    /* 0 -> 1: jobs (with the claim's columns) and their series */
    "CREATE TABLE jobs ("
    "  id BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY,"
    "  name TEXT NOT NULL,"
    "  preset TEXT,"
    "  status TEXT NOT NULL DEFAULT 'queued' CHECK (status IN ('queued', 'running', 'done',"
    "    'failed', 'diverged', 'cancelled')),"
    "  progress DOUBLE PRECISION NOT NULL DEFAULT 0,"
    "  created DOUBLE PRECISION NOT NULL,"
    "  started DOUBLE PRECISION NOT NULL DEFAULT 0,"
    "  finished DOUBLE PRECISION NOT NULL DEFAULT 0,"
    "  nbodies INTEGER NOT NULL,"
    "  nv INTEGER NOT NULL,"
    "  controller TEXT NOT NULL,"
    "  spec TEXT NOT NULL,"
    "  metrics TEXT,"
    "  message TEXT,"
    "  e_max DOUBLE PRECISION,"
    "  wall_s DOUBLE PRECISION,"
    "  worker TEXT,"
    "  lease_until DOUBLE PRECISION,"
    "  cancel_requested BOOLEAN NOT NULL DEFAULT false);"
    "CREATE INDEX jobs_by_status ON jobs (status);"
    "CREATE INDEX jobs_active ON jobs (id) WHERE status IN ('queued', 'running');"
    "CREATE TABLE series ("
    "  job_id BIGINT NOT NULL REFERENCES jobs (id) ON DELETE CASCADE,"
    "  channel TEXT NOT NULL,"
    "  width INTEGER NOT NULL CHECK (width > 0),"
    "  nsamples INTEGER NOT NULL CHECK (nsamples >= 0),"
    "  data BYTEA NOT NULL,"
    "  PRIMARY KEY (job_id, channel));"
    "ALTER TABLE series ALTER COLUMN data SET STORAGE EXTERNAL;"
    "UPDATE schema_version SET version = 1;",
    /* 1 -> 2: the count of each status, kept by a trigger that also notifies listeners */
    "CREATE TABLE job_counts ("
    "  status TEXT PRIMARY KEY,"
    "  n BIGINT NOT NULL CHECK (n >= 0));"
    "INSERT INTO job_counts (status, n) VALUES ('queued', 0), ('running', 0), ('done', 0),"
    "  ('failed', 0), ('diverged', 0), ('cancelled', 0);"
    "UPDATE job_counts SET n = (SELECT count(*) FROM jobs WHERE jobs.status = job_counts.status);"
    "CREATE FUNCTION ctcsim_job_change() RETURNS trigger LANGUAGE plpgsql AS $$ BEGIN"
    "  IF TG_OP = 'INSERT' THEN"
    "    UPDATE job_counts SET n = n + 1 WHERE status = NEW.status;"
    "    PERFORM pg_notify('" STORE_PG_CHANNEL "', NEW.id || ' ' || NEW.status);"
    "  ELSIF TG_OP = 'DELETE' THEN"
    "    UPDATE job_counts SET n = n - 1 WHERE status = OLD.status;"
    "  ELSIF OLD.status <> NEW.status THEN"
    "    UPDATE job_counts SET n = n + CASE WHEN status = NEW.status THEN 1 ELSE -1 END"
    "      WHERE status IN (OLD.status, NEW.status);"
    "    PERFORM pg_notify('" STORE_PG_CHANNEL "', NEW.id || ' ' || NEW.status);"
    "  END IF;"
    "  RETURN NULL; END $$;"
    "CREATE TRIGGER job_change AFTER INSERT OR DELETE OR UPDATE OF status ON jobs"
    "  FOR EACH ROW EXECUTE FUNCTION ctcsim_job_change();"
    "UPDATE schema_version SET version = 2;",
    /* 2 -> 3: families of jobs (family.h), as SQLite's version 3; a member is an ordinary job
     * that names its family, its number in it, its replica and its axis values (jobs stored
     * before have none). lanes holds when each lane (0: the single jobs, else a family) last had
     * a job claimed, and jobs_queued_lanes finds each lane's oldest claimable job (the claim's
     * fair turns, store_pg.h) */
    "CREATE TABLE families ("
    "  id BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY,"
    "  name TEXT NOT NULL,"
    "  spec TEXT NOT NULL,"
    "  axes TEXT NOT NULL,"
    "  members BIGINT NOT NULL CHECK (members >= 0),"
    "  created DOUBLE PRECISION NOT NULL);"
    "ALTER TABLE jobs ADD COLUMN family_id BIGINT REFERENCES families (id);"
    "ALTER TABLE jobs ADD COLUMN family_member BIGINT;"
    "ALTER TABLE jobs ADD COLUMN family_replica INTEGER;"
    "ALTER TABLE jobs ADD COLUMN family_values TEXT;"
    "CREATE INDEX jobs_by_family ON jobs (family_id, family_member) WHERE family_id IS NOT NULL;"
    "CREATE INDEX jobs_queued_lanes ON jobs ((coalesce(family_id, 0)), id)"
    "  WHERE status = 'queued' AND NOT cancel_requested;"
    "CREATE TABLE lanes ("
    "  lane BIGINT PRIMARY KEY,"
    "  served DOUBLE PRECISION NOT NULL);"
    "UPDATE schema_version SET version = 3;",
    /* 3 -> 4: a family's status counts read this index alone (an index-only scan: 1.8 ms instead
     * of 11-30 ms for 10,000 members), as on SQLite */
    ("CREATE INDEX jobs_by_family_status ON jobs (family_id, status) WHERE family_id IS NOT NULL;"
     "UPDATE schema_version SET version = 4;"),
};

#define JOB_COLUMNS                                                                                \
    "id, name, preset, status, progress, created, started, finished, nbodies, nv, controller, "    \
    "message, e_max, wall_s, family_id, " SUMMARY_COLUMNS
/* the summaries a list shows, as SQLite's (store.c): metrics.e_final and metrics.e_rms as JSON
   text, reduced in C (store_summarise_errors), and the normalised job's tags */
#define SUMMARY_COLUMNS                                                                            \
    "(jobs.metrics::json -> 'e_final')::text, (jobs.metrics::json -> 'e_rms')::text, "             \
    "nullif((jobs.spec::json -> 'tags')::text, 'null')"
#define ACTIVE "status IN ('queued', 'running')"
/* a queued job no cancel stops; jobs_queued_lanes's condition, which the claim's index scans
 * must repeat to use it */
#define CLAIMABLE "status = 'queued' AND NOT cancel_requested"
/* the advisory locks' keys: the schema's migration, and the queue's bound (store_pg_insert) */
#define LOCK_SCHEMA "7237151624"
#define LOCK_QUEUE_BOUND "7237151625"
#define DB_NOW "extract(epoch from clock_timestamp())::float8"

struct store_pg {
    PGconn *conn;
    char *url;
    int busy_ms;
    int listening;        /* LISTEN again after a reconnect */
    store_fault fault;    /* of the current (or last) call */
    char fault_msg[256];  /* its message */
    int changed;          /* rows the current call changed */
    store_health *health; /* NULL = not attached */
    int reading;          /* inside store_series_begin .. end */
    char owner[160];      /* the current claim's token, "" = none */
    unsigned long claims; /* claims made, for the tokens */
};

/* ---- helpers ---- */

#define set_err store_set_err /* store_common.h */

static double now_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

int store_pg_url(const char *path)
{
    return path &&
           (strncmp(path, "postgres://", 11) == 0 || strncmp(path, "postgresql://", 13) == 0);
}

void store_pg_redact(const char *url, char *out, size_t outlen)
{
    /* postgres://user:password@host/...: the password is between the first ':' after the
       scheme and the '@' of the authority */
    const char *scheme = strstr(url, "://");
    const char *at = scheme ? strchr(scheme + 3, '@') : NULL;
    const char *slash = scheme ? strchr(scheme + 3, '/') : NULL;
    const char *colon = scheme ? strchr(scheme + 3, ':') : NULL;
    if (at && (!slash || at < slash) && colon && colon < at)
        snprintf(out, outlen, "%.*s:***%s", (int)(colon - url), url, at);
    else
        snprintf(out, outlen, "%s", url);
}

/* libpq's message without its line end */
static const char *pg_message(const PGconn *c, const PGresult *r, char *buf, size_t len)
{
    const char *m = r ? PQresultErrorMessage(r) : NULL;
    if (!m || !*m) m = PQerrorMessage(c);
    if (!m || !*m) m = "unknown error";
    snprintf(buf, len, "%s", m);
    size_t n = strlen(buf);
    while (n > 0 && (buf[n - 1] == '\n' || buf[n - 1] == ' ')) buf[--n] = '\0';
    return buf;
}

/* the fault of a failed result (r may be NULL: no result at all) */
static store_fault fault_of(PGconn *c, const PGresult *r)
{
    if (PQstatus(c) == CONNECTION_BAD) return STORE_FAULT_IO;
    const char *st = r ? PQresultErrorField(r, PG_DIAG_SQLSTATE) : NULL;
    if (!st) return r ? STORE_FAULT_OTHER : STORE_FAULT_IO;
    if (strncmp(st, "08", 2) == 0 || strcmp(st, "57P01") == 0 || strcmp(st, "57P02") == 0 ||
        strcmp(st, "57P03") == 0 || strcmp(st, "58030") == 0)
        return STORE_FAULT_IO;
    if (strcmp(st, "40001") == 0 || strcmp(st, "40P01") == 0 || strcmp(st, "55P03") == 0 ||
        strcmp(st, "53300") == 0)
        return STORE_FAULT_LOCKED;
    if (strcmp(st, "53100") == 0) return STORE_FAULT_FULL;
    if (strcmp(st, "25006") == 0) return STORE_FAULT_READONLY;
    return STORE_FAULT_OTHER;
}

/* "WHAT: postgres's message"; records the call's fault (the first one of the call) */
static void db_err(store_pg *p, const PGresult *r, char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 5, 6)));

static void db_err(store_pg *p, const PGresult *r, char *err, size_t errlen, const char *fmt, ...)
{
    char what[256], msg[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    pg_message(p->conn, r, msg, sizeof msg);
    if (p->fault == STORE_FAULT_NONE) {
        p->fault = fault_of(p->conn, r);
        set_err(p->fault_msg, sizeof p->fault_msg, "%s: %s", what, msg);
    }
    set_err(err, errlen, "%s: %s", what, msg);
}

/* the session's settings, after a connect or reconnect; 0 or -1 */
static int session_setup(store_pg *p)
{
    char sql[160];
    snprintf(sql, sizeof sql, "SET lock_timeout = %d; SET client_min_messages = warning%s",
             STORE_PG_LOCK_MS, p->listening ? "; LISTEN " STORE_PG_CHANNEL : "");
    PGresult *r = PQexec(p->conn, sql);
    int ok = PQresultStatus(r) == PGRES_COMMAND_OK;
    PQclear(r);
    return ok ? 0 : -1;
}

/* the start of a public call: no fault yet, nothing changed; a lost connection is reset once
 * (a failed reset leaves the connection bad, and the call's first statement reports it) */
static void call_begin(store_pg *p)
{
    p->fault = STORE_FAULT_NONE;
    p->fault_msg[0] = '\0';
    p->changed = 0;
    /* an idle connection the server has ended (a restart, pg_terminate_backend) has its FATAL
       message and end of file waiting on the socket: reading them (without blocking) marks it
       bad, so the call reconnects instead of failing on it */
    for (int i = 0; i < 2 && PQstatus(p->conn) == CONNECTION_OK &&
                    PQtransactionStatus(p->conn) == PQTRANS_IDLE;
         i++)
        if (!PQconsumeInput(p->conn)) break; /* the message, then the end of file */
    if (PQstatus(p->conn) == CONNECTION_BAD) {
        PQreset(p->conn);
        p->reading = 0;
        if (PQstatus(p->conn) == CONNECTION_OK) session_setup(p);
    }
}

/* the end of a public write: its outcome told to health (store.c's rules) */
static int write_end(store_pg *p, int rc, int room)
{
    if (!p->health) return rc;
    if (store_fault_transient(p->fault) && !(p->fault == STORE_FAULT_LOCKED && p->busy_ms == 0))
        store_health_report_fault(p->health, p->fault, p->fault_msg);
    else if (p->fault == STORE_FAULT_NONE && p->changed > 0)
        store_health_report_ok(p->health, room);
    return rc;
}

/* Runs sql with n text parameters (NULL = SQL NULL); binary asks for binary results. Returns the
 * result when its status is PGRES_COMMAND_OK or PGRES_TUPLES_OK (rows changed added to
 * p->changed), else NULL after db_err with what. */
static PGresult *run(store_pg *p, const char *sql, int n, const char *const *vals, int binary,
                     char *err, size_t errlen, const char *what)
{
    /* PQexec takes several statements (the schema's), PQexecParams one */
    PGresult *r = n == 0 && !binary ? PQexec(p->conn, sql)
                                    : PQexecParams(p->conn, sql, n, NULL, vals, NULL, NULL, binary);
    ExecStatusType st = PQresultStatus(r);
    if (st != PGRES_COMMAND_OK && st != PGRES_TUPLES_OK) {
        db_err(p, r, err, errlen, "%s", what);
        PQclear(r);
        return NULL;
    }
    const char *rows = PQcmdTuples(r);
    if (rows && *rows && strncmp(sql, "SELECT", 6) != 0) p->changed += atoi(rows);
    return r;
}

/* a statement without parameters or rows (BEGIN, COMMIT, ROLLBACK); 0 or -1 */
static int run_simple(store_pg *p, const char *sql, char *err, size_t errlen, const char *what)
{
    PGresult *r = run(p, sql, 0, NULL, 0, err, errlen, what);
    PQclear(r);
    return r ? 0 : -1;
}

static void rollback(store_pg *p)
{
    if (PQtransactionStatus(p->conn) != PQTRANS_IDLE) PQclear(PQexec(p->conn, "ROLLBACK"));
}

/* rows changed by a result */
static int changes(const PGresult *r)
{
    const char *rows = PQcmdTuples((PGresult *)r);
    return rows && *rows ? atoi(rows) : 0;
}

static void fmt_i64(char *buf, size_t len, int64_t x)
{
    snprintf(buf, len, "%lld", (long long)x);
}

/* a real as text, NULL for NaN (SQL NULL) */
static const char *fmt_real(char *buf, size_t len, double x)
{
    if (isnan(x)) return NULL;
    if (isinf(x)) {
        snprintf(buf, len, "%s", x > 0 ? "Infinity" : "-Infinity");
        return buf;
    }
    snprintf(buf, len, "%.17g", x);
    return buf;
}

static double real_col(const PGresult *r, int row, int col)
{
    if (PQgetisnull(r, row, col)) return NAN;
    return strtod(PQgetvalue(r, row, col), NULL);
}

static int dup_col(const PGresult *r, int row, int col, char **out)
{
    *out = NULL;
    if (PQgetisnull(r, row, col)) return 0;
    *out = strdup(PQgetvalue(r, row, col));
    return *out ? 0 : -1;
}

/* big-endian binary columns of the series queries */
static int32_t be_i32(const PGresult *r, int row, int col)
{
    uint32_t v;
    memcpy(&v, PQgetvalue(r, row, col), 4);
    return (int32_t)be32toh(v);
}

static int read_job(const PGresult *r, int row, int with_spec, store_job *j, char *err,
                    size_t errlen)
{
    memset(j, 0, sizeof *j);
    j->id = strtoll(PQgetvalue(r, row, 0), NULL, 10);
    int status = store_status_parse(PQgetvalue(r, row, 3));
    if (status < 0) {
        set_err(err, errlen, "job %lld has an unknown status '%s'", (long long)j->id,
                PQgetvalue(r, row, 3));
        return -1;
    }
    j->status = (store_status)status;
    j->progress = real_col(r, row, 4);
    j->created = real_col(r, row, 5);
    j->started = real_col(r, row, 6);
    j->finished = real_col(r, row, 7);
    j->nbodies = atoi(PQgetvalue(r, row, 8));
    j->nv = atoi(PQgetvalue(r, row, 9));
    j->e_max = real_col(r, row, 12);
    j->wall_s = real_col(r, row, 13);
    j->family = PQgetisnull(r, row, 14) ? 0 : strtoll(PQgetvalue(r, row, 14), NULL, 10);
    store_summarise_errors(PQgetisnull(r, row, 15) ? NULL : PQgetvalue(r, row, 15),
                           PQgetisnull(r, row, 16) ? NULL : PQgetvalue(r, row, 16), &j->e_final,
                           &j->e_rms);
    if (dup_col(r, row, 1, &j->name) || dup_col(r, row, 2, &j->preset) ||
        dup_col(r, row, 10, &j->controller) || dup_col(r, row, 11, &j->message) ||
        dup_col(r, row, 17, &j->tags) ||
        (with_spec && (dup_col(r, row, 18, &j->spec) || dup_col(r, row, 19, &j->metrics)))) {
        set_err(err, errlen, "job %lld: out of memory", (long long)j->id);
        store_job_clear(j);
        return -1;
    }
    return 0;
}

/* a job's status: 1 when there is no such job, 0 with *st, -1 on error */
static int status_of(store_pg *p, int64_t id, store_status *st, char *err, size_t errlen)
{
    char ids[24];
    fmt_i64(ids, sizeof ids, id);
    const char *v[] = {ids};
    char what[64];
    snprintf(what, sizeof what, "job %lld: reading its status", (long long)id);
    PGresult *r = run(p, "SELECT status FROM jobs WHERE id = $1", 1, v, 0, err, errlen, what);
    if (!r) return -1;
    int rc = 1;
    if (PQntuples(r) == 1) {
        int parsed = store_status_parse(PQgetvalue(r, 0, 0));
        if (parsed < 0) {
            set_err(err, errlen, "job %lld has an unknown status '%s'", (long long)id,
                    PQgetvalue(r, 0, 0));
            rc = -1;
        } else {
            *st = (store_status)parsed;
            rc = 0;
        }
    }
    PQclear(r);
    return rc;
}

/* the reason an update that needs a running job changed nothing (store_not_running_err) */
static void not_running_err(store_pg *p, int64_t id, const char *what, char *err, size_t errlen)
{
    store_status st = STORE_QUEUED;
    int found = status_of(p, id, &st, err, errlen);
    store_not_running_err(id, what, found, st, err, errlen);
}

/* ---- opening ---- */

/* brings the schema to STORE_PG_SCHEMA_VERSION, or refuses a database that is not ctcsim's */
static int migrate(store_pg *p, const char *shown, char *err, size_t errlen)
{
    int rc = -1, version = 0;
    PGresult *r = NULL;
    if (run_simple(p, "BEGIN", err, errlen, "cannot open the database") != 0) goto done;
    /* one migration at a time across every process that opens the database */
    r = run(p, "SELECT pg_advisory_xact_lock(" LOCK_SCHEMA ")", 0, NULL, 0, err, errlen,
            "locking the schema");
    if (!r) goto done;
    PQclear(r);
    r = run(p,
            "SELECT to_regclass('schema_version') IS NOT NULL, (SELECT count(*) FROM pg_tables "
            "WHERE schemaname = current_schema())",
            0, NULL, 0, err, errlen, "reading the schema");
    if (!r) goto done;
    int have_version = PQgetvalue(r, 0, 0)[0] == 't';
    long tables = atol(PQgetvalue(r, 0, 1));
    PQclear(r);
    r = NULL;
    if (!have_version && tables > 0) {
        set_err(err, errlen,
                "database %s is not a ctcsim database (it has tables but no schema_version)",
                shown);
        goto done;
    }
    if (!have_version && run_simple(p,
                                    "CREATE TABLE schema_version (version INTEGER NOT NULL);"
                                    "INSERT INTO schema_version VALUES (0)",
                                    err, errlen, "creating the schema") != 0)
        goto done;
    r = run(p, "SELECT version FROM schema_version", 0, NULL, 0, err, errlen,
            "reading the schema version");
    if (!r) goto done;
    if (PQntuples(r) != 1) {
        set_err(err, errlen, "database %s is not a ctcsim database (schema_version has %d rows)",
                shown, PQntuples(r));
        goto done;
    }
    version = atoi(PQgetvalue(r, 0, 0));
    PQclear(r);
    r = NULL;
    if (version > STORE_PG_SCHEMA_VERSION || version < 0) {
        set_err(err, errlen,
                "database %s has schema version %d, newer than this ctcsim (%d): upgrade ctcsim",
                shown, version, STORE_PG_SCHEMA_VERSION);
        goto done;
    }
    for (int v = version; v < STORE_PG_SCHEMA_VERSION; v++) {
        PGresult *m = PQexec(p->conn, migrations[v]);
        if (PQresultStatus(m) != PGRES_COMMAND_OK) {
            char what[640];
            snprintf(what, sizeof what, "database %s: migrating the schema from version %d to %d",
                     shown, v, v + 1);
            db_err(p, m, err, errlen, "%s", what);
            PQclear(m);
            goto done;
        }
        PQclear(m);
    }
    if (run_simple(p, "COMMIT", err, errlen, "committing the schema") != 0) goto done;
    rc = 0;
done:
    PQclear(r);
    if (rc) rollback(p);
    return rc;
}

int store_pg_open(const char *url, store_pg **out, char *err, size_t errlen)
{
    char shown[512];
    store_pg_redact(url, shown, sizeof shown);
    *out = NULL;
    store_pg *p = calloc(1, sizeof *p);
    if (!p || !(p->url = strdup(url))) {
        free(p);
        set_err(err, errlen, "cannot open database %s: out of memory", shown);
        return -1;
    }
    const char *keys[] = {"dbname", "connect_timeout", "application_name", NULL};
    const char *vals[] = {url, "5", "ctcsim", NULL};
    p->conn = PQconnectdbParams(keys, vals, 1);
    p->busy_ms = STORE_PG_LOCK_MS;
    if (!p->conn || PQstatus(p->conn) != CONNECTION_OK) {
        char msg[512];
        set_err(err, errlen, "cannot open database %s: %s", shown,
                p->conn ? pg_message(p->conn, NULL, msg, sizeof msg) : "out of memory");
        store_pg_close(p);
        return -1;
    }
    if (session_setup(p) != 0 || migrate(p, shown, err, errlen) != 0) {
        if (err && !*err) set_err(err, errlen, "cannot open database %s", shown);
        store_pg_close(p);
        return -1;
    }
    *out = p;
    return 0;
}

void store_pg_close(store_pg *p)
{
    if (!p) return;
    PQfinish(p->conn);
    free(p->url);
    free(p);
}

void store_pg_set_busy_timeout(store_pg *p, int ms)
{
    p->busy_ms = ms > 0 ? ms : 0;
}

int store_pg_set_max_size(store_pg *p, long long max_bytes, char *err, size_t errlen)
{
    p->fault = STORE_FAULT_NONE;
    if (max_bytes == 0) return 0;
    set_err(err, errlen,
            "a size limit (--db-max-size) applies to SQLite only: PostgreSQL's size is the "
            "database server's to limit");
    return -1;
}

store_fault store_pg_last_fault(const store_pg *p)
{
    return p->fault;
}

void store_pg_attach(store_pg *p, store_health *h)
{
    p->health = h;
}

int store_pg_probe(store_pg *p, char *err, size_t errlen)
{
    call_begin(p);
    /* a write that changes nothing a reader sees; on PostgreSQL it needs room in the log, so
       its success also says the disk has room again */
    PGresult *r = run(p, "UPDATE job_counts SET n = n WHERE status = 'queued'", 0, NULL, 0, err,
                      errlen, "probing the database");
    PQclear(r);
    return write_end(p, r ? 0 : -1, 1);
}

int store_pg_reserve(store_pg *p, long long bytes, char *err, size_t errlen)
{
    (void)bytes;
    p->fault = STORE_FAULT_NONE;
    set_err(err, errlen, "reserving room for the log: PostgreSQL keeps its own write-ahead log");
    return -1;
}

/* ---- jobs ---- */

int store_pg_insert(store_pg *p, long max_queued, const char *name, const char *preset, int nbodies,
                    int nv, const char *controller, const char *spec, int64_t *id, char *err,
                    size_t errlen)
{
    call_begin(p);
    if (store_check_job(name, controller, spec, nbodies, nv, err, errlen) != 0) return -1;
    int rc = -1;
    PGresult *r = NULL;
    char created[40], nb[16], nvs[16], what[300];
    fmt_real(created, sizeof created, now_s());
    snprintf(nb, sizeof nb, "%d", nbodies);
    snprintf(nvs, sizeof nvs, "%d", nv);
    snprintf(what, sizeof what, "cannot store job '%.200s'", name);
    if (max_queued > 0) {
        /* the bound's check and the insert in one transaction, one at a time across every
           process: the lock is taken before the count's statement, whose snapshot then sees
           every insert committed under the lock before it */
        if (run_simple(p, "BEGIN", err, errlen, what) != 0) goto done;
        r = run(p, "SELECT pg_advisory_xact_lock(" LOCK_QUEUE_BOUND ")", 0, NULL, 0, err, errlen,
                what);
        if (!r) goto done;
        PQclear(r);
        r = run(p, "SELECT count(*) FROM jobs WHERE " CLAIMABLE " AND coalesce(family_id, 0) = 0",
                0, NULL, 0, err, errlen, what);
        if (!r) goto done;
        long queued = atol(PQgetvalue(r, 0, 0));
        PQclear(r);
        r = NULL;
        if (queued >= max_queued) {
            rc = 2;
            goto done;
        }
    }
    const char *v[] = {name, preset, created, nb, nvs, controller, spec};
    r = run(p,
            "INSERT INTO jobs (name, preset, status, progress, created, nbodies, nv, controller, "
            "spec) VALUES ($1, $2, 'queued', 0, $3, $4, $5, $6, $7) RETURNING id",
            7, v, 0, err, errlen, what);
    if (!r) goto done;
    *id = strtoll(PQgetvalue(r, 0, 0), NULL, 10);
    if (max_queued > 0 && run_simple(p, "COMMIT", err, errlen, what) != 0) goto done;
    rc = 0;
done:
    PQclear(r);
    rollback(p);
    return write_end(p, rc, 1);
}

int store_pg_recover(store_pg *p, int64_t **ids, int *n, char *err, size_t errlen)
{
    call_begin(p);
    int rc = -1;
    PGresult *r = NULL;
    *ids = NULL;
    *n = 0;
    if (run_simple(p, "BEGIN", err, errlen, "recovering jobs") != 0) goto done;
    /* a running job whose lease has expired restarts from t = 0 */
    r = run(p,
            "UPDATE jobs SET status = 'queued', progress = 0, started = 0, worker = NULL, "
            "lease_until = NULL WHERE status = 'running' AND (lease_until IS NULL OR "
            "lease_until < " DB_NOW ")",
            0, NULL, 0, err, errlen, "recovering jobs");
    if (!r) goto done;
    PQclear(r);
    /* a queued job whose cancel was asked for and not recorded (its API process died) */
    char fin[40];
    const char *fv[] = {fmt_real(fin, sizeof fin, now_s())};
    r = run(p,
            "UPDATE jobs SET status = 'cancelled', message = 'cancelled by request', finished = "
            "$1 WHERE status = 'queued' AND cancel_requested",
            1, fv, 0, err, errlen, "recovering jobs");
    if (!r) goto done;
    PQclear(r);
    r = run(p, "SELECT id FROM jobs WHERE status = 'queued' ORDER BY id", 0, NULL, 0, err, errlen,
            "recovering jobs");
    if (!r) goto done;
    int count = PQntuples(r);
    int64_t *list = malloc((size_t)(count > 0 ? count : 1) * sizeof *list);
    if (!list) {
        set_err(err, errlen, "recovering jobs: out of memory");
        goto done;
    }
    for (int i = 0; i < count; i++) list[i] = strtoll(PQgetvalue(r, i, 0), NULL, 10);
    if (run_simple(p, "COMMIT", err, errlen, "recovering jobs") != 0) {
        free(list);
        goto done;
    }
    *ids = list;
    *n = count;
    rc = 0;
done:
    PQclear(r);
    if (rc) rollback(p);
    return write_end(p, rc, 0);
}

int store_pg_start(store_pg *p, int64_t id, char *err, size_t errlen)
{
    call_begin(p);
    char ids[24], started[40], what[64];
    fmt_i64(ids, sizeof ids, id);
    fmt_real(started, sizeof started, now_s());
    snprintf(what, sizeof what, "cannot start job %lld", (long long)id);
    const char *v[] = {ids, started, p->owner[0] ? p->owner : NULL};
    PGresult *r = run(p,
                      "UPDATE jobs SET status = 'running', started = $2, progress = 0, worker = "
                      "$3 WHERE id = $1 AND status = 'queued'",
                      3, v, 0, err, errlen, what);
    int rc = r ? (changes(r) == 1 ? 0 : 1) : -1;
    PQclear(r);
    return write_end(p, rc, 0);
}

/* the condition that a running job is this connection's: its claim's token, or no claim at all
 * on either side (a job started with store_start by a connection that never claimed) */
#define HELD "worker IS NOT DISTINCT FROM $3"

int store_pg_progress(store_pg *p, int64_t id, double progress, char *err, size_t errlen)
{
    call_begin(p);
    int rc = -1;
    if (isnan(progress)) {
        set_err(err, errlen, "job %lld: progress is NaN", (long long)id);
        return write_end(p, -1, 0);
    }
    char ids[24], pr[40], what[64];
    fmt_i64(ids, sizeof ids, id);
    fmt_real(pr, sizeof pr, fmin(fmax(progress, 0.0), 1.0));
    snprintf(what, sizeof what, "job %lld: cannot record progress", (long long)id);
    const char *v[] = {ids, pr, p->owner[0] ? p->owner : NULL};
    PGresult *r =
        run(p, "UPDATE jobs SET progress = $2 WHERE id = $1 AND status = 'running' AND " HELD, 3, v,
            0, err, errlen, what);
    if (r && changes(r) == 1)
        rc = 0;
    else if (r)
        not_running_err(p, id, "record progress of", err, errlen);
    PQclear(r);
    return write_end(p, rc, 0);
}

int store_pg_requeue(store_pg *p, int64_t id, char *err, size_t errlen)
{
    call_begin(p);
    int rc = -1;
    char ids[24], what[64];
    fmt_i64(ids, sizeof ids, id);
    snprintf(what, sizeof what, "cannot requeue job %lld", (long long)id);
    const char *v[] = {ids, p->owner[0] ? p->owner : NULL};
    PGresult *r = run(p,
                      "UPDATE jobs SET status = 'queued', progress = 0, started = 0, worker = "
                      "NULL, lease_until = NULL WHERE id = $1 AND status = 'running' AND worker "
                      "IS NOT DISTINCT FROM $2",
                      2, v, 0, err, errlen, what);
    if (r && changes(r) == 1)
        rc = 0, p->owner[0] = '\0';
    else if (r)
        not_running_err(p, id, "requeue", err, errlen);
    PQclear(r);
    return write_end(p, rc, 0);
}

static double result_e_max(const ctc_sim_result *r)
{
    double m = NAN;
    if (!r || !r->metrics.e_max) return m;
    for (int i = 0; i < r->metrics.nv; i++)
        if (!isnan(r->metrics.e_max[i]) && (isnan(m) || r->metrics.e_max[i] > m))
            m = r->metrics.e_max[i];
    return m;
}

/* one series row; data holds nsamples x width doubles, sent as a binary parameter */
static int put_series(store_pg *p, int64_t id, const char *channel, int width, int nsamples,
                      const double *data, char *err, size_t errlen)
{
    char ids[24], ws[16], ns[16], what[96];
    fmt_i64(ids, sizeof ids, id);
    snprintf(ws, sizeof ws, "%d", width);
    snprintf(ns, sizeof ns, "%d", nsamples);
    snprintf(what, sizeof what, "job %lld: storing series %s", (long long)id, channel);
    size_t bytes = (size_t)nsamples * (size_t)width * sizeof(double);
    if (bytes > INT_MAX) {
        set_err(err, errlen, "%s: %zu bytes, more than PostgreSQL takes in one value", what, bytes);
        return -1;
    }
    const char *v[] = {ids, channel, ws, ns, data ? (const char *)data : ""};
    int lens[] = {0, 0, 0, 0, (int)bytes};
    int fmts[] = {0, 0, 0, 0, 1};
    PGresult *r = PQexecParams(p->conn,
                               "INSERT INTO series (job_id, channel, width, nsamples, data) "
                               "VALUES ($1, $2, $3, $4, $5)",
                               5, NULL, v, lens, fmts, 0);
    if (PQresultStatus(r) != PGRES_COMMAND_OK) {
        db_err(p, r, err, errlen, "%s", what);
        PQclear(r);
        return -1;
    }
    p->changed++;
    PQclear(r);
    return 0;
}

int store_pg_finish(store_pg *p, int64_t id, store_status status, const char *message,
                    const char *metrics, const ctc_sim_result *r, char *err, size_t errlen)
{
    call_begin(p);
    int rc = -1;
    PGresult *q = NULL;
    char what[64];
    snprintf(what, sizeof what, "cannot finish job %lld", (long long)id);
    if (store_check_finish(id, status, r, err, errlen) != 0) goto done;
    if (run_simple(p, "BEGIN", err, errlen, what) != 0) goto done;
    char ids[24], emax[40], wall[40], fin[40];
    fmt_i64(ids, sizeof ids, id);
    fmt_real(fin, sizeof fin, now_s());
    const char *v[] = {ids,
                       store_status_name(status),
                       message && *message ? message : NULL,
                       metrics,
                       fmt_real(emax, sizeof emax, result_e_max(r)),
                       fmt_real(wall, sizeof wall, r ? r->metrics.wall_s : NAN),
                       fin,
                       p->owner[0] ? p->owner : NULL};
    /* a queued job, or a running one that this connection's claim holds */
    q = run(p,
            "UPDATE jobs SET status = $2, message = $3, metrics = $4, e_max = $5, wall_s = $6, "
            "finished = $7, progress = CASE WHEN $2 = 'done' THEN 1 ELSE progress END, "
            "lease_until = NULL WHERE id = $1 AND (status = 'queued' OR (status = 'running' AND "
            "worker IS NOT DISTINCT FROM $8))",
            8, v, 0, err, errlen, what);
    if (!q) goto done;
    if (changes(q) != 1) {
        store_status st = STORE_QUEUED;
        int found = status_of(p, id, &st, err, errlen);
        store_not_finishable_err(id, found, st, err, errlen);
        goto done;
    }
    PQclear(q);
    const char *dv[] = {ids};
    char dwhat[64];
    snprintf(dwhat, sizeof dwhat, "job %lld: clearing its series", (long long)id);
    q = run(p, "DELETE FROM series WHERE job_id = $1", 1, dv, 0, err, errlen, dwhat);
    if (!q) goto done;
    if (r) {
        if (put_series(p, id, "t", 1, r->nsamples, r->t, err, errlen)) goto done;
        for (int c = 0; c < CTC_NCHANNELS; c++) {
            if (!r->ch[c] || r->width[c] <= 0) continue;
            if (put_series(p, id, ctc_channel_name((ctc_channel)c), r->width[c], r->nsamples,
                           r->ch[c], err, errlen))
                goto done;
        }
    }
    if (run_simple(p, "COMMIT", err, errlen, what) != 0) goto done;
    if (p->owner[0]) p->owner[0] = '\0'; /* the claim ends with its result */
    rc = 0;
done:
    PQclear(q);
    if (rc) rollback(p);
    return write_end(p, rc, r != NULL);
}

int store_pg_get(store_pg *p, int64_t id, store_job *out, char *err, size_t errlen)
{
    call_begin(p);
    memset(out, 0, sizeof *out);
    char ids[24], what[48];
    fmt_i64(ids, sizeof ids, id);
    snprintf(what, sizeof what, "cannot read job %lld", (long long)id);
    const char *v[] = {ids};
    PGresult *r = run(p, "SELECT " JOB_COLUMNS ", spec, metrics FROM jobs WHERE id = $1", 1, v, 0,
                      err, errlen, what);
    if (!r) return -1;
    int rc = PQntuples(r) == 0 ? 1 : read_job(r, 0, 1, out, err, errlen);
    PQclear(r);
    return rc;
}

/* How pg_rows reads a result: each element's size, the reader of row k (0, or -1 with err), and
 * the free of n elements read (a half-filled one included). */
typedef struct pg_row_reader {
    size_t size;
    int (*read)(const PGresult *r, int k, void *elem, char *err, size_t errlen);
    void (*free_rows)(void *rows, long n);
} pg_row_reader;

/* Reads every row of r (NULL: a failed query, err says why) with rr->read into zeroed elements of
 * a new array, then clears r: 0 with *rows (free with rr->free_rows) and *n, or -1 with err
 * ("WHAT: out of memory", or the reader's message) and nothing handed out. */
static int pg_rows(PGresult *r, const pg_row_reader *rr, void **rows, long *n, const char *what,
                   char *err, size_t errlen)
{
    *rows = NULL;
    *n = 0;
    if (!r) return -1;
    int count = PQntuples(r), got = 0, rc = -1;
    char *list = calloc((size_t)(count > 0 ? count : 1), rr->size);
    if (!list) {
        set_err(err, errlen, "%s: out of memory", what);
        goto done;
    }
    while (got < count) {
        got++;
        if (rr->read(r, got - 1, list + (size_t)(got - 1) * rr->size, err, errlen) != 0) goto done;
    }
    *rows = list;
    *n = count;
    list = NULL;
    rc = 0;
done:
    PQclear(r);
    if (list) rr->free_rows(list, got);
    return rc;
}

static int job_row_read(const PGresult *r, int k, void *elem, char *err, size_t errlen)
{
    return read_job(r, k, 0, elem, err, errlen);
}

static void job_rows_free(void *rows, long n)
{
    store_jobs_free(rows, (int)n);
}

static const pg_row_reader job_rows = {sizeof(store_job), job_row_read, job_rows_free};

/* the jobs of a list's result (NULL: the query failed) into *rows and *n; 0 or -1 */
static int job_list(PGresult *r, store_job **rows, int *n, char *err, size_t errlen)
{
    void *list;
    long count;
    int rc = pg_rows(r, &job_rows, &list, &count, "listing jobs", err, errlen);
    *rows = list;
    *n = (int)count;
    return rc;
}

int store_pg_list(store_pg *p, int64_t before, int status, int limit, store_job **rows, int *n,
                  char *err, size_t errlen)
{
    call_begin(p);
    *rows = NULL;
    *n = 0;
    if (store_check_list(before, status, limit, err, errlen) != 0) return -1;
    char bs[24], ls[16];
    fmt_i64(bs, sizeof bs, before > 0 ? before : INT64_MAX);
    snprintf(ls, sizeof ls, "%d", limit);
    const char *v[] = {bs, ls, status >= 0 ? store_status_name((store_status)status) : NULL};
    PGresult *r = run(p,
                      status >= 0 ? "SELECT " JOB_COLUMNS " FROM jobs WHERE status = $3 AND id < "
                                    "$1 ORDER BY id DESC LIMIT $2"
                                  : "SELECT " JOB_COLUMNS " FROM jobs WHERE id < $1 ORDER BY id "
                                    "DESC LIMIT $2",
                      status >= 0 ? 3 : 2, v, 0, err, errlen, "listing jobs");
    return job_list(r, rows, n, err, errlen);
}

/* translate(x, AZ) folds x's ASCII letters to lowercase, as SQLite's lower() does, which
 * store_search's contract follows (PostgreSQL's lower() folds by the database's locale) */
#define AZ "'ABCDEFGHIJKLMNOPQRSTUVWXYZ', 'abcdefghijklmnopqrstuvwxyz'"
/* the elements of the normalised job's tags, as text (none when it has no array of them) */
#define TAGS                                                                                       \
    "json_array_elements_text(CASE WHEN json_typeof(jobs.spec::json -> 'tags') = 'array' THEN "    \
    "jobs.spec::json -> 'tags' END) AS tag"
/* a search: $4 a lowercase text in the name, preset, controller or a tag; $5 a tag */
#define SEARCH_WHERE                                                                               \
    "($4::text IS NULL OR strpos(translate(name, " AZ "), $4) > 0 OR "                             \
    "strpos(translate(coalesce(preset, ''), " AZ "), $4) > 0 OR "                                  \
    "strpos(translate(controller, " AZ "), $4) > 0 OR "                                            \
    "EXISTS (SELECT 1 FROM " TAGS " WHERE strpos(translate(tag, " AZ "), $4) > 0)) AND "           \
    "($5::text IS NULL OR EXISTS (SELECT 1 FROM " TAGS " WHERE tag = $5))"

int store_pg_search(store_pg *p, int64_t before, const store_filter *f, int limit, store_job **rows,
                    int *n, char *err, size_t errlen)
{
    call_begin(p);
    *rows = NULL;
    *n = 0;
    if (store_check_list(before, f->status, limit, err, errlen) != 0) return -1;
    char bs[24], ls[16], *text = NULL;
    if (f->text) {
        if (!(text = strdup(f->text))) {
            set_err(err, errlen, "listing jobs: out of memory");
            return -1;
        }
        for (char *c = text; *c; c++)
            if (*c >= 'A' && *c <= 'Z') *c = (char)(*c - 'A' + 'a');
    }
    fmt_i64(bs, sizeof bs, before > 0 ? before : INT64_MAX);
    snprintf(ls, sizeof ls, "%d", limit);
    const char *v[] = {bs, ls, f->status >= 0 ? store_status_name((store_status)f->status) : NULL,
                       text, f->tag};
    PGresult *r = run(p,
                      "SELECT " JOB_COLUMNS " FROM jobs WHERE id < $1 AND ($3::text IS NULL OR "
                      "status = $3) AND " SEARCH_WHERE " ORDER BY id DESC LIMIT $2",
                      5, v, 0, err, errlen, "listing jobs");
    free(text);
    return job_list(r, rows, n, err, errlen);
}

#define SERIES_SHAPE                                                                               \
    "SELECT s.channel, s.width::int4, s.nsamples::int4, length(s.data)::int4, j.nv::int4"
#define SERIES_FROM " FROM series AS s JOIN jobs AS j ON j.id = s.job_id WHERE s.job_id = $1"

int store_pg_get_series(store_pg *p, int64_t id, ctc_sim_result **out, char *err, size_t errlen)
{
    call_begin(p);
    *out = NULL;
    char ids[24], what[64];
    fmt_i64(ids, sizeof ids, id);
    snprintf(what, sizeof what, "job %lld: reading its series", (long long)id);
    const char *v[] = {ids};
    PGresult *r = run(p, SERIES_SHAPE ", s.data" SERIES_FROM, 1, v, 1, err, errlen, what);
    if (!r) return -1;
    int rows = PQntuples(r), rc = -1, nv = 0, nind = 0, nsamples = -1;
    ctc_sim_result *res = NULL;
    if (rows == 0) {
        rc = 1;
        goto done;
    }
    nv = be_i32(r, 0, 4);
    res = calloc(1, sizeof *res);
    if (!res) {
        set_err(err, errlen, "job %lld: reading its series: out of memory", (long long)id);
        goto done;
    }
    for (int i = 0; i < rows; i++) {
        const char *name = PQgetvalue(r, i, 0);
        int width = be_i32(r, i, 1), c;
        int64_t bytes = PQgetlength(r, i, 5);
        if (store_series_check_row(id, &nv, &nind, &nsamples, name, width, be_i32(r, i, 2), bytes,
                                   &c, err, errlen))
            goto done;
        double *data = malloc(bytes > 0 ? (size_t)bytes : sizeof(double));
        if (!data) {
            set_err(err, errlen, "job %lld: reading series %s: out of memory", (long long)id, name);
            goto done;
        }
        if (bytes > 0) memcpy(data, PQgetvalue(r, i, 5), (size_t)bytes);
        if (c == -1) {
            free(res->t);
            res->t = data;
        } else {
            res->ch[c] = data;
            res->width[c] = width;
            res->channels |= CTC_CH_BIT(c);
        }
    }
    if (!res->t) {
        set_err(err, errlen, "job %lld: series has no t", (long long)id);
        goto done;
    }
    res->nsamples = nsamples;
    res->nv = nv;
    res->nq = res->width[CTC_CH_Q] ? res->width[CTC_CH_Q] : nv;
    res->metrics.nv = nv;
    *out = res;
    res = NULL;
    rc = 0;
done:
    PQclear(r);
    ctc_sim_result_free(res);
    return rc;
}

int store_pg_get_series_info(store_pg *p, int64_t id, store_series_info *out, char *err,
                             size_t errlen)
{
    call_begin(p);
    memset(out, 0, sizeof *out);
    char ids[24], what[64];
    fmt_i64(ids, sizeof ids, id);
    snprintf(what, sizeof what, "job %lld: reading its series", (long long)id);
    const char *v[] = {ids};
    PGresult *r = run(p, SERIES_SHAPE SERIES_FROM, 1, v, 1, err, errlen, what);
    if (!r) return -1;
    int rows = PQntuples(r), rc = -1, nv = 0, nind = 0, nsamples = -1, have_t = 0;
    if (rows == 0) {
        rc = 1;
        goto done;
    }
    nv = be_i32(r, 0, 4);
    for (int i = 0; i < rows; i++) {
        int width = be_i32(r, i, 1), c;
        int64_t bytes = be_i32(r, i, 3);
        if (store_series_check_row(id, &nv, &nind, &nsamples, PQgetvalue(r, i, 0), width,
                                   be_i32(r, i, 2), bytes, &c, err, errlen))
            goto done;
        if (c == -1) {
            have_t = 1;
        } else {
            out->width[c] = width;
            out->channels |= CTC_CH_BIT(c);
        }
        out->bytes += bytes;
    }
    if (!have_t) {
        set_err(err, errlen, "job %lld: series has no t", (long long)id);
        goto done;
    }
    out->nsamples = nsamples;
    out->nv = nv;
    out->nq = out->width[CTC_CH_Q] ? out->width[CTC_CH_Q] : nv;
    rc = 0;
done:
    PQclear(r);
    if (rc) memset(out, 0, sizeof *out);
    return rc;
}

int store_pg_series_begin(store_pg *p, char *err, size_t errlen)
{
    call_begin(p);
    if (p->reading) {
        set_err(err, errlen, "reading a series: a read is already under way");
        return -1;
    }
    if (run_simple(p, "BEGIN ISOLATION LEVEL REPEATABLE READ READ ONLY", err, errlen,
                   "reading a series") != 0)
        return -1;
    p->reading = 1;
    return 0;
}

int store_pg_series_read(store_pg *p, int64_t id, int channel, uint64_t offset, void *buf,
                         size_t len, char *err, size_t errlen)
{
    call_begin(p);
    const char *name = channel < 0 ? "t" : ctc_channel_name((ctc_channel)channel);
    if (!p->reading || channel < -1 || channel >= CTC_NCHANNELS) {
        set_err(err, errlen, "job %lld: reading series %s: %s", (long long)id, name,
                p->reading ? "no such channel" : "not inside store_series_begin");
        return -1;
    }
    char ids[24], off[24], ln[24], what[96];
    fmt_i64(ids, sizeof ids, id);
    snprintf(off, sizeof off, "%llu", (unsigned long long)offset + 1);
    snprintf(ln, sizeof ln, "%zu", len);
    snprintf(what, sizeof what, "job %lld: reading series %s", (long long)id, name);
    const char *v[] = {ids, name, off, ln};
    PGresult *r = run(p,
                      "SELECT substring(data FROM $3::int4 FOR $4::int4), length(data)::int4 "
                      "FROM series WHERE job_id = $1 AND channel = $2",
                      4, v, 1, err, errlen, what);
    if (!r) return -1;
    int rc = -1;
    if (PQntuples(r) == 0) {
        set_err(err, errlen, "job %lld: series %s is gone", (long long)id, name);
        rc = 1;
        goto done;
    }
    int64_t bytes = be_i32(r, 0, 1);
    if (offset > (uint64_t)bytes || len > (uint64_t)bytes - offset ||
        (size_t)PQgetlength(r, 0, 0) != len) {
        set_err(err, errlen,
                "job %lld: series %s holds %lld bytes, not the %zu asked for at byte %llu",
                (long long)id, name, (long long)bytes, len, (unsigned long long)offset);
        goto done;
    }
    memcpy(buf, PQgetvalue(r, 0, 0), len);
    rc = 0;
done:
    PQclear(r);
    return rc;
}

void store_pg_series_end(store_pg *p)
{
    if (!p || !p->reading) return;
    if (PQtransactionStatus(p->conn) != PQTRANS_IDLE) PQclear(PQexec(p->conn, "COMMIT"));
    p->reading = 0;
}

int store_pg_delete(store_pg *p, int64_t id, char *err, size_t errlen)
{
    call_begin(p);
    char ids[24], what[48];
    fmt_i64(ids, sizeof ids, id);
    snprintf(what, sizeof what, "cannot delete job %lld", (long long)id);
    const char *v[] = {ids};
    /* only a finished job goes (its series by ON DELETE CASCADE), decided in one statement */
    PGresult *r = run(p,
                      "WITH doomed AS (SELECT id, status FROM jobs WHERE id = $1 FOR UPDATE), "
                      "gone AS (DELETE FROM jobs WHERE id IN (SELECT id FROM doomed WHERE NOT "
                      "" ACTIVE ") RETURNING id) SELECT (SELECT status FROM doomed), (SELECT "
                      "count(*) FROM gone)",
                      1, v, 0, err, errlen, what);
    if (!r) return write_end(p, -1, 1);
    int rc;
    if (PQgetisnull(r, 0, 0))
        rc = 1;
    else if (atoi(PQgetvalue(r, 0, 1)) == 1)
        rc = 0, p->changed++;
    else
        rc = 2;
    PQclear(r);
    return write_end(p, rc, 1);
}

int store_pg_count(store_pg *p, long counts[STORE_NSTATUS], char *err, size_t errlen)
{
    call_begin(p);
    for (int i = 0; i < STORE_NSTATUS; i++) counts[i] = 0;
    PGresult *r =
        run(p, "SELECT status, n FROM job_counts", 0, NULL, 0, err, errlen, "counting jobs");
    if (!r) return -1;
    int rc = 0;
    for (int i = 0; i < PQntuples(r); i++) {
        int st = store_status_parse(PQgetvalue(r, i, 0));
        if (st < 0) {
            set_err(err, errlen, "counting jobs: unknown status '%s'", PQgetvalue(r, i, 0));
            rc = -1;
            break;
        }
        counts[st] = atol(PQgetvalue(r, i, 1));
    }
    PQclear(r);
    return rc;
}

/* ---- claims, heartbeats, notifications ---- */

/* the oldest jobs of each lane the claim considers: more than one, so that claims at the same
 * moment, which skip each other's locked rows, still find one in the lane served least
 * recently */
#define CLAIM_PER_LANE "4"

int store_pg_claim(store *s, double lease_s, int64_t *id, int *cancel, char *err, size_t errlen)
{
    store_pg *p = store_pg_of(s);
    call_begin(p);
    char host[128] = "", lease[40];
    gethostname(host, sizeof host - 1);
    p->claims++;
    /* a token no other claim has: host, process, connection, claim */
    snprintf(p->owner, sizeof p->owner, "%.100s:%ld:%p:%lu", host, (long)getpid(), (void *)p,
             p->claims);
    fmt_real(lease, sizeof lease, lease_s);
    char started[40];
    fmt_real(started, sizeof started, now_s());
    const char *v[] = {p->owner, lease, started};
    /* the candidates: every job whose lease expired (first), then the oldest few claimable
       jobs of each lane (found by a skip scan of jobs_queued_lanes: one index probe per lane),
       the lane served least recently first; the first candidate no other claim holds is taken
       and its lane marked served now. started is this worker's clock, read before the claim, so
       a job inserted meanwhile (or by a process whose clock is ahead) would seem to start before
       it was created: it starts no earlier than its creation */
    PGresult *r = run(
        p,
        "WITH RECURSIVE lane(id) AS (SELECT min(coalesce(family_id, 0)) FROM jobs WHERE " CLAIMABLE
        " UNION ALL SELECT (SELECT min(coalesce(family_id, 0)) FROM jobs WHERE " CLAIMABLE
        " AND coalesce(family_id, 0) > lane.id) FROM lane WHERE lane.id IS NOT NULL), "
        "cand AS (SELECT id, -1::float8 AS served FROM jobs WHERE status = 'running' AND "
        "lease_until < " DB_NOW " UNION ALL SELECT c.id, coalesce(l.served, 0) FROM lane LEFT "
        "JOIN lanes AS l ON l.lane = lane.id CROSS JOIN LATERAL (SELECT id FROM jobs "
        "WHERE " CLAIMABLE " AND coalesce(family_id, 0) = lane.id ORDER BY id LIMIT " CLAIM_PER_LANE
        ") AS c WHERE "
        "lane.id IS NOT NULL), "
        "pick AS (SELECT j.id FROM jobs AS j JOIN cand ON cand.id = j.id WHERE (j.status = "
        "'queued' AND NOT j.cancel_requested) OR (j.status = 'running' AND j.lease_until < " DB_NOW
        ") ORDER BY cand.served, j.id LIMIT 1 FOR UPDATE OF j SKIP LOCKED), "
        "claimed AS (UPDATE jobs SET status = 'running', worker = $1, lease_until = " DB_NOW
        " + $2::float8, started = greatest($3::float8, created), progress = 0 WHERE id = (SELECT "
        "id FROM pick) "
        "RETURNING id, cancel_requested, coalesce(family_id, 0) AS lane), "
        "served AS (INSERT INTO lanes (lane, served) SELECT lane, " DB_NOW " FROM claimed ON "
        "CONFLICT (lane) DO UPDATE SET served = EXCLUDED.served) "
        "SELECT id, cancel_requested FROM claimed",
        3, v, 0, err, errlen, "claiming a job");
    int rc = -1;
    if (r && PQntuples(r) == 1) {
        *id = strtoll(PQgetvalue(r, 0, 0), NULL, 10);
        *cancel = PQgetvalue(r, 0, 1)[0] == 't';
        rc = 0;
    } else if (r) {
        p->owner[0] = '\0';
        rc = 1;
    } else {
        p->owner[0] = '\0';
    }
    PQclear(r);
    return write_end(p, rc, 0);
}

int store_pg_heartbeat(store *s, int64_t id, double progress, double lease_s, int *cancel,
                       char *err, size_t errlen)
{
    store_pg *p = store_pg_of(s);
    call_begin(p);
    char ids[24], pr[40], lease[40], what[64];
    fmt_i64(ids, sizeof ids, id);
    fmt_real(pr, sizeof pr, isnan(progress) ? 0.0 : fmin(fmax(progress, 0.0), 1.0));
    fmt_real(lease, sizeof lease, lease_s);
    snprintf(what, sizeof what, "job %lld: renewing its lease", (long long)id);
    const char *v[] = {ids, pr, p->owner, lease};
    PGresult *r = run(p,
                      "UPDATE jobs SET progress = $2, lease_until = " DB_NOW " + $4::float8 "
                      "WHERE id = $1 AND status = 'running' AND worker = $3 "
                      "RETURNING cancel_requested",
                      4, v, 0, err, errlen, what);
    int rc = -1;
    if (r && PQntuples(r) == 1) {
        *cancel = PQgetvalue(r, 0, 0)[0] == 't';
        rc = 0;
    } else if (r) {
        set_err(err, errlen, "job %lld: the lease is lost (another worker holds it)",
                (long long)id);
        rc = 1;
    }
    PQclear(r);
    /* a worker's connection listens (it waits on it when idle); what came while it runs a job
       only said that something changed, which its next claim learns anyway */
    PGnotify *n;
    while ((n = PQnotifies(p->conn)) != NULL) PQfreemem(n);
    return write_end(p, rc, 0);
}

int store_pg_request_cancel(store *s, int64_t id, char *err, size_t errlen)
{
    store_pg *p = store_pg_of(s);
    call_begin(p);
    char ids[24], what[64];
    fmt_i64(ids, sizeof ids, id);
    snprintf(what, sizeof what, "cannot cancel job %lld", (long long)id);
    const char *v[] = {ids};
    PGresult *r = run(
        p, "UPDATE jobs SET cancel_requested = true WHERE id = $1 AND " ACTIVE " RETURNING status",
        1, v, 0, err, errlen, what);
    int rc = -1;
    if (r) rc = PQntuples(r) == 0 ? 0 : strcmp(PQgetvalue(r, 0, 0), "running") == 0 ? 2 : 1;
    PQclear(r);
    return write_end(p, rc, 0);
}

int store_pg_listen(store *s, char *err, size_t errlen)
{
    store_pg *p = store_pg_of(s);
    call_begin(p);
    p->listening = 1;
    return run_simple(p, "LISTEN " STORE_PG_CHANNEL, err, errlen, "listening for job changes");
}

int store_pg_notifications(store *s, double timeout_s,
                           void (*fn)(void *arg, int64_t id, int status), void *arg, char *err,
                           size_t errlen)
{
    store_pg *p = store_pg_of(s);
    call_begin(p);
    if (PQstatus(p->conn) != CONNECTION_OK) {
        db_err(p, NULL, err, errlen, "listening for job changes");
        return -1;
    }
    int count = 0;
    for (int pass = 0; pass < 2; pass++) {
        if (!PQconsumeInput(p->conn)) {
            db_err(p, NULL, err, errlen, "listening for job changes");
            return -1;
        }
        PGnotify *n;
        while ((n = PQnotifies(p->conn)) != NULL) {
            char status[16] = "";
            long long id = 0;
            if (sscanf(n->extra, "%lld %15s", &id, status) == 2)
                fn(arg, (int64_t)id, store_status_parse(status));
            PQfreemem(n);
            count++;
        }
        if (count > 0 || pass == 1) break;
        /* nothing yet: wait on the socket */
        struct pollfd pfd = {.fd = PQsocket(p->conn), .events = POLLIN};
        int ms = timeout_s > 0 ? (int)(timeout_s * 1000.0) : 0;
        if (pfd.fd < 0) {
            db_err(p, NULL, err, errlen, "listening for job changes");
            return -1;
        }
        if (poll(&pfd, 1, ms) < 0 && errno != EINTR) {
            set_err(err, errlen, "listening for job changes: %s", strerror(errno));
            return -1;
        }
    }
    return count;
}

int store_pg_statuses(store *s, const int64_t *ids, int n, int *out, char *err, size_t errlen)
{
    store_pg *p = store_pg_of(s);
    call_begin(p);
    if (n <= 0) return 0;
    /* the ids as a PostgreSQL array literal: {1,2,3} */
    size_t cap = (size_t)n * 21 + 3, used = 0;
    char *list = malloc(cap);
    if (!list) {
        set_err(err, errlen, "reading job statuses: out of memory");
        return -1;
    }
    list[used++] = '{';
    for (int i = 0; i < n; i++)
        used +=
            (size_t)snprintf(list + used, cap - used, "%s%lld", i ? "," : "", (long long)ids[i]);
    snprintf(list + used, cap - used, "}");
    const char *v[] = {list};
    PGresult *r = run(p, "SELECT id, status FROM jobs WHERE id = ANY($1::bigint[])", 1, v, 0, err,
                      errlen, "reading job statuses");
    free(list);
    if (!r) return -1;
    for (int i = 0; i < n; i++) out[i] = -1;
    for (int k = 0; k < PQntuples(r); k++) {
        long long id = strtoll(PQgetvalue(r, k, 0), NULL, 10);
        int st = store_status_parse(PQgetvalue(r, k, 1));
        for (int i = 0; i < n; i++)
            if (ids[i] == id) out[i] = st;
    }
    PQclear(r);
    return 0;
}

/* ---- families ---- */

/* the members as one JSON array of records, for json_to_recordset: one statement stores them
 * all (a statement per member would cost a round trip each); NULL when out of memory or a
 * member lacks a field (*bad receives its index, else -1) */
static char *members_json(const store_new_member *members, long n, long *bad)
{
    *bad = -1;
    cJSON *a = cJSON_CreateArray();
    for (long i = 0; a && i < n; i++) {
        const store_new_member *m = &members[i];
        if (!m->name || !m->controller || !m->spec || !m->values || m->nbodies < 1 || m->nv < 0) {
            *bad = i;
            cJSON_Delete(a);
            return NULL;
        }
        cJSON *o = cJSON_CreateObject();
        if (!o || !cJSON_AddStringToObject(o, "name", m->name) ||
            !(m->preset ? cJSON_AddStringToObject(o, "preset", m->preset)
                        : cJSON_AddNullToObject(o, "preset")) ||
            !cJSON_AddNumberToObject(o, "nbodies", m->nbodies) ||
            !cJSON_AddNumberToObject(o, "nv", m->nv) ||
            !cJSON_AddStringToObject(o, "controller", m->controller) ||
            !cJSON_AddStringToObject(o, "spec", m->spec) ||
            !cJSON_AddNumberToObject(o, "member", (double)m->index) ||
            !cJSON_AddNumberToObject(o, "replica", m->replica) ||
            !cJSON_AddStringToObject(o, "vals", m->values) ||
            !cJSON_AddNumberToObject(o, "ord", (double)i)) {
            cJSON_Delete(o);
            cJSON_Delete(a);
            return NULL;
        }
        cJSON_AddItemToArray(a, o);
    }
    char *text = a ? cJSON_PrintUnformatted(a) : NULL;
    cJSON_Delete(a);
    return text;
}

int store_pg_family_insert(store_pg *p, const char *name, const char *spec, const char *axes,
                           const store_new_member *members, long n, int64_t *family_id,
                           int64_t *ids, char *err, size_t errlen)
{
    call_begin(p);
    if (store_check_family(name, spec, axes, n, err, errlen) != 0) return -1;
    int rc = -1;
    long bad;
    PGresult *r = NULL;
    char *list = members_json(members, n, &bad);
    char what[300], created[40], ns[24], fid[24];
    snprintf(what, sizeof what, "cannot store family '%.200s'", name);
    if (!list) {
        if (bad >= 0)
            set_err(err, errlen, "cannot store member %ld of family '%.200s': a field is missing",
                    bad, name);
        else
            set_err(err, errlen, "%s: out of memory", what);
        return -1;
    }
    fmt_real(created, sizeof created, now_s());
    snprintf(ns, sizeof ns, "%ld", n);
    if (run_simple(p, "BEGIN", err, errlen, what) != 0) goto done;
    const char *fv[] = {name, spec, axes, ns, created};
    r = run(p,
            "INSERT INTO families (name, spec, axes, members, created) VALUES ($1, $2, $3, $4, "
            "$5) RETURNING id",
            5, fv, 0, err, errlen, what);
    if (!r) goto done;
    *family_id = strtoll(PQgetvalue(r, 0, 0), NULL, 10);
    PQclear(r);
    fmt_i64(fid, sizeof fid, *family_id);
    /* the ids are drawn in the order of the SELECT (ord, the members' order); read back in the
       order of the ids, each row must be the member of its place */
    const char *mv[] = {list, fid, created};
    r = run(p,
            "WITH ins AS (INSERT INTO jobs (name, preset, status, progress, created, nbodies, nv, "
            "controller, spec, family_id, family_member, family_replica, family_values) SELECT "
            "m.name, m.preset, 'queued', 0, $3::float8, m.nbodies, m.nv, m.controller, m.spec, "
            "$2::bigint, m.member, m.replica, m.vals FROM json_to_recordset($1::json) AS "
            "m(name text, preset text, nbodies int, nv int, controller text, spec "
            "text, member bigint, replica int, vals text, ord bigint) ORDER BY m.ord RETURNING "
            "id, family_member, family_replica) SELECT id, family_member, family_replica FROM ins "
            "ORDER BY id",
            3, mv, 0, err, errlen, what);
    if (!r) goto done;
    if (PQntuples(r) != n) {
        set_err(err, errlen, "%s: %d members stored, not %ld", what, PQntuples(r), n);
        goto done;
    }
    for (long i = 0; i < n; i++) {
        int k = (int)i;
        if (strtol(PQgetvalue(r, k, 1), NULL, 10) != members[i].index ||
            atoi(PQgetvalue(r, k, 2)) != members[i].replica) {
            set_err(err, errlen, "%s: the members' ids do not follow their order (member %ld)",
                    what, i);
            goto done;
        }
        ids[i] = strtoll(PQgetvalue(r, k, 0), NULL, 10);
    }
    PQclear(r);
    r = NULL;
    if (run_simple(p, "COMMIT", err, errlen, what) != 0) goto done;
    rc = 0;
done:
    PQclear(r);
    free(list);
    if (rc) rollback(p);
    return write_end(p, rc, 1);
}

/* a family's columns, then its counts as "status n,status n" (one statement: one snapshot) */
#define FAMILY_COLUMNS                                                                             \
    "f.id, f.name, f.spec, f.axes, f.members, f.created, (SELECT string_agg(c.status || ' ' || "   \
    "c.n, ',') FROM (SELECT status, count(*) AS n FROM jobs WHERE family_id = f.id GROUP BY "      \
    "status) AS c)"

static int read_family(const PGresult *r, int row, int with_spec, store_family *f, char *err,
                       size_t errlen)
{
    memset(f, 0, sizeof *f);
    f->id = strtoll(PQgetvalue(r, row, 0), NULL, 10);
    f->members = strtol(PQgetvalue(r, row, 4), NULL, 10);
    f->created = real_col(r, row, 5);
    const char *c = PQgetisnull(r, row, 6) ? "" : PQgetvalue(r, row, 6);
    while (*c) {
        char status[16];
        long count;
        int used = 0;
        if (sscanf(c, "%15s %ld%n", status, &count, &used) != 2) break;
        int st = store_status_parse(status);
        if (st >= 0) f->counts[st] = count;
        c += used;
        if (*c == ',') c++;
    }
    if (dup_col(r, row, 1, &f->name) || dup_col(r, row, 3, &f->axes) ||
        (with_spec && dup_col(r, row, 2, &f->spec))) {
        set_err(err, errlen, "family %lld: out of memory", (long long)f->id);
        store_family_clear(f);
        return -1;
    }
    return 0;
}

int store_pg_family_get(store_pg *p, int64_t id, store_family *out, char *err, size_t errlen)
{
    call_begin(p);
    memset(out, 0, sizeof *out);
    char ids[24], what[48];
    fmt_i64(ids, sizeof ids, id);
    snprintf(what, sizeof what, "cannot read family %lld", (long long)id);
    const char *v[] = {ids};
    PGresult *r = run(p, "SELECT " FAMILY_COLUMNS " FROM families AS f WHERE f.id = $1", 1, v, 0,
                      err, errlen, what);
    if (!r) return -1;
    int rc = PQntuples(r) == 0 ? 1 : read_family(r, 0, 1, out, err, errlen);
    PQclear(r);
    return rc;
}

static int family_row_read(const PGresult *r, int k, void *elem, char *err, size_t errlen)
{
    return read_family(r, k, 0, elem, err, errlen);
}

static void family_rows_free(void *rows, long n)
{
    store_families_free(rows, (int)n);
}

static const pg_row_reader family_list_rows = {sizeof(store_family), family_row_read,
                                               family_rows_free};

/* pg_rows's reader of a member: id, family_member, family_replica, status, family_values,
 * metrics, message */
static int member_row_read(const PGresult *r, int k, void *elem, char *err, size_t errlen)
{
    store_member *m = elem;
    m->job = strtoll(PQgetvalue(r, k, 0), NULL, 10);
    m->index = strtol(PQgetvalue(r, k, 1), NULL, 10);
    m->replica = atoi(PQgetvalue(r, k, 2));
    int st = store_status_parse(PQgetvalue(r, k, 3));
    m->status = st < 0 ? STORE_FAILED : (store_status)st;
    if (dup_col(r, k, 4, &m->values) || dup_col(r, k, 5, &m->metrics) ||
        dup_col(r, k, 6, &m->message)) {
        set_err(err, errlen, "job %lld: out of memory", (long long)m->job);
        return -1;
    }
    return 0;
}

static void member_rows_free(void *rows, long n)
{
    store_members_free(rows, n);
}

static const pg_row_reader member_rows = {sizeof(store_member), member_row_read, member_rows_free};

/* pg_rows's reader of an id (column 0) */
static int id_row_read(const PGresult *r, int k, void *elem, char *err, size_t errlen)
{
    (void)err, (void)errlen;
    *(int64_t *)elem = strtoll(PQgetvalue(r, k, 0), NULL, 10);
    return 0;
}

static void id_rows_free(void *rows, long n)
{
    (void)n;
    free(rows);
}

static const pg_row_reader id_rows = {sizeof(int64_t), id_row_read, id_rows_free};

/* the rows of sql, a query of family id's members with $1 = id */
static int family_rows(store_pg *p, const char *sql, const pg_row_reader *rr, int64_t id,
                       void **rows, long *n, char *err, size_t errlen)
{
    call_begin(p);
    char ids[24], what[64];
    fmt_i64(ids, sizeof ids, id);
    snprintf(what, sizeof what, "reading the members of family %lld", (long long)id);
    const char *v[] = {ids};
    return pg_rows(run(p, sql, 1, v, 0, err, errlen, what), rr, rows, n, what, err, errlen);
}

int store_pg_family_list(store_pg *p, int64_t before, int limit, store_family **rows, int *n,
                         char *err, size_t errlen)
{
    call_begin(p);
    *rows = NULL;
    *n = 0;
    if (store_check_limit(limit, err, errlen) != 0) return -1;
    char bs[24], ls[16];
    fmt_i64(bs, sizeof bs, before > 0 ? before : INT64_MAX);
    snprintf(ls, sizeof ls, "%d", limit);
    const char *v[] = {bs, ls};
    PGresult *r = run(p,
                      "SELECT " FAMILY_COLUMNS " FROM families AS f WHERE f.id < $1 ORDER BY f.id "
                      "DESC LIMIT $2",
                      2, v, 0, err, errlen, "listing families");
    void *list;
    long count;
    int rc = pg_rows(r, &family_list_rows, &list, &count, "listing families", err, errlen);
    *rows = list;
    *n = (int)count;
    return rc;
}

int store_pg_family_members(store_pg *p, int64_t id, store_member **rows, long *n, char *err,
                            size_t errlen)
{
    void *list;
    int rc = family_rows(p,
                         "SELECT id, family_member, family_replica, status, family_values, "
                         "metrics, message FROM jobs WHERE family_id = $1 ORDER BY family_member",
                         &member_rows, id, &list, n, err, errlen);
    *rows = list;
    return rc;
}

int store_pg_family_active(store_pg *p, int64_t id, int64_t **ids, long *n, char *err,
                           size_t errlen)
{
    void *list;
    int rc = family_rows(p, "SELECT id FROM jobs WHERE family_id = $1 AND " ACTIVE " ORDER BY id",
                         &id_rows, id, &list, n, err, errlen);
    *ids = list;
    return rc;
}

int store_pg_family_cancel(store_pg *p, int64_t id, const char *message, long *n, char *err,
                           size_t errlen)
{
    call_begin(p);
    *n = 0;
    char fid[24], fin[40], what[48];
    fmt_i64(fid, sizeof fid, id);
    fmt_real(fin, sizeof fin, now_s());
    snprintf(what, sizeof what, "cannot cancel family %lld", (long long)id);
    const char *v[] = {fid, message, fin};
    PGresult *r = run(p,
                      "UPDATE jobs SET status = 'cancelled', message = $2, finished = $3 WHERE "
                      "family_id = $1 AND status = 'queued'",
                      3, v, 0, err, errlen, what);
    if (r) *n = changes(r);
    PQclear(r);
    return write_end(p, r ? 0 : -1, 0);
}

int store_pg_family_delete(store_pg *p, int64_t id, char *err, size_t errlen)
{
    call_begin(p);
    int rc = -1;
    PGresult *r = NULL;
    char fid[24], what[48];
    fmt_i64(fid, sizeof fid, id);
    snprintf(what, sizeof what, "cannot delete family %lld", (long long)id);
    const char *v[] = {fid};
    if (run_simple(p, "BEGIN", err, errlen, what) != 0) goto done;
    /* the family's row locked, then whether a member is active: a finished member never
       becomes active again, so the answer holds until the commit */
    r = run(p,
            "SELECT (SELECT id FROM families WHERE id = $1 FOR UPDATE) IS NOT NULL, EXISTS "
            "(SELECT 1 FROM jobs WHERE family_id = $1 AND " ACTIVE ")",
            1, v, 0, err, errlen, what);
    if (!r) goto done;
    if (PQgetvalue(r, 0, 0)[0] != 't' || PQgetvalue(r, 0, 1)[0] == 't') {
        rc = PQgetvalue(r, 0, 0)[0] != 't' ? 1 : 2;
        goto done;
    }
    PQclear(r);
    /* the members first (their series follow by ON DELETE CASCADE), then the family */
    r = run(p, "DELETE FROM jobs WHERE family_id = $1", 1, v, 0, err, errlen, what);
    if (!r) goto done;
    PQclear(r);
    r = run(p, "DELETE FROM lanes WHERE lane = $1", 1, v, 0, err, errlen, what);
    if (!r) goto done;
    PQclear(r);
    r = run(p, "DELETE FROM families WHERE id = $1", 1, v, 0, err, errlen, what);
    if (!r) goto done;
    PQclear(r);
    r = NULL;
    if (run_simple(p, "COMMIT", err, errlen, what) != 0) goto done;
    rc = 0;
done:
    PQclear(r);
    if (rc != 0) rollback(p);
    return write_end(p, rc, 1);
}

int store_pg_job_families(store_pg *p, const int64_t *ids, int n, int64_t *families, char *err,
                          size_t errlen)
{
    call_begin(p);
    for (int i = 0; i < n; i++) families[i] = 0;
    if (n <= 0) return 0;
    size_t cap = (size_t)n * 21 + 3, used = 0;
    char *list = malloc(cap);
    if (!list) {
        set_err(err, errlen, "reading the jobs' families: out of memory");
        return -1;
    }
    list[used++] = '{';
    for (int i = 0; i < n; i++)
        used +=
            (size_t)snprintf(list + used, cap - used, "%s%lld", i ? "," : "", (long long)ids[i]);
    snprintf(list + used, cap - used, "}");
    const char *v[] = {list};
    PGresult *r = run(p,
                      "SELECT id, family_id FROM jobs WHERE id = ANY($1::bigint[]) AND family_id "
                      "IS NOT NULL",
                      1, v, 0, err, errlen, "reading the jobs' families");
    free(list);
    if (!r) return -1;
    for (int k = 0; k < PQntuples(r); k++) {
        long long id = strtoll(PQgetvalue(r, k, 0), NULL, 10);
        int64_t fam = strtoll(PQgetvalue(r, k, 1), NULL, 10);
        for (int i = 0; i < n; i++)
            if (ids[i] == id) families[i] = fam;
    }
    PQclear(r);
    return 0;
}

int store_pg_request_cancel_family(store *s, int64_t id, char *err, size_t errlen)
{
    store_pg *p = store_pg_of(s);
    call_begin(p);
    char fid[24], what[48];
    fmt_i64(fid, sizeof fid, id);
    snprintf(what, sizeof what, "cannot cancel family %lld", (long long)id);
    const char *v[] = {fid};
    PGresult *r = run(p,
                      "WITH flagged AS (UPDATE jobs SET cancel_requested = true WHERE family_id = "
                      "$1 AND " ACTIVE " RETURNING status) SELECT count(*) FROM flagged WHERE "
                      "status = 'running'",
                      1, v, 0, err, errlen, what);
    int rc = r ? atoi(PQgetvalue(r, 0, 0)) : -1;
    PQclear(r);
    return write_end(p, rc, 0);
}

int store_pg_queue_position(store *s, int64_t id, char *err, size_t errlen)
{
    store_pg *p = store_pg_of(s);
    call_begin(p);
    char ids[24], what[64];
    fmt_i64(ids, sizeof ids, id);
    snprintf(what, sizeof what, "job %lld: reading its place in the queue", (long long)id);
    const char *v[] = {ids};
    /* k of its own lane ahead of it, and min(k, count) of each other lane's (store_pg.h) */
    PGresult *r = run(p,
                      "WITH me AS (SELECT id, coalesce(family_id, 0) AS lane FROM jobs WHERE id = "
                      "$1 AND status = 'queued' AND NOT cancel_requested), "
                      "k AS (SELECT count(*) AS k FROM jobs AS j, me WHERE j.status = 'queued' "
                      "AND NOT j.cancel_requested AND coalesce(j.family_id, 0) = me.lane AND j.id "
                      "< me.id), "
                      "others AS (SELECT coalesce(j.family_id, 0) AS lane, count(*) AS c FROM "
                      "jobs AS j, me WHERE j.status = 'queued' AND NOT j.cancel_requested AND "
                      "coalesce(j.family_id, 0) <> me.lane GROUP BY 1) "
                      "SELECT 1 + k.k + coalesce((SELECT sum(least(o.c, k.k)) FROM others AS o), "
                      "0) FROM me, k",
                      1, v, 0, err, errlen, what);
    if (!r) return -1;
    long long pos = PQntuples(r) == 1 ? strtoll(PQgetvalue(r, 0, 0), NULL, 10) : 0;
    PQclear(r);
    return pos > INT_MAX ? INT_MAX : (int)pos;
}

int store_pg_queued_singles(store *s, long *n, char *err, size_t errlen)
{
    store_pg *p = store_pg_of(s);
    call_begin(p);
    *n = 0;
    /* jobs_queued_lanes's lane 0: as many rows as single jobs wait, which max_queue bounds */
    PGresult *r = run(p,
                      "SELECT count(*) FROM jobs WHERE " CLAIMABLE " AND coalesce(family_id, 0) "
                      "= 0",
                      0, NULL, 0, err, errlen, "counting the queued jobs");
    if (r) *n = atol(PQgetvalue(r, 0, 0));
    PQclear(r);
    return r ? 0 : -1;
}
