/*
 * test_gdca_parallel.c - the GDCA passes split over threads (gdca_par.h, pool.h,
 * ctc_data_set_threads) against the same passes on one thread.
 *
 * The oracle is the serial pass: splitting a tree height over threads must not change a single
 * bit of any result - accelerations, driving forces, joint loads, the assembled records - nor
 * which joint is reported singular. The forward pass is compared in the balanced tree's order
 * (options.h fwd_order), the one it splits; which order it takes by default on how many threads is
 * checked too. Each case runs a serial data and parallel data side by side
 * on the same random state: planar and spatial open chains of 1 to 1000 bodies (odd sizes,
 * powers of two and their neighbours), planar and spatial closed chains (loop models' roots stay
 * serial), on 2, 3 and 8 threads with every height split (grain 1) and with the measured grains.
 * The serial results themselves are checked against the oracles elsewhere (test_gdca_forward.c,
 * test_gdca_inverse.c, test_loop.c). Also: the pool's barrier in each of its waiting modes, the
 * first singular joint named as the serial pass names it, the thread setting's limits, the gate
 * that chooses between one thread and the split by measured cost (its decision from injected
 * timings; gated passes on 1 to 4 threads bitwise the serial ones of the order they took), and
 * whole simulations on one to three threads, the same to the forward pass's accuracy.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "chains.h"
#include "linalg.h"
#include "ctc.h"
#include "gdca_forward_seq.h"
#include "pool.h"
#include "sim.h"
#include "model_fixture.h"
#include "run_fixture.h"

/* ---- the pool ---- */

#define MAX_CHUNKS CTC_POOL_MAX_CHUNKS

/* a job of stages of given sizes: each chunk checks that every chunk of the earlier stages is
 * done and that it runs once */
typedef struct staged_job {
    int nstages, first[CTC_POOL_MAX_STAGES + 2]; /* first[nstages] = the number of chunks */
    atomic_int runs[MAX_CHUNKS];
    atomic_int done[MAX_CHUNKS];
    atomic_int early; /* chunks that started before their dependencies were done */
} staged_job;

static void staged_work(void *arg, int c)
{
    staged_job *j = arg;
    int s = 0;
    while (j->first[s + 1] <= c) s++;
    for (int i = 0; i < j->first[s]; i++) {
        if (!atomic_load(&j->done[i])) atomic_fetch_add(&j->early, 1);
    }
    atomic_fetch_add(&j->runs[c], 1);
    atomic_store(&j->done[c], 1);
}

/* runs a job of nstages stages of 1 + (s * 7) % width chunks 20 times */
static void check_staged(int nthreads, long spin_ns, long block_ns, int nstages, int width)
{
    staged_job *j = calloc(1, sizeof *j);
    cr_assert_not_null(j);
    j->nstages = nstages;
    for (int s = 0; s < nstages; s++) j->first[s + 1] = j->first[s] + 1 + (s * 7) % width;
    int n = j->first[nstages];
    cr_assert(n <= MAX_CHUNKS);
    ctc_pool *p = ctc_pool_new(nthreads);
    cr_assert_not_null(p);
    cr_assert_eq(ctc_pool_threads(p), nthreads);
    ctc_pool_set_wait(p, spin_ns, block_ns);
    ctc_pool_job job = {nstages, j->first, staged_work, j};
    for (int rep = 0; rep < 20; rep++) {
        for (int c = 0; c < n; c++) atomic_store(&j->done[c], 0);
        ctc_pool_run(p, &job);
        for (int c = 0; c < n; c++) {
            cr_assert_eq(atomic_load(&j->done[c]), 1, "%d threads: chunk %d not done", nthreads, c);
        }
    }
    for (int c = 0; c < n; c++) {
        cr_expect_eq(atomic_load(&j->runs[c]), 20, "%d threads: chunk %d ran %d times in 20 runs",
                     nthreads, c, atomic_load(&j->runs[c]));
    }
    cr_expect_eq(atomic_load(&j->early), 0, "%d threads, wait (%ld, %ld) ns: %d early starts",
                 nthreads, spin_ns, block_ns, atomic_load(&j->early));
    ctc_pool_free(p);
    free(j);
}

Test(gdca_parallel, pool_runs_every_chunk_once_after_its_stage_dependencies)
{
    check_staged(2, -1, 0, 40, 5);               /* the defaults */
    check_staged(3, 0, 0, 40, 9);                /* block at once */
    check_staged(2, 1000000, -1, 40, 3);         /* spin, never block */
    check_staged(8, 0, 50000, 30, 17);           /* yield, then block */
    check_staged(CTC_MAX_THREADS, -1, 0, 8, 64); /* more threads than cores */
    check_staged(4, -1, 0, CTC_POOL_MAX_STAGES, 2);
}

Test(gdca_parallel, pool_sizes_out_of_range_are_refused)
{
    cr_expect_null(ctc_pool_new(1));
    cr_expect_null(ctc_pool_new(0));
    cr_expect_null(ctc_pool_new(CTC_MAX_THREADS + 1));
    ctc_pool_free(NULL);
}

/* idle workers block between runs and wake for the next one; an empty job returns at once; a
 * job beyond the pool's capacity runs on the caller's thread */
Test(gdca_parallel, pool_runs_again_after_its_workers_have_blocked)
{
    staged_job *j = calloc(1, sizeof *j);
    cr_assert_not_null(j);
    j->nstages = 3;
    j->first[1] = 4, j->first[2] = 5, j->first[3] = 9;
    ctc_pool *p = ctc_pool_new(4);
    cr_assert_not_null(p);
    ctc_pool_set_wait(p, 1000, 2000);
    ctc_pool_job job = {3, j->first, staged_work, j}, empty = {0, j->first, staged_work, j};
    for (int run = 0; run < 3; run++) {
        for (int c = 0; c < 9; c++) atomic_store(&j->done[c], 0);
        ctc_pool_run(p, &job);
        ctc_pool_run(p, &empty);
        struct timespec nap = {0, 5000000}; /* 5 ms: every worker is blocked by now */
        nanosleep(&nap, NULL);
    }
    for (int c = 0; c < 9; c++) cr_expect_eq(atomic_load(&j->runs[c]), 3);
    cr_expect_eq(atomic_load(&j->early), 0);

    /* CTC_POOL_MAX_STAGES + 1 stages: too large for the pool */
    j->nstages = CTC_POOL_MAX_STAGES + 1;
    for (int s = 0; s < j->nstages; s++) j->first[s + 1] = j->first[s] + 1;
    cr_assert(j->first[j->nstages] <= MAX_CHUNKS);
    ctc_pool_job big = {j->nstages, j->first, staged_work, j};
    for (int c = 0; c < MAX_CHUNKS; c++) atomic_store(&j->runs[c], 0), atomic_store(&j->done[c], 0);
    ctc_pool_run(p, &big);
    for (int c = 0; c < j->nstages; c++) cr_expect_eq(atomic_load(&j->runs[c]), 1);
    cr_expect_eq(atomic_load(&j->early), 0);
    ctc_pool_free(p);
    free(j);
}

