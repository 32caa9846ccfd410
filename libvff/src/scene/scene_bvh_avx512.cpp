// Bvh4::collect's node step (scene_bvh.h) in AVX-512 lanes: sixteen rays of a node's list at a
// time, each ray's eight floats loaded whole and the sixteen transposed in registers into one
// vector per component, tested against the node's four boxes with the operations of hitNode4 in
// the same order (so the same answers, NaN included: min and max return their second operand for
// a NaN in SSE and AVX-512 alike), the indices of those that reach a child compressed onto its
// list. This file alone is compiled with -mavx512f -mavx512dq -mavx512vl -mavx512bw -mbmi2;
// scene_bvh.cpp calls it only on a CPU (and OS) with those. It calls no inline function of the
// baseline's and constructs no object of a type declared outside it.
#include "scene/scene_bvh.h"

#if defined(__AVX512F__) && defined(__AVX512DQ__) && defined(__AVX512VL__) && defined(__AVX512BW__) && defined(__BMI2__)
#include <immintrin.h>

namespace vff::detail {

namespace {

// The four registers' 4 x 4 blocks transposed, within each 128-bit lane.
inline void transpose4(__m512& a, __m512& b, __m512& c, __m512& d) {
  const __m512 t0 = _mm512_unpacklo_ps(a, b), t1 = _mm512_unpacklo_ps(c, d);
  const __m512 t2 = _mm512_unpackhi_ps(a, b), t3 = _mm512_unpackhi_ps(c, d);
  a = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(1, 0, 1, 0));
  b = _mm512_shuffle_ps(t0, t1, _MM_SHUFFLE(3, 2, 3, 2));
  c = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(1, 0, 1, 0));
  d = _mm512_shuffle_ps(t2, t3, _MM_SHUFFLE(3, 2, 3, 2));
}

}  // namespace

void collectNodeAvx512(const Node4& node, const float* rays, const uint32_t* in, uint32_t m, uint32_t* list,
                       size_t stride, uint32_t* count) noexcept {
  // After the loads and transposes, lo[k] holds component k of rays 0-3 | k + 4 of rays 0-3 |
  // k of rays 8-11 | k + 4 of rays 8-11 (128-bit lanes), and hi[k] the same of rays 4-7 and 12-15:
  // these pick component k, and k + 4, of the sixteen rays in order.
  const __m512i pickLow = _mm512_setr_epi32(0, 1, 2, 3, 16, 17, 18, 19, 8, 9, 10, 11, 24, 25, 26, 27);
  const __m512i pickHigh = _mm512_setr_epi32(4, 5, 6, 7, 20, 21, 22, 23, 12, 13, 14, 15, 28, 29, 30, 31);
  const __m512 zero = _mm512_setzero_ps();
  for (uint32_t i = 0; i < m; i += 16) {
    const uint32_t live = m - i < 16 ? m - i : 16;
    const __mmask16 lanes = __mmask16((1u << live) - 1);
    __m512 z[8];
    for (uint32_t j = 0; j < 8; ++j) {
      // (past the list's end, its first ray again: those lanes are masked off)
      const uint32_t a = in[i + (j < live ? j : 0)], b = in[i + (j + 8 < live ? j + 8 : 0)];
      z[j] = _mm512_insertf32x8(_mm512_castps256_ps512(_mm256_loadu_ps(rays + 8 * size_t(a))),
                                _mm256_loadu_ps(rays + 8 * size_t(b)), 1);
    }
    transpose4(z[0], z[1], z[2], z[3]);
    transpose4(z[4], z[5], z[6], z[7]);
    const __m512 o[3] = {_mm512_permutex2var_ps(z[0], pickLow, z[4]), _mm512_permutex2var_ps(z[1], pickLow, z[5]),
                         _mm512_permutex2var_ps(z[2], pickLow, z[6])};
    const __m512 inv[3] = {_mm512_permutex2var_ps(z[3], pickLow, z[7]), _mm512_permutex2var_ps(z[0], pickHigh, z[4]),
                           _mm512_permutex2var_ps(z[1], pickHigh, z[5])};
    const __m512 tmax = _mm512_permutex2var_ps(z[2], pickHigh, z[6]);
    const __m512i idx = _mm512_maskz_loadu_epi32(lanes, in + i);
    for (uint32_t c = 0; c < 4; ++c) {
      if (!(node.valid & (1u << c))) continue;
      __m512 tn = zero, tf = tmax;
      for (int a = 0; a < 3; ++a) {
        const __m512 t1 = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(node.lo[a][c]), o[a]), inv[a]);
        const __m512 t2 = _mm512_mul_ps(_mm512_sub_ps(_mm512_set1_ps(node.hi[a][c]), o[a]), inv[a]);
        tn = _mm512_max_ps(tn, _mm512_min_ps(t1, t2));
        tf = _mm512_min_ps(tf, _mm512_max_ps(t1, t2));
      }
      const __mmask16 reach = _mm512_mask_cmp_ps_mask(lanes, tn, tf, _CMP_LE_OQ);
      // A whole vector stored, the lanes past the reached ones included (the list has room).
      _mm512_storeu_si512(list + c * stride + count[c], _mm512_maskz_compress_epi32(reach, idx));
      count[c] += uint32_t(__builtin_popcount(unsigned(reach)));
    }
  }
}

}  // namespace vff::detail
#endif
