/*
 * ctrl_poles.c - gains that place the three closed-loop poles of one coordinate (ctrl.h; paper
 * section 6.2, Eq. 71-77).
 *
 * The closed loop of the error state E = (int e, e, de/dt) under w = K E is the companion matrix
 * of s^3 + kv s^2 + kp s + ki, so placing its poles at mu_0, mu_1, mu_2 means matching
 * coefficients with (s - mu_0)(s - mu_1)(s - mu_2):
 *     kv = -(mu_0 + mu_1 + mu_2),  kp = mu_0 mu_1 + mu_0 mu_2 + mu_1 mu_2,  ki = -mu_0 mu_1 mu_2.
 * A conjugate pair sigma +- i omega is multiplied out first into the real factor
 * s^2 - 2 sigma s + (sigma^2 + omega^2). Because every pole has a negative real part, every term
 * of each coefficient is positive, so the gains carry the poles' relative accuracy (no
 * cancellation).
 */
#include "ctrl.h"

#include <math.h>
#include <stdio.h>

#define CONJUGATE_RTOL 1e-12 /* relative to the pole's modulus */

/* "re" for a real pole, "re+imi" for a complex one */
static void format_pole(char *buf, size_t len, double re, double im)
{
    if (im == 0.0)
        snprintf(buf, len, "%g", re);
    else
        snprintf(buf, len, "%g%+gi", re, im);
}

/* whether pole j is the conjugate of pole i, to CONJUGATE_RTOL of |mu_i| */
static int is_conjugate(const double re[3], const double im[3], int i, int j)
{
    double tol = CONJUGATE_RTOL * hypot(re[i], im[i]);
    return fabs(re[j] - re[i]) <= tol && fabs(im[j] + im[i]) <= tol;
}

ctc_status ctc_ctrl_poles(const double re[3], const double im[3], ctc_gains *out, char *err,
                          size_t errlen)
{
    char pole[64];

    /* each pole finite and strictly in the left half plane */
    for (int j = 0; j < 3; j++) {
        format_pole(pole, sizeof pole, re[j], im[j]);
        if (!isfinite(re[j]) || !isfinite(im[j])) {
            return ctc_fail(CTC_EINVAL, err, errlen, "pole %d (%s) is not finite", j, pole);
        }
        if (!(re[j] < 0)) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "pole %d (%s) is not strictly in the left half plane", j, pole);
        }
    }

    /* pair every complex pole with its own conjugate */
    int partner[3] = {-1, -1, -1};
    for (int i = 0; i < 3; i++) {
        if (im[i] == 0.0 || partner[i] >= 0) continue;
        for (int j = 0; j < 3; j++) {
            if (j != i && partner[j] < 0 && is_conjugate(re, im, i, j)) {
                partner[i] = j;
                partner[j] = i;
                break;
            }
        }
        if (partner[i] < 0) {
            format_pole(pole, sizeof pole, re[i], im[i]);
            return ctc_fail(CTC_EINVAL, err, errlen, "pole %d (%s) has no conjugate partner", i,
                            pole);
        }
    }

    /* multiply out the factors (Eq. 77); all terms are positive */
    double ki, kp, kv;
    int pi = -1, pj = -1, real = -1;
    for (int j = 0; j < 3; j++) {
        if (partner[j] > j) {
            pi = j;
            pj = partner[j];
        }
    }
    if (pi >= 0) {
        for (int j = 0; j < 3; j++) {
            if (j != pi && j != pj) real = j;
        }
        /* (s^2 + p s + q)(s - r) */
        double p = -(re[pi] + re[pj]), q = re[pi] * re[pj] - im[pi] * im[pj], r = re[real];
        kv = p - r;
        kp = q - p * r;
        ki = -q * r;
    } else {
        double r0 = re[0], r1 = re[1], r2 = re[2];
        kv = -(r0 + r1 + r2);
        kp = r0 * r1 + r0 * r2 + r1 * r2;
        ki = -(r0 * r1 * r2);
    }

    /* the gains must be representable and pass the Routh test in double precision */
    if (!isfinite(ki) || !isfinite(kp) || !isfinite(kv)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "the poles are too far from the origin: the gains (ki, kp, kv) = "
                        "(%g, %g, %g) overflow",
                        ki, kp, kv);
    }
    if (!(ki > 0) || !(kp > 0) || !(kv > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "the poles are too close to the origin: the gains (ki, kp, kv) = "
                        "(%g, %g, %g) underflow to zero",
                        ki, kp, kv);
    }
    if (!(ki < kv * kp)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "the gains (ki, kp, kv) = (%.17g, %.17g, %.17g) fail the Routh-Hurwitz "
                        "test in double precision: the poles are too close to the imaginary axis",
                        ki, kp, kv);
    }
    out->ki = ki;
    out->kp = kp;
    out->kv = kv;
    return CTC_OK;
}

/* ---- the poles class (ctrl.h) ---- */

static ctc_status design_poles(const ctc_ctrl_params *p, ctc_gains *out, char *err, size_t errlen)
{
    return ctc_ctrl_poles(p->re, p->im, out, err, errlen);
}

const ctc_ctrl_class ctc_ctrl_class_poles = {
    .name = "poles",
    .params = CTC_CP_POLES,
    .required = CTC_CP_POLES,
    .nstate = 1,
    .design = design_poles,
    .law = ctc_ctrl_linear_law,
    .closed_loop = ctc_ctrl_linear_closed_loop,
};