/* ---- the passes ---- */

/* everything one state's passes produce */
typedef struct outputs {
    double *qacc, *f, *fm;      /* (nvx) forward; composite (or loop) inverse; mobility inverse */
    double *qref, *fref;        /* (nvx) the reference form from u (gdca.h), its f_ref */
    double *load, *load_inv;    /* (njoints x dim) after the forward, the composite inverse */
    double *load_ref;           /* (njoints x dim) after the reference form */
    double *load_mob;           /* (njoints x dim) after the mobility inverse */
    int sing_f, sing_i, sing_m; /* d->singular_joint after each */
} outputs;

static outputs *outputs_new(const ctc_model *m)
{
    outputs *o = calloc(1, sizeof *o);
    size_t nvx = (size_t)m->nvx + 1, nl = (size_t)m->njoints * (size_t)m->dim;
    cr_assert_not_null(o);
    o->qacc = calloc(nvx, sizeof(double)), o->f = calloc(nvx, sizeof(double));
    o->fm = calloc(nvx, sizeof(double));
    o->qref = calloc(nvx, sizeof(double)), o->fref = calloc(nvx, sizeof(double));
    o->load_ref = calloc(nl, sizeof(double));
    cr_assert(o->qref && o->fref && o->load_ref);
    o->load = calloc(nl, sizeof(double)), o->load_inv = calloc(nl, sizeof(double));
    o->load_mob = calloc(nl, sizeof(double));
    cr_assert(o->qacc && o->f && o->fm && o->load && o->load_inv && o->load_mob);
    return o;
}

static void outputs_free(outputs *o)
{
    free(o->qacc), free(o->f), free(o->fm), free(o->load), free(o->load_inv), free(o->load_mob);
    free(o->qref), free(o->fref), free(o->load_ref);
    free(o);
}

/* the inverse passes on u, then the forward pass on tau, then the reference form from u on tau
   (a loop model: the forward pass again), at (q, v) */
static void run_passes(const ctc_model *m, ctc_data *d, const double *q, const double *v,
                       const double *u, const double *tau, outputs *o)
{
    size_t nl = (size_t)m->njoints * (size_t)m->dim * sizeof(double);
    ctc_kinematics(m, d, q, v);
    ctc_handles(m, d);
    ctc_gdca_inverse(m, d, u, o->f);
    o->sing_i = d->singular_joint;
    memcpy(o->load_inv, d->jnt_load_inv, nl);
    ctc_gdca_inverse_mobility(m, d, u, o->fm);
    o->sing_m = d->singular_joint;
    memcpy(o->load_mob, d->jnt_load_inv, nl);
    ctc_gdca_forward(m, d, tau, o->qacc);
    o->sing_f = d->singular_joint;
    memcpy(o->load, d->jnt_load, nl);
    ctc_gdca_inverse(m, d, u, o->fref);
    ctc_gdca_forward_from(m, d, tau, u, o->fref, o->qref);
    memcpy(o->load_ref, d->jnt_load, nl);
}

/* asserts bitwise equality of two arrays of count doubles */
static void expect_same(const double *serial, const double *par, size_t count, const char *what,
                        const char *label, int n, int threads, int grain)
{
    int same = memcmp(serial, par, count * sizeof(double)) == 0;
    size_t i = 0;
    while (!same && i < count && memcmp(&serial[i], &par[i], sizeof(double)) == 0) i++;
    cr_expect(same, "%s n = %d, %d threads, grain %d: %s differs first at [%zu] (%.17g vs %.17g)",
              label, n, threads, grain, what, i, i < count ? serial[i] : 0.0,
              i < count ? par[i] : 0.0);
}

static const int thread_counts[] = {2, 3, 8};
#define NTHREADS ((int)(sizeof thread_counts / sizeof thread_counts[0]))

/* Runs the passes at one random state on a serial data and on parallel data with every thread
 * count, every height split (grain 1) and with the measured grains, and compares every output
 * and record bit for bit. The serial results must be finite (a valid state). */
