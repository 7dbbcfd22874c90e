/*
 * test_kinematics.c - the kinematics pass (src/model/kinematics.c) against closed forms and finite
 * differences.
 *
 * Oracles, each written apart from the code under test:
 *  - a planar double pendulum's poses and velocities in closed form, in planar and spatial form;
 *  - velocities: fourth-order central differences of the poses along the motion q(t), obtained by
 *    integrating qdot = ctc_model_q_rate(q, v) with RK4 (exact for all but the quaternions);
 *    omega is the axial vector of Rdot R^T;
 *  - joint maps: P and D orthonormal with D^T P = 0, and P v equal to the difference between the
 *    body's velocity and that of the parent's material point at the joint (finite differences);
 *  - the acceleration constraint A1(k) = A2(k-1) + P qdd + beta: along q(t) with v(t) = v + t qdd,
 *    second differences of the poses give the angular accelerations (the skew part of
 *    Rddot R^T, since [w]x^2 is symmetric), the acceleration of body k's origin and that of the
 *    material point of body k-1 that sits at body k's origin at t = 0;
 *  - planar chains forced to spatial form, also rotated into a tilted plane: the planar
 *    quantities read through the model's plane basis (e1, e2, n) as the spatial ones;
 *  - a branched tree (a Y, made by hand from a chain's model, model_fixture.h): each body placed
 *    as on the chain of its path from the ground, so the pass walks the parents.
 * Differences use the five-point stencils with h = 1e-3 (error O(h^4) plus rounding ~1e-9 for
 * second differences); observed errors are ~1e-10 against tolerances of 1e-8 (velocities) and
 * 1e-6 (accelerations), relative to the largest quantity compared. Random chains have 7 bodies;
 * the tests assert that every joint type (planar: prismatic, fixed, revolute about -z) occurs.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "chains.h"
#include "data.h"
#include "kinematics.h"
#include "model.h"
#include "model_fixture.h"
#include "shapes.h"
#include "spatial.h"

#define MAXB 8
#define MAXQ (4 * MAXB)
#define MAXV (3 * MAXB)

/* five-point stencil, offsets -2h..2h */
#define FD_STEP 1e-3
static const double fd_w1[5] = {1.0 / 12, -8.0 / 12, 0.0, 8.0 / 12, -1.0 / 12}; /* times 1/h */
static const double fd_w2[5] = {-1.0 / 12, 16.0 / 12, -30.0 / 12, 16.0 / 12, -1.0 / 12}; /* 1/h^2 */

typedef struct kin_fixture {
    ctc_model *m;
    ctc_data *d;
} kin_fixture;

static kin_fixture kin_make(const ctc_chain_spec *spec)
{
    kin_fixture f;
    char err[256] = "";
    ctc_status st = ctc_model_build(spec, &f.m, err, sizeof err);
    cr_assert_eq(st, CTC_OK, "ctc_model_build: %s", err);
    cr_assert_leq(f.m->nbodies, MAXB);
    f.d = ctc_data_new(f.m);
    cr_assert_not_null(f.d);
    return f;
}

static void kin_free(kin_fixture *f)
{
    ctc_data_free(f->d);
    ctc_model_free(f->m);
}

static double max_abs(int n, const double *x)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(x[i]));
    return s;
}

static double max_abs_diff(int n, const double *a, const double *b)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(a[i] - b[i]));
    return s;
}

/* ---- the motion q(t): q' = rate(q, v0 + t a), q(0) = q0, by RK4 ---- */

static void q_along_motion(const ctc_model *m, const double *q0, const double *v0, const double *a,
                           double t, double *q)
{
    const int steps = 8;
    double dt = t / steps, k1[MAXQ], k2[MAXQ], k3[MAXQ], k4[MAXQ], tmp[MAXQ], v[MAXV];
    memcpy(q, q0, (size_t)m->nq * sizeof(double));
    for (int s = 0; s < steps; s++) {
        double t0 = s * dt;
        for (int i = 0; i < m->nv; i++) v[i] = v0[i] + t0 * a[i];
        ctc_model_q_rate(m, q, v, k1);
        for (int i = 0; i < m->nv; i++) v[i] = v0[i] + (t0 + 0.5 * dt) * a[i];
        for (int i = 0; i < m->nq; i++) tmp[i] = q[i] + 0.5 * dt * k1[i];
        ctc_model_q_rate(m, tmp, v, k2);
        for (int i = 0; i < m->nq; i++) tmp[i] = q[i] + 0.5 * dt * k2[i];
        ctc_model_q_rate(m, tmp, v, k3);
        for (int i = 0; i < m->nv; i++) v[i] = v0[i] + (t0 + dt) * a[i];
        for (int i = 0; i < m->nq; i++) tmp[i] = q[i] + dt * k3[i];
        ctc_model_q_rate(m, tmp, v, k4);
        for (int i = 0; i < m->nq; i++) q[i] += dt / 6 * (k1[i] + 2 * k2[i] + 2 * k3[i] + k4[i]);
    }
}

/* poses along the motion at t = (s - 2) h, s = 0..4 */
typedef struct pose_stencil {
    double pos[5][3 * MAXB];
    double rot[5][9 * MAXB];
} pose_stencil;

