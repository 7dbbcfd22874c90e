/*
 * compare.js - several jobs overlaid on the same plots (#/compare?ids=3,5,8), each job in its
 * own colour (#compare-legend li[data-job-id]), coordinates told apart by dash pattern, one
 * time cursor for all. Without ids it offers the latest finished jobs to pick from.
 *
 * Jobs still queued or running are waited for (polled every 2 s); a job that cannot be loaded
 * stays in the legend with the reason, and the others are drawn.
 */
import {getJob, listJobs} from "./api.js";
import {el, errorBox, fmtNum, isFinished, sleep} from "./dom.js";
import {createTimeline, timeSlider} from "./timeline.js";
import {createPlots, jointToggles, zoomButtons, PALETTE} from "./plots.js";
import {loadPlotSeries} from "./series.js";

const go = (ids) => { location.hash = ids.length ? `#/compare?ids=${ids.join(",")}` : "#/compare"; };

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
      list.append(el("li", {}, el("label", {}, box, ` #${job.id} ${job.name} (${job.controller}, ${job.status}, max |e| ${fmtNum(job.e_max)})`)));
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

export async function compareView(root, ctx) {
  document.title = "Compare - ctcsim";
  const ids = [...new Set((ctx.params.query.get("ids") || "").split(",").map(Number)
    .filter((n) => Number.isInteger(n) && n > 0))];
  if (!ids.length) return picker(root, ctx);

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
  const host = el("div", {class: "plots compare"});
  root.append(el("h1", {text: "Compare jobs"}), legend, addForm, note, toolbar, host);

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
    e.text.replaceChildren(el("a", {href: `#/jobs/${j.id}`, text: `#${j.id} ${j.name}`}),
      ` · ${j.controller} · ${j.status}` + (isFinished(j.status) ? ` · max |e| ${fmtNum(j.e_max)}` : ` ${Math.round(100 * j.progress)} %`));
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

  const sources = [];
  await Promise.all(entries.filter((e) => e.job).map(async (e) => {
    try {
      const d = await loadPlotSeries(e.job, host.clientWidth, ctx.signal);
      e.source = {label: `#${e.id}`, color: e.color, series: d.series, joints: d.joints,
        coords: d.coords, loop: d.loop};
    } catch (err) {
      if (err.name === "AbortError") throw err;
      e.li.append(el("span", {class: "error", text: ` (no series: ${err.message})`}));
    }
  }));
  for (const e of entries) if (e.source) sources.push(e.source);
  if (!sources.length) {
    note.append(el("p", {class: "empty", text: "None of these jobs has a series to plot."}));
    ctx.ready();
    return;
  }

  const duration = Math.max(...entries.filter((e) => e.source).map((e) => e.job.spec.duration));
  const step = Math.min(...entries.filter((e) => e.source).map((e) => e.job.spec.output.interval));
  const timeline = createTimeline(duration);
  const plots = createPlots(host, sources, timeline, {compare: true});
  ctx.onCleanup(() => plots.destroy());
  /* rows of q, and beyond them the closing joints' controlled coordinates */
  const ncoord = Math.max(...entries.filter((e) => e.source).map((e) =>
    (e.source.joints ? e.source.joints.length : Math.max(e.job.metrics?.nv ?? 0, e.job.metrics?.nq ?? 0,
      ...(e.source.loop ? e.source.coords.map((c) => c.row + 1) : [])))));
  toolbar.append(timeSlider(timeline, step), zoomButtons(plots));
  host.prepend(jointToggles(plots, Array.from({length: ncoord}, (_, i) => i), () => null),
    el("p", {class: "muted small", text: "Colour: job. Coordinates 0, 1, 2, 3: solid, long dash, dotted, dash-dot. Thin dotted: desired q_d."}));
  timeline.set(0, null);
  ctx.ready();
}
