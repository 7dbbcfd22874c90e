/*
 * animate.js - the chain or tree drawn on a canvas (canvas#anim in a job's view) at the view's
 * time cursor, and the player (button#play, select#speed) that moves the cursor in real time,
 * faster (2x, 4x) or slower.
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
 * the base. Both zoom (the wheel, + and -, or the buttons) and pan (shift-drag, a planar drag,
 * or shift and the arrow keys); "Reset view" (or 0) restores the first view. The canvas carries
 * data-mode ("planar" | "spatial"), data-time (the time drawn, s, updated on every frame),
 * data-zoom (the zoom factor, 1 at first), data-pan ("x,y" in CSS px) and data-ghost ("1" while
 * a desired pose is drawn). The scale fits the largest reach over the whole run.
 *
 * A closed chain (scene.loop) has its second ground pivot, the anchor, drawn like the base (or,
 * for a loop closed on a body, a dot on that body), and a thin line from the last body's closing
 * point to it (a visible gap is the closure residual). Its ghost: q_des holds only the
 * independent coordinates (series.js controlledCoordinates), so the dependent ones are solved for
 * at each frame (kinematics.js closeLoop, from the previous frame's solution or the actual pose);
 * a frame where the loop cannot be closed within 0.1 % of the reach draws no ghost.
 */
import {el} from "./dom.js";
import {chainLayout, chainPose, closeLoop, loopAnchor, planeBasis, worldBasis, dot, norm, add, scale, cross} from "./kinematics.js";
import {controlledCoordinates} from "./series.js";
import {JOINT_NQ as NQ} from "./joints.js";

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

/* Fills each body's visual shapes (spec.scene.bodies[k].visuals: a URDF's <visual> boxes,
 * cylinders and spheres, in the body's frame) at pose, in color: each shape is the convex hull
 * of points on its surface projected by toXY, its outline under the orthographic view (a sphere's
 * from three great circles). Returns the number of shapes drawn. */
function drawVisuals(g, bodies, pose, toXY, color) {
  const mv = (R, v) => [0, 1, 2].map((i) => R[3 * i] * v[0] + R[3 * i + 1] * v[1] + R[3 * i + 2] * v[2]);
  const ring = (n) => Array.from({length: n}, (_, i) => [Math.cos((2 * Math.PI * i) / n), Math.sin((2 * Math.PI * i) / n)]);
  const cw = (o, a, b) => (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]);
  let drawn = 0;
  g.save();
  g.fillStyle = color; g.strokeStyle = color; g.lineWidth = 1.5;
  bodies.forEach((b, k) => {
    for (const v of Array.isArray(b?.visuals) ? b.visuals : []) {
      const pts = [], r = v.radius;
      if (v.type === "box") {
        const [a, c, d] = v.size.map((x) => x / 2);
        for (const x of [-a, a]) for (const y of [-c, c]) for (const z of [-d, d]) pts.push([x, y, z]);
      } else if (v.type === "cylinder") {
        for (const [c, s] of ring(24)) pts.push([r * c, r * s, -v.length / 2], [r * c, r * s, v.length / 2]);
      } else if (v.type === "sphere") {
        for (const [c, s] of ring(32)) pts.push([r * c, r * s, 0], [r * c, 0, r * s], [0, r * c, r * s]);
      } else continue;
      const R = v.rotation ? v.rotation.flat() : [1, 0, 0, 0, 1, 0, 0, 0, 1], o = v.origin || [0, 0, 0];
      const xy = pts.map((p) => toXY(add(pose[k].origin, mv(pose[k].rot, add(o, mv(R, p))))))
        .sort((p, q) => p[0] - q[0] || p[1] - q[1]);
      const hull = []; /* Andrew's monotone chain: lower then upper */
      for (const pass of [xy, [...xy].reverse()]) {
        const start = hull.length;
        for (const p of pass) {
          while (hull.length >= start + 2 && cw(hull[hull.length - 2], hull[hull.length - 1], p) <= 0) hull.pop();
          hull.push(p);
        }
        hull.pop();
      }
      g.globalAlpha = 0.35; g.beginPath();
      hull.forEach(([x, y], i) => (i ? g.lineTo(x, y) : g.moveTo(x, y)));
      g.closePath(); g.fill(); g.globalAlpha = 1; g.stroke();
      drawn++;
    }
  });
  g.restore();
  return drawn;
}

