/*
 * test_sim.c - CTC runs against closed forms, steady-state theory and conservation laws (sim.h).
 *
 * The oracles are written here, apart from the code under test: the closed-form solution of
 * e'' + kv e' + kp e = 0, the steady-state offset e_ss = -M(q)^-1 z / kp with M from the
 * independent mass-matrix oracle, the kinetic energy 1/2 v^T M v, and RK4's order of
 * convergence against a tight reference run.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "linalg.h"
#include "loop_oracle.h"
#include "oracle.h"
#include "shapes.h"
#include "sim.h"
#include "run_fixture.h"

#define PI 3.14159265358979323846
#define MAXV 64

typedef struct scene {
    test_chain *chain;
    int nv;
    double q0[MAXV], v0[MAXV];
    ctc_gains gains[MAXV];
    ctc_traj traj[MAXV];
    ctc_disturb dist[MAXV];
    ctc_sim_spec spec;
} scene;

static scene *scene_new(test_chain *chain, int nv)
{
    scene *s = calloc(1, sizeof *s);
    cr_assert(s && nv <= MAXV);
    s->chain = chain;
    s->nv = nv;
    s->spec.chain = chain->spec;
    s->spec.q0 = s->q0;
    s->spec.v0 = s->v0;
    s->spec.gains = s->gains;
    s->spec.traj = s->traj;
    s->spec.model_mass_scale = 1;
    s->spec.model_inertia_scale = 1;
    s->spec.integrator = (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-10, .atol = 1e-12};
    s->spec.duration = 5;
    s->spec.output_interval = 0.01;
    return s;
}

static void scene_free(scene *s)
{
    test_chain_free(s->chain);
    free(s);
}

static void set_pd(scene *s, double kp, double kv, double ki)
{
    s->spec.controller = ki > 0 ? CTC_CTRL_PID : CTC_CTRL_PD;
    for (int i = 0; i < s->nv; i++) s->gains[i] = (ctc_gains){.ki = ki, .kp = kp, .kv = kv};
}

static void set_disturbance(scene *s, double z)
{
    for (int i = 0; i < s->nv; i++)
        s->dist[i] = (ctc_disturb){.type = CTC_DISTURB_CONSTANT, .value = z};
    s->spec.disturb = s->dist;
}

/* the paper's planar triple pendulum (section 7.1): rods 1 m, 1 kg; sinusoidal trajectory */
static scene *triple_pendulum(void)
{
    scene *s = scene_new(test_chain_rod_pendulum(3, 1, 1), 3);
    s->q0[0] = 5 * PI / 6, s->q0[1] = 3 * PI / 4, s->q0[2] = 2 * PI / 3;
    for (int i = 0; i < 3; i++)
        s->traj[i] = (ctc_traj){
            .type = i == 1 ? CTC_TRAJ_COSINE : CTC_TRAJ_SINE, .amplitude = 0.6, .period = 1.5};
    return s;
}

/* the paper's spatial double pendulum (section 7.1): cuboids 1 x 0.1 x 0.1 m, 1 kg, J1 about the
 * world z axis, J2 about body 1's y axis at its far end; gravity -z */
static scene *spatial_double_pendulum(void)
{
    test_chain *c = calloc(1, sizeof *c);
    cr_assert(c);
    c->bodies = calloc(2, sizeof *c->bodies);
    c->joints = calloc(2, sizeof *c->joints);
    const double size[3] = {1, 0.1, 0.1}, centre[3] = {0.5, 0, 0};
    for (int k = 0; k < 2; k++)
        cr_assert_eq(ctc_shape_box(1, size, centre, &c->bodies[k], NULL, 0), CTC_OK);
    c->joints[0] = (ctc_joint_spec){.type = CTC_JOINT_REVOLUTE, .axis = {0, 0, 1}};
    c->joints[1] =
        (ctc_joint_spec){.type = CTC_JOINT_REVOLUTE, .axis = {0, 1, 0}, .location = {1, 0, 0}};
    c->spec = (ctc_chain_spec){
        .nbodies = 2, .bodies = c->bodies, .joints = c->joints, .gravity = {0, 0, -9.81}};
    scene *s = scene_new(c, 2);
    s->q0[0] = PI / 2, s->v0[0] = 1, s->v0[1] = 1;
    s->traj[0] = (ctc_traj){.type = CTC_TRAJ_SINE, .amplitude = 1, .period = 1.5};
    s->traj[1] = (ctc_traj){.type = CTC_TRAJ_COSINE, .amplitude = 1, .period = 1.5};
    return s;
}

/* the paper's N-link pendulum (section 7.3): q0_k = (-1)^k pi/6, q_d = 0 */
static scene *n_link_pendulum(int n)
{
    scene *s = scene_new(test_chain_rod_pendulum(n, 1, 1), n);
    for (int k = 0; k < n; k++) {
        s->q0[k] = ((k + 1) % 2 ? -1 : 1) * PI / 6;
        s->traj[k] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = 0};
    }
    return s;
}

static ctc_sim_result *run(const scene *s)
{
    ctc_sim_result *r = NULL;
    char err[256] = "";
    ctc_status st = ctc_sim_run(&s->spec, NULL, &r, err, sizeof err);
    cr_assert_eq(st, CTC_OK, "ctc_sim_run: %s", err);
    return r;
}

/* closed-form solution of e'' + kv e' + kp e = 0 from e(0) = e0, e'(0) = de0 */
static double pd_error(double kp, double kv, double e0, double de0, double t)
{
    double a = kv / 2, w2 = kp - a * a, b = de0 + a * e0;
    if (fabs(w2) <= 1e-12 * kp) return exp(-a * t) * (e0 + b * t);
    if (w2 > 0) {
        double w = sqrt(w2);
        return exp(-a * t) * (e0 * cos(w * t) + b / w * sin(w * t));
    }
    double g = sqrt(-w2);
    return exp(-a * t) * (e0 * cosh(g * t) + b / g * sinh(g * t));
}

