/*
 * jobform.js - the job form: fields for the parts of a job students change (name, duration,
 * output interval, controller and gains, trajectory, disturbance, integrator, each body's
 * parent) drawn from a job document and writing back into it.
 *
 * Every control's name is the JSON path it edits ("controller.kp", "trajectory[1].period"),
 * the same path the server names in its errors, so an error can be put next to its field; the
 * fieldsets are named too ("controller", "trajectory[1]") for errors about a whole object.
 * Choosing another controller type, trajectory or disturbance type or integrator method
 * replaces that object with the new type's defaults (as the server's preset overrides do) and
 * redraws the form; other fields change one key. The document is the truth: anything the form
 * does not show (the bodies' other keys, the loop, per-joint gains, limits) is kept as it is.
 * The trajectory and the disturbance have an entry per controlled coordinate: every coordinate
 * of an open chain, the independent ones of a closed chain (scene.loop), the closing joint's
 * last. A body's parent is shown as the format reads it (kinematics.js chainParents: the previous
 * body when none is given) and written as an index. The lab plant (server/job_json.h "plant")
 * is shown when it is one object for every coordinate: its torque limit, friction and sensor
 * noise, beside the controller's sample period and delay; an empty field removes its key, so
 * every term stays off unless given. A plant of one object per coordinate is kept as it is.
 */
import {el} from "./dom.js";
import {JOINT_NV as NV} from "./joints.js";
import {chainParents} from "./kinematics.js";

export const CONTROLLERS = {none: {}, pd: {kp: 100, kv: 20}, pid: {kp: 100, kv: 20, ki: 250},
  poles: {poles: [-2, -2.1, -2.2]}, lqr: {Q: [1, 1, 1], lambda: 0.01},
  joint_pd: {kp: 100, kv: 20}, pd_gravity: {kp: 100, kv: 20}, feedforward: {kp: 100, kv: 20}};
/* the baselines: their PD gives forces, in N m/rad and N m s/rad (ctrl.h ctc_ctrl_force) */
const BASELINES = new Set(["joint_pd", "pd_gravity", "feedforward"]);
export const TRAJECTORIES = {constant: {value: 0}, sine: {amplitude: 0.6, period: 1.5, phase: 0, offset: 0},
  cosine: {amplitude: 0.6, period: 1.5, phase: 0, offset: 0}, polynomial: {coefficients: [0, 0.1]},
  min_jerk: {from: 0, to: 1, start: 0, end: 1},
  spline: {times: [0, 1, 2], values: [0, 1, 0], boundary: "clamped"}};
export const DISTURBANCES = {none: {}, constant: {value: 0.2}, sine: {amplitude: 0.2, period: 1, phase: 0, offset: 0},
  step: {value: 0.2, time: 1}};
export const INTEGRATORS = {dopri5: {rtol: 1e-8, atol: 1e-10}, bdf: {rtol: 1e-8, atol: 1e-10}, rk4: {step: 0.001}};
/* bodies up to which the form shows a parent selector per body (each lists the bodies before
 * it: quadratic in the count); longer scenes edit their parents in the JSON */
export const MAX_PARENT_FIELDS = 64;
const LISTS = new Set(["coefficients", "times", "values"]);
const HINTS = {kp: "K_p, 1/s²", kv: "K_v, 1/s", ki: "K_i, 1/s³", zeta: "damping ratio ζ", tau: "time constant τ, s",
  period: "s", phase: "rad", amplitude: "rad or m", start: "s", end: "s", time: "s", step: "s",
  rtol: "relative tolerance", atol: "absolute tolerance", max_step: "s (0: no limit)"};
/* the plant's keys the form shows (server/job_json.h "plant"), with their labels and units */
export const PLANT_FIELDS = [["torque_limit", "torque limit", "±N m (N), clips the actuator; empty: none"],
  ["viscous", "viscous friction", "N m s/rad"], ["coulomb", "Coulomb friction", "N m"],
  ["coulomb_velocity", "Coulomb velocity", "rad/s, its regularisation"],
  ["noise_q", "position noise", "rad, std. dev.; needs a sample period"],
  ["noise_v", "rate noise", "rad/s, std. dev.; needs a sample period"]];

