/*
 * animate.js - the chain or tree drawn on canvas#anim at the view's time cursor, and the player
 * (button#play, select#speed) that moves the cursor in real time or slower.
 *
 * Each body is a segment from its joint to each of its children's joints (a body with several
 * children, a palm or a torso, a fan of segments), or to its tip when it has none
 * (kinematics.js chainLayout); the tree's shape is the spec's parents.
 *
 * Poses come from kinematics.js with q interpolated linearly between samples; the desired pose
 * (q_des, when the run had a controller) is drawn as a dashed orange ghost behind the actual
 * chain (solid blue). Planar scenes (metrics.form "planar") are drawn in their plane with "up"
 * against gravity (x right, y up for the presets); spatial ones in an orthographic projection
 * that dragging, or the arrow keys on the focused canvas, rotates, over a floor grid through
 * the base. The canvas carries data-mode ("planar" | "spatial") and data-time (the time drawn,
 * s, updated on every frame). The scale fits the largest reach over the whole run.
 *
 * A closed chain (scene.loop) has its second ground pivot, the anchor, drawn like the base (or,
 * for a loop closed on a body, a dot on that body), and a thin line from the last body's closing
 * point to it (a visible gap is the closure residual).
 * It has no ghost: q_des holds only the independent coordinates, and the desired pose of the
 * dependent joints is not recorded.
 */
import {el} from "./dom.js";
import {chainLayout, chainPose, loopAnchor, planeBasis, worldBasis, dot, norm, add, scale, cross} from "./kinematics.js";

const ACTUAL = "#0072B2";
const GHOST = "#D55E00";

/* i -> q_i at time t, linear between the samples around t; rows[i] is coordinate i's samples */
function sampler(ts, rows, t) {
  let lo = 0, hi = ts.length - 1;
  if (t <= ts[0]) hi = 0;
  else if (t >= ts[hi]) lo = hi;
  else {
    while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (ts[mid] <= t) lo = mid; else hi = mid; }
  }
  const f = hi > lo ? (t - ts[lo]) / (ts[hi] - ts[lo]) : 0;
  return (i) => {
    const r = rows[i];
    if (!r) return 0;
    const a = r[lo] ?? 0, b = r[hi] ?? a;
    return a + f * (b - a);
  };
}

