/*
 * joints.js - the joint kinds the page knows, written once: each type's number of position
 * coordinates nq (its entries of q) and velocity coordinates nv (its entries of qdot, and its
 * controlled coordinates when independent), as the library's table of joint kinds has them
 * (src/include/model.h ctc_joint_class, src/model/joint.c). Revolute and prismatic: one angle or
 * displacement; cylindrical: (angle, displacement); spherical: a unit quaternion (w, x, y, z)
 * moved by a 3-vector angular velocity; fixed: none.
 *
 * The page keeps its own copy rather than asking the server, so it works on a stored job alone;
 * tests/api/joints.test.mjs checks it against `ctcsim validate` (every type the job format
 * accepts is here, with the q0 and v0 lengths the parser gives it), so the two cannot drift.
 * JOINT_NQ and JOINT_NV are the same table by type name, for lookups as NQ[type] ?? 0.
 */

export const JOINTS = Object.freeze({
  revolute: Object.freeze({nq: 1, nv: 1}),
  prismatic: Object.freeze({nq: 1, nv: 1}),
  cylindrical: Object.freeze({nq: 2, nv: 2}),
  spherical: Object.freeze({nq: 4, nv: 3}),
  fixed: Object.freeze({nq: 0, nv: 0}),
});

export const JOINT_NQ = Object.freeze(Object.fromEntries(Object.entries(JOINTS).map(([t, j]) => [t, j.nq])));
export const JOINT_NV = Object.freeze(Object.fromEntries(Object.entries(JOINTS).map(([t, j]) => [t, j.nv])));
