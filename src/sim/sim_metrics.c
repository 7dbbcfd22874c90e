/*
 * sim_metrics.c - the figures of a run (sim.h ctc_sim_metrics): tracking errors, the energy
 * drift of a passive run, the deviation from the linear error dynamics, the integrator's and
 * the loop's figures, gathered at the output samples and completed at the run's end.
 *
 * The error-dynamics reference: with an exact model and no disturbance, a controller whose law
 * is the linear feedback w = K E (its class's closed_loop hook, ctrl.h) makes each coordinate's
 * error state E = (int e, e, de) obey dE/dt = Ac E exactly, so E(t) = expm(Ac t) E(0). The
 * reference is propagated from sample to sample with the 3x3 transition matrix of one output
 * interval (a shorter last interval gets its own), and errdyn_dev is the largest deviation of e
 * from it; saturation (plant.h) breaks the linear law, so a run with limits has no such reference.
 * The actuators' figures are those of sat(f), the force the actuator delivers, at the samples:
 * the peak and RMS, and the fraction of the samples at which it was clipped. The energy reference:
 * passive, no disturbance, E = KE + PE is conserved, and energy_drift is max |E(t) - E(0)| relative
 * to max(|E(0)|, the largest KE).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sim_internal.h"

static int has_disturbance(const ctc_sim_spec *s, int nv)
{
    if (!s->disturb) return 0;
    for (int i = 0; i < nv; i++)
        if (s->disturb[i].type != CTC_DISTURB_NONE) return 1;
    return 0;
}

/* 3x3 matrix exponential by scaling and squaring of a degree-18 Taylor polynomial */
static void expm3(const double a[9], double t, double out[9])
{
    double norm = 0;
    for (int i = 0; i < 9; i++) norm = fmax(norm, fabs(a[i] * t));
    int squarings = 0;
    while (norm * 3 > 0.5 && squarings < 60) {
        norm *= 0.5;
        squarings++;
    }
    double scale = ldexp(t, -squarings), x[9], term[9], sum[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int i = 0; i < 9; i++) x[i] = a[i] * scale;
    memcpy(term, sum, sizeof term);
    for (int k = 1; k <= 18; k++) {
        double next[9];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                next[3 * i + j] =
                    (term[3 * i] * x[j] + term[3 * i + 1] * x[3 + j] + term[3 * i + 2] * x[6 + j]) /
                    k;
        memcpy(term, next, sizeof term);
        for (int i = 0; i < 9; i++) sum[i] += term[i];
    }
    for (int s = 0; s < squarings; s++) {
        double sq[9];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                sq[3 * i + j] =
                    sum[3 * i] * sum[j] + sum[3 * i + 1] * sum[3 + j] + sum[3 * i + 2] * sum[6 + j];
        memcpy(sum, sq, sizeof sum);
    }
    memcpy(out, sum, sizeof sum);
}

ctc_status sim_metrics_init(const sim_ctx *c, recorder *rec, int exact, size_t nv)
{
    const ctc_sim_spec *spec = c->spec;
    rec->track_energy =
        !c->active && !has_disturbance(spec, c->nind) && !c->jforces && !c->armed && !c->wrenched;
    rec->track_errdyn = c->active && exact && c->cls->closed_loop &&
                        !has_disturbance(spec, c->nind) && !c->limited && c->jknown && !c->sampled;
    rec->e_sq = calloc(nv * 3, sizeof(double));
    rec->phi = calloc(nv * 12, sizeof(double));
    if (!rec->e_sq || !rec->phi) return CTC_ENOMEM;
    rec->tau_sq = rec->e_sq + nv, rec->sat_n = rec->tau_sq + nv;
    rec->eref = rec->phi + 9 * nv;
    if (rec->track_errdyn) {
        for (int i = 0; i < c->nind; i++) {
            double a[9];
            c->cls->closed_loop(&spec->gains[i], a);
            expm3(a, rec->dt, rec->phi + 9 * i);
        }
    }
    return CTC_OK;
}

void sim_metrics_sample(const sim_ctx *c, recorder *rec, long j, double t, const double *y,
                        double ke, double pe)
{
    ctc_sim_result *r = rec->r;
    ctc_sim_metrics *mt = &r->metrics;
    if (c->active) {
        for (int i = 0; i < c->nind; i++) {
            double e = c->des[3 * i] - c->qi[i];
            mt->e_max[i] = fmax(mt->e_max[i], fabs(e));
            rec->e_sq[i] += e * e;
            mt->e_final[i] = e;
            double f = c->f[c->plant->ind_coord[i]];
            mt->tau_peak[i] = fmax(mt->tau_peak[i], fabs(f));
            rec->tau_sq[i] += f * f;
            if (c->limited && c->clip[i] != 0) rec->sat_n[i]++;
        }
    }
    if (rec->track_energy) {
        if (j == 0) rec->e0 = ke + pe;
        rec->ke_max = fmax(rec->ke_max, ke);
        rec->drift = fmax(rec->drift, fabs(ke + pe - rec->e0));
    }
    if (rec->track_errdyn) {
        const double *ie = y + c->nq + c->nv;
        for (int i = 0; i < c->nind; i++) {
            double *er = rec->eref + 3 * i;
            if (j == 0) {
                mt->errdyn_dev = 0;
                er[0] = ie[i], er[1] = c->des[3 * i] - c->qi[i];
                er[2] = c->des[3 * i + 1] - c->vi[i];
            } else {
                double phi[9], next[3];
                const double *p = rec->phi + 9 * i;
                if (fabs(t - rec->t_ref - rec->dt) > 1e-9 * rec->dt) { /* the shorter last step */
                    double a[9];
                    c->cls->closed_loop(&c->spec->gains[i], a);
                    expm3(a, t - rec->t_ref, phi);
                    p = phi;
                }
                for (int k = 0; k < 3; k++)
                    next[k] = p[3 * k] * er[0] + p[3 * k + 1] * er[1] + p[3 * k + 2] * er[2];
                memcpy(er, next, sizeof next);
                mt->errdyn_dev = fmax(mt->errdyn_dev, fabs(c->des[3 * i] - c->qi[i] - er[1]));
            }
        }
        rec->t_ref = t;
    }
}

void sim_metrics_finish(const sim_ctx *c, const recorder *rec, const ctc_integ_stats *stats,
                        ctc_sim_metrics *mt)
{
    const ctc_sim_result *r = rec->r;
    mt->steps = stats->steps;
    mt->rejected = stats->rejected;
    mt->rhs_evals = c->evals;
    mt->err_estimate = stats->err_estimate;
    const double n = (double)r->nsamples;
    for (int i = 0; c->active && i < c->nind; i++) {
        mt->e_rms[i] = r->nsamples ? sqrt(rec->e_sq[i] / n) : 0;
        mt->tau_rms[i] = r->nsamples ? sqrt(rec->tau_sq[i] / n) : 0;
        if (c->limited) mt->sat_fraction[i] = r->nsamples ? rec->sat_n[i] / n : 0;
    }
    if (c->plant->has_loop) {
        mt->loop_res_max = rec->loop_max[0];
        mt->loop_vres_max = rec->loop_max[1];
    }
    if (rec->track_energy && r->nsamples)
        mt->energy_drift = rec->drift / fmax(fmax(fabs(rec->e0), rec->ke_max), 1e-300);
    if (!rec->track_errdyn || r->nsamples < 2) mt->errdyn_dev = NAN;
}

void sim_metrics_free(recorder *rec)
{
    free(rec->e_sq);
    free(rec->phi);
    rec->e_sq = rec->phi = rec->tau_sq = rec->sat_n = NULL;
}
