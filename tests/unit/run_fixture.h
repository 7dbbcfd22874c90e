/*
 * run_fixture.h - runs of the library's simulation (sim.h) that a test expects to finish, and the
 * recipes several test files share; tests/unit only.
 *
 * The helpers fail the test with the library's message when a run is refused or does not end
 * CTC_RUN_DONE. Results are the caller's to free (ctc_sim_result_free); the chains and specs given
 * stay the caller's.
 */
#ifndef CTC_RUN_FIXTURE_H
#define CTC_RUN_FIXTURE_H

#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "chains.h"
#include "sim.h"

/* The result of running spec to its end; fails the test unless ctc_sim_run returns CTC_OK and
 * the run is CTC_RUN_DONE (with the library's message). The caller frees the result
 * (ctc_sim_result_free). */
static inline ctc_sim_result *fixture_run_done(const ctc_sim_spec *spec)
{
    ctc_sim_result *r = NULL;
    char err[256] = "";
    cr_assert_eq(ctc_sim_run(spec, NULL, &r, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s", r->message);
    return r;
}

/* A passive run's spec for chain (no controller, the exact model): from q0 (nq; NULL = the
 * chain's zero pose) and v0 (nv; NULL = at rest), by integ for duration s, sampled
 * output_interval s apart. The arrays stay the caller's; set any other field on the result. */
static inline ctc_sim_spec fixture_passive_spec(const ctc_chain_spec *chain, const double *q0,
                                                const double *v0, ctc_integ_spec integ,
                                                double duration, double output_interval)
{
    ctc_sim_spec spec = {.chain = *chain, .q0 = q0, .v0 = v0, .controller = CTC_CTRL_NONE};
    spec.model_mass_scale = spec.model_inertia_scale = 1;
    spec.integrator = integ;
    spec.duration = duration;
    spec.output_interval = output_interval;
    return spec;
}

/* A PD run's spec for chain (the plant, kept by the caller): from q0 (nq; NULL = the chain's zero
 * pose) at rest, gains and traj per coordinate, with the exact model (mass and inertia scales 1),
 * by integ for duration s, sampled output_interval s apart. The arrays stay the caller's and must
 * outlive the runs of the spec; set any other field on the result. */
static inline ctc_sim_spec fixture_pd_spec(const ctc_chain_spec *chain, const double *q0,
                                           const ctc_gains *gains, const ctc_traj *traj,
                                           ctc_integ_spec integ, double duration,
                                           double output_interval)
{
    ctc_sim_spec spec = {.chain = *chain, .q0 = q0, .controller = CTC_CTRL_PD, .gains = gains};
    spec.model_mass_scale = spec.model_inertia_scale = 1;
    spec.traj = traj;
    spec.integrator = integ;
    spec.duration = duration;
    spec.output_interval = output_interval;
    return spec;
}

/* The PD run to rest of chain (n bodies on one-coordinate joints): q0_k = -q0 for even k and +q0
 * for odd k (rad), at rest, q_d = 0, kp = 100 s^-2 and kv = 20 s^-1 on every joint, the
 * controller's model with its masses scaled by mass_scale, by integ for duration s, sampled
 * output_interval s apart, on threads threads (ctc_sim_spec.threads). Fails the test unless it
 * runs to the end. The caller keeps chain and frees the result. */
static inline ctc_sim_result *fixture_pd_to_rest(const test_chain *chain, double q0,
                                                 double mass_scale, ctc_integ_spec integ,
                                                 double duration, double output_interval,
                                                 int threads)
{
    int n = chain->spec.nbodies;
    double *q = calloc((size_t)n, sizeof *q);
    ctc_gains *gains = calloc((size_t)n, sizeof *gains);
    ctc_traj *traj = calloc((size_t)n, sizeof *traj);
    cr_assert(q && gains && traj);
    for (int k = 0; k < n; k++) {
        q[k] = (k % 2 ? 1 : -1) * q0;
        gains[k] = (ctc_gains){.kp = 100, .kv = 20};
        traj[k] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = 0};
    }
    ctc_sim_spec spec =
        fixture_pd_spec(&chain->spec, q, gains, traj, integ, duration, output_interval);
    spec.model_mass_scale = mass_scale;
    spec.threads = threads;
    ctc_sim_result *r = fixture_run_done(&spec);
    free(q), free(gains), free(traj);
    return r;
}

/* Over channel ch's samples of two runs of the same length (ch recorded in both): the largest
 * |a - b| into *diff and the largest |a| into *big. */
static inline void fixture_channel_diff(const ctc_sim_result *a, const ctc_sim_result *b,
                                        ctc_channel ch, double *diff, double *big)
{
    size_t count = (size_t)a->nsamples * (size_t)a->width[ch];
    *diff = 0, *big = 0;
    for (size_t i = 0; i < count; i++) {
        *big = fmax(*big, fabs(a->ch[ch][i]));
        *diff = fmax(*diff, fabs(a->ch[ch][i] - b->ch[ch][i]));
    }
}

/* Known and unknown plant forces on a tracking run: the two-rod pendulum (1 m, 1 kg rods,
 * test_chain_rod_pendulum) from q0 = (0.3, -0.2) rad at rest tracks q_d = 0.6 sin(2 pi t / 1.5)
 * rad on both joints with PD (kp = 100 s^-2, kv = 20 s^-1, exact model) for 3 s by dopri5
 * (rtol 1e-10, atol 1e-12), with plant[2] in both joints: once known to the controller (known = 1;
 * then the error obeys the linear law, errdyn_dev <= 1e-7 is checked), once unknown (known = 0;
 * then there is no linear reference, errdyn_dev is NaN, checked). what names the forces in the
 * messages. plant's known flags are overwritten. The caller frees both results. */
static inline void fixture_run_known_and_unknown(ctc_plant_coord plant[2], const char *what,
                                                 ctc_sim_result **known, ctc_sim_result **unknown)
{
    test_chain *chain = test_chain_rod_pendulum(2, 1, 1);
    ctc_gains gains[2];
    ctc_traj traj[2];
    double q0[2] = {0.3, -0.2}, v0[2] = {0, 0};
    for (int i = 0; i < 2; i++) {
        gains[i] = (ctc_gains){.kp = 100, .kv = 20};
        traj[i] = (ctc_traj){.type = CTC_TRAJ_SINE, .amplitude = 0.6, .period = 1.5};
        plant[i].known = 1;
    }
    ctc_sim_spec spec = fixture_pd_spec(
        &chain->spec, q0, gains, traj,
        (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-10, .atol = 1e-12}, 3, 0.01);
    spec.v0 = v0;
    spec.plant = plant;
    *known = fixture_run_done(&spec);
    cr_expect_leq((*known)->metrics.errdyn_dev, 1e-7, "known: errdyn_dev %g",
                  (*known)->metrics.errdyn_dev);
    for (int i = 0; i < 2; i++) plant[i].known = 0;
    *unknown = fixture_run_done(&spec);
    cr_expect(isnan((*unknown)->metrics.errdyn_dev), "unknown %s: no linear reference", what);
    test_chain_free(chain);
}

#endif
