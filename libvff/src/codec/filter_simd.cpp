// filter_simd.cpp - the hits-med decoder for 16 maps at once, one map per byte lane of SSE2 vectors.
//
// Why: each map decodes as one serial chain (a hit's prediction needs the hit just decoded to its
// left and the map's previous hit), so the scalar decoder runs at the latency of that chain and
// mispredicts a branch at every hit/miss edge. The maps of a block are independent, so here lane i
// carries map i of a group of 16: the chain is walked once per texel position for all 16 maps,
// without branches, misses costing as much as hits. The result is exactly the scalar decoder's
// (filter.cpp, unapplyHitsMedScalar), which tests/unit/test_filter.cpp checks on random blocks.
//
// Per row y of the group:
//   1. each lane's residuals of the row are put at the x of its hits, in the transposed layout (one
//      vector per x). Each map's residuals lie contiguous in the stream, map after map, so a lane
//      starts where the previous lane's map ends. With SSSE3 (nearly every x86-64 processor, checked
//      at run time: filter_simd_ssse3.cpp), PSHUFB spreads them 8 texels at a time; with SSE2
//      alone, a scalar store per hit (slower: the per-hit loops' exits mispredict);
//   2. x walks the row 16 texels at a time: MED prediction from a (left), b (up) and c (up-left),
//      255 standing for a miss or a texel outside the map as in the spec, + residual, 255 where the
//      mask has a miss; the 16 result vectors are transposed back into 16 map rows and stored.
// The row above lives transposed (one vector per x) in `above`, which the walk overwrites in place.
#include "codec/filter.h"

#if VFF_HITS_MED_LANES

#include <emmintrin.h>  // SSE2

#include <bit>
#include <cstring>
#include <vector>

#include "platform/cpu_features.h"
#include "codec/filter_lanes.h"

