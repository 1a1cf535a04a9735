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
  streams: new Map(), // id -> EventSource (or fetchEvents' stand-in)
  templates: [], // GET /v1/templates
  watched: null, // id of the job shown in the result panel
  autoShow: null, // id of the latest job submitted here: shown when it finishes
  finished: new Set(), // ids whose end has been handled (see finished()), so it happens once
  inspectSeq: 0,
  showSeq: 0, // bumped by every show(): an older show() still waiting on the server gives up
  view: null, // the run being animated
  observations: [], // [{criterion, observed}] of the site analysis being prepared
  criteria: [], // the criteria a run is judged by, or a search combines, when more than the builder's one
};

// What a job is called on the page.
const KIND_LABEL = { run: "run", pga_search: "PGA search", site_analysis: "site analysis" };

// ---------- helpers ----------

// ---------- access token ----------
// A server started with `--tokens FILE` answers 401 to every /v1/ call without a valid
// `Authorization: Bearer TOKEN` (docs/service.md). The page then asks for a token, keeps it in
// sessionStorage (this tab only; gone when the tab closes) and retries the call.
const TOKEN_KEY = "ashlar-token";
const auth = { token: sessionStorage.getItem(TOKEN_KEY) || "", waiting: null };

function authHeaders(h = {}) {
  if (auth.token) h.Authorization = `Bearer ${auth.token}`;
  return h;
}

// Resolves when the user has entered a token; every call answered 401 meanwhile waits on the
// same prompt.
function askToken(message) {
  $("auth").hidden = false;
  $("token-error").textContent = message || "";
  if (!auth.waiting) {
    let resolve;
    const p = new Promise((r) => { resolve = r; });
    auth.waiting = { promise: p, resolve };
    $("token").focus();
  }
  return auth.waiting.promise;
}

function onTokenSubmit(ev) {
  ev.preventDefault();
  const t = $("token").value.trim();
  if (!t) { $("token-error").textContent = "Enter the token you were given."; return; }
  auth.token = t;
  sessionStorage.setItem(TOKEN_KEY, t);
  $("token").value = "";
  $("token-error").textContent = "";
  $("auth").hidden = true;
  const w = auth.waiting;
  auth.waiting = null;
  if (w) w.resolve();
}

function forgetToken() {
  auth.token = "";
  sessionStorage.removeItem(TOKEN_KEY);
  $("token-error").textContent = "Token forgotten.";
}

// fetch() with the token; a 401 asks for a token and retries (the token in use when the call
// was made is compared, so that a token entered meanwhile is tried before asking again).
async function authFetch(url, init = {}) {
  for (;;) {
    const used = auth.token;
    const r = await fetch(url, { ...init, headers: authHeaders({ ...(init.headers || {}) }) });
    if (r.status !== 401) return r;
    if (auth.token === used || !auth.token) {
      let detail = "";
      try { detail = (await r.json()).detail || ""; } catch (e) { /* not a problem document */ }
      await askToken(used ? `The token was refused: ${detail}` : "");
    }
  }
}

async function api(method, url, body) {
  const init = { method, headers: {} };
  if (body !== undefined) {
    init.headers["Content-Type"] = "application/json";
    init.body = JSON.stringify(body);
  }
  const r = await authFetch(url, init);
  const ct = r.headers.get("content-type") || "";
  let data = null;
  if (ct.includes("json")) data = await r.json();
  else data = await r.text();
  if (!r.ok) {
    const problem = data && typeof data === "object" ? data : { status: r.status, title: r.statusText, detail: String(data) };
    const err = new Error(problem.detail || problem.title || `HTTP ${r.status}`);
    err.problem = problem;
    err.status = r.status;
    throw err;
  }
  return data;
}

