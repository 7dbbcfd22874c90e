/*
 * loop.c - the closing joint's kinematics, the closure residuals, Newton's method onto the
 * closure and the mobility checks (loop.h).
 *
 * The closing joint's child is the ground (at rest: the relative angular velocity is -w_t and
 * beta = w_t x (-w_t) = 0 for the rotation) or body b, whose motion the kinematics pass has just
 * computed; either way the joint is written as a chain joint from the tip to the child. A
 * prismatic closing joint keeps the Coriolis term 2 w_t x u qd. For a prismatic joint the tip's
 * handle is its material point at the anchor (the point coincident with the child's side, as
 * for a chain's prismatic joint); for revolute and spherical ones the joint's centre on the tip.
 *
 * The loop Jacobian's column of a chain coordinate of the loop is its unit twist (P column at its
 * joint's centre) moved to the tip's handle, times -D^T. Newton and the velocity projection use
 * only the dependent coordinates' columns (all in the loop) and never store the Jacobian: G G^T
 * (at most 6 x 6) is summed column by column, and the step G^T y is a second sweep.
 */
#include "loop.h"

#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dense.h"
#include "kinematics.h"
#include "spatial.h"

/* relative singular value under which the loop Jacobian loses rank */
#define RANK_TOL 1e-9

static double wrap_angle(double a)
{
    a = fmod(a, 2 * CTC_PI);
    if (a > CTC_PI) a -= 2 * CTC_PI;
    if (a <= -CTC_PI) a += 2 * CTC_PI;
    return a;
}

/* the angle a, moved by whole turns to lie within pi of prev (a continuous coordinate) */
static double unwrap_near(double a, double prev)
{
    return a + 2 * CTC_PI * nearbyint((prev - a) / (2 * CTC_PI));
}

static void quat_from_matrix(const double r[9], double q[4])
{
    double tr = r[0] + r[4] + r[8];
    if (tr > 0) {
        double s = 2 * sqrt(1 + tr);
        q[0] = 0.25 * s;
        q[1] = (r[7] - r[5]) / s;
        q[2] = (r[2] - r[6]) / s;
        q[3] = (r[3] - r[1]) / s;
    } else if (r[0] > r[4] && r[0] > r[8]) {
        double s = 2 * sqrt(1 + r[0] - r[4] - r[8]);
        q[0] = (r[7] - r[5]) / s;
        q[1] = 0.25 * s;
        q[2] = (r[1] + r[3]) / s;
        q[3] = (r[2] + r[6]) / s;
    } else if (r[4] > r[8]) {
        double s = 2 * sqrt(1 + r[4] - r[0] - r[8]);
        q[0] = (r[2] - r[6]) / s;
        q[1] = (r[1] + r[3]) / s;
        q[2] = 0.25 * s;
        q[3] = (r[5] + r[7]) / s;
    } else {
        double s = 2 * sqrt(1 + r[8] - r[0] - r[4]);
        q[0] = (r[3] - r[1]) / s;
        q[1] = (r[2] + r[6]) / s;
        q[2] = (r[5] + r[7]) / s;
        q[3] = 0.25 * s;
    }
    if (q[0] < 0)
        for (int i = 0; i < 4; i++) q[i] = -q[i];
}

/* The closing joint's child (model.h): the ground, or body b, as a pose and a motion (world or
 * plane coordinates; planar: rot[0], rot[3] its angle's cosine and sine) */
typedef struct loop_child {
    double x[3], rot[9], w[3], v[3]; /* origin, orientation, angular velocity, origin velocity */
} loop_child;

static void loop_child_of(const ctc_model *m, const ctc_data *d, loop_child *c)
{
    static const loop_child ground = {.rot = {1, 0, 0, 0, 1, 0, 0, 0, 1}};
    const int b = m->loop_body;
    *c = ground;
    if (b < 0) return;
    memcpy(c->x, d->xpos + 3 * b, sizeof c->x);
    memcpy(c->rot, d->xrot + 9 * b, sizeof c->rot);
    memcpy(c->w, d->omega + 3 * b, sizeof c->w);
    memcpy(c->v, d->xvel + 3 * b, sizeof c->v);
}

