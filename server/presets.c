/*
 * presets.c - the paper's scenes as complete job documents (presets.h; Kingsley et al. 2017,
 * sections 7.1 and 7.3; DESIGN.md section 7).
 *
 * Each preset writes out every part of the job (job_json.h) that the paper fixes, so the document
 * `ctcsim preset NAME` prints is the experiment itself and reads without this file:
 *
 *  - planar triple pendulum: three uniform rods 1 m, 1 kg, hanging along -y at q = 0, revolute
 *    joints about +z, gravity -y; q0 = (5 pi/6, 3 pi/4, 2 pi/3), v0 = 0; q_d1 = q_d3 =
 *    0.6 sin(2 pi t / 1.5), q_d2 = 0.6 cos(2 pi t / 1.5) (Eq. 81-82); 0.2 N m on every joint;
 *    PD (kp 100, kv 20), PID (ki 250), poles (-2, -2.1, -2.2) or LQR (Q = I, lambda 0.01); the
 *    passive variant drops the controller, the trajectory and the disturbance;
 *  - spatial double pendulum: two uniform cuboids 1 x 0.1 x 0.1 m, 1 kg, each along its body x
 *    axis from its inboard joint; J1 about the world z axis at the origin, J2 about body 1's y
 *    axis at its far end; q0 = (pi/2, 0), v0 = (1, 1); q_d1 = sin(2 pi t / 1.5), q_d2 =
 *    cos(2 pi t / 1.5) (Eq. 83); 0.2 N m. The paper gives no gravity; we use -z (9.81 m/s^2) and
 *    say so in the name and the summary;
 *  - n-link pendulum (section 7.3): n rods as above, q0_k = (-1)^k pi/6 (k = 1..n, Eq. 84),
 *    v0 = 0, q_d = 0, PD, no disturbance.
 * Every preset runs 5 s with dopri5 (the method of MATLAB's ode45, which the paper used) at
 * rtol 1e-8, atol 1e-10, and samples every 0.01 s; all of it is written out, defaults included.
 *
 * Documents are built with cJSON. Every node is added through one helper that remembers a failed
 * allocation, so the builders read as the document they write and check for memory once, at the
 * end.
 */
#include "presets.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* pi to more digits than a double holds (M_PI is not strict C11) */
#define PRESETS_PI 3.14159265358979323846264338327950288

#define PAPER "Kingsley et al. 2017"
#define N_LINK_DEFAULT 8
#define N_LINK_MIN 2
#define N_LINK_MAX JOB_MAX_BODIES

typedef enum preset_ctrl {
    PRESET_NONE, /* passive */
    PRESET_PD,
    PRESET_PID,
    PRESET_POLES,
    PRESET_LQR,
} preset_ctrl;

/* ---- building documents ---- */

/* remembers whether any allocation failed while a document was built */
typedef struct doc_builder {
    int failed;
} doc_builder;

/* Adds item to parent under key (an object) or at its end (key NULL, an array) and returns it.
 * On any failure (item or parent NULL, no memory) deletes item, marks the builder and returns
 * NULL, so later adds below it fail quietly too. */
static cJSON *put(doc_builder *b, cJSON *parent, const char *key, cJSON *item)
{
    int ok = item != NULL && parent != NULL &&
             (key ? cJSON_AddItemToObject(parent, key, item) : cJSON_AddItemToArray(parent, item));
    if (!ok) {
        cJSON_Delete(item);
        b->failed = 1;
        return NULL;
    }
    return item;
}

static cJSON *put_object(doc_builder *b, cJSON *parent, const char *key)
{
    return put(b, parent, key, cJSON_CreateObject());
}

static cJSON *put_array(doc_builder *b, cJSON *parent, const char *key)
{
    return put(b, parent, key, cJSON_CreateArray());
}

static void put_number(doc_builder *b, cJSON *parent, const char *key, double x)
{
    put(b, parent, key, cJSON_CreateNumber(x));
}

