/*
 * series.js - fetching a finished job's series for the plots, the animation and the heat-map,
 * and which coordinate each column of the controller's channels belongs to.
 *
 * Everything comes in the compact binary form (?format=f32: float32, about a fifth of the
 * JSON's bytes). The plots ask for at most two rows per pixel of their width: every sample
 * when that is enough, otherwise min/max per bucket (?reduce=minmax), so a spike of one sample
 * still shows. Chains with more than MAX_PLOTTED coordinates plot a few (the worst by RMS
 * error, or the joint picker's choice: joints=...), and the animation then fetches q and q_des
 * of every coordinate in a second request of at most ANIM_VALUES values (frames x columns),
 * plain strides, since a pose must be one instant's. The heat-map fetches |e| of every
 * controlled coordinate as min/max per bucket, at most HEAT_VALUES values.
 *
 * The controller's channels (q_des, qdot_des, e, tau, w) have one column per controlled
 * coordinate: every coordinate of an open chain, the independent coordinates of a closed chain
 * (scene.loop) in joint order, the closing joint's last. metrics.coordinates names each one's
 * joint and its index in qdot; jobs stored before it existed get the same list from the spec.
 */
import {getSeriesF32} from "./api.js";
import {JOINT_NQ as NQ, JOINT_NV as NV} from "./joints.js";

export const MAX_PLOTTED = 24;
/* the coordinates a large chain plots at first: its worst by RMS error */
export const FIRST_PLOTTED = 8;
/* values (rows x columns) fetched at most for the animation and for the heat-map: with the plots'
   few hundred kilobytes, a 4096-link job's page stays under 5 MB */
export const ANIM_VALUES = 400000;
export const HEAT_VALUES = 400000;
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

/* The coordinates a large chain plots before the user picks: the FIRST_PLOTTED worst by RMS
 * error (open chains, where e's column i is coordinate i), else the first ones; in index order. */
export function defaultJoints(job) {
  const m = job.metrics || {};
  const nv = m.nv ?? job.scene.coordinates;
  if (nv <= MAX_PLOTTED) return null;
  const rms = !job.spec.scene.loop && Array.isArray(m.e_rms) && m.e_rms.length === nv ? m.e_rms : null;
  const order = Array.from({length: nv}, (_, i) => i);
  if (rms) order.sort((a, b) => Math.abs(rms[b] ?? 0) - Math.abs(rms[a] ?? 0) || a - b);
  return order.slice(0, FIRST_PLOTTED).sort((a, b) => a - b);
}

/* The rows to ask for a plot widthPx wide: {every, maxPoints, reduce}. */
function plotRows(samples, widthPx) {
  const rows = 2 * Math.max(200, Math.round(widthPx));
  return samples <= rows ? {every: 1, maxPoints: Math.max(2, samples), reduce: "stride"}
    : {every: 1, maxPoints: rows, reduce: "minmax"};
}

/* Whether loadPlotSeries's answer serves the animation too (every coordinate, plain strides). */
export function plotsCoverAnimation(job, widthPx, joints = defaultJoints(job)) {
  const m = job.metrics || {};
  return !joints && plotRows(m.samples || 1, widthPx).reduce === "stride";
}

/* -> {series (for the plots), joints (coordinate index of each plotted row, or null = all),
 *     coords (controlledCoordinates), loop (the job is a closed chain), anim (series with t, q,
 *     q_des of every coordinate, or null when q was not recorded)}. joints: the coordinates to
 *     plot (sorted), or undefined for defaultJoints. */
export async function loadPlotSeries(job, widthPx, signal, joints = defaultJoints(job)) {
  const m = job.metrics || {};
  const recorded = (job.spec.output && job.spec.output.channels) || WANTED;
  const channels = WANTED.filter((c) => recorded.includes(c));
  const samples = m.samples || 1;
  const rows = plotRows(samples, widthPx);
  const series = await getSeriesF32(job.id, {channels, joints, ...rows}, signal);
  const loop = Boolean(job.spec.scene && job.spec.scene.loop);
  return {series, joints, coords: controlledCoordinates(job), loop,
    anim: plotsCoverAnimation(job, widthPx, joints) ? series : null};
}

/* The animation's series: t, q and q_des of every coordinate, plain strides, at most
 * ANIM_VALUES values (and two frames per pixel of widthPx). */
export function loadAnimSeries(job, widthPx, signal) {
  const m = job.metrics || {};
  const recorded = (job.spec.output && job.spec.output.channels) || WANTED;
  const channels = ["q", "q_des"].filter((c) => recorded.includes(c));
  if (!channels.includes("q")) return Promise.resolve(null);
  const columns = 1 + (m.nq ?? job.scene.coordinates) + (channels.includes("q_des") ? (m.nind ?? m.nv ?? 0) : 0);
  const frames = Math.max(2, Math.min(2 * Math.max(200, Math.round(widthPx)), Math.floor(ANIM_VALUES / columns)));
  return getSeriesF32(job.id, {channels, maxPoints: frames, reduce: "stride"}, signal);
}

/* The heat-map's series: e of every controlled coordinate as min/max per bucket, at most
 * `buckets` buckets and HEAT_VALUES values; null when e was not recorded. */
export function loadHeatSeries(job, buckets, signal) {
  const m = job.metrics || {};
  const recorded = (job.spec.output && job.spec.output.channels) || WANTED;
  if (!recorded.includes("e") || !(m.nind > 0)) return Promise.resolve(null);
  const most = Math.max(2, Math.floor(HEAT_VALUES / (2 * (m.nind + 1))));
  return getSeriesF32(job.id, {channels: ["e"], maxPoints: 2 * Math.max(1, Math.min(buckets, most)),
    reduce: "minmax"}, signal);
}

/* A running job's samples from sample `from` on (?partial=1), every `every`-th (and the last),
 * for the plots: the coordinates defaultJoints picks. -> {series, next (the sample to ask from
 * next time), joints}. */
export async function loadPartialSeries(job, from, every, signal) {
  const recorded = (job.spec.output && job.spec.output.channels) || WANTED;
  const channels = WANTED.filter((c) => recorded.includes(c) && c !== "energy" && c !== "loop");
  const joints = defaultJoints(job);
  const series = await getSeriesF32(job.id, {channels, joints, every, maxPoints: 1e9, from, partial: true}, signal);
  const dt = job.spec.output.interval;
  const last = series.t.length ? series.t[series.t.length - 1] : null;
  return {series, joints, next: last === null ? from : Math.round(last / dt) + 1};
}

/* Appends the columns of b to those of a (both columnar series of the same channels). */
export function appendSeries(a, b) {
  if (!a) return b;
  for (const [k, v] of Object.entries(b)) {
    if (k === "t") a.t.push(...v);
    else if (Array.isArray(v) && Array.isArray(a[k])) v.forEach((col, i) => a[k][i].push(...col));
  }
  a.rows = a.t.length;
  return a;
}
