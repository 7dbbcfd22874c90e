/*
 * job_json.c - the job format (job_json.h): JSON text to a checked, runnable ctc_sim_spec and the
 * job's normalised document.
 *
 * One pass walks the document in the format's order: name, tags, scene, controller, trajectory,
 * disturbance, plant, integrator, duration, output, limits, threads. Each object's keys are checked
 * before any of its values is read, so a misspelt key is reported as unknown (with the nearest
 * valid key) rather than as the required key it was meant to be; a typed object ({"type": ...}) is
 * checked twice, against every key of its kind and then against the keys of its type. Types,
 * finiteness and the ranges the format owns (positive masses, non-zero axes, array lengths, the
 * limits) are checked here, and each error names the JSON path of the offending value. What the
 * library owns is checked by the library and reported at the nearest path with its message: a
 * controller's stability ("controller" or "controller.joints[i]", ctrl.h), a trajectory's,
 * disturbance's or integrator's parameters, a shape's dimensions, and what only ctc_model_build
 * sees - inertia tensors, a planar form asked of a spatial chain - at "scene". ctc_sim_check runs
 * last as a safety net (field "").
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
 * patch (json_merge.h, linear in the size of the request). The result is then parsed like any
 * job.
 *
 * The parser is in parts (job_parse.h): the generic reader json_read.c, the scene
 * job_scene.c, the run settings job_run.c; this file holds the controller and the entry points.
 *
 * Nothing here is global; any number of threads may parse at once. (cJSON itself records the
 * position of its last parse error in a global, which this file never reads.)
 */
#include "job_json.h"

#include <math.h>
#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_name.h"
#include "job_parse.h"
#include "json_merge.h"
#include "json_strict.h"
#include "presets.h"

/* ---- name ---- */

static int parse_name(parser *p, const cJSON *doc, const char *default_name)
{
    const char *name = default_name;
    const cJSON *v = json_member(doc, "name");
    if (v != NULL && json_name_at(p, v, "name", &name) != 0) return -1;
    p->j->name = strdup(name);
    if (p->j->name == NULL) return json_out_of_memory(p->err);
    json_put_string(p, p->norm, "name", name);
    return 0;
}

/* ---- tags ----
 *
 * Labels for finding runs again (GET /api/jobs?tag=): an array of at most JOB_MAX_TAGS distinct
 * strings of 1..JOB_MAX_TAG bytes, none holding a control character. Written to the normalised
 * document only when given, as given. */

static int parse_tags(parser *p, const cJSON *doc)
{
    const cJSON *v = json_member(doc, "tags");
    if (v == NULL) return 0;
    if (!cJSON_IsArray(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "tags",
                             "must be an array of strings (got %s)", json_kind(v));
    }
    int n = cJSON_GetArraySize(v);
    if (n > JOB_MAX_TAGS) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "tags",
                             "must have at most %d tags (got %d)", JOB_MAX_TAGS, n);
    }
    cJSON *out = json_put(p, p->norm, "tags", cJSON_CreateArray());
    int i = 0;
    for (const cJSON *t = v->child; t != NULL; t = t->next, i++) {
        char path[32];
        snprintf(path, sizeof path, "tags[%d]", i);
        if (!cJSON_IsString(t)) {
            return json_error_at(p->err, JOB_INVALID_FIELD, path, "must be a string (got %s)",
                                 json_kind(t));
        }
        size_t len = strlen(t->valuestring);
        if (len == 0 || len > JOB_MAX_TAG) {
            return json_error_at(p->err, JOB_INVALID_FIELD, path,
                                 "must be 1 to %d bytes long (got %zu)", JOB_MAX_TAG, len);
        }
        for (size_t k = 0; k < len; k++) {
            if ((unsigned char)t->valuestring[k] < 0x20 || t->valuestring[k] == 0x7f) {
                return json_error_at(p->err, JOB_INVALID_FIELD, path,
                                     "must not hold a control character (byte %zu)", k);
            }
        }
        for (const cJSON *u = v->child; u != t; u = u->next) {
            if (strcmp(u->valuestring, t->valuestring) == 0) {
                return json_error_at(p->err, JOB_INVALID_FIELD, path, "repeats tag \"%s\"",
                                     t->valuestring);
            }
        }
        if (out != NULL) cJSON_AddItemToArray(out, cJSON_CreateString(t->valuestring));
    }
    if (out == NULL || cJSON_GetArraySize(out) != n) p->oom = 1;
    return 0;
}

/* ---- controller ----
 *
 * Every kind comes from the table of controller classes (ctrl.h ctc_ctrl_classes): its name is
 * "controller.type", its parameter keys (ctc_ctrl_param_name) are the ones "controller" and each
 * "controller.joints" entry accept, its required keys and kp/kv-or-zeta/tau pair are checked
 * here, and its design turns the parameters into gains. The key lists below are built from the
 * table, in the order of the CTC_CP_* bits. */

/* The design parameters of one coordinate, as read from "controller" or an override. */
typedef struct gain_params {
    ctc_ctrl_params v; /* v.given: CTC_CP_* bits of the keys present */
    int q_diagonal;    /* Q was given as its diagonal */
} gain_params;

