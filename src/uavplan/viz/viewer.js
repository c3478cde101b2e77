// uavplan viewer: a plan in WebGL through three.js (the global THREE, vendored; no network).
// DATA (set by the page): bounds, terrain, cylinders, polygons, danger, uncertain, moving, uavs
// (each: id, ok, why, f = flat x,y,z of the flown path, t = its times, p = the planned path,
// len, m = its margins).
"use strict";
const errors = [];
window.addEventListener("error", (e) => errors.push(String(e.message)));
const consoleError = console.error.bind(console);
console.error = (...args) => { errors.push(args.map(String).join(" ")); consoleError(...args); };
const $ = (id) => document.getElementById(id);
const selftest = ["#selftest", "#fps", "#fps-empty"].includes(location.hash);

// ------------------------------------------------------------------ the world's frame
// Scene coordinates are metres from the map's centre, z up; a flat-looking world (heights under a
// tenth of the map) has its heights stretched, and a 2-D world's obstacles stand as low solids
// with the paths just above them.
const lo = DATA.bounds.lo, hi = DATA.bounds.hi;
const span = Math.max(hi[0] - lo[0], hi[1] - lo[1], 1);
const flat = DATA.dim !== 3;
const zr = Math.max(hi[2] - lo[2], 1e-9);
const zx = flat ? 1 : Math.max(1, Math.round((0.25 * span) / zr));
const lift = flat ? 0.02 * span : 0;
const C = [(lo[0] + hi[0]) / 2, (lo[1] + hi[1]) / 2, flat ? 0 : lo[2]];
const S = (x, y, z) => [x - C[0], y - C[1], flat ? (z || 0) + lift : ((z || 0) - C[2]) * zx];
const zTop = flat ? lift : (hi[2] - C[2]) * zx;
const palette = [0x1f77b4, 0xff7f0e, 0x2ca02c, 0x9467bd, 0x8c564b, 0xe377c2, 0x17becf, 0xbcbd22];
const RED = 0xe00000;
const uavColour = (u, k) => (u.ok === false ? RED : palette[k % palette.length]);
const t0 = Math.min(...DATA.uavs.map((u) => u.t[0]));
const tEnd = Math.max(t0 + 1e-9, ...DATA.uavs.map((u) => u.t[u.t.length - 1]));

function terrainColour(h, a, b) {  // green lowlands to brown and white heights, as [r, g, b] in 0-1
  const t = Math.min(1, Math.max(0, (h - a) / Math.max(b - a, 1e-9)));
  const stops = [[0, [96, 160, 96]], [0.5, [190, 170, 110]], [0.85, [150, 120, 90]], [1, [245, 245, 245]]];
  let k = 0;
  while (k < stops.length - 2 && t > stops[k + 1][0]) k++;
  const [s0, c0] = stops[k], [s1, c1] = stops[k + 1];
  const f = (t - s0) / (s1 - s0 || 1);
  return c0.map((c, i) => (c + f * (c1[i] - c)) / 255);
}

function groundAt(x, y) {  // the shown terrain's height at (x, y), bilinear; 0 without terrain
  const T = DATA.terrain;
  if (!T) return 0;
  const fx = Math.min(T.nx - 1, Math.max(0, (x - T.x0) / T.dx));
  const fy = Math.min(T.ny - 1, Math.max(0, (y - T.y0) / T.dy));
  const j = Math.min(T.nx - 2, Math.floor(fx)), i = Math.min(T.ny - 2, Math.floor(fy));
  const a = fx - j, b = fy - i, h = (r, c) => T.h[r * T.nx + c];
  return (1 - b) * ((1 - a) * h(i, j) + a * h(i, j + 1)) + b * ((1 - a) * h(i + 1, j) + a * h(i + 1, j + 1));
}

