/*
 * job_json.c - the job format (job_json.h): JSON text to a checked, runnable ctc_sim_spec and the
 * job's normalised document.
 *
 * One pass walks the document in the format's order: name, scene, controller, trajectory,
 * disturbance, integrator, duration, output, limits, threads. Each object's keys are checked before
 * any of its values is read, so a misspelt key is reported as unknown (with the nearest valid key)
 * rather than as the required key it was meant to be; a typed object ({"type": ...}) is checked
 * twice, against every key of its kind and then against the keys of its type. Types, finiteness
 * and the ranges the format owns (positive masses, non-zero axes, array lengths, the limits) are
 * checked here, and each error names the JSON path of the offending value. What the library owns
 * is checked by the library and reported at the nearest path with its message: a controller's
 * stability ("controller" or "controller.joints[i]", ctrl.h), a trajectory's, disturbance's or
 * integrator's parameters, a shape's dimensions, and what only ctc_model_build sees - inertia
 * tensors, a planar form asked of a spatial chain - at "scene". ctc_sim_check runs last as a
 * safety net (field "").
 *
 * A loop ("scene.loop", read after the bodies) changes the sizes that follow: the controller's
 * per-coordinate arrays and channels cover the nind independent coordinates, counted here from
 * the joints' "independent" flags as model.h counts them. What only the library can judge of a
 * loop - its mobility against nind, a singular or over-constrained configuration, a q0 it cannot
 * close - comes from ctc_model_build or ctc_sim_check; those messages speak of the loop (its
 * words: "loop", "mobility", "closing joint", "singular", "over-constrained") and are reported at
 * "scene.loop", or, when the loop "does not close" from q0, at "scene.q0".
 *
 * While it walks, the parser writes the normalised document: the keys it read in canonical order,
 * every default written out, a preset expanded. It parses to the same spec. Printed with cJSON it
 * parses back to the same text; numbers with more than 15 significant digits may come back one
 * unit in the last place off, because cJSON 1.7 prints 15 digits whenever they read back within
 * DBL_EPSILON relative.
 *
 * A preset request {"preset": NAME, ...} is expanded first: the preset builds its document from
 * the request's parameters, and the request's other keys are applied to it as an RFC 7386 merge
 * patch. The result is then parsed like any job.
 *
 * The parser is in parts (job_parse.h): the generic reader json_read.c, the scene
 * job_scene.c, the run settings job_run.c; this file holds the controller and the entry points.
 *
 * Nothing here is global; any number of threads may parse at once. (cJSON itself records the
 * position of its last parse error in a global, which this file never reads.)
 */
#include "job_json.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_parse.h"
#include "presets.h"

/* ---- name ---- */

static int parse_name(parser *p, const cJSON *doc, const char *default_name)
{
    const char *name = default_name;
    const cJSON *v = member(doc, "name");
    if (v != NULL && name_at(p, v, "name", &name) != 0) return -1;
    p->j->name = strdup(name);
    if (p->j->name == NULL) return out_of_memory(p->err);
    put_string(p, p->norm, "name", name);
    return 0;
}

/* ---- controller ---- */

/* the keys of the gain parameters, as bits of gain_params.given */
enum {
    G_KP = 1u << 0,
    G_KV = 1u << 1,
    G_KI = 1u << 2,
    G_ZETA = 1u << 3,
    G_TAU = 1u << 4,
    G_POLES = 1u << 5,
    G_Q = 1u << 6,
    G_LAMBDA = 1u << 7,
    G_PAIR_KP = G_KP | G_KV,
    G_PAIR_ZETA = G_ZETA | G_TAU,
};

/* The design parameters of one coordinate, as read from "controller" or an override. */
typedef struct gain_params {
    unsigned given; /* G_* bits of the keys present */
    double kp, kv, ki, zeta, tau;
    double re[3], im[3]; /* poles */
    double Q[9];         /* row-major */
    int q_diagonal;      /* Q was given as its diagonal */
    double lambda;
} gain_params;

