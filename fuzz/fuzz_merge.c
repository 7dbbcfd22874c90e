/*
 * fuzz_merge.c - libFuzzer harness of the merge patch (json_merge.h) against a naive reference.
 *
 * A preset request's overrides reach json_merge_patch from the network (job_json.c), but there
 * only over the presets' documents; this harness gives it any target. The input is two JSON texts
 * one after the other, the target and then the patch ("{...} {...}"); an input that is not two
 * documents cJSON reads is skipped.
 *
 * The oracle is RFC 7386 section 2's pseudocode written plainly over cJSON's own lookups
 * (cJSON_DetachItemFromObjectCaseSensitive, a scan of the member list: quadratic, and obviously
 * so), with the job format's refinement: an object whose "type" or "method" the patch changes
 * (both strings, different) is made again from the patch alone, MergePatch({}, patch), so that the
 * old kind's keys do not carry over. The result of json_merge_patch must print exactly as the
 * reference's (key order included: a key the patch names goes after the others), the patch must
 * be left as it was, and the key comparisons counted must stay within the contract's linear bound
 * (4 per key of the patch and 4 per object of the patch, which only a 64-bit FNV-1a collision
 * could exceed). The bound is checked where the target repeats no key: indexing a target object
 * compares each repeated key with its first copy, a count that grows with the target's repeats
 * (linearly, as the indexing itself), not with the patch.
 *
 * Repeated keys: json_merge_patch indexes the first of a target's repeated keys and applies a
 * patch's repeated key twice, in order; the reference does the same. When both the target and the
 * patch repeat keys the two may differ (the index no longer sees a target's second copy once the
 * first is gone), and the contract asks for a patch without repeated keys (job_json.c rejects a
 * request that has any), so such inputs are skipped.
 */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "json_merge.h"
#include "json_read.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void fail(const char *what, size_t size)
{
    fprintf(stderr, "fuzz_merge: %s (input of %zu bytes)\n", what, size);
    abort();
}

static void *checked(void *p, size_t size)
{
    if (p == NULL) fail("out of memory", size);
    return p;
}

/* the patch names another "type" or "method" than the target (both strings) */
static int reference_changes_kind(const cJSON *target, const cJSON *patch)
{
    static const char *const keys[] = {"type", "method"};
    for (int k = 0; k < 2; k++) {
        const cJSON *a = cJSON_GetObjectItemCaseSensitive(target, keys[k]);
        const cJSON *b = cJSON_GetObjectItemCaseSensitive(patch, keys[k]);
        if (cJSON_IsString(a) && cJSON_IsString(b) && strcmp(a->valuestring, b->valuestring) != 0)
            return 1;
    }
    return 0;
}

/* RFC 7386 section 2, MergePatch(Target, Patch), with the refinement; target consumed */
static cJSON *reference_merge(cJSON *target, const cJSON *patch, size_t size)
{
    if (!cJSON_IsObject(patch)) {
        cJSON_Delete(target);
        return checked(cJSON_Duplicate(patch, 1), size);
    }
    if (!cJSON_IsObject(target) || reference_changes_kind(target, patch)) {
        cJSON_Delete(target);
        target = checked(cJSON_CreateObject(), size);
    }
    for (const cJSON *m = patch->child; m != NULL; m = m->next) {
        cJSON *old = cJSON_DetachItemFromObjectCaseSensitive(target, m->string);
        if (cJSON_IsNull(m)) {
            cJSON_Delete(old);
            continue;
        }
        if (!cJSON_AddItemToObject(target, m->string, reference_merge(old, m, size)))
            fail("out of memory", size);
    }
    return target;
}

/* keys and objects of v, at any depth */
static void count_keys(const cJSON *v, size_t *keys, size_t *objects)
{
    if (cJSON_IsObject(v)) ++*objects;
    for (const cJSON *m = v->child; m != NULL; m = m->next) {
        if (cJSON_IsObject(v)) ++*keys;
        count_keys(m, keys, objects);
    }
}

static int has_repeated_keys(const cJSON *v)
{
    job_error e;
    return json_check_repeated_keys(&e, v, "") != 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *text = (const char *)data;
    const char *end = NULL;
    cJSON *target = cJSON_ParseWithLengthOpts(text, size, &end, 0);
    if (target == NULL) return 0;
    size_t used = (size_t)(end - text);
    cJSON *patch = cJSON_ParseWithLengthOpts(text + used, size - used, NULL, 0);
    int target_repeats = has_repeated_keys(target);
    if (patch == NULL || (target_repeats && has_repeated_keys(patch))) {
        cJSON_Delete(target);
        cJSON_Delete(patch);
        return 0;
    }

    char *patch_before = checked(cJSON_PrintUnformatted(patch), size);
    cJSON *expected = reference_merge(checked(cJSON_Duplicate(target, 1), size), patch, size);
    size_t compares = 0;
    cJSON *got = json_merge_patch(target, patch, &compares);
    if (got == NULL) fail("json_merge_patch returned NULL", size);

    char *want_text = checked(cJSON_PrintUnformatted(expected), size);
    char *got_text = checked(cJSON_PrintUnformatted(got), size);
    if (strcmp(want_text, got_text) != 0) {
        fprintf(stderr, "fuzz_merge: expected %s\nfuzz_merge: got      %s\n", want_text, got_text);
        fail("result differs from RFC 7386's", size);
    }
    char *patch_after = checked(cJSON_PrintUnformatted(patch), size);
    if (strcmp(patch_before, patch_after) != 0) fail("the patch was changed", size);
    size_t keys = 0, objects = 0;
    count_keys(patch, &keys, &objects);
    if (!target_repeats && compares > 4 * keys + 4 * objects) {
        fprintf(stderr, "fuzz_merge: %zu key comparisons for %zu keys in %zu objects\n", compares,
                keys, objects);
        fail("more key comparisons than the linear bound", size);
    }

    cJSON_free(patch_after);
    cJSON_free(got_text);
    cJSON_free(want_text);
    cJSON_free(patch_before);
    cJSON_Delete(got);
    cJSON_Delete(expected);
    cJSON_Delete(patch);
    return 0;
}
