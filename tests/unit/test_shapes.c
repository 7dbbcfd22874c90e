/*
 * test_shapes.c - body specs of uniform solids (src/model/shapes.c) against the textbook formulas,
 * the parallel-axis theorem (a solid cut in two halves must give the same inertia as the two halves
 * moved to its centre of mass), and the exact message of every invalid argument.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "shapes.h"
#include "spatial.h"

#define TOL 1e-14 /* relative to the largest moment */

static double max_abs(int n, const double *a)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(a[i]));
    return s;
}

static double max_abs_diff(int n, const double *a, const double *b)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(a[i] - b[i]));
    return s;
}

/* inertia about point p of a body (about its CoM c): I_c + m (|d|^2 1 - d d^T), d = c - p */
static void about_point(const ctc_body_spec *b, const double p[3], double out[9])
{
    double d[3];
    ctc_v3_sub(d, b->com, p);
    double d2 = ctc_v3_dot(d, d);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            out[3 * i + j] = b->inertia[3 * i + j] + b->mass * ((i == j) * d2 - d[i] * d[j]);
        }
    }
}

/* merges two bodies' inertias about the combined CoM (parallel-axis theorem) */
static void merge(const ctc_body_spec *a, const ctc_body_spec *b, ctc_body_spec *out)
{
    double ia[9], ib[9];
    out->mass = a->mass + b->mass;
    for (int i = 0; i < 3; i++)
        out->com[i] = (a->mass * a->com[i] + b->mass * b->com[i]) / out->mass;
    about_point(a, out->com, ia);
    about_point(b, out->com, ib);
    for (int i = 0; i < 9; i++) out->inertia[i] = ia[i] + ib[i];
}

static void expect_spec(const ctc_body_spec *got, double mass, const double com[3],
                        const double inertia[9], const char *what)
{
    double scale = max_abs(9, inertia);
    cr_assert_leq(fabs(got->mass - mass), 1e-15 * mass, "%s: mass %.17g, want %.17g", what,
                  got->mass, mass);
    cr_assert_leq(max_abs_diff(3, got->com, com), 1e-15 * fmax(1.0, max_abs(3, com)),
                  "%s: com (%g %g %g), want (%g %g %g)", what, got->com[0], got->com[1],
                  got->com[2], com[0], com[1], com[2]);
    for (int i = 0; i < 9; i++) {
        cr_assert_leq(fabs(got->inertia[i] - inertia[i]), TOL * scale,
                      "%s: inertia[%d][%d] = %.17g, want %.17g", what, i / 3, i % 3,
                      got->inertia[i], inertia[i]);
    }
}

/* ---- textbook values ---- */

Test(shapes, rod_matches_textbook_inertia)
{
    /* along -y: com (0, -L/2, 0), diag(m L^2/12, 0, m L^2/12) */
    char err[128] = "";
    ctc_body_spec b;
    const double end[3] = {0, -1.5, 0}, com[3] = {0, -0.75, 0};
    const double a = 2.0 * 1.5 * 1.5 / 12;
    const double want[9] = {a, 0, 0, 0, 0, 0, 0, 0, a};
    cr_assert_eq(ctc_shape_rod(2.0, end, &b, err, sizeof err), CTC_OK, "%s", err);
    expect_spec(&b, 2.0, com, want, "rod along -y");

    /* along (1, 2, 2), L = 3: I e = 0, I n = m L^2/12 n for n normal to e */
    const double end2[3] = {1, 2, 2}, e[3] = {1.0 / 3, 2.0 / 3, 2.0 / 3}, n[3] = {2, -1, 0};
    double ie[3], in[3];
    cr_assert_eq(ctc_shape_rod(0.6, end2, &b, err, sizeof err), CTC_OK, "%s", err);
    const double a2 = 0.6 * 9 / 12;
    ctc_m3_mulv(ie, b.inertia, e);
    ctc_m3_mulv(in, b.inertia, n);
    cr_assert_leq(max_abs(3, ie), TOL * a2, "I e = (%g %g %g)", ie[0], ie[1], ie[2]);
    for (int i = 0; i < 3; i++) {
        cr_assert_leq(fabs(in[i] - a2 * n[i]), TOL * a2 * 2, "I n [%d] = %.17g, want %.17g", i,
                      in[i], a2 * n[i]);
    }
    cr_assert_leq(max_abs_diff(3, b.com, (double[3]){0.5, 1, 1}), 1e-16);

    /* about its end, normal to it: m L^2 / 3 */
    double iend[9], zero[3] = {0, 0, 0}, ien[3];
    about_point(&b, zero, iend);
    ctc_m3_mulv(ien, iend, n);
    double nn = ctc_v3_dot(n, n);
    cr_assert_leq(fabs(ctc_v3_dot(n, ien) / nn - 0.6 * 9 / 3), TOL * a2,
                  "about the end: %.17g, want m L^2/3 = %.17g", ctc_v3_dot(n, ien) / nn,
                  0.6 * 9 / 3);
}

