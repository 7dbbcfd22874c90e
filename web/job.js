/*
 * job.js - one job (#/jobs/{id}): status while it is queued or running, then its plots,
 * animation, per-coordinate summary, error heat-map, metrics, normalised spec and downloads.
 *
 * While the job waits or runs the view polls GET /api/jobs/{id}?brief=1 every second (the row,
 * without the spec, which for a 4096-link chain is large) and shows its place in the queue,
 * the simulated time (progress x duration) and an estimate of the time left (the wall time so
 * far scaled by what remains). A running job's plots grow: every PARTIAL_EVERY_MS the view asks
 * for the samples recorded since the last ones it has (?partial=1&from=K, every k-th so that the
 * whole run is about PARTIAL_ROWS rows) and redraws them. The view is ready (data-ready) once the
 * job is shown: at once for a queued or running job, and again after the final plots are drawn.
 *
 * A run that stopped early (failed, diverged, cancelled) says how far it got ("ran 0.33 s of
 * 5 s"), why, with a hint, and offers re-runs - with BDF, with a smaller step - that post an
 * edited copy of its spec and open the new job. An RK4 step cut to divide the output interval
 * (metrics.step_cut) is shown. Cancel (queued or running only) and Delete (finished only) are
 * separate buttons, each confirmed in a dialog naming the job and its status; a cancel goes to
 * POST /api/jobs/{id}/cancel, which never deletes a job that finished in the meantime.
 *
 * A finished job is drawn in stages, so that the page is usable before all of it is there: the
 * plots' series is fetched first (the heat-map's at the same time), the plots, the time cursor
 * and the summary are drawn (div.plots gets data-drawn="1"), then after the first paint the
 * heat-map, then the animation: its own series (fetched only when the plots' does not serve it)
 * is asked for when its panel is in view, at once on a desktop, else when it scrolls into view
 * or on play. data-ready comes when the animation is drawn or waits out of view.
 *
 * Large chains: the plots show a few coordinates (series.js defaultJoints: the worst by RMS
 * error), chosen with the joint picker (form#joint-picker, "0-3, 17"), the summary table or a
 * click on the heat-map; the metrics list keeps the scalars and the table the per-coordinate
 * values.
 *
 * The address keeps the time cursor, the time and value zooms and the hidden coordinates
 * (#/jobs/7?t=1.2&x=0.5,1.5&y=e:-0.01:0.01&hide=0,2, viewstate.js), rewritten in place as they
 * change once the final plots are drawn; opening such an address restores them.
 */
import {getJob, getJobBrief, deleteJob, cancelJob, postJob, seriesUrl} from "./api.js";
import {el, errorBox, fmtNum, fmtTime, isFinished, prettyJson, sleep} from "./dom.js";
import {createTimeline, timeSlider} from "./timeline.js";
import {createPlots, jointToggles, zoomButtons, PALETTE} from "./plots.js";
import {createAnimation, createPlayer} from "./animate.js";
import {loadPlotSeries, loadAnimSeries, loadHeatSeries, loadPartialSeries, appendSeries, controlledCoordinates,
  plotsCoverAnimation, MAX_PLOTTED} from "./series.js";
import {jointSummary} from "./jointsummary.js";
import {createHeatmap} from "./heatmap.js";
import {confirmDialog} from "./confirm.js";
import {readState, writeState} from "./viewstate.js";

/* coordinates from which the heat-map is drawn: fewer read well enough in the plots */
const HEAT_MIN = 8;
/* a running job's plots: new samples at most this often, and about this many rows in all */
const PARTIAL_EVERY_MS = 2000;
const PARTIAL_ROWS = 2000;
/* characters of spec JSON shown at once; a longer one is behind a <details> */
const SPEC_OPEN_MAX = 200000;