/* max over samples and coordinates of |e - closed form| */
static double pd_deviation(const scene *s, const ctc_sim_result *r)
{
    double dev = 0;
    for (int i = 0; i < s->nv; i++) {
        double d0[3];
        ctc_traj_eval(&s->traj[i], 0, d0);
        double e0 = d0[0] - s->q0[i], de0 = d0[1] - s->v0[i];
        for (int j = 0; j < r->nsamples; j++) {
            double e = r->ch[CTC_CH_E][j * s->nv + i];
            double ref = pd_error(s->gains[i].kp, s->gains[i].kv, e0, de0, r->t[j]);
            dev = fmax(dev, fabs(e - ref));
        }
    }
    return dev;
}

static void check_pd_closed_form(scene *s, double kp, double kv)
{
    set_pd(s, kp, kv, 0);
    ctc_sim_result *r = run(s);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
    double dev = pd_deviation(s, r);
    cr_expect_leq(dev, 1e-6, "n = %d, kp %g kv %g: |e - e_closed_form| = %g", s->nv, kp, kv, dev);
    /* the run's own accuracy figure says the same */
    cr_expect_leq(r->metrics.errdyn_dev, 1e-6, "errdyn_dev %g", r->metrics.errdyn_dev);
    cr_expect_leq(fabs(r->metrics.errdyn_dev - dev), 1e-8);
    ctc_sim_result_free(r);
}

Test(sim, exact_pd_error_follows_closed_form_on_triple_pendulum)
{
    scene *s = triple_pendulum();
    check_pd_closed_form(s, 100, 20); /* the paper's gains: critically damped */
    check_pd_closed_form(s, 100, 6);  /* underdamped */
    check_pd_closed_form(s, 25, 30);  /* overdamped */
    scene_free(s);
}

Test(sim, exact_pd_error_follows_closed_form_on_spatial_double_pendulum)
{
    scene *s = spatial_double_pendulum();
    check_pd_closed_form(s, 100, 20);
    scene_free(s);
}

Test(sim, exact_pd_error_follows_closed_form_on_32_link_chain)
{
    scene *s = n_link_pendulum(32);
    s->spec.duration = 2;
    check_pd_closed_form(s, 100, 20);
    scene_free(s);
}

/* a branched tree under CTC: body 0 carries two double pendulums (the planar "Y": rods, bodies
   1-2 and 3-4 hang from body 0's tip), or Featherstone's autoTree with branching factor 2 and
   skewed axes (spatial, 7 bodies); each joint tracks its own sine */
static scene *tree_scene(int spatial)
{
    test_chain *c;
    if (spatial) {
        c = test_auto_tree(7, 2, 0.4, 0.9);
    } else {
        c = test_chain_rod_pendulum(5, 1, 1);
        const int parent[5] = {-1, 0, 1, 0, 3};
        test_chain_set_parents(c, parent);
    }
    scene *s = scene_new(c, c->spec.nbodies);
    for (int k = 0; k < s->nv; k++) {
        s->q0[k] = (k % 2 ? -1 : 1) * (0.2 + 0.1 * k);
        s->v0[k] = 0.1 * k;
        s->traj[k] = (ctc_traj){.type = k % 2 ? CTC_TRAJ_COSINE : CTC_TRAJ_SINE,
                                .amplitude = 0.5,
                                .period = 1.0 + 0.25 * k};
    }
    s->spec.duration = 2;
    return s;
}

Test(sim, exact_pd_error_follows_closed_form_on_branched_trees)
{
    for (int spatial = 0; spatial < 2; spatial++) {
        scene *s = tree_scene(spatial);
        check_pd_closed_form(s, 100, 20);
        check_pd_closed_form(s, 100, 6);
        scene_free(s);
    }
}

/* hold q_d = q0 against a constant disturbance z for 10 s; returns the final error */
static ctc_sim_result *hold_against_disturbance(scene *s, double ki)
{
    const double hold[3] = {0.3, -0.2, 0.1};
    for (int i = 0; i < 3; i++) {
        s->q0[i] = hold[i];
        s->traj[i] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = hold[i]};
    }
    set_pd(s, 100, 20, ki);
    set_disturbance(s, 0.2);
    s->spec.duration = 10;
    s->spec.output_interval = 0.05;
    ctc_sim_result *r = run(s);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
    return r;
}

Test(sim, pd_settles_at_the_offset_theory_predicts)
{
    scene *s = triple_pendulum();
    ctc_sim_result *r = hold_against_disturbance(s, 0);

    /* e_ss = -M(q_ss)^-1 z / kp with M from the oracle at the final position */
    ctc_model *m = NULL;
    cr_assert_eq(ctc_model_build(&s->spec.chain, &m, NULL, 0), CTC_OK);
    ctc_oracle *o = ctc_oracle_new(m);
    double mass[9], z[3] = {0.2, 0.2, 0.2}, x[3];
    const double *q_ss = r->ch[CTC_CH_Q] + 3 * (r->nsamples - 1);
    ctc_oracle_mass_matrix(m, o, q_ss, mass);
    cr_assert_eq(test_solve_spd(mass, 3, z, x), 0);
    for (int i = 0; i < 3; i++) {
        double expect = -x[i] / 100;
        cr_expect_leq(fabs(r->metrics.e_final[i] - expect), 1e-6,
                      "joint %d: e_ss %.9g, theory %.9g", i, r->metrics.e_final[i], expect);
        cr_expect_gt(fabs(expect), 1e-4); /* the offset is there to see */
    }
    cr_expect(isnan(r->metrics.errdyn_dev)); /* not the exact error dynamics: disturbed */
    ctc_oracle_free(o);
    ctc_model_free(m);
    ctc_sim_result_free(r);
    scene_free(s);
}

Test(sim, pid_settles_at_zero_error_against_constant_disturbance)
{
    scene *s = triple_pendulum();
    ctc_sim_result *r = hold_against_disturbance(s, 250);
    for (int i = 0; i < 3; i++)
        cr_expect_leq(fabs(r->metrics.e_final[i]), 1e-6, "joint %d: e %g", i,
                      r->metrics.e_final[i]);
    ctc_sim_result_free(r);
    scene_free(s);
}

