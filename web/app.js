// ashlar web page: submit a run or a PGA search, watch the queue, look at the results.
// Plain JavaScript against the service's own HTTP API (openapi.yaml); nothing is fetched from
// anywhere else. Plots come from plot.js (window.ashlarPlot).
"use strict";

const $ = (id) => document.getElementById(id);
const G = 9.80665; // standard gravity, m/s² (the service's "g")
const TOPPLE_RAD = 0.5236; // 30°: docs/format.md §3's toppled threshold on |rotation|
// Speed above which a block is drawn as moving: 5 mm/s (at the centroid, or at the block's
// corners for rotation) is well above the numerical creep of a block at rest and well below
// any rocking or sliding worth seeing.
const MOVING_SPEED = 0.005;
const MAX_STREAMS = 4; // SSE connections held at once (browsers allow ~6 per host over HTTP/1.1)

const state = {
  examples: [],
  scene: null, // the scene JSON to submit
  sceneSource: "",
  records: [], // [{name, format, content}]
  jobs: new Map(), // id -> job JSON
  order: [], // ids, newest first
  streams: new Map(), // id -> EventSource
  watched: null, // id of the job shown in the result panel
  autoShow: null, // id of the latest job submitted here: shown when it finishes
  finished: new Set(), // ids whose end has been handled (see finished()), so it happens once
  inspectSeq: 0,
  showSeq: 0, // bumped by every show(): an older show() still waiting on the server gives up
  view: null, // the run being animated
};

// ---------- helpers ----------

async function api(method, url, body) {
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.headers["Content-Type"] = "application/json";
    init.body = JSON.stringify(body);
  }
  const r = await fetch(url, init);
  const ct = r.headers.get("content-type") || "";
  let data = null;
  if (ct.includes("json")) data = await r.json();
  else data = await r.text();
  if (!r.ok) {
    const problem = data && typeof data === "object" ? data : { status: r.status, title: r.statusText, detail: String(data) };
    const err = new Error(problem.detail || problem.title || `HTTP ${r.status}`);
    err.problem = problem;
    throw err;
  }
  return data;
}

function fmt(v, digits = 3) {
  if (v === null || v === undefined || Number.isNaN(v)) return "–";
  if (typeof v !== "number") return String(v);
  if (v === 0) return "0";
  const a = Math.abs(v);
  if (a >= 1e5 || a < 1e-3) return v.toExponential(digits - 1);
  return Number(v.toPrecision(digits)).toString();
}

function el(tag, attrs = {}, ...children) {
  const e = document.createElement(tag);
  for (const [k, v] of Object.entries(attrs)) {
    if (k === "class") e.className = v;
    else if (k === "text") e.textContent = v;
    else if (k.startsWith("on")) e.addEventListener(k.slice(2), v);
    else if (v !== undefined && v !== null && v !== false) e.setAttribute(k, v === true ? "" : v);
  }
  for (const c of children) if (c !== null && c !== undefined) e.append(c);
  return e;
}

function radio(name) {
  const r = document.querySelector(`input[name="${name}"]:checked`);
  return r ? r.value : "";
}

function readFile(file) {
  return new Promise((resolve, reject) => {
    const fr = new FileReader();
    fr.onload = () => resolve(String(fr.result));
    fr.onerror = () => reject(fr.error);
    fr.readAsText(file);
  });
}

function formatFromName(name) {
  const n = name.toLowerCase();
  if (n.endsWith(".at2")) return "at2";
  if (n.endsWith(".csv")) return "csv";
  if (n.endsWith(".v1") || n.endsWith(".v2")) return "cosmos";
  if (n.endsWith(".asc")) return "esm";
  if (n.endsWith(".json")) return "json";
  return "";
}

// ---------- field errors ----------

// JSON pointer prefixes of the request bodies → the error slot next to the field.
const POINTER_SLOTS = [
  ["/scene/control/duration", "duration"],
  ["/scene/control/model", "model"],
  ["/scene", "scene"],
  ["/motion/scale", "scale"],
  ["/motions", "motion"],
  ["/motion", "motion"],
  ["/criterion", "criterion"],
  ["/range/min", "range-min"],
  ["/range/max", "range-max"],
  ["/range", "range-min"],
  ["/tolerance", "tolerance"],
  ["/scan_points", "scan-points"],
];

function slotInput(slot) {
  switch (slot) {
    case "duration": return $("duration");
    case "model": return $("model");
    case "scene": return state.sceneSource === "file" ? $("scene-file") : $("scene-example");
    case "scale": return $("scale-value");
    case "motion": return radio("motion-source") === "pulse" ? $("pulse-amplitude") : $("record-file");
    case "criterion": return $("criterion-kind");
    case "range-min": return $("range-min");
    case "range-max": return $("range-max");
    case "tolerance": return $("tolerance");
    case "scan-points": return $("scan-points");
    default: return null;
  }
}

function slotFor(pointer) {
  if (typeof pointer !== "string") return "submit";
  for (const [p, slot] of POINTER_SLOTS) if (pointer === p || pointer.startsWith(p + "/")) return slot;
  return "submit";
}

function clearErrors(slots) {
  for (const e of document.querySelectorAll(".field-error")) {
    const slot = e.id.replace(/-error$/, "");
    if (!slots || slots.includes(slot)) e.textContent = "";
  }
  for (const e of document.querySelectorAll("[aria-invalid=true]")) {
    e.removeAttribute("aria-invalid");
    e.removeAttribute("aria-describedby");
  }
}

function showFieldError(slot, text, focus = true) {
  const box = $(`${slot}-error`) || $("submit-error");
  box.textContent = text;
  const input = slotInput(slot);
  if (input) {
    input.setAttribute("aria-invalid", "true");
    input.setAttribute("aria-describedby", box.id);
    if (focus) input.focus();
  }
}

