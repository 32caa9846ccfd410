// main.js - the viewer page: open a .vff (file chooser, drop, ?file=URL, samples), decode it in a
// Worker with a progress bar, list every problem, show the summary, the contact sheet and the
// three.js view, and offer PNG and JSON downloads. A new file, or a bad one, first clears all that
// the previous file left. The file is read in the page and never sent anywhere.
import { FieldView } from './view3d.js';
import { openWebGpu } from './webgpu_ground.js';
import { ContactSheet } from './sheet.js';
import { fieldResources } from './field_three.js';
import { problemText } from './problems.js';
import { jsonText } from './inspect_json.js';
import { sheetGrey } from './decode.js';

const $ = (id) => document.getElementById(id);
const here = (p) => new URL(p, import.meta.url).href;

// The decoding Worker, and the answers it owes (one decode at a time; texel questions by id).
const worker = new Worker(here('./decode_worker.js'), { type: 'module' });
const ready = new Promise((resolve, reject) => {
  worker.addEventListener('message', function first({ data }) {
    if (data.ready) { worker.removeEventListener('message', first); resolve(); }
    else if (data.failure) reject(new Error(data.failure.message));
  });
});
worker.postMessage({ init: {
  decode: here('./decode.js'),
  imports: { fzstd: here('../../node_modules/fzstd/esm/index.mjs'), 'hash-wasm': here('../../node_modules/hash-wasm/dist/index.esm.js') },
} });
let pending = null, texelId = 0;
const texelAnswers = new Map();
worker.addEventListener('message', ({ data }) => {
  if (data.progress && pending) pending.progress(data.progress);
  else if (data.result && pending) { const p = pending; pending = null; p.resolve(data.result); }
  else if (data.failure && pending) { const p = pending; pending = null; p.reject(new Error(data.failure.message)); }
  else if (data.texel) { texelAnswers.get(data.texel.id)?.(data.texel.text); texelAnswers.delete(data.texel.id); }
});
const askTexel = (k, i, j) => new Promise((resolve) => { const id = ++texelId; texelAnswers.set(id, resolve); worker.postMessage({ texel: { k, i, j, id } }); });

const view = new FieldView($('view'), $('view-box'), ({ frame, maxFrames, ms }) => {
  $('frames').textContent = state?.result?.ok ? `${frame} / ${maxFrames} frames accumulated (${ms.toFixed(0)} ms for the last)` : '';
  showBackend();
});
const gl = view.renderer.getContext();
const limits = { maxTextureSize: gl.getParameter(gl.MAX_TEXTURE_SIZE), maxLayers: gl.getParameter(gl.MAX_ARRAY_TEXTURE_LAYERS), max3d: gl.getParameter(gl.MAX_3D_TEXTURE_SIZE) };
// The ground through WebGPU where the browser offers it (the object is WebGL2 either way); a file's
// layout must then fit both APIs' limits. Files wait for the answer (loadBytes).
// ?ground=webgpu takes a software adapter too; ?ground=webgl2 leaves WebGPU alone.
const groundParam = new URLSearchParams(location.search).get('ground');
const gpuOpened = (groundParam === 'webgl2' ? Promise.resolve({ reason: '?ground=webgl2' })
  : openWebGpu({ allowFallback: groundParam === 'webgpu' })).then(async (gpu) => {
  if (gpu.device) {
    for (const k of Object.keys(limits)) limits[k] = Math.min(limits[k], gpu.limits[k]);
    view.useWebGpu(gpu);
  } else {
    console.info(`vff viewer: the ground is drawn with WebGL2 (${gpu.reason})`);
  }
  showBackend();
  return view.backend;
});
function showBackend() { $('backend').textContent = state?.result?.ok ? `ground: ${view.backendName}` : ''; }
// (At once, not at the next frame: a page that draws no more frames still names its ground.)
view.onBackend = showBackend;
const sheet = new ContactSheet($('sheet'), $('under'), askTexel);

let state = null, loads = 0;

function setProgress(share, words) {
  const bar = $('progress');
  bar.hidden = share === null;
  if (share !== null) bar.value = share;
  $('status').textContent = words;
}

