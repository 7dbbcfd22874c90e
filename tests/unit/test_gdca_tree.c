/*
 * test_gdca_tree.c - GDCA forward and iGDCA inverse dynamics on branched kinematic trees (model.c,
 * "the plan of a branched tree"; gdca_rake.h) against the independent oracle (src/reference:
 * ABA, RNEA and CRBA, which walk body_parent), and the plan's shape and thread independence.
 *
 * Trees: Featherstone's autoTree family (tests/support/chains.h test_auto_tree: branching factor
 * 1, 2, 4 and in between, with taper and skew; skew 0 is planar), stars, binary trees, and random
 * parent arrays over random spatial bodies with every joint type and planar ones with prismatic
 * joints, with one root or several on the ground.
 *
 * The forward pass runs in both of its orders: the plan (gdca_forward.c, what threads split) and
 * the sequential tip runs (gdca_forward_tseq.c, one thread's default).
 *
 * Tolerances, as for chains (test_gdca_forward.c, test_gdca_inverse.c): the composite inverse
 * 1e-10 relative to RNEA; the forward pass 1e-10 relative to ABA, widened to 1e-14 cond(M) where
 * the mass matrix (CRBA) is ill conditioned, and the mobility inverse to 1e-13 cond(M). Beyond
 * 512 bodies the mass matrix is not formed: there the forward pass is checked by its backward
 * error, RNEA(q, v, qdd) against the forces it was given, to 1e-10 of their size plus the bias's.
 */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "ctc.h"
#include "gdca_refine.h"
#include "linalg.h"
#include "oracle.h"
#include "sim.h"
#include "model_fixture.h"
#include "oracle_fixture.h"
#include "run_fixture.h"

#define MAX_COND_N 512

static double forward_tolerance(double cond)
{
    return fmax(1e-10, 1e-14 * cond);
}

static double mobility_tolerance(double cond)
{
    return fmax(1e-9, 1e-13 * cond);
}

static double max_abs(const double *x, int n)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(x[i]));
    return s;
}

/* the three passes against the oracle at `trials` random states of m */
static void check_tree(const ctc_model *m, uint64_t seed, int trials, const char *what)
{
    ctc_data *d = ctc_data_new(m);
    ctc_oracle *o = ctc_oracle_new(m);
    const int nv = m->nv, nc = nv <= MAX_COND_N;
    double *q = calloc((size_t)m->nq + 1, 8), *v = calloc((size_t)nv + 1, 8);
    double *u = calloc((size_t)nv + 1, 8), *f = calloc((size_t)nv + 1, 8);
    double *ref = calloc((size_t)nv + 1, 8), *a = calloc((size_t)nv + 1, 8);
    double *bias = calloc((size_t)nv + 1, 8), *zero = calloc((size_t)nv + 1, 8);
    double *mass = nc ? calloc((size_t)nv * nv + 1, 8) : NULL;
    cr_assert(d && o && q && v && u && f && ref && a && bias && zero && (mass || !nc));
    uint64_t rng = seed;
    for (int t = 0; t < trials; t++) {
        test_random_state(m, &rng, 2.0, q, v);
        for (int i = 0; i < nv; i++) u[i] = test_uniform(&rng, -5, 5);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        double cond = 1.0;
        if (nc) {
            ctc_oracle_mass_matrix(m, o, q, mass);
            cond = nv ? test_cond_spd(mass, nv) : 1.0;
        }

        /* inverse, composite and mobility form, against RNEA */
        ctc_oracle_rnea(m, o, q, v, u, ref);
        ctc_gdca_inverse(m, d, u, f);
        cr_assert_eq(d->singular_joint, -1, "%s: singular joint %d", what, d->singular_joint);
        double err = test_rel_err(f, ref, nv);
        cr_assert(err <= 1e-10, "%s, n=%d trial %d: inverse error %.3g", what, m->nbodies, t, err);
        if (nc) {
            ctc_gdca_inverse_mobility(m, d, u, f);
            err = test_rel_err(f, ref, nv);
            cr_assert(err <= mobility_tolerance(cond),
                      "%s, n=%d trial %d: mobility inverse error %.3g (cond %.3g)", what,
                      m->nbodies, t, err, cond);
        }

        /* forward, of random forces, in both orders, against ABA (or by its backward error) */
        for (int i = 0; i < nv; i++) f[i] = test_uniform(&rng, -5, 5);
        for (int order = 0; order < 2; order++) {
            const char *oname = order ? "sequential" : "plan";
            d->opt.fwd_order = order ? CTC_ORDER_SEQ : CTC_ORDER_TREE;
            ctc_gdca_forward(m, d, f, a);
            cr_assert_eq(d->singular_joint, -1, "%s: singular joint %d", what, d->singular_joint);
            if (nc) {
                ctc_oracle_aba(m, o, q, v, f, ref);
                err = test_rel_err(a, ref, nv);
                cr_assert(err <= forward_tolerance(cond),
                          "%s, %s, n=%d trial %d: forward error %.3g > %.3g (cond %.3g)", what,
                          oname, m->nbodies, t, err, forward_tolerance(cond), cond);
            } else {
                ctc_oracle_rnea(m, o, q, v, a, ref);
                ctc_oracle_rnea(m, o, q, v, zero, bias);
                double scale = fmax(max_abs(f, nv), max_abs(bias, nv)), worst = 0;
                for (int i = 0; i < nv; i++) worst = fmax(worst, fabs(ref[i] - f[i]));
                cr_assert(worst <= 1e-10 * scale,
                          "%s, %s, n=%d trial %d: forward backward error %.3g of %.3g", what, oname,
                          m->nbodies, t, worst, scale);
            }
        }
        d->opt.fwd_order = CTC_ORDER_AUTO;
    }
    free(q), free(v), free(u), free(f), free(ref), free(a), free(bias), free(zero), free(mass);
    ctc_oracle_free(o);
    ctc_data_free(d);
}

