/*
 * integ_rk4.c - the classical fixed-step Runge-Kutta method of order 4, with cubic Hermite dense
 * output (integrator.h).
 *
 * One step of size h from (t, y), with k1 = f(t, y) kept from the previous step:
 *     k2 = f(t + h/2, y + h/2 k1),  k3 = f(t + h/2, y + h/2 k2),  k4 = f(t + h, y + h k3),
 *     y_new = y + h/6 (k1 + 2 k2 + 2 k3 + k4)
 * (Hairer, Norsett and Wanner, Solving ODEs I, section II.1). The step ends by evaluating
 * f(t + h, y_new): it is the next step's k1 and the slope the dense output needs at the end, so a
 * step costs 4 evaluations and the interpolation costs none.
 *
 * Dense output on [t_prev, t] with theta = (s - t_prev) / h is the cubic that matches y and f at
 * both ends (Hermite basis):
 *     y(s) = (1 - 3 theta^2 + 2 theta^3) y0 + (3 theta^2 - 2 theta^3) y1
 *          + h (theta - 2 theta^2 + theta^3) f0 + h (theta^3 - theta^2) f1,
 * whose error is O(h^4) on top of the step's own.
 *
 * The step size is spec.step except where tstop cuts it (ctc_integ_clip_step).
 */
#include <string.h>

#include "integrator_internal.h"

/* out = y + a k */
static void axpy(int n, double *out, const double *y, double a, const double *k)
{
    for (int i = 0; i < n; i++) out[i] = y[i] + a * k[i];
}

static void swap(double **a, double **b)
{
    double *tmp = *a;
    *a = *b;
    *b = tmp;
}

int ctc_rk4_step(ctc_integrator *it, double tstop, char *err, size_t errlen)
{
    const int n = it->n;
    const double t = it->t;
    if (ctc_integ_below_roundoff(it->spec.step, t)) {
        return ctc_integ_fail_roundoff(it->spec.step, t, err, errlen);
    }
    int lands;
    const double h = ctc_integ_clip_step(t, tstop, it->spec.step, 0.0, &lands);
    const double t_new = lands ? tstop : t + h;
    const double *y = it->y, *k1 = it->f;
    double *k2 = it->k_work[0], *k3 = it->k_work[1], *k4 = it->k_work[2];
    double *ys = it->y_stage, *y_new = it->y_new;
    int rc;

    /* the three new stages */
    axpy(n, ys, y, 0.5 * h, k1);
    if ((rc = ctc_integ_call_rhs(it, t + 0.5 * h, ys, k2)) != 0) {
        return ctc_integ_fail_rhs(rc, t + 0.5 * h, err, errlen);
    }
    axpy(n, ys, y, 0.5 * h, k2);
    if ((rc = ctc_integ_call_rhs(it, t + 0.5 * h, ys, k3)) != 0) {
        return ctc_integ_fail_rhs(rc, t + 0.5 * h, err, errlen);
    }
    axpy(n, ys, y, h, k3);
    if ((rc = ctc_integ_call_rhs(it, t_new, ys, k4)) != 0) {
        return ctc_integ_fail_rhs(rc, t_new, err, errlen);
    }

    /* the new state and its slope, which the next step starts from */
    const double h6 = h / 6.0;
    for (int i = 0; i < n; i++) y_new[i] = y[i] + h6 * (k1[i] + 2.0 * (k2[i] + k3[i]) + k4[i]);
    if ((rc = ctc_integ_call_rhs(it, t_new, y_new, it->f_new)) != 0) {
        return ctc_integ_fail_rhs(rc, t_new, err, errlen);
    }

    /* accept: rotate new -> current -> previous */
    swap(&it->y_prev, &it->y);
    swap(&it->y, &it->y_new);
    swap(&it->f_prev, &it->f);
    swap(&it->f, &it->f_new);
    it->t_prev = t;
    it->t = t_new;
    it->stats.steps++;
    it->stats.h_last = h;
    return 0;
}

void ctc_rk4_dense(const ctc_integrator *it, double t, double *y)
{
    const double h = it->t - it->t_prev;
    const double th = (t - it->t_prev) / h, th2 = th * th, th3 = th2 * th;
    const double c_y0 = 1.0 - 3.0 * th2 + 2.0 * th3, c_y1 = 3.0 * th2 - 2.0 * th3;
    const double c_f0 = h * (th - 2.0 * th2 + th3), c_f1 = h * (th3 - th2);
    const double *y0 = it->y_prev, *y1 = it->y, *f0 = it->f_prev, *f1 = it->f;
    for (int i = 0; i < it->n; i++)
        y[i] = c_y0 * y0[i] + c_y1 * y1[i] + c_f0 * f0[i] + c_f1 * f1[i];
}
