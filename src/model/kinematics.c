/*
 * kinematics.c - the kinematics pass (kinematics.h), one loop from base to tip per form.
 *
 * Each body is placed from its parent p = lambda(k) (model.h body_parent; the ground, at rest at
 * the origin with the world's axes, for p = -1), which the loop has already visited since p < k.
 * A body's origin velocity is the velocity of the coincident point of its parent plus the
 * relative velocity along a sliding axis: v_k = v_p + w_p x (x_k - x_p) + u qd.
 *
 * Each joint writes the entries of its motion map P and constraint map D (planar: and of its bias
 * beta) that its type can make non-zero, at every call; the others are zero from ctc_data_new
 * (calloc) and nothing else writes a body's joint maps (a joint's type is the constant model's;
 * the loop's closing joint, at index nbodies, is loop.c's), so the pass does not clear them.
 */
#include "kinematics.h"

#include <math.h>
#include <string.h>

#include "clones.h"
#include "loop.h"
#include "spatial.h"

static CTC_MULTIVERSION void kinematics_planar(const ctc_model *m, ctc_data *d, const double *q,
                                               const double *v)
{
    for (int k = 0; k < m->nbodies; k++) {
        /* the parent's angle, cos, sin, omega, origin and origin velocity (the ground's: zero) */
        const int par = m->body_parent[k];
        double theta = 0, cp = 1, sp = 0, wp = 0, pp[2] = {0, 0}, vp[2] = {0, 0};
        if (par >= 0) {
            theta = d->xangle[par];
            cp = d->xrot[9 * par], sp = d->xrot[9 * par + 3], wp = d->omega[3 * par + 2];
            pp[0] = d->xpos[3 * par], pp[1] = d->xpos[3 * par + 1];
            vp[0] = d->xvel[3 * par], vp[1] = d->xvel[3 * par + 1];
        }
        const ctc_planar_body *b = &m->planar[k];
        ctc_joint_type type = m->joints[k].type;
        const double *qk = q + m->jnt_qadr[k], *vk = v + m->jnt_vadr[k];
        double *P = d->jnt_P + 3 * 3 * k, *D = d->jnt_D + 9 * k, *beta = d->jnt_beta + 3 * k;

        /* joint centre, and the axis in the plane's coordinates */
        double p[2] = {pp[0] + cp * b->loc[0] - sp * b->loc[1],
                       pp[1] + sp * b->loc[0] + cp * b->loc[1]};
        double u[2] = {cp * b->axis[0] - sp * b->axis[1], sp * b->axis[0] + cp * b->axis[1]};
        double w = wp, slide = 0;

        switch (type) {
        case CTC_JOINT_REVOLUTE:
            theta += b->sign * qk[0];
            w += b->sign * vk[0];
            P[0] = b->sign;
            D[1] = 1;     /* column 0: (0, 1, 0) */
            D[3 + 2] = 1; /* column 1: (0, 0, 1) */
            break;
        case CTC_JOINT_PRISMATIC:
            p[0] += u[0] * qk[0];
            p[1] += u[1] * qk[0];
            slide = vk[0];
            P[1] = u[0];
            P[2] = u[1];
            D[0] = 1;
            D[3 + 1] = -u[1];
            D[3 + 2] = u[0];
            beta[1] = -2 * wp * u[1] * vk[0];
            beta[2] = 2 * wp * u[0] * vk[0];
            break;
        default: /* fixed: the builder admits no other joint in planar form */
            D[0] = D[4] = D[8] = 1;
            break;
        }

        /* pose and velocity */
        double c = cos(theta), s = sin(theta);
        double *xp = d->xpos + 3 * k, *xr = d->xrot + 9 * k, *xc = d->xcom + 3 * k;
        double *om = d->omega + 3 * k, *xv = d->xvel + 3 * k;
        d->xangle[k] = theta;
        ctc_v3_set(xp, p[0], p[1], 0);
        xr[0] = c, xr[1] = -s, xr[2] = 0;
        xr[3] = s, xr[4] = c, xr[5] = 0;
        xr[6] = 0, xr[7] = 0, xr[8] = 1;
        ctc_v3_set(xc, p[0] + c * b->com[0] - s * b->com[1], p[1] + s * b->com[0] + c * b->com[1],
                   0);
        ctc_v3_set(om, 0, 0, w);
        ctc_v3_set(xv, vp[0] - wp * (p[1] - pp[1]) + u[0] * slide,
                   vp[1] + wp * (p[0] - pp[0]) + u[1] * slide, 0);
    }
}

