// drivebus page: the scope (loaded after app.js, whose $ it uses).
// Samples come from the stream (app.js calls scopeSample); each channel
// keeps a bounded buffer (the page's own drops are counted next to the
// server's). A trigger (level with an edge, or a
// statusword bit) freezes a capture that starts at the triggering sample;
// two cursors read Δt and the values; CSV and PNG export what is shown.
"use strict";
const colours = ["#4fc3f7", "#ffb74d", "#81c784", "#e57373", "#ba68c8", "#fff176", "#90a4ae", "#f06292"];
// Samples kept per channel within two windows (older ones age out): 120 000
// is 1 min at 1 kHz; past that the oldest are dropped and counted.
const MAX_SAMPLES = 120000;
let channels = new Map(); // "node:INDEX:sub" -> [[t, v], ...], oldest first
let pageDropped = 0;
// Trigger: state off | armed | triggered | done; capture holds the samples
// from the triggering one on, for one window.
const trig = { state: "off", t: null, capture: null, last: null };
// Cursors as fractions of the time axis.
const cursors = { a: 0.25, b: 0.75, drag: null };

function windowMs() { return (parseFloat($("scope-window").value) || 10) * 1000; }

function push(map, key, t, v) {
  let s = map.get(key);
  if (!s) {
    map.set(key, (s = []));
    if (map === channels) addSource(key);
  }
  s.push([t, v]);
  // Samples older than two windows age out (checked every 1024 samples,
  // so the trimming copies once per block, not per sample).
  if (map === channels && (s.length & 1023) === 0) {
    let k = 0;
    while (k < s.length && s[k][0] < t - 2 * windowMs()) k++;
    if (k) s.splice(0, k);
  }
  // More within them than the page keeps: dropped and counted.
  if (s.length > MAX_SAMPLES) {
    // Dropped in blocks: one copy per 10 % instead of a shift per sample.
    const n = Math.ceil(MAX_SAMPLES / 10);
    s.splice(0, n);
    if (map === channels) pageDropped += n;
  }
}

// A channel seen for the first time becomes a trigger source (as the
// server names it, whatever name or hex form was subscribed).
function addSource(key) {
  const [node, index, sub] = key.split(":");
  const o = document.createElement("option");
  o.value = key;
  o.textContent = `node ${node} ${index}h:${sub}`;
  $("trig-source").appendChild(o);
}

// Samples of the previous subscription still queued before the server's
// `subscribed` are not this one's.
let awaiting = false;
function scopeSubscribed() { awaiting = false; }

// One sample of the stream.
function scopeSample(msg) {
  if (awaiting) return;
  const key = `${msg.node}:${msg.index}:${msg.sub}`;
  const v = Number(msg.value);
  push(channels, key, msg.t, v);
  if (trig.state === "armed" && key === $("trig-source").value) {
    if (trig.last !== null && fires(trig.last, v)) {
      trig.state = "triggered";
      trig.t = msg.t;
      trig.capture = new Map();
      showTrigger();
    }
    trig.last = v;
  }
  if (trig.state === "triggered") {
    if (msg.t >= trig.t) push(trig.capture, key, msg.t, v);
    if (msg.t - trig.t >= windowMs()) { trig.state = "done"; showTrigger(); }
  }
}

// Whether going from `a` to `b` is the trigger's edge.
function fires(a, b) {
  const kind = $("trig-kind").value;
  const level = parseFloat($("trig-level").value) || 0;
  if (kind === "rising") return a < level && b >= level;
  if (kind === "falling") return a > level && b <= level;
  const bit = (x) => (Math.trunc(x) >> (level & 31)) & 1;
  if (kind === "bit-set") return bit(a) === 0 && bit(b) === 1;
  if (kind === "bit-clear") return bit(a) === 1 && bit(b) === 0;
  return false;
}

function showTrigger() {
  const el = $("trig-state");
  el.dataset.state = trig.state;
  el.textContent = { off: "free running", armed: "armed", triggered: "triggered, capturing", done: "captured" }[trig.state]
    + (trig.t !== null && trig.state !== "armed" ? ` at ${(trig.t / 1000).toFixed(3)} s` : "");
}

function arm() {
  trig.state = "armed"; trig.t = null; trig.capture = null; trig.last = null;
  showTrigger();
}
function release() {
  trig.state = "off"; trig.t = null; trig.capture = null; trig.last = null;
  showTrigger();
}

// What the canvas shows: the capture when there is one, else the newest window.
function shown() {
  const w = windowMs();
  if (trig.capture) return { data: trig.capture, tMin: trig.t, w };
  let tMax = 0;
  for (const s of channels.values()) if (s.length) tMax = Math.max(tMax, s[s.length - 1][0]);
  return { data: channels, tMin: tMax - w, w };
}

function inView(s, tMin, w) {
  return s.filter(([t]) => t >= tMin && t <= tMin + w);
}

// The value of a trace at time t: the last sample at or before it.
function valueAt(s, t) {
  let v = null;
  for (const [ts, x] of s) { if (ts > t) break; v = x; }
  return v;
}

