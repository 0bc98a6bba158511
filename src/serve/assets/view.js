// klar dashboard: the toolpath view — an orthographic camera over the planned path, the
// executed trail, the BLK FORM blank and the tool, with zoom (wheel), pan (drag) and orbit
// (shift-drag, or the right mouse button). Double-click fits the drawing again.
"use strict";

// Camera presets: yaw turns about the Z axis, pitch tilts toward looking down Z.
const VIEW_PRESETS = {
  iso: { yaw: Math.PI / 4, pitch: Math.atan(1 / Math.SQRT2) },
  top: { yaw: 0, pitch: Math.PI / 2 },
  front: { yaw: 0, pitch: 0 },
  lathe: { yaw: 0, pitch: 0 },
};

const camera = { yaw: VIEW_PRESETS.iso.yaw, pitch: VIEW_PRESETS.iso.pitch, zoom: 1, panX: 0, panY: 0, custom: false };

// Length of the tool drawn along +Z from its tip, mm on the screen's scale.
const TOOL_LENGTH_PX = 40;

function setViewPreset(name) {
  const p = VIEW_PRESETS[name] || VIEW_PRESETS.iso;
  camera.yaw = p.yaw; camera.pitch = p.pitch;
  camera.zoom = 1; camera.panX = 0; camera.panY = 0; camera.custom = false;
}

// Path X/Y/Z to the view plane: u to the right, v up. A lathe's view has Z across and X
// (a radius) up, as `klar plot` draws it; the panning and zoom act on it as on the others.
function project(p) {
  const [x, y, z] = p;
  if (state.lathe) return [z, x];
  const cy = Math.cos(camera.yaw), sy = Math.sin(camera.yaw);
  const cp = Math.cos(camera.pitch), sp = Math.sin(camera.pitch);
  const u = x * cy - y * sy;
  const depth = x * sy + y * cy;
  return [u, depth * sp + z * cp];
}

// The twelve edges of a box given by its MIN and MAX corners.
function boxEdges(min, max) {
  const c = (i) => [i & 1 ? max[0] : min[0], i & 2 ? max[1] : min[1], i & 4 ? max[2] : min[2]];
  const edges = [];
  for (let i = 0; i < 8; i++) {
    for (const bit of [1, 2, 4]) if (!(i & bit)) edges.push([c(i), c(i | bit)]);
  }
  return edges;
}

// The tool tip (X, Y, Z) from the latest snapshot: its measured position in the frame of
// the program's path, the frame the path, the trace and the distance to go are drawn in.
function toolTip() {
  const s = state.lastSnapshot;
  return s && s.tool ? s.tool : null;
}

function drawToolpath() {
  const cv = $("toolpath");
  const g = cv.getContext("2d");
  g.clearRect(0, 0, cv.width, cv.height);
  const strokes = state.planned.map((s) => ({ rapid: s.rapid, pts: s.points.map(project) }));
  const trail = state.trail.map(project);
  const stock = state.stock ? boxEdges(state.stock[0], state.stock[1]).map((e) => e.map(project)) : [];
  const tip = toolTip();
  let x0 = Infinity, x1 = -Infinity, y0 = Infinity, y1 = -Infinity;
  const grow = ([x, y]) => { x0 = Math.min(x0, x); x1 = Math.max(x1, x); y0 = Math.min(y0, y); y1 = Math.max(y1, y); };
  // A lathe's view frames the cutting moves (when it has any), so a tool change point far
  // out does not shrink the part into a corner; elsewhere everything drawn is framed.
  const cutting = strokes.filter((s) => !s.rapid);
  if (state.lathe && cutting.length) {
    cutting.forEach((s) => s.pts.forEach(grow));
    stock.forEach((e) => e.forEach(grow));
  } else {
    strokes.forEach((s) => s.pts.forEach(grow));
    trail.forEach(grow);
    stock.forEach((e) => e.forEach(grow));
    if (tip) grow(project(tip));
  }
  if (!(x0 <= x1)) { x0 = -1; x1 = 1; y0 = -1; y1 = 1; }
  const pad = 30;
  const fit = Math.min((cv.width - 2 * pad) / Math.max(x1 - x0, 1), (cv.height - 2 * pad) / Math.max(y1 - y0, 1));
  const scale = fit * camera.zoom;
  const cx = (x0 + x1) / 2, cy = (y0 + y1) / 2;
  const px = ([x, y]) => [cv.width / 2 + (x - cx) * scale + camera.panX, cv.height / 2 - (y - cy) * scale + camera.panY];
  state.toScreen = px;

  drawScale(g, cv, scale);
  if (state.lathe) drawDiameterRuler(g, cv, scale, (v) => px([0, v])[1]);
  const line = (pts) => {
    g.beginPath();
    pts.forEach((p, i) => { const [a, b] = px(p); if (i) g.lineTo(a, b); else g.moveTo(a, b); });
    g.stroke();
  };
  if (stock.length) {
    g.strokeStyle = "#9a7b4f"; g.lineWidth = 1; g.setLineDash([2, 3]);
    stock.forEach(line);
  }
  g.lineWidth = 1.2;
  for (const s of strokes) {
    g.strokeStyle = s.rapid ? "#d9534f" : "#2b6cb0";
    g.setLineDash(s.rapid ? [6, 4] : []);
    line(s.pts);
  }
  g.setLineDash([]);
  if (trail.length) {
    g.strokeStyle = "#2e9d4a"; g.lineWidth = 3;
    line(trail);
  }
  if (tip) {
    // The tool: its tip as a dot, its shank along +Z.
    const [a, b] = px(project(tip));
    // (on a lathe the tool holder stands away from the spindle axis: along +X)
    const up = project(state.lathe ? [tip[0] + 1, tip[1], tip[2]] : [tip[0], tip[1], tip[2] + 1]);
    const [ua, ub] = px(up);
    const len = Math.hypot(ua - a, ub - b);
    const [dx, dy] = len > 1e-9 ? [(ua - a) / len, (ub - b) / len] : [0, 0];
    g.strokeStyle = "#1f2d3d"; g.lineWidth = 6; g.lineCap = "round";
    g.beginPath(); g.moveTo(a, b); g.lineTo(a + dx * TOOL_LENGTH_PX, b + dy * TOOL_LENGTH_PX); g.stroke();
    g.lineCap = "butt";
    g.fillStyle = "#f0a020";
    g.beginPath(); g.arc(a, b, 4, 0, 2 * Math.PI); g.fill();
  }
}

