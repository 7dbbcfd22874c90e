/*
 * families.js - studies: the families of jobs (#/families) and one family (#/families/{id}).
 *
 * A family (server/family.h, GET /api/families/{id}) is a base job swept along axes, each a JSON
 * path of the job with its values, and optionally repeated as seeded Monte-Carlo replicas. The
 * list shows each family's members, status counts and progress (finished / members). A
 * family's page shows the same counts, live while members run (polled every 2 s, table and
 * chart redrawn), its table - one row per member: member, replica, the axis values, status and
 * the metrics reduced over the controlled coordinates (largest |e_final|, e_rms, e_max,
 * |tau_peak|, energy drift, µs per evaluation, steps, wall time) - sortable by any column, each
 * row linking to its job, saved as the server's CSV; and a chart of a metric against an axis.
 *
 * The chart (uPlot) plots, for the axis chosen as x and the metric chosen as y, one line per
 * value of a second axis (when the family has two or more; the others are pooled), through the
 * mean of the members at each x; where there are several (replicas, or a pooled axis) each
 * member is also drawn as a point and the spread as mean ± one sample standard deviation
 * (dashed). This covers the studies of README's "Studies":
 * work-precision (e_rms or µs per evaluation against integrator.rtol, a line per method), cost
 * against n, error against gain, and Monte-Carlo spreads. An axis whose values are not numbers
 * (integrator.method) is drawn at 0, 1, 2, ... with its values as tick labels. Log x and log y
 * leave out values that are not positive. The chart is saved as PNG or SVG (export.js).
 *
 * Cancel and delete are separate, each confirmed (confirm.js): cancel asks every unfinished
 * member to stop (POST /api/jobs/{id}/cancel, which never deletes a member that finished
 * meanwhile); delete (only once every member has finished) is DELETE /api/families/{id}.
 * The address keeps the chart's axes, log toggles and the table's sort
 * (#/families/3?x=controller.kp&y=e_rms&by=controller.kv&logx=1&logy=1&sort=e_rms:asc).
 */
import uPlot from "./vendor/uPlot.esm.js";
import {cancelJob, request} from "./api.js";
import {el, errorBox, fmtNum, fmtTime, sleep} from "./dom.js";
import {PALETTE, tickLabels} from "./plots.js";
import {exportButtons} from "./export.js";
import {confirmDialog} from "./confirm.js";

const STATUSES = ["queued", "running", "done", "failed", "diverged", "cancelled"];
/* the metric columns of a family's table (server/family.h family_metric_names), with units */
export const METRICS = [
  ["e_final", "final |e|", "rad | m"], ["e_rms", "RMS e", "rad | m"], ["e_max", "max |e|", "rad | m"],
  ["tau_peak", "peak |τ|", "N m | N"], ["energy_drift", "energy drift", "1"],
  ["us_per_eval", "µs / eval", "µs"], ["steps", "steps", "1"], ["wall_s", "wall time", "s"],
];
const POLL_MS = 2000;
const CANCEL_AT_ONCE = 8; /* cancel requests in flight at once */

export const listFamilies = (signal) => request("/api/families?limit=200", {signal});
export const getFamily = (id, signal) => request(`/api/families/${id}`, {signal});
const deleteFamily = (id, signal) => request(`/api/families/${id}`, {method: "DELETE", signal});

/* {finished, members, unfinished} of a family row's counts */
export function familyProgress(f) {
  const c = f.counts || {};
  const unfinished = (c.queued || 0) + (c.running || 0);
  return {finished: f.members - unfinished, members: f.members, unfinished};
}

/* the counts as spans, span[data-status] with the number in data-count, in STATUSES order */
function countsNode(f, id) {
  const c = f.counts || {};
  return el("span", {class: "counts", id}, ...STATUSES.filter((s) => c[s]).map((s) =>
    el("span", {class: `status status-${s}`, "data-status": s, "data-count": c[s], text: `${c[s]} ${s}`})));
}

