// SPDX-License-Identifier: BSD-3-Clause
// viewer/assets/viewer.js -- the image database in the browser: one control per parameter column
// of data.csv, orbit by dragging, keys, play, neighbours preloaded, state in the URL, the rows as a
// filterable table, and (served by penumbra-view) new rows as a running solver writes them and the
// 3D mouse's motion.
"use strict";

const dbBase = document.querySelector('meta[name="pnb-db-base"]').content;
const live = document.querySelector('meta[name="pnb-live"]').content === "true";
const events = document.querySelector('meta[name="pnb-events"]').content === "true";
// free: the free camera (free_view.js) shows views rendered from the store instead of the rows.
const view = { columns: [], rows: [], values: {}, state: {}, csvText: null, playing: null, free: false, zoom: 1 };

// data.csv as rows of fields (RFC 4180: quoted fields, "" inside quotes).
function parseCsv(text) {
  const rows = [];
  let row = [], field = "", quoted = false;
  for (let i = 0; i < text.length; ++i) {
    const c = text[i];
    if (quoted) {
      if (c === '"' && text[i + 1] === '"') { field += '"'; ++i; }
      else if (c === '"') quoted = false;
      else field += c;
    } else if (c === '"' && field === "") quoted = true;
    else if (c === ",") { row.push(field); field = ""; }
    else if (c === "\n" || c === "\r") {
      if (c === "\r" && text[i + 1] === "\n") ++i;
      row.push(field); field = "";
      if (row.length > 1 || row[0] !== "") rows.push(row);
      row = [];
    } else field += c;
  }
  if (quoted) throw new Error("data.csv ends inside a quoted field");
  if (field !== "" || row.length) { row.push(field); rows.push(row); }
  return rows;
}

// The database from data.csv's text; throws an Error that says what is wrong.
function readDatabase(text) {
  const table = parseCsv(text);
  if (table.length === 0) throw new Error("data.csv is empty: the database has no header yet");
  const header = table[0];
  if (header[header.length - 1] !== "FILE") throw new Error("data.csv's last column is '" + header[header.length - 1] + "', not FILE: this is not a Cinema spec D database");
  const rows = [];
  for (let r = 1; r < table.length; ++r) {
    if (table[r].length !== header.length) throw new Error("data.csv line " + (r + 1) + " has " + table[r].length + " fields; the header has " + header.length);
    rows.push(table[r]);
  }
  return { columns: header.slice(0, -1), rows };
}

const isNumber = (s) => s !== "" && !isNaN(Number(s));
// Columns that describe an image without choosing it: a run with a "budget" says in `degraded`
// what a step gave up. They get no control and play no part in choosing a row.
const isAnnotation = (name) => name === "degraded";
function sortedValues(rows, c) {
  const values = [...new Set(rows.map((r) => r[c]))];
  return values.every(isNumber) ? values.sort((a, b) => Number(a) - Number(b)) : values.sort();
}

function showMessage(text) {
  const m = document.getElementById("message");
  m.hidden = !text;
  m.textContent = text || "";
}

// The row that shows the state: every column equal, else the one that keeps `changed` and most
// other columns (a named camera's row has its own phi and theta).
function rowFor(state, changed) {
  let best = null, bestScore = -1;
  for (const row of view.rows) {
    let score = 0;
    view.columns.forEach((name, c) => { if (!isAnnotation(name) && row[c] === state[name]) score += name === changed ? 1000 : 1; });
    if (score > bestScore) { best = row; bestScore = score; }
  }
  return best;
}

function imageUrl(row) { return dbBase + row[row.length - 1].split("/").map(encodeURIComponent).join("/"); }

const preloaded = new Map();
function preload(row) {
  if (!row) return;
  const url = imageUrl(row);
  if (preloaded.has(url)) return;
  const img = new Image();
  img.src = url;
  preloaded.set(url, img);
  if (preloaded.size > 256) preloaded.delete(preloaded.keys().next().value);
}

