/*
 * job_plant.c - the job format's "plant" (job_json.h): what each controlled coordinate of the
 * plant has beyond the rigid-body dynamics (plant.h), one object for every coordinate or an
 * array of nind of them, like the trajectory and the disturbance.
 *
 * Every term is off unless the job gives it, and no key has a default to write out: a job
 * without "plant" (normalised to "plant": {}) runs the paper's ideal plant and spec.plant stays
 * NULL. Each value is checked at its path: a limit and coulomb_velocity > 0, the friction levels,
 * the spring and the armature >= 0 (the armature in an open chain); a torque limit needs a
 * controller (it clips the controller's force); coulomb needs its coulomb_velocity, and
 * coulomb_velocity and spring_rest their term. "known" says the controller's model has the joint
 * forces and the armature (it compensates them; plant.h). The sensors' noise_q, noise_v and
 * resolution (>= 0) need a sampled controller, which reads them.
 *
 * "wrenches" (wrench.h), an array of external wrenches on the plant's bodies, default []: each
 * names its "body" by index and gives its "point" in the body's frame, "force" and "torque"
 * (default zero), their "frame" ("world", default, or "body"), its "profile" ("constant",
 * default; "sine" with "period" > 0 and "phase", default 0; "step" with "time" >= 0) and
 * "known" (default false: the controller does not compensate it). Open chains and trees only;
 * "known" needs a controller. Every key is written out.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_parse.h"

static const char *const plant_keys[] = {
    "torque_limit", "viscous", "coulomb", "coulomb_velocity", "spring",     "spring_rest",
    "armature",     "known",   "noise_q", "noise_v",          "resolution", NULL};

/* the number obj[key] (at path), if given, into *x, checked: min 1 means > 0, 0 means >= 0,
   -1 any finite number; written to out */
static int plant_number(parser *p, const cJSON *obj, const char *path, const char *key, int min,
                        double *x, int *given, cJSON *out)
{
    char at[PATH_LEN];
    *given = json_member(obj, key) != NULL;
    if (!*given) return 0;
    if (json_member_number(p, obj, path, key, REQUIRED, 0, x) != 0) return -1;
    json_key_path(at, path, key);
    if (min == 1 && !(*x > 0))
        return json_error_at(p->err, JOB_INVALID_FIELD, at, "must be positive (got %g)", *x);
    if (min == 0 && !(*x >= 0))
        return json_error_at(p->err, JOB_INVALID_FIELD, at, "must be non-negative (got %g)", *x);
    json_put_number(p, out, key, *x);
    return 0;
}

/* one plant object (at path) for coordinates first .. first + count - 1 */
static int parse_plant_item(parser *p, const cJSON *v, const char *path, int first, int count,
                            cJSON *out)
{
    char at[PATH_LEN];
    ctc_plant_coord pc = {0};
    int given[10];
    if (json_object_at(p, v, path) != 0 ||
        json_check_keys(p, v, path, plant_keys, NULL, NULL) != 0 ||
        plant_number(p, v, path, "torque_limit", 1, &pc.torque_limit, &given[0], out) != 0 ||
        plant_number(p, v, path, "viscous", 0, &pc.viscous, &given[1], out) != 0 ||
        plant_number(p, v, path, "coulomb", 0, &pc.coulomb, &given[2], out) != 0 ||
        plant_number(p, v, path, "coulomb_velocity", 1, &pc.coulomb_velocity, &given[3], out) !=
            0 ||
        plant_number(p, v, path, "spring", 0, &pc.spring, &given[4], out) != 0 ||
        plant_number(p, v, path, "spring_rest", -1, &pc.spring_rest, &given[5], out) != 0 ||
        plant_number(p, v, path, "noise_q", 0, &pc.noise_q, &given[6], out) != 0 ||
        plant_number(p, v, path, "noise_v", 0, &pc.noise_v, &given[7], out) != 0 ||
        plant_number(p, v, path, "resolution", 0, &pc.resolution, &given[8], out) != 0 ||
        plant_number(p, v, path, "armature", 0, &pc.armature, &given[9], out) != 0) {
        return -1;
    }
    static const char *const sensor_keys[3] = {"noise_q", "noise_v", "resolution"};
    for (int k = 0; k < 3; k++) {
        if (!given[6 + k]) continue;
        if (!(p->j->spec.sample_period > 0)) {
            return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, sensor_keys[k]),
                                 "needs a sampled controller (\"controller.sample_period\"): the "
                                 "sensors are read at its instants");
        }
        if (p->j->spec.chain.loop != NULL) {
            return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, sensor_keys[k]),
                                 "needs an open chain");
        }
    }
    if (given[9] && p->j->spec.chain.loop != NULL) {
        return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "armature"),
                             "needs an open chain");
    }
    if (given[0] && p->ctrl == CTC_CTRL_NONE) {
        return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "torque_limit"),
                             "needs a controller: it clips the controller's force (this run is "
                             "passive)");
    }
    if (given[2] && !given[3]) {
        return json_error_at(p->err, JOB_MISSING_FIELD, json_key_path(at, path, "coulomb_velocity"),
                             "is required with \"coulomb\" (the regularisation's speed scale, "
                             "rad/s or m/s: smaller is more accurate and stiffer)");
    }
    if (given[3] && !given[2]) {
        return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "coulomb_velocity"),
                             "applies only with \"coulomb\"");
    }
    if (given[5] && !given[4]) {
        return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "spring_rest"),
                             "applies only with \"spring\"");
    }
    const cJSON *known = json_member(v, "known");
    if (known != NULL) {
        if (json_bool_at(p, known, json_key_path(at, path, "known"), &pc.known) != 0) return -1;
        json_put(p, out, "known", cJSON_CreateBool(pc.known));
    }
    for (int i = first; i < first + count; i++) p->j->plant[i] = pc;
    return 0;
}

