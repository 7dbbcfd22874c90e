/*
 * presets_robots.c - robot arms, a textbook's and industrial ones, as ready-made jobs
 * (presets.h), each given in its published form, a DH table or a URDF document, which the job
 * format converts into bodies (dh.c, urdf.c), and each tracking a minimum-jerk move between two
 * poses with CTC (PD, kp 100 s^-2, kv 20 s^-1): the move takes 2 s from the start pose, which is
 * q0, so with the exact model the tracking error stays at the integrator's tolerance; 3 s at dopri5
 * rtol 1e-8, atol 1e-10, sampled every 0.01 s; gravity -z (the planar arm's -y).
 *
 *  - The two-link planar arm with point masses (standard DH): Lynch and Park, Modern Robotics
 *    (2017), section 8.1.1, Figure 8.1: links of lengths L1, L2 turning about z, a point mass m1
 *    at the end of link 1 (at joint 2) and m2 at the end of link 2, gravity g along -y, the
 *    joint angles measured from x (theta1) and from link 1 (theta2). The book keeps the values
 *    symbolic; here L1 = L2 = 1 m and m1 = m2 = 1 kg, and g = 9.81 m/s^2. Each mass sits at its
 *    DH frame's origin with no inertia, so M(q) = [[m1 L1^2 + m2 (L1^2 + 2 L1 L2 c2 + L2^2),
 *    m2 (L1 L2 c2 + L2^2)], [., m2 L2^2]] (the book's eq. 8.9), positive definite for m1 > 0.
 *    Move: from hanging straight down (-pi/2, 0) to (pi/6, pi/2).
 *  - UR5 (standard DH): a, d and alpha, the link masses and the centres of mass in the DH frames
 *    from Universal Robots, "Parameters for calculations of kinematics and dynamics"
 *    (universal-robots.com, UR5 column); the link inertias, principal about the centres of mass,
 *    those of ur_description's ur5 (cylinder approximations), as Lynch and Park, Modern Robotics
 *    (2017), list them (G1..G6). Move: from (0, -pi/2, 0, -pi/2, 0, 0) to (pi/3, -pi/3, pi/3,
 *    -pi/2, -pi/2, pi/4).
 *  - KUKA LBR iiwa 14 (URDF): the joint origins and axes, the link masses, centres of mass and
 *    inertias, and the joints' limits and damping of Drake's iiwa14_no_collision.urdf
 *    (RobotLocomotion/drake, manipulation/models/iiwa_description); link 0 is fixed to the world
 *    and the end-effector frames are massless, so 7 bodies. Move: from 0 to (0.5, 0.6, 0, -1.2,
 *    0, 0.8, 0).
 *  - Franka Emika Panda with its two fingers (URDF, a tree of 9 bodies): the joint origins, axes,
 *    limits and the hand's and fingers' joints of franka_description (frankaemika/franka_ros,
 *    robots/common/franka_arm.xacro and franka_hand.xacro, equal to Franka's modified DH table);
 *    the arm links' masses, centres of mass and inertias (link frames) identified by Gaz,
 *    Cognetti, Oliva, Robuffo Giordano and De Luca, "Dynamic Identification of the Franka Emika
 *    Panda Robot With Retrieval of Feasible Parameters Using Penalty-Based Optimization", IEEE
 *    RA-L 4(4), 2019, as franka_description's robots/common/inertial.yaml lists them; the hand's
 *    and fingers' values from that same file (franka_description's, not identified). Link 1's
 *    centre-of-mass height and its inertia about x and y do not act on a link turning about the
 *    vertical and are not identifiable; the file's values are kept. All values pass the model's
 *    checks as published (link 1's principal moments, about 0.7034, 0.7071 and 0.0085 kg m^2,
 *    satisfy the triangle inequality). The real gripper couples its fingers with <mimic>, which
 *    the importer refuses: here each finger has its own prismatic joint and trajectory, as in
 *    Drake's franka_description. Link 0 is fixed to the world (its inertial plays no part), the
 *    flange (link 8) is massless and the hand is fixed to it, so the hand is part of link 7's
 *    body and the fingers hang from that body. Move: from Franka's ready pose (0, -pi/4, 0,
 *    -3pi/4, 0, pi/2, pi/4) to (0.6, -0.2, -0.4, -2.0, 0.3, 2.0, 1.2), inside the joint limits,
 *    while both fingers open from 0.01 m to 0.04 m.
 *  - Puma 560 (modified DH): Armstrong, Khatib and Burdick, "The Explicit Dynamic Model and
 *    Inertial Parameters of the PUMA 560 Arm", IEEE ICRA 1986, as Corke's Robotics Toolbox
 *    mdl_puma560akb lists them (the link table L(1..6): a_(i-1), alpha_(i-1), d_i; the masses
 *    L(i).m; the centres of mass L(i).r in frame i; the inertias L(i).I, whose products are
 *    zero): link 1 has no mass (AKB found none; it does not enter the dynamics) and 0.35 kg m^2
 *    about its axis, a body the model accepts because M(q) stays positive definite. The motor
 *    inertias and gear ratios (Jm, G) and friction of that file are left out: ctcsim models the
 *    links. Move: from Corke's qz (all zero) to (pi/3, -pi/4, pi/4, pi/6, -pi/3, pi/4).
 * The Stanford arm is not here: its usual source, Corke's mdl_stanford (dynamic data cited to
 * Paul, Robot Manipulators, 1981, tables 6.4-6.6), gives link 5 principal moments (0.003,
 * 0.0004, 0) kg m^2, which break the triangle inequality, where Corke's older stanford.m of the
 * same table gives (0.003, 0.003, 0.0004) and moves that link's centre of mass from (0, 0,
 * 0.566) to (0, 0.566, 0.003); and its centres of mass mix units: link 1's (0, 0.0175, -0.1105)
 * reads as metres, links 2, 3 and 6's (-1.054, -6.447, 1.554 along y, z, z) cannot be metres on
 * an arm 0.412 m tall, yet as inches or centimetres they give different arms. Without Paul's
 * tables to settle which, any correction would be a guess no source backs.
 */
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

