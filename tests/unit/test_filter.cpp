// Block filter 1 (hits-med): the writer's frames hold exactly the stream spec/format.md defines (a
// reference implementation written from the spec, checked on the spec's own example), files using
// it are 1.1 with the filters bit, decode to the original maps, and misuse is refused.
#include <gtest/gtest.h>
#include <zstd.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

#include "codec/filter.h"  // private: the decoder's fast path against its scalar reference
#include "common/synthetic_field.h"
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

// A block of `maps` maps of m x m codes as the decoder meets them: maps with no hit, maps of hits only,
// and maps of smooth codes (so that every case of the prediction occurs) in regions and speckles of
// misses; now and then a code at the ends of the range, where the residual sums wrap.
std::vector<uint8_t> randomBlock(std::mt19937& rng, uint32_t m, uint32_t maps) {
  std::vector<uint8_t> raw(uint64_t(maps) * m * m);
  for (uint32_t k = 0; k < maps; ++k) {
    const uint32_t kind = uint32_t(rng()) % 6;  // 0: all misses, 1: all hits, else a mix
    const double cx = double(uint32_t(rng()) % 100) / 100, cy = double(uint32_t(rng()) % 100) / 100,
                 r2 = double(uint32_t(rng()) % 60) / 100;
    const int base = int(uint32_t(rng()) % 200), slope = int(uint32_t(rng()) % 9) - 4;
    const uint32_t speckle = uint32_t(rng()) % 4;
    for (uint32_t y = 0; y < m; ++y)
      for (uint32_t x = 0; x < m; ++x) {
        const double u = (x + 0.5) / m - cx, v = (y + 0.5) / m - cy;
        bool hit = kind == 1 || (kind != 0 && u * u + v * v < r2);
        if (kind > 1 && speckle && uint32_t(rng()) % (8 * speckle) == 0) hit = !hit;
        int code = base + slope * int(x) - slope * int(y) / 2 + int(uint32_t(rng()) % 3);
        if (uint32_t(rng()) % 50 == 0) code = uint32_t(rng()) % 2 ? 0 : 254;
        raw[(uint64_t(k) * m + y) * m + x] = hit ? uint8_t(std::clamp(code, 0, 254)) : uint8_t(255);
      }
  }
  return raw;
}

Status decodeFast(uint32_t m, const std::vector<uint8_t>& stream, std::vector<uint8_t>& raw) {
  return detail::unapplyFilter(Filter::kHitsMed, {m, 1}, stream, raw, Code::kBlockDecode);
}

Status decodeScalar(uint32_t m, const std::vector<uint8_t>& stream, std::vector<uint8_t>& raw) {
  return detail::unapplyHitsMedScalar({m, 1}, stream, raw, Code::kBlockDecode);
}

// Both decoders agree: the same maps, or the same error (code and message).
void expectSameDecode(uint32_t m, const std::vector<uint8_t>& stream, size_t rawSize, const std::string& what) {
  std::vector<uint8_t> fast(rawSize, 0x5A), scalar(rawSize, 0xA5);
  const Status a = decodeFast(m, stream, fast), b = decodeScalar(m, stream, scalar);
  ASSERT_EQ(bool(a), bool(b)) << what << ": " << (a ? b.error().toString() : a.error().toString());
  if (a) {
    EXPECT_EQ(fast, scalar) << what;
  } else {
    EXPECT_EQ(a.error().code, b.error().code) << what;
    EXPECT_EQ(a.error().message, b.error().message) << what;
  }
}

const uint32_t kResolutions[] = {1, 3, 8, 16, 17, 32, 48, 64, 80, 128};

TEST(HitsMed, FastDecoderMatchesTheScalarOneOnRandomBlocks) {
  std::mt19937 rng(20240611);
  for (int round = 0; round < 120; ++round) {
    const uint32_t m = kResolutions[uint32_t(rng()) % std::size(kResolutions)];
    const uint32_t maps = 1 + uint32_t(rng()) % (m >= 64 ? 40 : 70);  // often not a multiple of 16
    const auto raw = randomBlock(rng, m, maps);
    const auto stream = detail::applyFilter(Filter::kHitsMed, {m, 1}, raw);
    const std::string what =
        "M " + std::to_string(m) + ", " + std::to_string(maps) + " maps, round " + std::to_string(round);
    std::vector<uint8_t> out(raw.size());
    const Status st = decodeFast(m, stream, out);
    ASSERT_TRUE(st) << what << ": " << st.error().toString();
    EXPECT_EQ(out, raw) << what;
    expectSameDecode(m, stream, raw.size(), what);
  }
}

