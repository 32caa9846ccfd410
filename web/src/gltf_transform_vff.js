// gltf_transform_vff.js - VFF_visibility_field for glTF-Transform (@gltf-transform/core 4): the
// extension's payloads survive a read, transforms and a write.
//
//   import { NodeIO } from '@gltf-transform/core';
//   import { VffVisibilityField } from './src/gltf_transform_vff.js';
//   const io = new NodeIO().registerExtensions([VffVisibilityField]);
//   const doc = await io.read('scene.glb');
//   const field = doc.getRoot().listMeshes()[0].getExtension('VFF_visibility_field');
//   field.getPayload();        // the .vff file's bytes, untouched
//   await io.write('out.glb', doc);
//
// A field belongs to its mesh's own space (spec/gltf/VFF_visibility_field/README.md). A transform
// that moves the mesh's vertices (quantize, which re-frames positions into the node transform, or
// any edit) makes the field answer for another shape: on write each mesh's triangles are bounded
// as a reader bounds them and compared with the field's min/max, within tau = 2R/255 (R: the
// payload's sphere radius, one distance step). Beyond it the field is dropped, with a logger
// warning naming the mesh and rule 14103 (gltf-geometry-mismatch) - the rule a reader would apply.
// Within it the field is kept (a Draco re-encode moves vertices by less).
//
// Payloads referenced by a relative `uri` are kept as that uri (no bytes, no check); `data:` uris
// are decoded and written as a bufferView.
import { Extension, ExtensionProperty, PropertyType } from '@gltf-transform/core';
import { GLTF_FIELD_EXTENSION, VFF_MEDIA_TYPE, canonicalGeometryHash, decodeDataUri } from './gltf_fields.js';
import { initChecksums } from './checksum.js';
import { openVff } from './container.js';

await initChecksums();  // openVff checks the header's checksum; write() is synchronous

/** One mesh's field: the .vff bytes (or a uri), the geometry hash and the bounds it was baked from. */
export class VisibilityField extends ExtensionProperty {
  static EXTENSION_NAME = GLTF_FIELD_EXTENSION;
  init() {
    this.extensionName = GLTF_FIELD_EXTENSION;
    this.propertyType = 'VisibilityField';
    this.parentTypes = [PropertyType.MESH];
  }
  getDefaults() {
    return Object.assign(super.getDefaults(), { payload: null, uri: '', geometryHash: '', min: [0, 0, 0], max: [0, 0, 0] });
  }
  /** The complete .vff file (Uint8Array), or null for a field referenced by a relative uri. */
  getPayload() { return this.get('payload'); }
  setPayload(bytes) { return this.set('payload', bytes); }
  getUri() { return this.get('uri'); }
  setUri(uri) { return this.set('uri', uri); }
  getGeometryHash() { return this.get('geometryHash'); }
  setGeometryHash(h) { return this.set('geometryHash', h); }
  getMin() { return this.get('min'); }
  setMin(v) { return this.set('min', v); }
  getMax() { return this.get('max'); }
  setMax(v) { return this.set('max', v); }
}

/**
 * The triangles of a gltf-transform Mesh as a reader of the extension takes them: every primitive of
 * mode 4, 5 or 6, POSITION as read (normalized integers converted), in mesh space, zero-area
 * triangles dropped: {positions: Float32Array, indices: Uint32Array}.
 */
