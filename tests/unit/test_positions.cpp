// Positional-sample schemes (spec/positions.md): construction, counts, order and positions, checked
// against the definitions (the nearest lookup: test_position_lookup.cpp).
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "positions_reference.h"
#include "vff/vff.h"

namespace vff {
namespace {

using namespace vff::test;

// ---- Construction ------------------------------------------------------------------------------

TEST(PositionSet, CreateChecksSchemeAndParam) {
  struct Bad {
    PositionScheme s;
    uint32_t n;
  };
  for (Bad b : {Bad{PositionScheme::kInvalid, 1}, Bad{PositionScheme(4), 1}, Bad{PositionScheme::kOctaHemi2, 0},
                Bad{PositionScheme::kOctaHemi2, 1025}, Bad{PositionScheme::kEqualAreaOctaGrid, 0},
                Bad{PositionScheme::kEqualAreaOctaGrid, 2049}, Bad{PositionScheme::kSphericalFibonacci, 0},
                Bad{PositionScheme::kSphericalFibonacci, (1u << 24) + 1}}) {
    auto r = PositionSet::create(b.s, b.n);
    ASSERT_FALSE(r.ok()) << uint32_t(b.s) << " " << b.n;
    EXPECT_EQ(r.error().code, Code::kPositionScheme);
  }
  EXPECT_TRUE(PositionSet::create(PositionScheme::kOctaHemi2, 1024).ok());
  EXPECT_TRUE(PositionSet::create(PositionScheme::kEqualAreaOctaGrid, 2048).ok());
  EXPECT_TRUE(PositionSet::create(PositionScheme::kSphericalFibonacci, 1u << 24).ok());
}

TEST(PositionSet, CountsMatchTheFormat) {
  EXPECT_EQ(make(PositionScheme::kOctaHemi2, 32).count(), 4226u);
  EXPECT_EQ(make(PositionScheme::kOctaHemi2, 64).count(), 16642u);
  EXPECT_EQ(make(PositionScheme::kOctaHemi2, 1).count(), 10u);
  EXPECT_EQ(make(PositionScheme::kEqualAreaOctaGrid, 65).count(), 4225u);
  EXPECT_EQ(make(PositionScheme::kEqualAreaOctaGrid, 129).count(), 16641u);
  EXPECT_EQ(make(PositionScheme::kSphericalFibonacci, 4226).count(), 4226u);
  const PositionSet s = make(PositionScheme::kSphericalFibonacci, 16642);
  EXPECT_EQ(s.scheme(), PositionScheme::kSphericalFibonacci);
  EXPECT_EQ(s.param(), 16642u);
  EXPECT_EQ(s.count(), 16642u);
  for (PositionScheme sc :
       {PositionScheme::kOctaHemi2, PositionScheme::kEqualAreaOctaGrid, PositionScheme::kSphericalFibonacci})
    for (uint32_t n : {1u, 2u, 7u, 64u}) EXPECT_EQ(make(sc, n).count(), positionCount(sc, n).value());
}

TEST(PositionSet, FromFieldChecksMapCount) {
  FieldDesc f;
  f.positionScheme = PositionScheme::kOctaHemi2;
  f.positionParam = 32;
  f.mapCount = 4226;
  auto ok = PositionSet::fromField(f);
  ASSERT_TRUE(ok.ok());
  EXPECT_EQ(ok->count(), 4226u);
  f.mapCount = 4225;
  auto bad = PositionSet::fromField(f);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, Code::kMapCount);
  f.positionParam = 0;
  auto badParam = PositionSet::fromField(f);
  ASSERT_FALSE(badParam.ok());
  EXPECT_EQ(badParam.error().code, Code::kPositionScheme);
}

TEST(PositionSet, CandidatesHoldTheNearestSample) {
  // candidates() is what a table-driven lookup (the CPU query, a GPU port) chooses from.
  for (auto [sc, n] : {std::pair{PositionScheme::kOctaHemi2, 32u}, std::pair{PositionScheme::kEqualAreaOctaGrid, 65u},
                       std::pair{PositionScheme::kSphericalFibonacci, 4226u}}) {
    const PositionSet s = make(sc, n);
    SplitMix64 rng{42};
    for (int k = 0; k < 20000; ++k) {
      const Vec3 d = toF(rng.direction());
      uint32_t c[PositionSet::kMaxCandidates];
      const uint32_t count = s.candidates(d, c);
      ASSERT_GE(count, 1u);
      ASSERT_LE(count, PositionSet::kMaxCandidates);
      const uint32_t want = s.nearest(d);
      bool found = false;
      for (uint32_t i = 0; i < count; ++i) {
        ASSERT_LT(c[i], s.count());
        found = found || c[i] == want;
      }
      ASSERT_TRUE(found) << positionSchemeName(sc) << " query " << k;
    }
    uint32_t c[PositionSet::kMaxCandidates];
    EXPECT_EQ(s.candidates({0, 0, 0}, c), 1u);
    EXPECT_EQ(c[0], 0u);
  }
  uint32_t c[PositionSet::kMaxCandidates];
  EXPECT_EQ(PositionSet{}.candidates({1, 0, 0}, c), 0u);
}

TEST(PositionSet, EmptyAndInvalidInputsAreSafe) {
  static_assert(std::is_trivially_copyable_v<PositionSet>);
  const PositionSet empty;
  EXPECT_EQ(empty.count(), 0u);
  EXPECT_EQ(empty.nearest({0, 0, 1}), 0u);
  const Vec3 zero = empty.position(0);
  EXPECT_EQ(zero.x, 0.0f);
  const float nan = std::nanf(""), inf = INFINITY;
  for (PositionScheme sc :
       {PositionScheme::kOctaHemi2, PositionScheme::kEqualAreaOctaGrid, PositionScheme::kSphericalFibonacci}) {
    const PositionSet s = make(sc, 5);
    EXPECT_EQ(s.nearest({0, 0, 0}), 0u);
    EXPECT_EQ(s.nearest({nan, 0, 1}), 0u);
    EXPECT_EQ(s.nearest({inf, 0, 0}), 0u);
    const Vec3 out = s.position(s.count());
    EXPECT_EQ(out.x + out.y + out.z, 0.0f);
    // Not normalised, tiny or huge: still a valid index, the same as for the unit vector.
    EXPECT_EQ(s.nearest({3e-30f, 1e-30f, -2e-30f}), s.nearest({3, 1, -2}));
    EXPECT_EQ(s.nearest({3e30f, 1e30f, -2e30f}), s.nearest({3, 1, -2}));
    EXPECT_LT(s.nearest({0, 0, -1}), s.count());
    // The map frame looks inward.
    const Frame fr = s.frame(3);
    const Vec3 p = s.position(3);
    EXPECT_NEAR(fr.n.x * p.x + fr.n.y * p.y + fr.n.z * p.z, -1.0f, 1e-6f);
  }
}

// ---- Positions and order -----------------------------------------------------------------------

struct Param {
  PositionScheme scheme;
  uint32_t n;
};
const Param kSmallAndPaper[] = {
    {PositionScheme::kOctaHemi2, 1},
    {PositionScheme::kOctaHemi2, 2},
    {PositionScheme::kOctaHemi2, 3},
    {PositionScheme::kOctaHemi2, 32},
    {PositionScheme::kOctaHemi2, 64},
    {PositionScheme::kEqualAreaOctaGrid, 1},
    {PositionScheme::kEqualAreaOctaGrid, 2},
    {PositionScheme::kEqualAreaOctaGrid, 3},
    {PositionScheme::kEqualAreaOctaGrid, 64},
    {PositionScheme::kEqualAreaOctaGrid, 65},
    {PositionScheme::kEqualAreaOctaGrid, 129},
    {PositionScheme::kSphericalFibonacci, 1},
    {PositionScheme::kSphericalFibonacci, 2},
    {PositionScheme::kSphericalFibonacci, 3},
    {PositionScheme::kSphericalFibonacci, 4226},
    {PositionScheme::kSphericalFibonacci, 16642},
};

TEST(PositionSet, AllPositionsAreUnitVectors) {
  for (const Param& pr : kSmallAndPaper) {
    const PositionSet s = make(pr.scheme, pr.n);
    for (uint32_t i = 0; i < s.count(); ++i) {
      const D3 p = toD(s.position(i));
      ASSERT_NEAR(dot(p, p), 1.0, 4e-7) << positionSchemeName(pr.scheme) << " n=" << pr.n << " i=" << i;
    }
  }
}

TEST(PositionOctaHemi2, OrderMatchesSpec) {
  // n = 1: the octahedron's vertices, row by row.
  const PositionSet one = make(PositionScheme::kOctaHemi2, 1);
  const float expected[10][3] = {{0, -1, 0}, {-1, 0, 0}, {0, 0, 1},  {1, 0, 0}, {0, 1, 0},
                                 {0, -1, 0}, {-1, 0, 0}, {0, 0, -1}, {1, 0, 0}, {0, 1, 0}};
  for (uint32_t k = 0; k < 10; ++k) {
    const Vec3 p = one.position(k);
    EXPECT_EQ(p.x, expected[k][0]) << k;
    EXPECT_EQ(p.y, expected[k][1]) << k;
    EXPECT_EQ(p.z, expected[k][2]) << k;
  }
  // Any n: an independent enumeration (h, then q = -n..n, then p) gives the same bits.
  for (uint32_t un : {2u, 3u, 32u, 64u}) {
    const int64_t n = un;
    const PositionSet s = make(PositionScheme::kOctaHemi2, un);
    uint32_t k = 0;
    for (int64_t h = 0; h < 2; ++h)
      for (int64_t q = -n; q <= n; ++q)
        for (int64_t p = -(n - std::abs(q)); p <= n - std::abs(q); ++p, ++k) {
          const int64_t m = (h == 0 ? 1 : -1) * (n - std::abs(p) - std::abs(q));
          const double len = std::sqrt(double(p * p + q * q + m * m));
          const Vec3 got = s.position(k);
          ASSERT_EQ(got.x, float(double(p) / len)) << "n=" << n << " k=" << k;
          ASSERT_EQ(got.y, float(double(q) / len)) << "n=" << n << " k=" << k;
          ASSERT_EQ(got.z, float(double(m) / len)) << "n=" << n << " k=" << k;
        }
    EXPECT_EQ(k, s.count());
  }
}

TEST(PositionOctaHemi2, EquatorDuplicatesAreEqualAndResolveToTheUpperCopy) {
  for (uint32_t n : {1u, 2u, 5u, 32u, 64u}) {
    const PositionSet s = make(PositionScheme::kOctaHemi2, n);
    const uint32_t hemi = s.count() / 2;
    uint32_t equator = 0;
    for (uint32_t i = 0; i < hemi; ++i) {
      const Vec3 a = s.position(i), b = s.position(i + hemi);
      if (a.z == 0.0f) {
        ++equator;
        // Bit-identical copies (z is +0 in both), so their maps are identical too.
        EXPECT_EQ(std::bit_cast<uint32_t>(a.x), std::bit_cast<uint32_t>(b.x));
        EXPECT_EQ(std::bit_cast<uint32_t>(a.y), std::bit_cast<uint32_t>(b.y));
        EXPECT_EQ(std::bit_cast<uint32_t>(a.z), std::bit_cast<uint32_t>(b.z));
        EXPECT_EQ(s.nearest(b), i);
        // Just below the equator, the nearest is still this vertex, and still the upper copy.
        EXPECT_EQ(s.nearest({b.x, b.y, -1e-6f}), i);
      } else {
        EXPECT_EQ(a.z, -b.z);
        EXPECT_GT(a.z, 0.0f);
      }
    }
    EXPECT_EQ(equator, 4 * n);
  }
}

TEST(PositionEaOctaGrid, MatchesClarbergPbrtMap) {
  // pbrt-v4's EqualAreaSquareToSphere, transcribed in binary64 on p in [0,1]^2.
  auto pbrt = [](double px, double py) {
    const double u = 2 * px - 1, v = 2 * py - 1, up = std::fabs(u), vp = std::fabs(v);
    const double sd = 1 - (up + vp), d = std::fabs(sd), r = 1 - d;
    const double phi = (r == 0 ? 1 : (vp - up) / r + 1) * 3.141592653589793 / 4;
    const double z = std::copysign(1 - r * r, sd);
    const double cosPhi = std::copysign(std::cos(phi), u), sinPhi = std::copysign(std::sin(phi), v);
    const double s = r * std::sqrt(std::max(0.0, 2 - r * r));
    return D3{cosPhi * s, sinPhi * s, z};
  };
  for (uint32_t n : {1u, 2u, 3u, 64u, 65u}) {
    const PositionSet s = make(PositionScheme::kEqualAreaOctaGrid, n);
    for (uint32_t j = 0; j < n; ++j)
      for (uint32_t i = 0; i < n; ++i) {
        const D3 want = pbrt((i + 0.5) / n, (j + 0.5) / n);
        const D3 got = toD(s.position(j * n + i));
        ASSERT_NEAR(got.x, want.x, 2e-7) << n << " " << i << " " << j;
        ASSERT_NEAR(got.y, want.y, 2e-7) << n << " " << i << " " << j;
        ASSERT_NEAR(got.z, want.z, 2e-7) << n << " " << i << " " << j;
      }
  }
  // The examples of the spec: centre = north pole, corner cell in the lower hemisphere.
  const PositionSet s3 = make(PositionScheme::kEqualAreaOctaGrid, 3);
  EXPECT_EQ(s3.position(4).z, 1.0f);
  EXPECT_EQ(s3.position(5).x, 0x1.a9b7acp-1f);
  EXPECT_EQ(s3.position(5).y, 0.0f);
  EXPECT_EQ(s3.position(5).z, 0x1.1c71c8p-1f);
  EXPECT_EQ(s3.position(0).x, -0x1.2d0718p-1f);
  EXPECT_EQ(s3.position(0).z, -0x1.1c71c8p-1f);
}

TEST(PositionEaOctaGrid, NearestRegionsHaveNearlyEqualArea) {
  // The cells are equal-area, so the regions that look up each sample (their Voronoi cells) have
  // nearly equal solid angles: with 256 uniform directions per sample, every count is within 2x.
  const uint32_t n = 16;
  const PositionSet s = make(PositionScheme::kEqualAreaOctaGrid, n);
  std::vector<uint32_t> hits(s.count(), 0);
  SplitMix64 rng{42};
  const uint32_t q = 256 * s.count();
  for (uint32_t k = 0; k < q; ++k) ++hits[s.nearest(toF(rng.direction()))];
  const auto [lo, hi] = std::minmax_element(hits.begin(), hits.end());
  EXPECT_GT(*lo, 256u / 2);
  EXPECT_LT(*hi, 256u * 2);
}

TEST(PositionFibonacci, MatchesKeinertDefinition) {
  // z_i = 1 - (2i+1)/N and phi_i = 2 pi frac(i (Phi - 1)), in long double with the irrational Phi.
  for (uint32_t n : {1u, 2u, 3u, 4226u, 16642u}) {
    const PositionSet s = make(PositionScheme::kSphericalFibonacci, n);
    const long double phiM1 = (std::sqrt(5.0L) - 1.0L) / 2.0L;
    for (uint32_t i = 0; i < n; ++i) {
      const long double z = 1.0L - (2.0L * i + 1.0L) / n;
      const long double t = i * phiM1, ph = 2.0L * 3.14159265358979323846264338327950288L * (t - std::floor(t));
      const long double r = std::sqrt(1.0L - z * z);
      const Vec3 got = s.position(i);
      ASSERT_NEAR(got.x, double(r * std::cos(ph)), 2e-7) << n << " " << i;
      ASSERT_NEAR(got.y, double(r * std::sin(ph)), 2e-7) << n << " " << i;
      ASSERT_EQ(got.z, float(double(n - 2 * int64_t(i) - 1) / double(n))) << n << " " << i;
    }
  }
}

// ---- The binary64 evaluation is the correctly rounded binary32 value ----------------------------

TEST(PositionSet, PositionsAreCorrectlyRounded) {
  // Evaluate every formula again in long double and round to binary32: position() must give the
  // same bits (that is what makes the positions reproducible byte for byte).
  using L = long double;
  const L pi = 3.14159265358979323846264338327950288L;
  uint64_t total = 0, differ = 0;
  auto same = [&](Vec3 got, L x, L y, L z) {
    ++total;
    if (got.x != float(x) || got.y != float(y) || got.z != float(z)) ++differ;
  };
  for (uint32_t un : {32u, 64u}) {
    const PositionSet s = make(PositionScheme::kOctaHemi2, un);
    const int64_t n = un, hemi = s.count() / 2;
    for (int64_t k = 0; k < int64_t(s.count()); ++k) {
      const Vec3 p = s.position(uint32_t(k));
      // Recover (p, q, m) from the float (exact for these sizes), then normalise in long double.
      const int64_t h = k / hemi;
      const L l1 = L(std::fabs(p.x)) + std::fabs(p.y) + std::fabs(p.z);
      const int64_t a = std::llround(L(p.x) / l1 * n), b = std::llround(L(p.y) / l1 * n);
      const int64_t m = (h == 0 ? 1 : -1) * (n - std::abs(a) - std::abs(b));
      const L len = std::sqrt(L(a * a + b * b + m * m));
      same(p, a / len, b / len, m / len);
    }
  }
  for (uint32_t un : {65u, 129u}) {
    const PositionSet s = make(PositionScheme::kEqualAreaOctaGrid, un);
    const int64_t n = un;
    for (int64_t j = 0; j < n; ++j)
      for (int64_t i = 0; i < n; ++i) {
        const int64_t P = 2 * i + 1 - n, Q = 2 * j + 1 - n, ax = std::abs(P), ay = std::abs(Q);
        const bool upper = ax + ay <= n;
        const int64_t a = upper ? ax : n - ay, b = upper ? ay : n - ax, r = a + b;
        const L sg = upper ? 1 : -1;
        if (r == 0) {
          same(s.position(uint32_t(j * n + i)), 0, 0, sg);
          continue;
        }
        const L rho = L(r) * std::sqrt(L(2 * n * n - r * r)) / L(n * n);
        const L x = rho * std::sin(pi / 2 * a / r), y = rho * std::sin(pi / 2 * b / r);
        same(s.position(uint32_t(j * n + i)), P < 0 ? -x : x, Q < 0 ? -y : y, sg * L(n * n - r * r) / L(n * n));
      }
  }
  for (uint32_t un : {4226u, 16642u}) {
    const PositionSet s = make(PositionScheme::kSphericalFibonacci, un);
    const int64_t n = un;
    for (int64_t i = 0; i < n; ++i) {
      const uint64_t f = uint64_t(i) * 0x9E3779B97F4A7C15ull;
      const L ph = 2 * pi * (L(f) / 18446744073709551616.0L);
      const L rho = std::sqrt(L((2 * i + 1) * (2 * n - 2 * i - 1))) / n;
      same(s.position(uint32_t(i)), rho * std::cos(ph), rho * std::sin(ph), L(n - 2 * i - 1) / n);
    }
  }
  std::printf("[ positions ] %llu of %llu positions differ from the long-double evaluation\n",
              (unsigned long long)differ, (unsigned long long)total);
  RecordProperty("differ", std::to_string(differ));
  // long double is wider than binary64 on x86; elsewhere it may be binary64 and this is trivial.
  EXPECT_LE(differ, total / 100000);
}

}  // namespace
}  // namespace vff
