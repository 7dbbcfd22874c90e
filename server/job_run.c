/*
 * job_run.c - the job format's run settings (job_json.h): the trajectory and the disturbance
 * (one object for every controlled coordinate, or one each), the integrator, the duration, the
 * output (interval and channels), the limits and the thread count.
 *
 * They are read after the scene and the controller, whose results they depend on: the number of
 * controlled coordinates (nind), whether the run is passive (no trajectory, no tracking
 * channels), whether there is a loop (the loop channel). The library checks a trajectory's,
 * disturbance's and integrator's parameters (ctc_traj_check, ctc_disturb_check,
 * ctc_integ_check); its message is reported at the object's path. The output's size is bounded
 * before the run: at most JOB_MAX_SAMPLES samples and JOB_MAX_VALUES values.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_parse.h"

#define MAX_WHOLE 9007199254740992.0 /* 2^53: whole numbers beyond are not exact in a double */

/* ---- trajectory and disturbance: one object for every coordinate, or one per coordinate ---- */

/* v (the document's key): one object for every coordinate, or an array of nind of them */
int parse_per_coordinate(parser *p, const cJSON *v, const char *key, coord_item_parser item)
{
    int nind = p->j->nind;
    if (cJSON_IsObject(v)) {
        return item(p, v, key, 0, nind, json_put(p, p->norm, key, cJSON_CreateObject()));
    }
    if (!cJSON_IsArray(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, key,
                             "must be an object or an array of %d objects, one per %s (got %s)",
                             nind, coordinate_word(p), json_kind(v));
    }
    int len = cJSON_GetArraySize(v);
    if (len != nind) {
        return json_error_at(p->err, JOB_INVALID_FIELD, key,
                             "must have %d entries, one per %s (got %d)", nind, coordinate_word(p),
                             len);
    }
    cJSON *out = json_put(p, p->norm, key, cJSON_CreateArray());
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        char path[PATH_LEN];
        if (item(p, e, json_index_path(path, key, i), i, 1,
                 json_put(p, out, NULL, cJSON_CreateObject()))) {
            return -1;
        }
    }
    return 0;
}

static const char *const traj_names[] = {"constant",   "sine",     "cosine",
                                         "polynomial", "min_jerk", "spline"};
static const char *const traj_keys_all[] = {
    "type",  "value", "amplitude", "period", "phase",    "offset", "coefficients", "from", "to",
    "start", "end",   "times",     "values", "boundary", NULL};
static const char *const traj_keys_constant[] = {"type", "value", NULL};
static const char *const traj_keys_periodic[] = {"type",  "amplitude", "period",
                                                 "phase", "offset",    NULL};
static const char *const traj_keys_polynomial[] = {"type", "coefficients", NULL};
static const char *const traj_keys_min_jerk[] = {"type", "from", "to", "start", "end", NULL};
static const char *const traj_keys_spline[] = {"type", "times", "values", "boundary", NULL};
static const char *const *const traj_keys[] = {
    [CTC_TRAJ_CONSTANT] = traj_keys_constant, [CTC_TRAJ_SINE] = traj_keys_periodic,
    [CTC_TRAJ_COSINE] = traj_keys_periodic,   [CTC_TRAJ_POLYNOMIAL] = traj_keys_polynomial,
    [CTC_TRAJ_MIN_JERK] = traj_keys_min_jerk, [CTC_TRAJ_SPLINE] = traj_keys_spline};
static const char *const boundary_names[] = {
    [CTC_SPLINE_CLAMPED] = "clamped", [CTC_SPLINE_NATURAL] = "natural"};

