#!/usr/bin/env node
// Loads the viewer page from file:// in headless Chromium (Debian's, driven by playwright-core) and
// checks that every mesh of its manifest loads, is drawn in its pane and matches the run's triangle
// count, that a drag turns and the wheel zooms, with no console error, page error or failed request;
// keeps a screenshot per model.
//
//   node viewer/test/browser.mjs results/viewer/index.html [--screenshots results/viewer/screenshots]
import fs from "node:fs";
import os from "node:os";
import path from "node:path";
import { execFileSync } from "node:child_process";
import { pathToFileURL } from "node:url";
import { chromium } from "playwright-core";

const args = process.argv.slice(2);
const page_ = args.find((a) => !a.startsWith("--"));
const shotsAt = args.indexOf("--screenshots");
const shots = shotsAt >= 0 ? args[shotsAt + 1] : null;
const fail = (msg) => {
  console.error("test_viewer_browser: FAIL: " + msg);
  process.exit(1);
};
if (!page_ || !fs.existsSync(page_)) fail("no page " + page_ + " (make viewer writes results/viewer/index.html)");

function chromiumPath() {
  for (const name of ["chromium", "chromium-browser", "google-chrome"]) {
    try {
      return execFileSync("sh", ["-c", "command -v " + name], { encoding: "utf8" }).trim();
    } catch { /* next */ }
  }
  fail("no chromium on PATH; install it with: bash scripts/install-deps.sh --browser");
}

// Each screenshot also exercises one display mode.
const MODES = [
  { shading: "phong", wireframe: false, color: "none" },
  { shading: "flat", wireframe: true, color: "none" },
  { shading: "phong", wireframe: false, color: "shape_index" },
  { shading: "phong", wireframe: true, color: "none" },
  { shading: "phong", wireframe: false, color: "mac" },
  { shading: "flat", wireframe: true, color: "mean" },
];
const MIN_COVERAGE = 0.01;

const profile = fs.mkdtempSync(path.join(os.tmpdir(), "cdp-viewer-test-"));
const problems = [];
let context;
try {
  // --no-sandbox: CI containers run as root, where Chromium's sandbox refuses to start. The rest keep
  // a headless run from reaching the network or updating itself.
  context = await chromium.launchPersistentContext(profile, {
    executablePath: chromiumPath(), headless: true, viewport: { width: 1400, height: 800 },
    args: ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--no-first-run",
      "--disable-component-update", "--disable-sync", "--enable-unsafe-swiftshader"],
  });
  const page = await context.newPage();
  page.on("console", (m) => m.type() === "error" && problems.push("console error: " + m.text()));
  page.on("pageerror", (e) => problems.push("page error: " + e.message));
  page.on("requestfailed", (r) => problems.push("failed request: " + r.url() + " (" + r.failure().errorText + ")"));
  // Only files beside the page: the viewer must need no network.
  await page.route((url) => url.protocol !== "file:", (route) => {
    problems.push("network request: " + route.request().url());
    return route.abort();
  });
  await page.goto(pathToFileURL(path.resolve(page_)).href);
  await page.waitForFunction(() => window.cdpViewer || !document.getElementById("message").hidden, null,
    { timeout: 30000 });
  const missing = await page.evaluate(() => !window.cdpViewer && document.getElementById("message").textContent);
  if (missing) throw new Error(missing);
  await page.evaluate(() => window.cdpViewer.ready);
  const models = await page.evaluate(() => window.cdpViewer.manifest.models.map((m) => ({
    id: m.id, runs: m.runs.map((r) => ({ key: r.key, method: r.method,
      triangles: Number((r.figures.find((f) => f[0] === "triangles") || [])[1]) })) })));
  if (shots) fs.mkdirSync(shots, { recursive: true });
  let meshes = 0;
  for (const [i, model] of models.entries()) {
    const baselines = model.runs.filter((r) => r.method !== "adaptive");
    for (const b of baselines) {
      await page.evaluate(([id, vs]) => window.cdpViewer.show(id, vs), [model.id, b.method]);
      const cover = await page.evaluate(() => window.cdpViewer.coverage());
      cover.forEach((c, side) => c < MIN_COVERAGE &&
        problems.push(model.id + ": the " + (side ? "right (" + b.method + ")" : "left (ours)") +
          " pane is empty (" + (100 * c).toFixed(2) + "% drawn)"));
    }
    const loaded = await page.evaluate(() => window.cdpViewer.loaded);
    for (const r of model.runs) {
      meshes++;
      if (!loaded[r.key]) problems.push(r.key + " did not load");
      else if (loaded[r.key].triangles !== r.triangles)
        problems.push(r.key + ": " + loaded[r.key].triangles + " triangles, the run had " + r.triangles);
    }
    if (shots) {
      await page.evaluate(([id, vs, mode]) => window.cdpViewer.show(id, vs).then(() => window.cdpViewer.set(mode)),
        [model.id, baselines.length ? baselines[0].method : null, MODES[i % MODES.length]]);
      await page.screenshot({ path: path.join(shots, model.id + ".png") });
    }
  }
  // Turning and zooming with the mouse, as a person would: a drag on the left pane, then the wheel.
  const box = await page.locator("#view").boundingBox();
  const before = await page.evaluate(() => window.cdpViewer.view());
  await page.mouse.move(box.x + box.width / 4, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width / 4 + 120, box.y + box.height / 2 + 40, { steps: 8 });
  await page.mouse.up();
  const turned = await page.evaluate(() => window.cdpViewer.view());
  await page.mouse.wheel(0, -400);
  await page.waitForTimeout(200);
  const zoomed = await page.evaluate(() => window.cdpViewer.view());
  if (turned.position.every((v, k) => Math.abs(v - before.position[k]) < 1e-9)) problems.push("a drag did not turn the view");
  if (!(zoomed.distance < turned.distance)) problems.push("the wheel did not zoom in");
  problems.push(...(await page.evaluate(() => window.cdpViewer.errors)).map((e) => "viewer error: " + e));
  if (problems.length) throw new Error(problems.slice(0, 20).join("\n  "));
  console.log("test_viewer_browser: ok: " + meshes + " meshes of " + models.length + " models load and draw in " +
    page_ + (shots ? "; screenshots in " + shots : ""));
} catch (e) {
  process.exitCode = 1;
  console.error("test_viewer_browser: FAIL: " + e.message);
} finally {
  if (context) await context.close();
  fs.rmSync(profile, { recursive: true, force: true });
}
