/*
 * browse.js - the jobs table (#/jobs): newest first, a page at a time, filtered by status, by a
 * search (input#job-search: a text in the name, preset, controller or a tag, the server's
 * GET /api/jobs?q=) and by a tag (a tag button in a row, or ?tag=), refreshed while the view is
 * open (every 2 s while a job on the page is queued or running, every 6 s otherwise) so status
 * and progress are live. A run that stopped early (failed, diverged, cancelled) shows how far it
 * ran ("ran 7 %", the fraction of its duration), not its last progress write.
 *
 * Columns: the compare box, id, name, tags, scene, controller, status, progress, created, the
 * final |e| (largest over the coordinates at the end), the RMS e (over the run and the
 * coordinates) and the largest |e| (for a computed torque run usually the initial error, the
 * same for every controller of a scene: the first two rank them), and the wall time. Each
 * column but the box and progress sorts the page shown (button.sort[data-key] in its th, which
 * carries aria-sort); the API pages by id, so a sort orders the rows of the page. The address
 * keeps the filter, search, tag and sort (#/jobs?status=done&q=pid&tag=sweep&sort=e_rms:asc).
 *
 * Rows are kept by job id and updated in place, so a refresh neither loses keyboard focus nor
 * the ticked compare boxes. Pages follow the API's cursors (GET /api/jobs?cursor=ID): a stack
 * of the cursors that led here makes "previous" possible. A row is a link to #/jobs/ID (the
 * name cell holds the real <a>; a click anywhere else on the row follows it too).
 */
import {listJobs} from "./api.js";
import {el, errorBox, fmtNum, fmtTime, isFinished} from "./dom.js";

const PAGE = 25;
/* the columns, and the sort key of each sortable one (a job row -> a number or a string) */
const HEADS = [["compare", "compare"], ["id", "id"], ["name", "name"], ["tags", "tags"],
  ["scene", "scene"], ["controller", "controller"], ["status", "status"], ["progress", "progress"],
  ["created", "created"], ["e_final", "final |e|"], ["e_rms", "RMS e"], ["e_max", "max |e|"],
  ["wall_s", "wall s"]];
const SORTS = {
  id: (j) => j.id, name: (j) => j.name, tags: (j) => (j.tags || []).join(" ") || null,
  scene: (j) => j.preset || "", controller: (j) => j.controller, status: (j) => j.status,
  created: (j) => j.id, e_final: (j) => j.e_final, e_rms: (j) => j.e_rms, e_max: (j) => j.e_max,
  wall_s: (j) => j.wall_s,
};
const STATUSES = ["queued", "running", "done", "failed", "diverged", "cancelled"];

