/*
 * gdca_loop.h - the boundary equations of a closed chain, shared by the forward and the inverse
 * passes of loop models (internal to the library; paper section 5, Eq. 55-65, and its
 * reference [48]).
 *
 * After the assembly the loop's bodies are one record R: handle 1 at its first joint j (joint 0
 * of a loop on the ground, joint b+1 of a loop on body b, or on a tree the spine's body after b:
 * model.h loop_first), handle 2 at the closing joint's point p2 = d->loop_pt on the tip; a tree's
 * branches off the spine are raked into the records' bodies. A loop on body b has a second record
 * L, bodies 0..b (the spine's up to b): handle 1 at
 * joint 0, handle 2 at joint j's centre p1 on body b (model.h: the tree's root splits at j). The
 * joints that bound them, each written as "parent -> child" with F the load on the child at the
 * joint (the parent bears -F) and A the classical accelerations of the two sides there:
 *     joint 0   ground -> L, handle 1          (a loop on body b only)
 *     joint j   L, handle 2 (or the ground) -> R, handle 1
 *     joint n   R, handle 2 -> body b at p2 (or the ground)
 * Body b's acceleration at p2 is its acceleration at p1 shifted rigidly (gdca_loop_shift_accel)
 * plus d->loop_gam; a load at p2 on it is the load shifted to p1 (ctc_transfer_force,
 * gdca_tree.h). With A1 = h11 F1 + h12 F2 + h13, A2 = h21 F1 + h22 F2 + h23 for each record, each
 * joint asks F = S x + fo,     S^T (A_child - A_parent - a) = -off where for each joint either its
 * acceleration is unknown (a dependent joint, or any joint in the forward pass): S = D (its
 * constraint directions), fo = P f (its driving force), a = beta; or it is commanded (an
 * independent joint in the inverse pass, Eq. 19): S = 1 (the whole load is unknown), fo = 0, a = P
 * u + beta, and off (the closing joint's only, else zero) is the forward pass's Baumgarte term
 * D_n^T (A_t + beta_n - A_child) = 2 a dphi + b^2 phi (data.h). Each unknown x is conjugate to
 * the relative acceleration its rows measure, so the system in all the unknowns is symmetric: a
 * congruence of the loop's mobility, positive definite when the unknown accelerations determine
 * the loop and singular when they do not (a singular configuration, or redundant constraints).
 * It is solved by Cholesky after symmetric diagonal scaling (at most 18 unknowns).
 */
#ifndef CTC_GDCA_LOOP_H
#define CTC_GDCA_LOOP_H

#include "data.h"
#include "dense.h"

/* One joint of the boundary problem: s has ns columns of length dim at s[c dim]; s == NULL means
 * the identity (ns = dim). fo and a have dim entries; off ns entries or NULL. */
typedef struct gdca_end {
    const double *s;
    int ns;
    const double *fo, *a, *off;
} gdca_end;

/* The problem at the root of a loop model's tree (see above). */
typedef struct gdca_loop_root {
    int dim;             /* 3 or 6 */
    const double *l;     /* L's record, or NULL: the loop closes on the ground */
    const double *r;     /* R's record */
    const double *shift; /* (3) p2 - p1 (d->loop_r); L only */
    const double *gam;   /* (dim) d->loop_gam; L only */
    gdca_end e0, ej, en; /* joints 0 (L only), j and n */
    const double *lb[2]; /* L's bias terms h13, h23 in place of its record's; NULL: the record's
                            own (the refinement's correction passes zero for a body) */
    const double *rb[2]; /* R's, likewise */
} gdca_loop_root;

/* What the solve gives: the loads on the children of joints 0, j and n, and the classical
 * accelerations of L's handles, R's handles and body b at p2. On the ground (no L) joint j is
 * joint 0: f0 = fj, and al1, al2 and ab are zero. */
typedef struct gdca_loop_sol {
    double f0[CTC_DENSE_MAX], fj[CTC_DENSE_MAX], fn[CTC_DENSE_MAX];
    double al1[CTC_DENSE_MAX], al2[CTC_DENSE_MAX];
    double ar1[CTC_DENSE_MAX], ar2[CTC_DENSE_MAX];
    double ab[CTC_DENSE_MAX];
    double cond; /* max/min squared Cholesky pivot of the scaled matrix; inf when singular */
} gdca_loop_sol;

/* Solves the root problem p into s. Returns 0, or -1 when the matrix is not numerically positive
 * definite (the loads and accelerations are then NaN). */
int gdca_loop_solve(const gdca_loop_root *p, gdca_loop_sol *s);

/* off (nc = dim - nv_n) = the Baumgarte term 2 a dphi + b^2 phi of d->baumgarte (data.h), the
 * right-hand side of the forward pass's closure D_n^T (A_t + beta_n - A_child) = off. */
void gdca_loop_offset(const ctc_model *m, const ctc_data *d, double *off);

/* Writes the solution's joint loads into jnt_load (njoints x dim: joints 0, j and n; added to
 * what is there when add) and hands the root's loads down to the disassembly in tload
 * ((2n - 1) x 2 dim, by assembly index): the loop's record on the ground carries (F0, -Fn); on a
 * body, L carries (F0, -Fj + Fn moved to p1) and R (Fj, -Fn). shift is d->loop_r. */
void gdca_loop_hand_down(const ctc_model *m, const gdca_loop_sol *s, const double *shift, int add,
                         double *tload, double *jnt_load);

/* out = body b's classical acceleration at p2 from the one at p1 (dim): the rigid shift
 * (alpha; a + alpha x r) of gdca_tree.h's ctc_transfer_motion, + gam, r = p2 - p1 (3). out may
 * not alias in. */
void gdca_loop_shift_accel(int dim, const double *r, const double *gam, const double *in,
                           double *out);

#endif
