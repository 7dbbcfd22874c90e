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
 * Units: each coordinate has its own, from its joint's type in the spec (a source's "spec"):
 * rad for a revolute joint's angle, m for a prismatic joint's displacement (cylindrical: both),
 * none for a spherical joint's quaternion; tau is then N m or N, w rad/s² or m/s². A channel
 * whose lines share one unit says it on its axis ("q [rad]"); a mixed one lists the units on the
 * axis and puts each line's in its label ("q[3] (m)"). Without a spec the axis says "rad | m".
 *
 * Colours: the Okabe-Ito palette (safe for the common colour vision deficiencies, dark enough on
 * white) for the first seven, then hues a golden angle apart at a lightness that keeps the
 * contrast, so colours do not repeat within PALETTE's length (256). In a job's plots each
 * coordinate has its colour and q_d is dashed; when comparing, each job has its colour and
 * coordinates differ by dash pattern. Ticks: a large or tiny range (a loop's residuals at 1e-12)
 * is labelled in exponent form with the digits that tell ticks apart, and the value axis is as
 * wide as its longest label, so labels are never clipped. A run of one sample is drawn as a
 * point on a short axis around its time, not on uPlot's default 0-100.
 *
 * The plots of a set share the view's timeline: hovering a plot moves the time cursor, and
 * moving the time (slider, animation) puts every plot's cursor there, legends showing the
 * values at that time. Dragging across a plot zooms the time axis of every plot; dragging up or
 * down zooms that plot's value axis (a diagonal drag both); double-click, or "Reset zoom",
 * restores them. Options: logE draws |e| on a log axis (zeros left out); layout "paper" draws
 * q, e and tau as one panel per coordinate with every source overlaid (the paper's figures,
 * Kingsley et al. 2017 figs. 5-8), each panel div.plot[data-channel][data-joint]. Under each
 * plot's caption are its PNG and SVG export buttons (export.js). Sources of different sampling are aligned
 * with uPlot.join (gaps spanned).
 */
import uPlot from "./vendor/uPlot.esm.js";
import {el, fmtNum} from "./dom.js";
import {exportButtons} from "./export.js";
import {JOINT_NQ as NQ} from "./joints.js";

const OKABE_ITO = ["#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#000000"];
/* 256 colours: Okabe-Ito, then golden-angle hues at lightness 30-40 % (contrast >= 4.5 on white) */
export const PALETTE = Object.freeze([...OKABE_ITO, ...Array.from({length: 249}, (_, i) =>
  `hsl(${Math.round((i * 137.508 + 20) % 360)}, ${i % 2 ? 85 : 65}%, ${i % 3 === 0 ? 30 : 36}%)`)]);
export const jointColor = (j) => PALETTE[j % PALETTE.length];
const DASHES = [[], [10, 4], [3, 3], [12, 4, 3, 4]];
const HEIGHT = 230;
const AXIS = {stroke: "#1f2328", font: "13px system-ui, sans-serif",
  labelFont: "bold 13px system-ui, sans-serif", grid: {stroke: "#dde1e6", width: 1},
  ticks: {stroke: "#b8bec6", width: 1}};

export const CHANNELS = [
  {key: "q", title: "Joint coordinates q", axis: "q"},
  {key: "e", title: "Tracking error e = q_d − q", axis: "e"},
  {key: "tau", title: "Driving torques tau", axis: "tau"},
  {key: "w", title: "Controller output w (commanded acceleration)", axis: "w"},
  {key: "energy", title: "Energy", axis: "energy [J]"},
  {key: "loop", title: "Loop closure residuals (max-norms)", axis: "residual [m | rad, /s]"},
];
const PAPER = new Set(["q", "e", "tau"]); /* one panel per coordinate in the paper's layout */
const LOOP_PARTS = ["position residual", "velocity residual"];
/* a coordinate's unit by kind, per channel */
const UNIT = {
  rad: {q: "rad", e: "rad", tau: "N m", w: "rad/s²"},
  m: {q: "m", e: "m", tau: "N", w: "m/s²"},
  quat: {q: "1", e: "rad", tau: "N m", w: "rad/s²"},
};

/* The kind of each row of q ("rad", "m" or "quat"), the closing joint's after the bodies', from
 * the spec's joints; null without a spec. */
export function coordinateKinds(spec) {
  const scene = spec && spec.scene;
  if (!scene || !Array.isArray(scene.bodies)) return null;
  const joints = scene.bodies.map((b) => (b && b.joint) || {});
  if (scene.loop) joints.push(scene.loop.joint || {});
  const kinds = [];
  for (const j of joints) {
    if (j.type === "prismatic") kinds.push("m");
    else if (j.type === "cylindrical") kinds.push("rad", "m");
    else if (j.type === "spherical") kinds.push("quat", "quat", "quat", "quat");
    else for (let i = 0; i < (NQ[j.type] ?? 1); i++) kinds.push("rad");
  }
  return kinds;
}

/* The unit of channel key's line on row j of q in src, or null when unknown. */
function unitOf(key, src, j) {
  if (!src.kinds || j === null || j === undefined) return null;
  const k = src.kinds[j];
  return k ? UNIT[k][key] : null;
}

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

/* The lines of one channel: [{src, label, values, stroke, dash, width, joint, desired, unit}]
 * (joint: the row of q the line belongs to, null for energy and the loop). Each source is
 * {label, color, series, joints (coordinate index of each row, or null), coords (series.js
 * controlledCoordinates), loop (a closed chain), spec (optional: units)}. only: keep the lines
 * of that row of q alone (the paper's layout). */
function linesFor(key, sources, compare, only = null) {
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
      if (only !== null && j !== only) return;
      const unit = unitOf(key, src, j);
      const stroke = compare ? src.color : jointColor(j);
      const dash = compare ? (only !== null ? [] : DASHES[j % DASHES.length]) : [];
      lines.push({src: s, label: `${pre}${label}`, values, stroke, dash, width: 2, joint: j, unit});
      const des = key === "q" ? desiredOf(src, r, j) : null;
      if (des) {
        lines.push({src: s, label: `${pre}q_d[${j}]`, values: des, stroke,
          dash: compare ? [2, 3] : [7, 5], width: compare ? 1 : 1.5, joint: j, desired: true, unit});
      }
    });
  });
  return lines;
}

