// drivebus page: plain JS over the HTTP API (docs/http-api.md).
"use strict";
const token = new URLSearchParams(location.search).get("token");
const headers = token ? { "X-Drivebus-Token": token, "Content-Type": "application/json" } : { "Content-Type": "application/json" };
const $ = (id) => document.getElementById(id);
const ethercat = document.body.dataset.bus === "ethercat";

async function api(method, path, body) {
  const r = await fetch(path, { method, headers, body: body === undefined ? undefined : JSON.stringify(body) });
  const j = await r.json().catch(() => ({ error: "answer is not JSON (HTTP " + r.status + ")" }));
  if (!r.ok) throw new Error(j.error || "HTTP " + r.status);
  return j;
}

function show(el, v, isError) {
  el.textContent = typeof v === "string" ? v : JSON.stringify(v, null, 1);
  el.className = isError ? "error" : "";
}

// Nodes overview.
async function refreshNodes() {
  try {
    const { nodes } = await api("GET", "/api/nodes");
    const body = $("nodes").querySelector("tbody");
    body.innerHTML = "";
    for (const n of nodes) {
      const tr = document.createElement("tr");
      const hex = (v) => (v === undefined ? "–" : v.toString(16).toUpperCase().padStart(8, "0") + "h");
      const cells = [n.node, n.nmt || "–", n.heartbeat_age_ms == null ? "–" : n.heartbeat_age_ms + " ms ago",
        hex(n.identity.vendor_id), hex(n.identity.product_code), n.drive ? n.drive.state : "–"];
      for (const c of cells) { const td = document.createElement("td"); td.textContent = c; tr.appendChild(td); }
      body.appendChild(tr);
    }
    for (const sel of [$("sdo-node"), $("drive-node")]) {
      const keep = sel.value;
      sel.innerHTML = "";
      for (const n of nodes) { const o = document.createElement("option"); o.value = o.textContent = n.node; sel.appendChild(o); }
      if (keep) sel.value = keep;
    }
    $("conn").textContent = nodes.length + " node(s)";
  } catch (e) { $("conn").textContent = e.message; }
  refreshBusLoad();
}

// The bus load of the last full second (the CAN page only).
async function refreshBusLoad() {
  if (document.body.dataset.bus === "ethercat") return;
  try {
    const b = await api("GET", "/api/bus");
    const el = $("bus-load");
    if (b.frames_per_s === null) { el.textContent = "bus: measuring…"; return; }
    const load = b.load === null ? "load unknown (bitrate not given)" : `load ${(b.load * 100).toFixed(1)} % of ${b.bitrate / 1000} kbit/s`;
    el.textContent = `bus: ${Math.round(b.frames_per_s)} frames/s, ${(b.bits_per_s / 1000).toFixed(1)} kbit/s, ${load}`;
    Object.assign(el.dataset, { framesPerS: b.frames_per_s, load: b.load ?? "" });
  } catch (e) { /* shown by the overview */ }
}
setInterval(refreshBusLoad, 1000);

async function refreshEmcy() {
  try {
    const { emcy } = await api("GET", "/api/emcy");
    const ul = $("emcy");
    ul.innerHTML = "";
    for (const e of emcy.slice().reverse()) {
      const li = document.createElement("li");
      const detail = e.detail ? ` (${e.detail})` : "";
      li.textContent = `${(e.t / 1000).toFixed(1)} s  node ${e.node}  ${e.code}h  ${e.text || "manufacturer specific"}${detail}  register ${e.register.toString(16).toUpperCase().padStart(2, "0")}h  [${e.data}]`;
      Object.assign(li.dataset, { node: e.node, code: e.code, text: e.text || "" });
      ul.appendChild(li);
    }
  } catch (e) { /* shown by the overview */ }
}

// Object read/write.
function sdoPath() {
  const q = $("sdo-type").value ? "?type=" + encodeURIComponent($("sdo-type").value) : "";
  return `/api/nodes/${$("sdo-node").value}/sdo/${encodeURIComponent($("sdo-index").value)}/${encodeURIComponent($("sdo-sub").value)}${q}`;
}
$("sdo-read").onclick = async () => {
  try { const r = await api("GET", sdoPath()); show($("sdo-out"), r); $("sdo-value").value = r.value; }
  catch (e) { show($("sdo-out"), e.message, true); }
};
$("sdo-write").onclick = async () => {
  const raw = $("sdo-value").value.trim();
  const value = /^-?\d+(\.\d+)?$/.test(raw) ? Number(raw) : raw;
  const body = { value };
  if ($("sdo-type").value) body.type = $("sdo-type").value;
  try { show($("sdo-out"), await api("PUT", sdoPath().split("?")[0], body)); }
  catch (e) { show($("sdo-out"), e.message, true); }
};

