/*
 * job_json.c - the job format (job_json.h): JSON text to a checked, runnable ctc_sim_spec and the
 * job's normalised document.
 *
 * One pass walks the document in the format's order: name, scene, controller, trajectory,
 * disturbance, integrator, duration, output, limits, threads. Each object's keys are checked before
 * any of its values is read, so a misspelt key is reported as unknown (with the nearest valid key)
 * rather than as the required key it was meant to be; a typed object ({"type": ...}) is checked
 * twice, against every key of its kind and then against the keys of its type. Types, finiteness
 * and the ranges the format owns (positive masses, non-zero axes, array lengths, the limits) are
 * checked here, and each error names the JSON path of the offending value. What the library owns
 * is checked by the library and reported at the nearest path with its message: a controller's
 * stability ("controller" or "controller.joints[i]", ctrl.h), a trajectory's, disturbance's or
 * integrator's parameters, a shape's dimensions, and what only ctc_model_build sees - inertia
 * tensors, a planar form asked of a spatial chain - at "scene". ctc_sim_check runs last as a
 * safety net (field "").
 *
 * A loop ("scene.loop", read after the bodies) changes the sizes that follow: the controller's
 * per-coordinate arrays and channels cover the nind independent coordinates, counted here from
 * the joints' "independent" flags as model.h counts them. What only the library can judge of a
 * loop - its mobility against nind, a singular or over-constrained configuration, a q0 it cannot
 * close - comes from ctc_model_build or ctc_sim_check; those messages speak of the loop (its
 * words: "loop", "mobility", "closing joint", "singular", "over-constrained") and are reported at
 * "scene.loop", or, when the loop "does not close" from q0, at "scene.q0".
 *
 * While it walks, the parser writes the normalised document: the keys it read in canonical order,
 * every default written out, a preset expanded. It parses to the same spec. Printed with cJSON it
 * parses back to the same text; numbers with more than 15 significant digits may come back one
 * unit in the last place off, because cJSON 1.7 prints 15 digits whenever they read back within
 * DBL_EPSILON relative.
 *
 * A preset request {"preset": NAME, ...} is expanded first: the preset builds its document from
 * the request's parameters, and the request's other keys are applied to it as an RFC 7386 merge
 * patch. The result is then parsed like any job.
 *
 * Nothing here is global; any number of threads may parse at once. (cJSON itself records the
 * position of its last parse error in a global, which this file never reads.)
 */
#include "job_json.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "data.h"
#include "presets.h"
#include "shapes.h"

#define PATH_LEN 256
_Static_assert(sizeof(((job_error *)0)->field) == PATH_LEN, "paths are written into field");

/* defaults (job_json.h) */
#define DEFAULT_NAME "job"
#define DEFAULT_INTERVAL 0.01 /* s, or the duration when shorter */
#define DEFAULT_RK4_STEP 1e-3 /* s */
#define DEFAULT_RTOL 1e-8
#define DEFAULT_ATOL 1e-10
#define DEFAULT_MAX_STEPS 10000000.0
#define DEFAULT_MAX_SPEED 1e6 /* rad/s or m/s */

#define MAX_WHOLE 9007199254740992.0 /* 2^53: whole numbers beyond are not exact in a double */
#define AXIS_MIN_LENGTH 1e-12        /* as ctc_model_build */
#define QUAT_UNIT_TOL 1e-6           /* |norm - 1| allowed of a quaternion in q0 */
#define SMALL_OBJECT 16              /* objects up to this many keys are scanned pairwise */

enum { OPTIONAL = 0, REQUIRED = 1 };

/* the state of one parse */
typedef struct parser {
    job *j;                   /* the job being filled */
    job_error *err;           /* the first error */
    cJSON *norm;              /* the normalised document being written (j->normalised) */
    int oom;                  /* an allocation for the normalised document failed */
    char spherical[PATH_LEN]; /* the first independent spherical joint's owner
                                 ("scene.bodies[1]", "scene.loop"), or "" */
    ctc_ctrl_type ctrl;       /* the controller's type, once read */
} parser;

/* ---- errors and paths ---- */

static int error_at(job_error *err, job_error_code code, const char *field, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* Fills err (code, field, printf-style message) and returns -1. */
static int error_at(job_error *err, job_error_code code, const char *field, const char *fmt, ...)
{
    va_list ap;
    err->code = code;
    snprintf(err->field, sizeof err->field, "%s", field);
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return -1;
}

static int out_of_memory(job_error *err)
{
    return error_at(err, JOB_NO_MEMORY, "", "out of memory");
}

/* a path cut to fit ends in "..." */
static void mark_cut(char out[PATH_LEN], int written)
{
    if (written < 0 || written >= PATH_LEN) memcpy(out + PATH_LEN - 4, "...", 4);
}

/* out = path.key, or key alone at the root (path ""); returns out */
static const char *key_path(char out[PATH_LEN], const char *path, const char *key)
{
    int n = path[0] == '\0' ? snprintf(out, PATH_LEN, "%s", key)
                            : snprintf(out, PATH_LEN, "%s.%s", path, key);
    mark_cut(out, n);
    return out;
}

/* out = path[i]; returns out */
static const char *index_path(char out[PATH_LEN], const char *path, int i)
{
    mark_cut(out, snprintf(out, PATH_LEN, "%s[%d]", path, i));
    return out;
}

/* what a JSON value is, for "(got ...)" */
static const char *kind(const cJSON *v)
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

/* kind(v), or for an array its number of entries */
static const char *describe(char buf[32], const cJSON *v)
{
    if (!cJSON_IsArray(v)) return kind(v);
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
static int check_keys(parser *p, const cJSON *obj, const char *path, const char *const *allowed,
                      const char *const *known, const char *context)
{
    if (obj == NULL) return 0;
    for (const cJSON *c = obj->child; c != NULL; c = c->next) {
        if (in_list(allowed, c->string)) continue;
        char at[PATH_LEN];
        key_path(at, path, c->string);
        if (known != NULL && in_list(known, c->string)) {
            return error_at(p->err, JOB_UNKNOWN_FIELD, at, "key \"%s\" does not apply to %s",
                            c->string, context);
        }
        const char *hint = nearest_key(c->string, allowed);
        if (hint != NULL) {
            return error_at(p->err, JOB_UNKNOWN_FIELD, at,
                            "unknown key \"%s\" (did you mean \"%s\"?)", c->string, hint);
        }
        return error_at(p->err, JOB_UNKNOWN_FIELD, at, "unknown key \"%s\"", c->string);
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
static int check_repeated_keys(job_error *err, const cJSON *v, const char *path)
{
    char at[PATH_LEN];
    if (cJSON_IsObject(v)) {
        int oom = 0;
        const char *key = repeated_key(v, &oom);
        if (oom) return out_of_memory(err);
        if (key != NULL) {
            return error_at(err, JOB_INVALID_FIELD, key_path(at, path, key),
                            "key \"%s\" appears more than once", key);
        }
        for (const cJSON *c = v->child; c != NULL; c = c->next) {
            if (check_repeated_keys(err, c, key_path(at, path, c->string)) != 0) return -1;
        }
    } else if (cJSON_IsArray(v)) {
        int i = 0;
        for (const cJSON *c = v->child; c != NULL; c = c->next, i++) {
            if (check_repeated_keys(err, c, index_path(at, path, i)) != 0) return -1;
        }
    }
    return 0;
}

/* ---- reading values ---- */

static const cJSON *member(const cJSON *obj, const char *key)
{
    return cJSON_GetObjectItemCaseSensitive(obj, key);
}

static void *alloc(parser *p, size_t n, size_t size)
{
    void *x = calloc(n > 0 ? n : 1, size);
    if (x == NULL) out_of_memory(p->err);
    return x;
}

static int object_at(parser *p, const cJSON *v, const char *path)
{
    if (cJSON_IsObject(v)) return 0;
    return error_at(p->err, JOB_INVALID_FIELD, path, "must be an object (got %s)", kind(v));
}

/* obj[key], which must be present ("is required" otherwise, with an optional hint) */
static const cJSON *required_member(parser *p, const cJSON *obj, const char *path, const char *key,
                                    const char *hint)
{
    const cJSON *v = member(obj, key);
    if (v == NULL) {
        char at[PATH_LEN];
        error_at(p->err, JOB_MISSING_FIELD, key_path(at, path, key), "is required%s", hint);
    }
    return v;
}

/* *out = v, a finite number */
static int number_at(parser *p, const cJSON *v, const char *path, double *out)
{
    if (!cJSON_IsNumber(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must be a number (got %s)", kind(v));
    }
    if (!isfinite(v->valuedouble)) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must be finite (got %g)", v->valuedouble);
    }
    *out = v->valuedouble;
    return 0;
}

/* *out = obj[key] (obj at path) as a finite number; when absent, def or an error if required */
static int member_number(parser *p, const cJSON *obj, const char *path, const char *key,
                         int required, double def, double *out)
{
    char at[PATH_LEN];
    const cJSON *v = member(obj, key);
    if (v == NULL) {
        if (required)
            return error_at(p->err, JOB_MISSING_FIELD, key_path(at, path, key), "is required");
        *out = def;
        return 0;
    }
    return number_at(p, v, key_path(at, path, key), out);
}

/* the entries of array v (at path), each a finite number, into out */
static int numbers_in(parser *p, const cJSON *v, const char *path, double *out)
{
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        char at[PATH_LEN];
        if (number_at(p, e, index_path(at, path, i), &out[i]) != 0) return -1;
    }
    return 0;
}

/* out = v, an array of 3 finite numbers */
static int vec3_at(parser *p, const cJSON *v, const char *path, double out[3])
{
    char got[32];
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must be an array of 3 numbers (got %s)",
                        describe(got, v));
    }
    return numbers_in(p, v, path, out);
}

/* out = obj[key] as an array of 3 finite numbers; when absent, def or an error if required */
static int member_vec3(parser *p, const cJSON *obj, const char *path, const char *key, int required,
                       const double def[3], double out[3])
{
    char at[PATH_LEN];
    const cJSON *v = member(obj, key);
    key_path(at, path, key);
    if (v == NULL) {
        if (required) return error_at(p->err, JOB_MISSING_FIELD, at, "is required");
        memcpy(out, def, 3 * sizeof *out);
        return 0;
    }
    return vec3_at(p, v, at, out);
}

/* v: an array of lo..hi finite numbers; *out (freed by the caller) and *n */
static int number_list_at(parser *p, const cJSON *v, const char *path, int lo, int hi, double **out,
                          int *n)
{
    if (!cJSON_IsArray(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must be an array of numbers (got %s)",
                        kind(v));
    }
    *n = cJSON_GetArraySize(v);
    if (*n < lo || *n > hi) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must have %d to %d entries (got %d)", lo,
                        hi, *n);
    }
    *out = alloc(p, (size_t)*n, sizeof **out);
    if (*out == NULL) return -1;
    return numbers_in(p, v, path, *out);
}

/* v: an array of n finite numbers, one per coordinate (what: "coordinate", ...) */
static int coords_at(parser *p, const cJSON *v, const char *path, int n, const char *what,
                     double *out)
{
    if (!cJSON_IsArray(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, path,
                        "must be an array of %d numbers, one per %s (got %s)", n, what, kind(v));
    }
    int len = cJSON_GetArraySize(v);
    if (len != n) {
        return error_at(p->err, JOB_INVALID_FIELD, path,
                        "must have %d entries, one per %s (got %d)", n, what, len);
    }
    return numbers_in(p, v, path, out);
}

/* A 3x3 matrix (row-major into out): an array of 3 rows of 3 numbers, or an array of its 3
 * diagonal entries (*diagonal set; what names them in messages, e.g. "principal moments"). */
