// Block filter 1 (hits-med): the writer's frames hold exactly the stream spec/format.md defines (a
// reference implementation written from the spec, checked on the spec's own example), files using
// it are 1.1 with the filters bit, decode to the original maps, and misuse is refused.
#include <gtest/gtest.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "test_util.h"
#include "vff/vff.h"

namespace vff {
namespace {

// spec/format.md, "Filter 1, hits-med", transcribed.
std::vector<uint8_t> referenceHitsMed(const std::vector<uint8_t>& raw, uint32_t m) {
  std::vector<uint8_t> out((raw.size() + 7) / 8, 0);
  for (size_t t = 0; t < raw.size(); ++t)
    if (raw[t] != 255) out[t / 8] |= uint8_t(1u << (t % 8));
  for (size_t first = 0; first < raw.size(); first += size_t(m) * m) {
    int last = 0;
    auto code = [&](int x, int y) { return x < 0 || y < 0 ? -1 : raw[first + size_t(y) * m + size_t(x)] == 255 ? -1 : int(raw[first + size_t(y) * m + size_t(x)]); };
    for (int y = 0; y < int(m); ++y)
      for (int x = 0; x < int(m); ++x) {
        const int v = code(x, y);
        if (v < 0) continue;
        const int a = code(x - 1, y), b = code(x, y - 1), c = code(x - 1, y - 1);
        int p;
        if (a >= 0 && b >= 0 && c >= 0)
          p = c >= std::max(a, b) ? std::min(a, b) : c <= std::min(a, b) ? std::max(a, b) : a + b - c;
        else if (a >= 0 && b >= 0)
          p = (a + b) / 2;
        else if (a >= 0)
          p = a;
        else if (b >= 0)
          p = b;
        else
          p = c >= 0 ? c : last;
        out.push_back(uint8_t(v - p));
        last = v;
      }
  }
  return out;
}

TEST(HitsMed, ReferenceMatchesTheSpecExample) {
  const std::vector<uint8_t> map = {10, 12, 255, 11, 13, 14, 255, 255, 15};
  EXPECT_EQ(referenceHitsMed(map, 3), (std::vector<uint8_t>{0x3B, 0x01, 0x0A, 0x02, 0x01, 0x01, 0x01, 0x01}));
}

// A smooth field with miss regions, like a baked one: the filter wins on every block.
std::vector<uint8_t> smoothDistance(const FieldDesc& f) {
  const uint32_t m = f.mapResolution;
  std::vector<uint8_t> d(uint64_t(f.mapCount) * m * m);
  for (uint32_t k = 0; k < f.mapCount; ++k)
    for (uint32_t y = 0; y < m; ++y)
      for (uint32_t x = 0; x < m; ++x) {
        const double u = (x + 0.5) / m - 0.5, v = (y + 0.5) / m - 0.5 + 0.02 * (k % 7);
        const double r2 = u * u + v * v;
        d[(uint64_t(k) * m + y) * m + x] = r2 > 0.2 ? 255 : uint8_t(40 + 300 * r2 + (k % 5));
      }
  return d;
}

WriteOptions filtered(uint32_t g) {
  WriteOptions o;
  o.codec = Codec::kZstd;
  o.filter = Filter::kHitsMed;
  o.mapsPerBlock = g;
  o.sync = false;
  return o;
}

TEST(HitsMed, WriterFramesHoldTheSpecStream) {
  const FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kNone, 2, 32);
  const auto dist = smoothDistance(f);
  auto bytes = writeMemory(f, dist, {}, filtered(4));
  ASSERT_TRUE(bytes) << bytes.error().toString();
  auto file = File::openBuffer(*bytes);
  ASSERT_TRUE(file) << file.error().toString();
  EXPECT_EQ(file->info().versionMinor, 1);
  EXPECT_EQ(file->info().incompatFeatures, kFeatureZstd | kFeatureFilters);
  const PlaneInfo& pi = file->plane(Plane::kDistance);
  ASSERT_EQ(pi.blocks.size(), 7u);  // 26 maps, 4 per block
  for (const BlockInfo& b : pi.blocks) {
    EXPECT_EQ(b.filter, Filter::kHitsMed);
    EXPECT_EQ(b.codec, Codec::kZstd);
    const uint8_t* stored = file->bytes().data() + b.offset;
    const unsigned long long n = ZSTD_getFrameContentSize(stored, b.storedSize);
    ASSERT_LE(n, uint64_t(b.rawSize) + b.rawSize / 8);
    std::vector<uint8_t> stream(n);
    ASSERT_EQ(ZSTD_decompress(stream.data(), stream.size(), stored, b.storedSize), n);
    const uint64_t first = uint64_t(b.firstMap) * pi.mapBytes;
    const std::vector<uint8_t> raw(dist.begin() + std::ptrdiff_t(first), dist.begin() + std::ptrdiff_t(first + b.rawSize));
    EXPECT_EQ(stream, referenceHitsMed(raw, f.mapResolution)) << "block of map " << b.firstMap;
  }
  for (uint32_t k = 0; k < f.mapCount; ++k) {
    auto map = file->mapData(Plane::kDistance, k);
    ASSERT_TRUE(map);
    EXPECT_TRUE(std::equal(map->begin(), map->end(), dist.begin() + std::ptrdiff_t(k) * 1024)) << "map " << k;
  }
  EXPECT_TRUE(validate(*bytes).valid());
}

TEST(HitsMed, SmallerThanZstdAloneAndDeterministic) {
  const FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Chord, NormalEncoding::kNone, 2, 32);
  const auto dist = smoothDistance(f);
  WriteOptions plain = filtered(0);
  plain.filter = Filter::kNone;
  auto a = writeMemory(f, dist, {}, filtered(0));
  auto b = writeMemory(f, dist, {}, filtered(0));
  auto c = writeMemory(f, dist, {}, plain);
  ASSERT_TRUE(a && b && c);
  EXPECT_EQ(*a, *b);
  EXPECT_LT(a->size(), c->size());
  auto fc = File::openBuffer(*c);
  ASSERT_TRUE(fc);
  EXPECT_EQ(fc->info().versionMinor, 0);  // no 1.1 feature used: a 1.0 file
  EXPECT_EQ(fc->info().incompatFeatures, kFeatureZstd);
}

