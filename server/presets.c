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
 * Every preset of the open chains runs 5 s with dopri5 (the method of MATLAB's ode45, which the
 * paper used) at rtol 1e-8, atol 1e-10, and samples every 0.01 s; all of it is written out,
 * defaults included. The closed chains (loop presets, model.h) close the chain with a revolute
 * joint from the last body to an anchor in the world, stabilised by projection (tol 1e-12):
 *  - planar five-bar (section 7.2, DESIGN.md section 7 scene 3): five uniform rods of lengths
 *    (1, 1, 0.5, 1, 1) m, 1 kg each, hanging along -y at q = 0, revolute joints about +z, joint
 *    0 at the origin, each next one at the previous rod's end, gravity -y; joints 0, 1 and 2
 *    independent (the torques of the paper act at the inboard joints of bodies 1-3), joints 3
 *    and 4 and the closing joint at the end of rod 5 dependent; q0 = (-pi/8, 5 pi/8, 3 pi/8,
 *    3 pi/8, 5 pi/8), v0 = 0. The paper omits its ground pivots: the anchor is where q0 puts
 *    the end of rod 5, sum_k L_k (sin theta_k, -cos theta_k) with theta_k = q_0 + ... + q_k,
 *    i.e. (-0.28113192973418280, -0.67871251758038230, 0) m. Set point (0, pi/4, -3 pi/4) for
 *    joints 0-2 (reachable: the end of rod 3 is then 1.14 m from the anchor, within the 2 m of
 *    rods 4 and 5), PD (kp 100, kv 20), PID, poles or LQR with the gains above, no
 *    disturbance, 10 s at rtol 1e-8, atol 1e-10;
 *  - planar four-bar crank-rocker (not in the paper; Grashof: 0.4 + 1 <= 1 + 0.8): ground link
 *    1 m along +x from the crank's pivot at the origin to the anchor (1, 0, 0), crank 0.4 m,
 *    coupler 1 m, rocker 0.8 m, uniform rods of 1 kg/m hanging along -y at q = 0, revolute
 *    joints about +z, gravity -y, every joint dependent (a passive run needs no independent
 *    one). q0: the crank at 2 pi/3 from hanging down (30 degrees above +x), the coupler-rocker
 *    joint where the coupler's and the rocker's circles meet above the line from the crank's end
 *    to the anchor: q0 = (2.0943951023931953, 0.10035043422724721, -2.3935368163015450) (the
 *    coupler-rocker joint at (1.158, 0.784) m). v0 = 0, no control, 10 s at rtol 1e-10, atol
 *    1e-12, so the energy drift shows the integration and the projection alone;
 *  - planar four-bar on an arm (not in the paper; a loop closed on a body, model.h): the arm, a
 *    1.5 m rod of 1.5 kg hanging along -y at q = 0 from a revolute joint about +z at the origin,
 *    carries the crank-rocker above: the crank's pivot at the arm's end, the rocker's end pinned
 *    to the arm 1 m further in (the anchor (0, -0.5, 0) in the arm's frame, "body": 0), so the
 *    arm is the four-bar's ground link. q0: the arm along +x (pi/2) and the four-bar relative to
 *    it as four_bar_passive's relative to the ground, turned a quarter turn (the crank's angle
 *    plus pi/2). Joints 0 (arm) and 1 (crank) independent (mobility 2), PD (kp 100, kv 20): the
 *    arm follows pi/2 + 0.3 sin(2 pi t / 4), the crank turns at pi rad/s from its q0 (a Grashof
 *    crank turns fully); 10 s at rtol 1e-8, atol 1e-10;
 *  - spatial RSSR linkage (not in the paper): boxes of 1 kg/m with a 0.04 m square section,
 *    each along its body x axis from its inboard joint: crank 0.3 m, revolute about the world z
 *    axis at the origin; coupler 1 m, spherical at the crank's end; rocker 0.6 m, spherical at
 *    the coupler's end; the closing joint revolute about the rocker's y axis at its end, to the
 *    anchor (0.9, 0.8, 0.6) m: the rocker turns about the world y axis there, square to the
 *    crank's axis, so the loop is truly spatial (mobility 2: the crank's motion and the
 *    coupler's idle spin about its own axis). q0 closes exactly: the crank along +x, the
 *    coupler along (0, 0.8, 0.6) (a quarter turn about (0, -0.6, 0.8), quaternion (1/sqrt 2)
 *    (1, 0, -0.6, 0.8)), the rocker parallel to the world (the inverse turn); v0 = 0, gravity
 *    -z, every joint dependent, no control, 5 s at rtol 1e-10, atol 1e-12.
 * The trees (not in the paper; bodies that name their parent, job_json.h) track sines with PD
 * (kp 100, kv 20), 5 s with dopri5 at rtol 1e-8, atol 1e-10, sampled every 0.01 s:
 *  - planar Y: an arm, a uniform rod 1 m, 1 kg, hanging along -y at q = 0 from a revolute joint
 *    about +z at the origin, and on its tip two double pendulums of uniform rods 0.5 m, 0.5 kg
 *    (bodies "left upper", "left lower", then "right upper", which names "arm" as its parent,
 *    and "right lower"); gravity -y; q0 = (pi/6, pi/3, 0, -pi/3, 0), v0 = 0; the arm follows
 *    0.6 sin(2 pi t / 1.5), the upper links +-0.5 + 0.3 cos(2 pi t / 1.5) (the Y opens and
 *    closes), the lower links 0.6 sin(2 pi t / 1.5); 0.2 N m on every joint, as the paper's;
 *  - spatial hand: an aluminium (2700 kg/m^3) palm box 0.08 x 0.02 x 0.1 m hanging along -z
 *    from a wrist about y at the origin, and on its far edge (x = -0.025, 0, 0.025 m) three
 *    fingers of three square aluminium links 0.015 m across, 0.045, 0.03 and 0.025 m long, each
 *    joint about the palm's x axis; masses density x volume, inertias from the box shapes;
 *    gravity -z; q0 = 0, v0 = 0; the wrist follows 0.3 sin(2 pi t / 2), every finger joint
 *    0.4 + 0.4 sin(2 pi t / 1.5 - 2 pi f / 3) for finger f = 0, 1, 2 (a wave);
 *  - two-arm torso: a 25 kg torso box on a waist about z, two arms of three cylinders (the
 *    numbers at two_arm_torso_pd below); gravity -z; q0 = 0, v0 = 0; the waist follows
 *    0.4 sin(2 pi t / 3), each arm's shoulder 0.6 sin(2 pi t / 2 + phi), elbow 0.5 + 0.3
 *    sin(...), wrist 0.3 sin(...), with phi = 0 on the left and pi on the right.
 *
 * Documents are built with cJSON. Every node is added through one helper that remembers a failed
 * allocation, so the builders read as the document they write and check for memory once, at the
 * end.
 */