/* a loop on a body: r = p2 - p1 from the body's handle 2 (its child's joint centre, joint b+1)
 * to the closing point, and gam = (0; w x (w x r)), the centripetal part of the body's acceleration
 * moved there */
static void loop_shift(const ctc_model *m, ctc_data *d)
{
    memset(d->loop_r, 0, sizeof d->loop_r);
    memset(d->loop_gam, 0, sizeof d->loop_gam);
    if (m->loop_body < 0) return;
    const double *w = d->omega + 3 * m->loop_body;
    double t[3], g[3];
    ctc_v3_sub(d->loop_r, d->loop_pt, d->xpos + 3 * m->loop_first);
    ctc_v3_cross(t, w, d->loop_r);
    ctc_v3_cross(g, w, t);
    memcpy(d->loop_gam + (m->dim == 3 ? 1 : 3), g, (size_t)(m->dim == 3 ? 2 : 3) * sizeof *g);
}

static void loop_planar(const ctc_model *m, ctc_data *d)
{
    const int n = m->nbodies, k = n - 1;
    const ctc_planar_body *lp = &m->loop_planar;
    const double *p = d->xpos + 3 * k, *xr = d->xrot + 9 * k, *v = d->xvel + 3 * k;
    const double c = xr[0], s = xr[3], w = d->omega[3 * k + 2], *an = m->loop_anchor2;
    double *P = d->jnt_P + 9 * n, *D = d->jnt_D + 9 * n, *beta = d->jnt_beta + 3 * n;
    double pt[2] = {p[0] + c * lp->loc[0] - s * lp->loc[1], p[1] + s * lp->loc[0] + c * lp->loc[1]};
    loop_child ch;
    loop_child_of(m, d, &ch);
    /* the anchor in the plane, and the child's velocity there */
    const double cb = ch.rot[0], sb = ch.rot[3], wb = ch.w[2];
    double ag[2] = {ch.x[0] + cb * an[0] - sb * an[1], ch.x[1] + sb * an[0] + cb * an[1]};
    double va[2] = {ch.v[0] - wb * (ag[1] - ch.x[1]), ch.v[1] + wb * (ag[0] - ch.x[0])};
    /* the tip's angle relative to the child */
    double theta = atan2(s * cb - c * sb, c * cb + s * sb);

    memset(P, 0, 9 * sizeof *P);
    memset(D, 0, 9 * sizeof *D);
    beta[0] = beta[1] = beta[2] = 0;
    if (m->joints[n].type == CTC_JOINT_REVOLUTE) {
        /* the tip's point at the joint's centre, moving with v + w x (pt - p) */
        double vt[2] = {v[0] - w * (pt[1] - p[1]), v[1] + w * (pt[0] - p[0])};
        P[0] = lp->sign;
        D[1] = 1;
        D[3 + 2] = 1;
        ctc_v3_set(d->loop_pt, pt[0], pt[1], 0);
        d->loop_q[0] = unwrap_near(-lp->sign * theta, d->loop_q[0]);
        d->loop_v[0] = -lp->sign * (w - wb);
        d->loop_phi[0] = ag[0] - pt[0];
        d->loop_phi[1] = ag[1] - pt[1];
        d->loop_dphi[0] = va[0] - vt[0];
        d->loop_dphi[1] = va[1] - vt[1];
    } else { /* prismatic: the tip's point at the anchor */
        double u[2] = {c * lp->axis[0] - s * lp->axis[1], s * lp->axis[0] + c * lp->axis[1]};
        double nr[2] = {-u[1], u[0]}, gap[2] = {ag[0] - pt[0], ag[1] - pt[1]};
        double vc[2] = {v[0] - w * (ag[1] - p[1]), v[1] + w * (ag[0] - p[0])};
        double dv[2] = {va[0] - vc[0], va[1] - vc[1]};
        P[1] = u[0];
        P[2] = u[1];
        D[0] = 1;
        D[3 + 1] = nr[0];
        D[3 + 2] = nr[1];
        ctc_v3_set(d->loop_pt, ag[0], ag[1], 0);
        d->loop_q[0] = gap[0] * u[0] + gap[1] * u[1];
        d->loop_v[0] = dv[0] * u[0] + dv[1] * u[1];
        beta[1] = -2 * w * u[1] * d->loop_v[0];
        beta[2] = 2 * w * u[0] * d->loop_v[0];
        d->loop_phi[0] = -wrap_angle(theta);
        d->loop_phi[1] = gap[0] * nr[0] + gap[1] * nr[1];
        d->loop_dphi[0] = wb - w;
        d->loop_dphi[1] = dv[0] * nr[0] + dv[1] * nr[1];
    }
}

