/*
 * test_urdf.c - robots imported from URDF (server/urdf.c) and Denavit-Hartenberg tables
 * (server/dh.c) through the frame conversion of server/import.c, and the job format's "scene.urdf"
 * and "scene.dh" (server/job_scene.c).
 *
 * Oracle: the dynamics of each robot computed here by a separate route from the published
 * numbers, with no use of ctcsim's frames: forward kinematics of the original description (DH's
 * or URDF's transforms F_i = F_p(i) A_i Mot(axis_i, q_i) B_i, p(i) the link joint i hangs from,
 * with the inertial data in F_i), then the textbook Jacobians, with a column for each joint j on
 * link i's path to the ground and zero columns for the others (revolute: Jv_j = z_j x (p_c - o_j),
 * Jw_j = z_j; prismatic: Jv_j = z_j, Jw_j = 0) and
 *     M(q)    = sum_i m_i Jv_i^T Jv_i + Jw_i^T R_i I_i R_i^T Jw_i,
 *     G(q)    = -sum_i m_i Jv_i^T g,
 *     c(q, v) = sum_i m_i Jv_i^T (dJv_i v) + Jw_i^T (I_w (dJw_i v) + w_i x I_w w_i),
 * with dJ v from the axes' rates dz_j = w_p(j) x z_j and the joint points' velocities. ctcsim's
 * side is the model built from the converted job and the library's independent oracle
 * (oracle.h: composite-rigid-body M, Newton-Euler c + G). They must agree to 1e-10 at several
 * poses and velocities.
 *
 * Published numbers: the UR5's DH table, masses and centres of mass from Universal Robots,
 * "Parameters for calculations of kinematics and dynamics" (universal-robots.com, UR5 column);
 * its link inertias (about the centres of mass, principal, in the DH frames) from ur_description's
 * ur5 cylinder approximations as Lynch and Park, Modern Robotics (2017), list them for the UR5
 * (G1..G6). The Panda's joint origins and finger joints from franka_description's franka_arm and
 * franka_hand xacro files (frankaemika/franka_ros; equal to Franka's modified DH table); its arm
 * links' masses, centres of mass and inertias identified by Gaz, Cognetti, Oliva, Robuffo
 * Giordano and De Luca (IEEE RA-L 2019), and the hand's and fingers', as franka_description's
 * robots/common/inertial.yaml lists them; its arm also as Franka's modified DH table
 * (frankaemika.github.io), which must give the URDF's dynamics. The Panda with prismatic fingers
 * and the gripper on an arm written for the test are trees: a link's Jacobian has columns only for
 * the joints on its path to the ground. On them, and on every robot here, GDCA's forward
 * accelerations must also equal the oracle's M^-1 (tau - c - G), solved densely in the test. The
 * two-link arm is the textbook planar arm (Spong, Hutchinson and Vidyasagar, Robot Modeling and
 * Control, section 7.3: l = 1 m, lc = 0.5 m, m = 1 kg) with a slender-rod inertia m l^2 / 12 about
 * the normal axes and a small one about the rod's. The KUKA LBR iiwa 14 from Drake's
 * iiwa14_no_collision.urdf (RobotLocomotion/drake, manipulation/models/iiwa_description), typed in
 * here apart from its preset (server/presets_robots.c); so is the Panda's. The two-link preset is
 * Lynch and Park's arm with point masses at the link ends (Modern Robotics, section 8.1.1, its M, c
 * and g in closed form, eqs. 8.9-8.11); the Puma 560 preset is Armstrong, Khatib and Burdick's
 * (1986) modified DH table and inertial parameters as Corke's mdl_puma560akb lists them, link 1
 * massless with 0.35 kg m^2 about its axis.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "ctc.h"
#include "frames.h"
#include "job_json.h"
#include "model.h"
#include "oracle.h"
#include "presets.h"
#include "sim.h"
#include "urdf.h"

#define DYN_TOL 1e-10
#define MAXJ 16

/* ---- the oracle: a chain of transforms, its kinematics and its dynamics ---- */

typedef struct xf {
    double R[9], p[3];
} xf;

enum { T_REV, T_PRI, T_FIXED };

/* F_i = F_(i-1) A Mot(axis, q) B; inertial data in F_i */
typedef struct tjoint {
    int type;
    xf A, B;
    double axis[3];
    double mass, com[3], I[9];
} tjoint;

static xf xf_id(void)
{
    xf t = {{1, 0, 0, 0, 1, 0, 0, 0, 1}, {0, 0, 0}};
    return t;
}

static xf xf_mul(xf a, xf b)
{
    xf t;
    test_m3_mul(t.R, a.R, b.R);
    test_m3_mulv(t.p, a.R, b.p);
    for (int i = 0; i < 3; i++) t.p[i] += a.p[i];
    return t;
}

static void cross(const double *a, const double *b, double *c)
{
    double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2],
           z = a[0] * b[1] - a[1] * b[0];
    c[0] = x, c[1] = y, c[2] = z;
}

/* URDF's rpy: Rz(y) Ry(p) Rx(r), written as the product of the three elementary rotations */
static xf xf_rpy(double x, double y, double z, double r, double p, double yw)
{
    static const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    double Rx[9], Ry[9], Rz[9], t[9];
    xf o;
    test_m3_rot(Rx, ex, r);
    test_m3_rot(Ry, ey, p);
    test_m3_rot(Rz, ez, yw);
    test_m3_mul(t, Ry, Rx);
    test_m3_mul(o.R, Rz, t);
    o.p[0] = x, o.p[1] = y, o.p[2] = z;
    return o;
}

/* standard DH's B = Rz(theta) Tz(d) Tx(a) Rx(alpha) as a product of elementary transforms */
static xf dh_standard(double a, double alpha, double d, double theta)
{
    xf rz = xf_rpy(0, 0, d, 0, 0, theta), tx = xf_rpy(a, 0, 0, alpha, 0, 0);
    return xf_mul(rz, tx);
}

/* 1 when joint j is joint i or one of its ancestors; par[i] is joint i's parent joint (-1: the
 * ground), or par is NULL for a serial chain (parent i - 1) */
static int on_path(const int *par, int j, int i)
{
    if (par == NULL) return j <= i;
    for (; i >= 0; i = par[i])
        if (i == j) return 1;
    return 0;
}

/* the tree's M (nv x nv), G and c at q, v; gravity g. Joint i moves link i from the link of
 * joint par[i] (par NULL: a serial chain), par[i] < i. */
static int oracle_dynamics(const tjoint *J, const int *par, int n, const double *g, const double *q,
                           const double *v, double *M, double *G, double *c)
{
    double z[MAXJ][3], o[MAXJ][3], Rl[MAXJ][9], pl[MAXJ][3];
    int col[MAXJ], nv = 0;
    xf Tl[MAXJ];
    for (int i = 0; i < n; i++) {
        int p = par == NULL ? i - 1 : par[i];
        xf Tj = xf_mul(p < 0 ? xf_id() : Tl[p], J[i].A);
        double u[3], len = sqrt(J[i].axis[0] * J[i].axis[0] + J[i].axis[1] * J[i].axis[1] +
                                J[i].axis[2] * J[i].axis[2]);
        for (int k = 0; k < 3; k++) u[k] = J[i].axis[k] / len;
        test_m3_mulv(z[i], Tj.R, u);
        memcpy(o[i], Tj.p, sizeof o[i]);
        xf mot = xf_id();
        col[i] = J[i].type == T_FIXED ? -1 : nv++;
        if (J[i].type == T_REV) test_m3_rot(mot.R, u, q[col[i]]);
        if (J[i].type == T_PRI)
            for (int k = 0; k < 3; k++) mot.p[k] = q[col[i]] * u[k];
        Tl[i] = xf_mul(xf_mul(Tj, mot), J[i].B);
        memcpy(Rl[i], Tl[i].R, sizeof Tl[i].R);
        memcpy(pl[i], Tl[i].p, sizeof Tl[i].p);
    }
    /* angular velocity of link i, and of the link before joint i (its parent) */
    double w[MAXJ][3] = {{0}}, wb[MAXJ][3], ob[MAXJ][3];
    for (int i = 0; i < n; i++) {
        int p = par == NULL ? i - 1 : par[i];
        for (int k = 0; k < 3; k++) wb[i][k] = p < 0 ? 0 : w[p][k];
        /* velocity of the point o_i, fixed in the link before joint i: its ancestors' joints */
        for (int k = 0; k < 3; k++) ob[i][k] = 0;
        for (int j = 0; j < i; j++) {
            if (col[j] < 0 || !on_path(par, j, p)) continue;
            double t[3], r[3];
            if (J[j].type == T_REV) {
                for (int k = 0; k < 3; k++) r[k] = o[i][k] - o[j][k];
                cross(z[j], r, t);
            } else {
                memcpy(t, z[j], sizeof t);
            }
            for (int k = 0; k < 3; k++) ob[i][k] += t[k] * v[col[j]];
        }
        memcpy(w[i], wb[i], sizeof w[i]);
        if (J[i].type == T_REV)
            for (int k = 0; k < 3; k++) w[i][k] += z[i][k] * v[col[i]];
    }
    memset(M, 0, (size_t)(nv * nv) * sizeof *M);
    memset(G, 0, (size_t)nv * sizeof *G);
    memset(c, 0, (size_t)nv * sizeof *c);
    /* every link, a massless one too: its rotational inertia counts (Puma 560's link 1) */
    for (int i = 0; i < n; i++) {
        double pc[3], Iw[9], RI[9], Rt[9];
        test_m3_mulv(pc, Rl[i], J[i].com);
        for (int k = 0; k < 3; k++) pc[k] += pl[i][k];
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) Rt[3 * a + b] = Rl[i][3 * b + a];
        test_m3_mul(RI, Rl[i], J[i].I);
        test_m3_mul(Iw, RI, Rt);
        double Jv[MAXJ][3] = {{0}}, Jw[MAXJ][3] = {{0}};
        double vc[3] = {0, 0, 0};
        for (int j = 0; j <= i; j++) {
            if (col[j] < 0 || !on_path(par, j, i)) continue;
            if (J[j].type == T_REV) {
                double r[3];
                for (int k = 0; k < 3; k++) r[k] = pc[k] - o[j][k];
                cross(z[j], r, Jv[col[j]]);
                memcpy(Jw[col[j]], z[j], sizeof z[j]);
            } else {
                memcpy(Jv[col[j]], z[j], sizeof z[j]);
            }
            for (int k = 0; k < 3; k++) vc[k] += Jv[col[j]][k] * v[col[j]];
        }
        /* dJv v and dJw v */
        double av[3] = {0, 0, 0}, aw[3] = {0, 0, 0};
        for (int j = 0; j <= i; j++) {
            if (col[j] < 0 || !on_path(par, j, i)) continue;
            double dz[3], t1[3], t2[3], r[3], dr[3];
            cross(wb[j], z[j], dz);
            if (J[j].type == T_REV) {
                for (int k = 0; k < 3; k++) r[k] = pc[k] - o[j][k], dr[k] = vc[k] - ob[j][k];
                cross(dz, r, t1);
                cross(z[j], dr, t2);
                for (int k = 0; k < 3; k++) {
                    av[k] += (t1[k] + t2[k]) * v[col[j]];
                    aw[k] += dz[k] * v[col[j]];
                }
            } else {
                for (int k = 0; k < 3; k++) av[k] += dz[k] * v[col[j]];
            }
        }
        double Iaw[3], Iww[3], gyro[3], rot[3];
        test_m3_mulv(Iaw, Iw, aw);
        test_m3_mulv(Iww, Iw, w[i]);
        cross(w[i], Iww, gyro);
        for (int k = 0; k < 3; k++) rot[k] = Iaw[k] + gyro[k];
        for (int a = 0; a < nv; a++) {
            double IJa[3];
            test_m3_mulv(IJa, Iw, Jw[a]);
            for (int b = 0; b < nv; b++) {
                M[a * nv + b] +=
                    J[i].mass * (Jv[a][0] * Jv[b][0] + Jv[a][1] * Jv[b][1] + Jv[a][2] * Jv[b][2]) +
                    IJa[0] * Jw[b][0] + IJa[1] * Jw[b][1] + IJa[2] * Jw[b][2];
            }
            G[a] -= J[i].mass * (Jv[a][0] * g[0] + Jv[a][1] * g[1] + Jv[a][2] * g[2]);
            c[a] += J[i].mass * (Jv[a][0] * av[0] + Jv[a][1] * av[1] + Jv[a][2] * av[2]) +
                    Jw[a][0] * rot[0] + Jw[a][1] * rot[1] + Jw[a][2] * rot[2];
        }
    }
    return nv;
}

