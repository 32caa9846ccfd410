// vff_query.glsl - the visibility-field lookup in GLSL 4.30 core (spec/geometry.md section 7,
// spec/positions.md, spec/format.md "Packed slice layout" and "Value encodings").
//
// Include it after `#version 430` (or later). It answers rays as vff::FieldQuery does (query_ray.cpp),
// up to rounding near a texel or sample boundary (spec/geometry.md section 8).
//
// Resources (filled by the C++ loader vff::gl::loadField, gpu/loader/include/vff/gl/loader.h, which
// documents each): bindings VFF_FIELD_BINDING (default 0, uniform block VffFieldBlock),
// VFF_MAPS_BINDING (1, the packed distance slices; VFF_MAPS_3D, VFF_MAPS_BC4 select other texture
// kinds: vff::gl::shaderDefines), VFF_POSITIONS_BINDING (2, buffer VffPositionsBlock) and
// VFF_NORMALS_BINDING (3, the normal slices; VFF_NO_NORMALS omits them). Distinct numbers, so the
// declarations are valid for OpenGL and for Vulkan (one namespace per descriptor set, set 0).
//
// Entry points:
//   VffHit vffIntersect(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias)
//     direction need not be unit length; t is in multiples of it (as vff::Ray). intraBias says how
//     a ray from inside the sphere is answered: >= 0, on the object (section 7.3) with that bias;
//     VFF_OFF_OBJECT, off it (section 7.4: vff::RayOrigin::kOffObject); other negatives, on the
//     object with the field's default bias (vff::defaultIntraBias).
//   bool vffOccluded(...)  the same arguments; hit within [tmin, tmax].
//   VffHit vffIntersectInterpolated(...)  Reconstruction::kInterpolated (the miss-aware blend).
//   float vffVisibility(...)  kInterpolated FieldQuery::visibility: the unoccluded share in [0, 1].
//   VffHit vffQuery(..., bool interpolated, out float visibility)  the core of all four.
// vff_refine.glsl, pasted after this file: vffIntersectRefined, vffOccludedRefined (kRefined).
// A hit carries the object-space normal (hasNormal) when the field has a normal plane.
//
// Several fields at once (gpu/glsl/vff_scene.glsl): every lookup step reads its field through
// VFF_FIELD (default: the uniform block vffField) at VFF_POSITIONS_BASE, VFF_MAPS_LAYER and
// VFF_NORMALS_LAYER (default 0); the scene defines the four for the instance being queried.
// vffQuery's steps are named as vff::FieldQuery::Impl's: vffPrepare, vffNearestHit,
// vffInterpolated, vffBlendResult; docs/source-map.md lists every step's copies.
//
// Exactness. Variables on the path whose bits matter are `precise` (no fused multiply-add, no
// reassociation); divisions and square roots go through vffDivide and vffSqrt, which refine the
// driver's result to the correctly rounded one. A texel's decoded distance is the CPU's, bit for bit.
#ifndef VFF_QUERY_GLSL
#define VFF_QUERY_GLSL

#ifndef VFF_FIELD_BINDING
#define VFF_FIELD_BINDING 0
#endif
#ifndef VFF_MAPS_BINDING
#define VFF_MAPS_BINDING 1
#endif
#ifndef VFF_POSITIONS_BINDING
#define VFF_POSITIONS_BINDING 2
#endif
#ifndef VFF_NORMALS_BINDING
#define VFF_NORMALS_BINDING 3
#endif

// ---- Resources -----------------------------------------------------------------------------------
// Field and layout: the FDSC and LAYT fields (spec/format.md sections 5 and 6) plus the values the
// loader derives exactly as the CPU does. Must match vff::gl::FieldBlock (112 bytes; member order,
// types and std140 offsets are checked by tests/gpu/test_glsl_layout.cpp).
#ifndef VFF_FIELD
layout(std140, binding = VFF_FIELD_BINDING) uniform VffFieldBlock {
  vec3 sphereCenter;        // sphere.center
  float sphereRadius;       // sphere.radius
  uint positionScheme;      // VFF_POSITION_*
  uint positionParam;       // n
  uint mapCount;
  uint directionScheme;     // VFF_DIRECTION_*
  uint mapResolution;       // M
  uint distanceEncoding;    // VFF_ENCODING_*
  uint missCode;            // vff::missCode(distanceEncoding)
  uint normalEncoding;      // VFF_NORMAL_NONE, else the normal plane's encoding
  uint target;              // vff::LayoutTarget (not read: VFF_MAPS_3D selects the sampler)
  uint gutter;
  uint tileSize;
  uint tilesPerRow;
  uint tilesPerColumn;
  uint sliceWidth;
  uint sliceHeight;
  uint sliceCount;
  float intraBias;          // vff::defaultIntraBias(field), a fraction of R
  float distanceScale;      // unorm8/16-diameter: 2R / 254 or 2R / 65534 (float, as the CPU)
  float invRadius;          // 1 / R (float, as the CPU)
  float twoRadius;          // 2 R
  uint neighbourOffset;     // vec4 index of the neighbour lists in vffPositions (kInterpolated)
  float kernelRadius2;      // squared chord radius of the kInterpolated kernel (as the CPU)
  uint reserved0;
  uint reserved1;
} vffField;
#define VFF_FIELD vffField
#endif
// Where the field's data lie in vffPositions (vec4 index), vffMaps and vffNormals (first slice):
// 0 for a single field; vff_scene.glsl defines them for the instance it queries.
#ifndef VFF_POSITIONS_BASE
#define VFF_POSITIONS_BASE 0u
#endif
#ifndef VFF_MAPS_LAYER
#define VFF_MAPS_LAYER 0u
#endif
#ifndef VFF_NORMALS_LAYER
#define VFF_NORMALS_LAYER 0u
#endif

