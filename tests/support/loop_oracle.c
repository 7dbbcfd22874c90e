/*
 * loop_oracle.c - closed-chain dynamics by redundant coordinates and Lagrange multipliers, for
 * tests (loop_oracle.h has the formulation).
 *
 * The chain's (or tree's: each body from its spec parent) kinematics are recomputed here from
 * the spec with 3x3 rotations, a point's Jacobian over the joints from the ground to its body;
 * the mass matrix and the bias forces come from the library's open-chain oracle (Featherstone's
 * CRBA and RNEA, oracle.h) on an open model built from the same spec without its loop. Dense
 * systems are solved by LU with partial pivoting. Sizes are small (tests), so clarity wins over
 * speed. The file ends with the test loops (five-bar, four-bars, slider-crank, RSSR, spatial 8R),
 * each built so that its q0 closes the loop exactly, and loop_scene_branch, which hangs branches
 * off a loop's spine.
 */
#include "loop_oracle.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "frames.h"
#include "oracle.h"
#include "shapes.h"

#define LO_MAX_ROWS 6

/* one scalar constraint (loop_oracle.h): linear c . (p_t - p_a), or rotational c . (R_t b), c
 * fixed in the closing joint's child (c = R_a c_child) */
typedef struct lo_row {
    int rotational;
    double b[3]; /* tip frame (rotational) */
    double c[3]; /* the child's frame (world for the ground) */
} lo_row;

struct loop_oracle {
    loop_oracle_dims dims;
    ctc_body_spec *bodies;  /* (n) */
    ctc_joint_spec *joints; /* (n + 1) axes normalised; the closing joint last */
    double anchor[3];       /* the child's frame */
    int body;               /* the closing joint's child: -1 the ground, else a body */
    double gravity[3];
    unsigned char *indep; /* (n + 1) */
    int *qadr, *vadr;     /* (n + 1) */
    int *parent;          /* (n) each body's parent, -1 the ground (the spec's, or k - 1) */
    lo_row rows[LO_MAX_ROWS];

    ctc_model *open; /* the chain without its loop, for the library's oracle */
    ctc_oracle *rb;

    /* kinematics of the last state (world) */
    double *rot;    /* (n x 9) */
    double *pos;    /* (n x 3) origins */
    double *axis;   /* (n x 3) joint axes u_k = R_{k-1} a_k */
    double *omega;  /* (n x 3) */
    double *vel;    /* (n x 3) origin velocities */
    double *alpha0; /* (n x 3) angular accelerations at v' = 0 */
    double *acc0;   /* (n x 3) origin accelerations at v' = 0 */
    double pt[3], vt[3], at0[3];
    double *jac; /* (6 x nv) tip twist at p_t: rows 0-2 angular, 3-5 linear */
    /* the child's (zero for the ground): its orientation and angular motion, the anchor p_a and
       the child's point there (velocity, acceleration at v' = 0), its twist at p_a */
    double ra[9], wa[3], alpha0a[3], pa[3], va[3], aa0[3];
    double *jacb; /* (6 x nv) */

    /* scratch */
    double *mass, *h, *g, *gamma, *cmap, *big, *rhs;
};

/* ---- small vector helpers (written here, not the library's) ---- */

static void v3_cross(double r[3], const double a[3], const double b[3])
{
    double x = a[1] * b[2] - a[2] * b[1], y = a[2] * b[0] - a[0] * b[2],
           z = a[0] * b[1] - a[1] * b[0];
    r[0] = x, r[1] = y, r[2] = z;
}

static double v3_dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double v3_norm(const double a[3])
{
    return sqrt(v3_dot(a, a));
}

/* rotation of the quaternion (w, x, y, z), normalised first */
static void m3_quat(double r[9], const double q[4])
{
    double n = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3]);
    double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
    r[0] = 1 - 2 * (y * y + z * z), r[1] = 2 * (x * y - w * z), r[2] = 2 * (x * z + w * y);
    r[3] = 2 * (x * y + w * z), r[4] = 1 - 2 * (x * x + z * z), r[5] = 2 * (y * z - w * x);
    r[6] = 2 * (x * z - w * y), r[7] = 2 * (y * z + w * x), r[8] = 1 - 2 * (x * x + y * y);
}

/* two unit vectors completing the unit a to a right-handed orthonormal basis */
static void v3_normals(const double a[3], double n1[3], double n2[3])
{
    double e[3] = {0, 0, 0};
    int i = fabs(a[0]) <= fabs(a[1]) && fabs(a[0]) <= fabs(a[2]) ? 0
            : fabs(a[1]) <= fabs(a[2])                           ? 1
                                                                 : 2;
    e[i] = 1;
    v3_cross(n1, a, e);
    double s = v3_norm(n1);
    for (int k = 0; k < 3; k++) n1[k] /= s;
    v3_cross(n2, a, n1);
}

static int type_nq(ctc_joint_type t)
{
    return t == CTC_JOINT_SPHERICAL     ? 4
           : t == CTC_JOINT_CYLINDRICAL ? 2
           : t == CTC_JOINT_FIXED       ? 0
                                        : 1;
}

static int type_nv(ctc_joint_type t)
{
    return t == CTC_JOINT_SPHERICAL     ? 3
           : t == CTC_JOINT_CYLINDRICAL ? 2
           : t == CTC_JOINT_FIXED       ? 0
                                        : 1;
}

/* ---- dense LU ---- */

int loop_oracle_lu_solve(double *a, int n, double *b)
{
    double big = 0;
    for (int i = 0; i < n * n; i++) big = fmax(big, fabs(a[i]));
    if (!(big > 0)) return n ? -1 : 0;
    for (int k = 0; k < n; k++) {
        int p = k;
        for (int i = k + 1; i < n; i++)
            if (fabs(a[i * n + k]) > fabs(a[p * n + k])) p = i;
        if (!(fabs(a[p * n + k]) > 1e-13 * big)) return -1;
        if (p != k) {
            for (int j = 0; j < n; j++) {
                double t = a[k * n + j];
                a[k * n + j] = a[p * n + j], a[p * n + j] = t;
            }
            double t = b[k];
            b[k] = b[p], b[p] = t;
        }
        for (int i = k + 1; i < n; i++) {
            double l = a[i * n + k] / a[k * n + k];
            a[i * n + k] = l;
            for (int j = k + 1; j < n; j++) a[i * n + j] -= l * a[k * n + j];
            b[i] -= l * b[k];
        }
    }
    for (int i = n - 1; i >= 0; i--) {
        double s = b[i];
        for (int j = i + 1; j < n; j++) s -= a[i * n + j] * b[j];
        b[i] = s / a[i * n + i];
    }
    return 0;
}

/* ---- construction ---- */

