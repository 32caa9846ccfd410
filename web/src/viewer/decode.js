// decode.js - what the viewer needs from a .vff, made where it does not block the page (the
// decoding Worker runs it): every problem, the summary (text and vff-inspect's JSON), the slices
// for the GPU in a layout that fits the context's limits, the query tables and the contact sheet.
import { initVff, openVff } from '../vff.js';
import { summary } from '../summary.js';
import { chooseLayout } from '../gpu.js';
import { composeSlice } from '../layout.js';
import { buildQueryTables } from '../query_tables.js';
import { collectProblems, problemOf } from './problems.js';
import { inspectJson } from './inspect_json.js';

/** The most sheet pixels kept (the first maps that fit are drawn; the page says how many). */
export const SHEET_MAX_SIDE = 4096;
const MISS = [230, 0, 200];

/** Grey of a hit at distance v of a map whose far end is `scale` (near bright): the legend's ramp. */
export const sheetGrey = (v, scale) => Math.round(255 * (1 - 0.85 * Math.min(v / scale, 1)));

function sheet(file, onStep) {
  const M = file.field.mapResolution, n = file.field.mapCount;
  const maxCols = Math.max(1, Math.floor(SHEET_MAX_SIDE / (M + 1)));
  const shown = Math.min(n, maxCols * maxCols);
  const cols = Math.ceil(Math.sqrt(shown)), rows = Math.ceil(shown / cols);
  const W = cols * (M + 1), H = rows * (M + 1);
  const rgba = new Uint8ClampedArray(W * H * 4).fill(40);
  const scale = file.field.distanceEncoding === 4 ? 1 : 2 * file.field.sphere.radius;
  for (let k = 0; k < shown; ++k) {
    const d = file.distances(k), x0 = (k % cols) * (M + 1), y0 = Math.floor(k / cols) * (M + 1);
    for (let j = 0; j < M; ++j)
      for (let i = 0; i < M; ++i) {
        const v = d[j * M + i], o = 4 * ((y0 + j) * W + x0 + i);
        if (Number.isNaN(v)) rgba.set(MISS, o);
        else { const g = sheetGrey(v, scale); rgba[o] = g; rgba[o + 1] = g; rgba[o + 2] = g; }
        rgba[o + 3] = 255;
      }
    if (k % 64 === 0) onStep(k, shown);
  }
  return { rgba, width: W, height: H, cols, M, shown, mapCount: n, scale, bit1: file.field.distanceEncoding === 4 };
}

/** The words for texel (i, j) of map k, as the contact sheet names it. */
export function texelText(file, k, i, j) {
  const d = file.distance(k, i, j);
  return `map ${k}, texel (${i}, ${j}): ${d === null ? 'miss' : file.field.distanceEncoding === 4 ? 'hit' : `hit at ${d.toPrecision(6)}`}`;
}

/** The slices of a plane for a layout, in one buffer (slice after slice), and its texel format. */
function planeSlices(file, L, planeName) {
  const fd = file.field, e = fd.distanceEncoding, M = fd.mapResolution;
  const plane = (kind, texelBytes, fill) => ({ kind, texelBytes, fill, M, mapCount: fd.mapCount });
  let p, source, format, width = L.sliceWidth;
  if (planeName === 'normal') { p = plane('bytes', 4, 0); source = (k) => file.mapBytes('normal', k); format = 'RG16I'; }
  else if (e === 3) { p = plane('bytes', 2, 0xff); source = (k) => file.mapBytes('distance', k); format = 'R16UI'; }
  else if (e === 4) { p = plane('bit1', 1, 0); source = (k) => file.mapBytes('distance', k); format = 'R8UI'; width = L.sliceWidth / 8; }
  // bc4-diameter: the blocks decoded to their unorm8 codes here, uploaded as R8UI (every WebGL2 has it).
  else if (e === 5) { p = plane('bytes', 1, 0xff); source = (k) => file.codes(k); format = 'R8UI'; }
  else { p = plane('bytes', 1, 0xff); source = (k) => file.mapBytes('distance', k); format = 'R8UI'; }
  const first = composeSlice(L, p, 0, source);
  const all = new Uint8Array(first.length * L.sliceCount);
  all.set(first, 0);
  for (let s = 1; s < L.sliceCount; ++s) all.set(composeSlice(L, p, s, source), s * first.length);
  const data = format === 'R16UI' ? new Uint16Array(all.buffer) : format === 'RG16I' ? new Int16Array(all.buffer) : all;
  return { format, width, height: L.sliceHeight, depth: L.sliceCount, data };
}

/**
 * Decodes `bytes` for the viewer. limits: {maxTextureSize, maxLayers, max3d} of the page's context.
 * progress(share 0..1, stage words). Returns {result, file, transfer}: result is plain data
 * (structured-clone safe; its big buffers listed in transfer); file the opened VffFile or null.
 */
export async function decodeForViewer(bytes, name, limits, progress = () => {}) {
  progress(0, 'reading the header and sections');
  await initVff();
  let file;
  try {
    file = openVff(bytes, { checksums: 'lazy' });
  } catch (e) {
    return { result: { ok: false, name, problems: [problemOf(e)] }, file: null, transfer: [] };
  }
  progress(0.05, 'checking every block');
  const problems = collectProblems(file, (d, t) => { if (d % 8 === 0 || d === t) progress(0.05 + 0.55 * (d / t), 'checking every block'); });
  if (problems.some((p) => p.severity === 'error')) return { result: { ok: false, name, problems }, file: null, transfer: [] };
  const text = summary(file, name);
  const json = inspectJson(file, name);
  progress(0.6, 'packing the slices for the GPU');
  const fd = file.field;
  const field = { center: [...fd.sphere.center], radius: fd.sphere.radius, mapCount: fd.mapCount, mapResolution: fd.mapResolution, distanceEncoding: fd.distanceEncoding, normals: !!file.planes.normal };
  const chosen = chooseLayout(file, limits);
  let gpu = null;
  const transfer = [];
  if (!chosen.error) {
    const L = chosen.layout;
    const distance = planeSlices(file, L, 'distance');
    const normal = file.planes.normal ? planeSlices(file, L, 'normal') : null;
    const { block, table } = buildQueryTables(file, L);
    gpu = { layout: L, is3d: L.target === 2, note: chosen.note ?? '', distance, normal, block, table };
    transfer.push(distance.data.buffer, block, table.buffer);
    if (normal) transfer.push(normal.data.buffer);
  }
  progress(0.85, 'drawing the contact sheet');
  const sh = sheet(file, (k, n) => progress(0.85 + 0.15 * (k / n), 'drawing the contact sheet'));
  transfer.push(sh.rgba.buffer);
  progress(1, 'done');
  return {
    result: { ok: true, name, problems, summary: text, json, field, gpu, gpuError: chosen.error ?? '', sheet: sh },
    file, transfer,
  };
}
