/*
 * test_job_format.c - the job format's tables (job_json.h: job_format_object_tables and
 * job_format_defaults) against the two other descriptions of the format: the JSON Schema users
 * read (api/job.schema.json) and the parser's own behaviour.
 *
 * Against the schema: every object the parser reads is found in the schema at the same JSON path
 * (from $defs/job, following $ref, oneOf alternatives and array items, and choosing an
 * alternative by the const or enum of its "type" or "method"); the keys the parser accepts there
 * are exactly the schema's properties (less those an if/then/else forbids for the type), and the
 * schema has additionalProperties false there, as the parser rejects unknown keys; every default
 * of the parser is the schema's "default" there, and every schema default at those objects is one
 * of the parser's. Against the parser: for each default row, a valid job (a preset's normalised
 * document, with the row's object replaced by one of its type where needed) with the key removed
 * parses to a normalised document holding the row's default. The page's defaults
 * (web/jobform.js) are checked against the parser and the schema by tests/api/format.test.mjs.
 *
 * The tests read api/job.schema.json from the working directory: run them from the repository
 * root (make check does).
 */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"

#define SCHEMA_PATH "api/job.schema.json"
#define MAX_NODES 64

static cJSON *load_schema(void)
{
    FILE *f = fopen(SCHEMA_PATH, "rb");
    cr_assert_not_null(f, "cannot open %s (run from the repository root)", SCHEMA_PATH);
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *text = malloc((size_t)n + 1);
    cr_assert_eq(fread(text, 1, (size_t)n, f), (size_t)n);
    text[n] = '\0';
    fclose(f);
    cJSON *schema = cJSON_Parse(text);
    free(text);
    cr_assert_not_null(schema, "%s is not valid JSON", SCHEMA_PATH);
    return schema;
}

/* the node a local "$ref" ("#/$defs/x/properties/y") points to */
static const cJSON *resolve_ref(const cJSON *schema, const char *ref)
{
    cr_assert(strncmp(ref, "#/", 2) == 0, "only local $refs are expected (got %s)", ref);
    char buf[256];
    snprintf(buf, sizeof buf, "%s", ref + 2);
    const cJSON *node = schema;
    char *save = NULL;
    for (char *tok = strtok_r(buf, "/", &save); tok != NULL; tok = strtok_r(NULL, "/", &save)) {
        node = cJSON_GetObjectItemCaseSensitive(node, tok);
        cr_assert_not_null(node, "$ref %s does not resolve", ref);
    }
    return node;
}

/* a set of schema nodes (no repeats) */
typedef struct nodes {
    const cJSON *at[MAX_NODES];
    int n;
} nodes;

static void add_node(nodes *s, const cJSON *v)
{
    for (int i = 0; i < s->n; i++) {
        if (s->at[i] == v) return;
    }
    cr_assert_lt(s->n, MAX_NODES);
    s->at[s->n++] = v;
}

/* The alternatives node stands for: itself when it has properties or items, else what its $ref
 * or the entries of its oneOf/anyOf stand for. (An object with properties and a $ref, as pd's
 * "$ref": gain_pair, keeps its own properties: the $ref only adds constraints.) */
static void expand(const cJSON *schema, const cJSON *node, nodes *out)
{
    if (cJSON_GetObjectItemCaseSensitive(node, "properties") != NULL ||
        cJSON_GetObjectItemCaseSensitive(node, "items") != NULL) {
        add_node(out, node);
        return;
    }
    const cJSON *ref = cJSON_GetObjectItemCaseSensitive(node, "$ref");
    if (cJSON_IsString(ref)) {
        expand(schema, resolve_ref(schema, ref->valuestring), out);
        return;
    }
    static const char *const lists[] = {"oneOf", "anyOf"};
    for (int l = 0; l < 2; l++) {
        const cJSON *alt = cJSON_GetObjectItemCaseSensitive(node, lists[l]);
        for (const cJSON *a = alt != NULL ? alt->child : NULL; a != NULL; a = a->next) {
            expand(schema, a, out);
        }
    }
}

/* -1: object o names no type (by a const or enum of "type" or "method"); else whether type is
 * among those it names */
