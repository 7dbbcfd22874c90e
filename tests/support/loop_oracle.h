/*
 * loop_oracle.h - an independent reference for the dynamics of a chain closed by one loop:
 * redundant joint coordinates, the loop's constraint Jacobian and Lagrange multipliers
 * (tests only; nothing here shares code with src/model/loop.c or the GDCA passes).
 *
 * The chain is the spec's bodies 0..n-1 on joints 0..n-1 (model.h), closed by the joint n from
 * the tip body n-1 (its parent) to its child, the ground or a body b <= n-2 of the chain (then
 * "the child's frame" below is b's, and its motion enters every formula; on the ground it is the
 * world at rest). Its dynamics are those of the open chain plus the closure:
 *
 *     M(q) qdd + h(q, v) = tau + G(q)^T lambda,        G(q) qdd + gamma(q, v) = 0,
 *
 * where M (nv x nv) is the open chain's mass matrix (the library's composite-rigid-body oracle,
 * oracle.h), h = RNEA(q, v, 0) its gravity and velocity-product forces (recursive Newton-Euler,
 * oracle.h), tau the generalised driving forces, phi(q) = 0 the closure (nc equations),
 * G = d phi / dq in velocity coordinates (G v = d phi / dt), gamma = (d G / dt) v, and lambda
 * the multipliers (nc): G^T lambda are the generalised forces the closing joint's constraint
 * exerts on the chain.
 *
 * Kinematics (written here, world frame, 3x3 rotations and 3-vectors, no spatial algebra):
 * R_k, p_k the orientation and origin (= joint k's centre) of body k, with
 * R_k = R_{k-1} R_j(q_k) and p_k = p_{k-1} + R_{k-1} (location_k + axis_k s_k), s_k a prismatic
 * or cylindrical displacement; u_k = R_{k-1} axis_k the joint's world axis. The tip point p_t =
 * p_{n-1} + R_{n-1} location_n is the closing joint's centre on the tip; its twist is
 * V_t = (omega_t; v_t) = J v with the unit twists of the chain's coordinates moved to p_t:
 *     revolute (cylindrical angle)      (u_k; u_k x (p_t - p_k))
 *     prismatic (cylindrical slide)     (0; u_k)
 *     spherical, coordinate i           (R_k e_i; R_k e_i x (p_t - p_k))   (child-frame rates)
 * and its classical acceleration at v' = 0, (alpha0_t; a0_t), comes from a forward pass of
 * accelerations (omega_parent x relative rates, centripetal and Coriolis terms), so that
 * (alpha_t; a_t) = J qdd + (alpha0_t; a0_t).
 *
 * The closure. Two kinds of scalar constraints, each with a unit vector c fixed in the child
 * (c = R_a c0; on the ground R_a = 1, omega_a = 0, and every term in omega_a or alpha0_a
 * vanishes), p_a the anchor, v_a and a0_a the child's point there:
 *     linear      phi = c . (p_t - p_a)           G row = c^T (J_lin - J_a,lin) + (c x r)^T J_a,ang
 *                 (r = p_t - p_a; J_a the child's unit twists at p_a)
 *                 gamma = c . (a0_t - a0_a) + (c x r) . alpha0_a + (omega_a x c) . rd
 *                         + omega_a . ((omega_a x c) x r + c x rd),   rd = v_t - v_a
 *     rotational  phi = c . w,  w = R_t b         G row = (w x c)^T (J_ang - J_a,ang)
 *                 (b a unit vector fixed in the tip)
 *                 gamma = (w x c) . (alpha0_t - alpha0_a)
 *                         + ((omega_t x w) x c + w x (omega_a x c)) . (omega_t - omega_a).
 * They are holonomic, so G is exactly d phi / dq and gamma exactly the second derivative of phi
 * at qdd = 0 (both checked against finite differences in test_loop.c). The closing joint's
 * axis a (unit, tip frame) and the convention that the child's frame is Rot(a, q_n) of the
 * tip's for a revolute joint (hence R_t a = R_a a when closed) and equal to it for a prismatic
 * one give (c0 in the child's frame):
 *     revolute    spatial: linear c = x, y, z; rotational b = a, c = two unit normals of a (5)
 *                 planar:  linear c = e1, e2 (2)
 *     prismatic   spatial: rotational (b, c) = (y, z), (z, x), (x, y); linear c = two unit
 *                 normals of a (5);  planar: rotational (b, c) = (e1, e2); linear c = n x a (2)
 *     spherical   linear c = x, y, z (3)
 * Planar: every joint (the closing one included) is revolute about +-n, prismatic normal to n
 * or fixed, with n the first revolute axis, and gravity is normal to n (or the spec forces
 * CTC_FORM_PLANAR); e1, e2, n is a right-handed basis with e1 = the normalised world x axis
 * projected on the plane (y when x is normal to it). A planar loop's out-of-plane rows vanish
 * identically, so they are dropped. Any set of constraint functions with the same zero set and
 * a full-rank Jacobian gives the same accelerations and driving forces on the closure; only the
 * multipliers depend on the choice.
 *
 * The closing joint's coordinates, as the library defines them (model.h: the child's motion
 * relative to the tip), follow from the chain's state: qd_n = C^T v, qdd_n = C^T qdd + c_b:
 *     revolute    qd_n = w . (omega_a - omega_t),  w = R_t a
 *     prismatic   qd_n = w . (v_a(p_t) - v_t)      (v_a(p_t): the child's point at p_t; its
 *                                                    derivative is the library's on the closure)
 *     spherical   qd_n = R_a^T (omega_a - omega_t) (in the child's frame)
 * and q_n (revolute) is the angle of R_t^T R_a about a.
 *
 * Extended vectors (nvx = nv + nvn) list the chain's velocity coordinates, then the closing
 * joint's, as in gdca.h. Independent joints (spec->independent, n + 1 flags; NULL = all but
 * the closing joint) carry the driving forces:
 *     tau = sum over independent chain coordinates i of f_i e_i + C f_n (closing joint
 *           independent: its force, applied by the tip on its child, does the power f_n qd_n).
 *
 * Forward dynamics: [M G^T; G 0] [qdd; -lambda] = [tau - h; -gamma] by LU with partial
 * pivoting (dependent entries of f are ignored).
 *
 * Inverse dynamics for CTC, given the commanded accelerations u of the independent coordinates:
 *   1. kinematics, nv equations in qdd: G qdd = -gamma (nc rows), qdd_i = u_i for each
 *      independent chain coordinate, and C^T qdd = u_n - c_b when the closing joint is
 *      independent (its nvn rows). With nind = nvx - dim independent coordinates this is square.
 *   2. dynamics, nv equations in the nind + nc unknowns (f_ind, lambda):
 *      S^T f_chain + C f_n + G^T lambda = M qdd + h, S selecting the independent chain
 *      coordinates and the C f_n columns present only when the closing joint is independent.
 * Both square systems are solved by LU with partial pivoting; either being singular (the
 * independent set cannot drive the loop, or the loop is over-constrained) returns -1.
 *
 * Units SI (kg, m, s, rad, N, N m). Arrays are laid out as in the library: q (nq) by joint with
 * spherical joints as unit quaternions (w, x, y, z), v (nv) with a spherical joint's rates the
 * child's angular velocity relative to its parent in the child's frame and its forces the
 * torque vector in the child's frame. Matrices are row-major. Not thread-safe per oracle.
 */
