/*
 * family.c - a family of jobs: its document read, its axes' values made, its members built and
 * validated, and its table written (family.h, whose top comment is the format's reference).
 *
 * Expansion runs in three steps. The document is read whole (RFC 8259's numbers and strings,
 * json_strict.h; no repeated key; no unknown key) and the base is parsed once, which both checks
 * it (its errors are reported at "base.FIELD") and gives its normalised document, from which
 * arrays an axis path needs are copied and the seeded parts are found. Each axis's values are
 * then made as a cJSON array: a list as given, linspace and logspace by a + (b - a) i / (k - 1)
 * (in log10 for logspace, a whole decade exact, the last value exactly b), random draws from a
 * splitmix64 stream seeded with FAMILY_SEED(seed, axis index) (uniform: 53-bit mantissas; normal
 * and lognormal: Box-Muller, one normal per two uniforms, so a draw does not depend on the
 * platform's random generator); a made value is rounded to 15 significant digits, which cJSON
 * prints exactly, so the value a member runs with is the one its table row shows. The member count
 * is checked against the limit before any member is made, with the product computed in long double
 * so that it cannot overflow. Last, each member's request is the base request copied, its axis
 * values set and its seeds written, and is parsed by job_from_json; only its normalised document's
 * text and the few fields the store needs are kept, so a family of 10^4 triple pendulums costs
 * about its specs' text in memory.
 *
 * Seeds: splitmix64 (Steele, Lea and Flood 2014, "Fast splittable pseudorandom number
 * generators"), the same mixer for the axes' streams and the replicas' seeds.
 */
#include "family.h"

#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "json_read.h"
#include "json_strict.h"

#define SEED_MAX 9007199254740992.0 /* 2^53: a job's largest seed */

/* ---- seeds and draws ---- */

static uint64_t splitmix64(uint64_t *state)
{
    uint64_t z = (*state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
}

uint64_t family_seed(uint64_t seed, int replica)
{
    uint64_t state = seed ^ (0x632be59bd9b4e019ULL * (uint64_t)(replica + 1));
    return splitmix64(&state) % FAMILY_SEED_LIMIT;
}

/* x rounded to 15 significant digits: what cJSON prints of it exactly (it prints 15 digits when
 * they read back within a relative DBL_EPSILON, job_json.h), so a made value is the same in the
 * member's stored spec, in its table row and in its run */
static double printable(double x)
{
    char text[32];
    snprintf(text, sizeof text, "%.15g", x);
    return strtod(text, NULL);
}

/* a uniform draw in (0, 1): 53 random bits, never 0 (Box-Muller takes its log) */
static double uniform01(uint64_t *state)
{
    return ((double)(splitmix64(state) >> 11) + 0.5) * 0x1.0p-53;
}

static double normal01(uint64_t *state)
{
    double u1 = uniform01(state), u2 = uniform01(state);
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586476925 * u2) /* 2 pi */;
}

/* ---- errors ---- */

static int fam_fail(family_error *err, int status, const char *code, const char *field,
                    const char *fmt, ...) __attribute__((format(printf, 5, 6)));

static int fam_fail(family_error *err, int status, const char *code, const char *field,
                    const char *fmt, ...)
{
    err->status = status;
    snprintf(err->code, sizeof err->code, "%s", code);
    snprintf(err->field, sizeof err->field, "%s", field);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return -1;
}

static int no_memory(family_error *err)
{
    return fam_fail(err, 503, "NO_MEMORY", "", "out of memory");
}

/* a value as short text for the table, messages and names: numbers with the fewest of 15, 16
 * or 17 significant digits that read back exactly,
 * strings as they are, anything else as compact JSON; into buf */
static const char *value_text(const cJSON *v, char *buf, size_t len)
{
    if (cJSON_IsNumber(v)) {
        /* the shortest of %.15g..%.17g that reads back exactly */
        for (int digits = 15; digits <= 17; digits++) {
            snprintf(buf, len, "%.*g", digits, v->valuedouble);
            if (strtod(buf, NULL) == v->valuedouble) break;
        }
    } else if (cJSON_IsString(v)) {
        snprintf(buf, len, "%s", v->valuestring);
    } else {
        char *text = cJSON_PrintUnformatted(v);
        snprintf(buf, len, "%s", text ? text : "?");
        cJSON_free(text);
    }
    return buf;
}

/* ---- paths ---- */

/* One step of a path: an object key, or an array index (key NULL). */
typedef struct path_step {
    char key[FAMILY_MAX_PATH];
    long index;
    int is_index;
} path_step;

