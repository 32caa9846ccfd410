// synthetic_field.h - fields with known contents, made without the baker: a small field
// description, deterministic pseudo-random distance codes and normals (the unit and scene tests, the
// cli fixtures), and the integer hash behind them (also convert_check's inputs).
#pragma once

#include <cstdint>
#include <vector>

#include "vff/vff.h"

namespace vff::test {

inline FieldDesc smallField(DistanceEncoding enc, NormalEncoding normals = NormalEncoding::kNone,
                            uint32_t n = 1, uint32_t m = 8) {
  FieldDesc f;
  f.sphere = {{0.5f, -1.0f, 2.0f}, 1.5f};
  f.positionScheme = PositionScheme::kOctaHemi2;
  f.positionParam = n;
  f.mapCount = positionCount(PositionScheme::kOctaHemi2, n).value();
  f.directionScheme = DirectionScheme::kConcentricEqualArea;
  f.mapResolution = m;
  f.distanceEncoding = enc;
  f.normalEncoding = normals;
  return f;
}

// Deterministic pseudo-random bytes: distance codes with some misses, normals zero where missed.
inline uint32_t hashMix(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7feb352dU;
  x ^= x >> 15;
  x *= 0x846ca68bU;
  x ^= x >> 16;
  return x;
}

inline std::vector<uint8_t> syntheticDistance(const FieldDesc& f) {
  if (f.distanceEncoding == DistanceEncoding::kBc4Diameter) {  // unorm8-diameter codes, then BC4 blocks
    FieldDesc u8 = f;
    u8.distanceEncoding = DistanceEncoding::kUnorm8Diameter;
    const std::vector<uint8_t> codes = syntheticDistance(u8);
    const uint64_t texels = uint64_t(f.mapResolution) * f.mapResolution;
    std::vector<uint8_t> d(texels / 2 * f.mapCount);
    for (uint32_t k = 0; k < f.mapCount; ++k)
      encodeBc4Map(std::span<const uint8_t>(codes).subspan(k * texels, texels), f.mapResolution,
                   std::span<uint8_t>(d).subspan(k * texels / 2, texels / 2));
    return d;
  }
  std::vector<uint8_t> d(distanceMapBytes(f.distanceEncoding, f.mapResolution) * f.mapCount, 0);
  const uint32_t m = f.mapResolution;
  const uint64_t mb = distanceMapBytes(f.distanceEncoding, m);
  for (uint32_t k = 0; k < f.mapCount; ++k)
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        const uint32_t h = hashMix(k * 7919u + j * 131u + i);
        const bool hit = (h % 5) != 0;
        const uint32_t code = hit ? h % (maxHitCode(f.distanceEncoding) + 1) : missCode(f.distanceEncoding);
        storeCode(f.distanceEncoding, std::span<uint8_t>(d).subspan(k * mb, mb), m, i, j,
                  f.distanceEncoding == DistanceEncoding::kBit1 ? (hit ? 1 : 0) : code);
      }
  return d;
}

inline std::vector<uint8_t> syntheticNormals(const FieldDesc& f, const std::vector<uint8_t>& dist) {
  const uint32_t m = f.mapResolution;
  const uint64_t mb = distanceMapBytes(f.distanceEncoding, m);
  std::vector<uint8_t> n(uint64_t(f.mapCount) * m * m * 4, 0);
  for (uint32_t k = 0; k < f.mapCount; ++k)
    for (uint32_t t = 0; t < m * m; ++t) {
      const uint32_t code = loadCode(f.distanceEncoding, std::span<const uint8_t>(dist).subspan(k * mb, mb), m, t % m, t / m);
      if (!decodeDistance(f.distanceEncoding, code, 1, 1).hit) continue;
      const uint32_t h = hashMix(k * 31u + t);
      Vec3 v{float(int(h % 200) - 100), float(int((h >> 8) % 200) - 100), float(int((h >> 16) % 200) - 99)};
      encodeNormal(v, &n[(uint64_t(k) * m * m + t) * 4]);
    }
  return n;
}

}  // namespace vff::test
