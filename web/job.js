/*
 * job.js - one job (#/jobs/{id}): status and progress while it is queued or running (polled
 * every second), then its plots, animation, metrics, normalised spec and downloads.
 *
 * The view is ready (data-ready) once the job is shown: at once for a queued or running job
 * (status, progress, spec), and again after the plots are drawn when it finishes. The time
 * cursor (input#time-cursor), the player and the joint toggles sit in a toolbar that stays
 * at the top while the plots scroll; the animation, metrics and spec are beside the plots.
 * A finished job's status is shown with how its run ended when that says more ("failed
 * (singular)": a closed chain whose independent joints could no longer drive it).
 */
import {getJob, deleteJob, seriesUrl} from "./api.js";
import {el, errorBox, fmtList, fmtNum, fmtTime, isFinished, prettyJson, sleep} from "./dom.js";
import {createTimeline, timeSlider} from "./timeline.js";
import {createPlots, jointToggles, zoomButtons, PALETTE} from "./plots.js";
import {createAnimation, createPlayer} from "./animate.js";
import {loadPlotSeries} from "./series.js";

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
  if (m.e_max) {
    add(loop ? "max |e| per independent coordinate" : "max |e| per joint", fmtList(m.e_max));
    add("RMS e", fmtList(m.e_rms));
    add("final e", fmtList(m.e_final));
  }
  if (m.tau_peak) {
    add("actuator peak |τ|", fmtList(m.tau_peak));
    add("actuator RMS τ", fmtList(m.tau_rms));
  }
  if (m.sat_fraction) add("fraction of samples at the torque limit", fmtList(m.sat_fraction));
  if (loop) {
    add("loop residual max", `${fmtNum(loop.residual_max)} (position), ${fmtNum(loop.velocity_residual_max)} (velocity)`);
    add("loop condition max", fmtNum(loop.cond_max));
    add("projections onto the loop", String(loop.projections));
    const init = loop.initial || {};
    add("initial correction", `${init.iterations ?? "–"} Newton iterations, |dq| ≤ ${fmtNum(init.dq_max)}, ` +
      `|dv| ≤ ${fmtNum(init.dv_max)}, residual ${fmtNum(init.residual_before)} → ${fmtNum(init.residual_after)}`);
  }
  if (m.errdyn_dev !== null) add("deviation from the exact error dynamics", fmtNum(m.errdyn_dev));
  if (m.energy_drift !== null) add("relative energy drift", fmtNum(m.energy_drift));
  add("integrator error estimate", fmtNum(m.err_estimate));
  add("steps", `${m.steps} (${m.rejected} rejected), ${m.rhs_evals} evaluations`);
  add("wall time", `${fmtNum(m.wall_s)} s (CPU ${fmtNum(m.cpu_s)} s, ${fmtNum(m.us_per_eval)} µs per evaluation)`);
  if (m.diverged_joint !== null) add("diverged at joint", String(m.diverged_joint));
  if (m.gains) {
    const text = m.gains.map((g) => Object.entries(g).map(([k, v]) => `${k} ${fmtNum(v)}`).join(", "));
    add("gains", text.every((s) => s === text[0]) ? `every joint: ${text[0]}` :
      text.map((s, i) => `${i}: ${s}`).join("; "));
  }
  return dl;
}

