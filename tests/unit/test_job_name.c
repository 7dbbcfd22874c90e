/*
 * test_job_name.c - a preset job's name from what its edit changed (server/job_name.c): the
 * changes written as the header says, against names written out by hand for small documents
 * (the oracle: each expected string is read off the two documents), the limits (at most
 * JOB_NAME_MAX_CHANGES written, the rest counted, never more than the buffer, never a UTF-8
 * character cut), and the whole path through job_from_json: a preset request named after its
 * edit, the same edit posted as the whole document, a value restated at its default, a name of
 * the user's own kept. Tags: the validation messages, exactly.
 */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "job_name.h"
#include "job_fixture.h"

/* the name of edited against base, and the count of changes */
static int name_of(const char *base, const char *edited, char *out, size_t len)
{
    cJSON *a = fixture_cjson(base), *b = fixture_cjson(edited);
    int n = job_name_changes(a, b, "p", out, len);
    cJSON_Delete(a);
    cJSON_Delete(b);
    return n;
}

Test(job_name, each_kind_of_change_is_written_as_documented)
{
    char out[JOB_MAX_NAME + 1];
    cr_assert_eq(name_of("{'name':'x','duration':5}", "{'name':'y','duration':5}", out, sizeof out),
                 0);
    cr_assert_str_eq(out, "p", "no change (the name is not compared)");

    cr_assert_eq(name_of("{'controller':{'type':'pid','kp':100,'kv':20}}",
                         "{'controller':{'type':'pid','kp':400,'kv':20}}", out, sizeof out),
                 1);
    cr_assert_str_eq(out, "p, kp = 400", "\"controller.\" is left out of the path");

    name_of("{'duration':5,'integrator':{'method':'rk4','step':0.01}}",
            "{'duration':2.5,'integrator':{'method':'rk4','step':0.001}}", out, sizeof out);
    cr_assert_str_eq(out, "p, duration = 2.5, integrator.step = 0.001");

    name_of("{'scene':{'q0':[0,0,0]}}", "{'scene':{'q0':[0.1,0,0]}}", out, sizeof out);
    cr_assert_str_eq(out, "p, scene.q0 = [0.1, 0, 0]", "a short array of numbers, written out");

    name_of("{'scene':{'q0':[0,0,0,0,0]}}", "{'scene':{'q0':[0,0,0,0,1]}}", out, sizeof out);
    cr_assert_str_eq(out, "p, scene.q0 = (5 entries)", "a longer one, counted");

    name_of("{'trajectory':[{'type':'sine','amplitude':1},{'type':'sine','amplitude':1}]}",
            "{'trajectory':[{'type':'sine','amplitude':1},{'type':'sine','amplitude':0.5}]}", out,
            sizeof out);
    cr_assert_str_eq(out, "p, trajectory[1].amplitude = 0.5", "arrays of objects, entry by entry");

    name_of("{'disturbance':{'type':'step'},'duration':1}", "{'duration':1,'limits':{'a':true}}",
            out, sizeof out);
    cr_assert_str_eq(out, "p, limits = {...}, no disturbance", "added, then removed keys");

    name_of("{'controller':{'type':'pid','kp':100}}", "{'controller':{'type':'lqr','lambda':1}}",
            out, sizeof out);
    cr_assert_str_eq(out, "p, controller = lqr",
                     "another type: one change, parameters not compared");

    name_of("{'tags':['a'],'x':1}", "{'tags':['b'],'x':1}", out, sizeof out);
    cr_assert_str_eq(out, "p", "the tags are not compared");
}

Test(job_name, long_edits_are_cut_at_whole_changes_and_counted)
{
    char out[JOB_MAX_NAME + 1];
    int n = name_of("{'a':1,'b':1,'c':1,'d':1,'e':1,'f':1}",
                    "{'a':2,'b':2,'c':2,'d':2,'e':2,'f':2}", out, sizeof out);
    cr_assert_eq(n, 6);
    cr_assert_str_eq(out, "p, a = 2, b = 2, c = 2, d = 2, +2 more");

    /* a buffer with room for two changes and the count */
    char small[26];
    name_of("{'a':1,'b':1,'c':1}", "{'a':2,'b':2,'c':2}", small, sizeof small);
    cr_assert_str_eq(small, "p, a = 2, +2 more");

    /* a long multi-byte string is cut before a character, never inside one */
    char value[300] = "{'s':'";
    for (int i = 0; i < 60; i++) strcat(value, "\xc3\xa9"); /* é, 2 bytes */
    strcat(value, "'}");
    name_of("{'s':'x'}", value, out, sizeof out);
    size_t len = strlen(out);
    cr_assert_gt(len, 10);
    unsigned char last = (unsigned char)out[len - 1];
    cr_assert(last == 0xa9, "ends on a whole character (got byte 0x%02x)", last);
}

/* the name job_from_json gives doc (single quotes) */
static void expect_job_name(const char *doc, const char *want)
{
    cJSON *d = fixture_cjson(doc);
    job *j = NULL;
    job_error e;
    cr_assert_eq(job_from_json(d, &j, &e), 0, "%s: %s", e.field, e.message);
    cr_assert_str_eq(j->name, want, "%s", doc);
    const cJSON *n = cJSON_GetObjectItemCaseSensitive(j->normalised, "name");
    cr_assert_str_eq(n->valuestring, want, "the normalised job has the name too");
    job_free(j);
    cJSON_Delete(d);
}

