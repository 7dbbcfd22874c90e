/*
 * kinematics.js - forward kinematics of a job's chain or tree for the animation, from the
 * normalised spec's bodies and one sample of joint coordinates q.
 *
 * Conventions (README "Conventions"): body k's frame has its origin at its inboard joint k and, at
 * q = 0, is parallel to the world; joint k's location and axis are given in the frame of its parent
 * p = parent[k] (chainParents: the body's "parent"; the world's for -1), which comes before it
 * (p < k). Revolute:
 * rotation by q about the axis; prismatic: translation by q along it; cylindrical: (angle,
 * displacement); spherical: unit quaternion (w, x, y, z), four entries of q; fixed: nothing. So R_k
 * = R_p Rot(axis, angle) and p_k = p_p + R_p (location + axis d), walking the parents as the
 * library does (src/include/model.h body_parent). Rotations are row-major 3x3 arrays. A closed
 * chain (scene.loop) ends its last body at the closing joint's centre (loop.joint.location, in the
 * last body's frame), which the loop keeps at loop.anchor: in the world, or with loop.body in that
 * body's frame (loopAnchor). closeLoop solves a loop's dependent coordinates for given
 * independent ones (the desired pose of a closed chain).
 */
import {JOINT_NQ as NQ} from "./joints.js";

const dot = (a, b) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
const norm = (a) => Math.hypot(a[0], a[1], a[2]);
export const add = (a, b) => [a[0] + b[0], a[1] + b[1], a[2] + b[2]];
export const scale = (a, s) => [a[0] * s, a[1] * s, a[2] * s];
export const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
export function unit(a) { const n = norm(a); return n > 0 ? scale(a, 1 / n) : [0, 0, 0]; }

const mulv = (R, v) => [R[0] * v[0] + R[1] * v[1] + R[2] * v[2],
  R[3] * v[0] + R[4] * v[1] + R[5] * v[2], R[6] * v[0] + R[7] * v[1] + R[8] * v[2]];

function mul(A, B) {
  const C = new Array(9);
  for (let i = 0; i < 3; i++) {
    for (let j = 0; j < 3; j++) C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
  }
  return C;
}

/* rotation by angle about the unit axis n (Rodrigues) */
function rotAxis(n, angle) {
  const c = Math.cos(angle), s = Math.sin(angle), v = 1 - c;
  const [x, y, z] = n;
  return [c + x * x * v, x * y * v - z * s, x * z * v + y * s,
    y * x * v + z * s, c + y * y * v, y * z * v - x * s,
    z * x * v - y * s, z * y * v + x * s, c + z * z * v];
}

/* rotation of the quaternion (w, x, y, z), normalised first (interpolated samples drift) */
function rotQuat(w, x, y, z) {
  const n = Math.hypot(w, x, y, z) || 1;
  w /= n; x /= n; y /= n; z /= n;
  return [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y),
    2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
    2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)];
}

/* The far end of the last body, in its frame: a rod's end, the end of a box along its longest
 * side or of a cylinder along its axis (the one farther from the joint), else twice the CoM. */
function tipOf(body) {
  const sh = body.shape;
  const c = (sh && sh.centre) || [0, 0, 0];
  const farther = (a, b) => (norm(a) >= norm(b) ? a : b);
  if (sh && sh.type === "rod") return sh.end;
  if (sh && sh.type === "box") {
    const i = sh.size.indexOf(Math.max(...sh.size));
    const d = [0, 0, 0];
    d[i] = sh.size[i] / 2;
    return farther(add(c, d), add(c, scale(d, -1)));
  }
  if (sh && sh.type === "cylinder") {
    const d = scale(unit(sh.axis), sh.length / 2);
    return farther(add(c, d), add(c, scale(d, -1)));
  }
  return body.com ? scale(body.com, 2) : [0, 0, 0];
}