// A problem+json answer → next to the field it names. `base` prefixes pointers of bodies that
// are a part of the job request (the inspect endpoint takes the motion alone).
function showProblem(err, base = "", focus = true) {
  const p = err.problem || { detail: err.message };
  let detail = p.detail || p.title || err.message;
  const pointer = typeof p.pointer === "string" ? base + p.pointer : undefined;
  // Name the block a /scene/blocks/N pointer refers to.
  const m = pointer && pointer.match(/^\/scene\/blocks\/(\d+)/);
  if (m && state.scene && Array.isArray(state.scene.blocks) && state.scene.blocks[+m[1]]) {
    detail += ` (block "${state.scene.blocks[+m[1]].id}")`;
  }
  showFieldError(slotFor(pointer), detail, focus);
}

// ---------- scene ----------

function setScene(scene, source, label) {
  state.scene = scene;
  state.sceneSource = source;
  const blocks = Array.isArray(scene.blocks) ? scene.blocks : [];
  const free = blocks.filter((b) => !b.fixed && !(scene.excitation && scene.excitation.block === b.id));
  $("scene-info").textContent = `${label}: "${scene.name || "unnamed"}", ${blocks.length} blocks (${free.length} free)` +
    (scene.control && scene.control.duration ? `, ${scene.control.duration} s` : "");
  const sel = $("criterion-block");
  sel.replaceChildren(...free.map((b) => el("option", { value: b.id, text: b.id })));
  drawScenePreview(scene);
}

function drawScenePreview(scene) {
  const c = $("scene-preview");
  const { ctx, w, h } = window.ashlarPlot.fitCanvas(c);
  const blocks = (scene.blocks || []).filter((b) => Array.isArray(b.vertices) && b.vertices.length >= 3);
  const pts = blocks.flatMap((b) => b.vertices).filter((v) => Array.isArray(v) && v.every(Number.isFinite));
  if (!pts.length) return;
  const xs = pts.map((p) => p[0]), ys = pts.map((p) => p[1]);
  const [x0, x1, y0, y1] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
  const k = Math.min((w - 20) / Math.max(x1 - x0, 1e-9), (h - 20) / Math.max(y1 - y0, 1e-9));
  const ox = (w - k * (x1 - x0)) / 2, oy = (h - k * (y1 - y0)) / 2;
  for (const b of blocks) {
    ctx.beginPath();
    b.vertices.forEach((v, i) => {
      const X = ox + k * (v[0] - x0), Y = h - oy - k * (v[1] - y0);
      if (i === 0) ctx.moveTo(X, Y); else ctx.lineTo(X, Y);
    });
    ctx.closePath();
    ctx.fillStyle = b.fixed ? "#d6d3cc" : "#efe6d2";
    ctx.fill();
    ctx.strokeStyle = b.fixed ? "#777" : "#8a6d3b";
    ctx.lineWidth = 1.5;
    ctx.stroke();
  }
}

async function onSceneExample() {
  const name = $("scene-example").value;
  clearErrors(["scene"]);
  if (!name) return;
  $("scene-file").value = "";
  try {
    setScene(await api("GET", `/v1/examples/${encodeURIComponent(name)}`), "example", "Example");
  } catch (e) {
    showProblem(e);
  }
}

async function onSceneFile() {
  const f = $("scene-file").files[0];
  clearErrors(["scene"]);
  if (!f) return;
  $("scene-example").value = "";
  const text = await readFile(f);
  try {
    const v = JSON.parse(text);
    if (!v || typeof v !== "object" || Array.isArray(v)) throw new Error("expected a JSON object");
    setScene(v, "file", f.name);
  } catch (e) {
    state.scene = null;
    state.sceneSource = "file";
    $("scene-info").textContent = "";
    showFieldError("scene", `${f.name}: not a scene: ${e.message}`);
  }
}

// ---------- motion ----------

async function onRecordFiles() {
  clearErrors(["motion"]);
  const files = Array.from($("record-file").files);
  state.records = [];
  for (const f of files) {
    const content = await readFile(f);
    state.records.push({ name: f.name, content, format: formatFromName(f.name) });
  }
  $("record-info").textContent = files.length > 1
    ? `${files.length} records: a single run uses the first; a PGA search uses all of them (fragility curve).`
    : "";
  scheduleInspect();
}

// One record → a docs/format.md §2 component.
function recordComponent(rec) {
  const format = $("record-format").value || rec.format;
  if (format === "json") {
    const v = JSON.parse(rec.content);
    return { motion: v };
  }
  if (!format) throw Object.assign(new Error(`${rec.name}: cannot tell the format from the name; choose it`), { slot: "motion" });
  const c = { format, content: rec.content };
  const units = $("record-units").value;
  if (units && format === "csv") c.units = units;
  return { component: c };
}

function scaleSpec() {
  const mode = radio("scale-mode");
  const raw = $("scale-value").value;
  if (mode === "none") return undefined;
  const v = Number(raw);
  if (raw === "" || !Number.isFinite(v)) throw Object.assign(new Error("enter a number"), { slot: "scale" });
  return mode === "factor" ? { factor: v } : { target_pga: v, units: $("scale-units").value };
}

// The motions of the form (several only for record files), each a docs/format.md §2 object.
async function buildMotions(withScale) {
  const src = radio("motion-source");
  let motions;
  if (src === "none") return [null];
  if (src === "pulse") {
    const num = (id) => Number($(id).value);
    motions = [{ horizontal: { pulse: { shape: $("pulse-shape").value, amplitude: num("pulse-amplitude"), period: num("pulse-period"), cycles: num("pulse-cycles"), units: $("pulse-units").value } } }];
  } else if (src === "example") {
    motions = [await api("GET", "/v1/examples/half-sine-pulse")];
  } else {
    if (!state.records.length) throw Object.assign(new Error("choose a record file (or another source)"), { slot: "motion" });
    motions = state.records.map((r) => {
      const c = recordComponent(r);
      return c.motion ? c.motion : { horizontal: c.component };
    });
  }
  if (withScale) {
    const s = scaleSpec();
    if (s) for (const m of motions) m.scale = s;
  }
  return motions;
}

