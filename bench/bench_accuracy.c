/*
 * bench_accuracy.c - hard cases: the accuracy of the dynamics on long chains, against the oracle.
 *
 * For random planar rod chains, random spatial chains of every joint type and Featherstone's
 * coil (tests/support/chains.h) of n = 16 ... 4096 bodies, at a few random states, measures:
 *
 *   fwd rand    GDCA qdd against the oracle's ABA qdd for random driving forces f in [-5, 5];
 *   fwd ctc     the same for CTC-like forces f = RNEA(u), u random in [-1, 1]: f then nearly
 *               balances gravity and the velocity terms, and qdd = u is the small difference;
 *   rt gdca     the round trip GDCA(iGDCA(u)) against u (iGDCA in its composite form);
 *   rt tree     the same with the forward pass in the balanced tree's order, which it takes
 *               when split over threads (ctc_gdca_forward on one thread takes the sequential
 *               order on open chains: gdca_forward_seq.h);
 *   rt aba      the oracle's own round trip ABA(RNEA(u)) against u;
 *   inv comp    the composite iGDCA's f against RNEA's;
 *   inv mob     the paper's mobility-form iGDCA's f against RNEA's;
 * each as max |difference| / max |reference| (the reference: the oracle, or u), the largest over
 * the states. The round trips compare with the exact answer u; the "fwd" measures compare two
 * computed answers, so where the oracle itself is inexact (rt aba well above rounding) they
 * measure the two errors together. To tell which forward solver is nearer the truth without
 * trusting either, the backward errors
 *
 *   bwd gdca / bwd aba    max |f - iGDCA(qdd)| / max |f|
 *
 * measure how well each one's qdd satisfies the equations of motion, with the composite iGDCA
 * (accurate to rounding: inv comp) as the judge, for the random and the CTC-like forces. The
 * judge rounds too, relative to the terms M qdd and N it adds up, which random forces can make
 * far larger than f; "judge gap" = max |iGDCA(qdd) - RNEA(qdd)| / max |f| over both solvers'
 * qdd shows that floor: a backward error near it says only "no worse than the judge can see".
 * (ctc_gdca_forward's refinement drives its residual against the composite iGDCA to rounding
 * (gdca_refine.h), so "bwd gdca (ctc)" is no independent check of it; the judge gap, from RNEA,
 * and the round trips against the exact u are.) cond(M) is the 2-norm condition number of the mass
 * matrix from the oracle's CRBA and LAPACK's dsyev, at n <= 1024 (the largest over the states), as
 * the scale of what any forward solver may lose.
 *
 * Growth with n: the ratio of each measure between successive sizes, and the exponent p of a
 * least-squares fit measure ~ n^p over all sizes. Last, the hard-cases requirement: GDCA
 * against the oracle within 1e-8 on the coil at n = 4096 on random forces ("fwd rand"; the exit
 * status is 1 when it is not met). On CTC forces no forward solver can be held to 1e-8 - the
 * oracle's own round trip is far above it there - so "fwd ctc" and "rt gdca" are printed against
 * "rt aba" instead. ctc_gdca_forward is measured as it stands, so a change to it shows by simply
 * running this again. Last, slender rods (issue 18): GDCA against a dense solve, against ABA and
 * in a round trip, over each rod's moment ratio 1 .. 1e-12 at n = 2 ... 4096 (model.h "slender
 * bodies"), and the same chains of point masses, some with massless links between them (model.h
 * "singular bodies"). Usage: bench_accuracy [max_n] [states]
 */
#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "ctc.h"
#include "linalg.h"
#include "oracle.h"

enum {
    M_FWD_RAND,
    M_FWD_CTC,
    M_RT_GDCA,
    M_RT_TREE,
    M_RT_ABA,
    M_INV_COMP,
    M_INV_MOB,
    M_BWD_GDCA_RAND,
    M_BWD_ABA_RAND,
    M_BWD_GDCA_CTC,
    M_BWD_ABA_CTC,
    M_JUDGE_RAND,
    M_JUDGE_CTC,
    M_COND,
    NM
};

