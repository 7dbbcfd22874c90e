/*
 * test_loop.c - closed kinematic chains (loop.h, gdca.h on loop models, sim.h loop runs) against
 * an independent oracle, closed forms and conservation laws.
 *
 * The oracle (tests/support/loop_oracle.[ch]) writes the closed chain in redundant joint
 * coordinates: the open chain's mass matrix and bias forces (the library's CRBA and RNEA
 * oracle), the closure's Jacobian G and velocity-product term gamma from its own 3x3-rotation
 * kinematics, and Lagrange multipliers; forward dynamics by the KKT system, CTC inverse dynamics
 * by two square solves. The oracle is checked here first by itself: G and gamma against
 * fourth-order finite differences of its own residual, the closing joint's rate against finite
 * differences of its angle, its forward dynamics against the parallelogram four-bar's closed
 * form and against energy conservation (RK4, converging at fourth order).
 *
 * Then the library: iGDCA torques of the paper's five-bar at random consistent states (1e-8 of
 * the torque scale), forward GDCA on planar and spatial loops with revolute, prismatic and
 * spherical joints (1e-8), the round trip forward(inverse(u)) = u on the independent
 * coordinates for every boundary case of the paper's Eq. 55-65 (1e-9), the early stop of the
 * disassembly changing nothing, loop assembly, the error messages of bad loops, and simulations:
 * a passive four-bar's energy and loop residual, honest residuals without stabilisation,
 * Baumgarte stabilisation, and the exact-model PD error of the five-bar against its closed form.
 * Long loops of 16 to 4096 bodies: forces against the oracle, and the round trip against its
 * floor, what rounding the driving forces alone does to the accelerations (issue 18, part 3).
 * Last, a loop on a branched tree (loop_scene_branch hangs branches off a loop's spine): the same
 * checks against the oracle on planar and spatial trees closing on the ground or on an ancestor of
 * the tip, bitwise equal results at 1, 2 and 8 threads, and the exact PD error on a hand.
 *
 * Measured (this oracle against the library): torques and accelerations agree to <= 3e-12
 * relative, the round trip to <= 5e-12, the early stop changes nothing (bit-identical), the
 * five-bar's PD error matches its closed form to 1.3e-11; a passive four-bar over 10 s at rtol
 * 1e-10 drifts 6.8e-10 in energy with loop residual 3.9e-11 (projection), 3.6e-11 (Baumgarte)
 * and 7.9e-9 (none). Loops on branched trees (the planar Y, the planar hand, two spatial trees):
 * forward <= 7.5e-14, torques <= 1.5e-13, round trip <= 1.1e-12 and dependent accelerations
 * <= 4.6e-13 relative to the oracle; the early stop changes nothing (bit-identical).
 */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "ctc.h"
#include "linalg.h"
#include "loop.h"
#include "loop_oracle.h"
#include "sim.h"
#include "model_fixture.h"

#define PI 3.14159265358979323846
#define MAXX 64

/* ---- fixtures ---- */

typedef struct fixture {
    loop_scene *s;
    ctc_model *m;
    ctc_data *d;
    loop_oracle *o;
    const loop_oracle_dims *dims;
    const char *what; /* names the case in failure messages */
} fixture;

/* model, data and oracle of a scene (the fixture owns the scene) */
static fixture fx_make(loop_scene *s)
{
    fixture f = {.s = s, .what = ""};
    f.m = build(&s->spec);
    f.d = ctc_data_new(f.m);
    f.o = loop_oracle_new(&s->spec);
    cr_assert(f.d && f.o);
    f.dims = loop_oracle_get_dims(f.o);
    /* the oracle and the library agree on the sizes and the form */
    cr_assert_eq(f.m->nq, f.dims->nq);
    cr_assert_eq(f.m->nv, f.dims->nv);
    cr_assert_eq(f.m->nvx, f.dims->nvx);
    cr_assert_eq(f.m->nind, f.dims->nind);
    cr_assert_eq(f.m->form == CTC_FORM_PLANAR, f.dims->planar, "form %s, oracle planar %d",
                 ctc_form_name(f.m->form), f.dims->planar);
    return f;
}

static void fx_free(fixture *f)
{
    loop_oracle_free(f->o);
    ctc_data_free(f->d);
    ctc_model_free(f->m);
    free(f->s);
}

/* sets a scene's independent joints from a list terminated by -1 */
static void set_independent(loop_scene *s, const int *joints)
{
    memset(s->independent, 0, sizeof s->independent);
    for (int i = 0; joints[i] >= 0; i++) s->independent[joints[i]] = 1;
}

static double max_abs(const double *a, int n)
{
    double m = 0;
    for (int i = 0; i < n; i++) m = fmax(m, fabs(a[i]));
    return m;
}

/* the oracle's position residual max-norm at q and |G v| at (q, v) */
static double oracle_residual(fixture *f, const double *q)
{
    double phi[6];
    loop_oracle_residual(f->o, q, phi);
    return max_abs(phi, f->dims->nc);
}

static double oracle_velocity_residual(fixture *f, const double *q, const double *v)
{
    int nv = f->dims->nv, nc = f->dims->nc;
    double g[6 * MAXX], gv[6] = {0};
    loop_oracle_jacobian(f->o, q, NULL, g, NULL);
    for (int i = 0; i < nc; i++)
        for (int c = 0; c < nv; c++) gv[i] += g[i * nv + c] * v[c];
    return max_abs(gv, nc);
}

/* 1 if velocity coordinate i belongs to an independent joint (the closing joint's are the
   extended ones i >= nv) */
static int coord_independent(const fixture *f, int i)
{
    const ctc_model *m = f->m;
    for (int k = 0; k < m->njoints; k++)
        if (i >= m->jnt_vadr[k] && i < m->jnt_vadr[k] + m->jnt_nv[k]) return f->s->independent[k];
    return 0;
}

/* A random consistent state reached from the scene's q0 in three assembly steps (so each Newton
 * solve starts close to the closure): each step moves the independent coordinates by a third of
 * a random offset of up to qspread and the dependent ones by up to 0.02 at random, then
 * ctc_loop_assemble puts the guess onto the closure. A target the oracle's own Newton method
 * cannot close within 6 iterations and 0.2 (rad, m) of the guess (out of the sub-mechanism's
 * workspace, or near a singular configuration, which random spatial loops meet at a few tenths
 * of a radian) is drawn again, so the library is only asked to close loops that plainly can. Random
 * velocities (the dependent ones replaced by the assembly). Checked with the oracle's own
 * residuals. */
static void random_state(fixture *f, uint64_t *rng, double qspread, double vmax, double *q,
                         double *v)
{
    int nv = f->m->nv, nq = f->m->nq, ok = 0;
    double offset[MAXX], dv[MAXX], qo[MAXX];
    for (int attempt = 0; attempt < 20 && !ok; attempt++) {
        memcpy(q, f->s->q0, (size_t)nq * sizeof *q);
        for (int i = 0; i < nv; i++) {
            offset[i] = coord_independent(f, i) ? test_uniform(rng, -qspread, qspread) : 0;
            v[i] = test_uniform(rng, -vmax, vmax);
        }
        ok = 1;
        for (int step = 0; step < 3 && ok; step++) {
            for (int i = 0; i < nv; i++)
                dv[i] = coord_independent(f, i) ? offset[i] / 3 : test_uniform(rng, -0.02, 0.02);
            loop_oracle_q_add(f->o, q, dv, 1.0);
            memcpy(qo, q, (size_t)nq * sizeof *q);
            int it = loop_oracle_assemble(f->o, qo, NULL, 1e-12, 6);
            double jump = 0;
            for (int i = 0; i < nq; i++) jump = fmax(jump, fabs(qo[i] - q[i]));
            if (it < 0 || jump > 0.2) { /* not closable near the guess */
                ok = 0;
                break;
            }
            char err[512] = "";
            ctc_status st = ctc_loop_assemble(f->m, f->d, q, v, 1e-12, 50, NULL, err, sizeof err);
            cr_assert_eq(st, CTC_OK, "%s: assemble: %s", f->what, err);
        }
    }
    cr_assert(ok, "%s: no reachable random state in 20 draws", f->what);
    double res = oracle_residual(f, q), vres = oracle_velocity_residual(f, q, v);
    cr_assert_leq(res, 1e-11, "%s: oracle residual %g after assembly", f->what, res);
    cr_assert_leq(vres, 1e-11 * (1 + vmax), "%s: oracle velocity residual %g after assembly",
                  f->what, vres);
}

/* ---- the oracle by itself ---- */

/* 4th-order central difference of a vector function along s, step h: (8 (f1 - f-1) - (f2 -
   f-2)) / 12 h from the values at s = h, -h, 2h, -2h */
static double fd4(double fp1, double fm1, double fp2, double fm2, double h)
{
    return (8 * (fp1 - fm1) - (fp2 - fm2)) / (12 * h);
}

