// filter.h - block filters (private): reversible transforms of a block's raw bytes that make them
// compress better. spec/format.md section 4 ("Filters") is the normative definition.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include "vff/error.h"
#include "vff/format.h"
#include "vff/reader.h"

namespace vff::detail {

// What a filter needs to know about the block: its maps' resolution and the plane's encoding.
struct BlockShape {
  uint32_t mapResolution = 0;  // M: each map is M x M texels, row-major
  uint32_t texelBytes = 1;     // bytes per texel of the plane (1 for the 8-bit distance encodings)
};

// True when `filter` may be used on blocks of this plane of this field (rule 6008).
bool filterApplies(Filter filter, Plane plane, const FieldDesc& field) noexcept;

// The largest filtered size for `rawSize` raw bytes: a decoder never accepts (or allocates) more.
uint64_t filteredBound(Filter filter, uint64_t rawSize) noexcept;

// Applies the filter to whole maps (raw.size() a multiple of M * M * texelBytes).
std::vector<uint8_t> applyFilter(Filter filter, const BlockShape& shape, std::span<const uint8_t> raw);

// Reverses it into `raw` (exactly the block's rawSize). A filtered stream that is not what
// applyFilter produces for some raw block fails with `failCode`, naming the problem.
Status unapplyFilter(Filter filter, const BlockShape& shape, std::span<const uint8_t> filtered,
                     std::span<uint8_t> raw, Code failCode);

// The hits-med decoder, one map after another and texel by texel, as spec/format.md describes it:
// the reference that the lanes below must match byte for byte and error for error (the tests hold
// them to it). unapplyFilter uses it for the maps the lanes leave.
Status unapplyHitsMedScalar(const BlockShape& shape, std::span<const uint8_t> filtered, std::span<uint8_t> raw,
                            Code failCode);

// How far a hits-med decoder got: whole maps decoded, and the residual of the next map's first hit.
struct HitsMedProgress {
  uint64_t maps = 0;
  const uint8_t* residuals = nullptr;
};

#if defined(__SSE2__) && defined(__x86_64__)  // every x86-64 target (GCC, Clang): filter_simd.cpp
#define VFF_HITS_MED_LANES 1
constexpr uint32_t kHitsMedLanes = 16;  // maps decoded side by side, one per byte of an SSE2 vector

// True when this processor has SSSE3, which the lanes then use to place the residuals (PSHUFB).
bool hitsMedLanesSsse3() noexcept;

// Decodes the first groups of 16 maps of a hits-med stream that unapplyFilter has checked (mask
// size, mask tail and residual count), for M a multiple of 16; `mapCount` maps in all, of which it
// leaves the last mapCount % 16. It stops before the first group holding a hit that decodes to the
// miss code, so that the scalar decoder, resuming there, reports it. `ssse3` (hitsMedLanesSsse3(),
// or false for the SSE2 code, which the tests also check) chooses how the residuals are placed.
HitsMedProgress unapplyHitsMedLanes(std::span<const uint8_t> filtered, const uint8_t* residuals, uint32_t M,
                                    uint64_t mapCount, uint8_t* raw, bool ssse3);
#endif

}  // namespace vff::detail