static CTC_MULTIVERSION void kinematics_spatial(const ctc_model *m, ctc_data *d, const double *q,
                                                const double *v)
{
    static const double zero[3] = {0, 0, 0};
    static const double eye[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};

    for (int k = 0; k < m->nbodies; k++) {
        const ctc_joint_spec *j = &m->joints[k];
        const double *qk = q + m->jnt_qadr[k], *vk = v + m->jnt_vadr[k];
        const int par = m->body_parent[k]; /* the ground: at rest, world axes */
        const double *rp = par >= 0 ? d->xrot + 9 * par : eye;
        const double *pp = par >= 0 ? d->xpos + 3 * par : zero;
        const double *wp = par >= 0 ? d->omega + 3 * par : zero;
        const double *vp = par >= 0 ? d->xvel + 3 * par : zero;
        double *xp = d->xpos + 3 * k, *xr = d->xrot + 9 * k;
        double *om = d->omega + 3 * k, *xv = d->xvel + 3 * k;
        double *P = d->jnt_P + 18 * k, *D = d->jnt_D + 36 * k, *beta = d->jnt_beta + 6 * k;
        double u[3], n1[3], n2[3], rel[9], t[3], wrel[3] = {0, 0, 0}, slide[3] = {0, 0, 0};

        /* joint centre and axis in world coordinates */
        ctc_m3_mulv(t, rp, j->location);
        ctc_v3_add(xp, pp, t);
        ctc_m3_mulv(u, rp, j->axis);
        ctc_m3_mulv(n1, rp, &m->jnt_perp[6 * k]);
        ctc_m3_mulv(n2, rp, &m->jnt_perp[6 * k + 3]);
        memset(beta, 0, 6 * sizeof(double));

        switch (j->type) {
        case CTC_JOINT_REVOLUTE:
            ctc_m3_axis_angle(rel, j->axis, qk[0]);
            ctc_m3_mul(xr, rp, rel);
            ctc_v3_scale(wrel, u, vk[0]);
            ctc_v3_copy(P, u);
            ctc_v3_copy(D, n1);
            ctc_v3_copy(D + 6, n2);
            D[12 + 3] = D[18 + 4] = D[24 + 5] = 1;
            break;
        case CTC_JOINT_PRISMATIC:
            memcpy(xr, rp, 9 * sizeof(double));
            ctc_v3_addscl(xp, xp, u, qk[0]);
            ctc_v3_scale(slide, u, vk[0]);
            ctc_v3_copy(P + 3, u);
            D[0] = D[6 + 1] = D[12 + 2] = 1;
            ctc_v3_copy(D + 18 + 3, n1);
            ctc_v3_copy(D + 24 + 3, n2);
            break;
        case CTC_JOINT_CYLINDRICAL:
            ctc_m3_axis_angle(rel, j->axis, qk[0]);
            ctc_m3_mul(xr, rp, rel);
            ctc_v3_addscl(xp, xp, u, qk[1]);
            ctc_v3_scale(wrel, u, vk[0]);
            ctc_v3_scale(slide, u, vk[1]);
            ctc_v3_copy(P, u);
            ctc_v3_copy(P + 6 + 3, u);
            ctc_v3_copy(D, n1);
            ctc_v3_copy(D + 6, n2);
            ctc_v3_copy(D + 12 + 3, n1);
            ctc_v3_copy(D + 18 + 3, n2);
            break;
        case CTC_JOINT_SPHERICAL:
            ctc_m3_from_quat(rel, qk);
            ctc_m3_mul(xr, rp, rel);
            ctc_m3_mulv(wrel, xr, vk);
            for (int c = 0; c < 3; c++) { /* P columns: the child's axes */
                P[6 * c] = xr[c];
                P[6 * c + 1] = xr[3 + c];
                P[6 * c + 2] = xr[6 + c];
            }
            D[3] = D[6 + 4] = D[12 + 5] = 1;
            break;
        case CTC_JOINT_FIXED:
            memcpy(xr, rp, 9 * sizeof(double));
            for (int c = 0; c < 6; c++) D[6 * c + c] = 1;
            break;
        }

        /* velocities: omega = w_p + omega_rel, v = v_p + w_p x (p - p_p) + u sd */
        ctc_v3_add(om, wp, wrel);
        double dp[3];
        ctc_v3_sub(dp, xp, pp);
        ctc_v3_cross(t, wp, dp);
        ctc_v3_add(xv, vp, t);
        ctc_v3_add(xv, xv, slide);

        /* beta = (w_p x omega_rel; 2 w_p x slide velocity) */
        ctc_v3_cross(beta, wp, wrel);
        ctc_v3_cross(beta + 3, wp, slide);
        ctc_v3_scale(beta + 3, beta + 3, 2.0);

        /* centre of mass */
        ctc_m3_mulv(t, xr, m->bodies[k].com);
        ctc_v3_add(d->xcom + 3 * k, xp, t);
    }
}