/* takes ownership of s */
static void check_oracle_derivatives(loop_scene *s, uint64_t seed)
{
    loop_oracle *o = loop_oracle_new(&s->spec);
    cr_assert(o);
    const loop_oracle_dims *dm = loop_oracle_get_dims(o);
    int nq = dm->nq, nv = dm->nv, nc = dm->nc, nvn = dm->nvn;
    const double h = 1e-3, steps[4] = {h, -h, 2 * h, -2 * h};
    double phi[6];
    loop_oracle_residual(o, s->q0, phi);
    cr_expect_leq(max_abs(phi, nc), 1e-14, "the scene's q0 is not closed: %g", max_abs(phi, nc));
    uint64_t rng = seed;
    double err_g = 0, err_gamma = 0, err_cb = 0;
    for (int t = 0; t < 8; t++) {
        double q[MAXX], v[MAXX], dv[MAXX], g[6 * MAXX], gamma[6], cm[3 * MAXX], cb[3];
        for (int i = 0; i < nv; i++) dv[i] = test_uniform(&rng, -0.3, 0.3);
        memcpy(q, s->q0, (size_t)nq * sizeof *q);
        loop_oracle_q_add(o, q, dv, 1.0); /* anywhere, closed or not */
        for (int i = 0; i < nv; i++) {
            v[i] = test_uniform(&rng, -2, 2);
            dv[i] = test_uniform(&rng, -1, 1);
        }
        loop_oracle_jacobian(o, q, v, g, gamma);
        loop_oracle_closing(o, q, v, cm, cb, NULL);
        /* values along q (+) s dv (residual) and along q (+) s v (G v and C^T v) */
        double pr[4][6], gvs[4][6], cvs[4][3];
        for (int j = 0; j < 4; j++) {
            double qs[MAXX], gs[6 * MAXX], cms[3 * MAXX], cbs[3];
            memcpy(qs, q, (size_t)nq * sizeof *q);
            loop_oracle_q_add(o, qs, dv, steps[j]);
            loop_oracle_residual(o, qs, pr[j]);
            memcpy(qs, q, (size_t)nq * sizeof *q);
            loop_oracle_q_add(o, qs, v, steps[j]);
            loop_oracle_jacobian(o, qs, NULL, gs, NULL);
            loop_oracle_closing(o, qs, NULL, cms, cbs, NULL);
            for (int i = 0; i < nc; i++) {
                gvs[j][i] = 0;
                for (int c = 0; c < nv; c++) gvs[j][i] += gs[i * nv + c] * v[c];
            }
            for (int i = 0; i < nvn; i++) {
                cvs[j][i] = 0;
                for (int c = 0; c < nv; c++) cvs[j][i] += cms[c * nvn + i] * v[c];
            }
        }
        double scale = 1 + max_abs(gamma, nc);
        for (int i = 0; i < nc; i++) {
            double gdv = 0;
            for (int c = 0; c < nv; c++) gdv += g[i * nv + c] * dv[c];
            err_g = fmax(err_g, fabs(gdv - fd4(pr[0][i], pr[1][i], pr[2][i], pr[3][i], h)));
            double fd = fd4(gvs[0][i], gvs[1][i], gvs[2][i], gvs[3][i], h);
            err_gamma = fmax(err_gamma, fabs(gamma[i] - fd) / scale);
        }
        for (int i = 0; i < nvn; i++) {
            double fd = fd4(cvs[0][i], cvs[1][i], cvs[2][i], cvs[3][i], h);
            err_cb = fmax(err_cb, fabs(cb[i] - fd) / (1 + fabs(cb[i])));
        }
    }
    cr_expect_leq(err_g, 1e-10, "G vs finite differences of phi: %g", err_g);
    cr_expect_leq(err_gamma, 1e-9, "gamma vs finite differences of G v: %g", err_gamma);
    if (s->loop.joint.type != CTC_JOINT_PRISMATIC) /* the prismatic rate is exact on the closure */
        cr_expect_leq(err_cb, 1e-9, "c_b vs finite differences of C^T v: %g", err_cb);
    loop_oracle_free(o);
    free(s);
}

Test(loop_oracle, jacobian_and_velocity_product_terms_match_finite_differences)
{
    check_oracle_derivatives(loop_scene_five_bar(), 1);
    check_oracle_derivatives(loop_scene_four_bar(1.0, 0), 2);
    check_oracle_derivatives(loop_scene_four_bar(1.0, 1), 3);
    check_oracle_derivatives(loop_scene_slider_crank(0.7), 4);
    check_oracle_derivatives(loop_scene_rssr(), 5);
    check_oracle_derivatives(loop_scene_rssp(), 7);
    check_oracle_derivatives(loop_scene_spatial(6, CTC_JOINT_SPHERICAL, 13), 8);
    check_oracle_derivatives(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), 6);
}

/* s closed on body b instead of the ground */
static loop_scene *on_body(loop_scene *s, int b)
{
    loop_scene_close_on(s, b);
    return s;
}

Test(loop_oracle, derivatives_match_finite_differences_on_a_loop_closed_on_a_body)
{
    /* the child moves: its turning carries the constraint directions, and its motion enters G,
       gamma and the closing joint's rate */
    check_oracle_derivatives(on_body(loop_scene_five_bar(), 1), 11);
    check_oracle_derivatives(on_body(loop_scene_slider_crank(0.0), 0), 12);
    check_oracle_derivatives(on_body(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), 1), 13);
    check_oracle_derivatives(on_body(loop_scene_spatial(6, CTC_JOINT_SPHERICAL, 13), 1), 14);
    check_oracle_derivatives(on_body(loop_scene_spatial(7, CTC_JOINT_PRISMATIC, 5), 2), 15);
}

/* the closing joint's rate (C v) against the central difference of its angle along v, on the
   closure, for a loop closed on the ground or on body b (whose rotation enters the angle) */
static void check_closing_rate(loop_scene *s, const char *what)
{
    fixture f = fx_make(s);
    uint64_t rng = 8;
    double worst = 0;
    for (int t = 0; t < 5; t++) {
        double q[MAXX], v[MAXX], cm[MAXX], cb[1], qn[4], qp[MAXX], qm[MAXX], ap[4], am[4];
        random_state(&f, &rng, 0.2, 1, q, v);
        loop_oracle_closing(f.o, q, v, cm, cb, qn);
        double rate = 0, hh = 1e-6;
        for (int i = 0; i < f.m->nv; i++) rate += cm[i] * v[i];
        memcpy(qp, q, sizeof qp);
        memcpy(qm, q, sizeof qm);
        loop_oracle_q_add(f.o, qp, v, hh);
        loop_oracle_q_add(f.o, qm, v, -hh);
        loop_oracle_closing(f.o, qp, NULL, cm, cb, ap);
        loop_oracle_closing(f.o, qm, NULL, cm, cb, am);
        worst = fmax(worst, fabs(rate - remainder(ap[0] - am[0], 2 * PI) / (2 * hh)));
    }
    cr_expect_leq(worst, 1e-7, "%s: closing rate vs d(angle)/dt: %g", what, worst);
    fx_free(&f);
}

Test(loop_oracle, closing_joint_rate_is_the_derivative_of_its_angle_on_the_closure)
{
    check_closing_rate(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), "on the ground");
    loop_scene *s = on_body(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), 0);
    set_independent(s, (const int[]){0, 7, -1}); /* joint 0 carries the loop */
    check_closing_rate(s, "on body 0");
}

Test(loop_oracle, parallelogram_four_bar_matches_its_closed_form)
{
    /* the coupler translates: (5/3) theta'' = tau - 2 g sin(theta) (1 kg, 1 m rods) */
    for (int t = 0; t < 4; t++) {
        double th = 0.3 + 0.35 * t, thd = 1.3 - 0.8 * t, tau = 2.5 * t - 1, u0 = 0.7 - t;
        loop_scene *s = loop_scene_parallelogram(th);
        loop_oracle *o = loop_oracle_new(&s->spec);
        double v[3] = {thd, -thd, thd}, f[4] = {tau, 0, 0, 0}, a[4], u[4] = {u0, 0, 0, 0}, fi[4];
        cr_assert_eq(loop_oracle_forward(o, s->q0, v, f, a, NULL), 0);
        double ref = (tau - 2 * 9.81 * sin(th)) * 3 / 5;
        cr_expect_leq(fabs(a[0] - ref), 1e-12, "theta %g: %.15g vs %.15g", th, a[0], ref);
        /* the coupler does not turn; the rocker follows the crank; closing: -(sum) */
        cr_expect_leq(fabs(a[1] + ref) + fabs(a[2] - ref) + fabs(a[3] + ref), 1e-12);
        cr_assert_eq(loop_oracle_inverse(o, s->q0, v, u, fi, NULL), 0);
        double tref = 5.0 / 3 * u0 + 2 * 9.81 * sin(th);
        cr_expect_leq(fabs(fi[0] - tref), 1e-12, "theta %g: %.15g vs %.15g", th, fi[0], tref);
        loop_oracle_free(o);
        free(s);
    }
}

/* RK4 on the oracle's forward dynamics, passive, quaternions integrated as coordinates; returns
   the largest |E(t) - E(0)| over the steps */
static double oracle_energy_drift(loop_scene *s, double duration, double h)
{
    loop_oracle *o = loop_oracle_new(&s->spec);
    const loop_oracle_dims *dm = loop_oracle_get_dims(o);
    int nq = dm->nq, nv = dm->nv;
    double q[MAXX], v[MAXX] = {0}, f[MAXX] = {0}, kq[4][MAXX], kv[4][MAXX], ke, pe;
    memcpy(q, s->q0, (size_t)nq * sizeof *q);
    loop_oracle_energy(o, q, v, &ke, &pe);
    double e0 = ke + pe, drift = 0;
    for (int step = 0; step < (int)(duration / h + 0.5); step++) {
        for (int j = 0; j < 4; j++) {
            double c = j == 0 ? 0 : j == 3 ? h : h / 2, qt[MAXX], vt[MAXX], a[MAXX];
            for (int i = 0; i < nq; i++) qt[i] = q[i] + (j ? c * kq[j - 1][i] : 0);
            for (int i = 0; i < nv; i++) vt[i] = v[i] + (j ? c * kv[j - 1][i] : 0);
            cr_assert_eq(loop_oracle_forward(o, qt, vt, f, a, NULL), 0);
            memcpy(kv[j], a, (size_t)nv * sizeof *a);
            /* qdot: v, or 0.5 quat (x) (0, w) for spherical joints */
            for (int k = 0, iq = 0, iv = 0; k < s->spec.nbodies; k++) {
                const double *b = qt + iq, *w = vt + iv;
                if (s->joints[k].type == CTC_JOINT_SPHERICAL) {
                    kq[j][iq] = 0.5 * (-b[1] * w[0] - b[2] * w[1] - b[3] * w[2]);
                    kq[j][iq + 1] = 0.5 * (b[0] * w[0] + b[2] * w[2] - b[3] * w[1]);
                    kq[j][iq + 2] = 0.5 * (b[0] * w[1] - b[1] * w[2] + b[3] * w[0]);
                    kq[j][iq + 3] = 0.5 * (b[0] * w[2] + b[1] * w[1] - b[2] * w[0]);
                    iq += 4, iv += 3;
                } else {
                    kq[j][iq++] = vt[iv++]; /* revolute and prismatic only in these scenes */
                }
            }
        }
        for (int i = 0; i < nq; i++)
            q[i] += h * (kq[0][i] + 2 * kq[1][i] + 2 * kq[2][i] + kq[3][i]) / 6;
        for (int i = 0; i < nv; i++)
            v[i] += h * (kv[0][i] + 2 * kv[1][i] + 2 * kv[2][i] + kv[3][i]) / 6;
        loop_oracle_energy(o, q, v, &ke, &pe);
        drift = fmax(drift, fabs(ke + pe - e0));
    }
    loop_oracle_free(o);
    return drift;
}

