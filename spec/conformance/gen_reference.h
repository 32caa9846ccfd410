// gen_reference.h - what the conformance vectors must decode to, computed from spec/format.md
// independently of libvff: the bc4-diameter decoder, the hits-med filter's stream, the packed slices,
// the canonical layout and the REFN section (vff-conformance-gen only; see generate.cpp).
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "gen_bytes.h"
#include "gen_scene.h"
#include "vff/vff.h"

namespace vff::gen {

// bc4-diameter (spec/format.md 7.4): the code of texel (i, j) of a map of (M/4)^2 blocks.
uint32_t referenceBc4Code(std::span<const uint8_t> map, uint32_t m, uint32_t i, uint32_t j);

// Filter 1 (hits-med): the prediction of texel (x, y) of an 8-bit map from its left, upper and
// upper-left hits, or `last` (the map's previous hit) when it has none of them.
uint8_t hitsMedPrediction(const uint8_t* map, uint32_t m, uint32_t x, uint32_t y, uint8_t last);
// The filtered stream of a block of 8-bit maps: the hit mask (bit t % 8 of byte t / 8 set for a hit
// at block texel t), then one residual (code - prediction) mod 256 per hit, in texel order.
Bytes hitsMedStream(std::span<const uint8_t> raw, uint32_t m);

// The packed slices of plane `p`, composed independently of File::readSlice: each map at its tile,
// gutters replicating the nearest edge texel (clamping), empty tiles holding the miss code
// (distance) or zero (normals). bit1 slices pack 8 texels of a row per byte, LSB first.
std::vector<Bytes> composeSlices(const FieldDesc& f, const LayoutDesc& l, const Content& c, Plane p);

// The canonical layout, computed from spec/format.md's rule (checked against the writer's).
LayoutDesc canonicalLayout(const FieldDesc& f, const LayoutLimits& lim);
bool sameLayout(const LayoutDesc& a, const LayoutDesc& b);

// REFN (spec/format.md section 14), written from the spec's text independently of libvff.
struct ReferenceRefinement {
  uint32_t vertexCount = 0, triangleCount = 0;
  float margin = 0;
  uint32_t unsureTexels = 0;
  Bytes unsure;  // U = ceil(mapCount * M^2 / 8) bytes
  std::vector<float> positions;
  std::vector<uint32_t> indices;
};
// REFN's raw bytes (before its codec) for field `f`: the 64-byte header, the unsure bits, zero
// padding to a multiple of 4, the positions and the indices. It does not check `r`.
Bytes referenceRefinementBytes(const FieldDesc& f, const Refinement& r);
// Decodes REFN's raw bytes for field `f` and checks rules 8501-8503 in the order of
// spec/validation.md: 0 and *out filled when they hold, else the ID of the first rule broken (and
// *why says how).
uint32_t referenceDecodeRefinement(const FieldDesc& f, std::span<const uint8_t> raw, ReferenceRefinement* out,
                                   std::string* why);

}  // namespace vff::gen
