/*
 * test_plant.c - the plant's terms beyond rigid-body dynamics in a CTC run (plant.h, sim.h):
 * actuator saturation and the integral's anti-windup, friction, springs and dampers in the
 * joints, against closed forms written here.
 *
 * The scenes are single rods about a pivot (1 m, 1 kg: I_p = m l^2 / 3 about the pivot), where
 * the clipped actuator's motion has a closed form: with gravity, a constant torque L gives the
 * first integral 1/2 I_p v^2 - L q - m g (l/2) cos q = const; without gravity, q'' = L / I_p.
 * Once the actuator leaves its limit, an exact model makes the error obey the linear law
 * d/dt (int e, e, de) = Ac (int e, e, de) (ctrl.h), integrated here by a fine fixed-step RK4. A
 * spring and damper make I q'' + b q' + k (q - r) = 0, the damped oscillator; regularised Coulomb
 * friction under a constant load F creeps at v = v_s atanh(F / Fc) below the friction level and
 * accelerates at (F - Fc) / I above it.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "sim.h"
#include "run_fixture.h"

#define PI 3.14159265358979323846
#define G 9.81

/* one rod of 1 m, 1 kg about a revolute pivot; gravity -y, or none */
typedef struct rod_scene {
    test_chain *chain;
    double q0[1], v0[1];
    ctc_gains gains[1];
    ctc_traj traj[1];
    ctc_plant_coord plant[1];
    ctc_sim_spec spec;
} rod_scene;

static rod_scene *rod_new(double gravity, double q_des, double limit)
{
    rod_scene *s = calloc(1, sizeof *s);
    cr_assert_not_null(s);
    s->chain = test_chain_rod_pendulum(1, 1, 1);
    s->chain->spec.gravity[1] = -gravity;
    s->spec.chain = s->chain->spec;
    s->spec.q0 = s->q0;
    s->spec.v0 = s->v0;
    s->spec.gains = s->gains;
    s->spec.traj = s->traj;
    s->spec.model_mass_scale = s->spec.model_inertia_scale = 1;
    s->spec.integrator = (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-11, .atol = 1e-13};
    s->spec.output_interval = 0.001;
    s->spec.duration = 5;
    s->traj[0] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = q_des};
    s->plant[0].torque_limit = limit;
    s->spec.plant = s->plant;
    return s;
}

static void rod_free(rod_scene *s)
{
    test_chain_free(s->chain);
    free(s);
}

/* a pose whose gravity torque m g (l/2) sin(q) exceeds the limit, from rest at q0 = pi/2 with
   q_d = 2 above it: the clipped actuator gives the constant torque L throughout, and the rod
   swings conservatively about the equilibrium sin(q_eq) = L / (m g l/2), between q0 and the
   other root of the first integral */
Test(plant, held_pose_beyond_the_limit_sags_as_the_closed_form)
{
    const double L = 3, q_d = 2, q0 = PI / 2, ip = 1.0 / 3, mgl2 = G * 0.5;
    rod_scene *s = rod_new(G, q_d, L);
    s->q0[0] = q0;
    s->spec.controller = CTC_CTRL_PD;
    s->gains[0] = (ctc_gains){.kp = 100, .kv = 20};
    ctc_sim_result *r = fixture_run_done(&s->spec);

    /* the first integral, and the lower turning point by bisection on it */
    const double c0 = -L * q0 - mgl2 * cos(q0);
    double lo = -PI / 2, hi = asin(L / mgl2); /* the root lies below the equilibrium */
    for (int k = 0; k < 200; k++) {
        double mid = 0.5 * (lo + hi);
        if (-L * mid - mgl2 * cos(mid) - c0 > 0)
            lo = mid; /* potential above the start: past it */
        else
            hi = mid;
    }
    double q_low = 0.5 * (lo + hi), q_min = INFINITY, dev = 0;
    const double *q = r->ch[CTC_CH_Q], *v = r->ch[CTC_CH_QD], *tau = r->ch[CTC_CH_TAU];
    for (int j = 0; j < r->nsamples; j++) {
        double ci = 0.5 * ip * v[j] * v[j] - L * q[j] - mgl2 * cos(q[j]);
        dev = fmax(dev, fabs(ci - c0));
        q_min = fmin(q_min, q[j]);
        cr_assert_eq(tau[j], L, "t = %g: tau %.17g is not the limit", r->t[j], tau[j]);
    }
    cr_expect_leq(dev, 1e-9, "first integral drifts by %g", dev);
    /* sampled every 1 ms, the lowest sample is within 1/2 q'' dt^2 of the turning point */
    cr_expect_leq(fabs(q_min - q_low), 1e-5, "lowest q %.9f, closed form %.9f", q_min, q_low);
    cr_expect_eq(r->metrics.sat_fraction[0], 1.0);
    cr_expect_eq(r->metrics.tau_peak[0], L);
    cr_expect_eq(r->metrics.tau_rms[0], L);
    cr_expect(isnan(r->metrics.errdyn_dev), "no linear error law under saturation");
    ctc_sim_result_free(r);
    rod_free(s);
}