/* a spline's knots, built once per coordinate (each ctc_traj owns its knots) */
static int parse_spline(parser *p, const cJSON *v, const char *path, int first, int count,
                        cJSON *out)
{
    char at[PATH_LEN], msg[256];
    double *times = NULL, *values = NULL;
    int n = 0, nvalues = 0, boundary = CTC_SPLINE_CLAMPED, rc = -1;
    const cJSON *t = json_required_member(p, v, path, "times", "");
    const cJSON *y = t != NULL ? json_required_member(p, v, path, "values", "") : NULL;
    const cJSON *b = json_member(v, "boundary");
    if (y == NULL ||
        json_number_list_at(p, t, json_key_path(at, path, "times"), 2, CTC_TRAJ_MAX_KNOTS, &times,
                            &n) ||
        json_number_list_at(p, y, json_key_path(at, path, "values"), 0, CTC_TRAJ_MAX_KNOTS, &values,
                            &nvalues)) {
        goto done;
    }
    if (nvalues != n) {
        json_error_at(p->err, JOB_INVALID_FIELD, json_key_path(at, path, "values"),
                      "must have as many entries as \"times\" (%d, got %d)", n, nvalues);
        goto done;
    }
    if (b != NULL &&
        json_enum_at(p, b, json_key_path(at, path, "boundary"), boundary_names, 2, &boundary)) {
        goto done;
    }
    json_put_numbers(p, out, "times", times, n);
    json_put_numbers(p, out, "values", values, n);
    json_put_string(p, out, "boundary", boundary_names[boundary]);
    for (int i = first; i < first + count; i++) {
        ctc_status st = ctc_traj_spline(n, times, values, (ctc_spline_boundary)boundary,
                                        &p->j->traj[i], msg, sizeof msg);
        if (st == CTC_ENOMEM) {
            json_out_of_memory(p->err);
            goto done;
        }
        if (st != CTC_OK) {
            json_error_at(p->err, JOB_INVALID_FIELD, path, "%s", msg);
            goto done;
        }
    }
    rc = 0;
done:
    free(times);
    free(values);
    return rc;
}

/* One number member of an item: its key, REQUIRED or OPTIONAL (then 0 when absent), where it
 * goes. */
typedef struct number_member {
    const char *key;
    int required;
    double *value;
} number_member;

/* Reads the members m[0..] (up to the one with key NULL) of v, in order, as numbers, and puts
 * each into out, the item's normalised form, under its key; 0, or -1 at the first that fails. */
static int numbers_through(parser *p, const cJSON *v, const char *path, cJSON *out,
                           const number_member *m)
{
    for (; m->key; m++) {
        if (json_member_number(p, v, path, m->key, m->required, 0, m->value) != 0) return -1;
        json_put_number(p, out, m->key, *m->value);
    }
    return 0;
}

static int parse_traj_item(parser *p, const cJSON *v, const char *path, int first, int count,
                           cJSON *out)
{
    char at[PATH_LEN], msg[256];
    int type, n;
    ctc_traj tr = {0};
    double *coef = NULL;
    if (json_typed_object(p, v, path, "type", REQUIRED, 0, traj_names, 6, "trajectory type",
                          traj_keys, traj_keys_all, &type) != 0) {
        return -1;
    }
    tr.type = (ctc_traj_type)type;
    json_put_string(p, out, "type", traj_names[type]);
    switch (tr.type) {
    case CTC_TRAJ_CONSTANT:
        if (numbers_through(p, v, path, out,
                            (number_member[]){{"value", REQUIRED, &tr.value}, {NULL, 0, NULL}}))
            return -1;
        break;
    case CTC_TRAJ_SINE:
    case CTC_TRAJ_COSINE:
        if (numbers_through(p, v, path, out,
                            (number_member[]){{"amplitude", REQUIRED, &tr.amplitude},
                                              {"period", REQUIRED, &tr.period},
                                              {"phase", OPTIONAL, &tr.phase},
                                              {"offset", OPTIONAL, &tr.offset},
                                              {NULL, 0, NULL}}))
            return -1;
        break;
    case CTC_TRAJ_POLYNOMIAL: {
        const cJSON *c = json_required_member(p, v, path, "coefficients", "");
        if (c == NULL || json_number_list_at(p, c, json_key_path(at, path, "coefficients"), 1,
                                             CTC_TRAJ_MAX_COEF, &coef, &n) != 0) {
            free(coef);
            return -1;
        }
        tr.ncoef = n;
        memcpy(tr.coef, coef, (size_t)n * sizeof *coef);
        free(coef);
        json_put_numbers(p, out, "coefficients", tr.coef, n);
        break;
    }
    case CTC_TRAJ_MIN_JERK:
        if (numbers_through(p, v, path, out,
                            (number_member[]){{"from", REQUIRED, &tr.q0},
                                              {"to", REQUIRED, &tr.q1},
                                              {"start", REQUIRED, &tr.t0},
                                              {"end", REQUIRED, &tr.t1},
                                              {NULL, 0, NULL}}))
            return -1;
        break;
    case CTC_TRAJ_SPLINE:
        return parse_spline(p, v, path, first, count, out);
    }
    if (ctc_traj_check(&tr, msg, sizeof msg) != CTC_OK) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path, "%s", msg);
    }
    for (int i = first; i < first + count; i++) p->j->traj[i] = tr;
    return 0;
}

