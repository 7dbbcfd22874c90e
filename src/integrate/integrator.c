/*
 * integrator.c - the integrators' public API (integrator.h): the spec check, construction, reset,
 * and dispatch of step and dense output to the method files (integ_rk4.c, integ_dopri5.c,
 * integ_bdf.c), plus the helpers they share (integrator_internal.h).
 *
 * What is common to all methods lives here: the checks made before every step (a state to step
 * from, tstop after the current time, the max_steps budget) and reset's one evaluation of f at
 * the new initial point. The explicit methods' arrays are carved out of one allocation made in
 * ctc_integrator_new; nothing is allocated afterwards.
 */
#include "integrator.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "integrator_internal.h"

const char *ctc_integ_method_name(ctc_integ_method m)
{
    switch (m) {
    case CTC_INTEG_RK4:
        return "rk4";
    case CTC_INTEG_DOPRI5:
        return "dopri5";
    case CTC_INTEG_BDF:
        return "bdf";
    }
    return "unknown";
}

ctc_status ctc_integ_check(const ctc_integ_spec *spec, char *err, size_t errlen)
{
    if (spec == NULL) return ctc_fail(CTC_EINVAL, err, errlen, "integrator spec is NULL");
    switch (spec->method) {
    case CTC_INTEG_RK4:
        if (!isfinite(spec->step) || !(spec->step > 0)) {
            return ctc_fail(CTC_EINVAL, err, errlen, "step must be positive and finite (got %g s)",
                            spec->step);
        }
        break;
    case CTC_INTEG_DOPRI5:
    case CTC_INTEG_BDF:
        if (!(spec->rtol > 0 && spec->rtol < 1)) {
            return ctc_fail(CTC_EINVAL, err, errlen, "rtol must be in (0, 1) (got %g)", spec->rtol);
        }
        if (!isfinite(spec->atol) || !(spec->atol > 0)) {
            return ctc_fail(CTC_EINVAL, err, errlen, "atol must be positive and finite (got %g)",
                            spec->atol);
        }
        if (!isfinite(spec->initial_step) || !(spec->initial_step >= 0)) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "initial_step must be >= 0 and finite (got %g s)", spec->initial_step);
        }
        /* +inf is allowed: it means no bound, as 0 does */
        if (!(spec->max_step >= 0)) {
            return ctc_fail(CTC_EINVAL, err, errlen, "max_step must be >= 0 (got %g s)",
                            spec->max_step);
        }
        if (!isfinite(spec->min_step) || !(spec->min_step >= 0)) {
            return ctc_fail(CTC_EINVAL, err, errlen, "min_step must be >= 0 and finite (got %g s)",
                            spec->min_step);
        }
        if (spec->max_step > 0 && spec->min_step > spec->max_step) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "min_step must not exceed max_step (got %g s > %g s)", spec->min_step,
                            spec->max_step);
        }
        break;
    default:
        return ctc_fail(CTC_EINVAL, err, errlen, "unknown integration method %d",
                        (int)spec->method);
    }
    if (spec->max_steps < 0) {
        return ctc_fail(CTC_EINVAL, err, errlen, "max_steps must be >= 0 (got %ld)",
                        spec->max_steps);
    }
    return CTC_OK;
}

/* number of n-vectors each method keeps in the shared block */
static int vectors_needed(ctc_integ_method m)
{
    switch (m) {
    case CTC_INTEG_RK4:
        return 7 + 3; /* y and f (3 each), y_stage; k2..k4 */
    case CTC_INTEG_DOPRI5:
        return 7 + CTC_DOPRI5_WORK_STAGES + CTC_DOPRI5_KEPT_STAGES;
    case CTC_INTEG_BDF:
        return 4; /* y, y_prev, y_new, and f for reset's evaluation */
    }
    return 0;
}