#if defined(VFF_MAPS_BC4)
// bc4-diameter: the texture unit decodes the BC4 blocks (spec/format.md 7.4); 2D arrays only.
layout(binding = VFF_MAPS_BINDING) uniform highp sampler2DArray vffMaps;
#ifndef VFF_NO_NORMALS
layout(binding = VFF_NORMALS_BINDING) uniform highp isampler2DArray vffNormals;
#endif
#elif defined(VFF_MAPS_3D)
layout(binding = VFF_MAPS_BINDING) uniform highp usampler3D vffMaps;
#ifndef VFF_NO_NORMALS
layout(binding = VFF_NORMALS_BINDING) uniform highp isampler3D vffNormals;
#endif
#else
layout(binding = VFF_MAPS_BINDING) uniform highp usampler2DArray vffMaps;
#ifndef VFF_NO_NORMALS
layout(binding = VFF_NORMALS_BINDING) uniform highp isampler2DArray vffNormals;
#endif
#endif

// vffPositions[k], k < mapCount: the outward unit vector of sample k (w = 0); then, for
// unorm8-chord, the decode scale of texel t = j M + i at component t % 4 of [mapCount + t / 4]; from
// VFF_FIELD.neighbourOffset, kInterpolated's neighbour lists (VFF_NEIGHBOURS floats a map, -1 pads).
layout(std430, binding = VFF_POSITIONS_BINDING) readonly buffer VffPositionsBlock {
  vec4 vffPositions[];
};

// The values of vff/format.h's enums and of vff::kQueryNeighbours (tests/gpu/test_glsl_layout.cpp
// checks every top-level constant of this file against the C++).
const uint VFF_POSITION_OCTA_HEMI2 = 1u;
const uint VFF_POSITION_EA_OCTA_GRID = 2u;
const uint VFF_POSITION_FIBONACCI = 3u;
const uint VFF_DIRECTION_CONCENTRIC_EQUAL_AREA = 1u;
const uint VFF_DIRECTION_HEMI_OCTAHEDRAL = 2u;
const uint VFF_ENCODING_UNORM8_DIAMETER = 1u;
const uint VFF_ENCODING_UNORM8_CHORD = 2u;
const uint VFF_ENCODING_UNORM16_DIAMETER = 3u;
const uint VFF_ENCODING_BIT1 = 4u;
const uint VFF_ENCODING_BC4_DIAMETER = 5u;
const uint VFF_NORMAL_NONE = 0u;
const uint VFF_NEIGHBOURS = 8u;  // neighbour list entries per map (vff::kQueryNeighbours)

// ---- Arithmetic ----------------------------------------------------------------------------------
// a / b, correctly rounded (one Newton correction of the driver's quotient, with a fused residual).
float vffDivide(float a, float b) {
  precise float q = a / b;
  precise float r = fma(-q, b, a);
  precise float c = fma(r, 1.0 / b, q);
  // Keep the driver's quotient where the correction is meaningless (inf, nan, zero divisor).
  return (isinf(q) || isnan(c) || b == 0.0) ? q : c;
}

// sqrt(a), correctly rounded (one Newton correction with a fused residual; drivers approximate).
float vffSqrt(float a) {
  precise float s = sqrt(a);
  precise float r = fma(-s, s, a);
  precise float c = fma(r, vffDivide(0.5, s), s);
  return (s == 0.0 || isinf(s) || isnan(c)) ? s : c;
}

// a.x b.x + a.y b.y + a.z b.z, in this order, each operation rounded (as the C++ reference).
float vffDot(vec3 a, vec3 b) {
  precise float x = a.x * b.x;
  precise float y = a.y * b.y;
  precise float z = a.z * b.z;
  precise float s = x + y;
  precise float d = s + z;
  return d;
}