/* the largest |e| over the samples in [t0, end] */
static double max_error_after(const ctc_sim_result *r, double t0)
{
    double e = 0;
    for (int j = 0; j < r->nsamples; j++)
        for (int i = 0; r->t[j] >= t0 && i < r->nv; i++)
            e = fmax(e, fabs(r->ch[CTC_CH_E][j * r->nv + i]));
    return e;
}

Test(sim, pid_tracks_the_papers_sine_far_better_than_pd_under_disturbance)
{
    scene *s = triple_pendulum();
    set_disturbance(s, 0.2);
    s->spec.integrator.rtol = 1e-8;
    set_pd(s, 100, 20, 0);
    ctc_sim_result *pd = run(s);
    set_pd(s, 100, 20, 250);
    ctc_sim_result *pid = run(s);
    double e_pd = max_error_after(pd, 4), e_pid = max_error_after(pid, 4);
    /* PID removes the constant part of M(q)^-1 z; what is left varies with the motion */
    cr_expect_lt(e_pid, 0.25 * e_pd, "last second: PID %g, PD %g", e_pid, e_pd);
    cr_expect_gt(e_pd, 1e-4);
    ctc_sim_result_free(pd);
    ctc_sim_result_free(pid);
    scene_free(s);
}

Test(sim, passive_triple_pendulum_conserves_energy)
{
    scene *s = triple_pendulum();
    s->spec.controller = CTC_CTRL_NONE;
    ctc_sim_result *r = run(s);
    cr_assert_eq(r->status, CTC_RUN_DONE);
    cr_expect_leq(r->metrics.energy_drift, 1e-8, "relative drift %g", r->metrics.energy_drift);
    cr_expect_null(r->ch[CTC_CH_E]); /* tracking channels do not apply */

    /* the recorded kinetic energy is 1/2 v^T M v with M from the oracle */
    ctc_model *m = NULL;
    cr_assert_eq(ctc_model_build(&s->spec.chain, &m, NULL, 0), CTC_OK);
    ctc_oracle *o = ctc_oracle_new(m);
    for (int j = 0; j < r->nsamples; j += 97) {
        double mass[9];
        const double *q = r->ch[CTC_CH_Q] + 3 * j, *v = r->ch[CTC_CH_QD] + 3 * j;
        ctc_oracle_mass_matrix(m, o, q, mass);
        double ke = 0;
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) ke += 0.5 * v[a] * mass[3 * a + b] * v[b];
        cr_expect_leq(fabs(r->ch[CTC_CH_ENERGY][2 * j] - ke), 1e-10 * fmax(1, ke));
    }
    ctc_oracle_free(o);
    ctc_model_free(m);
    ctc_sim_result_free(r);
    scene_free(s);
}

Test(sim, passive_spherical_chain_conserves_energy_and_keeps_unit_quaternions)
{
    unsigned mask = (1u << CTC_JOINT_SPHERICAL) | (1u << CTC_JOINT_REVOLUTE);
    test_chain *c = test_chain_random_spatial(4, 7, mask);
    ctc_model *m = NULL;
    cr_assert_eq(ctc_model_build(&c->spec, &m, NULL, 0), CTC_OK);
    scene *s = scene_new(c, m->nv);
    uint64_t rng = 11;
    test_random_state(m, &rng, 1.0, s->q0, s->v0);
    s->spec.controller = CTC_CTRL_NONE;
    s->spec.duration = 2;
    ctc_sim_result *r = run(s);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
    cr_expect_leq(r->metrics.energy_drift, 1e-8, "relative drift %g", r->metrics.energy_drift);
    for (int k = 0; k < m->nbodies; k++) {
        if (m->joints[k].type != CTC_JOINT_SPHERICAL) continue;
        const double *qk = r->ch[CTC_CH_Q] + (size_t)(r->nsamples - 1) * m->nq + m->jnt_qadr[k];
        double norm = sqrt(qk[0] * qk[0] + qk[1] * qk[1] + qk[2] * qk[2] + qk[3] * qk[3]);
        cr_expect_leq(fabs(norm - 1), 1e-14);
    }
    ctc_sim_result_free(r);
    ctc_model_free(m);
    scene_free(s);
}

/* passive triple pendulum, 1 s, final q by rk4 with step h */
static void rk4_final(scene *s, double h, double *q)
{
    s->spec.integrator = (ctc_integ_spec){.method = CTC_INTEG_RK4, .step = h};
    ctc_sim_result *r = run(s);
    memcpy(q, r->ch[CTC_CH_Q] + 3 * (r->nsamples - 1), 3 * sizeof *q);
    ctc_sim_result_free(r);
}

Test(sim, rk4_converges_at_fourth_order)
{
    scene *s = triple_pendulum();
    s->spec.controller = CTC_CTRL_NONE;
    s->spec.duration = 1;
    s->spec.output_interval = 0.1;
    s->spec.integrator.rtol = 1e-13, s->spec.integrator.atol = 1e-14;
    ctc_sim_result *ref = run(s);
    const double *qref = ref->ch[CTC_CH_Q] + 3 * (ref->nsamples - 1);
    double q[3][3], err[3];
    const double h[3] = {0.004, 0.002, 0.001};
    for (int k = 0; k < 3; k++) {
        rk4_final(s, h[k], q[k]);
        err[k] = test_rel_err(q[k], qref, 3);
    }
    for (int k = 0; k < 2; k++)
        cr_expect(err[k] / err[k + 1] > 13 && err[k] / err[k + 1] < 19,
                  "h %g -> %g: error %g -> %g, ratio %g", h[k], h[k + 1], err[k], err[k + 1],
                  err[k] / err[k + 1]);
    ctc_sim_result_free(ref);
    scene_free(s);
}