namespace vff::detail {

namespace {

// Hits in `n` mask bytes (n a multiple of 16): a population count per byte, summed by PSADBW.
uint64_t countHits(const uint8_t* mask, uint64_t n) noexcept {
  const __m128i m1 = _mm_set1_epi8(0x55), m2 = _mm_set1_epi8(0x33), m4 = _mm_set1_epi8(0x0F);
  __m128i sum = _mm_setzero_si128();
  for (uint64_t i = 0; i < n; i += 16) {
    __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(mask + i));
    v = _mm_sub_epi8(v, _mm_and_si128(_mm_srli_epi16(v, 1), m1));
    v = _mm_add_epi8(_mm_and_si128(v, m2), _mm_and_si128(_mm_srli_epi16(v, 2), m2));
    v = _mm_and_si128(_mm_add_epi8(v, _mm_srli_epi16(v, 4)), m4);
    sum = _mm_add_epi64(sum, _mm_sad_epu8(v, _mm_setzero_si128()));
  }
  return uint64_t(_mm_cvtsi128_si64(sum)) + uint64_t(_mm_cvtsi128_si64(_mm_unpackhi_epi64(sum, sum)));
}

// The mask bits of x .. x + 63 of a row (x + 64 <= M) or x .. M - 1 (fewer when M is not a
// multiple of 64; rows start on a byte, M being a multiple of 16, and end on one).
inline uint64_t rowBits(const uint8_t* row, uint32_t x, uint32_t M) noexcept {
  uint64_t bits = 0;
  std::memcpy(&bits, row + x / 8, M - x >= 64 ? 8 : (M - x) / 8);  // little-endian, as le.h assumes
  return bits;
}

void scatterResiduals(GroupRow& row, uint8_t* /*scratch*/, __m128i* resT) {
  uint8_t* out = reinterpret_cast<uint8_t*>(resT);
  for (uint32_t i = 0; i < kHitsMedLanes; ++i) {
    const uint8_t* r = row.res[i];
    // A whole 64-bit word per loop keeps the mispredicted loop exits to one per 64 texels.
    for (uint32_t x0 = 0; x0 < row.M; x0 += 64)
      for (uint64_t b = rowBits(row.mask[i], x0, row.M); b; b &= b - 1)
        out[(x0 + uint32_t(std::countr_zero(b))) * 16 + i] = *r++;
    row.res[i] = r;
  }
}

// Decodes maps first .. first + 15 (lane i: map first + i), whose residuals start at start[i].
// `above` holds M + 1 vectors, `resT` M, `scratch` 17 M + 8 bytes. False when a hit decoded to the
// miss code (the output is then incomplete): there are then more miss codes in the output than
// misses in the mask, which is what is checked (counted per tile, out of the walk's registers).
bool decodeGroup(ExpandResiduals expand, const uint8_t* mask, const uint8_t* const start[kHitsMedLanes],
                 const uint8_t* end, uint32_t M, uint64_t first, uint8_t* raw, __m128i* above, __m128i* resT,
                 uint8_t* scratch) {
  const uint64_t mapTexels = uint64_t(M) * M;
  const __m128i miss = _mm_set1_epi8(-1), zero = _mm_setzero_si128();
  GroupRow row;
  row.end = end;
  row.M = M;
  for (uint32_t i = 0; i < kHitsMedLanes; ++i) row.res[i] = start[i];
  for (uint32_t x = 0; x <= M; ++x) above[x] = miss;  // above[0] is x = -1; the row above the first
  __m128i last = zero, missCount = zero;
  for (uint32_t y = 0; y < M; ++y) {
    // 1. Each lane's row of mask bits, and its residuals at their x.
    for (uint32_t i = 0; i < kHitsMedLanes; ++i) row.mask[i] = mask + ((first + i) * mapTexels + uint64_t(y) * M) / 8;
    expand(row, scratch, resT);
    // 2. The walk along x (predict() in filter.cpp for 16 maps, with compare masks for its branches),
    //    16 texels at a time, and 3. their transposition back into map rows.
    //    The walk is one chain per lane (a -> v -> a), so it is written to put as little as possible
    //    on it; everything that hangs on the mask and the row above is computed beside it. Which
    //    neighbours are hits is known from the mask (aMiss: the previous texel's isMiss) and the row
    //    above (bMiss; cMiss, the previous bMiss), not from a. With 255 the code of a miss, every case
    //    of predict() is a + b - M for one M, v = a + b' + r - M:
    //      a, b, c hits:           M = median(a, b, c)                      (MED: a + b - median)
    //      a, b hits, c a miss:    M = ceil((a + b) / 2) = PAVGB(a, b)      (floor((a + b) / 2))
    //      one of a, b a miss:     M = 255 (so the prediction is the other one)
    //      a, b misses:            M = 255, b' = c, or the previous hit where c is a miss too
    //    with b' = b but in the last case. M = min(median(a, b, c'), max(PAVGB(a, b), x1)), where
    //    c' = 255 unless a and b are hits, and x1 = c (a, b, c hits: the median is no more than
    //    max(PAVGB, c)), 0 (c a miss: the median of a, b, 255 is max(a, b), PAVGB is less) or 255
    //    (a or b a miss). The median is max(min(a, max(b, c')), min(b, c')), so a goes through five
    //    operations (min, max / PAVGB, max; min; sub; or), where predict()'s selects took ten.
    //    The previous hit: where it counts, the previous texel is a miss, so the value before that
    //    texel (lastPrev) is the same and keeps `last`'s update off the chain.
    __m128i a = miss, c = miss, aMiss = miss, cMiss = miss, lastPrev = last;
    for (uint32_t x0 = 0; x0 < M; x0 += 16) {
      // The tile's mask bits as bytes, lane i in byte i: x 0..7 in lo, 8..15 in hi (each lane's 16
      // bits set as a word, then split; the words are < 256 after masking or shifting, so the
      // saturating pack keeps them). _mm_setr_epi16 rather than a loop of _mm_insert_epi16, whose
      // index must be a constant (Clang insists even in an unrolled loop).
      uint16_t u[16];
      for (int i = 0; i < 16; ++i) std::memcpy(&u[i], row.mask[i] + x0 / 8, 2);
      const __m128i w0 = _mm_setr_epi16(short(u[0]), short(u[1]), short(u[2]), short(u[3]), short(u[4]),
                                        short(u[5]), short(u[6]), short(u[7]));
      const __m128i w1 = _mm_setr_epi16(short(u[8]), short(u[9]), short(u[10]), short(u[11]), short(u[12]),
                                        short(u[13]), short(u[14]), short(u[15]));
      const __m128i low = _mm_set1_epi16(0xFF);
      const __m128i lo = _mm_packus_epi16(_mm_and_si128(w0, low), _mm_and_si128(w1, low));
      const __m128i hi = _mm_packus_epi16(_mm_srli_epi16(w0, 8), _mm_srli_epi16(w1, 8));
      __m128i* out = above + x0 + 1;
#pragma GCC unroll 16
      for (int x = 0; x < 16; ++x) {
        const __m128i bit = _mm_set1_epi8(char(1 << (x & 7)));
        const __m128i isMiss = _mm_cmpeq_epi8(_mm_and_si128(x < 8 ? lo : hi, bit), zero);
        const __m128i b = out[x];
        const __m128i bMiss = _mm_cmpeq_epi8(b, miss);
        const __m128i abMiss = _mm_or_si128(aMiss, bMiss);
        const __m128i c1 = _mm_or_si128(c, abMiss);
        const __m128i hiBC = _mm_max_epu8(b, c1), loBC = _mm_min_epu8(b, c1);
        const __m128i x1 = _mm_andnot_si128(_mm_andnot_si128(abMiss, cMiss), c1);
        const __m128i e = _mm_sub_epi8(c, _mm_andnot_si128(lastPrev, cMiss));
        const __m128i be = _mm_sub_epi8(b, _mm_andnot_si128(e, _mm_and_si128(aMiss, bMiss)));
        const __m128i br = _mm_add_epi8(be, resT[x0 + x]);
        const __m128i med = _mm_max_epu8(_mm_min_epu8(a, hiBC), loBC);
        const __m128i t = _mm_max_epu8(_mm_avg_epu8(a, b), x1);
        const __m128i v = _mm_sub_epi8(_mm_add_epi8(a, br), _mm_min_epu8(med, t));
        lastPrev = last;
        last = _mm_or_si128(_mm_andnot_si128(isMiss, v), _mm_and_si128(isMiss, last));
        a = _mm_or_si128(v, isMiss);  // the miss code where the mask has a miss
        aMiss = isMiss;
        c = b;
        cMiss = bMiss;
        out[x] = a;
      }
      __m128i rows[16];
      __m128i n = zero;
      for (int x = 0; x < 16; ++x) rows[x] = out[x], n = _mm_sub_epi8(n, _mm_cmpeq_epi8(rows[x], miss));
      missCount = _mm_add_epi64(missCount, _mm_sad_epu8(n, zero));
      transpose16(rows);
      for (uint32_t i = 0; i < kHitsMedLanes; ++i)
        _mm_storeu_si128(reinterpret_cast<__m128i*>(raw + (first + i) * mapTexels + uint64_t(y) * M + x0), rows[i]);
    }
  }
  const uint64_t hits = uint64_t(row.res[kHitsMedLanes - 1] - start[0]);
  return uint64_t(_mm_cvtsi128_si64(missCount)) + uint64_t(_mm_cvtsi128_si64(_mm_unpackhi_epi64(missCount, missCount))) ==
         kHitsMedLanes * mapTexels - hits;
}

}  // namespace

