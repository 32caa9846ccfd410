// main.js - the example scene of @vff/three: a glTF with a floor and four objects that carry fields
// (VFF_visibility_field, baked by vff-bake), moving along paths over the floor. VffOcclusion adds
// their ambient occlusion and soft shadows to every surface, from one texture lookup per ray;
// 'exact reference' answers the same rays with three-mesh-bvh's GPU ray casting against the
// objects' triangles, for comparison.
//
// URL parameters: asset (a .glb; default assets/example.glb, made by web/tools/make-example.mjs),
// mode (field, reference, off), range (AO range, scene units), rays (AO rays per pixel and frame),
// t (the animation time, seconds), paused (1: hold still at t), dpr (the largest pixel ratio used).
//
// window.example is there for tests and benchmarks: setTime(t), renderFrames(n), the renderer,
// scene, camera and effect, and `ready` once the asset is on screen (or `error`).
import * as THREE from 'three';
import { GLTFLoader } from 'three/addons/loaders/GLTFLoader.js';
import { OrbitControls } from 'three/addons/controls/OrbitControls.js';
import { VffGLTFPlugin, VffOcclusion } from '@vff/three';

const params = new URLSearchParams(location.search);
const $ = (id) => document.getElementById(id);
const canvas = $('view');
const status = $('status');
const example = { ready: false, error: null };
window.example = example;

function showError(text) {
  example.error = text;
  $('message').textContent = text;
  $('message').hidden = false;
  status.textContent = 'not running';
}

// The light the shadows come from: the direction towards it, shared by three's light and the effect.
const LIGHT = new THREE.Vector3(0.45, 1, 0.35).normalize();

// Each object follows a closed path about the floor's centre: two on an inner circle, two on an
// outer one turning the other way, so that they never meet. Angular speed in radians per second.
const PATHS = [
  { radius: 1.0, phase: 0, speed: 0.5 },
  { radius: 1.0, phase: Math.PI, speed: 0.5 },
  { radius: 2.6, phase: Math.PI / 2, speed: -0.3 },
  { radius: 2.6, phase: -Math.PI / 2, speed: -0.3 },
];

const renderer = new THREE.WebGLRenderer({ canvas, antialias: false, preserveDrawingBuffer: true });
const maxDpr = Number(params.get('dpr') ?? 2);
renderer.setPixelRatio(Math.min(window.devicePixelRatio || 1, maxDpr > 0 ? maxDpr : 2));
renderer.outputColorSpace = THREE.SRGBColorSpace;

const scene = new THREE.Scene();
scene.background = new THREE.Color(0x2a3038);
const camera = new THREE.PerspectiveCamera(40, 1, 0.1, 100);
camera.position.set(0, 3.4, 5.6);
const controls = new OrbitControls(camera, canvas);
controls.target.set(0, 0.3, 0);
controls.maxPolarAngle = Math.PI * 0.48;  // stay above the floor
controls.minDistance = 2;
controls.maxDistance = 25;
controls.update();

scene.add(new THREE.HemisphereLight(0xdde6ff, 0x806850, 0.9));
const sun = new THREE.DirectionalLight(0xffffff, 1.6);
sun.position.copy(LIGHT).multiplyScalar(10);
scene.add(sun);

// The drawing buffer follows the canvas's CSS size times the pixel ratio, so nothing is stretched.
function resize() {
  const w = Math.max(1, canvas.clientWidth), h = Math.max(1, canvas.clientHeight);
  const size = renderer.getSize(new THREE.Vector2());
  if (size.x === w && size.y === h) return;
  renderer.setSize(w, h, false);
  camera.aspect = w / h;
  camera.updateProjectionMatrix();
}
new ResizeObserver(resize).observe(canvas);
resize();

const ui = {
  mode: params.get('mode') ?? 'field',
  range: Number(params.get('range') ?? 0.6),
  rays: Number(params.get('rays') ?? 4),
  paused: params.get('paused') === '1',
};
let time = Number(params.get('t') ?? 0);
let occ = null;
let movers = [];

/** Places every moving object at time t (seconds): on its path, facing along it, on the floor. */
function setTime(t) {
  time = t;
  movers.forEach((o, i) => {
    const p = PATHS[i % PATHS.length];
    const a = p.phase + p.speed * t;
    o.position.set(p.radius * Math.cos(a), 0, p.radius * Math.sin(a));
    // Tangent of the circle, in the direction of travel.
    o.rotation.set(0, -a - Math.sign(p.speed) * Math.PI / 2, 0);
  });
}