int parse_trajectory(parser *p, const cJSON *doc)
{
    job *j = p->j;
    const cJSON *v = json_member(doc, "trajectory");
    if (p->ctrl == CTC_CTRL_NONE) {
        if (v == NULL) return 0;
        return json_error_at(p->err, JOB_INVALID_FIELD, "trajectory",
                             "not allowed with controller \"none\" (a passive run has no desired "
                             "motion)");
    }
    if (v == NULL) {
        return json_error_at(p->err, JOB_MISSING_FIELD, "trajectory",
                             "is required with controller \"%s\"", ctc_ctrl_type_name(p->ctrl));
    }
    j->traj = json_alloc(p, (size_t)j->nind, sizeof *j->traj);
    if (j->traj == NULL) return -1;
    j->spec.traj = j->traj;
    return parse_per_coordinate(p, v, "trajectory", parse_traj_item);
}

static const char *const disturb_names[] = {"none", "constant", "sine", "step"};
static const char *const disturb_keys_all[] = {"type",  "value",  "amplitude", "period",
                                               "phase", "offset", "time",      NULL};
static const char *const disturb_keys_none[] = {"type", NULL};
static const char *const disturb_keys_constant[] = {"type", "value", NULL};
static const char *const disturb_keys_sine[] = {"type",  "amplitude", "period",
                                                "phase", "offset",    NULL};
static const char *const disturb_keys_step[] = {"type", "value", "time", NULL};
static const char *const *const disturb_keys[] = {[CTC_DISTURB_NONE] = disturb_keys_none,
                                                  [CTC_DISTURB_CONSTANT] = disturb_keys_constant,
                                                  [CTC_DISTURB_SINE] = disturb_keys_sine,
                                                  [CTC_DISTURB_STEP] = disturb_keys_step};

static int parse_disturb_item(parser *p, const cJSON *v, const char *path, int first, int count,
                              cJSON *out)
{
    char msg[256];
    int type;
    ctc_disturb z = {0};
    if (json_typed_object(p, v, path, "type", REQUIRED, 0, disturb_names, 4, "disturbance type",
                          disturb_keys, disturb_keys_all, &type) != 0) {
        return -1;
    }
    z.type = (ctc_disturb_type)type;
    json_put_string(p, out, "type", disturb_names[type]);
    switch (z.type) {
    case CTC_DISTURB_NONE:
        break;
    case CTC_DISTURB_CONSTANT:
        if (numbers_through(p, v, path, out,
                            (number_member[]){{"value", REQUIRED, &z.value}, {NULL, 0, NULL}}))
            return -1;
        break;
    case CTC_DISTURB_SINE:
        if (numbers_through(p, v, path, out,
                            (number_member[]){{"amplitude", REQUIRED, &z.amplitude},
                                              {"period", REQUIRED, &z.period},
                                              {"phase", OPTIONAL, &z.phase},
                                              {"offset", OPTIONAL, &z.offset},
                                              {NULL, 0, NULL}}))
            return -1;
        break;
    case CTC_DISTURB_STEP:
        if (numbers_through(p, v, path, out,
                            (number_member[]){{"value", REQUIRED, &z.value},
                                              {"time", REQUIRED, &z.time},
                                              {NULL, 0, NULL}}))
            return -1;
        break;
    }
    if (ctc_disturb_check(&z, msg, sizeof msg) != CTC_OK) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path, "%s", msg);
    }
    for (int i = first; i < first + count; i++) p->j->disturb[i] = z;
    return 0;
}

/* "disturbance": absent means none; a disturbance that is none everywhere leaves spec.disturb
 * NULL, so a job and its normalised document give the same spec */
int parse_disturbance(parser *p, const cJSON *doc)
{
    job *j = p->j;
    const cJSON *v = json_member(doc, "disturbance");
    if (v == NULL) {
        cJSON *out = json_put(p, p->norm, "disturbance", cJSON_CreateObject());
        json_put_string(p, out, "type", disturb_names[CTC_DISTURB_NONE]);
        return 0;
    }
    j->disturb = json_alloc(p, (size_t)j->nind, sizeof *j->disturb);
    if (j->disturb == NULL || parse_per_coordinate(p, v, "disturbance", parse_disturb_item) != 0) {
        return -1;
    }
    for (int i = 0; i < j->nind; i++) {
        if (j->disturb[i].type != CTC_DISTURB_NONE) {
            j->spec.disturb = j->disturb;
            return 0;
        }
    }
    free(j->disturb);
    j->disturb = NULL;
    return 0;
}

