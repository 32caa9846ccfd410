// simd/vfloat16_avx512.h - the lane type of the AVX-512 group kernel (query_group_avx512.cpp): F16,
// sixteen binary32 lanes in an AVX-512 vector, whose masks are mask registers (M16), with the
// operations query_group_kernel.h takes of a lane type.
// Included only by query_group_avx512.cpp, the one file compiled for this instruction set; everything
// here sits in an unnamed namespace, so that no function compiled for it is shared with other files.
// (One header per instruction set, as Embree's common/simd.)
#pragma once

#if !(defined(__AVX512F__) && defined(__AVX512DQ__) && defined(__AVX512VL__) && defined(__AVX512BW__) && defined(__BMI2__))
#error "compile this header's one includer for its instruction set (libvff/CMakeLists.txt)"
#endif

#include <cstddef>
#include <cstdint>

#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ < 13
// GCC 12's AVX-512 intrinsics start from _mm512_undefined_ps() and warn that it is uninitialized
// wherever they are inlined (GCC bug 105593, fixed in GCC 13).
#pragma GCC diagnostic ignored "-Wuninitialized"
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <immintrin.h>

#include "query/batch/query_group.h"

namespace vff::detail {
namespace {

// A mask of sixteen lanes: an AVX-512 mask register (the other kernels' masks are vectors).
struct M16 {
  static constexpr size_t kLanes = 16;
  using Mask = M16;
  __mmask16 k;
  static M16 none() { return {0}; }
};

// Sixteen lanes.
struct F16 {
  static constexpr size_t kLanes = 16;
  using Mask = M16;
  __m512 v;
  F16() = default;
  F16(__m512 x) : v(x) {}  // NOLINT: implicit, so that intrinsics' results are lanes
  explicit F16(float x) : v(_mm512_set1_ps(x)) {}
  // (Static: they take no lanes to choose an overload by.)
  static F16 load(const float* p);
  static F16 loadInt(const int32_t* p);
  static F16 gatherBytes(const uint8_t* base, const int32_t* at);
  static void gatherSnorm16Pairs(const uint8_t* base, const int32_t* at, F16* x, F16* y);
  static void compressIndex(uint32_t* dst, uint32_t first, unsigned mask);
  static uint64_t hitsByRay(const Group& g, uint64_t packed);
};

// A mask as a vector (all-ones or zero per lane), to store it among floats, and back.
inline F16 maskValue(M16 m) { return _mm512_castsi512_ps(_mm512_movm_epi32(m.k)); }
inline M16 valueMask(F16 a) { return {_mm512_movepi32_mask(_mm512_castps_si512(a.v))}; }

inline F16 operator+(F16 a, F16 b) { return _mm512_add_ps(a.v, b.v); }
inline F16 operator-(F16 a, F16 b) { return _mm512_sub_ps(a.v, b.v); }
inline F16 operator*(F16 a, F16 b) { return _mm512_mul_ps(a.v, b.v); }
inline F16 operator/(F16 a, F16 b) { return _mm512_div_ps(a.v, b.v); }
inline F16 vsqrt(F16 a) { return _mm512_sqrt_ps(a.v); }
inline F16 vrsqrt(F16 a) { return _mm512_rsqrt14_ps(a.v); }  // relative error <= 2^-14
inline F16 vmin(F16 a, F16 b) { return _mm512_min_ps(a.v, b.v); }  // a < b ? a : b, as SSE2
inline F16 vmax(F16 a, F16 b) { return _mm512_max_ps(a.v, b.v); }  // a > b ? a : b, as SSE2
inline M16 gt(F16 a, F16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_GT_OQ)}; }
inline M16 ge(F16 a, F16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_GE_OQ)}; }
inline M16 lt(F16 a, F16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_LT_OQ)}; }
inline M16 le(F16 a, F16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_LE_OQ)}; }
inline M16 eq(F16 a, F16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_EQ_OQ)}; }
inline M16 nlt(F16 a, F16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_NLT_UQ)}; }  // !(a < b): true for NaN
inline M16 ngt(F16 a, F16 b) { return {_mm512_cmp_ps_mask(a.v, b.v, _CMP_NGT_UQ)}; }  // !(a > b): true for NaN
inline M16 band(M16 a, M16 b) { return {__mmask16(a.k & b.k)}; }
inline M16 bor(M16 a, M16 b) { return {__mmask16(a.k | b.k)}; }
inline M16 bandnot(M16 a, M16 b) { return {__mmask16(~a.k & b.k)}; }  // ~a & b
inline M16 bnot(M16 a) { return {__mmask16(~a.k)}; }
// The lanes of a in m (band) or not in m (bandnot), zero elsewhere.
inline F16 band(M16 m, F16 a) { return _mm512_maskz_mov_ps(m.k, a.v); }
inline F16 bandnot(M16 m, F16 a) { return _mm512_maskz_mov_ps(__mmask16(~m.k), a.v); }
// m ? a : b lane by lane.
inline F16 sel(M16 m, F16 a, F16 b) { return _mm512_mask_blend_ps(m.k, b.v, a.v); }
inline F16 vabs(F16 a) { return _mm512_abs_ps(a.v); }
inline F16 vneg(F16 a) { return _mm512_xor_ps(a.v, _mm512_set1_ps(-0.0f)); }
inline F16 floorPos(F16 a) { return _mm512_cvtepi32_ps(_mm512_cvttps_epi32(a.v)); }  // 0 <= a < 2^31
inline F16 F16::load(const float* p) { return _mm512_loadu_ps(p); }
inline F16 F16::loadInt(const int32_t* p) { return _mm512_cvtepi32_ps(_mm512_loadu_si512(p)); }
inline void store(float* p, F16 a) { _mm512_storeu_ps(p, a.v); }
inline void storeInt(int32_t* p, F16 a) { _mm512_storeu_si512(p, _mm512_cvttps_epi32(a.v)); }
inline unsigned movemask(M16 m) { return unsigned(m.k); }

