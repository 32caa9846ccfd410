// simd/vfloat8_avx2.h - the lane type of the AVX2 group kernel (query_group_avx2.cpp): F8, eight
// binary32 lanes in an AVX2 vector, whose masks are vectors too (all-ones or zero per lane), with
// the operations query_group_kernel.h takes of a lane type.
// Included only by query_group_avx2.cpp, the one file compiled for this instruction set; everything
// here sits in an unnamed namespace, so that no function compiled for it is shared with other files.
// (One header per instruction set, as Embree's common/simd.)
#pragma once

#if !(defined(__AVX2__))
#error "compile this header's one includer for its instruction set (libvff/CMakeLists.txt)"
#endif

#include <cstddef>
#include <cstdint>

#include <immintrin.h>

#include "query/batch/query_group.h"

namespace vff::detail {
namespace {

struct F8 {
  static constexpr size_t kLanes = 8;
  using Mask = F8;  // masks are vectors: all-ones or zero per lane
  __m256 v;
  F8() = default;
  F8(__m256 x) : v(x) {}  // NOLINT: implicit, so that intrinsics' results are lanes
  explicit F8(float x) : v(_mm256_set1_ps(x)) {}
  // (Static: they take no lanes to choose an overload by.)
  static F8 none() { return F8(0.0f); }  // the mask of no lane
  static F8 load(const float* p);
  static F8 loadInt(const int32_t* p);
  static F8 gatherBytes(const uint8_t* base, const int32_t* at);
  static void gatherSnorm16Pairs(const uint8_t* base, const int32_t* at, F8* x, F8* y);
  static void compressIndex(uint32_t* dst, uint32_t first, unsigned mask);
  static uint64_t rayBits(const uint32_t* ray, unsigned bits);
  static uint64_t hitsByRay(const Group& g, uint64_t packed);
};

inline F8 operator+(F8 a, F8 b) { return _mm256_add_ps(a.v, b.v); }
inline F8 operator-(F8 a, F8 b) { return _mm256_sub_ps(a.v, b.v); }
inline F8 operator*(F8 a, F8 b) { return _mm256_mul_ps(a.v, b.v); }
inline F8 operator/(F8 a, F8 b) { return _mm256_div_ps(a.v, b.v); }
inline F8 vsqrt(F8 a) { return _mm256_sqrt_ps(a.v); }
inline F8 vrsqrt(F8 a) { return _mm256_rsqrt_ps(a.v); }  // relative error <= 1.5 * 2^-12
inline F8 vmin(F8 a, F8 b) { return _mm256_min_ps(a.v, b.v); }  // a < b ? a : b, as SSE2
inline F8 vmax(F8 a, F8 b) { return _mm256_max_ps(a.v, b.v); }  // a > b ? a : b, as SSE2
inline F8 gt(F8 a, F8 b) { return _mm256_cmp_ps(a.v, b.v, _CMP_GT_OQ); }
inline F8 ge(F8 a, F8 b) { return _mm256_cmp_ps(a.v, b.v, _CMP_GE_OQ); }
inline F8 lt(F8 a, F8 b) { return _mm256_cmp_ps(a.v, b.v, _CMP_LT_OQ); }
inline F8 le(F8 a, F8 b) { return _mm256_cmp_ps(a.v, b.v, _CMP_LE_OQ); }
inline F8 eq(F8 a, F8 b) { return _mm256_cmp_ps(a.v, b.v, _CMP_EQ_OQ); }
inline F8 nlt(F8 a, F8 b) { return _mm256_cmp_ps(a.v, b.v, _CMP_NLT_UQ); }  // !(a < b): true for NaN
inline F8 ngt(F8 a, F8 b) { return _mm256_cmp_ps(a.v, b.v, _CMP_NGT_UQ); }  // !(a > b): true for NaN
inline F8 band(F8 a, F8 b) { return _mm256_and_ps(a.v, b.v); }
inline F8 bor(F8 a, F8 b) { return _mm256_or_ps(a.v, b.v); }
inline F8 bandnot(F8 a, F8 b) { return _mm256_andnot_ps(a.v, b.v); }  // ~a & b
inline F8 bnot(F8 a) { return _mm256_xor_ps(a.v, _mm256_castsi256_ps(_mm256_set1_epi32(-1))); }
inline F8 sel(F8 m, F8 a, F8 b) { return _mm256_blendv_ps(b.v, a.v, m.v); }  // masks are all-ones or zero
// A mask as a vector, to store it among floats, and back (masks are vectors here).
inline F8 maskValue(F8 m) { return m; }
inline F8 valueMask(F8 a) { return a; }
inline F8 vabs(F8 a) { return _mm256_and_ps(a.v, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff))); }
inline F8 vneg(F8 a) { return _mm256_xor_ps(a.v, _mm256_set1_ps(-0.0f)); }
inline F8 floorPos(F8 a) { return _mm256_cvtepi32_ps(_mm256_cvttps_epi32(a.v)); }  // 0 <= a < 2^31
inline F8 F8::load(const float* p) { return _mm256_loadu_ps(p); }
inline F8 F8::loadInt(const int32_t* p) { return _mm256_cvtepi32_ps(_mm256_loadu_si256(reinterpret_cast<const __m256i*>(p))); }
inline void store(float* p, F8 a) { _mm256_storeu_ps(p, a.v); }
inline void storeInt(int32_t* p, F8 a) { _mm256_storeu_si256(reinterpret_cast<__m256i*>(p), _mm256_cvttps_epi32(a.v)); }
inline unsigned movemask(F8 a) { return unsigned(_mm256_movemask_ps(a.v)); }

