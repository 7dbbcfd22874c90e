/*
 * store.h - the service's SQLite storage: jobs, their specs, status, progress, metrics and
 * result series.
 *
 * One store is one SQLite connection and belongs to one thread at a time (the service opens one
 * per worker and one per HTTP thread). The database runs in WAL mode with a busy timeout, so
 * readers never block the writer; every statement is prepared once per connection and reused.
 * The schema is versioned with PRAGMA user_version and migrated forward in one transaction by
 * store_open; a database that is not ctcsim's (tables it does not know, or a newer version) is
 * refused with a message instead of being touched.
 *
 * Tables:
 *   jobs(id INTEGER PRIMARY KEY, name, preset, status, progress, created, started, finished,
 *        nbodies, nv, controller, spec TEXT (normalised job JSON), metrics TEXT (JSON, NULL until
 *        finished), message, e_max REAL, wall_s REAL)
 *        family_id (NULL, or its family), family_member, family_replica, family_values (JSON
 *        array of its axis values) - the four are NULL for a job posted alone)
 *   families(id INTEGER PRIMARY KEY, name, spec TEXT (the family's document), axes TEXT (JSON
 *        array of the axes' paths), members, created)  - version 3 (family.h)
 *   series(job_id, channel, width, nsamples, data BLOB)  - one row per recorded channel ("t" is a
 *        channel of width 1); data is nsamples x width float64, row-major, little-endian
 * A job's series and its final status are written in one transaction (store_finish), so a job is
 * either fully stored or still unfinished. Times are seconds since the Unix epoch (UTC).
 *
 * PostgreSQL. store_open of a "postgres://" or "postgresql://" URL opens a PostgreSQL database
 * instead (store_pg.h): the same tables and the same contracts, with the few differences listed
 * there (size cap, log reserve, recovery under leases), and what a queue shared by several
 * processes needs (claims, leases, notifications).
 *
 * Every function returns 0 on success and -1 on failure with a message in err (errlen bytes; err
 * may be NULL), except where it says otherwise. Strings returned in structs are owned by the
 * struct and freed by its clear function.
 *
 * Faults. After a -1, store_last_fault says what the database answered: a lock held too long
 * (SQLITE_BUSY, SQLITE_LOCKED), a full disk or a full database (SQLITE_FULL), a read-only file
 * (SQLITE_READONLY) or an I/O error (SQLITE_IOERR) are transient: the same call may succeed later
 * and the caller may retry it (the workers do, with backoff); any other failure (a job in the
 * wrong state, a damaged row, no memory) is not. The busy timeout bounds how long one call waits
 * for another connection's write lock before failing with STORE_FAULT_LOCKED.
 *
 * Health. A store_health is the database's state as the service's writes observe it, shared by
 * every connection attached to it (one per process; its own mutex, so any thread may read it).
 * Each write call on an attached store reports its outcome: a transient fault sets the state
 * (the first one's time is kept as `since` while the fault lasts), and a write that changed rows
 * clears it; a full database is cleared only by a write that adds rows (store_insert,
 * store_finish with a result) or frees room (store_delete), since an update in place may succeed
 * on a full disk. A connection whose busy timeout is 0 does not wait for locks by design, so its
 * lock failures are not reported (contention, not a fault). Reading the state is O(1).
 */
#ifndef STORE_H
#define STORE_H

#include <stddef.h>
#include <stdint.h>

#include "sim.h"

#define STORE_SCHEMA_VERSION 4

/* Job statuses as stored (and as the API shows them). */
typedef enum store_status {
    STORE_QUEUED = 0,
    STORE_RUNNING,
    STORE_DONE,
    STORE_FAILED, /* integrator failure or the per-job wall-time limit */
    STORE_DIVERGED,
    STORE_CANCELLED,
    STORE_NSTATUS
} store_status;

typedef struct store store;