/* planar as loop_oracle.h says; fills the basis */
static int detect_planar(const ctc_chain_spec *spec, const ctc_joint_spec *joints, int nj,
                         const double gravity[3], double plane[9])
{
    const double *nrm = NULL;
    for (int k = 0; k < nj && !nrm; k++)
        if (joints[k].type == CTC_JOINT_REVOLUTE) nrm = joints[k].axis;
    if (spec->form == CTC_FORM_SPATIAL || nrm == NULL) return 0;
    double n[3] = {nrm[0], nrm[1], nrm[2]};
    int big = fabs(n[0]) >= fabs(n[1]) && fabs(n[0]) >= fabs(n[2]) ? 0
              : fabs(n[1]) >= fabs(n[2])                           ? 1
                                                                   : 2;
    if (n[big] < 0)
        for (int i = 0; i < 3; i++) n[i] = -n[i];
    if (spec->form != CTC_FORM_PLANAR) {
        for (int k = 0; k < nj; k++) {
            const ctc_joint_spec *j = &joints[k];
            double c[3];
            v3_cross(c, j->axis, n);
            if (j->type == CTC_JOINT_REVOLUTE && v3_norm(c) > 1e-9) return 0;
            if (j->type == CTC_JOINT_PRISMATIC && fabs(v3_dot(j->axis, n)) > 1e-9) return 0;
            if (j->type == CTC_JOINT_SPHERICAL || j->type == CTC_JOINT_CYLINDRICAL) return 0;
        }
        if (fabs(v3_dot(gravity, n)) > 1e-9 * fmax(1, v3_norm(gravity))) return 0;
    }
    double e1[3] = {1, 0, 0}, e2[3];
    double d = v3_dot(e1, n);
    for (int i = 0; i < 3; i++) e1[i] -= d * n[i];
    if (v3_norm(e1) < 1e-6) {
        e1[0] = 0, e1[1] = 1, e1[2] = 0;
        d = v3_dot(e1, n);
        for (int i = 0; i < 3; i++) e1[i] -= d * n[i];
    }
    d = v3_norm(e1);
    for (int i = 0; i < 3; i++) e1[i] /= d;
    v3_cross(e2, n, e1);
    memcpy(plane, e1, sizeof e1);
    memcpy(plane + 3, e2, sizeof e2);
    memcpy(plane + 6, n, sizeof n);
    return 1;
}

static void set_rows(loop_oracle *o)
{
    const ctc_joint_spec *jn = &o->joints[o->dims.n];
    const double *a = jn->axis, *e1 = o->dims.plane, *e2 = o->dims.plane + 3,
                 *n = o->dims.plane + 6;
    const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    const double *basis[3] = {ex, ey, ez};
    lo_row *r = o->rows;
    int nc = 0;
    double n1[3], n2[3];
    switch (jn->type) {
    case CTC_JOINT_REVOLUTE:
        if (o->dims.planar) {
            memcpy(r[nc++].c, e1, 3 * sizeof(double));
            memcpy(r[nc++].c, e2, 3 * sizeof(double));
            break;
        }
        for (int i = 0; i < 3; i++) memcpy(r[nc++].c, basis[i], 3 * sizeof(double));
        v3_normals(a, n1, n2);
        for (int i = 0; i < 2; i++, nc++) {
            r[nc].rotational = 1;
            memcpy(r[nc].b, a, 3 * sizeof(double));
            memcpy(r[nc].c, i ? n2 : n1, 3 * sizeof(double));
        }
        break;
    case CTC_JOINT_PRISMATIC:
        if (o->dims.planar) {
            r[nc].rotational = 1;
            memcpy(r[nc].b, e1, 3 * sizeof(double));
            memcpy(r[nc++].c, e2, 3 * sizeof(double));
            v3_cross(r[nc++].c, n, a);
            break;
        }
        for (int i = 0; i < 3; i++, nc++) {
            r[nc].rotational = 1;
            memcpy(r[nc].b, basis[(i + 1) % 3], 3 * sizeof(double));
            memcpy(r[nc].c, basis[(i + 2) % 3], 3 * sizeof(double));
        }
        v3_normals(a, n1, n2);
        memcpy(r[nc++].c, n1, 3 * sizeof(double));
        memcpy(r[nc++].c, n2, 3 * sizeof(double));
        break;
    default: /* spherical */
        for (int i = 0; i < 3; i++) memcpy(r[nc++].c, basis[i], 3 * sizeof(double));
        break;
    }
    o->dims.nc = nc;
}

loop_oracle *loop_oracle_new(const ctc_chain_spec *spec)
{
    if (spec == NULL || spec->loop == NULL || spec->nbodies < 1) return NULL;
    int n = spec->nbodies;
    loop_oracle *o = calloc(1, sizeof *o);
    if (o == NULL) return NULL;
    o->dims.n = n;
    o->bodies = calloc((size_t)n, sizeof *o->bodies);
    o->joints = calloc((size_t)n + 1, sizeof *o->joints);
    o->indep = calloc((size_t)n + 1, 1);
    o->qadr = calloc((size_t)n + 1, sizeof(int));
    o->vadr = calloc((size_t)n + 1, sizeof(int));
    o->parent = calloc((size_t)n, sizeof(int));
    if (!o->bodies || !o->joints || !o->indep || !o->qadr || !o->vadr || !o->parent) goto fail;
    for (int k = 0; k < n; k++) o->parent[k] = spec->parent ? spec->parent[k] : k - 1;
    memcpy(o->bodies, spec->bodies, (size_t)n * sizeof *o->bodies);
    memcpy(o->joints, spec->joints, (size_t)n * sizeof *o->joints);
    o->joints[n] = spec->loop->joint;
    memcpy(o->anchor, spec->loop->anchor, sizeof o->anchor);
    o->body = spec->loop->on_body ? spec->loop->body : -1;
    if (o->body < -1 || o->body > n - 2) goto fail;
    memcpy(o->gravity, spec->gravity, sizeof o->gravity);
    for (int k = 0; k <= n; k++) {
        ctc_joint_spec *j = &o->joints[k];
        double s = v3_norm(j->axis);
        if (j->type != CTC_JOINT_SPHERICAL && j->type != CTC_JOINT_FIXED) {
            if (!(s > 0)) goto fail;
            for (int i = 0; i < 3; i++) j->axis[i] /= s;
        }
        o->indep[k] = spec->independent ? spec->independent[k] != 0 : k < n;
        o->qadr[k] = o->dims.nq, o->vadr[k] = o->dims.nv;
        if (k < n) o->dims.nq += type_nq(j->type), o->dims.nv += type_nv(j->type);
    }
    ctc_joint_type tn = o->joints[n].type;
    if (tn != CTC_JOINT_REVOLUTE && tn != CTC_JOINT_PRISMATIC && tn != CTC_JOINT_SPHERICAL)
        goto fail;
    o->dims.nqn = type_nq(tn), o->dims.nvn = type_nv(tn);
    o->dims.nvx = o->dims.nv + o->dims.nvn;
    for (int k = 0; k <= n; k++)
        if (o->indep[k]) o->dims.nind += k < n ? type_nv(o->joints[k].type) : o->dims.nvn;
    o->dims.planar = detect_planar(spec, o->joints, n + 1, o->gravity, o->dims.plane);
    set_rows(o);

    ctc_chain_spec open = *spec;
    open.loop = NULL;
    open.independent = NULL;
    /* the open chain's M and h; a massless tip that only the closure holds makes the open chain's
       M singular, which its builder refuses, so then the loop model's chain (the same bodies and
       coordinates: CRBA and RNEA ignore the closing joint) */
    if (ctc_model_build(&open, &o->open, NULL, 0) != CTC_OK &&
        ctc_model_build(spec, &o->open, NULL, 0) != CTC_OK)
        goto fail;
    if ((o->rb = ctc_oracle_new(o->open)) == NULL) goto fail;

    int nv = o->dims.nv, big = nv + LO_MAX_ROWS;
    o->rot = calloc((size_t)n * 9, sizeof(double));
    o->pos = calloc((size_t)n * 3, sizeof(double));
    o->axis = calloc((size_t)n * 3, sizeof(double));
    o->omega = calloc((size_t)n * 3, sizeof(double));
    o->vel = calloc((size_t)n * 3, sizeof(double));
    o->alpha0 = calloc((size_t)n * 3, sizeof(double));
    o->acc0 = calloc((size_t)n * 3, sizeof(double));
    o->jac = calloc((size_t)6 * nv + 1, sizeof(double));
    o->jacb = calloc((size_t)6 * nv + 1, sizeof(double));
    o->mass = calloc((size_t)nv * nv + 1, sizeof(double));
    o->h = calloc((size_t)nv + 1, sizeof(double));
    o->g = calloc((size_t)LO_MAX_ROWS * nv + 1, sizeof(double));
    o->gamma = calloc(LO_MAX_ROWS, sizeof(double));
    o->cmap = calloc((size_t)3 * nv + 1, sizeof(double));
    o->big = calloc((size_t)big * big, sizeof(double));
    o->rhs = calloc((size_t)big, sizeof(double));
    if (!o->rot || !o->pos || !o->axis || !o->omega || !o->vel || !o->alpha0 || !o->acc0 ||
        !o->jac || !o->jacb || !o->mass || !o->h || !o->g || !o->gamma || !o->cmap || !o->big ||
        !o->rhs)
        goto fail;
    return o;
fail:
    loop_oracle_free(o);
    return NULL;
}

