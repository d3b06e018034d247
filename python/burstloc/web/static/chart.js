// burstloc control room: the selected meter's pressure over the last five minutes, with its
// alarms and the answer's time. On app.js's globals (chart, cctx, rows, meta, selected, S);
// loaded before it.
"use strict";

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