// ---- Frames and direction schemes (spec/geometry.md sections 3 to 5) ------------------------------
const float kVffPi = 3.14159265358979323846;
const float kVffQuarterPi = kVffPi / 4.0;

// duff2017 frame around the unit inward normal n: columns t, b, n.
mat3 vffFrame(vec3 n) {
  precise float s = n.z >= 0.0 ? 1.0 : -1.0;  // not sign(): sign(0.0) is 0
  precise float a = vffDivide(-1.0, s + n.z);
  precise float k = n.x * n.y * a;
  precise vec3 t = vec3(1.0 + s * n.x * n.x * a, s * k, -s * n.x);
  precise vec3 b = vec3(k, s + n.y * n.y * a, -n.y);
  return mat3(t, b, n);
}
// (w.t, w.b, w.n)
vec3 vffToLocal(mat3 F, vec3 w) { return vec3(vffDot(w, F[0]), vffDot(w, F[1]), vffDot(w, F[2])); }

// scheme 1 = concentric-equal-area, 2 = hemi-octahedral. d.z < 0 is treated as the horizon.
vec2 vffHemisphereToSquare(uint scheme, vec3 d) {
  precise float z = max(0.0, d.z);
  if (scheme == VFF_DIRECTION_HEMI_OCTAHEDRAL) {
    precise float l1 = abs(d.x) + abs(d.y) + z;
    precise float inv = vffDivide(1.0, l1);
    precise float x = d.x * inv;
    precise float y = d.y * inv;
    precise vec2 uv = vec2(x + y, x - y);
    return clamp(uv, -1.0, 1.0);
  }
  precise float r = vffSqrt(max(0.0, 1.0 - z));
  if (r == 0.0) return vec2(0.0);            // the pole; atan(0, 0) is undefined in GLSL
  precise float phi = atan(d.y, d.x);        // (-pi, pi]
  if (phi < -kVffQuarterPi) phi += 2.0 * kVffPi;  // [-pi/4, 7pi/4)
  precise vec2 ab;
  if (phi < kVffQuarterPi) {
    ab = vec2(r, vffDivide(phi * r, kVffQuarterPi));
  } else if (phi < 3.0 * kVffQuarterPi) {
    ab = vec2(vffDivide(-(phi - 2.0 * kVffQuarterPi) * r, kVffQuarterPi), r);
  } else if (phi < 5.0 * kVffQuarterPi) {
    ab = vec2(-r, vffDivide((phi - kVffPi) * -r, kVffQuarterPi));
  } else {
    ab = vec2(vffDivide((phi - 6.0 * kVffQuarterPi) * r, kVffQuarterPi), -r);
  }
  return clamp(ab, -1.0, 1.0);
}

vec3 vffSquareToHemisphere(uint scheme, vec2 uv) {
  precise float a = clamp(uv.x, -1.0, 1.0);
  precise float b = clamp(uv.y, -1.0, 1.0);
  if (scheme == VFF_DIRECTION_HEMI_OCTAHEDRAL) {
    precise float x = (a + b) * 0.5;
    precise float y = (a - b) * 0.5;
    precise float z = 1.0 - abs(x) - abs(y);
    precise float ss = x * x + y * y + z * z;
    precise float len = vffSqrt(ss);
    return vec3(vffDivide(x, len), vffDivide(y, len), vffDivide(z, len));
  }
  precise float r, phi;
  if (a == 0.0 && b == 0.0) { r = 0.0; phi = 0.0; }
  else if (abs(a) > abs(b)) { r = a; phi = kVffQuarterPi * vffDivide(b, a); }
  else                      { r = b; phi = 2.0 * kVffQuarterPi - kVffQuarterPi * vffDivide(a, b); }
  precise float r2 = r * r;
  precise float s = r * vffSqrt(max(0.0, 2.0 - r2));
  return vec3(s * cos(phi), s * sin(phi), 1.0 - r2);
}

// cos(alpha) of the direction through square point uv: the z of vffSquareToHemisphere (which does
// not depend on its sin and cos, so compilers drop them).
float vffSquareToCosAlpha(uint scheme, vec2 uv) {
  return vffSquareToHemisphere(scheme, uv).z;
}

ivec2 vffSquareToTexel(vec2 uv, int M) {
  precise vec2 f = floor((uv + 1.0) * 0.5 * float(M));
  return clamp(ivec2(clamp(f, vec2(0.0), vec2(float(M - 1)))), ivec2(0), ivec2(M - 1));
}
vec2 vffTexelCenter(ivec2 ij, int M) {
  precise vec2 n = 2.0 * vec2(ij) + 1.0;
  return vec2(vffDivide(n.x, float(M)), vffDivide(n.y, float(M))) - 1.0;
}

// ---- Nearest positional sample (spec/positions.md section 6, positions read from the buffer) -------
vec3 vffPosition(int k) { return vffPositions[VFF_POSITIONS_BASE + uint(k)].xyz; }