#include "presets_robots.h"

#define HALF_PI 1.5707963267948966
#define MOVE_END 2.0 /* s */
#define DURATION 3.0 /* s */
#define KP 100.0     /* s^-2 */
#define KV 20.0      /* s^-1 */

/* Adds a PD controller, a minimum-jerk move of each of n coordinates from[i] -> to[i] over
 * [0, MOVE_END], q0 = from, v0 = 0, and the run settings to doc (whose "scene" exists). Returns
 * doc, or NULL (doc deleted) with err filled when an allocation failed. */
static cJSON *finish_robot(cJSON *doc, int n, const double *from, const double *to,
                           const char *preset_name, job_error *err)
{
    static const double zero[16] = {0};
    cJSON *scene = cJSON_GetObjectItemCaseSensitive(doc, "scene");
    cJSON *ctrl = cJSON_AddObjectToObject(doc, "controller");
    cJSON *traj = cJSON_AddArrayToObject(doc, "trajectory");
    cJSON *integ = cJSON_AddObjectToObject(doc, "integrator");
    cJSON *out = cJSON_AddObjectToObject(doc, "output");
    int ok = scene != NULL && ctrl != NULL && traj != NULL && integ != NULL && out != NULL &&
             cJSON_AddItemToObject(scene, "q0", cJSON_CreateDoubleArray(from, n)) &&
             cJSON_AddItemToObject(scene, "v0", cJSON_CreateDoubleArray(zero, n)) &&
             cJSON_AddStringToObject(ctrl, "type", "pd") &&
             cJSON_AddNumberToObject(ctrl, "kp", KP) && cJSON_AddNumberToObject(ctrl, "kv", KV);
    for (int i = 0; ok && i < n; i++) {
        cJSON *t = cJSON_CreateObject();
        ok = cJSON_AddItemToArray(traj, t) && cJSON_AddStringToObject(t, "type", "min_jerk") &&
             cJSON_AddNumberToObject(t, "from", from[i]) &&
             cJSON_AddNumberToObject(t, "to", to[i]) && cJSON_AddNumberToObject(t, "start", 0) &&
             cJSON_AddNumberToObject(t, "end", MOVE_END);
    }
    ok = ok && cJSON_AddStringToObject(integ, "method", "dopri5") &&
         cJSON_AddNumberToObject(integ, "rtol", 1e-8) &&
         cJSON_AddNumberToObject(integ, "atol", 1e-10) &&
         cJSON_AddNumberToObject(doc, "duration", DURATION) &&
         cJSON_AddNumberToObject(out, "interval", 0.01);
    if (ok) return doc;
    cJSON_Delete(doc);
    err->code = JOB_NO_MEMORY;
    err->field[0] = '\0';
    snprintf(err->message, sizeof err->message, "out of memory building preset %s", preset_name);
    return NULL;
}

