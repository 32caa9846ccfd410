// passes.js - the full-screen passes of the viewer's 3D view, each a ShaderMaterial that includes
// the field's GLSL ES query: the ground's AO and soft shadow accumulated over frames with per-pixel
// random rays; the object's lowest point from upward rays; and the deterministic reference view of
// the ground's AO that the tests compare with libvff (tests/web/web_reference.cpp).
import * as THREE from 'three';

const QUAD_VERTEX = `void main() { gl_Position = vec4(position.xy, 0.0, 1.0); }`;

// The share of a world ray [0, tmax] the object leaves open (1: open). A ground point is on no
// object (geometry.md 7.4): VFF_OFF_OBJECT.
const OPEN_SHARE = `
uniform bool uInterpolated;
float openShare(vec3 o, vec3 d, float tmax) {
  if (uInterpolated) return vffVisibility(o, d, 0.0, tmax, VFF_OFF_OBJECT);
  return vffOccluded(o, d, 0.0, tmax, VFF_OFF_OBJECT) ? 0.0 : 1.0;
}`;

const ACCUMULATE = `
uniform mat4 uInvViewProjection;
uniform vec2 uResolution;
uniform float uGroundY;
uniform int uFrame;            // frames accumulated so far; the new one is weighted 1 / (uFrame + 1)
uniform sampler2D uPrevious;
uniform vec3 uLight;           // unit direction towards the light
uniform float uLightAngle;     // half-angle of the light's cone, radians
uniform float uAoRange;
uniform int uAoRays;
uniform int uShadowRays;
out highp vec4 fragColor;
${OPEN_SHARE}

// A per-pixel, per-frame, per-ray random number pair (PCG hash).
uint pcg(uint v) {
  uint s = v * 747796405u + 2891336453u;
  uint w = ((s >> ((s >> 28u) + 4u)) ^ s) * 277803737u;
  return (w >> 22u) ^ w;
}
vec2 random2(uint ray) {
  uint h = pcg(uint(gl_FragCoord.x) + pcg(uint(gl_FragCoord.y) + pcg(uint(uFrame) * 64u + ray)));
  uint h2 = pcg(h);
  return vec2(float(h >> 8u), float(h2 >> 8u)) / 16777216.0;
}

void main() {
  vec4 previous = texelFetch(uPrevious, ivec2(gl_FragCoord.xy), 0);
  vec2 ndc = 2.0 * gl_FragCoord.xy / uResolution - 1.0;
  vec4 a = uInvViewProjection * vec4(ndc, -1.0, 1.0), b = uInvViewProjection * vec4(ndc, 1.0, 1.0);
  vec3 ro = a.xyz / a.w, rd = normalize(b.xyz / b.w - ro);
  float t = rd.y < 0.0 ? (uGroundY - ro.y) / rd.y : -1.0;
  if (t <= 0.0) { fragColor = vec4(1.0, 1.0, 0.0, 0.0); return; }
  vec3 p = ro + rd * t;
  float open = 0.0, lit = 0.0;
  for (int i = 0; i < 16; ++i) {
    if (i >= uAoRays) break;
    vec2 u = random2(uint(i));
    float r = sqrt(u.x), phi = 6.28318531 * u.y;  // cosine-weighted about +y
    open += openShare(p, vec3(r * cos(phi), sqrt(max(1.0 - u.x, 0.0)), r * sin(phi)), uAoRange);
  }
  vec3 tl = normalize(cross(abs(uLight.y) < 0.9 ? vec3(0, 1, 0) : vec3(1, 0, 0), uLight)), bl = cross(uLight, tl);
  for (int i = 0; i < 16; ++i) {
    if (i >= uShadowRays) break;
    vec2 u = random2(uint(16 + i));
    float c = mix(1.0, cos(uLightAngle), u.x), s = sqrt(max(1.0 - c * c, 0.0)), phi = 6.28318531 * u.y;
    lit += openShare(p, normalize(c * uLight + s * (cos(phi) * tl + sin(phi) * bl)), 1e30);
  }
  vec2 fresh = vec2(open / float(max(uAoRays, 1)), lit / float(max(uShadowRays, 1)));
  float w = 1.0 / float(uFrame + 1);
  fragColor = vec4(mix(uFrame == 0 ? fresh : previous.rg, fresh, w), 0.0, 1.0);
}`;

const LOWEST = `
uniform vec2 uResolution;
uniform vec3 uCenter;          // the field's sphere
uniform float uRadius;
out highp vec4 fragColor;
void main() {
  vec3 c = uCenter;
  float R = uRadius;
  vec2 q = (2.0 * gl_FragCoord.xy / uResolution - 1.0) * R;
  vec3 o = vec3(c.x + q.x, c.y - 1.01 * R, c.z + q.y);
  VffHit h = vffIntersect(o, vec3(0.0, 1.0, 0.0), 0.0, 2.02 * R, VFF_OFF_OBJECT);
  fragColor = h.hit ? vec4(o.y + h.t, 1.0, 0.0, 1.0) : vec4(0.0, 0.0, 0.0, 1.0);
}`;

