/*
 * test_end_effector.c - the end_effector channel (sim.h CTC_CH_EE, kinematics.h
 * ctc_kinematics_point, job format output.end_effector): the world position and velocity of a
 * point on a body, through the job format and a run.
 *
 * Oracles: forward kinematics of a two-joint chain (tests/support/frames.c) from its joint axes and
 * locations (Rodrigues' rotations composed from the ground, x = p_k + R_k point), evaluated at
 * each recorded q; and the velocity as the central difference of that forward kinematics along
 * the recorded qdot, (x(q + h qdot) - x(q - h qdot)) / 2h with h = 1e-6 s. Both a planar chain
 * (computed in the plane's form: the axis of joint 1 along -z and joint locations and the point
 * off the plane test the conversion to world coordinates) and a spatial one.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frames.h"
#include "job_json.h"
#include "sim.h"
#include "job_fixture.h"

/* a chain of two revolute joints (body 1 on body 0) and a point in body 1's frame (m) */
typedef struct chain2 {
    test_chain2 joints;
    double point[3];
} chain2;

/* x = p_1 + R_1 point */
static void forward(const chain2 *c, const double q[2], double x[3])
{
    double p[3], rot[9], u[3];
    test_chain2_pose(&c->joints, q, 1, p, rot);
    test_m3_mulv(u, rot, c->point);
    for (int i = 0; i < 3; i++) x[i] = p[i] + u[i];
}

/* the channel against the oracles over every sample of the run of job text, whose model has the
   given form */
static void check_run(const char *text, const chain2 *c, ctc_form form, const char *what)
{
    job *j;
    ctc_sim_result *r = fixture_run_text(text, what, &j);
    cr_assert_eq(r->metrics.form, form, "%s: computed in the expected form", what);
    cr_assert_not_null(r->ch[CTC_CH_EE], "%s: the channel is recorded by default", what);
    cr_assert_eq(r->width[CTC_CH_EE], 6);
    double dx = 0, dv = 0, h = 1e-6, vmax = 0;
    for (int k = 0; k < r->nsamples; k++) {
        const double *q = r->ch[CTC_CH_Q] + 2 * k, *v = r->ch[CTC_CH_QD] + 2 * k;
        const double *ee = r->ch[CTC_CH_EE] + 6 * k;
        double x[3], qp[2] = {q[0] + h * v[0], q[1] + h * v[1]};
        double qm[2] = {q[0] - h * v[0], q[1] - h * v[1]}, xp[3], xm[3];
        forward(c, q, x);
        forward(c, qp, xp);
        forward(c, qm, xm);
        for (int i = 0; i < 3; i++) {
            dx = fmax(dx, fabs(ee[i] - x[i]));
            dv = fmax(dv, fabs(ee[3 + i] - (xp[i] - xm[i]) / (2 * h)));
            vmax = fmax(vmax, fabs(ee[3 + i]));
        }
    }
    cr_expect_leq(dx, 1e-12, "%s: |x - forward kinematics| = %.3e", what, dx);
    cr_expect_leq(dv, 1e-8, "%s: |xd - central difference| = %.3e", what, dv);
    cr_expect_gt(vmax, 0.5, "%s: the point moves", what);
    cr_log_info("%s: position %.3e m, velocity %.3e m/s", what, dx, dv);
    ctc_sim_result_free(r);
    job_free(j);
}

Test(end_effector, planar_chain_matches_forward_kinematics_and_finite_differences)
{
    const chain2 c = {
        .joints = {.axis = {{0, 0, 1}, {0, 0, -1}}, .loc = {{0.1, 0, 0.1}, {0, -1, 0.2}}},
        .point = {0.1, -1, 0.3}};
    check_run("{'scene':{'gravity':[0,-9.81,0],'q0':[0.7,-0.4],'v0':[1,-2],'bodies':["
              "{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],"
              "'joint':{'type':'revolute','axis':[0,0,1],'location':[0.1,0,0.1]}},"
              "{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],"
              "'joint':{'type':'revolute','axis':[0,0,-1],'location':[0,-1,0.2]}}]},"
              "'controller':{'type':'none'},'duration':1,"
              "'output':{'interval':0.01,'end_effector':{'body':1,'point':[0.1,-1,0.3]}}}",
              &c, CTC_FORM_PLANAR, "planar");
}

Test(end_effector, spatial_chain_matches_forward_kinematics_and_finite_differences)
{
    const chain2 c = {.joints = {.axis = {{0, 0, 1}, {0, 1, 0}}, .loc = {{0, 0, 0}, {1, 0, 0}}},
                      .point = {1, 0.1, 0.05}};
    check_run("{'scene':{'gravity':[0,0,-9.81],'q0':[1.5707963267948966,0],'v0':[1,1],'bodies':["
              "{'mass':1,'com':[0.5,0,0],'inertia':[0.00166667,0.0841667,0.0841667],"
              "'joint':{'type':'revolute','axis':[0,0,1]}},"
              "{'mass':1,'com':[0.5,0,0],'inertia':[0.00166667,0.0841667,0.0841667],"
              "'joint':{'type':'revolute','axis':[0,1,0],'location':[1,0,0]}}]},"
              "'controller':{'type':'pd','kp':100,'kv':20},"
              "'trajectory':{'type':'sine','amplitude':1,'period':1.5},'duration':1,"
              "'output':{'interval':0.01,'end_effector':{'body':1,'point':[1,0.1,0.05]}}}",
              &c, CTC_FORM_SPATIAL, "spatial");
}

#define EE_JOB(output)                                                                             \
    "{'scene':{'bodies':[{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],"                      \
    "'joint':{'type':'revolute','axis':[0,0,1]}}]},'controller':{'type':'none'},'duration':1,"     \
    "'output':" output "}"

Test(end_effector, bad_points_and_a_channel_without_one_are_refused_naming_the_field)
{
    static const fixture_bad_job bad[] = {
        {EE_JOB("{'end_effector':{'body':1}}"), "output.end_effector.body",
         "must be a body index, a whole number from 0 to 0 (got 1)"},
        {EE_JOB("{'end_effector':{'body':0,'point':[0,1]}}"), "output.end_effector.point",
         "must be an array of 3 numbers (got 2 entries)"},
        {EE_JOB("{'end_effector':{'point':[0,1,0]}}"), "output.end_effector.body", "is required"},
        {EE_JOB("{'channels':['q','end_effector']}"), "output.channels[1]",
         "channel \"end_effector\" needs its point (\"output.end_effector\")"},
    };
    fixture_expect_refused(bad, sizeof bad / sizeof bad[0]);
    /* the library refuses what the format would not give it */
    job_error err;
    job *j = fixture_parse(EE_JOB("{'end_effector':{'body':0}}"), &err);
    cr_assert_not_null(j, "%s: %s", err.field, err.message);
    char msg[256];
    ctc_end_effector ee = {.body = 3};
    j->spec.end_effector = &ee;
    cr_expect_eq(ctc_sim_check(&j->spec, msg, sizeof msg), CTC_EINVAL);
    cr_expect_str_eq(msg, "end effector body 3 out of range (the chain has 1 bodies)");
    job_free(j);
}
