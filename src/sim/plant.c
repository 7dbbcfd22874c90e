/*
 * plant.c - the joint forces of a controlled coordinate (plant.h): viscous friction, regularised
 * Coulomb friction and a linear spring, the sensors' noise generator, and the forward dynamics
 * with armature, written as plant.h states them.
 */
#include "plant.h"

#include <math.h>
#include <string.h>

#include "gdca.h"

double ctc_plant_joint_force(const ctc_plant_coord *p, double q, double v)
{
    double tau = -p->viscous * v - p->spring * (q - p->spring_rest);
    if (p->coulomb > 0) tau -= p->coulomb * tanh(v / p->coulomb_velocity);
    return tau;
}

int ctc_plant_has_sensor_error(const ctc_plant_coord *p)
{
    return p->noise_q != 0 || p->noise_v != 0 || p->resolution != 0;
}

/* splitmix64's next output; the uniform in [0, 1) of its top 53 bits */
double ctc_plant_uniform(unsigned long long *state)
{
    unsigned long long z = (*state += 0x9e3779b97f4a7c15ull);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
    z ^= z >> 31;
    return (double)(z >> 11) * 0x1p-53;
}

double ctc_plant_normal(unsigned long long *state)
{
    const double two_pi = 6.283185307179586476925286766559;
    double ua = ctc_plant_uniform(state), ub = ctc_plant_uniform(state);
    return sqrt(-2 * log(1 - ua)) * cos(two_pi * ub);
}

int ctc_plant_has_joint_force(const ctc_plant_coord *p)
{
    return p->viscous != 0 || p->coulomb != 0 || p->spring != 0;
}

void ctc_plant_forward_armature(const ctc_model *m, ctc_data *d, const double *arm, const double *f,
                                double *qdd, double *work)
{
    const int nv = m->nv;
    int k = 0;
    for (int i = 0; i < nv; i++) k += arm[i] > 0;
    ctc_gdca_forward(m, d, f, qdd);
    if (k == 0) return;
    /* work: f + e_j (nv), X's columns J (nv x k, column-major), S (k x k, row-major), x (k) */
    double *fj = work, *x_cols = fj + nv, *s = x_cols + nv * k, *xj = s + k * k;
    /* X e_j = GDCA(f + e_j) - qdd0 */
    for (int i = 0, c = 0; i < nv; i++) {
        if (!(arm[i] > 0)) continue;
        double *col = x_cols + (size_t)nv * c++;
        memcpy(fj, f, (size_t)nv * sizeof *fj);
        fj[i] += 1;
        ctc_gdca_forward(m, d, fj, col);
        for (int r = 0; r < nv; r++) col[r] -= qdd[r];
    }
    /* S = I + X_JJ diag(arm_J), right-hand side qdd0_J */
    for (int i = 0, r = 0; i < nv; i++) {
        if (!(arm[i] > 0)) continue;
        for (int jj = 0, c = 0; jj < nv; jj++) {
            if (!(arm[jj] > 0)) continue;
            s[r * k + c] = (r == c) + x_cols[(size_t)nv * c + i] * arm[jj];
            c++;
        }
        xj[r++] = qdd[i];
    }
    /* Gaussian elimination with partial pivoting, then back substitution */
    for (int c = 0; c < k; c++) {
        int piv = c;
        for (int r = c + 1; r < k; r++)
            if (fabs(s[r * k + c]) > fabs(s[piv * k + c])) piv = r;
        if (piv != c) {
            for (int cc = 0; cc < k; cc++) {
                double t = s[c * k + cc];
                s[c * k + cc] = s[piv * k + cc];
                s[piv * k + cc] = t;
            }
            double t = xj[c];
            xj[c] = xj[piv];
            xj[piv] = t;
        }
        for (int r = c + 1; r < k; r++) {
            double l = s[r * k + c] / s[c * k + c];
            for (int cc = c; cc < k; cc++) s[r * k + cc] -= l * s[c * k + cc];
            xj[r] -= l * xj[c];
        }
    }
    for (int c = k - 1; c >= 0; c--) {
        double sum = xj[c];
        for (int cc = c + 1; cc < k; cc++) sum -= s[c * k + cc] * xj[cc];
        xj[c] = sum / s[c * k + c];
    }
    /* qdd = qdd0 - X_J diag(arm_J) qdd_J */
    for (int i = 0, c = 0; i < nv; i++) {
        if (!(arm[i] > 0)) continue;
        const double *col = x_cols + (size_t)nv * c;
        for (int r = 0; r < nv; r++) qdd[r] -= col[r] * arm[i] * xj[c];
        c++;
    }
}