/* one row of a DH table: the joint's geometry and link i's mass, centre of mass and principal
 * moments of inertia (about the centre of mass, along DH frame i's axes) */
typedef struct dh_link {
    const char *name;
    double a, alpha, d, mass, com[3], inertia[3];
} dh_link;

/* The document of the arm of n DH rows (convention "standard" or "modified"), named title, with
 * gravity g, moving from -> to by finish_robot. Returns NULL with err filled (out of memory). */
static cJSON *robot_from_dh(const char *title, const char *convention, const dh_link *rows, int n,
                            const double g[3], const double *from, const double *to,
                            const char *preset_name, job_error *err)
{
    cJSON *doc = cJSON_CreateObject();
    cJSON *scene = cJSON_AddObjectToObject(doc, "scene");
    cJSON *dh = cJSON_AddObjectToObject(scene, "dh");
    cJSON *list = cJSON_AddArrayToObject(dh, "rows");
    int ok = cJSON_AddStringToObject(doc, "name", title) &&
             cJSON_AddItemToObject(scene, "gravity", cJSON_CreateDoubleArray(g, 3)) &&
             cJSON_AddStringToObject(dh, "convention", convention) && list != NULL;
    for (int i = 0; ok && i < n; i++) {
        const dh_link *l = &rows[i];
        cJSON *r = cJSON_CreateObject();
        ok = cJSON_AddItemToArray(list, r) && cJSON_AddStringToObject(r, "name", l->name) &&
             cJSON_AddNumberToObject(r, "a", l->a) &&
             cJSON_AddNumberToObject(r, "alpha", l->alpha) &&
             cJSON_AddNumberToObject(r, "d", l->d) && cJSON_AddNumberToObject(r, "mass", l->mass) &&
             cJSON_AddItemToObject(r, "com", cJSON_CreateDoubleArray(l->com, 3)) &&
             cJSON_AddItemToObject(r, "inertia", cJSON_CreateDoubleArray(l->inertia, 3));
    }
    if (!ok) {
        cJSON_Delete(doc);
        err->code = JOB_NO_MEMORY;
        err->field[0] = '\0';
        snprintf(err->message, sizeof err->message, "out of memory building preset %s",
                 preset_name);
        return NULL;
    }
    return finish_robot(doc, n, from, to, preset_name, err);
}

/* The document of the arm described by the URDF text (NULL: it could not be written), named
 * title, with gravity -z, moving from -> to (n coordinates) by finish_robot. Returns NULL with err
 * filled (out of memory). */
static cJSON *robot_from_urdf(const char *title, const char *text, int n, const double *from,
                              const double *to, const char *preset_name, job_error *err)
{
    static const double gravity[3] = {0, 0, -9.81};
    cJSON *doc = text != NULL ? cJSON_CreateObject() : NULL;
    cJSON *scene = cJSON_AddObjectToObject(doc, "scene");
    int ok = doc != NULL && cJSON_AddStringToObject(doc, "name", title) &&
             cJSON_AddItemToObject(scene, "gravity", cJSON_CreateDoubleArray(gravity, 3)) &&
             cJSON_AddStringToObject(scene, "urdf", text);
    if (!ok) {
        cJSON_Delete(doc);
        err->code = JOB_NO_MEMORY;
        err->field[0] = '\0';
        snprintf(err->message, sizeof err->message, "out of memory building preset %s",
                 preset_name);
        return NULL;
    }
    return finish_robot(doc, n, from, to, preset_name, err);
}

/* ---- the two-link planar arm with point masses ---- */

/* standard DH: frame i sits at link i's far end, where its point mass is */
static const dh_link two_link[2] = {
    {"link1", 1.0, 0, 0, 1.0, {0, 0, 0}, {0, 0, 0}},
    {"link2", 1.0, 0, 0, 1.0, {0, 0, 0}, {0, 0, 0}},
};

