/*
 * energy.c - kinetic and potential energy of a chain (energy.h).
 *
 * Reads the world-frame (or plane-frame) poses and velocities of ctc_kinematics; the rotational
 * term uses the body-frame inertia about the centre of mass, turned into world axes by R I R^T,
 * or in planar form the planar inertia about the plane normal.
 */
#include "energy.h"

#include "spatial.h"

void ctc_energy(const ctc_model *m, const ctc_data *d, double *kinetic, double *potential)
{
    const int planar = m->form == CTC_FORM_PLANAR;
    const double *g = planar ? m->plane_gravity : m->gravity;
    double t = 0, v = 0;

    for (int k = 0; k < m->nbodies; k++) {
        const double *x = d->xpos + 3 * k, *c = d->xcom + 3 * k;
        const double *w = d->omega + 3 * k, *vo = d->xvel + 3 * k;
        double mass = m->bodies[k].mass;

        /* velocity of the centre of mass: v_c = v_o + omega x (c - x) */
        double r[3], wr[3], vc[3];
        ctc_v3_sub(r, c, x);
        ctc_v3_cross(wr, w, r);
        ctc_v3_add(vc, vo, wr);
        t += 0.5 * mass * ctc_v3_dot(vc, vc);

        /* rotation about the centre of mass */
        if (planar) {
            t += 0.5 * m->planar[k].inertia * w[2] * w[2];
        } else {
            double iw[9], iww[3];
            ctc_m3_rotate_sym(iw, d->xrot + 9 * k, m->bodies[k].inertia);
            ctc_m3_mulv(iww, iw, w);
            t += 0.5 * ctc_v3_dot(w, iww);
        }

        /* gravity: V = -m g . c (planar: g and c in the plane's coordinates) */
        v -= mass * (g[0] * c[0] + g[1] * c[1] + (planar ? 0 : g[2] * c[2]));
    }
    *kinetic = t;
    *potential = v;
}
