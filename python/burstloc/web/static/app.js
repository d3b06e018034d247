// burstloc control room: the network on a canvas, the monitor's records pushed by Server-Sent
// Events; or, with ?snapshot=ID, one incident drawn once for a picture. Plain JavaScript, no
// build step, no external asset: map.js draws the map, chart.js the chart (both loaded first,
// on the globals below). window.burstloc holds the state the page shows (read by the tests and
// the benchmark).
"use strict";

const S = (window.burstloc = {
  ready: false, // network drawn and the first snapshot applied
  pipes: 0, // pipes in the network file
  drawnPipes: 0, // pipe polylines in the canvas path
  links: 0,
  meterStatus: {}, // meter -> ok | silent | clock | implausible | unknown
  alarms: [], // current incident's alarms, in order
  transient: null,
  answer: null,
  highlighted: null, // pipe drawn as named
  position: null, // [x, y] of the marked position
  region: null, // {stretches: [...], pipes, missing, length, confidence}
  pipeLabels: 0, // pipe names drawn in the last frame (only when zoomed in: LABEL_PX)
  meterLabels: 0, // meter names drawn in the last frame
  snapshot: null, // ?snapshot=ID: the incident shown, without the event stream
  error: null, // why the snapshot cannot be shown
  highlights: [], // {pipe, type, received, drawn} (Date.now() ms)
  frames: 0,
  connected: false,
  snapshots: 0,
  log: [],
});

const query = new URLSearchParams(location.search);
const SNAPSHOT = query.get("snapshot"); // an incident's picture: no event stream, no polling
const tokenQuery = query.get("token") ? "?token=" + encodeURIComponent(query.get("token")) : "";
const $ = (id) => document.getElementById(id);
const map = $("map");
const ctx = map.getContext("2d");
const chart = $("chart");
const cctx = chart.getContext("2d");
const COLORS = {
  ok: "#3ccf7a", silent: "#7c8794", clock: "#4aa3ff", implausible: "#ffb020", unknown: "#55606c",
  alarm: "#ff4d5e", named: "#ff2d55", region: "#ffd23f", candidate: "#c06cff",
  pipe: "#50657a", pump: "#e08cff", valve: "#38d9c8", tank: "#7fb2ff", reservoir: "#4f8cff",
  junction: "#6b7e91", casing: "#0b1015",
};
const STATE_NAMES = {
  ok: "reporting", silent: "silent, excluded", clock: "clock offset corrected",
  implausible: "implausible readings", unknown: "no reading yet",
};

let net = null; // geometry
let view = { s: 1, ox: 0, oy: 0 };
let meta = { meters: [] };
let rows = []; // [t, values]
let health = null;
let implausibleAt = {};
let selected = null;
let chosen = false; // the operator picked a meter (else the first to alarm is shown)
let dirty = true;
let pendingRecord = null;

// ------------------------------------------------------------------ state of the meters
function meterStatus(m, j) {
  const h = health && health.meters ? health.meters[m] : null;
  const now = rows.length ? rows[rows.length - 1][0] : null;
  if (h && (h.silent || (health.excluded || []).includes(m))) return "silent";
  if (implausibleAt[m] !== undefined && now !== null && now - implausibleAt[m] <= 60) return "implausible";
  if (h && h.clock_offset) return "clock";
  if (h && h.readings > 0) return "ok";
  if (rows.length && rows[rows.length - 1][1][j] !== null) return "ok";
  return "unknown";
}

function lastReading(j) {
  for (let k = rows.length - 1; k >= 0; k--) if (rows[k][1][j] !== null) return [rows[k][0], rows[k][1][j]];
  return null;
}

function updateStatus() {
  S.meterStatus = {};
  meta.meters.forEach((m, j) => (S.meterStatus[m] = meterStatus(m, j)));
}

// ------------------------------------------------------------------ the answer on the map
function currentRecord() {
  return S.answer || S.transient;
}