static int matrix3_at(parser *p, const cJSON *v, const char *path, const char *what, double out[9],
                      int *diagonal)
{
    char got[32], at[PATH_LEN];
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) {
        return error_at(p->err, JOB_INVALID_FIELD, path,
                        "must be a 3x3 array of rows or an array of 3 %s (got %s)", what,
                        describe(got, v));
    }
    memset(out, 0, 9 * sizeof *out);
    *diagonal = !cJSON_IsArray(v->child);
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        index_path(at, path, i);
        if (*diagonal ? number_at(p, e, at, &out[4 * i]) : vec3_at(p, e, at, &out[3 * i])) {
            return -1;
        }
    }
    return 0;
}

/* v: a string of 1..JOB_MAX_NAME bytes */
static int name_at(parser *p, const cJSON *v, const char *path, const char **out)
{
    if (!cJSON_IsString(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must be a string (got %s)", kind(v));
    }
    size_t len = strlen(v->valuestring);
    if (len == 0) return error_at(p->err, JOB_INVALID_FIELD, path, "must not be empty");
    if (len > JOB_MAX_NAME) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must be at most %d bytes long (got %zu)",
                        JOB_MAX_NAME, len);
    }
    *out = v->valuestring;
    return 0;
}

/* *out = the index of string v in names (count of them) */
static int enum_at(parser *p, const cJSON *v, const char *path, const char *const *names, int count,
                   int *out)
{
    if (!cJSON_IsString(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must be a string (got %s)", kind(v));
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
    return error_at(p->err, JOB_INVALID_FIELD, path, "must be one of %s (got \"%s\")", list,
                    v->valuestring);
}

/* Reads the type of a typed object v (at path; NULL: absent, the type is def): checks v's keys
 * against all_keys of its kind, reads type_key, then checks the keys apply to that type
 * (keys_by_type[type]). what names the kind in messages ("joint type", "method"). */
static int typed_object(parser *p, const cJSON *v, const char *path, const char *type_key,
                        int required, int def, const char *const *names, int count,
                        const char *what, const char *const *const *keys_by_type,
                        const char *const *all_keys, int *type)
{
    char at[PATH_LEN], context[64];
    *type = def;
    if (v == NULL) return 0;
    if (object_at(p, v, path) != 0 || check_keys(p, v, path, all_keys, NULL, NULL) != 0) return -1;
    const cJSON *t = member(v, type_key);
    key_path(at, path, type_key);
    if (t == NULL && required) return error_at(p->err, JOB_MISSING_FIELD, at, "is required");
    if (t != NULL && enum_at(p, t, at, names, count, type) != 0) return -1;
    snprintf(context, sizeof context, "%s \"%s\"", what, names[*type]);
    return check_keys(p, v, path, keys_by_type[*type], all_keys, context);
}

/* ---- writing the normalised document ---- */

/* Adds item to obj under key (or at the end of array obj when key is NULL) and returns it; on
 * any failure deletes item, remembers it and returns NULL (adds below a NULL fail quietly). */
static cJSON *put(parser *p, cJSON *obj, const char *key, cJSON *item)
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

static void put_number(parser *p, cJSON *obj, const char *key, double x)
{
    put(p, obj, key, cJSON_CreateNumber(x));
}

static void put_string(parser *p, cJSON *obj, const char *key, const char *s)
{
    put(p, obj, key, cJSON_CreateString(s));
}

static void put_numbers(parser *p, cJSON *obj, const char *key, const double *x, int n)
{
    put(p, obj, key, n > 0 ? cJSON_CreateDoubleArray(x, n) : cJSON_CreateArray());
}

/* a 3x3 matrix as its diagonal or as 3 rows, as it was given */
static void put_matrix3(parser *p, cJSON *obj, const char *key, const double m[9], int diagonal)
{
    if (diagonal) {
        const double d[3] = {m[0], m[4], m[8]};
        put_numbers(p, obj, key, d, 3);
        return;
    }
    cJSON *rows = put(p, obj, key, cJSON_CreateArray());
    for (int i = 0; i < 3; i++) put_numbers(p, rows, NULL, &m[3 * i], 3);
}

/* ---- name ---- */

static int parse_name(parser *p, const cJSON *doc, const char *default_name)
{
    const char *name = default_name;
    const cJSON *v = member(doc, "name");
    if (v != NULL && name_at(p, v, "name", &name) != 0) return -1;
    p->j->name = strdup(name);
    if (p->j->name == NULL) return out_of_memory(p->err);
    put_string(p, p->norm, "name", name);
    return 0;
}

/* ---- scene ---- */

static const char *const shape_names[] = {"rod", "box", "cylinder"};
enum { SHAPE_ROD, SHAPE_BOX, SHAPE_CYLINDER };
static const char *const shape_keys_all[] = {"type",   "end",    "size", "centre",
                                             "radius", "length", "axis", NULL};
static const char *const shape_keys_rod[] = {"type", "end", NULL};
static const char *const shape_keys_box[] = {"type", "size", "centre", NULL};
static const char *const shape_keys_cylinder[] = {"type", "radius", "length",
                                                  "axis", "centre", NULL};
static const char *const *const shape_keys[] = {shape_keys_rod, shape_keys_box,
                                                shape_keys_cylinder};

/* a body's centre of mass and inertia from its "shape" (body->mass already read) */
static int parse_shape(parser *p, const cJSON *v, const char *body_path, ctc_body_spec *body,
                       cJSON *out_body)
{
    static const double origin[3] = {0, 0, 0};
    char path[PATH_LEN], msg[256];
    int type;
    key_path(path, body_path, "shape");
    if (typed_object(p, v, path, "type", REQUIRED, 0, shape_names, 3, "shape type", shape_keys,
                     shape_keys_all, &type) != 0) {
        return -1;
    }
    cJSON *out = put(p, out_body, "shape", cJSON_CreateObject());
    put_string(p, out, "type", shape_names[type]);

    ctc_status st = CTC_OK;
    double end[3], size[3], centre[3], axis[3], radius, length;
    switch (type) {
    case SHAPE_ROD:
        if (member_vec3(p, v, path, "end", REQUIRED, NULL, end) != 0) return -1;
        put_numbers(p, out, "end", end, 3);
        st = ctc_shape_rod(body->mass, end, body, msg, sizeof msg);
        break;
    case SHAPE_BOX:
        if (member_vec3(p, v, path, "size", REQUIRED, NULL, size) != 0 ||
            member_vec3(p, v, path, "centre", OPTIONAL, origin, centre) != 0) {
            return -1;
        }
        put_numbers(p, out, "size", size, 3);
        put_numbers(p, out, "centre", centre, 3);
        st = ctc_shape_box(body->mass, size, centre, body, msg, sizeof msg);
        break;
    case SHAPE_CYLINDER:
        if (member_number(p, v, path, "radius", REQUIRED, 0, &radius) != 0 ||
            member_number(p, v, path, "length", REQUIRED, 0, &length) != 0 ||
            member_vec3(p, v, path, "axis", REQUIRED, NULL, axis) != 0 ||
            member_vec3(p, v, path, "centre", OPTIONAL, origin, centre) != 0) {
            return -1;
        }
        put_number(p, out, "radius", radius);
        put_number(p, out, "length", length);
        put_numbers(p, out, "axis", axis, 3);
        put_numbers(p, out, "centre", centre, 3);
        st = ctc_shape_cylinder(body->mass, radius, length, axis, centre, body, msg, sizeof msg);
        break;
    }
    if (st != CTC_OK) return error_at(p->err, JOB_INVALID_FIELD, path, "%s", msg);
    return 0;
}

/* "inertia": 3x3 rows, or the principal moments along the body axes (none negative) */
static int parse_inertia(parser *p, const cJSON *v, const char *path, ctc_body_spec *body,
                         cJSON *out_body)
{
    char at[PATH_LEN];
    int diagonal;
    if (matrix3_at(p, v, path, "principal moments", body->inertia, &diagonal) != 0) return -1;
    for (int i = 0; diagonal && i < 3; i++) {
        if (body->inertia[4 * i] < 0) {
            return error_at(p->err, JOB_INVALID_FIELD, index_path(at, path, i),
                            "must not be negative (got %g kg m^2)", body->inertia[4 * i]);
        }
    }
    put_matrix3(p, out_body, "inertia", body->inertia, diagonal);
    return 0;
}

static const char *const joint_keys_all[] = {"type", "axis", "location", "independent", NULL};
static const char *const joint_keys_fixed[] = {"type", "location", "independent", NULL};
static const char *const *const joint_keys[] = {[CTC_JOINT_REVOLUTE] = joint_keys_all,
                                                [CTC_JOINT_PRISMATIC] = joint_keys_all,
                                                [CTC_JOINT_CYLINDRICAL] = joint_keys_all,
                                                [CTC_JOINT_SPHERICAL] = joint_keys_fixed,
                                                [CTC_JOINT_FIXED] = joint_keys_fixed};

/* *out = v, true or false */
static int bool_at(parser *p, const cJSON *v, const char *path, int *out)
{
    if (!cJSON_IsBool(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must be true or false (got %s)", kind(v));
    }
    *out = cJSON_IsTrue(v);
    return 0;
}

/* A joint's "axis" (joint v at path; the type needs one): any length, but not zero and not
 * overflowing. Written to out. */
static int parse_axis(parser *p, const cJSON *v, const char *path, double a[3], cJSON *out)
{
    char at[PATH_LEN];
    if (member_vec3(p, v, path, "axis", REQUIRED, NULL, a) != 0) return -1;
    double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    key_path(at, path, "axis");
    if (!isfinite(len)) {
        return error_at(p->err, JOB_INVALID_FIELD, at, "is too long (its length overflows)");
    }
    if (!(len > AXIS_MIN_LENGTH)) {
        return error_at(p->err, JOB_INVALID_FIELD, at,
                        "must have non-zero length (got [%g, %g, %g])", a[0], a[1], a[2]);
    }
    put_numbers(p, out, "axis", a, 3);
    return 0;
}

/* A joint's "location" (default the origin) and "independent" flag (default def; joint v at
 * path, owner names it for messages), written to out. The first independent spherical joint is
 * remembered: a controller cannot drive it. */
static int parse_joint_rest(parser *p, const cJSON *v, const char *path, const char *owner,
                            ctc_joint_spec *joint, int def, unsigned char *independent, cJSON *out)
{
    static const double origin[3] = {0, 0, 0};
    char at[PATH_LEN];
    if (member_vec3(p, v, path, "location", OPTIONAL, origin, joint->location) != 0) return -1;
    put_numbers(p, out, "location", joint->location, 3);
    int flag = def;
    const cJSON *f = member(v, "independent");
    if (f != NULL && bool_at(p, f, key_path(at, path, "independent"), &flag) != 0) return -1;
    *independent = (unsigned char)flag;
    put(p, out, "independent", cJSON_CreateBool(flag));
    if (flag && joint->type == CTC_JOINT_SPHERICAL && p->spherical[0] == '\0') {
        snprintf(p->spherical, sizeof p->spherical, "%s", owner);
    }
    return 0;
}

/* body k's inboard joint */
static int parse_joint(parser *p, const cJSON *body, const char *body_path, int k,
                       ctc_joint_spec *joint, cJSON *out_body)
{
    char path[PATH_LEN];
    const char *names[5];
    int type;
    for (int t = 0; t < 5; t++) names[t] = ctc_joint_type_name((ctc_joint_type)t);
    const cJSON *v = required_member(p, body, body_path, "joint", "");
    key_path(path, body_path, "joint");
    if (v == NULL || typed_object(p, v, path, "type", REQUIRED, 0, names, 5, "joint type",
                                  joint_keys, joint_keys_all, &type) != 0) {
        return -1;
    }
    joint->type = (ctc_joint_type)type;
    cJSON *out = put(p, out_body, "joint", cJSON_CreateObject());
    put_string(p, out, "type", names[type]);
    if (joint->type != CTC_JOINT_SPHERICAL && joint->type != CTC_JOINT_FIXED &&
        parse_axis(p, v, path, joint->axis, out) != 0) {
        return -1;
    }
    return parse_joint_rest(p, v, path, body_path, joint, 1, &p->j->independent[k], out);
}

static const char *const body_keys[] = {"name", "mass", "com", "inertia", "shape", "joint", NULL};

/* body k: mass, then com and inertia or a shape, then its joint */
static int parse_body(parser *p, const cJSON *v, int k, cJSON *out_bodies)
{
    char path[PATH_LEN], at[PATH_LEN];
    ctc_body_spec *body = &p->j->bodies[k];
    index_path(path, "scene.bodies", k);
    if (object_at(p, v, path) != 0 || check_keys(p, v, path, body_keys, NULL, NULL) != 0) return -1;
    cJSON *out = put(p, out_bodies, NULL, cJSON_CreateObject());

    /* a name, kept only in the document */
    const cJSON *name = member(v, "name");
    const char *s;
    if (name != NULL) {
        if (name_at(p, name, key_path(at, path, "name"), &s) != 0) return -1;
        put_string(p, out, "name", s);
    }

    /* mass */
    if (member_number(p, v, path, "mass", REQUIRED, 0, &body->mass) != 0) return -1;
    if (!(body->mass > 0)) {
        return error_at(p->err, JOB_INVALID_FIELD, key_path(at, path, "mass"),
                        "must be positive (got %g kg)", body->mass);
    }
    put_number(p, out, "mass", body->mass);

    /* centre of mass and inertia, or a shape that gives both */
    const cJSON *shape = member(v, "shape");
    if (shape != NULL) {
        static const char *const given[] = {"com", "inertia"};
        for (int i = 0; i < 2; i++) {
            if (member(v, given[i]) != NULL) {
                return error_at(p->err, JOB_INVALID_FIELD, key_path(at, path, given[i]),
                                "not allowed with \"shape\" (the shape gives it)");
            }
        }
        if (parse_shape(p, shape, path, body, out) != 0) return -1;
    } else {
        const char *hint = " (or give a \"shape\")";
        const cJSON *com = required_member(p, v, path, "com", hint);
        if (com == NULL || vec3_at(p, com, key_path(at, path, "com"), body->com) != 0) return -1;
        put_numbers(p, out, "com", body->com, 3);
        const cJSON *inertia = required_member(p, v, path, "inertia", hint);
        if (inertia == NULL ||
            parse_inertia(p, inertia, key_path(at, path, "inertia"), body, out) != 0) {
            return -1;
        }
    }
    return parse_joint(p, v, path, k, &p->j->joints[k], out);
}

/* "scene.bodies": 1..JOB_MAX_BODIES bodies */
static int parse_bodies(parser *p, const cJSON *scene, cJSON *out_scene)
{
    job *j = p->j;
    const cJSON *v = required_member(p, scene, "scene", "bodies", "");
    if (v == NULL) return -1;
    if (!cJSON_IsArray(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, "scene.bodies",
                        "must be an array of bodies (got %s)", kind(v));
    }
    int n = cJSON_GetArraySize(v);
    if (n == 0) return error_at(p->err, JOB_INVALID_FIELD, "scene.bodies", "must not be empty");
    if (n > JOB_MAX_BODIES) {
        return error_at(p->err, JOB_LIMIT_EXCEEDED, "scene.bodies",
                        "has %d bodies; the limit is %d", n, JOB_MAX_BODIES);
    }
    j->bodies = alloc(p, (size_t)n, sizeof *j->bodies);
    j->joints = alloc(p, (size_t)n, sizeof *j->joints);
    j->independent = alloc(p, (size_t)n + 1, sizeof *j->independent);
    if (j->bodies == NULL || j->joints == NULL || j->independent == NULL) return -1;
    j->spec.chain.nbodies = n;
    j->spec.chain.bodies = j->bodies;
    j->spec.chain.joints = j->joints;

    cJSON *out = put(p, out_scene, "bodies", cJSON_CreateArray());
    int k = 0;
    for (const cJSON *b = v->child; b != NULL; b = b->next, k++) {
        if (parse_body(p, b, k, out) != 0) return -1;
    }
    return 0;
}

/* "scene.q0" (default: the reference configuration) and "scene.v0" (default 0), given m */
static int parse_initial_state(parser *p, const cJSON *scene, const ctc_model *m, cJSON *out_scene)
{
    job *j = p->j;
    j->q0 = alloc(p, (size_t)m->nq, sizeof *j->q0);
    j->v0 = alloc(p, (size_t)m->nv, sizeof *j->v0);
    if (j->q0 == NULL || j->v0 == NULL) return -1;
    j->spec.q0 = j->q0;
    j->spec.v0 = j->v0;

    const cJSON *q0 = member(scene, "q0");
    if (q0 == NULL) {
        ctc_model_q_zero(m, j->q0);
    } else if (coords_at(p, q0, "scene.q0", m->nq, "position coordinate", j->q0) != 0) {
        return -1;
    }

    /* a spherical joint's quaternion must be a rotation */
    for (int k = 0; k < m->nbodies; k++) {
        if (m->joints[k].type != CTC_JOINT_SPHERICAL) continue;
        const double *q = &j->q0[m->jnt_qadr[k]];
        double norm = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
        if (!(fabs(norm - 1) <= QUAT_UNIT_TOL)) {
            return error_at(p->err, JOB_INVALID_FIELD, "scene.q0",
                            "entries %d to %d, the quaternion (w, x, y, z) of "
                            "scene.bodies[%d].joint, must have unit length (got %g)",
                            m->jnt_qadr[k], m->jnt_qadr[k] + 3, k, norm);
        }
    }
    put_numbers(p, out_scene, "q0", j->q0, m->nq);

    const cJSON *v0 = member(scene, "v0");
    if (v0 != NULL && coords_at(p, v0, "scene.v0", m->nv, "coordinate", j->v0) != 0) return -1;
    put_numbers(p, out_scene, "v0", j->v0, m->nv);
    return 0;
}

/* ---- the loop ---- */

/* the closing joint's types, as the format names them */
static const ctc_joint_type loop_types[] = {CTC_JOINT_REVOLUTE, CTC_JOINT_PRISMATIC,
                                            CTC_JOINT_SPHERICAL};
static const char *const loop_joint_keys_all[] = {"type", "axis", "location", "independent", NULL};
static const char *const loop_joint_keys_spherical[] = {"type", "location", "independent", NULL};
static const char *const *const loop_joint_keys[] = {loop_joint_keys_all, loop_joint_keys_all,
                                                     loop_joint_keys_spherical};

/* "scene.loop.joint": the closing joint, from the tip (body n - 1) to the ground or to body
 * "scene.loop.body" */
static int parse_loop_joint(parser *p, const cJSON *loop, cJSON *out_loop)
{
    static const char *const path = "scene.loop.joint";
    job *j = p->j;
    ctc_joint_spec *joint = &j->loop.joint;
    const char *names[3];
    int type;
    for (int t = 0; t < 3; t++) names[t] = ctc_joint_type_name(loop_types[t]);
    const cJSON *v = required_member(p, loop, "scene.loop", "joint", "");
    if (v == NULL || typed_object(p, v, path, "type", REQUIRED, 0, names, 3, "joint type",
                                  loop_joint_keys, loop_joint_keys_all, &type) != 0) {
        return -1;
    }
    joint->type = loop_types[type];
    cJSON *out = put(p, out_loop, "joint", cJSON_CreateObject());
    put_string(p, out, "type", names[type]);
    if (joint->type != CTC_JOINT_SPHERICAL && parse_axis(p, v, path, joint->axis, out) != 0) {
        return -1;
    }
    int n = j->spec.chain.nbodies;
    return parse_joint_rest(p, v, path, "scene.loop", joint, 0, &j->independent[n], out);
}

static const char *const stab_keys_all[] = {"method", "tol", "alpha", "beta", NULL};
static const char *const stab_keys_project[] = {"method", "tol", NULL};
static const char *const stab_keys_baumgarte[] = {"method", "alpha", "beta", NULL};
static const char *const stab_keys_none[] = {"method", NULL};
static const char *const *const stab_keys[] = {[CTC_LOOP_PROJECT] = stab_keys_project,
                                               [CTC_LOOP_BAUMGARTE] = stab_keys_baumgarte,
                                               [CTC_LOOP_NONE] = stab_keys_none};

/* "scene.loop.stabilization": how the state is kept on the closure (default project) */
static int parse_stabilization(parser *p, const cJSON *loop, cJSON *out_loop)
{
    static const char *const path = "scene.loop.stabilization";
    ctc_sim_spec *s = &p->j->spec;
    const char *names[3];
    int method;
    for (int m = 0; m < 3; m++) names[m] = ctc_loop_stab_name((ctc_loop_stab)m);
    if (typed_object(p, member(loop, "stabilization"), path, "method", OPTIONAL, CTC_LOOP_PROJECT,
                     names, 3, "method", stab_keys, stab_keys_all, &method) != 0) {
        return -1;
    }
    const cJSON *v = member(loop, "stabilization");
    s->loop_stab = (ctc_loop_stab)method;
    cJSON *out = put(p, out_loop, "stabilization", cJSON_CreateObject());
    put_string(p, out, "method", names[method]);
    switch (s->loop_stab) {
    case CTC_LOOP_PROJECT:
        if (member_number(p, v, path, "tol", OPTIONAL, CTC_SIM_DEFAULT_LOOP_TOL, &s->loop_tol) !=
            0) {
            return -1;
        }
        if (!(s->loop_tol > 0)) {
            return error_at(p->err, JOB_INVALID_FIELD, "scene.loop.stabilization.tol",
                            "must be positive (got %g)", s->loop_tol);
        }
        put_number(p, out, "tol", s->loop_tol);
        break;
    case CTC_LOOP_BAUMGARTE: {
        static const char *const keys[2] = {"alpha", "beta"};
        char at[PATH_LEN];
        for (int i = 0; i < 2; i++) {
            double *x = &s->baumgarte[i];
            if (member_number(p, v, path, keys[i], OPTIONAL, CTC_SIM_DEFAULT_BAUMGARTE, x) != 0)
                return -1;
            if (!(*x >= 0)) {
                return error_at(p->err, JOB_INVALID_FIELD, key_path(at, path, keys[i]),
                                "must not be negative (got %g 1/s)", *x);
            }
        }
        /* the library reads (0, 0) as its defaults: say "none" for no stabilisation */
        if (s->baumgarte[0] == 0 && s->baumgarte[1] == 0) {
            return error_at(p->err, JOB_INVALID_FIELD, path,
                            "alpha and beta must not both be 0 (use {\"method\": \"none\"} "
                            "for no stabilization)");
        }
        put_number(p, out, "alpha", s->baumgarte[0]);
        put_number(p, out, "beta", s->baumgarte[1]);
        break;
    }
    case CTC_LOOP_NONE:
        break;
    }
    return 0;
}

static const char *const loop_keys[] = {"joint",         "anchor",   "body",
                                        "stabilization", "cond_max", NULL};

/* "scene.loop.body" (optional): the body the loop closes on, a whole number 0..n-2; absent, the
 * loop closes on the ground */
static int parse_loop_body(parser *p, const cJSON *loop, cJSON *out_loop)
{
    job *j = p->j;
    int n = j->spec.chain.nbodies;
    double b;
    j->loop.on_body = 0;
    j->loop.body = 0;
    if (member(loop, "body") == NULL) return 0;
    if (member_number(p, loop, "scene.loop", "body", REQUIRED, 0, &b) != 0) return -1;
    if (!(b >= 0 && b <= n - 2 && b == floor(b))) {
        return error_at(p->err, JOB_INVALID_FIELD, "scene.loop.body",
                        "must be the index of a body before the tip (body %d): a whole number "
                        "from 0 to %d (got %g)",
                        n - 1, n - 2, b);
    }
    j->loop.on_body = 1;
    j->loop.body = (int)b;
    put_number(p, out_loop, "body", b);
    return 0;
}

/* "scene.loop" (optional): the closing joint, its anchor and the run's loop settings; then the
 * independent flags: with a loop they say which coordinates are controlled (nind), without one
 * every joint must be independent */
static int parse_loop(parser *p, const cJSON *scene, cJSON *out_scene)
{
    job *j = p->j;
    ctc_sim_spec *s = &j->spec;
    int n = s->chain.nbodies;
    const cJSON *v = member(scene, "loop");
    if (v == NULL) {
        for (int k = 0; k < n; k++) {
            if (j->independent[k]) continue;
            char body[PATH_LEN], joint[PATH_LEN], at[PATH_LEN];
            index_path(body, "scene.bodies", k);
            return error_at(p->err, JOB_INVALID_FIELD,
                            key_path(at, key_path(joint, body, "joint"), "independent"),
                            "must be true: an open chain is fully actuated (only a chain closed "
                            "by \"scene.loop\" has dependent joints)");
        }
        free(j->independent);
        j->independent = NULL;
        j->nind = j->nv;
        return 0;
    }
    if (object_at(p, v, "scene.loop") != 0 ||
        check_keys(p, v, "scene.loop", loop_keys, NULL, NULL) != 0) {
        return -1;
    }
    cJSON *out = put(p, out_scene, "loop", cJSON_CreateObject());
    if (parse_loop_joint(p, v, out) != 0 ||
        member_vec3(p, v, "scene.loop", "anchor", REQUIRED, NULL, j->loop.anchor) != 0) {
        return -1;
    }
    put_numbers(p, out, "anchor", j->loop.anchor, 3);
    if (parse_loop_body(p, v, out) != 0 || parse_stabilization(p, v, out) != 0 ||
        member_number(p, v, "scene.loop", "cond_max", OPTIONAL, CTC_SIM_DEFAULT_COND_MAX,
                      &s->loop_cond_max) != 0) {
        return -1;
    }
    if (!(s->loop_cond_max > 1)) {
        return error_at(p->err, JOB_INVALID_FIELD, "scene.loop.cond_max",
                        "must be greater than 1 (got %g)", s->loop_cond_max);
    }
    put_number(p, out, "cond_max", s->loop_cond_max);
    s->chain.loop = &j->loop;
    s->chain.independent = j->independent;

    /* the controlled coordinates: those of the independent joints, the closing joint's last */
    j->nind = 0;
    for (int k = 0; k < n; k++) {
        if (j->independent[k]) j->nind += ctc_joint_nv(j->joints[k].type);
    }
    if (j->independent[n]) j->nind += ctc_joint_nv(j->loop.joint.type);
    return 0;
}

/* The field of a library error about the scene of a job with a loop: the loop's settings, or
 * q0 when the loop does not close from it; "scene" for anything else. */
static const char *loop_error_field(const char *msg)
{
    static const char *const loop_words[] = {"loop",     "mobility",         "closing joint",
                                             "singular", "over-constrained", NULL};
    if (strncmp(msg, "body ", 5) == 0) return "scene"; /* a body's inertia, even a singular one */
    if (strstr(msg, "does not close") != NULL) return "scene.q0";
    for (const char *const *w = loop_words; *w != NULL; w++) {
        if (strstr(msg, *w) != NULL) return "scene.loop";
    }
    return "scene";
}

static const char *const scene_keys[] = {"gravity", "form", "bodies", "loop", "q0", "v0", NULL};

static int parse_scene(parser *p, const cJSON *doc)
{
    static const double gravity[3] = {0, -9.81, 0};
    job *j = p->j;
    ctc_chain_spec *chain = &j->spec.chain;
    const cJSON *v = required_member(p, doc, "", "scene", "");
    if (v == NULL || object_at(p, v, "scene") != 0 ||
        check_keys(p, v, "scene", scene_keys, NULL, NULL) != 0) {
        return -1;
    }
    cJSON *out = put(p, p->norm, "scene", cJSON_CreateObject());

    /* gravity and form */
    if (member_vec3(p, v, "scene", "gravity", OPTIONAL, gravity, chain->gravity) != 0) return -1;
    put_numbers(p, out, "gravity", chain->gravity, 3);
    const char *forms[3];
    int form = CTC_FORM_AUTO;
    for (int f = 0; f < 3; f++) forms[f] = ctc_form_name((ctc_form)f);
    const cJSON *fv = member(v, "form");
    if (fv != NULL && enum_at(p, fv, "scene.form", forms, 3, &form) != 0) return -1;
    chain->form = (ctc_form)form;
    put_string(p, out, "form", forms[form]);

    /* bodies; at least one coordinate must move */
    if (parse_bodies(p, v, out) != 0) return -1;
    for (int k = 0; k < chain->nbodies; k++) {
        j->nq += ctc_joint_nq(j->joints[k].type);
        j->nv += ctc_joint_nv(j->joints[k].type);
    }
    if (j->nv == 0) {
        return error_at(p->err, JOB_INVALID_FIELD, "scene.bodies",
                        "must have at least one joint that moves (every joint is fixed)");
    }
    if (parse_loop(p, v, out) != 0) return -1;

    /* what only the builder checks: inertia tensors, the plane of a planar chain, the loop */
    ctc_model *m = NULL;
    char msg[512];
    ctc_status st = ctc_model_build(chain, &m, msg, sizeof msg);
    if (st == CTC_ENOMEM) return out_of_memory(p->err);
    if (st != CTC_OK) {
        const char *field = chain->loop != NULL ? loop_error_field(msg) : "scene";
        return error_at(p->err, JOB_INVALID_FIELD, field, "%s", msg);
    }
    int rc = parse_initial_state(p, v, m, out);
    ctc_model_free(m);
    return rc;
}

/* ---- controller ---- */

/* the keys of the gain parameters, as bits of gain_params.given */
enum {
    G_KP = 1u << 0,
    G_KV = 1u << 1,
    G_KI = 1u << 2,
    G_ZETA = 1u << 3,
    G_TAU = 1u << 4,
    G_POLES = 1u << 5,
    G_Q = 1u << 6,
    G_LAMBDA = 1u << 7,
    G_PAIR_KP = G_KP | G_KV,
    G_PAIR_ZETA = G_ZETA | G_TAU,
};

/* The design parameters of one coordinate, as read from "controller" or an override. */
typedef struct gain_params {
    unsigned given; /* G_* bits of the keys present */
    double kp, kv, ki, zeta, tau;
    double re[3], im[3]; /* poles */
    double Q[9];         /* row-major */
    int q_diagonal;      /* Q was given as its diagonal */
    double lambda;
} gain_params;

static const char *const gains_pd[] = {"kp", "kv", "zeta", "tau", NULL};
static const char *const gains_pid[] = {"kp", "kv", "ki", "zeta", "tau", NULL};
static const char *const gains_poles[] = {"poles", NULL};
static const char *const gains_lqr[] = {"Q", "lambda", NULL};
static const char *const gains_none[] = {NULL};
static const char *const gains_all[] = {"kp",    "kv", "ki",     "zeta", "tau",
                                        "poles", "Q",  "lambda", NULL};
static const char *const *const gain_keys[] = {[CTC_CTRL_NONE] = gains_none,
                                               [CTC_CTRL_PD] = gains_pd,
                                               [CTC_CTRL_PID] = gains_pid,
                                               [CTC_CTRL_POLES] = gains_poles,
                                               [CTC_CTRL_LQR] = gains_lqr};

static const char *const ctrl_keys_all[] = {"type",  "kp", "kv",     "ki",     "zeta",  "tau",
                                            "poles", "Q",  "lambda", "joints", "model", NULL};
static const char *const ctrl_keys_none[] = {"type", NULL};
static const char *const ctrl_keys_pd[] = {"type", "kp",     "kv",    "zeta",
                                           "tau",  "joints", "model", NULL};
static const char *const ctrl_keys_pid[] = {"type", "kp",     "kv",    "ki", "zeta",
                                            "tau",  "joints", "model", NULL};
static const char *const ctrl_keys_poles[] = {"type", "poles", "joints", "model", NULL};
static const char *const ctrl_keys_lqr[] = {"type", "Q", "lambda", "joints", "model", NULL};
static const char *const *const ctrl_keys[] = {[CTC_CTRL_NONE] = ctrl_keys_none,
                                               [CTC_CTRL_PD] = ctrl_keys_pd,
                                               [CTC_CTRL_PID] = ctrl_keys_pid,
                                               [CTC_CTRL_POLES] = ctrl_keys_poles,
                                               [CTC_CTRL_LQR] = ctrl_keys_lqr};

/* "poles": three entries, each a real pole or {"re": x, "im": y} */
static int poles_at(parser *p, const cJSON *v, const char *path, double re[3], double im[3])
{
    static const char *const pole_keys[] = {"re", "im", NULL};
    char got[32], at[PATH_LEN];
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must be an array of 3 poles (got %s)",
                        describe(got, v));
    }
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        index_path(at, path, i);
        im[i] = 0;
        if (cJSON_IsNumber(e)) {
            if (number_at(p, e, at, &re[i]) != 0) return -1;
        } else if (cJSON_IsObject(e)) {
            if (check_keys(p, e, at, pole_keys, NULL, NULL) != 0 ||
                member_number(p, e, at, "re", REQUIRED, 0, &re[i]) != 0 ||
                member_number(p, e, at, "im", REQUIRED, 0, &im[i]) != 0) {
                return -1;
            }
        } else {
            return error_at(p->err, JOB_INVALID_FIELD, at,
                            "must be a number or an object {\"re\": x, \"im\": y} (got %s)",
                            kind(e));
        }
    }
    return 0;
}

