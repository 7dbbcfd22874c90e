/*
 * bench_loop.c - the cost of one CTC evaluation of a closed chain with the library's loop inverse
 * and with the paper's closed-chain iGDCA (with and without its early stop), against the same
 * chain left open, and the cost of putting a drifted state back onto the loop closure.
 *
 * Chains (one loop each, the closing joint from the tip to the ground, model.h; "on b" rows
 * close the same loop on body b instead, model.h, so that joints 0..b carry it):
 *   arch     n uniform 1 kg, 1 m rods about +z (planar form), absolute link angles spread evenly
 *            from 3 pi / 4 to pi / 4 (from -y) so the chain is an arch from the origin to its
 *            anchor; revolute closing joint at the tip's far end. Mobility n + 1 - 3 = n - 2:
 *            joints n/2, n-1 and the closing joint are dependent, every other joint independent
 *            (joint 0 driven and the closing joint passive, as in the five-bar).
 *   five-bar the paper's five-bar (section 7.2; tests/support/loop_oracle.h), joints 0, 1, 2
 *            independent.
 *   spatial  n 1 kg boxes on revolute joints with random unit axes and 0.3 m links in random
 *            directions (spatial form), closed by a spherical joint at the tip's link end.
 *            Mobility n + 3 - 6 = n - 3: joints n/4, n/2, 3n/4 and the closing joint are
 *            dependent, every other joint independent.
 *   arch spread  the arch with its dependent joints spread along it: n/3, 2n/3 and the closing
 *            joint (the arch's are bunched at the tip, which makes its problem ill conditioned).
 *   arch on b, spatial on b   the arch closed on body n/4, the spatial chain on body n/8: the
 *            anchor is the same point in that body's frame, the dependent joints the same.
 * Each loop is closed at its q0 by construction (the anchor is where forward kinematics at q0
 * puts the tip's closing point) and checked with ctc_loop_check; the state is q0 with random
 * velocities projected onto the closure, and random commanded accelerations.
 *
 * Timings per evaluation:
 *   ctc        kinematics + handles + iGDCA + GDCA forward, the work of one CTC right-hand side,
 *              with the library's loop inverse (ctc_gdca_inverse: the open chain's composite
 *              pass and one dim x dim solve at the closing joint, gdca_inverse_loop.h) and with
 *              the paper's iGDCA (ctc_gdca_inverse_mobility) in its place;
 *   iGDCA      the inverse pass alone: the library's, the paper's with its early stop (the
 *              nodes it visits are counted) and the paper's without it (d->opt.inv_full = 1);
 *   open       the same chain without its loop: ctc (composite iGDCA), the composite iGDCA and
 *              the mobility-form iGDCA alone;
 * every inverse pass timed alone is a first pass at its state (the composite pass's kept
 * inertias, gdca_inverse.c, cleared before each), as in bench_dynamics;
 *   projection ctc_loop_assemble (tol 1e-12, at most 20 Newton iterations) from the state with
 *              1e-9 added to every dependent chain coordinate and rate, restored each time.
 * Batches of all timings are interleaved so that machine noise hits them alike; each batch
 * starts one timing further on, and each timing runs untimed for SETTLE_S before it is timed, so
 * that the caches and the core's clock have settled after the timing before (bench/NOTEBOOK.md,
 * "Closed chains", "Measuring note"). The figures are medians over the batches.
 *
 * Checks before timing, reported in the second table: the paper's iGDCA gives bitwise the same
 * driving forces with and without its early stop, and every pass's are finite; the library's and
 * the paper's forces against the dense loop oracle (tests/support/loop_oracle.h; n <=
 * ORACLE_MAX_N); GDCA forward on the library's against the commanded accelerations of the
 * independent coordinates (the round trip, closed and open), and the round trip's floor: how far
 * the forward pass's accelerations move when each driving force is perturbed by its own rounding
 * (f_i (1 + eps r), r uniform in [-1, 1], FLOOR_DRAWS draws), relative to max |u| as the round
 * trip is: no solver in double precision can be held to less; the projection converges. A case that
 * fails is reported on stderr and left out of the tables, and the run ends with status 1. Usage:
 * bench_loop [max_n] [batches]
 */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "chains.h"
#include "ctc.h"
#include "linalg.h"
#include "loop_oracle.h"
#include "spatial.h"

