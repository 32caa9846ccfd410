#include <gtest/gtest.h>

#include <cmath>

#include "vff/vff.h"

namespace vff {
namespace {

float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

TEST(Direction, FrameIsOrthonormalForAllNormals) {
  for (int k = 0; k < 5000; ++k) {
    const float z = 1.0f - 2.0f * (float(k) + 0.5f) / 5000.0f;
    const float phi = 2.399963f * float(k);
    const float s = std::sqrt(1 - z * z);
    Frame f = frameFromNormal({s * std::cos(phi), s * std::sin(phi), z});
    EXPECT_NEAR(dot(f.t, f.t), 1.0f, 1e-5f);
    EXPECT_NEAR(dot(f.b, f.b), 1.0f, 1e-5f);
    EXPECT_NEAR(dot(f.t, f.b), 0.0f, 1e-5f);
    EXPECT_NEAR(dot(f.t, f.n), 0.0f, 1e-5f);
    EXPECT_NEAR(dot(f.b, f.n), 0.0f, 1e-5f);
    Vec3 w{0.3f, -0.5f, 0.8f};
    Vec3 back = toWorld(f, toLocal(f, w));
    EXPECT_NEAR(back.x, w.x, 1e-5f);
    EXPECT_NEAR(back.y, w.y, 1e-5f);
    EXPECT_NEAR(back.z, w.z, 1e-5f);
  }
  // The pole where n.z = -1 is the case the sign choice exists for.
  Frame f = frameFromNormal({0, 0, -1});
  EXPECT_NEAR(dot(f.t, f.b), 0.0f, 1e-6f);
  EXPECT_TRUE(std::isfinite(f.t.x) && std::isfinite(f.b.y));
}

class DirectionScheme_ : public ::testing::TestWithParam<DirectionScheme> {};

TEST_P(DirectionScheme_, SquareRoundTrip) {
  const DirectionScheme s = GetParam();
  for (int j = 0; j <= 200; ++j)
    for (int i = 0; i <= 200; ++i) {
      Vec2 uv{-1.0f + float(i) / 100.0f, -1.0f + float(j) / 100.0f};
      Vec3 d = squareToHemisphere(s, uv);
      ASSERT_NEAR(dot(d, d), 1.0f, 1e-5f);
      ASSERT_GE(d.z, -1e-6f);
      Vec2 back = hemisphereToSquare(s, d);
      // At the rim several square points map to one direction (concentric: the square's
      // boundary is the horizon circle; hemi-oct: the corners); compare directions there.
      Vec3 again = squareToHemisphere(s, back);
      ASSERT_GT(dot(d, again), 1.0f - 1e-5f) << "uv=(" << uv.x << "," << uv.y << ")";
      if (d.z > 1e-3f && std::fabs(uv.x) < 0.999f && std::fabs(uv.y) < 0.999f) {
        ASSERT_NEAR(back.x, uv.x, 2e-4f);
        ASSERT_NEAR(back.y, uv.y, 2e-4f);
      }
    }
}

TEST_P(DirectionScheme_, EveryTexelCentreMapsBackToItsTexel) {
  const DirectionScheme s = GetParam();
  for (uint32_t m : {8u, 32u, 64u}) {
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        Vec3 d = texelDirection(s, m, i, j);
        ASSERT_GT(d.z, 0.0f);  // chord encoding divides by cos(alpha)
        uint32_t bi, bj;
        squareToTexel(hemisphereToSquare(s, d), m, &bi, &bj);
        ASSERT_EQ(bi, i);
        ASSERT_EQ(bj, j);
      }
  }
}

INSTANTIATE_TEST_SUITE_P(All, DirectionScheme_,
                         ::testing::Values(DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral),
                         [](const auto& param_info) {
                           return param_info.param == DirectionScheme::kConcentricEqualArea ? std::string("Concentric")
                                                                                       : std::string("HemiOct");
                         });

TEST(Direction, ConcentricIsEqualArea) {
  // Each texel of the equal-area map subtends 2*pi/M^2 sr: estimate by uniform sampling.
  const uint32_t m = 8;
  std::vector<int> counts(m * m, 0);
  const int n = 400000;
  for (int k = 0; k < n; ++k) {
    const float z = (float(k) + 0.5f) / float(n);  // uniform in z = uniform in area on the hemisphere
    const float phi = 2.399963f * float(k);
    const float s = std::sqrt(1 - z * z);
    uint32_t i, j;
    squareToTexel(hemisphereToSquare(DirectionScheme::kConcentricEqualArea, {s * std::cos(phi), s * std::sin(phi), z}), m, &i, &j);
    counts[j * m + i]++;
  }
  const double expect = double(n) / (m * m);
  for (int c : counts) EXPECT_NEAR(c / expect, 1.0, 0.03);
}

}  // namespace
}  // namespace vff
