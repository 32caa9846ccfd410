// sdf_cases.h - the distance-field peer's GPU-vs-CPU comparison, defined once for the GL suite
// (test_gpu_sdf.cpp) and the Vulkan suite (test_vk_sdf.cpp, GLSL and HLSL): the grids, the rays,
// the tolerances, and one run's answers checked against the CPU tracer (sdf/src/sdf_field.cpp).
//
// Tolerances. Both tracers run in binary32 (the grid's float map, float samples and steps), the
// same operations in the same order; they can part only where the GPU rounds differently (llvmpipe
// and lavapipe contract a * b + c into fused multiply-adds, their length() and divisions are not
// the CPU's to the last bit). A sample within rounding of hitVoxels then hits on one side and takes
// one more step (at least minStepVoxels) on the other, and a step whose length rounds differently
// can land on either side of a block's exit. So: hit flags may differ on at most kMaxFlipShare of
// the rays; where both hit, t within kTightVoxels voxels on at least kTightShare of them, and within
// kLooseVoxels (one step below the hit threshold plus the threshold itself) on all; the cone
// estimate within kConeVis on all but kMaxFlipShare of the rays.
//
// A GPU run answers four floats a ray: hit (0 or 1), t, steps, visibility (the kernels' kRayMain).
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

#include "vff/bake/mesh.h"
#include "vff/bake/sphere.h"
#include "vff/sdf/sdf_field.h"

namespace vff::sdftest {

inline constexpr double kMaxFlipShare = 0.002;
inline constexpr double kTightVoxels = 1e-4;
inline constexpr double kTightShare = 0.99;
inline constexpr double kLooseVoxels = 0.5;
inline constexpr double kConeVis = 1e-4;  // the cone estimate, where the traces agree

inline vffx::SdfField buildSdf(const bake::Mesh& m, uint64_t budget, vffx::SdfValues values) {
  auto sdf = vffx::SdfField::build(m, {.budgetBytes = budget, .values = values});
  if (!sdf) ADD_FAILURE() << sdf.error().toString();
  return std::move(*sdf);
}

inline Sphere boundingSphere(const bake::Mesh& m) { return bake::minimalEnclosingSphere(m.positions); }

// Rays from outside the sphere aimed at points inside it (3 in 4), and from inside (1 in 4); some
// with non-unit directions and a finite tmax.
inline std::vector<Ray> makeRays(const Sphere& s, uint32_t n, uint64_t seed) {
  std::mt19937_64 g(seed);
  std::normal_distribution<float> nd;
  std::uniform_real_distribution<float> u(0, 1);
  auto dir = [&] {
    Vec3 v{nd(g), nd(g), nd(g)};
    const float l = std::sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return Vec3{v.x / l, v.y / l, v.z / l};
  };
  const Vec3 c{s.center[0], s.center[1], s.center[2]};
  const float R = s.radius;
  std::vector<Ray> rays(n);
  for (uint32_t i = 0; i < n; ++i) {
    Vec3 o, d;
    float tmax = INFINITY;
    if (i % 4 != 3) {
      const Vec3 a = dir(), b = dir();
      const float r0 = R * (1.1f + u(g)), r1 = R * 0.8f * std::cbrt(u(g));
      o = {c.x + a.x * r0, c.y + a.y * r0, c.z + a.z * r0};
      d = {c.x + b.x * r1 - o.x, c.y + b.y * r1 - o.y, c.z + b.z * r1 - o.z};
      if (i % 8 == 2) d = {d.x * 0.4f, d.y * 0.4f, d.z * 0.4f};
      if (i % 16 == 4) tmax = 1.2f * u(g);
    } else {
      const Vec3 a = dir();
      const float r0 = R * 0.9f * std::cbrt(u(g));
      o = {c.x + a.x * r0, c.y + a.y * r0, c.z + a.z * r0};
      d = dir();
    }
    rays[i] = Ray{o, d, 0.0f, tmax};
  }
  return rays;
}

// The rays as the kernels read them: origin.xyz, tmin, direction.xyz, tmax (two vec4 a ray).
inline std::vector<float> packRays(const std::vector<Ray>& rays) {
  std::vector<float> in(rays.size() * 8);
  for (size_t i = 0; i < rays.size(); ++i) {
    const Ray& r = rays[i];
    const float v[8] = {r.origin.x, r.origin.y, r.origin.z, r.tmin, r.direction.x, r.direction.y, r.direction.z, r.tmax};
    std::copy(v, v + 8, &in[i * 8]);
  }
  return in;
}

// The rays capped at 4 R along the ray (a finite tmax sets coneRadiusAtEnd's cone).
inline std::vector<Ray> capRays(std::vector<Ray> rays, float radius) {
  for (Ray& r : rays)
    r.tmax = std::min(r.tmax, 4.0f * radius /
                                  std::sqrt(r.direction.x * r.direction.x + r.direction.y * r.direction.y +
                                            r.direction.z * r.direction.z));
  return rays;
}

// A GPU run's answers (`out`, traced without a cone) against SdfField::intersect; prints the counts.
inline void expectTracerMatches(const char* api, const char* what, const vffx::SdfField& sdf,
                                const std::vector<Ray>& rays, const std::vector<float>& out) {
  ASSERT_EQ(out.size(), rays.size() * 4);
  size_t hits = 0, flips = 0, both = 0, tight = 0;
  double worst = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const vffx::SdfHit c = sdf.intersect(rays[i]);
    const bool g = out[i * 4] != 0;
    EXPECT_EQ(out[i * 4 + 3], g ? 0.0f : 1.0f) << "without a cone, visibility is 0 or 1";
    hits += c.hit;
    if (c.hit != g) {
      ++flips;
      continue;
    }
    if (!c.hit) continue;
    ++both;
    // |t difference| in voxels: t is in multiples of the direction.
    const Vec3& d = rays[i].direction;
    const double len = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
    const double dv = std::fabs(double(out[i * 4 + 1]) - double(c.t)) * len / double(sdf.voxelSize());
    worst = std::max(worst, dv);
    tight += dv <= kTightVoxels;
    EXPECT_LE(dv, kLooseVoxels) << what << " ray " << i << ": CPU t " << c.t << ", GPU t " << out[i * 4 + 1];
  }
  std::printf(
      "[ %s ] sdf %s (%s, voxel %.4g, NanoVDB %llu bytes): %zu rays, %zu hits; hit flags differ on %zu; "
      "where both hit (%zu): t within %.0e voxels on %zu, worst %.3g voxels\n",
      api, what, sdf.values() == vffx::SdfValues::kFp8 ? "fp8" : "float", double(sdf.voxelSize()),
      (unsigned long long)sdf.nanovdbBytes(), rays.size(), hits, flips, both, kTightVoxels, tight, worst);
  EXPECT_GT(hits, rays.size() / 4) << "too few hits for the test to mean anything";
  EXPECT_LE(double(flips), kMaxFlipShare * double(rays.size()));
  EXPECT_GE(double(tight), kTightShare * double(both));
}