enum {
    G_PAIR_KP = CTC_CP_KP | CTC_CP_KV,
    G_PAIR_ZETA = CTC_CP_ZETA | CTC_CP_TAU,
    /* the longest key list: "type", every parameter, "joints", "model", "sample_period",
       "sample_delay", "seed" and the terminator */
    KEYS_MAX = CTC_CP_COUNT + 7,
};

/* NULL-terminated into out: first (if not NULL), the parameter keys of the bits in params, then
 * the keys of tail (NULL-terminated; may be NULL) */
static void param_keys(const char *first, unsigned params, const char *const *tail,
                       const char *out[KEYS_MAX])
{
    int n = 0;
    if (first != NULL) out[n++] = first;
    for (int i = 0; i < CTC_CP_COUNT; i++)
        if (params & (1u << i)) out[n++] = ctc_ctrl_param_name(1u << i);
    for (int i = 0; tail != NULL && tail[i] != NULL; i++) out[n++] = tail[i];
    out[n] = NULL;
}

/* every parameter key any kind takes */
#define ALL_PARAMS ((1u << CTC_CP_COUNT) - 1u)

/* The controller's keys, made once from the class table (ctrl.h ctc_ctrl_classes) and read by
 * parse_controller and parse_gain_overrides, and, as the same arrays, by the format's tables
 * (job_format_object_tables): "controller" with the keys of every kind together and per kind,
 * and "controller.joints[]" entries per kind that has a law. */
static struct {
    const char *names[CTC_CTRL_NTYPES];
    const char *all[KEYS_MAX];
    const char *by_type[CTC_CTRL_NTYPES][KEYS_MAX];
    const char *const *by_type_list[CTC_CTRL_NTYPES];
    const char *joint_all[KEYS_MAX];
    const char *joint[CTC_CTRL_NTYPES][KEYS_MAX];
    job_format_object rows[2 * CTC_CTRL_NTYPES + 2];
} ctrl_format;
static pthread_once_t ctrl_format_once = PTHREAD_ONCE_INIT;

static void build_ctrl_format(void)
{
    static const char *const shared_keys[] = {"joints",       "model", "sample_period",
                                              "sample_delay", "seed",  NULL};
    int n = 0;
    param_keys("type", ALL_PARAMS, shared_keys, ctrl_format.all);
    param_keys(NULL, ALL_PARAMS, NULL, ctrl_format.joint_all);
    ctrl_format.rows[n++] =
        (job_format_object)FORMAT_KEYS("controller", "type", NULL, ctrl_format.all);
    for (int t = 0; t < CTC_CTRL_NTYPES; t++) {
        const ctc_ctrl_class *c = ctc_ctrl_classes[t];
        ctrl_format.names[t] = c->name;
        param_keys("type", c->params, c->law != NULL ? shared_keys : NULL, ctrl_format.by_type[t]);
        ctrl_format.by_type_list[t] = ctrl_format.by_type[t];
        param_keys(NULL, c->params, NULL, ctrl_format.joint[t]);
        ctrl_format.rows[n++] =
            (job_format_object)FORMAT_KEYS("controller", "type", c->name, ctrl_format.by_type[t]);
    }
    for (int t = 0; t < CTC_CTRL_NTYPES; t++) {
        const ctc_ctrl_class *c = ctc_ctrl_classes[t];
        if (c->law == NULL) continue;
        ctrl_format.rows[n++] = (job_format_object)FORMAT_KEYS("controller.joints[]", NULL, c->name,
                                                               ctrl_format.joint[t]);
    }
    ctrl_format.rows[n] = (job_format_object)FORMAT_END;
}

/* the keys of a complex pole, and of the controller's model */
static const char *const pole_keys[] = {"re", "im", NULL};
static const char *const model_keys[] = {"mass_scale", "inertia_scale", "bodies", "gravity",
                                         "payload",    "random",        NULL};

/* "poles": three entries, each a real pole or {"re": x, "im": y} */
static int poles_at(parser *p, const cJSON *v, const char *path, double re[3], double im[3])
{
    char got[32], at[PATH_LEN];
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 3) {
        return json_error_at(p->err, JOB_INVALID_FIELD, path,
                             "must be an array of 3 poles (got %s)", json_describe(got, v));
    }
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        json_index_path(at, path, i);
        im[i] = 0;
        if (cJSON_IsNumber(e)) {
            if (json_number_at(p, e, at, &re[i]) != 0) return -1;
        } else if (cJSON_IsObject(e)) {
            if (json_check_keys(p, e, at, pole_keys, NULL, NULL) != 0 ||
                json_member_number(p, e, at, "re", REQUIRED, 0, &re[i]) != 0 ||
                json_member_number(p, e, at, "im", REQUIRED, 0, &im[i]) != 0) {
                return -1;
            }
        } else {
            return json_error_at(p->err, JOB_INVALID_FIELD, at,
                                 "must be a number or an object {\"re\": x, \"im\": y} (got %s)",
                                 json_kind(e));
        }
    }
    return 0;
}

