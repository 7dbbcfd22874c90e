/*
 * frames.h - 3x3 rotations written out for the tests' own forward kinematics (oracles apart
 * from the library's spatial.h and kinematics.c): Rodrigues' rotation about an axis, the
 * quaternion's rotation matrix, products, and the poses of a chain of two revolute joints.
 *
 * Matrices are 3x3 row-major (9 doubles), vectors 3 doubles, angles in radians, lengths in
 * metres. The caller owns every array; nothing here allocates. Each result may alias an input.
 */
#ifndef CTC_TEST_FRAMES_H
#define CTC_TEST_FRAMES_H

/* r = a b (3x3 by 3x3) */
void test_m3_mul(double r[9], const double a[9], const double b[9]);

/* r = m a (3x3 by 3) */
void test_m3_mulv(double r[3], const double m[9], const double a[3]);

/* r = the rotation by theta about the unit axis a (Rodrigues):
 * R = cos(theta) 1 + sin(theta) [a]x + (1 - cos(theta)) a a^T */
void test_m3_rot(double r[9], const double a[3], double theta);

/* r = the rotation matrix of the quaternion q = (w, x, y, z) as given, not normalised first:
 * (w^2 + x^2 - y^2 - z^2, 2 (x y - w z), ...), which is |q|^2 times a rotation, so that comparing
 * it with a rotation also checks that q has unit length */
void test_m3_quat_raw(double r[9], const double q[4]);

/* A chain of two revolute joints: joint 0 at loc[0] in the world about axis[0] (unit), joint 1 at
 * loc[1] in body 0's frame about axis[1] (unit, body 0's frame); both frames are the world's at
 * q = 0. */
typedef struct test_chain2 {
    double axis[2][3], loc[2][3];
} test_chain2;

/* Body k's (0 or 1) frame at q (2 angles): its origin p (world, m) and rotation rot,
 * R_0 = R(a0, q0), R_1 = R_0 R(a1, q1), p_0 = loc0, p_1 = loc0 + R_0 loc1. */
void test_chain2_pose(const test_chain2 *c, const double q[2], int k, double p[3], double rot[9]);

#endif
