/*
 * submit.js - the job form (#/submit, #/submit?preset=NAME, #/submit?job=ID): start from a
 * preset or an earlier job, edit in the form or in the JSON beside it (the two kept in sync),
 * or upload a file (a job, or a robot's URDF, which becomes the job `ctcsim import` prints: a PD
 * controller moving every joint 0.2 from q = 0 by minimum jerk); validate on the server, run,
 * follow the progress, and open the job.
 *
 * The textarea (textarea#job-json) holds the job. A job started from a preset is sent as that
 * preset and a merge patch of the edits (names.js), so the server records the preset and names
 * the job after what changed; any other is sent as it stands. Form edits rewrite it;
 * typing in it redraws the form once it parses. A server error is shown next to the field
 * whose name is its JSON path (.field-error[data-field=PATH]), or in #form-error above the
 * form when no field has that name. While the job runs, progress#submit-progress follows it
 * (polled every 0.3 s); when it finishes the page goes to #/jobs/ID.
 */
import {getJob, getPreset, listPresets, postJob, validateJob} from "./api.js";
import {presetRequest} from "./names.js";
import {el, errorBox, isFinished, prettyJson, sleep} from "./dom.js";
import {jobForm} from "./jobform.js";

/* The job for a robot given as URDF text (the server converts it into bodies), as `ctcsim import`
 * makes it: named after the robot (or the file), PD with zeta 1 and tau 0.1 s, every joint moving
 * 0.2 rad or m from q = 0 by minimum jerk over 2 s, 3 s simulated. */
function robotJob(urdf, fileName) {
  const m = /<robot\b[^>]*\bname\s*=\s*"([^"]+)"/.exec(urdf);
  return {
    name: m ? m[1] : fileName.replace(/\.[^.]*$/, ""),
    scene: {urdf},
    controller: {type: "pd", zeta: 1, tau: 0.1},
    trajectory: {type: "min_jerk", from: 0, to: 0.2, start: 0, end: 2},
    duration: 3,
  };
}

