// filter_lanes.h - what the hits-med lanes' files share (private): filter_simd.cpp (SSE2, the
// baseline) and filter_simd_ssse3.cpp (compiled alone for SSSE3, called only where cpu_features.h
// finds it). The functions sit in an unnamed namespace, so that each file has its own copy,
// compiled for its own instruction set.
#pragma once

#include <emmintrin.h>  // SSE2

#include <cstdint>

#include "codec/filter.h"

namespace vff::detail {

// One row of a group: each lane's mask bits and next residual.
struct GroupRow {
  const uint8_t* mask[kHitsMedLanes];  // lane i's mask bits of the row
  const uint8_t* res[kHitsMedLanes];   // lane i's next residual; advanced past the row's
  const uint8_t* end;                  // the end of the stream
  uint32_t M;
};

// Puts each lane's residuals of the row at the x of its hits (resT[x] byte i; the bytes at misses
// are left as they were). Two ways: a scalar store per hit (SSE2, filter_simd.cpp), or PSHUFB
// (SSSE3, below).
using ExpandResiduals = void (*)(GroupRow& row, uint8_t* scratch, __m128i* resT);

// Each lane's row spread 8 texels at a time into `scratch` (16 rows of M bytes, then M + 8 for a
// row's residuals at the end of the stream), then transposed: no branch per hit, and 8 texels for a
// few instructions (filter_simd_ssse3.cpp, where libvff/CMakeLists.txt defines VFF_HAVE_SSSE3_LANES).
void shuffleResidualsSsse3(GroupRow& row, uint8_t* scratch, __m128i* resT);

namespace {

// Transposes a 16 x 16 byte matrix (v[i] byte j becomes v[j] byte i). Each round interleaves row i
// with row i + 8, which rotates the 8-bit (row, byte) index left by one; four rounds swap its halves.
inline void transpose16(__m128i v[16]) noexcept {
  for (int round = 0; round < 4; ++round) {
    __m128i t[16];
    for (int i = 0; i < 8; ++i) {
      t[2 * i] = _mm_unpacklo_epi8(v[i], v[i + 8]);
      t[2 * i + 1] = _mm_unpackhi_epi8(v[i], v[i + 8]);
    }
    for (int i = 0; i < 16; ++i) v[i] = t[i];
  }
}

}  // namespace
}  // namespace vff::detail
