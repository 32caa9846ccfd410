// occlusion.js - VffOcclusion: ambient occlusion and soft shadows that field instances (objects with
// a VffField, in their local space) cast on the scene's surfaces, for any number of moving instances.
//
//   const occ = new VffOcclusion(renderer, { aoRange: 0.5, aoRays: 4, shadowRays: 2 });
//   occ.collect(scene);                 // every object with userData.vffField (VffGLTFPlugin sets it)
//   function frame() { occ.render(scene, camera); requestAnimationFrame(frame); }
//
// Each frame: the scene is drawn once into a G-buffer (world position, geometric normal, object id),
// then a full-screen pass casts, per pixel, aoRays cosine-weighted rays in the hemisphere of the
// normal (hit within aoRange) and shadowRays rays in a cone of half-angle lightAngle about
// lightDirection (towards the light), against every instance but the one the pixel lies on (each
// ray carries its source object: a field does not answer for its own object's surface). Directions
// are a hash of pixel, frame and ray, so the image converges over frames while nothing moves; the
// mean goes to `output` (R: share of AO rays blocked, G: share of shadow rays blocked, B: 1 on a
// receiving surface). The scene is then drawn as usual and multiplied by
// (1 - aoIntensity R) (1 - shadowIntensity G).
//
// mode 'field' answers each ray with the instance's field (vffOccluded, gpu/glsl/vff_query.glsl);
// 'reference' with three-mesh-bvh's GPU ray casting against the instance's triangles, the same rays;
// 'off' draws the scene alone.
import * as THREE from 'three';
import { MeshBVH, MeshBVHUniformStruct, BVHShaderGLSL } from 'three-mesh-bvh';
import { FIELD_STRUCT, specialisedGlsl } from './field.js';
import { VFF_QUERY_GLSL_ES } from '../../src/vff_query_es.js';

const RECEIVER_ID = 4095;   // a receiving surface that is no instance

const DEFAULTS = Object.freeze({
  aoRange: 1, aoRays: 4, shadowRays: 2, lightDirection: new THREE.Vector3(0.4, 1, 0.3).normalize(), lightAngle: 0.08,
  shadowRange: 1e4, aoIntensity: 1, shadowIntensity: 0.6, bias: 0, maxInstances: 16, interpolated: true,
});

const PRECISION = `precision highp float;
precision highp int;
precision highp sampler2D;
precision highp usampler2D;
precision highp isampler2D;
precision highp sampler2DArray;
precision highp usampler2DArray;
precision highp isampler2DArray;
precision highp usampler3D;
precision highp isampler3D;
`;

const QUAD_VERTEX = `in vec3 position;
void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }`;

const GBUFFER_VERTEX = `${PRECISION}
uniform mat4 modelMatrix, viewMatrix, projectionMatrix;
in vec3 position;
out vec3 vWorld;
void main() {
  vec4 w = modelMatrix * vec4(position, 1.0);
  vWorld = w.xyz;
  gl_Position = projectionMatrix * viewMatrix * w;
}`;

// The geometric normal (from the world position's derivatives), turned towards the camera.
const GBUFFER_FRAGMENT = `${PRECISION}
uniform float uId;
uniform vec3 uEye;
uniform bool uOrtho;
uniform vec3 uViewDir;
in vec3 vWorld;
layout(location = 0) out vec4 gPosition;
layout(location = 1) out vec4 gNormal;
void main() {
  vec3 n = normalize(cross(dFdx(vWorld), dFdy(vWorld)));
  vec3 toEye = uOrtho ? -uViewDir : uEye - vWorld;
  if (dot(n, toEye) < 0.0) n = -n;
  gPosition = vec4(vWorld, uId);
  gNormal = vec4(n, 0.0);
}`;

const COMPOSITE_FRAGMENT = `${PRECISION}
uniform sampler2D uOcclusion;
uniform float uAoIntensity, uShadowIntensity;
uniform bool uEncode;
out vec4 outColor;
void main() {
  vec4 o = texelFetch(uOcclusion, ivec2(gl_FragCoord.xy), 0);
  float f = (1.0 - uAoIntensity * o.r) * (1.0 - uShadowIntensity * o.g);
  // The frame is already sRGB-encoded: scale the encoded value as the linear one is scaled.
  if (uEncode) f = pow(max(f, 0.0), 1.0 / 2.2);
  outColor = vec4(vec3(f), 1.0);
}`;

