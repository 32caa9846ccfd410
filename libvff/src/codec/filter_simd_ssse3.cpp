// filter_simd_ssse3.cpp - the hits-med lanes' residual placement with SSSE3's PSHUFB
// (filter_lanes.h, shuffleResidualsSsse3). This file alone is compiled with -mssse3
// (libvff/CMakeLists.txt); filter_simd.cpp calls it only where cpu_features.h finds SSSE3.
#include "codec/filter.h"

#if VFF_HITS_MED_LANES && defined(__SSSE3__)

#include <tmmintrin.h>  // SSSE3

#include <cstring>

#include "codec/filter_lanes.h"

namespace vff::detail {
namespace {

// For each mask byte, the PSHUFB control that spreads the next residuals over its hits (0x80, a
// zero, at its misses), and how many residuals it takes.
struct SpreadTable {
  uint8_t shuffle[256][8];
  uint8_t count[256];
};
constexpr SpreadTable makeSpreadTable() {
  SpreadTable t{};
  for (uint32_t m = 0; m < 256; ++m) {
    uint8_t k = 0;
    for (uint32_t j = 0; j < 8; ++j) t.shuffle[m][j] = (m >> j) & 1 ? k++ : 0x80;
    t.count[m] = k;
  }
  return t;
}
constexpr SpreadTable kSpread = makeSpreadTable();

}  // namespace

void shuffleResidualsSsse3(GroupRow& row, uint8_t* scratch, __m128i* resT) {
  const uint32_t M = row.M;
  for (uint32_t i = 0; i < kHitsMedLanes; ++i) {
    // A row takes at most M residuals, so each 8-byte load stays inside the row's M bytes; near the
    // end of the stream those are copied first, so that no load passes it.
    const uint8_t* r = row.res[i];
    if (uint64_t(row.end - r) < M) r = static_cast<uint8_t*>(std::memcpy(scratch + 16 * M, r, size_t(row.end - r)));
    const uint8_t* const from = r;
    uint8_t* out = scratch + i * M;
    for (uint32_t k = 0; k < M / 8; ++k) {
      const uint8_t m = row.mask[i][k];
      const __m128i v = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(r));
      const __m128i spread = _mm_loadl_epi64(reinterpret_cast<const __m128i*>(kSpread.shuffle[m]));
      _mm_storel_epi64(reinterpret_cast<__m128i*>(out + 8 * k), _mm_shuffle_epi8(v, spread));
      r += kSpread.count[m];
    }
    row.res[i] += r - from;
  }
  for (uint32_t x0 = 0; x0 < M; x0 += 16) {
    __m128i t[16];
    for (uint32_t i = 0; i < kHitsMedLanes; ++i)
      t[i] = _mm_loadu_si128(reinterpret_cast<const __m128i*>(scratch + i * M + x0));
    transpose16(t);
    for (uint32_t x = 0; x < 16; ++x) resT[x0 + x] = t[x];
  }
}

}  // namespace vff::detail

#endif