#if VFF_HITS_MED_LANES
TEST(HitsMed, LanesDecodeWholeGroupsWithAndWithoutSsse3) {
  // unapplyFilter uses one way on this processor; both are checked here, on the groups they decode.
  std::mt19937 rng(5);
  for (bool ssse3 : {false, true}) {
    if (ssse3 && !detail::hitsMedLanesSsse3()) continue;
    for (int round = 0; round < 40; ++round) {
      const uint32_t m = 16 * (1 + uint32_t(rng()) % 8);
      const uint32_t maps = 1 + uint32_t(rng()) % 50;
      const auto raw = randomBlock(rng, m, maps);
      const auto stream = detail::applyFilter(Filter::kHitsMed, {m, 1}, raw);
      const uint64_t nMask = (raw.size() + 7) / 8;
      std::vector<uint8_t> out(raw.size(), 0x5A);
      const auto done = detail::unapplyHitsMedLanes(stream, stream.data() + nMask, m, maps, out.data(), ssse3);
      const uint64_t whole = maps / 16 * 16, groupTexels = whole * m * m;
      const std::string what =
          std::string(ssse3 ? "SSSE3" : "SSE2") + ", M " + std::to_string(m) + ", " + std::to_string(maps) + " maps";
      EXPECT_EQ(done.maps, whole) << what;
      EXPECT_EQ(done.residuals - stream.data(),
                ptrdiff_t(nMask + std::count_if(raw.begin(), raw.begin() + ptrdiff_t(groupTexels),
                                                [](uint8_t v) { return v != 255; })))
          << what;
      EXPECT_TRUE(std::equal(out.begin(), out.begin() + ptrdiff_t(groupTexels), raw.begin())) << what;
      EXPECT_TRUE(std::all_of(out.begin() + ptrdiff_t(groupTexels), out.end(), [](uint8_t v) { return v == 0x5A; }))
          << what;
      // A hit made to decode to the miss code: they stop before its group.
      if (done.maps == 0 || stream.size() == nMask) continue;
      auto bad = stream;
      const uint64_t at = nMask + uint32_t(rng()) % (done.residuals - stream.data() - nMask);
      std::vector<uint8_t> scalar(raw.size());
      for (bad[at] = 0; detail::unapplyHitsMedScalar({m, 1}, bad, scalar, Code::kBlockDecode); ++bad[at]) {
      }
      const std::string message = detail::unapplyHitsMedScalar({m, 1}, bad, scalar, Code::kBlockDecode).error().message;
      const uint64_t texel = std::stoull(message.substr(message.find("texel ") + 6));
      const auto stopped = detail::unapplyHitsMedLanes(bad, bad.data() + nMask, m, maps, out.data(), ssse3);
      EXPECT_EQ(stopped.maps, texel / (uint64_t(m) * m) / 16 * 16) << what << ": " << message;
    }
  }
}
#endif

TEST(HitsMed, FastDecoderMatchesTheScalarOneOnCorruptStreams) {
  std::mt19937 rng(7);
  for (int round = 0; round < 200; ++round) {
    const uint32_t m = kResolutions[uint32_t(rng()) % std::size(kResolutions)];
    const uint32_t maps = 1 + uint32_t(rng()) % 40;
    const auto raw = randomBlock(rng, m, maps);
    auto stream = detail::applyFilter(Filter::kHitsMed, {m, 1}, raw);
    const uint64_t nMask = (raw.size() + 7) / 8;
    const std::string what =
        "M " + std::to_string(m) + ", " + std::to_string(maps) + " maps, round " + std::to_string(round);
    switch (round % 4) {
      case 0:  // residuals changed at random: hits that decode to the miss code, in any map
        for (uint32_t n = 1 + uint32_t(rng()) % 4; n && stream.size() > nMask; --n)
          stream[nMask + uint32_t(rng()) % (stream.size() - nMask)] = uint8_t(uint32_t(rng()));
        break;
      case 1:  // one hit made to decode to the miss code: the residual that adds 1 to a hit at 254
        if (stream.size() > nMask)
          stream[nMask + uint32_t(rng()) % (stream.size() - nMask)] += uint8_t(1 + uint32_t(rng()) % 255);
        break;
      case 2:  // a mask bit flipped: the residual count no longer matches
        stream[uint32_t(rng()) % nMask] ^= uint8_t(1u << (uint32_t(rng()) % 8));
        break;
      default:  // cut short, or a byte too many
        if (uint32_t(rng()) % 2)
          stream.resize(uint32_t(rng()) % stream.size());
        else
          stream.push_back(0);
    }
    expectSameDecode(m, stream, raw.size(), what);
  }
}

TEST(HitsMed, FastDecoderReportsTheFirstBadHitOfTheBlock) {
  // Residuals that make a hit of each later map decode to 255: the error names the first one, in a
  // group of 16 maps or in the maps after the last whole group.
  std::mt19937 rng(3);
  for (uint32_t maps : {16u, 35u}) {
    const auto raw = randomBlock(rng, 64, maps);
    const auto clean = detail::applyFilter(Filter::kHitsMed, {64, 1}, raw);
    const uint64_t nMask = (raw.size() + 7) / 8;
    for (uint64_t at = nMask; at < clean.size(); at += 1 + uint32_t(rng()) % 3000) {
      auto stream = clean;
      for (uint64_t j = at; j < stream.size(); j += 997) stream[j] = uint8_t(stream[j] + 1 + uint32_t(rng()) % 255);
      expectSameDecode(64, stream, raw.size(),
                       "M 64, " + std::to_string(maps) + " maps, residual " + std::to_string(at));
    }
  }
}

TEST(HitsMed, FastDecoderOnRandomStreams) {
  // Masks and residuals that no writer made: both decoders still agree, hit for hit.
  std::mt19937 rng(11);
  for (int round = 0; round < 100; ++round) {
    const uint32_t m = kResolutions[uint32_t(rng()) % std::size(kResolutions)];
    const uint32_t maps = 1 + uint32_t(rng()) % 40;
    const uint64_t texels = uint64_t(maps) * m * m;
    std::vector<uint8_t> stream((texels + 7) / 8);
    const uint32_t density = uint32_t(rng()) % 9;  // 0: no hit ... 8: all hits
    uint64_t hits = 0;
    for (uint64_t t = 0; t < texels; ++t)
      if (uint32_t(rng()) % 8 < density) stream[t / 8] |= uint8_t(1u << (t % 8)), ++hits;
    // Small residuals mostly, so that most streams decode; now and then any byte.
    for (uint64_t h = 0; h < hits; ++h)
      stream.push_back(uint32_t(rng()) % 64 ? uint8_t(uint32_t(rng()) % 5 - 2) : uint8_t(uint32_t(rng())));
    expectSameDecode(m, stream, texels,
                     "M " + std::to_string(m) + ", " + std::to_string(maps) + " maps, round " + std::to_string(round));
  }
}

}  // namespace
}  // namespace vff
