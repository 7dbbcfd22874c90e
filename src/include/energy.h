/*
 * energy.h - kinetic and potential energy of the chain in the state of the last kinematics pass.
 *
 *     T = sum_k 1/2 m_k |v_c,k|^2 + 1/2 omega_k^T (R_k I_k R_k^T) omega_k
 *     V = - sum_k m_k g . c_k
 *
 * with c_k the centre of mass in world coordinates (V is zero for mass at the world origin) and
 * v_c,k = v_k + omega_k x (c_k - x_k) its velocity. In planar form the same is computed in the
 * plane's coordinates with the inertia about the plane normal. Units: J. A passive chain without
 * disturbance conserves T + V, which the simulation reports as its energy drift.
 */
#ifndef CTC_ENERGY_H
#define CTC_ENERGY_H

#include "data.h"

/* Kinetic and potential energy (J) from d's kinematics (ctc_kinematics must have run). */
void ctc_energy(const ctc_model *m, const ctc_data *d, double *kinetic, double *potential);

#endif
