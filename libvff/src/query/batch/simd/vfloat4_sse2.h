// simd/vfloat4_sse2.h - the lane type of the SSE2 group kernel (query_group_sse2.cpp): F4, four
// binary32 lanes in an SSE2 vector (every x86-64 CPU has SSE2), whose masks are vectors too
// (all-ones or zero per lane), with the operations query_group_kernel.h takes of a lane type.
// Included only by query_group_sse2.cpp, the one file compiled for this instruction set; everything
// here sits in an unnamed namespace, so that no function compiled for it is shared with other files.
// (One header per instruction set, as Embree's common/simd.)
#pragma once

#if !(defined(__SSE2__))
#error "compile this header's one includer for its instruction set (libvff/CMakeLists.txt)"
#endif

#include <cstddef>
#include <cstdint>

#include <emmintrin.h>
#include <xmmintrin.h>

#include "query/batch/query_group.h"

namespace vff::detail {
namespace {

struct F4 {
  static constexpr size_t kLanes = 4;
  using Mask = F4;  // masks are vectors: all-ones or zero per lane
  __m128 v;
  F4() = default;
  F4(__m128 x) : v(x) {}  // NOLINT: implicit, so that intrinsics' results are lanes
  explicit F4(float x) : v(_mm_set1_ps(x)) {}
  // (Static: they take no lanes to choose an overload by.)
  static F4 none() { return F4(0.0f); }  // the mask of no lane
  static F4 load(const float* p);
  static F4 loadInt(const int32_t* p);
  static F4 gatherBytes(const uint8_t* base, const int32_t* at);
  static void compressIndex(uint32_t* dst, uint32_t first, unsigned mask);
  static uint64_t rayBits(const uint32_t* ray, unsigned bits);
  static uint64_t hitsByRay(const Group& g, uint64_t packed);
};

inline F4 operator+(F4 a, F4 b) { return _mm_add_ps(a.v, b.v); }
inline F4 operator-(F4 a, F4 b) { return _mm_sub_ps(a.v, b.v); }
inline F4 operator*(F4 a, F4 b) { return _mm_mul_ps(a.v, b.v); }
inline F4 operator/(F4 a, F4 b) { return _mm_div_ps(a.v, b.v); }
inline F4 vsqrt(F4 a) { return _mm_sqrt_ps(a.v); }
inline F4 vrsqrt(F4 a) { return _mm_rsqrt_ps(a.v); }  // relative error <= 1.5 * 2^-12
inline F4 vmin(F4 a, F4 b) { return _mm_min_ps(a.v, b.v); }  // a < b ? a : b
inline F4 vmax(F4 a, F4 b) { return _mm_max_ps(a.v, b.v); }  // a > b ? a : b
inline F4 gt(F4 a, F4 b) { return _mm_cmpgt_ps(a.v, b.v); }
inline F4 ge(F4 a, F4 b) { return _mm_cmpge_ps(a.v, b.v); }
inline F4 lt(F4 a, F4 b) { return _mm_cmplt_ps(a.v, b.v); }
inline F4 le(F4 a, F4 b) { return _mm_cmple_ps(a.v, b.v); }
inline F4 eq(F4 a, F4 b) { return _mm_cmpeq_ps(a.v, b.v); }
inline F4 nlt(F4 a, F4 b) { return _mm_cmpnlt_ps(a.v, b.v); }  // !(a < b): true for NaN
inline F4 ngt(F4 a, F4 b) { return _mm_cmpngt_ps(a.v, b.v); }  // !(a > b): true for NaN
inline F4 band(F4 a, F4 b) { return _mm_and_ps(a.v, b.v); }
inline F4 bor(F4 a, F4 b) { return _mm_or_ps(a.v, b.v); }
inline F4 bandnot(F4 a, F4 b) { return _mm_andnot_ps(a.v, b.v); }  // ~a & b
inline F4 bnot(F4 a) { return _mm_xor_ps(a.v, _mm_castsi128_ps(_mm_set1_epi32(-1))); }
inline F4 sel(F4 m, F4 a, F4 b) { return _mm_or_ps(_mm_and_ps(m.v, a.v), _mm_andnot_ps(m.v, b.v)); }
// A mask as a vector, to store it among floats, and back (masks are vectors here).
inline F4 maskValue(F4 m) { return m; }
inline F4 valueMask(F4 a) { return a; }
inline F4 vabs(F4 a) { return _mm_and_ps(a.v, _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff))); }
inline F4 vneg(F4 a) { return _mm_xor_ps(a.v, _mm_set1_ps(-0.0f)); }
inline F4 floorPos(F4 a) { return _mm_cvtepi32_ps(_mm_cvttps_epi32(a.v)); }  // 0 <= a < 2^31
inline F4 F4::load(const float* p) { return _mm_loadu_ps(p); }
inline F4 F4::loadInt(const int32_t* p) { return _mm_cvtepi32_ps(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))); }
inline void store(float* p, F4 a) { _mm_storeu_ps(p, a.v); }
inline void storeInt(int32_t* p, F4 a) { _mm_storeu_si128(reinterpret_cast<__m128i*>(p), _mm_cvttps_epi32(a.v)); }
inline unsigned movemask(F4 a) { return unsigned(_mm_movemask_ps(a.v)); }

