/*
 * test_handles.c - the body handle equations (src/dynamics/handles.c) against Newton-Euler written
 * out.
 *
 * For each body of random chains, random loads F1 = (tau1; f1) at handle 1 (the body's origin)
 * and F2 at handle 2 (the next body's origin, the CoM for the tip) give the body's motion
 *     m a_c = f1 + f2 + m g,    I_c alpha + w x I_c w = tau1 + tau2 + r1 x f1 + r2 x f2,
 * with I_c = R I_body R^T in world axes (planar: J alpha = ..., 2-D cross products), solved here
 * by Cramer's rule; the handle accelerations a_i = a_c + alpha x r_i + w x (w x r_i) must equal
 * A1 = h11 F1 + h12 F2 + h13 and A2 = h12^T F1 + h22 F2 + h23 read from the record (data.h).
 * A chain with fixed joints is checked on the bodies the passes see, the merged ones (model.h
 * "merged bodies"). The passes that read the bias terms h13 and h23 ask for them
 * (ctc_handles_bias): one test holds them to a fresh data's results at a second state.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "chains.h"
#include "data.h"
#include "gdca.h"
#include "handles.h"
#include "kinematics.h"
#include "model.h"
#include "spatial.h"

#define MAXQ 64
#define MAXV 48

static void cross3(const double a[3], const double b[3], double c[3])
{
    c[0] = a[1] * b[2] - a[2] * b[1];
    c[1] = a[2] * b[0] - a[0] * b[2];
    c[2] = a[0] * b[1] - a[1] * b[0];
}

static double det3(const double a[9])
{
    return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) +
           a[2] * (a[3] * a[7] - a[4] * a[6]);
}

/* x = A^-1 b by Cramer's rule */
static void solve3(const double a[9], const double b[3], double x[3])
{
    double det = det3(a);
    for (int c = 0; c < 3; c++) {
        double t[9];
        memcpy(t, a, sizeof t);
        for (int r = 0; r < 3; r++) t[3 * r + c] = b[r];
        x[c] = det3(t) / det;
    }
}

/* y = H x, H (dim x dim) row-major, or H^T x when transpose */
static void block_mulv(int dim, const double *h, int transpose, const double *x, double *y)
{
    for (int i = 0; i < dim; i++) {
        double s = 0;
        for (int j = 0; j < dim; j++) s += (transpose ? h[j * dim + i] : h[i * dim + j]) * x[j];
        y[i] = s;
    }
}

/* Newton-Euler: handle accelerations a1, a2 (dim each) of body k under F1, F2 */
static void newton_euler_spatial(const ctc_model *m, const ctc_data *d, int k, const double r1[3],
                                 const double r2[3], const double *F1, const double *F2, double *a1,
                                 double *a2)
{
    const ctc_body_spec *b = &m->bodies[k];
    const double *R = d->xrot + 9 * k, *w = d->omega + 3 * k;
    double ic[9], t[9];

    /* I_c = R I_body R^T */
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            t[3 * i + j] = 0;
            for (int l = 0; l < 3; l++) t[3 * i + j] += R[3 * i + l] * b->inertia[3 * l + j];
        }
    }
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) {
            ic[3 * i + j] = 0;
            for (int l = 0; l < 3; l++) ic[3 * i + j] += t[3 * i + l] * R[3 * j + l];
        }
    }

    /* torque about the CoM, less the gyroscopic term; force */
    double iw[3], gyro[3], m1[3], m2[3], tau[3], alpha[3], ac[3];
    for (int i = 0; i < 3; i++)
        iw[i] = ic[3 * i] * w[0] + ic[3 * i + 1] * w[1] + ic[3 * i + 2] * w[2];
    cross3(w, iw, gyro);
    cross3(r1, F1 + 3, m1);
    cross3(r2, F2 + 3, m2);
    for (int i = 0; i < 3; i++) {
        tau[i] = F1[i] + F2[i] + m1[i] + m2[i] - gyro[i];
        ac[i] = (F1[3 + i] + F2[3 + i]) / b->mass + m->gravity[i];
    }
    solve3(ic, tau, alpha);

    for (int h = 0; h < 2; h++) {
        const double *r = h ? r2 : r1;
        double *out = h ? a2 : a1, ar[3], wr[3], wwr[3];
        cross3(alpha, r, ar);
        cross3(w, r, wr);
        cross3(w, wr, wwr);
        for (int i = 0; i < 3; i++) {
            out[i] = alpha[i];
            out[3 + i] = ac[i] + ar[i] + wwr[i];
        }
    }
}

