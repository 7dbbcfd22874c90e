/*
 * plots.js - the time plots of one job or of several overlaid (uPlot): joint coordinates q with
 * the desired q_d, tracking error e, driving torques tau, controller output w,
 * energy and, for a closed chain, the loop's closure residuals, one div.plot[data-channel] each,
 * with data-points (samples drawn) and data-series (lines drawn, desired ones included).
 *
 * Every line of a coordinate carries its row of q (the joint toggles and the colours follow
 * it). The controller's channels have a column per controlled coordinate: for an open chain
 * every coordinate, so e[i] goes with q[i]; for a closed chain its independent coordinates,
 * labelled as the server names the columns (e[i], the i-th independent coordinate) with the
 * joint they belong to ("e[1] (joint 2)") and drawn in that joint's colour.
 *
 * Colours come from the Okabe-Ito palette (safe for the common colour vision deficiencies,
 * dark enough on white): in a job's plots each coordinate has its colour and q_d is dashed;
 * when comparing, each job has its colour and coordinates differ by dash pattern. The plots of
 * a set share the view's timeline: hovering a plot moves the time cursor, and moving the time
 * (slider, animation) puts every plot's cursor there, legends showing the values at that time.
 * Drag on a plot zooms the time axis of every plot; double-click, or "Reset zoom", restores it.
 * Sources of different sampling are aligned with uPlot.join (gaps spanned).
 */
import uPlot from "./vendor/uPlot.esm.js";
import {el, fmtNum} from "./dom.js";

export const PALETTE = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"];
const DASHES = [[], [10, 4], [3, 3], [12, 4, 3, 4]];
const HEIGHT = 230;
const AXIS = {stroke: "#1f2328", font: "13px system-ui, sans-serif",
  labelFont: "bold 13px system-ui, sans-serif", grid: {stroke: "#dde1e6", width: 1},
  ticks: {stroke: "#b8bec6", width: 1}};

export const CHANNELS = [
  {key: "q", title: "Joint coordinates q", axis: "q [rad | m]"},
  {key: "e", title: "Tracking error e = q_d − q", axis: "e [rad | m]"},
  {key: "tau", title: "Driving torques tau", axis: "tau [N m | N]"},
  {key: "w", title: "Controller output w (commanded acceleration)", axis: "w [rad/s² | m/s²]"},
  {key: "energy", title: "Energy", axis: "energy [J]"},
  {key: "loop", title: "Loop closure residuals (max-norms)", axis: "residual [m | rad, /s]"},
];
const LOOP_PARTS = ["position residual", "velocity residual"];

/* The row of q (joint toggle, colour) and the label of row r of a channel of src. */
function rowOf(key, src, rows, r) {
  const name = key;
  const coords = src.coords;
  if (key !== "q" && src.loop && coords && rows.length === coords.length) {
    return {j: coords[r].row, label: `${name}[${r}] (${coords[r].label})`};
  }
  const j = src.joints && rows.length === src.joints.length ? src.joints[r] : r;
  return {j, label: `${name}[${j}]`};
}

/* The desired q_d of q's row r (coordinate row j) in src, or null: q_des has a column per
 * controlled coordinate, every one of an open chain (fetched with the same joints as q). */
function desiredOf(src, r, j) {
  const des = src.series.q_des;
  if (!des) return null;
  if (!src.loop || !src.coords) return des[r] || null;
  const i = src.coords.findIndex((c) => c.row === j);
  return i >= 0 ? des[i] || null : null;
}

/* The lines of one channel: [{src, label, values, stroke, dash, width, joint, desired}] (joint:
 * the row of q the line belongs to, null for energy and the loop). Each source is {label,
 * color, series, joints (coordinate index of each row, or null), coords (series.js
 * controlledCoordinates), loop (a closed chain)}. */
