/*
 * gdca_rake.h - raking a body's light subtrees into it: the kernels of the SUM and RAKE nodes of a
 * branched tree's plan (model.c, "the plan of a branched tree"), for the passes that keep handle
 * records in mobility form (the forward pass and the mobility-form inverse; the composite inverse
 * rakes composite inertias, gdca_inverse.c). Internal to the library; meant to be inlined into
 * CTC_SPECIALISE wrappers with a constant dim, like gdca_tree.h.
 *
 * A light child c of body k, its subtree assembled with its tip free (A1 = h11 F + h13), is joined
 * to k's point c as a chain's root is joined to the ground (gdca_forward_joint.h with no left
 * part; the mobility inverse: gdca_inverse_mobility.c), which gives its load
 *     F_c = W_c A_c + z_c,      W_c = E E^T,
 * with A_c body k's acceleration at c. Body k about its centre of mass, X = (alpha, a_com) and
 * A_c = T_c X + kappa_c (T(r) = [1 0; -[r]x 1], kappa_c = (0; w x (w x r_c)), r_c = c - com),
 * obeys M' X = b' + T_1^T F_1 + T_2^T F_2 with
 *     M' = M + sum_c T_c^T W_c T_c,     b' = b - sum_c T_c^T (W_c kappa_c + z_c),
 * M = diag(I_c, m 1) (planar diag(J, m, m)), b = (-w x I_c w; m g) (planar (0; m g)), the body's
 * handle-equation terms of handles.h. The pseudo-body's record is then
 *     h_ij = T_i M'^-1 T_j^T,   h_i3 = T_i x0 + kappa_i,   x0 = M'^-1 b',
 * which for no light child is handles.h's. In the plan the sums run over a binary tree of SUM
 * nodes, whose records hold a partial sum S = sum T_c^T W_c T_c (at H11) and
 * s = sum T_c^T (W_c kappa_c + z_c) (at H13); the sequential order (gdca_forward_tseq.c) sums them
 * in the order of k's children. d->rake keeps M'^-1 and x0 of each raked body for its disassembly
 * and for the refinement's bias-free correction (kappa = 0, b = 0, M' reused).
 */
#ifndef CTC_GDCA_RAKE_H
#define CTC_GDCA_RAKE_H

#include "data.h"
#include "gdca_tree.h"

/* doubles that d->rake holds per body: M'^-1 (dim x dim) and x0 (dim) */
static inline double *gdca_rake_slot(const ctc_data *d, int k, const int dim)
{
    return d->rake + (size_t)k * (dim * dim + dim);
}

/* kappa = (0; w x (w x r)) for body k's angular velocity w (planar: (0, -w^2 r)) */
static inline void gdca_rake_kappa(const ctc_data *d, int k, const int dim, const double r[3],
                                   double *kappa)
{
    const double *w = d->omega + 3 * k;
    if (dim == 3) {
        const double w2 = w[2] * w[2];
        kappa[0] = 0, kappa[1] = -w2 * r[0], kappa[2] = -w2 * r[1];
    } else {
        double wr[3];
        ctc_v3_cross(wr, w, r);
        ctc_v3_set(kappa, 0, 0, 0);
        ctc_v3_cross(kappa + 3, w, wr);
    }
}

/* r = point c (joint c's centre) - body k's centre of mass, and kappa of it, world (planar: the
   plane's) coordinates */
static inline void gdca_rake_point(const ctc_data *d, int k, int c, const int dim, double r[3],
                                   double *kappa)
{
    ctc_v3_sub(r, d->xpos + 3 * c, d->xcom + 3 * k);
    if (dim == 3) r[2] = 0;
    gdca_rake_kappa(d, k, dim, r, kappa);
}

/* out = T(r) a for a (dim x dim, row-major): a's rows transferred. Spatial, T = [1 0; X 1] with
   X y = y x r: the lower rows gain X times the upper ones, column by column; planar, rows 1 and 2
   gain -r_y and r_x times row 0. out may not alias a. */
static inline void gdca_rake_trows(const int dim, const double r[3], const double *a, double *out)
{
    for (int i = 0; i < dim * dim; i++) out[i] = a[i];
    if (dim == 3) {
        for (int c = 0; c < 3; c++) {
            out[3 + c] -= r[1] * a[c];
            out[6 + c] += r[0] * a[c];
        }
        return;
    }
    for (int c = 0; c < 6; c++) {
        const double y[3] = {a[c], a[6 + c], a[12 + c]};
        double x[3];
        ctc_v3_cross(x, y, r);
        out[18 + c] += x[0], out[24 + c] += x[1], out[30 + c] += x[2];
    }
}