/* The desired pose's sampler of a closed chain: i -> q_i at time t with the independent
 * coordinates from q_des and the dependent ones solved for (null when it does not close). */
function loopGhost(layout, loop, spec, nq, ts, q, qDes) {
  /* each independent coordinate's row of q and its column of q_des (a closing joint's has no row) */
  const coords = controlledCoordinates({spec, metrics: null}).map((c, col) => ({row: c.row, col}))
    .filter((c) => c.row < nq);
  const rows = new Set(coords.map((c) => c.row));
  const free = Array.from({length: nq}, (_, i) => i).filter((i) => !rows.has(i));
  const joints = spec.scene.bodies.map((b) => b.joint.type);
  if (!coords.length || joints.includes("spherical")) return null;
  let reach = 0;
  for (const l of layout) reach += norm(l.loc) + norm(l.end);
  let warm = null;
  return (t) => {
    const actual = sampler(ts, q, t), desired = sampler(ts, qDes, t);
    const start = Array.from({length: nq}, (_, i) => (warm ? warm[i] : actual(i)));
    for (const c of coords) start[c.row] = desired(c.col);
    const {q: x, gap} = closeLoop(layout, loop, start, free);
    if (!(gap <= 1e-3 * Math.max(reach, 1e-3))) { warm = null; return null; }
    warm = x;
    return (i) => x[i] ?? 0;
  };
}

/* Draws into host; returns {destroy()}. series: {t, q, q_des?}; form: "planar" | "spatial";
 * id: the canvas's id (several in the compare view); caption: a line above the canvas. */
