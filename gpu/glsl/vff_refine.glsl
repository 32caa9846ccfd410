// vff_refine.glsl - Reconstruction::kRefined on the GPU (vff/refine.h, spec/geometry.md section
// 7.5), for a single field: paste it after vff_query.glsl, whose lookup steps it calls (GL has no
// #include; with GL_GOOGLE_include_directive, #include "vff_query.glsl" then "vff_refine.glsl").
//   VffHit vffIntersectRefined(origin, direction, tmin, tmax, intraBias)  vffIntersect's arguments
//   bool vffOccludedRefined(...)  the same; any hit within [tmin, tmax]
//   VffHit vffQueryRefined(..., bool anyHit, out bool exact)  the core of both
// Resources at bindings 10 to 14 (vff::gl::loadRefinement uploads them; its shaderDefines() gives
// VFF_REFINE_STACK for the BVH's depth).
// ---- Refined fields: Reconstruction::kRefined (vff/refine.h, spec/geometry.md section 7.5) --------
// The maps answer as kNearest does where the field is sure; where the texel that lookup reads is
// marked unsure, or its hit lies within the refinement's margin of either end of the ray's range, an
// exact ray cast through a BVH of the object's triangles answers (vff::buildRefinementBvh: the BVH
// the CPU query builds, so both casts visit the same nodes in the same order). The resources come
// from vff::gl::loadRefinement (gpu/loader/include/vff/gl/refine_loader.h), whose shaderDefines()
// defines VFF_REFINED and VFF_REFINE_STACK. Single fields only (not vff_scene.glsl's instances).
// Section 7.4 step 3, as vff::FieldQuery::Impl::behindOrigin (vffQuery's own step): the off-object
// lookup's surface lies behind the origin, so section 7.3 with no bias answers. `o`: the answer so far.
VffHit vffBehindOrigin(VffHit o, vec3 origin, vec3 direction, float tmin, float tmax, bool normals,
                       inout float visibility) {
  VffLookup l;
  bool behind;
  if (!vffPrepare(origin, direction, tmin, tmax, 0.0, l)) return o;
  o.sampleIndex = uint(l.k0);
  return vffNearestHit(o, l, normals, visibility, behind);
}

#ifndef VFF_UNSURE_BINDING
#define VFF_UNSURE_BINDING 10
#endif
#ifndef VFF_VERTICES_BINDING
#define VFF_VERTICES_BINDING 11
#endif
#ifndef VFF_BVH_BINDING
#define VFF_BVH_BINDING 12
#endif
#ifndef VFF_TRIANGLES_BINDING
#define VFF_TRIANGLES_BINDING 13
#endif
#ifndef VFF_REFINE_BINDING
#define VFF_REFINE_BINDING 14
#endif
// Entries of the cast's stack: it holds one postponed node per level of the current path, so the
// BVH's depth suffices (VffRefineBlock.stackDepth; the loader's shaderDefines() sets it to that).
// The default is vff::gl::kRefineStack, the depth below which the CPU's builder keeps every BVH.
#ifndef VFF_REFINE_STACK
#define VFF_REFINE_STACK 80
#endif

// The margin and the sizes. Must match vff::gl::RefineBlock (16 bytes; tests/gpu/test_glsl_layout.cpp).
layout(std140, binding = VFF_REFINE_BINDING) uniform VffRefineBlock {
  float margin;         // RefinementView::margin * R in object units (the CPU query's float product)
  uint triangleCount;   // 0: no refinement, every ray is answered as kNearest (as the CPU)
  uint nodeCount;       // BVH nodes
  uint stackDepth;      // the BVH's depth: VFF_REFINE_STACK must be at least this
} vffRefine;
// The unsure bits as words: texel (i, j) of map k is unsure when bit x % 32 of word x / 32 is set,
// x = (k M + j) M + i (the REFN bytes read as little-endian words).
layout(std430, binding = VFF_UNSURE_BINDING) readonly buffer VffUnsureBlock {
  uint vffUnsure[];
};
// The triangles' vertices: x, y, z per vertex, object space (RefinementView::positions).
layout(std430, binding = VFF_VERTICES_BINDING) readonly buffer VffVerticesBlock {
  float vffVertices[];
};
// The BVH, node n in two uvec4: [2n] = (lo.xyz as float bits, first), [2n + 1] = (hi.xyz, count).
// count >= 1: a leaf of triangles [first, first + count); 0: an inner node whose first child is
// n + 1 and whose second is `first`.
layout(std430, binding = VFF_BVH_BINDING) readonly buffer VffBvhBlock {
  uvec4 vffBvh[];
};
// Three vertex indices per triangle, in the BVH's leaf order.
layout(std430, binding = VFF_TRIANGLES_BINDING) readonly buffer VffTrianglesBlock {
  uint vffTriangles[];
};

