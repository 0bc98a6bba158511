// klar dashboard: talks to the server's JSON API and draws what the WebSocket streams.
"use strict";

const token = new URLSearchParams(location.search).get("token");
const HISTORY_SECONDS = 10;
const AXIS_COLOURS = ["#d9534f", "#2b6cb0", "#2e9d4a", "#8e44ad", "#e67e22", "#16a085"];

const state = {
  letters: [],
  planned: [],      // [{rapid, points: [[x, y, z], ...]}]
  trail: [],        // executed tool positions
  history: [],      // [{t, speed, acc: [...]}]
  currentLine: 0,
  lastSnapshot: null,
  view: "iso",
  runT: -1,
  shownProgram: null,
  stock: null,      // BLK FORM [[min], [max]] or null
  ends: {},         // program line -> [x, y, z] where its motion ends
  machineTime: 0,   // the test run's planned machine time of the shown program, s
  online: false,
  toScreen: null,
  lathe: false,     // a lathe: X shown as a diameter, the view Z across and X up
  spindleMax: null, // the spindle's highest speed, rpm (null: no spindle)
};

const $ = (id) => document.getElementById(id);

function withToken(url) {
  if (!token) return url;
  return url + (url.includes("?") ? "&" : "?") + "token=" + encodeURIComponent(token);
}

async function api(method, url, body) {
  const opts = { method, headers: {} };
  if (body !== undefined) {
    opts.headers["Content-Type"] = "application/json";
    opts.body = JSON.stringify(body);
  }
  const r = await fetch(withToken(url), opts);
  if (!r.ok) {
    let text = r.statusText;
    try { text = (await r.json()).error || text; } catch (_) { /* not JSON */ }
    showMessage(text);
    throw new Error(text);
  }
  return r.status === 204 ? null : r.json();
}

function showMessage(text) {
  const m = $("message");
  if (text) { m.textContent = text; m.hidden = false; } else { m.textContent = ""; m.hidden = true; }
}

// ---- program list and text -------------------------------------------------------------

async function loadProgramList() {
  const names = await api("GET", "/api/programs");
  const sel = $("program-select");
  sel.innerHTML = "";
  for (const n of names) {
    const o = document.createElement("option");
    o.value = n; o.textContent = n;
    sel.appendChild(o);
  }
}

async function showProgram(name) {
  state.shownProgram = name;
  $("program-select").value = name;
  const view = await api("GET", "/api/program?name=" + encodeURIComponent(name));
  const box = $("program-text");
  box.innerHTML = "";
  view.text.split(/\r?\n/).forEach((line, i) => {
    const div = document.createElement("div");
    div.className = "line";
    div.id = "L" + (i + 1);
    const no = document.createElement("span");
    no.className = "no"; no.textContent = String(i + 1);
    div.appendChild(no);
    div.appendChild(document.createTextNode(line));
    box.appendChild(div);
  });
  state.planned = view.path;
  state.stock = view.stock;
  state.ends = view.ends || {};
  state.machineTime = view.machine_time || 0;
  state.trail = [];
  state.currentLine = 0;
  showDiagnostics(view.diagnostics || []);
  $("total-time").textContent = state.machineTime ? state.machineTime.toFixed(1) : "—";
  drawToolpath();
}

// The test run's findings: the lines marked in the text, the list above it.
function showDiagnostics(diags) {
  const box = $("diagnostics");
  box.innerHTML = "";
  for (const d of diags) {
    const line = $("L" + d.line);
    if (line) {
      line.classList.add(d.error ? "err" : "warn");
      line.title = (line.title ? line.title + "\n" : "") + d.message;
    }
    const div = document.createElement("div");
    div.className = d.error ? "err" : "warn";
    div.textContent = `line ${d.line}:${d.col}: ${d.message}`;
    div.addEventListener("click", () => { const l = $("L" + d.line); if (l) l.scrollIntoView({ block: "center" }); });
    box.appendChild(div);
  }
  box.hidden = diags.length === 0;
}