// Shows the state's image once it has loaded, so the old one stays until then (no flicker).
function show(changed) {
  if (view.free) return;
  const row = rowFor(view.state, changed);
  if (!row) { showMessage("The database lists no images yet."); return; }
  view.columns.forEach((name, c) => { view.state[name] = row[c]; });
  syncControls();
  writeHash();
  const url = imageUrl(row);
  const next = new Image();
  next.onload = () => { document.getElementById("image").src = url; showMessage(""); showAnnotations(row); };
  next.onerror = () => showMessage("Image '" + row[row.length - 1] + "' is listed in data.csv but cannot be loaded.");
  next.src = url;
  highlightRow(row);
  for (const name of view.columns) if (!isAnnotation(name)) for (const d of [-1, 1]) preload(rowFor(stepped(name, d), name));
}

// What the shown image gave up to keep to its step's budget, when it gave up anything.
function showAnnotations(row) {
  const notes = [];
  view.columns.forEach((name, c) => { if (isAnnotation(name) && row[c] !== "none") notes.push(name + ": " + row[c]); });
  const el = document.getElementById("annotation");
  el.hidden = notes.length === 0;
  el.textContent = notes.join("; ");
}

// The state with column `name` moved `delta` values along its sorted values (wrapping for phi).
function stepped(name, delta) {
  const values = view.values[name], s = Object.assign({}, view.state);
  let i = values.indexOf(s[name]) + delta;
  if (name === "phi") i = (i + values.length) % values.length;
  s[name] = values[Math.max(0, Math.min(values.length - 1, i))];
  return s;
}
function step(name, delta) {
  if (!view.values[name]) return;
  view.state = stepped(name, delta);
  show(name);
}

function buildControls() {
  const form = document.getElementById("controls");
  form.replaceChildren();
  for (const name of view.columns) {
    if (isAnnotation(name)) continue;
    const values = view.values[name];
    const label = document.createElement("label");
    label.textContent = name + (values.length > 1 ? " (" + values.length + ")" : "");
    label.htmlFor = "control-" + name;
    form.append(label);
    if (name === "time") form.append(timeControl(values));
    else {
      const select = document.createElement("select");
      select.id = "control-" + name;
      for (const v of values) select.append(new Option(v, v));
      select.onchange = () => { view.state[name] = select.value; show(name); };
      form.append(select);
    }
  }
}

function timeControl(values) {
  const box = document.createElement("div");
  box.className = "row";
  const slider = document.createElement("input");
  Object.assign(slider, { type: "range", id: "control-time", min: 0, max: values.length - 1, step: 1 });
  slider.oninput = () => { view.state.time = view.values.time[Number(slider.value)]; show("time"); };
  const play = document.createElement("button");
  play.type = "button";
  play.id = "play";
  play.textContent = "▶";
  play.onclick = togglePlay;
  const speed = document.createElement("select");
  speed.id = "speed";
  for (const fps of [1, 2, 5, 10, 24]) speed.append(new Option(fps + " fps", fps));
  speed.value = "5";
  speed.onchange = () => { if (view.playing) { togglePlay(); togglePlay(); } };
  box.append(slider, play, speed);
  return box;
}

function togglePlay() {
  if (!view.values.time) return;
  const button = document.getElementById("play");
  if (view.playing) { clearInterval(view.playing); view.playing = null; if (button) button.textContent = "▶"; return; }
  const fps = Number(document.getElementById("speed").value);
  view.playing = setInterval(() => {
    const t = view.values.time, i = t.indexOf(view.state.time);
    view.state.time = t[(i + 1) % t.length];
    show("time");
  }, 1000 / fps);
  if (button) button.textContent = "❚❚";
}

function syncControls() {
  for (const name of view.columns) {
    const el = document.getElementById("control-" + name);
    if (!el) continue;
    if (name === "time") el.value = String(view.values.time.indexOf(view.state.time));
    else el.value = view.state[name];
  }
}