// Object dictionary browser: the node's EDS, searched; a row fills the
// form above and reads the value (edit it there).
$("od-search").onsubmit = async (ev) => {
  ev.preventDefault();
  const body = $("od").querySelector("tbody");
  try {
    const { objects } = await api("GET", `/api/nodes/${$("sdo-node").value}/objects?q=${encodeURIComponent($("od-q").value)}`);
    body.innerHTML = "";
    for (const o of objects) {
      const tr = document.createElement("tr");
      Object.assign(tr.dataset, { index: o.index, sub: o.sub });
      const lim = o.low === null && o.high === null ? "–" : `${o.low ?? ""}..${o.high ?? ""}`;
      const type = o.unit ? `${o.type} [${o.unit}]` : o.type;
      for (const c of [o.index, o.sub, o.name === o.object ? o.name : `${o.object} / ${o.name}`, type, o.access, lim, o.default ?? "–"]) {
        const td = document.createElement("td"); td.textContent = c; tr.appendChild(td);
      }
      tr.onclick = () => {
        for (const r of body.querySelectorAll("tr.selected")) r.classList.remove("selected");
        tr.classList.add("selected");
        $("sdo-index").value = o.index; $("sdo-sub").value = o.sub.toString(16); $("sdo-type").value = "";
        $("sdo-read").onclick();
      };
      body.appendChild(tr);
    }
    $("od-count").textContent = `${objects.length} entries`;
  } catch (e) { body.innerHTML = ""; $("od-count").textContent = e.message; }
};

// Drive panel.
async function driveAction(body) {
  try { show($("drive-out"), await api("POST", `/api/nodes/${$("drive-node").value}/drive`, body)); }
  catch (e) { show($("drive-out"), e.message, true); }
  refreshDrive();
  refreshNodes(); // the overview's 402 state follows the action at once
}
for (const b of document.querySelectorAll("[data-action]")) b.onclick = () => driveAction({ action: b.dataset.action });
$("home").onsubmit = (ev) => {
  ev.preventDefault();
  const body = { action: "home" };
  if ($("home-method").value !== "") body.method = parseInt($("home-method").value, 10);
  driveAction(body);
};
// The homing methods of the selected drive, the one in 6098h selected.
async function refreshHoming() {
  const sel = $("home-method");
  if (!$("drive-node").value) return;
  try {
    const h = await api("GET", `/api/nodes/${$("drive-node").value}/drive/homing`);
    sel.innerHTML = "";
    for (const m of h.methods) { const o = document.createElement("option"); o.value = o.textContent = m; sel.appendChild(o); }
    if (h.current !== null && h.methods.includes(h.current)) sel.value = h.current;
    sel.dataset.node = h.node;
    $("home-source").textContent = `(from ${h.source})`;
  } catch (e) { $("home-source").textContent = e.message; }
}
$("move").onsubmit = (ev) => {
  ev.preventDefault();
  const body = { action: "move", target: parseInt($("move-target").value, 10), relative: $("move-relative").checked };
  // Empty: the drive's own 6081h/6083h.
  for (const [k, id] of [["velocity", "move-velocity"], ["acceleration", "move-acceleration"]]) {
    const v = parseInt($(id).value, 10);
    if (!Number.isNaN(v)) body[k] = v;
  }
  driveAction(body);
};
let driveBusy = false; // one GET at a time: a slow bus must not pile them up
async function refreshDrive() {
  if (!$("drive-node").value || driveBusy) return;
  driveBusy = true;
  try {
    const d = await api("GET", `/api/nodes/${$("drive-node").value}/drive`);
    $("drive-state").textContent = `state: ${d.state} (statusword ${d.statusword.toString(16).toUpperCase().padStart(4, "0")}h), mode ${d.mode_name || "–"}, position ${d.position ?? "–"}, velocity ${d.velocity ?? "–"}`;
    markState(d.state);
    showSwitches(d.switches, d.limits);
  } catch (e) { $("drive-state").textContent = e.message; markState("unknown"); }
  finally { driveBusy = false; }
}
// The switch inputs (60FDh) lit, the limits (607Dh, 607Fh); "–" for an object the drive lacks.
function showSwitches(sw, lim) {
  for (const k of ["negative_limit", "positive_limit", "home_switch", "interlock"]) {
    const lamp = $("sw-" + k);
    lamp.classList.toggle("on", !!(sw && sw[k]));
    lamp.classList.toggle("absent", !sw);
  }
  $("sw-manufacturer").textContent = sw ? `manufacturer bits ${sw.manufacturer.toString(16).toUpperCase().padStart(4, "0")}h` : "60FDh: none";
  const v = (x) => x ?? "–";
  $("drive-limits").textContent = `limits: software position ${v(lim.software_position_min)} .. ${v(lim.software_position_max)} (607Dh), max profile velocity ${v(lim.max_profile_velocity)} (607Fh)`;
}
$("drive-node").onchange = () => { refreshDrive(); refreshHoming(); };