$("load").addEventListener("click", async () => {
  const name = $("program-select").value;
  if (!name) return;
  showMessage("");
  await api("POST", "/api/load", { name });
  await showProgram(name);
});

$("upload").addEventListener("click", async () => {
  const file = $("upload-file").files[0];
  if (!file) { showMessage("choose a program file to upload first"); return; }
  showMessage("");
  const text = await file.text();
  await api("POST", "/api/upload", { name: file.name, text });
  await loadProgramList();
  $("program-select").value = file.name;
});

// ---- controls ---------------------------------------------------------------------------

$("start").addEventListener("click", () => {
  showMessage("");
  state.trail = [];
  state.history = [];
  api("POST", "/api/start");
});
$("hold").addEventListener("click", () => api("POST", "/api/hold"));
$("resume").addEventListener("click", () => api("POST", "/api/resume"));
$("stop").addEventListener("click", () => api("POST", "/api/stop"));
$("reset").addEventListener("click", () => { showMessage(""); api("POST", "/api/reset"); });

// ---- manual operation -------------------------------------------------------------------

const jogSpeed = () => Number($("jog-speed").value);
function jogBy(sign) {
  showMessage("");
  api("POST", "/api/jog", { axis: $("jog-axis").value, distance: sign * Number($("jog-step").value), speed: jogSpeed() });
}
$("jog-minus").addEventListener("click", () => jogBy(-1));
$("jog-plus").addEventListener("click", () => jogBy(1));
// Continuous jog: moves while the button is held, stops when it is let go.
for (const [id, direction] of [["jog-cont-minus", -1], ["jog-cont-plus", 1]]) {
  const b = $(id);
  let moving = false;
  b.addEventListener("pointerdown", () => {
    showMessage("");
    moving = true;
    api("POST", "/api/jog", { axis: $("jog-axis").value, direction, speed: jogSpeed() }).catch(() => { moving = false; });
  });
  const release = () => { if (moving) { moving = false; api("POST", "/api/stop"); } };
  b.addEventListener("pointerup", release);
  b.addEventListener("pointerleave", release);
  b.addEventListener("pointercancel", release);
}
$("home-axis").addEventListener("click", () => { showMessage(""); api("POST", "/api/home", { axis: $("jog-axis").value }); });
$("home-all").addEventListener("click", () => { showMessage(""); api("POST", "/api/home"); });
function runMdi() {
  const block = $("mdi-block").value.trim();
  if (!block) return;
  showMessage("");
  api("POST", "/api/mdi", { block });
}
$("mdi-run").addEventListener("click", runMdi);
$("mdi-block").addEventListener("keydown", (e) => { if (e.key === "Enter") runMdi(); });
function spindle(direction) {
  showMessage("");
  api("POST", "/api/spindle", { direction, speed: Number($("spindle-speed").value) });
}
$("spindle-cw").addEventListener("click", () => spindle("cw"));
$("spindle-ccw").addEventListener("click", () => spindle("ccw"));
$("spindle-stop").addEventListener("click", () => spindle("stop"));
$("single-block").addEventListener("change", (e) => api("POST", "/api/single_block", { on: e.target.checked }));
$("override").addEventListener("input", (e) => {
  $("override-value").textContent = e.target.value + " %";
  api("POST", "/api/override", { factor: Number(e.target.value) / 100 });
});
$("clear-trail").addEventListener("click", () => { state.trail = []; drawToolpath(); });
for (const r of document.querySelectorAll("input[name=view]")) {
  r.addEventListener("change", (e) => { state.view = e.target.value; setViewPreset(state.view); drawToolpath(); });
}

// ---- live snapshots ---------------------------------------------------------------------

function buildDro(letters) {
  const body = $("dro").querySelector("tbody");
  body.innerHTML = "";
  for (const l of letters) {
    const tr = document.createElement("tr");
    tr.innerHTML = `<td class="letter" id="ref-${l}">${l}</td><td id="cmd-${l}"></td><td id="act-${l}"></td><td class="togo" id="togo-${l}"></td><td class="fe" id="fe-${l}"></td>`;
    body.appendChild(tr);
  }
  state.letters = letters;
  const sel = $("jog-axis");
  const was = sel.value;
  sel.innerHTML = "";
  for (const l of letters) {
    const o = document.createElement("option");
    o.value = l; o.textContent = l;
    sel.appendChild(o);
  }
  if (letters.includes(was)) sel.value = was;
}