#include "presets.h"
#include "presets_robots.h"

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

/* {"type": "revolute", "axis": axis, "location": location} as body's "joint"; returns it */
static cJSON *put_revolute(doc_builder *b, cJSON *body, const double axis[3],
                           const double location[3])
{
    cJSON *joint = put_object(b, body, "joint");
    put_string(b, joint, "type", "revolute");
    put_vector(b, joint, "axis", 3, axis);
    put_vector(b, joint, "location", 3, location);
    return joint;
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

/* "integrator" (dopri5 at rtol, atol), "duration" and "output" (a sample every 0.01 s) */
static void put_run_settings_of(doc_builder *b, cJSON *doc, double duration, double rtol,
                                double atol)
{
    cJSON *integ = put_object(b, doc, "integrator");
    put_string(b, integ, "method", "dopri5");
    put_number(b, integ, "rtol", rtol);
    put_number(b, integ, "atol", atol);
    put_number(b, doc, "duration", duration);
    cJSON *out = put_object(b, doc, "output");
    put_number(b, out, "interval", 0.01);
}

/* the run settings of the paper's open chains: 5 s, rtol 1e-8, atol 1e-10 */
static void put_run_settings(doc_builder *b, cJSON *doc)
{
    put_run_settings_of(b, doc, 5, 1e-8, 1e-10);
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

/* ---- closed chains ---- */

/* x rounded to 15 significant digits. cJSON 1.7 prints a number with 15 digits whenever they
 * read back within DBL_EPSILON relative, so a computed number may come back one unit in the last
 * place off; rounded first, it prints and reads back exactly, and a printed preset parses to the
 * same job. (The change, below 1e-15 relative, is far inside what putting the initial state
 * onto the closure corrects.) */
static double printable(double x)
{
    char buf[32];
    snprintf(buf, sizeof buf, "%.15g", x);
    return strtod(buf, NULL);
}

/* "scene.bodies": n uniform rods hanging along -y at q = 0, rod k of length[k] and mass[k],
 * revolute joints about +z, the first at the world origin, each next one at the end of its
 * parent; joint k independent when independent[k] */
static void put_rods(doc_builder *b, cJSON *scene, int n, const double *length, const double *mass,
                     const unsigned char *independent)
{
    static const double axis[3] = {0, 0, 1};
    cJSON *bodies = put_array(b, scene, "bodies");
    for (int k = 0; k < n && !b->failed; k++) {
        char name[32];
        snprintf(name, sizeof name, "rod %d", k + 1);
        cJSON *body = put_object(b, bodies, NULL);
        put_string(b, body, "name", name);
        put_number(b, body, "mass", mass[k]);
        cJSON *shape = put_object(b, body, "shape");
        put_string(b, shape, "type", "rod");
        put_vec3(b, shape, "end", 0, -length[k], 0);
        const double location[3] = {0, k == 0 ? 0 : -length[k - 1], 0};
        cJSON *joint = put_revolute(b, body, axis, location);
        put(b, joint, "independent", cJSON_CreateBool(independent[k]));
    }
}

/* The far end of a planar chain of n rods hanging along -y at q = 0 (put_rods), at q: with the
 * absolute angle theta_k = q_0 + ... + q_k, rod k runs from the end of rod k-1 (the origin for
 * k = 0) by length[k] (sin theta_k, -cos theta_k). */
static void rod_chain_end(int n, const double *length, const double *q, double end[2])
{
    double theta = 0;
    end[0] = end[1] = 0;
    for (int k = 0; k < n; k++) {
        theta += q[k];
        end[0] += length[k] * sin(theta);
        end[1] -= length[k] * cos(theta);
    }
}

/* "scene.loop": a closing joint from the tip, its centre at location (tip frame), to the anchor:
 * on the ground (world frame) for body < 0, else on that body (its frame, "body"); dependent;
 * stabilised by projection (the default, written out) */
static void put_loop(doc_builder *b, cJSON *scene, const char *type, const double *axis,
                     const double location[3], const double anchor[3], int body)
{
    cJSON *loop = put_object(b, scene, "loop");
    if (body >= 0) put_number(b, loop, "body", body);
    cJSON *joint = put_object(b, loop, "joint");
    put_string(b, joint, "type", type);
    if (axis != NULL) put_vector(b, joint, "axis", 3, axis);
    put_vector(b, joint, "location", 3, location);
    put(b, joint, "independent", cJSON_CreateFalse());
    put_vector(b, loop, "anchor", 3, anchor);
    cJSON *stab = put_object(b, loop, "stabilization");
    put_string(b, stab, "method", "project");
    put_number(b, stab, "tol", 1e-12);
}

/* the planar five-bar of section 7.2 (DESIGN.md section 7, scene 3) */
#define FIVE_BAR_N 5
static const double five_bar_length[FIVE_BAR_N] = {1, 1, 0.5, 1, 1}; /* m */
static const double five_bar_mass[FIVE_BAR_N] = {1, 1, 1, 1, 1};     /* kg */

/* q0 of the five-bar: (-pi/8, 5 pi/8, 3 pi/8, 3 pi/8, 5 pi/8) */
static void five_bar_q0(double q0[FIVE_BAR_N])
{
    const double pi = PRESETS_PI;
    q0[0] = -pi / 8;
    q0[1] = 5 * pi / 8;
    q0[2] = 3 * pi / 8;
    q0[3] = 3 * pi / 8;
    q0[4] = 5 * pi / 8;
}

/* the five-bar's second ground pivot: where q0 puts the end of rod 5 */
static void five_bar_anchor(double anchor[3])
{
    double q0[FIVE_BAR_N], end[2];
    five_bar_q0(q0);
    rod_chain_end(FIVE_BAR_N, five_bar_length, q0, end);
    anchor[0] = printable(end[0]);
    anchor[1] = printable(end[1]);
    anchor[2] = 0;
}

/* Planar five-bar closed chain (section 7.2, Fig. 12): five rods pinned to the ground at both
 * ends, joints 0-2 driven to the set point (0, pi/4, -3 pi/4), the rest passive. */
static cJSON *five_bar(const char *preset_name, const char *name, preset_ctrl ctrl, job_error *err)
{
    static const double z_axis[3] = {0, 0, 1};
    static const unsigned char independent[FIVE_BAR_N] = {1, 1, 1, 0, 0};
    const double rod_end[3] = {0, -five_bar_length[FIVE_BAR_N - 1], 0};
    const double pi = PRESETS_PI;
    double q0[FIVE_BAR_N], anchor[3];
    const double v0[FIVE_BAR_N] = {0, 0, 0, 0, 0};
    five_bar_q0(q0);
    five_bar_anchor(anchor);
    doc_builder b = {0};
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", name);

    /* five rods of 1 kg, gravity -y; the closing joint at the tip of rod 5, pinned where q0
       puts it */
    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, -9.81, 0);
    put_rods(&b, scene, FIVE_BAR_N, five_bar_length, five_bar_mass, independent);
    put_loop(&b, scene, "revolute", z_axis, rod_end, anchor, -1);
    put_vector(&b, scene, "q0", FIVE_BAR_N, q0);
    put_vector(&b, scene, "v0", FIVE_BAR_N, v0);

    /* control of joints 0-2 to a set point, no disturbance */
    put_controller(&b, doc, ctrl);
    const double set_point[3] = {0, pi / 4, -3 * pi / 4};
    cJSON *traj = put_array(&b, doc, "trajectory");
    for (int i = 0; i < 3; i++) {
        cJSON *tr = put_object(&b, traj, NULL);
        put_string(&b, tr, "type", "constant");
        put_number(&b, tr, "value", set_point[i]);
    }
    put_run_settings_of(&b, doc, 10, 1e-8, 1e-10);
    return finish(&b, doc, preset_name, err);
}

/* the four-bar crank-rocker: ground link 1 m along +x, crank 0.4 m, coupler 1 m, rocker 0.8 m */
#define FOUR_BAR_N 3
static const double four_bar_length[FOUR_BAR_N] = {0.4, 1, 0.8}; /* m: crank, coupler, rocker */
#define FOUR_BAR_GROUND 1.0                                      /* m */
#define FOUR_BAR_CRANK_ANGLE (2 * PRESETS_PI / 3) /* rad from hanging down: 30 deg above +x */

/* q0 of the four-bar: the crank at FOUR_BAR_CRANK_ANGLE; the coupler-rocker joint B where the
 * circles about the crank's end C (radius: the coupler) and about the ground pivot A = (1, 0)
 * (radius: the rocker) meet, on the left of the line from C to A (above it: elbow up) */
static void four_bar_q0(double q0[FOUR_BAR_N])
{
    const double *len = four_bar_length;
    double theta1 = FOUR_BAR_CRANK_ANGLE;
    double cx = len[0] * sin(theta1), cy = -len[0] * cos(theta1);
    double dx = FOUR_BAR_GROUND - cx, dy = -cy, d = sqrt(dx * dx + dy * dy);
    double a = (d * d + len[1] * len[1] - len[2] * len[2]) / (2 * d);
    double h = sqrt(len[1] * len[1] - a * a);
    double bx = cx + (a * dx - h * dy) / d, by = cy + (a * dy + h * dx) / d;
    /* absolute angles from hanging down: a rod from P to R has theta = atan2(Rx - Px, Py - Ry);
       the rocker runs from B to A = (1, 0) */
    double theta2 = atan2(bx - cx, cy - by), theta3 = atan2(FOUR_BAR_GROUND - bx, by);
    q0[0] = printable(theta1);
    q0[1] = printable(theta2 - theta1);
    q0[2] = printable(theta3 - theta2);
}

/* Planar four-bar crank-rocker swinging under gravity from rest, every joint passive. */
static cJSON *four_bar_passive(const cJSON *request, job_error *err)
{
    static const double z_axis[3] = {0, 0, 1}, anchor[3] = {FOUR_BAR_GROUND, 0, 0};
    static const unsigned char independent[FOUR_BAR_N] = {0, 0, 0};
    const double rocker_end[3] = {0, -four_bar_length[2], 0};
    const double v0[FOUR_BAR_N] = {0, 0, 0};
    double q0[FOUR_BAR_N];
    (void)request;
    four_bar_q0(q0);
    doc_builder b = {0};
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", "Four-bar linkage (crank-rocker), passive");

    /* rods of 1 kg/m (the masses in kg are the lengths in m), gravity -y; the rocker's end
       pinned to the ground 1 m from the crank's pivot */
    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, -9.81, 0);
    put_rods(&b, scene, FOUR_BAR_N, four_bar_length, four_bar_length, independent);
    put_loop(&b, scene, "revolute", z_axis, rocker_end, anchor, -1);
    put_vector(&b, scene, "q0", FOUR_BAR_N, q0);
    put_vector(&b, scene, "v0", FOUR_BAR_N, v0);
    put_controller(&b, doc, PRESET_NONE);
    put_run_settings_of(&b, doc, 10, 1e-10, 1e-12);
    return finish(&b, doc, "four_bar_passive", err);
}

