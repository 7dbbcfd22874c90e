/*
 * bench_dynamics.c - the cost of one CTC right-hand side: GDCA against the serial oracle pair.
 *
 * For planar rod chains and spatial revolute chains of n = 2 ... 4096 bodies, times
 *   ctc   = kinematics + body handles + iGDCA (composite form) + GDCA forward, the work of one
 *           right-hand side of a CTC simulation (f = iGDCA(q, v, u), qdd = GDCA(q, v, f));
 *   pair  = the oracle's RNEA + ABA on the same state (each does its own kinematics);
 * and, to show where the time goes, each stage of ctc alone and the paper's mobility-form iGDCA.
 * A second table splits ctc per body for the hot-path figures of bench/NOTEBOOK.md: kinematics,
 * handles, the composite iGDCA, GDCA forward without refinement (d->opt.fwd_refine = 0) and one
 * refinement step (GDCA forward with d->opt.fwd_refine = 1, less the unrefined pass), with the
 * steps the default makes and ctc with and without refinement, and the unrefined forward pass
 * and ctc with the forward pass in the balanced tree's order (gdca_forward_seq.h), at n = 16, 64,
 * 256, 1024 and 4096.
 * A third table times ctc and pair on Featherstone's autoTree family (tests/support/chains.h
 * test_auto_tree: taper 1, branching factor 1 = a chain, 2 and 4; planar with no skew, spatial
 * with skew 0.5 rad) at n = 16, 64, 256, 1024 and 4096, per body, with the plan's height and the
 * tree's ctc per body over the chain's (bf 1) at the same n and form.
 * Batches of each are interleaved so that machine noise hits all of them alike; the figures are
 * medians over the batches, per evaluation, and the ratio is ctc / pair from the same run.
 * Usage: bench_dynamics [max_n [batches [parts]]]: parts "t" (the first table), "s" (the split),
 * "a" (autoTree), any of them (default: all three)
 */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "chains.h"
#include "ctc.h"
#include "oracle.h"

enum {
    T_CTC,
    T_PAIR,
    T_KIN,
    T_INV,
    T_FWD,
    T_MOB,
    T_KIN_ONLY, /* the stage split: kinematics alone */
    T_HANDLES,
    T_FWD0,      /* GDCA forward unrefined */
    T_FWD1,      /* GDCA forward with one refinement step */
    T_CTC0,      /* ctc unrefined */
    T_FWD0_TREE, /* GDCA forward unrefined in the balanced tree's order (gdca_forward_seq.h) */
    T_CTC_TREE,  /* ctc with the forward pass in the balanced tree's order */
    NT
};

typedef struct bench_case {
    const ctc_model *m;
    ctc_data *d;
    ctc_oracle *o;
    double *q, *v, *u, *f, *a;
} bench_case;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static volatile double sink;