/* [t, line values...], the sources' times merged when there are several. */
function alignedData(lines, sources) {
  if (sources.length === 1) return [sources[0].series.t, ...lines.map((l) => l.values)];
  const used = sources.map((src, s) => s).filter((s) => lines.some((l) => l.src === s));
  if (used.length === 1) {
    const s = used[0];
    return [sources[s].series.t, ...lines.map((l) => l.values)];
  }
  const tables = used.map((s) => [sources[s].series.t, ...lines.filter((l) => l.src === s).map((l) => l.values)]);
  return uPlot.join(tables);
}

/* Tick labels that tell ticks apart at any magnitude: exponent form below 1e-3 or from 1e5 on
 * (with as many digits as the step needs), else as few decimals as the step needs. */
export function tickLabels(splits, log = false) {
  const finite = splits.filter((v) => Number.isFinite(v));
  if (!finite.length) return splits.map(() => "");
  const big = Math.max(...finite.map(Math.abs));
  if (log) return splits.map((v) => (Math.abs(Math.log10(v) % 1) < 1e-9 ? v.toExponential(0) : ""));
  const steps = finite.slice(1).map((v, i) => Math.abs(v - finite[i])).filter((d) => d > 0);
  const step = steps.length ? Math.min(...steps) : big || 1;
  if (big !== 0 && (big < 1e-3 || big >= 1e5)) {
    const digits = Math.min(6, Math.max(0, Math.ceil(Math.log10(big / step) - 1e-9)));
    return splits.map((v) => (v === 0 ? "0" : v.toExponential(digits)));
  }
  const decimals = Math.min(10, Math.max(0, -Math.floor(Math.log10(step) + 1e-9)));
  return splits.map((v) => v.toFixed(decimals));
}

/* an axis size that fits its longest tick label (uPlot calls it with the labels it drew) */
function axisSize(self, values, axisIdx, cycleNum) {
  const axis = self.axes[axisIdx];
  if (cycleNum > 1) return axis._size;
  let size = (axis.ticks.size ?? 10) + (axis.gap ?? 5) + 26; /* ticks, gap, the rotated label */
  const longest = (values || []).reduce((a, v) => (v != null && String(v).length > a.length ? String(v) : a), "");
  if (longest) {
    self.ctx.font = axis.font[0];
    size += self.ctx.measureText(longest).width / (window.devicePixelRatio || 1);
  }
  if (self._box) self._box.dataset.axisWidth = String(Math.ceil(size));
  return Math.ceil(size);
}

