/*
 * export.js - saving what the page shows: a plot as PNG (its canvas, with its title and a key of
 * its lines, on white) or as SVG (the lines redrawn as paths in the plot's current zoom, with
 * its ticks, axis labels, title and key: a vector figure for a paper), and a table as CSV.
 *
 * Each plot's caption gets button.export-png and button.export-svg (data-channel, and
 * data-joint in the paper's layout); a click downloads ctcsim-CHANNEL[-JOINT].png|svg. The SVG
 * uses the tick positions and labels uPlot drew (its axes' _splits and _values, uPlot 1.6, the
 * pinned version), so the two exports show the same axes. Hidden lines are left out of both.
 * CSV follows RFC 4180: fields with a comma, quote or line break are quoted, quotes doubled.
 */
import {el} from "./dom.js";

/* Saves blob as filename through a temporary link. */
export function download(blob, filename) {
  const url = URL.createObjectURL(blob);
  const a = el("a", {href: url, download: filename, hidden: true});
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(url), 10000);
}

/* rows (arrays of strings and numbers; null as empty) as CSV text */
export function csvText(rows) {
  const field = (v) => {
    const s = v === null || v === undefined ? "" : String(v);
    return /[",\r\n]/.test(s) ? `"${s.replace(/"/g, '""')}"` : s;
  };
  return rows.map((r) => r.map(field).join(",")).join("\r\n") + "\r\n";
}

const escapeXml = (s) => String(s).replace(/[<>&"']/g, (c) => ({"<": "&lt;", ">": "&gt;", "&": "&amp;", '"': "&quot;", "'": "&apos;"})[c]);
const FONT = "system-ui, sans-serif";

/* the lines shown: [{label, stroke, dash, width, i (series index)}] */
function shownLines(u, lines) {
  return lines.map((l, k) => ({...l, i: k + 1})).filter((l) => u.series[l.i].show !== false);
}

/* The plot u as an SVG document (text). meta: {title, yLabel, xLabel (default "t [s]"), lines};
 * a line with points: true is also drawn as dots at its values, only: true as dots alone, and
 * nokey: true is left out of the key. */
export function plotSvg(u, {title, yLabel, xLabel = "t [s]", lines}) {
  const W = u.width, plotH = u.height;
  const dpr = window.devicePixelRatio || 1;
  const left = u.bbox.left / dpr, top = u.bbox.top / dpr;
  const w = u.bbox.width / dpr, h = u.bbox.height / dpr;
  const shown = shownLines(u, lines);
  const keyed = shown.filter((l) => !l.nokey);
  const keyRows = Math.ceil(keyed.length / 3);
  const head = 28;
  const H = head + plotH + 18 * keyRows + 10;
  const out = [`<svg xmlns="http://www.w3.org/2000/svg" width="${W}" height="${H}" viewBox="0 0 ${W} ${H}" font-family="${FONT}">`,
    `<rect width="${W}" height="${H}" fill="#ffffff"/>`,
    `<text x="8" y="18" font-size="14" font-weight="bold" fill="#1f2328">${escapeXml(title)}</text>`,
    `<g transform="translate(0 ${head})">`];
  /* grid and ticks, as uPlot drew them */
  const ax = u.axes;
  const xs = (ax[0]._splits || []).map((v, k) => [v, (ax[0]._values || [])[k]]);
  const ys = (ax[1]._splits || []).map((v, k) => [v, (ax[1]._values || [])[k]]);
  for (const [v, label] of xs) {
    const x = left + u.valToPos(v, "x");
    if (!(x >= left - 0.5 && x <= left + w + 0.5)) continue;
    out.push(`<line x1="${x.toFixed(1)}" y1="${top}" x2="${x.toFixed(1)}" y2="${top + h}" stroke="#dde1e6"/>`,
      `<text x="${x.toFixed(1)}" y="${top + h + 16}" font-size="12" text-anchor="middle" fill="#1f2328">${escapeXml(label ?? "")}</text>`);
  }
  for (const [v, label] of ys) {
    const y = top + u.valToPos(v, "y");
    if (!(y >= top - 0.5 && y <= top + h + 0.5)) continue;
    out.push(`<line x1="${left}" y1="${y.toFixed(1)}" x2="${left + w}" y2="${y.toFixed(1)}" stroke="#dde1e6"/>`,
      `<text x="${left - 6}" y="${(y + 4).toFixed(1)}" font-size="12" text-anchor="end" fill="#1f2328">${escapeXml(label ?? "")}</text>`);
  }
  out.push(`<rect x="${left}" y="${top}" width="${w}" height="${h}" fill="none" stroke="#b8bec6"/>`,
    `<text x="${left + w / 2}" y="${top + h + 34}" font-size="13" font-weight="bold" text-anchor="middle" fill="#1f2328">${escapeXml(xLabel)}</text>`,
    `<text transform="translate(14 ${top + h / 2}) rotate(-90)" font-size="13" font-weight="bold" text-anchor="middle" fill="#1f2328">${escapeXml(yLabel)}</text>`,
    `<clipPath id="area"><rect x="${left}" y="${top}" width="${w}" height="${h}"/></clipPath>`,
    `<g clip-path="url(#area)" fill="none" stroke-linejoin="round">`);
  const t = u.data[0];
  for (const l of shown) {
    const vals = u.data[l.i];
    let d = "", pen = false;
    const dots = [];
    for (let k = 0; k < t.length; k++) {
      const v = vals[k];
      if (v === null || v === undefined || !Number.isFinite(v)) continue; /* gaps are spanned, as on screen */
      const x = left + u.valToPos(t[k], "x"), y = top + u.valToPos(v, "y");
      if (!Number.isFinite(x) || !Number.isFinite(y)) continue;
      d += `${pen ? "L" : "M"}${x.toFixed(2)} ${y.toFixed(2)}`;
      if (l.points) dots.push(`<circle cx="${x.toFixed(2)}" cy="${y.toFixed(2)}" r="2.5" fill="${l.stroke}" stroke="none"/>`);
      pen = true;
    }
    if (!d) continue;
    const dash = l.dash && l.dash.length ? ` stroke-dasharray="${l.dash.join(" ")}"` : "";
    if (!l.only) out.push(`<path d="${d}" stroke="${l.stroke}" stroke-width="${l.width}"${dash}><title>${escapeXml(l.label)}</title></path>`);
    if (dots.length) out.push(`<g class="points"><title>${escapeXml(l.label)}</title>${dots.join("")}</g>`);
  }
  out.push("</g></g>");
  /* the key (lines with nokey, a series' further slots, are left out of it) */
  keyed.forEach((l, k) => {
    const x = 10 + (k % 3) * (W / 3), y = head + plotH + 14 + 18 * Math.floor(k / 3);
    const dash = l.dash && l.dash.length ? ` stroke-dasharray="${l.dash.join(" ")}"` : "";
    out.push(`<line x1="${x}" y1="${y - 4}" x2="${x + 24}" y2="${y - 4}" stroke="${l.stroke}" stroke-width="${l.width}"${dash}/>`,
      `<text x="${x + 30}" y="${y}" font-size="12" fill="#1f2328">${escapeXml(l.label)}</text>`);
  });
  out.push("</svg>");
  return out.join("\n");
}

/* The plot u as a PNG blob: title, the canvas uPlot drew, a key of the lines shown. */
export function plotPng(u, {title, lines}) {
  const src = u.root.querySelector("canvas");
  const dpr = src.width / (u.width || 1);
  const shown = shownLines(u, lines).filter((l) => !l.nokey);
  const keyRows = Math.ceil(shown.length / 3);
  const head = 28, W = u.width, H = head + u.height + 18 * keyRows + 10;
  const c = document.createElement("canvas");
  c.width = Math.round(W * dpr);
  c.height = Math.round(H * dpr);
  const g = c.getContext("2d");
  g.scale(dpr, dpr);
  g.fillStyle = "#ffffff";
  g.fillRect(0, 0, W, H);
  g.fillStyle = "#1f2328";
  g.font = `bold 14px ${FONT}`;
  g.fillText(title, 8, 18);
  g.drawImage(src, 0, head, u.width, u.height);
  g.font = `12px ${FONT}`;
  shown.forEach((l, k) => {
    const x = 10 + (k % 3) * (W / 3), y = head + u.height + 14 + 18 * Math.floor(k / 3);
    g.strokeStyle = l.stroke;
    g.lineWidth = l.width;
    g.setLineDash(l.dash || []);
    g.beginPath(); g.moveTo(x, y - 4); g.lineTo(x + 24, y - 4); g.stroke();
    g.fillStyle = "#1f2328";
    g.fillText(l.label, x + 30, y);
  });
  return new Promise((resolve) => c.toBlob(resolve, "image/png"));
}

/* The PNG and SVG buttons of one plot. meta: {channel, joint (or null), title, yLabel, lines}. */
export function exportButtons(u, meta) {
  const base = `ctcsim-${meta.channel}${meta.joint !== null && meta.joint !== undefined ? `-${meta.joint}` : ""}`;
  const attrs = {"data-channel": meta.channel, "data-joint": meta.joint ?? null};
  const png = el("button", {type: "button", class: "export-png icon", ...attrs, text: "PNG",
    "aria-label": `save the plot "${meta.title}" as PNG`});
  const svg = el("button", {type: "button", class: "export-svg icon", ...attrs, text: "SVG",
    "aria-label": `save the plot "${meta.title}" as SVG`});
  png.addEventListener("click", async () => download(await plotPng(u, meta), `${base}.png`));
  svg.addEventListener("click", () => download(new Blob([plotSvg(u, meta)], {type: "image/svg+xml"}), `${base}.svg`));
  return el("span", {class: "export"}, png, svg);
}
