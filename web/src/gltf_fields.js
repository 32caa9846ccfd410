// gltf_fields.js - fields inside glTF assets: the extension VFF_visibility_field
// (spec/gltf/VFF_visibility_field/README.md), read and checked as libvff's readGltfFields does.
//
// A field is baked in its mesh's own space, so the extension sits on a mesh:
//   meshes[i].extensions.VFF_visibility_field = { bufferView | uri, mimeType, geometryHash, min, max }
// and its payload is a complete .vff file. The reader runs the rules 14001-14011 in the spec's order
// and matches each field against the triangles the asset ships (14101-14103): a Draco or quantized
// re-encode moves vertices a little, which the rules tolerate up to one distance step (2R/255).
//
//   import { readGltfFields } from './src/gltf_fields.js';
//   const r = await readGltfFields(glbBytes, { resolveUri: (path) => fetchBytes(path) });
//   for (const p of r.problems) console.log(formatGltfProblem('scene.glb', p));
//   for (const f of r.fields) if (f.usable) { const file = openVff(f.bytes); ... }
//
// Options:
//   resolveUri(path) -> Uint8Array | null (or a Promise of one): the bytes of a relative uri, already
//     percent-decoded (payloads and, for .gltf, buffers). Without it such files cannot be read.
//   decodedGeometry(mesh, primitive) -> {positions: Float32Array, indices?: Uint32Array, mode?} | null:
//     the decoded POSITION (and indices) of a Draco or meshopt compressed primitive, which this module
//     does not decode itself; null leaves the mesh unreadable (14011).
//   checkGeometry (default true): match each field against its mesh (else `match` stays 'unchecked').
import { initChecksums, xxh3Hex } from './checksum.js';
import { openVff } from './container.js';
import { VffError } from './errors.js';

export const GLTF_FIELD_EXTENSION = 'VFF_visibility_field';
export const VFF_MEDIA_TYPE = 'application/vnd.vff';

/** The rules' names by ID (the spec's section "Rules"), in check order; 141xx are not errors. */
export const GLTF_RULE_NAMES = Object.freeze({
  14001: 'gltf-container', 14002: 'gltf-required', 14003: 'gltf-used', 14004: 'gltf-extension-value',
  14005: 'gltf-field-source', 14006: 'gltf-buffer-view', 14007: 'gltf-uri', 14008: 'gltf-mime-type',
  14009: 'gltf-payload', 14010: 'gltf-hash-conflict', 14011: 'gltf-mesh-geometry',
  14101: 'gltf-geometry-exact', 14102: 'gltf-geometry-close', 14103: 'gltf-geometry-mismatch',
  14104: 'gltf-node-no-field',
});

const SEVERITY = { 14102: 'note', 14103: 'warning', 14104: 'note' };

/** "FILE: PATH: name (ID): message", the path left out when empty (as the C++ tools print). */
export function formatGltfProblem(file, p) {
  return `${file}: ${p.path ? p.path + ': ' : ''}${p.name} (${p.rule}): ${p.message}`;
}

const GLB_MAGIC = 0x46546c67;  // "glTF"
const CHUNK_JSON = 0x4e4f534a;
const CHUNK_BIN = 0x004e4942;

class FileProblem extends Error {
  constructor(message, path = '') {
    super(message);
    this.path = path;
  }
}

/** The JSON and the BIN chunk (or null) of a .glb, or the JSON of a .gltf; throws FileProblem. */
function parseContainer(bytes) {
  const dv = new DataView(bytes.buffer, bytes.byteOffset, bytes.byteLength);
  let jsonBytes = bytes;
  let bin = null;
  const glb = bytes.length >= 4 && dv.getUint32(0, true) === GLB_MAGIC;
  if (glb) {
    if (bytes.length < 20) throw new FileProblem(`a GLB of ${bytes.length} bytes, shorter than its header and first chunk header`);
    const version = dv.getUint32(4, true);
    if (version !== 2) throw new FileProblem(`GLB version ${version}, not 2`);
    const length = dv.getUint32(8, true);
    if (length !== bytes.length) throw new FileProblem(`the GLB header gives ${length} bytes, the file has ${bytes.length}`);
    let at = 12;
    let chunk = 0;
    while (at < length) {
      if (length - at < 8) throw new FileProblem(`chunk ${chunk} at byte ${at}: its header runs past the end of the file`);
      const size = dv.getUint32(at, true), type = dv.getUint32(at + 4, true);
      if (size > length - at - 8) throw new FileProblem(`chunk ${chunk} at byte ${at}: ${size} bytes run past the end of the file`);
      const data = bytes.subarray(at + 8, at + 8 + size);
      if (chunk === 0) {
        if (type !== CHUNK_JSON) throw new FileProblem('the first chunk is not JSON');
        jsonBytes = data;
      } else if (chunk === 1 && type === CHUNK_BIN) {
        bin = data;
      }
      at += 8 + size;
      ++chunk;
    }
    if (chunk === 0) throw new FileProblem('a GLB without a JSON chunk');
  }
  let json;
  try {
    json = JSON.parse(new TextDecoder('utf-8', { fatal: true }).decode(jsonBytes));
  } catch (e) {
    throw new FileProblem(`the JSON ${glb ? 'chunk ' : ''}cannot be parsed: ${e.message}`);
  }
  if (json === null || typeof json !== 'object' || Array.isArray(json)) throw new FileProblem('the JSON is not an object');
  const asset = json.asset;
  const version = asset !== null && typeof asset === 'object' && !Array.isArray(asset) ? asset.version : undefined;
  if (version === undefined) throw new FileProblem('asset.version is missing', '/asset/version');
  if (typeof version !== 'string' || !version.startsWith('2.'))
    throw new FileProblem(`asset.version is ${JSON.stringify(version)}, not "2.x"`, '/asset/version');
  return { json, bin, glb };
}