function regionOf(rec) {
  // the record's search region when it gives one, else the position's stretch on the pipe
  // pipes: the record's count of distinct pipes (a pipe may hold two stretches, one each side
  // of a gap: counting stretches counted it twice); missing: the listed pipes the map lacks
  let region = null;
  if (rec.region) {
    const r = rec.region;
    const stretches = (r.stretches || r.pipes || []).map((s) => (typeof s === "string" ? { pipe: s } : s));
    region = {
      stretches,
      pipes: r.pipe_count ?? new Set(stretches.map((s) => s.pipe)).size,
      length: r.length ?? r.length_m ?? null,
      confidence: r.confidence ?? r.probability ?? null,
    };
  } else if (rec.position && rec.position.length) {
    const pos = rec.position;
    region = { stretches: [{ pipe: pos.pipe, from: pos.from, low: pos.low, high: pos.high }], pipes: 1, length: pos.high - pos.low, confidence: null };
  }
  if (region) region.missing = [...new Set(region.stretches.map((s) => s.pipe))].filter((p) => net.linkIndex[p] === undefined);
  return region;
}

function applyRecord(rec) {
  const pipe = rec.pipes && rec.pipes.length ? rec.pipes[0].pipe : null;
  S.highlighted = pipe && net.linkIndex[pipe] !== undefined ? pipe : null;
  S.region = regionOf(rec);
  const pos = rec.position;
  S.position = null;
  if (pos && S.highlighted && pos.length > 0) S.position = pointAt(pos.pipe, pos.from, pos.metres / pos.length);
}

// ------------------------------------------------------------------ panels
const fmt = (v, d = 2) => (v === null || v === undefined ? "–" : Number(v).toFixed(d));
const esc = (s) => String(s).replace(/[&<>"]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;", '"': "&quot;" })[c]);

function renderIncident() {
  const rec = currentRecord();
  const box = $("answer");
  $("geojson").hidden = !(rec && (rec.region || rec.position)); // /region.geojson: this record
  if (!rec) {
    box.className = "quiet";
    box.innerHTML = S.alarms.length ? `${S.alarms.length} alarm(s), not located yet…` : "No alarm.";
  } else {
    box.className = "";
    const pipe = rec.pipes && rec.pipes.length ? rec.pipes[0].pipe : "–";
    const pos = rec.position;
    const kind = rec.type;
    const label = { decision: "burst", transient: rec.classify_at !== undefined ? "located, classifying" : "located, waiting for the answer", event: "not a burst" }[kind] || kind;
    let html = `<span class="kind ${kind}">${esc(label)}</span><span class="big">pipe ${esc(pipe)}</span>`;
    if (pos && pos.metres !== null && pos.metres !== undefined) {
      html += `<div class="row">position <b>${fmt(pos.metres, 0)} m</b> from node <b>${esc(pos.from)}</b> (${fmt(pos.low, 0)}–${fmt(pos.high, 0)} m of ${fmt(pos.length, 0)} m)</div>`;
    }
    if (S.region) {
      const r = S.region;
      if (r.confidence !== null && r.confidence !== undefined) {
        html += `<div class="row" id="regionrow">search region <b>${fmt(r.length, 0)} m</b> of main on <b>${r.pipes}</b> pipe(s), confidence <b>${fmt(100 * r.confidence, 0)} %</b></div>`;
      } else {
        html += `<div class="row" id="regionrow">search stretch <b>${fmt(r.length, 0)} m</b> (the position's interval)</div>`;
      }
      if (r.missing.length) html += `<div class="row err">not on the map (the network drawn lacks them): ${r.missing.map(esc).join(", ")}</div>`;
    }
    if (kind === "transient") html += waitRows(rec);
    else html += `<div class="row">decided at <b>t = ${fmt(rec.time, 1)} s</b>, first alarm ${fmt(rec.first_alarm, 1)} s (${fmt(rec.decision_delay_s, 1)} s later) by the ${esc(rec.localizer || "")} localizer</div>`;
    if (S.transient && S.answer) html += `<div class="row">early record: pipe <b>${esc(S.transient.pipes[0].pipe)}</b> at t = ${fmt(S.transient.time, 1)} s</div>`;
    if (rec.classification) html += `<div class="row">class <b>${esc(rec.classification.class)}</b>: ${esc(rec.classification.reason)}</div>`;
    if (rec.pipes && rec.pipes.length > 1) html += `<div class="row">next: ${rec.pipes.slice(1).map((p) => esc(p.pipe)).join(", ")}</div>`;
    box.innerHTML = html;
  }
  $("alarms").innerHTML = S.alarms
    .map((a) => a.time === null // a snapshot: the record names the meters, not their alarms
      ? `<li><b>${esc(a.meter)}</b> alarmed</li>`
      : `<li><b>${esc(a.meter)}</b> at t = ${fmt(a.time, 1)} s <span style="color:#8494a5">(change from ${fmt(a.onset, 1)} s, ${fmt(a.amplitude, 2)} m)</span></li>`)
    .join("");
}

