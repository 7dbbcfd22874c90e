/*
 * bench_peak.c - what one core of this machine can do: its clock, floating-point peak and
 * latency, and memory bandwidth. The yardsticks for the hot-path figures of bench_dynamics
 * (bench/NOTEBOOK.md, "Hot path").
 *
 * Timings (one thread; a multiply-add counts as 2 flops):
 *   clock         a dependent chain of register-to-register integer additions (1 cycle each,
 *                 x86-64 only; an add of an immediate would not do: this core's renamer folds
 *                 chains of those), which gives the core's clock while it runs; it is measured
 *                 alone, and again right after each timing below (flops / cycle use that one);
 *   fma zmm/ymm   x = x * b + c on NCHAIN independent registers of 8 (AVX-512) or 4 (AVX2)
 *                 doubles, fused: enough chains to keep both FMA ports busy through the
 *                 latency, so this is the practical peak;
 *   fma scalar    the same on single doubles (vfmadd..sd): the peak of code that does not
 *                 vectorise but fuses;
 *   mul+add       the same recurrence unfused, scalar (SSE2): a multiply and a dependent add,
 *                 which is what the library's kernels mostly compile to (-std=c11 turns
 *                 contraction off, and 3- and 6-vectors vectorise little);
 *   latency       one dependent chain of x = x * b + c, fused and unfused: the time per term of
 *                 a dot product summed in order, as the small dense kernels do;
 *   bandwidth     the sum of a double array (read) and a[i] = b[i] + s c[i] (triad, counted as
 *                 3 x 8 bytes), at working sets of L1, L2, L3 and main-memory size.
 * A step is one update x = x * b + c of one register (one fused instruction, or a multiply and
 * an add); "ns per step" is the reciprocal throughput with 16 chains and the latency with one.
 * Each figure is the median of BATCHES interleaved batches (bandwidth: BW_BATCHES). The vector
 * timings need the instruction set at compile time (make bench builds with -march=native); without
 * it they print "-". Usage: bench_peak
 */
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#if defined(__SSE2__)
#include <immintrin.h>
#endif

#define BATCHES 15
#define NCHAIN 16     /* independent recurrences: > 2 ports x 4 cycles of latency */
#define REPS 10000    /* recurrence steps per chain and batch */
#define LAT_REPS 4000 /* steps of the single dependent chain (x 8) */
#define BW_BATCHES 5  /* batches of the bandwidth timings */
#define SETTLE_S 3e-3 /* integer work before each timing */

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static volatile double sink;
static volatile double coef_b = 0.999999, coef_c = 1e-6; /* x -> 1, never denormal */

enum { P_CLOCK, P_ZMM, P_YMM, P_FMA, P_MULADD, P_LAT_FMA, P_LAT_MULADD, NP };

/* seconds per integer add in a dependent chain of 8 reps adds, or 0 where not measurable */
static double time_clock(int reps)
{
#if defined(__x86_64__) && defined(__GNUC__)
    long x = 0, one = (long)coef_b + 1;
    double s = now();
    for (int r = 0; r < reps; r++) {
        __asm__ volatile("add %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\t"
                         "add %1, %0\n\tadd %1, %0\n\tadd %1, %0\n\tadd %1, %0"
                         : "+r"(x)
                         : "r"(one));
    }
    double t = now() - s;
    sink += (double)x;
    return t / (reps * 8.0);
#else
    (void)reps;
    return 0;
#endif
}

/* integer work for SETTLE_S, so that a clock lowered by the previous vector code recovers */
static void settle(void)
{
    double s = now();
    while (now() - s < SETTLE_S) time_clock(1000);
}

/* seconds per recurrence step of one lane, or 0 where the instruction set is missing */
static double time_zmm(void)
{
#ifdef __AVX512F__
    __m512d x[NCHAIN], b = _mm512_set1_pd(coef_b), c = _mm512_set1_pd(coef_c);
    for (int k = 0; k < NCHAIN; k++) x[k] = _mm512_set1_pd(k);
    double s = now();
    for (int r = 0; r < REPS; r++) {
#pragma GCC unroll 16
        for (int k = 0; k < NCHAIN; k++) x[k] = _mm512_fmadd_pd(x[k], b, c);
    }
    double t = now() - s;
    for (int k = 0; k < NCHAIN; k++) sink += _mm512_reduce_add_pd(x[k]);
    return t / ((double)REPS * NCHAIN * 8);
#else
    return 0;
#endif
}