static int names_type(const cJSON *o, const char *type)
{
    const cJSON *props = cJSON_GetObjectItemCaseSensitive(o, "properties");
    static const char *const keys[] = {"type", "method"};
    for (int k = 0; k < 2; k++) {
        const cJSON *t = cJSON_GetObjectItemCaseSensitive(props, keys[k]);
        if (t == NULL) continue;
        const cJSON *c = cJSON_GetObjectItemCaseSensitive(t, "const");
        if (cJSON_IsString(c)) return strcmp(c->valuestring, type) == 0;
        const cJSON *e = cJSON_GetObjectItemCaseSensitive(t, "enum");
        if (!cJSON_IsArray(e)) continue;
        for (const cJSON *x = e->child; x != NULL; x = x->next) {
            if (cJSON_IsString(x) && strcmp(x->valuestring, type) == 0) return 1;
        }
        return 0;
    }
    return -1;
}

/* drops from s the objects that name another type than type (NULL: keeps all) */
static void keep_type(nodes *s, const char *type)
{
    if (type == NULL) return;
    int kept = 0;
    for (int i = 0; i < s->n; i++) {
        if (names_type(s->at[i], type) != 0) s->at[kept++] = s->at[i];
    }
    s->n = kept;
}

/* The schema's objects at a table path ("scene.bodies[].joint"), from $defs/job; type (or NULL)
 * picks the alternatives of that type on the way. At the end, an array's items stand for it
 * (the array form of a per-coordinate object). */
static nodes objects_at(const cJSON *schema, const char *path, const char *type)
{
    nodes cur = {.n = 0};
    expand(schema, resolve_ref(schema, "#/$defs/job"), &cur);
    char buf[256];
    char *save = NULL;
    snprintf(buf, sizeof buf, "%s", path);
    for (char *tok = buf[0] ? strtok_r(buf, ".", &save) : NULL; tok != NULL;
         tok = strtok_r(NULL, ".", &save)) {
        size_t len = strlen(tok);
        int items = len > 2 && strcmp(tok + len - 2, "[]") == 0;
        if (items) tok[len - 2] = '\0';
        keep_type(&cur, type);
        nodes next = {.n = 0};
        for (int i = 0; i < cur.n; i++) {
            const cJSON *props = cJSON_GetObjectItemCaseSensitive(cur.at[i], "properties");
            const cJSON *v = cJSON_GetObjectItemCaseSensitive(props, tok);
            if (v != NULL) expand(schema, v, &next);
        }
        if (items) {
            nodes inner = {.n = 0};
            for (int i = 0; i < next.n; i++) {
                const cJSON *it = cJSON_GetObjectItemCaseSensitive(next.at[i], "items");
                if (it != NULL) expand(schema, it, &inner);
            }
            next = inner;
        }
        cur = next;
    }
    nodes out = {.n = 0};
    for (int i = 0; i < cur.n; i++) {
        const cJSON *it = cJSON_GetObjectItemCaseSensitive(cur.at[i], "items");
        if (cJSON_GetObjectItemCaseSensitive(cur.at[i], "properties") != NULL) {
            add_node(&out, cur.at[i]);
        } else if (it != NULL) {
            nodes inner = {.n = 0};
            expand(schema, it, &inner);
            for (int k = 0; k < inner.n; k++) {
                if (cJSON_GetObjectItemCaseSensitive(inner.at[k], "properties") != NULL)
                    add_node(&out, inner.at[k]);
            }
        }
    }
    keep_type(&out, type);
    return out;
}

/* whether object o's if/then/else forbids key for type ("else": {"not": {"required": [key]}}) */
static int forbidden(const cJSON *o, const char *type, const char *key)
{
    const cJSON *cond = cJSON_GetObjectItemCaseSensitive(o, "if");
    if (cond == NULL || type == NULL) return 0;
    int match = names_type(cond, type);
    const cJSON *branch = cJSON_GetObjectItemCaseSensitive(o, match == 1 ? "then" : "else");
    const cJSON *not = cJSON_GetObjectItemCaseSensitive(branch, "not");
    const cJSON *req = cJSON_GetObjectItemCaseSensitive(not, "required");
    for (const cJSON *r = req != NULL ? req->child : NULL; r != NULL; r = r->next) {
        if (cJSON_IsString(r) && strcmp(r->valuestring, key) == 0) return 1;
    }
    return 0;
}

static int in_keys(const char *const *keys, const char *key)
{
    for (; *keys != NULL; keys++) {
        if (strcmp(*keys, key) == 0) return 1;
    }
    return 0;
}

