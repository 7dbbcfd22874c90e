/*
 * test_json_merge.c - RFC 7386 merge patch (server/json_merge.c): every example of the RFC's
 * appendix A against the RFC's own results, the job format's refinement (a changed "type" or
 * "method" replaces the object), the order of keys, and the cost: a patch of 100k keys is merged
 * with a number of key comparisons linear in its size (a scan of the target per patch key would
 * make N^2/2 = 5e9).
 */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "json_merge.h"
#include "job_fixture.h"

/* merge(target, patch) prints as expected (all in single quotes) */
static void expect_merge(const char *target, const char *patch, const char *expected)
{
    cJSON *p = fixture_cjson(patch), *want = fixture_cjson(expected);
    cJSON *got = json_merge_patch(fixture_cjson(target), p, NULL);
    cr_assert_not_null(got);
    char *g = cJSON_PrintUnformatted(got), *w = cJSON_PrintUnformatted(want);
    cr_assert_str_eq(g, w, "merge(%s, %s)", target, patch);
    free(g);
    free(w);
    cJSON_Delete(got);
    cJSON_Delete(want);
    cJSON_Delete(p);
}

Test(json_merge, rfc7386_appendix_a_examples)
{
    expect_merge("{'a':'b'}", "{'a':'c'}", "{'a':'c'}");
    expect_merge("{'a':'b'}", "{'b':'c'}", "{'a':'b','b':'c'}");
    expect_merge("{'a':'b'}", "{'a':null}", "{}");
    expect_merge("{'a':'b','b':'c'}", "{'a':null}", "{'b':'c'}");
    expect_merge("{'a':['b']}", "{'a':'c'}", "{'a':'c'}");
    expect_merge("{'a':'c'}", "{'a':['b']}", "{'a':['b']}");
    expect_merge("{'a':{'b':'c'}}", "{'a':{'b':'d','c':null}}", "{'a':{'b':'d'}}");
    expect_merge("{'a':[{'b':'c'}]}", "{'a':[1]}", "{'a':[1]}");
    expect_merge("['a','b']", "['c','d']", "['c','d']");
    expect_merge("{'a':'b'}", "['c']", "['c']");
    expect_merge("{'a':'foo'}", "null", "null");
    expect_merge("{'a':'foo'}", "'bar'", "'bar'");
    expect_merge("{'e':null}", "{'a':1}", "{'e':null,'a':1}");
    expect_merge("[1,2]", "{'a':'b','c':null}", "{'a':'b'}");
    expect_merge("{}", "{'a':{'bb':{'ccc':null}}}", "{'a':{'bb':{}}}");
}

Test(json_merge, a_null_target_is_an_empty_document)
{
    cJSON *p = fixture_cjson("{'a':1,'b':null}");
    cJSON *got = json_merge_patch(NULL, p, NULL);
    char *g = cJSON_PrintUnformatted(got);
    cr_assert_str_eq(g, "{\"a\":1}");
    free(g);
    cJSON_Delete(got);
    cJSON_Delete(p);
}

Test(json_merge, a_changed_type_or_method_replaces_the_object)
{
    expect_merge("{'c':{'type':'pid','kp':1,'ki':2}}", "{'c':{'type':'pd','kv':3}}",
                 "{'c':{'type':'pd','kv':3}}");
    expect_merge("{'i':{'method':'dopri5','rtol':1e-6}}", "{'i':{'method':'rk4'}}",
                 "{'i':{'method':'rk4'}}");
    /* the replacement is MergePatch({}, patch): the patch's nulls, at any depth, are dropped */
    expect_merge("{'c':{'type':'pid','kp':1,'ki':2}}", "{'c':{'type':'pd','kv':3,'ki':null}}",
                 "{'c':{'type':'pd','kv':3}}");
    expect_merge("{'i':{'method':'dopri5','rtol':1e-6}}",
                 "{'i':{'method':'rk4','rtol':null,'x':{'y':null,'z':1}}}",
                 "{'i':{'method':'rk4','x':{'z':1}}}");
    /* the same type, or a type given where the target has none, merges */
    expect_merge("{'c':{'type':'pid','kp':1,'ki':2}}", "{'c':{'type':'pid','kp':5}}",
                 "{'c':{'ki':2,'type':'pid','kp':5}}");
    expect_merge("{'c':{'kp':1}}", "{'c':{'type':'pd'}}", "{'c':{'kp':1,'type':'pd'}}");
}