static void compare_on(const ctc_model *m, const double *q, const double *v, uint64_t seed,
                       const char *label)
{
    const int nvx = m->nvx, n = m->nbodies;
    double *u = calloc((size_t)nvx + 1, sizeof(double)),
           *tau = calloc((size_t)nvx + 1, sizeof(double));
    cr_assert(u && tau);
    uint64_t rng = seed;
    for (int i = 0; i < nvx; i++) u[i] = test_uniform(&rng, -2, 2);
    for (int i = 0; i < nvx; i++) tau[i] = test_uniform(&rng, -5, 5);

    ctc_data *ds = ctc_data_new(m);
    cr_assert_not_null(ds);
    ds->opt.fwd_order = CTC_ORDER_TREE;
    outputs *s = outputs_new(m), *p = outputs_new(m);
    run_passes(m, ds, q, v, u, tau, s);
    cr_assert(test_all_finite(s->qacc, nvx) && test_all_finite(s->f, nvx) &&
                  test_all_finite(s->fm, nvx),
              "%s n = %d: the serial results are not finite", label, n);
    cr_assert_eq(s->sing_f, -1);

    size_t nl = (size_t)m->njoints * (size_t)m->dim, nt = (size_t)m->ntree * (size_t)ds->hsize;
    size_t nc = (2 * (size_t)n - 1) * (size_t)ds->csize;
    for (int t = 0; t < NTHREADS; t++) {
        for (int g = 0; g < 2; g++) {
            int threads = thread_counts[t], grain = g ? 0 : 1;
            ctc_data *dp = ctc_data_new(m);
            cr_assert_not_null(dp);
            cr_assert_eq(ctc_data_set_threads(dp, threads, NULL, 0), CTC_OK);
            dp->opt.par_grain = grain;
            dp->opt.fwd_order = CTC_ORDER_TREE;
            for (int rep = 0; rep < 2; rep++) { /* the second time on warm workers */
                run_passes(m, dp, q, v, u, tau, p);
                expect_same(s->qacc, p->qacc, (size_t)nvx, "qacc", label, n, threads, grain);
                expect_same(s->f, p->f, (size_t)nvx, "f", label, n, threads, grain);
                expect_same(s->fm, p->fm, (size_t)nvx, "f (mobility)", label, n, threads, grain);
                expect_same(s->load, p->load, nl, "jnt_load", label, n, threads, grain);
                expect_same(s->qref, p->qref, (size_t)nvx, "qacc (reference form)", label, n,
                            threads, grain);
                expect_same(s->load_ref, p->load_ref, nl, "jnt_load (reference form)", label, n,
                            threads, grain);
                expect_same(s->load_inv, p->load_inv, nl, "jnt_load_inv", label, n, threads, grain);
                expect_same(s->load_mob, p->load_mob, nl, "jnt_load_inv (mobility)", label, n,
                            threads, grain);
                expect_same(ds->hfwd, dp->hfwd, nt, "hfwd", label, n, threads, grain);
                expect_same(ds->hinv, dp->hinv, nt, "hinv", label, n, threads, grain);
                expect_same(ds->icomp, dp->icomp, nc, "icomp", label, n, threads, grain);
                cr_expect_eq(p->sing_f, s->sing_f);
                cr_expect_eq(p->sing_i, s->sing_i);
                cr_expect_eq(p->sing_m, s->sing_m);
            }
            /* grain 1 splits every height of two nodes or more: the pool must have started */
            if (grain == 1 && m->ntree >= 2) {
                cr_expect_not_null(dp->pool, "%s n = %d: no pool", label, n);
            }
            ctc_data_free(dp);
        }
    }
    outputs_free(s), outputs_free(p);
    ctc_data_free(ds);
    free(u), free(tau);
}

/* an open chain at a random state */
static void compare_open(test_chain *c, uint64_t seed, const char *label)
{
    ctc_model *m = build(&c->spec);
    double *q = calloc((size_t)m->nq, sizeof(double)), *v = calloc((size_t)m->nv, sizeof(double));
    cr_assert(q && v);
    uint64_t rng = seed;
    test_random_state(m, &rng, 2.0, q, v);
    compare_on(m, q, v, seed + 1, label);
    free(q), free(v);
    ctc_model_free(m);
    test_chain_free(c);
}

static const int sizes[] = {1,   2,   3,   4,   5,   6,   7,   8,   9,   13,  16,
                            17,  31,  32,  33,  63,  64,  65,  100, 127, 128, 129,
                            255, 256, 257, 333, 511, 512, 513, 777, 999, 1000};
#define NSIZES ((int)(sizeof sizes / sizeof sizes[0]))

Test(gdca_parallel, planar_chains_give_bitwise_the_serial_results_on_any_threads, .timeout = 300)
{
    for (int i = 0; i < NSIZES; i++) {
        compare_open(test_chain_random_planar(sizes[i], 300 + (uint64_t)i, i % 2, i % 3 == 0),
                     40 + (uint64_t)i, "planar");
    }
}

Test(gdca_parallel, spatial_chains_give_bitwise_the_serial_results_on_any_threads, .timeout = 300)
{
    for (int i = 0; i < NSIZES; i++) {
        compare_open(test_chain_random_spatial(sizes[i], 500 + (uint64_t)i, TEST_ALL_JOINTS),
                     60 + (uint64_t)i, "spatial");
    }
}

/* ---- closed chains ---- */

/* A loop on a random revolute chain of n bodies, closed at a random q0: planar rods closed by a
 * revolute joint (joints n/2, n-1 and the closing one dependent, mobility n - 2) or spatial
 * bodies closed by a spherical joint (joints n/4, n/2, 3n/4 and the closing one dependent,
 * mobility n - 3). The anchor is where the tip's closing point is at q0: on the ground, or with
 * on_body on body n/3 (planar) or n/8 (spatial), before the first dependent joint. */
typedef struct loop_chain {
    test_chain *c;
    ctc_loop_spec loop;
    unsigned char *independent;
    double *q0;
} loop_chain;

static loop_chain *loop_chain_new(int n, int spatial, int on_body, uint64_t seed)
{
    loop_chain *l = calloc(1, sizeof *l);
    cr_assert_not_null(l);
    l->c = spatial ? test_chain_random_spatial(n, seed, 1u << CTC_JOINT_REVOLUTE)
                   : test_chain_random_planar(n, seed, 0, 1);
    l->independent = calloc((size_t)n + 1, 1);
    l->q0 = calloc((size_t)n, sizeof(double));
    cr_assert(l->independent && l->q0);
    memset(l->independent, 1, (size_t)n);
    if (spatial) {
        l->loop.joint = (ctc_joint_spec){.type = CTC_JOINT_SPHERICAL, .location = {0.1, 0.2, 0.3}};
        l->independent[n / 4] = l->independent[n / 2] = l->independent[3 * n / 4] = 0;
    } else {
        l->loop.joint = (ctc_joint_spec){
            .type = CTC_JOINT_REVOLUTE, .axis = {0, 0, 1}, .location = {0.3, -0.4, 0}};
        l->independent[n / 2] = l->independent[n - 1] = 0;
    }
    uint64_t rng = seed;
    for (int k = 0; k < n; k++) l->q0[k] = test_uniform(&rng, -1, 1);

    /* the anchor: where the loop's kinematics put the tip's closing point at q0 */
    l->c->spec.loop = &l->loop;
    l->c->spec.independent = l->independent;
    const int b = on_body ? (spatial ? n / 8 : n / 3) : -1;
    char err[256] = "";
    cr_assert_eq(test_loop_anchor(&l->c->spec, l->q0, b, l->loop.anchor, err, sizeof err), CTC_OK,
                 "%s", err);
    if (on_body) { /* the anchor is in body b's frame */
        l->loop.on_body = 1;
        l->loop.body = b;
    }
    return l;
}

static void loop_chain_free(loop_chain *l)
{
    test_chain_free(l->c);
    free(l->independent), free(l->q0), free(l);
}