static void put_string(doc_builder *b, cJSON *parent, const char *key, const char *s)
{
    put(b, parent, key, cJSON_CreateString(s));
}

/* an array of n numbers */
static void put_vector(doc_builder *b, cJSON *parent, const char *key, int n, const double *v)
{
    put(b, parent, key, cJSON_CreateDoubleArray(v, n));
}

static void put_vec3(doc_builder *b, cJSON *parent, const char *key, double x, double y, double z)
{
    const double v[3] = {x, y, z};
    put_vector(b, parent, key, 3, v);
}

/* {"type": "revolute", "axis": axis, "location": location} */
static void put_revolute(doc_builder *b, cJSON *body, const double axis[3],
                         const double location[3])
{
    cJSON *joint = put_object(b, body, "joint");
    put_string(b, joint, "type", "revolute");
    put_vector(b, joint, "axis", 3, axis);
    put_vector(b, joint, "location", 3, location);
}

/* Returns the finished document, or NULL with an out-of-memory error (the document deleted). */
static cJSON *finish(doc_builder *b, cJSON *doc, const char *preset_name, job_error *err)
{
    if (doc != NULL && !b->failed) return doc;
    cJSON_Delete(doc);
    err->code = JOB_NO_MEMORY;
    err->field[0] = '\0';
    snprintf(err->message, sizeof err->message, "out of memory building preset %s", preset_name);
    return NULL;
}

/* ---- the parts shared by the scenes ---- */

/* "scene.bodies": n uniform rods 1 m, 1 kg hanging along -y at q = 0, revolute joints about +z,
 * the first at the world origin, each next one at the end of its parent */
static void put_rod_chain(doc_builder *b, cJSON *scene, int n)
{
    static const double axis[3] = {0, 0, 1}, origin[3] = {0, 0, 0}, tip[3] = {0, -1, 0};
    cJSON *bodies = put_array(b, scene, "bodies");
    for (int k = 0; k < n && !b->failed; k++) {
        char name[32];
        snprintf(name, sizeof name, "rod %d", k + 1);
        cJSON *body = put_object(b, bodies, NULL);
        put_string(b, body, "name", name);
        put_number(b, body, "mass", 1);
        cJSON *shape = put_object(b, body, "shape");
        put_string(b, shape, "type", "rod");
        put_vec3(b, shape, "end", 0, -1, 0);
        put_revolute(b, body, axis, k == 0 ? origin : tip);
    }
}

/* "controller" of the given kind with the paper's gains (section 7.1, Appendix B) */
static void put_controller(doc_builder *b, cJSON *doc, preset_ctrl ctrl)
{
    static const char *const type[] = {"none", "pd", "pid", "poles", "lqr"};
    cJSON *c = put_object(b, doc, "controller");
    put_string(b, c, "type", type[ctrl]);
    switch (ctrl) {
    case PRESET_NONE:
        break;
    case PRESET_PD:
        put_number(b, c, "kp", 100);
        put_number(b, c, "kv", 20);
        break;
    case PRESET_PID:
        put_number(b, c, "kp", 100);
        put_number(b, c, "kv", 20);
        put_number(b, c, "ki", 250);
        break;
    case PRESET_POLES:
        put_vec3(b, c, "poles", -2, -2.1, -2.2);
        break;
    case PRESET_LQR: {
        cJSON *q = put_array(b, c, "Q");
        put_vec3(b, q, NULL, 1, 0, 0);
        put_vec3(b, q, NULL, 0, 1, 0);
        put_vec3(b, q, NULL, 0, 0, 1);
        put_number(b, c, "lambda", 0.01);
        break;
    }
    }
}

/* {"type": "sine"|"cosine", "amplitude": amplitude, "period": period} at the end of array */
static void put_harmonic(doc_builder *b, cJSON *array, const char *type, double amplitude,
                         double period)
{
    cJSON *tr = put_object(b, array, NULL);
    put_string(b, tr, "type", type);
    put_number(b, tr, "amplitude", amplitude);
    put_number(b, tr, "period", period);
}

