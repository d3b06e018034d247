// burstloc control room: the network on a canvas, the monitor's records pushed by Server-Sent
// Events. Plain JavaScript, no build step, no external asset. window.burstloc holds the state the
// page shows (read by the tests and the benchmark).
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
  region: null, // {pipes: [...], length, confidence}
  highlights: [], // {pipe, type, received, drawn} (Date.now() ms)
  frames: 0,
  connected: false,
  snapshots: 0,
  log: [],
});

const query = new URLSearchParams(location.search);
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
  junction: "#6b7e91",
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

// ------------------------------------------------------------------ geometry
function polyline(i) {
  const L = net.links, N = net.nodes;
  const a = L.from[i], b = L.to[i];
  const pts = [N.x[a], N.y[a]].concat(L.vertices[i], [N.x[b], N.y[b]]);
  return pts;
}

function buildPaths() {
  const L = net.links;
  net.paths = { pipe: new Path2D(), pump: new Path2D(), valve: new Path2D() };
  net.linkIndex = {};
  net.nodeIndex = {};
  net.nodes.names.forEach((n, i) => (net.nodeIndex[n] = i));
  let pipes = 0;
  for (let i = 0; i < L.names.length; i++) {
    net.linkIndex[L.names[i]] = i;
    const p = polyline(i);
    const path = net.paths[L.kinds[i]];
    path.moveTo(p[0], p[1]);
    for (let k = 2; k < p.length; k += 2) path.lineTo(p[k], p[k + 1]);
    if (L.kinds[i] === "pipe") pipes++;
  }
  // a typical link's drawn length: junction dots are drawn only when links are long on screen
  const sample = [];
  for (let i = 0; i < L.names.length; i += Math.max(1, Math.floor(L.names.length / 500))) {
    const p = polyline(i);
    sample.push(Math.hypot(p[p.length - 2] - p[0], p[p.length - 1] - p[1]));
  }
  sample.sort((a, b) => a - b);
  net.typical = sample.length ? sample[Math.floor(sample.length / 2)] : 1;
  S.pipes = L.kinds.filter((k) => k === "pipe").length;
  S.drawnPipes = pipes;
  S.links = L.names.length;
}

function fit() {
  const N = net.nodes;
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (let i = 0; i < N.x.length; i++) {
    x0 = Math.min(x0, N.x[i]); x1 = Math.max(x1, N.x[i]);
    y0 = Math.min(y0, N.y[i]); y1 = Math.max(y1, N.y[i]);
  }
  const w = map.clientWidth, h = map.clientHeight, pad = 50;
  const s = Math.min((w - 2 * pad) / Math.max(x1 - x0, 1e-9), (h - 2 * pad - 40) / Math.max(y1 - y0, 1e-9));
  view = { s, ox: (w - s * (x0 + x1)) / 2, oy: (h - 30) / 2 + (s * (y0 + y1)) / 2 };
  dirty = true;
}

const sx = (x) => view.ox + view.s * x;
const sy = (y) => view.oy - view.s * y;

// A point `metres` along pipe `name` from node `from` (fractions of the polyline's length).
function along(name, from, fraction) {
  const i = net.linkIndex[name];
  let p = polyline(i);
  if (from !== undefined && from !== null && net.nodes.names[net.links.to[i]] === from) {
    const r = [];
    for (let k = p.length - 2; k >= 0; k -= 2) r.push(p[k], p[k + 1]);
    p = r;
  }
  const seg = [];
  let total = 0;
  for (let k = 2; k < p.length; k += 2) {
    const d = Math.hypot(p[k] - p[k - 2], p[k + 1] - p[k - 1]);
    seg.push(d);
    total += d;
  }
  return { p, seg, total, fraction };
}

function pointAt(name, from, fraction) {
  const g = along(name, from, fraction);
  let want = Math.min(Math.max(fraction, 0), 1) * g.total;
  for (let k = 0; k < g.seg.length; k++) {
    if (want <= g.seg[k] || k === g.seg.length - 1) {
      const f = g.seg[k] > 0 ? Math.min(want / g.seg[k], 1) : 0;
      const i = 2 * k;
      return [g.p[i] + f * (g.p[i + 2] - g.p[i]), g.p[i + 1] + f * (g.p[i + 3] - g.p[i + 1])];
    }
    want -= g.seg[k];
  }
  return [g.p[0], g.p[1]];
}

