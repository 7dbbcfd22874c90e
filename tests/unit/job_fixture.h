/*
 * job_fixture.h - jobs written in the tests as JSON with single quotes and parsed by the job format
 * (server/job_json.h); tests/unit only. Their runs: run_fixture.h, included here.
 *
 * Single quotes keep the jobs readable inside C strings: every ' becomes " before job_parse, so a
 * job given this way holds no apostrophe of its own. The helper that expects success fails the
 * test with the parser's message.
 */
#ifndef CTC_JOB_FIXTURE_H
#define CTC_JOB_FIXTURE_H

#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "run_fixture.h"

/* text with every single quote turned into a double quote; the caller frees the result */
static inline char *fixture_json(const char *text)
{
    char *s = strdup(text);
    cr_assert_not_null(s);
    for (char *c = s; *c != '\0'; c++)
        if (*c == '\'') *c = '"';
    return s;
}

/* the cJSON value of text (single quotes); fails the test when it is not JSON. The caller frees
 * it (cJSON_Delete). */
static inline cJSON *fixture_cjson(const char *text)
{
    char *s = fixture_json(text);
    cJSON *v = cJSON_Parse(s);
    cr_assert_not_null(v, "bad test JSON: %s", text);
    free(s);
    return v;
}

/* The job of text (single quotes, see above), or NULL with *err filled when the format refuses
 * it. The caller frees the job (job_free). */
static inline job *fixture_parse(const char *text, job_error *err)
{
    char *doc = fixture_json(text);
    job *j = NULL;
    int rc = job_parse(doc, strlen(doc), &j, err);
    free(doc);
    return rc == 0 ? j : NULL;
}

/* The job of text; fails the test with the error's code, field and message and the document
 * when the format refuses it. The caller frees the job (job_free). */
static inline job *fixture_parse_ok(const char *text)
{
    char *doc = fixture_json(text);
    job *j = NULL;
    job_error err;
    int rc = job_parse(doc, strlen(doc), &j, &err);
    cr_assert_eq(rc, 0, "job rejected: %s at \"%s\": %s\n%s", job_error_code_name(err.code),
                 err.field, err.message, doc);
    cr_assert_not_null(j);
    free(doc);
    return j;
}

/* The run to its end of the job of text (single quotes), the job into *j; fails the test, naming
 * what, when the format refuses the job, and as fixture_run_done does when the run fails. The
 * caller frees both (ctc_sim_result_free, job_free). */
static inline ctc_sim_result *fixture_run_text(const char *text, const char *what, job **j)
{
    job_error err;
    *j = fixture_parse(text, &err);
    cr_assert_not_null(*j, "%s: %s: %s", what, err.field, err.message);
    return fixture_run_done(&(*j)->spec);
}

/* A job the format must refuse: its text (single quotes) and the field and message it must
 * name. */
typedef struct fixture_bad_job {
    const char *text, *field, *message;
} fixture_bad_job;

/* Expects the format to refuse each of the n jobs of bad with exactly its field and message;
 * messages name a case by its index in bad. */
static inline void fixture_expect_refused(const fixture_bad_job *bad, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        job_error err;
        job *j = fixture_parse(bad[i].text, &err);
        cr_expect_null(j, "case %zu accepted", i);
        job_free(j);
        if (j) continue;
        cr_expect_str_eq(err.field, bad[i].field, "case %zu", i);
        cr_expect_str_eq(err.message, bad[i].message, "case %zu", i);
    }
}

/* Pieces of planar jobs: a uniform rod of 1 m and 1 kg (centre of mass 0.5 m below its joint,
 * I_c = 1/12 kg m^2 about every axis) on a revolute joint about z at the origin, the same rod
 * hung from the first one's tip (joint at (0, -1, 0) m), and DOPRI5 at rtol 1e-11, atol 1e-13. */
#define FIXTURE_ROD                                                                                \
    "{'mass':1,'com':[0,-0.5,0],'inertia':[0.0833333333333333,0.0833333333333333,"                 \
    "0.0833333333333333],'joint':{'type':'revolute','axis':[0,0,1]}}"
#define FIXTURE_ROD2                                                                               \
    "{'mass':1,'com':[0,-0.5,0],'inertia':[0.0833333333333333,0.0833333333333333,"                 \
    "0.0833333333333333],'joint':{'type':'revolute','axis':[0,0,1],'location':[0,-1,0]}}"
#define FIXTURE_INTEG "'integrator':{'method':'dopri5','rtol':1e-11,'atol':1e-13}"

#endif