static void compare_loop(int n, int spatial, int on_body, uint64_t seed)
{
    loop_chain *l = loop_chain_new(n, spatial, on_body, seed);
    ctc_model *m = build(&l->c->spec);
    cr_assert(m->has_loop);
    cr_assert_eq(m->loop_body, on_body ? (spatial ? n / 8 : n / 3) : -1);
    {
        ctc_data *d = ctc_data_new(m);
        double *zero = calloc((size_t)m->nv, sizeof(double)), pos, vel;
        cr_assert(d && zero);
        ctc_kinematics(m, d, l->q0, zero);
        ctc_loop_residual_norms(m, d, &pos, &vel);
        cr_assert_leq(pos, 1e-12 * n, "n = %d: the loop is open at q0 by %g", n, pos);
        free(zero);
        ctc_data_free(d);
    }
    cr_assert_eq(m->form, spatial ? CTC_FORM_SPATIAL : CTC_FORM_PLANAR);
    double *v = calloc((size_t)m->nv, sizeof(double));
    cr_assert_not_null(v);
    uint64_t rng = seed + 7;
    for (int i = 0; i < m->nv; i++) v[i] = test_uniform(&rng, -1, 1);
    compare_on(m, l->q0, v, seed + 9, spatial ? "spatial loop" : "planar loop");
    free(v);
    ctc_model_free(m);
    loop_chain_free(l);
}

Test(gdca_parallel, loops_give_bitwise_the_serial_results_on_any_threads, .timeout = 300)
{
    static const int planar[] = {5, 6, 17, 64, 257, 1000}, spatial[] = {5, 16, 129, 1000};
    for (int i = 0; i < 6; i++) compare_loop(planar[i], 0, 0, 700 + (uint64_t)i);
    for (int i = 0; i < 4; i++) compare_loop(spatial[i], 1, 0, 800 + (uint64_t)i);
}

Test(gdca_parallel, loops_closed_on_a_body_give_bitwise_the_serial_results_on_any_threads,
     .timeout = 300)
{
    static const int planar[] = {5, 17, 257, 1000}, spatial[] = {5, 16, 129, 1000};
    for (int i = 0; i < 4; i++) compare_loop(planar[i], 0, 1, 720 + (uint64_t)i);
    for (int i = 0; i < 4; i++) compare_loop(spatial[i], 1, 1, 820 + (uint64_t)i);
}

/* The paper's loop iGDCA (ctc_gdca_inverse_mobility, the form with the early stop;
 * d->opt.inv_full = 1 turns the stop off) gives bitwise the serial forces and loads on threads,
 * with and without the stop, and the stop does not change the forces beyond rounding. */
Test(gdca_parallel, the_early_stop_of_a_loops_inverse_pass_is_kept_on_threads)
{
    loop_chain *l = loop_chain_new(200, 0, 0, 901);
    ctc_model *m = build(&l->c->spec);
    ctc_data *ds = ctc_data_new(m), *dp = ctc_data_new(m);
    double *v = calloc((size_t)m->nv, sizeof(double));
    double *u = calloc((size_t)m->nvx, sizeof(double)),
           *fs = calloc((size_t)m->nvx, sizeof(double));
    double *fp = calloc((size_t)m->nvx, sizeof(double)),
           *f0 = calloc((size_t)m->nvx, sizeof(double));
    cr_assert(ds && dp && v && u && fs && fp && f0);
    uint64_t rng = 5;
    for (int i = 0; i < m->nvx; i++) u[i] = test_uniform(&rng, -1, 1);
    for (int i = 0; i < m->nv; i++) v[i] = test_uniform(&rng, -1, 1);
    cr_assert_eq(ctc_data_set_threads(dp, 2, NULL, 0), CTC_OK);
    dp->opt.par_grain = 1;
    for (int full = 0; full < 2; full++) {
        ds->opt.inv_full = dp->opt.inv_full = full;
        ctc_kinematics(m, ds, l->q0, v), ctc_handles(m, ds);
        ctc_kinematics(m, dp, l->q0, v), ctc_handles(m, dp);
        ctc_gdca_inverse_mobility(m, ds, u, fs);
        ctc_gdca_inverse_mobility(m, dp, u, fp);
        cr_assert_eq(ds->singular_joint, -1);
        cr_expect_eq(memcmp(fs, fp, (size_t)m->nvx * sizeof(double)), 0, "inv_full = %d", full);
        cr_expect_eq(memcmp(ds->jnt_load_inv, dp->jnt_load_inv,
                            (size_t)m->njoints * (size_t)m->dim * sizeof(double)),
                     0, "inv_full = %d", full);
        if (full) {
            cr_expect(test_rel_err(fs, f0, m->nvx) < 1e-9, "the stop moved f by %.3g",
                      test_rel_err(fs, f0, m->nvx));
        } else { /* the stop happened: on fresh data, joints it did not reach have no load */
            memcpy(f0, fs, (size_t)m->nvx * sizeof(double));
            int unreached = 0;
            for (int k = 0; k < m->njoints; k++) {
                int zero = 1;
                for (int i = 0; i < m->dim; i++) zero &= ds->jnt_load_inv[m->dim * k + i] == 0.0;
                unreached += zero;
            }
            cr_expect_gt(unreached, 0, "the pruned disassembly reached every joint");
        }
    }
    free(v), free(u), free(fs), free(fp), free(f0);
    ctc_data_free(ds), ctc_data_free(dp);
    ctc_model_free(m);
    loop_chain_free(l);
}

/* ---- the first singular joint ---- */

/* The joint the serial pass names when the records of the bodies in bad[] are NaN: the first
 * node in tree order (children before parents) with one of them inside - every node above a NaN
 * body fails too. From the tree alone. */
static int expected_singular(const ctc_model *m, const int *bad, int nbad)
{
    for (int i = 0; i < m->ntree; i++) {
        for (int b = 0; b < nbad; b++) {
            if (bad[b] >= m->tree[i].first && bad[b] <= m->tree[i].last) return m->tree[i].joint;
        }
    }
    return 0; /* a single body: the ground joint */
}

/* The joint the sequential order (gdca_forward_seq.c) names for the same NaN bodies: the lowest
 * joint whose K reads them. With r = (n - 1) / 2 the root joint, that is the lowest NaN body
 * below r (its base-run joint; the joints below it read only finite bodies), else r itself (the
 * tip run's joints are all above r). */
static int expected_singular_seq(const ctc_model *m, const int *bad, int nbad)
{
    const int r = (m->nbodies - 1) / 2;
    int want = r;
    for (int b = 0; b < nbad; b++) {
        if (bad[b] < want) want = bad[b];
    }
    return want;
}

