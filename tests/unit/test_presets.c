/*
 * test_presets.c - the paper's scenes as job documents (server/presets.c): every preset builds a
 * document that the job format (server/job_json.c) accepts, the documents hold the values of
 * Kingsley et al. 2017 sections 7.1, 7.2 and 7.3, the closed chains close at their q0 and build
 * loop models of the expected mobility, and the n-link pendulum's parameter is checked with exact
 * messages.
 *
 * Oracles, each written apart from the code under test:
 *  - the paper's numbers, typed in here (q0, trajectories, gains, disturbance, duration), read
 *    back from the document and from the parsed job;
 *  - the designed gains of the pole-placement and LQR presets against the values the paper
 *    prints (K = (9.24, 13.22, 6.3) and (10, 18.2674, 11.6848), DESIGN.md section 6);
 *  - the scene geometry: the parsed chain built with ctc_model_build and posed with
 *    ctc_kinematics, against hand-worked positions (rods hanging along -y; the tip of a planar
 *    chain at sum_k (sin theta_k, -cos theta_k) with theta_k the absolute angle of rod k; the
 *    spatial pendulum's second cuboid pointing down after a quarter turn about body 1's y);
 *  - the closure of the loop presets: the tip's closing point at q0, by forward kinematics
 *    worked here (planar) and by ctc_kinematics, against the anchor in the document, and the
 *    rotation of the RSSR's rocker about the closing axis; the mobility by Gruebler-Kutzbach
 *    counted here against the model's;
 *  - the trees: each body's parent written out here, against the job's and the model's; masses
 *    from density x volume (the hand's aluminium) or Winter's anthropometric fractions (the
 *    torso's arms), a box's or rod's inertia by its textbook formula; joints and tips posed by
 *    ctc_kinematics against positions worked by hand (the Y's rods at the sum of their
 *    ancestors' angles, a quarter turn of the wrist or the waist);
 *  - the Panda: Franka's ready pose and joint limits (franka_description's franka_arm and
 *    franka_hand xacro files) typed in here, against the document's moves and the limits its
 *    URDF carries; its exact tracking and published dynamics are checked in test_urdf.c;
 *  - the two-link arm: Lynch and Park's point masses at the link ends (Modern Robotics 8.1.1)
 *    posed by hand at the start and end of its move; the Puma 560: Armstrong, Khatib and
 *    Burdick's table as Corke's mdl_puma560akb lists it, typed in here and read back, and two
 *    centres of mass at Corke's qz worked by hand through the modified DH frames.
 * Positions are compared to 1e-12 m, numbers read back to 1e-15 relative.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "data.h"
#include "job_json.h"
#include "kinematics.h"
#include "model.h"
#include "presets.h"
#include "urdf.h"

#define POS_TOL 1e-12  /* m */
#define READ_TOL 1e-15 /* relative */

static const double pi = 3.14159265358979323846;

static const char *const all_names[] = {
    "triple_pendulum_pd",
    "triple_pendulum_pid",
    "triple_pendulum_poles",
    "triple_pendulum_lqr",
    "triple_pendulum_passive",
    "spatial_double_pendulum_pd",
    "spatial_double_pendulum_pid",
    "spatial_double_pendulum_poles",
    "spatial_double_pendulum_lqr",
    "n_link_pendulum",
    "five_bar_pd",
    "five_bar_pid",
    "five_bar_poles",
    "five_bar_lqr",
    "four_bar_passive",
    "arm_four_bar_pd",
    "rssr_passive",
    "y_pendulum_pd",
    "y_four_bar_pd",
    "spatial_hand_pd",
    "two_arm_torso_pd",
    "ur5_min_jerk",
    "iiwa14_min_jerk",
    "triple_pendulum_pid_1khz",
    "triple_pendulum_pid_200hz",
    "triple_pendulum_pid_50hz",
    "triple_pendulum_pid_limited",
    "panda_min_jerk",
    "two_link_min_jerk",
    "two_link_lab_payload",
    "puma560_min_jerk",
};
#define NPRESETS ((int)(sizeof all_names / sizeof all_names[0]))

/* what each preset of all_names holds, in the same order */
static const struct preset_want {
    int paper;           /* cites Kingsley et al. 2017 in its name */
    int nbodies, nq, nv; /* the chain */
    int loop, nind;      /* closed by a loop; the controlled coordinates */
    ctc_ctrl_type ctrl;  /* the controller */
    int disturbed;       /* 0.2 N m on every coordinate */
    double duration, rtol, atol;
} preset_want[] = {
    {1, 3, 3, 3, 0, 3, CTC_CTRL_PD, 1, 5, 1e-8, 1e-10},
    {1, 3, 3, 3, 0, 3, CTC_CTRL_PID, 1, 5, 1e-8, 1e-10},
    {1, 3, 3, 3, 0, 3, CTC_CTRL_POLES, 1, 5, 1e-8, 1e-10},
    {1, 3, 3, 3, 0, 3, CTC_CTRL_LQR, 1, 5, 1e-8, 1e-10},
    {1, 3, 3, 3, 0, 3, CTC_CTRL_NONE, 0, 5, 1e-8, 1e-10},
    {1, 2, 2, 2, 0, 2, CTC_CTRL_PD, 1, 5, 1e-8, 1e-10},
    {1, 2, 2, 2, 0, 2, CTC_CTRL_PID, 1, 5, 1e-8, 1e-10},
    {1, 2, 2, 2, 0, 2, CTC_CTRL_POLES, 1, 5, 1e-8, 1e-10},
    {1, 2, 2, 2, 0, 2, CTC_CTRL_LQR, 1, 5, 1e-8, 1e-10},
    {1, 8, 8, 8, 0, 8, CTC_CTRL_PD, 0, 5, 1e-8, 1e-10},
    {1, 5, 5, 5, 1, 3, CTC_CTRL_PD, 0, 10, 1e-8, 1e-10},
    {1, 5, 5, 5, 1, 3, CTC_CTRL_PID, 0, 10, 1e-8, 1e-10},
    {1, 5, 5, 5, 1, 3, CTC_CTRL_POLES, 0, 10, 1e-8, 1e-10},
    {1, 5, 5, 5, 1, 3, CTC_CTRL_LQR, 0, 10, 1e-8, 1e-10},
    {0, 3, 3, 3, 1, 0, CTC_CTRL_NONE, 0, 10, 1e-10, 1e-12},
    {0, 4, 4, 4, 1, 2, CTC_CTRL_PD, 0, 10, 1e-8, 1e-10},
    {0, 3, 9, 7, 1, 0, CTC_CTRL_NONE, 0, 5, 1e-10, 1e-12},
    {0, 5, 5, 5, 0, 5, CTC_CTRL_PD, 1, 5, 1e-8, 1e-10},
    {0, 6, 6, 6, 1, 4, CTC_CTRL_PD, 0, 10, 1e-8, 1e-10},
    {0, 10, 10, 10, 0, 10, CTC_CTRL_PD, 0, 5, 1e-8, 1e-10},
    {0, 7, 7, 7, 0, 7, CTC_CTRL_PD, 0, 5, 1e-8, 1e-10},
    {0, 6, 6, 6, 0, 6, CTC_CTRL_PD, 0, 3, 1e-8, 1e-10},
    {0, 7, 7, 7, 0, 7, CTC_CTRL_PD, 0, 3, 1e-8, 1e-10},
    {1, 3, 3, 3, 0, 3, CTC_CTRL_PID, 1, 5, 1e-8, 1e-10},
    {1, 3, 3, 3, 0, 3, CTC_CTRL_PID, 1, 5, 1e-8, 1e-10},
    {1, 3, 3, 3, 0, 3, CTC_CTRL_PID, 1, 5, 1e-8, 1e-10},
    {1, 3, 3, 3, 0, 3, CTC_CTRL_PID, 1, 5, 1e-8, 1e-10},
    {0, 9, 9, 9, 0, 9, CTC_CTRL_PD, 0, 3, 1e-8, 1e-10},
    {0, 2, 2, 2, 0, 2, CTC_CTRL_PD, 0, 3, 1e-8, 1e-10},
    {0, 2, 2, 2, 0, 2, CTC_CTRL_PD, 0, 3, 1e-8, 1e-10},
    {0, 6, 6, 6, 0, 6, CTC_CTRL_PD, 0, 3, 1e-8, 1e-10},
};
_Static_assert(sizeof preset_want / sizeof preset_want[0] == NPRESETS, "one row per preset");

/* ---- helpers ---- */

/* the preset's document for request (NULL = defaults); fails the test if it does not build */
static cJSON *build(const char *name, const cJSON *request)
{
    const preset *p = presets_find(name);
    cr_assert_not_null(p, "no preset %s", name);
    job_error err = {0};
    cJSON *doc = p->build(request, &err);
    cr_assert_not_null(doc, "%s: %s: %s", name, err.field, err.message);
    return doc;
}

/* request parsed from JSON text */
static cJSON *request_from(const char *text)
{
    cJSON *r = cJSON_Parse(text);
    cr_assert_not_null(r, "bad test JSON: %s", text);
    return r;
}

/* the parsed job of a document; fails the test on an error */
static job *parse_doc(const cJSON *doc, const char *what)
{
    job *j = NULL;
    job_error err = {0};
    int rc = job_from_json(doc, &j, &err);
    cr_assert_eq(rc, 0, "%s: job_from_json: %s at \"%s\": %s", what, job_error_code_name(err.code),
                 err.field, err.message);
    cr_assert_not_null(j);
    return j;
}