int vffOctaHemi2Index(int n, int h, int p, int q) {
  int t = n + q;
  int start = q <= 0 ? t * t : t * t - 2 * q * (q - 1);
  return h * (2 * n * n + 2 * n + 1) + start + p + n - abs(q);
}

int vffNearestOctaHemi2(vec3 d, int n) {
  int h = d.z >= 0.0 ? 0 : 1;
  vec3 a = abs(d);
  float s = float(n) / (a.x + a.y + a.z);
  ivec2 c0 = min(ivec2(a.xy * s), ivec2(n - 1));
  ivec2 sg = ivec2(d.x < 0.0 ? -1 : 1, d.y < 0.0 ? -1 : 1);
  const ivec2 offs[8] = ivec2[8](ivec2(0, 0), ivec2(1, 0), ivec2(0, 1), ivec2(1, 1),
                                 ivec2(-1, 1), ivec2(1, -1), ivec2(2, 0), ivec2(0, 2));
  float best = -2.0;
  int bestK = 0;
  for (int c = 0; c < 8; ++c) {
    ivec2 ab = c0 + offs[c];
    int l1 = abs(ab.x) + abs(ab.y);
    if (l1 > n) continue;
    ivec2 pq = sg * ab;
    int k = vffOctaHemi2Index(n, l1 == n ? 0 : h, pq.x, pq.y);
    float dd = vffDot(vffPosition(k), d);
    if (dd > best || (dd == best && k < bestK)) { best = dd; bestK = k; }
  }
  return bestK;
}

int vffNearestEaOctaGrid(vec3 d, int n) {
  vec3 a = abs(d);
  float r = sqrt((a.x * a.x + a.y * a.y) / (1.0 + a.z));
  float b = a.x + a.y > 0.0 ? r * (atan(a.y, a.x) * 0.636619772) : 0.0;  // atan(0, 0) is undefined
  vec2 uv = vec2(r - b, b);
  if (d.z < 0.0) uv = 1.0 - uv.yx;
  uv = vec2(d.x < 0.0 ? -uv.x : uv.x, d.y < 0.0 ? -uv.y : uv.y);
  ivec2 c0 = clamp(ivec2(floor((uv + 1.0) * (0.5 * float(n)))), ivec2(0), ivec2(n - 1));
  float best = -2.0;
  int bestK = 0;
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di) {
      ivec2 c = c0 + ivec2(di, dj);
      if (c.x < 0 || c.x >= n) c = ivec2(c.x < 0 ? 0 : n - 1, n - 1 - c.y);
      if (c.y < 0 || c.y >= n) c = ivec2(n - 1 - c.x, c.y < 0 ? 0 : n - 1);
      int k = c.y * n + c.x;
      float dd = vffDot(vffPosition(k), d);
      if (dd > best || (dd == best && k < bestK)) { best = dd; bestK = k; }
    }
  return bestK;
}

const uint VFF_FIB[22] = uint[22](0u, 1u, 1u, 2u, 3u, 5u, 8u, 13u, 21u, 34u, 55u, 89u, 144u, 233u,
                                  377u, 610u, 987u, 1597u, 2584u, 4181u, 6765u, 10946u);

// The top 32 bits of (k * 0x9E3779B97F4A7C15) mod 2^64, that is frac(k (Phi - 1)) * 2^32.
uint vffFibTop32(uint k) {
  uint hi, lo;
  umulExtended(k, 0x7F4A7C15u, hi, lo);
  return k * 0x9E3779B9u + hi;
}

int vffNearestFibonacci(vec3 d, int n) {
  float rho2 = d.x * d.x + d.y * d.y;
  float v = float(n) * 7.02481473 * rho2;                                  // n pi sqrt(5) rho^2
  int k = v > 1.0 ? clamp(int(floor(log(v) * 1.03904346)), 2, 20) : 2;    // 1 / ln(Phi^2)
  uint f0 = VFF_FIB[k], f1 = VFF_FIB[k + 1];
  float p0 = float(int(vffFibTop32(f0))) * (6.28318531 / 4294967296.0);
  float p1 = float(int(vffFibTop32(f1))) * (6.28318531 / 4294967296.0);
  float z0 = -2.0 * float(f0) / float(n), z1 = -2.0 * float(f1) / float(n);
  float phi = rho2 > 0.0 ? atan(d.y, d.x) : 0.0;
  float dz = d.z - (1.0 - 1.0 / float(n));
  float det = p0 * z1 - p1 * z0;
  int c0 = int(floor((phi * z1 - p1 * dz) / det));
  int c1 = int(floor((p0 * dz - z0 * phi) / det));
  float best = -2.0;
  int bestK = 0;
  for (int s = 0; s < 4; ++s) {
    int i = (c0 + (s & 1)) * int(f0) + (c1 + (s >> 1)) * int(f1);
    if (i < 0 || i >= n) continue;
    float dd = vffDot(vffPosition(i), d);
    if (dd > best || (dd == best && i < bestK)) { best = dd; bestK = i; }
  }
  return bestK;
}