static const char *const measure_name[NM] = {
    "fwd rand",      "fwd ctc",          "rt gdca",         "rt tree",        "rt aba",
    "inv comp",      "inv mob",          "bwd gdca (rand)", "bwd aba (rand)", "bwd gdca (ctc)",
    "bwd aba (ctc)", "judge gap (rand)", "judge gap (ctc)", "cond(M)",
};

#define NSIZES 5
static const int sizes[NSIZES] = {16, 64, 256, 1024, 4096};
#define NCHAINS 3
static const char *const chain_name[NCHAINS] = {"planar", "spatial", "coil"};
#define COND_MAX_N 1024    /* cond(M) by a dense eigensolver up to this n */
#define REQUIREMENT 1e-8   /* GDCA against the oracle on the coil at n = 4096 */
#define REQUIREMENT_N 4096 /* ... at this n */

/* the results: [chain][size][measure], NAN where not measured */
static double result[NCHAINS][NSIZES][NM];

static test_chain *make_chain(int chain, int n)
{
    switch (chain) {
    case 0:
        return test_chain_random_planar(n, 7, 0, 1);
    case 1:
        return test_chain_random_spatial(n, 7, TEST_ALL_JOINTS);
    default:
        return test_chain_coil(n);
    }
}

static double max_abs(const double *x, int n)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(x[i]));
    return s;
}

/* *slot = the larger of it and value (NAN: not set yet) */
static void update(double *slot, double value)
{
    *slot = isnan(*slot) ? value : fmax(*slot, value);
}

/* max |f - iGDCA(qdd)| / max |f|: how far qdd is from satisfying the equations of motion for f,
 * judged by the composite iGDCA (needs the state's kinematics and handles in d). The judge's own
 * error, max |iGDCA(qdd) - RNEA(qdd)| / max |f|, goes to *judge (the larger of it and *judge).
 * scratch: 2 nv. */
static double backward_error(const ctc_model *m, ctc_data *d, ctc_oracle *o, const double *q,
                             const double *v, const double *f, const double *qdd, double *scratch,
                             double *judge)
{
    double *fi = scratch, *fr = scratch + m->nv, e = 0, gap = 0;
    ctc_gdca_inverse(m, d, qdd, fi);
    ctc_oracle_rnea(m, o, q, v, qdd, fr);
    for (int i = 0; i < m->nv; i++) {
        e = fmax(e, fabs(f[i] - fi[i]));
        gap = fmax(gap, fabs(fr[i] - fi[i]));
    }
    double scale = fmax(max_abs(f, m->nv), 1e-300);
    update(judge, gap / scale);
    return e / scale;
}

/* 2-norm condition number of the mass matrix at q by its eigenvalues; NAN if it fails */
static double mass_cond(const ctc_model *m, ctc_oracle *o, const double *q)
{
    int nv = m->nv;
    double *mass = malloc(sizeof(double) * (size_t)nv * (size_t)nv);
    double *eig = malloc(sizeof(double) * (size_t)nv);
    double cond = NAN;
    if (mass && eig) {
        ctc_oracle_mass_matrix(m, o, q, mass);
        lapack_int info = LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'N', 'U', nv, mass, nv, eig);
        if (info == 0 && eig[0] > 0) cond = eig[nv - 1] / eig[0];
        if (info == 0 && !(eig[0] > 0)) cond = INFINITY;
    }
    free(mass);
    free(eig);
    return cond;
}

/* measures one chain at `states` random states into res (NM); returns 0, or 1 if any result is
 * not finite or a pass reports a singular joint */
