#include "vff/bc4.h"

#include <algorithm>
#include <cmath>

namespace vff {
namespace {

// The eight palette entries of endpoints (r0, r1), spec/format.md 7.4.
void palette(uint32_t r0, uint32_t r1, uint32_t p[8]) noexcept {
  p[0] = r0;
  p[1] = r1;
  if (r0 > r1) {
    for (uint32_t i = 2; i < 8; ++i) p[i] = ((8 - i) * r0 + (i - 1) * r1 + 3) / 7;
  } else {
    for (uint32_t i = 2; i < 6; ++i) p[i] = ((6 - i) * r0 + (i - 1) * r1 + 2) / 5;
    p[6] = 0;
    p[7] = 255;
  }
}

uint64_t indexWord(const uint8_t* block) noexcept {
  uint64_t w = 0;
  for (int b = 0; b < 6; ++b) w |= uint64_t(block[2 + b]) << (8 * b);
  return w;
}

constexpr uint32_t kMiss = 255;
constexpr uint32_t kMaxHit = 254;

// Fits the hits of a block to the palette of (r0, r1): the squared error, and each texel's index
// (misses: 7). `usable` is how many leading palette entries a hit may take (7 for r0 <= r1, whose
// entry 7 is the miss code; 8 for r0 > r1).
uint32_t fit(const uint8_t codes[16], uint32_t r0, uint32_t r1, uint64_t* word) noexcept {
  uint32_t p[8];
  palette(r0, r1, p);
  const uint32_t usable = r0 > r1 ? 8 : 7;
  uint32_t sse = 0;
  uint64_t w = 0;
  for (uint32_t u = 0; u < 16; ++u) {
    uint32_t best = 7, bestErr = 0;
    if (codes[u] != kMiss) {
      bestErr = UINT32_MAX;
      for (uint32_t i = 0; i < usable; ++i) {
        const int d = int(p[i]) - int(codes[u]);
        const uint32_t e = uint32_t(d * d);
        if (e < bestErr) {
          bestErr = e;
          best = i;
        }
      }
    }
    sse += bestErr;
    w |= uint64_t(best) << (3 * u);
  }
  *word = w;
  return sse;
}

void store(uint8_t* block, uint32_t r0, uint32_t r1, uint64_t word) noexcept {
  block[0] = uint8_t(r0);
  block[1] = uint8_t(r1);
  for (int b = 0; b < 6; ++b) block[2 + b] = uint8_t(word >> (8 * b));
}

}  // namespace

uint32_t bc4Texel(const uint8_t* block, uint32_t u) noexcept {
  const uint32_t r0 = block[0], r1 = block[1];
  const uint32_t i = uint32_t(indexWord(block) >> (3 * u)) & 7u;
  if (i == 0) return r0;
  if (i == 1) return r1;
  if (r0 > r1) return ((8 - i) * r0 + (i - 1) * r1 + 3) / 7;
  if (i == 6) return 0;
  if (i == 7) return 255;
  return ((6 - i) * r0 + (i - 1) * r1 + 2) / 5;
}

void decodeBc4Block(const uint8_t* block, uint8_t codes[16]) noexcept {
  uint32_t p[8];
  palette(block[0], block[1], p);
  const uint64_t w = indexWord(block);
  for (uint32_t u = 0; u < 16; ++u) codes[u] = uint8_t(p[(w >> (3 * u)) & 7u]);
}

namespace {

// Where palette index i lies between the low endpoint L and the high endpoint H (0 = L, 1 = H),
// or -1 for the constants 0 and 255 of the six-entry palette.
float position(bool eight, uint32_t i) noexcept {
  if (eight) return i == 0 ? 1.0f : i == 1 ? 0.0f : float(8 - i) / 7.0f;
  return i == 0 ? 0.0f : i == 1 ? 1.0f : i < 6 ? float(i - 1) / 5.0f : -1.0f;
}

// The best endpoints for one palette (eight entries: r0 = H > r1 = L; six: r0 = L <= r1 = H):
// from the hits' range, a few least-squares refinements of (L, H) given each hit's palette
// position, then a search of the neighbours of the best pair. Updates *best, *r0, *r1, *word.
void searchPalette(const uint8_t codes[16], bool eight, uint32_t lo, uint32_t hi, uint32_t* best, uint32_t* r0,
                   uint32_t* r1, uint64_t* word) noexcept {
  const auto tryPair = [&](int l, int h) {
    if (l < 0 || h > int(kMaxHit) || (eight ? l >= h : l > h)) return false;
    uint64_t w = 0;
    const uint32_t a = eight ? uint32_t(h) : uint32_t(l), b = eight ? uint32_t(l) : uint32_t(h);
    const uint32_t e = fit(codes, a, b, &w);
    if (e >= *best) return false;
    *best = e;
    *r0 = a;
    *r1 = b;
    *word = w;
    return true;
  };
  int l = int(lo), h = int(hi);
  if (eight && l == h) return;  // the eight-entry palette needs r0 > r1
  tryPair(l, h);
  for (int iter = 0; iter < 4 && *best != 0; ++iter) {
    // Least squares for (L, H) with each hit at its current palette position t: minimise
    // sum ((1 - t) L + t H - code)^2.
    uint64_t w = 0;
    fit(codes, eight ? uint32_t(h) : uint32_t(l), eight ? uint32_t(l) : uint32_t(h), &w);
    double a = 0, b = 0, c = 0, d = 0, e = 0;
    for (uint32_t u = 0; u < 16; ++u) {
      if (codes[u] == kMiss) continue;
      const float t = position(eight, uint32_t(w >> (3 * u)) & 7u);
      if (t < 0) continue;
      a += (1.0 - t) * (1.0 - t);
      b += (1.0 - t) * t;
      c += double(t) * t;
      d += (1.0 - t) * codes[u];
      e += double(t) * codes[u];
    }
    const double det = a * c - b * b;
    if (!(det > 1e-9)) break;
    const int nl = int(std::lround(std::clamp((d * c - b * e) / det, 0.0, double(kMaxHit))));
    const int nh = int(std::lround(std::clamp((a * e - b * d) / det, 0.0, double(kMaxHit))));
    if (nl == l && nh == h) break;
    l = nl;
    h = nh;
    tryPair(l, h);
  }
  // Endpoints just outside or inside the range: the optimum often puts an interpolated entry, not an
  // endpoint, on the smallest or largest hit. A window of about one palette step on each side.
  if (*best > 0) {
    const int steps = eight ? 7 : 5;
    const int reach = std::min(int(hi - lo) / steps + 1, 8);
    for (int dl = -reach; dl <= reach; ++dl)
      for (int dh = -reach; dh <= reach; ++dh) tryPair(int(lo) + dl, int(hi) + dh);
  }
  // The neighbours of the best pair so far, until none improves.
  for (int round = 0; round < 4 && *best != 0; ++round) {
    const int bl = eight ? int(*r1) : int(*r0), bh = eight ? int(*r0) : int(*r1);
    bool improved = false;
    for (int dl = -1; dl <= 1; ++dl)
      for (int dh = -1; dh <= 1; ++dh)
        if (dl || dh) improved |= tryPair(bl + dl, bh + dh);
    if (!improved) break;
  }
}

}  // namespace

void encodeBc4Block(const uint8_t codes[16], uint8_t* block) noexcept {
  uint32_t lo = kMaxHit, hi = 0;
  bool anyMiss = false, anyHit = false;
  for (uint32_t u = 0; u < 16; ++u) {
    if (codes[u] == kMiss) {
      anyMiss = true;
    } else {
      anyHit = true;
      lo = std::min<uint32_t>(lo, codes[u]);
      hi = std::max<uint32_t>(hi, codes[u]);
    }
  }
  if (!anyHit) {  // r0 = r1 = 255 selects the six-entry palette; every index 7: all misses
    store(block, 255, 255, ~uint64_t{0});
    return;
  }
  // The six-entry palette (the only one with the miss code), then, without misses, the eight-entry
  // one; a tie keeps the first.
  uint32_t best = UINT32_MAX, r0 = lo, r1 = hi;
  uint64_t word = 0;
  searchPalette(codes, false, lo, hi, &best, &r0, &r1, &word);
  if (!anyMiss && best != 0) searchPalette(codes, true, lo, hi, &best, &r0, &r1, &word);
  store(block, r0, r1, word);
}

void encodeBc4Map(std::span<const uint8_t> codes, uint32_t m, std::span<uint8_t> blocks) noexcept {
  const uint32_t nb = m / 4;
  uint8_t tile[16];
  for (uint32_t by = 0; by < nb; ++by)
    for (uint32_t bx = 0; bx < nb; ++bx) {
      for (uint32_t y = 0; y < 4; ++y)
        for (uint32_t x = 0; x < 4; ++x) tile[4 * y + x] = codes[size_t(4 * by + y) * m + 4 * bx + x];
      encodeBc4Block(tile, &blocks[(size_t(by) * nb + bx) * kBc4BlockBytes]);
    }
}

void decodeBc4Map(std::span<const uint8_t> blocks, uint32_t m, std::span<uint8_t> codes) noexcept {
  const uint32_t nb = m / 4;
  uint8_t tile[16];
  for (uint32_t by = 0; by < nb; ++by)
    for (uint32_t bx = 0; bx < nb; ++bx) {
      decodeBc4Block(&blocks[(size_t(by) * nb + bx) * kBc4BlockBytes], tile);
      for (uint32_t y = 0; y < 4; ++y)
        for (uint32_t x = 0; x < 4; ++x) codes[size_t(4 * by + y) * m + 4 * bx + x] = tile[4 * y + x];
    }
}

}  // namespace vff