Test(shapes, box_matches_textbook_inertia)
{
    /* m/12 diag(b^2 + c^2, a^2 + c^2, a^2 + b^2), centred at the given centre */
    char err[128] = "";
    ctc_body_spec b;
    const double size[3] = {1.0, 0.1, 0.2}, centre[3] = {0.5, -0.1, 0.3}, m = 3.0;
    const double want[9] = {m / 12 * (0.01 + 0.04), 0, 0, 0, m / 12 * (1 + 0.04), 0, 0, 0,
                            m / 12 * (1 + 0.01)};
    cr_assert_eq(ctc_shape_box(m, size, centre, &b, err, sizeof err), CTC_OK, "%s", err);
    expect_spec(&b, m, centre, want, "box");

    /* a cube: m a^2/6 about every axis */
    const double cube[3] = {0.4, 0.4, 0.4}, zero[3] = {0, 0, 0};
    const double c6 = 2.0 * 0.16 / 6;
    const double wantc[9] = {c6, 0, 0, 0, c6, 0, 0, 0, c6};
    cr_assert_eq(ctc_shape_box(2.0, cube, zero, &b, err, sizeof err), CTC_OK, "%s", err);
    expect_spec(&b, 2.0, zero, wantc, "cube");
}

Test(shapes, cylinder_matches_textbook_inertia)
{
    /* axis z: diag(m(3r^2 + L^2)/12, same, m r^2/2) */
    char err[128] = "";
    ctc_body_spec b;
    const double m = 1.5, r = 0.2, len = 0.9, z[3] = {0, 0, 1}, centre[3] = {0.1, 0.2, -0.3};
    const double t = m * (3 * r * r + len * len) / 12, ax = m * r * r / 2;
    const double want[9] = {t, 0, 0, 0, t, 0, 0, 0, ax};
    cr_assert_eq(ctc_shape_cylinder(m, r, len, z, centre, &b, err, sizeof err), CTC_OK, "%s", err);
    expect_spec(&b, m, centre, want, "cylinder along z");

    /* the axis may have any length: 5 z gives the same */
    const double z5[3] = {0, 0, 5};
    cr_assert_eq(ctc_shape_cylinder(m, r, len, z5, centre, &b, err, sizeof err), CTC_OK, "%s", err);
    expect_spec(&b, m, centre, want, "cylinder along 5 z");

    /* a tilted axis (1, 1, 0): I e = ax e, I n = t n for n normal to it */
    const double tilt[3] = {1, 1, 0}, e[3] = {1 / sqrt(2.0), 1 / sqrt(2.0), 0};
    const double n1[3] = {1, -1, 0}, n2[3] = {0, 0, 1};
    double ie[3], i1[3], i2[3];
    cr_assert_eq(ctc_shape_cylinder(m, r, len, tilt, centre, &b, err, sizeof err), CTC_OK, "%s",
                 err);
    ctc_m3_mulv(ie, b.inertia, e);
    ctc_m3_mulv(i1, b.inertia, n1);
    ctc_m3_mulv(i2, b.inertia, n2);
    for (int i = 0; i < 3; i++) {
        cr_assert_leq(fabs(ie[i] - ax * e[i]), TOL * t, "I e [%d]", i);
        cr_assert_leq(fabs(i1[i] - t * n1[i]), TOL * t, "I n1 [%d]", i);
        cr_assert_leq(fabs(i2[i] - t * n2[i]), TOL * t, "I n2 [%d]", i);
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            cr_assert_eq(b.inertia[3 * i + j], b.inertia[3 * j + i], "not symmetric");
        }
    }
}

/* ---- parallel-axis checks: a solid equals its two halves ---- */

Test(shapes, rod_equals_its_two_halves)
{
    /* rod 0 -> 2 s (mass 2m) = rod 0 -> s (m) + rod s -> 2 s (m), the second a rod 0 -> s moved
       by s */
    char err[128] = "";
    const double s[3] = {0.3, -0.8, 0.5}, s2[3] = {0.6, -1.6, 1.0};
    ctc_body_spec whole, half1, half2, merged;
    cr_assert_eq(ctc_shape_rod(2.4, s2, &whole, err, sizeof err), CTC_OK, "%s", err);
    cr_assert_eq(ctc_shape_rod(1.2, s, &half1, err, sizeof err), CTC_OK, "%s", err);
    half2 = half1;
    ctc_v3_add(half2.com, half1.com, s);
    merge(&half1, &half2, &merged);
    expect_spec(&whole, merged.mass, merged.com, merged.inertia, "rod halves");
}

