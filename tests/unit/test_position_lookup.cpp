// Positional-sample schemes (spec/positions.md): the O(1) nearest lookup checked against an exact
// (accelerated) brute force, plus a binary32 port of the lookup as a shader would run it (the GLSL
// listing of the spec, line for line).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>

#include "positions_reference.h"
#include "vff/vff.h"

namespace vff {
namespace {

using namespace vff::test;

// ---- binary32 port (the GLSL listing of spec/positions.md, in C++) -----------------------------

namespace f32 {

uint32_t umulHigh(uint32_t a, uint32_t b) {
  return uint32_t((uint64_t(a) * b) >> 32);
}
uint32_t fibTop32(uint32_t k) {
  return k * 0x9E3779B9u + umulHigh(k, 0x7F4A7C15u);
}
constexpr float kTwoPiOver2p32 = 6.28318531f / 4294967296.0f;
constexpr uint32_t kFib[22] = {0,  1,   1,   2,   3,   5,   8,    13,   21,   34,   55,
                               89, 144, 233, 377, 610, 987, 1597, 2584, 4181, 6765, 10946};

struct Best {
  float dot = -2.0f;
  int k = 0;
  void offer(float d, int i) {
    if (d > dot || (d == dot && i < k)) {
      dot = d;
      k = i;
    }
  }
};
float dotf(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}
Vec3 normalize(Vec3 v) {
  const float l = std::sqrt(dotf(v, v));
  return {v.x / l, v.y / l, v.z / l};
}

int octaIndex(int n, int h, int p, int q) {
  const int t = n + q;
  const int start = q <= 0 ? t * t : t * t - 2 * q * (q - 1);
  return h * (2 * n * n + 2 * n + 1) + start + p + n - std::abs(q);
}

int nearestOctaHemi2(Vec3 d, int n) {
  const int h = d.z >= 0.0f ? 0 : 1;
  const float ax = std::fabs(d.x), ay = std::fabs(d.y), az = std::fabs(d.z);
  const float s = float(n) / (ax + ay + az);
  const int a0 = std::min(int(ax * s), n - 1), b0 = std::min(int(ay * s), n - 1);
  const int sx = d.x < 0.0f ? -1 : 1, sy = d.y < 0.0f ? -1 : 1;
  static constexpr int kOffs[8][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}, {-1, 1}, {1, -1}, {2, 0}, {0, 2}};
  Best best;
  for (const auto& o : kOffs) {
    const int a = a0 + o[0], b = b0 + o[1];
    const int l1 = std::abs(a) + std::abs(b);
    if (l1 > n) continue;
    const int p = sx * a, q = sy * b, m = n - l1;
    const Vec3 u = normalize({float(p), float(q), float(h == 0 ? m : -m)});
    best.offer(dotf(u, d), octaIndex(n, l1 == n ? 0 : h, p, q));
  }
  return best.k;
}

Vec3 eaPosition(int n, int i, int j) {
  const int P = 2 * i + 1 - n, Q = 2 * j + 1 - n;
  const int ax = std::abs(P), ay = std::abs(Q);
  const bool upper = ax + ay <= n;
  const int a = upper ? ax : n - ay, b = upper ? ay : n - ax;
  const int r = a + b;
  const float s = upper ? 1.0f : -1.0f;
  if (r == 0) return {0.0f, 0.0f, s};
  const float nn = float(n * n);
  const float rho = float(r) * std::sqrt(float(2 * n * n - r * r)) / nn;
  const float x = rho * std::sin(float(a) / float(r) * 1.57079633f);
  const float y = rho * std::sin(float(b) / float(r) * 1.57079633f);
  return {P < 0 ? -x : x, Q < 0 ? -y : y, s * float(n * n - r * r) / nn};
}

int nearestEaOctaGrid(Vec3 d, int n) {
  const float ax = std::fabs(d.x), ay = std::fabs(d.y), az = std::fabs(d.z);
  const float r = std::sqrt((ax * ax + ay * ay) / (1.0f + az));
  const float b = ax + ay > 0.0f ? r * (std::atan2(ay, ax) * 0.636619772f) : 0.0f;
  float u = r - b, v = b;
  if (d.z < 0.0f) {
    const float t = u;
    u = 1.0f - v;
    v = 1.0f - t;
  }
  if (d.x < 0.0f) u = -u;
  if (d.y < 0.0f) v = -v;
  const int i0 = std::clamp(int(std::floor((u + 1.0f) * (0.5f * float(n)))), 0, n - 1);
  const int j0 = std::clamp(int(std::floor((v + 1.0f) * (0.5f * float(n)))), 0, n - 1);
  Best best;
  for (int dj = -1; dj <= 1; ++dj)
    for (int di = -1; di <= 1; ++di) {
      int i = i0 + di, j = j0 + dj;
      if (i < 0 || i >= n) {
        i = i < 0 ? 0 : n - 1;
        j = n - 1 - j;
      }
      if (j < 0 || j >= n) {
        j = j < 0 ? 0 : n - 1;
        i = n - 1 - i;
      }
      best.offer(dotf(eaPosition(n, i, j), d), j * n + i);
    }
  return best.k;
}

Vec3 fibPosition(int n, int k) {
  const float phi = float(fibTop32(uint32_t(k))) * kTwoPiOver2p32;
  const float z = float(n - 2 * k - 1) / float(n);
  const float rho = std::sqrt(float(2 * k + 1) * float(2 * n - 2 * k - 1)) / float(n);
  return {rho * std::cos(phi), rho * std::sin(phi), z};
}

int nearestFibonacci(Vec3 d, int n) {
  const float rho2 = d.x * d.x + d.y * d.y;
  const float v = float(n) * 7.02481473f * rho2;
  const int k = v > 1.0f ? std::clamp(int(std::floor(std::log(v) * 1.03904346f)), 2, 20) : 2;
  const uint32_t f0 = kFib[k], f1 = kFib[k + 1];
  const float p0 = float(int32_t(fibTop32(f0))) * kTwoPiOver2p32;
  const float p1 = float(int32_t(fibTop32(f1))) * kTwoPiOver2p32;
  const float z0 = -2.0f * float(f0) / float(n), z1 = -2.0f * float(f1) / float(n);
  const float phi = rho2 > 0.0f ? std::atan2(d.y, d.x) : 0.0f;
  const float dz = d.z - (1.0f - 1.0f / float(n));
  const float det = p0 * z1 - p1 * z0;
  const int c0 = int(std::floor((phi * z1 - p1 * dz) / det));
  const int c1 = int(std::floor((p0 * dz - z0 * phi) / det));
  Best best;
  for (int s = 0; s < 4; ++s) {
    const int i = (c0 + (s & 1)) * int(f0) + (c1 + (s >> 1)) * int(f1);
    if (i < 0 || i >= n) continue;
    best.offer(dotf(fibPosition(n, i), d), i);
  }
  return best.k;
}

int nearest(const PositionSet& set, Vec3 d) {
  const int n = int(set.param());
  switch (set.scheme()) {
    case PositionScheme::kOctaHemi2:
      return nearestOctaHemi2(d, n);
    case PositionScheme::kEqualAreaOctaGrid:
      return nearestEaOctaGrid(d, n);
    case PositionScheme::kSphericalFibonacci:
      return nearestFibonacci(d, n);
    case PositionScheme::kInvalid:
      break;
  }
  return 0;
}

Vec3 position(const PositionSet& set, uint32_t k) {
  const int n = int(set.param());
  switch (set.scheme()) {
    case PositionScheme::kOctaHemi2: {
      const int hemi = 2 * n * n + 2 * n + 1, h = int(k) / hemi;
      // Invert by search: the binary32 port only needs the forward index formula.
      for (int q = -n; q <= n; ++q) {
        const int w = n - std::abs(q);
        const int p = int(k) - octaIndex(n, h, -w, q) - w;
        if (p >= -w && p <= w) {
          const int m = n - std::abs(p) - std::abs(q);
          return normalize({float(p), float(q), float(h == 0 ? m : -m)});
        }
      }
      return {};
    }
    case PositionScheme::kEqualAreaOctaGrid:
      return eaPosition(n, int(k) % n, int(k) / n);
    case PositionScheme::kSphericalFibonacci:
      return fibPosition(n, int(k));
    case PositionScheme::kInvalid:
      break;
  }
  return {};
}

}  // namespace f32

// ---- The nearest lookup ------------------------------------------------------------------------

struct Case {
  const char* name;
  PositionScheme scheme;
  uint32_t n;
  uint32_t queries;
};

class PositionLookup : public ::testing::TestWithParam<Case> {};

std::string caseName(const ::testing::TestParamInfo<Case>& info) {
  return info.param.name;
}

TEST_P(PositionLookup, RoundTripsEverySample) {
  const Case c = GetParam();
  const PositionSet s = make(c.scheme, c.n);
  SplitMix64 rng{7};
  const double spacing = std::sqrt(4.0 * 3.141592653589793 / s.count());
  for (uint32_t i = 0; i < s.count(); ++i) {
    const Vec3 p = s.position(i);
    ASSERT_EQ(s.nearest(p), canonical(s, i)) << "i=" << i;
    // Nudged by a hundredth of the spacing: still the same sample.
    const D3 r = rng.direction(), pd = toD(p);
    const double e = 0.01 * spacing;
    ASSERT_EQ(s.nearest(toF({pd.x + e * r.x, pd.y + e * r.y, pd.z + e * r.z})), canonical(s, i)) << "i=" << i;
  }
}

TEST_P(PositionLookup, AgreesWithBruteForce) {
  const Case c = GetParam();
  const PositionSet s = make(c.scheme, c.n);
  const ExactNearest ref(s);
  const auto t0 = std::chrono::steady_clock::now();
  const Measured m = measure(
      ref, [&](Vec3 d) { return s.nearest(d); }, scaled(c.queries), 1000 + c.n);
  const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[ positions ] %s n=%u (%u samples), random: %s\n", positionSchemeName(c.scheme), c.n, s.count(),
              m.random.summary().c_str());
  std::printf("[ positions ] %s n=%u (%u samples), near ties: %s (%.2f s)\n", positionSchemeName(c.scheme), c.n,
              s.count(), m.adversarial.summary().c_str(), secs);
  RecordProperty("agreement", std::to_string(m.random.rate()));
  RecordProperty("queries", std::to_string(m.random.total));
  RecordProperty("agreement_near_ties", std::to_string(m.adversarial.rate()));
  // The lookup is exact for every scheme (spec/positions.md): no query may fail.
  ASSERT_EQ(m.random.fail, 0u) << m.random.summary();
  ASSERT_EQ(m.adversarial.fail, 0u) << m.adversarial.summary();
}