static void sample_poses(const kin_fixture *f, const double *q0, const double *v0, const double *a,
                         pose_stencil *ps)
{
    const ctc_model *m = f->m;
    for (int s = 0; s < 5; s++) {
        double t = (s - 2) * FD_STEP, q[MAXQ], v[MAXV];
        q_along_motion(m, q0, v0, a, t, q);
        for (int i = 0; i < m->nv; i++) v[i] = v0[i] + t * a[i];
        ctc_kinematics(m, f->d, q, v);
        memcpy(ps->pos[s], f->d->xpos, (size_t)m->nbodies * 3 * sizeof(double));
        memcpy(ps->rot[s], f->d->xrot, (size_t)m->nbodies * 9 * sizeof(double));
    }
}

/* axial vector of the skew part of W R0^T, W = sum_s w[s] R_s / scale */
static void fd_angular(const pose_stencil *ps, int k, const double w[5], double scale,
                       double out[3])
{
    double wd[9] = {0}, x[9];
    const double *r0 = &ps->rot[2][9 * k];
    for (int s = 0; s < 5; s++) {
        for (int i = 0; i < 9; i++) wd[i] += w[s] * ps->rot[s][9 * k + i] / scale;
    }
    for (int i = 0; i < 3; i++) { /* x = wd r0^T */
        for (int j = 0; j < 3; j++) {
            x[3 * i + j] = wd[3 * i] * r0[3 * j] + wd[3 * i + 1] * r0[3 * j + 1] +
                           wd[3 * i + 2] * r0[3 * j + 2];
        }
    }
    out[0] = 0.5 * (x[7] - x[5]);
    out[1] = 0.5 * (x[2] - x[6]);
    out[2] = 0.5 * (x[3] - x[1]);
}

/* derivative of the material point of body k with body coordinates b: x = p_k + R_k b */
static void fd_point(const pose_stencil *ps, int k, const double b[3], const double w[5],
                     double scale, double out[3])
{
    ctc_v3_set(out, 0, 0, 0);
    for (int s = 0; s < 5; s++) {
        double x[3];
        ctc_m3_mulv(x, &ps->rot[s][9 * k], b);
        ctc_v3_add(x, x, &ps->pos[s][3 * k]);
        ctc_v3_addscl(out, out, x, w[s] / scale);
    }
}

/* (angular; linear) as a dim-vector: spatial (ang; lin), planar (ang_z, lin_x, lin_y) */
static void pack(int dim, const double ang[3], const double lin[3], double out[6])
{
    if (dim == 6) {
        ctc_v3_copy(out, ang);
        ctc_v3_copy(out + 3, lin);
    } else {
        out[0] = ang[2];
        out[1] = lin[0];
        out[2] = lin[1];
    }
}

/* y = P_k x_k for joint k (x = joint k's velocity coordinates) */
static void joint_P_times(const ctc_model *m, const ctc_data *d, int k, const double *x,
                          double y[6])
{
    int dim = m->dim, nv = m->jnt_nv[k];
    for (int i = 0; i < dim; i++) y[i] = 0;
    for (int c = 0; c < nv; c++) {
        const double *col = d->jnt_P + (size_t)(3 * k + c) * dim;
        for (int i = 0; i < dim; i++) y[i] += col[i] * x[m->jnt_vadr[k] + c];
    }
}

/* The random chains of the tests, 7 bodies: spatial with all joint types, or planar in the x-y
 * plane with revolute joints about +-z and prismatic joints. Odd seeds move the ground joint off
 * the origin (in the plane for planar chains); planar chains of seeds divisible by 3 get a fixed
 * joint 2. covers[t] counts joints of type t, covers[5] revolute joints about -z. */
static test_chain *random_chain(int spatial, uint64_t seed, int covers[6])
{
    test_chain *c = spatial ? test_chain_random_spatial(7, seed, TEST_ALL_JOINTS)
                            : test_chain_random_planar(7, seed, 1, 0);
    if (seed % 2) ctc_v3_set(c->joints[0].location, 0.3, -0.2, spatial ? 0.25 : 0.0);
    if (!spatial && seed % 3 == 0) c->joints[2].type = CTC_JOINT_FIXED;
    for (int k = 0; k < c->spec.nbodies; k++) {
        covers[c->joints[k].type]++;
        if (c->joints[k].type == CTC_JOINT_REVOLUTE && c->joints[k].axis[2] < 0) covers[5]++;
    }
    return c;
}

/* asserts that the chains drawn covered what they should */
static void check_coverage(int spatial, const int covers[6])
{
    if (spatial) {
        for (int t = 0; t < 5; t++) {
            cr_assert_gt(covers[t], 0, "no %s joint drawn", ctc_joint_type_name((ctc_joint_type)t));
        }
    } else {
        cr_assert_gt(covers[CTC_JOINT_PRISMATIC], 0, "no prismatic joint drawn");
        cr_assert_gt(covers[CTC_JOINT_FIXED], 0, "no fixed joint drawn");
        cr_assert_gt(covers[5], 0, "no revolute joint about -z drawn");
    }
}

