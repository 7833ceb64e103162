// The viewer of `edmp-host view` (docs/viewer.md). It draws what the page's data says: the
// Rust side computed every link frame's world pose per sample with edmp-core's forward
// kinematics; this script places the meshes at those poses and interpolates between samples.
import * as THREE from "three";
import { OrbitControls } from "three/addons/OrbitControls.js";

const data = JSON.parse(document.getElementById("edmp-data").textContent);
const body = document.body;

/** Shows an error on the page and in `data-error` (read by the tests). */
function fail(message) {
  body.dataset.error = message;
  document.getElementById("error").textContent = message;
}
window.addEventListener("error", (e) => fail(String(e.message)));

// ---- renderer, camera, lights: the world is z up, like the robot's.
THREE.Object3D.DEFAULT_UP.set(0, 0, 1);
let renderer;
try {
  renderer = new THREE.WebGLRenderer({ antialias: true, preserveDrawingBuffer: true });
} catch (e) {
  fail("WebGL is not available in this browser: " + e.message);
  throw e;
}
renderer.setPixelRatio(window.devicePixelRatio);
renderer.setSize(window.innerWidth, window.innerHeight);
document.getElementById("view").appendChild(renderer.domElement);

const scene = new THREE.Scene();
scene.background = new THREE.Color(0xf4f5f7);
const camera = new THREE.PerspectiveCamera(40, window.innerWidth / window.innerHeight, 0.01, 50);
camera.position.set(1.9, -1.7, 1.35);
const controls = new OrbitControls(camera, renderer.domElement);
controls.target.set(0.3, 0, 0.35);
controls.update();

scene.add(new THREE.HemisphereLight(0xffffff, 0x9a9a9a, 2.2));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(1.5, -1.0, 3.0);
scene.add(sun);
const fill = new THREE.DirectionalLight(0xffffff, 0.6);
fill.position.set(-1.5, 1.5, 1.0);
scene.add(fill);

const grid = new THREE.GridHelper(2, 20, 0xb0b4ba, 0xd5d8dc);
grid.rotation.x = Math.PI / 2; // the helper lies in x-z; the floor is x-y
scene.add(grid);
scene.add(new THREE.AxesHelper(0.15));

/** Sets an object's pose from a position and a `[w, x, y, z]` quaternion. */
function place(object, position, wxyz) {
  object.position.set(position[0], position[1], position[2]);
  object.quaternion.set(wxyz[1], wxyz[2], wxyz[3], wxyz[0]);
}

// ---- obstacles: one drawing function per kind (a new kind of obstacle gets one here).
const SHAPES = {
  cuboid: (o) => new THREE.BoxGeometry(o.dims[0], o.dims[1], o.dims[2]),
  // three.js cylinders run along y; the scene's along their local z.
  cylinder: (o) => new THREE.CylinderGeometry(o.radius, o.radius, o.height, 48).rotateX(Math.PI / 2),
  sphere: (o) => new THREE.SphereGeometry(o.radius, 48, 24),
};

function primitive(o, material) {
  const make = SHAPES[o.type];
  if (!make) {
    throw new Error(`obstacles of type ${o.type} cannot be drawn`);
  }
  const mesh = new THREE.Mesh(make(o), material);
  place(mesh, o.position, o.quaternion);
  return mesh;
}

const OBSTACLE_COLOUR = 0xd9822b;
const obstacleMaterial = new THREE.MeshLambertMaterial({ color: OBSTACLE_COLOUR, transparent: true, opacity: 0.8 });
for (const o of data.obstacles) {
  scene.add(primitive(o, obstacleMaterial));
}

/** A little-endian typed array from base64 (how the page holds every binary array). */
function decode(base64, Type) {
  const bytes = Uint8Array.from(atob(base64), (c) => c.charCodeAt(0));
  return new Type(bytes.buffer);
}