function linesFor(key, sources, compare) {
  const lines = [];
  sources.forEach((src, s) => {
    const S = src.series;
    const pre = compare ? `${src.label} ` : "";
    if (key === "loop") {
      if (!S.loop || S.loop.length < 2) return;
      S.loop.forEach((values, i) => lines.push({src: s, label: `${pre}${LOOP_PARTS[i]}`, values,
        stroke: compare ? src.color : PALETTE[i], dash: compare ? DASHES[i] : [], width: 2, joint: null}));
      return;
    }
    if (key === "energy") {
      if (!S.energy || S.energy.length < 2) return;
      const [kin, pot] = S.energy;
      const total = kin.map((v, i) => (v === null || pot[i] === null ? null : v + pot[i]));
      if (compare) {
        lines.push({src: s, label: `${pre}total`, values: total, stroke: src.color, width: 2, joint: null});
      } else {
        lines.push({src: s, label: "kinetic", values: kin, stroke: PALETTE[0], width: 1.5, joint: null},
          {src: s, label: "potential", values: pot, stroke: PALETTE[1], width: 1.5, joint: null},
          {src: s, label: "total", values: total, stroke: PALETTE[6], width: 2.5, joint: null});
      }
      return;
    }
    const rows = S[key];
    if (!rows) return;
    rows.forEach((values, r) => {
      const {j, label} = rowOf(key, src, rows, r);
      const stroke = compare ? src.color : PALETTE[j % PALETTE.length];
      const dash = compare ? DASHES[j % DASHES.length] : (j >= PALETTE.length ? [14, 3] : []);
      lines.push({src: s, label: `${pre}${label}`, values, stroke, dash, width: 2, joint: j});
      const des = key === "q" ? desiredOf(src, r, j) : null;
      if (des) {
        lines.push({src: s, label: `${pre}q_d[${j}]`, values: des, stroke,
          dash: compare ? [2, 3] : [7, 5], width: compare ? 1 : 1.5, joint: j, desired: true});
      }
    });
  });
  return lines;
}

/* [t, line values...], the sources' times merged when there are several. */
function alignedData(lines, sources) {
  if (sources.length === 1) return [sources[0].series.t, ...lines.map((l) => l.values)];
  const tables = sources.map((src, s) => [src.series.t, ...lines.filter((l) => l.src === s).map((l) => l.values)]);
  const joined = uPlot.join(tables.filter((t) => t.length > 1));
  return joined;
}

/* Draws the plots into host. sources as in linesFor; returns {count, setJoint(j, show),
 * resetZoom(), zoomIn(), destroy()}. */
