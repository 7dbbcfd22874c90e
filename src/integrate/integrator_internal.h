/*
 * integrator_internal.h - the integrator's record and the per-method entry points shared by
 * integrator.c (public API, spec check, dispatch) and the method files integ_rk4.c,
 * integ_dopri5.c and integ_bdf.c. Not part of the public API (see integrator.h).
 *
 * Invariants, once a reset has succeeded (ready = 1):
 *   y = y(t), f = f(t, y) for rk4 and dopri5 (their first stage; dopri5's FSAL stage), and the
 *   last accepted step spans [t_prev, t] (t_prev = t right after a reset, before any step).
 *   y_prev and f_prev hold the state and slope at t_prev for the explicit methods' dense output.
 * A step computes into the *_new buffers and only an accepted step rotates them into place, so a
 * failed step (rhs error, step size underflow) leaves y, f and t at the last accepted step.
 * Every call of the rhs made by this code goes through ctc_integ_call_rhs, which counts it; bdf's
 * counts come from CVODE's own counters.
 */
#ifndef CTC_INTEGRATOR_INTERNAL_H
#define CTC_INTEGRATOR_INTERNAL_H

#include <float.h>
#include <math.h>
#include <stddef.h>

#include "integrator.h"

/* dopri5: stages k2..k6 of the step in progress and k3..k6 of the last accepted step (its dense
 * output needs them; k2 has weight zero there) */
#define CTC_DOPRI5_WORK_STAGES 5
#define CTC_DOPRI5_KEPT_STAGES 4

typedef struct ctc_bdf ctc_bdf; /* integ_bdf.c */

struct ctc_integrator {
    ctc_integ_spec spec;
    int n;
    ctc_ode_rhs rhs;
    ctc_ode_project proj; /* bdf: CVODE's in-step projection; NULL = none */
    void *ctx;

    int ready;     /* a reset succeeded: t, y (and f) are valid */
    double t;      /* s, end of the last accepted step */
    double t_prev; /* s, its start; equal to t right after a reset */
    double h;      /* dopri5: next step size to try (s), 0 = choose automatically; rk4: spec.step */

    double *y, *y_prev, *y_new; /* (n) each: state at t, at t_prev, of the step in progress */
    double *f, *f_prev, *f_new; /* (n) each: f at the same three points (rk4, dopri5) */
    double *y_stage;            /* (n) argument of the stage being evaluated */
    double *k_work[CTC_DOPRI5_WORK_STAGES]; /* (n) each: rk4 uses 3 (k2..k4), dopri5 all 5 */
    double *k_kept[CTC_DOPRI5_KEPT_STAGES]; /* (n) each, dopri5: k3..k6 of the last step */
    double *block;                          /* the one allocation all the arrays above live in */

    double err_old; /* dopri5: the previous accepted step's error norm (PI control), >= 1e-4 */
    int stiff_hits; /* dopri5: stiffness test (integ_dopri5.c): stability-bound steps counted */
    int stiff_miss; /* and the run of steps since the last one; neither is cleared by a reset */

    ctc_bdf *bdf; /* bdf: CVODE's memory and vectors; NULL otherwise */

    ctc_integ_stats stats;
};

/* The smallest step the explicit methods and bdf accept at time t: steps below 16 eps |t|
 * change t by only a few units in the last place. */
static inline int ctc_integ_below_roundoff(double h, double t)
{
    return !(h >= 16.0 * DBL_EPSILON * fabs(t)) || h == 0.0;
}

/* Calls the rhs and counts the call. */
static inline int ctc_integ_call_rhs(ctc_integrator *it, double t, const double *y, double *ydot)
{
    it->stats.rhs_evals++;
    return it->rhs(t, y, ydot, it->ctx);
}

/* The step to take from t towards tstop (> t) when the method wants step h (> 0) and may take
 * at most hmax (0 = no bound): the remaining distance itself when it is within 1% of h (and of
 * hmax), so no sliver is left over; half of it when it is less than two steps, so the last two
 * steps are equal; h otherwise. *lands is set to 1 when the step ends on tstop (its end time is
 * then tstop itself, not t + step, which may differ in the last bit). */
double ctc_integ_clip_step(double t, double tstop, double h, double hmax, int *lands);

/* Fills err with the round-off message and returns -1 (ctc_integrator_step's method failure). */
int ctc_integ_fail_roundoff(double h, double t, char *err, size_t errlen);

/* Fills err with the message for a step h wanted at time t below the spec's min_step and
 * returns -1 (ctc_integrator_step's method failure). */
int ctc_integ_fail_min_step(double h, double t, double min_step, char *err, size_t errlen);

/* Fills err with the message for an rhs that returned rc at time t and returns rc. */
int ctc_integ_fail_rhs(int rc, double t, char *err, size_t errlen);

/* ---- rk4 (integ_rk4.c) ---- */

/* One classical RK4 step towards tstop; f_new = f(t_new, y_new) is evaluated before the step is
 * accepted, so 4 evaluations a step. */
int ctc_rk4_step(ctc_integrator *it, double tstop, char *err, size_t errlen);

/* Cubic Hermite interpolation on the last step. */
void ctc_rk4_dense(const ctc_integrator *it, double t, double *y);

/* ---- dopri5 (integ_dopri5.c) ---- */

/* After a reset: the first reset takes spec.initial_step (0 leaves the choice to the first
 * step); later ones keep it->h; both bound it by spec.max_step. */
void ctc_dopri5_reset(ctc_integrator *it);

/* One accepted Dormand-Prince step towards tstop, after as many rejected attempts as the error
 * test asks for. */
int ctc_dopri5_step(ctc_integrator *it, double tstop, char *err, size_t errlen);

/* The 4th-order continuous extension on the last step. */
void ctc_dopri5_dense(const ctc_integrator *it, double t, double *y);

/* ---- bdf (integ_bdf.c) ---- */

/* Creates CVODE's memory for it (spec and n set) in it->bdf: CTC_OK, or CTC_ENOMEM or CTC_EINVAL
 * with a message, leaving what was made in it->bdf for ctc_integrator_free. */
ctc_status ctc_bdf_new(ctc_integrator *it, char *err, size_t errlen);

/* Frees what ctc_bdf_new made; NULL allowed. */
void ctc_bdf_free(ctc_bdf *bdf);

/* Restarts CVODE at (it->t, it->y) (CVodeReInit), keeping the counters; the first reset starts
 * from spec.initial_step, later ones let CVODE choose its starting step. Returns 0, or -1 if
 * CVODE refuses (which a valid spec never causes). */
int ctc_bdf_reset(ctc_integrator *it);

/* Turns CVODE's in-step projection on (it->proj set) or off (NULL): 0, or -1 if CVODE refuses. */
int ctc_bdf_set_projection(ctc_integrator *it);

/* Passes it->spec's rtol and atol to CVODE; 0, or -1 when it refuses them. */
int ctc_bdf_set_tolerances(ctc_integrator *it);

/* One CVODE step (CV_ONE_STEP) with stop time tstop. */
int ctc_bdf_step(ctc_integrator *it, double tstop, char *err, size_t errlen);

/* CVodeGetDky on the last step; NaN where CVODE refuses t. */
void ctc_bdf_dense(const ctc_integrator *it, double t, double *y);

#endif