// For every 8-bit mask, the lanes it selects, in order, packed into the low nibbles of a word
// (lane of position q in bits 4q .. 4q + 3).
constexpr uint32_t packedLanes(unsigned mask) {
  uint32_t word = 0;
  unsigned q = 0;
  for (unsigned l = 0; l < 8; ++l)
    if ((mask >> l) & 1u) word |= l << (4 * q++);
  return word;
}
struct LaneTable {
  uint32_t word[256];
  constexpr LaneTable() : word() {
    for (unsigned m = 0; m < 256; ++m) word[m] = packedLanes(m);
  }
};
constexpr LaneTable kLaneOrder{};

inline __m256i lanePermutation(unsigned mask) {
  const __m256i nibbles = _mm256_set1_epi32(int32_t(kLaneOrder.word[mask]));
  const __m256i shifts = _mm256_setr_epi32(0, 4, 8, 12, 16, 20, 24, 28);
  return _mm256_and_si256(_mm256_srlv_epi32(nibbles, shifts), _mm256_set1_epi32(7));
}
// Stores the lanes of `a` selected by `mask`, in order, at dst[0 ..] (writes 8 floats).
inline void compress(float* dst, F8 a, unsigned mask) {
  _mm256_storeu_ps(dst, _mm256_permutevar8x32_ps(a.v, lanePermutation(mask)));
}
// Stores first + l for the lanes l selected by `mask`, in order, at dst[0 ..] (writes 8 words).
inline void F8::compressIndex(uint32_t* dst, uint32_t first, unsigned mask) {
  const __m256i lanes = _mm256_add_epi32(lanePermutation(mask), _mm256_set1_epi32(int32_t(first)));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst), lanes);
}

// Positions unit4[4 k .. 4 k + 2] of the lanes' samples k (integer-valued floats).
inline void gatherUnit(const float* unit4, F8 k, F8* x, F8* y, F8* z) {
  const __m256i idx = _mm256_slli_epi32(_mm256_cvttps_epi32(k.v), 2);
  *x = _mm256_i32gather_ps(unit4, idx, 4);
  *y = _mm256_i32gather_ps(unit4 + 1, idx, 4);
  *z = _mm256_i32gather_ps(unit4 + 2, idx, 4);
}

// The words table[stride k + offset] as floats (UINT32_MAX as -1) for the lanes' k
// (integer-valued floats) in `use`, 0 in the others.
inline F8 gatherWord(const uint32_t* table, F8 k, int32_t stride, int32_t offset, F8 use) {
  const __m256i idx =
      _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(k.v), _mm256_set1_epi32(stride)), _mm256_set1_epi32(offset));
  return _mm256_cvtepi32_ps(_mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(table), idx,
                                                        _mm256_castps_si256(use.v), 4));
}

// The union of the bytes table[idx] over the lanes in `use` (idx: integer-valued floats; reads
// 4 bytes at table + idx).
inline unsigned maskUnion(const uint8_t* table, F8 idx, F8 use) {
  const __m256i words = _mm256_mask_i32gather_epi32(_mm256_setzero_si256(), reinterpret_cast<const int*>(table),
                                                    _mm256_cvttps_epi32(idx.v), _mm256_castps_si256(use.v), 1);
  __m128i x = _mm_or_si128(_mm256_castsi256_si128(words), _mm256_extracti128_si256(words, 1));
  x = _mm_or_si128(x, _mm_shuffle_epi32(x, 0x4E));
  x = _mm_or_si128(x, _mm_shuffle_epi32(x, 0xB1));
  return unsigned(_mm_cvtsi128_si32(x)) & 0xFFu;
}

// (AVX-512 only: here every lookup reads its cell's mask.)
inline bool cornersSuffice(const uint32_t*, F8, F8, F8) { return false; }

