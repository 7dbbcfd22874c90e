/*
 * compare.js - several jobs side by side (#/compare?ids=3,5,8): a legend naming each job by its
 * controller and what differs between the jobs (summary.js), each in its own colour
 * (#compare-legend li[data-job-id]); a table of their figures (table#compare-table: final, RMS
 * and largest |e| per coordinate, peak torque, energy drift, controller and gains, µs per
 * evaluation), sortable by any column and saved as CSV (button#compare-csv); the plots overlaid,
 * coordinates told apart by dash pattern, or in the paper's layout (select#layout "paper": a
 * panel per coordinate, the controllers overlaid), with |e| on a log axis (input#log-e) and the
 * value axes zoomable; and the jobs animated side by side (canvas.anim[data-job-id]) under one
 * time cursor and one player. Without ids it offers the latest finished jobs to pick from.
 *
 * The address keeps the view: ids, the time cursor (t), the time zoom (x=a,b), each plot's
 * value zoom (y=PLOT:lo:hi~...), the hidden coordinates (hide=0,2), log=1, layout=paper and the
 * table's sort (sort=KEY:asc|desc); a reload or a shared link restores them. It is rewritten in
 * place (history.replaceState) as they change, so Back leaves the view rather than undoing them.
 *
 * Jobs still queued or running are waited for (polled every 2 s); a job that cannot be loaded
 * stays in the legend with the reason, and the others are drawn.
 */
import {getJob, listJobs} from "./api.js";
import {el, errorBox, fmtNum, isFinished, sleep} from "./dom.js";
import {createTimeline, timeSlider} from "./timeline.js";
import {createPlots, jointToggles, zoomButtons, PALETTE} from "./plots.js";
import {createAnimation, createPlayer} from "./animate.js";
import {loadPlotSeries} from "./series.js";
import {differenceLabels, jobFigures} from "./summary.js";
import {csvText, download} from "./export.js";
import {readState, writeState} from "./viewstate.js";

const go = (ids) => { location.hash = ids.length ? `#/compare?ids=${ids.join(",")}` : "#/compare"; };
const PER_JOINT_MAX = 6; /* per-coordinate columns up to this many coordinates, else the max */

async function picker(root, ctx) {
  const list = el("ul", {class: "pick-list"});
  const button = el("button", {id: "compare-selected", type: "button", text: "Compare selected"});
  root.append(el("h1", {text: "Compare jobs"}),
    el("p", {text: "Tick the runs to overlay (for example the same scene under PID, pole placement and LQR), then compare them. The jobs table has the same boxes."}),
    list, button);
  try {
    const {jobs} = await listJobs({limit: 60}, ctx.signal);
    for (const job of jobs.filter((j) => isFinished(j.status) && j.status !== "cancelled")) {
      const box = el("input", {type: "checkbox", class: "compare-pick", "data-job-id": job.id});
      list.append(el("li", {}, el("label", {}, box, ` #${job.id} ${job.name} (${job.controller}, ${job.status}, final |e| ${fmtNum(job.e_final)}, RMS e ${fmtNum(job.e_rms)})`)));
    }
    if (!list.children.length) list.replaceWith(el("p", {class: "empty", text: "No finished jobs yet."}));
  } catch (e) {
    if (e.name === "AbortError") return;
    root.append(errorBox("The job list could not be loaded", e));
  }
  button.addEventListener("click", () => {
    go([...root.querySelectorAll("input.compare-pick:checked")].map((b) => b.dataset.jobId));
  });
  ctx.ready();
}

/* the comparison table's columns: [{key, head, title, value(entry) -> number | string | null}] */
function tableColumns(entries) {
  const n = Math.max(0, ...entries.map((e) => e.fig.eFinal.length));
  const perJoint = n <= PER_JOINT_MAX;
  const cols = [
    {key: "run", head: "run", title: "controller and what differs", value: (e) => e.label, text: true},
    {key: "controller", head: "controller", value: (e) => e.fig.controller, text: true},
    {key: "gains", head: "gains", value: (e) => e.fig.gains, text: true},
  ];
  for (const [key, head, field] of [["e_final", "final |e|", "eFinal"], ["e_rms", "RMS e", "eRms"], ["e_max", "max |e|", "eMax"]]) {
    if (perJoint) {
      for (let j = 0; j < n; j++) {
        cols.push({key: `${key}.${j}`, head: `${head} [${j}]`, title: `${head} of coordinate ${j}`,
          value: (e) => (typeof e.fig[field][j] === "number" ? Math.abs(e.fig[field][j]) : null)});
      }
    } else {
      cols.push({key: `${key}.max`, head: `${head} (max)`, title: `largest over the ${n} coordinates`,
        value: (e) => (e.fig[field].length ? Math.max(...e.fig[field].filter((v) => typeof v === "number").map(Math.abs)) : null)});
    }
  }
  cols.push({key: "tau_peak", head: "peak |τ|", title: "largest |tau| over the actuators (N m or N)", value: (e) => e.fig.tauPeak},
    {key: "energy_drift", head: "energy drift", title: "relative drift of the total energy (passive runs)", value: (e) => e.fig.energyDrift},
    {key: "us_per_eval", head: "µs / eval", title: "µs per evaluation of the dynamics", value: (e) => e.fig.usPerEval});
  return cols;
}