export function createAnimation(host, {spec, form, series, timeline, id = "anim", caption = null}) {
  const bodies = spec.scene.bodies;
  const loop = spec.scene.loop || null;
  const onBody = loop !== null && Number.isInteger(loop.body);
  const layout = chainLayout(bodies, loop);
  const branched = layout.some((l) => l.ends.length > 1) || layout.filter((l) => l.parent < 0).length > 1;
  const nq = bodies.reduce((n, b) => n + (NQ[b.joint.type] ?? 0), 0);
  const ghost = loop ? null : series.q_des;
  const ghostOfLoop = loop && series.q_des ? loopGhost(layout, loop, spec, nq, series.t, series.q, series.q_des) : null;
  const hasGhost = Boolean(ghost || ghostOfLoop);
  const ts = series.t;
  const spatial = form !== "planar";
  const canvas = el("canvas", {id, class: "anim", tabindex: "0", "data-mode": spatial ? "spatial" : "planar",
    "data-time": "0", "data-zoom": "1", "data-pan": "0,0", "data-ghost": "0", role: "img",
    "aria-label": `animation of the ${loop ? "closed chain" : branched ? "tree" : "chain"} (${spatial ? "3-D, drag or arrow keys to rotate" : "planar"}, wheel or + and - to zoom, shift-drag to pan); ` +
      (hasGhost ? "blue: actual pose, dashed orange: desired pose" : "blue: actual pose")});
  const zoomIn = el("button", {type: "button", class: "anim-zoom-in icon", "data-for": id, text: "+", "aria-label": "zoom the animation in"});
  const zoomOut = el("button", {type: "button", class: "anim-zoom-out icon", "data-for": id, text: "−", "aria-label": "zoom the animation out"});
  const reset = el("button", {type: "button", class: "anim-reset", "data-for": id, text: "Reset view"});
  if (caption) host.append(el("p", {class: "anim-caption", text: caption}));
  host.append(el("div", {class: "anim-wrap"}, canvas),
    el("p", {class: "muted small"}, el("span", {class: "key-actual", text: "━ actual"}), "  ",
      hasGhost ? el("span", {class: "key-ghost", text: "┅ desired"}) : null,
      loop ? (onBody ? "■ ground pivot, ● the loop's pivot on a body" : "■ ground pivots") : null, "  ·  ",
      spatial ? "drag or use the arrow keys to rotate, shift-drag to pan" : "x right, y up (against gravity); drag to pan"),
    el("div", {class: "anim-view"}, zoomIn, zoomOut, reset));

  let yaw = -0.6, pitch = 0.35, zoom = 1, pan = [0, 0];
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
    const s = 0.44 * zoom * Math.min(w, h) / reach, cx = w / 2 + pan[0], cy = h / 2 + pan[1];
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

    const ghostQ = ghost ? sampler(ts, ghost, t) : ghostOfLoop ? ghostOfLoop(t) : null;
    if (ghostQ) chain(chainPose(layout, ghostQ), toXY, GHOST, 3, [7, 5], 0.85);
    canvas.dataset.ghost = ghostQ ? "1" : "0";
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
    canvas.dataset.visuals = String(drawVisuals(g, bodies, pose, toXY, ACTUAL));
    chain(pose.filter((_, k) => !bodies[k]?.visuals?.length), toXY, ACTUAL, 5, [], 1);

    g.fillStyle = "#1f2328"; g.font = "bold 14px system-ui, sans-serif";
    g.fillText(`t = ${t.toFixed(2)} s`, 10, 20);
    canvas.dataset.time = String(Math.round(t * 1e6) / 1e6);
  }

  /* the view: rotation (spatial), zoom and pan */
  function setView(z, p) {
    zoom = Math.min(50, Math.max(0.1, z));
    pan = p;
    canvas.dataset.zoom = String(Math.round(zoom * 1000) / 1000);
    canvas.dataset.pan = `${Math.round(pan[0])},${Math.round(pan[1])}`;
    draw();
  }
  let drag = null;
  canvas.addEventListener("pointerdown", (ev) => {
    drag = {x: ev.clientX, y: ev.clientY, pan: !spatial || ev.shiftKey || ev.button !== 0};
    canvas.setPointerCapture(ev.pointerId);
  });
  canvas.addEventListener("pointermove", (ev) => {
    if (!drag) return;
    const dx = ev.clientX - drag.x, dy = ev.clientY - drag.y;
    drag.x = ev.clientX;
    drag.y = ev.clientY;
    if (drag.pan) { setView(zoom, [pan[0] + dx, pan[1] + dy]); return; }
    yaw -= dx * 0.01;
    pitch = Math.min(1.55, Math.max(-1.55, pitch + dy * 0.01));
    draw();
  });
  canvas.addEventListener("pointerup", () => { drag = null; });
  canvas.addEventListener("contextmenu", (ev) => ev.preventDefault());
  canvas.addEventListener("wheel", (ev) => {
    ev.preventDefault();
    setView(zoom * Math.exp(-ev.deltaY * 0.0015), pan);
  }, {passive: false});
  canvas.addEventListener("keydown", (ev) => {
    if (ev.key === "+" || ev.key === "=") { ev.preventDefault(); setView(zoom * 1.25, pan); return; }
    if (ev.key === "-") { ev.preventDefault(); setView(zoom / 1.25, pan); return; }
    if (ev.key === "0") { ev.preventDefault(); resetView(); return; }
    const d = {ArrowLeft: [0.1, 0], ArrowRight: [-0.1, 0], ArrowUp: [0, -0.1], ArrowDown: [0, 0.1]}[ev.key];
    if (!d) return;
    ev.preventDefault();
    if (ev.shiftKey || !spatial) { setView(zoom, [pan[0] - 200 * d[0], pan[1] - 200 * d[1]]); return; }
    yaw += d[0];
    pitch = Math.min(1.55, Math.max(-1.55, pitch + d[1]));
    draw();
  });
  function resetView() {
    yaw = -0.6;
    pitch = 0.35;
    setView(1, [0, 0]);
  }
  zoomIn.addEventListener("click", () => setView(zoom * 1.25, pan));
  zoomOut.addEventListener("click", () => setView(zoom / 1.25, pan));
  reset.addEventListener("click", resetView);

  const unsubscribe = timeline.subscribe(draw);
  window.addEventListener("resize", draw);
  draw();
  return {destroy() { unsubscribe(); window.removeEventListener("resize", draw); }};
}

/* button#play (aria-pressed) and select#speed (4, 2, 1, 0.5, 0.25, 0.1; 1 at first): plays the
 * timeline from its time to tEnd at the chosen speed; play at the end starts again from 0. */
export function createPlayer(timeline, tEnd) {
  const button = el("button", {id: "play", type: "button", "aria-pressed": "false", text: "▶ Play"});
  const speed = el("select", {id: "speed", "aria-label": "playback speed"},
    ...["4", "2", "1", "0.5", "0.25", "0.1"].map((v) => el("option", {value: v, text: `${v}×`})));
  speed.value = "1";
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