Test(shapes, box_equals_its_two_halves)
{
    /* cut across each axis in turn */
    char err[128] = "";
    const double size[3] = {0.8, 0.3, 0.5}, centre[3] = {0.1, -0.2, 0.4}, m = 4.0;
    ctc_body_spec whole, half1, half2, merged;
    cr_assert_eq(ctc_shape_box(m, size, centre, &whole, err, sizeof err), CTC_OK, "%s", err);
    for (int ax = 0; ax < 3; ax++) {
        double hs[3] = {size[0], size[1], size[2]}, c1[3], c2[3];
        hs[ax] /= 2;
        ctc_v3_copy(c1, centre);
        ctc_v3_copy(c2, centre);
        c1[ax] -= size[ax] / 4;
        c2[ax] += size[ax] / 4;
        cr_assert_eq(ctc_shape_box(m / 2, hs, c1, &half1, err, sizeof err), CTC_OK, "%s", err);
        cr_assert_eq(ctc_shape_box(m / 2, hs, c2, &half2, err, sizeof err), CTC_OK, "%s", err);
        merge(&half1, &half2, &merged);
        expect_spec(&whole, merged.mass, merged.com, merged.inertia, "box halves");
    }
}

Test(shapes, cylinder_equals_its_two_halves)
{
    /* cut across a tilted axis: two cylinders of half the length at +-L/4 along it */
    char err[128] = "";
    const double axis[3] = {1, -2, 2}, e[3] = {1.0 / 3, -2.0 / 3, 2.0 / 3};
    const double centre[3] = {0.2, 0.1, -0.1}, m = 2.0, r = 0.15, len = 1.2;
    ctc_body_spec whole, half1, half2, merged;
    double c1[3], c2[3];
    ctc_v3_addscl(c1, centre, e, -len / 4);
    ctc_v3_addscl(c2, centre, e, len / 4);
    cr_assert_eq(ctc_shape_cylinder(m, r, len, axis, centre, &whole, err, sizeof err), CTC_OK, "%s",
                 err);
    cr_assert_eq(ctc_shape_cylinder(m / 2, r, len / 2, axis, c1, &half1, err, sizeof err), CTC_OK,
                 "%s", err);
    cr_assert_eq(ctc_shape_cylinder(m / 2, r, len / 2, axis, c2, &half2, err, sizeof err), CTC_OK,
                 "%s", err);
    merge(&half1, &half2, &merged);
    expect_spec(&whole, merged.mass, merged.com, merged.inertia, "cylinder halves");
}

/* ---- invalid arguments ---- */

static void expect_error(ctc_status st, const char *err, const char *want)
{
    cr_assert_eq(st, CTC_EINVAL, "status %s for \"%s\"", ctc_status_name(st), want);
    cr_assert_str_eq(err, want);
}

Test(shapes, rod_rejects_invalid_arguments_with_exact_messages)
{
    char err[128];
    ctc_body_spec b;
    const double end[3] = {0, -1, 0}, zero[3] = {0, 0, 0}, bad[3] = {0, NAN, 0};
    const double inf[3] = {INFINITY, 0, 0}, huge[3] = {1e200, 1e200, 0};
    expect_error(ctc_shape_rod(0.0, end, &b, err, sizeof err), err,
                 "rod: mass must be positive and finite (got 0)");
    expect_error(ctc_shape_rod(-1.5, end, &b, err, sizeof err), err,
                 "rod: mass must be positive and finite (got -1.5)");
    expect_error(ctc_shape_rod(INFINITY, end, &b, err, sizeof err), err,
                 "rod: mass must be positive and finite (got inf)");
    expect_error(ctc_shape_rod(NAN, end, &b, err, sizeof err), err,
                 "rod: mass must be positive and finite (got nan)");
    expect_error(ctc_shape_rod(1.0, zero, &b, err, sizeof err), err,
                 "rod: length must be positive and finite");
    expect_error(ctc_shape_rod(1.0, bad, &b, err, sizeof err), err,
                 "rod: length must be positive and finite");
    expect_error(ctc_shape_rod(1.0, inf, &b, err, sizeof err), err,
                 "rod: length must be positive and finite");
    expect_error(ctc_shape_rod(1.0, huge, &b, err, sizeof err), err, /* |end| overflows */
                 "rod: length must be positive and finite");
}