Test(json_merge, keys_the_patch_names_move_after_the_others_in_patch_order)
{
    expect_merge("{'a':1,'b':2,'c':3,'d':4}", "{'c':30,'a':10,'e':5,'b':null}",
                 "{'d':4,'c':30,'a':10,'e':5}");
}

Test(json_merge, a_repeated_patch_key_is_applied_twice_in_order)
{
    expect_merge("{'a':{'x':1}}", "{'a':{'y':2},'a':{'x':null}}", "{'a':{'y':2}}");
    expect_merge("{}", "{'n':1,'n':null,'n':3}", "{'n':3}");
}

Test(json_merge, the_patch_is_not_changed_and_not_shared)
{
    cJSON *p = fixture_cjson("{'a':{'b':[1,2]},'c':'s'}");
    char *before = cJSON_PrintUnformatted(p);
    cJSON *got = json_merge_patch(fixture_cjson("{'a':{'z':0}}"), p, NULL);
    cJSON_Delete(got); /* would free the patch's items if it shared them */
    char *after = cJSON_PrintUnformatted(p);
    cr_assert_str_eq(after, before);
    free(before);
    free(after);
    cJSON_Delete(p);
}

/* {"k0":0,...,"k<n-1>":n-1} built directly (not parsed) */
static cJSON *many_keys(int n, int offset)
{
    cJSON *o = cJSON_CreateObject();
    cr_assert_not_null(o);
    char key[32];
    for (int i = 0; i < n; i++) {
        snprintf(key, sizeof key, "k%d", i);
        cr_assert_not_null(cJSON_AddNumberToObject(o, key, i + offset));
    }
    return o;
}

Test(json_merge, a_patch_of_100k_keys_costs_a_linear_number_of_key_comparisons)
{
    enum { N = 100000 };
    /* half the patch's keys are in the target (replaced), half are new (added) */
    cJSON *target = many_keys(N, 0);
    cJSON *patch = cJSON_CreateObject();
    char key[32];
    for (int i = N / 2; i < N + N / 2; i++) {
        snprintf(key, sizeof key, "k%d", i);
        cJSON_AddNumberToObject(patch, key, -i);
    }
    size_t compares = 0;
    cJSON *got = json_merge_patch(target, patch, &compares);
    cr_assert_not_null(got);
    cr_assert_eq(cJSON_GetArraySize(got), N + N / 2);
    cr_assert_eq(cJSON_GetObjectItemCaseSensitive(got, "k0")->valuedouble, 0);
    cr_assert_eq(cJSON_GetObjectItemCaseSensitive(got, "k60000")->valuedouble, -60000);
    cr_assert_eq(cJSON_GetObjectItemCaseSensitive(got, "k149999")->valuedouble, -149999);
    /* one per key found, two per key for the "type"/"method" scan of the patch, and the rare
       64-bit hash collision; a scan per key would make about N^2/2 */
    cr_assert_leq(compares, (size_t)4 * (N + N / 2), "%zu key comparisons for %d patch keys",
                  compares, N + N / 2);
    cr_assert_geq(compares, (size_t)N / 2, "the found keys were compared (%zu)", compares);
    cJSON_Delete(got);
    cJSON_Delete(patch);
}

Test(json_merge, nested_objects_are_indexed_each_once)
{
    /* 1000 objects of 100 keys below one key each: the cost stays linear in all the keys */
    cJSON *target = cJSON_CreateObject(), *patch = cJSON_CreateObject();
    char key[32];
    for (int i = 0; i < 1000; i++) {
        snprintf(key, sizeof key, "o%d", i);
        cJSON_AddItemToObject(target, key, many_keys(100, 0));
        cJSON_AddItemToObject(patch, key, many_keys(100, 1));
    }
    size_t compares = 0;
    cJSON *got = json_merge_patch(target, patch, &compares);
    cr_assert_not_null(got);
    cr_assert_eq(
        cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(got, "o999"), "k99")
            ->valuedouble,
        100);
    cr_assert_leq(compares, (size_t)4 * (1000 + 1000 * 100), "%zu", compares);
    cJSON_Delete(got);
    cJSON_Delete(patch);
}