// The sample nearest to direction d (need not be unit length).
int vffNearestSample(vec3 d) {
  vec3 u = normalize(d);
  int n = int(VFF_FIELD.positionParam);
  if (VFF_FIELD.positionScheme == VFF_POSITION_OCTA_HEMI2) return vffNearestOctaHemi2(u, n);
  if (VFF_FIELD.positionScheme == VFF_POSITION_EA_OCTA_GRID) return vffNearestEaOctaGrid(u, n);
  return vffNearestFibonacci(u, n);
}

// ---- Fetch and decode (spec/format.md "Packed slice layout", "Value encodings") ----------------------
// Where texel (i, j) of map k lies in the packed slices (placeMap): x, y, slice.
uvec3 vffPlace(uint k, uvec2 ij) {
  uint perSlice = VFF_FIELD.tilesPerRow * VFF_FIELD.tilesPerColumn;
  uint slice = k / perSlice;
  uint r = k - slice * perSlice;
  uint x = (r % VFF_FIELD.tilesPerRow) * VFF_FIELD.tileSize + VFF_FIELD.gutter + ij.x;
  uint y = (r / VFF_FIELD.tilesPerRow) * VFF_FIELD.tileSize + VFF_FIELD.gutter + ij.y;
  return uvec3(x, y, slice);
}

// The stored code of texel (i, j) of map k: placeMap, then texelFetch in the packed slices.
uint vffFetchCode(uint k, uvec2 ij) {
  uvec3 p = vffPlace(k, ij) + uvec3(0u, 0u, VFF_MAPS_LAYER);
#ifdef VFF_MAPS_BC4
  // The palette entry as a normalised value: its code is round(value * 255). Texture units may round
  // the interpolated entries differently from the CPU's integer rule (by under one code); 0 and 255
  // (a miss) are exact.
  return uint(round(texelFetch(vffMaps, ivec3(p), 0).r * 255.0));
#else
  if (VFF_FIELD.distanceEncoding == VFF_ENCODING_BIT1)
    return (texelFetch(vffMaps, ivec3(int(p.x >> 3u), int(p.y), int(p.z)), 0).r >> (p.x & 7u)) & 1u;
  return texelFetch(vffMaps, ivec3(p), 0).r;
#endif
}

// oct-snorm16 (spec/format.md 7.3) as vff::decodeNormal: X / 32767 clamped to -1, the octahedral
// unfold, then v / |v|, with correctly rounded division and square root.
vec3 vffDecodeNormal(ivec2 c) {
  precise float px = max(vffDivide(float(c.x), 32767.0), -1.0);
  precise float py = max(vffDivide(float(c.y), 32767.0), -1.0);
  precise float pz = 1.0 - abs(px) - abs(py);
  precise vec3 n = vec3(px, py, pz);
  if (n.z < 0.0) {
    precise float ox = (1.0 - abs(n.y)) * (n.x >= 0.0 ? 1.0 : -1.0);
    precise float oy = (1.0 - abs(n.x)) * (n.y >= 0.0 ? 1.0 : -1.0);
    n.x = ox;
    n.y = oy;
  }
  precise float len = vffSqrt(vffDot(n, n));
  return vec3(vffDivide(n.x, len), vffDivide(n.y, len), vffDivide(n.z, len));
}

// The object-space unit normal stored for texel (i, j) of map k (the field must have a normal
// plane; define VFF_NO_NORMALS to leave the normal texture out of the shader).
vec3 vffFetchNormal(uint k, uvec2 ij) {
#ifdef VFF_NO_NORMALS
  return vec3(0.0);
#else
  return vffDecodeNormal(texelFetch(vffNormals, ivec3(vffPlace(k, ij) + uvec3(0u, 0u, VFF_NORMALS_LAYER)), 0).rg);
#endif
}

// A decoded texel: hit, and the distance from the sample point (0 for bit1).
struct VffTexel {
  bool hit;
  float distance;
};

VffTexel vffDecode(uint code, uvec2 ij) {
  VffTexel o;
  uint e = VFF_FIELD.distanceEncoding;
  if (e == VFF_ENCODING_BIT1) {
    o.hit = code != 0u;
    o.distance = 0.0;
    return o;
  }
  o.hit = code != VFF_FIELD.missCode;
  if (e == VFF_ENCODING_UNORM8_CHORD) {
    // The texel's scale 2R cos(alpha) / 254 from the table after the positions (see the buffer).
    // Computing it here with vffSquareToCosAlpha is within an ulp, but not bit-exact on drivers
    // that fuse a * b + c despite `precise` (llvmpipe does).
    uint t = ij.y * VFF_FIELD.mapResolution + ij.x;
    float scale = vffPositions[VFF_POSITIONS_BASE + VFF_FIELD.mapCount + t / 4u][t % 4u];
    precise float d = float(code) * scale;
    o.distance = d;
  } else {
    precise float d = float(code) * VFF_FIELD.distanceScale;
    o.distance = d;
  }
  return o;
}