/* "path (type)" for messages */
static const char *where(char buf[128], const char *path, const char *type)
{
    snprintf(buf, 128, "\"%s\"%s%s%s", path, type ? " (" : "", type ? type : "", type ? ")" : "");
    return buf;
}

Test(job_format, parser_keys_equal_schema_properties_at_every_object)
{
    cJSON *schema = load_schema();
    int rows = 0;
    for (const job_format_object *const *t = job_format_object_tables(); *t != NULL; t++) {
        for (const job_format_object *o = *t; o->path != NULL; o++, rows++) {
            char w[128];
            where(w, o->path, o->type);
            nodes found = objects_at(schema, o->path, o->type);
            cr_expect_gt(found.n, 0, "%s: no object there in %s", w, SCHEMA_PATH);
            int typed = o->type != NULL && o->type_key != NULL;
            cr_expect(!typed || found.n == 1, "%s: %d schema alternatives of that type", w,
                      found.n);
            for (int i = 0; i < found.n; i++) {
                const cJSON *s = found.at[i];
                const cJSON *ap = cJSON_GetObjectItemCaseSensitive(s, "additionalProperties");
                cr_expect(cJSON_IsFalse(ap),
                          "%s: the parser rejects unknown keys, the schema must say "
                          "\"additionalProperties\": false",
                          w);
                const cJSON *props = cJSON_GetObjectItemCaseSensitive(s, "properties");
                for (const cJSON *k = props->child; k != NULL; k = k->next) {
                    if (forbidden(s, o->type, k->string)) continue;
                    cr_expect(in_keys(o->keys, k->string),
                              "%s: the schema has \"%s\", the parser does not accept it", w,
                              k->string);
                }
            }
            for (const char *const *k = o->keys; *k != NULL; k++) {
                int in_schema = 0;
                for (int i = 0; i < found.n; i++) {
                    const cJSON *props =
                        cJSON_GetObjectItemCaseSensitive(found.at[i], "properties");
                    if (cJSON_GetObjectItemCaseSensitive(props, *k) != NULL &&
                        !forbidden(found.at[i], o->type, *k)) {
                        in_schema = 1;
                    }
                }
                cr_expect(in_schema, "%s: the parser accepts \"%s\", the schema does not have it",
                          w, *k);
            }
        }
    }
    cr_expect_gt(rows, 40, "the tables list %d objects", rows);
    cJSON_Delete(schema);
}

/* the row's default as JSON (owned by the caller) */
static cJSON *default_value(const job_format_default *d)
{
    if (d->n == 1) return cJSON_CreateNumber(d->x[0]);
    if (d->n == 3) return cJSON_CreateDoubleArray(d->x, 3);
    cJSON *v = cJSON_Parse(d->json);
    cr_assert_not_null(v, "default of %s.%s is not JSON: %s", d->path, d->key, d->json);
    return v;
}

/* a schema property's own node, through a $ref (max_steps) when it has no "default" itself */
static const cJSON *property_default(const cJSON *schema, const cJSON *prop)
{
    const cJSON *def = cJSON_GetObjectItemCaseSensitive(prop, "default");
    const cJSON *ref = cJSON_GetObjectItemCaseSensitive(prop, "$ref");
    if (def == NULL && cJSON_IsString(ref)) {
        def = cJSON_GetObjectItemCaseSensitive(resolve_ref(schema, ref->valuestring), "default");
    }
    return def;
}

Test(job_format, parser_defaults_equal_schema_defaults)
{
    cJSON *schema = load_schema();
    for (const job_format_default *const *t = job_format_defaults; *t != NULL; t++) {
        for (const job_format_default *d = *t; d->path != NULL; d++) {
            char w[128];
            where(w, d->path, d->type);
            cJSON *want = default_value(d);
            nodes found = objects_at(schema, d->path, d->type);
            /* the default of a type key ("method": "dopri5") is at the alternative of that type */
            if (cJSON_IsString(want) &&
                (strcmp(d->key, "type") == 0 || strcmp(d->key, "method") == 0))
                keep_type(&found, want->valuestring);
            int seen = 0;
            for (int i = 0; i < found.n; i++) {
                const cJSON *props = cJSON_GetObjectItemCaseSensitive(found.at[i], "properties");
                const cJSON *prop = cJSON_GetObjectItemCaseSensitive(props, d->key);
                if (prop == NULL) continue;
                seen = 1;
                const cJSON *def = property_default(schema, prop);
                char *a = cJSON_PrintUnformatted(want);
                char *b = def != NULL ? cJSON_PrintUnformatted(def) : NULL;
                cr_expect(def != NULL && cJSON_Compare(want, def, 1),
                          "%s.%s: the parser's default is %s, the schema's %s", w, d->key, a,
                          b != NULL ? b : "missing");
                free(a);
                free(b);
            }
            cr_expect(seen, "%s.%s: the parser has a default, the schema has no such key", w,
                      d->key);
            cJSON_Delete(want);
        }
    }
    cJSON_Delete(schema);
}