function fmt(v, digits) { return (v >= 0 ? "+" : "") + v.toFixed(digits); }

// One DRO position cell: on a lathe X reads as a diameter (⌀), its radius in small print
// and in the tooltip; every other axis as it stands.
function showPosition(cell, letter, v) {
  if (state.lathe && letter === "X") {
    cell.innerHTML = "";
    cell.append("⌀ " + fmt(2 * v, 3));
    const r = document.createElement("small");
    r.className = "radius";
    r.textContent = "r " + fmt(v, 3);
    cell.appendChild(r);
    cell.title = "diameter; radius " + fmt(v, 3);
  } else {
    cell.textContent = fmt(v, 3);
  }
}

// The spindle: commanded direction and speed, measured speed.
function showSpindle(sp) {
  if (!sp) { $("spindle").textContent = "—"; return; }
  const dir = { cw: "M3 ⟳", ccw: "M4 ⟲", stop: "M5" }[sp.direction] || sp.direction;
  const cmd = sp.direction === "stop" ? dir : `${dir} ${sp.commanded.toFixed(0)}`;
  $("spindle").textContent = `${cmd} / ${sp.measured.toFixed(0)} rpm`;
}

// The last touch-probe cycle's results and the preset it wrote.
function showProbe(p) {
  const box = $("probe-box");
  box.hidden = !p;
  if (!p) return;
  $("probe-cycle").textContent = "cycle " + p.cycle;
  $("probe-params").textContent = p.params.map(([q, v]) => `Q${q} = ${fmt(v, 4)}`).join("   ");
  const pr = p.preset;
  if (pr) {
    const where = pr.row === null ? "the active preset (no preset table)" : `preset ${pr.row}${pr.active ? " (active)" : ""}`;
    const values = pr.values.map(([l, v]) => `${l} ${fmt(v, 4)}`);
    if (pr.rotation !== undefined && pr.rotation !== null) values.push(`ROT ${fmt(pr.rotation, 4)}°`);
    $("probe-preset").textContent = `written to ${where}: ${values.join("  ")}`;
  } else {
    $("probe-preset").textContent = "no preset written";
  }
}