function stretchPath(name, from, lo, hi) {
  // the sub-polyline between fractions lo and hi
  const g = along(name, from, 0);
  const path = new Path2D();
  const a = pointAt(name, from, lo);
  path.moveTo(a[0], a[1]);
  let acc = 0;
  for (let k = 0; k < g.seg.length; k++) {
    acc += g.seg[k];
    const f = g.total > 0 ? acc / g.total : 1;
    if (f > lo && f < hi) path.lineTo(g.p[2 * k + 2], g.p[2 * k + 3]);
  }
  const b = pointAt(name, from, hi);
  path.lineTo(b[0], b[1]);
  return path;
}

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
  if (rec.region) {
    const r = rec.region;
    return {
      stretches: (r.stretches || r.pipes || []).map((s) => (typeof s === "string" ? { pipe: s } : s)),
      length: r.length ?? r.length_m ?? null,
      confidence: r.confidence ?? r.probability ?? null,
    };
  }
  const pos = rec.position;
  if (pos && pos.length) {
    return { stretches: [{ pipe: pos.pipe, from: pos.from, low: pos.low, high: pos.high }], length: pos.high - pos.low, confidence: null };
  }
  return null;
}

function applyRecord(rec) {
  const pipe = rec.pipes && rec.pipes.length ? rec.pipes[0].pipe : null;
  S.highlighted = pipe && net.linkIndex[pipe] !== undefined ? pipe : null;
  S.region = regionOf(rec);
  const pos = rec.position;
  S.position = null;
  if (pos && S.highlighted && pos.length > 0) S.position = pointAt(pos.pipe, pos.from, pos.metres / pos.length);
}

// ------------------------------------------------------------------ drawing
function draw() {
  dirty = false;
  const dpr = window.devicePixelRatio || 1;
  const w = map.clientWidth, h = map.clientHeight;
  if (map.width !== Math.round(w * dpr) || map.height !== Math.round(h * dpr)) {
    map.width = Math.round(w * dpr);
    map.height = Math.round(h * dpr);
  }
  ctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  ctx.clearRect(0, 0, w, h);
  if (!net) return;
  const s = view.s;
  ctx.save();
  ctx.setTransform(dpr * s, 0, 0, -dpr * s, dpr * view.ox, dpr * view.oy);
  ctx.strokeStyle = COLORS.pipe;
  ctx.lineWidth = 1.6 / s;
  ctx.stroke(net.paths.pipe); // one path for every pipe (butt caps: the cheapest stroke)
  ctx.lineCap = "round";
  ctx.lineJoin = "round";
  ctx.strokeStyle = COLORS.pump;
  ctx.lineWidth = 3 / s;
  ctx.stroke(net.paths.pump);
  ctx.strokeStyle = COLORS.valve;
  ctx.stroke(net.paths.valve);
  const rec = currentRecord();
  if (rec && rec.pipes) {
    ctx.strokeStyle = COLORS.candidate;
    ctx.globalAlpha = 0.55;
    ctx.lineWidth = 5 / s;
    for (const c of rec.pipes.slice(1)) {
      const i = net.linkIndex[c.pipe];
      if (i === undefined) continue;
      const p = polyline(i);
      ctx.beginPath();
      ctx.moveTo(p[0], p[1]);
      for (let k = 2; k < p.length; k += 2) ctx.lineTo(p[k], p[k + 1]);
      ctx.stroke();
    }
    ctx.globalAlpha = 1;
  }
  if (S.highlighted) {
    const i = net.linkIndex[S.highlighted];
    const p = polyline(i);
    ctx.strokeStyle = COLORS.named;
    ctx.lineWidth = 6 / s;
    ctx.beginPath();
    ctx.moveTo(p[0], p[1]);
    for (let k = 2; k < p.length; k += 2) ctx.lineTo(p[k], p[k + 1]);
    ctx.stroke();
  }
  if (S.region) {
    ctx.strokeStyle = COLORS.region;
    ctx.globalAlpha = 0.9;
    ctx.lineWidth = 11 / s;
    for (const st of S.region.stretches) {
      const i = net.linkIndex[st.pipe];
      if (i === undefined) continue;
      const len = net.links.length[i] || 1;
      const lo = st.low !== undefined ? st.low / len : 0;
      const hi = st.high !== undefined ? st.high / len : 1;
      ctx.stroke(stretchPath(st.pipe, st.from, Math.max(lo, 0), Math.min(hi, 1)));
    }
    ctx.globalAlpha = 1;
  }
  ctx.restore();
  drawNodes();
  drawMeters();
  if (S.position) {
    const x = sx(S.position[0]), y = sy(S.position[1]);
    ctx.strokeStyle = "#fff";
    ctx.fillStyle = COLORS.named;
    ctx.lineWidth = 2;
    ctx.beginPath();
    ctx.arc(x, y, 8, 0, 2 * Math.PI);
    ctx.fill();
    ctx.stroke();
    ctx.beginPath();
    ctx.moveTo(x - 13, y); ctx.lineTo(x + 13, y); ctx.moveTo(x, y - 13); ctx.lineTo(x, y + 13);
    ctx.stroke();
  }
  if (S.drawIncidents) S.drawIncidents(ctx); // incidents.js: the found point
  S.frames++;
  if (pendingRecord) {
    pendingRecord.drawn = Date.now();
    S.highlights.push(pendingRecord);
    if (S.highlights.length > 1000) S.highlights.shift();
    pendingRecord = null;
  }
}

