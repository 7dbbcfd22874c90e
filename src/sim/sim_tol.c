/*
 * sim_tol.c - the tolerance floor of an adaptive run (sim.h ctc_sim_metrics tolerance_floor):
 * an error tolerance no tighter than the right-hand side's own rounding allows.
 *
 * The accelerations of a CTC evaluation come from forces that nearly balance gravity and the
 * velocity terms, so they carry an absolute rounding error that grows with the chain's length
 * and conditioning (bench/NOTEBOOK.md, "Hard cases"): about 1e-15 of the forces on a short chain,
 * 1e-5 of them at 4096 planar rods. An adaptive step (dopri5, bdf) estimates its local error
 * from differences of evaluations, and the rounding enters that estimate as noise of about
 * h delta in the velocities, for a step h and an acceleration rounding delta: where that noise
 * exceeds atol + rtol |y| the controller shrinks the step until h delta fits, so the run takes
 * steps far below what the dynamics need, without getting more accurate (a 5 s default run at
 * planar 4096: about 30 minutes; bench/NOTEBOOK.md "Long chains to 65536").
 *
 * The estimate, on an open model at the initial state y0 = (q0, v0), after the integrator's
 * start has evaluated the accelerations a0 there: the round trip of a0 through the plant's own
 * passes, on a data block of its own (the run's data and results are not touched),
 *     delta = max_i |GDCA(iGDCA(a0))_i - a0_i|  (rad/s^2, m/s^2),
 * where a run whose plant pass takes the reference form (sim_rhs.c: a computed-torque controller
 * on the plant's own model) uses it here too, from the first evaluation's u0 and f_ref =
 * iGDCA(u0): GDCA(iGDCA(a0)) = u0 + M^-1 (iGDCA(a0) - iGDCA(u0)) (gdca.h ctc_gdca_forward_from),
 * whose error is the inverse passes' rounding carried through M^-1,
 *     rho = delta / max(max |a0|, max |GDCA(0)|),
 * the rounding of accelerations of the run's own size, where the driving forces balance the bias
 * terms as in every CTC step. rho is relative to the larger of the accelerations and the free
 * ones (no driving force: what gravity and the velocity terms alone would do), because the
 * rounding comes from the terms that cancel, not from their balance: a chain held at rest in
 * equilibrium has a0 = 0 up to rounding, and delta / max |a0| would be of order one there. The
 * floor:
 *     atol >= SIM_TOL_FLOOR_STEP delta,      rtol >= rho,
 * the velocity error that the rounding alone puts into a step of SIM_TOL_FLOOR_STEP, and the
 * relative accuracy the accelerations carry. A tolerance below it, the default's or a job's
 * own, is raised to it (ctc_integrator_set_tolerances, before the first step), and the metrics
 * say so with the reason (sim.h tol_reason); it is never lowered. Short and well-conditioned
 * chains stay far below the floor (the paper's scenes: delta ~ 1e-14 rad/s^2, a floor near
 * 1e-18 on atol and 1e-15 on rtol), so their runs are unchanged bitwise. Loop models (whose
 * closure has its own tolerance, sim.h loop_tol) and rk4 runs (no error control) are not
 * floored. How the floor was chosen, and what it does at 1024 to 65536 bodies:
 * bench/NOTEBOOK.md, "Long chains to 65536".
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "gdca.h"
#include "handles.h"
#include "kinematics.h"
#include "sim_internal.h"

/* max_i |a_i - u_i| (u NULL: zero) */
static double max_diff(const double *a, const double *u, int n)
{
    double e = 0;
    for (int i = 0; i < n; i++) {
        double d = fabs(a[i] - (u ? u[i] : 0));
        e = d > e || isnan(d) ? d : e;
    }
    return e;
}

ctc_status sim_tolerance_floor(const sim_ctx *c, const double *y0, ctc_integ_spec *is,
                               ctc_sim_metrics *mt, char *err, size_t errlen)
{
    const ctc_model *m = c->plant;
    const int adaptive = is->method != CTC_INTEG_RK4;
    mt->accel_rounding = NAN;
    mt->tol_atol = adaptive ? is->atol : NAN;
    mt->tol_rtol = adaptive ? is->rtol : NAN;
    mt->tol_floored = 0;
    mt->tol_reason[0] = '\0';
    if (!adaptive || m->has_loop) return CTC_OK;

    /* the round trip of the initial accelerations */
    const int nv = m->nv;
    ctc_data *d = ctc_data_new(m);
    double *buf = malloc(4 * ((size_t)nv + 1) * sizeof *buf);
    if (d == NULL || buf == NULL) {
        ctc_data_free(d);
        free(buf);
        return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    }
    double *a0 = buf, *f = a0 + nv + 1, *a = f + nv + 1, *afree = a + nv + 1;
    memcpy(a0, c->acc, (size_t)nv * sizeof *a0);
    ctc_kinematics(m, d, y0, y0 + c->nq);
    ctc_handles(m, d);
    if (c->ref_valid) { /* the run's pass is the reference form from u0 (sim_rhs.c) */
        ctc_gdca_inverse(m, d, a0, f);
        ctc_gdca_inverse(m, d, c->u, afree);
        ctc_gdca_forward_from(m, d, f, c->u, afree, a);
    } else {
        ctc_gdca_inverse(m, d, a0, f);
        ctc_gdca_forward(m, d, f, a);
    }
    memset(f, 0, (size_t)nv * sizeof *f);
    ctc_gdca_forward(m, d, f, afree);
    const double delta = max_diff(a, a0, nv),
                 scale = fmax(max_diff(a0, NULL, nv), max_diff(afree, NULL, nv));
    ctc_data_free(d);
    free(buf);
    mt->accel_rounding = delta;

    /* the floor */
    const double atol_min = SIM_TOL_FLOOR_STEP * delta, rtol_min = scale > 0 ? delta / scale : 0;
    if (!isfinite(atol_min) || !isfinite(rtol_min)) return CTC_OK; /* the run will say why */
    char what[2][80] = {"", ""};
    if (is->atol < atol_min) {
        snprintf(what[0], sizeof what[0], "atol %.3g raised to %.3g", is->atol, atol_min);
        is->atol = atol_min;
        mt->tol_floored |= 1;
    }
    if (is->rtol < rtol_min && rtol_min < 1) {
        snprintf(what[1], sizeof what[1], "rtol %.3g raised to %.3g", is->rtol, rtol_min);
        is->rtol = rtol_min;
        mt->tol_floored |= 2;
    }
    mt->tol_atol = is->atol;
    mt->tol_rtol = is->rtol;
    if (mt->tol_floored) {
        snprintf(mt->tol_reason, sizeof mt->tol_reason,
                 "%s%s%s: the initial accelerations round to %.2g (%.2g of their size), so a "
                 "tighter tolerance would only shrink the steps",
                 what[0], what[0][0] && what[1][0] ? ", " : "", what[1], delta, rtol_min);
    }
    return CTC_OK;
}
