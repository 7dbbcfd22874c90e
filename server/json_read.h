/*
 * json_read.h - the job format's JSON reader: typed reads of cJSON values that name the JSON path
 * of every error, key checks (unknown keys with the nearest valid one, keys repeated in one
 * object), and the writers of the normalised document.
 *
 * Nothing here knows what a job contains: the scene, controller and run parts of the format
 * (job_scene.c, job_json.c, job_run.c) say which keys an object has and what they mean, and call
 * these helpers to read them. Each reader takes the parse's state p (job_parse.h), of which it
 * uses only p->err (the error it fills) and p->oom (set when the normalised document could not
 * grow).
 *
 * Conventions. A path is the JSON path of a value as errors show it: "scene.bodies[2].mass", ""
 * for the document itself; paths longer than PATH_LEN - 1 bytes end in "...". Readers return 0,
 * or -1 with p->err filled (the first error wins: a caller stops at the first -1). Messages say
 * what the value must be and what it was: "must be a number (got a string)", "must have 3 to 16
 * entries (got 20)". Numbers must be finite. Codes: JOB_MISSING_FIELD for an absent required key,
 * JOB_UNKNOWN_FIELD for a key the object does not have, JOB_INVALID_FIELD for every wrong type or
 * value, JOB_NO_MEMORY ("out of memory", field "") for a failed allocation.
 *
 * The writers (put_*) add to the normalised document and never fail loudly: a failed allocation
 * sets p->oom, and the parse reports it at the end; adding below a NULL parent does nothing.
 *
 * Thread safety: none of these keeps state; any number of parses may run at once.
 */
#ifndef JSON_READ_H
#define JSON_READ_H

#include <stddef.h>

#include <cjson/cJSON.h>

#include "job_json.h"

#define PATH_LEN 256 /* bytes of a JSON path, with its terminating zero (job_error.field) */

enum { OPTIONAL = 0, REQUIRED = 1 }; /* the required argument of the member_* readers */

typedef struct parser parser; /* the state of one parse (job_parse.h) */

/* ---- errors and paths ---- */

