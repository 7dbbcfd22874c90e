/*
 * test_spatial.c - the 3-D geometry helpers (src/include/spatial.h, src/core/spatial.c):
 * eigenvalues of symmetric 3x3 matrices against known spectra, quaternions against axis-angle
 * rotations and the quaternion product written out here, Rodrigues' formula against its vector
 * form, and the basis of normals to an axis.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "chains.h"
#include "spatial.h"

/* R D R^T with D = diag(d), written out */
static void rotated_diag(const double r[9], const double d[3], double s[9])
{
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            s[3 * i + j] = r[3 * i] * d[0] * r[3 * j] + r[3 * i + 1] * d[1] * r[3 * j + 1] +
                           r[3 * i + 2] * d[2] * r[3 * j + 2];
        }
    }
}

static void sort3(double a[3])
{
    for (int i = 0; i < 2; i++) {
        for (int j = 0; j < 2 - i; j++) {
            if (a[j] > a[j + 1]) {
                double t = a[j];
                a[j] = a[j + 1];
                a[j + 1] = t;
            }
        }
    }
}

static double max_abs_diff(int n, const double *a, const double *b)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(a[i] - b[i]));
    return s;
}

/* ---- eigenvalues ---- */

Test(spatial, eigenvalues_of_diagonal_matrices_are_the_sorted_diagonal)
{
    const double cases[][3] = {{3, -1, 2}, {1, 2, 3}, {3, 2, 1}, {0, 0, 0}, {-4, -4, 7}, {5, 5, 5}};
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        double s[9] = {cases[c][0], 0, 0, 0, cases[c][1], 0, 0, 0, cases[c][2]}, eig[3];
        double want[3] = {cases[c][0], cases[c][1], cases[c][2]};
        sort3(want);
        ctc_sym3_eigenvalues(s, eig);
        for (int i = 0; i < 3; i++) {
            cr_assert_eq(eig[i], want[i], "case %zu: eig[%d] = %.17g, want %.17g", c, i, eig[i],
                         want[i]);
        }
    }
}

Test(spatial, eigenvalues_of_matrices_with_zero_diagonal)
{
    /* [[0 1 0] [1 0 0] [0 0 0]]: (-1, 0, 1); [[0 1 1] [1 0 1] [1 1 0]]: (-1, -1, 2) */
    const double s1[9] = {0, 1, 0, 1, 0, 0, 0, 0, 0}, want1[3] = {-1, 0, 1};
    const double s2[9] = {0, 1, 1, 1, 0, 1, 1, 1, 0}, want2[3] = {-1, -1, 2};
    double eig[3];
    ctc_sym3_eigenvalues(s1, eig);
    cr_assert_leq(max_abs_diff(3, eig, want1), 1e-15, "(%.17g %.17g %.17g)", eig[0], eig[1],
                  eig[2]);
    ctc_sym3_eigenvalues(s2, eig);
    cr_assert_leq(max_abs_diff(3, eig, want2), 4e-15, "(%.17g %.17g %.17g)", eig[0], eig[1],
                  eig[2]);
}

Test(spatial, eigenvalues_of_rotated_diagonal_matrices_match_their_spectrum)
{
    /* S = R D R^T for random rotations and spectra (distinct, repeated, nearly repeated, of mixed
       sign): |eig - sorted D| <= 2e-14 max |D| */
    uint64_t rng = 7;
    double worst = 0;
    for (int t = 0; t < 400; t++) {
        double axis[3], r[9], d[3], s[9], eig[3];
        test_random_unit(&rng, axis);
        ctc_m3_axis_angle(r, axis, test_uniform(&rng, -CTC_PI, CTC_PI));
        for (int i = 0; i < 3; i++) d[i] = test_uniform(&rng, -5, 5);
        switch (t % 4) {
        case 1:
            d[1] = d[0];
            break; /* a repeated pair */
        case 2:
            d[1] = d[2] = d[0];
            break; /* a multiple of the identity */
        case 3:
            d[1] = d[0] * (1 + 1e-10);
            break; /* nearly repeated */
        default:
            break;
        }
        rotated_diag(r, d, s);
        ctc_sym3_eigenvalues(s, eig);
        sort3(d);
        double scale = fmax(fabs(d[0]), fmax(fabs(d[1]), fabs(d[2])));
        double e = max_abs_diff(3, eig, d) / scale;
        worst = fmax(worst, e);
        cr_assert_leq(e, 2e-14, "trial %d: eig (%.17g %.17g %.17g), spectrum (%.17g %.17g %.17g)",
                      t, eig[0], eig[1], eig[2], d[0], d[1], d[2]);
        cr_assert(eig[0] <= eig[1] && eig[1] <= eig[2], "trial %d: not ascending", t);
    }
    cr_log_info("rotated spectra: worst relative error %.2e (tolerance 2e-14)", worst);
}