Test(loop_oracle, forward_dynamics_conserve_energy_at_fourth_order)
{
    /* a wrong G, gamma or multiplier would leave a drift that does not vanish with h; RK4's
       falls 16-fold when h halves (measured over 0.5 s, J: five-bar 9.8e-6 -> 6.4e-7, RSSR
       2.2e-6 -> 1.4e-7, 8R 4.1e-8 -> 2.6e-9, RSSP 4.5e-8 -> 2.9e-9) */
    loop_scene *scenes[4] = {loop_scene_five_bar(), loop_scene_rssr(),
                             loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), loop_scene_rssp()};
    for (int i = 0; i < 4; i++) {
        double d1 = oracle_energy_drift(scenes[i], 0.5, 2e-3);
        double d2 = oracle_energy_drift(scenes[i], 0.5, 1e-3);
        cr_expect(d1 / d2 > 11 && d1 / d2 < 22, "scene %d: drift %g -> %g (ratio %g)", i, d1, d2,
                  d1 / d2);
        cr_expect_leq(d2, 1e-5, "scene %d: drift %g", i, d2);
        free(scenes[i]);
    }
}

/* ---- iGDCA against the oracle ---- */

/* f (nvx) at (q, v) for u (nvx) by the library's inverse for loops: which = 0 the default
 * (ctc_gdca_inverse: the open chain's composite pass and the closure, gdca_inverse_loop.h), 1 the
 * paper's iGDCA with the early-stopping disassembly, 2 the same disassembling every node */
static void library_inverse(fixture *f, const double *q, const double *v, const double *u,
                            int which, double *out)
{
    ctc_kinematics(f->m, f->d, q, v);
    ctc_handles(f->m, f->d);
    f->d->opt.inv_full = which == 2;
    if (which == 0)
        ctc_gdca_inverse(f->m, f->d, u, out);
    else
        ctc_gdca_inverse_mobility(f->m, f->d, u, out);
    f->d->opt.inv_full = 0;
    cr_assert_eq(f->d->singular_joint, -1, "%s: iGDCA reports a singular joint %d", f->what,
                 f->d->singular_joint);
}

static void library_forward(fixture *f, const double *q, const double *v, const double *force,
                            double *qacc)
{
    ctc_kinematics(f->m, f->d, q, v);
    ctc_handles(f->m, f->d);
    ctc_gdca_forward(f->m, f->d, force, qacc);
    cr_assert_eq(f->d->singular_joint, -1, "%s: GDCA forward reports a singular joint %d", f->what,
                 f->d->singular_joint);
}

/* worst errors of one boundary case over random consistent states */
typedef struct inverse_errors {
    double torque;    /* |f - f_oracle| / max |f_oracle|, the worse of both inverse forms */
    double full;      /* the paper's form: |f(inv_full) - f| / max |f| */
    double round;     /* |forward(f)_i - u_i| / max(1, |u|) on independent coordinates */
    double dependent; /* |forward(f)_d - qacc_oracle_d| / max |qacc_oracle| */
} inverse_errors;

static inverse_errors check_inverse(fixture *f, uint64_t seed, int states, double qspread)
{
    inverse_errors e = {0};
    int nvx = f->m->nvx;
    uint64_t rng = seed;
    for (int t = 0; t < states; t++) {
        double q[MAXX], v[MAXX], u[MAXX] = {0}, fl[MAXX], fo[MAXX], ff[MAXX], ao[MAXX], a[MAXX];
        random_state(f, &rng, qspread, 1.5, q, v);
        for (int i = 0; i < nvx; i++)
            u[i] = coord_independent(f, i) ? test_uniform(&rng, -5, 5) : 0;
        cr_assert_eq(loop_oracle_inverse(f->o, q, v, u, fo, ao), 0, "%s: oracle: singular",
                     f->what);
        for (int which = 1; which >= 0; which--) { /* the paper's form, then the default */
            library_inverse(f, q, v, u, which, fl);
            e.torque = fmax(e.torque, test_rel_err(fl, fo, nvx));
            for (int i = 0; i < nvx; i++)
                if (!coord_independent(f, i))
                    cr_expect_eq(fl[i], 0.0, "%s: dependent coordinate %d has a driving force %g",
                                 f->what, i, fl[i]);
            if (which == 1) {
                library_inverse(f, q, v, u, 2, ff);
                e.full = fmax(e.full, test_rel_err(ff, fl, nvx));
            }
        }
        library_forward(f, q, v, fl, a);
        double uscale = fmax(1, max_abs(u, nvx)), ascale = fmax(1, max_abs(ao, nvx));
        for (int i = 0; i < nvx; i++) {
            if (coord_independent(f, i))
                e.round = fmax(e.round, fabs(a[i] - u[i]) / uscale);
            else
                e.dependent = fmax(e.dependent, fabs(a[i] - ao[i]) / ascale);
        }
    }
    return e;
}

Test(loop, igdca_matches_the_oracle_on_the_papers_five_bar)
{
    fixture f = fx_make(loop_scene_five_bar()); /* joints 0, 1, 2 independent */
    f.what = "five-bar";
    cr_assert_eq(f.m->mobility, 3);
    cr_assert_eq(f.m->nind, 3);
    inverse_errors e = check_inverse(&f, 11, 20, 0.3);
    cr_expect_leq(e.torque, 1e-8, "driving torques vs oracle: %g", e.torque);
    cr_expect_leq(e.full, 1e-12, "early stop vs full disassembly: %g", e.full);
    cr_expect_leq(e.round, 1e-9, "round trip: %g", e.round);
    cr_expect_leq(e.dependent, 1e-8, "dependent accelerations: %g", e.dependent);

    /* what is commanded for dependent coordinates is ignored */
    uint64_t rng = 12;
    double q[MAXX], v[MAXX], u[MAXX], fa[MAXX], fb[MAXX];
    random_state(&f, &rng, 0.3, 1.5, q, v);
    for (int i = 0; i < f.m->nvx; i++)
        u[i] = coord_independent(&f, i) ? test_uniform(&rng, -5, 5) : 0;
    library_inverse(&f, q, v, u, 0, fa);
    for (int i = 0; i < f.m->nvx; i++)
        if (!coord_independent(&f, i)) u[i] = 1e3;
    library_inverse(&f, q, v, u, 0, fb);
    cr_expect_leq(test_rel_err(fb, fa, f.m->nvx), 1e-14, "u of dependent coordinates changed f");
    fx_free(&f);
}

/* the paper's five-bar and a spatial 8R loop in all of Eq. 55-65's boundary cases; joint 0 and
   the closing joint (5 on the five-bar, 7 on the 8R loop) are the terminal joints */
static void check_boundary_case(loop_scene *s, const int *indep, const char *what, uint64_t seed,
                                double qspread)
{
    set_independent(s, indep);
    fixture f = fx_make(s);
    f.what = what;
    char err[512] = "";
    double cond = 0;
    cr_assert_eq(ctc_loop_check(f.m, f.d, s->q0, &cond, err, sizeof err), CTC_OK, "%s: %s", what,
                 err);
    inverse_errors e = check_inverse(&f, seed, 6, qspread);
    cr_expect_leq(e.torque, 1e-8, "%s: torques vs oracle %g", what, e.torque);
    cr_expect_leq(e.full, 1e-12, "%s: early stop vs full %g", what, e.full);
    cr_expect_leq(e.round, 1e-9, "%s: round trip %g", what, e.round);
    cr_expect_leq(e.dependent, 1e-8, "%s: dependent accelerations %g", what, e.dependent);
    fx_free(&f);
}

Test(loop, round_trip_gives_the_commanded_accelerations_in_every_boundary_case)
{
    check_boundary_case(loop_scene_five_bar(), (const int[]){0, 2, 5, -1},
                        "five-bar, both terminal joints independent", 21, 0.2);
    check_boundary_case(loop_scene_five_bar(), (const int[]){0, 1, 2, -1},
                        "five-bar, joint 0 independent, closing joint dependent", 22, 0.2);
    check_boundary_case(loop_scene_five_bar(), (const int[]){1, 3, 5, -1},
                        "five-bar, joint 0 dependent, closing joint independent", 23, 0.2);
    check_boundary_case(loop_scene_five_bar(), (const int[]){1, 2, 4, -1},
                        "five-bar, both terminal joints dependent", 24, 0.2);
    check_boundary_case(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), (const int[]){0, 7, -1},
                        "8R, both terminal joints independent", 25, 0.2);
    check_boundary_case(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), (const int[]){0, 3, -1},
                        "8R, joint 0 independent, closing joint dependent", 26, 0.2);
    check_boundary_case(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), (const int[]){3, 7, -1},
                        "8R, joint 0 dependent, closing joint independent", 27, 0.2);
    check_boundary_case(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), (const int[]){2, 5, -1},
                        "8R, both terminal joints dependent", 28, 0.2);
}

Test(loop, round_trip_on_prismatic_and_four_bar_loops)
{
    check_boundary_case(loop_scene_slider_crank(0.7), (const int[]){0, -1},
                        "slider-crank driven at the crank", 31, 0.2);
    check_boundary_case(loop_scene_slider_crank(0.7), (const int[]){3, -1},
                        "slider-crank driven at the slider (prismatic closing joint)", 32, 0.2);
    check_boundary_case(loop_scene_four_bar(1.0, 0), (const int[]){0, -1},
                        "four-bar driven at the crank", 33, 0.2);
    check_boundary_case(loop_scene_four_bar(1.0, 0), (const int[]){3, -1},
                        "four-bar driven at the rocker's ground pivot", 34, 0.2);
    check_boundary_case(loop_scene_four_bar(1.0, 0), (const int[]){1, -1},
                        "four-bar driven at the crank-coupler joint", 35, 0.2);
}