void loop_oracle_free(loop_oracle *o)
{
    if (o == NULL) return;
    ctc_oracle_free(o->rb);
    ctc_model_free(o->open);
    free(o->bodies), free(o->joints), free(o->indep), free(o->qadr), free(o->vadr);
    free(o->parent);
    free(o->rot), free(o->pos), free(o->axis), free(o->omega), free(o->vel);
    free(o->alpha0), free(o->acc0), free(o->jac), free(o->jacb), free(o->mass), free(o->h),
        free(o->g);
    free(o->gamma), free(o->cmap), free(o->big), free(o->rhs);
    free(o);
}

const loop_oracle_dims *loop_oracle_get_dims(const loop_oracle *o)
{
    return &o->dims;
}

/* ---- kinematics ---- */

/* jac (6 x nv): the unit twists at the point p of the coordinates of the joints from the ground
 * to body last (body last's and its ancestors'; zero columns for the others), from the
 * kinematics in o */
static void point_jacobian(const loop_oracle *o, int last, const double p[3], double *jac)
{
    int nv = o->dims.nv;
    memset(jac, 0, (size_t)6 * nv * sizeof(double));
    for (int k = last; k >= 0; k = o->parent[k]) {
        const ctc_joint_spec *j = &o->joints[k];
        const double *uk = o->axis + 3 * k, *pk = o->pos + 3 * k, *rk = o->rot + 9 * k;
        double d[3] = {p[0] - pk[0], p[1] - pk[1], p[2] - pk[2]}, lin[3];
        int c0 = o->vadr[k];
        switch (j->type) {
        case CTC_JOINT_REVOLUTE:
        case CTC_JOINT_CYLINDRICAL:
            v3_cross(lin, uk, d);
            for (int i = 0; i < 3; i++) {
                jac[i * nv + c0] = uk[i];
                jac[(3 + i) * nv + c0] = lin[i];
            }
            if (j->type == CTC_JOINT_CYLINDRICAL)
                for (int i = 0; i < 3; i++) jac[(3 + i) * nv + c0 + 1] = uk[i];
            break;
        case CTC_JOINT_PRISMATIC:
            for (int i = 0; i < 3; i++) jac[(3 + i) * nv + c0] = uk[i];
            break;
        case CTC_JOINT_SPHERICAL:
            for (int c = 0; c < 3; c++) {
                double e[3] = {rk[c], rk[3 + c], rk[6 + c]}; /* column c of R_k */
                v3_cross(lin, e, d);
                for (int i = 0; i < 3; i++) {
                    jac[i * nv + c0 + c] = e[i];
                    jac[(3 + i) * nv + c0 + c] = lin[i];
                }
            }
            break;
        case CTC_JOINT_FIXED:
            break;
        }
    }
}

/* poses, velocities, bias accelerations (v' = 0) of every body, the tip point's motion, J
 * and the same of the closing joint's child */
static void kinematics(loop_oracle *o, const double *q, const double *v)
{
    int n = o->dims.n, nv = o->dims.nv;
    const double ident[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1}, zero[3] = {0, 0, 0};
    for (int k = 0; k < n; k++) {
        const ctc_joint_spec *j = &o->joints[k];
        const double *qk = q + o->qadr[k];
        const double *vk = v ? v + o->vadr[k] : NULL;
        const int pa = o->parent[k];
        const double *rp = pa >= 0 ? o->rot + 9 * pa : ident;
        const double *pp = pa >= 0 ? o->pos + 3 * pa : zero;
        const double *wp = pa >= 0 ? o->omega + 3 * pa : zero;
        const double *vp = pa >= 0 ? o->vel + 3 * pa : zero;
        const double *ap = pa >= 0 ? o->alpha0 + 3 * pa : zero;
        const double *lp = pa >= 0 ? o->acc0 + 3 * pa : zero;
        double *rk = o->rot + 9 * k, *pk = o->pos + 3 * k, *uk = o->axis + 3 * k;
        double *wk = o->omega + 3 * k, *vel = o->vel + 3 * k;
        double *ak = o->alpha0 + 3 * k, *lk = o->acc0 + 3 * k;
        double rj[9], loc[3], wrel[3] = {0, 0, 0}, slide = 0, sdot = 0;
        memcpy(rj, ident, sizeof rj);
        memcpy(loc, j->location, sizeof loc);
        test_m3_mulv(uk, rp, j->axis);
        switch (j->type) {
        case CTC_JOINT_REVOLUTE:
            test_m3_rot(rj, j->axis, qk[0]);
            if (vk)
                for (int i = 0; i < 3; i++) wrel[i] = uk[i] * vk[0];
            break;
        case CTC_JOINT_PRISMATIC:
            slide = qk[0], sdot = vk ? vk[0] : 0;
            break;
        case CTC_JOINT_CYLINDRICAL:
            test_m3_rot(rj, j->axis, qk[0]);
            slide = qk[1], sdot = vk ? vk[1] : 0;
            if (vk)
                for (int i = 0; i < 3; i++) wrel[i] = uk[i] * vk[0];
            break;
        case CTC_JOINT_SPHERICAL:
            m3_quat(rj, qk);
            break;
        case CTC_JOINT_FIXED:
            break;
        }
        for (int i = 0; i < 3; i++) loc[i] += j->axis[i] * slide;
        test_m3_mul(rk, rp, rj);
        test_m3_mulv(pk, rp, loc);
        for (int i = 0; i < 3; i++) pk[i] += pp[i];
        if (j->type == CTC_JOINT_SPHERICAL && vk) test_m3_mulv(wrel, rk, vk);

        /* velocities: omega_k = omega_p + w_rel; pdot_k = pdot_p + omega_p x r + u sdot */
        double r[3] = {pk[0] - pp[0], pk[1] - pp[1], pk[2] - pp[2]}, t[3], t2[3];
        for (int i = 0; i < 3; i++) wk[i] = wp[i] + wrel[i];
        v3_cross(t, wp, r);
        for (int i = 0; i < 3; i++) vel[i] = vp[i] + t[i] + uk[i] * sdot;

        /* accelerations at v' = 0: alpha_k = alpha_p + omega_p x w_rel;
           a_k = a_p + alpha_p x r + omega_p x (omega_p x r) + 2 omega_p x u sdot */
        v3_cross(t, wp, wrel);
        for (int i = 0; i < 3; i++) ak[i] = ap[i] + t[i];
        v3_cross(t, ap, r);
        for (int i = 0; i < 3; i++) lk[i] = lp[i] + t[i];
        v3_cross(t, wp, r);
        v3_cross(t2, wp, t);
        for (int i = 0; i < 3; i++) lk[i] += t2[i];
        v3_cross(t, wp, uk);
        for (int i = 0; i < 3; i++) lk[i] += 2 * t[i] * sdot;
    }

    /* the tip point */
    const double *rt = o->rot + 9 * (n - 1), *ot = o->pos + 3 * (n - 1);
    const double *wt = o->omega + 3 * (n - 1), *at = o->alpha0 + 3 * (n - 1);
    double r[3], t[3], t2[3];
    test_m3_mulv(r, rt, o->joints[n].location);
    for (int i = 0; i < 3; i++) o->pt[i] = ot[i] + r[i];
    v3_cross(t, wt, r);
    for (int i = 0; i < 3; i++) o->vt[i] = o->vel[3 * (n - 1) + i] + t[i];
    v3_cross(t, at, r);
    v3_cross(t2, wt, r);
    double t3[3];
    v3_cross(t3, wt, t2);
    for (int i = 0; i < 3; i++) o->at0[i] = o->acc0[3 * (n - 1) + i] + t[i] + t3[i];

    point_jacobian(o, n - 1, o->pt, o->jac);

    /* the closing joint's child */
    memset(o->wa, 0, sizeof o->wa), memset(o->alpha0a, 0, sizeof o->alpha0a);
    memset(o->va, 0, sizeof o->va), memset(o->aa0, 0, sizeof o->aa0);
    memcpy(o->ra, ident, sizeof o->ra);
    memcpy(o->pa, o->anchor, sizeof o->pa);
    memset(o->jacb, 0, (size_t)6 * nv * sizeof(double));
    if (o->body < 0) return;
    const int b = o->body;
    memcpy(o->ra, o->rot + 9 * b, sizeof o->ra);
    memcpy(o->wa, o->omega + 3 * b, sizeof o->wa);
    memcpy(o->alpha0a, o->alpha0 + 3 * b, sizeof o->alpha0a);
    test_m3_mulv(r, o->ra, o->anchor);
    for (int i = 0; i < 3; i++) o->pa[i] = o->pos[3 * b + i] + r[i];
    v3_cross(t, o->wa, r);
    for (int i = 0; i < 3; i++) o->va[i] = o->vel[3 * b + i] + t[i];
    v3_cross(t, o->alpha0a, r);
    v3_cross(t2, o->wa, r);
    v3_cross(t3, o->wa, t2);
    for (int i = 0; i < 3; i++) o->aa0[i] = o->acc0[3 * b + i] + t[i] + t3[i];
    point_jacobian(o, b, o->pa, o->jacb);
}