/* check_tree on the model of c */
static void check_spec(test_chain *c, uint64_t seed, int trials, const char *what)
{
    ctc_model *m = build(&c->spec);
    check_tree(m, seed, trials, what);
    ctc_model_free(m);
}

static const int sizes[] = {2, 3, 5, 8, 16, 33, 64, 200, 1024, 4096};
#define NSIZES ((int)(sizeof sizes / sizeof sizes[0]))

static int trials_for(int n)
{
    return n <= 64 ? 3 : 1;
}

Test(gdca_tree, matches_the_oracle_on_featherstones_auto_trees, .timeout = 300)
{
    const double bf[] = {1, 2, 4, 1.5};
    for (int b = 0; b < 4; b++) {
        for (int i = 0; i < NSIZES; i++) {
            const int n = sizes[i];
            /* taper only where its masses stay in proportion: taper^(3n) spans their ratio */
            const double taper = n <= 64 ? 0.95 : 1.0, skew[] = {0, 0.4};
            for (int s = 0; s < 2; s++) {
                if (n > 1024 && s == 1 && b != 1) continue; /* fewer samples at large n */
                test_chain *c = test_auto_tree(n, bf[b], skew[s], taper);
                char what[96];
                snprintf(what, sizeof what, "autoTree bf %g skew %g taper %g", bf[b], skew[s],
                         taper);
                ctc_model *m = build(&c->spec);
                cr_assert_eq(m->form, s == 0 ? CTC_FORM_PLANAR : CTC_FORM_SPATIAL, "%s", what);
                int chain = 1;
                for (int k = 0; k < n; k++) chain &= c->parent[k] == k - 1;
                cr_assert_eq(m->chain, chain, "%s", what);
                cr_assert(bf[b] != 1 || chain, "%s", what);
                check_tree(m, 100 + (uint64_t)(10 * b + i), trials_for(n), what);
                ctc_model_free(m);
                test_chain_free(c);
            }
        }
    }
}

Test(gdca_tree, matches_the_oracle_on_stars)
{
    const int n[] = {2, 3, 9, 64, 1024};
    for (int i = 0; i < 5; i++) {
        for (int spatial = 0; spatial < 2; spatial++) {
            test_chain *c = spatial ? test_chain_random_spatial(n[i], 40 + (uint64_t)i, 1u)
                                    : test_chain_random_planar(n[i], 40 + (uint64_t)i, 1, 0);
            int *parent = malloc((size_t)n[i] * sizeof *parent);
            cr_assert(parent);
            for (int k = 0; k < n[i]; k++) parent[k] = k ? 0 : -1;
            test_chain_set_parents(c, parent);
            check_spec(c, 50 + (uint64_t)i, trials_for(n[i]), spatial ? "spatial star" : "star");
            free(parent);
            test_chain_free(c);
        }
    }
}