static void newton_euler_planar(const ctc_model *m, const ctc_data *d, int k, const double r1[3],
                                const double r2[3], const double *F1, const double *F2, double *a1,
                                double *a2)
{
    const ctc_body_spec *b = &m->bodies[k];
    const double *n = m->plane_n, *in = b->inertia;
    double g[2] = {0, 0};
    /* J = n . I n about the CoM (n is the same in body and world axes: bodies turn about it);
       gravity in plane coordinates */
    double j = 0;
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) j += n[r] * in[3 * r + c] * n[c];
        g[0] += m->gravity[r] * m->plane_e1[r];
        g[1] += m->gravity[r] * m->plane_e2[r];
    }
    double w = d->omega[3 * k + 2];
    double tau = F1[0] + F2[0] + (r1[0] * F1[2] - r1[1] * F1[1]) + (r2[0] * F2[2] - r2[1] * F2[1]);
    double alpha = tau / j;
    double ac[2] = {(F1[1] + F2[1]) / b->mass + g[0], (F1[2] + F2[2]) / b->mass + g[1]};
    for (int h = 0; h < 2; h++) {
        const double *r = h ? r2 : r1;
        double *out = h ? a2 : a1;
        out[0] = alpha;
        out[1] = ac[0] - alpha * r[1] - w * w * r[0];
        out[2] = ac[1] + alpha * r[0] - w * w * r[1];
    }
}

typedef struct handle_errors {
    double accel; /* worst relative error of A1, A2 against Newton-Euler */
    double sym;   /* worst asymmetry of h11, h22 relative to their largest entry */
    int bodies;   /* bodies checked */
    int planar;   /* of which in planar form */
} handle_errors;

