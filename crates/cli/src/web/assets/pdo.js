// PDO mapping editor (docs/http-api.md, "PDO configuration"): the node's
// RPDOs and TPDOs with their mapping; entries are added from the object
// dictionary browser's selected row (or typed as INDEX:SUB), removed,
// moved up or down; "apply" writes the PDO with PUT and shows it read back.
"use strict";
(() => {
  if (document.body.dataset.bus === "ethercat") return;
  let pdos = { rpdo: [], tpdo: [] }; // as GET /api/nodes/{n}/pdo gave them, edited in place

  const node = () => $("pdo-node").value;

  // The object to add: the dictionary browser's selected row, else the text field.
  function objectToAdd() {
    const typed = $("pdo-add").value.trim();
    if (typed) {
      const [index, sub] = typed.split(":");
      return { index, sub: sub === undefined ? 0 : parseInt(sub, 16) };
    }
    const row = document.querySelector("#od tbody tr.selected");
    return row ? { index: row.dataset.index, sub: parseInt(row.dataset.sub, 10) } : null;
  }

  function cell(tr, text) { const td = document.createElement("td"); td.textContent = text; tr.appendChild(td); return td; }
  function button(parent, label, title, onclick) {
    const b = document.createElement("button");
    Object.assign(b, { type: "button", textContent: label, title, onclick });
    parent.appendChild(b);
    return b;
  }

  function render() {
    const box = $("pdo-list");
    box.innerHTML = "";
    for (const [key, dir, label] of [["rpdo", "rx", "RPDO"], ["tpdo", "tx", "TPDO"]]) {
      for (const p of pdos[key]) {
        const div = document.createElement("div");
        div.className = "pdo";
        Object.assign(div.dataset, { dir, num: p.num });
        const head = document.createElement("div");
        head.innerHTML = `<b>${label}${p.num}</b> `;
        const field = (name, value, size, title) => {
          const l = document.createElement("label");
          l.textContent = name + " ";
          const i = Object.assign(document.createElement("input"), { value: value ?? "", size, title });
          i.dataset.field = name;
          l.appendChild(i);
          head.appendChild(l);
          return i;
        };
        field("cob_id", p.cob_id, 4, "COB-ID in hex");
        field("type", p.transmission_type, 3, "transmission type (0..255)");
        field("event_ms", p.event_timer, 5, "event timer, ms (empty: left as it is)");
        const valid = Object.assign(document.createElement("input"), { type: "checkbox", checked: p.valid });
        valid.dataset.field = "valid";
        const vl = document.createElement("label");
        vl.append(valid, " valid");
        head.appendChild(vl);
        button(head, "add", "add the object selected in the dictionary (or typed in 'object')", () => {
          const o = objectToAdd();
          if (!o) { show($("pdo-out"), "select an object in the dictionary browser, or type INDEX:SUB", true); return; }
          p.mapping.push({ index: o.index, sub: o.sub, bits: null, name: null });
          render();
        });
        button(head, "apply", "write this PDO to the node", () => apply(dir, p, div));
        div.appendChild(head);
        const table = document.createElement("table");
        table.className = "pdo-map";
        const body = document.createElement("tbody");
        p.mapping.forEach((m, i) => {
          const tr = document.createElement("tr");
          Object.assign(tr.dataset, { index: m.index, sub: m.sub });
          cell(tr, `${m.index}h:${Number(m.sub).toString(16).toUpperCase().padStart(2, "0")}h`);
          cell(tr, m.bits === null ? "(size from dictionary)" : `${m.bits} bits`);
          cell(tr, m.name || "");
          const td = cell(tr, "");
          const move = (to) => { const [e] = p.mapping.splice(i, 1); p.mapping.splice(to, 0, e); render(); };
          button(td, "↑", "move up", () => i > 0 && move(i - 1));
          button(td, "↓", "move down", () => i < p.mapping.length - 1 && move(i + 1));
          button(td, "✕", "remove", () => { p.mapping.splice(i, 1); render(); });
          body.appendChild(tr);
        });
        table.appendChild(body);
        div.appendChild(table);
        box.appendChild(div);
      }
    }
  }

  async function apply(dir, p, div) {
    const get = (f) => div.querySelector(`[data-field="${f}"]`);
    const body = {
      cob_id: get("cob_id").value.trim() || undefined,
      valid: get("valid").checked,
      mapping: p.mapping.map((m) => (m.bits === null ? { index: m.index, sub: m.sub } : { index: m.index, sub: m.sub, bits: m.bits })),
    };
    const tt = parseInt(get("type").value, 10);
    if (!Number.isNaN(tt)) body.transmission_type = tt;
    const et = parseInt(get("event_ms").value, 10);
    if (!Number.isNaN(et)) body.event_timer = et;
    try {
      const r = await api("PUT", `/api/nodes/${node()}/pdo/${dir}/${p.num}`, body);
      show($("pdo-out"), `${dir === "rx" ? "RPDO" : "TPDO"}${p.num} written`);
      Object.assign(p, r.pdo);
      render();
    } catch (e) {
      show($("pdo-out"), e.message, true);
      load(); // what is in force now
    }
  }

  async function load() {
    if (!node()) return;
    try {
      pdos = await api("GET", `/api/nodes/${node()}/pdo`);
      $("pdo-list").dataset.node = pdos.node;
      render();
    } catch (e) { show($("pdo-out"), e.message, true); }
  }

  async function nodes() {
    try {
      const { nodes } = await api("GET", "/api/nodes");
      const sel = $("pdo-node");
      const keep = sel.value;
      sel.innerHTML = "";
      for (const n of nodes) { const o = document.createElement("option"); o.value = o.textContent = n.node; sel.appendChild(o); }
      if (keep) sel.value = keep;
    } catch (e) { show($("pdo-out"), e.message, true); }
  }

  $("pdo-load").onclick = load;
  $("pdo-node").onchange = load;
  nodes().then(load);
})();
