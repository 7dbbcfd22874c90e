/*
 * names.js - what the form sends for a job edited from a preset: the preset's name and its
 * parameters, and a JSON merge patch (RFC 7386) of the edits against the preset's document, so
 * that the server knows the preset (the list shows it, not "custom") and names the job after
 * what the edit changed ("triple_pendulum_pid, kp = 400": server/job_name.h). The naming is
 * done on the server, from the two normalised documents, so a job posted through the API gets
 * the same name as one from the page.
 *
 * The patch follows the server's merge (server/job_json.h): objects merge key by key, null
 * removes a key, arrays and scalars replace, and an object whose "type" or "method" changes is
 * replaced whole, so it is sent whole. The name is left out of the patch while it is the one the
 * form started with, so that the server names the job; a name the user typed is sent.
 */

const isObject = (v) => v !== null && typeof v === "object" && !Array.isArray(v);
const same = (a, b) => JSON.stringify(a) === JSON.stringify(b);

/* The merge patch that turns a into b. */
export function mergeDiff(a, b) {
  if (!isObject(a) || !isObject(b)) return b;
  if ((("type" in b) && a.type !== b.type) || (("method" in b) && a.method !== b.method)) return b;
  const patch = {};
  for (const [k, v] of Object.entries(b)) {
    if (!(k in a)) patch[k] = v;
    else if (!same(a[k], v)) patch[k] = isObject(a[k]) && isObject(v) ? mergeDiff(a[k], v) : v;
  }
  for (const k of Object.keys(a)) if (!(k in b)) patch[k] = null;
  return patch;
}

/* The request for doc: {preset, PARAMS..., PATCH...} when base ({preset, params, doc, name}:
 * the preset document the form started from, its parameters and the name it showed) is given,
 * else doc itself. */
export function presetRequest(base, doc) {
  if (!base || !isObject(doc)) return doc;
  const patch = mergeDiff(base.doc, doc);
  if (doc.name === base.name) delete patch.name;
  return {preset: base.preset, ...base.params, ...patch};
}
