/*
 * plucker.h - the oracle's own small Plücker (spatial vector) kernels, written out by component.
 *
 * These serve only the independent oracle (oracle.c, rnea.c, aba.c, crba.c); the GDCA code has its
 * own algebra in world coordinates, and the two are deliberately not shared so that one checks
 * the other. Conventions follow Featherstone, Rigid Body Dynamics Algorithms (2008), ch. 2:
 *  - a motion vector is m = (w, v): angular velocity w and the linear velocity v of the body-fixed
 *    point at the frame's origin, both in that frame's coordinates;
 *  - a force vector is f = (n, f): the moment n about the frame's origin and the force f;
 *  - a frame B whose origin sits at r and whose axes have the rotation E (x_B = E x_A) relative
 *    to frame A has the motion transform
 *        X = B_X_A = [ E       0 ]      so  w_B = E w_A,  v_B = E (v_A - r x w_A),
 *                    [ -E[r]x  E ]
 *    and forces go back with its transpose: f_A = X^T f_B (the dual transform of B_X_A^{-1});
 *  - 3x3 and 6x6 matrices are row-major; [r]x is the skew matrix with [r]x b = r x b.
 * Every kernel is pure (no state), so any thread may call it.
 */
#ifndef CTC_PLUCKER_H
#define CTC_PLUCKER_H

#include <math.h>
#include <string.h>

/* c = a x b (c may not alias a or b) */
static inline void plk_cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

/* c = A b for a 3x3 A */
static inline void plk_mat3_vec(const double a[9], const double b[3], double c[3])
{
    c[0] = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    c[1] = a[3] * b[0] + a[4] * b[1] + a[5] * b[2];
    c[2] = a[6] * b[0] + a[7] * b[1] + a[8] * b[2];
}

/* R = rotation by angle about the unit axis a (right hand):
 * R = 1 + sin(angle) [a]x + (1 - cos(angle)) [a]x^2, with [a]x^2 = a a^T - 1 */
static inline void plk_rot_axis_angle(const double a[3], double angle, double r[9])
{
    double s = sin(angle), c = cos(angle), t = 1.0 - c;

    r[0] = c + t * a[0] * a[0];
    r[1] = t * a[0] * a[1] - s * a[2];
    r[2] = t * a[0] * a[2] + s * a[1];
    r[3] = t * a[1] * a[0] + s * a[2];
    r[4] = c + t * a[1] * a[1];
    r[5] = t * a[1] * a[2] - s * a[0];
    r[6] = t * a[2] * a[0] - s * a[1];
    r[7] = t * a[2] * a[1] + s * a[0];
    r[8] = c + t * a[2] * a[2];
}

/* R = rotation of the quaternion (w, x, y, z), normalised here first; R maps the rotated frame's
 * coordinates into the reference frame's: x_ref = R x_rot */
static inline void plk_rot_quat(const double quat[4], double r[9])
{
    double nrm =
        sqrt(quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3]);
    double w = quat[0] / nrm, x = quat[1] / nrm, y = quat[2] / nrm, z = quat[3] / nrm;

    r[0] = 1.0 - 2.0 * (y * y + z * z);
    r[1] = 2.0 * (x * y - w * z);
    r[2] = 2.0 * (x * z + w * y);
    r[3] = 2.0 * (x * y + w * z);
    r[4] = 1.0 - 2.0 * (x * x + z * z);
    r[5] = 2.0 * (y * z - w * x);
    r[6] = 2.0 * (x * z - w * y);
    r[7] = 2.0 * (y * z + w * x);
    r[8] = 1.0 - 2.0 * (x * x + y * y);
}

/* X = [E 0; -E[r]x E]: the 6x6 motion transform into a frame at r with rotation E */
static inline void plk_motion_xform(const double e[9], const double r[3], double x[36])
{
    memset(x, 0, 36 * sizeof(double));
    for (int i = 0; i < 3; i++) {
        const double *ei = e + 3 * i;

        /* row i of -E[r]x: -(E_i0, E_i1, E_i2) [r]x = r x (E_i0, E_i1, E_i2) */
        double erx[3] = {
            r[1] * ei[2] - r[2] * ei[1],
            r[2] * ei[0] - r[0] * ei[2],
            r[0] * ei[1] - r[1] * ei[0],
        };
        for (int j = 0; j < 3; j++) {
            x[6 * i + j] = ei[j];
            x[6 * (i + 3) + j + 3] = ei[j];
            x[6 * (i + 3) + j] = erx[j];
        }
    }
}

/* out = A b for a 6x6 A (out may not alias b) */
static inline void plk_mat6_vec(const double a[36], const double b[6], double out[6])
{
    for (int i = 0; i < 6; i++) {
        const double *ai = a + 6 * i;
        out[i] =
            ai[0] * b[0] + ai[1] * b[1] + ai[2] * b[2] + ai[3] * b[3] + ai[4] * b[4] + ai[5] * b[5];
    }
}