/* the member at a dotted path of objects, e.g. "controller.kp"; fails the test if absent */
static const cJSON *at(const cJSON *doc, const char *path)
{
    char buf[128];
    snprintf(buf, sizeof buf, "%s", path);
    const cJSON *node = doc;
    for (char *save = NULL, *key = strtok_r(buf, ".", &save); key != NULL;
         key = strtok_r(NULL, ".", &save)) {
        node = cJSON_GetObjectItemCaseSensitive(node, key);
        cr_assert_not_null(node, "document has no %s", path);
    }
    return node;
}

static double number_at(const cJSON *doc, const char *path)
{
    const cJSON *v = at(doc, path);
    cr_assert(cJSON_IsNumber(v), "%s is not a number", path);
    return v->valuedouble;
}

static const char *string_at(const cJSON *doc, const char *path)
{
    const cJSON *v = at(doc, path);
    cr_assert(cJSON_IsString(v), "%s is not a string", path);
    return v->valuestring;
}

/* element i of a numeric array */
static double element(const cJSON *array, int i, const char *what)
{
    const cJSON *v = cJSON_GetArrayItem(array, i);
    cr_assert(cJSON_IsNumber(v), "%s[%d] is not a number", what, i);
    return v->valuedouble;
}

static void expect_close(double got, double want, double tol, const char *what)
{
    cr_assert_leq(fabs(got - want), tol, "%s = %.17g, want %.17g (tolerance %g)", what, got, want,
                  tol);
}

/* world coordinates of a vector given in the model's frame (planar form: plane coordinates) */
static void to_world(const ctc_model *m, const double in[3], double out[3])
{
    if (m->form != CTC_FORM_PLANAR) {
        for (int i = 0; i < 3; i++) out[i] = in[i];
        return;
    }
    for (int i = 0; i < 3; i++) {
        out[i] = in[0] * m->plane_e1[i] + in[1] * m->plane_e2[i] + in[2] * m->plane_n[i];
    }
}

/* the model's frame coordinates of a world vector (inverse of to_world) */
static void from_world(const ctc_model *m, const double in[3], double out[3])
{
    if (m->form != CTC_FORM_PLANAR) {
        for (int i = 0; i < 3; i++) out[i] = in[i];
        return;
    }
    const double *basis[3] = {m->plane_e1, m->plane_e2, m->plane_n};
    for (int r = 0; r < 3; r++) {
        out[r] = basis[r][0] * in[0] + basis[r][1] * in[1] + basis[r][2] * in[2];
    }
}

/* world position of the point p (body frame, world axes at q = 0) of body k after kinematics */
static void body_point(const ctc_model *m, const ctc_data *d, int k, const double p[3],
                       double out[3])
{
    double pm[3], rp[3], sum[3];
    const double *xr = d->xrot + 9 * k, *xp = d->xpos + 3 * k;
    from_world(m, p, pm);
    for (int i = 0; i < 3; i++) {
        rp[i] = xr[3 * i] * pm[0] + xr[3 * i + 1] * pm[1] + xr[3 * i + 2] * pm[2];
        sum[i] = xp[i] + rp[i];
    }
    to_world(m, sum, out);
}

static void expect_point(const double got[3], double x, double y, double z, const char *what)
{
    const double want[3] = {x, y, z};
    for (int i = 0; i < 3; i++) {
        cr_assert_leq(fabs(got[i] - want[i]), POS_TOL,
                      "%s = (%.17g, %.17g, %.17g), want (%g, %g, %g)", what, got[0], got[1], got[2],
                      x, y, z);
    }
}

/* the model of a parsed job, posed at q (nq) at rest */
typedef struct posed {
    ctc_model *m;
    ctc_data *d;
} posed;

static posed pose(const job *j, const double *q)
{
    posed p;
    char err[256] = "";
    cr_assert_eq(ctc_model_build(&j->spec.chain, &p.m, err, sizeof err), CTC_OK,
                 "ctc_model_build: %s", err);
    p.d = ctc_data_new(p.m);
    cr_assert_not_null(p.d);
    double v[8] = {0};
    cr_assert_leq(p.m->nv, 8);
    ctc_kinematics(p.m, p.d, q, v);
    return p;
}

static void pose_free(posed *p)
{
    ctc_data_free(p->d);
    ctc_model_free(p->m);
}

/* ---- the table ---- */

Test(presets, lists_every_paper_scene_once_in_order)
{
    int n = -1;
    const preset *list = presets_list(&n);
    cr_assert_eq(n, NPRESETS);
    for (int i = 0; i < n; i++) {
        cr_assert_str_eq(list[i].name, all_names[i]);
        cr_assert_eq(presets_find(all_names[i]), &list[i], "presets_find(%s)", all_names[i]);
        cr_assert_not_null(list[i].summary);
        cr_assert_gt(strlen(list[i].summary), 20, "%s: summary too short", list[i].name);
        cr_assert_null(strchr(list[i].summary, '\n'), "%s: summary is not one line", list[i].name);
        cr_assert_not_null(list[i].params, "%s: params must be a NULL-terminated list",
                           list[i].name);
        cr_assert_not_null(list[i].build);
    }
    cr_assert_null(presets_find("no_such_preset"));
    cr_assert_null(presets_find("triple_pendulum"));
    cr_assert_null(presets_find(""));
    cr_assert_null(presets_find(NULL));

    /* only the n-link pendulum takes a parameter */
    const preset *nl = presets_find("n_link_pendulum");
    cr_assert_str_eq(nl->params[0], "n");
    cr_assert_null(nl->params[1]);
    cr_assert_null(presets_find("triple_pendulum_pid")->params[0]);
}

/* ---- building and parsing ---- */

Test(presets, every_preset_builds_a_complete_job_document)
{
    for (int i = 0; i < NPRESETS; i++) {
        const struct preset_want *w = &preset_want[i];
        cJSON *doc = build(all_names[i], NULL);
        const char *name = string_at(doc, "name");
        cr_assert_leq(strlen(name), JOB_MAX_NAME, "%s: name too long", all_names[i]);
        cr_assert_eq(strstr(name, "Kingsley et al. 2017") != NULL, w->paper,
                     "%s: name \"%s\" (cites the paper: %d)", all_names[i], name, w->paper);
        /* the bodies, or a robot's DH table or URDF that the job format converts into bodies */
        const cJSON *scene = at(doc, "scene");
        cr_assert(cJSON_IsArray(cJSON_GetObjectItemCaseSensitive(scene, "bodies")) ||
                      cJSON_IsObject(cJSON_GetObjectItemCaseSensitive(scene, "dh")) ||
                      cJSON_IsString(cJSON_GetObjectItemCaseSensitive(scene, "urdf")),
                  "%s: no bodies, dh or urdf", all_names[i]);
        cr_assert(cJSON_IsArray(at(doc, "scene.gravity")));
        cr_assert(cJSON_IsArray(at(doc, "scene.q0")));
        cr_assert(cJSON_IsArray(at(doc, "scene.v0")));
        cr_assert(cJSON_IsString(at(doc, "controller.type")));
        cr_assert_eq(cJSON_GetObjectItemCaseSensitive(at(doc, "scene"), "loop") != NULL, w->loop,
                     "%s: loop", all_names[i]);
        cr_assert_eq(number_at(doc, "duration"), w->duration, "%s: duration", all_names[i]);
        /* the limited triple pendulum's clipping is stiff for dopri5 (presets.c) */
        const int bdf = strcmp(all_names[i], "triple_pendulum_pid_limited") == 0;
        cr_assert_str_eq(string_at(doc, "integrator.method"), bdf ? "bdf" : "dopri5");
        cr_assert_eq(number_at(doc, "integrator.rtol"), w->rtol, "%s: rtol", all_names[i]);
        cr_assert_eq(number_at(doc, "integrator.atol"), w->atol, "%s: atol", all_names[i]);
        cr_assert_eq(number_at(doc, "output.interval"), 0.01);

        /* keys that are not the preset's parameters do not change the document */
        cJSON *req = request_from("{\"preset\": \"x\", \"duration\": 3, \"scene\": null}");
        cJSON *again = build(all_names[i], req);
        cr_assert(cJSON_Compare(doc, again, 1), "%s: the request's other keys changed it",
                  all_names[i]);
        cJSON_Delete(again);
        cJSON_Delete(req);
        cJSON_Delete(doc);
    }
}