Test(shapes, box_rejects_invalid_arguments_with_exact_messages)
{
    char err[128];
    ctc_body_spec b;
    const double size[3] = {1, 0.1, 0.1}, centre[3] = {0, 0, 0};
    const double s1[3] = {1, 0, 0.1}, s2[3] = {1, 0.1, INFINITY}, s0[3] = {-2, 0.1, 0.1};
    const double c_bad[3] = {0, 0, NAN};
    expect_error(ctc_shape_box(-2.0, size, centre, &b, err, sizeof err), err,
                 "box: mass must be positive and finite (got -2)");
    expect_error(ctc_shape_box(0.0, size, centre, &b, err, sizeof err), err,
                 "box: mass must be positive and finite (got 0)");
    expect_error(ctc_shape_box(1.0, s0, centre, &b, err, sizeof err), err,
                 "box: size[0] must be positive and finite (got -2)");
    expect_error(ctc_shape_box(1.0, s1, centre, &b, err, sizeof err), err,
                 "box: size[1] must be positive and finite (got 0)");
    expect_error(ctc_shape_box(1.0, s2, centre, &b, err, sizeof err), err,
                 "box: size[2] must be positive and finite (got inf)");
    expect_error(ctc_shape_box(1.0, size, c_bad, &b, err, sizeof err), err,
                 "box: centre is not finite");
}

Test(shapes, cylinder_rejects_invalid_arguments_with_exact_messages)
{
    char err[128];
    ctc_body_spec b;
    const double axis[3] = {0, 0, 1}, centre[3] = {0, 0, 0}, zero[3] = {0, 0, 0};
    const double a_nan[3] = {NAN, 0, 1}, c_inf[3] = {0, -INFINITY, 0};
    expect_error(ctc_shape_cylinder(-1.0, 0.1, 1.0, axis, centre, &b, err, sizeof err), err,
                 "cylinder: mass must be positive and finite (got -1)");
    expect_error(ctc_shape_cylinder(1.0, -0.1, 1.0, axis, centre, &b, err, sizeof err), err,
                 "cylinder: radius must be positive and finite (got -0.1)");
    expect_error(ctc_shape_cylinder(1.0, NAN, 1.0, axis, centre, &b, err, sizeof err), err,
                 "cylinder: radius must be positive and finite (got nan)");
    expect_error(ctc_shape_cylinder(1.0, 0.1, 0.0, axis, centre, &b, err, sizeof err), err,
                 "cylinder: length must be positive and finite (got 0)");
    expect_error(ctc_shape_cylinder(1.0, 0.1, INFINITY, axis, centre, &b, err, sizeof err), err,
                 "cylinder: length must be positive and finite (got inf)");
    expect_error(ctc_shape_cylinder(1.0, 0.1, 1.0, zero, centre, &b, err, sizeof err), err,
                 "cylinder: axis has zero length");
    expect_error(ctc_shape_cylinder(1.0, 0.1, 1.0, a_nan, centre, &b, err, sizeof err), err,
                 "cylinder: axis is not finite");
    const double huge_axis[3] = {1e200, 1e200, 0}, huge_size[3] = {1e200, 1, 1};
    expect_error(ctc_shape_cylinder(1.0, 0.1, 1.0, huge_axis, centre, &b, err, sizeof err), err,
                 "cylinder: axis is too long (its length overflows)");
    expect_error(ctc_shape_box(1.0, huge_size, centre, &b, err, sizeof err), err,
                 "box: inertia overflows (mass or dimensions too large)");
    expect_error(ctc_shape_cylinder(1e300, 1e10, 1.0, axis, centre, &b, err, sizeof err), err,
                 "cylinder: inertia overflows (mass or dimensions too large)");
    expect_error(ctc_shape_cylinder(1.0, 0.1, 1.0, axis, c_inf, &b, err, sizeof err), err,
                 "cylinder: centre is not finite");
}

Test(shapes, error_buffer_may_be_null_or_short)
{
    /* no buffer: only the status; a short buffer: the message cut and terminated */
    ctc_body_spec b;
    const double zero[3] = {0, 0, 0};
    char err[8];
    memset(err, 'x', sizeof err);
    cr_assert_eq(ctc_shape_rod(1.0, zero, &b, NULL, 0), CTC_EINVAL);
    cr_assert_eq(ctc_shape_rod(1.0, zero, &b, err, sizeof err), CTC_EINVAL);
    cr_assert_str_eq(err, "rod: le");
}