// ---- clouds (one dot per kept point, the size of its ball) and meshes (their triangles in
// the obstacles' material, both sides, flat shaded).
const meshMaterial = obstacleMaterial.clone();
meshMaterial.side = THREE.DoubleSide;
meshMaterial.flatShading = true;
// A round dot: a disc in a small texture, the corners cut by the alpha test.
const DISC = 32;
const discPixels = new Uint8Array(4 * DISC * DISC);
for (let k = 0; k < DISC * DISC; k++) {
  const x = (k % DISC) + 0.5 - DISC / 2;
  const y = Math.floor(k / DISC) + 0.5 - DISC / 2;
  discPixels.set([255, 255, 255, x * x + y * y <= (DISC * DISC) / 4 ? 255 : 0], 4 * k);
}
const disc = new THREE.DataTexture(discPixels, DISC, DISC);
disc.needsUpdate = true;
let cloudPoints = 0;
let meshTriangles = 0;
for (const s of data.surfaces) {
  const geometry = new THREE.BufferGeometry();
  if (s.type === "points") {
    geometry.setAttribute("position", new THREE.BufferAttribute(decode(s.points, Float32Array), 3));
    // With size attenuation a point of size S is S * (canvas height / 2) / depth pixels wide;
    // a ball of diameter 2r is 2r / tan(fov / 2) times that.
    const size = (2 * s.radius) / Math.tan(THREE.MathUtils.degToRad(camera.fov / 2));
    const material = new THREE.PointsMaterial({ color: OBSTACLE_COLOUR, size, map: disc, alphaTest: 0.5 });
    scene.add(new THREE.Points(geometry, material));
    cloudPoints += s.drawn;
  } else if (s.type === "mesh") {
    geometry.setAttribute("position", new THREE.BufferAttribute(decode(s.vertices, Float32Array), 3));
    geometry.setIndex(new THREE.BufferAttribute(decode(s.indices, Uint32Array), 1));
    geometry.computeVertexNormals();
    scene.add(new THREE.Mesh(geometry, meshMaterial));
    meshTriangles += s.triangles;
  } else {
    throw new Error(`obstacles of type ${s.type} cannot be drawn`);
  }
}
body.dataset.cloudPoints = String(cloudPoints);
body.dataset.meshTriangles = String(meshTriangles);

// ---- the arm: one group per link frame, posed from the samples; the URDF's visual meshes are
// its children at their visual origins.

const frames = data.frames.map(() => new THREE.Group());
frames.forEach((g) => scene.add(g));
for (const m of data.meshes) {
  const geometry = new THREE.BufferGeometry();
  geometry.setAttribute("position", new THREE.BufferAttribute(decode(m.vertices, Float32Array), 3));
  geometry.setIndex(new THREE.BufferAttribute(decode(m.indices, Uint32Array), 1));
  const materials = m.groups.map((g, k) => {
    geometry.addGroup(g.start, g.count, k);
    const colour = new THREE.Color().setRGB(g.colour[0], g.colour[1], g.colour[2], THREE.SRGBColorSpace);
    return new THREE.MeshStandardMaterial({ color: colour, roughness: 0.55, metalness: 0.05, flatShading: true });
  });
  const mesh = new THREE.Mesh(geometry, materials);
  place(mesh, m.position, m.quaternion);
  mesh.scale.set(m.scale[0], m.scale[1], m.scale[2]);
  frames[m.frame].add(mesh);
}
if (data.held) {
  const held = new THREE.MeshLambertMaterial({ color: 0x3b82c4 });
  frames[data.hand_frame].add(primitive(data.held, held)); // its pose is in the hand frame
}
const tcp = frames[data.tcp_frame];