float vffRefineNone() { return uintBitsToFloat(0x7f800000u); }  // +inf: no hit, no entry

vec3 vffVertex(uint v) { return vec3(vffVertices[3u * v], vffVertices[3u * v + 1u], vffVertices[3u * v + 2u]); }

// a x b, each product and difference rounded (as the CPU's cross).
vec3 vffCross(vec3 a, vec3 b) {
  precise float x0 = a.y * b.z, x1 = a.z * b.y;
  precise float y0 = a.z * b.x, y1 = a.x * b.z;
  precise float z0 = a.x * b.y, z1 = a.y * b.x;
  precise vec3 c = vec3(x0 - x1, y0 - y1, z0 - z1);
  return c;
}

// Where o + t d (inv: 1 / d per axis) enters node n's box within [tmin, best]; +inf when it does
// not. As TriangleBvh::cast's enter: a NaN (an axis-parallel ray on a face) keeps the other bound.
float vffBvhEnter(uint n, vec3 o, vec3 inv, float tmin, float best) {
  vec3 lo = uintBitsToFloat(vffBvh[2u * n].xyz);
  vec3 hi = uintBitsToFloat(vffBvh[2u * n + 1u].xyz);
  precise float t0 = tmin, t1 = best;
  for (int a = 0; a < 3; ++a) {
    precise float dl = lo[a] - o[a], dh = hi[a] - o[a];
    precise float u = dl * inv[a], v = dh * inv[a];
    if (u > v) {
      precise float s = u;
      u = v;
      v = s;
    }
    t0 = u > t0 ? u : t0;
    t1 = v < t1 ? v : t1;
  }
  return t0 <= t1 ? t0 : vffRefineNone();
}

// Moller-Trumbore, two-sided, as TriangleBvh::cast: the t of o + t d on triangle `tri` when it lies
// in [tmin, best], else +inf.
float vffTriangleHit(uint tri, vec3 o, vec3 d, float tmin, float best) {
  vec3 v0 = vffVertex(vffTriangles[3u * tri]);
  vec3 v1 = vffVertex(vffTriangles[3u * tri + 1u]);
  vec3 v2 = vffVertex(vffTriangles[3u * tri + 2u]);
  precise vec3 e1 = v1 - v0, e2 = v2 - v0;
  vec3 pv = vffCross(d, e2);
  float det = vffDot(e1, pv);
  if (det == 0.0) return vffRefineNone();
  float invDet = vffDivide(1.0, det);
  precise vec3 tv = o - v0;
  precise float u = vffDot(tv, pv) * invDet;
  if (!(u >= 0.0 && u <= 1.0)) return vffRefineNone();
  vec3 qv = vffCross(tv, e1);
  precise float v = vffDot(d, qv) * invDet;
  precise float uv = u + v;
  if (!(v >= 0.0 && uv <= 1.0)) return vffRefineNone();
  precise float th = vffDot(e2, qv) * invDet;
  return (th >= tmin && th <= best) ? th : vffRefineNone();
}

// The unit geometric normal of triangle `tri`, facing against d (as TriangleBvh::intersect).
vec3 vffTriangleNormal(uint tri, vec3 d) {
  vec3 v0 = vffVertex(vffTriangles[3u * tri]);
  vec3 v1 = vffVertex(vffTriangles[3u * tri + 1u]);
  vec3 v2 = vffVertex(vffTriangles[3u * tri + 2u]);
  precise vec3 e1 = v1 - v0, e2 = v2 - v0;
  vec3 n = vffCross(e1, e2);
  float len = vffSqrt(vffDot(n, n));
  n = len > 0.0 ? vec3(vffDivide(n.x, len), vffDivide(n.y, len), vffDivide(n.z, len)) : vec3(0.0);
  return vffDot(n, d) > 0.0 ? -n : n;
}