// k * mapBytes + t for the lanes' samples k and texel bytes t (integer-valued floats), into dst.
inline void storeTexelIndex(int32_t* dst, F8 k, F8 t, int32_t mapBytes) {
  const __m256i at = _mm256_add_epi32(_mm256_mullo_epi32(_mm256_cvttps_epi32(k.v), _mm256_set1_epi32(mapBytes)),
                                      _mm256_cvttps_epi32(t.v));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(dst), at);
}
// The bytes base[at[l]] as floats. Reads 4 bytes per lane, ending at the byte (or, for the first 3
// bytes, starting at base): never outside [base, base + 4) and the bytes up to the one read.
inline F8 F8::gatherBytes(const uint8_t* base, const int32_t* at) {
  const __m256i idx = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(at));
  const __m256i back = _mm256_min_epi32(idx, _mm256_set1_epi32(3));  // bytes read before the wanted one
  const __m256i words = _mm256_i32gather_epi32(reinterpret_cast<const int*>(base), _mm256_sub_epi32(idx, back), 1);
  const __m256i bytes = _mm256_and_si256(_mm256_srlv_epi32(words, _mm256_slli_epi32(back, 3)), _mm256_set1_epi32(0xFF));
  return _mm256_cvtepi32_ps(bytes);
}
// The two snorm16 codes of the 4-byte words at base + at[l] (little-endian), as floats.
inline void F8::gatherSnorm16Pairs(const uint8_t* base, const int32_t* at, F8* x, F8* y) {
  const __m256i w = _mm256_i32gather_epi32(reinterpret_cast<const int*>(base),
                                           _mm256_loadu_si256(reinterpret_cast<const __m256i*>(at)), 1);
  *x = _mm256_cvtepi32_ps(_mm256_srai_epi32(_mm256_slli_epi32(w, 16), 16));
  *y = _mm256_cvtepi32_ps(_mm256_srai_epi32(w, 16));
}
// Bit ray[l] for every lane l set in `bits` (ray[l] < 64).
inline uint64_t F8::rayBits(const uint32_t* ray, unsigned bits) {
  const __m256i lane = _mm256_setr_epi32(1, 2, 4, 8, 16, 32, 64, 128);
  const __m256i on = _mm256_cmpeq_epi32(_mm256_and_si256(_mm256_set1_epi32(int32_t(bits)), lane), lane);
  const __m256i r = _mm256_loadu_si256(reinterpret_cast<const __m256i*>(ray));
  const __m256i one = _mm256_set1_epi32(1);
  // sllv gives 0 for shifts of 32 or more: the low word takes rays 0 .. 31, the high 32 .. 63.
  const __m256i lo = _mm256_and_si256(on, _mm256_sllv_epi32(one, r));
  const __m256i hi = _mm256_and_si256(on, _mm256_sllv_epi32(one, _mm256_sub_epi32(r, _mm256_set1_epi32(32))));
  auto orLanes = [](__m256i w) {
    __m128i x = _mm_or_si128(_mm256_castsi256_si128(w), _mm256_extracti128_si256(w, 1));
    x = _mm_or_si128(x, _mm_shuffle_epi32(x, 0x4E));
    x = _mm_or_si128(x, _mm_shuffle_epi32(x, 0xB1));
    return uint32_t(_mm_cvtsi128_si32(x));
  };
  return uint64_t(orLanes(lo)) | (uint64_t(orLanes(hi)) << 32);
}

// Eight rays of eight floats each (origin, direction, tmin, tmax), transposed.
inline void loadRays(const float* p, F8* ox, F8* oy, F8* oz, F8* dx, F8* dy, F8* dz, F8* tmin, F8* tmax) {
  __m256 r[8];
  for (int i = 0; i < 8; ++i) r[i] = _mm256_loadu_ps(p + 8 * i);
  const __m256 t0 = _mm256_unpacklo_ps(r[0], r[1]), t1 = _mm256_unpackhi_ps(r[0], r[1]);
  const __m256 t2 = _mm256_unpacklo_ps(r[2], r[3]), t3 = _mm256_unpackhi_ps(r[2], r[3]);
  const __m256 t4 = _mm256_unpacklo_ps(r[4], r[5]), t5 = _mm256_unpackhi_ps(r[4], r[5]);
  const __m256 t6 = _mm256_unpacklo_ps(r[6], r[7]), t7 = _mm256_unpackhi_ps(r[6], r[7]);
  const __m256 u0 = _mm256_shuffle_ps(t0, t2, 0x44), u1 = _mm256_shuffle_ps(t0, t2, 0xEE);
  const __m256 u2 = _mm256_shuffle_ps(t1, t3, 0x44), u3 = _mm256_shuffle_ps(t1, t3, 0xEE);
  const __m256 u4 = _mm256_shuffle_ps(t4, t6, 0x44), u5 = _mm256_shuffle_ps(t4, t6, 0xEE);
  const __m256 u6 = _mm256_shuffle_ps(t5, t7, 0x44), u7 = _mm256_shuffle_ps(t5, t7, 0xEE);
  *ox = _mm256_permute2f128_ps(u0, u4, 0x20);
  *oy = _mm256_permute2f128_ps(u1, u5, 0x20);
  *oz = _mm256_permute2f128_ps(u2, u6, 0x20);
  *dx = _mm256_permute2f128_ps(u3, u7, 0x20);
  *dy = _mm256_permute2f128_ps(u0, u4, 0x31);
  *dz = _mm256_permute2f128_ps(u1, u5, 0x31);
  *tmin = _mm256_permute2f128_ps(u2, u6, 0x31);
  *tmax = _mm256_permute2f128_ps(u3, u7, 0x31);
}

}  // namespace
}  // namespace vff::detail
