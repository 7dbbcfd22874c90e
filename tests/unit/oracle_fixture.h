/*
 * oracle_fixture.h - chains, states and independent reference computations for the oracle's tests
 * (test_rnea.c, test_aba.c, test_crba.c).
 *
 * Everything here is written apart from the oracle's code so that the tests can check it: a
 * deterministic random generator; random spatial chains (all five joint types, random axes and
 * locations, masses 0.1-10 kg, full-rank inertias R diag(p) R^T whose principal moments satisfy
 * the triangle inequality) and planar chains of slender rods, both built with ctc_model_build;
 * closed forms (rod pendulum, Lagrangian double pendulum, and from two of them a Y-shaped tree of
 * rods, the one branched tree here); merging two rigidly joined bodies; and
 * world-frame kinematics with 3x3 rotations (no spatial vectors) that give the kinetic and
 * potential energies, from which the mass matrix (by polarisation of the kinetic energy) and the
 * full inverse dynamics (by Lagrange's equations, central differences) follow.
 *
 * Spherical joints in Lagrange's equations: around the quaternion q0 the test uses local
 * coordinates x in R^3 with quat = q0 (x) Exp(x); the body-frame relative angular velocity is
 * then w = Jr(x) xdot with the right Jacobian Jr(x) = 1 - (1 - cos p)/p^2 [x]x
 * + (p - sin p)/p^3 [x]x^2, p = |x|. At x = 0, Jr = 1 and d(Jr)/dt xdot = -1/2 xdot x xdot = 0, so
 * the Lagrangian forces and accelerations in x equal the model's torques and wdot there.
 * The builders that pair a model with its oracle workspace (fx_make_random,
 * fx_make_fixed_merged, freed by fx_release) and the fixed-versus-merged check that test_rnea.c and
 * test_aba.c share (fx_check_fixed_equals_merged) close the file.
 * All helpers are static inline so that each test file uses what it needs.
 */
#ifndef CTC_ORACLE_FIXTURE_H
#define CTC_ORACLE_FIXTURE_H

#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "model.h"
#include "model_fixture.h"
#include "oracle.h"

#define FX_MAX_BODIES 64
#define FX_MAX_NV (3 * FX_MAX_BODIES)
#define FX_MAX_NQ (4 * FX_MAX_BODIES)
#define FX_G 9.81
#define FX_PI 3.14159265358979323846

/* a chain spec with its own storage */
typedef struct fx_chain {
    int n;
    ctc_body_spec bodies[FX_MAX_BODIES];
    ctc_joint_spec joints[FX_MAX_BODIES];
    double gravity[3];
} fx_chain;

/* ---- random numbers (splitmix64) ---- */

typedef struct fx_rng {
    uint64_t state;
} fx_rng;

static inline double fx_uniform(fx_rng *r, double lo, double hi)
{
    uint64_t z = (r->state += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    z ^= z >> 31;
    return lo + (hi - lo) * ((double)(z >> 11) * 0x1.0p-53);
}

static inline int fx_int(fx_rng *r, int n)
{
    int k = (int)fx_uniform(r, 0.0, (double)n);
    return k < n ? k : n - 1;
}

/* ---- small 3-D helpers (world frame, row-major 3x3) ---- */

static inline void fx_cross(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static inline double fx_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

/* c = A b */
static inline void fx_mv(const double a[9], const double b[3], double c[3])
{
    for (int i = 0; i < 3; i++) {
        c[i] = a[3 * i] * b[0] + a[3 * i + 1] * b[1] + a[3 * i + 2] * b[2];
    }
}

/* c = A^T b */
static inline void fx_mtv(const double a[9], const double b[3], double c[3])
{
    for (int i = 0; i < 3; i++) {
        c[i] = a[i] * b[0] + a[3 + i] * b[1] + a[6 + i] * b[2];
    }
}

/* C = A B */
static inline void fx_mm(const double a[9], const double b[9], double c[9])
{
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            c[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
        }
    }
}

/* rotation matrix of a unit quaternion (w, x, y, z), normalised first */
static inline void fx_quat_rot(const double q[4], double r[9])
{
    double s = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    double w = q[0] / s, x = q[1] / s, y = q[2] / s, z = q[3] / s;
    double m[9] = {
        w * w + x * x - y * y - z * z, 2 * (x * y - w * z),           2 * (x * z + w * y),
        2 * (x * y + w * z),           w * w - x * x + y * y - z * z, 2 * (y * z - w * x),
        2 * (x * z - w * y),           2 * (y * z + w * x),           w * w - x * x - y * y + z * z,
    };
    memcpy(r, m, sizeof(m));
}

/* rotation by angle about the unit axis a, as the quaternion (cos(t/2), sin(t/2) a) */
static inline void fx_axis_rot(const double a[3], double angle, double r[9])
{
    double s = sin(0.5 * angle);
    double q[4] = {cos(0.5 * angle), s * a[0], s * a[1], s * a[2]};
    fx_quat_rot(q, r);
}

/* c = a (x) b, Hamilton product */
static inline void fx_quat_mul(const double a[4], const double b[4], double c[4])
{
    c[0] = a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3];
    c[1] = a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2];
    c[2] = a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1];
    c[3] = a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0];
}