static void loop_spatial(const ctc_model *m, ctc_data *d)
{
    const int n = m->nbodies, k = n - 1;
    const ctc_joint_spec *j = &m->joints[n];
    const double *p = d->xpos + 3 * k, *r = d->xrot + 9 * k, *w = d->omega + 3 * k;
    const double *v = d->xvel + 3 * k;
    double *P = d->jnt_P + 18 * n, *D = d->jnt_D + 36 * n, *beta = d->jnt_beta + 6 * n;
    double pt[3], t[3], vt[3], vc[3], gap[3], ag[3], va[3], wrel[3];
    loop_child ch;
    loop_child_of(m, d, &ch);

    ctc_m3_mulv(t, ch.rot, m->loop_anchor); /* the anchor, and the child's velocity there */
    ctc_v3_add(ag, ch.x, t);
    ctc_v3_cross(va, ch.w, t);
    ctc_v3_add(va, va, ch.v);
    ctc_v3_sub(wrel, ch.w, w); /* the child's angular velocity relative to the tip */
    ctc_m3_mulv(t, r, j->location);
    ctc_v3_add(pt, p, t);
    ctc_v3_sub(gap, ag, pt);
    ctc_v3_sub(t, pt, p); /* the tip's point at the joint's centre: v + w x (pt - p) */
    ctc_v3_cross(vt, w, t);
    ctc_v3_add(vt, vt, v);
    ctc_v3_sub(t, ag, p); /* the tip's point at the anchor */
    ctc_v3_cross(vc, w, t);
    ctc_v3_add(vc, vc, v);
    memset(P, 0, 18 * sizeof *P);
    memset(D, 0, 36 * sizeof *D);
    memset(beta, 0, 6 * sizeof *beta);

    if (j->type == CTC_JOINT_SPHERICAL) {
        double rt[9];
        for (int a = 0; a < 3; a++) {
            for (int b = 0; b < 3; b++) P[6 * a + b] = ch.rot[3 * b + a]; /* the child's axes */
            D[6 * a + 3 + a] = 1; /* no relative translation */
            d->loop_phi[a] = gap[a];
            d->loop_dphi[a] = va[a] - vt[a];
        }
        ctc_m3_tmulv(d->loop_v, ch.rot, wrel); /* in the child's frame */
        ctc_v3_cross(beta, w, wrel);
        for (int a = 0; a < 3; a++) /* R_t^T R_child */
            for (int b = 0; b < 3; b++)
                rt[3 * a + b] =
                    r[a] * ch.rot[b] + r[3 + a] * ch.rot[3 + b] + r[6 + a] * ch.rot[6 + b];
        quat_from_matrix(rt, d->loop_q);
        ctc_v3_copy(d->loop_pt, pt);
        return;
    }

    double u[3], n1[3], n2[3];
    ctc_m3_mulv(u, r, j->axis);
    ctc_m3_mulv(n1, r, &m->jnt_perp[6 * n]);
    ctc_m3_mulv(n2, r, &m->jnt_perp[6 * n + 3]);
    if (j->type == CTC_JOINT_REVOLUTE) {
        /* angle of R_t^T R_child about the axis, from the tip-frame normals p1, p2 = a x p1 */
        double rp[3], mis[3], ub[3];
        const double *p1 = &m->jnt_perp[6 * n], *p2 = &m->jnt_perp[6 * n + 3];
        ctc_m3_mulv(t, ch.rot, p1);
        ctc_m3_tmulv(rp, r, t);
        ctc_v3_copy(P, u);
        ctc_v3_copy(D, n1);
        ctc_v3_copy(D + 6, n2);
        D[12 + 3] = D[18 + 4] = D[24 + 5] = 1;
        ctc_v3_copy(d->loop_pt, pt);
        d->loop_q[0] = unwrap_near(atan2(ctc_v3_dot(p2, rp), ctc_v3_dot(p1, rp)), d->loop_q[0]);
        d->loop_v[0] = ctc_v3_dot(u, wrel);
        ctc_v3_cross(beta, w, wrel);
        ctc_m3_mulv(ub, ch.rot, j->axis); /* the axis carried by the child */
        ctc_v3_cross(mis, u, ub);
        d->loop_phi[0] = ctc_v3_dot(n1, mis);
        d->loop_phi[1] = ctc_v3_dot(n2, mis);
        d->loop_dphi[0] = ctc_v3_dot(n1, wrel);
        d->loop_dphi[1] = ctc_v3_dot(n2, wrel);
        for (int a = 0; a < 3; a++) {
            d->loop_phi[2 + a] = gap[a];
            d->loop_dphi[2 + a] = va[a] - vt[a];
        }
        return;
    }

    /* prismatic: rotation error = rotation vector of Q = R_child R_t^T, about vee(Q - Q^T) / 2 */
    double q[9], dv[3];
    for (int a = 0; a < 3; a++)
        for (int b = 0; b < 3; b++)
            q[3 * a + b] = ch.rot[3 * a] * r[3 * b] + ch.rot[3 * a + 1] * r[3 * b + 1] +
                           ch.rot[3 * a + 2] * r[3 * b + 2];
    ctc_v3_sub(dv, va, vc);
    ctc_v3_copy(P + 3, u);
    D[0] = D[6 + 1] = D[12 + 2] = 1;
    ctc_v3_copy(D + 18 + 3, n1);
    ctc_v3_copy(D + 24 + 3, n2);
    ctc_v3_copy(d->loop_pt, ag);
    d->loop_q[0] = ctc_v3_dot(gap, u);
    d->loop_v[0] = ctc_v3_dot(dv, u);
    ctc_v3_cross(beta, w, wrel); /* zero on the closure, where the tip and the child turn alike */
    ctc_v3_cross(beta + 3, w, u);
    ctc_v3_scale(beta + 3, beta + 3, 2 * d->loop_v[0]);
    d->loop_phi[0] = 0.5 * (q[7] - q[5]);
    d->loop_phi[1] = 0.5 * (q[2] - q[6]);
    d->loop_phi[2] = 0.5 * (q[3] - q[1]);
    d->loop_phi[3] = ctc_v3_dot(gap, n1);
    d->loop_phi[4] = ctc_v3_dot(gap, n2);
    for (int a = 0; a < 3; a++) d->loop_dphi[a] = wrel[a];
    d->loop_dphi[3] = ctc_v3_dot(dv, n1);
    d->loop_dphi[4] = ctc_v3_dot(dv, n2);
}