Test(loop, round_trip_with_a_spherical_closing_joint)
{
    /* 6R + S: mobility 3; 7R + S: mobility 4. The spherical closing joint's three coordinates
       are the ground's angular velocity relative to the tip, in the ground's (world) frame */
    check_boundary_case(loop_scene_spatial(6, CTC_JOINT_SPHERICAL, 13), (const int[]){6, -1},
                        "6R+S, joint 0 dependent, spherical closing joint independent", 41, 0.2);
    check_boundary_case(loop_scene_spatial(6, CTC_JOINT_SPHERICAL, 13), (const int[]){0, 2, 4, -1},
                        "6R+S, joint 0 independent, closing joint dependent", 42, 0.2);
    check_boundary_case(loop_scene_spatial(6, CTC_JOINT_SPHERICAL, 13), (const int[]){1, 3, 5, -1},
                        "6R+S, both terminal joints dependent", 43, 0.2);
    check_boundary_case(loop_scene_spatial(7, CTC_JOINT_SPHERICAL, 14), (const int[]){0, 7, -1},
                        "7R+S, both terminal joints independent", 44, 0.2);
}

/* ---- forward GDCA against the oracle ---- */

/* worst |qacc - qacc_oracle| / max |qacc_oracle| over random consistent states; driven: random
   forces on the independent coordinates (and junk on the dependent ones, which is ignored) */
static double check_forward(fixture *f, uint64_t seed, int states, int driven)
{
    int nvx = f->m->nvx;
    double worst = 0;
    uint64_t rng = seed;
    for (int t = 0; t < states; t++) {
        double q[MAXX], v[MAXX], force[MAXX], a[MAXX], ao[MAXX];
        random_state(f, &rng, 0.2, 1.5, q, v);
        for (int i = 0; i < nvx; i++)
            force[i] = !driven ? 0 : coord_independent(f, i) ? test_uniform(&rng, -5, 5) : 77.0;
        cr_assert_eq(loop_oracle_forward(f->o, q, v, force, ao, NULL), 0);
        library_forward(f, q, v, force, a);
        worst = fmax(worst, test_rel_err(a, ao, nvx));
    }
    return worst;
}

/* one scene of a table of cases, with the joints that drive its loop (set_independent) */
typedef struct loop_case {
    loop_scene *s;
    const int *indep; /* -1-terminated; NULL: the scene's */
    const char *what;
} loop_case;

Test(loop, gdca_forward_matches_the_kkt_oracle)
{
    loop_case cases[] = {
        {loop_scene_five_bar(), NULL, "five-bar"},
        {loop_scene_five_bar(), (const int[]){0, 2, 5, -1}, "five-bar, closing joint driven"},
        {loop_scene_four_bar(1.0, 0), NULL, "four-bar"},
        {loop_scene_slider_crank(0.7), NULL, "slider-crank (prismatic closing joint)"},
        {loop_scene_slider_crank(0.7), (const int[]){3, -1}, "slider-crank, slider driven"},
        {loop_scene_rssr(), NULL, "RSSR (spherical joints)"},
        {loop_scene_rssp(), NULL, "RSSP (spatial prismatic closing joint)"},
        {loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), NULL, "spatial 8R"},
        {loop_scene_spatial(6, CTC_JOINT_SPHERICAL, 13), (const int[]){0, 2, 4, -1},
         "6R+S (spherical closing joint)"},
        {loop_scene_spatial(6, CTC_JOINT_SPHERICAL, 13), (const int[]){6, -1},
         "6R+S, spherical closing joint driven"},
        {loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 9), (const int[]){3, 7, -1},
         "spatial 8R, other independents"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        if (cases[i].indep) set_independent(cases[i].s, cases[i].indep);
        fixture f = fx_make(cases[i].s);
        f.what = cases[i].what;
        double passive = check_forward(&f, 40 + i, 5, 0), driven = check_forward(&f, 50 + i, 5, 1);
        cr_expect_leq(passive, 1e-8, "%s, passive: %g", cases[i].what, passive);
        cr_expect_leq(driven, 1e-8, "%s, driven: %g", cases[i].what, driven);
        fx_free(&f);
    }
}

/* A loop closed on body b of the chain (model.h): joints 0..b carry the loop, the root solve
 * couples joints 0, b + 1 and the closing joint, and both inverse forms use the child's motion.
 * Forward dynamics, both inverse forms and the round trip against the oracle. */
Test(loop, a_loop_closed_on_a_body_matches_the_oracle)
{
    loop_case cases[] = {
        {on_body(loop_scene_five_bar(), 0), (const int[]){0, 1, 2, -1},
         "five-bar on body 0, joints 1, 2 drive the loop"},
        {on_body(loop_scene_five_bar(), 0), (const int[]){0, 2, 4, -1},
         "five-bar on body 0, joints 2, 4 drive the loop"},
        {on_body(loop_scene_five_bar(), 1), (const int[]){0, 1, 2, -1},
         "five-bar on body 1, joint 2 drives the loop"},
        {on_body(loop_scene_five_bar(), 1), (const int[]){0, 1, 5, -1},
         "five-bar on body 1, the closing joint drives the loop"},
        {on_body(loop_scene_slider_crank(0.0), 0), (const int[]){0, -1},
         "slider-crank on its crank: a rigid loop with a prismatic closing joint"},
        {on_body(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), 0), (const int[]){0, 7, -1},
         "8R on body 0"},
        {on_body(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 9), 1), (const int[]){0, 1, -1},
         "8R on body 1: a rigid loop"},
        {on_body(loop_scene_spatial(6, CTC_JOINT_SPHERICAL, 13), 1), (const int[]){0, 1, 3, -1},
         "6R+S on body 1 (spherical closing joint)"},
        {on_body(loop_scene_spatial(7, CTC_JOINT_SPHERICAL, 14), 0), (const int[]){0, 7, -1},
         "7R+S on body 0, the spherical closing joint drives the loop"},
        {on_body(loop_scene_spatial(7, CTC_JOINT_PRISMATIC, 5), 1), (const int[]){0, 1, -1},
         "7R+P on body 1: a rigid loop with a spatial prismatic closing joint"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        set_independent(cases[i].s, cases[i].indep);
        fixture f = fx_make(cases[i].s);
        f.what = cases[i].what;
        char err[512] = "";
        cr_assert_eq(ctc_loop_check(f.m, f.d, f.s->q0, NULL, err, sizeof err), CTC_OK, "%s: %s",
                     f.what, err);
        double passive = check_forward(&f, 140 + i, 4, 0),
               driven = check_forward(&f, 150 + i, 4, 1);
        cr_expect_leq(passive, 1e-8, "%s, forward, passive: %g", f.what, passive);
        cr_expect_leq(driven, 1e-8, "%s, forward, driven: %g", f.what, driven);
        inverse_errors e = check_inverse(&f, 160 + i, 4, 0.2);
        cr_expect_leq(e.torque, 1e-8, "%s: torques vs oracle %g", f.what, e.torque);
        cr_expect_leq(e.full, 1e-12, "%s: early stop vs full %g", f.what, e.full);
        cr_expect_leq(e.round, 1e-9, "%s: round trip %g", f.what, e.round);
        cr_expect_leq(e.dependent, 1e-8, "%s: dependent accelerations %g", f.what, e.dependent);
        fx_free(&f);
    }
}

/* masses and inertias of s's bodies alternately times ratio and 1 / ratio */
static loop_scene *alternate_masses(loop_scene *s, double ratio)
{
    for (int k = 0; k < s->spec.nbodies; k++) {
        double x = k % 2 ? ratio : 1 / ratio;
        s->bodies[k].mass *= x;
        for (int i = 0; i < 9; i++) s->bodies[k].inertia[i] *= x;
    }
    return s;
}

/* |qacc - qacc_oracle| / max |qacc_oracle| at one random consistent driven state, with at most
   `steps` refinement steps (-1: the default rule) */
static double forward_error(fixture *f, int steps, uint64_t seed)
{
    uint64_t rng = seed;
    double q[MAXX], v[MAXX], force[MAXX], a[MAXX], ao[MAXX];
    random_state(f, &rng, 0.1, 1, q, v);
    for (int i = 0; i < f->m->nvx; i++) force[i] = test_uniform(&rng, -5, 5);
    cr_assert_eq(loop_oracle_forward(f->o, q, v, force, ao, NULL), 0);
    f->d->opt.fwd_refine = steps;
    library_forward(f, q, v, force, a);
    f->d->opt.fwd_refine = -1;
    return test_rel_err(a, ao, f->m->nvx);
}

/* The forward pass's refinement on loops (gdca_refine.h): the residual carries the closing
 * joint's load and the closure. With masses alternating by 1e4 the literal pass loses digits
 * (2e-7 on the 8R loop, 7e-9 on the five-bar); the default refines (mass ratio >= 100)
 * and each step gains about two orders (to 5e-14 and 2e-15). On an evenly proportioned loop a
 * forced step changes nothing beyond rounding. */
Test(loop, the_forward_refinement_of_a_loop_reaches_the_oracle)
{
    loop_case cases[] = {
        {alternate_masses(loop_scene_five_bar(), 1e4), NULL, "five-bar, masses 1e4 apart"},
        {alternate_masses(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7), 1e4), NULL,
         "8R, masses 1e4 apart"},
        {alternate_masses(on_body(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 9), 1), 1e4),
         (const int[]){0, 1, -1}, "8R on body 1, masses 1e4 apart"},
        {alternate_masses(on_body(loop_scene_slider_crank(0.0), 0), 1e4), (const int[]){0, -1},
         "slider-crank on its crank, masses 1e4 apart"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        if (cases[i].indep) set_independent(cases[i].s, cases[i].indep);
        fixture f = fx_make(cases[i].s);
        f.what = cases[i].what;
        double literal = forward_error(&f, 0, 80 + i), refined = forward_error(&f, -1, 80 + i);
        cr_expect_gt(f.d->fwd_refine_done, 0, "%s: not refined by default", f.what);
        cr_expect_leq(refined, 1e-11, "%s: refined %g", f.what, refined);
        cr_expect_gt(literal, 100 * refined, "%s: literal %g, refined %g", f.what, literal,
                     refined);
        fx_free(&f);
    }

    fixture f = fx_make(loop_scene_five_bar());
    f.what = "five-bar";
    double literal = forward_error(&f, 0, 90), forced = forward_error(&f, 2, 90);
    forward_error(&f, -1, 90);
    cr_expect_eq(f.d->fwd_refine_done, 0, "the five-bar is not refined by default");
    cr_expect_leq(literal, 1e-13, "literal %g", literal);
    cr_expect_leq(forced, 1e-13, "a forced step %g", forced);
    fx_free(&f);
}