/* What the database answered to a store's last failed call (see "Faults" above). */
typedef enum store_fault {
    STORE_FAULT_NONE = 0, /* the last call succeeded, or failed for a reason not the database's */
    STORE_FAULT_LOCKED,   /* another connection or process held the write lock too long */
    STORE_FAULT_FULL,     /* the disk, or the database's size limit, is full */
    STORE_FAULT_READONLY, /* the database cannot be written */
    STORE_FAULT_IO,       /* the operating system reported an I/O error */
    STORE_FAULT_OTHER,    /* any other SQLite error: not transient */
    STORE_NFAULT
} store_fault;

/* The shared state of the database as writes observe it (see "Health" above). */
typedef struct store_health store_health;

/* A snapshot of a store_health. */
typedef struct store_state {
    store_fault fault; /* STORE_FAULT_NONE when writes work (or none was tried yet) */
    double since;      /* s since the epoch of the first write that met this fault; 0 if none */
    double last_ok;    /* s since the epoch of the last write that changed rows; 0 if none */
    long failures;     /* writes that met a transient fault since the last success */
    char message[256]; /* the first failing call's message while the fault lasts, else "" */
} store_state;

/* One job's row, without its series. */
typedef struct store_job {
    int64_t id;
    char *name;
    char *preset; /* NULL when not from a preset */
    store_status status;
    double progress; /* 0..1 */
    double created;  /* s since the epoch */
    double started;  /* 0 until it starts */
    double finished; /* 0 until it finishes */
    int nbodies, nv;
    char *controller; /* "pid", "none", ... */
    char *spec;       /* normalised job JSON */
    char *metrics;    /* metrics JSON (result_out.h) or NULL */
    char *message;    /* why it failed / diverged / was cancelled, or NULL */
    double e_max;     /* max over coordinates of metrics.e_max, NaN if none */
    double wall_s;    /* NaN until finished */
    double e_final;   /* max over coordinates of |metrics.e_final|, NaN if none */
    double e_rms;     /* sqrt of the mean over coordinates of metrics.e_rms^2 (the RMS over the
                         run and the coordinates), NaN if none */
    char *tags;       /* the normalised job's "tags" as JSON text, NULL when it has none */
    int64_t family;   /* the family it belongs to, 0 for none */
} store_job;

/* Opens (creating if absent) the database at path, sets WAL mode, foreign keys and a busy
 * timeout, and migrates the schema to STORE_SCHEMA_VERSION. Fails with a clear message when the
 * file cannot be opened or created, is not an SQLite database, or is not ctcsim's. */
int store_open(const char *path, store **out, char *err, size_t errlen);

/* Closes the connection (finalising its statements); NULL is allowed. */
void store_close(store *s);

/* Sets how long (ms, >= 0) the calls of s wait for another connection's lock before failing with
 * STORE_FAULT_LOCKED; store_open sets 5000. 0 does not wait (and reports no lock to health). */
void store_set_busy_timeout(store *s, int ms);

/* Caps the database's size at max_bytes (rounded down to whole pages; 0 = no cap beyond SQLite's
 * own) for the writes of s: a write that would grow the file past it fails with
 * STORE_FAULT_FULL, as on a full disk. A cap below the current size refuses every growing write
 * but lets deletes run. The cap belongs to the connection, not to the file. */
int store_set_max_size(store *s, long long max_bytes, char *err, size_t errlen);

/* The fault of the last call on s: STORE_FAULT_NONE after a success or a failure that was not
 * the database's. Cleared at the start of every call. */
store_fault store_last_fault(const store *s);

/* 1 for the faults a retry may outlive (LOCKED, FULL, READONLY, IO), else 0. */
int store_fault_transient(store_fault f);

/* "ok", "locked", "full", "readonly", "io_error", "error": the name health shows. */
const char *store_fault_name(store_fault f);

/* SQLite's words for the fault ("database is locked", "database or disk is full", "attempt to
 * write a readonly database", "disk I/O error"; "not an error" for NONE). */
const char *store_fault_text(store_fault f);

/* A new health state (fault NONE), or NULL when out of memory. Free with store_health_free after
 * every store attached to it is closed; NULL is allowed there. */