let inspectTimer = null;
function scheduleInspect() {
  clearTimeout(inspectTimer);
  inspectTimer = setTimeout(inspect, 250);
}

async function inspect() {
  const seq = ++state.inspectSeq;
  clearErrors(["motion", "scale"]);
  let motion;
  try {
    const ms = await buildMotions(radio("analysis") === "run");
    motion = ms[0];
  } catch (e) {
    if (e.slot && radio("motion-source") !== "record") showFieldError(e.slot, e.message, false);
    $("record-view").hidden = true;
    $("record-empty").hidden = false;
    return;
  }
  if (!motion || !motion.horizontal) {
    $("record-view").hidden = true;
    $("record-empty").hidden = false;
    return;
  }
  try {
    const im = await api("POST", "/v1/motions/inspect", motion);
    if (seq !== state.inspectSeq) return;
    showMeasures(im);
  } catch (e) {
    if (seq !== state.inspectSeq) return;
    $("record-view").hidden = true;
    $("record-empty").hidden = false;
    showProblem(e, "/motion", false);
  }
}

function showMeasures(im) {
  $("record-empty").hidden = true;
  $("record-view").hidden = false;
  $("record-provenance").textContent = im.provenance + (im.scale !== 1 ? `, scaled ×${fmt(im.scale, 4)}` : "");
  const rows = [
    ["PGA", `${fmt(im.pga)} m/s² (${fmt(im.pga / G)} g)`],
    ["PGV", `${fmt(im.pgv)} m/s`],
    ["PGD", `${fmt(im.pgd)} m`],
    ["Arias intensity", `${fmt(im.arias_intensity)} m/s`],
    ["Significant duration D5–95", `${fmt(im.significant_duration_5_95)} s`],
    ["CAV", `${fmt(im.cav)} m/s`],
    ["Mean period Tm", `${fmt(im.mean_period)} s`],
    ["Samples × step", `${im.npts} × ${fmt(im.dt, 4)} s = ${fmt(im.duration, 4)} s`],
    ["Original units", im.original_units],
  ];
  $("record-measures").tBodies[0].replaceChildren(...rows.map(([k, v]) => el("tr", {}, el("td", { text: k }), el("td", { text: v }))));
  const { plot } = window.ashlarPlot;
  plot($("record-accel"), {
    title: "Ground acceleration", xlabel: "time (s)", ylabel: "m/s²",
    series: [{ x: im.series.time, y: im.series.acceleration, width: 1 }],
  });
  const sp = im.spectrum;
  plot($("record-spectrum"), {
    title: `Response spectrum (${Math.round(sp.damping * 100)} % damping)`, xlabel: "period (s)", ylabel: "PSA (g)", xlog: true,
    series: [{ x: sp.periods, y: sp.psa.map((v) => v / G), width: 2 }],
  });
}

// ---------- submit ----------

async function onSubmit(ev) {
  ev.preventDefault();
  clearErrors();
  $("submit-status").textContent = "";
  if (!state.scene) {
    showFieldError("scene", "Choose a bundled example or load a scene file.");
    return;
  }
  const kind = radio("analysis");
  let motions;
  try {
    motions = await buildMotions(kind === "run");
  } catch (e) {
    showFieldError(e.slot || "submit", e.message);
    return;
  }
  const scene = JSON.parse(JSON.stringify(state.scene));
  const dur = $("duration").value.trim();
  if (dur !== "") {
    const d = Number(dur);
    if (!Number.isFinite(d) || d <= 0) { showFieldError("duration", "The duration must be a number of seconds > 0."); return; }
    scene.control = Object.assign({}, scene.control || {}, { duration: d });
  }
  const model = $("model").value;
  if (model !== "") scene.control = Object.assign({}, scene.control || {}, { model });
  let url, body;
  if (kind === "run") {
    url = "/v1/jobs";
    body = { scene };
    if (motions[0]) body.motion = motions[0];
  } else {
    url = "/v1/pga-searches";
    const block = $("criterion-block").value;
    const ck = $("criterion-kind").value;
    const criterion = ck === "toppled" ? `toppled:${block}` : `${ck}:${block}:${$("criterion-value").value}`;
    body = { scene, criterion, range: { min: Number($("range-min").value), max: Number($("range-max").value), units: $("range-units").value } };
    if ($("tolerance").value !== "") body.tolerance = Number($("tolerance").value);
    if ($("scan-points").value !== "") body.scan_points = Number($("scan-points").value);
    if (!motions[0]) { showFieldError("motion", "A PGA search needs a ground motion to scale."); return; }
    if (motions.length > 1) body.motions = motions;
    else body.motion = motions[0];
  }
  $("submit-button").disabled = true;
  $("submit-status").textContent = "Submitting…";
  try {
    const acc = await api("POST", url, body);
    $("submit-status").textContent = `Queued ${acc.kind === "run" ? "run" : "PGA search"} ${acc.id.slice(0, 8)}.`;
    // Only the latest submission takes the result panel when it finishes: an earlier job
    // that ends later (a cancelled run writing its outputs) must not replace it.
    state.autoShow = acc.id;
    const job = await api("GET", acc.links.self);
    upsertJob(job);
    renderJobs();
    if (TERMINAL.has(job.status)) finished(job.id);
    else follow(job);
  } catch (e) {
    $("submit-status").textContent = "";
    showProblem(e);
  } finally {
    $("submit-button").disabled = false;
  }
}

