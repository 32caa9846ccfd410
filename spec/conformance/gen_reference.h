// gen_reference.h - what the conformance vectors must decode to, computed from spec/format.md
// independently of libvff: the bc4-diameter decoder, the hits-med filter's stream, the packed slices
// and the canonical layout (vff-conformance-gen only; see generate.cpp).
#pragma once

#include <cstdint>
#include <span>
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

}  // namespace vff::gen
