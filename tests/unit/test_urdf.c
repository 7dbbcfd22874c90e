/*
 * test_urdf.c - robots imported from URDF (server/urdf.c) and Denavit-Hartenberg tables
 * (server/dh.c) through the frame conversion of server/import.c, and the job format's "scene.urdf"
 * and "scene.dh" (server/job_scene.c).
 *
 * Oracle: the dynamics of each robot computed here by a separate route from the published
 * numbers, with no use of ctcsim's frames: forward kinematics of the original description (DH's
 * or URDF's chain of transforms F_i = F_(i-1) A_i Mot(axis_i, q_i) B_i, with the inertial data in
 * F_i), then the textbook Jacobians (revolute: Jv_j = z_j x (p_c - o_j), Jw_j = z_j; prismatic:
 * Jv_j = z_j, Jw_j = 0) and
 *     M(q)    = sum_i m_i Jv_i^T Jv_i + Jw_i^T R_i I_i R_i^T Jw_i,
 *     G(q)    = -sum_i m_i Jv_i^T g,
 *     c(q, v) = sum_i m_i Jv_i^T (dJv_i v) + Jw_i^T (I_w (dJw_i v) + w_i x I_w w_i),
 * with dJ v from the axes' rates dz_j = w_(j-1) x z_j and the joint points' velocities. ctcsim's
 * side is the model built from the converted job and the library's independent oracle
 * (oracle.h: composite-rigid-body M, Newton-Euler c + G). They must agree to 1e-10 at several
 * poses and velocities.
 *
 * Published numbers: the UR5's DH table, masses and centres of mass from Universal Robots,
 * "Parameters for calculations of kinematics and dynamics" (universal-robots.com, UR5 column);
 * its link inertias (about the centres of mass, principal, in the DH frames) from ur_description's
 * ur5 cylinder approximations as Lynch and Park, Modern Robotics (2017), list them for the UR5
 * (G1..G6). The Panda's joint origins and finger joints from franka_description's panda_arm and
 * hand xacro files (equal to Franka's modified DH table); its masses, centres of mass and
 * inertias here are illustrative. The two-link arm is the textbook planar arm (Spong, Hutchinson
 * and Vidyasagar, Robot Modeling and Control, section 7.3: l = 1 m, lc = 0.5 m, m = 1 kg) with a
 * slender-rod inertia m l^2 / 12 about the normal axes and a small one about the rod's. The KUKA
 * LBR iiwa 14 from Drake's iiwa14_no_collision.urdf (RobotLocomotion/drake, manipulation/models/
 * iiwa_description), typed in here apart from its preset (server/presets_robots.c).
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

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

static void mm(const double *a, const double *b, double *c)
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            c[3 * i + j] = a[3 * i] * b[j] + a[3 * i + 1] * b[3 + j] + a[3 * i + 2] * b[6 + j];
}

static void mv(const double *R, const double *x, double *y)
{
    for (int i = 0; i < 3; i++) y[i] = R[3 * i] * x[0] + R[3 * i + 1] * x[1] + R[3 * i + 2] * x[2];
}

static xf xf_mul(xf a, xf b)
{
    xf t;
    mm(a.R, b.R, t.R);
    mv(a.R, b.p, t.p);
    for (int i = 0; i < 3; i++) t.p[i] += a.p[i];
    return t;
}

static void cross(const double *a, const double *b, double *c)
{
    double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2],
           z = a[0] * b[1] - a[1] * b[0];
    c[0] = x, c[1] = y, c[2] = z;
}

/* rotation by angle q about unit axis u (Rodrigues) */
static void rot_axis(const double *u, double q, double *R)
{
    double c = cos(q), s = sin(q), v = 1 - c;
    double x = u[0], y = u[1], z = u[2];
    double r[9] = {c + x * x * v,     x * y * v - z * s, x * z * v + y * s,
                   y * x * v + z * s, c + y * y * v,     y * z * v - x * s,
                   z * x * v - y * s, z * y * v + x * s, c + z * z * v};
    memcpy(R, r, sizeof r);
}

