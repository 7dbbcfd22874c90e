/*
 * disturb.h - disturbance forces on one joint coordinate, added to the driving force after the
 * controller (DESIGN.md section 6): the plant feels f + z(t) while the controller computed f.
 *
 *   none      z = 0
 *   constant  z = value
 *   sine      z = offset + amplitude sin(2 pi t / period + phase)
 *   step      z = 0 before time, value from time on (a discontinuity: the simulation restarts
 *             its integrator there, see ctc_disturb_breakpoint)
 *
 * Units: N m (revolute) or N (prismatic); t and time in s; phase in rad. Pure and thread-safe.
 */
#ifndef CTC_DISTURB_H
#define CTC_DISTURB_H

#include <stddef.h>

#include "status.h"

typedef enum ctc_disturb_type {
    CTC_DISTURB_NONE = 0,
    CTC_DISTURB_CONSTANT,
    CTC_DISTURB_SINE,
    CTC_DISTURB_STEP,
} ctc_disturb_type;

typedef struct ctc_disturb {
    ctc_disturb_type type;
    double value;                    /* constant, step */
    double amplitude, period, phase; /* sine: period > 0 */
    double offset;                   /* sine */
    double time;                     /* step: s */
} ctc_disturb;

/* Checks the parameters (finite, period > 0, offset + amplitude representable); a none ignores
 * its fields. The message starts with the type and names the parameter and the reason, e.g.
 * "sine: period must be positive and finite (got 0 s)". */
ctc_status ctc_disturb_check(const ctc_disturb *z, char *err, size_t errlen);

/* The disturbance at time t; z must have passed ctc_disturb_check. A step is right-continuous:
 * at t == time it already has its value. */
double ctc_disturb_eval(const ctc_disturb *z, double t);

/* The time of z's discontinuity (a step's time), or INFINITY when it has none. */
double ctc_disturb_breakpoint(const ctc_disturb *z);

#endif