/* Splits "a.b[2].c" into steps; the count, or -1 with why set. */
static int path_split(const char *path, path_step *steps, int max, const char **why)
{
    int n = 0;
    const char *p = path;
    if (!*p) {
        *why = "is empty";
        return -1;
    }
    while (*p) {
        if (n == max) {
            *why = "has too many steps";
            return -1;
        }
        path_step *s = &steps[n];
        memset(s, 0, sizeof *s);
        if (*p == '[') {
            char *end;
            errno = 0;
            long i = strtol(p + 1, &end, 10);
            if (end == p + 1 || *end != ']' || i < 0 || errno || p[1] == '-' || p[1] == '+') {
                *why = "has an index that is not [N] with N >= 0";
                return -1;
            }
            s->index = i;
            s->is_index = 1;
            p = end + 1;
            if (*p == '.') {
                p++;
                if (!*p || *p == '.' || *p == '[') {
                    *why = "has an empty key";
                    return -1;
                }
            } else if (*p && *p != '[') {
                *why = "needs a '.' after an index";
                return -1;
            }
        } else {
            size_t k = strcspn(p, ".[");
            if (k == 0 || k >= sizeof s->key) {
                *why = k ? "has a key too long" : "has an empty key";
                return -1;
            }
            memcpy(s->key, p, k);
            s->key[k] = '\0';
            p += k;
            if (*p == '.') {
                p++;
                if (!*p || *p == '.' || *p == '[') {
                    *why = "has an empty key";
                    return -1;
                }
            }
        }
        n++;
    }
    if (steps[0].is_index) {
        *why = "must start with a key";
        return -1;
    }
    return n;
}

/* the item at steps[0..n) of doc, or NULL */
static const cJSON *path_get(const cJSON *doc, const path_step *steps, int n)
{
    const cJSON *v = doc;
    for (int i = 0; v && i < n; i++) {
        if (steps[i].is_index)
            v = cJSON_IsArray(v) && steps[i].index < cJSON_GetArraySize(v)
                    ? cJSON_GetArrayItem(v, (int)steps[i].index)
                    : NULL;
        else
            v = cJSON_IsObject(v) ? cJSON_GetObjectItemCaseSensitive(v, steps[i].key) : NULL;
    }
    return v;
}

/* Sets value (consumed) at the path in request: objects on the way are made when absent, an
 * array on the way that request lacks is copied from normalised. 0, or -1 with why. */
static int path_set(cJSON *request, const cJSON *normalised, const path_step *steps, int n,
                    cJSON *value, const char **why)
{
    cJSON *v = request;
    for (int i = 0; i < n; i++) {
        int last = i == n - 1;
        if (steps[i].is_index) {
            if (!cJSON_IsArray(v) || steps[i].index >= cJSON_GetArraySize(v)) {
                *why = "indexes past the end of an array of the job";
                goto fail;
            }
            if (last) {
                cJSON_ReplaceItemInArray(v, (int)steps[i].index, value);
                return 0;
            }
            v = cJSON_GetArrayItem(v, (int)steps[i].index);
            continue;
        }
        if (!cJSON_IsObject(v)) {
            *why = "goes through a value of the job that is not an object";
            goto fail;
        }
        if (last) {
            if (cJSON_GetObjectItemCaseSensitive(v, steps[i].key))
                cJSON_ReplaceItemInObjectCaseSensitive(v, steps[i].key, value);
            else
                cJSON_AddItemToObject(v, steps[i].key, value);
            return 0;
        }
        cJSON *next = cJSON_GetObjectItemCaseSensitive(v, steps[i].key);
        if (!next) {
            if (steps[i + 1].is_index) {
                /* the array as the job has it, to index into */
                const cJSON *from = path_get(normalised, steps, i + 1);
                if (!cJSON_IsArray(from)) {
                    *why = "goes through an array the job does not have";
                    goto fail;
                }
                next = cJSON_Duplicate(from, 1);
            } else {
                next = cJSON_CreateObject();
            }
            if (!next) {
                *why = "out of memory";
                goto fail;
            }
            cJSON_AddItemToObject(v, steps[i].key, next);
        }
        v = next;
    }
fail:
    cJSON_Delete(value);
    return -1;
}

/* ---- the document ---- */

typedef struct axis {
    char path[FAMILY_MAX_PATH];
    path_step steps[32];
    int nsteps;
    cJSON *values; /* array */
    int count;
} axis;

static int check_keys(const cJSON *obj, const char *path, const char *const *allowed,
                      family_error *err)
{
    for (const cJSON *k = obj->child; k; k = k->next) {
        int ok = 0;
        for (int i = 0; allowed[i]; i++) ok |= strcmp(k->string, allowed[i]) == 0;
        if (!ok) {
            char keys[256] = "";
            for (int i = 0; allowed[i]; i++) {
                size_t used = strlen(keys);
                snprintf(keys + used, sizeof keys - used, "%s%s", i ? ", " : "", allowed[i]);
            }
            char field[256];
            snprintf(field, sizeof field, "%s%s%s", path, *path ? "." : "", k->string);
            return fam_fail(err, 400, "UNKNOWN_FIELD", field, "unknown key (the keys are: %s)",
                            keys);
        }
    }
    return 0;
}

/* a whole number lo..hi at field; 0, or -1 */
static int whole_number(const cJSON *v, const char *field, double lo, double hi, double *out,
                        family_error *err)
{
    if (!cJSON_IsNumber(v) || v->valuedouble != floor(v->valuedouble) || v->valuedouble < lo ||
        v->valuedouble > hi) {
        char got[64];
        return fam_fail(err, 400, "INVALID_FIELD", field,
                        "must be a whole number from %.17g to %.17g (got %s)", lo, hi,
                        value_text(v, got, sizeof got));
    }
    *out = v->valuedouble;
    return 0;
}

