/*
 * wrench.c - an external wrench's time profile and its generalised forces (wrench.h): the
 * virtual work of the force at its point and of the torque, taken over each joint's free-motion
 * map on the path from the ground to the body.
 */
#include "wrench.h"

#include <math.h>

#include "kinematics.h"
#include "spatial.h"

double ctc_wrench_scale(const ctc_wrench *w, double t)
{
    switch (w->profile) {
    case CTC_WRENCH_SINE:
        return sin(2 * CTC_PI / w->period * fmod(t, w->period) + w->phase);
    case CTC_WRENCH_STEP:
        return t >= w->time ? 1 : 0;
    default:
        return 1;
    }
}

void ctc_wrench_forces(const ctc_model *m, const ctc_data *d, const ctc_wrench *w, double t,
                       double *f)
{
    const double s = ctc_wrench_scale(w, t);
    if (s == 0) return;
    const int k = w->body, dim = d->dim;
    /* force and torque in the world's axes, and the point x in the world */
    double fw[3], nw[3], x[3], xd[3];
    if (w->frame == CTC_WRENCH_BODY) {
        double rot[9];
        ctc_kinematics_body_rotation(m, d, k, rot);
        ctc_m3_mulv(fw, rot, w->force);
        ctc_m3_mulv(nw, rot, w->torque);
    } else {
        ctc_v3_copy(fw, w->force);
        ctc_v3_copy(nw, w->torque);
    }
    ctc_v3_scale(fw, fw, s);
    ctc_v3_scale(nw, nw, s);
    ctc_kinematics_point(m, d, k, w->point, x, xd);

    /* in planar form, the plane's components: x and the joints' centres in (e1, e2), the
       force in the plane, the torque along n */
    double xp[2] = {0, 0}, fp[2] = {0, 0}, np = 0;
    if (m->form == CTC_FORM_PLANAR) {
        xp[0] = ctc_v3_dot(x, m->plane_e1), xp[1] = ctc_v3_dot(x, m->plane_e2);
        fp[0] = ctc_v3_dot(fw, m->plane_e1), fp[1] = ctc_v3_dot(fw, m->plane_e2);
        np = ctc_v3_dot(nw, m->plane_n);
    }

    /* each joint on the path from the ground: its columns P_c = (u_w; u_v) at its centre o_j */
    for (int j = k; j >= 0; j = m->body_parent[j]) {
        const double *o = d->xpos + 3 * j;
        double about[3]; /* the moment about o_j: n + (x - o_j) x f */
        if (m->form == CTC_FORM_PLANAR) {
            about[0] = np + (xp[0] - o[0]) * fp[1] - (xp[1] - o[1]) * fp[0];
        } else {
            double r[3], rxf[3];
            ctc_v3_sub(r, x, o);
            ctc_v3_cross(rxf, r, fw);
            ctc_v3_add(about, nw, rxf);
        }
        for (int c = 0; c < m->jnt_nv[j]; c++) {
            const double *P = d->jnt_P + (size_t)(3 * j + c) * (size_t)dim;
            double g;
            if (m->form == CTC_FORM_PLANAR)
                g = P[0] * about[0] + P[1] * fp[0] + P[2] * fp[1];
            else
                g = ctc_v3_dot(P, about) + ctc_v3_dot(P + 3, fw);
            f[m->jnt_vadr[j] + c] += g;
        }
    }
}

const char *ctc_wrench_profile_name(ctc_wrench_profile p)
{
    static const char *const names[] = {"constant", "sine", "step"};
    return p >= 0 && p <= CTC_WRENCH_STEP ? names[p] : "?";
}

const char *ctc_wrench_frame_name(ctc_wrench_frame f)
{
    static const char *const names[] = {"world", "body"};
    return f >= 0 && f <= CTC_WRENCH_BODY ? names[f] : "?";
}
