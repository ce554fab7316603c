// EtherCAT line view (docs/http-api.md, "EtherCAT line state"): on a page
// served by `ethercat serve --http` (<body data-bus="ethercat">) the
// slaves in line order with their ESM state, AL status and counters,
// refreshed twice a second. The CAN panels are hidden (style.css).
"use strict";
(() => {
  if (document.body.dataset.bus !== "ethercat") return;
  const el = (id) => document.getElementById(id);
  let busy = false;
  async function refresh() {
    if (busy) return;
    busy = true;
    try {
      const r = await fetch("/api/ethercat");
      if (!r.ok) throw new Error("GET /api/ethercat: HTTP " + r.status);
      const { slaves, line } = await r.json();
      const body = el("line").querySelector("tbody");
      body.innerHTML = "";
      for (const s of slaves) {
        const tr = document.createElement("tr");
        Object.assign(tr.dataset, { position: s.position, state: s.state, alStatusCode: s.al_status_code });
        tr.classList.toggle("error", s.error || !s.powered);
        const hex = (v, n) => v.toString(16).toUpperCase().padStart(n, "0") + "h";
        const al = `${hex(s.al_status_code, 4)} ${s.al_status_text}`;
        const cells = [s.position, s.name || "–", hex(s.identity.vendor_id, 8), hex(s.identity.product_code, 8),
          s.state + (s.error ? " (error)" : ""), al, s.powered ? "on" : "off", s.frames, s.datagrams, s.wkc];
        for (const c of cells) { const td = document.createElement("td"); td.textContent = c; tr.appendChild(td); }
        body.appendChild(tr);
      }
      el("line-stats").textContent = `frames ${line.frames}, datagrams ${line.datagrams}, bad frames ${line.bad_frames}, lost ${line.lost}`;
      el("conn").textContent = `EtherCAT line: ${slaves.length} slave(s)`;
    } catch (e) {
      el("conn").textContent = e.message;
    } finally {
      busy = false;
    }
  }
  refresh();
  setInterval(refresh, 500);
})();