store_health *store_health_new(void);
void store_health_free(store_health *h);

/* Attaches s to h (NULL detaches): each later write call on s reports its outcome to h.
 * h must outlive s. */
void store_attach(store *s, store_health *h);

/* Copies h's state into *out. O(1), thread-safe. */
void store_health_read(store_health *h, store_state *out);

/* 1 when h holds a fault and no probe ran in the last interval_s seconds (the caller should run
 * store_probe now; the probe's time is taken, so concurrent callers get 0), else 0. Thread-safe. */
int store_health_probe_due(store_health *h, double interval_s);

/* Learns whether the fault of s's health state has passed, when no other write comes to say so,
 * and reports it like a write: a full database is writable again when the disk and the size cap
 * both leave 1 MiB free (measured: statvfs and the page counts, nothing written); any other fault
 * is tested with a write that changes nothing a reader can see (one row of job_counts rewritten
 * with its own value, in a transaction). 0 when the database can take writes. */
int store_probe(store *s, char *err, size_t errlen);

/* Allocates bytes of disk for the database's write-ahead log (the -wal file's blocks, past its
 * end, its size unchanged: Linux fallocate with FALLOC_FL_KEEP_SIZE), so that the log can take
 * the next transactions when the disk is full: a delete, which frees pages, can then commit.
 * The log exists while a connection is open and goes when the last one closes, so call it with
 * the service's connections open. Fails with errno's message (e.g. no space, or a file system
 * without fallocate); the database is untouched either way. */
int store_reserve(store *s, long long bytes, char *err, size_t errlen);

/* Inserts a new queued job: name, preset (may be NULL), nbodies, nv, controller name and the
 * normalised spec JSON. *id receives its id (increasing). */
int store_insert(store *s, const char *name, const char *preset, int nbodies, int nv,
                 const char *controller, const char *spec, int64_t *id, char *err, size_t errlen);

/* As store_insert, but refused when the database holds max_queued queued single jobs (a family's
 * members and jobs whose cancel was asked for do not count) or more: returns 2 and stores
 * nothing. On PostgreSQL the count and the insert are one transaction under an advisory lock, so
 * API processes inserting at once cannot pass the bound together. On SQLite one process owns
 * the file and its queue holds the bound under its lock (jobq_submit answers 1), so the bound is
 * not read here. max_queued <= 0: no bound. */
int store_insert_bounded(store *s, long max_queued, const char *name, const char *preset,
                         int nbodies, int nv, const char *controller, const char *spec, int64_t *id,
                         char *err, size_t errlen);

/* Start-up recovery: every job found queued or running becomes queued with progress 0 (a running
 * one restarts from t = 0; its partial series, if any, is deleted). *ids receives a new array
 * (free()) of their ids, oldest first, and *n its length. */
int store_recover(store *s, int64_t **ids, int *n, char *err, size_t errlen);

/* Marks a queued job running (started = now, progress 0). Returns 1 if the job was not queued
 * (cancelled or deleted meanwhile: do not run it), 0 on success, -1 on error. */
int store_start(store *s, int64_t id, char *err, size_t errlen);

/* Records progress (0..1) of a running job. */
int store_progress(store *s, int64_t id, double progress, char *err, size_t errlen);

/* Puts a running job back to queued (shutdown interrupted it; it will restart from t = 0). */
int store_requeue(store *s, int64_t id, char *err, size_t errlen);

/* Finishes a job in one transaction: status (DONE, FAILED, DIVERGED or CANCELLED), message (may be
 * NULL or ""), metrics JSON, and the recorded series of r (may be NULL: no series, e.g. a queued
 * job cancelled before it ran). finished = now, progress 1 for DONE. */
int store_finish(store *s, int64_t id, store_status status, const char *message,
                 const char *metrics, const ctc_sim_result *r, char *err, size_t errlen);

/* Reads one job. Returns 1 if there is no such job, 0 when found, -1 on error. Clear *out with
 * store_job_clear after a 0. */
