// towtank watch page: fetches /state.json whenever /events says the version changed.
// Vanilla JS, no framework, no CDN. Every text from the state goes in as textContent, never HTML.
"use strict";

const STATUS_WORD = { ok: "OK", suspicious: "SUSPICIOUS", rejected: "REJECTED" };
const SHEET_MARK = { done: "✓", rejected: "✗", "to do": "○", void: "–", waiting: "◷" };
const SHEET_ORDER = ["done", "rejected", "waiting", "to do", "void"];
// coefficients.csv's columns shown, in this order, when present; the interval's width follows ci_high
const COEF_SHOWN = ["symbol", "value", "unit", "ci_low", "ci_high", "n_runs"];
const COEF_TITLE = {
  symbol: "symbol", value: "value", unit: "unit", ci_low: "95 % low", ci_high: "95 % high",
  n_runs: "runs", width: "± half-width",
};
const TEXT_COLUMNS = new Set(["symbol", "unit", "method", "alt_method", "agreement"]);

let shown = null;      // version on the page
let busy = false;      // a fetch is running
let again = false;     // another fetch is due after it
let source = null;     // the EventSource

function el(tag, cls, text) {
  const node = document.createElement(tag);
  if (cls) node.className = cls;
  if (text !== undefined && text !== null) node.textContent = String(text);
  return node;
}

function clear(node) {
  while (node.firstChild) node.removeChild(node.firstChild);
  return node;
}

function isNum(x) {
  return typeof x === "number" && Number.isFinite(x);
}

// A number to four significant figures (the intervals' width is what tells the precision).
function fmt(x) {
  if (!isNum(x)) return x === null || x === undefined ? "—" : String(x);
  if (x === 0) return "0";
  const a = Math.abs(x);
  let s;
  if (a >= 1e5 || a < 1e-4) s = x.toExponential(3).replace(/\.?0+e/, "e");
  else s = String(Number(x.toPrecision(4)));
  return s.replace("-", "−");
}

function clock(iso) {
  if (!iso) return "—";
  const d = new Date(iso);
  if (Number.isNaN(d.getTime())) return String(iso);
  return d.toLocaleTimeString([], { hour: "2-digit", minute: "2-digit", second: "2-digit",
    hour12: false });
}

function setConnection(on) {
  const c = document.getElementById("connection");
  c.textContent = on ? "live" : "reconnecting…";
  c.className = on ? "conn-on" : "conn-off";
}

function renderHeader(s) {
  document.getElementById("protocol").textContent = s.protocol || "towtank watch";
  document.title = "towtank watch: " + (s.protocol || "");
  document.getElementById("updated").textContent = "updated " + clock(s.updated) +
    " · version " + s.version;
  const pdf = s.pdf;
  document.getElementById("pdf").textContent = pdf && pdf.written
    ? "report.pdf written " + clock(pdf.written) + (isNum(pdf.runs) ? " (" + pdf.runs + " runs)" : "")
    : "report.pdf not written yet";
}

function renderVerdict(s) {
  const box = document.getElementById("verdict");
  const head = document.getElementById("verdict-head");
  const line = document.getElementById("verdict-line");
  const reason = document.getElementById("verdict-reason");
  const latest = s.latest;
  if (!latest) {
    box.className = "verdict none";
    head.textContent = "no run reduced yet";
    line.textContent = "";
    reason.textContent = "";
    return;
  }
  const status = String(latest.status || "");
  box.className = "verdict " + (STATUS_WORD[status] ? status : "none");
  head.textContent = "Run " + latest.run + "  " + (STATUS_WORD[status] || status);
  const verdicts = Array.isArray(s.verdicts) ? s.verdicts : [];
  let why = null;
  for (let i = verdicts.length - 1; i >= 0; i--) {
    if (verdicts[i].run === latest.run) { why = verdicts[i].reason; break; }
  }
  // the reason stands on its own line, in colour: not twice when the terminal line ends with it
  let text = String(latest.line || "");
  if (why && text.endsWith(why)) text = text.slice(0, -why.length).replace(/[\s:;,—-]+$/, "");
  line.textContent = text;
  reason.textContent = why || "";
}