/* one scalar gain key of obj (at path), if present */
static int read_gain(parser *p, const cJSON *obj, const char *path, const char *key, unsigned bit,
                     double *x, unsigned *given)
{
    char at[PATH_LEN];
    const cJSON *v = member(obj, key);
    if (v == NULL) return 0;
    if (number_at(p, v, key_path(at, path, key), x) != 0) return -1;
    *given |= bit;
    return 0;
}

/* the gain keys present in obj (at path; its keys already checked) */
static int read_gain_params(parser *p, const cJSON *obj, const char *path, gain_params *g)
{
    char at[PATH_LEN];
    const cJSON *v;
    if (read_gain(p, obj, path, "kp", G_KP, &g->kp, &g->given) != 0 ||
        read_gain(p, obj, path, "kv", G_KV, &g->kv, &g->given) != 0 ||
        read_gain(p, obj, path, "ki", G_KI, &g->ki, &g->given) != 0 ||
        read_gain(p, obj, path, "zeta", G_ZETA, &g->zeta, &g->given) != 0 ||
        read_gain(p, obj, path, "tau", G_TAU, &g->tau, &g->given) != 0 ||
        read_gain(p, obj, path, "lambda", G_LAMBDA, &g->lambda, &g->given) != 0) {
        return -1;
    }
    if ((v = member(obj, "poles")) != NULL) {
        if (poles_at(p, v, key_path(at, path, "poles"), g->re, g->im) != 0) return -1;
        g->given |= G_POLES;
    }
    if ((v = member(obj, "Q")) != NULL) {
        if (matrix3_at(p, v, key_path(at, path, "Q"), "diagonal entries", g->Q, &g->q_diagonal) !=
            0) {
            return -1;
        }
        g->given |= G_Q;
    }
    return 0;
}