const isObject = (v) => v !== null && typeof v === 'object' && !Array.isArray(v);
const isIndex = (v) => Number.isInteger(v) && v >= 0;
const arr = (v) => (Array.isArray(v) ? v : []);
const has = (o, k) => Object.prototype.hasOwnProperty.call(o, k);

// ---- URIs ---------------------------------------------------------------------------------------

/** Percent-decodes a relative uri as glTF does; {path} or {error}. */
export function checkRelativeUri(uri) {
  if (uri.length === 0) return { error: 'the uri is empty' };
  if (/^[A-Za-z][A-Za-z0-9+.-]*:/.test(uri)) return { error: `an absolute uri (scheme "${uri.slice(0, uri.indexOf(':'))}"), only relative ones and data: are allowed` };
  if (uri.startsWith('/')) return { error: 'an absolute path' };
  if (uri.includes('//')) return { error: 'the uri contains "//"' };
  for (const c of ['?', '#', '\\']) if (uri.includes(c)) return { error: `the uri contains "${c}"` };
  const out = [];
  const enc = new TextEncoder();
  for (let i = 0; i < uri.length; ++i) {
    if (uri[i] === '%') {
      const h = uri.slice(i + 1, i + 3);
      if (!/^[0-9A-Fa-f]{2}$/.test(h)) return { error: `a bad percent escape at character ${i}` };
      const b = parseInt(h, 16);
      if (b === 0) return { error: 'the uri decodes to a NUL character' };
      out.push(b);
      i += 2;
    } else {
      for (const b of enc.encode(uri[i])) out.push(b);
    }
  }
  let path;
  try {
    path = new TextDecoder('utf-8', { fatal: true }).decode(new Uint8Array(out));
  } catch {
    return { error: 'the uri does not decode to UTF-8 text' };
  }
  return { path };
}

const B64 = 'ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/';

/** The bytes of a `data:...;base64,` uri, or {error}. */
export function decodeDataUri(uri) {
  const comma = uri.indexOf(',');
  if (comma < 0) return { error: 'a data: uri without a comma' };
  if (!/;base64$/i.test(uri.slice(0, comma))) return { error: 'a data: uri that is not base64' };
  const s = uri.slice(comma + 1);
  const pad = s.endsWith('==') ? 2 : s.endsWith('=') ? 1 : 0;
  const body = s.slice(0, s.length - pad);
  if ((pad && s.length % 4 !== 0) || body.length % 4 === 1) return { error: 'the base64 data has a bad length' };
  const out = new Uint8Array(Math.floor((body.length * 3) / 4));
  let acc = 0, bits = 0, o = 0;
  for (let i = 0; i < body.length; ++i) {
    const v = B64.indexOf(body[i]);
    if (v < 0) return { error: `a character outside base64 at ${i}` };
    acc = (acc << 6) | v;
    bits += 6;
    if (bits >= 8) {
      bits -= 8;
      out[o++] = (acc >> bits) & 0xff;
    }
  }
  return { bytes: out };
}

async function readUri(resolveUri, path) {
  if (!resolveUri) return { error: 'no resolveUri was given to read it' };
  try {
    const b = await resolveUri(path);
    if (b == null) return { error: `${path} cannot be read` };
    return { bytes: b instanceof Uint8Array ? b : new Uint8Array(b) };
  } catch (e) {
    return { error: `${path} cannot be read: ${e?.message ?? e}` };
  }
}

// ---- Geometry -----------------------------------------------------------------------------------

const COMPONENT_SIZE = { 5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4 };

