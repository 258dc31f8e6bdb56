// SPDX-License-Identifier: BSD-3-Clause
// tests/viewer/browser/viewer_browser_test.mjs -- penumbra-view in Debian's chromium, headless,
// driven by playwright-core: the example's database shown pixel for pixel, time and orbit moved
// through the controls and the keys, the state in the URL, a 3D mouse's recorded reports moving the
// view, a live run's new rows, clear messages; with the run's store, a free camera rendered by the
// server against penumbra-replay's offline render of the same camera and step.
//
// usage: node viewer_browser_test.mjs PENUMBRA_VIEW EXAMPLE_PROGRAM OUT_DIR [CHROMIUM [PENUMBRA_REPLAY]]
import { spawn, execFileSync } from "node:child_process";
import fs from "node:fs";
import path from "node:path";
import { chromium } from "playwright-core";

const [viewBin, exampleBin, outDir, chromiumPath = "/usr/bin/chromium", replayBin = "none"] = process.argv.slice(2);
let failures = 0;
function check(ok, what) {
  console.log((ok ? "ok   " : "FAIL ") + what);
  if (!ok) failures += 1;
}

// A database made by the example mini-app.
const db = path.join(outDir, "example-db");
fs.rmSync(outDir, { recursive: true, force: true });
fs.mkdirSync(outDir, { recursive: true });
execFileSync(exampleBin, [db], { stdio: "ignore" });
const rows = fs.readFileSync(path.join(db, "data.csv"), "utf8").trim().split("\n").map((l) => l.split(","));
const header = rows[0];
const fileOf = (time, phi, theta) => rows.find((r) => r[0] === time && r[1] === phi && r[2] === theta).at(-1);

// A 3D mouse's recorded reports (newer layout: id 1, then translation and rotation as int16 little
// endian): slid left, pushed down and twisted counterclockwise seen from above (x -350, z +350,
// rz -350) for 36 reports 30 ms apart, then at rest. penumbra-view plays them through its parser and
// mapping when it gets SIGUSR1. Each report stands for 30 to 50 ms: phi turns by 97 to 162 degrees.
const spacemouseScript = path.join(outDir, "spacemouse.script");
fs.writeFileSync(spacemouseScript, "30 01 a2 fe 00 00 5e 01 00 00 00 00 a2 fe\n".repeat(36) + "30 01" + " 00".repeat(12) + "\n");

// penumbra-view on a free port; the URL it prints carries the token.
function startViewer(dir, extra = []) {
  const child = spawn(viewBin, [dir, ...extra], { stdio: ["ignore", "pipe", "inherit"] });
  return new Promise((resolve, reject) => {
    let out = "";
    child.stdout.on("data", (d) => {
      out += d;
      const m = out.match(/http:\/\/\S+token=[0-9a-f]+/);
      if (m) resolve({ child, url: m[0] });
    });
    child.on("exit", (code) => reject(new Error("penumbra-view exited " + code)));
  });
}

// The pixels of the image the page shows, and of `file` decoded by the same browser.
async function shownPixels(page) {
  return page.evaluate(() => {
    const img = document.getElementById("image");
    const c = document.createElement("canvas");
    c.width = img.naturalWidth;
    c.height = img.naturalHeight;
    c.getContext("2d").drawImage(img, 0, 0);
    return Array.from(c.getContext("2d").getImageData(0, 0, c.width, c.height).data);
  });
}
async function filePixels(page, file, dir = db) {
  const data = "data:image/png;base64," + fs.readFileSync(path.join(dir, file)).toString("base64");
  return page.evaluate(async (src) => {
    const img = new Image();
    img.src = src;
    await img.decode();
    const c = document.createElement("canvas");
    c.width = img.naturalWidth;
    c.height = img.naturalHeight;
    c.getContext("2d").drawImage(img, 0, 0);
    return Array.from(c.getContext("2d").getImageData(0, 0, c.width, c.height).data);
  }, data);
}
// page.waitForFunction evaluates strings, which the page's Content-Security-Policy forbids: poll.
async function waitUntil(page, predicate, arg, what) {
  for (const start = Date.now(); Date.now() - start < 10000; await new Promise((r) => setTimeout(r, 100)))
    if (await page.evaluate(predicate, arg)) return;
  throw new Error("timed out waiting for " + what);
}
const samePixels = (a, b) => a.length === b.length && a.every((v, i) => v === b[i]);
async function waitForFile(page, file) {
  await waitUntil(page, (f) => decodeURIComponent(document.getElementById("image").src).endsWith("/db/" + f), file, file);
}

