/*
 * json_read.c - the job format's JSON reader (json_read.h): typed reads with the JSON path of
 * every error, unknown and repeated keys, and the writers of the normalised document.
 *
 * A misspelt key is reported with the nearest valid key by edit distance (Levenshtein, keys of up
 * to 32 bytes), so "masss" says "did you mean \"mass\"?". Repeated keys are found pairwise in
 * small objects and by sorting in large ones (a body array's objects are small; a hostile
 * document's may not be). Error messages say what the value must be and what it was.
 */
#include "json_read.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_parse.h"

#define SMALL_OBJECT 16 /* objects up to this many keys are scanned pairwise */

/* ---- errors and paths ---- */

/* Fills err (code, field, printf-style message) and returns -1. */
int json_error_at(job_error *err, job_error_code code, const char *field, const char *fmt, ...)
{
    va_list ap;
    err->code = code;
    snprintf(err->field, sizeof err->field, "%s", field);
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return -1;
}

int json_out_of_memory(job_error *err)
{
    return json_error_at(err, JOB_NO_MEMORY, "", "out of memory");
}

/* a path cut to fit ends in "..." */
static void mark_cut(char out[PATH_LEN], int written)
{
    if (written < 0 || written >= PATH_LEN) memcpy(out + PATH_LEN - 4, "...", 4);
}

/* out = path.key, or key alone at the root (path ""); returns out */
const char *json_key_path(char out[PATH_LEN], const char *path, const char *key)
{
    int n = path[0] == '\0' ? snprintf(out, PATH_LEN, "%s", key)
                            : snprintf(out, PATH_LEN, "%s.%s", path, key);
    mark_cut(out, n);
    return out;
}

/* out = path[i]; returns out */
const char *json_index_path(char out[PATH_LEN], const char *path, int i)
{
    mark_cut(out, snprintf(out, PATH_LEN, "%s[%d]", path, i));
    return out;
}

/* what a JSON value is, for "(got ...)" */
const char *json_kind(const cJSON *v)
{
    if (v == NULL) return "nothing";
    if (cJSON_IsNull(v)) return "null";
    if (cJSON_IsBool(v)) return "a boolean";
    if (cJSON_IsNumber(v)) return "a number";
    if (cJSON_IsString(v)) return "a string";
    if (cJSON_IsArray(v)) return "an array";
    if (cJSON_IsObject(v)) return "an object";
    return "an invalid value";
}

/* json_kind(v), or for an array its number of entries */
const char *json_describe(char buf[32], const cJSON *v)
{
    if (!cJSON_IsArray(v)) return json_kind(v);
    int n = cJSON_GetArraySize(v);
    snprintf(buf, 32, "%d %s", n, n == 1 ? "entry" : "entries");
    return buf;
}

static int in_list(const char *const *list, const char *s)
{
    for (; *list != NULL; list++) {
        if (strcmp(*list, s) == 0) return 1;
    }
    return 0;
}