int store_get(store *s, int64_t id, store_job *out, char *err, size_t errlen);

/* Frees the strings of a job row and zeroes it. */
void store_job_clear(store_job *j);

/* Lists jobs newest first: those with id < before (0 = from the newest), with the given status
 * (-1 = any), at most limit (1..1000) rows, without spec and metrics (NULL in the rows). *rows
 * receives a new array (free with store_jobs_free), *n its length. */
int store_list(store *s, int64_t before, int status, int limit, store_job **rows, int *n, char *err,
               size_t errlen);

/* What store_search looks for; NULL (or -1) for what is not asked. */
typedef struct store_filter {
    int status;       /* a store_status, or -1 for any */
    const char *text; /* in the name, preset, controller or a tag, ASCII case ignored */
    const char *tag;  /* one of the job's tags, exactly */
} store_filter;

/* store_list with a filter: the jobs that match all it asks, newest first, from id < before
 * (0 = the newest), at most limit (1..1000). A search reads every job's name, preset and
 * controller and, where those do not match, its normalised job's tags: linear in the jobs
 * stored. 0, or -1 with a message. *rows as store_list's. */
int store_search(store *s, int64_t before, const store_filter *f, int limit, store_job **rows,
                 int *n, char *err, size_t errlen);

/* Frees an array from store_list or store_search. */
void store_jobs_free(store_job *rows, int n);

/* Reads the series of a job into a new result (free with ctc_sim_result_free): t, the recorded
 * channels with their widths, nsamples, nq and nv; status and metrics are left zero except
 * metrics.nv. Returns 1 if the job has no series (unknown, unfinished or cancelled before it ran),
 * 0 on success, -1 on error. */
int store_get_series(store *s, int64_t id, ctc_sim_result **out, char *err, size_t errlen);

/* The shape of a job's series, read without its samples (store_get_series_info). */
typedef struct store_series_info {
    int nsamples;
    int nq, nv;
    unsigned channels;        /* CTC_CH_BIT mask of the recorded channels */
    int width[CTC_NCHANNELS]; /* values per sample of each channel, 0 if not recorded */
    int64_t bytes;            /* the samples' size, t included (8 bytes a value) */
} store_series_info;

/* Reads the shape of a job's series, checking every row as store_get_series does (the same
 * messages) but reading none of the samples. Returns 1 if the job has no series, 0 on success,
 * -1 on error. */
int store_get_series_info(store *s, int64_t id, store_series_info *out, char *err, size_t errlen);

/* Reading a series in pieces, for a reader that must not hold it all in memory: between
 * store_series_begin and store_series_end the connection is inside one read transaction (one
 * snapshot of the database, which no writer waits for), and store_series_read copies len bytes
 * at offset of a channel's samples (channel -1 = t, else a ctc_channel; nsamples x width
 * float64, row-major, little-endian) into buf through a blob handle kept open until the end. A
 * reader that must not hold a snapshot for long (HTTP: the client sets the pace) ends the read
 * after each piece: the series may then be deleted between two reads, which the next read
 * reports. No other call may use s between begin and end, except store_close, which ends the
 * read. store_series_begin returns 0 or -1 (a read already under way, or the database failed);
 * store_series_read returns 0, 1 if the series is gone (the job was deleted; err says so) or
 * -1 on error, a read past the row's end included; store_series_end does nothing outside a
 * read, and accepts NULL. */
int store_series_begin(store *s, char *err, size_t errlen);
int store_series_read(store *s, int64_t id, int channel, uint64_t offset, void *buf, size_t len,
                      char *err, size_t errlen);
void store_series_end(store *s);

/* Deletes a finished job and its series. Returns 1 if there is no such job, 2 if it is queued or
 * running (cancel it first), 0 on success, -1 on error. */
int store_delete(store *s, int64_t id, char *err, size_t errlen);

/* Counts jobs by status into counts[STORE_NSTATUS]; also a cheap database health check. Reads
 * the job_counts table (six rows kept by triggers), so its cost does not grow with the number
 * of jobs. */