/* a finite number at field; 0, or -1 */
static int number(const cJSON *v, const char *field, double *out, family_error *err)
{
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) {
        char got[64];
        return fam_fail(err, 400, "INVALID_FIELD", field, "must be a finite number (got %s)",
                        value_text(v, got, sizeof got));
    }
    *out = v->valuedouble;
    return 0;
}

/* linspace or logspace [a, b, k] at field into a->values */
static int make_range(axis *a, const cJSON *spec, const char *field, int logs, long max_members,
                      family_error *err)
{
    char at[440];
    double x[2], k = 0;
    if (!cJSON_IsArray(spec) || cJSON_GetArraySize(spec) != 3)
        return fam_fail(err, 400, "INVALID_FIELD", field, "must be [from, to, count]");
    for (int i = 0; i < 2; i++) {
        snprintf(at, sizeof at, "%s[%d]", field, i);
        if (number(cJSON_GetArrayItem(spec, i), at, &x[i], err)) return -1;
        if (logs && !(x[i] > 0))
            return fam_fail(err, 400, "INVALID_FIELD", at,
                            "must be > 0 on a logarithmic axis (got %.17g)", x[i]);
    }
    snprintf(at, sizeof at, "%s[2]", field);
    if (whole_number(cJSON_GetArrayItem(spec, 2), at, 1, (double)max_members, &k, err)) return -1;
    a->count = (int)k;
    a->values = cJSON_CreateArray();
    double lo = logs ? log10(x[0]) : x[0], hi = logs ? log10(x[1]) : x[1];
    for (int i = 0; a->values && i < a->count; i++) {
        double t = a->count > 1 ? (double)i / (a->count - 1) : 0;
        double y = i == a->count - 1 && a->count > 1 ? hi : lo + (hi - lo) * t;
        /* a decade lands on its power of ten exactly (log10 of 1e-4 need not be -4) */
        if (logs && fabs(y - nearbyint(y)) < 1e-9) y = nearbyint(y);
        double v = logs ? pow(10.0, y) : y;
        if (i == 0) v = x[0];
        if (i == a->count - 1 && a->count > 1) v = x[1];
        if (!cJSON_AddItemToArray(a->values, cJSON_CreateNumber(printable(v))))
            return no_memory(err);
    }
    return a->values ? 0 : no_memory(err);
}

/* "random": {dist, ...} with "count" k, drawn from the axis's stream */
static int make_random(axis *a, const cJSON *ax, const char *field, uint64_t seed, int axis_index,
                       long max_members, family_error *err)
{
    static const char *const dists[] = {"uniform", "normal", "lognormal"};
    static const char *const params[][3] = {
        {"dist", "low", "high"}, {"dist", "mean", "std"}, {"dist", "mu", "sigma"}};
    char at[400];
    const cJSON *spec = cJSON_GetObjectItemCaseSensitive(ax, "random");
    const cJSON *count = cJSON_GetObjectItemCaseSensitive(ax, "count");
    snprintf(at, sizeof at, "%s.random", field);
    if (!cJSON_IsObject(spec))
        return fam_fail(err, 400, "INVALID_FIELD", at, "must be an object {\"dist\", ...}");
    const cJSON *dist = cJSON_GetObjectItemCaseSensitive(spec, "dist");
    int d = -1;
    for (int i = 0; i < 3 && cJSON_IsString(dist); i++)
        if (strcmp(dist->valuestring, dists[i]) == 0) d = i;
    if (d < 0) {
        snprintf(at, sizeof at, "%s.random.dist", field);
        return fam_fail(err, 400, dist ? "INVALID_FIELD" : "MISSING_FIELD", at,
                        "must be \"uniform\", \"normal\" or \"lognormal\"");
    }
    const char *allowed[] = {params[d][0], params[d][1], params[d][2], NULL};
    snprintf(at, sizeof at, "%s.random", field);
    if (check_keys(spec, at, allowed, err)) return -1;
    double p[2];
    for (int i = 0; i < 2; i++) {
        snprintf(at, sizeof at, "%s.random.%s", field, params[d][i + 1]);
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(spec, params[d][i + 1]);
        if (!v) return fam_fail(err, 400, "MISSING_FIELD", at, "is required");
        if (number(v, at, &p[i], err)) return -1;
    }
    if (d == 0 && !(p[1] > p[0]))
        return fam_fail(err, 400, "INVALID_FIELD", at, "must be more than low (%.17g; got %.17g)",
                        p[0], p[1]);
    if (d > 0 && !(p[1] > 0))
        return fam_fail(err, 400, "INVALID_FIELD", at, "must be > 0 (got %.17g)", p[1]);
    snprintf(at, sizeof at, "%s.count", field);
    double k = 0;
    if (!count) return fam_fail(err, 400, "MISSING_FIELD", at, "is required with \"random\"");
    if (whole_number(count, at, 1, (double)max_members, &k, err)) return -1;
    a->count = (int)k;
    a->values = cJSON_CreateArray();
    uint64_t state = family_seed(seed, -2 - axis_index);
    for (int i = 0; a->values && i < a->count; i++) {
        double v = d == 0   ? p[0] + (p[1] - p[0]) * uniform01(&state)
                   : d == 1 ? p[0] + p[1] * normal01(&state)
                            : exp(p[0] + p[1] * normal01(&state));
        if (!cJSON_AddItemToArray(a->values, cJSON_CreateNumber(printable(v))))
            return no_memory(err);
    }
    return a->values ? 0 : no_memory(err);
}