function progressNode(f, id) {
  const p = familyProgress(f);
  const bar = el("progress", {max: String(Math.max(1, p.members)), value: String(p.finished), id,
    "aria-label": `${p.finished} of ${p.members} members finished`});
  return el("span", {class: "family-progress"}, bar, el("span", {class: "muted", text: ` ${p.finished} / ${p.members}`}));
}

/* ---- the list ---- */

export async function familiesView(root, ctx) {
  document.title = "Studies - ctcsim";
  const body = el("tbody");
  const table = el("table", {id: "families-table"},
    el("caption", {class: "visually-hidden", text: "The families of jobs, newest first"}),
    el("thead", {}, el("tr", {}, ...["id", "name", "status", "progress", "members", "axes", "created"]
      .map((h) => el("th", {scope: "col", "data-col": h, text: h})))), body);
  const note = el("div", {role: "status"});
  root.append(el("h1", {text: "Studies"}),
    el("p", {class: "muted", text: "Families of jobs swept along axes (POST /api/families, README \"Studies\"). Open one for its table and chart."}),
    note, el("div", {class: "table-wrap"}, table));
  for (;;) {
    let list;
    try {
      list = (await listFamilies(ctx.signal)).families;
    } catch (e) {
      if (e.name === "AbortError") return;
      note.replaceChildren(errorBox("The families could not be loaded", e));
      ctx.ready();
      return;
    }
    body.replaceChildren(...list.map((f) => el("tr", {"data-family-id": f.id},
      el("td", {class: "num", "data-col": "id", text: f.id}),
      el("td", {"data-col": "family"}, el("a", {href: `#/families/${f.id}`, text: f.name || `family ${f.id}`})),
      el("td", {"data-col": "status"}, countsNode(f)),
      el("td", {"data-col": "progress"}, progressNode(f)),
      el("td", {class: "num", "data-col": "members", text: f.members}),
      el("td", {"data-col": "axes", text: (f.axes || []).join(" × ")}),
      el("td", {"data-col": "created", text: fmtTime(f.created)}))));
    note.replaceChildren(list.length ? "" : el("p", {class: "empty", text: "No families yet."}));
    ctx.ready();
    await sleep(list.some((f) => familyProgress(f).unfinished) ? POLL_MS : 3 * POLL_MS, ctx.signal);
  }
}

/* ---- one family ---- */

/* The chart's points from the table: rows (table rows), xi (the x axis's index), yKey (a metric),
 * gi (the grouping axis's index, or -1). Values of x that are not numbers become their index in
 * the order met (categories). Returns {xs (distinct x, ascending), cats (names or null), groups:
 * [{value, points: [[x, y]...], mean: [y per xs], sd: [y per xs]}]}. */
export function chartData(rows, xi, yKey, gi) {
  const raw = rows.map((r) => r.values[xi]);
  const numeric = raw.every((v) => typeof v === "number");
  const cats = numeric ? null : [...new Set(raw.map(String))];
  const xOf = (v) => (numeric ? v : cats.indexOf(String(v)));
  const xs = [...new Set(raw.map(xOf))].sort((a, b) => a - b);
  const byGroup = new Map();
  for (const r of rows) {
    const g = gi >= 0 ? r.values[gi] : null;
    const key = JSON.stringify(g);
    if (!byGroup.has(key)) byGroup.set(key, {value: g, points: []});
    const y = r[yKey];
    if (typeof y === "number" && Number.isFinite(y)) byGroup.get(key).points.push([xOf(r.values[xi]), y]);
  }
  const groups = [...byGroup.values()];
  groups.sort((a, b) => (typeof a.value === "number" && typeof b.value === "number" ? a.value - b.value :
    String(a.value).localeCompare(String(b.value))));
  for (const g of groups) {
    g.mean = xs.map(() => null);
    g.sd = xs.map(() => null);
    xs.forEach((x, k) => {
      const ys = g.points.filter((p) => p[0] === x).map((p) => p[1]);
      if (!ys.length) return;
      const mean = ys.reduce((s, v) => s + v, 0) / ys.length;
      g.mean[k] = mean;
      g.sd[k] = ys.length > 1 ? Math.sqrt(ys.reduce((s, v) => s + (v - mean) ** 2, 0) / (ys.length - 1)) : 0;
    });
  }
  return {xs, cats, groups};
}

