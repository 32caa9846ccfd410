// The query's fast paths against their references: the binary32 octa-hemi2 nearest sample and the
// atan2-free texel mapping (libvff/src/query/fast_lookup.h), and the group kernel behind the batch
// functions (libvff/src/query/batch/query_group_kernel.h), which must answer every ray exactly as a lookup
// written here from the reference functions does.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#if defined(__SSE__) || defined(__x86_64__)
#include <xmmintrin.h>
#endif
#include <limits>
#include <random>
#include <vector>

#include "query/fast_lookup.h"  // private: the fast paths against their references
#include "query/batch/query_group.h"  // private: choose the group kernel under test
#include "common/synthetic_field.h"
#include "vff/vff.h"

namespace vff {
namespace {

float dot3(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// The float positions of every sample, as FieldQuery keeps them.
std::vector<Vec3> unitTable(const PositionSet& ps) {
  std::vector<Vec3> unit(ps.count());
  for (uint32_t k = 0; k < ps.count(); ++k) unit[k] = ps.position(k);
  return unit;
}

// The same positions in the padded layout the fast paths read (GroupTables::unit4).
std::vector<float> unit4Table(const std::vector<Vec3>& unit) {
  std::vector<float> unit4;
  for (const Vec3& u : unit) unit4.insert(unit4.end(), {u.x, u.y, u.z, 0.0f});
  return unit4;
}

// A random point of cell (a0, b0) of the octa-hemi2 grid n's quadrant, as a direction (not unit)
// in the octant that bits 0-2 of s choose; false past the face (a + b > n).
bool cellDirection(uint32_t n, uint32_t a0, uint32_t b0, int s, std::mt19937* rng, Vec3* d) {
  std::uniform_real_distribution<float> u01(0.0f, 1.0f);
  const float a = float(a0) + u01(*rng), b = float(b0) + u01(*rng);
  if (a + b > float(n)) return false;
  *d = {(s & 1) ? -a : a, (s & 2) ? -b : b, ((s & 4) ? -1.0f : 1.0f) * (float(n) - a - b)};
  return true;
}

// FieldQuery's reference choice: the reference candidates, binary32 dot products with the float
// positions, ties to the smallest index.
uint32_t referenceNearest(const PositionSet& ps, const std::vector<Vec3>& unit, Vec3 d) {
  uint32_t c[PositionSet::kMaxCandidates];
  const uint32_t n = ps.candidates(d, c);
  uint32_t best = c[0];
  float bestDot = dot3(unit[best], d);
  for (uint32_t i = 1; i < n; ++i) {
    const float v = dot3(unit[c[i]], d);
    if (v > bestDot || (v == bestDot && c[i] < best)) {
      bestDot = v;
      best = c[i];
    }
  }
  return best;
}

// Random unit directions, and directions on the features where the fast paths must refuse:
// axes, octant diagonals, the equator, grid lines of the octahedral projection.
std::vector<Vec3> testDirections(uint32_t gridN, size_t random) {
  std::mt19937 rng(7);
  std::normal_distribution<float> g;
  std::vector<Vec3> out;
  for (size_t r = 0; r < random; ++r) out.push_back({g(rng), g(rng), g(rng)});
  for (float x : {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f})
    for (float y : {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f})
      for (float z : {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f})
        if (x != 0 || y != 0 || z != 0) out.push_back({x, y, z});
  std::uniform_int_distribution<uint32_t> cell(0, gridN);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  for (int r = 0; r < 20000; ++r) {
    // On a grid line a = integer (or b), or a hair away from it, in every octant.
    const float a = float(cell(rng)) + (r % 3 == 0 ? 0.0f : (r % 3 == 1 ? 1e-6f : -1e-6f));
    const float b = u(rng) * (float(gridN) - a);
    const float c = float(gridN) - a - b;
    const float sx = (r & 8) ? -1.0f : 1.0f, sy = (r & 16) ? -1.0f : 1.0f, sz = (r & 32) ? -1.0f : 1.0f;
    if (r & 64)
      out.push_back({sx * b, sy * a, sz * std::max(c, 0.0f)});
    else
      out.push_back({sx * a, sy * b, sz * std::max(c, 0.0f)});
  }
  return out;
}

#if defined(__SSE__) || defined(__x86_64__)
// The group kernel's candidate score, one lane: g.q / |g| for the integer grid vector g, with the
// hardware's approximate reciprocal square root and one Newton step, in the kernel's order.
float kernelScore(float gi, float gj, float gk, Vec3 q) {
  const float len2 = (gi * gi + gj * gj) + gk * gk;
  const float y0 = _mm_cvtss_f32(_mm_rsqrt_ss(_mm_set_ss(len2)));
  const float y = y0 * (1.5f - 0.5f * len2 * y0 * y0);
  return ((gi * q.x + gj * q.y) + gk * q.z) * y;
}

// fast_lookup.h's bound: the kernel's score of a candidate is within kOctaScoreError (|q.x| +
// |q.y| + |q.z|) of the reference's, unit(k).q in binary32, for queries of length 0.5 to 2.
TEST(FastLookup, KernelScoresAreWithinTheBoundOfTheReference) {
  std::mt19937 rng(11);
  std::normal_distribution<float> g;
  std::uniform_real_distribution<float> u(0.5f, 2.0f);
  for (uint32_t n : {1u, 5u, 32u, 128u, 1024u}) {
    auto ps = PositionSet::create(PositionScheme::kOctaHemi2, n);
    ASSERT_TRUE(ps);
    float worst = 0;
    for (int r = 0; r < 100000; ++r) {
      Vec3 q{g(rng), g(rng), g(rng)};
      const float l = std::sqrt(dot3(q, q)), s = u(rng) / l;
      if (!(l > 0)) continue;
      q = {q.x * s, q.y * s, q.z * s};
      const float l1 = std::fabs(q.x) + std::fabs(q.y) + std::fabs(q.z);
      uint32_t cand[PositionSet::kMaxCandidates];
      const uint32_t nc = ps->candidates(q, cand);
      for (uint32_t c = 0; c < nc; ++c) {
        const Vec3 p = ps->position(cand[c]);
        // The sample's grid vector: its position scaled to |i| + |j| + |k| = n.
        const float pl1 = std::fabs(p.x) + std::fabs(p.y) + std::fabs(p.z), f = float(n) / pl1;
        const float gi = std::round(p.x * f), gj = std::round(p.y * f), gk = std::round(p.z * f);
        ASSERT_EQ(std::fabs(gi) + std::fabs(gj) + std::fabs(gk), float(n));
        const float err = std::fabs(kernelScore(gi, gj, gk, q) - dot3(p, q)) / l1;
        worst = std::max(worst, err);
      }
    }
    std::printf("n %u: worst score error %.3g per unit of |q|_1 (bound %.3g)\n", n, double(worst),
                double(detail::kOctaScoreError));
    EXPECT_LT(worst, detail::kOctaScoreError) << "n " << n;
  }
}
#endif

TEST(FastLookup, OctaNearestEqualsTheReferenceWhereverItAnswers) {
  for (uint32_t n : {1u, 2u, 3u, 8u, 32u, 64u, 255u, 1024u}) {  // 1024: the largest n
    auto ps = PositionSet::create(PositionScheme::kOctaHemi2, n);
    ASSERT_TRUE(ps);
    const std::vector<Vec3> unit = unitTable(*ps);
    const std::vector<float> unit4 = unit4Table(unit);
    const std::vector<Vec3> dirs = testDirections(n, 200000);
    size_t answered = 0, randomRefused = 0;
    for (size_t r = 0; r < dirs.size(); ++r) {
      uint32_t fast = 0;
      if (!detail::octaNearestFast(n, unit4.data(), dirs[r], &fast)) {
        randomRefused += r < 200000;
        continue;
      }
      ++answered;
      ASSERT_EQ(fast, referenceNearest(*ps, unit, dirs[r]))
          << "n " << n << " direction " << dirs[r].x << " " << dirs[r].y << " " << dirs[r].z;
    }
    // The guard band is narrow: random directions almost never fall back.
    EXPECT_LT(randomRefused, 200000 / 100) << "n " << n;
    EXPECT_GT(answered, 190000u);
  }
}

TEST(FastLookup, CandidateMasksKeepTheNearest) {
  for (uint32_t n : {1u, 2u, 5u, 32u, 64u, 128u}) {
    auto ps = PositionSet::create(PositionScheme::kOctaHemi2, n);
    ASSERT_TRUE(ps);
    const std::vector<Vec3> unit = unitTable(*ps);
    const std::vector<uint8_t> masks = detail::octaCandidateMasks(n);
    ASSERT_EQ(masks.size(), size_t(n) * n);
    size_t kept = 0;
    for (uint8_t m : masks) kept += size_t(__builtin_popcount(m));
    const std::vector<float> unit4 = unit4Table(unit);
    // Random directions, and some in every cell of the quadrant.
    std::vector<Vec3> dirs = testDirections(n, 100000);
    std::mt19937 rng(n);
    for (uint32_t b0 = 0; b0 < n; ++b0)
      for (uint32_t a0 = 0; a0 + b0 < n; ++a0) {
        const int perCell = std::max(40, int(400000 / (n * n)));
        for (int r = 0; r < perCell; ++r)
          if (Vec3 d; cellDirection(n, a0, b0, r, &rng, &d)) dirs.push_back(d);
      }
    for (const Vec3& d : dirs) {
      // The cell of d, as octaNearestFast computes it (directions on a grid line are skipped:
      // there the fast path defers to the reference).
      const float ax = std::fabs(d.x), ay = std::fabs(d.y), l1 = ax + ay + std::fabs(d.z);
      const float pa = ax / l1 * float(n), pb = ay / l1 * float(n);
      const int a0 = std::min(int(pa), int(n) - 1), b0 = std::min(int(pb), int(n) - 1);
      const float gg = detail::gridGuard(n);
      if (pa - std::floor(pa) < gg || std::ceil(pa) - pa < gg || pb - std::floor(pb) < gg || std::ceil(pb) - pb < gg)
        continue;
      const uint32_t ref = referenceNearest(*ps, unit, d);
      // The candidate the reference chose, as an offset from the cell in the quadrant frame.
      const Vec3 u = ps->position(ref);
      const float ul1 = std::fabs(u.x) + std::fabs(u.y) + std::fabs(u.z);
      const int ra = int(std::lround(std::fabs(u.x) / ul1 * float(n))), rb = int(std::lround(std::fabs(u.y) / ul1 * float(n)));
      // Mirror candidates (offset -1) sit across the quadrant's edge: their |a| is the offset's size.
      bool found = false;
      for (int c = 0; c < 8; ++c) {
        if (!((masks[size_t(b0) * n + size_t(a0)] >> c) & 1)) continue;
        const int ca = a0 + detail::kOctaCandidates[c][0], cb = b0 + detail::kOctaCandidates[c][1];
        found = found || (std::abs(ca) == ra && std::abs(cb) == rb);
      }
      ASSERT_TRUE(found) << "n " << n << " cell " << a0 << " " << b0 << " direction " << d.x << " " << d.y << " " << d.z;
      // The binary32 scores of the cell's mask pick what those of all eight candidates pick.
      uint32_t kAll = 0, kMask = 0;
      int32_t aAll = 0, bAll = 0, aMask = 0, bMask = 0;
      const bool all = detail::octaBestCandidate(int32_t(n), unit4.data(), d.x, d.y, d.z, a0, b0, &kAll, &aAll, &bAll);
      const bool mask = detail::octaBestCandidate(int32_t(n), unit4.data(), d.x, d.y, d.z, a0, b0, &kMask, &aMask,
                                                  &bMask, masks[size_t(b0) * n + size_t(a0)]);
      ASSERT_EQ(all, mask) << "n " << n << " cell " << a0 << " " << b0;
      ASSERT_EQ(kAll, kMask) << "n " << n << " cell " << a0 << " " << b0;
    }
    // Away from the poles of the octahedron a cell needs its four corners only.
    EXPECT_LT(kept, size_t(n) * n * 5) << "n " << n;
  }
}

TEST(FastLookup, CornerRowsMarkTheCellsThatNeedMoreThanTheirCorners) {
  for (uint32_t n = 1; n <= 40; ++n) {
    const std::vector<uint8_t> masks = detail::octaCandidateMasks(n);
    const std::vector<uint32_t> rows = detail::octaCornerRows(masks, n);
    if (n > detail::kOctaCornerRowsMax) {
      EXPECT_TRUE(rows.empty()) << "n " << n;
      continue;
    }
    ASSERT_EQ(rows.size(), size_t(detail::kOctaCornerRowsMax)) << "n " << n;
    size_t marked = 0;
    for (uint32_t b0 = 0; b0 < detail::kOctaCornerRowsMax; ++b0)
      for (uint32_t a0 = 0; a0 < 32; ++a0) {
        const bool bit = (rows[b0] >> a0) & 1u;
        const bool more = a0 < n && b0 < n && (masks[size_t(b0) * n + a0] & ~0x0Fu) != 0;
        ASSERT_EQ(bit, more) << "n " << n << " cell " << a0 << " " << b0;
        marked += bit && a0 + b0 < n;
      }
    // Of the face's cells, (n - 2, 0) and (0, n - 2) from n = 10 on, none below.
    EXPECT_EQ(marked, size_t(n >= 10 ? 2 : 0)) << "n " << n << ": cells of the face";
  }
}

TEST(FastLookup, TexelEqualsTheReferenceWhereverItAnswers) {
  std::mt19937 rng(3);
  std::normal_distribution<float> g;
  std::vector<Vec3> dirs;
  for (int r = 0; r < 300000; ++r) dirs.push_back({g(rng), g(rng), std::fabs(g(rng))});
  const size_t random = dirs.size();
  for (float x : {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f})
    for (float y : {-1.0f, -0.5f, 0.0f, 0.5f, 1.0f})
      for (float z : {-0.1f, 0.0f, 0.5f, 1.0f}) dirs.push_back({x, y, z});
  for (int r = 0; r < 20000; ++r) {  // near the octant diagonals and the horizon
    const float x = g(rng), e = (r % 2 ? 1e-7f : 0.0f) * x;
    dirs.push_back({x, ((r & 2) ? -x : x) + e, (r & 4) ? 0.0f : std::fabs(g(rng))});
  }
  for (Vec3& d : dirs) {
    const float l = std::sqrt(dot3(d, d));
    if (l > 0) d = {d.x / l, d.y / l, d.z / l};
  }
  for (DirectionScheme scheme : {DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral}) {
    for (uint32_t m : {1u, 2u, 4u, 16u, 64u, 255u, 1024u}) {
      size_t randomRefused = 0;
      for (size_t r = 0; r < dirs.size(); ++r) {
        uint32_t fi = 0, fj = 0, ri = 0, rj = 0;
        if (!detail::texelFast(scheme, dirs[r], m, &fi, &fj)) {
          randomRefused += r < random;
          continue;
        }
        squareToTexel(hemisphereToSquare(scheme, dirs[r]), m, &ri, &rj);
        ASSERT_EQ(fi, ri) << "m " << m << " direction " << dirs[r].x << " " << dirs[r].y << " " << dirs[r].z;
        ASSERT_EQ(fj, rj) << "m " << m << " direction " << dirs[r].x << " " << dirs[r].y << " " << dirs[r].z;
      }
      EXPECT_LT(randomRefused, random * (m >= 1024 ? 3 : 1) / 100) << "m " << m;
    }
  }
}

TEST(FastLookup, SquareCoordinatesAreWithinAMillionthOfTheReference) {
  std::mt19937 rng(5);
  std::normal_distribution<float> g;
  std::vector<Vec3> dirs = {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}, {1, 1, 0}, {-1, 1, 1}, {0, 0, -1}};
  for (int r = 0; r < 300000; ++r) dirs.push_back({g(rng), g(rng), std::fabs(g(rng))});
  for (Vec3& d : dirs) {
    const float l = std::sqrt(dot3(d, d));
    d = {d.x / l, d.y / l, d.z / l};
  }
  for (DirectionScheme scheme : {DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral}) {
    float worst = 0;
    for (const Vec3& d : dirs) {
      const Vec2 f = detail::hemisphereToSquareFast(scheme, d), r = hemisphereToSquare(scheme, d);
      worst = std::max({worst, std::fabs(f.x - r.x), std::fabs(f.y - r.y)});
    }
    EXPECT_LT(worst, 1e-6f) << "scheme " << int(scheme);
  }
}

// ---- The batch functions (group kernel) against a lookup written from the reference functions --

struct RefHit {
  bool hit = false;
  float t = 0;
};

// spec/geometry.md section 7 for an unorm8-diameter field, from the public reference functions.
RefHit referenceLookup(const FieldDesc& f, const std::vector<Vec3>& unit, const PositionSet& ps,
                       const std::vector<uint8_t>& dist, const Ray& ray, float biasR) {
  const float len = std::sqrt(dot3(ray.direction, ray.direction));
  if (!(len > 0) || !std::isfinite(len)) return {};
  const float il = 1.0f / len;
  const Vec3 w{ray.direction.x * il, ray.direction.y * il, ray.direction.z * il};
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float r = f.sphere.radius;
  const Vec3 delta{ray.origin.x - c.x, ray.origin.y - c.y, ray.origin.z - c.z};
  const float beta = dot3(delta, w), gamma = dot3(delta, delta) - r * r, disc = beta * beta - gamma;
  if (!(disc >= 0)) return {};
  const float sq = std::sqrt(disc), t1 = -beta + sq;
  if (t1 < 0) return {};
  const bool inside = gamma <= 0;
  const float t0 = inside ? t1 : std::max(-beta - sq, 0.0f);
  float lo = ray.tmin * len;
  const float hi = ray.tmax * len;
  if (inside) lo = std::max(lo, biasR);
  if (!inside && t0 > hi) return {};
  const float ir = 1.0f / r;
  const Vec3 eu{(ray.origin.x + w.x * t0 - c.x) * ir, (ray.origin.y + w.y * t0 - c.y) * ir,
                (ray.origin.z + w.z * t0 - c.z) * ir};
  const Vec3 v = inside ? Vec3{-w.x, -w.y, -w.z} : w;
  const uint32_t k = referenceNearest(ps, unit, eu);
  uint32_t i = 0, j = 0;
  squareToTexel(hemisphereToSquare(f.directionScheme, toLocal(ps.frame(k), v)), f.mapResolution, &i, &j);
  const uint32_t code = dist[size_t(k) * f.mapResolution * f.mapResolution + size_t(j) * f.mapResolution + i];
  if (code == 255) return {};
  const float d = float(code) * quantizationStep(f.distanceEncoding, r, 1.0f);  // (the query's scale)
  const float t = inside ? t0 - d : t0 + d;
  if (t < lo || t > hi) return {};
  return {true, t / len};
}

std::vector<Ray> testRays(const FieldDesc& f, size_t count, uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g;
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float r = f.sphere.radius;
  std::vector<Ray> rays;
  for (size_t n = 0; n < count; ++n) {
    Vec3 o{g(rng), g(rng), g(rng)};
    const float ol = std::sqrt(dot3(o, o)) + 1e-12f, dist = r * 3.0f * u(rng);  // inside and outside
    o = {c.x + o.x / ol * dist, c.y + o.y / ol * dist, c.z + o.z / ol * dist};
    Ray ray{o, {g(rng), g(rng), g(rng)}};
    if (n % 3 == 0) {  // aimed at the sphere, with a scaled direction
      const Vec3 target{c.x + r * 0.9f * g(rng) / 3, c.y + r * 0.9f * g(rng) / 3, c.z + r * 0.9f * g(rng) / 3};
      ray.direction = {(target.x - o.x) * 0.37f, (target.y - o.y) * 0.37f, (target.z - o.z) * 0.37f};
    }
    if (n % 5 == 1) ray.tmax = r * 2.0f * u(rng);
    if (n % 7 == 2) ray.tmin = r * 0.5f * u(rng);
    rays.push_back(ray);
  }
  // Degenerate rays: zero, infinite and NaN directions, an infinite origin, a tangent ray.
  const float inf = std::numeric_limits<float>::infinity(), nan = std::numeric_limits<float>::quiet_NaN();
  rays.push_back({c, {0, 0, 0}});
  rays.push_back({c, {inf, 0, 0}});
  rays.push_back({c, {nan, 1, 0}});
  rays.push_back({{inf, 0, 0}, {-1, 0, 0}});
  rays.push_back({{c.x - 3 * r, c.y + r, c.z}, {1, 0, 0}});
  rays.push_back({{c.x - 3 * r, c.y, c.z}, {1, 0, 0}, 0.0f, 0.0f});
  return rays;
}

// Rays whose entry points lie on, or within a few millionths of, the bisector of the two nearest
// samples: where the group kernel's scores (fast_lookup.h, kOctaScoreError) cannot tell the two
// apart and must leave the choice to the reference. Aimed at the centre from outside.
std::vector<Ray> tieRays(const FieldDesc& f, const PositionSet& ps, const std::vector<Vec3>& unit, size_t count,
                         uint32_t seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<float> g;
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float r = f.sphere.radius;
  static constexpr float kOffsets[] = {0.0f, 1e-7f, -1e-7f, 1e-6f, -1e-6f, 3e-6f, -3e-6f, 1e-5f, -1e-5f};
  std::vector<Ray> rays;
  while (rays.size() < count) {
    Vec3 e{g(rng), g(rng), g(rng)};
    const float el = std::sqrt(dot3(e, e));
    if (!(el > 0)) continue;
    e = {e.x / el, e.y / el, e.z / el};
    // The best and second best of the reference candidates.
    uint32_t cand[PositionSet::kMaxCandidates];
    const uint32_t nc = ps.candidates(e, cand);
    if (nc < 2) continue;
    const uint32_t k1 = referenceNearest(ps, unit, e);
    uint32_t k2 = k1;
    float second = -2;
    for (uint32_t i = 0; i < nc; ++i) {
      const float v = dot3(unit[cand[i]], e);
      if (cand[i] != k1 && v > second) {
        second = v;
        k2 = cand[i];
      }
    }
    const Vec3 u1 = unit[k1], u2 = unit[k2];
    for (float off : kOffsets) {
      Vec3 m{u1.x + u2.x + off * (u1.x - u2.x), u1.y + u2.y + off * (u1.y - u2.y), u1.z + u2.z + off * (u1.z - u2.z)};
      const float ml = std::sqrt(dot3(m, m));
      m = {m.x / ml, m.y / ml, m.z / ml};
      rays.push_back({{c.x + 1.5f * r * m.x, c.y + 1.5f * r * m.y, c.z + 1.5f * r * m.z}, {-m.x, -m.y, -m.z}});
    }
  }
  return rays;
}

// Rays aimed at the centre whose entry points lie in the octa-hemi2 cells that may need a
// candidate other than their four corners (octaCandidateMasks), in every quadrant and hemisphere:
// the AVX-512 kernel reads the masks for these lanes (octaCornerRows), and the corners alone for
// the others. These rays run the masks' path. (At n <= 32 the extra candidates seem to enter the
// masks through their safety margin alone: no ray sampled in those cells had one as its nearest,
// so answers do not tell the two paths apart; the table itself is checked above.)
std::vector<Ray> cornerCellRays(const FieldDesc& f, uint32_t n, uint32_t seed) {
  const std::vector<uint8_t> masks = detail::octaCandidateMasks(n);
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float r = f.sphere.radius;
  std::mt19937 rng(seed);
  std::vector<Ray> rays;
  for (uint32_t b0 = 0; b0 < n && !masks.empty(); ++b0)
    for (uint32_t a0 = 0; a0 + b0 < n; ++a0) {
      if (!(masks[size_t(b0) * n + a0] & ~0x0Fu)) continue;
      for (int s = 0; s < 400; ++s) {
        Vec3 e;
        if (!cellDirection(n, a0, b0, s, &rng, &e)) continue;
        const float el = std::sqrt(dot3(e, e));
        e = {e.x / el, e.y / el, e.z / el};
        rays.push_back({{c.x + 1.5f * r * e.x, c.y + 1.5f * r * e.y, c.z + 1.5f * r * e.z}, {-e.x, -e.y, -e.z}});
      }
    }
  return rays;
}

// `rays` spread out, every `every`-th of count rays, the others leaving the sphere behind them
// (origin outside, pointing away): groups where a ray or two reach the sphere, whose lookups wait
// in the batch's queue over many groups (and fill its ring of groups in flight).
std::vector<Ray> sparseRays(const FieldDesc& f, const std::vector<Ray>& rays, size_t every, size_t count) {
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float r = f.sphere.radius;
  std::vector<Ray> out;
  for (size_t n = 0; n < count; ++n) {
    if (n % every == 0) {
      out.push_back(rays[(n / every) % rays.size()]);
    } else {
      const Vec3 d{std::cos(float(n)), std::sin(float(n)), 0.5f};
      out.push_back({{c.x + 2 * r * d.x, c.y + 2 * r * d.y, c.z + 2 * r * d.z}, d});
    }
  }
  return out;
}

// Restores the default kernel when a test ends, even a failed one.
struct KernelScope {
  explicit KernelScope(detail::KernelChoice c) { detail::forceGroupKernel(c); }
  ~KernelScope() { detail::forceGroupKernel(detail::KernelChoice::kAuto); }
};

// Every kernel this CPU can run: the widest, AVX-512 and AVX2 (each where present), SSE2, and none
// (per-ray prepare).
void checkBatches(detail::KernelChoice choice);

TEST(FastLookup, BatchesAnswerLikeTheReferenceLookup) {
  const KernelScope scope(detail::KernelChoice::kAuto);
  std::printf("group kernel: %s\n", detail::groupKernelName());
  checkBatches(detail::KernelChoice::kAuto);
}

TEST(FastLookup, BatchesAnswerLikeTheReferenceLookupWithAvx512Lanes) {
  if (!detail::groupKernelRuns(detail::KernelChoice::kAvx512))
    GTEST_SKIP() << "this build or CPU has no AVX-512 kernel (AVX-512 F, DQ, VL and BW)";
  const KernelScope scope(detail::KernelChoice::kAvx512);
  EXPECT_STREQ(detail::groupKernelName(), "avx512");
  checkBatches(detail::KernelChoice::kAvx512);
}

TEST(FastLookup, BatchesAnswerLikeTheReferenceLookupWithAvx2Lanes) {
  if (!detail::groupKernelRuns(detail::KernelChoice::kAvx2)) GTEST_SKIP() << "this build or CPU has no AVX2 kernel";
  const KernelScope scope(detail::KernelChoice::kAvx2);
  EXPECT_STREQ(detail::groupKernelName(), "avx2");
  checkBatches(detail::KernelChoice::kAvx2);
}

TEST(FastLookup, BatchesAnswerLikeTheReferenceLookupWithSse2Lanes) {
  const KernelScope scope(detail::KernelChoice::kSse2);
  std::printf("group kernel: %s\n", detail::groupKernelName());
  checkBatches(detail::KernelChoice::kSse2);
}

TEST(FastLookup, BatchesAnswerLikeTheReferenceLookupWithoutGroupKernel) {
  const KernelScope scope(detail::KernelChoice::kNone);
  EXPECT_STREQ(detail::groupKernelName(), "scalar");
  checkBatches(detail::KernelChoice::kNone);
}

void checkBatches(detail::KernelChoice) {
  // n = 200: no candidate masks (octaCandidateMasks stops at 128); smaller maps there.
  for (uint32_t n : {1u, 5u, 32u, 200u}) {
    for (DirectionScheme scheme : {DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral}) {
      FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kNone, n, n > 32 ? 4 : 16);
      f.directionScheme = scheme;
      const std::vector<uint8_t> dist = test::syntheticDistance(f);
      auto q = FieldQuery::fromMaps(f, dist);
      ASSERT_TRUE(q);
      auto ps = PositionSet::fromField(f);
      const std::vector<Vec3> unit = unitTable(*ps);
      std::vector<Ray> rays = testRays(f, 20000, n);
      if (n > 1) {
        const std::vector<Ray> ties = tieRays(f, *ps, unit, 9000, n + 7);
        rays.insert(rays.end(), ties.begin(), ties.end());
      }
      const std::vector<Ray> corner = cornerCellRays(f, n, n + 11);
      if (n == 32) {
        EXPECT_GT(corner.size(), size_t(500)) << "n 32: two cells need more than their corners";
      }
      rays.insert(rays.end(), corner.begin(), corner.end());
      const std::vector<Ray> sparse = sparseRays(f, rays, 37, 20000);
      rays.insert(rays.end(), sparse.begin(), sparse.end());
      QueryOptions o;
      o.intraBias = 0.05f;
      const float biasR = o.intraBias * f.sphere.radius;
      // Batch sizes that leave partial quads and partial groups.
      for (size_t batch : {size_t(1), size_t(3), size_t(63), size_t(65), rays.size()}) {
        std::vector<QueryHit> hits(rays.size());
        std::vector<uint8_t> occ(rays.size());
        std::vector<LookupSite> where(rays.size());
        for (size_t b = 0; b < rays.size(); b += batch) {
          const size_t e = std::min(rays.size(), b + batch);
          q->intersect(std::span<const Ray>(rays).subspan(b, e - b), std::span<QueryHit>(hits).subspan(b, e - b), o);
          q->occluded(std::span<const Ray>(rays).subspan(b, e - b), std::span<uint8_t>(occ).subspan(b, e - b), o);
          q->sites(std::span<const Ray>(rays).subspan(b, e - b), std::span<LookupSite>(where).subspan(b, e - b), o);
        }
        size_t hitCount = 0;
        for (size_t r = 0; r < rays.size(); ++r) {
          const RefHit ref = referenceLookup(f, unit, *ps, dist, rays[r], biasR);
          ASSERT_EQ(hits[r].hit, ref.hit) << "n " << n << " batch " << batch << " ray " << r;
          ASSERT_EQ(occ[r] != 0, ref.hit) << "n " << n << " batch " << batch << " ray " << r;
          if (ref.hit) {
            ASSERT_EQ(hits[r].t, ref.t) << "n " << n << " batch " << batch << " ray " << r;
            ++hitCount;
          }
          const QueryHit single = q->intersect(rays[r], o);
          ASSERT_EQ(single.hit, ref.hit);
          const LookupSite site = q->site(rays[r], o);  // the reference prepare()
          ASSERT_EQ(where[r].valid, site.valid) << "n " << n << " batch " << batch << " ray " << r;
          ASSERT_TRUE(where[r].sample == site.sample && where[r].i == site.i && where[r].j == site.j)
              << "n " << n << " batch " << batch << " ray " << r;
          if (ref.hit) {
            ASSERT_EQ(single.t, ref.t);
          }
        }
        EXPECT_GT(hitCount, rays.size() / 10);  // the test exercises hits, not only misses
      }
      // Interpolated batches (the group kernel finds the nearest samples; the rays that reach the
      // sphere fill blocks of 16 across its groups) against one-ray calls, on the field and on the
      // same field with a normal field; calls that end within a group and within a block.
      QueryOptions oi = o;
      oi.reconstruction = Reconstruction::kInterpolated;
      FieldDesc fn = f;
      fn.normalEncoding = NormalEncoding::kOctSnorm16;
      const std::vector<uint8_t> normals = test::syntheticNormals(fn, dist);
      auto qn = FieldQuery::fromMaps(fn, dist, normals);
      ASSERT_TRUE(qn);
      size_t normalHits = 0;
      for (const FieldQuery* field : {&*q, &*qn}) {
        std::vector<float> vis(rays.size());
        std::vector<QueryHit> hits(rays.size());
        field->visibility(rays, vis, oi);
        field->intersect(rays, hits, oi);
        for (size_t batch : {size_t(7), size_t(65), size_t(200)}) {
          std::vector<float> part(rays.size());
          for (size_t b = 0; b < rays.size(); b += batch) {
            const size_t e = std::min(rays.size(), b + batch);
            field->visibility(std::span<const Ray>(rays).subspan(b, e - b), std::span<float>(part).subspan(b, e - b), oi);
          }
          for (size_t r = 0; r < rays.size(); ++r)
            ASSERT_EQ(part[r], vis[r]) << "n " << n << " batch " << batch << " ray " << r;
        }
        for (size_t r = 0; r < rays.size(); ++r) {
          ASSERT_EQ(vis[r], field->visibility(rays[r], oi)) << "n " << n << " ray " << r;
          const QueryHit single = field->intersect(rays[r], oi);
          ASSERT_EQ(hits[r].hit, single.hit) << "n " << n << " ray " << r;
          ASSERT_EQ(hits[r].t, single.t) << "n " << n << " ray " << r;
          ASSERT_EQ(hits[r].hasNormal, single.hasNormal) << "n " << n << " ray " << r;
          ASSERT_EQ(hits[r].normal.x, single.normal.x) << "n " << n << " ray " << r;
          ASSERT_EQ(hits[r].normal.y, single.normal.y) << "n " << n << " ray " << r;
          ASSERT_EQ(hits[r].normal.z, single.normal.z) << "n " << n << " ray " << r;
          normalHits += single.hasNormal;
        }
      }
      EXPECT_GT(normalHits, rays.size() / 20);  // the normal field is exercised
      // The field placed by an Instance: its nearest batches hand the kernel world-space rays,
      // which it takes to object space lane by lane; its one-ray calls use RigidTransform.
      const Instance inst{&*q, RigidTransform::fromAxisAngle({1, 2, 3}, 0.7f, {5, -2, 1}, 2.5f)};
      std::vector<Ray> world(rays.size());
      for (size_t r = 0; r < rays.size(); ++r)
        world[r] = {inst.transform.toWorldPoint(rays[r].origin), inst.transform.toWorldVector(rays[r].direction),
                    rays[r].tmin, rays[r].tmax};
      constexpr size_t kBatches[2] = {65, 0};  // 0: all the rays in one call
      std::vector<uint8_t> placedOcc[2];
      std::vector<QueryHit> placedHits[2];
      for (size_t c = 0; c < 2; ++c) {
        const size_t batch = kBatches[c] ? kBatches[c] : world.size();
        placedOcc[c].resize(world.size());
        placedHits[c].resize(world.size());
        for (size_t b = 0; b < world.size(); b += batch) {
          const size_t e = std::min(world.size(), b + batch);
          const std::span<const Ray> part = std::span<const Ray>(world).subspan(b, e - b);
          inst.occluded(part, std::span<uint8_t>(placedOcc[c]).subspan(b, e - b), o);
          inst.intersect(part, std::span<QueryHit>(placedHits[c]).subspan(b, e - b), o);
        }
      }
      size_t hitCount = 0;
      for (size_t r = 0; r < world.size(); ++r) {
        const QueryHit single = inst.intersect(world[r], o);
        hitCount += single.hit;
        for (size_t c = 0; c < 2; ++c) {
          const QueryHit& h = placedHits[c][r];
          ASSERT_EQ(h.hit, single.hit) << "n " << n << " batch " << kBatches[c] << " world ray " << r;
          ASSERT_EQ(placedOcc[c][r] != 0, single.hit) << "n " << n << " batch " << kBatches[c] << " world ray " << r;
          if (single.hit) {
            ASSERT_EQ(h.t, single.t) << "n " << n << " batch " << kBatches[c] << " world ray " << r;
            ASSERT_EQ(h.point.x, single.point.x) << "n " << n << " batch " << kBatches[c] << " world ray " << r;
          }
        }
      }
      EXPECT_GT(hitCount, world.size() / 10);
    }
  }
}

TEST(FastLookup, OtherPositionSchemesTakeTheReferencePath) {
  for (PositionScheme scheme : {PositionScheme::kEqualAreaOctaGrid, PositionScheme::kSphericalFibonacci}) {
    FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kNone, 1, 8);
    f.positionScheme = scheme;
    f.positionParam = scheme == PositionScheme::kEqualAreaOctaGrid ? 6 : 40;
    f.mapCount = positionCount(scheme, f.positionParam).value();
    const std::vector<uint8_t> dist = test::syntheticDistance(f);
    auto q = FieldQuery::fromMaps(f, dist);
    ASSERT_TRUE(q);
    auto ps = PositionSet::fromField(f);
    const std::vector<Vec3> unit = unitTable(*ps);
    const std::vector<Ray> rays = testRays(f, 5000, 9);
    QueryOptions o;
    o.intraBias = 0.0f;
    std::vector<QueryHit> hits(rays.size());
    q->intersect(rays, hits, o);
    for (size_t r = 0; r < rays.size(); ++r) {
      const RefHit ref = referenceLookup(f, unit, *ps, dist, rays[r], 0.0f);
      ASSERT_EQ(hits[r].hit, ref.hit) << "ray " << r;
      if (ref.hit) {
        ASSERT_EQ(hits[r].t, ref.t) << "ray " << r;
      }
    }
  }
}

}  // namespace
}  // namespace vff
