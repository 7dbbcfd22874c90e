/*
 * test_body_pose.c - the body_pose channel (sim.h CTC_CH_POSE, kinematics.h
 * ctc_kinematics_body_rotation and ctc_rotation_quaternion, job format output.body_pose): the
 * world position of a body's frame origin and its orientation as a unit quaternion, through the
 * job format and a run.
 *
 * Oracle written here: forward kinematics of a two-joint chain from its joint axes and
 * locations (Rodrigues' rotations composed from the ground: R_0 = R(a0, q0), R_1 = R_0 R(a1, q1),
 * p_1 = loc0 + R_0 loc1), evaluated at each recorded q, and the quaternion's rotation matrix
 * (w^2 + x^2 - y^2 - z^2, ...) compared with those rotations, so the quaternion is checked
 * without a second matrix-to-quaternion conversion. A planar chain (computed in the plane's
 * form, joint 1's axis along -z and locations off the plane) and a spatial one.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "kinematics.h"
#include "sim.h"

#define PI 3.14159265358979323846

/* single quotes to double quotes, into a malloc'd string */
static char *json(const char *text)
{
    char *s = strdup(text);
    cr_assert_not_null(s);
    for (char *c = s; *c; c++)
        if (*c == '\'') *c = '"';
    return s;
}

static job *parse(const char *text, job_error *err)
{
    char *doc = json(text);
    job *j = NULL;
    int rc = job_parse(doc, strlen(doc), &j, err);
    free(doc);
    return rc == 0 ? j : NULL;
}

/* R = rotation by angle about the unit axis a (Rodrigues), row-major */
static void rotation(const double a[3], double angle, double r[9])
{
    double c = cos(angle), s = sin(angle), t = 1 - c;
    r[0] = c + t * a[0] * a[0], r[1] = t * a[0] * a[1] - s * a[2],
    r[2] = t * a[0] * a[2] + s * a[1];
    r[3] = t * a[1] * a[0] + s * a[2], r[4] = c + t * a[1] * a[1],
    r[5] = t * a[1] * a[2] - s * a[0];
    r[6] = t * a[2] * a[0] - s * a[1], r[7] = t * a[2] * a[1] + s * a[0],
    r[8] = c + t * a[2] * a[2];
}

static void mul(const double a[9], const double b[9], double c[9])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            c[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

/* the rotation of the unit quaternion (w, x, y, z) */
static void quat_matrix(const double q[4], double r[9])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    r[0] = w * w + x * x - y * y - z * z, r[1] = 2 * (x * y - w * z), r[2] = 2 * (x * z + w * y);
    r[3] = 2 * (x * y + w * z), r[4] = w * w - x * x + y * y - z * z, r[5] = 2 * (y * z - w * x);
    r[6] = 2 * (x * z - w * y), r[7] = 2 * (y * z + w * x), r[8] = w * w - x * x - y * y + z * z;
}

typedef struct chain2 {
    double axis[2][3], loc[2][3];
} chain2;

/* body k's origin p_k and rotation R_k at q */
static void forward(const chain2 *c, const double q[2], int k, double p[3], double rot[9])
{
    double r0[9], r1[9];
    rotation(c->axis[0], q[0], r0);
    for (int i = 0; i < 3; i++) p[i] = c->loc[0][i];
    memcpy(rot, r0, sizeof r0);
    if (k == 0) return;
    rotation(c->axis[1], q[1], r1);
    mul(r0, r1, rot);
    for (int i = 0; i < 3; i++)
        p[i] +=
            r0[3 * i] * c->loc[1][0] + r0[3 * i + 1] * c->loc[1][1] + r0[3 * i + 2] * c->loc[1][2];
}

static void check_run(const char *text, const chain2 *c, ctc_form form, const char *what)
{
    job_error err;
    job *j = parse(text, &err);
    cr_assert_not_null(j, "%s: %s: %s", what, err.field, err.message);
    ctc_sim_result *r = NULL;
    char msg[256] = "";
    cr_assert_eq(ctc_sim_run(&j->spec, NULL, &r, msg, sizeof msg), CTC_OK, "%s", msg);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
    cr_assert_eq(r->metrics.form, form, "%s: computed in the expected form", what);
    cr_assert_not_null(r->ch[CTC_CH_POSE], "%s: the channel is recorded by default", what);
    cr_assert_eq(r->width[CTC_CH_POSE], 14, "two bodies, 7 values each");
    double dx = 0, dr = 0, dn = 0, wmin = 1;
    const int order[2] = {1, 0}; /* as listed in output.body_pose */
    for (int s = 0; s < r->nsamples; s++) {
        const double *q = r->ch[CTC_CH_Q] + 2 * s;
        for (int b = 0; b < 2; b++) {
            const double *pose = r->ch[CTC_CH_POSE] + 14 * s + 7 * b;
            double p[3], rot[9], rq[9];
            forward(c, q, order[b], p, rot);
            quat_matrix(pose + 3, rq);
            for (int i = 0; i < 3; i++) dx = fmax(dx, fabs(pose[i] - p[i]));
            for (int i = 0; i < 9; i++) dr = fmax(dr, fabs(rq[i] - rot[i]));
            double n2 = 0;
            for (int i = 3; i < 7; i++) n2 += pose[i] * pose[i];
            dn = fmax(dn, fabs(n2 - 1));
            wmin = fmin(wmin, pose[3]);
        }
    }
    cr_expect_leq(dx, 1e-12, "%s: |x - forward kinematics| = %.3e m", what, dx);
    cr_expect_leq(dr, 1e-12, "%s: |R(quaternion) - forward kinematics| = %.3e", what, dr);
    cr_expect_leq(dn, 1e-14, "%s: | |quaternion|^2 - 1 | = %.3e", what, dn);
    cr_expect_geq(wmin, 0, "%s: the scalar part is never negative", what);
    cr_log_info("%s: position %.3e m, rotation %.3e", what, dx, dr);
    ctc_sim_result_free(r);
    job_free(j);
}

