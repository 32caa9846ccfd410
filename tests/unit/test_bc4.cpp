// bc4-diameter (format 1.2): the block decode as spec/format.md 7.4 defines it (hand-worked blocks),
// the encoder's guarantees (a miss stays a miss, a hit stays a hit, small ranges are lossless, the
// error is bounded on smooth data), and files that use it (version 1.2, incompatFeatures bit 2,
// the layout rules, the CPU query decoding the blocks).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "common/synthetic_field.h"
#include "vff/vff.h"

namespace vff {
namespace {

// Builds a block from endpoints and 16 indices.
std::vector<uint8_t> block(uint8_t r0, uint8_t r1, const std::vector<int>& idx) {
  uint64_t w = 0;
  for (size_t u = 0; u < 16; ++u) w |= uint64_t(idx[u] & 7) << (3 * u);
  std::vector<uint8_t> b{r0, r1};
  for (int k = 0; k < 6; ++k) b.push_back(uint8_t(w >> (8 * k)));
  return b;
}

TEST(Bc4, EightEntryPaletteAsTheSpecWorksIt) {
  // r0 = 200 > r1 = 60: 200, 60, then (6*200+60+3)/7 = 180, 160, 140, 120, 100, 80.
  std::vector<int> idx(16);
  for (int u = 0; u < 16; ++u) idx[size_t(u)] = u % 8;
  auto b = block(200, 60, idx);
  EXPECT_EQ(b, (std::vector<uint8_t>{0xC8, 0x3C, 0x88, 0xC6, 0xFA, 0x88, 0xC6, 0xFA}));  // the spec's example
  const uint32_t want[8] = {200, 60, 180, 160, 140, 120, 100, 80};
  uint8_t codes[16];
  decodeBc4Block(b.data(), codes);
  for (uint32_t u = 0; u < 16; ++u) {
    EXPECT_EQ(codes[u], want[u % 8]) << u;
    EXPECT_EQ(bc4Texel(b.data(), u), want[u % 8]) << u;
  }
  // Rounding: r0 = 10, r1 = 0: (6*10+0+3)/7 = 9, (50+3)/7 = 7, (40+3)/7 = 6, 4, 3, 1.
  auto c = block(10, 0, idx);
  const uint32_t want2[8] = {10, 0, 9, 7, 6, 4, 3, 1};
  for (uint32_t u = 0; u < 8; ++u) EXPECT_EQ(bc4Texel(c.data(), u), want2[u]) << u;
}

TEST(Bc4, SixEntryPaletteHasExactZeroAndMiss) {
  // r0 = 10 <= r1 = 30: 10, 30, (4*10+30+2)/5 = 14, 18, 22, 26, then 0 and 255.
  std::vector<int> idx(16);
  for (int u = 0; u < 16; ++u) idx[size_t(u)] = u % 8;
  auto b = block(10, 30, idx);
  const uint32_t want[8] = {10, 30, 14, 18, 22, 26, 0, 255};
  for (uint32_t u = 0; u < 16; ++u) EXPECT_EQ(bc4Texel(b.data(), u), want[u % 8]) << u;
  // Equal endpoints select this palette too.
  auto e = block(77, 77, idx);
  EXPECT_EQ(bc4Texel(e.data(), 2), 77u);
  EXPECT_EQ(bc4Texel(e.data(), 7), 255u);
  // The texel order: u = 4y + x, index bits 3u..3u+2 of the little-endian word after the endpoints.
  std::vector<int> one(16, 0);
  one[13] = 1;  // x = 1, y = 3
  auto f = block(5, 9, one);
  for (uint32_t u = 0; u < 16; ++u) EXPECT_EQ(bc4Texel(f.data(), u), u == 13 ? 9u : 5u);
}

// Encodes and decodes one block; checks the miss/hit guarantees and returns the decoded codes.
std::vector<uint8_t> roundTrip(const std::vector<uint8_t>& in) {
  uint8_t b[8], out[16];
  encodeBc4Block(in.data(), b);
  decodeBc4Block(b, out);
  for (size_t u = 0; u < 16; ++u) {
    if (in[u] == 255) EXPECT_EQ(out[u], 255) << "a miss became a hit at texel " << u;
    else EXPECT_NE(out[u], 255) << "a hit became a miss at texel " << u;
  }
  return {out, out + 16};
}

TEST(Bc4, EncoderKeepsMissesAndHitsAcrossRandomBlocks) {
  double sse = 0;
  size_t hits = 0;
  for (uint32_t trial = 0; trial < 20000; ++trial) {
    std::vector<uint8_t> in(16);
    const uint32_t h0 = test::hashMix(trial);
    const uint32_t missRate = h0 % 4;  // 0: no misses ... 3: most texels miss
    const uint32_t base = h0 % 255, spread = 1 + (h0 >> 8) % 64;
    for (uint32_t u = 0; u < 16; ++u) {
      const uint32_t h = test::hashMix(trial * 16 + u + 1);
      const bool miss = missRate && h % 4 < missRate;
      in[u] = miss ? 255 : uint8_t(std::min<uint32_t>(254, base + h % spread));
    }
    auto out = roundTrip(in);
    for (size_t u = 0; u < 16; ++u)
      if (in[u] != 255) {
        sse += double(int(out[u]) - int(in[u])) * (int(out[u]) - int(in[u]));
        ++hits;
      }
  }
  // Random noise of up to 64 codes in a block: 6 or 8 levels over the range leave a few codes.
  EXPECT_LT(std::sqrt(sse / double(hits)), 4.0);
}

TEST(Bc4, SmallRangesAreLossless) {
  // Six palette entries cover every code of a range of 5 exactly, with or without misses.
  for (uint32_t base = 0; base + 5 <= 254; base += 7)
    for (uint32_t pattern = 0; pattern < 8; ++pattern) {
      std::vector<uint8_t> in(16);
      for (uint32_t u = 0; u < 16; ++u)
        in[u] = (pattern & 1) && u % 5 == 0 ? 255 : uint8_t(base + (u * (pattern + 1)) % 6);
      EXPECT_EQ(roundTrip(in), in) << "base " << base << " pattern " << pattern;
    }
  // All misses.
  std::vector<uint8_t> misses(16, 255);
  EXPECT_EQ(roundTrip(misses), misses);
  uint8_t b[8];
  encodeBc4Block(misses.data(), b);
  for (uint8_t v : b) EXPECT_EQ(v, 0xFF);
  // Codes 0 and 254 next to misses.
  std::vector<uint8_t> ends{0, 254, 255, 0, 254, 255, 0, 254, 255, 0, 254, 255, 0, 254, 255, 0};
  EXPECT_EQ(roundTrip(ends), ends);
}

// The smallest squared error any pair of endpoints reaches (every pair tried).
uint32_t optimalError(const std::vector<uint8_t>& in) {
  bool anyMiss = false;
  for (uint8_t c : in) anyMiss |= c == 255;
  uint32_t best = UINT32_MAX;
  for (uint32_t r0 = 0; r0 <= 254; ++r0)
    for (uint32_t r1 = 0; r1 <= 254; ++r1) {
      if (anyMiss && r0 > r1) continue;  // only the six-entry palette has the miss code
      auto b = block(uint8_t(r0), uint8_t(r1), std::vector<int>(16, 0));
      uint32_t p[8];
      for (uint32_t i = 0; i < 8; ++i) {
        std::vector<int> idx(16, int(i));
        p[i] = bc4Texel(block(uint8_t(r0), uint8_t(r1), idx).data(), 0);
      }
      uint32_t e = 0;
      for (uint8_t c : in) {
        if (c == 255) continue;
        uint32_t m = UINT32_MAX;
        for (uint32_t i = 0; i < 8; ++i)
          if (p[i] != 255) m = std::min(m, uint32_t((int(p[i]) - c) * (int(p[i]) - c)));
        e += m;
      }
      best = std::min(best, e);
    }
  return best;
}

TEST(Bc4, EncoderIsNearTheBestEndpoints) {
  // Rim blocks (a wide range of codes, with and without misses) against an exhaustive search.
  uint64_t ours = 0, optimal = 0;
  for (uint32_t trial = 0; trial < 12; ++trial) {
    std::vector<uint8_t> in(16);
    for (uint32_t u = 0; u < 16; ++u) {
      const uint32_t x = u % 4, y = u / 4;
      const bool miss = trial % 2 && x + y > 4;
      in[u] = miss ? 255 : uint8_t(std::min<uint32_t>(254, 20 * trial + (x + y) * (trial + 3) + test::hashMix(trial * 16 + u) % 3));
    }
    auto out = roundTrip(in);
    uint32_t e = 0;
    for (size_t u = 0; u < 16; ++u)
      if (in[u] != 255) e += uint32_t((int(out[u]) - in[u]) * (int(out[u]) - in[u]));
    const uint32_t o = optimalError(in);
    EXPECT_LE(e, o + o / 2 + 2) << "trial " << trial;
    ours += e;
    optimal += o;
  }
  EXPECT_LE(ours, optimal + optimal / 5) << "ours " << ours << ", optimal " << optimal;
}

TEST(Bc4, SmoothMapsLoseAboutOneCode) {
  // A sphere-like depth ramp with a silhouette: the error on hits stays near a code.
  const uint32_t m = 32;
  std::vector<uint8_t> codes(m * m), blocks(m * m / 2), back(m * m);
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t i = 0; i < m; ++i) {
      const float x = (float(i) + 0.5f) / float(m) * 2 - 1, y = (float(j) + 0.5f) / float(m) * 2 - 1;
      const float r2 = x * x + y * y;
      codes[j * m + i] = r2 < 0.8f ? uint8_t(std::lround(254.0f * (1.0f - std::sqrt(1.0f - r2)) * 0.9f)) : 255;
    }
  encodeBc4Map(codes, m, blocks);
  decodeBc4Map(blocks, m, back);
  double sse = 0;
  int hits = 0, worst = 0;
  for (uint32_t t = 0; t < m * m; ++t) {
    ASSERT_EQ(codes[t] == 255, back[t] == 255) << t;
    if (codes[t] == 255) continue;
    const int d = std::abs(int(back[t]) - int(codes[t]));
    sse += d * d;
    worst = std::max(worst, d);
    ++hits;
  }
  // Measured: 1.44 codes RMS, worst 6 (the steep rim, where a block spans ~40 codes).
  EXPECT_LT(std::sqrt(sse / hits), 1.6);
  EXPECT_LE(worst, 8);
  // loadCode reads the same texels from the blocks.
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t i = 0; i < m; ++i)
      ASSERT_EQ(loadCode(DistanceEncoding::kBc4Diameter, blocks, m, i, j), back[j * m + i]);
}

