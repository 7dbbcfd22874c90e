/*
 * main.c - `ctcsim-server`, the HTTP/JSON service: reads its settings, starts the store check,
 * the job queue and the HTTP daemon, and stops them again on SIGINT or SIGTERM.
 *
 * Every setting has a flag and an environment variable (the table below; --help prints it with
 * the defaults); a flag overrides the environment, an empty variable counts as unset. A bad value
 * is reported with the flag or variable that gave it and exits 2.
 *
 * Start-up order: block SIGINT and SIGTERM (before any thread exists, so every thread inherits
 * the mask and only main's sigwait sees them); open the database once, which creates or migrates
 * it and refuses one that is not ctcsim's (exit 3); make the one store_health (store.h) that every
 * connection's writes report to and GET /api/health reads; start the workers, which re-queue the
 * jobs a previous run left queued or running and reserve disk for SQLite's log; start listening
 * (exit 4 when the address cannot be bound); print one line saying where. Shutdown: refuse new
 * jobs, stop the HTTP daemon (requests in flight finish), stop the workers (running jobs go back
 * to queued and restart at the next start), exit 0.
 */
#include <arpa/inet.h>
#include <errno.h>
#include <math.h>
#include <signal.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "http.h"
#include "jobq.h"
#include "pool.h"
#include "routes.h"
#include "store.h"
#include "store_pg.h"

enum { EXIT_BAD_SETTING = 2, EXIT_DATABASE = 3, EXIT_LISTEN = 4 };

#define MAX_WAIT 300.0 /* s, the largest ?wait= of POST /api/jobs */

/* The settings, as given or defaulted. */
typedef struct server_settings {
    const char *bind;
    long long port;
    const char *db;
    long long workers;
    long long job_threads; /* the most threads one job's dynamics may use */
    long long max_queue;
    long long max_body;        /* bytes */
    const char *token;         /* NULL = none */
    const char *token_file;    /* the token's file, NULL = none */
    const char *allowed_hosts; /* comma-separated; NULL = the default (http.h) */
    const char *web;
    const char *api;
    double job_time_limit; /* s, 0 = none */
    long long http_threads;
    long long idle_timeout;           /* s */
    long long max_connections;        /* open at once */
    long long max_per_ip;             /* open at once from one address */
    long long max_waiters;            /* POST /api/jobs?wait clients waiting at once */
    long long max_waiters_per_client; /* of which from one client address */
    long long max_jobs_per_client;    /* queued and running jobs of one client address */
    long long max_family;             /* members of one family (POST /api/families) */

    long long max_series_streams; /* large GET /api/jobs/{id}/series replies sent at once */
    long long db_max_size;        /* bytes the database may grow to; 0 = as the disk allows */
    const char *role;             /* "all", "api" or "worker" */
    double lease;                 /* s, a claimed job's lease (PostgreSQL) */
} server_settings;

typedef enum setting_kind {
    SETTING_TEXT,    /* any string */
    SETTING_ADDRESS, /* a numeric IPv4 or IPv6 address */
    SETTING_INTEGER, /* from min to max */
    SETTING_BYTES,   /* an integer with an optional K or M (KiB, MiB), from min to max */
    SETTING_SECONDS, /* a number of seconds from min to max */
} setting_kind;

typedef struct setting {
    const char *flag;
    const char *env; /* its environment variable, read before the flags */
    setting_kind kind;
    size_t offset; /* of the value in server_settings */
    long long min, max;
    const char *arg;  /* the value's name in --help */
    const char *help; /* what it sets; the default follows in --help */
} setting;

#define AT(field) offsetof(server_settings, field)