/* whether a default row covers key at path for type */
static int has_default(const char *path, const char *type, const char *key)
{
    for (const job_format_default *const *t = job_format_defaults; *t != NULL; t++) {
        for (const job_format_default *d = *t; d->path != NULL; d++) {
            if (strcmp(d->path, path) == 0 && strcmp(d->key, key) == 0 &&
                (d->type == NULL || (type != NULL && strcmp(d->type, type) == 0))) {
                return 1;
            }
        }
    }
    return 0;
}

Test(job_format, every_schema_default_is_a_parser_default)
{
    cJSON *schema = load_schema();
    for (const job_format_object *const *t = job_format_object_tables(); *t != NULL; t++) {
        for (const job_format_object *o = *t; o->path != NULL; o++) {
            if (o->type_key != NULL && o->type == NULL) continue; /* a typed object's union */
            char w[128];
            where(w, o->path, o->type);
            nodes found = objects_at(schema, o->path, o->type);
            for (int i = 0; i < found.n; i++) {
                const cJSON *props = cJSON_GetObjectItemCaseSensitive(found.at[i], "properties");
                for (const cJSON *k = props->child; k != NULL; k = k->next) {
                    if (property_default(schema, k) == NULL) continue;
                    cr_expect(has_default(o->path, o->type, k->string),
                              "%s.%s: the schema has a default, the parser's tables do not", w,
                              k->string);
                }
            }
        }
    }
    cJSON_Delete(schema);
}

/* ---- the tables against the parser ---- */

/* A valid object of a type, for the rows whose object the base job does not have. */
static const struct {
    const char *path, *type, *json;
} probes[] = {
    {"scene.bodies[].shape", "box", "{\"type\": \"box\", \"size\": [0.1, 1, 0.1]}"},
    {"scene.bodies[].shape", "cylinder",
     "{\"type\": \"cylinder\", \"radius\": 0.05, \"length\": 1, \"axis\": [0, 1, 0]}"},
    {"scene.loop.stabilization", "project", "{\"method\": \"project\"}"},
    {"scene.loop.stabilization", "baumgarte", "{\"method\": \"baumgarte\"}"},
    {"trajectory", "sine", "{\"type\": \"sine\", \"amplitude\": 0.1, \"period\": 1}"},
    {"trajectory", "cosine", "{\"type\": \"cosine\", \"amplitude\": 0.1, \"period\": 1}"},
    {"trajectory", "spline", "{\"type\": \"spline\", \"times\": [0, 1], \"values\": [0, 0]}"},
    {"disturbance", "sine", "{\"type\": \"sine\", \"amplitude\": 0.1, \"period\": 1}"},
    {"integrator", "rk4", "{\"method\": \"rk4\"}"},
    {"integrator", "dopri5", "{\"method\": \"dopri5\"}"},
    {"integrator", "bdf", "{\"method\": \"bdf\"}"},
    {"controller", "pid", "{\"type\": \"pid\", \"kp\": 100, \"kv\": 20, \"ki\": 250}"},
    {"controller", "poles", "{\"type\": \"poles\", \"poles\": [-2, -2.1, -2.2]}"},
    {"controller", "lqr", "{\"type\": \"lqr\", \"Q\": [1, 1, 1], \"lambda\": 0.01}"},
    {"controller", "joint_pd", "{\"type\": \"joint_pd\", \"kp\": 100, \"kv\": 20}"},
    {"controller", "pd_gravity", "{\"type\": \"pd_gravity\", \"kp\": 100, \"kv\": 20}"},
    {"controller", "feedforward", "{\"type\": \"feedforward\", \"kp\": 100, \"kv\": 20}"},
};