/* d/dt x = Ac x over t by RK4 with steps of at most h */
static void linear_flow(const ctc_gains *g, double x[3], double t, double h)
{
    int n = (int)ceil(t / h);
    if (n < 1) return;
    double dt = t / n;
    for (int k = 0; k < n; k++) {
        double s[4][3], y[3];
        for (int st = 0; st < 4; st++) {
            double c = st == 0 ? 0 : st == 3 ? 1 : 0.5;
            for (int i = 0; i < 3; i++) y[i] = x[i] + (st ? c * dt * s[st - 1][i] : 0);
            s[st][0] = y[1], s[st][1] = y[2];
            s[st][2] = -g->ki * y[0] - g->kp * y[1] - g->kv * y[2];
        }
        for (int i = 0; i < 3; i++)
            x[i] += dt / 6 * (s[0][i] + 2 * s[1][i] + 2 * s[2][i] + s[3][i]);
    }
}

/* Without gravity, PID from rest to q_d = 1 with the actuator clipped at L: while clipped,
   q = (a/2) t^2 with a = L / I_p, and the clamped integral stays at exactly 0, so the actuator
   leaves the limit at t_s where kp (1 - q) - kv a t = a, and from there the error follows the
   linear law from E(t_s) = (0, 1 - q(t_s), -a t_s). A wound-up integral (int e from 0 to t_s,
   0.35 here) would follow another solution. The recovery bound: |e| < 1e-3 from the time the
   closed form says, plus the integrator's tolerance. */
Test(plant, pid_anti_windup_follows_the_linear_law_after_the_limit)
{
    const double L = 0.5, ip = 1.0 / 3, a = L / ip;
    const ctc_gains g = {.ki = 2, .kp = 4, .kv = 4};
    rod_scene *s = rod_new(0, 1, L);
    s->spec.controller = CTC_CTRL_PID;
    s->gains[0] = g;
    s->spec.duration = 20;
    s->spec.output_interval = 0.01;
    ctc_sim_result *r = fixture_run_done(&s->spec);

    /* kp (1 - a t^2 / 2) - kv a t = a */
    const double qa = g.kp * a / 2, qb = g.kv * a, qc = a - g.kp;
    const double ts = (-qb + sqrt(qb * qb - 4 * qa * qc)) / (2 * qa);
    double dev = 0, t_recover = 0, e_after = 0;
    const double *e = r->ch[CTC_CH_E], *tau = r->ch[CTC_CH_TAU];
    for (int j = 0; j < r->nsamples; j++) {
        double t = r->t[j], ref;
        if (t <= ts) {
            ref = 1 - 0.5 * a * t * t;
            cr_assert_leq(fabs(tau[j] - L), 1e-9 * L, "t = %g: tau %g while clipped", t, tau[j]);
        } else {
            double x[3] = {0, 1 - 0.5 * a * ts * ts, -a * ts};
            linear_flow(&g, x, t - ts, 1e-4);
            ref = x[1];
            /* the scene stays off the limit: the linear law's force is within it */
            double w = g.ki * x[0] + g.kp * x[1] + g.kv * x[2];
            cr_assert_lt(fabs(ip * w), L * (1 + 1e-9), "t = %g: the scene saturates again", t);
        }
        dev = fmax(dev, fabs(e[j] - ref));
        if (fabs(ref) >= 1e-3) t_recover = t;
    }
    for (int j = 0; j < r->nsamples; j++)
        if (r->t[j] > t_recover) e_after = fmax(e_after, fabs(e[j]));
    cr_expect_leq(dev, 1e-7, "|e - closed form| = %g (t_s = %g s)", dev, ts);
    cr_expect_lt(t_recover, 15, "the closed form recovers within the run (t %g)", t_recover);
    cr_expect_leq(e_after, 1e-3 + 1e-7, "after t = %g s, |e| = %g", t_recover, e_after);
    cr_expect_gt(r->metrics.sat_fraction[0], 0);
    cr_expect_lt(r->metrics.sat_fraction[0], ts / s->spec.duration + 0.01);
    ctc_sim_result_free(r);
    rod_free(s);
}

