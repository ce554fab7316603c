// EtherCAT line view (docs/http-api.md, "EtherCAT line"): on a page
// served by `ethercat serve --http` (<body data-bus="ethercat">) the
// slaves in line order with their ESM state, AL status and counters,
// refreshed twice a second and at once on every ESM event of the
// stream (/api/stream), the last events listed. The CAN panels are
// hidden (style.css).
"use strict";
(() => {
  if (document.body.dataset.bus !== "ethercat") return;
  const el = (id) => document.getElementById(id);
  let busy = false;
  async function refresh() {
    if (busy) return;
    busy = true;
    try {
      const r = await fetch("/api/ethercat" + location.search); // ?token= when required
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
  // ESM events: listed newest first (the last 50), and the table refreshed.
  function listen() {
    const ws = new WebSocket(`${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/api/stream${location.search}`);
    ws.onmessage = (m) => {
      const e = JSON.parse(m.data);
      if (e.type !== "event" || e.event !== "esm") return;
      const li = document.createElement("li");
      Object.assign(li.dataset, { position: e.position, state: e.state, alStatusCode: e.al_status_code });
      const code = e.al_status_code ? `, AL status code ${e.al_status_code.toString(16).toUpperCase().padStart(4, "0")}h ${e.al_status_text}` : "";
      li.textContent = `${(e.t / 1000).toFixed(3)} s: slave ${e.position} ${e.from} → ${e.state}${e.error ? " (error)" : ""}${code}`;
      const list = el("line-events");
      list.prepend(li);
      while (list.children.length > 50) list.lastChild.remove();
      refresh();
    };
    ws.onclose = () => setTimeout(listen, 1000);
  }
  refresh();
  listen();
  setInterval(refresh, 500);
})();