/* Fills err (code, field, printf-style message) and returns -1. */
int json_error_at(job_error *err, job_error_code code, const char *field, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* Fills err with JOB_NO_MEMORY, field "", "out of memory", and returns -1. */
int json_out_of_memory(job_error *err);

/* out = "path.key", or "key" alone at the root (path ""); returns out. */
const char *json_key_path(char out[PATH_LEN], const char *path, const char *key);

/* out = "path[i]"; returns out. */
const char *json_index_path(char out[PATH_LEN], const char *path, int i);

/* What a JSON value is, for "(got ...)": "a number", "an array", "null", "nothing" for NULL. */
const char *json_kind(const cJSON *v);

/* json_kind(v), or for an array its size written into buf ("3 entries", "1 entry"); returns either.
 */
const char *json_describe(char buf[32], const cJSON *v);

/* Checks that every key of object obj (at path; NULL, an absent object, passes) is in allowed
 * (NULL-terminated). The first key that is not is an error, JOB_UNKNOWN_FIELD at path.key: "key
 * \"K\" does not apply to <context>" when K is in known (the keys of another type of the same
 * kind; known may be NULL), otherwise "unknown key \"K\" (did you mean \"A\"?)" when an allowed
 * key A is within 2 edits of K (1 for keys of up to 3 letters), otherwise "unknown key \"K\"". */
int json_check_keys(parser *p, const cJSON *obj, const char *path, const char *const *allowed,
                    const char *const *known, const char *context);

/* Rejects a key repeated in any object of the document v (at path), depth first in document
 * order: JOB_INVALID_FIELD at path.key, "key \"K\" appears more than once" (cJSON keeps both
 * copies, and the format must not guess which one was meant). Objects of more than 16 keys are
 * checked in O(n log n); NO_MEMORY when the sort's array cannot be allocated. */
int json_check_repeated_keys(job_error *err, const cJSON *v, const char *path);

/* ---- reading values ---- */

/* obj[key], matched case-sensitively, or NULL (also for a NULL obj). */
const cJSON *json_member(const cJSON *obj, const char *key);

/* calloc(max(n, 1), size), or NULL with NO_MEMORY in p->err. The caller frees it. */
void *json_alloc(parser *p, size_t n, size_t size);

/* v must be an object: "must be an object (got ...)" otherwise. */
int json_object_at(parser *p, const cJSON *v, const char *path);

/* obj[key] (obj at path), or NULL with MISSING_FIELD at path.key: "is required<hint>" (hint is
 * appended as given, e.g. " (or give a \"shape\")", or ""). */
const cJSON *json_required_member(parser *p, const cJSON *obj, const char *path, const char *key,
                                  const char *hint);

/* *out = v, a finite number: "must be a number (got ...)", "must be finite (got inf)". */
int json_number_at(parser *p, const cJSON *v, const char *path, double *out);

/* *out = obj[key] (obj at path, may be NULL) as a finite number; when absent, def, or
 * MISSING_FIELD "is required" at path.key when required (REQUIRED). */
int json_member_number(parser *p, const cJSON *obj, const char *path, const char *key, int required,
                       double def, double *out);

/* The entries of array v (at path), each a finite number, into out (one per entry; the caller
 * sized it). An entry's error is at path[i]. */
int json_numbers_in(parser *p, const cJSON *v, const char *path, double *out);

/* out = v, an array of exactly 3 finite numbers: "must be an array of 3 numbers (got ...)". */
int json_vec3_at(parser *p, const cJSON *v, const char *path, double out[3]);

/* out = obj[key] (obj at path, may be NULL) as an array of 3 finite numbers; when absent, def
 * (3 numbers; may be NULL when required) or MISSING_FIELD when required. */
int json_member_vec3(parser *p, const cJSON *obj, const char *path, const char *key, int required,
                     const double def[3], double out[3]);

/* v: an array of lo..hi finite numbers; *out (allocated here, freed by the caller, also after an
 * error) and *n its length. "must be an array of numbers", "must have lo to hi entries". */
int json_number_list_at(parser *p, const cJSON *v, const char *path, int lo, int hi, double **out,
                        int *n);

/* v: an array of exactly n finite numbers, one per what ("coordinate", ...), into out:
 * "must be an array of n numbers, one per <what>", "must have n entries, one per <what>". */
int json_coords_at(parser *p, const cJSON *v, const char *path, int n, const char *what,
                   double *out);

/* A 3x3 matrix into out (row-major): an array of 3 rows of 3 numbers, or an array of its 3
 * diagonal entries (*diagonal set, off-diagonal zero); what names the diagonal form in the
 * message ("principal moments"). */
int json_matrix3_at(parser *p, const cJSON *v, const char *path, const char *what, double out[9],
                    int *diagonal);

/* *out = v's text (kept in v), a string of 1..JOB_MAX_NAME bytes. */
int json_name_at(parser *p, const cJSON *v, const char *path, const char **out);

/* *out = the index of string v in names (count of them): "must be one of \"a\", \"b\" (got
 * \"c\")". */
int json_enum_at(parser *p, const cJSON *v, const char *path, const char *const *names, int count,
                 int *out);

/* Reads the type of a typed object v (at path; NULL, an absent object, leaves *type = def):
 * v must be an object whose keys are all in all_keys (the keys of every type of its kind);
 * v[type_key] is one of names (count of them; MISSING_FIELD when absent and required, def when
 * absent and optional); then v's keys must apply to that type (keys_by_type[*type], indexed like
 * names), "does not apply to <what> \"<name>\"" otherwise. */
int json_typed_object(parser *p, const cJSON *v, const char *path, const char *type_key,
                      int required, int def, const char *const *names, int count, const char *what,
                      const char *const *const *keys_by_type, const char *const *all_keys,
                      int *type);

/* *out = v, true (1) or false (0): "must be true or false (got ...)". */
int json_bool_at(parser *p, const cJSON *v, const char *path, int *out);

/* ---- writing the normalised document ---- */

/* Adds item to obj under key (or at the end of array obj when key is NULL) and returns it. When
 * item or obj is NULL or the add fails, deletes item, sets p->oom and returns NULL. */
cJSON *json_put(parser *p, cJSON *obj, const char *key, cJSON *item);

/* json_put() of a number, a string (copied), an array of n numbers ([] for n = 0). */
void json_put_number(parser *p, cJSON *obj, const char *key, double x);
void json_put_string(parser *p, cJSON *obj, const char *key, const char *s);
void json_put_numbers(parser *p, cJSON *obj, const char *key, const double *x, int n);

/* json_put() of a 3x3 matrix (row-major m) as its diagonal or as 3 rows, as matrix3_at read it. */
void json_put_matrix3(parser *p, cJSON *obj, const char *key, const double m[9], int diagonal);

#endif
