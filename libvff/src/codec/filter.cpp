// filter.cpp - filter 1 `hits-med`: a hit mask, then the hits' residuals against the median edge
// detector (MED, LOCO-I / JPEG-LS) of their left, upper and upper-left hit neighbours.
//
// Why this filter (tools/vff-compress --benchmark compares it with the others): most texels are
// misses, which a mask holds in a few bits each, and the hits are a smooth function of the texel
// position, which MED predicts closely. Predicting
// the raw bytes instead (misses included) gains little over zstd alone, because every hit/miss edge
// becomes a large residual.
#include "codec/filter.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>

namespace vff::detail {

namespace {

constexpr uint8_t kMiss8 = 255;  // the miss code of unorm8-diameter and unorm8-chord

// The prediction of a hit from its left (a), upper (b) and upper-left (c) neighbours' codes, with
// 255 standing for a neighbour that is a miss or outside the map (spec/format.md, filter 1); `last`
// is the previous hit of the map (0 before the first).
inline uint8_t predict(int a, int b, int c, uint8_t last) noexcept {
  const int mx = std::max(a, b), mn = std::min(a, b);
  if (mx != kMiss8) {  // the common case, a and b are hits
    // MED is a + b - c clamped to [min(a, b), max(a, b)]: min/max compile to conditional moves,
    // where the textbook three-way comparison would branch on the data.
    const int med = std::min(mx, std::max(mn, a + b - c));
    return uint8_t(c != kMiss8 ? med : (a + b) >> 1);
  }
  if (mn != kMiss8) return uint8_t(mn);  // exactly one of a and b is a hit
  return c != kMiss8 ? uint8_t(c) : last;
}

// Population count without relying on a POPCNT instruction (the library targets baseline x86-64,
// where std::popcount becomes a call per byte).
inline int popcount64(uint64_t x) noexcept {
  x = x - ((x >> 1) & 0x5555555555555555ull);
  x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Full;
  return int((x * 0x0101010101010101ull) >> 56);
}

// `n` <= 64 bits of the mask from bit `pos` on, bit 0 first.
inline uint64_t loadBits(const uint8_t* mask, uint64_t maskSize, uint64_t pos, uint32_t n) noexcept {
  const uint64_t at = pos >> 3;
  const uint32_t shift = uint32_t(pos & 7);
  uint8_t b[9] = {};
  if (at + 9 <= maskSize)
    std::memcpy(b, mask + at, 9);
  else
    std::memcpy(b, mask + at, size_t(maskSize - at));
  uint64_t lo;
  std::memcpy(&lo, b, 8);  // little-endian hosts (le.h's assumption for the whole library)
  uint64_t bits = shift ? (lo >> shift) | (uint64_t(b[8]) << (64 - shift)) : lo;
  return n == 64 ? bits : bits & ((uint64_t{1} << n) - 1);
}

uint64_t maskBytes(uint64_t texels) noexcept { return (texels + 7) / 8; }

}  // namespace

bool filterApplies(Filter filter, Plane plane, const FieldDesc& field) noexcept {
  switch (filter) {
    case Filter::kNone: return true;
    case Filter::kHitsMed:
      return plane == Plane::kDistance && (field.distanceEncoding == DistanceEncoding::kUnorm8Diameter ||
                                           field.distanceEncoding == DistanceEncoding::kUnorm8Chord);
  }
  return false;
}

uint64_t filteredBound(Filter filter, uint64_t rawSize) noexcept {
  return filter == Filter::kHitsMed ? rawSize + maskBytes(rawSize) : rawSize;
}

std::vector<uint8_t> applyFilter(Filter filter, const BlockShape& shape, std::span<const uint8_t> raw) {
  if (filter != Filter::kHitsMed) return std::vector<uint8_t>(raw.begin(), raw.end());
  const uint32_t M = shape.mapResolution;
  const uint64_t mapTexels = uint64_t(M) * M;
  const uint64_t texels = raw.size();
  std::vector<uint8_t> out(maskBytes(texels), 0);
  out.reserve(out.size() + texels);
  for (uint64_t j = 0; j < texels; ++j)
    if (raw[j] != kMiss8) out[j >> 3] |= uint8_t(1u << (j & 7));
  for (uint64_t first = 0; first < texels; first += mapTexels) {
    const uint8_t* m = raw.data() + first;
    uint8_t last = 0;
    for (uint32_t y = 0; y < M; ++y)
      for (uint32_t x = 0; x < M; ++x) {
        const uint8_t v = m[y * M + x];
        if (v == kMiss8) continue;
        const int left = x ? m[y * M + x - 1] : kMiss8, up = y ? m[(y - 1) * M + x] : kMiss8;
        const int upLeft = x && y ? m[(y - 1) * M + x - 1] : kMiss8;
        out.push_back(uint8_t(v - predict(left, up, upLeft, last)));
        last = v;
      }
  }
  return out;
}

namespace {

// Checks what a hits-med stream must hold before any texel is decoded (spec/format.md, filter 1): the
// whole mask, no mask bit past the last texel, and exactly one residual per hit. Sets *nMask.
Status checkHitsMed(const BlockShape& shape, std::span<const uint8_t> filtered, uint64_t texels, Code failCode,
                    uint64_t* nMask) {
  const uint32_t M = shape.mapResolution;
  const uint64_t mapTexels = uint64_t(M) * M;
  if (M == 0 || texels % mapTexels != 0) return makeError(failCode, "block is not a whole number of maps");
  *nMask = maskBytes(texels);
  if (filtered.size() < *nMask)
    return makeError(failCode, "hits-med stream of " + std::to_string(filtered.size()) + " bytes is shorter than its " +
                                   std::to_string(*nMask) + "-byte hit mask");
  const uint8_t* mask = filtered.data();
  uint64_t hits = 0;
  for (uint64_t i = 0; i < *nMask; i += 8) hits += uint64_t(popcount64(loadBits(mask, *nMask, i * 8, 64)));
  if (texels % 8 != 0 && (mask[*nMask - 1] >> (texels % 8)) != 0)
    return makeError(failCode, "hits-med mask has bits set past the block's last texel");
  if (filtered.size() != *nMask + hits)
    return makeError(failCode, "hits-med stream holds " + std::to_string(filtered.size() - *nMask) +
                                   " residuals for " + std::to_string(hits) + " hits");
  return {};
}

// Decodes the maps from `firstMap` on of a checked stream, texel by texel; `res` is the residual of
// the first hit of map `firstMap`.
Status unapplyHitsMedMaps(std::span<const uint8_t> filtered, uint64_t nMask, const uint8_t* res, uint32_t M,
                          uint64_t firstMap, std::span<uint8_t> raw, Code failCode) {
  const uint8_t* mask = filtered.data();
  const uint64_t mapTexels = uint64_t(M) * M;
  // Row by row: the row is filled with the miss code, then only the hits (the set mask bits, found
  // 64 at a time) are predicted and written, so misses cost a memset.
  const std::vector<uint8_t> missRow(M, kMiss8);  // the row above the first
  for (uint64_t first = firstMap * mapTexels; first < raw.size(); first += mapTexels) {
    uint8_t* m = raw.data() + first;
    uint8_t last = 0;
    for (uint32_t y = 0; y < M; ++y) {
      uint8_t* row = m + uint64_t(y) * M;
      const uint8_t* up = y ? row - M : missRow.data();
      std::memset(row, kMiss8, M);
      uint32_t lastX = ~0u - 1;  // no hit in this row yet
      for (uint32_t x0 = 0; x0 < M; x0 += 64) {
        uint64_t bits = loadBits(mask, nMask, first + uint64_t(y) * M + x0, std::min<uint32_t>(64, M - x0));
        while (bits) {
          const uint32_t x = x0 + uint32_t(std::countr_zero(bits));
          bits &= bits - 1;
          // The left neighbour is `last` when the previous hit was at x - 1 of this row.
          const int left = x == lastX + 1 ? last : kMiss8;
          const uint8_t v = uint8_t(predict(left, up[x], x ? up[x - 1] : kMiss8, last) + *res++);
          if (v == kMiss8)
            return makeError(failCode, "hits-med residual of texel " + std::to_string(first + uint64_t(y) * M + x) +
                                           " decodes to the miss code, but the mask marks a hit");
          row[x] = v;
          last = v;
          lastX = x;
        }
      }
    }
  }
  return {};
}

}  // namespace

Status unapplyHitsMedScalar(const BlockShape& shape, std::span<const uint8_t> filtered, std::span<uint8_t> raw,
                            Code failCode) {
  uint64_t nMask = 0;
  if (Status st = checkHitsMed(shape, filtered, raw.size(), failCode, &nMask); !st) return st;
  return unapplyHitsMedMaps(filtered, nMask, filtered.data() + nMask, shape.mapResolution, 0, raw, failCode);
}

Status unapplyFilter(Filter filter, const BlockShape& shape, std::span<const uint8_t> filtered,
                     std::span<uint8_t> raw, Code failCode) {
  if (filter == Filter::kNone) {
    if (filtered.size() != raw.size())
      return makeError(failCode, "unfiltered size " + std::to_string(filtered.size()) + " differs from raw size " +
                                     std::to_string(raw.size()));
    if (!raw.empty()) std::memcpy(raw.data(), filtered.data(), raw.size());
    return {};
  }
  if (filter != Filter::kHitsMed) return makeError(failCode, "unknown filter " + std::to_string(unsigned(filter)));
  uint64_t nMask = 0;
  if (Status st = checkHitsMed(shape, filtered, raw.size(), failCode, &nMask); !st) return st;
  const uint32_t M = shape.mapResolution;
  HitsMedProgress done{0, filtered.data() + nMask};
#if VFF_HITS_MED_LANES
  // The maps in whole groups of 16 go through the lanes; the rest, and any group holding a hit that
  // decodes to the miss code, go through the scalar decoder, which names the bad texel.
  if (M % kHitsMedLanes == 0)
    done = unapplyHitsMedLanes(filtered, done.residuals, M, raw.size() / (uint64_t(M) * M), raw.data(),
                               hitsMedLanesSsse3());
#endif
  return unapplyHitsMedMaps(filtered, nMask, done.residuals, M, done.maps, raw, failCode);
}

}  // namespace vff::detail
