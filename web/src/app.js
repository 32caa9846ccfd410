// app.js - the viewer page: open or drop a .vff, show its summary, its maps and the WebGL2 view.
// The file is read with the File API and never leaves the page.
import { initVff, openVff } from './vff.js';
import { summary } from './summary.js';
import { attachSheet } from './contact.js';
import { uploadField } from './gpu.js';
import { createProgram, draw } from './scene.js';

const $ = (id) => document.getElementById(id);
const view = { yaw: 0.6, pitch: -0.35, distance: 5, objectYaw: 0, objectPitch: 0, lightYaw: -0.8, lightPitch: 0.9, interpolated: false, reference: false, aoRays: 16 };
let state = null;
const programs = new Map();

/**
 * Loads bytes named `name` into the page; returns {ok, gl, id?, message?} (the tests call it).
 * options.bc4OnCpu: decode bc4-diameter maps on the CPU even where the context has RGTC.
 */
export async function loadBytes(bytes, name, options = {}) {
  await initVff();
  $('error').textContent = ''; $('note').textContent = ''; $('summary').textContent = '';
  let file;
  try {
    file = openVff(bytes);
    file.validateDeep();
  } catch (e) {
    $('error').textContent = `${name}${e.id ? `: ${e.message}` : `: ${e}`}`;
    return { ok: false, id: e.id ?? 0, message: e.message };
  }
  $('summary').textContent = summary(file, name);
  attachSheet($('sheet'), file, $('under'));
  const gl = $('view').getContext('webgl2', { preserveDrawingBuffer: true, antialias: false });
  if (!gl) { $('error').textContent = 'This browser has no WebGL2 context.'; return { ok: true, gl: false }; }
  const up = uploadField(gl, file, options);
  if (up.error) { $('error').textContent = up.error; return { ok: true, gl: false, message: up.error }; }
  if (up.note) $('note').textContent = up.note;
  // Programs depend only on the defines (3D target, normals, BC4): compile each variant once.
  const key = up.field.defines.join(' ');
  if (!programs.has(key)) programs.set(key, createProgram(gl, up.field));
  state = { gl, file, field: up.field, program: programs.get(key) };
  redraw();
  return { ok: true, gl: true, ...(up.bc4 ? { bc4: up.bc4 } : {}) };
}

/** Draws a frame now; returns the milliseconds until the GPU finished it. */
export function redraw() {
  if (!state) return 0;
  const t0 = performance.now();
  draw(state.gl, state.program, state.field, view);
  state.gl.readPixels(0, 0, 1, 1, state.gl.RGBA, state.gl.UNSIGNED_BYTE, new Uint8Array(4));  // waits for the frame
  return performance.now() - t0;
}

async function openFile(f) { await loadBytes(new Uint8Array(await f.arrayBuffer()), f.name); }

$('open').onchange = (e) => e.target.files[0] && openFile(e.target.files[0]);
const drop = $('drop');
document.body.ondragover = (e) => { e.preventDefault(); drop.classList.add('over'); };
document.body.ondragleave = () => drop.classList.remove('over');
document.body.ondrop = (e) => { e.preventDefault(); drop.classList.remove('over'); if (e.dataTransfer.files[0]) openFile(e.dataTransfer.files[0]); };
$('interp').onchange = (e) => { view.interpolated = e.target.checked; redraw(); };
$('rays').oninput = (e) => { view.aoRays = Number(e.target.value); redraw(); };

let drag = null;
const canvas = $('view');
canvas.onmousedown = (e) => { drag = { x: e.clientX, y: e.clientY, shift: e.shiftKey, alt: e.altKey }; };
window.addEventListener('mouseup', () => {
  if (drag && view.moving) { view.moving = false; $('fps').textContent = `${redraw().toFixed(1)} ms per frame`; }
  drag = null;
});
window.addEventListener('mousemove', (e) => {
  if (!drag) return;
  const dx = (e.clientX - drag.x) * 0.01, dy = (e.clientY - drag.y) * 0.01;
  drag.x = e.clientX; drag.y = e.clientY;
  view.moving = true;
  if (drag.shift) { view.objectYaw += dx; view.objectPitch += dy; }
  else if (drag.alt) { view.lightYaw += dx; view.lightPitch = Math.min(1.5, Math.max(0.05, view.lightPitch - dy)); }
  else { view.yaw -= dx; view.pitch = Math.min(-0.05, Math.max(-1.5, view.pitch - dy)); }
  const ms = redraw();
  $('fps').textContent = `${ms.toFixed(1)} ms per frame (moving: 4 AO rays)`;
});
canvas.onwheel = (e) => { e.preventDefault(); view.distance = Math.min(30, Math.max(1.5, view.distance * (e.deltaY > 0 ? 1.1 : 0.9))); redraw(); };

// For the tests and the benchmark (web/test/browser/): the view state and the entry points.
window.vffViewer = { loadBytes, redraw, view };