TEST(Bc4, FilesAreVersion12WithTheFeatureBit) {
  FieldDesc f = test::smallField(DistanceEncoding::kBc4Diameter, NormalEncoding::kNone, 2, 8);
  EXPECT_EQ(distanceMapBytes(f.distanceEncoding, 8), 32u);
  EXPECT_EQ(missCode(f.distanceEncoding), 255u);
  EXPECT_STREQ(distanceEncodingName(f.distanceEncoding), "bc4-diameter");
  auto dist = test::syntheticDistance(f);
  auto bytes = writeMemory(f, dist);
  ASSERT_TRUE(bytes.ok()) << bytes.error().toString();
  auto file = File::openMemory(*bytes);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  EXPECT_EQ(file->info().versionMinor, 2);
  EXPECT_EQ(file->info().incompatFeatures & kFeatureBc4, kFeatureBc4);
  // Without bc4 the same writer still makes 1.0 files.
  FieldDesc u = test::smallField(DistanceEncoding::kUnorm8Diameter, NormalEncoding::kNone, 2, 8);
  auto plain = writeMemory(u, test::syntheticDistance(u));
  ASSERT_TRUE(plain.ok());
  EXPECT_EQ(File::openMemory(*plain)->info().versionMinor, 0);
}

TEST(Bc4, FieldAndLayoutRules) {
  FieldDesc f = test::smallField(DistanceEncoding::kBc4Diameter, NormalEncoding::kNone, 1, 6);
  EXPECT_EQ(checkFieldDesc(f).error().code, Code::kMapResolution);  // M a multiple of 4
  f.mapResolution = 12;
  EXPECT_TRUE(checkFieldDesc(f).ok());
  LayoutLimits lim;
  lim.gutter = 1;
  EXPECT_EQ(computeLayout(f, lim).error().code, Code::kLayoutTile);
  lim.gutter = 0;
  lim.target = LayoutTarget::kTexture3D;
  EXPECT_EQ(computeLayout(f, lim).error().code, Code::kLayoutTarget);
  lim.target = LayoutTarget::kTexture2DArray;
  EXPECT_TRUE(computeLayout(f, lim).ok());
  // The writer refuses the hits-med filter on bc4 blocks (it applies to unorm8 codes only).
  WriteOptions wo;
  wo.codec = Codec::kZstd;
  wo.filter = Filter::kHitsMed;
  FieldDesc g = test::smallField(DistanceEncoding::kBc4Diameter, NormalEncoding::kNone, 1, 8);
  EXPECT_FALSE(writeMemory(g, test::syntheticDistance(g), {}, wo).ok());
}