/* ---- long loops (issue 18, part 3) ---- */

/* What one long loop gives at its q0 with rates projected onto the closure (seeded uniform in
 * [-1, 1] before) and commands u uniform in [-1, 1]: the library's forces against the oracle's
 * (max |f - f_oracle| / max |f_oracle|; -1 without the oracle), the round trip max |qacc_i - u_i|
 * / max |u| over the independent coordinates, and its floor: the same measure of how far the
 * forward pass's accelerations move when each force is perturbed by its own rounding,
 * f_i (1 + eps r), r uniform in [-1, 1], the worst of three draws. No solver in double precision
 * can be held to a round trip under its floor. */
typedef struct long_loop_errors {
    double force, trip, floor;
} long_loop_errors;

static long_loop_errors check_long_loop(test_loop *l, int oracle, const char *what)
{
    cr_assert(l != NULL, "%s: the scene", what);
    ctc_model *m = build(&l->spec);
    ctc_data *d = ctc_data_new(m);
    cr_assert(d != NULL);
    const int nvx = m->nvx;
    double *buf = calloc((size_t)m->nq + (size_t)m->nv + 5 * (size_t)nvx, sizeof(double));
    cr_assert(buf != NULL);
    double *q = buf, *v = q + m->nq, *u = v + m->nv, *f = u + nvx, *a = f + nvx, *fp = a + nvx,
           *ap = fp + nvx;
    char err[256] = "";
    uint64_t rng = 3;
    memcpy(q, l->q0, (size_t)m->nq * sizeof *q);
    for (int i = 0; i < m->nv; i++) v[i] = test_uniform(&rng, -1, 1);
    for (int i = 0; i < nvx; i++) u[i] = test_uniform(&rng, -1, 1);
    cr_assert_eq(ctc_loop_assemble(m, d, q, v, 1e-12, 20, NULL, err, sizeof err), CTC_OK, "%s: %s",
                 what, err);
    ctc_kinematics(m, d, q, v);
    ctc_handles(m, d);
    ctc_gdca_inverse(m, d, u, f);
    ctc_gdca_forward(m, d, f, a);
    cr_assert(test_all_finite(f, nvx) && test_all_finite(a, nvx), "%s: finite", what);
    long_loop_errors e = {.force = -1};
    const double umax = max_abs(u, nvx);
    for (int i = 0; i < m->nind; i++) {
        const int c = m->ind_coord[i];
        e.trip = fmax(e.trip, fabs(a[c] - u[c]) / umax);
    }
    for (int t = 0; t < 3; t++) {
        for (int i = 0; i < nvx; i++) fp[i] = f[i] * (1 + DBL_EPSILON * test_uniform(&rng, -1, 1));
        ctc_gdca_forward(m, d, fp, ap);
        for (int i = 0; i < m->nind; i++) {
            const int c = m->ind_coord[i];
            e.floor = fmax(e.floor, fabs(ap[c] - a[c]) / umax);
        }
    }
    if (oracle) {
        loop_oracle *o = loop_oracle_new(&l->spec);
        cr_assert(o != NULL);
        cr_assert_eq(loop_oracle_inverse(o, q, v, u, fp, NULL), 0, "%s: oracle: singular", what);
        e.force = test_rel_err(f, fp, nvx);
        loop_oracle_free(o);
    }
    free(buf);
    ctc_data_free(d);
    ctc_model_free(m);
    return e;
}

/* Loops of 16 to 4096 bodies (tests/support: the arch, the arch with its dependent joints spread,
 * the random spatial loop; the oracle is O(n^3), so up to 1024 bodies): forces within 1e-9 of the
 * oracle's, and the round trip within 8 times its floor (plus 1e-13), within 1e-8 where the floor
 * allows (n <= 64). The floor is a one-draw estimate of the rounding: the portable build's FMA
 * kernels move it by 1.5x and the round trip by 2.4x at n = 16 (arch spread: 3.3e-12 against
 * 5.2e-13, 6.3 times). Measured (gcc -O3): forces <= 5.5e-13; round trip / floor 0.5 to 6.3; the
 * floors: 6.7e-11 to 3e-10 at n <= 64, 1.9e-7 (arch spread) to 8.9e-4 (spatial) at 256, 5e-6
 * (spatial) to 0.12 (arch) at 1024; bench/NOTEBOOK.md, "Long loops". Unrefined, the spatial loop
 * of 256 is 24 times over its floor. */
Test(loop, long_loops_match_the_oracle_and_reach_their_round_trip_floor)
{
    static const int sizes[] = {16, 64, 256, 1024, 4096};
    for (size_t i = 0; i < sizeof sizes / sizeof *sizes; i++) {
        const int n = sizes[i], oracle = n <= 1024;
        for (int kind = 0; kind < 3; kind++) {
            static const char *const names[] = {"arch", "arch spread", "spatial"};
            test_loop *l = kind == 0   ? test_loop_arch(n)
                           : kind == 1 ? test_loop_arch_spread(n)
                                       : test_loop_spatial(n, 11);
            long_loop_errors e = check_long_loop(l, oracle, names[kind]);
            test_loop_free(l);
            cr_log_info("%s n = %d: forces %.1e, round trip %.1e, floor %.1e\n", names[kind], n,
                        e.force, e.trip, e.floor);
            if (oracle)
                cr_expect_leq(e.force, 1e-9, "%s n = %d: forces off the oracle by %g", names[kind],
                              n, e.force);
            cr_expect_leq(e.trip, 8 * e.floor + 1e-13, "%s n = %d: round trip %g, its floor %g",
                          names[kind], n, e.trip, e.floor);
            if (n <= 64)
                cr_expect_leq(e.trip, 1e-8, "%s n = %d: round trip %g", names[kind], n, e.trip);
        }
    }
}

Test(loop, gdca_matches_the_parallelogram_closed_form)
{
    for (int t = 0; t < 3; t++) {
        double th = 0.3 + 0.4 * t, thd = 1.3 - t, tau = 2.5 * t - 1, u0 = 0.5 + t;
        fixture f = fx_make(loop_scene_parallelogram(th));
        double v[3] = {thd, -thd, thd}, force[4] = {tau, 0, 0, 0}, a[4], u[4] = {u0, 0, 0, 0},
               fi[4];
        library_forward(&f, f.s->q0, v, force, a);
        double ref = (tau - 2 * 9.81 * sin(th)) * 3 / 5;
        cr_expect_leq(fabs(a[0] - ref), 1e-10, "forward, theta %g: %.15g vs %.15g", th, a[0], ref);
        cr_expect_leq(fabs(a[1] + ref) + fabs(a[2] - ref) + fabs(a[3] + ref), 1e-10,
                      "forward: %g %g %g", a[1], a[2], a[3]);
        library_inverse(&f, f.s->q0, v, u, 0, fi);
        double tref = 5.0 / 3 * u0 + 2 * 9.81 * sin(th);
        cr_expect_leq(fabs(fi[0] - tref), 1e-10, "inverse, theta %g: %.15g vs %.15g", th, fi[0],
                      tref);
        fx_free(&f);
    }
}

Test(loop, closing_joint_coordinates_and_residuals_match_the_oracle)
{
    /* at closed states: the closing joint's angle and rate; at open states (the planar
       five-bar): the residual norms, which are the in-plane components of p_t - anchor and of
       the tip point's velocity */
    fixture f = fx_make(loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7));
    uint64_t rng = 61;
    for (int t = 0; t < 4; t++) {
        double q[MAXX], v[MAXX], cm[MAXX], cb[1], qn[4];
        random_state(&f, &rng, 0.2, 1, q, v);
        ctc_kinematics(f.m, f.d, q, v);
        loop_oracle_closing(f.o, q, v, cm, cb, qn);
        double rate = 0;
        for (int i = 0; i < f.m->nv; i++) rate += cm[i] * v[i];
        cr_expect_leq(fabs(remainder(f.d->loop_q[0] - qn[0], 2 * PI)), 1e-10, "q_n %g vs %g",
                      f.d->loop_q[0], qn[0]);
        cr_expect_leq(fabs(f.d->loop_v[0] - rate), 1e-10, "qd_n %g vs %g", f.d->loop_v[0], rate);
    }
    fx_free(&f);

    f = fx_make(loop_scene_five_bar());
    for (int t = 0; t < 4; t++) {
        double q[MAXX], v[MAXX], pt[3], vt[3], pos, vel;
        for (int i = 0; i < 5; i++) {
            q[i] = f.s->q0[i] + test_uniform(&rng, -0.2, 0.2);
            v[i] = test_uniform(&rng, -1, 1);
        }
        ctc_kinematics(f.m, f.d, q, v);
        ctc_loop_residual_norms(f.m, f.d, &pos, &vel);
        loop_oracle_tip(f.o, q, v, pt, NULL, vt, NULL);
        double dp[3] = {pt[0] - f.s->loop.anchor[0], pt[1] - f.s->loop.anchor[1], 0};
        double mp = fmax(fabs(dp[0] * f.m->plane_e1[0] + dp[1] * f.m->plane_e1[1]),
                         fabs(dp[0] * f.m->plane_e2[0] + dp[1] * f.m->plane_e2[1]));
        double mv = fmax(fabs(vt[0] * f.m->plane_e1[0] + vt[1] * f.m->plane_e1[1]),
                         fabs(vt[0] * f.m->plane_e2[0] + vt[1] * f.m->plane_e2[1]));
        cr_expect_leq(fabs(pos - mp), 1e-14, "position residual %.17g vs %.17g", pos, mp);
        cr_expect_leq(fabs(vel - mv), 1e-14, "velocity residual %.17g vs %.17g", vel, mv);
    }
    fx_free(&f);
}