Test(spatial, eigenvalues_of_a_slender_rod_are_zero_and_a_repeated_pair)
{
    /* I = (m L^2 / 12)(1 - e e^T): spectrum (0, a, a), a = m L^2 / 12 */
    uint64_t rng = 11;
    for (int t = 0; t < 100; t++) {
        double e[3], s[9], eig[3], mass = test_uniform(&rng, 0.1, 10),
                                   len = test_uniform(&rng, 0.1, 3);
        double a = mass * len * len / 12;
        test_random_unit(&rng, e);
        if (t < 3) ctc_v3_set(e, t == 0, t == 1, t == 2); /* along the coordinate axes */
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) s[3 * i + j] = a * ((i == j) - e[i] * e[j]);
        }
        ctc_sym3_eigenvalues(s, eig);
        cr_assert_leq(fabs(eig[0]), 1e-14 * a, "trial %d: zero moment %.3e", t, eig[0]);
        cr_assert_leq(fabs(eig[1] - a), 1e-14 * a, "trial %d: eig[1] = %.17g, want %.17g", t,
                      eig[1], a);
        cr_assert_leq(fabs(eig[2] - a), 1e-14 * a, "trial %d: eig[2] = %.17g, want %.17g", t,
                      eig[2], a);
    }
}

/* ---- rotations and quaternions ---- */

static double orthonormality_error(const double r[9])
{
    double e = 0;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            double dot = r[i] * r[j] + r[3 + i] * r[3 + j] + r[6 + i] * r[6 + j]; /* (R^T R)_ij */
            e = fmax(e, fabs(dot - (i == j)));
        }
    }
    return e;
}

static double det3(const double a[9])
{
    return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
           a[2] * (a[3] * a[7] - a[4] * a[6]);
}

/* Hamilton product p (x) q, (w, x, y, z) */
static void quat_mul(const double p[4], const double q[4], double r[4])
{
    r[0] = p[0] * q[0] - p[1] * q[1] - p[2] * q[2] - p[3] * q[3];
    r[1] = p[0] * q[1] + p[1] * q[0] + p[2] * q[3] - p[3] * q[2];
    r[2] = p[0] * q[2] - p[1] * q[3] + p[2] * q[0] + p[3] * q[1];
    r[3] = p[0] * q[3] + p[1] * q[2] - p[2] * q[1] + p[3] * q[0];
}

Test(spatial, quaternion_rotation_is_orthonormal_with_unit_determinant)
{
    /* any non-zero quaternion, not normalised: R^T R = 1 and det R = 1 to 4e-15 */
    uint64_t rng = 3;
    double worst = 0;
    for (int t = 0; t < 1000; t++) {
        double q[4], r[9], scale = exp(test_uniform(&rng, -3, 3));
        for (int i = 0; i < 4; i++) q[i] = scale * test_uniform(&rng, -1, 1);
        ctc_m3_from_quat(r, q);
        double e = fmax(orthonormality_error(r), fabs(det3(r) - 1));
        worst = fmax(worst, e);
        cr_assert_leq(e, 4e-15, "trial %d: orthonormality/determinant error %.3e", t, e);
    }
    cr_log_info("quaternion rotations: worst orthonormality error %.2e (tolerance 4e-15)", worst);
}

Test(spatial, quaternion_of_axis_angle_gives_the_axis_angle_rotation)
{
    /* (cos th/2, sin th/2 a), its negative and any positive multiple all give
       ctc_m3_axis_angle(a, th) to 4e-15 */
    uint64_t rng = 5;
    double worst = 0;
    for (int t = 0; t < 500; t++) {
        double a[3], q[4], r[9], want[9];
        double th = test_uniform(&rng, -2 * CTC_PI, 2 * CTC_PI);
        test_random_unit(&rng, a);
        if (t < 6) { /* the coordinate axes, both signs */
            ctc_v3_set(a, 0, 0, 0);
            a[t % 3] = t < 3 ? 1 : -1;
        }
        ctc_m3_axis_angle(want, a, th);
        double mult[3] = {1.0, -1.0, 3.7};
        for (int s = 0; s < 3; s++) {
            q[0] = mult[s] * cos(th / 2);
            for (int i = 0; i < 3; i++) q[1 + i] = mult[s] * sin(th / 2) * a[i];
            ctc_m3_from_quat(r, q);
            double e = max_abs_diff(9, r, want);
            worst = fmax(worst, e);
            cr_assert_leq(e, 4e-15, "trial %d, multiple %g: differs by %.3e", t, mult[s], e);
        }
    }
    cr_log_info("quaternion vs axis-angle: worst difference %.2e (tolerance 4e-15)", worst);
}