// The early record's wait: located from the arrivals, the answer due at answer_at (the burst's
// onset + the wait the record carries), counted down in reading time.
function waitRows(rec) {
  const what = rec.classify_at !== undefined ? "classification" : "answer with the lasting drop";
  let html = `<div class="row">located from the arrivals at t = ${fmt(rec.time, 1)} s (first alarm ${fmt(rec.first_alarm, 1)} s) by the ${esc(rec.localizer || "")} localizer</div>`;
  html += `<div class="row" id="due">${what} due at <b>t = ${fmt(rec.answer_at, 1)} s</b>`;
  if (rec.wait_s !== undefined && rec.wait_s !== null) html += `: the burst's onset t = ${fmt(rec.answer_at - rec.wait_s, 1)} s + the ${fmt(rec.wait_s, 0)} s wait`;
  const now = rows.length ? rows[rows.length - 1][0] : null;
  if (now !== null && !SNAPSHOT) html += now < rec.answer_at ? `, in <b>${fmt(rec.answer_at - now, 0)} s</b>` : " (overdue: waiting for readings)";
  return html + "</div>";
}

// a meter's false alarms of the incidents its alarms made (incidents.js: S.meterOutcomes)
function falseAlarmsCell(m) {
  const o = S.meterOutcomes ? S.meterOutcomes[m] : null;
  if (!o) return `<td class="fa"></td>`;
  const title = `alarmed in incident${o.alarmed === 1 ? "" : "s"} ${o.incidents.map((i) => "#" + i).join(", ")}` +
    (o.false_alarms ? `; false alarms: ${o.false_alarm_incidents.map((i) => "#" + i).join(", ")}` : "");
  return `<td class="fa" title="${esc(title)}">${o.false_alarms}/${o.alarmed}</td>`;
}

// a meter's shelving (incidents.js: S.shelvedMeters, S.shelveMeter): when it returns, a button
function shelfCell(m) {
  const sh = S.shelvedMeters ? S.shelvedMeters[m] : null;
  const label = sh ? `<span class="shelf" title="${esc(`by ${sh.by}: ${sh.reason}`)}">until ${new Date(sh.until * 1000).toLocaleTimeString()}</span> ` : "";
  const button = S.shelveMeter ? `<button data-shelve="${sh ? "unshelve" : "shelve"}">${sh ? "Unshelve" : "Shelve"}</button>` : "";
  return `<td class="shelfcell">${label}${button}</td>`;
}

function renderHealth() {
  const tb = $("health").tBodies[0];
  tb.innerHTML = meta.meters
    .map((m, j) => {
      const h = health && health.meters ? health.meters[m] || {} : {};
      const st = S.meterStatus[m] || "unknown";
      const last = lastReading(j);
      const shelved = S.shelvedMeters && S.shelvedMeters[m] ? " shelved" : "";
      return `<tr data-m="${esc(m)}" class="${m === selected ? "sel" : ""}${shelved}"><td>${esc(m)}</td>` +
        `<td data-status="${st}"><span class="dot" style="background:${COLORS[st]}"></span>${STATE_NAMES[st]}</td>` +
        `<td>${last ? fmt(last[1]) : "–"}</td><td>${last ? fmt(last[0], 1) : "–"}</td>` +
        `<td>${h.clock_offset ? (h.clock_offset > 0 ? "+" : "") + fmt(h.clock_offset, 1) + " s" : ""}</td><td>${h.implausible || ""}</td>` +
        `<td>${h.late || ""}</td><td>${h.filled || ""}</td>${falseAlarmsCell(m)}${shelfCell(m)}</tr>`;
    })
    .join("");
}

function addLog(entry) {
  S.log.push(entry);
  if (S.log.length > 400) S.log.shift();
}