int store_count(store *s, long counts[STORE_NSTATUS], char *err, size_t errlen);

/* The SQLite virtual-machine steps (SQLITE_STMTSTATUS_VM_STEP) the last store_count took on s, 0
 * before the first: the measure of its work that tests and benchmarks check. */
long store_count_vm_steps(const store *s);

/* ---- families (family.h) ---- */

/* A family's row with the number of its members in each status. */
typedef struct store_family {
    int64_t id;
    char *name;
    char *spec; /* the family's document (JSON) */
    char *axes; /* JSON array of its axes' paths */
    long members;
    double created; /* s since the epoch */
    long counts[STORE_NSTATUS];
} store_family;

/* A member to store (store_family_insert): the fields of store_insert and its place. */
typedef struct store_new_member {
    const char *name, *preset, *controller, *spec; /* as store_insert's; preset may be NULL */
    int nbodies, nv;
    long index;         /* its number in the family, 0-based */
    int replica;        /* its replica, 0-based */
    const char *values; /* JSON array of its axis values */
} store_new_member;

/* One member's result (store_family_members). */
typedef struct store_member {
    int64_t job;
    long index;
    int replica;
    store_status status;
    char *values;  /* JSON array */
    char *metrics; /* metrics JSON or NULL */
    char *message; /* or NULL */
} store_member;

/* Stores a family and its n (>= 0) members, queued, in one transaction: the family is stored
 * whole or not at all. *family_id receives its id and ids[0..n) the members' job ids, which
 * increase with the member's index. name, spec and axes must not be NULL. */
int store_family_insert(store *s, const char *name, const char *spec, const char *axes,
                        const store_new_member *members, long n, int64_t *family_id, int64_t *ids,
                        char *err, size_t errlen);

/* Reads one family with its status counts. Returns 1 if there is no such family, 0 when found
 * (clear *out with store_family_clear), -1 on error. */
int store_family_get(store *s, int64_t id, store_family *out, char *err, size_t errlen);

/* Frees the strings of a family row and zeroes it; NULL is allowed. */
void store_family_clear(store_family *f);

/* Lists families newest first, those with id < before (0 = from the newest), at most limit
 * (1..1000), each with its counts and without its spec (NULL). *rows receives a new array (free
 * with store_families_free), *n its length. */
int store_family_list(store *s, int64_t before, int limit, store_family **rows, int *n, char *err,
                      size_t errlen);
void store_families_free(store_family *rows, int n);

/* Reads every member of a family, in member order, into a new array *rows (free with
 * store_members_free) of *n. A family without members (or no such family) gives 0 rows. */
int store_family_members(store *s, int64_t id, store_member **rows, long *n, char *err,
                         size_t errlen);
void store_members_free(store_member *rows, long n);

/* The ids of a family's members that are queued or running, in increasing order, into a new
 * array *ids (free()) of *n. */
int store_family_active(store *s, int64_t id, int64_t **ids, long *n, char *err, size_t errlen);

/* Records every queued member of a family cancelled (finished = now, message) in one
 * transaction; running members are left to their workers. *n receives how many were. */
int store_family_cancel(store *s, int64_t id, const char *message, long *n, char *err,
                        size_t errlen);

/* Deletes a family, its members and their series in one transaction. Returns 1 if there is no
 * such family, 2 if a member is queued or running (cancel them first), 0 on success, -1 on
 * error. */
int store_family_delete(store *s, int64_t id, char *err, size_t errlen);

/* The family of each of the n jobs ids[i] into families[i] (0: none, or no such job), read in
 * one snapshot (start-up recovery sorts the queued jobs into the queue's lanes with it). */
int store_job_families(store *s, const int64_t *ids, int n, int64_t *families, char *err,
                       size_t errlen);

/* "queued", "running", "done", "failed", "diverged", "cancelled"; and back (-1 if unknown). */
const char *store_status_name(store_status st);
int store_status_parse(const char *name);

#endif
