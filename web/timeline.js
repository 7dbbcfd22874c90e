/*
 * timeline.js - the time cursor one view shares between its plots, its animation and the
 * slider: a value t in seconds (clamped to [0, tmax]) with subscribers, and the slider itself
 * (input#time-cursor, type range, min 0, max the duration; output#time-value shows t).
 *
 * set(t, from) tells every subscriber the new time and who moved it (a plot, "slider",
 * "play"), so a source can skip its own echo.
 */
import {el} from "./dom.js";

export function createTimeline(tmax) {
  const subs = new Set();
  let t = 0;
  return {
    tmax,
    get t() { return t; },
    set(value, from = null) {
      const v = Math.min(Math.max(Number(value) || 0, 0), tmax);
      t = v;
      for (const fn of subs) fn(v, from);
    },
    subscribe(fn) { subs.add(fn); return () => subs.delete(fn); },
  };
}

/* The slider and its read-out, bound both ways to timeline; step = the output interval. */
export function timeSlider(timeline, step) {
  const input = el("input", {id: "time-cursor", type: "range", min: "0", max: String(timeline.tmax),
    step: step > 0 ? String(step) : "any", value: "0", "aria-label": "time cursor (s)"});
  const out = el("output", {id: "time-value", for: "time-cursor", text: "0.000 s"});
  input.addEventListener("input", () => timeline.set(Number(input.value), "slider"));
  timeline.subscribe((t, from) => {
    if (from !== "slider") input.value = String(t);
    out.textContent = `${t.toFixed(3)} s`;
  });
  return el("label", {class: "time-slider"}, el("span", {text: "t"}), input, out);
}
