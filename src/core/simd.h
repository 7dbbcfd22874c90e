/*
 * simd.h - short vectors of doubles for the spatial (6 x 6) kernels, by the vector extensions of
 * GCC and Clang: no intrinsics, so the compiler lowers them to what the target has (SSE2 on any
 * x86-64, AVX with -march=native, NEON on arm64, or scalar code).
 *
 * Every function takes and gives vectors through pointers, never by value: a 32-byte vector
 * passed by value changes the calling convention between targets with and without AVX (gcc's
 * -Wpsabi), and once inlined the two are the same code. Loads and stores go by memcpy, so p needs
 * no alignment beyond a double's.
 */
#ifndef CTC_SIMD_H
#define CTC_SIMD_H

#include <string.h>

typedef double ctc_v4 __attribute__((vector_size(32)));
typedef double ctc_v2 __attribute__((vector_size(16)));

/* a 6-vector: entries 0..3 and 4..5 */
typedef struct ctc_v6 {
    ctc_v4 lo;
    ctc_v2 hi;
} ctc_v6;

/* v = p[0..5] */
static inline void ctc_v6_load(ctc_v6 *v, const double *p)
{
    memcpy(&v->lo, p, sizeof v->lo);
    memcpy(&v->hi, p + 4, sizeof v->hi);
}

/* p[0..5] = v */
static inline void ctc_v6_store(double *p, const ctc_v6 *v)
{
    memcpy(p, &v->lo, sizeof v->lo);
    memcpy(p + 4, &v->hi, sizeof v->hi);
}

/* acc += s x */
static inline void ctc_v6_madd(ctc_v6 *acc, double s, const ctc_v6 *x)
{
    acc->lo += s * x->lo;
    acc->hi += s * x->hi;
}

/* acc -= s x */
static inline void ctc_v6_msub(ctc_v6 *acc, double s, const ctc_v6 *x)
{
    acc->lo -= s * x->lo;
    acc->hi -= s * x->hi;
}

/* v = s x */
static inline void ctc_v6_scale(ctc_v6 *v, double s, const ctc_v6 *x)
{
    v->lo = s * x->lo;
    v->hi = s * x->hi;
}

/* out = a + b, 36 entries (a 6 x 6 block) */
static inline void ctc_v36_add(const double *a, const double *b, double *out)
{
    for (int i = 0; i < 36; i += 4) {
        ctc_v4 x, y;
        memcpy(&x, a + i, sizeof x);
        memcpy(&y, b + i, sizeof y);
        x += y;
        memcpy(out + i, &x, sizeof x);
    }
}

/* y = A^T x for A (6 x 6, row-major): the rows of A times x's entries, summed in row order */
static inline void ctc_v6_tmulv(const double *a, const double *x, double *y)
{
    ctc_v6 acc, row;
    ctc_v6_load(&row, a);
    ctc_v6_scale(&acc, x[0], &row);
    for (int i = 1; i < 6; i++) {
        ctc_v6_load(&row, a + 6 * i);
        ctc_v6_madd(&acc, x[i], &row);
    }
    ctc_v6_store(y, &acc);
}

#endif
