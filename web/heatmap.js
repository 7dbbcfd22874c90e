/*
 * heatmap.js - the tracking error of every controlled coordinate against time, as one picture:
 * a canvas (canvas#heatmap) whose rows are the coordinates (coordinate 0 at the top) and whose
 * columns are the buckets of time that the series endpoint's min/max reduction gives
 * (series.js loadHeatSeries), each cell coloured by the largest |e| in it, max(|min|, |max|).
 *
 * Colour is log10 |e| over four decades below the largest value (smaller errors share the
 * lightest colour), on a light-to-dark sequential scale (cividis-like, readable with the
 * common colour vision deficiencies), with its key beside the canvas. When there are more
 * coordinates than pixel rows, a pixel row shows the largest |e| of the coordinates it covers,
 * so a bad joint is never averaged away. Pointing at a cell names its coordinate, time and
 * value in output#heatmap-value; a click (or Enter on the focused canvas, for the coordinate
 * under the keyboard cursor moved by the arrow keys) calls onPick(coordinate index).
 *
 * Test hooks: canvas#heatmap carries data-rows (coordinates), data-cols (time buckets) and
 * data-max (the largest |e|, rad or m).
 */
import {el, fmtNum} from "./dom.js";

const DECADES = 4;
/* a sequential scale from light yellow to dark blue (sRGB stops, interpolated linearly) */
const STOPS = [[253, 231, 145], [190, 188, 116], [124, 123, 120], [72, 88, 140], [0, 34, 78]];

function colour(f) {
  const x = Math.min(1, Math.max(0, f)) * (STOPS.length - 1);
  const k = Math.min(STOPS.length - 2, Math.floor(x));
  const a = STOPS[k], b = STOPS[k + 1], u = x - k;
  return [0, 1, 2].map((i) => Math.round(a[i] + (b[i] - a[i]) * u));
}

/* The largest |e| per cell: {cells (Float64Array rows x cols, row-major; NaN = no number),
 * rows, cols, t0 (bucket start times), t1 (bucket end times), max}. series: {t, e} from
 * loadHeatSeries (two rows per bucket). */
export function heatCells(series) {
  const rows = series.e.length, cols = Math.floor(series.t.length / 2);
  const cells = new Float64Array(rows * cols).fill(NaN);
  let max = 0;
  for (let r = 0; r < rows; r++) {
    const col = series.e[r];
    for (let b = 0; b < cols; b++) {
      const lo = col[2 * b], hi = col[2 * b + 1];
      let v = NaN;
      if (lo !== null) v = Math.abs(lo);
      if (hi !== null) v = Number.isNaN(v) ? Math.abs(hi) : Math.max(v, Math.abs(hi));
      cells[r * cols + b] = v;
      if (v > max) max = v;
    }
  }
  const t0 = [], t1 = [];
  for (let b = 0; b < cols; b++) { t0.push(series.t[2 * b]); t1.push(series.t[2 * b + 1]); }
  return {cells, rows, cols, t0, t1, max};
}

/* Draws the heat-map of series (loadHeatSeries) into host; labelOf(i) names coordinate i.
 * Returns {destroy()}. */
export function createHeatmap(host, series, {labelOf = (i) => `joint ${i}`, onPick = null} = {}) {
  const h = heatCells(series);
  const height = Math.min(360, Math.max(120, h.rows * 4));
  const canvas = el("canvas", {id: "heatmap", tabindex: "0", role: "img",
    "data-rows": h.rows, "data-cols": h.cols, "data-max": h.max,
    "aria-label": `tracking error |e| of ${h.rows} coordinates over time; largest ${fmtNum(h.max)}`});
  const readout = el("output", {id: "heatmap-value", class: "muted small", "aria-live": "polite"});
  const lo = h.max > 0 ? h.max / 10 ** DECADES : 0;
  const key = el("div", {class: "heat-key"},
    el("span", {text: lo > 0 ? `≤ ${fmtNum(lo)}` : "0"}),
    el("span", {class: "heat-ramp", "aria-hidden": "true",
      style: `background: linear-gradient(to right, ${STOPS.map((s) => `rgb(${s.join(",")})`).join(", ")})`}),
    el("span", {text: `${fmtNum(h.max)} (log scale)`}));
  host.append(canvas, key, readout);

  const shade = (v) => {
    if (Number.isNaN(v)) return [255, 255, 255];
    if (!(h.max > 0) || v <= lo) return colour(0);
    return colour(Math.log10(v / lo) / DECADES);
  };
  function draw() {
    const w = Math.max(100, Math.round(canvas.clientWidth || 300));
    canvas.width = w;
    canvas.height = height;
    const ctx = canvas.getContext("2d");
    const img = ctx.createImageData(w, height);
    for (let y = 0; y < height; y++) {
      const r0 = Math.floor((y * h.rows) / height);
      const r1 = Math.max(r0 + 1, Math.floor(((y + 1) * h.rows) / height));
      for (let x = 0; x < w; x++) {
        const b = Math.min(h.cols - 1, Math.floor((x * h.cols) / w));
        let v = NaN;
        for (let r = r0; r < r1; r++) {
          const c = h.cells[r * h.cols + b];
          if (!Number.isNaN(c) && !(c <= v)) v = c;
        }
        const [R, G, B] = shade(v);
        const k = 4 * (y * w + x);
        img.data[k] = R; img.data[k + 1] = G; img.data[k + 2] = B; img.data[k + 3] = 255;
      }
    }
    ctx.putImageData(img, 0, 0);
  }

  let at = {row: 0, col: 0};
  function show({row, col}) {
    at = {row, col};
    const v = h.cells[row * h.cols + col];
    readout.textContent = `${labelOf(row)}, t ${fmtNum(h.t0[col])}–${fmtNum(h.t1[col])} s: ` +
      `|e| ≤ ${Number.isNaN(v) ? "–" : fmtNum(v)}`;
  }
  function cellAt(ev) {
    const box = canvas.getBoundingClientRect();
    const row = Math.min(h.rows - 1, Math.max(0, Math.floor(((ev.clientY - box.top) / box.height) * h.rows)));
    const col = Math.min(h.cols - 1, Math.max(0, Math.floor(((ev.clientX - box.left) / box.width) * h.cols)));
    return {row, col};
  }
  canvas.addEventListener("mousemove", (ev) => show(cellAt(ev)));
  canvas.addEventListener("click", (ev) => { const c = cellAt(ev); show(c); if (onPick) onPick(c.row); });
  canvas.addEventListener("keydown", (ev) => {
    const moves = {ArrowUp: [-1, 0], ArrowDown: [1, 0], ArrowLeft: [0, -1], ArrowRight: [0, 1]};
    if (moves[ev.key]) {
      ev.preventDefault();
      const [dr, dc] = moves[ev.key];
      show({row: Math.min(h.rows - 1, Math.max(0, at.row + dr)), col: Math.min(h.cols - 1, Math.max(0, at.col + dc))});
    } else if (ev.key === "Enter" && onPick) {
      onPick(at.row);
    }
  });
  const resizer = new ResizeObserver(() => { if (Math.abs(canvas.width - canvas.clientWidth) > 1) draw(); });
  resizer.observe(canvas);
  if (h.rows && h.cols) draw();
  return {destroy() { resizer.disconnect(); }};
}