/* ---- ctcsim's side ---- */

static job *parse_ok(const char *doc)
{
    job *j = NULL;
    job_error err;
    int rc = job_parse(doc, strlen(doc), &j, &err);
    cr_assert_eq(rc, 0, "%s: %s", err.field, err.message);
    return j;
}

/* a job document around a scene (JSON text) */
static char *job_text(const char *scene_json)
{
    size_t n = strlen(scene_json) + 200;
    char *s = malloc(n);
    snprintf(s, n, "{\"scene\": %s, \"controller\": {\"type\": \"none\"}, \"duration\": 0.1}",
             scene_json);
    return s;
}

/* {"scene": {"urdf": text}} as a job document */
static char *urdf_job(const char *urdf)
{
    cJSON *scene = cJSON_CreateObject();
    cJSON_AddStringToObject(scene, "urdf", urdf);
    char *s = cJSON_PrintUnformatted(scene);
    cJSON_Delete(scene);
    char *doc = job_text(s);
    free(s);
    return doc;
}

/* poses and velocities from a fixed pattern */
static void pose(int k, int nv, double *q, double *v)
{
    for (int i = 0; i < nv; i++) {
        q[i] = k == 0 ? 0 : 0.7 * sin(1.3 * k + 0.9 * i) + 0.1 * k;
        v[i] = k == 0 ? 0 : 1.1 * cos(0.7 * k + 1.7 * i);
    }
}

/* x = A^-1 b for a symmetric positive definite A (n x n), by Cholesky, written here */
static void spd_solve(const double *A, int n, const double *b, double *x)
{
    double L[MAXJ * MAXJ] = {0}, y[MAXJ];
    for (int i = 0; i < n; i++) {
        for (int j = 0; j <= i; j++) {
            double t = A[i * n + j];
            for (int k = 0; k < j; k++) t -= L[i * n + k] * L[j * n + k];
            if (i == j) {
                cr_assert_gt(t, 0, "the oracle's M is not positive definite");
                L[i * n + i] = sqrt(t);
            } else {
                L[i * n + j] = t / L[j * n + j];
            }
        }
    }
    for (int i = 0; i < n; i++) {
        double t = b[i];
        for (int k = 0; k < i; k++) t -= L[i * n + k] * y[k];
        y[i] = t / L[i * n + i];
    }
    for (int i = n - 1; i >= 0; i--) {
        double t = y[i];
        for (int k = i + 1; k < n; k++) t -= L[k * n + i] * x[k];
        x[i] = t / L[i * n + i];
    }
}

/* the job's model against the oracle's tree (par as oracle_dynamics) at 5 poses: M from the
 * composite-rigid-body oracle, c and G from Newton-Euler, each to DYN_TOL, and GDCA's forward
 * accelerations against the oracle's qacc = M^-1 (tau - c - G), solved densely here, to DYN_TOL
 * relative to the largest. Returns the largest difference of M, c and G; the largest relative
 * difference of the accelerations into acc_err (may be NULL). */
static double compare_tree(const job *j, const tjoint *J, const int *par, int n, double *acc_err)
{
    ctc_model *m = NULL;
    char msg[256];
    cr_assert_eq(ctc_model_build(&j->spec.chain, &m, msg, sizeof msg), CTC_OK, "%s", msg);
    ctc_oracle *o = ctc_oracle_new(m);
    ctc_data *d = ctc_data_new(m);
    cr_assert(o != NULL && d != NULL);
    int nv = m->nv;
    double q[MAXJ], v[MAXJ], zero[MAXJ] = {0}, M[MAXJ * MAXJ], G[MAXJ], c[MAXJ];
    double Mc[MAXJ * MAXJ], tv[MAXJ], t0[MAXJ], worst = 0, worst_acc = 0;
    double tau[MAXJ], rhs[MAXJ], acc[MAXJ], acc_gdca[MAXJ];
    for (int k = 0; k < 5; k++) {
        pose(k, nv, q, v);
        cr_assert_eq(oracle_dynamics(J, par, n, m->gravity, q, v, M, G, c), nv);
        ctc_oracle_mass_matrix(m, o, q, Mc);
        ctc_oracle_rnea(m, o, q, v, zero, tv);
        ctc_oracle_rnea(m, o, q, zero, zero, t0);
        for (int a = 0; a < nv; a++) {
            for (int b = 0; b < nv; b++) {
                double e = fabs(M[a * nv + b] - Mc[a * nv + b]);
                cr_assert_leq(e, DYN_TOL, "pose %d: M[%d][%d] %.17g vs ctcsim %.17g", k, a, b,
                              M[a * nv + b], Mc[a * nv + b]);
                worst = fmax(worst, e);
            }
            double dg = fabs(G[a] - t0[a]), dc = fabs(c[a] - (tv[a] - t0[a]));
            cr_assert_leq(dg, DYN_TOL, "pose %d: G[%d] %.17g vs ctcsim %.17g", k, a, G[a], t0[a]);
            cr_assert_leq(dc, DYN_TOL, "pose %d: c[%d] %.17g vs ctcsim %.17g", k, a, c[a],
                          tv[a] - t0[a]);
            worst = fmax(worst, fmax(dg, dc));
        }
        /* forward dynamics under driving forces of a few N m (N) */
        for (int a = 0; a < nv; a++) {
            tau[a] = 2 * sin(0.9 * k + 1.1 * a);
            rhs[a] = tau[a] - c[a] - G[a];
        }
        spd_solve(M, nv, rhs, acc);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, tau, acc_gdca);
        cr_assert_eq(d->singular_joint, -1, "pose %d", k);
        double scale = 0, e = 0;
        for (int a = 0; a < nv; a++) {
            scale = fmax(scale, fabs(acc[a]));
            e = fmax(e, fabs(acc[a] - acc_gdca[a]));
        }
        for (int a = 0; a < nv; a++)
            cr_assert_leq(fabs(acc[a] - acc_gdca[a]), DYN_TOL * scale,
                          "pose %d: qacc[%d] %.17g vs GDCA %.17g", k, a, acc[a], acc_gdca[a]);
        worst_acc = fmax(worst_acc, e / scale);
    }
    ctc_data_free(d);
    ctc_oracle_free(o);
    ctc_model_free(m);
    if (acc_err != NULL) *acc_err = worst_acc;
    return worst;
}

/* compare_tree for a serial chain */
static double compare(const job *j, const tjoint *J, int n)
{
    return compare_tree(j, J, NULL, n, NULL);
}

/* two models' M, c + G agree at 5 poses */
static void compare_jobs(const job *a, const job *b)
{
    ctc_model *ma = NULL, *mb = NULL;
    char msg[256];
    cr_assert_eq(ctc_model_build(&a->spec.chain, &ma, msg, sizeof msg), CTC_OK, "%s", msg);
    cr_assert_eq(ctc_model_build(&b->spec.chain, &mb, msg, sizeof msg), CTC_OK, "%s", msg);
    cr_assert_eq(ma->nv, mb->nv);
    ctc_oracle *oa = ctc_oracle_new(ma), *ob = ctc_oracle_new(mb);
    double q[MAXJ], v[MAXJ], zero[MAXJ] = {0}, Ma[MAXJ * MAXJ], Mb[MAXJ * MAXJ], ta[MAXJ], tb[MAXJ];
    for (int k = 0; k < 5; k++) {
        pose(k, ma->nv, q, v);
        ctc_oracle_mass_matrix(ma, oa, q, Ma);
        ctc_oracle_mass_matrix(mb, ob, q, Mb);
        ctc_oracle_rnea(ma, oa, q, v, zero, ta);
        ctc_oracle_rnea(mb, ob, q, v, zero, tb);
        for (int i = 0; i < ma->nv * ma->nv; i++)
            cr_assert_leq(fabs(Ma[i] - Mb[i]), DYN_TOL, "pose %d: M entry %d", k, i);
        for (int i = 0; i < ma->nv; i++)
            cr_assert_leq(fabs(ta[i] - tb[i]), DYN_TOL, "pose %d: c + G entry %d", k, i);
    }
    ctc_oracle_free(oa);
    ctc_oracle_free(ob);
    ctc_model_free(ma);
    ctc_model_free(mb);
}

/* ---- a growing text buffer for documents ---- */

typedef struct buf {
    char s[32768];
    size_t n;
} buf;

static void put(buf *b, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static void put(buf *b, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(b->s + b->n, sizeof b->s - b->n, fmt, ap);
    va_end(ap);
    cr_assert(k >= 0 && (size_t)k < sizeof b->s - b->n, "test buffer too small");
    b->n += (size_t)k;
}

/* ---- the two-link planar arm ---- */

static const char two_link_urdf[] =
    "<?xml version=\"1.0\"?>\n"
    "<robot name=\"two_link\">\n"
    "  <link name=\"base\"/>\n"
    "  <link name=\"upper\">\n"
    "    <inertial><origin xyz=\"0.5 0 0\"/><mass value=\"1\"/>\n"
    "      <inertia ixx=\"1e-4\" iyy=\"0.0833333333333333\" izz=\"0.0833333333333333\"/>\n"
    "    </inertial>\n"
    "  </link>\n"
    "  <link name=\"fore\">\n"
    "    <inertial><origin xyz=\"0.5 0 0\"/><mass value=\"1\"/>\n"
    "      <inertia ixx=\"1e-4\" iyy=\"0.0833333333333333\" izz=\"0.0833333333333333\"/>\n"
    "    </inertial>\n"
    "  </link>\n"
    "  <joint name=\"shoulder\" type=\"continuous\">\n"
    "    <parent link=\"base\"/><child link=\"upper\"/><axis xyz=\"0 0 1\"/>\n"
    "    <dynamics damping=\"0.05\" friction=\"0.01\"/>\n"
    "  </joint>\n"
    "  <joint name=\"elbow\" type=\"revolute\">\n"
    "    <parent link=\"upper\"/><child link=\"fore\"/><origin xyz=\"1 0 0\"/>\n"
    "    <axis xyz=\"0 0 1\"/><limit lower=\"-2.5\" upper=\"2.5\" effort=\"20\" velocity=\"3\"/>\n"
    "  </joint>\n"
    "</robot>\n";

Test(urdf, two_link_arm_matches_jacobian_dynamics_and_closed_form)
{
    static const double I[9] = {1e-4, 0, 0, 0, 0.0833333333333333, 0, 0, 0, 0.0833333333333333};
    tjoint J[2];
    for (int i = 0; i < 2; i++) {
        J[i] = (tjoint){.type = T_REV,
                        .A = xf_rpy(i, 0, 0, 0, 0, 0),
                        .B = xf_id(),
                        .axis = {0, 0, 1},
                        .mass = 1,
                        .com = {0.5, 0, 0}};
        memcpy(J[i].I, I, sizeof I);
    }
    char *doc = urdf_job(two_link_urdf);
    job *j = parse_ok(doc);
    cr_assert_eq(j->spec.chain.nbodies, 2);
    compare(j, J, 2);

    /* the closed form (Spong 7.3): M11 = m lc^2 + m (l^2 + lc^2 + 2 l lc c2) + 2 Izz,
       M12 = m (lc^2 + l lc c2) + Izz, M22 = m lc^2 + Izz */
    ctc_model *m = NULL;
    char msg[256];
    cr_assert_eq(ctc_model_build(&j->spec.chain, &m, msg, sizeof msg), CTC_OK);
    ctc_oracle *o = ctc_oracle_new(m);
    double q[2] = {0.3, 1.1}, M[4], izz = 0.0833333333333333, c2 = cos(q[1]);
    ctc_oracle_mass_matrix(m, o, q, M);
    cr_assert_float_eq(M[0], 0.25 + (1 + 0.25 + c2) + 2 * izz, 1e-13);
    cr_assert_float_eq(M[1], 0.25 + 0.5 * c2 + izz, 1e-13);
    cr_assert_float_eq(M[3], 0.25 + izz, 1e-13);
    ctc_oracle_free(o);
    ctc_model_free(m);

    /* the joint's limit and dynamics are kept in the normalised job; gravity is z-up */
    const cJSON *scene = cJSON_GetObjectItemCaseSensitive(j->normalised, "scene");
    const cJSON *bodies = cJSON_GetObjectItemCaseSensitive(scene, "bodies");
    const cJSON *j0 = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(bodies, 0), "joint");
    const cJSON *j1 = cJSON_GetObjectItemCaseSensitive(cJSON_GetArrayItem(bodies, 1), "joint");
    char *d0 = cJSON_PrintUnformatted(cJSON_GetObjectItemCaseSensitive(j0, "dynamics"));
    char *l1 = cJSON_PrintUnformatted(cJSON_GetObjectItemCaseSensitive(j1, "limit"));
    cr_assert_str_eq(d0, "{\"damping\":0.05,\"friction\":0.01}");
    cr_assert_str_eq(l1, "{\"lower\":-2.5,\"upper\":2.5,\"effort\":20,\"velocity\":3}");
    cr_assert_null(cJSON_GetObjectItemCaseSensitive(scene, "urdf"));
    cr_assert_eq(j->spec.chain.gravity[2], -9.81);
    cr_assert_eq(j->spec.chain.gravity[1], 0);
    free(d0);
    free(l1);
    job_free(j);
    free(doc);
}