/** Everything the previous file put on the page, gone. */
function clearPage() {
  state = null;
  view.clear();
  sheet.set(null);
  $('summary').textContent = '';
  $('problems').replaceChildren();
  $('problems-box').hidden = true;
  $('note').textContent = '';
  $('frames').textContent = '';
  $('maps-legend').hidden = true;
  for (const b of ['save-png', 'save-json']) $(b).disabled = true;
}

function listProblems(name, problems) {
  const ul = $('problems');
  ul.replaceChildren(...problems.map((p) => {
    const li = document.createElement('li');
    li.textContent = problemText(name, p);
    li.className = p.severity;
    return li;
  }));
  $('problems-box').hidden = problems.length === 0;
  $('problems-title').textContent = problems.some((p) => p.severity === 'error')
    ? `${name} cannot be shown: ${problems.filter((p) => p.severity === 'error').length} problem${problems.length === 1 ? '' : 's'}`
    : `${name}: warnings`;
}

function showMapsLegend(s) {
  $('maps-legend').hidden = false;
  const far = sheetGrey(1, 1), near = sheetGrey(0, 1);
  $('maps-ramp').style.background = `linear-gradient(to right, rgb(${near},${near},${near}), rgb(${far},${far},${far}))`;
  $('maps-near').textContent = s.bit1 ? 'hit' : '0';
  $('maps-far').textContent = s.bit1 ? '' : `${s.scale.toPrecision(4)} (2R) and beyond`;
  $('maps-shown').textContent = s.shown < s.mapCount ? `The first ${s.shown} of ${s.mapCount} maps are shown.` : `${s.mapCount} maps.`;
}

/**
 * Opens bytes named `name`. Returns {ok, gl, id?, message?, problems, groundY?}. options.keepBytes:
 * the caller's buffer is copied rather than handed to the Worker.
 */
export async function loadBytes(bytes, name, options = {}) {
  const mine = ++loads;
  clearPage();
  setProgress(0, `Decoding ${name}…`);
  await ready;
  await gpuOpened;
  const copy = options.keepBytes === false && bytes.byteOffset === 0 && bytes.byteLength === bytes.buffer.byteLength ? bytes : bytes.slice();
  let result;
  try {
    result = await new Promise((resolve, reject) => {
      pending = { resolve, reject, progress: ({ share, stage }) => { if (mine === loads) setProgress(share, `${name}: ${stage}…`); } };
      worker.postMessage({ decode: { bytes: copy, name, limits } }, [copy.buffer]);
    });
  } catch (e) {
    result = { ok: false, name, problems: [{ severity: 'error', id: 0, message: `the decoder failed: ${e.message}` }] };
  }
  if (mine !== loads) return { ok: false, superseded: true };
  listProblems(name, result.problems);
  if (!result.ok) {
    setProgress(null, `${name} cannot be shown (${result.problems.length} problem${result.problems.length === 1 ? '' : 's'} listed below).`);
    const first = result.problems[0] ?? {};
    return { ok: false, gl: false, id: first.id ?? 0, message: first.message ?? '', problems: result.problems };
  }
  state = { name, result };
  $('summary').textContent = result.summary;
  sheet.set(result.sheet);
  showMapsLegend(result.sheet);
  $('save-json').disabled = false;
  if (!result.gpu) {
    $('note').textContent = result.gpuError;
    setProgress(null, `${name}: summary and maps shown; the 3D view cannot show this file.`);
    return { ok: true, gl: false, message: result.gpuError, problems: result.problems };
  }
  $('note').textContent = result.gpu.note;
  const placed = view.setField(fieldResources(result));
  showBackend();
  $('save-png').disabled = false;
  setProgress(null, `${name}: ${result.field.mapCount} maps of ${result.field.mapResolution}²; the object stands on the ground at y = ${placed.groundY.toPrecision(5)}.`);
  return { ok: true, gl: true, problems: result.problems, groundY: placed.groundY, lowest: placed.lowest };
}

