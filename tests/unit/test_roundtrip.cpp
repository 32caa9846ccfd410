#include <gtest/gtest.h>

#include <cstring>
#include <tuple>

#include "common/synthetic_field.h"
#include "vff/vff.h"

namespace vff {
namespace {

using test::smallField;
using test::syntheticDistance;
using test::syntheticNormals;

struct Case {
  DistanceEncoding enc;
  NormalEncoding normals;
  Codec codec;
  uint32_t gutter;
  LayoutTarget target;
  uint32_t mapsPerBlock;
};

std::string caseName(const ::testing::TestParamInfo<Case>& info) {
  const Case& c = info.param;
  std::string s = std::string(distanceEncodingName(c.enc)) + "_" + normalEncodingName(c.normals) + "_" +
                  codecName(c.codec) + "_g" + std::to_string(c.gutter) + "_" + layoutTargetName(c.target) + "_b" +
                  std::to_string(c.mapsPerBlock);
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

class RoundTrip : public ::testing::TestWithParam<Case> {};

TEST_P(RoundTrip, WriteOpenValidateDecode) {
  const Case c = GetParam();
  FieldDesc f = smallField(c.enc, c.normals, 2, 8);  // 26 maps of 8x8
  auto dist = syntheticDistance(f);
  auto norm = c.normals == NormalEncoding::kNone ? std::vector<uint8_t>{} : syntheticNormals(f, dist);
  WriteOptions wo;
  wo.codec = c.codec;
  wo.mapsPerBlock = c.mapsPerBlock;
  wo.layout.gutter = c.gutter;
  wo.layout.target = c.target;
  wo.layout.maxTextureSize = 64;
  wo.metadataJson = R"({"z": 1, "a": {"y": [1, 2], "b": "x"}})";
  auto bytes = writeMemory(f, dist, norm, wo);
  ASSERT_TRUE(bytes.ok()) << bytes.error().toString();

  Report rep = validate(*bytes);
  for (const Issue& i : rep.issues) ADD_FAILURE() << codeName(i.code) << ": " << i.message;
  ASSERT_TRUE(rep.valid());

  for (auto policy : {ChecksumPolicy::kVerifyAll, ChecksumPolicy::kLazy, ChecksumPolicy::kNone}) {
    ReadOptions ro;
    ro.checksums = policy;
    auto file = File::openMemory(*bytes, ro);
    ASSERT_TRUE(file.ok()) << file.error().toString();
    EXPECT_EQ(file->field().mapCount, f.mapCount);
    EXPECT_EQ(file->field().distanceEncoding, f.distanceEncoding);
    EXPECT_EQ(file->field().sphere.radius, f.sphere.radius);
    EXPECT_EQ(file->metadata(), R"({"a":{"b":"x","y":[1,2]},"z":1})");  // canonical JSON
    EXPECT_EQ(file->hasNormals(), c.normals != NormalEncoding::kNone);
    const uint64_t mb = distanceMapBytes(f.distanceEncoding, f.mapResolution);
    for (uint32_t k = 0; k < f.mapCount; ++k) {
      auto m = file->mapData(Plane::kDistance, k);
      ASSERT_TRUE(m.ok()) << m.error().toString();
      ASSERT_EQ(m->size(), mb);
      ASSERT_EQ(0, std::memcmp(m->data(), dist.data() + k * mb, mb)) << "map " << k;
      if (file->hasNormals()) {
        auto n = file->mapData(Plane::kNormal, k);
        ASSERT_TRUE(n.ok());
        ASSERT_EQ(0, std::memcmp(n->data(), norm.data() + uint64_t(k) * n->size(), n->size()));
      }
    }
    EXPECT_EQ(file->mapData(Plane::kDistance, f.mapCount).error().code, Code::kOutOfRange);
    if (!file->hasNormals()) {
      EXPECT_EQ(file->mapData(Plane::kNormal, 0).error().code, Code::kPlanePresence);
    }
  }
  // Stored blocks are zero-copy views into the file's bytes.
  if (c.codec == Codec::kStored) {
    auto file = File::openMemory(*bytes);
    auto m = file->mapData(Plane::kDistance, 3);
    EXPECT_GE(m->data(), bytes->data());
    EXPECT_LT(m->data(), bytes->data() + bytes->size());
  }
}

TEST_P(RoundTrip, SlicesPlaceEveryTexel) {
  const Case c = GetParam();
  FieldDesc f = smallField(c.enc, c.normals, 2, 8);
  auto dist = syntheticDistance(f);
  auto norm = c.normals == NormalEncoding::kNone ? std::vector<uint8_t>{} : syntheticNormals(f, dist);
  WriteOptions wo;
  wo.codec = c.codec;
  wo.layout.gutter = c.gutter;
  wo.layout.target = c.target;
  wo.layout.maxTextureSize = 64;
  auto bytes = writeMemory(f, dist, norm, wo);
  ASSERT_TRUE(bytes.ok());
  auto file = File::openMemory(*bytes);
  ASSERT_TRUE(file.ok());
  const LayoutDesc& l = file->layout();
  EXPECT_EQ(l.tileSize, 8 + 2 * c.gutter);
  const uint32_t m = f.mapResolution;
  const uint64_t mb = distanceMapBytes(f.distanceEncoding, m);
  std::vector<uint8_t> slice(file->sliceBytes(Plane::kDistance));
  uint32_t seen = 0;
  for (uint32_t s = 0; s < l.sliceCount; ++s) {
    ASSERT_TRUE(file->readSlice(Plane::kDistance, s, slice).ok());
    const bool bit1 = f.distanceEncoding == DistanceEncoding::kBit1;
    const bool bc4 = f.distanceEncoding == DistanceEncoding::kBc4Diameter;
    const uint32_t tb = f.distanceEncoding == DistanceEncoding::kUnorm16Diameter ? 2 : 1;
    const uint64_t rowBytes = bit1 ? l.sliceWidth / 8 : bc4 ? uint64_t(l.sliceWidth) * 2 : uint64_t(l.sliceWidth) * tb;
    for (uint32_t k = 0; k < f.mapCount; ++k) {
      TilePlacement p = placeMap(l, k);
      if (p.slice != s) continue;
      ++seen;
      auto map = std::span<const uint8_t>(dist).subspan(k * mb, mb);
      // Inside the tile, and (with a gutter) one texel outside, the code equals the clamped texel.
      const int lo = -int(c.gutter), hi = int(m) + int(c.gutter);
      for (int j = lo; j < hi; ++j)
        for (int i = lo; i < hi; ++i) {
          const uint32_t ci = uint32_t(std::clamp(i, 0, int(m) - 1)), cj = uint32_t(std::clamp(j, 0, int(m) - 1));
          const uint32_t want = loadCode(f.distanceEncoding, map, m, ci, cj);
          const uint64_t x = uint64_t(int64_t(p.x) + i), y = uint64_t(int64_t(p.y) + j);
          uint32_t got;
          if (bit1) got = (slice[y * rowBytes + x / 8] >> (x % 8)) & 1u;
          else if (bc4) got = bc4Texel(&slice[(y / 4) * rowBytes + (x / 4) * 8], uint32_t((y % 4) * 4 + x % 4));
          else if (tb == 2) got = uint32_t(slice[y * rowBytes + 2 * x]) | uint32_t(slice[y * rowBytes + 2 * x + 1]) << 8;
          else got = slice[y * rowBytes + x];
          ASSERT_EQ(got, want) << "map " << k << " texel " << i << "," << j;
        }
    }
  }
  EXPECT_EQ(seen, f.mapCount);
  // Unused tiles of the last slice hold the miss code.
  const uint32_t perSlice = l.tilesPerRow * l.tilesPerColumn;
  if (f.mapCount % perSlice != 0 && f.distanceEncoding == DistanceEncoding::kUnorm8Diameter) {
    EXPECT_EQ(slice.back(), 255);
  }
  if (f.mapCount % perSlice != 0 && f.distanceEncoding == DistanceEncoding::kBc4Diameter) {
    EXPECT_EQ(bc4Texel(&slice[slice.size() - 8], 15), 255u);
  }
}

std::vector<Case> allCases() {
  std::vector<Case> v;
  for (auto enc : {DistanceEncoding::kUnorm8Diameter, DistanceEncoding::kUnorm8Chord, DistanceEncoding::kUnorm16Diameter,
                   DistanceEncoding::kBit1})
    for (auto codec : {Codec::kStored, Codec::kZstd}) {
      v.push_back({enc, NormalEncoding::kNone, codec, 0, LayoutTarget::kTexture2DArray, 0});
      v.push_back({enc, NormalEncoding::kOctSnorm16, codec, 0, LayoutTarget::kTexture3D, 5});
      if (enc != DistanceEncoding::kBit1)
        v.push_back({enc, NormalEncoding::kNone, codec, 1, LayoutTarget::kTexture2DArray, 1});
    }
  // bc4-diameter: 2d-array and no gutter only (rules 7001, 7002).
  for (auto codec : {Codec::kStored, Codec::kZstd}) {
    v.push_back({DistanceEncoding::kBc4Diameter, NormalEncoding::kNone, codec, 0, LayoutTarget::kTexture2DArray, 0});
    v.push_back({DistanceEncoding::kBc4Diameter, NormalEncoding::kOctSnorm16, codec, 0, LayoutTarget::kTexture2DArray, 5});
  }
  return v;
}

INSTANTIATE_TEST_SUITE_P(Variants, RoundTrip, ::testing::ValuesIn(allCases()), caseName);

TEST(Writer, DeterministicAndStreamingEqualsOneShot) {
  FieldDesc f = smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kOctSnorm16, 3, 16);
  auto dist = syntheticDistance(f);
  auto norm = syntheticNormals(f, dist);
  WriteOptions wo;
  wo.codec = Codec::kZstd;
  wo.zstdLevel = 3;
  wo.mapsPerBlock = 7;
  auto a = writeMemory(f, dist, norm, wo);
  auto b = writeMemory(f, dist, norm, wo);
  ASSERT_TRUE(a.ok() && b.ok());
  EXPECT_EQ(*a, *b);
  // Streaming in uneven pieces gives the same bytes.
  auto w = Writer::createInMemory(f, wo);
  ASSERT_TRUE(w.ok());
  const uint64_t mb = 16 * 16;
  uint64_t at = 0;
  for (uint64_t piece : {1u, 5u, 2u, 13u, 1u}) {
    ASSERT_TRUE(w->writeMaps(Plane::kDistance, std::span<const uint8_t>(dist).subspan(at, piece * mb)).ok());
    at += piece * mb;
  }
  ASSERT_TRUE(w->writeMaps(Plane::kDistance, std::span<const uint8_t>(dist).subspan(at)).ok());
  ASSERT_TRUE(w->writeMaps(Plane::kNormal, norm).ok());
  auto c = w->finishToMemory();
  ASSERT_TRUE(c.ok());
  EXPECT_EQ(*a, *c);
}

TEST(Writer, RejectsMisuse) {
  FieldDesc f = smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kOctSnorm16);
  auto w = Writer::createInMemory(f);
  ASSERT_TRUE(w.ok());
  std::vector<uint8_t> one(64 * 4, 0);
  EXPECT_EQ(w->writeMaps(Plane::kNormal, one).error().code, Code::kBadState);  // distance first
  EXPECT_EQ(w->writeMaps(Plane::kDistance, std::span<const uint8_t>(one).subspan(0, 63)).error().code,
            Code::kInvalidArgument);  // whole maps only
  EXPECT_EQ(w->finishToMemory().error().code, Code::kBadState);  // incomplete
  FieldDesc bad = f;
  bad.mapCount = 7;
  EXPECT_EQ(Writer::createInMemory(bad).error().code, Code::kMapCount);
  WriteOptions wo;
  wo.metadataJson = "[1,2]";
  EXPECT_EQ(Writer::createInMemory(f, wo).error().code, Code::kMetadataNotObject);
}

TEST(Writer, RefusesBlocksADefaultReaderRefuses) {
  // 1024^2 normals are 4 MiB a map: 16 maps a block are exactly ReadOptions::maxBlockBytes.
  FieldDesc f = smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kOctSnorm16, 3, 1024);
  ASSERT_GE(f.mapCount, 17u);
  WriteOptions wo;
  wo.mapsPerBlock = 16;
  EXPECT_TRUE(Writer::createInMemory(f, wo).ok());
  wo.mapsPerBlock = 17;
  auto w = Writer::createInMemory(f, wo);
  ASSERT_FALSE(w.ok());
  EXPECT_EQ(w.error().code, Code::kInvalidArgument);
  EXPECT_NE(w.error().message.find("ReadOptions::maxBlockBytes"), std::string::npos) << w.error().message;
}

TEST(Reader, LimitsRejectBeforeAllocating) {
  FieldDesc f = smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kNone, 2, 8);
  auto bytes = writeMemory(f, syntheticDistance(f));
  ASSERT_TRUE(bytes.ok());
  ReadOptions ro;
  ro.maxMaps = 10;
  EXPECT_EQ(File::openMemory(*bytes, ro).error().code, Code::kMapCount);
  ro = {};
  ro.maxPayloadBytes = 100;
  EXPECT_EQ(File::openMemory(*bytes, ro).error().code, Code::kDecodedLimit);
  ro = {};
  ro.maxMapResolution = 4;
  EXPECT_EQ(File::openMemory(*bytes, ro).error().code, Code::kMapResolution);
}

}  // namespace
}  // namespace vff