/* ---- assembly and validation ---- */

Test(loop, assemble_closes_the_loop_and_keeps_the_independent_coordinates)
{
    loop_scene *scenes[3] = {loop_scene_five_bar(), loop_scene_rssr(),
                             loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7)};
    for (int sc = 0; sc < 3; sc++) {
        fixture f = fx_make(scenes[sc]);
        int nq = f.m->nq, nv = f.m->nv;
        uint64_t rng = 70 + (uint64_t)sc;
        for (int t = 0; t < 5; t++) {
            double q[MAXX], v[MAXX], q1[MAXX], v1[MAXX], dv[MAXX];
            memcpy(q, f.s->q0, (size_t)nq * sizeof *q);
            for (int i = 0; i < nv; i++) {
                dv[i] = test_uniform(&rng, -0.15, 0.15);
                v[i] = test_uniform(&rng, -1, 1);
            }
            loop_oracle_q_add(f.o, q, dv, 1.0);
            memcpy(q1, q, sizeof q1);
            memcpy(v1, v, sizeof v1);
            double before = oracle_residual(&f, q);
            char err[512] = "";
            ctc_loop_fix fix;
            ctc_status st = ctc_loop_assemble(f.m, f.d, q1, v1, 1e-12, 50, &fix, err, sizeof err);
            cr_assert_eq(st, CTC_OK, "scene %d: %s", sc, err);
            cr_expect_gt(fix.iterations, 0);
            cr_expect_leq(fix.res_after, 1e-12, "scene %d: reported residual %g", sc,
                          fix.res_after);
            cr_expect_leq(fix.vres_after, 1e-12, "scene %d: reported velocity residual %g", sc,
                          fix.vres_after);
            cr_expect_leq(oracle_residual(&f, q1), 1e-12, "scene %d: residual %g", sc,
                          oracle_residual(&f, q1));
            cr_expect_leq(oracle_velocity_residual(&f, q1, v1), 1e-12, "scene %d: |G v| %g", sc,
                          oracle_velocity_residual(&f, q1, v1));
            if (f.m->form == CTC_FORM_PLANAR) /* same residual definition: in-plane p_t - anchor */
                cr_expect_leq(fabs(fix.res_before - before), 1e-14, "res_before %g vs %g",
                              fix.res_before, before);
            /* the independent chain coordinates are exact */
            for (int k = 0; k < f.m->nbodies; k++) {
                if (!f.s->independent[k]) continue;
                for (int c = 0; c < f.m->jnt_nq[k]; c++)
                    cr_expect_eq(q1[f.m->jnt_qadr[k] + c], q[f.m->jnt_qadr[k] + c],
                                 "scene %d joint %d moved", sc, k);
                for (int c = 0; c < f.m->jnt_nv[k]; c++)
                    cr_expect_eq(v1[f.m->jnt_vadr[k] + c], v[f.m->jnt_vadr[k] + c],
                                 "scene %d joint %d velocity changed", sc, k);
            }
        }
        fx_free(&f);
    }
}

Test(loop, an_anchor_out_of_reach_does_not_close)
{
    loop_scene *s = loop_scene_five_bar();
    s->loop.anchor[0] = 10; /* the chain reaches 4.5 m at most */
    fixture f = fx_make(s);
    double q[MAXX], v[MAXX] = {0};
    memcpy(q, s->q0, sizeof q);
    char err[512] = "";
    ctc_status st = ctc_loop_assemble(f.m, f.d, q, v, 1e-12, 50, NULL, err, sizeof err);
    cr_expect_eq(st, CTC_EINVAL);
    cr_expect(strstr(err, "does not close") != NULL, "%s", err);
    fx_free(&f);
}

/* a bad loop is rejected, at build time or by ctc_loop_check at q0, with words in its message */
static void expect_loop_error(loop_scene *s, const char *const *words)
{
    char err[512] = "";
    ctc_model *m = NULL;
    ctc_status st = ctc_model_build(&s->spec, &m, err, sizeof err);
    if (st == CTC_OK) {
        ctc_data *d = ctc_data_new(m);
        st = ctc_loop_check(m, d, s->q0, NULL, err, sizeof err);
        ctc_data_free(d);
        ctc_model_free(m);
    }
    cr_expect_eq(st, CTC_EINVAL, "accepted a bad loop");
    for (int i = 0; words[i]; i++)
        cr_expect(strstr(err, words[i]) != NULL, "\"%s\" not in: %s", words[i], err);
    free(s);
}

Test(loop, bad_loops_are_rejected_with_clear_messages)
{
    /* two independent coordinates on a loop of mobility 3 */
    loop_scene *s = loop_scene_five_bar();
    set_independent(s, (const int[]){0, 1, -1});
    expect_loop_error(s, (const char *const[]){"mobility", "3", "2", NULL});

    /* four: one too many */
    s = loop_scene_five_bar();
    set_independent(s, (const int[]){0, 1, 2, 3, -1});
    expect_loop_error(s, (const char *const[]){"mobility", "3", "4", NULL});

    /* a planar four-bar in spatial form: Gruebler-Kutzbach -2, yet it moves (rank mobility 1) */
    expect_loop_error(loop_scene_four_bar(1.0, 1), (const char *const[]){"over-constrained", NULL});

    /* at the paper's q0 the links of bodies 0 and 4 are parallel and joint 4's centre lies on
       their line: the dependent joints 0, 4 and the closing joint are collinear */
    s = loop_scene_five_bar();
    set_independent(s, (const int[]){1, 2, 3, -1});
    expect_loop_error(s, (const char *const[]){"singular", NULL});

    /* closed on a body: the body must come before the tip */
    s = on_body(loop_scene_five_bar(), 1);
    s->loop.body = 4;
    expect_loop_error(s, (const char *const[]){"loop", "bodies 0..3", "got 4", NULL});

    /* a joint outside the loop cannot be dependent (unless every joint is) */
    s = on_body(loop_scene_five_bar(), 1);
    set_independent(s, (const int[]){0, 2, 3, -1});
    expect_loop_error(s, (const char *const[]){"joint 1 is outside the loop", "body 1", NULL});

    /* the tip pinned twice to body 3: its joint and the closing joint both revolute */
    s = on_body(loop_scene_five_bar(), 3);
    set_independent(s, (const int[]){0, 1, 2, 3, -1});
    expect_loop_error(s, (const char *const[]){"mobility", NULL});
}

/* ---- simulation ---- */

typedef struct loop_run {
    loop_scene *s;
    double v0[MAXX];
    ctc_gains gains[MAXX];
    ctc_traj traj[MAXX];
    ctc_sim_spec spec;
} loop_run;

static loop_run *run_new(loop_scene *s, double duration)
{
    loop_run *r = calloc(1, sizeof *r);
    cr_assert(r);
    r->s = s;
    r->spec.chain = s->spec;
    r->spec.q0 = s->q0;
    r->spec.v0 = r->v0;
    r->spec.gains = r->gains;
    r->spec.traj = r->traj;
    r->spec.model_mass_scale = 1;
    r->spec.model_inertia_scale = 1;
    r->spec.integrator = (ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-10, .atol = 1e-12};
    r->spec.duration = duration;
    r->spec.output_interval = 0.01;
    return r;
}

static void run_free(loop_run *r)
{
    free(r->s);
    free(r);
}

static ctc_sim_result *run(const loop_run *r)
{
    ctc_sim_result *res = NULL;
    char err[512] = "";
    ctc_status st = ctc_sim_run(&r->spec, NULL, &res, err, sizeof err);
    cr_assert_eq(st, CTC_OK, "ctc_sim_run: %s", err);
    return res;
}

/* a passive run that finished, conserved its energy to 1e-8, stayed on the closure to 1e-10 and
   moved (a kinetic energy above 1 J at some sample) */
static void expect_passive_run(const ctc_sim_result *res, const char *what)
{
    cr_assert_eq(res->status, CTC_RUN_DONE, "%s: %s", what, res->message);
    cr_expect_leq(res->metrics.energy_drift, 1e-8, "%s: energy drift %g", what,
                  res->metrics.energy_drift);
    cr_expect_leq(res->metrics.loop_res_max, 1e-10, "%s: loop residual %g", what,
                  res->metrics.loop_res_max);
    double ke = 0;
    for (int j = 0; j < res->nsamples; j++) ke = fmax(ke, res->ch[CTC_CH_ENERGY][2 * j]);
    cr_expect_gt(ke, 1, "%s: max kinetic energy %g J", what, ke);
}

Test(loop, passive_four_bar_conserves_energy_and_stays_closed_with_projection)
{
    loop_run *r = run_new(loop_scene_four_bar(1.0, 0), 10);
    ctc_sim_result *res = run(r);
    expect_passive_run(res, "four-bar");
    cr_expect_gt(res->metrics.projections, 0, "drift happens, so projections must too");
    /* the velocity residual grows between projections with the integrator's error (rtol 1e-10
       of speeds of a few rad/s): a sanity bound */
    cr_expect_leq(res->metrics.loop_vres_max, 1e-8, "velocity residual %g",
                  res->metrics.loop_vres_max);
    ctc_sim_result_free(res);
    run_free(r);
}

