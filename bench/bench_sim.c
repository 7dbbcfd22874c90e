/*
 * bench_sim.c - speed against error of whole simulations: the paper's 5 s triple pendulum PID
 * run (section 7.1, disturbance 0.2 N m) with every integrator over a range of step sizes and
 * tolerances.
 *
 * The error of a run is max over its samples and joints of |q - q_ref|, with q_ref from a
 * reference run of DOPRI5 at rtol 1e-12, atol 1e-14 sampled at the same times. Wall times are
 * medians over interleaved repetitions (every configuration once per round), so machine noise
 * falls on all of them alike. Prints a markdown table and writes a log-log work-precision plot as
 * SVG to the path in argv[1] (default build/work_precision_triple_pid.svg).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "chains.h"
#include "sim.h"

#define PI 3.14159265358979323846
#define ROUNDS 5

typedef struct config {
    const char *label;
    ctc_integ_spec integ;
    double wall[ROUNDS];
    double error;
    long steps, evals;
} config;

static test_chain *chain;
static ctc_gains gains[3];
static ctc_traj traj[3];
static ctc_disturb dist[3];

static ctc_sim_spec paper_spec(ctc_integ_spec integ)
{
    static const double q0[3] = {5 * PI / 6, 3 * PI / 4, 2 * PI / 3};
    for (int i = 0; i < 3; i++) {
        gains[i] = (ctc_gains){.ki = 250, .kp = 100, .kv = 20};
        traj[i] = (ctc_traj){
            .type = i == 1 ? CTC_TRAJ_COSINE : CTC_TRAJ_SINE, .amplitude = 0.6, .period = 1.5};
        dist[i] = (ctc_disturb){.type = CTC_DISTURB_CONSTANT, .value = 0.2};
    }
    return (ctc_sim_spec){.chain = chain->spec,
                          .q0 = q0,
                          .controller = CTC_CTRL_PID,
                          .gains = gains,
                          .model_mass_scale = 1,
                          .model_inertia_scale = 1,
                          .traj = traj,
                          .disturb = dist,
                          .integrator = integ,
                          .duration = 5,
                          .output_interval = 0.01,
                          .channels = CTC_CH_BIT(CTC_CH_Q)};
}

static ctc_sim_result *run(ctc_integ_spec integ)
{
    ctc_sim_spec spec = paper_spec(integ);
    ctc_sim_result *r = NULL;
    char err[256];
    if (ctc_sim_run(&spec, NULL, &r, err, sizeof err) != CTC_OK || r->status != CTC_RUN_DONE) {
        fprintf(stderr, "bench_sim: run failed: %s\n", r ? r->message : err);
        exit(1);
    }
    return r;
}

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

/* log-log scatter, one polyline per method, as a small standalone SVG */
static void write_svg(const char *path, const config *c, int n)
{
    FILE *f = fopen(path, "w");
    if (!f) {
        perror(path);
        return;
    }
    double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
    for (int i = 0; i < n; i++) {
        double x = log10(median(c[i].wall, ROUNDS) * 1e3), y = log10(fmax(c[i].error, 1e-16));
        x0 = fmin(x0, x), x1 = fmax(x1, x), y0 = fmin(y0, y), y1 = fmax(y1, y);
    }
    x0 = floor(x0), x1 = ceil(x1), y0 = floor(y0), y1 = ceil(y1);
    const double w = 640, h = 420, left = 70, right = 150, top = 20, bottom = 50;
#define PX(x) (left + ((x)-x0) / (x1 - x0) * (w - left - right))
#define PY(y) (top + (y1 - (y)) / (y1 - y0) * (h - top - bottom))
    fprintf(f,
            "<svg xmlns='http://www.w3.org/2000/svg' width='%g' height='%g' "
            "font-family='sans-serif' font-size='12'>\n"
            "<rect width='100%%' height='100%%' fill='white'/>\n",
            w, h);
    for (double x = x0; x <= x1; x++)
        fprintf(f,
                "<line x1='%.1f' y1='%g' x2='%.1f' y2='%g' stroke='#ddd'/>"
                "<text x='%.1f' y='%g' text-anchor='middle'>1e%g</text>\n",
                PX(x), top, PX(x), h - bottom, PX(x), h - bottom + 16, x);
    for (double y = y0; y <= y1; y++)
        fprintf(f,
                "<line x1='%g' y1='%.1f' x2='%g' y2='%.1f' stroke='#ddd'/>"
                "<text x='%g' y='%.1f' text-anchor='end'>1e%g</text>\n",
                left, PY(y), w - right, PY(y), left - 6, PY(y) + 4, y);
    fprintf(f,
            "<text x='%g' y='%g' text-anchor='middle'>wall time per 5 s run (ms)</text>\n"
            "<text transform='translate(16,%g) rotate(-90)' text-anchor='middle'>"
            "max |q - q_ref| (rad)</text>\n",
            (left + w - right) / 2, h - 12, (top + h - bottom) / 2);
    static const char *const colours[] = {"#1b6ac9", "#d1495b", "#2e8b57"};
    static const char *const names[] = {"rk4", "dopri5", "bdf"};
    for (int m = 0; m < 3; m++) {
        fprintf(f, "<polyline fill='none' stroke='%s' stroke-width='2' points='", colours[m]);
        for (int i = 0; i < n; i++)
            if ((int)c[i].integ.method == m)
                fprintf(f, "%.1f,%.1f ", PX(log10(median(c[i].wall, ROUNDS) * 1e3)),
                        PY(log10(fmax(c[i].error, 1e-16))));
        fprintf(f, "'/>\n");
        for (int i = 0; i < n; i++)
            if ((int)c[i].integ.method == m)
                fprintf(f, "<circle cx='%.1f' cy='%.1f' r='3' fill='%s'/>\n",
                        PX(log10(median(c[i].wall, ROUNDS) * 1e3)),
                        PY(log10(fmax(c[i].error, 1e-16))), colours[m]);
        fprintf(f,
                "<line x1='%g' y1='%d' x2='%g' y2='%d' stroke='%s' stroke-width='2'/>"
                "<text x='%g' y='%d'>%s</text>\n",
                w - right + 15, 40 + 20 * m, w - right + 40, 40 + 20 * m, colours[m],
                w - right + 46, 44 + 20 * m, names[m]);
    }
    fprintf(f, "</svg>\n");
#undef PX
#undef PY
    fclose(f);
}