// ------------------------------------------------------------------ renderer, camera, lights
const view = $("view");
THREE.ColorManagement.enabled = false;  // colours as given: sRGB values, drawn as they are
// A software renderer (SwiftShader, llvmpipe: headless browsers, remote desktops, machines
// without a GPU driver) draws at half the frame rate with multisampling, so it draws without.
function softwareRenderer() {
  try {
    const g = document.createElement("canvas").getContext("webgl2");
    const ext = g && g.getExtension("WEBGL_debug_renderer_info");
    const name = ext ? String(g.getParameter(ext.UNMASKED_RENDERER_WEBGL)) : "";
    const lose = g && g.getExtension("WEBGL_lose_context");
    if (lose) lose.loseContext();
    return /swiftshader|llvmpipe|softpipe|software|basic render/i.test(name);
  } catch (e) {
    return false;
  }
}
const software = softwareRenderer();
let renderer = null;
try {
  renderer = new THREE.WebGLRenderer({ antialias: !software, preserveDrawingBuffer: false });
} catch (e) {
  renderer = null;
}
if (!renderer) {
  errors.length = 0;  // three's own message says the same as ours
  view.innerHTML = "<p id='webgl'>This viewer draws with WebGL, which this browser does not offer here " +
    "(enable hardware acceleration, or open the page in another browser). plan.png shows the plan.</p>";
  if (selftest) $("selftest").textContent = JSON.stringify({ webgl: false, errors });
  throw new Error("no WebGL");
}
renderer.outputColorSpace = THREE.LinearSRGBColorSpace;
renderer.setPixelRatio(software ? 1 : Math.min(2, window.devicePixelRatio || 1));
view.appendChild(renderer.domElement);
// Two scenes: `scene` holds what stands still while the fleet plays (terrain, obstacles, areas,
// every path) and is drawn into a texture only when the camera or the selection changes; `live`
// holds what moves (markers, trails, moving obstacles) and is drawn every frame over a copy of
// that texture, its depth included, so the terrain still hides what is behind it.
const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf4f6f8);
const live = new THREE.Scene();
const camera = new THREE.PerspectiveCamera(45, 1, span * 1e-3, span * 20);
camera.up.set(0, 0, 1);
if (flat) camera.position.set(0, -0.02 * span, 1.25 * span);
else camera.position.set(-0.55 * span, -0.95 * span, zTop + 0.55 * span);
const controls = new THREE.OrbitControls(camera, renderer.domElement);
controls.target.set(0, 0, flat ? lift : 0.3 * zTop);
controls.maxPolarAngle = flat ? 0.45 * Math.PI : 0.49 * Math.PI;
// Lighting: a sky light and a sun fixed in the world. Diffuse light does not depend on where the
// camera is, so it is computed once per vertex here and drawn as vertex colours (a software
// renderer then draws the terrain at several times the frame rate of per-pixel lighting).
const SUN = new THREE.Vector3(-0.6, -0.4, 1.0).normalize();
function shade(geometry, base) {  // base: [r, g, b] sRGB 0-1, or per vertex (a function of k)
  geometry.computeVertexNormals();
  const n = geometry.attributes.normal, out = new Float32Array(3 * n.count);
  for (let k = 0; k < n.count; k++) {
    const nz = n.getZ(k), d = Math.max(0, n.getX(k) * SUN.x + n.getY(k) * SUN.y + nz * SUN.z);
    const light = 0.42 + 0.16 * (0.5 + 0.5 * nz) + 0.55 * d;
    const c = typeof base === "function" ? base(k) : base;
    for (let i = 0; i < 3; i++) out[3 * k + i] = Math.min(1, c[i] * light);
  }
  geometry.setAttribute("color", new THREE.BufferAttribute(out, 3));
  return geometry;
}
const rgb = (hex) => [(hex >> 16) / 255, ((hex >> 8) & 255) / 255, (hex & 255) / 255];
const solid = (opacity) => new THREE.MeshBasicMaterial({
  // translucent solids hide nothing behind them (a UAV behind a cylinder shows through it)
  vertexColors: true, transparent: opacity < 1, opacity, side: THREE.DoubleSide, depthWrite: opacity >= 1,
});
const lineOf = (pts, colour, opacity, dashed) => {  // pts: [x, y, z] in the world's frame
  const g = new THREE.BufferGeometry().setAttribute("position",
    new THREE.Float32BufferAttribute(pts.flatMap((p) => S(p[0], p[1], p[2])), 3));
  const m = dashed
    ? new THREE.LineDashedMaterial({ color: colour, dashSize: span / 120, gapSize: span / 160, transparent: opacity < 1, opacity })
    : new THREE.LineBasicMaterial({ color: colour, transparent: opacity < 1, opacity });
  const l = new THREE.Line(g, m);
  if (dashed) l.computeLineDistances();
  scene.add(l);
  return l;
};
const ring = (c, r, n) => Array.from({ length: n + 1 }, (_, k) => {
  const a = (2 * Math.PI * k) / n;
  return [c[0] + r * Math.cos(a), c[1] + r * Math.sin(a)];
});
const onGround = (pts, up) => pts.map((p) => [p[0], p[1], groundAt(p[0], p[1]) + (up || 0)]);
const densify = (pts, step) => {  // points every `step` metres along a closed outline
  const out = [];
  for (let k = 0; k + 1 < pts.length; k++) {
    const n = Math.max(1, Math.ceil(Math.hypot(pts[k + 1][0] - pts[k][0], pts[k + 1][1] - pts[k][1]) / step));
    for (let i = 0; i < n; i++) out.push([pts[k][0] + (i / n) * (pts[k + 1][0] - pts[k][0]), pts[k][1] + (i / n) * (pts[k + 1][1] - pts[k][1])]);
  }
  out.push(pts[pts.length - 1]);
  return out;
};
const column = (outline, z0, z1, colour, opacity) => {  // a solid from z0 to z1 over an outline
  const shape = new THREE.Shape(outline.map((p) => new THREE.Vector2(p[0] - C[0], p[1] - C[1])));
  const a = S(0, 0, z0)[2], b = S(0, 0, z1)[2];
  const g = new THREE.ExtrudeGeometry(shape, { depth: Math.max(b - a, 1e-6), bevelEnabled: false, curveSegments: 48 });
  const mesh = new THREE.Mesh(shade(g, rgb(colour)), solid(opacity));
  mesh.position.z = a;
  scene.add(mesh);
  return mesh;
};