/* A model with merged bodies (model.h): the reduced model's kinematics in d->dyn from d's. A body
 * that stays has the same pose, velocities and joint maps in both (world quantities; a merged
 * parent moves as its composite does), and its composite's centre of mass is placed from the
 * reduced model's body data as the passes above place it. */
static void kinematics_dyn(const ctc_model *m, ctc_data *d)
{
    const ctc_model *r = m->dyn;
    ctc_data *e = d->dyn;
    for (int j = 0; j < r->nbodies; j++) {
        const int k = m->dyn_body[j];
        memcpy(e->xpos + 3 * j, d->xpos + 3 * k, 3 * sizeof(double));
        memcpy(e->xrot + 9 * j, d->xrot + 9 * k, 9 * sizeof(double));
        memcpy(e->omega + 3 * j, d->omega + 3 * k, 3 * sizeof(double));
        memcpy(e->xvel + 3 * j, d->xvel + 3 * k, 3 * sizeof(double));
        const double *xp = e->xpos + 3 * j, *xr = e->xrot + 9 * j;
        if (m->form == CTC_FORM_PLANAR) { /* the joint maps: 3 x 3 each */
            memcpy(e->jnt_P + 9 * j, d->jnt_P + 9 * k, 9 * sizeof(double));
            memcpy(e->jnt_D + 9 * j, d->jnt_D + 9 * k, 9 * sizeof(double));
            memcpy(e->jnt_beta + 3 * j, d->jnt_beta + 3 * k, 3 * sizeof(double));
            const double *c = r->planar[j].com;
            e->xangle[j] = d->xangle[k];
            ctc_v3_set(e->xcom + 3 * j, xp[0] + xr[0] * c[0] + xr[1] * c[1],
                       xp[1] + xr[3] * c[0] + xr[4] * c[1], 0);
        } else { /* P: 3 x 6, D: 6 x 6 */
            double t[3];
            memcpy(e->jnt_P + 18 * j, d->jnt_P + 18 * k, 18 * sizeof(double));
            memcpy(e->jnt_D + 36 * j, d->jnt_D + 36 * k, 36 * sizeof(double));
            memcpy(e->jnt_beta + 6 * j, d->jnt_beta + 6 * k, 6 * sizeof(double));
            ctc_m3_mulv(t, xr, r->bodies[j].com);
            ctc_v3_add(e->xcom + 3 * j, xp, t);
        }
    }
    if (r->has_loop) ctc_loop_kinematics(r, e);
}

void ctc_kinematics(const ctc_model *m, ctc_data *d, const double *q, const double *v)
{
    ctc_data_eval_begin(d); /* a new state starts an evaluation (data.h ctc_eval_gate) */
    if (m->form == CTC_FORM_PLANAR) {
        kinematics_planar(m, d, q, v);
    } else {
        kinematics_spatial(m, d, q, v);
    }
    if (m->has_loop) ctc_loop_kinematics(m, d);
    if (m->dyn != NULL) kinematics_dyn(m, d);
}

