/*
 * job_model.c - the job format's "controller.model" beyond the two global scales (job_json.h):
 * the controller's model of each body, its gravity, a payload the plant carries and the model
 * does not, and seeded random draws of the model's errors for Monte-Carlo studies (sim.h
 * model_bodies, model_gravity).
 *
 * The model's bodies start as the scene's (the plant's without the payload) and are changed in
 * this order: the random draws, then each "bodies" entry, then the global scales (applied by the
 * library, sim.c). The random draws, body by body in scene order, take five uniforms u in [0, 1)
 * from splitmix64 seeded with "seed" (plant.h ctc_plant_uniform), whether or not a range is 0:
 *     mass    *= 1 + mass_range (2u - 1)
 *     com[i]  += com_range (2u - 1),       i = x, y, z (m, the body's frame)
 *     inertia *= 1 + inertia_range (2u - 1)
 * so the same seed gives the same model bit for bit, and the ranges < 1 keep masses and
 * inertias positive. A "bodies" entry names its body by index and gives "mass" or "mass_scale",
 * "com", and "inertia" (as the scene's: 3x3 rows or principal moments) or "inertia_scale".
 * The payload, a point mass at a point in the body's frame, is merged into the plant's body
 * (centre of mass and inertia about it by the parallel-axis theorem): the plant carries it and
 * the controller's model does not. Every term is off by default: without them the model's
 * bodies stay NULL and the plant's are used, so existing jobs run as before.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_parse.h"
#include "plant.h"

static const char *const body_keys[] = {"body",    "mass",          "mass_scale", "com",
                                        "inertia", "inertia_scale", NULL};
static const char *const payload_keys[] = {"body", "mass", "point", NULL};
static const char *const random_keys[] = {"seed", "mass", "com", "inertia", NULL};

/* obj["body"] (at path), a body index 0 .. nbodies - 1, into *k; written to out */
static int body_index(parser *p, const cJSON *obj, const char *path, int *k, cJSON *out)
{
    char at[PATH_LEN];
    double x;
    const int n = p->j->spec.chain.nbodies;
    if (json_member_number(p, obj, path, "body", REQUIRED, 0, &x) != 0) return -1;
    if (!(x >= 0 && x < n && x == floor(x))) {
        return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "body"),
                             "must be a body index, a whole number from 0 to %d (got %g)", n - 1,
                             x);
    }
    *k = (int)x;
    json_put_number(p, out, "body", x);
    return 0;
}

/* obj[key] (at path), if given, a number > 0 (positive) or >= 0, into *x; written to out */
static int model_number(parser *p, const cJSON *obj, const char *path, const char *key,
                        int positive, double *x, int *given, cJSON *out)
{
    char at[PATH_LEN];
    *given = json_member(obj, key) != NULL;
    if (!*given) return 0;
    if (json_member_number(p, obj, path, key, REQUIRED, 0, x) != 0) return -1;
    json_key_path(at, path, key);
    if (positive && !(*x > 0))
        return json_error_at(p->err, JOB_INVALID_FIELD, at, "must be positive (got %g)", *x);
    if (!positive && !(*x >= 0))
        return json_error_at(p->err, JOB_INVALID_FIELD, at, "must not be negative (got %g)", *x);
    json_put_number(p, out, key, *x);
    return 0;
}

/* keys a and b of obj (at path) exclude each other */
static int either(parser *p, const cJSON *obj, const char *path, const char *a, const char *b)
{
    char at[PATH_LEN];
    if (json_member(obj, a) == NULL || json_member(obj, b) == NULL) return 0;
    return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, b),
                         "give either \"%s\" or \"%s\", not both", a, b);
}

/* "random": the seeded draws above, into the model's bodies b */
static int parse_random(parser *p, const cJSON *v, ctc_body_spec *b, cJSON *out_model)
{
    const char *path = "controller.model.random";
    char at[PATH_LEN];
    double seed, range[3] = {0, 0, 0};
    static const char *const names[3] = {"mass", "com", "inertia"};
    cJSON *out = json_put(p, out_model, "random", cJSON_CreateObject());
    if (json_object_at(p, v, path) != 0 ||
        json_check_keys(p, v, path, random_keys, NULL, NULL) != 0 ||
        json_member_number(p, v, path, "seed", REQUIRED, 0, &seed) != 0) {
        return -1;
    }
    if (!(seed >= 0 && seed <= 9007199254740992.0 && seed == floor(seed))) {
        return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "seed"),
                             "must be a whole number from 0 to 2^53 (got %g)", seed);
    }
    json_put_number(p, out, "seed", seed);
    for (int i = 0; i < 3; i++) {
        int given;
        if (model_number(p, v, path, names[i], 0, &range[i], &given, out) != 0) return -1;
        if (i != 1 && !(range[i] < 1)) {
            return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, names[i]),
                                 "must be less than 1, a relative range (got %g)", range[i]);
        }
    }
    unsigned long long rng = (unsigned long long)seed;
    for (int k = 0; k < p->j->spec.chain.nbodies; k++) {
        b[k].mass *= 1 + range[0] * (2 * ctc_plant_uniform(&rng) - 1);
        for (int i = 0; i < 3; i++) b[k].com[i] += range[1] * (2 * ctc_plant_uniform(&rng) - 1);
        double s = 1 + range[2] * (2 * ctc_plant_uniform(&rng) - 1);
        for (int i = 0; i < 9; i++) b[k].inertia[i] *= s;
    }
    return 0;
}