static double time_ymm(void)
{
#if defined(__AVX2__) && defined(__FMA__)
    __m256d x[NCHAIN], b = _mm256_set1_pd(coef_b), c = _mm256_set1_pd(coef_c);
    for (int k = 0; k < NCHAIN; k++) x[k] = _mm256_set1_pd(k);
    double s = now();
    for (int r = 0; r < REPS; r++) {
#pragma GCC unroll 16
        for (int k = 0; k < NCHAIN; k++) x[k] = _mm256_fmadd_pd(x[k], b, c);
    }
    double t = now() - s;
    double lanes[4];
    for (int k = 0; k < NCHAIN; k++) {
        _mm256_storeu_pd(lanes, x[k]);
        sink += lanes[0] + lanes[1] + lanes[2] + lanes[3];
    }
    return t / ((double)REPS * NCHAIN * 4);
#else
    return 0;
#endif
}

static double time_fma_scalar(void)
{
#ifdef __FMA__
    __m128d x[NCHAIN], b = _mm_set_sd(coef_b), c = _mm_set_sd(coef_c);
    for (int k = 0; k < NCHAIN; k++) x[k] = _mm_set_sd(k);
    double s = now();
    for (int r = 0; r < REPS; r++) {
#pragma GCC unroll 16
        for (int k = 0; k < NCHAIN; k++) x[k] = _mm_fmadd_sd(x[k], b, c);
    }
    double t = now() - s;
    for (int k = 0; k < NCHAIN; k++) sink += _mm_cvtsd_f64(x[k]);
    return t / ((double)REPS * NCHAIN);
#else
    return 0;
#endif
}

/* unfused: x * b rounded, then + c, one double per instruction (SSE2 intrinsics, so that the
 * compiler neither fuses nor pairs the chains into vectors) */
static double time_muladd_scalar(void)
{
#ifdef __SSE2__
    __m128d x[NCHAIN], b = _mm_set_sd(coef_b), c = _mm_set_sd(coef_c);
    for (int k = 0; k < NCHAIN; k++) x[k] = _mm_set_sd(k);
    double s = now();
    for (int r = 0; r < REPS; r++) {
#pragma GCC unroll 16
        for (int k = 0; k < NCHAIN; k++) x[k] = _mm_add_sd(_mm_mul_sd(x[k], b), c);
    }
    double t = now() - s;
    for (int k = 0; k < NCHAIN; k++) sink += _mm_cvtsd_f64(x[k]);
    return t / ((double)REPS * NCHAIN);
#else
    return 0;
#endif
}

static double time_latency(int fused)
{
    double b = coef_b, c = coef_c, x = 0.5, s = now();
    if (fused) {
#ifdef __FMA__
        __m128d xv = _mm_set_sd(x), bv = _mm_set_sd(b), cv = _mm_set_sd(c);
        for (int r = 0; r < LAT_REPS * 8; r++) xv = _mm_fmadd_sd(xv, bv, cv);
        x = _mm_cvtsd_f64(xv);
#else
        return 0;
#endif
    } else {
#ifdef __SSE2__
        __m128d xv = _mm_set_sd(x), bv = _mm_set_sd(b), cv = _mm_set_sd(c);
        for (int r = 0; r < LAT_REPS * 8; r++) xv = _mm_add_sd(_mm_mul_sd(xv, bv), cv);
        x = _mm_cvtsd_f64(xv);
#else
        return 0;
#endif
    }
    double t = now() - s;
    sink += x;
    return t / (LAT_REPS * 8.0);
}

static int cmp_double(const void *x, const void *y)
{
    double a = *(const double *)x, b = *(const double *)y;
    return (a > b) - (a < b);
}

static double median(double *v, int n)
{
    qsort(v, (size_t)n, sizeof *v, cmp_double);
    return v[n / 2];
}

/* bytes per second of the sum over a, b, c (triad = 0) or of the triad a = b + s c (triad = 1);
 * a, b, c are n doubles each, consecutive in memory */
static double time_bandwidth(double *a, double *b, double *c, size_t n, int triad)
{
    double samples[BW_BATCHES];
    /* at least 2 passes, or about 1e7 doubles per batch */
    int passes = (int)(1e7 / (double)(3 * n)) + 2;
    for (int k = 0; k < BW_BATCHES; k++) {
        double s = now(), acc = 0;
        for (int p = 0; p < passes; p++) {
            if (triad) {
                double scl = 1e-3 * p;
                for (size_t i = 0; i < n; i++) a[i] = b[i] + scl * c[i];
                acc += a[p % n];
            } else {
                double s0 = 0, s1 = 0, s2 = 0, s3 = 0, s4 = 0, s5 = 0, s6 = 0, s7 = 0;
                for (size_t i = 0; i + 8 <= 3 * n; i += 8) {
                    s0 += a[i], s1 += a[i + 1], s2 += a[i + 2], s3 += a[i + 3];
                    s4 += a[i + 4], s5 += a[i + 5], s6 += a[i + 6], s7 += a[i + 7];
                }
                acc += s0 + s1 + s2 + s3 + s4 + s5 + s6 + s7;
            }
        }
        samples[k] = (now() - s) / passes;
        sink += acc;
    }
    return 3.0 * 8.0 * (double)n / median(samples, BW_BATCHES);
}