Test(sim, samples_fall_on_the_interval_and_end_at_the_duration)
{
    scene *s = triple_pendulum();
    set_pd(s, 100, 20, 0);
    s->spec.duration = 1;
    s->spec.output_interval = 0.3;
    s->spec.channels = CTC_CH_BIT(CTC_CH_Q) | CTC_CH_BIT(CTC_CH_TAU);
    ctc_sim_result *r = run(s);
    const double expect[] = {0, 0.3, 0.6, 0.9, 1};
    cr_assert_eq(r->nsamples, 5);
    for (int j = 0; j < 5; j++) cr_expect_float_eq(r->t[j], expect[j], 1e-12);
    cr_expect_eq(r->t[4], 1.0); /* exactly */
    cr_expect_null(r->ch[CTC_CH_E]);
    cr_expect_not_null(r->ch[CTC_CH_TAU]);
    cr_expect_eq(r->width[CTC_CH_Q], 3);
    cr_expect_eq(r->width[CTC_CH_ENERGY], 0);
    ctc_sim_result_free(r);
    scene_free(s);
}

Test(sim, applied_torque_is_inverse_dynamics_plus_disturbance)
{
    /* tau = M u + N + z with u = qdd_d + w: check against the RNEA oracle at each sample */
    scene *s = triple_pendulum();
    set_pd(s, 100, 20, 250);
    set_disturbance(s, 0.2);
    s->spec.duration = 0.5;
    s->spec.output_interval = 0.05;
    ctc_sim_result *r = run(s);
    ctc_model *m = NULL;
    cr_assert_eq(ctc_model_build(&s->spec.chain, &m, NULL, 0), CTC_OK);
    ctc_oracle *o = ctc_oracle_new(m);
    for (int j = 0; j < r->nsamples; j++) {
        const double *q = r->ch[CTC_CH_Q] + 3 * j, *v = r->ch[CTC_CH_QD] + 3 * j;
        double u[3], tau[3];
        for (int i = 0; i < 3; i++) {
            double d[3];
            ctc_traj_eval(&s->traj[i], r->t[j], d);
            u[i] = d[2] + r->ch[CTC_CH_W][3 * j + i];
            cr_expect_float_eq(r->ch[CTC_CH_Q_DES][3 * j + i], d[0], 1e-15);
        }
        ctc_oracle_rnea(m, o, q, v, u, tau);
        for (int i = 0; i < 3; i++)
            cr_expect_leq(fabs(r->ch[CTC_CH_TAU][3 * j + i] - (tau[i] + 0.2)), 1e-9,
                          "t %g joint %d: %g vs %g", r->t[j], i, r->ch[CTC_CH_TAU][3 * j + i],
                          tau[i] + 0.2);
    }
    ctc_oracle_free(o);
    ctc_model_free(m);
    ctc_sim_result_free(r);
    scene_free(s);
}

Test(sim, open_chain_samples_cost_no_evaluation_of_the_dynamics)
{
    /* every channel recorded, yet the right-hand sides are the integrator's alone: dopri5 makes
       one at its start, one for its first step size and 6 per attempted step (FSAL); rk4 one at
       its start and 4 per step. A sample's forces and energy take the inverse pass and the
       kinematics only, or nothing at a step's end (the last evaluation is at that state) */
    scene *s = triple_pendulum();
    set_pd(s, 100, 20, 250);
    set_disturbance(s, 0.2);
    s->spec.duration = 2;
    s->spec.output_interval = 0.01;
    for (int method = 0; method < 2; method++) {
        s->spec.integrator =
            method ? (ctc_integ_spec){.method = CTC_INTEG_RK4, .step = 0.005}
                   : (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-6, .atol = 1e-8};
        ctc_sim_result *r = run(s);
        cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
        cr_assert_eq(r->nsamples, 201);
        const ctc_sim_metrics *mt = &r->metrics;
        long expected = method ? 1 + 4 * mt->steps : 2 + 6 * (mt->steps + mt->rejected);
        cr_expect_eq(mt->rhs_evals, expected, "%s: %ld evaluations for %ld steps (%ld rejected)",
                     method ? "rk4" : "dopri5", mt->rhs_evals, mt->steps, mt->rejected);
        ctc_sim_result_free(r);
    }
    scene_free(s);
}

Test(sim, step_disturbance_acts_from_its_time)
{
    scene *s = triple_pendulum();
    for (int i = 0; i < 3; i++) {
        s->q0[i] = 0.2;
        s->traj[i] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = 0.2};
        s->dist[i] = (ctc_disturb){.type = CTC_DISTURB_STEP, .value = 0.5, .time = 1.05};
    }
    s->spec.disturb = s->dist;
    set_pd(s, 100, 20, 0);
    s->spec.duration = 3;
    ctc_sim_result *r = run(s);
    cr_assert_eq(r->status, CTC_RUN_DONE);
    cr_expect_leq(max_error_after(r, 0) - max_error_after(r, 1.05), 0); /* nothing before */
    for (int j = 0; r->t[j] < 1.05; j++)
        for (int i = 0; i < 3; i++) cr_expect_leq(fabs(r->ch[CTC_CH_E][3 * j + i]), 1e-9);
    cr_expect_gt(max_error_after(r, 2.5), 1e-4); /* the offset after it */
    ctc_sim_result_free(r);
    scene_free(s);
}

Test(sim, model_error_is_reported_not_hidden)
{
    scene *s = triple_pendulum();
    set_pd(s, 100, 20, 0);
    s->spec.model_mass_scale = 1.3;
    s->spec.model_inertia_scale = 0.8;
    s->spec.duration = 2;
    ctc_sim_result *r = run(s);
    cr_assert_eq(r->status, CTC_RUN_DONE);
    cr_expect(isnan(r->metrics.errdyn_dev)); /* no exact error dynamics to compare with */
    double dev = pd_deviation(s, r);
    cr_expect_gt(dev, 1e-4, "a 30%% mass error must show in the tracking (dev %g)", dev);
    ctc_sim_result_free(r);
    scene_free(s);
}

