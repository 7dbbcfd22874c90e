/*
 * app.js - the page's entry point: a hash router that mounts one view at a time in #view.
 *
 * Routes (web/README.md): "#/jobs" (also "#/" and empty) browse, "#/jobs/{id}" one job,
 * "#/compare?ids=3,5,8" compare, "#/submit?preset=NAME" (or "?job=ID") the job form,
 * "#/families" the studies and "#/families/{id}" one family. Each
 * mount gets a context: its route parameters, an AbortSignal that fires when the user leaves
 * (so late replies never write into another view), onCleanup() for timers and listeners, and
 * ready()/busy() which set and remove data-ready="1" on #view, the browser tests' signal that
 * the view's data is in and its plots are drawn.
 */
import {browseView} from "./browse.js";
import {jobView} from "./job.js";
import {compareView} from "./compare.js";
import {submitView} from "./submit.js";
import {familiesView, familyView} from "./families.js";
import {el, errorBox} from "./dom.js";

const ROUTES = [
  {pattern: /^\/?(jobs\/?)?$/, view: browseView, nav: "#/jobs"},
  {pattern: /^\/jobs\/(\d+)$/, view: jobView, nav: "#/jobs"},
  {pattern: /^\/compare\/?$/, view: compareView, nav: "#/compare"},
  {pattern: /^\/submit\/?$/, view: submitView, nav: "#/submit"},
  {pattern: /^\/families\/?$/, view: familiesView, nav: "#/families"},
  {pattern: /^\/families\/(\d+)$/, view: familyView, nav: "#/families"},
];

const root = document.getElementById("view");
let current = null; /* {controller, cleanups} of the mounted view */

function unmount() {
  if (!current) return;
  current.controller.abort();
  for (const fn of current.cleanups) {
    try { fn(); } catch (e) { console.error(e); }
  }
  current = null;
}

function route() {
  const hash = decodeURIComponent(location.hash.replace(/^#/, ""));
  const [path, query = ""] = hash.split("?");
  unmount();
  root.removeAttribute("data-ready");
  root.replaceChildren();
  window.scrollTo(0, 0);

  const match = ROUTES.find((r) => r.pattern.test(path));
  for (const a of document.querySelectorAll("nav a")) {
    if (match && a.getAttribute("href") === match.nav) a.setAttribute("aria-current", "page");
    else a.removeAttribute("aria-current");
  }
  if (!match) {
    root.append(el("h1", {text: "Not found"}),
      el("p", {}, "No view at this address. ", el("a", {href: "#/jobs", text: "Go to the jobs."})));
    root.setAttribute("data-ready", "1");
    return;
  }

  const controller = new AbortController();
  const mounted = {controller, cleanups: []};
  current = mounted;
  const ctx = {
    params: {path, id: (path.match(/^\/jobs\/(\d+)$/) || [])[1],
      familyId: (path.match(/^\/families\/(\d+)$/) || [])[1], query: new URLSearchParams(query)},
    signal: controller.signal,
    alive: () => !controller.signal.aborted,
    onCleanup: (fn) => mounted.cleanups.push(fn),
    ready: () => { if (!controller.signal.aborted) root.setAttribute("data-ready", "1"); },
    busy: () => { if (!controller.signal.aborted) root.removeAttribute("data-ready"); },
  };
  Promise.resolve()
    .then(() => match.view(root, ctx))
    .catch((e) => {
      if (e.name === "AbortError" || !ctx.alive()) return;
      console.error(e);
      root.append(errorBox("This view failed", e));
      ctx.ready();
    });
}

window.addEventListener("hashchange", route);
route();