/* The metrics as a definition list (dl#metrics). */
export function metricsList(m) {
  const dl = el("dl", {id: "metrics"});
  const add = (term, value) => dl.append(el("dt", {text: term}), el("dd", {text: value}));
  if (!m) { add("metrics", "none yet: the job has not run to the end"); return dl; }
  add("status", m.message ? `${m.status}: ${m.message}` : m.status);
  const loop = m.loop;
  add("form", `${m.form} (nq ${m.nq}, nv ${m.nv}${loop ? `, ${m.nind} independent` : ""})`);
  if (loop && Array.isArray(m.coordinates)) {
    add("controlled coordinates", m.coordinates.length ?
      m.coordinates.map((c, i) => `${i}: joint ${c.joint}`).join(", ") : "none (every joint passive)");
  }
  add("samples", `${m.samples} to t = ${fmtNum(m.t_end)} s`);
  const worst = (xs) => (Array.isArray(xs) && xs.length ? Math.max(...xs.map((x) => Math.abs(x ?? 0))) : null);
  if (m.e_rms) {
    add("tracking error", `RMS ≤ ${fmtNum(worst(m.e_rms))}, final |e| ≤ ${fmtNum(worst(m.e_final))}, ` +
      `max |e| ≤ ${fmtNum(worst(m.e_max))} (worst coordinate; each one in the table)`);
  }
  if (m.tau_peak) add("actuator peak |τ|", `≤ ${fmtNum(worst(m.tau_peak))} (worst coordinate)`);
  if (m.sat_fraction) add("fraction of samples at the torque limit", `≤ ${fmtNum(worst(m.sat_fraction))}`);
  if (m.step_cut) add("RK4 step", `${fmtNum(m.step_cut.used)} s, cut from the ${fmtNum(m.step_cut.asked)} s asked`);
  if (loop) {
    add("loop residual max", `${fmtNum(loop.residual_max)} (position), ${fmtNum(loop.velocity_residual_max)} (velocity)`);
    add("loop condition max", fmtNum(loop.cond_max));
    add("projections onto the loop", String(loop.projections));
    const init = loop.initial || {};
    add("initial correction", `${init.iterations ?? "–"} Newton iterations, |dq| ≤ ${fmtNum(init.dq_max)}, ` +
      `|dv| ≤ ${fmtNum(init.dv_max)}, residual ${fmtNum(init.residual_before)} → ${fmtNum(init.residual_after)}`);
  }
  const causes = errorCausesText(m.error_by_cause);
  if (causes) add("tracking error by cause", causes);
  if (m.errdyn_dev !== null) add("deviation from the exact error dynamics", fmtNum(m.errdyn_dev));
  if (m.energy_drift !== null) add("relative energy drift", fmtNum(m.energy_drift));
  add("integrator error estimate", fmtNum(m.err_estimate));
  const floor = m.tolerance_floor;
  if (floor) {
    add("tolerances", floor.raised ? `raised: ${floor.reason}` :
      `rtol ${fmtNum(floor.rtol)}, atol ${fmtNum(floor.atol)}, as asked (the accelerations round to ` +
      `${fmtNum(floor.accel_rounding)}: no need to raise them)`);
  }
  add("cost", `${fmtNum(m.us_per_eval)} µs per evaluation; ${m.steps} steps (${m.rejected} rejected), ` +
    `${m.rhs_evals} evaluations`);
  add("wall time", `${fmtNum(m.wall_s)} s (CPU ${fmtNum(m.cpu_s)} s)`);
  if (m.diverged_joint !== null) add("diverged at joint", String(m.diverged_joint));
  if (m.gains) {
    const text = m.gains.map((g) => Object.entries(g).map(([k, v]) => `${k} ${fmtNum(v)}`).join(", "));
    const shown = 6;
    add("gains", text.every((s) => s === text[0]) ? `every joint: ${text[0]}` :
      text.slice(0, shown).map((s, i) => `${i}: ${s}`).join("; ") +
      (text.length > shown ? `; … (${text.length} coordinates: the spec has them all)` : ""));
  }
  return dl;
}

/* metrics.error_by_cause in one line: each cause's RMS over time and the coordinates and its share
 * of the three causes' sum ("sampling 0.012 (80 %), noise 0.003 (20 %), model 0 (0 %); the job's
 * total 0.013 ..."), or null when the job has none of the causes (all zeros), or the metrics none
 * (a passive run, or a job stored before them). */
export function errorCausesText(causes) {
  if (!causes || !Array.isArray(causes.total)) return null;
  const rms = (xs) => (Array.isArray(xs) && xs.length ?
    Math.sqrt(xs.reduce((s, x) => s + (x ?? 0) * (x ?? 0), 0) / xs.length) : 0);
  const names = ["sampling", "noise", "model"];
  const each = names.map((k) => rms(causes[k]));
  const sum = each.reduce((a, b) => a + b, 0);
  if (!(sum > 0)) return null;
  const parts = names.map((k, i) => `${k} ${fmtNum(each[i])} (${Math.round((100 * each[i]) / sum)} %)`);
  return `${parts.join(", ")}; the job's total ${fmtNum(rms(causes.total))} (RMS over time and coordinates)`;
}