static inline void fx_random_unit(fx_rng *r, double a[3])
{
    double s;
    do {
        for (int i = 0; i < 3; i++) {
            a[i] = fx_uniform(r, -1.0, 1.0);
        }
        s = sqrt(fx_dot(a, a));
    } while (s < 0.1 || s > 1.0);
    for (int i = 0; i < 3; i++) {
        a[i] /= s;
    }
}

static inline void fx_random_quat(fx_rng *r, double q[4])
{
    double s;
    do {
        for (int i = 0; i < 4; i++) {
            q[i] = fx_uniform(r, -1.0, 1.0);
        }
        s = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    } while (s < 0.1 || s > 1.0);
    for (int i = 0; i < 4; i++) {
        q[i] /= s;
    }
}

/* ---- bodies and chains ---- */

/* a random body: mass log-uniform in [0.1, 10] kg, com within 0.3 m of the origin, inertia
 * R diag(p) R^T with p_i = s_j + s_k (so p obeys the triangle inequality), s_i = m l_i^2 */
static inline void fx_random_body(fx_rng *r, ctc_body_spec *b)
{
    double s[3], p[3], quat[4], rot[9];

    b->mass = exp(fx_uniform(r, log(0.1), log(10.0)));
    for (int i = 0; i < 3; i++) {
        double len = fx_uniform(r, 0.05, 0.3);
        b->com[i] = fx_uniform(r, -0.3, 0.3);
        s[i] = b->mass * len * len;
    }
    p[0] = s[1] + s[2];
    p[1] = s[0] + s[2];
    p[2] = s[0] + s[1];
    fx_random_quat(r, quat);
    fx_quat_rot(quat, rot);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j <= i; j++) {
            double sum = 0.0;
            for (int k = 0; k < 3; k++) {
                sum += rot[3 * i + k] * p[k] * rot[3 * j + k];
            }
            b->inertia[3 * i + j] = sum;
            b->inertia[3 * j + i] = sum;
        }
    }
}

/* a random chain of n bodies; for n >= 5 every joint type appears at least once, and at least
 * one joint moves */
static inline void fx_random_chain(fx_rng *r, int n, fx_chain *c)
{
    int moving = 0;

    cr_assert(n >= 1 && n <= FX_MAX_BODIES);
    c->n = n;
    c->gravity[0] = 0.0;
    c->gravity[1] = -FX_G;
    c->gravity[2] = 0.0;
    for (int k = 0; k < n; k++) {
        ctc_joint_spec *j = &c->joints[k];
        j->type = (ctc_joint_type)(n >= 5 && k < 5 ? k : fx_int(r, 5));
        fx_random_unit(r, j->axis);
        for (int i = 0; i < 3; i++) {
            j->location[i] = k == 0 ? fx_uniform(r, -0.2, 0.2) : fx_uniform(r, -0.5, 0.5);
        }
        fx_random_body(r, &c->bodies[k]);
    }

    /* shuffle the joint types (Fisher-Yates), then make sure something moves */
    for (int k = n - 1; k > 0; k--) {
        int i = fx_int(r, k + 1);
        ctc_joint_type t = c->joints[k].type;
        c->joints[k].type = c->joints[i].type;
        c->joints[i].type = t;
    }
    for (int k = 0; k < n; k++) {
        moving += c->joints[k].type != CTC_JOINT_FIXED;
    }
    if (moving == 0) {
        c->joints[0].type = CTC_JOINT_REVOLUTE;
    }
}

/* builds the model of chain c with the given form; the test fails with the builder's message */
static inline ctc_model *fx_build(const fx_chain *c, ctc_form form)
{
    char err[256] = "";
    ctc_model *m = NULL;
    ctc_chain_spec spec = {
        .nbodies = c->n,
        .bodies = c->bodies,
        .joints = c->joints,
        .gravity = {c->gravity[0], c->gravity[1], c->gravity[2]},
        .form = form,
    };
    ctc_status st = ctc_model_build(&spec, &m, err, sizeof(err));
    cr_assert_eq(st, CTC_OK, "ctc_model_build failed: %s", err);
    return m;
}

/* builds the model of chain c (into *m) and an oracle workspace for it */
static inline ctc_oracle *fx_make(const fx_chain *c, ctc_form form, ctc_model **m)
{
    *m = fx_build(c, form);
    ctc_oracle *o = ctc_oracle_new(*m);
    cr_assert_not_null(o, "ctc_oracle_new failed");
    return o;
}

/* a uniform slender rod of mass m and length l hanging along -y from its frame origin */
static inline ctc_body_spec fx_rod(double mass, double len)
{
    double i = mass * len * len / 12.0;
    ctc_body_spec b = {
        .mass = mass,
        .com = {0.0, -0.5 * len, 0.0},
        .inertia = {i, 0, 0, 0, 0, 0, 0, 0, i},
    };
    return b;
}

/* a planar chain of n rods on revolute +z joints, each hung from the tip of the previous one,
 * gravity (0, -g, 0) */