void ctc_loop_kinematics(const ctc_model *m, ctc_data *d)
{
    if (!m->has_loop) return;
    if (m->form == CTC_FORM_PLANAR) {
        loop_planar(m, d);
    } else {
        loop_spatial(m, d);
    }
    loop_shift(m, d);
}

/* number of closure residuals */
static int loop_nc(const ctc_model *m)
{
    return m->dim - m->jnt_nv[m->nbodies];
}

void ctc_loop_residual_norms(const ctc_model *m, const ctc_data *d, double *pos, double *vel)
{
    *pos = *vel = 0;
    for (int i = 0; m->has_loop && i < loop_nc(m); i++) {
        *pos = fmax(*pos, fabs(d->loop_phi[i]));
        *vel = fmax(*vel, fabs(d->loop_dphi[i]));
    }
}

void ctc_loop_coord_twist(const ctc_model *m, const ctc_data *d, int k, int c, double *tw)
{
    double r[3];
    ctc_v3_sub(r, d->loop_pt, d->xpos + 3 * k);
    ctc_transfer_motion(m->dim, r, d->jnt_P + 3 * m->dim * k + c * m->dim, tw);
}

/* the loop Jacobian's column of chain coordinate (k, c): g = -D_n^T (unit twist) (nc) */
static void loop_column(const ctc_model *m, const ctc_data *d, int k, int c, double *g)
{
    const int dim = m->dim, nc = loop_nc(m);
    const double *D = d->jnt_D + dim * dim * m->nbodies;
    double tw[CTC_DENSE_MAX];
    ctc_loop_coord_twist(m, d, k, c, tw);
    for (int a = 0; a < nc; a++) {
        double s = 0;
        for (int i = 0; i < dim; i++) s += D[a * dim + i] * tw[i];
        g[a] = -s;
    }
}

