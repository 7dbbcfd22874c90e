/*
 * test_sampled.c - the sampled controller with zero-order hold and a delay of whole samples
 * (sim.h sample_period, sample_delay), against the closed-form discrete-time solution.
 *
 * The scene is a rod about a pivot without gravity (I_p = 1/3 kg m^2), regulated to a constant
 * q_d: with an exact model the command f_k = I_p u_k makes q'' = u_k exactly while it is held,
 * so the error e = q_d - q at the samples t_k = k T obeys the ZOH double integrator
 *     e_k+1 = e_k + T de_k - T^2/2 u_(k-d),   de_k+1 = de_k - T u_(k-d)   (u = 0 before t_d)
 *     u_k = ki xi_k + kp e_k + kv de_k,        xi_k+1 = xi_k + T e_k
 * which the test iterates; between samples the plant's motion is a parabola, which the
 * integrator reproduces to rounding, so the run must match to 1e-10. With noisy, quantised
 * sensors (plant.h) the controller's e and de are the measured ones, drawn here from the
 * generator plant.h specifies, written out apart from the library's.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "sim.h"
#include "run_fixture.h"

typedef struct sampled_case {
    ctc_gains g;
    double period;
    int delay;
    ctc_integ_method method;
    double noise_q, noise_v, resolution; /* the sensors (plant.h) */
    unsigned long long seed;
} sampled_case;

static ctc_sim_result *run_rod(const sampled_case *sc, double q0, double qd, double duration)
{
    test_chain *chain = test_chain_rod_pendulum(1, 1, 1);
    chain->spec.gravity[1] = 0;
    double q0v[1] = {q0}, v0[1] = {0};
    ctc_traj traj[1] = {{.type = CTC_TRAJ_CONSTANT, .value = qd}};
    ctc_gains gains[1] = {sc->g};
    ctc_plant_coord plant[1] = {
        {.noise_q = sc->noise_q, .noise_v = sc->noise_v, .resolution = sc->resolution}};
    ctc_sim_spec spec = {
        .chain = chain->spec,
        .q0 = q0v,
        .v0 = v0,
        .controller = sc->g.ki > 0 ? CTC_CTRL_PID : CTC_CTRL_PD,
        .gains = gains,
        .model_mass_scale = 1,
        .model_inertia_scale = 1,
        .traj = traj,
        .sample_period = sc->period,
        .sample_delay = sc->delay,
        .seed = sc->seed,
        .plant = ctc_plant_has_sensor_error(plant) ? plant : NULL,
        .integrator = {.method = sc->method, .rtol = 1e-12, .atol = 1e-14, .step = sc->period / 4},
        .duration = duration,
        .output_interval = sc->period};
    ctc_sim_result *r = fixture_run_done(&spec);
    test_chain_free(chain);
    return r;
}

