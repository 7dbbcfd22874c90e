/*
 * spatial.h - 3-vector geometry for the planar and spatial forms: vectors, rotations, quaternions.
 *
 * Small fixed-size kernels written out by component, static inline so they cost nothing in the
 * hot loops. 3x3 matrices are row-major double[9]. Rotation matrices map body coordinates to
 * world (or parent) coordinates: x_world = R x_body. Quaternions are (w, x, y, z), w the scalar.
 * The only non-inline functions (spatial.c) are used outside the hot loops: eigenvalues of a
 * symmetric 3x3 matrix and a pair of unit vectors normal to an axis.
 */
#ifndef CTC_SPATIAL_H
#define CTC_SPATIAL_H

#include <math.h>

#define CTC_PI 3.14159265358979323846

static inline void ctc_v3_set(double r[3], double x, double y, double z)
{
    r[0] = x;
    r[1] = y;
    r[2] = z;
}

static inline void ctc_v3_copy(double r[3], const double a[3])
{
    r[0] = a[0];
    r[1] = a[1];
    r[2] = a[2];
}

static inline void ctc_v3_add(double r[3], const double a[3], const double b[3])
{
    r[0] = a[0] + b[0];
    r[1] = a[1] + b[1];
    r[2] = a[2] + b[2];
}

static inline void ctc_v3_sub(double r[3], const double a[3], const double b[3])
{
    r[0] = a[0] - b[0];
    r[1] = a[1] - b[1];
    r[2] = a[2] - b[2];
}

/* r = a + s b */
static inline void ctc_v3_addscl(double r[3], const double a[3], const double b[3], double s)
{
    r[0] = a[0] + s * b[0];
    r[1] = a[1] + s * b[1];
    r[2] = a[2] + s * b[2];
}

static inline void ctc_v3_scale(double r[3], const double a[3], double s)
{
    r[0] = s * a[0];
    r[1] = s * a[1];
    r[2] = s * a[2];
}

static inline double ctc_v3_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static inline double ctc_v3_norm(const double a[3])
{
    return sqrt(ctc_v3_dot(a, a));
}

/* r = a x b; r may not alias a or b */
static inline void ctc_v3_cross(double r[3], const double a[3], const double b[3])
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

/* r = M a (M row-major 3x3); r may not alias a */
static inline void ctc_m3_mulv(double r[3], const double m[9], const double a[3])
{
    r[0] = m[0] * a[0] + m[1] * a[1] + m[2] * a[2];
    r[1] = m[3] * a[0] + m[4] * a[1] + m[5] * a[2];
    r[2] = m[6] * a[0] + m[7] * a[1] + m[8] * a[2];
}

/* r = M^T a; r may not alias a */
static inline void ctc_m3_tmulv(double r[3], const double m[9], const double a[3])
{
    r[0] = m[0] * a[0] + m[3] * a[1] + m[6] * a[2];
    r[1] = m[1] * a[0] + m[4] * a[1] + m[7] * a[2];
    r[2] = m[2] * a[0] + m[5] * a[1] + m[8] * a[2];
}

/* r = A B; r may not alias A or B */
static inline void ctc_m3_mul(double r[9], const double a[9], const double b[9])
{
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            r[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
        }
    }
}

/* r = R S R^T for S symmetric (a tensor rotated into the frame R maps to); r symmetric */
static inline void ctc_m3_rotate_sym(double r[9], const double rot[9], const double s[9])
{
    double t[9]; /* t = R S */
    ctc_m3_mul(t, rot, s);
    for (int i = 0; i < 3; i++) {
        for (int j = i; j < 3; j++) {
            double x = t[3 * i] * rot[3 * j] + t[3 * i + 1] * rot[3 * j + 1] +
                       t[3 * i + 2] * rot[3 * j + 2];
            r[3 * i + j] = x;
            r[3 * j + i] = x;
        }
    }
}

static inline void ctc_m3_identity(double r[9])
{
    r[0] = 1, r[1] = 0, r[2] = 0;
    r[3] = 0, r[4] = 1, r[5] = 0;
    r[6] = 0, r[7] = 0, r[8] = 1;
}

/* Rotation by angle theta (rad) about the unit axis a (Rodrigues' formula). */
static inline void ctc_m3_axis_angle(double r[9], const double a[3], double theta)
{
    double c = cos(theta), s = sin(theta), t = 1.0 - c;
    r[0] = t * a[0] * a[0] + c;
    r[1] = t * a[0] * a[1] - s * a[2];
    r[2] = t * a[0] * a[2] + s * a[1];
    r[3] = t * a[0] * a[1] + s * a[2];
    r[4] = t * a[1] * a[1] + c;
    r[5] = t * a[1] * a[2] - s * a[0];
    r[6] = t * a[0] * a[2] - s * a[1];
    r[7] = t * a[1] * a[2] + s * a[0];
    r[8] = t * a[2] * a[2] + c;
}

/* Rotation matrix of the quaternion (w, x, y, z), normalised first (a zero quaternion gives
 * the identity). */
static inline void ctc_m3_from_quat(double r[9], const double quat[4])
{
    double n2 = quat[0] * quat[0] + quat[1] * quat[1] + quat[2] * quat[2] + quat[3] * quat[3];
    if (!(n2 > 0)) {
        ctc_m3_identity(r);
        return;
    }
    double s = 2.0 / n2;
    double w = quat[0], x = quat[1], y = quat[2], z = quat[3];
    r[0] = 1 - s * (y * y + z * z);
    r[1] = s * (x * y - w * z);
    r[2] = s * (x * z + w * y);
    r[3] = s * (x * y + w * z);
    r[4] = 1 - s * (x * x + z * z);
    r[5] = s * (y * z - w * x);
    r[6] = s * (x * z - w * y);
    r[7] = s * (y * z + w * x);
    r[8] = 1 - s * (x * x + y * y);
}

/* out = T(r) a, in either form (dim 3: planar (w, v_x, v_y); 6: spatial (w; v)): the acceleration
   (or velocity) a of a rigid body at a point, moved to the point r further on (v + w x r, DESIGN.md
   section 3); out may not alias a */
static inline void ctc_transfer_motion(int dim, const double r[3], const double *a, double *out)
{
    if (dim == 3) {
        out[0] = a[0];
        out[1] = a[1] - r[1] * a[0];
        out[2] = a[2] + r[0] * a[0];
    } else {
        double t[3];
        ctc_v3_cross(t, a, r);
        ctc_v3_copy(out, a);
        ctc_v3_add(out + 3, a + 3, t);
    }
}

/* out = T(r)^T f: a load f at the point r further on, as a load at this point (its moment
   gains r x the force); out may not alias f */
static inline void ctc_transfer_force(int dim, const double r[3], const double *f, double *out)
{
    if (dim == 3) {
        out[0] = f[0] - r[1] * f[1] + r[0] * f[2];
        out[1] = f[1];
        out[2] = f[2];
    } else {
        double t[3];
        ctc_v3_cross(t, r, f + 3);
        ctc_v3_add(out, f, t);
        ctc_v3_copy(out + 3, f + 3);
    }
}

/* Eigenvalues of the symmetric 3x3 matrix s, ascending (cyclic Jacobi; accurate to rounding). */
void ctc_sym3_eigenvalues(const double s[9], double eig[3]);

/* Two unit vectors n1, n2 such that (a, n1, n2) is a right-handed orthonormal basis; a must be a
 * unit vector. Deterministic in a. */
void ctc_v3_normals(const double a[3], double n1[3], double n2[3]);

#endif