Test(sim, divergence_stops_the_run_with_time_and_joint)
{
    scene *s = triple_pendulum();
    s->spec.controller = CTC_CTRL_NONE;
    s->spec.max_speed = 2;
    ctc_sim_result *r = run(s);
    cr_assert_eq(r->status, CTC_RUN_DIVERGED);
    cr_expect_geq(r->metrics.diverged_joint, 0);
    cr_expect_lt(r->metrics.t_end, 5);
    cr_expect(strstr(r->message, "rad/s exceeds the bound 2") != NULL, "%s", r->message);
    cr_expect_gt(r->nsamples, 1); /* the samples before it are kept */
    for (int j = 0; j < r->nsamples; j++) cr_expect_leq(r->t[j], r->metrics.t_end);
    ctc_sim_result_free(r);
    scene_free(s);
}

static int cancel_after(void *ctx)
{
    int *calls = ctx;
    return ++*calls >= 10;
}

Test(sim, cancellation_stops_between_steps)
{
    scene *s = triple_pendulum();
    set_pd(s, 100, 20, 0);
    int calls = 0;
    ctc_sim_hooks hooks = {.ctx = &calls, .cancelled = cancel_after};
    ctc_sim_result *r = NULL;
    cr_assert_eq(ctc_sim_run(&s->spec, &hooks, &r, NULL, 0), CTC_OK);
    cr_expect_eq(r->status, CTC_RUN_CANCELLED);
    cr_expect_eq(r->metrics.steps, 10);
    cr_expect(strstr(r->message, "cancelled at t = ") == r->message);
    ctc_sim_result_free(r);
    scene_free(s);
}

/* what the recorded hook saw: each call's sample count, and the last sample's t and q[0] then */
typedef struct seen_samples {
    const ctc_sim_result *r;
    int calls, bad_order;
    double t[512], q0[512];
} seen_samples;

static void note_recorded(void *ctx, const ctc_sim_result *r)
{
    seen_samples *s = ctx;
    if (s->r && s->r != r) s->bad_order = 1;
    s->r = r;
    if (r->nsamples != s->calls + 1) s->bad_order = 1;
    int j = r->nsamples - 1;
    if (j >= 0 && j < 512) {
        s->t[j] = r->t[j];
        s->q0[j] = r->ch[CTC_CH_Q][(size_t)j * (size_t)r->width[CTC_CH_Q]];
    }
    s->calls++;
}

Test(sim, the_recorded_hook_sees_each_sample_once_as_it_stays)
{
    scene *s = triple_pendulum();
    set_pd(s, 100, 20, 0);
    s->spec.duration = 1;
    s->spec.output_interval = 0.01;
    static seen_samples seen;
    ctc_sim_hooks hooks = {.ctx = &seen, .recorded = note_recorded};
    ctc_sim_result *r = NULL;
    cr_assert_eq(ctc_sim_run(&s->spec, &hooks, &r, NULL, 0), CTC_OK);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
    cr_expect_eq(seen.r, r, "the hook's result is the one returned");
    cr_expect_eq(seen.calls, r->nsamples, "%d calls for %d samples", seen.calls, r->nsamples);
    cr_expect_eq(seen.bad_order, 0, "each call adds one sample");
    for (int j = 0; j < r->nsamples && j < 512; j++) {
        cr_expect_eq(seen.t[j], r->t[j], "t[%d] changed after its call", j);
        cr_expect_eq(seen.q0[j], r->ch[CTC_CH_Q][(size_t)j * 3], "q[0] of sample %d changed", j);
    }
    ctc_sim_result_free(r);
    scene_free(s);
}

Test(sim, stiff_gains_run_with_bdf_in_fewer_steps_than_dopri5)
{
    scene *s = triple_pendulum();
    set_pd(s, 1e8, 2e4, 0); /* double pole at -1e4 */
    s->spec.duration = 1;
    s->spec.integrator = (ctc_integ_spec){.method = CTC_INTEG_BDF, .rtol = 1e-8, .atol = 1e-10};
    ctc_sim_result *bdf = run(s);
    s->spec.integrator.method = CTC_INTEG_DOPRI5;
    ctc_sim_result *dp = run(s);
    cr_assert_eq(bdf->status, CTC_RUN_DONE, "%s", bdf->message);
    cr_assert_eq(dp->status, CTC_RUN_DONE, "%s", dp->message);
    cr_expect_leq(bdf->metrics.errdyn_dev, 1e-5, "bdf deviation %g", bdf->metrics.errdyn_dev);
    cr_expect_lt(bdf->metrics.steps, dp->metrics.steps / 2, "bdf %ld steps, dopri5 %ld",
                 bdf->metrics.steps, dp->metrics.steps);
    ctc_sim_result_free(bdf);
    ctc_sim_result_free(dp);
    scene_free(s);
}

