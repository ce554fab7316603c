// The LSS panel (CiA 305): scan, inquire, configure over /api/lss/*
// (docs/http-api.md "LSS (CiA 305)"). Uses app.js's $, headers, refreshNodes.
"use strict";

// Like app.js's api(), but the HTTP status is kept: a refusal (422), a
// conflict (409) and no answer (504) read differently.
async function lssPost(path, body) {
  const r = await fetch(path, { method: "POST", headers, body: JSON.stringify(body) });
  const j = await r.json().catch(() => ({ error: "answer is not JSON (HTTP " + r.status + ")" }));
  if (!r.ok) { const e = new Error(j.error || "HTTP " + r.status); e.status = r.status; throw e; }
  return j;
}

const LSS_FIELDS = ["vendor_id", "product_code", "revision", "serial"];
const lssHex = (v) => "0x" + (v >>> 0).toString(16).toUpperCase();
function lssNum(s) {
  const t = s.trim();
  const v = /^0x[0-9a-f]+$/i.test(t) ? parseInt(t.slice(2), 16) : /^\d+$/.test(t) ? parseInt(t, 10) : NaN;
  return v >= 0 && v <= 0xFFFFFFFF ? v : NaN;
}

// The slave the form names: {} (the only unconfigured one), {node} or {address}.
function lssTarget() {
  const how = $("lss-target").value;
  if (how === "node") {
    const n = parseInt($("lss-node").value, 10);
    if (!(n >= 1 && n <= 127)) throw new Error("give the configured node's ID (1..127)");
    return { node: n };
  }
  if (how === "address") {
    const address = {};
    for (const f of LSS_FIELDS) {
      const v = lssNum($("lss-" + f).value);
      if (Number.isNaN(v)) throw new Error(`${f.replace("_", " ")}: a 32-bit number (decimal or 0x hex)`);
      address[f] = v;
    }
    return { address };
  }
  return {};
}

function lssAddress(a) {
  return `vendor ${lssHex(a.vendor_id)} product ${lssHex(a.product_code)} revision ${lssHex(a.revision)} serial ${lssHex(a.serial)}`;
}

// One line per request in the log (newest first), the result or the refusal.
function lssLog(what, text, ok) {
  const li = document.createElement("li");
  li.textContent = `${what}: ${text}`;
  li.className = ok ? "ok" : "error";
  li.dataset.result = ok ? "ok" : "error";
  $("lss-log").prepend(li);
  show($("lss-out"), `${what}: ${text}`, !ok);
}

async function lssRun(what, path, body, done) {
  for (const b of document.querySelectorAll("#lss-panel button")) b.disabled = true;
  $("lss-out").dataset.state = "busy";
  // A fastscan asks up to 133 questions, each waited for: it takes a while.
  show($("lss-out"), `${what}: waiting for the LSS answers…`);
  try {
    const r = await lssPost(path, body);
    lssLog(what, done(r), true);
  } catch (e) {
    lssLog(what, (e.status ? `HTTP ${e.status}: ` : "") + e.message, false);
  } finally {
    for (const b of document.querySelectorAll("#lss-panel button")) b.disabled = false;
    $("lss-out").dataset.state = "idle";
  }
}

// The address found fills the form: configure then names exactly that slave.
function lssFill(a) {
  for (const f of LSS_FIELDS) $("lss-" + f).value = lssHex(a[f]);
  $("lss-target").value = "address";
  lssTargetShown();
}

$("lss-scan").onclick = () => lssRun("scan", "/api/lss/scan", {}, (r) => {
  if (!r.found) return "no unconfigured slave answered";
  lssFill(r.first);
  return `found ${lssAddress(r.first)}${r.more ? "; more unconfigured slaves answer" : ""}`;
});

$("lss-inquire").onclick = () => {
  let t;
  try { t = lssTarget(); } catch (e) { return lssLog("inquire", e.message, false); }
  lssRun("inquire", "/api/lss/inquire", t, (r) =>
    `${lssAddress(r.address)}, ${r.configured ? "node-ID " + r.node_id : "unconfigured (node-ID FFh)"}`);
};

$("lss-configure").onclick = () => {
  let body;
  try { body = lssTarget(); } catch (e) { return lssLog("configure", e.message, false); }
  const id = parseInt($("lss-node-id").value, 10);
  if (!(id >= 1 && id <= 127)) return lssLog("configure", "the new node-ID: 1..127", false);
  body.node_id = id;
  body.store = $("lss-store").checked;
  if ($("lss-bit-timing").value !== "") body.bit_timing = parseInt($("lss-bit-timing").value, 10);
  lssRun("configure", "/api/lss/configure", body, (r) => {
    // A slave that starts under its new node-ID boots: the overview lists it.
    setTimeout(refreshNodes, 300);
    return `node-ID ${r.node_id} for ${lssAddress(r.address)}${r.stored ? ", stored" : ""}${r.bit_timing == null ? "" : ", bit timing " + r.bit_timing}; active ${r.active}`;
  });
};

// The address fields only matter for "address", the node field for "node".
function lssTargetShown() {
  const how = $("lss-target").value;
  $("lss-address").hidden = how !== "address";
  $("lss-node-label").hidden = how !== "node";
}
$("lss-target").onchange = lssTargetShown;
lssTargetShown();
