// warpsim's page: draws what the server sends over its WebSocket and sends back the keys held and the mouse.
// The protocol is described in warpsim/viewer/web.py. Everything here is served by warpsim itself (three.js is
// bundled beside this file, with its licence in three.LICENSE): the page fetches nothing from elsewhere.
import * as THREE from "./three.min.js";

const canvas = document.getElementById("view");
const hudText = document.getElementById("hud");
const overlayText = document.getElementById("overlay");
const roleText = document.getElementById("role-text");
const handover = document.getElementById("handover");
const roleBox = document.getElementById("role");

// what a test or benchmark reads: pictures received and drawn, bytes received, the role, the last frame's header,
// the share of the page's pixels drawn (resolution)
const stats = { pictures: 0, drawn: 0, bytes: 0, started: performance.now(), role: "", id: 0, watchers: 0,
                ack: 0, sentSeq: 0, held: [], header: null, closed: "", resolution: 1 };
window.warpsim = stats;

const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: false });
renderer.setPixelRatio(1);
const scene = new THREE.Scene();
scene.background = new THREE.Color(0.6, 0.75, 0.92);
scene.fog = new THREE.Fog(0xdbe8f5, 600, 6000);
const camera = new THREE.PerspectiveCamera(50, 16 / 9, 0.05, 20000);
camera.up.set(0, 0, 1);
scene.add(new THREE.HemisphereLight(0xdfe9ff, 0x6b7052, 0.9));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.set(0.35, -0.25, 0.9);
scene.add(sun);
scene.add(sun.target);

// ------------------------------------------------------------------ the scene, built once from the hello message
let parts = null; // {meshes: [{ids, geometry}], curves: [{chain, geometry}], tubes: [...], spheres: [...]}
let origin = [0, 0, 0];

function decode(text, Type) {
  const bytes = Uint8Array.from(atob(text), (c) => c.charCodeAt(0));
  return new Type(bytes.buffer);
}

function material(rgb, options = {}) {
  return new THREE.MeshLambertMaterial({ color: new THREE.Color(...rgb), side: THREE.DoubleSide, ...options });
}