Test(gdca_tree, matches_the_oracle_on_random_trees_of_every_joint_type)
{
    const int n[] = {2, 4, 7, 16, 40, 100, 300};
    const double ground[] = {0, 0.05, 0.3};
    for (int i = 0; i < 7; i++) {
        for (int g = 0; g < 3; g++) {
            int *parent = malloc((size_t)n[i] * sizeof *parent);
            cr_assert(parent);
            test_random_parents(n[i], 60 + (uint64_t)(3 * i + g), ground[g], parent);
            test_chain *c = test_chain_random_spatial(n[i], 70 + (uint64_t)i, TEST_ALL_JOINTS);
            test_chain_set_parents(c, parent);
            check_spec(c, 80 + (uint64_t)i, trials_for(n[i]), "random spatial tree");
            test_chain_free(c);
            c = test_chain_random_planar(n[i], 90 + (uint64_t)i, 1, 0);
            test_chain_set_parents(c, parent);
            check_spec(c, 95 + (uint64_t)i, trials_for(n[i]), "random planar tree");
            test_chain_free(c);
            c = test_chain_random_planar(n[i], 91 + (uint64_t)i, 0, 1); /* slender rods */
            test_chain_set_parents(c, parent);
            check_spec(c, 96 + (uint64_t)i, trials_for(n[i]), "random planar rod tree");
            test_chain_free(c);
            free(parent);
        }
    }
}

Test(gdca_tree, planar_and_spatial_forms_agree)
{
    for (int i = 0; i < 3; i++) {
        const int n = 5 + 20 * i;
        int *parent = malloc((size_t)n * sizeof *parent);
        cr_assert(parent);
        test_random_parents(n, 120 + (uint64_t)i, 0.1, parent);
        test_chain *c = test_chain_random_planar(n, 130 + (uint64_t)i, 1, 0);
        test_chain_set_parents(c, parent);
        ctc_model *mp = build(&c->spec);
        c->spec.form = CTC_FORM_SPATIAL;
        ctc_model *ms = build(&c->spec);
        cr_assert_eq(mp->form, CTC_FORM_PLANAR);
        cr_assert_eq(ms->form, CTC_FORM_SPATIAL);
        ctc_data *dp = ctc_data_new(mp), *ds = ctc_data_new(ms);
        double q[64], v[64], f[64], ap[64], as[64], fp[64], fs[64];
        uint64_t rng = 140 + (uint64_t)i;
        test_random_state(mp, &rng, 2.0, q, v);
        for (int k = 0; k < mp->nv; k++) f[k] = test_uniform(&rng, -5, 5);
        ctc_kinematics(mp, dp, q, v), ctc_handles(mp, dp);
        ctc_kinematics(ms, ds, q, v), ctc_handles(ms, ds);
        ctc_gdca_forward(mp, dp, f, ap);
        ctc_gdca_forward(ms, ds, f, as);
        ctc_gdca_inverse(mp, dp, f, fp);
        ctc_gdca_inverse(ms, ds, f, fs);
        cr_assert_leq(test_rel_err(ap, as, mp->nv), 1e-10, "n=%d forward", n);
        cr_assert_leq(test_rel_err(fp, fs, mp->nv), 1e-10, "n=%d inverse", n);
        ctc_data_free(dp), ctc_data_free(ds);
        ctc_model_free(mp), ctc_model_free(ms);
        test_chain_free(c);
        free(parent);
    }
}

/* every body is a leaf of the plan once, every light child one operand of a SUM or RAKE node of
   its parent, every joint solved once; nodes come before their parents by height */
