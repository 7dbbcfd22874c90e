/*
 * plant.h - what a controlled coordinate of the plant has beyond the rigid-body dynamics: the
 * actuator's torque (or force) limit, friction, and a spring and damper in the joint (sim.h
 * ctc_sim_spec.plant).
 *
 * Saturation. The actuator of coordinate i delivers sat(f_i) = min(max(f_i, -limit), limit) of
 * the controller's force f_i (N m for a revolute coordinate, N for a prismatic one). The plant
 * receives sat(f_i) + z_i(t): the disturbance z (disturb.h) is a load on the joint, not the
 * actuator's output, so it is not limited. The controller's integral state is protected from
 * windup by clamping (conditional integration): while coordinate i is clipped and its error
 * e_i = q_d,i - q_i has the sign of the clipped excess f_i - sat(f_i), d/dt int(e_i) = 0; at any
 * other time d/dt int(e_i) = e_i. (With kp, kv > 0 a positive e_i raises w_i and so f_i, since
 * M(q) has a positive diagonal: integrating it would only push further into the limit.)
 *
 * Joint forces. The joint itself adds the generalised force
 *     tau_j(q_i, v_i) = -viscous v_i - coulomb tanh(v_i / coulomb_velocity)
 *                       - spring (q_i - spring_rest)
 * to what the forward dynamics receive (N m for a revolute coordinate, N for a prismatic one;
 * q_i, v_i the coordinate's position and rate). Viscous friction and a damper are the same term.
 * Coulomb friction is regularised: tanh makes it smooth, so the integrators' error control stays
 * valid, at the price of a creep: under a steady load F below the friction level coulomb the
 * joint does not stick but slides at v = coulomb_velocity atanh(F / coulomb) (at most
 * 0.55 coulomb_velocity for F <= coulomb / 2); above it, it accelerates as a joint with the
 * constant friction coulomb once |v| >> coulomb_velocity (tanh(5) = 1 - 9e-5). A smaller
 * coulomb_velocity is more accurate and stiffer (d tau_j / d v = -coulomb / coulomb_velocity):
 * "bdf" integrates it in fewer steps than the explicit methods.
 * When `known` is set, the controller's model has these terms too: the controller adds -tau_j to
 * its force before the actuator's limit, so that with an exact model and no limit reached the
 * error dynamics are the linear law of ctrl.h again. Otherwise the controller ignores them.
 *
 * Sensors. A sampled controller (sim.h sample_period) sees, at each of its instants, the
 * coordinate's position and rate as measured:
 *     q_m = resolution round((q + noise_q n1) / resolution)   (q + noise_q n1 when resolution 0)
 *     v_m = v + noise_v n2
 * with n1, n2 standard normal draws from the run's generator (sim.h seed): an encoder's counts
 * after Gaussian noise. Draws are taken at each instant, coordinate by coordinate, n1 then n2,
 * each only where its standard deviation is positive, so the same seed gives the same run bit
 * for bit. The generator is splitmix64 (s += 0x9e3779b97f4a7c15, then the mix of Steele, Lea and
 * Flood 2014), u = (x >> 11) 2^-53, and a normal n = sqrt(-2 ln(1 - u_a)) cos(2 pi u_b) from two
 * successive uniforms (Box-Muller, the cosine branch only). Open chains only.
 *
 * Armature. The reflected inertia of the actuator's rotor (gear ratio squared times the rotor's
 * inertia), armature_i in kg m^2 (kg for a prismatic coordinate), is added to the diagonal of the
 * joint-space mass matrix: the plant's accelerations solve
 *     (M(q) + diag(armature)) qdd = f - h(q, v)
 * (Featherstone 2008, section 9.6; MuJoCo's dof_armature). GDCA's assembly is not changed: the
 * plant solves this exactly from k + 1 forward passes at the same state, k the number of
 * coordinates with armature (ctc_plant_forward_armature below). When `known` is set, the
 * controller adds armature_i u_i to its force, u the commanded acceleration (the inverse
 * dynamics of the plant with armature: iGDCA's force plus armature u), so that with an exact
 * model the error dynamics are the linear law of ctrl.h again. Open chains only.
 *
 * A zero-initialised ctc_plant_coord is the ideal coordinate of the paper: no limit, no joint
 * force, exact sensors.
 */
#ifndef CTC_PLANT_H
#define CTC_PLANT_H

#include "data.h"
#include "model.h"

typedef struct ctc_plant_coord {
    double torque_limit;     /* N m, or N for a prismatic coordinate: > 0 saturates the actuator at
                                +-torque_limit; 0 = none */
    double viscous;          /* N m s/rad, N s/m: >= 0 */
    double coulomb;          /* N m, N: >= 0, the friction level */
    double coulomb_velocity; /* rad/s, m/s: > 0 when coulomb > 0, the regularisation's scale */
    double spring;           /* N m/rad, N/m: >= 0 */
    double spring_rest;      /* rad, m: the spring's rest position */
    double armature;   /* kg m^2, kg: >= 0, the reflected rotor inertia added to M's diagonal */
    int known;         /* 1: the controller's model has the joint forces and the armature */
    double noise_q;    /* rad, m: >= 0, the position noise's standard deviation */
    double noise_v;    /* rad/s, m/s: >= 0, the rate noise's standard deviation */
    double resolution; /* rad, m: >= 0, the encoder's count; 0 = continuous */
} ctc_plant_coord;

/* The joint force tau_j of coordinate p at position q and rate v (above). Pure. */
double ctc_plant_joint_force(const ctc_plant_coord *p, double q, double v);

/* 1 when p adds a joint force (any of viscous, coulomb, spring non-zero). */
int ctc_plant_has_joint_force(const ctc_plant_coord *p);

/* 1 when p's sensors are not exact (noise_q, noise_v or resolution non-zero). */
int ctc_plant_has_sensor_error(const ctc_plant_coord *p);

/* The generator of the sensors' noise (above): the next standard normal draw, advancing *state. */
double ctc_plant_normal(unsigned long long *state);

/* The same generator's next uniform draw in [0, 1), u = (x >> 11) 2^-53 (above), advancing
 * *state: for seeded draws of a model's errors (Monte-Carlo studies). */
double ctc_plant_uniform(unsigned long long *state);

/* The accelerations qdd (nv) of an open-chain model m with armature arm (nv, >= 0, per velocity
 * coordinate) under the generalised forces f (nv): (M(q) + diag(arm)) qdd = f - h(q, v), for the
 * state whose kinematics and body handle equations d holds (ctc_kinematics, ctc_handles). With
 * J the k coordinates where arm > 0 and X = M^-1 (columns J), from k + 1 GDCA forward passes
 * qdd0 = GDCA(f) and X e_j = GDCA(f + e_j) - qdd0:
 *     (I + X_JJ diag(arm_J)) qdd_J = qdd0_J,   qdd = qdd0 - X_J diag(arm_J) qdd_J
 * (I + X_JJ A_J is non-singular: X_JJ is positive definite and A_J >= 0), solved by Gaussian
 * elimination with partial pivoting. work holds ctc_plant_armature_work(nv, k) doubles. With no
 * armature it is ctc_gdca_forward. Not thread-safe on one d; allocates nothing. */
void ctc_plant_forward_armature(const ctc_model *m, ctc_data *d, const double *arm, const double *f,
                                double *qdd, double *work);

/* the size in doubles of ctc_plant_forward_armature's work for nv coordinates, k with armature */
static inline int ctc_plant_armature_work(int nv, int k)
{
    return nv + nv * k + k * k + k;
}

#endif