Test(gdca_parallel, the_first_singular_joint_is_the_serial_passes_whatever_the_threads)
{
    test_chain *c = test_chain_random_spatial(300, 17, TEST_ALL_JOINTS);
    ctc_model *m = build(&c->spec);
    double *q = calloc((size_t)m->nq, sizeof(double)), *v = calloc((size_t)m->nv, sizeof(double));
    double *x = calloc((size_t)m->nv, sizeof(double)), *y = calloc((size_t)m->nv, sizeof(double));
    cr_assert(q && v && x && y);
    uint64_t rng = 3;
    test_random_state(m, &rng, 1.0, q, v);
    /* the passes run on the merged bodies (model.h "merged bodies"): their records are poisoned,
       the cases spread over them as over the 300 bodies, and the joint named is the model's */
    const ctc_model *pm = m->dyn != NULL ? m->dyn : m;
    cr_assert_gt(pm->nbodies, 200);
    /* NaN bodies in different threads' chunks, the later one alone, at a leaf and deeper */
    static const int given[][2] = {{250, 20}, {299, 151}, {150, 149}, {7, 7}, {0, 298}, {148, 5}};
    for (int k = 0; k < 6; k++) {
        int bad[2];
        for (int b = 0; b < 2; b++) bad[b] = given[k][b] * (pm->nbodies - 1) / 299;
        int want = expected_singular(pm, bad, 2);
        if (m->dyn != NULL) want = m->dyn_body[want];
        for (int threads = 0; threads <= 8; threads++) { /* 0: one thread, the sequential order */
            ctc_data *d = ctc_data_new(m);
            cr_assert_not_null(d);
            cr_assert_eq(ctc_data_set_threads(d, threads > 0 ? threads : 1, NULL, 0), CTC_OK);
            d->opt.par_grain = 1;
            d->opt.fwd_order = threads > 0 ? CTC_ORDER_TREE : CTC_ORDER_SEQ;
            ctc_kinematics(m, d, q, v);
            ctc_handles(m, d);
            ctc_data *pd = m->dyn != NULL ? d->dyn : d;
            for (int b = 0; b < 2; b++) {
                double *h = pd->hbody + (size_t)bad[b] * pd->hsize;
                for (int i = 0; i < pd->hsize; i++) h[i] = NAN;
            }
            ctc_gdca_forward(m, d, x, y);
            int want_f = threads > 0 ? want : expected_singular_seq(pm, bad, 2);
            if (threads == 0 && m->dyn != NULL) want_f = m->dyn_body[want_f];
            cr_expect_eq(d->singular_joint, want_f, "forward, bodies %d and %d, %d threads: %d",
                         bad[0], bad[1], threads, d->singular_joint);
            ctc_gdca_inverse_mobility(m, d, x, y);
            cr_expect_eq(d->singular_joint, want, "mobility, bodies %d and %d, %d threads: %d",
                         bad[0], bad[1], threads, d->singular_joint);
            ctc_data_free(d);
        }
    }
    free(q), free(v), free(x), free(y);
    ctc_model_free(m);
    test_chain_free(c);
}

/* ---- the forward pass's order ---- */

/* chains of n bodies, planar rods or spatial revolute */
static ctc_model *order_model(int n, int spatial)
{
    test_chain *c = spatial ? test_chain_random_spatial(n, 5, 1u << CTC_JOINT_REVOLUTE)
                            : test_chain_random_planar(n, 5, 0, 1);
    ctc_model *m = build(&c->spec);
    test_chain_free(c);
    return m;
}

/* By default (CTC_ORDER_AUTO) an open chain's forward pass takes the sequential order on one
 * thread at any length; on two threads or more it may take the tree from 2048 planar or 512
 * spatial bodies (gdca_forward.c), where the gate chooses by measured cost; before any pass the
 * order is the sequential one; a shared pool's owner's count decides; loop models take the tree
 * always; the setting overrides the rule for open chains. */
Test(gdca_parallel, the_forward_pass_may_take_the_tree_on_threads_only_from_the_least_length)
{
    static const struct {
        int n, spatial, threads, candidate;
    } cases[] = {{2, 0, 1, 0},    {4095, 0, 1, 0}, {8192, 0, 1, 0}, {2047, 0, 2, 0},
                 {2048, 0, 2, 1}, {4096, 0, 8, 1}, {511, 1, 2, 0},  {511, 1, 64, 0},
                 {512, 1, 2, 1},  {1024, 1, 1, 0}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ctc_model *m = order_model(cases[i].n, cases[i].spatial);
        ctc_data *d = ctc_data_new(m), *owner = ctc_data_new(m);
        cr_assert(d && owner);
        cr_assert_eq(ctc_data_set_threads(d, cases[i].threads, NULL, 0), CTC_OK);
        cr_expect_eq(gdca_forward_tree_candidate(m, d), cases[i].candidate, "n = %d %s, %d threads",
                     cases[i].n, cases[i].spatial ? "spatial" : "planar", cases[i].threads);
        cr_expect_eq(gdca_forward_order_seq(m, d), 1, "no pass yet: the sequential order");
        d->fwd_split = 1; /* as the gate would set it */
        cr_expect_eq(gdca_forward_order_seq(m, d), !cases[i].candidate);
        d->opt.fwd_order = CTC_ORDER_TREE;
        cr_expect_eq(gdca_forward_tree_candidate(m, d), 0, "told the order: no gate");
        cr_expect_eq(gdca_forward_order_seq(m, d), 0);
        d->opt.fwd_order = CTC_ORDER_SEQ;
        cr_expect_eq(gdca_forward_order_seq(m, d), 1);
        /* a data that uses another's pool goes by the owner's count */
        d->opt.fwd_order = CTC_ORDER_AUTO;
        cr_assert_eq(ctc_data_set_threads(d, 1, NULL, 0), CTC_OK);
        cr_assert_eq(ctc_data_set_threads(owner, cases[i].threads, NULL, 0), CTC_OK);
        ctc_data_share_pool(d, owner);
        cr_expect_eq(gdca_forward_tree_candidate(m, d), cases[i].candidate);
        ctc_data_free(d), ctc_data_free(owner);
        ctc_model_free(m);
    }
    loop_chain *l = loop_chain_new(17, 0, 0, 33);
    ctc_model *m = build(&l->c->spec);
    ctc_data *d = ctc_data_new(m);
    cr_assert_not_null(d);
    d->opt.fwd_order = CTC_ORDER_SEQ;
    cr_expect_eq(gdca_forward_order_seq(m, d), 0, "a loop model takes the tree");
    ctc_data_free(d);
    ctc_model_free(m);
    loop_chain_free(l);
}

