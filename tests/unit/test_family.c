/*
 * test_family.c - families of jobs (server/family.c): the axes' values, their combination, the
 * members' documents and seeds, the refusals, and the table.
 *
 * Oracles, each apart from the code under test:
 *  - the job format itself: a member's spec must be byte for byte what job_parse makes of the
 *    request written out here by hand (the base with the axis's key set), which is what
 *    POST /api/jobs would store for it;
 *  - closed forms: linspace and logspace values computed here, the powers of ten exact;
 *  - statistics: 4000 uniform and normal draws have the mean and deviation of their law within
 *    five standard errors, and stay in their range;
 *  - a second expansion of the same document (bitwise the same members) and one with another
 *    seed (other draws);
 *  - the table's text written out here for rows whose metrics are known.
 * Error paths assert the exact message.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "family.h"
#include "job_json.h"

/* expands text, which must succeed */
static family *expand_ok(const char *text, long max)
{
    family *f = NULL;
    family_error err;
    int rc = family_expand(text, strlen(text), max, &f, &err);
    cr_assert_eq(rc, 0, "family_expand: %d %s %s: %s", err.status, err.code, err.field,
                 err.message);
    cr_assert_not_null(f);
    return f;
}

/* expands text, which must fail with exactly this status, code, field and message */
static void expand_fails(const char *text, long max, int status, const char *code,
                         const char *field, const char *message)
{
    family *f = (family *)&max;
    family_error err;
    cr_assert_eq(family_expand(text, strlen(text), max, &f, &err), -1, "%s expanded", text);
    cr_assert_null(f);
    cr_assert_eq(err.status, status, "%s: status %d", text, err.status);
    cr_assert_str_eq(err.code, code, "%s\ngot: %s", text, err.code);
    cr_assert_str_eq(err.field, field, "%s\ngot: %s: %s", text, err.field, err.message);
    cr_assert_str_eq(err.message, message, "%s\ngot: %s", text, err.message);
}

/* the normalised text job_parse makes of a request */
static char *normalised(const char *request)
{
    job *j = NULL;
    job_error err;
    cr_assert_eq(job_parse(request, strlen(request), &j, &err), 0, "%s: %s: %s", request, err.field,
                 err.message);
    char *text = cJSON_PrintUnformatted(j->normalised);
    job_free(j);
    return text;
}

/* member m's axis value a */
static double value_of(const family *f, long m, int a)
{
    cJSON *v = cJSON_Parse(f->members[m].values);
    cr_assert(cJSON_IsArray(v));
    double x = cJSON_GetArrayItem(v, a)->valuedouble;
    cJSON_Delete(v);
    return x;
}

/* a number at a path of member m's spec */
static double spec_number(const family *f, long m, const char *k1, const char *k2, const char *k3)
{
    cJSON *doc = cJSON_Parse(f->members[m].spec);
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(doc, k1);
    if (k2) v = cJSON_GetObjectItemCaseSensitive(v, k2);
    if (k3) v = cJSON_GetObjectItemCaseSensitive(v, k3);
    cr_assert(cJSON_IsNumber(v), "member %ld has no number at %s.%s.%s", m, k1, k2 ? k2 : "",
              k3 ? k3 : "");
    double x = v->valuedouble;
    cJSON_Delete(doc);
    return x;
}

#define BASE "{\"preset\": \"triple_pendulum_pd\", \"duration\": 0.05}"