/* ---- the UR5: its DH table, and a URDF written from it ---- */

/* Universal Robots' UR5 DH parameters, masses and centres of mass (in the DH frames) */
static const double ur5_a[6] = {0, -0.425, -0.39225, 0, 0, 0};
static const double ur5_d[6] = {0.089159, 0, 0, 0.10915, 0.09465, 0.0823};
static const double ur5_alpha[6] = {1.57079632679489662,  0, 0, 1.57079632679489662,
                                    -1.57079632679489662, 0};
static const double ur5_mass[6] = {3.7, 8.393, 2.33, 1.219, 1.219, 0.1879};
static const double ur5_com[6][3] = {{0, -0.02561, 0.00193}, {0.2125, 0, 0.11336},
                                     {0.15, 0, 0.0265},      {0, -0.0018, 0.01634},
                                     {0, 0.0018, 0.01634},   {0, 0, -0.001159}};
/* ur_description's cylinder inertias (Modern Robotics' G1..G6), principal, kg m^2 */
static const double ur5_inertia[6][3] = {
    {0.010267495893, 0.010267495893, 0.00666},  {0.22689067591, 0.22689067591, 0.0151074},
    {0.049443313556, 0.049443313556, 0.004095}, {0.111172755531, 0.111172755531, 0.21942},
    {0.111172755531, 0.111172755531, 0.21942},  {0.0171364731454, 0.0171364731454, 0.033822}};

static void ur5_oracle(tjoint *J)
{
    for (int i = 0; i < 6; i++) {
        J[i] = (tjoint){.type = T_REV,
                        .A = xf_id(),
                        .B = dh_standard(ur5_a[i], ur5_alpha[i], ur5_d[i], 0),
                        .axis = {0, 0, 1},
                        .mass = ur5_mass[i]};
        memcpy(J[i].com, ur5_com[i], sizeof J[i].com);
        for (int k = 0; k < 3; k++) J[i].I[4 * k] = ur5_inertia[i][k];
    }
}

static void ur5_dh_scene(buf *b)
{
    put(b, "{\"dh\": {\"convention\": \"standard\", \"rows\": [");
    for (int i = 0; i < 6; i++) {
        put(b,
            "%s{\"name\": \"ur5_%d\", \"a\": %.17g, \"alpha\": %.17g, \"d\": %.17g, \"mass\": "
            "%.17g, \"com\": [%.17g, %.17g, %.17g], \"inertia\": [%.17g, %.17g, %.17g]}",
            i ? ", " : "", i + 1, ur5_a[i], ur5_alpha[i], ur5_d[i], ur5_mass[i], ur5_com[i][0],
            ur5_com[i][1], ur5_com[i][2], ur5_inertia[i][0], ur5_inertia[i][1], ur5_inertia[i][2]);
    }
    put(b, "]}}");
}

/* The URDF of the same arm: link i's frame is DH frame i-1 turned by q_i, so joint i+1's origin
 * is B_i = Rz(0) Tz(d_i) Tx(a_i) Rx(alpha_i) (xyz (a_i, 0, d_i), rpy (alpha_i, 0, 0)) and link
 * i's inertial origin is B_i applied to the centre of mass, with B_i's rpy. */
static void ur5_urdf(buf *b)
{
    put(b, "<robot name=\"ur5\">\n  <link name=\"base_link\"/>\n");
    for (int i = 0; i < 6; i++) {
        xf B = dh_standard(ur5_a[i], ur5_alpha[i], ur5_d[i], 0);
        double c[3];
        test_m3_mulv(c, B.R, ur5_com[i]);
        for (int k = 0; k < 3; k++) c[k] += B.p[k];
        put(b,
            "  <link name=\"link%d\"><inertial><origin xyz=\"%.17g %.17g %.17g\" rpy=\"%.17g 0 "
            "0\"/><mass value=\"%.17g\"/><inertia ixx=\"%.17g\" iyy=\"%.17g\" izz=\"%.17g\" "
            "ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>\n",
            i + 1, c[0], c[1], c[2], ur5_alpha[i], ur5_mass[i], ur5_inertia[i][0],
            ur5_inertia[i][1], ur5_inertia[i][2]);
        char parent[16] = "base_link";
        if (i > 0) snprintf(parent, sizeof parent, "link%d", i);
        put(b, "  <joint name=\"joint%d\" type=\"revolute\"><parent link=\"%s\"/>", i + 1, parent);
        put(b, "<child link=\"link%d\"/><axis xyz=\"0 0 1\"/>", i + 1);
        if (i > 0) {
            put(b, "<origin xyz=\"%.17g 0 %.17g\" rpy=\"%.17g 0 0\"/>", ur5_a[i - 1], ur5_d[i - 1],
                ur5_alpha[i - 1]);
        }
        put(b, "</joint>\n");
    }
    put(b, "</robot>\n");
}

Test(urdf, ur5_dh_table_matches_jacobian_dynamics)
{
    tjoint J[6];
    ur5_oracle(J);
    buf b = {.n = 0};
    ur5_dh_scene(&b);
    char *doc = job_text(b.s);
    job *j = parse_ok(doc);
    cr_assert_eq(j->spec.chain.nbodies, 6);
    compare(j, J, 6);
    job_free(j);
    free(doc);
}

Test(urdf, ur5_urdf_matches_jacobian_dynamics_and_its_dh_table)
{
    tjoint J[6];
    ur5_oracle(J);
    buf u = {.n = 0}, d = {.n = 0};
    ur5_urdf(&u);
    ur5_dh_scene(&d);
    char *doc = urdf_job(u.s), *doc_dh = job_text(d.s);
    job *j = parse_ok(doc), *jd = parse_ok(doc_dh);
    compare(j, J, 6);
    compare_jobs(j, jd);
    job_free(j);
    job_free(jd);
    free(doc);
    free(doc_dh);
}

/* ---- a modified (Craig) DH table with offsets and a prismatic joint, and its URDF ---- */

/* a Stanford-arm-like table in Craig's convention: row i holds a_(i-1), alpha_(i-1), d_i,
 * theta_i (the offset) */
static const double md_a[5] = {0, 0, 0.05, 0.1, 0};
static const double md_alpha[5] = {0, -1.57079632679489662, 1.57079632679489662, 0.3,
                                   -1.57079632679489662};
static const double md_d[5] = {0.4, 0.15, 0.5, 0.02, 0.2};
static const double md_theta[5] = {0.2, -0.4, 0, 1.0, 0.5};
static const int md_prismatic[5] = {0, 0, 1, 0, 0};
static const double md_mass[5] = {9.29, 5.01, 4.25, 1.08, 0.63};
static const double md_com[5][3] = {
    {0, 0.0175, -0.11}, {0, -0.105, 0}, {0, 0, -0.25}, {0.01, 0.09, -0.05}, {0, 0.05, 0.003}};
static const double md_inertia[5][9] = {{0.276, 0, 0, 0, 0.255, 0, 0, 0, 0.071},
                                        {0.108, 0.001, 0, 0.001, 0.018, 0.002, 0, 0.002, 0.1},
                                        {2.51, 0, 0, 0, 2.51, 0, 0, 0, 0.006},
                                        {0.002, 0, 0, 0, 0.001, 0, 0, 0, 0.001},
                                        {0.003, 0, 0.0005, 0, 0.0028, 0, 0.0005, 0, 0.0012}};

Test(urdf, modified_dh_with_offsets_and_a_prismatic_joint_matches_jacobian_dynamics)
{
    tjoint J[5];
    buf b = {.n = 0};
    put(&b, "{\"dh\": {\"convention\": \"modified\", \"rows\": [");
    for (int i = 0; i < 5; i++) {
        xf rx = xf_rpy(md_a[i], 0, 0, md_alpha[i], 0, 0);
        xf B = xf_rpy(0, 0, md_d[i], 0, 0, md_theta[i]); /* Rz(theta) Tz(d) */
        J[i] = (tjoint){.type = md_prismatic[i] ? T_PRI : T_REV,
                        .A = rx,
                        .B = B,
                        .axis = {0, 0, 1},
                        .mass = md_mass[i]};
        memcpy(J[i].com, md_com[i], sizeof J[i].com);
        memcpy(J[i].I, md_inertia[i], sizeof J[i].I);
        put(&b,
            "%s{\"type\": \"%s\", \"a\": %.17g, \"alpha\": %.17g, \"d\": %.17g, \"theta\": "
            "%.17g, \"mass\": %.17g, \"com\": [%.17g, %.17g, %.17g], \"inertia\": [[%.17g, "
            "%.17g, %.17g], [%.17g, %.17g, %.17g], [%.17g, %.17g, %.17g]]}",
            i ? ", " : "", md_prismatic[i] ? "prismatic" : "revolute", md_a[i], md_alpha[i],
            md_d[i], md_theta[i], md_mass[i], md_com[i][0], md_com[i][1], md_com[i][2],
            md_inertia[i][0], md_inertia[i][1], md_inertia[i][2], md_inertia[i][3],
            md_inertia[i][4], md_inertia[i][5], md_inertia[i][6], md_inertia[i][7],
            md_inertia[i][8]);
    }
    put(&b, "], \"gravity_unused\": 0}}");
    /* an unknown key is refused with its path */
    char *bad = job_text(b.s);
    job *j = NULL;
    job_error err;
    cr_assert_eq(job_parse(bad, strlen(bad), &j, &err), -1);
    cr_assert_str_eq(err.field, "scene.dh.gravity_unused");
    cr_assert_str_eq(err.message, "unknown key \"gravity_unused\"");
    free(bad);

    b.n -= strlen(", \"gravity_unused\": 0}}");
    put(&b, "}, \"gravity\": [0.5, -2, -9.7]}");
    char *doc = job_text(b.s);
    j = parse_ok(doc);
    cr_assert_eq(j->spec.chain.gravity[0], 0.5);
    compare(j, J, 5);
    job_free(j);
    free(doc);
}

/* ---- rpy on every axis, fixed joints mid-chain, a massless link merged ---- */

/* the links: name, inertial (xyz rpy mass ixx iyy izz ixy ixz iyz, or none), and the joint from
 * the previous link: type, xyz rpy, axis */
typedef struct tlink {
    const char *name;
    int inertial;
    double ixyz[3], irpy[3], mass, in[6];
    int type;
    double xyz[3], rpy[3], axis[3];
} tlink;