static int measure_chain(int chain, int n, int states, double res[NM])
{
    char err[256];
    test_chain *c = make_chain(chain, n);
    ctc_model *m = NULL;
    if (ctc_model_build(&c->spec, &m, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "%s n = %d: %s\n", chain_name[chain], n, err);
        exit(1);
    }
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    size_t nq = (size_t)m->nq, nv = (size_t)m->nv;
    double *buf = calloc(nq + 9 * nv, sizeof(double));
    if (!d || !o || !buf) {
        fprintf(stderr, "out of memory\n");
        exit(1);
    }
    double *q = buf, *v = q + nq, *u = v + nv, *f = u + nv, *fc = f + nv, *a = fc + nv;
    double *ref = a + nv, *scratch = ref + nv;
    int bad = 0;
    for (int i = 0; i < NM; i++) res[i] = NAN;

    uint64_t rng = 1000 + (uint64_t)n;
    for (int s = 0; s < states; s++) {
        test_random_state(m, &rng, 2.0, q, v);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);

        /* (a) random driving forces */
        for (size_t i = 0; i < nv; i++) f[i] = test_uniform(&rng, -5, 5);
        ctc_gdca_forward(m, d, f, a);
        bad |= d->singular_joint != -1;
        ctc_oracle_aba(m, o, q, v, f, ref);
        update(&res[M_FWD_RAND], test_rel_err(a, ref, m->nv));
        update(&res[M_BWD_GDCA_RAND],
               backward_error(m, d, o, q, v, f, a, scratch, &res[M_JUDGE_RAND]));
        update(&res[M_BWD_ABA_RAND],
               backward_error(m, d, o, q, v, f, ref, scratch, &res[M_JUDGE_RAND]));

        /* (b) CTC-like forces f = RNEA(u) */
        for (size_t i = 0; i < nv; i++) u[i] = test_uniform(&rng, -1, 1);
        ctc_oracle_rnea(m, o, q, v, u, f);
        ctc_gdca_forward(m, d, f, a);
        bad |= d->singular_joint != -1;
        ctc_oracle_aba(m, o, q, v, f, ref);
        update(&res[M_FWD_CTC], test_rel_err(a, ref, m->nv));
        update(&res[M_RT_ABA], test_rel_err(ref, u, m->nv));
        update(&res[M_BWD_GDCA_CTC],
               backward_error(m, d, o, q, v, f, a, scratch, &res[M_JUDGE_CTC]));
        update(&res[M_BWD_ABA_CTC],
               backward_error(m, d, o, q, v, f, ref, scratch, &res[M_JUDGE_CTC]));

        /* inverse dynamics, both forms, and GDCA's round trip */
        ctc_gdca_inverse(m, d, u, fc);
        bad |= d->singular_joint != -1;
        update(&res[M_INV_COMP], test_rel_err(fc, f, m->nv));
        ctc_gdca_forward(m, d, fc, a);
        update(&res[M_RT_GDCA], test_rel_err(a, u, m->nv));
        d->opt.fwd_order = CTC_ORDER_TREE; /* the other assembly order (gdca_forward_seq.h) */
        ctc_gdca_forward(m, d, fc, a);
        d->opt.fwd_order = CTC_ORDER_AUTO;
        update(&res[M_RT_TREE], test_rel_err(a, u, m->nv));
        ctc_gdca_inverse_mobility(m, d, u, scratch);
        bad |= d->singular_joint != -1;
        update(&res[M_INV_MOB], test_rel_err(scratch, f, m->nv));

        if (n <= COND_MAX_N) update(&res[M_COND], mass_cond(m, o, q));
    }
    for (int i = 0; i < NM; i++) bad |= !(isnan(res[i]) || isfinite(res[i]));
    if (bad)
        fprintf(stderr, "%s n = %d: a result is not finite or a joint is singular\n",
                chain_name[chain], n);
    free(buf);
    ctc_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
    return bad;
}

static void print_cell(double x)
{
    if (isnan(x))
        printf(" %8s |", "-");
    else
        printf(" %8.1e |", x);
}

static void print_table(const int *cols, int ncols)
{
    printf("| chain   |    n |");
    for (int j = 0; j < ncols; j++) printf(" %s |", measure_name[cols[j]]);
    printf("\n| ------- | ---: |");
    for (int j = 0; j < ncols; j++) printf(" ---: |");
    printf("\n");
    for (int ch = 0; ch < NCHAINS; ch++) {
        for (int s = 0; s < NSIZES; s++) {
            if (isnan(result[ch][s][M_FWD_RAND])) continue;
            printf("| %-7s | %4d |", chain_name[ch], sizes[s]);
            for (int j = 0; j < ncols; j++) print_cell(result[ch][s][cols[j]]);
            printf("\n");
        }
    }
    printf("\n");
}

/* least-squares slope of log(y) against log(n) over the sizes where y is positive and finite */
static double growth_exponent(const double *y_by_size, int stride)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int k = 0;
    for (int s = 0; s < NSIZES; s++) {
        double y = y_by_size[s * stride];
        if (!(y > 0) || !isfinite(y)) continue;
        double x = log((double)sizes[s]), ly = log(y);
        sx += x, sy += ly, sxx += x * x, sxy += x * ly, k++;
    }
    if (k < 2) return NAN;
    return (k * sxy - sx * sy) / (k * sxx - sx * sx);
}