/* How far a run got, for a finished job: "ran 0.33 s of 5 s", or null when it ran to the end. */
export function ranText(job) {
  const m = job.metrics;
  const duration = job.spec && job.spec.duration;
  if (!m || !(duration > 0) || !Number.isFinite(m.t_end) || m.t_end >= duration * (1 - 1e-9)) return null;
  return `ran ${fmtNum(m.t_end)} s of ${fmtNum(duration)} s (${Math.floor((100 * m.t_end) / duration)} %)`;
}

/* A hint for a run that stopped early, from its status and message. */
export function failureHint(job) {
  const m = job.metrics || {};
  const text = `${job.message || ""} ${m.message || ""}`;
  const status = m.status || job.status;
  if (job.status === "cancelled") return "It was cancelled; run it again to see it to the end.";
  if (status === "singular" || /singular|cannot drive/.test(text)) {
    return "The closed chain reached a pose where its independent joints can no longer drive it: " +
      "choose other independent joints, or a set point and start away from that pose.";
  }
  if (/wall|time limit/.test(text)) return "It ran out of wall time: shorten the duration, or record fewer samples.";
  if (/stiff/.test(text)) return "The system is stiff here (high gains or light bodies): BDF is made for this.";
  if (/exceeds the bound|not finite|NaN/.test(text)) {
    return "The state grew without bound: the gains may be too high for the step (a smaller step or BDF " +
      "keeps up), or the controller cannot hold the chain (lower the gains).";
  }
  return "A smaller step or BDF is the usual first try; the message above says what the integrator met.";
}

/* The edited copies that the re-run buttons post: [{id, label, doc}]. */
export function rerunDocs(job) {
  const spec = job.spec || {};
  const integ = spec.integrator || {method: "dopri5"};
  const name = spec.name || job.name || `job ${job.id}`;
  const out = [];
  if (integ.method !== "bdf") {
    out.push({id: "rerun-bdf", label: "Re-run with BDF", doc: {...structuredClone(spec), name: `${name}, with BDF`,
      integrator: {method: "bdf", rtol: integ.rtol ?? 1e-8, atol: integ.atol ?? 1e-10}}});
  }
  let smaller;
  if (integ.method === "rk4") {
    const used = (job.metrics && job.metrics.step_cut && job.metrics.step_cut.used) || integ.step || 0.001;
    smaller = {...integ, step: used / 4};
  } else {
    smaller = {...integ, rtol: Math.max(1e-13, (integ.rtol ?? 1e-8) / 100), atol: Math.max(1e-15, (integ.atol ?? 1e-10) / 100)};
    if (integ.max_step > 0) smaller.max_step = integ.max_step / 4;
  }
  const what = integ.method === "rk4" ? `step ${fmtNum(smaller.step)} s` : `rtol ${fmtNum(smaller.rtol)}`;
  out.push({id: "rerun-smaller-step", label: `Re-run with a smaller step (${what})`,
    doc: {...structuredClone(spec), name: `${name}, ${what}`, integrator: smaller}});
  return out;
}

/* "1st", "2nd", "3rd", "4th", ... */
function ordinal(n) {
  const s = n % 100 >= 11 && n % 100 <= 13 ? "th" : ({1: "st", 2: "nd", 3: "rd"})[n % 10] || "th";
  return `${n}${s}`;
}

/* Where a queued or running job stands: queue place, simulated time, time left. */
export function runningText(job, duration, now = Date.now()) {
  if (job.status === "queued") {
    return job.queue_position ? `${ordinal(job.queue_position)} in the queue` : "waiting for a worker";
  }
  const p = Math.min(1, Math.max(0, job.progress || 0));
  const parts = [`simulated ${fmtNum(p * duration)} s of ${fmtNum(duration)} s`];
  const started = job.started ? Date.parse(job.started) : NaN;
  if (p > 0.01 && Number.isFinite(started)) {
    const left = ((now - started) / 1000) * (1 - p) / p;
    parts.push(`about ${left < 1 ? "1 s" : left < 120 ? `${Math.round(left)} s` : `${Math.round(left / 60)} min`} left`);
  }
  return parts.join(", ");
}