#ifndef CTC_TEST_LOOP_ORACLE_H
#define CTC_TEST_LOOP_ORACLE_H

#include "model.h"

typedef struct loop_oracle loop_oracle;

/* Sizes and form of an oracle (read-only for the caller). */
typedef struct loop_oracle_dims {
    int n;           /* bodies */
    int nq, nv;      /* the chain's position and velocity coordinates */
    int nqn;         /* the closing joint's position coordinates (1 or 4) */
    int nvn;         /* its velocity coordinates (1 or 3) */
    int nvx;         /* nv + nvn */
    int nc;          /* closure equations */
    int nind;        /* independent coordinates (closing joint included) */
    int planar;      /* 1 if the closure is written in the plane */
    double plane[9]; /* planar: e1, e2, n (world) */
} loop_oracle_dims;

/* Makes an oracle for spec (spec->loop non-NULL; the spec is copied and need not outlive it).
 * Returns NULL if the spec has no loop, an open-chain model of it does not build, or memory
 * runs out. Free with loop_oracle_free (NULL allowed). */
loop_oracle *loop_oracle_new(const ctc_chain_spec *spec);
void loop_oracle_free(loop_oracle *o);

const loop_oracle_dims *loop_oracle_get_dims(const loop_oracle *o);

/* Tip point p_t (3, m), its orientation R_t (9, may be NULL), its velocity v_t (3, m/s; may be
 * NULL) and the tip's angular velocity omega_t (3, rad/s; may be NULL) at (q, v); v may be NULL
 * (then the velocities are zero). */
void loop_oracle_tip(loop_oracle *o, const double *q, const double *v, double pt[3], double rt[9],
                     double vt[3], double omega_t[3]);