static const tlink frames_links[] = {
    {"base", 0, {0}, {0}, 0, {0}, T_FIXED, {0}, {0}, {0}},
    {"l1",
     1,
     {0.01, 0.02, 0.15},
     {0.3, -0.2, 0.7},
     2.5,
     {0.02, 0.03, 0.015, 0.001, -0.002, 0.0005},
     T_REV,
     {0.1, -0.05, 0.2},
     {0.4, 0.5, -0.6},
     {0.2, 0.3, 1}},
    {"l2",
     1,
     {0.2, 0, 0.01},
     {-0.5, 0.25, 1.1},
     1.7,
     {0.004, 0.05, 0.05, 0, 0.001, 0},
     T_REV,
     {0, 0.12, 0.3},
     {-0.8, 0.3, 0.2},
     {0, 1, 0}},
    /* a sensor plate fixed mid-chain, with mass, rotated on every axis */
    {"plate",
     1,
     {0.03, -0.01, 0.02},
     {0.1, 0.2, 0.3},
     0.4,
     {0.001, 0.002, 0.0025, 0, 0, 0.0001},
     T_FIXED,
     {0.35, 0.02, -0.01},
     {1.2, -0.7, 0.4},
     {1, 0, 0}},
    /* a massless frame fixed to it */
    {"frame", 0, {0}, {0}, 0, {0}, T_FIXED, {0, 0, 0.05}, {0, 0.9, 0}, {1, 0, 0}},
    {"slide",
     1,
     {0, 0, 0.1},
     {0.2, 0, -0.3},
     0.9,
     {0.003, 0.003, 0.001, 0, 0, 0},
     T_PRI,
     {0.05, 0, 0.1},
     {0.6, 0.1, -1.3},
     {1, -1, 0.5}},
    /* a massless link on a moving joint, carried by a massive link fixed to it */
    {"wrist", 0, {0}, {0}, 0, {0}, T_REV, {0, 0.1, 0.2}, {-0.3, 1.4, 0.2}, {0, 0, 1}},
    {"tool",
     1,
     {0.02, 0.01, 0.06},
     {0.5, 0.5, 0.5},
     0.3,
     {0.0004, 0.0005, 0.0002, 0, 0, 0},
     T_FIXED,
     {0, 0, 0.04},
     {0.1, -0.2, 0.3},
     {1, 0, 0}},
};
#define NFRAMES ((int)(sizeof frames_links / sizeof frames_links[0]))

/* the links L[0..n-1] as a URDF document, the joints first, then the links in reverse order
 * (reversed = 1) or in order; link i hangs from link par[i] (par NULL: i - 1). The importer
 * orders a link's children as their <link> elements come in the document (urdf.c), so a tree's
 * bodies follow L's order only when its links are written in order. */
static void frames_urdf_tree(buf *b, const char *robot, const tlink *L, const int *par, int n,
                             int reversed)
{
    static const char *const types[] = {"revolute", "prismatic", "fixed"};
    put(b, "<robot name=\"%s\">\n", robot);
    for (int i = 1; i < n; i++) {
        const tlink *l = &L[i];
        put(b,
            "  <joint name=\"j_%s\" type=\"%s\"><parent link=\"%s\"/><child link=\"%s\"/>"
            "<origin xyz=\"%.17g %.17g %.17g\" rpy=\"%.17g %.17g %.17g\"/>"
            "<axis xyz=\"%.17g %.17g %.17g\"/></joint>\n",
            l->name, types[l->type], L[par == NULL ? i - 1 : par[i]].name, l->name, l->xyz[0],
            l->xyz[1], l->xyz[2], l->rpy[0], l->rpy[1], l->rpy[2], l->axis[0], l->axis[1],
            l->axis[2]);
    }
    for (int k = 0; k < n; k++) {
        const tlink *l = &L[reversed ? n - 1 - k : k];
        if (!l->inertial) {
            put(b, "  <link name=\"%s\"/>\n", l->name);
            continue;
        }
        put(b,
            "  <link name=\"%s\"><inertial><origin xyz=\"%.17g %.17g %.17g\" rpy=\"%.17g %.17g "
            "%.17g\"/><mass value=\"%.17g\"/><inertia ixx=\"%.17g\" iyy=\"%.17g\" izz=\"%.17g\" "
            "ixy=\"%.17g\" ixz=\"%.17g\" iyz=\"%.17g\"/></inertial></link>\n",
            l->name, l->ixyz[0], l->ixyz[1], l->ixyz[2], l->irpy[0], l->irpy[1], l->irpy[2],
            l->mass, l->in[0], l->in[1], l->in[2], l->in[3], l->in[4], l->in[5]);
    }
    put(b, "</robot>\n");
}

/* a chain's document, its links in reverse: the document's order must not matter */
static void frames_urdf(buf *b, const char *robot, const tlink *L, int n)
{
    frames_urdf_tree(b, robot, L, NULL, n, 1);
}

/* the oracle's chain from the links: joint origin as A, the inertial frame's data rotated into
 * the link frame */
static int frames_oracle(const tlink *L, int n, tjoint *J)
{
    for (int i = 1; i < n; i++) {
        const tlink *l = &L[i];
        tjoint *t = &J[i - 1];
        *t = (tjoint){.type = l->type, .B = xf_id()};
        t->A = xf_rpy(l->xyz[0], l->xyz[1], l->xyz[2], l->rpy[0], l->rpy[1], l->rpy[2]);
        memcpy(t->axis, l->axis, sizeof t->axis);
        if (!l->inertial) continue;
        xf in = xf_rpy(l->ixyz[0], l->ixyz[1], l->ixyz[2], l->irpy[0], l->irpy[1], l->irpy[2]);
        double I[9] = {l->in[0], l->in[3], l->in[4], l->in[3], l->in[1],
                       l->in[5], l->in[4], l->in[5], l->in[2]};
        double RI[9], Rt[9];
        for (int a = 0; a < 3; a++)
            for (int c = 0; c < 3; c++) Rt[3 * a + c] = in.R[3 * c + a];
        test_m3_mul(RI, in.R, I);
        test_m3_mul(t->I, RI, Rt);
        t->mass = l->mass;
        memcpy(t->com, in.p, sizeof t->com);
    }
    return n - 1;
}

Test(urdf, rpy_on_every_axis_fixed_joints_and_a_massless_link_match_jacobian_dynamics)
{
    tjoint J[NFRAMES];
    buf b = {.n = 0};
    frames_urdf(&b, "frames", frames_links, NFRAMES);
    int n = frames_oracle(frames_links, NFRAMES, J);
    char *doc = urdf_job(b.s);
    job *j = parse_ok(doc);
    /* l1, l2 (+ plate + frame), slide, wrist (+ tool) */
    cr_assert_eq(j->spec.chain.nbodies, 4);
    double worst = compare(j, J, n);
    cr_log_info("frames: largest difference %.3g", worst);
    job_free(j);
    free(doc);
}

/* ---- the Panda: a tree (two fingers on the hand) ---- */

/* franka_description's franka_arm and franka_hand xacro files: joint origins (xyz, rpy) and axes;
 * the arm links' inertials identified by Gaz et al. (RA-L 2019) and the hand's, as
 * franka_description's robots/common/inertial.yaml lists them (ixx iyy izz ixy ixz iyz) */
