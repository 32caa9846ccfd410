// rng.h - the tests' random numbers, seeded: what a test expects can depend on its seed and on these
// sequences, so neither generator may change.
//
//   Rng         std::mt19937_64 drawn as binary32 values, points, directions and placements (the
//               query, scene, Embree and GPU tests).
//   SplitMix64  a fixed sequence in binary64 that no standard library's distributions take part in
//               (the positional-sample tests).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <random>

#include "vff/vff.h"

namespace vff::test {

class Rng {
 public:
  explicit Rng(uint64_t seed) : g_(seed) {}

  // Uniform in [a, b): one binary64 draw in [0, 1), scaled in binary32.
  float uniform(float a = 0, float b = 1) {
    return a + (b - a) * float(std::uniform_real_distribution<double>(0, 1)(g_));
  }
  // Uniform on the unit sphere.
  Vec3 direction() {
    const float z = uniform(-1, 1), phi = uniform(0, 6.2831853f);
    const float r = std::sqrt(std::max(0.0f, 1 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
  }
  // Uniform in the cube [-extent, extent]^3.
  Vec3 point(float extent) { return {uniform(-extent, extent), uniform(-extent, extent), uniform(-extent, extent)}; }
  // Cosine-weighted around the unit normal n.
  Vec3 cosine(Vec3 n) {
    const float u = uniform(), phi = 6.2831853f * uniform();
    const float r = std::sqrt(u);
    const Frame f = frameFromNormal(n);
    return toWorld(f, {r * std::cos(phi), r * std::sin(phi), std::sqrt(std::max(0.0f, 1 - u))});
  }
  // A rotation by a uniform angle about a random axis, a translation in the cube [-extent, extent]^3
  // and a scale in [minScale, maxScale).
  RigidTransform transform(float extent, float minScale, float maxScale) {
    return RigidTransform::fromAxisAngle(direction(), uniform(0, 6.2831853f), point(extent),
                                         uniform(minScale, maxScale));
  }

 private:
  std::mt19937_64 g_;
};

// A binary64 vector (the positional-sample reference's arithmetic is in tests/unit/positions_reference.h).
struct D3 {
  double x = 0, y = 0, z = 0;
};

// SplitMix64: the same sequence with every compiler and standard library.
struct SplitMix64 {
  uint64_t s;
  uint64_t next() {
    uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return double(next() >> 11) * 0x1p-53; }  // [0, 1)
  D3 direction() {                                             // uniform on the sphere
    const double z = 2.0 * uniform() - 1.0, phi = 6.283185307179586 * uniform();
    const double r = std::sqrt(std::max(0.0, 1.0 - z * z));
    return {r * std::cos(phi), r * std::sin(phi), z};
  }
};

}  // namespace vff::test