// ---------- queue ----------

const TERMINAL = new Set(["succeeded", "failed", "cancelled"]);

function upsertJob(job) {
  const known = state.jobs.get(job.id);
  state.jobs.set(job.id, Object.assign(known || {}, job));
  if (!known) state.order.unshift(job.id);
}

async function refreshJobs() {
  try {
    const r = await api("GET", "/v1/jobs?limit=30");
    const ids = [];
    const ended = [];
    for (const j of r.jobs) {
      ids.push(j.id);
      const stream = state.streams.has(j.id);
      const known = state.jobs.get(j.id);
      if (TERMINAL.has(j.status) && (state.autoShow === j.id || (known && !TERMINAL.has(known.status)))) ended.push(j.id);
      // A live stream is fresher than the listing for progress.
      if (stream && known) Object.assign(known, { ...j, progress: Math.max(known.progress, j.progress), status: TERMINAL.has(j.status) ? j.status : known.status });
      else state.jobs.set(j.id, Object.assign(known || {}, j));
    }
    const extra = state.order.filter((id) => !ids.includes(id));
    state.order = ids.concat(extra);
    renderJobs();
    for (const id of ended) finished(id);
    for (const j of r.jobs) if (!TERMINAL.has(j.status)) follow(j);
  } catch (e) {
    console.warn("job list:", e);
  }
}

// Follow a job's progress with server-sent events (at most MAX_STREAMS at once; the rest are
// refreshed by the periodic listing).
function follow(job) {
  if (TERMINAL.has(job.status) || state.streams.has(job.id) || state.streams.size >= MAX_STREAMS) return;
  const es = new EventSource(job.links.events);
  state.streams.set(job.id, es);
  const update = (ev) => {
    const d = JSON.parse(ev.data);
    const j = state.jobs.get(d.id);
    if (j) { j.status = d.status; j.progress = d.progress; }
    renderJobRow(d.id);
  };
  es.addEventListener("progress", update);
  es.addEventListener("end", async (ev) => {
    update(ev);
    es.close();
    state.streams.delete(job.id);
    try {
      const fresh = await api("GET", job.links.self);
      upsertJob(fresh);
      renderJobRow(fresh.id);
    } catch (e) { console.warn(e); }
    finished(job.id);
  });
  es.onerror = () => {
    // The server closed the stream (shutdown) or the network failed: fall back to polling.
    if (es.readyState === EventSource.CLOSED) state.streams.delete(job.id);
  };
}

// A job has been seen in a final state: by its stream's end event, by the periodic listing, or
// by the read right after submitting (a short job can finish before the page follows it, and
// then it never gets a stream). The latest submission, or the job on view, is shown, once.
function finished(id) {
  if (state.finished.has(id)) return;
  state.finished.add(id);
  if (state.autoShow !== id && state.watched !== id) return;
  if (state.autoShow === id) state.autoShow = null;
  show(id);
}

function renderJobs() {
  const body = $("jobs-body");
  // Rows whose state is unchanged are updated in place; the table is rebuilt only when a job
  // appears or changes state (or the watched job changes).
  const shown = [...body.rows].map((r) => `${r.id}:${r.dataset.status}:${r.classList.contains("watched")}`).join();
  const want = state.order.filter((id) => state.jobs.has(id)).map((id) => `job-${id}:${state.jobs.get(id).status}:${state.watched === id}`).join();
  if (shown === want) {
    for (const id of state.order) renderJobRow(id);
    return;
  }
  // Keep keyboard focus on the same button across the re-render.
  const a = document.activeElement;
  const keep = a && body.contains(a) ? [a.closest("tr").id, a.dataset.action] : null;
  const rows = state.order.map((id) => jobRow(state.jobs.get(id))).filter(Boolean);
  body.replaceChildren(...rows);
  $("jobs-empty").hidden = rows.length > 0;
  if (keep) {
    const b = document.querySelector(`#${CSS.escape(keep[0])} [data-action="${keep[1]}"]`);
    if (b) b.focus();
  }
}

function renderJobRow(id) {
  const old = document.getElementById(`job-${id}`);
  const j = state.jobs.get(id);
  if (!j) return;
  // Same state: move the bar in place (re-creating the row would pull its buttons from under
  // the pointer at every progress event).
  if (old && old.dataset.status === j.status) {
    const pct = Math.round((j.progress || 0) * 100);
    const bar = old.querySelector("progress");
    if (bar) { bar.value = pct; old.querySelector(".pct").textContent = `${pct} %`; }
    return;
  }
  const fresh = jobRow(j);
  if (old) {
    // Keep keyboard focus on the same button across the re-render.
    const focused = document.activeElement && old.contains(document.activeElement) ? document.activeElement.dataset.action : null;
    old.replaceWith(fresh);
    if (focused) { const b = fresh.querySelector(`[data-action="${focused}"]`); if (b) b.focus(); }
  } else renderJobs();
}