/* "disturbance": the same constant generalised force on every coordinate */
static void put_constant_disturbance(doc_builder *b, cJSON *doc, double value)
{
    cJSON *z = put_object(b, doc, "disturbance");
    put_string(b, z, "type", "constant");
    put_number(b, z, "value", value);
}

/* "integrator", "duration" and "output", the same for every preset */
static void put_run_settings(doc_builder *b, cJSON *doc)
{
    cJSON *integ = put_object(b, doc, "integrator");
    put_string(b, integ, "method", "dopri5");
    put_number(b, integ, "rtol", 1e-8);
    put_number(b, integ, "atol", 1e-10);
    put_number(b, doc, "duration", 5);
    cJSON *out = put_object(b, doc, "output");
    put_number(b, out, "interval", 0.01);
}

/* ---- the scenes ---- */

/* Planar triple pendulum (section 7.1, Fig. 6(a), 7, 8). */
static cJSON *triple_pendulum(const char *preset_name, const char *name, preset_ctrl ctrl,
                              job_error *err)
{
    const double pi = PRESETS_PI;
    const double q0[3] = {5 * pi / 6, 3 * pi / 4, 2 * pi / 3}, v0[3] = {0, 0, 0};
    doc_builder b = {0};
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", name);

    /* three rods hanging along -y, gravity -y */
    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, -9.81, 0);
    put_rod_chain(&b, scene, 3);
    put_vector(&b, scene, "q0", 3, q0);
    put_vector(&b, scene, "v0", 3, v0);

    /* control: Eq. 81-82 and 0.2 N m on every joint; the passive run has neither */
    put_controller(&b, doc, ctrl);
    if (ctrl != PRESET_NONE) {
        cJSON *traj = put_array(&b, doc, "trajectory");
        put_harmonic(&b, traj, "sine", 0.6, 1.5);
        put_harmonic(&b, traj, "cosine", 0.6, 1.5);
        put_harmonic(&b, traj, "sine", 0.6, 1.5);
        put_constant_disturbance(&b, doc, 0.2);
    }
    put_run_settings(&b, doc);
    return finish(&b, doc, preset_name, err);
}

/* Spatial double pendulum (section 7.1, Fig. 6(b), 9, 10), gravity -z. */
static cJSON *spatial_double_pendulum(const char *preset_name, const char *name, preset_ctrl ctrl,
                                      job_error *err)
{
    static const double z_axis[3] = {0, 0, 1}, y_axis[3] = {0, 1, 0};
    static const double origin[3] = {0, 0, 0}, far_end[3] = {1, 0, 0};
    const double pi = PRESETS_PI;
    const double q0[2] = {pi / 2, 0}, v0[2] = {1, 1};
    doc_builder b = {0};
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", name);

    /* two cuboids along their body x axes; J1 about world z, J2 about body 1's y at its end */
    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, 0, -9.81);
    cJSON *bodies = put_array(&b, scene, "bodies");
    for (int k = 0; k < 2; k++) {
        cJSON *body = put_object(&b, bodies, NULL);
        put_string(&b, body, "name", k == 0 ? "cuboid 1" : "cuboid 2");
        put_number(&b, body, "mass", 1);
        cJSON *shape = put_object(&b, body, "shape");
        put_string(&b, shape, "type", "box");
        put_vec3(&b, shape, "size", 1, 0.1, 0.1);
        put_vec3(&b, shape, "centre", 0.5, 0, 0);
        put_revolute(&b, body, k == 0 ? z_axis : y_axis, k == 0 ? origin : far_end);
    }
    put_vector(&b, scene, "q0", 2, q0);
    put_vector(&b, scene, "v0", 2, v0);

    /* control: Eq. 83 and 0.2 N m on both joints */
    put_controller(&b, doc, ctrl);
    cJSON *traj = put_array(&b, doc, "trajectory");
    put_harmonic(&b, traj, "sine", 1, 1.5);
    put_harmonic(&b, traj, "cosine", 1, 1.5);
    put_constant_disturbance(&b, doc, 0.2);
    put_run_settings(&b, doc);
    return finish(&b, doc, preset_name, err);
}