/* axes[i] at field: its path and values */
static int read_axis(axis *a, const cJSON *ax, const char *field, uint64_t seed, int index,
                     long max_members, family_error *err)
{
    static const char *const keys[] = {"path",   "values", "linspace", "logspace",
                                       "random", "count",  NULL};
    char at[400];
    if (!cJSON_IsObject(ax))
        return fam_fail(err, 400, "INVALID_FIELD", field,
                        "must be an object {\"path\", and \"values\", \"linspace\", "
                        "\"logspace\" or \"random\"}");
    if (check_keys(ax, field, keys, err)) return -1;
    const cJSON *path = cJSON_GetObjectItemCaseSensitive(ax, "path");
    snprintf(at, sizeof at, "%s.path", field);
    if (!path) return fam_fail(err, 400, "MISSING_FIELD", at, "is required");
    if (!cJSON_IsString(path) || strlen(path->valuestring) >= sizeof a->path)
        return fam_fail(err, 400, "INVALID_FIELD", at, "must be a string of at most %d bytes",
                        FAMILY_MAX_PATH - 1);
    snprintf(a->path, sizeof a->path, "%s", path->valuestring);
    const char *why = "";
    a->nsteps = path_split(a->path, a->steps, 32, &why);
    if (a->nsteps < 0)
        return fam_fail(err, 400, "INVALID_FIELD", at, "the path \"%s\" %s", a->path, why);
    if (strcmp(a->path, "preset") == 0 || strcmp(a->path, "name") == 0)
        return fam_fail(err, 400, "INVALID_FIELD", at, "an axis cannot set \"%s\"", a->path);

    const char *kinds[] = {"values", "linspace", "logspace", "random"};
    int kind = -1, given = 0;
    for (int i = 0; i < 4; i++)
        if (cJSON_GetObjectItemCaseSensitive(ax, kinds[i])) kind = i, given++;
    if (given != 1)
        return fam_fail(err, 400, given ? "INVALID_FIELD" : "MISSING_FIELD", field,
                        "an axis needs exactly one of \"values\", \"linspace\", \"logspace\" and "
                        "\"random\" (got %d)",
                        given);
    if (kind != 3 && cJSON_GetObjectItemCaseSensitive(ax, "count")) {
        snprintf(at, sizeof at, "%s.count", field);
        return fam_fail(err, 400, "UNKNOWN_FIELD", at, "\"count\" goes with \"random\" only");
    }
    snprintf(at, sizeof at, "%s.%s", field, kinds[kind]);
    const cJSON *spec = cJSON_GetObjectItemCaseSensitive(ax, kinds[kind]);
    if (kind == 0) {
        int k = cJSON_IsArray(spec) ? cJSON_GetArraySize(spec) : 0;
        if (k < 1 || k > max_members)
            return fam_fail(err, 400, k > max_members ? "LIMIT_EXCEEDED" : "INVALID_FIELD", at,
                            "must be an array of 1 to %ld values (got %s%d)", max_members,
                            cJSON_IsArray(spec) ? "" : "not an array, ", k);
        a->count = k;
        a->values = cJSON_Duplicate(spec, 1);
        return a->values ? 0 : no_memory(err);
    }
    if (kind == 3) return make_random(a, ax, field, seed, index, max_members, err);
    return make_range(a, spec, at, kind == 2, max_members, err);
}

/* ---- members ---- */

/* cuts the UTF-8 text s to at most max bytes, never inside a letter */
static void cut_utf8(char *s, size_t max)
{
    size_t n = strlen(s);
    if (n <= max) return;
    n = max;
    /* the last letter's lead byte, and the length it announces */
    size_t lead = n;
    while (lead > 0 && ((unsigned char)s[lead - 1] & 0xC0) == 0x80 && n - lead < 3) lead--;
    if (lead > 0 && ((unsigned char)s[lead - 1] & 0xC0) == 0xC0) {
        unsigned char c = (unsigned char)s[lead - 1];
        size_t want = c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : 2;
        if (n - (lead - 1) < want) n = lead - 1;
    }
    s[n] = '\0';
}

/* sets the request's "name"; 0 when out of memory */
static int set_name(cJSON *req, const char *name)
{
    cJSON *s = cJSON_CreateString(name);
    if (!s) return 0;
    if (cJSON_GetObjectItemCaseSensitive(req, "name"))
        return cJSON_ReplaceItemInObjectCaseSensitive(req, "name", s);
    return cJSON_AddItemToObject(req, "name", s);
}