export async function jobView(root, ctx) {
  const id = Number(ctx.params.id);
  const state = readState(ctx.params.query);
  document.title = `Job ${id} - ctcsim`;
  let job;
  try {
    job = await getJob(id, ctx.signal);
  } catch (e) {
    if (e.name === "AbortError") return;
    root.append(el("h1", {text: `Job ${id}`}), errorBox(`Job ${id} could not be loaded`, e),
      el("p", {}, el("a", {href: "#/jobs", text: "Back to the jobs"})));
    ctx.ready();
    return;
  }
  const spec = job.spec;
  const duration = spec.duration;

  /* header: name, what it is, status, actions */
  const statusEl = el("span", {id: "job-status"});
  const progress = el("progress", {id: "job-progress", max: "1", "aria-label": "job progress"});
  const percent = el("span", {id: "job-progress-text", class: "muted"});
  const message = el("p", {class: "message", role: "status"}); /* what an action did */
  const jobMessage = el("p", {id: "job-message", class: "muted"}); /* the server's word on the run */
  const actions = el("div", {class: "actions"});
  const cancel = el("button", {type: "button", id: "cancel-job", class: "danger", text: "Cancel job"});
  const remove = el("button", {type: "button", id: "delete-job", class: "danger", text: "Delete job"});
  const meta = el("p", {class: "meta"});
  const failure = el("section", {id: "job-failure", class: "panel failure", hidden: true,
    "aria-labelledby": "job-failure-title"});
  const stepCut = el("p", {id: "step-cut", class: "note", hidden: true});
  root.append(el("section", {class: "job-head"},
    el("h1", {text: job.name}), meta,
    el("p", {class: "status-line"}, "Status ", statusEl, " ", progress, " ", percent),
    jobMessage, message, stepCut, actions), failure);
  const metricsBox = el("section", {class: "panel"}, el("h2", {text: "Metrics"}));
  /* a large spec (thousands of bodies) is laid out only when opened: a 1.4 MB <pre> would
     cost its layout on every reflow of the page */
  const specText = prettyJson(spec);
  const specPre = el("pre", {id: "spec", tabindex: "0", text: specText});
  const specBox = el("section", {class: "panel"}, el("h2", {text: "Normalised job"}),
    specText.length > SPEC_OPEN_MAX ? el("details", {class: "spec-details"},
      el("summary", {text: `Show it (${(specText.length / 1e6).toFixed(1)} MB of JSON)`}), specPre) : specPre);
  const toolbar = el("div", {class: "sticky-toolbar"});
  const plotsHost = el("div", {class: "plots"});
  const heatBox = el("section", {class: "panel heat", hidden: true, "aria-labelledby": "heat-title"},
    el("h2", {id: "heat-title", text: "Tracking error |e|, coordinate × time"}));
  const summaryHost = el("div", {class: "summary-host"});
  const animBox = el("section", {class: "panel anim"}, el("h2", {text: "Animation"}));
  root.append(toolbar, el("div", {class: "job-grid"}, el("div", {class: "main-col"}, plotsHost, heatBox),
    el("aside", {class: "side"}, animBox, summaryHost, metricsBox, specBox)));

  function showFailure(j) {
    const ran = ranText(j);
    const stopped = isFinished(j.status) && j.status !== "done";
    failure.hidden = !stopped;
    if (!stopped) return;
    const reason = j.message || (j.metrics && j.metrics.message) || "";
    const buttons = j.status === "cancelled" ? [] : rerunDocs(j).map(({id: bid, label, doc}) => {
      const b = el("button", {type: "button", id: bid, text: label});
      b.addEventListener("click", async () => {
        b.disabled = true;
        try {
          const made = await postJob(doc, ctx.signal);
          location.hash = `#/jobs/${made.id}`;
        } catch (e) {
          if (e.name !== "AbortError") failure.append(errorBox("The re-run was not accepted", e));
          b.disabled = false;
        }
      });
      return b;
    });
    failure.replaceChildren(
      el("h2", {id: "job-failure-title", text: j.status === "cancelled" ? "Cancelled" : "The run stopped early"}),
      el("p", {id: "job-ran", text: ran ? `It ${ran}.` : "It reached the end of its duration."}),
      reason ? el("p", {id: "job-reason"}, el("strong", {text: "Why: "}), reason) : null,
      el("p", {id: "job-hint", class: "hint-text", text: failureHint(j)}),
      buttons.length ? el("div", {class: "actions"}, ...buttons) : null);
  }

  function show(j) {
    meta.textContent = `#${j.id} · ${j.preset || "custom job"} · ${j.scene.bodies} bodies, ` +
      `${j.scene.coordinates} coordinates · controller ${j.controller} · created ${fmtTime(j.created)}` +
      (j.finished ? ` · finished ${fmtTime(j.finished)}` : "") +
      (j.wall_s !== null ? ` · wall ${fmtNum(j.wall_s)} s` : "");
    const ended = j.metrics && j.metrics.status;
    statusEl.textContent = ended && isFinished(j.status) && ended !== j.status && ended !== "done" ?
      `${j.status} (${ended})` : j.status;
    statusEl.className = `status status-${j.status}`;
    const running = !isFinished(j.status);
    progress.hidden = !running;
    if (running) progress.value = j.progress; else progress.remove();
    percent.textContent = running ? `${Math.round(100 * j.progress)} % · ${runningText(j, duration)}` :
      (ranText(j) || (j.status === "done" ? "" : `${Math.round(100 * j.progress)} %`));
    jobMessage.textContent = running ? "" : j.message || "";
    cancel.hidden = !running;
    remove.hidden = running;
    const cut = j.metrics && j.metrics.step_cut;
    stepCut.hidden = !cut;
    if (cut) {
      stepCut.textContent = `RK4 ran with a step of ${fmtNum(cut.used)} s, not the ${fmtNum(cut.asked)} s asked: ` +
        `the step is cut to divide the output interval (${fmtNum(spec.output && spec.output.interval)} s). ` +
        "For a longer step, lengthen the output interval too.";
    }
    if (j.metrics !== undefined) {
      metricsBox.querySelector("dl")?.remove();
      metricsBox.append(metricsList(j.metrics));
      showFailure(j);
    }
  }

  const describe = (j) => `job #${j.id} “${j.name}”, now ${j.status}`;
  cancel.addEventListener("click", async () => {
    const ok = await confirmDialog({title: "Cancel this job?",
      text: `Cancel ${describe(job)}? It stops at its next step and keeps what it ran so far.`, action: "Cancel job"});
    if (!ok || !ctx.alive()) return;
    try {
      await cancelJob(id, ctx.signal);
      message.textContent = "Cancel requested.";
    } catch (e) {
      if (e.name === "AbortError") return;
      message.replaceChildren(e.code === "ALREADY_FINISHED" ?
        el("span", {text: `Not cancelled: ${e.message}. The job is kept.`}) : errorBox("Not cancelled", e));
    }
  });
  remove.addEventListener("click", async () => {
    const ok = await confirmDialog({title: "Delete this job?",
      text: `Delete ${describe(job)}, with its series? This cannot be undone.`, action: "Delete job"});
    if (!ok || !ctx.alive()) return;
    try {
      await deleteJob(id, ctx.signal);
      location.hash = "#/jobs";
    } catch (e) {
      if (e.name !== "AbortError") message.replaceChildren(errorBox("Not deleted", e));
    }
  });
  actions.append(
    el("a", {class: "button", href: `#/compare?ids=${id}`, text: "Compare…"}),
    el("a", {class: "button", href: `#/submit?job=${id}`, text: "Edit as a new job"}), cancel, remove);
  show(job);

  /* wait for the end: the row only, every second, and the new samples every PARTIAL_EVERY_MS */
  const waiting = el("p", {class: "empty", id: "plots-waiting",
    text: "The plots grow as the job runs; the animation, the summary and the heat-map come when it has finished."});
  if (!isFinished(job.status)) plotsHost.append(waiting);
  const partial = {series: null, next: 0, at: 0, plots: null, timeline: createTimeline(duration),
    every: Math.max(1, Math.ceil((duration / spec.output.interval + 1) / PARTIAL_ROWS))};
  ctx.onCleanup(() => partial.plots && partial.plots.destroy());
  async function growPlots() {
    partial.at = Date.now();
    let got;
    try {
      got = await loadPartialSeries(job, partial.next, partial.every, ctx.signal);
    } catch (e) {
      if (e.name === "AbortError") throw e;
      return; /* no sample yet (409), or finished meanwhile: the next poll tells */
    }
    if (!got.series.t.length) return;
    partial.series = appendSeries(partial.series, got.series);
    partial.next = got.next;
    if (partial.plots) partial.plots.destroy();
    const t = partial.series.t;
    waiting.textContent = `Running: the plots show t = 0 to ${fmtNum(t[t.length - 1])} s of ${fmtNum(duration)} s, ` +
      "growing as the job runs.";
    plotsHost.replaceChildren(waiting);
    const host = el("div", {class: "plot-area", "data-partial": "1"});
    plotsHost.append(host);
    partial.plots = createPlots(host, [{label: `#${id}`, color: PALETTE[0], series: partial.series,
      joints: got.joints, coords: controlledCoordinates(job), loop: Boolean(spec.scene.loop), spec}], partial.timeline);
  }
  while (!isFinished(job.status)) {
    ctx.ready();
    await sleep(1000, ctx.signal);
    try {
      const row = await getJobBrief(id, ctx.signal);
      job = isFinished(row.status) ? await getJob(id, ctx.signal) : {...job, ...row};
      show(job);
      if (job.status === "running" && Date.now() - partial.at >= PARTIAL_EVERY_MS) await growPlots();
    } catch (e) {
      if (e.name === "AbortError") return;
      message.replaceChildren(errorBox("The job's status could not be refreshed", e));
    }
  }
  if (partial.plots) { partial.plots.destroy(); partial.plots = null; }
  ctx.busy();
  plotsHost.replaceChildren(el("p", {class: "empty loading", role: "status", text: "Loading the series…"}));
  actions.prepend(
    el("a", {id: "download-csv", class: "button", href: seriesUrl(id, "csv"), download: `ctcsim-job-${id}.csv`, text: "Download CSV"}),
    el("a", {id: "download-json", class: "button", href: seriesUrl(id, "json"), download: `ctcsim-job-${id}.json`, text: "Download JSON"}));

  const m = job.metrics || {};
  const width = plotsHost.clientWidth;
  const nind = m.nind ?? 0;
  /* the plots' series first; the heat-map's comes meanwhile and is drawn after the first paint,
     the animation's (when the plots' does not serve it) once its panel is in view */
  const heatLoad = nind >= HEAT_MIN ? loadHeatSeries(job, Math.round(width), ctx.signal) : Promise.resolve(null);
  heatLoad.catch(() => {}); /* awaited below; a rejection is reported there */
  let data;
  try {
    data = await loadPlotSeries(job, width, ctx.signal);
  } catch (e) {
    if (e.name === "AbortError") return;
    plotsHost.replaceChildren(e.status === 404 ? el("p", {class: "empty", text: "This job has no series (it stopped before it ran)."})
      : errorBox("The series could not be loaded", e));
    ctx.ready();
    return;
  }

  const timeline = createTimeline(duration);
  const ncoord = Math.max(m.nv ?? 0, m.nq ?? 0);
  let plots = null;
  const zoomProxy = {zoomIn: () => plots && plots.zoomIn(), zoomInY: () => plots && plots.zoomInY(),
    resetZoom: () => plots && plots.resetZoom()};
  /* the address, rewritten (debounced) as the cursor, the zooms and the hidden rows change */
  let saving = 0;
  function save() {
    clearTimeout(saving);
    saving = setTimeout(() => {
      if (!ctx.alive()) return;
      const p = writeState(new URLSearchParams(), {t: timeline.t, x: plots && plots.xRange(), y: state.y, hide: state.hide});
      const query = decodeURIComponent(p.toString());
      history.replaceState(null, "", `#/jobs/${id}${query ? `?${query}` : ""}`);
    }, 250);
  }
  ctx.onCleanup(() => clearTimeout(saving));
  ctx.onCleanup(() => plots && plots.destroy());
  const plotArea = el("div", {class: "plot-area"});
  const large = ncoord > MAX_PLOTTED;

  function draw(d) {
    const x = plots ? plots.xRange() : state.x;
    if (plots) plots.destroy();
    plots = createPlots(plotArea, [{label: `#${id}`, color: PALETTE[0], series: d.series,
      joints: d.joints, coords: d.coords, loop: d.loop, spec: job.spec}], timeline, {yZoom: state.y, onZoom: save});
    const coords = (d.joints || Array.from({length: ncoord}, (_, i) => i));
    /* a closing joint's controlled coordinate has a row beyond q's */
    for (const c of d.loop ? d.coords : []) if (c.row >= ncoord && !d.joints) coords.push(c.row);
    plotArea.prepend(jointToggles(plots, coords, (j) => PALETTE[j % PALETTE.length],
      (j) => (j >= ncoord ? "closing joint" : `joint ${j}`),
      {hidden: state.hide, onChange: (hidden) => { state.hide = hidden; save(); }}));
    if (x) plots.setX(x[0], x[1]);
    if (d.joints) {
      plotArea.prepend(el("p", {class: "muted", id: "plotted-note",
        text: `The plots show ${d.joints.length} of ${m.nv} coordinates: ${listText(d.joints)}.`}));
    }
    timeline.set(timeline.t, null);
  }

  /* the joint picker: which coordinates a large chain plots */
  let picker = null, pickInput = null, pickError = null;
  async function plotJoints(list) {
    ctx.busy();
    try {
      const d = await loadPlotSeries(job, plotsHost.clientWidth, ctx.signal, list);
      plotArea.replaceChildren();
      draw(d);
      pickInput.value = listText(list);
    } catch (e) {
      if (e.name === "AbortError") return;
      pickError.textContent = `The series could not be loaded: ${e.message}`;
    }
    ctx.ready();
  }
  if (large) {
    pickInput = el("input", {type: "text", id: "joint-list", name: "joints", "aria-describedby": "joint-list-hint joint-list-error",
      value: listText(data.joints), autocomplete: "off", spellcheck: "false"});
    pickError = el("span", {class: "field-error", id: "joint-list-error", "aria-live": "polite"});
    picker = el("form", {id: "joint-picker", class: "joint-picker"},
      el("label", {for: "joint-list", text: "Coordinates to plot"}), pickInput,
      el("button", {type: "submit", id: "joint-plot", text: "Plot"}),
      el("span", {class: "hint", id: "joint-list-hint", text: `indices 0–${m.nv - 1}, ranges allowed ("0-3, 17"), at most ${MAX_PLOTTED}`}),
      pickError);
    picker.addEventListener("submit", (ev) => {
      ev.preventDefault();
      const parsed = parseJointList(pickInput.value, m.nv, MAX_PLOTTED);
      pickInput.setAttribute("aria-invalid", parsed.error ? "true" : "false");
      pickError.textContent = parsed.error || "";
      if (!parsed.error) plotJoints(parsed.joints);
    });
  }
  const pickJoint = large ? (i) => {
    const now = parseJointList(pickInput.value, m.nv, MAX_PLOTTED).joints || [];
    const next = [...new Set([...now, i])].sort((a, b) => a - b).slice(-MAX_PLOTTED);
    plotJoints(next);
    plotsHost.scrollIntoView({block: "start"});
  } : null;

  plotsHost.replaceChildren(...(picker ? [picker] : []), plotArea);
  draw(data);
  const tEnd = data.series.t.length ? data.series.t[data.series.t.length - 1] : 0;
  const player = createPlayer(timeline, tEnd);
  ctx.onCleanup(() => player.destroy());
  toolbar.append(timeSlider(timeline, spec.output ? spec.output.interval : 0), player.node, zoomButtons(zoomProxy));

  const summary = jointSummary(m, data.coords, pickJoint && !data.loop ? pickJoint : null);
  if (summary) summaryHost.append(summary);
  timeline.set(Math.min(state.t, duration), null);
  timeline.subscribe(() => save());
  plotsHost.setAttribute("data-drawn", "1"); /* plots, cursor and summary: the page is usable */

  /* the heat-map after the first paint */
  await afterPaint(ctx.signal);
  let heat = null;
  try {
    heat = await heatLoad;
  } catch (e) {
    if (e.name === "AbortError") return;
    heatBox.hidden = false;
    heatBox.append(errorBox("The heat-map's series could not be loaded", e));
  }
  if (!ctx.alive()) return;
  if (heat && heat.e && heat.t.length) {
    heatBox.hidden = false;
    const labels = data.coords;
    const hm = createHeatmap(heatBox, heat, {labelOf: (i) => (labels[i] ? labels[i].label : `coordinate ${i}`),
      onPick: pickJoint && !data.loop ? pickJoint : null});
    ctx.onCleanup(() => hm.destroy());
    await afterPaint(ctx.signal);
  }

  /* the animation: at once when its panel is in view, else when it scrolls into view or on play */
  const recordsQ = ((spec.output && spec.output.channels) || ["q"]).includes("q");
  if (!recordsQ) {
    animBox.append(el("p", {class: "muted", text: "No animation: the run did not record q."}));
    ctx.ready();
    return;
  }
  let animStarted = false;
  const animNote = el("p", {class: "muted", id: "anim-waiting", role: "status",
    text: "The animation loads when this panel is in view, or on play."});
  async function showAnimation() {
    if (animStarted) return;
    animStarted = true;
    seen.disconnect();
    ctx.busy();
    animNote.textContent = "Loading the animation…";
    let anim = data.anim;
    try {
      anim = anim || await loadAnimSeries(job, animBox.clientWidth || width, ctx.signal);
    } catch (e) {
      if (e.name === "AbortError") return;
      animNote.replaceWith(errorBox("The animation's series could not be loaded", e));
      ctx.ready();
      return;
    }
    animNote.remove();
    if (anim && anim.q && anim.t.length) {
      const a = createAnimation(animBox, {spec, form: m.form, series: anim, timeline});
      ctx.onCleanup(() => a.destroy());
      timeline.set(timeline.t, null);
    } else {
      animBox.append(el("p", {class: "muted", text: "No animation: the run did not record q."}));
    }
    ctx.ready();
  }
  const seen = new IntersectionObserver((entries) => {
    if (entries.some((e) => e.isIntersecting)) showAnimation();
  });
  ctx.onCleanup(() => seen.disconnect());
  if (data.anim) { await showAnimation(); return; }
  animBox.append(animNote);
  player.node.querySelector("button#play").addEventListener("click", showAnimation);
  /* the observer's first report says whether the panel is in view now */
  const inView = await new Promise((resolve) => {
    const first = new IntersectionObserver((entries) => { first.disconnect(); resolve(entries.some((e) => e.isIntersecting)); });
    first.observe(animBox);
  });
  if (!ctx.alive()) return;
  if (inView) { await showAnimation(); return; }
  seen.observe(animBox);
  ctx.ready();
}