// A GPU run's cone estimates (out[i * 4 + 3], traced with `o`) against SdfField::visibility: the
// minimum over the same steps of the same expression, so within rounding where the traces agree.
inline void expectConeMatches(const char* api, const vffx::SdfField& sdf, const vffx::SdfTraceOptions& o,
                              const std::vector<Ray>& rays, const std::vector<float>& out) {
  ASSERT_EQ(out.size(), rays.size() * 4);
  std::vector<float> cpu(rays.size());
  sdf.visibility(rays, cpu, o);
  size_t off = 0, partial = 0;
  double worst = 0;
  for (size_t i = 0; i < rays.size(); ++i) {
    const double e = std::fabs(double(out[i * 4 + 3]) - double(cpu[i]));
    off += e > kConeVis;
    partial += cpu[i] > 0 && cpu[i] < 1;
    worst = std::max(worst, e);
  }
  std::printf("[ %s ] sdf cone estimate (%s): %zu rays, %zu with a partial estimate; %zu differ by over %.0e, worst %.3g\n",
              api, o.coneTan > 0 ? "coneTan" : "coneRadiusAtEnd", rays.size(), partial, off, kConeVis, worst);
  EXPECT_GT(partial, rays.size() / 8) << "too few partial estimates for the test to mean anything";
  EXPECT_LE(double(off), kMaxFlipShare * double(rays.size()));
}

}  // namespace vff::sdftest