Test(presets, every_preset_parses_as_a_job)
{
    const struct preset_want *want = preset_want;
    for (int i = 0; i < NPRESETS; i++) {
        cJSON *doc = build(all_names[i], NULL);

        /* from the tree and from its text */
        job *j = parse_doc(doc, all_names[i]);
        char *text = cJSON_PrintUnformatted(doc);
        cr_assert_not_null(text);
        job *jt = NULL;
        job_error err = {0};
        cr_assert_eq(job_parse(text, strlen(text), &jt, &err), 0, "%s: job_parse: %s: %s",
                     all_names[i], err.field, err.message);

        for (int pass = 0; pass < 2; pass++) {
            const job *p = pass ? jt : j;
            int nb = want[i].nbodies;
            cr_assert_str_eq(p->name, string_at(doc, "name"));
            cr_assert_eq(p->spec.chain.nbodies, nb, "%s: %d bodies", all_names[i],
                         p->spec.chain.nbodies);
            cr_assert_eq(p->nq, want[i].nq, "%s: nq", all_names[i]);
            cr_assert_eq(p->nv, want[i].nv, "%s: nv", all_names[i]);
            cr_assert_eq(p->nind, want[i].nind, "%s: nind", all_names[i]);
            cr_assert_eq(p->spec.chain.loop != NULL, want[i].loop, "%s: loop", all_names[i]);
            cr_assert_eq(p->spec.controller, want[i].ctrl, "%s: controller", all_names[i]);
            cr_assert_eq(p->gains == NULL, want[i].ctrl == CTC_CTRL_NONE, "%s: gains",
                         all_names[i]);
            cr_assert_eq(p->traj == NULL, want[i].ctrl == CTC_CTRL_NONE, "%s: trajectory",
                         all_names[i]);
            if (want[i].disturbed) {
                cr_assert_not_null(p->disturb, "%s: no disturbance", all_names[i]);
                for (int k = 0; k < nb; k++) {
                    cr_assert_eq(p->disturb[k].type, CTC_DISTURB_CONSTANT);
                    cr_assert_eq(p->disturb[k].value, 0.2, "%s: disturbance %d", all_names[i], k);
                }
            } else if (p->disturb != NULL) {
                for (int k = 0; k < p->nind; k++) {
                    cr_assert_eq(ctc_disturb_eval(&p->disturb[k], 1.0), 0.0, "%s: disturbance %d",
                                 all_names[i], k);
                }
            }
            cr_assert_eq(p->spec.duration, want[i].duration);
            cr_assert_eq(p->spec.output_interval, 0.01);
            cr_assert_eq(p->spec.integrator.method,
                         strcmp(all_names[i], "triple_pendulum_pid_limited") == 0
                             ? CTC_INTEG_BDF
                             : CTC_INTEG_DOPRI5);
            cr_assert_eq(p->spec.integrator.rtol, want[i].rtol);
            cr_assert_eq(p->spec.integrator.atol, want[i].atol);
            cr_assert_not_null(p->normalised);
        }

        /* the expanded document is itself a job that parses to the same sizes */
        job *jn = parse_doc(j->normalised, all_names[i]);
        cr_assert_eq(jn->spec.chain.nbodies, j->spec.chain.nbodies);
        cr_assert_eq(jn->spec.controller, j->spec.controller);

        job_free(jn);
        job_free(jt);
        job_free(j);
        free(text);
        cJSON_Delete(doc);
    }
}

/* ---- the paper's values ---- */

Test(presets, triple_pendulum_holds_the_papers_values)
{
    const double q0[3] = {5 * pi / 6, 3 * pi / 4, 2 * pi / 3};
    static const char *const shape[3] = {"sine", "cosine", "sine"};
    cJSON *doc = build("triple_pendulum_pid", NULL);
    cr_assert_str_eq(string_at(doc, "name"),
                     "Triple pendulum, PID (Kingsley et al. 2017, sec. 7.1)");

    /* the document: three unit rods, gravity -y, q0, v0, Eq. 81-82, PID, 0.2 N m, 5 s */
    const cJSON *g = at(doc, "scene.gravity"), *bodies = at(doc, "scene.bodies");
    const cJSON *dq0 = at(doc, "scene.q0"), *dv0 = at(doc, "scene.v0"),
                *traj = at(doc, "trajectory");
    expect_close(element(g, 0, "gravity"), 0, 0, "gravity x");
    expect_close(element(g, 1, "gravity"), -9.81, 0, "gravity y");
    expect_close(element(g, 2, "gravity"), 0, 0, "gravity z");
    cr_assert_eq(cJSON_GetArraySize(bodies), 3);
    cr_assert_eq(cJSON_GetArraySize(dq0), 3);
    cr_assert_eq(cJSON_GetArraySize(dv0), 3);
    cr_assert_eq(cJSON_GetArraySize(traj), 3);
    for (int k = 0; k < 3; k++) {
        const cJSON *b = cJSON_GetArrayItem(bodies, k);
        const double loc_y = k == 0 ? 0 : -1;
        cr_assert_eq(number_at(b, "mass"), 1.0);
        cr_assert_str_eq(string_at(b, "shape.type"), "rod");
        const cJSON *end = at(b, "shape.end"), *axis = at(b, "joint.axis"),
                    *loc = at(b, "joint.location");
        cr_assert_str_eq(string_at(b, "joint.type"), "revolute");
        for (int i = 0; i < 3; i++) {
            cr_assert_eq(element(end, i, "end"), i == 1 ? -1.0 : 0.0, "rod %d end[%d]", k, i);
            cr_assert_eq(element(axis, i, "axis"), i == 2 ? 1.0 : 0.0, "joint %d axis[%d]", k, i);
            cr_assert_eq(element(loc, i, "location"), i == 1 ? loc_y : 0.0, "joint %d location[%d]",
                         k, i);
        }
        expect_close(element(dq0, k, "q0"), q0[k], READ_TOL * q0[k], "q0");
        cr_assert_eq(element(dv0, k, "v0"), 0.0);
        const cJSON *tr = cJSON_GetArrayItem(traj, k);
        cr_assert_str_eq(string_at(tr, "type"), shape[k], "trajectory %d", k);
        cr_assert_eq(number_at(tr, "amplitude"), 0.6);
        cr_assert_eq(number_at(tr, "period"), 1.5);
    }
    cr_assert_str_eq(string_at(doc, "controller.type"), "pid");
    cr_assert_eq(number_at(doc, "controller.kp"), 100.0);
    cr_assert_eq(number_at(doc, "controller.kv"), 20.0);
    cr_assert_eq(number_at(doc, "controller.ki"), 250.0);
    cr_assert_str_eq(string_at(doc, "disturbance.type"), "constant");
    cr_assert_eq(number_at(doc, "disturbance.value"), 0.2);

    /* the parsed job: the same numbers where the simulation reads them */
    job *j = parse_doc(doc, "triple_pendulum_pid");
    const ctc_traj_type tt[3] = {CTC_TRAJ_SINE, CTC_TRAJ_COSINE, CTC_TRAJ_SINE};
    for (int k = 0; k < 3; k++) {
        expect_close(j->q0[k], q0[k], READ_TOL * q0[k], "job q0");
        cr_assert_eq(j->v0[k], 0.0);
        cr_assert_eq(j->traj[k].type, tt[k], "job trajectory %d type", k);
        cr_assert_eq(j->traj[k].amplitude, 0.6);
        cr_assert_eq(j->traj[k].period, 1.5);
        cr_assert_eq(j->traj[k].phase, 0.0);
        cr_assert_eq(j->traj[k].offset, 0.0);
        cr_assert_eq(j->gains[k].kp, 100.0);
        cr_assert_eq(j->gains[k].kv, 20.0);
        cr_assert_eq(j->gains[k].ki, 250.0);
        cr_assert_eq(j->bodies[k].mass, 1.0);
    }
    /* q_d(0) from the trajectory: (0, 0.6, 0), Eq. 81-82 at t = 0, and q_d1(0.375 s) = 0.6 */
    double out[3];
    ctc_traj_eval(&j->traj[1], 0.0, out);
    expect_close(out[0], 0.6, 1e-15, "q_d2(0)");
    ctc_traj_eval(&j->traj[0], 0.375, out);
    expect_close(out[0], 0.6, 1e-15, "q_d1(T/4)");
    job_free(j);
    cJSON_Delete(doc);
}

Test(presets, passive_triple_pendulum_has_no_control)
{
    cJSON *doc = build("triple_pendulum_passive", NULL);
    const cJSON *ctrl = at(doc, "controller");
    cr_assert_str_eq(string_at(doc, "controller.type"), "none");
    cr_assert_eq(cJSON_GetArraySize(ctrl), 1, "a passive controller has only \"type\"");
    cr_assert_null(cJSON_GetObjectItemCaseSensitive(doc, "trajectory"));
    cr_assert_null(cJSON_GetObjectItemCaseSensitive(doc, "disturbance"));
    const cJSON *q0 = at(doc, "scene.q0");
    expect_close(element(q0, 0, "q0"), 5 * pi / 6, 1e-15, "q0[0]");
    cJSON_Delete(doc);
}

Test(presets, pole_and_lqr_presets_give_the_papers_gains)
{
    /* poles (-2, -2.1, -2.2): (s + 2)(s + 2.1)(s + 2.2) = s^3 + 6.3 s^2 + 13.22 s + 9.24;
       LQR Q = I, lambda = 0.01: K = (10, 18.2674, 11.6848) as printed (4 decimals) */
    static const struct {
        const char *name;
        double ki, kp, kv, tol;
    } want[] = {
        {"triple_pendulum_poles", 9.24, 13.22, 6.3, 1e-12},
        {"spatial_double_pendulum_poles", 9.24, 13.22, 6.3, 1e-12},
        {"triple_pendulum_lqr", 10, 18.2674, 11.6848, 5e-5},
        {"spatial_double_pendulum_lqr", 10, 18.2674, 11.6848, 5e-5},
        {"five_bar_poles", 9.24, 13.22, 6.3, 1e-12},
        {"five_bar_lqr", 10, 18.2674, 11.6848, 5e-5},
    };
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        cJSON *doc = build(want[i].name, NULL);
        job *j = parse_doc(doc, want[i].name);
        for (int k = 0; k < j->nind; k++) {
            expect_close(j->gains[k].ki, want[i].ki, want[i].tol, "ki");
            expect_close(j->gains[k].kp, want[i].kp, want[i].tol, "kp");
            expect_close(j->gains[k].kv, want[i].kv, want[i].tol, "kv");
        }
        job_free(j);
        cJSON_Delete(doc);
    }
}