int main(void)
{
    /* each timing starts after SETTLE_S of integer work and is followed at once by a short clock
       measurement: the core runs AVX-512 code at a lower clock, for a while after it too */
    double samples[NP][BATCHES], clock[NP][BATCHES], med[NP], ghz_after[NP];
    for (int k = 0; k < BATCHES; k++) {
        for (int p = 0; p < NP; p++) {
            settle();
            switch (p) {
            case P_CLOCK:
                samples[p][k] = time_clock(REPS * 4);
                break;
            case P_ZMM:
                samples[p][k] = time_zmm();
                break;
            case P_YMM:
                samples[p][k] = time_ymm();
                break;
            case P_FMA:
                samples[p][k] = time_fma_scalar();
                break;
            case P_MULADD:
                samples[p][k] = time_muladd_scalar();
                break;
            default:
                samples[p][k] = time_latency(p == P_LAT_FMA);
                break;
            }
            clock[p][k] = time_clock(REPS / 4);
        }
    }
    for (int p = 0; p < NP; p++) {
        med[p] = median(samples[p], BATCHES);
        double c = median(clock[p], BATCHES);
        ghz_after[p] = c > 0 ? 1e-9 / c : 0;
    }

    double ghz = med[P_CLOCK] > 0 ? 1e-9 / med[P_CLOCK] : 0;
    printf("One core: floating-point throughput and latency (medians of %d batches; a "
           "multiply-add = 2 flops).\n\n",
           BATCHES);
    if (ghz > 0) {
        printf("clock (dependent integer adds): %.2f GHz\n\n", ghz);
    } else {
        printf("clock: not measured on this machine\n\n");
    }
    printf("| kernel | GFLOP/s | clock right after (GHz) | flops / cycle | ns per step |\n"
           "| --- | ---: | ---: | ---: | ---: |\n");
    static const char *names[NP] = {
        "",
        "fma, 8 doubles (zmm), 16 chains",
        "fma, 4 doubles (ymm), 16 chains",
        "fma, scalar, 16 chains",
        "mul + add, scalar, 16 chains",
        "fma, scalar, 1 dependent chain",
        "mul + add, scalar, 1 dependent chain",
    };
    for (int p = P_ZMM; p < NP; p++) {
        if (med[p] <= 0) {
            printf("| %s | - | - | - | - |\n", names[p]);
            continue;
        }
        double gflops = 2e-9 / med[p];
        /* a vector step covers 8 or 4 lanes: the time per instruction is the lane time x lanes */
        int lanes = p == P_ZMM ? 8 : p == P_YMM ? 4 : 1;
        if (ghz_after[p] > 0) {
            printf("| %s | %.1f | %.2f | %.2f | %.3f |\n", names[p], gflops, ghz_after[p],
                   gflops / ghz_after[p], 1e9 * med[p] * lanes);
        } else {
            printf("| %s | %.1f | - | - | %.3f |\n", names[p], gflops, 1e9 * med[p] * lanes);
        }
    }

    /* bandwidth at working sets (the three arrays together) in L1 (48 KiB here), L2 (2 MiB),
       L3 and main memory */
    static const size_t bytes[] = {24u << 10, 768u << 10, 24u << 20, 384u << 20};
    static const char *level[] = {"24 KiB", "768 KiB", "24 MiB", "384 MiB"};
    printf("\nMemory bandwidth (medians of %d batches)\n\n", BW_BATCHES);
    printf("| working set | read (GB/s) | triad (GB/s) |\n| --- | ---: | ---: |\n");
    for (int s = 0; s < 4; s++) {
        size_t n = bytes[s] / 3 / sizeof(double);
        double *a = malloc(3 * n * sizeof *a);
        if (!a) {
            fprintf(stderr, "bench_peak: out of memory for %s\n", level[s]);
            return 1;
        }
        for (size_t i = 0; i < 3 * n; i++) a[i] = 1.0 / (double)(i + 1);
        double rd = time_bandwidth(a, a + n, a + 2 * n, n, 0);
        double tr = time_bandwidth(a, a + n, a + 2 * n, n, 1);
        printf("| %s | %.1f | %.1f |\n", level[s], 1e-9 * rd, 1e-9 * tr);
        free(a);
    }
    return sink == 12345.678 ? 1 : 0;
}