/* the value-axis label of a channel: its units, and whether lines must carry their own */
function axisLabel(def, lines, logE) {
  if (def.key === "energy" || def.key === "loop") return {text: def.axis, mixed: false};
  const units = [...new Set(lines.map((l) => l.unit ?? null))];
  const name = def.key === "e" && logE ? "|e|" : def.axis;
  const known = units.filter((u) => u !== null);
  if (!known.length || known.length !== units.length) {
    const generic = {q: "rad | m", e: "rad | m", tau: "N m | N", w: "rad/s² | m/s²"}[def.key];
    return {text: `${name} [${generic}]${def.key === "e" && logE ? " (log)" : ""}`, mixed: false};
  }
  return {text: `${name} [${known.join(" | ")}]${def.key === "e" && logE ? " (log)" : ""}`, mixed: known.length > 1};
}

/* Draws the plots into host. sources as in linesFor; opts: compare (several jobs), logE,
 * layout ("channels" | "paper"), yZoom ({plot id: [min, max]}, kept as the user zooms; a plot's
 * id is its channel, or "e.2" for a panel of the paper's layout), onZoom(state) called after
 * any zoom. Returns {count, setJoint(j, show), resetZoom(), zoomIn(), zoomInY(), xRange(),
 * setX(min, max), plots (the uPlots with their ids), destroy()}. */