/* Resolves after the next frame has been painted (a frame callback, then a task). */
function afterPaint(signal) {
  return new Promise((resolve, reject) => {
    requestAnimationFrame(() => setTimeout(() => (signal && signal.aborted ?
      reject(new DOMException("left the view", "AbortError")) : resolve()), 0));
  });
}

/* "0-3, 17" for [0, 1, 2, 3, 17]. */
export function listText(joints) {
  if (!joints) return "";
  const out = [];
  for (let k = 0; k < joints.length; k++) {
    let e = k;
    while (e + 1 < joints.length && joints[e + 1] === joints[e] + 1) e++;
    out.push(e > k + 1 ? `${joints[k]}-${joints[e]}` : e === k + 1 ? `${joints[k]}, ${joints[e]}` : `${joints[k]}`);
    k = e;
  }
  return out.join(", ");
}

/* "0-3, 17" -> {joints: [0, 1, 2, 3, 17]} (sorted, distinct), or {error} saying what is wrong. */
export function parseJointList(text, n, most) {
  const set = new Set();
  const parts = String(text).split(",").map((p) => p.trim()).filter((p) => p !== "");
  if (!parts.length) return {error: "name at least one coordinate"};
  for (const p of parts) {
    const m = /^(\d+)\s*(?:-\s*(\d+))?$/.exec(p);
    if (!m) return {error: `"${p}" is not an index or a range such as 4-7`};
    const a = Number(m[1]), b = m[2] === undefined ? a : Number(m[2]);
    if (b < a) return {error: `the range ${p} runs backwards`};
    if (b >= n) return {error: `${b} is past the last coordinate, ${n - 1}`};
    for (let i = a; i <= b && set.size <= most; i++) set.add(i);
    if (set.size > most) return {error: `at most ${most} coordinates at once`};
  }
  return {joints: [...set].sort((x, y) => x - y)};
}
