/*
 * test_wrench.c - external wrenches on the plant's bodies (wrench.h, job format "wrenches"):
 * their generalised forces, a held pose's steady error, the work of a push, the controller that
 * knows the wrench, and the refusals.
 *
 * Oracles written here: forward kinematics of the planar two-link arm (rods of 1 m hanging at
 * q = 0; body 1's origin at R(q0) (0, -1)), whose central differences give the Jacobian of the
 * point, so tau_j = f_w . dx/dq_j + n_z (j on the path) is the virtual work by a route apart from
 * the library's joint maps. PD with gravity compensation, f = g(q) + kp e + kv de, holds a pose
 * under a constant wrench where kp e = -tau_ext(q) (the plant at rest: g(q) + kp e + tau_ext = g),
 * with q = q_d - e solved here by fixed-point iteration. A passive rod pushed by a sine wrench
 * gains the energy E(T) - E(0) = int_0^T s(t) (f . v_x + n . omega) dt, integrated here by
 * Simpson's rule over the samples of the end_effector channel (the point's velocity).
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "kinematics.h"
#include "sim.h"
#include "job_fixture.h"

#define PI 3.14159265358979323846

/* the arm's point p (body k's frame) in the world at q: o_k + R(theta_k) p */
static void arm_point(const double q[2], int k, const double p[2], double x[2])
{
    double th = q[0] + (k ? q[1] : 0), c = cos(th), s = sin(th);
    x[0] = c * p[0] - s * p[1], x[1] = s * p[0] + c * p[1];
    if (k) x[0] += sin(q[0]), x[1] -= cos(q[0]);
}

/* one wrench of the test: world force and torque n_z at q (a body-frame force turned by
   theta_k) */
typedef struct arm_wrench {
    int body, body_frame;
    double point[2], force[2], torque;
} arm_wrench;

/* tau (2) = sum over the wrenches of f_w . dx/dq_j + n_z [j <= k], by central differences */
static void arm_tau(const arm_wrench *w, int n, const double q[2], double tau[2])
{
    const double h = 1e-6;
    tau[0] = tau[1] = 0;
    for (int i = 0; i < n; i++) {
        double th = q[0] + (w[i].body ? q[1] : 0), f[2] = {w[i].force[0], w[i].force[1]};
        if (w[i].body_frame) {
            f[0] = cos(th) * w[i].force[0] - sin(th) * w[i].force[1];
            f[1] = sin(th) * w[i].force[0] + cos(th) * w[i].force[1];
        }
        for (int j = 0; j < 2; j++) {
            double qp[2] = {q[0], q[1]}, qm[2] = {q[0], q[1]}, xp[2], xm[2];
            qp[j] += h, qm[j] -= h;
            arm_point(qp, w[i].body, w[i].point, xp);
            arm_point(qm, w[i].body, w[i].point, xm);
            tau[j] += f[0] * (xp[0] - xm[0]) / (2 * h) + f[1] * (xp[1] - xm[1]) / (2 * h);
            if (j <= w[i].body) tau[j] += w[i].torque;
        }
    }
}

static const arm_wrench held_wrenches[2] = {
    {.body = 1, .point = {0.2, -0.7}, .force = {3, -2}},
    {.body = 0, .body_frame = 1, .point = {0, -0.5}, .force = {1.5, 0}, .torque = 0.8},
};
#define HELD_WRENCHES                                                                              \
    "'wrenches':[{'body':1,'point':[0.2,-0.7,0],'force':[3,-2,0]},"                                \
    "{'body':0,'point':[0,-0.5,0],'force':[1.5,0,0],'torque':[0,0,0.8],'frame':'body'}]"

Test(wrench, generalised_forces_match_the_virtual_work_of_the_arm)
{
    job *j = fixture_parse_ok("{'scene':{'gravity':[0,-9.81,0],'bodies':[" FIXTURE_ROD
                              "," FIXTURE_ROD2 "]},"
                              "'controller':{'type':'none'},'duration':1," HELD_WRENCHES "}");
    ctc_model *m = NULL;
    char err[256];
    cr_assert_eq(ctc_model_build(&j->spec.chain, &m, err, sizeof err), CTC_OK, "%s", err);
    ctc_data *d = ctc_data_new(m);
    cr_assert_not_null(d);
    double dev = 0;
    const double qs[3][2] = {{0.4, -0.3}, {2.5, 1.1}, {-1.3, 3.0}}, v[2] = {0.7, -0.2};
    for (int s = 0; s < 3; s++) {
        double f[2] = {0, 0}, tau[2];
        ctc_kinematics(m, d, qs[s], v);
        for (int k = 0; k < j->spec.nwrenches; k++)
            ctc_wrench_forces(m, d, &j->spec.wrenches[k], 0.5, f);
        arm_tau(held_wrenches, 2, qs[s], tau);
        for (int i = 0; i < 2; i++) dev = fmax(dev, fabs(f[i] - tau[i]));
    }
    cr_expect_leq(dev, 1e-9, "|J^T W - virtual work| = %.3e N m", dev);
    cr_log_info("|J^T W - virtual work| = %.3e N m", dev);
    ctc_data_free(d);
    ctc_model_free(m);
    job_free(j);
}