/* Builds, parses and keeps member m: the base request with the axes' values of combination
 * (pos[]) and the replica's seeds. 0, or -1. */
static int make_member(family *f, long m, const cJSON *base, const cJSON *normalised,
                       const char *base_name, axis *axes, int naxes, const int *pos, int replica,
                       int seeded, uint64_t seed, family_error *err)
{
    family_member *fm = &f->members[m];
    char name[JOB_MAX_NAME * 2 + 8], text[128];
    const char *why = "";
    int rc = -1;
    job *j = NULL;
    cJSON *req = cJSON_Duplicate(base, 1), *values = cJSON_CreateArray();
    if (!req || !values) {
        no_memory(err);
        goto done;
    }
    size_t used = (size_t)snprintf(name, sizeof name, "%s", base_name);
    for (int a = 0; a < naxes; a++) {
        const cJSON *v = cJSON_GetArrayItem(axes[a].values, pos[a]);
        cJSON *copy = cJSON_Duplicate(v, 1), *copy2 = cJSON_Duplicate(v, 1);
        if (!copy || !copy2 || !cJSON_AddItemToArray(values, copy2)) {
            cJSON_Delete(copy);
            cJSON_Delete(copy2);
            no_memory(err);
            goto done;
        }
        if (used < sizeof name)
            used += (size_t)snprintf(name + used, sizeof name - used, "%s%s=%s", a ? ", " : " [",
                                     axes[a].path, value_text(v, text, sizeof text));
        if (path_set(req, normalised, axes[a].steps, axes[a].nsteps, copy, &why) != 0) {
            char field[32];
            snprintf(field, sizeof field, "axes[%d]", a);
            fam_fail(err, 400, "INVALID_FIELD", field, "axis %s = %s (member %ld): the path %s",
                     axes[a].path, text, m, why);
            goto done;
        }
    }
    if (naxes && used < sizeof name) used += (size_t)snprintf(name + used, sizeof name - used, "]");
    if (f->replicas > 1 && used < sizeof name)
        snprintf(name + used, sizeof name - used, " #%d", replica);
    cut_utf8(name, JOB_MAX_NAME);
    if (!set_name(req, name)) {
        no_memory(err);
        goto done;
    }

    /* the replica's seeds, where the job has seeded parts */
    if (seeded) {
        static const path_step noise[] = {{"controller", 0, 0}, {"seed", 0, 0}};
        static const path_step model[] = {
            {"controller", 0, 0}, {"model", 0, 0}, {"random", 0, 0}, {"seed", 0, 0}};
        double s = (double)family_seed(seed, replica);
        const cJSON *type =
            path_get(normalised, (path_step[]){{"controller", 0, 0}, {"type", 0, 0}}, 2);
        if (cJSON_IsString(type) && strcmp(type->valuestring, "none") != 0 &&
            path_set(req, normalised, noise, 2, cJSON_CreateNumber(s), &why) != 0)
            goto seed_failed;
        if (path_get(normalised, model, 3) &&
            path_set(req, normalised, model, 4, cJSON_CreateNumber(s), &why) != 0)
            goto seed_failed;
    }

    job_error jerr = {0};
    if (job_from_json(req, &j, &jerr) != 0) {
        if (jerr.code == JOB_NO_MEMORY) {
            no_memory(err);
            goto done;
        }
        char axes_text[1024] = "";
        size_t at = 0;
        for (int a = 0; a < naxes && at < sizeof axes_text; a++)
            at += (size_t)snprintf(
                axes_text + at, sizeof axes_text - at, "%saxis %s = %s", a ? ", " : "",
                axes[a].path,
                value_text(cJSON_GetArrayItem(axes[a].values, pos[a]), text, sizeof text));
        char who[64];
        if (f->replicas > 1)
            snprintf(who, sizeof who, "member %ld, replica %d", m, replica);
        else
            snprintf(who, sizeof who, "member %ld", m);
        fam_fail(err, 400, job_error_code_name(jerr.code),
                 naxes == 1 ? "axes[0]"
                 : naxes    ? "axes"
                            : "base",
                 "%s%s(%s): %s%s%s", axes_text, naxes ? " " : "", who, jerr.field,
                 jerr.field[0] ? ": " : "", jerr.message);
        goto done;
    }
    fm->index = m;
    fm->replica = replica;
    fm->nbodies = j->spec.chain.nbodies;
    fm->nv = j->nv;
    fm->threads = j->spec.threads;
    fm->values = cJSON_PrintUnformatted(values);
    fm->name = strdup(j->name);
    fm->preset = j->preset ? strdup(j->preset) : NULL;
    fm->controller = strdup(ctc_ctrl_type_name(j->spec.controller));
    fm->spec = cJSON_PrintUnformatted(j->normalised);
    if (!fm->values || !fm->name || (j->preset && !fm->preset) || !fm->controller || !fm->spec) {
        no_memory(err);
        goto done;
    }
    rc = 0;
    goto done;
seed_failed:
    fam_fail(err, 400, "INVALID_FIELD", "seed", "member %ld: setting its seed: the path %s", m,
             why);
done:
    job_free(j);
    cJSON_Delete(req);
    cJSON_Delete(values);
    return rc;
}

