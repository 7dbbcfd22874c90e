/*
 * browse.js - the jobs table (#/jobs): newest first, a page at a time, filtered by status,
 * refreshed while the view is open (every 2 s while a job on the page is queued or running,
 * every 6 s otherwise) so status and progress are live.
 *
 * Rows are kept by job id and updated in place, so a refresh neither loses keyboard focus nor
 * the ticked compare boxes. Pages follow the API's cursors (GET /api/jobs?cursor=ID): a stack
 * of the cursors that led here makes "previous" possible. A row is a link to #/jobs/ID (the
 * name cell holds the real <a>; a click anywhere else on the row follows it too).
 */
import {listJobs} from "./api.js";
import {el, errorBox, fmtNum, fmtTime, isFinished} from "./dom.js";

const PAGE = 25;
const STATUSES = ["queued", "running", "done", "failed", "diverged", "cancelled"];

export async function browseView(root, ctx) {
  document.title = "Jobs - ctcsim";
  const picked = new Set(); /* job ids ticked for comparison */
  const cursors = [null];   /* cursors[i] opened page i */
  let status = ctx.params.query.get("status") || "";
  let timer = 0;
  let loads = 0; /* the latest load's number: an older reply that comes late is dropped */

  const filter = el("select", {id: "status-filter"},
    el("option", {value: "", text: "all"}),
    ...STATUSES.map((s) => el("option", {value: s, text: s})));
  filter.value = status;
  const compareBtn = el("button", {id: "compare-selected", type: "button", disabled: true,
    text: "Compare selected"});
  const tbody = el("tbody");
  const table = el("table", {id: "jobs-table"},
    el("caption", {class: "visually-hidden", text: "Jobs, newest first"}),
    el("thead", {}, el("tr", {},
      ...["compare", "id", "name", "scene", "controller", "status", "progress", "created",
        "max |e|", "wall s"].map((h) => el("th", {scope: "col", text: h})))),
    tbody);
  const prev = el("button", {id: "prev-page", type: "button", text: "← Newer"});
  const next = el("button", {id: "next-page", type: "button", text: "Older →"});
  const pageNote = el("span", {class: "muted"});
  const note = el("div", {role: "status"});

  root.append(
    el("div", {class: "view-head"},
      el("h1", {text: "Jobs"}),
      el("div", {class: "toolbar"},
        el("label", {}, "Status ", filter), compareBtn,
        el("a", {class: "button", href: "#/submit", text: "New job"}))),
    note, el("div", {class: "table-wrap"}, table),
    el("div", {class: "pager"}, prev, pageNote, next));

  function updateCompareButton() {
    compareBtn.disabled = picked.size === 0;
    compareBtn.textContent = picked.size ? `Compare selected (${picked.size})` : "Compare selected";
  }

  function fillRow(tr, job) {
    const cells = tr._cells;
    cells.name.firstChild.textContent = job.name;
    cells.scene.replaceChildren(el("span", {text: job.preset || "custom"}),
      el("span", {class: "sub", text: `${job.scene.bodies} bodies, ${job.scene.coordinates} coordinates`}));
    cells.controller.textContent = job.controller;
    cells.status.textContent = job.status;
    cells.status.className = `status status-${job.status}`;
    if (isFinished(job.status)) {
      cells.progress.textContent = `${Math.round(100 * job.progress)} %`;
    } else {
      let bar = cells.progress.querySelector("progress");
      if (!bar) {
        bar = el("progress", {max: "1", "aria-label": `job ${job.id} progress`});
        cells.progress.replaceChildren(bar);
      }
      bar.value = job.progress;
    }
    cells.created.textContent = fmtTime(job.created);
    cells.created.title = job.created || "";
    cells.emax.textContent = fmtNum(job.e_max);
    cells.wall.textContent = fmtNum(job.wall_s);
  }

  function makeRow(job) {
    const href = `#/jobs/${job.id}`;
    const box = el("input", {type: "checkbox", class: "compare-pick", "data-job-id": job.id,
      "aria-label": `compare job ${job.id}`});
    box.checked = picked.has(job.id);
    box.addEventListener("change", () => {
      if (box.checked) picked.add(job.id); else picked.delete(job.id);
      updateCompareButton();
    });
    const cells = {
      pick: el("td", {}, box),
      id: el("td", {class: "num", text: job.id}),
      name: el("td", {"data-col": "name"}, el("a", {href})),
      scene: el("td", {"data-col": "scene"}),
      controller: el("td", {"data-col": "controller"}),
      status: el("td", {"data-col": "status"}),
      progress: el("td", {"data-col": "progress", class: "num"}),
      created: el("td", {"data-col": "created"}),
      emax: el("td", {"data-col": "e_max", class: "num"}),
      wall: el("td", {"data-col": "wall_s", class: "num"}),
    };
    const tr = el("tr", {"data-job-id": job.id, class: "link-row"}, ...Object.values(cells));
    tr._cells = cells;
    tr.addEventListener("click", (ev) => {
      if (ev.target.closest("a, input, button, label")) return;
      location.hash = href;
    });
    return tr;
  }

  /* loads the current page; quiet = a background refresh (keeps data-ready, no "loading") */
  async function load(quiet) {
    clearTimeout(timer);
    if (!quiet) { ctx.busy(); note.replaceChildren(el("p", {class: "muted", text: "Loading…"})); }
    const page = cursors.length - 1;
    const mine = ++loads;
    let busyJobs = false;
    try {
      const body = await listJobs({limit: PAGE, cursor: cursors[page], status}, ctx.signal);
      if (mine !== loads) return;
      const old = new Map([...tbody.rows].map((tr) => [Number(tr.dataset.jobId), tr]));
      const rows = body.jobs.map((job) => {
        const tr = old.get(job.id) || makeRow(job);
        fillRow(tr, job);
        busyJobs ||= !isFinished(job.status);
        return tr;
      });
      tbody.replaceChildren(...rows); /* moves kept rows, drops vanished ones */
      next.disabled = body.next_cursor === null;
      next.dataset.cursor = body.next_cursor ?? "";
      prev.disabled = page === 0;
      pageNote.textContent = `page ${page + 1}`;
      note.replaceChildren();
      if (!body.jobs.length) {
        note.append(el("p", {class: "empty"}, status ? `No ${status} jobs. ` : "No jobs yet. ",
          el("a", {href: "#/submit", text: "Start one from a preset."})));
      }
    } catch (e) {
      if (e.name === "AbortError" || mine !== loads) return;
      note.replaceChildren(errorBox("The job list could not be loaded", e));
    }
    if (!ctx.alive()) return;
    ctx.ready();
    timer = setTimeout(() => load(true), busyJobs ? 2000 : 6000);
  }

  filter.addEventListener("change", () => {
    status = filter.value;
    cursors.length = 1;
    history.replaceState(null, "", status ? `#/jobs?status=${status}` : "#/jobs");
    load(false);
  });
  next.addEventListener("click", () => {
    if (next.dataset.cursor === "") return;
    cursors.push(Number(next.dataset.cursor));
    load(false);
  });
  prev.addEventListener("click", () => {
    if (cursors.length > 1) cursors.pop();
    load(false);
  });
  compareBtn.addEventListener("click", () => {
    if (picked.size) location.hash = `#/compare?ids=${[...picked].sort((a, b) => a - b).join(",")}`;
  });
  ctx.onCleanup(() => clearTimeout(timer));
  await load(false);
}