static const char *const gains_pd[] = {"kp", "kv", "zeta", "tau", NULL};
static const char *const gains_pid[] = {"kp", "kv", "ki", "zeta", "tau", NULL};
static const char *const gains_poles[] = {"poles", NULL};
static const char *const gains_lqr[] = {"Q", "lambda", NULL};
static const char *const gains_none[] = {NULL};
static const char *const gains_all[] = {"kp",    "kv", "ki",     "zeta", "tau",
                                        "poles", "Q",  "lambda", NULL};
static const char *const *const gain_keys[] = {[CTC_CTRL_NONE] = gains_none,
                                               [CTC_CTRL_PD] = gains_pd,
                                               [CTC_CTRL_PID] = gains_pid,
                                               [CTC_CTRL_POLES] = gains_poles,
                                               [CTC_CTRL_LQR] = gains_lqr};

static const char *const ctrl_keys_all[] = {"type",  "kp", "kv",     "ki",     "zeta",  "tau",
                                            "poles", "Q",  "lambda", "joints", "model", NULL};
static const char *const ctrl_keys_none[] = {"type", NULL};
static const char *const ctrl_keys_pd[] = {"type", "kp",     "kv",    "zeta",
                                           "tau",  "joints", "model", NULL};
static const char *const ctrl_keys_pid[] = {"type", "kp",     "kv",    "ki", "zeta",
                                            "tau",  "joints", "model", NULL};
static const char *const ctrl_keys_poles[] = {"type", "poles", "joints", "model", NULL};
static const char *const ctrl_keys_lqr[] = {"type", "Q", "lambda", "joints", "model", NULL};
static const char *const *const ctrl_keys[] = {[CTC_CTRL_NONE] = ctrl_keys_none,
                                               [CTC_CTRL_PD] = ctrl_keys_pd,
                                               [CTC_CTRL_PID] = ctrl_keys_pid,
                                               [CTC_CTRL_POLES] = ctrl_keys_poles,
                                               [CTC_CTRL_LQR] = ctrl_keys_lqr};

static const char *const pole_keys[] = {"re", "im", NULL};

/* "poles": three entries, each a real pole or {"re": x, "im": y} */
static int poles_at(parser *p, const cJSON *v, const char *path, double re[3], double im[3])
{
    char got[32], at[PATH_LEN];
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) {
        return error_at(p->err, JOB_INVALID_FIELD, path, "must be an array of 3 poles (got %s)",
                        describe(got, v));
    }
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        index_path(at, path, i);
        im[i] = 0;
        if (cJSON_IsNumber(e)) {
            if (number_at(p, e, at, &re[i]) != 0) return -1;
        } else if (cJSON_IsObject(e)) {
            if (check_keys(p, e, at, pole_keys, NULL, NULL) != 0 ||
                member_number(p, e, at, "re", REQUIRED, 0, &re[i]) != 0 ||
                member_number(p, e, at, "im", REQUIRED, 0, &im[i]) != 0) {
                return -1;
            }
        } else {
            return error_at(p->err, JOB_INVALID_FIELD, at,
                            "must be a number or an object {\"re\": x, \"im\": y} (got %s)",
                            kind(e));
        }
    }
    return 0;
}

/* one scalar gain key of obj (at path), if present */
static int read_gain(parser *p, const cJSON *obj, const char *path, const char *key, unsigned bit,
                     double *x, unsigned *given)
{
    char at[PATH_LEN];
    const cJSON *v = member(obj, key);
    if (v == NULL) return 0;
    if (number_at(p, v, key_path(at, path, key), x) != 0) return -1;
    *given |= bit;
    return 0;
}

/* the gain keys present in obj (at path; its keys already checked) */
static int read_gain_params(parser *p, const cJSON *obj, const char *path, gain_params *g)
{
    char at[PATH_LEN];
    const cJSON *v;
    if (read_gain(p, obj, path, "kp", G_KP, &g->kp, &g->given) != 0 ||
        read_gain(p, obj, path, "kv", G_KV, &g->kv, &g->given) != 0 ||
        read_gain(p, obj, path, "ki", G_KI, &g->ki, &g->given) != 0 ||
        read_gain(p, obj, path, "zeta", G_ZETA, &g->zeta, &g->given) != 0 ||
        read_gain(p, obj, path, "tau", G_TAU, &g->tau, &g->given) != 0 ||
        read_gain(p, obj, path, "lambda", G_LAMBDA, &g->lambda, &g->given) != 0) {
        return -1;
    }
    if ((v = member(obj, "poles")) != NULL) {
        if (poles_at(p, v, key_path(at, path, "poles"), g->re, g->im) != 0) return -1;
        g->given |= G_POLES;
    }
    if ((v = member(obj, "Q")) != NULL) {
        if (matrix3_at(p, v, key_path(at, path, "Q"), "diagonal entries", g->Q, &g->q_diagonal) !=
            0) {
            return -1;
        }
        g->given |= G_Q;
    }
    return 0;
}