// ---- The ray query (spec/geometry.md 7.2-7.4; vff::FieldQuery, kNearest and kInterpolated) ------
const float VFF_OFF_OBJECT = -2.0;  // intraBias of a ray that starts off the object (section 7.4)
struct VffHit {
  bool hit;       // the ray hits the object with t in [tmin, tmax]
  bool inside;    // the origin was inside the bounding sphere (the reversed-ray test of 7.3)
  float t;        // along the ray, in multiples of its direction; +inf without a hit
  vec3 normal;    // object-space unit surface normal at the hit, when hasNormal
  bool hasNormal; // the field has a normal plane (normalEncoding != VFF_NORMAL_NONE) and the ray hit
  // The lookup that answered the ray (valid when looked): sample, texel, stored code and its
  // decoded distance from the sample's entry point. Useful for debugging and for the tests.
  // kInterpolated: the nearest sample only (texel, code and distance are 0).
  bool looked;
  uint sampleIndex;
  uvec2 texel;
  uint code;
  float distance;
};

// The kInterpolated kernel weight of sample k for the unit entry point eu (as the CPU).
float vffKernel(vec3 eu, uint k) {
  precise vec3 d = eu - vffPosition(int(k));
  precise float x = 1.0 - vffDivide(vffDot(d, d), VFF_FIELD.kernelRadius2);
  precise float w = x * x;
  return x > 0.0 ? w : 0.0;
}

// A ray where it enters the field's sphere, as vff::FieldQuery::Impl::Lookup: unit direction w,
// length len; the direction looked up, v (-w for section 7.3's reversed ray); the entry point t0 and
// the range [lo, hi], along w; the entry point on the unit sphere, eu, and its nearest sample k0.
struct VffLookup {
  vec3 w, v, eu;
  float len, t0, lo, hi;
  bool inside, off;  // answered by section 7.3; by 7.4 (origin inside the sphere, t0 < 0)
  int k0;
};

// 1. The sphere and 2. the nearest sample, as vff::FieldQuery::Impl::prepare: false (l unset) when
// the ray misses the sphere or cannot be answered (a zero direction; a bit1 field from inside).
bool vffPrepare(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias, out VffLookup l) {
  precise float len = vffSqrt(vffDot(direction, direction));
  if (!(len > 0.0) || isinf(len) || isnan(len)) return false;
  precise float invLen = vffDivide(1.0, len);
  precise vec3 w = direction * invLen;
  precise float lo = tmin * len;
  precise float hi = tmax * len;
  vec3 c = VFF_FIELD.sphereCenter;
  float R = VFF_FIELD.sphereRadius;
  precise vec3 delta = origin - c;
  precise float beta = vffDot(delta, w);
  precise float gamma = vffDot(delta, delta) - R * R;
  precise float disc = beta * beta - gamma;
  if (!(disc >= 0.0)) return false;
  precise float sq = vffSqrt(disc);
  precise float t1 = -beta + sq;
  if (t1 < 0.0) return false;
  bool inSphere = gamma <= 0.0, offObject = intraBias == VFF_OFF_OBJECT, inside = inSphere && !offObject;
  if (inSphere && VFF_FIELD.distanceEncoding == VFF_ENCODING_BIT1) return false;  // no distances: cannot tell
  // On the object the reversed ray enters at the exit point and looks back at the origin; off it,
  // the ray extended backwards enters before the origin (t0 < 0).
  precise float tIn = -beta - sq;
  precise float t0 = inside ? t1 : (offObject && inSphere ? tIn : max(tIn, 0.0));
  precise vec3 e = origin + w * t0;
  vec3 v = inside ? -w : w;
  if (inside) {
    precise float bias = (intraBias >= 0.0 ? intraBias : VFF_FIELD.intraBias) * R;
    lo = max(lo, bias);
  }
  precise vec3 eu = (e - c) * VFF_FIELD.invRadius;
  l = VffLookup(w, v, eu, len, t0, lo, hi, inside, !inside && t0 < 0.0, vffNearestSample(eu));
  return true;
}

float vffOffTolerance() { return vffDivide(2.0 * VFF_FIELD.sphereRadius, 255.0); }  // section 7.4's, 2R/255

