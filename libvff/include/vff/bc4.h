// vff/bc4.h - the bc4-diameter distance encoding (format 1.2, spec/format.md 7.4): unorm8-diameter
// codes stored lossily in BC4 blocks, the single-channel block format GPUs decode in the texture unit
// (GL_COMPRESSED_RED_RGTC1, DXGI_FORMAT_BC4_UNORM, VK_FORMAT_BC4_UNORM_BLOCK).
//
// A map of M x M texels (M a multiple of 4) is (M/4) x (M/4) blocks of 4 x 4 texels, stored
// row-major, 8 bytes each, M*M/2 bytes in all: half of unorm8-diameter. Block (bx, by) holds texels
// (4bx + x, 4by + y), x, y < 4, as texel index u = 4y + x:
//
//   byte 0: r0, byte 1: r1 (endpoint codes); bytes 2..7: a 48-bit little-endian word whose bits
//   3u..3u+2 are the palette index of texel u.
//   r0 >  r1: palette = r0, r1, then ((8-i) r0 + (i-1) r1 + 3) / 7 for i = 2..7   (integer division)
//   r0 <= r1: palette = r0, r1, then ((6-i) r0 + (i-1) r1 + 2) / 5 for i = 2..5, 0, 255
//
// The texel's code is its palette entry, read exactly like a unorm8-diameter code: 255 is a miss,
// any other code c a hit at c * 2R / 254. The encoder below is miss-aware: a miss always decodes to
// 255 (index 7 of the r0 <= r1 palette) and a hit never does (endpoints <= 254), so BC4 moves
// distances but never turns a hit into a miss or a miss into a hit. GPU texture units decode the
// same palette in floating point (code = round(value * 255)); some round the interpolated entries
// differently, by at most one code, and 0 and 255 are exact on every one.
#pragma once

#include <cstdint>
#include <span>

#include "vff/export.h"

namespace vff {

inline constexpr uint32_t kBc4BlockBytes = 8;

// The code of texel u = 4y + x (u < 16) of one block.
VFF_API uint32_t bc4Texel(const uint8_t* block, uint32_t u) noexcept;

// All 16 codes of one block, in texel order.
VFF_API void decodeBc4Block(const uint8_t* block, uint8_t codes[16]) noexcept;

// Encodes 16 unorm8-diameter codes (texel order, 255 = miss) into one block: misses decode to 255,
// hits to a code <= 254 chosen to minimise the squared code error (endpoints searched around the
// hits' range; deterministic).
VFF_API void encodeBc4Block(const uint8_t codes[16], uint8_t* block) noexcept;

// A whole map: M x M row-major codes <-> (M/4)^2 blocks. M must be a multiple of 4; `codes` holds
// M*M bytes and `blocks` M*M/2 (no checks beyond that).
VFF_API void encodeBc4Map(std::span<const uint8_t> codes, uint32_t m, std::span<uint8_t> blocks) noexcept;
VFF_API void decodeBc4Map(std::span<const uint8_t> blocks, uint32_t m, std::span<uint8_t> codes) noexcept;

}  // namespace vff
