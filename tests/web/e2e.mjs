// End-to-end test of the ashlar web page in headless Chromium (run by tests/web/run.sh, which
// starts `ashlar serve` and sets the environment):
//   ASHLAR_URL         base URL of the running server (http://127.0.0.1:PORT)
//   ASHLAR_RECORD      a ground-motion record file (AT2) to upload
//   ASHLAR_SCENE_BAD   a scene file the server must refuse (a block with two vertices)
//   ASHLAR_SCREENSHOT  where to save the screenshot of the finished run (and, beside it,
//                      web-<width>.png of the PGA result at each width the layout is checked at)
//   ASHLAR_URL_TOKENS  base URL of a second server started with --tokens (token prompt check)
//   ASHLAR_TOKEN       a token that server accepts
//   CHROMIUM           the browser (default /usr/bin/chromium)
// Prints one line per check and a closing "N passed, N failed" line; exits non-zero on failure.
import { chromium } from "playwright-core";
import { mkdtempSync, readFileSync, rmSync } from "node:fs";
import { tmpdir } from "node:os";
import { dirname, join } from "node:path";

const base = process.env.ASHLAR_URL;
const record = process.env.ASHLAR_RECORD;
const badScene = process.env.ASHLAR_SCENE_BAD;
const screenshot = process.env.ASHLAR_SCREENSHOT;
const baseTokens = process.env.ASHLAR_URL_TOKENS;
const token = process.env.ASHLAR_TOKEN;
if (!base || !record || !badScene) {
  console.error("e2e: set ASHLAR_URL, ASHLAR_RECORD and ASHLAR_SCENE_BAD (tests/web/run.sh does)");
  process.exit(2);
}

let passed = 0;
let failed = 0;
async function check(name, fn) {
  const t0 = Date.now();
  try {
    await fn();
    passed++;
    console.log(`ok   ${name} (${Date.now() - t0} ms)`);
  } catch (e) {
    failed++;
    console.log(`FAIL ${name}: ${e && e.stack ? e.stack : e}`);
  }
}
function assert(cond, msg) {
  if (!cond) throw new Error(msg);
}

// Pixels of a canvas that carry a saturated colour: data series and state outlines are drawn in
// saturated colours, axes, grids, labels and fixed blocks in greys, so this counts drawn data.
async function colouredPixels(page, id) {
  return page.evaluate((id) => {
    const c = document.getElementById(id);
    const d = c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) {
      if (d[i + 3] > 0 && Math.max(d[i], d[i + 1], d[i + 2]) - Math.min(d[i], d[i + 1], d[i + 2]) > 60) n++;
    }
    return n;
  }, id);
}

// The widths the layout is checked at: the three of docs/web.md, plus the narrowest supported width
// and the narrowest three-column layout (the tightest jobs panel).
const WIDTHS = [1280, 1400, 1920];
const EXTRA_WIDTHS = [1024, 1201];

async function atWidth(page, width) {
  await page.setViewportSize({ width, height: 900 });
  // The page redraws its plots on the next animation frame after a resize.
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  await page.waitForTimeout(100);
}

// Every element of the jobs table lies inside the jobs panel's content box and the viewport,
// and nothing scrolls sideways (a scrolled-away View button is as cut off as a clipped one).
// Returns the number of rows and action buttons checked, so that a caller can tell the check
// was not vacuous.
async function jobsTableFits(page, width) {
  const r = await page.evaluate(() => {
    const q = document.getElementById("queue");
    const cs = getComputedStyle(q);
    const qr = q.getBoundingClientRect();
    const left = qr.left + parseFloat(cs.borderLeftWidth) + parseFloat(cs.paddingLeft);
    const right = qr.right - parseFloat(cs.borderRightWidth) - parseFloat(cs.paddingRight);
    const vw = document.documentElement.clientWidth;
    const bad = [];
    for (const e of q.querySelectorAll("table.jobs, table.jobs *")) {
      const b = e.getBoundingClientRect();
      if (b.width === 0 && b.height === 0) continue;
      if (e.closest("thead") && getComputedStyle(e.closest("thead")).position === "absolute") continue; // visually hidden header
      if (e.classList.contains("sr-only")) continue;
      if (b.left < left - 0.5 || b.right > right + 0.5 || b.right > vw + 0.5) {
        bad.push(`${e.tagName.toLowerCase()}${e.dataset.action ? `[${e.dataset.action}]` : ""} "${e.textContent.trim().slice(0, 20)}" spans ${b.left.toFixed(0)}–${b.right.toFixed(0)} px, panel content ${left.toFixed(0)}–${right.toFixed(0)}, viewport ${vw}`);
      }
    }
    if (q.scrollWidth > q.clientWidth + 1) bad.push(`the jobs panel scrolls sideways: ${q.scrollWidth} > ${q.clientWidth} px`);
    const de = document.documentElement;
    if (de.scrollWidth > de.clientWidth + 1) bad.push(`the page scrolls sideways: ${de.scrollWidth} > ${de.clientWidth} px`);
    const buttons = [...q.querySelectorAll("tbody button")].map((b) => b.dataset.action);
    return { bad, rows: q.querySelectorAll("tbody tr").length, buttons };
  });
  assert(r.bad.length === 0, `at ${width} px: ${r.bad.length} elements outside, e.g. ${r.bad.filter((b) => /^(button|td|th)/.test(b)).slice(0, 3).join("; ") || r.bad[0]}`);
  return r;
}

// The legend of a plot covers none of its points. Independent of where the plot says it put
// its legend: the test wraps window.ashlarPlot.plot to keep each canvas' spec and the mapping
// the data was drawn with, redraws the canvas with and without its legend, and takes the
// legend's footprint from the pixels that differ (plus the box the plot reports, when the
// layout does not allow the comparison). A point's footprint is its marker (radius 5, line 2).
async function legendClearOfPoints(page, id) {
  return page.evaluate((id) => {
    const c = document.getElementById(id);
    const plotted = () => c.__e2e;
    const draw = (spec) => { window.ashlarPlot.plot(c, spec); return plotted(); };
    const image = () => c.getContext("2d").getImageData(0, 0, c.width, c.height).data;
    const spec = plotted().spec;
    const pts = (spec.points || []).filter((p) => Number.isFinite(p.x) && Number.isFinite(p.y));
    if (!pts.length) return { error: `${id}: no points plotted` };
    const without = draw({ ...spec, legend: false });
    const mapNo = pts.map((p) => [without.sx(p.x), without.sy(p.y)]);
    const imgNo = image();
    const withL = draw(spec);
    const mapL = pts.map((p) => [withL.sx(p.x), withL.sy(p.y)]);
    const imgL = image();
    // Device pixels per CSS pixel, once the canvas has been redrawn at its current size.
    const dpr = c.width / c.getBoundingClientRect().width;
    const regions = [];
    const reported = c.dataset.legend ? c.dataset.legend.split(",").map(Number) : null;
    if (reported) regions.push({ from: "reported box", x: reported[0], y: reported[1], w: reported[2], h: reported[3] });
    const sameLayout = mapNo.every(([X, Y], k) => Math.abs(X - mapL[k][0]) < 0.01 && Math.abs(Y - mapL[k][1]) < 0.01);
    let diff = null;
    if (sameLayout) {
      let [a0, b0, a1, b1] = [Infinity, Infinity, -Infinity, -Infinity];
      for (let i = 0; i < imgL.length; i += 4) {
        if (Math.abs(imgL[i] - imgNo[i]) + Math.abs(imgL[i + 1] - imgNo[i + 1]) + Math.abs(imgL[i + 2] - imgNo[i + 2]) + Math.abs(imgL[i + 3] - imgNo[i + 3]) > 8) {
          const px = (i / 4) % c.width, py = Math.floor(i / 4 / c.width);
          a0 = Math.min(a0, px); a1 = Math.max(a1, px); b0 = Math.min(b0, py); b1 = Math.max(b1, py);
        }
      }
      if (a1 >= a0) {
        diff = { from: "pixels the legend changes", x: a0 / dpr, y: b0 / dpr, w: (a1 - a0 + 1) / dpr, h: (b1 - b0 + 1) / dpr };
        regions.push(diff);
      }
    }
    if (!regions.length) return { error: `${id}: no legend found (labels: ${pts.map((p) => p.label).join(",")})` };
    const problems = [];
    // The reported box holds all the legend's ink (the report is what the pixels show).
    if (reported && diff && (diff.x < reported[0] - 1 || diff.y < reported[1] - 1 || diff.x + diff.w > reported[0] + reported[2] + 1 || diff.y + diff.h > reported[1] + reported[3] + 1)) {
      problems.push(`the legend draws outside its reported box: ${JSON.stringify(diff)} vs ${reported}`);
    }
    pts.forEach((p, k) => {
      const [X, Y] = mapL[k];
      for (const r of regions) {
        if (X + 6 > r.x && X - 6 < r.x + r.w && Y + 6 > r.y && Y - 6 < r.y + r.h) {
          problems.push(`${p.label || "point"} at PGA ${p.x} (${X.toFixed(0)}, ${Y.toFixed(0)} px) under the legend (${r.from}: ${r.x.toFixed(0)}, ${r.y.toFixed(0)}, ${r.w.toFixed(0)} × ${r.h.toFixed(0)} px)`);
        }
      }
    });
    return { problems, points: pts.length, place: c.dataset.legendPlace || "(not reported)", regions: regions.map((r) => r.from) };
  }, id);
}