// The exact step's cast, as TriangleBvh::cast: whether o + t d meets a triangle with t in
// [tmin, tmax]; tHit and tri: the nearest such hit and its triangle (anyHit: the first one found,
// for occlusion). Nearer child first; a postponed node is skipped when the ray no longer enters it
// before the best hit.
bool vffBvhCast(vec3 o, vec3 d, float tmin, float tmax, bool anyHit, out float tHit, out uint tri) {
  float none = vffRefineNone();
  tHit = none;
  tri = 0u;
  if (vffRefine.nodeCount == 0u || !(tmax >= tmin)) return false;
  vec3 inv = vec3(vffDivide(1.0, d.x), vffDivide(1.0, d.y), vffDivide(1.0, d.z));
  float best = tmax;
  bool found = false;
  uint stack[VFF_REFINE_STACK];
  uint top = 0u, node = 0u;
  if (vffBvhEnter(0u, o, inv, tmin, best) == none) return false;
  for (;;) {
    uint first = vffBvh[2u * node].w, count = vffBvh[2u * node + 1u].w;
    if (count == 0u) {
      uint a = node + 1u, b = first;
      float ta = vffBvhEnter(a, o, inv, tmin, best), tb = vffBvhEnter(b, o, inv, tmin, best);
      bool hitA = ta != none, hitB = tb != none;
      if (hitA && hitB) {
        bool aFirst = ta <= tb;
        node = aFirst ? a : b;
        stack[top] = aFirst ? b : a;
        ++top;
        continue;
      }
      if (hitA || hitB) {
        node = hitA ? a : b;
        continue;
      }
    } else {
      for (uint t = first; t < first + count; ++t) {
        float th = vffTriangleHit(t, o, d, tmin, best);
        if (th == none) continue;
        tri = t;
        if (anyHit) {
          tHit = th;
          return true;
        }
        best = th;
        found = true;
      }
    }
    // Next: the nearest postponed node that the ray still enters before the best hit.
    for (;;) {
      if (top == 0u) {
        if (found) tHit = best;
        return found;
      }
      --top;
      node = stack[top];
      if (anyHit || vffBvhEnter(node, o, inv, tmin, best) != none) break;
    }
  }
  return false;
}

// The exact step, as vff::FieldQuery::Impl::exactHit: `o` (the lookup made) answered by the cast
// over the ray's own [tmin, tmax]; the normal is the triangle's (not with anyHit, whose t is that
// of the first hit found).
VffHit vffExactHit(VffHit o, vec3 origin, vec3 direction, float tmin, float tmax, bool anyHit) {
  float t;
  uint tri;
  o.hit = vffBvhCast(origin, direction, tmin, tmax, anyHit, t, tri);
  o.inside = false;
  o.t = t;
  o.hasNormal = o.hit && !anyHit;
  o.normal = o.hasNormal ? vffTriangleNormal(tri, direction) : vec3(0.0);
  return o;
}

// kRefined, as vff::FieldQuery::Impl::query and refinedAt: kNearest's lookup (vffPrepare, then
// vffNearestHit's texel and decoded distance) answers where the field is sure; the exact step
// where that texel is unsure or its hit t = t0 + distance lies within the margin of either end of
// [lo, hi] (t < lo + margin, |t - hi| < margin); a sure miss is a miss. Rays answered by section
// 7.3 get kNearest's answer, and so does every ray without a refinement (triangleCount 0).
// Arguments as vffIntersect's; anyHit: the exact step stops at the first hit (occlusion); exact:
// whether the exact step answered.
VffHit vffQueryRefined(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias, bool anyHit,
                       out bool exact) {
  exact = false;
  VffHit o = VffHit(false, false, vffRefineNone(), vec3(0.0), false, false, 0u, uvec2(0u), 0u, 0.0);
  VffLookup l;
  if (!vffPrepare(origin, direction, tmin, tmax, intraBias, l)) return o;
  if (!l.inside && l.t0 > l.hi) return o;  // the sphere begins beyond the range (the CPU's prepare)
  o.looked = true;
  o.sampleIndex = uint(l.k0);
#ifdef VFF_NO_NORMALS
  bool normals = false;
#else
  bool normals = VFF_FIELD.normalEncoding != VFF_NORMAL_NONE;
#endif
  float visibility = 1.0;
  bool behind = false;
  VffHit n = vffNearestHit(o, l, normals, visibility, behind);
  if (!l.inside && vffRefine.triangleCount > 0u) {
    uint M = VFF_FIELD.mapResolution;
    uint x = (uint(l.k0) * M + n.texel.y) * M + n.texel.x;
    exact = ((vffUnsure[x >> 5u] >> (x & 31u)) & 1u) != 0u;
    if (!exact) {
      if (!vffDecode(n.code, n.texel).hit) return n;  // a sure miss: the texels around it miss too
      // Near the start of the range (or behind an origin inside the sphere) or near its end, the
      // hit may lie on the other side of it.
      precise float t = l.t0 + n.distance;
      precise float nearLo = l.lo + vffRefine.margin;
      precise float dt = t - l.hi;
      exact = t < nearLo || abs(dt) < vffRefine.margin;
    }
    if (exact) return vffExactHit(n, origin, direction, tmin, tmax, anyHit);
  }
  if (behind) return vffBehindOrigin(o, origin, direction, tmin, tmax, normals, visibility);
  return n;
}

// vff::FieldQuery::intersect with Reconstruction::kRefined.
VffHit vffIntersectRefined(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias) {
  bool exact;
  return vffQueryRefined(origin, direction, tmin, tmax, intraBias, false, exact);
}

// vff::FieldQuery::occluded with Reconstruction::kRefined (the exact step as an any-hit cast).
bool vffOccludedRefined(vec3 origin, vec3 direction, float tmin, float tmax, float intraBias) {
  bool exact;
  return vffQueryRefined(origin, direction, tmin, tmax, intraBias, true, exact).hit;
}