/* the four-bar carried by an arm: the arm, then the four-bar's crank, coupler and rocker */
#define ARM_FOUR_BAR_N 4
#define ARM_LENGTH 1.5 /* m: the crank's pivot at its end, the rocker's 1 m further in */
static const double arm_four_bar_length[ARM_FOUR_BAR_N] = {ARM_LENGTH, 0.4, 1, 0.8}; /* m */

/* q0: the arm along +x (a quarter turn from hanging down); relative to it the four-bar stands
 * as four_bar_passive's does relative to the ground, turned a quarter turn so that its ground
 * link runs from the arm's end back along the arm */
static void arm_four_bar_q0(double q0[ARM_FOUR_BAR_N])
{
    double fb[FOUR_BAR_N];
    four_bar_q0(fb);
    q0[0] = printable(PRESETS_PI / 2);
    q0[1] = printable(fb[0] + PRESETS_PI / 2);
    q0[2] = fb[1];
    q0[3] = fb[2];
}

/* The drive of a four-bar on an arm (arm_four_bar_pd, y_four_bar_pd): PD, the arm (coordinate 0)
 * at q0 + 0.3 sin(2 pi t / 4), the crank (coordinate 1) at q0 + pi t. Returns the trajectory
 * array, to which a scene with more independent joints adds theirs. */
static cJSON *put_arm_crank_drive(doc_builder *b, cJSON *doc, const double *q0)
{
    put_controller(b, doc, PRESET_PD);
    cJSON *traj = put_array(b, doc, "trajectory");
    cJSON *arm = put_object(b, traj, NULL);
    put_string(b, arm, "type", "sine");
    put_number(b, arm, "amplitude", 0.3);
    put_number(b, arm, "period", 4);
    put_number(b, arm, "offset", q0[0]);
    cJSON *crank = put_object(b, traj, NULL);
    put_string(b, crank, "type", "polynomial");
    const double coef[2] = {q0[1], printable(PRESETS_PI)};
    put_vector(b, crank, "coefficients", 2, coef);
    return traj;
}

