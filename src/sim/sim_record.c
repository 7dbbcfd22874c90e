/*
 * sim_record.c - the samples of a run (sim.h ctc_sim_result, sim_internal.h): their times, the
 * result's arrays sized before the first step, and one sample's channels.
 *
 * Samples fall at t = 0, dt, 2 dt, ... and at the duration; the run takes every sample inside an
 * accepted step from the integrator's dense output. A sample costs only what its channels and
 * metrics read (sim_sample_needs): on an open chain no forward pass, the inverse pass only for
 * the "tau" channel, the kinematics only for energy; a sample at the state of the last
 * right-hand side (the end of an rk4 or dopri5 step, t = 0) reuses that evaluation. The values
 * are bitwise those of a full evaluation (sim_rhs.c). Samples report normalised quaternions.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "energy.h"
#include "kinematics.h"
#include "sim_internal.h"

long sim_sample_count(double duration, double dt)
{
    double n = floor(duration / dt * (1 + 1e-12));
    if (!(n < (double)SIM_MAX_SAMPLES)) return SIM_MAX_SAMPLES + 1;
    long count = (long)n + 1;
    if ((double)(count - 1) * dt < duration * (1 - 1e-12)) count++; /* a last sample at duration */
    return count;
}

double sim_sample_time(long j, long count, double duration, double dt)
{
    return j == count - 1 ? duration : (double)j * dt;
}

/* What a sample needs of an evaluation at its state. Its outputs are q, v, the desired motion,
 * e and w (no pass needed); the driving forces (the inverse pass, with a controller: the tau
 * channel, the force metrics and the saturation); the energy
 * (the kinematics). A loop model's sample takes a full evaluation: the forward pass's boundary
 * solve has its own condition estimate, which metrics.loop_cond_max reports at the samples. No
 * sample needs the forward pass's accelerations otherwise. */
unsigned sim_sample_needs(const sim_ctx *c, const recorder *rec)
{
    const ctc_sim_result *r = rec->r;
    if (c->plant->has_loop) return SIM_EVAL_FULL;
    unsigned what = 0;
    if (c->active) what |= SIM_EVAL_FORCES; /* the tau channel and metrics, the clipping */
    if (r->ch[CTC_CH_ENERGY] || r->ch[CTC_CH_EE] || r->ch[CTC_CH_POSE] || rec->track_energy)
        what |= SIM_EVAL_KIN;
    return what;
}

/* Records sample j = r->nsamples at (t, y): its channels and its share of the metrics. A sample
 * at the state of the last full evaluation (an explicit step's end, t = 0) reuses it; otherwise
 * it evaluates what sim_sample_needs says, with the very same calls as the right-hand side, so the
 * values are bitwise those a full evaluation would give. */
void sim_record_sample(sim_ctx *c, recorder *rec, double t, const double *y)
{
    ctc_sim_result *r = rec->r;
    long j = r->nsamples;
    if (!(c->eval_valid && t == c->t_eval && memcmp(y, c->y_eval, (size_t)c->ny * sizeof *y) == 0))
        sim_evaluate(c, t, y, rec->eval);
    r->t[j] = t;
    const double *q = c->has_quat ? c->qn : y, *v = y + c->nq;
    const int *ic = c->plant->ind_coord;
    double res[2] = {0, 0};
    if (c->plant->has_loop) {
        ctc_loop_residual_norms(c->plant, c->dp, &res[0], &res[1]);
        rec->loop_max[0] = fmax(rec->loop_max[0], res[0]);
        rec->loop_max[1] = fmax(rec->loop_max[1], res[1]);
        r->metrics.loop_cond_max = fmax(r->metrics.loop_cond_max, c->cond);
    }
    for (int ch = 0; ch < CTC_NCHANNELS; ch++) {
        double *out = r->ch[ch];
        if (!out) continue;
        out += (size_t)j * (size_t)r->width[ch];
        for (int i = 0; i < r->width[ch]; i++) {
            switch ((ctc_channel)ch) {
            case CTC_CH_Q:
                out[i] = q[i];
                break;
            case CTC_CH_QD:
                out[i] = v[i];
                break;
            case CTC_CH_Q_DES:
                out[i] = c->des[3 * i];
                break;
            case CTC_CH_QD_DES:
                out[i] = c->des[3 * i + 1];
                break;
            case CTC_CH_E:
                out[i] = c->des[3 * i] - c->qi[i];
                break;
            case CTC_CH_TAU:
                out[i] = c->fz[ic[i]];
                break;
            case CTC_CH_LOOP:
                out[i] = res[i];
                break;
            case CTC_CH_W:
                out[i] = c->w[i];
                break;
            default:
                break;
            }
        }
    }
    if (r->ch[CTC_CH_EE]) {
        double *out = r->ch[CTC_CH_EE] + 6 * (size_t)j;
        const ctc_end_effector *ee = c->spec->end_effector;
        ctc_kinematics_point(c->plant, c->dp, ee->body, ee->point, out, out + 3);
    }
    if (r->ch[CTC_CH_POSE]) {
        double *out = r->ch[CTC_CH_POSE] + 7 * (size_t)c->spec->npose * (size_t)j;
        for (int b = 0; b < c->spec->npose; b++, out += 7) {
            static const double origin[3] = {0, 0, 0};
            double xd[3], rot[9];
            const int k = c->spec->pose_bodies[b];
            ctc_kinematics_point(c->plant, c->dp, k, origin, out, xd);
            ctc_kinematics_body_rotation(c->plant, c->dp, k, rot);
            ctc_rotation_quaternion(rot, out + 3);
        }
    }
    double ke = 0, pe = 0;
    if (r->ch[CTC_CH_ENERGY] || rec->track_energy) {
        ctc_energy(c->plant, c->dp, &ke, &pe);
        if (r->ch[CTC_CH_ENERGY]) {
            r->ch[CTC_CH_ENERGY][2 * j] = ke;
            r->ch[CTC_CH_ENERGY][2 * j + 1] = pe;
        }
    }
    sim_metrics_sample(c, rec, j, t, y, ke, pe);
    r->nsamples++;
}