// The CiA 402 state machine (CiA 402-2 figure "state machine"): states as
// the API names them (DriveState::name), transitions with their numbers.
const SVG = "http://www.w3.org/2000/svg";
const states = [
  // name, label, x, y (box 150 × 30)
  ["not ready to switch on", "Not ready to switch on", 80, 24],
  ["switch on disabled", "Switch on disabled", 80, 84],
  ["ready to switch on", "Ready to switch on", 80, 144],
  ["switched on", "Switched on", 80, 204],
  ["operation enabled", "Operation enabled", 80, 264],
  ["fault reaction active", "Fault reaction active", 320, 24],
  ["fault", "Fault", 320, 84],
  ["quick stop active", "Quick stop active", 320, 264],
];
// from, to, number, bend (0 straight; else the control point's x offset)
const transitions = [
  [null, "not ready to switch on", 0], ["not ready to switch on", "switch on disabled", 1],
  ["switch on disabled", "ready to switch on", 2], ["ready to switch on", "switched on", 3],
  ["switched on", "operation enabled", 4], ["operation enabled", "switched on", 5],
  ["switched on", "ready to switch on", 6], ["ready to switch on", "switch on disabled", 7],
  ["operation enabled", "ready to switch on", 8, -38], ["operation enabled", "switch on disabled", 9, -62],
  ["switched on", "switch on disabled", 10, -50], ["operation enabled", "quick stop active", 11],
  ["quick stop active", "switch on disabled", 12], [null, "fault reaction active", 13],
  ["fault reaction active", "fault", 14], ["fault", "switch on disabled", 15],
  ["quick stop active", "operation enabled", 16],
];
function svgEl(tag, attrs, parent) {
  const e = document.createElementNS(SVG, tag);
  for (const [k, v] of Object.entries(attrs)) e.setAttribute(k, v);
  if (parent) parent.appendChild(e);
  return e;
}
function drawStateMachine() {
  const svg = svgEl("svg", { id: "state-diagram", viewBox: "0 0 500 310", width: "500", height: "310",
    role: "img", "aria-label": "CiA 402 state machine", "data-state": "unknown" });
  const defs = svgEl("defs", {}, svg);
  const m = svgEl("marker", { id: "arrow", viewBox: "0 0 8 8", refX: "8", refY: "4", markerWidth: "7", markerHeight: "7", orient: "auto" }, defs);
  svgEl("path", { d: "M0,0 L8,4 L0,8 z", fill: "#667" }, m);
  const at = Object.fromEntries(states.map(([n, , x, y]) => [n, { x, y }]));
  const W = 150, H = 30;
  const links = svgEl("g", { class: "transitions" }, svg);
  for (const [from, to, num, bend] of transitions) {
    const b = at[to];
    let d, lx, ly;
    if (from === null) { // 0: from power on; 13: from any state on a fault
      const [x, y] = num === 0 ? [b.x + W / 2, 4] : [b.x + W + 12, b.y - 10];
      const [ex, ey] = num === 0 ? [b.x + W / 2, b.y] : [b.x + W - 10, b.y];
      d = `M${x},${y} L${ex},${ey}`; [lx, ly] = num === 0 ? [x + 4, y + 12] : [x + 2, y + 4];
    } else {
      const a = at[from];
      if (a.x === b.x && !bend) { // vertical: down on the left third, up on the right third
        const x = a.y < b.y ? a.x + W / 3 : a.x + (2 * W) / 3;
        const [y1, y2] = a.y < b.y ? [a.y + H, b.y] : [a.y, b.y + H];
        d = `M${x},${y1} L${x},${y2}`; [lx, ly] = [x + 4, (y1 + y2) / 2 + 4];
      } else if (bend) { // left of the column, bent outwards
        const [y1, y2] = [a.y + H / 2 + (num === 9 ? 6 : 0), b.y + H / 2 + (num === 9 ? 6 : 0)];
        const cx = a.x + bend;
        d = `M${a.x},${y1} Q${cx},${(y1 + y2) / 2} ${b.x},${y2}`; [lx, ly] = [a.x + bend / 2 - 6, (y1 + y2) / 2 + 4];
      } else if (a.y === b.y) { // horizontal pair (11 and 16)
        const y = num === 11 ? a.y + 9 : a.y + H - 9;
        const [x1, x2] = a.x < b.x ? [a.x + W, b.x] : [a.x, b.x + W];
        d = `M${x1},${y} L${x2},${y}`; [lx, ly] = [(x1 + x2) / 2 - 4, y - 3];
      } else { // diagonal (12, 15)
        const [x1, y1] = [a.x, a.y + (num === 12 ? 0 : H / 2)];
        const [x2, y2] = [b.x + W, b.y + H / 2];
        d = `M${x1},${y1} L${x2},${y2}`; [lx, ly] = [(x1 + x2) / 2, (y1 + y2) / 2 - 4];
      }
    }
    svgEl("path", { d, class: "transition", "data-transition": num, "marker-end": "url(#arrow)" }, links);
    const t = svgEl("text", { x: lx, y: ly, class: "tnum" }, links);
    t.textContent = num;
  }
  for (const [name, label, x, y] of states) {
    const g = svgEl("g", { class: "state", "data-state-name": name }, svg);
    svgEl("rect", { x, y, width: W, height: H, rx: 5 }, g);
    const t = svgEl("text", { x: x + W / 2, y: y + 19, "text-anchor": "middle" }, g);
    t.textContent = label;
  }
  $("state-diagram-box").appendChild(svg);
}
// Highlights `name` (the API's state word); the SVG's data-state says which.
function markState(name) {
  const svg = $("state-diagram");
  if (!svg || svg.dataset.state === name) return;
  svg.dataset.state = name;
  for (const g of svg.querySelectorAll("g.state")) g.classList.toggle("current", g.dataset.stateName === name);
}
drawStateMachine();

