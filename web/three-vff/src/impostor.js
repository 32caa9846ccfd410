// impostor.js - a field's object drawn from the field itself: a ShaderMaterial on a sphere around
// the field's bounding sphere that casts each pixel's camera ray through the field (the GLSL ES
// query), shades the hit and writes its depth, so the object takes part in the scene's depth test
// like a mesh. Rays are cast in the mesh's local space (the field's object space).
//
//   const mesh = createVffImpostor(field, {interpolated: false});
//   scene.add(mesh);
//
// `field` is a VffField (or any object with its uniforms, defines, glsl, center and radius).
import { Mesh, SphereGeometry, ShaderMaterial, BackSide, GLSL3, Vector3, Color, Matrix4 } from 'three';

const VERTEX = `
out vec3 vWorld;
void main() {
  vec4 w = modelMatrix * vec4(position, 1.0);
  vWorld = w.xyz;
  gl_Position = projectionMatrix * viewMatrix * w;
}`;

const FRAGMENT = `
uniform mat4 modelMatrix;       // three.js sets these for the vertex stage; the ray needs them here
uniform mat4 projectionMatrix;
uniform mat4 uWorldToObject;
uniform vec3 uLight;          // unit direction towards the light, world space
uniform vec3 uColor;
uniform vec3 uSky;            // ambient from above
uniform vec3 uGroundBounce;   // ambient from below
uniform bool uInterpolated;
uniform bool uSelfShadow;
uniform float uRadius;       // the field's sphere radius (object space)
// How far (in radii) a self-shadow ray starts off the surface: past the intra-object test's error
// near its origin, which otherwise darkens whole sampling cells (acne).
const float VFF_SHADOW_LIFT = 0.05;
in vec3 vWorld;
out highp vec4 fragColor;

// The camera ray through world point w (on the proxy sphere) cast through the field from ro (object
// space); *pW: its hit (or the proxy point) in world space.
VffHit vffCameraHit(vec3 ro, vec3 w, out vec3 pW) {
  vec3 rd = normalize((uWorldToObject * vec4(w, 1.0)).xyz - ro);
  VffHit h;
  if (uInterpolated) h = vffIntersectInterpolated(ro, rd, 0.0, 1e30, VFF_OFF_OBJECT);
  else h = vffIntersect(ro, rd, 0.0, 1e30, VFF_OFF_OBJECT);
  pW = h.hit ? (modelMatrix * vec4(ro + rd * h.t, 1.0)).xyz : w;
  return h;
}

// Whether two camera hits come from the same sampling cell: the same nearest sample and, for
// kNearest, the same texel. Within a cell the surface has no step between sampling cells.
bool vffSameCell(VffHit a, VffHit b) {
  return a.sampleIndex == b.sampleIndex && (uInterpolated || a.texel == b.texel);
}

// The surface's step from hit h (at p) towards the next pixel along dw (a pixel's step on the
// proxy): the forward difference where that pixel's hit lies in h's sampling cell; else the nearer
// of the two one-sided differences, since the other may cross a step between sampling cells (a
// screen-space derivative takes whichever side its 2x2 quad has, which dots the cells' seams).
// *ok: false where neither neighbour hits.
vec3 vffSurfaceStep(vec3 ro, VffHit h, vec3 p, vec3 dw, out bool ok) {
  vec3 pa, pb;
  VffHit ha = vffCameraHit(ro, vWorld + dw, pa);
  vec3 a = pa - p;
  ok = true;
  if (ha.hit && vffSameCell(ha, h)) return a;
  bool hitB = vffCameraHit(ro, vWorld - dw, pb).hit;
  vec3 b = p - pb;
  ok = ha.hit || hitB;
  return !ha.hit ? b : !hitB ? a : (dot(a, a) <= dot(b, b) ? a : b);
}

void main() {
  vec3 ro = (uWorldToObject * vec4(cameraPosition, 1.0)).xyz;
  // (The proxy's pixel steps, taken before any invocation of the quad discards.)
  vec3 dwx = dFdx(vWorld), dwy = dFdy(vWorld);
  vec3 pW;
  VffHit h = vffCameraHit(ro, vWorld, pW);
  if (!h.hit) discard;
  vec3 pObj = (uWorldToObject * vec4(pW, 1.0)).xyz;
  vec3 rdW = normalize(pW - cameraPosition);
  vec3 n;
  if (h.hasNormal) n = normalize(mat3(modelMatrix) * h.normal);
  else {
    // Without a normal plane: the normal from the neighbouring pixels' hits, unless they lie on
    // another surface (a silhouette or a large step), where it would be wrong.
    bool okX, okY;
    vec3 dx = vffSurfaceStep(ro, h, pW, dwx, okX), dy = vffSurfaceStep(ro, h, pW, dwy, okY);
    vec3 c = cross(dx, dy);
    float step = max(length(dx), length(dy));
    n = (okX && okY && length(c) > 0.0 && step < 0.16 * uRadius) ? normalize(c) : -rdW;
  }
  if (dot(n, rdW) > 0.0) n = -n;
  float lit = max(dot(n, uLight), 0.0);
  if (uSelfShadow && lit > 0.0) {
    vec3 lObj = normalize(mat3(uWorldToObject) * uLight);
    // The intra-object test (section 7.3) from a point lifted off the hit along its normal: from
    // the hit point itself, the sampling's error shades whole cells of the surface (acne).
    vec3 pLift = pObj + normalize(mat3(uWorldToObject) * n) * (VFF_SHADOW_LIFT * uRadius);
    if (vffOccluded(pLift, lObj, 0.0, 1e30, -1.0)) lit = 0.0;
  }
  vec3 ambient = mix(uGroundBounce, uSky, 0.5 + 0.5 * n.y);
  vec3 col = uColor * (0.8 * ambient + 0.6 * lit);
  fragColor = vec4(col, 1.0);
  vec4 clip = projectionMatrix * viewMatrix * vec4(pW, 1.0);
  gl_FragDepth = 0.5 * (clip.z / clip.w) + 0.5;
}`;

/** The impostor's material. options: interpolated, selfShadow, color, lightDirection (towards the light). */
export class VffImpostorMaterial extends ShaderMaterial {
  constructor(field, options = {}) {
    super({
      glslVersion: GLSL3,
      defines: { ...field.defines },
      uniforms: {
        ...field.uniforms,
        uWorldToObject: { value: new Matrix4() },
        uLight: { value: (options.lightDirection ?? new Vector3(-0.5, 0.8, 0.3)).clone().normalize() },
        uColor: { value: new Color(options.color ?? 0xd9c7a8) },
        uSky: { value: new Color(0.62, 0.66, 0.72) },
        uGroundBounce: { value: new Color(0.36, 0.33, 0.29) },
        uInterpolated: { value: !!options.interpolated },
        uSelfShadow: { value: options.selfShadow ?? true },
        uRadius: { value: field.radius },
      },
      vertexShader: VERTEX,
      fragmentShader: `${field.glsl}\n${FRAGMENT}`,
      side: BackSide,
    });
    this.field = field;
  }
}

/** A mesh drawing `field`'s object; its local space is the field's object space. */
export function createVffImpostor(field, options = {}) {
  const material = new VffImpostorMaterial(field, options);
  // The far side of the sphere: still drawn when the camera is inside the bounding sphere.
  const geometry = new SphereGeometry(field.radius * 1.01, 48, 24);
  geometry.translate(field.center.x, field.center.y, field.center.z);
  const mesh = new Mesh(geometry, material);
  mesh.onBeforeRender = () => { material.uniforms.uWorldToObject.value.copy(mesh.matrixWorld).invert(); };
  return mesh;
}