function renderRecent(s) {
  const list = clear(document.getElementById("recent"));
  const verdicts = Array.isArray(s.verdicts) ? s.verdicts : [];
  for (const v of verdicts.slice(-6).reverse()) {
    const li = el("li", "st-" + v.status, v.line || ("run " + v.run + "  " + v.status));
    if (v.reason) li.title = v.reason;
    list.appendChild(li);
  }
}

function renderFigure(id, name, version, alt) {
  const box = clear(document.getElementById("fig-" + id));
  if (!name) {
    box.appendChild(el("div", "none", "no figure yet"));
    return;
  }
  const img = el("img");
  img.alt = alt;
  img.onerror = () => { clear(box).appendChild(el("div", "none", "figure not available")); };
  img.src = "/figures/" + encodeURIComponent(name) + "?v=" + encodeURIComponent(version);
  box.appendChild(img);
}

function renderFigures(s) {
  const f = s.figures && typeof s.figures === "object" ? s.figures : {};
  renderFigure("latest_run", f.latest_run, s.version, "the latest run's traces, phases and windows");
  renderFigure("damping", f.damping, s.version, "C_D(α) and its fit");
  renderFigure("added_mass", f.added_mass, s.version, "added-mass fit");
  renderFigure("captive", f.captive, s.version, "captive tests: loads against the fitted derivatives");
  // a captive day has no C_D(α) nor added-mass fit: its panel shows instead
  const captive = Boolean(f.captive) && !f.damping && !f.added_mass;
  document.getElementById("captive-panel").hidden = !f.captive;
  document.getElementById("damping-panel").hidden = captive;
  document.getElementById("added-mass-panel").hidden = captive;
}

function renderSheet(s) {
  const rows = Array.isArray(s.sheet) ? s.sheet : [];
  const counts = {};
  const list = clear(document.getElementById("sheet"));
  const latest = s.latest ? s.latest.run : null;
  for (const r of rows.filter((x) => x && typeof x === "object")) {
    const state = String(r.state || "");
    counts[state] = (counts[state] || 0) + 1;
    const li = el("li", state.replace(" ", "-") + (r.run === latest ? " latest" : ""));
    li.dataset.run = String(r.run);
    li.dataset.state = state;
    li.appendChild(el("span", "mark", SHEET_MARK[state] || "?"));
    li.appendChild(el("span", "run", r.run));
    li.appendChild(el("span", "test", r.test || ""));
    li.appendChild(el("span", "angle", isNum(r.angle_deg) ? fmt(r.angle_deg) + "°" : ""));
    li.appendChild(el("span", "speed", isNum(r.speed_m_s) ? r.speed_m_s.toFixed(2) + " m/s" : ""));
    li.appendChild(el("span", "state", state === "done" ? "" : state));
    li.title = [r.file, r.config].filter(Boolean).join(" · ");
    list.appendChild(li);
  }
  const box = clear(document.getElementById("sheet-counts"));
  for (const state of SHEET_ORDER) {
    if (!counts[state] && state !== "done" && state !== "to do") continue;
    const chip = el("span", "count " + state.replace(" ", "-"),
      (SHEET_MARK[state] || "") + " " + state + " " + (counts[state] || 0));
    chip.dataset.state = state;
    box.appendChild(chip);
  }
  box.appendChild(el("span", "of", "of " + rows.length + " runs"));
}

function renderCoefficients(s) {
  const rows = Array.isArray(s.coefficients) ? s.coefficients : [];
  const columns = Array.isArray(s.coefficient_columns) ? s.coefficient_columns
    : (rows.length ? Object.keys(rows[0]) : []);
  let shownCols = COEF_SHOWN.filter((c) => columns.includes(c));
  const hasInterval = columns.includes("ci_low") && columns.includes("ci_high");
  if (!shownCols.includes("value")) shownCols = columns.slice();
  else if (hasInterval) shownCols.splice(shownCols.indexOf("ci_high") + 1, 0, "width");
  const targets = new Set((Array.isArray(s.next_runs) ? s.next_runs : []).map((n) => n.target));

  const head = clear(document.getElementById("coef-head"));
  for (const c of shownCols) {
    head.appendChild(el("th", TEXT_COLUMNS.has(c) ? "text" : "", COEF_TITLE[c] || c));
  }
  const body = clear(document.getElementById("coef-body"));
  if (!rows.length) {
    const tr = el("tr");
    const td = el("td", "text none-yet", "no coefficient yet");
    td.colSpan = Math.max(shownCols.length, 1);
    tr.appendChild(td);
    body.appendChild(tr);
    return;
  }
  for (const r of rows) {
    const tr = el("tr", targets.has(r.symbol) ? "target" : "");
    for (const c of shownCols) {
      const td = el("td", TEXT_COLUMNS.has(c) ? "text " + c : c);
      td.dataset.column = c;
      if (c === "width") {
        fillWidth(td, r.value, r.ci_low, r.ci_high);
      } else {
        td.textContent = isNum(r[c]) ? fmt(r[c]) : (r[c] === null || r[c] === undefined ? "—"
          : String(r[c]));
        if (c === "symbol" && r.method) td.title = String(r.method);
      }
      tr.appendChild(td);
    }
    body.appendChild(tr);
  }
}