cJSON *presets_two_link(const cJSON *request, job_error *err)
{
    (void)request;
    static const double from[2] = {-HALF_PI, 0};
    static const double to[2] = {0.52359877559829887, HALF_PI};
    static const double gravity[3] = {0, -9.81, 0};
    return robot_from_dh("Two-link planar arm with point masses at the link ends, minimum-jerk "
                         "move, PD (Lynch and Park, Modern Robotics, sec. 8.1.1)",
                         "standard", two_link, 2, gravity, from, to, "two_link_min_jerk", err);
}

/* The same arm as it is in a lab (issue 21): each joint with viscous friction 0.2 N m s/rad and
 * Coulomb friction 1 N m (regularised over 0.01 rad/s), and a 0.5 kg payload at link 2's tip,
 * all unknown to the controller, whose model is the textbook arm. */
cJSON *presets_two_link_lab(const cJSON *request, job_error *err)
{
    cJSON *doc = presets_two_link(request, err);
    if (doc == NULL) return NULL;
    static const double tip[3] = {1, 0, 0};
    cJSON *name = cJSON_CreateString("Two-link planar arm with point masses at the link ends "
                                     "(Lynch and Park, Modern Robotics, sec. 8.1.1), joint "
                                     "friction and a 0.5 kg payload the PD controller's model "
                                     "lacks, minimum-jerk move");
    cJSON *plant = cJSON_CreateObject(), *model = cJSON_CreateObject();
    cJSON *payload = cJSON_AddObjectToObject(model, "payload");
    cJSON *ctrl = cJSON_GetObjectItemCaseSensitive(doc, "controller");
    int ok = name != NULL && plant != NULL && payload != NULL && ctrl != NULL &&
             cJSON_AddNumberToObject(plant, "viscous", 0.2) &&
             cJSON_AddNumberToObject(plant, "coulomb", 1) &&
             cJSON_AddNumberToObject(plant, "coulomb_velocity", 0.01) &&
             cJSON_AddNumberToObject(payload, "body", 1) &&
             cJSON_AddNumberToObject(payload, "mass", 0.5) &&
             cJSON_AddItemToObject(payload, "point", cJSON_CreateDoubleArray(tip, 3)) &&
             cJSON_ReplaceItemInObjectCaseSensitive(doc, "name", name);
    if (ok) name = NULL;
    ok = ok && cJSON_AddItemToObject(doc, "plant", plant);
    if (ok) plant = NULL;
    ok = ok && cJSON_AddItemToObject(ctrl, "model", model);
    if (ok) model = NULL;
    cJSON_Delete(name);
    cJSON_Delete(plant);
    cJSON_Delete(model);
    if (!ok) {
        cJSON_Delete(doc);
        err->code = JOB_NO_MEMORY;
        err->field[0] = '\0';
        snprintf(err->message, sizeof err->message,
                 "out of memory building preset two_link_lab_payload");
        return NULL;
    }
    return doc;
}

/* ---- UR5 ---- */

static const dh_link ur5[6] = {
    {"shoulder",
     0,
     HALF_PI,
     0.089159,
     3.7,
     {0, -0.02561, 0.00193},
     {0.010267495893, 0.010267495893, 0.00666}},
    {"upper_arm",
     -0.425,
     0,
     0,
     8.393,
     {0.2125, 0, 0.11336},
     {0.22689067591, 0.22689067591, 0.0151074}},
    {"forearm",
     -0.39225,
     0,
     0,
     2.33,
     {0.15, 0, 0.0265},
     {0.049443313556, 0.049443313556, 0.004095}},
    {"wrist_1",
     0,
     HALF_PI,
     0.10915,
     1.219,
     {0, -0.0018, 0.01634},
     {0.111172755531, 0.111172755531, 0.21942}},
    {"wrist_2",
     0,
     -HALF_PI,
     0.09465,
     1.219,
     {0, 0.0018, 0.01634},
     {0.111172755531, 0.111172755531, 0.21942}},
    {"wrist_3",
     0,
     0,
     0.0823,
     0.1879,
     {0, 0, -0.001159},
     {0.0171364731454, 0.0171364731454, 0.033822}},
};