Test(job_name, preset_requests_are_named_after_their_edit)
{
    expect_job_name("{'preset':'triple_pendulum_pid','controller':{'kp':400}}",
                    "triple_pendulum_pid, kp = 400");
    expect_job_name("{'preset':'triple_pendulum_pid','controller':{'kp':100}}",
                    "Triple pendulum, PID (Kingsley et al. 2017, sec. 7.1)");
    expect_job_name("{'preset':'n_link_pendulum','n':4,'duration':2}",
                    "n_link_pendulum, n = 4, duration = 2");
    expect_job_name("{'preset':'triple_pendulum_pid','name':'mine','duration':2}", "mine");
    expect_job_name("{'preset':'triple_pendulum_pid','name':'Triple pendulum, PID (Kingsley et al. "
                    "2017, sec. 7.1)','duration':2}",
                    "triple_pendulum_pid, duration = 2");
    /* another controller: the preset's name for it (which changes defaults elsewhere too) */
    expect_job_name("{'preset':'triple_pendulum_pid','controller':{'type':'lqr','Q':[1,1,1],"
                    "'lambda':0.01},'duration':2}",
                    "Triple pendulum, LQR (scene of Kingsley et al. 2017, sec. 7.1)");
}

Test(job_name, a_whole_document_over_its_preset_is_named_as_its_edit)
{
    /* the preset's normalised job, edited in one gain, posted whole with "preset" */
    cJSON *req = fixture_cjson("{'preset':'triple_pendulum_pd'}");
    job *j = NULL;
    job_error e;
    cr_assert_eq(job_from_json(req, &j, &e), 0, "%s", e.message);
    cJSON *doc = cJSON_Duplicate(j->normalised, 1);
    job_free(j);
    cJSON_Delete(req);
    cJSON *ctrl = cJSON_GetObjectItemCaseSensitive(doc, "controller");
    cJSON_ReplaceItemInObjectCaseSensitive(ctrl, "kv", cJSON_CreateNumber(35));
    cJSON_AddStringToObject(doc, "preset", "triple_pendulum_pd");
    cr_assert_eq(job_from_json(doc, &j, &e), 0, "%s", e.message);
    cr_assert_str_eq(j->name, "triple_pendulum_pd, kv = 35",
                     "every restated default is no change: only kv is named");
    job_free(j);
    cJSON_Delete(doc);
}

/* job_from_json(doc) fails at field with message */
static void expect_error(const char *doc, const char *field, const char *message)
{
    cJSON *d = fixture_cjson(doc);
    job *j = NULL;
    job_error e;
    cr_assert_eq(job_from_json(d, &j, &e), -1, "%s should fail", doc);
    cr_assert_eq(e.code, JOB_INVALID_FIELD);
    cr_assert_str_eq(e.field, field);
    cr_assert_str_eq(e.message, message);
    cJSON_Delete(d);
}

Test(job_name, tags_are_checked_and_kept_as_given)
{
    expect_error("{'preset':'triple_pendulum_pd','tags':'a'}", "tags",
                 "must be an array of strings (got a string)");
    expect_error("{'preset':'triple_pendulum_pd','tags':['a',3]}", "tags[1]",
                 "must be a string (got a number)");
    expect_error("{'preset':'triple_pendulum_pd','tags':['']}", "tags[0]",
                 "must be 1 to 40 bytes long (got 0)");
    expect_error(
        "{'preset':'triple_pendulum_pd','tags':['12345678901234567890123456789012345678901']}",
        "tags[0]", "must be 1 to 40 bytes long (got 41)");
    expect_error("{'preset':'triple_pendulum_pd','tags':['a','b','a']}", "tags[2]",
                 "repeats tag \"a\"");
    expect_error("{'preset':'triple_pendulum_pd','tags':['a\\tb']}", "tags[0]",
                 "must not hold a control character (byte 1)");
    expect_error("{'preset':'triple_pendulum_pd','tags':['1','2','3','4','5','6','7','8','9','10',"
                 "'11','12','13','14','15','16','17']}",
                 "tags", "must have at most 16 tags (got 17)");

    cJSON *d = fixture_cjson("{'preset':'triple_pendulum_pd','tags':['sweep','kp = 400']}");
    job *j = NULL;
    job_error e;
    cr_assert_eq(job_from_json(d, &j, &e), 0, "%s", e.message);
    char *text = cJSON_PrintUnformatted(cJSON_GetObjectItemCaseSensitive(j->normalised, "tags"));
    cr_assert_str_eq(text, "[\"sweep\",\"kp = 400\"]");
    cr_assert_str_eq(j->normalised->child->next->string, "tags", "tags come right after the name");
    free(text);
    job_free(j);
    cJSON_Delete(d);

    d = fixture_cjson("{'preset':'triple_pendulum_pd'}");
    cr_assert_eq(job_from_json(d, &j, &e), 0, "%s", e.message);
    cr_assert_null(cJSON_GetObjectItemCaseSensitive(j->normalised, "tags"),
                   "none given: none kept");
    job_free(j);
    cJSON_Delete(d);
}
