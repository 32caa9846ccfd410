// gen_scene.h - the conformance vectors' source data: an analytic scene, the maps computed from it
// (vff-conformance-gen only; see generate.cpp).
#pragma once

#include <cstdint>

#include "gen_bytes.h"
#include "vff/vff.h"

namespace vff::gen {

struct Content {
  Bytes distance;  // mapCount maps, in file order
  Bytes codes;     // bc4-diameter: the unorm8-diameter codes the blocks were made from (M*M per map)
  Bytes normals;   // empty without a normal encoding
  uint64_t hits = 0, misses = 0;
};

// The maps of field `f`: the distance from each stand-in sample on the bounding sphere along each
// texel-centre ray to an off-centre sphere of radius 0.7R, and its normal at the hit (gen_scene.cpp).
// Checks libvff's texelDirection and frameFromNormal against the generator's own (fail()).
Content makeContent(const FieldDesc& f);

// The source of a refined vector's REFN section (spec/format.md section 14), made by the generator's
// own rule rather than libvff's makeRefinement (the vectors test the container, not the writer
// rule): texel (i, j) of map k is unsure when one of its 4 neighbours in its map hits where it
// misses or misses where it hits (the silhouette of the inner sphere); the margin is `margin`; the
// triangles are the octahedron inscribed in the scene's inner sphere (centre C + R(0.10, -0.08,
// 0.12), radius 0.7R, so every vertex lies within 0.88R of C), each face split in 4 `level` times,
// new vertices pushed out onto the inner sphere.
Refinement makeRefinementSource(const FieldDesc& f, const Content& c, float margin, uint32_t level);

}  // namespace vff::gen