static void check_plan(const ctc_model *m, const char *what)
{
    const int n = m->nbodies;
    int *seen = calloc((size_t)(2 * n), sizeof *seen), *joint = calloc((size_t)n, sizeof *joint);
    cr_assert(seen && joint);
    for (int r = 0; r < m->nroots; r++) {
        seen[m->root_asm[r]]++;
        joint[m->root_joint[r]]++;
        cr_assert_eq(m->body_parent[m->root_joint[r]], -1, "%s", what);
    }
    for (int i = 0; i < m->ntree; i++) {
        const ctc_tree_node *t = &m->tree[i];
        int ops[2] = {t->left, t->right}, js[2] = {t->ljoint, t->rjoint};
        for (int o = 0; o < 2; o++) {
            if (ops[o] < 0) continue;
            seen[ops[o]]++;
            if (ops[o] >= n) cr_assert_lt(m->tree[ops[o] - n].height, t->height, "%s", what);
            if (js[o] >= 0) {
                joint[js[o]]++;
                cr_assert_eq(m->body_parent[js[o]], t->body, "%s: node %d", what, i);
                cr_assert_neq(m->body_heavy[t->body], js[o], "%s: node %d", what, i);
            }
        }
        if (t->kind == CTC_NODE_JOIN) {
            joint[t->joint]++;
            cr_assert_eq(t->ljoint, -1);
        }
    }
    for (int a = 0; a < n + m->ntree; a++) {
        const int leaf = a < n && m->body_child[a] >= 0 && m->body_heavy[a] >= 0 &&
                         m->body_sibling[m->body_child[a]] >= 0;
        /* a body with light children appears through its RAKE node instead */
        cr_assert_eq(seen[a], leaf ? 0 : 1, "%s: assembly index %d seen %d times", what, a,
                     seen[a]);
    }
    for (int k = 0; k < n; k++)
        cr_assert_eq(joint[k], 1, "%s: joint %d solved %d times", what, k, joint[k]);
    free(seen), free(joint);
}

Test(gdca_tree, plans_cover_every_body_and_joint_once_and_stay_logarithmic)
{
    const int n[] = {1, 2, 3, 10, 100, 1000, 4096};
    for (int i = 0; i < 7; i++) {
        int *parent = malloc((size_t)n[i] * sizeof *parent);
        cr_assert(parent);
        for (int shape = 0; shape < 5; shape++) {
            const char *names[] = {"chain", "star", "binary", "random", "caterpillar"};
            for (int k = 0; k < n[i]; k++) {
                switch (shape) {
                case 0:
                    parent[k] = k - 1;
                    break;
                case 1:
                    parent[k] = k ? 0 : -1;
                    break;
                case 2:
                    parent[k] = (k + 1) / 2 - 1;
                    break;
                case 3:
                    parent[k] = k ? (int)(((unsigned)k * 2654435761u >> 7) % (unsigned)k) : -1;
                    break;
                default:
                    parent[k] = k < 2 ? k - 1 : k % 2 ? k - 1 : k - 2;
                    break;
                }
            }
            test_chain *c = test_chain_random_planar(n[i], 7, 0, 0);
            test_chain_set_parents(c, parent);
            ctc_model *m = build(&c->spec);
            check_plan(m, names[shape]);
            const double lg = n[i] > 1 ? log2((double)n[i]) : 0;
            cr_assert_leq(m->height, (int)ceil(3 * lg) + 2, "%s n=%d: height %d", names[shape],
                          n[i], m->height);
            if (shape == 0) cr_assert_eq(m->height, (int)ceil(lg), "chain n=%d", n[i]);
            ctc_model_free(m);
            test_chain_free(c);
        }
        free(parent);
    }
}

