/*
 * gdca_loop.c - the closed chain's boundary equations (gdca_loop.h).
 *
 * The matrix is built column by column: each unknown's unit load, applied to the records, gives
 * the relative accelerations of every bounding joint, and the rows take them along each joint's
 * S. The same function with the known loads and the records' bias terms gives the right-hand
 * side, and once more with the solution the loads' accelerations.
 */
#include "gdca_loop.h"

#include <math.h>

#include "gdca_tree.h"

#define NB (3 * CTC_DENSE_MAX)

/* relative pivot below which the scaled system counts as singular */
#define BOUNDARY_PIVOT_MIN 1e-13

/* column c of S (identity when s is NULL) */
static inline double s_at(const gdca_end *e, int dim, int row, int c)
{
    return e->s ? e->s[c * dim + row] : (double)(row == c);
}

void gdca_loop_shift_accel(int dim, const double *r, const double *gam, const double *in,
                           double *out)
{
    ctc_transfer_motion(dim, r, in, out);
    for (int i = 0; i < dim; i++) out[i] += gam[i];
}

/* a1 = h11 f1 + h12 f2 (+ b13), a2 = h21 f1 + h22 f2 (+ b23), the biases b the record's h13,
   h23 or those of b (when not NULL) */
static void record_accel(int dim, const double *h, const double *const b[2], const double *f1,
                         const double *f2, int bias, double *a1, double *a2)
{
    double t[CTC_DENSE_MAX];
    const double *b13 = b[0] ? b[0] : h + H13(dim), *b23 = b[1] ? b[1] : h + H23(dim);
    ctc_dense_mulv(dim, dim, h + H11(dim), f1, a1);
    ctc_dense_mulv(dim, dim, h + H12(dim), f2, t);
    for (int i = 0; i < dim; i++) a1[i] += t[i] + (bias ? b13[i] : 0.0);
    ctc_dense_tmulv(dim, dim, h + H12(dim), f1, a2);
    ctc_dense_mulv(dim, dim, h + H22(dim), f2, t);
    for (int i = 0; i < dim; i++) a2[i] += t[i] + (bias ? b23[i] : 0.0);
}

/* The accelerations that the loads f[0], f[1], f[2] on the children of joints 0, j and n cause
 * (with the records' bias terms, and gam, when bias), into s; w[J] gets joint J's relative
 * acceleration A_child - A_parent. */
static void root_accel(const gdca_loop_root *p, const double f[3][CTC_DENSE_MAX], int bias,
                       gdca_loop_sol *s, double w[3][CTC_DENSE_MAX])
{
    const int dim = p->dim;
    double neg[CTC_DENSE_MAX] = {0};
    for (int i = 0; i < dim; i++) neg[i] = -f[2][i];
    record_accel(dim, p->r, p->rb, f[1], neg, bias, s->ar1, s->ar2);
    if (p->l == NULL) {
        for (int i = 0; i < dim; i++) {
            s->al1[i] = s->al2[i] = s->ab[i] = w[0][i] = 0;
            w[1][i] = s->ar1[i];
            w[2][i] = -s->ar2[i];
        }
        return;
    }
    double fl2[CTC_DENSE_MAX] = {0};
    ctc_transfer_force(dim, p->shift, f[2], fl2);
    for (int i = 0; i < dim; i++) fl2[i] -= f[1][i];
    record_accel(dim, p->l, p->lb, f[0], fl2, bias, s->al1, s->al2);
    gdca_loop_shift_accel(dim, p->shift, bias ? p->gam : gdca_zero6, s->al2, s->ab);
    for (int i = 0; i < dim; i++) {
        w[0][i] = s->al1[i];
        w[1][i] = s->ar1[i] - s->al2[i];
        w[2][i] = s->ab[i] - s->ar2[i];
    }
}

static void fail(int dim, gdca_loop_sol *s)
{
    s->cond = INFINITY;
    for (int i = 0; i < dim; i++) {
        s->f0[i] = s->fj[i] = s->fn[i] = NAN;
        s->al1[i] = s->al2[i] = s->ar1[i] = s->ar2[i] = s->ab[i] = NAN;
    }
}