// Stores the lanes of `a` selected by `mask`, in order, at dst[0 ..].
inline void compress(float* dst, F4 a, unsigned mask) {
  alignas(16) float v[4];
  _mm_store_ps(v, a.v);
  for (int l = 0; l < 4; ++l)
    if ((mask >> l) & 1u) *dst++ = v[l];
}
// Stores first + l for the lanes l selected by `mask`, in order, at dst[0 ..].
inline void F4::compressIndex(uint32_t* dst, uint32_t first, unsigned mask) {
  for (uint32_t l = 0; l < 4; ++l)
    if ((mask >> l) & 1u) *dst++ = first + l;
}

// Positions unit4[4 k .. 4 k + 2] of the lanes' samples k (integer-valued floats).
inline void gatherUnit(const float* unit4, F4 k, F4* x, F4* y, F4* z) {
  alignas(16) int32_t idx[4];
  storeInt(idx, k);
  __m128 r0 = _mm_loadu_ps(unit4 + 4 * size_t(idx[0])), r1 = _mm_loadu_ps(unit4 + 4 * size_t(idx[1]));
  __m128 r2 = _mm_loadu_ps(unit4 + 4 * size_t(idx[2])), r3 = _mm_loadu_ps(unit4 + 4 * size_t(idx[3]));
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  *x = r0;
  *y = r1;
  *z = r2;
}

// The union of the bytes table[idx] over the lanes in `use` (idx: integer-valued floats).
inline unsigned maskUnion(const uint8_t* table, F4 idx, F4 use) {
  alignas(16) int32_t at[4];
  storeInt(at, idx);
  const unsigned bits = movemask(use);
  unsigned u = 0;
  for (int l = 0; l < 4; ++l)
    if ((bits >> l) & 1u) u |= table[at[l]];
  return u;
}

// (AVX-512 only: here every lookup reads its cell's mask.)
inline bool cornersSuffice(const uint32_t*, F4, F4, F4) { return false; }

// k * mapBytes + t for the lanes' samples k and texel bytes t (integer-valued floats), into dst.
inline void storeTexelIndex(int32_t* dst, F4 k, F4 t, int32_t mapBytes) {
  alignas(16) int32_t ki[4], ti[4];
  storeInt(ki, k);
  storeInt(ti, t);
  for (int l = 0; l < 4; ++l) dst[l] = ki[l] * mapBytes + ti[l];
}
// The bytes base[at[l]] as floats.
inline F4 F4::gatherBytes(const uint8_t* base, const int32_t* at) {
  return _mm_cvtepi32_ps(_mm_setr_epi32(base[at[0]], base[at[1]], base[at[2]], base[at[3]]));
}
// Bit ray[l] for every lane l set in `bits` (ray[l] < 64).
inline uint64_t F4::rayBits(const uint32_t* ray, unsigned bits) {
  uint64_t out = 0;
  for (int l = 0; l < 4; ++l)
    if ((bits >> l) & 1u) out |= uint64_t(1) << ray[l];
  return out;
}

// Four rays of eight floats each (origin, direction, tmin, tmax), transposed.
inline void loadRays(const float* p, F4* ox, F4* oy, F4* oz, F4* dx, F4* dy, F4* dz, F4* tmin, F4* tmax) {
  __m128 a0 = _mm_loadu_ps(p), a1 = _mm_loadu_ps(p + 8), a2 = _mm_loadu_ps(p + 16), a3 = _mm_loadu_ps(p + 24);
  _MM_TRANSPOSE4_PS(a0, a1, a2, a3);
  __m128 b0 = _mm_loadu_ps(p + 4), b1 = _mm_loadu_ps(p + 12), b2 = _mm_loadu_ps(p + 20), b3 = _mm_loadu_ps(p + 28);
  _MM_TRANSPOSE4_PS(b0, b1, b2, b3);
  *ox = a0;
  *oy = a1;
  *oz = a2;
  *dx = a3;
  *dy = b0;
  *dz = b1;
  *tmin = b2;
  *tmax = b3;
}

}  // namespace
}  // namespace vff::detail