function scopeCsv() {
  const { data, tMin, w } = shown();
  const rows = ["t_ms,node,index,sub,value"];
  const all = [];
  for (const [key, s] of data) {
    const [node, index, sub] = key.split(":");
    for (const [t, v] of inView(s, tMin, w)) all.push([t, node, index, sub, v]);
  }
  all.sort((x, y) => x[0] - y[0]);
  for (const [t, node, index, sub, v] of all) rows.push(`${t.toFixed(3)},${node},${index},${sub},${v}`);
  return rows.join("\n") + "\n";
}

function download(name, href) {
  const a = document.createElement("a");
  a.href = href; a.download = name;
  document.body.appendChild(a); a.click(); a.remove();
}

function drawScope() {
  const c = $("scope");
  const g = c.getContext("2d");
  g.fillStyle = "#101820"; g.fillRect(0, 0, c.width, c.height);
  const { data, tMin, w } = shown();
  const legend = [];
  const readout = [];
  const [ta, tb] = [tMin + cursors.a * w, tMin + cursors.b * w];
  let i = 0;
  for (const [key, all] of data) {
    const col = colours[i++ % colours.length];
    const s = inView(all, tMin, w);
    if (!s.length) continue;
    let lo = Infinity, hi = -Infinity;
    for (const [, v] of s) { lo = Math.min(lo, v); hi = Math.max(hi, v); }
    if (hi === lo) { hi += 1; lo -= 1; }
    g.strokeStyle = col; g.beginPath();
    s.forEach(([t, v], k) => {
      const x = ((t - tMin) / w) * c.width;
      const y = c.height - 10 - ((v - lo) / (hi - lo)) * (c.height - 20);
      k ? g.lineTo(x, y) : g.moveTo(x, y);
    });
    g.stroke();
    const [node, index, sub] = key.split(":");
    legend.push(`<span style="color:${col}">node ${node} ${index}h:${sub} = ${s[s.length - 1][1]} [${lo}..${hi}]</span>`);
    const [va, vb] = [valueAt(s, ta), valueAt(s, tb)];
    const d = va !== null && vb !== null ? vb - va : "–";
    readout.push(`<span style="color:${col}">${index}h: A ${va ?? "–"}, B ${vb ?? "–"}, Δ ${d}</span>`);
  }
  // Trigger instant (left edge of a capture) and the cursors.
  g.setLineDash([4, 4]);
  for (const [f, col] of [[cursors.a, "#ffffff"], [cursors.b, "#ffeb3b"]]) {
    g.strokeStyle = col; g.beginPath(); g.moveTo(f * c.width, 0); g.lineTo(f * c.width, c.height); g.stroke();
  }
  g.setLineDash([]);
  $("legend").innerHTML = legend.join("");
  const cur = $("cursors");
  cur.dataset.dt = (tb - ta).toFixed(3);
  cur.innerHTML = `A ${((ta - tMin) / 1000).toFixed(3)} s, B ${((tb - tMin) / 1000).toFixed(3)} s, Δt ${(tb - ta).toFixed(1)} ms ` + readout.join("");
  $("page-dropped").textContent = pageDropped ? `${pageDropped} samples dropped by the page` : "";
  requestAnimationFrame(drawScope);
}

// The nearer cursor follows a click or a drag on the canvas.
function cursorAt(ev) {
  const r = $("scope").getBoundingClientRect();
  return Math.min(1, Math.max(0, (ev.clientX - r.left) / r.width));
}
$("scope").onmousedown = (ev) => {
  const f = cursorAt(ev);
  cursors.drag = Math.abs(f - cursors.a) <= Math.abs(f - cursors.b) ? "a" : "b";
  cursors[cursors.drag] = f;
};
$("scope").onmousemove = (ev) => { if (cursors.drag) cursors[cursors.drag] = cursorAt(ev); };
window.addEventListener("mouseup", () => { cursors.drag = null; });

// Channels of the scope as the stream wants them, and the trigger's source list.
function scopeChannels() {
  const period = parseInt($("scope-period").value, 10) || 10;
  const list = $("scope-channels").value.split(",").map((s) => s.trim()).filter(Boolean).slice(0, 8).map((s) => {
    const [node, index, sub] = s.split(":");
    return { node: parseInt(node, 10), index, sub: sub ? parseInt(sub, 16) : 0, period_ms: period };
  });
  $("trig-source").innerHTML = "";
  awaiting = true;
  channels = new Map();
  pageDropped = 0;
  release();
  return list;
}

$("trig-arm").onclick = arm;
$("trig-off").onclick = release;
$("export-csv").onclick = () => download("drivebus-scope.csv", URL.createObjectURL(new Blob([scopeCsv()], { type: "text/csv" })));
$("export-png").onclick = () => download("drivebus-scope.png", $("scope").toDataURL("image/png"));

// For tests and the console.
window.drivebus = {
  samples: () => Object.fromEntries([...channels].map(([k, s]) => [k, s.slice()])),
  capture: () => (trig.capture ? Object.fromEntries([...trig.capture].map(([k, s]) => [k, s.slice()])) : null),
  trigger: () => ({ state: trig.state, t: trig.t }),
  csv: scopeCsv,
  png: () => $("scope").toDataURL("image/png"),
};
showTrigger();
requestAnimationFrame(drawScope);
