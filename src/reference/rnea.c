/*
 * rnea.c - inverse dynamics of a tree of bodies by the recursive Newton-Euler algorithm
 * (Featherstone, Rigid Body Dynamics Algorithms, 2008, section 5.3, Table 5.1), in body
 * coordinates.
 *
 * Outward pass, k = 0..n-1 (parent p = lambda(k) = m->body_parent[k] < k; the ground, p = -1, has
 * v = 0 and a = (0; -g), so gravity needs no term of its own):
 *     v_k = X_k v_p + S_k qdot_k
 *     a_k = X_k a_p + S_k qddot_k + v_k x (S_k qdot_k)
 *     f_k = I_k a_k + v_k x* (I_k v_k)          (net force on body k, Newton-Euler)
 * Inward pass, k = n-1..0: f_k becomes the force the parent exerts on body k across joint k,
 *     tau_k = S_k^T f_k,    f_p += X_k^T f_k.
 * O(n); the velocities and transforms come from ctc_oracle_forward_pass (oracle.c).
 */
#include <string.h>

#include "oracle.h"
#include "oracle_internal.h"
#include "plucker.h"

void ctc_oracle_rnea(const ctc_model *m, ctc_oracle *o, const double *q, const double *v,
                     const double *vdot, double *tau)
{
    int n = m->nbodies;
    double ground_acc[6] = {0, 0, 0, -m->gravity[0], -m->gravity[1], -m->gravity[2]};

    ctc_oracle_forward_pass(m, o, q, v);

    /* outward: accelerations and the net force of each body */
    for (int k = 0; k < n; k++) {
        const double *x = o->xform + 36 * (size_t)k;
        const double *s = o->subspace + 18 * (size_t)k;
        const double *vk = o->vel + 6 * (size_t)k;
        const double *ck = o->bias + 6 * (size_t)k;
        const double *ik = o->inertia + 36 * (size_t)k;
        const int p = m->body_parent[k];
        const double *ap = (p < 0) ? ground_acc : o->acc + 6 * (size_t)p;
        const double *qdd = vdot + m->jnt_vadr[k];
        double *ak = o->acc + 6 * (size_t)k;
        double *fk = o->force + 6 * (size_t)k;
        double h[6], gyro[6];

        /* a_k = X_k a_p + S_k qddot_k + c_k */
        plk_mat6_vec(x, ap, ak);
        for (int i = 0; i < 6; i++) {
            ak[i] += ck[i];
        }
        for (int c = 0; c < m->jnt_nv[k]; c++) {
            for (int i = 0; i < 6; i++) {
                ak[i] += s[6 * c + i] * qdd[c];
            }
        }

        /* f_k = I_k a_k + v_k x* (I_k v_k) */
        plk_mat6_vec(ik, ak, fk);
        plk_mat6_vec(ik, vk, h);
        plk_cross_force(vk, h, gyro);
        for (int i = 0; i < 6; i++) {
            fk[i] += gyro[i];
        }
    }

    /* inward: joint forces, projected on the subspace and passed to the parent */
    for (int k = n - 1; k >= 0; k--) {
        const double *x = o->xform + 36 * (size_t)k;
        const double *s = o->subspace + 18 * (size_t)k;
        const double *fk = o->force + 6 * (size_t)k;
        double *tk = tau + m->jnt_vadr[k];

        /* tau_k = S_k^T f_k */
        for (int c = 0; c < m->jnt_nv[k]; c++) {
            double t = 0.0;
            for (int i = 0; i < 6; i++) {
                t += s[6 * c + i] * fk[i];
            }
            tk[c] = t;
        }

        /* f_p += X_k^T f_k */
        const int p = m->body_parent[k];
        if (p >= 0) {
            double fp[6];
            double *parent = o->force + 6 * (size_t)p;
            plk_mat6t_vec(x, fk, fp);
            for (int i = 0; i < 6; i++) {
                parent[i] += fp[i];
            }
        }
    }
}