/* the object at a table path in doc ("[]" and a per-coordinate array: entry 0), or NULL */
static cJSON *object_in(cJSON *doc, const char *path)
{
    char buf[256];
    char *save = NULL;
    snprintf(buf, sizeof buf, "%s", path);
    cJSON *v = doc;
    for (char *tok = buf[0] ? strtok_r(buf, ".", &save) : NULL; tok != NULL;
         tok = strtok_r(NULL, ".", &save)) {
        size_t len = strlen(tok);
        int items = len > 2 && strcmp(tok + len - 2, "[]") == 0;
        if (items) tok[len - 2] = '\0';
        v = cJSON_GetObjectItemCaseSensitive(v, tok);
        if (items) v = cJSON_GetArrayItem(v, 0);
    }
    if (cJSON_IsArray(v)) v = cJSON_GetArrayItem(v, 0);
    return v;
}

/* the normalised document of a preset (owned by the caller) */
static cJSON *preset_document(const char *name)
{
    char text[128];
    job *j = NULL;
    job_error err;
    snprintf(text, sizeof text, "{\"preset\": \"%s\"}", name);
    cr_assert_eq(job_parse(text, strlen(text), &j, &err), 0, "%s: %s", err.field, err.message);
    cJSON *doc = cJSON_Duplicate(j->normalised, 1);
    job_free(j);
    return doc;
}

Test(job_format, parser_applies_each_default_of_its_tables)
{
    int checked = 0;
    for (const job_format_default *const *t = job_format_defaults; *t != NULL; t++) {
        for (const job_format_default *d = *t; d->path != NULL; d++, checked++) {
            char w[128];
            where(w, d->path, d->type);
            /* The closing joint's location cannot be left out of a loop preset (the loop would
             * no longer close at q0), and no preset's closing joint sits at its tip's origin:
             * that default is checked against the schema only. */
            if (strcmp(d->path, "scene.loop.joint") == 0 && strcmp(d->key, "location") == 0)
                continue;
            int loop = strncmp(d->path, "scene.loop", 10) == 0;
            cJSON *doc = preset_document(loop ? "five_bar_pd" : "triple_pendulum_pd");
            cJSON *obj = object_in(doc, d->path);
            cr_assert_not_null(obj, "%s: the base job has no such object", w);

            /* an object of the row's type, where the base job's is of another */
            const char *type_key = cJSON_HasObjectItem(obj, "method") ? "method" : "type";
            const cJSON *type = cJSON_GetObjectItemCaseSensitive(obj, type_key);
            if (d->type != NULL &&
                !(cJSON_IsString(type) && strcmp(type->valuestring, d->type) == 0)) {
                const char *probe = NULL;
                for (size_t i = 0; i < sizeof probes / sizeof probes[0]; i++) {
                    if (strcmp(probes[i].path, d->path) == 0 &&
                        strcmp(probes[i].type, d->type) == 0)
                        probe = probes[i].json;
                }
                cr_assert_not_null(probe, "%s: add a probe object of that type to this test", w);
                cJSON *p = cJSON_Parse(probe);
                for (cJSON *c = obj->child; c != NULL; c = obj->child) {
                    cJSON_Delete(cJSON_DetachItemViaPointer(obj, c));
                }
                for (cJSON *c = p->child; c != NULL; c = p->child) {
                    cJSON_AddItemToObject(obj, c->string, cJSON_DetachItemViaPointer(p, c));
                }
                cJSON_Delete(p);
            }
            cJSON_DeleteItemFromObjectCaseSensitive(obj, d->key);

            job *j = NULL;
            job_error err;
            int rc = job_from_json(doc, &j, &err);
            cr_expect_eq(rc, 0, "%s without \"%s\": %s: %s", w, d->key, err.field, err.message);
            if (rc == 0) {
                const cJSON *got =
                    cJSON_GetObjectItemCaseSensitive(object_in(j->normalised, d->path), d->key);
                cJSON *want = default_value(d);
                char *a = cJSON_PrintUnformatted(want);
                char *b = got != NULL ? cJSON_PrintUnformatted(got) : NULL;
                cr_expect(got != NULL && cJSON_Compare(want, got, 1),
                          "%s.%s: the table says %s, the parser gives %s", w, d->key, a,
                          b != NULL ? b : "nothing");
                free(a);
                free(b);
                cJSON_Delete(want);
            }
            job_free(j);
            cJSON_Delete(doc);
        }
    }
    cr_expect_gt(checked, 35, "the tables list %d defaults", checked);
}