/* Writes x in the fewest significant digits that read back as x. */
static void format_number(char *buf, size_t len, double x)
{
    for (int digits = 1; digits <= 17; digits++) {
        snprintf(buf, len, "%.*g", digits, x);
        if (strtod(buf, NULL) == x) return;
    }
}

/* What a JSON value is, for messages: "2.5", "a string", "null", ... */
static void describe_value(char *buf, size_t len, const cJSON *v)
{
    if (cJSON_IsNumber(v)) {
        format_number(buf, len, v->valuedouble);
    } else if (cJSON_IsString(v)) {
        snprintf(buf, len, "a string");
    } else if (cJSON_IsBool(v)) {
        snprintf(buf, len, "%s", cJSON_IsTrue(v) ? "true" : "false");
    } else if (cJSON_IsNull(v)) {
        snprintf(buf, len, "null");
    } else if (cJSON_IsArray(v)) {
        snprintf(buf, len, "an array");
    } else {
        snprintf(buf, len, "an object");
    }
}

/* N-link planar pendulum (section 7.3, Eq. 84), parameter "n". */
static cJSON *n_link_pendulum(const cJSON *request, job_error *err)
{
    const double pi = PRESETS_PI;
    doc_builder b = {0};

    /* the parameter: an integer number of bodies, N_LINK_DEFAULT when absent */
    int n = N_LINK_DEFAULT;
    const cJSON *param = request ? cJSON_GetObjectItemCaseSensitive(request, "n") : NULL;
    if (param != NULL) {
        double x = cJSON_IsNumber(param) ? param->valuedouble : NAN;
        if (!(x >= N_LINK_MIN && x <= N_LINK_MAX && x == floor(x))) {
            char got[64];
            describe_value(got, sizeof got, param);
            err->code = JOB_INVALID_FIELD;
            snprintf(err->field, sizeof err->field, "n");
            snprintf(err->message, sizeof err->message, "must be an integer from %d to %d (got %s)",
                     N_LINK_MIN, N_LINK_MAX, got);
            return NULL;
        }
        n = (int)x;
    }

    char name[JOB_MAX_NAME];
    snprintf(name, sizeof name, "%d-link pendulum, PD (" PAPER ", sec. 7.3)", n);
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", name);

    /* n rods hanging along -y, gravity -y, starting from alternating +-pi/6 at rest */
    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, -9.81, 0);
    put_rod_chain(&b, scene, n);
    cJSON *q0 = put_array(&b, scene, "q0");
    cJSON *v0 = put_array(&b, scene, "v0");
    for (int k = 1; k <= n && !b.failed; k++) {
        put_number(&b, q0, NULL, (k % 2 ? -1 : 1) * pi / 6);
        put_number(&b, v0, NULL, 0);
    }

    /* PD to q = 0, no disturbance */
    put_controller(&b, doc, PRESET_PD);
    cJSON *traj = put_object(&b, doc, "trajectory");
    put_string(&b, traj, "type", "constant");
    put_number(&b, traj, "value", 0);
    put_run_settings(&b, doc);
    return finish(&b, doc, "n_link_pendulum", err);
}

/* ---- the table ---- */