cJSON *presets_ur5(const cJSON *request, job_error *err)
{
    (void)request;
    static const double from[6] = {0, -HALF_PI, 0, -HALF_PI, 0, 0};
    static const double to[6] = {1.0471975511965976, -1.0471975511965976,
                                 1.0471975511965976, -HALF_PI,
                                 -HALF_PI,           0.78539816339744831};
    static const double gravity[3] = {0, 0, -9.81};
    return robot_from_dh("UR5 minimum-jerk move, PD (DH, masses and centres of mass of "
                         "Universal Robots; inertias of ur_description)",
                         "standard", ur5, 6, gravity, from, to, "ur5_min_jerk", err);
}

/* ---- Puma 560 ---- */

/* Armstrong, Khatib and Burdick 1986 as Corke's mdl_puma560akb lists them: modified DH, row i
 * holding a_(i-1), alpha_(i-1) and d_i; m_i, r_i and the diagonal of I_i (kg m^2, about the
 * centre of mass, in frame i; the products are zero) */
static const dh_link puma560[6] = {
    {"link1", 0, 0, 0, 0, {0, 0, 0}, {0, 0, 0.35}},
    {"link2", 0, -HALF_PI, 0.2435, 17.4, {0.068, 0.006, -0.016}, {0.13, 0.524, 0.539}},
    {"link3", 0.4318, 0, -0.0934, 4.8, {0, -0.070, 0.014}, {0.066, 0.0125, 0.066}},
    {"link4", -0.0203, HALF_PI, 0.4331, 0.82, {0, 0, -0.019}, {1.8e-3, 1.8e-3, 1.3e-3}},
    {"link5", 0, -HALF_PI, 0, 0.34, {0, 0, 0}, {0.3e-3, 0.3e-3, 0.4e-3}},
    {"link6", 0, HALF_PI, 0, 0.09, {0, 0, 0.032}, {0.15e-3, 0.15e-3, 0.04e-3}},
};

cJSON *presets_puma560(const cJSON *request, job_error *err)
{
    (void)request;
    static const double from[6] = {0, 0, 0, 0, 0, 0};
    static const double to[6] = {1.0471975511965976,  -0.78539816339744831, 0.78539816339744831,
                                 0.52359877559829887, -1.0471975511965976,  0.78539816339744831};
    static const double gravity[3] = {0, 0, -9.81};
    return robot_from_dh("Puma 560 minimum-jerk move, PD (modified DH and inertial parameters of "
                         "Armstrong, Khatib and Burdick 1986, as Corke's mdl_puma560akb)",
                         "modified", puma560, 6, gravity, from, to, "puma560_min_jerk", err);
}

/* ---- KUKA LBR iiwa 14 ---- */

/* Drake's iiwa14_no_collision.urdf, its links' inertials and its joints (origins, axes, limits,
 * damping); visuals, materials, Gazebo and transmission elements left out. The head of the
 * document: */
static const char iiwa14_urdf[] =
    "<?xml version=\"1.0\"?>\n"
    "<robot name=\"iiwa14\">\n"
    "  <link name=\"base\"/>\n"
    "  <joint name=\"iiwa_base_joint\" type=\"fixed\">\n"
    "    <parent link=\"base\"/><child link=\"iiwa_link_0\"/>\n"
    "  </joint>\n"
    "  <link name=\"iiwa_link_0\"><inertial><origin xyz=\"-0.1 0 0.07\"/><mass value=\"5\"/>\n"
    "    <inertia ixx=\"0.05\" iyy=\"0.06\" izz=\"0.03\"/></inertial></link>\n";

/* joint i (from 1) from link i-1 to link i, and link i's inertial: the rest of the document */
typedef struct iiwa_joint {
    const char *rpy, *xyz, *effort, *limit, *velocity;
    const char *com, *mass, *ixx, *iyy, *izz;
} iiwa_joint;