TEST_P(PositionLookup, Binary32PortAgrees) {
  // The GLSL listing of the spec, run in binary32: positions within a few ulp, and the same nearest
  // sample except within binary32 rounding of a tie (1e-5 in dot is allowed here; reported).
  const Case c = GetParam();
  const PositionSet s = make(c.scheme, c.n);
  double worst = 0;
  for (uint32_t i = 0; i < s.count(); ++i) {
    const D3 d = sub(toD(s.position(i)), toD(f32::position(s, i)));
    worst = std::max(worst, std::sqrt(dot(d, d)));
  }
  EXPECT_LT(worst, 2e-6);
  const ExactNearest ref(s);
  const Measured m = measure(
      ref, [&](Vec3 d) { return uint32_t(f32::nearest(s, d)); }, scaled(100000), 77 + c.n);
  std::printf("[ positions ] binary32 port %s n=%u: max position error %.2g; random: %s; near ties: %s\n",
              positionSchemeName(c.scheme), c.n, worst, m.random.summary().c_str(), m.adversarial.summary().c_str());
  RecordProperty("binary32_agreement", std::to_string(m.random.rate()));
  EXPECT_EQ(m.random.fail - m.random.nearTie, 0u) << m.random.summary();
  EXPECT_EQ(m.adversarial.fail - m.adversarial.nearTie, 0u) << m.adversarial.summary();
}