Test(spatial, quaternion_product_composes_rotations)
{
    /* R(p (x) q) = R(p) R(q) */
    uint64_t rng = 9;
    for (int t = 0; t < 300; t++) {
        double p[4], q[4], pq[4], rp[9], rq[9], rpq[9], prod[9];
        for (int i = 0; i < 4; i++) {
            p[i] = test_uniform(&rng, -1, 1);
            q[i] = test_uniform(&rng, -1, 1);
        }
        quat_mul(p, q, pq);
        ctc_m3_from_quat(rp, p);
        ctc_m3_from_quat(rq, q);
        ctc_m3_from_quat(rpq, pq);
        ctc_m3_mul(prod, rp, rq);
        cr_assert_leq(max_abs_diff(9, rpq, prod), 4e-15, "trial %d: differs by %.3e", t,
                      max_abs_diff(9, rpq, prod));
    }
}

Test(spatial, zero_quaternion_gives_the_identity)
{
    const double zero[4] = {0, 0, 0, 0}, eye[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double r[9];
    ctc_m3_from_quat(r, zero);
    cr_assert_eq(max_abs_diff(9, r, eye), 0.0);
}

Test(spatial, axis_angle_rotates_by_the_right_hand_rule)
{
    /* R x = x cos th + (a x x) sin th + a (a . x)(1 - cos th); a quarter turn about z takes x to
       y */
    const double ez[3] = {0, 0, 1}, ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0};
    double r[9], y[3];
    ctc_m3_axis_angle(r, ez, CTC_PI / 2);
    ctc_m3_mulv(y, r, ex);
    cr_assert_leq(max_abs_diff(3, y, ey), 1e-16, "Rz(pi/2) x = (%g %g %g)", y[0], y[1], y[2]);

    uint64_t rng = 13;
    for (int t = 0; t < 300; t++) {
        double a[3], x[3], ax[3], want[3], got[3], th = test_uniform(&rng, -CTC_PI, CTC_PI);
        test_random_unit(&rng, a);
        for (int i = 0; i < 3; i++) x[i] = test_uniform(&rng, -2, 2);
        ctc_m3_axis_angle(r, a, th);
        ctc_m3_mulv(got, r, x);
        ctc_v3_cross(ax, a, x);
        double c = cos(th), s = sin(th), ad = ctc_v3_dot(a, x);
        for (int i = 0; i < 3; i++) want[i] = x[i] * c + ax[i] * s + a[i] * ad * (1 - c);
        cr_assert_leq(max_abs_diff(3, got, want), 1e-14, "trial %d: differs by %.3e", t,
                      max_abs_diff(3, got, want));
        cr_assert_leq(orthonormality_error(r), 4e-15, "trial %d: orthonormality error %.3e", t,
                      orthonormality_error(r));
    }
}

Test(spatial, rotate_sym_equals_r_s_rt)
{
    /* ctc_m3_rotate_sym(R, S) = R S R^T written out, and exactly symmetric */
    uint64_t rng = 17;
    for (int t = 0; t < 200; t++) {
        double a[3], r[9], s[9], got[9], want[9];
        test_random_unit(&rng, a);
        ctc_m3_axis_angle(r, a, test_uniform(&rng, -CTC_PI, CTC_PI));
        for (int i = 0; i < 3; i++) {
            for (int j = i; j < 3; j++) s[3 * i + j] = s[3 * j + i] = test_uniform(&rng, -1, 1);
        }
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) {
                double x = 0;
                for (int k = 0; k < 3; k++) {
                    for (int l = 0; l < 3; l++) x += r[3 * i + k] * s[3 * k + l] * r[3 * j + l];
                }
                want[3 * i + j] = x;
            }
        }
        ctc_m3_rotate_sym(got, r, s);
        cr_assert_leq(max_abs_diff(9, got, want), 4e-15, "trial %d", t);
        for (int i = 0; i < 3; i++) {
            for (int j = 0; j < 3; j++) cr_assert_eq(got[3 * i + j], got[3 * j + i]);
        }
    }
}

/* ---- normals to an axis ---- */

