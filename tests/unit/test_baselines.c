/*
 * test_baselines.c - the controllers computed torque control is compared with (ctrl.h
 * ctc_ctrl_force: ctrl_joint_pd.c, ctrl_pd_gravity.c, ctrl_feedforward.c), run by sim.h,
 * against what each must do by construction and against closed forms written here:
 *   PD with gravity compensation holds a pose at rest exactly (f is the gravity load there);
 *   the feedforward started on the desired motion stays on it (f is the motion's forces);
 *   independent joint PD on a rod is the damped oscillator I e'' + kv e' + kp e = 0 without
 *   gravity, and rests where kp (q_d - q) = m g (l/2) sin q with it.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "chains.h"
#include "sim.h"
#include "run_fixture.h"

#define G 9.81
#define MAXN 4

typedef struct bscene {
    test_chain *chain;
    double q0[MAXN], v0[MAXN];
    ctc_gains gains[MAXN];
    ctc_traj traj[MAXN];
    ctc_sim_spec spec;
} bscene;

/* n rods of 1 m, 1 kg, each coordinate held at q_d[i] (or tracking a sine when period > 0) */
static bscene *bscene_new(int n, ctc_ctrl_type type, double kp, double kv)
{
    bscene *s = calloc(1, sizeof *s);
    cr_assert(s && n <= MAXN);
    s->chain = test_chain_rod_pendulum(n, 1, 1);
    for (int i = 0; i < n; i++) s->gains[i] = (ctc_gains){.kp = kp, .kv = kv};
    s->spec =
        (ctc_sim_spec){.chain = s->chain->spec,
                       .q0 = s->q0,
                       .v0 = s->v0,
                       .controller = type,
                       .gains = s->gains,
                       .model_mass_scale = 1,
                       .model_inertia_scale = 1,
                       .traj = s->traj,
                       .integrator = {.method = CTC_INTEG_DOPRI5, .rtol = 1e-11, .atol = 1e-13},
                       .duration = 5,
                       .output_interval = 0.01};
    return s;
}

static ctc_sim_result *brun(bscene *s)
{
    s->spec.chain = s->chain->spec;
    ctc_sim_result *r = fixture_run_done(&s->spec);
    return r;
}

static double max_abs_e(const ctc_sim_result *r)
{
    double m = 0;
    for (int i = 0; i < r->nind; i++) m = fmax(m, r->metrics.e_max[i]);
    return m;
}

Test(baselines, pd_with_gravity_compensation_holds_a_pose_exactly)
{
    bscene *s = bscene_new(3, CTC_CTRL_PD_GRAVITY, 100, 20);
    const double pose[3] = {0.7, -0.4, 1.1};
    for (int i = 0; i < 3; i++) {
        s->q0[i] = pose[i];
        s->traj[i] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = pose[i]};
    }
    ctc_sim_result *r = brun(s);
    cr_expect_leq(max_abs_e(r), 1e-12, "max |e| %g from rest at the pose", max_abs_e(r));
    /* the actuators carry the gravity load: the tip joint's is m g (l/2) sin(q1 + q2 + q3) */
    double tip = G * 0.5 * sin(pose[0] + pose[1] + pose[2]);
    cr_expect_leq(fabs(r->ch[CTC_CH_TAU][2] - tip), 1e-12, "tau[2] %.15g, m g l/2 sin %.15g",
                  r->ch[CTC_CH_TAU][2], tip);
    ctc_sim_result_free(r);

    /* and it regulates to the pose from elsewhere (Takegaki and Arimoto) */
    s->q0[0] = 0, s->q0[1] = 0, s->q0[2] = 0;
    s->spec.duration = 20;
    r = brun(s);
    for (int i = 0; i < 3; i++)
        cr_expect_leq(fabs(r->metrics.e_final[i]), 1e-6, "joint %d: e %g after 20 s", i,
                      r->metrics.e_final[i]);
    ctc_sim_result_free(r);
    test_chain_free(s->chain);
    free(s);
}

Test(baselines, feedforward_started_on_the_trajectory_stays_on_it)
{
    bscene *s = bscene_new(3, CTC_CTRL_FEEDFORWARD, 100, 20);
    for (int i = 0; i < 3; i++) {
        s->traj[i] = (ctc_traj){
            .type = i == 1 ? CTC_TRAJ_COSINE : CTC_TRAJ_SINE, .amplitude = 0.6, .period = 1.5};
        double d[3];
        ctc_traj_eval(&s->traj[i], 0, d);
        s->q0[i] = d[0], s->v0[i] = d[1];
    }
    ctc_sim_result *r = brun(s);
    cr_expect_leq(max_abs_e(r), 1e-8, "exact model: max |e| %g", max_abs_e(r));
    ctc_sim_result_free(r);
    /* a model 20 % heavier than the plant leaves the trajectory */
    s->spec.model_mass_scale = 1.2;
    r = brun(s);
    cr_expect_gt(max_abs_e(r), 1e-3, "wrong model: max |e| %g", max_abs_e(r));
    ctc_sim_result_free(r);
    test_chain_free(s->chain);
    free(s);
}

Test(baselines, joint_pd_on_a_rod_is_the_damped_oscillator)
{
    const double ip = 1.0 / 3, kp = 3, kv = 0.4, e0 = 0.8;
    bscene *s = bscene_new(1, CTC_CTRL_JOINT_PD, kp, kv);
    s->chain->spec.gravity[1] = 0;
    s->traj[0] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = e0};
    ctc_sim_result *r = brun(s);
    const double sigma = kv / (2 * ip), wd = sqrt(kp / ip - sigma * sigma);
    double dev = 0;
    for (int j = 0; j < r->nsamples; j++) {
        double t = r->t[j];
        double e = exp(-sigma * t) * (e0 * cos(wd * t) + sigma * e0 / wd * sin(wd * t));
        dev = fmax(dev, fabs(r->ch[CTC_CH_E][j] - e));
    }
    cr_expect_leq(dev, 1e-8, "|e - closed form| = %g", dev);
    ctc_sim_result_free(r);
    test_chain_free(s->chain);
    free(s);
}

Test(baselines, joint_pd_under_gravity_rests_at_its_static_offset)
{
    const double kp = 20, kv = 5, qd = 0.5, mgl2 = G * 0.5;
    bscene *s = bscene_new(1, CTC_CTRL_JOINT_PD, kp, kv);
    s->traj[0] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = qd};
    s->spec.duration = 30;
    ctc_sim_result *r = brun(s);
    /* kp (qd - q) = m g (l/2) sin q, by bisection on [0, qd] */
    double lo = 0, hi = qd;
    for (int k = 0; k < 200; k++) {
        double mid = 0.5 * (lo + hi);
        if (kp * (qd - mid) - mgl2 * sin(mid) > 0)
            lo = mid;
        else
            hi = mid;
    }
    double q = r->ch[CTC_CH_Q][r->nsamples - 1];
    cr_expect_leq(fabs(q - lo), 1e-9, "q %.12f, closed form %.12f", q, lo);
    ctc_sim_result_free(r);
    test_chain_free(s->chain);
    free(s);
}
