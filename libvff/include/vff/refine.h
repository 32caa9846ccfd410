// vff/refine.h - refined fields: the field answers the rays it is sure of, the object's triangles
// the rest (spec/format.md section 14, spec/geometry.md section 7.5).
//
// A field is wrong mostly near silhouettes, where the rays that share one texel disagree (a hit
// next to a miss), and where a hit lies near either end of a ray's range. A refined field stores,
// beside its maps, one bit per texel that marks the texels whose rays the maps cannot answer for
// sure, a distance margin, and the object's triangles: the optional section REFN (format 1.3).
// Reconstruction::kRefined (vff/query.h) answers every ray that lands on an unmarked texel, and
// whose hit is not within the margin of its range's ends, from the maps as kNearest does; it
// answers the others exactly, by a ray cast through a BVH of the triangles, built when the query
// is made. Readers without REFN (format 1.2 and older) ignore the section and answer from the
// maps alone.
//
//   vff::Result<vff::Refinement> r = vff::makeRefinement(field, distance, mesh.positions, mesh.indices);
//   vff::WriteOptions wo;
//   wo.refinement = r->view();                       // vff-bake --refine does these steps
//   vff::writeFile("bunny.vff", field, distance, {}, wo);
//   ...
//   q->occluded(ray, {.reconstruction = vff::Reconstruction::kRefined});
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "vff/error.h"
#include "vff/export.h"
#include "vff/format.h"

namespace vff {

inline constexpr uint32_t kTagRefinement = fourcc('R', 'E', 'F', 'N');  // refinement, optional (1.3)
inline constexpr uint32_t kRefinementHeaderSize = 64;

// A refinement borrowed from a File (File::refinement()) or from a Refinement. Empty: no REFN.
struct RefinementView {
  // Hits within margin * R of either end of a ray's range go to the exact step (R: the field's
  // radius).
  float margin = 0;
  // Bit (k * M * M + j * M + i) % 8 of byte (k * M * M + j * M + i) / 8: texel (i, j) of map k is
  // unsure. ceil(mapCount * M * M / 8) bytes.
  std::span<const uint8_t> unsure;
  uint32_t unsureTexels = 0;        // the number of bits set
  std::span<const float> positions;  // x, y, z per vertex, in the field's object space
  std::span<const uint32_t> indices; // three per triangle
  bool empty() const noexcept { return indices.empty(); }
  bool isUnsure(uint64_t texel) const noexcept { return (unsure[texel >> 3] >> (texel & 7u)) & 1u; }
};

// A refinement held in memory (makeRefinement's result).
struct Refinement {
  float margin = 0;
  std::vector<uint8_t> unsure;
  uint32_t unsureTexels = 0;
  std::vector<float> positions;
  std::vector<uint32_t> indices;
  RefinementView view() const noexcept { return {margin, unsure, unsureTexels, positions, indices}; }
};

struct RefineOptions {
  // The margin, in multiples of the field's lateral spread: half a mean sample spacing plus half
  // a texel's angle seen over the sphere's diameter (refineSpread below). A hit nearer than this
  // to either end of a ray's range may lie on the other side of it.
  float marginSpreads = 1.0f;
  // A texel is unsure when a neighbour's hit lies more than this many margins before or after its
  // own along the ray (a depth step: one part of the object in front of another).
  float jumpMargins = 4.0f;
  // Whether to test the texels whose neighbours disagree with rays through the triangles: 24 rays
  // through the corners of the texel's cell in ray space (entry points around the sample, directions
  // at the texel's corners). The texel stays unsure only when one of them meets the surface
  // otherwise than the texel says. Fewer texels are marked, so fewer rays take the exact step; a
  // silhouette that crosses only the inside of a cell goes unseen (vff-experiments sdf-bench
  // --refine-probe measures both). Deterministic.
  bool probe = false;
  unsigned threads = 0;  // 0: one per core; the result does not depend on it
};

// The lateral spread of a field's rays, as a fraction of R: how far apart two rays that read the
// same texel can pass the object, sqrt(4 pi / mapCount) / 2 + (angle of a texel) at distance 2R / 2,
// the angle of a texel taken as sqrt(2 pi) / M.
VFF_API float refineSpread(const FieldDesc& field) noexcept;

// Marks the unsure texels of a field's distance maps (map-major, as a File holds them) and takes a
// copy of the object's triangles (which must be the ones the field was baked from, in its object
// space). A texel is unsure when a texel that rays beside its own read disagrees with it: one of
// the 8 around it in its map, or the texel of the same direction in the maps of the neighbouring
// positional samples (queryNeighbours, vff/query.h), hits where it misses or misses where it hits,
// or hits a depth step away (jumpMargins). Errors: kInvalidArgument for sizes that do not match the
// field, an index out of range, a coordinate that is not finite or outside the bounding sphere,
// kUnsupported for bit1 fields (no distances).
VFF_API Result<Refinement> makeRefinement(const FieldDesc& field, std::span<const uint8_t> distance,
                                          std::span<const float> positions, std::span<const uint32_t> indices,
                                          const RefineOptions& options = {});

// The exact step's BVH over a refinement's triangles, as the CPU query builds it (deterministic),
// for a GPU port (gpu/): 8 words per node, depth-first from the root: lo.x, lo.y, lo.z (binary32
// bits), first, hi.x, hi.y, hi.z, count. A leaf (count >= 1) holds triangles [first, first + count)
// of `triangles` (three vertex indices each, leaf order); an inner node (count 0) has its first
// child right after it and its second at index `first`. A ray visits the nearer child first.
// Experimental (vff/export.h): the layout changes with the CPU's.
struct RefinementBvh {
  std::vector<uint32_t> nodes;
  std::vector<uint32_t> triangles;
};
VFF_EXPERIMENTAL RefinementBvh buildRefinementBvh(const RefinementView& refinement);
// The depth no such BVH exceeds (root at depth 1): a cast's stack of this many entries suffices.
inline constexpr uint32_t kRefinementBvhMaxDepth = 80;

// The REFN section's raw bytes (spec/format.md section 14) for a field. Errors as makeRefinement's,
// for a view that does not match the field.
VFF_API Result<std::vector<uint8_t>> encodeRefinement(const FieldDesc& field, const RefinementView& refinement);

}  // namespace vff
