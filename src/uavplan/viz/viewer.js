// uavplan viewer: an orthographic 3-D view on a 2-D canvas (no library, no network).
// DATA (set by the page): bounds, terrain, cylinders, polygons, moving, uavs.
"use strict";
const errors = [];
window.addEventListener("error", (e) => errors.push(String(e.message)));
const consoleError = console.error.bind(console);
console.error = (...args) => { errors.push(args.map(String).join(" ")); consoleError(...args); };
const cv = document.getElementById("view");
const ctx = cv.getContext("2d");
const slider = document.getElementById("time");
const clock = document.getElementById("clock");
const lo = DATA.bounds.lo, hi = DATA.bounds.hi;
const span = Math.max(hi[0] - lo[0], hi[1] - lo[1], 1);
const zr = Math.max(hi[2] - lo[2], 1e-9);
// a flat-looking world (heights under a tenth of the map) is drawn with its z stretched
const zx = DATA.dim === 3 ? Math.max(1, Math.round((0.25 * span) / zr)) : 1;
const centre = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, (lo[2] + hi[2]) / 2];
let yaw = DATA.dim === 3 ? -0.6 : 0.0, pitch = DATA.dim === 3 ? 0.9 : Math.PI / 2, zoom = 1.0;
const tEnd = Math.max(1e-9, ...DATA.uavs.map((u) => u.times[u.times.length - 1]));
const palette = ["#1f77b4", "#ff7f0e", "#2ca02c", "#9467bd", "#8c564b", "#e377c2", "#17becf", "#bcbd22"];

function project(p) {
  const x = p[0] - centre[0], y = p[1] - centre[1], z = ((p[2] || 0) - centre[2]) * zx;
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  const x1 = cy * x - sy * y, y1 = sy * x + cy * y;           // turn about z
  const y2 = cp * y1 - sp * z, z2 = sp * y1 + cp * z;          // tilt about x
  const s = (zoom * 0.8 * Math.min(cv.width, cv.height)) / span;
  return [cv.width / 2 + s * x1, cv.height / 2 - s * z2, y2];  // screen x, y, depth
}

function colour(h) {  // a terrain ramp from green lowlands to brown and white heights
  const t = Math.min(1, Math.max(0, (h - lo[2]) / zr));
  const stops = [[0, [96, 160, 96]], [0.5, [190, 170, 110]], [0.85, [150, 120, 90]], [1, [245, 245, 245]]];
  let k = 0;
  while (k < stops.length - 2 && t > stops[k + 1][0]) k++;
  const [t0, c0] = stops[k], [t1, c1] = stops[k + 1];
  const f = (t - t0) / (t1 - t0 || 1);
  return c0.map((c, i) => Math.round(c + f * (c1[i] - c)));
}

function at(times, pts, t) {  // position at time t (held before the start and after the end)
  if (t <= times[0]) return pts[0];
  const n = times.length - 1;
  if (t >= times[n]) return pts[n];
  let a = 0, b = n;
  while (b - a > 1) { const m = (a + b) >> 1; if (times[m] <= t) a = m; else b = m; }
  const f = (t - times[a]) / (times[b] - times[a] || 1);
  return pts[a].map((v, i) => v + f * (pts[b][i] - v));
}

function groundAt(x, y) {  // the shown terrain's height at (x, y) (nearest node), else 0
  const T = DATA.terrain;
  if (!T) return 0;
  const i = Math.min(T.h.length - 1, Math.max(0, Math.round((y - T.y0) / T.dy)));
  const j = Math.min(T.h[0].length - 1, Math.max(0, Math.round((x - T.x0) / T.dx)));
  return T.h[i][j];
}

function line(pts, style, width, dash) {
  ctx.strokeStyle = style; ctx.lineWidth = width; ctx.setLineDash(dash || []);
  ctx.beginPath();
  pts.forEach((p, i) => { const q = project(p); if (i) ctx.lineTo(q[0], q[1]); else ctx.moveTo(q[0], q[1]); });
  ctx.stroke(); ctx.setLineDash([]);
}