Test(presets, spatial_double_pendulum_holds_the_papers_values)
{
    cJSON *doc = build("spatial_double_pendulum_lqr", NULL);
    job *j = parse_doc(doc, "spatial_double_pendulum_lqr");
    cr_assert_eq(j->spec.chain.gravity[2], -9.81, "gravity -z (the paper gives none)");
    cr_assert_eq(j->spec.chain.gravity[0], 0.0);
    cr_assert_eq(j->spec.chain.gravity[1], 0.0);
    expect_close(j->q0[0], pi / 2, 1e-15, "q0[0]");
    cr_assert_eq(j->q0[1], 0.0);
    cr_assert_eq(j->v0[0], 1.0);
    cr_assert_eq(j->v0[1], 1.0);
    cr_assert_eq(j->traj[0].type, CTC_TRAJ_SINE);
    cr_assert_eq(j->traj[1].type, CTC_TRAJ_COSINE);
    for (int k = 0; k < 2; k++) {
        cr_assert_eq(j->traj[k].amplitude, 1.0);
        cr_assert_eq(j->traj[k].period, 1.5);
        /* uniform cuboid 1 x 0.1 x 0.1 m, 1 kg: m/12 diag(b^2 + c^2, a^2 + c^2, a^2 + b^2) */
        const ctc_body_spec *b = &j->bodies[k];
        cr_assert_eq(b->mass, 1.0);
        expect_close(b->com[0], 0.5, 1e-15, "com x");
        expect_close(b->inertia[0], 0.02 / 12, 1e-15, "Ixx");
        expect_close(b->inertia[4], 1.01 / 12, 1e-15, "Iyy");
        expect_close(b->inertia[8], 1.01 / 12, 1e-15, "Izz");
    }
    job_free(j);
    cJSON_Delete(doc);
}

/* ---- the n-link pendulum's parameter ---- */

Test(presets, n_link_pendulum_of_16_has_16_bodies_and_alternating_q0)
{
    cJSON *req = request_from("{\"preset\": \"n_link_pendulum\", \"n\": 16}");
    cJSON *doc = build("n_link_pendulum", req);
    cr_assert_str_eq(string_at(doc, "name"),
                     "16-link pendulum, PD (Kingsley et al. 2017, sec. 7.3)");
    cr_assert_eq(cJSON_GetArraySize(at(doc, "scene.bodies")), 16);
    cr_assert_str_eq(string_at(doc, "controller.type"), "pd");
    cr_assert_eq(number_at(doc, "controller.kp"), 100.0);
    cr_assert_eq(number_at(doc, "controller.kv"), 20.0);
    cr_assert_null(cJSON_GetObjectItemCaseSensitive(doc, "disturbance"));

    /* Eq. 84: q0_k = (-1)^k pi/6 for k = 1..n, at rest, driven to q_d = 0 */
    job *j = parse_doc(doc, "n_link_pendulum n = 16");
    cr_assert_eq(j->spec.chain.nbodies, 16);
    cr_assert_eq(j->nv, 16);
    for (int k = 1; k <= 16; k++) {
        double want = (k % 2 == 0 ? 1 : -1) * pi / 6;
        expect_close(j->q0[k - 1], want, 1e-15, "q0_k");
        cr_assert_eq(j->v0[k - 1], 0.0);
        double out[3];
        ctc_traj_eval(&j->traj[k - 1], 2.0, out);
        cr_assert(out[0] == 0 && out[1] == 0 && out[2] == 0, "q_d_%d(2) is not 0", k);
        cr_assert_eq(j->gains[k - 1].ki, 0.0);
    }
    job_free(j);
    cJSON_Delete(doc);
    cJSON_Delete(req);
}

Test(presets, n_link_pendulum_takes_n_from_2_to_65536_default_8)
{
    static const struct {
        const char *request;
        int n;
    } cases[] = {
        {NULL, 8},
        {"{}", 8},
        {"{\"preset\": \"n_link_pendulum\", \"duration\": 2}", 8},
        {"{\"n\": 2}", 2},
        {"{\"n\": 3.0}", 3},
        {"{\"n\": 4096}", 4096},
        {"{\"n\": 65536}", 65536},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        cJSON *req = cases[i].request ? request_from(cases[i].request) : NULL;
        cJSON *doc = build("n_link_pendulum", req);
        const char *what = cases[i].request ? cases[i].request : "NULL";
        cr_assert_eq(cJSON_GetArraySize(at(doc, "scene.bodies")), cases[i].n, "%s", what);
        cr_assert_eq(cJSON_GetArraySize(at(doc, "scene.q0")), cases[i].n, "%s", what);
        if (cases[i].n > 4096) /* few samples, within the output limit (job_json.h) */
            cJSON_ReplaceItemInObjectCaseSensitive(doc, "duration", cJSON_CreateNumber(0.01));
        job *j = parse_doc(doc, what);
        cr_assert_eq(j->spec.chain.nbodies, cases[i].n, "%s", what);
        job_free(j);
        cJSON_Delete(doc);
        cJSON_Delete(req);
    }
}

Test(presets, n_link_pendulum_rejects_bad_n_with_exact_messages)
{
    static const struct {
        const char *request;
        const char *message;
    } cases[] = {
        {"{\"n\": 0}", "must be an integer from 2 to 65536 (got 0)"},
        {"{\"n\": 1}", "must be an integer from 2 to 65536 (got 1)"},
        {"{\"n\": 65537}", "must be an integer from 2 to 65536 (got 65537)"},
        {"{\"n\": 2.5}", "must be an integer from 2 to 65536 (got 2.5)"},
        {"{\"n\": \"8\"}", "must be an integer from 2 to 65536 (got a string)"},
        {"{\"n\": -3}", "must be an integer from 2 to 65536 (got -3)"},
        {"{\"n\": 1e10}", "must be an integer from 2 to 65536 (got 1e+10)"},
        {"{\"n\": 0.1}", "must be an integer from 2 to 65536 (got 0.1)"},
        {"{\"n\": true}", "must be an integer from 2 to 65536 (got true)"},
        {"{\"n\": null}", "must be an integer from 2 to 65536 (got null)"},
        {"{\"n\": [8]}", "must be an integer from 2 to 65536 (got an array)"},
        {"{\"n\": {}}", "must be an integer from 2 to 65536 (got an object)"},
    };
    const preset *p = presets_find("n_link_pendulum");
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        cJSON *req = request_from(cases[i].request);
        job_error err = {0};
        cJSON *doc = p->build(req, &err);
        cr_assert_null(doc, "%s: built a document", cases[i].request);
        cr_assert_eq(err.code, JOB_INVALID_FIELD, "%s: code %s", cases[i].request,
                     job_error_code_name(err.code));
        cr_assert_str_eq(err.field, "n", "%s", cases[i].request);
        cr_assert_str_eq(err.message, cases[i].message, "%s", cases[i].request);
        cJSON_Delete(req);
    }
}

/* ---- through the job format's preset form ---- */

Test(presets, preset_form_takes_the_parameter_and_applies_overrides)
{
    /* the presets write their integrator out (dopri5 with rtol, atol): a patch that switches to
       rk4 replaces the object, so rk4 does not inherit the keys it does not take */
    static const char text[] = "{\"preset\": \"n_link_pendulum\", \"n\": 16, \"duration\": 3,"
                               " \"integrator\": {\"method\": \"rk4\", \"step\": 0.001}}";
    job *j = NULL;
    job_error err = {0};
    cr_assert_eq(job_parse(text, strlen(text), &j, &err), 0, "job_parse: %s at \"%s\": %s",
                 job_error_code_name(err.code), err.field, err.message);
    cr_assert_str_eq(j->preset, "n_link_pendulum");
    cr_assert_eq(j->spec.chain.nbodies, 16);
    cr_assert_eq(j->spec.duration, 3.0);
    cr_assert_eq(j->spec.integrator.method, CTC_INTEG_RK4);
    cr_assert_eq(j->spec.integrator.step, 0.001);
    expect_close(j->q0[15], pi / 6, 1e-15, "q0_16");
    job_free(j);

    /* a bad parameter comes back as the preset reported it */
    static const char bad[] = "{\"preset\": \"n_link_pendulum\", \"n\": 1}";
    j = NULL;
    cr_assert_neq(job_parse(bad, strlen(bad), &j, &err), 0);
    cr_assert_null(j);
    cr_assert_eq(err.code, JOB_INVALID_FIELD, "code %s", job_error_code_name(err.code));
    cr_assert_str_eq(err.field, "n");
    cr_assert_str_eq(err.message, "must be an integer from 2 to 65536 (got 1)");
}

/* ---- the scene geometry, through the library's kinematics ---- */

Test(presets, triple_pendulum_hangs_along_minus_y_and_poses_as_drawn)
{
    static const double end[3] = {0, -1, 0};
    cJSON *doc = build("triple_pendulum_pd", NULL);
    job *j = parse_doc(doc, "triple_pendulum_pd");

    /* q = 0: joints at y = 0, -1, -2; body 3's centre of mass at y = -2.5, its tip at y = -3 */
    const double zero[3] = {0, 0, 0};
    posed p = pose(j, zero);
    cr_assert_eq(p.m->form, CTC_FORM_PLANAR, "the triple pendulum is planar");
    double got[3], com[3];
    for (int k = 0; k < 3; k++) {
        body_point(p.m, p.d, k, zero, got);
        expect_point(got, 0, -k, 0, "joint centre");
    }
    to_world(p.m, p.d->xcom + 6, com);
    expect_point(com, 0, -2.5, 0, "body 3 centre of mass");
    body_point(p.m, p.d, 2, end, got);
    expect_point(got, 0, -3, 0, "body 3 tip");
    pose_free(&p);

    /* the paper's q0: rod k points along (sin theta_k, -cos theta_k), theta_k = q_1 + .. + q_k */
    p = pose(j, j->q0);
    double theta = 0, tip[3] = {0, 0, 0};
    for (int k = 0; k < 3; k++) {
        theta += j->q0[k];
        tip[0] += sin(theta);
        tip[1] -= cos(theta);
    }
    body_point(p.m, p.d, 2, end, got);
    expect_point(got, tip[0], tip[1], 0, "body 3 tip at q0");
    pose_free(&p);

    job_free(j);
    cJSON_Delete(doc);
}