void loop_oracle_tip(loop_oracle *o, const double *q, const double *v, double pt[3], double rt[9],
                     double vt[3], double omega_t[3])
{
    int n = o->dims.n;
    kinematics(o, q, v);
    memcpy(pt, o->pt, 3 * sizeof(double));
    if (rt) memcpy(rt, o->rot + 9 * (n - 1), 9 * sizeof(double));
    if (vt) memcpy(vt, o->vt, 3 * sizeof(double));
    if (omega_t) memcpy(omega_t, o->omega + 3 * (n - 1), 3 * sizeof(double));
}

void loop_oracle_residual(loop_oracle *o, const double *q, double *phi)
{
    kinematics(o, q, NULL);
    const double *rt = o->rot + 9 * (o->dims.n - 1);
    for (int i = 0; i < o->dims.nc; i++) {
        const lo_row *r = &o->rows[i];
        double w[3], c[3];
        test_m3_mulv(c, o->ra, r->c);
        if (r->rotational) {
            test_m3_mulv(w, rt, r->b);
            phi[i] = v3_dot(c, w);
        } else {
            double d[3] = {o->pt[0] - o->pa[0], o->pt[1] - o->pa[1], o->pt[2] - o->pa[2]};
            phi[i] = v3_dot(c, d);
        }
    }
}

/* y (nv) = a^T jac's angular (row0 = 0) or linear (row0 = 3) rows, added with sign s */
static void add_rows(const loop_oracle *o, const double *jac, int row0, const double a[3], double s,
                     double *y)
{
    int nv = o->dims.nv;
    for (int c = 0; c < nv; c++) {
        y[c] += s * (a[0] * jac[row0 * nv + c] + a[1] * jac[(row0 + 1) * nv + c] +
                     a[2] * jac[(row0 + 2) * nv + c]);
    }
}

/* G and gamma from the kinematics already in o (v given to kinematics, or zero). With c = R_a c0
 * turning with the child (w_a):
 *   linear      phi = c . r, r = p_t - p_a:  d phi/dt = c . (v_t - v_a) + (c x r) . w_a,
 *               gamma = c . (a0_t - a0_a) + (c x r) . alpha0_a + (w_a x c) . rd
 *                       + w_a . ((w_a x c) x r + c x rd),  rd = v_t - v_a;
 *   rotational  phi = c . w, w = R_t b:       d phi/dt = (w x c) . (w_t - w_a),
 *               gamma = (w x c) . (alpha0_t - alpha0_a)
 *                       + ((w_t x w) x c + w x (w_a x c)) . (w_t - w_a). */
static void jacobian_from_kinematics(loop_oracle *o, double *g, double *gamma)
{
    int n = o->dims.n, nv = o->dims.nv;
    const double *rt = o->rot + 9 * (n - 1), *wt = o->omega + 3 * (n - 1);
    const double *at = o->alpha0 + 3 * (n - 1), *wa = o->wa;
    double wrel[3] = {wt[0] - wa[0], wt[1] - wa[1], wt[2] - wa[2]};
    for (int i = 0; i < o->dims.nc; i++) {
        const lo_row *r = &o->rows[i];
        double *gi = g + (size_t)i * nv, c[3], wc[3], t[3], t2[3];
        memset(gi, 0, (size_t)nv * sizeof *gi);
        test_m3_mulv(c, o->ra, r->c);
        v3_cross(wc, wa, c); /* dc/dt */
        if (r->rotational) {
            double w[3], a[3];
            test_m3_mulv(w, rt, r->b);
            v3_cross(a, w, c);
            add_rows(o, o->jac, 0, a, 1, gi);
            add_rows(o, o->jacb, 0, a, -1, gi);
            if (gamma) {
                double arel[3] = {at[0] - o->alpha0a[0], at[1] - o->alpha0a[1],
                                  at[2] - o->alpha0a[2]};
                v3_cross(t, wt, w);
                v3_cross(t2, t, c);
                v3_cross(t, w, wc);
                for (int k = 0; k < 3; k++) t2[k] += t[k];
                gamma[i] = v3_dot(a, arel) + v3_dot(t2, wrel);
            }
        } else {
            double rr[3] = {o->pt[0] - o->pa[0], o->pt[1] - o->pa[1], o->pt[2] - o->pa[2]};
            double rd[3] = {o->vt[0] - o->va[0], o->vt[1] - o->va[1], o->vt[2] - o->va[2]};
            double cr[3];
            v3_cross(cr, c, rr);
            add_rows(o, o->jac, 3, c, 1, gi);
            add_rows(o, o->jacb, 3, c, -1, gi);
            add_rows(o, o->jacb, 0, cr, 1, gi);
            if (gamma) {
                double da[3] = {o->at0[0] - o->aa0[0], o->at0[1] - o->aa0[1],
                                o->at0[2] - o->aa0[2]};
                v3_cross(t, wc, rr);
                v3_cross(t2, c, rd);
                for (int k = 0; k < 3; k++) t[k] += t2[k];
                gamma[i] = v3_dot(c, da) + v3_dot(cr, o->alpha0a) + v3_dot(wc, rd) + v3_dot(wa, t);
            }
        }
    }
}

void loop_oracle_jacobian(loop_oracle *o, const double *q, const double *v, double *g,
                          double *gamma)
{
    kinematics(o, q, v);
    jacobian_from_kinematics(o, g, gamma);
}

