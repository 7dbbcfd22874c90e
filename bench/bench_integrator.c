/*
 * bench_integrator.c - the cost of one step of the in-house explicit integrators (integrator.h)
 * against SUNDIALS ARKODE's ERKStep doing the same work.
 *
 * The system is a chain of m unit masses between two walls, joined by springs with a small cubic
 * stiffening and light damping: n = 2 m states (positions, then velocities), n = 6, 18 and 96.
 * Its rhs costs a few flops per state, so the integrators' own work (stage combinations, error
 * norm, step control, bookkeeping) dominates the time. Four timings:
 *   rk4     ctc rk4, h = 1e-3                   vs  erk-rk4  ERKStep with the classical RK4
 *                                                   table, ERKStepSetFixedStep(1e-3)
 *   dopri5  ctc dopri5, rtol 1e-8, atol 1e-10   vs  erk-dp5  ERKStep with
 *                                                   ARKODE_DORMAND_PRINCE_7_4_5, same tolerances
 * (SUNDIALS 6.4 has no built-in RK4 table, so it is made with ARKodeButcherTable_Create; see
 * setup() for the extra stage it needs.)
 * Each runs one step at a time (ARK_ONE_STEP for ERKStep) from the same initial state over the
 * same interval, restarted (reset) at the start of each run; the figure is wall time per accepted
 * step. ERKStep keeps its default Hermite interpolation module, as a user of it would. Runs of
 * the four, and of the rhs alone, are interleaved so machine noise falls on all of them alike;
 * the figures are medians over the batches, and the ratio is ctc / ERKStep from the same run.
 * The last two columns check that each pair solved the same problem (largest difference of the
 * final states: rounding for rk4, the tolerance for the two adaptive codes).
 * Debian's SUNDIALS 6.4.1 libraries are built without optimisation (their disassembly is -O0
 * code: every local goes through the stack), so the ERKStep figures are those of the library this
 * project links against, not of an optimised SUNDIALS build.
 * Usage: bench_integrator [batches]
 */
#include <arkode/arkode_erkstep.h> /* includes arkode_butcher.h, which needs stdio.h first */
#include <math.h>
#include <nvector/nvector_serial.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sundials/sundials_context.h>
#include <time.h>

#include "integrator.h"

#define H_FIXED 1e-3
#define RTOL 1e-8
#define ATOL 1e-10

enum { T_RK4, T_ERK_RK4, T_DOPRI5, T_ERK_DP5, T_RHS, NT };

typedef struct chain {
    int m;      /* masses */
    long evals; /* rhs calls */
} chain;

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* x_i'' = -k (x_i - x_{i-1}) - k (x_i - x_{i+1}) - eps (...)^3 - c v_i, walls at x = 0 */
static int chain_rhs(double t, const double *y, double *ydot, void *ctx)
{
    (void)t;
    chain *c = ctx;
    const int m = c->m;
    const double k = 40.0, eps = 5.0, damp = 0.05;
    const double *x = y, *v = y + m;
    c->evals++;
    for (int i = 0; i < m; i++) {
        double left = x[i] - (i > 0 ? x[i - 1] : 0.0);
        double right = x[i] - (i < m - 1 ? x[i + 1] : 0.0);
        ydot[i] = v[i];
        ydot[m + i] =
            -k * (left + right) - eps * (left * left * left + right * right * right) - damp * v[i];
    }
    return 0;
}

static int chain_rhs_nv(sunrealtype t, N_Vector y, N_Vector ydot, void *ctx)
{
    return chain_rhs(t, N_VGetArrayPointer(y), N_VGetArrayPointer(ydot), ctx);
}

static void initial_state(int m, double *y)
{
    for (int i = 0; i < m; i++) {
        y[i] = 0.3 * sin(1.7 * (i + 1));
        y[m + i] = 0.0;
    }
}

typedef struct bench_case {
    int n;
    chain c;
    double *y0, *scratch;
    double t_fixed, t_adaptive; /* run lengths (s) */
    ctc_integrator *rk4, *dopri5;
    SUNContext sunctx;
    N_Vector y_nv;
    void *erk_rk4, *erk_dp5;
    ARKodeButcherTable rk4_table;
    long steps[NT]; /* accepted steps of the last run */
    long evals[NT]; /* rhs evaluations of the last run */
    double y_end[NT][96];
} bench_case;

static void die(const char *what)
{
    fprintf(stderr, "bench_integrator: %s\n", what);
    exit(1);
}