/* L L^T = G_dep G_dep^T over the dependent chain coordinates of the loop (nc x nc); -1 if
 * singular */
static int dependent_gram(const ctc_model *m, const ctc_data *d, double *gram)
{
    const int nc = loop_nc(m);
    memset(gram, 0, (size_t)nc * nc * sizeof *gram);
    for (int k = m->loop_first; k < m->nbodies; k++) {
        if (m->jnt_indep[k] || !m->jnt_loop[k]) continue;
        for (int c = 0; c < m->jnt_nv[k]; c++) {
            double g[CTC_DENSE_MAX];
            loop_column(m, d, k, c, g);
            for (int a = 0; a < nc; a++)
                for (int b = 0; b < nc; b++) gram[a * nc + b] += g[a] * g[b];
        }
    }
    double dmax = 0;
    for (int a = 0; a < nc; a++) dmax = fmax(dmax, gram[a * nc + a]);
    if (ctc_dense_cholesky(nc, gram) != 0) return -1;
    for (int a = 0; a < nc; a++)
        if (!(gram[a * nc + a] * gram[a * nc + a] > 1e-24 * dmax)) return -1;
    return 0;
}

/* dv (nv) = -G_dep^T (G_dep G_dep^T)^-1 r over the dependent coordinates, 0 elsewhere: the
 * least-norm change that removes the residual r (nc) to first order; returns max |dv| */
static double dependent_step(const ctc_model *m, const ctc_data *d, const double *chol,
                             const double *r, double *dv)
{
    const int nc = loop_nc(m);
    double y[CTC_DENSE_MAX], big = 0;
    memcpy(y, r, (size_t)nc * sizeof *y);
    ctc_dense_lsolve(nc, chol, y);
    ctc_dense_ltsolve(nc, chol, y);
    memset(dv, 0, (size_t)m->nv * sizeof *dv);
    for (int k = m->loop_first; k < m->nbodies; k++) {
        if (m->jnt_indep[k] || !m->jnt_loop[k]) continue;
        for (int c = 0; c < m->jnt_nv[k]; c++) {
            double g[CTC_DENSE_MAX], s = 0;
            loop_column(m, d, k, c, g);
            for (int a = 0; a < nc; a++) s += g[a] * y[a];
            dv[m->jnt_vadr[k] + c] = -s;
            big = fmax(big, fabs(s));
        }
    }
    return big;
}

