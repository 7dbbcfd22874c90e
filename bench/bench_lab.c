/*
 * bench_lab.c - the tracking error of the lab plant (issue 21): how much a sampled controller and
 * an unmodelled payload cost computed torque control, for PD, PID and LQR on the paper's triple
 * pendulum (sec. 7.1: sines, 0.2 N m disturbance, 5 s).
 *
 * Every run is a job built from the preset triple_pendulum_{pd,pid,lqr} with overrides, parsed
 * by the job format and run by ctc_sim_run, as a user submits it. Parts:
 *
 *  1. Sample rate: the controller sampled with zero-order hold at 1000, 500, 200, 100, 50 and
 *     20 Hz, exact model. Reported: the RMS over the samples (every 0.01 s) and the three joints
 *     of e, and metrics.error_by_cause.sampling (the RMS of e(sampled) - e(continuous), mean over
 *     the joints), with the continuous controller's RMS error as the reference row; a run that
 *     diverges is marked so.
 *  2. Payload error: a point mass of 0.05 ... 2 kg at the tip of body 3 (1 m along it) that the
 *     continuous controller's model lacks. Reported: the RMS error and error_by_cause.model.
 *
 * Prints markdown tables (bench/NOTEBOOK.md, "The lab plant") and writes lab_error.svg into the
 * directory given as the first argument (default build): the error caused by sampling against
 * the sample period, and by the payload against its mass, one series per controller. The runs
 * are deterministic; no timing is taken.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_json.h"
#include "sim.h"
#include "svgplot.h"

#define NCTRL 3
#define NRATE 6
#define NMASS 6

static const char *const ctrl_name[NCTRL] = {"pd", "pid", "lqr"};
static const char *const ctrl_colour[NCTRL] = {"#1b6ac9", "#d1495b", "#2e8b57"};
static const svg_marker ctrl_marker[NCTRL] = {SVG_CIRCLE, SVG_SQUARE, SVG_TRIANGLE};
static const double rate_hz[NRATE] = {1000, 500, 200, 100, 50, 20};
static const double payload_kg[NMASS] = {0.05, 0.1, 0.2, 0.5, 1, 2};

/* one run's figures, mean over the joints; NaN when it did not finish */
typedef struct lab_run {
    double e_rms, cause;
    ctc_run_status status;
} lab_run;

/* runs the job text; cause: the row of error_by_cause to report */
static lab_run run_job(const char *text, int cause)
{
    lab_run out = {NAN, NAN, CTC_RUN_FAILED};
    job *j = NULL;
    job_error err;
    if (job_parse(text, strlen(text), &j, &err) != 0) {
        fprintf(stderr, "bench_lab: job refused at %s: %s\n", err.field, err.message);
        exit(1);
    }
    ctc_sim_result *r = NULL;
    char msg[256];
    if (ctc_sim_run(&j->spec, NULL, &r, msg, sizeof msg) != CTC_OK) {
        fprintf(stderr, "bench_lab: %s\n", msg);
        exit(1);
    }
    out.status = r->status;
    if (r->status == CTC_RUN_DONE) {
        double e = 0, c = 0;
        for (int i = 0; i < r->nind; i++) {
            e += r->metrics.e_rms[i] / r->nind;
            c += r->metrics.err_cause[(size_t)cause * (size_t)r->nind + (size_t)i] / r->nind;
        }
        out.e_rms = e, out.cause = c;
    }
    ctc_sim_result_free(r);
    job_free(j);
    return out;
}

static void print_cell(const lab_run *r, int cause)
{
    if (r->status != CTC_RUN_DONE)
        printf(" | %s | –", ctc_run_status_name(r->status));
    else
        printf(" | %.3g | %.3g", r->e_rms, cause ? r->cause : 0.0);
}