/* pd and pid take "kp" and "kv", or "zeta" and "tau": exactly one whole pair (bits given) */
static int check_gain_pair(parser *p, unsigned given, const char *path)
{
    char at[PATH_LEN];
    if ((given & G_PAIR_KP) && (given & G_PAIR_ZETA)) {
        return error_at(p->err, JOB_INVALID_FIELD,
                        key_path(at, path, given & G_ZETA ? "zeta" : "tau"),
                        "cannot be combined with \"kp\" and \"kv\" (give \"kp\" and \"kv\", or "
                        "\"zeta\" and \"tau\")");
    }
    if (!(given & (G_PAIR_KP | G_PAIR_ZETA))) {
        return error_at(p->err, JOB_MISSING_FIELD, key_path(at, path, "kp"),
                        "is required (or give \"zeta\" and \"tau\")");
    }
    static const struct {
        unsigned bit, partner;
        const char *key, *partner_key;
    } pairs[] = {{G_KP, G_KV, "kp", "kv"},
                 {G_KV, G_KP, "kv", "kp"},
                 {G_ZETA, G_TAU, "zeta", "tau"},
                 {G_TAU, G_ZETA, "tau", "zeta"}};
    for (int i = 0; i < 4; i++) {
        if ((given & pairs[i].bit) && !(given & pairs[i].partner)) {
            return error_at(p->err, JOB_MISSING_FIELD, key_path(at, path, pairs[i].partner_key),
                            "is required with \"%s\"", pairs[i].key);
        }
    }
    return 0;
}