class GeometryProblem extends Error {}

/**
 * The triangles of mesh `m` as shipped (every primitive of mode 4, 5 or 6; POSITION read as glTF and
 * KHR_mesh_quantization say; Draco or meshopt through `decoded`), in mesh space: {positions, indices}.
 * Throws GeometryProblem.
 */
async function meshTriangles(ctx, m) {
  const mesh = ctx.json.meshes[m];
  const positions = [];
  const indices = [];
  let prims = 0;
  for (const [pi, p] of arr(mesh.primitives).entries()) {
    if (!isObject(p)) throw new GeometryProblem(`primitive ${pi} is not an object`);
    const mode = p.mode === undefined ? 4 : p.mode;
    if (mode !== 4 && mode !== 5 && mode !== 6) continue;  // points and lines have no area
    const where = `primitive ${pi}`;
    let xyz, idx;
    const compressed = (isObject(p.extensions) && has(p.extensions, 'KHR_draco_mesh_compression')) ||
      usesMeshopt(ctx, p.attributes?.POSITION) || (p.indices !== undefined && usesMeshopt(ctx, p.indices));
    if (compressed) {
      const d = ctx.decodedGeometry ? await ctx.decodedGeometry(m, pi) : null;
      if (!d || !d.positions) throw new GeometryProblem(`${where} is compressed (Draco or meshopt) and no decoded geometry was given`);
      xyz = d.positions instanceof Float32Array ? d.positions : Float32Array.from(d.positions);
      idx = d.indices ? Uint32Array.from(d.indices) : null;
    } else {
      if (!isObject(p.attributes) || p.attributes.POSITION === undefined) throw new GeometryProblem(`${where} has no POSITION`);
      xyz = readPositions(ctx, p.attributes.POSITION, where);
      idx = p.indices === undefined ? null : readIndices(ctx, p.indices, where, xyz.length / 3);
    }
    const count = xyz.length / 3;
    for (let i = 0; i < xyz.length; ++i)
      if (!Number.isFinite(xyz[i])) throw new GeometryProblem(`${where}: vertex ${i / 3 | 0} has a non-finite coordinate`);
    if (!idx) idx = Uint32Array.from({ length: count }, (_, i) => i);
    for (const v of idx) if (v >= count) throw new GeometryProblem(`${where}: index ${v} >= vertex count ${count}`);
    const base = positions.length / 3;
    for (const v of xyz) positions.push(v === 0 ? 0 : v);
    const tri = (a, b, c) => indices.push(base + a, base + b, base + c);
    if (mode === 4) for (let t = 0; t + 2 < idx.length; t += 3) tri(idx[t], idx[t + 1], idx[t + 2]);
    else if (mode === 5) for (let t = 0; t + 2 < idx.length; ++t) (t % 2 === 0 ? tri(idx[t], idx[t + 1], idx[t + 2]) : tri(idx[t + 1], idx[t], idx[t + 2]));
    else for (let t = 1; t + 1 < idx.length; ++t) tri(idx[0], idx[t], idx[t + 1]);
    ++prims;
  }
  if (prims === 0) throw new GeometryProblem('the mesh has no triangle primitive (points or lines only)');
  return dropZeroArea(Float32Array.from(positions), indices);
}

function usesMeshopt(ctx, accessor) {
  const a = ctx.json.accessors?.[accessor];
  const bv = isObject(a) ? ctx.json.bufferViews?.[a.bufferView] : undefined;
  return isObject(bv) && isObject(bv.extensions) &&
    (has(bv.extensions, 'EXT_meshopt_compression') || has(bv.extensions, 'KHR_meshopt_compression'));
}

/** The bytes an accessor covers, checked against its buffer, as the C++ importer's view(). */
function accessorView(ctx, index, elemSize, what) {
  const a = ctx.json.accessors?.[index];
  if (!isIndex(index) || !isObject(a)) throw new GeometryProblem(`${what}: accessor ${index} out of range`);
  if (a.sparse !== undefined) throw new GeometryProblem(`${what}: sparse accessors are not supported`);
  const bv = ctx.json.bufferViews?.[a.bufferView];
  if (!isIndex(a.bufferView) || !isObject(bv)) throw new GeometryProblem(`${what}: accessor has no valid bufferView`);
  const buf = ctx.buffers[bv.buffer];
  if (!buf || buf.bytes == null) throw new GeometryProblem(`${what}: bufferView ${a.bufferView} has no buffer data${buf?.error ? ' (' + buf.error + ')' : ''}`);
  const stride = bv.byteStride || elemSize;
  const count = Number.isInteger(a.count) && a.count >= 0 ? a.count : 0;
  const need = count === 0 ? 0 : stride * (count - 1) + elemSize;
  const vOff = bv.byteOffset ?? 0, vLen = bv.byteLength ?? 0, aOff = a.byteOffset ?? 0;
  if (!(vOff + vLen <= buf.bytes.length) || !(aOff + need <= vLen))
    throw new GeometryProblem(`${what}: accessor of ${count} elements (stride ${stride}) reaches outside its ${buf.bytes.length}-byte buffer`);
  const start = buf.bytes.byteOffset + vOff + aOff;
  return { dv: new DataView(buf.bytes.buffer, start, need), stride, count, a };
}