static const iiwa_joint iiwa14[7] = {
    {"0 0 0", "0 0 0.1575", "320", "2.96705972839", "1.4835298641951802", "0 -0.03 0.12", "5.76",
     "0.033", "0.0333", "0.0123"},
    {"1.570796326794897 0 3.141592653589793", "0 0 0.2025", "320", "2.09439510239",
     "1.4835298641951802", "0.0003 0.059 0.042", "6.35", "0.0305", "0.0304", "0.011"},
    {"1.570796326794897 0 3.141592653589793", "0 0.2045 0", "176", "2.96705972839",
     "1.7453292519943295", "0 0.03 0.13", "3.5", "0.025", "0.0238", "0.0076"},
    {"1.570796326794897 0 0", "0 0 0.2155", "176", "2.09439510239", "1.3089969389957472",
     "0 0.067 0.034", "3.5", "0.017", "0.0164", "0.006"},
    {"-1.570796326794897 3.141592653589793 0", "0 0.1845 0", "110", "2.96705972839",
     "2.2689280275926285", "0.0001 0.021 0.076", "3.5", "0.01", "0.0087", "0.00449"},
    {"1.570796326794897 0 0", "0 0 0.2155", "40", "2.09439510239", "2.356194490192345",
     "0 0.0006 0.0004", "1.8", "0.0049", "0.0047", "0.0036"},
    {"-1.570796326794897 3.141592653589793 0", "0 0.081 0", "40", "3.05432619099",
     "2.356194490192345", "0 0 0.02", "1.2", "0.001", "0.001", "0.001"},
};

/* Appends printf's text of fmt at buf + *n, buf being len bytes in all, and advances *n: 0, or -1
 * when it does not fit (buf then holds a truncated, terminated text). */
