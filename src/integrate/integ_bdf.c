/*
 * integ_bdf.c - the stiff method: SUNDIALS CVODE's variable-order (1-5), variable-step BDF with
 * Newton iteration, a dense direct linear solver and CVODE's difference-quotient Jacobian
 * (integrator.h).
 *
 * Reference: A. C. Hindmarsh et al., "SUNDIALS: Suite of nonlinear and differential/algebraic
 * equation solvers", ACM TOMS 31 (2005), and the CVODE user guide (v6.4) for the calls used here.
 *
 * CVODE is driven one internal step at a time (CV_ONE_STEP) with CVodeSetStopTime(tstop) before
 * each step, so a step never passes tstop; a step that would is shortened by CVODE, which then
 * returns the solution interpolated at tstop itself (CV_TSTOP_RETURN, *tret == tstop exactly).
 * CVODE's solution vector is separate from the integrator's state, which is copied only after a
 * successful step: a failure leaves the state at the last accepted step.
 *
 * The user's rhs returning non-zero is reported to CVODE as an unrecoverable failure (-1), so
 * CVODE stops at once; its code is remembered and returned by ctc_integrator_step (this also
 * covers a failure inside the difference-quotient Jacobian, which CVODE reports as a linear
 * solver setup failure). CVODE's error messages go to an error handler that keeps the last one
 * for err instead of printing it.
 *
 * With a projection (ctc_integrator_set_projection), CVODE calls bdf_project after the Newton
 * iteration of every step attempt: the caller's function works on a copy of CVODE's solution
 * (it->y_new, which bdf does not otherwise use) and CVODE gets the difference as its correction,
 * which it folds into the step's Nordsieck history. Error-estimate projection is off: the caller
 * projects a nonlinear closure, not the linear map CVODE would apply to the estimate. A failed
 * projection stops CVODE at once, as a failed rhs does, and its code is returned.
 *
 * A reset restarts CVODE at order 1. Unlike the explicit methods it does not keep the step size:
 * the first reset starts from spec.initial_step, later ones from CVODE's own estimate (a few rhs
 * evaluations), because the step that suited the order-5 history is far too long for order 1.
 *
 * CVodeReInit, which a reset calls, zeroes CVODE's counters; the totals up to then are kept in
 * `base` and the statistics are base + CVODE's current counters. CVODE's linear-solver counters
 * are zeroed only when it sets up its first step after a (re)initialisation, which is also where
 * it makes its first rhs evaluation, so they are read only once that evaluation has happened.
 * Allocation happens in ctc_bdf_new and in the first ctc_bdf_set_projection (CVODE's projection
 * memory) only (CVODE's difference-quotient Jacobian itself makes a vector header per Jacobian
 * evaluation).
 */
#include <cvode/cvode.h>
#include <cvode/cvode_proj.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sundials/sundials_context.h>
#include <sunlinsol/sunlinsol_dense.h>
#include <sunmatrix/sunmatrix_dense.h>

#include "integrator_internal.h"

struct ctc_bdf {
    SUNContext sunctx;
    void *cvode;
    N_Vector y_out; /* (n) CVODE's solution after a step, copied into it->y on success */
    N_Vector ele;   /* (n) estimated local errors of the last step */
    N_Vector dky;   /* (n) dense output */
    SUNMatrix jac;  /* (n x n) Newton matrix */
    SUNLinearSolver ls;
    ctc_integrator *it; /* the owner, for the rhs wrapper */
    int rhs_rc;         /* the user's rhs's last non-zero return, 0 if none */
    double rhs_t;       /* and the time it was called at */
    int proj_on;        /* 1 once CVODE's projection is set up (its memory exists) */
    int proj_rc;        /* the projection's last non-zero return, 0 if none */
    double proj_t;      /* and its time */
    double h_init;      /* the step CVODE starts from after a (re)initialisation, 0 = its choice */
    long reinits;       /* resets so far */
    ctc_integ_stats base; /* totals before the last CVodeReInit (and reset evaluations) */
    char msg[256];        /* CVODE's last error message */
};

