// SPDX-License-Identifier: BSD-3-Clause
// viewer/assets/free_view.js -- views the run never stored, rendered by penumbra-view from the
// run's compressed history (penumbra-view --store): any orbit angle and zoom, any stored step,
// lighting on or off, another transfer function. Where the page is served without a store (or
// exported to a static server) the panel stays hidden.
"use strict";

const free = {
  info: null, phi: 0, theta: 30, zoom: 1, step: 0, field: 0, lit: true, tf: null,
  client: Math.random().toString(36).slice(2), inFlight: false, again: false, url: null,
};

function freeElement(tag, props, ...children) {
  const el = Object.assign(document.createElement(tag), props);
  el.append(...children);
  return el;
}
const byId = (id) => document.getElementById(id);

// A transfer function as the text of its editor: one control point per line.
const pointsText = (points) => points.map((p) => p.join(" ")).join("\n");
function parsePoints(text, width, what) {
  const points = text.split("\n").map((l) => l.trim()).filter(Boolean).map((l) => l.split(/[\s,]+/).map(Number));
  points.forEach((p, i) => {
    if (p.length !== width || p.some((v) => !Number.isFinite(v)))
      throw new Error(what + " line " + (i + 1) + ": expected " + width + " numbers");
  });
  if (points.length === 0) throw new Error(what + ": at least one point");
  return points;
}

function freeQuery() {
  const p = new URLSearchParams({
    step: free.step, field: free.field, phi: free.phi.toFixed(2), theta: free.theta.toFixed(2),
    zoom: free.zoom.toFixed(3), lit: free.lit ? 1 : 0, client: free.client,
  });
  if (free.tf) p.set("tf", JSON.stringify(free.tf));
  return p.toString();
}

// One request in flight per page: a change made meanwhile asks again when it returns, and the
// server drops this page's requests that are still waiting.
async function renderFree() {
  if (!view.free) return;
  if (free.inFlight) { free.again = true; return; }
  free.inFlight = true;
  try {
    const response = await fetch("api/render?" + freeQuery(), { cache: "no-store" });
    if (response.ok) {
      const url = URL.createObjectURL(await response.blob());
      if (view.free) {
        byId("image").src = url;
        if (free.url) URL.revokeObjectURL(free.url);
        free.url = url;
        const ms = (name) => response.headers.get("X-Penumbra-" + name + "-Ms");
        byId("free-timing").textContent = "rendered: load " + ms("Load") + " ms, light " + ms("Light") +
          " ms, render " + ms("Render") + " ms" + (response.headers.get("X-Penumbra-Light") ? " (light not converged)" : "");
        showMessage("");
      } else URL.revokeObjectURL(url);
    } else if (response.status === 503) {
      free.again = true;
    } else if (response.status !== 409) {
      showMessage((await response.text()).trim());
    }
  } catch (e) {
    showMessage("the view could not be rendered: " + e.message);
  } finally {
    free.inFlight = false;
    if (free.again) { free.again = false; setTimeout(renderFree, 0); }
  }
}

function syncFreeControls() {
  byId("free-step").value = String(free.step);
  byId("free-time").textContent = "time " + Number(free.info.times[free.step].toPrecision(6)) + " (cycle " + free.info.cycles[free.step] + ")";
  byId("free-phi").value = free.phi.toFixed(1);
  byId("free-theta").value = free.theta.toFixed(1);
  byId("free-zoom").value = String(free.zoom);
}

// Moves the free view; everything that changes it goes through here (controls, drag, keys, 3D mouse).
function moveFree(change) {
  if (change.phi !== undefined) free.phi = ((change.phi % 360) + 540) % 360 - 180;
  if (change.theta !== undefined) free.theta = Math.max(-90, Math.min(90, change.theta));
  if (change.zoom !== undefined) free.zoom = Math.max(0.25, Math.min(8, change.zoom));
  if (change.step !== undefined) free.step = Math.max(0, Math.min(free.info.times.length - 1, change.step));
  syncFreeControls();
  renderFree();
}

// Entering the free view starts from the stored view on screen.
function enterFree() {
  view.free = true;
  setZoom(view.zoom);
  const number = (name, fallback) => (isNumber(view.state[name] || "") ? Number(view.state[name]) : fallback);
  const time = number("time", free.info.times[0]);
  let nearest = 0;
  free.info.times.forEach((t, i) => { if (Math.abs(t - time) < Math.abs(free.info.times[nearest] - time)) nearest = i; });
  const field = free.info.fields.indexOf(view.state.field);
  free.field = field >= 0 ? field : free.field;
  byId("free-field").value = String(free.field);
  moveFree({ phi: number("phi", free.phi), theta: number("theta", free.theta), step: nearest });
}
function leaveFree() {
  view.free = false;
  setZoom(view.zoom);
  byId("free-timing").textContent = "";
  show(view.columns[0]);
}

