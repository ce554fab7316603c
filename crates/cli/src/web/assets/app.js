// drivebus page: plain JS over the HTTP API (docs/http-api.md).
"use strict";
const token = new URLSearchParams(location.search).get("token");
const headers = token ? { "X-Drivebus-Token": token, "Content-Type": "application/json" } : { "Content-Type": "application/json" };
const $ = (id) => document.getElementById(id);

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
}

async function refreshEmcy() {
  try {
    const { emcy } = await api("GET", "/api/emcy");
    const ul = $("emcy");
    ul.innerHTML = "";
    for (const e of emcy.slice().reverse()) {
      const li = document.createElement("li");
      li.textContent = `${(e.t / 1000).toFixed(1)} s  node ${e.node}  ${e.code}h  ${e.text || "manufacturer specific"}  [${e.data}]`;
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

// Drive panel.
async function driveAction(body) {
  try { show($("drive-out"), await api("POST", `/api/nodes/${$("drive-node").value}/drive`, body)); }
  catch (e) { show($("drive-out"), e.message, true); }
  refreshDrive();
  refreshNodes(); // the overview's 402 state follows the action at once
}
for (const b of document.querySelectorAll("[data-action]")) b.onclick = () => driveAction({ action: b.dataset.action });
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
async function refreshDrive() {
  if (!$("drive-node").value) return;
  try {
    const d = await api("GET", `/api/nodes/${$("drive-node").value}/drive`);
    $("drive-state").textContent = `state: ${d.state} (statusword ${d.statusword.toString(16).toUpperCase().padStart(4, "0")}h), mode ${d.mode_name || "–"}, position ${d.position ?? "–"}, velocity ${d.velocity ?? "–"}`;
  } catch (e) { $("drive-state").textContent = e.message; }
}

// Scope: channels over the WebSocket stream, drawn on a canvas.
const colours = ["#4fc3f7", "#ffb74d", "#81c784", "#e57373", "#ba68c8", "#fff176", "#90a4ae", "#f06292"];
let channels = new Map(); // "node:INDEX:sub" -> [[t, v], ...]
let ws;
function connect() {
  const url = (location.protocol === "https:" ? "wss://" : "ws://") + location.host + "/api/stream" + (token ? "?token=" + token : "");
  ws = new WebSocket(url);
  ws.onopen = () => subscribe();
  ws.onclose = () => setTimeout(connect, 1000);
  ws.onmessage = (m) => {
    const msg = JSON.parse(m.data);
    if (msg.type === "sample") {
      const key = `${msg.node}:${msg.index}:${msg.sub}`;
      if (!channels.has(key)) channels.set(key, []);
      channels.get(key).push([msg.t, Number(msg.value)]);
    } else if (msg.type === "status") {
      $("dropped").textContent = msg.dropped ? `${msg.dropped} samples dropped` : "";
    } else if (msg.type === "event") {
      if (msg.event === "emcy") refreshEmcy();
      if (msg.event === "motion") show($("drive-out"), msg);
      if (msg.event !== "motion") refreshNodes();
    } else if (msg.type === "error") {
      show($("drive-out"), msg.error, true);
    }
  };
}
function subscribe() {
  if (!ws || ws.readyState !== 1) return;
  const period = parseInt($("scope-period").value, 10) || 10;
  const list = $("scope-channels").value.split(",").map((s) => s.trim()).filter(Boolean).slice(0, 8).map((s) => {
    const [node, index, sub] = s.split(":");
    return { node: parseInt(node, 10), index, sub: sub ? parseInt(sub, 16) : 0, period_ms: period };
  });
  channels = new Map();
  ws.send(JSON.stringify({ subscribe: list }));
}
$("scope-form").onsubmit = (ev) => { ev.preventDefault(); subscribe(); };

function draw() {
  const c = $("scope");
  const g = c.getContext("2d");
  g.fillStyle = "#101820"; g.fillRect(0, 0, c.width, c.height);
  const windowMs = (parseFloat($("scope-window").value) || 10) * 1000;
  let tMax = 0;
  for (const s of channels.values()) if (s.length) tMax = Math.max(tMax, s[s.length - 1][0]);
  const tMin = tMax - windowMs;
  const legend = [];
  let i = 0;
  for (const [key, s] of channels) {
    while (s.length && s[0][0] < tMin) s.shift();
    const col = colours[i++ % colours.length];
    if (!s.length) continue;
    let lo = Infinity, hi = -Infinity;
    for (const [, v] of s) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (hi === lo) { hi += 1; lo -= 1; }
    g.strokeStyle = col; g.beginPath();
    s.forEach(([t, v], k) => {
      const x = ((t - tMin) / windowMs) * c.width;
      const y = c.height - 10 - ((v - lo) / (hi - lo)) * (c.height - 20);
      k ? g.lineTo(x, y) : g.moveTo(x, y);
    });
    g.stroke();
    const [node, index, sub] = key.split(":");
    legend.push(`<span style="color:${col}">node ${node} ${index}h:${sub} = ${s[s.length - 1][1]} [${lo}..${hi}]</span>`);
  }
  $("legend").innerHTML = legend.join("");
  requestAnimationFrame(draw);
}

$("refresh").onclick = refreshNodes;
refreshNodes().then(refreshDrive);
refreshEmcy();
setInterval(refreshNodes, 3000);
setInterval(refreshDrive, 500);
connect();
requestAnimationFrame(draw);
