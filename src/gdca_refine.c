/*
 * gdca_refine.c - when ctc_gdca_forward refines its result (gdca_refine.h).
 *
 * The correction pass itself is the forward pass of gdca_forward.c in its bias-free mode (every
 * body's h13 = h23 = 0 and every beta = 0, the factors and the assembled matrices reused), so it
 * shares that pass's kernels and its split over threads; this file holds the step rule.
 */
#include "gdca_refine.h"

int gdca_refine_steps(const ctc_model *m, const ctc_data *d)
{
    if (m->has_loop) return 0;
    if (d->fwd_refine >= 0) return d->fwd_refine;
    int needed = m->nbodies >= CTC_REFINE_MIN_BODIES || m->mass_ratio >= CTC_REFINE_MASS_RATIO;
    return needed ? CTC_REFINE_MAX_STEPS : 0;
}
