// nearest_check.h - the kNearest comparison of the GL, Vulkan and WebGPU query suites, defined once:
// the CPU's lookup step by step (cpuLookup), and one GPU answer classified against it (classify).
//
// A ray agrees when the lookup and the hit flag are the CPU's. A disagreement is allowed only where
// the CPU shows the ray within a small epsilon of a boundary:
//   sample boundary: the GPU's sample is as near to the entry point as the CPU's (dot products of
//                    the unit entry point within kSampleEps);
//   texel boundary:  same sample, and the CPU's (u, v) is within kTexelEps texels of the line
//                    between the two texels;
//   range boundary:  same texel, and the hit lies within kRangeEps * R of tmin, tmax or the bias;
//   bc4 rounding:    bc4-diameter, same texel: the texture unit computes the interpolated palette
//                    entries itself and may round them the other way (spec/format.md 7.4), so a
//                    hit's code may differ by one; its distance is then that code's, bit for bit.
// Everything else is "hard" and fails the test. When the texel agrees, the code must be the CPU's
// map value and the decoded distance bit-identical to the CPU query's.
//
// The GPU side is a GpuLookup, which each suite fills from its own answer struct.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "field_cases.h"
#include "vff/vff.h"

namespace vff::gputest {

constexpr double kSampleEps = 1e-5;  // dot-product difference of two equally near samples
constexpr double kTexelEps = 1e-3;   // texels from the texel boundary
constexpr double kRangeEps = 1e-5;   // fraction of R from tmin / tmax / bias

// The lookup of FieldQuery::intersect (kNearest), step by step with the public API, so that the test
// knows which sample and texel the CPU used and how close the ray was to their boundaries.
struct CpuLookup {
  bool looked = false, inside = false, hit = false;
  float t = INFINITY;  // in multiples of the direction
  float lo = 0, hi = 0, tLen = 0;
  Vec3 eu;
  uint32_t k = 0, i = 0, j = 0, code = 0;
  Vec2 uv;
  float distance = 0;
};

// The decode of libvff/src/query/query_impl.h (FieldQuery::Impl::texel); *hit: the code is a hit.
inline float decodeDistance(const FieldDesc& f, uint32_t code, uint32_t i, uint32_t j, bool* hit) {
  const float radius = f.sphere.radius;
  switch (f.distanceEncoding) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kBc4Diameter:  // loadCode decoded the block: a unorm8-diameter code
      *hit = code != 255u;
      return float(code) * (2.0f * radius / 254.0f);
    case DistanceEncoding::kUnorm16Diameter:
      *hit = code != 65535u;
      return float(code) * (2.0f * radius / 65534.0f);
    case DistanceEncoding::kUnorm8Chord: {
      *hit = code != 255u;
      const float cosAlpha = texelDirection(f.directionScheme, f.mapResolution, i, j).z;
      return float(code) * (2.0f * radius * cosAlpha / 254.0f);
    }
    case DistanceEncoding::kBit1:
      *hit = code != 0;
      return 0.0f;
    default:
      *hit = false;
      return 0.0f;
  }
}