/* one scalar gain key of obj (at path), if present */
static int read_gain(parser *p, const cJSON *obj, const char *path, const char *key, unsigned bit,
                     double *x, unsigned *given)
{
    char at[PATH_LEN];
    const cJSON *v = json_member(obj, key);
    if (v == NULL) return 0;
    if (json_number_at(p, v, json_key_path(at, path, key), x) != 0) return -1;
    *given |= bit;
    return 0;
}

/* the gain keys present in obj (at path; its keys already checked) */
static int read_gain_params(parser *p, const cJSON *obj, const char *path, gain_params *g)
{
    char at[PATH_LEN];
    const cJSON *v;
    ctc_ctrl_params *x = &g->v;
    if (read_gain(p, obj, path, "kp", CTC_CP_KP, &x->kp, &x->given) != 0 ||
        read_gain(p, obj, path, "kv", CTC_CP_KV, &x->kv, &x->given) != 0 ||
        read_gain(p, obj, path, "ki", CTC_CP_KI, &x->ki, &x->given) != 0 ||
        read_gain(p, obj, path, "zeta", CTC_CP_ZETA, &x->zeta, &x->given) != 0 ||
        read_gain(p, obj, path, "tau", CTC_CP_TAU, &x->tau, &x->given) != 0 ||
        read_gain(p, obj, path, "lambda", CTC_CP_LAMBDA, &x->lambda, &x->given) != 0) {
        return -1;
    }
    if ((v = json_member(obj, "poles")) != NULL) {
        if (poles_at(p, v, json_key_path(at, path, "poles"), x->re, x->im) != 0) return -1;
        x->given |= CTC_CP_POLES;
    }
    if ((v = json_member(obj, "Q")) != NULL) {
        if (json_matrix3_at(p, v, json_key_path(at, path, "Q"), "diagonal entries", x->Q,
                            &g->q_diagonal) != 0) {
            return -1;
        }
        x->given |= CTC_CP_Q;
    }
    return 0;
}

/* pd and pid take "kp" and "kv", or "zeta" and "tau": exactly one whole pair (bits given) */
static int check_gain_pair(parser *p, unsigned given, const char *path)
{
    char at[PATH_LEN];
    if ((given & G_PAIR_KP) && (given & G_PAIR_ZETA)) {
        return json_error_at(
            p->err, JOB_INVALID_FIELD,
            json_key_path(at, path, given & CTC_CP_ZETA ? "zeta" : "tau"),
            "cannot be combined with \"kp\" and \"kv\" (give \"kp\" and \"kv\", or "
            "\"zeta\" and \"tau\")");
    }
    if (!(given & (G_PAIR_KP | G_PAIR_ZETA))) {
        return json_error_at(p->err, JOB_MISSING_FIELD, json_key_path(at, path, "kp"),
                             "is required (or give \"zeta\" and \"tau\")");
    }
    static const struct {
        unsigned bit, partner;
        const char *key, *partner_key;
    } pairs[] = {{CTC_CP_KP, CTC_CP_KV, "kp", "kv"},
                 {CTC_CP_KV, CTC_CP_KP, "kv", "kp"},
                 {CTC_CP_ZETA, CTC_CP_TAU, "zeta", "tau"},
                 {CTC_CP_TAU, CTC_CP_ZETA, "tau", "zeta"}};
    for (int i = 0; i < 4; i++) {
        if ((given & pairs[i].bit) && !(given & pairs[i].partner)) {
            return json_error_at(p->err, JOB_MISSING_FIELD,
                                 json_key_path(at, path, pairs[i].partner_key),
                                 "is required with \"%s\"", pairs[i].key);
        }
    }
    return 0;
}

/* the keys the controller object itself must give for its kind: the class's required ones, in
 * bit order, then its pair */
static int check_required_gains(parser *p, const ctc_ctrl_class *cls, unsigned given)
{
    char at[PATH_LEN];
    for (int i = 0; i < CTC_CP_COUNT; i++) {
        unsigned bit = 1u << i;
        if ((cls->required & bit) && !(given & bit)) {
            return json_error_at(p->err, JOB_MISSING_FIELD,
                                 json_key_path(at, "controller", ctc_ctrl_param_name(bit)),
                                 "is required");
        }
    }
    return cls->gain_pair ? check_gain_pair(p, given, "controller") : 0;
}

/* g with the override o applied key by key; a pd/pid pair in o replaces the other pair in g */
static void merge_gains(gain_params *g, const gain_params *o)
{
    ctc_ctrl_params *x = &g->v;
    const ctc_ctrl_params *y = &o->v;
    if ((y->given & G_PAIR_KP) && !(y->given & G_PAIR_ZETA)) x->given &= ~(unsigned)G_PAIR_ZETA;
    if ((y->given & G_PAIR_ZETA) && !(y->given & G_PAIR_KP)) x->given &= ~(unsigned)G_PAIR_KP;
    if (y->given & CTC_CP_KP) x->kp = y->kp;
    if (y->given & CTC_CP_KV) x->kv = y->kv;
    if (y->given & CTC_CP_KI) x->ki = y->ki;
    if (y->given & CTC_CP_ZETA) x->zeta = y->zeta;
    if (y->given & CTC_CP_TAU) x->tau = y->tau;
    if (y->given & CTC_CP_POLES) {
        memcpy(x->re, y->re, sizeof x->re);
        memcpy(x->im, y->im, sizeof x->im);
    }
    if (y->given & CTC_CP_Q) {
        memcpy(x->Q, y->Q, sizeof x->Q);
        g->q_diagonal = o->q_diagonal;
    }
    if (y->given & CTC_CP_LAMBDA) x->lambda = y->lambda;
    x->given |= y->given;
}

