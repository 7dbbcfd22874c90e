/*
 * test_armature.c - the armature, the actuator rotor's reflected inertia (plant.h): the plant's
 * forward dynamics with armature against the oracle, and CTC runs with a known and an unknown
 * armature.
 *
 * Oracles: the composite-rigid-body mass matrix plus diag(armature) and the Newton-Euler bias
 * forces h = RNEA(q, v, 0), so that (CRBA + diag(a)) qdd + h = f; the inverse GDCA plus the
 * armature's a qdd, iGDCA(qdd) + a qdd = f; the effective mass matrix's columns from differences
 * of forward solves, (CRBA + diag(a)) (GDCA_a(f + e_j) - GDCA_a(f)) = e_j. In a run: a rod on a
 * spring without gravity oscillates at omega = sqrt(k / (I_p + a)), and an exact model with the
 * armature known tracks with the linear error law of ctrl.h (the errdyn_dev metric).
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "ctc.h"
#include "gdca.h"
#include "handles.h"
#include "kinematics.h"
#include "oracle.h"
#include "plant.h"
#include "sim.h"
#include "model_fixture.h"
#include "oracle_fixture.h"
#include "run_fixture.h"

#define MAXV 128

/* the largest |x_i| over n, at least 1: the scale of a relative residual */
static double scale_of(int n, const double *x)
{
    double s = 1;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(x[i]));
    return s;
}

/* one model at a random state: the three oracles above, to 1e-10 relative; returns the worst */
static double check_model(const ctc_model *m, uint64_t seed, const char *what)
{
    const int nv = m->nv;
    cr_assert_leq(nv, MAXV);
    fx_rng rng = {seed};
    double q[4 * MAXV], v[MAXV], f[MAXV], arm[MAXV], qdd[MAXV], h[MAXV], tau[MAXV], zero[MAXV];
    double col[MAXV], fj[MAXV];
    static double mm[MAXV * MAXV];
    fx_random_state(&rng, m, q, v, f);
    for (int i = 0; i < nv; i++) {
        arm[i] = i % 3 == 1 ? 0 : fx_uniform(&rng, 0.01, 0.5); /* some coordinates without */
        zero[i] = 0;
    }
    ctc_oracle *o = ctc_oracle_new(m);
    ctc_data *d = ctc_data_new(m);
    cr_assert(o && d);
    double *work = malloc((size_t)ctc_plant_armature_work(nv, nv) * sizeof *work);
    cr_assert_not_null(work);
    ctc_kinematics(m, d, q, v);
    ctc_handles(m, d);
    ctc_plant_forward_armature(m, d, arm, f, qdd, work);

    /* (CRBA + diag(a)) qdd + RNEA(q, v, 0) = f */
    ctc_oracle_mass_matrix(m, o, q, mm);
    ctc_oracle_rnea(m, o, q, v, zero, h);
    const double fs = scale_of(nv, f);
    double worst = 0;
    for (int i = 0; i < nv; i++) {
        double r = h[i] + arm[i] * qdd[i] - f[i];
        for (int j = 0; j < nv; j++) r += mm[i * nv + j] * qdd[j];
        worst = fmax(worst, fabs(r) / fs);
    }
    cr_expect_leq(worst, 1e-10, "%s: (CRBA + diag(a)) qdd + h - f = %.3e relative", what, worst);

    /* iGDCA(qdd) + a qdd = f */
    ctc_gdca_inverse(m, d, qdd, tau);
    double inv = 0;
    for (int i = 0; i < nv; i++) inv = fmax(inv, fabs(tau[i] + arm[i] * qdd[i] - f[i]) / fs);
    cr_expect_leq(inv, 1e-10, "%s: iGDCA(qdd) + a qdd - f = %.3e relative", what, inv);
    worst = fmax(worst, inv);

    /* the effective mass matrix: (CRBA + diag(a)) (GDCA_a(f + e_j) - GDCA_a(f)) = e_j */
    for (int j = 0; j < nv; j++) {
        memcpy(fj, f, (size_t)nv * sizeof *fj);
        fj[j] += 1;
        ctc_plant_forward_armature(m, d, arm, fj, col, work);
        for (int i = 0; i < nv; i++) col[i] -= qdd[i];
        for (int i = 0; i < nv; i++) {
            double r = arm[i] * col[i] - (i == j);
            for (int k = 0; k < nv; k++) r += mm[i * nv + k] * col[k];
            cr_expect_leq(fabs(r), 1e-9 * fs, "%s: M_a column %d, row %d: %.3e", what, j, i, r);
            worst = fmax(worst, fabs(r) / fs);
        }
    }
    free(work);
    ctc_data_free(d);
    ctc_oracle_free(o);
    return worst;
}