// ------------------------------------------------------------------ terrain
const T = DATA.terrain;
if (T) {
  let a = Infinity, b = -Infinity;
  for (const h of T.h) { a = Math.min(a, h); b = Math.max(b, h); }
  const pos = new Float32Array(T.nx * T.ny * 3), col = new Float32Array(T.nx * T.ny * 3);
  for (let i = 0; i < T.ny; i++) {
    for (let j = 0; j < T.nx; j++) {
      const k = i * T.nx + j;
      pos.set(S(T.x0 + j * T.dx, T.y0 + i * T.dy, T.h[k]), 3 * k);
      col.set(terrainColour(T.h[k], a, b), 3 * k);
    }
  }
  const index = [];
  for (let i = 0; i + 1 < T.ny; i++) {
    for (let j = 0; j + 1 < T.nx; j++) {
      const k = i * T.nx + j;
      index.push(k, k + 1, k + T.nx + 1, k, k + T.nx + 1, k + T.nx);
    }
  }
  const g = new THREE.BufferGeometry();
  g.setAttribute("position", new THREE.BufferAttribute(pos, 3));
  g.setIndex(index);
  shade(g, (k) => col.subarray(3 * k, 3 * k + 3));
  scene.add(new THREE.Mesh(g, solid(1)));
} else {  // a ground plane under the bounds
  const g = new THREE.CircleGeometry(0.75 * span, 4);
  g.rotateZ(Math.PI / 4);
  const m = new THREE.Mesh(shade(g, rgb(0xe4e8e0)), solid(1));
  m.position.z = (flat ? 0 : S(0, 0, lo[2])[2]) - 1e-3 * span;  // under the obstacles' feet
  scene.add(m);
}

// ------------------------------------------------------------------ obstacles and areas
const cylinders = DATA.cylinders || [];
if (cylinders.length) {
  const g = new THREE.CylinderGeometry(1, 1, 1, 48, 1);
  g.rotateX(Math.PI / 2);
  const mesh = new THREE.InstancedMesh(shade(g, rgb(0x8d939c)), solid(0.75), cylinders.length);
  const M = new THREE.Matrix4();
  cylinders.forEach((c, k) => {
    const z0 = flat ? 0 : c.z[0], z1 = flat ? 0 : c.z[1];
    const a = flat ? 0 : S(0, 0, z0)[2], b = flat ? lift : S(0, 0, z1)[2];
    M.makeScale(c.r, c.r, Math.max(b - a, 1e-6)).setPosition(c.c[0] - C[0], c.c[1] - C[1], (a + b) / 2);
    mesh.setMatrixAt(k, M);
  });
  scene.add(mesh);
}
const obstacleZ = (z) => (flat ? [-lift, 0] : z);  // S() lifts 2-D heights by `lift`
for (const P of DATA.polygons || []) column([...P.v, P.v[0]], ...obstacleZ(P.z), 0x8e44ad, 0.8);
const airTop = flat ? 0 : hi[2];
for (const d of DATA.danger || []) {
  const r = ring(d.c, d.r, 64);
  column(r, flat ? -lift : lo[2], airTop, 0xd4a017, 0.16);
  lineOf(onGround(r, 0.002 * zr), 0xb8860b, 1);
}
for (const u of DATA.uncertain || []) {
  const v = [...u.v, u.v[0]];
  column(v, flat ? -lift : lo[2], airTop, 0x8e44ad, u.known ? 0.16 : 0.08);
  lineOf(onGround(densify(v, span / 100), 0.002 * zr), 0x8e44ad, 1, !u.known);
}
const movers = (DATA.moving || []).map((m) => {
  const mesh = new THREE.Mesh(shade(new THREE.SphereGeometry(1, 24, 16), rgb(0xe67e22)), solid(0.6));
  mesh.scale.set(m.r, m.r, flat ? m.r : m.r * zx);
  live.add(mesh);
  lineOf(m.p, 0xe67e22, 0.35);
  return { m, mesh, p: m.p.flat() };
});