/* ---- the gate: alone or split by measured cost ---- */

/* The decision is the medians' comparison with the margin, from the timings alone: the same
 * timings in any order give the same answer, one outlier does not move it, and without timings
 * of both ways it stays alone. */
Test(gdca_parallel, the_gate_decides_from_injected_timings_by_their_medians)
{
    const double alone[6] = {1.0, 1.1, 0.9, 1.0, 5.0, 1.0};
    const double faster[6] = {0.90, 0.80, 0.94, 9.00, 0.85, 0.93}; /* median 0.915 */
    const double level[6] = {0.97, 0.96, 0.98, 0.90, 1.20, 0.99};  /* median 0.975 > 0.95 */
    const double reordered[6] = {0.93, 0.85, 9.00, 0.94, 0.80, 0.90};
    cr_expect_eq(ctc_pool_gate_choose(alone, 6, faster, 6), 1);
    cr_expect_eq(ctc_pool_gate_choose(alone, 6, reordered, 6), 1, "order does not matter");
    cr_expect_eq(ctc_pool_gate_choose(alone, 6, level, 6), 0, "within the margin: alone");
    cr_expect_eq(ctc_pool_gate_choose(faster, 6, alone, 6), 0, "split slower: alone");
    cr_expect_eq(ctc_pool_gate_choose(alone, 0, faster, 6), 0, "no timings alone");
    cr_expect_eq(ctc_pool_gate_choose(alone, 6, faster, 0), 0, "no timings split");
    const double a2[2] = {1.0, 2.0}, s2[2] = {1.3, 1.5}; /* medians 1.5 and 1.4: 1.4 < 1.425 */
    cr_expect_eq(ctc_pool_gate_choose(a2, 2, s2, 2), 1, "even counts: the middle two's mean");
}

/* Fed timings by way (the clock left out), a gate alternates blocks of CTC_POOL_GATE_BLOCK runs
 * of each way as ABBA, leaves the first run of each block out (here the faster way's first runs
 * are made slow, as a run after a change of way can be), so that both ways get
 * CTC_POOL_GATE_SAMPLES timings, takes the faster way, keeps it for CTC_POOL_GATE_RECHECK runs
 * and then measures again. */
Test(gdca_parallel, the_gate_alternates_then_keeps_the_faster_way_and_rechecks)
{
    enum { RUNS = 2 * CTC_POOL_GATE_SAMPLES / (CTC_POOL_GATE_BLOCK - 1) * CTC_POOL_GATE_BLOCK };
    for (int faster = 0; faster < 2; faster++) {
        ctc_pool_gate g = {0};
        int count[2] = {0, 0}, runs = 0, last = -1;
        while (!g.decided) {
            int way = ctc_pool_gate_way(&g);
            const int first = g.runs % CTC_POOL_GATE_BLOCK == 0;
            cr_assert(first || way == last, "run %d: a block keeps its way", runs);
            last = way;
            count[way]++;
            ctc_pool_gate_record(&g, way, way == faster ? (first ? 1.0 : 1e-3) : 2e-3);
            cr_assert(++runs < 100);
        }
        cr_expect_eq(runs, RUNS, "blocks of one way, their first runs left out");
        cr_expect_eq(count[0], count[1]);
        cr_expect_eq(g.way, faster);
        for (int k = 1; k < CTC_POOL_GATE_RECHECK; k++) {
            cr_assert_eq(ctc_pool_gate_way(&g), faster);
            ctc_pool_gate_record(&g, faster, 1e-3 * (1 + k % 3 * 0.01)); /* as measured */
        }
        cr_expect(g.decided);
        ctc_pool_gate_record(&g, faster, 1e-3);
        cr_expect(!g.decided, "measures again after the recheck count");
        cr_expect_eq(ctc_pool_gate_way(&g), 0);
    }
}

/* A split the gate decided on is watched: once the median of its latest timings no longer beats
 * the timings alone by the margin, the gate runs alone until the recheck count, then measures
 * again; one slow run among fast ones does not move it. A decision alone is kept whatever its
 * timings, until the recheck count. */
Test(gdca_parallel, the_gate_drops_a_split_that_stops_paying)
{
    for (int faster = 0; faster < 2; faster++) {
        ctc_pool_gate g = {0};
        while (!g.decided) {
            int way = ctc_pool_gate_way(&g);
            ctc_pool_gate_record(&g, way, way == faster ? 1e-3 : 2e-3);
        }
        cr_assert_eq(g.way, faster);
        ctc_pool_gate_record(&g, faster, 9e-3); /* one outlier */
        cr_expect(g.decided && g.way == faster, "one slow run does not move it");
        int runs = 0;
        while (g.decided && g.way == faster && runs < CTC_POOL_GATE_SAMPLES + 2) {
            ctc_pool_gate_record(&g, faster, 4e-3); /* the decided way is now the slower */
            runs++;
        }
        if (faster == 1) {
            cr_expect(g.decided && g.way == 0, "a split that stopped paying is dropped");
            cr_expect_leq(runs, CTC_POOL_GATE_SAMPLES / 2 + 1, "within half its samples");
            for (int k = 1; k < CTC_POOL_GATE_RECHECK; k++) {
                cr_assert_eq(ctc_pool_gate_way(&g), 0, "alone until the recheck");
                ctc_pool_gate_record(&g, 0, 1e-3); /* alone's timings are not looked at */
            }
            ctc_pool_gate_record(&g, 0, 1e-3);
            cr_expect(!g.decided, "then it measures again");
        } else {
            cr_expect(g.decided && g.way == 0, "alone is kept whatever its timings");
        }
    }
}

/* With the gate on (no forced split), a pass on 1 to 4 threads gives, run after run while the
 * gate measures and after it decides, bitwise the serial results: the composite inverse always,
 * the forward pass those of one of its two orders (the sequential one of one thread, or the
 * balanced tree) - the gate may pick either. */