function readPositions(ctx, index, where) {
  const what = `${where} POSITION`;
  const a0 = ctx.json.accessors?.[index];
  const cs = isObject(a0) ? COMPONENT_SIZE[a0.componentType] ?? 4 : 4;
  const { dv, stride, count, a } = accessorView(ctx, index, 3 * cs, what);
  if (a.type !== 'VEC3') throw new GeometryProblem(`${what}: only VEC3 data is supported`);
  const ct = a.componentType;
  const norm = a.normalized === true;
  const readers = {
    5126: [(o) => dv.getFloat32(o, true), 1],
    5120: [(o) => dv.getInt8(o), 127],
    5121: [(o) => dv.getUint8(o), 255],
    5122: [(o) => dv.getInt16(o, true), 32767],
    5123: [(o) => dv.getUint16(o, true), 65535],
  };
  if (!readers[ct]) throw new GeometryProblem(`${what}: component type ${ct}${norm ? ' (normalized)' : ''} is not one that glTF or KHR_mesh_quantization allows for this attribute`);
  const [get, max] = readers[ct];
  const out = new Float32Array(3 * count);
  for (let i = 0; i < count; ++i)
    for (let c = 0; c < 3; ++c) {
      let f = get(i * stride + c * cs);
      if (ct !== 5126 && norm) f = Math.max(f / max, -1);
      out[3 * i + c] = f;
    }
  return out;
}

function readIndices(ctx, index, where, vertexCount) {
  const what = `${where} indices`;
  const a0 = ctx.json.accessors?.[index];
  const ct0 = isObject(a0) ? a0.componentType : 0;
  const es = ct0 === 5121 ? 1 : ct0 === 5123 ? 2 : 4;
  const { dv, stride, count, a } = accessorView(ctx, index, es, what);
  if (a.type !== 'SCALAR' || ![5121, 5123, 5125].includes(a.componentType))
    throw new GeometryProblem(`${what}: indices must be unsigned scalar integers`);
  const out = new Uint32Array(count);
  for (let i = 0; i < count; ++i) {
    const v = es === 1 ? dv.getUint8(i * stride) : es === 2 ? dv.getUint16(i * stride, true) : dv.getUint32(i * stride, true);
    if (v >= vertexCount) throw new GeometryProblem(`${what}: index ${v} >= vertex count ${vertexCount}`);
    out[i] = v;
  }
  return out;
}

/** Drops the triangles of exactly zero area (spec/format.md section 9); throws when none is left. */
function dropZeroArea(p, indices) {
  const kept = [];
  for (let t = 0; t < indices.length; t += 3) {
    const a = indices[t], b = indices[t + 1], c = indices[t + 2];
    const ux = p[3 * b] - p[3 * a], uy = p[3 * b + 1] - p[3 * a + 1], uz = p[3 * b + 2] - p[3 * a + 2];
    const vx = p[3 * c] - p[3 * a], vy = p[3 * c + 1] - p[3 * a + 1], vz = p[3 * c + 2] - p[3 * a + 2];
    const cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
    if (cx * cx + cy * cy + cz * cz !== 0) kept.push(a, b, c);
  }
  if (indices.length === 0) throw new GeometryProblem('the mesh has no triangles');
  if (kept.length === 0) throw new GeometryProblem(`all ${indices.length / 3} triangles have zero area`);
  return { positions: p, indices: Uint32Array.from(kept) };
}

/**
 * The canonical geometry hash of triangles (spec/format.md section 9, META vff.source.geometryHash):
 * XXH3-64 of the triangles as nine little-endian f32 each (-0 as +0), each rotated so that its
 * smallest vertex comes first, sorted. `positions` f32 x, y, z per vertex, `indices` three per
 * triangle (zero-area triangles already dropped). Needs `await initVff()` first.
 */
