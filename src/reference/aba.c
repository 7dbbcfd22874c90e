/*
 * aba.c - forward dynamics of a tree of bodies by the articulated-body algorithm (Featherstone,
 * Rigid Body Dynamics Algorithms, 2008, section 7.3, Table 7.1), in body coordinates.
 *
 * Pass 1, outward: v_k, c_k = v_k x (S_k qdot_k) (ctc_oracle_forward_pass), and
 *     I^A_k = I_k,    p^A_k = v_k x* (I_k v_k).
 * Pass 2, inward, k = n-1..0 (parent p = lambda(k) = m->body_parent[k] < k, so every child is
 * done before its parent):
 *     U_k = I^A_k S_k,   D_k = S_k^T U_k,   u_k = tau_k - S_k^T p^A_k
 *     I^a = I^A_k - U_k D_k^{-1} U_k^T
 *     p^a = p^A_k + I^a c_k + U_k D_k^{-1} u_k
 *     I^A_p += X_k^T I^a X_k,    p^A_p += X_k^T p^a           (unless p is the ground)
 * Pass 3, outward, from the ground's a = (0; -g):
 *     a' = X_k a_p + c_k,   qddot_k = D_k^{-1} (u_k - U_k^T a'),   a_k = a' + S_k qddot_k.
 * D_k (at most 3x3) is symmetric positive definite for a chain that can move; it is factored
 * once by Cholesky. Nothing here inverts a body's own inertia. O(n).
 */
#include <string.h>

#include "oracle.h"
#include "oracle_internal.h"
#include "plucker.h"

void ctc_oracle_aba(const ctc_model *m, ctc_oracle *o, const double *q, const double *v,
                    const double *tau, double *vdot)
{
    int n = m->nbodies;
    double ground_acc[6] = {0, 0, 0, -m->gravity[0], -m->gravity[1], -m->gravity[2]};

    ctc_oracle_forward_pass(m, o, q, v);

    /* pass 1: each body alone, I^A = I, p^A = v x* I v */
    for (int k = 0; k < n; k++) {
        const double *vk = o->vel + 6 * (size_t)k;
        double h[6];

        memcpy(o->art_inertia + 36 * (size_t)k, o->inertia + 36 * (size_t)k, 36 * sizeof(double));
        plk_mat6_vec(o->inertia + 36 * (size_t)k, vk, h);
        plk_cross_force(vk, h, o->art_bias + 6 * (size_t)k);
    }

    /* pass 2: articulated inertias and bias forces, tip to base */
    for (int k = n - 1; k >= 0; k--) {
        int nv = m->jnt_nv[k];
        const double *x = o->xform + 36 * (size_t)k;
        const double *s = o->subspace + 18 * (size_t)k;
        const double *ck = o->bias + 6 * (size_t)k;
        const double *tk = tau + m->jnt_vadr[k];
        double *ia = o->art_inertia + 36 * (size_t)k;
        double *pa = o->art_bias + 6 * (size_t)k;
        double *u = o->art_u + 18 * (size_t)k;
        double *dl = o->art_dchol + 9 * (size_t)k;
        double *uk = o->art_tau + 3 * (size_t)k;
        double d[9];

        /* U = I^A S (column by column), D = S^T U, u = tau - S^T p^A */
        for (int c = 0; c < nv; c++) {
            plk_mat6_vec(ia, s + 6 * c, u + 6 * c);
        }
        for (int r = 0; r < nv; r++) {
            double sp = 0.0;
            for (int i = 0; i < 6; i++) {
                sp += s[6 * r + i] * pa[i];
            }
            uk[r] = tk[r] - sp;
            for (int c = 0; c < nv; c++) {
                double sum = 0.0;
                for (int i = 0; i < 6; i++) {
                    sum += s[6 * r + i] * u[6 * c + i];
                }
                d[nv * r + c] = sum;
            }
        }
        plk_chol_factor(nv, d, dl);
        const int p = m->body_parent[k];
        if (p < 0) {
            continue;
        }

        /* I^a = I^A - U D^{-1} U^T: W = D^{-1} U^T row by row of U, then subtract U W */
        double ia_art[36], pa_art[6], tmp[6];
        memcpy(ia_art, ia, sizeof(ia_art));
        for (int i = 0; i < 6; i++) {
            double urow[3], w[3];
            for (int c = 0; c < nv; c++) {
                urow[c] = u[6 * c + i];
            }
            plk_chol_solve(nv, dl, urow, w); /* column i of W = D^{-1} U^T */
            for (int j = 0; j < 6; j++) {
                double sum = 0.0;
                for (int c = 0; c < nv; c++) {
                    sum += u[6 * c + j] * w[c];
                }
                ia_art[6 * j + i] -= sum;
            }
        }

        /* p^a = p^A + I^a c + U D^{-1} u */
        double dinv_u[3];
        plk_chol_solve(nv, dl, uk, dinv_u);
        plk_mat6_vec(ia_art, ck, tmp);
        for (int i = 0; i < 6; i++) {
            double sum = pa[i] + tmp[i];
            for (int c = 0; c < nv; c++) {
                sum += u[6 * c + i] * dinv_u[c];
            }
            pa_art[i] = sum;
        }

        /* hand both to the parent: I^A_p += X^T I^a X, p^A_p += X^T p^a */
        double *pp = o->art_bias + 6 * (size_t)p;
        plk_congruence_add(x, ia_art, o->art_inertia + 36 * (size_t)p);
        plk_mat6t_vec(x, pa_art, tmp);
        for (int i = 0; i < 6; i++) {
            pp[i] += tmp[i];
        }
    }

    /* pass 3: accelerations, base to tip */
    for (int k = 0; k < n; k++) {
        int nv = m->jnt_nv[k];
        const double *x = o->xform + 36 * (size_t)k;
        const double *s = o->subspace + 18 * (size_t)k;
        const double *ck = o->bias + 6 * (size_t)k;
        const double *u = o->art_u + 18 * (size_t)k;
        const double *dl = o->art_dchol + 9 * (size_t)k;
        const double *uk = o->art_tau + 3 * (size_t)k;
        const int p = m->body_parent[k];
        const double *ap = (p < 0) ? ground_acc : o->acc + 6 * (size_t)p;
        double *ak = o->acc + 6 * (size_t)k;
        double *qdd = vdot + m->jnt_vadr[k];
        double rhs[3];

        /* a' = X a_p + c */
        plk_mat6_vec(x, ap, ak);
        for (int i = 0; i < 6; i++) {
            ak[i] += ck[i];
        }

        /* qddot = D^{-1} (u - U^T a'), then a = a' + S qddot */
        for (int c = 0; c < nv; c++) {
            double sum = 0.0;
            for (int i = 0; i < 6; i++) {
                sum += u[6 * c + i] * ak[i];
            }
            rhs[c] = uk[c] - sum;
        }
        plk_chol_solve(nv, dl, rhs, qdd);
        for (int c = 0; c < nv; c++) {
            for (int i = 0; i < 6; i++) {
                ak[i] += s[6 * c + i] * qdd[c];
            }
        }
    }
}