async function unlabelled(page) {
  return page.evaluate(() =>
    [...document.querySelectorAll("input, select, button, textarea")]
      .filter((e) => !(e.labels && e.labels.length) && !e.getAttribute("aria-label") && !(e.tagName === "BUTTON" && e.textContent.trim()))
      .map((e) => e.id || e.outerHTML.slice(0, 60)));
}

// The scene drawing, measured as a user would with the scale bar: the rendered extent of the
// blocks (free ones, or those named) in metres = pixels ÷ (scale bar's pixels ÷ its metres).
async function drawnExtent(page, ids) {
  return page.evaluate((ids) => {
    const bar = document.getElementById("scale-bar");
    const line = document.getElementById("scale-bar-line").getBoundingClientRect();
    const pxPerM = line.width / Number(bar.dataset.metres);
    const polys = [...document.querySelectorAll("#scene-svg polygon")].filter((p) => (ids ? ids.includes(p.dataset.id) : p.classList.contains("free")));
    const r = polys.map((p) => p.getBoundingClientRect());
    const x0 = Math.min(...r.map((b) => b.left)), x1 = Math.max(...r.map((b) => b.right));
    const y0 = Math.min(...r.map((b) => b.top)), y1 = Math.max(...r.map((b) => b.bottom));
    return { width: (x1 - x0) / pxPerM, height: (y1 - y0) / pxPerM, pxPerM, n: polys.length, all: document.querySelectorAll("#scene-svg polygon").length };
  }, ids);
}

const userDataDir = mkdtempSync(join(tmpdir(), "ashlar-e2e-chromium-"));
const context = await chromium.launchPersistentContext(userDataDir, {
  executablePath: process.env.CHROMIUM || "/usr/bin/chromium",
  headless: true,
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
    "--disable-background-networking", "--disable-component-update", "--disable-sync"],
  viewport: { width: 1440, height: 900 },
});
const page = context.pages()[0] || (await context.newPage());
const pageErrors = [];
const foreign = [];
page.on("pageerror", (e) => pageErrors.push(String(e)));
// The browser logs every 4xx answer as a console error; the page handles those (field errors).
page.on("console", (m) => { if (m.type() === "error" && !m.text().startsWith("Failed to load resource")) pageErrors.push(m.text()); });
page.on("request", (r) => { const u = r.url(); if (!u.startsWith(base) && !u.startsWith("data:") && !u.startsWith("blob:")) foreign.push(u); });
// What the page asked of the API and what it logged, printed when a check times out.
const t00 = Date.now();
const trail = [];
const note = (what) => trail.push(`${((Date.now() - t00) / 1000).toFixed(2)} s ${what}`);
// The periodic job listing is left out: it would crowd out the rest.
const api = (r) => { const u = r.url().replace(base, ""); return u.startsWith("/v1/") && !u.startsWith("/v1/jobs?"); };
page.on("request", (r) => { if (api(r)) note(`-> ${r.method()} ${r.url().replace(base, "")}`); });
page.on("response", (r) => { if (api(r.request())) note(`<- ${r.status()} ${r.request().method()} ${r.url().replace(base, "")}`); });
page.on("requestfailed", (r) => { if (api(r)) note(`xx ${r.method()} ${r.url().replace(base, "")}: ${r.failure() && r.failure().errorText}`); });
page.on("console", (m) => { if (m.type() !== "log") note(`console.${m.type()}: ${m.text()}`); });