static double residual_norm(const ctc_model *m, const ctc_data *d)
{
    double pos, vel;
    ctc_loop_residual_norms(m, d, &pos, &vel);
    return pos;
}

ctc_status ctc_loop_assemble(const ctc_model *m, ctc_data *d, double *q, double *v, double tol,
                             int max_iter, ctc_loop_fix *fix, char *err, size_t errlen)
{
    ctc_loop_fix f = {0};
    if (fix) *fix = f;
    if (!m->has_loop) return CTC_OK;
    if (!(tol > 0)) return ctc_fail(CTC_EINVAL, err, errlen, "loop: tolerance must be positive");
    const int nc = loop_nc(m);
    double *dv = d->xbuf, *qsave = d->xbuf + m->nvx, chol[CTC_DENSE_MAX * CTC_DENSE_MAX];

    ctc_kinematics(m, d, q, v);
    double res = residual_norm(m, d);
    ctc_loop_residual_norms(m, d, &f.res_before, &f.vres_before);
    while (res > tol && f.iterations < max_iter) {
        if (dependent_gram(m, d, chol) != 0) {
            return ctc_fail(CTC_EINVAL, err, errlen,
                            "loop: the dependent joints cannot move the loop here (singular "
                            "configuration, residual %.3g)",
                            res);
        }
        double r[CTC_DENSE_MAX];
        memcpy(r, d->loop_phi, (size_t)nc * sizeof *r);
        double step = dependent_step(m, d, chol, r, dv);
        memcpy(qsave, q, (size_t)m->nq * sizeof *q);
        /* Newton's step, halved while it does not reduce the residual */
        double s = 1, trial = INFINITY;
        for (int h = 0; h < 30; h++, s *= 0.5) {
            memcpy(q, qsave, (size_t)m->nq * sizeof *q);
            ctc_model_q_add(m, q, dv, s);
            ctc_kinematics(m, d, q, v);
            trial = residual_norm(m, d);
            if (trial < res) break;
        }
        f.dq_max = fmax(f.dq_max, s * step);
        f.iterations++;
        if (!(trial < res)) break; /* no descent: leave the loop open and report it */
        res = trial;
    }
    if (!(res <= tol)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "loop: the loop does not close: position residual %.3g after %d Newton "
                        "iterations (is the anchor within reach of the chain?)",
                        res, f.iterations);
    }

    /* velocities: remove the velocity residual with the dependent coordinates */
    if (dependent_gram(m, d, chol) != 0) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "loop: the dependent joints cannot move the loop here (singular "
                        "configuration)");
    }
    double r[CTC_DENSE_MAX];
    memcpy(r, d->loop_dphi, (size_t)nc * sizeof *r);
    f.dv_max = dependent_step(m, d, chol, r, dv);
    for (int i = 0; i < m->nv; i++) v[i] += dv[i];
    ctc_kinematics(m, d, q, v);
    ctc_loop_residual_norms(m, d, &f.res_after, &f.vres_after);
    if (fix) *fix = f;
    return CTC_OK;
}

/* singular values (descending, into s: min(dim, ncols)) of the loop's twist matrix over the
 * coordinates that `pick` selects (1 = chain coordinates and closing joint, independent or not
 * per `dep_only`), with the linear rows divided by a length scale so the units agree */