int parse_plant(parser *p, const cJSON *doc)
{
    job *j = p->j;
    const cJSON *v = json_member(doc, "plant");
    if (v == NULL) {
        json_put(p, p->norm, "plant", cJSON_CreateObject());
        return 0;
    }
    j->plant = json_alloc(p, (size_t)j->nind, sizeof *j->plant);
    if (j->plant == NULL || parse_per_coordinate(p, v, "plant", parse_plant_item) != 0) return -1;
    for (int i = 0; i < j->nind; i++) {
        if (j->plant[i].torque_limit > 0 || j->plant[i].armature > 0 ||
            ctc_plant_has_joint_force(&j->plant[i]) || ctc_plant_has_sensor_error(&j->plant[i])) {
            j->spec.plant = j->plant;
            return 0;
        }
    }
    free(j->plant); /* the ideal plant everywhere: the paper's run, spec.plant NULL */
    j->plant = NULL;
    return 0;
}

static const char *const wrench_keys[] = {"body",   "point", "force", "torque", "frame", "profile",
                                          "period", "phase", "time",  "known",  NULL};

/* wrenches[i] (at path) into *w; written to out */
static int parse_wrench(parser *p, const cJSON *v, const char *path, ctc_wrench *w, cJSON *out)
{
    static const double zero[3] = {0, 0, 0};
    static const char *const frames[] = {"world", "body"};
    static const char *const profiles[] = {"constant", "sine", "step"};
    char at[PATH_LEN];
    double body;
    int frame = CTC_WRENCH_WORLD, profile = CTC_WRENCH_CONSTANT;
    const int n = p->j->spec.chain.nbodies;
    if (json_object_at(p, v, path) != 0 ||
        json_check_keys(p, v, path, wrench_keys, NULL, NULL) != 0 ||
        json_member_number(p, v, path, "body", REQUIRED, 0, &body) != 0)
        return -1;
    if (!(body >= 0 && body < n && body == floor(body))) {
        return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "body"),
                             "must be a body index, a whole number from 0 to %d (got %g)", n - 1,
                             body);
    }
    w->body = (int)body;
    if (json_member_vec3(p, v, path, "point", OPTIONAL, zero, w->point) != 0 ||
        json_member_vec3(p, v, path, "force", OPTIONAL, zero, w->force) != 0 ||
        json_member_vec3(p, v, path, "torque", OPTIONAL, zero, w->torque) != 0)
        return -1;
    const cJSON *x = json_member(v, "frame");
    if (x != NULL && json_enum_at(p, x, json_key_path(at, path, "frame"), frames, 2, &frame) != 0)
        return -1;
    x = json_member(v, "profile");
    if (x != NULL &&
        json_enum_at(p, x, json_key_path(at, path, "profile"), profiles, 3, &profile) != 0)
        return -1;
    w->frame = (ctc_wrench_frame)frame;
    w->profile = (ctc_wrench_profile)profile;
    json_put_number(p, out, "body", body);
    json_put_numbers(p, out, "point", w->point, 3);
    json_put_numbers(p, out, "force", w->force, 3);
    json_put_numbers(p, out, "torque", w->torque, 3);
    json_put(p, out, "frame", cJSON_CreateString(frames[frame]));
    json_put(p, out, "profile", cJSON_CreateString(profiles[profile]));
    /* the profile's own keys: required, defaulted, or not allowed */
    static const char *const own[3] = {"period", "phase", "time"};
    const int allowed[3][3] = {{0, 0, 0}, {1, 1, 0}, {0, 0, 1}};
    for (int k = 0; k < 3; k++) {
        if (json_member(v, own[k]) != NULL && !allowed[profile][k]) {
            return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, own[k]),
                                 "applies only to the profile \"%s\"", k == 2 ? "step" : "sine");
        }
    }
    if (profile == CTC_WRENCH_SINE) {
        if (json_member_number(p, v, path, "period", REQUIRED, 0, &w->period) != 0 ||
            json_member_number(p, v, path, "phase", OPTIONAL, 0, &w->phase) != 0)
            return -1;
        if (!(w->period > 0)) {
            return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "period"),
                                 "must be positive (got %g s)", w->period);
        }
        json_put_number(p, out, "period", w->period);
        json_put_number(p, out, "phase", w->phase);
    }
    if (profile == CTC_WRENCH_STEP) {
        if (json_member_number(p, v, path, "time", REQUIRED, 0, &w->time) != 0) return -1;
        if (!(w->time >= 0)) {
            return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "time"),
                                 "must be non-negative (got %g s)", w->time);
        }
        json_put_number(p, out, "time", w->time);
    }
    x = json_member(v, "known");
    if (x != NULL && json_bool_at(p, x, json_key_path(at, path, "known"), &w->known) != 0)
        return -1;
    if (w->known && p->ctrl == CTC_CTRL_NONE) {
        return json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "known"),
                             "needs a controller: the controller compensates a known wrench (this "
                             "run is passive)");
    }
    json_put(p, out, "known", cJSON_CreateBool(w->known));
    return 0;
}