// Server-sent events over fetch (EventSource cannot send an Authorization header). The same
// interface as the part of EventSource the page uses: addEventListener(type, fn) with
// {data}, onerror, close(), readyState.
function fetchEvents(url) {
  const ctl = new AbortController();
  const es = { readyState: 0, onerror: null, listeners: {}, close() { es.readyState = 2; ctl.abort(); } };
  es.addEventListener = (type, fn) => { (es.listeners[type] = es.listeners[type] || []).push(fn); };
  (async () => {
    try {
      const r = await authFetch(url, { headers: { Accept: "text/event-stream" }, signal: ctl.signal });
      if (!r.ok || !r.body) throw new Error(`events: HTTP ${r.status}`);
      es.readyState = 1;
      const reader = r.body.pipeThrough(new TextDecoderStream()).getReader();
      let buf = "";
      for (;;) {
        const { value, done } = await reader.read();
        if (done) break;
        buf += value.replace(/\r\n?/g, "\n");
        let cut;
        while ((cut = buf.indexOf("\n\n")) >= 0) {
          const block = buf.slice(0, cut);
          buf = buf.slice(cut + 2);
          let type = "message";
          const data = [];
          for (const line of block.split("\n")) {
            if (line.startsWith("event:")) type = line.slice(6).trim();
            else if (line.startsWith("data:")) data.push(line.slice(5).replace(/^ /, ""));
          }
          if (data.length) for (const fn of es.listeners[type] || []) fn({ data: data.join("\n") });
        }
      }
    } catch (e) {
      if (es.readyState === 2) return;
    }
    es.readyState = 2;
    if (es.onerror) es.onerror();
  })();
  return es;
}

// A download link to the API: with a token, the browser's own navigation cannot send the
// header, so the file is fetched with it and handed over as a blob.
function apiLink(a) {
  a.addEventListener("click", async (ev) => {
    if (!auth.token || !a.getAttribute("href").startsWith("/v1/")) return;
    ev.preventDefault();
    try {
      const r = await authFetch(a.getAttribute("href"));
      if (!r.ok) throw new Error(`HTTP ${r.status}`);
      const url = URL.createObjectURL(await r.blob());
      const tmp = el("a", { href: url, download: a.getAttribute("download") || "" });
      document.body.append(tmp);
      tmp.click();
      tmp.remove();
      setTimeout(() => URL.revokeObjectURL(url), 60000);
    } catch (e) {
      alert(`Download: ${e.message}`);
    }
  });
  return a;
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
  ["/observations", "observations"],
  ["/range/min", "range-min"],
  ["/range/max", "range-max"],
  ["/range", "range-min"],
  ["/tolerance", "tolerance"],
  ["/resolution", "resolution"],
  ["/scan_points", "scan-points"],
];

