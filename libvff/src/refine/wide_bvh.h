// wide_bvh.h - the CPU's exact step of refined queries (private): the triangle BVH of
// triangle_bvh.h collapsed to four children a node, cast with four box tests at once.
//
// The GPU walks the binary BVH (its arrays are what gpu/ uploads); the CPU walks this one, made
// from it: the same leaves, the same triangles in the same order, and the same triangle test
// (triangleHit), so both find the same nearest t. A node holds its children's boxes as four lanes
// of each bound and a reference a child: an inner node's index, or a leaf's first triangle and
// count (kLeaf set). A node has fewer than four children only where the binary tree runs out of
// inner nodes to open; the unused lanes have no child (kNone) and are masked off.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "refine/triangle_bvh.h"

namespace vff::detail {

struct alignas(16) WideNode {
  float lo[3][4];  // lo[axis][child]
  float hi[3][4];
  uint32_t child[4];
};
static_assert(sizeof(WideNode) == 112);

class WideBvh {
 public:
  static constexpr uint32_t kNone = 0xFFFFFFFFu;
  static constexpr uint32_t kLeaf = 0x80000000u;
  // A leaf's reference: kLeaf | first << 3 | (count - 1); so a BVH holds fewer triangles than this.
  static constexpr uint32_t kMaxTriangles = 1u << 28;

  WideBvh() = default;
  // Collapses a binary BVH: borrows its positions (as it does), copies its leaf-ordered triangles.
  // Precondition: b.triangles().size() / 3 < kMaxTriangles.
  explicit WideBvh(const TriangleBvh& b);

  bool empty() const noexcept { return nodes_.empty(); }
  // As TriangleBvh::occluded and TriangleBvh::intersect, with the same answers.
  bool occluded(Vec3 o, Vec3 d, float tmin, float tmax) const noexcept;
  bool intersect(Vec3 o, Vec3 d, float tmin, float tmax, float* t, Vec3* normal) const noexcept;
  // Bytes the BVH holds (nodes and the leaf-ordered indices) besides the borrowed positions.
  uint64_t bytes() const noexcept { return nodes_.size() * sizeof(WideNode) + tris_.size() * 4; }
  size_t nodeCount() const noexcept { return nodes_.size(); }

 private:
  template <bool kAny>
  bool cast(Vec3 o, Vec3 d, float tmin, float tmax, float* t, uint32_t* tri) const noexcept;
  std::span<const float> pos_;
  std::vector<WideNode> nodes_;
  std::vector<uint32_t> tris_;
};

}  // namespace vff::detail