/* A planar four-bar crank-rocker whose ground link is an arm (a loop closed on body 0, not on the
 * ground): PD drives the arm along a sine about +x and the crank round at 1 turn per 2 s; the
 * coupler, the rocker and the closing joint follow. */
static cJSON *arm_four_bar_pd(const cJSON *request, job_error *err)
{
    static const double z_axis[3] = {0, 0, 1};
    static const unsigned char independent[ARM_FOUR_BAR_N] = {1, 1, 0, 0};
    const double anchor[3] = {0, -(ARM_LENGTH - FOUR_BAR_GROUND), 0}; /* in the arm's frame */
    const double rocker_end[3] = {0, -arm_four_bar_length[3], 0};
    const double v0[ARM_FOUR_BAR_N] = {0, 0, 0, 0};
    double q0[ARM_FOUR_BAR_N];
    (void)request;
    arm_four_bar_q0(q0);
    doc_builder b = {0};
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", "Four-bar linkage on a swinging arm, PD");

    /* rods of 1 kg/m, gravity -y; the rocker's end pinned to the arm 1 m in from its end */
    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, -9.81, 0);
    put_rods(&b, scene, ARM_FOUR_BAR_N, arm_four_bar_length, arm_four_bar_length, independent);
    put_loop(&b, scene, "revolute", z_axis, rocker_end, anchor, 0);
    put_vector(&b, scene, "q0", ARM_FOUR_BAR_N, q0);
    put_vector(&b, scene, "v0", ARM_FOUR_BAR_N, v0);

    put_arm_crank_drive(&b, doc, q0);
    put_run_settings_of(&b, doc, 10, 1e-8, 1e-10);
    return finish(&b, doc, "arm_four_bar_pd", err);
}

/* the spatial RSSR linkage: crank 0.3 m about the world z axis at the origin, coupler 1 m,
 * rocker 0.6 m turning about the world y axis at the anchor (0.9, 0.8, 0.6) */
#define RSSR_CRANK 0.3
#define RSSR_COUPLER 1.0
#define RSSR_ROCKER 0.6
#define RSSR_THICKNESS 0.04 /* m, the boxes' square section */

/* one box body along its own x axis from its inboard joint, 1 kg/m; the joint of the given type
 * (axis NULL for spherical) at location in the parent's frame, dependent */
static void put_bar(doc_builder *b, cJSON *bodies, const char *name, double length,
                    const char *joint_type, const double *axis, const double location[3])
{
    cJSON *body = put_object(b, bodies, NULL);
    put_string(b, body, "name", name);
    put_number(b, body, "mass", length);
    cJSON *shape = put_object(b, body, "shape");
    put_string(b, shape, "type", "box");
    put_vec3(b, shape, "size", length, RSSR_THICKNESS, RSSR_THICKNESS);
    put_vec3(b, shape, "centre", length / 2, 0, 0);
    cJSON *joint = put_object(b, body, "joint");
    put_string(b, joint, "type", joint_type);
    if (axis != NULL) put_vector(b, joint, "axis", 3, axis);
    put_vector(b, joint, "location", 3, location);
    put(b, joint, "independent", cJSON_CreateFalse());
}

/* Spatial RSSR linkage swinging under gravity -z from rest, every joint passive. */
static cJSON *rssr_passive(const cJSON *request, job_error *err)
{
    static const double z_axis[3] = {0, 0, 1}, y_axis[3] = {0, 1, 0}, origin[3] = {0, 0, 0};
    static const double crank_end[3] = {RSSR_CRANK, 0, 0}, coupler_end[3] = {RSSR_COUPLER, 0, 0};
    static const double rocker_end[3] = {RSSR_ROCKER, 0, 0};
    /* (crank + rocker, 0.8 coupler, 0.6 coupler), written as the numbers it prints as */
    static const double anchor[3] = {0.9, 0.8, 0.6};
    (void)request;

    /* q0: the crank along +x (angle 0); the coupler along u = (0, 0.8, 0.6), a quarter turn of
       its x axis about x-hat x u = (0, -0.6, 0.8); the rocker back parallel to the world, so its
       x axis points from the coupler's end to the anchor and its y axis is the closing axis */
    const double c = printable(sqrt(0.5)), s6 = printable(0.6 * c), s8 = printable(0.8 * c);
    const double q0[9] = {0, c, 0, -s6, s8, c, 0, s6, -s8};
    const double v0[7] = {0, 0, 0, 0, 0, 0, 0};
    doc_builder b = {0};
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", "Spatial RSSR linkage, passive (gravity -z)");

    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, 0, -9.81);
    cJSON *bodies = put_array(&b, scene, "bodies");
    put_bar(&b, bodies, "crank", RSSR_CRANK, "revolute", z_axis, origin);
    put_bar(&b, bodies, "coupler", RSSR_COUPLER, "spherical", NULL, crank_end);
    put_bar(&b, bodies, "rocker", RSSR_ROCKER, "spherical", NULL, coupler_end);
    put_loop(&b, scene, "revolute", y_axis, rocker_end, anchor, -1);
    put_vector(&b, scene, "q0", 9, q0);
    put_vector(&b, scene, "v0", 7, v0);
    put_controller(&b, doc, PRESET_NONE);
    put_run_settings_of(&b, doc, 5, 1e-10, 1e-12);
    return finish(&b, doc, "rssr_passive", err);
}

/* ---- trees ---- */

/* One sine (or cosine) of a tree preset's desired trajectory: q = offset + amplitude
 * sin(2 pi t / period + phase). */
typedef struct tree_sine {
    const char *type; /* "sine" or "cosine" */
    double amplitude, period, phase, offset;
} tree_sine;

/* the trajectory, one entry per coordinate, at the end of doc */
static void put_sines(doc_builder *b, cJSON *doc, int n, const tree_sine *sines)
{
    cJSON *traj = put_array(b, doc, "trajectory");
    for (int i = 0; i < n && !b->failed; i++) {
        cJSON *tr = put_object(b, traj, NULL);
        put_string(b, tr, "type", sines[i].type);
        put_number(b, tr, "amplitude", sines[i].amplitude);
        put_number(b, tr, "period", sines[i].period);
        put_number(b, tr, "phase", sines[i].phase);
        put_number(b, tr, "offset", sines[i].offset);
    }
}

/* A body of a tree at the end of bodies: its name, its parent by name (NULL: the default, the
 * previous body or the ground for the first), its mass, and a revolute joint about axis at
 * location (parent's frame); its shape is added by the caller. Returns the body. */
static cJSON *put_tree_body(doc_builder *b, cJSON *bodies, const char *name, const char *parent,
                            double mass, const double axis[3], const double location[3])
{
    cJSON *body = put_object(b, bodies, NULL);
    put_string(b, body, "name", name);
    if (parent != NULL) put_string(b, body, "parent", parent);
    put_number(b, body, "mass", mass);
    put_revolute(b, body, axis, location);
    return body;
}

