/*
 * gdca_refine.c - when ctc_gdca_forward refines its result (gdca_refine.h).
 *
 * The correction pass itself is the forward pass in its bias-free mode (gdca_forward.c and
 * gdca_forward_seq.c: every body's h13 = h23 = 0 and every beta = 0, the factors and the
 * assembled matrices reused), so it shares that pass's kernels and its split over threads; this
 * file holds the step rule and the residual.
 */
#include "gdca_refine.h"

#include "gdca.h"
#include "gdca_inverse_loop.h"
#include "gdca_loop.h"
#include "loop.h"

int gdca_refine_steps(const ctc_model *m, const ctc_data *d)
{
    if (m->nsingular > 0 || m->nslender > 0) { /* it makes the augmented pass exact */
        return d->opt.fwd_refine > CTC_REFINE_SINGULAR_STEPS ? d->opt.fwd_refine
                                                             : CTC_REFINE_SINGULAR_STEPS;
    }
    if (d->opt.fwd_refine >= 0) return d->opt.fwd_refine;
    if (m->mass_ratio >= CTC_REFINE_MASS_RATIO) return CTC_REFINE_MAX_STEPS;
    return m->nbodies >= CTC_REFINE_MIN_BODIES ? 1 : 0;
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
