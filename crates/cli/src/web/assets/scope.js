// drivebus page: the scope (loaded after app.js, whose $ it uses).
// Samples come from the stream (app.js calls scopeSample); each channel
// keeps a bounded buffer (the page's own drops are counted next to the
// server's). A trigger (level with an edge, or a
// statusword bit) freezes a capture that starts at the triggering sample;
// two cursors read Δt and the values; CSV and PNG export what is shown.
// The wheel zooms the time axis around the mouse, a drag pans; the view
// then stays where it is (recording goes on) until "live" or a
// double-click returns to following the newest samples.
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
// The time axis: live follows the newest samples (or the capture) over
// one window; otherwise it stays at [tMin, tMin + w] ms.
const view = { live: true, tMin: 0, w: 0, pan: null };

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
  // A paused view keeps what it shows (bounded by MAX_SAMPLES below).
  if (map === channels && (s.length & 1023) === 0) {
    const keep = view.live ? t - 2 * windowMs() : Math.min(t - 2 * windowMs(), view.tMin);
    let k = 0;
    while (k < s.length && s[k][0] < keep) k++;
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

// What the canvas shows: the view when paused; else the capture when
// there is one, else the newest window.
function shown() {
  const data = trig.capture || channels;
  if (!view.live) return { data, tMin: view.tMin, w: view.w };
  return followed();
}
function followed() {
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
  // The time axis: its ends in s and the span shown.
  g.fillStyle = "#90a4ae"; g.font = "11px monospace";
  g.fillText(`${(tMin / 1000).toFixed(3)} s`, 4, c.height - 2);
  const end = `${((tMin + w) / 1000).toFixed(3)} s`;
  g.fillText(end, c.width - 4 - g.measureText(end).width, c.height - 2);
  const span = `${w >= 1000 ? (w / 1000).toPrecision(3) + " s" : w.toPrecision(3) + " ms"}${view.live ? "" : " (paused)"}`;
  g.fillText(span, (c.width - g.measureText(span).width) / 2, c.height - 2);
  $("legend").innerHTML = legend.join("");
  const cur = $("cursors");
  cur.dataset.dt = (tb - ta).toFixed(3);
  cur.innerHTML = `A ${((ta - tMin) / 1000).toFixed(3)} s, B ${((tb - tMin) / 1000).toFixed(3)} s, Δt ${(tb - ta).toFixed(1)} ms ` + readout.join("");
  $("page-dropped").textContent = pageDropped ? `${pageDropped} samples dropped by the page` : "";
  requestAnimationFrame(drawScope);
}

// A drag on a cursor moves it; a drag elsewhere pans; a click without
// a drag puts the nearer cursor there.
function cursorAt(ev) {
  const r = $("scope").getBoundingClientRect();
  return Math.min(1, Math.max(0, (ev.clientX - r.left) / r.width));
}
// Leaves live follow at what is shown now.
function pause() {
  if (!view.live) return;
  const { tMin, w } = followed();
  Object.assign(view, { live: false, tMin, w });
  showView();
}
function goLive() {
  Object.assign(view, { live: true, pan: null });
  showView();
}
function showView() {
  const el = $("scope-live");
  el.disabled = view.live;
  el.textContent = view.live ? "live" : "back to live";
}
// Zooms by `factor` (< 1: in) keeping the time under fraction `f` in place.
function zoom(f, factor) {
  pause();
  const at = view.tMin + f * view.w;
  view.w = Math.min(Math.max(view.w * factor, 1), 3600e3); // 1 ms .. 1 h
  view.tMin = at - f * view.w;
}
$("scope").onmousedown = (ev) => {
  const f = cursorAt(ev);
  const px = $("scope").getBoundingClientRect().width;
  const near = Math.abs(f - cursors.a) <= Math.abs(f - cursors.b) ? "a" : "b";
  if (Math.abs(f - cursors[near]) * px <= 6) cursors.drag = near;
  else view.pan = { f, moved: false, near };
};
$("scope").onmousemove = (ev) => {
  const f = cursorAt(ev);
  if (cursors.drag) cursors[cursors.drag] = f;
  else if (view.pan && (view.pan.moved || Math.abs(f - view.pan.f) > 0.005)) {
    pause();
    view.tMin -= (f - view.pan.f) * view.w;
    view.pan.f = f;
    view.pan.moved = true;
  }
};
window.addEventListener("mouseup", (ev) => {
  if (view.pan && !view.pan.moved && ev.target === $("scope")) cursors[view.pan.near] = view.pan.f;
  cursors.drag = null;
  view.pan = null;
});
$("scope").addEventListener("wheel", (ev) => {
  ev.preventDefault();
  zoom(cursorAt(ev), ev.deltaY > 0 ? 1.25 : 0.8);
}, { passive: false });
$("scope").ondblclick = goLive;
$("scope-live").onclick = goLive;

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
  goLive();
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
  // The time axis shown: live or not, its start and span in ms.
  view: () => { const { tMin, w } = shown(); return { live: view.live, tMin, w }; },
  zoom,
  csv: scopeCsv,
  png: () => $("scope").toDataURL("image/png"),
};
showTrigger();
showView();
requestAnimationFrame(drawScope);