/* a rod from the joint to end (body frame) as body's "shape" */
static void put_rod_shape(doc_builder *b, cJSON *body, double x, double y, double z)
{
    cJSON *shape = put_object(b, body, "shape");
    put_string(b, shape, "type", "rod");
    put_vec3(b, shape, "end", x, y, z);
}

/* a box of size (along the body's x, y, z axes) centred at centre (body frame) as body's
 * "shape" */
static void put_box_shape(doc_builder *b, cJSON *body, const double size[3], const double centre[3])
{
    cJSON *shape = put_object(b, body, "shape");
    put_string(b, shape, "type", "box");
    put_vector(b, shape, "size", 3, size);
    put_vector(b, shape, "centre", 3, centre);
}

/* a cylinder of radius r and length L along -z from the joint (body frame) as body's "shape" */
static void put_hanging_cylinder(doc_builder *b, cJSON *body, double r, double length)
{
    cJSON *shape = put_object(b, body, "shape");
    put_string(b, shape, "type", "cylinder");
    put_number(b, shape, "radius", r);
    put_number(b, shape, "length", length);
    put_vec3(b, shape, "axis", 0, 0, 1);
    put_vec3(b, shape, "centre", 0, 0, -length / 2);
}

/* the planar Y: an arm of 1 m, 1 kg, and on its tip two double pendulums of 0.5 m, 0.5 kg rods */
#define Y_ARM 1.0
#define Y_LINK 0.5
#define Y_N 5

/* Planar "Y" tree tracking sines: two double pendulums hanging from the tip of one arm. */
static cJSON *y_pendulum_pd(const cJSON *request, job_error *err)
{
    static const double z_axis[3] = {0, 0, 1}, origin[3] = {0, 0, 0};
    static const double arm_tip[3] = {0, -Y_ARM, 0}, link_tip[3] = {0, -Y_LINK, 0};
    static const char *const names[Y_N] = {"arm", "left upper", "left lower", "right upper",
                                           "right lower"};
    /* the right branch names the arm; the others hang from the previous body (the default) */
    static const char *const parents[Y_N] = {NULL, NULL, NULL, "arm", NULL};
    const double pi = PRESETS_PI;
    const double q0[Y_N] = {pi / 6, pi / 3, 0, -pi / 3, 0}, v0[Y_N] = {0, 0, 0, 0, 0};
    /* the arm swings, the branches open and close about +-0.5 rad, the lower links swing */
    const tree_sine sines[Y_N] = {
        {"sine", 0.6, 1.5, 0, 0},      {"cosine", 0.3, 1.5, 0, 0.5}, {"sine", 0.6, 1.5, 0, 0},
        {"cosine", 0.3, 1.5, 0, -0.5}, {"sine", 0.6, 1.5, 0, 0},
    };
    (void)request;
    doc_builder b = {0};
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", "Y pendulum, PD (planar tree: two double pendulums on an arm)");

    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, -9.81, 0);
    cJSON *bodies = put_array(&b, scene, "bodies");
    for (int k = 0; k < Y_N && !b.failed; k++) {
        const double *at = k == 0 ? origin : k == 1 || k == 3 ? arm_tip : link_tip;
        double length = k == 0 ? Y_ARM : Y_LINK;
        cJSON *body = put_tree_body(&b, bodies, names[k], parents[k], k == 0 ? 1 : 0.5, z_axis, at);
        put_rod_shape(&b, body, 0, -length, 0);
    }
    put_vector(&b, scene, "q0", Y_N, q0);
    put_vector(&b, scene, "v0", Y_N, v0);
    put_controller(&b, doc, PRESET_PD);
    put_sines(&b, doc, Y_N, sines);
    put_constant_disturbance(&b, doc, 0.2);
    put_run_settings(&b, doc);
    return finish(&b, doc, "y_pendulum_pd", err);
}

/* the Y whose one branch is a four-bar: arm_four_bar_pd's arm (1.5 m) carrying at its end the
 * four-bar's crank and coupler and, beside them, a double pendulum of 0.5 m rods; the rocker
 * last (the loop's tip), pinned to the arm 1 m in from its end */
#define Y_FOUR_BAR_N 6

/* A planar Y tree whose one branch is a four-bar closing on the arm (a loop on a tree): PD drives
 * the arm along a sine about +x, the crank round at 1 turn per 2 s and the double pendulum's two
 * joints along sines; the coupler, the rocker and the closing joint follow. */
static cJSON *y_four_bar_pd(const cJSON *request, job_error *err)
{
    static const double z_axis[3] = {0, 0, 1};
    static const char *const names[Y_FOUR_BAR_N] = {"arm",        "crank",      "coupler",
                                                    "upper link", "lower link", "rocker"};
    /* the crank and the upper link hang from the arm's end, the rocker from the coupler's */
    static const char *const parents[Y_FOUR_BAR_N] = {NULL, NULL, NULL, "arm", NULL, "coupler"};
    const double *len = arm_four_bar_length;
    const double length[Y_FOUR_BAR_N] = {len[0], len[1], len[2], Y_LINK, Y_LINK, len[3]};
    const double at[Y_FOUR_BAR_N][3] = {{0, 0, 0},       {0, -len[0], 0}, {0, -len[1], 0},
                                        {0, -len[0], 0}, {0, -Y_LINK, 0}, {0, -len[2], 0}};
    static const int independent[Y_FOUR_BAR_N] = {1, 1, 0, 1, 1, 0};
    const double anchor[3] = {0, -(ARM_LENGTH - FOUR_BAR_GROUND), 0}; /* in the arm's frame */
    const double rocker_end[3] = {0, -len[3], 0};
    const double v0[Y_FOUR_BAR_N] = {0, 0, 0, 0, 0, 0};
    double fb[ARM_FOUR_BAR_N];
    (void)request;
    arm_four_bar_q0(fb);
    /* the double pendulum hangs down from the horizontal arm: -pi/2 relative to it, then 0.3 */
    const double q0[Y_FOUR_BAR_N] = {fb[0], fb[1], fb[2], printable(-PRESETS_PI / 2 + 0.3),
                                     0.2,   fb[3]};
    doc_builder b = {0};
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", "Y with a four-bar branch, PD (a loop on a planar tree)");

    /* rods of 1 kg/m, gravity -y */
    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, -9.81, 0);
    cJSON *bodies = put_array(&b, scene, "bodies");
    for (int k = 0; k < Y_FOUR_BAR_N && !b.failed; k++) {
        cJSON *body = put_tree_body(&b, bodies, names[k], parents[k], length[k], z_axis, at[k]);
        put_rod_shape(&b, body, 0, -length[k], 0);
        cJSON *joint = cJSON_GetObjectItemCaseSensitive(body, "joint");
        if (joint != NULL) put(&b, joint, "independent", cJSON_CreateBool(independent[k]));
    }
    put_loop(&b, scene, "revolute", z_axis, rocker_end, anchor, 0);
    put_vector(&b, scene, "q0", Y_FOUR_BAR_N, q0);
    put_vector(&b, scene, "v0", Y_FOUR_BAR_N, v0);

    /* the arm and the crank as on the arm's four-bar; the pendulum's joints: sines */
    cJSON *traj = put_arm_crank_drive(&b, doc, q0);
    for (int i = 3; i <= 4 && !b.failed; i++) {
        cJSON *tr = put_object(&b, traj, NULL);
        put_string(&b, tr, "type", "sine");
        put_number(&b, tr, "amplitude", 0.4);
        put_number(&b, tr, "period", 1.5);
        put_number(&b, tr, "phase", 0);
        put_number(&b, tr, "offset", q0[i]);
    }
    put_run_settings_of(&b, doc, 10, 1e-8, 1e-10);
    return finish(&b, doc, "y_four_bar_pd", err);
}