static void check_normals(const double a[3], const char *what)
{
    double n1[3], n2[3], m1[3], m2[3], c[3];
    ctc_v3_normals(a, n1, n2);
    cr_assert_leq(fabs(ctc_v3_norm(n1) - 1), 2e-15, "%s: |n1| = %.17g", what, ctc_v3_norm(n1));
    cr_assert_leq(fabs(ctc_v3_norm(n2) - 1), 2e-15, "%s: |n2| = %.17g", what, ctc_v3_norm(n2));
    cr_assert_leq(fabs(ctc_v3_dot(a, n1)), 2e-15, "%s: a . n1 = %.3e", what, ctc_v3_dot(a, n1));
    cr_assert_leq(fabs(ctc_v3_dot(a, n2)), 2e-15, "%s: a . n2 = %.3e", what, ctc_v3_dot(a, n2));
    cr_assert_leq(fabs(ctc_v3_dot(n1, n2)), 2e-15, "%s: n1 . n2 = %.3e", what, ctc_v3_dot(n1, n2));
    /* right-handed: (a x n1) . n2 = +1 */
    ctc_v3_cross(c, a, n1);
    cr_assert_leq(fabs(ctc_v3_dot(c, n2) - 1), 2e-15, "%s: (a x n1) . n2 = %.17g", what,
                  ctc_v3_dot(c, n2));
    /* deterministic */
    ctc_v3_normals(a, m1, m2);
    cr_assert(memcmp(n1, m1, sizeof n1) == 0 && memcmp(n2, m2, sizeof n2) == 0,
              "%s: not deterministic", what);
}

Test(spatial, normals_form_a_right_handed_orthonormal_basis)
{
    char what[64];
    for (int i = 0; i < 6; i++) { /* the coordinate axes, both signs */
        double a[3] = {0, 0, 0};
        a[i % 3] = i < 3 ? 1 : -1;
        snprintf(what, sizeof what, "axis %s%c", i < 3 ? "+" : "-", "xyz"[i % 3]);
        check_normals(a, what);
    }
    const double r3 = 1 / sqrt(3.0), r2 = 1 / sqrt(2.0);
    const double special[][3] = {
        {r3, r3, r3}, {-r3, r3, -r3}, {r2, r2, 0}, {0, -r2, r2}, {1, 1e-12, -1e-12}};
    for (int i = 0; i < 5; i++) {
        double a[3];
        ctc_v3_scale(a, special[i], 1 / ctc_v3_norm(special[i]));
        snprintf(what, sizeof what, "special axis %d", i);
        check_normals(a, what);
    }
    uint64_t rng = 21;
    for (int t = 0; t < 1000; t++) {
        double a[3];
        test_random_unit(&rng, a);
        snprintf(what, sizeof what, "random axis %d", t);
        check_normals(a, what);
    }
}

/* The rigid shift of a twist to a point r further on is v + w x r, and that of a load back from
 * r adds r x the force to its moment: the two are adjoint (T(r)^T), so the power a load does on a
 * twist is the same at either point. The planar form is the spatial one restricted to the plane
 * (w along z; v and the force in x-y). */
Test(spatial, transfer_of_motion_and_force_are_adjoint_rigid_shifts)
{
    uint64_t rng = 12345;
    for (int trial = 0; trial < 100; trial++) {
        double r[3], a[6], f[6], ta[6], tf[6], wxr[3];
        for (int i = 0; i < 3; i++) r[i] = test_uniform(&rng, -2, 2);
        for (int i = 0; i < 6; i++) a[i] = test_uniform(&rng, -3, 3);
        for (int i = 0; i < 6; i++) f[i] = test_uniform(&rng, -3, 3);
        ctc_transfer_motion(6, r, a, ta);
        ctc_transfer_force(6, r, f, tf);
        ctc_v3_cross(wxr, a, r);
        for (int i = 0; i < 3; i++) {
            cr_assert_eq(ta[i], a[i]);
            cr_assert_float_eq(ta[3 + i], a[3 + i] + wxr[i], 1e-14);
        }
        double p_far = 0, p_near = 0;
        for (int i = 0; i < 6; i++) p_far += f[i] * ta[i], p_near += tf[i] * a[i];
        cr_assert_float_eq(p_far, p_near, 1e-12, "power at r %g, moved back %g", p_far, p_near);

        /* planar: (w_z, v_x, v_y) and (tau_z, f_x, f_y), r in the plane */
        double r2[3] = {r[0], r[1], 0}, a3[3] = {a[2], a[3], a[4]}, f3[3] = {f[2], f[3], f[4]};
        double a6[6] = {0, 0, a[2], a[3], a[4], 0}, f6[6] = {0, 0, f[2], f[3], f[4], 0};
        double p3[3], q3[3], p6[6], q6[6];
        ctc_transfer_motion(3, r2, a3, p3);
        ctc_transfer_force(3, r2, f3, q3);
        ctc_transfer_motion(6, r2, a6, p6);
        ctc_transfer_force(6, r2, f6, q6);
        const int at[3] = {2, 3, 4};
        for (int i = 0; i < 3; i++) {
            cr_assert_float_eq(p3[i], p6[at[i]], 1e-14, "planar motion %d", i);
            cr_assert_float_eq(q3[i], q6[at[i]], 1e-14, "planar force %d", i);
        }
    }
}