export function canonicalGeometryHash(positions, indices) {
  const n = indices.length / 3;
  const tris = new Float32Array(9 * n);
  const v = [[0, 0, 0], [0, 0, 0], [0, 0, 0]];
  const less = (x, y) => x[0] < y[0] || (x[0] === y[0] && (x[1] < y[1] || (x[1] === y[1] && x[2] < y[2])));
  for (let t = 0; t < n; ++t) {
    for (let k = 0; k < 3; ++k)
      for (let c = 0; c < 3; ++c) {
        const x = positions[3 * indices[3 * t + k] + c];
        v[k][c] = x === 0 ? 0 : x;
      }
    let first = 0;
    for (let k = 1; k < 3; ++k) if (less(v[k], v[first])) first = k;
    for (let k = 0; k < 3; ++k) for (let c = 0; c < 3; ++c) tris[9 * t + 3 * k + c] = v[(first + k) % 3][c];
  }
  const order = Uint32Array.from({ length: n }, (_, i) => i);
  order.sort((a, b) => {
    for (let i = 0; i < 9; ++i) {
      const x = tris[9 * a + i], y = tris[9 * b + i];
      if (x < y) return -1;
      if (x > y) return 1;
    }
    return 0;
  });
  const out = new Float32Array(9 * n);
  for (let t = 0; t < n; ++t) out.set(tris.subarray(9 * order[t], 9 * order[t] + 9), 9 * t);
  const bytes = new Uint8Array(out.buffer);
  if (new Uint8Array(new Uint16Array([1]).buffer)[0] !== 1) {  // a big-endian host: write little-endian
    const dv = new DataView(bytes.buffer);
    for (let i = 0; i < out.length; ++i) dv.setFloat32(4 * i, out[i], true);
  }
  return xxh3Hex(bytes);
}

/** Bounds (f32) of the vertices the triangles use. */
function triangleBounds(p, indices) {
  const min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
  for (const v of indices)
    for (let c = 0; c < 3; ++c) {
      const x = p[3 * v + c];
      if (x < min[c]) min[c] = x;
      if (x > max[c]) max[c] = x;
    }
  return { min, max };
}

// ---- Nodes --------------------------------------------------------------------------------------

function mul(a, b) {
  const r = new Array(16).fill(0);
  for (let c = 0; c < 4; ++c)
    for (let rr = 0; rr < 4; ++rr) {
      let s = 0;
      for (let k = 0; k < 4; ++k) s += a[k * 4 + rr] * b[c * 4 + k];
      r[c * 4 + rr] = s;
    }
  return r;
}

const IDENTITY = [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1];

function nodeMatrix(n) {
  const nums = (v, k) => (Array.isArray(v) && v.length === k && v.every((x) => typeof x === 'number') ? v : null);
  if (nums(n.matrix, 16)) return n.matrix.slice();
  const [tx, ty, tz] = nums(n.translation, 3) ?? [0, 0, 0];
  const [x, y, z, w] = nums(n.rotation, 4) ?? [0, 0, 0, 1];
  const s = nums(n.scale, 3) ?? [1, 1, 1];
  const r = [1 - 2 * (y * y + z * z), 2 * (x * y + z * w), 2 * (x * z - y * w),
    2 * (x * y - z * w), 1 - 2 * (x * x + z * z), 2 * (y * z + x * w),
    2 * (x * z + y * w), 2 * (y * z - x * w), 1 - 2 * (x * x + y * y)];
  const m = [...IDENTITY];
  for (let c = 0; c < 3; ++c) for (let rr = 0; rr < 3; ++rr) m[c * 4 + rr] = r[c * 3 + rr] * s[c];
  [m[12], m[13], m[14]] = [tx, ty, tz];
  return m;
}

/** Why a world matrix is not a similarity (a positive uniform scale times a rotation), or ''. */
function notSimilarity(m) {
  const a = [[m[0], m[4], m[8]], [m[1], m[5], m[9]], [m[2], m[6], m[10]]];
  const det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
    a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
  if (det < 0) return 'mirror';
  if (!(det > 0)) return 'non-uniform scale';
  const s = Math.cbrt(det);
  for (let i = 0; i < 3; ++i)
    for (let j = 0; j < 3; ++j) {
      let dot = 0;
      for (let k = 0; k < 3; ++k) dot += a[k][i] * a[k][j];
      if (Math.abs(dot - (i === j ? s * s : 0)) > 1e-5 * s * s) return 'non-uniform scale';
    }
  return '';
}

/**
 * The nodes of the scene read (the default scene, else scene 0; without scenes, the hierarchy from
 * every root) with their world matrices, depth first.
 */