/* out = a T(r)^T for a (dim x dim, row-major): a's columns transferred; spatial, row i's last
   three entries gain (its first three) x r; planar, columns 1 and 2 gain -r_y and r_x times
   column 0. out may not alias a. */
static inline void gdca_rake_tcols(const int dim, const double r[3], const double *a, double *out)
{
    for (int i = 0; i < dim * dim; i++) out[i] = a[i];
    if (dim == 3) {
        for (int i = 0; i < 3; i++) {
            out[3 * i + 1] -= r[1] * a[3 * i];
            out[3 * i + 2] += r[0] * a[3 * i];
        }
        return;
    }
    for (int i = 0; i < 6; i++) {
        double x[3];
        ctc_v3_cross(x, a + 6 * i, r);
        out[6 * i + 3] += x[0], out[6 * i + 4] += x[1], out[6 * i + 5] += x[2];
    }
}

/* out = E E^T x for E (dim x nc) made by gdca_joint_factor_typed for a joint of type `type`, or
   by the general factor when type < 0 */
static inline void gdca_rake_apply(const int dim, int type, int nc, const double *e,
                                   const double *x, double *out)
{
    if (type >= 0) {
        gdca_factor_apply_typed(dim, (ctc_joint_type)type, nc, e, x, out);
    } else {
        gdca_factor_apply_nc(dim, nc, e, x, out);
    }
}

/* one light child's terms: s (dim x dim; NULL: not formed) = T^T E E^T T and b (dim) =
   T^T (E E^T kappa + z), for E (dim x nc; type as gdca_rake_apply), r and kappa (NULL: zero) of
   gdca_rake_point */
static inline void gdca_rake_light(const int dim, int type, int nc, const double *e,
                                   const double r[3], const double *kappa, const double *z,
                                   double *s, double *b)
{
    double v[CTC_DENSE_MAX];
    if (kappa != NULL) {
        gdca_rake_apply(dim, type, nc, e, kappa, v);
        for (int i = 0; i < dim; i++) v[i] += z[i];
    } else {
        for (int i = 0; i < dim; i++) v[i] = z[i];
    }
    ctc_transfer_force(dim, r, v, b);
    if (s == NULL) return;
    double q[CTC_DENSE_MAX * CTC_DENSE_MAX], col[CTC_DENSE_MAX], tc[CTC_DENSE_MAX];
    for (int c = 0; c < nc; c++) { /* column c of Q = T^T E */
        for (int i = 0; i < dim; i++) col[i] = e[i * nc + c];
        ctc_transfer_force(dim, r, col, tc);
        for (int i = 0; i < dim; i++) q[i * nc + c] = tc[i];
    }
    for (int i = 0; i < dim; i++) {
        for (int j = i; j < dim; j++) {
            double t = 0;
            for (int c = 0; c < nc; c++) t += q[i * nc + c] * q[j * nc + c];
            s[i * dim + j] = s[j * dim + i] = t;
        }
    }
}

/* body k's M (dim x dim) and b (dim) about its centre of mass (handles.h): M that of the forward
 * bodies (model.h fwd_bodies, a singular body's augmented), b the body's own */
static inline void gdca_rake_body(const ctc_model *m, const ctc_data *d, int k, const int dim,
                                  double *mm, double *b)
{
    for (int i = 0; i < dim * dim; i++) mm[i] = 0;
    if (dim == 3) {
        const ctc_planar_body *p = &m->planar[k];
        mm[0] = p->fwd_inertia, mm[4] = mm[8] = p->fwd_mass;
        b[0] = 0, b[1] = p->mass * m->plane_gravity[0], b[2] = p->mass * m->plane_gravity[1];
        return;
    }
    const ctc_body_spec *body = &m->bodies[k];
    const double *w = d->omega + 3 * k;
    double iw[9], iww[3];
    const ctc_body_spec *fwd = &m->fwd_bodies[k];
    ctc_m3_rotate_sym(iw, d->xrot + 9 * k, fwd->inertia);
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) mm[6 * i + j] = iw[3 * i + j];
        mm[6 * (3 + i) + 3 + i] = fwd->mass;
    }
    if (fwd != body) ctc_m3_rotate_sym(iw, d->xrot + 9 * k, body->inertia);
    ctc_m3_mulv(iww, iw, w);
    ctc_v3_cross(b, iww, w); /* -w x I w */
    ctc_v3_scale(b + 3, m->gravity, body->mass);
}

