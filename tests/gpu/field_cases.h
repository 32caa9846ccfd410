// field_cases.h - what the GL, Vulkan and WebGPU query suites run, defined once so that every API
// answers the same questions: the baked cases (kNearest: nearestCases; normals and kInterpolated:
// interpolatedCases), the valid conformance vectors and their gtest names, the random rays, and
// the normals and kInterpolated comparison of one answer (compareInterpolated, reportInterpolated).
//
// The rays are built into any struct with float origin[4], direction[4] and range[4] (tmin, tmax,
// intraBias, unused): the GL tests' std430 GpuRay, vff::vk::QueryRay and wgsltest::QueryRay are
// all that layout.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>
#include <system_error>
#include <vector>

#include "baked_fields.h"
#include "common/rng.h"
#include "vff/vff.h"

namespace vff::gputest {

// The normals and kInterpolated suites' tolerances (test_gpu_field.cpp, test_vk_query.cpp): normals
// of agreeing hits; a tie of the vote (visibility this near 0.5); t, as a fraction of R; visibility.
inline constexpr double kNormalEps = 1e-5;
inline constexpr double kVoteEps = 1e-4;
inline constexpr double kInterpT = 1e-4;
inline constexpr double kInterpVis = 1e-4;

// kNearest: the three position schemes x both direction schemes x the four uncompressed encodings,
// the 3D target once per encoding family, bc4-diameter (2D arrays only) once per direction scheme.
inline std::vector<FieldCase> nearestCases() {
  std::vector<FieldCase> cases;
  for (auto p : {PositionScheme::kOctaHemi2, PositionScheme::kEqualAreaOctaGrid, PositionScheme::kSphericalFibonacci})
    for (auto d : {DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral})
      for (auto e : {DistanceEncoding::kUnorm8Diameter, DistanceEncoding::kUnorm8Chord,
                     DistanceEncoding::kUnorm16Diameter, DistanceEncoding::kBit1})
        cases.push_back({p, d, e});
  cases.push_back({PositionScheme::kOctaHemi2, DirectionScheme::kConcentricEqualArea,
                   DistanceEncoding::kUnorm16Diameter, LayoutTarget::kTexture3D});
  cases.push_back({PositionScheme::kSphericalFibonacci, DirectionScheme::kHemiOctahedral, DistanceEncoding::kBit1,
                   LayoutTarget::kTexture3D});
  for (auto d : {DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral})
    cases.push_back({PositionScheme::kOctaHemi2, d, DistanceEncoding::kBc4Diameter});
  return cases;
}

// Normals and kInterpolated (baked with a normal plane): unorm8-diameter in every scheme pair, plus
// unorm8-chord, unorm16-diameter in a 3D texture and bit1.
inline std::vector<FieldCase> interpolatedCases() {
  std::vector<FieldCase> cases;
  for (auto p : {PositionScheme::kOctaHemi2, PositionScheme::kEqualAreaOctaGrid, PositionScheme::kSphericalFibonacci})
    for (auto d : {DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral})
      cases.push_back({p, d, DistanceEncoding::kUnorm8Diameter});
  cases.push_back({PositionScheme::kOctaHemi2, DirectionScheme::kHemiOctahedral, DistanceEncoding::kUnorm8Chord});
  cases.push_back({PositionScheme::kSphericalFibonacci, DirectionScheme::kConcentricEqualArea,
                   DistanceEncoding::kUnorm16Diameter, LayoutTarget::kTexture3D});
  cases.push_back({PositionScheme::kEqualAreaOctaGrid, DirectionScheme::kConcentricEqualArea, DistanceEncoding::kBit1});
  return cases;
}

// spec/conformance/valid/*.vff by glob (a vector added there is run without registering it), stems.
inline std::vector<std::string> validVectors() {
  std::vector<std::string> names;
  const std::filesystem::path dir = std::filesystem::path(VFF_SOURCE_DIR) / "spec/conformance/valid";
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.path().extension() == ".vff") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

inline std::string vectorPath(const std::string& stem) {
  return std::string(VFF_SOURCE_DIR) + "/spec/conformance/valid/" + stem + ".vff";
}

// A vector's gtest name: its stem with every character that is not a letter or digit as '_'.
inline std::string vectorName(const std::string& stem) {
  std::string s = stem;
  for (char& ch : s)
    if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
  return s;
}

// The name generators of INSTANTIATE_TEST_SUITE_P.
inline std::string caseParamName(const ::testing::TestParamInfo<FieldCase>& i) {
  return caseName(i.param);
}
inline std::string vectorParamName(const ::testing::TestParamInfo<std::string>& i) {
  return vectorName(i.param);
}

namespace rays {
inline Vec3 add(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 sub(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 mul(Vec3 a, float s) {
  return {a.x * s, a.y * s, a.z * s};
}
}  // namespace rays

// kNearest's random rays: half from outside the sphere towards points inside it (a few miss the
// sphere), half from inside; some non-unit directions and finite ranges; intra bias -1, 0, 0.02.
template <class GpuRay>
std::vector<GpuRay> nearestRays(const FieldDesc& f, uint32_t count, uint64_t seed) {
  using namespace rays;
  test::Rng rng(seed);
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float R = f.sphere.radius;
  std::vector<GpuRay> out(count);
  const float biases[3] = {-1.0f, 0.0f, 0.02f};
  for (uint32_t r = 0; r < count; ++r) {
    Vec3 o, d;
    float tmin = 0, tmax = INFINITY;
    if (r % 2 == 0) {
      o = add(c, mul(rng.direction(), R * (1.05f + 2.0f * rng.uniform())));
      const Vec3 target = add(c, mul(rng.direction(), R * 1.1f * std::cbrt(rng.uniform())));
      d = sub(target, o);
      if (r % 8 == 2) d = mul(d, 0.5f + 3 * rng.uniform());  // non-unit directions
      if (r % 16 == 4) tmax = 1.5f * rng.uniform();          // finite ranges
      if (r % 16 == 6) tmin = 0.5f * rng.uniform();
    } else {
      o = add(c, mul(rng.direction(), R * 0.95f * std::cbrt(rng.uniform())));
      d = rng.direction();
      if (r % 16 == 5) tmax = R * rng.uniform();
    }
    out[r] = GpuRay{{o.x, o.y, o.z, 0}, {d.x, d.y, d.z, 0}, {tmin, tmax, biases[r % 3], 0}};
  }
  return out;
}

// Normals' and kInterpolated's random rays: mostly from outside (the interpolated path), some from
// inside, short rays from inside off the object (intraBias -2, VFF_OFF_OBJECT: section 7.4).
template <class GpuRay>
std::vector<GpuRay> interpolatedRays(const FieldDesc& f, uint32_t count, uint64_t seed) {
  test::Rng rng(seed);
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float R = f.sphere.radius;
  std::vector<GpuRay> out(count);
  for (uint32_t r = 0; r < count; ++r) {
    Vec3 o, d;
    float tmin = 0, tmax = INFINITY;
    if (r % 4 != 3) {
      const Vec3 a = rng.direction(), b = rng.direction();
      const float s = R * (1.05f + 2.0f * rng.uniform()), s2 = R * 1.1f * std::cbrt(rng.uniform());
      o = Vec3{c.x + a.x * s, c.y + a.y * s, c.z + a.z * s};
      d = Vec3{c.x + b.x * s2 - o.x, c.y + b.y * s2 - o.y, c.z + b.z * s2 - o.z};
      if (r % 8 == 2) d = Vec3{d.x * 2.5f, d.y * 2.5f, d.z * 2.5f};
      if (r % 16 == 4) tmax = 1.5f * rng.uniform();
    } else {
      // Sequenced (not as two arguments of one call) so that every compiler draws the same rays.
      const Vec3 a = rng.direction();
      const float s = R * 0.95f * std::cbrt(rng.uniform());
      o = Vec3{c.x + a.x * s, c.y + a.y * s, c.z + a.z * s};
      d = rng.direction();
    }
    if (r % 8 == 7) tmax = 0.6f * R * rng.uniform();  // short rays from inside: the contact case
    const float bias = r % 8 == 7 ? -2.0f : r % 3 == 0 ? 0.0f : -1.0f;
    out[r] = GpuRay{{o.x, o.y, o.z, 0}, {d.x, d.y, d.z, 0}, {tmin, tmax, bias, 0}};
  }
  return out;
}

// ---- Normals and kInterpolated: one answer against FieldQuery ---------------------------------------

inline double maxDiff3(const float* g, Vec3 c) {
  return std::max({std::fabs(double(g[0]) - c.x), std::fabs(double(g[1]) - c.y), std::fabs(double(g[2]) - c.z)});
}

struct InterpCounts {
  uint64_t rays = 0, nNormals = 0, nFlag = 0, iAgree = 0, iTie = 0, iHits = 0, fails = 0;
  double nMax = 0, iMaxT = 0, iMaxVis = 0;
  std::string first;
  void fail(size_t r, const std::string& why) {
    ++fails;
    if (first.empty()) first = "ray " + std::to_string(r) + ": " + why;
  }
};

// One ray: kNearest's normal, then kInterpolated's flag, t, visibility and normal. Answer: the
// Vulkan kernel's layout (vff::vk::QueryAnswer: flags kHit, kHasNormal, kInterpHit,
// kInterpHasNormal; t, normal, visibility, interpT, interpNormal).
template <class GpuRay, class Answer>
void compareInterpolated(const FieldQuery& cpu, const GpuRay& g, const Answer& o, float R, size_t r, InterpCounts& n) {
  ++n.rays;
  const Ray ray{{g.origin[0], g.origin[1], g.origin[2]},
                {g.direction[0], g.direction[1], g.direction[2]},
                g.range[0],
                g.range[1]};
  const Vec3 d = ray.direction;
  const double len = std::sqrt(double(d.x * d.x + d.y * d.y + d.z * d.z));
  QueryOptions qn;
  qn.intraBias = g.range[2];
  if (g.range[2] == -2.0f) qn.origin = RayOrigin::kOffObject;  // VFF_OFF_OBJECT
  const QueryHit h = cpu.intersect(ray, qn);
  if (((o.flags & Answer::kHit) != 0) != h.hit) {
    ++n.nFlag;  // test_gpu_query-style boundary rays; the GL suite sees none on these fields
  } else if (h.hit && std::fabs(double(o.t) - double(h.t)) * len <= 1e-5 * R) {
    if (((o.flags & Answer::kHasNormal) != 0) != h.hasNormal) return n.fail(r, "hasNormal differs");
    ++n.nNormals;
    const double e = maxDiff3(o.normal, h.normal);
    n.nMax = std::max(n.nMax, e);
    if (e > kNormalEps) return n.fail(r, "nearest normal differs by " + std::to_string(e));
  }
  QueryOptions qi = qn;
  qi.reconstruction = Reconstruction::kInterpolated;
  const QueryHit hi = cpu.intersect(ray, qi);
  const float vis = cpu.visibility(ray, qi);
  const double dv = std::fabs(double(o.visibility) - double(vis));
  n.iMaxVis = std::max(n.iMaxVis, dv);
  if (dv > kInterpVis) return n.fail(r, "visibility " + std::to_string(o.visibility) + " vs " + std::to_string(vis));
  if (((o.flags & Answer::kInterpHit) != 0) != hi.hit) {
    if (std::fabs(double(vis) - 0.5) > kVoteEps) return n.fail(r, "interpolated hit flag differs");
    ++n.iTie;
    return;
  }
  ++n.iAgree;
  if (!hi.hit) return;
  ++n.iHits;
  const double dt = std::fabs(double(o.interpT[0]) - double(hi.t)) * len / R;
  n.iMaxT = std::max(n.iMaxT, dt);
  if (dt > kInterpT) return n.fail(r, "interpolated t differs by " + std::to_string(dt) + " R");
  if (((o.flags & Answer::kInterpHasNormal) != 0) != hi.hasNormal) return n.fail(r, "interpolated hasNormal differs");
  if (hi.hasNormal && maxDiff3(o.interpNormal, hi.normal) > 1e-4) return n.fail(r, "interpolated normal differs");
}

// Prints the counts after `head` and checks what every suite requires of them.
inline void reportInterpolated(const InterpCounts& n, const std::string& head, const std::string& label) {
  std::printf(
      "%s: kNearest: %llu normals compared, max diff %.3g, hit-flag mismatches %llu; kInterpolated: "
      "%llu rays, agreement %.3f%%, vote ties %llu, failures %llu; %llu hits, max |t_gpu - t_cpu| = %.3g R, "
      "max |vis_gpu - vis_cpu| = %.3g\n",
      head.c_str(), (unsigned long long)n.nNormals, n.nMax, (unsigned long long)n.nFlag, (unsigned long long)n.rays,
      100.0 * double(n.iAgree) / double(std::max<uint64_t>(n.rays, 1)), (unsigned long long)n.iTie,
      (unsigned long long)n.fails, (unsigned long long)n.iHits, n.iMaxT, n.iMaxVis);
  EXPECT_EQ(n.fails, 0u) << label << ": " << n.first;
  EXPECT_EQ(n.nFlag, 0u) << label;
  EXPECT_GT(n.nNormals, n.rays / 8) << label;
  EXPECT_GT(n.iHits, n.rays / 8) << label;
}

}  // namespace vff::gputest