void ctc_kinematics_point(const ctc_model *m, const ctc_data *d, int k, const double p[3],
                          double x[3], double xd[3])
{
    const double *xr = d->xrot + 9 * k, *w = d->omega + 3 * k;
    double r[3], wr[3];
    if (m->form != CTC_FORM_PLANAR) {
        ctc_m3_mulv(r, xr, p);
        ctc_v3_add(x, d->xpos + 3 * k, r);
        ctc_v3_cross(wr, w, r);
        ctc_v3_add(xd, d->xvel + 3 * k, wr);
        return;
    }
    /* planar: p in the plane's coordinates, turned by the body's angle (xrot's 2 x 2 block) */
    const double *e1 = m->plane_e1, *e2 = m->plane_e2, *n = m->plane_n;
    const double p1 = ctc_v3_dot(p, e1), p2 = ctc_v3_dot(p, e2);
    double zn = ctc_v3_dot(p, n);
    for (int j = k; j >= 0; j = m->body_parent[j]) zn += ctc_v3_dot(m->joints[j].location, n);
    r[0] = xr[0] * p1 + xr[1] * p2;
    r[1] = xr[3] * p1 + xr[4] * p2;
    const double px = d->xpos[3 * k] + r[0], py = d->xpos[3 * k + 1] + r[1];
    const double vx = d->xvel[3 * k] - w[2] * r[1], vy = d->xvel[3 * k + 1] + w[2] * r[0];
    for (int i = 0; i < 3; i++) {
        x[i] = px * e1[i] + py * e2[i] + zn * n[i];
        xd[i] = vx * e1[i] + vy * e2[i];
    }
}

void ctc_kinematics_body_rotation(const ctc_model *m, const ctc_data *d, int k, double rot[9])
{
    const double *xr = d->xrot + 9 * k;
    if (m->form != CTC_FORM_PLANAR) {
        memcpy(rot, xr, 9 * sizeof *rot);
        return;
    }
    /* B R_z B^T: column j of the world's rotation is B R_z (B^T e_j) */
    const double *e1 = m->plane_e1, *e2 = m->plane_e2, *n = m->plane_n;
    for (int j = 0; j < 3; j++) {
        const double a = e1[j], b = e2[j], c = n[j];
        const double ra = xr[0] * a + xr[1] * b, rb = xr[3] * a + xr[4] * b;
        for (int i = 0; i < 3; i++) rot[3 * i + j] = ra * e1[i] + rb * e2[i] + c * n[i];
    }
}

void ctc_rotation_quaternion(const double rot[9], double quat[4])
{
    const double r00 = rot[0], r11 = rot[4], r22 = rot[8], tr = r00 + r11 + r22;
    double w, x, y, z;
    if (tr >= r00 && tr >= r11 && tr >= r22) {
        w = 0.5 * sqrt(1 + tr);
        x = (rot[7] - rot[5]) / (4 * w), y = (rot[2] - rot[6]) / (4 * w);
        z = (rot[3] - rot[1]) / (4 * w);
    } else if (r00 >= r11 && r00 >= r22) {
        x = 0.5 * sqrt(1 + r00 - r11 - r22);
        w = (rot[7] - rot[5]) / (4 * x), y = (rot[1] + rot[3]) / (4 * x);
        z = (rot[2] + rot[6]) / (4 * x);
    } else if (r11 >= r22) {
        y = 0.5 * sqrt(1 - r00 + r11 - r22);
        w = (rot[2] - rot[6]) / (4 * y), x = (rot[1] + rot[3]) / (4 * y);
        z = (rot[5] + rot[7]) / (4 * y);
    } else {
        z = 0.5 * sqrt(1 - r00 - r11 + r22);
        w = (rot[3] - rot[1]) / (4 * z), x = (rot[2] + rot[6]) / (4 * z);
        y = (rot[5] + rot[7]) / (4 * z);
    }
    const int flip = w < 0 || (w == 0 && (x < 0 || (x == 0 && (y < 0 || (y == 0 && z < 0)))));
    const double s = flip ? -1 : 1;
    quat[0] = s * w, quat[1] = s * x, quat[2] = s * y, quat[3] = s * z;
}