function ring(c, r, z, n) {
  const out = [];
  for (let k = 0; k <= n; k++) { const a = (2 * Math.PI * k) / n; out.push([c[0] + r * Math.cos(a), c[1] + r * Math.sin(a), z]); }
  return out;
}

function drawTerrain() {
  const T = DATA.terrain;
  if (!T) return;
  const quads = [];
  for (let i = 0; i + 1 < T.h.length; i++) {
    for (let j = 0; j + 1 < T.h[i].length; j++) {
      const p = [[j, i], [j + 1, i], [j + 1, i + 1], [j, i + 1]].map(([a, b]) => [T.x0 + a * T.dx, T.y0 + b * T.dy, T.h[b][a]]);
      const q = p.map(project);
      quads.push([q.reduce((s, v) => s + v[2], 0) / 4, q, (p[0][2] + p[2][2]) / 2]);
    }
  }
  quads.sort((a, b) => b[0] - a[0]);  // far to near
  for (const [, q, h] of quads) {
    const [r, g, b] = colour(h);
    ctx.fillStyle = ctx.strokeStyle = `rgb(${r},${g},${b})`;
    ctx.lineWidth = 1;
    ctx.beginPath(); q.forEach((v, k) => (k ? ctx.lineTo(v[0], v[1]) : ctx.moveTo(v[0], v[1]))); ctx.closePath();
    ctx.fill(); ctx.stroke();  // the stroke hides the seams between quads
  }
}

