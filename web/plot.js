// ashlar web page: a small canvas plotting helper (no dependencies, no network).
// plot(canvas, spec) draws axes with round ticks, line series, scatter points, shaded bands and a
// cursor line. Series colours are saturated so that tests can tell data from axes.
"use strict";

const PLOT_COLORS = ["#1f6fd1", "#d1491f", "#2e9b3e", "#9b2ec4", "#c49b0e", "#0e9bb0", "#b0306a"];

function niceStep(span, target) {
  const raw = span / Math.max(1, target);
  const p = Math.pow(10, Math.floor(Math.log10(raw)));
  const m = raw / p;
  return (m < 1.5 ? 1 : m < 3.5 ? 2 : m < 7.5 ? 5 : 10) * p;
}

function fmtTick(v, step) {
  if (v === 0) return "0";
  const a = Math.abs(v);
  if (a >= 1e5 || a < 1e-3) return v.toExponential(1);
  const digits = Math.max(0, -Math.floor(Math.log10(step)) + (step / Math.pow(10, Math.floor(Math.log10(step))) === 1 ? 0 : 1));
  return v.toFixed(Math.min(6, digits));
}

function extent(values, lo, hi) {
  for (const v of values) {
    if (Number.isFinite(v)) {
      if (v < lo) lo = v;
      if (v > hi) hi = v;
    }
  }
  return [lo, hi];
}

// Fit the canvas backing store to its CSS size and the device pixel ratio; returns the 2D context
// in CSS pixels and the size.
function fitCanvas(canvas) {
  const dpr = window.devicePixelRatio || 1;
  const rect = canvas.getBoundingClientRect();
  const w = Math.max(50, Math.round(rect.width || canvas.width));
  const h = Math.max(50, Math.round(rect.height || canvas.height));
  if (canvas.width !== Math.round(w * dpr) || canvas.height !== Math.round(h * dpr)) {
    canvas.width = Math.round(w * dpr);
    canvas.height = Math.round(h * dpr);
  }
  const ctx = canvas.getContext("2d");
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.clearRect(0, 0, w, h);
  return { ctx, w, h };
}

// spec: { title, xlabel, ylabel, xlog, ylog, xrange:[a,b], yrange:[a,b], series:[{x, y, color, label,
//   width, dash}], points:[{x, y, color, label, shape:"o"|"x"}], bands:[{x0, x1, color, label}],
//   vlines:[{x, color, label}], cursor: x, legend: true }
// The spec last drawn on each canvas, so that a resized page can redraw its plots (replotAll).
const PLOTTED = new Map();

// Does the rectangle r ({x, y, w, h}, CSS px) cover any drawn data of the spec under the
// mapping sx, sy: a point's marker, a series' line, a vertical line? Shaded bands and the cursor
// are background and may be covered.
function coversData(r, spec, sx, sy) {
  const x0 = r.x, x1 = r.x + r.w, y0 = r.y, y1 = r.y + r.h;
  const ok = (v, log) => Number.isFinite(v) && (!log || v > 0);
  for (const p of spec.points || []) {
    if (!ok(p.x, spec.xlog) || !ok(p.y, spec.ylog)) continue;
    const X = sx(p.x), Y = sy(p.y);
    if (X + 7 > x0 && X - 7 < x1 && Y + 7 > y0 && Y - 7 < y1) return true;
  }
  for (const v of spec.vlines || []) { const X = sx(v.x); if (X + 2 > x0 && X - 2 < x1) return true; }
  // A segment meets the rectangle (grown by the line's half width) unless both ends lie beyond
  // one of its sides or the rectangle's corners all lie on one side of the segment's line.
  for (const s of spec.series || []) {
    const g = (s.width || 1.5) / 2 + 1;
    const a0 = x0 - g, a1 = x1 + g, b0 = y0 - g, b1 = y1 + g;
    let px = NaN, py = NaN;
    for (let i = 0; i < s.x.length; i++) {
      if (!ok(s.x[i], spec.xlog) || !ok(s.y[i], spec.ylog)) { px = NaN; continue; }
      const X = sx(s.x[i]), Y = sy(s.y[i]);
      if (Number.isFinite(px) && !((px < a0 && X < a0) || (px > a1 && X > a1) || (py < b0 && Y < b0) || (py > b1 && Y > b1))) {
        const side = (cx, cy) => Math.sign((X - px) * (cy - py) - (Y - py) * (cx - px));
        const sides = new Set([side(a0, b0), side(a1, b0), side(a0, b1), side(a1, b1)]);
        if (sides.size > 1 || sides.has(0)) return true;
      }
      px = X; py = Y;
    }
  }
  return false;
}

