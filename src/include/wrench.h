/*
 * wrench.h - an external wrench on a body of the plant (a push, a payload's weight, a contact
 * the controller does not see): a force at a point fixed in the body and a torque, constant,
 * sinusoidal or stepped in time, turned into generalised forces by the body's Jacobian.
 *
 * A wrench on body k is the force f (N) applied at the point p (m, in body k's frame, whose
 * origin is joint k's centre) and a torque n (N m), both scaled by s(t):
 *     constant  s = 1
 *     sine      s = sin(2 pi (t mod period) / period + phase)
 *     step      s = 0 for t < time, 1 from t = time on (a discontinuity: the run restarts there)
 * Their components are given in the world's axes (frame CTC_WRENCH_WORLD: the force keeps its
 * direction as the body turns, like a weight) or in the body's (CTC_WRENCH_BODY: the force
 * turns with the body, like a thruster), f_w = R_k f then. The plant receives the generalised
 * forces of the virtual work n . omega_k + f . v_x of the point x = x_k + R_k p:
 *     tau_ext = J_x(q)^T f_w + J_omega(q)^T n_w
 * computed per joint j on the path from the ground to body k (joints of bodies that are not k's
 * ancestors get nothing) from the joint's free-motion map P_j = (u_w; u_v) at its centre o_j
 * (kinematics.h), one column per coordinate:
 *     tau_ext,c = u_w . (n_w + (x - o_j) x f_w) + u_v . f_w
 * (Featherstone 2008, section 2.9: the power of a wrench about o_j on the motion P_j). In planar
 * form the plane's components are kept: the torque's along the normal and the force's in the
 * plane; the rest is carried by the joints' constraints and does no work.
 *
 * A wrench is part of the plant: the controller does not know it unless `known` is set, and then
 * subtracts tau_ext (at the state it measures) from its force before the actuators' limits, so
 * that with an exact model computed torque control tracks as if there were none. Open chains and
 * trees only (sim_check.c). A zero-initialised ctc_wrench is a constant zero wrench on body 0.
 */
#ifndef CTC_WRENCH_H
#define CTC_WRENCH_H

#include "data.h"
#include "model.h"

typedef enum ctc_wrench_profile {
    CTC_WRENCH_CONSTANT = 0,
    CTC_WRENCH_SINE,
    CTC_WRENCH_STEP,
} ctc_wrench_profile;

typedef enum ctc_wrench_frame {
    CTC_WRENCH_WORLD = 0, /* force and torque components in the world's axes */
    CTC_WRENCH_BODY,      /* in the body's axes: they turn with it */
} ctc_wrench_frame;

typedef struct ctc_wrench {
    int body;                   /* 0 .. nbodies - 1 */
    double point[3];            /* m, in the body's frame: where the force acts */
    double force[3];            /* N */
    double torque[3];           /* N m */
    ctc_wrench_frame frame;     /* the axes of force and torque */
    ctc_wrench_profile profile; /* s(t) above */
    double period;              /* s, > 0: sine only */
    double phase;               /* rad: sine only */
    double time;                /* s, >= 0: step only, when it comes on */
    int known;                  /* 1: the controller compensates it */
} ctc_wrench;

/* s(t) of wrench w (above). Pure. */
double ctc_wrench_scale(const ctc_wrench *w, double t);

/* Adds the generalised forces tau_ext (nv, N m or N per velocity coordinate) of wrench w at time
 * t to f, for the state whose kinematics d holds (ctc_kinematics). Open-chain or tree model m;
 * spherical joints get their angular columns as any other. Allocates nothing; pure but for f. */
void ctc_wrench_forces(const ctc_model *m, const ctc_data *d, const ctc_wrench *w, double t,
                       double *f);

/* "constant", "sine", "step"; "world", "body" */
const char *ctc_wrench_profile_name(ctc_wrench_profile p);
const char *ctc_wrench_frame_name(ctc_wrench_frame f);

#endif