/* the results of the three passes, bitwise, at 1, 2 and 8 threads (every height split) */
Test(gdca_tree, threads_give_bitwise_the_serial_results, .timeout = 120)
{
    const double bf[] = {2, 4, 1.5};
    for (int b = 0; b < 3; b++) {
        for (int s = 0; s < 2; s++) {
            test_chain *c = test_auto_tree(300, bf[b], s ? 0.3 : 0.0, 1.0);
            ctc_model *m = build(&c->spec);
            const int nv = m->nv;
            double *q = calloc((size_t)m->nq, 8), *v = calloc((size_t)nv, 8);
            double *u = calloc((size_t)nv, 8), *out[3][3];
            cr_assert(q && v && u);
            uint64_t rng = 200 + (uint64_t)b;
            test_random_state(m, &rng, 2.0, q, v);
            for (int i = 0; i < nv; i++) u[i] = test_uniform(&rng, -5, 5);
            const int threads[] = {1, 2, 8};
            for (int t = 0; t < 3; t++) {
                ctc_data *d = ctc_data_new(m);
                cr_assert_eq(ctc_data_set_threads(d, threads[t], NULL, 0), CTC_OK);
                d->opt.par_grain = 1;
                d->opt.fwd_order = CTC_ORDER_TREE; /* one thread's default is the sequential */
                for (int p = 0; p < 3; p++) out[t][p] = calloc((size_t)nv, 8);
                ctc_kinematics(m, d, q, v);
                ctc_handles(m, d);
                ctc_gdca_inverse(m, d, u, out[t][0]);
                ctc_gdca_inverse_mobility(m, d, u, out[t][1]);
                ctc_gdca_forward(m, d, u, out[t][2]);
                ctc_data_free(d);
            }
            for (int t = 1; t < 3; t++) {
                for (int p = 0; p < 3; p++) {
                    cr_assert(memcmp(out[0][p], out[t][p], (size_t)nv * 8) == 0,
                              "bf %g skew %d: pass %d differs at %d threads", bf[b], s, p,
                              threads[t]);
                }
            }
            for (int t = 0; t < 3; t++) {
                for (int p = 0; p < 3; p++) free(out[t][p]);
            }
            free(q), free(v), free(u);
            ctc_model_free(m);
            test_chain_free(c);
        }
    }
}

/* the Y tree of oracle_fixture.h (two rods hung from a third's tip) in closed form: the composite
   inverse gives tau = M a + h, the forward pass a = M^-1 (f - h), the mobility inverse tau */
Test(gdca_tree, y_tree_matches_its_closed_form)
{
    const double mass[3] = {1.3, 0.7, 0.9}, len[3] = {1.1, 0.8, 0.6};
    ctc_model *m;
    ctc_oracle *o = fx_make_y_tree(mass, len, &m);
    cr_assert_eq(m->form, CTC_FORM_PLANAR);
    cr_assert_eq(m->chain, 0);
    ctc_data *d = ctc_data_new(m);
    fx_rng rng = {31};
    const double zero[3] = {0, 0, 0};
    for (int s = 0; s < 100; s++) {
        double q[12], v[3], a[3], mm[9], want[3], bias[3], tau[3], acc[3], rhs[3];
        fx_random_state(&rng, m, q, v, a);
        fx_y_tree(mass, len, q, v, a, mm, want);
        fx_y_tree(mass, len, q, v, zero, mm, bias);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        ctc_gdca_inverse(m, d, a, tau);
        double scale = fmax(1.0, fx_max_abs(3, want));
        cr_assert_leq(fx_max_abs_diff(3, tau, want) / scale, 1e-13, "sample %d: inverse", s);
        ctc_gdca_inverse_mobility(m, d, a, tau);
        cr_assert_leq(fx_max_abs_diff(3, tau, want) / scale, 1e-12, "sample %d: mobility", s);
        ctc_gdca_forward(m, d, want, acc);
        /* M acc + h = tau: the closed form's own equations, solved by neither pass */
        for (int i = 0; i < 3; i++)
            rhs[i] = mm[3 * i] * acc[0] + mm[3 * i + 1] * acc[1] + mm[3 * i + 2] * acc[2] +
                     bias[i] - want[i];
        cr_assert_leq(fx_max_abs(3, rhs) / scale, 1e-12, "sample %d: forward", s);
    }
    ctc_data_free(d);
    ctc_oracle_free(o);
    ctc_model_free(m);
}

/* the refinement's bias-free correction (gdca_refine.h) through the rake: dq = M^-1 r, M from
   CRBA, on trees whose light subtrees carry every joint type */