/* "a.b[2].c" -> ["a", "b", 2, "c"] */
const tokens = (path) => path.split(/\.|(?=\[)/).map((t) => (t.startsWith("[") ? Number(t.slice(1, -1)) : t));

export function getPath(doc, path) {
  let v = doc;
  for (const t of tokens(path)) { if (v === null || typeof v !== "object") return undefined; v = v[t]; }
  return v;
}

/* Sets doc at path (creating objects on the way); undefined deletes the key. */
export function setPath(doc, path, value) {
  const ts = tokens(path);
  let o = doc;
  for (const t of ts.slice(0, -1)) {
    if (o[t] === null || typeof o[t] !== "object") o[t] = {};
    o = o[t];
  }
  const last = ts[ts.length - 1];
  if (value === undefined) delete o[last]; else o[last] = value;
}

/* text <-> value for the non-numeric fields; a token that is no number is kept as text so
 * the server names the mistake */
const num = (s) => (s.trim() === "" || Number.isNaN(Number(s)) ? s.trim() : Number(s));
const parseList = (s) => (s.trim() === "" ? undefined : s.split(/[,\s]+/).filter(Boolean).map(num));
const showList = (v) => (Array.isArray(v) ? v.join(", ") : v ?? "");
function parsePoles(s) {
  if (s.trim() === "") return undefined;
  return s.split(",").map((p) => {
    const m = p.replace(/\s+/g, "").match(/^([-+]?[\d.]+(?:e[-+]?\d+)?)([-+][\d.]*)i$/i);
    if (!m) return num(p);
    const im = m[2] === "+" || m[2] === "-" ? `${m[2]}1` : m[2];
    return {re: Number(m[1]), im: Number(im)};
  });
}
const showPoles = (v) => (Array.isArray(v) ? v.map((p) => (p && typeof p === "object" ?
  `${p.re}${p.im < 0 ? "-" : "+"}${Math.abs(p.im)}i` : p)).join(", ") : v ?? "");
function parseQ(s) {
  if (s.trim() === "") return undefined;
  const rows = s.split(";").map(parseList).filter(Boolean);
  return rows.length === 1 ? rows[0] : rows;
}
const showQ = (v) => (Array.isArray(v) && Array.isArray(v[0]) ? v.map((r) => r.join(", ")).join("; ") : showList(v));

/* The names of the controlled coordinates of doc's scene, one per coordinate ("" when its body
 * has no name): every coordinate of an open chain, the independent ones of a closed chain. */
function controlledNames(doc) {
  const bodies = doc.scene && Array.isArray(doc.scene.bodies) ? doc.scene.bodies : [];
  const loop = doc.scene && doc.scene.loop;
  const joints = bodies.map((b) => ({joint: b?.joint, name: b?.name || "", independent: !loop || b?.joint?.independent !== false}));
  if (loop && typeof loop === "object") joints.push({joint: loop.joint, name: "closing joint", independent: loop.joint?.independent === true});
  return joints.flatMap((j) => (j.independent ? Array(NV[j.joint?.type] ?? 0).fill(j.name) : []));
}

/* The number of controlled coordinates of doc's scene, or 0 when it has no bodies. */
function coordinates(doc) {
  return controlledNames(doc).length;
}

/* Binds a form to a document: render() draws the fields of getDoc(); edits change the
 * document in place and call edited(). */
export function jobForm(host, getDoc, edited) {
  const controls = new WeakMap(); /* control -> {parse, apply} */

  function register(control, path, parse, apply) {
    controls.set(control, {path, parse, apply});
    return control;
  }
  function label(text, control, hint) {
    return el("label", {class: "field"}, el("span", {class: "label", text}), control,
      hint ? el("small", {class: "hint", text: hint}) : null);
  }
  function number(doc, path, text, hint) {
    const v = getPath(doc, path);
    const input = el("input", {type: "number", step: "any", name: path, value: v ?? "", inputmode: "decimal"});
    register(input, path, (s) => (s === "" ? undefined : Number(s)));
    return label(text, input, hint ?? HINTS[path.split(".").pop()]);
  }
  function text(doc, path, textLabel, parse, show, hint) {
    const input = el("input", {type: "text", name: path, value: show(getPath(doc, path)), spellcheck: "false"});
    register(input, path, parse);
    return label(textLabel, input, hint);
  }
  function select(path, textLabel, options, value, apply, attrs = {}) {
    const s = el("select", {name: path, ...attrs}, ...options.map((o) => el("option", {value: o, text: o})));
    s.value = value ?? "";
    register(s, path, (x) => x, apply);
    return label(textLabel, s);
  }

  /* one trajectory or disturbance object at base ("trajectory" or "trajectory[1]") */
  function entry(doc, base, table) {
    const obj = getPath(doc, base) || (base === "disturbance" ? {type: "none"} : {});
    const type = obj.type;
    const parts = [select(`${base}.type`, "type", Object.keys(table), type, (d, v) => setPath(d, base, {type: v, ...table[v]}))];
    for (const key of Object.keys(table[type] || {})) {
      const path = `${base}.${key}`;
      if (key === "boundary") parts.push(select(path, key, ["clamped", "natural"], obj[key]));
      else if (LISTS.has(key)) parts.push(text(doc, path, key, parseList, showList, "comma separated"));
      else parts.push(number(doc, path, key));
    }
    return parts;
  }

  /* a trajectory or disturbance section: one object for every coordinate, or one each */
  function perCoordinate(doc, key, title, table) {
    const nv = coordinates(doc);
    const value = doc[key];
    const fs = el("fieldset", {name: key}, el("legend", {text: title}));
    const each = Array.isArray(value);
    const scope = el("select", {id: `${key}-scope`, disabled: nv === 0},
      el("option", {value: "all", text: "the same for every coordinate"}),
      el("option", {value: "each", text: "one per coordinate"}));
    scope.value = each ? "each" : "all";
    register(scope, null, (x) => x, (d, v) => {
      const cur = d[key] || {type: Object.keys(table)[0], ...Object.values(table)[0]};
      if (v === "each" && !Array.isArray(cur)) d[key] = Array.from({length: nv}, () => structuredClone(cur));
      if (v === "all" && Array.isArray(cur)) d[key] = cur[0];
    });
    fs.append(label("applies to", scope));
    if (!each) {
      fs.append(el("div", {class: "row"}, ...entry(doc, key, table)));
    } else {
      const names = controlledNames(doc);
      value.forEach((_, i) => {
        fs.append(el("fieldset", {name: `${key}[${i}]`, class: "entry"},
          el("legend", {text: `coordinate ${i}${names[i] ? ` (${names[i]})` : ""}`}),
          el("div", {class: "row"}, ...entry(doc, `${key}[${i}]`, table))));
      });
    }
    return fs;
  }

  /* the lab plant and the sampled controller: the plant's terms when it is one object for every
   * coordinate, the sample period and delay when there is a controller */
  function plant(doc, type) {
    const fs = el("fieldset", {name: "plant"}, el("legend", {text: "Plant and sampling"}));
    if (type && type !== "none") {
      fs.append(el("div", {class: "row"},
        number(doc, "controller.sample_period", "sample period", "s, zero-order hold; empty or 0: continuous"),
        number(doc, "controller.sample_delay", "sample delay", "whole samples")));
    }
    if (Array.isArray(doc.plant)) {
      fs.append(el("p", {class: "hint", text: "The plant has one object per coordinate: edit it in the JSON."}));
    } else {
      fs.append(el("div", {class: "row"}, ...PLANT_FIELDS.map(([key, text, hint]) => number(doc, `plant.${key}`, text, hint))));
    }
    return fs;
  }

  /* the bodies' parents: per body a select of the ground and the bodies before it, showing the
   * parent the format reads (the previous body when none is given); a choice writes the index */
  function tree(bodies) {
    const fs = el("fieldset", {name: "scene.bodies"}, el("legend", {text: "Bodies and their parents"}));
    if (bodies.length > MAX_PARENT_FIELDS) {
      fs.append(el("p", {class: "hint", text: `${bodies.length} bodies: edit their parents (scene.bodies[k].parent) in the JSON.`}));
      return fs;
    }
    const parents = chainParents(bodies);
    const named = (k) => `body ${k}${bodies[k]?.name ? ` (${bodies[k].name})` : ""}`;
    const row = el("div", {class: "row"});
    bodies.forEach((_, k) => {
      const path = `scene.bodies[${k}].parent`;
      const s = el("select", {name: path},
        el("option", {value: "-1", text: "the ground"}),
        ...Array.from({length: k}, (__, j) => el("option", {value: String(j), text: named(j)})));
      s.value = String(parents[k]);
      register(s, path, (x) => Number(x));
      row.append(label(named(k), s, "hangs from"));
    });
    fs.append(row);
    return fs;
  }

  function sections(doc) {
    const out = [];
    out.push(el("fieldset", {name: "job"}, el("legend", {text: "Run"}),
      el("div", {class: "row"}, text(doc, "name", "name", (s) => (s === "" ? undefined : s), (v) => v ?? ""),
        number(doc, "duration", "duration", "s of simulated time"),
        number(doc, "output.interval", "output interval", "s between samples"))));

    const c = doc.controller || {};
    const type = c.type;
    const ctl = el("fieldset", {name: "controller"}, el("legend", {text: "Controller"}));
    const row = el("div", {class: "row"}, select("controller.type", "type", Object.keys(CONTROLLERS), type, (d, v) => {
      const wasNone = !d.controller || d.controller.type === "none";
      d.controller = {type: v, ...structuredClone(CONTROLLERS[v])};
      if (v !== "none" && c.model) d.controller.model = c.model;
      if (v === "none") { if (d.trajectory) savedTrajectory = d.trajectory; delete d.trajectory; }
      else if (!d.trajectory) d.trajectory = savedTrajectory || {type: "constant", value: 0};
      if ((v === "none") !== wasNone && d.output) delete d.output.channels;
    }));
    if (type === "pd" || type === "pid") {
      const byTime = c.zeta !== undefined || c.tau !== undefined;
      const form = el("select", {id: "gain-form"}, el("option", {value: "gains", text: "gains K_p, K_v"}),
        el("option", {value: "time", text: "damping ζ and time constant τ"}));
      form.value = byTime ? "time" : "gains";
      register(form, null, (x) => x, (d, v) => {
        for (const k of ["kp", "kv", "zeta", "tau"]) delete d.controller[k];
        Object.assign(d.controller, v === "time" ? {zeta: 1, tau: 0.1} : {kp: 100, kv: 20});
      });
      row.append(label("given as", form));
      if (byTime) row.append(number(doc, "controller.zeta", "ζ"), number(doc, "controller.tau", "τ"));
      else row.append(number(doc, "controller.kp", "K_p"), number(doc, "controller.kv", "K_v"));
      if (type === "pid") row.append(number(doc, "controller.ki", "K_i"));
    } else if (type === "poles") {
      row.append(text(doc, "controller.poles", "poles", parsePoles, showPoles, "three, e.g. -2, -2.1, -2.2 or -2, -1+2i, -1-2i"));
    } else if (BASELINES.has(type)) {
      row.append(number(doc, "controller.kp", "K_p", "N m/rad"), number(doc, "controller.kv", "K_v", "N m s/rad"));
    } else if (type === "lqr") {
      row.append(text(doc, "controller.Q", "Q", parseQ, showQ, "diagonal q1, q2, q3 or rows separated by ;"),
        number(doc, "controller.lambda", "λ", "control weight, > 0"));
    }
    ctl.append(row);
    if (type && type !== "none") {
      ctl.append(el("div", {class: "row"},
        number(doc, "controller.model.mass_scale", "model mass scale", "the controller's model error, 1 = exact"),
        number(doc, "controller.model.inertia_scale", "model inertia scale", "1 = exact")));
      if (Array.isArray(c.joints)) ctl.append(el("p", {class: "hint", text: "Per-joint overrides (controller.joints) are kept; edit them in the JSON."}));
    }
    out.push(ctl);

    if (type !== "none") out.push(perCoordinate(doc, "trajectory", "Desired trajectory", TRAJECTORIES));
    out.push(perCoordinate(doc, "disturbance", "Disturbance (added to the driving torque)", DISTURBANCES));
    out.push(plant(doc, type));

    const bodies = doc.scene && Array.isArray(doc.scene.bodies) ? doc.scene.bodies : [];
    if (bodies.length > 0) out.push(tree(bodies));

    const integ = doc.integrator || {};
    const ifs = el("fieldset", {name: "integrator"}, el("legend", {text: "Integrator"}));
    const irow = el("div", {class: "row"}, select("integrator.method", "method", Object.keys(INTEGRATORS), integ.method, (d, v) => {
      const keep = d.integrator && d.integrator.max_steps !== undefined ? {max_steps: d.integrator.max_steps} : {};
      d.integrator = {method: v, ...INTEGRATORS[v], ...keep};
    }));
    if (integ.method === "rk4") irow.append(number(doc, "integrator.step", "step"));
    else irow.append(number(doc, "integrator.rtol", "rtol"), number(doc, "integrator.atol", "atol"),
      number(doc, "integrator.max_step", "max step"));
    ifs.append(irow);
    out.push(ifs);
    return out;
  }

  let savedTrajectory = null;
  function render() {
    const doc = getDoc();
    const focused = document.activeElement;
    const key = focused && host.contains(focused) ? (focused.name || focused.id) : null;
    host.replaceChildren(...(doc && typeof doc === "object" ? sections(doc) : []));
    if (key) host.querySelector(`[name="${CSS.escape(key)}"], #${CSS.escape(key)}`)?.focus();
  }
  function onEdit(ev) {
    const c = controls.get(ev.target);
    if (!c) return;
    const doc = getDoc();
    if (c.apply) {
      if (ev.type !== "change") return;
      c.apply(doc, ev.target.value);
      edited();
      render();
    } else {
      if (ev.type === "change" && ev.target.tagName !== "SELECT") return;
      setPath(doc, c.path, c.parse(ev.target.value));
      edited();
    }
  }
  host.addEventListener("input", onEdit);
  host.addEventListener("change", onEdit);
  return {render};
}