#define PANDA_H 1.57079632679489662
static const tlink panda_links[] = {
    {"panda_link0", 0, {0}, {0}, 0, {0}, T_FIXED, {0}, {0}, {0}},
    {"panda_link1",
     1,
     {0.003875, 0.002081, -0.04762},
     {0},
     4.970684,
     {0.70337, 0.70661, 0.009117, -0.000139, 0.006772, 0.019169},
     T_REV,
     {0, 0, 0.333},
     {0, 0, 0},
     {0, 0, 1}},
    {"panda_link2",
     1,
     {-0.003141, -0.02872, 0.003495},
     {0},
     0.646926,
     {0.007962, 0.02811, 0.025995, -0.003925, 0.010254, 0.000704},
     T_REV,
     {0, 0, 0},
     {-PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link3",
     1,
     {0.027518, 0.039252, -0.066502},
     {0},
     3.228604,
     {0.037242, 0.036155, 0.01083, -0.004761, -0.011396, -0.012805},
     T_REV,
     {0, -0.316, 0},
     {PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link4",
     1,
     {-0.05317, 0.104419, 0.027454},
     {0},
     3.587895,
     {0.025853, 0.019552, 0.028323, 0.007796, -0.001332, 0.008641},
     T_REV,
     {0.0825, 0, 0},
     {PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link5",
     1,
     {-0.011953, 0.041065, -0.038437},
     {0},
     1.225946,
     {0.035549, 0.029474, 0.008627, -0.002117, -0.004037, 0.000229},
     T_REV,
     {-0.0825, 0.384, 0},
     {-PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link6",
     1,
     {0.060149, -0.014117, -0.010517},
     {0},
     1.666555,
     {0.001964, 0.004354, 0.005433, 0.000109, -0.001158, 0.000341},
     T_REV,
     {0, 0, 0},
     {PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link7",
     1,
     {0.010517, -0.004252, 0.061597},
     {0},
     0.735522,
     {0.012516, 0.010027, 0.004815, -0.000428, -0.001196, -0.000741},
     T_REV,
     {0.088, 0, 0},
     {PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link8", 0, {0}, {0}, 0, {0}, T_FIXED, {0, 0, 0.107}, {0, 0, 0}, {1, 0, 0}},
    {"panda_hand",
     1,
     {-0.01, 0, 0.03},
     {0},
     0.73,
     {0.001, 0.0025, 0.0017, 0, 0, 0},
     T_FIXED,
     {0, 0, 0},
     {0, 0, -0.785398163397448},
     {1, 0, 0}},
};
#define NPANDA ((int)(sizeof panda_links / sizeof panda_links[0]))

/* franka_hand.xacro's fingers: both at 0.0584 m along the hand's z, sliding along +y (left) and
 * -y (right); inertial.yaml's finger: 0.015 kg at the joint frame's origin */
#define FINGER_Z 0.0584
#define FINGER_MASS 0.015
#define FINGER_IXX 2.375e-6
#define FINGER_IZZ 7.5e-7

static void panda_urdf(buf *b, const char *finger_type)
{
    frames_urdf(b, "panda", panda_links, NPANDA);
    b->n -= strlen("</robot>\n");
    for (int f = 0; f < 2; f++) {
        put(b,
            "  <link name=\"panda_%sfinger\"><inertial><origin xyz=\"0 0 0\"/>"
            "<mass value=\"%.17g\"/><inertia ixx=\"%.17g\" iyy=\"%.17g\" izz=\"%.17g\"/>"
            "</inertial></link>\n"
            "  <joint name=\"panda_finger_joint%d\" type=\"%s\"><parent link=\"panda_hand\"/>"
            "<child link=\"panda_%sfinger\"/><origin xyz=\"0 0 %.17g\" rpy=\"0 0 0\"/>"
            "<axis xyz=\"0 %s1 0\"/><limit effort=\"100\" lower=\"0.0\" upper=\"0.04\" "
            "velocity=\"0.2\"/><dynamics damping=\"0.3\"/></joint>\n",
            f ? "right" : "left", FINGER_MASS, FINGER_IXX, FINGER_IXX, FINGER_IZZ, f + 1,
            finger_type, f ? "right" : "left", FINGER_Z, f ? "-" : "");
    }
    put(b, "</robot>\n");
}

/* the oracle's Panda: the arm's chain (link 1 .. the hand, J[0..NPANDA-2]) and the two fingers,
 * each a joint of type finger_type hanging from the hand; the joints' parents into par. Returns
 * the number of joints. */
static int panda_oracle(int finger_type, tjoint *J, int *par)
{
    int n = frames_oracle(panda_links, NPANDA, J);
    for (int i = 0; i < n; i++) par[i] = i - 1;
    int hand = n - 1;
    for (int f = 0; f < 2; f++) {
        par[n] = hand;
        J[n++] = (tjoint){.type = finger_type,
                          .A = xf_rpy(0, 0, FINGER_Z, 0, 0, 0),
                          .B = xf_id(),
                          .axis = {0, f ? -1 : 1, 0},
                          .mass = FINGER_MASS,
                          .I = {FINGER_IXX, 0, 0, 0, FINGER_IXX, 0, 0, 0, FINGER_IZZ}};
    }
    return n;
}

Test(urdf, panda_with_fingers_converts_to_a_tree_of_nine_bodies)
{
    buf b = {.n = 0};
    panda_urdf(&b, "prismatic");
    char name[64], msg[512];
    cJSON *bodies = urdf_to_bodies(b.s, b.n, name, sizeof name, msg, sizeof msg);
    cr_assert_not_null(bodies, "%s", msg);
    cr_assert_str_eq(name, "panda");
    static const int parents[9] = {-1, 0, 1, 2, 3, 4, 5, 6, 6};
    static const char *const names[9] = {"panda_link1", "panda_link2",      "panda_link3",
                                         "panda_link4", "panda_link5",      "panda_link6",
                                         "panda_link7", "panda_leftfinger", "panda_rightfinger"};
    cr_assert_eq(cJSON_GetArraySize(bodies), 9);
    int k = 0;
    for (const cJSON *o = bodies->child; o != NULL; o = o->next, k++) {
        cr_assert_str_eq(cJSON_GetObjectItemCaseSensitive(o, "name")->valuestring, names[k]);
        cr_assert_eq(cJSON_GetObjectItemCaseSensitive(o, "parent")->valuedouble, parents[k]);
    }
    /* the fingers slide along the hand's +y and -y: in the world at q = 0, link 7's rotation
       (the joints' rolls) times the hand's Rz(-pi/4) applied to (0, 1, 0) */
    const cJSON *left = cJSON_GetArrayItem(bodies, 7), *right = cJSON_GetArrayItem(bodies, 8);
    const cJSON *ja = cJSON_GetObjectItemCaseSensitive(left, "joint");
    const cJSON *jb = cJSON_GetObjectItemCaseSensitive(right, "joint");
    const cJSON *axis = cJSON_GetObjectItemCaseSensitive(ja, "axis");
    const cJSON *axis_r = cJSON_GetObjectItemCaseSensitive(jb, "axis");
    double expect[3], R7[9], Rz[9], t[9];
    xf acc = xf_id();
    for (int i = 1; i <= 7; i++) acc = xf_mul(acc, xf_rpy(0, 0, 0, panda_links[i].rpy[0], 0, 0));
    memcpy(R7, acc.R, sizeof R7);
    xf hand = xf_rpy(0, 0, 0, 0, 0, -0.785398163397448);
    memcpy(Rz, hand.R, sizeof Rz);
    test_m3_mul(t, R7, Rz);
    double y[3] = {0, 1, 0};
    test_m3_mulv(expect, t, y);
    for (int i = 0; i < 3; i++) {
        cr_assert_float_eq(cJSON_GetArrayItem(axis, i)->valuedouble, expect[i], 1e-15);
        cr_assert_float_eq(cJSON_GetArrayItem(axis_r, i)->valuedouble, -expect[i], 1e-15);
    }
    const cJSON *limit = cJSON_GetObjectItemCaseSensitive(ja, "limit");
    cr_assert_eq(cJSON_GetObjectItemCaseSensitive(limit, "upper")->valuedouble, 0.04);
    cJSON_Delete(bodies);

    /* a job takes the tree: both fingers hang from the hand (link 7), as the URDF says */
    char *doc = urdf_job(b.s);
    job *j = NULL;
    job_error err;
    cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), 0, "%s: %s", err.field, err.message);
    cr_assert_eq(j->spec.chain.nbodies, 9);
    for (k = 0; k < 9; k++) cr_assert_eq(j->spec.chain.parent[k], parents[k], "body %d", k);
    job_free(j);
    free(doc);
}

Test(urdf, panda_with_prismatic_fingers_matches_jacobian_dynamics_and_gdca)
{
    buf b = {.n = 0};
    panda_urdf(&b, "prismatic");
    tjoint J[NPANDA + 2];
    int par[NPANDA + 2];
    int n = panda_oracle(T_PRI, J, par);
    char *doc = urdf_job(b.s);
    job *j = parse_ok(doc);
    cr_assert_eq(j->spec.chain.nbodies, 9);
    double acc = 0, worst = compare_tree(j, J, par, n, &acc);
    cr_log_info("panda with fingers: M, c, G to %.3g; GDCA qacc to %.3g relative", worst, acc);
    job_free(j);
    free(doc);
}

Test(urdf, panda_arm_with_fixed_fingers_matches_jacobian_dynamics)
{
    buf b = {.n = 0};
    panda_urdf(&b, "fixed");
    tjoint J[NPANDA + 2];
    int par[NPANDA + 2];
    int n = panda_oracle(T_FIXED, J, par);
    char *doc = urdf_job(b.s);
    job *j = parse_ok(doc);
    cr_assert_eq(j->spec.chain.nbodies, 7);
    compare_tree(j, J, par, n, NULL);
    job_free(j);
    free(doc);
}

/* Franka's modified (Craig) DH table of the Panda (frankaemika.github.io, "Denavit-Hartenberg
 * parameters"): row i holds a_(i-1), alpha_(i-1) and d_i */
static const double panda_dh_a[7] = {0, 0, 0, 0.0825, -0.0825, 0, 0.088};
static const double panda_dh_d[7] = {0.333, 0, 0.316, 0, 0.384, 0, 0};
static const double panda_dh_alpha[7] = {0, -PANDA_H, PANDA_H, PANDA_H, -PANDA_H, PANDA_H, PANDA_H};

Test(urdf, panda_arm_urdf_and_frankas_modified_dh_table_give_the_same_dynamics)
{
    /* the arm alone (links 0..7): the URDF's link frames are the DH frames, so each row takes
       the link's inertial as it is */
    buf b = {.n = 0};
    frames_urdf(&b, "panda_arm", panda_links, 8);
    char *doc_urdf = urdf_job(b.s);
    b.n = 0;
    put(&b, "{\"dh\": {\"convention\": \"modified\", \"rows\": [");
    for (int i = 0; i < 7; i++) {
        const tlink *l = &panda_links[i + 1];
        put(&b,
            "%s{\"a\": %.17g, \"alpha\": %.17g, \"d\": %.17g, \"mass\": %.17g, \"com\": "
            "[%.17g, %.17g, %.17g], \"inertia\": [[%.17g, %.17g, %.17g], [%.17g, %.17g, %.17g], "
            "[%.17g, %.17g, %.17g]]}",
            i ? ", " : "", panda_dh_a[i], panda_dh_alpha[i], panda_dh_d[i], l->mass, l->ixyz[0],
            l->ixyz[1], l->ixyz[2], l->in[0], l->in[3], l->in[4], l->in[3], l->in[1], l->in[5],
            l->in[4], l->in[5], l->in[2]);
    }
    put(&b, "]}}");
    char *doc_dh = job_text(b.s);
    job *ju = parse_ok(doc_urdf), *jd = parse_ok(doc_dh);
    cr_assert_eq(jd->spec.chain.nbodies, 7);
    compare_jobs(ju, jd);
    tjoint J[8];
    int n = frames_oracle(panda_links, 8, J);
    compare(jd, J, n);
    job_free(ju);
    job_free(jd);
    free(doc_urdf);
    free(doc_dh);
}

/* ---- a two-finger gripper on a three-joint arm, written for this test ---- */

/* the arm's links (rpy on every axis, off-axis centres of mass, products of inertia), a palm
 * fixed to the forearm, and two fingers on the palm: the left one two revolute joints, the right
 * one a prismatic joint and a revolute one. Listed breadth first and written in this order, the
 * order of the converted bodies (urdf.c), so that the oracle's coordinates are ctcsim's. */
static const tlink gripper_links[] = {
    {"base", 0, {0}, {0}, 0, {0}, T_FIXED, {0}, {0}, {0}},
    {"shoulder",
     1,
     {0.01, 0.02, 0.1},
     {0.1, 0, 0},
     2.0,
     {0.02, 0.021, 0.008, 0.001, 0.0005, 0},
     T_REV,
     {0, 0, 0.2},
     {0, 0, 0.3},
     {0, 0, 1}},
    {"upper",
     1,
     {0.15, 0, 0.02},
     {0, 0.3, 0},
     1.5,
     {0.003, 0.012, 0.011, 0, 0, 0.0004},
     T_REV,
     {0, 0.05, 0.15},
     {-1.2, 0.2, 0},
     {0, 0, 1}},
    {"fore",
     1,
     {0.12, 0.01, 0},
     {0},
     1.0,
     {0.002, 0.006, 0.006, 0, 0.0002, 0},
     T_REV,
     {0.3, 0, 0.02},
     {0, 0, 0.5},
     {0, 1, 0.2}},
    {"palm",
     1,
     {0.02, 0, 0.005},
     {0.2, 0, 0},
     0.3,
     {0.0004, 0.0003, 0.0003, 0, 0, 0},
     T_FIXED,
     {0.25, 0, 0},
     {0.4, 0.1, -0.2},
     {1, 0, 0}},
    {"left_base",
     1,
     {0.03, 0, 0.005},
     {0},
     0.05,
     {1e-5, 4e-5, 4e-5, 0, 0, 0},
     T_REV,
     {0.04, 0.03, 0},
     {0, 0, 0.3},
     {0, 0, 1}},
    {"right_base",
     1,
     {0.03, 0, -0.004},
     {0},
     0.05,
     {1e-5, 4e-5, 4e-5, 0, 0, 0},
     T_PRI,
     {0.04, -0.03, 0},
     {0, 0, -0.3},
     {0, -1, 0}},
    {"left_tip",
     1,
     {0.02, 0.003, 0},
     {0, 0, 0.2},
     0.03,
     {5e-6, 1.5e-5, 1.5e-5, 0, 0, 0},
     T_REV,
     {0.06, 0, 0},
     {0.2, 0, 0},
     {0, 0, 1}},
    {"right_tip",
     1,
     {0.02, -0.003, 0.001},
     {0.1, 0, 0},
     0.03,
     {5e-6, 1.5e-5, 1.5e-5, 0, 0, 0},
     T_REV,
     {0.06, 0, 0},
     {-0.2, 0, 0},
     {0, 0, -1}},
};
#define NGRIPPER ((int)(sizeof gripper_links / sizeof gripper_links[0]))
static const int gripper_parent[NGRIPPER] = {-1, 0, 1, 2, 3, 4, 4, 5, 6};

Test(urdf, gripper_tree_matches_jacobian_dynamics_and_gdca)
{
    buf b = {.n = 0};
    frames_urdf_tree(&b, "gripper", gripper_links, gripper_parent, NGRIPPER, 0);
    tjoint J[NGRIPPER];
    int par[NGRIPPER];
    int n = frames_oracle(gripper_links, NGRIPPER, J);
    /* joint i moves link i + 1 */
    for (int i = 0; i < n; i++) par[i] = gripper_parent[i + 1] - 1;
    char *doc = urdf_job(b.s);
    job *j = parse_ok(doc);
    /* shoulder, upper, fore (+ palm), the fingers' bases, the fingers' tips */
    static const int parents[7] = {-1, 0, 1, 2, 2, 3, 4};
    cr_assert_eq(j->spec.chain.nbodies, 7);
    for (int k = 0; k < 7; k++) cr_assert_eq(j->spec.chain.parent[k], parents[k], "body %d", k);
    double acc = 0, worst = compare_tree(j, J, par, n, &acc);
    cr_log_info("gripper: M, c, G to %.3g; GDCA qacc to %.3g relative", worst, acc);
    job_free(j);
    free(doc);
}

/* ---- malformed documents, each with its exact message ---- */

static void refused(const char *urdf, const char *message)
{
    char msg[512];
    cJSON *bodies = urdf_to_bodies(urdf, strlen(urdf), NULL, 0, msg, sizeof msg);
    cr_assert_null(bodies, "accepted: %s", urdf);
    cr_assert_str_eq(msg, message);
    /* and through the job format, at scene.urdf */
    char *doc = urdf_job(urdf);
    job *j = NULL;
    job_error err;
    cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), -1);
    cr_assert_str_eq(err.field, "scene.urdf");
    cr_assert_str_eq(err.message, message);
    free(doc);
}

#define LINK(n)                                                                                    \
    "<link name=\"" n "\"><inertial><mass value=\"1\"/>"                                           \
    "<inertia ixx=\"0.1\" iyy=\"0.1\" izz=\"0.1\"/></inertial></link>\n"
#define JOINT(n, t, p, c)                                                                          \
    "<joint name=\"" n "\" type=\"" t "\"><parent link=\"" p "\"/>"                                \
    "<child link=\"" c "\"/><axis xyz=\"0 0 1\"/></joint>\n"

Test(urdf, malformed_documents_are_refused_naming_element_and_line)
{
    refused("<robot name=\"r\">\n<link name=\"a\">\n</robot>\n",
            "line 3: not well-formed XML: Opening and ending tag mismatch: link line 2 and robot");
    refused("<robot name=\"r\">\n" LINK("a") "<link name=\"b\"/>\n",
            "line 4: not well-formed XML: Premature end of data in tag robot line 1");
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"><inertial>\n"
            "<mass value=\"-1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\"/></inertial></link>\n"
            "</robot>\n",
            "line 4: <mass> in <link name=\"b\">: value must not be negative (got -1 kg)");
    refused(
        "<robot name=\"r\">\n<link name=\"a\"/>\n" LINK(
            "b") "<joint name=\"j\" type=\"ball\"><parent link=\"a\"/><child link=\"b\"/></joint>\n"
                 "</robot>\n",
        "line 4: <joint name=\"j\">: type \"ball\" is not one of revolute, continuous, "
        "prismatic, fixed");
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n" LINK(
                "b") "<joint name=\"j\" type=\"floating\"><parent link=\"a\"/><child "
                     "link=\"b\"/></joint>\n"
                     "</robot>\n",
            "line 4: <joint name=\"j\">: type \"floating\" is not supported (ctcsim's robots are "
            "fixed to the world and their joints are revolute, continuous, prismatic or fixed)");
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n" LINK(
                "b") "<joint name=\"j\" type=\"planar\"><parent link=\"a\"/><child "
                     "link=\"b\"/></joint>\n"
                     "</robot>\n",
            "line 4: <joint name=\"j\">: type \"planar\" is not supported (ctcsim's robots are "
            "fixed to the world and their joints are revolute, continuous, prismatic or fixed)");
    refused(
        "<robot name=\"r\">\n<link name=\"a\"/>\n" LINK("b") LINK("c") JOINT(
            "j1", "revolute", "a",
            "b") "<joint name=\"j2\" type=\"revolute\"><parent link=\"a\"/><child link=\"c\"/>\n"
                 "  <mimic joint=\"j1\" multiplier=\"2\"/></joint>\n</robot>\n",
        "line 7: <mimic> in <joint name=\"j2\">: mimic joints are not supported (each joint "
        "is its own coordinate)");
    /* a parent/child cycle: a is the root, b and c hang from each other */
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n" LINK("b") LINK("c")
                JOINT("j1", "revolute", "c", "b") JOINT("j2", "revolute", "b", "c") "</robot>\n",
            "line 6: <joint name=\"j2\">: a parent/child cycle: link \"c\" is its own ancestor (a "
            "robot is a tree)");
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n" LINK("b") LINK("c")
                JOINT("j1", "revolute", "a", "b") JOINT("j2", "revolute", "c", "b") "</robot>\n",
            "line 6: <joint name=\"j2\">: link \"b\" has two parents: joint \"j1\" (line 5) is "
            "its parent already");
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n" LINK("b")
                JOINT("j1", "revolute", "a", "bb") "</robot>\n",
            "line 4: <child> in <joint name=\"j1\">: link \"bb\" is not a <link> of the robot");
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n" LINK("b") LINK("c")
                JOINT("j1", "revolute", "a", "b") "</robot>\n",
            "line 4: <link name=\"c\">: a second root: link \"a\" (line 2) has no parent joint "
            "either; a robot is one tree of links fixed to the world");
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"><inertial>"
            "<mass value=\"1\"/></inertial></link>\n</robot>\n",
            "line 3: <inertial> in <link name=\"b\">: <inertia> is required");
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n" LINK(
                "b") "<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\n"
                     "<origin xyz=\"1 2\"/></joint>\n</robot>\n",
            "line 5: <origin> in <joint name=\"j\">: xyz must be 3 finite numbers (got \"1 2\")");
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n" LINK(
                "b") "<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\n"
                     "<axis xyz=\"0 0 0\"/></joint>\n</robot>\n",
            "line 5: <axis> in <joint name=\"j\">: xyz must have non-zero length (got \"0 0 0\")");
    refused("<robot name=\"r\">\n" LINK("a") LINK("a") "</robot>\n",
            "line 3: <link name=\"a\">: a second link named \"a\" (the first is on line 2)");
    refused("<model name=\"r\"/>\n",
            "line 1: <model name=\"r\">: the root element must be <robot>");
    refused("<!DOCTYPE robot [<!ENTITY x \"y\">]>\n<robot name=\"r\"/>\n",
            "a document type declaration (<!DOCTYPE>) is not allowed");
    refused("<robot name=\"r\">\n<link name=\"a\"/>\n" LINK("b")
                JOINT("j1", "fixed", "a", "b") "</robot>\n",
            "no joint moves (every joint is fixed)");
}