static int bdf_rhs(sunrealtype t, N_Vector y, N_Vector ydot, void *user_data)
{
    ctc_bdf *b = user_data;
    int rc = b->it->rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), b->it->ctx);
    if (rc != 0) {
        b->rhs_rc = rc;
        b->rhs_t = t;
        return -1; /* unrecoverable: CVODE stops and returns */
    }
    return 0;
}

/* CVProjFn: corr = P(ycur) - ycur, with P the caller's projection (integrator.h) */
static int bdf_project(sunrealtype t, N_Vector ycur, N_Vector corr, sunrealtype eps_proj,
                       N_Vector err, void *user_data)
{
    ctc_bdf *b = user_data;
    ctc_integrator *it = b->it;
    (void)eps_proj; /* the caller's own tolerance applies */
    (void)err;      /* NULL: error projection is off */
    const double *y = N_VGetArrayPointer(ycur);
    double *c = N_VGetArrayPointer(corr), *yp = it->y_new;
    memcpy(yp, y, (size_t)it->n * sizeof *yp);
    int rc = it->proj(t, yp, it->ctx);
    if (rc != 0) {
        b->proj_rc = rc;
        b->proj_t = t;
        return -1; /* unrecoverable: CVODE stops and returns */
    }
    for (int i = 0; i < it->n; i++) c[i] = yp[i] - y[i];
    return 0;
}

static void bdf_error_handler(int error_code, const char *module, const char *function, char *msg,
                              void *user_data)
{
    ctc_bdf *b = user_data;
    (void)module;
    (void)function;
    if (error_code == CV_WARNING) return; /* e.g. t + h == t: the round-off check reports it */
    snprintf(b->msg, sizeof b->msg, "%s", msg);
}

/* statistics = base + CVODE's counters since the last (re)initialisation */
static void refresh_stats(ctc_integrator *it)
{
    ctc_bdf *b = it->bdf;
    long nst = 0, nfe = 0, nfe_ls = 0, netf = 0, ncfn = 0, nje = 0;
    CVodeGetNumSteps(b->cvode, &nst);
    CVodeGetNumRhsEvals(b->cvode, &nfe);
    CVodeGetNumErrTestFails(b->cvode, &netf);
    CVodeGetNumNonlinSolvConvFails(b->cvode, &ncfn);
    if (nfe > 0) {
        CVodeGetNumLinRhsEvals(b->cvode, &nfe_ls);
        CVodeGetNumJacEvals(b->cvode, &nje);
    }
    it->stats.steps = b->base.steps + nst;
    it->stats.rejected = b->base.rejected + netf + ncfn;
    it->stats.rhs_evals = b->base.rhs_evals + nfe + nfe_ls;
    it->stats.jac_evals = b->base.jac_evals + nje;
}

