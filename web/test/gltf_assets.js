// gltf_assets.js - glTF assets with VFF_visibility_field for the gltf_* tests, made with
// glTF-Transform and the project's conformance vectors (no other tool needed), and GLB editing.
import { readFileSync } from 'node:fs';
import { join, dirname } from 'node:path';
import { fileURLToPath } from 'node:url';
import { Document, Logger, NodeIO } from '@gltf-transform/core';
import { ALL_EXTENSIONS } from '@gltf-transform/extensions';
import draco3d from 'draco3dgltf';
import { MeshoptDecoder, MeshoptEncoder } from 'meshoptimizer';
import { VffVisibilityField, meshGeometry } from '../src/gltf_transform_vff.js';
import { openVff } from '../src/vff.js';

export const ROOT = join(dirname(fileURLToPath(import.meta.url)), '..', '..');
export const EXT = 'VFF_visibility_field';

/** A whole valid field without META (spec/conformance/valid/u8d-stored.vff) and its R. */
export function vectorPayload() {
  const bytes = new Uint8Array(readFileSync(join(ROOT, 'spec', 'conformance', 'valid', 'u8d-stored.vff')));
  return { bytes, radius: openVff(bytes).field.sphere.radius };
}

/** A logger that keeps the warnings. */
export class KeepLogger extends Logger {
  constructor() {
    super(Logger.Verbosity.WARN);
    this.warnings = [];
  }
  warn(text) { this.warnings.push(text); }
}

/** NodeIO with every Khronos/EXT extension (Draco and meshopt codecs loaded) and, by default, ours. */
export async function makeIO({ vff = true, logger = null } = {}) {
  const io = new NodeIO()
    .registerExtensions(vff ? [...ALL_EXTENSIONS, VffVisibilityField] : ALL_EXTENSIONS)
    .registerDependencies({
      'draco3d.decoder': await draco3d.createDecoderModule(),
      'draco3d.encoder': await draco3d.createEncoderModule(),
      'meshopt.decoder': MeshoptDecoder,
      'meshopt.encoder': MeshoptEncoder,
    });
  await MeshoptDecoder.ready;
  await MeshoptEncoder.ready;
  if (logger) io.setLogger(logger);
  return io;
}

// A box of 12 triangles (24 vertices, as flat-shaded exports have) around the origin.
const BOX_POSITIONS = (() => {
  const out = [];
  const s = [0.5, 0.3, 0.2];
  for (let axis = 0; axis < 3; ++axis)
    for (const sign of [-1, 1]) {
      const u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (const [a, b] of [[-1, -1], [1, -1], [1, 1], [-1, 1]]) {
        const p = [0, 0, 0];
        p[axis] = sign * s[axis];
        p[u] = a * s[u];
        p[v] = b * s[v] * sign;
        out.push(...p);
      }
    }
  return new Float32Array(out);
})();
const BOX_INDICES = new Uint16Array(Array.from({ length: 6 }, (_, f) => [0, 1, 2, 0, 2, 3].map((i) => 4 * f + i)).flat());

/**
 * A document of `meshes` boxes (mesh i offset by i along x), each used by a node, with
 * every mesh's field from `payload` (geometryHash and bounds computed from the mesh).
 */
export function boxDocument({ meshes = 1, payload = vectorPayload().bytes, fields = true, nodes = null } = {}) {
  const doc = new Document();
  const buffer = doc.createBuffer();
  const scene = doc.createScene('main');
  doc.getRoot().setDefaultScene(scene);
  const ext = doc.createExtension(VffVisibilityField);
  for (let i = 0; i < meshes; ++i) {
    const p = BOX_POSITIONS.map((x, k) => (k % 3 === 0 ? x + i : x));
    const pos = doc.createAccessor().setType('VEC3').setArray(new Float32Array(p)).setBuffer(buffer);
    const ind = doc.createAccessor().setType('SCALAR').setArray(BOX_INDICES.slice()).setBuffer(buffer);
    const mesh = doc.createMesh(`box${i}`).addPrimitive(doc.createPrimitive().setAttribute('POSITION', pos).setIndices(ind));
    if (fields) attachField(doc, mesh, i ? payload.slice() : payload, ext);  // a bufferView each
    const node = doc.createNode(`box${i}`).setMesh(mesh);
    if (nodes?.[i]) nodes[i](node);
    scene.addChild(node);
  }
  return doc;
}

/** Attaches `payload` to `mesh`, declaring the mesh's current geometry. */
export function attachField(doc, mesh, payload, ext = doc.createExtension(VffVisibilityField)) {
  const g = meshGeometry(mesh);
  mesh.setExtension(EXT, ext.createVisibilityField().setPayload(payload).setGeometryHash(g.geometryHash).setMin(g.min).setMax(g.max));
}

/** {json, bin} of a GLB. */
export function splitGlb(glb) {
  const dv = new DataView(glb.buffer, glb.byteOffset, glb.byteLength);
  const jsonLength = dv.getUint32(12, true);
  const json = JSON.parse(new TextDecoder().decode(glb.subarray(20, 20 + jsonLength)));
  const at = 20 + jsonLength;
  const bin = at + 8 <= glb.length ? glb.slice(at + 8, at + 8 + dv.getUint32(at, true)) : null;
  return { json, bin };
}

/** A GLB of `json` and `bin` (null: no binary chunk), chunks padded to 4 bytes. */
export function packGlb(json, bin) {
  let text = new TextEncoder().encode(JSON.stringify(json));
  const pad = (b, fill) => {
    const out = new Uint8Array(Math.ceil(b.length / 4) * 4).fill(fill);
    out.set(b);
    return out;
  };
  text = pad(text, 0x20);
  const binP = bin ? pad(bin, 0) : null;
  const total = 12 + 8 + text.length + (binP ? 8 + binP.length : 0);
  const out = new Uint8Array(total);
  const dv = new DataView(out.buffer);
  dv.setUint32(0, 0x46546c67, true);
  dv.setUint32(4, 2, true);
  dv.setUint32(8, total, true);
  dv.setUint32(12, text.length, true);
  dv.setUint32(16, 0x4e4f534a, true);
  out.set(text, 20);
  if (binP) {
    const at = 20 + text.length;
    dv.setUint32(at, binP.length, true);
    dv.setUint32(at + 4, 0x004e4942, true);
    out.set(binP, at + 8);
  }
  return out;
}

/** The GLB with its JSON changed by edit(json, bin) (which may return a new bin). */
export function editGlb(glb, edit) {
  const { json, bin } = splitGlb(glb);
  const newBin = edit(json, bin);
  return packGlb(json, newBin === undefined ? bin : newBin);
}

/** The bytes of bufferView `v` of a GLB. */
export function viewBytes(glb, v) {
  const { json, bin } = splitGlb(glb);
  const bv = json.bufferViews[v];
  return bin.subarray(bv.byteOffset ?? 0, (bv.byteOffset ?? 0) + bv.byteLength);
}