TEST(HitsMed, UnfilteredBlocksWhereTheFilterDoesNotWin) {
  // Noise: the filter cannot beat zstd alone, so the writer keeps plain blocks and a 1.0 file.
  const FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kNone, 2, 16);
  const auto dist = test::syntheticDistance(f);
  auto bytes = writeMemory(f, dist, {}, filtered(0));
  ASSERT_TRUE(bytes);
  auto file = File::openBuffer(*bytes);
  ASSERT_TRUE(file);
  for (const BlockInfo& b : file->plane(Plane::kDistance).blocks) EXPECT_EQ(b.filter, Filter::kNone);
  EXPECT_EQ(file->info().incompatFeatures & kFeatureFilters, 0u);
}

TEST(HitsMed, OnlyNormalsStayUnfiltered) {
  const FieldDesc f = test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kOctSnorm16, 2, 32);
  const auto dist = smoothDistance(f);
  const auto normals = test::syntheticNormals(f, dist);
  auto bytes = writeMemory(f, dist, normals, filtered(0));
  ASSERT_TRUE(bytes);
  auto file = File::openBuffer(*bytes);
  ASSERT_TRUE(file);
  for (const BlockInfo& b : file->plane(Plane::kNormal).blocks) EXPECT_EQ(b.filter, Filter::kNone);
  EXPECT_EQ(file->plane(Plane::kDistance).blocks.front().filter, Filter::kHitsMed);
  EXPECT_TRUE(validate(*bytes).valid());
}

TEST(HitsMed, WriterRefusesMisuse) {
  const FieldDesc u8 = test::smallField(DistanceEncoding::kUnorm8Diameter);
  const auto d8 = test::syntheticDistance(u8);
  WriteOptions stored = filtered(0);
  stored.codec = Codec::kStored;
  auto r = writeMemory(u8, d8, {}, stored);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code, Code::kInvalidArgument);
  EXPECT_NE(r.error().message.find("zstd"), std::string::npos) << r.error().message;
  for (DistanceEncoding e : {DistanceEncoding::kUnorm16Diameter, DistanceEncoding::kBit1}) {
    const FieldDesc f = test::smallField(e);
    auto w = writeMemory(f, test::syntheticDistance(f), {}, filtered(0));
    ASSERT_FALSE(w) << distanceEncodingName(e);
    EXPECT_EQ(w.error().code, Code::kInvalidArgument);
    EXPECT_NE(w.error().message.find(distanceEncodingName(e)), std::string::npos) << w.error().message;
  }
}

}  // namespace
}  // namespace vff
