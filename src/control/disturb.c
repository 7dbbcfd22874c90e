/*
 * disturb.c - disturbance forces on one coordinate (disturb.h): none, a constant, a sinusoid and
 * a step.
 *
 * The sinusoid reduces t modulo the period before forming the angle, as the sinusoidal
 * trajectories do (traj.c), so its phase stays accurate at large t. A step is right-continuous:
 * at t == time the new value already applies, which is also where the simulation restarts its
 * integrator (ctc_disturb_breakpoint), so the integrator never steps across the jump.
 */
#include "disturb.h"

#include <math.h>

#include "spatial.h"

/* CTC_EINVAL with "<type>: <what> must be finite (got <x><unit>)" unless x is finite */
static ctc_status check_finite(const char *type, const char *what, double x, const char *unit,
                               char *err, size_t errlen)
{
    if (isfinite(x)) return CTC_OK;
    return ctc_fail(CTC_EINVAL, err, errlen, "%s: %s must be finite (got %g%s)", type, what, x,
                    unit);
}

static ctc_status check_sine(const ctc_disturb *z, char *err, size_t errlen)
{
    ctc_status st = check_finite("sine", "amplitude", z->amplitude, "", err, errlen);
    if (st != CTC_OK) return st;
    if (!isfinite(z->period) || !(z->period > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "sine: period must be positive and finite (got %g s)", z->period);
    }
    st = check_finite("sine", "phase", z->phase, " rad", err, errlen);
    if (st == CTC_OK) st = check_finite("sine", "offset", z->offset, "", err, errlen);
    if (st != CTC_OK) return st;

    /* the largest |z| and the angular frequency must be representable */
    if (!isfinite(fabs(z->offset) + fabs(z->amplitude))) {
        return ctc_fail(CTC_EINVAL, err, errlen, "sine: offset + amplitude overflows");
    }
    if (!isfinite(2 * CTC_PI / z->period)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "sine: period %g s is too short (2 pi / period overflows)", z->period);
    }
    return CTC_OK;
}

ctc_status ctc_disturb_check(const ctc_disturb *z, char *err, size_t errlen)
{
    if (z == NULL) return ctc_fail(CTC_EINVAL, err, errlen, "disturbance is NULL");
    switch (z->type) {
    case CTC_DISTURB_NONE:
        return CTC_OK;
    case CTC_DISTURB_CONSTANT:
        return check_finite("constant", "value", z->value, "", err, errlen);
    case CTC_DISTURB_SINE:
        return check_sine(z, err, errlen);
    case CTC_DISTURB_STEP: {
        ctc_status st = check_finite("step", "value", z->value, "", err, errlen);
        if (st == CTC_OK) st = check_finite("step", "time", z->time, " s", err, errlen);
        return st;
    }
    }
    return ctc_fail(CTC_EINVAL, err, errlen, "unknown disturbance type %d", (int)z->type);
}

double ctc_disturb_eval(const ctc_disturb *z, double t)
{
    switch (z->type) {
    case CTC_DISTURB_NONE:
        return 0;
    case CTC_DISTURB_CONSTANT:
        return z->value;
    case CTC_DISTURB_SINE: {
        double angle = 2 * CTC_PI / z->period * fmod(t, z->period) + z->phase;
        return z->offset + z->amplitude * sin(angle);
    }
    case CTC_DISTURB_STEP:
        /* right-continuous: the value applies from t == time on (a NaN t gives NaN) */
        if (isnan(t)) return NAN;
        return t >= z->time ? z->value : 0;
    }
    /* an unchecked, unknown type: make it visible */
    return NAN;
}

double ctc_disturb_breakpoint(const ctc_disturb *z)
{
    return z->type == CTC_DISTURB_STEP ? z->time : INFINITY;
}