/* the sensors' generator as plant.h states it: splitmix64, 53-bit uniforms, Box-Muller's cosine */
static double test_uniform53(unsigned long long *s)
{
    unsigned long long z = (*s += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    return (double)((z ^ (z >> 31)) >> 11) / 9007199254740992.0;
}

static double test_normal(unsigned long long *s)
{
    double a = test_uniform53(s), b = test_uniform53(s);
    return sqrt(-2 * log(1 - a)) * cos(2 * 3.14159265358979323846 * b);
}

/* the largest deviation of the run's error and w from the discrete-time recursion, in which
   the controller sees the measured error: the true one less the sensors' noise, then the
   encoder's rounding of the position (q_d - q_m, -v_m) */
static double discrete_deviation(const sampled_case *sc, const ctc_sim_result *r, double e0)
{
    const double T = sc->period, qd = r->ch[CTC_CH_Q_DES][0];
    const int d = sc->delay;
    unsigned long long rng = sc->seed;
    double e = e0, de = 0, xi = 0, dev = 0;
    double *u = calloc((size_t)r->nsamples + 1, sizeof *u);
    cr_assert_not_null(u);
    for (int k = 0; k < r->nsamples; k++) {
        cr_assert_leq(fabs(r->t[k] - k * T), 1e-12, "sample %d at t = %.17g", k, r->t[k]);
        dev = fmax(dev, fabs(r->ch[CTC_CH_E][k] - e));
        double qm = qd - e, vm = -de; /* the plant's q and v at t_k */
        if (sc->noise_q > 0) qm += sc->noise_q * test_normal(&rng);
        if (sc->noise_v > 0) vm += sc->noise_v * test_normal(&rng);
        if (sc->resolution > 0) qm = sc->resolution * round(qm / sc->resolution);
        double em = qd - qm, dem = -vm;
        u[k] = sc->g.ki * xi + sc->g.kp * em + sc->g.kv * dem;
        double applied = k >= d ? u[k - d] : 0;
        /* the w channel shows the command being applied (the delayed one) */
        dev = fmax(dev, fabs(r->ch[CTC_CH_W][k] - applied) * T * T);
        xi += T * em;
        e += T * de - 0.5 * T * T * applied;
        de -= T * applied;
    }
    free(u);
    return dev;
}

Test(sampled, pd_with_zero_order_hold_matches_the_discrete_closed_form)
{
    const sampled_case sc = {
        .g = {.kp = 100, .kv = 20}, .period = 0.01, .method = CTC_INTEG_DOPRI5};
    ctc_sim_result *r = run_rod(&sc, 0, 1, 2);
    double dev = discrete_deviation(&sc, r, 1);
    cr_expect_leq(dev, 1e-10, "|e - discrete closed form| = %g", dev);
    cr_expect_geq(r->metrics.steps, r->nsamples - 1, "one restart per sample at least");
    cr_expect(isnan(r->metrics.errdyn_dev), "no continuous error law for a sampled controller");
    ctc_sim_result_free(r);
}

Test(sampled, pid_with_a_delay_of_two_samples_matches_the_discrete_closed_form)
{
    const sampled_case sc = {
        .g = {.ki = 10, .kp = 16, .kv = 6}, .period = 0.02, .delay = 2, .method = CTC_INTEG_DOPRI5};
    ctc_sim_result *r = run_rod(&sc, 0.5, -0.25, 3);
    double dev = discrete_deviation(&sc, r, -0.75);
    cr_expect_leq(dev, 1e-10, "|e - discrete closed form| = %g", dev);
    ctc_sim_result_free(r);
}

Test(sampled, every_integrator_restarts_on_the_samples)
{
    sampled_case sc = {.g = {.kp = 25, .kv = 10}, .period = 0.05, .delay = 1};
    const ctc_integ_method methods[3] = {CTC_INTEG_RK4, CTC_INTEG_DOPRI5, CTC_INTEG_BDF};
    for (int m = 0; m < 3; m++) {
        sc.method = methods[m];
        ctc_sim_result *r = run_rod(&sc, 0, 1, 2);
        double dev = discrete_deviation(&sc, r, 1);
        /* bdf's error control is looser on a parabola than the explicit methods' */
        cr_expect_leq(dev, m == 2 ? 1e-8 : 1e-10, "method %d: deviation %g", m, dev);
        ctc_sim_result_free(r);
    }
}

Test(sampled, a_delay_without_a_period_and_bad_periods_are_refused)
{
    test_chain *chain = test_chain_rod_pendulum(1, 1, 1);
    ctc_traj traj[1] = {{.type = CTC_TRAJ_CONSTANT, .value = 0}};
    ctc_gains gains[1] = {{.kp = 1, .kv = 2}};
    ctc_sim_spec spec = {.chain = chain->spec,
                         .controller = CTC_CTRL_PD,
                         .gains = gains,
                         .model_mass_scale = 1,
                         .model_inertia_scale = 1,
                         .traj = traj,
                         .sample_delay = 1,
                         .integrator = {.method = CTC_INTEG_DOPRI5, .rtol = 1e-8, .atol = 1e-10},
                         .duration = 1,
                         .output_interval = 0.1};
    char err[256];
    cr_assert_eq(ctc_sim_check(&spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "sample_delay needs a sample_period (a continuous controller has no "
                          "samples to delay)");
    spec.sample_delay = 0;
    spec.sample_period = -0.01;
    cr_assert_eq(ctc_sim_check(&spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "sample_period must be >= 0 and finite (got -0.01 s; 0 = continuous)");
    spec.sample_period = 0.01;
    spec.controller = CTC_CTRL_NONE;
    cr_assert_eq(ctc_sim_check(&spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "sample_period needs a controller (this run is passive)");
    test_chain_free(chain);
}

/* noisy encoders with counts of 1 mrad, PID, a delay of one sample: the same recursion with the
   measurement the test draws from the generator plant.h specifies */
Test(sampled, noisy_quantised_sensors_match_the_discrete_closed_form)
{
    const sampled_case sc = {.g = {.ki = 10, .kp = 16, .kv = 6},
                             .period = 0.01,
                             .delay = 1,
                             .method = CTC_INTEG_DOPRI5,
                             .noise_q = 2e-3,
                             .noise_v = 0.05,
                             .resolution = 1e-3,
                             .seed = 12345};
    ctc_sim_result *r = run_rod(&sc, 0, 1, 2);
    double dev = discrete_deviation(&sc, r, 1);
    cr_expect_leq(dev, 1e-10, "|e - discrete closed form| = %g", dev);
    ctc_sim_result_free(r);
}

/* the same seed gives the same run bit for bit; another seed another run */
Test(sampled, the_seed_fixes_the_noise_bit_for_bit)
{
    sampled_case sc = {.g = {.kp = 100, .kv = 20},
                       .period = 0.005,
                       .method = CTC_INTEG_DOPRI5,
                       .noise_q = 1e-3,
                       .noise_v = 1e-2,
                       .seed = 7};
    ctc_sim_result *a = run_rod(&sc, 0, 1, 1), *b = run_rod(&sc, 0, 1, 1);
    sc.seed = 8;
    ctc_sim_result *c = run_rod(&sc, 0, 1, 1);
    size_t n = (size_t)a->nsamples * (size_t)a->width[CTC_CH_Q] * sizeof(double);
    cr_assert_eq(a->nsamples, b->nsamples);
    cr_expect_eq(memcmp(a->ch[CTC_CH_Q], b->ch[CTC_CH_Q], n), 0, "seed 7 twice: q differs");
    cr_expect_eq(memcmp(a->ch[CTC_CH_TAU], b->ch[CTC_CH_TAU], n), 0, "seed 7 twice: tau differs");
    cr_expect_neq(memcmp(a->ch[CTC_CH_Q], c->ch[CTC_CH_Q], n), 0, "seeds 7 and 8: the same q");
    ctc_sim_result_free(a);
    ctc_sim_result_free(b);
    ctc_sim_result_free(c);
}
