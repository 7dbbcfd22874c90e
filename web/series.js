/*
 * series.js - fetching a finished job's series for the plots and the animation, and which
 * coordinate each column of the controller's channels belongs to.
 *
 * The server decimates (every=N keeps every N-th sample and always the last), so a long run
 * costs no more than the plot can show: N = ceil(samples / (2 * plot width in px)); getSeries
 * also asks for at most SERIES_MAX_POINTS samples (max_points), a bound whatever the width. Chains with
 * more than MAX_PLOTTED coordinates plot the first MAX_PLOTTED (joints=0,1,...); the animation
 * then fetches q and q_des for all of them in a second request.
 *
 * The controller's channels (q_des, qdot_des, e, tau, w) have one column per controlled
 * coordinate: every coordinate of an open chain, the independent coordinates of a closed chain
 * (scene.loop) in joint order, the closing joint's last. metrics.coordinates names each one's
 * joint and its index in qdot; jobs stored before it existed get the same list from the spec.
 */
import {getSeries} from "./api.js";
import {decimation} from "./plots.js";
import {JOINT_NQ as NQ, JOINT_NV as NV} from "./joints.js";

export const MAX_PLOTTED = 24;
const WANTED = ["q", "q_des", "e", "tau", "w", "energy", "loop"];

/* The controlled coordinates of a job: [{joint, coordinate, row, label}] in column order.
 * coordinate: the index in qdot (a closing joint's from nv on); row: the plotted row it goes
 * with, its index in q (a closing joint's from nq on, beyond q's rows), which gives its colour
 * and its toggle; label: "joint k" ("joint k.m" for the m-th coordinate of a joint that has
 * several) or "closing joint". */
export function controlledCoordinates(job) {
  const bodies = (job.spec && job.spec.scene && job.spec.scene.bodies) || [];
  const loop = job.spec && job.spec.scene ? job.spec.scene.loop : undefined;
  const joints = bodies.map((b) => b.joint || {});
  if (loop) joints.push(loop.joint || {});
  /* where each joint's coordinates start in qdot and in q */
  const vadr = [], qadr = [];
  let v = 0, q = 0;
  for (const j of joints) { vadr.push(v); qadr.push(q); v += NV[j.type] ?? 0; q += NQ[j.type] ?? 0; }
  const entry = (k, coordinate) => {
    const m = coordinate - vadr[k];
    const base = loop && k === bodies.length ? "closing joint" : `joint ${k}`;
    return {joint: k, coordinate, row: qadr[k] + m,
      label: (NV[joints[k] && joints[k].type] ?? 1) > 1 ? `${base}.${m}` : base};
  };
  const listed = job.metrics && job.metrics.coordinates;
  if (Array.isArray(listed)) return listed.filter((c) => c.joint < joints.length).map((c) => entry(c.joint, c.coordinate));
  const out = [];
  joints.forEach((j, k) => {
    const independent = !loop || (k === bodies.length ? j.independent === true : j.independent !== false);
    for (let m = 0; independent && m < (NV[j.type] ?? 0); m++) out.push(entry(k, vadr[k] + m));
  });
  return out;
}

/* -> {series (for the plots), joints (coordinate index of each plotted row, or null = all),
 *     coords (controlledCoordinates), loop (the job is a closed chain), anim (series with t, q,
 *     q_des of every coordinate), every} */
export async function loadPlotSeries(job, widthPx, signal) {
  const m = job.metrics || {};
  const recorded = (job.spec.output && job.spec.output.channels) || WANTED;
  const channels = WANTED.filter((c) => recorded.includes(c));
  const every = decimation(m.samples || 1, widthPx);
  const nv = m.nv ?? job.scene.coordinates;
  const joints = nv > MAX_PLOTTED ? Array.from({length: MAX_PLOTTED}, (_, i) => i) : null;
  const series = await getSeries(job.id, {channels, joints, every}, signal);
  let anim = series;
  if (joints && channels.includes("q")) {
    anim = await getSeries(job.id, {channels: channels.filter((c) => c === "q" || c === "q_des"), every}, signal);
  }
  const loop = Boolean(job.spec.scene && job.spec.scene.loop);
  return {series, joints, coords: controlledCoordinates(job), loop, anim, every};
}
