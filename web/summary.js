/*
 * summary.js - what tells runs apart: each job's figures of merit from its metrics
 * (server/result_out.h), and a short label per job that names its controller and what differs
 * between the jobs compared ("pid, kp = 400"), not its number.
 *
 * Figures: per controlled coordinate the final, RMS and largest |e| (for computed torque control
 * the largest is usually the initial error, the same for every controller of a scene: the final
 * and RMS errors are the ones that rank them), the peak |tau| over the actuators, the relative
 * energy drift (passive runs), the controller's type and gains, and the cost, µs per evaluation
 * of the dynamics.
 *
 * Differences: the normalised specs are flattened to leaves (objects key by key, arrays of
 * objects entry by entry, an array of numbers one leaf, "scene" one leaf) and the leaves whose
 * values are not all equal are the ones named, at most three after the controller's type; the
 * controller's parameters where they differ among the jobs of one type; when the scenes differ, the
 * scene alone, by its preset's name or its bodies ("pd, five_bar_pd"), since everything else
 * follows from it. Jobs that still share a label get their id after it.
 */
import {fmtNum} from "./dom.js";

const isObject = (v) => v !== null && typeof v === "object" && !Array.isArray(v);
const maxOf = (xs) => (Array.isArray(xs) && xs.some((x) => typeof x === "number") ?
  Math.max(...xs.filter((x) => typeof x === "number").map(Math.abs)) : null);

/* gains as text: "kp 100, kv 20, ki 250" (every coordinate alike) or per coordinate */
export function gainsText(gains) {
  if (!Array.isArray(gains) || !gains.length) return "–";
  const text = gains.map((g) => Object.entries(g).map(([k, v]) => `${k} ${fmtNum(v)}`).join(", "));
  return text.every((s) => s === text[0]) ? text[0] : text.map((s, i) => `${i}: ${s}`).join("; ");
}

/* The figures of one job (GET /api/jobs/{id}): {eFinal, eRms, eMax (arrays, per controlled
 * coordinate), tauPeak, energyDrift, usPerEval, controller, gains (text)}. */
export function jobFigures(job) {
  const m = job.metrics || {};
  const list = (xs) => (Array.isArray(xs) ? xs : []);
  return {
    eFinal: list(m.e_final), eRms: list(m.e_rms), eMax: list(m.e_max),
    tauPeak: maxOf(m.tau_peak), energyDrift: m.energy_drift ?? null, usPerEval: m.us_per_eval ?? null,
    controller: (job.spec && job.spec.controller && job.spec.controller.type) || job.controller || "–",
    gains: gainsText(m.gains),
  };
}

/* path -> JSON text of each leaf of a spec (see the file's comment); the scene is one leaf,
 * its JSON, named in labels by sceneName */
function leaves(spec) {
  const out = new Map();
  const walk = (v, path) => {
    if (path === "scene") {
      out.set(path, JSON.stringify(v));
      return;
    }
    if (isObject(v)) { for (const [k, x] of Object.entries(v)) walk(x, path ? `${path}.${k}` : k); return; }
    if (Array.isArray(v) && v.some((x) => isObject(x) || Array.isArray(x))) { v.forEach((x, i) => walk(x, `${path}[${i}]`)); return; }
    out.set(path, JSON.stringify(v));
  };
  for (const [k, v] of Object.entries(spec || {})) if (k !== "name" && k !== "tags") walk(v, k);
  return out;
}

/* a leaf's value for a label: numbers in 4 digits, strings bare */
function shown(text) {
  try {
    const v = JSON.parse(text);
    if (typeof v === "number") return fmtNum(v);
    if (typeof v === "string") return v;
    if (Array.isArray(v)) return `[${v.map((x) => (typeof x === "number" ? fmtNum(x) : String(x))).join(", ")}]`;
    return text;
  } catch {
    return text; /* a scene's name */
  }
}

/* A label per job (same order): "pid", "pid, kp = 400", "lqr, duration = 2", "pd, five_bar_pd";
 * jobs whose labels would be equal get " #ID". */
export function differenceLabels(jobs) {
  const flat = jobs.map((j) => leaves(j.spec));
  const sceneName = (j) => j.preset || `${(j.spec && j.spec.scene && j.spec.scene.bodies && j.spec.scene.bodies.length) || 0}-body scene`;
  const types = jobs.map((j) => (j.spec && j.spec.controller && j.spec.controller.type) || j.controller || "?");
  const paths = [];
  const seen = new Set();
  for (const f of flat) for (const p of f.keys()) if (!seen.has(p)) { seen.add(p); paths.push(p); }
  const differs = (p, members) => {
    const vals = members.map((i) => flat[i].get(p) ?? "(none)");
    return vals.some((v) => v !== vals[0]);
  };
  const all = jobs.map((_, i) => i);
  /* the controller's parameters differ among the jobs of one type; the rest among all */
  let differing = paths.filter((p) => !p.startsWith("controller.") && differs(p, all));
  const byType = new Map();
  for (const i of all) byType.set(types[i], [...(byType.get(types[i]) || []), i]);
  const ctrlDiffering = new Map([...byType].map(([t, members]) => [t,
    members.length > 1 ? paths.filter((p) => p.startsWith("controller.") && p !== "controller.type" && differs(p, members)) : []]));
  /* other scenes: the scene says it, the rest follows from it */
  if (differing.includes("scene")) differing = ["scene"];
  const labels = jobs.map((j, i) => {
    const mine = [...ctrlDiffering.get(types[i]), ...differing];
    const parts = mine.slice(0, 3).map((p) => {
      if (p === "scene") return sceneName(j);
      const name = p.startsWith("controller.") ? p.slice(11) : p;
      const v = flat[i].get(p);
      return v === undefined ? `no ${name}` : `${name} = ${shown(v)}`;
    });
    if (mine.length > 3) parts.push(`+${mine.length - 3} more`);
    return [types[i], ...parts].join(", ");
  });
  return labels.map((l, i) => (labels.indexOf(l) !== labels.lastIndexOf(l) ? `${l} #${jobs[i].id}` : l));
}
