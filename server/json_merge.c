/*
 * json_merge.c - RFC 7386 merge patch (json_merge.h) in linear time.
 *
 * cJSON keeps an object's members in a linked list, and cJSON_GetObjectItem scans it, so looking
 * each of a patch's N keys up in a target that grows to N keys would cost N^2/2 comparisons.
 * Here each target object the patch reaches gets a key index first: an open-addressing table
 * (linear probing, power-of-two size at least 3/2 of the keys it may hold) of the members' 64-bit
 * FNV-1a hashes and pointers. A string comparison is made only where two hashes are equal, so a
 * lookup costs one comparison when the key is there and almost never one when it is not. Members
 * are detached by pointer (O(1), cJSON keeps the list's tail in its head's prev) and appended at
 * the tail, where RFC 7386 section 2's pseudocode puts them. The table holds the target's keys
 * and those the patch adds, so it never grows; a deleted key leaves a tombstone, and a merged key
 * takes its old slot.
 */
#include "json_merge.h"

#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* the table's slots: item NULL is empty, TOMBSTONE a deleted key */
typedef struct slot {
    uint64_t hash;
    cJSON *item;
} slot;

static cJSON tombstone_item;
#define TOMBSTONE (&tombstone_item)

typedef struct key_index {
    slot *slots;
    size_t mask;      /* size - 1, size a power of two */
    size_t *compares; /* key comparisons made, counted here */
} key_index;

static uint64_t fnv1a(const char *s)
{
    uint64_t h = 14695981039346656037u;
    for (; *s != '\0'; s++) {
        h ^= (unsigned char)*s;
        h *= 1099511628211u;
    }
    return h;
}

/* the slot holding key, or, when it is absent, the slot where it would go (the first tombstone or
 * the empty slot that ends the probe); *found says which */
static size_t index_probe(key_index *idx, const char *key, uint64_t hash, int *found)
{
    size_t free_slot = SIZE_MAX;
    for (size_t i = (size_t)hash & idx->mask;; i = (i + 1) & idx->mask) {
        slot *s = &idx->slots[i];
        if (s->item == NULL) {
            *found = 0;
            return free_slot != SIZE_MAX ? free_slot : i;
        }
        if (s->item == TOMBSTONE) {
            if (free_slot == SIZE_MAX) free_slot = i;
        } else if (s->hash == hash) {
            ++*idx->compares;
            if (strcmp(s->item->string, key) == 0) {
                *found = 1;
                return i;
            }
        }
    }
}

/* an index of object's members, room for extra more; the first of a repeated key is indexed,
 * as cJSON_GetObjectItemCaseSensitive finds it. Returns 0, or -1 out of memory. */
static int index_build(key_index *idx, const cJSON *object, size_t extra, size_t *compares)
{
    size_t n = 0;
    for (const cJSON *m = object->child; m != NULL; m = m->next) n++;
    size_t want = (n + extra) + (n + extra) / 2 + 1, size = 8;
    while (size < want) size *= 2;
    idx->slots = calloc(size, sizeof *idx->slots);
    if (idx->slots == NULL) return -1;
    idx->mask = size - 1;
    idx->compares = compares;
    for (cJSON *m = object->child; m != NULL; m = m->next) {
        if (m->string == NULL) continue;
        uint64_t h = fnv1a(m->string);
        int found;
        size_t i = index_probe(idx, m->string, h, &found);
        if (!found) idx->slots[i] = (slot){h, m};
    }
    return 0;
}

/* patch names another "type" or "method" than target (both objects) */
static int changes_kind(key_index *idx, const cJSON *patch)
{
    static const char *const keys[] = {"type", "method"};
    for (int k = 0; k < 2; k++) {
        const cJSON *b = NULL;
        for (const cJSON *m = patch->child; m != NULL && b == NULL; m = m->next) {
            ++*idx->compares;
            if (m->string != NULL && strcmp(m->string, keys[k]) == 0) b = m;
        }
        if (!cJSON_IsString(b)) continue;
        int found;
        size_t i = index_probe(idx, keys[k], fnv1a(keys[k]), &found);
        const cJSON *a = found ? idx->slots[i].item : NULL;
        if (cJSON_IsString(a) && strcmp(a->valuestring, b->valuestring) != 0) return 1;
    }
    return 0;
}

static cJSON *merge(cJSON *target, const cJSON *patch, size_t *compares);

/* merges the members of patch (an object) into target (an object, consumed); NULL out of memory */
static cJSON *merge_members(cJSON *target, const cJSON *patch, size_t *compares)
{
    size_t npatch = 0;
    for (const cJSON *m = patch->child; m != NULL; m = m->next) npatch++;
    key_index idx;
    if (index_build(&idx, target, npatch, compares) != 0) {
        cJSON_Delete(target);
        return NULL;
    }
    if (changes_kind(&idx, patch)) {
        /* made again from the patch alone, MergePatch({}, patch): its nulls remove nothing and
           are dropped, as RFC 7386 drops them wherever a patch replaces a non-object */
        free(idx.slots);
        cJSON_Delete(target);
        return merge(NULL, patch, compares);
    }
    for (const cJSON *m = patch->child; m != NULL; m = m->next) {
        uint64_t h = fnv1a(m->string);
        int found;
        size_t i = index_probe(&idx, m->string, h, &found);
        cJSON *old = found ? cJSON_DetachItemViaPointer(target, idx.slots[i].item) : NULL;
        if (cJSON_IsNull(m)) {
            cJSON_Delete(old); /* null removes the key */
            if (found) idx.slots[i].item = TOMBSTONE;
            continue;
        }
        cJSON *merged = merge(old, m, compares);
        if (merged == NULL || !cJSON_AddItemToObject(target, m->string, merged)) {
            cJSON_Delete(merged);
            cJSON_Delete(target);
            free(idx.slots);
            return NULL;
        }
        idx.slots[i] = (slot){h, merged};
    }
    free(idx.slots);
    return target;
}

static cJSON *merge(cJSON *target, const cJSON *patch, size_t *compares)
{
    if (!cJSON_IsObject(patch)) {
        cJSON_Delete(target);
        return cJSON_Duplicate(patch, 1);
    }
    if (!cJSON_IsObject(target)) {
        cJSON_Delete(target);
        target = cJSON_CreateObject();
        if (target == NULL) return NULL;
    }
    if (patch->child == NULL) return target;
    return merge_members(target, patch, compares);
}

cJSON *json_merge_patch(cJSON *target, const cJSON *patch, size_t *compares)
{
    size_t count = 0;
    cJSON *out = merge(target, patch, &count);
    if (compares != NULL) *compares = count;
    return out;
}