/* C and c_b from the kinematics in o. With w = R_t a, the child's angular velocity w_a, its
 * point velocity v_b(p_t) = v_a + w_a x (p_t - p_a) and a0_b(p_t) at v' = 0 likewise:
 *   revolute    qd_n = w . (w_a - w_t),        c_b = w . (alpha0_a - alpha0_t) + (w_t x w) . (w_a -
 * w_t) prismatic   qd_n = w . (v_b(p_t) - v_t),   c_b = (w_t x w) . (v_b(p_t) - v_t)
 *               + w . (a0_a + alpha0_a x (p_t - p_a) + w_a x (v_t - v_a) - a0_t)
 *   spherical   qd_n = R_a^T (w_a - w_t),      c_b = R_a^T (alpha0_a - alpha0_t - w_a x (w_a -
 * w_t)) (on the ground w_a, v_a, alpha0_a and a0_a vanish and R_a = 1). */
static void closing_from_kinematics(loop_oracle *o, double *cmap, double *cb, double *qn)
{
    int n = o->dims.n, nv = o->dims.nv, nvn = o->dims.nvn;
    const ctc_joint_spec *jn = &o->joints[n];
    const double *rt = o->rot + 9 * (n - 1), *wt = o->omega + 3 * (n - 1);
    const double *at = o->alpha0 + 3 * (n - 1), *wa = o->wa;
    double w[3], wrel[3] = {wa[0] - wt[0], wa[1] - wt[1], wa[2] - wt[2]}, t[3];
    double arel[3] = {o->alpha0a[0] - at[0], o->alpha0a[1] - at[1], o->alpha0a[2] - at[2]};
    test_m3_mulv(w, rt, jn->axis);
    if (qn) memset(qn, 0, (size_t)o->dims.nqn * sizeof(double));
    memset(cmap, 0, (size_t)nv * nvn * sizeof(double));
    switch (jn->type) {
    case CTC_JOINT_REVOLUTE:
        add_rows(o, o->jacb, 0, w, 1, cmap);
        add_rows(o, o->jac, 0, w, -1, cmap);
        v3_cross(t, wt, w);
        cb[0] = v3_dot(w, arel) + v3_dot(t, wrel);
        if (qn) {
            /* R_t^T R_a = Rot(a, q_n): minus the angle of R_a^T R_t about a, from a unit normal p
             */
            double p1[3], p2[3], rp[3], x[3];
            v3_normals(jn->axis, p1, p2);
            test_m3_mulv(x, rt, p1);
            for (int i = 0; i < 3; i++) /* R_a^T x */
                rp[i] = o->ra[i] * x[0] + o->ra[3 + i] * x[1] + o->ra[6 + i] * x[2];
            v3_cross(x, p1, rp);
            qn[0] = -atan2(v3_dot(jn->axis, x), v3_dot(p1, rp));
        }
        break;
    case CTC_JOINT_PRISMATIC: {
        double r[3] = {o->pt[0] - o->pa[0], o->pt[1] - o->pa[1], o->pt[2] - o->pa[2]};
        double vb[3], ab[3],
            rd[3] = {o->vt[0] - o->va[0], o->vt[1] - o->va[1], o->vt[2] - o->va[2]};
        double wr[3];
        v3_cross(t, wa, r);
        for (int i = 0; i < 3; i++) vb[i] = o->va[i] + t[i] - o->vt[i]; /* v_b(p_t) - v_t */
        v3_cross(wr, r, w); /* w . (x x r) = (r x w) . x */
        add_rows(o, o->jacb, 3, w, 1, cmap);
        add_rows(o, o->jacb, 0, wr, 1, cmap);
        add_rows(o, o->jac, 3, w, -1, cmap);
        v3_cross(t, o->alpha0a, r);
        for (int i = 0; i < 3; i++) ab[i] = o->aa0[i] + t[i] - o->at0[i];
        v3_cross(t, wa, rd);
        for (int i = 0; i < 3; i++) ab[i] += t[i];
        v3_cross(t, wt, w);
        cb[0] = v3_dot(t, vb) + v3_dot(w, ab);
        if (qn) {
            double d[3] = {o->pa[0] - o->pt[0], o->pa[1] - o->pt[1], o->pa[2] - o->pt[2]};
            qn[0] = v3_dot(d, w);
        }
        break;
    }
    default: { /* spherical: qd_n = R_a^T (w_a - w_t), in the child's frame */
        double x[3];
        v3_cross(t, wa, wrel);
        for (int i = 0; i < 3; i++) x[i] = arel[i] - t[i];
        for (int i = 0; i < 3; i++) {
            const double e[3] = {o->ra[i], o->ra[3 + i], o->ra[6 + i]}; /* column i of R_a */
            for (int c = 0; c < nv; c++) {
                double s = 0;
                for (int k = 0; k < 3; k++) s += e[k] * (o->jacb[k * nv + c] - o->jac[k * nv + c]);
                cmap[c * nvn + i] = s;
            }
            cb[i] = v3_dot(e, x);
        }
        break;
    }
    }
}

void loop_oracle_closing(loop_oracle *o, const double *q, const double *v, double *cmap, double *cb,
                         double *qn)
{
    kinematics(o, q, v);
    closing_from_kinematics(o, cmap, cb, qn);
}

void loop_oracle_mass_bias(loop_oracle *o, const double *q, const double *v, double *mass,
                           double *h)
{
    int nv = o->dims.nv;
    double *zero = o->rhs; /* nv + 6 entries */
    memset(zero, 0, (size_t)nv * sizeof(double));
    if (mass) ctc_oracle_mass_matrix(o->open, o->rb, q, mass);
    if (h) ctc_oracle_rnea(o->open, o->rb, q, v, zero, h);
}

void loop_oracle_energy(loop_oracle *o, const double *q, const double *v, double *kinetic,
                        double *potential)
{
    int n = o->dims.n, nv = o->dims.nv;
    ctc_oracle_mass_matrix(o->open, o->rb, q, o->mass);
    double ke = 0;
    for (int a = 0; a < nv; a++)
        for (int b = 0; b < nv; b++) ke += 0.5 * v[a] * o->mass[a * nv + b] * v[b];
    kinematics(o, q, NULL);
    double pe = 0;
    for (int k = 0; k < n; k++) {
        double c[3];
        test_m3_mulv(c, o->rot + 9 * k, o->bodies[k].com);
        for (int i = 0; i < 3; i++) c[i] += o->pos[3 * k + i];
        pe -= o->bodies[k].mass * v3_dot(o->gravity, c);
    }
    *kinetic = ke;
    *potential = pe;
}

/* ---- dynamics ---- */

/* M, h, G, gamma, C, c_b at (q, v) into o's scratch */
static void dynamics_terms(loop_oracle *o, const double *q, const double *v, double *cb)
{
    loop_oracle_mass_bias(o, q, v, o->mass, o->h);
    kinematics(o, q, v);
    jacobian_from_kinematics(o, o->g, o->gamma);
    closing_from_kinematics(o, o->cmap, cb, NULL);
}

int loop_oracle_forward(loop_oracle *o, const double *q, const double *v, const double *f,
                        double *qacc, double *lambda)
{
    int n = o->dims.n, nv = o->dims.nv, nc = o->dims.nc, nvn = o->dims.nvn, s = nv + nc;
    double cb[3];
    dynamics_terms(o, q, v, cb);

    /* [M G^T; G 0] [qdd; mu] = [tau - h; -gamma], lambda = -mu */
    double *a = o->big, *b = o->rhs;
    memset(a, 0, (size_t)s * s * sizeof(double));
    for (int i = 0; i < nv; i++) {
        for (int j = 0; j < nv; j++) a[i * s + j] = o->mass[i * nv + j];
        for (int r = 0; r < nc; r++) a[i * s + nv + r] = a[(nv + r) * s + i] = o->g[r * nv + i];
    }
    for (int k = 0; k < n; k++)
        for (int c = 0; c < type_nv(o->joints[k].type); c++) {
            int i = o->vadr[k] + c;
            b[i] = (o->indep[k] ? f[i] : 0) - o->h[i];
        }
    if (o->indep[n])
        for (int i = 0; i < nv; i++)
            for (int c = 0; c < nvn; c++) b[i] += o->cmap[i * nvn + c] * f[nv + c];
    for (int r = 0; r < nc; r++) b[nv + r] = -o->gamma[r];
    if (loop_oracle_lu_solve(a, s, b) != 0) return -1;
    for (int i = 0; i < nv; i++) qacc[i] = b[i];
    for (int c = 0; c < nvn; c++) {
        double x = cb[c];
        for (int i = 0; i < nv; i++) x += o->cmap[i * nvn + c] * b[i];
        qacc[nv + c] = x;
    }
    if (lambda)
        for (int r = 0; r < nc; r++) lambda[r] = -b[nv + r];
    return 0;
}