/* CSV of the table: every coordinate's column whatever the screen shows */
function tableCsv(entries) {
  const n = Math.max(0, ...entries.map((e) => e.fig.eFinal.length));
  const head = ["job", "name", "run", "controller", "gains"];
  for (const m of ["e_final", "e_rms", "e_max"]) for (let j = 0; j < n; j++) head.push(`${m}[${j}]`);
  head.push("tau_peak", "energy_drift", "us_per_eval");
  const rows = entries.map((e) => {
    const r = [e.id, e.job.name, e.label, e.fig.controller, e.fig.gains];
    for (const f of ["eFinal", "eRms", "eMax"]) for (let j = 0; j < n; j++) r.push(e.fig[f][j] ?? null);
    r.push(e.fig.tauPeak, e.fig.energyDrift, e.fig.usPerEval);
    return r;
  });
  return csvText([head, ...rows]);
}

/* table#compare-table into host: sortable by each column's button (aria-sort on its th) */
function compareTable(host, entries, sort, onSort) {
  const cols = tableColumns(entries);
  const table = el("table", {id: "compare-table"});
  const draw = () => {
    const col = sort && cols.find((c) => c.key === sort.key);
    const rows = entries.slice();
    if (col) {
      const sign = sort.dir === "desc" ? -1 : 1;
      rows.sort((a, b) => {
        const va = col.value(a), vb = col.value(b);
        if (va === null || va === undefined) return vb === null || vb === undefined ? 0 : 1;
        if (vb === null || vb === undefined) return -1;
        return sign * (col.text ? String(va).localeCompare(String(vb)) : va - vb);
      });
    }
    table.replaceChildren(
      el("caption", {class: "visually-hidden", text: "The jobs compared, one row each"}),
      el("thead", {}, el("tr", {}, ...cols.map((c) => {
        const state = sort && sort.key === c.key ? (sort.dir === "desc" ? "descending" : "ascending") : null;
        const b = el("button", {type: "button", class: "sort", "data-key": c.key, title: c.title || null,
          text: c.head + (state ? (state === "ascending" ? " ▲" : " ▼") : "")});
        b.addEventListener("click", () => {
          sort = {key: c.key, dir: sort && sort.key === c.key && sort.dir === "asc" ? "desc" : "asc"};
          onSort(sort);
          draw();
          table.querySelector(`button.sort[data-key="${CSS.escape(c.key)}"]`)?.focus();
        });
        return el("th", {scope: "col", "aria-sort": state}, b);
      }))),
      el("tbody", {}, ...rows.map((e) => el("tr", {"data-job-id": e.id}, ...cols.map((c) => {
        const v = c.value(e);
        if (c.key === "run") {
          return el("th", {scope: "row", "data-key": c.key},
            el("span", {class: "swatch", style: `background:${e.color}`}),
            el("a", {href: `#/jobs/${e.id}`, text: e.label, title: `job ${e.id}: ${e.job.name}`}));
        }
        return el("td", {"data-key": c.key, class: c.text ? null : "num", "data-value": c.text ? null : (v ?? "")},
          c.text ? String(v ?? "–") : fmtNum(v));
      })))));
  };
  draw();
  const csv = el("button", {type: "button", id: "compare-csv", text: "Download CSV"});
  csv.addEventListener("click", () => download(new Blob([tableCsv(entries)], {type: "text/csv"}), "ctcsim-compare.csv"));
  host.append(el("div", {class: "table-head"}, el("h2", {text: "Figures"}), csv),
    el("div", {class: "table-wrap"}, table));
}