// kNearest (and every ray from inside), as vff::FieldQuery::Impl::nearestHit and, off the object,
// offHitAt: 3. the texel of the nearest sample's map in direction v, 4. its decode, 5. the result.
// `o` is the answer so far (the sample looked up); `visibility` becomes 0 on a hit. behind: an
// off-object lookup's surface lies behind the origin (section 7.4 step 3 applies; o is no answer).
VffHit vffNearestHit(VffHit o, VffLookup l, bool normals, inout float visibility, out bool behind) {
  behind = false;
  int k = l.k0;
  int M = int(VFF_FIELD.mapResolution);
  vec3 ek = vffPosition(k);
  mat3 F = vffFrame(-ek);
  vec3 lv = vffToLocal(F, l.v);
  vec2 uv = vffHemisphereToSquare(VFF_FIELD.directionScheme, lv);
  uvec2 ij = uvec2(vffSquareToTexel(uv, M));
  uint code = vffFetchCode(uint(k), ij);
  VffTexel s = vffDecode(code, ij);
  o.texel = ij;
  o.code = code;
  o.distance = s.distance;
  if (!s.hit) return o;
  // 5. The result.
  precise float t = l.inside ? l.t0 - s.distance : l.t0 + s.distance;
  behind = l.off && t < l.lo - vffOffTolerance();
  if (l.off) t = max(t, l.lo);  // (within the tolerance behind: a hit at lo)
  if (behind || t < l.lo || t > l.hi) return o;
  visibility = 0.0;
  o.hit = true;
  o.inside = l.inside;
  o.t = vffDivide(t, l.len);
  if (normals) {
    o.normal = vffFetchNormal(uint(k), ij);
    o.hasNormal = true;
  }
  return o;
}

// The kernel of kInterpolated around the nearest sample k: k itself (which always contributes) and
// its neighbours of positive weight, in the CPU's order.
struct VffKernelSamples {
  uint count;
  uint index[VFF_NEIGHBOURS + 1u];
  float weight[VFF_NEIGHBOURS + 1u];
};

VffKernelSamples vffKernelSamples(vec3 eu, uint k) {
  VffKernelSamples ks;
  ks.count = 1u;
  ks.index[0] = k;
  ks.weight[0] = max(vffKernel(eu, k), 1e-6);  // the nearest sample always contributes
  uint nbase = VFF_FIELD.neighbourOffset + (VFF_NEIGHBOURS / 4u) * k;
  for (uint q = 0u; q < VFF_NEIGHBOURS; ++q) {
    float f = vffPositions[VFF_POSITIONS_BASE + nbase + q / 4u][q % 4u];
    if (f < 0.0) break;
    uint nk = uint(f);
    float wk = vffKernel(eu, nk);
    if (wk > 0.0) {
      ks.index[ks.count] = nk;
      ks.weight[ks.count] = wk;
      ++ks.count;
    }
  }
  return ks;
}

// The answer of a kInterpolated blend from its weight sums (vff::detail::Blend: the hits within
// the range, with their weighted t and normals; the misses; the hits beyond tmax), as
// vff::FieldQuery::Impl::blendResult: `visibility` becomes the unoccluded share; a hit where the
// hits outweigh the rest, at their mean t.
VffHit vffBlendResult(VffHit o, float hitW, float missW, float farW, float tSum, vec3 nSum, float len,
                      bool normals, inout float visibility) {
  precise float open = missW + farW;
  precise float total = hitW + open;
  if (!(total > 0.0)) return o;
  visibility = vffDivide(open, total);
  if (hitW <= open) return o;
  precise float t = vffDivide(tSum, hitW);
  o.hit = true;
  o.t = vffDivide(t, len);
  if (normals) {
    precise float nl = vffSqrt(vffDot(nSum, nSum));
    if (nl > 0.0) {
      precise vec3 n = nSum * vffDivide(1.0, nl);  // the CPU's normalize: times the reciprocal
      o.normal = n;
      o.hasNormal = vffDot(n, n) > 0.0;
    }
  }
  return o;
}