function draw() {
  cv.width = window.innerWidth; cv.height = Math.max(200, window.innerHeight - 40);
  ctx.fillStyle = "#fff"; ctx.fillRect(0, 0, cv.width, cv.height);
  const t = (slider.value / 1000) * tEnd;
  clock.textContent = `t = ${t.toFixed(1)} s of ${tEnd.toFixed(1)} s`;
  drawTerrain();
  for (const c of DATA.cylinders || []) {
    line(ring(c.c, c.r, c.z[0], 48), "#c0392b", 1.5);
    line(ring(c.c, c.r, c.z[1], 48), "#c0392b", 1.5);
    for (let k = 0; k < 4; k++) { const a = (Math.PI * k) / 2; const x = c.c[0] + c.r * Math.cos(a), y = c.c[1] + c.r * Math.sin(a); line([[x, y, c.z[0]], [x, y, c.z[1]]], "#c0392b", 1); }
  }
  for (const P of DATA.polygons || []) {
    for (const z of P.z) line([...P.v, P.v[0]].map((v) => [v[0], v[1], z]), "#8e44ad", 1.5);
  }
  // areas lie on the ground: each outline point at the terrain's height there
  const onGround = (pts) => pts.map((p) => [p[0], p[1], groundAt(p[0], p[1])]);
  for (const d of DATA.danger || []) line(onGround(ring(d.c, d.r, 0, 48)), "#d4a017", 2);
  for (const u of DATA.uncertain || []) {
    const edge = [];
    const v = [...u.v, u.v[0]];
    for (let k = 0; k + 1 < v.length; k++) {
      for (let f = 0; f < 1; f += 0.05) edge.push([v[k][0] + f * (v[k + 1][0] - v[k][0]), v[k][1] + f * (v[k + 1][1] - v[k][1])]);
    }
    edge.push(v[v.length - 1]);
    line(onGround(edge), "#8e44ad", 2, u.known ? [] : [6, 4]);
  }
  DATA.uavs.forEach((u, k) => {
    const col = u.ok === false ? "#e00000" : palette[k % palette.length];
    line(u.planned, "#888", 1, [4, 4]);
    line(u.flown, col, u.ok === false ? 3 : 1.8);
  });
  for (const m of DATA.moving || []) {
    const p = project(at(m.t, m.p, t));
    const s = (zoom * 0.8 * Math.min(cv.width, cv.height)) / span;
    ctx.fillStyle = "#e67e2244"; ctx.strokeStyle = "#e67e22";
    ctx.beginPath(); ctx.arc(p[0], p[1], Math.max(3, m.r * s), 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
  }
  const shown = [];
  DATA.uavs.forEach((u, k) => {
    const p = project(at(u.times, u.flown, t));
    shown.push([u.id, p[0], p[1]]);
    ctx.fillStyle = u.ok === false ? "#e00000" : palette[k % palette.length];
    ctx.strokeStyle = "#000"; ctx.lineWidth = 1;
    ctx.beginPath(); ctx.arc(p[0], p[1], 4.5, 0, 2 * Math.PI); ctx.fill(); ctx.stroke();
    if (DATA.uavs.length <= 40) { ctx.fillStyle = "#000"; ctx.fillText(u.id, p[0] + 6, p[1] - 6); }
  });
  window.__shown = shown;
}

function legend() {
  const bad = DATA.uavs.filter((u) => u.ok === false).length;
  const rows = [
    `<b>${DATA.name}</b>: ${DATA.uavs.length} UAV${DATA.uavs.length === 1 ? "" : "s"}`,
    DATA.feasible === true ? "verified as flown" : "<span style='color:#e00000'><b>NOT FLYABLE</b>: do not fly this plan</span>",
    "<span style='color:#1f77b4'>&#9473;</span> flown (declared, verified)",
    "<span style='color:#888'>&#9476;</span> planned polyline",
  ];
  if (bad) rows.push(`<span style='color:#e00000'>&#9473;</span> ${bad} UAV(s) failing a check`);
  if ((DATA.cylinders || []).length) rows.push("<span style='color:#c0392b'>&#9711;</span> cylinders / circles");
  if ((DATA.polygons || []).length) rows.push("<span style='color:#8e44ad'>&#9645;</span> polygons");
  if ((DATA.danger || []).length) rows.push("<span style='color:#d4a017'>&#9711;</span> danger areas");
  if ((DATA.uncertain || []).length) rows.push("<span style='color:#8e44ad'>&#9633;</span> uncertain areas (dashed: unknown at take-off)");
  if ((DATA.moving || []).length) rows.push("<span style='color:#e67e22'>&#9679;</span> moving obstacles");
  if (DATA.terrain) rows.push(`terrain ${Math.round(lo[2])}-${Math.round(hi[2])} m${zx > 1 ? `, heights x${zx}` : ""}`);
  rows.push("drag: turn; wheel: zoom");
  document.getElementById("legend").innerHTML = rows.join("<br>");
}

let drag = null, playing = null;
cv.addEventListener("mousedown", (e) => (drag = [e.clientX, e.clientY]));
window.addEventListener("mouseup", () => (drag = null));
window.addEventListener("mousemove", (e) => {
  if (!drag) return;
  yaw += (e.clientX - drag[0]) * 0.01; pitch = Math.min(1.55, Math.max(0, pitch + (e.clientY - drag[1]) * 0.01));
  drag = [e.clientX, e.clientY]; draw();
});
cv.addEventListener("wheel", (e) => { e.preventDefault(); zoom *= e.deltaY < 0 ? 1.1 : 1 / 1.1; draw(); });
slider.addEventListener("input", draw);
window.addEventListener("resize", draw);
document.getElementById("play").addEventListener("click", () => {
  if (playing) { clearInterval(playing); playing = null; return; }
  playing = setInterval(() => { slider.value = (Number(slider.value) + 2) % 1001; draw(); }, 30);
});
legend();
draw();

if (location.hash === "#selftest") {  // the browser test: does the slider move the UAVs?
  slider.value = 0; draw(); const first = window.__shown.map((s) => [s[1], s[2]]);
  slider.value = 1000; draw(); const last = window.__shown.map((s) => [s[1], s[2]]);
  const moved = first.filter((p, k) => Math.hypot(p[0] - last[k][0], p[1] - last[k][1]) > 1).length;
  const out = document.getElementById("selftest");
  out.textContent = JSON.stringify({ uavs: first.length, moved, errors });
}