export function createPlots(host, sources, timeline, {compare = false, logE = false, layout = "channels",
  yZoom = {}, onZoom = null} = {}) {
  const plots = []; /* {u, lines, box, id} */
  let syncing = false;
  let scaling = false;
  for (const src of sources) if (src.kinds === undefined) src.kinds = coordinateKinds(src.spec);

  function place(u, t) {
    const x = u.valToPos(t, "x");
    const inside = Number.isFinite(x) && x >= 0 && x <= u.bbox.width / devicePixelRatio;
    syncing = true;
    u.setCursor({left: inside ? x : -10, top: 8});
    syncing = false;
  }
  function onCursor(u) {
    /* only a pointer over the plot moves the time (uPlot also moves its cursor on resizes) */
    if (syncing || !u._hover || u.cursor.left < 0 || u.cursor.idx == null) return;
    timeline.set(u.data[0][u.cursor.idx], u);
  }
  function setAll(min, max, except) {
    scaling = true;
    for (const {u} of plots) if (u !== except) u.setScale("x", {min, max});
    scaling = false;
    for (const {u} of plots) place(u, timeline.t);
  }
  /* the range shown, for tests and links: data-xmin/xmax, data-ymin/ymax */
  function markRange(u, key) {
    const sc = u.scales[key];
    if (u._box && sc && Number.isFinite(sc.min) && Number.isFinite(sc.max)) {
      u._box.dataset[`${key}min`] = String(sc.min);
      u._box.dataset[`${key}max`] = String(sc.max);
    }
  }
  function onScale(u, key) {
    if (key === "x" || key === "y") markRange(u, key);
    if (scaling || plots.length === 0) return;
    if (key === "x") {
      setAll(u.scales.x.min, u.scales.x.max, u);
      if (onZoom) onZoom();
      return;
    }
    if (key === "y" && u._dragging) {
      const p = plots.find((x) => x.u === u);
      if (p) yZoom[p.id] = [u.scales.y.min, u.scales.y.max];
      if (onZoom) onZoom();
    }
  }

  /* the panels: [{def, id, only (a row of q, or null), title}] */
  const panels = [];
  for (const def of CHANNELS) {
    if (layout === "paper" && PAPER.has(def.key)) {
      const rows = [...new Set(linesFor(def.key, sources, compare).map((l) => l.joint))];
      for (const j of rows) panels.push({def, id: `${def.key}.${j}`, only: j});
    } else {
      panels.push({def, id: def.key, only: null});
    }
  }

  for (const {def, id, only} of panels) {
    let lines = linesFor(def.key, sources, compare, only);
    if (!lines.length) continue;
    const log = logE && def.key === "e";
    if (log) lines = lines.map((l) => ({...l, values: l.values.map((v) => (v === null || v === 0 ? null : Math.abs(v)))}));
    const label = axisLabel(def, lines, logE);
    if (label.mixed) for (const l of lines) l.label += ` (${l.unit})`;
    const data = alignedData(lines, sources);
    const one = data[0].length === 1;
    const box = el("div", {class: "plot", "data-channel": def.key, "data-points": data[0].length,
      "data-series": lines.length, "data-unit": label.text, "data-log": log ? "1" : null,
      "data-joint": only ?? null});
    const title = (only !== null ? `${def.title}: coordinate ${only}` : def.title) +
      (def.key === "q" && lines.some((l) => l.desired) ?
        ` (solid) and desired q_d (${compare ? "thin dotted" : "dashed"})` : "") + (log ? ", |e| on a log scale" : "");
    const tools = el("div", {class: "plot-tools"});
    host.append(el("figure", {class: "plot-fig"}, el("figcaption", {text: title}), tools, box));
    const yRange = (u, dmin, dmax) => {
      if (yZoom[id]) return yZoom[id].slice();
      if (dmin === null || dmax === null) return log ? [1e-6, 1] : [-1, 1];
      if (log) return uPlot.rangeLog(dmin, dmax, 10, true);
      return uPlot.rangeNum(dmin, dmax, 0.1, true);
    };
    const u = new uPlot({
      width: Math.max(280, box.clientWidth), height: HEIGHT,
      scales: {
        x: {time: false, range: (u0, min, max) => {
          if (min === null || max === null) return [0, 1];
          if (min !== max) return [min, max];
          const half = Math.max(Math.abs(min) * 0.05, 0.01);
          return [min - half, max + half];
        }},
        y: {distr: log ? 3 : 1, log: 10, range: yRange},
      },
      series: [{label: "t", value: (self, v) => (v == null ? "–" : `${v.toFixed(3)} s`)},
        ...lines.map((l) => ({label: l.label, stroke: l.stroke, width: l.width, dash: l.dash,
          spanGaps: true, points: {show: one, size: 8, fill: l.stroke}, value: (self, v) => fmtNum(v)}))],
      axes: [{...AXIS, label: "t [s]", values: (self, splits) => tickLabels(splits)},
        {...AXIS, label: label.text, size: axisSize, values: (self, splits) => {
          const labels = tickLabels(splits, log);
          box.dataset.yTicks = labels.join("|"); /* the labels drawn, for tests */
          return labels;
        }}],
      cursor: {y: false, drag: {x: true, y: true, uni: 30}, points: {size: 7}},
      legend: {show: lines.length <= 24, live: true},
      hooks: {setCursor: [onCursor], setScale: [onScale]},
    }, data, (self, init) => { self._box = box; box.append(self.root); init(); });
    /* a y zoom is a drag's: mark drags so that the setScale hook can tell them from auto-ranging */
    u.over.addEventListener("mousedown", () => { u._dragging = true; });
    u.over.addEventListener("dblclick", () => { delete yZoom[id]; autoY(u); if (onZoom) onZoom(); });
    u.over.addEventListener("mouseenter", () => { u._hover = true; });
    u.over.addEventListener("mouseleave", () => { u._hover = false; requestAnimationFrame(() => place(u, timeline.t)); });
    markRange(u, "x");
    markRange(u, "y");
    tools.append(exportButtons(u, {channel: def.key, joint: only, title, yLabel: label.text, lines, log}));
    plots.push({u, lines, box, id});
  }

  /* the y range of the data in view, as uPlot's auto-ranging would give */
  function autoY(u) {
    const [a, b] = [u.scales.x.min, u.scales.x.max];
    let lo = Infinity, hi = -Infinity;
    u.data.slice(1).forEach((vals, i) => {
      if (u.series[i + 1].show === false) return;
      for (let k = 0; k < vals.length; k++) {
        const t = u.data[0][k];
        if (t < a || t > b || vals[k] === null || vals[k] === undefined) continue;
        if (vals[k] < lo) lo = vals[k];
        if (vals[k] > hi) hi = vals[k];
      }
    });
    if (!Number.isFinite(lo)) return;
    const log = u.scales.y.distr === 3;
    const [min, max] = log ? uPlot.rangeLog(lo, hi, 10, true) : uPlot.rangeNum(lo, hi, 0.1, true);
    u.setScale("y", {min, max});
  }

  /* after uPlot's own mouseup handler (which sets the scales) */
  const endDrag = () => setTimeout(() => { for (const {u} of plots) u._dragging = false; }, 0);
  window.addEventListener("mouseup", endDrag);
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
  for (const {u, id} of plots) if (yZoom[id]) u.setScale("y", {min: yZoom[id][0], max: yZoom[id][1]});

  const full = () => {
    const t = plots.length ? plots[0].u.data[0] : [0, 1];
    return [t[0], t[t.length - 1]];
  };
  return {
    count: plots.length,
    plots,
    setJoint(j, show) {
      for (const {u, lines} of plots) {
        lines.forEach((l, i) => { if (l.joint === j) u.setSeries(i + 1, {show}); });
      }
    },
    resetZoom() {
      for (const k of Object.keys(yZoom)) delete yZoom[k];
      const [a, b] = full();
      if (a === b) return;
      setAll(a, b, null);
      for (const {u} of plots) autoY(u);
      if (onZoom) onZoom();
    },
    zoomIn() {
      if (!plots.length) return;
      const {min, max} = plots[0].u.scales.x;
      const half = (max - min) / 4;
      const [a, b] = full();
      const c = Math.min(Math.max(timeline.t, a + half), b - half);
      setAll(c - half, c + half, null);
      if (onZoom) onZoom();
    },
    /* halves every plot's value span around its middle (a factor 10 each way on a log axis) */
    zoomInY() {
      for (const {u, id} of plots) {
        const {min, max} = u.scales.y;
        let r;
        const f = Math.pow(max / min, 0.25);
        r = u.scales.y.distr === 3 ? [min * f, max / f] : [min + (max - min) / 4, max - (max - min) / 4];
        yZoom[id] = r;
        u.setScale("y", {min: r[0], max: r[1]});
      }
      if (onZoom) onZoom();
    },
    xRange() {
      if (!plots.length) return null;
      const {min, max} = plots[0].u.scales.x;
      const [a, b] = full();
      return Math.abs(min - a) < 1e-12 && Math.abs(max - b) < 1e-12 ? null : [min, max];
    },
    setX(min, max) { if (plots.length && max > min) setAll(min, max, null); },
    destroy() {
      unsubscribe();
      window.removeEventListener("mouseup", endDrag);
      resizer.disconnect();
      for (const {u} of plots) u.destroy();
    },
  };
}