function sceneNodes(json) {
  const nodes = arr(json.nodes);
  const scenes = arr(json.scenes);
  let roots;
  if (scenes.length) {
    const si = isIndex(json.scene) && json.scene < scenes.length ? json.scene : 0;
    roots = arr(scenes[si]?.nodes);
  } else {
    const child = new Set();
    for (const n of nodes) if (isObject(n)) for (const c of arr(n.children)) child.add(c);
    roots = nodes.map((_, i) => i).filter((i) => !child.has(i));
  }
  const out = [];
  const stack = roots.slice().reverse().map((node) => ({ node, parent: IDENTITY, depth: 0 }));
  while (stack.length) {
    const f = stack.pop();
    const n = nodes[f.node];
    if (!isIndex(f.node) || !isObject(n) || f.depth > 64) continue;
    const world = mul(f.parent, nodeMatrix(n));
    out.push({ node: f.node, world });
    for (const c of arr(n.children).slice().reverse()) stack.push({ node: c, parent: world, depth: f.depth + 1 });
  }
  return out;
}

function nodeReason(json, n, world) {
  if (has(n, 'skin')) return 'skin';
  const mesh = json.meshes[n.mesh];
  const targets = arr(mesh.primitives).some((p) => isObject(p) && arr(p.targets).length > 0);
  const w = Array.isArray(n.weights) ? n.weights : Array.isArray(mesh.weights) ? mesh.weights : [];
  if (targets && w.some((x) => typeof x !== 'number' || x !== 0)) return 'morph targets';
  return notSimilarity(world);
}

// ---- The reader ---------------------------------------------------------------------------------

/** Loads every buffer's bytes: {bytes} or {bytes: null, error}. */
async function loadBuffers(json, bin, glb, resolveUri) {
  const out = [];
  for (const [i, b] of arr(json.buffers).entries()) {
    let r;
    if (!isObject(b)) r = { error: 'not an object' };
    else if (b.uri === undefined) r = glb && i === 0 && bin ? { bytes: bin } : { error: glb && i === 0 ? 'the GLB has no BIN chunk' : 'the buffer has no uri' };
    else if (typeof b.uri !== 'string') r = { error: 'a uri that is not a string' };
    else if (/^data:/i.test(b.uri)) r = decodeDataUri(b.uri);
    else {
      const u = checkRelativeUri(b.uri);
      r = u.error ? u : await readUri(resolveUri, u.path);
    }
    if (r.bytes && Number.isInteger(b.byteLength)) {
      if (b.byteLength > r.bytes.length) r = { error: `byteLength ${b.byteLength}, the data has ${r.bytes.length} bytes` };
      else r = { bytes: r.bytes.subarray(0, b.byteLength) };
    }
    out.push({ bytes: r.bytes ?? null, error: r.error ?? '' });
  }
  return out;
}

/** Checks the members' JSON types and values (14004); '' or [member, message]. */
function extensionValueProblem(ext) {
  const shown = (v) => JSON.stringify(v) ?? String(v);
  if (!isObject(ext)) return ['', `the extension value is ${shown(ext)}, not an object`];
  if (has(ext, 'bufferView') && !(isIndex(ext.bufferView) && ext.bufferView <= 0x7fffffff))
    return ['bufferView', `bufferView is ${shown(ext.bufferView)}, not an integer >= 0`];
  for (const k of ['uri', 'mimeType', 'geometryHash'])
    if (has(ext, k) && typeof ext[k] !== 'string') return [k, `${k} is ${shown(ext[k])}, not a string`];
  if (!has(ext, 'geometryHash')) return ['geometryHash', 'geometryHash is missing'];
  if (!/^[0-9a-f]{16}$/.test(ext.geometryHash)) return ['geometryHash', `geometryHash '${ext.geometryHash}' is not 16 lowercase hex digits`];
  for (const k of ['min', 'max']) {
    if (!has(ext, k)) return [k, `${k} is missing`];
    const v = ext[k];
    if (!Array.isArray(v) || v.length !== 3 || !v.every((x) => typeof x === 'number' && Number.isFinite(Math.fround(x))))
      return [k, `${k} is ${shown(v)}, not 3 finite numbers`];
  }
  for (let c = 0; c < 3; ++c)
    if (Math.fround(ext.min[c]) > Math.fround(ext.max[c])) return ['min', `min[${c}] ${Math.fround(ext.min[c])} > max[${c}] ${Math.fround(ext.max[c])}`];
  return '';
}

/**
 * Reads the VFF_visibility_field extension of a .gltf or .glb held in memory, checking it against
 * rules 14001-14011 and matching each field (14101-14104). File-level problems (14001-14003) end the
 * check; each mesh stops at its first error. Never throws on bad input.
 * @param {Uint8Array|ArrayBuffer} data
 * @param {{resolveUri?: Function, decodedGeometry?: Function, checkGeometry?: boolean}} [options]
 * @returns {Promise<{meshCount: number, fields: object[], problems: object[]}>}
 */