function jobRow(j) {
  if (!j) return null;
  const pct = Math.round((j.progress || 0) * 100);
  const label = j.kind === "run" ? "run" : "PGA search";
  const actions = el("td", { class: "actions" });
  const viewable = j.status === "succeeded" || (j.kind === "run" && j.status === "cancelled" && j.started_at) || j.status === "failed";
  if (viewable) actions.append(el("button", { type: "button", class: "secondary", "data-action": "view", "aria-label": `View ${label} ${j.id.slice(0, 8)}`, onclick: () => show(j.id), text: "View" }));
  if (!TERMINAL.has(j.status)) actions.append(el("button", { type: "button", class: "danger", "data-action": "cancel", "aria-label": `Cancel ${label} ${j.id.slice(0, 8)}`, onclick: () => cancel(j.id), text: "Cancel" }));
  const when = new Date(j.created_at);
  return el("tr", { id: `job-${j.id}`, class: state.watched === j.id ? "watched" : "", "data-status": j.status },
    el("td", { title: `${j.id}\n${(j.motion && j.motion.provenance) || ""}` }, el("code", { text: j.id.slice(0, 8) })),
    el("td", { text: label }),
    el("td", {}, el("span", { class: `state ${j.status}`, text: j.status })),
    el("td", {}, el("progress", { max: "100", value: String(pct), "aria-label": `Progress of ${j.id.slice(0, 8)}` }), " ", el("span", { class: "pct", text: `${pct} %` })),
    el("td", { text: isNaN(when) ? "" : when.toLocaleTimeString() }),
    actions);
}

async function cancel(id) {
  const j = state.jobs.get(id);
  if (!j) return;
  try {
    const r = await api("POST", j.links.cancel);
    upsertJob(r);
  } catch (e) {
    alert(`Cancel: ${e.message}`);
  }
  renderJobRow(id);
}

// ---------- results ----------

async function show(id) {
  const seq = ++state.showSeq;
  const current = () => seq === state.showSeq;
  state.watched = id;
  renderJobs();
  stopPlaying();
  const j = await api("GET", state.jobs.get(id).links.self);
  if (!current()) return;
  upsertJob(j);
  $("result").hidden = false;
  $("run-view").hidden = true;
  $("pga-view").hidden = true;
  const head = $("result-head");
  const kind = j.kind === "run" ? "Run" : "PGA search";
  head.textContent = `${kind} ${j.id.slice(0, 8)}: ${j.status}` + (j.motion ? ` · motion: ${j.motion.provenance}, PGA ${fmt(j.motion.pga)} m/s² (${fmt(j.motion.pga / G)} g)` : "");
  if (j.status === "failed") {
    head.textContent += ` · ${j.error || "failed"}`;
    return;
  }
  try {
    if (j.kind === "run") await showRun(j, current);
    else showPga(j);
  } catch (e) {
    if (!current()) return;
    // E.g. a run cancelled before it started has no histories.
    $("run-view").hidden = true;
    head.textContent += ` · ${e.message}`;
  }
  if (current()) $("result").scrollIntoView({ behavior: "smooth", block: "start" });
}

async function showRun(j, current) {
  const [geo, hist, ground] = await Promise.all([
    api("GET", `/v1/jobs/${j.id}/scene`),
    api("GET", j.links.histories),
    api("GET", `/v1/jobs/${j.id}/ground`),
  ]);
  if (!current()) return;
  $("run-view").hidden = false;
  state.view = buildView(j, geo, hist, ground);
  const slider = $("time-slider");
  slider.max = String(Math.max(0, hist.time.length - 1));
  slider.value = slider.max; // open on the final state
  renderSummary(j);
  renderDownloads(j);
  drawFrame(Number(slider.value));
}

function rot(p, c, th) {
  const dx = p[0] - c[0], dy = p[1] - c[1], cs = Math.cos(th), sn = Math.sin(th);
  return [c[0] + cs * dx - sn * dy, c[1] + sn * dx + cs * dy];
}

function interp(ts, ys, t) {
  if (!ts.length) return 0;
  if (t <= ts[0]) return ys[0];
  if (t >= ts[ts.length - 1]) return ys[ys.length - 1];
  let lo = 0, hi = ts.length - 1;
  while (hi - lo > 1) { const mid = (lo + hi) >> 1; if (ts[mid] <= t) lo = mid; else hi = mid; }
  const f = (t - ts[lo]) / (ts[hi] - ts[lo]);
  return ys[lo] + f * (ys[hi] - ys[lo]);
}

// Everything the animation needs, computed once: per frame and block the outline's placement
// and the state shown by its colour.
function buildView(job, geo, hist, ground) {
  const time = hist.time;
  const blocks = geo.blocks.map((b) => {
    const h = hist.blocks[b.id];
    const radius = Math.max(...b.vertices.map((v) => Math.hypot(v[0] - b.centroid[0], v[1] - b.centroid[1])));
    let states = null;
    if (h) {
      states = time.map((t, i) => {
        if (Math.abs(h.rotation[i]) > TOPPLE_RAD) return "toppled";
        const k = i > 0 ? i - 1 : Math.min(1, time.length - 1);
        const dt = Math.abs(time[i] - time[k]) || 1;
        const v = Math.hypot(h.x[i] - h.x[k], h.y[i] - h.y[k]) / dt + (Math.abs(h.rotation[i] - h.rotation[k]) * radius) / dt;
        return v > MOVING_SPEED ? "moving" : "rest";
      });
    }
    return { ...b, h, states };
  });
  // Driven blocks follow the ground displacement (absolute results).
  const groundAt = (t) => interp(ground.time, ground.displacement, t);
  const place = (b, i) => {
    if (b.h) return b.vertices.map((v) => { const p = rot(v, b.centroid, b.h.rotation[i]); return [p[0] + b.h.x[i], p[1] + b.h.y[i]]; });
    if (b.driven) { const d = groundAt(time[i] || 0); return b.vertices.map((v) => [v[0] + d, v[1]]); }
    return b.vertices;
  };
  // World bounds over the whole run, so that the view does not jump while playing.
  let [x0, x1, y0, y1] = [Infinity, -Infinity, Infinity, -Infinity];
  const stride = Math.max(1, Math.floor(time.length / 400));
  for (let i = 0; i < Math.max(1, time.length); i += stride) {
    for (const b of blocks) for (const p of place(b, Math.min(i, time.length - 1))) {
      x0 = Math.min(x0, p[0]); x1 = Math.max(x1, p[0]); y0 = Math.min(y0, p[1]); y1 = Math.max(y1, p[1]);
    }
  }
  for (const b of blocks) for (const p of place(b, time.length - 1)) { x0 = Math.min(x0, p[0]); x1 = Math.max(x1, p[0]); y0 = Math.min(y0, p[1]); y1 = Math.max(y1, p[1]); }
  const ids = blocks.filter((b) => b.h).map((b) => b.id);
  const last = time.length ? time[time.length - 1] : 0;
  const gi = ground.time.findIndex((t) => t > last + 1e-9);
  const gEnd = gi < 0 ? ground.time.length : gi;
  return { job, geo, hist, ground: { time: ground.time.slice(0, gEnd), acc: ground.acceleration.slice(0, gEnd) }, blocks, place, bounds: [x0, x1, y0, y1], ids, frame: 0, lastPlotFrame: -1 };
}