int parse_wrenches(parser *p, const cJSON *doc)
{
    job *j = p->j;
    const cJSON *v = json_member(doc, "wrenches");
    cJSON *out = json_put(p, p->norm, "wrenches", cJSON_CreateArray());
    if (v == NULL) return 0;
    if (!cJSON_IsArray(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "wrenches",
                             "must be an array of wrench objects (got %s)", json_kind(v));
    }
    const int count = cJSON_GetArraySize(v);
    if (count == 0) return 0;
    if (count > JOB_MAX_WRENCHES) {
        return json_error_at(p->err, JOB_LIMIT_EXCEEDED, "wrenches",
                             "has %d wrenches; the limit is %d", count, JOB_MAX_WRENCHES);
    }
    if (j->spec.chain.loop != NULL) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "wrenches",
                             "needs an open chain or tree (the scene has a loop)");
    }
    j->wrenches = json_alloc(p, (size_t)count, sizeof *j->wrenches);
    if (j->wrenches == NULL) return -1;
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        char at[PATH_LEN];
        cJSON *o = cJSON_CreateObject();
        if (out != NULL && o != NULL) cJSON_AddItemToArray(out, o);
        if (parse_wrench(p, e, json_index_path(at, "wrenches", i), &j->wrenches[i], o) != 0)
            return -1;
    }
    j->spec.wrenches = j->wrenches;
    j->spec.nwrenches = count;
    return 0;
}

const job_format_object job_plant_objects[] = {
    FORMAT_KEYS("plant", NULL, NULL, plant_keys),
    FORMAT_KEYS("wrenches[]", NULL, NULL, wrench_keys),
    FORMAT_END,
};

const job_format_default job_plant_defaults[] = {
    DEFAULT_JSON("", NULL, "plant", "{}"),
    DEFAULT_JSON("", NULL, "wrenches", "[]"),
    DEFAULT_END,
};