// ------------------------------------------------------------------ paths and markers
// All flown paths are one draw call in `scene` (each vertex knows its UAV, so a selection dims
// the others); the trails (the last `trail` seconds of every flight) are one in `live`.
const nSeg = DATA.uavs.reduce((s, u) => s + u.t.length - 1, 0);
const pathPos = new Float32Array(6 * nSeg), pathRgb = new Float32Array(6 * nSeg), pathId = new Float32Array(2 * nSeg);
const scenePts = DATA.uavs.map((u) => {  // each UAV's path in scene coordinates
  const out = new Float32Array(u.f.length);
  for (let i = 0; i < u.f.length; i += 3) out.set(S(u.f[i], u.f[i + 1], u.f[i + 2]), i);
  return out;
});
const planned = [];
const colour = new THREE.Color();
const rgbOf = DATA.uavs.map((u, k) => { colour.setHex(uavColour(u, k)); return [colour.r, colour.g, colour.b]; });
let v = 0;
DATA.uavs.forEach((u, k) => {
  const P = scenePts[k];
  for (let i = 0; i + 1 < u.t.length; i++) {
    pathPos.set(P.subarray(3 * i, 3 * i + 6), 3 * v);
    pathRgb.set(rgbOf[k], 3 * v); pathRgb.set(rgbOf[k], 3 * v + 3);
    pathId[v] = pathId[v + 1] = k;
    v += 2;
  }
  for (let i = 0; i + 3 < u.p.length; i += 3) {
    planned.push(...S(u.p[i], u.p[i + 1], u.p[i + 2]), ...S(u.p[i + 3], u.p[i + 4], u.p[i + 5]));
  }
});
const lineShader = (alpha) => new THREE.ShaderMaterial({
  uniforms: { sel: { value: -1 } },
  vertexShader: `attribute vec3 rgb; attribute float uid; uniform float sel; varying vec3 vc; varying float va;
    void main() {
      vc = rgb;
      va = sel < 0.0 ? ${alpha} : (abs(uid - sel) > 0.5 ? ${alpha} * 0.15 : 1.0);
      gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0);
    }`,
  fragmentShader: `varying vec3 vc; varying float va;
    void main() { gl_FragColor = vec4(vc, va);
    }`,
  transparent: true, depthWrite: false,
});
const pathGeo = new THREE.BufferGeometry();
pathGeo.setAttribute("position", new THREE.BufferAttribute(pathPos, 3));
pathGeo.setAttribute("rgb", new THREE.BufferAttribute(pathRgb, 3));
pathGeo.setAttribute("uid", new THREE.BufferAttribute(pathId, 1));
const pathMat = lineShader(DATA.uavs.length <= 100 ? "0.8" : "0.45");
scene.add(new THREE.LineSegments(pathGeo, pathMat));
const trail = 0.06 * (tEnd - t0);
const trailPos = new Float32Array(6 * nSeg + 6 * DATA.uavs.length), trailRgb = new Float32Array(trailPos.length);
const trailId = new Float32Array(trailPos.length / 3);
const trailGeo = new THREE.BufferGeometry();
trailGeo.setAttribute("position", new THREE.BufferAttribute(trailPos, 3).setUsage(THREE.DynamicDrawUsage));
trailGeo.setAttribute("rgb", new THREE.BufferAttribute(trailRgb, 3).setUsage(THREE.DynamicDrawUsage));
trailGeo.setAttribute("uid", new THREE.BufferAttribute(trailId, 1).setUsage(THREE.DynamicDrawUsage));
const trailMat = lineShader("1.0");
const trails = new THREE.LineSegments(trailGeo, trailMat);
trails.frustumCulled = false;
live.add(trails);
const plannedGeo = new THREE.BufferGeometry().setAttribute("position", new THREE.Float32BufferAttribute(planned, 3));
const plannedLines = new THREE.LineSegments(plannedGeo, new THREE.LineDashedMaterial({
  color: 0x666666, dashSize: span / 150, gapSize: span / 150, transparent: true, opacity: 0.7,
}));
plannedLines.computeLineDistances();
plannedLines.visible = $("planned").checked = DATA.uavs.length <= 10;
scene.add(plannedLines);