/* ---- the expansion ---- */

void family_free(family *f)
{
    if (!f) return;
    for (long i = 0; f->members && i < f->nmembers; i++) {
        family_member *m = &f->members[i];
        cJSON_free(m->values);
        free(m->name);
        free(m->preset);
        free(m->controller);
        cJSON_free(m->spec);
    }
    free(f->members);
    free(f->name);
    cJSON_free(f->doc);
    cJSON_free(f->paths);
    free(f);
}

/* parses the base request once: its errors at "base.FIELD", its normalised document and name */
static int parse_base(const cJSON *base, cJSON **normalised, char **name, family_error *err)
{
    job *j = NULL;
    job_error jerr = {0};
    if (!cJSON_IsObject(base))
        return fam_fail(err, 400, "INVALID_FIELD", "base",
                        "must be a job object or {\"preset\": NAME, ...}");
    if (job_from_json(base, &j, &jerr) != 0) {
        if (jerr.code == JOB_NO_MEMORY) return no_memory(err);
        char field[sizeof jerr.field + 8];
        snprintf(field, sizeof field, "base%s%s", jerr.field[0] ? "." : "", jerr.field);
        return fam_fail(err, 400, job_error_code_name(jerr.code), field, "%s", jerr.message);
    }
    *normalised = cJSON_Duplicate(j->normalised, 1);
    *name = strdup(j->name);
    job_free(j);
    if (!*normalised || !*name) {
        cJSON_Delete(*normalised);
        free(*name);
        *normalised = NULL;
        *name = NULL;
        return no_memory(err);
    }
    return 0;
}

