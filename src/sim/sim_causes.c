/*
 * sim_causes.c - the tracking error by cause (sim.h metrics.err_cause): how much of a run's error
 * its sampled controller, its sensors and its controller's model cause, each measured against
 * counterfactual runs that differ from the run by that cause alone.
 *
 * A run whose controller has any of the causes S (a sample period, with its delay), N (noise or
 * quantisation of its sensors, read at the samples) and M (a controller model other than the
 * plant: per-body values, scales, gravity; a payload the plant carries) is run again with the
 * same plant, trajectory, disturbance, wrenches, integrator and output samples, recording e only:
 *     e_0   the ideal: continuous controller, exact sensors, the plant as the model
 *     e_S   sampled as the run, exact sensors and model        (when S)
 *     e_SN  sampled with the run's sensors, exact model         (when N)
 *     e_M   continuous, exact sensors, the run's model          (when M)
 * and the rows are RMS over the samples of e_S - e_0 (sampling), e_SN - e_S (noise: the sensors
 * are read at the samples only, so noise is measured on top of sampling), e_M - e_0 (model) and
 * e - e_0 (total, the run's own error). A counterfactual run that is the run itself (one cause
 * alone) is not repeated. The shares need not add up to the total: the causes interact (a model
 * error's effect changes with the sample period), and the total says by how much.
 * Noise on a continuous controller is never read (sim.h), so N counts only with S. A
 * run that stopped early (diverged, cancelled, ...) has NaN in every row when it has a cause. A
 * counterfactual that does not run to its end (diverged, failed, out of wall time) leaves NaN in
 * the rows that need it. The runs share the spec's wall_limit with the run itself: each gets
 * what the run and the runs before it left of it. Their time is not part of the run's wall_s
 * and cpu_s.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim_internal.h"

enum { CAUSE_S = 1, CAUSE_N = 2, CAUSE_M = 4 };

/* the causes spec s has (above) */
static unsigned causes_of(const ctc_sim_spec *s, int nind)
{
    unsigned x = 0;
    if (s->sample_period > 0) x |= CAUSE_S;
    for (int i = 0; (x & CAUSE_S) && s->plant && i < nind; i++)
        if (ctc_plant_has_sensor_error(&s->plant[i])) x |= CAUSE_N;
    if (s->model_bodies || s->model_gravity || s->model_mass_scale != 1 ||
        s->model_inertia_scale != 1)
        x |= CAUSE_M;
    return x;
}

/* The run of spec s with the causes x only, recording e: *out, or NULL when it did not run to
 * its end (a cancelled run sets *cancelled). plant is scratch of nind coordinates. */
static ctc_status run_with(const ctc_sim_spec *s, unsigned x, int nind, ctc_plant_coord *plant,
                           const ctc_sim_hooks *hooks, double *wall_used, ctc_sim_result **out,
                           int *cancelled, char *err, size_t errlen)
{
    ctc_sim_spec cf = *s;
    *out = NULL;
    if (s->wall_limit > 0) {
        cf.wall_limit = s->wall_limit - *wall_used;
        if (!(cf.wall_limit > 0)) return CTC_OK;
    }
    cf.channels = CTC_CH_BIT(CTC_CH_E);
    cf.end_effector = NULL;
    cf.pose_bodies = NULL, cf.npose = 0;
    if (!(x & CAUSE_S)) cf.sample_period = 0, cf.sample_delay = 0;
    if (!(x & CAUSE_N) && s->plant) {
        memcpy(plant, s->plant, (size_t)nind * sizeof *plant);
        for (int i = 0; i < nind; i++)
            plant[i].noise_q = plant[i].noise_v = plant[i].resolution = 0;
        cf.plant = plant;
    }
    if (!(x & CAUSE_M)) {
        cf.model_bodies = NULL, cf.model_gravity = NULL;
        cf.model_mass_scale = cf.model_inertia_scale = 1;
    }
    ctc_sim_hooks h = {.ctx = hooks->ctx, .cancelled = hooks->cancelled};
    ctc_sim_result *r = NULL;
    ctc_status st = sim_run_once(&cf, &h, &r, err, errlen);
    if (st != CTC_OK) return st;
    *wall_used += r->metrics.wall_s;
    *cancelled |= r->status == CTC_RUN_CANCELLED;
    if (r->status != CTC_RUN_DONE) {
        ctc_sim_result_free(r);
        return CTC_OK;
    }
    *out = r;
    return CTC_OK;
}