function applyOptions() {
  occ.mode = ui.mode;
  // The effect reads its options each frame; a change restarts the accumulation.
  Object.assign(occ.options, { aoRange: ui.range, aoRays: ui.rays, shadowRays: ui.rays });
  $('range-out').value = ui.range.toFixed(2);
  $('rays-out').value = String(ui.rays);
}

let frameMs = 0;
function renderOnce() {
  resize();
  const t0 = performance.now();
  occ.render(scene, camera);
  frameMs = performance.now() - t0;
}

/** Draws n frames at the current time and view (they accumulate); returns ms per frame. */
function renderFrames(n) {
  const gl = renderer.getContext();
  const px = new Uint8Array(4);
  const t0 = performance.now();
  for (let i = 0; i < n; ++i) renderOnce();
  gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, px);  // waits for the GPU
  return (performance.now() - t0) / n;
}

function bindControls() {
  for (const r of document.querySelectorAll('input[name=mode]')) {
    r.checked = r.value === ui.mode;
    r.addEventListener('change', () => { ui.mode = r.value; applyOptions(); });
  }
  $('range').value = String(ui.range);
  $('range').addEventListener('input', () => { ui.range = Number($('range').value); applyOptions(); });
  $('rays').value = String(ui.rays);
  $('rays').addEventListener('input', () => { ui.rays = Number($('rays').value); applyOptions(); });
  $('pause').checked = ui.paused;
  $('pause').addEventListener('change', () => { ui.paused = $('pause').checked; });
}

async function start() {
  const url = params.get('asset') ?? 'assets/example.glb';
  const loader = new GLTFLoader();
  loader.register((parser) => new VffGLTFPlugin(parser));
  let gltf;
  try {
    gltf = await loader.loadAsync(url);
  } catch (e) {
    const missing = /404|Not Found|fetch/i.test(String(e?.message ?? e));
    throw new Error(missing
      ? `${url} is not there: make it with \`node tools/make-example.mjs\` in web/ (needs vff-bake), then reload.`
      : `${url}: ${e.message ?? e}`);
  }
  scene.add(gltf.scene);
  const found = gltf.userData.vffFields ?? [];
  const problems = gltf.userData.vffProblems ?? found.flatMap((f) => f.problems ?? []);
  movers = [];
  gltf.scene.traverse((o) => { if (o.userData.vffField && o.name !== 'floor') movers.push(o); });
  if (!movers.length) throw new Error(`${url}: no object carries a usable field (VFF_visibility_field)`);

  occ = new VffOcclusion(renderer, {
    aoRange: ui.range, aoRays: ui.rays, shadowRays: ui.rays, lightDirection: LIGHT, lightAngle: 0.08,
    maxInstances: Math.max(8, movers.length),
  });
  // The floor receives; the moving objects cast (and receive each other's occlusion).
  occ.setInstances(movers.map((object) => ({ object, field: object.userData.vffField })));
  applyOptions();
  bindControls();
  setTime(time);

  Object.assign(example, {
    renderer, scene, camera, controls, occ, movers, gltf, problems,
    setTime, renderFrames, applyOptions, ui,
    setMode(m) { ui.mode = m; applyOptions(); },
  });
  renderOnce();
  status.textContent = `${ui.mode} · ready`;
  example.ready = true;

  let last = performance.now(), avg = 0;
  const loop = () => {
    const now = performance.now();
    const dt = Math.min(0.1, (now - last) / 1000);
    avg = avg ? 0.9 * avg + 0.1 * (now - last) : now - last;
    last = now;
    if (!ui.paused) setTime(time + dt);
    controls.update();
    renderOnce();
    const notes = problems.length ? ` · ${problems.length} asset note(s)` : '';
    status.textContent = `${ui.mode} · ${avg.toFixed(0)} ms/frame (draw ${frameMs.toFixed(1)} ms) · ` +
      `${occ.frame} frame(s) accumulated${notes}`;
  };
  // noloop: frames only on request (renderFrames), for tests and benchmarks.
  example.setLoop = (on) => {
    last = performance.now();
    avg = 0;
    renderer.setAnimationLoop(on ? loop : null);
  };
  example.setLoop(!params.has('noloop'));
}

start().catch((e) => showError(e.message ?? String(e)));
