// drivebus page: jog and the CSP sine generator of the drive panel
// (loaded after app.js, whose $, api and show it uses).
"use strict";

// Jog: while a button is held the page repeats the request (the server
// stops a jog not repeated within 500 ms); release, leaving the button,
// losing focus or hiding the page stop it.
const JOG_REPEAT_MS = 150;
const jogging = { timer: null, node: null };

function jogSend(node, velocity) {
  return api("POST", `/api/nodes/${node}/drive/jog`, { velocity });
}

function jogStart(sign) {
  jogStop();
  const speed = Math.abs(parseInt($("jog-speed").value, 10) || 0);
  if (!speed) { show($("drive-out"), "jog: set a speed", true); return; }
  const node = $("drive-node").value;
  const v = sign * speed;
  jogging.node = node;
  const send = () => jogSend(node, v).catch((e) => { show($("drive-out"), e.message, true); jogStop(); });
  send();
  jogging.timer = setInterval(send, JOG_REPEAT_MS);
  $("jog-state").textContent = `jogging at ${v}`;
}

function jogStop() {
  if (jogging.timer === null) return;
  clearInterval(jogging.timer);
  jogging.timer = null;
  $("jog-state").textContent = "";
  jogSend(jogging.node, 0).catch((e) => show($("drive-out"), e.message, true));
}

for (const [id, sign] of [["jog-plus", 1], ["jog-minus", -1]]) {
  const b = $(id);
  b.addEventListener("pointerdown", (ev) => { ev.preventDefault(); jogStart(sign); });
  for (const e of ["pointerup", "pointerleave", "pointercancel"]) b.addEventListener(e, jogStop);
}
window.addEventListener("blur", jogStop);
document.addEventListener("visibilitychange", () => { if (document.hidden) jogStop(); });
window.addEventListener("pagehide", jogStop);

// The CSP sine: the server streams it and reports its end as an event.
$("sine").onsubmit = async (ev) => {
  ev.preventDefault();
  const num = (id) => parseInt($(id).value, 10);
  const body = { amplitude: num("sine-amplitude"), period_ms: num("sine-period"), duration_ms: num("sine-duration") };
  try { show($("drive-out"), await api("POST", `/api/nodes/${$("drive-node").value}/drive/sine`, body)); }
  catch (e) { show($("drive-out"), e.message, true); }
};
$("sine-stop").onclick = async () => {
  try { show($("drive-out"), await api("POST", `/api/nodes/${$("drive-node").value}/drive/sine`, { stop: true })); }
  catch (e) { show($("drive-out"), e.message, true); }
};

// A jog's or a sine's end, as the stream reports it.
function motionEvent(msg) {
  const r = msg.result;
  const what = msg.event === "sine" ? `sine ${r.end}${r.cycles === undefined ? "" : " after " + r.cycles + " cycles"}` : `jog ${r.end}`;
  show($("motion-out"), `node ${msg.node}: ${what}${r.position == null ? "" : " at " + r.position}${r.reason ? " (" + r.reason + ")" : ""}`,
    r.end === "error" || r.end === "watchdog");
}