const { child, url } = await startViewer(db, ["--spacemouse-script", spacemouseScript]);
// Without the background-networking flags chromium keeps trying hosts a closed network refuses.
const browser = await chromium.launch({
  executablePath: chromiumPath,
  args: ["--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run", "--disable-background-networking",
         "--disable-component-update", "--disable-sync"],
});
try {
  const page = await browser.newPage();
  await page.goto(url);
  const times = [...new Set(rows.slice(1).map((r) => r[0]))].sort((a, b) => Number(a) - Number(b));
  const first = rows[1];
  await waitForFile(page, first.at(-1));
  check(samePixels(await shownPixels(page), await filePixels(page, first.at(-1))), "the first row's image, pixel for pixel");
  check((await page.locator("#controls select, #controls input").count()) >= header.length - 1, "one control per parameter column");
  check((await page.locator("#free-panel").count()) === 0, "without a store, no free camera is offered");

  // Time by the key and by the slider; the state follows in the URL.
  await page.keyboard.press("ArrowRight");
  const next = fileOf(times[1], first[1], first[2]);
  await waitForFile(page, next);
  check(samePixels(await shownPixels(page), await filePixels(page, next)), "ArrowRight: the next time's image, pixel for pixel");
  check(new URL(page.url()).hash.includes("time=" + times[1]), "the time is in the URL");
  await page.locator("#control-time").fill(String(times.length - 1));
  await waitForFile(page, fileOf(times.at(-1), first[1], first[2]));
  check(true, "the time slider moves to the last time");

  // Orbit through the phi control and by dragging on the image.
  const phis = [...new Set(rows.slice(1).map((r) => r[1]))].sort((a, b) => Number(a) - Number(b));
  await page.locator("#control-phi").selectOption(phis[1]);
  await waitForFile(page, fileOf(times.at(-1), phis[1], first[2]));
  check(true, "the phi control orbits");
  const box = await page.locator("#image").boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  await page.mouse.down();
  await page.mouse.move(box.x + box.width / 2 + 30, box.y + box.height / 2, { steps: 4 });
  await page.mouse.up();
  await waitUntil(page, (p) => !document.getElementById("image").src.includes("_phi" + p + "_"), phis[1], "the drag");
  check(true, "dragging the image orbits to the neighbouring stored phi");

  // A shared link restores the state.
  const shared = url + "#time=" + times[2] + "&phi=" + phis[0] + "&theta=" + first[2];
  const other = await browser.newPage();
  await other.goto(shared);
  await waitForFile(other, fileOf(times[2], phis[0], first[2]));
  check(true, "a link with the state in its fragment shows that image");

  // The 3D mouse: its status in the page, then its reports orbit to the next stored phi (90 degrees
  // away; the one after is 90 more), move time back and zoom in.
  await page.locator("#control-phi").selectOption(phis[0]);
  await waitForFile(page, fileOf(times.at(-1), phis[0], first[2]));
  const device = () => page.locator("#device").textContent();
  await waitUntil(page, () => document.getElementById("device").textContent === "no 3D mouse found", null, "the 3D mouse's status");
  check(true, "the page shows the 3D mouse's status");
  child.kill("SIGUSR1");
  await waitUntil(page, () => document.getElementById("device").textContent.includes("unplugged"), null, "the scripted 3D mouse");
  check((await device()).startsWith("3D mouse unplugged"), "the 3D mouse's reports played, then it unplugged");
  const moved = new URLSearchParams(new URL(page.url()).hash.slice(1));
  check(moved.get("phi") === phis[1], "twisting the 3D mouse orbits to the next stored phi (" + moved.get("phi") + ")");
  check(times.indexOf(moved.get("time")) < times.length - 1, "sliding it left moves time back (" + moved.get("time") + ")");
  await waitForFile(page, fileOf(moved.get("time"), moved.get("phi"), first[2]));
  check(true, "the image follows the 3D mouse");
  check((await page.locator("#image").evaluate((img) => img.style.transform)).startsWith("scale("), "pushing it down zooms in");

  // Live: a new row appended by a running solver appears.
  const before = await page.locator("#status").textContent();
  fs.appendFileSync(path.join(db, "data.csv"), [String(Number(times.at(-1)) + 1), ...first.slice(1, -1), first.at(-1)].join(",") + "\n");
  await waitUntil(page, (b) => document.getElementById("status").textContent !== b, before, "the new row");
  check((await page.locator("#status").textContent()).startsWith(String(rows.length) + " images"), "a new row appears while the page is open");

  // A malformed data.csv gives a message, not a blank page.
  fs.appendFileSync(path.join(db, "data.csv"), "1,2\n");
  await waitUntil(page, () => !document.getElementById("message").hidden, null, "the message");
  check((await page.locator("#message").textContent()).includes("data.csv line"), "a malformed data.csv is named in the page");

  // Without the token: refused.
  const bare = await browser.newPage();
  const response = await bare.goto(url.replace(/\?token=.*/, ""));
  check(response.status() === 403, "the page without the token is refused");

  await page.screenshot({ path: path.join(outDir, "viewer.png") });
} catch (e) {
  check(false, "browser session: " + e.message);
} finally {
  child.kill("SIGTERM");
}
try {
  await freeCamera();
} catch (e) {
  check(false, "free camera session: " + e.message);
}
try {
  await degradedColumn();
} catch (e) {
  check(false, "degraded column session: " + e.message);
} finally {
  await browser.close();
}