static inline void fx_rod_chain(int n, const double *mass, const double *len, fx_chain *c)
{
    memset(c, 0, sizeof(*c));
    c->n = n;
    c->gravity[1] = -FX_G;
    for (int k = 0; k < n; k++) {
        c->bodies[k] = fx_rod(mass[k], len[k]);
        c->joints[k].type = CTC_JOINT_REVOLUTE;
        c->joints[k].axis[2] = 1.0;
        c->joints[k].location[1] = k == 0 ? 0.0 : -len[k - 1];
    }
}

/* a random state: angles in [-pi, pi], displacements in [-0.5, 0.5] m, random unit quaternions,
 * velocities in [-2, 2], accelerations (or forces) in [-5, 5]; v and a may be NULL */
static inline void fx_random_state(fx_rng *r, const ctc_model *m, double *q, double *v, double *a)
{
    for (int k = 0; k < m->nbodies; k++) {
        double *qk = q + m->jnt_qadr[k];
        switch (m->joints[k].type) {
        case CTC_JOINT_REVOLUTE:
            qk[0] = fx_uniform(r, -FX_PI, FX_PI);
            break;
        case CTC_JOINT_PRISMATIC:
            qk[0] = fx_uniform(r, -0.5, 0.5);
            break;
        case CTC_JOINT_CYLINDRICAL:
            qk[0] = fx_uniform(r, -FX_PI, FX_PI);
            qk[1] = fx_uniform(r, -0.5, 0.5);
            break;
        case CTC_JOINT_SPHERICAL:
            fx_random_quat(r, qk);
            break;
        case CTC_JOINT_FIXED:
            break;
        }
    }
    for (int i = 0; i < m->nv; i++) {
        if (v != NULL) {
            v[i] = fx_uniform(r, -2.0, 2.0);
        }
        if (a != NULL) {
            a[i] = fx_uniform(r, -5.0, 5.0);
        }
    }
}

/* the body that child and parent make when the child is fixed (no rotation) at loc in the
 * parent's frame: one mass, one centre, parallel-axis inertias summed about the new centre */
static inline ctc_body_spec fx_merge_bodies(const ctc_body_spec *parent, const ctc_body_spec *child,
                                            const double loc[3])
{
    ctc_body_spec out;
    double mass = parent->mass + child->mass;
    double cc[3], d1[3], d2[3];

    for (int i = 0; i < 3; i++) {
        cc[i] = loc[i] + child->com[i];
        out.com[i] = (parent->mass * parent->com[i] + child->mass * cc[i]) / mass;
    }
    for (int i = 0; i < 3; i++) {
        d1[i] = parent->com[i] - out.com[i];
        d2[i] = cc[i] - out.com[i];
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            double eye = i == j ? 1.0 : 0.0;
            out.inertia[3 * i + j] = parent->inertia[3 * i + j] + child->inertia[3 * i + j] +
                                     parent->mass * (fx_dot(d1, d1) * eye - d1[i] * d1[j]) +
                                     child->mass * (fx_dot(d2, d2) * eye - d2[i] * d2[j]);
        }
    }
    out.mass = mass;
    return out;
}

/* a random chain of n moving joints (revolute, prismatic, cylindrical or spherical) in which
 * joint w is then made fixed, and the same chain with that joint removed: body w merged into its
 * parent (or, for w = 0, dropped, being part of the ground) and the next joint's location
 * carried over (the fixed joint does not rotate, so body w's frame is its parent's, shifted by
 * joint w's location). Both have the same coordinates. */
static inline void fx_fixed_and_merged(fx_rng *r, int n, int w, fx_chain *with_fixed,
                                       fx_chain *merged)
{
    cr_assert(n >= 2 && w >= 0 && w < n);
    fx_random_chain(r, n, with_fixed);
    for (int k = 0; k < n; k++) {
        with_fixed->joints[k].type = (ctc_joint_type)fx_int(r, 4);
    }
    with_fixed->joints[w].type = CTC_JOINT_FIXED;

    /* merged: drop index w */
    *merged = *with_fixed;
    const double *loc = with_fixed->joints[w].location;
    if (w > 0) {
        merged->bodies[w - 1] =
            fx_merge_bodies(&with_fixed->bodies[w - 1], &with_fixed->bodies[w], loc);
    }
    for (int k = w; k + 1 < n; k++) {
        merged->bodies[k] = with_fixed->bodies[k + 1];
        merged->joints[k] = with_fixed->joints[k + 1];
    }
    if (w + 1 < n) {
        for (int i = 0; i < 3; i++) {
            merged->joints[w].location[i] += loc[i];
        }
    }
    merged->n = n - 1;
}

/* ---- closed form: planar double pendulum of uniform rods (relative angles, 0 = hanging) ----
 * with lc_i = L_i / 2, I_i = m_i L_i^2 / 12 and h = -m2 L1 lc2 sin q2:
 *   M11 = m1 lc1^2 + I1 + m2 (L1^2 + lc2^2 + 2 L1 lc2 cos q2) + I2
 *   M12 = m2 (lc2^2 + L1 lc2 cos q2) + I2,    M22 = m2 lc2^2 + I2
 *   tau1 = M11 a1 + M12 a2 + h (2 v1 v2 + v2^2) + g ((m1 lc1 + m2 L1) sin q1 + m2 lc2 sin(q1+q2))
 *   tau2 = M12 a1 + M22 a2 - h v1^2 + g m2 lc2 sin(q1 + q2)
 * from T = 1/2 qdot^T M qdot and V = -g (m1 lc1 cos q1 + m2 (L1 cos q1 + lc2 cos(q1 + q2))). */