/* The closure residual phi (nc) at q: m for linear rows, dimensionless (sines) for rotational. */
void loop_oracle_residual(loop_oracle *o, const double *q, double *phi);

/* The constraint Jacobian G (nc x nv) at q and, when v is not NULL, gamma = (dG/dt) v (nc). */
void loop_oracle_jacobian(loop_oracle *o, const double *q, const double *v, double *g,
                          double *gamma);

/* The closing joint's rate map: C (nv x nvn) and c_b (nvn) with qd_n = C^T v and
 * qdd_n = C^T qdd + c_b; qn (nqn; may be NULL) its coordinates (revolute only: the angle;
 * others get 0). */
void loop_oracle_closing(loop_oracle *o, const double *q, const double *v, double *cmap, double *cb,
                         double *qn);

/* Open-chain mass matrix (nv x nv) and h = RNEA(q, v, 0) (nv), from the library's oracle. */
void loop_oracle_mass_bias(loop_oracle *o, const double *q, const double *v, double *mass,
                           double *h);

/* Kinetic and potential energy (J) of the chain's bodies at (q, v), gravity potential zero at
 * the world origin. */
void loop_oracle_energy(loop_oracle *o, const double *q, const double *v, double *kinetic,
                        double *potential);

/* Forward dynamics: qacc (nvx) from the driving forces f (nvx; dependent entries ignored);
 * lambda (nc; may be NULL). Returns 0, or -1 if the KKT matrix is singular. */
int loop_oracle_forward(loop_oracle *o, const double *q, const double *v, const double *f,
                        double *qacc, double *lambda);

/* Inverse dynamics for CTC: the driving forces f (nvx; 0 on dependent coordinates) that give
 * the independent coordinates the accelerations u (nvx; dependent entries ignored), and the
 * resulting accelerations qacc (nvx; may be NULL). Returns 0, or -1 if a solve is singular. */
int loop_oracle_inverse(loop_oracle *o, const double *q, const double *v, const double *u,
                        double *f, double *qacc);

/* Puts (q, v) onto the closure (the oracle's own Newton method, least-norm steps on the
 * dependent chain coordinates, which the closing joint's independence may leave redundant):
 * independent chain coordinates are not changed. v may be NULL. Returns the number of
 * iterations, or -1 if the residual's max-norm is not below tol after max_iter. */
int loop_oracle_assemble(loop_oracle *o, double *q, double *v, double tol, int max_iter);

/* q (nq) moved by s times the velocity-space increment dv (nv): q_i += s dv_i, a spherical
 * joint's quaternion turned by the rotation vector s dv (child frame) and renormalised. Along
 * q(t) = q0 (+) t v with constant v the chain moves with velocity v exactly. */
void loop_oracle_q_add(const loop_oracle *o, double *q, const double *dv, double s);

/* Solves a (n x n, row-major, overwritten) x = b in place by LU with partial pivoting; returns
 * -1 if a pivot is below 1e-13 times the largest entry of a. */
int loop_oracle_lu_solve(double *a, int n, double *b);

/* ---- test loops ----
 * A loop_scene owns its spec's arrays (spec points into the struct: do not copy it; free()).
 * q0 is a configuration where the loop is closed exactly (by construction); independent[] is
 * spec.independent, editable. Joint centres, axes and the anchor follow model.h. */
#define LOOP_SCENE_MAX 16

typedef struct loop_scene {
    ctc_chain_spec spec;
    ctc_body_spec bodies[LOOP_SCENE_MAX];
    ctc_joint_spec joints[LOOP_SCENE_MAX];
    ctc_loop_spec loop;
    unsigned char independent[LOOP_SCENE_MAX + 1];
    int parent[LOOP_SCENE_MAX]; /* spec.parent: each body's parent (a chain: k - 1) */
    int nq, nv;
    double q0[4 * LOOP_SCENE_MAX];
} loop_scene;

/* The paper's planar five-bar (section 7.2): uniform 1 kg rods of lengths 1, 1, 0.5, 1, 1 m
 * hanging along -y at q = 0 from revolute joints about +z, joint 0 at the origin, gravity -y;
 * the closing revolute joint at the tip's far end, anchored where q0 = (-pi/8, 5pi/8, 3pi/8,
 * 3pi/8, 5pi/8) closes the loop (about (-0.2811, -0.6787, 0)); joints 0, 1, 2 independent. */
loop_scene *loop_scene_five_bar(void);

