// scene.js - the WebGL2 view: the field's object on a ground plane that touches the bottom of its
// bounding sphere, ground ambient occlusion and a soft shadow answered by the GLSL ES port of the
// query (vff_query_es.js), nearest or interpolated; and the reference view the tests compare with
// the C++ render (tests/web/web_reference.cpp).
import { VFF_QUERY_GLSL_ES } from './vff_query_es.js';

export const AO_RAYS = 32;       // tests/web/web_reference.cpp kAoRays

const VERTEX = `#version 300 es
void main() {
  vec2 p = vec2(gl_VertexID == 1 ? 3.0 : -1.0, gl_VertexID == 2 ? 3.0 : -1.0);
  gl_Position = vec4(p, 0.0, 1.0);
}`;

const MAIN = `
uniform vec2 uSize;
uniform vec3 uEye;
uniform mat3 uCamera;       // columns: right, up, back
uniform mat3 uObject;       // object rotation about the sphere centre (object -> world)
uniform vec3 uLight;        // unit direction towards the light
uniform int uInterpolated;
uniform int uReference;     // 1: ground AO seen from straight above, grey levels
uniform int uAoRays;
uniform int uShadowRays;
out vec4 fragColor;

const int AO_RAYS = ${AO_RAYS};

// web_reference.cpp aoDirection: a Fibonacci spiral, cosine-weighted around +y.
vec3 aoDirection(int i, int count) {
  float u = (float(i) + 0.5) / float(count);
  float r = sqrt(u);
  float phi = float(i) * 2.39996323;
  return vec3(r * cos(phi), sqrt(1.0 - u), r * sin(phi));
}

// The share of a world ray [0, tmax] the object leaves open (1: unoccluded).
float openShare(vec3 o, vec3 d, float tmax) {
  vec3 c = vffField.sphereCenter;
  vec3 oo = c + transpose(uObject) * (o - c);
  vec3 od = transpose(uObject) * d;
  // (A ground point is on no object: section 7.4.)
  if (uInterpolated != 0) return vffVisibility(oo, od, 0.0, tmax, VFF_OFF_OBJECT);
  return vffOccluded(oo, od, 0.0, tmax, VFF_OFF_OBJECT) ? 0.0 : 1.0;
}

float groundAo(vec3 p, int count) {
  float R = vffField.sphereRadius, open = 0.0;
  for (int i = 0; i < AO_RAYS; ++i) {
    if (i >= count) break;
    open += openShare(p, aoDirection(i, count), 4.0 * R);
  }
  return open / float(count);
}

float softShadow(vec3 p) {
  vec3 t = normalize(cross(abs(uLight.y) < 0.9 ? vec3(0, 1, 0) : vec3(1, 0, 0), uLight));
  vec3 b = cross(uLight, t);
  float lit = 0.0;
  for (int i = 0; i < 8; ++i) {
    if (i >= uShadowRays) break;
    float a = float(i) * 2.39996323, r = 0.12 * sqrt((float(i) + 0.5) / float(uShadowRays));
    lit += openShare(p, normalize(uLight + r * (cos(a) * t + sin(a) * b)), 1e30);
  }
  return lit / float(uShadowRays);
}

void main() {
  vec3 c = vffField.sphereCenter;
  float R = vffField.sphereRadius;
  float groundY = c.y - R;
  if (uReference != 0) {
    vec2 q = (2.0 * gl_FragCoord.xy / uSize - 1.0) * 2.0 * R;
    float ao = groundAo(vec3(c.x + q.x, groundY, c.z + q.y), AO_RAYS);
    fragColor = vec4(vec3(ao), 1.0);
    return;
  }
  vec2 s = (2.0 * gl_FragCoord.xy - uSize) / uSize.y;
  vec3 d = normalize(uCamera * vec3(s, -1.8));
  vec3 col = mix(vec3(0.80, 0.86, 0.93), vec3(0.45, 0.60, 0.82), clamp(d.y * 2.0, 0.0, 1.0));
  float tGround = d.y < 0.0 ? (groundY - uEye.y) / d.y : 1e30;
  // The object: the field answers the camera ray in object space.
  vec3 oo = c + transpose(uObject) * (uEye - c);
  vec3 od = transpose(uObject) * d;
  VffHit h;
  if (uInterpolated != 0) h = vffIntersectInterpolated(oo, od, 0.0, 1e30, 0.0);
  else h = vffIntersect(oo, od, 0.0, 1e30, 0.0);
  if (h.hit && h.t < tGround) {
    vec3 n = h.hasNormal ? uObject * h.normal : -d;
    if (dot(n, d) > 0.0) n = -n;
    float diff = max(dot(n, uLight), 0.0);
    float depth = clamp((h.t - (length(uEye - c) - R)) / (2.0 * R), 0.0, 1.0);
    vec3 albedo = h.hasNormal ? vec3(0.85, 0.78, 0.66) : mix(vec3(0.95, 0.75, 0.45), vec3(0.55, 0.25, 0.15), depth);
    fragColor = vec4(albedo * (0.35 + 0.65 * diff), 1.0);
    return;
  }
  if (tGround < 1e29) {
    vec3 p = uEye + d * tGround;
    float ao = groundAo(p, uAoRays);
    float lit = uLight.y > 0.0 ? softShadow(p) * uLight.y : 0.0;
    vec2 g = abs(fract((p.xz - c.xz) / R) - 0.5);
    float grid = min(g.x, g.y) < 0.01 ? 0.9 : 1.0;
    vec3 ground = vec3(0.78, 0.76, 0.72) * grid;
    col = ground * (0.45 * ao + 0.6 * lit);
    col = mix(col, vec3(0.80, 0.86, 0.93), clamp((tGround - 12.0 * R) / (20.0 * R), 0.0, 1.0));
  }
  fragColor = vec4(col, 1.0);
}`;