/* The raked body's record (out, hsize) from M' (mm, dim x dim, overwritten) and b' (dim), its
 * handles r1, r2 relative to its centre of mass and kappa1, kappa2 (NULL: zero, the correction);
 * keeps M'^-1 and x0 in slot (gdca_rake_slot). matrices = 0 (the correction) reuses slot's M'^-1
 * and writes only h13 and h23. Returns 0, or -1 if M' is not positive definite. */
static inline int gdca_rake_record(const int dim, double *mm, const double *bp, const double *r1,
                                   const double *r2, const double *kappa1, const double *kappa2,
                                   double *slot, double *out, int matrices)
{
    double *minv = slot, *x0 = slot + dim * dim;
    int st = 0;
    if (matrices) {
        double li[CTC_DENSE_MAX * CTC_DENSE_MAX], p1[CTC_DENSE_MAX * CTC_DENSE_MAX];
        double p2[CTC_DENSE_MAX * CTC_DENSE_MAX];
        st = gdca_chol_inv(dim, mm, li); /* M' = L L^T, M'^-1 = L^-T L^-1 */
        for (int i = 0; i < dim; i++) {
            for (int j = i; j < dim; j++) {
                double t = 0;
                for (int k = j; k < dim; k++) t += li[k * dim + i] * li[k * dim + j];
                minv[i * dim + j] = minv[j * dim + i] = st == 0 ? t : NAN;
            }
        }
        gdca_rake_trows(dim, r1, minv, p1); /* T_i M'^-1 */
        gdca_rake_trows(dim, r2, minv, p2);
        gdca_rake_tcols(dim, r1, p1, out + H11(dim)); /* h_ij = (T_i M'^-1) T_j^T */
        gdca_rake_tcols(dim, r2, p1, out + H12(dim));
        gdca_rake_tcols(dim, r2, p2, out + H22(dim));
        for (int i = 0; i < dim; i++) { /* exactly symmetric */
            for (int j = i + 1; j < dim; j++) {
                out[H11(dim) + j * dim + i] = out[H11(dim) + i * dim + j];
                out[H22(dim) + j * dim + i] = out[H22(dim) + i * dim + j];
            }
        }
    }
    ctc_dense_mulv(dim, dim, minv, bp, x0);
    ctc_transfer_motion(dim, r1, x0, out + H13(dim));
    ctc_transfer_motion(dim, r2, x0, out + H23(dim));
    for (int i = 0; kappa1 != NULL && i < dim; i++) {
        out[H13(dim) + i] += kappa1[i];
        out[H23(dim) + i] += kappa2[i];
    }
    return st;
}

/* the raked body's X = (alpha, a_com) = x0 + M'^-1 (T_1^T F1 + T_2^T F2) from its loads */
static inline void gdca_rake_motion(const int dim, const double *slot, const double *r1,
                                    const double *r2, const double *f1, const double *f2, double *x)
{
    double t1[CTC_DENSE_MAX], t2[CTC_DENSE_MAX];
    ctc_transfer_force(dim, r1, f1, t1);
    ctc_transfer_force(dim, r2, f2, t2);
    for (int i = 0; i < dim; i++) t1[i] += t2[i];
    ctc_dense_mulv(dim, dim, slot, t1, t2);
    for (int i = 0; i < dim; i++) x[i] = slot[dim * dim + i] + t2[i];
}

/* a light child's A_c = T_c X + kappa (kappa NULL: zero) and load F_c = E E^T A_c + z (type as
   gdca_rake_apply) */
static inline void gdca_rake_child_load(const int dim, int type, int nc, const double *e,
                                        const double *z, const double r[3], const double *kappa,
                                        const double *x, double *ac, double *fc)
{
    ctc_transfer_motion(dim, r, x, ac);
    for (int i = 0; kappa != NULL && i < dim; i++) ac[i] += kappa[i];
    gdca_rake_apply(dim, type, nc, e, ac, fc);
    for (int i = 0; i < dim; i++) fc[i] += z[i];
}

#endif