/* pd and pid take "kp" and "kv", or "zeta" and "tau": exactly one whole pair (bits given) */
static int check_gain_pair(parser *p, unsigned given, const char *path)
{
    char at[PATH_LEN];
    if ((given & G_PAIR_KP) && (given & G_PAIR_ZETA)) {
        return error_at(p->err, JOB_INVALID_FIELD,
                        key_path(at, path, given & G_ZETA ? "zeta" : "tau"),
                        "cannot be combined with \"kp\" and \"kv\" (give \"kp\" and \"kv\", or "
                        "\"zeta\" and \"tau\")");
    }
    if (!(given & (G_PAIR_KP | G_PAIR_ZETA))) {
        return error_at(p->err, JOB_MISSING_FIELD, key_path(at, path, "kp"),
                        "is required (or give \"zeta\" and \"tau\")");
    }
    static const struct {
        unsigned bit, partner;
        const char *key, *partner_key;
    } pairs[] = {{G_KP, G_KV, "kp", "kv"},
                 {G_KV, G_KP, "kv", "kp"},
                 {G_ZETA, G_TAU, "zeta", "tau"},
                 {G_TAU, G_ZETA, "tau", "zeta"}};
    for (int i = 0; i < 4; i++) {
        if ((given & pairs[i].bit) && !(given & pairs[i].partner)) {
            return error_at(p->err, JOB_MISSING_FIELD, key_path(at, path, pairs[i].partner_key),
                            "is required with \"%s\"", pairs[i].key);
        }
    }
    return 0;
}

/* the keys the controller object itself must give for its type */
static int check_required_gains(parser *p, ctc_ctrl_type type, unsigned given)
{
    switch (type) {
    case CTC_CTRL_PID:
        if (!(given & G_KI)) {
            return error_at(p->err, JOB_MISSING_FIELD, "controller.ki", "is required");
        }
        return check_gain_pair(p, given, "controller");
    case CTC_CTRL_PD:
        return check_gain_pair(p, given, "controller");
    case CTC_CTRL_POLES:
        if (!(given & G_POLES)) {
            return error_at(p->err, JOB_MISSING_FIELD, "controller.poles", "is required");
        }
        return 0;
    case CTC_CTRL_LQR:
        if (!(given & G_Q))
            return error_at(p->err, JOB_MISSING_FIELD, "controller.Q", "is required");
        if (!(given & G_LAMBDA)) {
            return error_at(p->err, JOB_MISSING_FIELD, "controller.lambda", "is required");
        }
        return 0;
    case CTC_CTRL_NONE:
        break;
    }
    return 0;
}

/* g with the override o applied key by key; a pd/pid pair in o replaces the other pair in g */
static void merge_gains(gain_params *g, const gain_params *o)
{
    if ((o->given & G_PAIR_KP) && !(o->given & G_PAIR_ZETA)) g->given &= ~(unsigned)G_PAIR_ZETA;
    if ((o->given & G_PAIR_ZETA) && !(o->given & G_PAIR_KP)) g->given &= ~(unsigned)G_PAIR_KP;
    if (o->given & G_KP) g->kp = o->kp;
    if (o->given & G_KV) g->kv = o->kv;
    if (o->given & G_KI) g->ki = o->ki;
    if (o->given & G_ZETA) g->zeta = o->zeta;
    if (o->given & G_TAU) g->tau = o->tau;
    if (o->given & G_POLES) {
        memcpy(g->re, o->re, sizeof g->re);
        memcpy(g->im, o->im, sizeof g->im);
    }
    if (o->given & G_Q) {
        memcpy(g->Q, o->Q, sizeof g->Q);
        g->q_diagonal = o->q_diagonal;
    }
    if (o->given & G_LAMBDA) g->lambda = o->lambda;
    g->given |= o->given;
}