static void expect_check_error(const ctc_sim_spec *spec, const char *message)
{
    char err[256] = "";
    cr_expect_eq(ctc_sim_check(spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, message);
    ctc_sim_result *r = (ctc_sim_result *)1;
    cr_expect_eq(ctc_sim_run(spec, NULL, &r, NULL, 0), CTC_EINVAL);
    cr_expect_null(r);
}

Test(sim, bad_specs_are_rejected_with_exact_messages)
{
    scene *s = triple_pendulum();
    set_pd(s, 100, 20, 0);
    ctc_sim_spec good = s->spec, bad;
    char err[256] = "";
    cr_assert_eq(ctc_sim_check(&good, err, sizeof err), CTC_OK, "%s", err);

    bad = good, bad.duration = -1;
    expect_check_error(&bad, "duration must be positive and finite (got -1 s)");
    bad = good, bad.output_interval = 6;
    expect_check_error(&bad, "output interval (6 s) must not exceed the duration (5 s)");
    bad = good, bad.output_interval = 1e-9;
    expect_check_error(&bad, "more than 50000000 output samples");
    bad = good, bad.model_mass_scale = 0;
    expect_check_error(&bad, "model mass scale must be positive and finite (got 0)");
    bad = good, bad.max_speed = -1;
    expect_check_error(&bad, "max_speed must be >= 0 and finite (got -1)");
    bad = good, bad.controller = CTC_CTRL_NONE, bad.channels = CTC_CH_BIT(CTC_CH_E);
    expect_check_error(&bad, "channel \"e\" needs a controller (this run is passive)");
    s->gains[1].kp = -100; /* s (s^2 + 20 s - 100): a pole at -10 + sqrt(200) */
    expect_check_error(&good, "coordinate 1: gains (ki 0, kp -100, kv 20) make the error dynamics "
                              "unstable (pole at 4.14214)");
    s->gains[1].kp = 100;
    s->gains[0].ki = 2500; /* above kv kp = 2000 */
    cr_expect_eq(ctc_sim_check(&good, err, sizeof err), CTC_EINVAL);
    cr_expect(strstr(err, "coordinate 0: gains (ki 2500, kp 100, kv 20) make the error dynamics "
                          "unstable (pole at ") == err,
              "%s", err);
    s->gains[0].ki = 0;
    s->traj[2].period = 0;
    cr_expect_eq(ctc_sim_check(&good, err, sizeof err), CTC_EINVAL);
    cr_expect(strstr(err, "coordinate 2: trajectory: ") == err, "%s", err);
    s->traj[2].period = 1.5;
    bad = good, bad.q0 = (const double[]){0, NAN, 0};
    expect_check_error(&bad, "q0[1] is not finite");
    scene_free(s);
}

Test(sim, spherical_joints_need_a_passive_run)
{
    test_chain *c = test_chain_random_spatial(2, 3, 1u << CTC_JOINT_SPHERICAL);
    scene *s = scene_new(c, 6);
    set_pd(s, 100, 20, 0);
    for (int i = 0; i < 6; i++) s->traj[i] = (ctc_traj){.type = CTC_TRAJ_CONSTANT};
    s->spec.q0 = NULL;
    expect_check_error(&s->spec,
                       "joint 0: spherical joints are allowed in passive runs only (controller "
                       "\"none\")");
    scene_free(s);
}

/* the paper's five-bar under PD to (0, pi/4, -3 pi/4) with kp 100, kv 20 (the five_bar_pd
 * preset), for 3 s with the integrator and stabilisation given */
static ctc_sim_result *five_bar_run(ctc_integ_spec integ, ctc_loop_stab stab)
{
    loop_scene *s = loop_scene_five_bar();
    const double target[3] = {0, PI / 4, -3 * PI / 4};
    ctc_gains gains[3];
    ctc_traj traj[3];
    for (int i = 0; i < 3; i++) {
        gains[i] = (ctc_gains){.kp = 100, .kv = 20};
        traj[i] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = target[i]};
    }
    ctc_sim_spec spec = fixture_pd_spec(&s->spec, s->q0, gains, traj, integ, 3, 0.01);
    spec.loop_stab = stab;
    ctc_sim_result *r = fixture_run_done(&spec);
    free(s);
    return r;
}

Test(sim, bdf_projects_a_loop_without_restarting_at_every_step)
{
    /* Projecting after a step and restarting CVODE sent it back to order 1 each time, and the
       drift of those short steps asked for the next projection: 122,632 steps for the preset's
       10 s (rtol 1e-8), 98 times Baumgarte's. Projecting inside CVODE's steps keeps its
       history: measured 785 steps on those 10 s, Baumgarte 1,257. This run is shorter; the
       assertions are the ratio's */
    const ctc_integ_spec bdf = {.method = CTC_INTEG_BDF, .rtol = 1e-8, .atol = 1e-10};
    ctc_sim_result *proj = five_bar_run(bdf, CTC_LOOP_PROJECT);
    ctc_sim_result *baum = five_bar_run(bdf, CTC_LOOP_BAUMGARTE);
    const ctc_sim_metrics *mp = &proj->metrics, *mb = &baum->metrics;
    cr_expect_leq(mp->steps, 2 * mb->steps, "projection %ld steps, Baumgarte %ld", mp->steps,
                  mb->steps);
    cr_expect_leq(mp->rhs_evals, 2 * mb->rhs_evals, "projection %ld evaluations, Baumgarte %ld",
                  mp->rhs_evals, mb->rhs_evals);
    cr_expect_gt(mp->projections, 0, "it drifts, so it projects");
    cr_expect_leq(mp->projections, mp->steps);
    /* the drift of one step is within the tolerances (loop_res_max is the largest of the samples'
       position residuals, sim.c) */
    cr_expect_leq(mp->loop_res_max, 1e-8, "residual %g", mp->loop_res_max);
    /* the error dynamics hold as well as with Baumgarte's terms */
    cr_expect_leq(mp->errdyn_dev, 1e-6, "error-dynamics deviation %g", mp->errdyn_dev);
    ctc_sim_result_free(proj);
    ctc_sim_result_free(baum);
}

/* ---- controllers of the test's own, through the class interface (ctrl.h) ---- */

/* PD/PID written here from the contract: w = ki int(e) + kp e + kv de per coordinate */
static void own_pd_law(const ctc_ctrl_eval *in, double *w)
{
    for (int i = 0; i < in->nind; i++) {
        const ctc_gains *g = &in->gains[i];
        const double *d = in->des + 3 * i;
        w[i] = g->ki * in->xi[i] + g->kp * (d[0] - in->qi[i]) + g->kv * (d[1] - in->vi[i]);
    }
}

/* d/dt (int e, e, de) under that law with an exact model, where e'' = -w */
static void own_pd_closed_loop(const ctc_gains *g, double a[9])
{
    const double m[9] = {0, 1, 0, 0, 0, 1, -g->ki, -g->kp, -g->kv};
    memcpy(a, m, sizeof m);
}

static const ctc_ctrl_class own_pd = {
    .name = "own_pd", .nstate = 1, .law = own_pd_law, .closed_loop = own_pd_closed_loop};