function drawNodes() {
  const N = net.nodes;
  const n = N.names.length;
  if (view.s * net.typical > 12) {
    ctx.fillStyle = COLORS.junction;
    const path = new Path2D();
    const w = map.clientWidth, h = map.clientHeight;
    for (let i = 0; i < n; i++) {
      if (N.kinds[i] !== "junction") continue;
      const x = sx(N.x[i]), y = sy(N.y[i]);
      if (x < -5 || y < -5 || x > w + 5 || y > h + 5) continue;
      path.rect(x - 1.5, y - 1.5, 3, 3);
    }
    ctx.fill(path);
  }
  for (let i = 0; i < n; i++) {
    const k = N.kinds[i];
    if (k === "junction") continue;
    const x = sx(N.x[i]), y = sy(N.y[i]);
    ctx.fillStyle = COLORS[k];
    ctx.strokeStyle = "#0b1015";
    ctx.lineWidth = 1.5;
    ctx.beginPath();
    if (k === "tank") ctx.rect(x - 7, y - 7, 14, 14);
    else { ctx.moveTo(x, y - 9); ctx.lineTo(x + 9, y + 7); ctx.lineTo(x - 9, y + 7); ctx.closePath(); }
    ctx.fill();
    ctx.stroke();
    ctx.fillStyle = COLORS.dim || "#8494a5";
    ctx.font = "11px system-ui";
    ctx.fillText(N.names[i], x + 10, y - 8);
  }
  const L = net.links;
  for (let i = 0; i < L.names.length; i++) {
    if (L.kinds[i] === "pipe") continue;
    const p = pointAt(L.names[i], null, 0.5);
    const x = sx(p[0]), y = sy(p[1]);
    ctx.fillStyle = COLORS[L.kinds[i]];
    ctx.beginPath();
    if (L.kinds[i] === "pump") ctx.arc(x, y, 6, 0, 2 * Math.PI);
    else { ctx.moveTo(x - 6, y - 5); ctx.lineTo(x + 6, y + 5); ctx.lineTo(x + 6, y - 5); ctx.lineTo(x - 6, y + 5); ctx.closePath(); }
    ctx.fill();
  }
}