static const setting settings[] = {
    {"--bind", "CTCSIM_BIND", SETTING_ADDRESS, AT(bind), 0, 0, "ADDR",
     "address to listen on (numeric IPv4 or IPv6; 0.0.0.0 for all)"},
    {"--port", "CTCSIM_PORT", SETTING_INTEGER, AT(port), 0, 65535, "PORT",
     "port to listen on (0: any free port, printed at start)"},
    {"--db", "CTCSIM_DB", SETTING_TEXT, AT(db), 0, 0, "FILE|URL",
     "SQLite database of the jobs (created when absent), or a PostgreSQL database shared by "
     "several processes (postgres://user@host:port/dbname; its tables are created when absent)"},
    {"--role", "CTCSIM_ROLE", SETTING_TEXT, AT(role), 0, 0, "ROLE",
     "all (HTTP and workers), api (HTTP only) or worker (workers only); api and worker need a "
     "PostgreSQL --db"},
    {"--lease", "CTCSIM_LEASE", SETTING_SECONDS, AT(lease), 1, 86400, "SECONDS",
     "PostgreSQL: a running job's lease, renewed while it runs; a job whose worker died runs "
     "again elsewhere once it expires"},
    {"--workers", "CTCSIM_WORKERS", SETTING_INTEGER, AT(workers), 1, 1024, "N",
     "simulations run at once"},
    {"--job-threads", "CTCSIM_JOB_THREADS", SETTING_INTEGER, AT(job_threads), 1, CTC_MAX_THREADS,
     "N", "most threads one job's dynamics may use (its \"threads\"; more are refused with 400)"},
    {"--max-queue", "CTCSIM_MAX_QUEUE", SETTING_INTEGER, AT(max_queue), 1, 1000000, "N",
     "single jobs waiting at most (on PostgreSQL in the whole database, checked atomically "
     "with the insert); more are refused with 503"},
    {"--max-body", "CTCSIM_MAX_BODY", SETTING_BYTES, AT(max_body), 1024, 1LL << 30, "BYTES",
     "largest request body (suffix K or M for KiB, MiB)"},
    {"--token", "CTCSIM_TOKEN", SETTING_TEXT, AT(token), 0, 0, "TOKEN",
     "when set, POST and DELETE need \"Authorization: Bearer TOKEN\" (a flag shows in ps: "
     "prefer the variable or --token-file)"},
    {"--token-file", "CTCSIM_TOKEN_FILE", SETTING_TEXT, AT(token_file), 0, 0, "FILE",
     "read the token from FILE, once at start (one line; keep it mode 600)"},
    {"--allowed-hosts", "CTCSIM_ALLOWED_HOSTS", SETTING_TEXT, AT(allowed_hosts), 0, 0, "HOSTS",
     "names the Host header may give, comma-separated (* any); others: 421"},
    {"--web", "CTCSIM_WEB", SETTING_TEXT, AT(web), 0, 0, "DIR",
     "web root: the page as `make web` assembles it"},
    {"--api", "CTCSIM_API", SETTING_TEXT, AT(api), 0, 0, "DIR",
     "directory of openapi.yaml (served at /api/openapi.yaml)"},
    {"--job-time-limit", "CTCSIM_JOB_TIME_LIMIT", SETTING_SECONDS, AT(job_time_limit), 0, 1000000,
     "SECONDS", "wall time one job may take (0: no limit)"},
    {"--http-threads", "CTCSIM_HTTP_THREADS", SETTING_INTEGER, AT(http_threads), 1, 1024, "N",
     "threads answering HTTP requests"},
    {"--idle-timeout", "CTCSIM_IDLE_TIMEOUT", SETTING_INTEGER, AT(idle_timeout), 1, 86400,
     "SECONDS", "a connection silent this long is closed"},
    {"--max-connections", "CTCSIM_MAX_CONNECTIONS", SETTING_INTEGER, AT(max_connections), 1, 100000,
     "N", "connections open at once; more are closed when they open"},
    {"--max-connections-per-ip", "CTCSIM_MAX_CONNECTIONS_PER_IP", SETTING_INTEGER, AT(max_per_ip),
     1, 100000, "N", "connections open at once from one client address; more are closed"},
    {"--max-waiters", "CTCSIM_MAX_WAITERS", SETTING_INTEGER, AT(max_waiters), 1, 100000, "N",
     "POST /api/jobs?wait clients waiting at once; more get 202 at once"},
    {"--max-waiters-per-client", "CTCSIM_MAX_WAITERS_PER_CLIENT", SETTING_INTEGER,
     AT(max_waiters_per_client), 1, 100000, "N",
     "of those, waiting at once from one client address; more get 202 at once"},
    {"--max-jobs-per-client", "CTCSIM_MAX_JOBS_PER_CLIENT", SETTING_INTEGER,
     AT(max_jobs_per_client), 1, 1000000, "N",
     "jobs queued or running at once from one client address; more are refused with 429"},
    {"--max-family", "CTCSIM_MAX_FAMILY", SETTING_INTEGER, AT(max_family), 1, 1000000, "N",
     "members one family (POST /api/families) may have; a larger one is refused with 413"},
    {"--max-series-streams", "CTCSIM_MAX_SERIES_STREAMS", SETTING_INTEGER, AT(max_series_streams),
     1, 100000, "N", "large series replies (over 1048576 values) sent at once; more get 503"},
    {"--db-max-size", "CTCSIM_DB_MAX_SIZE", SETTING_BYTES, AT(db_max_size), 0, 1LL << 50, "BYTES",
     "SQLite only: largest size of the database file (0: as the disk allows); past it writes "
     "fail as on a full disk (503 DATABASE_FULL) and DELETE frees room"},
};