// kInterpolated from outside, as vff::FieldQuery::Impl::interpolated: the kernel's samples, each
// looked up along v from its own sample point with miss-aware bilinear weights; every hit point is
// projected onto the ray. Hits and misses are summed separately. `o` is the answer so far.
VffHit vffInterpolated(VffHit o, vec3 origin, VffLookup l, bool normals, inout float visibility) {
  // The sphere begins beyond the range: nothing can occlude (the CPU query returns before any
  // lookup; for kNearest the texel's hit would lie beyond tmax anyway).
  if (l.t0 > l.hi) return o;
  VffKernelSamples ks = vffKernelSamples(l.eu, uint(l.k0));
  vec3 c = VFF_FIELD.sphereCenter;
  float R = VFF_FIELD.sphereRadius;
  int M = int(VFF_FIELD.mapResolution);
  precise float hitW = 0.0, missW = 0.0, farW = 0.0, tSum = 0.0;
  precise vec3 nSum = vec3(0.0);
  for (uint q = 0u; q < ks.count; ++q) {
    uint kk = ks.index[q];
    vec3 uk = vffPosition(int(kk));
    precise vec3 p = c + uk * R;
    vec3 lv = vffToLocal(vffFrame(-uk), l.v);
    if (lv.z <= 0.0) continue;  // the sample does not see this direction
    vec2 uv = vffHemisphereToSquare(VFF_FIELD.directionScheme, lv);
    precise float x = (uv.x + 1.0) * 0.5 * float(M) - 0.5;
    precise float y = (uv.y + 1.0) * 0.5 * float(M) - 0.5;
    precise float fx0 = floor(x), fy0 = floor(y);
    precise float fx = x - fx0, fy = y - fy0;
    int ix = int(fx0), iy = int(fy0);
    precise float base = vffDot(p - origin, l.w);  // t of the sample point, projected on the ray
    for (int dj = 0; dj < 2; ++dj) {
      for (int di = 0; di < 2; ++di) {
        precise float bw = ks.weight[q] * (di != 0 ? fx : 1.0 - fx) * (dj != 0 ? fy : 1.0 - fy);
        if (bw <= 0.0) continue;
        uvec2 tij = uvec2(clamp(ivec2(ix + di, iy + dj), ivec2(0), ivec2(M - 1)));
        VffTexel s = vffDecode(vffFetchCode(kk, tij), tij);
        if (!s.hit) {
          missW += bw;
          continue;
        }
        precise float t = base + s.distance;  // along v = w from outside (t per unit distance: 1)
        if (t > l.hi) {
          farW += bw;
        } else if (t >= l.lo) {
          hitW += bw;
          tSum += bw * t;
          if (normals) nSum = nSum + vffFetchNormal(kk, tij) * bw;
        }
        // t < lo: a hit before the range, neither an occluder nor a miss
      }
    }
  }
  return vffBlendResult(o, hitW, missW, farW, tSum, nSum, l.len, normals, visibility);
}

// The core of every query, as vff::FieldQuery::Impl::query. `visibility` receives the unoccluded
// share: 0 or 1 for kNearest (interpolated == false), the misses' and far hits' share of the blend
// weight for kInterpolated. Rays answered by section 7.3 are answered as kNearest in both modes.
VffHit vffQuery(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias, bool interpolated,
                out float visibility) {
  // No hit (t = +inf), nothing looked up.
  VffHit o = VffHit(false, false, uintBitsToFloat(0x7f800000u), vec3(0.0), false, false, 0u, uvec2(0u), 0u, 0.0);
  visibility = 1.0;
  VffLookup l;
  if (!vffPrepare(origin, direction, tmin, tmax, intraBias, l)) return o;
  o.looked = true;
  o.sampleIndex = uint(l.k0);
#ifdef VFF_NO_NORMALS
  bool normals = false;
#else
  bool normals = VFF_FIELD.normalEncoding != VFF_NORMAL_NONE;
#endif
  bool behind = false;
  if (!interpolated || l.inside || l.off) {
    VffHit n = vffNearestHit(o, l, normals, visibility, behind);
    if (!behind && (!interpolated || l.inside)) return n;
    visibility = 1.0;
  }
  if (behind) {  // section 7.4 step 3: section 7.3 with no bias
    if (!vffPrepare(origin, direction, tmin, tmax, 0.0, l)) return o;
    o.sampleIndex = uint(l.k0);
    return vffNearestHit(o, l, normals, visibility, behind);
  }
  if (!l.off) return vffInterpolated(o, origin, l, normals, visibility);
  // Section 7.4, interpolated: the blend over [lo - tolerance, hi], its distance clamped to lo.
  precise float lo = l.lo;
  l.lo = lo - vffOffTolerance();
  VffHit h = vffInterpolated(o, origin, l, normals, visibility);
  precise float tl = h.t * l.len;
  if (h.hit && tl < lo) h.t = vffDivide(lo, l.len);
  return h;
}

// vff::FieldQuery::intersect with Reconstruction::kNearest (the paper's lookup).
VffHit vffIntersect(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias) {
  float v;
  return vffQuery(origin, direction, tmin, tmax, intraBias, false, v);
}

// vff::FieldQuery::intersect with Reconstruction::kInterpolated.
VffHit vffIntersectInterpolated(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias) {
  float v;
  return vffQuery(origin, direction, tmin, tmax, intraBias, true, v);
}

// kNearest occluded(): a hit within [tmin, tmax].
bool vffOccluded(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias) {
  return vffIntersect(origin, direction, tmin, tmax, intraBias).hit;
}

// vff::FieldQuery::visibility with Reconstruction::kInterpolated: the unoccluded share in [0, 1].
float vffVisibility(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias) {
  float v;
  vffQuery(origin, direction, tmin, tmax, intraBias, true, v);
  return v;
}

#endif  // VFF_QUERY_GLSL
