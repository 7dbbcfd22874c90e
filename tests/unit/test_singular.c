/*
 * test_singular.c - singular bodies (model.h "singular bodies"): point masses, massless bodies and
 * bodies with inertia about one axis only, accepted wherever the joint-space mass matrix is
 * positive definite and refused, naming the body, where it is not.
 *
 * Oracles: the closed-form M(q), Coriolis and gravity terms of the two-link planar arm with point
 * masses at the link ends (Spong, Hutchinson and Vidyasagar, Robot Modeling and Control, 2006,
 * sec. 7.4.2 with I1 = I2 = 0 and lc_i = l_i), written out here; the articulated-body,
 * Newton-Euler and composite-rigid-body algorithms of oracle.h, which invert no body's inertia;
 * and a model with the massless frame merged by hand (parallel-axis theorem). Errors are
 * max |difference| / max |reference|. Bounds are the largest value measured here (gcc, -O3)
 * times 100 or more, the measured value beside them.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "ctc.h"
#include "linalg.h"
#include "loop_oracle.h"
#include "model_fixture.h"
#include "oracle.h"
#include "spatial.h"

#define MAXV 8

static const double L1 = 0.8, L2 = 0.6, M1 = 2.0, M2 = 1.5, G = 9.81;

/* the two-link arm: joint 0 at the origin, both axes +z, body k a point mass m_k at (l_k, 0, 0)
   of its frame, joint 1 at body 0's mass; q_i measured from the x axis, gravity -y */
static void arm_spec(ctc_body_spec b[2], ctc_joint_spec j[2], ctc_chain_spec *spec, double m2,
                     double l2, ctc_form form)
{
    memset(b, 0, 2 * sizeof *b);
    memset(j, 0, 2 * sizeof *j);
    memset(spec, 0, sizeof *spec);
    b[0].mass = M1, b[0].com[0] = L1;
    b[1].mass = m2, b[1].com[0] = l2;
    for (int k = 0; k < 2; k++) j[k].type = CTC_JOINT_REVOLUTE, j[k].axis[2] = 1;
    j[1].location[0] = L1;
    spec->nbodies = 2, spec->bodies = b, spec->joints = j, spec->form = form;
    spec->gravity[1] = -G;
}

/* Spong's closed form: tau = M(q) a + C(q, v) v + g(q) */
static void arm_closed_form(const double q[2], const double v[2], const double a[2], double mm[4],
                            double tau[2])
{
    double c2 = cos(q[1]), s2 = sin(q[1]), c1 = cos(q[0]), c12 = cos(q[0] + q[1]);
    double h = -M2 * L1 * L2 * s2;
    mm[0] = M1 * L1 * L1 + M2 * (L1 * L1 + L2 * L2 + 2 * L1 * L2 * c2);
    mm[1] = mm[2] = M2 * (L2 * L2 + L1 * L2 * c2);
    mm[3] = M2 * L2 * L2;
    double g1 = (M1 + M2) * G * L1 * c1 + M2 * G * L2 * c12, g2 = M2 * G * L2 * c12;
    tau[0] = mm[0] * a[0] + mm[1] * a[1] + h * (2 * v[0] * v[1] + v[1] * v[1]) + g1;
    tau[1] = mm[2] * a[0] + mm[3] * a[1] - h * v[0] * v[0] + g2;
}

static double max_abs(const double *x, int n)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(x[i]));
    return s;
}

static double rel_diff(const double *x, const double *ref, int n)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(x[i] - ref[i]));
    return s / max_abs(ref, n);
}