function drawMeters() {
  const order = {};
  S.alarms.forEach((a, k) => { if (order[a.meter] === undefined) order[a.meter] = k + 1; });
  ctx.font = "bold 11px system-ui";
  meta.meters.forEach((m) => {
    const i = net.nodeIndex[m];
    if (i === undefined) return;
    const x = sx(net.nodes.x[i]), y = sy(net.nodes.y[i]);
    const st = S.meterStatus[m] || "unknown";
    if (order[m] !== undefined) {
      ctx.strokeStyle = COLORS.alarm;
      ctx.lineWidth = 3;
      ctx.beginPath();
      ctx.arc(x, y, 12, 0, 2 * Math.PI);
      ctx.stroke();
      ctx.fillStyle = COLORS.alarm;
      ctx.fillText(String(order[m]), x + 13, y + 14);
    }
    ctx.fillStyle = COLORS[st];
    ctx.strokeStyle = m === selected ? "#fff" : "#0b1015";
    ctx.lineWidth = m === selected ? 3 : 2;
    ctx.beginPath();
    ctx.arc(x, y, 7, 0, 2 * Math.PI);
    ctx.fill();
    ctx.stroke();
    if (meta.meters.length <= 60) {
      ctx.fillStyle = "#c9d4df";
      ctx.fillText(m, x + 10, y - 7);
    }
  });
}

function drawChart() {
  const dpr = window.devicePixelRatio || 1;
  const w = chart.clientWidth, h = chart.clientHeight;
  chart.width = Math.round(w * dpr);
  chart.height = Math.round(h * dpr);
  cctx.setTransform(dpr, 0, 0, dpr, 0, 0);
  cctx.clearRect(0, 0, w, h);
  $("chartmeter").textContent = selected || "–";
  const j = meta.meters.indexOf(selected);
  if (j < 0 || !rows.length) return;
  const t1 = rows[rows.length - 1][0];
  const t0 = Math.max(rows[0][0], t1 - 300); // the last five minutes
  let lo = Infinity, hi = -Infinity;
  for (const r of rows) if (r[0] >= t0 && r[1][j] !== null) { lo = Math.min(lo, r[1][j]); hi = Math.max(hi, r[1][j]); }
  if (!isFinite(lo)) return;
  const padv = Math.max((hi - lo) * 0.1, 0.05);
  lo -= padv; hi += padv;
  const L = 44, R = 8, T = 8, B = 18;
  const X = (t) => L + ((t - t0) / Math.max(t1 - t0, 1e-9)) * (w - L - R);
  const Y = (v) => T + (1 - (v - lo) / (hi - lo)) * (h - T - B);
  cctx.strokeStyle = "#2a3746";
  cctx.fillStyle = "#8494a5";
  cctx.font = "10px system-ui";
  cctx.lineWidth = 1;
  for (let k = 0; k <= 3; k++) {
    const v = lo + ((hi - lo) * k) / 3;
    cctx.beginPath(); cctx.moveTo(L, Y(v)); cctx.lineTo(w - R, Y(v)); cctx.stroke();
    cctx.fillText(v.toFixed(2), 2, Y(v) + 3);
  }
  cctx.fillText("t = " + t0.toFixed(0) + " s", L, h - 4);
  cctx.fillText(t1.toFixed(0) + " s", w - R - 40, h - 4);
  const marks = S.alarms.filter((a) => a.meter === selected);
  const rec = currentRecord();
  for (const a of marks) {
    cctx.strokeStyle = COLORS.alarm;
    cctx.setLineDash([3, 3]);
    cctx.beginPath(); cctx.moveTo(X(a.onset), T); cctx.lineTo(X(a.onset), h - B); cctx.stroke();
    cctx.setLineDash([]);
    cctx.beginPath(); cctx.moveTo(X(a.time), T); cctx.lineTo(X(a.time), h - B); cctx.stroke();
    cctx.fillStyle = COLORS.alarm;
    cctx.fillText("alarm", X(a.time) + 3, T + 9);
  }
  if (rec && rec.time >= t0) {
    cctx.strokeStyle = COLORS.region;
    cctx.beginPath(); cctx.moveTo(X(rec.time), T); cctx.lineTo(X(rec.time), h - B); cctx.stroke();
  }
  cctx.strokeStyle = "#7fd1ff";
  cctx.lineWidth = 1.5;
  cctx.beginPath();
  let started = false;
  for (const r of rows) {
    if (r[0] < t0 || r[1][j] === null) { started = false; continue; }
    if (!started) { cctx.moveTo(X(r[0]), Y(r[1][j])); started = true; } else cctx.lineTo(X(r[0]), Y(r[1][j]));
  }
  cctx.stroke();
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
    box.innerHTML = S.alarms.length ? "Alarms: locating…" : "No alarm.";
  } else {
    box.className = "";
    const pipe = rec.pipes && rec.pipes.length ? rec.pipes[0].pipe : "–";
    const pos = rec.position;
    const kind = rec.type;
    const label = { decision: "burst", transient: rec.classify_at !== undefined ? "located, classifying" : "located, narrowing", event: "not a burst" }[kind] || kind;
    let html = `<span class="kind ${kind}">${esc(label)}</span><span class="big">pipe ${esc(pipe)}</span>`;
    if (pos && pos.metres !== null && pos.metres !== undefined) {
      html += `<div class="row">position <b>${fmt(pos.metres, 0)} m</b> from node <b>${esc(pos.from)}</b> (${fmt(pos.low, 0)}–${fmt(pos.high, 0)} m of ${fmt(pos.length, 0)} m)</div>`;
    }
    if (S.region) {
      if (S.region.confidence !== null && S.region.confidence !== undefined) {
        html += `<div class="row">search region <b>${fmt(S.region.length, 0)} m</b> of main on ${S.region.stretches.length} pipe(s), confidence <b>${fmt(100 * S.region.confidence, 0)} %</b></div>`;
      } else {
        html += `<div class="row">search stretch <b>${fmt(S.region.length, 0)} m</b> (the position's interval)</div>`;
      }
    }
    html += `<div class="row">decided at <b>t = ${fmt(rec.time, 1)} s</b>, first alarm ${fmt(rec.first_alarm, 1)} s (${fmt(rec.decision_delay_s, 1)} s later) by the ${esc(rec.localizer || "")} localizer</div>`;
    if (S.transient && S.answer) html += `<div class="row">early record: pipe <b>${esc(S.transient.pipes[0].pipe)}</b> at t = ${fmt(S.transient.time, 1)} s</div>`;
    if (kind === "transient") html += rec.classify_at !== undefined
      ? `<div class="row">classified at t = ${fmt(rec.classify_at, 1)} s</div>`
      : `<div class="row">answered with the lasting drop at t = ${fmt(rec.answer_at, 1)} s</div>`;
    if (rec.classification) html += `<div class="row">class <b>${esc(rec.classification.class)}</b>: ${esc(rec.classification.reason)}</div>`;
    if (rec.pipes && rec.pipes.length > 1) html += `<div class="row">next: ${rec.pipes.slice(1).map((p) => esc(p.pipe)).join(", ")}</div>`;
    box.innerHTML = html;
  }
  $("alarms").innerHTML = S.alarms
    .map((a) => `<li><b>${esc(a.meter)}</b> at t = ${fmt(a.time, 1)} s <span style="color:#8494a5">(change from ${fmt(a.onset, 1)} s, ${fmt(a.amplitude, 2)} m)</span></li>`)
    .join("");
}