#define TRIPLE(suffix, ctrl, label)                                                                \
    static cJSON *build_triple_pendulum_##suffix(const cJSON *request, job_error *err)             \
    {                                                                                              \
        (void)request;                                                                             \
        return triple_pendulum("triple_pendulum_" #suffix, label, ctrl, err);                      \
    }
#define SPATIAL(suffix, ctrl, label)                                                               \
    static cJSON *build_spatial_double_pendulum_##suffix(const cJSON *request, job_error *err)     \
    {                                                                                              \
        (void)request;                                                                             \
        return spatial_double_pendulum("spatial_double_pendulum_" #suffix, label, ctrl, err);      \
    }

TRIPLE(pd, PRESET_PD, "Triple pendulum, PD (" PAPER ", sec. 7.1)")
TRIPLE(pid, PRESET_PID, "Triple pendulum, PID (" PAPER ", sec. 7.1)")
TRIPLE(poles, PRESET_POLES, "Triple pendulum, pole placement (" PAPER ", sec. 7.1)")
TRIPLE(lqr, PRESET_LQR, "Triple pendulum, LQR (" PAPER ", sec. 7.1)")
TRIPLE(passive, PRESET_NONE, "Triple pendulum, passive (scene of " PAPER ", sec. 7.1)")
SPATIAL(pd, PRESET_PD, "Spatial double pendulum, PD (" PAPER ", sec. 7.1; gravity -z)")
SPATIAL(pid, PRESET_PID, "Spatial double pendulum, PID (" PAPER ", sec. 7.1; gravity -z)")
SPATIAL(poles, PRESET_POLES,
        "Spatial double pendulum, pole placement (" PAPER ", sec. 7.1; gravity -z)")
SPATIAL(lqr, PRESET_LQR, "Spatial double pendulum, LQR (" PAPER ", sec. 7.1; gravity -z)")

static const char *const no_params[] = {NULL};
static const char *const n_link_params[] = {"n", NULL};

/* one line each for listings (`ctcsim presets`): the scene, then the controller */
#define TRIPLE_SUMMARY(ctrl) "Triple pendulum tracking sines, " ctrl ", 0.2 N m disturbance"
#define SPATIAL_SUMMARY(ctrl)                                                                      \
    "Spatial double pendulum tracking sines, " ctrl ", 0.2 N m, gravity -z"
#define PID_GAINS "PID kp 100 kv 20 ki 250"
#define PD_GAINS "PD kp 100 kv 20"
#define POLES "poles -2 -2.1 -2.2"
#define LQR_WEIGHTS "LQR Q = I lambda 0.01"

static const preset preset_table[] = {
    {"triple_pendulum_pd", TRIPLE_SUMMARY(PD_GAINS), no_params, build_triple_pendulum_pd},
    {"triple_pendulum_pid", TRIPLE_SUMMARY(PID_GAINS), no_params, build_triple_pendulum_pid},
    {"triple_pendulum_poles", TRIPLE_SUMMARY(POLES), no_params, build_triple_pendulum_poles},
    {"triple_pendulum_lqr", TRIPLE_SUMMARY(LQR_WEIGHTS), no_params, build_triple_pendulum_lqr},
    {"triple_pendulum_passive",
     "Triple pendulum falling from the start pose of sec. 7.1, no control", no_params,
     build_triple_pendulum_passive},
    {"spatial_double_pendulum_pd", SPATIAL_SUMMARY(PD_GAINS), no_params,
     build_spatial_double_pendulum_pd},
    {"spatial_double_pendulum_pid", SPATIAL_SUMMARY(PID_GAINS), no_params,
     build_spatial_double_pendulum_pid},
    {"spatial_double_pendulum_poles", SPATIAL_SUMMARY(POLES), no_params,
     build_spatial_double_pendulum_poles},
    {"spatial_double_pendulum_lqr", SPATIAL_SUMMARY(LQR_WEIGHTS), no_params,
     build_spatial_double_pendulum_lqr},
    {"n_link_pendulum",
     "Pendulum of n rods (\"n\" 2..4096, default 8) from +-pi/6 to rest, " PD_GAINS, n_link_params,
     n_link_pendulum},
};

const preset *presets_list(int *count)
{
    *count = (int)(sizeof preset_table / sizeof preset_table[0]);
    return preset_table;
}

const preset *presets_find(const char *name)
{
    if (name == NULL) return NULL;
    for (size_t i = 0; i < sizeof preset_table / sizeof preset_table[0]; i++) {
        if (strcmp(preset_table[i].name, name) == 0) return &preset_table[i];
    }
    return NULL;
}
