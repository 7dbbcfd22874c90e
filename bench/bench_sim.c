/*
 * bench_sim.c - whole simulations: speed against error for every integrator on five scenes, how
 * honest each run's own accuracy figures are, what high gains do to the explicit and the
 * implicit method, and the energy drift of long passive runs.
 *
 * Every run is a job built from a preset (server/presets.c) with overrides, parsed by the job
 * format (server/job_json.h) and run by ctc_sim_run, so the bench runs exactly what a user
 * submits. Parts:
 *
 *  1. Work-precision: scenes triple pendulum PID (paper 7.1, 0.2 N m disturbance, 5 s), spatial
 *     double pendulum PID (7.1, 0.2 N m, 5 s), five-bar PD (7.2, closed chain, projection, 10 s),
 *     64-link pendulum PD (7.3, 5 s) and the passive triple pendulum (5 s). Integrators: rk4 at h =
 *     0.01 ... 0.0005 s, dopri5 and bdf at rtol 1e-4 ... 1e-10, atol = rtol / 100. The error of a
 *     run is max over its samples (every 0.01 s) and all chain coordinates of |q - q_ref| (for the
 *     five-bar: the three independent joints and the two dependent ones), q_ref from dopri5 at rtol
 *     1e-12, atol 1e-14; the reference's own error is gauged by a run at rtol 1e-11 against it. The
 *     five-bar also runs bdf with Baumgarte stabilisation instead of the projection (bdf projects
 *     inside CVODE's steps: src/sim/sim_rhs.c, src/integrate/integ_bdf.c). Each configuration runs
 *     once untimed (the warm-up, which also gives its error and metrics: the runs are
 *     deterministic), then in timed rounds that interleave every configuration of every scene, so
 *     machine noise falls on all alike; the wall time is the median over the rounds (ROUNDS,
 *     SLOW_ROUNDS for the 64-link chain). A configuration whose warm-up took over SLOW_RUN_S is
 *     timed by that run alone, and one that needs more than WP_MAX_STEPS steps is stopped there
 *     (the five-bar's bdf at tight tolerances), to keep the whole bench within a few minutes.
 *  2. Honesty: each run's own figures against the true error each can stand for. err_estimate
 *     (the integrator's summed local error estimates, over the whole state) and energy_drift
 *     (passive runs) against the true state error, max over the samples and all coordinates of
 *     |q - q_ref| and |qdot - qdot_ref|; errdyn_dev (position deviation from the closed-form
 *     error dynamics; exact model, no disturbance: five-bar, 64-link) and loop_res_max
 *     (five-bar) against max |q - q_ref| over the controlled coordinates (the five-bar's
 *     independent joints).
 *  3. Stiff gains: the triple pendulum PD preset, no disturbance, 5 s, kp = 1e2 ... 1e10 with
 *     kv = 2 sqrt(kp), dopri5 and bdf at rtol 1e-8 and 1e-4; the error against the closed-form
 *     error dynamics e = (e0 + (de0 + w e0) t) exp(-w t), w = sqrt(kp). One run each.
 *  4. Long passive runs: 1000 s of the passive triple pendulum, samples every 0.1 s, energy
 *     drift and wall time per integrator and setting; the wall time is the median of
 *     LONG_ROUNDS interleaved runs.
 *
 * Prints markdown tables and writes two SVG figures (bench/svgplot.h) into the directory given
 * as the first argument (default build): work_precision.svg (parts 1 and 3) and
 * estimates_vs_error.svg (part 2). "--quick" as an argument: one timed round, part 4 over 100 s,
 * part 3 without kp 1e10 - for trying changes, not for the notebook's figures.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "sim.h"
#include "svgplot.h"

#define PI 3.14159265358979323846
#define ROUNDS 9      /* timed rounds */
#define SLOW_ROUNDS 3 /* for the 64-link chain */
#define MAX_CONFIGS 17
#define NSCENES 5
#define NSERIES 4           /* rk4, dopri5, bdf, and bdf with a scene variant */
#define SLOW_RUN_S 1.0      /* a warm-up run longer than this is its configuration's only timing */
#define WP_MAX_STEPS 150000 /* a run that needs more stops (and shows as failed) */

