// What vff_gl uploads for a refined field (vff/gl/refine_loader.h), computed without GL: the
// uniform block, the unsure bits as words, the vertices and the CPU query's BVH. Kept apart from
// the GL calls (refine_loader.cpp) so that tests can check them where no GL library is installed.
#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

#include "vff/gl/refine_loader.h"

namespace vff::gl {
namespace {

// The depth of the BVH's deepest leaf (root 0), walking the depth-first node array; UINT32_MAX for
// a node array that does not form a tree (a child index out of range or not after its parent).
uint32_t bvhDepth(const std::vector<uint32_t>& nodes) {
  const size_t count = nodes.size() / 8;
  if (count == 0) return 0;
  struct Entry {
    size_t node;
    uint32_t depth;
  };
  std::vector<Entry> stack{{0, 0}};
  uint32_t deepest = 0;
  size_t visited = 0;
  while (!stack.empty()) {
    const Entry e = stack.back();
    stack.pop_back();
    if (++visited > count) return UINT32_MAX;
    const uint32_t* n = &nodes[8 * e.node];
    if (n[7] != 0) {  // a leaf
      deepest = std::max(deepest, e.depth);
      continue;
    }
    const size_t a = e.node + 1, b = n[3];
    if (a >= count || b >= count || b <= e.node) return UINT32_MAX;
    stack.push_back({b, e.depth + 1});
    stack.push_back({a, e.depth + 1});
  }
  return deepest;
}

}  // namespace

Result<RefinementBuffers> makeRefinementBuffers(const FieldDesc& field, const RefinementView& r) {
  if (Status s = checkFieldDesc(field); !s) return s.error();
  RefinementBuffers out;
  if (r.empty()) {
    // As the CPU query without a refinement: the shader answers every ray as kNearest.
    out.unsure.assign(1, 0);
    out.vertices.assign(3, 0.0f);
    out.nodes.assign(8, 0);
    out.triangles.assign(3, 0);
    return out;
  }
  // The reader's checks of a REFN section, as FieldQuery::fromMaps makes them.
  if (auto raw = encodeRefinement(field, r); !raw) return std::move(raw).error();
  const uint64_t texels = uint64_t(field.mapCount) * field.mapResolution * field.mapResolution;
  if (texels > UINT32_MAX)
    return makeError(Code::kUnsupported, "the shader indexes the unsure bits with 32-bit words: the field has " +
                                             std::to_string(texels) + " texels, at most 2^32 - 1 fit");
  if (r.positions.size() > UINT32_MAX || r.indices.size() > UINT32_MAX)
    return makeError(Code::kUnsupported, "the shader indexes vertices and triangles with 32-bit words");
  // Byte b of the bits is byte b % 4 of word b / 4 (little-endian), so texel x is bit x % 32 of
  // word x / 32, whatever the host's byte order.
  out.unsure.assign((r.unsure.size() + 3) / 4, 0);
  for (size_t b = 0; b < r.unsure.size(); ++b) out.unsure[b / 4] |= uint32_t(r.unsure[b]) << (8 * (b % 4));
  out.vertices.assign(r.positions.begin(), r.positions.end());
  RefinementBvh bvh = buildRefinementBvh(r);
  out.nodes = std::move(bvh.nodes);
  out.triangles = std::move(bvh.triangles);
  if (out.nodes.empty() || out.nodes.size() / 8 > UINT32_MAX)
    return makeError(Code::kUnsupported, "the refinement's BVH has " + std::to_string(out.nodes.size() / 8) + " nodes");
  const uint32_t depth = bvhDepth(out.nodes);
  if (depth == UINT32_MAX) return makeError(Code::kUnsupported, "the refinement's BVH is not a depth-first tree");
  if (depth > kRefineStack)
    return makeError(Code::kUnsupported, "the refinement's BVH is " + std::to_string(depth) +
                                             " levels deep, the shader's stack holds " + std::to_string(kRefineStack));
  // The CPU query's margin in object units: the same float product (FieldQuery::Impl::setRefinement).
  out.block.margin = r.margin * field.sphere.radius;
  out.block.triangleCount = uint32_t(out.triangles.size() / 3);
  out.block.nodeCount = uint32_t(out.nodes.size() / 8);
  out.block.stackDepth = depth;
  return out;
}

std::string refinementShaderDefines(const RefineBlock& block) {
  return "#define VFF_REFINED\n#define VFF_REFINE_STACK " + std::to_string(std::max<uint32_t>(1, block.stackDepth)) +
         "\n";
}

}  // namespace vff::gl