inline float dot3(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

// `ray`: origin[4], direction[4], range[4] = tmin, tmax, intraBias (field_cases.h).
template <class GpuRay>
CpuLookup cpuLookup(const File& file, const PositionSet& ps, const GpuRay& ray) {
  using namespace rays;
  const FieldDesc& f = file.field();
  const Vec3 o{ray.origin[0], ray.origin[1], ray.origin[2]}, d{ray.direction[0], ray.direction[1], ray.direction[2]};
  CpuLookup c;
  const Vec3 center{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float radius = f.sphere.radius;
  const float len = std::sqrt(dot3(d, d));
  const Vec3 w = mul(d, 1.0f / len);
  c.lo = ray.range[0] * len;
  c.hi = ray.range[1] * len;
  const Vec3 delta = sub(o, center);
  const float beta = dot3(delta, w), gamma = dot3(delta, delta) - radius * radius;
  const float disc = beta * beta - gamma;
  if (!(disc >= 0)) return c;
  const float sq = std::sqrt(disc), t1 = -beta + sq;
  if (t1 < 0) return c;
  c.inside = gamma <= 0;
  float t0 = c.inside ? t1 : -beta - sq;
  if (!c.inside) t0 = std::max(t0, 0.0f);
  const Vec3 e = add(o, mul(w, t0));
  const Vec3 v = c.inside ? mul(w, -1.0f) : w;
  if (c.inside) {
    if (f.distanceEncoding == DistanceEncoding::kBit1) return c;
    c.lo = std::max(c.lo, (ray.range[2] >= 0 ? ray.range[2] : defaultIntraBias(f)) * radius);
  }
  c.eu = mul(sub(e, center), 1.0f / radius);
  c.k = ps.nearest(c.eu);
  c.uv = hemisphereToSquare(f.directionScheme, toLocal(ps.frame(c.k), v));
  squareToTexel(c.uv, f.mapResolution, &c.i, &c.j);
  auto map = file.mapData(Plane::kDistance, c.k);
  EXPECT_TRUE(map.ok());
  c.code = loadCode(f.distanceEncoding, *map, f.mapResolution, c.i, c.j);
  c.looked = true;
  bool hit = false;
  c.distance = decodeDistance(f, c.code, c.i, c.j, &hit);
  if (!hit) return c;
  const float t = c.inside ? t0 - c.distance : t0 + c.distance;
  c.tLen = t;
  if (t < c.lo || t > c.hi) return c;
  c.hit = true;
  c.t = t / len;
  return c;
}

// The step-by-step lookup is the CPU query, bit for bit.
template <class GpuRay>
void expectLookupIsCpuQuery(const FieldQuery& cpu, const GpuRay& ray, const CpuLookup& c, size_t r) {
  QueryOptions qo;
  qo.intraBias = ray.range[2];
  const QueryHit q = cpu.intersect(Ray{{ray.origin[0], ray.origin[1], ray.origin[2]},
                                       {ray.direction[0], ray.direction[1], ray.direction[2]},
                                       ray.range[0],
                                       ray.range[1]},
                                   qo);
  EXPECT_EQ(q.hit, c.hit) << "ray " << r;
  if (q.hit && c.hit) {
    EXPECT_EQ(q.t, c.t) << "ray " << r;
  }
}

// What the GPU answered for one ray (kNearest).
struct GpuLookup {
  bool looked = false, hit = false;
  float t = INFINITY;
  uint32_t k = 0, i = 0, j = 0, code = 0;
  float distance = 0;
};

struct Agreement {
  uint64_t rays = 0, agree = 0, sampleBoundary = 0, texelBoundary = 0, rangeBoundary = 0, bc4Rounding = 0, hard = 0;
  uint64_t exactDistances = 0, hits = 0;
  double maxTDiff = 0;  // over rays where both hit with the same texel, in units of R
  std::string firstHard;
};

// One ray's GPU answer against the CPU lookup; counts it into `a`.
template <class GpuRay>
void classify(const File& file, const PositionSet& ps, const GpuRay& ray, const CpuLookup& c, const GpuLookup& g,
              size_t r, Agreement& a) {
  const FieldDesc& f = file.field();
  const float R = f.sphere.radius;
  ++a.rays;
  auto hard = [&](const char* why) {
    ++a.hard;
    if (!a.firstHard.empty()) return;
    char buf[512];
    std::snprintf(buf, sizeof(buf),
                  "ray %zu: %s (cpu looked %d k %u texel %u,%u code %u hit %d t %.9g; gpu looked %d k %u texel %u,%u "
                  "code %u hit %d t %.9g)",
                  r, why, c.looked, c.k, c.i, c.j, c.code, c.hit, double(c.t), g.looked, g.k, g.i, g.j, g.code, g.hit,
                  double(g.t));
    a.firstHard = buf;
  };
  if (g.looked != c.looked) return hard("lookup made on one side only");
  if (!c.looked) {
    if (g.hit) return hard("GPU hit without a lookup");
    ++a.agree;
    return;
  }
  if (g.k != c.k) {
    if (g.k >= f.mapCount) return hard("GPU sample out of range");
    const double l = std::sqrt(double(c.eu.x) * c.eu.x + double(c.eu.y) * c.eu.y + double(c.eu.z) * c.eu.z);
    auto dotk = [&](uint32_t k) {
      const Vec3 u = ps.position(k);
      return (double(u.x) * c.eu.x + double(u.y) * c.eu.y + double(u.z) * c.eu.z) / l;
    };
    if (std::fabs(dotk(g.k) - dotk(c.k)) > kSampleEps) return hard("different sample");
    ++a.sampleBoundary;
    return;
  }
  if (g.i != c.i || g.j != c.j) {
    auto nearLine = [&](float s, uint32_t ci, uint32_t gi) {
      if (ci == gi) return true;
      if (std::max(ci, gi) - std::min(ci, gi) != 1) return false;
      const double x = (double(s) + 1.0) * 0.5 * f.mapResolution;  // texel units
      return std::fabs(x - double(std::max(ci, gi))) <= kTexelEps;
    };
    if (!(nearLine(c.uv.x, c.i, g.i) && nearLine(c.uv.y, c.j, g.j))) return hard("different texel");
    ++a.texelBoundary;
    return;
  }
  const bool bc4 = f.distanceEncoding == DistanceEncoding::kBc4Diameter;
  if (g.code != c.code && bc4 && g.code != 255 && c.code != 255 && (g.code == c.code + 1 || c.code == g.code + 1)) {
    const float want = float(g.code) * (2.0f * R / 254.0f);
    if (std::memcmp(&want, &g.distance, 4) != 0) return hard("decoded distance not bit-identical to the GPU code's");
    ++a.bc4Rounding;
    ++a.agree;
    return;
  }
  if (g.code != c.code) return hard("different code for the same texel");
  if (std::memcmp(&g.distance, &c.distance, 4) != 0) return hard("decoded distance not bit-identical");
  ++a.exactDistances;
  if (g.hit != c.hit) {
    const double eps = kRangeEps * R;
    if (!(std::fabs(c.tLen - c.lo) <= eps || std::fabs(c.tLen - c.hi) <= eps))
      return hard("different hit flag for the same texel");
    ++a.rangeBoundary;
    return;
  }
  if (c.hit) {
    ++a.hits;
    const double len =
        std::sqrt(double(ray.direction[0]) * ray.direction[0] + double(ray.direction[1]) * ray.direction[1] +
                  double(ray.direction[2]) * ray.direction[2]);
    a.maxTDiff = std::max(a.maxTDiff, std::fabs(double(g.t) - double(c.t)) * len / R);
  }
  ++a.agree;
}

// Prints the counts after `head` (e.g. "[ gpu ] <case>") and checks what every suite requires: no
// hard mismatch, t within 1e-5 R where the texels agree.
inline void reportAgreement(const Agreement& a, const std::string& head, const std::string& label) {
  std::printf(
      "%s: %llu rays, agreement %.3f%% (%llu); allowed mismatches: sample boundary %llu, texel boundary %llu, "
      "range boundary %llu, bc4 rounding %llu; hard %llu; %llu texel-agreeing lookups with bit-identical "
      "distances, %llu hits, max |t_gpu - t_cpu| = %.3g R\n",
      head.c_str(), (unsigned long long)a.rays, 100.0 * double(a.agree) / double(std::max<uint64_t>(a.rays, 1)),
      (unsigned long long)a.agree, (unsigned long long)a.sampleBoundary, (unsigned long long)a.texelBoundary,
      (unsigned long long)a.rangeBoundary, (unsigned long long)a.bc4Rounding, (unsigned long long)a.hard,
      (unsigned long long)a.exactDistances, (unsigned long long)a.hits, a.maxTDiff);
  EXPECT_EQ(a.hard, 0u) << label << ": " << a.firstHard;
  EXPECT_LT(a.maxTDiff, 1e-5) << label;
}

// A GpuLookup from an answer of the Vulkan kernel's layout (vff::vk::QueryAnswer and the WebGPU
// suite's copy of it: flags with kLooked and kHit, t, sampleIndex, texelI, texelJ, code, distance).
template <class Answer>
GpuLookup lookupOf(const Answer& g) {
  return {(g.flags & Answer::kLooked) != 0,
          (g.flags & Answer::kHit) != 0,
          g.t,
          g.sampleIndex,
          g.texelI,
          g.texelJ,
          g.code,
          g.distance};
}

// Every ray's answer (Answer: as lookupOf's) against the CPU lookup: the lookup is checked to be
// the CPU query, each answer classified, the counts reported after `head` (reportAgreement).
template <class GpuRay, class Answer>
Agreement compareNearestAnswers(const File& file, const FieldQuery& cpu, const std::vector<GpuRay>& rays,
                                const std::vector<Answer>& answers, const std::string& head, const std::string& label) {
  Agreement a;
  EXPECT_EQ(answers.size(), rays.size()) << label;
  if (answers.size() != rays.size()) return a;
  for (size_t r = 0; r < rays.size(); ++r) {
    const CpuLookup c = cpuLookup(file, cpu.positions(), rays[r]);
    expectLookupIsCpuQuery(cpu, rays[r], c, r);
    classify(file, cpu.positions(), rays[r], c, lookupOf(answers[r]), r, a);
  }
  reportAgreement(a, head, label);
  EXPECT_EQ(a.rays, uint64_t(rays.size())) << label;
  return a;
}

// The baked fields' further bounds (not the conformance vectors'): boundary cases are rare, and
// many lookups agree to the bit.
inline void expectBakedAgreement(const Agreement& a, const std::string& label) {
  EXPECT_GE(a.agree, a.rays * 99 / 100) << label;
  EXPECT_GT(a.exactDistances, a.rays / 4) << label;
}

}  // namespace vff::gputest