/* one "bodies" entry (at path) applied to the model's bodies b */
static int parse_model_body(parser *p, const cJSON *v, const char *path, ctc_body_spec *b,
                            cJSON *out)
{
    char at[PATH_LEN];
    int k, given;
    double x;
    if (json_object_at(p, v, path) != 0 ||
        json_check_keys(p, v, path, body_keys, NULL, NULL) != 0 ||
        body_index(p, v, path, &k, out) != 0 || either(p, v, path, "mass", "mass_scale") != 0 ||
        either(p, v, path, "inertia", "inertia_scale") != 0) {
        return -1;
    }
    if (model_number(p, v, path, "mass", 0, &x, &given, out) != 0) return -1;
    if (given) b[k].mass = x;
    if (model_number(p, v, path, "mass_scale", 1, &x, &given, out) != 0) return -1;
    if (given) b[k].mass *= x;
    if (json_member(v, "com") != NULL) {
        if (json_vec3_at(p, json_member(v, "com"), json_key_path(at, path, "com"), b[k].com) != 0)
            return -1;
        json_put_numbers(p, out, "com", b[k].com, 3);
    }
    const cJSON *in = json_member(v, "inertia");
    if (in != NULL) {
        int diagonal;
        json_key_path(at, path, "inertia");
        if (json_matrix3_at(p, in, at, "principal moments", b[k].inertia, &diagonal) != 0)
            return -1;
        for (int i = 0; i < 3; i++) {
            char ati[PATH_LEN];
            if (b[k].inertia[4 * i] < 0) {
                return json_error_at(p->err, JOB_INVALID_FIELD,
                                     diagonal ? json_index_path(ati, at, i) : at,
                                     "must not be negative (got %g kg m^2)", b[k].inertia[4 * i]);
            }
        }
        json_put_matrix3(p, out, "inertia", b[k].inertia, diagonal);
    }
    if (model_number(p, v, path, "inertia_scale", 1, &x, &given, out) != 0) return -1;
    for (int i = 0; given && i < 9; i++) b[k].inertia[i] *= x;
    return 0;
}

/* "payload": a point mass merged into the plant's body (parallel-axis theorem) */
static int parse_payload(parser *p, const cJSON *v, cJSON *out_model)
{
    const char *path = "controller.model.payload";
    int k, given;
    double mp, r[3];
    cJSON *out = json_put(p, out_model, "payload", cJSON_CreateObject());
    if (json_object_at(p, v, path) != 0 ||
        json_check_keys(p, v, path, payload_keys, NULL, NULL) != 0 ||
        body_index(p, v, path, &k, out) != 0 ||
        json_required_member(p, v, path, "mass", "") == NULL ||
        model_number(p, v, path, "mass", 1, &mp, &given, out) != 0 ||
        json_member_vec3(p, v, path, "point", REQUIRED, NULL, r) != 0) {
        return -1;
    }
    json_put_numbers(p, out, "point", r, 3);
    ctc_body_spec *b = &p->j->bodies[k];
    const double mb = b->mass, m = mb + mp;
    double c[3], db[3], dp[3];
    for (int i = 0; i < 3; i++) {
        c[i] = (mb * b->com[i] + mp * r[i]) / m;
        db[i] = b->com[i] - c[i];
        dp[i] = r[i] - c[i];
    }
    const double nb = db[0] * db[0] + db[1] * db[1] + db[2] * db[2];
    const double np = dp[0] * dp[0] + dp[1] * dp[1] + dp[2] * dp[2];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            b->inertia[3 * i + j] +=
                mb * ((i == j) * nb - db[i] * db[j]) + mp * ((i == j) * np - dp[i] * dp[j]);
        }
    }
    memcpy(b->com, c, sizeof c);
    b->mass = m;
    return 0;
}

int parse_model_bodies(parser *p, const cJSON *model, cJSON *out_model)
{
    job *j = p->j;
    const int n = j->spec.chain.nbodies;
    const cJSON *bodies = json_member(model, "bodies"), *random = json_member(model, "random");
    const cJSON *payload = json_member(model, "payload"), *gravity = json_member(model, "gravity");
    if (gravity != NULL) {
        if (json_vec3_at(p, gravity, "controller.model.gravity", j->model_gravity) != 0) return -1;
        json_put_numbers(p, out_model, "gravity", j->model_gravity, 3);
        j->spec.model_gravity = j->model_gravity;
    }
    if (bodies == NULL && random == NULL && payload == NULL) return 0;
    j->model_bodies = json_alloc(p, (size_t)n, sizeof *j->model_bodies);
    if (j->model_bodies == NULL) return -1;
    memcpy(j->model_bodies, j->bodies, (size_t)n * sizeof *j->bodies);
    j->spec.model_bodies = j->model_bodies;
    if (random != NULL && parse_random(p, random, j->model_bodies, out_model) != 0) return -1;
    if (bodies != NULL) {
        char at[PATH_LEN];
        if (!cJSON_IsArray(bodies)) {
            char kind[32];
            return json_error_at(p->err, JOB_INVALID_FIELD, "controller.model.bodies",
                                 "must be an array of objects (got %s)",
                                 json_describe(kind, bodies));
        }
        cJSON *out = json_put(p, out_model, "bodies", cJSON_CreateArray());
        int i = 0;
        for (const cJSON *e = bodies->child; e != NULL; e = e->next, i++) {
            json_index_path(at, "controller.model.bodies", i);
            cJSON *oe = json_put(p, out, NULL, cJSON_CreateObject());
            if (parse_model_body(p, e, at, j->model_bodies, oe) != 0) return -1;
        }
    }
    if (payload != NULL && parse_payload(p, payload, out_model) != 0) return -1;
    return 0;
}

const job_format_object job_model_objects[] = {
    FORMAT_KEYS("controller.model.bodies[]", NULL, NULL, body_keys),
    FORMAT_KEYS("controller.model.payload", NULL, NULL, payload_keys),
    FORMAT_KEYS("controller.model.random", NULL, NULL, random_keys),
    FORMAT_END,
};