// ---- paths: the chosen one (the TCP through the samples) and the candidates' (toggle).
function marker(position, colour) {
  const m = new THREE.Mesh(new THREE.SphereGeometry(0.015, 24, 12), new THREE.MeshLambertMaterial({ color: colour }));
  m.position.set(position[0], position[1], position[2]);
  return m;
}
const pathGroup = new THREE.Group();
scene.add(pathGroup);
pathGroup.add(marker(data.start_tcp, 0x2a5bd7));
pathGroup.add(marker(data.goal_tcp, 0x1a9e40));
const points = data.samples.tcp.map((p) => new THREE.Vector3(p[0], p[1], p[2]));
if (points.length > 1) {
  const curve = new THREE.CatmullRomCurve3(points);
  const tube = new THREE.TubeGeometry(curve, Math.min(4 * points.length, 800), 0.004, 8, false);
  pathGroup.add(new THREE.Mesh(tube, new THREE.MeshBasicMaterial({ color: 0x9a0d0d })));
}
// The plan's waypoints: a dot at each one's TCP.
const dots = new THREE.BufferGeometry().setFromPoints(
  data.waypoints_tcp.map((p) => new THREE.Vector3(p[0], p[1], p[2])),
);
pathGroup.add(new THREE.Points(dots, new THREE.PointsMaterial({ color: 0x5c0808, size: 5, sizeAttenuation: false })));
const CANDIDATE_COLOURS = [0x1f77b4, 0x2ca02c, 0x9467bd, 0xe377c2, 0x17becf, 0xbcbd22];
const candidateGroup = new THREE.Group();
candidateGroup.visible = false;
scene.add(candidateGroup);
let free = 0;
for (const c of data.candidates) {
  const colour = c.collision_free ? CANDIDATE_COLOURS[free++ % CANDIDATE_COLOURS.length] : 0x8c8c8c;
  const geometry = new THREE.BufferGeometry().setFromPoints(c.tcp.map((p) => new THREE.Vector3(p[0], p[1], p[2])));
  candidateGroup.add(new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: colour })));
}

// ---- the report: status, stage and timings of the plan.
document.getElementById("title").textContent = data.title;
const info = data.info;
const summary = document.getElementById("summary");
if (info.status) {
  const status = document.createElement("span");
  status.className = info.status;
  status.textContent = info.status;
  summary.append(status);
  const motion = info.timed ? "timed trajectory" : "untimed, played evenly";
  summary.append(` · ${info.stage ?? "?"} · ${info.waypoints} waypoints · ${motion}`);
} else {
  summary.textContent = "scene only (no plan): the arm at the start";
}
const timings = document.getElementById("timings");
const order = info.timing_ms.map((r) => r[0]).sort((a, b) => (a === "total") - (b === "total"));
for (const name of order) {
  const ms = info.timing_ms.find((r) => r[0] === name)[1];
  const row = timings.insertRow();
  row.insertCell().textContent = name;
  const cell = row.insertCell();
  cell.className = "ms";
  cell.textContent = `${ms.toFixed(1)} ms`;
}
summary.append(` · ${data.obstacles.length} obstacle${data.obstacles.length === 1 ? "" : "s"}`);
for (const kind of ["points", "mesh"]) {
  const list = data.surfaces.filter((s) => s.type === kind);
  if (list.length === 0) continue;
  const many = list.length > 1;
  if (kind === "mesh") {
    const triangles = list.reduce((n, s) => n + s.triangles, 0);
    summary.append(` · ${list.length} mesh${many ? "es" : ""} (${triangles} triangles)`);
  } else {
    const count = list.reduce((n, s) => n + s.count, 0);
    const drawn = list.reduce((n, s) => n + s.drawn, 0);
    const points = drawn < count ? `${drawn} of ${count} points drawn` : `${count} points`;
    summary.append(` · ${list.length} cloud${many ? "s" : ""} (${points})`);
  }
}

// ---- time: pose every frame at time t (seconds), interpolating between samples.
const times = data.samples.times;
const poses = data.samples.poses;
const duration = times[times.length - 1];
const slider = document.getElementById("slider");
const timeLabel = document.getElementById("time");
const playButton = document.getElementById("play");
const qa = new THREE.Quaternion();
const qb = new THREE.Quaternion();
let t = 0;
let playing = duration > 0;
let lastTick = null;

/** Index k of the sample at or before time s (times ascending). */
function sampleBefore(s) {
  let lo = 0;
  let hi = times.length - 1;
  while (hi - lo > 1) {
    const mid = (lo + hi) >> 1;
    if (times[mid] <= s) lo = mid;
    else hi = mid;
  }
  return lo;
}