static void expect_same_doubles(const double *a, const double *b, size_t n, const char *what)
{
    cr_assert((a == NULL) == (b == NULL), "%s: one is missing", what);
    if (n > 0 && a) cr_expect_eq(memcmp(a, b, n * sizeof *a), 0, "%s differ", what);
}

Test(sim, a_pd_class_written_here_reproduces_the_builtin_pd_run_bit_for_bit)
{
    for (int with_disturbance = 0; with_disturbance < 2; with_disturbance++) {
        scene *s = triple_pendulum();
        set_pd(s, 100, 20, 0);
        if (with_disturbance) set_disturbance(s, 0.2);
        ctc_sim_result *builtin = run(s);
        s->spec.ctrl_class = &own_pd;
        s->spec.controller = CTC_CTRL_NONE; /* ignored once a class is given */
        ctc_sim_result *own = run(s);
        cr_assert_eq(own->status, CTC_RUN_DONE, "%s", own->message);
        cr_assert_eq(own->nsamples, builtin->nsamples);
        cr_assert_eq(own->channels, builtin->channels);
        expect_same_doubles(own->t, builtin->t, (size_t)own->nsamples, "t");
        for (int ch = 0; ch < CTC_NCHANNELS; ch++) {
            cr_assert_eq(own->width[ch], builtin->width[ch]);
            expect_same_doubles(own->ch[ch], builtin->ch[ch],
                                (size_t)own->nsamples * (size_t)own->width[ch],
                                ctc_channel_name((ctc_channel)ch));
        }
        const ctc_sim_metrics *mo = &own->metrics, *mb = &builtin->metrics;
        expect_same_doubles(mo->e_max, mb->e_max, 3, "e_max");
        expect_same_doubles(mo->e_rms, mb->e_rms, 3, "e_rms");
        expect_same_doubles(mo->e_final, mb->e_final, 3, "e_final");
        cr_expect(mo->steps == mb->steps && mo->rejected == mb->rejected &&
                  mo->rhs_evals == mb->rhs_evals);
        cr_expect_eq(memcmp(&mo->err_estimate, &mb->err_estimate, sizeof(double)), 0);
        /* the metrics hook: the error-dynamics reference exists without a disturbance only */
        cr_expect_eq(memcmp(&mo->errdyn_dev, &mb->errdyn_dev, sizeof(double)), 0,
                     "errdyn_dev %g and %g", mo->errdyn_dev, mb->errdyn_dev);
        cr_expect_eq(isnan(mo->errdyn_dev), with_disturbance);
        ctc_sim_result_free(builtin);
        ctc_sim_result_free(own);
        scene_free(s);
    }
}

/* a nonlinear law of the test's own, without gains or state: w = kp e + kv de + c e^3 */
typedef struct cubic_params {
    double kp, kv, c;
} cubic_params;

static void cubic_law(const ctc_ctrl_eval *in, double *w)
{
    const cubic_params *p = in->params;
    for (int i = 0; i < in->nind; i++) {
        double e = in->des[3 * i] - in->qi[i], de = in->des[3 * i + 1] - in->vi[i];
        w[i] = p->kp * e + p->kv * de + p->c * e * e * e;
    }
}

/* e'' = -(kp e + kv e' + c e^3) from (e0, de0) to t by RK4 with a step of 1e-4 s, the oracle */
static double cubic_error(const cubic_params *p, double e0, double de0, double t)
{
    double x[2] = {e0, de0}, done = 0;
    while (done < t) {
        double h = fmin(1e-4, t - done), k[4][2], y[2];
        for (int s = 0; s < 4; s++) {
            double f = s == 0 ? 0 : s == 3 ? 1 : 0.5;
            for (int i = 0; i < 2; i++) y[i] = x[i] + (s ? f * h * k[s - 1][i] : 0);
            k[s][0] = y[1];
            k[s][1] = -(p->kp * y[0] + p->kv * y[1] + p->c * y[0] * y[0] * y[0]);
        }
        for (int i = 0; i < 2; i++) x[i] += h / 6 * (k[0][i] + 2 * k[1][i] + 2 * k[2][i] + k[3][i]);
        done += h;
    }
    return x[0];
}

Test(sim, a_nonlinear_controller_plugs_in_and_its_error_obeys_its_own_law)
{
    /* exact model, no disturbance: qdd = qdd_d + w, so e'' = -w(e, e') whatever the chain */
    const cubic_params params = {.kp = 25, .kv = 6, .c = 40};
    const ctc_ctrl_class cubic = {.name = "cubic", .law = cubic_law};
    scene *s = triple_pendulum();
    s->spec.gains = NULL;
    s->spec.ctrl_class = &cubic;
    s->spec.ctrl_params = &params;
    s->spec.duration = 2;
    s->spec.output_interval = 0.05;
    ctc_sim_result *r = run(s);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
    double dev = 0;
    for (int i = 0; i < 3; i++) {
        double d0[3];
        ctc_traj_eval(&s->traj[i], 0, d0);
        for (int j = 0; j < r->nsamples; j++) {
            double ref = cubic_error(&params, d0[0] - s->q0[i], d0[1] - s->v0[i], r->t[j]);
            dev = fmax(dev, fabs(r->ch[CTC_CH_E][3 * j + i] - ref));
        }
    }
    cr_expect_leq(dev, 1e-6, "|e - e_oracle| = %g", dev);
    /* the error is large at first (e0 up to 2.6 rad), so the cubic term mattered */
    cr_expect_gt(r->metrics.e_max[0], 2);
    /* no closed-loop hook: no linear error-dynamics reference */
    cr_expect(isnan(r->metrics.errdyn_dev));
    ctc_sim_result_free(r);
    scene_free(s);
}