export async function compareView(root, ctx) {
  document.title = "Compare - ctcsim";
  const q = ctx.params.query;
  const ids = [...new Set((q.get("ids") || "").split(",").map(Number)
    .filter((n) => Number.isInteger(n) && n > 0))];
  if (!ids.length) return picker(root, ctx);
  const state = readState(q);

  const legend = el("ul", {id: "compare-legend"});
  const addInput = el("input", {type: "number", min: "1", step: "1", id: "compare-add", "aria-label": "job id to add"});
  const addForm = el("form", {class: "inline"}, el("label", {}, "Add job # ", addInput), el("button", {type: "submit", text: "Add"}));
  addForm.addEventListener("submit", (ev) => {
    ev.preventDefault();
    const n = Number(addInput.value);
    if (Number.isInteger(n) && n > 0 && !ids.includes(n)) go([...ids, n]);
  });
  const note = el("div", {role: "status"});
  const toolbar = el("div", {class: "sticky-toolbar"});
  const tableBox = el("section", {class: "compare-table"});
  const options = el("div", {class: "toolbar plot-options"});
  const host = el("div", {class: "plots compare"});
  const animBox = el("section", {class: "compare-anims"});
  root.append(el("h1", {text: "Compare jobs"}), legend, addForm, note, tableBox, toolbar, options, host, animBox);

  /* the jobs, in the order asked; entries {id, color, job | error, li} */
  const entries = ids.map((id, i) => ({id, color: PALETTE[i % PALETTE.length]}));
  for (const e of entries) {
    const remove = el("button", {type: "button", class: "icon", "aria-label": `remove job ${e.id}`, text: "×"});
    remove.addEventListener("click", () => go(ids.filter((x) => x !== e.id)));
    e.text = el("span", {text: `#${e.id} loading…`});
    e.li = el("li", {"data-job-id": e.id, style: `border-left-color:${e.color}`},
      el("span", {class: "swatch", style: `background:${e.color}`}), e.text, remove);
    legend.append(e.li);
  }
  const describe = (e) => {
    if (e.error) { e.text.textContent = `#${e.id}: ${e.error.message}`; return; }
    const j = e.job;
    const fig = jobFigures(j);
    e.text.replaceChildren(el("a", {href: `#/jobs/${j.id}`, class: "run-label", text: e.label || j.name, title: `job ${j.id}`}),
      el("span", {class: "muted small", text: ` ${j.name}`}),
      ` · ${j.status}` + (isFinished(j.status) ? ` · final |e| ${fmtNum(Math.max(0, ...fig.eFinal.map(Math.abs)))} · RMS e ${fmtNum(j.e_rms)}` : ` ${Math.round(100 * j.progress)} %`));
  };

  for (;;) {
    await Promise.all(entries.filter((e) => !e.job || !isFinished(e.job.status)).map(async (e) => {
      if (e.error) return;
      try { e.job = await getJob(e.id, ctx.signal); } catch (err) {
        if (err.name === "AbortError") throw err;
        e.error = err;
      }
      describe(e);
    }));
    if (entries.every((e) => e.error || isFinished(e.job.status))) break;
    note.replaceChildren(el("p", {class: "muted", text: "Waiting for the jobs still queued or running…"}));
    ctx.ready();
    await sleep(2000, ctx.signal);
  }
  ctx.busy();
  note.replaceChildren();

  /* labels: the controller and what differs */
  const loaded = entries.filter((e) => e.job);
  differenceLabels(loaded.map((e) => e.job)).forEach((l, i) => { loaded[i].label = l; });
  for (const e of loaded) { e.fig = jobFigures(e.job); describe(e); }
  if (loaded.length) compareTable(tableBox, loaded, state.sort, (s) => { state.sort = s; save(); });

  await Promise.all(loaded.map(async (e) => {
    try {
      const d = await loadPlotSeries(e.job, host.clientWidth, ctx.signal);
      e.data = d;
      e.source = {label: e.label, color: e.color, series: d.series, joints: d.joints,
        coords: d.coords, loop: d.loop, spec: e.job.spec};
    } catch (err) {
      if (err.name === "AbortError") throw err;
      e.li.append(el("span", {class: "error", text: ` (no series: ${err.message})`}));
    }
  }));
  const drawn = entries.filter((e) => e.source);
  if (!drawn.length) {
    note.append(el("p", {class: "empty", text: "None of these jobs has a series to plot."}));
    ctx.ready();
    return;
  }

  const duration = Math.max(...drawn.map((e) => e.job.spec.duration));
  const step = Math.min(...drawn.map((e) => e.job.spec.output.interval));
  const timeline = createTimeline(duration);
  const tEnd = Math.max(...drawn.map((e) => (e.data.anim.t.length ? e.data.anim.t[e.data.anim.t.length - 1] : 0)));
  const player = createPlayer(timeline, tEnd);
  ctx.onCleanup(() => player.destroy());

  /* the address, rewritten (debounced) as the state changes */
  let saving = 0;
  function save() {
    clearTimeout(saving);
    saving = setTimeout(() => {
      if (!ctx.alive()) return;
      const p = writeState(new URLSearchParams({ids: ids.join(",")}),
        {t: timeline.t, x: plots && plots.xRange(), y: state.y, hide: state.hide});
      if (state.log) p.set("log", "1");
      if (state.layout === "paper") p.set("layout", "paper");
      if (state.sort) p.set("sort", `${state.sort.key}:${state.sort.dir}`);
      history.replaceState(null, "", `#/compare?${decodeURIComponent(p.toString())}`);
    }, 250);
  }
  ctx.onCleanup(() => clearTimeout(saving));
  timeline.subscribe(() => save());

  /* the plots, drawn again when the layout or the log axis changes */
  let plots = null;
  let toggles = null;
  const ncoord = Math.max(...drawn.map((e) => (e.source.joints ? e.source.joints.length :
    Math.max(e.job.metrics?.nv ?? 0, e.job.metrics?.nq ?? 0, ...(e.source.loop ? e.source.coords.map((c) => c.row + 1) : [])))));
  function drawPlots(x) {
    if (plots) plots.destroy();
    host.replaceChildren();
    plots = createPlots(host, drawn.map((e) => e.source), timeline,
      {compare: true, logE: state.log, layout: state.layout, yZoom: state.y, onZoom: save});
    toggles = jointToggles(plots, Array.from({length: ncoord}, (_, i) => i), () => null, (j) => `joint ${j}`,
      {hidden: state.hide, onChange: (hidden) => { state.hide = hidden; save(); }});
    host.prepend(toggles, el("p", {class: "muted small", text: state.layout === "paper" ?
      "A panel per coordinate; colour: run. Thin dotted: desired q_d." :
      "Colour: run. Coordinates 0, 1, 2, 3: solid, long dash, dotted, dash-dot. Thin dotted: desired q_d."}));
    if (x) plots.setX(x[0], x[1]);
  }
  const logBox = el("input", {type: "checkbox", id: "log-e"});
  logBox.checked = state.log;
  const layoutSel = el("select", {id: "layout"},
    el("option", {value: "channels", text: "one plot per quantity"}),
    el("option", {value: "paper", text: "the paper's: a panel per coordinate"}));
  layoutSel.value = state.layout;
  logBox.addEventListener("change", () => {
    state.log = logBox.checked;
    delete state.y.e;
    for (const k of Object.keys(state.y)) if (k.startsWith("e.")) delete state.y[k];
    ctx.busy(); drawPlots(plots && plots.xRange()); save(); ctx.ready();
  });
  layoutSel.addEventListener("change", () => {
    state.layout = layoutSel.value;
    ctx.busy(); drawPlots(plots && plots.xRange()); save(); ctx.ready();
  });
  options.append(el("label", {}, logBox, " |e| on a log scale"), el("label", {}, "Layout ", layoutSel));
  drawPlots(state.x);
  ctx.onCleanup(() => plots && plots.destroy());
  toolbar.append(timeSlider(timeline, step), player.node, zoomButtons({
    zoomIn: () => plots.zoomIn(), zoomInY: () => plots.zoomInY(), resetZoom: () => plots.resetZoom()}));

  /* the runs animated side by side */
  const animated = drawn.filter((e) => e.data.anim.q && e.data.anim.t.length);
  if (animated.length) {
    const grid = el("div", {class: "anim-grid"});
    animBox.append(el("h2", {text: "Animations"}), grid);
    for (const e of animated) {
      const cell = el("div", {class: "panel anim", "data-job-id": e.id, style: `border-top: 5px solid ${e.color}`});
      grid.append(cell);
      const anim = createAnimation(cell, {spec: e.job.spec, form: e.job.metrics?.form, series: e.data.anim,
        timeline, id: `anim-${e.id}`, caption: e.label});
      cell.querySelector("canvas").dataset.jobId = String(e.id);
      ctx.onCleanup(() => anim.destroy());
    }
  }
  timeline.set(Math.min(state.t, duration), null);
  ctx.ready();
}