export function meshTriangles(mesh) {
  const positions = [];
  const kept = [];
  for (const prim of mesh.listPrimitives()) {
    const mode = prim.getMode();
    const pos = prim.getAttribute('POSITION');
    if ((mode !== 4 && mode !== 5 && mode !== 6) || !pos) continue;
    const base = positions.length / 3;
    const n = pos.getCount();
    const e = [0, 0, 0];
    for (let i = 0; i < n; ++i) for (const x of pos.getElement(i, e)) positions.push(Math.fround(x) === 0 ? 0 : Math.fround(x));
    const ind = prim.getIndices();
    const idx = ind ? ind.getArray() : Uint32Array.from({ length: n }, (_, i) => i);
    const tri = (a, b, c) => kept.push(base + a, base + b, base + c);
    if (mode === 4) for (let t = 0; t + 2 < idx.length; t += 3) tri(idx[t], idx[t + 1], idx[t + 2]);
    else if (mode === 5) for (let t = 0; t + 2 < idx.length; ++t) (t % 2 === 0 ? tri(idx[t], idx[t + 1], idx[t + 2]) : tri(idx[t + 1], idx[t], idx[t + 2]));
    else for (let t = 1; t + 1 < idx.length; ++t) tri(idx[0], idx[t], idx[t + 1]);
  }
  const p = Float32Array.from(positions);
  const indices = [];
  for (let t = 0; t < kept.length; t += 3) {
    const [a, b, c] = [kept[t], kept[t + 1], kept[t + 2]];
    const ux = p[3 * b] - p[3 * a], uy = p[3 * b + 1] - p[3 * a + 1], uz = p[3 * b + 2] - p[3 * a + 2];
    const vx = p[3 * c] - p[3 * a], vy = p[3 * c + 1] - p[3 * a + 1], vz = p[3 * c + 2] - p[3 * a + 2];
    const cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
    if (cx * cx + cy * cy + cz * cz !== 0) indices.push(a, b, c);
  }
  return { positions: p, indices: Uint32Array.from(indices) };
}

/** Bounds of the vertices the triangles use, or null when there are none. */
export function meshTriangleBounds(mesh) {
  const { positions: p, indices } = meshTriangles(mesh);
  if (!indices.length) return null;
  const min = [Infinity, Infinity, Infinity], max = [-Infinity, -Infinity, -Infinity];
  for (const v of indices)
    for (let k = 0; k < 3; ++k) {
      min[k] = Math.min(min[k], p[3 * v + k]);
      max[k] = Math.max(max[k], p[3 * v + k]);
    }
  return { min, max };
}

/**
 * What the extension declares of a mesh: {geometryHash, min, max} of its triangles (the canonical
 * hash of spec/format.md section 9, as vff-bake writes to META), or null without triangles.
 */
export function meshGeometry(mesh) {
  const t = meshTriangles(mesh);
  const b = meshTriangleBounds(mesh);
  return b ? { geometryHash: canonicalGeometryHash(t.positions, t.indices), ...b } : null;
}

/**
 * The geometry of a primitive of `document` (read by gltf-transform, which decodes Draco and meshopt
 * when their decoders are registered), as readGltfFields's `decodedGeometry` option takes it. The
 * document must have been read from the same bytes (gltf-transform keeps mesh and primitive order).
 */
export function decodedGeometryFrom(document) {
  const meshes = document.getRoot().listMeshes();
  return (m, p) => {
    const prim = meshes[m]?.listPrimitives()[p];
    const pos = prim?.getAttribute('POSITION');
    if (!pos) return null;
    const n = pos.getCount();
    const positions = new Float32Array(3 * n);
    const e = [0, 0, 0];
    for (let i = 0; i < n; ++i) positions.set(pos.getElement(i, e), 3 * i);
    const ind = prim.getIndices();
    return { positions, indices: ind ? Uint32Array.from(ind.getArray()) : null, mode: prim.getMode() };
  };
}

/** The extension for glTF-Transform: register it with `io.registerExtensions([VffVisibilityField])`. */
export class VffVisibilityField extends Extension {
  static EXTENSION_NAME = GLTF_FIELD_EXTENSION;
  extensionName = GLTF_FIELD_EXTENSION;
  prewriteTypes = [PropertyType.BUFFER];

  /** A new field, to attach with mesh.setExtension('VFF_visibility_field', field). */
  createVisibilityField() { return new VisibilityField(this.document.getGraph()); }