export async function submitView(root, ctx) {
  document.title = "New job - ctcsim";
  let doc = null;
  /* the preset document the form started from ({preset, params, doc, name}), or null: a job
   * from it is sent as the preset and a patch (names.js) */
  let base = null;
  let presets = [];

  const presetSel = el("select", {id: "preset"}, el("option", {value: "", text: "(none: edit or paste the JSON)"}));
  const params = el("span", {class: "preset-params"});
  const file = el("input", {type: "file", id: "job-file", accept: ".json,application/json,.urdf,.xml"});
  const formError = el("div", {id: "form-error", role: "alert"});
  const fields = el("div", {class: "form-sections"});
  const validateBtn = el("button", {type: "button", id: "validate-job", text: "Validate"});
  const submitBtn = el("button", {type: "submit", id: "submit-job", class: "primary", text: "Run job"});
  const status = el("div", {id: "submit-status", role: "status"});
  const form = el("form", {id: "job-form", novalidate: true}, fields,
    el("div", {class: "buttons"}, validateBtn, submitBtn), status);
  const textarea = el("textarea", {id: "job-json", spellcheck: "false", rows: "30",
    "aria-label": "the whole job as JSON", autocomplete: "off"});
  const jsonNote = el("p", {class: "json-note", role: "status"});

  root.append(el("h1", {text: "New job"}),
    el("p", {class: "lead", text: "Start from a preset (the paper's scenes), change the controller, trajectory, disturbance or integrator, and run. The JSON on the right is what is sent; edit it for anything the form does not show."}),
    el("div", {class: "toolbar"}, el("label", {}, "Preset ", presetSel), params,
      el("label", {}, "or upload a job or a URDF file ", file)),
    formError,
    el("div", {class: "submit-grid"}, form,
      el("section", {class: "json-col"}, el("h2", {}, el("label", {for: "job-json", text: "Job JSON"})), textarea, jsonNote)));

  const formCtl = jobForm(fields, () => doc, () => { textarea.value = prettyJson(doc); clearErrors(); });

  function setDoc(d, fromText) {
    doc = d;
    if (!fromText) textarea.value = prettyJson(d);
    jsonNote.textContent = "";
    formCtl.render();
    clearErrors();
  }
  function clearErrors() {
    formError.replaceChildren();
    for (const n of root.querySelectorAll(".field-error")) n.remove();
    for (const n of root.querySelectorAll("[aria-invalid]")) { n.removeAttribute("aria-invalid"); n.removeAttribute("aria-describedby"); }
  }
  function showError(e) {
    clearErrors();
    const target = e.field ? form.querySelector(`[name="${CSS.escape(e.field)}"]`) : null;
    if (!target) {
      formError.append(el("p", {class: "error", text: e.field ? `${e.field}: ${e.message}` :
        `The job was not accepted: ${e.message}${e.code ? ` (${e.code})` : ""}`}));
      return;
    }
    const msg = el("span", {class: "field-error", "data-field": e.field, id: "field-error-msg", role: "alert", text: e.message});
    if (target.tagName === "FIELDSET") target.querySelector("legend").after(msg);
    else target.after(msg);
    target.setAttribute("aria-invalid", "true");
    target.setAttribute("aria-describedby", "field-error-msg");
    target.scrollIntoView({block: "center"});
  }
  /* the document to send: the textarea parsed, or null with the reason shown */
  function current() {
    try {
      return JSON.parse(textarea.value);
    } catch (e) {
      clearErrors();
      formError.append(el("p", {class: "error", text: `The JSON does not parse: ${e.message}`}));
      return null;
    }
  }

  async function loadPreset(name) {
    const p = presets.find((x) => x.name === name);
    const values = {};
    for (const input of params.querySelectorAll("input")) if (input.value !== "") values[input.dataset.param] = input.value;
    try {
      const d = await getPreset(name, values, ctx.signal);
      const numbers = Object.fromEntries(Object.entries(values).map(([k, v]) => [k, Number(v)]));
      base = {preset: name, params: numbers, doc: structuredClone(d), name: d.name};
      setDoc(d);
      history.replaceState(null, "", `#/submit?preset=${encodeURIComponent(name)}`);
    } catch (e) {
      if (e.name !== "AbortError") showError(e);
    }
    return p;
  }
  function showParams(name) {
    const p = presets.find((x) => x.name === name);
    params.replaceChildren(...(p ? p.params : []).map((k) => {
      const input = el("input", {type: "number", step: "1", id: `preset-param-${k}`, "data-param": k, name: k,
        placeholder: "default", class: "short"});
      input.addEventListener("change", () => loadPreset(name));
      return el("label", {}, `${k} `, input);
    }));
  }

  presetSel.addEventListener("change", () => {
    showParams(presetSel.value);
    if (presetSel.value) loadPreset(presetSel.value);
    else base = null;
  });
  let typing = 0;
  textarea.addEventListener("input", () => {
    clearTimeout(typing);
    typing = setTimeout(() => {
      try {
        const d = JSON.parse(textarea.value);
        setDoc(d, true);
      } catch (e) {
        jsonNote.textContent = `Not valid JSON yet: ${e.message}`;
      }
    }, 300);
  });
  ctx.onCleanup(() => clearTimeout(typing));
  file.addEventListener("change", async () => {
    const f = file.files[0];
    if (!f) return;
    const text = await f.text();
    presetSel.value = "";
    showParams("");
    base = null;
    if (/\.(urdf|xml)$/i.test(f.name) || text.trimStart().startsWith("<")) {
      setDoc(robotJob(text, f.name));
      return;
    }
    textarea.value = text;
    try { setDoc(JSON.parse(textarea.value), true); } catch (e) {
      clearErrors();
      formError.append(el("p", {class: "error", text: `${f.name} is not valid JSON: ${e.message}`}));
    }
  });

  validateBtn.addEventListener("click", async () => {
    const d = current();
    if (!d) return;
    status.replaceChildren(el("p", {class: "muted", text: "Validating…"}));
    try {
      const r = await validateJob(presetRequest(base, d), ctx.signal);
      clearErrors();
      status.replaceChildren(el("p", {class: "ok", text: `Valid: ${r.spec.scene.bodies.length} bodies, controller ${r.spec.controller.type}, ${r.spec.duration} s.`}));
    } catch (e) {
      if (e.name === "AbortError") return;
      status.replaceChildren();
      showError(e);
    }
  });
  form.addEventListener("submit", async (ev) => {
    ev.preventDefault();
    const d = current();
    if (!d) return;
    validateBtn.disabled = submitBtn.disabled = true;
    status.replaceChildren(el("p", {class: "muted", text: "Sending…"}));
    try {
      let job = await postJob(presetRequest(base, d), ctx.signal);
      clearErrors();
      const bar = el("progress", {id: "submit-progress", max: "1", value: String(job.progress)});
      const line = el("span");
      status.replaceChildren(el("p", {}, el("a", {href: `#/jobs/${job.id}`, text: `Job #${job.id}`}), " ", line, " ", bar));
      while (!isFinished(job.status)) {
        line.textContent = `${job.status} ${Math.round(100 * job.progress)} %`;
        bar.value = job.progress;
        await sleep(300, ctx.signal);
        job = await getJob(job.id, ctx.signal);
      }
      location.hash = `#/jobs/${job.id}`;
    } catch (e) {
      if (e.name === "AbortError") return;
      if (status.querySelector("#submit-progress")) status.append(errorBox("Lost track of the job", e));
      else { status.replaceChildren(); showError(e); }
    } finally {
      validateBtn.disabled = submitBtn.disabled = false;
    }
  });

  /* the presets, then the starting document */
  const q = ctx.params.query;
  try {
    presets = (await listPresets(ctx.signal)).presets;
    presetSel.append(...presets.map((p) => el("option", {value: p.name, text: `${p.name} — ${p.summary}`})));
    if (q.get("job")) {
      const job = await getJob(Number(q.get("job")), ctx.signal);
      setDoc(job.spec);
      jsonNote.textContent = `Started from job #${job.id}.`;
    } else {
      const name = presets.some((p) => p.name === q.get("preset")) ? q.get("preset") : "triple_pendulum_pid";
      presetSel.value = name;
      showParams(name);
      const d = await getPreset(name, {}, ctx.signal);
      base = {preset: name, params: {}, doc: structuredClone(d), name: d.name};
      setDoc(d);
      if (q.get("preset") && q.get("preset") !== name) formError.append(el("p", {class: "error", text: `No preset named "${q.get("preset")}"; showing ${name}.`}));
    }
  } catch (e) {
    if (e.name === "AbortError") return;
    formError.append(errorBox("The form could not be prepared", e));
  }
  ctx.ready();
}