function renderLog() {
  $("log").innerHTML = S.log
    .slice()
    .reverse()
    .map((e) => `<li class="${esc(e.kind)}"><span class="t">${e.time === null || e.time === undefined ? "" : fmt(e.time, 1) + " s"}</span> ${esc(e.text)}</li>`)
    .join("");
}

let panelsDue = false;
function schedulePanels() {
  if (panelsDue) return;
  panelsDue = true;
  setTimeout(() => {
    panelsDue = false;
    renderIncident();
    renderHealth();
    renderLog();
    drawChart();
    if (rows.length) $("clock").textContent = "t = " + rows[rows.length - 1][0].toFixed(1) + " s";
  }, 100);
}

// ------------------------------------------------------------------ news
function apply(n) {
  if (n.kind === "rows") {
    for (const r of n.rows) rows.push(r);
    const keep = Math.max(Math.ceil(600 / (meta.capture_interval || 0.2)), 10);
    if (rows.length > keep * 1.2) rows = rows.slice(rows.length - keep);
  } else if (n.kind === "incident") {
    S.alarms = []; S.transient = null; S.answer = null; S.highlighted = null; S.region = null; S.position = null;
  } else if (n.kind === "alarm") {
    S.alarms.push(n.alarm);
    if (!chosen && S.alarms.length === 1) selected = n.alarm.meter;
    addLog(n.log);
  } else if (n.kind === "record") {
    const rec = n.record;
    if (rec.type === "transient") S.transient = rec;
    else S.answer = rec;
    applyRecord(rec);
    pendingRecord = { pipe: S.highlighted, type: rec.type, received: Date.now(), time: rec.time };
    addLog(n.log);
    if (S.incidentsChanged) S.incidentsChanged(); // incidents.js: the list, from the store
  } else if (n.kind === "message") {
    addLog(n.log);
  } else if (n.kind === "health") {
    health = n.health;
    implausibleAt = n.implausible_at;
  }
}

function snapshot(doc) {
  meta = doc.meta;
  rows = doc.rows;
  health = doc.health;
  implausibleAt = doc.implausible_at;
  S.alarms = doc.alarms;
  S.transient = doc.transient;
  S.answer = doc.answer;
  S.log = doc.log.slice();
  S.highlighted = null; S.region = null; S.position = null;
  const rec = currentRecord();
  if (rec) {
    applyRecord(rec);
    pendingRecord = { pipe: S.highlighted, type: rec.type, received: Date.now(), time: rec.time };
  }
  if (!chosen) selected = S.alarms.length ? S.alarms[0].meter : meta.meters[0] || null;
  $("meta").textContent = `${meta.network || ""} · ${meta.meters.length} meters · ${meta.detector || ""} / ${meta.localizer || ""} · capture ${meta.capture_interval} s`;
  S.snapshots++;
}

function connect() {
  const es = new EventSource("events" + tokenQuery);
  es.addEventListener("open", () => { S.connected = true; $("link").className = "up"; $("link").textContent = "live"; });
  es.addEventListener("error", () => { S.connected = false; $("link").className = "down"; $("link").textContent = "reconnecting"; });
  es.addEventListener("snapshot", (e) => {
    snapshot(JSON.parse(e.data));
    updateStatus();
    dirty = true;
    S.ready = true;
    S.readyAt = performance.now();
    schedulePanels();
  });
  es.addEventListener("update", (e) => {
    for (const n of JSON.parse(e.data)) apply(n);
    updateStatus();
    dirty = true;
    schedulePanels();
  });
}

// ------------------------------------------------------------------ interaction
function nearestMeter(mx, my) {
  let best = null, bestD = 14;
  for (const m of meta.meters) {
    const i = net.nodeIndex[m];
    if (i === undefined) continue;
    const d = Math.hypot(sx(net.nodes.x[i]) - mx, sy(net.nodes.y[i]) - my);
    if (d < bestD) { best = m; bestD = d; }
  }
  return best;
}

