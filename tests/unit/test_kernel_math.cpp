// The group kernel's per-lane maths (libvff/src/query/batch/kernel_math.h) against the one-ray steps they
// mirror, bit for bit: each lane of the SSE2 lane type (every x86-64 CPU runs it) must give
// exactly what hemisphereToSquareFast, frameFromNormal + toLocal and decodeNormal give, so that a
// change to either side that lets them drift apart fails here, not only in the batch tests.
#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include "vff/vff.h"

#if defined(__SSE2__) && (defined(__x86_64__) || defined(_M_X64))
#include "query/batch/simd/vfloat4_sse2.h"  // private: the lane type under test
#include "query/batch/kernel_math.h"        // private: the per-lane maths

using namespace vff;

namespace {

constexpr size_t kLanes = detail::F4::kLanes;

// Unit directions on the z >= 0 side, with the concentric map's special cases (axes, diagonals).
std::vector<Vec3> localDirections() {
  std::vector<Vec3> dirs = {{0, 0, 1}, {1, 0, 0}, {0, -1, 0}, {1, 1, 0}, {-1, 1, 1}, {1, -1, 0.5f}, {0, 1, 1e-3f}};
  std::mt19937 rng(11);
  std::normal_distribution<float> g;
  for (int r = 0; r < 100000; ++r) dirs.push_back({g(rng), g(rng), std::fabs(g(rng))});
  for (Vec3& d : dirs) {
    const float l = std::sqrt(d.x * d.x + d.y * d.y + d.z * d.z);
    d = {d.x / l, d.y / l, d.z / l};
  }
  while (dirs.size() % kLanes) dirs.push_back({0, 0, 1});
  return dirs;
}

detail::F4 lanes(const float* v) { return detail::F4::load(v); }

void store4(const detail::F4& x, float out[kLanes]) { detail::store(out, x); }

}  // namespace

TEST(KernelMath, HemisphereToSquareLanesEqualTheFastLookupBitForBit) {
  const std::vector<Vec3> dirs = localDirections();
  for (DirectionScheme scheme : {DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral}) {
    size_t checked = 0;
    for (size_t base = 0; base < dirs.size(); base += kLanes) {
      float x[kLanes], y[kLanes], z[kLanes], a[kLanes], b[kLanes];
      for (size_t l = 0; l < kLanes; ++l) {
        x[l] = dirs[base + l].x;
        y[l] = dirs[base + l].y;
        z[l] = dirs[base + l].z;
      }
      detail::F4 va, vb;
      detail::hemisphereToSquareV<true>(scheme, lanes(x), lanes(y), lanes(z), &va, &vb);
      store4(va, a);
      store4(vb, b);
      for (size_t l = 0; l < kLanes; ++l) {
        const Vec2 f = detail::hemisphereToSquareFast(scheme, dirs[base + l]);
        ASSERT_EQ(std::bit_cast<uint32_t>(a[l]), std::bit_cast<uint32_t>(f.x)) << "scheme " << int(scheme) << " dir " << base + l;
        ASSERT_EQ(std::bit_cast<uint32_t>(b[l]), std::bit_cast<uint32_t>(f.y)) << "scheme " << int(scheme) << " dir " << base + l;
        ++checked;
      }
    }
    EXPECT_EQ(checked, dirs.size());
  }
}

// The octahedral map has no approximation: its fast version is the reference, bit for bit.
TEST(KernelMath, HemiOctahedralFastSquareIsTheReferenceBitForBit) {
  for (const Vec3& d : localDirections()) {
    const Vec2 f = detail::hemisphereToSquareFast(DirectionScheme::kHemiOctahedral, d);
    const Vec2 r = hemisphereToSquare(DirectionScheme::kHemiOctahedral, d);
    ASSERT_EQ(std::bit_cast<uint32_t>(f.x), std::bit_cast<uint32_t>(r.x));
    ASSERT_EQ(std::bit_cast<uint32_t>(f.y), std::bit_cast<uint32_t>(r.y));
  }
}

TEST(KernelMath, SampleFrameLanesEqualFrameFromNormalAndToLocalBitForBit) {
  const std::vector<Vec3> dirs = localDirections();
  std::mt19937 rng(12);
  std::normal_distribution<float> g;
  for (size_t base = 0; base < dirs.size(); base += kLanes) {
    float ux[kLanes], uy[kLanes], uz[kLanes], vx[kLanes], vy[kLanes], vz[kLanes], lx[kLanes], ly[kLanes], lz[kLanes];
    Vec3 u[kLanes];
    for (size_t l = 0; l < kLanes; ++l) {
      const float p = g(rng), q = g(rng), r = g(rng), n = std::sqrt(p * p + q * q + r * r);
      u[l] = {p / n, q / n, r / n};
      ux[l] = u[l].x, uy[l] = u[l].y, uz[l] = u[l].z;
      vx[l] = dirs[base + l].x, vy[l] = dirs[base + l].y, vz[l] = dirs[base + l].z;
    }
    detail::F4 ox, oy, oz;
    detail::toSampleFrame(lanes(ux), lanes(uy), lanes(uz), lanes(vx), lanes(vy), lanes(vz), &ox, &oy, &oz);
    store4(ox, lx);
    store4(oy, ly);
    store4(oz, lz);
    for (size_t l = 0; l < kLanes; ++l) {
      const Vec3 ref = toLocal(frameFromNormal({-u[l].x, -u[l].y, -u[l].z}), dirs[base + l]);
      ASSERT_EQ(std::bit_cast<uint32_t>(lx[l]), std::bit_cast<uint32_t>(ref.x));
      ASSERT_EQ(std::bit_cast<uint32_t>(ly[l]), std::bit_cast<uint32_t>(ref.y));
      ASSERT_EQ(std::bit_cast<uint32_t>(lz[l]), std::bit_cast<uint32_t>(ref.z));
    }
  }
}

TEST(KernelMath, NormalLanesEqualDecodeNormalBitForBit) {
  std::mt19937 rng(13);
  std::uniform_int_distribution<int> code(-32768, 32767);
  for (int round = 0; round < 20000; ++round) {
    float cx[kLanes], cy[kLanes], nx[kLanes], ny[kLanes], nz[kLanes];
    uint8_t bytes[kLanes][4];
    for (size_t l = 0; l < kLanes; ++l) {
      const int16_t a = int16_t(code(rng)), b = int16_t(code(rng));
      cx[l] = float(a);
      cy[l] = float(b);
      bytes[l][0] = uint8_t(uint16_t(a) & 0xFF), bytes[l][1] = uint8_t(uint16_t(a) >> 8);
      bytes[l][2] = uint8_t(uint16_t(b) & 0xFF), bytes[l][3] = uint8_t(uint16_t(b) >> 8);
    }
    detail::F4 x, y, z;
    detail::decodeNormalV(lanes(cx), lanes(cy), &x, &y, &z);
    store4(x, nx);
    store4(y, ny);
    store4(z, nz);
    for (size_t l = 0; l < kLanes; ++l) {
      const Vec3 ref = decodeNormal(bytes[l]);
      ASSERT_EQ(std::bit_cast<uint32_t>(nx[l]), std::bit_cast<uint32_t>(ref.x)) << cx[l] << " " << cy[l];
      ASSERT_EQ(std::bit_cast<uint32_t>(ny[l]), std::bit_cast<uint32_t>(ref.y)) << cx[l] << " " << cy[l];
      ASSERT_EQ(std::bit_cast<uint32_t>(nz[l]), std::bit_cast<uint32_t>(ref.z)) << cx[l] << " " << cy[l];
    }
  }
}

#endif
