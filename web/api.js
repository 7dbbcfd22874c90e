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

export const seriesUrl = (id, format) => `/api/jobs/${id}/series?format=${format}`;
export const postJob = (doc, signal) => request("/api/jobs", {method: "POST", body: doc, signal});
export const validateJob = (doc, signal) => request("/api/validate", {method: "POST", body: doc, signal});
export const deleteJob = (id, signal) => request(`/api/jobs/${id}`, {method: "DELETE", signal});
export const listPresets = (signal) => request("/api/presets", {signal});

export function getPreset(name, params = {}, signal) {
  const q = new URLSearchParams(params);
  const tail = q.toString() ? `?${q}` : "";
  return request(`/api/presets/${encodeURIComponent(name)}${tail}`, {signal});
}
