/*
 * store_common.h - what the two stores check and say alike: the SQLite store (store.c) and the
 * PostgreSQL one (store_pg.c) take the same arguments through store.h, so they refuse the same
 * bad ones with the same messages, and explain an update that found its job in the wrong state
 * in the same words. Only backend-independent checks live here: nothing in this file touches a
 * database. Used by store.c and store_pg.c only (not part of store.h's interface).
 *
 * Each check returns 0 when the arguments are good, or -1 with the message in err (errlen bytes,
 * truncated to fit; err may be NULL). Thread-safe: no state.
 */
#ifndef STORE_COMMON_H
#define STORE_COMMON_H

#include <stddef.h>
#include <stdint.h>

#include "store.h"

#define STORE_MAX_LIST 1000 /* rows one list or search returns at most */

/* Writes printf's text of fmt into err (errlen bytes, truncated to fit); nothing when err is
 * NULL or errlen 0. The one way both stores fill their err. */
void store_set_err(char *err, size_t errlen, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* A job to insert: its name, controller and spec present ("cannot store a job without a name"),
 * at least one body and no negative coordinate count. */
int store_check_job(const char *name, const char *controller, const char *spec, int nbodies, int nv,
                    char *err, size_t errlen);

/* A job's final status (done, failed, diverged or cancelled) and its result r (NULL allowed: no
 * series): a sample count >= 0, and times when there are samples. */
int store_check_finish(int64_t id, store_status status, const ctc_sim_result *r, char *err,
                       size_t errlen);

/* A page's size: 1 .. STORE_MAX_LIST. */
int store_check_limit(int limit, char *err, size_t errlen);

/* A list's or a search's arguments: limit as store_check_limit, before 0 (the newest) or an id,
 * status -1 (any) or a store_status. */
int store_check_list(int64_t before, int status, int limit, char *err, size_t errlen);

/* A family to insert: its name, spec and axes present, n >= 0 members. */
int store_check_family(const char *name, const char *spec, const char *axes, long n, char *err,
                       size_t errlen);

/* Why an update of job id that needs it running changed nothing, from the status read after it:
 * found is that read's result (1 no such job, 0 read into st, -1 err already says why), what the
 * update ("record progress of"): "cannot WHAT job 3: no such job", "...: another worker holds
 * it" (running under another claim), "...: it is done, not running". */
void store_not_running_err(int64_t id, const char *what, int found, store_status st, char *err,
                           size_t errlen);

/* The same for store_finish, which needs the job queued or running under this claim: "cannot
 * finish job 3: no such job", "...: another worker holds it", "...: it is already done". */
void store_not_finishable_err(int64_t id, int found, store_status st, char *err, size_t errlen);

#endif