Test(urdf, scene_takes_one_of_bodies_urdf_and_dh)
{
    char *doc = job_text("{\"urdf\": \"<robot/>\", \"dh\": {}}");
    job *j = NULL;
    job_error err;
    cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), -1);
    cr_assert_str_eq(err.field, "scene.urdf");
    cr_assert_str_eq(err.message, "not allowed with \"dh\" (give the robot one way)");
    free(doc);
    doc = job_text("{\"urdf\": 3}");
    cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), -1);
    cr_assert_str_eq(err.field, "scene.urdf");
    cr_assert_str_eq(err.message, "must be a string, the URDF document (got a number)");
    free(doc);
    doc = job_text("{\"dh\": {\"convention\": \"craig\", \"rows\": []}}");
    cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), -1);
    cr_assert_str_eq(err.field, "scene.dh.convention");
    free(doc);
    doc = job_text("{\"dh\": {\"convention\": \"standard\", \"rows\": [{\"a\": 0, \"alpha\": 0, "
                   "\"d\": 0, \"mass\": -1, \"com\": [0, 0, 0], \"inertia\": [1, 1, 1]}]}}");
    cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), -1);
    cr_assert_str_eq(err.field, "scene.dh.rows[0].mass");
    cr_assert_str_eq(err.message, "must not be negative (got -1 kg)");
    free(doc);
}

/* ---- the robot presets ---- */

/* Drake's iiwa14_no_collision.urdf, typed in again: the joints' rpy and xyz, the links' inertials
 */
static const tlink iiwa_links[] = {
    {"base", 0, {0}, {0}, 0, {0}, T_FIXED, {0}, {0}, {0}},
    {"iiwa_link_0",
     1,
     {-0.1, 0, 0.07},
     {0},
     5,
     {0.05, 0.06, 0.03, 0, 0, 0},
     T_FIXED,
     {0},
     {0},
     {1, 0, 0}},
    {"iiwa_link_1",
     1,
     {0, -0.03, 0.12},
     {0},
     5.76,
     {0.033, 0.0333, 0.0123, 0, 0, 0},
     T_REV,
     {0, 0, 0.1575},
     {0, 0, 0},
     {0, 0, 1}},
    {"iiwa_link_2",
     1,
     {0.0003, 0.059, 0.042},
     {0},
     6.35,
     {0.0305, 0.0304, 0.011, 0, 0, 0},
     T_REV,
     {0, 0, 0.2025},
     {PANDA_H, 0, 2 * PANDA_H},
     {0, 0, 1}},
    {"iiwa_link_3",
     1,
     {0, 0.03, 0.13},
     {0},
     3.5,
     {0.025, 0.0238, 0.0076, 0, 0, 0},
     T_REV,
     {0, 0.2045, 0},
     {PANDA_H, 0, 2 * PANDA_H},
     {0, 0, 1}},
    {"iiwa_link_4",
     1,
     {0, 0.067, 0.034},
     {0},
     3.5,
     {0.017, 0.0164, 0.006, 0, 0, 0},
     T_REV,
     {0, 0, 0.2155},
     {PANDA_H, 0, 0},
     {0, 0, 1}},
    {"iiwa_link_5",
     1,
     {0.0001, 0.021, 0.076},
     {0},
     3.5,
     {0.01, 0.0087, 0.00449, 0, 0, 0},
     T_REV,
     {0, 0.1845, 0},
     {-PANDA_H, 2 * PANDA_H, 0},
     {0, 0, 1}},
    {"iiwa_link_6",
     1,
     {0, 0.0006, 0.0004},
     {0},
     1.8,
     {0.0049, 0.0047, 0.0036, 0, 0, 0},
     T_REV,
     {0, 0, 0.2155},
     {PANDA_H, 0, 0},
     {0, 0, 1}},
    {"iiwa_link_7",
     1,
     {0, 0, 0.02},
     {0},
     1.2,
     {0.001, 0.001, 0.001, 0, 0, 0},
     T_REV,
     {0, 0.081, 0},
     {-PANDA_H, 2 * PANDA_H, 0},
     {0, 0, 1}},
};
#define NIIWA ((int)(sizeof iiwa_links / sizeof iiwa_links[0]))

/* the preset's parsed job, its run checked: done, with the exact model's error dynamics */
static job *run_preset(const char *name)
{
    const preset *p = presets_find(name);
    cr_assert_not_null(p, "no preset %s", name);
    job_error err;
    cJSON *doc = p->build(NULL, &err);
    cr_assert_not_null(doc, "%s", err.message);
    job *j = NULL;
    cr_assert_eq(job_from_json(doc, &j, &err), 0, "%s: %s", err.field, err.message);
    cJSON_Delete(doc);
    ctc_sim_result *r = NULL;
    char msg[256];
    cr_assert_eq(ctc_sim_run(&j->spec, NULL, &r, msg, sizeof msg), CTC_OK, "%s", msg);
    cr_assert_eq(r->status, CTC_RUN_DONE, "%s: %s", name, r->message);
    /* started on the trajectory with the exact model: the error stays at the integrator's
       tolerance (rtol 1e-8) */
    cr_assert_leq(r->metrics.errdyn_dev, 1e-6, "%s: error-dynamics deviation %g", name,
                  r->metrics.errdyn_dev);
    for (int i = 0; i < r->metrics.nv; i++)
        cr_assert_leq(r->metrics.e_max[i], 1e-6, "%s: |e[%d]| %g", name, i, r->metrics.e_max[i]);
    ctc_sim_result_free(r);
    return j;
}

Test(urdf, ur5_preset_tracks_exactly_and_holds_the_published_dynamics)
{
    tjoint J[6];
    ur5_oracle(J);
    job *j = run_preset("ur5_min_jerk");
    cr_assert_eq(j->spec.chain.nbodies, 6);
    cr_assert_eq(j->spec.chain.gravity[2], -9.81);
    compare(j, J, 6);
    job_free(j);
}

Test(urdf, iiwa14_preset_tracks_exactly_and_holds_the_published_dynamics)
{
    tjoint J[NIIWA];
    int n = frames_oracle(iiwa_links, NIIWA, J);
    job *j = run_preset("iiwa14_min_jerk");
    cr_assert_eq(j->spec.chain.nbodies, 7);
    compare(j, J, n);
    job_free(j);
}

Test(urdf, panda_preset_tracks_exactly_and_holds_the_published_dynamics)
{
    tjoint J[NPANDA + 2];
    int par[NPANDA + 2];
    int n = panda_oracle(T_PRI, J, par);
    job *j = run_preset("panda_min_jerk");
    static const int parents[9] = {-1, 0, 1, 2, 3, 4, 5, 6, 6};
    cr_assert_eq(j->spec.chain.nbodies, 9);
    for (int k = 0; k < 9; k++) cr_assert_eq(j->spec.chain.parent[k], parents[k], "body %d", k);
    compare_tree(j, J, par, n, NULL);
    job_free(j);
}

