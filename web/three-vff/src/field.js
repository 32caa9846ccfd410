// field.js - VffField: one .vff as three.js textures and uniforms for the GLSL ES query
// (web/src/vff_query_es.js, generated from gpu/glsl/vff_query.glsl). The field is in the space it
// was baked in: for a glTF mesh, that mesh's local space.
//
//   const field = await VffField.fromBytes(bytes, { name: 'bunny.vff' });  // throws VffError
//   field.upload(renderer);
//   new THREE.ShaderMaterial({ glslVersion: THREE.GLSL3, defines: field.defines,
//     uniforms: { ...field.uniforms }, fragmentShader: field.glsl + myCode });
//   // myCode calls vffOccluded(origin, direction, tmin, tmax, VFF_OFF_OBJECT) etc. in field space.
import * as THREE from 'three';
import { VFF_QUERY_GLSL_ES } from '../../src/vff_query_es.js';
import { contextLimits } from '../../src/gpu.js';
import { decodeVff, textureDataOf } from './decode.js';

// The query reads its field through VFF_FIELD; a struct uniform stands in for the std140 block
// (three.js fills struct members by name, uints included).
export const FIELD_STRUCT = `struct VffFieldData {
  vec3 sphereCenter; float sphereRadius;
  uint positionScheme; uint positionParam; uint mapCount; uint directionScheme;
  uint mapResolution; uint distanceEncoding; uint missCode; uint normalEncoding;
  uint target; uint gutter; uint tileSize; uint tilesPerRow; uint tilesPerColumn;
  uint sliceWidth; uint sliceHeight; uint sliceCount;
  float intraBias; float distanceScale; float invRadius; float twoRadius;
  uint neighbourOffset; float kernelRadius2;
};
uniform VffFieldData vffField;
#define VFF_FIELD vffField
`;

/** The GLSL ES source of the query with its field uniform, for any field. */
export const FIELD_GLSL = `precision highp float;\nprecision highp int;\n${FIELD_STRUCT}${VFF_QUERY_GLSL_ES}\n`;

// The field's parameters that specialisedGlsl writes in as constants: those that choose a branch.
// Sizes stay uniforms, so fields that differ only in size share one compiled program.
const SPECIALISED = ['positionScheme', 'directionScheme', 'distanceEncoding', 'missCode', 'normalEncoding'];

/**
 * FIELD_GLSL (or `src`) specialised to one field: every `VFF_FIELD.<parameter>` that chooses a
 * scheme or an encoding becomes the value in `value` (the vffField uniform's value). The compiler then
 * drops the schemes and encodings the field does not use, which software renderers (SwiftShader)
 * otherwise run, masked, on every lookup. What `field.glsl` holds.
 */
export function specialisedGlsl(value, src = FIELD_GLSL) {
  for (const name of SPECIALISED) src = src.replaceAll(`VFF_FIELD.${name}`, `${value[name] >>> 0}u`);
  return src;
}

const UINTS = ['positionScheme', 'positionParam', 'mapCount', 'directionScheme', 'mapResolution', 'distanceEncoding',
  'missCode', 'normalEncoding', 'target', 'gutter', 'tileSize', 'tilesPerRow', 'tilesPerColumn', 'sliceWidth',
  'sliceHeight', 'sliceCount'];

/** The std140 VffFieldBlock (query_tables.js) as the struct uniform's value. */
export function blockValue(block) {
  const F = new Float32Array(block), U = new Uint32Array(block);
  const v = { sphereCenter: new THREE.Vector3(F[0], F[1], F[2]), sphereRadius: F[3] };
  UINTS.forEach((name, i) => { v[name] = U[4 + i]; });
  Object.assign(v, { intraBias: F[20], distanceScale: F[21], invRadius: F[22], twoRadius: F[23], neighbourOffset: U[24], kernelRadius2: F[25] });
  return v;
}

const FORMATS = {
  r8ui: { format: THREE.RedIntegerFormat, type: THREE.UnsignedByteType, internal: 'R8UI' },
  r16ui: { format: THREE.RedIntegerFormat, type: THREE.UnsignedShortType, internal: 'R16UI' },
  rg16i: { format: THREE.RGIntegerFormat, type: THREE.ShortType, internal: 'RG16I' },
};