/* the gains of g by the class's design; its errors at field */
static int design_gains(parser *p, const ctc_ctrl_class *cls, const gain_params *g,
                        const char *field, ctc_gains *out)
{
    char msg[512];
    ctc_status st = cls->design != NULL ? cls->design(&g->v, out, msg, sizeof msg) : CTC_OK;
    if (st == CTC_ENOMEM) return json_out_of_memory(p->err);
    if (st != CTC_OK) return json_error_at(p->err, JOB_INVALID_FIELD, field, "%s", msg);
    return 0;
}

/* the keys of g that were given, in canonical order */
static void put_gain_params(parser *p, cJSON *out, const gain_params *gp)
{
    const ctc_ctrl_params *g = &gp->v;
    if (g->given & CTC_CP_KP) json_put_number(p, out, "kp", g->kp);
    if (g->given & CTC_CP_KV) json_put_number(p, out, "kv", g->kv);
    if (g->given & CTC_CP_ZETA) json_put_number(p, out, "zeta", g->zeta);
    if (g->given & CTC_CP_TAU) json_put_number(p, out, "tau", g->tau);
    if (g->given & CTC_CP_KI) json_put_number(p, out, "ki", g->ki);
    if (g->given & CTC_CP_POLES) {
        cJSON *poles = json_put(p, out, "poles", cJSON_CreateArray());
        for (int i = 0; i < 3; i++) {
            if (g->im[i] == 0) {
                json_put_number(p, poles, NULL, g->re[i]);
                continue;
            }
            cJSON *pole = json_put(p, poles, NULL, cJSON_CreateObject());
            json_put_number(p, pole, "re", g->re[i]);
            json_put_number(p, pole, "im", g->im[i]);
        }
    }
    if (g->given & CTC_CP_Q) json_put_matrix3(p, out, "Q", g->Q, gp->q_diagonal);
    if (g->given & CTC_CP_LAMBDA) json_put_number(p, out, "lambda", g->lambda);
}

/* what one entry of a per-coordinate array stands for, in messages */
const char *coordinate_word(const parser *p)
{
    return p->j->spec.chain.loop != NULL ? "independent coordinate" : "coordinate";
}

/* "controller.joints": nind overrides of the shared parameters, one per coordinate */
static int parse_gain_overrides(parser *p, const cJSON *v, const ctc_ctrl_class *cls,
                                const gain_params *shared, const char *context, cJSON *out_ctrl)
{
    job *j = p->j;
    char path[PATH_LEN];
    const char *const *mine_keys = ctrl_format.joint[p->ctrl];
    const char *const *all_keys = ctrl_format.joint_all;
    if (!cJSON_IsArray(v)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "controller.joints",
                             "must be an array of %d objects, one per %s (got %s)", j->nind,
                             coordinate_word(p), json_kind(v));
    }
    int len = cJSON_GetArraySize(v);
    if (len != j->nind) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "controller.joints",
                             "must have %d entries, one per %s (got %d)", j->nind,
                             coordinate_word(p), len);
    }
    cJSON *out = json_put(p, out_ctrl, "joints", cJSON_CreateArray());
    int i = 0;
    for (const cJSON *e = v->child; e != NULL; e = e->next, i++) {
        gain_params override = {0};
        json_index_path(path, "controller.joints", i);
        if (json_object_at(p, e, path) != 0 ||
            json_check_keys(p, e, path, mine_keys, all_keys, context) != 0 ||
            read_gain_params(p, e, path, &override) != 0) {
            return -1;
        }
        put_gain_params(p, json_put(p, out, NULL, cJSON_CreateObject()), &override);
        if (override.v.given == 0) continue; /* {} keeps the shared gains */

        gain_params mine = *shared;
        merge_gains(&mine, &override);
        if (cls->gain_pair && check_gain_pair(p, mine.v.given, path) != 0) {
            return -1;
        }
        if (design_gains(p, cls, &mine, path, &j->gains[i]) != 0) return -1;
    }
    return 0;
}

/* "controller.model": the controller's model of the plant */
static int parse_ctrl_model(parser *p, const cJSON *ctrl, cJSON *out_ctrl)
{
    const char *keys[2] = {"mass_scale", "inertia_scale"};
    double *scales[2] = {&p->j->spec.model_mass_scale, &p->j->spec.model_inertia_scale};
    const cJSON *v = json_member(ctrl, "model");
    if (v != NULL && (json_object_at(p, v, "controller.model") != 0 ||
                      json_check_keys(p, v, "controller.model", model_keys, NULL, NULL) != 0)) {
        return -1;
    }
    cJSON *out = json_put(p, out_ctrl, "model", cJSON_CreateObject());
    for (int i = 0; i < 2; i++) {
        char at[PATH_LEN];
        if (json_member_number(p, v, "controller.model", keys[i], OPTIONAL, 1.0, scales[i]) != 0) {
            return -1;
        }
        if (!(*scales[i] > 0)) {
            return json_error_at(p->err, JOB_INVALID_FIELD,
                                 json_key_path(at, "controller.model", keys[i]),
                                 "must be positive (got %g)", *scales[i]);
        }
        json_put_number(p, out, keys[i], *scales[i]);
    }
    return parse_model_bodies(p, v, out);
}

