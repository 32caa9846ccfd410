#include "vff/encoding.h"

#include <algorithm>
#include <cmath>

#include "container/le.h"
#include "vff/bc4.h"

namespace vff {
namespace {

// The value a code scales against: 2R, or the chord 2R cos(alpha) of the texel-centre direction.
float scaleOf(DistanceEncoding e, float radius, float cosAlpha) noexcept {
  const float diameter = 2.0f * radius;
  return e == DistanceEncoding::kUnorm8Chord ? diameter * std::max(cosAlpha, 0.0f) : diameter;
}

}  // namespace

uint32_t encodeDistance(DistanceEncoding e, bool hit, float distance, float radius,
                        float cosAlpha) noexcept {
  if (e == DistanceEncoding::kBit1) return hit ? 1u : 0u;
  if (!hit) return missCode(e);
  const float top = float(maxHitCode(e));
  const float scale = scaleOf(e, radius, cosAlpha);
  if (!(scale > 0.0f) || !(distance > 0.0f)) return 0;  // NaN and non-positive distances clamp to 0
  const float q = std::nearbyint(std::min(distance / scale, 1.0f) * top);
  return uint32_t(std::clamp(q, 0.0f, top));
}

Texel decodeDistance(DistanceEncoding e, uint32_t code, float radius, float cosAlpha) noexcept {
  if (e == DistanceEncoding::kBit1) return {code != 0, 0.0f};
  if (code >= missCode(e) || e == DistanceEncoding::kInvalid) return {false, 0.0f};
  const float scale = scaleOf(e, radius, cosAlpha);
  return {true, float(code) * scale / float(maxHitCode(e))};
}

float quantizationStep(DistanceEncoding e, float radius, float cosAlpha) noexcept {
  if (e == DistanceEncoding::kBit1 || e == DistanceEncoding::kInvalid) return 0.0f;
  return scaleOf(e, radius, cosAlpha) / float(maxHitCode(e));
}

uint32_t loadCode(DistanceEncoding e, std::span<const uint8_t> map, uint32_t m, uint32_t i,
                  uint32_t j) noexcept {
  const size_t t = size_t(j) * m + i;
  switch (e) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kUnorm8Chord: return map[t];
    case DistanceEncoding::kUnorm16Diameter: return detail::loadU16(&map[2 * t]);
    case DistanceEncoding::kBit1: return (map[t / 8] >> (t % 8)) & 1u;
    case DistanceEncoding::kBc4Diameter:
      return bc4Texel(&map[(size_t(j / 4) * (m / 4) + i / 4) * kBc4BlockBytes], (j % 4) * 4 + i % 4);
    case DistanceEncoding::kInvalid: break;
  }
  return 0;
}

void storeCode(DistanceEncoding e, std::span<uint8_t> map, uint32_t m, uint32_t i, uint32_t j,
               uint32_t code) noexcept {
  const size_t t = size_t(j) * m + i;
  switch (e) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kUnorm8Chord: map[t] = uint8_t(code); break;
    case DistanceEncoding::kUnorm16Diameter: detail::store<uint16_t>(&map[2 * t], uint16_t(code)); break;
    case DistanceEncoding::kBit1: {
      const uint8_t bit = uint8_t(1u << (t % 8));
      map[t / 8] = code ? uint8_t(map[t / 8] | bit) : uint8_t(map[t / 8] & ~bit);
      break;
    }
    case DistanceEncoding::kBc4Diameter:  // blocks are encoded whole (encodeBc4Map)
    case DistanceEncoding::kInvalid: break;
  }
}

void encodeNormal(Vec3 n, uint8_t out[4]) noexcept {
  const float l1 = std::fabs(n.x) + std::fabs(n.y) + std::fabs(n.z);
  float px = 0.0f, py = 0.0f;
  if (l1 > 0.0f && std::isfinite(l1)) {
    px = n.x / l1;
    py = n.y / l1;
    if (n.z < 0.0f) {
      const float ox = (1.0f - std::fabs(py)) * (px >= 0.0f ? 1.0f : -1.0f);
      const float oy = (1.0f - std::fabs(px)) * (py >= 0.0f ? 1.0f : -1.0f);
      px = ox;
      py = oy;
    }
  }
  const auto q = [](float v) {
    return int16_t(std::nearbyint(std::clamp(v, -1.0f, 1.0f) * 32767.0f));
  };
  detail::store<int16_t>(out, q(px));
  detail::store<int16_t>(out + 2, q(py));
}

Vec3 decodeNormal(const uint8_t in[4]) noexcept {
  const float px = std::max(float(detail::load<int16_t>(in)) / 32767.0f, -1.0f);
  const float py = std::max(float(detail::load<int16_t>(in + 2)) / 32767.0f, -1.0f);
  Vec3 n{px, py, 1.0f - std::fabs(px) - std::fabs(py)};
  if (n.z < 0.0f) {
    const float ox = (1.0f - std::fabs(n.y)) * (n.x >= 0.0f ? 1.0f : -1.0f);
    const float oy = (1.0f - std::fabs(n.x)) * (n.y >= 0.0f ? 1.0f : -1.0f);
    n.x = ox;
    n.y = oy;
  }
  const float len = std::sqrt(n.x * n.x + n.y * n.y + n.z * n.z);
  return {n.x / len, n.y / len, n.z / len};
}

}  // namespace vff