int main(int argc, char **argv)
{
    const char *dir = argc > 1 ? argv[1] : "build";
    static lab_run rate[NCTRL][NRATE], cont[NCTRL], mass[NCTRL][NMASS];
    char text[512];

    /* part 1: sample rate */
    for (int c = 0; c < NCTRL; c++) {
        snprintf(text, sizeof text, "{\"preset\": \"triple_pendulum_%s\"}", ctrl_name[c]);
        cont[c] = run_job(text, CTC_CAUSE_SAMPLING);
        for (int k = 0; k < NRATE; k++) {
            snprintf(text, sizeof text,
                     "{\"preset\": \"triple_pendulum_%s\", \"controller\": {\"sample_period\": "
                     "%.17g}}",
                     ctrl_name[c], 1 / rate_hz[k]);
            rate[c][k] = run_job(text, CTC_CAUSE_SAMPLING);
        }
    }
    printf("## Part 1: tracking error against the sample rate (triple pendulum, 5 s)\n\n");
    printf("RMS of e over the samples and joints, rad; and error_by_cause.sampling, rad\n\n");
    printf("| rate (Hz) | PD e_rms | PD sampling | PID e_rms | PID sampling | LQR e_rms | LQR "
           "sampling |\n| ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    printf("| continuous");
    for (int c = 0; c < NCTRL; c++) print_cell(&cont[c], 0);
    printf(" |\n");
    for (int k = 0; k < NRATE; k++) {
        printf("| %g", rate_hz[k]);
        for (int c = 0; c < NCTRL; c++) print_cell(&rate[c][k], 1);
        printf(" |\n");
    }

    /* part 2: payload error */
    for (int c = 0; c < NCTRL; c++)
        for (int k = 0; k < NMASS; k++) {
            snprintf(text, sizeof text,
                     "{\"preset\": \"triple_pendulum_%s\", \"controller\": {\"model\": "
                     "{\"payload\": {\"body\": 2, \"mass\": %.17g, \"point\": [0, -1, 0]}}}}",
                     ctrl_name[c], payload_kg[k]);
            mass[c][k] = run_job(text, CTC_CAUSE_MODEL);
        }
    printf("\n## Part 2: tracking error against an unmodelled payload at the tip (5 s)\n\n");
    printf("RMS of e over the samples and joints, rad; and error_by_cause.model, rad\n\n");
    printf("| payload (kg) | PD e_rms | PD model | PID e_rms | PID model | LQR e_rms | LQR model "
           "|\n| ---: | ---: | ---: | ---: | ---: | ---: | ---: |\n");
    printf("| 0");
    for (int c = 0; c < NCTRL; c++) print_cell(&cont[c], 0);
    printf(" |\n");
    for (int k = 0; k < NMASS; k++) {
        printf("| %g", payload_kg[k]);
        for (int c = 0; c < NCTRL; c++) print_cell(&mass[c][k], 1);
        printf(" |\n");
    }

    /* the figure: the caused error against the sample period and the payload's mass */
    static double px[2][NCTRL][NRATE > NMASS ? NRATE : NMASS];
    static double py[2][NCTRL][NRATE > NMASS ? NRATE : NMASS];
    static svg_series series[2][NCTRL];
    for (int c = 0; c < NCTRL; c++) {
        int n = 0;
        for (int k = 0; k < NRATE; k++)
            if (rate[c][k].status == CTC_RUN_DONE) {
                px[0][c][n] = 1e3 / rate_hz[k], py[0][c][n] = rate[c][k].cause;
                n++;
            }
        series[0][c] = (svg_series){.label = ctrl_name[c],
                                    .colour = ctrl_colour[c],
                                    .marker = ctrl_marker[c],
                                    .joined = 1,
                                    .n = n,
                                    .x = px[0][c],
                                    .y = py[0][c]};
        n = 0;
        for (int k = 0; k < NMASS; k++)
            if (mass[c][k].status == CTC_RUN_DONE) {
                px[1][c][n] = payload_kg[k], py[1][c][n] = mass[c][k].cause;
                n++;
            }
        series[1][c] = (svg_series){.label = ctrl_name[c],
                                    .colour = ctrl_colour[c],
                                    .marker = ctrl_marker[c],
                                    .joined = 1,
                                    .n = n,
                                    .x = px[1][c],
                                    .y = py[1][c]};
    }
    const svg_panel panels[2] = {
        {.title = "Sampling (ZOH): triple pendulum, 5 s",
         .xlabel = "sample period (ms)",
         .ylabel = "error_by_cause.sampling (rad)",
         .nseries = NCTRL,
         .series = series[0]},
        {.title = "Unmodelled payload at the tip, 5 s",
         .xlabel = "payload (kg)",
         .ylabel = "error_by_cause.model (rad)",
         .nseries = NCTRL,
         .series = series[1]},
    };
    char path[512];
    snprintf(path, sizeof path, "%s/lab_error.svg", dir);
    if (svg_write_figure(path, 2, 2, panels) != 0) {
        fprintf(stderr, "bench_lab: could not write %s\n", path);
        return 1;
    }
    printf("\n(figure: %s)\n", path);
    return 0;
}