INSTANTIATE_TEST_SUITE_P(Positions, PositionLookup,
                         // 10^6 random directions for the ~4k-sample sets and 2 * 10^5 for the ~16k-sample sets.
                         ::testing::Values(Case{"OctaHemi2_n32", PositionScheme::kOctaHemi2, 32, 1000000},
                                           Case{"OctaHemi2_n64", PositionScheme::kOctaHemi2, 64, 200000},
                                           Case{"EaOctaGrid_n65", PositionScheme::kEqualAreaOctaGrid, 65, 1000000},
                                           Case{"EaOctaGrid_n129", PositionScheme::kEqualAreaOctaGrid, 129, 200000},
                                           Case{"Fibonacci_n4226", PositionScheme::kSphericalFibonacci, 4226, 1000000},
                                           Case{"Fibonacci_n16642", PositionScheme::kSphericalFibonacci, 16642,
                                                200000}),
                         caseName);

TEST(PositionLookupSmall, AgreesWithBruteForceForSmallParams) {
  // Small parameters, where the sphere's curvature is largest relative to the sample spacing.
  for (PositionScheme sc :
       {PositionScheme::kOctaHemi2, PositionScheme::kEqualAreaOctaGrid, PositionScheme::kSphericalFibonacci}) {
    const uint32_t last = sc == PositionScheme::kSphericalFibonacci ? 64 : 16;
    for (uint32_t n = 1; n <= last; ++n) {
      const PositionSet s = make(sc, n);
      const ExactNearest ref(s);
      const Measured m = measure(
          ref, [&](Vec3 d) { return s.nearest(d); }, scaled(4000), n);
      ASSERT_EQ(m.random.fail, 0u) << positionSchemeName(sc) << " n=" << n << ": " << m.random.summary();
      ASSERT_EQ(m.adversarial.fail, 0u) << positionSchemeName(sc) << " n=" << n << ": " << m.adversarial.summary();
      for (uint32_t i = 0; i < s.count(); ++i) ASSERT_EQ(s.nearest(s.position(i)), canonical(s, i));
    }
  }
}

