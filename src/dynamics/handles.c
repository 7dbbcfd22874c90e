/*
 * handles.c - body handle equations (handles.h), written out by component.
 *
 * Spatial: with S_i = -[r_i]x (S_i x = x x r_i) and G_i = S_i I^-1, the blocks are
 *     h_ij = [ I^-1   G_j^T ;  G_i   G_i S_j^T + 1/m ],   row a of G_i S_j^T = (row a of G_i) x r_j
 *     h_i3 = ( a0 ;  a0 x r_i + g + w x (w x r_i) ),     a0 = I^-1 (-w x I w)
 * Planar: h_ij = [1/J, -y_j/J, x_j/J; -y_i/J, y_i y_j/J + 1/m, -y_i x_j/J;
 *                 x_i/J, -x_i y_j/J, x_i x_j/J + 1/m],   h_i3 = (0, g_x - w^2 x_i, g_y - w^2 y_i).
 * M^-1 is that of the model's forward bodies (model.h fwd_bodies, planar fwd_mass, fwd_inertia):
 * a singular body's augmented inertia, whose error the forward pass's refinement removes
 * (gdca_refine.h); the bias b is the body's own.
 */
#include "handles.h"

#include "clones.h"
#include "gdca_par.h"
#include "spatial.h"

/* The least bodies from which the records are computed on the data's threads, where the
 * evaluation splits (data.h ctc_eval_gate): those of the composite inverse that follows
 * (gdca_inverse.c), so that the handles split only in evaluations whose passes split. */
#define HANDLES_MIN_BODIES_PLANAR 1024
#define HANDLES_MIN_BODIES_SPATIAL 256

/* what a range of bodies needs (gdca_par_bodies) */
typedef struct handles_args {
    const ctc_model *m;
    ctc_data *d;
} handles_args;

static void planar_block(double *h, const double ri[2], const double rj[2], double ij, double im)
{
    h[0] = ij;
    h[1] = -rj[1] * ij;
    h[2] = rj[0] * ij;
    h[3] = -ri[1] * ij;
    h[4] = ri[1] * rj[1] * ij + im;
    h[5] = -ri[1] * rj[0] * ij;
    h[6] = ri[0] * ij;
    h[7] = -ri[0] * rj[1] * ij;
    h[8] = ri[0] * rj[0] * ij + im;
}

/* Body k's handle 2: its heavy child's joint centre (model.h body_heavy; a chain's one child;
 * the light children are raked into a tree's body by the passes, gdca_rake.h), else the closing
 * joint's centre on the tip of a loop model, else the centre of mass c, where no load acts. */
static inline const double *handle2(const ctc_model *m, const ctc_data *d, int k, const double *c)
{
    const int child = m->body_heavy[k];
    return child >= 0                           ? d->xpos + 3 * child
           : m->has_loop && k == m->nbodies - 1 ? d->loop_pt /* the closing joint's parent */
                                                : c;
}

/* the handles and the matrices of the records of bodies first..end-1 */
static CTC_MULTIVERSION void handles_planar(void *ctx, int first, int end)
{
    const handles_args *args = ctx;
    const ctc_model *m = args->m;
    ctc_data *d = args->d;
    for (int k = first; k < end; k++) {
        const ctc_planar_body *b = &m->planar[k];
        const double *c = d->xcom + 3 * k;
        const double *next = handle2(m, d, k, c);
        double *hr = d->hr + 6 * k;
        double r1[2] = {d->xpos[3 * k] - c[0], d->xpos[3 * k + 1] - c[1]};
        double r2[2] = {next[0] - c[0], next[1] - c[1]};
        ctc_v3_set(hr, r1[0], r1[1], 0);
        ctc_v3_set(hr + 3, r2[0], r2[1], 0);

        double *h = d->hbody + (size_t)k * d->hsize;
        const double ij = 1.0 / b->fwd_inertia, im = 1.0 / b->fwd_mass;
        planar_block(h, r1, r1, ij, im);      /* h11 */
        planar_block(h + 9, r1, r2, ij, im);  /* h12 */
        planar_block(h + 18, r2, r2, ij, im); /* h22 */
    }
}

/* h13 and h23 of bodies first..end-1 from their handles d->hr */
static CTC_MULTIVERSION void handles_bias_planar(void *ctx, int first, int end)
{
    const handles_args *args = ctx;
    const ctc_model *m = args->m;
    ctc_data *d = args->d;
    const double *g = m->plane_gravity;
    for (int k = first; k < end; k++) {
        const double *r1 = d->hr + 6 * k, *r2 = d->hr + 6 * k + 3;
        double *h = d->hbody + (size_t)k * d->hsize, w2 = d->omega[3 * k + 2];
        w2 *= w2;
        ctc_v3_set(h + 27, 0, g[0] - w2 * r1[0], g[1] - w2 * r1[1]);
        ctc_v3_set(h + 30, 0, g[0] - w2 * r2[0], g[1] - w2 * r2[1]);
    }
}

/* h = [ iw  G_j^T ; G_i  G_i S_j^T + 1/m ] (6x6 row-major), row by row; row a of G_i S_j^T is
 * (row a of G_i) x r_j, and 1/m goes on the diagonal only */