function renderHealth() {
  const tb = $("health").tBodies[0];
  tb.innerHTML = meta.meters
    .map((m, j) => {
      const h = health && health.meters ? health.meters[m] || {} : {};
      const st = S.meterStatus[m] || "unknown";
      const last = lastReading(j);
      return `<tr data-m="${esc(m)}" class="${m === selected ? "sel" : ""}"><td>${esc(m)}</td>` +
        `<td data-status="${st}"><span class="dot" style="background:${COLORS[st]}"></span>${STATE_NAMES[st]}</td>` +
        `<td>${last ? fmt(last[1]) : "–"}</td><td>${last ? fmt(last[0], 1) : "–"}</td>` +
        `<td>${h.clock_offset ? (h.clock_offset > 0 ? "+" : "") + fmt(h.clock_offset, 1) + " s" : ""}</td><td>${h.implausible || ""}</td>` +
        `<td>${h.late || ""}</td><td>${h.filled || ""}</td></tr>`;
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
  if (tr) { selected = tr.dataset.m; chosen = true; dirty = true; schedulePanels(); }
});
window.addEventListener("resize", () => { dirty = true; schedulePanels(); });

function frame() {
  if (dirty) draw();
  requestAnimationFrame(frame);
}

async function start() {
  const response = await fetch("network.json" + tokenQuery);
  net = await response.json();
  buildPaths();
  fit();
  draw();
  requestAnimationFrame(frame);
  connect();
}

start();