/* Levenshtein distance of two short keys (99 for long ones) */
static int edit_distance(const char *a, const char *b)
{
    enum { MAX_KEY = 32 };
    size_t la = strlen(a), lb = strlen(b);
    if (la > MAX_KEY || lb > MAX_KEY) return 99;
    int row[MAX_KEY + 1];
    for (size_t j = 0; j <= lb; j++) row[j] = (int)j;
    for (size_t i = 1; i <= la; i++) {
        int diag = row[0];
        row[0] = (int)i;
        for (size_t j = 1; j <= lb; j++) {
            int up = row[j];
            int best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best) best = up + 1;
            if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[lb];
}

/* the allowed key nearest to key when it is a likely typo of it, else NULL */
static const char *nearest_key(const char *key, const char *const *allowed)
{
    const char *best = NULL;
    int best_d = 3;
    for (; *allowed != NULL; allowed++) {
        int d = edit_distance(key, *allowed);
        int most = strlen(*allowed) <= 3 ? 1 : 2;
        if (d <= most && d < best_d) {
            best = *allowed;
            best_d = d;
        }
    }
    return best;
}

/* Checks that every key of obj (at path; NULL is an absent object) is in allowed. A key in known
 * but not in allowed belongs to another type of the same kind: "does not apply to <context>". */
int json_check_keys(parser *p, const cJSON *obj, const char *path, const char *const *allowed,
                    const char *const *known, const char *context)
{
    if (obj == NULL) return 0;
    for (const cJSON *c = obj->child; c != NULL; c = c->next) {
        if (in_list(allowed, c->string)) continue;
        char at[PATH_LEN];
        json_key_path(at, path, c->string);
        if (known != NULL && in_list(known, c->string)) {
            return json_error_at(p->err, JOB_UNKNOWN_FIELD, at, "key \"%s\" does not apply to %s",
                                 c->string, context);
        }
        const char *hint = nearest_key(c->string, allowed);
        if (hint != NULL) {
            return json_error_at(p->err, JOB_UNKNOWN_FIELD, at,
                                 "unknown key \"%s\" (did you mean \"%s\"?)", c->string, hint);
        }
        return json_error_at(p->err, JOB_UNKNOWN_FIELD, at, "unknown key \"%s\"", c->string);
    }
    return 0;
}

static int compare_keys(const void *a, const void *b)
{
    return strcmp(*(const char *const *)a, *(const char *const *)b);
}

/* the first key of object v that appears twice in it, or NULL (out of memory: *oom set) */
static const char *repeated_key(const cJSON *v, int *oom)
{
    int n = cJSON_GetArraySize(v);
    if (n <= SMALL_OBJECT) {
        for (const cJSON *a = v->child; a != NULL; a = a->next) {
            for (const cJSON *b = a->next; b != NULL; b = b->next) {
                if (strcmp(a->string, b->string) == 0) return a->string;
            }
        }
        return NULL;
    }

    /* many keys: sort them, so the scan stays O(n log n) */
    const char **keys = malloc((size_t)n * sizeof *keys);
    if (keys == NULL) {
        *oom = 1;
        return NULL;
    }
    int i = 0;
    for (const cJSON *a = v->child; a != NULL; a = a->next) keys[i++] = a->string;
    qsort(keys, (size_t)n, sizeof *keys, compare_keys);
    const char *found = NULL;
    for (i = 1; i < n && found == NULL; i++) {
        if (strcmp(keys[i - 1], keys[i]) == 0) found = keys[i];
    }
    free(keys);
    return found;
}

/* Rejects a key repeated in any object of the document v (at path): cJSON keeps both, and the
 * format must not guess which one was meant. */
int json_check_repeated_keys(job_error *err, const cJSON *v, const char *path)
{
    char at[PATH_LEN];
    if (cJSON_IsObject(v)) {
        int oom = 0;
        const char *key = repeated_key(v, &oom);
        if (oom) return json_out_of_memory(err);
        if (key != NULL) {
            return json_error_at(err, JOB_INVALID_FIELD, json_key_path(at, path, key),
                                 "key \"%s\" appears more than once", key);
        }
        for (const cJSON *c = v->child; c != NULL; c = c->next) {
            if (json_check_repeated_keys(err, c, json_key_path(at, path, c->string)) != 0)
                return -1;
        }
    } else if (cJSON_IsArray(v)) {
        int i = 0;
        for (const cJSON *c = v->child; c != NULL; c = c->next, i++) {
            if (json_check_repeated_keys(err, c, json_index_path(at, path, i)) != 0) return -1;
        }
    }
    return 0;
}

/* ---- reading values ---- */

const cJSON *json_member(const cJSON *obj, const char *key)
{
    return cJSON_GetObjectItemCaseSensitive(obj, key);
}

void *json_alloc(parser *p, size_t n, size_t size)
{
    void *x = calloc(n > 0 ? n : 1, size);
    if (x == NULL) json_out_of_memory(p->err);
    return x;
}

int json_object_at(parser *p, const cJSON *v, const char *path)
{
    if (cJSON_IsObject(v)) return 0;
    return json_error_at(p->err, JOB_INVALID_FIELD, path, "must be an object (got %s)",
                         json_kind(v));
}

/* obj[key], which must be present ("is required" otherwise, with an optional hint) */
const cJSON *json_required_member(parser *p, const cJSON *obj, const char *path, const char *key,
                                  const char *hint)
{
    const cJSON *v = json_member(obj, key);
    if (v == NULL) {
        char at[PATH_LEN];
        json_error_at(p->err, JOB_MISSING_FIELD, json_key_path(at, path, key), "is required%s",
                      hint);
    }
    return v;
}

/* *out = v, a finite number */
int json_number_at(parser *p, const cJSON *v, const char *path, double *out)
{
    if (!cJSON_IsNumber(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path, "must be a number (got %s)",
                             json_kind(v));
    }
    if (!isfinite(v->valuedouble)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path, "must be finite (got %g)",
                             v->valuedouble);
    }
    *out = v->valuedouble;
    return 0;
}