Test(armature, forward_matches_crba_plus_diag_and_rnea_on_chains_and_trees)
{
    const int n[] = {1, 2, 5, 9, 16};
    double worst = 0;
    for (int i = 0; i < 5; i++) {
        test_chain *c = test_chain_random_spatial(n[i], 300 + (uint64_t)i, TEST_ALL_JOINTS);
        ctc_model *m = build(&c->spec);
        worst = fmax(worst, check_model(m, 310 + (uint64_t)i, "spatial chain"));
        ctc_model_free(m);
        int parent[16];
        test_random_parents(n[i], 320 + (uint64_t)i, 0.2, parent);
        test_chain_set_parents(c, parent);
        m = build(&c->spec);
        worst = fmax(worst, check_model(m, 330 + (uint64_t)i, "spatial tree"));
        ctc_model_free(m);
        test_chain_free(c);
        c = test_chain_random_planar(n[i], 340 + (uint64_t)i, 1, 0);
        test_chain_set_parents(c, parent);
        m = build(&c->spec);
        worst = fmax(worst, check_model(m, 350 + (uint64_t)i, "planar tree"));
        ctc_model_free(m);
        test_chain_free(c);
    }
    cr_log_info("armature: worst relative residual %.3e", worst);
}

/* no gravity, a spring k: (I_p + a) q'' + k q = 0, so q = x0 cos(omega t), omega^2 = k/(I_p + a) */
Test(armature, rod_on_a_spring_oscillates_at_the_closed_form_frequency)
{
    test_chain *chain = test_chain_rod_pendulum(1, 1, 1);
    chain->spec.gravity[1] = 0;
    const double ip = 1.0 / 3, a = 0.25, k = 4, x0 = 0.3;
    double q0[1] = {x0}, v0[1] = {0};
    ctc_plant_coord plant[1] = {{.spring = k, .armature = a}};
    ctc_sim_spec spec = fixture_passive_spec(
        &chain->spec, q0, v0,
        (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-11, .atol = 1e-13}, 3, 0.01);
    spec.plant = plant;
    ctc_sim_result *r = fixture_run_done(&spec);
    const double w = sqrt(k / (ip + a));
    double dev = 0;
    for (int j = 0; j < r->nsamples; j++)
        dev = fmax(dev, fabs(r->ch[CTC_CH_Q][j] - x0 * cos(w * r->t[j])));
    cr_expect_leq(dev, 1e-8, "|q - x0 cos(omega t)| = %g", dev);
    cr_expect(isnan(r->metrics.energy_drift), "the rotor's energy is not the bodies'");
    ctc_sim_result_free(r);
    test_chain_free(chain);
}

/* two rods tracking sines with PD: a known armature keeps the linear error law (errdyn_dev at
   the integrator's tolerance), an unknown one leaves an error */
Test(armature, known_armature_keeps_the_error_law_exact)
{
    ctc_plant_coord plant[2];
    for (int i = 0; i < 2; i++) plant[i] = (ctc_plant_coord){.armature = 0.4 - 0.15 * i};
    ctc_sim_result *known, *unknown;
    fixture_run_known_and_unknown(plant, "armature", &known, &unknown);
    cr_expect_gt(fabs(unknown->metrics.e_rms[0]) - fabs(known->metrics.e_rms[0]), 1e-4,
                 "the unknown armature adds error: rms %g against %g", unknown->metrics.e_rms[0],
                 known->metrics.e_rms[0]);
    ctc_sim_result_free(known);
    ctc_sim_result_free(unknown);
}

Test(armature, negative_or_nan_armature_is_refused)
{
    test_chain *chain = test_chain_rod_pendulum(1, 1, 1);
    double q0[1] = {0}, v0[1] = {0};
    ctc_plant_coord plant[1] = {{.armature = -1}};
    ctc_sim_spec spec = fixture_passive_spec(
        &chain->spec, q0, v0,
        (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-8, .atol = 1e-10}, 1, 0.01);
    spec.plant = plant;
    char err[256];
    cr_assert_eq(ctc_sim_check(&spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "coordinate 0: armature must be non-negative and finite (got -1)");
    plant[0].armature = NAN;
    cr_assert_eq(ctc_sim_check(&spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "coordinate 0: armature must be non-negative and finite (got nan)");
    test_chain_free(chain);
}