/* the keys the controller object itself must give for its type */
static int check_required_gains(parser *p, ctc_ctrl_type type, unsigned given)
{
    switch (type) {
    case CTC_CTRL_PID:
        if (!(given & G_KI)) {
            return error_at(p->err, JOB_MISSING_FIELD, "controller.ki", "is required");
        }
        return check_gain_pair(p, given, "controller");
    case CTC_CTRL_PD:
        return check_gain_pair(p, given, "controller");
    case CTC_CTRL_POLES:
        if (!(given & G_POLES)) {
            return error_at(p->err, JOB_MISSING_FIELD, "controller.poles", "is required");
        }
        return 0;
    case CTC_CTRL_LQR:
        if (!(given & G_Q))
            return error_at(p->err, JOB_MISSING_FIELD, "controller.Q", "is required");
        if (!(given & G_LAMBDA)) {
            return error_at(p->err, JOB_MISSING_FIELD, "controller.lambda", "is required");
        }
        return 0;
    case CTC_CTRL_NONE:
        break;
    }
    return 0;
}

/* g with the override o applied key by key; a pd/pid pair in o replaces the other pair in g */
static void merge_gains(gain_params *g, const gain_params *o)
{
    if ((o->given & G_PAIR_KP) && !(o->given & G_PAIR_ZETA)) g->given &= ~(unsigned)G_PAIR_ZETA;
    if ((o->given & G_PAIR_ZETA) && !(o->given & G_PAIR_KP)) g->given &= ~(unsigned)G_PAIR_KP;
    if (o->given & G_KP) g->kp = o->kp;
    if (o->given & G_KV) g->kv = o->kv;
    if (o->given & G_KI) g->ki = o->ki;
    if (o->given & G_ZETA) g->zeta = o->zeta;
    if (o->given & G_TAU) g->tau = o->tau;
    if (o->given & G_POLES) {
        memcpy(g->re, o->re, sizeof g->re);
        memcpy(g->im, o->im, sizeof g->im);
    }
    if (o->given & G_Q) {
        memcpy(g->Q, o->Q, sizeof g->Q);
        g->q_diagonal = o->q_diagonal;
    }
    if (o->given & G_LAMBDA) g->lambda = o->lambda;
    g->given |= o->given;
}

/* the gains of g by the library's design functions; their errors at field */
static int design_gains(parser *p, ctc_ctrl_type type, const gain_params *g, const char *field,
                        ctc_gains *out)
{
    char msg[512];
    ctc_status st = CTC_OK;
    double ki = type == CTC_CTRL_PID ? g->ki : 0.0;
    switch (type) {
    case CTC_CTRL_PD:
    case CTC_CTRL_PID:
        st = (g->given & G_KP) ? ctc_ctrl_pid(g->kp, g->kv, ki, out, msg, sizeof msg)
                               : ctc_ctrl_zeta_tau(g->zeta, g->tau, ki, out, msg, sizeof msg);
        break;
    case CTC_CTRL_POLES:
        st = ctc_ctrl_poles(g->re, g->im, out, msg, sizeof msg);
        break;
    case CTC_CTRL_LQR:
        st = ctc_ctrl_lqr(g->Q, g->lambda, out, NULL, msg, sizeof msg);
        break;
    case CTC_CTRL_NONE:
        break;
    }
    if (st == CTC_ENOMEM) return out_of_memory(p->err);
    if (st != CTC_OK) return error_at(p->err, JOB_INVALID_FIELD, field, "%s", msg);
    return 0;
}

/* the keys of g that were given, in canonical order */
static void put_gain_params(parser *p, cJSON *out, const gain_params *g)
{
    if (g->given & G_KP) put_number(p, out, "kp", g->kp);
    if (g->given & G_KV) put_number(p, out, "kv", g->kv);
    if (g->given & G_ZETA) put_number(p, out, "zeta", g->zeta);
    if (g->given & G_TAU) put_number(p, out, "tau", g->tau);
    if (g->given & G_KI) put_number(p, out, "ki", g->ki);
    if (g->given & G_POLES) {
        cJSON *poles = put(p, out, "poles", cJSON_CreateArray());
        for (int i = 0; i < 3; i++) {
            if (g->im[i] == 0) {
                put_number(p, poles, NULL, g->re[i]);
                continue;
            }
            cJSON *pole = put(p, poles, NULL, cJSON_CreateObject());
            put_number(p, pole, "re", g->re[i]);
            put_number(p, pole, "im", g->im[i]);
        }
    }
    if (g->given & G_Q) put_matrix3(p, out, "Q", g->Q, g->q_diagonal);
    if (g->given & G_LAMBDA) put_number(p, out, "lambda", g->lambda);
}

/* what one entry of a per-coordinate array stands for, in messages */
static const char *coordinate_word(const parser *p)
{
    return p->j->spec.chain.loop != NULL ? "independent coordinate" : "coordinate";
}

/* "controller.joints": nind overrides of the shared parameters, one per coordinate */
static int parse_gain_overrides(parser *p, const cJSON *v, ctc_ctrl_type type,
                                const gain_params *shared, const char *context, cJSON *out_ctrl)
{
    job *j = p->j;
    char path[PATH_LEN];
    if (!cJSON_IsArray(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, "controller.joints",
                        "must be an array of %d objects, one per %s (got %s)", j->nind,
                        coordinate_word(p), kind(v));
    }
    int len = cJSON_GetArraySize(v);
    if (len != j->nind) {
        return error_at(p->err, JOB_INVALID_FIELD, "controller.joints",
                        "must have %d entries, one per %s (got %d)", j->nind, coordinate_word(p),
                        len);
    }
    cJSON *out = put(p, out_ctrl, "joints", cJSON_CreateArray());
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        gain_params override = {0};
        index_path(path, "controller.joints", i);
        if (object_at(p, e, path) != 0 ||
            check_keys(p, e, path, gain_keys[type], gains_all, context) != 0 ||
            read_gain_params(p, e, path, &override) != 0) {
            return -1;
        }
        put_gain_params(p, put(p, out, NULL, cJSON_CreateObject()), &override);
        if (override.given == 0) continue; /* {} keeps the shared gains */

        gain_params mine = *shared;
        merge_gains(&mine, &override);
        if ((type == CTC_CTRL_PD || type == CTC_CTRL_PID) && check_gain_pair(p, mine.given, path)) {
            return -1;
        }
        if (design_gains(p, type, &mine, path, &j->gains[i]) != 0) return -1;
    }
    return 0;
}

/* "controller.model": the controller's model of the plant */
static int parse_ctrl_model(parser *p, const cJSON *ctrl, cJSON *out_ctrl)
{
    static const char *const model_keys[] = {"mass_scale", "inertia_scale", NULL};
    const char *keys[2] = {"mass_scale", "inertia_scale"};
    double *scales[2] = {&p->j->spec.model_mass_scale, &p->j->spec.model_inertia_scale};
    const cJSON *v = member(ctrl, "model");
    if (v != NULL && (object_at(p, v, "controller.model") != 0 ||
                      check_keys(p, v, "controller.model", model_keys, NULL, NULL) != 0)) {
        return -1;
    }
    cJSON *out = put(p, out_ctrl, "model", cJSON_CreateObject());
    for (int i = 0; i < 2; i++) {
        char at[PATH_LEN];
        if (member_number(p, v, "controller.model", keys[i], OPTIONAL, 1.0, scales[i]) != 0) {
            return -1;
        }
        if (!(*scales[i] > 0)) {
            return error_at(p->err, JOB_INVALID_FIELD, key_path(at, "controller.model", keys[i]),
                            "must be positive (got %g)", *scales[i]);
        }
        put_number(p, out, keys[i], *scales[i]);
    }
    return 0;
}

static int parse_controller(parser *p, const cJSON *doc)
{
    job *j = p->j;
    const char *names[5];
    int type;
    for (int t = 0; t < 5; t++) names[t] = ctc_ctrl_type_name((ctc_ctrl_type)t);
    const cJSON *v =
        required_member(p, doc, "", "controller", " ({\"type\": \"none\"} for a passive run)");
    if (v == NULL || typed_object(p, v, "controller", "type", REQUIRED, 0, names, 5,
                                  "controller type", ctrl_keys, ctrl_keys_all, &type) != 0) {
        return -1;
    }
    p->ctrl = j->spec.controller = (ctc_ctrl_type)type;
    j->spec.model_mass_scale = j->spec.model_inertia_scale = 1.0;
    cJSON *out = put(p, p->norm, "controller", cJSON_CreateObject());
    put_string(p, out, "type", names[type]);
    if (p->ctrl == CTC_CTRL_NONE) return 0;

    /* computed torque control per coordinate: not for a spherical joint's quaternion */
    if (p->spherical[0] != '\0') {
        const char *allowed = j->spec.chain.loop != NULL
                                  ? "a spherical joint in a loop must be dependent, or the run "
                                    "passive (controller \"none\")"
                                  : "spherical joints are allowed only with controller \"none\"";
        return error_at(p->err, JOB_INVALID_FIELD, "controller.type",
                        "\"%s\" cannot drive the spherical joint of %s (its quaternion error is "
                        "not a per-coordinate error); %s",
                        names[type], p->spherical, allowed);
    }

    /* the gains the coordinates share, designed once */
    gain_params shared = {0};
    ctc_gains gains;
    if (read_gain_params(p, v, "controller", &shared) != 0 ||
        check_required_gains(p, p->ctrl, shared.given) != 0 ||
        design_gains(p, p->ctrl, &shared, "controller", &gains) != 0) {
        return -1;
    }
    put_gain_params(p, out, &shared);
    j->gains = alloc(p, (size_t)j->nind, sizeof *j->gains);
    if (j->gains == NULL) return -1;
    for (int i = 0; i < j->nind; i++) j->gains[i] = gains;
    j->spec.gains = j->gains;

    /* per-coordinate overrides, then the controller's model */
    const cJSON *joints = member(v, "joints");
    char context[64];
    snprintf(context, sizeof context, "controller type \"%s\"", names[type]);
    if (joints != NULL && parse_gain_overrides(p, joints, p->ctrl, &shared, context, out) != 0) {
        return -1;
    }
    return parse_ctrl_model(p, v, out);
}

