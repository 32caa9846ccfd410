// fast_lookup.h - the two hot steps of a nearest lookup in binary32, inlined, with a fallback.
//
// A query's cost is dominated by (1) finding the positional sample nearest to the entry point and
// (2) mapping the lookup direction to a texel of that sample's map. The reference functions
// (PositionSet::candidates, hemisphereToSquare + squareToTexel) are exact but slow: binary64
// arithmetic, atan2f, calls across the library. The functions below compute the same answers in a
// few dozen binary32 operations, and refuse (return false) whenever a rounding difference between
// the two could change the answer: when the query lies within a guard band of a grid line or of a
// texel edge. The caller then takes the reference path, so the fast and reference paths agree on
// every ray (tests/unit/test_fast_lookup.cpp compares them on millions of directions, including
// every kind of boundary).
#pragma once

#include <cmath>
#include <cstdint>
#include <vector>

#include "vff/direction.h"

namespace vff::detail {
// (Everything here has a copy per file: the SIMD kernels' files, compiled for AVX2 or AVX-512, call
// some of these functions and must share no function with code that runs on any x86-64 CPU.)
namespace {

// Guard bands: far wider than the binary32 error of the quantities they protect (a few ulps of
// values <= 1, scaled by the grid or map resolution), and narrow enough that the fallback runs
// for well under 1% of random rays.
inline constexpr float kGridGuard = 1e-4f;   // grid units, plus 1e-6 per unit of n: octa-hemi2 cells
inline constexpr float kTexelGuard = 1e-4f;  // texel units, plus 2e-6 per texel of map width

// The guard band of an octa-hemi2 grid of parameter n, in grid units (the query's projection is
// about n times a value <= 1 with a relative error of a few ulps: 2.5e-4 at n = 1024).
inline float gridGuard(uint32_t n) noexcept { return kGridGuard + 1e-6f * float(n); }
// The guard band of an M x M map, in texel units.
inline float texelGuard(uint32_t m) noexcept { return kTexelGuard + 2e-6f * float(m); }

// The SIMD kernel (query_group_kernel.h) scores an octa-hemi2 candidate, grid point g of the query's
// quadrant, as g.(|q.x|, |q.y|, |q.z|) / |g|, with the reciprocal square root approximated
// (relative error <= 1.5 * 2^-12: rsqrtps; AVX-512's rsqrt14ps, 2^-14, is within it) and refined
// by one Newton step; the reference scores it as
// unit(k).q in binary32, unit(k) being the binary64 position rounded to binary32. Bounds, in
// units of u = 2^-24 and |q|: the reference's products and sums 3 u, its rounded position u;
// the kernel's dot product 3 u, the refined reciprocal 1.5 (1.5 * 2^-12)^2 + 4 u (about 7.4 u),
// its last product u. Together under 16 u = 9.5e-7 |q|; kOctaScoreError allows twice that, per
// unit of |q.x| + |q.y| + |q.z| (>= |q|). A lead of the best score over the second by more
// than 2 kOctaScoreError (|q.x| + |q.y| + |q.z|) proves the reference picks the same sample;
// with a smaller lead the kernel scores that lane's candidates as the reference does
// (octaBestCandidate).
inline constexpr float kOctaScoreError = 2e-6f;

// atanUnit's constants (Cephes atanf), shared with the SIMD kernel's copy of it.
inline constexpr float kTanPi8 = 0.41421356f, kQuarterPiF = 0.78539816f;
inline constexpr float kAtanP[4] = {8.05374449538e-2f, -1.38776856032e-1f, 1.99777106478e-1f, -3.33329491539e-1f};

// The candidates of an octa-hemi2 query in cell (a0, b0) of its quadrant (PositionSet::candidates):
// grid vertices (a0 + da, b0 + db), those with |a| + |b| > n left out.
inline constexpr int8_t kOctaCandidates[8][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {-1, 1}, {1, -1}, {2, 0}, {0, 2}};

// For every cell (a0, b0) of an octa-hemi2 quadrant (index b0 * n + a0), the candidates that can
// be the nearest somewhere in the cell: bit c stands for kOctaCandidates[c]. The cell is a planar
// quadrilateral on the octahedron's face, and "candidate q is nearer than s, seen from the centre"
// is a half-plane there; q is left out when clipping the cell by its half-planes against every
// other candidate leaves nothing, each half-plane widened by a margin far above binary32
// rounding, so a binary32 comparison never picks a candidate left out. The quadrants and
// hemispheres are mirror images: one table serves all. Empty (no table: try all eight) for n > 128.
inline std::vector<uint8_t> octaCandidateMasks(uint32_t un) {
  if (un == 0 || un > 128) return {};
  const int n = int(un);
  std::vector<uint8_t> masks(size_t(n) * size_t(n), 0xFF);
  struct D3 {
    double x, y, z;
  };
  auto dotD = [](const D3& u, const D3& v) { return u.x * v.x + u.y * v.y + u.z * v.z; };
  for (int b0 = 0; b0 < n; ++b0)
    for (int a0 = 0; a0 < n; ++a0) {
      D3 cand[8];
      bool valid[8];
      for (int c = 0; c < 8; ++c) {
        const int a = a0 + kOctaCandidates[c][0], b = b0 + kOctaCandidates[c][1];
        const int aa = a < 0 ? -a : a, ab = b < 0 ? -b : b;
        valid[c] = aa + ab <= n;
        const double z = double(n - aa - ab), l = std::sqrt(double(a) * a + double(b) * b + z * z);
        cand[c] = {a / l, b / l, z / l};
      }
      const D3 cell[4] = {{double(a0), double(b0), double(n - a0 - b0)},
                          {double(a0 + 1), double(b0), double(n - a0 - b0 - 1)},
                          {double(a0 + 1), double(b0 + 1), double(n - a0 - b0 - 2)},
                          {double(a0), double(b0 + 1), double(n - a0 - b0 - 1)}};
      const double margin = 1e-5 * std::sqrt(3.0) * double(n);  // 1e-5 of the longest point of the face
      uint8_t mask = 0;
      for (int q = 0; q < 8; ++q) {
        if (!valid[q]) continue;
        std::vector<D3> poly(cell, cell + 4), next;
        for (int s = 0; s < 8 && !poly.empty(); ++s) {
          if (s == q || !valid[s]) continue;
          const D3 d{cand[q].x - cand[s].x, cand[q].y - cand[s].y, cand[q].z - cand[s].z};
          next.clear();
          for (size_t e = 0; e < poly.size(); ++e) {
            const D3& p1 = poly[e];
            const D3& p2 = poly[(e + 1) % poly.size()];
            const double f1 = dotD(d, p1) + margin, f2 = dotD(d, p2) + margin;
            if (f1 >= 0) next.push_back(p1);
            if ((f1 >= 0) != (f2 >= 0)) {
              const double t = f1 / (f1 - f2);
              next.push_back({p1.x + (p2.x - p1.x) * t, p1.y + (p2.y - p1.y) * t, p1.z + (p2.z - p1.z) * t});
            }
          }
          poly.swap(next);
        }
        if (!poly.empty()) mask = uint8_t(mask | (1u << q));
      }
      masks[size_t(b0) * size_t(n) + size_t(a0)] = mask;
    }
  return masks;
}

// For n <= kOctaCornerRowsMax: per row b0 of the quadrant's cells, bit a0 set where cell (a0, b0)
// of octaCandidateMasks(n) may need a candidate other than its four corners (kOctaCandidates 0-3);
// kOctaCornerRowsMax rows, zero past n. Empty for larger n (or no masks). The AVX-512 kernel
// looks a lane's row up in two registers instead of gathering the lane's mask: two of the face's
// cells (a0 + b0 < n) have such a bit for 10 <= n <= 32 (528 cells at n = 32), none below (the
// cells past the face, which no lane reaches, have theirs too).
inline constexpr uint32_t kOctaCornerRowsMax = 32;
inline std::vector<uint32_t> octaCornerRows(const std::vector<uint8_t>& masks, uint32_t n) {
  if (n == 0 || n > kOctaCornerRowsMax || masks.size() < size_t(n) * n) return {};
  std::vector<uint32_t> rows(kOctaCornerRowsMax, 0);
  for (uint32_t b0 = 0; b0 < n; ++b0)
    for (uint32_t a0 = 0; a0 < n; ++a0)
      if (masks[size_t(b0) * n + a0] & ~0x0Fu) rows[b0] |= uint32_t(1) << a0;
  return rows;
}

// The nearest of the octa-hemi2 candidates of cell (a0, b0) of q's quadrant (kOctaCandidates,
// those with |a| + |b| <= n) by binary32 dot products of q with the float table `unit4` (4 floats
// per sample: x, y, z and padding), ties to the smallest index, as FieldQuery does with the
// reference candidates: its index in *k and its grid point in the quadrant frame in (*a, *b).
// False when no candidate lies on the grid. `only`: the candidates to score (bit c for
// kOctaCandidates[c]); the cell's octaCandidateMasks entry gives the same answer as all eight.
inline bool octaBestCandidate(int32_t n, const float* unit4, float qx, float qy, float qz, int32_t a0, int32_t b0,
                              uint32_t* k, int32_t* a, int32_t* b, unsigned only = 0xFFu) noexcept {
  const int32_t h = qz >= 0 ? 0 : 1;
  const int32_t si = qx < 0 ? -1 : 1, sj = qy < 0 ? -1 : 1;
  const int32_t hemi = 2 * n * n + 2 * n + 1;
  float bestDot = -INFINITY;
  bool any = false;
  *k = 0;
  *a = a0;
  *b = b0;
  for (unsigned ci = 0; ci < 8; ++ci) {
    if (!((only >> ci) & 1u)) continue;
    const int32_t ca = a0 + kOctaCandidates[ci][0], cb = b0 + kOctaCandidates[ci][1];
    const int32_t aa = ca < 0 ? -ca : ca, ab = cb < 0 ? -cb : cb;
    if (aa + ab > n) continue;
    const int32_t i = si * ca, j = sj * cb;
    const int32_t hh = aa + ab == n ? 0 : h;  // an equator point is its hemisphere-0 copy
    // octaIndex: row j starts at (n + j)^2, less 2 j (j - 1) for j > 0; row j spans i = -w .. w.
    const int32_t t = n + j;
    const int32_t rowStart = j <= 0 ? t * t : t * t - 2 * j * (j - 1);
    const int32_t w = n - (j < 0 ? -j : j);
    const uint32_t ck = uint32_t(hh * hemi + rowStart + i + w);
    const float* u = unit4 + size_t(ck) * 4;
    const float d = u[0] * qx + u[1] * qy + u[2] * qz;
    if (!any || d > bestDot || (d == bestDot && ck < *k)) {
      bestDot = d;
      *k = ck;
      *a = ca;
      *b = cb;
      any = true;
    }
  }
  return any;
}

// The octa-hemi2 candidates of PositionSet::candidates (positions.cpp, octaCandidates) for the
// direction q (finite, non-zero, need not be unit), evaluated in binary32, then the nearest of
// them (octaBestCandidate). False when the projection of q lies within gridGuard(n) of a grid
// line, where the binary64 reference could choose another cell.
inline bool octaNearestFast(uint32_t un, const float* unit4, Vec3 q, uint32_t* out) noexcept {
  const int32_t n = int32_t(un);
  const float ax = std::fabs(q.x), ay = std::fabs(q.y), az = std::fabs(q.z);
  const float l1 = ax + ay + az;
  if (!(l1 > 0) || !(l1 < 3.0e38f)) return false;
  const float fn = float(n);
  const float pa = ax / l1 * fn, pb = ay / l1 * fn;
  const float fa = std::floor(pa), fb = std::floor(pb);
  // Near a grid line (or at the edge |i| + |j| = n, or at the clamp to n - 1) the reference,
  // which normalises in binary64 first, may land in the neighbouring cell.
  const float g = gridGuard(un);
  if (pa - fa < g || fa + 1.0f - pa < g || pb - fb < g || fb + 1.0f - pb < g)
    return false;
  const int32_t a0 = std::min(int32_t(fa), n - 1), b0 = std::min(int32_t(fb), n - 1);
  int32_t a, b;
  return octaBestCandidate(n, unit4, q.x, q.y, q.z, a0, b0, out, &a, &b);
}

// atan(t) for |t| <= 1 in binary32 (Cephes atanf: range reduction at tan(pi/8), degree-9
// polynomial; error about 2e-7).
inline float atanUnit(float t) noexcept {
  const float at = std::fabs(t);
  const bool big = at > kTanPi8;
  const float x = big ? (at - 1.0f) / (at + 1.0f) : at;
  const float y0 = big ? kQuarterPiF : 0.0f;
  const float z = x * x;
  const float p = (((kAtanP[0] * z + kAtanP[1]) * z + kAtanP[2]) * z + kAtanP[3]) * z * x + x;
  const float r = y0 + p;
  return t < 0 ? -r : r;
}

// hemisphereToSquare(scheme, local) without atan2f: the concentric map's angle from atanUnit,
// within about 1e-6 of the reference in square units. For kInterpolated's bilinear weights, where
// such a difference changes a weight by about 1e-6 of a texel; not for choosing a texel.
inline Vec2 hemisphereToSquareFast(DirectionScheme scheme, Vec3 local) noexcept {
  const float z = std::max(0.0f, local.z);
  float a, b;
  if (scheme == DirectionScheme::kHemiOctahedral) {
    const float inv = 1.0f / (std::fabs(local.x) + std::fabs(local.y) + z);
    const float x = local.x * inv, y = local.y * inv;
    a = x + y;
    b = x - y;
  } else {
    const float r = std::sqrt(std::max(0.0f, 1.0f - z));
    const float ax = std::fabs(local.x), ay = std::fabs(local.y);
    if (ax == 0 && ay == 0) return {r, 0.0f};  // as the reference, whose atan2(0, 0) is 0
    const float k = r * (4.0f / 3.14159265358979323846f);
    if (ax > ay) {
      a = local.x < 0 ? -r : r;
      const float s = atanUnit(local.y / local.x) * k;
      b = local.x < 0 ? -s : s;
    } else {
      b = local.y < 0 ? -r : r;
      const float s = atanUnit(local.x / local.y) * k;
      a = local.y < 0 ? -s : s;
    }
  }
  return {std::min(std::max(a, -1.0f), 1.0f), std::min(std::max(b, -1.0f), 1.0f)};
}

// The texel of an M x M map that holds the unit local direction `local` (z >= 0 side), as
// squareToTexel(hemisphereToSquare(scheme, local), M): without atan2f for the concentric map.
// False when the direction lies within the guard band of a texel edge or of an octant diagonal of
// the concentric map (where the reference's atan2f decides).
inline bool texelFast(DirectionScheme scheme, Vec3 local, uint32_t m, uint32_t* i, uint32_t* j) noexcept {
  if (scheme != DirectionScheme::kHemiOctahedral) {
    // Octant diagonals |x| = |y| (and the centre, x = y = 0): left to the reference.
    const float ax = std::fabs(local.x), ay = std::fabs(local.y);
    if (!(std::fabs(ax - ay) > 1e-5f * (ax + ay))) return false;
  }
  const Vec2 uv = hemisphereToSquareFast(scheme, local);
  const float fm = float(m);
  const float x = (uv.x + 1.0f) * 0.5f * fm, y = (uv.y + 1.0f) * 0.5f * fm;
  const float fx = std::floor(x), fy = std::floor(y);
  // Within the guard band of an inner texel edge (1 .. m - 1): refused. Near the map's outer
  // edges (0 and m) both paths clamp to the same texel: about 0.3% of random rays look up at
  // the edge of the map (their direction grazes the sample's hemisphere), which were all sent to
  // the reference before.
  const float g = texelGuard(m), top = fm - 1.0f;
  auto nearEdge = [g, top](float v, float fv) {
    return (v - fv < g && fv >= 1.0f && fv <= top) || (fv + 1.0f - v < g && fv + 1.0f <= top);
  };
  if (nearEdge(x, fx) || nearEdge(y, fy)) return false;
  *i = uint32_t(std::min(std::max(fx, 0.0f), fm - 1.0f));
  *j = uint32_t(std::min(std::max(fy, 0.0f), fm - 1.0f));
  return true;
}

}  // namespace
}  // namespace vff::detail