/* the gains of g by the library's design functions; their errors at field */
static int design_gains(parser *p, ctc_ctrl_type type, const gain_params *g, const char *field,
                        ctc_gains *out)
{
    char msg[512];
    ctc_status st = CTC_OK;
    double ki = type == CTC_CTRL_PID ? g->ki : 0.0;
    switch (type) {
    case CTC_CTRL_PD:
    case CTC_CTRL_PID:
        st = (g->given & G_KP) ? ctc_ctrl_pid(g->kp, g->kv, ki, out, msg, sizeof msg)
                               : ctc_ctrl_zeta_tau(g->zeta, g->tau, ki, out, msg, sizeof msg);
        break;
    case CTC_CTRL_POLES:
        st = ctc_ctrl_poles(g->re, g->im, out, msg, sizeof msg);
        break;
    case CTC_CTRL_LQR:
        st = ctc_ctrl_lqr(g->Q, g->lambda, out, NULL, msg, sizeof msg);
        break;
    case CTC_CTRL_NONE:
        break;
    }
    if (st == CTC_ENOMEM) return out_of_memory(p->err);
    if (st != CTC_OK) return error_at(p->err, JOB_INVALID_FIELD, field, "%s", msg);
    return 0;
}

/* the keys of g that were given, in canonical order */
static void put_gain_params(parser *p, cJSON *out, const gain_params *g)
{
    if (g->given & G_KP) put_number(p, out, "kp", g->kp);
    if (g->given & G_KV) put_number(p, out, "kv", g->kv);
    if (g->given & G_ZETA) put_number(p, out, "zeta", g->zeta);
    if (g->given & G_TAU) put_number(p, out, "tau", g->tau);
    if (g->given & G_KI) put_number(p, out, "ki", g->ki);
    if (g->given & G_POLES) {
        cJSON *poles = put(p, out, "poles", cJSON_CreateArray());
        for (int i = 0; i < 3; i++) {
            if (g->im[i] == 0) {
                put_number(p, poles, NULL, g->re[i]);
                continue;
            }
            cJSON *pole = put(p, poles, NULL, cJSON_CreateObject());
            put_number(p, pole, "re", g->re[i]);
            put_number(p, pole, "im", g->im[i]);
        }
    }
    if (g->given & G_Q) put_matrix3(p, out, "Q", g->Q, g->q_diagonal);
    if (g->given & G_LAMBDA) put_number(p, out, "lambda", g->lambda);
}

/* what one entry of a per-coordinate array stands for, in messages */
const char *coordinate_word(const parser *p)
{
    return p->j->spec.chain.loop != NULL ? "independent coordinate" : "coordinate";
}

/* "controller.joints": nind overrides of the shared parameters, one per coordinate */
static int parse_gain_overrides(parser *p, const cJSON *v, ctc_ctrl_type type,
                                const gain_params *shared, const char *context, cJSON *out_ctrl)
{
    job *j = p->j;
    char path[PATH_LEN];
    if (!cJSON_IsArray(v)) {
        return error_at(p->err, JOB_INVALID_FIELD, "controller.joints",
                        "must be an array of %d objects, one per %s (got %s)", j->nind,
                        coordinate_word(p), kind(v));
    }
    int len = cJSON_GetArraySize(v);
    if (len != j->nind) {
        return error_at(p->err, JOB_INVALID_FIELD, "controller.joints",
                        "must have %d entries, one per %s (got %d)", j->nind, coordinate_word(p),
                        len);
    }
    cJSON *out = put(p, out_ctrl, "joints", cJSON_CreateArray());
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        gain_params override = {0};
        index_path(path, "controller.joints", i);
        if (object_at(p, e, path) != 0 ||
            check_keys(p, e, path, gain_keys[type], gains_all, context) != 0 ||
            read_gain_params(p, e, path, &override) != 0) {
            return -1;
        }
        put_gain_params(p, put(p, out, NULL, cJSON_CreateObject()), &override);
        if (override.given == 0) continue; /* {} keeps the shared gains */

        gain_params mine = *shared;
        merge_gains(&mine, &override);
        if ((type == CTC_CTRL_PD || type == CTC_CTRL_PID) && check_gain_pair(p, mine.given, path)) {
            return -1;
        }
        if (design_gains(p, type, &mine, path, &j->gains[i]) != 0) return -1;
    }
    return 0;
}