/* the view's state from the address */
function readState(q, axes) {
  const [key, dir] = (q.get("sort") || "").split(":");
  const x = axes.indexOf(q.get("x"));
  const by = q.has("by") ? axes.indexOf(q.get("by")) : -2;
  return {
    x: x >= 0 ? x : 0,
    y: METRICS.some(([k]) => k === q.get("y")) ? q.get("y") : "e_rms",
    by, logx: q.get("logx") === "1", logy: q.get("logy") === "1",
    sort: key ? {key, dir: dir === "desc" ? "desc" : "asc"} : null,
  };
}

/* the table's columns: [{key, head, value(row) -> number | string | null, text}] */
function tableColumns(axes) {
  return [
    {key: "member", head: "member", value: (r) => r.member},
    {key: "replica", head: "replica", value: (r) => r.replica},
    ...axes.map((a, i) => ({key: `axis.${i}`, head: a, value: (r) => r.values[i] ?? null})),
    {key: "status", head: "status", value: (r) => r.status, text: true},
    ...METRICS.map(([key, head]) => ({key, head, value: (r) => r[key]})),
  ];
}

function compareValues(a, b) {
  if (a === null || a === undefined) return b === null || b === undefined ? 0 : 1;
  if (b === null || b === undefined) return -1;
  return typeof a === "number" && typeof b === "number" ? a - b : String(a).localeCompare(String(b));
}