TEST(Bc4, QueryDecodesTheBlocks) {
  // The CPU query's distances for a bc4 field equal those of the unorm8-diameter field holding the
  // decoded codes, ray for ray.
  FieldDesc f = test::smallField(DistanceEncoding::kBc4Diameter, NormalEncoding::kNone, 3, 16);
  auto blocks = test::syntheticDistance(f);
  FieldDesc u = f;
  u.distanceEncoding = DistanceEncoding::kUnorm8Diameter;
  const uint64_t texels = 16 * 16;
  std::vector<uint8_t> codes(texels * f.mapCount);
  for (uint32_t k = 0; k < f.mapCount; ++k)
    decodeBc4Map(std::span<const uint8_t>(blocks).subspan(k * texels / 2, texels / 2), 16,
                 std::span<uint8_t>(codes).subspan(k * texels, texels));
  auto qb = FieldQuery::fromMaps(f, blocks);
  auto qu = FieldQuery::fromMaps(u, codes);
  ASSERT_TRUE(qb.ok() && qu.ok());
  int hits = 0;
  for (uint32_t r = 0; r < 4000; ++r) {
    const uint32_t h = test::hashMix(r);
    const float th = float(h % 1000) / 1000.0f * 6.2831853f, z = float((h >> 10) % 1000) / 500.0f - 1.0f;
    const float s = std::sqrt(1 - z * z);
    Vec3 dir{s * std::cos(th), s * std::sin(th), z};
    // From 3R outside the centre towards it, offset sideways by up to 0.6 R.
    const float back = 3.0f * f.sphere.radius, side = 0.1f * float(h % 7);
    const Vec3 o{f.sphere.center[0] - dir.x * back + side, f.sphere.center[1] - dir.y * back - side,
                 f.sphere.center[2] - dir.z * back + 0.5f * side};
    Ray ray{o, dir, 0.0f, 100.0f};
    QueryHit a = qb->intersect(ray), b = qu->intersect(ray);
    ASSERT_EQ(a.hit, b.hit) << r;
    if (a.hit) {
      ++hits;
      ASSERT_EQ(a.t, b.t) << r;
    }
  }
  EXPECT_GT(hits, 100);
}

}  // namespace
}  // namespace vff