static void setup(bench_case *b, int n)
{
    char err[256];
    memset(b, 0, sizeof *b);
    b->n = n;
    b->c.m = n / 2;
    b->y0 = calloc((size_t)n, sizeof(double));
    b->scratch = calloc((size_t)n, sizeof(double));
    initial_state(b->c.m, b->y0);

    /* in-house */
    ctc_integ_spec rk4 = {.method = CTC_INTEG_RK4, .step = H_FIXED};
    ctc_integ_spec dp = {.method = CTC_INTEG_DOPRI5, .rtol = RTOL, .atol = ATOL};
    if (ctc_integrator_new(&rk4, n, chain_rhs, &b->c, &b->rk4, err, sizeof err) != CTC_OK ||
        ctc_integrator_new(&dp, n, chain_rhs, &b->c, &b->dopri5, err, sizeof err) != CTC_OK) {
        die(err);
    }

    /* ERKStep: the classical RK4 tableau plus a fifth stage f(t + h, y_new) of weight 0, fixed
     * step. ERKStep 6.4 takes any table with c_s = 1 for first-same-as-last and reuses its last
     * stage as the next step's first (SUNDIALS issue #311, fixed in 6.6): plain RK4's last stage
     * f(t + h, y + h k3) is not f at y_new, so it would take 3 evaluations a step and lose
     * accuracy. With the extra stage the reuse is right, and ERKStep does what ctc rk4 does:
     * 4 evaluations a step, the 4th at the new state. */
    if (SUNContext_Create(NULL, &b->sunctx) != 0) die("SUNContext_Create failed");
    b->y_nv = N_VNew_Serial(n, b->sunctx);
    memcpy(N_VGetArrayPointer(b->y_nv), b->y0, (size_t)n * sizeof(double));
    sunrealtype c[5] = {0, 0.5, 0.5, 1, 1};
    sunrealtype w[5] = {1.0 / 6, 1.0 / 3, 1.0 / 3, 1.0 / 6, 0};
    sunrealtype a[25] = {0};
    a[1 * 5 + 0] = 0.5;
    a[2 * 5 + 1] = 0.5;
    a[3 * 5 + 2] = 1;
    for (int j = 0; j < 4; j++) a[4 * 5 + j] = w[j];
    b->rk4_table = ARKodeButcherTable_Create(5, 4, 0, c, a, w, NULL);
    b->erk_rk4 = ERKStepCreate(chain_rhs_nv, 0.0, b->y_nv, b->sunctx);
    b->erk_dp5 = ERKStepCreate(chain_rhs_nv, 0.0, b->y_nv, b->sunctx);
    if (b->rk4_table == NULL || b->erk_rk4 == NULL || b->erk_dp5 == NULL) die("ERKStep setup");
    int flag = ERKStepSetTable(b->erk_rk4, b->rk4_table);
    flag |= ERKStepSetFixedStep(b->erk_rk4, H_FIXED);
    flag |= ERKStepSetUserData(b->erk_rk4, &b->c);
    flag |= ERKStepSetMaxNumSteps(b->erk_rk4, -1);

    /* ERKStep: Dormand-Prince 5(4), adaptive */
    flag |= ERKStepSetTableNum(b->erk_dp5, ARKODE_DORMAND_PRINCE_7_4_5);
    flag |= ERKStepSStolerances(b->erk_dp5, RTOL, ATOL);
    flag |= ERKStepSetUserData(b->erk_dp5, &b->c);
    flag |= ERKStepSetMaxNumSteps(b->erk_dp5, -1);
    if (flag != 0) die("ERKStep options");
}

static void teardown(bench_case *b)
{
    ctc_integrator_free(b->rk4);
    ctc_integrator_free(b->dopri5);
    ERKStepFree(&b->erk_rk4);
    ERKStepFree(&b->erk_dp5);
    ARKodeButcherTable_Free(b->rk4_table);
    N_VDestroy(b->y_nv);
    SUNContext_Free(&b->sunctx);
    free(b->y0);
    free(b->scratch);
}