// The lanes selected by `mask`, in order, then zeros: the permutation that compress applies, as
// the AVX2 kernel's lanePermutation. (The sphere step compresses ten arrays by one mask: GCC
// computes this once for all of them, and each array then costs one vpermps, one micro-op,
// instead of a vcompressps, two.)
inline __m512i lanePermutation(unsigned mask) {
  return _mm512_maskz_compress_epi32(__mmask16(mask), _mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15));
}
// Stores the lanes of `a` selected by `mask`, in order, at dst[0 ..] (writes 16 floats).
inline void compress(float* dst, F16 a, unsigned mask) {
  _mm512_storeu_ps(dst, _mm512_permutexvar_ps(lanePermutation(mask), a.v));
}
// Stores first + l for the lanes l selected by `mask`, in order, at dst[0 ..] (writes 16 words).
inline void F16::compressIndex(uint32_t* dst, uint32_t first, unsigned mask) {
  const __m512i lanes =
      _mm512_add_epi32(_mm512_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15), _mm512_set1_epi32(int32_t(first)));
  _mm512_storeu_si512(dst, _mm512_maskz_compress_epi32(__mmask16(mask), lanes));
}

// Positions unit4[4 k .. 4 k + 2] of the lanes' samples k (integer-valued floats): (x, y) as one
// 8-byte word per lane, two gathers of eight, and z by a gather of sixteen: 32 lanes gathered
// instead of 48 for three gathers of sixteen.
inline void gatherUnit(const float* unit4, F16 k, F16* x, F16* y, F16* z) {
  const __m512i ki = _mm512_cvttps_epi32(k.v);
  const __m512i pair = _mm512_slli_epi32(ki, 1);  // the index of (x, y) in 8-byte words
  const __m512 lo = _mm512_castsi512_ps(_mm512_i32gather_epi64(_mm512_castsi512_si256(pair), unit4, 8));
  const __m512 hi = _mm512_castsi512_ps(_mm512_i32gather_epi64(_mm512_extracti64x4_epi64(pair, 1), unit4, 8));
  *x = _mm512_permutex2var_ps(lo, _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30), hi);
  *y = _mm512_permutex2var_ps(lo, _mm512_setr_epi32(1, 3, 5, 7, 9, 11, 13, 15, 17, 19, 21, 23, 25, 27, 29, 31), hi);
  *z = _mm512_i32gather_ps(_mm512_slli_epi32(ki, 2), unit4 + 2, 4);
}

