/*
 * ctc.h - the ctcsim library in one include: model, state, kinematics, handle equations, GDCA
 * forward and inverse dynamics, closed loops, and the independent oracle used by tests and
 * benchmarks.
 */
#ifndef CTC_H
#define CTC_H

#include "data.h"
#include "gdca.h"
#include "handles.h"
#include "kinematics.h"
#include "loop.h"
#include "model.h"
#include "shapes.h"
#include "status.h"

#endif