/// A scale bar of a round length in the lower left corner, and the view's name.
function drawScale(g, cv, scale) {
  const target = 120 / scale;
  const pow = Math.pow(10, Math.floor(Math.log10(target)));
  const len = [1, 2, 5, 10].map((m) => m * pow).filter((l) => l <= target).pop() || pow;
  const w = len * scale;
  g.strokeStyle = "#333"; g.lineWidth = 2; g.setLineDash([]);
  g.beginPath(); g.moveTo(12, cv.height - 14); g.lineTo(12 + w, cv.height - 14); g.stroke();
  g.fillStyle = "#333"; g.font = "12px sans-serif";
  g.fillText(len + " mm", 16 + w, cv.height - 10);
  const names = { iso: "isometric", top: "X/Y", front: "X/Z", lathe: "Z → / X ⌀ ↑" };
  const zoom = camera.zoom === 1 ? "" : "  zoom " + camera.zoom.toFixed(2) + "×";
  g.fillText((camera.custom ? "orbit" : names[state.view]) + zoom, 12, 16);
}

/// A lathe's X ruler on the left edge: ticks at round radii, labelled as diameters (X ⌀),
/// and the spindle axis (X = 0) dash-dotted across. `yOf` maps a radius to the canvas.
function drawDiameterRuler(g, cv, scale, yOf) {
  const target = 60 / scale;
  const pow = Math.pow(10, Math.floor(Math.log10(target)));
  const step = [1, 2, 5, 10].map((m) => m * pow).find((l) => l >= target) || pow;
  g.strokeStyle = "#555"; g.fillStyle = "#333"; g.lineWidth = 1; g.font = "11px sans-serif";
  const x = 44;
  g.beginPath(); g.moveTo(x, 44); g.lineTo(x, cv.height - 30); g.stroke();
  const top = Math.ceil(radiusAt(cv.height - 30) / step), bottom = Math.floor(radiusAt(44) / step);
  function radiusAt(y) { return (yOf(0) - y) / scale; }
  for (let k = top; k <= bottom; k++) {
    const y = yOf(k * step);
    g.beginPath(); g.moveTo(x - 4, y); g.lineTo(x, y); g.stroke();
    const label = String(+(2 * k * step).toFixed(6));
    g.fillText(label, x - 6 - g.measureText(label).width, y + 4);
  }
  g.fillText("X ⌀ [mm]", x - 30, 36);
  const y0 = yOf(0);
  if (y0 > 0 && y0 < cv.height) {
    g.setLineDash([12, 3, 2, 3]); g.strokeStyle = "#8a96a3";
    g.beginPath(); g.moveTo(x, y0); g.lineTo(cv.width - 8, y0); g.stroke();
    g.setLineDash([]);
  }
}

// ---- mouse and touch: zoom, pan, orbit ----------------------------------------------------

(function installViewControls() {
  const cv = $("toolpath");
  // Canvas pixels per CSS pixel (the canvas is scaled to the page's width).
  const ratio = () => cv.width / cv.getBoundingClientRect().width;
  cv.addEventListener("wheel", (e) => {
    e.preventDefault();
    const r = cv.getBoundingClientRect();
    const mx = (e.clientX - r.left) * ratio() - cv.width / 2;
    const my = (e.clientY - r.top) * ratio() - cv.height / 2;
    const f = Math.exp(-e.deltaY * 0.0015);
    const zoom = Math.min(200, Math.max(0.05, camera.zoom * f));
    const k = zoom / camera.zoom;
    // Keep the point under the cursor where it is.
    camera.panX = mx - (mx - camera.panX) * k;
    camera.panY = my - (my - camera.panY) * k;
    camera.zoom = zoom;
    drawToolpath();
  }, { passive: false });
  let drag = null;
  cv.addEventListener("pointerdown", (e) => {
    drag = { x: e.clientX, y: e.clientY, orbit: !state.lathe && (e.shiftKey || e.button === 2) };
    cv.setPointerCapture(e.pointerId);
  });
  cv.addEventListener("pointermove", (e) => {
    if (!drag) return;
    const dx = e.clientX - drag.x, dy = e.clientY - drag.y;
    drag.x = e.clientX; drag.y = e.clientY;
    if (drag.orbit) {
      camera.yaw += dx * 0.01;
      camera.pitch = Math.min(Math.PI / 2, Math.max(-Math.PI / 2, camera.pitch + dy * 0.01));
      camera.custom = true;
    } else {
      camera.panX += dx * ratio();
      camera.panY += dy * ratio();
    }
    drawToolpath();
  });
  const end = () => { drag = null; };
  cv.addEventListener("pointerup", end);
  cv.addEventListener("pointercancel", end);
  cv.addEventListener("contextmenu", (e) => e.preventDefault());
  cv.addEventListener("dblclick", () => { setViewPreset(state.view); drawToolpath(); });
})();