function buildTable() {
  const head = document.querySelector("#rows thead"), body = document.querySelector("#rows tbody");
  head.replaceChildren();
  body.replaceChildren();
  const tr = document.createElement("tr");
  for (const name of view.columns) { const th = document.createElement("th"); th.textContent = name; tr.append(th); }
  head.append(tr);
  for (const row of view.rows) {
    const r = document.createElement("tr");
    for (let c = 0; c < view.columns.length; ++c) { const td = document.createElement("td"); td.textContent = row[c]; r.append(td); }
    r.onclick = () => { view.columns.forEach((name, c) => { view.state[name] = row[c]; }); show(view.columns[0]); };
    r.row = row;
    body.append(r);
  }
  filterTable();
}
function filterTable() {
  const words = document.getElementById("filter").value.toLowerCase().split(/\s+/).filter(Boolean);
  for (const r of document.querySelectorAll("#rows tbody tr"))
    r.hidden = !words.every((w) => r.textContent.toLowerCase().includes(w));
}
function highlightRow(row) {
  for (const r of document.querySelectorAll("#rows tbody tr")) r.classList.toggle("selected", r.row === row);
}

// The state in the URL's fragment (the token stays in the query, never in a shared link's state).
function writeHash() {
  const p = new URLSearchParams();
  for (const name of view.columns) if (!isAnnotation(name)) p.set(name, view.state[name]);
  history.replaceState(null, "", "#" + p.toString());
}
function readHash() {
  const p = new URLSearchParams(location.hash.slice(1));
  for (const name of view.columns) if (p.has(name) && view.values[name].includes(p.get(name))) view.state[name] = p.get(name);
}

// Orbit by dragging: every 24 pixels step phi (horizontal) or theta (vertical) to the next stored value.
function setupDrag() {
  const img = document.getElementById("image");
  let from = null;
  img.addEventListener("pointerdown", (e) => { from = { x: e.clientX, y: e.clientY }; img.setPointerCapture(e.pointerId); });
  img.addEventListener("pointerup", () => { from = null; });
  img.addEventListener("pointermove", (e) => {
    if (!from || view.free) return;
    const dx = e.clientX - from.x, dy = e.clientY - from.y;
    if (Math.abs(dx) >= 24 && view.values.phi) { step("phi", dx > 0 ? -1 : 1); from.x = e.clientX; }
    if (Math.abs(dy) >= 24 && view.values.theta) { step("theta", dy > 0 ? 1 : -1); from.y = e.clientY; }
  });
}

// Keys typed into a text field or the transfer-function editor are the field's, not the view's.
const typingInto = (el) => el.tagName === "TEXTAREA" || (el.tagName === "INPUT" && ["search", "number", "text"].includes(el.type));

function setupKeys() {
  document.addEventListener("keydown", (e) => {
    if (view.free || typingInto(e.target)) return;
    const keys = { ArrowLeft: ["time", -1], ArrowRight: ["time", 1], ArrowUp: ["theta", 1], ArrowDown: ["theta", -1],
                   "[": ["phi", -1], "]": ["phi", 1] };
    if (keys[e.key]) { e.preventDefault(); step(...keys[e.key]); }
    else if (e.key === " ") { e.preventDefault(); togglePlay(); }
  });
}

// The 3D mouse (penumbra-view's /events): its motion comes in small amounts (degrees, time steps),
// which add up until they reach the neighbouring stored value, as a drag steps every 24 pixels; in
// the free camera they turn, zoom and step the rendered view directly.
const motion = { phi: 0, theta: 0, time: 0, last: 0 };
const kMotionPause = 400;   // ms without motion after which what had added up is dropped
const kFallbackGap = 30;    // degrees between values that are not numbers
const kMaxZoom = 8;

// How much motion takes column `name` to its neighbour in direction `d`: the angle between them
// (phi wraps around), or one time step; Infinity at an end.
function gap(name, d) {
  const values = view.values[name], i = values.indexOf(view.state[name]);
  const wraps = name === "phi" && (i + d < 0 || i + d >= values.length);
  const j = wraps ? (i + d + values.length) % values.length : i + d;
  if (d === 0 || i < 0 || j < 0 || j >= values.length || j === i) return Infinity;
  if (name === "time") return 1;
  const angle = Math.abs(Number(values[j]) - Number(values[i]));
  const g = wraps ? 360 - angle : angle;
  return Number.isFinite(g) && g > 0 ? g : kFallbackGap;
}

function moveBy(name, amount) {
  if (!amount || !view.values[name] || view.values[name].length < 2) return;
  motion[name] += amount;
  for (;;) {
    const d = Math.sign(motion[name]), g = gap(name, d);
    if (!Number.isFinite(g)) { motion[name] = 0; return; }
    if (Math.abs(motion[name]) < g) return;
    motion[name] -= d * g;
    step(name, d);
  }
}