typedef struct config {
    char label[48];
    int series; /* 0..2: the method (ctc_integ_method); 3: bdf on the scene's variant */
    ctc_integ_method method;
    double param; /* rk4: step (s); dopri5, bdf: rtol */
    job *job;
    int slow;            /* its warm-up run took over SLOW_RUN_S and is its only timing */
    double wall[ROUNDS]; /* s, the timings */
    int nwall;
    ctc_run_status status;
    char message[256];
    long steps, evals;
    /* true errors: max |q - q_ref| over all coordinates, over the controlled ones (the
     * independent joints of a loop), and max over q and qdot */
    double err_q, err_ctrl, err_state;
    double err_estimate, errdyn_dev, energy_drift, loop_res_max;
} config;

typedef struct scene {
    const char *key;          /* short name: legends */
    const char *title;        /* heading */
    const char *json;         /* the job's keys before "integrator" and "output" */
    const char *colour;       /* in the honesty figure */
    const char *variant_json; /* keys for series 3 (bdf), NULL = none */
    const char *variant_name; /* its legend */
    int rounds;
    int n;
    config c[MAX_CONFIGS];
    ctc_sim_result *ref;
    long ref_steps;
    double ref_check; /* max |q(rtol 1e-11) - q_ref| */
} scene;

static const char *const series_colour[NSERIES] = {"#1b6ac9", "#d1495b", "#2e8b57", "#9b59b6"};
static const svg_marker series_marker[NSERIES] = {SVG_CIRCLE, SVG_SQUARE, SVG_TRIANGLE,
                                                  SVG_DIAMOND};

/* ---- jobs ---- */

static job *make_job(const char *keys, const char *integrator, const char *output)
{
    char text[2048];
    snprintf(text, sizeof text, "{%s, \"integrator\": %s, \"output\": %s}", keys, integrator,
             output);
    job *j = NULL;
    job_error jerr = {0};
    if (job_parse(text, strlen(text), &j, &jerr) != 0) {
        fprintf(stderr, "bench_sim: bad job %s: %s: %s\n", text, jerr.field, jerr.message);
        exit(1);
    }
    return j;
}

/* the integrator object; max_steps > 0 is written out */
static void integrator_json(char *buf, size_t len, ctc_integ_method m, double param, long max_steps)
{
    char limit[48] = "";
    if (max_steps > 0) snprintf(limit, sizeof limit, ", \"max_steps\": %ld", max_steps);
    if (m == CTC_INTEG_RK4) {
        snprintf(buf, len, "{\"method\": \"rk4\", \"step\": %g%s}", param, limit);
    } else {
        snprintf(buf, len, "{\"method\": \"%s\", \"rtol\": %g, \"atol\": %g%s}",
                 ctc_integ_method_name(m), param, param / 100, limit);
    }
}

/* runs a job; a run that does not finish is returned too (its status says so) */
static ctc_sim_result *run_job(const job *j)
{
    ctc_sim_result *r = NULL;
    char err[256];
    if (ctc_sim_run(&j->spec, NULL, &r, err, sizeof err) != CTC_OK) {
        fprintf(stderr, "bench_sim: %s\n", err);
        exit(1);
    }
    return r;
}

static const char *const wp_output = "{\"interval\": 0.01, \"channels\": [\"q\", \"qdot\"]}";

/* max over samples and the columns of channel ch with keep[col] non-zero (keep NULL: all) of
 * |a - b| */
static double max_diff(const ctc_sim_result *a, const ctc_sim_result *b, ctc_channel ch,
                       const unsigned char *keep)
{
    double e = 0;
    int w = a->width[ch];
    if (a->nsamples != b->nsamples || w != b->width[ch]) return NAN;
    for (int k = 0; k < a->nsamples; k++)
        for (int i = 0; i < w; i++)
            if (!keep || keep[i]) e = fmax(e, fabs(a->ch[ch][k * w + i] - b->ch[ch][k * w + i]));
    return e;
}