/* ---- integrator, duration, output, limits ---- */

static const char *const integ_keys_all[] = {
    "method", "step", "rtol", "atol", "initial_step", "max_step", "min_step", "max_steps", NULL};
static const char *const integ_keys_fixed[] = {"method", "step", "max_steps", NULL};
static const char *const integ_keys_adaptive[] = {
    "method", "rtol", "atol", "initial_step", "max_step", "min_step", "max_steps", NULL};
static const char *const *const integ_keys[] = {[CTC_INTEG_RK4] = integ_keys_fixed,
                                                [CTC_INTEG_DOPRI5] = integ_keys_adaptive,
                                                [CTC_INTEG_BDF] = integ_keys_adaptive};

int parse_integrator(parser *p, const cJSON *doc)
{
    ctc_integ_spec *s = &p->j->spec.integrator;
    const cJSON *v = json_member(doc, "integrator");
    const char *names[3];
    int method;
    for (int m = 0; m < 3; m++) names[m] = ctc_integ_method_name((ctc_integ_method)m);
    if (json_typed_object(p, v, "integrator", "method", OPTIONAL, CTC_INTEG_DOPRI5, names, 3,
                          "method", integ_keys, integ_keys_all, &method) != 0) {
        return -1;
    }
    s->method = (ctc_integ_method)method;
    cJSON *out = json_put(p, p->norm, "integrator", cJSON_CreateObject());
    json_put_string(p, out, "method", names[method]);

    /* the method's own settings */
    if (s->method == CTC_INTEG_RK4) {
        if (json_member_number(p, v, "integrator", "step", OPTIONAL, DEFAULT_RK4_STEP, &s->step) !=
            0) {
            return -1;
        }
        json_put_number(p, out, "step", s->step);
    } else {
        if (json_member_number(p, v, "integrator", "rtol", OPTIONAL, DEFAULT_RTOL, &s->rtol) != 0 ||
            json_member_number(p, v, "integrator", "atol", OPTIONAL, DEFAULT_ATOL, &s->atol) != 0 ||
            json_member_number(p, v, "integrator", "initial_step", OPTIONAL, 0, &s->initial_step) ||
            json_member_number(p, v, "integrator", "max_step", OPTIONAL, 0, &s->max_step) != 0 ||
            json_member_number(p, v, "integrator", "min_step", OPTIONAL, 0, &s->min_step) != 0) {
            return -1;
        }
        json_put_number(p, out, "rtol", s->rtol);
        json_put_number(p, out, "atol", s->atol);
        json_put_number(p, out, "initial_step", s->initial_step);
        json_put_number(p, out, "max_step", s->max_step);
        json_put_number(p, out, "min_step", s->min_step);
    }

    /* a whole number of steps; 0 = no limit */
    double steps;
    if (json_member_number(p, v, "integrator", "max_steps", OPTIONAL, DEFAULT_MAX_STEPS, &steps) !=
        0) {
        return -1;
    }
    if (!(steps >= 0 && steps <= MAX_WHOLE && steps == floor(steps))) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "integrator.max_steps",
                             "must be a whole number from 0 (no limit) to 2^53 (got %g)", steps);
    }
    s->max_steps = (long)steps;
    json_put_number(p, out, "max_steps", steps);

    char msg[256];
    if (ctc_integ_check(s, msg, sizeof msg) != CTC_OK) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "integrator", "%s", msg);
    }
    return 0;
}