// The words table[stride k + offset] as floats (UINT32_MAX as -1) for the lanes' k
// (integer-valued floats) in `use`, 0 in the others.
inline F16 gatherWord(const uint32_t* table, F16 k, int32_t stride, int32_t offset, M16 use) {
  const __m512i idx =
      _mm512_add_epi32(_mm512_mullo_epi32(_mm512_cvttps_epi32(k.v), _mm512_set1_epi32(stride)), _mm512_set1_epi32(offset));
  return _mm512_cvtepi32_ps(_mm512_mask_i32gather_epi32(_mm512_setzero_si512(), use.k, idx, table, 4));
}

// The union of the bytes table[idx] over the lanes in `use` (idx: integer-valued floats; reads
// 4 bytes at table + idx).
inline unsigned maskUnion(const uint8_t* table, F16 idx, M16 use) {
  const __mmask16 k = use.k;
  const __m512i words = _mm512_mask_i32gather_epi32(_mm512_setzero_si512(), k, _mm512_cvttps_epi32(idx.v), table, 1);
  return unsigned(_mm512_mask_reduce_or_epi32(k, words)) & 0xFFu;
}

// Whether every lane in `use` lies in a cell (a0, b0) (integer-valued floats, < 32) whose bit a0 of
// rows[b0] is clear (GroupTables::octaCornerRows: 32 rows, looked up in two registers).
inline bool cornersSuffice(const uint32_t* rows, F16 a0, F16 b0, M16 use) {
  const __m512i row = _mm512_permutex2var_epi32(_mm512_loadu_si512(rows), _mm512_cvttps_epi32(b0.v),
                                                _mm512_loadu_si512(rows + 16));
  const __m512i bit = _mm512_srlv_epi32(row, _mm512_cvttps_epi32(a0.v));
  return _mm512_mask_test_epi32_mask(use.k, bit, _mm512_set1_epi32(1)) == 0;
}

// k * mapBytes + t for the lanes' samples k and texel bytes t (integer-valued floats), into dst.
inline void storeTexelIndex(int32_t* dst, F16 k, F16 t, int32_t mapBytes) {
  const __m512i at = _mm512_add_epi32(_mm512_mullo_epi32(_mm512_cvttps_epi32(k.v), _mm512_set1_epi32(mapBytes)),
                                      _mm512_cvttps_epi32(t.v));
  _mm512_storeu_si512(dst, at);
}
// The bytes base[at[l]] as floats: sixteen byte loads, which ran no slower than a vpgatherdd of the
// words ending at each byte on the scattered texels of the decode (loading the sample positions of
// gatherUnit the same way, with a transpose, gained nothing).
inline F16 F16::gatherBytes(const uint8_t* base, const int32_t* at) {
  alignas(64) int32_t bytes[16];
  for (int l = 0; l < 16; ++l) bytes[l] = base[at[l]];
  return _mm512_cvtepi32_ps(_mm512_load_si512(bytes));
}
// The two snorm16 codes of the 4-byte words at base + at[l] (little-endian), as floats.
inline void F16::gatherSnorm16Pairs(const uint8_t* base, const int32_t* at, F16* x, F16* y) {
  const __m512i w = _mm512_i32gather_epi32(_mm512_loadu_si512(at), base, 1);
  *x = _mm512_cvtepi32_ps(_mm512_srai_epi32(_mm512_slli_epi32(w, 16), 16));
  *y = _mm512_cvtepi32_ps(_mm512_srai_epi32(w, 16));
}
// Bit g.ray[p] for every bit p set in `packed` (packed ray p): the packed rays are the rays set in
// g.reached, in order, so this deposits the bits of `packed` at those of g.reached (BMI2's pdep,
// which every CPU with AVX-512 BW, DQ and VL has; query_group.cpp checks it too).
inline uint64_t F16::hitsByRay(const Group& g, uint64_t packed) { return _pdep_u64(packed, g.reached); }

