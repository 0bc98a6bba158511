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
  state.trail = [];
  state.currentLine = 0;
  if (view.errors.length) showMessage(view.errors.join("\n"));
  drawToolpath();
}

$("load").addEventListener("click", async () => {
  const name = $("program-select").value;
  if (!name) return;
  showMessage("");
  await api("POST", "/api/load", { name });
  await showProgram(name);
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
$("single-block").addEventListener("change", (e) => api("POST", "/api/single_block", { on: e.target.checked }));
$("override").addEventListener("input", (e) => {
  $("override-value").textContent = e.target.value + " %";
  api("POST", "/api/override", { factor: Number(e.target.value) / 100 });
});
$("clear-trail").addEventListener("click", () => { state.trail = []; drawToolpath(); });
for (const r of document.querySelectorAll("input[name=view]")) {
  r.addEventListener("change", (e) => { state.view = e.target.value; drawToolpath(); });
}

// ---- live snapshots ---------------------------------------------------------------------

function buildDro(letters) {
  const body = $("dro").querySelector("tbody");
  body.innerHTML = "";
  for (const l of letters) {
    const tr = document.createElement("tr");
    tr.innerHTML = `<td class="letter" id="ref-${l}">${l}</td><td id="cmd-${l}"></td><td id="act-${l}"></td><td class="fe" id="fe-${l}"></td>`;
    body.appendChild(tr);
  }
  state.letters = letters;
}

function fmt(v, digits) { return (v >= 0 ? "+" : "") + v.toFixed(digits); }

function applySnapshot(s) {
  if (s.letters.join() !== state.letters.join()) buildDro(s.letters);
  if (s.program && s.program !== state.shownProgram) showProgram(s.program);
  s.letters.forEach((l, i) => {
    $("cmd-" + l).textContent = fmt(s.commanded[i], 3);
    $("act-" + l).textContent = fmt(s.actual[i], 3);
    $("fe-" + l).textContent = fmt(s.following_error[i], 4);
    // An axis whose position is not referenced (not homed, no absolute encoder) is marked.
    const referenced = !s.referenced || s.referenced[i];
    const cell = $("ref-" + l);
    cell.classList.toggle("unreferenced", !referenced);
    cell.title = referenced ? "referenced" : "not referenced";
  });
  $("state").textContent = s.state;
  $("line-no").textContent = s.line;
  $("time").textContent = s.t.toFixed(3);
  $("path-speed").textContent = s.path_speed.toFixed(1);
  $("blocks").textContent = s.blocks;
  $("spindle").textContent = s.spindle_rpm === null ? "—" : s.spindle_rpm.toFixed(0) + " rpm";
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
  if (s.t < state.runT) { state.history = []; }
  state.runT = s.t;
  if (s.state === "running" || s.state === "held") {
    for (const p of s.trail) state.trail.push(p);
    state.history.push({ t: s.t, speed: s.path_speed, acc: s.acceleration.slice() });
    while (state.history.length && state.history[0].t < s.t - HISTORY_SECONDS) state.history.shift();
  }
  state.lastSnapshot = s;
  drawToolpath();
  drawSpeedPlot();
}

function connect() {
  const proto = location.protocol === "https:" ? "wss://" : "ws://";
  const ws = new WebSocket(withToken(proto + location.host + "/ws"));
  ws.onopen = () => { $("link").textContent = "live"; $("link").className = "link up"; };
  ws.onmessage = (ev) => applySnapshot(JSON.parse(ev.data));
  ws.onclose = () => {
    $("link").textContent = "offline"; $("link").className = "link down";
    setTimeout(connect, 1000);
  };
}

// ---- drawing ------------------------------------------------------------------------------

function project(p) {
  const [x, y, z] = p;
  switch (state.view) {
    case "top": return [x, y];
    case "front": return [x, z];
    default: {
      const c = Math.cos(Math.PI / 6), s = Math.sin(Math.PI / 6);
      return [(x - y) * c, (x + y) * s + z];
    }
  }
}

function drawToolpath() {
  const cv = $("toolpath");
  const g = cv.getContext("2d");
  g.clearRect(0, 0, cv.width, cv.height);
  const strokes = state.planned.map((s) => ({ rapid: s.rapid, pts: s.points.map(project) }));
  const trail = state.trail.map(project);
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  const grow = ([x, y]) => { x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y); };
  strokes.forEach((s) => s.pts.forEach(grow));
  trail.forEach(grow);
  if (!(x0 <= x1)) { x0 = -1; x1 = 1; y0 = -1; y1 = 1; }
  const pad = 30;
  const scale = Math.min((cv.width - 2 * pad) / Math.max(x1 - x0, 1), (cv.height - 2 * pad) / Math.max(y1 - y0, 1));
  const ox = pad + ((cv.width - 2 * pad) - (x1 - x0) * scale) / 2;
  const oy = pad + ((cv.height - 2 * pad) - (y1 - y0) * scale) / 2;
  const px = ([x, y]) => [ox + (x - x0) * scale, cv.height - (oy + (y - y0) * scale)];

  drawScale(g, cv, scale);
  g.lineWidth = 1.2;
  for (const s of strokes) {
    g.strokeStyle = s.rapid ? "#d9534f" : "#2b6cb0";
    g.setLineDash(s.rapid ? [6, 4] : []);
    g.beginPath();
    s.pts.forEach((p, i) => { const [a, b] = px(p); if (i) g.lineTo(a, b); else g.moveTo(a, b); });
    g.stroke();
  }
  g.setLineDash([]);
  if (trail.length) {
    g.strokeStyle = "#2e9d4a";
    g.lineWidth = 3;
    g.beginPath();
    trail.forEach((p, i) => { const [a, b] = px(p); if (i) g.lineTo(a, b); else g.moveTo(a, b); });
    g.stroke();
    const [a, b] = px(trail[trail.length - 1]);
    g.fillStyle = "#1f2d3d";
    g.beginPath(); g.arc(a, b, 5, 0, 2 * Math.PI); g.fill();
  }
}

/// A scale bar of a round length in the lower left corner.
function drawScale(g, cv, scale) {
  const target = 120 / scale;
  const pow = Math.pow(10, Math.floor(Math.log10(target)));
  const len = [1, 2, 5, 10].map((m) => m * pow).filter((l) => l <= target).pop() || pow;
  const w = len * scale;
  g.strokeStyle = "#333"; g.lineWidth = 2; g.setLineDash([]);
  g.beginPath(); g.moveTo(12, cv.height - 14); g.lineTo(12 + w, cv.height - 14); g.stroke();
  g.fillStyle = "#333"; g.font = "12px sans-serif";
  g.fillText(len + " mm", 16 + w, cv.height - 10);
  const names = { iso: "isometric", top: "X/Y", front: "X/Z" };
  g.fillText(names[state.view], 12, 16);
}

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
  $("machine-preset").textContent = "preset " + m.preset;
  buildDro(m.letters);
  await loadProgramList();
  connect();
})();