export async function browseView(root, ctx) {
  document.title = "Jobs - ctcsim";
  const picked = new Set(); /* job ids ticked for comparison */
  const cursors = [null];   /* cursors[i] opened page i */
  const query = ctx.params.query;
  let status = query.get("status") || "";
  let text = query.get("q") || "";
  let tag = query.get("tag") || "";
  let sort = (() => {
    const [key, dir] = (query.get("sort") || "").split(":");
    return SORTS[key] ? {key, dir: dir === "desc" ? "desc" : "asc"} : null;
  })();
  let timer = 0;
  let loads = 0; /* the latest load's number: an older reply that comes late is dropped */

  const filter = el("select", {id: "status-filter"},
    el("option", {value: "", text: "all"}),
    ...STATUSES.map((s) => el("option", {value: s, text: s})));
  filter.value = status;
  const compareBtn = el("button", {id: "compare-selected", type: "button", disabled: true,
    text: "Compare selected"});
  const search = el("input", {type: "search", id: "job-search", value: text, placeholder: "name, preset, controller, tag",
    "aria-label": "search the jobs by name, preset, controller or tag"});
  const searchForm = el("form", {class: "inline search", role: "search"}, search,
    el("button", {type: "submit", text: "Search"}));
  const tagNote = el("span", {class: "tag-filter"});
  const tbody = el("tbody");
  const heads = HEADS.map(([key, label]) => {
    if (!SORTS[key]) return el("th", {scope: "col", "data-col": key, text: label});
    const b = el("button", {type: "button", class: "sort", "data-key": key, text: label,
      title: `sort the page by ${label}`});
    b.addEventListener("click", () => {
      sort = {key, dir: sort && sort.key === key && sort.dir === "asc" ? "desc" : "asc"};
      order();
      remember();
    });
    return el("th", {scope: "col", "data-key": key}, b);
  });
  const table = el("table", {id: "jobs-table"},
    el("caption", {class: "visually-hidden", text: "Jobs, newest first unless sorted"}),
    el("thead", {}, el("tr", {}, ...heads)),
    tbody);
  const prev = el("button", {id: "prev-page", type: "button", text: "← Newer"});
  const next = el("button", {id: "next-page", type: "button", text: "Older →"});
  const pageNote = el("span", {class: "muted"});
  const note = el("div", {role: "status"});

  root.append(
    el("div", {class: "view-head"},
      el("h1", {text: "Jobs"}),
      el("div", {class: "toolbar"},
        searchForm, el("label", {}, "Status ", filter), tagNote, compareBtn,
        el("a", {class: "button", href: "#/submit", text: "New job"}))),
    note, el("div", {class: "table-wrap"}, table),
    el("div", {class: "pager"}, prev, pageNote, next));

  function updateCompareButton() {
    compareBtn.disabled = picked.size === 0;
    compareBtn.textContent = picked.size ? `Compare selected (${picked.size})` : "Compare selected";
  }

  /* the address of the view as it is filtered and sorted */
  function remember() {
    const p = new URLSearchParams();
    if (status) p.set("status", status);
    if (text) p.set("q", text);
    if (tag) p.set("tag", tag);
    if (sort) p.set("sort", `${sort.key}:${sort.dir}`);
    history.replaceState(null, "", p.toString() ? `#/jobs?${p}` : "#/jobs");
  }
  /* the rows in the sort's order (the server's, newest first, without one) */
  function order() {
    for (const th of heads) {
      const key = th.dataset.key;
      if (!key) continue;
      const on = sort && sort.key === key;
      th.setAttribute("aria-sort", on ? (sort.dir === "asc" ? "ascending" : "descending") : "none");
      th.firstChild.textContent = HEADS.find((h) => h[0] === key)[1] + (on ? (sort.dir === "asc" ? " ▲" : " ▼") : "");
    }
    const rows = [...tbody.rows];
    const by = sort ? SORTS[sort.key] : (j) => -j.id;
    const sign = sort && sort.dir === "desc" ? -1 : 1;
    rows.sort((a, b) => {
      const va = by(a._job), vb = by(b._job);
      const na = va === null || va === undefined || Number.isNaN(va), nb = vb === null || vb === undefined || Number.isNaN(vb);
      if (na || nb) return na && nb ? 0 : na ? 1 : -1; /* no value: last either way */
      return sign * (typeof va === "string" ? va.localeCompare(vb) : va - vb);
    });
    if (rows.some((tr, i) => tr !== tbody.rows[i])) tbody.append(...rows);
  }
  function showTag() {
    tagNote.replaceChildren();
    if (!tag) return;
    const clear = el("button", {type: "button", class: "icon", id: "clear-tag", "aria-label": `stop filtering by the tag ${tag}`, text: "×"});
    clear.addEventListener("click", () => { tag = ""; showTag(); cursors.length = 1; remember(); load(false); });
    tagNote.append("tag ", el("span", {class: "tag", text: tag}), clear);
  }
  function pickTag(t) {
    tag = t;
    showTag();
    cursors.length = 1;
    remember();
    load(false);
  }

  /* A finished job's progress cell: "100 %" for a done one; for a run that stopped early, how
     far it ran ("ran 7 %": the worker records the fraction of the duration it reached) */
  function stoppedText(job) {
    return job.status === "done" ? `${Math.round(100 * job.progress)} %` : `ran ${Math.floor(100 * job.progress)} %`;
  }

  function fillRow(tr, job) {
    const cells = tr._cells;
    tr._job = job;
    cells.name.firstChild.textContent = job.name;
    const tags = Array.isArray(job.tags) ? job.tags : [];
    if (cells.tags.dataset.tags !== JSON.stringify(tags)) {
      cells.tags.dataset.tags = JSON.stringify(tags);
      cells.tags.replaceChildren(...tags.map((t) => {
        const b = el("button", {type: "button", class: "tag", "data-tag": t, text: t, title: `only the jobs tagged ${t}`});
        b.addEventListener("click", () => pickTag(t));
        return b;
      }));
    }
    cells.scene.replaceChildren(el("span", {text: job.preset || "custom"}),
      el("span", {class: "sub", text: `${job.scene.bodies} bodies, ${job.scene.coordinates} coordinates`}));
    cells.controller.textContent = job.controller;
    cells.status.textContent = job.status;
    cells.status.className = `status status-${job.status}`;
    if (isFinished(job.status)) {
      cells.progress.textContent = stoppedText(job);
      cells.progress.title = job.status === "done" ? "" : `${job.status}: it ran ${Math.floor(100 * job.progress)} % of its duration`;
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
    cells.efinal.textContent = fmtNum(job.e_final);
    cells.erms.textContent = fmtNum(job.e_rms);
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
      tags: el("td", {"data-col": "tags"}),
      scene: el("td", {"data-col": "scene"}),
      controller: el("td", {"data-col": "controller"}),
      status: el("td", {"data-col": "status"}),
      progress: el("td", {"data-col": "progress", class: "num"}),
      created: el("td", {"data-col": "created"}),
      efinal: el("td", {"data-col": "e_final", class: "num"}),
      erms: el("td", {"data-col": "e_rms", class: "num"}),
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
      const body = await listJobs({limit: PAGE, cursor: cursors[page], status, text, tag}, ctx.signal);
      if (mine !== loads) return;
      const old = new Map([...tbody.rows].map((tr) => [Number(tr.dataset.jobId), tr]));
      const rows = body.jobs.map((job) => {
        const tr = old.get(job.id) || makeRow(job);
        fillRow(tr, job);
        busyJobs ||= !isFinished(job.status);
        return tr;
      });
      tbody.replaceChildren(...rows); /* moves kept rows, drops vanished ones */
      order();
      next.disabled = body.next_cursor === null;
      next.dataset.cursor = body.next_cursor ?? "";
      prev.disabled = page === 0;
      pageNote.textContent = `page ${page + 1}`;
      note.replaceChildren();
      if (!body.jobs.length) {
        note.append(el("p", {class: "empty"}, text || tag ? "No job matches. " : status ? `No ${status} jobs. ` : "No jobs yet. ",
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
    remember();
    load(false);
  });
  searchForm.addEventListener("submit", (ev) => {
    ev.preventDefault();
    text = search.value.trim();
    cursors.length = 1;
    remember();
    load(false);
  });
  showTag();
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