ctc_status ctc_integrator_new(const ctc_integ_spec *spec, int n, ctc_ode_rhs rhs, void *ctx,
                              ctc_integrator **out, char *err, size_t errlen)
{
    if (out == NULL) return ctc_fail(CTC_EINVAL, err, errlen, "out is NULL");
    *out = NULL;
    ctc_status st = ctc_integ_check(spec, err, errlen);
    if (st != CTC_OK) return st;
    if (n < 1) return ctc_fail(CTC_EINVAL, err, errlen, "n must be >= 1 (got %d)", n);
    if (rhs == NULL) return ctc_fail(CTC_EINVAL, err, errlen, "rhs is NULL");

    ctc_integrator *it = calloc(1, sizeof *it);
    if (it == NULL) return ctc_fail(CTC_ENOMEM, err, errlen, "integrator: out of memory");
    it->spec = *spec;
    it->n = n;
    it->rhs = rhs;
    it->ctx = ctx;
    it->stats.err_estimate = spec->method == CTC_INTEG_RK4 ? NAN : 0.0;
    it->h = spec->method == CTC_INTEG_RK4 ? spec->step : 0.0;
    it->err_old = 1e-4;

    /* one block for every n-vector, handed out in the order of slots (bdf takes the first 4) */
    int nvec = vectors_needed(spec->method);
    it->block = calloc((size_t)nvec * (size_t)n, sizeof(double));
    if (it->block == NULL) {
        free(it);
        return ctc_fail(CTC_ENOMEM, err, errlen, "integrator: out of memory for %d x %d doubles",
                        nvec, n);
    }
    double **slots[7 + CTC_DOPRI5_WORK_STAGES + CTC_DOPRI5_KEPT_STAGES] = {
        &it->y,         &it->y_prev,    &it->y_new,     &it->f,
        &it->f_prev,    &it->f_new,     &it->y_stage,   &it->k_work[0],
        &it->k_work[1], &it->k_work[2], &it->k_work[3], &it->k_work[4],
        &it->k_kept[0], &it->k_kept[1], &it->k_kept[2], &it->k_kept[3]};
    for (int i = 0; i < nvec; i++) *slots[i] = it->block + (size_t)i * (size_t)n;

    if (spec->method == CTC_INTEG_BDF) {
        st = ctc_bdf_new(it, err, errlen);
        if (st != CTC_OK) {
            ctc_integrator_free(it);
            return st;
        }
    }
    *out = it;
    return CTC_OK;
}

void ctc_integrator_free(ctc_integrator *it)
{
    if (it == NULL) return;
    ctc_bdf_free(it->bdf);
    free(it->block);
    free(it);
}

int ctc_integrator_reset(ctc_integrator *it, double t0, const double *y0)
{
    size_t bytes = (size_t)it->n * sizeof(double);
    it->ready = 0;
    it->t = t0;
    it->t_prev = t0;
    memmove(it->y, y0, bytes);
    memcpy(it->y_prev, it->y, bytes);

    /* f at the new start: the explicit methods' first stage, and the rhs's say on the state */
    int rc = ctc_integ_call_rhs(it, t0, it->y, it->f);
    if (rc != 0) return rc;
    if (it->f_prev != NULL) memcpy(it->f_prev, it->f, bytes);

    switch (it->spec.method) {
    case CTC_INTEG_RK4:
        break;
    case CTC_INTEG_DOPRI5:
        ctc_dopri5_reset(it);
        break;
    case CTC_INTEG_BDF:
        if (ctc_bdf_reset(it) != 0) return -1;
        break;
    }
    it->ready = 1;
    return 0;
}

ctc_status ctc_integrator_set_projection(ctc_integrator *it, ctc_ode_project proj, char *err,
                                         size_t errlen)
{
    if (it->spec.method != CTC_INTEG_BDF)
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "in-step projection needs method bdf (this integrator is %s)",
                        ctc_integ_method_name(it->spec.method));
    it->proj = proj;
    if (ctc_bdf_set_projection(it) != 0)
        return ctc_fail(CTC_EINVAL, err, errlen, "bdf: CVODE refused the projection function");
    return CTC_OK;
}