int loop_oracle_inverse(loop_oracle *o, const double *q, const double *v, const double *u,
                        double *f, double *qacc)
{
    int n = o->dims.n, nv = o->dims.nv, nc = o->dims.nc, nvn = o->dims.nvn;
    double cb[3];
    dynamics_terms(o, q, v, cb);
    double *a = o->big, *b = o->rhs;
    double *qdd = calloc((size_t)nv + 1, sizeof(double));
    if (qdd == NULL) return -1;

    /* 1. kinematics: G qdd = -gamma; qdd_i = u_i (independent chain coordinates);
          C^T qdd = u_n - c_b (independent closing joint) */
    int rows = 0;
    memset(a, 0, (size_t)nv * nv * sizeof(double));
    for (int r = 0; r < nc && rows < nv; r++, rows++) {
        for (int j = 0; j < nv; j++) a[rows * nv + j] = o->g[r * nv + j];
        b[rows] = -o->gamma[r];
    }
    for (int k = 0; k <= n; k++) {
        if (!o->indep[k]) continue;
        int nvk = k < n ? type_nv(o->joints[k].type) : nvn;
        for (int c = 0; c < nvk; c++) {
            if (rows >= nv) goto singular; /* more conditions than coordinates */
            if (k < n) {
                a[rows * nv + o->vadr[k] + c] = 1;
                b[rows] = u[o->vadr[k] + c];
            } else {
                for (int j = 0; j < nv; j++) a[rows * nv + j] = o->cmap[j * nvn + c];
                b[rows] = u[nv + c] - cb[c];
            }
            rows++;
        }
    }
    if (rows != nv || loop_oracle_lu_solve(a, nv, b) != 0) goto singular;
    memcpy(qdd, b, (size_t)nv * sizeof(double));

    /* 2. dynamics: columns e_i (independent chain coordinates), C (independent closing joint),
          G^T; right-hand side M qdd + h */
    int cols = 0;
    memset(a, 0, (size_t)nv * nv * sizeof(double));
    for (int k = 0; k <= n; k++) {
        if (!o->indep[k]) continue;
        int nvk = k < n ? type_nv(o->joints[k].type) : nvn;
        for (int c = 0; c < nvk; c++, cols++) {
            if (k < n) {
                a[(o->vadr[k] + c) * nv + cols] = 1;
            } else {
                for (int j = 0; j < nv; j++) a[j * nv + cols] = o->cmap[j * nvn + c];
            }
        }
    }
    for (int r = 0; r < nc; r++, cols++)
        for (int j = 0; j < nv; j++) a[j * nv + cols] = o->g[r * nv + j];
    for (int i = 0; i < nv; i++) {
        double s = o->h[i];
        for (int j = 0; j < nv; j++) s += o->mass[i * nv + j] * qdd[j];
        b[i] = s;
    }
    if (cols != nv || loop_oracle_lu_solve(a, nv, b) != 0) goto singular;

    memset(f, 0, (size_t)o->dims.nvx * sizeof(double));
    cols = 0;
    for (int k = 0; k <= n; k++) {
        if (!o->indep[k]) continue;
        int nvk = k < n ? type_nv(o->joints[k].type) : nvn;
        for (int c = 0; c < nvk; c++, cols++) f[k < n ? o->vadr[k] + c : nv + c] = b[cols];
    }
    if (qacc) {
        memcpy(qacc, qdd, (size_t)nv * sizeof(double));
        for (int c = 0; c < nvn; c++) {
            double x = cb[c];
            for (int i = 0; i < nv; i++) x += o->cmap[i * nvn + c] * qdd[i];
            qacc[nv + c] = x;
        }
    }
    free(qdd);
    return 0;
singular:
    free(qdd);
    return -1;
}

/* ---- assembly ---- */

void loop_oracle_q_add(const loop_oracle *o, double *q, const double *dv, double s)
{
    for (int k = 0; k < o->dims.n; k++) {
        double *qk = q + o->qadr[k];
        const double *dk = dv + o->vadr[k];
        if (o->joints[k].type != CTC_JOINT_SPHERICAL) {
            for (int i = 0; i < type_nv(o->joints[k].type); i++) qk[i] += s * dk[i];
            continue;
        }
        double d[3] = {s * dk[0], s * dk[1], s * dk[2]};
        double th = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        double sh = th > 0 ? sin(th / 2) / th : 0.5;
        double e[4] = {cos(th / 2), sh * d[0], sh * d[1], sh * d[2]}, a[4];
        memcpy(a, qk, sizeof a);
        qk[0] = a[0] * e[0] - a[1] * e[1] - a[2] * e[2] - a[3] * e[3];
        qk[1] = a[0] * e[1] + a[1] * e[0] + a[2] * e[3] - a[3] * e[2];
        qk[2] = a[0] * e[2] - a[1] * e[3] + a[2] * e[0] + a[3] * e[1];
        qk[3] = a[0] * e[3] + a[1] * e[2] - a[2] * e[1] + a[3] * e[0];
        double nrm = sqrt(qk[0] * qk[0] + qk[1] * qk[1] + qk[2] * qk[2] + qk[3] * qk[3]);
        for (int i = 0; i < 4; i++) qk[i] /= nrm;
    }
}

/* least-norm x (dependent chain coordinates only) of G_d x = r: x = G_d^T (G_d G_d^T)^-1 r */
static int least_norm(loop_oracle *o, const double *g, const unsigned char *dep, const double *r,
                      double *x)
{
    int nv = o->dims.nv, nc = o->dims.nc;
    double a[LO_MAX_ROWS * LO_MAX_ROWS], y[LO_MAX_ROWS];
    for (int i = 0; i < nc; i++) {
        y[i] = r[i];
        for (int j = 0; j < nc; j++) {
            double s = 0;
            for (int c = 0; c < nv; c++)
                if (dep[c]) s += g[i * nv + c] * g[j * nv + c];
            a[i * nc + j] = s;
        }
    }
    if (loop_oracle_lu_solve(a, nc, y) != 0) return -1;
    for (int c = 0; c < nv; c++) {
        double s = 0;
        for (int i = 0; dep[c] && i < nc; i++) s += g[i * nv + c] * y[i];
        x[c] = s;
    }
    return 0;
}