/* one run of timing w from the initial state; returns the seconds it took */
static double run_once(bench_case *b, int w)
{
    char err[256];
    const int n = b->n;
    long evals0 = b->c.evals;
    double t0 = now();
    switch (w) {
    case T_RK4:
    case T_DOPRI5: {
        ctc_integrator *it = w == T_RK4 ? b->rk4 : b->dopri5;
        double t_end = w == T_RK4 ? b->t_fixed : b->t_adaptive;
        long steps0 = ctc_integrator_stats(it)->steps;
        if (ctc_integrator_reset(it, 0.0, b->y0) != 0) die("reset failed");
        while (ctc_integrator_time(it) < t_end) {
            if (ctc_integrator_step(it, t_end, err, sizeof err) != 0) die(err);
        }
        b->steps[w] = ctc_integrator_stats(it)->steps - steps0;
        memcpy(b->y_end[w], ctc_integrator_state(it), (size_t)n * sizeof(double));
        break;
    }
    case T_ERK_RK4:
    case T_ERK_DP5: {
        void *mem = w == T_ERK_RK4 ? b->erk_rk4 : b->erk_dp5;
        double t_end = w == T_ERK_RK4 ? b->t_fixed : b->t_adaptive, t = 0;
        long steps0 = 0, steps1 = 0;
        ERKStepGetNumSteps(mem, &steps0);
        memcpy(N_VGetArrayPointer(b->y_nv), b->y0, (size_t)n * sizeof(double));
        if (ERKStepReset(mem, 0.0, b->y_nv) != ARK_SUCCESS) die("ERKStepReset failed");
        if (ERKStepSetStopTime(mem, t_end) != ARK_SUCCESS) die("ERKStepSetStopTime failed");
        while (t < t_end) {
            if (ERKStepEvolve(mem, t_end, b->y_nv, &t, ARK_ONE_STEP) < 0) die("ERKStepEvolve");
        }
        ERKStepGetNumSteps(mem, &steps1);
        b->steps[w] = steps1 - steps0;
        memcpy(b->y_end[w], N_VGetArrayPointer(b->y_nv), (size_t)n * sizeof(double));
        break;
    }
    case T_RHS:
        /* as many evaluations as rk4's run makes */
        for (long i = 0; i < b->steps[T_RK4] * 4; i++) chain_rhs(0.0, b->y0, b->scratch, &b->c);
        b->steps[w] = b->steps[T_RK4] * 4;
        break;
    }
    double dt = now() - t0;
    b->evals[w] = b->c.evals - evals0;
    return dt;
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

static double max_abs_diff(int n, const double *a, const double *b)
{
    double s = 0;
    for (int i = 0; i < n; i++) s = fmax(s, fabs(a[i] - b[i]));
    return s;
}

static void bench_size(int n, int batches)
{
    bench_case b;
    setup(&b, n);

    /* run lengths: about 2 ms of rk4 and of dopri5 per run */
    b.t_fixed = 0.1;
    b.t_adaptive = 0.5;
    for (int w = T_RK4; w <= T_DOPRI5; w += T_DOPRI5 - T_RK4) {
        double *len = w == T_RK4 ? &b.t_fixed : &b.t_adaptive;
        while (run_once(&b, w) < 2e-3 && *len < 1e4) *len *= 2;
    }

    double *samples = malloc(sizeof(double) * (size_t)batches * NT);
    for (int i = 0; i < batches; i++) {
        for (int w = 0; w < NT; w++) {
            double dt = run_once(&b, w);
            samples[w * batches + i] = dt / (double)b.steps[w];
        }
    }
    double med[NT];
    for (int w = 0; w < NT; w++) {
        qsort(samples + w * batches, (size_t)batches, sizeof(double), cmp_double);
        med[w] = samples[w * batches + batches / 2];
    }
    free(samples);

    /* both pairs solved the same problem: final states agree */
    double d_fixed = max_abs_diff(n, b.y_end[T_RK4], b.y_end[T_ERK_RK4]);
    double d_adapt = max_abs_diff(n, b.y_end[T_DOPRI5], b.y_end[T_ERK_DP5]);
    double rhs_ns = 1e9 * med[T_RHS];
    printf("| %3d | %8.0f | %8.0f | %5.2f | %8.0f | %8.0f | %5.2f | %5ld / %5ld | %.1f / %.1f | "
           "%6.1f | %8.0e | %8.0e |\n",
           n, 1e9 * med[T_RK4], 1e9 * med[T_ERK_RK4], med[T_RK4] / med[T_ERK_RK4],
           1e9 * med[T_DOPRI5], 1e9 * med[T_ERK_DP5], med[T_DOPRI5] / med[T_ERK_DP5],
           b.steps[T_DOPRI5], b.steps[T_ERK_DP5], (double)b.evals[T_DOPRI5] / b.steps[T_DOPRI5],
           (double)b.evals[T_ERK_DP5] / b.steps[T_ERK_DP5], rhs_ns, d_fixed, d_adapt);
    fflush(stdout);
    teardown(&b);
}

int main(int argc, char **argv)
{
    int batches = argc > 1 ? atoi(argv[1]) : 31;
    if (batches < 1) {
        fprintf(stderr, "usage: bench_integrator [batches >= 1]\n");
        return 2;
    }
    printf("Explicit integrators, ns per accepted step (medians of %d interleaved runs): ctc "
           "against SUNDIALS ARKODE ERKStep\non a spring-mass chain of n states. rk4: h = %g; "
           "dopri5 and ERKStep's Dormand-Prince 7_4_5: rtol %g, atol %g.\n\n",
           batches, H_FIXED, RTOL, ATOL);
    printf("|   n | rk4 (ns) | erk-rk4 (ns) | ratio | dopri5 (ns) | erk-dp5 (ns) | ratio | "
           "steps dopri5 / erk | evals/step | rhs (ns) | rk4 vs erk | dp5 vs erk |\n");
    printf("| --: | -------: | -------: | ----: | -------: | -------: | ----: | ----: | ----: | "
           "-----: | -------: | -------: |\n");
    const int sizes[3] = {6, 18, 96};
    for (int i = 0; i < 3; i++) bench_size(sizes[i], batches);
    return 0;
}
