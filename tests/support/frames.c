/*
 * frames.c - 3x3 rotations and the two-joint chain's forward kinematics for the tests (frames.h).
 *
 * Written out by component from the textbook formulas (Rodrigues' rotation, the quaternion's
 * rotation matrix, composition from the ground outward), apart from the library's spatial.h, so
 * that the tests that use them check the library by a second route.
 */
#include "frames.h"

#include <math.h>
#include <string.h>

void test_m3_mul(double r[9], const double a[9], const double b[9])
{
    double t[9];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            t[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
    memcpy(r, t, sizeof t);
}

void test_m3_mulv(double r[3], const double m[9], const double a[3])
{
    double x = m[0] * a[0] + m[1] * a[1] + m[2] * a[2];
    double y = m[3] * a[0] + m[4] * a[1] + m[5] * a[2];
    double z = m[6] * a[0] + m[7] * a[1] + m[8] * a[2];
    r[0] = x, r[1] = y, r[2] = z;
}

void test_m3_rot(double r[9], const double a[3], double theta)
{
    double c = cos(theta), s = sin(theta), t = 1 - c;
    r[0] = c + t * a[0] * a[0], r[1] = t * a[0] * a[1] - s * a[2],
    r[2] = t * a[0] * a[2] + s * a[1];
    r[3] = t * a[0] * a[1] + s * a[2], r[4] = c + t * a[1] * a[1],
    r[5] = t * a[1] * a[2] - s * a[0];
    r[6] = t * a[0] * a[2] - s * a[1], r[7] = t * a[1] * a[2] + s * a[0],
    r[8] = c + t * a[2] * a[2];
}

void test_m3_quat_raw(double r[9], const double q[4])
{
    double w = q[0], x = q[1], y = q[2], z = q[3];
    double t[9] = {
        w * w + x * x - y * y - z * z, 2 * (x * y - w * z),           2 * (x * z + w * y),
        2 * (x * y + w * z),           w * w - x * x + y * y - z * z, 2 * (y * z - w * x),
        2 * (x * z - w * y),           2 * (y * z + w * x),           w * w - x * x - y * y + z * z,
    };
    memcpy(r, t, sizeof t);
}

void test_chain2_pose(const test_chain2 *c, const double q[2], int k, double p[3], double rot[9])
{
    double r0[9], r1[9], t[3];
    test_m3_rot(r0, c->axis[0], q[0]);
    memcpy(p, c->loc[0], 3 * sizeof(double));
    memcpy(rot, r0, sizeof r0);
    if (k == 0) return;
    test_m3_rot(r1, c->axis[1], q[1]);
    test_m3_mul(rot, r0, r1);
    test_m3_mulv(t, r0, c->loc[1]);
    for (int i = 0; i < 3; i++) p[i] += t[i];
}