Test(body_pose, planar_chain_matches_forward_kinematics)
{
    const chain2 c = {.axis = {{0, 0, 1}, {0, 0, -1}}, .loc = {{0.1, 0, 0.1}, {0, -1, 0.2}}};
    check_run("{'scene':{'gravity':[0,-9.81,0],'q0':[2.9,-0.4],'v0':[3,-2],'bodies':["
              "{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],"
              "'joint':{'type':'revolute','axis':[0,0,1],'location':[0.1,0,0.1]}},"
              "{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],"
              "'joint':{'type':'revolute','axis':[0,0,-1],'location':[0,-1,0.2]}}]},"
              "'controller':{'type':'none'},'duration':2,"
              "'output':{'interval':0.01,'body_pose':[1,0]}}",
              &c, CTC_FORM_PLANAR, "planar");
}

Test(body_pose, spatial_chain_matches_forward_kinematics)
{
    const chain2 c = {.axis = {{0, 0, 1}, {0, 1, 0}}, .loc = {{0, 0, 0}, {1, 0, 0}}};
    check_run("{'scene':{'gravity':[0,0,-9.81],'q0':[3,0],'v0':[1,4],'bodies':["
              "{'mass':1,'com':[0.5,0,0],'inertia':[0.00166667,0.0841667,0.0841667],"
              "'joint':{'type':'revolute','axis':[0,0,1]}},"
              "{'mass':1,'com':[0.5,0,0],'inertia':[0.00166667,0.0841667,0.0841667],"
              "'joint':{'type':'revolute','axis':[0,1,0],'location':[1,0,0]}}]},"
              "'controller':{'type':'none'},'duration':2,"
              "'output':{'interval':0.01,'body_pose':[1,0]}}",
              &c, CTC_FORM_SPATIAL, "spatial");
}

Test(body_pose, quaternion_of_every_branch_of_shepperds_method)
{
    /* rotations by pi - 0.1 about x, y, z and by 0.3 about a skew axis: each branch's largest
       component, checked by the quaternion's own rotation matrix */
    const double axes[4][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {0.48, 0.6, 0.64}};
    const double angles[4] = {PI - 0.1, PI - 0.1, PI - 0.1, 0.3};
    for (int k = 0; k < 4; k++) {
        double rot[9], q[4], rq[9], d = 0;
        rotation(axes[k], angles[k], rot);
        ctc_rotation_quaternion(rot, q);
        quat_matrix(q, rq);
        for (int i = 0; i < 9; i++) d = fmax(d, fabs(rq[i] - rot[i]));
        cr_expect_leq(d, 1e-15, "axis %d: %.3e", k, d);
        cr_expect_geq(q[0], 0, "axis %d: w >= 0", k);
        cr_expect_float_eq(q[0], cos(angles[k] / 2), 1e-15, "axis %d", k);
    }
}

#define POSE_JOB(output)                                                                           \
    "{'scene':{'bodies':[{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],"                      \
    "'joint':{'type':'revolute','axis':[0,0,1]}}]},'controller':{'type':'none'},'duration':1,"     \
    "'output':" output "}"

Test(body_pose, bad_lists_and_a_channel_without_one_are_refused_naming_the_field)
{
    static const struct {
        const char *text, *field, *message;
    } bad[] = {
        {POSE_JOB("{'body_pose':[1]}"), "output.body_pose[0]",
         "must be a body index, a whole number from 0 to 0 (got 1)"},
        {POSE_JOB("{'body_pose':[0,0]}"), "output.body_pose",
         "must be an array of 1 to 1 body indices (got 2 entries)"},
        {POSE_JOB("{'body_pose':0}"), "output.body_pose",
         "must be an array of 1 to 1 body indices (got a number)"},
        {POSE_JOB("{'channels':['q','body_pose']}"), "output.channels[1]",
         "channel \"body_pose\" needs its bodies (\"output.body_pose\")"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        job_error err;
        job *j = parse(bad[i].text, &err);
        cr_expect_null(j, "case %zu accepted", i);
        job_free(j);
        if (j) continue;
        cr_expect_str_eq(err.field, bad[i].field, "case %zu", i);
        cr_expect_str_eq(err.message, bad[i].message, "case %zu", i);
    }
    job_error err;
    job *j = parse(POSE_JOB("{'body_pose':[0]}"), &err);
    cr_assert_not_null(j, "%s: %s", err.field, err.message);
    char msg[256];
    const int bodies[1] = {2};
    j->spec.pose_bodies = bodies;
    cr_expect_eq(ctc_sim_check(&j->spec, msg, sizeof msg), CTC_EINVAL);
    cr_expect_str_eq(msg, "body_pose body 2 out of range (the chain has 1 bodies)");
    job_free(j);
}
