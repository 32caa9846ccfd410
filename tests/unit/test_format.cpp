#include <gtest/gtest.h>

#include "vff/vff.h"

namespace vff {
namespace {

TEST(Format, PaperPositionCounts) {
  EXPECT_EQ(positionCount(PositionScheme::kOctaHemi2, 32).value(), 4226u);
  EXPECT_EQ(positionCount(PositionScheme::kOctaHemi2, 64).value(), 16642u);
  EXPECT_EQ(positionCount(PositionScheme::kEqualAreaOctaGrid, 65).value(), 4225u);
  EXPECT_EQ(positionCount(PositionScheme::kSphericalFibonacci, 4226).value(), 4226u);
  EXPECT_EQ(positionCount(PositionScheme::kOctaHemi2, 0).error().code, Code::kPositionScheme);
  EXPECT_EQ(positionCount(PositionScheme::kInvalid, 3).error().code, Code::kPositionScheme);
}

TEST(Format, PaperPayloadSizes) {
  // 4226 maps of 64x64 at 1 byte: 17,309,696 bytes = 16.508 MiB; 4 bytes per ray: 66.031 MiB.
  EXPECT_EQ(4226 * distanceMapBytes(DistanceEncoding::kUnorm8Diameter, 64), 17309696u);
  EXPECT_EQ(4226 * normalMapBytes(NormalEncoding::kOctSnorm16, 64), 69238784u);
  EXPECT_NEAR(69238784.0 / 1048576.0, 66.031, 5e-4);
  EXPECT_NEAR(double(16642 * distanceMapBytes(DistanceEncoding::kUnorm8Diameter, 64)) / 1048576.0, 65.008, 5e-4);
  EXPECT_EQ(distanceMapBytes(DistanceEncoding::kUnorm16Diameter, 32), 2048u);
  EXPECT_EQ(distanceMapBytes(DistanceEncoding::kBit1, 64), 512u);
  EXPECT_EQ(distanceMapBytes(DistanceEncoding::kBit1, 12), 0u);  // bit1 needs M % 8 == 0
}

TEST(Format, MissCodes) {
  EXPECT_EQ(missCode(DistanceEncoding::kUnorm8Diameter), 255u);
  EXPECT_EQ(missCode(DistanceEncoding::kUnorm8Chord), 255u);
  EXPECT_EQ(missCode(DistanceEncoding::kUnorm16Diameter), 65535u);
  EXPECT_EQ(missCode(DistanceEncoding::kBit1), 0u);
}

FieldDesc paperField() {
  FieldDesc f;
  f.sphere = {{0, 0, 0}, 1};
  f.positionScheme = PositionScheme::kOctaHemi2;
  f.positionParam = 32;
  f.mapCount = 4226;
  f.directionScheme = DirectionScheme::kConcentricEqualArea;
  f.mapResolution = 64;
  f.distanceEncoding = DistanceEncoding::kUnorm8Diameter;
  return f;
}

TEST(Format, CheckFieldDescNamesTheRule) {
  FieldDesc f = paperField();
  EXPECT_TRUE(checkFieldDesc(f).ok());
  f.mapCount = 4225;
  EXPECT_EQ(checkFieldDesc(f).error().code, Code::kMapCount);
  f = paperField();
  f.sphere.radius = -1;
  EXPECT_EQ(checkFieldDesc(f).error().code, Code::kSphere);
  f = paperField();
  f.sphere.center[1] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(checkFieldDesc(f).error().code, Code::kSphere);
  f = paperField();
  f.distanceEncoding = DistanceEncoding::kBit1;
  f.mapResolution = 12;
  EXPECT_EQ(checkFieldDesc(f).error().code, Code::kMapResolution);
  f = paperField();
  f.directionScheme = DirectionScheme(9);
  EXPECT_EQ(checkFieldDesc(f).error().code, Code::kDirectionScheme);
}

TEST(Layout, PaperFieldPacksIntoFiveSlices) {
  auto l = computeLayout(paperField(), LayoutLimits{});
  ASSERT_TRUE(l.ok()) << l.error().toString();
  EXPECT_EQ(l->tilesPerRow, 32u);
  EXPECT_EQ(l->tilesPerColumn, 32u);
  EXPECT_EQ(l->sliceWidth, 2048u);
  EXPECT_EQ(l->sliceCount, 5u);  // 4226 maps exceed 2048 layers: several maps per slice
  EXPECT_TRUE(checkLayout(*l, paperField()).ok());
  TilePlacement p = placeMap(*l, 1024 + 33);
  EXPECT_EQ(p.slice, 1u);
  EXPECT_EQ(p.x, 64u);
  EXPECT_EQ(p.y, 64u);
}

TEST(Layout, GutterAndLimits) {
  LayoutLimits lim;
  lim.gutter = 1;
  auto l = computeLayout(paperField(), lim);
  ASSERT_TRUE(l.ok());
  EXPECT_EQ(l->tileSize, 66u);
  EXPECT_EQ(l->tilesPerRow, 31u);
  EXPECT_EQ(l->sliceCount, 5u);
  EXPECT_EQ(placeMap(*l, 0).x, 1u);
  lim = {};
  lim.maxTextureSize = 256;
  lim.maxLayers = 16;
  auto bad = computeLayout(paperField(), lim);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code, Code::kLayoutGeometry);
  EXPECT_NE(bad.error().message.find("layers"), std::string::npos) << bad.error().message;
}

TEST(Error, ToStringNamesPlaceAndCode) {
  Error e = makeError(Code::kHeaderChecksum, "mismatch", kTagDistance, 0x40);
  EXPECT_EQ(e.toString(), "@0x40 [DIST] header-checksum (3005): mismatch");
  EXPECT_STREQ(codeName(Code::kBlockDecode), "block-decode");
}

}  // namespace
}  // namespace vff