/* Each body's parent (-1: the ground), as the job format reads it (server/job_json.h): the
 * body's "parent", an index (the normalised spec's form), a body's name or "ground"; absent,
 * the previous body (the ground for the first). An entry that names no body before its child
 * (a document the server would refuse) falls back to the previous body, so a drawing never
 * loops. A loop's closing joint is not an edge. */
export function chainParents(bodies) {
  return bodies.map((b, k) => {
    const p = b ? b.parent : undefined;
    let i = k - 1;
    if (p === "ground") i = -1;
    else if (typeof p === "string") i = bodies.findIndex((o) => o && o.name === p);
    else if (Number.isInteger(p)) i = p;
    return i >= -1 && i < k ? i : k - 1;
  });
}

/* The tree's constant part: per body its parent, its joint (type, unit axis, location), where
 * its coordinates start in q, and the points its drawn segments end at (in its own frame):
 * each child's joint centre (a palm with three fingers is drawn as a fan of three segments), or
 * for a body without children its tip, or on a loop's last body the closing joint's centre;
 * `end` is the first of them. */
export function chainLayout(bodies, loop) {
  let qi = 0;
  const parents = chainParents(bodies);
  const last = loop ? (loop.joint && loop.joint.location) || [0, 0, 0] : null;
  const children = bodies.map(() => []); /* each body's children, in order */
  parents.forEach((p, k) => { if (p >= 0) children[p].push(k); });
  return bodies.map((b, k) => {
    const j = b.joint;
    const leafEnd = k === bodies.length - 1 && last ? last : tipOf(b);
    const ends = children[k].length ? children[k].map((c) => bodies[c].joint.location || [0, 0, 0]) : [leafEnd];
    const link = {parent: parents[k], type: j.type, axis: j.axis ? unit(j.axis) : [0, 0, 1],
      loc: j.location || [0, 0, 0], qi, end: ends[0], ends};
    qi += NQ[j.type] ?? 0;
    return link;
  });
}

/* World positions for one q (a function i -> q[i]): per body its joint origin, the point on
 * the parent where the joint sits (differs for prismatic and cylindrical) and its drawn ends
 * (`ends`, one per segment of chainLayout; `end` the first). */
export function chainPose(layout, q) {
  const pose = [];
  for (const l of layout) {
    const up = l.parent >= 0 ? pose[l.parent] : null; /* the ground: at the origin, world axes */
    let R = up ? up.rot : [1, 0, 0, 0, 1, 0, 0, 0, 1];
    const p = up ? up.origin : [0, 0, 0];
    const attach = add(p, mulv(R, l.loc));
    let slide = 0;
    let Rj = null;
    if (l.type === "revolute") Rj = rotAxis(l.axis, q(l.qi));
    else if (l.type === "prismatic") slide = q(l.qi);
    else if (l.type === "cylindrical") { Rj = rotAxis(l.axis, q(l.qi)); slide = q(l.qi + 1); }
    else if (l.type === "spherical") Rj = rotQuat(q(l.qi), q(l.qi + 1), q(l.qi + 2), q(l.qi + 3));
    const origin = add(attach, scale(mulv(R, l.axis), slide));
    if (Rj) R = mul(R, Rj);
    const ends = (l.ends || [l.end]).map((e) => add(origin, mulv(R, e)));
    pose.push({attach, origin, end: ends[0], ends, rot: R});
  }
  return pose;
}

/* The world position of a loop's anchor for a pose of chainPose: fixed in the world, or on the
 * body loop.body (its frame) when the loop closes on a body. */
export function loopAnchor(loop, pose) {
  const a = loop.anchor || [0, 0, 0];
  const b = Number.isInteger(loop.body) ? pose[loop.body] : null;
  return b ? add(b.origin, mulv(b.rot, a)) : a;
}

/* The loop closed by moving the coordinates free (rows of q) from q (an array, not modified):
 * damped Gauss-Newton (Levenberg-Marquardt) on the gap between the last body's closing point
 * and the anchor (loopAnchor), with a forward-difference Jacobian, at most 30 iterations.
 * Returns {q, gap} (gap: the distance left, m). Used for a closed chain's desired pose, whose
 * dependent coordinates are not recorded (server: q_des holds the independent ones). */