/* pack(A1(body k)) - pack(A2(body k-1)) from the stencil, A2 of the material point of body k-1
 * at body k's origin at t = 0 (zero for the ground); w, scale: a derivative's stencil */
static void joint_relative(const ctc_model *m, const pose_stencil *ps, int k, const double w[5],
                           double scale, double a1[6], double a2[6])
{
    static const double zero[3] = {0, 0, 0};
    double ang[3], lin[3];
    fd_angular(ps, k, w, scale, ang);
    fd_point(ps, k, zero, w, scale, lin);
    pack(m->dim, ang, lin, a1);
    if (k == 0) {
        for (int i = 0; i < m->dim; i++) a2[i] = 0;
        return;
    }
    double rel[3], b[3];
    ctc_v3_sub(rel, &ps->pos[2][3 * k], &ps->pos[2][3 * (k - 1)]);
    ctc_m3_tmulv(b, &ps->rot[2][9 * (k - 1)], rel); /* in body k-1's frame */
    fd_angular(ps, k - 1, w, scale, ang);
    fd_point(ps, k - 1, b, w, scale, lin);
    pack(m->dim, ang, lin, a2);
}

/* ---- closed form: planar double pendulum ---- */

static const double dp_len[2] = {1.2, 0.7};
static const double dp_mass[2] = {1.0, 0.5};

/* thin boxes hanging along -y from revolute joints about +z; their inertia has full rank, so the
 * same chain is valid in spatial form */
static ctc_chain_spec dp_spec(ctc_body_spec bodies[2], ctc_joint_spec joints[2], ctc_form form)
{
    for (int k = 0; k < 2; k++) {
        double size[3] = {0.05, dp_len[k], 0.04}, centre[3] = {0, -dp_len[k] / 2, 0};
        char err[128] = "";
        cr_assert_eq(ctc_shape_box(dp_mass[k], size, centre, &bodies[k], err, sizeof err), CTC_OK,
                     "%s", err);
        joints[k] = (ctc_joint_spec){
            .type = CTC_JOINT_REVOLUTE, .axis = {0, 0, 1}, .location = {0, k ? -dp_len[0] : 0, 0}};
    }
    return (ctc_chain_spec){
        .nbodies = 2, .bodies = bodies, .joints = joints, .gravity = {0, -9.81, 0}, .form = form};
}

/* the closed form of the pendulum's kinematics */
typedef struct dp_state {
    double pos[6], rot[18], com[6], omega[6], vel[6];
} dp_state;

static dp_state dp_closed_form(const double q[2], const double v[2])
{
    dp_state s;
    double a0 = q[0], a1 = q[0] + q[1];
    double c0 = cos(a0), s0 = sin(a0), c1 = cos(a1), s1 = sin(a1);
    double rz0[9] = {c0, -s0, 0, s0, c0, 0, 0, 0, 1}, rz1[9] = {c1, -s1, 0, s1, c1, 0, 0, 0, 1};
    ctc_v3_set(s.pos, 0, 0, 0);
    ctc_v3_set(s.pos + 3, dp_len[0] * s0, -dp_len[0] * c0, 0);
    memcpy(s.rot, rz0, sizeof rz0);
    memcpy(s.rot + 9, rz1, sizeof rz1);
    ctc_v3_set(s.com, 0.5 * dp_len[0] * s0, -0.5 * dp_len[0] * c0, 0);
    ctc_v3_set(s.com + 3, dp_len[0] * s0 + 0.5 * dp_len[1] * s1,
               -dp_len[0] * c0 - 0.5 * dp_len[1] * c1, 0);
    ctc_v3_set(s.omega, 0, 0, v[0]);
    ctc_v3_set(s.omega + 3, 0, 0, v[0] + v[1]);
    ctc_v3_set(s.vel, 0, 0, 0);
    ctc_v3_set(s.vel + 3, dp_len[0] * v[0] * c0, dp_len[0] * v[0] * s0, 0);
    return s;
}

static double dp_compare(const ctc_data *d, const dp_state *s)
{
    double e = max_abs_diff(6, d->xpos, s->pos);
    e = fmax(e, max_abs_diff(18, d->xrot, s->rot));
    e = fmax(e, max_abs_diff(6, d->xcom, s->com));
    e = fmax(e, max_abs_diff(6, d->omega, s->omega));
    return fmax(e, max_abs_diff(6, d->xvel, s->vel));
}

