/*
 * integrator.h - ODE integrators for dy/dt = f(t, y), stepped one step at a time.
 *
 * Three methods behind one interface, so a run (src/sim/sim.c) can check for divergence,
 * cancellation and progress between steps and sample the solution at its own output times:
 *
 *   rk4     classical fixed-step Runge-Kutta of order 4 (4 evaluations a step). Dense output by
 *           cubic Hermite interpolation from y and f at both ends of the step (order 3, the
 *           evaluation at the end is the next step's first, so it costs nothing).
 *   dopri5  Dormand-Prince 5(4), adaptive, local extrapolation (the 5th-order solution is kept),
 *           FSAL (6 evaluations an accepted step), PI step-size control, and the method's
 *           4th-order continuous extension for dense output - MATLAB's ode45, which the paper
 *           used. Error test: ||err_i / (atol + rtol max(|y_i|, |y_new_i|))||_rms <= 1.
 *           Stops a run that turns out stiff (Hairer's test: the step held at the stability
 *           limit on 15 steps) when reaching tstop would take more than 1e5 further steps.
 *   bdf     SUNDIALS CVODE, variable-order variable-step BDF (orders 1-5) with Newton iteration
 *           and a dense direct linear solver on a difference-quotient Jacobian; for stiff
 *           systems (very high gains). Dense output by CVodeGetDky. Optionally projects onto an
 *           invariant inside its steps (ctc_integrator_set_projection).
 *
 * The in-house explicit steppers are used rather than SUNDIALS ARKODE's ERKStep because they
 * cost less per step on the small systems of a chain (bench/NOTEBOOK.md, "Explicit integrators").
 *
 * The right-hand side returns 0 on success; any other value stops the step, is returned by
 * ctc_integrator_step and leaves the integrator's state at the last accepted step.
 * An integrator belongs to one thread. rk4 and dopri5 allocate only in ctc_integrator_new; bdf's
 * CVODE also allocates its projection memory once in ctc_integrator_set_projection and a little
 * at each Jacobian evaluation (its difference-quotient Jacobian).
 */
#ifndef CTC_INTEGRATOR_H
#define CTC_INTEGRATOR_H

#include <stddef.h>

#include "status.h"

/* Right-hand side: ydot (n) = f(t, y (n)); ctx is the pointer given to ctc_integrator_new. */
typedef int (*ctc_ode_rhs)(double t, const double *y, double *ydot, void *ctx);

/* Projection onto an invariant of the ODE (a manifold its exact solution stays on, such as a
 * kinematic loop's closure): moves y (n) at time t onto it in place, or leaves it where it is
 * close enough; returns 0, or non-zero to stop the step (ctc_integrator_set_projection). ctx is
 * the pointer given to ctc_integrator_new. */
typedef int (*ctc_ode_project)(double t, double *y, void *ctx);

typedef enum ctc_integ_method {
    CTC_INTEG_RK4,
    CTC_INTEG_DOPRI5,
    CTC_INTEG_BDF,
} ctc_integ_method;

typedef struct ctc_integ_spec {
    ctc_integ_method method;
    double step;         /* rk4: step size h > 0 (s) */
    double rtol, atol;   /* dopri5, bdf: relative and absolute tolerance, > 0 */
    double initial_step; /* dopri5, bdf: first step (s); 0 = chosen automatically */
    double max_step;     /* dopri5, bdf: largest step (s); 0 = unbounded */
    double min_step;     /* dopri5, bdf: smallest step (s) the error control may take before
                            ctc_integrator_step fails ("step size ... below min_step"); 0 = only
                            the round-off limit. A step cut short to land on tstop is exempt */
    long max_steps;      /* any: ctc_integrator_step fails after this many steps; 0 = no limit */
} ctc_integ_spec;

typedef struct ctc_integ_stats {
    long steps;          /* accepted steps */
    long rejected;       /* rejected steps (error test or, for bdf, convergence failures) */
    long rhs_evals;      /* right-hand-side evaluations, Jacobian difference quotients included */
    long jac_evals;      /* bdf: Jacobian evaluations; 0 otherwise */
    double err_estimate; /* sum over accepted steps of the local error estimate's max-norm
                            (units of y); the global error can exceed it where the dynamics
                            amplify errors. NaN for rk4, which has no estimate */
    double h_last;       /* the last accepted step size, s */
} ctc_integ_stats;

typedef struct ctc_integrator ctc_integrator;