Test(gdca_parallel, gated_passes_give_bitwise_the_serial_results_on_1_to_4_threads, .timeout = 120)
{
    for (int spatial = 0; spatial < 2; spatial++) {
        ctc_model *m = order_model(spatial ? 512 : 2048, spatial);
        const size_t nv = (size_t)m->nv, bytes = nv * sizeof(double);
        double *q = calloc(nv, sizeof(double)), *v = calloc(nv, sizeof(double));
        double *u = calloc(nv, sizeof(double)), *f1 = calloc(nv, sizeof(double));
        double *fk = calloc(nv, sizeof(double)), *aseq = calloc(nv, sizeof(double));
        double *atree = calloc(nv, sizeof(double)), *ak = calloc(nv, sizeof(double));
        ctc_data *ds = ctc_data_new(m), *dt = ctc_data_new(m), *dk[4] = {0};
        cr_assert(q && v && u && f1 && fk && aseq && atree && ak && ds && dt);
        dt->opt.fwd_order = CTC_ORDER_TREE;
        for (int k = 1; k < 4; k++) {
            dk[k] = ctc_data_new(m);
            cr_assert_not_null(dk[k]);
            cr_assert_eq(ctc_data_set_threads(dk[k], k + 1, NULL, 0), CTC_OK);
        }
        uint64_t rng = 77;
        for (int run = 0; run < 40; run++) {
            test_random_state(m, &rng, 1.0, q, v);
            for (size_t i = 0; i < nv; i++) u[i] = test_uniform(&rng, -1, 1);
            ctc_data *ref[2] = {ds, dt};
            for (int r = 0; r < 2; r++) {
                ctc_kinematics(m, ref[r], q, v);
                ctc_handles(m, ref[r]);
            }
            ctc_gdca_inverse(m, ds, u, f1);
            ctc_gdca_forward(m, ds, f1, aseq);
            ctc_gdca_forward(m, dt, f1, atree);
            for (int k = 1; k < 4; k++) {
                ctc_kinematics(m, dk[k], q, v);
                ctc_handles(m, dk[k]);
                ctc_gdca_inverse(m, dk[k], u, fk);
                cr_expect_eq(memcmp(fk, f1, bytes), 0, "%s run %d, %d threads: inverse",
                             spatial ? "spatial" : "planar", run, k + 1);
                ctc_gdca_forward(m, dk[k], f1, ak);
                cr_expect(memcmp(ak, dk[k]->fwd_split ? atree : aseq, bytes) == 0,
                          "%s run %d, %d threads: forward (%s order)",
                          spatial ? "spatial" : "planar", run, k + 1,
                          dk[k]->fwd_split ? "tree" : "sequential");
            }
        }
        for (int k = 1; k < 4; k++) {
            cr_expect(dk[k]->eval.gate.decided, "the evaluation gate has decided");
            ctc_data_free(dk[k]);
        }
        ctc_data_free(ds), ctc_data_free(dt);
        free(q), free(v), free(u), free(f1), free(fk), free(aseq), free(atree), free(ak);
        ctc_model_free(m);
    }
}

/* The gate weighs whole evaluations (data.h ctc_eval_gate): ctc_kinematics starts one, every
 * gated pass in it takes its way (the forward order too), an evaluation with no pass that could
 * split is not timed, a forced split does not ask, and a model with merged bodies (fixed joints)
 * times its reduced model's passes in its own gate. */
Test(gdca_parallel, the_gate_weighs_whole_evaluations_and_their_passes_share_its_way)
{
    for (int merged = 0; merged < 2; merged++) {
        test_chain *c = test_chain_random_spatial(1024, 5, 1u << CTC_JOINT_REVOLUTE);
        if (merged) { /* every 8th joint fixed: bodies merge into their parents (model.h) */
            for (int k = 8; k < c->spec.nbodies; k += 8) c->joints[k].type = CTC_JOINT_FIXED;
        }
        ctc_model *m = build(&c->spec);
        test_chain_free(c);
        cr_assert_eq(m->dyn != NULL, merged);
        const size_t nv = (size_t)m->nv;
        double *q = calloc(nv, sizeof(double)), *v = calloc(nv, sizeof(double));
        double *u = calloc(nv, sizeof(double)), *f = calloc(nv, sizeof(double));
        double *a = calloc(nv, sizeof(double));
        ctc_data *d = ctc_data_new(m);
        cr_assert(q && v && u && f && a && d);
        cr_assert_eq(ctc_data_set_threads(d, 2, NULL, 0), CTC_OK);
        uint64_t rng = 5;
        test_random_state(m, &rng, 1.0, q, v);
        for (int e = 0; e < 4 * CTC_POOL_GATE_SAMPLES; e++) {
            const long runs = d->eval.gate.runs;
            const int decided = d->eval.gate.decided;
            ctc_kinematics(m, d, q, v); /* a kinematics-only evaluation: not timed */
            ctc_kinematics(m, d, q, v);
            cr_expect_eq(d->eval.gate.runs, runs, "evaluation %d: only kinematics", e);
            const int way = d->eval.split;
            cr_expect_eq(way, ctc_pool_gate_way(&d->eval.gate));
            ctc_handles(m, d);
            ctc_gdca_inverse(m, d, u, f);
            cr_expect_eq(d->eval.gated, 1, "evaluation %d: the inverse asked the way", e);
            ctc_gdca_forward(m, d, f, a);
            cr_expect_eq(d->fwd_split, way, "evaluation %d: the forward order is its way", e);
            cr_expect(d->eval.t1 >= d->eval.t0);
            ctc_kinematics(m, d, q, v); /* records it */
            if (!decided) cr_expect_eq(d->eval.gate.runs, d->eval.gate.decided ? 0 : runs + 1);
        }
        cr_expect(d->eval.gate.decided, "decided after %d evaluations", 4 * CTC_POOL_GATE_SAMPLES);
        /* a forced split neither asks nor marks */
        d->opt.par_split = 1;
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_inverse(m, d, u, f);
        ctc_gdca_forward(m, d, f, a);
        cr_expect_eq(d->eval.gated, 0, "forced: not timed");
        cr_expect_eq(d->fwd_split, 1, "forced: the tree split");
        ctc_data_free(d);
        free(q), free(v), free(u), free(f), free(a);
        ctc_model_free(m);
    }
}

/* ---- the setting ---- */