Test(presets, spatial_double_pendulum_poses_as_drawn)
{
    static const double far_end[3] = {1, 0, 0}, origin[3] = {0, 0, 0};
    cJSON *doc = build("spatial_double_pendulum_pd", NULL);
    job *j = parse_doc(doc, "spatial_double_pendulum_pd");
    double got[3];

    /* q = 0: both cuboids along +x, J2 at (1, 0, 0), the tip at (2, 0, 0) */
    const double q_zero[2] = {0, 0};
    posed p = pose(j, q_zero);
    cr_assert_eq(p.m->form, CTC_FORM_SPATIAL, "J1 about z and J2 about y: not planar");
    body_point(p.m, p.d, 1, origin, got);
    expect_point(got, 1, 0, 0, "J2 at q = 0");
    body_point(p.m, p.d, 1, far_end, got);
    expect_point(got, 2, 0, 0, "tip at q = 0");
    pose_free(&p);

    /* q0 = (pi/2, 0): a quarter turn about z lays both along +y, centres at y = 0.5 and 1.5 */
    p = pose(j, j->q0);
    double com[3];
    to_world(p.m, p.d->xcom, com);
    expect_point(com, 0, 0.5, 0, "body 1 centre of mass at q0");
    to_world(p.m, p.d->xcom + 3, com);
    expect_point(com, 0, 1.5, 0, "body 2 centre of mass at q0");
    pose_free(&p);

    /* (pi/2, pi/2): a quarter turn about body 1's y (now world -x) turns body 2's x from +y
       towards -z: body 2 hangs straight down from J2 */
    const double q_down[2] = {pi / 2, pi / 2};
    p = pose(j, q_down);
    body_point(p.m, p.d, 1, far_end, got);
    expect_point(got, 0, 1, -1, "tip at (pi/2, pi/2)");
    to_world(p.m, p.d->xcom + 3, com);
    expect_point(com, 0, 1, -0.5, "body 2 centre of mass at (pi/2, pi/2)");
    pose_free(&p);

    job_free(j);
    cJSON_Delete(doc);
}

/* ---- the closed chains ---- */

/* the closed chain presets: the tip's closing point at q0 against the anchor, and the model */
static const struct {
    const char *name;
    int tip;           /* the tip body */
    ctc_form form;     /* the model's */
    int freedoms, dim; /* Gruebler-Kutzbach: sum of the joint freedoms, closing one included */
    int nind;          /* independent coordinates */
    int body;          /* the body the loop closes on, -1: the ground */
} loop_want[] = {
    {"five_bar_pd", 4, CTC_FORM_PLANAR, 6, 3, 3, -1},
    {"five_bar_lqr", 4, CTC_FORM_PLANAR, 6, 3, 3, -1},
    {"four_bar_passive", 2, CTC_FORM_PLANAR, 4, 3, 0, -1},
    {"arm_four_bar_pd", 3, CTC_FORM_PLANAR, 5, 3, 2, 0},
    {"rssr_passive", 2, CTC_FORM_SPATIAL, 8, 6, 0, -1},
    {"y_four_bar_pd", 5, CTC_FORM_PLANAR, 7, 3, 4, 0},
};

/* element i of the array at path as a 3-vector */
static void vec3_at(const cJSON *doc, const char *path, double out[3])
{
    const cJSON *v = at(doc, path);
    cr_assert_eq(cJSON_GetArraySize(v), 3, "%s is not a 3-vector", path);
    for (int i = 0; i < 3; i++) out[i] = element(v, i, path);
}

Test(presets, five_bar_holds_the_papers_values)
{
    static const double length[5] = {1, 1, 0.5, 1, 1};
    static const int independent[5] = {1, 1, 1, 0, 0};
    const double q0[5] = {-pi / 8, 5 * pi / 8, 3 * pi / 8, 3 * pi / 8, 5 * pi / 8};
    const double set_point[3] = {0, pi / 4, -3 * pi / 4};
    cJSON *doc = build("five_bar_pd", NULL);
    cr_assert_str_eq(string_at(doc, "name"),
                     "Five-bar closed chain, PD (Kingsley et al. 2017, sec. 7.2)");

    /* five uniform rods of 1 kg along -y, each joint at the previous rod's end, joints 0-2
       independent, gravity -y */
    const cJSON *bodies = at(doc, "scene.bodies"), *dq0 = at(doc, "scene.q0");
    cr_assert_eq(cJSON_GetArraySize(bodies), 5);
    cr_assert_eq(element(at(doc, "scene.gravity"), 1, "gravity"), -9.81);
    for (int k = 0; k < 5; k++) {
        const cJSON *b = cJSON_GetArrayItem(bodies, k);
        double end[3], axis[3], loc[3];
        cr_assert_eq(number_at(b, "mass"), 1.0, "rod %d mass", k);
        cr_assert_str_eq(string_at(b, "shape.type"), "rod");
        vec3_at(b, "shape.end", end);
        vec3_at(b, "joint.axis", axis);
        vec3_at(b, "joint.location", loc);
        expect_point(end, 0, -length[k], 0, "rod end");
        expect_point(axis, 0, 0, 1, "joint axis");
        expect_point(loc, 0, k == 0 ? 0 : -length[k - 1], 0, "joint location");
        cr_assert_str_eq(string_at(b, "joint.type"), "revolute");
        cr_assert_eq(cJSON_IsTrue(at(b, "joint.independent")), independent[k], "joint %d", k);
        expect_close(element(dq0, k, "q0"), q0[k], 1e-15, "q0");
        cr_assert_eq(element(at(doc, "scene.v0"), k, "v0"), 0.0);
    }

    /* the closing joint: dependent, revolute about z at the end of rod 5 */
    double axis[3], loc[3];
    cr_assert_str_eq(string_at(doc, "scene.loop.joint.type"), "revolute");
    cr_assert(cJSON_IsFalse(at(doc, "scene.loop.joint.independent")));
    vec3_at(doc, "scene.loop.joint.axis", axis);
    vec3_at(doc, "scene.loop.joint.location", loc);
    expect_point(axis, 0, 0, 1, "closing axis");
    expect_point(loc, 0, -1, 0, "closing joint on rod 5");

    /* the set point (0, pi/4, -3 pi/4) by PD, no disturbance, 10 s */
    const cJSON *traj = at(doc, "trajectory");
    cr_assert_eq(cJSON_GetArraySize(traj), 3);
    for (int i = 0; i < 3; i++) {
        const cJSON *tr = cJSON_GetArrayItem(traj, i);
        cr_assert_str_eq(string_at(tr, "type"), "constant");
        expect_close(number_at(tr, "value"), set_point[i], 1e-15, "set point");
    }
    cr_assert_eq(number_at(doc, "controller.kp"), 100.0);
    cr_assert_eq(number_at(doc, "controller.kv"), 20.0);
    cr_assert_null(cJSON_GetObjectItemCaseSensitive(doc, "disturbance"));
    cr_assert_eq(number_at(doc, "duration"), 10.0);

    /* the job: three controlled coordinates, joints 0, 1 and 2 */
    job *j = parse_doc(doc, "five_bar_pd");
    cr_assert_eq(j->nind, 3);
    static const unsigned char flags[6] = {1, 1, 1, 0, 0, 0};
    for (int k = 0; k < 6; k++) cr_assert_eq(j->independent[k], flags[k], "independent[%d]", k);
    for (int i = 0; i < 3; i++) {
        double out[3];
        ctc_traj_eval(&j->traj[i], 3.0, out);
        expect_close(out[0], set_point[i], 1e-15, "q_d");
        cr_assert_eq(j->gains[i].ki, 0.0);
    }
    cr_assert_null(j->spec.disturb);
    job_free(j);
    cJSON_Delete(doc);
}

Test(presets, five_bar_anchor_is_where_q0_puts_the_end_of_rod_5)
{
    /* forward kinematics by hand: rod k from the end of rod k-1 by L_k (sin theta_k, -cos
       theta_k), theta_k = q_0 + ... + q_k */
    static const double length[5] = {1, 1, 0.5, 1, 1};
    const double q0[5] = {-pi / 8, 5 * pi / 8, 3 * pi / 8, 3 * pi / 8, 5 * pi / 8};
    double theta = 0, x = 0, y = 0;
    for (int k = 0; k < 5; k++) {
        theta += q0[k];
        x += length[k] * sin(theta);
        y -= length[k] * cos(theta);
    }
    for (int i = 0; i < 2; i++) {
        cJSON *doc = build(i ? "five_bar_lqr" : "five_bar_pd", NULL);
        double anchor[3];
        vec3_at(doc, "scene.loop.anchor", anchor);
        expect_point(anchor, x, y, 0, "anchor against forward kinematics");
        /* the numbers presets.c documents */
        expect_point(anchor, -0.28113192973418280, -0.67871251758038230, 0, "documented anchor");
        cJSON_Delete(doc);
    }
}