#define NSETTINGS (sizeof settings / sizeof settings[0])

/* The default of a setting as text, for --help. */
static void default_text(const setting *st, const server_settings *def, char *buf, size_t len)
{
    const char *base = (const char *)def + st->offset;
    switch (st->kind) {
    case SETTING_TEXT:
    case SETTING_ADDRESS: {
        const char *s = *(const char *const *)(const void *)base;
        snprintf(buf, len, "%s", s ? s : "none");
        break;
    }
    case SETTING_INTEGER:
    case SETTING_BYTES: {
        long long x = *(const long long *)(const void *)base;
        if (st->kind == SETTING_BYTES && x != 0 && x % (1024 * 1024) == 0)
            snprintf(buf, len, "%lldM", x / (1024 * 1024));
        else if (st->kind == SETTING_BYTES && x != 0 && x % 1024 == 0)
            snprintf(buf, len, "%lldK", x / 1024);
        else
            snprintf(buf, len, "%lld", x);
        break;
    }
    case SETTING_SECONDS:
        snprintf(buf, len, "%g", *(const double *)(const void *)base);
        break;
    }
}

static void print_help(const server_settings *def)
{
    printf("usage: ctcsim-server [OPTION ...]\n"
           "\n"
           "The ctcsim HTTP/JSON service: runs computed torque control simulations submitted\n"
           "as jobs (POST /api/jobs), stores them and their results in a database (an SQLite\n"
           "file for one process, or PostgreSQL shared by API and worker processes: --db,\n"
           "--role), and serves the web page. Every option also reads from its environment\n"
           "variable; a flag wins.\n"
           "\n");
    for (size_t i = 0; i < NSETTINGS; i++) {
        const setting *st = &settings[i];
        char flag[64], def_text[96];
        snprintf(flag, sizeof flag, "%s %s", st->flag, st->arg);
        default_text(st, def, def_text, sizeof def_text);
        if (st->offset == AT(workers) || st->offset == AT(job_threads)) { /* from the machine */
            const long long x = *(const long long *)(const void *)((const char *)def + st->offset);
            snprintf(def_text, sizeof def_text, "the online cores, %lld here", x);
        }
        if (st->offset == AT(allowed_hosts))
            snprintf(def_text, sizeof def_text,
                     "the bind address, localhost, 127.0.0.1, [::1]; any when bound to 0.0.0.0");
        printf("  %-26s %s\n  %-26s (default %s%s%s)\n", flag, st->help, "", def_text,
               st->env ? "; " : "", st->env ? st->env : "");
    }
    printf("  %-26s %s\n  %-26s %s\n", "--help", "print this and exit", "--version",
           "print the version and exit");
    printf("\n"
           "Stop it with SIGINT (Ctrl-C) or SIGTERM: running jobs are put back in the queue\n"
           "and start again at the next start.\n"
           "exit codes: 0 stopped by a signal, 2 bad option, 3 database error, 4 cannot listen\n");
}