function transferFunctionEditor() {
  const tf = free.info.transfer_functions[free.field];
  const colors = freeElement("textarea", { id: "free-colors", rows: 4, value: pointsText(tf.colors), spellcheck: false });
  const opacities = freeElement("textarea", { id: "free-opacities", rows: 3, value: pointsText(tf.opacities), spellcheck: false });
  const apply = freeElement("button", { type: "button", id: "free-apply", textContent: "Apply" });
  const reset = freeElement("button", { type: "button", id: "free-reset", textContent: "The run's" });
  apply.onclick = () => {
    try {
      free.tf = { colors: parsePoints(colors.value, 4, "colours"), opacities: parsePoints(opacities.value, 2, "opacities") };
      showMessage("");
      renderFree();
    } catch (e) { showMessage("transfer function: " + e.message); }
  };
  reset.onclick = () => {
    free.tf = null;
    colors.value = pointsText(free.info.transfer_functions[free.field].colors);
    opacities.value = pointsText(free.info.transfer_functions[free.field].opacities);
    renderFree();
  };
  return freeElement("div", { className: "tf" },
    freeElement("label", { htmlFor: "free-colors", textContent: "colours: x r g b per line" }), colors,
    freeElement("label", { htmlFor: "free-opacities", textContent: "opacities: x extinction per line" }), opacities,
    freeElement("div", { className: "row" }, apply, reset));
}

function buildFreePanel() {
  const on = freeElement("input", { type: "checkbox", id: "free-on" });
  on.onchange = () => (on.checked ? enterFree() : leaveFree());
  const stepSlider = freeElement("input", { type: "range", id: "free-step", min: 0, max: free.info.times.length - 1, step: 1 });
  stepSlider.oninput = () => moveFree({ step: Number(stepSlider.value) });
  const field = freeElement("select", { id: "free-field" });
  free.info.fields.forEach((name, i) => field.append(new Option(name, i)));
  field.onchange = () => { free.field = Number(field.value); free.tf = null; renderFree(); };
  const phi = freeElement("input", { type: "number", id: "free-phi", step: 1 });
  phi.onchange = () => moveFree({ phi: Number(phi.value) });
  const theta = freeElement("input", { type: "number", id: "free-theta", min: -90, max: 90, step: 1 });
  theta.onchange = () => moveFree({ theta: Number(theta.value) });
  const zoom = freeElement("input", { type: "range", id: "free-zoom", min: 0.25, max: 8, step: 0.05 });
  zoom.oninput = () => moveFree({ zoom: Number(zoom.value) });
  const lit = freeElement("input", { type: "checkbox", id: "free-lit", checked: true });
  lit.onchange = () => { free.lit = lit.checked; renderFree(); };
  const panel = freeElement("details", { id: "free-panel", open: true },
    freeElement("summary", { textContent: "New views (rendered from the run's store)" }),
    freeElement("label", {}, on, " free camera"),
    freeElement("label", { htmlFor: "free-step", textContent: "step (" + free.info.times.length + " stored)" }),
    stepSlider, freeElement("span", { id: "free-time" }),
    freeElement("label", { htmlFor: "free-field", textContent: "field" }), field,
    freeElement("div", { className: "row" },
      freeElement("label", { htmlFor: "free-phi", textContent: "phi" }), phi,
      freeElement("label", { htmlFor: "free-theta", textContent: "theta" }), theta),
    freeElement("label", { htmlFor: "free-zoom", textContent: "zoom" }), zoom,
    freeElement("label", {}, lit, " lighting (" + free.info.lighting + ")"),
    transferFunctionEditor(),
    freeElement("p", { id: "free-timing", className: "hint" }));
  document.querySelector("aside").prepend(panel);
  syncFreeControls();
}

// Free orbit by dragging (half a degree per pixel) and zoom by the wheel, while the free camera is on.
function setupFreeDrag() {
  const img = byId("image");
  let from = null;
  img.addEventListener("pointerdown", (e) => { if (view.free) from = { x: e.clientX, y: e.clientY }; });
  img.addEventListener("pointerup", () => { from = null; });
  img.addEventListener("pointermove", (e) => {
    if (!view.free || !from) return;
    const dx = e.clientX - from.x, dy = e.clientY - from.y;
    from = { x: e.clientX, y: e.clientY };
    moveFree({ phi: free.phi - 0.5 * dx, theta: free.theta + 0.5 * dy });
  });
  img.addEventListener("wheel", (e) => {
    if (!view.free) return;
    e.preventDefault();
    moveFree({ zoom: free.zoom * Math.exp(-e.deltaY / 500) });
  }, { passive: false });
}

function setupFreeKeys() {
  document.addEventListener("keydown", (e) => {
    if (!view.free || typingInto(e.target)) return;
    const moves = { ArrowLeft: { step: free.step - 1 }, ArrowRight: { step: free.step + 1 }, ArrowUp: { theta: free.theta + 5 },
                    ArrowDown: { theta: free.theta - 5 }, "[": { phi: free.phi - 5 }, "]": { phi: free.phi + 5 },
                    "+": { zoom: free.zoom * 1.25 }, "-": { zoom: free.zoom / 1.25 } };
    if (moves[e.key]) { e.preventDefault(); moveFree(moves[e.key]); }
  });
}

(async () => {
  let response;
  try { response = await fetch("api/store", { cache: "no-store" }); } catch (e) { return; }
  if (!response.ok) return;
  free.info = await response.json();
  buildFreePanel();
  setupFreeDrag();
  setupFreeKeys();
})();