Test(singular, point_mass_arm_matches_the_closed_form_in_both_forms)
{
    for (int form = CTC_FORM_AUTO; form <= CTC_FORM_SPATIAL; form += 2) {
        ctc_body_spec b[2];
        ctc_joint_spec j[2];
        ctc_chain_spec spec;
        arm_spec(b, j, &spec, M2, L2, (ctc_form)form);
        ctc_model *m = build(&spec);
        cr_assert_eq(m->form, form == CTC_FORM_AUTO ? CTC_FORM_PLANAR : CTC_FORM_SPATIAL);
        cr_assert_eq(m->nsingular, 2, "both point masses are singular bodies");
        ctc_data *d = ctc_data_new(m);
        ctc_oracle *o = ctc_oracle_new(m);
        uint64_t rng = 18;
        double worst[6] = {0};
        for (int t = 0; t < 50; t++) {
            double q[2], v[2], u[2], mm[4], tau[2], f[2], a[2], x[4], acc[2];
            for (int i = 0; i < 2; i++) {
                q[i] = test_uniform(&rng, -CTC_PI, CTC_PI);
                v[i] = test_uniform(&rng, -3, 3);
                u[i] = test_uniform(&rng, -2, 2);
            }
            arm_closed_form(q, v, u, mm, tau);

            /* the oracle: CRBA's M, RNEA's tau */
            ctc_oracle_mass_matrix(m, o, q, x);
            worst[0] = fmax(worst[0], rel_diff(x, mm, 4));
            ctc_oracle_rnea(m, o, q, v, u, f);
            worst[1] = fmax(worst[1], rel_diff(f, tau, 2));

            /* iGDCA's tau, then GDCA and ABA back to u */
            ctc_kinematics(m, d, q, v);
            ctc_handles(m, d);
            ctc_gdca_inverse(m, d, u, f);
            worst[2] = fmax(worst[2], rel_diff(f, tau, 2));
            ctc_gdca_forward(m, d, tau, a);
            worst[3] = fmax(worst[3], rel_diff(a, u, 2));
            ctc_oracle_aba(m, o, q, v, tau, acc);
            worst[4] = fmax(worst[4], rel_diff(acc, u, 2));
            cr_assert_eq(d->singular_joint, -1);
            worst[5] = fmax(worst[5], rel_diff(a, acc, 2));
        }
        /* measured (planar, spatial): CRBA 2.8e-16, RNEA 3.9e-16, iGDCA 5.2e-16 and 6.3e-16,
           GDCA 1.8e-14 and 1.1e-14, ABA 2.0e-14, GDCA vs ABA 1.4e-14 and 1.2e-14 */
        cr_assert_lt(worst[0], 5e-14, "CRBA vs closed form %g", worst[0]);
        cr_assert_lt(worst[1], 5e-14, "RNEA vs closed form %g", worst[1]);
        cr_assert_lt(worst[2], 1e-13, "iGDCA vs closed form %g", worst[2]);
        cr_assert_lt(worst[3], 2e-12, "GDCA vs closed form %g (%s)", worst[3],
                     ctc_form_name(m->form));
        cr_assert_lt(worst[4], 5e-12, "ABA vs closed form %g", worst[4]);
        cr_assert_lt(worst[5], 2e-12, "GDCA vs ABA %g", worst[5]);
        ctc_oracle_free(o);
        ctc_data_free(d);
        ctc_model_free(m);
    }
}

/* Puma 560's link set as Armstrong, Khatib and Burdick (1986) measured it ("The Explicit Dynamic
   Model and Inertial Parameters of the Puma 560 Arm"), in the modified Denavit-Hartenberg form of
   Corke's Robotics Toolbox for MATLAB, puma560akb.m (mdl_puma560akb.m in later releases): per link
   alpha_(i-1), a_(i-1) (m), d_i (m), mass (kg), centre of mass r (m) and principal inertia
   (Ixx, Iyy, Izz) (kg m^2) in the link's frame. Link 1 has mass 0 and inertia 0.35 kg m^2 about
   its joint's axis (z) only: a lumped inertia no rigid body has, and a singular body. */
static const double puma_akb[6][10] = {
    {0, 0, 0, 0, 0, 0, 0, 0, 0, 0.35},
    {-CTC_PI / 2, 0, 0.2435, 17.4, 0.068, 0.006, -0.016, 0.13, 0.524, 0.539},
    {0, 0.4318, -0.0934, 4.8, 0, -0.070, 0.014, 0.066, 0.0125, 0.066},
    {CTC_PI / 2, -0.0203, 0.4331, 0.82, 0, 0, -0.019, 1.8e-3, 1.8e-3, 1.3e-3},
    {-CTC_PI / 2, 0, 0, 0.34, 0, 0, 0, 0.3e-3, 0.3e-3, 0.4e-3},
    {CTC_PI / 2, 0, 0, 0.09, 0, 0, 0.032, 0.15e-3, 0.15e-3, 0.04e-3},
};