function plot(canvas, spec) {
  PLOTTED.set(canvas, spec);
  const { ctx, w, h } = fitCanvas(canvas);
  // The legend's entries, measured first: where it goes decides the plot frame.
  const items = [];
  (spec.series || []).forEach((s, k) => { if (s.label) items.push([s.label, s.color || PLOT_COLORS[k % PLOT_COLORS.length], "line"]); });
  const seen = new Set();
  for (const p of spec.points || []) if (p.label && !seen.has(p.label)) { seen.add(p.label); items.push([p.label, p.color || "#000", p.shape || "o"]); }
  for (const b of spec.bands || []) if (b.label) items.push([b.label, b.color, "band"]);
  const showLegend = items.length > 0 && spec.legend !== false;
  ctx.font = "11px system-ui, sans-serif";
  const itemW = items.map(([t]) => ctx.measureText(t).width + 30);
  const m = { l: 58, r: 12, t: spec.title ? 22 : 10, b: 38 };
  let pw = w - m.l - m.r, ph = h - m.t - m.b;
  const tx = spec.xlog ? Math.log10 : (v) => v;
  const ty = spec.ylog ? Math.log10 : (v) => v;
  let [x0, x1] = spec.xrange || [Infinity, -Infinity];
  let [y0, y1] = spec.yrange || [Infinity, -Infinity];
  if (!spec.xrange) {
    for (const s of spec.series || []) [x0, x1] = extent(s.x, x0, x1);
    for (const p of spec.points || []) [x0, x1] = extent([p.x], x0, x1);
    for (const b of spec.bands || []) [x0, x1] = extent([b.x0, b.x1], x0, x1);
  }
  if (!spec.yrange) {
    for (const s of spec.series || []) [y0, y1] = extent(s.y, y0, y1);
    for (const p of spec.points || []) [y0, y1] = extent([p.y], y0, y1);
  }
  if (!Number.isFinite(x0)) { x0 = 0; x1 = 1; }
  if (!Number.isFinite(y0)) { y0 = 0; y1 = 1; }
  if (x1 === x0) { x1 = x0 + 1; }
  if (y1 === y0) { const d = Math.abs(y0) > 0 ? Math.abs(y0) * 0.1 : 1; y0 -= d; y1 += d; }
  if (!spec.yrange && !spec.ylog) { const pad = 0.05 * (y1 - y0); y0 -= pad; y1 += pad; }
  // Scatter points sit inside the frame, not on its edge.
  if (!spec.xrange && !spec.xlog && (spec.points || []).length) { const pad = 0.04 * (x1 - x0); x0 -= pad; x1 += pad; }
  const X0 = tx(x0), X1 = tx(x1), Y0 = ty(y0), Y1 = ty(y1);
  const sx = (v) => m.l + ((tx(v) - X0) / (X1 - X0)) * pw;
  const sy = (v) => m.t + ph - ((ty(v) - Y0) / (Y1 - Y0)) * ph;

  // The legend never covers data: a corner of the frame that no point, line or marker line
  // crosses (top right, top left, bottom right, bottom left), else rows above the frame, under
  // the title, for which the frame gives up its height.
  let legend = null; // {x, y, w, h, place}: the legend's box, CSS px
  if (showLegend) {
    const bw = Math.max(...itemW) + 8, bh = items.length * 15 + 6;
    const corners = [["top-right", m.l + pw - bw - 2, m.t + 2], ["top-left", m.l + 2, m.t + 2],
      ["bottom-right", m.l + pw - bw - 2, m.t + ph - bh - 2], ["bottom-left", m.l + 2, m.t + ph - bh - 2]];
    for (const [place, x, y] of corners) {
      const r = { x, y, w: bw, h: bh };
      if (bw <= pw - 4 && bh <= ph - 4 && !coversData(r, spec, sx, sy)) { legend = { ...r, place }; break; }
    }
    if (!legend) {
      let rows = 1, lineW = 0;
      for (const iw of itemW) { if (lineW > 0 && lineW + iw > pw) { rows++; lineW = 0; } lineW += iw + 8; }
      const top = m.t - 2;
      legend = { x: m.l, y: top, w: pw, h: rows * 15 + 2, place: "above" };
      m.t = top + rows * 15 + 6;
      ph = h - m.t - m.b;
    }
  }

  ctx.font = "12px system-ui, sans-serif";
  ctx.fillStyle = "#222";
  if (spec.title) { ctx.textAlign = "left"; ctx.textBaseline = "top"; ctx.fillText(spec.title, m.l, 4); }

  // Grid and ticks.
  ctx.strokeStyle = "#ddd";
  ctx.lineWidth = 1;
  ctx.fillStyle = "#444";
  const ticks = (lo, hi, log, n) => {
    if (log) {
      const out = [];
      for (let e = Math.floor(Math.log10(lo)); e <= Math.ceil(Math.log10(hi)); e++) {
        const v = Math.pow(10, e);
        if (v >= lo * 0.999 && v <= hi * 1.001) out.push([v, 1]);
      }
      return out;
    }
    const step = niceStep(hi - lo, n);
    const out = [];
    for (let v = Math.ceil(lo / step) * step; v <= hi + step * 1e-9; v += step) out.push([Math.abs(v) < step * 1e-9 ? 0 : v, step]);
    return out;
  };
  ctx.textAlign = "center"; ctx.textBaseline = "top";
  for (const [v, step] of ticks(x0, x1, spec.xlog, Math.max(2, Math.floor(pw / 80)))) {
    const X = sx(v);
    ctx.beginPath(); ctx.moveTo(X, m.t); ctx.lineTo(X, m.t + ph); ctx.stroke();
    ctx.fillText(spec.xlog ? String(v) : fmtTick(v, step), X, m.t + ph + 4);
  }
  ctx.textAlign = "right"; ctx.textBaseline = "middle";
  // spec.yticks: [[value, label], ...] replaces the automatic ticks (categorical rows).
  const yt = spec.yticks || ticks(y0, y1, spec.ylog, Math.max(2, Math.floor(ph / 40))).map(([v, step]) => [v, spec.ylog ? String(v) : fmtTick(v, step)]);
  for (const [v, label] of yt) {
    const Y = sy(v);
    ctx.beginPath(); ctx.moveTo(m.l, Y); ctx.lineTo(m.l + pw, Y); ctx.stroke();
    ctx.fillText(String(label).slice(0, 9), m.l - 4, Y);
  }
  ctx.strokeStyle = "#555";
  ctx.strokeRect(m.l, m.t, pw, ph);
  ctx.fillStyle = "#222";
  if (spec.xlabel) { ctx.textAlign = "center"; ctx.textBaseline = "bottom"; ctx.fillText(spec.xlabel, m.l + pw / 2, h - 2); }
  if (spec.ylabel) {
    ctx.save(); ctx.translate(12, m.t + ph / 2); ctx.rotate(-Math.PI / 2);
    ctx.textAlign = "center"; ctx.textBaseline = "middle"; ctx.fillText(spec.ylabel, 0, 0); ctx.restore();
  }

  ctx.save();
  ctx.beginPath(); ctx.rect(m.l, m.t, pw, ph); ctx.clip();
  for (const b of spec.bands || []) {
    ctx.fillStyle = b.color || "rgba(230,160,0,0.25)";
    const a = sx(b.x0), c = sx(b.x1);
    ctx.fillRect(Math.min(a, c), m.t, Math.max(2, Math.abs(c - a)), ph);
  }
  let drawn = 0;
  (spec.series || []).forEach((s, k) => {
    ctx.strokeStyle = s.color || PLOT_COLORS[k % PLOT_COLORS.length];
    ctx.lineWidth = s.width || 1.5;
    ctx.setLineDash(s.dash || []);
    ctx.beginPath();
    let pen = false;
    for (let i = 0; i < s.x.length; i++) {
      const xv = s.x[i], yv = s.y[i];
      if (!Number.isFinite(xv) || !Number.isFinite(yv) || (spec.xlog && xv <= 0) || (spec.ylog && yv <= 0)) { pen = false; continue; }
      const X = sx(xv), Y = sy(yv);
      if (pen) ctx.lineTo(X, Y); else ctx.moveTo(X, Y);
      pen = true;
      drawn++;
    }
    ctx.stroke();
  });
  ctx.setLineDash([]);
  for (const p of spec.points || []) {
    const X = sx(p.x), Y = sy(p.y);
    ctx.strokeStyle = p.color || "#000";
    ctx.lineWidth = 2;
    ctx.beginPath();
    if (p.shape === "x") { ctx.moveTo(X - 5, Y - 5); ctx.lineTo(X + 5, Y + 5); ctx.moveTo(X + 5, Y - 5); ctx.lineTo(X - 5, Y + 5); }
    else { ctx.arc(X, Y, 5, 0, 2 * Math.PI); }
    ctx.stroke();
    drawn++;
  }
  for (const v of spec.vlines || []) {
    ctx.strokeStyle = v.color || "#888"; ctx.lineWidth = 1.5; ctx.setLineDash([5, 4]);
    ctx.beginPath(); ctx.moveTo(sx(v.x), m.t); ctx.lineTo(sx(v.x), m.t + ph); ctx.stroke(); ctx.setLineDash([]);
  }
  if (Number.isFinite(spec.cursor)) {
    ctx.strokeStyle = "#111"; ctx.lineWidth = 1;
    ctx.beginPath(); ctx.moveTo(sx(spec.cursor), m.t); ctx.lineTo(sx(spec.cursor), m.t + ph); ctx.stroke();
  }
  ctx.restore();

  // Legend: a boxed column in a free corner, or rows of entries above the frame.
  if (legend) {
    ctx.font = "11px system-ui, sans-serif";
    if (legend.place !== "above") {
      ctx.fillStyle = "rgba(255,255,255,0.85)";
      ctx.fillRect(legend.x, legend.y, legend.w, legend.h);
    }
    let x = legend.x + 4, y = legend.y + 4;
    items.forEach(([t, c, kind], k) => {
      if (legend.place === "above" && x > legend.x + 4 && x + itemW[k] > legend.x + legend.w) { x = legend.x + 4; y += 15; }
      ctx.strokeStyle = c; ctx.fillStyle = c; ctx.lineWidth = 2;
      if (kind === "band") ctx.fillRect(x, y + 2, 18, 8);
      else if (kind === "line") { ctx.beginPath(); ctx.moveTo(x, y + 6); ctx.lineTo(x + 18, y + 6); ctx.stroke(); }
      else if (kind === "x") { ctx.beginPath(); ctx.moveTo(x + 5, y + 2); ctx.lineTo(x + 13, y + 10); ctx.moveTo(x + 13, y + 2); ctx.lineTo(x + 5, y + 10); ctx.stroke(); }
      else { ctx.beginPath(); ctx.arc(x + 9, y + 6, 4, 0, 2 * Math.PI); ctx.stroke(); }
      ctx.fillStyle = "#222"; ctx.textAlign = "left"; ctx.textBaseline = "middle";
      ctx.fillText(t, x + 24, y + 6);
      if (legend.place === "above") x += itemW[k] + 8; else y += 15;
    });
    canvas.dataset.legend = [legend.x, legend.y, legend.w, legend.h].map((v) => v.toFixed(1)).join(",");
    canvas.dataset.legendPlace = legend.place;
  } else {
    delete canvas.dataset.legend;
    delete canvas.dataset.legendPlace;
  }
  canvas.dataset.drawn = String(drawn);
  return { sx, sy, legend };
}

// Redraw every plot still on the page at its current size (after a resize: a canvas stretched
// by CSS would blur and keep a legend placed for its old shape).
function replotAll() {
  for (const [canvas, spec] of PLOTTED) {
    if (!canvas.isConnected) PLOTTED.delete(canvas);
    else if (canvas.getClientRects().length) plot(canvas, spec);
  }
}

// Standard normal CDF (Abramowitz & Stegun 7.1.26 for erf, |error| < 1.5e-7: far below what a
// plotted fragility curve can show).
function normalCdf(z) {
  const x = Math.abs(z) / Math.SQRT2;
  const t = 1 / (1 + 0.3275911 * x);
  const y = 1 - (((((1.061405429 * t - 1.453152027) * t) + 1.421413741) * t - 0.284496736) * t + 0.254829592) * t * Math.exp(-x * x);
  return z >= 0 ? 0.5 * (1 + y) : 0.5 * (1 - y);
}

window.ashlarPlot = { plot, replotAll, normalCdf, PLOT_COLORS, fitCanvas };