/* URDF's rpy: Rz(y) Ry(p) Rx(r), written as the product of the three elementary rotations */
static xf xf_rpy(double x, double y, double z, double r, double p, double yw)
{
    static const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    double Rx[9], Ry[9], Rz[9], t[9];
    xf o;
    rot_axis(ex, r, Rx);
    rot_axis(ey, p, Ry);
    rot_axis(ez, yw, Rz);
    mm(Ry, Rx, t);
    mm(Rz, t, o.R);
    o.p[0] = x, o.p[1] = y, o.p[2] = z;
    return o;
}

/* standard DH's B = Rz(theta) Tz(d) Tx(a) Rx(alpha) as a product of elementary transforms */
static xf dh_standard(double a, double alpha, double d, double theta)
{
    xf rz = xf_rpy(0, 0, d, 0, 0, theta), tx = xf_rpy(a, 0, 0, alpha, 0, 0);
    return xf_mul(rz, tx);
}

/* the chain's M (nv x nv), G and c at q, v; gravity g */
static int oracle_dynamics(const tjoint *J, int n, const double *g, const double *q,
                           const double *v, double *M, double *G, double *c)
{
    double z[MAXJ][3], o[MAXJ][3], Rl[MAXJ][9], pl[MAXJ][3];
    int col[MAXJ], nv = 0;
    xf T = xf_id();
    for (int i = 0; i < n; i++) {
        xf Tj = xf_mul(T, J[i].A);
        double u[3], len = sqrt(J[i].axis[0] * J[i].axis[0] + J[i].axis[1] * J[i].axis[1] +
                                J[i].axis[2] * J[i].axis[2]);
        for (int k = 0; k < 3; k++) u[k] = J[i].axis[k] / len;
        mv(Tj.R, u, z[i]);
        memcpy(o[i], Tj.p, sizeof o[i]);
        xf mot = xf_id();
        col[i] = J[i].type == T_FIXED ? -1 : nv++;
        if (J[i].type == T_REV) rot_axis(u, q[col[i]], mot.R);
        if (J[i].type == T_PRI)
            for (int k = 0; k < 3; k++) mot.p[k] = q[col[i]] * u[k];
        T = xf_mul(xf_mul(Tj, mot), J[i].B);
        memcpy(Rl[i], T.R, sizeof T.R);
        memcpy(pl[i], T.p, sizeof T.p);
    }
    /* angular velocity of link i, and of the link before joint i */
    double w[MAXJ][3], wb[MAXJ][3], ob[MAXJ][3];
    double wa[3] = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        memcpy(wb[i], wa, sizeof wa);
        /* velocity of the point o_i, fixed in the link before joint i */
        for (int k = 0; k < 3; k++) ob[i][k] = 0;
        for (int j = 0; j < i; j++) {
            if (col[j] < 0) continue;
            double t[3], r[3];
            if (J[j].type == T_REV) {
                for (int k = 0; k < 3; k++) r[k] = o[i][k] - o[j][k];
                cross(z[j], r, t);
            } else {
                memcpy(t, z[j], sizeof t);
            }
            for (int k = 0; k < 3; k++) ob[i][k] += t[k] * v[col[j]];
        }
        if (J[i].type == T_REV)
            for (int k = 0; k < 3; k++) wa[k] += z[i][k] * v[col[i]];
        memcpy(w[i], wa, sizeof wa);
    }
    memset(M, 0, (size_t)(nv * nv) * sizeof *M);
    memset(G, 0, (size_t)nv * sizeof *G);
    memset(c, 0, (size_t)nv * sizeof *c);
    for (int i = 0; i < n; i++) {
        if (J[i].mass == 0) continue;
        double pc[3], Iw[9], RI[9], Rt[9];
        mv(Rl[i], J[i].com, pc);
        for (int k = 0; k < 3; k++) pc[k] += pl[i][k];
        for (int a = 0; a < 3; a++)
            for (int b = 0; b < 3; b++) Rt[3 * a + b] = Rl[i][3 * b + a];
        mm(Rl[i], J[i].I, RI);
        mm(RI, Rt, Iw);
        double Jv[MAXJ][3] = {{0}}, Jw[MAXJ][3] = {{0}};
        double vc[3] = {0, 0, 0};
        for (int j = 0; j <= i; j++) {
            if (col[j] < 0) continue;
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
            if (col[j] < 0) continue;
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
        mv(Iw, aw, Iaw);
        mv(Iw, w[i], Iww);
        cross(w[i], Iww, gyro);
        for (int k = 0; k < 3; k++) rot[k] = Iaw[k] + gyro[k];
        for (int a = 0; a < nv; a++) {
            double IJa[3];
            mv(Iw, Jw[a], IJa);
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

/* the job's M, c and G against the oracle's at 5 poses; returns the largest difference */
static double compare(const job *j, const tjoint *J, int n)
{
    ctc_model *m = NULL;
    char msg[256];
    cr_assert_eq(ctc_model_build(&j->spec.chain, &m, msg, sizeof msg), CTC_OK, "%s", msg);
    ctc_oracle *o = ctc_oracle_new(m);
    int nv = m->nv;
    double q[MAXJ], v[MAXJ], zero[MAXJ] = {0}, M[MAXJ * MAXJ], G[MAXJ], c[MAXJ];
    double Mc[MAXJ * MAXJ], tv[MAXJ], t0[MAXJ], worst = 0;
    for (int k = 0; k < 5; k++) {
        pose(k, nv, q, v);
        cr_assert_eq(oracle_dynamics(J, n, m->gravity, q, v, M, G, c), nv);
        ctc_oracle_mass_matrix(m, o, q, Mc);
        ctc_oracle_rnea(m, o, q, v, zero, tv);
        ctc_oracle_rnea(m, o, q, zero, zero, t0);
        for (int a = 0; a < nv; a++) {
            for (int b = 0; b < nv; b++) {
                double d = fabs(M[a * nv + b] - Mc[a * nv + b]);
                cr_assert_leq(d, DYN_TOL, "pose %d: M[%d][%d] %.17g vs ctcsim %.17g", k, a, b,
                              M[a * nv + b], Mc[a * nv + b]);
                worst = fmax(worst, d);
            }
            double dg = fabs(G[a] - t0[a]), dc = fabs(c[a] - (tv[a] - t0[a]));
            cr_assert_leq(dg, DYN_TOL, "pose %d: G[%d] %.17g vs ctcsim %.17g", k, a, G[a], t0[a]);
            cr_assert_leq(dc, DYN_TOL, "pose %d: c[%d] %.17g vs ctcsim %.17g", k, a, c[a],
                          tv[a] - t0[a]);
            worst = fmax(worst, fmax(dg, dc));
        }
    }
    ctc_oracle_free(o);
    ctc_model_free(m);
    return worst;
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
        mv(B.R, ur5_com[i], c);
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

static void frames_urdf(buf *b, const char *robot, const tlink *L, int n)
{
    static const char *const types[] = {"revolute", "prismatic", "fixed"};
    put(b, "<robot name=\"%s\">\n", robot);
    /* joints first, links in reverse: the document's order must not matter */
    for (int i = 1; i < n; i++) {
        const tlink *l = &L[i];
        put(b,
            "  <joint name=\"j_%s\" type=\"%s\"><parent link=\"%s\"/><child link=\"%s\"/>"
            "<origin xyz=\"%.17g %.17g %.17g\" rpy=\"%.17g %.17g %.17g\"/>"
            "<axis xyz=\"%.17g %.17g %.17g\"/></joint>\n",
            l->name, types[l->type], L[i - 1].name, l->name, l->xyz[0], l->xyz[1], l->xyz[2],
            l->rpy[0], l->rpy[1], l->rpy[2], l->axis[0], l->axis[1], l->axis[2]);
    }
    for (int i = n - 1; i >= 0; i--) {
        const tlink *l = &L[i];
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
        mm(in.R, I, RI);
        mm(RI, Rt, t->I);
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

/* franka_description's panda_arm and hand: joint origins (xyz, rpy) and axes */
#define PANDA_H 1.57079632679489662
static const tlink panda_links[] = {
    {"panda_link0", 0, {0}, {0}, 0, {0}, T_FIXED, {0}, {0}, {0}},
    {"panda_link1",
     1,
     {0, -0.03, -0.1},
     {0},
     4.97,
     {0.7, 0.7, 0.01, 0, 0, 0.02},
     T_REV,
     {0, 0, 0.333},
     {0, 0, 0},
     {0, 0, 1}},
    {"panda_link2",
     1,
     {0, -0.07, 0.03},
     {0},
     0.65,
     {0.008, 0.03, 0.03, 0, 0, 0},
     T_REV,
     {0, 0, 0},
     {-PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link3",
     1,
     {0.04, 0.03, -0.07},
     {0},
     3.23,
     {0.04, 0.04, 0.01, 0, 0, 0},
     T_REV,
     {0, -0.316, 0},
     {PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link4",
     1,
     {-0.05, 0.1, 0.03},
     {0},
     3.59,
     {0.03, 0.03, 0.01, 0, 0, 0},
     T_REV,
     {0.0825, 0, 0},
     {PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link5",
     1,
     {-0.01, 0.04, -0.11},
     {0},
     1.23,
     {0.04, 0.04, 0.005, 0, 0, 0},
     T_REV,
     {-0.0825, 0.384, 0},
     {-PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link6",
     1,
     {0.06, -0.01, 0.01},
     {0},
     1.67,
     {0.002, 0.004, 0.005, 0, 0, 0},
     T_REV,
     {0, 0, 0},
     {PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link7",
     1,
     {0.01, 0.01, 0.08},
     {0},
     0.74,
     {0.01, 0.01, 0.005, 0, 0, 0},
     T_REV,
     {0.088, 0, 0},
     {PANDA_H, 0, 0},
     {0, 0, 1}},
    {"panda_link8", 0, {0}, {0}, 0, {0}, T_FIXED, {0, 0, 0.107}, {0, 0, 0}, {1, 0, 0}},
    {"panda_hand",
     1,
     {0, 0, 0.04},
     {0},
     0.73,
     {0.0025, 0.0005, 0.0018, 0, 0, 0},
     T_FIXED,
     {0, 0, 0},
     {0, 0, -0.785398163397448},
     {1, 0, 0}},
};
#define NPANDA ((int)(sizeof panda_links / sizeof panda_links[0]))

static void panda_urdf(buf *b, const char *finger_type)
{
    frames_urdf(b, "panda", panda_links, NPANDA);
    b->n -= strlen("</robot>\n");
    for (int f = 0; f < 2; f++) {
        put(b,
            "  <link name=\"panda_%sfinger\"><inertial><origin xyz=\"0 %s0.01 0.02\"/>"
            "<mass value=\"0.015\"/><inertia ixx=\"2.4e-6\" iyy=\"2.4e-6\" izz=\"7.5e-7\"/>"
            "</inertial></link>\n"
            "  <joint name=\"panda_finger_joint%d\" type=\"%s\"><parent link=\"panda_hand\"/>"
            "<child link=\"panda_%sfinger\"/><origin xyz=\"0 0 0.0584\" rpy=\"0 0 0\"/>"
            "<axis xyz=\"0 %s1 0\"/><limit effort=\"20\" lower=\"0.0\" upper=\"0.04\" "
            "velocity=\"0.2\"/></joint>\n",
            f ? "right" : "left", f ? "-" : "", f + 1, finger_type, f ? "right" : "left",
            f ? "-" : "");
    }
    put(b, "</robot>\n");
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
    mm(R7, Rz, t);
    double y[3] = {0, 1, 0};
    mv(t, y, expect);
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

Test(urdf, panda_arm_with_fixed_fingers_matches_jacobian_dynamics)
{
    buf b = {.n = 0};
    panda_urdf(&b, "fixed");
    tjoint J[NPANDA + 2];
    int n = frames_oracle(panda_links, NPANDA, J);
    /* the fingers, fixed to the hand */
    for (int f = 0; f < 2; f++) {
        tjoint *t = &J[n++];
        *t = (tjoint){.type = T_FIXED,
                      .A = xf_rpy(0, 0, 0.0584, 0, 0, 0),
                      .B = xf_id(),
                      .axis = {1, 0, 0},
                      .mass = 0.015,
                      .com = {0, f ? -0.01 : 0.01, 0.02},
                      .I = {2.4e-6, 0, 0, 0, 2.4e-6, 0, 0, 0, 7.5e-7}};
    }
    /* the oracle's chain is serial: the right finger hangs from the left one, whose frame is
       the right finger's own (both are the hand's frame moved by the same origin) */
    J[n - 1].A = xf_id();
    char *doc = urdf_job(b.s);
    job *j = parse_ok(doc);
    cr_assert_eq(j->spec.chain.nbodies, 7);
    compare(j, J, n);
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