/* The Puma's model: at q = 0 link i's frame is R_i = R_(i-1) Rx(alpha_(i-1)) with origin
   o_i = o_(i-1) + R_(i-1) (a_(i-1), 0, 0) + R_i (0, 0, d_i); joint i turns about R_i z through o_i.
   ctcsim's body frames are parallel to the world's at q = 0, so each joint's axis is R_i z, its
   location o_i - o_(i-1), the centre of mass R_i r and the inertia R_i diag(I) R_i^T. */
static void puma_spec(ctc_body_spec b[6], ctc_joint_spec j[6], ctc_chain_spec *spec)
{
    double rot[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, o[3] = {0, 0, 0};
    memset(b, 0, 6 * sizeof *b);
    memset(j, 0, 6 * sizeof *j);
    for (int i = 0; i < 6; i++) {
        const double *p = puma_akb[i];
        double ca = cos(p[0]), sa = sin(p[0]);
        double rx[9] = {1, 0, 0, 0, ca, -sa, 0, sa, ca}, ri[9], t[3], along[3] = {p[1], 0, 0};
        ctc_m3_mul(ri, rot, rx);
        double oi[3], dz[3] = {0, 0, p[2]};
        ctc_m3_mulv(t, rot, along);
        ctc_v3_add(oi, o, t);
        ctc_m3_mulv(t, ri, dz);
        ctc_v3_add(oi, oi, t);
        j[i].type = CTC_JOINT_REVOLUTE;
        ctc_v3_set(j[i].axis, ri[2], ri[5], ri[8]);
        ctc_v3_sub(j[i].location, oi, o);
        b[i].mass = p[3];
        ctc_m3_mulv(b[i].com, ri, p + 4);
        double diag[9] = {p[7], 0, 0, 0, p[8], 0, 0, 0, p[9]};
        ctc_m3_rotate_sym(b[i].inertia, ri, diag);
        memcpy(rot, ri, sizeof rot);
        ctc_v3_copy(o, oi);
    }
    memset(spec, 0, sizeof *spec);
    spec->nbodies = 6, spec->bodies = b, spec->joints = j;
    spec->gravity[2] = -9.81;
}

Test(singular, puma_560_link_set_matches_the_oracle_at_random_states)
{
    ctc_body_spec b[6];
    ctc_joint_spec j[6];
    ctc_chain_spec spec;
    puma_spec(b, j, &spec);
    ctc_model *m = build(&spec);
    cr_assert_eq(m->form, CTC_FORM_SPATIAL);
    cr_assert_eq(m->nsingular, 1, "link 1 (body 0) is the one singular body");
    cr_assert(m->body_singular[0]);
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    uint64_t rng = 560;
    double fwd = 0, inv = 0, rt = 0;
    for (int t = 0; t < 40; t++) {
        double q[6], v[6], f[6], a[6], ref[6], u[6], fi[6];
        test_random_state(m, &rng, 2.0, q, v);
        for (int i = 0; i < 6; i++) {
            f[i] = test_uniform(&rng, -50, 50);
            u[i] = test_uniform(&rng, -5, 5);
        }
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        cr_assert(test_all_finite(a, 6));
        ctc_oracle_aba(m, o, q, v, f, ref);
        fwd = fmax(fwd, rel_diff(a, ref, 6));
        ctc_gdca_inverse(m, d, u, fi);
        ctc_oracle_rnea(m, o, q, v, u, ref);
        inv = fmax(inv, rel_diff(fi, ref, 6));
        ctc_gdca_forward(m, d, fi, a);
        rt = fmax(rt, rel_diff(a, u, 6));
    }
    /* measured: forward 1.5e-15, inverse 7.6e-16, round trip 4.8e-14; the bound is the issue's */
    cr_assert_lt(fwd, 1e-10, "GDCA vs ABA %g", fwd);
    cr_assert_lt(inv, 1e-10, "iGDCA vs RNEA %g", inv);
    cr_assert_lt(rt, 1e-10, "GDCA(iGDCA(u)) vs u %g", rt);
    ctc_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
}

/* a spatial chain whose body 1 is a massless frame between fixed joints: body 0 (a box on a
   revolute joint), body 1 (m = 0, I = 0, fixed to body 0), body 2 (a mass fixed to body 1), body 3
   (a box on a revolute joint on body 2); against the same chain with bodies 0-2 merged by hand */
Test(singular, massless_frame_between_fixed_joints_equals_the_merged_body)
{
    ctc_body_spec b[4];
    ctc_joint_spec j[4];
    memset(b, 0, sizeof b);
    memset(j, 0, sizeof j);
    double ax0[3] = {0, 0, 1}, ax3[3] = {0, 1, 0};
    b[0].mass = 2, ctc_v3_set(b[0].com, 0.3, 0, 0);
    b[0].inertia[0] = 0.01, b[0].inertia[4] = 0.05, b[0].inertia[8] = 0.055;
    b[2].mass = 0.5, ctc_v3_set(b[2].com, 0, 0.1, 0.05);
    b[2].inertia[0] = b[2].inertia[4] = b[2].inertia[8] = 0.002;
    b[3].mass = 1, ctc_v3_set(b[3].com, 0.2, 0, -0.1);
    b[3].inertia[0] = 0.004, b[3].inertia[4] = 0.02, b[3].inertia[8] = 0.021;
    j[0].type = CTC_JOINT_REVOLUTE, ctc_v3_copy(j[0].axis, ax0);
    j[1].type = CTC_JOINT_FIXED, ctc_v3_set(j[1].location, 0.6, 0, 0);
    j[2].type = CTC_JOINT_FIXED, ctc_v3_set(j[2].location, 0.1, 0.05, 0);
    j[3].type = CTC_JOINT_REVOLUTE, ctc_v3_copy(j[3].axis, ax3);
    ctc_v3_set(j[3].location, 0.05, -0.05, 0.02);
    ctc_chain_spec spec = {.nbodies = 4, .bodies = b, .joints = j, .gravity = {0, 0, -9.81}};
    ctc_model *m = build(&spec);
    cr_assert_eq(m->nsingular, 1);

    /* merged: body 2's mass at 0.7, 0.05, 0 + its com in body 0's frame; parallel-axis theorem */
    ctc_body_spec mb[2];
    ctc_joint_spec mj[2] = {j[0], j[3]};
    double c2[3] = {0.7, 0.15, 0.05}, mt = b[0].mass + b[2].mass, com[3];
    for (int a = 0; a < 3; a++) com[a] = (b[0].mass * b[0].com[a] + b[2].mass * c2[a]) / mt;
    memset(mb, 0, sizeof mb);
    mb[0].mass = mt;
    ctc_v3_copy(mb[0].com, com);
    for (int body = 0; body < 2; body++) {
        const double *c = body ? c2 : b[0].com, mass = body ? b[2].mass : b[0].mass;
        const double *in = body ? b[2].inertia : b[0].inertia;
        double r[3];
        ctc_v3_sub(r, c, com);
        for (int a = 0; a < 3; a++) {
            for (int e = 0; e < 3; e++) {
                mb[0].inertia[3 * a + e] +=
                    in[3 * a + e] + mass * ((a == e) * ctc_v3_dot(r, r) - r[a] * r[e]);
            }
        }
    }
    mb[1] = b[3];
    ctc_v3_set(mj[1].location, 0.75, 0, 0.02);
    ctc_chain_spec mspec = {.nbodies = 2, .bodies = mb, .joints = mj, .gravity = {0, 0, -9.81}};
    ctc_model *mm = build(&mspec);
    cr_assert_eq(mm->nsingular, 0);

    ctc_data *d = ctc_data_new(m), *dm = ctc_data_new(mm);
    uint64_t rng = 7;
    double fwd = 0, inv = 0;
    for (int t = 0; t < 20; t++) {
        double q[2], v[2], f[2], a[2], ref[2];
        for (int i = 0; i < 2; i++) {
            q[i] = test_uniform(&rng, -CTC_PI, CTC_PI);
            v[i] = test_uniform(&rng, -3, 3);
            f[i] = test_uniform(&rng, -5, 5);
        }
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_kinematics(mm, dm, q, v);
        ctc_handles(mm, dm);
        ctc_gdca_forward(m, d, f, a);
        ctc_gdca_forward(mm, dm, f, ref);
        fwd = fmax(fwd, rel_diff(a, ref, 2));
        ctc_gdca_inverse(m, d, f, a);
        ctc_gdca_inverse(mm, dm, f, ref);
        inv = fmax(inv, rel_diff(a, ref, 2));
    }
    /* measured: forward 2.0e-14, inverse 3.9e-16 */
    cr_assert_lt(fwd, 5e-12, "forward vs merged %g", fwd);
    cr_assert_lt(inv, 1e-13, "inverse vs merged %g", inv);
    ctc_data_free(d);
    ctc_data_free(dm);
    ctc_model_free(m);
    ctc_model_free(mm);
}

/* 32 point masses of 1 kg, each 1 m beyond its joint on a massless link: planar, and spatial with
   the hinges about z and x alternately; every body singular */
Test(singular, long_point_mass_chains_match_the_oracle)
{
    enum { N = 32 };
    for (int spatial = 0; spatial < 2; spatial++) {
        test_chain *c = test_chain_rod_pendulum(N, 1.0, 1.0);
        for (int k = 0; k < N; k++) {
            memset(c->bodies[k].inertia, 0, sizeof c->bodies[k].inertia);
            ctc_v3_set(c->bodies[k].com, 0, -1, 0);
            if (spatial && (k & 1)) ctc_v3_set(c->joints[k].axis, 1, 0, 0);
        }
        ctc_model *m = build(&c->spec);
        cr_assert_eq(m->form, spatial ? CTC_FORM_SPATIAL : CTC_FORM_PLANAR);
        cr_assert_eq(m->nsingular, N);
        ctc_data *d = ctc_data_new(m);
        ctc_oracle *o = ctc_oracle_new(m);
        uint64_t rng = 32;
        double fwd = 0, inv = 0;
        for (int t = 0; t < 20; t++) {
            double q[N], v[N], f[N], a[N], ref[N];
            test_random_state(m, &rng, 2.0, q, v);
            for (int i = 0; i < N; i++) f[i] = test_uniform(&rng, -20, 20);
            ctc_kinematics(m, d, q, v);
            ctc_handles(m, d);
            ctc_gdca_forward(m, d, f, a);
            cr_assert(test_all_finite(a, N));
            ctc_oracle_aba(m, o, q, v, f, ref);
            fwd = fmax(fwd, rel_diff(a, ref, N));
            ctc_gdca_inverse(m, d, f, a);
            ctc_oracle_rnea(m, o, q, v, f, ref);
            inv = fmax(inv, rel_diff(a, ref, N));
        }
        /* measured (planar, spatial): forward 3.6e-14 and 2.2e-14, inverse 2.6e-15 and 1.4e-15 */
        cr_assert_lt(fwd, 5e-12, "GDCA vs ABA %g (%s)", fwd, ctc_form_name(m->form));
        cr_assert_lt(inv, 5e-13, "iGDCA vs RNEA %g (%s)", inv, ctc_form_name(m->form));
        ctc_oracle_free(o);
        ctc_data_free(d);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

Test(singular, a_singular_mass_matrix_is_refused_naming_the_body)
{
    ctc_body_spec b[2];
    ctc_joint_spec j[2];
    ctc_chain_spec spec;
    for (int form = CTC_FORM_AUTO; form <= CTC_FORM_SPATIAL; form += 2) {
        /* a massless tip on a revolute joint */
        arm_spec(b, j, &spec, 0.0, L2, (ctc_form)form);
        expect_build_error(&spec,
                           "body 1: the joint-space mass matrix is singular: joint 1 (revolute) "
                           "moves no mass or inertia that the joints before it do not (relative "
                           "pivot 0 <= 1e-10); body 1 and the bodies beyond it need mass off the "
                           "joint's axis or inertia about it");
        /* a point mass on its revolute joint's axis */
        arm_spec(b, j, &spec, M2, 0.0, (ctc_form)form);
        expect_build_error(&spec,
                           "body 1: the joint-space mass matrix is singular: joint 1 (revolute) "
                           "moves no mass or inertia that the joints before it do not (relative "
                           "pivot 0 <= 1e-10); body 1 and the bodies beyond it need mass off the "
                           "joint's axis or inertia about it");
    }
    /* a lumped inertia about an axis the joint does not turn: Puma's link 1 alone (0.35 kg m^2
       about z), turned about x */
    arm_spec(b, j, &spec, M2, L2, CTC_FORM_SPATIAL);
    spec.nbodies = 1;
    b[0].mass = 0, ctc_v3_set(b[0].com, 0, 0, 0);
    b[0].inertia[8] = 0.35;
    ctc_v3_set(j[0].axis, 1, 0, 0);
    expect_build_error(&spec,
                       "body 0: the joint-space mass matrix is singular: joint 0 (revolute) moves "
                       "no mass or inertia that the joints before it do not (relative pivot 0 <= "
                       "1e-10); body 0 and the bodies beyond it need mass off the joint's axis or "
                       "inertia about it");
    /* ... which the same joint about z accepts */
    ctc_v3_set(j[0].axis, 0, 0, 1);
    ctc_model *m = build(&spec);
    ctc_model_free(m);

    arm_spec(b, j, &spec, -1.0, L2, CTC_FORM_AUTO);
    expect_build_error(&spec, "body 1: mass must not be negative (got -1 kg)");
}

/* Worst errors of a loop model against the loop oracle (tests/support/loop_oracle.h) over random
 * states near q0 put onto the closure (ctc_loop_assemble): forward accelerations for random
 * forces on the independent coordinates, and CTC driving forces for random commands, each
 * relative to the oracle's largest entry. */
static void check_loop_against_oracle(const ctc_chain_spec *spec, const double *q0, int states,
                                      double *fwd, double *inv)
{
    ctc_model *m = build(spec);
    ctc_data *d = ctc_data_new(m);
    loop_oracle *o = loop_oracle_new(spec);
    cr_assert(d != NULL && o != NULL);
    const int nq = m->nq, nv = m->nv, nvx = m->nvx;
    double q[4 * LOOP_SCENE_MAX], v[LOOP_SCENE_MAX + 3], f[LOOP_SCENE_MAX + 3],
        a[LOOP_SCENE_MAX + 3], ref[LOOP_SCENE_MAX + 3];
    cr_assert(nq <= 4 * LOOP_SCENE_MAX && nvx <= LOOP_SCENE_MAX + 3);
    uint64_t rng = 1818;
    *fwd = *inv = 0;
    for (int t = 0; t < states; t++) {
        for (int i = 0; i < nq; i++) q[i] = q0[i] + test_uniform(&rng, -0.01, 0.01);
        for (int i = 0; i < nv; i++) v[i] = test_uniform(&rng, -1, 1);
        char err[256] = "";
        cr_assert_eq(ctc_loop_assemble(m, d, q, v, 1e-12, 20, NULL, err, sizeof err), CTC_OK,
                     "state %d: %s", t, err);
        for (int i = 0; i < nvx; i++) f[i] = 0;
        for (int i = 0; i < m->nind; i++) f[m->ind_coord[i]] = test_uniform(&rng, -5, 5);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        cr_assert_eq(loop_oracle_forward(o, q, v, f, ref, NULL), 0);
        *fwd = fmax(*fwd, rel_diff(a, ref, nvx));
        /* f as the commands u */
        ctc_gdca_inverse(m, d, f, a);
        cr_assert_eq(loop_oracle_inverse(o, q, v, f, ref, NULL), 0);
        *inv = fmax(*inv, rel_diff(a, ref, nvx));
    }
    loop_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
}

/* Loop models take point masses and massless bodies where the loop's reduced mass matrix (M(q) on
 * the closure's tangent space) is positive definite: the forward pass augments them and its
 * refinement reaches the oracle, and the loop's CTC inverse (gdca_inverse_loop.h) inverts no
 * body. The paper's five-bar with its 0.5 m link massless (planar), or a point mass at that
 * link's far end (planar: no inertia about the normal), or its last link massless (the closing
 * joint holds it; the open chain's M is singular there); a spatial loop of 8 boxes with body 3 a
 * point mass and body 5 massless, and the same loop with its tip massless. */
Test(singular, loops_with_point_masses_and_massless_bodies_match_the_oracle)
{
    static const char *const what[] = {"five-bar, massless link", "five-bar, point mass",
                                       "five-bar, massless tip", "spatial loop",
                                       "spatial loop, massless tip"};
    for (int c = 0; c < 5; c++) {
        double fwd, inv;
        if (c < 3) {
            loop_scene *s = loop_scene_five_bar();
            ctc_body_spec *b = &s->bodies[c < 2 ? 2 : 4];
            memset(b->inertia, 0, sizeof b->inertia);
            if (c == 1) {
                ctc_v3_set(b->com, 0, -0.5, 0); /* the link's far end */
            } else {
                b->mass = 0;
            }
            check_loop_against_oracle(&s->spec, s->q0, 20, &fwd, &inv);
            free(s);
        } else {
            test_loop *l = test_loop_spatial(8, 7);
            cr_assert(l != NULL);
            const int tip = c == 4 ? 7 : 5;
            if (c == 3) memset(l->bodies[3].inertia, 0, sizeof l->bodies[3].inertia);
            l->bodies[tip].mass = 0;
            memset(l->bodies[tip].inertia, 0, sizeof l->bodies[tip].inertia);
            check_loop_against_oracle(&l->spec, l->q0, 20, &fwd, &inv);
            test_loop_free(l);
        }
        cr_log_info("%s: forward %.1e, inverse %.1e\n", what[c], fwd, inv);
        cr_expect_lt(fwd, 1e-10, "%s: GDCA vs the oracle %g", what[c], fwd);
        cr_expect_lt(inv, 1e-10, "%s: iGDCA vs the oracle %g", what[c], inv);
    }
}

/* ... and refuse one whose reduced mass matrix is singular, naming the body: the five-bar's
 * massless tip with the closing joint at the tip's own joint (the closure pins that point, and
 * nothing resists the tip's turning about it), and the same on the spatial loop, whose spherical
 * closing joint sits on the tip's joint axis. */
Test(singular, loop_models_refuse_a_singular_mass_matrix_naming_the_body)
{
    loop_scene *s = loop_scene_five_bar();
    s->bodies[4].mass = 0;
    memset(s->bodies[4].inertia, 0, sizeof s->bodies[4].inertia);
    memset(s->loop.joint.location, 0, sizeof s->loop.joint.location);
    expect_build_error(&s->spec,
                       "body 4: the loop's joint-space mass matrix is singular: joint 4 "
                       "(revolute) moves no mass or inertia that the joints before it do not, "
                       "nor does the loop's closure hold it (relative pivot 0 <= 1e-10); body "
                       "4 and the bodies beyond it need mass off the joint's axis or inertia "
                       "about it");
    free(s);

    test_loop *l = test_loop_spatial(8, 7);
    cr_assert(l != NULL);
    l->bodies[7].mass = 0;
    memset(l->bodies[7].inertia, 0, sizeof l->bodies[7].inertia);
    for (int a = 0; a < 3; a++) l->loop.joint.location[a] = 0.3 * l->joints[7].axis[a];
    ctc_model *m = NULL;
    char err[512] = "";
    cr_assert_eq(ctc_model_build(&l->spec, &m, err, sizeof err), CTC_EINVAL);
    cr_expect(strstr(err, "body 7: the loop's joint-space mass matrix is singular: joint 7 "
                          "(revolute)") == err,
              "%s", err);
    test_loop_free(l);
}

/* ctc_gdca_inverse_mobility (gdca.h) on models with augmented bodies: the paper's literal form
 * needs each body's inverse inertia (Eq. 42-43), which a singular body has not, so there it gives
 * ctc_gdca_inverse's forces, bitwise, and both match the oracles. Open: the point-mass arm (both
 * forms), Puma 560's link set, and 16 slender rods (ratio 1e-8, spatial), against RNEA; loops:
 * the five-bar with its tip massless and the spatial loop of 8 with a point mass and a massless
 * body, against the loop oracle. Measured before (the literal form on the augmented records):
 * arm 1.8e-6 (both forms), Puma 1.1e-5, rods 6.8e-7, five-bar 1.4e-7, spatial loop 1.0e-6. */
static double mobility_vs_oracle(const ctc_chain_spec *spec, const double *q0, int states)
{
    ctc_model *m = build(spec);
    cr_assert(m->fwd_bodies != m->bodies, "the model has augmented bodies");
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = m->has_loop ? NULL : ctc_oracle_new(m);
    loop_oracle *lo = m->has_loop ? loop_oracle_new(spec) : NULL;
    cr_assert(d != NULL && (o != NULL || lo != NULL));
    const int nq = m->nq, nv = m->nv, nvx = m->nvx;
    double *buf = calloc((size_t)nq + (size_t)nv + 4 * (size_t)nvx, sizeof(double));
    cr_assert(buf != NULL);
    double *q = buf, *v = q + nq, *u = v + nv, *f = u + nvx, *fc = f + nvx, *ref = fc + nvx;
    uint64_t rng = 4242;
    double worst = 0;
    for (int t = 0; t < states; t++) {
        for (int i = 0; i < nvx; i++) u[i] = 0;
        if (m->has_loop) {
            for (int i = 0; i < nq; i++) q[i] = q0[i] + test_uniform(&rng, -0.01, 0.01);
            for (int i = 0; i < nv; i++) v[i] = test_uniform(&rng, -1, 1);
            char err[256] = "";
            cr_assert_eq(ctc_loop_assemble(m, d, q, v, 1e-12, 20, NULL, err, sizeof err), CTC_OK,
                         "state %d: %s", t, err);
        } else {
            test_random_state(m, &rng, 2.0, q, v);
        }
        for (int i = 0; i < m->nind; i++) u[m->ind_coord[i]] = test_uniform(&rng, -5, 5);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_inverse_mobility(m, d, u, f);
        ctc_gdca_inverse(m, d, u, fc);
        cr_expect_arr_eq(f, fc, (size_t)nvx * sizeof *f, "state %d: the composite form's forces",
                         t);
        if (m->has_loop) {
            cr_assert_eq(loop_oracle_inverse(lo, q, v, u, ref, NULL), 0);
        } else {
            ctc_oracle_rnea(m, o, q, v, u, ref);
        }
        worst = fmax(worst, rel_diff(f, ref, nvx));
    }
    free(buf);
    loop_oracle_free(lo);
    ctc_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
    return worst;
}

Test(singular, the_mobility_form_gives_exact_forces_on_augmented_models)
{
    double err[6];
    ctc_body_spec b[6];
    ctc_joint_spec j[6];
    ctc_chain_spec spec;
    arm_spec(b, j, &spec, M2, L2, CTC_FORM_AUTO);
    err[0] = mobility_vs_oracle(&spec, NULL, 40);
    arm_spec(b, j, &spec, M2, L2, CTC_FORM_SPATIAL);
    err[1] = mobility_vs_oracle(&spec, NULL, 40);
    puma_spec(b, j, &spec);
    err[2] = mobility_vs_oracle(&spec, NULL, 40);
    test_chain *c = test_chain_slender_rods(16, 1e-8);
    err[3] = mobility_vs_oracle(&c->spec, NULL, 40);
    test_chain_free(c);
    loop_scene *s = loop_scene_five_bar();
    s->bodies[4].mass = 0;
    memset(s->bodies[4].inertia, 0, sizeof s->bodies[4].inertia);
    err[4] = mobility_vs_oracle(&s->spec, s->q0, 20);
    free(s);
    test_loop *l = test_loop_spatial(8, 7);
    cr_assert(l != NULL);
    memset(l->bodies[3].inertia, 0, sizeof l->bodies[3].inertia);
    l->bodies[5].mass = 0;
    memset(l->bodies[5].inertia, 0, sizeof l->bodies[5].inertia);
    err[5] = mobility_vs_oracle(&l->spec, l->q0, 20);
    test_loop_free(l);
    static const char *const what[] = {"arm, planar", "arm, spatial",           "Puma 560",
                                       "16 rods",     "five-bar, massless tip", "spatial loop"};
    for (int i = 0; i < 6; i++) {
        cr_log_info("%s: mobility form vs the oracle %.1e\n", what[i], err[i]);
        cr_expect_lt(err[i], 1e-12, "%s: %g", what[i], err[i]);
    }
}