/* ---- trajectory and disturbance: one object for every coordinate, or one per coordinate ---- */

/* Reads one item v (at path) for coordinates first .. first + count - 1, writing its normalised
 * form into out. */
typedef int (*coord_item_parser)(parser *p, const cJSON *v, const char *path, int first, int count,
                                 cJSON *out);

/* v (the document's key): one object for every coordinate, or an array of nind of them */
static int parse_per_coordinate(parser *p, const cJSON *v, const char *key, coord_item_parser item)
{
    int nind = p->j->nind;
    if (cJSON_IsObject(v)) {
        return item(p, v, key, 0, nind, put(p, p->norm, key, cJSON_CreateObject()));
    }
    if (!cJSON_IsArray(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, key,
                        "must be an object or an array of %d objects, one per %s (got %s)", nind,
                        coordinate_word(p), kind(v));
    }
    int len = cJSON_GetArraySize(v);
    if (len != nind) {
        return error_at(p->err, JOB_INVALID_FIELD, key, "must have %d entries, one per %s (got %d)",
                        nind, coordinate_word(p), len);
    }
    cJSON *out = put(p, p->norm, key, cJSON_CreateArray());
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        char path[PATH_LEN];
        if (item(p, e, index_path(path, key, i), i, 1, put(p, out, NULL, cJSON_CreateObject()))) {
            return -1;
        }
    }
    return 0;
}

static const char *const traj_names[] = {"constant",   "sine",     "cosine",
                                         "polynomial", "min_jerk", "spline"};
static const char *const traj_keys_all[] = {
    "type",  "value", "amplitude", "period", "phase",    "offset", "coefficients", "from", "to",
    "start", "end",   "times",     "values", "boundary", NULL};
static const char *const traj_keys_constant[] = {"type", "value", NULL};
static const char *const traj_keys_periodic[] = {"type",  "amplitude", "period",
                                                 "phase", "offset",    NULL};
static const char *const traj_keys_polynomial[] = {"type", "coefficients", NULL};
static const char *const traj_keys_min_jerk[] = {"type", "from", "to", "start", "end", NULL};
static const char *const traj_keys_spline[] = {"type", "times", "values", "boundary", NULL};
static const char *const *const traj_keys[] = {
    [CTC_TRAJ_CONSTANT] = traj_keys_constant, [CTC_TRAJ_SINE] = traj_keys_periodic,
    [CTC_TRAJ_COSINE] = traj_keys_periodic,   [CTC_TRAJ_POLYNOMIAL] = traj_keys_polynomial,
    [CTC_TRAJ_MIN_JERK] = traj_keys_min_jerk, [CTC_TRAJ_SPLINE] = traj_keys_spline};
static const char *const boundary_names[] = {
    [CTC_SPLINE_CLAMPED] = "clamped", [CTC_SPLINE_NATURAL] = "natural"};

/* a spline's knots, built once per coordinate (each ctc_traj owns its knots) */
static int parse_spline(parser *p, const cJSON *v, const char *path, int first, int count,
                        cJSON *out)
{
    char at[PATH_LEN], msg[256];
    double *times = NULL, *values = NULL;
    int n = 0, nvalues = 0, boundary = CTC_SPLINE_CLAMPED, rc = -1;
    const cJSON *t = required_member(p, v, path, "times", "");
    const cJSON *y = t != NULL ? required_member(p, v, path, "values", "") : NULL;
    const cJSON *b = member(v, "boundary");
    if (y == NULL ||
        number_list_at(p, t, key_path(at, path, "times"), 2, CTC_TRAJ_MAX_KNOTS, &times, &n) ||
        number_list_at(p, y, key_path(at, path, "values"), 0, CTC_TRAJ_MAX_KNOTS, &values,
                       &nvalues)) {
        goto done;
    }
    if (nvalues != n) {
        error_at(p->err, JOB_INVALID_FIELD, key_path(at, path, "values"),
                 "must have as many entries as \"times\" (%d, got %d)", n, nvalues);
        goto done;
    }
    if (b != NULL && enum_at(p, b, key_path(at, path, "boundary"), boundary_names, 2, &boundary)) {
        goto done;
    }
    put_numbers(p, out, "times", times, n);
    put_numbers(p, out, "values", values, n);
    put_string(p, out, "boundary", boundary_names[boundary]);
    for (int i = first; i < first + count; i++) {
        ctc_status st = ctc_traj_spline(n, times, values, (ctc_spline_boundary)boundary,
                                        &p->j->traj[i], msg, sizeof msg);
        if (st == CTC_ENOMEM) {
            out_of_memory(p->err);
            goto done;
        }
        if (st != CTC_OK) {
            error_at(p->err, JOB_INVALID_FIELD, path, "%s", msg);
            goto done;
        }
    }
    rc = 0;
done:
    free(times);
    free(values);
    return rc;
}

static int parse_traj_item(parser *p, const cJSON *v, const char *path, int first, int count,
                           cJSON *out)
{
    char at[PATH_LEN], msg[256];
    int type, n;
    ctc_traj tr = {0};
    double *coef = NULL;
    if (typed_object(p, v, path, "type", REQUIRED, 0, traj_names, 6, "trajectory type", traj_keys,
                     traj_keys_all, &type) != 0) {
        return -1;
    }
    tr.type = (ctc_traj_type)type;
    put_string(p, out, "type", traj_names[type]);
    switch (tr.type) {
    case CTC_TRAJ_CONSTANT:
        if (member_number(p, v, path, "value", REQUIRED, 0, &tr.value) != 0) return -1;
        put_number(p, out, "value", tr.value);
        break;
    case CTC_TRAJ_SINE:
    case CTC_TRAJ_COSINE:
        if (member_number(p, v, path, "amplitude", REQUIRED, 0, &tr.amplitude) != 0 ||
            member_number(p, v, path, "period", REQUIRED, 0, &tr.period) != 0 ||
            member_number(p, v, path, "phase", OPTIONAL, 0, &tr.phase) != 0 ||
            member_number(p, v, path, "offset", OPTIONAL, 0, &tr.offset) != 0) {
            return -1;
        }
        put_number(p, out, "amplitude", tr.amplitude);
        put_number(p, out, "period", tr.period);
        put_number(p, out, "phase", tr.phase);
        put_number(p, out, "offset", tr.offset);
        break;
    case CTC_TRAJ_POLYNOMIAL: {
        const cJSON *c = required_member(p, v, path, "coefficients", "");
        if (c == NULL || number_list_at(p, c, key_path(at, path, "coefficients"), 1,
                                        CTC_TRAJ_MAX_COEF, &coef, &n) != 0) {
            free(coef);
            return -1;
        }
        tr.ncoef = n;
        memcpy(tr.coef, coef, (size_t)n * sizeof *coef);
        free(coef);
        put_numbers(p, out, "coefficients", tr.coef, n);
        break;
    }
    case CTC_TRAJ_MIN_JERK:
        if (member_number(p, v, path, "from", REQUIRED, 0, &tr.q0) != 0 ||
            member_number(p, v, path, "to", REQUIRED, 0, &tr.q1) != 0 ||
            member_number(p, v, path, "start", REQUIRED, 0, &tr.t0) != 0 ||
            member_number(p, v, path, "end", REQUIRED, 0, &tr.t1) != 0) {
            return -1;
        }
        put_number(p, out, "from", tr.q0);
        put_number(p, out, "to", tr.q1);
        put_number(p, out, "start", tr.t0);
        put_number(p, out, "end", tr.t1);
        break;
    case CTC_TRAJ_SPLINE:
        return parse_spline(p, v, path, first, count, out);
    }
    if (ctc_traj_check(&tr, msg, sizeof msg) != CTC_OK) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "%s", msg);
    }
    for (int i = first; i < first + count; i++) p->j->traj[i] = tr;
    return 0;
}

static int parse_trajectory(parser *p, const cJSON *doc)
{
    job *j = p->j;
    const cJSON *v = member(doc, "trajectory");
    if (p->ctrl == CTC_CTRL_NONE) {
        if (v == NULL) return 0;
        return error_at(p->err, JOB_INVALID_FIELD, "trajectory",
                        "not allowed with controller \"none\" (a passive run has no desired "
                        "motion)");
    }
    if (v == NULL) {
        return error_at(p->err, JOB_MISSING_FIELD, "trajectory",
                        "is required with controller \"%s\"", ctc_ctrl_type_name(p->ctrl));
    }
    j->traj = alloc(p, (size_t)j->nind, sizeof *j->traj);
    if (j->traj == NULL) return -1;
    j->spec.traj = j->traj;
    return parse_per_coordinate(p, v, "trajectory", parse_traj_item);
}

static const char *const disturb_names[] = {"none", "constant", "sine", "step"};
static const char *const disturb_keys_all[] = {"type",  "value",  "amplitude", "period",
                                               "phase", "offset", "time",      NULL};
static const char *const disturb_keys_none[] = {"type", NULL};
static const char *const disturb_keys_constant[] = {"type", "value", NULL};
static const char *const disturb_keys_sine[] = {"type",  "amplitude", "period",
                                                "phase", "offset",    NULL};
static const char *const disturb_keys_step[] = {"type", "value", "time", NULL};
static const char *const *const disturb_keys[] = {[CTC_DISTURB_NONE] = disturb_keys_none,
                                                  [CTC_DISTURB_CONSTANT] = disturb_keys_constant,
                                                  [CTC_DISTURB_SINE] = disturb_keys_sine,
                                                  [CTC_DISTURB_STEP] = disturb_keys_step};

static int parse_disturb_item(parser *p, const cJSON *v, const char *path, int first, int count,
                              cJSON *out)
{
    char msg[256];
    int type;
    ctc_disturb z = {0};
    if (typed_object(p, v, path, "type", REQUIRED, 0, disturb_names, 4, "disturbance type",
                     disturb_keys, disturb_keys_all, &type) != 0) {
        return -1;
    }
    z.type = (ctc_disturb_type)type;
    put_string(p, out, "type", disturb_names[type]);
    switch (z.type) {
    case CTC_DISTURB_NONE:
        break;
    case CTC_DISTURB_CONSTANT:
        if (member_number(p, v, path, "value", REQUIRED, 0, &z.value) != 0) return -1;
        put_number(p, out, "value", z.value);
        break;
    case CTC_DISTURB_SINE:
        if (member_number(p, v, path, "amplitude", REQUIRED, 0, &z.amplitude) != 0 ||
            member_number(p, v, path, "period", REQUIRED, 0, &z.period) != 0 ||
            member_number(p, v, path, "phase", OPTIONAL, 0, &z.phase) != 0 ||
            member_number(p, v, path, "offset", OPTIONAL, 0, &z.offset) != 0) {
            return -1;
        }
        put_number(p, out, "amplitude", z.amplitude);
        put_number(p, out, "period", z.period);
        put_number(p, out, "phase", z.phase);
        put_number(p, out, "offset", z.offset);
        break;
    case CTC_DISTURB_STEP:
        if (member_number(p, v, path, "value", REQUIRED, 0, &z.value) != 0 ||
            member_number(p, v, path, "time", REQUIRED, 0, &z.time) != 0) {
            return -1;
        }
        put_number(p, out, "value", z.value);
        put_number(p, out, "time", z.time);
        break;
    }
    if (ctc_disturb_check(&z, msg, sizeof msg) != CTC_OK) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "%s", msg);
    }
    for (int i = first; i < first + count; i++) p->j->disturb[i] = z;
    return 0;
}