function setTime(seconds) {
  t = Math.min(Math.max(seconds, 0), duration);
  const k = sampleBefore(t);
  const next = Math.min(k + 1, times.length - 1);
  const span = times[next] - times[k];
  const s = span > 0 ? Math.min(Math.max((t - times[k]) / span, 0), 1) : 0;
  const a = poses[k];
  const b = poses[next];
  frames.forEach((group, i) => {
    const o = 7 * i;
    group.position.set(
      a[o] + s * (b[o] - a[o]),
      a[o + 1] + s * (b[o + 1] - a[o + 1]),
      a[o + 2] + s * (b[o + 2] - a[o + 2]),
    );
    qa.set(a[o + 4], a[o + 5], a[o + 6], a[o + 3]);
    qb.set(b[o + 4], b[o + 5], b[o + 6], b[o + 3]);
    group.quaternion.slerpQuaternions(qa, qb, s);
  });
  slider.value = duration > 0 ? Math.round((1000 * t) / duration) : 0;
  timeLabel.textContent = `${t.toFixed(2)} s / ${duration.toFixed(2)} s`;
}

/** Draws, and writes the drawn TCP into the DOM: `data-tcp` (world, m), `data-tcp-px` (pixels). */
function render() {
  scene.updateMatrixWorld();
  renderer.render(scene, camera);
  const p = new THREE.Vector3().setFromMatrixPosition(tcp.matrixWorld);
  body.dataset.t = t.toFixed(6);
  body.dataset.tcp = `${p.x.toFixed(6)} ${p.y.toFixed(6)} ${p.z.toFixed(6)}`;
  const ndc = p.clone().project(camera);
  const u = ((ndc.x + 1) / 2) * window.innerWidth;
  const v = ((1 - ndc.y) / 2) * window.innerHeight;
  body.dataset.tcpPx = `${u.toFixed(1)} ${v.toFixed(1)}`;
}

function setPlaying(on) {
  playing = on && duration > 0;
  playButton.textContent = playing ? "Pause" : "Play";
  lastTick = null;
  if (playing) requestAnimationFrame(tick);
}

function tick(now) {
  if (!playing) return;
  if (lastTick !== null) {
    const next = t + (now - lastTick) / 1000;
    setTime(next > duration ? 0 : next); // loop
  }
  lastTick = now;
  render();
  requestAnimationFrame(tick);
}

/** `#t=F` (F in [0, 1], a fraction of the duration) pauses at that time. */
function fromHash() {
  const m = /(?:^#|&)t=([0-9.eE+-]+)/.exec(window.location.hash);
  if (!m) return false;
  setPlaying(false);
  setTime(Number(m[1]) * duration);
  render();
  return true;
}

slider.addEventListener("input", () => {
  setPlaying(false);
  setTime((Number(slider.value) / 1000) * duration);
  render();
});
playButton.addEventListener("click", () => setPlaying(!playing));
window.addEventListener("keydown", (e) => {
  if (e.code === "Space" && e.target === document.body) {
    e.preventDefault();
    setPlaying(!playing);
  }
});
const showPath = document.getElementById("show-path");
showPath.addEventListener("change", () => {
  pathGroup.visible = showPath.checked;
  render();
});
const showCandidates = document.getElementById("show-candidates");
showCandidates.disabled = data.candidates.length === 0;
showCandidates.parentElement.title = data.candidates.length
  ? `${data.candidates.length} candidates' TCP paths`
  : "the plan has no candidates (plan with --candidates)";
showCandidates.addEventListener("change", () => {
  candidateGroup.visible = showCandidates.checked;
  render();
});
// A scene without a plan has nothing to play.
playButton.disabled = duration === 0;
slider.disabled = duration === 0;
controls.addEventListener("change", render);
window.addEventListener("hashchange", fromHash);
window.addEventListener("resize", () => {
  camera.aspect = window.innerWidth / window.innerHeight;
  camera.updateProjectionMatrix();
  renderer.setSize(window.innerWidth, window.innerHeight);
  render();
});

setTime(0);
if (!fromHash()) {
  render();
  setPlaying(playing);
}
body.dataset.loadMs = performance.now().toFixed(0);
body.dataset.ready = "1";