function build(hello) {
  document.title = hello.title;
  const built = { meshes: [], curves: [], tubes: [], spheres: [] };
  for (const m of hello.meshes) {
    const triangles = decode(m.triangles, Int32Array);
    const local = new Map();
    const ids = [];
    const index = new Uint32Array(triangles.length);
    triangles.forEach((p, k) => {
      if (!local.has(p)) { local.set(p, ids.length); ids.push(p); }
      index[k] = local.get(p);
    });
    const geometry = new THREE.BufferGeometry();
    const position = new THREE.BufferAttribute(new Float32Array(ids.length * 3), 3);
    position.setUsage(THREE.DynamicDrawUsage);
    geometry.setAttribute("position", position);
    geometry.setIndex(new THREE.BufferAttribute(index, 1));
    const mesh = new THREE.Mesh(geometry, material(m.rgb));
    mesh.frustumCulled = false;
    scene.add(mesh);
    built.meshes.push({ ids: Int32Array.from(ids), geometry });
  }
  for (const c of hello.curves) {
    const geometry = new THREE.BufferGeometry();
    const position = new THREE.BufferAttribute(new Float32Array(c.chain.length * 3), 3);
    position.setUsage(THREE.DynamicDrawUsage);
    geometry.setAttribute("position", position);
    const line = new THREE.Line(geometry, new THREE.LineBasicMaterial({ color: new THREE.Color(...c.rgb) }));
    line.frustumCulled = false;
    scene.add(line);
    built.curves.push({ chain: c.chain, geometry });
  }
  const cylinder = new THREE.CylinderGeometry(1, 1, 1, 8);
  cylinder.rotateX(Math.PI / 2); // along z, from -0.5 to 0.5
  for (const t of hello.tubes) {
    const mesh = new THREE.Mesh(cylinder, material(t.rgb));
    mesh.frustumCulled = false;
    scene.add(mesh);
    built.tubes.push({ a: t.a, b: t.b, radius: t.radius, mesh });
  }
  const ball = new THREE.SphereGeometry(1, 12, 8);
  for (const s of hello.spheres) {
    const mesh = new THREE.Mesh(ball, material(s.rgb));
    mesh.scale.setScalar(s.radius);
    mesh.frustumCulled = false;
    scene.add(mesh);
    built.spheres.push({ point: s.point, mesh });
  }
  const t = hello.terrain;
  const terrain = new THREE.BufferGeometry();
  terrain.setAttribute("position", new THREE.BufferAttribute(decode(t.points, Float32Array), 3));
  terrain.setIndex(new THREE.BufferAttribute(new Uint32Array(decode(t.triangles, Int32Array).buffer), 1));
  terrain.computeVertexNormals();
  // the sun does not move: the terrain's light is baked into its colours once, and it is drawn unlit (the
  // cheapest fragment shader: the page must keep its frame rate on a software renderer too)
  const colours = decode(t.colours, Float32Array);
  const normals = terrain.getAttribute("normal").array;
  const s = sun.position.clone().normalize();
  for (let k = 0; k < colours.length; k += 3) {
    const light = 0.35 + 0.65 * Math.abs(normals[k] * s.x + normals[k + 1] * s.y + normals[k + 2] * s.z);
    colours[k] *= light; colours[k + 1] *= light; colours[k + 2] *= light;
  }
  terrain.setAttribute("color", new THREE.BufferAttribute(colours, 3));
  const ground = built.ground = new THREE.Mesh(terrain, new THREE.MeshBasicMaterial({ vertexColors: true, side: THREE.DoubleSide }));
  ground.frustumCulled = false;
  scene.add(ground);
  const keys = hello.keys.map(([k, what]) => `${k.padStart(13)}   ${what}`);
  built.help = keys.join("\n");
  parts = built;
}

// ------------------------------------------------------------------ a picture from one binary frame
const up = new THREE.Vector3(0, 0, 1);
const along = new THREE.Vector3();

function picture(buffer) {
  const view = new DataView(buffer);
  const magic = String.fromCharCode(...new Uint8Array(buffer, 0, 4));
  if (magic !== "WSF1") return;
  const ack = view.getUint32(8, true);
  const n = view.getUint32(12, true);
  const header = JSON.parse(new TextDecoder().decode(new Uint8Array(buffer, 16, n)));
  const points = new Float32Array(buffer, 16 + n, header.count * 3);
  stats.pictures += 1;
  if (header.pilot === stats.id) stats.ack = ack; // each pilot counts its own keys messages
  stats.header = header;
  if (!parts) return;
  // everything is drawn relative to the frame's origin (a float64 on the server): float32 keeps millimetres; the
  // ground, whose points never move, moves by -origin as a whole (JavaScript's matrices are float64)
  origin = header.origin;
  parts.ground.position.set(-origin[0], -origin[1], -origin[2]);
  for (const m of parts.meshes) {
    const p = m.geometry.getAttribute("position");
    const a = p.array;
    for (let k = 0; k < m.ids.length; k++) {
      const i = 3 * m.ids[k];
      a[3 * k] = points[i];
      a[3 * k + 1] = points[i + 1];
      a[3 * k + 2] = points[i + 2];
    }
    p.needsUpdate = true;
    m.geometry.computeVertexNormals();
  }
  for (const c of parts.curves) {
    const p = c.geometry.getAttribute("position");
    c.chain.forEach((i, k) => {
      p.array[3 * k] = points[3 * i];
      p.array[3 * k + 1] = points[3 * i + 1];
      p.array[3 * k + 2] = points[3 * i + 2];
    });
    p.needsUpdate = true;
  }
  for (const t of parts.tubes) {
    const a = new THREE.Vector3(points[3 * t.a], points[3 * t.a + 1], points[3 * t.a + 2]);
    const b = new THREE.Vector3(points[3 * t.b], points[3 * t.b + 1], points[3 * t.b + 2]);
    along.subVectors(b, a);
    const length = along.length();
    t.mesh.position.addVectors(a, b).multiplyScalar(0.5);
    if (length > 1e-9) t.mesh.quaternion.setFromUnitVectors(up, along.divideScalar(length));
    t.mesh.scale.set(t.radius, t.radius, Math.max(length, 1e-6));
  }
  for (const s of parts.spheres) {
    const i = 3 * s.point;
    s.mesh.position.set(points[i], points[i + 1], points[i + 2]);
  }
  const v = header.view;
  camera.position.set(v.eye[0] - origin[0], v.eye[1] - origin[1], v.eye[2] - origin[2]);
  camera.fov = v.fov;
  const reach = Math.hypot(v.target[0] - v.eye[0], v.target[1] - v.eye[1], v.target[2] - v.eye[2]);
  camera.near = Math.max(0.05, reach / 500);
  camera.lookAt(v.target[0] - origin[0], v.target[1] - origin[1], v.target[2] - origin[2]);
  hudText.textContent = header.hud.join("\n");
  overlayText.textContent = header.overlay.join("\n");
  pending = true;
}