ctc_status sim_alloc_result(const sim_ctx *c, unsigned channels, long count, ctc_sim_result **out)
{
    ctc_sim_result *r = calloc(1, sizeof *r);
    if (!r) return CTC_ENOMEM;
    *out = r;
    r->nq = c->nq, r->nv = c->nv, r->nind = c->nind, r->channels = channels;
    r->t = malloc((size_t)count * sizeof *r->t);
    if (!r->t) return CTC_ENOMEM;
    for (int ch = 0; ch < CTC_NCHANNELS; ch++) {
        if (!(channels & CTC_CH_BIT(ch))) continue;
        r->width[ch] = ch == CTC_CH_Q                             ? c->nq
                       : ch == CTC_CH_QD                          ? c->nv
                       : ch == CTC_CH_ENERGY || ch == CTC_CH_LOOP ? 2
                       : ch == CTC_CH_EE                          ? 6
                       : ch == CTC_CH_POSE                        ? 7 * c->spec->npose
                                                                  : c->nind;
        if (r->width[ch] == 0) continue;
        r->ch[ch] = malloc((size_t)count * (size_t)r->width[ch] * sizeof(double));
        if (!r->ch[ch]) return CTC_ENOMEM;
    }
    ctc_sim_metrics *mt = &r->metrics;
    mt->form = c->plant->form;
    mt->nv = c->nind;
    mt->energy_drift = NAN;
    mt->loop_res_max = mt->loop_vres_max = mt->loop_cond_max = NAN;
    if (c->plant->has_loop) mt->loop_cond_max = 0;
    mt->errdyn_dev = NAN;
    mt->err_estimate = NAN;
    mt->step_used = NAN;
    mt->accel_rounding = mt->tol_rtol = mt->tol_atol = NAN; /* set at the start: sim_tol.c */
    mt->diverged_joint = -1;
    if (c->active) {
        mt->e_max = calloc((size_t)c->nind + 1, sizeof(double));
        mt->e_rms = calloc((size_t)c->nind + 1, sizeof(double));
        mt->e_final = calloc((size_t)c->nind + 1, sizeof(double));
        mt->tau_peak = calloc((size_t)c->nind + 1, sizeof(double));
        mt->tau_rms = calloc((size_t)c->nind + 1, sizeof(double));
        mt->err_cause = calloc((size_t)CTC_NCAUSES * (size_t)c->nind + 1, sizeof(double));
        if (!mt->e_max || !mt->e_rms || !mt->e_final || !mt->tau_peak || !mt->tau_rms ||
            !mt->err_cause)
            return CTC_ENOMEM;
    }
    if (c->limited) {
        mt->sat_fraction = calloc((size_t)c->nind + 1, sizeof(double));
        if (!mt->sat_fraction) return CTC_ENOMEM;
    }
    return CTC_OK;
}

void ctc_sim_result_free(ctc_sim_result *r)
{
    if (!r) return;
    free(r->t);
    for (int ch = 0; ch < CTC_NCHANNELS; ch++) free(r->ch[ch]);
    free(r->metrics.e_max);
    free(r->metrics.e_rms);
    free(r->metrics.e_final);
    free(r->metrics.tau_peak);
    free(r->metrics.tau_rms);
    free(r->metrics.sat_fraction);
    free(r->metrics.err_cause);
    free(r);
}