/* ---- statistics ---- */

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median(const double *x, int n)
{
    double s[ROUNDS];
    memcpy(s, x, (size_t)n * sizeof *x);
    qsort(s, (size_t)n, sizeof *s, cmp_double);
    return n % 2 ? s[n / 2] : 0.5 * (s[n / 2 - 1] + s[n / 2]);
}

/* ---- part 1 and 2: work-precision and honesty ---- */

static void add_config(scene *s, int series, ctc_integ_method m, double param)
{
    config *c = &s->c[s->n++];
    c->series = series, c->method = m, c->param = param;
    if (m == CTC_INTEG_RK4) {
        snprintf(c->label, sizeof c->label, "rk4 h = %g", param);
    } else {
        snprintf(c->label, sizeof c->label, "%s rtol = %g",
                 series == 3 ? s->variant_name : ctc_integ_method_name(m), param);
    }
    char integ[160], keys[512];
    integrator_json(integ, sizeof integ, m, param, WP_MAX_STEPS);
    snprintf(keys, sizeof keys, "%s%s", s->json, series == 3 ? s->variant_json : "");
    c->job = make_job(keys, integ, wp_output);
}

static void scene_setup(scene *s, int rounds)
{
    static const double steps[] = {0.01, 0.005, 0.002, 0.001, 0.0005};
    static const double tols[] = {1e-4, 1e-6, 1e-8, 1e-10};
    s->rounds = rounds;
    s->n = 0;
    for (int i = 0; i < 5; i++) add_config(s, 0, CTC_INTEG_RK4, steps[i]);
    for (int m = CTC_INTEG_DOPRI5; m <= CTC_INTEG_BDF; m++)
        for (int i = 0; i < 4; i++) add_config(s, m, (ctc_integ_method)m, tols[i]);
    if (s->variant_json)
        for (int i = 0; i < 4; i++) add_config(s, 3, CTC_INTEG_BDF, tols[i]);

    /* the reference, and a run one decade looser to gauge it */
    job *jr =
        make_job(s->json, "{\"method\": \"dopri5\", \"rtol\": 1e-12, \"atol\": 1e-14}", wp_output);
    job *jc =
        make_job(s->json, "{\"method\": \"dopri5\", \"rtol\": 1e-11, \"atol\": 1e-13}", wp_output);
    s->ref = run_job(jr);
    ctc_sim_result *chk = run_job(jc);
    if (s->ref->status != CTC_RUN_DONE || chk->status != CTC_RUN_DONE) {
        fprintf(stderr, "bench_sim: %s: reference run failed: %s%s\n", s->title, s->ref->message,
                chk->message);
        exit(1);
    }
    s->ref_steps = s->ref->metrics.steps;
    s->ref_check = max_diff(chk, s->ref, CTC_CH_Q, NULL);
    ctc_sim_result_free(chk);

    /* the controlled coordinates' columns of q: a loop's independent joints (one q each in
     * these scenes), every column of an open chain */
    static unsigned char keep[64];
    const unsigned char *ctrl = NULL;
    if (jr->independent && jr->nq == jr->spec.chain.nbodies && jr->nq <= 64) {
        for (int i = 0; i < jr->nq; i++) keep[i] = jr->independent[i];
        ctrl = keep;
    }

    /* the untimed warm-up run of each configuration gives its errors and figures; a slow one
     * is timed by it alone */
    for (int i = 0; i < s->n; i++) {
        config *c = &s->c[i];
        ctc_sim_result *r = run_job(c->job);
        c->status = r->status;
        snprintf(c->message, sizeof c->message, "%s", r->message);
        c->steps = r->metrics.steps;
        c->evals = r->metrics.rhs_evals;
        c->err_estimate = r->metrics.err_estimate;
        c->errdyn_dev = r->metrics.errdyn_dev;
        c->energy_drift = r->metrics.energy_drift;
        c->loop_res_max = r->metrics.loop_res_max;
        c->err_q = c->err_ctrl = c->err_state = NAN;
        if (r->status == CTC_RUN_DONE) {
            c->err_q = max_diff(r, s->ref, CTC_CH_Q, NULL);
            c->err_ctrl = ctrl ? max_diff(r, s->ref, CTC_CH_Q, ctrl) : c->err_q;
            c->err_state = fmax(c->err_q, max_diff(r, s->ref, CTC_CH_QD, NULL));
        }
        c->slow = r->metrics.wall_s > SLOW_RUN_S;
        c->nwall = 0;
        if (c->slow) c->wall[c->nwall++] = r->metrics.wall_s;
        ctc_sim_result_free(r);
    }
    job_free(jr);
    job_free(jc);
}