/* "disturbance": absent means none; a disturbance that is none everywhere leaves spec.disturb
 * NULL, so a job and its normalised document give the same spec */
static int parse_disturbance(parser *p, const cJSON *doc)
{
    job *j = p->j;
    const cJSON *v = member(doc, "disturbance");
    if (v == NULL) {
        cJSON *out = put(p, p->norm, "disturbance", cJSON_CreateObject());
        put_string(p, out, "type", disturb_names[CTC_DISTURB_NONE]);
        return 0;
    }
    j->disturb = alloc(p, (size_t)j->nind, sizeof *j->disturb);
    if (j->disturb == NULL || parse_per_coordinate(p, v, "disturbance", parse_disturb_item) != 0) {
        return -1;
    }
    for (int i = 0; i < j->nind; i++) {
        if (j->disturb[i].type != CTC_DISTURB_NONE) {
            j->spec.disturb = j->disturb;
            return 0;
        }
    }
    free(j->disturb);
    j->disturb = NULL;
    return 0;
}

/* ---- integrator, duration, output, limits ---- */

static const char *const integ_keys_all[] = {"method",       "step",     "rtol",      "atol",
                                             "initial_step", "max_step", "max_steps", NULL};
static const char *const integ_keys_fixed[] = {"method", "step", "max_steps", NULL};
static const char *const integ_keys_adaptive[] = {"method",   "rtol",      "atol", "initial_step",
                                                  "max_step", "max_steps", NULL};
static const char *const *const integ_keys[] = {[CTC_INTEG_RK4] = integ_keys_fixed,
                                                [CTC_INTEG_DOPRI5] = integ_keys_adaptive,
                                                [CTC_INTEG_BDF] = integ_keys_adaptive};

static int parse_integrator(parser *p, const cJSON *doc)
{
    ctc_integ_spec *s = &p->j->spec.integrator;
    const cJSON *v = member(doc, "integrator");
    const char *names[3];
    int method;
    for (int m = 0; m < 3; m++) names[m] = ctc_integ_method_name((ctc_integ_method)m);
    if (typed_object(p, v, "integrator", "method", OPTIONAL, CTC_INTEG_DOPRI5, names, 3, "method",
                     integ_keys, integ_keys_all, &method) != 0) {
        return -1;
    }
    s->method = (ctc_integ_method)method;
    cJSON *out = put(p, p->norm, "integrator", cJSON_CreateObject());
    put_string(p, out, "method", names[method]);

    /* the method's own settings */
    if (s->method == CTC_INTEG_RK4) {
        if (member_number(p, v, "integrator", "step", OPTIONAL, DEFAULT_RK4_STEP, &s->step) != 0) {
            return -1;
        }
        put_number(p, out, "step", s->step);
    } else {
        if (member_number(p, v, "integrator", "rtol", OPTIONAL, DEFAULT_RTOL, &s->rtol) != 0 ||
            member_number(p, v, "integrator", "atol", OPTIONAL, DEFAULT_ATOL, &s->atol) != 0 ||
            member_number(p, v, "integrator", "initial_step", OPTIONAL, 0, &s->initial_step) ||
            member_number(p, v, "integrator", "max_step", OPTIONAL, 0, &s->max_step) != 0) {
            return -1;
        }
        put_number(p, out, "rtol", s->rtol);
        put_number(p, out, "atol", s->atol);
        put_number(p, out, "initial_step", s->initial_step);
        put_number(p, out, "max_step", s->max_step);
    }

    /* a whole number of steps; 0 = no limit */
    double steps;
    if (member_number(p, v, "integrator", "max_steps", OPTIONAL, DEFAULT_MAX_STEPS, &steps) != 0) {
        return -1;
    }
    if (!(steps >= 0 && steps <= MAX_WHOLE && steps == floor(steps))) {
        return error_at(p->err, JOB_INVALID_FIELD, "integrator.max_steps",
                        "must be a whole number from 0 (no limit) to 2^53 (got %g)", steps);
    }
    s->max_steps = (long)steps;
    put_number(p, out, "max_steps", steps);

    char msg[256];
    if (ctc_integ_check(s, msg, sizeof msg) != CTC_OK) {
        return error_at(p->err, JOB_INVALID_FIELD, "integrator", "%s", msg);
    }
    return 0;
}

static int parse_duration(parser *p, const cJSON *doc)
{
    double *d = &p->j->spec.duration;
    if (member_number(p, doc, "", "duration", REQUIRED, 0, d) != 0) return -1;
    if (!(*d > 0)) {
        return error_at(p->err, JOB_INVALID_FIELD, "duration", "must be positive (got %g s)", *d);
    }
    if (*d > JOB_MAX_DURATION) {
        return error_at(p->err, JOB_LIMIT_EXCEEDED, "duration", "must be at most %g s (got %g s)",
                        JOB_MAX_DURATION, *d);
    }
    put_number(p, p->norm, "duration", *d);
    return 0;
}

static unsigned tracking_channels(void)
{
    return CTC_CH_BIT(CTC_CH_Q_DES) | CTC_CH_BIT(CTC_CH_QD_DES) | CTC_CH_BIT(CTC_CH_E) |
           CTC_CH_BIT(CTC_CH_W);
}

/* values per sample of channel c (sim.h): q nq, qdot nv, energy and loop 2, the others one per
 * controlled coordinate */
static int channel_width(const job *j, int c)
{
    switch (c) {
    case CTC_CH_Q:
        return j->nq;
    case CTC_CH_QD:
        return j->nv;
    case CTC_CH_ENERGY:
    case CTC_CH_LOOP:
        return 2;
    default:
        return j->nind;
    }
}

/* why channel c does not apply to this job ("needs a controller (this run is passive)") */
static const char *why_not_applicable(int c)
{
    if (c == CTC_CH_LOOP) return "needs a loop (\"scene.loop\")";
    if (c == CTC_CH_TAU) return "has no columns (the loop has no independent coordinates)";
    return "needs a controller (this run is passive)";
}

/* "output.channels" into spec.channels (explicit; default every channel that applies) */
static int parse_channels(parser *p, const cJSON *output, const char *const *names, unsigned *mask)
{
    unsigned applicable = CTC_CH_ALL;
    if (p->ctrl == CTC_CTRL_NONE) applicable &= ~tracking_channels();
    if (p->j->spec.chain.loop == NULL) applicable &= ~CTC_CH_BIT(CTC_CH_LOOP);
    if (p->j->nind == 0) applicable &= ~CTC_CH_BIT(CTC_CH_TAU); /* a loop of dependent joints */
    const cJSON *v = member(output, "channels");
    if (v == NULL) {
        *mask = applicable;
        return 0;
    }
    if (!cJSON_IsArray(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, "output.channels",
                        "must be an array of channel names (got %s)", kind(v));
    }
    if (v->child == NULL) {
        return error_at(p->err, JOB_INVALID_FIELD, "output.channels",
                        "must name at least one channel");
    }
    *mask = 0;
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        char at[PATH_LEN];
        int c = 0;
        index_path(at, "output.channels", i);
        if (enum_at(p, e, at, names, CTC_NCHANNELS, &c) != 0) return -1;
        if (*mask & CTC_CH_BIT(c)) {
            return error_at(p->err, JOB_INVALID_FIELD, at, "\"%s\" is listed twice", names[c]);
        }
        if (!(applicable & CTC_CH_BIT(c))) {
            return error_at(p->err, JOB_INVALID_FIELD, at, "channel \"%s\" %s", names[c],
                            why_not_applicable(c));
        }
        *mask |= CTC_CH_BIT(c);
    }
    return 0;
}

static int parse_output(parser *p, const cJSON *doc)
{
    static const char *const output_keys[] = {"interval", "channels", NULL};
    job *j = p->j;
    ctc_sim_spec *s = &j->spec;
    const cJSON *v = member(doc, "output");
    if (v != NULL && (object_at(p, v, "output") != 0 ||
                      check_keys(p, v, "output", output_keys, NULL, NULL) != 0)) {
        return -1;
    }

    /* the sample interval: positive, within the duration, not too many samples */
    double def = fmin(DEFAULT_INTERVAL, s->duration);
    if (member_number(p, v, "output", "interval", OPTIONAL, def, &s->output_interval) != 0) {
        return -1;
    }
    if (!(s->output_interval > 0)) {
        return error_at(p->err, JOB_INVALID_FIELD, "output.interval", "must be positive (got %g s)",
                        s->output_interval);
    }
    if (s->output_interval > s->duration) {
        return error_at(p->err, JOB_INVALID_FIELD, "output.interval",
                        "must not exceed the duration (got %g s > %g s)", s->output_interval,
                        s->duration);
    }
    double samples = floor(s->duration / s->output_interval) + 2; /* a bound: t = 0 .. duration */
    if (samples > JOB_MAX_SAMPLES) {
        return error_at(p->err, JOB_LIMIT_EXCEEDED, "output.interval",
                        "gives up to %.0f samples over %g s; the limit is %d (use a longer "
                        "interval)",
                        samples, s->duration, JOB_MAX_SAMPLES);
    }

    /* the channels, and the values they record */
    const char *names[CTC_NCHANNELS];
    for (int c = 0; c < CTC_NCHANNELS; c++) names[c] = ctc_channel_name((ctc_channel)c);
    if (parse_channels(p, v, names, &s->channels) != 0) return -1;
    double per_sample = 1; /* t */
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (!(s->channels & CTC_CH_BIT(c))) continue;
        per_sample += channel_width(j, c);
    }
    if (samples * per_sample > JOB_MAX_VALUES) {
        return error_at(p->err, JOB_LIMIT_EXCEEDED, "output",
                        "would record up to %.0f values (%.0f samples x %.0f per sample); the "
                        "limit is %d (record fewer channels or use a longer interval)",
                        samples * per_sample, samples, per_sample, JOB_MAX_VALUES);
    }

    cJSON *out = put(p, p->norm, "output", cJSON_CreateObject());
    put_number(p, out, "interval", s->output_interval);
    cJSON *channels = put(p, out, "channels", cJSON_CreateArray());
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (s->channels & CTC_CH_BIT(c)) put(p, channels, NULL, cJSON_CreateString(names[c]));
    }
    return 0;
}

static int parse_limits(parser *p, const cJSON *doc)
{
    static const char *const limit_keys[] = {"max_speed", "wall_time", NULL};
    ctc_sim_spec *s = &p->j->spec;
    const cJSON *v = member(doc, "limits");
    if (v != NULL && (object_at(p, v, "limits") != 0 ||
                      check_keys(p, v, "limits", limit_keys, NULL, NULL) != 0)) {
        return -1;
    }
    if (member_number(p, v, "limits", "max_speed", OPTIONAL, DEFAULT_MAX_SPEED, &s->max_speed) ||
        member_number(p, v, "limits", "wall_time", OPTIONAL, 0, &s->wall_limit)) {
        return -1;
    }
    if (!(s->max_speed > 0)) {
        return error_at(p->err, JOB_INVALID_FIELD, "limits.max_speed", "must be positive (got %g)",
                        s->max_speed);
    }
    if (!(s->wall_limit >= 0)) {
        return error_at(p->err, JOB_INVALID_FIELD, "limits.wall_time",
                        "must not be negative (got %g s)", s->wall_limit);
    }
    cJSON *out = put(p, p->norm, "limits", cJSON_CreateObject());
    put_number(p, out, "max_speed", s->max_speed);
    put_number(p, out, "wall_time", s->wall_limit);
    return 0;
}