/* Sets one setting from text; 0, or -1 after printing why (source names the flag or variable). */
static int set_value(const setting *st, const char *text, const char *source, server_settings *out)
{
    char *base = (char *)out + st->offset;
    char *end = NULL;
    switch (st->kind) {
    case SETTING_TEXT:
        *(const char **)(void *)base = text;
        return 0;
    case SETTING_ADDRESS: {
        unsigned char addr[16];
        if (inet_pton(AF_INET, text, addr) == 1 || inet_pton(AF_INET6, text, addr) == 1) {
            *(const char **)(void *)base = text;
            return 0;
        }
        fprintf(stderr, "ctcsim-server: %s must be a numeric IPv4 or IPv6 address (got \"%s\")\n",
                source, text);
        return -1;
    }
    case SETTING_INTEGER:
    case SETTING_BYTES: {
        errno = 0;
        long long x = strtoll(text, &end, 10);
        long long unit = 1;
        if (st->kind == SETTING_BYTES && (*end == 'K' || *end == 'k')) unit = 1024, end++;
        if (st->kind == SETTING_BYTES && (*end == 'M' || *end == 'm')) unit = 1024 * 1024, end++;
        int digits = end != text && text[0] >= '0' && text[0] <= '9';
        if (!digits || *end || errno == ERANGE || x > st->max / unit || x * unit < st->min) {
            if (st->kind == SETTING_BYTES)
                fprintf(stderr,
                        "ctcsim-server: %s must be a number of bytes from %lld to %lld, "
                        "with an optional K or M (got \"%s\")\n",
                        source, st->min, st->max, text);
            else
                fprintf(stderr,
                        "ctcsim-server: %s must be an integer from %lld to %lld (got \"%s\")\n",
                        source, st->min, st->max, text);
            return -1;
        }
        *(long long *)(void *)base = x * unit;
        return 0;
    }
    case SETTING_SECONDS: {
        double x = strtod(text, &end);
        if (end == text || *end || !isfinite(x) || x < (double)st->min || x > (double)st->max) {
            fprintf(stderr,
                    "ctcsim-server: %s must be a number of seconds from %lld to %lld (got "
                    "\"%s\")\n",
                    source, st->min, st->max, text);
            return -1;
        }
        *(double *)(void *)base = x;
        return 0;
    }
    }
    return -1;
}

/* Reads the environment, then the flags over it. Returns 0 to run, 1 when --help or --version
 * has been answered, -1 after printing what is wrong. */
static int read_settings(int argc, char **argv, server_settings *out)
{
    server_settings def = *out;
    for (size_t i = 0; i < NSETTINGS; i++) {
        const char *value = settings[i].env ? getenv(settings[i].env) : NULL;
        if (value && *value && set_value(&settings[i], value, settings[i].env, out) != 0) return -1;
    }
    for (int a = 1; a < argc; a++) {
        const char *arg = argv[a];
        if (strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0) {
            print_help(&def);
            return 1;
        }
        if (strcmp(arg, "--version") == 0) {
            printf("ctcsim-server " CTCSIM_VERSION "\n");
            return 1;
        }
        const setting *st = NULL;
        const char *value = NULL;
        for (size_t i = 0; i < NSETTINGS && !st; i++) {
            size_t n = strlen(settings[i].flag);
            if (strncmp(arg, settings[i].flag, n) != 0) continue;
            if (arg[n] == '=') st = &settings[i], value = arg + n + 1;
            if (arg[n] == 0) st = &settings[i];
        }
        if (!st) {
            fprintf(stderr, "ctcsim-server: unknown option \"%s\" (--help lists them)\n", arg);
            return -1;
        }
        if (!value) {
            if (a + 1 == argc) {
                fprintf(stderr, "ctcsim-server: %s needs a value (%s)\n", st->flag, st->arg);
                return -1;
            }
            value = argv[++a];
        }
        if (set_value(st, value, st->flag, out) != 0) return -1;
    }
    if (out->token && !out->token[0]) out->token = NULL;
    return 0;
}

/* The token of --token-file: the file's one line, its line end stripped, into a static buffer
 * (it lives as long as the process). 0, or -1 after printing why: unreadable, empty, too long,
 * more than one line, or given with --token as well. A file others may read is used with a
 * warning. */
static int read_token_file(server_settings *cfg)
{
    static char token[4097];
    const char *path = cfg->token_file;
    if (cfg->token) {
        fprintf(stderr, "ctcsim-server: give the token once: --token or --token-file, not both\n");
        return -1;
    }
    FILE *f = fopen(path, "rb");
    if (!f) {
        fprintf(stderr, "ctcsim-server: --token-file %s: %s\n", path, strerror(errno));
        return -1;
    }
    struct stat st;
    if (fstat(fileno(f), &st) == 0 && (st.st_mode & (S_IRGRP | S_IROTH)))
        fprintf(stderr,
                "ctcsim-server: warning: --token-file %s can be read by other users (chmod 600 "
                "it)\n",
                path);
    size_t n = fread(token, 1, sizeof token, f);
    int failed = ferror(f);
    fclose(f);
    if (failed) {
        fprintf(stderr, "ctcsim-server: --token-file %s: cannot read it\n", path);
        return -1;
    }
    if (n == sizeof token) {
        fprintf(stderr, "ctcsim-server: --token-file %s: longer than %zu bytes\n", path,
                sizeof token - 1);
        return -1;
    }
    if (n > 0 && token[n - 1] == '\n') n--;
    if (n > 0 && token[n - 1] == '\r') n--;
    token[n] = 0;
    if (n == 0) {
        fprintf(stderr, "ctcsim-server: --token-file %s is empty\n", path);
        return -1;
    }
    if (strlen(token) != n || strpbrk(token, "\r\n")) {
        fprintf(stderr, "ctcsim-server: --token-file %s must hold one line of text\n", path);
        return -1;
    }
    cfg->token = token;
    return 0;
}