Test(loop, without_stabilisation_the_residual_is_reported_honestly)
{
    loop_run *r = run_new(loop_scene_four_bar(1.0, 0), 10);
    r->spec.loop_stab = CTC_LOOP_NONE;
    r->spec.output_interval = 0.05;
    ctc_sim_result *res = run(r);
    cr_assert_eq(res->status, CTC_RUN_DONE, "%s", res->message);
    cr_assert_eq(res->width[CTC_CH_LOOP], 2);
    fixture f = fx_make(loop_scene_four_bar(1.0, 0));
    double worst = 0, worst_v = 0, largest = 0;
    for (int j = 0; j < res->nsamples; j++) {
        const double *q = res->ch[CTC_CH_Q] + (size_t)j * res->nq;
        const double *v = res->ch[CTC_CH_QD] + (size_t)j * res->nv;
        const double *rep = res->ch[CTC_CH_LOOP] + 2 * j;
        double pt[3], vt[3];
        loop_oracle_tip(f.o, q, v, pt, NULL, vt, NULL);
        double dp[2] = {pt[0] - f.s->loop.anchor[0], pt[1] - f.s->loop.anchor[1]};
        double mp = fmax(fabs(dp[0] * f.m->plane_e1[0] + dp[1] * f.m->plane_e1[1]),
                         fabs(dp[0] * f.m->plane_e2[0] + dp[1] * f.m->plane_e2[1]));
        double mv = fmax(fabs(vt[0] * f.m->plane_e1[0] + vt[1] * f.m->plane_e1[1]),
                         fabs(vt[0] * f.m->plane_e2[0] + vt[1] * f.m->plane_e2[1]));
        cr_assert(isfinite(rep[0]) && isfinite(rep[1]));
        worst = fmax(worst, fabs(rep[0] - mp));
        worst_v = fmax(worst_v, fabs(rep[1] - mv));
        largest = fmax(largest, rep[0]);
    }
    cr_expect_leq(worst, 1e-12, "reported vs recomputed position residual: %g", worst);
    cr_expect_leq(worst_v, 1e-12, "reported vs recomputed velocity residual: %g", worst_v);
    cr_expect_gt(largest, 0, "no drift at all is not credible without stabilisation");
    cr_expect_geq(res->metrics.loop_res_max, largest, "metric %g below the samples' %g",
                  res->metrics.loop_res_max, largest);
    cr_expect_eq(res->metrics.projections, 0);
    fx_free(&f);
    ctc_sim_result_free(res);
    run_free(r);
}

Test(loop, baumgarte_stabilisation_keeps_the_loop_closer_than_none)
{
    /* measured over 10 s: residual 3.6e-11 with Baumgarte (10, 10), 7.9e-9 without */
    double res[2];
    for (int i = 0; i < 2; i++) {
        loop_run *r = run_new(loop_scene_four_bar(1.0, 0), 10);
        r->spec.loop_stab = i ? CTC_LOOP_NONE : CTC_LOOP_BAUMGARTE;
        ctc_sim_result *out = run(r);
        cr_assert_eq(out->status, CTC_RUN_DONE, "%s", out->message);
        res[i] = out->metrics.loop_res_max;
        if (i == 0) /* measured 2.9e-10 (and 9.8e-9 without stabilisation) */
            cr_expect_leq(out->metrics.energy_drift, 1e-8, "Baumgarte: energy drift %g",
                          out->metrics.energy_drift);
        cr_expect_eq(out->metrics.projections, 0);
        ctc_sim_result_free(out);
        run_free(r);
    }
    cr_expect_leq(res[0], 1e-9, "Baumgarte: residual %g", res[0]);
    cr_expect_lt(10 * res[0], res[1], "Baumgarte %g vs none %g", res[0], res[1]);
}

Test(loop, exact_pd_error_of_the_five_bar_follows_the_closed_form)
{
    loop_run *r = run_new(loop_scene_five_bar(), 10);
    const double target[3] = {0, PI / 4, -3 * PI / 4}, kp = 25, kv = 10, wn = 5; /* critical */
    r->spec.controller = CTC_CTRL_PD;
    for (int i = 0; i < 3; i++) {
        r->gains[i] = (ctc_gains){.kp = kp, .kv = kv};
        r->traj[i] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = target[i]};
    }
    ctc_sim_result *res = run(r);
    cr_assert_eq(res->status, CTC_RUN_DONE, "%s", res->message);
    cr_assert_eq(res->nind, 3);
    cr_assert_eq(res->width[CTC_CH_E], 3);
    double dev = 0;
    for (int i = 0; i < 3; i++) {
        double e0 = target[i] - r->s->q0[i], de0 = 0; /* from rest */
        for (int j = 0; j < res->nsamples; j++) {
            double t = res->t[j], ref = (e0 + (de0 + wn * e0) * t) * exp(-wn * t);
            dev = fmax(dev, fabs(res->ch[CTC_CH_E][3 * j + i] - ref));
        }
    }
    cr_expect_leq(dev, 1e-6, "|e - closed form| = %g", dev);
    cr_expect_leq(res->metrics.errdyn_dev, 1e-6, "errdyn_dev %g", res->metrics.errdyn_dev);
    cr_expect_leq(res->metrics.loop_res_max, 1e-10, "loop residual %g", res->metrics.loop_res_max);
    /* it arrives: the final independent coordinates are the set point */
    const double *qf = res->ch[CTC_CH_Q] + (size_t)(res->nsamples - 1) * res->nq;
    for (int i = 0; i < 3; i++) cr_expect_leq(fabs(qf[i] - target[i]), 1e-6, "joint %d", i);
    ctc_sim_result_free(res);
    run_free(r);
}

Test(loop, a_loop_closed_on_a_body_in_simulation)
{
    /* passive: the five-bar closed on body 0, every joint dependent, swings from q0 */
    loop_run *r = run_new(on_body(loop_scene_five_bar(), 0), 5);
    set_independent(r->s, (const int[]){-1});
    ctc_sim_result *res = run(r);
    expect_passive_run(res, "passive five-bar on body 0");
    ctc_sim_result_free(res);
    run_free(r);

    /* exact-model PD on the five-bar closed on body 1: joints 0 and 1 carry the loop, joint 2
       drives it; each independent error follows e(t) = e0 (1 + wn t) exp(-wn t) */
    r = run_new(on_body(loop_scene_five_bar(), 1), 5);
    set_independent(r->s, (const int[]){0, 1, 2, -1});
    const double move[3] = {0.4, -0.3, 0.25}, wn = 5;
    r->spec.controller = CTC_CTRL_PD;
    for (int i = 0; i < 3; i++) {
        r->gains[i] = (ctc_gains){.kp = wn * wn, .kv = 2 * wn};
        r->traj[i] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = r->s->q0[i] + move[i]};
    }
    res = run(r);
    cr_assert_eq(res->status, CTC_RUN_DONE, "%s", res->message);
    double dev = 0;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < res->nsamples; j++) {
            double t = res->t[j], ref = move[i] * (1 + wn * t) * exp(-wn * t);
            dev = fmax(dev, fabs(res->ch[CTC_CH_E][3 * j + i] - ref));
        }
    }
    cr_expect_leq(dev, 1e-6, "PD on a body's loop: |e - closed form| = %g", dev);
    cr_expect_leq(res->metrics.loop_res_max, 1e-10, "PD: loop residual %g",
                  res->metrics.loop_res_max);
    ctc_sim_result_free(res);
    run_free(r);
}

Test(loop, a_singular_start_is_reported_not_simulated)
{
    loop_run *r = run_new(loop_scene_five_bar(), 1);
    set_independent(r->s, (const int[]){1, 2, 3, -1});
    r->spec.controller = CTC_CTRL_PD;
    for (int i = 0; i < 3; i++) {
        r->gains[i] = (ctc_gains){.kp = 25, .kv = 10};
        r->traj[i] = (ctc_traj){.type = CTC_TRAJ_CONSTANT, .value = r->s->q0[i + 1]};
    }
    ctc_sim_result *res = NULL;
    char err[512] = "";
    ctc_status st = ctc_sim_run(&r->spec, NULL, &res, err, sizeof err);
    if (st == CTC_OK) {
        cr_expect_eq(res->status, CTC_RUN_SINGULAR, "status %s", ctc_run_status_name(res->status));
        cr_expect(strstr(res->message, "singular") != NULL, "%s", res->message);
        ctc_sim_result_free(res);
    } else {
        cr_expect_eq(st, CTC_EINVAL);
        cr_expect(strstr(err, "singular") != NULL, "%s", err);
    }
    run_free(r);
}

/* ---- a loop on a branched tree ---- */

/* The planar Y: a crank-rocker four-bar closing on the ground (bodies 0, 1 and the tip 4), with
 * a double pendulum (bodies 2, 3) hanging from the crank's end. Joints 0, 2, 3 independent. */
static loop_scene *tree_y(void)
{
    loop_scene *s = loop_scene_four_bar(1.0, 0);
    const loop_branch br[] = {
        {.parent = 0,
         .type = CTC_JOINT_REVOLUTE,
         .axis = {0, 0, 1},
         .location = {0, -0.5, 0},
         .q0 = {0.4}},
        {.parent = -2,
         .type = CTC_JOINT_REVOLUTE,
         .axis = {0, 0, 1},
         .location = {0, -0.4, 0},
         .q0 = {-0.7}},
    };
    loop_scene_branch(s, 2, br);
    set_independent(s, (const int[]){0, 2, 3, -1});
    return s;
}

/* The planar hand: the paper's five-bar closed on body 0 (the palm), so bodies 1-3 and the tip
 * 8 make a four-bar finger closing on the palm; a two-link finger (4, 5) and a one-link finger
 * (6) on the palm, and a link (7) on body 2 inside the loop. Joints 0-2 and the branches
 * independent. */
static loop_scene *tree_hand(void)
{
    loop_scene *s = loop_scene_five_bar();
    loop_scene_close_on(s, 0);
    const loop_branch br[] = {
        {.parent = 0,
         .type = CTC_JOINT_REVOLUTE,
         .axis = {0, 0, 1},
         .location = {0.1, -0.6, 0},
         .q0 = {0.5}},
        {.parent = -2,
         .type = CTC_JOINT_REVOLUTE,
         .axis = {0, 0, -1},
         .location = {0, -0.4, 0},
         .q0 = {0.3}},
        {.parent = 0,
         .type = CTC_JOINT_PRISMATIC,
         .axis = {1, -1, 0},
         .location = {0, -0.3, 0},
         .q0 = {0.1}},
        {.parent = 2,
         .type = CTC_JOINT_REVOLUTE,
         .axis = {0, 0, 1},
         .location = {0, -0.25, 0},
         .q0 = {-0.6}},
    };
    loop_scene_branch(s, 4, br);
    set_independent(s, (const int[]){0, 1, 2, 4, 5, 6, 7, -1});
    return s;
}