Test(family, a_product_of_a_list_and_a_logspace_makes_each_member_as_post_would)
{
    family *f = expand_ok("{\"name\": \"gains\", \"base\": " BASE ", \"axes\": ["
                          "{\"path\": \"controller.kp\", \"values\": [50, 200]},"
                          "{\"path\": \"integrator.rtol\", \"logspace\": [1e-4, 1e-12, 5]}]}",
                          100);
    cr_assert_str_eq(f->name, "gains");
    cr_assert_str_eq(f->paths, "[\"controller.kp\",\"integrator.rtol\"]");
    cr_assert_eq(f->naxes, 2);
    cr_assert_eq(f->nmembers, 10);
    const double kp[2] = {50, 200}, rtol[5] = {1e-4, 1e-6, 1e-8, 1e-10, 1e-12};
    for (long m = 0; m < 10; m++) {
        /* the last axis varies fastest; the decades are their powers of ten exactly */
        cr_assert_eq(f->members[m].index, m);
        cr_assert_eq(f->members[m].replica, 0);
        cr_assert_eq(value_of(f, m, 0), kp[m / 5], "member %ld", m);
        cr_assert_eq(value_of(f, m, 1), rtol[m % 5], "member %ld: %.17g", m, value_of(f, m, 1));
        /* the spec is what POST /api/jobs makes of the request with the two keys set */
        char request[512], name[256];
        snprintf(name, sizeof name,
                 "triple_pendulum_pd, duration = 0.05 [controller.kp=%g, integrator.rtol=%g]",
                 kp[m / 5], rtol[m % 5]);
        snprintf(request, sizeof request,
                 "{\"preset\": \"triple_pendulum_pd\", \"duration\": 0.05, \"controller\": "
                 "{\"kp\": %g}, \"integrator\": {\"rtol\": %g}, \"name\": \"%s\"}",
                 kp[m / 5], rtol[m % 5], name);
        char *want = normalised(request);
        cr_assert_str_eq(f->members[m].spec, want, "member %ld", m);
        cr_assert_str_eq(f->members[m].name, name);
        free(want);
        cr_assert_str_eq(f->members[m].preset, "triple_pendulum_pd");
        cr_assert_str_eq(f->members[m].controller, "pd");
        cr_assert(f->members[m].nbodies == 3 && f->members[m].nv == 3);
    }
    family_free(f);
}

Test(family, linspace_zip_and_an_array_path_into_a_preset)
{
    family *f = expand_ok("{\"base\": " BASE ", \"combine\": \"zip\", \"axes\": ["
                          "{\"path\": \"scene.bodies[1].mass\", \"linspace\": [0.5, 2, 4]},"
                          "{\"path\": \"controller.kv\", \"values\": [10, 20, 30, 40]}]}",
                          100);
    cr_assert_eq(f->nmembers, 4);
    for (long m = 0; m < 4; m++) {
        double mass = 0.5 + 1.5 * (double)m / 3;
        cr_assert_eq(value_of(f, m, 0), mass, "member %ld", m);
        cr_assert_eq(spec_number(f, m, "controller", "kv", NULL), 10.0 * (double)(m + 1));
        /* the array came from the preset's document: body 1 changed, bodies 0 and 2 as they
         * were */
        cJSON *doc = cJSON_Parse(f->members[m].spec);
        const cJSON *bodies = cJSON_GetObjectItemCaseSensitive(
            cJSON_GetObjectItemCaseSensitive(doc, "scene"), "bodies");
        cr_assert_eq(cJSON_GetArraySize(bodies), 3);
        for (int k = 0; k < 3; k++) {
            double got = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(bodies, k), "mass")
                             ->valuedouble;
            cr_assert_eq(got, k == 1 ? mass : 1.0, "member %ld body %d", m, k);
        }
        cJSON_Delete(doc);
    }
    family_free(f);
}

Test(family, the_same_document_gives_bitwise_the_same_members_and_another_seed_other_draws)
{
    const char *doc = "{\"base\": " BASE ", \"seed\": 42, \"replicas\": 3, \"axes\": ["
                      "{\"path\": \"controller.model.mass_scale\", \"random\": {\"dist\": "
                      "\"lognormal\", \"mu\": 0, \"sigma\": 0.1}, \"count\": 4}]}";
    family *a = expand_ok(doc, 100), *b = expand_ok(doc, 100);
    cr_assert_eq(a->nmembers, 12);
    cr_assert_eq(b->nmembers, 12);
    for (long m = 0; m < 12; m++) {
        cr_assert_str_eq(a->members[m].spec, b->members[m].spec, "member %ld", m);
        cr_assert_str_eq(a->members[m].values, b->members[m].values, "member %ld", m);
        cr_assert_eq(a->members[m].replica, m % 3);
        /* replica r of every combination has the same sensor seed, and it is the documented
         * one; the mass scale is the axis's draw */
        cr_assert_eq(spec_number(a, m, "controller", "seed", NULL),
                     (double)family_seed(42, (int)(m % 3)));
        cr_assert_eq(spec_number(a, m, "controller", "model", "mass_scale"), value_of(a, m, 0));
        cr_assert(value_of(a, m, 0) > 0);
    }
    cr_assert_neq(family_seed(42, 0), family_seed(42, 1));
    cr_assert(family_seed(42, 0) < FAMILY_SEED_LIMIT);
    family *c = expand_ok("{\"base\": " BASE ", \"seed\": 43, \"replicas\": 3, \"axes\": ["
                          "{\"path\": \"controller.model.mass_scale\", \"random\": {\"dist\": "
                          "\"lognormal\", \"mu\": 0, \"sigma\": 0.1}, \"count\": 4}]}",
                          100);
    for (long m = 0; m < 12; m++)
        cr_assert_neq(value_of(a, m, 0), value_of(c, m, 0), "member %ld drew the same", m);
    family_free(a);
    family_free(b);
    family_free(c);
}