// The stored images' zoom scales the image; the free camera zooms its own camera instead.
function setZoom(zoom) {
  view.zoom = Math.min(kMaxZoom, Math.max(1, zoom));
  document.getElementById("image").style.transform = view.zoom === 1 || view.free ? "" : "scale(" + view.zoom + ")";
}

// Button 1: the first row's orbit, unzoomed, the other columns as they are.
function resetView() {
  setZoom(1);
  motion.phi = motion.theta = motion.time = 0;
  for (const name of ["phi", "theta"]) if (view.values[name]) view.state[name] = view.rows[0][view.columns.indexOf(name)];
  show(view.values.phi ? "phi" : view.columns[0]);
}

// Whole steps of the free camera's stored steps, the rest kept for the next motion.
function freeMotion(e) {
  motion.time += e.d_time;
  const steps = Math.trunc(motion.time);
  motion.time -= steps;
  const first = (name, fallback) => (view.values[name] ? Number(view.rows[0][view.columns.indexOf(name)]) : fallback);
  const from = e.reset_view ? { phi: first("phi", free.phi), theta: first("theta", free.theta), zoom: 1 } : free;
  moveFree({ phi: from.phi + e.d_phi, theta: from.theta + e.d_theta, zoom: from.zoom * e.zoom, step: free.step + steps });
}

function applyMotion(e) {
  const now = performance.now();
  if (now - motion.last > kMotionPause) motion.phi = motion.theta = motion.time = 0;
  motion.last = now;
  if (view.free) { freeMotion(e); return; }
  if (view.rows.length === 0) return;
  if (e.reset_view) resetView();
  if (e.toggle_play) togglePlay();
  moveBy("phi", e.d_phi);
  moveBy("theta", e.d_theta);
  moveBy("time", e.d_time);
  if (e.zoom !== 1) setZoom(view.zoom * e.zoom);
}

// A stream that was refused (too many pages listen) is asked for again later; one that drops,
// EventSource opens again by itself.
function listenToDevices() {
  const source = new EventSource("events");
  source.onmessage = (m) => {
    let e;
    try { e = JSON.parse(m.data); } catch { return; }
    if (e.type === "motion") applyMotion(e);
    else if (e.type === "status") document.getElementById("device").textContent = e.message;
  };
  source.onerror = () => { if (source.readyState === EventSource.CLOSED) setTimeout(listenToDevices, 5000); };
}

// Reads data.csv and rebuilds what changed; the state is kept where the new rows still hold it.
async function load() {
  let text;
  try {
    const response = await fetch(dbBase + "data.csv", { cache: "no-store" });
    if (!response.ok) throw new Error("data.csv could not be read (HTTP " + response.status + ")");
    text = await response.text();
  } catch (e) {
    showMessage(e.message.includes("data.csv") ? e.message : "data.csv could not be read: " + e.message);
    return;
  }
  if (text === view.csvText) return;
  view.csvText = text;
  let db;
  try { db = readDatabase(text); } catch (e) { showMessage(e.message); return; }
  const first = view.columns.length === 0;
  view.columns = db.columns;
  view.rows = db.rows;
  for (let c = 0; c < view.columns.length; ++c) view.values[view.columns[c]] = sortedValues(view.rows, c);
  document.getElementById("status").textContent = view.rows.length + " images" + (live ? " · live" : "");
  buildControls();
  buildTable();
  if (view.rows.length === 0) { showMessage("The database lists no images yet" + (live ? "; new ones appear as they are written." : ".")); return; }
  if (first) {
    view.columns.forEach((name, c) => { view.state[name] = view.rows[0][c]; });
    readHash();
  }
  show(view.columns[0]);
}

setupDrag();
setupKeys();
document.getElementById("filter").addEventListener("input", filterTable);
// The page's policy forbids inline handlers: the controls' form never submits.
document.getElementById("controls").addEventListener("submit", (e) => e.preventDefault());
window.addEventListener("hashchange", () => { readHash(); show(view.columns[0]); });
load();
if (live) setInterval(load, 2000);
if (events) listenToDevices();