// The stream: samples to the scope (scope.js), events to the panels.
let ws;
function connect() {
  const url = (location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/api/stream" + (token ? "?token=" + token : "");
  ws = new WebSocket(url);
  ws.onopen = () => subscribe();
  ws.onclose = () => setTimeout(connect, 1000);
  ws.onmessage = (m) => {
    const msg = JSON.parse(m.data);
    if (msg.type === "sample") {
      scopeSample(msg);
    } else if (msg.type === "subscribed") {
      scopeSubscribed();
    } else if (msg.type === "status") {
      $("dropped").textContent = msg.dropped ? `${msg.dropped} samples dropped` : "";
    } else if (msg.type === "event" && ethercat) {
      // ESM events: the line view has its own stream (line.js).
    } else if (msg.type === "event") {
      if (msg.event === "emcy") refreshEmcy();
      // Its own line: a short motion (homing on the spot) may end before
      // the POST's answer is shown in drive-out.
      if (msg.event === "motion") show($("motion-out"), `node ${msg.node}: ${msg.result.end}${msg.result.position === undefined ? "" : " at " + msg.result.position}${msg.result.reason ? " (" + msg.result.reason + ")" : ""}`, msg.result.end === "error");
      if (msg.event === "jog" || msg.event === "sine") motionEvent(msg); // motion.js
      else if (msg.event !== "motion") refreshNodes();
    } else if (msg.type === "error") {
      show($("drive-out"), msg.error, true);
    }
  };
}
function subscribe() {
  if (!ws || ws.readyState !== 1) return;
  ws.send(JSON.stringify({ subscribe: scopeChannels() }));
}
$("scope-form").onsubmit = (ev) => { ev.preventDefault(); subscribe(); };

$("refresh").onclick = refreshNodes;
// The slaves of an EtherCAT line by position, in the object form: the
// same object URLs with the position as the node.
async function refreshSlaves() {
  try {
    const { slaves } = await api("GET", "/api/ethercat");
    const sel = $("sdo-node");
    const keep = sel.value;
    sel.innerHTML = "";
    for (const s of slaves) {
      const o = document.createElement("option");
      o.value = s.position;
      o.textContent = `${s.position}${s.name ? " " + s.name : ""}`;
      sel.appendChild(o);
    }
    if (keep) sel.value = keep;
  } catch (e) { show($("sdo-out"), e.message, true); }
}
// An EtherCAT line's page: the line view (line.js), the object form, the
// dictionary browser and the scope.
if (ethercat) {
  $("sdo-node").previousSibling.textContent = "slave ";
  refreshSlaves();
  setInterval(refreshSlaves, 3000);
  connect();
} else {
  refreshNodes().then(() => { refreshDrive(); refreshHoming(); });
  refreshEmcy();
  setInterval(refreshNodes, 3000);
  setInterval(refreshDrive, 250);
  connect();
}