/* the spatial hand, hanging along -z from the wrist at the origin: an aluminium palm (2700
 * kg/m^3) 0.08 wide (x), 0.02 thick (y), 0.1 m long (z); three fingers at x = -0.025, 0, 0.025
 * on its far edge, each of three square links 0.015 m across, 0.045, 0.03 and 0.025 m long */
#define HAND_DENSITY 2700.0 /* kg/m^3, aluminium */
#define HAND_FINGERS 3
#define HAND_LINKS 3
#define HAND_N (1 + HAND_FINGERS * HAND_LINKS)
#define HAND_FINGER_SIDE 0.015                                    /* m */
static const double hand_palm[3] = {0.08, 0.02, 0.1};             /* m */
static const double hand_link[HAND_LINKS] = {0.045, 0.03, 0.025}; /* m */
static const double hand_finger_x[HAND_FINGERS] = {-0.025, 0, 0.025};

/* Spatial hand tracking sines: a wrist (about y) driving a palm, three three-link fingers (each
 * joint about the palm's x axis) curling in a wave. */
static cJSON *spatial_hand_pd(const cJSON *request, job_error *err)
{
    static const double x_axis[3] = {1, 0, 0}, y_axis[3] = {0, 1, 0}, origin[3] = {0, 0, 0};
    static const char *const finger[HAND_FINGERS] = {"index", "middle", "ring"};
    static const char *const link[HAND_LINKS] = {"proximal", "middle", "distal"};
    const double pi = PRESETS_PI;
    double q0[HAND_N] = {0}, v0[HAND_N] = {0};
    tree_sine sines[HAND_N];
    (void)request;
    doc_builder b = {0};
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", "Spatial hand, PD (a palm on a wrist, three three-link fingers)");

    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, 0, -9.81);
    cJSON *bodies = put_array(&b, scene, "bodies");

    /* the palm on the wrist, swinging +-0.3 rad about y every 2 s */
    const double palm_centre[3] = {0, 0, -hand_palm[2] / 2};
    double palm_mass = printable(HAND_DENSITY * hand_palm[0] * hand_palm[1] * hand_palm[2]);
    cJSON *palm = put_tree_body(&b, bodies, "palm", NULL, palm_mass, y_axis, origin);
    put_box_shape(&b, palm, hand_palm, palm_centre);
    sines[0] = (tree_sine){"sine", 0.3, 2, 0, 0};

    /* each finger on the palm's far edge; its joints curl between 0 and 0.8 rad, each finger a
       third of a period after the one before */
    int k = 1;
    for (int f = 0; f < HAND_FINGERS; f++) {
        for (int l = 0; l < HAND_LINKS && !b.failed; l++, k++) {
            char name[48];
            snprintf(name, sizeof name, "%s %s", finger[f], link[l]);
            const double base[3] = {hand_finger_x[f], 0, -hand_palm[2]};
            const double prev[3] = {0, 0, l > 0 ? -hand_link[l - 1] : 0};
            double len = hand_link[l];
            double mass = printable(HAND_DENSITY * HAND_FINGER_SIDE * HAND_FINGER_SIDE * len);
            cJSON *body = put_tree_body(&b, bodies, name, l == 0 ? "palm" : NULL, mass, x_axis,
                                        l == 0 ? base : prev);
            const double size[3] = {HAND_FINGER_SIDE, HAND_FINGER_SIDE, len};
            const double centre[3] = {0, 0, -len / 2};
            put_box_shape(&b, body, size, centre);
            sines[k] = (tree_sine){"sine", 0.4, 1.5, printable(-2 * pi * f / HAND_FINGERS), 0.4};
        }
    }
    put_vector(&b, scene, "q0", HAND_N, q0);
    put_vector(&b, scene, "v0", HAND_N, v0);
    put_controller(&b, doc, PRESET_PD);
    put_sines(&b, doc, HAND_N, sines);
    put_run_settings(&b, doc);
    return finish(&b, doc, "spatial_hand_pd", err);
}

/* the two-arm torso, gravity -z: a torso box 0.3 wide (x), 0.2 deep (y), 0.5 m tall (z) on a
 * waist about z at the origin, shoulders at (+-0.2, 0, 0.45) m; each arm an upper arm, a forearm
 * and a hand, solid cylinders hanging along -z. Masses and lengths are Winter's anthropometric
 * fractions (Biomechanics and Motor Control of Human Movement, 4th ed., 2009, Table 4.1) of a
 * 70 kg, 1.75 m person, lengths to the centimetre: thorax and abdomen 0.355 M (25 kg); upper arm
 * 0.028 M, 0.186 H; forearm 0.016 M, 0.146 H; hand 0.006 M, 0.108 H. Shoulder and elbow turn
 * about x (swinging forward and back), the wrist about y. */
#define TORSO_ARMS 2
#define TORSO_LINKS 3
#define TORSO_N (1 + TORSO_ARMS * TORSO_LINKS)
#define TORSO_MASS 25.0                                               /* kg */
static const double torso_size[3] = {0.3, 0.2, 0.5};                  /* m */
static const double torso_link[TORSO_LINKS] = {0.33, 0.26, 0.19};     /* m */
static const double torso_radius[TORSO_LINKS] = {0.045, 0.035, 0.03}; /* m */
static const double torso_mass[TORSO_LINKS] = {1.96, 1.12, 0.42};     /* kg */

