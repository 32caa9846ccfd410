#include <gtest/gtest.h>

#include <cmath>

#include "vff/vff.h"

namespace vff {
namespace {

TEST(Encoding, DiameterRoundTripWithinHalfStep) {
  const float r = 2.5f;
  for (auto e : {DistanceEncoding::kUnorm8Diameter, DistanceEncoding::kUnorm16Diameter}) {
    const float step = quantizationStep(e, r, 1.0f);
    EXPECT_FLOAT_EQ(step, 2 * r / float(maxHitCode(e)));
    for (int k = 0; k <= 1000; ++k) {
      const float d = 2 * r * float(k) / 1000.0f;
      const uint32_t c = encodeDistance(e, true, d, r, 1.0f);
      ASSERT_NE(c, missCode(e));
      Texel t = decodeDistance(e, c, r, 1.0f);
      ASSERT_TRUE(t.hit);
      EXPECT_LE(std::fabs(t.distance - d), 0.5f * step * 1.0001f) << "d=" << d;
    }
  }
}

TEST(Encoding, ChordUsesTheTexelChord) {
  const float r = 1.0f, cosA = 0.25f;  // chord = 0.5
  const auto e = DistanceEncoding::kUnorm8Chord;
  EXPECT_EQ(encodeDistance(e, true, 0.5f, r, cosA), 254u);
  EXPECT_EQ(encodeDistance(e, true, 0.25f, r, cosA), 127u);
  EXPECT_NEAR(decodeDistance(e, 127, r, cosA).distance, 0.25f, 0.5f / 254.0f);
  EXPECT_FLOAT_EQ(quantizationStep(e, r, cosA), 0.5f / 254.0f);
}

TEST(Encoding, MissesAndClamping) {
  const auto e = DistanceEncoding::kUnorm8Diameter;
  EXPECT_EQ(encodeDistance(e, false, 0.3f, 1, 1), 255u);
  EXPECT_FALSE(decodeDistance(e, 255, 1, 1).hit);
  EXPECT_EQ(encodeDistance(e, true, 100.0f, 1, 1), 254u);  // never the miss code
  EXPECT_EQ(encodeDistance(e, true, -1.0f, 1, 1), 0u);
  EXPECT_EQ(encodeDistance(e, true, std::nanf(""), 1, 1), 0u);
  EXPECT_EQ(encodeDistance(DistanceEncoding::kBit1, true, 0.3f, 1, 1), 1u);
  EXPECT_TRUE(decodeDistance(DistanceEncoding::kBit1, 1, 1, 1).hit);
  EXPECT_FALSE(decodeDistance(DistanceEncoding::kBit1, 0, 1, 1).hit);
}

TEST(Encoding, CodesInMaps) {
  std::vector<uint8_t> m8(64 * 2, 0);
  storeCode(DistanceEncoding::kUnorm16Diameter, m8, 8, 3, 5, 0xBEEF);
  EXPECT_EQ(m8[2 * (5 * 8 + 3)], 0xEF);  // little-endian
  EXPECT_EQ(loadCode(DistanceEncoding::kUnorm16Diameter, m8, 8, 3, 5), 0xBEEFu);
  std::vector<uint8_t> bits(8, 0);
  storeCode(DistanceEncoding::kBit1, bits, 8, 1, 2, 1);  // texel 17: byte 2, bit 1
  EXPECT_EQ(bits[2], 0x02);
  EXPECT_EQ(loadCode(DistanceEncoding::kBit1, bits, 8, 1, 2), 1u);
  storeCode(DistanceEncoding::kBit1, bits, 8, 1, 2, 0);
  EXPECT_EQ(bits[2], 0x00);
}

TEST(Encoding, OctahedralNormalsRoundTrip) {
  double worst = 0;
  for (int k = 0; k < 20000; ++k) {
    const float z = 1.0f - 2.0f * (float(k) + 0.5f) / 20000.0f;
    const float phi = 2.399963f * float(k);
    const float s = std::sqrt(1 - z * z);
    Vec3 n{s * std::cos(phi), s * std::sin(phi), z};
    uint8_t b[4];
    encodeNormal(n, b);
    Vec3 d = decodeNormal(b);
    // atan2(|n x d|, n.d) stays accurate for tiny angles, where acos(n.d) does not.
    const double cx = double(n.y) * d.z - double(n.z) * d.y, cy = double(n.z) * d.x - double(n.x) * d.z,
                 cz = double(n.x) * d.y - double(n.y) * d.x;
    const double dot = double(n.x) * d.x + double(n.y) * d.y + double(n.z) * d.z;
    worst = std::max(worst, std::atan2(std::sqrt(cx * cx + cy * cy + cz * cz), dot));
  }
  EXPECT_LT(worst * 180.0 / M_PI, 0.01);  // snorm16 octahedral: under 0.01 degrees
}

}  // namespace
}  // namespace vff