/* checks every body of chain c in state drawn from rng; accumulates into e */
static void check_chain(const ctc_chain_spec *spec, uint64_t *rng, handle_errors *e)
{
    char err[256] = "";
    ctc_model *given;
    cr_assert_eq(ctc_model_build(spec, &given, err, sizeof err), CTC_OK, "%s", err);
    ctc_data *dgiven = ctc_data_new(given);
    cr_assert_not_null(dgiven);
    double q[MAXQ], v[MAXV];
    cr_assert_leq(given->nq, MAXQ);
    cr_assert_leq(given->nv, MAXV);
    /* a first state whose bias terms are filled, then the state checked: its ctc_handles must
       have the bias terms recomputed (handles.h ctc_handles_bias) */
    test_random_state(given, rng, 3.0, q, v);
    ctc_kinematics(given, dgiven, q, v);
    ctc_handles(given, dgiven);
    ctc_handles_bias(given, dgiven);
    test_random_state(given, rng, 3.0, q, v);
    ctc_kinematics(given, dgiven, q, v);
    ctc_handles(given, dgiven);
    ctc_handles_bias(given, dgiven);
    /* the records are the bodies' the passes see: with fixed joints, the merged ones (model.h
       "merged bodies"), whose kinematics ctc_kinematics also fills */
    const ctc_model *m = given->dyn != NULL ? given->dyn : given;
    const ctc_data *d = given->dyn != NULL ? dgiven->dyn : dgiven;
    int dim = m->dim, n = m->nbodies;

    for (int k = 0; k < n; k++) {
        const double *c = d->xcom + 3 * k;
        const double *next = k + 1 < n ? d->xpos + 3 * (k + 1) : c;
        double r1[3], r2[3];
        for (int i = 0; i < 3; i++) {
            r1[i] = d->xpos[3 * k + i] - c[i];
            r2[i] = next[i] - c[i];
        }
        for (int i = 0; i < 3; i++) {
            cr_assert_leq(fabs(d->hr[6 * k + i] - r1[i]), 1e-15, "body %d: r1[%d]", k, i);
            cr_assert_leq(fabs(d->hr[6 * k + 3 + i] - r2[i]), 1e-15, "body %d: r2[%d]", k, i);
        }

        double F1[6], F2[6], want1[6], want2[6], got1[6], got2[6], t1[6], t2[6];
        for (int i = 0; i < dim; i++) {
            F1[i] = test_uniform(rng, -5, 5);
            F2[i] = test_uniform(rng, -5, 5);
        }
        if (dim == 6) {
            newton_euler_spatial(m, d, k, r1, r2, F1, F2, want1, want2);
        } else {
            newton_euler_planar(m, d, k, r1, r2, F1, F2, want1, want2);
        }

        const double *h = ctc_data_handles(m, d, k, 0);
        const double *h11 = h, *h12 = h + dim * dim, *h22 = h + 2 * dim * dim;
        const double *h13 = h + 3 * dim * dim, *h23 = h13 + dim;
        cr_assert_eq(h, ctc_data_handles(m, d, k, 1), "bodies share one record");
        block_mulv(dim, h11, 0, F1, got1);
        block_mulv(dim, h12, 0, F2, t1);
        block_mulv(dim, h12, 1, F1, got2);
        block_mulv(dim, h22, 0, F2, t2);
        double scale = 1.0;
        for (int i = 0; i < dim; i++) {
            got1[i] += t1[i] + h13[i];
            got2[i] += t2[i] + h23[i];
            scale = fmax(scale, fmax(fabs(want1[i]), fabs(want2[i])));
        }
        for (int i = 0; i < dim; i++) {
            double e1 = fabs(got1[i] - want1[i]) / scale, e2 = fabs(got2[i] - want2[i]) / scale;
            e->accel = fmax(e->accel, fmax(e1, e2));
            cr_assert_leq(e1, 1e-12, "%s body %d: A1[%d] = %.17g, Newton-Euler %.17g",
                          ctc_form_name(m->form), k, i, got1[i], want1[i]);
            cr_assert_leq(e2, 1e-12, "%s body %d: A2[%d] = %.17g, Newton-Euler %.17g",
                          ctc_form_name(m->form), k, i, got2[i], want2[i]);
        }

        /* h11, h22 symmetric to rounding */
        for (int b = 0; b < 2; b++) {
            const double *hb = b ? h22 : h11;
            double big = 0, asym = 0;
            for (int i = 0; i < dim * dim; i++) big = fmax(big, fabs(hb[i]));
            for (int i = 0; i < dim; i++) {
                for (int j = i + 1; j < dim; j++) {
                    asym = fmax(asym, fabs(hb[i * dim + j] - hb[j * dim + i]));
                }
            }
            e->sym = fmax(e->sym, asym / big);
            cr_assert_leq(asym, 1e-14 * big, "%s body %d: h%d%d asymmetric by %.3e",
                          ctc_form_name(m->form), k, b + 1, b + 1, asym);
        }
        e->bodies++;
        e->planar += m->form == CTC_FORM_PLANAR;
    }
    ctc_data_free(dgiven);
    ctc_model_free(given);
}

Test(handles, spatial_records_match_newton_euler_on_random_chains)
{
    handle_errors e = {0};
    uint64_t rng = 42;
    const int sizes[] = {1, 2, 7, 12};
    for (int s = 0; s < 4; s++) {
        for (uint64_t seed = 1; seed <= 4; seed++) {
            test_chain *c =
                test_chain_random_spatial(sizes[s], 100 * seed + sizes[s], TEST_ALL_JOINTS);
            check_chain(&c->spec, &rng, &e);
            test_chain_free(c);
        }
    }
    cr_assert_eq(e.planar, 0);
    cr_log_info("spatial handles vs Newton-Euler over %d bodies: worst relative error %.2e "
                "(tolerance 1e-12), asymmetry %.2e (tolerance 1e-14)",
                e.bodies, e.accel, e.sym);
}

