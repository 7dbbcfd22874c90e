/*
 * api.js - the HTTP API of ctcsim-server as promises (server/routes.h is the reference).
 *
 * request() sends JSON, reads JSON back and turns every failure into an ApiError carrying the
 * server's stable error code and the JSON path of the offending field ({"error": {"code",
 * "message", "field"}}), or code NETWORK when the server cannot be reached. Views pass their
 * AbortSignal so that leaving a view cancels its requests; an aborted request rejects with an
 * AbortError that views ignore.
 */

export class ApiError extends Error {
  constructor(message, status, code, field) {
    super(message);
    this.status = status; /* HTTP status, 0 when the server was not reached */
    this.code = code;     /* "INVALID_FIELD", "NOT_FOUND", ..., "NETWORK", "BAD_REPLY" */
    this.field = field;   /* JSON path such as "controller.kp", or "" */
  }
}

export async function request(path, {method = "GET", body, signal} = {}) {
  const init = {method, signal, headers: {Accept: "application/json"}};
  if (body !== undefined) {
    init.headers["Content-Type"] = "application/json";
    init.body = typeof body === "string" ? body : JSON.stringify(body);
  }
  let reply;
  try {
    reply = await fetch(path, init);
  } catch (e) {
    if (e.name === "AbortError") throw e;
    throw new ApiError(`the server cannot be reached (${e.message})`, 0, "NETWORK", "");
  }
  if (reply.status === 204) return null;
  let data;
  try {
    data = await reply.json();
  } catch (e) {
    if (e.name === "AbortError") throw e;
    throw new ApiError(`HTTP ${reply.status}: the reply is not JSON`, reply.status, "BAD_REPLY", "");
  }
  if (!reply.ok) {
    const err = (data && data.error) || {};
    throw new ApiError(err.message || `HTTP ${reply.status}`, reply.status, err.code || "HTTP",
      err.field || "");
  }
  return data;
}

/* One page of the job list: {jobs: [rows], next_cursor}; text searches the name, preset,
 * controller and tags, tag is one tag exactly. */
export function listJobs({limit = 25, cursor = null, status = "", text = "", tag = ""} = {}, signal) {
  const q = new URLSearchParams({limit: String(limit)});
  if (cursor !== null) q.set("cursor", String(cursor));
  if (status) q.set("status", status);
  if (text) q.set("q", text);
  if (tag) q.set("tag", tag);
  return request(`/api/jobs?${q}`, {signal});
}

export const getJob = (id, signal) => request(`/api/jobs/${id}`, {signal});
/* The job's row, message and queue_position, without spec and metrics: for polling. */
export const getJobBrief = (id, signal) => request(`/api/jobs/${id}?brief=1`, {signal});

/* The series as columnar JSON: {t: [...], q: [[q0...], [q1...]], ...}. The server keeps every
 * every-th sample and the last, and at most maxPoints samples (first and last included): a
 * bound on what a plot or the animation fetches, whatever every says. */
export const SERIES_MAX_POINTS = 5000;
export function getSeries(id, {channels, joints, every = 1, maxPoints = SERIES_MAX_POINTS} = {}, signal) {
  const q = new URLSearchParams({every: String(every), max_points: String(maxPoints), format: "json"});
  if (channels) q.set("channels", channels.join(","));
  if (joints) q.set("joints", joints.join(","));
  return request(`/api/jobs/${id}/series?${q}`, {signal});
}

/* The series in the compact binary form (?format=f32, api/openapi.yaml): {t: [...], q: [[...]],
 * ..., rows, reduce}, columnar as getSeries gives it, non-finite values as null. reduce:
 * "stride" (every-th sample, at most maxPoints) or "minmax" (per bucket of samples, a row at its
 * first time with each column's minimum and one at its last time with the maximum: spikes
 * survive; at most maxPoints rows). from: the first sample; partial: a running job's samples so
 * far (404/409 errors as ApiError). */
export async function getSeriesF32(id, {channels, joints, every = 1, maxPoints = SERIES_MAX_POINTS, reduce = "stride",
  from = 0, partial = false} = {}, signal) {
  const q = new URLSearchParams({every: String(every), max_points: String(maxPoints), format: "f32", reduce});
  if (from) q.set("from", String(from));
  if (partial) q.set("partial", "1");
  if (channels) q.set("channels", channels.join(","));
  if (joints) q.set("joints", joints.join(","));
  let reply;
  try {
    reply = await fetch(`/api/jobs/${id}/series?${q}`, {signal});
  } catch (e) {
    if (e.name === "AbortError") throw e;
    throw new ApiError(`the server cannot be reached (${e.message})`, 0, "NETWORK", "");
  }
  if (!reply.ok) {
    let err = {};
    try { err = (await reply.json()).error || {}; } catch (e) { if (e.name === "AbortError") throw e; }
    throw new ApiError(err.message || `HTTP ${reply.status}`, reply.status, err.code || "HTTP", err.field || "");
  }
  return decodeF32(await reply.arrayBuffer());
}

/* The f32 body as columnar arrays (t as one array). Float32Array reads the machine's byte
 * order, little-endian on every platform a browser runs on today, as the server writes. */
export function decodeF32(buf) {
  const view = new DataView(buf);
  if (buf.byteLength < 4) throw new ApiError("the f32 series is truncated", 200, "BAD_REPLY", "");
  const h = view.getUint32(0, true);
  const head = JSON.parse(new TextDecoder().decode(new Uint8Array(buf, 4, h)));
  const out = {rows: head.rows, reduce: head.reduce};
  let at = 4 + h;
  const rows = head.rows;
  for (const [name, width] of head.channels) {
    const n = rows * width;
    if (at + 4 * n > buf.byteLength) throw new ApiError("the f32 series is truncated", 200, "BAD_REPLY", "");
    const v = new Float32Array(buf, at, n);
    at += 4 * n;
    const cols = Array.from({length: width}, () => new Array(rows));
    for (let r = 0; r < rows; r++) {
      for (let c = 0; c < width; c++) {
        const x = v[r * width + c];
        cols[c][r] = Number.isFinite(x) ? x : null;
      }
    }
    out[name] = name === "t" ? cols[0] : cols;
  }
  return out;
}

export const seriesUrl = (id, format) => `/api/jobs/${id}/series?format=${format}`;
export const postJob = (doc, signal) => request("/api/jobs", {method: "POST", body: doc, signal});
export const validateJob = (doc, signal) => request("/api/validate", {method: "POST", body: doc, signal});
export const deleteJob = (id, signal) => request(`/api/jobs/${id}`, {method: "DELETE", signal});
/* Cancels a queued or running job; never deletes one (409 ALREADY_FINISHED once it has ended). */
export const cancelJob = (id, signal) => request(`/api/jobs/${id}/cancel`, {method: "POST", signal});
export const listPresets = (signal) => request("/api/presets", {signal});

export function getPreset(name, params = {}, signal) {
  const q = new URLSearchParams(params);
  const tail = q.toString() ? `?${q}` : "";
  return request(`/api/presets/${encodeURIComponent(name)}${tail}`, {signal});
}
