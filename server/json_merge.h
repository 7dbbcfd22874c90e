/*
 * json_merge.h - RFC 7386 JSON merge patch in time linear in the size of the target and the patch.
 *
 * The preset requests of the job format (job_json.c) are merge patches applied to a preset's
 * document, and they arrive from the network: a patch of N keys must cost O(N), not the O(N^2) of
 * looking each patch key up by a scan of the target's keys. Each object of the target that the
 * patch reaches is indexed once (an open-addressing hash table of its keys, FNV-1a), so each patch
 * key costs O(1) expected key comparisons.
 *
 * Semantics (RFC 7386 section 2, with one refinement of the job format): a patch that is not an
 * object replaces the target; null deletes a key; an object merges key by key, recursively; a key
 * the target lacks is added. The refinement: an object whose "type" or "method" the patch changes
 * (both strings, different) is replaced whole: made from the patch alone as MergePatch({}, patch),
 * so that the old kind's keys (a PID's "ki", dopri5's "rtol") do not carry over to the new kind,
 * and the patch's nulls are dropped (a "ki": null that removes the old kind's key is not left in
 * the result). Key order: keys the patch does not
 * name keep their place; a key the patch names is (re)added after them, in the patch's order.
 */
#ifndef JSON_MERGE_H
#define JSON_MERGE_H

#include <stddef.h>

#include <cjson/cJSON.h>

/* Applies patch to target and returns the result, or NULL out of memory (target is then freed).
 * target is consumed (freed or reused in the result; it may be NULL, which is an empty document);
 * patch is only read, and the result shares nothing with it. Keys are compared case-sensitively;
 * the patch's objects should have no repeated key (json_check_repeated_keys): a repeated key is
 * applied twice, in order. compares, when not NULL, receives the number of key comparisons
 * (strcmp) the merge made: at most a small constant times the number of keys of the patch, in
 * expectation, whatever the sizes (the contract tests/unit/test_json_merge.c checks).
 * Thread safety: none shared; any number of merges may run at once on distinct documents. */
cJSON *json_merge_patch(cJSON *target, const cJSON *patch, size_t *compares);

#endif