Test(handles, planar_records_match_newton_euler_on_random_chains)
{
    /* full-rank bodies with prismatic joints, and slender rods (singular 3-D inertia) */
    handle_errors e = {0};
    uint64_t rng = 43;
    const int sizes[] = {1, 2, 7, 12};
    for (int s = 0; s < 4; s++) {
        for (uint64_t seed = 1; seed <= 4; seed++) {
            for (int rods = 0; rods < 2; rods++) {
                test_chain *c =
                    test_chain_random_planar(sizes[s], 100 * seed + sizes[s], !rods, rods);
                check_chain(&c->spec, &rng, &e);
                test_chain_free(c);
            }
        }
    }
    cr_assert_eq(e.planar, e.bodies, "a planar chain was not computed in planar form");
    cr_log_info("planar handles vs Newton-Euler over %d bodies: worst relative error %.2e "
                "(tolerance 1e-12), asymmetry %.2e (tolerance 1e-14)",
                e.bodies, e.accel, e.sym);
}

Test(handles, planar_chain_in_spatial_form_matches_newton_euler)
{
    /* the same planar chains forced to spatial form go through the 6-D records */
    handle_errors e = {0};
    uint64_t rng = 44;
    for (uint64_t seed = 1; seed <= 4; seed++) {
        test_chain *c = test_chain_random_planar(7, seed, 1, 0);
        c->spec.form = CTC_FORM_SPATIAL;
        check_chain(&c->spec, &rng, &e);
        test_chain_free(c);
    }
    cr_assert_eq(e.planar, 0);
    cr_log_info("planar chains in spatial form: worst relative error %.2e (tolerance 1e-12)",
                e.accel);
}

Test(handles, planar_records_in_a_tilted_plane_match_newton_euler)
{
    /* random planar chains rotated as a whole: J = n . I n, gravity (g . e1, g . e2) */
    handle_errors e = {0};
    uint64_t rng = 45;
    for (uint64_t seed = 1; seed <= 6; seed++) {
        test_chain *c = test_chain_random_planar(7, seed, 1, seed % 2);
        double axis[3] = {test_uniform(&rng, -1, 1), test_uniform(&rng, -1, 1), 0.4}, rot[9];
        ctc_v3_scale(axis, axis, 1.0 / ctc_v3_norm(axis));
        ctc_m3_axis_angle(rot, axis, test_uniform(&rng, 0.3, 2.8));
        test_chain_rotate(c, rot);
        check_chain(&c->spec, &rng, &e);
        test_chain_free(c);
    }
    cr_assert_eq(e.planar, e.bodies, "a rotated chain was not computed in planar form");
    cr_log_info("tilted planar handles vs Newton-Euler: worst relative error %.2e (tolerance "
                "1e-12)",
                e.accel);
}