/* The per-coordinate toggles (button.joint-toggle[data-joint], aria-pressed) for a plot set;
 * colorOf(j) gives a swatch colour (null: none), labelOf(j) the button's text; hidden: rows to
 * start hidden; onChange(hidden rows) after each toggle. */
export function jointToggles(plotSet, coords, colorOf, labelOf = (j) => `joint ${j}`,
  {hidden = [], onChange = null} = {}) {
  const off = new Set(hidden.filter((j) => coords.includes(j)));
  const bar = el("div", {class: "joint-toggles", role: "group", "aria-label": "coordinates shown"});
  for (const j of coords) {
    const color = colorOf(j);
    const b = el("button", {type: "button", class: "joint-toggle", "data-joint": j,
      "aria-pressed": String(!off.has(j)), title: `show or hide coordinate ${j} in every plot`},
    color ? el("span", {class: "swatch", style: `background:${color}`}) : null, labelOf(j));
    b.addEventListener("click", () => {
      const show = b.getAttribute("aria-pressed") !== "true";
      b.setAttribute("aria-pressed", String(show));
      plotSet.setJoint(j, show);
      if (show) off.delete(j); else off.add(j);
      if (onChange) onChange([...off].sort((x, y) => x - y));
    });
    bar.append(b);
  }
  for (const j of off) plotSet.setJoint(j, false);
  return bar;
}

/* "Zoom in" (half the time span, around the time cursor), "Zoom y in" (half each value span)
 * and "Reset zoom", for the keyboard. */
export function zoomButtons(plotSet) {
  const zoomIn = el("button", {type: "button", text: "Zoom in", title: "halve the time span around the cursor"});
  const zoomY = el("button", {type: "button", class: "zoom-y", text: "Zoom y in", title: "halve each plot's value span"});
  const reset = el("button", {type: "button", text: "Reset zoom"});
  zoomIn.addEventListener("click", () => plotSet.zoomIn());
  zoomY.addEventListener("click", () => plotSet.zoomInY());
  reset.addEventListener("click", () => plotSet.resetZoom());
  return el("div", {class: "zoom"}, zoomIn, zoomY, reset);
}

/* every= for the series request: about two samples per pixel of plot width. */
export function decimation(samples, widthPx) {
  return Math.max(1, Math.ceil(samples / (2 * Math.max(200, widthPx))));
}