const nU = DATA.uavs.length;
const markPos = new Float32Array(3 * nU), markRgb = new Float32Array(3 * nU), markAir = new Float32Array(nU);
DATA.uavs.forEach((u, k) => markRgb.set(rgbOf[k], 3 * k));
const markGeo = new THREE.BufferGeometry();
markGeo.setAttribute("position", new THREE.BufferAttribute(markPos, 3).setUsage(THREE.DynamicDrawUsage));
markGeo.setAttribute("rgb", new THREE.BufferAttribute(markRgb, 3));
markGeo.setAttribute("air", new THREE.BufferAttribute(markAir, 1).setUsage(THREE.DynamicDrawUsage));
const markMat = new THREE.ShaderMaterial({
  uniforms: { size: { value: (nU > 100 ? 7 : 10) * renderer.getPixelRatio() } },
  vertexShader: `attribute vec3 rgb; attribute float air; uniform float size; varying vec3 vc;
    void main() { vc = rgb; gl_PointSize = air > 0.5 ? size : 0.6 * size;  // on the ground: smaller
      gl_Position = projectionMatrix * modelViewMatrix * vec4(position, 1.0); }`,
  fragmentShader: `varying vec3 vc; void main() {
      float r = length(gl_PointCoord - vec2(0.5));
      if (r > 0.5) discard;
      gl_FragColor = r > 0.34 ? vec4(0.05, 0.05, 0.05, 1.0) : vec4(vc, 1.0);
      }`,
});
const markers = new THREE.Points(markGeo, markMat);
markers.frustumCulled = false;
live.add(markers);