/* the exponents p, one row per measure, one column per chain */
static void print_exponents(void)
{
    printf("| measure | planar | spatial | coil |\n| --- | ---: | ---: | ---: |\n");
    for (int i = 0; i < NM; i++) {
        printf("| %s |", measure_name[i]);
        for (int ch = 0; ch < NCHAINS; ch++) {
            double p = growth_exponent(&result[ch][0][i], NM);
            if (isnan(p))
                printf(" %6s |", "-");
            else
                printf(" %6.2f |", p);
        }
        printf("\n");
    }
    printf("\n");
}

/* the ratios between successive sizes, one row per chain and measure */
static void print_ratios(void)
{
    printf("| chain   | measure          |");
    for (int s = 1; s < NSIZES; s++) printf(" %d/%d |", sizes[s], sizes[s - 1]);
    printf("\n| ------- | ---------------- |");
    for (int s = 1; s < NSIZES; s++) printf(" ---: |");
    printf("\n");
    for (int ch = 0; ch < NCHAINS; ch++) {
        for (int i = 0; i < NM; i++) {
            printf("| %-7s | %-16s |", chain_name[ch], measure_name[i]);
            for (int s = 1; s < NSIZES; s++) {
                double r = result[ch][s][i] / result[ch][s - 1][i];
                if (isnan(r) || isinf(r))
                    printf(" %6s |", "-");
                else
                    printf(" %6.1f |", r);
            }
            printf("\n");
        }
    }
    printf("\n");
}

/* the requirement on the coil at REQUIREMENT_N (random forces); returns 1 when it is not met */
static int print_requirement(void)
{
    int s = NSIZES - 1;
    if (sizes[s] != REQUIREMENT_N || isnan(result[2][s][M_FWD_RAND])) {
        printf("requirement: coil n = %d not measured\n", REQUIREMENT_N);
        return 0;
    }
    const double x = result[2][s][M_FWD_RAND];
    printf("requirement: GDCA vs oracle <= %.0e on the coil at n = %d, random forces\n",
           REQUIREMENT, REQUIREMENT_N);
    printf("  %-9s %8.1e  %s\n", measure_name[M_FWD_RAND], x, x <= REQUIREMENT ? "met" : "NOT met");
    printf("  CTC forces, against the oracle's own round trip (rt aba %.1e): fwd ctc %.1e (%.1fx), "
           "rt gdca %.1e (%.1fx), rt tree %.1e (%.1fx)\n",
           result[2][s][M_RT_ABA], result[2][s][M_FWD_CTC],
           result[2][s][M_FWD_CTC] / result[2][s][M_RT_ABA], result[2][s][M_RT_GDCA],
           result[2][s][M_RT_GDCA] / result[2][s][M_RT_ABA], result[2][s][M_RT_TREE],
           result[2][s][M_RT_TREE] / result[2][s][M_RT_ABA]);
    printf("  (backward errors, random forces: gdca %.1e, aba %.1e, judge gap %.1e; ctc forces: "
           "gdca %.1e, aba %.1e, judge gap %.1e)\n",
           result[2][s][M_BWD_GDCA_RAND], result[2][s][M_BWD_ABA_RAND], result[2][s][M_JUDGE_RAND],
           result[2][s][M_BWD_GDCA_CTC], result[2][s][M_BWD_ABA_CTC], result[2][s][M_JUDGE_CTC]);
    return !(x <= REQUIREMENT);
}

/* ---- slender bodies (issue 18): test_chain_slender_rods over moment ratios ---- */

static const double slender_ratio[] = {1, 1e-2, 2e-3, 1e-4, 1e-6, 1e-8, 1e-10, 1e-12};
static const int slender_n[] = {2, 16, 256, 1024, 4096};
#define NSLR ((int)(sizeof slender_ratio / sizeof *slender_ratio))
#define NSLN ((int)(sizeof slender_n / sizeof *slender_n))
#define SLENDER_DENSE_MAX 1024 /* the dense solve's O(n^3) cost beyond */