export async function jobView(root, ctx) {
  const id = Number(ctx.params.id);
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

  /* header: name, what it is, status, actions */
  const statusEl = el("span", {id: "job-status"});
  const progress = el("progress", {id: "job-progress", max: "1", "aria-label": "job progress"});
  const percent = el("span", {class: "muted"});
  const message = el("p", {class: "message", role: "status"});
  const actions = el("div", {class: "actions"});
  const remove = el("button", {type: "button", class: "danger"});
  const meta = el("p", {class: "meta"});
  root.append(el("section", {class: "job-head"},
    el("h1", {text: job.name}), meta,
    el("p", {class: "status-line"}, "Status ", statusEl, " ", progress, " ", percent),
    message, actions));
  const metricsBox = el("section", {class: "panel"}, el("h2", {text: "Metrics"}));
  const specBox = el("section", {class: "panel"}, el("h2", {text: "Normalised job"}),
    el("pre", {id: "spec", tabindex: "0", text: prettyJson(job.spec)}));
  const toolbar = el("div", {class: "sticky-toolbar"});
  const plotsHost = el("div", {class: "plots"});
  const animBox = el("section", {class: "panel anim"}, el("h2", {text: "Animation"}));
  root.append(toolbar, el("div", {class: "job-grid"}, plotsHost,
    el("aside", {class: "side"}, animBox, metricsBox, specBox)));

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
    percent.textContent = `${Math.round(100 * j.progress)} %`;
    message.textContent = j.message || "";
    remove.textContent = running ? "Cancel job" : "Delete job";
    metricsBox.querySelector("dl")?.remove();
    metricsBox.append(metricsList(j.metrics));
  }
  remove.addEventListener("click", async () => {
    if (!confirm(`${remove.textContent} ${id}?`)) return;
    try {
      await deleteJob(id, ctx.signal);
      if (isFinished(job.status)) location.hash = "#/jobs";
    } catch (e) {
      if (e.name !== "AbortError") message.replaceChildren(errorBox("Not done", e));
    }
  });
  actions.append(
    el("a", {class: "button", href: `#/compare?ids=${id}`, text: "Compare…"}),
    el("a", {class: "button", href: `#/submit?job=${id}`, text: "Edit as a new job"}), remove);
  show(job);

  /* wait for the end */
  if (!isFinished(job.status)) plotsHost.append(el("p", {class: "empty", text: "The plots and the animation appear when the job has finished."}));
  while (!isFinished(job.status)) {
    ctx.ready();
    await sleep(1000, ctx.signal);
    try {
      job = await getJob(id, ctx.signal);
      show(job);
    } catch (e) {
      if (e.name === "AbortError") return;
      message.replaceChildren(errorBox("The job's status could not be refreshed", e));
    }
  }
  ctx.busy();
  plotsHost.replaceChildren();
  actions.prepend(
    el("a", {id: "download-csv", class: "button", href: seriesUrl(id, "csv"), download: `ctcsim-job-${id}.csv`, text: "Download CSV"}),
    el("a", {id: "download-json", class: "button", href: seriesUrl(id, "json"), download: `ctcsim-job-${id}.json`, text: "Download JSON"}));

  let data;
  try {
    data = await loadPlotSeries(job, plotsHost.clientWidth, ctx.signal);
  } catch (e) {
    if (e.name === "AbortError") return;
    plotsHost.append(e.status === 404 ? el("p", {class: "empty", text: "This job has no series (it stopped before it ran)."})
      : errorBox("The series could not be loaded", e));
    ctx.ready();
    return;
  }

  const m = job.metrics || {};
  const timeline = createTimeline(job.spec.duration);
  const plots = createPlots(plotsHost, [{label: `#${id}`, color: PALETTE[0], series: data.series,
    joints: data.joints, coords: data.coords, loop: data.loop, spec: job.spec}], timeline);
  ctx.onCleanup(() => plots.destroy());
  const ncoord = Math.max(m.nv ?? 0, m.nq ?? 0);
  const coords = (data.joints || Array.from({length: ncoord}, (_, i) => i));
  /* a closing joint's controlled coordinate has a row beyond q's */
  for (const c of data.loop ? data.coords : []) if (c.row >= ncoord && !data.joints) coords.push(c.row);
  const tEnd = data.series.t.length ? data.series.t[data.series.t.length - 1] : 0;
  const player = createPlayer(timeline, tEnd);
  ctx.onCleanup(() => player.destroy());
  toolbar.append(timeSlider(timeline, job.spec.output ? job.spec.output.interval : 0), player.node,
    zoomButtons(plots));
  plotsHost.prepend(jointToggles(plots, coords, (j) => PALETTE[j % PALETTE.length],
    (j) => (j >= ncoord ? "closing joint" : `joint ${j}`)));
  if (data.joints) {
    plotsHost.prepend(el("p", {class: "muted", text: `The plots show the first ${data.joints.length} of ${m.nv} coordinates.`}));
  }
  if (data.anim.q && data.anim.t.length) {
    const anim = createAnimation(animBox, {spec: job.spec, form: m.form, series: data.anim, timeline});
    ctx.onCleanup(() => anim.destroy());
  } else {
    animBox.append(el("p", {class: "muted", text: "No animation: the run did not record q."}));
  }
  timeline.set(0, null);
  ctx.ready();
}