// ------------------------------------------------------------------ time, drawing, overlays
const slider = $("time"), clock = $("clock");
let now = t0, pending = false, playing = false, lastFrame = 0;
const tmp = [0, 0, 0];
function locate(times, t) {  // [a, f]: t lies between times[a] and times[a + 1] at fraction f
  const n = times.length - 1;
  if (t >= times[n]) return [n, 0];
  if (t <= times[0]) return [0, 0];
  let a = 0, b = n;
  while (b - a > 1) { const m = (a + b) >> 1; if (times[m] <= t) a = m; else b = m; }
  return [a, (t - times[a]) / (times[a + 1] - times[a] || 1)];
}
function pointAt(P, a, f, out, o) {  // P: flat x, y, z; the point f of the way from a to a + 1
  for (let i = 0; i < 3; i++) out[o + i] = f > 0 ? P[3 * a + i] + f * (P[3 * a + 3 + i] - P[3 * a + i]) : P[3 * a + i];
}
function setTime(t) {
  now = t;
  let nv = 0;
  DATA.uavs.forEach((u, k) => {
    const P = scenePts[k], [a, f] = locate(u.t, t);
    pointAt(P, a, f, markPos, 3 * k);
    markAir[k] = t > u.t[0] && t < u.t[u.t.length - 1] ? 1 : 0;
    if (t <= u.t[0]) return;  // not in the air yet: no trail
    let [pa, pf] = locate(u.t, t - trail);
    const seg = (qa, qf) => {
      for (const [ia, fa] of [[pa, pf], [qa, qf]]) {
        pointAt(P, ia, fa, trailPos, 3 * nv);
        trailRgb.set(rgbOf[k], 3 * nv);
        trailId[nv++] = k;
      }
      pa = qa; pf = qf;
    };
    for (let i = pa + 1; i <= a; i++) seg(i, 0);
    if (f > 0) seg(a, f);
  });
  for (const name of ["position", "rgb", "uid"]) {
    const attr = trailGeo.attributes[name];
    attr.clearUpdateRanges();
    attr.addUpdateRange(0, nv * attr.itemSize);
    attr.needsUpdate = true;
  }
  trailGeo.setDrawRange(0, nv);
  markGeo.attributes.position.needsUpdate = markGeo.attributes.air.needsUpdate = true;
  for (const o of movers) {
    const [a, f] = locate(o.m.t, t);
    pointAt(o.p, a, f, tmp, 0);
    const s = S(tmp[0], tmp[1], tmp[2]);
    o.mesh.position.set(s[0], s[1], s[2]);
  }
  clock.textContent = `t = ${t.toFixed(1)} s of ${tEnd.toFixed(1)} s`;
}
const toScreen = (p) => {  // scene point -> CSS pixels in the view
  const q = new THREE.Vector3(p[0], p[1], p[2]).project(camera);
  const r = renderer.domElement.getBoundingClientRect();
  return [(q.x + 1) / 2 * r.width, (1 - q.y) / 2 * r.height, q.z];
};
function markerScreen() {
  const out = [];
  for (let k = 0; k < nU; k++) out.push(toScreen([markPos[3 * k], markPos[3 * k + 1], markPos[3 * k + 2]]));
  return out;
}
const niceLength = (m) => {
  const p = 10 ** Math.floor(Math.log10(m));
  return [5, 2, 1].map((f) => f * p).find((x) => x <= m) || p;
};
function overlays() {
  // the scale bar: metres per pixel at the centre of the view, along the screen's horizontal
  const c = controls.target, right = new THREE.Vector3().setFromMatrixColumn(camera.matrixWorld, 0);
  const a = toScreen([c.x, c.y, c.z]), d = span / 10;
  const b = toScreen([c.x + right.x * d, c.y + right.y * d, c.z + right.z * d]);
  const mpp = d / Math.max(1e-9, Math.hypot(b[0] - a[0], b[1] - a[1]));
  const L = niceLength(110 * mpp);
  $("scalebar").style.width = `${(L / mpp).toFixed(0)}px`;
  $("scaletext").textContent = `${L >= 1000 ? `${L / 1000} km` : `${L} m`} at the centre of view`;
  const n = toScreen([c.x, c.y + d, c.z]);  // north: +y in the world's frame
  $("north").style.transform = `rotate(${Math.atan2(n[0] - a[0], a[1] - n[1])}rad)`;
  const box = $("labelbox");
  if ($("labels").checked) {
    const pts = markerScreen();
    box.innerHTML = DATA.uavs.map((u, k) => `<span class='lab' style='left:${(pts[k][0] + 7).toFixed(0)}px;` +
      `top:${(pts[k][1] - 16).toFixed(0)}px'>${esc(u.id)}</span>`).join("");
  } else box.innerHTML = "";
}
// On a software renderer, what stands still is drawn into an off-screen buffer only when the
// camera or the selection changes, and each frame copies it (colour and depth, so the terrain
// still hides what is behind it) and draws `live` over it. A GPU draws everything every frame.
let target = null, staticDirty = true, cache = software;
const gl = renderer.getContext();
function render() {
  controls.update();
  if (cache && staticDirty) {
    renderer.setRenderTarget(target);
    renderer.render(scene, camera);
    renderer.setRenderTarget(null);
    staticDirty = false;
  }
  if (cache) {
    gl.bindFramebuffer(gl.READ_FRAMEBUFFER, renderer.properties.get(target).__webglFramebuffer);
    gl.bindFramebuffer(gl.DRAW_FRAMEBUFFER, null);
    gl.blitFramebuffer(0, 0, target.width, target.height, 0, 0, target.width, target.height,
      gl.COLOR_BUFFER_BIT | gl.DEPTH_BUFFER_BIT, gl.NEAREST);
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    if (gl.getError() !== gl.NO_ERROR) { cache = false; return render(); }  // draw it all then
  } else renderer.render(scene, camera);
  renderer.autoClear = false;
  renderer.render(live, camera);
  renderer.autoClear = true;
  overlays();
}
function requestDraw() {
  if (pending) return;
  pending = true;
  requestAnimationFrame(() => { pending = false; render(); });
}
function resize() {
  const w = view.clientWidth || window.innerWidth, h = view.clientHeight || window.innerHeight - 41;
  renderer.setSize(w, h);
  const pr = renderer.getPixelRatio(), W = Math.round(w * pr), H = Math.round(h * pr);
  if (target) target.dispose();
  // with a stencil buffer, its depth buffer has the format of the page's (needed by the copy)
  target = new THREE.WebGLRenderTarget(W, H, { stencilBuffer: true });
  staticDirty = true;
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
  requestDraw();
}
const esc = (s) => String(s).replace(/[&<>]/g, (c) => ({ "&": "&amp;", "<": "&lt;", ">": "&gt;" }[c]));