static ctc_status twist_svd(const ctc_model *m, const ctc_data *d, int dep_only, double *s,
                            int *ncols, char *err, size_t errlen)
{
    const int dim = m->dim, n = m->nbodies;
    double len = 0;
    for (int k = m->loop_first; k < n; k++) {
        if (!m->jnt_loop[k]) continue;
        double r[3];
        ctc_v3_sub(r, d->xpos + 3 * k, d->loop_pt);
        len = fmax(len, ctc_v3_norm(r));
    }
    len = fmax(len, 1e-6);
    int cols = 0;
    for (int k = m->loop_first; k <= n; k++)
        if (m->jnt_loop[k] && (!dep_only || !m->jnt_indep[k])) cols += m->jnt_nv[k];
    *ncols = cols;
    if (cols == 0) return CTC_OK;
    double *a = malloc((size_t)dim * cols * sizeof *a), superb[CTC_DENSE_MAX];
    if (!a) return ctc_fail(CTC_ENOMEM, err, errlen, "out of memory");
    int col = 0;
    for (int k = m->loop_first; k <= n; k++) {
        if (!m->jnt_loop[k] || (dep_only && m->jnt_indep[k])) continue;
        for (int c = 0; c < m->jnt_nv[k]; c++, col++) {
            double tw[CTC_DENSE_MAX];
            if (k < n) {
                ctc_loop_coord_twist(m, d, k, c, tw);
            } else {
                memcpy(tw, d->jnt_P + 3 * dim * n + c * dim, (size_t)dim * sizeof *tw);
            }
            for (int i = 0; i < dim; i++) {
                int linear = dim == 3 ? i > 0 : i >= 3;
                a[(size_t)i * cols + col] = linear ? tw[i] / len : tw[i];
            }
        }
    }
    lapack_int info =
        LAPACKE_dgesvd(LAPACK_ROW_MAJOR, 'N', 'N', dim, cols, a, cols, s, NULL, 1, NULL, 1, superb);
    free(a);
    if (info != 0) return ctc_fail(CTC_EINVAL, err, errlen, "loop: SVD failed (%d)", (int)info);
    return CTC_OK;
}

ctc_status ctc_loop_check(const ctc_model *m, ctc_data *d, const double *q, double *cond, char *err,
                          size_t errlen)
{
    if (cond) *cond = 1;
    if (!m->has_loop) return CTC_OK;
    const int dim = m->dim;
    double *zero = d->xbuf, s[CTC_DENSE_MAX] = {0};
    memset(zero, 0, (size_t)m->nvx * sizeof *zero);
    ctc_kinematics(m, d, q, zero);

    int cols;
    ctc_status st = twist_svd(m, d, 0, s, &cols, err, errlen);
    if (st != CTC_OK) return st;
    int rank = 0;
    for (int i = 0; i < dim && i < cols; i++) rank += s[i] > RANK_TOL * s[0];
    if (rank < dim) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "loop: the loop is over-constrained: Gruebler-Kutzbach gives mobility %d "
                        "(%d joint freedoms - %d) but the loop Jacobian has rank %d, so it moves "
                        "with %d freedoms and its constraint loads are not unique%s",
                        m->mobility, m->nvx, dim, rank, m->nvx - rank,
                        m->form == CTC_FORM_SPATIAL
                            ? " (a loop that moves in a plane must be computed in planar form)"
                            : "");
    }
    if (m->nind > 0 && m->nind != m->mobility) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "loop: mobility is %d (Gruebler-Kutzbach: %d joint freedoms - %d) but %d "
                        "coordinates are independent; mark exactly %d as independent",
                        m->mobility, m->nvx, dim, m->nind, m->mobility);
    }
    if (m->nind == 0) return CTC_OK; /* passive: every coordinate moves with the loop */

    st = twist_svd(m, d, 1, s, &cols, err, errlen);
    if (st != CTC_OK) return st;
    double c = s[dim - 1] > 0 ? s[0] / s[dim - 1] : INFINITY;
    if (cond) *cond = c;
    if (!(c <= CTC_LOOP_SINGULAR_COND)) {
        return ctc_fail(CTC_EINVAL, err, errlen,
                        "loop: the dependent joints cannot move the loop here (singular "
                        "configuration; condition number %.3g), so the independent joints "
                        "cannot drive it: choose other independent joints or another q0",
                        c);
    }
    return CTC_OK;
}