/* Checks spec: the method's own fields must be finite and positive (e.g. "step must be
 * positive and finite (got 0 s)", "rtol must be in (0, 1) (got 2)"), max_step >= 0,
 * min_step >= 0 and finite and, with max_step > 0, min_step <= max_step, and max_steps >= 0. */
ctc_status ctc_integ_check(const ctc_integ_spec *spec, char *err, size_t errlen);

/* Makes an integrator for an n-dimensional system (n >= 1). The spec is copied. On success
 * *out owns it (ctc_integrator_free); returns CTC_EINVAL (bad spec) or CTC_ENOMEM otherwise. */
ctc_status ctc_integrator_new(const ctc_integ_spec *spec, int n, ctc_ode_rhs rhs, void *ctx,
                              ctc_integrator **out, char *err, size_t errlen);

/* Frees it; NULL is allowed. */
void ctc_integrator_free(ctc_integrator *it);

/* Starts (or restarts, after a discontinuity or a change of y made by the caller) at time t0
 * from y0 (n): forgets the step history (dopri5's FSAL stage, bdf's history) but keeps the
 * stats (max_steps counts from ctc_integrator_new) and, for rk4 and dopri5, the current step
 * size; bdf restarts at order 1 and lets CVODE choose its starting step. Evaluates f once;
 * returns what the rhs returned (0 = ok). */
int ctc_integrator_reset(ctc_integrator *it, double t0, const double *y0);

/* Sets the tolerances of an adaptive integrator (dopri5, bdf) from its next step on: rtol in
 * (0, 1), atol > 0 and finite, as ctc_integ_check requires. The state, the step size and the
 * statistics are kept. Returns CTC_OK, or CTC_EINVAL with a message (rk4 has no tolerances: "rk4
 * has no tolerances"; a value out of range as ctc_integ_check words it). */
ctc_status ctc_integrator_set_tolerances(ctc_integrator *it, double rtol, double atol, char *err,
                                         size_t errlen);

/* bdf only: has CVODE call proj inside every step, after its Newton iteration and before its
 * error test (CVODE's projection, CVodeSetProjFn), and take the correction into the step. So a
 * projection keeps CVODE's order and step-size history, which putting the state back with
 * ctc_integrator_reset would throw away (order 1 and a fresh step size after every step). A
 * call can belong to an attempt that the error test then rejects; the last call before
 * ctc_integrator_step returns after an accepted step is that step's. The error estimate is not
 * projected (the test sees the error before the projection: conservative). A non-zero return of
 * proj fails the step: ctc_integrator_step returns it, as for the rhs, with "projection failed
 * (returned 3) at t = ... s". NULL turns it off. Returns CTC_OK; CTC_EINVAL for rk4 and dopri5,
 * whose callers project between steps and reset (their restart is one evaluation of f). */
ctc_status ctc_integrator_set_projection(ctc_integrator *it, ctc_ode_project proj, char *err,
                                         size_t errlen);

/* Takes one step from the current time t towards tstop > t, never past it (a step that would
 * pass it is shortened to end exactly on it). Returns 0 after an accepted step; the rhs's
 * non-zero code if it failed; -1 with a message in err when the method fails (step size below
 * the round-off limit, too many steps, bdf convergence failure, dopri5 on a stiff problem) - e.g.
 * "step size 1.2e-15 s at t = 0.73 s fell below the round-off limit", or "stiff: step size below
 * the stability limit, h = 2.39e-05 s at t = 0.0594776982 s (h |lambda| > 3.25 on 15 steps),
 * 2.1e+05 steps short of t = 5 s: use \"method\": \"bdf\"" (integ_dopri5.c). */
int ctc_integrator_step(ctc_integrator *it, double tstop, char *err, size_t errlen);

/* Current time (end of the last accepted step) and state (n; valid until the next call). */
double ctc_integrator_time(const ctc_integrator *it);
const double *ctc_integrator_state(const ctc_integrator *it);

/* The solution at t within the last accepted step [t_prev, t_now] by the method's dense
 * output, into y (n). At t = t_now it is the state exactly. */
void ctc_integrator_dense(const ctc_integrator *it, double t, double *y);

/* Counters since ctc_integrator_new (bdf: CVODE's own, summed over its restarts). */
const ctc_integ_stats *ctc_integrator_stats(const ctc_integrator *it);

/* Method name ("rk4", "dopri5", "bdf"). */
const char *ctc_integ_method_name(ctc_integ_method m);

#endif