/* A spatial tree: the random 8R loop closed on body 0 (joints 1-6 and the closing joint 10 in
 * the loop), with a spherical joint on body 0 outside the loop, a revolute link on body 3 and a
 * prismatic one under it, and a revolute link on body 5. Joints 0, 6-9 and 11 independent. */
static loop_scene *tree_spatial(void)
{
    loop_scene *s = loop_scene_spatial(7, CTC_JOINT_REVOLUTE, 7);
    loop_scene_close_on(s, 0);
    const loop_branch br[] = {
        {.parent = 0,
         .type = CTC_JOINT_SPHERICAL,
         .location = {0.1, 0.2, -0.1},
         .q0 = {0.9, 0.3, -0.2, 0.1}},
        {.parent = 3,
         .type = CTC_JOINT_REVOLUTE,
         .axis = {0.3, 1, -0.2},
         .location = {0.05, 0, 0.1},
         .q0 = {0.8}},
        {.parent = -3,
         .type = CTC_JOINT_PRISMATIC,
         .axis = {1, 0.2, 0.4},
         .location = {0, -0.4, 0},
         .q0 = {0.15}},
        {.parent = 5,
         .type = CTC_JOINT_REVOLUTE,
         .axis = {-0.5, 0.1, 1},
         .location = {0, 0.1, 0},
         .q0 = {-0.4}},
    };
    double nrm = sqrt(0.81 + 0.09 + 0.04 + 0.01);
    loop_branch b0 = br[0];
    for (int i = 0; i < 4; i++) b0.q0[i] /= nrm;
    loop_branch all[4] = {b0, br[1], br[2], br[3]};
    loop_scene_branch(s, 4, all);
    set_independent(s, (const int[]){0, 6, 7, 8, 9, 11, -1});
    return s;
}

/* A spatial tree closing on the ground: the 6R+S loop (spherical closing joint) with a revolute
 * link on body 1 and a spherical one on body 3. Joints 0, 2, 4 and the branches 5, 6
 * independent. */
static loop_scene *tree_spatial_ground(void)
{
    loop_scene *s = loop_scene_spatial(6, CTC_JOINT_SPHERICAL, 13);
    const loop_branch br[] = {
        {.parent = 1,
         .type = CTC_JOINT_REVOLUTE,
         .axis = {0, 1, 0.3},
         .location = {0, 0, 0.1},
         .q0 = {0.6}},
        {.parent = 3, .type = CTC_JOINT_SPHERICAL, .location = {0.1, 0, 0}, .q0 = {1, 0, 0, 0}},
    };
    loop_scene_branch(s, 2, br);
    set_independent(s, (const int[]){0, 2, 4, 5, 6, -1});
    return s;
}

Test(loop, a_loop_on_a_branched_tree_plans_its_spine_as_one_path)
{
    fixture f = fx_make(tree_hand());
    const ctc_model *m = f.m;
    cr_assert_eq(m->chain, 0);
    cr_assert_eq(m->loop_body, 0);
    cr_assert_eq(m->loop_first, 1);
    /* the spine 0-1-2-3-8 is one path whatever the subtree sizes */
    const int spine[] = {0, 1, 2, 3, 8};
    for (int i = 0; i + 1 < 5; i++) cr_expect_eq(m->body_heavy[spine[i]], spine[i + 1]);
    const unsigned char in_loop[10] = {0, 1, 1, 1, 0, 0, 0, 0, 1, 1};
    for (int k = 0; k < m->njoints; k++) cr_expect_eq(m->jnt_loop[k], in_loop[k], "joint %d", k);
    /* the top node splits the spine at the loop's first joint */
    const ctc_tree_node *top = &m->tree[m->ntree - 1];
    cr_expect_eq(top->kind, CTC_NODE_JOIN);
    cr_expect_eq(top->joint, 1);
    cr_expect_eq(m->height_start[m->height] - m->height_start[m->height - 1], 1);
    cr_expect_eq(m->mobility, 3 + 4);
    cr_expect_eq(m->nind, 7);
    fx_free(&f);
}

/* Forward GDCA, both inverse forms and the round trip on loops closed on the ground or on an
 * ancestor of the tip of branched trees, planar and spatial, against the oracle. */
Test(loop, a_loop_on_a_branched_tree_matches_the_oracle)
{
    loop_case cases[] = {
        {tree_y(), NULL, "planar Y, one branch a four-bar on the ground"},
        {tree_hand(), NULL, "planar hand, a four-bar finger closing on the palm"},
        {tree_spatial(), NULL, "spatial tree, 8R loop on body 0"},
        {tree_spatial_ground(), NULL, "spatial tree, 6R+S loop on the ground"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        fixture f = fx_make(cases[i].s);
        f.what = cases[i].what;
        cr_assert_eq(f.m->chain, 0, "%s", f.what);
        char err[512] = "";
        cr_assert_eq(ctc_loop_check(f.m, f.d, f.s->q0, NULL, err, sizeof err), CTC_OK, "%s: %s",
                     f.what, err);
        double passive = check_forward(&f, 240 + i, 4, 0),
               driven = check_forward(&f, 250 + i, 4, 1);
        cr_expect_leq(passive, 1e-10, "%s, forward, passive: %g", f.what, passive);
        cr_expect_leq(driven, 1e-10, "%s, forward, driven: %g", f.what, driven);
        inverse_errors e = check_inverse(&f, 260 + i, 4, 0.2);
        cr_expect_leq(e.torque, 1e-10, "%s: torques vs oracle %g", f.what, e.torque);
        cr_expect_leq(e.full, 1e-12, "%s: early stop vs full %g", f.what, e.full);
        cr_expect_leq(e.round, 1e-10, "%s: round trip %g", f.what, e.round);
        cr_expect_leq(e.dependent, 1e-10, "%s: dependent accelerations %g", f.what, e.dependent);
        fx_free(&f);
    }
}

/* Forward and both inverse forms of a loop on a tree at 1, 2 and 8 threads, split at every
 * height (grain 1): bitwise equal. */
Test(loop, a_loop_on_a_branched_tree_gives_bitwise_equal_results_on_threads)
{
    loop_scene *(*make[])(void) = {tree_hand, tree_spatial};
    for (int c = 0; c < 2; c++) {
        fixture f = fx_make(make[c]());
        f.what = c ? "spatial tree" : "planar hand";
        uint64_t rng = 300 + c;
        const int nvx = f.m->nvx;
        double q[MAXX], v[MAXX], force[MAXX], u[MAXX], a[3][MAXX], fi[3][MAXX], fm[3][MAXX];
        random_state(&f, &rng, 0.2, 1.5, q, v);
        for (int i = 0; i < nvx; i++) {
            force[i] = coord_independent(&f, i) ? test_uniform(&rng, -5, 5) : 0;
            u[i] = coord_independent(&f, i) ? test_uniform(&rng, -5, 5) : 0;
        }
        const int threads[3] = {1, 2, 8};
        for (int t = 0; t < 3; t++) {
            cr_assert_eq(ctc_data_set_threads(f.d, threads[t], NULL, 0), CTC_OK);
            f.d->opt.par_grain = 1;
            library_forward(&f, q, v, force, a[t]);
            library_inverse(&f, q, v, u, 0, fi[t]);
            library_inverse(&f, q, v, u, 1, fm[t]);
        }
        for (int t = 1; t < 3; t++) {
            cr_expect_eq(memcmp(a[t], a[0], (size_t)nvx * sizeof **a), 0, "%s: forward, %d threads",
                         f.what, threads[t]);
            cr_expect_eq(memcmp(fi[t], fi[0], (size_t)nvx * sizeof **fi), 0,
                         "%s: inverse, %d threads", f.what, threads[t]);
            cr_expect_eq(memcmp(fm[t], fm[0], (size_t)nvx * sizeof **fm), 0,
                         "%s: mobility inverse, %d threads", f.what, threads[t]);
        }
        fx_free(&f);
    }
}

/* Exact-model PD on the planar hand: the four-bar finger on the palm driven by joints 1 and 2,
 * the palm and the open fingers by theirs; each independent error follows the critically
 * damped closed form e(t) = e0 (1 + wn t) exp(-wn t) from rest. */
Test(loop, exact_pd_error_on_a_loop_tree_follows_the_closed_form)
{
    loop_run *r = run_new(tree_hand(), 4);
    ctc_model *m = build(&r->s->spec);
    const int nind = m->nind;
    const double wn = 5;
    double move[MAXX];
    r->spec.controller = CTC_CTRL_PD;
    for (int i = 0; i < nind; i++) {
        move[i] = 0.2 * (i % 2 ? -1 : 1) * (1 + 0.1 * i);
        r->gains[i] = (ctc_gains){.kp = wn * wn, .kv = 2 * wn};
        r->traj[i] = (ctc_traj){.type = CTC_TRAJ_CONSTANT,
                                .value = r->s->q0[m->jnt_qadr[m->ind_joint[i]]] + move[i]};
    }
    ctc_model_free(m);
    ctc_sim_result *res = run(r);
    cr_assert_eq(res->status, CTC_RUN_DONE, "%s", res->message);
    cr_assert_eq(res->nind, nind);
    double dev = 0;
    for (int i = 0; i < nind; i++) {
        for (int j = 0; j < res->nsamples; j++) {
            double t = res->t[j], ref = move[i] * (1 + wn * t) * exp(-wn * t);
            dev = fmax(dev, fabs(res->ch[CTC_CH_E][(size_t)nind * j + i] - ref));
        }
    }
    cr_expect_leq(dev, 1e-6, "PD on a loop tree: |e - closed form| = %g", dev);
    cr_expect_leq(res->metrics.errdyn_dev, 1e-6, "errdyn_dev %g", res->metrics.errdyn_dev);
    cr_expect_leq(res->metrics.loop_res_max, 1e-10, "loop residual %g", res->metrics.loop_res_max);
    ctc_sim_result_free(res);
    run_free(r);
}