int main(int argc, char **argv)
{
    const char *svg = argc > 1 ? argv[1] : "build/work_precision_triple_pid.svg";
    chain = test_chain_rod_pendulum(3, 1, 1);

    ctc_sim_result *ref =
        run((ctc_integ_spec){.method = CTC_INTEG_DOPRI5, .rtol = 1e-12, .atol = 1e-14});

    config c[32];
    int n = 0;
    static const double steps[] = {0.01, 0.005, 0.002, 0.001, 0.0005};
    static const double tols[] = {1e-4, 1e-6, 1e-8, 1e-10};
    static char labels[32][32];
    for (int i = 0; i < 5; i++) {
        snprintf(labels[n], sizeof labels[n], "rk4 h = %g", steps[i]);
        c[n] = (config){.label = labels[n], .integ = {.method = CTC_INTEG_RK4, .step = steps[i]}};
        n++;
    }
    for (int m = CTC_INTEG_DOPRI5; m <= CTC_INTEG_BDF; m++)
        for (int i = 0; i < 4; i++) {
            snprintf(labels[n], sizeof labels[n], "%s rtol = %g",
                     ctc_integ_method_name((ctc_integ_method)m), tols[i]);
            ctc_integ_spec integ = {
                .method = (ctc_integ_method)m, .rtol = tols[i], .atol = tols[i] * 1e-2};
            c[n] = (config){.label = labels[n], .integ = integ};
            n++;
        }

    for (int round = 0; round < ROUNDS; round++)
        for (int i = 0; i < n; i++) {
            ctc_sim_result *r = run(c[i].integ);
            c[i].wall[round] = r->metrics.wall_s;
            c[i].steps = r->metrics.steps;
            c[i].evals = r->metrics.rhs_evals;
            double e = 0;
            for (int j = 0; j < r->nsamples * 3; j++)
                e = fmax(e, fabs(r->ch[CTC_CH_Q][j] - ref->ch[CTC_CH_Q][j]));
            c[i].error = e;
            ctc_sim_result_free(r);
        }

    printf("## Triple pendulum, PID, 5 s (paper section 7.1): speed against error\n\n"
           "Reference: dopri5 at rtol 1e-12 (%ld steps). Error = max over 501 samples and 3 "
           "joints of |q - q_ref|. Median of %d interleaved runs.\n\n",
           ref->metrics.steps, ROUNDS);
    printf("| integrator | wall (ms) | steps | rhs evals | us / eval | max error (rad) |\n"
           "| --- | ---: | ---: | ---: | ---: | ---: |\n");
    for (int i = 0; i < n; i++) {
        double wall = median(c[i].wall, ROUNDS);
        printf("| %s | %.2f | %ld | %ld | %.2f | %.2e |\n", c[i].label, wall * 1e3, c[i].steps,
               c[i].evals, wall * 1e6 / (double)c[i].evals, c[i].error);
    }
    write_svg(svg, c, n);
    printf("\nplot: %s\n", svg);
    ctc_sim_result_free(ref);
    test_chain_free(chain);
    return 0;
}