/* out = A^T b for a 6x6 A (out may not alias b) */
static inline void plk_mat6t_vec(const double a[36], const double b[6], double out[6])
{
    for (int j = 0; j < 6; j++) {
        out[j] = 0.0;
    }
    for (int i = 0; i < 6; i++) {
        const double *ai = a + 6 * i;
        for (int j = 0; j < 6; j++) {
            out[j] += ai[j] * b[i];
        }
    }
}

/* acc += X^T I X: a body inertia I (6x6) in frame B seen from frame A, with X = B_X_A */
static inline void plk_congruence_add(const double x[36], const double inertia[36], double acc[36])
{
    double ix[36]; /* I X */

    for (int i = 0; i < 6; i++) {
        for (int j = 0; j < 6; j++) {
            double s = 0.0;
            for (int k = 0; k < 6; k++) {
                s += inertia[6 * i + k] * x[6 * k + j];
            }
            ix[6 * i + j] = s;
        }
    }
    for (int i = 0; i < 6; i++) {
        for (int j = 0; j < 6; j++) {
            double s = 0.0;
            for (int k = 0; k < 6; k++) {
                s += x[6 * k + i] * ix[6 * k + j];
            }
            acc[6 * i + j] += s;
        }
    }
}

/* out = v x m (motion cross product, crm): (w x mw, w x mv + vo x mw) for v = (w, vo) */
static inline void plk_cross_motion(const double v[6], const double m[6], double out[6])
{
    double t[3];

    plk_cross3(v, m, out);
    plk_cross3(v, m + 3, out + 3);
    plk_cross3(v + 3, m, t);
    out[3] += t[0];
    out[4] += t[1];
    out[5] += t[2];
}

/* out = v x* f (force cross product, crf): (w x n + vo x f, w x f) for v = (w, vo) */
static inline void plk_cross_force(const double v[6], const double f[6], double out[6])
{
    double t[3];

    plk_cross3(v, f, out);
    plk_cross3(v + 3, f + 3, t);
    out[0] += t[0];
    out[1] += t[1];
    out[2] += t[2];
    plk_cross3(v, f + 3, out + 3);
}

/* the spatial inertia about the frame origin of a body with mass m, centre of mass c and
 * inertia Ic about c (frame axes):
 *     I = [ Ic + m [c]x [c]x^T   m [c]x ]
 *         [ m [c]x^T             m 1    ]
 * it is never inverted (a slender rod's Ic is singular) */
static inline void plk_body_inertia(double mass, const double c[3], const double ic[9],
                                    double out[36])
{
    /* [c]x row-major */
    double cx[9] = {0.0, -c[2], c[1], c[2], 0.0, -c[0], -c[1], c[0], 0.0};

    memset(out, 0, 36 * sizeof(double));
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            /* ([c]x [c]x^T)_ij = sum_k cx_ik cx_jk */
            double cc = cx[3 * i] * cx[3 * j] + cx[3 * i + 1] * cx[3 * j + 1] +
                        cx[3 * i + 2] * cx[3 * j + 2];
            out[6 * i + j] = ic[3 * i + j] + mass * cc;
            out[6 * i + j + 3] = mass * cx[3 * i + j];
            out[6 * (i + 3) + j] = mass * cx[3 * j + i];
        }
        out[6 * (i + 3) + i + 3] = mass;
    }
}

/* Cholesky factor L (lower, n x n, row-major, n <= 3) of a symmetric positive definite A:
 * A = L L^T. A non-positive pivot leaves NaN in L, which then shows in every result. */
static inline void plk_chol_factor(int n, const double *a, double *l)
{
    for (int i = 0; i < n * n; i++) {
        l[i] = 0.0;
    }
    for (int j = 0; j < n; j++) {
        double d = a[n * j + j];
        for (int k = 0; k < j; k++) {
            d -= l[n * j + k] * l[n * j + k];
        }
        l[n * j + j] = sqrt(d);
        for (int i = j + 1; i < n; i++) {
            double s = a[n * i + j];
            for (int k = 0; k < j; k++) {
                s -= l[n * i + k] * l[n * j + k];
            }
            l[n * i + j] = s / l[n * j + j];
        }
    }
}

/* x = A^{-1} b with the Cholesky factor l of A (n <= 3; x may alias b) */
static inline void plk_chol_solve(int n, const double *l, const double *b, double *x)
{
    double y[3];

    /* forward: L y = b */
    for (int i = 0; i < n; i++) {
        double s = b[i];
        for (int k = 0; k < i; k++) {
            s -= l[n * i + k] * y[k];
        }
        y[i] = s / l[n * i + i];
    }
    /* backward: L^T x = y */
    for (int i = n - 1; i >= 0; i--) {
        double s = y[i];
        for (int k = i + 1; k < n; k++) {
            s -= l[n * k + i] * x[k];
        }
        x[i] = s / l[n * i + i];
    }
}

#endif
