/*
 * gdca_loop.h - the boundary equations of a closed chain, shared by the forward and the inverse
 * passes of loop models (internal to the library; paper section 5, Eq. 55-65, and its
 * reference [48]).
 *
 * After the assembly the whole chain is one record h (data.h) with handle 1 at joint 0 and
 * handle 2 at the closing joint's point on the tip. Both handles are jointed to the ground:
 *     F1 = S1 x1 + F1o,      S1^T (A1 - a1) = 0                 (joint 0: ground -> body 0)
 *     F2 = -(S2 x2 + F2o),   S2^T (A2 + a2) = s2                (closing joint: tip -> ground)
 * where F1 is the load on the chain at handle 1, F2 at handle 2 (the closing joint's load on the
 * ground is -F2), and for each end either
 *     the joint's acceleration is unknown (a dependent joint, or any joint in the forward pass):
 *         S = D (its constraint directions), Fo = P f (its driving force), a = beta;
 *     or it is commanded (an independent joint in the inverse pass, Eq. 19):
 *         S = 1 (the whole load is unknown), Fo = 0, a = P u + beta.
 * s2 is the Baumgarte term of the forward pass (zero otherwise). With A1 = h11 F1 + h12 F2 + h13
 * and A2 = h21 F1 + h22 F2 + h23 this is the symmetric system
 *     [ S1^T h11 S1   -S1^T h12 S2 ] [x1]   [ S1^T (a1 - h13 - h11 F1o + h12 F2o)      ]
 *     [-S2^T h21 S1    S2^T h22 S2 ] [x2] = [ S2^T (a2 + h23 + h21 F1o - h22 F2o) - s2 ]
 * whose matrix is a congruence of the chain's mobility, positive definite when the unknown
 * accelerations determine the loop and singular when they do not (a singular configuration, or
 * redundant constraints). It is solved by Cholesky after symmetric diagonal scaling.
 */
#ifndef CTC_GDCA_LOOP_H
#define CTC_GDCA_LOOP_H

/* One end of the boundary problem: s has ns columns of length dim at s[c dim]; s == NULL means
 * the identity (ns = dim). fo and a have dim entries; s2 (end 2 only) ns entries or NULL. */
typedef struct gdca_end {
    const double *s;
    int ns;
    const double *fo, *a, *off;
} gdca_end;

/* Solves the boundary equations for the root record h (dim 3 or 6) into f1 and f2 (dim each)
 * and the accelerations a1 = A1, a2 = A2 of the handles (dim each). *cond receives the
 * condition estimate (max/min squared Cholesky pivot of the scaled matrix; inf when singular).
 * Returns 0, or -1 when the matrix is not numerically positive definite (outputs NaN). */
int gdca_loop_boundary(int dim, const double *h, const gdca_end *e1, const gdca_end *e2, double *f1,
                       double *f2, double *a1, double *a2, double *cond);

#endif