Test(urdf, two_link_preset_tracks_exactly_and_has_modern_robotics_closed_form)
{
    /* Lynch and Park, Modern Robotics 8.1.1: point masses m1 = m2 = 1 kg at the ends of links
       L1 = L2 = 1 m, g along -y; as standard DH rows (a = L, the mass at frame i's origin) */
    tjoint J[2];
    for (int i = 0; i < 2; i++)
        J[i] = (tjoint){.type = T_REV,
                        .A = xf_id(),
                        .B = dh_standard(1, 0, 0, 0),
                        .axis = {0, 0, 1},
                        .mass = 1};
    job *j = run_preset("two_link_min_jerk");
    cr_assert_eq(j->spec.chain.nbodies, 2);
    compare(j, J, 2);

    /* the book's eqs. 8.9-8.11: M11 = m1 L1^2 + m2 (L1^2 + 2 L1 L2 c2 + L2^2),
       M12 = m2 (L1 L2 c2 + L2^2), M22 = m2 L2^2; c = (-m2 L1 L2 s2 (2 v1 v2 + v2^2),
       m2 L1 L2 v1^2 s2); g = ((m1 + m2) L1 g c1 + m2 g L2 c12, m2 g L2 c12) */
    ctc_model *m = NULL;
    char msg[256];
    cr_assert_eq(ctc_model_build(&j->spec.chain, &m, msg, sizeof msg), CTC_OK, "%s", msg);
    ctc_oracle *o = ctc_oracle_new(m);
    const double g = 9.81, zero[2] = {0, 0};
    for (int k = 1; k < 5; k++) {
        double q[2], v[2], M[4], tv[2], t0[2];
        pose(k, 2, q, v);
        double c1 = cos(q[0]), c2 = cos(q[1]), s2 = sin(q[1]), c12 = cos(q[0] + q[1]);
        const double Mw[4] = {1 + (1 + 2 * c2 + 1), c2 + 1, c2 + 1, 1};
        const double cw[2] = {-s2 * (2 * v[0] * v[1] + v[1] * v[1]), v[0] * v[0] * s2};
        const double gw[2] = {2 * g * c1 + g * c12, g * c12};
        ctc_oracle_mass_matrix(m, o, q, M);
        ctc_oracle_rnea(m, o, q, v, zero, tv);
        ctc_oracle_rnea(m, o, q, zero, zero, t0);
        for (int e = 0; e < 4; e++)
            cr_assert_leq(fabs(M[e] - Mw[e]), DYN_TOL, "pose %d: M[%d] %.17g, want %.17g", k, e,
                          M[e], Mw[e]);
        for (int i = 0; i < 2; i++) {
            cr_assert_leq(fabs(t0[i] - gw[i]), DYN_TOL, "pose %d: g[%d] %.17g, want %.17g", k, i,
                          t0[i], gw[i]);
            cr_assert_leq(fabs(tv[i] - t0[i] - cw[i]), DYN_TOL, "pose %d: c[%d] %.17g, want %.17g",
                          k, i, tv[i] - t0[i], cw[i]);
        }
    }
    ctc_oracle_free(o);
    ctc_model_free(m);
    job_free(j);
}

/* Armstrong, Khatib and Burdick's Puma 560 as Corke's mdl_puma560akb lists it, typed in again:
 * modified DH (a_(i-1), alpha_(i-1), d_i), masses, centres of mass and principal inertias in the
 * link frames */
static const double puma_a[6] = {0, 0, 0.4318, -0.0203, 0, 0};
static const double puma_alpha[6] = {0, -PANDA_H, 0, PANDA_H, -PANDA_H, PANDA_H};
static const double puma_d[6] = {0, 0.2435, -0.0934, 0.4331, 0, 0};
static const double puma_m[6] = {0, 17.4, 4.8, 0.82, 0.34, 0.09};
static const double puma_r[6][3] = {{0, 0, 0},          {0.068, 0.006, -0.016},
                                    {0, -0.070, 0.014}, {0, 0, -0.019},
                                    {0, 0, 0},          {0, 0, 0.032}};
static const double puma_I[6][3] = {{0, 0, 0.35},
                                    {0.13, 0.524, 0.539},
                                    {0.066, 0.0125, 0.066},
                                    {1.8e-3, 1.8e-3, 1.3e-3},
                                    {0.3e-3, 0.3e-3, 0.4e-3},
                                    {0.15e-3, 0.15e-3, 0.04e-3}};

Test(urdf, puma560_preset_tracks_exactly_with_its_massless_first_link)
{
    /* F_i = F_(i-1) Rx(alpha_(i-1)) Tx(a_(i-1)) Rz(q_i) Tz(d_i) */
    tjoint J[6];
    for (int i = 0; i < 6; i++) {
        J[i] = (tjoint){.type = T_REV,
                        .A = xf_rpy(puma_a[i], 0, 0, puma_alpha[i], 0, 0),
                        .B = xf_rpy(0, 0, puma_d[i], 0, 0, 0),
                        .axis = {0, 0, 1},
                        .mass = puma_m[i]};
        memcpy(J[i].com, puma_r[i], sizeof J[i].com);
        for (int k = 0; k < 3; k++) J[i].I[4 * k] = puma_I[i][k];
    }
    job *j = run_preset("puma560_min_jerk");
    cr_assert_eq(j->spec.chain.nbodies, 6);
    cr_assert_eq(j->spec.chain.bodies[0].mass, 0);
    cr_assert_eq(j->spec.chain.gravity[2], -9.81);
    compare(j, J, 6);
    job_free(j);
}

Test(urdf, joint_limit_and_dynamics_are_checked_and_kept)
{
    static const struct {
        const char *joint, *field, *message;
    } bad[] = {
        {"'limit':{'effort':-1}", "scene.bodies[0].joint.limit.effort",
         "must not be negative (got -1)"},
        {"'limit':{'lower':1,'upper':0.5}", "scene.bodies[0].joint.limit.upper",
         "must not be below lower (got 0.5 < 1)"},
        {"'limit':{'torque':1}", "scene.bodies[0].joint.limit.torque", "unknown key \"torque\""},
        {"'dynamics':{'damping':-0.1}", "scene.bodies[0].joint.dynamics.damping",
         "must not be negative (got -0.1)"},
        {"'dynamics':[]", "scene.bodies[0].joint.dynamics", "must be an object (got an array)"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char doc[512];
        snprintf(doc, sizeof doc,
                 "{'scene':{'bodies':[{'mass':1,'com':[0,-0.5,0],'inertia':[0.1,0.1,0.1],"
                 "'joint':{'type':'revolute','axis':[0,0,1],%s}}]},'controller':{'type':'none'},"
                 "'duration':0.1}",
                 bad[i].joint);
        for (char *c = doc; *c; c++)
            if (*c == '\'') *c = '"';
        job *j = NULL;
        job_error err;
        cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), -1, "%s", bad[i].joint);
        cr_assert_str_eq(err.field, bad[i].field);
        cr_assert_str_eq(err.message, bad[i].message);
    }
    /* given ones are kept, in the format's order, whatever the document's */
    const char *ok = "{\"scene\":{\"bodies\":[{\"mass\":1,\"com\":[0,-0.5,0],\"inertia\":[0.1,"
                     "0.1,0.1],\"joint\":{\"type\":\"prismatic\",\"axis\":[1,0,0],\"limit\":{"
                     "\"velocity\":0.5,\"upper\":0.3},\"dynamics\":{\"friction\":2}}}]},"
                     "\"controller\":{\"type\":\"none\"},\"duration\":0.1}";
    job *j = parse_ok(ok);
    const cJSON *joint = cJSON_GetObjectItemCaseSensitive(
        cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(
                               cJSON_GetObjectItemCaseSensitive(j->normalised, "scene"), "bodies"),
                           0),
        "joint");
    char *text = cJSON_PrintUnformatted(joint);
    cr_assert_str_eq(text, "{\"type\":\"prismatic\",\"axis\":[1,0,0],\"location\":[0,0,0],"
                           "\"independent\":true,\"limit\":{\"upper\":0.3,\"velocity\":0.5},"
                           "\"dynamics\":{\"friction\":2}}");
    free(text);
    job_free(j);
}

Test(urdf, elements_and_attributes_not_modelled_are_ignored)
{
    /* the two-link arm dressed as robots come: namespaces, materials, visuals and collisions
       with meshes, transmissions, Gazebo blocks, comments, an extra attribute on <limit> */
    static const char dressed[] =
        "<?xml version=\"1.0\"?>\n"
        "<robot xmlns:drake=\"http://drake.mit.edu\" name=\"two_link\">\n"
        "  <!-- a comment -->\n"
        "  <material name=\"Grey\"><color rgba=\"0.4 0.4 0.4 1.0\"/></material>\n"
        "  <link name=\"base\"><visual><geometry><box size=\"1 1 1\"/></geometry></visual></link>\n"
        "  <link name=\"upper\">\n"
        "    <inertial><origin xyz=\"0.5 0 0\"/><mass value=\"1\"/>\n"
        "      <inertia ixx=\"1e-4\" iyy=\"0.0833333333333333\" izz=\"0.0833333333333333\"/>\n"
        "    </inertial>\n"
        "    <visual><origin xyz=\"0.5 0 0\"/><geometry><mesh filename=\"package://x/upper.obj\"/>"
        "</geometry><material name=\"Grey\"/></visual>\n"
        "    <collision><geometry><cylinder radius=\"0.05\" length=\"1\"/></geometry></collision>\n"
        "  </link>\n"
        "  <link name=\"fore\">\n"
        "    <inertial><origin xyz=\"0.5 0 0\"/><mass value=\"1\"/>\n"
        "      <inertia ixx=\"1e-4\" iyy=\"0.0833333333333333\" izz=\"0.0833333333333333\"/>\n"
        "    </inertial>\n"
        "  </link>\n"
        "  <joint name=\"shoulder\" type=\"continuous\">\n"
        "    <parent link=\"base\"/><child link=\"upper\"/><axis xyz=\"0 0 1\"/>\n"
        "    <dynamics damping=\"0.05\" friction=\"0.01\"/>\n"
        "    <safety_controller k_velocity=\"10\"/>\n"
        "  </joint>\n"
        "  <joint name=\"elbow\" type=\"revolute\">\n"
        "    <parent link=\"upper\"/><child link=\"fore\"/><origin xyz=\"1 0 0\"/>\n"
        "    <axis xyz=\"0 0 1\"/><limit drake:acceleration=\"8\" lower=\"-2.5\" upper=\"2.5\" "
        "effort=\"20\" velocity=\"3\"/>\n"
        "  </joint>\n"
        "  <transmission name=\"t\"><type>SimpleTransmission</type><joint name=\"elbow\"/>"
        "</transmission>\n"
        "  <gazebo reference=\"upper\"><material>Gazebo/Grey</material></gazebo>\n"
        "</robot>\n";
    char msg[512];
    cJSON *plain = urdf_to_bodies(two_link_urdf, strlen(two_link_urdf), NULL, 0, msg, sizeof msg);
    cr_assert_not_null(plain, "%s", msg);
    cJSON *dressed_bodies = urdf_to_bodies(dressed, strlen(dressed), NULL, 0, msg, sizeof msg);
    cr_assert_not_null(dressed_bodies, "%s", msg);
    cr_assert(cJSON_Compare(plain, dressed_bodies, 1));
    cJSON_Delete(plain);
    cJSON_Delete(dressed_bodies);
}

Test(urdf, builder_errors_about_a_converted_body_name_its_link)
{
    /* fore's inertia breaks the triangle inequality: the builder's "body 1" is the link */
    char *bad = strdup(two_link_urdf);
    char *at = strstr(strstr(bad, "name=\"fore\""), "izz=\"");
    memcpy(at, "izz=\"0.9999999999999999\"", strlen("izz=\"0.9999999999999999\""));
    char *doc = urdf_job(bad);
    job *j = NULL;
    job_error err;
    cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), -1);
    cr_assert_str_eq(err.field, "scene");
    cr_assert(strncmp(err.message, "body 1: ", 8) == 0, "%s", err.message);
    const char *tail = " (the robot's link \"fore\")";
    cr_assert_str_eq(err.message + strlen(err.message) - strlen(tail), tail, "%s", err.message);
    free(doc);
    free(bad);
}