export async function readGltfFields(data, options = {}) {
  const bytes = data instanceof Uint8Array ? data : new Uint8Array(data);
  let parsed;
  try {
    parsed = parseContainer(bytes);
  } catch (e) {
    if (!(e instanceof FileProblem)) throw e;
    const report = { meshCount: 0, fields: [], problems: [] };
    report.problems.push({ rule: 14001, name: GLTF_RULE_NAMES[14001], severity: 'error', path: e.path, message: e.message });
    return report;
  }
  return readParsedGltfFields(parsed, options);
}

/**
 * readGltfFields on an asset already parsed (a loader's): `json` the glTF JSON, `bin` the .glb's BIN
 * chunk (Uint8Array, or null), `glb` whether the asset came as a .glb (its buffer 0 without uri is
 * the BIN chunk). Runs the rules from 14002 on; the same report.
 * @param {{json: object, bin: Uint8Array|null, glb: boolean}} parsed
 */
export async function readParsedGltfFields({ json, bin = null, glb = false }, options = {}) {
  await initChecksums();
  const { resolveUri = null, decodedGeometry = null, checkGeometry = true } = options;
  const report = { meshCount: 0, fields: [], problems: [] };
  const problem = (rule, path, message, extra = {}) =>
    report.problems.push({ rule, name: GLTF_RULE_NAMES[rule], severity: SEVERITY[rule] ?? 'error', path, message, ...extra });
  const meshes = arr(json.meshes);
  report.meshCount = meshes.length;
  if (arr(json.extensionsRequired).includes(GLTF_FIELD_EXTENSION)) {
    problem(14002, '/extensionsRequired', `${GLTF_FIELD_EXTENSION} is listed in extensionsRequired; a field is optional to engines`);
    return report;
  }
  const carrying = [];
  meshes.forEach((m, i) => { if (isObject(m) && isObject(m.extensions) && has(m.extensions, GLTF_FIELD_EXTENSION)) carrying.push(i); });
  if (carrying.length && !arr(json.extensionsUsed).includes(GLTF_FIELD_EXTENSION)) {
    problem(14003, '/extensionsUsed', `mesh ${carrying[0]} carries ${GLTF_FIELD_EXTENSION} but extensionsUsed does not list it`);
    return report;
  }
  if (!carrying.length) return report;

  const buffers = await loadBuffers(json, bin, glb, resolveUri);
  const ctx = { json, buffers, decodedGeometry };
  const instances = sceneNodes(json);

  for (const m of carrying) {
    const mesh = meshes[m];
    const ext = mesh.extensions[GLTF_FIELD_EXTENSION];
    const path = `/meshes/${m}/extensions/${GLTF_FIELD_EXTENSION}`;
    const field = {
      mesh: m, meshName: typeof mesh.name === 'string' ? mesh.name : '', path, bufferView: -1, uri: '',
      geometryHash: '', min: [0, 0, 0], max: [0, 0, 0], bytes: null, valid: false, match: 'unchecked',
      meshGeometryHash: '', meshMin: [0, 0, 0], meshMax: [0, 0, 0], tolerance: 0, boundsDifference: 0, nodes: [],
      usable: false,
    };
    report.fields.push(field);
    for (const inst of instances) {
      const n = arr(json.nodes)[inst.node];
      if (n.mesh !== m) continue;
      const reason = nodeReason(json, n, inst.world);
      field.nodes.push({ node: inst.node, name: typeof n.name === 'string' ? n.name : '', answered: !reason, reason });
    }
    const fail = (rule, suffix, message, extra) => { problem(rule, path + suffix, message, extra); };

    const bad = extensionValueProblem(ext);
    if (bad) { fail(14004, bad[0] ? '/' + bad[0] : '', bad[1]); continue; }
    field.geometryHash = ext.geometryHash;
    field.min = ext.min.map(Math.fround);
    field.max = ext.max.map(Math.fround);
    const hasView = has(ext, 'bufferView'), hasUri = has(ext, 'uri');
    if (hasView === hasUri) {
      fail(14005, '', hasView ? 'both bufferView and uri are given' : 'neither bufferView nor uri is given');
      continue;
    }
    let payload;
    if (hasView) {
      field.bufferView = ext.bufferView;
      const bv = arr(json.bufferViews)[ext.bufferView];
      const at = '/bufferView';
      if (!isObject(bv)) { fail(14006, at, `bufferView ${ext.bufferView} does not exist (the file has ${arr(json.bufferViews).length})`); continue; }
      if (bv.byteStride !== undefined) { fail(14006, at, `bufferView ${ext.bufferView} has a byteStride`); continue; }
      const buf = isIndex(bv.buffer) ? buffers[bv.buffer] : undefined;
      if (!buf) { fail(14006, at, `bufferView ${ext.bufferView} names buffer ${bv.buffer}, which does not exist`); continue; }
      if (!buf.bytes) { fail(14006, at, `buffer ${bv.buffer} has no data: ${buf.error}`); continue; }
      const off = bv.byteOffset ?? 0, len = bv.byteLength;
      if (!isIndex(off) || !isIndex(len) || off + len > buf.bytes.length) {
        fail(14006, at, `bufferView ${ext.bufferView} (offset ${off}, ${len} bytes) lies outside its ${buf.bytes.length}-byte buffer`);
        continue;
      }
      payload = buf.bytes.subarray(off, off + len);
    } else {
      field.uri = ext.uri;
      const at = '/uri';
      let r;
      if (/^data:/i.test(ext.uri)) {
        r = decodeDataUri(ext.uri);
        if (r.error) { fail(14007, at, r.error); continue; }
      } else {
        const u = checkRelativeUri(ext.uri);
        if (u.error) { fail(14007, at, u.error); continue; }
        r = await readUri(resolveUri, u.path);
        if (r.error) { fail(14007, at, r.error, { ioError: true }); continue; }
      }
      payload = r.bytes;
    }
    if (hasView && !has(ext, 'mimeType')) { fail(14008, '', `mimeType is required with bufferView (${VFF_MEDIA_TYPE})`); continue; }
    if (has(ext, 'mimeType') && ext.mimeType !== VFF_MEDIA_TYPE) {
      fail(14008, '/mimeType', `mimeType "${ext.mimeType}", expected "${VFF_MEDIA_TYPE}"`);
      continue;
    }
    let file;
    try {
      file = openVff(payload);
      file.validateDeep();
    } catch (e) {
      if (!(e instanceof VffError)) throw e;
      fail(14009, '', `the payload (${payload.length} bytes) is not a valid .vff: ${e.codeName} (${e.id}): ${e.detail}`);
      continue;
    }
    const meta = file.metadata?.value;
    if (isObject(meta) && has(meta, 'vff.partial')) {
      fail(14009, '', 'the payload is a partial result (META has vff.partial), not a whole field');
      continue;
    }
    const source = isObject(meta) && isObject(meta['vff.source']) ? meta['vff.source'] : {};
    if (has(source, 'geometryHash') && source.geometryHash !== ext.geometryHash) {
      fail(14010, '/geometryHash', `geometryHash '${ext.geometryHash}' differs from the payload's META vff.source.geometryHash ${JSON.stringify(source.geometryHash)}`);
      continue;
    }
    field.bytes = payload;
    field.tolerance = (2 * file.field.sphere.radius) / 255;
    if (checkGeometry) {
      let tris;
      try {
        tris = await meshTriangles(ctx, m);
      } catch (e) {
        if (!(e instanceof GeometryProblem)) throw e;
        problem(14011, `/meshes/${m}`, `${e.message}: the field cannot be matched`);
        field.bytes = null;
        continue;
      }
      field.meshGeometryHash = canonicalGeometryHash(tris.positions, tris.indices);
      const b = triangleBounds(tris.positions, tris.indices);
      field.meshMin = b.min;
      field.meshMax = b.max;
      let diff = 0;
      for (let c = 0; c < 3; ++c) diff = Math.max(diff, Math.abs(b.min[c] - field.min[c]), Math.abs(b.max[c] - field.max[c]));
      field.boundsDifference = diff;
      const figures = `the largest bound difference is ${diff}, tau = 2R/255 = ${field.tolerance}`;
      const hashes = `mesh ${m}'s triangles hash to ${field.meshGeometryHash}, not ${ext.geometryHash}`;
      if (field.meshGeometryHash === ext.geometryHash) field.match = 'exact';
      else if (diff <= field.tolerance) {
        field.match = 'close';
        problem(14102, path, `${hashes}, but its bounds are within one distance step: the field is used (${figures})`);
      } else {
        field.match = 'mismatch';
        problem(14103, path, `${hashes}, and its bounds differ by more than one distance step: the field is not used (${figures})`);
      }
    }
    field.valid = true;
    field.usable = field.match === 'exact' || field.match === 'close';
    for (const n of field.nodes) {
      if (n.answered) continue;
      const what = n.reason === 'skin' ? 'a skin' : n.reason === 'mirror' ? 'a mirroring transform'
        : n.reason === 'morph targets' ? 'morph targets with weights not all zero' : `a transform that is not a similarity (${n.reason})`;
      problem(14104, `/nodes/${n.node}`, `node ${n.node}${n.name ? ` '${n.name}'` : ''} uses mesh ${m} but has ${what}: no field answers for it`);
    }
  }
  return report;
}