static int append(char *buf, size_t len, size_t *n, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static int append(char *buf, size_t len, size_t *n, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(buf + *n, len - *n, fmt, ap);
    va_end(ap);
    if (k < 0 || (size_t)k >= len - *n) return -1;
    *n += (size_t)k;
    return 0;
}

/* the URDF text into buf (len bytes); -1 when it does not fit */
static int iiwa14_text(char *buf, size_t len)
{
    size_t n = 0;
    if (append(buf, len, &n, "%s", iiwa14_urdf) != 0) return -1;
    for (int i = 0; i < 7; i++) {
        const iiwa_joint *j = &iiwa14[i];
        if (append(buf, len, &n,
                   "  <joint name=\"iiwa_joint_%d\" type=\"revolute\">\n"
                   "    <parent link=\"iiwa_link_%d\"/><child link=\"iiwa_link_%d\"/>\n"
                   "    <origin rpy=\"%s\" xyz=\"%s\"/><axis xyz=\"0 0 1\"/>\n"
                   "    <limit effort=\"%s\" lower=\"-%s\" upper=\"%s\" velocity=\"%s\"/>\n"
                   "    <dynamics damping=\"0.5\"/>\n"
                   "  </joint>\n"
                   "  <link name=\"iiwa_link_%d\"><inertial><origin xyz=\"%s\"/>"
                   "<mass value=\"%s\"/>\n"
                   "    <inertia ixx=\"%s\" iyy=\"%s\" izz=\"%s\"/></inertial></link>\n",
                   i + 1, i, i + 1, j->rpy, j->xyz, j->effort, j->limit, j->limit, j->velocity,
                   i + 1, j->com, j->mass, j->ixx, j->iyy, j->izz) != 0)
            return -1;
    }
    return append(buf, len, &n,
                  "  <joint name=\"iiwa_joint_ee\" type=\"fixed\">\n"
                  "    <parent link=\"iiwa_link_7\"/><child link=\"iiwa_link_ee\"/>\n"
                  "    <origin rpy=\"0 -1.570796326794897 0\" xyz=\"0 0 0.045\"/>\n"
                  "  </joint>\n"
                  "  <link name=\"iiwa_link_ee\"/>\n"
                  "</robot>\n");
}

cJSON *presets_iiwa14(const cJSON *request, job_error *err)
{
    (void)request;
    static const double from[7] = {0, 0, 0, 0, 0, 0, 0};
    static const double to[7] = {0.5, 0.6, 0, -1.2, 0, 0.8, 0};
    char text[8192];
    return robot_from_urdf("KUKA LBR iiwa 14 minimum-jerk move, PD (URDF of Drake's "
                           "iiwa14_no_collision.urdf)",
                           iiwa14_text(text, sizeof text) == 0 ? text : NULL, 7, from, to,
                           "iiwa14_min_jerk", err);
}

/* ---- Franka Emika Panda with its fingers ---- */

/* joint i (from 1) from panda_link(i-1) to panda_link(i): franka_arm.xacro's origin and limits;
 * link i's inertial: inertial.yaml's (Gaz et al. 2019) */
typedef struct panda_joint {
    const char *xyz, *rpy, *lower, *upper, *effort, *velocity;
    const char *com, *mass, *ixx, *iyy, *izz, *ixy, *ixz, *iyz;
} panda_joint;

#define PANDA_RPY_PLUS "1.5707963267948966 0 0"
#define PANDA_RPY_MINUS "-1.5707963267948966 0 0"

static const panda_joint panda[7] = {
    {"0 0 0.333", "0 0 0", "-2.8973", "2.8973", "87", "2.1750", "0.003875 0.002081 -0.04762",
     "4.970684", "0.70337", "0.70661", "0.0091170", "-0.00013900", "0.0067720", "0.019169"},
    {"0 0 0", PANDA_RPY_MINUS, "-1.7628", "1.7628", "87", "2.1750", "-0.003141 -0.02872 0.003495",
     "0.646926", "0.0079620", "2.8110e-02", "2.5995e-02", "-3.9250e-3", "1.0254e-02", "7.0400e-04"},
    {"0 -0.316 0", PANDA_RPY_PLUS, "-2.8973", "2.8973", "87", "2.1750",
     "2.7518e-02 3.9252e-02 -6.6502e-02", "3.228604", "3.7242e-02", "3.6155e-02", "1.0830e-02",
     "-4.7610e-03", "-1.1396e-02", "-1.2805e-02"},
    {"0.0825 0 0", PANDA_RPY_PLUS, "-3.0718", "-0.0698", "87", "2.1750",
     "-5.317e-02 1.04419e-01 2.7454e-02", "3.587895", "2.5853e-02", "1.9552e-02", "2.8323e-02",
     "7.7960e-03", "-1.3320e-03", "8.6410e-03"},
    {"-0.0825 0.384 0", PANDA_RPY_MINUS, "-2.8973", "2.8973", "12", "2.6100",
     "-1.1953e-02 4.1065e-02 -3.8437e-02", "1.225946", "3.5549e-02", "2.9474e-02", "8.6270e-03",
     "-2.1170e-03", "-4.0370e-03", "2.2900e-04"},
    {"0 0 0", PANDA_RPY_PLUS, "-0.0175", "3.7525", "12", "2.6100",
     "6.0149e-02 -1.4117e-02 -1.0517e-02", "1.666555", "1.9640e-03", "4.3540e-03", "5.4330e-03",
     "1.0900e-04", "-1.1580e-03", "3.4100e-04"},
    {"0.088 0 0", PANDA_RPY_PLUS, "-2.8973", "2.8973", "12", "2.6100",
     "1.0517e-02 -4.252e-03 6.1597e-02", "7.35522e-01", "1.2516e-02", "1.0027e-02", "4.8150e-03",
     "-4.2800e-04", "-1.1960e-03", "-7.4100e-04"},
};

/* the arm's base (link 0 and its inertial), before the joints */
static const char panda_urdf_head[] =
    "<?xml version=\"1.0\"?>\n"
    "<robot name=\"panda\">\n"
    "  <link name=\"panda_link0\"><inertial><origin xyz=\"-0.041018 -0.00014 0.049974\"/>"
    "<mass value=\"0.629769\"/>\n"
    "    <inertia ixx=\"0.00315\" iyy=\"0.00388\" izz=\"0.004285\" ixy=\"8.2904E-07\" "
    "ixz=\"0.00015\" iyz=\"8.2299E-06\"/></inertial></link>\n";

/* the flange (link 8), the hand on it and the two fingers on the hand, after the joints */
static const char panda_urdf_tail[] =
    "  <joint name=\"panda_joint8\" type=\"fixed\">\n"
    "    <parent link=\"panda_link7\"/><child link=\"panda_link8\"/>"
    "<origin xyz=\"0 0 0.107\" rpy=\"0 0 0\"/>\n"
    "  </joint>\n"
    "  <link name=\"panda_link8\"/>\n"
    "  <joint name=\"panda_hand_joint\" type=\"fixed\">\n"
    "    <parent link=\"panda_link8\"/><child link=\"panda_hand\"/>"
    "<origin xyz=\"0 0 0\" rpy=\"0 0 -0.7853981633974483\"/>\n"
    "  </joint>\n"
    "  <link name=\"panda_hand\"><inertial><origin xyz=\"-0.01 0 0.03\"/>"
    "<mass value=\"0.73\"/>\n"
    "    <inertia ixx=\"0.001\" iyy=\"0.0025\" izz=\"0.0017\"/></inertial></link>\n"
    "  <joint name=\"panda_finger_joint1\" type=\"prismatic\">\n"
    "    <parent link=\"panda_hand\"/><child link=\"panda_leftfinger\"/>"
    "<origin xyz=\"0 0 0.0584\" rpy=\"0 0 0\"/><axis xyz=\"0 1 0\"/>\n"
    "    <limit effort=\"100\" lower=\"0.0\" upper=\"0.04\" velocity=\"0.2\"/>"
    "<dynamics damping=\"0.3\"/>\n"
    "  </joint>\n"
    "  <link name=\"panda_leftfinger\"><inertial><origin xyz=\"0 0 0\"/>"
    "<mass value=\"0.015\"/>\n"
    "    <inertia ixx=\"2.375e-06\" iyy=\"2.375e-06\" izz=\"7.5e-07\"/></inertial></link>\n"
    "  <joint name=\"panda_finger_joint2\" type=\"prismatic\">\n"
    "    <parent link=\"panda_hand\"/><child link=\"panda_rightfinger\"/>"
    "<origin xyz=\"0 0 0.0584\" rpy=\"0 0 0\"/><axis xyz=\"0 -1 0\"/>\n"
    "    <limit effort=\"100\" lower=\"0.0\" upper=\"0.04\" velocity=\"0.2\"/>"
    "<dynamics damping=\"0.3\"/>\n"
    "  </joint>\n"
    "  <link name=\"panda_rightfinger\"><inertial><origin xyz=\"0 0 0\"/>"
    "<mass value=\"0.015\"/>\n"
    "    <inertia ixx=\"2.375e-06\" iyy=\"2.375e-06\" izz=\"7.5e-07\"/></inertial></link>\n"
    "</robot>\n";

/* the URDF text into buf (len bytes); -1 when it does not fit */
static int panda_text(char *buf, size_t len)
{
    size_t n = 0;
    if (append(buf, len, &n, "%s", panda_urdf_head) != 0) return -1;
    for (int i = 0; i < 7; i++) {
        const panda_joint *j = &panda[i];
        if (append(buf, len, &n,
                   "  <joint name=\"panda_joint%d\" type=\"revolute\">\n"
                   "    <parent link=\"panda_link%d\"/><child link=\"panda_link%d\"/>\n"
                   "    <origin xyz=\"%s\" rpy=\"%s\"/><axis xyz=\"0 0 1\"/>\n"
                   "    <limit effort=\"%s\" lower=\"%s\" upper=\"%s\" velocity=\"%s\"/>\n"
                   "  </joint>\n"
                   "  <link name=\"panda_link%d\"><inertial><origin xyz=\"%s\"/>"
                   "<mass value=\"%s\"/>\n"
                   "    <inertia ixx=\"%s\" iyy=\"%s\" izz=\"%s\" ixy=\"%s\" ixz=\"%s\" "
                   "iyz=\"%s\"/></inertial></link>\n",
                   i + 1, i, i + 1, j->xyz, j->rpy, j->effort, j->lower, j->upper, j->velocity,
                   i + 1, j->com, j->mass, j->ixx, j->iyy, j->izz, j->ixy, j->ixz, j->iyz) != 0)
            return -1;
    }
    return append(buf, len, &n, "%s", panda_urdf_tail);
}

cJSON *presets_panda(const cJSON *request, job_error *err)
{
    (void)request;
    static const double from[9] = {
        0,   -0.78539816339744831, 0, -2.3561944901923448, 0, HALF_PI, 0.78539816339744831, 0.01,
        0.01};
    static const double to[9] = {0.6, -0.2, -0.4, -2.0, 0.3, 2.0, 1.2, 0.04, 0.04};
    char text[12288];
    return robot_from_urdf("Franka Emika Panda minimum-jerk move opening its fingers, PD (URDF of "
                           "franka_description; link inertials of Gaz et al. 2019)",
                           panda_text(text, sizeof text) == 0 ? text : NULL, 9, from, to,
                           "panda_min_jerk", err);
}