/* one timed run of every configuration not timed by its warm-up */
static void scene_time_round(scene *s, int round)
{
    if (round >= s->rounds) return;
    for (int i = 0; i < s->n; i++) {
        config *c = &s->c[i];
        if (c->slow) continue;
        ctc_sim_result *r = run_job(c->job);
        c->wall[c->nwall++] = r->metrics.wall_s;
        ctc_sim_result_free(r);
    }
}

static void scene_print(const scene *s)
{
    printf("### %s\n\nReference: dopri5 at rtol 1e-12 (%ld steps); dopri5 at rtol 1e-11 is "
           "%.1e rad from it. Wall time: median of %d interleaved runs (runs over %g s: one).\n\n",
           s->title, s->ref_steps, s->ref_check, s->rounds, SLOW_RUN_S);
    printf("| integrator | wall (ms) | steps | rhs evals | us / eval | max error q (rad) |\n"
           "| --- | ---: | ---: | ---: | ---: | ---: |\n");
    for (int i = 0; i < s->n; i++) {
        const config *c = &s->c[i];
        double wall = median(c->wall, c->nwall);
        char result[300];
        if (c->status == CTC_RUN_DONE) {
            snprintf(result, sizeof result, "%.2e", c->err_q);
        } else {
            snprintf(result, sizeof result, "%s: %s", ctc_run_status_name(c->status), c->message);
        }
        printf("| %s | %.2f%s | %ld | %ld | %.2f | %s |\n", c->label, wall * 1e3,
               c->nwall == 1 ? " (1 run)" : "", c->steps, c->evals, wall * 1e6 / (double)c->evals,
               result);
    }
    printf("\n");
}

/* "1.2e-08 (0.31)": a figure and its ratio to the true error; "-" when it does not apply */
static void figure_cell(char *buf, size_t len, double figure, double truth)
{
    if (isnan(figure)) {
        snprintf(buf, len, "-");
    } else {
        snprintf(buf, len, "%.1e (%.2g)", figure, figure / truth);
    }
}

