/*
 * test_body_pose.c - the body_pose channel (sim.h CTC_CH_POSE, kinematics.h
 * ctc_kinematics_body_rotation and ctc_rotation_quaternion, job format output.body_pose): the
 * world position of a body's frame origin and its orientation as a unit quaternion, through the
 * job format and a run.
 *
 * Oracle (tests/support/frames.c): forward kinematics of a two-joint chain from its joint axes and
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

#include "frames.h"
#include "job_json.h"
#include "kinematics.h"
#include "sim.h"
#include "job_fixture.h"

#define PI 3.14159265358979323846

static void check_run(const char *text, const test_chain2 *c, ctc_form form, const char *what)
{
    job *j;
    ctc_sim_result *r = fixture_run_text(text, what, &j);
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
            test_chain2_pose(c, q, order[b], p, rot);
            test_m3_quat_raw(rq, pose + 3);
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
    const test_chain2 c = {.axis = {{0, 0, 1}, {0, 0, -1}}, .loc = {{0.1, 0, 0.1}, {0, -1, 0.2}}};
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
    const test_chain2 c = {.axis = {{0, 0, 1}, {0, 1, 0}}, .loc = {{0, 0, 0}, {1, 0, 0}}};
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
        test_m3_rot(rot, axes[k], angles[k]);
        ctc_rotation_quaternion(rot, q);
        test_m3_quat_raw(rq, q);
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
    static const fixture_bad_job bad[] = {
        {POSE_JOB("{'body_pose':[1]}"), "output.body_pose[0]",
         "must be a body index, a whole number from 0 to 0 (got 1)"},
        {POSE_JOB("{'body_pose':[0,0]}"), "output.body_pose",
         "must be an array of 1 to 1 body indices (got 2 entries)"},
        {POSE_JOB("{'body_pose':0}"), "output.body_pose",
         "must be an array of 1 to 1 body indices (got a number)"},
        {POSE_JOB("{'channels':['q','body_pose']}"), "output.channels[1]",
         "channel \"body_pose\" needs its bodies (\"output.body_pose\")"},
    };
    fixture_expect_refused(bad, sizeof bad / sizeof bad[0]);
    job_error err;
    job *j = fixture_parse(POSE_JOB("{'body_pose':[0]}"), &err);
    cr_assert_not_null(j, "%s: %s", err.field, err.message);
    char msg[256];
    const int bodies[1] = {2};
    j->spec.pose_bodies = bodies;
    cr_expect_eq(ctc_sim_check(&j->spec, msg, sizeof msg), CTC_EINVAL);
    cr_expect_str_eq(msg, "body_pose body 2 out of range (the chain has 1 bodies)");
    job_free(j);
}