int gdca_loop_solve(const gdca_loop_root *p, gdca_loop_sol *s)
{
    const int dim = p->dim;
    const gdca_end *ends[3] = {p->l ? &p->e0 : NULL, &p->ej, &p->en};
    int owner[NB], col[NB], nb = 0; /* each unknown's joint and its column there */
    for (int e = 0; e < 3; e++) {
        for (int c = 0; ends[e] && c < ends[e]->ns; c++, nb++) owner[nb] = e, col[nb] = c;
    }
    double f[3][CTC_DENSE_MAX] = {{0}}, w[3][CTC_DENSE_MAX], wc[NB][3][CTC_DENSE_MAX];
    double b[NB * NB], r[NB], x[NB], scale[NB];

    /* the right-hand side S^T (a - w(fo)) - off, with the known loads and the bias terms */
    for (int e = 0; e < 3; e++)
        for (int i = 0; ends[e] && i < dim; i++) f[e][i] = ends[e]->fo[i];
    root_accel(p, (const double(*)[CTC_DENSE_MAX])f, 1, s, w);
    for (int a = 0; a < nb; a++) {
        const gdca_end *e = ends[owner[a]];
        double t = e->off ? -e->off[col[a]] : 0.0;
        for (int i = 0; i < dim; i++) t += s_at(e, dim, i, col[a]) * (e->a[i] - w[owner[a]][i]);
        r[a] = t;
    }

    /* B: column c holds what unknown c's unit load does to every row */
    for (int c = 0; c < nb; c++) {
        double fc[3][CTC_DENSE_MAX] = {{0}};
        for (int i = 0; i < dim; i++) fc[owner[c]][i] = s_at(ends[owner[c]], dim, i, col[c]);
        root_accel(p, (const double(*)[CTC_DENSE_MAX])fc, 0, s, wc[c]);
    }
    for (int a = 0; a < nb; a++) {
        const gdca_end *e = ends[owner[a]];
        for (int c = 0; c < nb; c++) {
            double t = 0;
            for (int i = 0; i < dim; i++) t += s_at(e, dim, i, col[a]) * wc[c][owner[a]][i];
            b[a * nb + c] = t;
        }
    }

    /* symmetric scaling, Cholesky, condition estimate from the pivots */
    int ok = 1;
    for (int a = 0; a < nb; a++) {
        double dgl = b[a * nb + a];
        if (!(dgl > 0)) ok = 0;
        scale[a] = dgl > 0 ? 1.0 / sqrt(dgl) : 1.0;
    }
    for (int a = 0; ok && a < nb; a++) {
        for (int c = 0; c < nb; c++) b[a * nb + c] *= scale[a] * scale[c];
        r[a] *= scale[a];
    }
    if (ok && ctc_dense_cholesky(nb, b) != 0) ok = 0;
    double pmin = INFINITY, pmax = 0;
    for (int a = 0; ok && a < nb; a++) {
        double piv = b[a * nb + a];
        pmin = fmin(pmin, piv);
        pmax = fmax(pmax, piv);
    }
    if (ok && !(pmin > BOUNDARY_PIVOT_MIN * pmax)) ok = 0;
    if (!ok) {
        fail(dim, s);
        return -1;
    }
    s->cond = nb ? (pmax / pmin) * (pmax / pmin) : 1.0;
    for (int a = 0; a < nb; a++) x[a] = r[a];
    ctc_dense_lsolve(nb, b, x);
    ctc_dense_ltsolve(nb, b, x);
    for (int a = 0; a < nb; a++) {
        x[a] *= scale[a];
        for (int i = 0; i < dim; i++) f[owner[a]][i] += s_at(ends[owner[a]], dim, i, col[a]) * x[a];
    }

    /* the loads and what they do */
    root_accel(p, (const double(*)[CTC_DENSE_MAX])f, 1, s, w);
    for (int i = 0; i < dim; i++) {
        s->f0[i] = p->l ? f[0][i] : f[1][i];
        s->fj[i] = f[1][i];
        s->fn[i] = f[2][i];
    }
    return 0;
}

void gdca_loop_hand_down(const ctc_model *m, const gdca_loop_sol *s, const double *shift, int add,
                         double *tload, double *jnt_load)
{
    const int dim = m->dim, n = m->nbodies, j = m->loop_first;
    const ctc_tree_node *top = &m->tree[m->ntree - 1];
    const int at[3] = {0, j, n};
    const double *f[3] = {s->f0, s->fj, s->fn};
    for (int e = 0; e < 3; e++) {
        if (e == 1 && j == 0) continue; /* joint j is joint 0 */
        for (int i = 0; i < dim; i++) {
            double *x = jnt_load + dim * at[e] + i;
            *x = add ? *x + f[e][i] : f[e][i];
        }
    }
    if (j == 0) {
        double *t = tload + (size_t)m->root * 2 * dim;
        for (int i = 0; i < dim; i++) t[i] = s->fj[i], t[dim + i] = -s->fn[i];
        return;
    }
    double *tl = tload + (size_t)top->left * 2 * dim, *tr = tload + (size_t)top->right * 2 * dim;
    ctc_transfer_force(dim, shift, s->fn, tl + dim);
    for (int i = 0; i < dim; i++) {
        tl[i] = s->f0[i];
        tl[dim + i] -= s->fj[i];
        tr[i] = s->fj[i];
        tr[dim + i] = -s->fn[i];
    }
}

void gdca_loop_offset(const ctc_model *m, const ctc_data *d, double *off)
{
    const double a = d->baumgarte[0], b = d->baumgarte[1];
    for (int c = 0; c < m->dim - m->jnt_nv[m->nbodies]; c++) {
        off[c] = 2 * a * d->loop_dphi[c] + b * b * d->loop_phi[c];
    }
}
