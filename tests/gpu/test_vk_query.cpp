// The Vulkan path of the single-object query (gpu/vulkan, vff_vk): gpu/glsl/vff_query.glsl compiled
// to SPIR-V at build time, the field uploaded by vff::vk::loadField, rays run by
// vff::vk::QueryPipeline, against the CPU query ray by ray, with the Khronos validation layer on.
//
// The comparisons are test_gpu_query.cpp's and test_gpu_field.cpp's (the GL path), with their
// tolerances:
// * kNearest: every ray's lookup (sample k, texel (i, j), code, decoded distance) and hit flag are
//   the CPU's; a disagreement is allowed only where the CPU shows the ray within kSampleEps (dot
//   product) of a sample boundary, kTexelEps texels of a texel boundary, or kRangeEps * R of
//   tmin / tmax / the bias; where the texel agrees the decoded distance is bit-identical, and t
//   within 1e-5 R. bc4-diameter (where the device samples BC4): a hit's code may be one off the
//   CPU's (the texture unit rounds the palette its own way), its distance then that code's.
// * kInterpolated: hit flags equal except at a tie of the vote (visibility within kVoteEps of
//   0.5), t within kInterpT R, visibility within kInterpVis; normals of agreeing kNearest hits
//   within kNormalEps.
// * Every case: zero validation errors and warnings (the layer is enabled explicitly; lavapipe
//   itself does not check descriptor types).
// Where no Vulkan device or no validation layer is installed, the cases skip and say why.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "baked_fields.h"
#include "common/rng.h"
#include "vff/vff.h"
#include "vff/vk/context.h"
#include "vff/vk/field.h"
#include "vff/vk/query.h"

