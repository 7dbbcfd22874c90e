/*
 * viewstate.js - a plot view's state in its address, shared by the job view (#/jobs/{id}?...)
 * and compare (#/compare?ids=...&...): the time cursor t (s), the time zoom x=a,b, each plot's
 * value zoom y=PLOT:lo:hi~... (PLOT a channel, or "e.2" for a panel of the paper's layout), the
 * hidden coordinates hide=0,2, log=1, layout=paper and a table's sort=KEY:asc|desc. Values that
 * do not parse, or an empty or reversed range, are dropped, so a mangled link opens the view
 * unzoomed rather than failing. Views rewrite their address in place (history.replaceState),
 * so Back leaves the view rather than undoing a zoom.
 */

/* The state in the query q (URLSearchParams): {t, x ([a, b] or null), y ({PLOT: [lo, hi]}),
 * hide (rows), log, layout ("channels" | "paper"), sort ({key, dir} or null)}. */
export function readState(q) {
  const nums = (s) => (s || "").split(",").filter((x) => x !== "").map(Number).filter(Number.isFinite);
  const x = nums(q.get("x"));
  const y = {};
  for (const part of (q.get("y") || "").split("~")) {
    const [id, lo, hi] = part.split(":");
    if (id && Number.isFinite(Number(lo)) && Number.isFinite(Number(hi)) && Number(hi) > Number(lo)) y[id] = [Number(lo), Number(hi)];
  }
  const [key, dir] = (q.get("sort") || "").split(":");
  const t = Number(q.get("t"));
  return {
    t: Number.isFinite(t) && t > 0 ? t : 0,
    x: x.length === 2 && x[1] > x[0] ? x : null, y,
    hide: nums(q.get("hide")).filter((j) => Number.isInteger(j) && j >= 0),
    log: q.get("log") === "1", layout: q.get("layout") === "paper" ? "paper" : "channels",
    sort: key ? {key, dir: dir === "desc" ? "desc" : "asc"} : null,
  };
}

/* Sets p's (URLSearchParams) t, x, y and hide from the time t, the time zoom x (or null), the
 * value zooms y and the hidden rows hide; the defaults are left out. Returns p. */
export function writeState(p, {t, x, y, hide}) {
  if (t > 0) p.set("t", String(Math.round(t * 1e6) / 1e6));
  if (x) p.set("x", x.map((v) => Number(v.toPrecision(8))).join(","));
  const ys = Object.entries(y || {}).map(([id, [lo, hi]]) => `${id}:${Number(lo.toPrecision(6))}:${Number(hi.toPrecision(6))}`);
  if (ys.length) p.set("y", ys.join("~"));
  if (hide && hide.length) p.set("hide", hide.join(","));
  return p;
}