ctc_status ctc_integrator_set_tolerances(ctc_integrator *it, double rtol, double atol, char *err,
                                         size_t errlen)
{
    if (it->spec.method == CTC_INTEG_RK4)
        return ctc_fail(CTC_EINVAL, err, errlen, "rk4 has no tolerances");
    ctc_integ_spec s = it->spec;
    s.rtol = rtol;
    s.atol = atol;
    ctc_status st = ctc_integ_check(&s, err, errlen);
    if (st != CTC_OK) return st;
    it->spec.rtol = rtol;
    it->spec.atol = atol;
    if (it->spec.method == CTC_INTEG_BDF && ctc_bdf_set_tolerances(it) != 0)
        return ctc_fail(CTC_EINVAL, err, errlen, "bdf: CVODE refused the tolerances");
    return CTC_OK;
}

int ctc_integrator_step(ctc_integrator *it, double tstop, char *err, size_t errlen)
{
    if (!it->ready) {
        ctc_fail(CTC_EINVAL, err, errlen, "no state to step from: reset was not called or failed");
        return -1;
    }
    if (!(tstop > it->t) || !isfinite(tstop)) {
        ctc_fail(CTC_EINVAL, err, errlen,
                 "tstop must be finite and after the current time %.10g s (got %.10g s)", it->t,
                 tstop);
        return -1;
    }
    if (it->spec.max_steps > 0 && it->stats.steps >= it->spec.max_steps) {
        ctc_fail(CTC_EINVAL, err, errlen, "max_steps (%ld) reached at t = %.10g s",
                 it->spec.max_steps, it->t);
        return -1;
    }
    switch (it->spec.method) {
    case CTC_INTEG_RK4:
        return ctc_rk4_step(it, tstop, err, errlen);
    case CTC_INTEG_DOPRI5:
        return ctc_dopri5_step(it, tstop, err, errlen);
    case CTC_INTEG_BDF:
        return ctc_bdf_step(it, tstop, err, errlen);
    }
    return -1;
}

double ctc_integrator_time(const ctc_integrator *it)
{
    return it->t;
}

const double *ctc_integrator_state(const ctc_integrator *it)
{
    return it->y;
}

void ctc_integrator_dense(const ctc_integrator *it, double t, double *y)
{
    /* the end of the step, and a step of zero length (right after a reset), are the state */
    if (t == it->t || it->t == it->t_prev) {
        memcpy(y, it->y, (size_t)it->n * sizeof(double));
        return;
    }
    switch (it->spec.method) {
    case CTC_INTEG_RK4:
        ctc_rk4_dense(it, t, y);
        break;
    case CTC_INTEG_DOPRI5:
        ctc_dopri5_dense(it, t, y);
        break;
    case CTC_INTEG_BDF:
        ctc_bdf_dense(it, t, y);
        break;
    }
}

const ctc_integ_stats *ctc_integrator_stats(const ctc_integrator *it)
{
    return &it->stats;
}

/* ---- helpers shared by the method files ---- */

double ctc_integ_clip_step(double t, double tstop, double h, double hmax, int *lands)
{
    double remaining = tstop - t;
    *lands = 0;
    if (remaining <= 1.01 * h && (hmax == 0 || remaining <= hmax)) {
        *lands = 1;
        return remaining;
    }
    if (remaining < 2.0 * h) return 0.5 * remaining;
    return h;
}

int ctc_integ_fail_roundoff(double h, double t, char *err, size_t errlen)
{
    ctc_fail(CTC_EINVAL, err, errlen,
             "step size %.3g s at t = %.10g s fell below the round-off limit", h, t);
    return -1;
}

int ctc_integ_fail_min_step(double h, double t, double min_step, char *err, size_t errlen)
{
    ctc_fail(CTC_EINVAL, err, errlen,
             "step size %.3g s at t = %.10g s fell below min_step (%g s): the problem needs a "
             "smaller step, looser tolerances or \"method\": \"bdf\"",
             h, t, min_step);
    return -1;
}

int ctc_integ_fail_rhs(int rc, double t, char *err, size_t errlen)
{
    ctc_fail(CTC_EINVAL, err, errlen, "right-hand side failed (returned %d) at t = %.10g s", rc, t);
    return rc;
}