enum {
    T_CTC,
    T_CTC_PAPER,
    T_INV,
    T_INV_PAPER,
    T_INV_FULL,
    T_OPEN_CTC,
    T_OPEN_INV,
    T_OPEN_MOB,
    T_PROJ,
    NT
};

#define PROJ_TOL 1e-12
#define PROJ_ITER 20
#define DRIFT 1e-9
#define ORACLE_MAX_N 1024 /* the dense oracle is O(n^3) */
#define SETTLE_S 5e-3     /* s, untimed runs before each timing in a batch */
#define FLOOR_DRAWS 3

typedef struct bench_case {
    const ctc_model *m;    /* the closed chain */
    const ctc_model *open; /* the same chain, open */
    ctc_data *d, *d_open, *d_proj;
    double *q, *v;      /* the state: (nq), (nv) */
    double *u, *f, *a;  /* (nvx) */
    double *fo, *ao;    /* open chain: (nv) */
    double *qd, *vd;    /* the drifted state */
    double *qp, *vp;    /* its copy, projected in place */
    ctc_loop_fix fix;   /* what the last projection did */
    ctc_status proj_st; /* and its status */
} bench_case;

typedef struct bench_row {
    char label[16];
    int n, ntree, visited, mobility, iterations;
    double med[NT], cond, res_after;
    double f_oracle, f_paper;     /* max |f - f_oracle| / max |f_oracle| of the default and the
                                     paper's iGDCA; -1: not computed */
    double round_trip, open_trip; /* max |qacc - u| / max |u| over the independent coordinates */
    double floor;                 /* the round trip's floor: max |qacc(f + df) - qacc(f)| / max |u|
                                     over FLOOR_DRAWS draws of df_i = eps |f_i| uniform(-1, 1) */
} bench_row;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static volatile double sink;

/* the inverse pass: which = 0 the library's default (ctc_gdca_inverse: for loops the open
   chain's composite pass and the closure), 1 the paper's iGDCA with its early stop, 2 the paper's
   iGDCA disassembling every node */
static void inverse(const ctc_model *m, ctc_data *d, const double *u, double *f, int which)
{
    d->icomp_stamp = 0; /* a first pass at the state: no composite inertias kept from the last */
    d->opt.inv_full = which == 2;
    if (which == 0)
        ctc_gdca_inverse(m, d, u, f);
    else
        ctc_gdca_inverse_mobility(m, d, u, f);
    d->opt.inv_full = 0;
}

static void ctc_eval(const ctc_model *m, ctc_data *d, const double *q, const double *v,
                     const double *u, double *f, double *a, int which)
{
    ctc_kinematics(m, d, q, v);
    ctc_handles(m, d);
    inverse(m, d, u, f, which);
    ctc_gdca_forward(m, d, f, a);
}