int family_expand(const char *text, size_t len, long max_members, family **out, family_error *err)
{
    static const char *const keys[] = {"name", "base", "axes", "combine", "replicas", "seed", NULL};
    int rc = -1, naxes = 0;
    axis axes[FAMILY_MAX_AXES];
    family *f = NULL;
    cJSON *doc = NULL, *normalised = NULL, *paths = NULL;
    char *base_name = NULL;
    memset(err, 0, sizeof *err);
    memset(axes, 0, sizeof axes);
    *out = NULL;
    if (max_members < 1) max_members = 1;

    /* the document: JSON by RFC 8259, one object, no repeated or unknown key */
    size_t pos = 0;
    const char *why = NULL;
    if (json_strict_check(text, len, &pos, &why) != 0) {
        fam_fail(err, 400, "INVALID_JSON", "", "invalid JSON at byte %zu: %s", pos, why);
        goto done;
    }
    const char *end = NULL;
    doc = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    if (!doc) {
        fam_fail(err, 400, "INVALID_JSON", "", "invalid JSON at byte %ld",
                 end ? (long)(end - text) : 0L);
        goto done;
    }
    if (!cJSON_IsObject(doc)) {
        fam_fail(err, 400, "INVALID_JSON", "", "a family is a JSON object");
        goto done;
    }
    job_error jerr = {0};
    if (json_check_repeated_keys(&jerr, doc, "") != 0) {
        fam_fail(err, 400, job_error_code_name(jerr.code), jerr.field, "%s", jerr.message);
        goto done;
    }
    if (check_keys(doc, "", keys, err)) goto done;

    f = calloc(1, sizeof *f);
    if (!f) {
        no_memory(err);
        goto done;
    }
    double replicas = 1, seed = 0;
    const cJSON *v;
    int seeded = 0;
    if ((v = cJSON_GetObjectItemCaseSensitive(doc, "replicas")) &&
        whole_number(v, "replicas", 1, (double)max_members, &replicas, err))
        goto done;
    if ((v = cJSON_GetObjectItemCaseSensitive(doc, "seed"))) {
        if (whole_number(v, "seed", 0, SEED_MAX, &seed, err)) goto done;
        seeded = 1;
    }
    f->replicas = (int)replicas;
    seeded |= f->replicas > 1;
    int zip = 0;
    if ((v = cJSON_GetObjectItemCaseSensitive(doc, "combine"))) {
        if (!cJSON_IsString(v) ||
            (strcmp(v->valuestring, "product") != 0 && strcmp(v->valuestring, "zip") != 0)) {
            fam_fail(err, 400, "INVALID_FIELD", "combine", "must be \"product\" or \"zip\"");
            goto done;
        }
        zip = strcmp(v->valuestring, "zip") == 0;
    }
    const cJSON *name = cJSON_GetObjectItemCaseSensitive(doc, "name");
    if (name && (!cJSON_IsString(name) || !name->valuestring[0] ||
                 strlen(name->valuestring) > JOB_MAX_NAME)) {
        fam_fail(err, 400, "INVALID_FIELD", "name", "must be a string of 1 to %d bytes",
                 JOB_MAX_NAME);
        goto done;
    }
    const cJSON *base = cJSON_GetObjectItemCaseSensitive(doc, "base");
    if (!base) {
        fam_fail(err, 400, "MISSING_FIELD", "base",
                 "is required: a job, or {\"preset\": NAME, ...} with overrides");
        goto done;
    }
    if (parse_base(base, &normalised, &base_name, err)) goto done;

    /* the axes and their values */
    const cJSON *list = cJSON_GetObjectItemCaseSensitive(doc, "axes");
    if (list && (!cJSON_IsArray(list) || cJSON_GetArraySize(list) > FAMILY_MAX_AXES)) {
        fam_fail(err, 400, "INVALID_FIELD", "axes", "must be an array of at most %d axes",
                 FAMILY_MAX_AXES);
        goto done;
    }
    paths = cJSON_CreateArray();
    if (!paths) {
        no_memory(err);
        goto done;
    }
    long double count = 1;
    for (const cJSON *ax = list ? list->child : NULL; ax; ax = ax->next, naxes++) {
        char field[32];
        snprintf(field, sizeof field, "axes[%d]", naxes);
        if (read_axis(&axes[naxes], ax, field, (uint64_t)seed, naxes, max_members, err)) {
            naxes++;
            goto done;
        }
        for (int b = 0; b < naxes; b++)
            if (strcmp(axes[b].path, axes[naxes].path) == 0) {
                snprintf(field, sizeof field, "axes[%d].path", naxes);
                fam_fail(err, 400, "INVALID_FIELD", field, "axes[%d] sets \"%s\" already", b,
                         axes[b].path);
                naxes++;
                goto done;
            }
        if (zip && naxes > 0 && axes[naxes].count != axes[0].count) {
            fam_fail(err, 400, "INVALID_FIELD", field,
                     "zipped axes must have the same number of values (axes[0] has %d, this one "
                     "%d)",
                     axes[0].count, axes[naxes].count);
            naxes++;
            goto done;
        }
        if (!cJSON_AddItemToArray(paths, cJSON_CreateString(axes[naxes].path))) {
            no_memory(err);
            naxes++;
            goto done;
        }
        if (!zip || naxes == 0) count *= axes[naxes].count;
    }
    count *= f->replicas;
    if (count > (long double)max_members) {
        fam_fail(err, 413, "FAMILY_TOO_LARGE", "axes",
                 "the family has %.0Lf members, more than this server takes (--max-family %ld)",
                 count, max_members);
        goto done;
    }

    /* the members, in product (or zip) order, replicas innermost */
    f->naxes = naxes;
    f->nmembers = (long)count;
    f->members = calloc((size_t)f->nmembers, sizeof *f->members);
    f->name = strdup(name ? name->valuestring : base_name);
    f->doc = cJSON_PrintUnformatted(doc);
    f->paths = cJSON_PrintUnformatted(paths);
    if (!f->members || !f->name || !f->doc || !f->paths) {
        no_memory(err);
        goto done;
    }
    int pos_of[FAMILY_MAX_AXES] = {0};
    long combinations = f->nmembers / f->replicas;
    for (long c = 0; c < combinations; c++) {
        long rest = c;
        for (int a = naxes - 1; a >= 0; a--) {
            if (zip) {
                pos_of[a] = (int)c;
            } else {
                pos_of[a] = (int)(rest % axes[a].count);
                rest /= axes[a].count;
            }
        }
        for (int r = 0; r < f->replicas; r++)
            if (make_member(f, c * f->replicas + r, base, normalised, base_name, axes, naxes,
                            pos_of, r, seeded, (uint64_t)seed, err))
                goto done;
    }
    *out = f;
    f = NULL;
    rc = 0;
done:
    for (int a = 0; a < naxes && a < FAMILY_MAX_AXES; a++) cJSON_Delete(axes[a].values);
    family_free(f);
    cJSON_Delete(doc);
    cJSON_Delete(normalised);
    cJSON_Delete(paths);
    free(base_name);
    return rc;
}

/* ---- the table ---- */

const char *const family_metric_names[FAMILY_NMETRICS] = {
    "e_final", "e_rms", "e_max", "tau_peak", "energy_drift", "us_per_eval", "steps", "wall_s",
};

/* the largest |x| of a metrics array, NaN when absent or with a null */
static double largest(const cJSON *a)
{
    double m = NAN;
    if (!cJSON_IsArray(a)) return NAN;
    for (const cJSON *x = a->child; x; x = x->next) {
        if (!cJSON_IsNumber(x)) return NAN;
        double v = fabs(x->valuedouble);
        if (!(m >= v)) m = v;
    }
    return m;
}

static double scalar(const cJSON *x)
{
    return cJSON_IsNumber(x) ? x->valuedouble : NAN;
}

void family_row_metrics(const cJSON *metrics, double out[FAMILY_NMETRICS])
{
    for (int i = 0; i < FAMILY_NMETRICS; i++) {
        const cJSON *x =
            metrics ? cJSON_GetObjectItemCaseSensitive(metrics, family_metric_names[i]) : NULL;
        out[i] = i < 4 ? largest(x) : scalar(x);
    }
}