/* "controller.model": the controller's model of the plant */
static const char *const model_keys[] = {"mass_scale", "inertia_scale", NULL};

static int parse_ctrl_model(parser *p, const cJSON *ctrl, cJSON *out_ctrl)
{
    const char *keys[2] = {"mass_scale", "inertia_scale"};
    double *scales[2] = {&p->j->spec.model_mass_scale, &p->j->spec.model_inertia_scale};
    const cJSON *v = member(ctrl, "model");
    if (v != NULL && (object_at(p, v, "controller.model") != 0 ||
                      check_keys(p, v, "controller.model", model_keys, NULL, NULL) != 0)) {
        return -1;
    }
    cJSON *out = put(p, out_ctrl, "model", cJSON_CreateObject());
    for (int i = 0; i < 2; i++) {
        char at[PATH_LEN];
        if (member_number(p, v, "controller.model", keys[i], OPTIONAL, 1.0, scales[i]) != 0) {
            return -1;
        }
        if (!(*scales[i] > 0)) {
            return error_at(p->err, JOB_INVALID_FIELD, key_path(at, "controller.model", keys[i]),
                            "must be positive (got %g)", *scales[i]);
        }
        put_number(p, out, keys[i], *scales[i]);
    }
    return 0;
}

static int parse_controller(parser *p, const cJSON *doc)
{
    job *j = p->j;
    const char *names[5];
    int type;
    for (int t = 0; t < 5; t++) names[t] = ctc_ctrl_type_name((ctc_ctrl_type)t);
    const cJSON *v =
        required_member(p, doc, "", "controller", " ({\"type\": \"none\"} for a passive run)");
    if (v == NULL || typed_object(p, v, "controller", "type", REQUIRED, 0, names, 5,
                                  "controller type", ctrl_keys, ctrl_keys_all, &type) != 0) {
        return -1;
    }
    p->ctrl = j->spec.controller = (ctc_ctrl_type)type;
    j->spec.model_mass_scale = j->spec.model_inertia_scale = 1.0;
    cJSON *out = put(p, p->norm, "controller", cJSON_CreateObject());
    put_string(p, out, "type", names[type]);
    if (p->ctrl == CTC_CTRL_NONE) return 0;

    /* computed torque control per coordinate: not for a spherical joint's quaternion */
    if (p->spherical[0] != '\0') {
        const char *allowed = j->spec.chain.loop != NULL
                                  ? "a spherical joint in a loop must be dependent, or the run "
                                    "passive (controller \"none\")"
                                  : "spherical joints are allowed only with controller \"none\"";
        return error_at(p->err, JOB_INVALID_FIELD, "controller.type",
                        "\"%s\" cannot drive the spherical joint of %s (its quaternion error is "
                        "not a per-coordinate error); %s",
                        names[type], p->spherical, allowed);
    }

    /* the gains the coordinates share, designed once */
    gain_params shared = {0};
    ctc_gains gains;
    if (read_gain_params(p, v, "controller", &shared) != 0 ||
        check_required_gains(p, p->ctrl, shared.given) != 0 ||
        design_gains(p, p->ctrl, &shared, "controller", &gains) != 0) {
        return -1;
    }
    put_gain_params(p, out, &shared);
    j->gains = alloc(p, (size_t)j->nind, sizeof *j->gains);
    if (j->gains == NULL) return -1;
    for (int i = 0; i < j->nind; i++) j->gains[i] = gains;
    j->spec.gains = j->gains;

    /* per-coordinate overrides, then the controller's model */
    const cJSON *joints = member(v, "joints");
    char context[64];
    snprintf(context, sizeof context, "controller type \"%s\"", names[type]);
    if (joints != NULL && parse_gain_overrides(p, joints, p->ctrl, &shared, context, out) != 0) {
        return -1;
    }
    return parse_ctrl_model(p, v, out);
}