static void run_once(bench_case *c, int what)
{
    const ctc_model *m = c->m;
    const int refine = c->d->opt.fwd_refine;
    switch (what) {
    case T_CTC:
        ctc_kinematics(m, c->d, c->q, c->v);
        ctc_handles(m, c->d);
        ctc_gdca_inverse(m, c->d, c->u, c->f);
        ctc_gdca_forward(m, c->d, c->f, c->a);
        break;
    case T_PAIR:
        ctc_oracle_rnea(m, c->o, c->q, c->v, c->u, c->f);
        ctc_oracle_aba(m, c->o, c->q, c->v, c->f, c->a);
        break;
    case T_KIN:
        ctc_kinematics(m, c->d, c->q, c->v);
        ctc_handles(m, c->d);
        break;
    case T_INV: /* as the first pass at a state, which computes the composite inertias that
                   later passes at the same state keep (gdca_inverse.c) */
        c->d->icomp_stamp = 0;
        ctc_gdca_inverse(m, c->d, c->u, c->f);
        break;
    case T_FWD:
        ctc_gdca_forward(m, c->d, c->f, c->a);
        break;
    case T_MOB:
        ctc_gdca_inverse_mobility(m, c->d, c->u, c->f);
        break;
    case T_KIN_ONLY:
        ctc_kinematics(m, c->d, c->q, c->v);
        break;
    case T_HANDLES:
        ctc_handles(m, c->d);
        break;
    case T_FWD0:
    case T_FWD1:
        c->d->opt.fwd_refine = what == T_FWD0 ? 0 : 1;
        ctc_gdca_forward(m, c->d, c->f, c->a);
        c->d->opt.fwd_refine = refine;
        break;
    case T_CTC0:
        c->d->opt.fwd_refine = 0;
        run_once(c, T_CTC);
        c->d->opt.fwd_refine = refine;
        break;
    case T_FWD0_TREE:
    case T_CTC_TREE:
        c->d->opt.fwd_order = CTC_ORDER_TREE;
        run_once(c, what == T_FWD0_TREE ? T_FWD0 : T_CTC);
        c->d->opt.fwd_order = CTC_ORDER_AUTO;
        break;
    }
    sink += c->a[0] + c->f[0];
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

/* median seconds per evaluation of the nw timings in which (med indexed by timing), from
 * interleaved batches */
static void measure(bench_case *c, int batches, const int *which, int nw, double med[NT])
{
    /* a batch of reps evaluations lasts about 2 ms for the slowest timing */
    run_once(c, T_CTC);
    run_once(c, T_PAIR);
    double t0 = now();
    int probe = 0;
    while (now() - t0 < 2e-3 || probe < 1) {
        run_once(c, T_CTC);
        run_once(c, T_PAIR);
        probe++;
    }
    int reps = probe > 1 ? probe : 1;
    double *samples = malloc(sizeof(double) * (size_t)batches * nw);
    for (int b = 0; b < batches; b++) {
        for (int i = 0; i < nw; i++) {
            double s = now();
            for (int r = 0; r < reps; r++) run_once(c, which[i]);
            samples[i * batches + b] = (now() - s) / reps;
            /* the stage timings assume the state's kinematics and forces are in place */
            if (which[i] == T_PAIR) run_once(c, T_CTC);
        }
    }
    for (int i = 0; i < nw; i++) {
        qsort(samples + i * batches, (size_t)batches, sizeof(double), cmp_double);
        med[which[i]] = samples[i * batches + batches / 2];
    }
    free(samples);
}

/* the main table's row (split = 0), the stage split's (split = 1) or the autoTree table's (split
   = 2, its ctc per body over chain_per_body, or none when that is 0); returns ctc per body, s */
static double bench_chain(const char *label, test_chain *chain, int batches, int split,
                          double chain_per_body)
{
    char err[256];
    ctc_model *m = NULL;
    if (ctc_model_build(&chain->spec, &m, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "%s: %s\n", label, err);
        exit(1);
    }
    bench_case c = {.m = m, .d = ctc_data_new(m), .o = ctc_oracle_new(m)};
    size_t nq = (size_t)m->nq, nv = (size_t)m->nv;
    c.q = calloc(nq, sizeof(double));
    c.v = calloc(nv, sizeof(double));
    c.u = calloc(nv, sizeof(double));
    c.f = calloc(nv, sizeof(double));
    c.a = calloc(nv, sizeof(double));
    uint64_t rng = 1;
    test_random_state(m, &rng, 1.0, c.q, c.v);
    for (size_t i = 0; i < nv; i++) c.u[i] = test_uniform(&rng, -1, 1);

    double med[NT];
    int n = m->nbodies;
    if (split == 2) {
        static const int which[] = {T_CTC, T_PAIR};
        measure(&c, batches, which, 2, med);
        printf("| %-7s | %5d | %6d | %10.2f | %10.2f | %5.2f | %7.1f | %7.1f | ", label, n,
               m->height, 1e6 * med[T_CTC], 1e6 * med[T_PAIR], med[T_CTC] / med[T_PAIR],
               1e9 * med[T_CTC] / n, 1e9 * med[T_PAIR] / n);
        if (chain_per_body > 0) {
            printf("%5.2f |\n", med[T_CTC] / n / chain_per_body);
        } else {
            printf("    - |\n");
        }
    } else if (split) {
        static const int which[] = {T_KIN_ONLY, T_HANDLES, T_INV,       T_FWD0,    T_FWD1,
                                    T_CTC,      T_CTC0,    T_FWD0_TREE, T_CTC_TREE};
        measure(&c, batches, which, (int)(sizeof which / sizeof *which), med);
        run_once(&c, T_CTC); /* the default's refinement steps */
        printf("| %-7s | %5d | %7.1f | %7.1f | %7.1f | %7.1f | %7.1f | %5d | %7.1f | %7.1f | "
               "%7.1f | %7.1f |\n",
               label, n, 1e9 * med[T_KIN_ONLY] / n, 1e9 * med[T_HANDLES] / n, 1e9 * med[T_INV] / n,
               1e9 * med[T_FWD0] / n, 1e9 * (med[T_FWD1] - med[T_FWD0]) / n, c.d->fwd_refine_done,
               1e9 * med[T_CTC0] / n, 1e9 * med[T_CTC] / n, 1e9 * med[T_FWD0_TREE] / n,
               1e9 * med[T_CTC_TREE] / n);
    } else {
        static const int which[] = {T_CTC, T_PAIR, T_KIN, T_INV, T_FWD, T_MOB};
        measure(&c, batches, which, (int)(sizeof which / sizeof *which), med);
        printf("| %-7s | %5d | %10.2f | %10.2f | %5.2f | %7.1f | %7.1f | %8.2f | %8.2f | %8.2f | "
               "%8.2f |\n",
               label, n, 1e6 * med[T_CTC], 1e6 * med[T_PAIR], med[T_CTC] / med[T_PAIR],
               1e9 * med[T_CTC] / n, 1e9 * med[T_PAIR] / n, 1e6 * med[T_KIN], 1e6 * med[T_INV],
               1e6 * med[T_FWD], 1e6 * med[T_MOB]);
    }
    fflush(stdout);
    free(c.q), free(c.v), free(c.u), free(c.f), free(c.a);
    ctc_oracle_free(c.o);
    ctc_data_free(c.d);
    ctc_model_free(m);
    return med[T_CTC] / n;
}

int main(int argc, char **argv)
{
    int max_n = argc > 1 ? atoi(argv[1]) : 4096;
    int batches = argc > 2 ? atoi(argv[2]) : 15;
    const char *parts = argc > 3 ? argv[3] : "tsa";
    if (max_n < 2 || batches < 1 || parts[strspn(parts, "tsa")] != '\0') {
        fprintf(stderr, "usage: bench_dynamics [max_n >= 2 [batches >= 1 [parts: t s a]]]\n");
        return 2;
    }
    if (strchr(parts, 't') != NULL) {
        printf("One CTC right-hand side: ctc = kinematics + handles + iGDCA + GDCA; pair = oracle "
               "RNEA + ABA.\nMedians of %d interleaved batches; times in microseconds, per body in "
               "nanoseconds.\n\n",
               batches);
        printf("| chain   |     n | ctc (us)   | pair (us)  | ratio | ctc/n ns | pair/n ns | "
               "kin+handles | iGDCA | GDCA fwd | iGDCA mobility |\n");
        printf(
            "| ------- | ----: | ---------: | ---------: | ----: | ------: | ------: | -------: | "
            "-------: | -------: | -------: |\n");
        for (int n = 2; n <= max_n; n *= 2) {
            test_chain *c = test_chain_random_planar(n, 7, 0, 1);
            bench_chain("planar", c, batches, 0, 0);
            test_chain_free(c);
        }
        for (int n = 2; n <= max_n; n *= 2) {
            test_chain *c = test_chain_random_spatial(n, 7, 1u << CTC_JOINT_REVOLUTE);
            bench_chain("spatial", c, batches, 0, 0);
            test_chain_free(c);
        }
    }
    if (strchr(parts, 's') != NULL) {
        printf("\nHot path: ns per body of each stage of ctc; refine step = GDCA forward with one "
               "refinement step less the unrefined pass; steps = those the default makes.\n\n");
        printf(
            "| chain   |     n | kinematics | handles | iGDCA | GDCA fwd unrefined | refine step | "
            "steps | ctc unrefined | ctc | GDCA fwd unrefined, tree | ctc, tree |\n");
        printf("| ------- | ----: | ------: | ------: | ------: | ------: | ------: | ----: | "
               "------: | "
               "------: | ------: | ------: |\n");
        for (int form = 0; form < 2; form++) {
            for (int n = 16; n <= max_n; n *= 4) {
                test_chain *c = form ? test_chain_random_spatial(n, 7, 1u << CTC_JOINT_REVOLUTE)
                                     : test_chain_random_planar(n, 7, 0, 1);
                bench_chain(form ? "spatial" : "planar", c, batches, 1, 0);
                test_chain_free(c);
            }
        }
    }
    if (strchr(parts, 'a') != NULL) {
        printf("\nautoTree (taper 1; planar: skew 0, spatial: skew 0.5 rad): one CTC right-hand "
               "side, ctc against pair; tree/chain = ctc per body over the chain's (bf 1) at the "
               "same n and form.\n\n");
        printf(
            "| form    |     n | height | ctc (us)   | pair (us)  | ratio | ctc/n ns | pair/n ns "
            "| tree/chain |\n");
        printf("| ------- | ----: | -----: | ---------: | ---------: | ----: | ------: | ------: | "
               "----: |\n");
        for (int form = 0; form < 2; form++) {
            for (int n = 16; n <= max_n; n *= 4) {
                double chain = 0;
                const int bf[] = {1, 2, 4};
                for (int b = 0; b < 3; b++) {
                    char label[16];
                    snprintf(label, sizeof label, "%s %d", form ? "sp bf" : "pl bf", bf[b]);
                    test_chain *c = test_auto_tree(n, bf[b], form ? 0.5 : 0.0, 1.0);
                    double per = bench_chain(label, c, batches, 2, chain);
                    if (b == 0) chain = per;
                    test_chain_free(c);
                }
            }
        }
    }
    return sink == 12345.678 ? 1 : 0;
}