/** Fetches a URL with a progress bar, then opens it. */
export async function loadUrl(url) {
  const name = decodeURIComponent(new URL(url, location.href).pathname.split('/').pop() || 'file.vff');
  clearPage();
  setProgress(0, `Fetching ${url}…`);
  let res;
  try {
    res = await fetch(url);
    if (!res.ok) throw new Error(`HTTP ${res.status} ${res.statusText}`);
  } catch (e) {
    const problems = [{ severity: 'error', id: 0, message: `cannot fetch ${url}: ${e.message}` }];
    listProblems(name, problems);
    setProgress(null, `${name} could not be fetched.`);
    return { ok: false, gl: false, id: 0, message: problems[0].message, problems };
  }
  const total = Number(res.headers.get('content-length')) || 0;
  const chunks = [];
  let got = 0;
  for (const reader = res.body.getReader(); ;) {
    const { done, value } = await reader.read();
    if (done) break;
    chunks.push(value);
    got += value.length;
    setProgress(total ? got / total : 0, `Fetching ${name}: ${(got / 1048576).toFixed(1)} MiB…`);
  }
  const bytes = new Uint8Array(got);
  let at = 0;
  for (const c of chunks) { bytes.set(c, at); at += c.length; }
  return loadBytes(bytes, name, { keepBytes: false });
}

function download(blob, name) {
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}
const stem = () => (state?.name ?? 'field').replace(/\.vff$/i, '');

$('open').addEventListener('change', (e) => { const f = e.target.files[0]; if (f) f.arrayBuffer().then((b) => loadBytes(new Uint8Array(b), f.name, { keepBytes: false })); });
document.body.addEventListener('dragover', (e) => { e.preventDefault(); $('drop').classList.add('over'); });
document.body.addEventListener('dragleave', () => $('drop').classList.remove('over'));
document.body.addEventListener('drop', (e) => {
  e.preventDefault();
  $('drop').classList.remove('over');
  const f = e.dataTransfer.files[0];
  if (f) f.arrayBuffer().then((b) => loadBytes(new Uint8Array(b), f.name, { keepBytes: false }));
});
$('sample').addEventListener('change', (e) => { if (e.target.value) loadUrl(e.target.value); });
$('interp').addEventListener('change', (e) => view.setOptions({ interpolated: e.target.checked }));
view.setOptions({ interpolated: $('interp').checked });  // a browser may restore the box's state on reload
$('show').addEventListener('change', (e) => {
  view.setOptions({ show: Number(e.target.value) });
  $('ao-legend-title').textContent = ['Ground: lit colour × (AO and shadow)', 'Ground AO', 'Ground light (soft shadow)'][Number(e.target.value)];
});
$('light-az').addEventListener('input', (e) => view.setOptions({ lightAzimuth: (Number(e.target.value) * Math.PI) / 180 }));
$('light-el').addEventListener('input', (e) => view.setOptions({ lightElevation: (Number(e.target.value) * Math.PI) / 180 }));
$('save-png').addEventListener('click', async () => download(await view.png(), `${stem()}.png`));
$('save-json').addEventListener('click', () => state && download(new Blob([jsonText(state.result.json)], { type: 'application/json' }), `${stem()}.json`));

// For the tests and the benchmark (web/test/browser/): the entry points and the view.
window.vffViewer = {
  loadBytes, loadUrl, view, ready,
  /** Resolves once WebGPU has answered (a device or none); view.backend says what draws the ground. */
  gpuOpened,
  get state() { return state; },
  /** Draws one frame now (one accumulation step); returns the milliseconds until the GPU finished. */
  redraw() {
    const t0 = performance.now();
    view.draw();
    gl.readPixels(0, 0, 1, 1, gl.RGBA, gl.UNSIGNED_BYTE, new Uint8Array(4));
    return performance.now() - t0;
  },
  reference: (size, interpolated, api) => view.reference(size, interpolated, api),
  objectPixels: () => view.objectPixels(),
};

const fileParam = new URLSearchParams(location.search).get('file');
if (fileParam) loadUrl(fileParam);