Test(gdca_parallel, thread_counts_out_of_range_are_refused_with_the_range)
{
    test_chain *c = test_chain_rod_pendulum(4, 1, 1);
    ctc_model *m = build(&c->spec);
    ctc_data *d = ctc_data_new(m);
    char err[128] = "";
    cr_assert_eq(ctc_data_set_threads(d, 0, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "threads must be 1 to 64 (got 0)");
    cr_assert_eq(ctc_data_set_threads(d, 65, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "threads must be 1 to 64 (got 65)");
    cr_expect_eq(d->threads, 1, "a refused count changes nothing");
    cr_expect_eq(ctc_data_set_threads(d, 64, NULL, 0), CTC_OK);
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
}

/* a data that shares another's workers runs on them and gives the serial results */
Test(gdca_parallel, a_shared_pool_serves_two_data_in_turn)
{
    test_chain *c = test_chain_random_planar(400, 77, 0, 0);
    ctc_model *m = build(&c->spec);
    ctc_data *owner = ctc_data_new(m), *user = ctc_data_new(m), *serial = ctc_data_new(m);
    double *q = calloc((size_t)m->nq, sizeof(double)), *v = calloc((size_t)m->nv, sizeof(double));
    double *f = calloc((size_t)m->nv, sizeof(double)), *a1 = calloc((size_t)m->nv, sizeof(double));
    double *a2 = calloc((size_t)m->nv, sizeof(double));
    cr_assert(owner && user && serial && q && v && f && a1 && a2);
    uint64_t rng = 9;
    test_random_state(m, &rng, 1.0, q, v);
    for (int i = 0; i < m->nv; i++) f[i] = test_uniform(&rng, -1, 1);
    cr_assert_eq(ctc_data_set_threads(owner, 2, NULL, 0), CTC_OK);
    ctc_data_share_pool(user, owner);
    user->opt.par_grain = 1;
    ctc_data *both[3] = {serial, user, owner};
    for (int k = 0; k < 3; k++) {
        both[k]->opt.fwd_order = CTC_ORDER_TREE;
        ctc_kinematics(m, both[k], q, v);
        ctc_handles(m, both[k]);
    }
    ctc_gdca_forward(m, serial, f, a1);
    ctc_gdca_forward(m, user, f, a2);
    cr_expect_eq(memcmp(a1, a2, (size_t)m->nv * sizeof(double)), 0);
    cr_expect_null(user->pool, "the user starts no pool of its own");
    cr_expect_not_null(owner->pool, "the owner's pool did the work");
    ctc_data_free(user);
    ctc_data_free(owner);
    ctc_data_free(serial);
    free(q), free(v), free(f), free(a1), free(a2);
    ctc_model_free(m);
    test_chain_free(c);
}

/* ---- whole simulations ---- */

#define SIM_N                                                                                      \
    4096 /* long enough for both passes to split by default, and for the forward pass to take      \
            the tree on threads (gdca_forward.c, gdca_inverse.c) */

/* a PD run of SIM_N-link rod pendulum from q0_k = +-pi/6 to rest, RK4, 50 steps */
static ctc_sim_result *pendulum_run(int threads, double mass_scale)
{
    test_chain *c = test_chain_rod_pendulum(SIM_N, 0.1, 0.1);
    ctc_sim_result *r = fixture_pd_to_rest(c, 0.5235987755982988, mass_scale,
                                           (ctc_integ_spec){.method = CTC_INTEG_RK4, .step = 1e-3},
                                           0.05, 0.01, threads);
    test_chain_free(c);
    return r;
}

/* the largest difference of two runs' samples of channel ch, relative to the largest sample */
static double run_difference(const ctc_sim_result *a, const ctc_sim_result *b, ctc_channel ch)
{
    double diff, big;
    fixture_channel_diff(a, b, ch, &diff, &big);
    return diff > 0 ? diff / big : 0.0;
}

/* One, two and three threads record the same samples to the forward pass's accuracy on a chain
 * this long: the forward pass takes the sequential order on one thread and, on more, whichever
 * of it and the split tree the gate measures faster, evaluation by evaluation while the gate
 * measures; each order's accelerations are off the exact ones by up to about 2e-5 at n = 4096
 * (the round trip on uniform rods, bench/NOTEBOOK.md "Hard cases"), and the runs differ by up to
 * 3e-6 of the largest sample (qdot, tau, energy; q by 2e-7). (Bitwise equality of the split
 * passes: the tests above.) */
Test(gdca_parallel, a_simulation_on_threads_records_the_same_samples, .timeout = 120)
{
    for (int err = 0; err < 2; err++) { /* exact model, then a controller model of its own */
        double scale = err ? 1.1 : 1.0;
        ctc_sim_result *serial = pendulum_run(0, scale), *two = pendulum_run(2, scale);
        ctc_sim_result *three = pendulum_run(3, scale);
        cr_assert_eq(serial->nsamples, two->nsamples);
        cr_assert_eq(serial->nsamples, three->nsamples);
        cr_expect_eq(memcmp(serial->t, two->t, (size_t)serial->nsamples * sizeof(double)), 0);
        for (int ch = 0; ch < CTC_NCHANNELS; ch++) {
            if (!serial->ch[ch]) continue;
            double e2 = run_difference(serial, two, (ctc_channel)ch);
            double e3 = run_difference(serial, three, (ctc_channel)ch);
            cr_expect(
                e2 < 1e-5 && e3 < 1e-5, "%s: channel %s: 1 and 2, 3 threads differ by %.3g, %.3g",
                err ? "model error" : "exact model", ctc_channel_name((ctc_channel)ch), e2, e3);
        }
        ctc_sim_result_free(serial);
        ctc_sim_result_free(two);
        ctc_sim_result_free(three);
    }
}

Test(gdca_parallel, a_simulation_refuses_thread_counts_out_of_range)
{
    test_chain *c = test_chain_rod_pendulum(2, 1, 1);
    ctc_sim_spec spec = {.chain = c->spec,
                         .integrator = {.method = CTC_INTEG_RK4, .step = 1e-3},
                         .duration = 0.1,
                         .output_interval = 0.01,
                         .threads = 65};
    char err[256] = "";
    cr_expect_eq(ctc_sim_check(&spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "threads must be 0 to 64 (got 65)");
    spec.threads = -1;
    cr_expect_eq(ctc_sim_check(&spec, err, sizeof err), CTC_EINVAL);
    cr_expect_str_eq(err, "threads must be 0 to 64 (got -1)");
    spec.threads = 64;
    cr_expect_eq(ctc_sim_check(&spec, err, sizeof err), CTC_OK, "%s", err);
    test_chain_free(c);
}