/* "controller.sample_period" (s >= 0, 0 = continuous) and "controller.sample_delay" (whole
 * samples >= 0, only with a period), at most JOB_MAX_CONTROL_SAMPLES samples in the run */
static int parse_sampling(parser *p, const cJSON *ctrl, cJSON *out_ctrl)
{
    ctc_sim_spec *s = &p->j->spec;
    double delay;
    if (json_member_number(p, ctrl, "controller", "sample_period", OPTIONAL, 0,
                           &s->sample_period) != 0 ||
        json_member_number(p, ctrl, "controller", "sample_delay", OPTIONAL, 0, &delay) != 0) {
        return -1;
    }
    if (!(s->sample_period >= 0)) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "controller.sample_period",
                             "must be non-negative (got %g s; 0 = a continuous controller)",
                             s->sample_period);
    }
    if (!(delay >= 0 && delay <= CTC_SIM_MAX_DELAY && delay == floor(delay))) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "controller.sample_delay",
                             "must be a whole number of samples from 0 to %d (got %g)",
                             CTC_SIM_MAX_DELAY, delay);
    }
    if (delay > 0 && s->sample_period == 0) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "controller.sample_delay",
                             "needs \"sample_period\" (a continuous controller has no samples to "
                             "delay)");
    }
    s->sample_delay = (int)delay;
    double seed;
    if (json_member_number(p, ctrl, "controller", "seed", OPTIONAL, 0, &seed) != 0) return -1;
    if (!(seed >= 0 && seed <= 9007199254740992.0 && seed == floor(seed))) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "controller.seed",
                             "must be a whole number from 0 to 2^53 (got %g)", seed);
    }
    s->seed = (unsigned long long)seed;
    json_put_number(p, out_ctrl, "sample_period", s->sample_period);
    json_put_number(p, out_ctrl, "sample_delay", delay);
    json_put_number(p, out_ctrl, "seed", seed);
    return 0;
}

static int parse_controller(parser *p, const cJSON *doc)
{
    job *j = p->j;
    const char *const *names = ctrl_format.names;
    int type;
    pthread_once(&ctrl_format_once, build_ctrl_format);
    const cJSON *v =
        json_required_member(p, doc, "", "controller", " ({\"type\": \"none\"} for a passive run)");
    if (v == NULL || json_typed_object(p, v, "controller", "type", REQUIRED, 0, names,
                                       CTC_CTRL_NTYPES, "controller type", ctrl_format.by_type_list,
                                       ctrl_format.all, &type) != 0) {
        return -1;
    }
    const ctc_ctrl_class *cls = ctc_ctrl_classes[type];
    p->ctrl = j->spec.controller = (ctc_ctrl_type)type;
    j->spec.model_mass_scale = j->spec.model_inertia_scale = 1.0;
    cJSON *out = json_put(p, p->norm, "controller", cJSON_CreateObject());
    json_put_string(p, out, "type", names[type]);
    if (cls->law == NULL) return 0; /* passive */

    /* computed torque control per coordinate: not for a joint whose error has no per-coordinate
       form (the spherical joint's quaternion) */
    if (p->undriven[0] != '\0') {
        const char *kind = ctc_joint_type_name(p->undriven_type);
        char allowed[160];
        if (j->spec.chain.loop != NULL)
            snprintf(allowed, sizeof allowed,
                     "a %s joint in a loop must be dependent, or the run passive (controller "
                     "\"none\")",
                     kind);
        else
            snprintf(allowed, sizeof allowed, "%s joints are allowed only with controller \"none\"",
                     kind);
        return json_error_at(p->err, JOB_INVALID_FIELD, "controller.type",
                             "\"%s\" cannot drive the %s joint of %s (%s); %s", names[type], kind,
                             p->undriven, ctc_joint_classes[p->undriven_type].undriven, allowed);
    }

    if (cls->force != CTC_FORCE_COMPUTED_TORQUE && j->spec.chain.loop != NULL) {
        return json_error_at(p->err, JOB_INVALID_FIELD, "controller.type",
                             "\"%s\" needs an open chain (its model's desired or resting state is "
                             "not defined for a loop's dependent joints)",
                             names[type]);
    }

    /* the gains the coordinates share, designed once */
    gain_params shared = {0};
    ctc_gains gains = {0};
    if (read_gain_params(p, v, "controller", &shared) != 0 ||
        check_required_gains(p, cls, shared.v.given) != 0 ||
        design_gains(p, cls, &shared, "controller", &gains) != 0) {
        return -1;
    }
    put_gain_params(p, out, &shared);
    j->gains = json_alloc(p, (size_t)j->nind, sizeof *j->gains);
    if (j->gains == NULL) return -1;
    for (int i = 0; i < j->nind; i++) j->gains[i] = gains;
    j->spec.gains = j->gains;

    /* per-coordinate overrides, then the controller's model */
    const cJSON *joints = json_member(v, "joints");
    char context[64];
    snprintf(context, sizeof context, "controller type \"%s\"", names[type]);
    if (joints != NULL && parse_gain_overrides(p, joints, cls, &shared, context, out) != 0) {
        return -1;
    }
    if (parse_ctrl_model(p, v, out) != 0) return -1;
    return parse_sampling(p, v, out);
}