static inline void fx_double_pendulum(const double mass[2], const double len[2], const double q[2],
                                      const double v[2], const double a[2], double mm[4],
                                      double tau[2])
{
    double m1 = mass[0], m2 = mass[1], l1 = len[0];
    double lc1 = 0.5 * len[0], lc2 = 0.5 * len[1];
    double i1 = m1 * len[0] * len[0] / 12.0, i2 = m2 * len[1] * len[1] / 12.0;
    double h = -m2 * l1 * lc2 * sin(q[1]);

    mm[0] = m1 * lc1 * lc1 + i1 + m2 * (l1 * l1 + lc2 * lc2 + 2.0 * l1 * lc2 * cos(q[1])) + i2;
    mm[1] = m2 * (lc2 * lc2 + l1 * lc2 * cos(q[1])) + i2;
    mm[2] = mm[1];
    mm[3] = m2 * lc2 * lc2 + i2;
    tau[0] = mm[0] * a[0] + mm[1] * a[1] + h * (2.0 * v[0] * v[1] + v[1] * v[1]) +
             FX_G * ((m1 * lc1 + m2 * l1) * sin(q[0]) + m2 * lc2 * sin(q[0] + q[1]));
    tau[1] = mm[2] * a[0] + mm[3] * a[1] - h * v[0] * v[0] + FX_G * m2 * lc2 * sin(q[0] + q[1]);
}

/* A Y-shaped tree of three rods (not a chain): rod 0 on a revolute +z joint at the origin, rods 1
 * and 2 both hung from rod 0's tip on revolute +z joints, gravity (0, -g, 0). The chain spec of
 * fx_rod_chain with joint 2 moved to rod 0's tip (in rod 0's frame), built with the parents
 * FX_Y_PARENTS (fx_make_y_tree), or built as a chain and rewired (model_fixture.h
 * fixture_set_parents). */
#define FX_Y_PARENTS                                                                               \
    {                                                                                              \
        -1, 0, 0                                                                                   \
    }
static inline void fx_rod_y(const double mass[3], const double len[3], fx_chain *c)
{
    fx_rod_chain(3, mass, len, c);
    c->joints[2].location[1] = -len[0];
}

/* The Y tree's model, built with the parents FX_Y_PARENTS (ctc_chain_spec.parent), in *m and
 * its oracle (free both) */
static inline ctc_oracle *fx_make_y_tree(const double mass[3], const double len[3], ctc_model **m)
{
    static const int parent[3] = FX_Y_PARENTS;
    fx_chain c;
    char err[256] = "";
    fx_rod_y(mass, len, &c);
    ctc_chain_spec spec = {.nbodies = c.n,
                           .bodies = c.bodies,
                           .joints = c.joints,
                           .parent = parent,
                           .gravity = {c.gravity[0], c.gravity[1], c.gravity[2]}};
    ctc_status st = ctc_model_build(&spec, m, err, sizeof err);
    cr_assert_eq(st, CTC_OK, "ctc_model_build failed: %s", err);
    ctc_oracle *o = ctc_oracle_new(*m);
    cr_assert_not_null(o, "ctc_oracle_new failed");
    return o;
}

/* The Y tree's mass matrix mm (3x3, row-major) and inverse dynamics tau (3) in closed form. Its
 * dynamics are linear in the bodies' inertial parameters, so with rod 0 split into two halves of
 * half its mass (the same centre of mass, half the inertia) the tree is two double pendulums
 * that share joint 0: (rod 0 / 2, rod 1) on (q0, q1) and (rod 0 / 2, rod 2) on (q0, q2), whose
 * forces add on joint 0. Joints 1 and 2 lie on different branches: mm[1][2] = mm[2][1] = 0. */
static inline void fx_y_tree(const double mass[3], const double len[3], const double q[3],
                             const double v[3], const double a[3], double mm[9], double tau[3])
{
    const double ma[2] = {0.5 * mass[0], mass[1]}, la[2] = {len[0], len[1]};
    const double mb[2] = {0.5 * mass[0], mass[2]}, lb[2] = {len[0], len[2]};
    const double qa[2] = {q[0], q[1]}, va[2] = {v[0], v[1]}, aa[2] = {a[0], a[1]};
    const double qb[2] = {q[0], q[2]}, vb[2] = {v[0], v[2]}, ab[2] = {a[0], a[2]};
    double mma[4], mmb[4], ta[2], tb[2];
    fx_double_pendulum(ma, la, qa, va, aa, mma, ta);
    fx_double_pendulum(mb, lb, qb, vb, ab, mmb, tb);
    mm[0] = mma[0] + mmb[0], mm[1] = mma[1], mm[2] = mmb[1];
    mm[3] = mma[2], mm[4] = mma[3], mm[5] = 0.0;
    mm[6] = mmb[2], mm[7] = 0.0, mm[8] = mmb[3];
    tau[0] = ta[0] + tb[0], tau[1] = ta[1], tau[2] = tb[1];
}

