/*
 * linalg.h - dense helpers for tests and benchmarks (not the library's hot path).
 */
#ifndef CTC_TEST_LINALG_H
#define CTC_TEST_LINALG_H

/* Estimated 2-norm condition number of the symmetric positive definite M (n x n, row-major):
 * power iteration for the largest eigenvalue, inverse iteration (Cholesky) for the smallest.
 * Returns INFINITY if M is not numerically positive definite. */
double test_cond_spd(const double *m, int n);

/* Solves M x = b for the symmetric positive definite M (n x n, row-major) by Cholesky; returns
 * -1 if M is not numerically positive definite, else 0. x may alias b. */
int test_solve_spd(const double *m, int n, const double *b, double *x);

/* Largest |a_i - b_i| over max |b_i| (or over 1 when b is all zero). */
double test_rel_err(const double *a, const double *b, int n);

/* 1 if every one of the n entries of x is finite */
int test_all_finite(const double *x, int n);

#endif
