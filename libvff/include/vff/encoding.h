// vff/encoding.h - turning distances into texel codes and back (spec/format.md, "Value encodings").
//
// Distances are measured along the ray from its entry point on the bounding sphere to the first
// surface hit, in object-space units. For an M x M map the texel (i, j) is at index j*M + i.
#pragma once

#include <cstdint>
#include <span>

#include "vff/direction.h"
#include "vff/export.h"
#include "vff/format.h"

namespace vff {

// A decoded texel. For kBit1 only `hit` is meaningful (distance is 0).
struct Texel {
  bool hit = false;
  float distance = 0;  // object-space distance from the sphere entry point; 0 for a miss
};

// The code stored for a hit at `distance` (clamped to [0, scale]) or for a miss. `cosAlpha` is the
// cosine between the texel-centre direction and the inward normal (used by kUnorm8Chord only).
// Hits never produce the miss code.
VFF_API uint32_t encodeDistance(DistanceEncoding e, bool hit, float distance, float radius, float cosAlpha) noexcept;

// The texel a code stands for. `cosAlpha` as above.
VFF_API Texel decodeDistance(DistanceEncoding e, uint32_t code, float radius, float cosAlpha) noexcept;

// One quantisation step in object-space units (0 for kBit1); for kUnorm8Chord the step of the
// direction with cosine cosAlpha.
VFF_API float quantizationStep(DistanceEncoding e, float radius, float cosAlpha) noexcept;

// Reads / writes the code of texel (i, j) in one distance map of `mapResolution` squared texels.
// The span must hold distanceMapBytes(e, mapResolution) bytes; no bounds checks beyond that.
// kBc4Diameter: loadCode decodes the texel's block (vff/bc4.h); storeCode does nothing, since a
// block is encoded from all its 16 codes at once: write unorm8-diameter codes, then encodeBc4Map.
VFF_API uint32_t loadCode(DistanceEncoding e, std::span<const uint8_t> map, uint32_t mapResolution, uint32_t i,
                          uint32_t j) noexcept;
VFF_API void storeCode(DistanceEncoding e, std::span<uint8_t> map, uint32_t mapResolution, uint32_t i, uint32_t j,
                       uint32_t code) noexcept;

// Normals: the object-space unit normal <-> its 4-byte kOctSnorm16 texel (x then y, snorm16 LE).
VFF_API void encodeNormal(Vec3 normal, uint8_t out[4]) noexcept;
VFF_API Vec3 decodeNormal(const uint8_t in[4]) noexcept;

}  // namespace vff
