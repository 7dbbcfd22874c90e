/*
 * dom.js - small helpers shared by the views: building elements, formatting numbers and times,
 * and showing an error where the user sees it.
 *
 * Every string that comes from the server goes into the page through textContent or an
 * attribute (el() below), never as markup, so a job named "<b>" shows as typed. Numbers are
 * shown with four significant digits, very small or large ones in exponent form; null (a value
 * the server could not compute, or a non-finite one) shows as a dash.
 */

/* el("a", {href: "#/jobs", class: "x", text: "Jobs", on: {click: f}}, child, ...) -> element.
 * Attributes with value null, undefined or false are left out; true sets an empty attribute. */
export function el(tag, attrs = {}, ...children) {
  const node = document.createElement(tag);
  for (const [key, value] of Object.entries(attrs)) {
    if (value === null || value === undefined || value === false) continue;
    if (key === "text") node.textContent = String(value);
    else if (key === "class") node.className = value;
    else if (key === "on") for (const [type, fn] of Object.entries(value)) node.addEventListener(type, fn);
    else node.setAttribute(key, value === true ? "" : String(value));
  }
  for (const child of children) {
    if (child === null || child === undefined || child === false) continue;
    node.append(child instanceof Node ? child : String(child));
  }
  return node;
}

/* A number for people: "0.1312", "2.618", "1.5e-07", "12345"; null and NaN as "–". */
export function fmtNum(x) {
  if (x === null || x === undefined || typeof x !== "number" || !Number.isFinite(x)) return "–";
  if (Number.isInteger(x) && Math.abs(x) < 1e9) return String(x);
  const a = Math.abs(x);
  if (a !== 0 && (a < 1e-3 || a >= 1e6)) return x.toExponential(2);
  return String(Number(x.toPrecision(4)));
}

/* A list of numbers, comma separated (null -> "–"). */
export function fmtList(xs) {
  return Array.isArray(xs) ? xs.map(fmtNum).join(", ") : fmtNum(xs);
}

/* An ISO 8601 UTC time as local "YYYY-MM-DD HH:MM:SS"; null as "–". */
export function fmtTime(iso) {
  if (!iso) return "–";
  const d = new Date(iso);
  if (Number.isNaN(d.getTime())) return String(iso);
  const p = (n) => String(n).padStart(2, "0");
  return `${d.getFullYear()}-${p(d.getMonth() + 1)}-${p(d.getDate())} ` +
    `${p(d.getHours())}:${p(d.getMinutes())}:${p(d.getSeconds())}`;
}

/* A visible error paragraph (role alert) for a failed request: "prefix: message (CODE)". */
export function errorBox(prefix, err) {
  const code = err && err.code ? ` (${err.code})` : "";
  return el("p", {class: "error", role: "alert", text: `${prefix}: ${err.message}${code}`});
}

/* JSON indented by 2, arrays without objects or arrays inside on one line ("end": [0, -1, 0]).
 * Only the line breaks JSON.stringify adds are touched (a string never holds a raw newline). */
export function prettyJson(value) {
  return JSON.stringify(value, null, 2).replace(/\[[^[\]{}]*\]/g,
    (m) => m.replace(/\[\n\s*/, "[").replace(/\n\s*\]$/, "]").replace(/,\n\s*/g, ", "));
}

/* Statuses after which a job no longer changes. */
export function isFinished(status) {
  return status !== "queued" && status !== "running";
}

/* Resolves after ms, or rejects with an AbortError when signal fires first. */
export function sleep(ms, signal) {
  return new Promise((resolve, reject) => {
    const timer = setTimeout(resolve, ms);
    signal.addEventListener("abort", () => {
      clearTimeout(timer);
      reject(new DOMException("view left", "AbortError"));
    }, {once: true});
  });
}