/* Spatial torso on a waist with two three-link arms swinging in opposition, tracking sines. */
static cJSON *two_arm_torso_pd(const cJSON *request, job_error *err)
{
    static const double x_axis[3] = {1, 0, 0}, y_axis[3] = {0, 1, 0}, z_axis[3] = {0, 0, 1};
    static const double origin[3] = {0, 0, 0};
    static const char *const side[TORSO_ARMS] = {"left", "right"};
    static const char *const link[TORSO_LINKS] = {"upper arm", "forearm", "hand"};
    const double pi = PRESETS_PI;
    double q0[TORSO_N] = {0}, v0[TORSO_N] = {0};
    tree_sine sines[TORSO_N];
    (void)request;
    doc_builder b = {0};
    cJSON *doc = cJSON_CreateObject();
    put_string(&b, doc, "name", "Two-arm torso, PD (a torso on a waist, two three-link arms)");

    cJSON *scene = put_object(&b, doc, "scene");
    put_vec3(&b, scene, "gravity", 0, 0, -9.81);
    cJSON *bodies = put_array(&b, scene, "bodies");

    /* the torso turns +-0.4 rad about the waist every 3 s */
    const double torso_centre[3] = {0, 0, torso_size[2] / 2};
    cJSON *torso = put_tree_body(&b, bodies, "torso", NULL, TORSO_MASS, z_axis, origin);
    put_box_shape(&b, torso, torso_size, torso_centre);
    sines[0] = (tree_sine){"sine", 0.4, 3, 0, 0};

    /* the arms swing half a period apart: shoulders +-0.6 rad, elbows bent 0.5 +- 0.3 rad, the
       wrists +-0.3 rad, every 2 s */
    int k = 1;
    for (int a = 0; a < TORSO_ARMS; a++) {
        for (int l = 0; l < TORSO_LINKS && !b.failed; l++, k++) {
            char name[48];
            snprintf(name, sizeof name, "%s %s", side[a], link[l]);
            const double shoulder[3] = {a == 0 ? 0.2 : -0.2, 0, 0.45};
            const double prev[3] = {0, 0, l > 0 ? -torso_link[l - 1] : 0};
            cJSON *body =
                put_tree_body(&b, bodies, name, l == 0 ? "torso" : NULL, torso_mass[l],
                              l == TORSO_LINKS - 1 ? y_axis : x_axis, l == 0 ? shoulder : prev);
            put_hanging_cylinder(&b, body, torso_radius[l], torso_link[l]);
            double phase = a == 0 ? 0 : printable(pi);
            static const double amplitude[TORSO_LINKS] = {0.6, 0.3, 0.3};
            static const double offset[TORSO_LINKS] = {0, 0.5, 0};
            sines[k] = (tree_sine){"sine", amplitude[l], 2, phase, offset[l]};
        }
    }
    put_vector(&b, scene, "q0", TORSO_N, q0);
    put_vector(&b, scene, "v0", TORSO_N, v0);
    put_controller(&b, doc, PRESET_PD);
    put_sines(&b, doc, TORSO_N, sines);
    put_run_settings(&b, doc);
    return finish(&b, doc, "two_arm_torso_pd", err);
}

/* ---- the paper's triple pendulum as it is in a lab (issue 21) ---- */

/* The triple pendulum with PID, changed after it is built: its controller sampled every period
 * s with zero-order hold (0: continuous), its actuators limited to +-limit N m (0: none), and
 * the integrator's method (NULL: the paper's dopri5). */
static cJSON *lab_triple_pendulum(const char *preset_name, const char *name, double period,
                                  double limit, const char *method, job_error *err)
{
    cJSON *doc = triple_pendulum(preset_name, name, PRESET_PID, err);
    if (doc == NULL) return NULL;
    doc_builder b = {0};
    if (period > 0)
        put_number(&b, cJSON_GetObjectItemCaseSensitive(doc, "controller"), "sample_period",
                   period);
    if (limit > 0) put_number(&b, put_object(&b, doc, "plant"), "torque_limit", limit);
    if (method != NULL) {
        cJSON *integ = cJSON_GetObjectItemCaseSensitive(doc, "integrator");
        cJSON *m = cJSON_CreateString(method);
        if (m == NULL || !cJSON_ReplaceItemInObjectCaseSensitive(integ, "method", m)) {
            cJSON_Delete(m);
            b.failed = 1;
        }
    }
    return finish(&b, doc, preset_name, err);
}