Test(sim, a_controller_class_is_checked_with_exact_messages)
{
    scene *s = triple_pendulum();
    set_pd(s, 100, 20, 0);
    char err[256] = "";
    ctc_sim_result *r = NULL;
    ctc_ctrl_class bad = own_pd;
    bad.nstate = 2;
    s->spec.ctrl_class = &bad;
    cr_assert_eq(ctc_sim_run(&s->spec, NULL, &r, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err,
                     "controller \"own_pd\": state size must be 0 or 1 per coordinate (got 2)");
    bad = own_pd;
    bad.nstate = 0;
    cr_assert_eq(ctc_sim_check(&s->spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "controller \"own_pd\": a closed-loop matrix needs a law and the "
                          "integral state (nstate 1)");
    bad = own_pd;
    s->spec.gains = NULL;
    cr_assert_eq(ctc_sim_check(&s->spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "a controller needs gains and a trajectory for every coordinate");
    bad.name = NULL;
    cr_assert_eq(ctc_sim_check(&s->spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "the controller class has no name");
    cr_expect_null(r);
    scene_free(s);
}

/* ---- the tolerance floor (sim_tol.c) ---- */

/* The PD run of the n-link rod pendulum from q0_k = +-pi/6 to rest, on the given integrator,
 * for duration s, the controller's model's masses scaled by mass_scale (1: the exact model). */
static ctc_sim_result *long_pendulum_model(int n, ctc_integ_spec integ, double duration,
                                           double mass_scale)
{
    test_chain *c = test_chain_rod_pendulum(n, 1, 1);
    cr_assert_not_null(c);
    ctc_sim_result *r =
        fixture_pd_to_rest(c, PI / 6, mass_scale, integ, duration, duration / 10, 0);
    test_chain_free(c);
    return r;
}

static ctc_sim_result *long_pendulum(int n, ctc_integ_spec integ, double duration)
{
    return long_pendulum_model(n, integ, duration, 1);
}

/* The paper's scenes stay far below the floor: their tolerances are kept exactly (so their runs
 * are those of before the floor), and the estimate is near rounding. */
Test(sim, the_tolerance_floor_leaves_short_chains_alone)
{
    scene *s = triple_pendulum();
    set_pd(s, 100, 20, 250);
    s->spec.integrator = (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-8, .atol = 1e-10};
    ctc_sim_result *r = run(s);
    const ctc_sim_metrics *m = &r->metrics;
    cr_expect_eq(m->tol_floored, 0);
    cr_expect_eq(m->tol_rtol, 1e-8);
    cr_expect_eq(m->tol_atol, 1e-10);
    cr_expect_str_empty(m->tol_reason);
    cr_expect(m->accel_rounding >= 0 && m->accel_rounding < 1e-12, "rounding %g",
              m->accel_rounding);
    ctc_sim_result_free(r);
    scene_free(s);
}

/* On 1024 rods with a controller model of its own (masses 1.1 times the plant's), the plant's
 * pass is the literal one refined, and the default tolerances ask for more than its accelerations
 * carry (their round trip at the start is about 2e-5 rad/s^2, 4e-7 of their size): both are
 * raised, with the reason, and the run takes tens of steps instead of thousands. With the exact
 * model the plant's pass takes the reference form (sim_rhs.c), whose accelerations are u plus
 * M^-1 of what the plant adds (nothing here) and carry no such rounding: nothing is raised, the
 * run is as short, and its error stays where the closed-form error dynamics put it (errdyn_dev,
 * 1e-6 asserted over 0.5 s). A job's own tolerances above the floor are kept; rk4 has none to
 * floor. */
Test(sim, the_tolerance_floor_raises_what_a_long_chain_cannot_meet, .timeout = 60)
{
    ctc_integ_spec def = {.method = CTC_INTEG_DOPRI5, .rtol = 1e-8, .atol = 1e-10};
    ctc_sim_result *r = long_pendulum_model(1024, def, 0.5, 1.1);
    const ctc_sim_metrics *m = &r->metrics;
    cr_expect_eq(m->tol_floored, 3, "both raised");
    cr_expect(m->accel_rounding > 1e-7 && m->accel_rounding < 1e-3, "rounding %g",
              m->accel_rounding);
    cr_expect_eq(m->tol_atol, 1e-4 * m->accel_rounding, "atol %g", m->tol_atol);
    cr_expect(m->tol_rtol > 1e-8 && m->tol_rtol < 1e-5, "rtol %g", m->tol_rtol);
    cr_expect(strstr(m->tol_reason, "atol 1e-10 raised to ") == m->tol_reason, "%s", m->tol_reason);
    cr_expect(strstr(m->tol_reason, ", rtol 1e-08 raised to ") != NULL, "%s", m->tol_reason);
    cr_expect_lt(m->steps, 100, "%ld steps", m->steps);
    ctc_sim_result_free(r);

    r = long_pendulum(1024, def, 0.5);
    m = &r->metrics;
    cr_expect_eq(m->tol_floored, 0, "%s", m->tol_reason);
    cr_expect(m->accel_rounding >= 0 && m->accel_rounding < 1e-10, "rounding %g",
              m->accel_rounding);
    cr_expect_lt(m->steps, 100, "%ld steps", m->steps);
    cr_expect_lt(m->errdyn_dev, 1e-6, "errdyn_dev %g", m->errdyn_dev);
    ctc_sim_result_free(r);

    ctc_integ_spec loose = {.method = CTC_INTEG_DOPRI5, .rtol = 1e-4, .atol = 1e-4};
    r = long_pendulum(1024, loose, 0.1);
    cr_expect_eq(r->metrics.tol_floored, 0);
    cr_expect_eq(r->metrics.tol_rtol, 1e-4);
    cr_expect_eq(r->metrics.tol_atol, 1e-4);
    ctc_sim_result_free(r);

    r = long_pendulum(1024, (ctc_integ_spec){.method = CTC_INTEG_RK4, .step = 1e-2}, 0.1);
    cr_expect(isnan(r->metrics.accel_rounding) && isnan(r->metrics.tol_atol));
    cr_expect_eq(r->metrics.tol_floored, 0);
    ctc_sim_result_free(r);
}