/* "threads": a whole number 1..CTC_MAX_THREADS, default 1 (serial) */
static int parse_threads(parser *p, const cJSON *doc)
{
    double threads;
    if (member_number(p, doc, "", "threads", OPTIONAL, 1, &threads) != 0) return -1;
    if (!(threads >= 1 && threads <= CTC_MAX_THREADS && threads == floor(threads))) {
        return error_at(p->err, JOB_INVALID_FIELD, "threads",
                        "must be a whole number from 1 to %d (got %g)", CTC_MAX_THREADS, threads);
    }
    p->j->spec.threads = (int)threads;
    put_number(p, p->norm, "threads", threads);
    return 0;
}

/* ---- the document ---- */

static const char *const job_keys[] = {"name",        "scene",      "controller", "trajectory",
                                       "disturbance", "integrator", "duration",   "output",
                                       "limits",      "threads",    NULL};

/* the whole check of the spec by the library, after the format's own; what it finds wrong with
 * a loop (the mobility, the configuration at q0) is reported at the loop or at q0 */
static int check_spec(parser *p)
{
    char msg[512];
    if (p->oom) return out_of_memory(p->err);
    ctc_status st = ctc_sim_check(&p->j->spec, msg, sizeof msg);
    if (st == CTC_ENOMEM) return out_of_memory(p->err);
    if (st != CTC_OK) {
        const char *field = "";
        if (p->j->spec.chain.loop != NULL && strcmp(loop_error_field(msg), "scene") != 0) {
            field = loop_error_field(msg);
        }
        return error_at(p->err, JOB_INVALID_FIELD, field, "%s", msg);
    }
    return 0;
}

/* Parses a job document without a preset (doc's keys not repeated). */
static int parse_job(const cJSON *doc, const char *default_name, job **out, job_error *err)
{
    job *j = calloc(1, sizeof *j);
    if (j == NULL) return out_of_memory(err);
    parser p = {.j = j, .err = err, .ctrl = CTC_CTRL_NONE};
    j->normalised = p.norm = cJSON_CreateObject();
    if (p.norm == NULL || check_keys(&p, doc, "", job_keys, NULL, NULL) != 0 ||
        parse_name(&p, doc, default_name) != 0 || parse_scene(&p, doc) != 0 ||
        parse_controller(&p, doc) != 0 || parse_trajectory(&p, doc) != 0 ||
        parse_disturbance(&p, doc) != 0 || parse_integrator(&p, doc) != 0 ||
        parse_duration(&p, doc) != 0 || parse_output(&p, doc) != 0 || parse_limits(&p, doc) != 0 ||
        parse_threads(&p, doc) != 0 || check_spec(&p) != 0) {
        if (p.norm == NULL) out_of_memory(err);
        job_free(j);
        return -1;
    }
    *out = j;
    return 0;
}

/* ---- presets ---- */

/* a patch object that names another "type" or "method" than its target's starts afresh: the
 * old type's keys (a PID's ki, dopri5's rtol) do not carry over to the new one */
static int changes_kind(const cJSON *target, const cJSON *patch)
{
    static const char *const keys[] = {"type", "method"};
    for (int i = 0; i < 2; i++) {
        const cJSON *a = cJSON_GetObjectItemCaseSensitive(target, keys[i]);
        const cJSON *b = cJSON_GetObjectItemCaseSensitive(patch, keys[i]);
        if (cJSON_IsString(a) && cJSON_IsString(b) && strcmp(a->valuestring, b->valuestring) != 0)
            return 1;
    }
    return 0;
}

/* RFC 7386 merge patch: returns target (consumed) with patch applied, or NULL out of memory.
 * One refinement: an object whose "type" or "method" the patch changes is replaced whole. */
static cJSON *merge_patch(cJSON *target, const cJSON *patch)
{
    if (!cJSON_IsObject(patch) || (cJSON_IsObject(target) && changes_kind(target, patch))) {
        cJSON_Delete(target);
        return cJSON_Duplicate(patch, 1);
    }
    if (!cJSON_IsObject(target)) {
        cJSON_Delete(target);
        target = cJSON_CreateObject();
        if (target == NULL) return NULL;
    }
    for (const cJSON *m = patch->child; m != NULL; m = m->next) {
        cJSON *old = cJSON_DetachItemFromObjectCaseSensitive(target, m->string);
        if (cJSON_IsNull(m)) {
            cJSON_Delete(old); /* null removes the key */
            continue;
        }
        cJSON *merged = merge_patch(old, m);
        if (merged == NULL || !cJSON_AddItemToObject(target, m->string, merged)) {
            cJSON_Delete(merged);
            cJSON_Delete(target);
            return NULL;
        }
    }
    return target;
}

/* the names of the presets, comma-separated, into buf */
static void list_presets(char *buf, size_t len)
{
    int count;
    const preset *list = presets_list(&count);
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; i < count; i++) {
        int w = snprintf(buf + used, len - used, "%s%s", i > 0 ? ", " : "", list[i].name);
        if (w < 0 || (size_t)w >= len - used) break;
        used += (size_t)w;
    }
}

/* The document of a preset request: the preset's own, with the request's other keys merged in
 * (RFC 7386). *out owns it. */
static int expand_preset(const cJSON *request, cJSON **out, const preset **used, job_error *err)
{
    const cJSON *name = member(request, "preset");
    if (!cJSON_IsString(name)) {
        return error_at(err, JOB_INVALID_FIELD, "preset", "must be a string (got %s)", kind(name));
    }
    const preset *pr = presets_find(name->valuestring);
    if (pr == NULL) {
        char names[400];
        list_presets(names, sizeof names);
        return error_at(err, JOB_UNKNOWN_PRESET, "preset",
                        "unknown preset \"%s\" (the presets are: %s)", name->valuestring, names);
    }

    /* the patch: the request without "preset" and the preset's parameters */
    cJSON *patch = cJSON_Duplicate(request, 1);
    if (patch == NULL) return out_of_memory(err);
    cJSON_DeleteItemFromObjectCaseSensitive(patch, "preset");
    for (const char *const *param = pr->params; param != NULL && *param != NULL; param++) {
        cJSON_DeleteItemFromObjectCaseSensitive(patch, *param);
    }

    cJSON *doc = pr->build(request, err);
    if (doc == NULL) {
        cJSON_Delete(patch);
        if (err->code == JOB_OK) {
            error_at(err, JOB_INVALID_FIELD, "preset", "preset \"%s\" could not be built",
                     pr->name);
        }
        return -1;
    }
    /* the controller type the preset's name speaks of, before the patch may change it */
    char preset_ctrl[16] = "";
    const cJSON *ctrl_type = member(member(doc, "controller"), "type");
    if (cJSON_IsString(ctrl_type))
        snprintf(preset_ctrl, sizeof preset_ctrl, "%s", ctrl_type->valuestring);

    doc = merge_patch(doc, patch);
    cJSON_Delete(patch);
    if (doc == NULL) return out_of_memory(err);

    /* a controller of another type, with no name given: the name says which (presets.h) */
    ctrl_type = member(member(doc, "controller"), "type");
    const cJSON *preset_name = member(doc, "name");
    if (member(request, "name") == NULL && cJSON_IsString(ctrl_type) &&
        cJSON_IsString(preset_name) && strcmp(ctrl_type->valuestring, preset_ctrl) != 0) {
        char renamed[JOB_MAX_NAME + 1];
        if (presets_name_for_controller(preset_name->valuestring, preset_ctrl,
                                        ctrl_type->valuestring, renamed, sizeof renamed) == 0) {
            cJSON *v = cJSON_CreateString(renamed);
            if (v == NULL || !cJSON_ReplaceItemInObjectCaseSensitive(doc, "name", v)) {
                cJSON_Delete(v);
                cJSON_Delete(doc);
                return out_of_memory(err);
            }
        }
    }
    *out = doc;
    *used = pr;
    return 0;
}

/* ---- the interface ---- */

static void clear_error(job_error *err)
{
    err->code = JOB_OK;
    err->field[0] = '\0';
    err->message[0] = '\0';
}

int job_from_json(const cJSON *doc, job **out, job_error *err)
{
    *out = NULL;
    clear_error(err);
    if (!cJSON_IsObject(doc)) {
        return error_at(err, JOB_INVALID_FIELD, "", "the job must be a JSON object (got %s)",
                        kind(doc));
    }
    if (check_repeated_keys(err, doc, "") != 0) return -1;
    if (member(doc, "preset") == NULL) return parse_job(doc, DEFAULT_NAME, out, err);

    /* a preset: expand it, then parse the result as any job */
    cJSON *expanded = NULL;
    const preset *pr = NULL;
    if (expand_preset(doc, &expanded, &pr, err) != 0) return -1;
    int rc = check_repeated_keys(err, expanded, "");
    if (rc == 0) rc = parse_job(expanded, pr->name, out, err);
    cJSON_Delete(expanded);
    if (rc == 0 && ((*out)->preset = strdup(pr->name)) == NULL) {
        job_free(*out);
        *out = NULL;
        return out_of_memory(err);
    }
    return rc;
}

static int is_json_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

/* 1-based line and column (in bytes) of text[pos] */
static void line_column(const char *text, size_t pos, int *line, int *column)
{
    *line = 1;
    *column = 1;
    for (size_t i = 0; i < pos; i++) {
        if (text[i] == '\n') {
            ++*line;
            *column = 1;
        } else {
            ++*column;
        }
    }
}

int job_parse(const char *text, size_t len, job **out, job_error *err)
{
    int line, column;
    *out = NULL;
    clear_error(err);
    if (text == NULL) len = 0;
    size_t start = 0;
    while (start < len && is_json_space(text[start])) start++;
    if (start == len) return error_at(err, JOB_INVALID_JSON, "", "empty document");

    /* cJSON stops at the end of the first value: what follows must be white space */
    const char *end = NULL;
    cJSON *doc = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    if (doc == NULL) {
        size_t pos = end != NULL ? (size_t)(end - text) : 0;
        line_column(text, pos, &line, &column);
        return error_at(err, JOB_INVALID_JSON, "", "invalid JSON at line %d, column %d", line,
                        column);
    }
    size_t rest = (size_t)(end - text);
    while (rest < len && is_json_space(text[rest])) rest++;
    if (rest < len) {
        cJSON_Delete(doc);
        line_column(text, rest, &line, &column);
        return error_at(err, JOB_INVALID_JSON, "",
                        "invalid JSON at line %d, column %d: text after the end of the document",
                        line, column);
    }
    int rc = job_from_json(doc, out, err);
    cJSON_Delete(doc);
    return rc;
}

void job_free(job *j)
{
    if (j == NULL) return;
    for (int i = 0; j->traj != NULL && i < j->nind; i++) ctc_traj_free(&j->traj[i]);
    free(j->traj);
    free(j->disturb);
    free(j->gains);
    free(j->q0);
    free(j->v0);
    free(j->bodies);
    free(j->joints);
    free(j->independent);
    free(j->name);
    free(j->preset);
    cJSON_Delete(j->normalised);
    free(j);
}

const char *job_error_code_name(job_error_code c)
{
    switch (c) {
    case JOB_OK:
        return "OK";
    case JOB_INVALID_JSON:
        return "INVALID_JSON";
    case JOB_MISSING_FIELD:
        return "MISSING_FIELD";
    case JOB_UNKNOWN_FIELD:
        return "UNKNOWN_FIELD";
    case JOB_INVALID_FIELD:
        return "INVALID_FIELD";
    case JOB_UNKNOWN_PRESET:
        return "UNKNOWN_PRESET";
    case JOB_LIMIT_EXCEEDED:
        return "LIMIT_EXCEEDED";
    case JOB_NO_MEMORY:
        return "NO_MEMORY";
    }
    return "UNKNOWN";
}