function slotInput(slot) {
  switch (slot) {
    case "duration": return $("duration");
    case "model": return $("model");
    case "scene": return state.sceneSource === "file" ? $("scene-file") : $("scene-example");
    case "scale": return $("scale-value");
    case "motion": return radio("motion-source") === "pulse" ? $("pulse-amplitude") : $("record-file");
    case "criterion": return $("criterion-kind").value === "json" ? $("criterion-json") : $("criterion-kind");
    case "observations": return $("obs-add-fell");
    case "template": return $("template");
    case "dxf": return $("dxf-file");
    case "range-min": return $("range-min");
    case "range-max": return $("range-max");
    case "tolerance": return $("tolerance");
    case "resolution": return $("resolution");
    case "scan-points": return $("scan-points");
    default: return slot.startsWith("tp-") ? $(slot) : null;
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
  // Only the fields whose error is cleared: clearing one slot must not un-mark another slot's
  // field while its message stays (CI saw a scene's clear un-mark the DXF field's error).
  for (const e of document.querySelectorAll("[aria-invalid=true]")) {
    const slot = (e.getAttribute("aria-describedby") || "").replace(/-error$/, "");
    if (slots && !slots.includes(slot)) continue;
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
  const free = blocks.filter((b) => !isHeld(scene, b));
  $("scene-info").textContent = `${label}: "${scene.name || "unnamed"}", ${blocks.length} blocks (${free.length} free)` +
    (scene.control && scene.control.duration ? `, ${scene.control.duration} s` : "");
  $("criterion-block").replaceChildren(...free.map((b) => el("option", { value: b.id, text: b.id })));
  $("criterion-insert").replaceChildren(el("option", { value: "", text: "(block)" }), ...free.map((b) => el("option", { value: b.id, text: b.id })));
  // Another source replaces the scene: the other pickers go back to "none".
  if (source !== "example") $("scene-example").value = "";
  if (source !== "file") $("scene-file").value = "";
  if (source !== "dxf") $("dxf-file").value = "";
  if (source !== "template") { $("template").value = ""; $("template-box").hidden = true; }
  drawScene(scene);
}

// A fixed block, or the block driven by the ground (not free to move).
function isHeld(scene, b) {
  return !!b.fixed || !!(scene.excitation && scene.excitation.block === b.id);
}

const SVG_NS = "http://www.w3.org/2000/svg";
function svg(tag, attrs = {}, text) {
  const e = document.createElementNS(SVG_NS, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, String(v));
  if (text !== undefined) e.textContent = text;
  return e;
}

// The scene to scale in an SVG: one polygon per block (data-id), fixed and driven blocks
// shaded, a scale bar in metres at the bottom left (data-metres: its length in m). The drawing's
// pixels per metre are in data-px-per-m (the same in x and y). A click on a block offers its id
// to the criterion.
function drawScene(scene) {
  const box = $("scene-svg");
  const w = Math.max(200, box.clientWidth || 320), h = Math.max(120, box.clientHeight || 260);
  box.setAttribute("viewBox", `0 0 ${w} ${h}`);
  const blocks = (scene.blocks || []).filter((b) => Array.isArray(b.vertices) && b.vertices.length >= 3 &&
    b.vertices.every((v) => Array.isArray(v) && v.length === 2 && v.every(Number.isFinite)));
  const defs = svg("defs");
  const hatch = svg("pattern", { id: "hatch", width: 6, height: 6, patternUnits: "userSpaceOnUse", patternTransform: "rotate(45)" });
  hatch.append(svg("rect", { width: 6, height: 6, fill: "#d6d3cc" }), svg("line", { x1: 0, y1: 0, x2: 0, y2: 6, stroke: "#9a968e", "stroke-width": 1.5 }));
  defs.append(hatch);
  box.replaceChildren(defs);
  if (!blocks.length) return;
  const pts = blocks.flatMap((b) => b.vertices);
  const xs = pts.map((p) => p[0]), ys = pts.map((p) => p[1]);
  const [x0, x1, y0, y1] = [Math.min(...xs), Math.max(...xs), Math.min(...ys), Math.max(...ys)];
  const pad = 10, bar = 26; // margins, and room for the scale bar below the drawing (px)
  const k = Math.min((w - 2 * pad) / Math.max(x1 - x0, 1e-9), (h - 2 * pad - bar) / Math.max(y1 - y0, 1e-9));
  const ox = (w - k * (x1 - x0)) / 2, oy = pad + (h - 2 * pad - bar - k * (y1 - y0)) / 2;
  const X = (x) => ox + k * (x - x0), Y = (y) => oy + k * (y1 - y);
  box.dataset.pxPerM = String(k);
  const g = svg("g", { class: "blocks" });
  for (const b of blocks) {
    const held = isHeld(scene, b);
    const poly = svg("polygon", {
      points: b.vertices.map((v) => `${X(v[0]).toFixed(2)},${Y(v[1]).toFixed(2)}`).join(" "),
      class: held ? "block held" : "block free",
      fill: held ? "url(#hatch)" : "#efe6d2",
      stroke: held ? "#777" : "#8a6d3b",
      "stroke-width": 1.2,
      "data-id": b.id,
    });
    poly.append(svg("title", {}, `${b.id}${held ? " (fixed)" : ""}`));
    if (!held) poly.addEventListener("click", () => offerBlock(b.id));
    g.append(poly);
  }
  box.append(g);
  // Scale bar: a round length about a quarter of the drawing's width.
  const len = niceLength(Math.max(x1 - x0, y1 - y0) / 4 || 1);
  const bx = pad, by = h - 8;
  const sb = svg("g", { id: "scale-bar", "data-metres": len });
  sb.append(
    svg("line", { id: "scale-bar-line", x1: bx, y1: by, x2: bx + k * len, y2: by, stroke: "#222", "stroke-width": 2 }),
    svg("line", { x1: bx, y1: by - 4, x2: bx, y2: by + 3, stroke: "#222", "stroke-width": 1.5 }),
    svg("line", { x1: bx + k * len, y1: by - 4, x2: bx + k * len, y2: by + 3, stroke: "#222", "stroke-width": 1.5 }),
    svg("text", { x: bx + k * len + 6, y: by + 4, "font-size": 12, fill: "#222" }, `${len} m`));
  box.append(sb);
}

// ---------- templates ----------

const UNIT_LABELS = { m: "m", deg: "°", count: "count", 1: "ratio", "": "" };

async function loadTemplates() {
  const r = await api("GET", "/v1/templates");
  state.templates = r.templates;
  $("template").append(...r.templates.map((t) => el("option", { value: t.name, text: t.name })));
}

function onTemplatePick() {
  const t = state.templates.find((x) => x.name === $("template").value);
  clearErrors(["template"]);
  $("template-box").hidden = !t;
  if (!t) return;
  $("template-description").textContent = t.description;
  const rows = [];
  for (const p of t.parameters) {
    const id = `tp-${p.name}`;
    const unit = UNIT_LABELS[p.units] !== undefined ? UNIT_LABELS[p.units] : p.units;
    const label = el("label", { for: id, title: p.description }, `${p.name.replace(/_/g, " ")}${unit ? ` (${unit})` : ""}`);
    let input;
    if (Array.isArray(p.choices)) {
      input = el("select", { id, "data-param": p.name }, ...p.choices.map((c) => el("option", { value: c, text: c, selected: c === p.default })));
    } else {
      input = el("input", { type: "number", id, "data-param": p.name, value: String(p.default), step: p.units === "count" ? "1" : "any",
        min: p.min ?? undefined, max: p.max ?? undefined, inputmode: "decimal", title: p.description });
    }
    const range = p.min !== null && p.min !== undefined ? el("span", { class: "range", text: `${p.min}–${p.max}` }) : null;
    rows.push(el("div", { class: "row" }, label, input, range));
    rows.push(el("p", { id: `${id}-error`, class: "field-error", role: "alert" }));
  }
  $("template-fields").replaceChildren(...rows);
  for (const i of $("template-fields").querySelectorAll("[data-param]")) i.addEventListener("change", buildTemplate);
  buildTemplate();
}

// POST /v1/templates/{name} with the form's values; the scene is drawn (and becomes the one to
// submit). A 422 names /parameters/KEY: shown beside that field.
async function buildTemplate() {
  const name = $("template").value;
  if (!name) return;
  const seq = (state.templateSeq = (state.templateSeq || 0) + 1);
  const parameters = {};
  for (const i of $("template-fields").querySelectorAll("[data-param]")) {
    const raw = i.value.trim();
    if (i.tagName === "SELECT") parameters[i.dataset.param] = raw;
    else if (raw !== "") parameters[i.dataset.param] = Number(raw);
  }
  clearErrors([...Object.keys(parameters).map((k) => `tp-${k}`), "template"]);
  try {
    const scene = await api("POST", `/v1/templates/${encodeURIComponent(name)}`, { parameters });
    if (seq !== state.templateSeq) return;
    setScene(scene, "template", `Template ${name}`);
    $("template").value = name;
    $("template-box").hidden = false;
  } catch (e) {
    if (seq !== state.templateSeq) return;
    const p = e.problem || {};
    const m = typeof p.pointer === "string" && p.pointer.match(/^\/parameters\/(.+)$/);
    const key = m ? m[1].replace(/~1/g, "/").replace(/~0/g, "~") : null;
    if (key && $(`tp-${key}`)) showFieldError(`tp-${key}`, p.detail || e.message);
    else showFieldError("template", p.detail || e.message);
  }
}

// ---------- CAD import ----------

// POST /v1/scenes/import {"dxf": text, "options": null} → a scene, or a 422 naming the entity
// handle and layer. A server without the route (404) is told apart.
async function onDxfFile() {
  const f = $("dxf-file").files[0];
  clearErrors(["dxf", "scene"]);
  if (!f) return;
  const text = await readFile(f);
  try {
    const scene = await api("POST", "/v1/scenes/import", { dxf: text, options: null });
    setScene(scene, "dxf", f.name);
  } catch (e) {
    const p = e.problem || {};
    if (e.status === 404 || e.status === 405) {
      showFieldError("dxf", `This server cannot import DXF drawings (POST /v1/scenes/import answered ${e.status}): convert the drawing with \`ashlar scene import\` or use a newer server.`);
    } else {
      showFieldError("dxf", `${f.name}: ${p.detail || p.title || e.message}`);
    }
  }
}

// ---------- damage criterion (JSON) ----------

function criterionSkeleton(kind) {
  const free = [...$("criterion-block").options].map((o) => o.value);
  const a = free[free.length - 1] || "BLOCK", b = free[free.length - 2] || "BLOCK";
  switch (kind) {
    case "fallen": return { kind, blocks: [a] };
    case "relative_sliding": return { kind, blocks: [a, b], metres: 0.03 };
    case "drop": return { kind, block: a, metres: 0.05 };
    case "rotation": return { kind, block: a, degrees: 5 };
    case "displaced_fraction": return { kind, metres: 0.05, fraction: 0.5 };
    case "all": case "any": return { kind, of: [{ kind: "fallen", blocks: [a] }, { kind: "drop", block: b, metres: 0.05 }] };
    case "not": return { kind, of: { kind: "fallen", blocks: [a] } };
    default: return null;
  }
}

// A block id offered by a click on the drawing or the select: into the JSON criterion at the
// cursor (as a JSON string) when that is the criterion in use, else as the criterion's block.
function offerBlock(id) {
  if ($("criterion-kind").value === "json" && !$("criterion-box").hidden) {
    const t = $("criterion-json");
    const text = JSON.stringify(id);
    const at = t.selectionStart ?? t.value.length, end = t.selectionEnd ?? at;
    t.value = t.value.slice(0, at) + text + t.value.slice(end);
    t.focus();
    t.setSelectionRange(at + text.length, at + text.length);
  } else if ([...$("criterion-block").options].some((o) => o.value === id)) {
    $("criterion-block").value = id;
  }
  for (const p of $("scene-svg").querySelectorAll("polygon.free")) p.classList.toggle("picked", p.dataset.id === id);
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
    drawScene({ blocks: [] });
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

function rangeSpec() {
  return { min: Number($("range-min").value), max: Number($("range-max").value), units: $("range-units").value };
}

// A search's or site analysis's optional fields beyond the range, in the range's units: the
// tolerance, and the scan resolution or else the scan points (the API takes one of the two).
function addSearchFields(body) {
  if ($("tolerance").value !== "") body.tolerance = Number($("tolerance").value);
  if ($("resolution").value !== "") body.resolution = Number($("resolution").value);
  else if ($("scan-points").value !== "") body.scan_points = Number($("scan-points").value);
}

// The criterion of the form (docs/format.md §3), or null after showing why it is not valid.
function currentCriterion() {
  const block = $("criterion-block").value;
  const ck = $("criterion-kind").value;
  if (ck !== "json") return ck === "toppled" ? `toppled:${block}` : `${ck}:${block}:${$("criterion-value").value}`;
  // Sent as the JSON text the service parses; checked here for syntax only, the server names
  // unknown kinds, fields and blocks.
  const criterion = $("criterion-json").value.trim();
  try {
    const v = JSON.parse(criterion);
    if (!v || typeof v !== "object" || Array.isArray(v)) throw new Error("expected a JSON object with a \"kind\"");
  } catch (e) {
    showFieldError("criterion", `The criterion is not valid JSON: ${e.message}`);
    return null;
  }
  return criterion;
}

// ---------- several criteria (a run's verdicts, a search's combination) ----------

function addCriterion() {
  clearErrors(["criterion"]);
  const criterion = currentCriterion();
  if (criterion === null) return;
  state.criteria.push(criterion);
  renderCriteria();
}

function renderCriteria() {
  const rows = state.criteria.map((c, k) => el("tr", { class: "crit" },
    el("td", {}, el("code", { text: c })),
    el("td", { class: "actions" }, el("button", { type: "button", class: "secondary", "aria-label": `Remove criterion ${k + 1}`, text: "Remove", onclick: () => { state.criteria.splice(k, 1); renderCriteria(); } }))));
  $("crit-body").replaceChildren(...rows);
  $("crit-table").hidden = rows.length === 0;
}

// What the job's `criterion` is: the list when one was made (the API takes an array,
// openapi.yaml), else the builder's one criterion; null after showing why it is not valid.
function criteriaToSend() {
  if (state.criteria.length > 1) return [...state.criteria];
  if (state.criteria.length === 1) return state.criteria[0];
  return currentCriterion();
}

// ---------- site observations ----------

function addObservation(observed) {
  clearErrors(["criterion", "observations"]);
  const criterion = currentCriterion();
  if (criterion === null) return;
  state.observations.push({ criterion, observed });
  renderObservations();
}

// docs/observations.md's worked example: the two columns, A fell and B stands, under the
// bundled half-sine pulse scaled over 2–12 m/s² (its answer there: [5.64, 8.60] m/s²).
async function fillSiteExample() {
  $("scene-example").value = "two-columns";
  await onSceneExample();
  $("duration").value = "";
  $("model").value = "";
  state.observations = [
    { criterion: '{"kind": "fallen", "blocks": ["A"]}', observed: true },
    { criterion: "toppled:B", observed: false },
  ];
  renderObservations();
  document.querySelector('input[name="motion-source"][value="example"]').checked = true;
  $("range-min").value = "2";
  $("range-max").value = "12";
  $("range-units").value = "m/s2";
  $("tolerance").value = "0.02";
  $("resolution").value = "";
  $("scan-points").value = "6";
  syncVisibility();
  scheduleInspect();
}

function renderObservations() {
  const rows = state.observations.map((o, k) => {
    const pick = el("select", { "aria-label": `What is seen of observation ${k + 1}`, "data-obs": String(k) },
      el("option", { value: "seen", text: "seen (fell)" }), el("option", { value: "not", text: "not seen (stands)" }));
    pick.value = o.observed ? "seen" : "not";
    pick.addEventListener("change", () => { o.observed = pick.value === "seen"; });
    return el("tr", { class: "obs" },
      el("td", {}, el("code", { text: o.criterion })),
      el("td", {}, pick),
      el("td", { class: "actions" }, el("button", { type: "button", class: "secondary", "aria-label": `Remove observation ${k + 1}`, text: "Remove", onclick: () => { state.observations.splice(k, 1); renderObservations(); } })));
  });
  $("obs-body").replaceChildren(...rows);
  $("obs-table").hidden = rows.length === 0;
}

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
  if (kind === "site") {
    url = "/v1/site-analyses";
    if (!state.observations.length) { showFieldError("observations", "Add at least one observation: what fell (seen) or what stands (not seen)."); return; }
    if (!motions[0]) { showFieldError("motion", "A site analysis needs records to scale."); return; }
    // Named by their files, so that the result's rows say which record is which.
    if (radio("motion-source") === "record") motions = motions.map((m, i) => (state.records[i] ? Object.assign({ name: state.records[i].name }, m) : m));
    body = { scene, motions, observations: state.observations.map((o) => ({ criterion: o.criterion, observed: o.observed })), range: rangeSpec() };
    addSearchFields(body);
  } else if (kind === "run") {
    url = "/v1/jobs";
    body = { scene };
    if (motions[0]) body.motion = motions[0];
    // Optional: the finished run's summary then says whether the criterion was met.
    if ($("run-judge").checked) {
      const criterion = criteriaToSend();
      if (criterion === null) return;
      body.criterion = criterion;
    }
  } else {
    url = "/v1/pga-searches";
    const criterion = criteriaToSend();
    if (criterion === null) return;
    body = { scene, criterion, range: rangeSpec() };
    if (Array.isArray(criterion)) body.combine = $("crit-combine").value;
    addSearchFields(body);
    if (!motions[0]) { showFieldError("motion", "A PGA search needs a ground motion to scale."); return; }
    if (motions.length > 1) body.motions = motions;
    else body.motion = motions[0];
  }
  $("submit-button").disabled = true;
  $("submit-status").textContent = "Submitting…";
  try {
    const acc = await api("POST", url, body);
    $("submit-status").textContent = `Queued ${KIND_LABEL[acc.kind] || acc.kind} ${acc.id.slice(0, 8)}.`;
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
  // One listing at a time (a listing waiting on the token prompt must not pile up).
  if (state.listing) return;
  state.listing = true;
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
  } finally {
    state.listing = false;
  }
}

// Follow a job's progress with server-sent events (at most MAX_STREAMS at once; the rest are
// refreshed by the periodic listing).
function follow(job) {
  if (TERMINAL.has(job.status) || state.streams.has(job.id) || state.streams.size >= MAX_STREAMS) return;
  // With a token the stream is read through fetch (an EventSource cannot send the header).
  const es = auth.token ? fetchEvents(job.links.events) : new EventSource(job.links.events);
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
    if (es.readyState === 2) state.streams.delete(job.id); // EventSource.CLOSED
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
  const label = KIND_LABEL[j.kind] || j.kind;
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
  $("site-view").hidden = true;
  const head = $("result-head");
  const label = KIND_LABEL[j.kind] || j.kind;
  const kind = label.charAt(0).toUpperCase() + label.slice(1);
  head.textContent = `${kind} ${j.id.slice(0, 8)}: ${j.status}` + (j.motion ? ` · motion: ${j.motion.provenance}, PGA ${fmt(j.motion.pga)} m/s² (${fmt(j.motion.pga / G)} g)` : "");
  if (j.status === "failed") {
    head.textContent += ` · ${j.error || "failed"}`;
    return;
  }
  try {
    if (j.kind === "run") await showRun(j, current);
    else if (j.kind === "site_analysis") showSite(j);
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
  // The verdicts of the criteria the run was submitted with (summary.criteria, docs/web.md).
  const verdicts = Array.isArray(s.criteria) && s.criteria.length
    ? el("table", { class: "peaks criteria", id: "criteria" },
      el("thead", {}, el("tr", {}, el("th", { scope: "col", text: "Damage criterion" }), el("th", { scope: "col", text: "On this run" }))),
      el("tbody", {}, ...s.criteria.map((c) => el("tr", { "data-met": String(Boolean(c.met)) },
        el("td", {}, el("code", { text: c.criterion })),
        el("td", {}, el("span", { class: `badge ${c.met ? "met" : "not-met"}`, text: c.met ? "met" : "not met" }))))))
    : null;
  const diag = s.diagnostics ? el("p", { class: "info", text: "Diagnostics: " + Object.entries(s.diagnostics).map(([k, v]) => `${k.replace(/_/g, " ")} ${typeof v === "number" ? fmt(v) : JSON.stringify(v)}`).join(" · ") }) : null;
  box.replaceChildren(facts, verdicts || "", table, diag || "");
}

function renderDownloads(j) {
  // With tokens on, the job gives signed links (docs/service.md "Signed links"): Foxglove
  // fetches the MCAP itself, without the header, so it gets the signed one.
  const signed = j.signed_links && j.signed_links.trajectory;
  const mcap = new URL(signed || j.links.trajectory, location.href).href;
  const fox = `https://app.foxglove.dev/?ds=remote-file&ds.url=${encodeURIComponent(mcap)}`;
  // With a token, links to /v1/ are fetched with the header (apiLink).
  const hist = j.links.histories;
  const csvHref = `${hist}${hist.includes("?") ? "&" : "?"}format=csv`;
  const foxNote = auth.token && !signed
    ? " — this server asks for a token, which Foxglove cannot send: download the MCAP and open the file in Foxglove instead"
    : " — needs this server to be reachable from your browser (Foxglove fetches the file)";
  $("downloads").replaceChildren(
    el("li", {}, apiLink(el("a", { href: csvHref, download: `histories-${j.id.slice(0, 8)}.csv`, id: "dl-csv", text: "Histories (CSV)" })), " — time (s), x, y (m), rotation (rad) of every free block"),
    el("li", {}, apiLink(el("a", { href: j.links.trajectory, download: `trajectory-${j.id.slice(0, 8)}.mcap`, id: "dl-mcap", text: "Trajectory (MCAP)" })), " — blocks, ground motion and outlines over time"),
    el("li", {}, el("a", { href: fox, target: "_blank", rel: "noopener", id: "dl-foxglove", text: "Open the trajectory in Foxglove" }), foxNote),
    el("li", {}, apiLink(el("a", { href: j.links.self, id: "dl-job", download: `job-${j.id.slice(0, 8)}.json`, text: "Job and summary (JSON)" }))));
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

// A site analysis: each record's interval, and the distribution of the site's PGA over the
// records with what it assumes (docs/observations.md).
function showSite(j) {
  $("site-view").hidden = false;
  const r = j.result;
  const box = $("site-summary");
  if (!r) { box.replaceChildren(el("p", { class: "info", text: "No result was recorded." })); $("site-assumes").textContent = ""; return; }
  const both = (v) => (v === null || v === undefined ? "–" : `${fmt(v)} m/s² (${fmt(v / G)} g)`);
  const head = el("tr", {}, ...["Record", "PGA from", "PGA to", "consistent"].map((t) => el("th", { scope: "col", text: t })));
  const rows = r.records.map((rec) => el("tr", {}, el("th", { scope: "row", text: rec.record }), el("td", { text: both(rec.lower) }), el("td", { text: both(rec.upper) }), el("td", { text: rec.consistent ? "yes" : "no: no scaling of this record reproduces every observation" })));
  const d = r.distribution;
  const obs = d.criteria.map((c) => `${c.criterion} ${c.observed ? "seen" : "not seen"}`).join("; ");
  const post = (name, p, err) => el("tr", {}, el("th", { scope: "row", text: name }),
    ...(p ? [el("td", { text: both(p.median) }), el("td", { text: `${fmt(p.p16_p84[0])}–${fmt(p.p16_p84[1])} m/s²` }), el("td", { text: `${fmt(p.p05_p95[0])}–${fmt(p.p05_p95[1])} m/s²` })]
      : [el("td", { colspan: "3", text: err || "none" })]));
  box.replaceChildren(
    el("p", {}, `Observations: ${obs}`),
    el("h3", { text: "Per record: the PGA consistent with every observation" }),
    el("table", { id: "site-records" }, el("thead", {}, head), el("tbody", {}, ...rows)),
    el("h3", { text: "Over the records: the site's PGA" }),
    el("table", { id: "site-distribution" },
      el("thead", {}, el("tr", {}, ...["fragilities", "median", "16–84 %", "5–95 %"].map((t) => el("th", { scope: "col", text: t })))),
      el("tbody", {}, post("lognormal", d.lognormal, d.lognormal_error), post("empirical", d.empirical, d.empirical_error))));
  $("site-assumes").textContent = `Prior: ${d.prior}. Likelihood: ${d.likelihood}. Assumes: ${d.assumes}`;
  const series = [];
  if (d.lognormal) series.push({ x: d.lognormal.pga, y: d.lognormal.density, label: "lognormal fragilities", color: "#1f6fd1", width: 2 });
  if (d.empirical) series.push({ x: d.empirical.pga, y: d.empirical.density, label: "empirical fragilities", color: "#e0a000", width: 2 });
  const canvas = $("plot-site");
  canvas.hidden = series.length === 0;
  if (series.length) {
    window.ashlarPlot.plot(canvas, { title: "Distribution of the site's PGA given the observations", xlabel: "PGA (m/s²)", ylabel: "density (1/(m/s²))", series,
      bands: r.records.filter((rec) => rec.consistent).map((rec) => ({ x0: rec.lower, x1: rec.upper, color: "rgba(46,125,50,0.10)" })) });
  }
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
  const site = radio("analysis") === "site";
  const pga = radio("analysis") === "pga" || site;
  const run = radio("analysis") === "run";
  $("pga-fields").hidden = !pga;
  $("pga-info").hidden = !pga;
  $("run-judge-row").hidden = !run;
  // One criterion builder: a search's or site's criterion, or the one a single run is judged by.
  $("criterion-box").hidden = !(pga || (run && $("run-judge").checked));
  $("site-box").hidden = !site;
  // A site's observations are their own list; a run's and a search's criteria this one.
  $("criteria-list-box").hidden = site;
  $("crit-combine").hidden = !pga;
  $("crit-combine-label").hidden = !pga;
  // A PGA search scales the record itself: no scale of its own.
  $("scale-mode-row").hidden = pga;
  if (pga) $("scale-row").hidden = true;
  const ck = $("criterion-kind").value;
  $("criterion-value").disabled = ck === "toppled" || ck === "json";
  $("criterion-block").disabled = ck === "json";
  $("criterion-json-box").hidden = ck !== "json";
  // A resolution replaces the scan points (the API refuses both).
  $("scan-points").disabled = $("resolution").value !== "";
}

async function init() {
  $("auth-form").addEventListener("submit", onTokenSubmit);
  $("token-forget").addEventListener("click", forgetToken);
  try {
    const ex = await api("GET", "/v1/examples");
    state.examples = ex.examples;
    for (const e of ex.examples.filter((x) => x.kind === "scene")) $("scene-example").append(el("option", { value: e.name, text: e.title }));
  } catch (e) { console.warn(e); }
  try { await loadTemplates(); } catch (e) { console.warn("templates:", e); }
  $("template").addEventListener("change", onTemplatePick);
  $("template-build").addEventListener("click", buildTemplate);
  $("dxf-file").addEventListener("change", onDxfFile);
  $("criterion-template").addEventListener("change", () => {
    const v = criterionSkeleton($("criterion-template").value);
    if (v) $("criterion-json").value = JSON.stringify(v, null, 1).replace(/\n\s*/g, " ");
    $("criterion-template").value = "";
  });
  $("criterion-insert").addEventListener("change", () => {
    const id = $("criterion-insert").value;
    if (id) offerBlock(id);
    $("criterion-insert").value = "";
  });
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
  $("run-judge").addEventListener("change", syncVisibility);
  $("resolution").addEventListener("input", syncVisibility);
  $("job-form").addEventListener("submit", onSubmit);
  $("crit-add").addEventListener("click", addCriterion);
  $("obs-add-fell").addEventListener("click", () => addObservation(true));
  $("obs-add-stood").addEventListener("click", () => addObservation(false));
  $("site-example").addEventListener("click", fillSiteExample);
  $("play").addEventListener("click", togglePlay);
  $("time-slider").addEventListener("input", () => { stopPlaying(); drawFrame(Number($("time-slider").value)); });
  let resizing = 0;
  window.addEventListener("resize", () => {
    cancelAnimationFrame(resizing);
    resizing = requestAnimationFrame(() => {
      window.ashlarPlot.replotAll();
      if (state.view) { state.view.lastPlotFrame = -1; drawFrame(state.view.frame); }
      if (state.scene) drawScene(state.scene);
    });
  });
  syncVisibility();
  await refreshJobs();
  // The listing catches jobs submitted elsewhere and those without a live stream.
  setInterval(() => { if (!document.hidden) refreshJobs(); }, 3000);
}

document.addEventListener("DOMContentLoaded", init);