/** The query's source for field slot i, specialised to its field: every vff/Vff/VFF_/kVff name gets the slot's prefix. */
export function slotGlsl(i, field) {
  const rename = (s) => s.replace(/\b(vff|Vff|VFF_|kVff)/g, (m) => (m === 'VFF_' ? `VFF${i}_` : `${m}${i}_`));
  const defines = Object.entries(field.defines).map(([d, v]) => `#define ${rename(d)}${v === '' ? '' : ` ${v}`}\n`).join('');
  return defines + rename(specialisedGlsl(field.uniforms.vffField.value, FIELD_STRUCT + VFF_QUERY_GLSL_ES));
}

function occlusionFragment({ mode, slots, maxInstances, interpolated }) {
  // The instances are ordered by slot (uRange[i] .. uRange[i + 1] use slot i), and each slot's query
  // is called in a loop of its own: every instance costs one query, never a masked run of the others'.
  let resources = '', loops = '';
  slots.forEach((f, i) => {
    let hit;
    if (mode === 'field') {
      resources += slotGlsl(i, f) + '\n';
      hit = interpolated ? `vff${i}_IntersectInterpolated(o, d, 0.0, tmax, VFF${i}_OFF_OBJECT).hit` : `vff${i}_Occluded(o, d, 0.0, tmax, VFF${i}_OFF_OBJECT)`;
    } else {
      resources += `uniform BVH bvh${i};\n`;
      hit = `bvhIntersectFirstHit(bvh${i}, o, d, fi, fn, bc, side, dist) && dist >= 0.0 && dist <= tmax`;
    }
    loops += `  for (int j = uRange[${i}]; j < uRange[${i + 1}]; ++j) {
    if (j == skip || !nearSphere(j, p, dw, tmax)) continue;
    vec3 o = (uInverse[j] * vec4(p, 1.0)).xyz, d = mat3(uInverse[j]) * dw;
${mode === 'field' ? '' : '    uvec4 fi; vec3 fn, bc; float side, dist;\n'}    if (${hit}) return true;
  }
`;
  });
  if (mode === 'reference') resources = BVHShaderGLSL.common_functions + BVHShaderGLSL.bvh_struct_definitions + BVHShaderGLSL.bvh_ray_functions + resources;
  return `${PRECISION}
#define MAX_INSTANCES ${maxInstances}
uniform sampler2D uPosition, uNormal, uPrevious;
uniform float uBlend;
uniform uint uFrame;
uniform int uAoRays, uShadowRays;
uniform float uAoRange, uShadowRange, uBias, uCosCone;
uniform vec3 uLight;
uniform mat4 uInverse[MAX_INSTANCES];   // world to local, in slot order
uniform int uSorted[MAX_INSTANCES];     // instance k's place in slot order
uniform int uRange[${slots.length + 1}];
uniform vec4 uSphere[MAX_INSTANCES];
${resources}
// Whether a world ray p + t dw, t in [0, tmax], meets instance j's bounding sphere (slightly enlarged):
// others are not asked.
bool nearSphere(int j, vec3 p, vec3 dw, float tmax) {
  vec3 oc = p - uSphere[j].xyz;
  float bb = dot(oc, dw), cc = dot(oc, oc) - uSphere[j].w * uSphere[j].w;
  if (cc > 0.0 && bb > 0.0) return false;
  float disc = bb * bb - cc;
  return disc >= 0.0 && -bb - sqrt(disc) <= tmax;
}
// Whether an instance other than the one in slot order place \`skip\` blocks the ray (dw unit); each
// instance answers in its local space.
bool occluded(int skip, vec3 p, vec3 dw, float tmax) {
${loops}  return false;
}
uint pcg(uint v) {
  uint s = v * 747796405u + 2891336453u;
  uint w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
  return (w >> 22u) ^ w;
}
float rnd(inout uint s) { s = pcg(s); return float(s >> 8u) * (1.0 / 16777216.0); }
// An orthonormal basis about n (Duff et al. 2017).
void basis(vec3 n, out vec3 t, out vec3 b) {
  float sg = n.z >= 0.0 ? 1.0 : -1.0;
  float a = -1.0 / (sg + n.z), c = n.x * n.y * a;
  t = vec3(1.0 + sg * n.x * n.x * a, sg * c, -sg * n.x);
  b = vec3(c, sg + n.y * n.y * a, -n.y);
}
out vec4 outColor;
void main() {
  ivec2 px = ivec2(gl_FragCoord.xy);
  vec4 P = texelFetch(uPosition, px, 0);
  int id = int(P.w + 0.5);
  if (id == 0) { outColor = vec4(0.0); return; }
  vec3 n = texelFetch(uNormal, px, 0).xyz;
  vec3 p = P.xyz + n * uBias;
  int skip = id <= MAX_INSTANCES ? uSorted[id - 1] : -1;
  uint seed = pcg(uint(px.x) + pcg(uint(px.y) + pcg(uFrame)));
  vec3 t, b;
  basis(n, t, b);
  vec3 lt, lb;
  basis(uLight, lt, lb);
  // One loop, one call site of the query (a program's size, and its compile time, grow with each):
  // the AO rays first, then the shadow rays.
  float ao = 0.0, sh = 0.0;
  for (int r = 0; r < uAoRays + uShadowRays; ++r) {
    float u1 = rnd(seed), u2 = rnd(seed), phi = 6.283185307179586 * u2;
    bool isAo = r < uAoRays;
    vec3 d;
    if (isAo) {
      float rr = sqrt(u1);
      d = normalize(t * (rr * cos(phi)) + b * (rr * sin(phi)) + n * sqrt(max(0.0, 1.0 - u1)));
    } else {
      float c = 1.0 - u1 * (1.0 - uCosCone), sn = sqrt(max(0.0, 1.0 - c * c));
      d = normalize(lt * (sn * cos(phi)) + lb * (sn * sin(phi)) + uLight * c);
    }
    if (occluded(skip, p, d, isAo ? uAoRange : uShadowRange)) {
      if (isAo) ao += 1.0; else sh += 1.0;
    }
  }
  vec4 cur = vec4(uAoRays > 0 ? ao / float(uAoRays) : 0.0, uShadowRays > 0 ? sh / float(uShadowRays) : 0.0, 1.0, 1.0);
  outColor = mix(texelFetch(uPrevious, px, 0), cur, uBlend);
}`;
}