/* a CSV field: quoted when it holds a comma, a quote or a line break */
static int csv_text(FILE *f, const char *s)
{
    if (!strpbrk(s, ",\"\r\n")) return fputs(s, f) < 0 ? -1 : 0;
    if (fputc('"', f) == EOF) return -1;
    for (; *s; s++)
        if ((*s == '"' && fputc('"', f) == EOF) || fputc(*s, f) == EOF) return -1;
    return fputc('"', f) == EOF ? -1 : 0;
}

static int csv_number(FILE *f, double x)
{
    char text[64];
    if (!isfinite(x)) return 0; /* absent: an empty field */
    cJSON n = {.type = cJSON_Number, .valuedouble = x};
    return fputs(value_text(&n, text, sizeof text), f) < 0 ? -1 : 0;
}

int family_write_csv(FILE *f, const cJSON *paths, const family_row *rows, long n)
{
    char text[512];
    if (fputs("member,replica", f) < 0) return -1;
    for (const cJSON *p = paths ? paths->child : NULL; p; p = p->next)
        if (fputc(',', f) == EOF || csv_text(f, cJSON_IsString(p) ? p->valuestring : "?"))
            return -1;
    if (fputs(",status", f) < 0) return -1;
    for (int i = 0; i < FAMILY_NMETRICS; i++)
        if (fprintf(f, ",%s", family_metric_names[i]) < 0) return -1;
    if (fputc('\n', f) == EOF) return -1;
    for (long r = 0; r < n; r++) {
        const family_row *row = &rows[r];
        double m[FAMILY_NMETRICS];
        if (fprintf(f, "%ld,%d", row->index, row->replica) < 0) return -1;
        for (const cJSON *v = row->values ? row->values->child : NULL; v; v = v->next) {
            if (fputc(',', f) == EOF) return -1;
            if (cJSON_IsNumber(v) ? csv_number(f, v->valuedouble)
                                  : csv_text(f, value_text(v, text, sizeof text)))
                return -1;
        }
        if (fputc(',', f) == EOF || csv_text(f, row->status ? row->status : "")) return -1;
        family_row_metrics(row->metrics, m);
        for (int i = 0; i < FAMILY_NMETRICS; i++)
            if (fputc(',', f) == EOF || csv_number(f, m[i])) return -1;
        if (fputc('\n', f) == EOF) return -1;
    }
    return fflush(f) == 0 ? 0 : -1;
}

static cJSON *number_or_null(double x)
{
    return isfinite(x) ? cJSON_CreateNumber(x) : cJSON_CreateNull();
}

cJSON *family_table_json(const cJSON *paths, const family_row *rows, long n)
{
    cJSON *o = cJSON_CreateObject();
    cJSON *columns = cJSON_AddArrayToObject(o, "columns");
    cJSON *list = cJSON_AddArrayToObject(o, "rows");
    if (!columns || !list) goto fail;
    cJSON_AddItemToArray(columns, cJSON_CreateString("member"));
    cJSON_AddItemToArray(columns, cJSON_CreateString("replica"));
    for (const cJSON *p = paths ? paths->child : NULL; p; p = p->next)
        cJSON_AddItemToArray(columns, cJSON_Duplicate(p, 1));
    cJSON_AddItemToArray(columns, cJSON_CreateString("status"));
    for (int i = 0; i < FAMILY_NMETRICS; i++)
        cJSON_AddItemToArray(columns, cJSON_CreateString(family_metric_names[i]));
    for (long r = 0; r < n; r++) {
        const family_row *row = &rows[r];
        double m[FAMILY_NMETRICS];
        cJSON *e = cJSON_CreateObject();
        if (!e || !cJSON_AddItemToArray(list, e)) {
            cJSON_Delete(e);
            goto fail;
        }
        cJSON_AddNumberToObject(e, "member", (double)row->index);
        cJSON_AddNumberToObject(e, "replica", row->replica);
        cJSON_AddItemToObject(
            e, "job", row->job > 0 ? cJSON_CreateNumber((double)row->job) : cJSON_CreateNull());
        cJSON_AddItemToObject(e, "values",
                              row->values ? cJSON_Duplicate(row->values, 1) : cJSON_CreateArray());
        cJSON_AddStringToObject(e, "status", row->status ? row->status : "");
        cJSON_AddItemToObject(e, "message",
                              row->message && row->message[0] ? cJSON_CreateString(row->message)
                                                              : cJSON_CreateNull());
        family_row_metrics(row->metrics, m);
        for (int i = 0; i < FAMILY_NMETRICS; i++)
            cJSON_AddItemToObject(e, family_metric_names[i], number_or_null(m[i]));
        /* cJSON's adders fail quietly: the last one tells */
        if (!cJSON_GetObjectItemCaseSensitive(e, family_metric_names[FAMILY_NMETRICS - 1]))
            goto fail;
    }
    if (cJSON_GetArraySize(columns) != 3 + FAMILY_NMETRICS + cJSON_GetArraySize((cJSON *)paths))
        goto fail;
    return o;
fail:
    cJSON_Delete(o);
    return NULL;
}