function applySnapshot(s) {
  if (s.letters.join() !== state.letters.join()) buildDro(s.letters);
  if (s.program && s.program !== state.shownProgram) showProgram(s.program);
  s.letters.forEach((l, i) => {
    showPosition($("cmd-" + l), l, s.commanded[i]);
    showPosition($("act-" + l), l, s.actual[i]);
    $("fe-" + l).textContent = fmt(s.following_error[i], 4);
    // An axis whose position is not referenced (not homed, no absolute encoder) is marked.
    const referenced = !s.referenced || s.referenced[i];
    const cell = $("ref-" + l);
    cell.classList.toggle("unreferenced", !referenced);
    cell.title = referenced ? "referenced" : "not referenced";
  });
  // Distance to go: from the tool to the end of the executing block's motion, both in the
  // frame of the program's path (on a lathe X as a diameter).
  const end = !s.manual && (s.state === "running" || s.state === "held") ? state.ends[s.line] : null;
  s.letters.forEach((l) => {
    const k = ["X", "Y", "Z"].indexOf(l);
    const d = end && k >= 0 ? (end[k] - s.tool[k]) * (state.lathe && l === "X" ? 2 : 1) : null;
    $("togo-" + l).textContent = d === null ? "" : fmt(d, 3);
  });
  // Progress by machine time against the test run's planned machine time.
  const total = s.manual ? 0 : state.machineTime;
  const running = s.state === "running" || s.state === "held";
  const done = s.state === "finished" ? 1 : (total > 0 ? Math.min(1, s.t / total) : 0);
  $("progress").value = running || s.state === "finished" ? done : 0;
  $("progress-pct").textContent = Math.round(100 * $("progress").value);
  $("remaining").textContent = total > 0 && running ? Math.max(0, total - s.t).toFixed(1) : "—";
  $("manual-op").textContent = s.manual ? "manual: " + s.manual : "";
  $("state").textContent = s.state;
  $("line-no").textContent = s.line;
  $("time").textContent = s.t.toFixed(3);
  $("path-speed").textContent = s.path_speed.toFixed(1);
  $("blocks").textContent = s.blocks;
  showSpindle(s.spindle);
  showProbe(s.probe);
  $("single-block").checked = s.single_block;
  if (document.activeElement !== $("override")) {
    const pct = Math.round(s.feed_override * 100);
    $("override").value = pct;
    $("override-value").textContent = pct + " %";
  }
  if (s.message) showMessage(s.message);
  if (s.line !== state.currentLine) {
    const old = $("L" + state.currentLine);
    if (old) old.classList.remove("current");
    const now = $("L" + s.line);
    if (now) {
      now.classList.add("current");
      now.scrollIntoView({ block: "nearest" });
    }
    state.currentLine = s.line;
  }
  // A new run (its machine time starts again): a new motion plot. At the end t is cleared;
  // the plot of the run just ended stays.
  const live = s.state === "running" || s.state === "held";
  if (live && s.t < state.runT) { state.history = []; }
  state.runT = live ? s.t : 0;
  if (s.state === "running" || s.state === "held") {
    for (const p of s.trail) state.trail.push(p);
    state.history.push({ t: s.t, speed: s.path_speed, acc: s.acceleration.slice() });
    while (state.history.length && state.history[0].t < s.t - HISTORY_SECONDS) state.history.shift();
  }
  state.lastSnapshot = s;
  updateButtons();
  drawToolpath();
  drawSpeedPlot();
}

// Every control enabled only when it acts in the machine's state; none without the server.
function updateButtons() {
  const s = state.lastSnapshot;
  const st = s ? s.state : "offline";
  const on = state.online && s;
  const moving = st === "running" || st === "held";
  const fault = st === "fault";
  const enable = {
    start: on && !moving && !fault && !!s.program && !!$("program-select").options.length,
    hold: on && st === "running",
    resume: on && st === "held",
    stop: on && moving,
    reset: on && (fault || st === "error"),
    load: on && !moving,
    upload: on && !moving,
  };
  for (const id of ["jog-minus", "jog-plus", "jog-cont-minus", "jog-cont-plus", "home-axis", "home-all", "mdi-run"]) {
    enable[id] = on && !moving && !fault;
  }
  for (const id of ["spindle-cw", "spindle-ccw", "spindle-stop"]) {
    enable[id] = on && !moving && !fault && state.spindleMax !== null;
  }
  // A continuous jog's own button stays usable while it moves: letting go stops it.
  if (on && st === "running" && s.manual && s.manual.startsWith("jog") && !/\d/.test(s.manual)) {
    enable["jog-cont-minus"] = enable["jog-cont-plus"] = true;
  }
  // Override and single block act in every state, but only with the server there.
  enable.override = !!on;
  enable["single-block"] = !!on;
  for (const [id, ok] of Object.entries(enable)) $(id).disabled = !ok;
  document.body.classList.toggle("offline", !state.online);
}

function connect() {
  const proto = location.protocol === "https:" ? "wss://" : "ws://";
  const ws = new WebSocket(withToken(proto + location.host + "/ws"));
  ws.onopen = () => {
    state.online = true;
    $("link").textContent = "live"; $("link").className = "link up";
    updateButtons();
  };
  ws.onmessage = (ev) => applySnapshot(JSON.parse(ev.data));
  ws.onclose = () => {
    // Whatever the page showed is no longer known: say so instead of the last state.
    state.online = false;
    $("link").textContent = "offline"; $("link").className = "link down";
    $("state").textContent = "no connection to the server";
    $("path-speed").textContent = "—";
    $("spindle").textContent = "—";
    updateButtons();
    setTimeout(connect, 1000);
  };
}