/* ---- the document ---- */

static const char *const job_keys[] = {
    "name",     "tags",       "scene",    "controller", "trajectory", "disturbance", "plant",
    "wrenches", "integrator", "duration", "output",     "limits",     "threads",     NULL};

/* ---- the controller's and the document's keys and defaults, as data (job_json.h) ---- */

static const job_format_object doc_objects[] = {
    FORMAT_KEYS("", NULL, NULL, job_keys),
    FORMAT_KEYS("controller.model", NULL, NULL, model_keys),
    FORMAT_KEYS("controller.poles[]", NULL, NULL, pole_keys),
    FORMAT_KEYS("controller.joints[].poles[]", NULL, NULL, pole_keys),
    FORMAT_END,
};

static const job_format_default doc_defaults[] = {
    DEFAULT_JSON("", NULL, "name", "\"" DEFAULT_NAME "\""),
    DEFAULT_NUMBER("controller.model", NULL, "mass_scale", 1),
    DEFAULT_NUMBER("controller.model", NULL, "inertia_scale", 1),
    DEFAULT_NUMBER("controller", "pd", "sample_period", 0),
    DEFAULT_NUMBER("controller", "pd", "sample_delay", 0),
    DEFAULT_NUMBER("controller", "pid", "sample_period", 0),
    DEFAULT_NUMBER("controller", "pid", "sample_delay", 0),
    DEFAULT_NUMBER("controller", "poles", "sample_period", 0),
    DEFAULT_NUMBER("controller", "poles", "sample_delay", 0),
    DEFAULT_NUMBER("controller", "lqr", "sample_period", 0),
    DEFAULT_NUMBER("controller", "lqr", "sample_delay", 0),
    DEFAULT_NUMBER("controller", "joint_pd", "sample_period", 0),
    DEFAULT_NUMBER("controller", "joint_pd", "sample_delay", 0),
    DEFAULT_NUMBER("controller", "pd_gravity", "sample_period", 0),
    DEFAULT_NUMBER("controller", "pd_gravity", "sample_delay", 0),
    DEFAULT_NUMBER("controller", "feedforward", "sample_period", 0),
    DEFAULT_NUMBER("controller", "feedforward", "sample_delay", 0),
    DEFAULT_NUMBER("controller", "pd", "seed", 0),
    DEFAULT_NUMBER("controller", "pid", "seed", 0),
    DEFAULT_NUMBER("controller", "poles", "seed", 0),
    DEFAULT_NUMBER("controller", "lqr", "seed", 0),
    DEFAULT_NUMBER("controller", "joint_pd", "seed", 0),
    DEFAULT_NUMBER("controller", "pd_gravity", "seed", 0),
    DEFAULT_NUMBER("controller", "feedforward", "seed", 0),
    DEFAULT_END,
};

const job_format_object *const *job_format_object_tables(void)
{
    static const job_format_object *const tables[] = {
        doc_objects,     ctrl_format.rows,  job_scene_objects, job_scene_joint_objects,
        job_run_objects, job_plant_objects, job_model_objects, NULL};
    pthread_once(&ctrl_format_once, build_ctrl_format);
    job_scene_joint_format();
    return tables;
}

const job_format_default *const job_format_defaults[] = {
    doc_defaults, job_scene_defaults, job_run_defaults, job_plant_defaults, NULL};

/* the whole check of the spec by the library, after the format's own; what it finds wrong with
 * a loop (the mobility, the configuration at q0) is reported at the loop or at q0 */
static int check_spec(parser *p)
{
    char msg[512];
    if (p->oom) return json_out_of_memory(p->err);
    ctc_status st = ctc_sim_check(&p->j->spec, msg, sizeof msg);
    if (st == CTC_ENOMEM) return json_out_of_memory(p->err);
    if (st != CTC_OK) {
        const char *field = "";
        if (p->j->spec.chain.loop != NULL && strcmp(loop_error_field(msg), "scene") != 0) {
            field = loop_error_field(msg);
        }
        return json_error_at(p->err, JOB_INVALID_FIELD, field, "%s", msg);
    }
    return 0;
}

