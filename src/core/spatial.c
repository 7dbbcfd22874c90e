/*
 * spatial.c - the non-inline geometry helpers of spatial.h, used when a model is built.
 */
#include "spatial.h"

void ctc_sym3_eigenvalues(const double s[9], double eig[3])
{
    double a[3][3];
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            a[i][j] = 0.5 * (s[3 * i + j] + s[3 * j + i]);
        }
    }

    /* cyclic Jacobi sweeps: rotate away each off-diagonal entry until none is left */
    for (int sweep = 0; sweep < 50; sweep++) {
        double off = fabs(a[0][1]) + fabs(a[0][2]) + fabs(a[1][2]);
        double diag = fabs(a[0][0]) + fabs(a[1][1]) + fabs(a[2][2]);
        if (off == 0.0 || off <= 1e-300 + 1e-17 * diag) {
            break;
        }
        for (int p = 0; p < 2; p++) {
            for (int q = p + 1; q < 3; q++) {
                if (a[p][q] == 0.0) {
                    continue;
                }
                double theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), sn = t * c;
                for (int k = 0; k < 3; k++) { /* columns p, q */
                    double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - sn * akq;
                    a[k][q] = sn * akp + c * akq;
                }
                for (int k = 0; k < 3; k++) { /* rows p, q */
                    double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - sn * aqk;
                    a[q][k] = sn * apk + c * aqk;
                }
            }
        }
    }

    /* sort the diagonal ascending */
    double e0 = a[0][0], e1 = a[1][1], e2 = a[2][2], t;
    if (e0 > e1) t = e0, e0 = e1, e1 = t;
    if (e1 > e2) t = e1, e1 = e2, e2 = t;
    if (e0 > e1) t = e0, e0 = e1, e1 = t;
    eig[0] = e0;
    eig[1] = e1;
    eig[2] = e2;
}

void ctc_v3_normals(const double a[3], double n1[3], double n2[3])
{
    /* start from the world axis least aligned with a, remove its a-component */
    int k = 0;
    if (fabs(a[1]) < fabs(a[k])) k = 1;
    if (fabs(a[2]) < fabs(a[k])) k = 2;
    double e[3] = {0, 0, 0};
    e[k] = 1.0;
    ctc_v3_addscl(n1, e, a, -ctc_v3_dot(e, a));
    ctc_v3_scale(n1, n1, 1.0 / ctc_v3_norm(n1));
    ctc_v3_cross(n2, a, n1);
}