Test(wrench, held_pose_settles_at_the_closed_form_steady_error_of_pd)
{
    const double qd[2] = {0.4, -0.3}, kp = 100;
    job *j =
        fixture_parse_ok("{'scene':{'gravity':[0,-9.81,0],'q0':[0.4,-0.3],'bodies':[" FIXTURE_ROD
                         "," FIXTURE_ROD2 "]},'controller':{'type':'pd_gravity','kp':100,'kv':20},"
                         "'trajectory':[{'type':'constant','value':0.4},{'type':'constant','value':"
                         "-0.3}],'duration':20," HELD_WRENCHES "," FIXTURE_INTEG "}");
    ctc_sim_result *r = fixture_run_done(&j->spec);
    /* kp (q_d - q) = -tau_ext(q): q = q_d + tau_ext(q) / kp, a contraction for kp this large */
    double q[2] = {qd[0], qd[1]}, tau[2];
    for (int it = 0; it < 200; it++) {
        arm_tau(held_wrenches, 2, q, tau);
        q[0] = qd[0] + tau[0] / kp, q[1] = qd[1] + tau[1] / kp;
    }
    for (int i = 0; i < 2; i++) {
        cr_expect_leq(fabs(r->metrics.e_final[i] - (qd[i] - q[i])), 1e-9,
                      "joint %d: e = %.12g, closed form %.12g", i, r->metrics.e_final[i],
                      qd[i] - q[i]);
        cr_expect_gt(fabs(qd[i] - q[i]), 0.005, "joint %d: the wrench moves the pose", i);
        cr_log_info("joint %d: e = %.12g, closed form %.12g", i, r->metrics.e_final[i],
                    qd[i] - q[i]);
    }
    cr_expect(isnan(r->metrics.errdyn_dev), "an unknown wrench has no linear error law");
    ctc_sim_result_free(r);
    job_free(j);
}

Test(wrench, a_known_wrench_leaves_the_linear_error_law_of_ctc)
{
    job *j = fixture_parse_ok(
        "{'scene':{'gravity':[0,-9.81,0],'bodies':[" FIXTURE_ROD "," FIXTURE_ROD2 "]},"
        "'controller':{'type':'pd','kp':100,'kv':20},"
        "'trajectory':{'type':'sine','amplitude':0.6,'period':1.5},'duration':3,"
        "'wrenches':[{'body':1,'point':[0.2,-0.7,0],'force':[3,-2,0],'profile':"
        "'sine','period':0.4,'known':true},{'body':0,'point':[0,-0.5,0],'torque':"
        "[0,0,0.8],'frame':'body','profile':'step','time':1.25,'known':true}],"
        "'output':{'interval':0.01}," FIXTURE_INTEG "}");
    ctc_sim_result *r = fixture_run_done(&j->spec);
    cr_assert(isfinite(r->metrics.errdyn_dev), "tracked: every wrench is known");
    cr_expect_leq(r->metrics.errdyn_dev, 1e-8, "deviation from the linear law %.3e",
                  r->metrics.errdyn_dev);
    cr_log_info("known wrenches: deviation from the linear law %.3e", r->metrics.errdyn_dev);
    ctc_sim_result_free(r);
    j->wrenches[0].known = j->wrenches[1].known = 0;
    r = fixture_run_done(&j->spec);
    cr_expect_gt(r->metrics.e_max[1], 0.01, "unknown, the same wrenches push the arm off");
    cr_log_info("unknown wrenches: max |e| %.3g, %.3g rad", r->metrics.e_max[0],
                r->metrics.e_max[1]);
    ctc_sim_result_free(r);
    job_free(j);
}