/* A limit the actuator never reaches changes nothing: the same samples, bit for bit */
Test(plant, unreached_limit_gives_the_ideal_run_bitwise)
{
    rod_scene *s = rod_new(G, 0.3, 1e6);
    s->spec.controller = CTC_CTRL_PID;
    s->gains[0] = (ctc_gains){.ki = 250, .kp = 100, .kv = 20};
    s->q0[0] = 1;
    ctc_sim_result *limited = fixture_run_done(&s->spec);
    s->spec.plant = NULL;
    ctc_sim_result *ideal = fixture_run_done(&s->spec);
    cr_assert_eq(limited->nsamples, ideal->nsamples);
    for (int c = 0; c < CTC_NCHANNELS; c++) {
        if (!ideal->ch[c]) continue;
        size_t n = (size_t)ideal->nsamples * (size_t)ideal->width[c] * sizeof(double);
        cr_expect_eq(memcmp(limited->ch[c], ideal->ch[c], n), 0, "channel %s differs",
                     ctc_channel_name((ctc_channel)c));
    }
    cr_expect_eq(limited->metrics.sat_fraction[0], 0);
    cr_expect_null(ideal->metrics.sat_fraction);
    cr_expect_eq(limited->metrics.tau_peak[0], ideal->metrics.tau_peak[0]);
    ctc_sim_result_free(limited);
    ctc_sim_result_free(ideal);
    rod_free(s);
}