export const REFERENCE_AO_RAYS = 32;  // tests/web/web_reference.cpp kAoRays
const REFERENCE = `
uniform vec2 uResolution;
uniform vec3 uCenter;          // the field's sphere
uniform float uRadius;
out highp vec4 fragColor;
${OPEN_SHARE}
// web_reference.cpp aoDirection: a Fibonacci spiral, cosine-weighted around +y.
vec3 aoDirection(int i, int count) {
  float u = (float(i) + 0.5) / float(count);
  float r = sqrt(u);
  float phi = float(i) * 2.39996323;
  return vec3(r * cos(phi), sqrt(1.0 - u), r * sin(phi));
}
void main() {
  vec3 c = uCenter;
  float R = uRadius;
  vec2 q = (2.0 * gl_FragCoord.xy / uResolution - 1.0) * 2.0 * R;
  vec3 p = vec3(c.x + q.x, c.y - R, c.z + q.y);
  float open = 0.0;
  for (int i = 0; i < ${REFERENCE_AO_RAYS}; ++i) open += openShare(p, aoDirection(i, ${REFERENCE_AO_RAYS}), 4.0 * R);
  fragColor = vec4(vec3(open / float(${REFERENCE_AO_RAYS})), 1.0);
}`;

/** A full-screen pass: {material, run(renderer, target)}. */
export function fieldPass(field, body, uniforms = {}) {
  const material = new THREE.ShaderMaterial({
    glslVersion: THREE.GLSL3,
    defines: { ...field.defines },
    uniforms: { ...field.uniforms, uCenter: { value: field.center.clone() }, uRadius: { value: field.radius }, ...uniforms },
    vertexShader: QUAD_VERTEX,
    fragmentShader: `${field.glsl}\n${body}`,
    depthTest: false, depthWrite: false,
  });
  const mesh = new THREE.Mesh(new THREE.PlaneGeometry(2, 2), material);
  mesh.frustumCulled = false;
  const scene = new THREE.Scene();
  scene.add(mesh);
  const camera = new THREE.OrthographicCamera(-1, 1, 1, -1, 0, 1);
  return {
    material,
    run(renderer, target) {
      const old = renderer.getRenderTarget();
      renderer.setRenderTarget(target);
      renderer.render(scene, camera);
      renderer.setRenderTarget(old);
    },
    dispose(keep = null) { if (keep) keep.push(material); else material.dispose(); mesh.geometry.dispose(); },
  };
}

export const accumulatePass = (field) => fieldPass(field, ACCUMULATE, {
  uInvViewProjection: { value: new THREE.Matrix4() }, uResolution: { value: new THREE.Vector2(1, 1) },
  uGroundY: { value: 0 }, uFrame: { value: 0 }, uPrevious: { value: null }, uLight: { value: new THREE.Vector3(0, 1, 0) },
  uLightAngle: { value: 0.1 }, uAoRange: { value: 1 }, uAoRays: { value: 2 }, uShadowRays: { value: 1 }, uInterpolated: { value: false },
});

/** A float render target (falls back to half floats where float colour buffers are missing). */
export function floatTarget(w, h, renderer) {
  const type = renderer.extensions.has('EXT_color_buffer_float') ? THREE.FloatType : THREE.HalfFloatType;
  return new THREE.WebGLRenderTarget(w, h, { type, format: THREE.RGBAFormat, minFilter: THREE.NearestFilter, magFilter: THREE.NearestFilter, depthBuffer: false });
}

/**
 * The object's lowest point (world y): the highest first hit of no upward ray lies below it. A grid
 * of `grid` x `grid` vertical rays over the sphere's footprint; null when every ray misses. With
 * `keep` (an array), the pass's material goes there instead of being disposed: its compiled program
 * then serves the next field of the same schemes (see FieldView.clear).
 */
export function lowestPoint(renderer, field, grid = 96, keep = null) {
  const pass = fieldPass(field, LOWEST, { uResolution: { value: new THREE.Vector2(grid, grid) } });
  const target = floatTarget(grid, grid, renderer);
  pass.run(renderer, target);
  const px = new Float32Array(grid * grid * 4);
  renderer.readRenderTargetPixels(target, 0, 0, grid, grid, px);
  pass.dispose(keep); target.dispose();
  let low = Infinity, hits = 0;
  for (let i = 0; i < px.length; i += 4) if (px[i + 1] > 0.5) { ++hits; low = Math.min(low, px[i]); }
  return hits ? { y: low, hits, rays: grid * grid } : null;
}

/** The reference view (size x size grey levels, row 0 at the bottom) of the ground AO. */
export function referenceView(renderer, field, size, interpolated) {
  const pass = fieldPass(field, REFERENCE, { uResolution: { value: new THREE.Vector2(size, size) }, uInterpolated: { value: !!interpolated } });
  const target = new THREE.WebGLRenderTarget(size, size, { depthBuffer: false });
  pass.run(renderer, target);
  const px = new Uint8Array(size * size * 4);
  renderer.readRenderTargetPixels(target, 0, 0, size, size, px);
  pass.dispose(); target.dispose();
  return Array.from(px.filter((_, i) => i % 4 === 0));
}