Test(family, replicas_seed_the_models_random_errors)
{
    family *f = expand_ok("{\"base\": {\"preset\": \"triple_pendulum_pd\", \"duration\": 0.05, "
                          "\"controller\": {\"model\": {\"random\": {\"seed\": 0, \"mass\": "
                          "0.2}}}}, \"seed\": 7, \"replicas\": 4}",
                          100);
    cr_assert_eq(f->nmembers, 4);
    cr_assert_str_eq(f->paths, "[]");
    for (long m = 0; m < 4; m++) {
        cJSON *doc = cJSON_Parse(f->members[m].spec);
        const cJSON *seed = cJSON_GetObjectItemCaseSensitive(
            cJSON_GetObjectItemCaseSensitive(
                cJSON_GetObjectItemCaseSensitive(
                    cJSON_GetObjectItemCaseSensitive(doc, "controller"), "model"),
                "random"),
            "seed");
        cr_assert_eq(seed->valuedouble, (double)family_seed(7, (int)m), "%.17g vs %.17g",
                     seed->valuedouble, (double)family_seed(7, (int)m));
        cJSON_Delete(doc);
        char want[128];
        snprintf(want, sizeof want,
                 "triple_pendulum_pd, model.random = {...}, duration = 0.05 #%ld", m);
        cr_assert_str_eq(f->members[m].name, want);
    }
    family_free(f);
}

Test(family, uniform_and_normal_draws_follow_their_law)
{
    const char *dists[2] = {"{\"dist\": \"uniform\", \"low\": 2, \"high\": 5}",
                            "{\"dist\": \"normal\", \"mean\": 1, \"std\": 0.5}"};
    /* uniform(2, 5): mean 3.5, sd 3/sqrt(12); normal(1, 0.5) */
    const double mean[2] = {3.5, 1}, sd[2] = {3 / sqrt(12), 0.5};
    for (int d = 0; d < 2; d++) {
        char doc[512];
        snprintf(doc, sizeof doc,
                 "{\"base\": {\"preset\": \"triple_pendulum_passive\", \"duration\": 0.01}, "
                 "\"seed\": 1, \"axes\": [{\"path\": \"scene.gravity[1]\", \"random\": %s, "
                 "\"count\": 4000}]}",
                 dists[d]);
        family *f = expand_ok(doc, 4000);
        double sum = 0, sum2 = 0;
        for (long m = 0; m < f->nmembers; m++) {
            double x = value_of(f, m, 0);
            if (d == 0) cr_assert(x >= 2 && x <= 5, "draw %g out of [2, 5]", x);
            sum += x;
            sum2 += x * x;
        }
        double n = (double)f->nmembers, mu = sum / n, var = sum2 / n - mu * mu;
        cr_assert(fabs(mu - mean[d]) < 5 * sd[d] / sqrt(n), "%s: mean %g", dists[d], mu);
        cr_assert(fabs(sqrt(var) - sd[d]) < 0.05 * sd[d], "%s: sd %g", dists[d], sqrt(var));
        family_free(f);
    }
}

Test(family, a_bad_member_names_the_axis_the_value_and_the_jobs_error)
{
    expand_fails(
        "{\"base\": " BASE ", \"axes\": [{\"path\": \"integrator.rtol\", "
        "\"values\": [1e-6, -1]}]}",
        100, 400, "INVALID_FIELD", "axes[0]",
        "axis integrator.rtol = -1 (member 1): integrator: rtol must be in (0, 1) (got -1)");
    expand_fails("{\"base\": " BASE ", \"axes\": [{\"path\": \"controller.kp\", \"values\": "
                 "[1, 2]}, {\"path\": \"controller.gain\", \"values\": [3]}]}",
                 100, 400, "UNKNOWN_FIELD", "axes",
                 "axis controller.kp = 1, axis controller.gain = 3 (member 0): controller.gain: "
                 "unknown key \"gain\"");
    expand_fails("{\"base\": " BASE ", \"axes\": [{\"path\": \"scene.bodies[7].mass\", "
                 "\"values\": [1]}]}",
                 100, 400, "INVALID_FIELD", "axes[0]",
                 "axis scene.bodies[7].mass = 1 (member 0): the path indexes past the end of an "
                 "array of the job");
}