// ------------------------------------------------------------------ drawing: once per animation frame with news
let pending = false;
let drawnSize = [0, 0];

function draw() {
  requestAnimationFrame(draw);
  if (!pending) return;
  pending = false;
  const width = canvas.clientWidth, height = canvas.clientHeight;
  if (width !== drawnSize[0] || height !== drawnSize[1]) {
    renderer.setSize(width, height, false);
    drawnSize = [width, height];
  }
  // the view goes below the heads-up panel, so that the panel never covers what the camera frames
  const panel = Math.min(hudText.offsetHeight + 4, height * 0.5);
  const below = Math.max(height - panel, 1);
  camera.aspect = width / below;
  camera.updateProjectionMatrix();
  renderer.setViewport(0, 0, width, below);
  renderer.render(scene, camera);
  stats.drawn += 1;
  adapt();
}
requestAnimationFrame(draw);

// a page on a software renderer (no GPU: SwiftShader, llvmpipe) cannot fill every pixel at the server's rate: when
// it draws fewer than 85 % of the pictures it receives, it draws at a lower resolution (down to 40 % of the side);
// when it keeps up with room to spare for 6 s it goes back up. A hidden tab (the browser stops its drawing) and the
// seconds after a change do not count.
let checked = { at: performance.now(), pictures: 0, drawn: 0, good: 0 };
function resolution(value) {
  stats.resolution = value;
  renderer.setPixelRatio(value);
  drawnSize = [0, 0];
}
function adapt() {
  const now = performance.now();
  if (now - checked.at < 2000) return;
  const received = stats.pictures - checked.pictures, drawn = stats.drawn - checked.drawn;
  const good = received > 20 && drawn >= 0.97 * received ? checked.good + 1 : 0;
  checked = { at: now, pictures: stats.pictures, drawn: stats.drawn, good };
  if (received > 20 && drawn < 0.85 * received && stats.resolution > 0.4) {
    resolution(Math.max(0.4, stats.resolution * 0.8));
  } else if (good >= 3 && stats.resolution < 1) {
    resolution(Math.min(1, stats.resolution / 0.8));
    checked.good = 0;
  }
}
document.addEventListener("visibilitychange", () => { // back from a hidden tab: start counting afresh
  checked = { at: performance.now(), pictures: stats.pictures, drawn: stats.drawn, good: 0 };
});

// ------------------------------------------------------------------ the socket
const token = new URLSearchParams(location.search).get("token");
const address = `${location.protocol === "https:" ? "wss" : "ws"}://${location.host}/ws` +
  (token ? `?token=${encodeURIComponent(token)}` : "");
const socket = new WebSocket(address);
socket.binaryType = "arraybuffer";