/* ---- the document ---- */

static const char *const job_keys[] = {"name",        "scene",      "controller", "trajectory",
                                       "disturbance", "integrator", "duration",   "output",
                                       "limits",      "threads",    NULL};

/* ---- the controller's and the document's keys and defaults, as data (job_json.h) ---- */

static const job_format_object doc_objects[] = {
    FORMAT_KEYS("", NULL, NULL, job_keys),
    FORMAT_KEYS("controller", "type", NULL, ctrl_keys_all),
    FORMAT_KEYS("controller", "type", "none", ctrl_keys[CTC_CTRL_NONE]),
    FORMAT_KEYS("controller", "type", "pd", ctrl_keys[CTC_CTRL_PD]),
    FORMAT_KEYS("controller", "type", "pid", ctrl_keys[CTC_CTRL_PID]),
    FORMAT_KEYS("controller", "type", "poles", ctrl_keys[CTC_CTRL_POLES]),
    FORMAT_KEYS("controller", "type", "lqr", ctrl_keys[CTC_CTRL_LQR]),
    FORMAT_KEYS("controller.joints[]", NULL, "pd", gain_keys[CTC_CTRL_PD]),
    FORMAT_KEYS("controller.joints[]", NULL, "pid", gain_keys[CTC_CTRL_PID]),
    FORMAT_KEYS("controller.joints[]", NULL, "poles", gain_keys[CTC_CTRL_POLES]),
    FORMAT_KEYS("controller.joints[]", NULL, "lqr", gain_keys[CTC_CTRL_LQR]),
    FORMAT_KEYS("controller.model", NULL, NULL, model_keys),
    FORMAT_KEYS("controller.poles[]", NULL, NULL, pole_keys),
    FORMAT_KEYS("controller.joints[].poles[]", NULL, NULL, pole_keys),
    FORMAT_END,
};

static const job_format_default doc_defaults[] = {
    DEFAULT_JSON("", NULL, "name", "\"" DEFAULT_NAME "\""),
    DEFAULT_NUMBER("controller.model", NULL, "mass_scale", 1),
    DEFAULT_NUMBER("controller.model", NULL, "inertia_scale", 1),
    DEFAULT_END,
};

const job_format_object *const job_format_objects[] = {doc_objects, job_scene_objects,
                                                       job_run_objects, NULL};
const job_format_default *const job_format_defaults[] = {doc_defaults, job_scene_defaults,
                                                         job_run_defaults, NULL};

/* the whole check of the spec by the library, after the format's own; what it finds wrong with
 * a loop (the mobility, the configuration at q0) is reported at the loop or at q0 */
static int check_spec(parser *p)
{
    char msg[512];
    if (p->oom) return out_of_memory(p->err);
    ctc_status st = ctc_sim_check(&p->j->spec, msg, sizeof msg);
    if (st == CTC_ENOMEM) return out_of_memory(p->err);
    if (st != CTC_OK) {
        const char *field = "";
        if (p->j->spec.chain.loop != NULL && strcmp(loop_error_field(msg), "scene") != 0) {
            field = loop_error_field(msg);
        }
        return error_at(p->err, JOB_INVALID_FIELD, field, "%s", msg);
    }
    return 0;
}

/* Parses a job document without a preset (doc's keys not repeated). */
static int parse_job(const cJSON *doc, const char *default_name, job **out, job_error *err)
{
    job *j = calloc(1, sizeof *j);
    if (j == NULL) return out_of_memory(err);
    parser p = {.j = j, .err = err, .ctrl = CTC_CTRL_NONE};
    j->normalised = p.norm = cJSON_CreateObject();
    if (p.norm == NULL || check_keys(&p, doc, "", job_keys, NULL, NULL) != 0 ||
        parse_name(&p, doc, default_name) != 0 || parse_scene(&p, doc) != 0 ||
        parse_controller(&p, doc) != 0 || parse_trajectory(&p, doc) != 0 ||
        parse_disturbance(&p, doc) != 0 || parse_integrator(&p, doc) != 0 ||
        parse_duration(&p, doc) != 0 || parse_output(&p, doc) != 0 || parse_limits(&p, doc) != 0 ||
        parse_threads(&p, doc) != 0 || check_spec(&p) != 0) {
        if (p.norm == NULL) out_of_memory(err);
        job_free(j);
        return -1;
    }
    *out = j;
    return 0;
}