// ------------------------------------------------------------------ legend and the UAV card
function legend() {
  const bad = DATA.uavs.map((u, k) => [u, k]).filter(([u]) => u.ok === false);
  const ex = DATA.execution;
  const rows = [
    `<b>${esc(DATA.name)}</b>: ${nU} UAV${nU === 1 ? "" : "s"}`,
    DATA.feasible === true ? "<span class='good'>verified as flown</span>" : DATA.rejected
      ? "<span class='bad'>REJECTED by the independent verifier: do not fly this plan</span>"
      : "<span class='bad'>NOT FLYABLE: do not fly this plan</span>",
  ];
  const exact = ex && !ex.takeoff_s && !ex.speed && !ex.track_h && !ex.track_v;
  if (exact) rows.push("execution model: nominal (flown exactly as planned)");
  else if (ex) rows.push(`execution model: take-off ±${ex.takeoff_s} s, speed ±${trim((100 * ex.speed).toFixed(3))} %, tracking ${ex.track_h} m / ${ex.track_v} m`);
  rows.push(`lines: flown paths; bright: each UAV's last ${trail.toFixed(0)} s`);
  if (bad.length) {
    rows.push(`<span class='bad'>${bad.length} UAV(s) failing a check</span>: ` +
      bad.slice(0, 12).map(([u, k]) => `<a data-k='${k}'>${esc(u.id)}</a>`).join(", ") + (bad.length > 12 ? " ..." : ""));
  }
  if (cylinders.length) rows.push("<span style='color:#8d939c'>&#9632;</span> cylinders / circles");
  if ((DATA.polygons || []).length) rows.push("<span style='color:#8e44ad'>&#9632;</span> polygons");
  if ((DATA.danger || []).length) rows.push("<span style='color:#d4a017'>&#9632;</span> danger areas");
  if ((DATA.uncertain || []).length) rows.push("<span style='color:#8e44ad'>&#9633;</span> uncertain areas (dashed: unknown at take-off)");
  if (movers.length) rows.push("<span style='color:#e67e22'>&#9679;</span> moving obstacles");
  if (T) rows.push(`terrain ${Math.round(Math.min(...T.h))}-${Math.round(Math.max(...T.h))} m${zx > 1 ? `, heights x${zx}` : ""}`);
  rows.push("small markers: on the ground (before take-off, after landing)");
  rows.push("drag: turn; right-drag: move; wheel: zoom; click a UAV");
  $("legend").innerHTML = rows.join("<br>");
  for (const a of $("legend").querySelectorAll("a[data-k]")) a.addEventListener("click", () => select(Number(a.dataset.k)));
}
const trim = (t) => (t.includes(".") && !t.includes("e") ? t.replace(/0+$/, "").replace(/\.$/, "") : t);
const num = (x, unit, scale) => {
  const v = x * (scale || 1);
  return `±${Math.abs(v) >= 1000 ? String(Math.round(v)) : trim(v.toPrecision(3))} ${unit}`;
};
const limit = (x, unit, scale) => (x === null || x === undefined ? "any" : num(x, unit, scale));
function select(k) {
  pathMat.uniforms.sel.value = trailMat.uniforms.sel.value = k;
  staticDirty = true;
  const card = $("info");
  if (k < 0) { card.style.display = "none"; requestDraw(); return; }
  const u = DATA.uavs[k];
  const verdict = u.ok === true ? "<span class='good'>verified as flown</span>"
    : u.ok === false ? `<span class='bad'>fails</span>: ${esc(u.why.join("; ") || "a check")}` : "not checked";
  const rows = [`<b>${esc(u.id)}</b>: ${verdict}`,
    `flies t = ${u.t[0].toFixed(1)} to ${u.t[u.t.length - 1].toFixed(1)} s, ${(u.len / 1000).toFixed(2)} km`];
  if (u.m) {
    const by = (w) => (u.m.limited_by && u.m.limited_by[w] ? ` (by ${esc(u.m.limited_by[w])})` : "");
    rows.push("margins it tolerates:",
      `&nbsp; take-off error: ${limit(u.m.takeoff_s, "s")}${by("takeoff_s")}`,
      `&nbsp; speed error: ${limit(u.m.speed, "%", 100)}${by("speed")}`,
      `&nbsp; tracking: ${limit(u.m.track_h, "m")} horizontal${by("track_h")}, ${limit(u.m.track_v, "m")} vertical${by("track_v")}`);
  }
  rows.push("<a id='unselect' style='cursor:pointer;color:#06c'>close</a>");
  card.innerHTML = rows.join("<br>");
  card.style.display = "block";
  $("unselect").addEventListener("click", () => select(-1));
  requestDraw();
}
function pick(x, y) {  // the UAV whose marker is nearest (x, y) within 12 px, else -1
  const pts = markerScreen();
  let best = -1, dist = 12;
  pts.forEach((p, k) => { const d = Math.hypot(p[0] - x, p[1] - y); if (p[2] < 1 && d < dist) { dist = d; best = k; } });
  return best;
}