int parse_duration(parser *p, const cJSON *doc)
{
    double *d = &p->j->spec.duration;
    if (json_member_number(p, doc, "", "duration", REQUIRED, 0, d) != 0) return -1;
    if (!(*d > 0)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "duration", "must be positive (got %g s)",
                             *d);
    }
    if (*d > JOB_MAX_DURATION) {
        return json_error_at(p->err, JOB_LIMIT_EXCEEDED, "duration",
                             "must be at most %g s (got %g s)", JOB_MAX_DURATION, *d);
    }
    json_put_number(p, p->norm, "duration", *d);

    /* rk4's work is known before it runs: duration / step steps, within max_steps (or
     * JOB_MAX_FIXED_STEPS where max_steps is 0, no limit), each step costing about the same per
     * body, so that steps x bodies must be within JOB_MAX_WORK. (The adaptive methods' step count
     * depends on the motion: max_steps, min_step and the server's time limit bound them as they
     * run.) */
    const ctc_integ_spec *s = &p->j->spec.integrator;
    if (s->method == CTC_INTEG_RK4) {
        const double steps = ceil(*d / s->step);
        const double bound = s->max_steps > 0 ? (double)s->max_steps : JOB_MAX_FIXED_STEPS;
        if (!(steps <= bound)) {
            return json_error_at(p->err, JOB_INVALID_FIELD, "integrator.step",
                                 "duration / step = %.3g steps exceeds %s (%.0f): use a larger "
                                 "step (got %g s for %g s)",
                                 steps, s->max_steps > 0 ? "integrator.max_steps" : "the bound",
                                 bound, s->step, *d);
        }
        const int nbodies = p->j->spec.chain.nbodies;
        if (steps * nbodies > JOB_MAX_WORK) {
            return json_error_at(p->err, JOB_LIMIT_EXCEEDED, "integrator.step",
                                 "%.3g steps x %d bodies = %.3g body-steps exceeds the bound on a "
                                 "job's work (%.0e): use a larger step, a shorter duration or "
                                 "fewer bodies (got %g s for %g s)",
                                 steps, nbodies, steps * nbodies, JOB_MAX_WORK, s->step, *d);
        }
    }
    /* a sampled controller restarts the integrator at each of its instants */
    const double period = p->j->spec.sample_period;
    if (period > 0 && !(*d / period <= JOB_MAX_CONTROL_SAMPLES)) {
        return json_error_at(p->err, JOB_LIMIT_EXCEEDED, "controller.sample_period",
                             "duration / sample_period = %.3g instants exceeds %.0e: use a longer "
                             "period or a shorter duration (got %g s for %g s)",
                             *d / period, JOB_MAX_CONTROL_SAMPLES, period, *d);
    }
    return 0;
}

static unsigned tracking_channels(void)
{
    return CTC_CH_BIT(CTC_CH_Q_DES) | CTC_CH_BIT(CTC_CH_QD_DES) | CTC_CH_BIT(CTC_CH_E) |
           CTC_CH_BIT(CTC_CH_W);
}

/* values per sample of channel c (sim.h): q nq, qdot nv, energy and loop 2, the others one per
 * controlled coordinate */
static int channel_width(const job *j, int c)
{
    switch (c) {
    case CTC_CH_Q:
        return j->nq;
    case CTC_CH_QD:
        return j->nv;
    case CTC_CH_ENERGY:
    case CTC_CH_LOOP:
        return 2;
    case CTC_CH_EE:
        return 6;
    case CTC_CH_POSE:
        return 7 * j->spec.npose;
    default:
        return j->nind;
    }
}

/* why channel c does not apply to this job ("needs a controller (this run is passive)") */
static const char *why_not_applicable(int c)
{
    if (c == CTC_CH_LOOP) return "needs a loop (\"scene.loop\")";
    if (c == CTC_CH_EE) return "needs its point (\"output.end_effector\")";
    if (c == CTC_CH_POSE) return "needs its bodies (\"output.body_pose\")";
    if (c == CTC_CH_TAU) return "has no columns (the loop has no independent coordinates)";
    return "needs a controller (this run is passive)";
}

/* "output.channels" into spec.channels (explicit; default every channel that applies) */
static int parse_channels(parser *p, const cJSON *output, const char *const *names, unsigned *mask)
{
    unsigned applicable = CTC_CH_ALL;
    if (p->ctrl == CTC_CTRL_NONE) applicable &= ~tracking_channels();
    if (p->j->spec.chain.loop == NULL) applicable &= ~CTC_CH_BIT(CTC_CH_LOOP);
    if (p->j->spec.end_effector == NULL) applicable &= ~CTC_CH_BIT(CTC_CH_EE);
    if (p->j->spec.npose == 0) applicable &= ~CTC_CH_BIT(CTC_CH_POSE);
    if (p->j->nind == 0) applicable &= ~CTC_CH_BIT(CTC_CH_TAU); /* a loop of dependent joints */
    const cJSON *v = json_member(output, "channels");
    if (v == NULL) {
        *mask = applicable;
        return 0;
    }
    if (!cJSON_IsArray(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "output.channels",
                             "must be an array of channel names (got %s)", json_kind(v));
    }
    if (v->child == NULL) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "output.channels",
                             "must name at least one channel");
    }
    *mask = 0;
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        char at[PATH_LEN];
        int c = 0;
        json_index_path(at, "output.channels", i);
        if (json_enum_at(p, e, at, names, CTC_NCHANNELS, &c) != 0) return -1;
        if (*mask & CTC_CH_BIT(c)) {
            return json_error_at(p->err, JOB_INVALID_FIELD, at, "\"%s\" is listed twice", names[c]);
        }
        if (!(applicable & CTC_CH_BIT(c))) {
            return json_error_at(p->err, JOB_INVALID_FIELD, at, "channel \"%s\" %s", names[c],
                                 why_not_applicable(c));
        }
        *mask |= CTC_CH_BIT(c);
    }
    return 0;
}