/* ---- presets ---- */

/* a patch object that names another "type" or "method" than its target's starts afresh: the
 * old type's keys (a PID's ki, dopri5's rtol) do not carry over to the new one */
static int changes_kind(const cJSON *target, const cJSON *patch)
{
    static const char *const keys[] = {"type", "method"};
    for (int i = 0; i < 2; i++) {
        const cJSON *a = cJSON_GetObjectItemCaseSensitive(target, keys[i]);
        const cJSON *b = cJSON_GetObjectItemCaseSensitive(patch, keys[i]);
        if (cJSON_IsString(a) && cJSON_IsString(b) && strcmp(a->valuestring, b->valuestring) != 0)
            return 1;
    }
    return 0;
}

/* RFC 7386 merge patch: returns target (consumed) with patch applied, or NULL out of memory.
 * One refinement: an object whose "type" or "method" the patch changes is replaced whole. */
static cJSON *merge_patch(cJSON *target, const cJSON *patch)
{
    if (!cJSON_IsObject(patch) || (cJSON_IsObject(target) && changes_kind(target, patch))) {
        cJSON_Delete(target);
        return cJSON_Duplicate(patch, 1);
    }
    if (!cJSON_IsObject(target)) {
        cJSON_Delete(target);
        target = cJSON_CreateObject();
        if (target == NULL) return NULL;
    }
    for (const cJSON *m = patch->child; m != NULL; m = m->next) {
        cJSON *old = cJSON_DetachItemFromObjectCaseSensitive(target, m->string);
        if (cJSON_IsNull(m)) {
            cJSON_Delete(old); /* null removes the key */
            continue;
        }
        cJSON *merged = merge_patch(old, m);
        if (merged == NULL || !cJSON_AddItemToObject(target, m->string, merged)) {
            cJSON_Delete(merged);
            cJSON_Delete(target);
            return NULL;
        }
    }
    return target;
}

/* the names of the presets, comma-separated, into buf */
static void list_presets(char *buf, size_t len)
{
    int count;
    const preset *list = presets_list(&count);
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; i < count; i++) {
        int w = snprintf(buf + used, len - used, "%s%s", i > 0 ? ", " : "", list[i].name);
        if (w < 0 || (size_t)w >= len - used) break;
        used += (size_t)w;
    }
}

/* The document of a preset request: the preset's own, with the request's other keys merged in
 * (RFC 7386). *out owns it. */
static int expand_preset(const cJSON *request, cJSON **out, const preset **used, job_error *err)
{
    const cJSON *name = member(request, "preset");
    if (!cJSON_IsString(name)) {
        return error_at(err, JOB_INVALID_FIELD, "preset", "must be a string (got %s)", kind(name));
    }
    const preset *pr = presets_find(name->valuestring);
    if (pr == NULL) {
        char names[400];
        list_presets(names, sizeof names);
        return error_at(err, JOB_UNKNOWN_PRESET, "preset",
                        "unknown preset \"%s\" (the presets are: %s)", name->valuestring, names);
    }

    /* the patch: the request without "preset" and the preset's parameters */
    cJSON *patch = cJSON_Duplicate(request, 1);
    if (patch == NULL) return out_of_memory(err);
    cJSON_DeleteItemFromObjectCaseSensitive(patch, "preset");
    for (const char *const *param = pr->params; param != NULL && *param != NULL; param++) {
        cJSON_DeleteItemFromObjectCaseSensitive(patch, *param);
    }

    cJSON *doc = pr->build(request, err);
    if (doc == NULL) {
        cJSON_Delete(patch);
        if (err->code == JOB_OK) {
            error_at(err, JOB_INVALID_FIELD, "preset", "preset \"%s\" could not be built",
                     pr->name);
        }
        return -1;
    }
    doc = merge_patch(doc, patch);
    cJSON_Delete(patch);
    if (doc == NULL) return out_of_memory(err);
    *out = doc;
    *used = pr;
    return 0;
}