/* *out = obj[key] (obj at path) as a finite number; when absent, def or an error if required */
int json_member_number(parser *p, const cJSON *obj, const char *path, const char *key, int required,
                       double def, double *out)
{
    char at[PATH_LEN];
    const cJSON *v = json_member(obj, key);
    if (v == NULL) {
        if (required)
            return json_error_at(p->err, JOB_MISSING_FIELD, json_key_path(at, path, key),
                                 "is required");
        *out = def;
        return 0;
    }
    return json_number_at(p, v, json_key_path(at, path, key), out);
}

/* the entries of array v (at path), each a finite number, into out */
int json_numbers_in(parser *p, const cJSON *v, const char *path, double *out)
{
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        char at[PATH_LEN];
        if (json_number_at(p, e, json_index_path(at, path, i), &out[i]) != 0) return -1;
    }
    return 0;
}

/* out = v, an array of 3 finite numbers */
int json_vec3_at(parser *p, const cJSON *v, const char *path, double out[3])
{
    char got[32];
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must be an array of 3 numbers (got %s)", json_describe(got, v));
    }
    return json_numbers_in(p, v, path, out);
}

/* out = obj[key] as an array of 3 finite numbers; when absent, def or an error if required */
int json_member_vec3(parser *p, const cJSON *obj, const char *path, const char *key, int required,
                     const double def[3], double out[3])
{
    char at[PATH_LEN];
    const cJSON *v = json_member(obj, key);
    json_key_path(at, path, key);
    if (v == NULL) {
        if (required) return json_error_at(p->err, JOB_MISSING_FIELD, at, "is required");
        memcpy(out, def, 3 * sizeof *out);
        return 0;
    }
    return json_vec3_at(p, v, at, out);
}

/* v: an array of lo..hi finite numbers; *out (freed by the caller) and *n */
int json_number_list_at(parser *p, const cJSON *v, const char *path, int lo, int hi, double **out,
                        int *n)
{
    if (!cJSON_IsArray(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must be an array of numbers (got %s)", json_kind(v));
    }
    *n = cJSON_GetArraySize(v);
    if (*n < lo || *n > hi) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path, "must have %d to %d entries (got %d)",
                             lo, hi, *n);
    }
    *out = json_alloc(p, (size_t)*n, sizeof **out);
    if (*out == NULL) return -1;
    return json_numbers_in(p, v, path, *out);
}

/* v: an array of n finite numbers, one per coordinate (what: "coordinate", ...) */
int json_coords_at(parser *p, const cJSON *v, const char *path, int n, const char *what,
                   double *out)
{
    if (!cJSON_IsArray(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must be an array of %d numbers, one per %s (got %s)", n, what,
                             json_kind(v));
    }
    int len = cJSON_GetArraySize(v);
    if (len != n) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must have %d entries, one per %s (got %d)", n, what, len);
    }
    return json_numbers_in(p, v, path, out);
}

/* A 3x3 matrix (row-major into out): an array of 3 rows of 3 numbers, or an array of its 3
 * diagonal entries (*diagonal set; what names them in messages, e.g. "principal moments"). */
int json_matrix3_at(parser *p, const cJSON *v, const char *path, const char *what, double out[9],
                    int *diagonal)
{
    char got[32], at[PATH_LEN];
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must be a 3x3 array of rows or an array of 3 %s (got %s)", what,
                             json_describe(got, v));
    }
    memset(out, 0, 9 * sizeof *out);
    *diagonal = !cJSON_IsArray(v->child);
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        json_index_path(at, path, i);
        if (*diagonal ? json_number_at(p, e, at, &out[4 * i])
                      : json_vec3_at(p, e, at, &out[3 * i])) {
            return -1;
        }
    }
    return 0;
}

/* v: a string of 1..JOB_MAX_NAME bytes */
int json_name_at(parser *p, const cJSON *v, const char *path, const char **out)
{
    if (!cJSON_IsString(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path, "must be a string (got %s)",
                             json_kind(v));
    }
    size_t len = strlen(v->valuestring);
    if (len == 0) return json_error_at(p->err, JOB_INVALID_FIELD, path, "must not be empty");
    if (len > JOB_MAX_NAME) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must be at most %d bytes long (got %zu)", JOB_MAX_NAME, len);
    }
    *out = v->valuestring;
    return 0;
}