static const char *const output_keys[] = {"interval", "channels", "end_effector", "body_pose",
                                          NULL};
static const char *const end_effector_keys[] = {"body", "point", NULL};

/* "output.end_effector": {"body": k, "point": [x, y, z] (m, body frame; default the origin)},
 * into j->end_effector and spec.end_effector; written to out */
static int parse_end_effector(parser *p, const cJSON *output, cJSON *out)
{
    const char *path = "output.end_effector";
    static const double origin[3] = {0, 0, 0};
    job *j = p->j;
    const cJSON *v = json_member(output, "end_effector");
    double body;
    if (v == NULL) return 0;
    if (json_object_at(p, v, path) != 0 ||
        json_check_keys(p, v, path, end_effector_keys, NULL, NULL) != 0 ||
        json_member_number(p, v, path, "body", REQUIRED, 0, &body) != 0 ||
        json_member_vec3(p, v, path, "point", OPTIONAL, origin, j->end_effector.point) != 0) {
        return -1;
    }
    const int n = j->spec.chain.nbodies;
    if (!(body >= 0 && body < n && body == floor(body))) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "output.end_effector.body",
                             "must be a body index, a whole number from 0 to %d (got %g)", n - 1,
                             body);
    }
    j->end_effector.body = (int)body;
    j->spec.end_effector = &j->end_effector;
    cJSON *o = json_put(p, out, "end_effector", cJSON_CreateObject());
    json_put_number(p, o, "body", body);
    json_put_numbers(p, o, "point", j->end_effector.point, 3);
    return 0;
}

/* "output.body_pose": [k, ...], 1 to nbodies distinct body indices, into j->pose_bodies and
 * spec.pose_bodies; written to out */
static int parse_body_pose(parser *p, const cJSON *output, cJSON *out)
{
    const char *path = "output.body_pose";
    job *j = p->j;
    const cJSON *v = json_member(output, "body_pose");
    if (v == NULL) return 0;
    const int n = j->spec.chain.nbodies;
    const int count = cJSON_IsArray(v) ? cJSON_GetArraySize(v) : 0;
    if (count < 1 || count > n) {
        char buf[32];
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must be an array of 1 to %d body indices (got %s)", n,
                             json_describe(buf, v));
    }
    j->pose_bodies = json_alloc(p, (size_t)count, sizeof *j->pose_bodies);
    if (j->pose_bodies == NULL) return -1;
    cJSON *o = json_put(p, out, "body_pose", cJSON_CreateArray());
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        char at[PATH_LEN];
        double x;
        json_index_path(at, path, i);
        if (json_number_at(p, e, at, &x) != 0) return -1;
        if (!(x >= 0 && x < n && x == floor(x))) {
            return json_error_at(p->err, JOB_INVALID_FIELD, at,
                                 "must be a body index, a whole number from 0 to %d (got %g)",
                                 n - 1, x);
        }
        for (int k = 0; k < i; k++)
            if (j->pose_bodies[k] == (int)x)
                return json_error_at(p->err, JOB_INVALID_FIELD, at, "body %d is listed twice",
                                     (int)x);
        j->pose_bodies[i] = (int)x;
        if (o) cJSON_AddItemToArray(o, cJSON_CreateNumber(x));
    }
    j->spec.pose_bodies = j->pose_bodies;
    j->spec.npose = count;
    return 0;
}