function niceLength(x) {
  const p = Math.pow(10, Math.floor(Math.log10(x)));
  const m = x / p;
  return (m < 2 ? 1 : m < 5 ? 2 : 5) * p;
}

const STATE_COLORS = { rest: "#2e7d32", moving: "#e08a00", toppled: "#c62828" };

function drawFrame(i) {
  const v = state.view;
  if (!v) return;
  const time = v.hist.time;
  i = Math.max(0, Math.min(i, time.length - 1));
  v.frame = i;
  const t = time[i] || 0;
  $("time-label").value = `t = ${t.toFixed(2)} s`;
  $("time-label").textContent = `t = ${t.toFixed(2)} s`;
  const c = $("anim");
  const { ctx, w, h } = window.ashlarPlot.fitCanvas(c);
  const [x0, x1, y0, y1] = v.bounds;
  const pad = 30;
  const k = Math.min((w - 2 * pad) / Math.max(x1 - x0, 1e-9), (h - 2 * pad - 20) / Math.max(y1 - y0, 1e-9));
  const ox = (w - k * (x1 - x0)) / 2, oy = (h - 20 - k * (y1 - y0)) / 2;
  const X = (x) => ox + k * (x - x0), Y = (y) => h - 20 - oy - k * (y - y0);
  for (const b of v.blocks) {
    const pts = v.place(b, i);
    ctx.beginPath();
    pts.forEach((p, n) => (n ? ctx.lineTo(X(p[0]), Y(p[1])) : ctx.moveTo(X(p[0]), Y(p[1]))));
    ctx.closePath();
    const st = b.states ? b.states[i] : null;
    ctx.fillStyle = st ? "#f3ead7" : "#dcd9d2";
    ctx.fill();
    ctx.lineWidth = st ? 2.5 : 1.5;
    ctx.strokeStyle = st ? STATE_COLORS[st] : "#777";
    ctx.stroke();
    if (st) {
      const cpos = [b.centroid[0] + b.h.x[i], b.centroid[1] + b.h.y[i]];
      ctx.fillStyle = "#333"; ctx.font = "12px system-ui, sans-serif"; ctx.textAlign = "center"; ctx.textBaseline = "middle";
      ctx.fillText(b.id, X(cpos[0]), Y(cpos[1]));
    }
  }
  // Scale bar and time.
  const len = niceLength((x1 - x0) / 4 || 1);
  ctx.strokeStyle = "#222"; ctx.lineWidth = 2;
  ctx.beginPath(); ctx.moveTo(12, h - 10); ctx.lineTo(12 + k * len, h - 10); ctx.moveTo(12, h - 14); ctx.lineTo(12, h - 6); ctx.moveTo(12 + k * len, h - 14); ctx.lineTo(12 + k * len, h - 6); ctx.stroke();
  ctx.fillStyle = "#222"; ctx.font = "12px system-ui, sans-serif"; ctx.textAlign = "left"; ctx.textBaseline = "bottom";
  ctx.fillText(`${len} m`, 18 + k * len, h - 4);
  ctx.textAlign = "right"; ctx.textBaseline = "top";
  ctx.fillText(`t = ${t.toFixed(2)} s`, w - 8, 6);
  if (v.lastPlotFrame !== i) { drawPlots(t); v.lastPlotFrame = i; }
}

function drawPlots(cursor) {
  const v = state.view;
  const { plot, PLOT_COLORS } = window.ashlarPlot;
  const time = v.hist.time;
  const series = (f) => v.ids.map((id, k) => ({ x: time, y: f(v.hist.blocks[id]), label: id, color: PLOT_COLORS[k % PLOT_COLORS.length] }));
  plot($("plot-displacement"), { title: "Horizontal displacement of each block (centroid)", xlabel: "time (s)", ylabel: "x (m)", series: series((h) => h.x), cursor, xrange: [time[0] || 0, time[time.length - 1] || 1] });
  plot($("plot-rotation"), { title: "Rotation of each block (counter-clockwise +)", xlabel: "time (s)", ylabel: "θ (°)", series: series((h) => h.rotation.map((r) => (r * 180) / Math.PI)), cursor, xrange: [time[0] || 0, time[time.length - 1] || 1] });
  plot($("plot-ground"), { title: "Ground acceleration", xlabel: "time (s)", ylabel: "m/s²", series: [{ x: v.ground.time, y: v.ground.acc, label: "horizontal", color: "#6a3d9a", width: 1 }], cursor, xrange: [time[0] || 0, time[time.length - 1] || 1] });
}

let playing = null;
function stopPlaying() {
  if (playing) cancelAnimationFrame(playing.raf);
  playing = null;
  $("play").textContent = "Play";
  $("play").setAttribute("aria-pressed", "false");
}