// Sixteen rays of eight floats each (origin, direction, tmin, tmax), transposed: lane l of
// component c is float c of ray l. Each 256-bit half of a vector takes one ray (r[i]: rays i and
// i + 4, r[4 + i]: rays 8 + i and 12 + i, i < 4), so that the eight-by-eight transpose runs
// within the 128-bit lanes (unpack, then shuffle) and ends with one shuffle of 128-bit lanes
// per component.
inline void loadRays(const float* p, F16* ox, F16* oy, F16* oz, F16* dx, F16* dy, F16* dz, F16* tmin, F16* tmax) {
  __m512 r[8];
  for (int i = 0; i < 4; ++i) {
    r[i] = _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_loadu_ps(p + 8 * i)), _mm256_loadu_ps(p + 8 * (i + 4)), 1);
    r[4 + i] = _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_loadu_ps(p + 8 * (8 + i))),
                                  _mm256_loadu_ps(p + 8 * (12 + i)), 1);
  }
  // Per 128-bit lane, of rays a and b: (a0 b0 a1 b1) and (a2 b2 a3 b3) (floats 4-7 in the upper
  // lane of each half).
  __m512 t[8];
  for (int q = 0; q < 4; ++q) {
    t[2 * q] = _mm512_unpacklo_ps(r[2 * q], r[2 * q + 1]);
    t[2 * q + 1] = _mm512_unpackhi_ps(r[2 * q], r[2 * q + 1]);
  }
  // Float c of four rays per 128-bit lane: s[4 h + c] (c < 4) holds float c in lanes 0 and 2,
  // float c + 4 in lanes 1 and 3, of rays 0-3 and 4-7 (h = 0) or 8-11 and 12-15 (h = 1).
  __m512 s[8];
  for (int h = 0; h < 2; ++h) {
    const __m512 a = t[4 * h], b = t[4 * h + 1], c = t[4 * h + 2], d = t[4 * h + 3];
    s[4 * h + 0] = _mm512_shuffle_ps(a, c, _MM_SHUFFLE(1, 0, 1, 0));
    s[4 * h + 1] = _mm512_shuffle_ps(a, c, _MM_SHUFFLE(3, 2, 3, 2));
    s[4 * h + 2] = _mm512_shuffle_ps(b, d, _MM_SHUFFLE(1, 0, 1, 0));
    s[4 * h + 3] = _mm512_shuffle_ps(b, d, _MM_SHUFFLE(3, 2, 3, 2));
  }
  // Lanes 0 and 2 of each (floats 0-3), or 1 and 3 (floats 4-7), rays 0-15 in order.
  F16* const low[4] = {ox, oy, oz, dx};
  F16* const high[4] = {dy, dz, tmin, tmax};
  for (int c = 0; c < 4; ++c) {
    *low[c] = _mm512_shuffle_f32x4(s[c], s[4 + c], _MM_SHUFFLE(2, 0, 2, 0));
    *high[c] = _mm512_shuffle_f32x4(s[c], s[4 + c], _MM_SHUFFLE(3, 1, 3, 1));
  }
}

}  // namespace
}  // namespace vff::detail