int parse_output(parser *p, const cJSON *doc)
{
    job *j = p->j;
    ctc_sim_spec *s = &j->spec;
    const cJSON *v = json_member(doc, "output");
    if (v != NULL && (json_object_at(p, v, "output") != 0 ||
                      json_check_keys(p, v, "output", output_keys, NULL, NULL) != 0)) {
        return -1;
    }

    /* the sample interval: positive, within the duration, not too many samples */
    double def = fmin(DEFAULT_INTERVAL, s->duration);
    if (json_member_number(p, v, "output", "interval", OPTIONAL, def, &s->output_interval) != 0) {
        return -1;
    }
    if (!(s->output_interval > 0)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "output.interval",
                             "must be positive (got %g s)", s->output_interval);
    }
    if (s->output_interval > s->duration) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "output.interval",
                             "must not exceed the duration (got %g s > %g s)", s->output_interval,
                             s->duration);
    }
    double samples = floor(s->duration / s->output_interval) + 2; /* a bound: t = 0 .. duration */
    if (samples > JOB_MAX_SAMPLES) {
        return json_error_at(p->err, JOB_LIMIT_EXCEEDED, "output.interval",
                             "gives up to %.0f samples over %g s; the limit is %d (use a longer "
                             "interval)",
                             samples, s->duration, JOB_MAX_SAMPLES);
    }

    /* the channels, and the values they record */
    const char *names[CTC_NCHANNELS];
    for (int c = 0; c < CTC_NCHANNELS; c++) names[c] = ctc_channel_name((ctc_channel)c);
    cJSON *out = json_put(p, p->norm, "output", cJSON_CreateObject());
    json_put_number(p, out, "interval", s->output_interval);
    if (parse_end_effector(p, v, out) != 0 || parse_body_pose(p, v, out) != 0 ||
        parse_channels(p, v, names, &s->channels) != 0)
        return -1;
    double per_sample = 1; /* t */
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (!(s->channels & CTC_CH_BIT(c))) continue;
        per_sample += channel_width(j, c);
    }
    if (samples * per_sample > JOB_MAX_VALUES) {
        return json_error_at(p->err, JOB_LIMIT_EXCEEDED, "output",
                             "would record up to %.0f values (%.0f samples x %.0f per sample); the "
                             "limit is %d (record fewer channels or use a longer interval)",
                             samples * per_sample, samples, per_sample, JOB_MAX_VALUES);
    }

    cJSON *channels = json_put(p, out, "channels", cJSON_CreateArray());
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (s->channels & CTC_CH_BIT(c)) json_put(p, channels, NULL, cJSON_CreateString(names[c]));
    }
    return 0;
}

static const char *const limit_keys[] = {"max_speed", "wall_time", NULL};

int parse_limits(parser *p, const cJSON *doc)
{
    ctc_sim_spec *s = &p->j->spec;
    const cJSON *v = json_member(doc, "limits");
    if (v != NULL && (json_object_at(p, v, "limits") != 0 ||
                      json_check_keys(p, v, "limits", limit_keys, NULL, NULL) != 0)) {
        return -1;
    }
    if (json_member_number(p, v, "limits", "max_speed", OPTIONAL, DEFAULT_MAX_SPEED,
                           &s->max_speed) ||
        json_member_number(p, v, "limits", "wall_time", OPTIONAL, 0, &s->wall_limit)) {
        return -1;
    }
    if (!(s->max_speed > 0)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "limits.max_speed",
                             "must be positive (got %g)", s->max_speed);
    }
    if (!(s->wall_limit >= 0)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "limits.wall_time",
                             "must not be negative (got %g s)", s->wall_limit);
    }
    cJSON *out = json_put(p, p->norm, "limits", cJSON_CreateObject());
    json_put_number(p, out, "max_speed", s->max_speed);
    json_put_number(p, out, "wall_time", s->wall_limit);
    return 0;
}

/* "threads": a whole number 1..CTC_MAX_THREADS, default 1 (serial) */
int parse_threads(parser *p, const cJSON *doc)
{
    double threads;
    if (json_member_number(p, doc, "", "threads", OPTIONAL, 1, &threads) != 0) return -1;
    if (!(threads >= 1 && threads <= CTC_MAX_THREADS && threads == floor(threads))) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "threads",
                             "must be a whole number from 1 to %d (got %g)", CTC_MAX_THREADS,
                             threads);
    }
    p->j->spec.threads = (int)threads;
    json_put_number(p, p->norm, "threads", threads);
    return 0;
}

/* ---- the run settings' keys and defaults, as data (job_json.h) ---- */