const keyIds = new WeakMap();
let nextKeyId = 0;
function keyId(k) {
  if (!keyIds.has(k)) keyIds.set(k, ++nextKeyId);
  return keyIds.get(k);
}

function target(w, h, count = 1) {
  return new THREE.WebGLRenderTarget(w, h, {
    count, type: THREE.FloatType, format: THREE.RGBAFormat, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter,
    depthBuffer: count > 1, generateMipmaps: false,
  });
}

/** The triangles of every mesh under `object`, in its local space, as one indexed geometry. */
function mergedGeometry(object) {
  object.updateWorldMatrix(true, true);
  const toLocal = new THREE.Matrix4().copy(object.matrixWorld).invert();
  const positions = [], indices = [];
  const m = new THREE.Matrix4(), v = new THREE.Vector3();
  object.traverse((o) => {
    if (!o.isMesh || !o.geometry?.getAttribute('position')) return;
    m.multiplyMatrices(toLocal, o.matrixWorld);
    const pos = o.geometry.getAttribute('position'), base = positions.length / 3;
    for (let i = 0; i < pos.count; ++i) { v.fromBufferAttribute(pos, i).applyMatrix4(m); positions.push(v.x, v.y, v.z); }
    const idx = o.geometry.getIndex();
    const n = idx ? idx.count : pos.count;
    for (let i = 0; i < n; ++i) indices.push(base + (idx ? idx.getX(i) : i));
  });
  const g = new THREE.BufferGeometry();
  g.setAttribute('position', new THREE.Float32BufferAttribute(positions, 3));
  g.setIndex(indices);
  return g;
}