/** The fragment shader for a field loaded by gpu.js (its defines: VFF_MAPS_3D, VFF_NO_NORMALS). */
export function fragmentSource(defines) {
  return `#version 300 es
${defines.map((d) => `#define ${d}`).join('\n')}
precision highp float;
precision highp int;
${VFF_QUERY_GLSL_ES}
${MAIN}`;
}

function compile(gl, type, src) {
  const s = gl.createShader(type);
  gl.shaderSource(s, src);
  gl.compileShader(s);
  if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) throw new Error(`shader: ${gl.getShaderInfoLog(s)}`);
  return s;
}

/** Links the scene program for a loaded field and binds its resources' units. */
export function createProgram(gl, field) {
  const p = gl.createProgram();
  gl.attachShader(p, compile(gl, gl.VERTEX_SHADER, VERTEX));
  gl.attachShader(p, compile(gl, gl.FRAGMENT_SHADER, fragmentSource(field.defines)));
  gl.linkProgram(p);
  if (!gl.getProgramParameter(p, gl.LINK_STATUS)) throw new Error(`link: ${gl.getProgramInfoLog(p)}`);
  gl.useProgram(p);
  gl.uniformBlockBinding(p, gl.getUniformBlockIndex(p, 'VffFieldBlock'), 0);
  gl.uniform1i(gl.getUniformLocation(p, 'vffMaps'), 0);
  gl.uniform1i(gl.getUniformLocation(p, 'vffNormals'), 1);
  gl.uniform1i(gl.getUniformLocation(p, 'vffPositionsTex'), 2);
  return p;
}

function rotation(yaw, pitch) {
  const cy = Math.cos(yaw), sy = Math.sin(yaw), cp = Math.cos(pitch), sp = Math.sin(pitch);
  // Columns right, up, back of a camera turned by yaw about y, then pitch about its right axis.
  return [cy, 0, -sy, sy * sp, cp, cy * sp, sy * cp, -sp, cy * cp];
}

/**
 * Draws one frame. view: {yaw, pitch, distance (in R), objectYaw, objectPitch, lightYaw,
 * lightPitch, interpolated, reference, aoRays, moving}.
 */
export function draw(gl, program, field, view) {
  const [w, h] = [gl.drawingBufferWidth, gl.drawingBufferHeight];
  gl.viewport(0, 0, w, h);
  gl.useProgram(program);
  gl.uniformBlockBinding(program, gl.getUniformBlockIndex(program, 'VffFieldBlock'), 0);
  const u = (n) => gl.getUniformLocation(program, n);
  const c = field.center, R = field.radius;
  const cam = rotation(view.yaw, view.pitch);
  const D = view.distance * R;
  gl.uniform2f(u('uSize'), w, h);
  gl.uniform3f(u('uEye'), c[0] + cam[6] * D, c[1] + cam[7] * D, c[2] + cam[8] * D);
  gl.uniformMatrix3fv(u('uCamera'), false, cam);
  gl.uniformMatrix3fv(u('uObject'), false, rotation(view.objectYaw, view.objectPitch));
  const lp = view.lightPitch, ly = view.lightYaw;
  gl.uniform3f(u('uLight'), Math.cos(lp) * Math.sin(ly), Math.sin(lp), Math.cos(lp) * Math.cos(ly));
  gl.uniform1i(u('uInterpolated'), view.interpolated ? 1 : 0);
  gl.uniform1i(u('uReference'), view.reference ? 1 : 0);
  // While the user drags, fewer rays keep the view responsive; the full frame follows on release.
  gl.uniform1i(u('uAoRays'), view.moving ? 4 : Math.min(view.aoRays ?? 16, AO_RAYS));
  gl.uniform1i(u('uShadowRays'), view.moving ? 2 : 8);
  gl.drawArrays(gl.TRIANGLES, 0, 3);
}