// ---- drawing (the toolpath view is in view.js) ----------------------------------------

function drawSpeedPlot() {
  const cv = $("speed-plot");
  const g = cv.getContext("2d");
  g.clearRect(0, 0, cv.width, cv.height);
  const h = state.history;
  const half = cv.height / 2;
  g.font = "11px sans-serif";
  g.fillStyle = "#333";
  g.fillText("path speed [mm/s]", 6, 12);
  g.fillText("axis acceleration [mm/s²]", 6, half + 12);
  if (h.length < 2) return;
  const tEnd = h[h.length - 1].t, tStart = tEnd - HISTORY_SECONDS;
  const X = (t) => 40 + (t - tStart) / HISTORY_SECONDS * (cv.width - 50);
  const vMax = Math.max(1, ...h.map((e) => e.speed));
  const aMax = Math.max(1, ...h.flatMap((e) => e.acc.map(Math.abs)));
  g.strokeStyle = "#ccc"; g.lineWidth = 1;
  g.beginPath(); g.moveTo(40, half - 4); g.lineTo(cv.width - 10, half - 4); g.stroke();
  g.beginPath(); g.moveTo(40, half + half / 2 + 6); g.lineTo(cv.width - 10, half + half / 2 + 6); g.stroke();
  g.fillText(vMax.toFixed(0), 4, 26);
  g.fillText(aMax.toFixed(0), 4, half + 26);
  g.strokeStyle = "#1f2d3d"; g.lineWidth = 1.5;
  g.beginPath();
  h.forEach((e, i) => { const y = half - 4 - e.speed / vMax * (half - 24); if (i) g.lineTo(X(e.t), y); else g.moveTo(X(e.t), y); });
  g.stroke();
  const mid = half + half / 2 + 6, amp = half / 2 - 14;
  state.letters.forEach((l, k) => {
    g.strokeStyle = AXIS_COLOURS[k % AXIS_COLOURS.length];
    g.beginPath();
    h.forEach((e, i) => { const y = mid - (e.acc[k] || 0) / aMax * amp; if (i) g.lineTo(X(e.t), y); else g.moveTo(X(e.t), y); });
    g.stroke();
    g.fillStyle = g.strokeStyle;
    g.fillText(l, cv.width - 40 + 10 * k, half + 12);
  });
}

// ---- start ----------------------------------------------------------------------------------

(async () => {
  const m = await api("GET", "/api/machine");
  $("machine-name").textContent = m.name;
  state.lathe = !!m.lathe;
  state.spindleMax = m.spindle_max_rpm === undefined ? null : m.spindle_max_rpm;
  if (state.spindleMax !== null) $("spindle-speed").max = state.spindleMax;
  $("spindle-bar").hidden = state.spindleMax === null;
  // On a lathe the spindle is the main spindle, and the view is the lathe's Z/X.
  for (const e of document.querySelectorAll(".spindle-name")) e.textContent = state.lathe ? "main spindle" : "spindle";
  for (const e of document.querySelectorAll(".mill-view")) e.hidden = state.lathe;
  $("lathe-view").hidden = !state.lathe;
  if (state.lathe) { state.view = "lathe"; setViewPreset("lathe"); }
  $("machine-preset").textContent = "preset " + m.preset;
  $("preset-line").textContent = "active preset: " + m.preset;
  const tools = $("tools").querySelector("tbody");
  tools.innerHTML = "";
  for (const t of m.tools || []) {
    const tr = document.createElement("tr");
    for (const v of [t.number, t.name, t.length.toFixed(3), t.radius.toFixed(3)]) {
      const td = document.createElement("td");
      td.textContent = v;
      tr.appendChild(td);
    }
    tools.appendChild(tr);
  }
  if (!(m.tools || []).length) tools.innerHTML = "<tr><td colspan=4>no tool table</td></tr>";
  buildDro(m.letters);
  updateButtons();
  await loadProgramList();
  connect();
})();