static void run_once(bench_case *c, int what)
{
    const ctc_model *m = c->m;
    switch (what) {
    case T_CTC:
    case T_CTC_PAPER:
        ctc_eval(m, c->d, c->q, c->v, c->u, c->f, c->a, what == T_CTC_PAPER);
        break;
    case T_INV:
    case T_INV_PAPER:
    case T_INV_FULL:
        inverse(m, c->d, c->u, c->f, what - T_INV);
        break;
    case T_OPEN_CTC:
        ctc_eval(c->open, c->d_open, c->q, c->v, c->u, c->fo, c->ao, 0);
        break;
    case T_OPEN_INV:
        c->d_open->icomp_stamp = 0;
        ctc_gdca_inverse(c->open, c->d_open, c->u, c->fo);
        break;
    case T_OPEN_MOB:
        ctc_gdca_inverse_mobility(c->open, c->d_open, c->u, c->fo);
        break;
    case T_PROJ:
        memcpy(c->qp, c->qd, (size_t)m->nq * sizeof *c->qp);
        memcpy(c->vp, c->vd, (size_t)m->nv * sizeof *c->vp);
        c->proj_st =
            ctc_loop_assemble(m, c->d_proj, c->qp, c->vp, PROJ_TOL, PROJ_ITER, &c->fix, NULL, 0);
        break;
    }
    sink += c->a[0] + c->f[0] + c->fo[0] + c->qp[0];
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* median seconds per evaluation of each timing, from interleaved batches */
static void measure(bench_case *c, int batches, double med[NT])
{
    /* a batch of reps evaluations lasts about 2 ms for the slowest timing */
    double t0 = now();
    int probe = 0;
    while (now() - t0 < 2e-3 || probe < 1) {
        run_once(c, T_CTC_PAPER);
        run_once(c, T_OPEN_CTC);
        run_once(c, T_PROJ);
        probe++;
    }
    int reps = probe;
    double *samples = malloc(sizeof(double) * (size_t)batches * NT);
    if (!samples) abort();
    for (int b = 0; b < batches; b++) {
        for (int i = 0; i < NT; i++) {
            /* each batch starts with the next timing, so none always follows the same one;
               each runs untimed for SETTLE_S first (see the top of the file) */
            int w = (b + i) % NT;
            double s = now();
            do {
                run_once(c, w);
            } while (now() - s < SETTLE_S);
            s = now();
            for (int r = 0; r < reps; r++) run_once(c, w);
            samples[w * batches + b] = (now() - s) / reps;
        }
    }
    for (int w = 0; w < NT; w++) {
        qsort(samples + w * batches, (size_t)batches, sizeof(double), cmp_double);
        med[w] = samples[w * batches + batches / 2];
    }
    free(samples);
}

/* builds a model, or ends the run: the scenes here are valid by construction */
static ctc_model *build(const ctc_chain_spec *spec, const char *label)
{
    char err[256];
    ctc_model *m = NULL;
    if (ctc_model_build(spec, &m, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "bench_loop: %s n = %d: %s\n", label, spec->nbodies, err);
        exit(1);
    }
    return m;
}

/* the scene, or ends the run */
static test_loop *scene(test_loop *l, const char *label, int n)
{
    if (l == NULL) {
        fprintf(stderr, "bench_loop: %s n = %d: could not make the scene\n", label, n);
        exit(1);
    }
    return l;
}

static double max_abs(const double *x, int n)
{
    double r = 0;
    for (int i = 0; i < n; i++) r = fmax(r, fabs(x[i]));
    return r;
}

/* max |qacc - u| over the independent coordinates, relative to max |u| */
static double trip_error(const ctc_model *m, const double *u, const double *qacc)
{
    double e = 0;
    for (int i = 0; i < m->nind; i++) e = fmax(e, fabs(qacc[m->ind_coord[i]] - u[m->ind_coord[i]]));
    return e / max_abs(u, m->nvx);
}

/* Builds the closed and the open chain of spec, checks them at q0 and times them into row.
 * Returns 0, or -1 after printing what went wrong (a library error, non-finite or inconsistent
 * results, a projection that does not converge). */
static int bench_loop_case(const char *label, const ctc_chain_spec *spec, const double *q0,
                           int batches, bench_row *row)
{
    char err[256] = "";
    const int n = spec->nbodies;
    ctc_chain_spec open_spec = *spec;
    open_spec.loop = NULL;
    open_spec.independent = NULL;
    ctc_model *m = build(spec, label), *open = build(&open_spec, label);
    bench_case c = {.m = m, .open = open};
    c.d = ctc_data_new(m), c.d_open = ctc_data_new(open), c.d_proj = ctc_data_new(m);
    const size_t nq = (size_t)m->nq, nv = (size_t)m->nv, nvx = (size_t)m->nvx;
    c.q = calloc(nq, sizeof(double)), c.v = calloc(nv, sizeof(double));
    c.u = calloc(nvx, sizeof(double)), c.f = calloc(nvx, sizeof(double));
    c.a = calloc(nvx, sizeof(double));
    c.fo = calloc(nv, sizeof(double)), c.ao = calloc(nv, sizeof(double));
    c.qd = calloc(nq, sizeof(double)), c.vd = calloc(nv, sizeof(double));
    c.qp = calloc(nq, sizeof(double)), c.vp = calloc(nv, sizeof(double));
    double *f_full = calloc(nvx, sizeof(double)), *f_paper = calloc(nvx, sizeof(double));
    if (!c.d || !c.d_open || !c.d_proj || !c.q || !c.v || !c.u || !c.f || !c.a || !c.fo || !c.ao ||
        !c.qd || !c.vd || !c.qp || !c.vp || !f_full || !f_paper)
        abort();

    /* the loop is closed at q0 and the independent joints drive it there */
    memset(row, 0, sizeof *row);
    snprintf(row->label, sizeof row->label, "%s", label);
    row->n = n, row->ntree = m->ntree, row->mobility = m->mobility;
    if (ctc_loop_check(m, c.d, q0, &row->cond, err, sizeof err) != CTC_OK) goto done;
    for (int i = 0; i < m->ntree; i++) row->visited += m->inv_need[i];

    /* the state: q0, random rates projected onto the closure; random commands */
    uint64_t rng = 3;
    memcpy(c.q, q0, nq * sizeof(double));
    for (size_t i = 0; i < nv; i++) c.v[i] = test_uniform(&rng, -1, 1);
    for (size_t i = 0; i < nvx; i++) c.u[i] = test_uniform(&rng, -1, 1);
    if (ctc_loop_assemble(m, c.d, c.q, c.v, PROJ_TOL, PROJ_ITER, NULL, err, sizeof err) != CTC_OK)
        goto done;

    /* the paper's iGDCA gives the same forces with and without its early stop; all are finite
       and against the loop oracle's (up to n = ORACLE_MAX_N); the forward pass turns the
       default's into the commanded accelerations */
    ctc_eval(m, c.d, c.q, c.v, c.u, f_full, c.a, 2);
    ctc_eval(m, c.d, c.q, c.v, c.u, f_paper, c.a, 1);
    ctc_eval(m, c.d, c.q, c.v, c.u, c.f, c.a, 0);
    if (!test_all_finite(c.f, m->nvx) || !test_all_finite(f_full, m->nvx) ||
        !test_all_finite(c.a, m->nvx) || !test_all_finite(f_paper, m->nvx)) {
        ctc_gdca_inverse(m, c.d, c.u, c.f); /* for its singular_joint and loop_cond */
        snprintf(err, sizeof err,
                 "non-finite driving forces or accelerations (inverse pass: singular_joint %d, "
                 "loop_cond %g)",
                 c.d->singular_joint, c.d->loop_cond);
        goto done;
    }
    if (memcmp(f_paper, f_full, nvx * sizeof(double)) != 0) {
        snprintf(err, sizeof err, "the early-stopped inverse pass changed the driving forces");
        goto done;
    }
    row->round_trip = trip_error(m, c.u, c.a);
    row->f_oracle = row->f_paper = -1;
    if (n <= ORACLE_MAX_N) {
        loop_oracle *o = loop_oracle_new(spec);
        int st = o ? loop_oracle_inverse(o, c.q, c.v, c.u, f_full, NULL) : -1;
        loop_oracle_free(o);
        if (st != 0) {
            snprintf(err, sizeof err, "the loop oracle failed");
            goto done;
        }
        for (size_t i = 0; i < nvx; i++) {
            row->f_oracle = fmax(row->f_oracle, fabs(c.f[i] - f_full[i]));
            row->f_paper = fmax(row->f_paper, fabs(f_paper[i] - f_full[i]));
        }
        row->f_oracle /= max_abs(f_full, m->nvx);
        row->f_paper /= max_abs(f_full, m->nvx);
    }

    /* the floor: what rounding the driving forces alone does to the accelerations (f_paper
       and f_full are free from here) */
    for (int t = 0; t < FLOOR_DRAWS; t++) {
        for (size_t i = 0; i < nvx; i++) {
            f_paper[i] = c.f[i] * (1 + DBL_EPSILON * test_uniform(&rng, -1, 1));
        }
        ctc_kinematics(m, c.d, c.q, c.v);
        ctc_handles(m, c.d);
        ctc_gdca_forward(m, c.d, f_paper, f_full);
        double e = 0;
        for (int i = 0; i < m->nind; i++) {
            e = fmax(e, fabs(f_full[m->ind_coord[i]] - c.a[m->ind_coord[i]]));
        }
        row->floor = fmax(row->floor, e / max_abs(c.u, m->nvx));
    }
    ctc_eval(open, c.d_open, c.q, c.v, c.u, c.fo, c.ao, 0);
    if (!test_all_finite(c.fo, m->nv) || !test_all_finite(c.ao, m->nv)) {
        snprintf(err, sizeof err, "open chain: non-finite driving forces or accelerations");
        goto done;
    }
    row->open_trip = trip_error(open, c.u, c.ao);

    /* the drifted state: every dependent chain coordinate and rate off by DRIFT */
    memcpy(c.qd, c.q, nq * sizeof(double));
    memcpy(c.vd, c.v, nv * sizeof(double));
    for (int k = 0; k < n; k++) {
        if (m->jnt_indep[k]) continue;
        for (int i = 0; i < m->jnt_nv[k]; i++) {
            c.qd[m->jnt_qadr[k] + i] += DRIFT;
            c.vd[m->jnt_vadr[k] + i] += DRIFT;
        }
    }
    run_once(&c, T_PROJ);
    if (c.proj_st != CTC_OK) {
        ctc_loop_assemble(m, c.d_proj, c.qp, c.vp, PROJ_TOL, PROJ_ITER, NULL, err, sizeof err);
        goto done;
    }
    row->iterations = c.fix.iterations;
    row->res_after = c.fix.res_after;

    measure(&c, batches, row->med);
    if (c.proj_st != CTC_OK) snprintf(err, sizeof err, "projection failed while timing");

done:
    if (err[0]) fprintf(stderr, "bench_loop: %s n = %d: %s\n", label, n, err);
    free(c.q), free(c.v), free(c.u), free(c.f), free(c.a), free(c.fo), free(c.ao);
    free(c.qd), free(c.vd), free(c.qp), free(c.vp), free(f_full), free(f_paper);
    ctc_data_free(c.d), ctc_data_free(c.d_open), ctc_data_free(c.d_proj);
    ctc_model_free(m), ctc_model_free(open);
    return err[0] ? -1 : 0;
}

static double saving(double early, double full)
{
    return 100.0 * (full - early) / full;
}

static void print_rows(const bench_row *rows, int nrows)
{
    printf("| chain    |    n | ctc (us) | ctc, paper's iGDCA (us) | iGDCA (us) | paper's iGDCA "
           "(us) | nodes visited | paper's, no early stop (us) | saving | open ctc (us) | "
           "closed / open | ctc/n ns | open iGDCA composite (us) | open iGDCA mobility (us) |\n");
    printf("| -------- | ---: | ---------: | ---------: | -------: | -------: | ------------: | "
           "-------: | ----: | ---------: | ----: | -----: | -------: | -------: |\n");
    for (int i = 0; i < nrows; i++) {
        const bench_row *r = &rows[i];
        const double *t = r->med;
        char nodes[32];
        snprintf(nodes, sizeof nodes, "%d / %d", r->visited, r->ntree);
        printf("| %-8s | %4d | %10.2f | %10.2f | %8.2f | %8.2f | %13s | %8.2f | %4.1f%% | %10.2f "
               "| %5.2f | %6.1f | %8.2f | %8.2f |\n",
               r->label, r->n, 1e6 * t[T_CTC], 1e6 * t[T_CTC_PAPER], 1e6 * t[T_INV],
               1e6 * t[T_INV_PAPER], nodes, 1e6 * t[T_INV_FULL],
               saving(t[T_INV_PAPER], t[T_INV_FULL]), 1e6 * t[T_OPEN_CTC], t[T_CTC] / t[T_OPEN_CTC],
               1e9 * t[T_CTC] / r->n, 1e6 * t[T_OPEN_INV], 1e6 * t[T_OPEN_MOB]);
    }
    printf("\nProjection (ctc_loop_assemble, tol %g, from a drift of %g on every dependent chain "
           "coordinate and rate) against one DOPRI5 step (6 ctc evaluations), and "
           "the accuracy of what was timed:\n\n",
           PROJ_TOL, DRIFT);
    printf("| chain    |    n | mobility | cond (dependent) | projection (us) | Newton its | "
           "residual after (m) | 6 ctc (us) | projection / 6 ctc | f vs oracle | paper's f vs "
           "oracle | round trip | its floor | open round trip |\n");
    printf("| -------- | ---: | ---: | ---: | ---------: | ---: | ---: | ---------: | ----: | ---: "
           "| ---: | ---: | ---: | ---: |\n");
    for (int i = 0; i < nrows; i++) {
        const bench_row *r = &rows[i];
        const double *t = r->med;
        char oracle[16] = "-", paper[16] = "-";
        if (r->f_oracle >= 0) snprintf(oracle, sizeof oracle, "%7.1e", r->f_oracle);
        if (r->f_paper >= 0) snprintf(paper, sizeof paper, "%7.1e", r->f_paper);
        printf("| %-8s | %4d | %4d | %6.1e | %10.2f | %d | %7.1e | %10.2f | %5.1f%% | %7s | %7s | "
               "%7.1e | %7.1e | %7.1e |\n",
               r->label, r->n, r->mobility, r->cond, 1e6 * t[T_PROJ], r->iterations, r->res_after,
               6e6 * t[T_CTC], 100.0 * t[T_PROJ] / (6 * t[T_CTC]), oracle, paper, r->round_trip,
               r->floor, r->open_trip);
    }
}

int main(int argc, char **argv)
{
    int max_n = argc > 1 ? atoi(argv[1]) : 4096;
    int batches = argc > 2 ? atoi(argv[2]) : 31;
    if (max_n < 5 || batches < 1) {
        fprintf(stderr, "usage: bench_loop [max_n >= 5] [batches >= 1]\n");
        return 2;
    }
    printf("One CTC evaluation of a closed chain (one loop): ctc = kinematics + handles + iGDCA + "
           "GDCA, with the library's inverse (the open chain's composite pass and the closure) and "
           "with the paper's iGDCA, with and without its early stop; the same chain open for "
           "reference.\nMedians of %d interleaved batches; times in "
           "microseconds, per body in nanoseconds.\n\n",
           batches);
    static const int arch_n[] = {5, 16, 64, 256, 1024, 4096};
    static const int spatial_n[] = {5, 64, 256, 1024};
    bench_row rows[32];
    int nrows = 0;

    /* a case that fails is reported and left out; the run then ends with status 1 */
    int failed = 0;
    loop_scene *five = loop_scene_five_bar();
    if (bench_loop_case("five-bar", &five->spec, five->q0, batches, &rows[nrows]) == 0)
        nrows++;
    else
        failed = 1;
    free(five);
    for (size_t i = 0; i < sizeof arch_n / sizeof *arch_n && arch_n[i] <= max_n; i++) {
        test_loop *s = scene(test_loop_arch(arch_n[i]), "arch", arch_n[i]);
        if (bench_loop_case("arch", &s->spec, s->q0, batches, &rows[nrows]) == 0)
            nrows++;
        else
            failed = 1;
        test_loop_free(s);
    }
    for (size_t i = 1; i < sizeof arch_n / sizeof *arch_n && arch_n[i] <= max_n; i++) {
        test_loop *s = scene(test_loop_arch_spread(arch_n[i]), "arch spread", arch_n[i]);
        if (bench_loop_case("arch spread", &s->spec, s->q0, batches, &rows[nrows]) == 0)
            nrows++;
        else
            failed = 1;
        test_loop_free(s);
    }
    for (size_t i = 0; i < sizeof spatial_n / sizeof *spatial_n && spatial_n[i] <= max_n; i++) {
        test_loop *s = scene(test_loop_spatial(spatial_n[i], 11), "spatial", spatial_n[i]);
        if (bench_loop_case("spatial", &s->spec, s->q0, batches, &rows[nrows]) == 0)
            nrows++;
        else
            failed = 1;
        test_loop_free(s);
    }
    /* loops closed on a body: the same passes below an extra level of the tree */
    for (int i = 0; i < 3; i++) {
        const int spatial = i == 2, n = spatial ? 256 : i ? 1024 : 64;
        if (n > max_n) continue;
        const char *label = spatial ? "spatial on b" : "arch on b";
        test_loop *s = scene(spatial ? test_loop_spatial(n, 11) : test_loop_arch(n), label, n);
        char err[256];
        if (test_loop_close_on(s, spatial ? n / 8 : n / 4, err, sizeof err) != CTC_OK) {
            fprintf(stderr, "bench_loop: %s n = %d: %s\n", label, n, err);
            return 1;
        }
        if (bench_loop_case(label, &s->spec, s->q0, batches, &rows[nrows]) == 0)
            nrows++;
        else
            failed = 1;
        test_loop_free(s);
    }
    print_rows(rows, nrows);
    if (failed) return 1;
    return sink == 12345.678 ? 1 : 0;
}