static void print_honesty(const scene *sc, int nscenes)
{
    printf("### Each run's own figures against its true error\n\n"
           "err (q, qdot): max over the samples and all coordinates of |q - q_ref| and "
           "|qdot - qdot_ref|; err q: max |q - q_ref| over the controlled coordinates (the "
           "independent joints of the five-bar). In brackets, each figure's ratio to the true "
           "error it stands for (below 1: it under-reports): err_estimate and energy_drift "
           "against err (q, qdot), errdyn_dev and loop_res_max against err q.\n\n"
           "| scene | integrator | err (q, qdot) | err q | err_estimate | errdyn_dev | "
           "energy_drift | loop_res_max |\n"
           "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    for (int k = 0; k < nscenes; k++)
        for (int i = 0; i < sc[k].n; i++) {
            const config *c = &sc[k].c[i];
            if (c->status != CTC_RUN_DONE) continue;
            char est[40], dev[40], drift[40], loop[40];
            figure_cell(est, sizeof est, c->err_estimate, c->err_state);
            figure_cell(dev, sizeof dev, c->errdyn_dev, c->err_ctrl);
            figure_cell(drift, sizeof drift, c->energy_drift, c->err_state);
            figure_cell(loop, sizeof loop, c->loop_res_max, c->err_ctrl);
            printf("| %s | %s | %.1e | %.1e | %s | %s | %s | %s |\n", sc[k].key, c->label,
                   c->err_state, c->err_ctrl, est, dev, drift, loop);
        }
    printf("\n");
}

/* ---- part 3: stiff gains ---- */

#define NKP 5
#define NSTIFF (NKP * 4)

typedef struct stiff_run {
    double kp, rtol;
    ctc_integ_method method;
    ctc_run_status status;
    char message[256];
    long steps;
    double wall, t_end, deviation;
} stiff_run;

/* max over samples and joints of |q - (q_d - e)| with the closed-form error of a critically
 * damped PD loop (kv = 2 sqrt(kp)) from the triple pendulum preset's start at rest */
static double closed_form_deviation(const ctc_sim_result *r, double kp)
{
    const double w = sqrt(kp), a = 0.6, omega = 2 * PI / 1.5;
    const double q0[3] = {5 * PI / 6, 3 * PI / 4, 2 * PI / 3};
    double worst = 0;
    for (int k = 0; k < r->nsamples; k++) {
        const double t = r->t[k];
        for (int i = 0; i < 3; i++) {
            double qd = i == 1 ? a * cos(omega * t) : a * sin(omega * t);
            double e0 = (i == 1 ? a : 0) - q0[i], de0 = i == 1 ? 0 : a * omega;
            double e = (e0 + (de0 + w * e0) * t) * exp(-w * t);
            worst = fmax(worst, fabs(r->ch[CTC_CH_Q][3 * k + i] - (qd - e)));
        }
    }
    return worst;
}

static int stiff_sweep(stiff_run *out, int quick)
{
    static const double kps[NKP] = {1e2, 1e4, 1e6, 1e8, 1e10};
    static const double rtols[2] = {1e-8, 1e-4};
    int n = 0;
    for (int ir = 0; ir < 2; ir++)
        for (int m = CTC_INTEG_DOPRI5; m <= CTC_INTEG_BDF; m++)
            for (int k = 0; k < NKP; k++) {
                if (quick && kps[k] > 1e8) continue;
                char keys[512], integ[128];
                snprintf(keys, sizeof keys,
                         "\"preset\": \"triple_pendulum_pd\", \"controller\": {\"kp\": %g, "
                         "\"kv\": %.17g}, \"disturbance\": {\"type\": \"none\"}, "
                         "\"duration\": 5",
                         kps[k], 2 * sqrt(kps[k]));
                integrator_json(integ, sizeof integ, (ctc_integ_method)m, rtols[ir], 0);
                job *j = make_job(keys, integ, "{\"interval\": 0.01, \"channels\": [\"q\"]}");
                ctc_sim_result *r = run_job(j);
                stiff_run *s = &out[n++];
                *s = (stiff_run){.kp = kps[k],
                                 .rtol = rtols[ir],
                                 .method = (ctc_integ_method)m,
                                 .status = r->status,
                                 .steps = r->metrics.steps,
                                 .wall = r->metrics.wall_s,
                                 .t_end = r->metrics.t_end,
                                 .deviation = closed_form_deviation(r, kps[k])};
                snprintf(s->message, sizeof s->message, "%s", r->message);
                ctc_sim_result_free(r);
                job_free(j);
            }
    return n;
}

static void print_stiff(const stiff_run *s, int n)
{
    printf("### Stiff gains: triple pendulum PD, no disturbance, 5 s, kv = 2 sqrt(kp)\n\n"
           "Error: max over the samples and joints of |q - q_closed|, the closed-form motion of "
           "the exact error dynamics. h sqrt(kp): the mean step (time reached / steps) times the "
           "double pole's |lambda|. One run each.\n\n"
           "| kp | integrator | status | steps | wall (ms) | h sqrt(kp) | max error q (rad) |\n"
           "| ---: | --- | --- | ---: | ---: | ---: | ---: |\n");
    for (int i = 0; i < n; i++) {
        char status[300];
        if (s[i].status == CTC_RUN_DONE) {
            snprintf(status, sizeof status, "done");
        } else {
            snprintf(status, sizeof status, "%s at t = %.3g s", ctc_run_status_name(s[i].status),
                     s[i].t_end);
        }
        printf("| %.0e | %s rtol = %g | %s | %ld | %.1f | %.2f | %.1e |\n", s[i].kp,
               ctc_integ_method_name(s[i].method), s[i].rtol, status, s[i].steps, s[i].wall * 1e3,
               s[i].t_end / (double)s[i].steps * sqrt(s[i].kp), s[i].deviation);
    }
    for (int i = 0; i < n; i++)
        if (s[i].status != CTC_RUN_DONE)
            printf("\nkp %.0e, %s rtol = %g: %s\n", s[i].kp, ctc_integ_method_name(s[i].method),
                   s[i].rtol, s[i].message);
    printf("\n");
}

/* ---- part 4: long passive runs ---- */

#define LONG_RUNS 6
#define LONG_ROUNDS 3

static void long_passive(int quick)
{
    static const struct {
        ctc_integ_method m;
        double param;
    } runs[LONG_RUNS] = {{CTC_INTEG_RK4, 1e-2},     {CTC_INTEG_RK4, 1e-3},
                         {CTC_INTEG_DOPRI5, 1e-6},  {CTC_INTEG_DOPRI5, 1e-8},
                         {CTC_INTEG_DOPRI5, 1e-10}, {CTC_INTEG_BDF, 1e-8}};
    const double duration = quick ? 100 : 1000;
    const int rounds = quick ? 1 : LONG_ROUNDS;
    char keys[256];
    snprintf(keys, sizeof keys, "\"preset\": \"triple_pendulum_passive\", \"duration\": %g",
             duration);
    job *jobs[LONG_RUNS];
    double wall[LONG_RUNS][ROUNDS];
    ctc_sim_result *last[LONG_RUNS] = {NULL};
    for (int i = 0; i < LONG_RUNS; i++) {
        char integ[128];
        integrator_json(integ, sizeof integ, runs[i].m, runs[i].param, 0);
        jobs[i] = make_job(keys, integ, "{\"interval\": 0.1, \"channels\": [\"q\"]}");
    }
    /* interleaved: every setting once per round; the last round's result is reported */
    for (int round = 0; round < rounds; round++)
        for (int i = 0; i < LONG_RUNS; i++) {
            ctc_sim_result_free(last[i]);
            last[i] = run_job(jobs[i]);
            wall[i][round] = last[i]->metrics.wall_s;
        }

    printf("### Passive triple pendulum, %g s: energy drift\n\n"
           "Energy drift: max over the samples (every 0.1 s) of |E(t) - E(0)| / max(|E(0)|, "
           "max kinetic energy). Wall time: median of %d interleaved runs.\n\n"
           "| integrator | steps | rhs evals | wall (s) | energy drift |\n"
           "| --- | ---: | ---: | ---: | ---: |\n",
           duration, rounds);
    for (int i = 0; i < LONG_RUNS; i++) {
        const ctc_sim_result *r = last[i];
        char label[64], drift[300];
        snprintf(label, sizeof label, "%s %s = %g", ctc_integ_method_name(runs[i].m),
                 runs[i].m == CTC_INTEG_RK4 ? "h" : "rtol", runs[i].param);
        if (r->status == CTC_RUN_DONE) {
            snprintf(drift, sizeof drift, "%.1e", r->metrics.energy_drift);
        } else {
            snprintf(drift, sizeof drift, "%s: %s", ctc_run_status_name(r->status), r->message);
        }
        printf("| %s | %ld | %ld | %.2f | %s |\n", label, r->metrics.steps, r->metrics.rhs_evals,
               median(wall[i], rounds), drift);
        ctc_sim_result_free(last[i]);
        job_free(jobs[i]);
    }
    printf("\n");
}

/* ---- figures ---- */

/* the points of one panel's series; static storage for the figure being written */
typedef struct series_points {
    double x[NSTIFF > MAX_CONFIGS ? NSTIFF : MAX_CONFIGS];
    double y[NSTIFF > MAX_CONFIGS ? NSTIFF : MAX_CONFIGS];
} series_points;

static const char *series_name(const scene *s, int series)
{
    return series == 3 ? s->variant_name : ctc_integ_method_name((ctc_integ_method)series);
}

static void write_work_precision(const char *path, const scene *sc, int nscenes,
                                 const stiff_run *st, int nst)
{
    static series_points pts[NSCENES + 1][NSERIES];
    static svg_series series[NSCENES + 1][NSERIES];
    svg_panel panels[NSCENES + 1];
    for (int k = 0; k < nscenes; k++) {
        int ns = 0;
        for (int m = 0; m < NSERIES; m++) {
            int n = 0;
            for (int i = 0; i < sc[k].n; i++) {
                const config *c = &sc[k].c[i];
                if (c->series != m || c->status != CTC_RUN_DONE) continue;
                pts[k][m].x[n] = median(c->wall, c->nwall) * 1e3;
                pts[k][m].y[n] = c->err_q;
                n++;
            }
            if (m == 3 && !sc[k].variant_json) continue;
            series[k][ns++] = (svg_series){.label = series_name(&sc[k], m),
                                           .colour = series_colour[m],
                                           .marker = series_marker[m],
                                           .joined = 1,
                                           .n = n,
                                           .x = pts[k][m].x,
                                           .y = pts[k][m].y};
        }
        panels[k] = (svg_panel){.title = sc[k].title,
                                .xlabel = "wall time per run (ms)",
                                .ylabel = "max |q - q_ref| (rad)",
                                .nseries = ns,
                                .series = series[k]};
    }

    /* stiff gains: wall time against kp, one series per method and rtol */
    static const char *const labels[4] = {"dopri5 1e-8", "bdf 1e-8", "dopri5 1e-4", "bdf 1e-4"};
    static const char *const colours[4] = {"#d1495b", "#2e8b57", "#f4a3ae", "#8fd19e"};
    for (int s = 0; s < 4; s++) {
        double rtol = s < 2 ? 1e-8 : 1e-4;
        ctc_integ_method m = s % 2 ? CTC_INTEG_BDF : CTC_INTEG_DOPRI5;
        int n = 0;
        for (int i = 0; i < nst; i++)
            if (st[i].rtol == rtol && st[i].method == m) {
                pts[nscenes][s].x[n] = st[i].kp;
                /* a run that stopped counts as the time it took to stop */
                pts[nscenes][s].y[n] = st[i].wall * 1e3;
                n++;
            }
        series[nscenes][s] = (svg_series){.label = labels[s],
                                          .colour = colours[s],
                                          .marker = series_marker[m],
                                          .joined = 1,
                                          .n = n,
                                          .x = pts[nscenes][s].x,
                                          .y = pts[nscenes][s].y};
    }
    panels[nscenes] = (svg_panel){.title = "Stiff gains: triple pendulum PD, 5 s",
                                  .xlabel = "kp (kv = 2 sqrt(kp))",
                                  .ylabel = "wall time per run (ms)",
                                  .nseries = 4,
                                  .series = series[nscenes]};
    svg_write_figure(path, 3, nscenes + 1, panels);
}

/* one panel per figure, one series per scene and integrator series that has it */
static void write_honesty(const char *path, const scene *sc, int nscenes)
{
    enum { NFIG = 4, NSER = NSCENES * NSERIES };
    static const char *const names[NFIG] = {"err_estimate", "errdyn_dev", "energy_drift",
                                            "loop_res_max"};
    static const char *const xlabels[NFIG] = {
        "true error, max over q and qdot", "true error, max |q - q_ref| (controlled)",
        "true error, max over q and qdot", "true error, max |q - q_ref| (controlled)"};
    static const char *const ylabels[NFIG] = {"err_estimate (summed local estimates)",
                                              "errdyn_dev (rad)", "energy_drift (relative)",
                                              "loop_res_max (m)"};
    static series_points pts[NFIG][NSER];
    static svg_series series[NFIG][NSER];
    static char labels[NFIG][NSER][48];
    svg_panel panels[NFIG];
    for (int f = 0; f < NFIG; f++) {
        int ns = 0;
        for (int k = 0; k < nscenes; k++)
            for (int m = 0; m < NSERIES; m++) {
                int n = 0;
                for (int i = 0; i < sc[k].n; i++) {
                    const config *c = &sc[k].c[i];
                    if (c->series != m || c->status != CTC_RUN_DONE) continue;
                    double fig = f == 0   ? c->err_estimate
                                 : f == 1 ? c->errdyn_dev
                                 : f == 2 ? c->energy_drift
                                          : c->loop_res_max;
                    if (isnan(fig)) continue;
                    pts[f][ns].x[n] = f % 2 ? c->err_ctrl : c->err_state;
                    pts[f][ns].y[n] = fig;
                    n++;
                }
                if (n == 0) continue;
                snprintf(labels[f][ns], sizeof labels[f][ns], "%s %s", sc[k].key,
                         series_name(&sc[k], m));
                series[f][ns] = (svg_series){.label = labels[f][ns],
                                             .colour = sc[k].colour,
                                             .marker = series_marker[m],
                                             .n = n,
                                             .x = pts[f][ns].x,
                                             .y = pts[f][ns].y};
                ns++;
            }
        panels[f] = (svg_panel){.title = names[f],
                                .xlabel = xlabels[f],
                                .ylabel = ylabels[f],
                                .diagonal = 1,
                                .nseries = ns,
                                .series = series[f]};
    }
    svg_write_figure(path, 2, NFIG, panels);
}

int main(int argc, char **argv)
{
    const char *dir = "build";
    int quick = 0;
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--quick") == 0) {
            quick = 1;
        } else {
            dir = argv[i];
        }
    }
    static scene sc[NSCENES] = {
        {.key = "triple",
         .title = "Triple pendulum, PID, 0.2 N m, 5 s",
         .json = "\"preset\": \"triple_pendulum_pid\"",
         .colour = "#1b6ac9"},
        {.key = "spatial",
         .title = "Spatial double pendulum, PID, 0.2 N m, 5 s",
         .json = "\"preset\": \"spatial_double_pendulum_pid\"",
         .colour = "#d1495b"},
        {.key = "five-bar",
         .title = "Five-bar (closed chain), PD, 10 s",
         .json = "\"preset\": \"five_bar_pd\"",
         .colour = "#2e8b57",
         .variant_json = ", \"scene\": {\"loop\": {\"stabilization\": {\"method\": "
                         "\"baumgarte\"}}}",
         .variant_name = "bdf+Baumgarte"},
        {.key = "64-link",
         .title = "64-link pendulum, PD, 5 s",
         .json = "\"preset\": \"n_link_pendulum\", \"n\": 64",
         .colour = "#8e44ad"},
        {.key = "passive",
         .title = "Passive triple pendulum, 5 s",
         .json = "\"preset\": \"triple_pendulum_passive\"",
         .colour = "#e67e22"},
    };
    for (int k = 0; k < NSCENES; k++) {
        int rounds = quick ? 1 : k == 3 ? SLOW_ROUNDS : ROUNDS;
        scene_setup(&sc[k], rounds);
    }
    for (int round = 0; round < ROUNDS; round++)
        for (int k = 0; k < NSCENES; k++) scene_time_round(&sc[k], round);

    printf("## Whole simulations: speed against error\n\n");
    for (int k = 0; k < NSCENES; k++) scene_print(&sc[k]);
    print_honesty(sc, NSCENES);

    static stiff_run st[NSTIFF];
    int nst = stiff_sweep(st, quick);
    print_stiff(st, nst);
    long_passive(quick);

    char path[1024];
    snprintf(path, sizeof path, "%s/work_precision.svg", dir);
    write_work_precision(path, sc, NSCENES, st, nst);
    printf("plots: %s", path);
    snprintf(path, sizeof path, "%s/estimates_vs_error.svg", dir);
    write_honesty(path, sc, NSCENES);
    printf(", %s\n", path);

    for (int k = 0; k < NSCENES; k++) {
        for (int i = 0; i < sc[k].n; i++) job_free(sc[k].c[i].job);
        ctc_sim_result_free(sc[k].ref);
    }
    return 0;
}