Test(presets, every_loop_preset_closes_at_q0_and_builds_its_loop_model)
{
    for (size_t i = 0; i < sizeof loop_want / sizeof loop_want[0]; i++) {
        const char *name = loop_want[i].name;
        cJSON *doc = build(name, NULL);
        job *j = parse_doc(doc, name);
        double anchor[3], loc[3], got[3];
        vec3_at(doc, "scene.loop.anchor", anchor);
        vec3_at(doc, "scene.loop.joint.location", loc);

        /* the model: a loop of the expected form, mobility and independent coordinates */
        posed p = pose(j, j->q0);
        cr_assert_eq(p.m->has_loop, 1, "%s: no loop", name);
        cr_assert_eq(p.m->form, loop_want[i].form, "%s: form %s", name, ctc_form_name(p.m->form));
        cr_assert_eq(p.m->njoints, p.m->nbodies + 1, "%s", name);
        cr_assert_eq(p.m->nvx, loop_want[i].freedoms, "%s: nvx", name);
        cr_assert_eq(p.m->mobility, loop_want[i].freedoms - loop_want[i].dim, "%s: mobility", name);
        cr_assert_eq(p.m->nind, loop_want[i].nind, "%s: nind", name);
        cr_assert_eq(p.m->nind, j->nind, "%s: the format's count", name);
        cr_assert_eq(p.m->loop_body, loop_want[i].body, "%s: the loop's body", name);

        /* the tip's closing point at q0 is the anchor (on the ground, or on the loop's body) */
        body_point(p.m, p.d, loop_want[i].tip, loc, got);
        if (loop_want[i].body >= 0) {
            double a[3];
            body_point(p.m, p.d, loop_want[i].body, anchor, a);
            memcpy(anchor, a, sizeof a);
        }
        expect_point(got, anchor[0], anchor[1], anchor[2], name);
        pose_free(&p);
        job_free(j);
        cJSON_Delete(doc);
    }
}

Test(presets, four_bar_is_a_crank_rocker_closed_at_q0)
{
    cJSON *doc = build("four_bar_passive", NULL);
    cr_assert_str_eq(string_at(doc, "controller.type"), "none");
    cr_assert_null(cJSON_GetObjectItemCaseSensitive(doc, "trajectory"));
    job *j = parse_doc(doc, "four_bar_passive");

    /* crank 0.4, coupler 1, rocker 0.8 m of 1 kg/m; ground 1 m; Grashof s + l <= p + q with
       the crank the shortest link */
    static const double length[3] = {0.4, 1, 0.8};
    for (int k = 0; k < 3; k++) {
        cr_assert_eq(j->bodies[k].mass, length[k], "rod %d mass", k);
        cr_assert_eq(j->independent[k], 0, "joint %d dependent", k);
    }
    cr_assert_eq(j->independent[3], 0, "the closing joint dependent");
    cr_assert(0.4 + 1 <= 1 + 0.8);
    expect_close(j->q0[0], 2 * pi / 3, 1e-14, "crank at 2 pi/3");

    /* the joints at q0: C at the crank's end, B (coupler-rocker) 1 m from C and 0.8 m from the
       anchor A = (1, 0), above the line C-A (elbow up) */
    posed p = pose(j, j->q0);
    const double origin[3] = {0, 0, 0};
    double c[3], b[3];
    body_point(p.m, p.d, 1, origin, c);
    body_point(p.m, p.d, 2, origin, b);
    expect_point(c, 0.4 * sin(2 * pi / 3), -0.4 * cos(2 * pi / 3), 0, "crank end");
    expect_close(hypot(b[0] - c[0], b[1] - c[1]), 1, POS_TOL, "coupler length");
    expect_close(hypot(b[0] - 1, b[1]), 0.8, POS_TOL, "rocker length");
    double side = (1 - c[0]) * (b[1] - c[1]) - (0 - c[1]) * (b[0] - c[0]);
    cr_assert_gt(side, 0, "B is on the left of C -> A");
    expect_close(b[0], 1.158, 5e-4, "B x, as documented");
    expect_close(b[1], 0.784, 5e-4, "B y, as documented");
    pose_free(&p);
    job_free(j);
    cJSON_Delete(doc);
}

Test(presets, rssr_rocker_turns_about_the_closing_axis_at_q0)
{
    cJSON *doc = build("rssr_passive", NULL);
    job *j = parse_doc(doc, "rssr_passive");
    cr_assert_eq(j->spec.chain.gravity[2], -9.81);
    cr_assert_eq(j->joints[0].type, CTC_JOINT_REVOLUTE);
    cr_assert_eq(j->joints[1].type, CTC_JOINT_SPHERICAL);
    cr_assert_eq(j->joints[2].type, CTC_JOINT_SPHERICAL);
    cr_assert_eq(j->loop.joint.type, CTC_JOINT_REVOLUTE);

    /* the crank turns about z, the rocker about y: not parallel, so the loop is spatial */
    const double *crank = j->joints[0].axis, *a = j->loop.joint.axis;
    double cross[3] = {crank[1] * a[2] - crank[2] * a[1], crank[2] * a[0] - crank[0] * a[2],
                       crank[0] * a[1] - crank[1] * a[0]};
    cr_assert_gt(fabs(cross[0]) + fabs(cross[1]) + fabs(cross[2]), 0.5, "axes not parallel");

    /* at q0 the coupler runs 1 m from the crank's end to the rocker's joint, and the rocker's
       orientation leaves the closing axis where it is in the world (the closure's rotation) */
    posed p = pose(j, j->q0);
    const double origin[3] = {0, 0, 0};
    double b[3], c[3];
    body_point(p.m, p.d, 1, origin, b);
    body_point(p.m, p.d, 2, origin, c);
    expect_point(b, 0.3, 0, 0, "crank end");
    expect_point(c, 0.3, 0.8, 0.6, "coupler end");
    const double *r = p.d->xrot + 9 * 2;
    double ra[3];
    for (int i = 0; i < 3; i++) ra[i] = r[3 * i] * a[0] + r[3 * i + 1] * a[1] + r[3 * i + 2] * a[2];
    expect_point(ra, a[0], a[1], a[2], "closing axis carried by the rocker");
    pose_free(&p);
    job_free(j);
    cJSON_Delete(doc);
}

/* ---- trees ---- */

/* The model of a tree preset's job, posed at q (nq) at rest, for any size. */
static posed pose_tree(const job *j, const double *q)
{
    posed p;
    char err[256] = "";
    cr_assert_eq(ctc_model_build(&j->spec.chain, &p.m, err, sizeof err), CTC_OK,
                 "ctc_model_build: %s", err);
    p.d = ctc_data_new(p.m);
    cr_assert_not_null(p.d);
    double *v = calloc((size_t)p.m->nv, sizeof *v);
    ctc_kinematics(p.m, p.d, q, v);
    free(v);
    return p;
}

/* the job's parents, and the model's, against want (n) */
static void expect_parents(const job *j, const posed *p, const int *want, int n, const char *what)
{
    for (int k = 0; k < n; k++) {
        cr_assert_eq(j->parent[k], want[k], "%s: body %d's parent in the job", what, k);
        cr_assert_eq(p->m->body_parent[k], want[k], "%s: body %d's parent in the model", what, k);
    }
}

Test(presets, y_pendulum_hangs_two_double_pendulums_from_the_arms_tip)
{
    static const int parent[5] = {-1, 0, 1, 0, 3};
    static const double length[5] = {1, 0.5, 0.5, 0.5, 0.5}, mass[5] = {1, 0.5, 0.5, 0.5, 0.5};
    cJSON *doc = build("y_pendulum_pd", NULL);
    job *j = parse_doc(doc, "y_pendulum_pd");
    posed p = pose_tree(j, j->q0);
    cr_assert_eq(p.m->form, CTC_FORM_PLANAR, "the Y is planar");
    expect_parents(j, &p, parent, 5, "y_pendulum_pd");

    /* rods: mass and inertia m L^2 / 12 about the centre, along -y */
    for (int k = 0; k < 5; k++) {
        cr_assert_eq(j->bodies[k].mass, mass[k]);
        expect_close(j->bodies[k].inertia[0], mass[k] * length[k] * length[k] / 12, 1e-15, "Ixx");
        expect_close(j->bodies[k].com[1], -length[k] / 2, 1e-15, "com y");
    }

    /* at q0, rod k hangs at theta_k, the sum of its ancestors' angles and its own, from its
       parent's tip */
    double theta[5], tip[5][2];
    for (int k = 0; k < 5; k++) {
        int a = parent[k];
        theta[k] = (a < 0 ? 0 : theta[a]) + j->q0[k];
        tip[k][0] = (a < 0 ? 0 : tip[a][0]) + length[k] * sin(theta[k]);
        tip[k][1] = (a < 0 ? 0 : tip[a][1]) - length[k] * cos(theta[k]);
        const double end[3] = {0, -length[k], 0};
        double got[3];
        body_point(p.m, p.d, k, end, got);
        expect_point(got, tip[k][0], tip[k][1], 0, "a rod's tip at q0");
    }
    pose_free(&p);
    job_free(j);
    cJSON_Delete(doc);
}