// ------------------------------------------------------------------ events
let down = null;
renderer.domElement.addEventListener("pointerdown", (e) => (down = [e.clientX, e.clientY]));
renderer.domElement.addEventListener("pointerup", (e) => {
  if (down && Math.hypot(e.clientX - down[0], e.clientY - down[1]) < 4) {
    const r = renderer.domElement.getBoundingClientRect();
    select(pick(e.clientX - r.left, e.clientY - r.top));
  }
  down = null;
});
controls.addEventListener("change", () => { staticDirty = true; requestDraw(); });
slider.addEventListener("input", () => { setTime(t0 + (slider.value / 1000) * (tEnd - t0)); requestDraw(); });
$("planned").addEventListener("change", () => { plannedLines.visible = $("planned").checked; staticDirty = true; requestDraw(); });
$("labels").checked = nU <= 20;
$("labels").addEventListener("change", requestDraw);
window.addEventListener("resize", resize);
function tick(ms) {  // playing: the whole flight in about 20 s
  if (!playing) return;
  const dt = lastFrame ? (ms - lastFrame) / 1000 : 0;
  lastFrame = ms;
  let t = now + dt * (tEnd - t0) / 20;
  if (t > tEnd) t = t0;
  setTime(t);
  slider.value = Math.round((1000 * (t - t0)) / (tEnd - t0));
  render();
  requestAnimationFrame(tick);
}
$("play").addEventListener("click", () => {
  playing = !playing;
  $("play").textContent = playing ? "pause" : "play";
  lastFrame = 0;
  if (playing) requestAnimationFrame(tick);
});
legend();
setTime(t0);
resize();
// a view to share: page.html#t=120&uav=uav7 opens at 120 s with uav7's card
const opened = new URLSearchParams(location.hash.slice(1));
if (!selftest && opened.has("t")) {
  const t = Math.min(tEnd, Math.max(t0, Number(opened.get("t")) || t0));
  setTime(t);
  slider.value = Math.round((1000 * (t - t0)) / (tEnd - t0));
}
if (!selftest && opened.has("uav")) select(DATA.uavs.findIndex((u) => u.id === opened.get("uav")));
render();

// ------------------------------------------------------------------ the browser tests
if (selftest) {
  // gl: the renderer's context (above)
  const canvas = renderer.domElement, w = canvas.width, h = canvas.height;
  const bg = [244, 246, 248];
  const painted = () => {  // the share of pixels not the background's, and the red ones
    const px = new Uint8Array(4 * w * h);
    gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, px);
    let n = 0, red = 0;
    for (let i = 0; i < px.length; i += 4) {
      if (Math.abs(px[i] - bg[0]) + Math.abs(px[i + 1] - bg[1]) + Math.abs(px[i + 2] - bg[2]) > 12) n++;
      if (px[i] > 170 && px[i + 1] < 70 && px[i + 2] < 70) red++;
    }
    return [n / (w * h), red];
  };
  const result = { webgl: !!gl && !gl.isContextLost(), uavs: nU, size: [w, h] };
  result.ready_ms = Math.round(performance.now());  // from navigation to the first frame drawn
  setTime(t0); render();
  const first = markerScreen();
  const [share, red] = painted();
  result.painted = Math.round(1000 * share) / 1000;
  result.red = red;  // failing UAVs' markers and paths (#e00000)
  setTime(tEnd); render();
  const last = markerScreen();
  result.moved = first.filter((p, k) => Math.hypot(p[0] - last[k][0], p[1] - last[k][1]) > 1).length;
  // a click on the last UAV's marker opens its card (the pick that a click runs)
  const k = pick(last[nU - 1][0], last[nU - 1][1]);
  select(k);
  result.picked = k >= 0 && $("info").style.display === "block" ? $("info").textContent.split(":")[0] : null;
  select(-1);
  // play: two frames half a second apart move the clock and the slider
  setTime(t0); slider.value = 0;
  playing = true; lastFrame = 0;
  tick(1000); tick(1500);
  playing = false;
  result.played = now > t0 && Number(slider.value) > 0;
  if (location.hash.startsWith("#fps")) {  // frames drawn per second while playing (each frame finished)
    if (location.hash === "#fps-empty") scene.visible = live.visible = false;  // the reference
    const px = new Uint8Array(4);
    const n = 40;
    render(); gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    const start = performance.now();
    for (let i = 0; i < n; i++) {
      setTime(t0 + ((i + 0.5) / n) * (tEnd - t0));
      render();
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    }
    result.fps = Math.round((10 * n * 1000) / (performance.now() - start)) / 10;
    const turn = performance.now();  // turning the camera: everything drawn every frame
    for (let i = 0; i < n; i++) {
      camera.position.applyAxisAngle(new THREE.Vector3(0, 0, 1), 0.01);
      staticDirty = true;
      render();
      gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);
    }
    result.fps_turning = Math.round((10 * n * 1000) / (performance.now() - turn)) / 10;
    const info = renderer.info.render;
    result.draw_calls = info.calls;
    result.vertices = 2 * nSeg + nU;
    result.antialias = !software;
    result.renderer = (gl.getExtension("WEBGL_debug_renderer_info") &&
      gl.getParameter(gl.getExtension("WEBGL_debug_renderer_info").UNMASKED_RENDERER_WEBGL)) || "unknown";
  }
  setTime(t0); render();
  result.errors = errors;
  $("selftest").textContent = JSON.stringify(result);
}