bool hitsMedLanesSsse3() noexcept {
#if defined(VFF_HAVE_SSSE3_LANES)
  return cpuFeatures().ssse3;
#else
  return false;
#endif
}

HitsMedProgress unapplyHitsMedLanes(std::span<const uint8_t> filtered, const uint8_t* residuals, uint32_t M,
                                    uint64_t mapCount, uint8_t* raw, bool ssse3) {
#if defined(VFF_HAVE_SSSE3_LANES)
  const ExpandResiduals expand = ssse3 ? shuffleResidualsSsse3 : scatterResiduals;
#else
  const ExpandResiduals expand = scatterResiduals;
  (void)ssse3;
#endif
  const uint8_t* mask = filtered.data();
  const uint64_t mapMaskBytes = uint64_t(M) * M / 8;  // a multiple of 32: maps start on a byte
  struct alignas(16) Vec {  // storage for __m128i (which a std::vector would lose the attributes of)
    uint8_t bytes[16];
  };
  std::vector<Vec> above(M + 1), resT(M);
  std::vector<uint8_t> scratch(17 * uint64_t(M) + 8);
  HitsMedProgress done{0, residuals};
  for (; done.maps + kHitsMedLanes <= mapCount; done.maps += kHitsMedLanes) {
    const uint8_t* start[kHitsMedLanes + 1] = {done.residuals};
    for (uint32_t i = 0; i < kHitsMedLanes; ++i)
      start[i + 1] = start[i] + countHits(mask + (done.maps + i) * mapMaskBytes, mapMaskBytes);
    if (!decodeGroup(expand, mask, start, filtered.data() + filtered.size(), M, done.maps, raw,
                     reinterpret_cast<__m128i*>(above.data()), reinterpret_cast<__m128i*>(resT.data()),
                     scratch.data()))
      break;
    done.residuals = start[kHitsMedLanes];
  }
  return done;
}

}  // namespace vff::detail

#endif