Test(presets, spatial_hand_is_aluminium_and_its_fingertips_hang_below_the_palm)
{
    static const int parent[10] = {-1, 0, 1, 2, 0, 4, 5, 0, 7, 8};
    static const double link[3] = {0.045, 0.03, 0.025}, finger_x[3] = {-0.025, 0, 0.025};
    const double rho = 2700, side = 0.015;
    cJSON *doc = build("spatial_hand_pd", NULL);
    job *j = parse_doc(doc, "spatial_hand_pd");
    double q[10] = {0};
    posed p = pose_tree(j, q);
    cr_assert_eq(p.m->form, CTC_FORM_SPATIAL, "the hand is spatial");
    expect_parents(j, &p, parent, 10, "spatial_hand_pd");

    /* the palm: 0.08 x 0.02 x 0.1 m of aluminium, a box's inertia m (b^2 + c^2) / 12 */
    double palm = rho * 0.08 * 0.02 * 0.1;
    expect_close(j->bodies[0].mass, palm, 1e-14 * palm, "palm mass");
    expect_close(j->bodies[0].inertia[0], palm * (0.02 * 0.02 + 0.1 * 0.1) / 12, 1e-15, "palm Ixx");
    expect_close(j->bodies[0].inertia[8], palm * (0.08 * 0.08 + 0.02 * 0.02) / 12, 1e-15,
                 "palm Izz");

    /* q = 0: each finger's links straight down from the palm's far edge, its tip 0.2 m below the
       wrist; each link's mass density x volume */
    for (int f = 0; f < 3; f++) {
        double z = -0.1;
        for (int l = 0; l < 3; l++) {
            int k = 1 + 3 * f + l;
            double m = rho * side * side * link[l];
            expect_close(j->bodies[k].mass, m, 1e-14 * m, "finger link mass");
            double got[3];
            const double origin[3] = {0, 0, 0}, end[3] = {0, 0, -link[l]};
            body_point(p.m, p.d, k, origin, got);
            expect_point(got, finger_x[f], 0, z, "a finger joint at q = 0");
            z -= link[l];
            body_point(p.m, p.d, k, end, got);
            expect_point(got, finger_x[f], 0, z, "a finger link's end at q = 0");
        }
    }
    pose_free(&p);

    /* the wrist turned a quarter turn about y: the middle fingertip at (-0.2, 0, 0) */
    q[0] = pi / 2;
    p = pose_tree(j, q);
    const double end[3] = {0, 0, -0.025};
    double got[3];
    body_point(p.m, p.d, 6, end, got);
    expect_point(got, -0.2, 0, 0, "the middle fingertip after a quarter turn of the wrist");
    pose_free(&p);
    job_free(j);
    cJSON_Delete(doc);
}

Test(presets, two_arm_torso_has_winters_segments_on_both_shoulders)
{
    static const int parent[7] = {-1, 0, 1, 2, 0, 4, 5};
    /* Winter (2009) Table 4.1 for 70 kg, 1.75 m: mass fractions and length fractions */
    static const double mfrac[3] = {0.028, 0.016, 0.006}, lfrac[3] = {0.186, 0.146, 0.108};
    cJSON *doc = build("two_arm_torso_pd", NULL);
    job *j = parse_doc(doc, "two_arm_torso_pd");
    double q[7] = {0};
    posed p = pose_tree(j, q);
    cr_assert_eq(p.m->form, CTC_FORM_SPATIAL);
    expect_parents(j, &p, parent, 7, "two_arm_torso_pd");
    expect_close(j->bodies[0].mass, 0.355 * 70, 0.2, "torso mass (thorax and abdomen)");

    /* q = 0: both arms straight down from (+-0.2, 0, 0.45); segment masses and lengths within
       rounding of Winter's fractions */
    for (int a = 0; a < 2; a++) {
        double z = 0.45, x = a == 0 ? 0.2 : -0.2;
        for (int l = 0; l < 3; l++) {
            int k = 1 + 3 * a + l;
            expect_close(j->bodies[k].mass, mfrac[l] * 70, 0.005, "segment mass");
            double len = -2 * j->bodies[k].com[2]; /* a uniform cylinder: its centre halfway */
            expect_close(len, lfrac[l] * 1.75, 0.005, "segment length");
            double got[3];
            const double origin[3] = {0, 0, 0};
            body_point(p.m, p.d, k, origin, got);
            expect_point(got, x, 0, z, "an arm joint at q = 0");
            z -= len;
        }
    }
    pose_free(&p);

    /* the waist a quarter turn: the left shoulder at (0, 0.2, 0.45) */
    q[0] = pi / 2;
    p = pose_tree(j, q);
    const double origin[3] = {0, 0, 0};
    double got[3];
    body_point(p.m, p.d, 1, origin, got);
    expect_point(got, 0, 0.2, 0.45, "the left shoulder after a quarter turn of the waist");
    pose_free(&p);
    job_free(j);
    cJSON_Delete(doc);
}

/* the lab's triple pendulum: the paper's PID scene with its controller sampled at 1 kHz, 200 Hz
   and 50 Hz, or its actuators limited to +-50 N m (integrated by bdf) */
Test(presets, lab_triple_pendulums_are_the_papers_scene_sampled_or_limited)
{
    const char *names[4] = {"triple_pendulum_pid_1khz", "triple_pendulum_pid_200hz",
                            "triple_pendulum_pid_50hz", "triple_pendulum_pid_limited"};
    const double period[4] = {1e-3, 5e-3, 2e-2, 0};
    for (int i = 0; i < 4; i++) {
        char text[128];
        job *j = NULL;
        job_error err;
        snprintf(text, sizeof text, "{\"preset\": \"%s\"}", names[i]);
        cr_assert_eq(job_parse(text, strlen(text), &j, &err), 0, "%s: %s: %s", names[i], err.field,
                     err.message);
        const ctc_sim_spec *s = &j->spec;
        cr_expect_eq(s->controller, CTC_CTRL_PID, "%s", names[i]);
        cr_expect(s->gains[0].kp == 100 && s->gains[0].kv == 20 && s->gains[0].ki == 250);
        cr_expect_eq(s->sample_period, period[i], "%s", names[i]);
        cr_expect_eq(s->sample_delay, 0);
        cr_expect_eq(s->disturb[2].value, 0.2);
        if (i == 3) {
            cr_assert_not_null(s->plant);
            for (int k = 0; k < 3; k++) cr_expect_eq(s->plant[k].torque_limit, 50);
            cr_expect_eq(s->integrator.method, CTC_INTEG_BDF);
        } else {
            cr_expect_null(s->plant, "%s: the ideal plant", names[i]);
            cr_expect_eq(s->integrator.method, CTC_INTEG_DOPRI5);
        }
        job_free(j);
    }
}

Test(presets, y_four_bar_closes_its_four_bar_branch_on_the_arm)
{
    static const int parent[6] = {-1, 0, 1, 0, 3, 2};
    cJSON *doc = build("y_four_bar_pd", NULL);
    job *j = parse_doc(doc, "y_four_bar_pd");
    posed p = pose_tree(j, j->q0);
    expect_parents(j, &p, parent, 6, "y_four_bar_pd");
    cr_assert_eq(p.m->chain, 0);
    cr_assert_eq(p.m->form, CTC_FORM_PLANAR);
    /* the spine arm-crank-coupler-rocker is the root path; the loop's joints are 1, 2, 5 and the
       closing one, the double pendulum's 3, 4 are outside it and driven */
    cr_assert_eq(p.m->body_heavy[0], 1);
    cr_assert_eq(p.m->body_heavy[2], 5);
    const unsigned char in_loop[7] = {0, 1, 1, 0, 0, 1, 1}, indep[7] = {1, 1, 0, 1, 1, 0, 0};
    for (int k = 0; k < 7; k++) {
        cr_expect_eq(p.m->jnt_loop[k], in_loop[k], "joint %d in the loop", k);
        cr_expect_eq(p.m->jnt_indep[k], indep[k], "joint %d independent", k);
    }
    /* the trajectory: one entry per independent coordinate, starting at q0 */
    cr_assert_eq(cJSON_GetArraySize(at(doc, "trajectory")), 4);
    pose_free(&p);
    job_free(j);
    cJSON_Delete(doc);
}

Test(presets, panda_moves_inside_frankas_joint_limits_and_opens_both_fingers)
{
    /* franka_arm.xacro's limits (rad) and franka_hand.xacro's (m) */
    static const double lower[9] = {-2.8973, -1.7628, -2.8973, -3.0718, -2.8973,
                                    -0.0175, -2.8973, 0,       0};
    static const double upper[9] = {2.8973, 1.7628, 2.8973, -0.0698, 2.8973,
                                    3.7525, 2.8973, 0.04,   0.04};
    /* Franka's ready pose, then both fingers from 1 cm to 4 cm open */
    const double ready[9] = {0, -pi / 4, 0, -3 * pi / 4, 0, pi / 2, pi / 4, 0.01, 0.01};
    static const int parents[9] = {-1, 0, 1, 2, 3, 4, 5, 6, 6};
    cJSON *doc = build("panda_min_jerk", NULL);
    const cJSON *traj = cJSON_GetObjectItemCaseSensitive(doc, "trajectory");
    const cJSON *q0 =
        cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(doc, "scene"), "q0");
    cr_assert_eq(cJSON_GetArraySize(traj), 9);
    for (int i = 0; i < 9; i++) {
        const cJSON *t = cJSON_GetArrayItem(traj, i);
        double from = cJSON_GetObjectItemCaseSensitive(t, "from")->valuedouble;
        double to = cJSON_GetObjectItemCaseSensitive(t, "to")->valuedouble;
        cr_assert_str_eq(cJSON_GetObjectItemCaseSensitive(t, "type")->valuestring, "min_jerk");
        cr_assert_float_eq(from, ready[i], READ_TOL, "joint %d starts at %g", i, from);
        cr_assert_eq(cJSON_GetArrayItem(q0, i)->valuedouble, from, "q0[%d]", i);
        cr_assert(from >= lower[i] && from <= upper[i] && to >= lower[i] && to <= upper[i],
                  "joint %d: %g -> %g leaves [%g, %g]", i, from, to, lower[i], upper[i]);
        if (i >= 7) cr_assert_eq(to, 0.04, "finger %d opens to 4 cm", i - 7);
    }
    /* the URDF carries the same limits, and both fingers hang from the hand (link 7) */
    const char *text =
        cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(doc, "scene"), "urdf")
            ->valuestring;
    char msg[256];
    cJSON *bodies = urdf_to_bodies(text, strlen(text), NULL, 0, msg, sizeof msg);
    cr_assert_not_null(bodies, "%s", msg);
    cr_assert_eq(cJSON_GetArraySize(bodies), 9);
    for (int i = 0; i < 9; i++) {
        const cJSON *b = cJSON_GetArrayItem(bodies, i);
        const cJSON *limit =
            cJSON_GetObjectItemCaseSensitive(cJSON_GetObjectItemCaseSensitive(b, "joint"), "limit");
        cr_assert_eq(cJSON_GetObjectItemCaseSensitive(b, "parent")->valuedouble, parents[i]);
        cr_assert_eq(cJSON_GetObjectItemCaseSensitive(limit, "lower")->valuedouble, lower[i],
                     "body %d", i);
        cr_assert_eq(cJSON_GetObjectItemCaseSensitive(limit, "upper")->valuedouble, upper[i],
                     "body %d", i);
    }
    cJSON_Delete(bodies);
    job *j = parse_doc(doc, "panda_min_jerk");
    cr_assert_eq(j->spec.chain.nbodies, 9);
    for (int i = 0; i < 9; i++) cr_assert_eq(j->spec.chain.parent[i], parents[i], "body %d", i);
    job_free(j);
    cJSON_Delete(doc);
}