function togglePlay() {
  const v = state.view;
  if (!v) return;
  if (playing) { stopPlaying(); return; }
  const time = v.hist.time;
  if (v.frame >= time.length - 1) v.frame = 0;
  playing = { t0: performance.now(), sim0: time[v.frame] || 0, raf: 0 };
  $("play").textContent = "Pause";
  $("play").setAttribute("aria-pressed", "true");
  const step = (now) => {
    if (!playing) return;
    const sim = playing.sim0 + ((now - playing.t0) / 1000) * Number($("speed").value);
    let i = v.frame;
    while (i < time.length - 1 && time[i + 1] <= sim) i++;
    $("time-slider").value = String(i);
    drawFrame(i);
    if (i >= time.length - 1) { stopPlaying(); return; }
    playing.raf = requestAnimationFrame(step);
  };
  playing.raf = requestAnimationFrame(step);
}

function renderSummary(j) {
  const s = j.summary;
  const box = $("summary");
  if (!s) { box.replaceChildren(el("p", { class: "info", text: "No summary was recorded." })); return; }
  const deg = (r) => (r === null || r === undefined ? "–" : fmt((r * 180) / Math.PI));
  const facts = el("p", {},
    "Failure mode: ", el("span", { class: `badge ${s.failure_mode}`, id: "failure-mode", text: s.failure_mode }),
    ` · ${s.completed ? "completed" : "stopped early"} at t = ${fmt(s.simulated_time)} s · ${s.steps} steps in ${fmt(s.wall_time_s)} s · PGA ${fmt(s.pga)} m/s² (${fmt(s.pga / G)} g)` +
      (s.model ? ` · model: ${s.model}` : ""));
  const head = el("tr", {}, ...["Block", "max displacement (m)", "final displacement x, y (m)", "max |rotation| (°)", "final rotation (°)", "sliding distance (m)", "toppled"].map((t) => el("th", { scope: "col", text: t })));
  const rows = (s.blocks || []).map((b) => el("tr", {},
    el("th", { scope: "row", text: b.id }),
    el("td", { class: "num", text: fmt(b.max_displacement) }),
    el("td", { class: "num", text: Array.isArray(b.final_displacement) ? b.final_displacement.map((x) => fmt(x)).join(", ") : "–" }),
    el("td", { class: "num", text: deg(b.max_rotation) }),
    el("td", { class: "num", text: deg(b.final_rotation) }),
    el("td", { class: "num", text: fmt(b.sliding_distance) }),
    el("td", { text: b.toppled ? "yes" : "no" })));
  const table = el("table", { class: "peaks" }, el("thead", {}, head), el("tbody", {}, ...rows));
  const diag = s.diagnostics ? el("p", { class: "info", text: "Diagnostics: " + Object.entries(s.diagnostics).map(([k, v]) => `${k.replace(/_/g, " ")} ${typeof v === "number" ? fmt(v) : JSON.stringify(v)}`).join(" · ") }) : null;
  box.replaceChildren(facts, table, diag || "");
}

function renderDownloads(j) {
  const mcap = new URL(j.links.trajectory, location.href).href;
  const fox = `https://app.foxglove.dev/?ds=remote-file&ds.url=${encodeURIComponent(mcap)}`;
  $("downloads").replaceChildren(
    el("li", {}, el("a", { href: `${j.links.histories}?format=csv`, download: `histories-${j.id.slice(0, 8)}.csv`, id: "dl-csv", text: "Histories (CSV)" }), " — time (s), x, y (m), rotation (rad) of every free block"),
    el("li", {}, el("a", { href: j.links.trajectory, download: `trajectory-${j.id.slice(0, 8)}.mcap`, id: "dl-mcap", text: "Trajectory (MCAP)" }), " — blocks, ground motion and outlines over time"),
    el("li", {}, el("a", { href: fox, target: "_blank", rel: "noopener", id: "dl-foxglove", text: "Open the trajectory in Foxglove" }), " — needs this server to be reachable from your browser (Foxglove fetches the file)"),
    el("li", {}, el("a", { href: j.links.self, id: "dl-job", text: "Job and summary (JSON)" })));
}