/* "ctcsim-server: DB: why", naming the database once (the store's messages may name it) */
static void database_error(const char *db, const char *err)
{
    if (strstr(err, db))
        fprintf(stderr, "ctcsim-server: %s\n", err);
    else
        fprintf(stderr, "ctcsim-server: %s: %s\n", db, err);
}

int main(int argc, char **argv)
{
    long cores = sysconf(_SC_NPROCESSORS_ONLN);
    server_settings cfg = {
        .bind = "127.0.0.1",
        .port = 8080,
        .db = "ctcsim.db",
        .workers = cores >= 1 ? (cores <= 1024 ? cores : 1024) : 1,
        .job_threads = cores >= 1 ? (cores <= CTC_MAX_THREADS ? cores : CTC_MAX_THREADS) : 1,
        .max_queue = 1024,
        .max_body = 8 * 1024 * 1024,
        .token = NULL,
        .web = "build/web",
        .api = "api",
        .job_time_limit = 600,
        .http_threads = 4,
        .idle_timeout = 30,
        .max_connections = 1000,
        .max_per_ip = 64,
        .max_waiters = 256,
        .max_waiters_per_client = 16,
        .max_jobs_per_client = 64,
        .max_family = 10000,
        .max_series_streams = 4,
        .role = "all",
        .lease = 30,
    };
    int rc = read_settings(argc, argv, &cfg);
    if (rc != 0) return rc > 0 ? 0 : EXIT_BAD_SETTING;
    if (cfg.token_file && cfg.token_file[0] && read_token_file(&cfg) != 0) return EXIT_BAD_SETTING;
    int shared = store_pg_url(cfg.db);
    int serve_http = strcmp(cfg.role, "worker") != 0, run_workers = strcmp(cfg.role, "api") != 0;
    if (strcmp(cfg.role, "all") != 0 && strcmp(cfg.role, "api") != 0 &&
        strcmp(cfg.role, "worker") != 0) {
        fprintf(stderr, "ctcsim-server: --role must be all, api or worker (got \"%s\")\n",
                cfg.role);
        return EXIT_BAD_SETTING;
    }
    if (!shared && (!serve_http || !run_workers)) {
        fprintf(stderr,
                "ctcsim-server: --role %s needs a PostgreSQL database (--db postgres://...): "
                "an SQLite file is not shared between processes\n",
                cfg.role);
        return EXIT_BAD_SETTING;
    }
    if (shared && cfg.db_max_size > 0) {
        fprintf(stderr, "ctcsim-server: --db-max-size applies to SQLite only: PostgreSQL's size "
                        "is the database server's to limit\n");
        return EXIT_BAD_SETTING;
    }
    /* the database as messages show it: a URL's password is not printed */
    char shown[512];
    store_pg_redact(cfg.db, shown, sizeof shown);

    /* signals: SIGINT and SIGTERM for sigwait below, in every thread started from here on */
    sigset_t stop_signals;
    sigemptyset(&stop_signals);
    sigaddset(&stop_signals, SIGINT);
    sigaddset(&stop_signals, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stop_signals, NULL);
    struct sigaction ignore = {.sa_handler = SIG_IGN};
    sigaction(SIGPIPE, &ignore, NULL); /* a client gone mid-reply is not our death */

    /* the database: created, migrated and checked once, here */
    char err[512] = "";
    store *check = NULL;
    if (store_open(cfg.db, &check, err, sizeof err) != 0) {
        database_error(shown, err);
        return EXIT_DATABASE;
    }
    store_close(check);
    struct stat st;
    if (serve_http && (stat(cfg.web, &st) != 0 || !S_ISDIR(st.st_mode)))
        fprintf(stderr,
                "ctcsim-server: warning: web root %s is not a directory (pages answer 404)\n",
                cfg.web);

    /* the database's state as the writes see it, one for all threads */
    store_health *health = store_health_new();
    if (!health) {
        fprintf(stderr, "ctcsim-server: out of memory\n");
        return EXIT_DATABASE;
    }
    /* the workers, then the HTTP daemon; a job leaving the workers frees its client's place */
    routes_ctx ctx = {.db_path = cfg.db,
                      .api_dir = cfg.api,
                      .max_wait = MAX_WAIT,
                      .job_threads = (int)cfg.job_threads,
                      .jobs_by_client = client_count_new(),
                      .max_jobs_per_client = (unsigned)cfg.max_jobs_per_client,
                      .max_queue = (long)cfg.max_queue,
                      .max_family = (long)cfg.max_family,
                      .max_series_streams = (int)cfg.max_series_streams,
                      .db_max_size = cfg.db_max_size,
                      .health = health};
    if (!ctx.jobs_by_client) {
        store_health_free(health);
        fprintf(stderr, "ctcsim-server: out of memory\n");
        return EXIT_DATABASE;
    }
    jobq_config qc = {.db_path = cfg.db,
                      .workers = run_workers ? (int)cfg.workers : 0,
                      .lease_s = cfg.lease,
                      .listen = serve_http,
                      .max_queue = (int)cfg.max_queue,
                      .job_time_limit = cfg.job_time_limit,
                      .db_max_size = cfg.db_max_size,
                      .health = health,
                      .left = routes_job_left,
                      .left_arg = &ctx};
    jobq *queue = NULL;
    if (jobq_start(&qc, &queue, err, sizeof err) != 0) {
        database_error(shown, err);
        client_count_free(ctx.jobs_by_client);
        store_health_free(health);
        return EXIT_DATABASE;
    }
    ctx.queue = queue;
    http_config hc = {.bind = cfg.bind,
                      .port = (int)cfg.port,
                      .threads = (int)cfg.http_threads,
                      .max_body = (size_t)cfg.max_body,
                      .web_root = cfg.web,
                      .token = cfg.token,
                      .allowed_hosts = cfg.allowed_hosts,
                      .idle_timeout = (unsigned)cfg.idle_timeout,
                      .max_connections = (unsigned)cfg.max_connections,
                      .max_per_ip = (unsigned)cfg.max_per_ip,
                      .max_deferred = (unsigned)cfg.max_waiters,
                      .max_deferred_per_client = (unsigned)cfg.max_waiters_per_client,
                      .routes = routes_table,
                      .ctx = &ctx};
    http_server *http = NULL;
    if (!serve_http) {
        fprintf(stderr,
                "ctcsim-server " CTCSIM_VERSION " worker: %lld worker%s, database %s, lease %g s\n",
                cfg.workers, cfg.workers == 1 ? "" : "s", shown, cfg.lease);
        fflush(stderr);
    } else if (http_start(&hc, &http, err, sizeof err) != 0) {
        fprintf(stderr, "ctcsim-server: %s\n", err);
        jobq_stop(queue);
        client_count_free(ctx.jobs_by_client);
        store_health_free(health);
        return EXIT_LISTEN;
    }
    int v6 = strchr(cfg.bind, ':') != NULL;
    if (http) {
        long long nw = run_workers ? cfg.workers : 0;
        fprintf(stderr,
                "ctcsim-server " CTCSIM_VERSION " listening on http://%s%s%s:%d (%lld worker%s, "
                "database %s)\n",
                v6 ? "[" : "", cfg.bind, v6 ? "]" : "", http_port(http), nw, nw == 1 ? "" : "s",
                shown);
        fflush(stderr);
    }

    /* until SIGINT or SIGTERM */
    int sig = 0;
    while (sigwait(&stop_signals, &sig) != 0) continue;

    atomic_store(&ctx.stopping, 1);
    http_stop(http);
    jobq_stop(queue);
    client_count_free(ctx.jobs_by_client);
    /* the HTTP threads' connections closed with their threads, the workers' with the queue */
    store_health_free(health);
    fprintf(stderr, "ctcsim-server: stopped\n");
    return 0;
}