Test(presets, two_link_arm_carries_point_masses_at_its_link_ends_from_hanging_down)
{
    cJSON *doc = build("two_link_min_jerk", NULL);
    job *j = parse_doc(doc, "two_link_min_jerk");
    cr_assert_eq(j->spec.chain.gravity[1], -9.81, "gravity along -y, as Modern Robotics 8.1.1");
    /* 1 kg each, no inertia: point masses */
    for (int k = 0; k < 2; k++) {
        const ctc_body_spec *b = &j->spec.chain.bodies[k];
        cr_assert_eq(b->mass, 1.0, "m%d", k + 1);
        for (int e = 0; e < 9; e++) cr_assert_eq(b->inertia[e], 0.0, "body %d inertia[%d]", k, e);
    }
    /* from hanging straight down to theta = (pi/6, pi/2) */
    const double from[2] = {-pi / 2, 0}, to[2] = {pi / 6, pi / 2};
    const cJSON *traj = at(doc, "trajectory");
    for (int i = 0; i < 2; i++) {
        const cJSON *t = cJSON_GetArrayItem(traj, i);
        cr_assert_str_eq(string_at(t, "type"), "min_jerk");
        expect_close(number_at(t, "from"), from[i], READ_TOL, "from");
        expect_close(number_at(t, "to"), to[i], 4 * READ_TOL, "to");
        expect_close(j->q0[i], from[i], READ_TOL, "q0");
    }
    /* the masses: at the ends of links of 1 m, link k along theta_1 + .. + theta_k from x */
    const double *poses[2] = {from, to};
    for (int c = 0; c < 2; c++) {
        posed p = pose(j, poses[c]);
        cr_assert_eq(p.m->form, CTC_FORM_PLANAR, "the two-link arm is planar");
        double theta = 0, x = 0, y = 0, com[3];
        for (int k = 0; k < 2; k++) {
            theta += poses[c][k];
            x += cos(theta);
            y += sin(theta);
            to_world(p.m, p.d->xcom + 3 * k, com);
            expect_point(com, x, y, 0, "point mass");
        }
        pose_free(&p);
    }
    job_free(j);
    cJSON_Delete(doc);
}

Test(presets, two_link_lab_arm_is_the_textbook_arm_with_friction_and_a_payload_it_ignores)
{
    cJSON *lab = build("two_link_lab_payload", NULL), *book = build("two_link_min_jerk", NULL);
    job *j = parse_doc(lab, "two_link_lab_payload"), *b = parse_doc(book, "two_link_min_jerk");
    /* the plant carries 0.5 kg at link 2's tip (1 m along its x): 1.5 kg, centre of mass at the
       tip still; the controller's model is the book's arm */
    cr_assert_eq(j->spec.chain.bodies[1].mass, 1.5);
    cr_assert_eq(j->spec.chain.bodies[1].com[0], 1.0);
    cr_assert_not_null(j->spec.model_bodies);
    for (int k = 0; k < 2; k++) {
        cr_assert_eq(j->spec.model_bodies[k].mass, b->spec.chain.bodies[k].mass, "body %d", k);
        cr_assert_eq(j->spec.chain.bodies[0].mass, b->spec.chain.bodies[0].mass);
    }
    /* friction on both joints, unknown to the controller */
    cr_assert_not_null(j->spec.plant);
    for (int i = 0; i < 2; i++) {
        const ctc_plant_coord *pc = &j->spec.plant[i];
        cr_assert(pc->viscous == 0.2 && pc->coulomb == 1 && pc->coulomb_velocity == 0.01);
        cr_assert_eq(pc->known, 0, "joint %d", i);
    }
    /* the same move; its error comes from the model: error_by_cause's model row is its own */
    for (int i = 0; i < 2; i++) {
        cr_assert_eq(j->traj[i].type, b->traj[i].type);
        cr_assert_eq(j->q0[i], b->q0[i]);
    }
    ctc_sim_result *r = NULL;
    char err[256];
    cr_assert_eq(ctc_sim_run(&j->spec, NULL, &r, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
    for (int i = 0; i < 2; i++) {
        cr_expect_gt(r->metrics.err_cause[CTC_CAUSE_MODEL * 2 + i], 1e-3, "joint %d", i);
        cr_expect_eq(r->metrics.err_cause[CTC_CAUSE_MODEL * 2 + i],
                     r->metrics.err_cause[CTC_CAUSE_TOTAL * 2 + i], "the model is the only cause");
        cr_expect_eq(r->metrics.err_cause[CTC_CAUSE_SAMPLING * 2 + i], 0);
    }
    ctc_sim_result_free(r);
    job_free(j);
    job_free(b);
    cJSON_Delete(lab);
    cJSON_Delete(book);
}

Test(presets, puma560_holds_armstrong_khatib_burdicks_table_as_corke_lists_it)
{
    /* mdl_puma560akb: a_(i-1), alpha_(i-1), d_i, m_i, r_i, diag(I_i) */
    static const double a[6] = {0, 0, 0.4318, -0.0203, 0, 0};
    const double alpha[6] = {0, -pi / 2, 0, pi / 2, -pi / 2, pi / 2};
    static const double d[6] = {0, 0.2435, -0.0934, 0.4331, 0, 0};
    static const double m[6] = {0, 17.4, 4.8, 0.82, 0.34, 0.09};
    static const double r[6][3] = {{0, 0, 0},          {0.068, 0.006, -0.016},
                                   {0, -0.070, 0.014}, {0, 0, -0.019},
                                   {0, 0, 0},          {0, 0, 0.032}};
    static const double I[6][3] = {{0, 0, 0.35},
                                   {0.13, 0.524, 0.539},
                                   {0.066, 0.0125, 0.066},
                                   {1.8e-3, 1.8e-3, 1.3e-3},
                                   {0.3e-3, 0.3e-3, 0.4e-3},
                                   {0.15e-3, 0.15e-3, 0.04e-3}};
    cJSON *doc = build("puma560_min_jerk", NULL);
    cr_assert_str_eq(string_at(doc, "scene.dh.convention"), "modified");
    const cJSON *rows = at(doc, "scene.dh.rows");
    cr_assert_eq(cJSON_GetArraySize(rows), 6);
    for (int i = 0; i < 6; i++) {
        const cJSON *row = cJSON_GetArrayItem(rows, i);
        expect_close(number_at(row, "a"), a[i], 0, "a");
        expect_close(number_at(row, "alpha"), alpha[i], READ_TOL, "alpha");
        expect_close(number_at(row, "d"), d[i], 0, "d");
        expect_close(number_at(row, "mass"), m[i], 0, "mass");
        for (int k = 0; k < 3; k++) {
            expect_close(element(at(row, "com"), k, "com"), r[i][k], 0, "com");
            expect_close(element(at(row, "inertia"), k, "inertia"), I[i][k], 0, "inertia");
        }
    }
    /* from Corke's qz (all zero) */
    job *j = parse_doc(doc, "puma560_min_jerk");
    cr_assert_eq(j->spec.chain.bodies[0].mass, 0, "link 1 is massless");
    for (int i = 0; i < 6; i++) cr_assert_eq(j->q0[i], 0, "q0[%d]", i);
    /* at qz, frame 2 = Rx(-pi/2) at (0, 0.2435, 0): link 2's centre of mass at
       (0.068, 0.2435 - 0.016, -0.006); frames 4..6 meet at (0.4318 - 0.0203, 0.2435 - 0.0934,
       0.4331), frame 6 parallel to the world's: link 6's centre of mass 0.032 above */
    posed p = pose(j, j->q0);
    expect_point(p.d->xcom + 3, 0.068, 0.2275, -0.006, "link 2 centre of mass");
    expect_point(p.d->xcom + 15, 0.4115, 0.1501, 0.4651, "link 6 centre of mass");
    pose_free(&p);
    job_free(j);
    cJSON_Delete(doc);
}