Test(family, the_document_and_the_limit_are_checked_before_any_member)
{
    expand_fails("{\"base\": " BASE ", \"axes\": [{\"path\": \"controller.kp\", \"linspace\": "
                 "[1, 2, 101]}]}",
                 100, 400, "INVALID_FIELD", "axes[0].linspace[2]",
                 "must be a whole number from 1 to 100 (got 101)");
    expand_fails("{\"base\": " BASE ", \"replicas\": 11, \"axes\": [{\"path\": \"controller.kp\", "
                 "\"linspace\": [1, 2, 10]}]}",
                 100, 413, "FAMILY_TOO_LARGE", "axes",
                 "the family has 110 members, more than this server takes (--max-family 100)");
    expand_fails("{\"base\": " BASE ", \"axes\": [{\"path\": \"controller.kp\", \"linspace\": "
                 "[1, 2, 100]}, {\"path\": \"controller.kv\", \"linspace\": [1, 2, 100]}, "
                 "{\"path\": \"duration\", \"linspace\": [1, 2, 100]}]}",
                 100, 413, "FAMILY_TOO_LARGE", "axes",
                 "the family has 1000000 members, more than this server takes (--max-family "
                 "100)");
    expand_fails("{\"base\": " BASE ", \"axis\": []}", 100, 400, "UNKNOWN_FIELD", "axis",
                 "unknown key (the keys are: name, base, axes, combine, replicas, seed)");
    expand_fails("{\"axes\": []}", 100, 400, "MISSING_FIELD", "base",
                 "is required: a job, or {\"preset\": NAME, ...} with overrides");
    expand_fails("{\"base\": {\"preset\": \"triple_pendulum_pd\", \"controller\": {\"kp\": -1}}}",
                 100, 400, "INVALID_FIELD", "base.controller",
                 "kp must be positive and finite (got -1)");
    expand_fails("{\"base\": " BASE ", \"axes\": [{\"path\": \"a..b\", \"values\": [1]}]}", 100,
                 400, "INVALID_FIELD", "axes[0].path", "the path \"a..b\" has an empty key");
    expand_fails("{\"base\": " BASE ", \"axes\": [{\"path\": \"n\", \"values\": [1]}, "
                 "{\"path\": \"n\", \"values\": [2]}]}",
                 100, 400, "INVALID_FIELD", "axes[1].path", "axes[0] sets \"n\" already");
    expand_fails("{\"base\": " BASE ", \"combine\": \"zip\", \"axes\": [{\"path\": \"a\", "
                 "\"values\": [1, 2]}, {\"path\": \"b\", \"values\": [1]}]}",
                 100, 400, "INVALID_FIELD", "axes[1]",
                 "zipped axes must have the same number of values (axes[0] has 2, this one 1)");
    expand_fails("{\"base\": " BASE ", \"axes\": [{\"path\": \"a\", \"logspace\": [0, 1, 3]}]}",
                 100, 400, "INVALID_FIELD", "axes[0].logspace[0]",
                 "must be > 0 on a logarithmic axis (got 0)");
    expand_fails("{\"base\": " BASE ", \"axes\": [{\"path\": \"a\", \"random\": {\"dist\": "
                 "\"normal\", \"mean\": 0, \"std\": 1}}]}",
                 100, 400, "MISSING_FIELD", "axes[0].count", "is required with \"random\"");
    expand_fails("{\"base\": " BASE ", \"axes\": [{\"path\": \"a\", \"values\": [1], "
                 "\"linspace\": [1, 2, 2]}]}",
                 100, 400, "INVALID_FIELD", "axes[0]",
                 "an axis needs exactly one of \"values\", \"linspace\", \"logspace\" and "
                 "\"random\" (got 2)");
    expand_fails("{\"base\": " BASE ", \"seed\": 1, \"seed\": 2}", 100, 400, "INVALID_FIELD",
                 "seed", "key \"seed\" appears more than once");
    expand_fails("{\"base\": 01}", 100, 400, "INVALID_JSON", "",
                 "invalid JSON at byte 9: a number must not have a leading zero");
}

Test(family, preset_parameters_are_axes_too)
{
    family *f = expand_ok("{\"base\": {\"preset\": \"n_link_pendulum\", \"duration\": 0.01}, "
                          "\"axes\": [{\"path\": \"n\", \"values\": [2, 16, 64]}]}",
                          100);
    cr_assert_eq(f->nmembers, 3);
    cr_assert(f->members[0].nbodies == 2 && f->members[1].nbodies == 16 &&
              f->members[2].nbodies == 64);
    family_free(f);
}

