/*
 * store_common.c - the argument checks and state messages that the SQLite store (store.c) and
 * the PostgreSQL store (store_pg.c) share (store_common.h). The messages are the service's
 * (routes.c passes them on in 503 and 500 replies and the workers log them), so one text per
 * fault, whichever backend met it.
 */
#include "store_common.h"

#include <stdarg.h>
#include <stdio.h>

#define set_err store_set_err

void store_set_err(char *err, size_t errlen, const char *fmt, ...)
{
    if (!err || errlen == 0) return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

int store_check_job(const char *name, const char *controller, const char *spec, int nbodies, int nv,
                    char *err, size_t errlen)
{
    if (!name || !controller || !spec) {
        set_err(err, errlen, "cannot store a job without %s",
                !name         ? "a name"
                : !controller ? "a controller"
                              : "a spec");
        return -1;
    }
    if (nbodies < 1 || nv < 0) {
        set_err(err, errlen, "cannot store a job of %d bodies and %d coordinates", nbodies, nv);
        return -1;
    }
    return 0;
}

int store_check_finish(int64_t id, store_status status, const ctc_sim_result *r, char *err,
                       size_t errlen)
{
    if (status < STORE_DONE || status >= STORE_NSTATUS) {
        set_err(err, errlen,
                "cannot finish job %lld as %s: the status must be done, failed, diverged or "
                "cancelled",
                (long long)id, store_status_name(status));
        return -1;
    }
    if (r && r->nsamples < 0) {
        set_err(err, errlen, "cannot finish job %lld: the result has %d samples", (long long)id,
                r->nsamples);
        return -1;
    }
    if (r && r->nsamples > 0 && !r->t) {
        set_err(err, errlen, "cannot finish job %lld: the result has samples but no times",
                (long long)id);
        return -1;
    }
    return 0;
}

int store_check_limit(int limit, char *err, size_t errlen)
{
    if (limit < 1 || limit > STORE_MAX_LIST) {
        set_err(err, errlen, "limit must be between 1 and %d (got %d)", STORE_MAX_LIST, limit);
        return -1;
    }
    return 0;
}

int store_check_list(int64_t before, int status, int limit, char *err, size_t errlen)
{
    if (store_check_limit(limit, err, errlen) != 0) return -1;
    if (before < 0) {
        set_err(err, errlen, "before must be 0 or a job id (got %lld)", (long long)before);
        return -1;
    }
    if (status < -1 || status >= STORE_NSTATUS) {
        set_err(err, errlen, "unknown job status %d", status);
        return -1;
    }
    return 0;
}

int store_check_family(const char *name, const char *spec, const char *axes, long n, char *err,
                       size_t errlen)
{
    if (!name || !spec || !axes || n < 0) {
        set_err(err, errlen, "cannot store a family without a name, a spec and its axes");
        return -1;
    }
    return 0;
}

/* the cases both messages share; 1 when one of them was written */
static int unchanged_err(int64_t id, const char *what, int found, store_status st, char *err,
                         size_t errlen)
{
    if (found == 1) {
        set_err(err, errlen, "cannot %s job %lld: no such job", what, (long long)id);
        return 1;
    }
    if (found == 0 && st == STORE_RUNNING) {
        set_err(err, errlen, "cannot %s job %lld: another worker holds it", what, (long long)id);
        return 1;
    }
    return found != 0; /* -1: err says why already */
}

void store_not_running_err(int64_t id, const char *what, int found, store_status st, char *err,
                           size_t errlen)
{
    if (!unchanged_err(id, what, found, st, err, errlen))
        set_err(err, errlen, "cannot %s job %lld: it is %s, not running", what, (long long)id,
                store_status_name(st));
}

void store_not_finishable_err(int64_t id, int found, store_status st, char *err, size_t errlen)
{
    if (!unchanged_err(id, "finish", found, st, err, errlen))
        set_err(err, errlen, "cannot finish job %lld: it is already %s", (long long)id,
                store_status_name(st));
}