function planeTexture(p, is3d) {
  const f = FORMATS[p.format];
  const t = is3d ? new THREE.Data3DTexture(p.data, p.width, p.height, p.layers) : new THREE.DataArrayTexture(p.data, p.width, p.height, p.layers);
  t.format = f.format;
  t.type = f.type;
  t.internalFormat = f.internal;
  t.minFilter = t.magFilter = THREE.NearestFilter;
  t.generateMipmaps = false;
  t.unpackAlignment = 1;
  t.flipY = false;
  t.needsUpdate = true;
  return t;
}

export class VffField {
  /**
   * Decodes and checks a .vff (every block, spec/validation.md); throws the decoder's VffError.
   * options: {name, limits, onProgress} (decode.js).
   */
  static async fromBytes(bytes, options = {}) {
    const { file, data } = await decodeVff(bytes, options);
    return new VffField(data, { name: options.name, file });
  }

  /** A field from decodeInWorker's (or decodeVff's) data; options.file: the opened file, if any. */
  static fromDecoded(data, options = {}) {
    return new VffField(data, options);
  }

  constructor(data, { name = '', file = null } = {}) {
    this.name = name;
    this.file = file;
    this.data = data;
    this.layout = data.layout;
    this.note = data.note ?? null;
    const fd = data.field;
    this.center = new THREE.Vector3(...fd.sphere.center);
    this.radius = fd.sphere.radius;
    this.textures = null;
    this.uniforms = {
      vffField: { value: blockValue(data.textures.block) },
      vffMaps: { value: null },
      vffNormals: { value: null },
      vffPositionsTex: { value: null },
    };
    this.defines = Object.fromEntries(data.textures.defines.map((d) => [d, '']));
    this.defines.VFF_POSITIONS_WIDTH = String(data.textures.positions.width);
    this.glsl = specialisedGlsl(this.uniforms.vffField.value);
  }

  /**
   * Makes the textures (once; a later call with another renderer reuses them). When the field's
   * layout exceeds the renderer's limits and the file is at hand, the maps are repacked
   * (spec/format.md 10.4); without the file that throws, naming the limit. Returns this.
   */
  upload(renderer) {
    if (this.textures) return this;
    const lim = contextLimits(renderer.getContext());
    const L = this.layout, is3d = L.target === 2;
    const size = is3d ? lim.max3d : lim.maxTextureSize;
    const fits = L.sliceWidth <= size && L.sliceHeight <= size && L.sliceCount <= (is3d ? lim.max3d : lim.maxLayers);
    if (!fits) {
      if (!this.file) throw new Error(`${this.name || 'the field'}: its layout (${L.sliceCount} slices of ${L.sliceWidth} x ${L.sliceHeight}) exceeds this context's limits; decode it with options.limits`);
      this.data = textureDataOf(this.file, lim);
      this.layout = this.data.layout;
      this.note = this.data.note;
      this.uniforms.vffField.value = blockValue(this.data.textures.block);
    }
    const t = this.data.textures;
    const maps = planeTexture(t.maps, t.is3d);
    const normals = t.normals ? planeTexture(t.normals, t.is3d) : null;
    const positions = new THREE.DataTexture(t.positions.data, t.positions.width, t.positions.height, THREE.RGBAFormat, THREE.FloatType);
    positions.minFilter = positions.magFilter = THREE.NearestFilter;
    positions.generateMipmaps = false;
    positions.needsUpdate = true;
    this.textures = { maps, normals, positions };
    this.uniforms.vffMaps.value = maps;
    this.uniforms.vffNormals.value = normals;
    this.uniforms.vffPositionsTex.value = positions;
    return this;
  }

  /** The number of texels' bytes the textures hold (maps, normals, positions). */
  get byteLength() {
    const t = this.data.textures;
    return t.maps.data.byteLength + (t.normals?.data.byteLength ?? 0) + t.positions.data.byteLength;
  }

  // three.js deep-copies userData through JSON (Object3D.copy, clone, toJSON): a field is left out
  // rather than serialised; a clone's userData.vffField must be set again.
  toJSON() { return undefined; }

  dispose() {
    if (!this.textures) return;
    for (const t of Object.values(this.textures)) t?.dispose();
    this.textures = null;
    this.uniforms.vffMaps.value = this.uniforms.vffNormals.value = this.uniforms.vffPositionsTex.value = null;
  }
}