// The interval's half-width, absolute and relative to the value, with a bar as long as the latter.
function fillWidth(td, value, low, high) {
  if (!isNum(low) || !isNum(high)) { td.textContent = "—"; return; }
  const half = (high - low) / 2;
  const rel = isNum(value) && value !== 0 ? Math.abs(half / value) : null;
  if (rel !== null) {
    const bar = el("span", "bar" + (rel > 0.3 ? " very-wide" : rel > 0.1 ? " wide" : ""));
    bar.style.width = (0.25 + Math.min(rel, 1) * 6).toFixed(2) + "em";
    td.appendChild(bar);
  }
  td.appendChild(document.createTextNode("±" + fmt(half) +
    (rel !== null ? "  (" + (100 * rel).toPrecision(2).replace(/\.0$/, "") + " %)" : "")));
}

function renderNext(s) {
  const list = clear(document.getElementById("next-runs"));
  const next = Array.isArray(s.next_runs) ? s.next_runs : [];
  if (!next.length) {
    list.appendChild(el("li", "none-yet", "no fit yet"));
    list.style.listStyle = "none";
    return;
  }
  list.style.listStyle = "";
  for (const n of next.slice(0, 3)) {
    const li = el("li");
    li.appendChild(el("div", "desc", n.description || ("run " + n.run)));
    let gain = n.target + ": ±" + fmt(n.half_width_now) + " → ±" + fmt(n.half_width_after);
    if (isNum(n.relative_now) && isNum(n.relative_after)) {
      gain += "  (" + Math.round(100 * n.relative_now) + " % → " +
        Math.round(100 * n.relative_after) + " %)";
    }
    li.appendChild(el("div", "gain", gain));
    list.appendChild(li);
  }
}

function renderMessages(s) {
  const list = clear(document.getElementById("messages"));
  const msgs = Array.isArray(s.messages) ? s.messages : [];
  if (!msgs.length) list.appendChild(el("li", "none-yet", "none"));
  for (const m of msgs) list.appendChild(el("li", "", m));
}

function render(s) {
  // one malformed part of a state leaves the others on the page
  for (const part of [renderHeader, renderVerdict, renderRecent, renderFigures, renderSheet,
    renderCoefficients, renderNext, renderMessages]) {
    try { part(s); } catch (err) { console.error(part.name, err); }
  }
  shown = s.version;
  document.body.dataset.version = String(s.version);
}

async function refresh() {
  if (busy) { again = true; return; }
  busy = true;
  try {
    const r = await fetch("/state.json", { cache: "no-store" });
    if (r.status === 503) {
      const why = await r.json();
      document.getElementById("verdict-head").textContent = "waiting for the first state…";
      document.getElementById("verdict-line").textContent = why.reason || "";
    } else if (r.ok) {
      const s = await r.json();
      if (s.version !== shown) render(s);  // the same version twice: nothing to redraw
    }
  } catch (e) {
    setConnection(false);
  } finally {
    busy = false;
    if (again) { again = false; refresh(); }
  }
}

function connect() {
  if (source) source.close();
  source = new EventSource("/events");
  source.onopen = () => { setConnection(true); refresh(); };
  source.addEventListener("state", (e) => {
    let v = null;
    try { v = JSON.parse(e.data).version; } catch (err) { v = null; }
    if (v === null || v !== shown) refresh();
  });
  source.onerror = () => {
    setConnection(false);
    // the browser retries by itself; if it gave up (server gone for good), start again
    if (source.readyState === EventSource.CLOSED) setTimeout(connect, 2000);
  };
}

refresh();
connect();