TEST(PositionLookupLarge, FibonacciLargestNSpotCheck) {
  // n = 2^24: binary32 positions are too coarse to rank neighbours (spacing 8.6e-4 rad), so the
  // reference evaluates the definition in long double. Exact reference: the samples are sorted by
  // z, and every sample nearer than the answer lies in the band |z_i - z_q| < chord(answer).
  using L = long double;
  const uint32_t un = 1u << 24;
  const int64_t n = un;
  const PositionSet fib = make(PositionScheme::kSphericalFibonacci, un);
  auto exact = [&](int64_t i) {
    const uint64_t f = uint64_t(i) * 0x9E3779B97F4A7C15ull;
    const L ph = 2 * 3.14159265358979323846264338327950288L * (L(f) / 18446744073709551616.0L);
    const L rho = std::sqrt(L((2 * i + 1) * (2 * n - 2 * i - 1))) / n;
    return std::array<L, 3>{rho * std::cos(ph), rho * std::sin(ph), L(n - 2 * i - 1) / n};
  };
  SplitMix64 rng{3};
  for (int k = 0; k < int(scaled(200)); ++k) {
    const Vec3 q = toF(rng.direction());
    const uint32_t got = fib.nearest(q);
    const auto g = exact(got);
    const L gd = g[0] * q.x + g[1] * q.y + g[2] * q.z;
    // q is a unit vector only to binary32 precision: the band is computed from the normalised query.
    const L len = std::sqrt(L(q.x) * q.x + L(q.y) * q.y + L(q.z) * q.z);
    const double qz = double(q.z / len);
    const double chord = std::sqrt(std::max(0.0, double(2 - 2 * (gd / len)))) + 1e-9;
    const int64_t lo = std::max<int64_t>(0, int64_t(std::floor((n * (1 - qz - chord) - 1) / 2)) - 1);
    const int64_t hi = std::min<int64_t>(n - 1, int64_t(std::ceil((n * (1 - qz + chord) - 1) / 2)) + 1);
    ASSERT_LE(lo, hi) << "query " << k;
    for (int64_t i = lo; i <= hi; ++i) {
      const auto p = exact(i);
      ASSERT_LE(double(p[0] * q.x + p[1] * q.y + p[2] * q.z - gd), 1e-12) << "query " << k << " i=" << i;
    }
  }
}

}  // namespace
}  // namespace vff
