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

}  // namespace vff::detail
