/*
 * job_name.c - a preset job's name from what its edit changed (job_name.h).
 *
 * A recursive walk over the two normalised documents in the edited one's key order (the
 * format's order), then the keys only the preset's has. The first JOB_NAME_MAX_CHANGES changes
 * are kept as text, the others only counted. The walk is linear in the size of the documents.
 */
#include "job_name.h"

#include <stdio.h>
#include <string.h>

#define CHANGE_TEXT 96 /* bytes of one change's text, its NUL included */

typedef struct changes {
    char text[JOB_NAME_MAX_CHANGES][CHANGE_TEXT];
    int n; /* changes found, kept or not */
} changes;

/* cuts s before a UTF-8 sequence that snprintf left incomplete at its end */
static void utf8_trim(char *s)
{
    size_t n = strlen(s), i = n;
    while (i > 0 && ((unsigned char)s[i - 1] & 0xc0) == 0x80) i--;
    if (i == 0) return;
    unsigned char lead = (unsigned char)s[i - 1];
    size_t want = lead >= 0xf0 ? 4 : lead >= 0xe0 ? 3 : lead >= 0xc0 ? 2 : 1;
    if (n - (i - 1) < want) s[i - 1] = '\0';
}

/* v as a short value ("400", "rk4", "[0.1, 0, 0]", "(12 entries)") into buf */
static void value_text(const cJSON *v, char *buf, size_t len)
{
    if (cJSON_IsNumber(v)) {
        snprintf(buf, len, "%g", v->valuedouble);
    } else if (cJSON_IsString(v)) {
        snprintf(buf, len, "%s", v->valuestring);
        utf8_trim(buf);
    } else if (cJSON_IsBool(v)) {
        snprintf(buf, len, "%s", cJSON_IsTrue(v) ? "true" : "false");
    } else if (cJSON_IsNull(v) || v == NULL) {
        snprintf(buf, len, "null");
    } else if (cJSON_IsArray(v)) {
        int n = cJSON_GetArraySize(v), scalars = 1;
        for (const cJSON *e = v->child; e != NULL; e = e->next)
            scalars &= !cJSON_IsArray(e) && !cJSON_IsObject(e);
        if (n > 4 || !scalars) {
            snprintf(buf, len, "(%d entries)", n);
            return;
        }
        size_t used = (size_t)snprintf(buf, len, "[");
        for (const cJSON *e = v->child; e != NULL && used < len; e = e->next) {
            char one[32];
            value_text(e, one, sizeof one);
            used +=
                (size_t)snprintf(buf + used, len - used, "%s%s", e == v->child ? "" : ", ", one);
        }
        if (used < len) snprintf(buf + used, len - used, "]");
    } else {
        snprintf(buf, len, "{...}");
    }
}

/* records "PATH = VALUE" (v NULL: "no PATH") */
static void note(changes *c, const char *path, const cJSON *v, int removed)
{
    if (c->n < JOB_NAME_MAX_CHANGES) {
        const char *shown = strncmp(path, "controller.", 11) == 0 ? path + 11 : path;
        char value[48];
        value_text(v, value, sizeof value);
        utf8_trim(value);
        char *t = c->text[c->n];
        if (removed)
            snprintf(t, CHANGE_TEXT, "no %.60s", shown);
        else
            snprintf(t, CHANGE_TEXT, "%.44s = %s", shown, value);
        utf8_trim(t);
    }
    c->n++;
}

static int scalar_equal(const cJSON *a, const cJSON *b)
{
    if (cJSON_IsNumber(a) && cJSON_IsNumber(b)) return a->valuedouble == b->valuedouble;
    if (cJSON_IsString(a) && cJSON_IsString(b)) return strcmp(a->valuestring, b->valuestring) == 0;
    return (a->type & 0xff) == (b->type & 0xff) && !cJSON_IsArray(a) && !cJSON_IsObject(a);
}

static void diff(const cJSON *a, const cJSON *b, const char *path, int top, changes *c)
{
    char sub[256];
    if (cJSON_IsObject(a) && cJSON_IsObject(b)) {
        for (const cJSON *kb = b->child; kb != NULL; kb = kb->next) {
            if (top && (strcmp(kb->string, "name") == 0 || strcmp(kb->string, "tags") == 0))
                continue;
            snprintf(sub, sizeof sub, "%s%s%s", path, path[0] ? "." : "", kb->string);
            const cJSON *ka = cJSON_GetObjectItemCaseSensitive(a, kb->string);
            if (ka == NULL) {
                note(c, sub, kb, 0);
                continue;
            }
            if (top && strcmp(kb->string, "controller") == 0) {
                const cJSON *ta = cJSON_GetObjectItemCaseSensitive(ka, "type");
                const cJSON *tb = cJSON_GetObjectItemCaseSensitive(kb, "type");
                if (cJSON_IsString(ta) && cJSON_IsString(tb) &&
                    strcmp(ta->valuestring, tb->valuestring) != 0) {
                    note(c, "controller", tb, 0);
                    continue;
                }
            }
            diff(ka, kb, sub, 0, c);
        }
        for (const cJSON *ka = a->child; ka != NULL; ka = ka->next) {
            if (top && (strcmp(ka->string, "name") == 0 || strcmp(ka->string, "tags") == 0))
                continue;
            if (cJSON_GetObjectItemCaseSensitive(b, ka->string) != NULL) continue;
            snprintf(sub, sizeof sub, "%s%s%s", path, path[0] ? "." : "", ka->string);
            note(c, sub, NULL, 1);
        }
        return;
    }
    if (cJSON_IsArray(a) && cJSON_IsArray(b)) {
        int na = cJSON_GetArraySize(a), nb = cJSON_GetArraySize(b), scalars = 1, same = 1;
        for (const cJSON *e = b->child; e != NULL; e = e->next)
            scalars &= !cJSON_IsArray(e) && !cJSON_IsObject(e);
        if (na != nb) {
            note(c, path, b, 0);
            return;
        }
        if (scalars) {
            for (const cJSON *x = a->child, *y = b->child; x && y; x = x->next, y = y->next)
                same &= scalar_equal(x, y);
            if (!same) note(c, path, b, 0);
            return;
        }
        int i = 0;
        for (const cJSON *x = a->child, *y = b->child; x && y; x = x->next, y = y->next, i++) {
            snprintf(sub, sizeof sub, "%s[%d]", path, i);
            diff(x, y, sub, 0, c);
        }
        return;
    }
    if (cJSON_IsArray(a) || cJSON_IsObject(a) || cJSON_IsArray(b) || cJSON_IsObject(b) ||
        !scalar_equal(a, b))
        note(c, path, b, 0);
}

int job_name_changes(const cJSON *base, const cJSON *edited, const char *base_name, char *out,
                     size_t len)
{
    changes c = {.n = 0};
    diff(base, edited, "", 1, &c);
    if (len == 0) return c.n;
    snprintf(out, len, "%s", base_name);
    size_t used = strlen(out);
    int kept = c.n < JOB_NAME_MAX_CHANGES ? c.n : JOB_NAME_MAX_CHANGES;
    int written = 0;
    for (int i = 0; i < kept; i++) {
        size_t need = 2 + strlen(c.text[i]);
        /* room for this change and, when others follow, for ", +NN more" */
        size_t reserve = i + 1 < c.n ? 16 : 0;
        if (used + need + reserve >= len) break;
        used += (size_t)snprintf(out + used, len - used, ", %s", c.text[i]);
        written++;
    }
    if (written < c.n && used + 16 < len)
        snprintf(out + used, len - used, ", +%d more", c.n - written);
    return c.n;
}