Test(kinematics, double_pendulum_matches_closed_form)
{
    /* all quantities are O(1): absolute tolerance 1e-14 */
    ctc_body_spec bodies[2];
    ctc_joint_spec joints[2];
    ctc_chain_spec spec = dp_spec(bodies, joints, CTC_FORM_AUTO);
    kin_fixture f = kin_make(&spec);
    cr_assert_eq(f.m->form, CTC_FORM_PLANAR);
    double worst = 0;

    for (int i = 0; i < 9; i++) {
        for (int j = 0; j < 9; j++) {
            double q[2] = {-CTC_PI + 0.1 + i * 0.77, -CTC_PI + 0.3 + j * 0.71};
            double v[2] = {1.5 - 0.4 * i, -2.0 + 0.5 * j};
            ctc_kinematics(f.m, f.d, q, v);
            dp_state s = dp_closed_form(q, v);
            double e = dp_compare(f.d, &s);
            worst = fmax(worst, e);
            cr_assert_leq(e, 1e-14, "q = (%g, %g): error %.3e", q[0], q[1], e);

            /* joint maps of a revolute joint in planar form */
            for (int k = 0; k < 2; k++) {
                const double *P = f.d->jnt_P + 9 * k, *D = f.d->jnt_D + 9 * k;
                const double *beta = f.d->jnt_beta + 3 * k;
                double wantP[3] = {1, 0, 0}, wantD[6] = {0, 1, 0, 0, 0, 1}, zero[3] = {0};
                cr_assert_leq(max_abs_diff(3, P, wantP), 0.0, "joint %d: P", k);
                cr_assert_leq(max_abs_diff(6, D, wantD), 0.0, "joint %d: D", k);
                cr_assert_leq(max_abs_diff(3, beta, zero), 0.0, "joint %d: beta", k);
            }
        }
    }
    cr_log_info("double pendulum vs closed form: worst error %.2e (tolerance 1e-14)", worst);
    kin_free(&f);
}