static inline void spatial_block(double *h, const double iw[9], const double gi[9],
                                 const double gj[9], const double rj[3], double im)
{
    for (int a = 0; a < 3; a++) {
        double *top = h + 6 * a, *bottom = h + 6 * (a + 3);
        const double *ga = gi + 3 * a;
        ctc_v3_copy(top, iw + 3 * a);
        ctc_v3_set(top + 3, gj[a], gj[3 + a], gj[6 + a]);
        ctc_v3_copy(bottom, ga);
        ctc_v3_cross(bottom + 3, ga, rj);
        bottom[3 + a] += im;
    }
}

/* the handles and the matrices of the records of bodies first..end-1 */
static CTC_MULTIVERSION void handles_spatial(void *ctx, int first, int end)
{
    const handles_args *args = ctx;
    const ctc_model *m = args->m;
    ctc_data *d = args->d;
    for (int k = first; k < end; k++) {
        const double *rot = d->xrot + 9 * k, *c = d->xcom + 3 * k;
        const double *next = handle2(m, d, k, c);
        double *r1 = d->hr + 6 * k, *r2 = d->hr + 6 * k + 3;
        ctc_v3_sub(r1, d->xpos + 3 * k, c);
        ctc_v3_sub(r2, next, c);

        /* inverse inertia in world axes; G_i = S_i I^-1, column j = (row j of I^-1) x r_i */
        double iw[9], g1[9], g2[9];
        ctc_m3_rotate_sym(iw, rot, &m->body_inertia_inv[9 * k]);
        for (int j = 0; j < 3; j++) {
            double c1[3], c2[3];
            ctc_v3_cross(c1, &iw[3 * j], r1);
            ctc_v3_cross(c2, &iw[3 * j], r2);
            for (int a = 0; a < 3; a++) {
                g1[3 * a + j] = c1[a];
                g2[3 * a + j] = c2[a];
            }
        }
        double *h = d->hbody + (size_t)k * d->hsize;
        double im = 1.0 / m->fwd_bodies[k].mass;
        spatial_block(h, iw, g1, g1, r1, im);      /* h11 */
        spatial_block(h + 36, iw, g1, g2, r2, im); /* h12 */
        spatial_block(h + 72, iw, g2, g2, r2, im); /* h22 */
    }
}

/* h13 and h23 of bodies first..end-1 from their handles d->hr and the inverse inertia in world
 * axes that h11 holds in its upper left block */
static CTC_MULTIVERSION void handles_bias_spatial(void *ctx, int first, int end)
{
    const handles_args *args = ctx;
    const ctc_model *m = args->m;
    ctc_data *d = args->d;
    for (int k = first; k < end; k++) {
        const ctc_body_spec *body = &m->bodies[k];
        const double *rot = d->xrot + 9 * k, *w = d->omega + 3 * k;
        const double *r1 = d->hr + 6 * k, *r2 = d->hr + 6 * k + 3;
        double *h = d->hbody + (size_t)k * d->hsize, iw[9], t[3];
        for (int i = 0; i < 3; i++) ctc_v3_copy(iw + 3 * i, h + 6 * i);

        /* gyroscopic term: a0 = I^-1 (-w x I w), I w = R I_b R^T w */
        double wb[3], iwb[3], iww[3], gyro[3], a0[3];
        ctc_m3_tmulv(wb, rot, w);
        ctc_m3_mulv(iwb, body->inertia, wb);
        ctc_m3_mulv(iww, rot, iwb);
        ctc_v3_cross(gyro, iww, w); /* = -w x I w */
        ctc_m3_mulv(a0, iw, gyro);

        /* h_i3 = (a0; a0 x r_i + g + w x (w x r_i)) */
        double *h13 = h + 108, *h23 = h + 114;
        for (int i = 0; i < 2; i++) {
            const double *r = i ? r2 : r1;
            double *hi = i ? h23 : h13, wr[3], wwr[3];
            ctc_v3_copy(hi, a0);
            ctc_v3_cross(t, a0, r);
            ctc_v3_cross(wr, w, r);
            ctc_v3_cross(wwr, w, wr);
            ctc_v3_add(hi + 3, t, m->gravity);
            ctc_v3_add(hi + 3, hi + 3, wwr);
        }
    }
}

/* the records' part `bodies` (handles_planar or _spatial, or their biases) of every body, on the
   data's threads where the evaluation splits */
static void handles_run(const ctc_model *m, ctc_data *d, void (*bodies)(void *, int, int))
{
    handles_args args = {m, d};
    const int least =
        m->form == CTC_FORM_PLANAR ? HANDLES_MIN_BODIES_PLANAR : HANDLES_MIN_BODIES_SPATIAL;
    if (!gdca_par_bodies(m, d, bodies, &args, least)) bodies(&args, 0, m->nbodies);
}

void ctc_handles(const ctc_model *m, ctc_data *d)
{
    d->handles_stamp++; /* a new state: the composite inverse recomputes its records */
    if (m->dyn != NULL) {
        /* merged bodies (model.h): the records of the reduced model's bodies */
        ctc_handles(m->dyn, ctc_data_dyn_begin(m, d));
        return;
    }
    handles_run(m, d, m->form == CTC_FORM_PLANAR ? handles_planar : handles_spatial);
}

void ctc_handles_bias(const ctc_model *m, ctc_data *d)
{
    if (m->dyn != NULL) {
        ctc_handles_bias(m->dyn, ctc_data_dyn_begin(m, d));
        return;
    }
    if (d->hbias_stamp == d->handles_stamp) return;
    handles_run(m, d, m->form == CTC_FORM_PLANAR ? handles_bias_planar : handles_bias_spatial);
    d->hbias_stamp = d->handles_stamp;
}