export function createPlots(host, sources, timeline, {compare = false} = {}) {
  const plots = []; /* {u, lines, box} */
  let syncing = false;
  let scaling = false;

  function place(u, t) {
    const x = u.valToPos(t, "x");
    const inside = Number.isFinite(x) && x >= 0 && x <= u.bbox.width / devicePixelRatio;
    syncing = true;
    u.setCursor({left: inside ? x : -10, top: 8});
    syncing = false;
  }
  function onCursor(u) {
    if (syncing || u.cursor.left < 0 || u.cursor.idx == null) return;
    timeline.set(u.data[0][u.cursor.idx], u);
  }
  function setAll(min, max, except) {
    scaling = true;
    for (const {u} of plots) if (u !== except) u.setScale("x", {min, max});
    scaling = false;
    for (const {u} of plots) place(u, timeline.t);
  }
  function onScale(u, key) {
    if (key !== "x" || scaling || plots.length === 0) return;
    setAll(u.scales.x.min, u.scales.x.max, u);
  }

  for (const def of CHANNELS) {
    const lines = linesFor(def.key, sources, compare);
    if (!lines.length) continue;
    const data = alignedData(lines, sources);
    const box = el("div", {class: "plot", "data-channel": def.key, "data-points": data[0].length,
      "data-series": lines.length});
    const title = def.key === "q" && lines.some((l) => l.desired) ?
      `${def.title} (solid) and desired q_d (${compare ? "thin dotted" : "dashed"})` : def.title;
    host.append(el("figure", {class: "plot-fig"}, el("figcaption", {text: title}), box));
    const u = new uPlot({
      width: Math.max(280, box.clientWidth), height: HEIGHT,
      scales: {x: {time: false}},
      series: [{label: "t", value: (self, v) => (v == null ? "–" : `${v.toFixed(3)} s`)},
        ...lines.map((l) => ({label: l.label, stroke: l.stroke, width: l.width, dash: l.dash,
          spanGaps: true, points: {show: false}, value: (self, v) => fmtNum(v)}))],
      axes: [{...AXIS, label: "t [s]"}, {...AXIS, label: def.axis, size: 70}],
      cursor: {y: false, drag: {x: true, y: false}, points: {size: 7}},
      legend: {show: lines.length <= 24, live: true},
      hooks: {setCursor: [onCursor], setScale: [onScale]},
    }, data, box);
    u.over.addEventListener("mouseleave", () => requestAnimationFrame(() => place(u, timeline.t)));
    plots.push({u, lines, box});
  }

  const unsubscribe = timeline.subscribe((t, from) => {
    for (const {u} of plots) if (u !== from) place(u, t);
  });
  /* follow the width of each plot's box (window resizes, layout changes) */
  const resizer = new ResizeObserver(() => {
    for (const {u, box} of plots) {
      const width = Math.max(280, box.clientWidth);
      if (Math.abs(width - u.width) > 1) u.setSize({width, height: HEIGHT});
    }
  });
  for (const {box} of plots) resizer.observe(box);
  for (const {u} of plots) place(u, timeline.t);

  const full = () => {
    const t = plots.length ? plots[0].u.data[0] : [0, 1];
    return [t[0], t[t.length - 1]];
  };
  return {
    count: plots.length,
    setJoint(j, show) {
      for (const {u, lines} of plots) {
        lines.forEach((l, i) => { if (l.joint === j) u.setSeries(i + 1, {show}); });
      }
    },
    resetZoom() { const [a, b] = full(); setAll(a, b, null); },
    zoomIn() {
      if (!plots.length) return;
      const {min, max} = plots[0].u.scales.x;
      const half = (max - min) / 4;
      const [a, b] = full();
      const c = Math.min(Math.max(timeline.t, a + half), b - half);
      setAll(c - half, c + half, null);
    },
    destroy() {
      unsubscribe();
      resizer.disconnect();
      for (const {u} of plots) u.destroy();
    },
  };
}

/* The per-coordinate toggles (button.joint-toggle[data-joint], aria-pressed) for a plot set;
 * colorOf(j) gives a swatch colour (null: none), labelOf(j) the button's text. */
export function jointToggles(plotSet, coords, colorOf, labelOf = (j) => `joint ${j}`) {
  const bar = el("div", {class: "joint-toggles", role: "group", "aria-label": "coordinates shown"});
  for (const j of coords) {
    const color = colorOf(j);
    const b = el("button", {type: "button", class: "joint-toggle", "data-joint": j,
      "aria-pressed": "true", title: `show or hide coordinate ${j} in every plot`},
    color ? el("span", {class: "swatch", style: `background:${color}`}) : null, labelOf(j));
    b.addEventListener("click", () => {
      const show = b.getAttribute("aria-pressed") !== "true";
      b.setAttribute("aria-pressed", String(show));
      plotSet.setJoint(j, show);
    });
    bar.append(b);
  }
  return bar;
}

/* "Zoom in" (half the span, around the time cursor) and "Reset zoom", for the keyboard. */
export function zoomButtons(plotSet) {
  const zoomIn = el("button", {type: "button", text: "Zoom in", title: "halve the time span around the cursor"});
  const reset = el("button", {type: "button", text: "Reset zoom"});
  zoomIn.addEventListener("click", () => plotSet.zoomIn());
  reset.addEventListener("click", () => plotSet.resetZoom());
  return el("div", {class: "zoom"}, zoomIn, reset);
}

/* every= for the series request: about two samples per pixel of plot width. */
export function decimation(samples, widthPx) {
  return Math.max(1, Math.ceil(samples / (2 * Math.max(200, widthPx))));
}
