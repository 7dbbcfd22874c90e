/*
 * crba.c - the joint-space mass matrix of a tree of bodies by the composite-rigid-body algorithm
 * (Featherstone, Rigid Body Dynamics Algorithms, 2008, section 6.2, Table 6.2), in body
 * coordinates.
 *
 * Composite inertias, k = n-1..0 (parent p = lambda(k) = m->body_parent[k] < k):
 *     I^c_k = I_k + (the composites of k's children, already added),  I^c_p += X_k^T I^c_k X_k.
 * Then for each joint i, F = I^c_i S_i gives the diagonal block M_ii = S_i^T F, and walking up
 * the tree to the base, F = X_j^T F then j = lambda(j), followed by M_{j,i} = S_j^T F, gives the
 * blocks of i's ancestors j; M_{i,j} = M_{j,i}^T. Every other block is zero: joints on different
 * branches do not couple. F is the force that accelerating joint i alone (unit rates, no
 * velocity, no gravity) needs on i's subtree, seen from each joint below. O(n d), d the depth
 * (O(n^2) for a chain).
 */
#include <string.h>

#include "oracle.h"
#include "oracle_internal.h"
#include "plucker.h"

void ctc_oracle_mass_matrix(const ctc_model *m, ctc_oracle *o, const double *q, double *mass)
{
    int n = m->nbodies;
    int nv = m->nv;

    ctc_oracle_forward_pass(m, o, q, NULL);
    memset(mass, 0, (size_t)nv * (size_t)nv * sizeof(double));

    /* composite inertias, tip to base */
    memcpy(o->art_inertia, o->inertia, 36 * (size_t)n * sizeof(double));
    for (int k = n - 1; k >= 0; k--) {
        const int p = m->body_parent[k];
        if (p >= 0) {
            plk_congruence_add(o->xform + 36 * (size_t)k, o->art_inertia + 36 * (size_t)k,
                               o->art_inertia + 36 * (size_t)p);
        }
    }

    /* each joint's column blocks: diagonal, then up the tree to the base, j = lambda(j) */
    for (int i = 0; i < n; i++) {
        int nvi = m->jnt_nv[i];
        int ci = m->jnt_vadr[i];
        const double *si = o->subspace + 18 * (size_t)i;
        double f[3][6]; /* F = I^c_i S_i, one 6-vector per column of S_i */

        if (nvi == 0) {
            continue;
        }
        for (int c = 0; c < nvi; c++) {
            plk_mat6_vec(o->art_inertia + 36 * (size_t)i, si + 6 * c, f[c]);
        }
        for (int j = i; j >= 0; j = m->body_parent[j]) {
            const double *sj = o->subspace + 18 * (size_t)j;
            int rj = m->jnt_vadr[j];

            /* M_ji = S_j^T F, mirrored into M_ij */
            for (int r = 0; r < m->jnt_nv[j]; r++) {
                for (int c = 0; c < nvi; c++) {
                    double sum = 0.0;
                    for (int e = 0; e < 6; e++) {
                        sum += sj[6 * r + e] * f[c][e];
                    }
                    mass[(size_t)(rj + r) * nv + ci + c] = sum;
                    mass[(size_t)(ci + c) * nv + rj + r] = sum;
                }
            }

            /* F = X_j^T F: the same force seen from body j's parent */
            if (m->body_parent[j] >= 0) {
                for (int c = 0; c < nvi; c++) {
                    double fp[6];
                    plk_mat6t_vec(o->xform + 36 * (size_t)j, f[c], fp);
                    memcpy(f[c], fp, sizeof(fp));
                }
            }
        }
    }
}
