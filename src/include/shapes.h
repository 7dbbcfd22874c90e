/*
 * shapes.h - body specs of uniform solids: slender rod, box (cuboid) and solid cylinder.
 *
 * Each helper fills a ctc_body_spec (mass, centre of mass and inertia about it, body frame) from
 * the shape's dimensions, in metres and kilograms. They validate their arguments and return
 * CTC_EINVAL with a message naming the argument, e.g. "rod: length must be positive and
 * finite", or "box: inertia overflows (mass or dimensions too large)".
 */
#ifndef CTC_SHAPES_H
#define CTC_SHAPES_H

#include "model.h"

/* Uniform slender rod from the body origin to the point end (body frame): centre of mass end/2,
 * inertia (m L^2 / 12)(1 - e e^T) with e = end / L. It has no inertia about its own axis: in
 * spatial form it is a singular body (model.h), refused where a joint spins it about that axis
 * alone. */
ctc_status ctc_shape_rod(double mass, const double end[3], ctc_body_spec *out, char *err,
                         size_t errlen);

/* Uniform box with edge lengths size (along the body axes) centred at centre:
 * inertia m/12 diag(b^2 + c^2, a^2 + c^2, a^2 + b^2). */
ctc_status ctc_shape_box(double mass, const double size[3], const double centre[3],
                         ctc_body_spec *out, char *err, size_t errlen);

/* Uniform solid cylinder of the given radius and length, its axis along axis (any length > 0),
 * centred at centre: m r^2 / 2 about the axis, m (3 r^2 + L^2) / 12 about any diameter. */
ctc_status ctc_shape_cylinder(double mass, double radius, double length, const double axis[3],
                              const double centre[3], ctc_body_spec *out, char *err, size_t errlen);

#endif
