/*
 * series.js - fetching a finished job's series for the plots and the animation.
 *
 * The server decimates (every=N keeps every N-th sample and always the last), so a long run
 * costs no more than the plot can show: N = ceil(samples / (2 * plot width in px)). Chains with
 * more than MAX_PLOTTED coordinates plot the first MAX_PLOTTED (joints=0,1,...); the animation
 * then fetches q and q_des for all of them in a second request.
 */
import {getSeries} from "./api.js";
import {decimation} from "./plots.js";

export const MAX_PLOTTED = 24;
const WANTED = ["q", "q_des", "e", "tau", "w", "energy"];

/* -> {series (for the plots), joints (coordinate index of each plotted row, or null = all),
 *     anim (series with t, q, q_des of every coordinate), every} */
export async function loadPlotSeries(job, widthPx, signal) {
  const m = job.metrics || {};
  const recorded = (job.spec.output && job.spec.output.channels) || WANTED;
  const channels = WANTED.filter((c) => recorded.includes(c));
  const every = decimation(m.samples || 1, widthPx);
  const nv = m.nv ?? job.scene.coordinates;
  const joints = nv > MAX_PLOTTED ? Array.from({length: MAX_PLOTTED}, (_, i) => i) : null;
  const series = await getSeries(job.id, {channels, joints, every}, signal);
  let anim = series;
  if (joints && channels.includes("q")) {
    anim = await getSeries(job.id, {channels: channels.filter((c) => c === "q" || c === "q_des"), every}, signal);
  }
  return {series, joints, anim, every};
}
