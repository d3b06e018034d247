// burstloc control room: the network on the map's canvas (geometry, the drawing, the names on
// zoom). Functions only, on app.js's globals (S, COLORS, net, view, map, ctx, meta, selected, ...);
// loaded before it.
"use strict";

// Names are drawn once a typical link is this long on screen (px): a pipe's at LABEL_PX.pipe,
// a meter's at LABEL_PX.meter. At the full view of a large network neither shows.
const LABEL_PX = { pipe: 70, meter: 35 };

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
  if (S.highlighted) { // above the region: a dark casing, then the named pipe's colour
    const i = net.linkIndex[S.highlighted];
    const p = polyline(i);
    ctx.beginPath();
    ctx.moveTo(p[0], p[1]);
    for (let k = 2; k < p.length; k += 2) ctx.lineTo(p[k], p[k + 1]);
    ctx.strokeStyle = COLORS.casing;
    ctx.lineWidth = 8 / s;
    ctx.stroke();
    ctx.strokeStyle = COLORS.named;
    ctx.lineWidth = 4.5 / s;
    ctx.stroke();
  }
  ctx.restore();
  drawNodes();
  drawPipeLabels();
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
  S.meterLabels = 0;
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
    if (view.s * net.typical >= LABEL_PX.meter) {
      ctx.fillStyle = "#c9d4df";
      ctx.fillText(m, x + 10, y - 7);
      S.meterLabels++;
    }
  });
}

// Each pipe's name at its middle, once zoomed in (LABEL_PX.pipe); only the pipes on screen.
// A snapshot (the crew's picture) names the named pipe and the region's pipes at any zoom.
function drawPipeLabels() {
  S.pipeLabels = 0;
  const all = view.s * net.typical >= LABEL_PX.pipe;
  const crew = new Set(SNAPSHOT && S.region ? S.region.stretches.map((st) => st.pipe) : []);
  if (SNAPSHOT && S.highlighted) crew.add(S.highlighted);
  if (!all && !crew.size) return;
  const L = net.links, w = map.clientWidth, h = map.clientHeight;
  ctx.font = "10px system-ui";
  ctx.textAlign = "center";
  ctx.lineWidth = 3;
  ctx.strokeStyle = COLORS.casing;
  for (let i = 0; i < L.names.length; i++) {
    if (!all && !crew.has(L.names[i])) continue;
    const p = pointAt(L.names[i], null, 0.5);
    const x = sx(p[0]), y = sy(p[1]);
    if (x < 0 || y < 0 || x > w || y > h) continue;
    const named = L.names[i] === S.highlighted;
    ctx.fillStyle = named ? COLORS.named : "#9fb0c1";
    ctx.strokeText(L.names[i], x, y - 4);
    ctx.fillText(L.names[i], x, y - 4);
    S.pipeLabels++;
  }
  ctx.textAlign = "start";
}

// The view around the record's region and named pipe (a third of the network at least).
function fitRecord() {
  const names = S.region ? S.region.stretches.map((s) => s.pipe) : [];
  if (S.highlighted) names.push(S.highlighted);
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  for (const name of names) {
    if (net.linkIndex[name] === undefined) continue;
    const p = polyline(net.linkIndex[name]);
    for (let k = 0; k < p.length; k += 2) {
      x0 = Math.min(x0, p[k]); x1 = Math.max(x1, p[k]); y0 = Math.min(y0, p[k + 1]); y1 = Math.max(y1, p[k + 1]);
    }
  }
  if (!isFinite(x0)) return;
  const w = map.clientWidth, h = map.clientHeight;
  const most = view.s * 3; // at most three times the full view's scale: the streets around stay
  const s = Math.min(most, (w - 160) / Math.max(x1 - x0, 1e-9), (h - 160) / Math.max(y1 - y0, 1e-9));
  view = { s, ox: w / 2 - (s * (x0 + x1)) / 2, oy: h / 2 + (s * (y0 + y1)) / 2 };
}
