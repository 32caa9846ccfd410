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

}  // namespace vff::gen