ctc_status ctc_bdf_new(ctc_integrator *it, char *err, size_t errlen)
{
    const int n = it->n;
    ctc_bdf *b = calloc(1, sizeof *b);
    if (b == NULL) return ctc_fail(CTC_ENOMEM, err, errlen, "bdf: out of memory");
    it->bdf = b;
    b->it = it;
    if (SUNContext_Create(NULL, &b->sunctx) != 0) {
        return ctc_fail(CTC_ENOMEM, err, errlen, "bdf: SUNContext_Create failed");
    }

    /* vectors, CVODE's memory, and its error messages routed to b->msg */
    b->y_out = N_VNew_Serial(n, b->sunctx);
    b->ele = N_VNew_Serial(n, b->sunctx);
    b->dky = N_VNew_Serial(n, b->sunctx);
    b->cvode = CVodeCreate(CV_BDF, b->sunctx);
    if (b->y_out == NULL || b->ele == NULL || b->dky == NULL || b->cvode == NULL) {
        return ctc_fail(CTC_ENOMEM, err, errlen, "bdf: out of memory for CVODE (n = %d)", n);
    }
    N_VConst(0.0, b->y_out);
    int flag = CVodeSetErrHandlerFn(b->cvode, bdf_error_handler, b);
    if (flag == CV_SUCCESS) flag = CVodeInit(b->cvode, bdf_rhs, 0.0, b->y_out);
    if (flag == CV_SUCCESS) flag = CVodeSetUserData(b->cvode, b);
    if (flag == CV_SUCCESS) flag = CVodeSStolerances(b->cvode, it->spec.rtol, it->spec.atol);
    if (flag != CV_SUCCESS) {
        return ctc_fail(flag == CV_MEM_FAIL ? CTC_ENOMEM : CTC_EINVAL, err, errlen,
                        "bdf: CVODE setup failed (%d): %s", flag, b->msg);
    }

    /* Newton with a dense direct solver on CVODE's difference-quotient Jacobian */
    b->jac = SUNDenseMatrix(n, n, b->sunctx);
    b->ls = b->jac != NULL ? SUNLinSol_Dense(b->y_out, b->jac, b->sunctx) : NULL;
    if (b->jac == NULL || b->ls == NULL) {
        return ctc_fail(CTC_ENOMEM, err, errlen, "bdf: out of memory for the %d x %d Jacobian", n,
                        n);
    }
    flag = CVodeSetLinearSolver(b->cvode, b->ls, b->jac);
    if (flag != CV_SUCCESS) {
        return ctc_fail(CTC_ENOMEM, err, errlen, "bdf: CVodeSetLinearSolver failed (%d): %s", flag,
                        b->msg);
    }

    /* bounds on the step */
    if (it->spec.max_step > 0 && isfinite(it->spec.max_step)) {
        flag = CVodeSetMaxStep(b->cvode, it->spec.max_step);
        if (flag != CV_SUCCESS) {
            return ctc_fail(CTC_EINVAL, err, errlen, "bdf: CVodeSetMaxStep failed (%d): %s", flag,
                            b->msg);
        }
    }
    if (it->spec.min_step > 0) {
        flag = CVodeSetMinStep(b->cvode, it->spec.min_step);
        if (flag != CV_SUCCESS) {
            return ctc_fail(CTC_EINVAL, err, errlen, "bdf: CVodeSetMinStep failed (%d): %s", flag,
                            b->msg);
        }
    }
    b->h_init = it->spec.initial_step;
    if (it->spec.max_step > 0 && b->h_init > it->spec.max_step) b->h_init = it->spec.max_step;
    return CTC_OK;
}

void ctc_bdf_free(ctc_bdf *b)
{
    if (b == NULL) return;
    if (b->cvode != NULL) CVodeFree(&b->cvode);
    if (b->ls != NULL) SUNLinSolFree(b->ls);
    if (b->jac != NULL) SUNMatDestroy(b->jac);
    if (b->y_out != NULL) N_VDestroy(b->y_out);
    if (b->ele != NULL) N_VDestroy(b->ele);
    if (b->dky != NULL) N_VDestroy(b->dky);
    if (b->sunctx != NULL) SUNContext_Free(&b->sunctx);
    free(b);
}

int ctc_bdf_reset(ctc_integrator *it)
{
    ctc_bdf *b = it->bdf;

    /* after the first reset CVODE chooses the starting step itself: it restarts at order 1,
     * where the step the order-5 history allowed fails the error test again and again
     * (CV_ERR_FAILURE at the first jump of a stiff forced problem) */
    if (b->reinits++ > 0) b->h_init = 0;

    /* fold CVODE's counters (and reset's own evaluation) into the base; ReInit zeroes them */
    b->base = it->stats;
    memcpy(N_VGetArrayPointer(b->y_out), it->y, (size_t)it->n * sizeof(double));
    if (CVodeReInit(b->cvode, it->t, b->y_out) != CV_SUCCESS) return -1;
    if (CVodeSetInitStep(b->cvode, b->h_init) != CV_SUCCESS) return -1;
    return 0;
}