Test(gdca_tree, correction_pass_solves_the_mass_matrix)
{
    for (int form = 0; form < 2; form++) {
        const int n = 23;
        int parent[23];
        test_random_parents(n, 150 + (uint64_t)form, 0.1, parent);
        test_chain *c = form ? test_chain_random_spatial(n, 61, TEST_ALL_JOINTS)
                             : test_chain_random_planar(n, 61, 1, 0);
        test_chain_set_parents(c, parent);
        ctc_model *m = build(&c->spec);
        cr_assert_eq(m->chain, 0);
        ctc_data *d = ctc_data_new(m);
        ctc_oracle *o = ctc_oracle_new(m);
        const int nv = m->nv;
        double *q = calloc((size_t)m->nq, 8), *v = calloc((size_t)nv, 8),
               *f = calloc((size_t)nv, 8);
        double *a = calloc((size_t)nv, 8), *r = calloc((size_t)nv, 8), *dq = calloc((size_t)nv, 8);
        double *ref = calloc((size_t)nv, 8), *mass = calloc((size_t)nv * (size_t)nv, 8);
        cr_assert(q && v && f && a && r && dq && ref && mass);
        uint64_t rng = 62;
        test_random_state(m, &rng, 2.0, q, v);
        for (int i = 0; i < nv; i++) f[i] = test_uniform(&rng, -5, 5);
        ctc_kinematics(m, d, q, v);
        ctc_handles(m, d);
        d->opt.fwd_refine = 0;
        ctc_gdca_forward(m, d, f, a);      /* the factors the correction reuses */
        gdca_forward_correct(m, d, r, dq); /* r = 0 */
        for (int i = 0; i < nv; i++) cr_assert_eq(dq[i], 0.0);
        for (int i = 0; i < nv; i++) r[i] = test_uniform(&rng, -5, 5);
        gdca_forward_correct(m, d, r, dq);
        ctc_oracle_mass_matrix(m, o, q, mass);
        cr_assert_eq(test_solve_spd(mass, nv, r, ref), 0);
        double err = test_rel_err(dq, ref, nv);
        cr_assert(err < 1e-11, "%s: M^-1 r off by %.3g", form ? "spatial" : "planar", err);
        free(q), free(v), free(f), free(a), free(r), free(dq), free(ref), free(mass);
        ctc_oracle_free(o);
        ctc_data_free(d);
        ctc_model_free(m);
        test_chain_free(c);
    }
}

/* a PD run of a spatial autoTree (bf 2, 1024 bodies: long enough for both passes to split and for
   the forward pass to take the plan on threads) from q0 = +-0.1 rad to rest, RK4, 20 steps */
static ctc_sim_result *tree_run(int threads)
{
    test_chain *c = test_auto_tree(1024, 2, 0.5, 1.0);
    ctc_sim_result *r = fixture_pd_to_rest(
        c, 0.1, 1.1, (ctc_integ_spec){.method = CTC_INTEG_RK4, .step = 1e-3}, 0.02, 0.01, threads);
    test_chain_free(c);
    return r;
}

/* One, two and three threads record the same samples of a CTC run on a tree to rounding. Not
   bitwise: each run's gates (pool.h) choose between the sequential order and the split plan by
   their own timings, so two runs may take different orders at some evaluations; that each order
   on threads gives bitwise its serial results is test_gdca_parallel's
   gated_passes_give_bitwise_the_serial_results_on_1_to_4_threads. */
Test(gdca_tree, a_simulation_on_threads_records_the_same_samples)
{
    ctc_sim_result *one = tree_run(0), *two = tree_run(2), *three = tree_run(3);
    cr_assert_eq(two->nsamples, three->nsamples);
    cr_assert_eq(one->nsamples, two->nsamples);
    for (int ch = 0; ch < CTC_NCHANNELS; ch++) {
        if (!two->ch[ch]) continue;
        double big, diff;
        fixture_channel_diff(one, two, (ctc_channel)ch, &diff, &big);
        cr_expect(diff <= 1e-8 * big, "channel %s: 1 and 2 threads differ by %.3g of %.3g",
                  ctc_channel_name((ctc_channel)ch), diff, big);
        fixture_channel_diff(two, three, (ctc_channel)ch, &diff, &big);
        cr_expect(diff <= 1e-8 * big, "channel %s: 2 and 3 threads differ by %.3g of %.3g",
                  ctc_channel_name((ctc_channel)ch), diff, big);
    }
    ctc_sim_result_free(one);
    ctc_sim_result_free(two);
    ctc_sim_result_free(three);
}