static int measure_rods(test_chain *c, double ratio, int states, double out[4]);

/* n rods of moment ratio `ratio` at `states` random states (v in [-1, 1] rad/s): the largest
 * error of ctc_gdca_forward's qdd against the dense solve of M qdd = f - N (CRBA, RNEA,
 * Cholesky; n <= SLENDER_DENSE_MAX, else NAN) and against ABA for f in [-5, 5] N m (out[0],
 * out[1]), and the round trip GDCA(RNEA(u)) against u in [-1, 1] (out[2]); out[3] = the
 * refinement steps of the last call. Returns 1 if a result is not finite. */
static int measure_slender(int n, double ratio, int states, double out[4])
{
    return measure_rods(test_chain_slender_rods(n, ratio), ratio, states, out);
}

/* the same measures on the chain c (freed here), whose rods are named by `ratio` in messages */
static int measure_rods(test_chain *c, double ratio, int states, double out[4])
{
    char err[256];
    const int n = c->spec.nbodies;
    ctc_model *m = NULL;
    if (ctc_model_build(&c->spec, &m, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "slender n = %d ratio %g: %s\n", n, ratio, err);
        test_chain_free(c);
        return 1;
    }
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    const int nv = m->nv, dense = n <= SLENDER_DENSE_MAX;
    double *buf = calloc((size_t)m->nq + 8 * (size_t)nv, sizeof(double));
    double *mm = dense ? malloc(sizeof(double) * (size_t)nv * (size_t)nv) : NULL;
    int bad = d == NULL || o == NULL || buf == NULL || (dense && mm == NULL);
    for (int i = 0; i < 4; i++) out[i] = NAN;
    uint64_t rng = 18;
    for (int s = 0; s < states && !bad; s++) {
        double *q = buf, *v = q + m->nq, *f = v + nv, *a = f + nv, *ref = a + nv, *b = ref + nv,
               *zero = b + nv, *u = zero + nv, *fu = u + nv;
        test_random_state(m, &rng, 1.0, q, v);
        for (int i = 0; i < nv; i++) {
            f[i] = test_uniform(&rng, -5, 5);
            u[i] = test_uniform(&rng, -1, 1);
        }
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_forward(m, d, f, a);
        bad |= !test_all_finite(a, nv);
        if (dense) {
            ctc_oracle_mass_matrix(m, o, q, mm);
            ctc_oracle_rnea(m, o, q, v, zero, b);
            for (int i = 0; i < nv; i++) b[i] = f[i] - b[i];
            bad |= test_solve_spd(mm, nv, b, ref) != 0;
            update(&out[0], test_rel_err(a, ref, nv));
        }
        ctc_oracle_aba(m, o, q, v, f, ref);
        update(&out[1], test_rel_err(a, ref, nv));
        ctc_oracle_rnea(m, o, q, v, u, fu);
        ctc_gdca_forward(m, d, fu, a);
        bad |= !test_all_finite(a, nv);
        update(&out[2], test_rel_err(a, u, nv));
        out[3] = d->fwd_refine_done;
    }
    free(mm);
    free(buf);
    ctc_oracle_free(o);
    ctc_data_free(d);
    ctc_model_free(m);
    test_chain_free(c);
    return bad;
}

static int print_slender(int max_n, int states)
{
    int bad = 0;
    printf("\nSlender rods (issue 18; tests/support test_chain_slender_rods: 1 kg, 1 m, hinges "
           "about z and y),\nby each rod's smallest / largest principal moment, the largest over "
           "%d states:\nGDCA qdd vs the dense solve (n <= %d) | vs ABA | round trip "
           "GDCA(RNEA(u)) vs u | refinement steps\n\n%7s",
           states, SLENDER_DENSE_MAX, "ratio");
    for (int j = 0; j < NSLN && slender_n[j] <= max_n; j++) printf(" %31d", slender_n[j]);
    printf("\n");
    for (int r = 0; r < NSLR; r++) {
        printf("%7.0e", slender_ratio[r]);
        for (int j = 0; j < NSLN && slender_n[j] <= max_n; j++) {
            double x[4] = {NAN, NAN, NAN, NAN};
            int fail = measure_slender(slender_n[j], slender_ratio[r], states, x);
            bad |= fail;
            printf("  %7.1e %7.1e %7.1e %2.0f%s", x[0], x[1], x[2], x[3], fail ? "!" : " ");
        }
        printf("\n");
        fflush(stdout);
    }
    printf("(! : a non-finite result)\n");
    return bad;
}