int loop_oracle_assemble(loop_oracle *o, double *q, double *v, double tol, int max_iter)
{
    int n = o->dims.n, nv = o->dims.nv, nc = o->dims.nc, it = 0, ok = -1;
    unsigned char *dep = calloc((size_t)nv + 1, 1);
    double *dq = calloc((size_t)nv + 1, sizeof(double)), phi[LO_MAX_ROWS];
    if (dep == NULL || dq == NULL) goto done;
    for (int k = 0; k < n; k++)
        for (int c = 0; c < type_nv(o->joints[k].type); c++) dep[o->vadr[k] + c] = !o->indep[k];
    for (;; it++) {
        loop_oracle_residual(o, q, phi);
        double res = 0;
        for (int i = 0; i < nc; i++) res = fmax(res, fabs(phi[i]));
        if (res < tol) break;
        if (it >= max_iter) goto done;
        for (int i = 0; i < nc; i++) phi[i] = -phi[i];
        loop_oracle_jacobian(o, q, NULL, o->g, NULL);
        if (least_norm(o, o->g, dep, phi, dq) != 0) goto done;
        loop_oracle_q_add(o, q, dq, 1.0);
    }
    if (v) {
        /* G_d v_d = -G_i v_i */
        double r[LO_MAX_ROWS];
        loop_oracle_jacobian(o, q, NULL, o->g, NULL);
        for (int i = 0; i < nc; i++) {
            double s = 0;
            for (int c = 0; c < nv; c++)
                if (!dep[c]) s += o->g[i * nv + c] * v[c];
            r[i] = -s;
        }
        if (least_norm(o, o->g, dep, r, dq) != 0) goto done;
        for (int c = 0; c < nv; c++)
            if (dep[c]) v[c] = dq[c];
    }
    ok = it;
done:
    free(dep);
    free(dq);
    return ok;
}

/* ---- test loops ---- */

#define LO_PI 3.14159265358979323846

static loop_scene *scene_alloc(int n, double gx, double gy, double gz, ctc_form form)
{
    loop_scene *s = calloc(1, sizeof *s);
    if (s == NULL) abort();
    s->spec.nbodies = n;
    s->spec.bodies = s->bodies;
    s->spec.joints = s->joints;
    s->spec.loop = &s->loop;
    s->spec.independent = s->independent;
    s->spec.parent = s->parent;
    for (int k = 0; k < n; k++) s->parent[k] = k - 1;
    s->spec.gravity[0] = gx, s->spec.gravity[1] = gy, s->spec.gravity[2] = gz;
    s->spec.form = form;
    return s;
}

/* counts the chain's coordinates into s->nq, s->nv */
static void scene_count(loop_scene *s)
{
    s->nq = s->nv = 0;
    for (int k = 0; k < s->spec.nbodies; k++) {
        s->nq += type_nq(s->joints[k].type);
        s->nv += type_nv(s->joints[k].type);
    }
}

/* a planar chain of rods (or thin boxes) of lengths len hanging along -y, revolute about +z,
   the closing revolute joint at the tip's far end */
static loop_scene *planar_rods(int n, const double *len, const double *mass, int boxes)
{
    loop_scene *s = scene_alloc(n, 0, -9.81, 0, boxes ? CTC_FORM_SPATIAL : CTC_FORM_AUTO);
    for (int k = 0; k < n; k++) {
        double end[3] = {0, -len[k], 0}, size[3] = {0.05, len[k], 0.05},
               centre[3] = {0, -len[k] / 2, 0};
        s->joints[k] = (ctc_joint_spec){.type = CTC_JOINT_REVOLUTE, .axis = {0, 0, 1}};
        if (k) s->joints[k].location[1] = -len[k - 1];
        if (boxes)
            ctc_shape_box(mass[k], size, centre, &s->bodies[k], NULL, 0);
        else
            ctc_shape_rod(mass[k], end, &s->bodies[k], NULL, 0);
    }
    s->loop.joint = (ctc_joint_spec){
        .type = CTC_JOINT_REVOLUTE, .axis = {0, 0, 1}, .location = {0, -len[n - 1], 0}};
    scene_count(s);
    return s;
}

/* absolute angle (from -y, counterclockwise) of the direction d */
static double angle_of(double dx, double dy)
{
    return atan2(dx, -dy);
}

loop_scene *loop_scene_five_bar(void)
{
    const double len[5] = {1, 1, 0.5, 1, 1}, mass[5] = {1, 1, 1, 1, 1};
    const double q0[5] = {-LO_PI / 8, 5 * LO_PI / 8, 3 * LO_PI / 8, 3 * LO_PI / 8, 5 * LO_PI / 8};
    loop_scene *s = planar_rods(5, len, mass, 0);
    double th = 0, x = 0, y = 0;
    for (int k = 0; k < 5; k++) {
        th += q0[k];
        x += len[k] * sin(th), y -= len[k] * cos(th);
        s->q0[k] = q0[k];
    }
    s->loop.anchor[0] = x, s->loop.anchor[1] = y;
    for (int k = 0; k < 6; k++) s->independent[k] = k < 3;
    return s;
}

loop_scene *loop_scene_four_bar(double theta1, int spatial)
{
    const double len[3] = {0.5, 1.2, 1.0}, mass[3] = {1, 1, 1}, ax = 1, ay = 0;
    loop_scene *s = planar_rods(3, len, mass, spatial);
    s->loop.anchor[0] = ax, s->loop.anchor[1] = ay;
    double p1x = len[0] * sin(theta1), p1y = -len[0] * cos(theta1);
    double dx = ax - p1x, dy = ay - p1y, d = hypot(dx, dy);
    double a = (len[1] * len[1] - len[2] * len[2] + d * d) / (2 * d);
    double h = sqrt(len[1] * len[1] - a * a);
    double p2x = p1x + (a * dx - h * dy) / d, p2y = p1y + (a * dy + h * dx) / d;
    double phi2 = angle_of(p2x - p1x, p2y - p1y), phi3 = angle_of(ax - p2x, ay - p2y);
    s->q0[0] = theta1, s->q0[1] = phi2 - theta1, s->q0[2] = phi3 - phi2;
    s->independent[0] = 1;
    return s;
}

loop_scene *loop_scene_parallelogram(double theta)
{
    const double len[3] = {1, 1, 1}, mass[3] = {1, 1, 1};
    loop_scene *s = planar_rods(3, len, mass, 0);
    s->loop.anchor[0] = 1;
    s->q0[0] = theta, s->q0[1] = LO_PI / 2 - theta, s->q0[2] = theta + LO_PI / 2;
    s->independent[0] = 1;
    return s;
}

loop_scene *loop_scene_slider_crank(double theta)
{
    const double r = 0.3, l = 1.0, ys = -0.2;
    loop_scene *s = scene_alloc(3, 0, -9.81, 0, CTC_FORM_AUTO);
    double end0[3] = {0, -r, 0}, end1[3] = {0, -l, 0};
    s->joints[0] = (ctc_joint_spec){.type = CTC_JOINT_REVOLUTE, .axis = {0, 0, 1}};
    s->joints[1] =
        (ctc_joint_spec){.type = CTC_JOINT_REVOLUTE, .axis = {0, 0, 1}, .location = {0, -r, 0}};
    s->joints[2] =
        (ctc_joint_spec){.type = CTC_JOINT_REVOLUTE, .axis = {0, 0, 1}, .location = {0, -l, 0}};
    ctc_shape_rod(1, end0, &s->bodies[0], NULL, 0);
    ctc_shape_rod(1, end1, &s->bodies[1], NULL, 0);
    s->bodies[2] = (ctc_body_spec){.mass = 0.5, .inertia = {0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.01}};
    s->loop.joint = (ctc_joint_spec){.type = CTC_JOINT_PRISMATIC, .axis = {1, 0, 0}};
    s->loop.anchor[1] = ys;
    double p1x = r * sin(theta), p1y = -r * cos(theta);
    double p2x = p1x + sqrt(l * l - (p1y - ys) * (p1y - ys));
    double phi = angle_of(p2x - p1x, ys - p1y);
    s->q0[0] = theta, s->q0[1] = phi - theta, s->q0[2] = -phi;
    s->independent[0] = 1;
    scene_count(s);
    return s;
}

