/*
 * dart_peer.h - DART (Debian's libdart-dev, 6.12) as a peer of ctcsim in bench_mujoco: a chain
 * or tree of revolute joints built from a ctcsim spec, and one CTC right-hand side in DART's
 * O(n) recursive algorithms (inverse dynamics, then the articulated-body forward dynamics at the
 * same state). C on the outside, C++ inside (dart_peer.cpp).
 *
 * The skeleton has one body per ctcsim body, in the spec's order: its joint frame at the joint's
 * location in the parent's frame, parallel to it at q = 0 (model.h), the child's frame at the
 * joint, the revolute axis in it, mass, centre of mass and inertia about the centre of mass as
 * the spec gives them, the spec's gravity; no damping, springs, limits or contacts. So DART's
 * q, v, tau and qdd are ctcsim's, entry for entry.
 *
 * Built without DART's headers (the Makefile's DART_FOUND), dart_peer_available() is 0 and
 * dart_peer_new always fails with a message saying so: bench_mujoco then skips DART.
 */
#ifndef CTC_BENCH_DART_PEER_H
#define CTC_BENCH_DART_PEER_H

#include "model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct dart_peer dart_peer;

/* 1 when this build has DART, else 0 */
int dart_peer_available(void);

/* DART's version, "6.12.1"; "(not in this build)" without DART */
const char *dart_peer_version(void);

/* A new skeleton of spec (revolute joints only). NULL, with the reason in err (size errsz),
 * when a joint is not revolute or the build has no DART. Free with dart_peer_free (NULL
 * allowed). */
dart_peer *dart_peer_new(const ctc_chain_spec *spec, char *err, int errsz);

void dart_peer_free(dart_peer *p);

/* One CTC right-hand side at (q, v) (n each): tau = M(q) u + c(q, v) by DART's inverse
 * dynamics, then qdd = M(q)^-1 (tau - c(q, v)) by its forward dynamics, sharing the kinematics.
 * tau and qdd (n) are written; either may be NULL. */
void dart_peer_rhs(dart_peer *p, const double *q, const double *v, const double *u, double *tau,
                   double *qdd);

/* qdd = M(q)^-1 (tau - c(q, v)) alone, DART's articulated-body forward dynamics */
void dart_peer_forward(dart_peer *p, const double *q, const double *v, const double *tau,
                       double *qdd);

#ifdef __cplusplus
}
#endif

#endif