/* point masses (issue 18): test_chain_slender_rods of ratio 1 with every rod's inertia 0 (each a
   point mass at its rod's centre), or every other rod also massless (mass 0: a massless link
   between point masses) */
static int print_point_masses(int max_n, int states)
{
    int bad = 0;
    printf("\nPoint masses (issue 18; the rods above with inertia 0: a point mass at each rod's "
           "centre;\n\"massless\": every odd rod also of mass 0), the largest over %d states:\n"
           "GDCA qdd vs the dense solve (n <= %d) | vs ABA | round trip GDCA(RNEA(u)) vs u | "
           "refinement steps\n\n%9s",
           states, SLENDER_DENSE_MAX, "chain");
    for (int j = 0; j < NSLN && slender_n[j] <= max_n; j++) printf(" %31d", slender_n[j]);
    printf("\n");
    for (int kind = 0; kind < 2; kind++) {
        printf("%9s", kind ? "massless" : "points");
        for (int j = 0; j < NSLN && slender_n[j] <= max_n; j++) {
            const int n = slender_n[j];
            test_chain *c = test_chain_slender_rods(n, 1);
            for (int k = 0; k < n; k++) {
                for (int e = 0; e < 9; e++) c->bodies[k].inertia[e] = 0;
                if (kind && k % 2 && k + 1 < n) c->bodies[k].mass = 0;
            }
            double x[4] = {NAN, NAN, NAN, NAN};
            int fail = measure_rods(c, 0, states, x);
            bad |= fail;
            printf("  %7.1e %7.1e %7.1e %2.0f%s", x[0], x[1], x[2], x[3], fail ? "!" : " ");
        }
        printf("\n");
        fflush(stdout);
    }
    printf("(! : a non-finite result or a refused model)\n");
    return bad;
}

int main(int argc, char **argv)
{
    int max_n = argc > 1 ? atoi(argv[1]) : sizes[NSIZES - 1];
    int states = argc > 2 ? atoi(argv[2]) : 5;
    if (max_n < sizes[0] || states < 1) {
        fprintf(stderr, "usage: bench_accuracy [max_n >= %d] [states >= 1]\n", sizes[0]);
        return 2;
    }
    for (int ch = 0; ch < NCHAINS; ch++)
        for (int s = 0; s < NSIZES; s++)
            for (int i = 0; i < NM; i++) result[ch][s][i] = NAN;

    int bad = 0;
    for (int ch = 0; ch < NCHAINS; ch++)
        for (int s = 0; s < NSIZES && sizes[s] <= max_n; s++)
            bad |= measure_chain(ch, sizes[s], states, result[ch][s]);

    printf("Accuracy of the dynamics: max |difference| / max |reference|, the largest over %d "
           "random states\n(velocities up to 2 rad/s or m/s per joint). ctc_gdca_forward as "
           "built.\n\n",
           states);
    static const int fwd_cols[] = {M_FWD_RAND, M_FWD_CTC, M_RT_GDCA, M_RT_TREE, M_RT_ABA, M_COND};
    static const int inv_cols[] = {M_INV_COMP,   M_INV_MOB,      M_BWD_GDCA_RAND, M_BWD_ABA_RAND,
                                   M_JUDGE_RAND, M_BWD_GDCA_CTC, M_BWD_ABA_CTC,   M_JUDGE_CTC};
    printf("Forward dynamics and round trips:\n\n");
    print_table(fwd_cols, 6);
    printf("Inverse dynamics, and backward errors max |f - iGDCA(qdd)| / max |f|:\n\n");
    print_table(inv_cols, 8);
    printf("Growth with n: exponent p of a least-squares fit measure ~ n^p over the sizes:\n\n");
    print_exponents();
    printf("Growth with n: ratio between successive sizes:\n\n");
    print_ratios();
    bad |= print_requirement();
    bad |= print_slender(max_n, states);
    bad |= print_point_masses(max_n, states);
    return bad;
}
