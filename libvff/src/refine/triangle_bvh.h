// triangle_bvh.h - the exact step of refined queries (private): a bounding volume hierarchy over a
// refined field's triangles, and ray casts through it (vff/refine.h).
//
// A binary BVH built by binned surface-area heuristic, deterministically (one thread, ties to the
// lower bin and axis), with at most kMaxLeaf triangles a leaf. Nodes are 32 bytes, depth-first:
// an inner node's first child follows it, `next` names its second; a leaf holds triangles
// [first, first + count) of `tris`, the triangles' vertex indices in leaf order. The GLSL port
// (gpu/) reads the same arrays.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "vff/direction.h"
#include "vff/refine.h"

namespace vff::detail {

// The triangle test both BVHs cast with (Möller-Trumbore, two-sided): whether the ray o + t d meets
// triangle (v0, v1, v2) at a t within [tmin, tmax], *t that t. One definition, so that the binary
// BVH (whose arrays the GPU walks) and the wide one (the CPU's casts) answer alike.
inline bool triangleHit(Vec3 o, Vec3 d, Vec3 v0, Vec3 v1, Vec3 v2, float tmin, float tmax, float* t) noexcept {
  auto sub = [](Vec3 a, Vec3 b) { return Vec3{a.x - b.x, a.y - b.y, a.z - b.z}; };
  auto cross = [](Vec3 a, Vec3 b) { return Vec3{a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; };
  auto dot = [](Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; };
  const Vec3 e1 = sub(v1, v0), e2 = sub(v2, v0);
  const Vec3 pv = cross(d, e2);
  const float det = dot(e1, pv);
  if (det == 0.0f) return false;
  const float invDet = 1.0f / det;
  const Vec3 tv = sub(o, v0);
  const float u = dot(tv, pv) * invDet;
  if (!(u >= 0.0f && u <= 1.0f)) return false;
  const Vec3 qv = cross(tv, e1);
  const float v = dot(d, qv) * invDet;
  if (!(v >= 0.0f && u + v <= 1.0f)) return false;
  const float th = dot(e2, qv) * invDet;
  if (!(th >= tmin && th <= tmax)) return false;
  *t = th;
  return true;
}

// A leaf of either BVH: triangles [first, first + count) of `tris` (three vertex indices each into
// positions p) against the ray within [tmin, *best]. Returns whether one is hit; then *best and
// *tri are the nearest one's (kAny: the first one found's).
template <bool kAny>
inline bool leafHit(Vec3 o, Vec3 d, const float* p, const uint32_t* tris, uint32_t first, uint32_t count, float tmin,
                    float* best, uint32_t* tri) noexcept {
  auto vert = [p](uint32_t v) { return Vec3{p[3 * size_t(v)], p[3 * size_t(v) + 1], p[3 * size_t(v) + 2]}; };
  bool found = false;
  for (uint32_t t = first; t < first + count; ++t) {
    const uint32_t* v = &tris[3 * size_t(t)];
    float th = 0;
    if (!triangleHit(o, d, vert(v[0]), vert(v[1]), vert(v[2]), tmin, *best, &th)) continue;
    *best = th;
    *tri = t;
    found = true;
    if constexpr (kAny) return true;
  }
  return found;
}

// The unit geometric normal of triangle (v0, v1, v2), facing against d.
Vec3 triangleNormal(Vec3 v0, Vec3 v1, Vec3 v2, Vec3 d) noexcept;

struct BvhNode {
  float lo[3];
  uint32_t first;  // leaf: first triangle; inner: index of the second child
  float hi[3];
  uint32_t count;  // leaf: triangles (>= 1); inner: 0
};
static_assert(sizeof(BvhNode) == 32);

class TriangleBvh {
 public:
  static constexpr uint32_t kMaxLeaf = 8;
  static constexpr uint32_t kMaxDepth = kRefinementBvhMaxDepth;

  TriangleBvh() = default;
  // Borrows positions (x, y, z per vertex), which must outlive the BVH; copies the indices into
  // leaf order. Preconditions (checked by the REFN reader): indices in range, finite positions.
  TriangleBvh(std::span<const float> positions, std::span<const uint32_t> indices);

  bool empty() const noexcept { return nodes_.empty(); }
  // Whether the ray o + t d hits a triangle with t in [tmin, tmax] (two-sided).
  bool occluded(Vec3 o, Vec3 d, float tmin, float tmax) const noexcept;
  // The nearest such hit: true with *t and the triangle's unit geometric normal (facing against d).
  bool intersect(Vec3 o, Vec3 d, float tmin, float tmax, float* t, Vec3* normal) const noexcept;
  // Bytes the BVH holds (nodes and the reordered indices) besides the borrowed positions.
  uint64_t bytes() const noexcept { return nodes_.size() * sizeof(BvhNode) + tris_.size() * 4; }
  std::span<const BvhNode> nodes() const noexcept { return nodes_; }
  std::span<const uint32_t> triangles() const noexcept { return tris_; }
  std::span<const float> positions() const noexcept { return pos_; }

 private:
  template <bool kAny>
  bool cast(Vec3 o, Vec3 d, float tmin, float tmax, float* t, uint32_t* tri) const noexcept;
  std::span<const float> pos_;
  std::vector<BvhNode> nodes_;
  std::vector<uint32_t> tris_;  // three vertex indices per triangle, leaf order
};

}  // namespace vff::detail
