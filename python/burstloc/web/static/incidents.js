// burstloc control room: the incidents the monitor keeps (burstloc monitor --db), open first,
// and the operators' actions on them (acknowledge, dispatch, close with an outcome, note; shelve
// for a while with a reason, unshelve; a meter's shelving from the Meters table).
// Read from the store through /incidents.json (polled cheaply: ?after=VERSION); written by POST
// with the page's token (its cookie) and the X-Burstloc-Request header. Uses app.js's globals
// ($, S, esc, fmt, map, view, net, sx, sy, dirty, tokenQuery). window.burstloc.incidents holds
// the state shown (read by the tests).
"use strict";

const I = (S.incidents = {
  enabled: null, // the monitor keeps incidents
  writable: false, // the server has a token: operators may act
  why: null, // why not (enabled or writable)
  list: [], // every incident, open first
  version: null,
  selected: null, // the incident shown below the list
  detail: null, // the selected incident with its history
  error: null, // the last refusal
  picking: false, // the next click on the map is where the burst was found
  posts: 0, // actions accepted
  rendered: 0, // rows drawn in the list
});
const SHOWN = 200; // rows drawn at most (the rest: `burstloc incidents list`)
const POLL_MS = 2000;
const OPEN = ["detected", "acknowledged", "dispatched"];
// A link to one incident (a webhook alert's): #incident=ID selects it.
const linked = /^#incident=(\d+)$/.exec(location.hash);
if (linked) I.selected = Number(linked[1]);
let fetchedAt = 0;
let serverNow = 0;
let polling = null;

function ageOf(t) {
  const s = Math.max(0, Math.floor(serverNow + (Date.now() - fetchedAt) / 1000 - t));
  if (s < 60) return s + " s";
  if (s < 3600) return Math.floor(s / 60) + " min";
  if (s < 86400) return Math.floor(s / 3600) + " h " + String(Math.floor((s % 3600) / 60)).padStart(2, "0");
  return Math.floor(s / 86400) + " d " + Math.floor((s % 86400) / 3600) + " h";
}

function withToken(path, query) {
  const q = [query, tokenQuery.slice(1)].filter((x) => x).join("&");
  return path + (q ? "?" + q : "");
}

async function refresh() {
  const after = I.version === null ? "" : "after=" + I.version;
  let doc;
  try {
    const response = await fetch(withToken("incidents.json", after));
    doc = await response.json();
    if (!response.ok) { I.error = doc.error || response.statusText; renderIncidents(); return; }
  } catch (e) {
    return; // the server is restarting: the next poll tries again
  }
  I.enabled = doc.enabled;
  if (!doc.enabled) { I.why = doc.why; renderIncidents(); return; }
  if (doc.unchanged) { renderIncidents(); return; }
  I.version = doc.version;
  I.writable = doc.writable;
  I.why = doc.why;
  I.list = doc.incidents;
  // per meter: false alarms of the incidents its alarms made (app.js's Meters table shows them)
  S.meterOutcomes = Object.fromEntries((doc.meters || []).map((m) => [m.meter, m]));
  S.shelvedMeters = doc.shelved_meters || {}; // app.js's Meters table marks them
  S.shelveMeter = I.writable ? shelveMeter : null;
  if (S.ready) schedulePanels();
  serverNow = doc.now;
  fetchedAt = Date.now();
  if (I.selected === null) {
    const first = I.list.find((r) => OPEN.includes(r.state)) || I.list[0];
    if (first) I.selected = first.id;
  }
  if (I.selected !== null) await loadDetail(I.selected);
  renderIncidents();
}

async function loadDetail(id) {
  const response = await fetch(withToken(`incidents/${id}.json`, ""));
  if (response.ok) I.detail = await response.json();
}

// the operator's name (remembered), or null after saying it is needed
function operator() {
  const by = $("op-name").value.trim();
  if (!by) { I.error = "type your name first: every action is recorded with who did it"; renderIncidents(); return null; }
  localStorage.setItem("burstloc.operator", by);
  return by;
}

async function post(path, body) {
  const response = await fetch(withToken(path, ""), {
    method: "POST",
    headers: { "Content-Type": "application/json", "X-Burstloc-Request": "page" },
    body: JSON.stringify(body),
  });
  let doc = {};
  try { doc = await response.json(); } catch (e) { doc = { error: response.statusText }; }
  return [response.ok, doc];
}