Test(urdf, moving_links_without_mass_are_accepted_where_the_mass_matrix_allows)
{
    /* b has no <inertial> and is the tip of a revolute joint: nothing moves with it, so the
       builder refuses it and the job names the link */
    const char *tip = "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n"
                      "<joint name=\"j\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>"
                      "</joint>\n</robot>\n";
    char *doc = urdf_job(tip);
    job *j = NULL;
    job_error err;
    cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), -1);
    cr_assert_str_eq(err.field, "scene");
    cr_assert_str_eq(err.message,
                     "body 0: the joint-space mass matrix is singular: joint 0 (revolute) moves "
                     "no mass or inertia that the joints before it do not (relative pivot 0 <= "
                     "1e-10); body 0 and the bodies beyond it need mass off the joint's axis or "
                     "inertia about it (the robot's link \"b\")");
    free(doc);

    /* a massless link b between two joints (a universal joint's cross), c with mass beyond it:
       accepted, b a massless body */
    const char *cross = "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n"
                        "<link name=\"c\"><inertial><origin xyz=\"0.5 0 0\"/><mass value=\"1\"/>"
                        "<inertia ixx=\"0.01\" iyy=\"0.02\" izz=\"0.02\"/></inertial></link>\n"
                        "<joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/>"
                        "<child link=\"b\"/><axis xyz=\"0 0 1\"/></joint>\n"
                        "<joint name=\"j2\" type=\"revolute\"><parent link=\"b\"/>"
                        "<child link=\"c\"/><axis xyz=\"0 1 0\"/></joint>\n</robot>\n";
    doc = urdf_job(cross);
    cr_assert_eq(job_parse(doc, strlen(doc), &j, &err), 0, "%s: %s", err.field, err.message);
    cr_assert_eq(j->bodies[0].mass, 0.0);
    job_free(j);
    free(doc);
}

/* ---- visual shapes (urdf.h, import.h "visuals") ---- */

/* A chain base -> a (revolute, origin with rpy) -> b (fixed, origin with rpy) -> c (revolute)
 * with a box on a, a cylinder on b (merged into a's body) and a sphere and a mesh on c: each
 * shape's pose in its body's frame against the chain of transforms at q = 0 written here, the
 * body's frame being parallel to the world's with its origin at its joint's centre. */
static const char visuals_urdf[] =
    "<robot name=\"dressed\">\n"
    "  <link name=\"base\"><visual><geometry><box size=\"1 1 1\"/></geometry></visual></link>\n"
    "  <link name=\"a\">\n"
    "    <inertial><mass value=\"1\"/><inertia ixx=\"0.1\" iyy=\"0.1\" izz=\"0.1\"/></inertial>\n"
    "    <visual><origin xyz=\"0.5 0.1 -0.2\" rpy=\"0.3 -0.2 0.7\"/>\n"
    "      <geometry><box size=\"1 0.1 0.05\"/></geometry></visual>\n"
    "  </link>\n"
    "  <link name=\"b\"><visual><origin xyz=\"0 0 0.25\" rpy=\"1.5707963267948966 0 0\"/>\n"
    "    <geometry><cylinder radius=\"0.04\" length=\"0.5\"/></geometry></visual></link>\n"
    "  <link name=\"c\">\n"
    "    <inertial><origin xyz=\"0.3 0 0\"/><mass value=\"0.5\"/>\n"
    "      <inertia ixx=\"0.01\" iyy=\"0.01\" izz=\"0.01\"/></inertial>\n"
    "    <visual><origin xyz=\"0.6 0 0\"/><geometry><sphere radius=\"0.07\"/></geometry></visual>\n"
    "    <visual><geometry><mesh filename=\"package://x/c.stl\"/></geometry></visual>\n"
    "  </link>\n"
    "  <joint name=\"ja\" type=\"revolute\"><parent link=\"base\"/><child link=\"a\"/>\n"
    "    <origin xyz=\"0 0 0.3\" rpy=\"0.1 0.2 0.4\"/><axis xyz=\"0 0 1\"/></joint>\n"
    "  <joint name=\"jb\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/>\n"
    "    <origin xyz=\"1 0 0\" rpy=\"0 0.5 -0.3\"/></joint>\n"
    "  <joint name=\"jc\" type=\"revolute\"><parent link=\"b\"/><child link=\"c\"/>\n"
    "    <origin xyz=\"0 0 0.5\" rpy=\"-0.6 0 0.2\"/><axis xyz=\"0 1 0\"/></joint>\n"
    "</robot>\n";

/* the expected pose (origin, rotation) of a shape at xf v in the link whose world frame at q = 0
   is L, in the body whose origin is at o */
static void expect_visual(const cJSON *vis, xf L, xf v, const double o[3], const char *type,
                          const char *what)
{
    xf w = xf_mul(L, v);
    cr_assert_not_null(vis, "%s: no visual", what);
    cr_expect_str_eq(cJSON_GetObjectItem(vis, "type")->valuestring, type, "%s", what);
    const cJSON *origin = cJSON_GetObjectItem(vis, "origin");
    for (int i = 0; i < 3; i++) {
        double got = cJSON_GetArrayItem(origin, i)->valuedouble;
        cr_expect(fabs(got - (w.p[i] - o[i])) <= 1e-14, "%s: origin[%d] %.17g, want %.17g", what, i,
                  got, w.p[i] - o[i]);
    }
    const cJSON *rows = cJSON_GetObjectItem(vis, "rotation");
    if (strcmp(type, "sphere") == 0) {
        cr_expect_null(rows, "%s: a sphere has no rotation", what);
        return;
    }
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            double got = cJSON_GetArrayItem(cJSON_GetArrayItem(rows, i), j)->valuedouble;
            cr_expect(fabs(got - w.R[3 * i + j]) <= 1e-14, "%s: rotation[%d][%d] %.17g, want %.17g",
                      what, i, j, got, w.R[3 * i + j]);
        }
}

Test(urdf, visual_boxes_cylinders_and_spheres_are_kept_in_their_bodies_frames)
{
    char msg[512], name[64];
    int meshes = -1;
    cJSON *bodies =
        urdf_read(visuals_urdf, strlen(visuals_urdf), name, sizeof name, &meshes, msg, sizeof msg);
    cr_assert_not_null(bodies, "%s", msg);
    cr_expect_eq(meshes, 1, "the mesh is counted");
    cr_assert_eq(cJSON_GetArraySize(bodies), 2, "a (with b merged) and c");
    /* the links' world frames at q = 0, and the bodies' origins (their joints' centres) */
    xf A = xf_rpy(0, 0, 0.3, 0.1, 0.2, 0.4);
    xf B = xf_mul(A, xf_rpy(1, 0, 0, 0, 0.5, -0.3));
    xf C = xf_mul(B, xf_rpy(0, 0, 0.5, -0.6, 0, 0.2));
    const cJSON *va = cJSON_GetObjectItem(cJSON_GetArrayItem(bodies, 0), "visuals");
    const cJSON *vc = cJSON_GetObjectItem(cJSON_GetArrayItem(bodies, 1), "visuals");
    cr_assert_eq(cJSON_GetArraySize(va), 2, "a's box and b's cylinder");
    cr_assert_eq(cJSON_GetArraySize(vc), 1, "c's sphere; its mesh left out");
    expect_visual(cJSON_GetArrayItem(va, 0), A, xf_rpy(0.5, 0.1, -0.2, 0.3, -0.2, 0.7), A.p, "box",
                  "a's box");
    expect_visual(cJSON_GetArrayItem(va, 1), B, xf_rpy(0, 0, 0.25, 1.5707963267948966, 0, 0), A.p,
                  "cylinder", "b's cylinder on a");
    expect_visual(cJSON_GetArrayItem(vc, 0), C, xf_rpy(0.6, 0, 0, 0, 0, 0), C.p, "sphere",
                  "c's sphere");
    const cJSON *box = cJSON_GetArrayItem(va, 0), *cyl = cJSON_GetArrayItem(va, 1);
    cr_expect_eq(cJSON_GetArrayItem(cJSON_GetObjectItem(box, "size"), 1)->valuedouble, 0.1);
    cr_expect_eq(cJSON_GetObjectItem(cyl, "radius")->valuedouble, 0.04);
    cr_expect_eq(cJSON_GetObjectItem(cyl, "length")->valuedouble, 0.5);
    cr_expect_eq(cJSON_GetObjectItem(cJSON_GetArrayItem(vc, 0), "radius")->valuedouble, 0.07);
    cJSON_Delete(bodies);

    /* through the job format: the normalised job keeps them, and they parse back the same */
    char *doc = urdf_job(visuals_urdf);
    job *j = parse_ok(doc);
    const cJSON *stored = cJSON_GetObjectItem(
        cJSON_GetArrayItem(
            cJSON_GetObjectItem(cJSON_GetObjectItem(j->normalised, "scene"), "bodies"), 0),
        "visuals");
    cr_assert_eq(cJSON_GetArraySize(stored), 2);
    expect_visual(cJSON_GetArrayItem(stored, 0), A, xf_rpy(0.5, 0.1, -0.2, 0.3, -0.2, 0.7), A.p,
                  "box", "the stored box");
    char *again = cJSON_PrintUnformatted(j->normalised);
    job *k = parse_ok(again);
    cr_expect(cJSON_Compare(j->normalised, k->normalised, 1),
              "the normalised job is a fixed point");
    job_free(k);
    free(again);
    job_free(j);
    free(doc);
}

Test(urdf, bad_visuals_are_refused_with_their_element_and_line)
{
    static const struct {
        const char *visual, *message;
    } bad[] = {
        {"<visual><origin xyz=\"1 0 0\"/></visual>",
         "line 2: <visual> in <link name=\"a\">: <geometry> is required"},
        {"<visual><geometry><box size=\"1 0 1\"/></geometry></visual>",
         "line 2: <box> in <link name=\"a\">: size must be positive"},
        {"<visual><geometry><cylinder radius=\"0.1\"/></geometry></visual>",
         "line 2: <cylinder> in <link name=\"a\">: attribute length is required"},
        {"<visual><geometry><capsule radius=\"0.1\" length=\"1\"/></geometry></visual>",
         "line 2: <geometry> in <link name=\"a\">: must hold a <box>, <cylinder>, <sphere> or "
         "<mesh>"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        char urdf[1024], msg[512];
        snprintf(urdf, sizeof urdf,
                 "<robot name=\"r\"><link name=\"base\"/>\n<link name=\"a\">%s<inertial><mass "
                 "value=\"1\"/><inertia ixx=\"1\" iyy=\"1\" izz=\"1\"/></inertial></link>"
                 "<joint name=\"j\" type=\"revolute\"><parent link=\"base\"/><child link=\"a\"/>"
                 "</joint></robot>",
                 bad[i].visual);
        cJSON *b = urdf_to_bodies(urdf, strlen(urdf), NULL, 0, msg, sizeof msg);
        cr_expect_null(b, "case %zu accepted", i);
        cJSON_Delete(b);
        cr_expect_str_eq(msg, bad[i].message, "case %zu", i);
    }
    /* the job format's own checks of a body's visuals */
    static const struct {
        const char *visuals, *field, *message;
    } fmt[] = {
        {"[{'type':'cone'}]", "scene.bodies[0].visuals[0].type",
         "must be one of \"box\", \"cylinder\", \"sphere\" (got \"cone\")"},
        {"[{'type':'sphere','radius':0.1,'size':[1,1,1]}]", "scene.bodies[0].visuals[0].size",
         "does not apply to a sphere"},
        {"[{'type':'box','size':[1,1,1],'rotation':[[1,0,0],[0,1,0],[0,0,-1]]}]",
         "scene.bodies[0].visuals[0].rotation",
         "must be a rotation (orthonormal rows, determinant +1)"},
        {"[{'type':'cylinder','radius':-1,'length':1}]", "scene.bodies[0].visuals[0].radius",
         "must be positive (got -1 m)"},
    };
    for (size_t i = 0; i < sizeof fmt / sizeof fmt[0]; i++) {
        char text[1024];
        snprintf(text, sizeof text,
                 "{'scene':{'bodies':[{'mass':1,'com':[0,0,0],'inertia':[1,1,1],'joint':{'type':"
                 "'revolute','axis':[0,0,1]},'visuals':%s}]},'controller':{'type':'none'},"
                 "'duration':1}",
                 fmt[i].visuals);
        for (char *c = text; *c; c++)
            if (*c == '\'') *c = '"';
        job *j = NULL;
        job_error err;
        cr_expect_eq(job_parse(text, strlen(text), &j, &err), -1, "case %zu accepted", i);
        if (j) {
            job_free(j);
            continue;
        }
        cr_expect_str_eq(err.field, fmt[i].field, "case %zu", i);
        cr_expect_str_eq(err.message, fmt[i].message, "case %zu", i);
    }
}
