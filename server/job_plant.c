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

const job_format_object job_plant_objects[] = {
    FORMAT_KEYS("plant", NULL, NULL, plant_keys),
    FORMAT_END,
};

const job_format_default job_plant_defaults[] = {
    DEFAULT_JSON("", NULL, "plant", "{}"),
    DEFAULT_END,
};