/* row (nind) = RMS over the samples of a's e minus b's; NaN when either is missing */
static void rms_difference(const ctc_sim_result *a, const ctc_sim_result *b, int nind, double *row)
{
    for (int i = 0; i < nind; i++) row[i] = NAN;
    if (!a || !b || !a->ch[CTC_CH_E] || !b->ch[CTC_CH_E] || a->nsamples != b->nsamples ||
        a->nsamples == 0)
        return;
    for (int i = 0; i < nind; i++) {
        double sum = 0;
        for (int j = 0; j < a->nsamples; j++) {
            double d = a->ch[CTC_CH_E][(size_t)j * (size_t)nind + (size_t)i] -
                       b->ch[CTC_CH_E][(size_t)j * (size_t)nind + (size_t)i];
            sum += d * d;
        }
        row[i] = sqrt(sum / a->nsamples);
    }
}

ctc_status sim_error_by_cause(const ctc_sim_spec *s, const ctc_sim_hooks *hooks, ctc_sim_result *r,
                              char *err, size_t errlen)
{
    const int nind = r->nind;
    double *rows = r->metrics.err_cause;
    const unsigned x = causes_of(s, nind);
    if (!rows || x == 0) return CTC_OK;
    if (r->status != CTC_RUN_DONE) { /* a run stopped early has no shares to measure */
        for (size_t i = 0; i < (size_t)CTC_NCAUSES * (size_t)nind; i++) rows[i] = NAN;
        return CTC_OK;
    }
    ctc_plant_coord *plant = calloc((size_t)nind + 1, sizeof *plant);
    ctc_sim_result *run[8] = {0}; /* by causes; the run itself at x when it recorded e */
    int cancelled = 0;
    double wall_used = r->metrics.wall_s;
    ctc_status st = plant ? CTC_OK : ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    const unsigned need[] = {0, CAUSE_S, CAUSE_S | CAUSE_N, CAUSE_M, x};
    for (size_t k = 0; st == CTC_OK && !cancelled && k < sizeof need / sizeof *need; k++) {
        const unsigned y = need[k];
        if ((y & ~x) || run[y] || (y == x && r->ch[CTC_CH_E])) continue;
        st = run_with(s, y, nind, plant, hooks, &wall_used, &run[y], &cancelled, err, errlen);
    }
    if (st == CTC_OK && cancelled) {
        r->status = CTC_RUN_CANCELLED;
        strcpy(r->message, "cancelled while computing the error by cause");
    }
    if (st == CTC_OK && !cancelled) {
        const ctc_sim_result *self = r->ch[CTC_CH_E] ? r : run[x];
#define ROW(c) (rows + (size_t)(c) * (size_t)nind)
#define GET(y) ((y) == x ? self : run[y])
        if (x & CAUSE_S) rms_difference(GET(CAUSE_S), GET(0), nind, ROW(CTC_CAUSE_SAMPLING));
        if (x & CAUSE_N)
            rms_difference(GET(CAUSE_S | CAUSE_N), GET(CAUSE_S), nind, ROW(CTC_CAUSE_NOISE));
        if (x & CAUSE_M) rms_difference(GET(CAUSE_M), GET(0), nind, ROW(CTC_CAUSE_MODEL));
        rms_difference(self, GET(0), nind, ROW(CTC_CAUSE_TOTAL));
#undef GET
#undef ROW
    }
    for (int k = 0; k < 8; k++) ctc_sim_result_free(run[k]);
    free(plant);
    return st;
}