const job_format_object job_run_objects[] = {
    FORMAT_KEYS("trajectory", "type", NULL, traj_keys_all),
    FORMAT_KEYS("trajectory", "type", "constant", traj_keys[CTC_TRAJ_CONSTANT]),
    FORMAT_KEYS("trajectory", "type", "sine", traj_keys[CTC_TRAJ_SINE]),
    FORMAT_KEYS("trajectory", "type", "cosine", traj_keys[CTC_TRAJ_COSINE]),
    FORMAT_KEYS("trajectory", "type", "polynomial", traj_keys[CTC_TRAJ_POLYNOMIAL]),
    FORMAT_KEYS("trajectory", "type", "min_jerk", traj_keys[CTC_TRAJ_MIN_JERK]),
    FORMAT_KEYS("trajectory", "type", "spline", traj_keys[CTC_TRAJ_SPLINE]),
    FORMAT_KEYS("output.end_effector", NULL, NULL, end_effector_keys),
    FORMAT_KEYS("disturbance", "type", NULL, disturb_keys_all),
    FORMAT_KEYS("disturbance", "type", "none", disturb_keys[CTC_DISTURB_NONE]),
    FORMAT_KEYS("disturbance", "type", "constant", disturb_keys[CTC_DISTURB_CONSTANT]),
    FORMAT_KEYS("disturbance", "type", "sine", disturb_keys[CTC_DISTURB_SINE]),
    FORMAT_KEYS("disturbance", "type", "step", disturb_keys[CTC_DISTURB_STEP]),
    FORMAT_KEYS("integrator", "method", NULL, integ_keys_all),
    FORMAT_KEYS("integrator", "method", "rk4", integ_keys[CTC_INTEG_RK4]),
    FORMAT_KEYS("integrator", "method", "dopri5", integ_keys[CTC_INTEG_DOPRI5]),
    FORMAT_KEYS("integrator", "method", "bdf", integ_keys[CTC_INTEG_BDF]),
    FORMAT_KEYS("output", NULL, NULL, output_keys),
    FORMAT_KEYS("limits", NULL, NULL, limit_keys),
    FORMAT_END,
};

const job_format_default job_run_defaults[] = {
    DEFAULT_NUMBER("trajectory", "sine", "phase", 0),
    DEFAULT_NUMBER("trajectory", "sine", "offset", 0),
    DEFAULT_NUMBER("trajectory", "cosine", "phase", 0),
    DEFAULT_NUMBER("trajectory", "cosine", "offset", 0),
    DEFAULT_JSON("trajectory", "spline", "boundary", "\"clamped\""),
    DEFAULT_NUMBER("disturbance", "sine", "phase", 0),
    DEFAULT_NUMBER("disturbance", "sine", "offset", 0),
    DEFAULT_JSON("integrator", NULL, "method", "\"dopri5\""),
    DEFAULT_NUMBER("integrator", "rk4", "step", DEFAULT_RK4_STEP),
    DEFAULT_NUMBER("integrator", "dopri5", "rtol", DEFAULT_RTOL),
    DEFAULT_NUMBER("integrator", "dopri5", "atol", DEFAULT_ATOL),
    DEFAULT_NUMBER("integrator", "dopri5", "initial_step", 0),
    DEFAULT_NUMBER("integrator", "dopri5", "max_step", 0),
    DEFAULT_NUMBER("integrator", "dopri5", "min_step", 0),
    DEFAULT_NUMBER("integrator", "bdf", "rtol", DEFAULT_RTOL),
    DEFAULT_NUMBER("integrator", "bdf", "atol", DEFAULT_ATOL),
    DEFAULT_NUMBER("integrator", "bdf", "initial_step", 0),
    DEFAULT_NUMBER("integrator", "bdf", "max_step", 0),
    DEFAULT_NUMBER("integrator", "bdf", "min_step", 0),
    DEFAULT_NUMBER("integrator", NULL, "max_steps", DEFAULT_MAX_STEPS),
    DEFAULT_NUMBER("output", NULL, "interval", DEFAULT_INTERVAL),
    DEFAULT_NUMBER("limits", NULL, "max_speed", DEFAULT_MAX_SPEED),
    DEFAULT_NUMBER("limits", NULL, "wall_time", 0),
    DEFAULT_NUMBER("", NULL, "threads", 1),
    DEFAULT_JSON("", NULL, "disturbance", "{\"type\": \"none\"}"),
    DEFAULT_END,
};