Test(handles, tip_handle_2_is_the_centre_of_mass)
{
    /* the tip body's handle 2 is its CoM: r2 = 0, so h22 is the CoM's mobility diag(I^-1, 1/m)
       and h23 = (I^-1 (-w x I w); g) has no centripetal part */
    test_chain *c = test_chain_random_planar(3, 9, 0, 0);
    char err[256] = "";
    ctc_model *m;
    cr_assert_eq(ctc_model_build(&c->spec, &m, err, sizeof err), CTC_OK, "%s", err);
    ctc_data *d = ctc_data_new(m);
    double q[3] = {0.3, -1.1, 2.0}, v[3] = {1.5, -2.0, 0.7};
    ctc_kinematics(m, d, q, v);
    ctc_handles(m, d);
    ctc_handles_bias(m, d);
    const double *hr = d->hr + 6 * 2, *h = ctc_data_handles(m, d, 2, 0);
    for (int i = 0; i < 3; i++) cr_assert_eq(hr[3 + i], 0.0, "r2[%d] = %g", i, hr[3 + i]);
    double j = c->bodies[2].inertia[8], mass = c->bodies[2].mass;
    double want22[9] = {1 / j, 0, 0, 0, 1 / mass, 0, 0, 0, 1 / mass};
    double want23[3] = {0, 0, -9.81};
    for (int i = 0; i < 9; i++) {
        cr_assert_leq(fabs(h[18 + i] - want22[i]), 1e-15 * fabs(want22[0]) + 1e-15,
                      "h22[%d] = %.17g, want %.17g", i, h[18 + i], want22[i]);
    }
    for (int i = 0; i < 3; i++) {
        cr_assert_leq(fabs(h[30 + i] - want23[i]), 1e-15, "h23[%d] = %.17g, want %.17g", i,
                      h[30 + i], want23[i]);
    }
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
}

/* One state of m in d and fresh, the bias terms filled in fresh only */
static void set_state(const ctc_model *m, ctc_data *d, ctc_data *fresh, const test_loop *l,
                      uint64_t *rng)
{
    double q[MAXQ], v[MAXV];
    test_random_state(m, rng, 2.0, q, v);
    if (l != NULL) memcpy(q, l->q0, (size_t)m->nq * sizeof *q); /* a closed pose */
    for (int w = 0; w < 2; w++) {
        ctc_kinematics(m, w ? fresh : d, q, v);
        ctc_handles(m, w ? fresh : d);
    }
    ctc_handles_bias(m, fresh);
}

/* The passes that read the bias terms (the literal forward pass, also on a loop, and the
   mobility-form inverse) ask for them: after a state whose bias terms were filled, each pass at
   a new state gives bitwise what it gives from records filled at that state. */
Test(handles, passes_take_the_bias_terms_of_the_current_state)
{
    uint64_t rng = 46;
    for (int c = 0; c < 3; c++) {
        test_chain *ch = c == 0   ? test_chain_random_spatial(7, 5, TEST_ALL_JOINTS)
                         : c == 1 ? test_chain_random_planar(7, 6, 1, 0)
                                  : NULL;
        test_loop *l = c == 2 ? test_loop_spatial(8, 7) : NULL;
        char err[256] = "";
        ctc_model *m;
        cr_assert_eq(ctc_model_build(l ? &l->spec : &ch->spec, &m, err, sizeof err), CTC_OK, "%s",
                     err);
        cr_assert_leq(m->nq, MAXQ);
        cr_assert_leq(m->nvx, MAXV);
        ctc_data *d = ctc_data_new(m), *fresh = ctc_data_new(m);
        d->opt.fwd_form = fresh->opt.fwd_form = CTC_FWD_LITERAL;
        double f[MAXV], a[MAXV], want[MAXV], got[MAXV];
        for (int i = 0; i < m->nvx; i++) f[i] = test_uniform(&rng, -3, 3);
        for (int i = 0; i < m->nvx; i++) a[i] = test_uniform(&rng, -3, 3);
        set_state(m, d, fresh, l, &rng);
        ctc_handles_bias(m, d); /* the first state's, which the passes must not read */
        set_state(m, d, fresh, l, &rng);
        ctc_gdca_forward(m, d, f, got);
        ctc_gdca_forward(m, fresh, f, want);
        cr_assert_arr_eq(got, want, (size_t)m->nvx * sizeof *got, "model %d: forward", c);
        set_state(m, d, fresh, l, &rng);
        ctc_gdca_inverse_mobility(m, d, a, got);
        ctc_gdca_inverse_mobility(m, fresh, a, want);
        cr_assert_arr_eq(got, want, (size_t)m->nv * sizeof *got, "model %d: mobility inverse", c);
        ctc_data_free(d);
        ctc_data_free(fresh);
        ctc_model_free(m);
        test_chain_free(ch);
        test_loop_free(l);
    }
}