let drag = null;
map.addEventListener("mousedown", (e) => { drag = { x: e.clientX, y: e.clientY, moved: false }; map.classList.add("dragging"); });
window.addEventListener("mouseup", (e) => {
  map.classList.remove("dragging");
  if (drag && !drag.moved && net) {
    const r = map.getBoundingClientRect();
    const m = nearestMeter(e.clientX - r.left, e.clientY - r.top);
    if (m) { selected = m; chosen = true; dirty = true; schedulePanels(); }
  }
  drag = null;
});
window.addEventListener("mousemove", (e) => {
  if (drag) {
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    if (Math.abs(dx) + Math.abs(dy) > 2) drag.moved = true;
    view.ox += dx; view.oy += dy;
    drag.x = e.clientX; drag.y = e.clientY;
    dirty = true;
    return;
  }
  if (!net || e.target !== map) { $("tip").hidden = true; return; }
  const r = map.getBoundingClientRect();
  const mx = e.clientX - r.left, my = e.clientY - r.top;
  const m = nearestMeter(mx, my);
  const tip = $("tip");
  if (!m) { tip.hidden = true; return; }
  const j = meta.meters.indexOf(m);
  const last = lastReading(j);
  const a = S.alarms.find((x) => x.meter === m);
  tip.textContent = `meter ${m}\n${STATE_NAMES[S.meterStatus[m] || "unknown"]}\n` +
    (last ? `last reading ${fmt(last[1])} m at t = ${fmt(last[0], 1)} s` : "no reading yet") +
    (a ? `\nalarmed at t = ${fmt(a.time, 1)} s` : "");
  tip.style.left = mx + 14 + "px";
  tip.style.top = my + 10 + "px";
  tip.hidden = false;
});
map.addEventListener("wheel", (e) => {
  e.preventDefault();
  const r = map.getBoundingClientRect();
  const mx = e.clientX - r.left, my = e.clientY - r.top;
  const k = Math.exp(-e.deltaY * 0.0015);
  view.ox = mx - (mx - view.ox) * k;
  view.oy = my - (my - view.oy) * k;
  view.s *= k;
  dirty = true;
}, { passive: false });
map.addEventListener("dblclick", () => fit());
$("health").addEventListener("click", (e) => {
  const tr = e.target.closest("tr[data-m]");
  const button = e.target.closest("button[data-shelve]");
  if (tr && button && S.shelveMeter) { S.shelveMeter(tr.dataset.m, button.dataset.shelve); return; }
  if (tr) { selected = tr.dataset.m; chosen = true; dirty = true; schedulePanels(); }
});
window.addEventListener("resize", () => { dirty = true; schedulePanels(); });

function frame() {
  if (dirty) draw();
  requestAnimationFrame(frame);
}

// ?snapshot=ID: one incident's record from the store, drawn once, for a picture (burstloc
// incidents png): no event stream and no polling, so that the page finishes loading;
// window.burstloc.ready (and <body data-ready>) once drawn.
async function showSnapshot(id) {
  document.body.classList.add("snapshot");
  S.snapshot = id;
  $("link").className = "up";
  $("link").textContent = "incident " + id;
  const response = await fetch(`incidents/${encodeURIComponent(id)}.json` + tokenQuery);
  const doc = await response.json();
  const rec = response.ok ? doc.record : null;
  if (!response.ok || !rec) {
    S.error = response.ok ? `incident ${id} has no located record to draw` : doc.error || response.statusText;
    $("answer").textContent = S.error;
  } else {
    const state = await (await fetch("state.json" + tokenQuery)).json(); // the network's name
    meta = Object.assign({}, state.meta, { meters: rec.meters || [] });
    $("meta").textContent = `${meta.network || ""} · ${meta.meters.length} meters · the ${rec.localizer || ""} localizer's ${rec.type} record`;
    S.alarms = (rec.alarmed || []).map((m) => ({ meter: m, time: null, onset: null, amplitude: null }));
    if (rec.type === "transient") S.transient = rec;
    else S.answer = rec;
    applyRecord(rec);
    fitRecord();
    updateStatus();
    renderIncident();
    $("clock").textContent = `t = ${fmt(rec.time, 1)} s`;
  }
  if (S.showIncident && response.ok) S.showIncident(doc); // incidents.js: its state and history
  draw();
  S.ready = true;
  document.body.dataset.ready = "1";
}

async function start() {
  const response = await fetch("network.json" + tokenQuery);
  net = await response.json();
  buildPaths();
  fit();
  if (SNAPSHOT) {
    await showSnapshot(SNAPSHOT);
  } else {
    draw();
    connect();
  }
  requestAnimationFrame(frame);
}

start();