Test(family, the_table_reduces_the_metrics_over_the_coordinates)
{
    cJSON *paths = cJSON_Parse("[\"controller.kp\", \"integrator.method\"]");
    cJSON *v0 = cJSON_Parse("[50, \"rk4\"]"), *v1 = cJSON_Parse("[100, \"a,b\"]");
    cJSON *m0 = cJSON_Parse("{\"e_final\": [0.5, -2, 1], \"e_rms\": [0.25, 0.125, 3], "
                            "\"e_max\": [1, 2, 4], \"tau_peak\": [-10, 3, 5], "
                            "\"energy_drift\": null, \"us_per_eval\": 1.5, \"steps\": 40, "
                            "\"wall_s\": 0.01}");
    family_row rows[2] = {
        {.job = 7, .index = 0, .replica = 0, .status = "done", .values = v0, .metrics = m0},
        {.job = 8, .index = 1, .replica = 1, .status = "queued", .values = v1},
    };
    char *text = NULL;
    size_t len = 0;
    FILE *f = open_memstream(&text, &len);
    cr_assert_eq(family_write_csv(f, paths, rows, 2), 0);
    fclose(f);
    cr_assert_str_eq(text, "member,replica,controller.kp,integrator.method,status,e_final,e_rms,"
                           "e_max,tau_peak,energy_drift,us_per_eval,steps,wall_s\n"
                           "0,0,50,rk4,done,2,3,4,10,,1.5,40,0.01\n"
                           "1,1,100,\"a,b\",queued,,,,,,,,\n");
    free(text);
    cJSON *t = family_table_json(paths, rows, 2);
    char *json = cJSON_PrintUnformatted(t);
    cr_assert_str_eq(
        json, "{\"columns\":[\"member\",\"replica\",\"controller.kp\",\"integrator.method\","
              "\"status\",\"e_final\",\"e_rms\",\"e_max\",\"tau_peak\",\"energy_drift\","
              "\"us_per_eval\",\"steps\",\"wall_s\"],\"rows\":[{\"member\":0,\"replica\":0,"
              "\"job\":7,\"values\":[50,\"rk4\"],\"status\":\"done\",\"message\":null,"
              "\"e_final\":2,\"e_rms\":3,\"e_max\":4,\"tau_peak\":10,\"energy_drift\":null,"
              "\"us_per_eval\":1.5,\"steps\":40,\"wall_s\":0.01},{\"member\":1,\"replica\":1,"
              "\"job\":8,\"values\":[100,\"a,b\"],\"status\":\"queued\",\"message\":null,"
              "\"e_final\":null,\"e_rms\":null,\"e_max\":null,\"tau_peak\":null,"
              "\"energy_drift\":null,\"us_per_eval\":null,\"steps\":null,\"wall_s\":null}]}");
    cJSON_free(json);
    cJSON_Delete(t);
    cJSON_Delete(paths);
    cJSON_Delete(v0);
    cJSON_Delete(v1);
    cJSON_Delete(m0);
}

Test(family, a_members_name_is_cut_to_the_jobs_limit_between_letters)
{
    /* a base name of 100 two-byte letters (200 bytes, the limit) keeps every letter and loses
       the axis suffix; one of 199 ASCII bytes keeps the suffix's first byte */
    char doc[1024], name[256] = "";
    for (int i = 0; i < 100; i++) strcat(name, "\xc3\xa9");
    snprintf(doc, sizeof doc,
             "{\"base\": {\"preset\": \"triple_pendulum_pd\", \"duration\": 0.01, \"name\": "
             "\"%s\"}, \"axes\": [{\"path\": \"controller.kp\", \"values\": [50]}]}",
             name);
    family *f = expand_ok(doc, 10);
    cr_assert_str_eq(f->members[0].name, name);
    family_free(f);
    memset(name, 'a', 199);
    name[199] = '\0';
    snprintf(doc, sizeof doc,
             "{\"base\": {\"preset\": \"triple_pendulum_pd\", \"duration\": 0.01, \"name\": "
             "\"%s\"}, \"axes\": [{\"path\": \"controller.kp\", \"values\": [50]}]}",
             name);
    f = expand_ok(doc, 10);
    cr_assert_eq(strlen(f->members[0].name), 200);
    cr_assert_eq(f->members[0].name[199], ' ');
    family_free(f);
}