/* Parses a job document without a preset (doc's keys not repeated). */
static int parse_job(const cJSON *doc, const char *default_name, job **out, job_error *err)
{
    job *j = calloc(1, sizeof *j);
    if (j == NULL) return json_out_of_memory(err);
    parser p = {.j = j, .err = err, .ctrl = CTC_CTRL_NONE};
    j->normalised = p.norm = cJSON_CreateObject();
    if (p.norm == NULL || json_check_keys(&p, doc, "", job_keys, NULL, NULL) != 0 ||
        parse_name(&p, doc, default_name) != 0 || parse_tags(&p, doc) != 0 ||
        parse_scene(&p, doc) != 0 || parse_controller(&p, doc) != 0 ||
        parse_trajectory(&p, doc) != 0 || parse_disturbance(&p, doc) != 0 ||
        parse_plant(&p, doc) != 0 || parse_wrenches(&p, doc) != 0 ||
        parse_integrator(&p, doc) != 0 || parse_duration(&p, doc) != 0 ||
        parse_output(&p, doc) != 0 || parse_limits(&p, doc) != 0 || parse_threads(&p, doc) != 0 ||
        check_spec(&p) != 0) {
        if (p.norm == NULL) json_out_of_memory(err);
        job_free(j);
        return -1;
    }
    *out = j;
    return 0;
}

/* ---- presets ---- */

/* the names of the presets, comma-separated, into buf; names that do not fit whole are left
 * out and the list ends with ", ..." */
static void list_presets(char *buf, size_t len)
{
    static const char more[] = ", ...";
    int count;
    const preset *list = presets_list(&count);
    size_t used = 0;
    buf[0] = '\0';
    for (int i = 0; i < count; i++) {
        size_t need = (i > 0 ? 2 : 0) + strlen(list[i].name);
        if (used + need + sizeof more > len) { /* keep room for ", ..." and the NUL */
            memcpy(buf + used, more, sizeof more);
            return;
        }
        used += (size_t)snprintf(buf + used, len - used, "%s%s", i > 0 ? ", " : "", list[i].name);
    }
}

/* The document of a preset request: the preset's own, with the request's other keys merged in
 * (RFC 7386). *out owns it. */
static int expand_preset(const cJSON *request, cJSON **out, const preset **used, job_error *err)
{
    const cJSON *name = json_member(request, "preset");
    if (!cJSON_IsString(name)) {
        return json_error_at(err, JOB_INVALID_FIELD, "preset", "must be a string (got %s)",
                             json_kind(name));
    }
    const preset *pr = presets_find(name->valuestring);
    if (pr == NULL) {
        /* the list within err->message, with room for the rest of the sentence */
        char names[sizeof err->message - 64];
        list_presets(names, sizeof names);
        return json_error_at(err, JOB_UNKNOWN_PRESET, "preset",
                             "unknown preset \"%s\" (the presets are: %s)", name->valuestring,
                             names);
    }

    /* the patch: the request without "preset" and the preset's parameters */
    cJSON *patch = cJSON_Duplicate(request, 1);
    if (patch == NULL) return json_out_of_memory(err);
    cJSON_DeleteItemFromObjectCaseSensitive(patch, "preset");
    for (const char *const *param = pr->params; param != NULL && *param != NULL; param++) {
        cJSON_DeleteItemFromObjectCaseSensitive(patch, *param);
    }

    cJSON *doc = pr->build(request, err);
    if (doc == NULL) {
        cJSON_Delete(patch);
        if (err->code == JOB_OK) {
            json_error_at(err, JOB_INVALID_FIELD, "preset", "preset \"%s\" could not be built",
                          pr->name);
        }
        return -1;
    }
    /* the controller type the preset's name speaks of, before the patch may change it */
    char preset_ctrl[16] = "";
    const cJSON *ctrl_type = json_member(json_member(doc, "controller"), "type");
    if (cJSON_IsString(ctrl_type))
        snprintf(preset_ctrl, sizeof preset_ctrl, "%s", ctrl_type->valuestring);

    doc = json_merge_patch(doc, patch, NULL);
    cJSON_Delete(patch);
    if (doc == NULL) return json_out_of_memory(err);

    /* a controller of another type, with no name given: the name says which (presets.h) */
    ctrl_type = json_member(json_member(doc, "controller"), "type");
    const cJSON *preset_name = json_member(doc, "name");
    if (json_member(request, "name") == NULL && cJSON_IsString(ctrl_type) &&
        cJSON_IsString(preset_name) && strcmp(ctrl_type->valuestring, preset_ctrl) != 0) {
        char renamed[JOB_MAX_NAME + 1];
        if (presets_name_for_controller(preset_name->valuestring, preset_ctrl,
                                        ctrl_type->valuestring, renamed, sizeof renamed) == 0) {
            cJSON *v = cJSON_CreateString(renamed);
            if (v == NULL || !cJSON_ReplaceItemInObjectCaseSensitive(doc, "name", v)) {
                cJSON_Delete(v);
                cJSON_Delete(doc);
                return json_out_of_memory(err);
            }
        }
    }
    *out = doc;
    *used = pr;
    return 0;
}

/* A preset job whose request names it not, or names it as the preset's own document does, is
 * named after what the request changed (job_name.h): its normalised document against the one
 * of the preset alone, built from the request's preset parameters ("n_link_pendulum, n = 64,
 * kp = 40"). A "name": null keeps the preset's key; a run with another controller keeps the
 * name expand_preset gave it. 0, or -1 with *err set. */