int ctc_bdf_set_projection(ctc_integrator *it)
{
    ctc_bdf *b = it->bdf;
    if (it->proj == NULL) { /* off: nothing to do if it was never on (CVODE has no memory for it) */
        return !b->proj_on || CVodeSetProjFrequency(b->cvode, 0) == CV_SUCCESS ? 0 : -1;
    }
    int flag = CVodeSetProjFn(b->cvode, bdf_project);
    if (flag == CV_SUCCESS) flag = CVodeSetProjErrEst(b->cvode, SUNFALSE);
    if (flag == CV_SUCCESS) flag = CVodeSetProjFrequency(b->cvode, 1);
    if (flag == CV_SUCCESS) b->proj_on = 1;
    return flag == CV_SUCCESS ? 0 : -1;
}

int ctc_bdf_step(ctc_integrator *it, double tstop, char *err, size_t errlen)
{
    ctc_bdf *b = it->bdf;
    const double t = it->t;

    /* the step CVODE will try: the round-off check before it spends anything */
    double h_next = b->h_init;
    if (it->stats.steps > b->base.steps) CVodeGetCurrentStep(b->cvode, &h_next);
    if (h_next != 0 && ctc_integ_below_roundoff(h_next, t)) {
        return ctc_integ_fail_roundoff(h_next, t, err, errlen);
    }
    if (h_next != 0 && h_next < it->spec.min_step && h_next < tstop - t) {
        return ctc_integ_fail_min_step(h_next, t, it->spec.min_step, err, errlen);
    }

    /* one internal step, stopping at tstop */
    b->rhs_rc = 0;
    b->proj_rc = 0;
    b->msg[0] = '\0';
    const long steps_before = it->stats.steps;
    double t_ret = t;
    int flag = CVodeSetStopTime(b->cvode, tstop);
    if (flag == CV_SUCCESS) flag = CVode(b->cvode, tstop, b->y_out, &t_ret, CV_ONE_STEP);
    refresh_stats(it);
    if (b->rhs_rc != 0) return ctc_integ_fail_rhs(b->rhs_rc, b->rhs_t, err, errlen);
    if (b->proj_rc != 0) {
        ctc_fail(CTC_EINVAL, err, errlen, "projection failed (returned %d) at t = %.10g s",
                 b->proj_rc, b->proj_t);
        return b->proj_rc;
    }
    if (flag < 0 && it->spec.min_step > 0) {
        /* CVODE holds its steps at min_step and fails where the error or the Newton iteration
         * needs smaller ones: the step floor's message */
        double h_fail = 0;
        CVodeGetCurrentStep(b->cvode, &h_fail);
        if ((flag == CV_ERR_FAILURE || flag == CV_CONV_FAILURE) &&
            fabs(h_fail) <= it->spec.min_step * (1 + 1e-12)) {
            return ctc_integ_fail_min_step(fabs(h_fail), t, it->spec.min_step, err, errlen);
        }
    }
    if (flag < 0) {
        ctc_fail(CTC_EINVAL, err, errlen, "CVODE failed (flag %d) at t = %.10g s: %s", flag, t,
                 b->msg);
        return -1;
    }

    /* accepted (CVODE returns at once, without a step, when tstop is within round-off) */
    if (it->stats.steps > steps_before) {
        double h_last = 0;
        CVodeGetLastStep(b->cvode, &h_last);
        CVodeGetEstLocalErrors(b->cvode, b->ele);
        it->stats.h_last = h_last;
        it->stats.err_estimate += N_VMaxNorm(b->ele);
    }
    memcpy(it->y, N_VGetArrayPointer(b->y_out), (size_t)it->n * sizeof(double));
    it->t_prev = t;
    it->t = flag == CV_TSTOP_RETURN ? tstop : t_ret;
    return 0;
}

void ctc_bdf_dense(const ctc_integrator *it, double t, double *y)
{
    ctc_bdf *b = it->bdf;
    if (CVodeGetDky(b->cvode, t, 0, b->dky) != CV_SUCCESS) {
        for (int i = 0; i < it->n; i++) y[i] = NAN;
        return;
    }
    memcpy(y, N_VGetArrayPointer(b->dky), (size_t)it->n * sizeof(double));
}

int ctc_bdf_set_tolerances(ctc_integrator *it)
{
    return CVodeSStolerances(it->bdf->cvode, it->spec.rtol, it->spec.atol) == CV_SUCCESS ? 0 : -1;
}