function showPga(j) {
  $("pga-view").hidden = false;
  const r = j.result;
  const box = $("pga-summary");
  const { plot, normalCdf } = window.ashlarPlot;
  if (!r) { box.replaceChildren(el("p", { class: "info", text: "No result was recorded." })); return; }
  const units = r.units || "m/s2";
  const toG = units === "g" ? 1 : units === "cm/s2" || units === "gal" ? 0.01 / G : 1 / G;
  const both = (v) => (v === null || v === undefined ? "–" : `${fmt(v)} ${units}` + (units === "g" ? "" : ` (${fmt(v * toG)} g)`));
  const scanCanvas = $("plot-scan");
  const fragCanvas = $("plot-fragility");
  if (Array.isArray(r.records)) {
    const head = el("tr", {}, ...["Record", "safe PGA", "failing PGA", "runs", "monotonic"].map((t) => el("th", { scope: "col", text: t })));
    const rows = r.records.map((rec) => el("tr", {}, el("th", { scope: "row", text: rec.motion || "" }), el("td", { text: both(rec.safe_pga) }), el("td", { text: both(rec.failing_pga) }), el("td", { class: "num", text: String((rec.runs || []).length) }), el("td", { text: rec.monotonic ? "yes" : "no" })));
    const f = r.fragility;
    box.replaceChildren(
      el("p", {}, `Criterion ${r.criterion}`, f ? ` · fragility: median ${both(f.median)}, β = ${fmt(f.beta)} (${f.method})` : ""),
      el("table", {}, el("thead", {}, head), el("tbody", {}, ...rows)));
    const points = [];
    r.records.forEach((rec, k) => {
      for (const run of rec.runs || []) points.push({ x: run.pga, y: k, color: run.failed ? "#c62828" : "#2e7d32", shape: run.failed ? "x" : "o", label: run.failed ? "failed" : "safe" });
    });
    const brackets = r.records.filter((rec) => rec.safe_pga !== null && rec.failing_pga !== null).map((rec) => ({ x: [rec.safe_pga, rec.failing_pga], y: [r.records.indexOf(rec), r.records.indexOf(rec)], color: "#e0a000", width: 6 }));
    plot(scanCanvas, { title: "Scan points per record (safe ○, failed ×; bracket in orange)", xlabel: `PGA (${units})`, ylabel: "record", series: brackets, points, yrange: [-0.7, r.records.length - 0.3], yticks: r.records.map((rec, k) => [k, rec.motion || String(k + 1)]) });
    if (f && f.median > 0 && f.beta > 0) {
      fragCanvas.hidden = false;
      const all = (f.points || []).map((p) => p.pga).concat(r.records.flatMap((rec) => (rec.runs || []).map((x) => x.pga)));
      const lo = Math.max(Math.min(...all, f.median / 4), 1e-9), hi = Math.max(...all, f.median * 3);
      const xs = Array.from({ length: 200 }, (_, i) => lo + ((hi - lo) * i) / 199);
      plot(fragCanvas, {
        title: "Fragility: probability of meeting the criterion", xlabel: `PGA (${units})`, ylabel: "P(failure)", yrange: [-0.05, 1.05],
        series: [{ x: xs, y: xs.map((a) => normalCdf(Math.log(a / f.median) / f.beta)), label: `lognormal, median ${fmt(f.median)}, β ${fmt(f.beta)}`, color: "#1f6fd1", width: 2 }],
        points: (f.points || []).map((p) => ({ x: p.pga, y: p.failed ? 1 : 0, color: p.failed ? "#c62828" : "#2e7d32", shape: p.failed ? "x" : "o", label: p.failed ? "failed" : "safe" })),
        vlines: [{ x: f.median, color: "#1f6fd1" }],
      });
    } else fragCanvas.hidden = true;
    return;
  }
  fragCanvas.hidden = true;
  box.replaceChildren(el("p", {},
    `Criterion ${r.criterion}: safe up to ${both(r.safe_pga)}, fails from ${both(r.failing_pga)}` +
      ` · ${(r.runs || []).length} runs` + (r.monotonic ? "" : " · not monotonic: a failing amplitude lies below a safe one")));
  const bands = r.safe_pga !== null && r.failing_pga !== null ? [{ x0: r.safe_pga, x1: r.failing_pga, color: "rgba(224,160,0,0.35)", label: "bracket" }] : [];
  plot(scanCanvas, {
    title: "Scan points", xlabel: `PGA (${units})`, ylabel: "failed (1) / safe (0)", yrange: [-0.3, 1.3], bands,
    points: (r.runs || []).map((p) => ({ x: p.pga, y: p.failed ? 1 : 0, color: p.failed ? "#c62828" : "#2e7d32", shape: p.failed ? "x" : "o", label: p.failed ? "failed" : "safe" })),
  });
}

// ---------- wiring ----------

function syncVisibility() {
  const src = radio("motion-source");
  $("record-fields").hidden = src !== "record";
  $("pulse-fields").hidden = src !== "pulse";
  const mode = radio("scale-mode");
  $("scale-row").hidden = mode === "none";
  $("scale-label").textContent = mode === "pga" ? "Target PGA" : "Factor";
  $("scale-units").hidden = mode !== "pga";
  document.querySelector('label[for="scale-units"]').hidden = mode !== "pga";
  const pga = radio("analysis") === "pga";
  $("pga-fields").hidden = !pga;
  // A PGA search scales the record itself: no scale of its own.
  $("scale-mode-row").hidden = pga;
  if (pga) $("scale-row").hidden = true;
  $("criterion-value").disabled = $("criterion-kind").value === "toppled";
}

async function init() {
  try {
    const ex = await api("GET", "/v1/examples");
    state.examples = ex.examples;
    for (const e of ex.examples.filter((x) => x.kind === "scene")) $("scene-example").append(el("option", { value: e.name, text: e.title }));
  } catch (e) { console.warn(e); }
  $("scene-example").addEventListener("change", onSceneExample);
  $("scene-file").addEventListener("change", onSceneFile);
  $("record-file").addEventListener("change", onRecordFiles);
  for (const id of ["record-format", "record-units", "pulse-shape", "pulse-amplitude", "pulse-units", "pulse-period", "pulse-cycles", "scale-value", "scale-units"]) {
    $(id).addEventListener("input", scheduleInspect);
    $(id).addEventListener("change", scheduleInspect);
  }
  for (const r of document.querySelectorAll('input[name="motion-source"], input[name="scale-mode"], input[name="analysis"]')) {
    r.addEventListener("change", () => { syncVisibility(); scheduleInspect(); });
  }
  $("criterion-kind").addEventListener("change", syncVisibility);
  $("job-form").addEventListener("submit", onSubmit);
  $("play").addEventListener("click", togglePlay);
  $("time-slider").addEventListener("input", () => { stopPlaying(); drawFrame(Number($("time-slider").value)); });
  let resizing = 0;
  window.addEventListener("resize", () => {
    cancelAnimationFrame(resizing);
    resizing = requestAnimationFrame(() => {
      window.ashlarPlot.replotAll();
      if (state.view) { state.view.lastPlotFrame = -1; drawFrame(state.view.frame); }
    });
  });
  syncVisibility();
  await refreshJobs();
  // The listing catches jobs submitted elsewhere and those without a live stream.
  setInterval(() => { if (!document.hidden) refreshJobs(); }, 3000);
}

document.addEventListener("DOMContentLoaded", init);
