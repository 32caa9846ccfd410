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

 private:
  template <bool kAny>
  bool cast(Vec3 o, Vec3 d, float tmin, float tmax, float* t, uint32_t* tri) const noexcept;
  std::span<const float> pos_;
  std::vector<BvhNode> nodes_;
  std::vector<uint32_t> tris_;  // three vertex indices per triangle, leaf order
};

}  // namespace vff::detail