/* A planar crank-rocker four-bar: rods of 1 kg, crank 0.5 m, coupler 1.2 m, rocker 1 m, ground
 * pivots at the origin and (1, 0, 0); q0 closed with the crank at theta1 (rad, from -y) and the
 * coupler-rocker joint above the ground line. spatial: boxes 0.05 m thick instead of rods and
 * the form forced SPATIAL (over-constrained). Joint 0 (the crank) independent. */
loop_scene *loop_scene_four_bar(double theta1, int spatial);

/* A parallelogram four-bar: 1 kg rods, crank and rocker 1 m, coupler 1 m, pivots at the origin
 * and (1, 0, 0), closed at crank angle theta (from -y). The coupler translates, so
 * (5/3) theta'' = tau_0 - 2 g sin(theta) with tau_0 the crank's driving torque. */
loop_scene *loop_scene_parallelogram(double theta);

/* A planar offset slider-crank: crank rod 0.3 m 1 kg about the origin, connecting rod 1 m 1 kg,
 * slider 0.5 kg (the tip) on the line y = -0.2 m, closed by a prismatic joint along x to the
 * anchor (0, -0.2, 0); q0 closed at crank angle theta (from -y). Joint 0 independent. */
loop_scene *loop_scene_slider_crank(double theta);

/* A spatial RSSR linkage closed at q = 0: crank (revolute about x at the origin) to B =
 * (0, 0.4, 0), spherical joint, coupler to C = (0.3, 0.5, 1), spherical joint, rocker of radius
 * 0.6 m to the closing revolute joint at D on the axis (1, 0, -0.3) through it, the rocker
 * normal to the axis and to the coupler (good transmission at both ends); 1 kg boxes spanning
 * the links; gravity -z; mobility 2 (one of them the coupler's spin about B-C, which no
 * revolute joint drives); joints 0 and 3 independent. */
loop_scene *loop_scene_rssr(void);

/* A spatial RSSP linkage closed at q = 0: the RSSR's crank to B = (0, 0.4, 0), spherical
 * joint, coupler to C = (0.3, 0.5, 1), spherical joint, a 0.5 kg slider block (the tip) at C
 * closed by a prismatic joint along (0.3, 0.1, 1) to the anchor C; gravity -z; mobility 2 (one
 * of them the coupler's spin); joints 0 and 3 independent. */
loop_scene *loop_scene_rssp(void);

/* A spatial loop closed at q = 0: n bodies on revolute joints with random unit axes, links of
 * 0.3-0.6 m, masses 0.5-2 kg and full-rank inertias, closed by a joint of the given type
 * (revolute with a random axis, or spherical) at the tip's link end; gravity -z; mobility
 * n + 1 - 6 (revolute closing joint) or n + 3 - 6 (spherical); joints 0 and n independent
 * (edit to match the mobility). */
loop_scene *loop_scene_spatial(int n, ctc_joint_type closing, unsigned long long seed);

/* Closes s's loop on body `body` (0 <= body <= n - 2) instead of the ground: the closing joint
 * keeps its type, axis and centre on the tip, and its anchor becomes the tip's point at q0 in
 * body's frame, so q0 stays closed. The joints 0..body then lie outside the loop (model.h); the
 * caller sets the independent joints to match (the mobility does not change). The closure of
 * orientation needs the tip's and the body's frames to differ by a rotation about the closing
 * joint's axis at q0, as they do in every scene above (planar, or spatial ones at q0 = 0). */
void loop_scene_close_on(loop_scene *s, int body);

/* One body added to a loop scene as a branch off its loop's spine (loop_scene_branch). */
typedef struct loop_branch {
    int parent;          /* a body of the scene before the tip (0..n-2), or -2 - e for the
                            branch body e added before this one */
    ctc_joint_type type; /* REVOLUTE, PRISMATIC or SPHERICAL */
    double axis[3];      /* the joint's axis, parent frame */
    double location[3];  /* m, the joint's centre, parent frame */
    double q0[4];        /* its coordinates in q0 (a spherical joint's unit quaternion) */
} loop_branch;

/* Makes s (a scene whose bodies form a chain) a branched tree: the nb branch bodies are
 * inserted after the bodies 0..n-2 and before the tip, which keeps its parent (body n - 2), so
 * the bodies renumber as 0..n-2, the branches n-1..n+nb-2 in the order given, the tip
 * n + nb - 1; q0 gets each branch joint's coordinates before the tip's; the branch joints are
 * independent. The branch bodies are 0.6 kg boxes 0.1 x 0.4 x 0.12 m hanging along -y from their
 * joint centre. The loop's closure at q0 does not change (a branch does not move the spine). */
void loop_scene_branch(loop_scene *s, int nb, const loop_branch *br);

#endif