/* ---- world-frame kinematics and energies (no spatial algebra) ---- */

/* per body: rotation R (body to world), origin p, angular velocity w and origin velocity pd, all
 * in world coordinates; v may be NULL (then w and pd are not written) */
static inline void fx_world_kinematics(const ctc_model *m, const double *q, const double *v,
                                       double *rot, double *pos, double *w, double *pd)
{
    double rp[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, pp[3] = {0, 0, 0};
    double wp[3] = {0, 0, 0}, pdp[3] = {0, 0, 0};

    for (int k = 0; k < m->nbodies; k++) {
        const ctc_joint_spec *j = &m->joints[k];
        const double *qk = q + m->jnt_qadr[k];
        const double *vk = v != NULL ? v + m->jnt_vadr[k] : NULL;
        double rj[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        double d[3] = {0, 0, 0}, wrel[3] = {0, 0, 0}, dd[3] = {0, 0, 0};
        double *rk = rot + 9 * k, *pk = pos + 3 * k;

        /* the joint: rotation, displacement and their rates, in the parent's frame */
        switch (j->type) {
        case CTC_JOINT_REVOLUTE:
            fx_axis_rot(j->axis, qk[0], rj);
            for (int i = 0; vk && i < 3; i++) {
                wrel[i] = j->axis[i] * vk[0];
            }
            break;
        case CTC_JOINT_PRISMATIC:
            for (int i = 0; i < 3; i++) {
                d[i] = j->axis[i] * qk[0];
                dd[i] = vk ? j->axis[i] * vk[0] : 0.0;
            }
            break;
        case CTC_JOINT_CYLINDRICAL:
            fx_axis_rot(j->axis, qk[0], rj);
            for (int i = 0; i < 3; i++) {
                d[i] = j->axis[i] * qk[1];
                wrel[i] = vk ? j->axis[i] * vk[0] : 0.0;
                dd[i] = vk ? j->axis[i] * vk[1] : 0.0;
            }
            break;
        case CTC_JOINT_SPHERICAL:
            fx_quat_rot(qk, rj);
            if (vk != NULL) {
                fx_mv(rj, vk, wrel);
            }
            break;
        case CTC_JOINT_FIXED:
            break;
        }

        /* compose with the parent: R = Rp Rj, p = pp + Rp (loc + d) */
        double arm_local[3], arm[3], wr[3], ddw[3], t[3];
        for (int i = 0; i < 3; i++) {
            arm_local[i] = j->location[i] + d[i];
        }
        fx_mm(rp, rj, rk);
        fx_mv(rp, arm_local, arm);
        for (int i = 0; i < 3; i++) {
            pk[i] = pp[i] + arm[i];
        }

        /* w = wp + Rp wrel, pd = pdp + wp x arm + Rp dd */
        if (v != NULL) {
            double *wk = w + 3 * k, *pdk = pd + 3 * k;
            fx_mv(rp, wrel, wr);
            fx_mv(rp, dd, ddw);
            fx_cross(wp, arm, t);
            for (int i = 0; i < 3; i++) {
                wk[i] = wp[i] + wr[i];
                pdk[i] = pdp[i] + t[i] + ddw[i];
            }
            memcpy(wp, wk, sizeof(wp));
            memcpy(pdp, pdk, sizeof(pdp));
        }
        memcpy(rp, rk, sizeof(rp));
        memcpy(pp, pk, sizeof(pp));
    }
}

/* kinetic energy sum_k 1/2 m |v_c|^2 + 1/2 w_b^T I w_b, w_b the angular velocity in body axes */
static inline double fx_kinetic_energy(const ctc_model *m, const double *q, const double *v)
{
    int n = m->nbodies;
    double *buf = malloc((size_t)n * 18 * sizeof(double));
    double *rot = buf, *pos = buf + 9 * n, *w = buf + 12 * n, *pd = buf + 15 * n;
    double energy = 0.0;

    cr_assert_not_null(buf);
    fx_world_kinematics(m, q, v, rot, pos, w, pd);
    for (int k = 0; k < n; k++) {
        const ctc_body_spec *b = &m->bodies[k];
        double cw[3], vc[3], wb[3], iw[3];
        fx_mv(rot + 9 * k, b->com, cw);
        fx_cross(w + 3 * k, cw, vc);
        for (int i = 0; i < 3; i++) {
            vc[i] += pd[3 * k + i];
        }
        fx_mtv(rot + 9 * k, w + 3 * k, wb);
        fx_mv(b->inertia, wb, iw);
        energy += 0.5 * b->mass * fx_dot(vc, vc) + 0.5 * fx_dot(wb, iw);
    }
    free(buf);
    return energy;
}

/* potential energy -sum_k m g . c_k (world centre of mass c_k) */
static inline double fx_potential_energy(const ctc_model *m, const double *q)
{
    int n = m->nbodies;
    double *buf = malloc((size_t)n * 12 * sizeof(double));
    double *rot = buf, *pos = buf + 9 * n;
    double energy = 0.0;

    cr_assert_not_null(buf);
    fx_world_kinematics(m, q, NULL, rot, pos, NULL, NULL);
    for (int k = 0; k < n; k++) {
        double cw[3];
        fx_mv(rot + 9 * k, m->bodies[k].com, cw);
        for (int i = 0; i < 3; i++) {
            cw[i] += pos[3 * k + i];
        }
        energy -= m->bodies[k].mass * fx_dot(m->gravity, cw);
    }
    free(buf);
    return energy;
}

/* ---- local coordinates x (nv) around q0 for Lagrange's equations ---- */

/* q = q0 "+" x: added for scalar coordinates, q0 (x) Exp(x) for spherical joints */
static inline void fx_retract(const ctc_model *m, const double *q0, const double *x, double *q)
{
    memcpy(q, q0, (size_t)m->nq * sizeof(double));
    for (int k = 0; k < m->nbodies; k++) {
        const double *xk = x + m->jnt_vadr[k];
        double *qk = q + m->jnt_qadr[k];
        if (m->joints[k].type != CTC_JOINT_SPHERICAL) {
            for (int i = 0; i < m->jnt_nv[k]; i++) {
                qk[i] += xk[i];
            }
            continue;
        }
        double phi = sqrt(fx_dot(xk, xk));
        double s = phi > 0.0 ? sin(0.5 * phi) / phi : 0.5;
        double e[4] = {cos(0.5 * phi), s * xk[0], s * xk[1], s * xk[2]};
        double base[4] = {qk[0], qk[1], qk[2], qk[3]};
        fx_quat_mul(base, e, qk);
    }
}

/* model velocities v from local rates xdot at x: v = xdot, or Jr(x) xdot for spherical joints */
static inline void fx_local_velocity(const ctc_model *m, const double *x, const double *xdot,
                                     double *v)
{
    for (int k = 0; k < m->nbodies; k++) {
        const double *xk = x + m->jnt_vadr[k], *dk = xdot + m->jnt_vadr[k];
        double *vk = v + m->jnt_vadr[k];
        if (m->joints[k].type != CTC_JOINT_SPHERICAL) {
            for (int i = 0; i < m->jnt_nv[k]; i++) {
                vk[i] = dk[i];
            }
            continue;
        }
        double p2 = fx_dot(xk, xk), p = sqrt(p2);
        double c1, c2; /* (1 - cos p)/p^2 and (p - sin p)/p^3, by series when p is small */
        if (p < 1e-2) {
            c1 = 0.5 - p2 / 24.0 + p2 * p2 / 720.0;
            c2 = 1.0 / 6.0 - p2 / 120.0 + p2 * p2 / 5040.0;
        } else {
            c1 = 2.0 * sin(0.5 * p) * sin(0.5 * p) / p2;
            c2 = (p - sin(p)) / (p2 * p);
        }
        double t1[3], t2[3];
        fx_cross(xk, dk, t1);
        fx_cross(xk, t1, t2);
        for (int i = 0; i < 3; i++) {
            vk[i] = dk[i] - c1 * t1[i] + c2 * t2[i];
        }
    }
}

/* kinetic energy as a function of local coordinates x and rates xdot around q0 */
static inline double fx_local_kinetic(const ctc_model *m, const double *q0, const double *x,
                                      const double *xdot)
{
    double q[FX_MAX_NQ], v[FX_MAX_NV];
    fx_retract(m, q0, x, q);
    fx_local_velocity(m, x, xdot, v);
    return fx_kinetic_energy(m, q, v);
}

/* generalised momentum p = dT/dxdot at (x, xdot); exact, since T is quadratic in xdot:
 * p_i = (T(xdot + e_i) - T(xdot - e_i)) / 2 */
static inline void fx_local_momentum(const ctc_model *m, const double *q0, const double *x,
                                     const double *xdot, double *p)
{
    double xd[FX_MAX_NV];
    memcpy(xd, xdot, (size_t)m->nv * sizeof(double));
    for (int i = 0; i < m->nv; i++) {
        xd[i] = xdot[i] + 1.0;
        double up = fx_local_kinetic(m, q0, x, xd);
        xd[i] = xdot[i] - 1.0;
        double down = fx_local_kinetic(m, q0, x, xd);
        xd[i] = xdot[i];
        p[i] = 0.5 * (up - down);
    }
}

/* the mass matrix at q from the kinetic energy alone, by polarisation:
 * M_ii = 2 T(e_i), M_ij = T(e_i + e_j) - T(e_i) - T(e_j); M is nv x nv row-major */
static inline void fx_energy_mass_matrix(const ctc_model *m, const double *q, double *mm)
{
    int nv = m->nv;
    double v[FX_MAX_NV] = {0};
    double diag[FX_MAX_NV];

    for (int i = 0; i < nv; i++) {
        v[i] = 1.0;
        diag[i] = fx_kinetic_energy(m, q, v);
        v[i] = 0.0;
        mm[(size_t)i * nv + i] = 2.0 * diag[i];
    }
    for (int i = 0; i < nv; i++) {
        for (int j = i + 1; j < nv; j++) {
            v[i] = v[j] = 1.0;
            double t = fx_kinetic_energy(m, q, v) - diag[i] - diag[j];
            v[i] = v[j] = 0.0;
            mm[(size_t)i * nv + j] = t;
            mm[(size_t)j * nv + i] = t;
        }
    }
}

/* inverse dynamics from Lagrange's equations in local coordinates x at x = 0:
 *     tau = d/dt (dT/dxdot) - dT/dx + dV/dx
 *         = M a + (dp/dx) xdot - dT/dx + dV/dx,
 * with M a and p exact by polarisation and the x-derivatives by central differences of step h */
static inline void fx_lagrange_inverse(const ctc_model *m, const double *q0, const double *v,
                                       const double *a, double h, double *tau)
{
    int nv = m->nv;
    double x[FX_MAX_NV] = {0}, zero[FX_MAX_NV] = {0};
    double ma[FX_MAX_NV], p_up[FX_MAX_NV], p_down[FX_MAX_NV], q[FX_MAX_NQ];

    /* M a: the momentum for rates a at x = 0 */
    fx_local_momentum(m, q0, zero, a, ma);

    /* (dp/dx) xdot: momentum at x = +-h v */
    for (int i = 0; i < nv; i++) {
        x[i] = h * v[i];
    }
    fx_local_momentum(m, q0, x, v, p_up);
    for (int i = 0; i < nv; i++) {
        x[i] = -h * v[i];
    }
    fx_local_momentum(m, q0, x, v, p_down);
    for (int i = 0; i < nv; i++) {
        x[i] = 0.0;
    }

    /* assemble, with dT/dx_i and dV/dx_i at x = +-h e_i */
    for (int i = 0; i < nv; i++) {
        x[i] = h;
        double t_up = fx_local_kinetic(m, q0, x, v);
        fx_retract(m, q0, x, q);
        double v_up = fx_potential_energy(m, q);
        x[i] = -h;
        double t_down = fx_local_kinetic(m, q0, x, v);
        fx_retract(m, q0, x, q);
        double v_down = fx_potential_energy(m, q);
        x[i] = 0.0;
        tau[i] = ma[i] + (p_up[i] - p_down[i]) / (2.0 * h) - (t_up - t_down) / (2.0 * h) +
                 (v_up - v_down) / (2.0 * h);
    }
}

/* ---- models with their oracle workspaces ---- */

/* builds the model of a random chain of n bodies (fx_random_chain, drawing from r) in the given
 * form (into *m) and an oracle workspace for it; free both with fx_release */
static inline ctc_oracle *fx_make_random(fx_rng *r, int n, ctc_form form, ctc_model **m)
{
    fx_chain c;
    fx_random_chain(r, n, &c);
    return fx_make(&c, form, m);
}

/* builds the model of the rod chain fx_rod_chain(n, mass, len) in form AUTO (planar: revolute z
 * joints) into *m and an oracle workspace for it; free both with fx_release */
static inline ctc_oracle *fx_make_rods(int n, const double *mass, const double *len, ctc_model **m)
{
    fx_chain c;
    fx_rod_chain(n, mass, len, &c);
    return fx_make(&c, CTC_FORM_AUTO, m);
}

/* Builds the spatial models and oracle workspaces of fx_fixed_and_merged(r, n, w): a random chain
 * with joint w fixed (*mf, *of) and the same chain with body w merged into its parent (*mm, *om).
 * Both have the same nq and nv (asserted), so one state serves both. Free each pair with
 * fx_release. */
static inline void fx_make_fixed_merged(fx_rng *r, int n, int w, ctc_model **mf, ctc_oracle **of,
                                        ctc_model **mm, ctc_oracle **om)
{
    fx_chain cf, cm;
    fx_fixed_and_merged(r, n, w, &cf, &cm);
    *of = fx_make(&cf, CTC_FORM_SPATIAL, mf);
    *om = fx_make(&cm, CTC_FORM_SPATIAL, mm);
    cr_assert_eq((*mf)->nq, (*mm)->nq, "fixed joint %d: nq", w);
    cr_assert_eq((*mf)->nv, (*mm)->nv, "fixed joint %d: nv", w);
}

/* frees what fx_make or fx_make_random gave: the oracle workspace o and the model m */
static inline void fx_release(ctc_model *m, ctc_oracle *o)
{
    ctc_oracle_free(o);
    ctc_model_free(m);
}

/* ---- dense helpers ---- */

static inline double fx_max_abs(int n, const double *x)
{
    double s = 0.0;
    for (int i = 0; i < n; i++) {
        s = fmax(s, fabs(x[i]));
    }
    return s;
}

static inline double fx_max_abs_diff(int n, const double *x, const double *y)
{
    double s = 0.0;
    for (int i = 0; i < n; i++) {
        s = fmax(s, fabs(x[i] - y[i]));
    }
    return s;
}

/* max |x_i - y_i| relative to the reference y: over max |y_i|, or over 1 when that is smaller */
static inline double fx_rel_diff(int n, const double *x, const double *y)
{
    return fx_max_abs_diff(n, x, y) / fmax(1.0, fx_max_abs(n, y));
}

/* in-place Cholesky of an n x n row-major symmetric A into its lower factor; returns 0 when a
 * pivot is not positive (A is not positive definite) */
static inline int fx_cholesky(int n, double *a)
{
    for (int j = 0; j < n; j++) {
        double d = a[(size_t)j * n + j];
        for (int k = 0; k < j; k++) {
            d -= a[(size_t)j * n + k] * a[(size_t)j * n + k];
        }
        if (!(d > 0.0)) {
            return 0;
        }
        a[(size_t)j * n + j] = sqrt(d);
        for (int i = j + 1; i < n; i++) {
            double s = a[(size_t)i * n + j];
            for (int k = 0; k < j; k++) {
                s -= a[(size_t)i * n + k] * a[(size_t)j * n + k];
            }
            a[(size_t)i * n + j] = s / a[(size_t)j * n + j];
        }
    }
    return 1;
}

/* x = A^{-1} b given the lower Cholesky factor of A (from fx_cholesky); x may alias b */
static inline void fx_cholesky_solve(int n, const double *l, const double *b, double *x)
{
    for (int i = 0; i < n; i++) {
        double s = b[i];
        for (int k = 0; k < i; k++) {
            s -= l[(size_t)i * n + k] * x[k];
        }
        x[i] = s / l[(size_t)i * n + i];
    }
    for (int i = n - 1; i >= 0; i--) {
        double s = x[i];
        for (int k = i + 1; k < n; k++) {
            s -= l[(size_t)k * n + i] * x[k];
        }
        x[i] = s / l[(size_t)i * n + i];
    }
}

/* an estimate (from below) of the 2-norm condition number of a symmetric positive definite
 * n x n matrix: 300 steps of power iteration for its largest eigenvalue and of inverse
 * iteration (Cholesky) for its smallest; returns 0 when A is not positive definite */
static inline double fx_condition_number(int n, const double *a)
{
    double *l = malloc((size_t)n * n * sizeof(double));
    double *x = malloc((size_t)n * sizeof(double)), *y = malloc((size_t)n * sizeof(double));
    double lmax = 0.0, lmin_inv = 0.0, cond = 0.0;

    cr_assert(l != NULL && x != NULL && y != NULL);
    memcpy(l, a, (size_t)n * n * sizeof(double));
    if (fx_cholesky(n, l)) {
        /* largest eigenvalue: y = A x, normalise */
        for (int i = 0; i < n; i++) {
            x[i] = 1.0 / (i + 1);
        }
        for (int it = 0; it < 300; it++) {
            double s = 0.0;
            for (int i = 0; i < n; i++) {
                y[i] = 0.0;
                for (int j = 0; j < n; j++) {
                    y[i] += a[(size_t)i * n + j] * x[j];
                }
                s += y[i] * y[i];
            }
            lmax = sqrt(s);
            for (int i = 0; i < n; i++) {
                x[i] = y[i] / lmax;
            }
        }
        /* smallest: y = A^{-1} x, normalise */
        for (int i = 0; i < n; i++) {
            x[i] = 1.0 / (i + 1);
        }
        for (int it = 0; it < 300; it++) {
            double s = 0.0;
            fx_cholesky_solve(n, l, x, y);
            for (int i = 0; i < n; i++) {
                s += y[i] * y[i];
            }
            lmin_inv = sqrt(s);
            for (int i = 0; i < n; i++) {
                x[i] = y[i] / lmin_inv;
            }
        }
        cond = lmax * lmin_inv;
    }
    free(l);
    free(x);
    free(y);
    return cond;
}

/* ---- checks shared by the oracle's tests ---- */

/* an oracle pass from (q, v, x) to y: ctc_oracle_rnea (x = vdot, y = tau) or ctc_oracle_aba
 * (x = tau, y = vdot) */
typedef void (*fx_pass)(const ctc_model *m, ctc_oracle *o, const double *q, const double *v,
                        const double *x, double *y);

/* For w = 0..4, the fixed joint at the base, inside and at the tip of a random 5-body chain
 * (fx_make_fixed_merged, drawing from r): pass on the chain with joint w fixed and on the chain
 * with body w merged, at one random state q, v, x (fx_random_state, drawing from r), must agree:
 * fx_rel_diff (relative to the merged chain's y) at most tol, asserted with w in the message.
 * Returns the worst relative difference. */
static inline double fx_check_fixed_equals_merged(fx_rng *r, fx_pass pass, double tol)
{
    double worst = 0.0;
    for (int w = 0; w < 5; w++) {
        ctc_model *mf, *mm;
        ctc_oracle *of, *om;
        fx_make_fixed_merged(r, 5, w, &mf, &of, &mm, &om);
        double q[FX_MAX_NQ], v[FX_MAX_NV], x[FX_MAX_NV], yf[FX_MAX_NV], ym[FX_MAX_NV];

        fx_random_state(r, mf, q, v, x);
        pass(mf, of, q, v, x, yf);
        pass(mm, om, q, v, x, ym);
        double err = fx_rel_diff(mf->nv, yf, ym);
        worst = fmax(worst, err);
        cr_assert_leq(err, tol, "fixed joint %d: relative difference %.3e", w, err);
        fx_release(mf, of);
        fx_release(mm, om);
    }
    return worst;
}

#endif
