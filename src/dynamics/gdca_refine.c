/*
 * gdca_refine.c - when ctc_gdca_forward refines its result (gdca_refine.h).
 *
 * The correction pass itself is the forward pass in its bias-free mode (gdca_forward.c and
 * gdca_forward_seq.c: every body's h13 = h23 = 0 and every beta = 0, the factors and the
 * assembled matrices reused), so it shares that pass's kernels and its split over threads; this
 * file holds the step rule and the residual.
 */
#include "gdca_refine.h"

#include <math.h>
#include <string.h>

#include "gdca.h"
#include "gdca_inverse_loop.h"
#include "gdca_loop.h"
#include "loop.h"

int gdca_refine_steps(const ctc_model *m, const ctc_data *d)
{
    if (m->dyn != NULL) m = m->dyn; /* merged bodies (model.h): the passes run on the reduced */
    if (m->nsingular > 0 || m->nslender > 0) { /* it makes the augmented pass exact */
        return d->opt.fwd_refine > CTC_REFINE_SINGULAR_STEPS ? d->opt.fwd_refine
                                                             : CTC_REFINE_SINGULAR_STEPS;
    }
    if (d->opt.fwd_refine >= 0) return d->opt.fwd_refine;
    if (m->mass_ratio >= CTC_REFINE_MASS_RATIO) return CTC_REFINE_MAX_STEPS;
    return m->nbodies >= CTC_REFINE_MIN_BODIES ? 1 : 0;
}

int gdca_refine_steps_ref(const ctc_model *m, const ctc_data *d)
{
    if (m->dyn != NULL) m = m->dyn;
    if (m->nsingular > 0 || m->nslender > 0) return gdca_refine_steps(m, d);
    if (d->opt.fwd_refine >= 0) return d->opt.fwd_refine;
    return m->mass_ratio >= CTC_REFINE_MASS_RATIO ? CTC_REFINE_MAX_STEPS : 0;
}

int gdca_refine_step(gdca_refine_rule *rule, int nvx, const double *dq, double *dq_last,
                     double *qacc)
{
    /* an augmented model's ratio of this correction to the last, and whether to extrapolate */
    double lambda = 0, w = 1;
    if (rule->augmented && rule->steps > 0) {
        double dd = 0, ll = 0;
        for (int i = 0; i < nvx; i++) dd += dq[i] * dq_last[i], ll += dq_last[i] * dq_last[i];
        lambda = ll > 0 ? dd / ll : 0;
    }
    const double mag = fabs(lambda);
    const int extrapolate = rule->steps > 1 && !rule->extrapolate && mag >= CTC_REFINE_EXTRAP_MIN &&
                            mag <= CTC_REFINE_EXTRAP_MAX &&
                            fabs(lambda - rule->lambda) <= CTC_REFINE_RATE_AGREE * mag;
    if (extrapolate) w = 1 / (1 - lambda);

    /* the largest |qacc| and |w dq|: plain comparisons, not libm's fmax (a call each); a NaN is
       skipped either way */
    double amax = 0, dmax = 0;
    for (int i = 0; i < nvx; i++) {
        const double step = w * dq[i];
        qacc[i] += step;
        double aa = fabs(qacc[i]), ad = fabs(step);
        if (aa > amax) amax = aa;
        if (ad > dmax) dmax = ad;
    }
    const int first = rule->steps == 0;
    const double last = rule->last;
    rule->steps++;
    rule->lambda = lambda;
    rule->extrapolate = extrapolate;
    rule->last = dmax;
    if (first || !rule->augmented) {
        if (dmax <= CTC_REFINE_CONVERGED * amax) return 1;
        if (!first && dmax * CTC_REFINE_STALL > last) return 1;
    } else if (!extrapolate) {
        if (mag * CTC_REFINE_SLOW_STALL >= 1) return 1;
        if (dmax <= CTC_REFINE_TOL * amax && dmax * mag <= CTC_REFINE_TAIL * amax * (1 - mag))
            return 1;
    }
    if (rule->augmented) memcpy(dq_last, dq, (size_t)nvx * sizeof *dq);
    return 0;
}

void gdca_refine_residual(const ctc_model *m, ctc_data *d, const double *f, double *qacc, double *r)
{
    if (!m->has_loop) {
        ctc_gdca_inverse(m, d, qacc, r);
        for (int i = 0; i < m->nv; i++) r[i] = f[i] - r[i];
        return;
    }
    const int n = m->nbodies, dim = m->dim, nv = m->nv;
    const double *load = d->jnt_load + dim * n; /* the closing joint's, on its child */
    double rel[CTC_DENSE_MAX], off[CTC_DENSE_MAX];

    /* the chain: r = f - tau - J^T F over the loop's coordinates, tau = M qdd + N */
    gdca_inverse_composite(m, d, qacc, r);
    for (int k = 0; k < n; k++) {
        for (int c = 0; c < m->jnt_nv[k]; c++) {
            const int i = m->jnt_vadr[k] + c;
            double s = f[i] - r[i];
            if (m->jnt_loop[k]) {
                double tw[CTC_DENSE_MAX];
                ctc_loop_coord_twist(m, d, k, c, tw);
                for (int a = 0; a < dim; a++) s -= tw[a] * load[a];
            }
            r[i] = s;
        }
    }
    for (int c = 0; c < m->jnt_nv[n]; c++) r[nv + c] = 0; /* f_n = P_n^T F holds by construction */

    /* the closure, from the accelerations of the same pass: rel = A_child - A_t - beta_n gives
       the closing joint's accelerations P_n^T rel and the residual rho = -D_n^T rel - off */
    gdca_inverse_closing_accel(m, d, rel);
    for (int a = 0; a < dim; a++) rel[a] -= d->jnt_beta[dim * n + a];
    gdca_loop_offset(m, d, off);
    const double *P = d->jnt_P + 3 * dim * n, *D = d->jnt_D + dim * dim * n;
    for (int c = 0; c < m->jnt_nv[n]; c++) {
        double s = 0;
        for (int a = 0; a < dim; a++) s += P[c * dim + a] * rel[a];
        qacc[nv + c] = s;
    }
    for (int c = 0; c < dim - m->jnt_nv[n]; c++) {
        double s = 0;
        for (int a = 0; a < dim; a++) s += D[c * dim + a] * rel[a];
        d->loop_rho[c] = -s - off[c];
    }
}