/* *out = the index of string v in names (count of them) */
int json_enum_at(parser *p, const cJSON *v, const char *path, const char *const *names, int count,
                 int *out)
{
    if (!cJSON_IsString(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path, "must be a string (got %s)",
                             json_kind(v));
    }
    for (int i = 0; i < count; i++) {
        if (strcmp(v->valuestring, names[i]) == 0) {
            *out = i;
            return 0;
        }
    }
    char list[320] = "";
    size_t used = 0;
    for (int i = 0; i < count; i++) {
        int w = snprintf(list + used, sizeof list - used, "%s\"%s\"", i > 0 ? ", " : "", names[i]);
        if (w < 0 || (size_t)w >= sizeof list - used) break;
        used += (size_t)w;
    }
    return json_error_at(p->err, JOB_INVALID_FIELD, path, "must be one of %s (got \"%s\")", list,
                         v->valuestring);
}

/* Reads the type of a typed object v (at path; NULL: absent, the type is def): checks v's keys
 * against all_keys of its kind, reads type_key, then checks the keys apply to that type
 * (keys_by_type[type]). what names the kind in messages ("joint type", "method"). */
int json_typed_object(parser *p, const cJSON *v, const char *path, const char *type_key,
                      int required, int def, const char *const *names, int count, const char *what,
                      const char *const *const *keys_by_type, const char *const *all_keys,
                      int *type)
{
    char at[PATH_LEN], context[64];
    *type = def;
    if (v == NULL) return 0;
    if (json_object_at(p, v, path) != 0 || json_check_keys(p, v, path, all_keys, NULL, NULL) != 0)
        return -1;
    const cJSON *t = json_member(v, type_key);
    json_key_path(at, path, type_key);
    if (t == NULL && required) return json_error_at(p->err, JOB_MISSING_FIELD, at, "is required");
    if (t != NULL && json_enum_at(p, t, at, names, count, type) != 0) return -1;
    snprintf(context, sizeof context, "%s \"%s\"", what, names[*type]);
    return json_check_keys(p, v, path, keys_by_type[*type], all_keys, context);
}

/* *out = v, true or false */
int json_bool_at(parser *p, const cJSON *v, const char *path, int *out)
{
    if (!cJSON_IsBool(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path, "must be true or false (got %s)",
                             json_kind(v));
    }
    *out = cJSON_IsTrue(v);
    return 0;
}

/* ---- writing the normalised document ---- */

/* Adds item to obj under key (or at the end of array obj when key is NULL) and returns it; on
 * any failure deletes item, remembers it and returns NULL (adds below a NULL fail quietly). */
cJSON *json_put(parser *p, cJSON *obj, const char *key, cJSON *item)
{
    int ok =
        item != NULL && obj != NULL &&
        (key != NULL ? cJSON_AddItemToObject(obj, key, item) : cJSON_AddItemToArray(obj, item));
    if (!ok) {
        cJSON_Delete(item);
        p->oom = 1;
        return NULL;
    }
    return item;
}

void json_put_number(parser *p, cJSON *obj, const char *key, double x)
{
    json_put(p, obj, key, cJSON_CreateNumber(x));
}

void json_put_string(parser *p, cJSON *obj, const char *key, const char *s)
{
    json_put(p, obj, key, cJSON_CreateString(s));
}

void json_put_numbers(parser *p, cJSON *obj, const char *key, const double *x, int n)
{
    json_put(p, obj, key, n > 0 ? cJSON_CreateDoubleArray(x, n) : cJSON_CreateArray());
}

/* a 3x3 matrix as its diagonal or as 3 rows, as it was given */
void json_put_matrix3(parser *p, cJSON *obj, const char *key, const double m[9], int diagonal)
{
    if (diagonal) {
        const double d[3] = {m[0], m[4], m[8]};
        json_put_numbers(p, obj, key, d, 3);
        return;
    }
    cJSON *rows = json_put(p, obj, key, cJSON_CreateArray());
    for (int i = 0; i < 3; i++) json_put_numbers(p, rows, NULL, &m[3 * i], 3);
}