Test(plant, negative_limit_and_passive_limit_are_refused)
{
    char err[256];
    rod_scene *s = rod_new(G, 0, -1);
    s->spec.controller = CTC_CTRL_PD;
    s->gains[0] = (ctc_gains){.kp = 100, .kv = 20};
    cr_assert_eq(ctc_sim_check(&s->spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "coordinate 0: torque_limit must be positive and finite, or 0 for none "
                          "(got -1)");
    s->plant[0].torque_limit = 2;
    s->spec.controller = CTC_CTRL_NONE;
    cr_assert_eq(ctc_sim_check(&s->spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "coordinate 0: torque_limit needs a controller (this run is passive)");
    rod_free(s);
}

/* the held pose of the first test, with a viscous joint: the swing dies out and the rod rests
   where the clipped actuator balances gravity, sin(q_eq) = L / (m g l/2) */
Test(plant, held_pose_beyond_the_limit_with_damping_rests_at_the_closed_form_equilibrium)
{
    const double L = 3, mgl2 = G * 0.5;
    rod_scene *s = rod_new(G, PI / 2, L);
    s->q0[0] = PI / 2;
    s->plant[0].viscous = 1;
    s->spec.controller = CTC_CTRL_PD;
    s->gains[0] = (ctc_gains){.kp = 100, .kv = 20};
    s->spec.duration = 40;
    s->spec.output_interval = 0.01;
    ctc_sim_result *r = fixture_run_done(&s->spec);
    int last = r->nsamples - 1;
    double q = r->ch[CTC_CH_Q][last], v = r->ch[CTC_CH_QD][last];
    cr_expect_leq(fabs(q - asin(L / mgl2)), 1e-9, "q %.12f, closed form %.12f", q, asin(L / mgl2));
    cr_expect_leq(fabs(v), 1e-9, "v %g", v);
    cr_expect_eq(r->ch[CTC_CH_TAU][last], L);
    ctc_sim_result_free(r);
    rod_free(s);
}

/* a passive rod without gravity under a constant load F (the disturbance) */
static ctc_sim_result *loaded_rod(double F, double coulomb, double vs, double duration)
{
    rod_scene *s = rod_new(0, 0, 0);
    static ctc_disturb z[1];
    z[0] = (ctc_disturb){.type = CTC_DISTURB_CONSTANT, .value = F};
    s->spec.disturb = z;
    s->spec.controller = CTC_CTRL_NONE;
    s->spec.traj = NULL;
    s->spec.gains = NULL;
    s->plant[0] = (ctc_plant_coord){.coulomb = coulomb, .coulomb_velocity = vs};
    s->spec.integrator = (ctc_integ_spec){.method = CTC_INTEG_BDF, .rtol = 1e-10, .atol = 1e-14};
    s->spec.duration = duration;
    s->spec.output_interval = 0.01;
    ctc_sim_result *r = fixture_run_done(&s->spec);
    rod_free(s);
    return r;
}

Test(plant, coulomb_friction_below_breakaway_holds_the_joint_up_to_its_creep)
{
    const double Fc = 1, vs = 1e-4, F = 0.5;
    ctc_sim_result *r = loaded_rod(F, Fc, vs, 2);
    const double creep = vs * atanh(F / Fc); /* 5.5e-5 rad/s */
    int last = r->nsamples - 1;
    double v = r->ch[CTC_CH_QD][last], q = r->ch[CTC_CH_Q][last];
    cr_expect_leq(fabs(v - creep), 1e-9 * creep + 1e-15, "v %.12g, creep %.12g", v, creep);
    cr_expect_leq(fabs(q), creep * 2 + 1e-12, "q %g after 2 s: more than the creep", q);
    cr_expect_gt(q, 0, "it creeps in the load's direction");
    ctc_sim_result_free(r);
}

Test(plant, coulomb_friction_above_breakaway_accelerates_as_the_closed_form)
{
    const double Fc = 1, vs = 1e-4, F = 2, ip = 1.0 / 3, a = (F - Fc) / ip;
    ctc_sim_result *r = loaded_rod(F, Fc, vs, 1);
    const double *v = r->ch[CTC_CH_QD], *q = r->ch[CTC_CH_Q];
    /* |v| >> vs after the first millisecond: v' = a exactly (tanh(v / vs) = 1 in doubles) */
    for (int j = 10; j < r->nsamples; j++) {
        double acc = (v[j] - v[j - 1]) / (r->t[j] - r->t[j - 1]);
        cr_expect_leq(fabs(acc - a), 1e-7 * a, "t = %g: acceleration %.12g, closed form %g",
                      r->t[j], acc, a);
    }
    /* the start, where tanh is still below 1, gains at most vs-sized speed over the closed form */
    int last = r->nsamples - 1;
    cr_expect_leq(fabs(q[last] - 0.5 * a), 1e-3, "q(1) %.9g, closed form %.9g", q[last], 0.5 * a);
    cr_expect_geq(q[last], 0.5 * a, "friction below its level at the start only helps");
    ctc_sim_result_free(r);
}

Test(plant, spring_and_damper_give_the_damped_oscillator)
{
    const double ip = 1.0 / 3, k = 3, b = 0.4, rest = 0.2, x0 = 0.8;
    rod_scene *s = rod_new(0, 0, 0);
    s->spec.controller = CTC_CTRL_NONE;
    s->spec.traj = NULL;
    s->q0[0] = rest + x0;
    s->plant[0] = (ctc_plant_coord){.viscous = b, .spring = k, .spring_rest = rest};
    ctc_sim_result *r = fixture_run_done(&s->spec);
    cr_expect(isnan(r->metrics.energy_drift), "the joint forces do work: no energy reference");
    const double sigma = b / (2 * ip), wd = sqrt(k / ip - sigma * sigma);
    double dev = 0;
    for (int j = 0; j < r->nsamples; j++) {
        double t = r->t[j];
        double x = exp(-sigma * t) * (x0 * cos(wd * t) + sigma * x0 / wd * sin(wd * t));
        dev = fmax(dev, fabs(r->ch[CTC_CH_Q][j] - rest - x));
    }
    cr_expect_leq(dev, 1e-8, "|q - closed form| = %g", dev);
    ctc_sim_result_free(r);
    rod_free(s);
}

/* a two-rod pendulum tracking sines with friction, spring and damper in both joints: known to
   the controller, the error obeys the linear law of an exact model again (errdyn_dev at the
   integrator's tolerance); unknown, it does not */
Test(plant, joint_forces_known_to_the_controller_keep_the_error_law_exact)
{
    ctc_plant_coord plant[2];
    for (int i = 0; i < 2; i++)
        plant[i] = (ctc_plant_coord){.viscous = 0.5,
                                     .coulomb = 2,
                                     .coulomb_velocity = 0.01,
                                     .spring = 5,
                                     .spring_rest = 0.1};
    ctc_sim_result *known, *unknown;
    fixture_run_known_and_unknown(plant, "forces", &known, &unknown);
    cr_expect_gt(unknown->metrics.e_final[0] * unknown->metrics.e_final[0] +
                     unknown->metrics.e_final[1] * unknown->metrics.e_final[1],
                 1e-6, "the unknown forces leave an error");
    ctc_sim_result_free(known);
    ctc_sim_result_free(unknown);
}

Test(plant, bad_joint_force_parameters_are_refused_with_their_names)
{
    char err[256];
    rod_scene *s = rod_new(G, 0, 0);
    s->spec.controller = CTC_CTRL_PD;
    s->gains[0] = (ctc_gains){.kp = 100, .kv = 20};
    s->plant[0].viscous = -1;
    cr_assert_eq(ctc_sim_check(&s->spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "coordinate 0: viscous must be non-negative and finite (got -1)");
    s->plant[0].viscous = 0;
    s->plant[0].coulomb = 1;
    cr_assert_eq(ctc_sim_check(&s->spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "coordinate 0: coulomb_velocity must be positive and finite with "
                          "coulomb friction (got 0)");
    s->plant[0].coulomb = 0;
    s->plant[0].spring = INFINITY;
    cr_assert_eq(ctc_sim_check(&s->spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "coordinate 0: spring must be non-negative and finite (got inf)");
    rod_free(s);
}
