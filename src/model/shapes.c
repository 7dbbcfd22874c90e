/*
 * shapes.c - inertia of uniform solids (shapes.h), from the textbook formulas.
 */
#include "shapes.h"

#include <math.h>

#include "spatial.h"

static int finite3(const double v[3])
{
    return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]);
}

static ctc_status check_mass(const char *shape, double mass, char *err, size_t errlen)
{
    if (!isfinite(mass) || !(mass > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "%s: mass must be positive and finite (got %g)",
                        shape, mass);
    }
    return CTC_OK;
}

/* CTC_OK if the filled spec's numbers are finite; otherwise the dimensions overflowed */
static ctc_status check_result(const char *shape, const ctc_body_spec *b, char *err, size_t errlen)
{
    for (int i = 0; i < 9; i++) {
        if (!isfinite(b->inertia[i])) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "%s: inertia overflows (mass or dimensions too large)", shape);
        }
    }
    return CTC_OK;
}

/* inertia = a (1 - e e^T) + b e e^T for unit e: the tensor of a body symmetric about e */
static void axisymmetric(double inertia[9], const double e[3], double transverse, double axial)
{
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            inertia[3 * i + j] = (i == j ? transverse : 0.0) + (axial - transverse) * e[i] * e[j];
        }
    }
}

ctc_status ctc_shape_rod(double mass, const double end[3], ctc_body_spec *out, char *err,
                         size_t errlen)
{
    ctc_status st = check_mass("rod", mass, err, errlen);
    if (st != CTC_OK) return st;
    double len = finite3(end) ? ctc_v3_norm(end) : NAN;
    if (!(len > 0) || !isfinite(len)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "rod: length must be positive and finite");
    }
    double e[3];
    ctc_v3_scale(e, end, 1.0 / len);
    out->mass = mass;
    ctc_v3_scale(out->com, end, 0.5);
    axisymmetric(out->inertia, e, mass * len * len / 12.0, 0.0);
    return check_result("rod", out, err, errlen);
}

ctc_status ctc_shape_box(double mass, const double size[3], const double centre[3],
                         ctc_body_spec *out, char *err, size_t errlen)
{
    ctc_status st = check_mass("box", mass, err, errlen);
    if (st != CTC_OK) return st;
    for (int i = 0; i < 3; i++) {
        if (!isfinite(size[i]) || !(size[i] > 0)) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "box: size[%d] must be positive and finite (got %g)", i, size[i]);
        }
    }
    if (!finite3(centre)) return ctc_fail(CTC_EINVAL, err, errlen, "box: centre is not finite");
    double a2 = size[0] * size[0], b2 = size[1] * size[1], c2 = size[2] * size[2];
    out->mass = mass;
    ctc_v3_copy(out->com, centre);
    for (int i = 0; i < 9; i++) out->inertia[i] = 0;
    out->inertia[0] = mass * (b2 + c2) / 12.0;
    out->inertia[4] = mass * (a2 + c2) / 12.0;
    out->inertia[8] = mass * (a2 + b2) / 12.0;
    return check_result("box", out, err, errlen);
}

ctc_status ctc_shape_cylinder(double mass, double radius, double length, const double axis[3],
                              const double centre[3], ctc_body_spec *out, char *err, size_t errlen)
{
    ctc_status st = check_mass("cylinder", mass, err, errlen);
    if (st != CTC_OK) return st;
    if (!isfinite(radius) || !(radius > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "cylinder: radius must be positive and finite (got %g)", radius);
    }
    if (!isfinite(length) || !(length > 0)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "cylinder: length must be positive and finite (got %g)", length);
    }
    if (!finite3(axis)) return ctc_fail(CTC_EINVAL, err, errlen, "cylinder: axis is not finite");
    double n = ctc_v3_norm(axis);
    if (!isfinite(n)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "cylinder: axis is too long (its length overflows)");
    }
    if (!(n > 0)) return ctc_fail(CTC_EINVAL, err, errlen, "cylinder: axis has zero length");
    if (!finite3(centre)) {
        return ctc_fail(CTC_EINVAL, err, errlen, "cylinder: centre is not finite");
    }
    double e[3];
    ctc_v3_scale(e, axis, 1.0 / n);
    out->mass = mass;
    ctc_v3_copy(out->com, centre);
    axisymmetric(out->inertia, e, mass * (3 * radius * radius + length * length) / 12.0,
                 mass * radius * radius / 2.0);
    return check_result("cylinder", out, err, errlen);
}