/* Draws into host; returns {destroy()}. series: {t, q, q_des?}; form: "planar" | "spatial". */
export function createAnimation(host, {spec, form, series, timeline}) {
  const bodies = spec.scene.bodies;
  const loop = spec.scene.loop || null;
  const onBody = loop !== null && Number.isInteger(loop.body);
  const layout = chainLayout(bodies, loop);
  const branched = layout.some((l) => l.ends.length > 1) || layout.filter((l) => l.parent < 0).length > 1;
  const ghost = loop ? null : series.q_des;
  const ts = series.t;
  const spatial = form !== "planar";
  const canvas = el("canvas", {id: "anim", tabindex: "0", "data-mode": spatial ? "spatial" : "planar",
    "data-time": "0", role: "img",
    "aria-label": `animation of the ${loop ? "closed chain" : branched ? "tree" : "chain"} (${spatial ? "3-D, drag or arrow keys to rotate" : "planar"}); ` +
      (ghost ? "blue: actual pose, dashed orange: desired pose" : "blue: actual pose")});
  host.append(el("div", {class: "anim-wrap"}, canvas),
    el("p", {class: "muted small"}, el("span", {class: "key-actual", text: "━ actual"}), "  ",
      ghost ? el("span", {class: "key-ghost", text: "┅ desired"}) : null,
      loop ? (onBody ? "■ ground pivot, ● the loop's pivot on a body" : "■ ground pivots") : null, "  ·  ",
      spatial ? "drag or use the arrow keys to rotate" : "x right, y up (against gravity)"));

  let yaw = -0.6, pitch = 0.35;
  let basis;
  function project(p) {
    if (!spatial) return [dot(p, basis.right), dot(p, basis.up)];
    const r = add(scale(basis.h1, Math.cos(yaw)), scale(basis.h2, Math.sin(yaw)));
    const f = cross(basis.up, r);
    const s = add(scale(basis.up, Math.cos(pitch)), scale(f, Math.sin(pitch)));
    return [dot(p, r), dot(p, s)];
  }
  basis = spatial ? worldBasis(spec.scene.gravity) : planeBasis(bodies, spec.scene.gravity);

  /* the largest distance from the base over the run, actual and desired */
  let reach = loop && !onBody ? Math.max(1e-3, norm(loop.anchor || [0, 0, 0])) : 1e-3;
  const stride = Math.max(1, Math.floor(ts.length / 400));
  for (const rows of [series.q, ghost]) {
    if (!rows) continue;
    for (let k = 0; k < ts.length; k += stride) {
      for (const b of chainPose(layout, (i) => (rows[i] ? rows[i][k] ?? 0 : 0))) {
        reach = Math.max(reach, norm(b.origin), norm(b.attach), ...b.ends.map(norm));
      }
    }
  }

  const g = canvas.getContext("2d");
  const thin = bodies.length > 12; /* many short links: thinner lines, smaller joints */
  function chain(poses, toXY, color, width, dash, alpha) {
    if (thin) width = Math.max(2, width - 2);
    g.save();
    g.globalAlpha = alpha;
    g.strokeStyle = color;
    g.lineCap = "round";
    g.setLineDash(dash);
    /* one path per kind of stroke: a 4096-link chain is then a few canvas calls, not 8000 */
    g.lineWidth = 1.5;
    g.beginPath();
    for (const b of poses) {
      const [ax, ay] = toXY(b.attach), [ox, oy] = toXY(b.origin);
      if (Math.hypot(ax - ox, ay - oy) > 0.5) { g.moveTo(ax, ay); g.lineTo(ox, oy); }
    }
    g.stroke();
    g.lineWidth = width;
    g.beginPath();
    for (const b of poses) {
      const [ox, oy] = toXY(b.origin);
      for (const e of b.ends) { const [ex, ey] = toXY(e); g.moveTo(ox, oy); g.lineTo(ex, ey); }
    }
    g.stroke();
    g.setLineDash([]);
    g.lineWidth = 2;
    g.beginPath();
    for (const b of poses) {
      const [ox, oy] = toXY(b.origin);
      const r = thin ? 2 : width + 1;
      g.moveTo(ox + r, oy); g.arc(ox, oy, r, 0, 2 * Math.PI);
    }
    g.fillStyle = "#ffffff"; g.fill(); g.stroke();
    g.restore();
  }

  function draw() {
    const t = Math.min(Math.max(timeline.t, ts[0] ?? 0), ts[ts.length - 1] ?? 0);
    const dpr = window.devicePixelRatio || 1;
    const w = canvas.clientWidth || 400, h = Math.round(w * 0.75);
    if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
      canvas.width = Math.round(w * dpr); canvas.height = Math.round(h * dpr);
      canvas.style.height = `${h}px`;
    }
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.fillStyle = "#fbfbfc"; g.fillRect(0, 0, w, h);
    const s = 0.44 * Math.min(w, h) / reach, cx = w / 2, cy = h / 2;
    const toXY = (p) => { const [x, y] = project(p); return [cx + s * x, cy - s * y]; };

    g.strokeStyle = "#d5d9de"; g.lineWidth = 1;
    if (spatial) {
      for (let i = -4; i <= 4; i++) {
        const a = (i / 4) * reach;
        for (const [d1, d2] of [[basis.h1, basis.h2], [basis.h2, basis.h1]]) {
          const [x0, y0] = toXY(add(scale(d1, a), scale(d2, -reach)));
          const [x1, y1] = toXY(add(scale(d1, a), scale(d2, reach)));
          g.beginPath(); g.moveTo(x0, y0); g.lineTo(x1, y1); g.stroke();
        }
      }
      g.font = "12px system-ui, sans-serif"; g.fillStyle = "#3d434a"; g.lineWidth = 1.5;
      ["x", "y", "z"].forEach((name, i) => {
        const e = [0, 0, 0]; e[i] = 0.25 * reach;
        const [x0, y0] = toXY([0, 0, 0]), [x1, y1] = toXY(e);
        g.strokeStyle = "#6b7280"; g.beginPath(); g.moveTo(x0, y0); g.lineTo(x1, y1); g.stroke();
        g.fillText(name, x1 + 3, y1 - 3);
      });
    } else {
      const [bx, by] = toXY([0, 0, 0]);
      g.beginPath(); g.moveTo(0, by); g.lineTo(w, by); g.moveTo(bx, 0); g.lineTo(bx, h); g.stroke();
    }
    const [bx, by] = toXY([0, 0, 0]);
    g.fillStyle = "#3d434a"; g.fillRect(bx - 7, by - 7, 14, 14);

    if (ghost) chain(chainPose(layout, sampler(ts, ghost, t)), toXY, GHOST, 3, [7, 5], 0.85);
    const pose = chainPose(layout, sampler(ts, series.q, t));
    if (loop) {
      /* the anchor, and the closing joint from the last body's closing point to it */
      const [ax, ay] = toXY(loopAnchor(loop, pose));
      const [ex, ey] = toXY(pose[pose.length - 1].end);
      g.fillStyle = "#3d434a";
      if (onBody) { g.beginPath(); g.arc(ax, ay, 6, 0, 2 * Math.PI); g.fill(); }
      else g.fillRect(ax - 7, ay - 7, 14, 14);
      g.strokeStyle = "#3d434a"; g.lineWidth = 1.5;
      g.beginPath(); g.moveTo(ex, ey); g.lineTo(ax, ay); g.stroke();
    }
    chain(pose, toXY, ACTUAL, 5, [], 1);

    g.fillStyle = "#1f2328"; g.font = "bold 14px system-ui, sans-serif";
    g.fillText(`t = ${t.toFixed(2)} s`, 10, 20);
    canvas.dataset.time = String(Math.round(t * 1e6) / 1e6);
  }

  /* rotation of the spatial view */
  let drag = null;
  canvas.addEventListener("pointerdown", (ev) => {
    if (!spatial) return;
    drag = {x: ev.clientX, y: ev.clientY};
    canvas.setPointerCapture(ev.pointerId);
  });
  canvas.addEventListener("pointermove", (ev) => {
    if (!drag) return;
    yaw -= (ev.clientX - drag.x) * 0.01;
    pitch = Math.min(1.55, Math.max(-1.55, pitch + (ev.clientY - drag.y) * 0.01));
    drag = {x: ev.clientX, y: ev.clientY};
    draw();
  });
  canvas.addEventListener("pointerup", () => { drag = null; });
  canvas.addEventListener("keydown", (ev) => {
    if (!spatial) return;
    const d = {ArrowLeft: [0.1, 0], ArrowRight: [-0.1, 0], ArrowUp: [0, -0.1], ArrowDown: [0, 0.1]}[ev.key];
    if (!d) return;
    ev.preventDefault();
    yaw += d[0];
    pitch = Math.min(1.55, Math.max(-1.55, pitch + d[1]));
    draw();
  });

  const unsubscribe = timeline.subscribe(draw);
  window.addEventListener("resize", draw);
  draw();
  return {destroy() { unsubscribe(); window.removeEventListener("resize", draw); }};
}