namespace vff {
namespace {

constexpr double kSampleEps = 1e-5;  // dot-product difference of two equally near samples
constexpr double kTexelEps = 1e-3;   // texels from the texel boundary
constexpr double kRangeEps = 1e-5;   // fraction of R from tmin / tmax / bias
constexpr double kNormalEps = 1e-5;
constexpr double kVoteEps = 1e-4;
constexpr double kInterpT = 1e-4;  // fraction of R
constexpr double kInterpVis = 1e-4;

using vk::QueryAnswer;
using vk::QueryRay;

// The case's context: a CPU device first (lavapipe, as the GL tests' llvmpipe), validation on.
// Each gtest case runs in its own process (gtest_discover_tests), so this is one context a case.
struct VkEnv {
  Result<vk::Context> ctx = makeError(Code::kBadState, "not created");
  std::string skip;  // why the case cannot run
};

VkEnv& vkEnv() {
  static VkEnv env = [] {
    VkEnv e;
    vk::ContextOptions o;
    o.validation = true;
    o.preferCpu = true;
    e.ctx = vk::Context::create(o);
    if (!e.ctx)
      e.skip = "no Vulkan device: " + e.ctx.error().toString();
    else if (!e.ctx->validationEnabled())
      e.skip = "no Vulkan validation layer: " + e.ctx->validationNote();
    else
      std::printf("[ vk ] device: %s\n", e.ctx->deviceName().c_str());
    return e;
  }();
  return env;
}

#define VFF_REQUIRE_VK()                                     \
  do {                                                       \
    if (!vkEnv().skip.empty()) GTEST_SKIP() << vkEnv().skip; \
  } while (0)

// Every case ends here: nothing reported by the validation layer.
void expectNoValidationMessages() {
  const vk::Context& c = *vkEnv().ctx;
  std::printf("[ vk ] validation: %u errors, %u warnings\n", c.validationErrors(), c.validationWarnings());
  EXPECT_EQ(c.validationErrors(), 0u) << c.validationLog();
  EXPECT_EQ(c.validationWarnings(), 0u) << c.validationLog();
}

Vec3 add(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
Vec3 sub(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
Vec3 mul(Vec3 a, float s) {
  return {a.x * s, a.y * s, a.z * s};
}
float dot3(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

// Uploads the field and runs the rays; ADD_FAILUREs and returns empty on a setup failure.
std::vector<QueryAnswer> runVk(const File& file, const std::vector<QueryRay>& rays) {
  const vk::Context& ctx = *vkEnv().ctx;
  auto gpu = vk::loadField(ctx, file);
  EXPECT_TRUE(gpu.ok()) << gpu.error().toString();
  if (!gpu) return {};
  auto pipe = vk::QueryPipeline::create(ctx, gpu->kind());
  EXPECT_TRUE(pipe.ok()) << pipe.error().toString();
  if (!pipe) return {};
  auto out = pipe->run(ctx, *gpu, rays);
  EXPECT_TRUE(out.ok()) << out.error().toString();
  if (!out) return {};
  return std::move(*out);
}

// ---- kNearest: the lookup, step by step -----------------------------------------------------------

// FieldQuery::intersect's kNearest lookup through the public API (test_gpu_query.cpp's), so that
// the test knows which sample and texel the CPU used and how near the ray was to their boundaries.
struct CpuLookup {
  bool looked = false, inside = false, hit = false;
  float t = INFINITY, lo = 0, hi = 0, tLen = 0;
  Vec3 eu;
  uint32_t k = 0, i = 0, j = 0, code = 0;
  Vec2 uv;
  float distance = 0;
};

float decodeDistance(const FieldDesc& f, uint32_t code, uint32_t i, uint32_t j, bool* hit) {
  const float radius = f.sphere.radius;
  switch (f.distanceEncoding) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kBc4Diameter:
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

CpuLookup cpuLookup(const File& file, const PositionSet& ps, const QueryRay& ray) {
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

// Random rays (test_gpu_query.cpp's): half from outside the sphere towards points inside it, half
// from inside; some non-unit directions and finite ranges; intra bias -1, 0 and 0.02.
std::vector<QueryRay> nearestRays(const FieldDesc& f, uint32_t count, uint64_t seed) {
  test::Rng rng(seed);
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float R = f.sphere.radius;
  std::vector<QueryRay> rays(count);
  const float biases[3] = {-1.0f, 0.0f, 0.02f};
  for (uint32_t r = 0; r < count; ++r) {
    Vec3 o, d;
    float tmin = 0, tmax = INFINITY;
    if (r % 2 == 0) {
      o = add(c, mul(rng.direction(), R * (1.05f + 2.0f * rng.uniform())));
      const Vec3 target = add(c, mul(rng.direction(), R * 1.1f * std::cbrt(rng.uniform())));
      d = sub(target, o);
      if (r % 8 == 2) d = mul(d, 0.5f + 3 * rng.uniform());
      if (r % 16 == 4) tmax = 1.5f * rng.uniform();
      if (r % 16 == 6) tmin = 0.5f * rng.uniform();
    } else {
      o = add(c, mul(rng.direction(), R * 0.95f * std::cbrt(rng.uniform())));
      d = rng.direction();
      if (r % 16 == 5) tmax = R * rng.uniform();
    }
    rays[r] = QueryRay{{o.x, o.y, o.z, 0}, {d.x, d.y, d.z, 0}, {tmin, tmax, biases[r % 3], 0}};
  }
  return rays;
}

struct Agreement {
  uint64_t rays = 0, agree = 0, sampleBoundary = 0, texelBoundary = 0, rangeBoundary = 0, bc4Rounding = 0, hard = 0;
  uint64_t exactDistances = 0, hits = 0;
  double maxTDiff = 0;  // R units, where both hit with the same texel
  std::string firstHard;
};

// One ray's GPU answer against the CPU lookup; counts it into `a`.
void classify(const File& file, const PositionSet& ps, const QueryRay& ray, const CpuLookup& c, const QueryAnswer& g,
              size_t r, Agreement& a) {
  const FieldDesc& f = file.field();
  const float R = f.sphere.radius;
  const bool gLooked = (g.flags & QueryAnswer::kLooked) != 0, gHit = (g.flags & QueryAnswer::kHit) != 0;
  ++a.rays;
  auto hard = [&](const char* why) {
    ++a.hard;
    if (!a.firstHard.empty()) return;
    char buf[512];
    std::snprintf(buf, sizeof(buf),
                  "ray %zu: %s (cpu looked %d k %u texel %u,%u code %u hit %d t %.9g; gpu looked %d k %u texel %u,%u "
                  "code %u hit %d t %.9g)",
                  r, why, c.looked, c.k, c.i, c.j, c.code, c.hit, double(c.t), gLooked, g.sampleIndex, g.texelI,
                  g.texelJ, g.code, gHit, double(g.t));
    a.firstHard = buf;
  };
  if (gLooked != c.looked) return hard("lookup made on one side only");
  if (!c.looked) {
    if (gHit) return hard("GPU hit without a lookup");
    ++a.agree;
    return;
  }
  if (g.sampleIndex != c.k) {
    if (g.sampleIndex >= f.mapCount) return hard("GPU sample out of range");
    const double l = std::sqrt(double(c.eu.x) * c.eu.x + double(c.eu.y) * c.eu.y + double(c.eu.z) * c.eu.z);
    auto dotk = [&](uint32_t k) {
      const Vec3 u = ps.position(k);
      return (double(u.x) * c.eu.x + double(u.y) * c.eu.y + double(u.z) * c.eu.z) / l;
    };
    if (std::fabs(dotk(g.sampleIndex) - dotk(c.k)) > kSampleEps) return hard("different sample");
    ++a.sampleBoundary;
    return;
  }
  if (g.texelI != c.i || g.texelJ != c.j) {
    auto nearLine = [&](float s, uint32_t ci, uint32_t gi) {
      if (ci == gi) return true;
      if (std::max(ci, gi) - std::min(ci, gi) != 1) return false;
      const double x = (double(s) + 1.0) * 0.5 * f.mapResolution;
      return std::fabs(x - double(std::max(ci, gi))) <= kTexelEps;
    };
    if (!(nearLine(c.uv.x, c.i, g.texelI) && nearLine(c.uv.y, c.j, g.texelJ))) return hard("different texel");
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
  if (gHit != c.hit) {
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

Agreement compareNearest(const File& file, uint32_t rayCount, uint64_t seed, const std::string& label) {
  Agreement a;
  auto cpu = FieldQuery::fromFile(file);
  EXPECT_TRUE(cpu.ok()) << cpu.error().toString();
  if (!cpu) return a;
  const std::vector<QueryRay> rays = nearestRays(file.field(), rayCount, seed);
  const std::vector<QueryAnswer> out = runVk(file, rays);
  if (out.size() != rays.size()) return a;
  for (size_t r = 0; r < rays.size(); ++r) {
    const QueryRay& ray = rays[r];
    const CpuLookup c = cpuLookup(file, cpu->positions(), ray);
    // The step-by-step lookup is the CPU query, bit for bit.
    QueryOptions qo;
    qo.intraBias = ray.range[2];
    const QueryHit q = cpu->intersect(Ray{{ray.origin[0], ray.origin[1], ray.origin[2]},
                                          {ray.direction[0], ray.direction[1], ray.direction[2]},
                                          ray.range[0],
                                          ray.range[1]},
                                      qo);
    EXPECT_EQ(q.hit, c.hit) << "ray " << r;
    if (q.hit && c.hit) {
      EXPECT_EQ(q.t, c.t) << "ray " << r;
    }
    classify(file, cpu->positions(), ray, c, out[r], r, a);
  }
  std::printf(
      "[ vk ] %s: kNearest: %llu rays, agreement %.3f%% (%llu); allowed mismatches: sample boundary %llu, "
      "texel boundary %llu, range boundary %llu, bc4 rounding %llu; hard %llu; %llu texel-agreeing lookups "
      "with bit-identical distances, %llu hits, max |t_gpu - t_cpu| = %.3g R\n",
      label.c_str(), (unsigned long long)a.rays, 100.0 * double(a.agree) / double(std::max<uint64_t>(a.rays, 1)),
      (unsigned long long)a.agree, (unsigned long long)a.sampleBoundary, (unsigned long long)a.texelBoundary,
      (unsigned long long)a.rangeBoundary, (unsigned long long)a.bc4Rounding, (unsigned long long)a.hard,
      (unsigned long long)a.exactDistances, (unsigned long long)a.hits, a.maxTDiff);
  EXPECT_EQ(a.rays, uint64_t(rayCount)) << label;
  EXPECT_EQ(a.hard, 0u) << label << ": " << a.firstHard;
  EXPECT_LT(a.maxTDiff, 1e-5) << label;
  return a;
}

// ---- Baked fields, kNearest ---------------------------------------------------------------------------

using gputest::caseName;
using gputest::FieldCase;

class VkQuery : public ::testing::TestWithParam<FieldCase> {};

TEST_P(VkQuery, MatchesCpuNearest) {
  VFF_REQUIRE_VK();
  auto file = gputest::bakeFile(GetParam(), false);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  EXPECT_GT(file->layout().sliceCount, 1u);
  if (file->field().distanceEncoding == DistanceEncoding::kBc4Diameter) {
    // BC4 is optional in Vulkan (textureCompressionBC); the loader says so as kUnsupported.
    auto probe = vk::loadField(*vkEnv().ctx, *file);
    if (!probe && probe.error().code == Code::kUnsupported) GTEST_SKIP() << probe.error().message;
  }
  const Agreement a = compareNearest(*file, 8192, 1234, caseName(GetParam()));
  EXPECT_GE(a.agree, a.rays * 99 / 100);  // boundary cases are rare
  EXPECT_GT(a.exactDistances, a.rays / 4);
  expectNoValidationMessages();
}

std::vector<FieldCase> nearestCases() {
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

INSTANTIATE_TEST_SUITE_P(Fields, VkQuery, ::testing::ValuesIn(nearestCases()),
                         [](const ::testing::TestParamInfo<FieldCase>& i) { return caseName(i.param); });

// ---- Conformance vectors, kNearest -------------------------------------------------------------------

std::vector<std::string> validVectors() {
  std::vector<std::string> names;
  const std::filesystem::path dir = std::filesystem::path(VFF_SOURCE_DIR) / "spec/conformance/valid";
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.path().extension() == ".vff") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

class VkConformance : public ::testing::TestWithParam<std::string> {};

TEST_P(VkConformance, MatchesCpuNearest) {
  VFF_REQUIRE_VK();
  auto file = File::open(std::string(VFF_SOURCE_DIR) + "/spec/conformance/valid/" + GetParam() + ".vff");
  ASSERT_TRUE(file.ok()) << file.error().toString();
  if (file->field().distanceEncoding == DistanceEncoding::kBc4Diameter) {
    auto probe = vk::loadField(*vkEnv().ctx, *file);
    if (!probe && probe.error().code == Code::kUnsupported) GTEST_SKIP() << probe.error().message;
  }
  compareNearest(*file, 4096, 99, GetParam());
  expectNoValidationMessages();
}

INSTANTIATE_TEST_SUITE_P(Valid, VkConformance, ::testing::ValuesIn(validVectors()),
                         [](const ::testing::TestParamInfo<std::string>& i) {
                           std::string s = i.param;
                           for (char& ch : s)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return s;
                         });

// ---- Normals and kInterpolated ----------------------------------------------------------------------

// test_gpu_field.cpp's rays: mostly from outside (the interpolated path), some from inside, short
// rays from inside off the object (VFF_OFF_OBJECT, section 7.4).
std::vector<QueryRay> interpolatedRays(const FieldDesc& f, uint32_t count, uint64_t seed) {
  test::Rng rng(seed);
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float R = f.sphere.radius;
  std::vector<QueryRay> rays(count);
  for (uint32_t r = 0; r < count; ++r) {
    Vec3 o, d;
    float tmin = 0, tmax = INFINITY;
    if (r % 4 != 3) {
      const Vec3 a = rng.direction(), b = rng.direction();
      const float s = R * (1.05f + 2.0f * rng.uniform()), s2 = R * 1.1f * std::cbrt(rng.uniform());
      o = add(c, mul(a, s));
      d = sub(add(c, mul(b, s2)), o);
      if (r % 8 == 2) d = mul(d, 2.5f);
      if (r % 16 == 4) tmax = 1.5f * rng.uniform();
    } else {
      o = add(c, mul(rng.direction(), R * 0.95f * std::cbrt(rng.uniform())));
      d = rng.direction();
    }
    if (r % 8 == 7) tmax = 0.6f * R * rng.uniform();
    const float bias = r % 8 == 7 ? -2.0f : r % 3 == 0 ? 0.0f : -1.0f;
    rays[r] = QueryRay{{o.x, o.y, o.z, 0}, {d.x, d.y, d.z, 0}, {tmin, tmax, bias, 0}};
  }
  return rays;
}

double maxDiff3(const float* g, Vec3 c) {
  return std::max({std::fabs(double(g[0]) - c.x), std::fabs(double(g[1]) - c.y), std::fabs(double(g[2]) - c.z)});
}

struct InterpCounts {
  uint64_t nNormals = 0, nFlag = 0, iAgree = 0, iTie = 0, iHits = 0, fails = 0;
  double nMax = 0, iMaxT = 0, iMaxVis = 0;
  std::string first;
  void fail(size_t r, const std::string& why) {
    ++fails;
    if (first.empty()) first = "ray " + std::to_string(r) + ": " + why;
  }
};

// One ray: kNearest's normal, then kInterpolated's flag, t, visibility and normal.
void compareInterpolated(const FieldQuery& cpu, const QueryRay& g, const QueryAnswer& o, float R, size_t r,
                         InterpCounts& n) {
  const Ray ray{{g.origin[0], g.origin[1], g.origin[2]},
                {g.direction[0], g.direction[1], g.direction[2]},
                g.range[0],
                g.range[1]};
  const double len = std::sqrt(double(dot3(ray.direction, ray.direction)));
  QueryOptions qn;
  qn.intraBias = g.range[2];
  if (g.range[2] == -2.0f) qn.origin = RayOrigin::kOffObject;  // VFF_OFF_OBJECT
  const QueryHit h = cpu.intersect(ray, qn);
  if (((o.flags & QueryAnswer::kHit) != 0) != h.hit) {
    ++n.nFlag;  // test_gpu_query-style boundary rays; the GL suite sees none on these fields
  } else if (h.hit && std::fabs(double(o.t) - double(h.t)) * len <= 1e-5 * R) {
    if (((o.flags & QueryAnswer::kHasNormal) != 0) != h.hasNormal) return n.fail(r, "hasNormal differs");
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
  if (((o.flags & QueryAnswer::kInterpHit) != 0) != hi.hit) {
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
  if (((o.flags & QueryAnswer::kInterpHasNormal) != 0) != hi.hasNormal)
    return n.fail(r, "interpolated hasNormal differs");
  if (hi.hasNormal && maxDiff3(o.interpNormal, hi.normal) > 1e-4) return n.fail(r, "interpolated normal differs");
}

class VkField : public ::testing::TestWithParam<FieldCase> {};

TEST_P(VkField, NormalsAndInterpolatedMatchCpu) {
  VFF_REQUIRE_VK();
  auto file = gputest::bakeFile(GetParam(), true);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  ASSERT_TRUE(file->hasNormals());
  auto cpu = FieldQuery::fromFile(*file);
  ASSERT_TRUE(cpu.ok()) << cpu.error().toString();
  const std::vector<QueryRay> rays = interpolatedRays(file->field(), 8192, 77);
  const std::vector<QueryAnswer> out = runVk(*file, rays);
  ASSERT_EQ(out.size(), rays.size());
  InterpCounts n;
  for (size_t r = 0; r < rays.size(); ++r)
    compareInterpolated(*cpu, rays[r], out[r], file->field().sphere.radius, r, n);
  std::printf(
      "[ vk ] %s: kNearest: %llu normals compared, max diff %.3g, hit-flag mismatches %llu; kInterpolated: "
      "%llu rays, agreement %.3f%%, vote ties %llu, failures %llu; %llu hits, max |t_gpu - t_cpu| = %.3g R, "
      "max |vis_gpu - vis_cpu| = %.3g\n",
      caseName(GetParam()).c_str(), (unsigned long long)n.nNormals, n.nMax, (unsigned long long)n.nFlag,
      (unsigned long long)rays.size(), 100.0 * double(n.iAgree) / double(rays.size()), (unsigned long long)n.iTie,
      (unsigned long long)n.fails, (unsigned long long)n.iHits, n.iMaxT, n.iMaxVis);
  EXPECT_EQ(n.fails, 0u) << n.first;
  EXPECT_EQ(n.nFlag, 0u);
  EXPECT_GT(n.nNormals, rays.size() / 8);
  EXPECT_GT(n.iHits, rays.size() / 8);
  expectNoValidationMessages();
}

// test_gpu_field.cpp's fields.
std::vector<FieldCase> interpolatedCases() {
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

INSTANTIATE_TEST_SUITE_P(Fields, VkField, ::testing::ValuesIn(interpolatedCases()),
                         [](const ::testing::TestParamInfo<FieldCase>& i) { return caseName(i.param); });

// ---- The context ---------------------------------------------------------------------------------------

// The zero counts above mean something only if the messenger counts: a call that breaks a valid
// usage rule (two bindings with the same number in one set layout) must be reported as an error.
TEST(VkContext, ValidationMessengerCountsErrors) {
  VFF_REQUIRE_VK();
  vk::ContextOptions o;
  o.validation = true;
  o.preferCpu = true;
  auto ctx = vk::Context::create(o);
  ASSERT_TRUE(ctx.ok()) << ctx.error().toString();
  ASSERT_TRUE(ctx->validationEnabled());
  EXPECT_EQ(ctx->validationErrors(), 0u) << ctx->validationLog();
  VkDescriptorSetLayoutBinding b[2] = {{0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr},
                                       {0, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr}};
  VkDescriptorSetLayoutCreateInfo li{};
  li.sType = VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO;
  li.bindingCount = 2;
  li.pBindings = b;
  VkDescriptorSetLayout layout = VK_NULL_HANDLE;
  if (vkCreateDescriptorSetLayout(ctx->device(), &li, nullptr, &layout) == VK_SUCCESS && layout)
    vkDestroyDescriptorSetLayout(ctx->device(), layout, nullptr);
  EXPECT_GE(ctx->validationErrors(), 1u);
  std::printf("[ vk ] the deliberate error was counted: %u error(s)\n", ctx->validationErrors());
}

// Fields of a variant the pipeline was not made for are refused, not run.
TEST(VkQueryPipeline, RefusesAnotherVariant) {
  VFF_REQUIRE_VK();
  const vk::Context& ctx = *vkEnv().ctx;
  auto file = gputest::bakeFile({PositionScheme::kOctaHemi2, DirectionScheme::kConcentricEqualArea,
                                 DistanceEncoding::kUnorm16Diameter, LayoutTarget::kTexture3D},
                                false);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  auto gpu = vk::loadField(ctx, *file);
  ASSERT_TRUE(gpu.ok()) << gpu.error().toString();
  EXPECT_EQ(gpu->kind(), vk::MapsKind::kTexture3D);
  EXPECT_FALSE(gpu->hasNormals());
  EXPECT_EQ(gpu->block().sliceCount, file->layout().sliceCount);
  EXPECT_EQ(gpu->textureBytes(), file->sliceBytes(Plane::kDistance) * file->layout().sliceCount);
  auto pipe = vk::QueryPipeline::create(ctx, vk::MapsKind::kArray2D);
  ASSERT_TRUE(pipe.ok()) << pipe.error().toString();
  const std::vector<QueryRay> rays = nearestRays(file->field(), 4, 1);
  auto out = pipe->run(ctx, *gpu, rays);
  ASSERT_FALSE(out.ok());
  EXPECT_EQ(out.error().code, Code::kInvalidArgument);
  expectNoValidationMessages();
}

}  // namespace
}  // namespace vff
