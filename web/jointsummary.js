/*
 * jointsummary.js - the per-coordinate metrics of a job as a table, worst first, instead of one
 * line per value: the TOP rows with the largest RMS tracking error (for a CTC run max |e| is
 * the initial error, the same for every controller, so RMS and final error say more), and a
 * button that opens the whole table in a box of bounded height that scrolls, built only when
 * asked (a 4096-link chain's table is 4096 rows).
 *
 * Columns: the coordinate (its label from series.js controlledCoordinates), RMS e, final e,
 * max |e|, actuator peak |τ| and RMS τ, and the fraction of samples at the torque limit when the
 * job has limits. Values are the job's metrics arrays (metrics.e_rms, ...), one per controlled
 * coordinate; e in rad or m, τ in N m or N.
 *
 * Test hooks: table#joint-summary (the top rows, tr[data-coord="i"], i the column of the
 * controller's channels), button#joint-summary-all (aria-expanded), and once opened
 * div#joint-summary-all-box (scrolls) holding table#joint-summary-full with every row.
 */
import {el, fmtNum} from "./dom.js";

export const TOP = 10;

/* The rows, worst first: [{i, label, rms, final, max, peak, tauRms, sat}]. */
export function summaryRows(m, coords) {
  const n = Array.isArray(m.e_rms) ? m.e_rms.length : Array.isArray(m.tau_peak) ? m.tau_peak.length : 0;
  const at = (a, i) => (Array.isArray(a) ? a[i] : null);
  const rows = Array.from({length: n}, (_, i) => ({
    i, label: coords && coords[i] ? coords[i].label : `joint ${i}`,
    rms: at(m.e_rms, i), final: at(m.e_final, i), max: at(m.e_max, i),
    peak: at(m.tau_peak, i), tauRms: at(m.tau_rms, i), sat: at(m.sat_fraction, i),
  }));
  const key = (r) => (r.rms === null || r.rms === undefined ? -Infinity : Math.abs(r.rms));
  return rows.sort((a, b) => key(b) - key(a) || a.i - b.i);
}

function table(id, rows, sat, caption, onPick) {
  const head = ["coordinate", "RMS e", "final e", "max |e|", "peak |τ|", "RMS τ"];
  if (sat) head.push("at limit");
  const body = rows.map((r) => {
    const name = onPick ? el("button", {type: "button", class: "link plot-joint", "data-coord": r.i,
      title: `plot ${r.label}`, text: r.label}) : r.label;
    if (onPick) name.addEventListener("click", () => onPick(r.i));
    const cells = [r.rms, r.final, r.max, r.peak, r.tauRms];
    if (sat) cells.push(r.sat);
    return el("tr", {"data-coord": r.i}, el("th", {scope: "row"}, name),
      ...cells.map((v) => el("td", {class: "num", text: fmtNum(v)})));
  });
  return el("table", {id, class: "summary"}, el("caption", {class: "visually-hidden", text: caption}),
    el("thead", {}, el("tr", {}, ...head.map((h) => el("th", {scope: "col", text: h})))),
    el("tbody", {}, ...body));
}

/* The summary of metrics m (coords: controlledCoordinates) as a section, or null when the job
 * has no per-coordinate metrics. onPick(i), when given, plots coordinate column i. */
export function jointSummary(m, coords, onPick = null) {
  const rows = summaryRows(m || {}, coords);
  if (!rows.length) return null;
  const sat = Array.isArray(m.sat_fraction);
  const top = rows.slice(0, TOP);
  const box = el("section", {class: "panel joint-summary", "aria-labelledby": "joint-summary-title"},
    el("h2", {id: "joint-summary-title",
      text: rows.length > TOP ? `Worst ${TOP} of ${rows.length} coordinates` : "Per coordinate"}),
    el("p", {class: "muted small", text: "Sorted by RMS tracking error, largest first (e in rad or m, τ in N m or N)."}),
    el("div", {class: "table-wrap"}, table("joint-summary", top, sat, "coordinates with the largest RMS error", onPick)));
  if (rows.length > TOP) {
    const all = el("div", {id: "joint-summary-all-box", class: "summary-all", tabindex: "0",
      role: "region", "aria-label": `all ${rows.length} coordinates`});
    all.hidden = true;
    const button = el("button", {type: "button", id: "joint-summary-all", "aria-expanded": "false",
      "aria-controls": "joint-summary-all-box", text: `Show all ${rows.length}`});
    button.addEventListener("click", () => {
      const open = button.getAttribute("aria-expanded") !== "true";
      if (open && !all.firstChild) all.append(table("joint-summary-full", rows, sat, "every coordinate", onPick));
      all.hidden = !open;
      button.setAttribute("aria-expanded", String(open));
      button.textContent = open ? "Show the worst only" : `Show all ${rows.length}`;
    });
    box.append(button, all);
  }
  return box;
}