loop_scene *loop_scene_rssr(void)
{
    loop_scene *s = scene_alloc(3, 0, 0, -9.81, CTC_FORM_AUTO);
    const double b[3] = {0, 0.4, 0}, c[3] = {0.3, 0.5, 1.0}, axis[3] = {1, 0, -0.3};
    double t[3] = {c[0] - b[0], c[1] - b[1], c[2] - b[2]}, r[3], d[3];
    v3_cross(r, axis, t);
    double rn = v3_norm(r);
    for (int i = 0; i < 3; i++) d[i] = c[i] - 0.6 * r[i] / rn;
    /* crank O-B, coupler B-C, rocker C-D: 1 kg boxes centred on the links */
    const double *ends[4] = {NULL, b, c, d};
    const double zero[3] = {0, 0, 0};
    ends[0] = zero;
    for (int k = 0; k < 3; k++) {
        double link[3], centre[3], size[3];
        for (int i = 0; i < 3; i++) {
            link[i] = ends[k + 1][i] - ends[k][i];
            centre[i] = link[i] / 2;
            size[i] = fmax(0.08, fabs(link[i]));
        }
        ctc_shape_box(1, size, centre, &s->bodies[k], NULL, 0);
        if (k) {
            s->joints[k].type = CTC_JOINT_SPHERICAL;
            for (int i = 0; i < 3; i++) s->joints[k].location[i] = ends[k][i] - ends[k - 1][i];
        }
    }
    s->joints[0] = (ctc_joint_spec){.type = CTC_JOINT_REVOLUTE, .axis = {1, 0, 0}};
    s->loop.joint.type = CTC_JOINT_REVOLUTE;
    for (int i = 0; i < 3; i++) {
        s->loop.joint.axis[i] = axis[i];
        s->loop.joint.location[i] = d[i] - c[i];
        s->loop.anchor[i] = d[i];
    }
    s->q0[1] = 1, s->q0[5] = 1;
    s->independent[0] = s->independent[3] = 1;
    scene_count(s);
    return s;
}

loop_scene *loop_scene_rssp(void)
{
    loop_scene *s = scene_alloc(3, 0, 0, -9.81, CTC_FORM_AUTO);
    const double b[3] = {0, 0.4, 0}, c[3] = {0.3, 0.5, 1.0}, axis[3] = {0.3, 0.1, 1.0};
    const double sz0[3] = {0.05, 0.4, 0.05}, c0[3] = {0, 0.2, 0};
    const double sz1[3] = {0.3, 0.1, 1.0}, c1[3] = {0.15, 0.05, 0.5};
    const double sz2[3] = {0.2, 0.15, 0.1}, c2[3] = {0, 0, 0};
    ctc_shape_box(1, sz0, c0, &s->bodies[0], NULL, 0);
    ctc_shape_box(1, sz1, c1, &s->bodies[1], NULL, 0);
    ctc_shape_box(0.5, sz2, c2, &s->bodies[2], NULL, 0);
    s->joints[0] = (ctc_joint_spec){.type = CTC_JOINT_REVOLUTE, .axis = {1, 0, 0}};
    s->joints[1] = (ctc_joint_spec){.type = CTC_JOINT_SPHERICAL};
    s->joints[2] = (ctc_joint_spec){.type = CTC_JOINT_SPHERICAL};
    for (int i = 0; i < 3; i++) {
        s->joints[1].location[i] = b[i];
        s->joints[2].location[i] = c[i] - b[i];
        s->loop.anchor[i] = c[i];
    }
    s->loop.joint.type = CTC_JOINT_PRISMATIC;
    memcpy(s->loop.joint.axis, axis, sizeof axis);
    s->q0[1] = 1, s->q0[5] = 1;
    s->independent[0] = s->independent[3] = 1;
    scene_count(s);
    return s;
}

loop_scene *loop_scene_spatial(int n, ctc_joint_type closing, unsigned long long seed)
{
    uint64_t rng = seed;
    loop_scene *s = scene_alloc(n, 0, 0, -9.81, CTC_FORM_SPATIAL);
    double link[3] = {0, 0, 0};
    for (int k = 0; k < n; k++) {
        ctc_joint_spec *j = &s->joints[k];
        j->type = CTC_JOINT_REVOLUTE;
        test_random_unit(&rng, j->axis);
        for (int i = 0; i < 3; i++) j->location[i] = link[i];
        double dir[3], len = test_uniform(&rng, 0.3, 0.6);
        test_random_unit(&rng, dir);
        for (int i = 0; i < 3; i++) link[i] = len * dir[i];
        ctc_body_spec *b = &s->bodies[k];
        b->mass = test_uniform(&rng, 0.5, 2);
        for (int i = 0; i < 3; i++) b->com[i] = link[i] / 2 + test_uniform(&rng, -0.05, 0.05);
        test_random_inertia(&rng, 0.01, 0.1, b->inertia);
        for (int i = 0; i < 3; i++) s->loop.anchor[i] += j->location[i];
    }
    s->loop.joint.type = closing;
    test_random_unit(&rng, s->loop.joint.axis);
    for (int i = 0; i < 3; i++) {
        s->loop.joint.location[i] = link[i];
        s->loop.anchor[i] += link[i];
    }
    s->independent[0] = s->independent[n] = 1;
    scene_count(s);
    return s;
}

void loop_scene_close_on(loop_scene *s, int body)
{
    loop_oracle *o = loop_oracle_new(&s->spec);
    if (o == NULL || body < 0 || body > s->spec.nbodies - 2) abort();
    kinematics(o, s->q0, NULL);
    const double *rb = o->rot + 9 * body, *xb = o->pos + 3 * body;
    double d[3] = {o->pt[0] - xb[0], o->pt[1] - xb[1], o->pt[2] - xb[2]};
    for (int i = 0; i < 3; i++) /* R_b^T (p_t - x_b) */
        s->loop.anchor[i] = rb[i] * d[0] + rb[3 + i] * d[1] + rb[6 + i] * d[2];
    s->loop.on_body = 1;
    s->loop.body = body;
    loop_oracle_free(o);
}

void loop_scene_branch(loop_scene *s, int nb, const loop_branch *br)
{
    const int n = s->spec.nbodies, nt = n + nb, tip = nt - 1;
    if (nt > LOOP_SCENE_MAX) abort();
    int qtip = 0;
    for (int k = 0; k < n - 1; k++) qtip += type_nq(s->joints[k].type);
    const int nqtip = type_nq(s->joints[n - 1].type);
    double qt[4];
    memcpy(qt, s->q0 + qtip, (size_t)nqtip * sizeof *qt);
    unsigned char indep_tip = s->independent[n - 1], indep_close = s->independent[n];

    /* the tip and the closing joint move to the end */
    s->bodies[tip] = s->bodies[n - 1];
    s->joints[tip] = s->joints[n - 1];
    s->parent[tip] = n - 2;
    int q = qtip;
    for (int e = 0; e < nb; e++) {
        const int k = n - 1 + e;
        const loop_branch *b = &br[e];
        double size[3] = {0.1, 0.4, 0.12}, com[3] = {0, -0.2, 0};
        if (ctc_shape_box(0.6, size, com, &s->bodies[k], NULL, 0) != CTC_OK) abort();
        s->joints[k] = (ctc_joint_spec){.type = b->type};
        memcpy(s->joints[k].axis, b->axis, sizeof b->axis);
        memcpy(s->joints[k].location, b->location, sizeof b->location);
        s->parent[k] = b->parent >= 0 ? b->parent : n - 1 + (-2 - b->parent);
        s->independent[k] = 1;
        memcpy(s->q0 + q, b->q0, (size_t)type_nq(b->type) * sizeof *s->q0);
        q += type_nq(b->type);
    }
    memcpy(s->q0 + q, qt, (size_t)nqtip * sizeof *qt);
    s->independent[tip] = indep_tip;
    s->independent[nt] = indep_close;
    s->spec.nbodies = nt;
    scene_count(s);
}