export async function familyView(root, ctx) {
  const id = Number(ctx.params.familyId);
  document.title = `Study ${id} - ctcsim`;
  let fam;
  try {
    fam = await getFamily(id, ctx.signal);
  } catch (e) {
    if (e.name === "AbortError") return;
    root.append(el("h1", {text: `Study ${id}`}), errorBox(`Family ${id} could not be loaded`, e),
      el("p", {}, el("a", {href: "#/families", text: "Back to the studies"})));
    ctx.ready();
    return;
  }
  const axes = fam.axes || [];
  const state = readState(ctx.params.query, axes);
  if (state.by === -2 || state.by === state.x) state.by = axes.length > 1 ? (state.x === 0 ? 1 : 0) : -1;
  const picked = new Set();

  const counts = el("span", {id: "family-counts"});
  const progHost = el("span");
  const message = el("p", {class: "message", role: "status"});
  const cancel = el("button", {type: "button", id: "cancel-family", class: "danger", text: "Cancel unfinished members"});
  const remove = el("button", {type: "button", id: "delete-family", class: "danger", text: "Delete family"});
  const csv = el("a", {id: "family-csv", class: "button", href: `/api/families/${id}?format=csv`,
    download: `ctcsim-family-${id}.csv`, text: "Download CSV"});
  const compareBtn = el("button", {type: "button", id: "family-compare", disabled: true, text: "Compare selected"});
  const spec = fam.spec || {};
  root.append(el("section", {class: "job-head"},
    el("h1", {id: "family-name", text: fam.name || `Family ${id}`}),
    el("p", {class: "meta", text: `#${id} · ${fam.members} members · axes ${axes.join(" × ") || "none"}` +
      (spec.replicas > 1 ? ` · ${spec.replicas} replicas` : "") + ` · created ${fmtTime(fam.created)}`}),
    el("p", {class: "status-line"}, "Members ", counts, " ", progHost),
    message, el("div", {class: "actions"}, csv, compareBtn, cancel, remove)));

  /* the chart's controls */
  const xSel = el("select", {id: "family-x"}, ...axes.map((a, i) => el("option", {value: String(i), text: a})));
  const ySel = el("select", {id: "family-y"}, ...METRICS.map(([k, h]) => el("option", {value: k, text: `${h} (${k})`})));
  const bySel = el("select", {id: "family-by"}, el("option", {value: "-1", text: "none (pooled)"}),
    ...axes.map((a, i) => el("option", {value: String(i), text: a})));
  const logx = el("input", {type: "checkbox", id: "family-logx"});
  const logy = el("input", {type: "checkbox", id: "family-logy"});
  const chartNote = el("p", {class: "muted small", id: "family-chart-note"});
  const chartBox = el("div", {class: "plot family-chart", id: "family-chart", "data-channel": "family"});
  const chartCaption = el("figcaption");
  const chartTools = el("div", {class: "plot-tools"});
  const chartSection = el("section", {class: "panel", "aria-labelledby": "family-chart-title"},
    el("h2", {id: "family-chart-title", text: "Chart"}),
    el("div", {class: "toolbar plot-options"},
      el("label", {}, "x ", xSel), el("label", {}, "y ", ySel),
      axes.length > 1 ? el("label", {}, "a line per ", bySel) : null,
      el("label", {}, logx, " log x"), el("label", {}, logy, " log y")),
    chartNote, el("figure", {class: "plot-fig"}, chartCaption, chartTools, chartBox));
  const tableHost = el("div", {class: "table-wrap"});
  root.append(chartSection, el("section", {class: "panel"}, el("h2", {text: "Members"}), tableHost));
  xSel.value = String(state.x);
  ySel.value = state.y;
  bySel.value = String(state.by);
  logx.checked = state.logx;
  logy.checked = state.logy;

  let saving = 0;
  function save() {
    clearTimeout(saving);
    saving = setTimeout(() => {
      if (!ctx.alive()) return;
      const p = new URLSearchParams();
      if (axes.length) p.set("x", axes[state.x]);
      p.set("y", state.y);
      if (axes.length > 1) p.set("by", state.by >= 0 ? axes[state.by] : "none");
      if (state.logx) p.set("logx", "1");
      if (state.logy) p.set("logy", "1");
      if (state.sort) p.set("sort", `${state.sort.key}:${state.sort.dir}`);
      history.replaceState(null, "", `#/families/${id}?${decodeURIComponent(p.toString())}`);
    }, 250);
  }
  ctx.onCleanup(() => clearTimeout(saving));

  /* the table */
  const cols = tableColumns(axes);
  function drawTable() {
    const rows = fam.table.rows.slice();
    const col = state.sort && cols.find((c) => c.key === state.sort.key);
    if (col) {
      const sign = state.sort.dir === "desc" ? -1 : 1;
      rows.sort((a, b) => {
        const va = col.value(a), vb = col.value(b);
        if (va === null || va === undefined || vb === null || vb === undefined) return compareValues(va, vb);
        return sign * compareValues(va, vb);
      });
    }
    const focused = document.activeElement?.matches?.("#family-table button.sort") ? document.activeElement.dataset.key : null;
    const table = el("table", {id: "family-table"},
      el("caption", {class: "visually-hidden", text: "The family's members, one row each"}),
      el("thead", {}, el("tr", {}, el("th", {scope: "col", text: "compare"}), ...cols.map((c) => {
        const on = state.sort && state.sort.key === c.key ? (state.sort.dir === "desc" ? "descending" : "ascending") : null;
        const b = el("button", {type: "button", class: "sort", "data-key": c.key,
          text: c.head + (on ? (on === "ascending" ? " ▲" : " ▼") : "")});
        b.addEventListener("click", () => {
          state.sort = {key: c.key, dir: state.sort && state.sort.key === c.key && state.sort.dir === "asc" ? "desc" : "asc"};
          save();
          drawTable();
        });
        return el("th", {scope: "col", "aria-sort": on}, b);
      }))),
      el("tbody", {}, ...rows.map((r) => {
        const box = r.job ? el("input", {type: "checkbox", class: "compare-pick", "data-job-id": r.job,
          "aria-label": `compare member ${r.member}`}) : null;
        if (box) {
          box.checked = picked.has(r.job);
          box.addEventListener("change", () => {
            if (box.checked) picked.add(r.job); else picked.delete(r.job);
            compareBtn.disabled = picked.size === 0;
          });
        }
        return el("tr", {"data-job-id": r.job ?? "", "data-member": r.member, title: r.message || null},
          el("td", {}, box), ...cols.map((c) => {
            const v = c.value(r);
            if (c.key === "member") {
              return el("th", {scope: "row", "data-key": c.key},
                r.job ? el("a", {href: `#/jobs/${r.job}`, text: `${r.member}`, title: `job ${r.job}`}) : String(r.member));
            }
            if (c.key === "status") return el("td", {"data-key": c.key, class: `status status-${v}`, text: v});
            const num = typeof v === "number";
            return el("td", {"data-key": c.key, class: num ? "num" : null, "data-value": v ?? ""}, num ? fmtNum(v) : String(v ?? "–"));
          }));
      })));
    tableHost.replaceChildren(table);
    if (focused) table.querySelector(`button.sort[data-key="${CSS.escape(focused)}"]`)?.focus();
  }
  compareBtn.addEventListener("click", () => {
    const ids = fam.table.rows.map((r) => r.job).filter((j) => picked.has(j));
    if (ids.length) location.hash = `#/compare?ids=${ids.join(",")}`;
  });

  /* the chart */
  let u = null;
  const chartOff = () => { if (u) { u.destroy(); u = null; } };
  ctx.onCleanup(chartOff);
  function drawChart() {
    chartOff();
    chartBox.replaceChildren();
    chartTools.replaceChildren();
    chartCaption.textContent = "";
    if (!axes.length) { chartNote.textContent = "This family has no axis to plot against."; return; }
    const d = chartData(fam.table.rows, state.x, state.y, state.by);
    const catX = d.cats !== null;
    const useLogX = state.logx && !catX;
    const useLogY = state.logy;
    const keepX = (x) => !useLogX || x > 0;
    const keepY = (y) => y !== null && Number.isFinite(y) && (!useLogY || y > 0);
    /* one row per x; several members at one x (replicas, or a pooled axis) are drawn as
       points, a series per slot (uPlot's x must be strictly ascending), and as mean ± sd */
    const slots = Math.max(1, ...d.groups.map((g) => Math.max(0, ...d.xs.map((x) => g.points.filter((p) => p[0] === x).length))));
    const several = slots > 1;
    const each = (spec.replicas || 1) > 1 ? "each replica" : "each member";
    const xs = d.xs.filter(keepX);
    const data = [xs];
    const series = [{}];
    const lines = [];
    const unlisted = []; /* series left out of the legend: the second and later slots */
    let drawnPoints = 0;
    const yMeta = METRICS.find(([k]) => k === state.y);
    const name = (g) => (state.by >= 0 ? `${axes[state.by]} = ${typeof g.value === "number" ? fmtNum(g.value) : g.value}` : yMeta[1]);
    d.groups.forEach((g, gi) => {
      const color = PALETTE[gi % PALETTE.length];
      const at = xs.map((x) => d.xs.indexOf(x));
      const pick = (f) => at.map((k) => (keepY(f(k)) ? f(k) : null));
      const mean = pick((k) => g.mean[k]);
      const label = name(g);
      data.push(mean);
      series.push({label: several ? `${label} (mean)` : label, stroke: color, width: 2, spanGaps: true,
        points: {show: !several, size: 7, fill: color}});
      lines.push({label: several ? `${label} (mean)` : label, stroke: color, width: 2, dash: [], points: !several});
      if (!several) {
        drawnPoints += mean.filter((v) => v !== null).length;
        return;
      }
      for (let s = 0; s < slots; s++) {
        const pts = xs.map((x) => {
          const ys = g.points.filter((p) => p[0] === x).map((p) => p[1]);
          return s < ys.length && keepY(ys[s]) ? ys[s] : null;
        });
        drawnPoints += pts.filter((v) => v !== null).length;
        data.push(pts);
        if (s > 0) unlisted.push(series.length);
        series.push({label: `${label}, ${each}`, stroke: color, width: 0, paths: () => null,
          points: {show: true, size: 7, width: 1, fill: color, stroke: "#ffffff"}});
        lines.push({label: `${label}, ${each}`, stroke: color, width: 1, dash: [], points: true, only: true, nokey: s > 0});
      }
      for (const [f, which] of [[(k) => g.mean[k] - g.sd[k], "− 1 sd"], [(k) => g.mean[k] + g.sd[k], "+ 1 sd"]]) {
        data.push(pick(f));
        series.push({label: `${label} ${which}`, stroke: color, width: 1, dash: [5, 4], spanGaps: true, points: {show: false}});
        lines.push({label: `${label} ${which}`, stroke: color, width: 1, dash: [5, 4]});
      }
    });
    const notes = [];
    if (state.logx && catX) notes.push(`${axes[state.x]} is not numeric: no log x.`);
    if (useLogX && xs.length < d.xs.length) notes.push("x values that are not positive are left out on the log axis.");
    if (useLogY) notes.push("y values that are not positive are left out on the log axis.");
    if (several) notes.push(`Points: ${each}; solid: their mean; dashed: mean ± 1 standard deviation.`);
    if (state.by < 0 && axes.length > 1) notes.push(`Members differing in ${axes.filter((_, i) => i !== state.x).join(", ")} are pooled.`);
    chartNote.textContent = notes.join(" ");
    Object.assign(chartBox.dataset, {x: axes[state.x], y: state.y, by: state.by >= 0 ? axes[state.by] : "",
      points: String(drawnPoints), lines: String(d.groups.length), logX: useLogX ? "1" : "0", logY: useLogY ? "1" : "0"});
    if (!xs.length || !drawnPoints) {
      chartBox.append(el("p", {class: "empty", text: fam.table.rows.some((r) => r.status === "done") ?
        "No value of this metric to plot." : "No member has finished yet."}));
      return;
    }
    const title = `${yMeta[1]} against ${axes[state.x]}`;
    const yLabel = `${state.y} [${yMeta[2]}]`;
    const xLabel = axes[state.x];
    const width = Math.max(280, Math.min(chartSection.clientWidth - 24, 1100));
    u = new uPlot({
      width, height: 320, series,
      scales: {x: {time: false, distr: useLogX ? 3 : 1}, y: {distr: useLogY ? 3 : 1}},
      legend: {live: false},
      cursor: {drag: {x: false, y: false}},
      axes: [
        {label: xLabel, values: catX ? (_, splits) => splits.map((v) => (Number.isInteger(v) && d.cats[v] !== undefined ? d.cats[v] : "")) :
          (_, splits) => tickLabels(splits, useLogX), ...(catX ? {splits: () => xs} : {})},
        {label: yLabel, size: 70, values: (_, splits) => tickLabels(splits, useLogY)},
      ],
    }, data, chartBox);
    /* the legend's rows by series index (x's row is there only with a live legend) */
    const legendRows = u.root.querySelectorAll(".u-legend .u-series");
    const shift = legendRows.length === series.length ? 0 : 1;
    for (const i of unlisted) if (legendRows[i - shift]) legendRows[i - shift].style.display = "none";
    chartCaption.textContent = title + (several ? ", mean and spread" : "");
    chartTools.append(exportButtons(u, {channel: "family", joint: null, title, yLabel, xLabel, lines}));
    const xsc = u.scales.x, ysc = u.scales.y;
    Object.assign(chartBox.dataset, {xmin: String(xsc.min), xmax: String(xsc.max), ymin: String(ysc.min), ymax: String(ysc.max)});
  }
  const redraw = () => { ctx.busy(); drawChart(); save(); ctx.ready(); };
  xSel.addEventListener("change", () => {
    state.x = Number(xSel.value);
    if (state.by === state.x) { state.by = axes.length > 1 ? axes.findIndex((_, i) => i !== state.x) : -1; bySel.value = String(state.by); }
    redraw();
  });
  ySel.addEventListener("change", () => { state.y = ySel.value; redraw(); });
  bySel.addEventListener("change", () => {
    state.by = Number(bySel.value);
    if (state.by === state.x) { state.x = axes.findIndex((_, i) => i !== state.by); xSel.value = String(state.x); }
    redraw();
  });
  logx.addEventListener("change", () => { state.logx = logx.checked; redraw(); });
  logy.addEventListener("change", () => { state.logy = logy.checked; redraw(); });

  /* cancel and delete */
  const describe = () => {
    const p = familyProgress(fam);
    return `family #${id} “${fam.name}” (${p.finished} of ${p.members} members finished)`;
  };
  cancel.addEventListener("click", async () => {
    const ok = await confirmDialog({title: "Cancel this family's unfinished members?",
      text: `Cancel the unfinished members of ${describe()}? Running ones stop at their next step; finished ones are kept.`,
      action: "Cancel members"});
    if (!ok || !ctx.alive()) return;
    const active = fam.table.rows.filter((r) => r.job && (r.status === "queued" || r.status === "running")).map((r) => r.job);
    let done = 0, failed = 0, lastError = null;
    const worker = async () => {
      while (active.length) {
        const job = active.shift();
        try { await cancelJob(job, ctx.signal); done++; } catch (e) {
          if (e.name === "AbortError") throw e;
          if (e.code !== "ALREADY_FINISHED") { failed++; lastError = e; }
        }
      }
    };
    try {
      await Promise.all(Array.from({length: CANCEL_AT_ONCE}, worker));
    } catch (e) {
      if (e.name === "AbortError") return;
    }
    message.replaceChildren(failed ? errorBox(`${failed} members not cancelled`, lastError) :
      el("span", {text: `Cancel requested for ${done} members.`}));
  });
  remove.addEventListener("click", async () => {
    const ok = await confirmDialog({title: "Delete this family?",
      text: `Delete ${describe()}, with every member and its series? This cannot be undone.`, action: "Delete family"});
    if (!ok || !ctx.alive()) return;
    try {
      const p = familyProgress(await getFamily(id, ctx.signal));
      if (p.unfinished) { message.textContent = "Not deleted: some members are queued or running again."; return; }
      await deleteFamily(id, ctx.signal);
      location.hash = "#/families";
    } catch (e) {
      if (e.name !== "AbortError") message.replaceChildren(errorBox("Not deleted", e));
    }
  });

  function show() {
    const p = familyProgress(fam);
    counts.replaceChildren(countsNode(fam));
    progHost.replaceChildren(progressNode(fam, "family-progress"));
    cancel.hidden = p.unfinished === 0;
    remove.hidden = p.unfinished > 0;
    drawTable();
    drawChart();
  }
  show();
  ctx.ready();
  /* live while members run: the counts, the table and the chart every POLL_MS */
  let before = JSON.stringify(fam.counts);
  while (familyProgress(fam).unfinished) {
    await sleep(POLL_MS, ctx.signal);
    try {
      fam = await getFamily(id, ctx.signal);
    } catch (e) {
      if (e.name === "AbortError") return;
      message.replaceChildren(errorBox("The family could not be refreshed", e));
      continue;
    }
    const now = JSON.stringify(fam.counts);
    if (now !== before) {
      before = now;
      ctx.busy();
      show();
      ctx.ready();
    }
  }
}