  read(context) {
    const json = context.jsonDoc.json;
    (json.meshes || []).forEach((meshDef, i) => {
      const def = meshDef.extensions?.[GLTF_FIELD_EXTENSION];
      if (!def || typeof def !== 'object') return;
      const field = this.createVisibilityField()
        .setGeometryHash(def.geometryHash ?? '')
        .setMin(Array.isArray(def.min) ? def.min.slice() : [0, 0, 0])
        .setMax(Array.isArray(def.max) ? def.max.slice() : [0, 0, 0]);
      if (Number.isInteger(def.bufferView) && context.bufferViews[def.bufferView]) {
        field.setPayload(context.bufferViews[def.bufferView].slice());
      } else if (typeof def.uri === 'string' && /^data:/i.test(def.uri)) {
        const d = decodeDataUri(def.uri);
        if (d.error) { this.document.getLogger().warn(`${GLTF_FIELD_EXTENSION}: mesh ${i}: ${d.error}; the field is dropped`); return; }
        field.setPayload(d.bytes);
      } else if (typeof def.uri === 'string') {
        field.setUri(def.uri);
      } else {
        this.document.getLogger().warn(`${GLTF_FIELD_EXTENSION}: mesh ${i} has neither a bufferView nor a uri; the field is dropped`);
        return;
      }
      context.meshes[i].setExtension(GLTF_FIELD_EXTENSION, field);
    });
    return this;
  }

  /** The fields written by this write: mesh -> field, after the bounds check. */
  #kept = new Map();

  prewrite(context, propertyType) {
    if (propertyType !== PropertyType.BUFFER) return this;
    this.#kept = new Map();
    const logger = this.document.getLogger();
    const buffer = this.document.getRoot().listBuffers()[0];
    const views = [];
    this.document.getRoot().listMeshes().forEach((mesh, i) => {
      const field = mesh.getExtension(GLTF_FIELD_EXTENSION);
      if (!field) return;
      const payload = field.getPayload();
      if (payload) {
        const why = this.#mismatch(mesh, field, payload);
        if (why) {
          logger.warn(`${GLTF_FIELD_EXTENSION}: mesh ${i}${mesh.getName() ? ` '${mesh.getName()}'` : ''}: ` +
            `gltf-geometry-mismatch (14103): ${why}; the field is dropped`);
          return;
        }
        if (!views.includes(payload)) views.push(payload);
      }
      this.#kept.set(mesh, field);
    });
    if (views.length) {
      if (!buffer) throw new Error(`${GLTF_FIELD_EXTENSION}: the document has no buffer for the payloads`);
      const list = context.otherBufferViews.get(buffer) || [];
      list.push(...views);
      context.otherBufferViews.set(buffer, list);
    }
    return this;
  }

  /** Why the mesh no longer matches the field's bounds, or ''. */
  #mismatch(mesh, field, payload) {
    let R;
    try {
      R = openVff(payload, { checksums: 'none' }).field.sphere.radius;
    } catch (e) {
      return `the payload is not a valid .vff (${e.message})`;
    }
    const b = meshTriangleBounds(mesh);
    if (!b) return 'the mesh has no triangles';
    const tau = (2 * R) / 255;
    let diff = 0;
    for (let c = 0; c < 3; ++c)
      diff = Math.max(diff, Math.abs(b.min[c] - Math.fround(field.getMin()[c])), Math.abs(b.max[c] - Math.fround(field.getMax()[c])));
    return diff <= tau ? '' : `the mesh's bounds differ from the field's by ${diff}, beyond tolerance ${tau} (2R/255)`;
  }

  write(context) {
    const json = context.jsonDoc.json;
    for (const [mesh, field] of this.#kept) {
      const meshDef = json.meshes[context.meshIndexMap.get(mesh)];
      const def = {};
      const payload = field.getPayload();
      if (payload) {
        def.bufferView = context.otherBufferViewsIndexMap.get(payload);
        def.mimeType = VFF_MEDIA_TYPE;
      } else {
        def.uri = field.getUri();
      }
      def.geometryHash = field.getGeometryHash();
      def.min = field.getMin().slice();
      def.max = field.getMax().slice();
      meshDef.extensions = meshDef.extensions || {};
      meshDef.extensions[GLTF_FIELD_EXTENSION] = def;
    }
    if (this.#kept.size === 0 && Array.isArray(json.extensionsUsed)) {
      // Every field was dropped: the extension is no longer used.
      json.extensionsUsed = json.extensionsUsed.filter((n) => n !== GLTF_FIELD_EXTENSION);
      if (!json.extensionsUsed.length) delete json.extensionsUsed;
    }
    this.#kept = new Map();
    return this;
  }
}