export function closeLoop(layout, loop, q, free) {
  const x = q.slice();
  const gapOf = (v) => {
    const pose = chainPose(layout, (i) => v[i] ?? 0);
    const a = loopAnchor(loop, pose), e = pose[pose.length - 1].end;
    return [e[0] - a[0], e[1] - a[1], e[2] - a[2]];
  };
  let r = gapOf(x);
  let lambda = 1e-3;
  const m = free.length;
  for (let it = 0; it < 30 && m > 0 && norm(r) > 1e-12; it++) {
    const J = free.map((i) => {
      const h = 1e-7 * Math.max(1, Math.abs(x[i]));
      const y = x.slice(); y[i] += h;
      const ry = gapOf(y);
      return [(ry[0] - r[0]) / h, (ry[1] - r[1]) / h, (ry[2] - r[2]) / h];
    });
    /* (J^T J + lambda diag) dx = -J^T r, J^T J is m x m (m: the dependent coordinates, a few) */
    const A = J.map((ci, a) => J.map((cj, b) => dot(ci, cj) + (a === b ? lambda * (1 + dot(ci, ci)) : 0)));
    const rhs = J.map((ci) => -dot(ci, r));
    const dx = solveSmall(A, rhs);
    if (!dx) break;
    const y = x.slice();
    free.forEach((i, k) => { y[i] += dx[k]; });
    const ry = gapOf(y);
    if (norm(ry) < norm(r)) { free.forEach((i) => { x[i] = y[i]; }); r = ry; lambda = Math.max(1e-9, lambda / 10); }
    else lambda *= 10;
  }
  return {q: x, gap: norm(r)};
}

/* x with A x = b by Gaussian elimination with partial pivoting (A m x m, small); null if singular */
function solveSmall(A, b) {
  const m = b.length;
  const M = A.map((row, i) => [...row, b[i]]);
  for (let c = 0; c < m; c++) {
    let p = c;
    for (let r = c + 1; r < m; r++) if (Math.abs(M[r][c]) > Math.abs(M[p][c])) p = r;
    if (!(Math.abs(M[p][c]) > 1e-300)) return null;
    [M[c], M[p]] = [M[p], M[c]];
    for (let r = c + 1; r < m; r++) {
      const f = M[r][c] / M[c][c];
      for (let k = c; k <= m; k++) M[r][k] -= f * M[c][k];
    }
  }
  const x = new Array(m).fill(0);
  for (let r = m - 1; r >= 0; r--) {
    let v = M[r][m];
    for (let k = r + 1; k < m; k++) v -= M[r][k] * x[k];
    x[r] = v / M[r][r];
  }
  return x;
}

/* The plane a planar chain moves in: normal = the first rotation axis (z if none), "up" =
 * against gravity within that plane, "right" = up x normal (so x right, y up for the presets). */
export function planeBasis(bodies, gravity) {
  const rot = bodies.find((b) => b.joint.type === "revolute" || b.joint.type === "cylindrical");
  const n = rot ? unit(rot.joint.axis) : [0, 0, 1];
  const g = gravity || [0, -9.81, 0];
  let up = unit(add(scale(g, -1), scale(n, dot(g, n))));
  if (norm(up) === 0) up = unit(cross(n, Math.abs(n[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0]));
  return {right: cross(up, n), up};
}

/* For a spatial view: "up" against gravity (z if none) and two horizontal directions. */
export function worldBasis(gravity) {
  let up = unit(scale(gravity || [0, 0, -1], -1));
  if (norm(up) === 0) up = [0, 0, 1];
  const ref = Math.abs(up[0]) < 0.9 ? [1, 0, 0] : [0, 1, 0];
  const h1 = unit(add(ref, scale(up, -dot(ref, up))));
  return {up, h1, h2: cross(up, h1)};
}

export {dot, norm};
