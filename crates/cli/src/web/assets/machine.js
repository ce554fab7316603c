// The machine panel: inputs and faults of the drive the drive panel shows,
// through POST /api/nodes/N/machine/{input,fault} (docs/http-api.md
// "Machine inputs and faults"). The API has no read-back of the machine,
// so the panel lists what was set from this page (until a duration runs
// out); what the drive makes of it shows where a real drive's would: the
// overview's 402 state, the drive panel's switch lamps, the EMCY log.
// Uses app.js's $, api, show, refreshNodes, refreshDrive.
"use strict";

// Per node: "digital:3" -> {value, until}, and the faults -> {until}.
const machineSet = new Map();
function machineOf(node) {
  if (!machineSet.has(node)) machineSet.set(node, { inputs: new Map(), faults: new Map() });
  return machineSet.get(node);
}

const INPUT_LINES = { digital: [1, 16], analog: [1, 4] };
const INPUT_UNITS = { digital: "0/1", analog: "V", master_velocity: "counts/s", master_position: "counts", motor_temperature: "°C", brake: "0/1" };

function machineNode() { return $("drive-node").value; }

async function machinePost(kind, body, record) {
  const node = machineNode();
  $("machine-node").textContent = node || "–";
  if (!node) return show($("machine-out"), "no drive selected in the drive panel", true);
  const duration = parseFloat($("mi-duration").value);
  if (!Number.isNaN(duration) && body.kind !== "clear") body.duration = duration;
  try {
    const r = await api("POST", `/api/nodes/${node}/machine/${kind}`, body);
    show($("machine-out"), r);
    const until = r.duration ? Date.now() + r.duration * 1000 : null;
    record(machineOf(node), until);
  } catch (e) { show($("machine-out"), e.message, true); }
  machineShow();
  // The drive's reaction: its state and switches.
  refreshDrive();
  refreshNodes();
}

function setInput() {
  const input = $("mi-input").value;
  const body = { input, value: parseFloat($("mi-value").value) };
  if (INPUT_LINES[input]) body.line = parseInt($("mi-line").value, 10);
  const key = body.line === undefined ? input : `${input}:${body.line}`;
  machinePost("input", body, (m, until) => m.inputs.set(key, { value: body.value, until }));
}
$("machine-input").onsubmit = (ev) => { ev.preventDefault(); setInput(); };
$("mi-input").onchange = () => {
  const lines = INPUT_LINES[$("mi-input").value];
  $("mi-line").disabled = !lines;
  if (lines) { $("mi-line").min = lines[0]; $("mi-line").max = lines[1]; }
  $("mi-unit").textContent = INPUT_UNITS[$("mi-input").value] || "";
};
$("mi-input").onchange();

// A fault button: data-fault (the kind) and, for trip/wire_break, data-switch.
for (const b of document.querySelectorAll("#machine-panel button[data-fault]")) {
  b.onclick = () => {
    const body = { kind: b.dataset.fault };
    if (b.dataset.switch) body.switch = b.dataset.switch;
    const key = b.dataset.switch ? `${b.dataset.fault}:${b.dataset.switch}` : b.dataset.fault;
    machinePost("fault", body, (m, until) => m.faults.set(key, { until }));
  };
}
// "clear" ends every machine fault (a latched drive fault stays until a fault reset).
$("machine-clear").onclick = () => machinePost("fault", { kind: "clear" }, (m) => m.faults.clear());

// Lights the fault states and lists the inputs set, for the selected node.
function machineShow() {
  const node = machineNode();
  $("machine-node").textContent = node || "–";
  const m = machineOf(node);
  const now = Date.now();
  for (const map of [m.inputs, m.faults]) {
    for (const [k, v] of map) if (v.until !== null && v.until <= now) map.delete(k);
  }
  for (const s of document.querySelectorAll("#machine-panel [data-fault-state]")) {
    const f = m.faults.get(s.dataset.faultState);
    s.classList.toggle("on", !!f);
    s.dataset.active = f ? "true" : "false";
    s.title = f ? (f.until ? `active for ${Math.ceil((f.until - now) / 1000)} s more` : "active until cleared") : "not set from this page";
  }
  const ul = $("machine-inputs");
  const rows = [...m.inputs].sort(([a], [b]) => a.localeCompare(b, "en", { numeric: true }));
  const want = rows.map(([k, v]) => `${k}=${v.value}`).join(" ");
  if (ul.dataset.shown === want) return;
  ul.dataset.shown = want;
  ul.innerHTML = "";
  for (const [k, v] of rows) {
    const li = document.createElement("li");
    const [input] = k.split(":");
    li.textContent = `${k.replace(":", " line ")} = ${v.value} ${INPUT_UNITS[input] || ""}${v.until ? " (for a while)" : ""}`;
    Object.assign(li.dataset, { input: k, value: v.value });
    ul.appendChild(li);
  }
  if (!rows.length) ul.innerHTML = "<li>none set from this page: the machine's own values</li>";
}
$("drive-node").addEventListener("change", machineShow);
if (document.body.dataset.bus !== "ethercat") setInterval(machineShow, 500);