#define LAB_TRIPLE(fn, period, limit, method, label)                                               \
    static cJSON *fn(const cJSON *request, job_error *err)                                         \
    {                                                                                              \
        (void)request;                                                                             \
        return lab_triple_pendulum(#fn, label, period, limit, method, err);                        \
    }
LAB_TRIPLE(triple_pendulum_pid_1khz, 1e-3, 0, NULL,
           "Triple pendulum, PID sampled at 1 kHz (scene of " PAPER ", sec. 7.1)")
LAB_TRIPLE(triple_pendulum_pid_200hz, 5e-3, 0, NULL,
           "Triple pendulum, PID sampled at 200 Hz (scene of " PAPER ", sec. 7.1)")
LAB_TRIPLE(triple_pendulum_pid_50hz, 2e-2, 0, NULL,
           "Triple pendulum, PID sampled at 50 Hz (scene of " PAPER ", sec. 7.1)")
LAB_TRIPLE(triple_pendulum_pid_limited, 0, 50, "bdf",
           "Triple pendulum, PID with +-50 N m actuators (scene of " PAPER ", sec. 7.1)")

/* ---- the table ---- */

/* build_SCENE_SUFFIX: the preset "SCENE_SUFFIX", made by the scene's builder SCENE(name, label,
   controller, err) */
#define PRESET(scene, suffix, ctrl, label)                                                         \
    static cJSON *build_##scene##_##suffix(const cJSON *request, job_error *err)                   \
    {                                                                                              \
        (void)request;                                                                             \
        return scene(#scene "_" #suffix, label, ctrl, err);                                        \
    }
#define TRIPLE(suffix, ctrl, label) PRESET(triple_pendulum, suffix, ctrl, label)
#define SPATIAL(suffix, ctrl, label) PRESET(spatial_double_pendulum, suffix, ctrl, label)
#define FIVE_BAR(suffix, ctrl, label) PRESET(five_bar, suffix, ctrl, label)

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

FIVE_BAR(pd, PRESET_PD, "Five-bar closed chain, PD (" PAPER ", sec. 7.2)")
FIVE_BAR(pid, PRESET_PID, "Five-bar closed chain, PID (" PAPER ", sec. 7.2)")
FIVE_BAR(poles, PRESET_POLES, "Five-bar closed chain, pole placement (" PAPER ", sec. 7.2)")
FIVE_BAR(lqr, PRESET_LQR, "Five-bar closed chain, LQR (" PAPER ", sec. 7.2)")

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
#define FIVE_BAR_SUMMARY(ctrl)                                                                     \
    "Five-bar closed chain of sec. 7.2, joints 0-2 to (0, pi/4, -3 pi/4), " ctrl ", 10 s"

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
     "Pendulum of n rods (\"n\" 2..65536, default 8) from +-pi/6 to rest, " PD_GAINS, n_link_params,
     n_link_pendulum},
    {"five_bar_pd", FIVE_BAR_SUMMARY(PD_GAINS), no_params, build_five_bar_pd},
    {"five_bar_pid", FIVE_BAR_SUMMARY(PID_GAINS), no_params, build_five_bar_pid},
    {"five_bar_poles", FIVE_BAR_SUMMARY(POLES), no_params, build_five_bar_poles},
    {"five_bar_lqr", FIVE_BAR_SUMMARY(LQR_WEIGHTS), no_params, build_five_bar_lqr},
    {"four_bar_passive",
     "Four-bar crank-rocker (ground 1, crank 0.4, coupler 1, rocker 0.8 m) falling from rest, "
     "all joints passive",
     no_params, four_bar_passive},
    {"arm_four_bar_pd",
     "Four-bar crank-rocker on an arm (a loop closed on a body): the arm swings, the crank "
     "turns, " PD_GAINS,
     no_params, arm_four_bar_pd},
    {"rssr_passive",
     "Spatial RSSR linkage (crank about z, rocker about y) falling from rest, gravity -z, all "
     "joints passive",
     no_params, rssr_passive},
    {"y_pendulum_pd",
     "Planar Y tree: two double pendulums on the tip of an arm, tracking sines, " PD_GAINS
     ", 0.2 N m",
     no_params, y_pendulum_pd},
    {"y_four_bar_pd",
     "Planar Y whose one branch is a four-bar closing on the arm (a loop on a tree), beside a "
     "double pendulum: the arm swings, the crank turns, " PD_GAINS,
     no_params, y_four_bar_pd},
    {"spatial_hand_pd",
     "Spatial hand: a wrist driving a palm with three three-link fingers curling in a wave, "
     "tracking sines, " PD_GAINS ", gravity -z",
     no_params, spatial_hand_pd},
    {"two_arm_torso_pd",
     "Spatial torso on a waist with two three-link arms swinging in opposition, tracking "
     "sines, " PD_GAINS ", gravity -z",
     no_params, two_arm_torso_pd},
    {"ur5_min_jerk", "UR5 (DH table) moving between two poses by minimum jerk, " PD_GAINS,
     no_params, presets_ur5},
    {"iiwa14_min_jerk",
     "KUKA LBR iiwa 14 (URDF) moving between two poses by minimum jerk, " PD_GAINS, no_params,
     presets_iiwa14},
    {"triple_pendulum_pid_1khz", TRIPLE_SUMMARY(PID_GAINS " sampled at 1 kHz (zero-order hold)"),
     no_params, triple_pendulum_pid_1khz},
    {"triple_pendulum_pid_200hz", TRIPLE_SUMMARY(PID_GAINS " sampled at 200 Hz (zero-order hold)"),
     no_params, triple_pendulum_pid_200hz},
    {"triple_pendulum_pid_50hz", TRIPLE_SUMMARY(PID_GAINS " sampled at 50 Hz (zero-order hold)"),
     no_params, triple_pendulum_pid_50hz},
    {"triple_pendulum_pid_limited",
     TRIPLE_SUMMARY(PID_GAINS " with +-50 N m actuators (anti-windup; bdf)"), no_params,
     triple_pendulum_pid_limited},
    {"panda_min_jerk",
     "Franka Emika Panda (URDF) moving between two poses by minimum jerk while its two fingers "
     "open, " PD_GAINS,
     no_params, presets_panda},
    {"two_link_min_jerk",
     "Two-link planar arm with point masses at the link ends (DH table; Modern Robotics 8.1.1) "
     "moving between two poses by minimum jerk, " PD_GAINS ", gravity -y",
     no_params, presets_two_link},
    {"two_link_lab_payload",
     "Two-link planar arm (Modern Robotics 8.1.1) with joint friction and an unmodelled 0.5 kg "
     "payload at its tip, minimum-jerk move, " PD_GAINS ", gravity -y",
     no_params, presets_two_link_lab},
    {"puma560_min_jerk",
     "Puma 560 (modified DH table of Armstrong, Khatib and Burdick 1986) moving between two "
     "poses by minimum jerk, " PD_GAINS,
     no_params, presets_puma560},
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

/* ---- names after a controller override ---- */

/* the label a preset's name gives a controller type (job_json.h), or NULL */
static const char *controller_label(const char *type)
{
    static const char *const labels[][2] = {
        {"none", "passive"},
        {"pd", "PD"},
        {"pid", "PID"},
        {"poles", "pole placement"},
        {"lqr", "LQR"},
        {"joint_pd", "joint PD"},
        {"pd_gravity", "PD with gravity compensation"},
        {"feedforward", "feedforward"},
    };
    for (size_t i = 0; i < sizeof labels / sizeof labels[0]; i++) {
        if (strcmp(labels[i][0], type) == 0) return labels[i][1];
    }
    return NULL;
}

/* the first ", LABEL" in name that ends the name or is followed by ' ', ',' or '(', or NULL */
static const char *find_label(const char *name, const char *label)
{
    size_t n = strlen(label);
    for (const char *p = strstr(name, ", "); p != NULL; p = strstr(p + 1, ", ")) {
        const char *end = p + 2 + n;
        if (strncmp(p + 2, label, n) == 0 && (*end == '\0' || strchr(" ,(", *end) != NULL)) {
            return p;
        }
    }
    return NULL;
}

int presets_name_for_controller(const char *name, const char *from, const char *to, char *buf,
                                size_t len)
{
    const char *old_label = controller_label(from), *new_label = controller_label(to);
    if (old_label == NULL || new_label == NULL || len == 0) return -1;

    /* the name with the label replaced (or appended) */
    char renamed[2 * JOB_MAX_NAME];
    const char *at = find_label(name, old_label);
    if (at != NULL) {
        snprintf(renamed, sizeof renamed, "%.*s, %s%s", (int)(at - name), name, new_label,
                 at + 2 + strlen(old_label));
    } else {
        snprintf(renamed, sizeof renamed, "%s, %s", name, new_label);
    }

    /* the paper's reference becomes the scene's */
    const char *ref = strstr(renamed, "(" PAPER);
    if (ref != NULL) {
        snprintf(buf, len, "%.*s(scene of %s", (int)(ref - renamed), renamed, ref + 1);
    } else {
        snprintf(buf, len, "%s", renamed);
    }
    return 0;
}
