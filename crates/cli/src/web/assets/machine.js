// The machine panel: inputs and faults of the drive the drive panel shows,
// through POST /api/nodes/N/machine/{input,fault}, and what is in force on
// its machine (the machine file's and those set at run time, from this
// page or elsewhere) from GET /api/nodes/N/machine (docs/http-api.md
// "Machine inputs and faults"). What the drive makes of it shows where a
// real drive's would: the overview's 402 state, the drive panel's switch
// lamps, the EMCY log.
// Uses app.js's $, api, show, refreshNodes, refreshDrive.
"use strict";

const INPUT_LINES = { digital: [1, 16], analog: [1, 4] };
const INPUT_UNITS = { digital: "0/1", analog: "V", master_velocity: "counts/s", master_position: "counts", motor_temperature: "°C", brake: "0/1" };

function machineNode() { return $("drive-node").value; }

async function machinePost(kind, body) {
  const node = machineNode();
  $("machine-node").textContent = node || "–";
  if (!node) return show($("machine-out"), "no drive selected in the drive panel", true);
  const duration = parseFloat($("mi-duration").value);
  if (!Number.isNaN(duration) && body.kind !== "clear") body.duration = duration;
  try {
    const r = await api("POST", `/api/nodes/${node}/machine/${kind}`, body);
    show($("machine-out"), r);
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
  machinePost("input", body);
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
    machinePost("fault", body);
  };
}
// "clear" ends every machine fault (a latched drive fault stays until a fault reset).
$("machine-clear").onclick = () => machinePost("fault", { kind: "clear" });

// Lights the faults in force and lists the inputs held, for the selected node.
async function machineShow() {
  const node = machineNode();
  $("machine-node").textContent = node || "–";
  if (!node) return;
  let m;
  try { m = await api("GET", `/api/nodes/${node}/machine`); } catch (e) { return; }
  if (machineNode() !== node) return;
  const left = (x) => x.remaining_s === null ? "until changed or cleared" : `for ${Math.ceil(x.remaining_s)} s more`;
  const faults = new Map(m.faults.map((f) => [f.switch ? `${f.kind}:${f.switch}` : f.kind, f]));
  for (const s of document.querySelectorAll("#machine-panel [data-fault-state]")) {
    const f = faults.get(s.dataset.faultState);
    s.classList.toggle("on", !!f);
    s.dataset.active = f ? "true" : "false";
    s.title = f ? `in force ${left(f)}` : "not in force";
  }
  // The last change of an input wins (the list is in the order they began).
  const inputs = new Map();
  for (const i of m.inputs) inputs.set(i.line === null ? i.input : `${i.input}:${i.line}`, i);
  const rows = [...inputs].sort(([a], [b]) => a.localeCompare(b, "en", { numeric: true }));
  const ul = $("machine-inputs");
  const want = rows.map(([k, v]) => `${k}=${v.value}`).join(" ");
  if (ul.dataset.shown === want) return;
  ul.dataset.shown = want;
  ul.innerHTML = "";
  for (const [k, v] of rows) {
    const li = document.createElement("li");
    li.textContent = `${k.replace(":", " line ")} = ${v.value} ${INPUT_UNITS[v.input] || ""} (${left(v)})`;
    Object.assign(li.dataset, { input: k, value: v.value });
    ul.appendChild(li);
  }
  if (!rows.length) ul.innerHTML = "<li>none: the machine's own values</li>";
}
$("drive-node").addEventListener("change", machineShow);
if (document.body.dataset.bus !== "ethercat") setInterval(machineShow, 500);