/* ---- the interface ---- */

static void clear_error(job_error *err)
{
    err->code = JOB_OK;
    err->field[0] = '\0';
    err->message[0] = '\0';
}

int job_from_json(const cJSON *doc, job **out, job_error *err)
{
    *out = NULL;
    clear_error(err);
    if (!cJSON_IsObject(doc)) {
        return error_at(err, JOB_INVALID_FIELD, "", "the job must be a JSON object (got %s)",
                        kind(doc));
    }
    if (check_repeated_keys(err, doc, "") != 0) return -1;
    if (member(doc, "preset") == NULL) return parse_job(doc, DEFAULT_NAME, out, err);

    /* a preset: expand it, then parse the result as any job */
    cJSON *expanded = NULL;
    const preset *pr = NULL;
    if (expand_preset(doc, &expanded, &pr, err) != 0) return -1;
    int rc = check_repeated_keys(err, expanded, "");
    if (rc == 0) rc = parse_job(expanded, pr->name, out, err);
    cJSON_Delete(expanded);
    if (rc == 0 && ((*out)->preset = strdup(pr->name)) == NULL) {
        job_free(*out);
        *out = NULL;
        return out_of_memory(err);
    }
    return rc;
}

static int is_json_space(char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

/* 1-based line and column (in bytes) of text[pos] */
static void line_column(const char *text, size_t pos, int *line, int *column)
{
    *line = 1;
    *column = 1;
    for (size_t i = 0; i < pos; i++) {
        if (text[i] == '\n') {
            ++*line;
            *column = 1;
        } else {
            ++*column;
        }
    }
}

int job_parse(const char *text, size_t len, job **out, job_error *err)
{
    int line, column;
    *out = NULL;
    clear_error(err);
    if (text == NULL) len = 0;
    size_t start = 0;
    while (start < len && is_json_space(text[start])) start++;
    if (start == len) return error_at(err, JOB_INVALID_JSON, "", "empty document");

    /* cJSON stops at the end of the first value: what follows must be white space */
    const char *end = NULL;
    cJSON *doc = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    if (doc == NULL) {
        size_t pos = end != NULL ? (size_t)(end - text) : 0;
        line_column(text, pos, &line, &column);
        return error_at(err, JOB_INVALID_JSON, "", "invalid JSON at line %d, column %d", line,
                        column);
    }
    size_t rest = (size_t)(end - text);
    while (rest < len && is_json_space(text[rest])) rest++;
    if (rest < len) {
        cJSON_Delete(doc);
        line_column(text, rest, &line, &column);
        return error_at(err, JOB_INVALID_JSON, "",
                        "invalid JSON at line %d, column %d: text after the end of the document",
                        line, column);
    }
    int rc = job_from_json(doc, out, err);
    cJSON_Delete(doc);
    return rc;
}

void job_free(job *j)
{
    if (j == NULL) return;
    for (int i = 0; j->traj != NULL && i < j->nind; i++) ctc_traj_free(&j->traj[i]);
    free(j->traj);
    free(j->disturb);
    free(j->gains);
    free(j->q0);
    free(j->v0);
    free(j->bodies);
    free(j->joints);
    free(j->independent);
    free(j->name);
    free(j->preset);
    cJSON_Delete(j->normalised);
    free(j);
}

const char *job_error_code_name(job_error_code c)
{
    switch (c) {
    case JOB_OK:
        return "OK";
    case JOB_INVALID_JSON:
        return "INVALID_JSON";
    case JOB_MISSING_FIELD:
        return "MISSING_FIELD";
    case JOB_UNKNOWN_FIELD:
        return "UNKNOWN_FIELD";
    case JOB_INVALID_FIELD:
        return "INVALID_FIELD";
    case JOB_UNKNOWN_PRESET:
        return "UNKNOWN_PRESET";
    case JOB_LIMIT_EXCEEDED:
        return "LIMIT_EXCEEDED";
    case JOB_NO_MEMORY:
        return "NO_MEMORY";
    }
    return "UNKNOWN";
}