Test(kinematics, double_pendulum_in_spatial_form_matches_planar_form)
{
    /* forced to spatial form, the +z chain gives the planar form's world quantities (the plane is
       the x-y plane itself) and the closed form; revolute beta = w x u qd = 0 (parallel axes) */
    ctc_body_spec bp[2], bs[2];
    ctc_joint_spec jp[2], js[2];
    ctc_chain_spec sp = dp_spec(bp, jp, CTC_FORM_AUTO), ss = dp_spec(bs, js, CTC_FORM_SPATIAL);
    kin_fixture fp = kin_make(&sp), fs = kin_make(&ss);
    cr_assert_eq(fp.m->form, CTC_FORM_PLANAR);
    cr_assert_eq(fs.m->form, CTC_FORM_SPATIAL);
    const double plane[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    cr_assert_leq(max_abs_diff(3, fp.m->plane_e1, plane), 0.0);
    cr_assert_leq(max_abs_diff(3, fp.m->plane_e2, plane + 3), 0.0);
    cr_assert_leq(max_abs_diff(3, fp.m->plane_n, plane + 6), 0.0);
    double worst = 0;

    for (int i = 0; i < 12; i++) {
        double q[2] = {-3.0 + 0.53 * i, 2.9 - 0.61 * i}, v[2] = {0.3 * i - 1.7, 2.1 - 0.2 * i};
        ctc_kinematics(fp.m, fp.d, q, v);
        ctc_kinematics(fs.m, fs.d, q, v);
        dp_state s = dp_closed_form(q, v);
        double e = fmax(dp_compare(fs.d, &s), max_abs_diff(6, fs.d->xpos, fp.d->xpos));
        e = fmax(e, max_abs_diff(18, fs.d->xrot, fp.d->xrot));
        e = fmax(e, max_abs_diff(6, fs.d->xcom, fp.d->xcom));
        e = fmax(e, max_abs_diff(6, fs.d->omega, fp.d->omega));
        e = fmax(e, max_abs_diff(6, fs.d->xvel, fp.d->xvel));
        worst = fmax(worst, e);
        cr_assert_leq(e, 1e-14, "q = (%g, %g): spatial vs planar/closed form %.3e", q[0], q[1], e);
        for (int k = 0; k < 2; k++) {
            const double wantP[6] = {0, 0, 1, 0, 0, 0}, zero[6] = {0};
            cr_assert_leq(max_abs_diff(6, fs.d->jnt_P + 18 * k, wantP), 1e-15, "joint %d: P", k);
            cr_assert_leq(max_abs_diff(6, fs.d->jnt_beta + 6 * k, zero), 1e-15, "joint %d: beta",
                          k);
        }
    }
    cr_log_info("double pendulum spatial vs planar form: worst difference %.2e (tolerance 1e-14)",
                worst);
    kin_free(&fp);
    kin_free(&fs);
}

/* ---- random chains: velocities, joint maps, acceleration constraint ---- */

#define NSEEDS 6

static double check_velocities(int spatial)
{
    int covers[6] = {0};
    double worst = 0;
    for (uint64_t seed = 1; seed <= NSEEDS; seed++) {
        test_chain *c = random_chain(spatial, seed, covers);
        kin_fixture f = kin_make(&c->spec);
        cr_assert_eq(f.m->form, spatial ? CTC_FORM_SPATIAL : CTC_FORM_PLANAR);
        uint64_t rng = 1000 + seed;
        double q[MAXQ], v[MAXV], a[MAXV] = {0}, omega[3 * MAXB], xvel[3 * MAXB];
        static pose_stencil ps;
        test_random_state(f.m, &rng, 2.0, q, v);
        ctc_kinematics(f.m, f.d, q, v);
        memcpy(omega, f.d->omega, (size_t)f.m->nbodies * 3 * sizeof(double));
        memcpy(xvel, f.d->xvel, (size_t)f.m->nbodies * 3 * sizeof(double));
        sample_poses(&f, q, v, a, &ps);

        for (int k = 0; k < f.m->nbodies; k++) {
            static const double zero[3] = {0, 0, 0};
            double w[3], vel[3];
            fd_angular(&ps, k, fd_w1, FD_STEP, w);
            fd_point(&ps, k, zero, fd_w1, FD_STEP, vel);
            double scale = fmax(1.0, fmax(max_abs(3, &omega[3 * k]), max_abs(3, &xvel[3 * k])));
            double ew = max_abs_diff(3, w, &omega[3 * k]) / scale;
            double ev = max_abs_diff(3, vel, &xvel[3 * k]) / scale;
            worst = fmax(worst, fmax(ew, ev));
            cr_assert_leq(ew, 1e-8,
                          "seed %d body %d: omega (%.12g %.12g %.12g), differences (%.12g "
                          "%.12g %.12g)",
                          (int)seed, k, omega[3 * k], omega[3 * k + 1], omega[3 * k + 2], w[0],
                          w[1], w[2]);
            cr_assert_leq(ev, 1e-8,
                          "seed %d body %d: xvel (%.12g %.12g %.12g), differences (%.12g "
                          "%.12g %.12g)",
                          (int)seed, k, xvel[3 * k], xvel[3 * k + 1], xvel[3 * k + 2], vel[0],
                          vel[1], vel[2]);
        }
        kin_free(&f);
        test_chain_free(c);
    }
    check_coverage(spatial, covers);
    return worst;
}

Test(kinematics, velocities_match_finite_differences_on_random_spatial_chains)
{
    double worst = check_velocities(1);
    cr_log_info("spatial velocities vs differences: worst relative error %.2e (tolerance 1e-8)",
                worst);
}

Test(kinematics, velocities_match_finite_differences_on_random_planar_chains)
{
    double worst = check_velocities(0);
    cr_log_info("planar velocities vs differences: worst relative error %.2e (tolerance 1e-8)",
                worst);
}

/* P, D orthonormal, D^T P = 0, and V1(k) - V2(k-1) = P v_k (finite differences) */
static void check_joint_maps(int spatial, double *worst_ortho, double *worst_vel)
{
    int covers[6] = {0};
    *worst_ortho = *worst_vel = 0;
    for (uint64_t seed = 1; seed <= NSEEDS; seed++) {
        test_chain *c = random_chain(spatial, seed, covers);
        kin_fixture f = kin_make(&c->spec);
        const ctc_model *m = f.m;
        int dim = m->dim;
        uint64_t rng = 2000 + seed;
        double q[MAXQ], v[MAXV], a[MAXV] = {0};
        static pose_stencil ps;
        static double P[MAXB * 3 * 6], D[MAXB * 6 * 6];
        test_random_state(m, &rng, 2.0, q, v);
        ctc_kinematics(m, f.d, q, v);
        memcpy(P, f.d->jnt_P, (size_t)m->nbodies * 3 * dim * sizeof(double));
        memcpy(D, f.d->jnt_D, (size_t)m->nbodies * dim * dim * sizeof(double));

        for (int k = 0; k < m->nbodies; k++) {
            int nv = m->jnt_nv[k];
            /* columns: P's nv, then D's dim - nv; all dim of them orthonormal */
            const double *col[6];
            for (int i = 0; i < nv; i++) col[i] = P + (size_t)(3 * k + i) * dim;
            for (int i = 0; i < dim - nv; i++) col[nv + i] = D + (size_t)(dim * k + i) * dim;
            for (int i = 0; i < dim; i++) {
                for (int j = 0; j < dim; j++) {
                    double dot = 0;
                    for (int r = 0; r < dim; r++) dot += col[i][r] * col[j][r];
                    double e = fabs(dot - (i == j ? 1.0 : 0.0));
                    *worst_ortho = fmax(*worst_ortho, e);
                    cr_assert_leq(e, 1e-14,
                                  "seed %d joint %d (%s): column %d . column %d = %.17g "
                                  "(columns 0..%d are P's)",
                                  (int)seed, k, ctc_joint_type_name(m->joints[k].type), i, j, dot,
                                  nv - 1);
                }
            }
        }

        /* P v from the velocities by differences */
        sample_poses(&f, q, v, a, &ps);
        ctc_kinematics(m, f.d, q, v);
        for (int k = 0; k < m->nbodies; k++) {
            double v1[6], v2[6], pv[6];
            joint_relative(m, &ps, k, fd_w1, FD_STEP, v1, v2);
            joint_P_times(m, f.d, k, v, pv);
            double scale = fmax(1.0, fmax(max_abs(dim, v1), max_abs(dim, v2)));
            for (int i = 0; i < dim; i++) {
                double e = fabs(v1[i] - v2[i] - pv[i]) / scale;
                *worst_vel = fmax(*worst_vel, e);
                cr_assert_leq(
                    e, 1e-8, "seed %d joint %d (%s) component %d: V1 - V2 = %.12g, P v = %.12g",
                    (int)seed, k, ctc_joint_type_name(m->joints[k].type), i, v1[i] - v2[i], pv[i]);
            }
        }
        kin_free(&f);
        test_chain_free(c);
    }
    check_coverage(spatial, covers);
}

Test(kinematics, joint_maps_are_orthonormal_and_map_joint_velocity_on_spatial_chains)
{
    double eo, ev;
    check_joint_maps(1, &eo, &ev);
    cr_log_info("spatial joint maps: orthonormality %.2e (tolerance 1e-14), P v vs differences "
                "%.2e (tolerance 1e-8)",
                eo, ev);
}

Test(kinematics, joint_maps_are_orthonormal_and_map_joint_velocity_on_planar_chains)
{
    double eo, ev;
    check_joint_maps(0, &eo, &ev);
    cr_log_info("planar joint maps: orthonormality %.2e (tolerance 1e-14), P v vs differences "
                "%.2e (tolerance 1e-8)",
                eo, ev);
}

/* A1(k) - A2(k-1) - P qdd = beta, accelerations by second differences along the motion */
static double check_acceleration_constraint(int spatial)
{
    int covers[6] = {0};
    double worst = 0;
    for (uint64_t seed = 1; seed <= NSEEDS; seed++) {
        test_chain *c = random_chain(spatial, seed, covers);
        kin_fixture f = kin_make(&c->spec);
        const ctc_model *m = f.m;
        int dim = m->dim;
        uint64_t rng = 3000 + seed;
        double q[MAXQ], v[MAXV], qdd[MAXV], beta[6 * MAXB];
        static pose_stencil ps;
        test_random_state(m, &rng, 2.0, q, v);
        for (int i = 0; i < m->nv; i++) qdd[i] = test_uniform(&rng, -3, 3);
        sample_poses(&f, q, v, qdd, &ps);
        ctc_kinematics(m, f.d, q, v);
        memcpy(beta, f.d->jnt_beta, (size_t)m->nbodies * dim * sizeof(double));

        for (int k = 0; k < m->nbodies; k++) {
            double a1[6], a2[6], pa[6];
            joint_relative(m, &ps, k, fd_w2, FD_STEP * FD_STEP, a1, a2);
            joint_P_times(m, f.d, k, qdd, pa);
            double scale = fmax(1.0, fmax(max_abs(dim, a1), max_abs(dim, a2)));
            for (int i = 0; i < dim; i++) {
                double want = a1[i] - a2[i] - pa[i];
                double e = fabs(beta[dim * k + i] - want) / scale;
                worst = fmax(worst, e);
                cr_assert_leq(e, 1e-6,
                              "seed %d joint %d (%s) component %d: beta = %.12g, A1 - A2 - P qdd "
                              "= %.12g (scale %.3g)",
                              (int)seed, k, ctc_joint_type_name(m->joints[k].type), i,
                              beta[dim * k + i], want, scale);
            }
        }
        kin_free(&f);
        test_chain_free(c);
    }
    check_coverage(spatial, covers);
    return worst;
}

Test(kinematics, acceleration_constraint_matches_finite_differences_on_spatial_chains)
{
    double worst = check_acceleration_constraint(1);
    cr_log_info("spatial beta vs differences: worst relative error %.2e (tolerance 1e-6)", worst);
}

Test(kinematics, acceleration_constraint_matches_finite_differences_on_planar_chains)
{
    double worst = check_acceleration_constraint(0);
    cr_log_info("planar beta vs differences: worst relative error %.2e (tolerance 1e-6)", worst);
}

Test(kinematics, planar_chains_agree_in_planar_and_spatial_form)
{
    /* a chain in the x-y plane, forced to spatial form: the same poses, velocities, P columns and
       beta, planar (a, b, c) reading spatial (0, 0, a, b, c, 0); the CoM is compared in the plane
       only (planar form drops its out-of-plane offset) */
    int covers[6] = {0};
    double worst = 0;
    for (uint64_t seed = 1; seed <= NSEEDS; seed++) {
        test_chain *c = random_chain(0, seed, covers);
        kin_fixture fp = kin_make(&c->spec);
        c->spec.form = CTC_FORM_SPATIAL;
        kin_fixture fs = kin_make(&c->spec);
        cr_assert_eq(fp.m->form, CTC_FORM_PLANAR);
        cr_assert_eq(fs.m->form, CTC_FORM_SPATIAL);
        const ctc_data *dp = fp.d, *ds = fs.d;
        uint64_t rng = 4000 + seed;
        double q[MAXQ], v[MAXV];
        test_random_state(fp.m, &rng, 2.0, q, v);
        ctc_kinematics(fp.m, fp.d, q, v);
        ctc_kinematics(fs.m, fs.d, q, v);

        for (int k = 0; k < fp.m->nbodies; k++) {
            double e = max_abs_diff(3, dp->xpos + 3 * k, ds->xpos + 3 * k);
            e = fmax(e, max_abs_diff(9, dp->xrot + 9 * k, ds->xrot + 9 * k));
            e = fmax(e, max_abs_diff(2, dp->xcom + 3 * k, ds->xcom + 3 * k));
            e = fmax(e, max_abs_diff(3, dp->omega + 3 * k, ds->omega + 3 * k));
            e = fmax(e, max_abs_diff(3, dp->xvel + 3 * k, ds->xvel + 3 * k));
            for (int i = 0; i < fp.m->jnt_nv[k]; i++) {
                const double *pp = dp->jnt_P + 3 * (3 * k + i),
                             *pspat = ds->jnt_P + 6 * (3 * k + i);
                double emb[6] = {0, 0, pp[0], pp[1], pp[2], 0};
                e = fmax(e, max_abs_diff(6, emb, pspat));
            }
            const double *bp = dp->jnt_beta + 3 * k;
            double emb[6] = {0, 0, bp[0], bp[1], bp[2], 0};
            e = fmax(e, max_abs_diff(6, emb, ds->jnt_beta + 6 * k));
            worst = fmax(worst, e);
            cr_assert_leq(e, 1e-13, "seed %d body %d: planar vs spatial form differ by %.3e",
                          (int)seed, k, e);
        }
        kin_free(&fp);
        kin_free(&fs);
        test_chain_free(c);
    }
    check_coverage(0, covers);
    cr_log_info("planar vs spatial form: worst difference %.2e (tolerance 1e-13)", worst);
}

Test(kinematics, planar_form_in_a_tilted_plane_reads_as_spatial_form)
{
    /* a random planar chain rotated as a whole by R (axes, locations, CoMs, inertias, gravity):
       its plane is tilted, and with B = [e1 e2 n] from the model the planar quantities must read
       as the spatial form's world ones: position x e1 + y e2, rotation B R_planar B^T, angular
       velocity omega_z n, joint vectors (a, b, c) -> (a n; b e1 + c e2) */
    int covers[6] = {0};
    double worst = 0;
    uint64_t rng = 77;
    for (uint64_t seed = 1; seed <= NSEEDS; seed++) {
        test_chain *c = random_chain(0, seed, covers);
        double axis[3], rot[9];
        ctc_v3_set(axis, test_uniform(&rng, -1, 1), test_uniform(&rng, -1, 1), 0.5);
        ctc_v3_scale(axis, axis, 1.0 / ctc_v3_norm(axis));
        ctc_m3_axis_angle(rot, axis, test_uniform(&rng, 0.3, 2.8));
        test_chain_rotate(c, rot);

        kin_fixture fp = kin_make(&c->spec);
        c->spec.form = CTC_FORM_SPATIAL;
        kin_fixture fs = kin_make(&c->spec);
        cr_assert_eq(fp.m->form, CTC_FORM_PLANAR, "seed %d: the rotated chain is not planar",
                     (int)seed);
        const double *e1 = fp.m->plane_e1, *e2 = fp.m->plane_e2, *n = fp.m->plane_n;
        double bm[9] = {e1[0], e2[0], n[0], e1[1], e2[1], n[1], e1[2], e2[2], n[2]};
        double q[MAXQ], v[MAXV];
        test_random_state(fp.m, &rng, 2.0, q, v);
        ctc_kinematics(fp.m, fp.d, q, v);
        ctc_kinematics(fs.m, fs.d, q, v);
        const ctc_data *dp = fp.d, *ds = fs.d;

        for (int k = 0; k < fp.m->nbodies; k++) {
            double x[3], r[9], tmp[9];
            /* position, CoM (in-plane part), velocity */
            ctc_m3_mulv(x, bm, dp->xpos + 3 * k);
            double e = max_abs_diff(3, x, ds->xpos + 3 * k);
            e = fmax(e, fabs(ctc_v3_dot(ds->xcom + 3 * k, e1) - dp->xcom[3 * k]));
            e = fmax(e, fabs(ctc_v3_dot(ds->xcom + 3 * k, e2) - dp->xcom[3 * k + 1]));
            ctc_m3_mulv(x, bm, dp->xvel + 3 * k);
            e = fmax(e, max_abs_diff(3, x, ds->xvel + 3 * k));
            /* orientation and angular velocity */
            ctc_m3_mul(tmp, bm, dp->xrot + 9 * k);
            for (int i = 0; i < 3; i++) {
                for (int j = 0; j < 3; j++) {
                    r[3 * i + j] = tmp[3 * i] * bm[3 * j] + tmp[3 * i + 1] * bm[3 * j + 1] +
                                   tmp[3 * i + 2] * bm[3 * j + 2];
                }
            }
            e = fmax(e, max_abs_diff(9, r, ds->xrot + 9 * k));
            ctc_v3_scale(x, n, dp->omega[3 * k + 2]);
            e = fmax(e, max_abs_diff(3, x, ds->omega + 3 * k));
            /* P columns and beta */
            for (int i = 0; i <= fp.m->jnt_nv[k]; i++) {
                const double *pv =
                    i < fp.m->jnt_nv[k] ? dp->jnt_P + 3 * (3 * k + i) : dp->jnt_beta + 3 * k;
                const double *sv =
                    i < fp.m->jnt_nv[k] ? ds->jnt_P + 6 * (3 * k + i) : ds->jnt_beta + 6 * k;
                double emb[6];
                ctc_v3_scale(emb, n, pv[0]);
                for (int j = 0; j < 3; j++) emb[3 + j] = pv[1] * e1[j] + pv[2] * e2[j];
                e = fmax(e, max_abs_diff(6, emb, sv));
            }
            worst = fmax(worst, e);
            cr_assert_leq(e, 1e-13,
                          "seed %d body %d: planar form in a tilted plane differs from "
                          "spatial form by %.3e",
                          (int)seed, k, e);
        }
        kin_free(&fp);
        kin_free(&fs);
        test_chain_free(c);
    }
    check_coverage(0, covers);
    cr_log_info("tilted plane, planar vs spatial form: worst difference %.2e (tolerance 1e-13)",
                worst);
}

/* Body t of model a (data da) against body i of model b (data db), and their inboard joints */
static void expect_same_body(const ctc_model *a, const ctc_data *da, int t, const ctc_model *b,
                             const ctc_data *db, int i, int sample)
{
    const int dim = a->dim;
    struct {
        const char *name;
        const double *x, *y;
        int len;
    } f[] = {
        {"xpos", da->xpos + 3 * t, db->xpos + 3 * i, 3},
        {"xrot", da->xrot + 9 * t, db->xrot + 9 * i, 9},
        {"xcom", da->xcom + 3 * t, db->xcom + 3 * i, 3},
        {"omega", da->omega + 3 * t, db->omega + 3 * i, 3},
        {"xvel", da->xvel + 3 * t, db->xvel + 3 * i, 3},
        {"jnt_P", da->jnt_P + 3 * dim * t, db->jnt_P + 3 * dim * i, dim * b->jnt_nv[i]},
        {"jnt_D", da->jnt_D + dim * dim * t, db->jnt_D + dim * dim * i, dim * dim},
        {"jnt_beta", da->jnt_beta + dim * t, db->jnt_beta + dim * i, dim},
    };
    for (size_t c = 0; c < sizeof f / sizeof f[0]; c++) {
        for (int e = 0; e < f[c].len; e++) {
            cr_assert_leq(fabs(f[c].x[e] - f[c].y[e]), 1e-14 * fmax(1.0, fabs(f[c].y[e])),
                          "sample %d: tree body %d, %s[%d] = %.17g, on its path's chain %.17g",
                          sample, t, f[c].name, e, f[c].x[e], f[c].y[e]);
        }
    }
}

/* A Y tree (bodies 1 and 2 on body 0) made from the 3-body chain c, against the two chains of
 * its paths, bodies (0, 1) and (0, 2), in the tree's form and with the same coordinates. */
static void check_tree_paths(test_chain *c, uint64_t seed)
{
    const int parent[3] = {-1, 0, 0};
    kin_fixture tree = kin_make(&c->spec);
    fixture_set_parents(tree.m, parent);
    kin_fixture path[2];
    for (int p = 0; p < 2; p++) {
        ctc_body_spec bodies[2] = {c->bodies[0], c->bodies[1 + p]};
        ctc_joint_spec joints[2] = {c->joints[0], c->joints[1 + p]};
        ctc_chain_spec spec = c->spec;
        spec.nbodies = 2, spec.bodies = bodies, spec.joints = joints, spec.form = tree.m->form;
        path[p] = kin_make(&spec);
        if (tree.m->form == CTC_FORM_PLANAR) { /* the same plane, so the same coordinates */
            for (int e = 0; e < 3; e++) {
                cr_assert_eq(path[p].m->plane_n[e], tree.m->plane_n[e]);
                cr_assert_eq(path[p].m->plane_e1[e], tree.m->plane_e1[e]);
            }
        }
    }
    uint64_t rng = seed;
    for (int s = 0; s < 50; s++) {
        double q[MAXQ], v[MAXV], qp[MAXQ], vp[MAXV];
        test_random_state(tree.m, &rng, 2.0, q, v);
        ctc_kinematics(tree.m, tree.d, q, v);
        for (int p = 0; p < 2; p++) {
            const ctc_model *m = tree.m;
            int iq = 0, iv = 0;
            for (int k = 0; k <= 1 + p; k += 1 + p) { /* joints 0 and 1 + p */
                for (int e = 0; e < m->jnt_nq[k]; e++) qp[iq++] = q[m->jnt_qadr[k] + e];
                for (int e = 0; e < m->jnt_nv[k]; e++) vp[iv++] = v[m->jnt_vadr[k] + e];
            }
            ctc_kinematics(path[p].m, path[p].d, qp, vp);
            expect_same_body(tree.m, tree.d, 0, path[p].m, path[p].d, 0, s);
            expect_same_body(tree.m, tree.d, 1 + p, path[p].m, path[p].d, 1, s);
        }
    }
    kin_free(&path[0]);
    kin_free(&path[1]);
    kin_free(&tree);
}

Test(kinematics, a_branched_tree_places_each_body_from_its_parent)
{
    for (uint64_t seed = 1; seed <= 8; seed++) {
        test_chain *c = test_chain_random_spatial(3, seed, TEST_ALL_JOINTS);
        check_tree_paths(c, seed);
        test_chain_free(c);
        c = test_chain_random_planar(3, seed, 1, 0);
        check_tree_paths(c, seed);
        test_chain_free(c);
    }
}