static int name_edit(const cJSON *request, const preset *pr, job *j, job_error *err)
{
    cJSON *own = pr->build(request, err);
    if (own == NULL) return err->code == JOB_OK ? json_out_of_memory(err) : -1;
    const cJSON *own_name = json_member(own, "name");
    const cJSON *asked = json_member(request, "name");
    if (asked != NULL && !(cJSON_IsString(asked) && cJSON_IsString(own_name) &&
                           strcmp(asked->valuestring, own_name->valuestring) == 0)) {
        cJSON_Delete(own);
        return 0; /* a name of the user's own */
    }
    job *base = NULL;
    job_error ignored;
    int rc = parse_job(own, pr->name, &base, &ignored);
    cJSON_Delete(own);
    if (rc != 0) {
        /* a preset that does not parse alone is a bug of the preset's; the job keeps its name */
        return ignored.code == JOB_NO_MEMORY ? json_out_of_memory(err) : 0;
    }
    /* another controller with a name of its own (expand_preset): that name says the change */
    if (strcmp(j->name, base->name) != 0) {
        job_free(base);
        return 0;
    }
    /* the preset's key and the parameters the request gives it ("n_link_pendulum, n = 64") */
    char base_name[JOB_MAX_NAME + 1], name[JOB_MAX_NAME + 1];
    size_t used = (size_t)snprintf(base_name, sizeof base_name, "%s", pr->name);
    for (const char *const *param = pr->params; param != NULL && *param != NULL; param++) {
        const cJSON *v = json_member(request, *param);
        if (cJSON_IsNumber(v) && used < sizeof base_name)
            used += (size_t)snprintf(base_name + used, sizeof base_name - used, ", %s = %g", *param,
                                     v->valuedouble);
    }
    int n = job_name_changes(base->normalised, j->normalised, base_name, name, sizeof name);
    job_free(base);
    if (n == 0) return 0;
    char *copy = strdup(name);
    cJSON *v = cJSON_CreateString(name);
    if (copy == NULL || v == NULL ||
        !cJSON_ReplaceItemInObjectCaseSensitive(j->normalised, "name", v)) {
        free(copy);
        cJSON_Delete(v);
        return json_out_of_memory(err);
    }
    free(j->name);
    j->name = copy;
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
        return json_error_at(err, JOB_INVALID_FIELD, "", "the job must be a JSON object (got %s)",
                             json_kind(doc));
    }
    if (json_check_repeated_keys(err, doc, "") != 0) return -1;
    if (json_member(doc, "preset") == NULL) return parse_job(doc, DEFAULT_NAME, out, err);

    /* a preset: expand it, then parse the result as any job */
    cJSON *expanded = NULL;
    const preset *pr = NULL;
    if (expand_preset(doc, &expanded, &pr, err) != 0) return -1;
    int rc = json_check_repeated_keys(err, expanded, "");
    if (rc == 0) rc = parse_job(expanded, pr->name, out, err);
    cJSON_Delete(expanded);
    if (rc == 0 && ((*out)->preset = strdup(pr->name)) == NULL) rc = json_out_of_memory(err);
    if (rc == 0) rc = name_edit(doc, pr, *out, err);
    if (rc != 0) {
        job_free(*out);
        *out = NULL;
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
    if (start == len) return json_error_at(err, JOB_INVALID_JSON, "", "empty document");

    /* cJSON stops at the end of the first value: what follows must be white space */
    const char *end = NULL;
    cJSON *doc = cJSON_ParseWithLengthOpts(text, len, &end, 0);
    size_t cjson_pos = SIZE_MAX; /* where cJSON failed, or the text after the document */
    if (doc == NULL) {
        cjson_pos = end != NULL ? (size_t)(end - text) : 0;
    } else {
        size_t rest = (size_t)(end - text);
        while (rest < len && is_json_space(text[rest])) rest++;
        if (rest < len) cjson_pos = rest;
    }
    /* what cJSON takes but RFC 8259 does not ("01", "1.", "\u0000"): the first error wins */
    size_t strict_pos = SIZE_MAX;
    const char *why = NULL;
    if (json_strict_check(text, len, &strict_pos, &why) != 0 && strict_pos < cjson_pos) {
        cJSON_Delete(doc);
        line_column(text, strict_pos, &line, &column);
        return json_error_at(err, JOB_INVALID_JSON, "", "invalid JSON at line %d, column %d: %s",
                             line, column, why);
    }
    if (doc == NULL) {
        line_column(text, cjson_pos, &line, &column);
        return json_error_at(err, JOB_INVALID_JSON, "", "invalid JSON at line %d, column %d", line,
                             column);
    }
    if (cjson_pos != SIZE_MAX) {
        cJSON_Delete(doc);
        line_column(text, cjson_pos, &line, &column);
        return json_error_at(
            err, JOB_INVALID_JSON, "",
            "invalid JSON at line %d, column %d: text after the end of the document", line, column);
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
    free(j->plant);
    free(j->model_bodies);
    free(j->pose_bodies);
    free(j->wrenches);
    free(j->gains);
    free(j->q0);
    free(j->v0);
    free(j->bodies);
    free(j->joints);
    free(j->parent);
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