/* button#play (aria-pressed) and select#speed (1, 0.5, 0.25, 0.1): plays the timeline from
 * its time to tEnd at the chosen speed; play at the end starts again from 0. */
export function createPlayer(timeline, tEnd) {
  const button = el("button", {id: "play", type: "button", "aria-pressed": "false", text: "▶ Play"});
  const speed = el("select", {id: "speed", "aria-label": "playback speed"},
    ...["1", "0.5", "0.25", "0.1"].map((v) => el("option", {value: v, text: `${v}×`})));
  let frame = 0, last = 0;

  function stop() {
    cancelAnimationFrame(frame);
    frame = 0;
    button.setAttribute("aria-pressed", "false");
    button.textContent = "▶ Play";
  }
  function tick(now) {
    const dt = Math.min(0.1, (now - last) / 1000);
    last = now;
    const t = timeline.t + dt * Number(speed.value);
    if (t >= tEnd) { timeline.set(tEnd, "play"); stop(); return; }
    timeline.set(t, "play");
    frame = requestAnimationFrame(tick);
  }
  button.addEventListener("click", () => {
    if (frame) { stop(); return; }
    if (timeline.t >= tEnd - 1e-9) timeline.set(0, "play");
    button.setAttribute("aria-pressed", "true");
    button.textContent = "❚❚ Pause";
    last = performance.now();
    frame = requestAnimationFrame(tick);
  });
  const node = el("div", {class: "player"}, button, el("label", {}, "speed ", speed));
  return {node, destroy: stop};
}