export class VffOcclusion {
  /**
   * options: aoRange (world units), aoRays, shadowRays (rays a pixel a frame), lightDirection
   * (THREE.Vector3 towards the light), lightAngle (the cone's half-angle, radians), shadowRange,
   * aoIntensity, shadowIntensity (how much a fully blocked pixel darkens), bias (the ray origin's
   * offset along the normal, world units; 0: aoRange / 1000), maxInstances. Later changes to
   * occ.options take effect on the next frame and restart the accumulation.
   */
  constructor(renderer, options = {}) {
    this.renderer = renderer;
    this.options = { ...DEFAULTS, ...options };
    this.options.lightDirection = (options.lightDirection ?? DEFAULTS.lightDirection).clone();
    this.mode = 'field';
    this.receivers = null;
    this.instances = [];
    this.frame = 0;
    this.referenceGeometry = new Map();   // object -> geometry (setReferenceGeometry)
    this.bvhs = new Map();                // key (geometry or field) -> {bvh, uniform}
    this.idMaterials = new Map();
    this.size = new THREE.Vector2();
    this.gbuffer = null;
    this.accum = [];
    this.material = null;
    this.materials = new Map();             // key -> the occlusion pass's material
    this.materialKey = '';
    this.signature = null;
    this.quadCamera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
    this.quad = new THREE.Mesh(new THREE.PlaneGeometry(2, 2));
    this.quad.frustumCulled = false;
    this.quadScene = new THREE.Scene().add(this.quad);
    this.composite = new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3, vertexShader: QUAD_VERTEX, fragmentShader: COMPOSITE_FRAGMENT,
      uniforms: { uOcclusion: { value: null }, uAoIntensity: { value: 1 }, uShadowIntensity: { value: 1 }, uEncode: { value: true } },
      blending: THREE.CustomBlending, blendEquation: THREE.AddEquation, blendSrc: THREE.ZeroFactor, blendDst: THREE.SrcColorFactor,
      transparent: true, depthTest: false, depthWrite: false,
    });
  }

  /** The accumulated occlusion (R: AO, G: shadow, B: 1 on receivers), a render target. */
  get output() { return this.accum[0] ?? null; }

  /** The instances: [{object, field}] (entries without a field are left out). */
  setInstances(list) {
    const usable = list.filter((e) => e && e.object && e.field);
    if (usable.length > this.options.maxInstances)
      throw new Error(`VffOcclusion: ${usable.length} instances, more than maxInstances ${this.options.maxInstances}`);
    this.instances = usable.map(({ object, field }) => ({ object, field }));
    this.signature = null;
    return this;
  }

  /** Every object under `root` with userData.vffField, as instances. */
  collect(root) {
    const list = [];
    root.traverse((o) => { if (o.userData?.vffField) list.push({ object: o, field: o.userData.vffField }); });
    return this.setInstances(list);
  }

  /** The triangles 'reference' mode casts against for `object` (in its local space, as its field). */
  setReferenceGeometry(object, geometry) {
    this.referenceGeometry.set(object, geometry);
    this.materialKey = '';
    return this;
  }

  /** Restarts the accumulation. */
  reset() { this.frame = 0; }

  // Field slots (mode 'field': distinct fields) or BVH slots ('reference': distinct geometries).
  slots() {
    const keys = [], slotOf = [];
    for (const inst of this.instances) {
      const key = this.mode === 'reference' ? this.referenceGeometry.get(inst.object) ?? inst.field : inst.field;
      let i = keys.indexOf(key);
      if (i < 0) { i = keys.length; keys.push(key); }
      slotOf.push(i);
    }
    return { keys, slotOf };
  }

  bvhFor(key, object) {
    let e = this.bvhs.get(key);
    if (!e) {
      const g = key.isBufferGeometry ? key.clone() : mergedGeometry(object);
      const bvh = new MeshBVH(g);
      const uniform = new MeshBVHUniformStruct();
      uniform.updateFrom(bvh);
      e = { bvh, uniform, geometry: g };
      this.bvhs.set(key, e);
    }
    return e;
  }

  buildMaterial(keys, slotOf) {
    const key = `${this.mode}|${this.options.maxInstances}|${!!this.options.interpolated}|${keys.map(keyId).join(',')}`;
    if (key === this.materialKey && this.material) return;
    // A program compiles slowly (seconds in software): one material a key, kept for a later switch back.
    if (this.materials.has(key)) {
      this.material = this.materials.get(key);
      this.materialKey = key;
      return;
    }
    // Samplers: the G-buffer's two and the running mean, then 3 a field (maps, normals, positions)
    // or 4 a BVH (positions, index, bounds, contents).
    const units = 3 + (this.mode === 'reference' ? 4 * keys.length : keys.reduce((n, f) => n + ('VFF_NO_NORMALS' in f.defines ? 2 : 3), 0));
    const max = this.renderer.capabilities.maxTextures;
    if (units > max)
      throw new Error(`VffOcclusion: ${keys.length} distinct ${this.mode === 'reference' ? 'geometries' : 'fields'} need ${units} texture units, this context has ${max}`);
    const uniforms = {
      uPosition: { value: null }, uNormal: { value: null }, uPrevious: { value: null }, uBlend: { value: 1 }, uFrame: { value: 0 },
      uAoRays: { value: 0 }, uShadowRays: { value: 0 }, uAoRange: { value: 1 }, uShadowRange: { value: 1 },
      uBias: { value: 0 }, uCosCone: { value: 1 }, uLight: { value: new THREE.Vector3() },
      uInverse: { value: Array.from({ length: this.options.maxInstances }, () => new THREE.Matrix4()) },
      uSorted: { value: new Int32Array(this.options.maxInstances) },
      uRange: { value: new Int32Array(keys.length + 1) },
      uSphere: { value: Array.from({ length: this.options.maxInstances }, () => new THREE.Vector4()) },
    };
    keys.forEach((k, i) => {
      if (this.mode === 'reference') {
        const object = this.instances[slotOf.indexOf(i)].object;
        uniforms[`bvh${i}`] = { value: this.bvhFor(k, object).uniform };
      } else {
        k.upload(this.renderer);
        for (const [name, u] of Object.entries(k.uniforms)) uniforms[name.replace(/^vff/, `vff${i}_`)] = u;
      }
    });
    this.material = new THREE.RawShaderMaterial({
      glslVersion: THREE.GLSL3, vertexShader: QUAD_VERTEX, uniforms, depthTest: false, depthWrite: false,
      fragmentShader: occlusionFragment({ mode: this.mode, slots: keys, maxInstances: this.options.maxInstances, interpolated: !!this.options.interpolated }),
    });
    this.materialKey = key;
    this.materials.set(key, this.material);
  }

  idMaterial(id) {
    let m = this.idMaterials.get(id);
    if (!m) {
      m = new THREE.RawShaderMaterial({
        glslVersion: THREE.GLSL3, vertexShader: GBUFFER_VERTEX, fragmentShader: GBUFFER_FRAGMENT, side: THREE.DoubleSide,
        uniforms: { uId: { value: id }, uEye: this.eye, uOrtho: this.ortho, uViewDir: this.viewDir },
      });
      this.idMaterials.set(id, m);
    }
    return m;
  }

  resize(w, h) {
    if (this.gbuffer && this.size.x === w && this.size.y === h) return;
    this.size.set(w, h);
    this.gbuffer?.dispose();
    for (const t of this.accum) t.dispose();
    this.gbuffer = target(w, h, 2);
    this.accum = [target(w, h), target(w, h)];
    this.frame = 0;
  }

  /** Draws the scene with the occlusion of the instances applied (to the renderer's current target). */
  render(scene, camera) {
    const r = this.renderer;
    if (this.mode === 'off') { r.render(scene, camera); this.signature = null; return; }
    if (this.mode !== 'field' && this.mode !== 'reference') throw new Error(`VffOcclusion: mode '${this.mode}', expected 'field', 'reference' or 'off'`);
    const out = r.getRenderTarget();
    const size = out ? new THREE.Vector2(out.width, out.height) : r.getDrawingBufferSize(new THREE.Vector2());
    this.resize(size.x, size.y);
    scene.updateMatrixWorld();
    if (camera.parent === null) camera.updateMatrixWorld();
    const { keys, slotOf } = this.slots();
    this.buildMaterial(keys, slotOf);

    // Ids: instance k's meshes k + 1, other receivers RECEIVER_ID, the rest 0.
    const ids = new Map();
    this.instances.forEach((inst, k) => inst.object.traverse((o) => { if (o.isMesh) ids.set(o, k + 1); }));
    const receiving = this.receivers ? new Set(this.receivers) : null;
    const isReceiver = (o) => { for (let a = o; a; a = a.parent) if (receiving.has(a)) return true; return false; };
    const swapped = [], hidden = [], sig = [...camera.matrixWorld.elements, ...camera.projectionMatrix.elements, size.x, size.y];
    this.eye ??= { value: new THREE.Vector3() };
    this.ortho ??= { value: false };
    this.viewDir ??= { value: new THREE.Vector3() };
    this.eye.value.setFromMatrixPosition(camera.matrixWorld);
    this.ortho.value = !!camera.isOrthographicCamera;
    camera.getWorldDirection(this.viewDir.value);
    scene.traverseVisible((o) => {
      if (o.isMesh) {
        let id = ids.get(o) ?? RECEIVER_ID;
        if (receiving && !isReceiver(o)) id = 0;
        swapped.push([o, o.material]);
        o.material = this.idMaterial(id);
        sig.push(id, ...o.matrixWorld.elements);
      } else if (o.isPoints || o.isLine || o.isSprite) {
        hidden.push(o);
        o.visible = false;
      }
    });
    for (const inst of this.instances) sig.push(...inst.object.matrixWorld.elements);
    const o = this.options;
    const opt = JSON.stringify([this.mode, this.materialKey, o.aoRange, o.aoRays, o.shadowRays, o.lightDirection.toArray(), o.lightAngle, o.shadowRange, o.bias]);
    const same = this.signature && this.signature.opt === opt && this.signature.values.length === sig.length && this.signature.values.every((v, i) => v === sig[i]);
    if (!same) this.frame = 0;
    this.signature = { opt, values: sig };

    // 1. The G-buffer.
    const background = scene.background, override = scene.overrideMaterial, fog = scene.fog;
    const clear = r.getClearColor(new THREE.Color()), clearAlpha = r.getClearAlpha(), autoClear = r.autoClear;
    const shadowAuto = r.shadowMap.autoUpdate;
    scene.background = null;
    scene.overrideMaterial = null;
    scene.fog = null;
    r.shadowMap.autoUpdate = false;
    r.setClearColor(0x000000, 0);
    r.setRenderTarget(this.gbuffer);
    r.autoClear = true;
    r.render(scene, camera);
    for (const [m, mat] of swapped) m.material = mat;
    for (const h of hidden) h.visible = true;
    scene.background = background;
    scene.overrideMaterial = override;
    scene.fog = fog;
    r.shadowMap.autoUpdate = shadowAuto;

    // 2. This frame's rays, blended into the running mean.
    const u = this.material.uniforms;
    u.uPosition.value = this.gbuffer.textures[0];
    u.uNormal.value = this.gbuffer.textures[1];
    u.uPrevious.value = this.accum[0].texture;
    u.uBlend.value = 1 / (this.frame + 1);
    u.uFrame.value = this.frame;
    u.uAoRays.value = o.aoRays;
    u.uShadowRays.value = o.shadowRays;
    u.uAoRange.value = o.aoRange;
    u.uShadowRange.value = o.shadowRange;
    u.uBias.value = o.bias || o.aoRange / 1000;
    u.uCosCone.value = Math.cos(o.lightAngle);
    u.uLight.value.copy(o.lightDirection).normalize();
    // Slot order: the instances of slot 0, then of slot 1, ...; ties in the instances' order.
    const order = this.instances.map((_, k) => k).sort((a, b) => slotOf[a] - slotOf[b] || a - b);
    u.uRange.value.fill(0);
    order.forEach((k, j) => {
      const inst = this.instances[k], w = inst.object.matrixWorld;
      u.uInverse.value[j].copy(w).invert();
      u.uSorted.value[k] = j;
      const c = inst.field.center.clone().applyMatrix4(w);
      u.uSphere.value[j].set(c.x, c.y, c.z, inst.field.radius * w.getMaxScaleOnAxis() * 1.001 + 1e-6);
      u.uRange.value[slotOf[k] + 1] = j + 1;
    });
    // A slot without instances begins and ends where the slot before it ends.
    for (let i = 1; i < u.uRange.value.length; ++i) u.uRange.value[i] = Math.max(u.uRange.value[i], u.uRange.value[i - 1]);
    this.quad.material = this.material;
    r.setRenderTarget(this.accum[1]);
    r.render(this.quadScene, this.quadCamera);
    this.accum.reverse();
    this.frame += 1;

    // 3. The scene as usual, 4. multiplied by the occlusion.
    r.setRenderTarget(out);
    r.setClearColor(clear, clearAlpha);
    r.autoClear = autoClear;
    r.render(scene, camera);
    const c = this.composite.uniforms;
    c.uOcclusion.value = this.accum[0].texture;
    c.uAoIntensity.value = o.aoIntensity;
    c.uShadowIntensity.value = o.shadowIntensity;
    c.uEncode.value = !out && r.outputColorSpace === THREE.SRGBColorSpace;
    this.quad.material = this.composite;
    r.autoClear = false;
    r.render(this.quadScene, this.quadCamera);
    r.autoClear = autoClear;
  }

  dispose() {
    this.gbuffer?.dispose();
    for (const t of this.accum) t.dispose();
    for (const m of this.materials.values()) m.dispose();
    this.materials.clear();
    this.composite.dispose();
    for (const m of this.idMaterials.values()) m.dispose();
    for (const e of this.bvhs.values()) e.geometry.dispose();
    this.quad.geometry.dispose();
  }
}