socket.onmessage = (event) => {
  if (typeof event.data === "string") {
    const message = JSON.parse(event.data);
    if (message.type === "hello") build(message);
    else if (message.type === "role") {
      stats.role = message.role;
      stats.id = message.id;
      stats.watchers = message.watchers;
      roleText.textContent = message.role === "pilot"
        ? `you steer${message.watchers ? ` (${message.watchers} watching)` : ""}`
        : "watching: the pilot steers";
      handover.hidden = !(message.role === "pilot" && message.watchers > 0);
      if (message.role !== "pilot") held.clear();
    }
    return;
  }
  stats.bytes += event.data.byteLength;
  picture(event.data);
};
socket.onclose = (event) => {
  stats.closed = event.reason || `the connection closed (code ${event.code})`;
  overlayText.textContent = stats.closed === "the flight ended" ? "the flight ended" : `the flight ended: ${stats.closed}`;
  roleBox.hidden = true;
};

function send(message) {
  if (socket.readyState === WebSocket.OPEN) socket.send(JSON.stringify(message));
}

// ------------------------------------------------------------------ keys: the held set, sent when it changes
// by the physical key (event.code), so that a key let go after Shift (which changes event.key) is the key pressed
const NAMES = { ArrowUp: "UP", ArrowDown: "DOWN", ArrowLeft: "LEFT", ArrowRight: "RIGHT", Space: "SPACE",
                Escape: "ESCAPE", Equal: "PLUS", NumpadAdd: "PLUS", Minus: "MINUS", NumpadSubtract: "MINUS",
                BracketLeft: "[", BracketRight: "]", Period: ".", Slash: "?" };
const held = new Set();
let seq = 0;

function keyName(event) {
  if (event.code in NAMES) return NAMES[event.code];
  const letter = /^Key([A-Z])$/.exec(event.code);
  return letter ? letter[1] : null;
}

function sendHeld() {
  seq += 1;
  stats.sentSeq = seq;
  stats.held = [...held].sort();
  send({ type: "keys", seq, held: [...held] });
}

window.addEventListener("keydown", (event) => {
  const key = keyName(event);
  if (!key || event.ctrlKey || event.metaKey || event.altKey) return;
  event.preventDefault();
  if (event.repeat || held.has(key)) return; // the browser's auto-repeat is not a new press
  held.add(key);
  sendHeld();
});
window.addEventListener("keyup", (event) => {
  const key = keyName(event);
  if (!key || !held.has(key)) return;
  event.preventDefault();
  held.delete(key);
  sendHeld();
});
window.addEventListener("blur", () => { // keys let go while the page had no focus would stay held
  if (held.size) { held.clear(); sendHeld(); }
});

// ------------------------------------------------------------------ mouse: drag to orbit, wheel to zoom
let dragging = false;
let drag = [0, 0];
canvas.addEventListener("pointerdown", (event) => { dragging = true; canvas.setPointerCapture(event.pointerId); canvas.focus(); });
canvas.addEventListener("pointerup", () => { dragging = false; });
canvas.addEventListener("pointercancel", () => { dragging = false; });
canvas.addEventListener("lostpointercapture", () => { dragging = false; });
canvas.addEventListener("pointermove", (event) => {
  if (!dragging) return;
  drag[0] += event.movementX;
  drag[1] -= event.movementY; // up is positive, as in the window
});
setInterval(() => { // at most 30 drag messages a second
  if (drag[0] || drag[1]) { send({ type: "drag", dx: drag[0], dy: drag[1] }); drag = [0, 0]; }
}, 33);
canvas.addEventListener("wheel", (event) => {
  event.preventDefault();
  // a wheel's notch is 100 pixels (or 3 lines); a touchpad's glide sends many small ones
  const notches = event.deltaMode === 1 ? event.deltaY / 3 : event.deltaMode === 2 ? event.deltaY : event.deltaY / 100;
  const clicks = Math.max(-10, Math.min(10, -notches));
  if (clicks) send({ type: "scroll", clicks });
}, { passive: false });
handover.addEventListener("click", () => send({ type: "handover" }));
canvas.focus();
