// filter.cpp - filter 1 `hits-med`: a hit mask, then the hits' residuals against the median edge
// detector (MED, LOCO-I / JPEG-LS) of their left, upper and upper-left hit neighbours.
//
// Why this filter (measured on the bunny at 4226 x 64 x 64, tools/vff-compress --benchmark): three
// quarters of the texels are misses, which a mask holds in a few bits each, and the hits are a
// smooth function of the texel position, which MED predicts to within a code or two. Predicting
// the raw bytes instead (misses included) gains little over zstd alone, because every hit/miss edge
// becomes a large residual.
#include "filter.h"

#include <algorithm>
#include <bit>
#include <cstring>
#include <string>

namespace vff::detail {

namespace {

constexpr uint8_t kMiss8 = 255;  // the miss code of unorm8-diameter and unorm8-chord

// The prediction of texel (x, y) of a map from its already decoded neighbours (spec/format.md,
// filter 1). `m` holds the map's codes so far; `last` is the previous hit of the map (0 before it).
inline uint8_t predict(const uint8_t* m, uint32_t M, uint32_t x, uint32_t y, uint8_t last) noexcept {
  const bool hasA = x > 0 && m[y * M + x - 1] != kMiss8;
  const bool hasB = y > 0 && m[(y - 1) * M + x] != kMiss8;
  const bool hasC = x > 0 && y > 0 && m[(y - 1) * M + x - 1] != kMiss8;
  const int a = hasA ? m[y * M + x - 1] : 0;
  const int b = hasB ? m[(y - 1) * M + x] : 0;
  const int c = hasC ? m[(y - 1) * M + x - 1] : 0;
  if (hasA && hasB) {
    if (!hasC) return uint8_t((a + b) >> 1);
    const int mx = std::max(a, b), mn = std::min(a, b);
    return uint8_t(c >= mx ? mn : c <= mn ? mx : a + b - c);
  }
  if (hasA) return uint8_t(a);
  if (hasB) return uint8_t(b);
  return hasC ? uint8_t(c) : last;
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
        out.push_back(uint8_t(v - predict(m, M, x, y, last)));
        last = v;
      }
  }
  return out;
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
  const uint32_t M = shape.mapResolution;
  const uint64_t mapTexels = uint64_t(M) * M;
  const uint64_t texels = raw.size();
  if (M == 0 || texels % mapTexels != 0) return makeError(failCode, "block is not a whole number of maps");
  const uint64_t nMask = maskBytes(texels);
  if (filtered.size() < nMask)
    return makeError(failCode, "hits-med stream of " + std::to_string(filtered.size()) + " bytes is shorter than its " +
                                   std::to_string(nMask) + "-byte hit mask");
  const uint8_t* mask = filtered.data();
  uint64_t hits = 0;
  for (uint64_t i = 0; i < nMask; ++i) hits += uint64_t(std::popcount(mask[i]));
  if (texels % 8 != 0 && (mask[nMask - 1] >> (texels % 8)) != 0)
    return makeError(failCode, "hits-med mask has bits set past the block's last texel");
  if (filtered.size() != nMask + hits)
    return makeError(failCode, "hits-med stream holds " + std::to_string(filtered.size() - nMask) +
                                   " residuals for " + std::to_string(hits) + " hits");
  const uint8_t* res = mask + nMask;
  for (uint64_t first = 0; first < texels; first += mapTexels) {
    uint8_t* m = raw.data() + first;
    uint8_t last = 0;
    uint64_t j = first;
    for (uint32_t y = 0; y < M; ++y)
      for (uint32_t x = 0; x < M; ++x, ++j) {
        // Eight misses at once where the mask byte is empty and the run stays in this row.
        if ((j & 7) == 0 && mask[j >> 3] == 0 && x + 8 <= M) {
          std::memset(m + y * M + x, kMiss8, 8);
          x += 7;
          j += 7;
          continue;
        }
        if (!((mask[j >> 3] >> (j & 7)) & 1)) {
          m[y * M + x] = kMiss8;
          continue;
        }
        const uint8_t v = uint8_t(predict(m, M, x, y, last) + *res++);
        if (v == kMiss8)
          return makeError(failCode, "hits-med residual of texel " + std::to_string(j) +
                                         " decodes to the miss code, but the mask marks a hit");
        m[y * M + x] = v;
        last = v;
      }
  }
  return {};
}

}  // namespace vff::detail