async function act(action, extra) {
  const by = operator();
  if (!by) return;
  const note = $("op-note").value.trim();
  const body = Object.assign({ by, note: note || null }, extra || {});
  const [ok, doc] = await post(`incidents/${I.selected}/${action}`, body);
  if (ok) {
    I.error = null;
    I.detail = doc;
    I.posts++;
    $("op-note").value = "";
  } else {
    I.error = doc.error || "refused";
  }
  if (ok && action === "shelve") $("op-reason").value = "";
  I.picking = false;
  dirty = true;
  renderIncidents(); // the state shown and the buttons it allows, at once
  await refresh();
}

// a meter's shelving from the Meters table (app.js): how long and why asked for
async function shelveMeter(meter, action) {
  const by = operator();
  if (!by) return;
  const body = { by };
  if (action === "shelve") {
    body.for = prompt(`Shelve meter ${meter}'s faults for how long? (e.g. 4h, at most 24h; it still takes part in localization)`, "4h");
    if (body.for === null) return;
    body.reason = prompt(`Why is meter ${meter} shelved? (recorded)`, "");
    if (body.reason === null) return;
  }
  const [ok, doc] = await post(`incidents/meters/${encodeURIComponent(meter)}/${action}`, body);
  I.error = ok ? null : doc.error || "refused";
  I.posts += ok ? 1 : 0;
  I.version = null; // the listing again, with the meters' shelvings
  await refresh();
}

const clockOf = (t) => new Date(t * 1000).toLocaleTimeString();
const isShelved = (r) => r.shelved_until !== null && r.shelved_until !== undefined;

function rowOf(r) {
  const back = isShelved(r) ? ` <span class="shelf">back ${clockOf(r.shelved_until)}</span>` : "";
  return `<tr data-i="${r.id}" class="${r.id === I.selected ? "sel" : ""} ${esc(r.state)}${isShelved(r) ? " shelved" : ""}">` +
    `<td>${r.id}</td><td><span class="st ${esc(r.state)}">${esc(r.state)}</span>${back}</td>` +
    `<td>${esc(r.kind)}</td><td>${ageOf(r.detected_at)}</td><td class="what">${esc(r.summary)}</td></tr>`;
}

function renderIncidents() {
  const box = $("inclist");
  const status = $("incstatus");
  if (I.enabled === false) {
    status.textContent = I.why || "incidents are not kept";
    box.innerHTML = "";
    $("incdetail").innerHTML = "";
    return;
  }
  const open = I.list.filter((r) => OPEN.includes(r.state)).length;
  const shelved = I.list.filter(isShelved);
  status.textContent = `${open} open${shelved.length ? ` (${shelved.length} shelved)` : ""} · ${I.list.length} in all` +
    (I.list.length > SHOWN ? ` (the newest ${SHOWN} shown; burstloc incidents list has every one)` : "");
  // the shelved ones apart, after the open ones (the store lists open first, closed last)
  const rest = I.list.filter((r) => !isShelved(r)).slice(0, SHOWN);
  const opened = rest.filter((r) => OPEN.includes(r.state));
  const group = shelved.length ? `<tr class="group" id="shelvedgroup"><td colspan="5">shelved: they come back by themselves</td></tr>` : "";
  I.rendered = rest.length + shelved.length;
  box.innerHTML = opened.map(rowOf).join("") + group + shelved.map(rowOf).join("") +
    rest.filter((r) => !OPEN.includes(r.state)).map(rowOf).join("");
  renderDetail();
}