try {
  await check("the page loads from the server alone", async () => {
    const r = await page.goto(`${base}/`);
    assert(r.status() === 200, `status ${r.status()}`);
    await page.waitForSelector("#scene-example option[value=column]", { state: "attached", timeout: 10000 });
    assert((await page.title()).includes("ashlar"), "title");
    // Keep, per canvas, the spec drawn and the mapping it was drawn with (legend check).
    await page.evaluate(() => {
      const inner = window.ashlarPlot.plot;
      window.ashlarPlot.plot = (c, spec) => { const r = inner(c, spec); c.__e2e = { spec, sx: r.sx, sy: r.sy }; return r; };
    });
  });

  await check("every input and select has a label", async () => {
    assert((await unlabelled(page)).length === 0, `unlabelled: ${(await unlabelled(page)).join(", ")}`);
  });

  await check("the record's intensity measures and spectrum show before submitting", async () => {
    await page.selectOption("#scene-example", "column");
    await page.waitForFunction(() => document.getElementById("scene-info").textContent.includes("column"));
    await page.setInputFiles("#record-file", record);
    await page.check('input[name="scale-mode"][value="pga"]');
    await page.fill("#scale-value", "1");
    await page.selectOption("#scale-units", "g");
    await page.waitForFunction(() => document.getElementById("record-provenance").textContent.includes("scaled"), null, { timeout: 20000 });
    const table = await page.textContent("#record-measures");
    assert(/PGA\s*9\.81 m\/s² \(1 g\)/.test(table), `measures: ${table}`);
    assert(table.includes("Arias intensity") && table.includes("D5–95"), table);
    for (const id of ["record-accel", "record-spectrum"]) {
      const n = await colouredPixels(page, id);
      assert(n > 200, `${id}: ${n} coloured pixels`);
    }
  });

  let runId = null;
  const held = { count: 0, done: 0 }; // the cancelled run's delayed GETs: started, answered
  await check("submitting the column with the record runs to completion", async () => {
    await page.fill("#duration", "8");
    await page.click("#submit-button");
    await page.waitForFunction(() => /Queued run/.test(document.getElementById("submit-status").textContent), null, { timeout: 20000 });
    runId = (await page.textContent("#submit-status")).match(/Queued run (\w+)/)[1];
    await page.waitForFunction(() => /: succeeded/.test(document.getElementById("result-head").textContent) && !document.getElementById("run-view").hidden, null, { timeout: 180000 });
    const row = await page.getAttribute("#jobs-body tr:first-child", "data-status");
    assert(row === "succeeded", `queue row: ${row}`);
  });

  await check("the animation and both plots (and the ground) have drawn", async () => {
    await page.waitForTimeout(300);
    for (const id of ["anim", "plot-displacement", "plot-rotation", "plot-ground"]) {
      const n = await colouredPixels(page, id);
      assert(n > 150, `${id}: ${n} coloured pixels`);
    }
  });

  await check("summary: failure mode and per-block peaks", async () => {
    const mode = await page.textContent("#failure-mode");
    assert(["stable", "sliding", "toppling", "sliding_toppling", "collapse", "undecided"].includes(mode), `mode ${mode}`);
    const peaks = await page.textContent("#summary table.peaks:not(.criteria)");
    assert(peaks.includes("column"), peaks);
    // Submitted without a criterion: no verdicts shown.
    assert((await page.$("#criteria")) === null, "verdicts shown for a run submitted without a criterion");
  });

  await check("time slider and play/pause", async () => {
    await page.focus("#time-slider");
    await page.keyboard.press("Home");
    assert((await page.textContent("#time-label")) === "t = 0.00 s", await page.textContent("#time-label"));
    await page.click("#play");
    await page.waitForTimeout(700);
    await page.click("#play");
    const label = await page.textContent("#time-label");
    assert(label !== "t = 0.00 s" && (await page.textContent("#play")) === "Play", `after playing: ${label}`);
    await page.focus("#time-slider");
    await page.keyboard.press("End");
  });

  await check("downloads: histories CSV, trajectory MCAP, Foxglove link", async () => {
    const csvHref = await page.getAttribute("#dl-csv", "href");
    const csv = await page.evaluate(async (u) => (await fetch(u)).text(), csvHref);
    assert(csv.startsWith("time_s,column.x_m,column.y_m,column.rotation_rad"), csv.slice(0, 80));
    const mcapHref = await page.getAttribute("#dl-mcap", "href");
    const magic = await page.evaluate(async (u) => Array.from(new Uint8Array(await (await fetch(u)).arrayBuffer()).slice(0, 8)), mcapHref);
    assert(String.fromCharCode(...magic.slice(1, 5)) === "MCAP" && magic[0] === 0x89, `magic ${magic}`);
    const fox = await page.getAttribute("#dl-foxglove", "href");
    const want = `https://app.foxglove.dev/?ds=remote-file&ds.url=${encodeURIComponent(new URL(mcapHref, base).href)}`;
    assert(fox === want, `${fox} != ${want}`);
  });

  if (screenshot) {
    await check("screenshot of the finished run", async () => {
      await page.evaluate(() => window.scrollTo(0, 0));
      await page.screenshot({ path: screenshot, fullPage: true });
    });
  }

  await check("a bad scene shows the server's error next to the scene field", async () => {
    await page.setInputFiles("#scene-file", badScene);
    await page.fill("#duration", "");
    await page.click("#submit-button");
    await page.waitForFunction(() => document.getElementById("scene-error").textContent.length > 0, null, { timeout: 10000 });
    const text = await page.textContent("#scene-error");
    assert(text.includes("/scene/blocks/1/vertices") && text.includes('block "column"'), text);
    assert((await page.getAttribute("#scene-file", "aria-invalid")) === "true", "the field is not marked invalid");
    const focused = await page.evaluate(() => document.activeElement.id);
    assert(focused === "scene-file", `focus on ${focused}`);
  });

  await check("a model the scene cannot take shows the server's error next to the model field", async () => {
    const scene = JSON.parse(readFileSync(new URL("../../examples/column.json", import.meta.url), "utf8"));
    const twin = JSON.parse(JSON.stringify(scene.blocks[1]));
    twin.id = "twin";
    twin.vertices = twin.vertices.map(([x, y]) => [x + 0.9, y]);
    scene.blocks.push(twin);
    await page.setInputFiles("#scene-file", { name: "two-columns.json", mimeType: "application/json", buffer: Buffer.from(JSON.stringify(scene)) });
    await page.waitForFunction(() => /^two-columns\.json: .*\(2 free\)/.test(document.getElementById("scene-info").textContent), null, { timeout: 10000 });
    await page.selectOption("#model", "rocking");
    await page.click("#submit-button");
    await page.waitForFunction(() => document.getElementById("model-error").textContent.length > 0, null, { timeout: 10000 });
    const text = await page.textContent("#model-error");
    assert(text.includes("/scene/control/model") && text.includes("2 free blocks"), text);
    assert((await page.getAttribute("#model", "aria-invalid")) === "true", "the model field is not marked invalid");
    await page.selectOption("#model", "");
  });

  await check("cancel: a long run is cancelled from the queue", async () => {
    await page.selectOption("#scene-example", "column");
    await page.waitForFunction(() => !document.getElementById("scene-error").textContent);
    await page.fill("#duration", "600");
    // The full engine: the default reduced model runs the column's 600 s in about a second,
    // which CI once finished before the click landed (the cancel button was gone).
    await page.selectOption("#model", "dda");
    await page.click("#submit-button");
    await page.waitForFunction((prev) => { const m = document.getElementById("submit-status").textContent.match(/Queued run (\w+)/); return m && m[1] !== prev; }, runId, { timeout: 20000 });
    // From here on the cancelled run's own record comes back 3 s late, as from a loaded server:
    // its view must never replace the PGA search submitted after it (CI once showed the run).
    const cancelledId = (await page.textContent("#submit-status")).match(/Queued run (\w+)/)[1];
    await page.route(`**/v1/jobs/${cancelledId}*`, async (route) => {
      if (route.request().method() !== "GET") return route.continue();
      held.count++;
      await new Promise((r) => setTimeout(r, 3000));
      await route.continue();
      held.done++;
    });
    const row = "#jobs-body tr:first-child";
    await page.waitForFunction((sel) => document.querySelector(sel).dataset.status === "running", row, { timeout: 30000 });
    await page.waitForFunction((sel) => parseFloat(document.querySelector(`${sel} progress`).value) > 0, row, { timeout: 30000 });
    // The jobs table with a running job (its Cancel button) and finished ones (View) fits its
    // panel at every width.
    for (const w of [...EXTRA_WIDTHS, ...WIDTHS]) {
      const r = await jobsTableFits(page, w);
      assert(r.buttons.includes("cancel") && r.buttons.includes("view"), `at ${w} px: buttons ${r.buttons}`);
    }
    await atWidth(page, 1440);
    await page.click(`${row} button[data-action=cancel]`);
    await page.waitForFunction((sel) => document.querySelector(sel).dataset.status === "cancelled", row, { timeout: 30000 });
  });

  await check("PGA search: scan points and bracket are plotted", async () => {
    // Rotation beyond 2° within 8 s: the column (7.5° at 1 g, the first run) passes the
    // low scan points and fails the high ones, so the plot has failed points at the top right,
    // where the legend used to sit (the layout check below).
    await page.fill("#duration", "8");
    await page.selectOption("#model", "");
    await page.check('input[name="analysis"][value="pga"]');
    await page.selectOption("#criterion-kind", "rotation");
    await page.fill("#criterion-value", "2");
    await page.fill("#range-min", "0.1");
    await page.fill("#range-max", "1.5");
    await page.selectOption("#range-units", "g");
    await page.fill("#tolerance", "0.1");
    // The scan resolution in the range's units (g), sent as the API's `resolution` instead of
    // the scan points, which it disables: 0.5 g gives the lattice h = 0.1 g × 2² = 0.4 g, the
    // one 4 scan points (1.4 g / 3 = 0.47 g) gave before, so the outcomes below are unchanged.
    await page.fill("#scan-points", "4");
    await page.fill("#resolution", "0.5");
    assert(await page.isDisabled("#scan-points"), "the scan points stay enabled with a resolution");
    const sentSearch = page.waitForRequest((r) => r.url().endsWith("/v1/pga-searches") && r.method() === "POST", { timeout: 20000 });
    // The page's first read of the new search is held until the search has finished, as when
    // a short job ends before the page follows it: CI once never showed such a search.
    const firstRead = { held: false, status: "" };
    await page.route("**/v1/pga-searches/*", async (route) => {
      if (route.request().method() !== "GET" || firstRead.held) return route.continue();
      firstRead.held = true;
      for (;;) {
        firstRead.status = (await (await fetch(route.request().url())).json()).status;
        if (["succeeded", "failed", "cancelled"].includes(firstRead.status)) break;
        await new Promise((r) => setTimeout(r, 200));
      }
      await route.continue();
    });
    await page.click("#submit-button");
    const searchBody = (await sentSearch).postDataJSON();
    assert(searchBody.resolution === 0.5 && !("scan_points" in searchBody) && searchBody.range.units === "g", `search request: ${JSON.stringify({ ...searchBody, scene: undefined, motion: undefined })}`);
    await page.waitForFunction(() => /Queued PGA search/.test(document.getElementById("submit-status").textContent), null, { timeout: 20000 });
    try {
      await page.waitForFunction(() => /PGA search \w+: succeeded/.test(document.getElementById("result-head").textContent) && !document.getElementById("pga-view").hidden, null, { timeout: 300000 });
    } catch (e) {
      const shown = await page.evaluate(() => ({
        head: document.getElementById("result-head").textContent,
        pga: !document.getElementById("pga-view").hidden,
        rows: [...document.querySelectorAll("#jobs-body tr")].map((r) => `${r.id}:${r.dataset.status}`),
        status: document.getElementById("submit-status").textContent,
        autoShow: state.autoShow,
        watched: state.watched,
        streams: [...state.streams].map(([id, es]) => `${id}:${es.readyState}`),
      }));
      throw new Error(`${e.message}\n    shown: ${JSON.stringify(shown)}\n    trail:\n      ${trail.slice(-60).join("\n      ")}`);
    }
    assert(firstRead.status === "succeeded", `the page's first read of the search was not held until it finished: ${JSON.stringify(firstRead)}`);
    const n = await colouredPixels(page, "plot-scan");
    assert(n > 50, `plot-scan: ${n} coloured pixels`);
    const text = await page.textContent("#pga-summary");
    assert(text.includes("rotation:column:2"), text);
    const outcomes = await page.evaluate(() => document.getElementById("plot-scan").__e2e.spec.points.map((p) => p.label));
    assert(outcomes.includes("failed") && outcomes.includes("safe"), `scan outcomes: ${outcomes}`);
    // The stored result's lattice spacing (m/s²): 0.4 g, the largest 0.1 g × 2^K not above 0.5 g.
    const searched = (await (await fetch(`${base}/v1/jobs?kind=pga_search&limit=1`)).json()).jobs[0].result;
    assert(Math.abs(searched.resolution - 0.4 * 9.80665) < 1e-9, `result resolution ${searched.resolution} m/s², not 0.4 g`);
    await page.fill("#resolution", "");
    assert(!(await page.isDisabled("#scan-points")), "the scan points stay disabled with the resolution cleared");
    // Every held request of the cancelled run has been answered and its handlers have run.
    for (let quiet = 0; quiet < 2; ) {
      await page.waitForTimeout(500);
      quiet = held.count === held.done ? quiet + 1 : 0;
    }
    const head = await page.textContent("#result-head");
    assert(/^PGA search \w+: succeeded/.test(head) && !(await page.isHidden("#pga-view")), `after the cancelled run's late answers: ${head}`);
    await page.unrouteAll();
  });

  await check(`layout at ${WIDTHS.join(", ")} px: the jobs table fits its panel, the PGA legend covers no point`, async () => {
    // Every width and both checks run before failing, so that a failure lists them all.
    const failures = [];
    const found = [];
    for (const w of [...EXTRA_WIDTHS, ...WIDTHS]) {
      await atWidth(page, w);
      try {
        const t = await jobsTableFits(page, w);
        assert(t.rows >= 3 && t.buttons.filter((b) => b === "view").length >= 2, `at ${w} px: ${t.rows} rows, buttons ${t.buttons}`);
      } catch (e) { failures.push(`jobs table: ${e.message}`); }
      if (!WIDTHS.includes(w)) continue;
      const l = await legendClearOfPoints(page, "plot-scan");
      if (l.error) failures.push(`PGA legend at ${w} px: ${l.error}`);
      else if (l.problems.length) failures.push(`PGA legend at ${w} px: ${l.problems.join("; ")}`);
      else found.push(`${w} px: legend ${l.place} (${l.points} points clear)`);
      if (screenshot) {
        await page.evaluate(() => window.scrollTo(0, 0));
        await page.screenshot({ path: join(dirname(screenshot), `web-${w}.png`), fullPage: true });
      }
    }
    await atWidth(page, 1440);
    if (found.length) console.log(`     ${found.join("; ")}`);
    assert(failures.length === 0, `\n     ${failures.join("\n     ")}`);
  });

  // ---------- structures: templates, bundled examples, DXF, damage criteria ----------

  const templates = await (await fetch(`${base}/v1/templates`)).json();
  await check("template picker: the default drum-column is drawn to scale, fixed blocks shaded", async () => {
    await page.evaluate(() => window.scrollTo(0, 0));
    const names = await page.$$eval("#template option", (os) => os.map((o) => o.value).filter(Boolean));
    assert(JSON.stringify(names) === JSON.stringify(templates.templates.map((t) => t.name)), `templates listed: ${names}`);
    await page.selectOption("#template", "drum-column");
    await page.waitForFunction(() => /^Template drum-column/.test(document.getElementById("scene-info").textContent), null, { timeout: 10000 });
    const dc = templates.templates.find((t) => t.name === "drum-column");
    const def = Object.fromEntries(dc.parameters.map((p) => [p.name, p.default]));
    // Every parameter has its input, bounded by its range and labelled with its units.
    for (const p of dc.parameters) {
      const a = await page.evaluate((n) => { const i = document.getElementById(`tp-${n}`); return { min: i.min, max: i.max, value: i.value, label: i.labels[0].textContent }; }, p.name);
      assert(Number(a.min) === p.min && Number(a.max) === p.max && Number(a.value) === p.default, `${p.name}: ${JSON.stringify(a)} vs ${JSON.stringify(p)}`);
      const unit = { m: "(m)", deg: "(°)", count: "(count)" }[p.units];
      assert(!unit || a.label.endsWith(unit), `${p.name} label: ${a.label}`);
    }
    assert((await unlabelled(page)).length === 0, `unlabelled: ${await unlabelled(page)}`);
    // Height of the column: shaft + echinus + abacus + base, from the template's own defaults
    // (6.2 m). Tolerance 0.02 m: the drawing is about 35 px/m, so 0.7 px of rounding and
    // anti-aliasing, far below a missing stone (≥ 0.2 m) or a y scale unlike the x scale.
    const height = def.shaft_height + def.capital_height + def.abacus_height + def.base_height;
    const m = await drawnExtent(page);
    assert(m.n === def.drums + 2, `${m.n} free blocks drawn, want ${def.drums} drums + capital + abacus`);
    assert(Math.abs(m.height - height) < 0.02, `drawn height ${m.height.toFixed(4)} m, template ${height} m (scale ${m.pxPerM.toFixed(2)} px/m)`);
    // The x scale is the y scale: the lowest drum is lower_diameter wide, the abacus abacus_width.
    const drum = await drawnExtent(page, ["drum1"]);
    assert(Math.abs(drum.width - def.lower_diameter) < 0.02, `drum1 drawn ${drum.width.toFixed(4)} m wide, want ${def.lower_diameter}`);
    const abacus = await drawnExtent(page, ["abacus"]);
    assert(Math.abs(abacus.width - def.abacus_width) < 0.02 && Math.abs(abacus.height - def.abacus_height) < 0.02, `abacus drawn ${abacus.width.toFixed(3)} × ${abacus.height.toFixed(3)} m`);
    console.log(`     drawn at ${m.pxPerM.toFixed(2)} px/m: column ${m.height.toFixed(4)} m tall (template ${height} m), drum1 ${drum.width.toFixed(4)} m wide (${def.lower_diameter}), abacus ${abacus.width.toFixed(4)} × ${abacus.height.toFixed(4)} m (${def.abacus_width} × ${def.abacus_height})`);
    if (screenshot) await page.locator("#job-form fieldset").first().screenshot({ path: join(dirname(screenshot), "web-template.png") });
    const fixed = await page.$$eval("#scene-svg polygon.held", (ps) => ps.map((p) => `${p.dataset.id}:${p.getAttribute("fill")}`));
    assert(fixed.length === 1 && fixed[0] === "foundation:url(#hatch)", `fixed blocks: ${fixed}`);
    // Five drums: redrawn with two stones fewer.
    await page.fill("#tp-drums", "5");
    await page.click("#template-build");
    await page.waitForFunction(() => document.querySelectorAll("#scene-svg polygon.free").length === 7, null, { timeout: 10000 });
  });

  await check("template picker: a bad parameter shows the server's error beside its field", async () => {
    await page.fill("#tp-drums", "0");
    await page.click("#template-build");
    await page.waitForFunction(() => document.getElementById("tp-drums-error").textContent.length > 0, null, { timeout: 10000 });
    const text = await page.textContent("#tp-drums-error");
    assert(/drums/.test(text) && /\[1, 30\]|1/.test(text), text);
    assert((await page.getAttribute("#tp-drums", "aria-invalid")) === "true", "the field is not marked invalid");
    assert((await page.textContent("#template-error")) === "", "the error went to the template's slot instead of the field's");
    await page.fill("#tp-drums", "7");
    await page.click("#template-build");
    await page.waitForFunction(() => document.getElementById("tp-drums-error").textContent === "" && document.querySelectorAll("#scene-svg polygon.free").length === 9, null, { timeout: 10000 });
  });

  await check("bundled examples: listed, and each drawn with every block", async () => {
    const listed = await page.$$eval("#scene-example option", (os) => os.map((o) => o.value).filter(Boolean));
    for (const name of ["column", "incline", "arch", "doric-colonnade", "wall-window", "two-columns"]) {
      assert(listed.includes(name), `${name} not listed: ${listed}`);
      const scene = JSON.parse(readFileSync(new URL(`../../examples/${name}.json`, import.meta.url), "utf8"));
      await page.selectOption("#scene-example", name);
      // The drawing of this scene, not of the one before (column and incline both have two
      // blocks: counting alone passed on the old drawing once).
      await page.waitForFunction((ids) => JSON.stringify([...document.querySelectorAll("#scene-svg polygon")].map((p) => p.dataset.id)) === JSON.stringify(ids) && /^Example/.test(document.getElementById("scene-info").textContent), scene.blocks.map((b) => b.id), { timeout: 10000 });
      const held = await page.$$eval("#scene-svg polygon.held", (ps) => ps.map((p) => p.dataset.id));
      const want = scene.blocks.filter((b) => b.fixed || (scene.excitation && scene.excitation.block === b.id)).map((b) => b.id);
      assert(JSON.stringify(held) === JSON.stringify(want), `${name}: shaded ${held}, fixed ${want}`);
    }
    assert((await page.$eval("#template", (s) => s.value)) === "", "the template picker still shows a template");
  });

  await check("damage criterion: built from a kind, block ids inserted by clicking the drawing, server errors beside it", async () => {
    await page.selectOption("#scene-example", "arch");
    await page.waitForFunction(() => document.querySelectorAll("#scene-svg polygon").length === 18);
    await page.check('input[name="analysis"][value="pga"]');
    await page.selectOption("#criterion-kind", "json");
    assert(!(await page.isHidden("#criterion-json")), "the JSON criterion field is hidden");
    await page.selectOption("#criterion-template", "relative_sliding");
    const built = JSON.parse(await page.inputValue("#criterion-json"));
    assert(built.kind === "relative_sliding" && built.blocks.length === 2 && typeof built.metres === "number", JSON.stringify(built));
    // Typed, with the keystone and a pier inserted by clicking them and from the select.
    await page.fill("#criterion-json", '{"kind": "any", "of": [{"kind": "drop", "block": ');
    await page.click('#scene-svg polygon[data-id="v8"]');
    await page.focus("#criterion-json");
    await page.keyboard.press("End");
    await page.keyboard.type(', "metres": 0.05}, {"kind": "fallen", "blocks": [');
    await page.selectOption("#criterion-insert", "pier_left");
    await page.focus("#criterion-json");
    await page.keyboard.press("End");
    await page.keyboard.type("]}]}");
    const typed = JSON.parse(await page.inputValue("#criterion-json"));
    assert(JSON.stringify(typed) === JSON.stringify({ kind: "any", of: [{ kind: "drop", block: "v8", metres: 0.05 }, { kind: "fallen", blocks: ["pier_left"] }] }), JSON.stringify(typed));
    // A fixed block is not offered (and the server refuses it, naming the field).
    const offered = await page.$$eval("#criterion-insert option", (os) => os.map((o) => o.value));
    assert(!offered.includes("foundation") && offered.includes("v1"), `offered: ${offered}`);
    // (The service checks the first block a criterion names at submission; docs/format.md.)
    await page.fill("#criterion-json", '{"kind": "drop", "block": "foundation", "metres": 0.05}');
    await page.click("#submit-button");
    await page.waitForFunction(() => document.getElementById("criterion-error").textContent.length > 0, null, { timeout: 10000 });
    const err = await page.textContent("#criterion-error");
    assert(err.includes("/criterion") && err.includes('"foundation"'), err);
    assert((await page.getAttribute("#criterion-json", "aria-invalid")) === "true", "the criterion field is not marked invalid");
    // Bad JSON is caught before sending.
    await page.fill("#criterion-json", '{"kind": "fallen", "blocks": ["v8"]');
    await page.click("#submit-button");
    await page.waitForFunction(() => /not valid JSON/.test(document.getElementById("criterion-error").textContent), null, { timeout: 5000 });
  });

  await check("damage criterion: a PGA search with a JSON criterion runs", async () => {
    // The column under the record already loaded, as in the search above: rotation beyond 2°.
    await page.selectOption("#scene-example", "column");
    await page.waitForFunction(() => document.querySelectorAll("#scene-svg polygon").length === 2);
    await page.click('#scene-svg polygon[data-id="column"]'); // not the JSON criterion: picks the block
    await page.fill("#criterion-json", '{"kind": "rotation", "block": "column", "degrees": 2}');
    await page.click("#submit-button");
    await page.waitForFunction(() => /Queued PGA search/.test(document.getElementById("submit-status").textContent), null, { timeout: 20000 });
    const id = (await page.textContent("#submit-status")).match(/Queued PGA search (\w+)/)[1];
    await page.waitForFunction((id) => new RegExp(`PGA search ${id}: succeeded`).test(document.getElementById("result-head").textContent) && !document.getElementById("pga-view").hidden, id, { timeout: 300000 });
    const text = await page.textContent("#pga-summary");
    assert(text.includes('"kind":"rotation"') || text.includes('"kind": "rotation"'), text);
    console.log(`     ${text.slice(0, 160)}`);
    await page.selectOption("#criterion-kind", "toppled");
    await page.check('input[name="analysis"][value="run"]');
  });

  await check("DXF upload: a scene drawn, a 422 naming the entity shown, a server without the route told apart (route stubbed)", async () => {
    const dxf = "0\nSECTION\n2\nENTITIES\n0\nENDSEC\n0\nEOF\n";
    const scene = JSON.parse(readFileSync(new URL("../../examples/two-columns.json", import.meta.url), "utf8"));
    let sent = null;
    let answer = { status: 200, contentType: "application/json", body: JSON.stringify(scene) };
    await page.route("**/v1/scenes/import", async (route) => {
      sent = { method: route.request().method(), type: route.request().headers()["content-type"], body: route.request().postDataJSON() };
      await route.fulfill(answer);
    });
    try {
      await page.setInputFiles("#dxf-file", { name: "survey.dxf", mimeType: "application/dxf", buffer: Buffer.from(dxf) });
      await page.waitForFunction((n) => /^survey\.dxf: /.test(document.getElementById("scene-info").textContent) && document.querySelectorAll("#scene-svg polygon").length === n, scene.blocks.length, { timeout: 10000 });
      assert(sent && sent.method === "POST" && sent.type === "application/json" && sent.body.dxf === dxf && sent.body.options === null && Object.keys(sent.body).length === 2, `request: ${JSON.stringify(sent)}`);
      assert((await page.$eval("#scene-example", (s) => s.value)) === "", "the example picker still shows an example");
      const problem = { type: "about:blank", title: "invalid drawing", status: 422, detail: "entity 2F (LWPOLYLINE) on layer \"marble\": the polyline is not closed", pointer: "/dxf" };
      answer = { status: 422, contentType: "application/problem+json", body: JSON.stringify(problem) };
      await page.setInputFiles("#dxf-file", { name: "open.dxf", mimeType: "application/dxf", buffer: Buffer.from(dxf) });
      await page.waitForFunction(() => document.getElementById("dxf-error").textContent.length > 0, null, { timeout: 10000 });
      const text = await page.textContent("#dxf-error");
      assert(text.includes("open.dxf") && text.includes("2F") && text.includes('"marble"'), text);
      assert((await page.getAttribute("#dxf-file", "aria-invalid")) === "true", "the DXF field is not marked invalid");
      // A pending motion inspection clears its own slots only: it once un-marked this field too
      // (CI, under load, when the debounced inspect fired after the 422).
      await page.evaluate(() => clearErrors(["motion", "scale"]));
      assert((await page.getAttribute("#dxf-file", "aria-invalid")) === "true", "clearing the motion's errors un-marked the DXF field");
      // This binary's own answer for a route it does not have, as a server before the import.
      const missing = await fetch(`${base}/v1/scenes/import`, { method: "POST", headers: { "Content-Type": "application/json" }, body: "{}" });
      answer = { status: 404, contentType: "application/problem+json", body: JSON.stringify({ type: "about:blank", title: "not found", status: 404, detail: "no route /v1/scenes/import" }) };
      if (missing.status === 404) answer.body = await missing.text();
      await page.setInputFiles("#dxf-file", { name: "any.dxf", mimeType: "application/dxf", buffer: Buffer.from(dxf) });
      await page.waitForFunction(() => /cannot import DXF/.test(document.getElementById("dxf-error").textContent), null, { timeout: 10000 });
    } finally {
      // Unrouted even when an assertion fails, so the next check reaches the real server.
      await page.unroute("**/v1/scenes/import");
    }
  });

  await check("DXF upload against the real POST /v1/scenes/import: an ezdxf drawing (tests/fixtures/dxf) becomes its scene, every vertex within 1e-9 m; a bad drawing's 422 names the entity", async () => {
    const fixture = (name) => readFileSync(new URL(`../fixtures/dxf/${name}`, import.meta.url));
    const want = JSON.parse(fixture("wall_mm.json").toString("utf8"));
    const calls = [];
    const onResponse = (r) => { if (r.url().endsWith("/v1/scenes/import")) calls.push(r.status()); };
    page.on("response", onResponse);
    try {
      await page.setInputFiles("#dxf-file", { name: "wall_mm.dxf", mimeType: "application/dxf", buffer: fixture("wall_mm.dxf") });
      await page.waitForFunction((n) => /^wall_mm\.dxf: /.test(document.getElementById("scene-info").textContent) && document.querySelectorAll("#scene-svg polygon").length === n, want.blocks.length, { timeout: 20000 });
      const got = await page.evaluate(() => state.scene);
      assert(got.blocks.length === want.blocks.length, `${got.blocks.length} blocks, the drawing has ${want.blocks.length}`);
      let worst = 0;
      want.blocks.forEach((w, k) => {
        const b = got.blocks[k];
        assert(b.id === `${w.layer}-${w.handle}` && Boolean(b.fixed) === w.fixed, `block ${k}: ${b.id} fixed=${b.fixed}, want ${w.layer}-${w.handle} fixed=${w.fixed}`);
        assert(b.vertices.length === w.vertices.length, `${b.id}: ${b.vertices.length} vertices, want ${w.vertices.length}`);
        b.vertices.forEach((v, i) => { for (const c of [0, 1]) worst = Math.max(worst, Math.abs(v[c] - w.vertices[i][c])); });
      });
      // 1e-9 m: the issue's target for DXF import (the conversion is exact to rounding).
      assert(worst <= 1e-9, `largest vertex error ${worst} m`);
      const bad = JSON.parse(fixture("bad_open.json").toString("utf8"));
      await page.setInputFiles("#dxf-file", { name: "bad_open.dxf", mimeType: "application/dxf", buffer: fixture("bad_open.dxf") });
      await page.waitForFunction(() => document.getElementById("dxf-error").textContent.length > 0, null, { timeout: 20000 });
      const text = await page.textContent("#dxf-error");
      assert(text.includes("bad_open.dxf") && text.includes(`entity ${bad.handle} on layer "${bad.layer}"`), text);
      assert(calls.length === 2 && calls[0] === 200 && calls[1] === 422, `the real route answered ${calls}`);
      console.log(`     ${want.blocks.length} blocks, largest vertex error ${worst.toExponential(2)} m; ${text.slice(0, 120)}`);
    } finally {
      page.off("response", onResponse);
    }
  });

  await check("site analysis: observations entered (fell / stands), records picked, submitted, intervals and the distribution shown", async () => {
    const scene = readFileSync(new URL("../../examples/two-columns.json", import.meta.url));
    await page.setInputFiles("#scene-file", { name: "two-columns.json", mimeType: "application/json", buffer: scene });
    await page.waitForFunction(() => /^two-columns\.json: .*\(2 free\)/.test(document.getElementById("scene-info").textContent), null, { timeout: 10000 });
    await page.fill("#duration", "1.5");
    await page.check('input[name="analysis"][value="site"]');
    assert(!(await page.isHidden("#site-box")) && !(await page.isHidden("#pga-fields")), "the observations are not offered");
    // No observation yet: refused on the page, next to the observations.
    await page.click("#submit-button");
    await page.waitForFunction(() => /at least one observation/.test(document.getElementById("observations-error").textContent), null, { timeout: 5000 });
    // A fell (clicked on the drawing), B stands (a JSON criterion).
    await page.selectOption("#criterion-kind", "toppled");
    await page.click('#scene-svg polygon[data-id="A"]');
    await page.click("#obs-add-fell");
    await page.selectOption("#criterion-kind", "json");
    await page.fill("#criterion-json", '{"kind": "fallen", "blocks": ["B"]}');
    await page.click("#obs-add-stood");
    const rows = await page.$$eval("#obs-body tr", (rs) => rs.map((r) => [r.querySelector("code").textContent, r.querySelector("select").value]));
    assert(JSON.stringify(rows) === JSON.stringify([["toppled:A", "seen"], ['{"kind": "fallen", "blocks": ["B"]}', "not"]]), JSON.stringify(rows));
    // Two records: two half-sine pulses as record files (JSON ground motions).
    const pulseFile = (period) => ({ name: `pulse-${period}s.json`, mimeType: "application/json", buffer: Buffer.from(JSON.stringify({ horizontal: { pulse: { amplitude: 1, period, cycles: 0.5, units: "m/s2" } } })) });
    await page.check('input[name="motion-source"][value="record"]');
    await page.setInputFiles("#record-file", [pulseFile(0.5), pulseFile(0.7)]);
    await page.fill("#range-min", "2");
    await page.fill("#range-max", "14");
    await page.selectOption("#range-units", "m/s2");
    await page.fill("#tolerance", "0.5");
    await page.fill("#scan-points", "4");
    const sent = page.waitForRequest((r) => r.url().endsWith("/v1/site-analyses") && r.method() === "POST", { timeout: 20000 });
    await page.click("#submit-button");
    const body = (await sent).postDataJSON();
    assert(body.motions.length === 2 && body.observations.length === 2 && body.observations[0].observed === true && body.observations[1].observed === false, JSON.stringify(body).slice(0, 300));
    await page.waitForFunction(() => /Queued site analysis/.test(document.getElementById("submit-status").textContent), null, { timeout: 20000 });
    const id = (await page.textContent("#submit-status")).match(/Queued site analysis (\w+)/)[1];
    await page.waitForFunction((id) => new RegExp(`Site analysis ${id}: succeeded`).test(document.getElementById("result-head").textContent) && !document.getElementById("site-view").hidden, id, { timeout: 300000 });
    // What the page shows is the stored result.
    const job = await (await fetch(`${base}/v1/jobs?kind=site_analysis&limit=1`)).json();
    const r = job.jobs[0].result;
    const recs = await page.$$eval("#site-records tbody tr", (rs) => rs.map((x) => x.textContent));
    assert(recs.length === 2 && recs[0].startsWith("pulse-0.5s.json") && recs[1].startsWith("pulse-0.7s.json"), JSON.stringify(recs));
    const dist = await page.textContent("#site-distribution");
    const d = r.distribution;
    const shown = (v) => dist.includes(String(Number(Number(v).toPrecision(3)))); // the page's fmt()
    assert(d.lognormal || d.empirical, `no distribution: ${JSON.stringify(d).slice(0, 300)}`);
    for (const p of [d.lognormal, d.empirical]) if (p) assert(shown(p.median), `median ${p.median} not in: ${dist}`);
    assert(/independent given the PGA/.test(await page.textContent("#site-assumes")), "the assumption is not stated");
    assert((await colouredPixels(page, "plot-site")) > 100, "the distribution is not drawn");
    console.log(`     ${recs.join(" | ").slice(0, 200)}`);
    console.log(`     ${dist.slice(0, 200)}`);
    // The page's worked example is docs/observations.md's: A fell, B stands, under the bundled
    // pulse; the interval there is [5.63, 8.60] m/s² (A's threshold is Housner's overturning
    // amplitude, checked by an independent RK4 in tests/engine/rocking.rs).
    await page.click("#site-example");
    await page.waitForFunction(() => document.querySelectorAll("#obs-body tr").length === 2 && document.querySelectorAll("#scene-svg polygon").length === 3, null, { timeout: 10000 });
    await page.click("#submit-button");
    await page.waitForFunction((prev) => { const m = document.getElementById("submit-status").textContent.match(/Queued site analysis (\w+)/); return m && m[1] !== prev; }, id, { timeout: 20000 });
    const id2 = (await page.textContent("#submit-status")).match(/Queued site analysis (\w+)/)[1];
    await page.waitForFunction((id) => new RegExp(`Site analysis ${id}: succeeded`).test(document.getElementById("result-head").textContent) && !document.getElementById("site-view").hidden, id2, { timeout: 300000 });
    const worked = await page.textContent("#site-records");
    // The interval's ends as shown (3 significant digits): A's bracket is refined to the
    // example's tolerance (0.02 m/s²) and holds Housner's 5.64, so its lower end is within
    // 0.02 + the display's rounding (0.005) of it; B's upper end likewise of 8.60 (the engine's,
    // docs/observations.md). The exact digits move with the search's lattice (session 39: 5.63).
    const cells = await page.$$eval("#site-records tbody tr:first-child td", (tds) => tds.map((t) => parseFloat(t.textContent)));
    assert(cells.length >= 2 && Math.abs(cells[0] - 5.64) <= 0.025 && Math.abs(cells[1] - 8.6) <= 0.025, `worked example: ${worked} (${JSON.stringify(cells)})`);
    console.log(`     worked example: ${worked.slice(0, 160)}`);
    await page.selectOption("#criterion-kind", "toppled");
    await page.check('input[name="analysis"][value="run"]');
    await page.fill("#duration", "");
  });

  await check("a single run judged by a damage criterion: the control in run mode, `criterion` sent, met / not met shown", async () => {
    // docs/observations.md: under the 1 s half-sine pulse, column A of examples/two-columns.json
    // topples from 5.64 m/s² (Housner's amplitude, independent RK4 in tests/engine/rocking.rs) and
    // B stands up to 8.60 m/s². At 7 m/s², A falls and B stands (`ashlar run --criterion` agrees).
    const scene = readFileSync(new URL("../../examples/two-columns.json", import.meta.url));
    await page.setInputFiles("#scene-file", { name: "two-columns.json", mimeType: "application/json", buffer: scene });
    await page.waitForFunction(() => /^two-columns\.json: .*\(2 free\)/.test(document.getElementById("scene-info").textContent), null, { timeout: 10000 });
    // (isHidden is also true of an element that is not there.)
    assert((await page.$("#run-judge")) !== null && (await page.$("#criterion-box")) !== null, "the page has no run criterion control");
    await page.check('input[name="analysis"][value="pga"]');
    assert(await page.isHidden("#run-judge-row"), "the run's criterion control is offered in a PGA search");
    await page.check('input[name="analysis"][value="run"]');
    assert(!(await page.isHidden("#run-judge-row")), "no criterion control in run mode");
    assert(await page.isHidden("#criterion-box"), "the criterion builder shows before the run is to be judged");
    await page.check("#run-judge");
    assert(!(await page.isHidden("#criterion-box")), "the criterion builder does not show when the run is to be judged");
    await page.check('input[name="motion-source"][value="pulse"]');
    await page.selectOption("#pulse-shape", "sine");
    await page.fill("#pulse-amplitude", "7");
    await page.selectOption("#pulse-units", "m/s2");
    await page.fill("#pulse-period", "1");
    await page.fill("#pulse-cycles", "0.5");
    await page.check('input[name="scale-mode"][value="none"]');
    const judged = async (expect) => {
      const sent = page.waitForRequest((r) => r.url().endsWith("/v1/jobs") && r.method() === "POST", { timeout: 20000 });
      const prev = ((await page.textContent("#submit-status")).match(/Queued run (\w+)/) || [])[1];
      await page.click("#submit-button");
      const body = (await sent).postDataJSON();
      assert(JSON.stringify(body.criterion) === JSON.stringify(expect.criterion) && body.motion.horizontal.pulse.amplitude === 7, `sent: ${JSON.stringify({ criterion: body.criterion, motion: body.motion })}`);
      await page.waitForFunction((prev) => { const m = document.getElementById("submit-status").textContent.match(/Queued run (\w+)/); return m && m[1] !== prev; }, prev, { timeout: 20000 });
      const id = (await page.textContent("#submit-status")).match(/Queued run (\w+)/)[1];
      await page.waitForFunction((id) => new RegExp(`Run ${id}: succeeded`).test(document.getElementById("result-head").textContent) && !document.getElementById("run-view").hidden, id, { timeout: 180000 });
      const rows = await page.$$eval("#criteria tbody tr", (rs) => rs.map((r) => [r.querySelector("code").textContent, r.querySelector(".badge").textContent, r.dataset.met]));
      // The service gives a criterion back in its own text form (compact JSON for a damage object).
      const shown = [].concat(expect.shown), met = [].concat(expect.met);
      const want = shown.map((c, k) => [c, met[k] ? "met" : "not met", String(met[k])]);
      assert(JSON.stringify(rows) === JSON.stringify(want), `shown ${JSON.stringify(rows)}, want ${JSON.stringify(want)}`);
      // What the page shows is the stored summary, and agrees with the per-block table.
      const job = await (await fetch(`${base}/v1/jobs?kind=run&limit=1`)).json();
      const s = job.jobs[0].summary;
      assert(job.jobs[0].id.startsWith(id) && JSON.stringify(s.criteria) === JSON.stringify(shown.map((c, k) => ({ criterion: c, met: met[k] }))), `stored: ${JSON.stringify(s.criteria)}`);
      const toppled = Object.fromEntries(s.blocks.map((b) => [b.id, b.toppled]));
      assert(toppled.A === true && toppled.B === false, `A and B at 7 m/s²: ${JSON.stringify(toppled)}`);
      console.log(`     ${expect.criterion}: ${rows[0][1]} (run ${id}, failure mode ${s.failure_mode})`);
    };
    // A by a click on the drawing (toppled:A): met.
    await page.selectOption("#criterion-kind", "toppled");
    await page.click('#scene-svg polygon[data-id="A"]');
    await judged({ criterion: "toppled:A", shown: "toppled:A", met: true });
    // B as a JSON damage criterion, its id inserted from the drawing: not met.
    await page.selectOption("#criterion-kind", "json");
    await page.fill("#criterion-json", '{"kind": "fallen", "blocks": [');
    await page.focus("#criterion-json");
    await page.keyboard.press("End");
    await page.click('#scene-svg polygon[data-id="B"]');
    await page.focus("#criterion-json");
    await page.keyboard.press("End");
    await page.keyboard.type("]}");
    await judged({ criterion: '{"kind": "fallen", "blocks": ["B"]}', shown: '{"kind":"fallen","blocks":["B"]}', met: false });
    // Several criteria in one run (the API's array): both added to the list, both judged.
    assert(!(await page.isHidden("#crit-add")) && await page.isHidden("#crit-combine"), "the list's controls in run mode");
    await page.click("#crit-add");
    await page.selectOption("#criterion-kind", "toppled");
    await page.click('#scene-svg polygon[data-id="A"]');
    await page.click("#crit-add");
    assert((await page.$$("#crit-body tr")).length === 2, "two criteria listed");
    await judged({
      criterion: ['{"kind": "fallen", "blocks": ["B"]}', "toppled:A"],
      shown: ['{"kind":"fallen","blocks":["B"]}', "toppled:A"], met: [false, true],
    });
    // A PGA search sends the list with how it combines (checked on the request; not run here).
    await page.check('input[name="analysis"][value="pga"]');
    assert(!(await page.isHidden("#crit-combine")), "no combine control in a PGA search");
    await page.selectOption("#crit-combine", "any");
    let searched = null;
    await page.route("**/v1/pga-searches", async (route) => { searched = route.request().postDataJSON(); await route.abort(); });
    try {
      await page.click("#submit-button");
      for (let i = 0; i < 50 && searched === null; i++) await new Promise((r) => setTimeout(r, 100));
    } finally {
      await page.unroute("**/v1/pga-searches");
    }
    assert(searched && JSON.stringify(searched.criterion) === JSON.stringify(['{"kind": "fallen", "blocks": ["B"]}', "toppled:A"]) && searched.combine === "any",
      `search sent: ${JSON.stringify(searched && { criterion: searched.criterion, combine: searched.combine })}`);
    await page.check('input[name="analysis"][value="run"]');
    await page.click('button[aria-label="Remove criterion 2"]');
    await page.click('button[aria-label="Remove criterion 1"]');
    assert(await page.isHidden("#crit-table"), "the emptied list still shows");
    await page.selectOption("#criterion-kind", "toppled");
    await page.uncheck("#run-judge");
    assert(await page.isHidden("#criterion-box"), "the criterion builder stays after unticking");
  });

  if (baseTokens && token) {
    await check("token prompt: asked on 401, kept in sessionStorage, sent on every call, event stream and downloads", async () => {
      const p2 = await context.newPage();
      const errors = [];
      p2.on("pageerror", (e) => errors.push(String(e)));
      const calls = [];
      p2.on("request", (r) => { const u = r.url().replace(baseTokens, ""); if (u.startsWith("/v1/")) calls.push({ u, auth: r.headers().authorization || "", t: Date.now() }); });
      await p2.goto(`${baseTokens}/`);
      await p2.waitForSelector("#auth", { state: "visible", timeout: 10000 });
      assert((await p2.evaluate(() => sessionStorage.getItem("ashlar-token"))) === null, "a token is stored before one was given");
      assert((await p2.$$("#scene-example option[value=column]")).length === 0, "examples listed without a token");
      // A wrong token is refused and asked again.
      await p2.fill("#token", "not-the-right-token-0000");
      await p2.click("#token-submit");
      await p2.waitForFunction(() => /refused/.test(document.getElementById("token-error").textContent) && !document.getElementById("auth").hidden, null, { timeout: 10000 });
      await p2.fill("#token", token);
      const t0 = Date.now();
      await p2.click("#token-submit");
      await p2.waitForSelector("#scene-example option[value=column]", { state: "attached", timeout: 10000 });
      assert(await p2.isHidden("#auth"), "the prompt is still shown");
      assert((await p2.evaluate(() => sessionStorage.getItem("ashlar-token"))) === token, "the token is not in sessionStorage");
      await p2.waitForSelector("#template option[value=drum-column]", { state: "attached", timeout: 10000 });
      // A run of the column under the bundled pulse: submitted, followed, shown. The full
      // engine and 20 s, so that it is still running when the page follows it (the reduced model
      // would end before). The events the page's fetch-based stream delivers are counted.
      await p2.evaluate(() => {
        const inner = fetchEvents;
        window.__events = [];
        fetchEvents = (url) => {
          const es = inner(url);
          const add = es.addEventListener;
          es.addEventListener = (type, fn) => add(type, (ev) => { window.__events.push(type); fn(ev); });
          return es;
        };
      });
      await p2.selectOption("#scene-example", "column");
      await p2.check('input[name="motion-source"][value="example"]');
      await p2.fill("#duration", "20");
      await p2.selectOption("#model", "dda");
      await p2.click("#submit-button");
      await p2.waitForFunction(() => /: succeeded/.test(document.getElementById("result-head").textContent) && !document.getElementById("run-view").hidden, null, { timeout: 120000 });
      const events = await p2.evaluate(() => window.__events);
      assert(events.includes("end"), `events read through the token-carrying stream: ${events}`);
      const [dl] = await Promise.all([p2.waitForEvent("download", { timeout: 10000 }), p2.click("#dl-csv")]);
      const path = await dl.path();
      const csv = readFileSync(path, "utf8");
      assert(csv.startsWith("time_s,column.x_m"), `downloaded: ${csv.slice(0, 60)}`);
      // After the token: every API call carried it (the page's reads, the submission, the job's
      // event stream when it was followed, the download).
      const after = calls.filter((c) => c.t >= t0);
      const bare = after.filter((c) => c.auth !== `Bearer ${token}`);
      assert(after.length >= 5 && bare.length === 0, `${bare.length} of ${after.length} calls without the token: ${bare.map((c) => c.u).join(", ")}`);
      assert(after.some((c) => c.u.endsWith("histories?format=csv")), `no download call: ${after.map((c) => c.u).join(", ")}`);
      // A reload keeps the token (same tab): no prompt.
      await p2.reload();
      await p2.waitForSelector("#scene-example option[value=column]", { state: "attached", timeout: 10000 });
      assert(await p2.isHidden("#auth"), "asked again after a reload");
      assert(errors.length === 0, `script errors: ${errors.join(" | ")}`);
      await p2.close();
    });
  }

  await check("no script errors, nothing fetched from another host", async () => {
    assert(pageErrors.length === 0, `errors: ${pageErrors.join(" | ")}`);
    assert(foreign.length === 0, `foreign requests: ${foreign.join(", ")}`);
  });
} finally {
  await context.close();
  rmSync(userDataDir, { recursive: true, force: true });
}

console.log(`web e2e: ${passed} passed, ${failed} failed`);
process.exit(failed ? 1 : 0);