// RMS difference of two RGBA pixel arrays over the colour channels, in percent of 255.
function rmsPercent(a, b) {
  let sum = 0, n = 0;
  for (let i = 0; i < a.length; ++i) if (i % 4 !== 3) { sum += (a[i] - b[i]) ** 2; ++n; }
  return (100 * Math.sqrt(sum / n)) / 255;
}

// The example's run again, with its store: the page's free camera at an angle the run never
// stored, against penumbra-replay's render of the same camera and step from the same store.
async function freeCamera() {
  const db2 = path.join(outDir, "example-store-db");
  execFileSync(exampleBin, [db2], { stdio: "ignore" });
  const viewer = await startViewer(db2, ["--store", path.join(db2, "store"), "--spacemouse-script", spacemouseScript]);
  try {
    const page = await browser.newPage();
    await page.goto(viewer.url);
    await page.locator("#free-panel").waitFor({ timeout: 10000 });
    check(true, "with a store, the free camera is offered");
    await page.locator("#free-on").check();
    await page.locator("#free-step").fill("5");
    for (const [id, value] of [["#free-phi", "45"], ["#free-theta", "10"]]) {
      await page.locator(id).fill(value);
      await page.locator(id).dispatchEvent("change");
    }
    const settled = () => !free.inFlight && !free.again && document.getElementById("image").src.startsWith("blob:") &&
      free.phi === 45 && free.theta === 10 && free.step === 5 && document.getElementById("free-timing").textContent !== "";
    await waitUntil(page, settled, null, "the free camera's render");
    await new Promise((r) => setTimeout(r, 300));
    await waitUntil(page, settled, null, "the free camera's last render");
    const shown = await shownPixels(page);
    check(shown.length === 128 * 128 * 4, "the free camera shows a rendered 128x128 image");
    if (replayBin === "none") {
      console.log("skip the offline comparison: penumbra-replay was not built");
    } else {
      const config = JSON.parse(fs.readFileSync(path.join(db2, "store", "config.json"), "utf8"));
      const offline = path.join(outDir, "offline-db");
      fs.rmSync(offline, { recursive: true, force: true });
      config.output = { directory: offline };
      config.cameras = { phi: [45], theta: [10], fov: config.cameras.fov };
      delete config.store;
      execFileSync(replayBin, [JSON.stringify(config), path.join(db2, "store"), "--steps", "5:6", "--quiet"]);
      const line = fs.readFileSync(path.join(offline, "data.csv"), "utf8").trim().split("\n")[1].split(",");
      const rms = rmsPercent(shown, await filePixels(page, line.at(-1), offline));
      console.log("free camera against penumbra-replay: RMS " + rms.toFixed(4) + " %");
      // The same store, camera and transfer function; only the light's start differs (the viewer
      // warm-starts from the step it showed before), and both converge to the light's tolerance.
      check(rms < 0.1, "the free camera matches penumbra-replay's offline render of that camera (RMS < 0.1 %)");
    }
    // Another transfer function: fully transparent, the background alone.
    await page.locator("#free-opacities").fill("0 0\n1 0");
    await page.locator("#free-apply").click();
    await waitUntil(page, () => !free.inFlight && !free.again && free.tf && free.tf.opacities[1][1] === 0, null, "the new transfer function");
    await new Promise((r) => setTimeout(r, 300));
    const blank = await shownPixels(page);
    check(blank.every((v, i) => i % 4 === 3 || Math.abs(v - blank[i % 4]) <= 1), "a transparent transfer function shows the background alone");
    // A bad transfer function is named in the page.
    await page.locator("#free-opacities").fill("0 x");
    await page.locator("#free-apply").click();
    check((await page.locator("#message").textContent()).includes("opacities line 1"), "a malformed transfer function is named in the page");
    // Back to the run's transfer function, for the README's picture of the page.
    await page.locator("#free-reset").click();
    await waitUntil(page, () => !free.inFlight && !free.again && free.tf === null, null, "the run's transfer function");
    await new Promise((r) => setTimeout(r, 300));
    await page.screenshot({ path: path.join(outDir, "viewer-free-camera.png") });
    // The 3D mouse's reports turn the free camera by their degrees (97 to 162), zoom it and step it back.
    await waitUntil(page, () => document.getElementById("device").textContent === "no 3D mouse found", null, "the 3D mouse's status");
    const before = await page.evaluate(() => ({ phi: free.phi, theta: free.theta, zoom: free.zoom, step: free.step }));
    viewer.child.kill("SIGUSR1");
    await waitUntil(page, () => document.getElementById("device").textContent.includes("unplugged"), null, "the scripted 3D mouse");
    const after = await page.evaluate(() => ({ phi: free.phi, theta: free.theta, zoom: free.zoom, step: free.step }));
    const turned = ((after.phi - before.phi + 540) % 360) - 180;
    check(turned > 90 && turned < 170 && after.theta === before.theta,
          "twisting the 3D mouse turns the free camera by its degrees (" + turned.toFixed(1) + ")");
    check(after.zoom > 1.5 * before.zoom && after.step < before.step, "pushing it down zooms the free camera in, sliding it left steps back");
  } finally {
    viewer.child.kill("SIGTERM");
  }
}
// A run with a "budget" adds a `degraded` column: the example's database with one, its first row
// degraded. The column gets no control; the page says what a shown image gave up, and nothing for
// one that gave up nothing.
async function degradedColumn() {
  const db3 = path.join(outDir, "degraded-db");
  fs.cpSync(db, db3, { recursive: true });
  const table = fs.readFileSync(path.join(db3, "data.csv"), "utf8").trim().split("\n").filter((l) => l.split(",").length === header.length);
  const withColumn = table.map((l, r) => {
    const cells = l.split(",");
    cells.splice(cells.length - 1, 0, r === 0 ? "degraded" : r === 1 ? "light+image:0.5" : "none");
    return cells.join(",");
  });
  fs.writeFileSync(path.join(db3, "data.csv"), withColumn.join("\n") + "\n");
  const viewer = await startViewer(db3);
  try {
    const page = await browser.newPage();
    const firstRow = table[1].split(",");
    await page.goto(viewer.url + "#time=" + firstRow[0] + "&phi=" + firstRow[1] + "&theta=" + firstRow[2]);
    await waitUntil(page, () => !document.getElementById("annotation").hidden, null, "the degraded image's note");
    check((await page.locator("#annotation").textContent()) === "degraded: light+image:0.5", "a degraded image says what it gave up");
    check((await page.locator("#control-degraded").count()) === 0, "the degraded column gets no control");
    await page.keyboard.press("ArrowRight");
    await waitUntil(page, () => document.getElementById("annotation").hidden, null, "the next image, not degraded");
    check(!new URL(page.url()).hash.includes("degraded"), "the degraded column is not part of the shared state");
  } finally {
    viewer.child.kill("SIGTERM");
  }
}

console.log(failures === 0 ? "viewer browser test: ok" : "viewer browser test: " + failures + " failure(s)");
process.exit(failures === 0 ? 0 : 1);