function renderDetail() {
  const box = $("incdetail");
  const d = I.detail;
  $("incops").hidden = !(d && d.id === I.selected);
  if (!d || d.id !== I.selected) { box.innerHTML = ""; return; }
  const can = {
    acknowledge: d.state === "detected",
    dispatch: d.state === "acknowledged",
    close: d.state === "acknowledged" || d.state === "dispatched",
    note: true,
    shelve: OPEN.includes(d.state),
    unshelve: isShelved(d),
  };
  const outcome = d.outcome === "found"
    ? `found at ${fmt(d.found_x, 1)}, ${fmt(d.found_y, 1)}`
    : d.outcome === "false-alarm" ? "false alarm" : "";
  const label = (h) => (h.action === "unshelved" && h.via === "expiry" ? "unshelved (expired)" : h.action);
  const until = (h) => (h.action === "shelved" && h.detail && h.detail.until ? ` until ${clockOf(h.detail.until)}` : "");
  const history = d.history
    .map((h) => `<li data-action="${esc(h.action)}"><span class="t">${clockOf(h.at)}</span> ` +
      `<b>${esc(label(h))}</b>${until(h)} by ${esc(h.by)}${h.via !== "monitor" ? ` <span class="via">(${esc(h.via)})</span>` : ""}` +
      `${h.note && h.by !== "monitor" ? ": " + esc(h.note) : ""}</li>`)
    .join("");
  const shelf = isShelved(d)
    ? ` · <b id="shelved">shelved until ${clockOf(d.shelved_until)}</b> <span class="shelf">by ${esc(d.shelved_by)}: ${esc(d.shelved_reason)}</span>`
    : "";
  box.innerHTML =
    `<div class="head">incident <b>${d.id}</b> · <span class="st ${esc(d.state)}">${esc(d.state)}</span> · ${esc(d.kind)}` +
    `${outcome ? ` · <b id="outcome">${esc(outcome)}</b>` : ""}${shelf}</div>` +
    `<div class="sum">${esc(d.summary)}</div><ol id="inchistory">${history}</ol>`;
  for (const [id, action] of [["b-ack", "acknowledge"], ["b-dispatch", "dispatch"], ["b-found", "close"], ["b-false", "close"], ["b-note", "note"], ["b-shelve", "shelve"], ["b-unshelve", "unshelve"]]) {
    $(id).disabled = !(I.writable && can[action]);
  }
  $("b-found").textContent = I.picking ? "Click the map…" : "Close: found at…";
  $("inchint").textContent = I.picking ? "click the map where the burst was found (Esc: cancel)" : "";
  $("incerror").textContent = I.error || "";
  $("incwhy").textContent = I.writable ? "" : I.why || "";
}

$("op-name").value = localStorage.getItem("burstloc.operator") || "";
$("b-ack").onclick = () => act("acknowledge");
$("b-dispatch").onclick = () => act("dispatch");
$("b-found").onclick = () => { I.picking = !I.picking; map.classList.toggle("picking", I.picking); renderDetail(); };
$("b-false").onclick = () => act("close", { outcome: "false-alarm" });
$("b-note").onclick = () => act("note");
$("b-shelve").onclick = () => act("shelve", { for: $("op-shelve-for").value, reason: $("op-reason").value.trim() });
$("b-unshelve").onclick = () => act("unshelve");

// the found point of the selected incident, on the map (called by app.js's draw)
S.drawIncidents = (c) => {
  const d = I.detail;
  if (!net || !d || d.id !== I.selected || d.found_x === null || d.found_x === undefined) return;
  const x = sx(d.found_x), y = sy(d.found_y);
  c.fillStyle = "#3ccf7a";
  c.strokeStyle = "#fff";
  c.lineWidth = 2;
  c.beginPath();
  c.moveTo(x, y - 10); c.lineTo(x + 10, y); c.lineTo(x, y + 10); c.lineTo(x - 10, y); c.closePath();
  c.fill();
  c.stroke();
};
S.incidentsChanged = () => refresh();
// ?snapshot=ID (app.js): this incident alone, its state and history, no actions
S.showIncident = (doc) => {
  Object.assign(I, { enabled: true, writable: false, why: null, list: [doc], selected: doc.id, detail: doc });
  renderIncidents();
  $("incops").hidden = true;
};

let down = null;
map.addEventListener("mousedown", (e) => { down = [e.clientX, e.clientY]; });
map.addEventListener("click", (e) => {
  if (!I.picking || !down || Math.hypot(e.clientX - down[0], e.clientY - down[1]) > 3) return;
  const r = map.getBoundingClientRect();
  const x = (e.clientX - r.left - view.ox) / view.s, y = (view.oy - (e.clientY - r.top)) / view.s;
  map.classList.remove("picking");
  act("close", { outcome: "found", at: [x, y] });
});
window.addEventListener("keydown", (e) => {
  if (e.key === "Escape" && I.picking) { I.picking = false; map.classList.remove("picking"); renderDetail(); }
});
$("inclist").addEventListener("click", async (e) => {
  const tr = e.target.closest("tr[data-i]");
  if (!tr) return;
  I.selected = Number(tr.dataset.i);
  I.error = null;
  I.picking = false;
  await loadDetail(I.selected);
  dirty = true;
  renderIncidents();
});

async function poll() {
  await refresh();
  polling = setTimeout(poll, POLL_MS);
}
if (!SNAPSHOT) poll();