Test(wrench, sine_push_on_a_passive_rod_does_the_work_the_energy_gains)
{
    const double period = 0.7, phase = 0.3, f[2] = {2, 0.5}, n = 0.4, dt = 1e-3;
    job *j = fixture_parse_ok(
        "{'scene':{'gravity':[0,-9.81,0],'q0':[0.5],'bodies':[" FIXTURE_ROD "]},"
        "'controller':{'type':'none'},'duration':2,"
        "'wrenches':[{'body':0,'point':[0,-1,0],'force':[2,0.5,0],'torque':[0,0,0.4],"
        "'profile':'sine','period':0.7,'phase':0.3}],"
        "'output':{'interval':0.001,'end_effector':{'body':0,'point':[0,-1,0]}},"
        "'integrator':{'method':'dopri5','rtol':1e-12,'atol':1e-14}}");
    ctc_sim_result *r = fixture_run_done(&j->spec);
    cr_assert_eq(r->nsamples, 2001);
    double work = 0;
    for (int s = 0; s < r->nsamples; s++) {
        const double t = r->t[s], *ee = r->ch[CTC_CH_EE] + 6 * s;
        const double p = sin(2 * PI * t / period + phase) *
                         (f[0] * ee[3] + f[1] * ee[4] + n * r->ch[CTC_CH_QD][s]);
        const double wgt = s == 0 || s == r->nsamples - 1 ? 1 : s % 2 ? 4 : 2;
        work += wgt * p * dt / 3;
    }
    const double *e0 = r->ch[CTC_CH_ENERGY], *e1 = e0 + 2 * (r->nsamples - 1);
    const double gain = e1[0] + e1[1] - e0[0] - e0[1];
    cr_expect_leq(fabs(gain - work), 1e-9, "energy gained %.12g J, work done %.12g J", gain, work);
    cr_expect_gt(fabs(work), 0.05, "the push does work");
    cr_log_info("energy gained %.12g J, work done %.12g J", gain, work);
    cr_expect(isnan(r->metrics.energy_drift), "a pushed rod does not conserve energy");
    ctc_sim_result_free(r);
    job_free(j);
}

Test(wrench, profiles_follow_their_formulas)
{
    ctc_wrench w = {.profile = CTC_WRENCH_CONSTANT};
    cr_expect_eq(ctc_wrench_scale(&w, 3.7), 1);
    w = (ctc_wrench){.profile = CTC_WRENCH_STEP, .time = 0.5};
    cr_expect_eq(ctc_wrench_scale(&w, 0.4999), 0);
    cr_expect_eq(ctc_wrench_scale(&w, 0.5), 1, "on from its time");
    w = (ctc_wrench){.profile = CTC_WRENCH_SINE, .period = 0.8, .phase = 0.2};
    cr_expect_float_eq(ctc_wrench_scale(&w, 1.9), sin(2 * PI * 1.9 / 0.8 + 0.2), 1e-14);
}

#define W_JOB(ctrl, wrenches)                                                                      \
    "{'scene':{'bodies':[" FIXTURE_ROD "]},'controller':" ctrl                                     \
    ",'duration':1,'wrenches':" wrenches "}"

Test(wrench, bad_wrenches_are_refused_naming_the_field)
{
    static const fixture_bad_job bad[] = {
        {W_JOB("{'type':'none'}", "[{'body':1}]"), "wrenches[0].body",
         "must be a body index, a whole number from 0 to 0 (got 1)"},
        {W_JOB("{'type':'none'}", "[{'force':[1,0,0]}]"), "wrenches[0].body", "is required"},
        {W_JOB("{'type':'none'}", "[{'body':0,'profile':'sine'}]"), "wrenches[0].period",
         "is required"},
        {W_JOB("{'type':'none'}", "[{'body':0,'profile':'sine','period':-1}]"),
         "wrenches[0].period", "must be positive (got -1 s)"},
        {W_JOB("{'type':'none'}", "[{'body':0,'profile':'step','time':-0.5}]"), "wrenches[0].time",
         "must be non-negative (got -0.5 s)"},
        {W_JOB("{'type':'none'}", "[{'body':0,'time':0.5}]"), "wrenches[0].time",
         "applies only to the profile \"step\""},
        {W_JOB("{'type':'none'}", "[{'body':0,'known':true}]"), "wrenches[0].known",
         "needs a controller: the controller compensates a known wrench (this run is passive)"},
        {W_JOB("{'type':'none'}", "[{'body':0,'force':[1,0]}]"), "wrenches[0].force",
         "must be an array of 3 numbers (got 2 entries)"},
        {W_JOB("{'type':'none'}", "{'body':0}"), "wrenches",
         "must be an array of wrench objects (got an object)"},
        {"{'preset':'five_bar_pd','wrenches':[{'body':0}]}", "wrenches",
         "needs an open chain or tree (the scene has a loop)"},
    };
    fixture_expect_refused(bad, sizeof bad / sizeof bad[0]);
    /* the library refuses what the format would not give it */
    job_error err;
    job *j = fixture_parse(W_JOB("{'type':'none'}", "[{'body':0}]"), &err);
    cr_assert_not_null(j, "%s: %s", err.field, err.message);
    char msg[256];
    j->wrenches[0].body = 4;
    cr_expect_eq(ctc_sim_check(&j->spec, msg, sizeof msg), CTC_EINVAL);
    cr_expect_str_eq(msg, "wrench 0: body 4 out of range (the chain has 1 bodies)");
    job_free(j);
}
