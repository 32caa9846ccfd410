#include "vff/direction.h"

#include <algorithm>
#include <cmath>

namespace vff {
namespace {
constexpr float kPi = 3.14159265358979323846f;
constexpr float kQuarterPi = kPi / 4;
}  // namespace

Frame frameFromNormal(Vec3 n) noexcept {
  const float s = n.z >= 0.0f ? 1.0f : -1.0f;
  const float a = -1.0f / (s + n.z);
  const float k = n.x * n.y * a;
  Frame f;
  f.t = {1.0f + s * n.x * n.x * a, s * k, -s * n.x};
  f.b = {k, s + n.y * n.y * a, -n.y};
  f.n = n;
  return f;
}

Vec3 toLocal(const Frame& f, Vec3 w) noexcept {
  return {w.x * f.t.x + w.y * f.t.y + w.z * f.t.z, w.x * f.b.x + w.y * f.b.y + w.z * f.b.z,
          w.x * f.n.x + w.y * f.n.y + w.z * f.n.z};
}

Vec3 toWorld(const Frame& f, Vec3 l) noexcept {
  return {l.x * f.t.x + l.y * f.b.x + l.z * f.n.x, l.x * f.t.y + l.y * f.b.y + l.z * f.n.y,
          l.x * f.t.z + l.y * f.b.z + l.z * f.n.z};
}

Vec3 squareToHemisphere(DirectionScheme scheme, Vec2 uv) noexcept {
  const float a = std::clamp(uv.x, -1.0f, 1.0f), b = std::clamp(uv.y, -1.0f, 1.0f);
  if (scheme == DirectionScheme::kHemiOctahedral) {
    // Rotate the square by 45 degrees onto the octahedron's upper half |x| + |y| <= 1.
    const float x = (a + b) * 0.5f, y = (a - b) * 0.5f;
    const float z = 1.0f - std::fabs(x) - std::fabs(y);
    const float len = std::sqrt(x * x + y * y + z * z);
    return {x / len, y / len, z / len};
  }
  // Shirley-Chiu concentric square -> disk.
  float r, phi;
  if (a == 0.0f && b == 0.0f) {
    r = 0.0f;
    phi = 0.0f;
  } else if (std::fabs(a) > std::fabs(b)) {
    r = a;
    phi = kQuarterPi * (b / a);
  } else {
    r = b;
    phi = 2.0f * kQuarterPi - kQuarterPi * (a / b);
  }
  // Equal-area lift of the unit disk onto the hemisphere: z = 1 - r^2.
  const float r2 = r * r;
  const float s = r * std::sqrt(std::max(0.0f, 2.0f - r2));
  return {s * std::cos(phi), s * std::sin(phi), 1.0f - r2};
}

Vec2 hemisphereToSquare(DirectionScheme scheme, Vec3 d) noexcept {
  const float z = std::max(0.0f, d.z);
  if (scheme == DirectionScheme::kHemiOctahedral) {
    const float inv = 1.0f / (std::fabs(d.x) + std::fabs(d.y) + z);
    const float x = d.x * inv, y = d.y * inv;
    return {std::clamp(x + y, -1.0f, 1.0f), std::clamp(x - y, -1.0f, 1.0f)};
  }
  // Inverse equal-area lift: r = sqrt(1 - z), angle from (x, y).
  const float r = std::sqrt(std::max(0.0f, 1.0f - z));
  float phi = std::atan2(d.y, d.x);  // (-pi, pi]
  if (phi < -kQuarterPi) phi += 2.0f * kPi;  // [-pi/4, 7pi/4)
  float a, b;
  if (phi < kQuarterPi) {
    a = r;
    b = phi * a / kQuarterPi;
  } else if (phi < 3.0f * kQuarterPi) {
    b = r;
    a = -(phi - 2.0f * kQuarterPi) * b / kQuarterPi;
  } else if (phi < 5.0f * kQuarterPi) {
    a = -r;
    b = (phi - kPi) * a / kQuarterPi;
  } else {
    b = -r;
    a = -(phi - 6.0f * kQuarterPi) * b / kQuarterPi;
  }
  return {std::clamp(a, -1.0f, 1.0f), std::clamp(b, -1.0f, 1.0f)};
}

void squareToTexel(Vec2 uv, uint32_t m, uint32_t* i, uint32_t* j) noexcept {
  const float fm = float(m);
  const float fx = std::floor((uv.x + 1.0f) * 0.5f * fm);
  const float fy = std::floor((uv.y + 1.0f) * 0.5f * fm);
  *i = uint32_t(std::clamp(fx, 0.0f, fm - 1.0f));
  *j = uint32_t(std::clamp(fy, 0.0f, fm - 1.0f));
}

Vec2 texelCenter(uint32_t i, uint32_t j, uint32_t m) noexcept {
  const float fm = float(m);
  return {(2.0f * float(i) + 1.0f) / fm - 1.0f, (2.0f * float(j) + 1.0f) / fm - 1.0f};
}

Vec3 texelDirection(DirectionScheme scheme, uint32_t m, uint32_t i, uint32_t j) noexcept {
  return squareToHemisphere(scheme, texelCenter(i, j, m));
}

}  // namespace vff
