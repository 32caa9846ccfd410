// The GLSL lookup (gpu/glsl/vff_query.glsl), uploaded with vff_gl and run in a compute shader on a
// headless EGL context, against the CPU query (vff::FieldQuery::intersect, kNearest) ray by ray.
//
// For every ray the shader writes the hit flag, t and the lookup it made (sample k, texel (i, j),
// stored code, decoded distance). A ray agrees when the lookup and the hit flag are the CPU's. A
// disagreement is allowed only where the CPU shows the ray within a small epsilon of a boundary:
//   sample boundary: the GPU's sample is as near to the entry point as the CPU's (dot products of
//                    the unit entry point within kSampleEps);
//   texel boundary:  same sample, and the CPU's (u, v) is within kTexelEps texels of the line
//                    between the two texels;
//   range boundary:  same texel, and the hit lies within kRangeEps * R of tmin, tmax or the bias.
// Everything else fails the test. When the texel agrees, the code must be the CPU's map byte and
// the decoded distance must be bit-identical to the CPU query's.
#include <gtest/gtest.h>
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "baked_fields.h"
#include "common/rng.h"
#include "dispatch.h"
#include "egl_context.h"
#include "gl_test.h"
#include "vff/bake/baker.h"
#include "vff/bake/procedural.h"
#include "vff/gl/loader.h"
#include "vff/vff.h"

namespace vff {
namespace {

constexpr double kSampleEps = 1e-5;  // dot-product difference of two equally near samples
constexpr double kTexelEps = 1e-3;   // texels from the texel boundary
constexpr double kRangeEps = 1e-5;   // fraction of R from tmin / tmax / bias

Vec3 add(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
Vec3 sub(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
Vec3 mul(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
float dot3(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

// ---- GL plumbing -----------------------------------------------------------------------------------


// The test's compute shader: one ray per invocation.
const std::string kMain =
    "struct TestOut { uint flags; float t; uint k; uint i; uint j; uint code; float distance; uint pad; };\n" +
    test::rayShaderHead(3, 4) + R"(
  VffHit h = vffIntersect(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
  TestOut o;
  o.flags = (h.hit ? 1u : 0u) | (h.inside ? 2u : 0u) | (h.looked ? 4u : 0u);
  o.t = h.t;
  o.k = h.sampleIndex;
  o.i = h.texel.x;
  o.j = h.texel.y;
  o.code = h.code;
  o.distance = h.distance;
  o.pad = 0u;
  outs[id] = o;
}
)";

struct GpuRay {
  float origin[4];
  float direction[4];
  float range[4];
};
struct GpuOut {
  uint32_t flags;
  float t;
  uint32_t k, i, j, code;
  float distance;
  uint32_t pad;
};
static_assert(sizeof(GpuRay) == 48 && sizeof(GpuOut) == 32);

// Compiles the program for a field (gl::shaderDefines); empty string on success, else the log.
std::string buildProgram(const File& file, GLuint* program) {
  std::string log;
  *program = harness::buildQueryProgram(gl::shaderDefines(file.field(), file.layout()), kMain, &log);
  return log;
}

// Runs the rays through the shader.
std::vector<GpuOut> runGpu(const gl::GpuField& field, GLuint program, const std::vector<GpuRay>& rays) {
  field.bind();
  glUseProgram(program);
  std::vector<GpuOut> out = test::dispatchRays<GpuOut>(std::span<const GpuRay>(rays), rays.size(), 1, 3, 4);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  return out;
}

// ---- The CPU side ------------------------------------------------------------------------------------

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

CpuLookup cpuLookup(const File& file, const PositionSet& ps, const Vec3 o, const Vec3 d, float tmin, float tmax,
                    float intraBias) {
  const FieldDesc& f = file.field();
  CpuLookup c;
  const Vec3 center{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float radius = f.sphere.radius;
  const uint32_t m = f.mapResolution;
  const float len = std::sqrt(dot3(d, d));
  const Vec3 w = mul(d, 1.0f / len);
  c.lo = tmin * len;
  c.hi = tmax * len;
  const Vec3 delta = sub(o, center);
  const float beta = dot3(delta, w);
  const float gamma = dot3(delta, delta) - radius * radius;
  const float disc = beta * beta - gamma;
  if (!(disc >= 0)) return c;
  const float sq = std::sqrt(disc);
  const float t1 = -beta + sq;
  if (t1 < 0) return c;
  c.inside = gamma <= 0;
  float t0 = c.inside ? t1 : -beta - sq;
  if (!c.inside) t0 = std::max(t0, 0.0f);
  const Vec3 e = add(o, mul(w, t0));
  const Vec3 v = c.inside ? mul(w, -1.0f) : w;
  if (c.inside) {
    if (f.distanceEncoding == DistanceEncoding::kBit1) return c;
    const float bias = (intraBias >= 0 ? intraBias : defaultIntraBias(f)) * radius;
    c.lo = std::max(c.lo, bias);
  }
  c.eu = mul(sub(e, center), 1.0f / radius);
  c.k = ps.nearest(c.eu);
  const Vec3 l = toLocal(ps.frame(c.k), v);
  c.uv = hemisphereToSquare(f.directionScheme, l);
  squareToTexel(c.uv, m, &c.i, &c.j);
  auto map = file.mapData(Plane::kDistance, c.k);
  EXPECT_TRUE(map.ok());
  c.code = loadCode(f.distanceEncoding, *map, m, c.i, c.j);
  c.looked = true;
  // The decode of libvff/src/query/query_impl.h (FieldQuery::Impl::texel).
  bool hit = false;
  switch (f.distanceEncoding) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kBc4Diameter:  // loadCode decoded the block: a unorm8-diameter code
      hit = c.code != 255u;
      c.distance = float(c.code) * (2.0f * radius / 254.0f);
      break;
    case DistanceEncoding::kUnorm16Diameter:
      hit = c.code != 65535u;
      c.distance = float(c.code) * (2.0f * radius / 65534.0f);
      break;
    case DistanceEncoding::kUnorm8Chord: {
      hit = c.code != 255u;
      const float cosAlpha = texelDirection(f.directionScheme, m, c.i, c.j).z;
      c.distance = float(c.code) * (2.0f * radius * cosAlpha / 254.0f);
      break;
    }
    case DistanceEncoding::kBit1: hit = c.code != 0; break;
    default: break;
  }
  if (!hit) return c;
  const float t = c.inside ? t0 - c.distance : t0 + c.distance;
  c.tLen = t;
  if (t < c.lo || t > c.hi) return c;
  c.hit = true;
  c.t = t / len;
  return c;
}

struct Agreement {
  uint64_t rays = 0, agree = 0, sampleBoundary = 0, texelBoundary = 0, rangeBoundary = 0, hard = 0;
  uint64_t exactDistances = 0, hits = 0;
  uint64_t bc4Rounding = 0;  // bc4-diameter: lookups whose GPU code is one from the CPU's (see compare)
  double maxTDiff = 0;  // over rays where both hit with the same texel, in units of R
  std::string firstHard;
};

// Random rays: half from outside the sphere towards points inside it, half from inside.
std::vector<GpuRay> makeRays(const FieldDesc& f, uint32_t count, uint64_t seed) {
  test::Rng rng(seed);
  const Vec3 c{f.sphere.center[0], f.sphere.center[1], f.sphere.center[2]};
  const float R = f.sphere.radius;
  std::vector<GpuRay> rays(count);
  const float biases[3] = {-1.0f, 0.0f, 0.02f};
  for (uint32_t r = 0; r < count; ++r) {
    Vec3 o, d;
    float tmin = 0, tmax = INFINITY;
    if (r % 2 == 0) {
      o = add(c, mul(rng.direction(), R * (1.05f + 2.0f * rng.uniform())));
      const Vec3 target = add(c, mul(rng.direction(), R * 1.1f * std::cbrt(rng.uniform())));  // a few miss the sphere
      d = sub(target, o);
      if (r % 8 == 2) d = mul(d, 0.5f + 3 * rng.uniform());  // non-unit directions
      if (r % 16 == 4) tmax = 1.5f * rng.uniform();          // finite ranges
      if (r % 16 == 6) tmin = 0.5f * rng.uniform();
    } else {
      o = add(c, mul(rng.direction(), R * 0.95f * std::cbrt(rng.uniform())));
      d = rng.direction();
      if (r % 16 == 5) tmax = R * rng.uniform();
    }
    rays[r] = GpuRay{{o.x, o.y, o.z, 0}, {d.x, d.y, d.z, 0}, {tmin, tmax, biases[r % 3], 0}};
  }
  return rays;
}

// Runs `rays` on the GPU and compares with the CPU. Returns false (after ADD_FAILUREs) on a setup
// failure.
Agreement compare(const File& file, uint32_t rayCount, uint64_t seed, const std::string& label) {
  Agreement a;
  const FieldDesc& f = file.field();
  auto gpu = gl::loadField(file);
  EXPECT_TRUE(gpu.ok()) << gpu.error().toString();
  if (!gpu) return a;
  GLuint program = 0;
  const std::string log = buildProgram(file, &program);
  EXPECT_TRUE(log.empty()) << log;
  if (!log.empty()) return a;
  auto cpu = FieldQuery::fromFile(file);
  EXPECT_TRUE(cpu.ok()) << cpu.error().toString();
  if (!cpu) return a;
  const PositionSet& ps = cpu->positions();
  const std::vector<GpuRay> rays = makeRays(f, rayCount, seed);
  const std::vector<GpuOut> out = runGpu(*gpu, program, rays);
  glDeleteProgram(program);
  const float R = f.sphere.radius;
  const bool bc4 = f.distanceEncoding == DistanceEncoding::kBc4Diameter;
  const uint32_t m = f.mapResolution;
  for (size_t r = 0; r < rays.size(); ++r) {
    const GpuRay& ray = rays[r];
    const Vec3 o{ray.origin[0], ray.origin[1], ray.origin[2]};
    const Vec3 d{ray.direction[0], ray.direction[1], ray.direction[2]};
    const CpuLookup c = cpuLookup(file, ps, o, d, ray.range[0], ray.range[1], ray.range[2]);
    // The step-by-step lookup is the CPU query (bit for bit).
    QueryOptions qo;
    qo.intraBias = ray.range[2];
    const QueryHit q = cpu->intersect(Ray{o, d, ray.range[0], ray.range[1]}, qo);
    EXPECT_EQ(q.hit, c.hit) << "ray " << r;
    if (q.hit && c.hit) {
      EXPECT_EQ(q.t, c.t) << "ray " << r;
    }
    ++a.rays;
    const GpuOut& g = out[r];
    const bool gLooked = (g.flags & 4u) != 0, gHit = (g.flags & 1u) != 0;
    auto hard = [&](const std::string& why) {
      ++a.hard;
      if (a.firstHard.empty()) {
        char buf[512];
        std::snprintf(buf, sizeof(buf),
                      "ray %zu: %s (cpu looked %d k %u texel %u,%u code %u hit %d t %.9g; gpu looked %d k %u "
                      "texel %u,%u code %u hit %d t %.9g)",
                      r, why.c_str(), c.looked, c.k, c.i, c.j, c.code, c.hit, double(c.t), gLooked, g.k, g.i, g.j,
                      g.code, gHit, double(g.t));
        a.firstHard = buf;
      }
    };
    if (gLooked != c.looked) {
      hard("lookup made on one side only");
      continue;
    }
    if (!c.looked) {
      if (gHit) {
        hard("GPU hit without a lookup");
      } else {
        ++a.agree;
      }
      continue;
    }
    if (g.k != c.k) {
      if (g.k >= f.mapCount) {
        hard("GPU sample out of range");
        continue;
      }
      const double l = std::sqrt(double(c.eu.x) * c.eu.x + double(c.eu.y) * c.eu.y + double(c.eu.z) * c.eu.z);
      auto dotk = [&](uint32_t k) {
        const Vec3 u = ps.position(k);
        return (double(u.x) * c.eu.x + double(u.y) * c.eu.y + double(u.z) * c.eu.z) / l;
      };
      if (std::fabs(dotk(g.k) - dotk(c.k)) <= kSampleEps) ++a.sampleBoundary;
      else hard("different sample");
      continue;
    }
    if (g.i != c.i || g.j != c.j) {
      auto nearLine = [&](float s, uint32_t ci, uint32_t gi) {
        if (ci == gi) return true;
        if (std::max(ci, gi) - std::min(ci, gi) != 1) return false;
        const double x = (double(s) + 1.0) * 0.5 * m;  // texel units
        return std::fabs(x - double(std::max(ci, gi))) <= kTexelEps;
      };
      if (nearLine(c.uv.x, c.i, g.i) && nearLine(c.uv.y, c.j, g.j)) ++a.texelBoundary;
      else hard("different texel");
      continue;
    }
    // Same texel: the same code and bit-identical distance. bc4-diameter: the texture unit computes
    // the interpolated palette entries itself and may round them the other way (spec/format.md 7.4),
    // so a hit's code may differ by one; its distance is then that code's, bit for bit.
    if (g.code != c.code && bc4 && g.code != 255 && c.code != 255 && (g.code == c.code + 1 || c.code == g.code + 1)) {
      const float want = float(g.code) * (2.0f * R / 254.0f);
      if (std::memcmp(&want, &g.distance, 4) != 0) hard("decoded distance not bit-identical to the GPU code's");
      else {
        ++a.bc4Rounding;
        ++a.agree;
      }
      continue;
    }
    if (g.code != c.code) {
      hard("different code for the same texel");
      continue;
    }
    uint32_t gb, cb;
    std::memcpy(&gb, &g.distance, 4);
    std::memcpy(&cb, &c.distance, 4);
    if (gb != cb) {
      hard("decoded distance not bit-identical");
      continue;
    }
    ++a.exactDistances;
    if (gHit != c.hit) {
      const double eps = kRangeEps * R;
      if (std::fabs(c.tLen - c.lo) <= eps || std::fabs(c.tLen - c.hi) <= eps) ++a.rangeBoundary;
      else hard("different hit flag for the same texel");
      continue;
    }
    if (c.hit) {
      ++a.hits;
      const double len = std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z);
      a.maxTDiff = std::max(a.maxTDiff, std::fabs(double(g.t) - double(c.t)) * len / R);
    }
    ++a.agree;
  }
  std::printf("[ gpu ] %s: %llu rays, agreement %.3f%% (%llu); allowed mismatches: sample boundary %llu, "
              "texel boundary %llu, range boundary %llu, bc4 rounding %llu; hard %llu; %llu texel-agreeing "
              "lookups with bit-identical distances, %llu hits, max |t_gpu - t_cpu| = %.3g R\n",
              label.c_str(), (unsigned long long)a.rays, 100.0 * double(a.agree) / double(std::max<uint64_t>(a.rays, 1)),
              (unsigned long long)a.agree, (unsigned long long)a.sampleBoundary, (unsigned long long)a.texelBoundary,
              (unsigned long long)a.rangeBoundary, (unsigned long long)a.bc4Rounding, (unsigned long long)a.hard, (unsigned long long)a.exactDistances,
              (unsigned long long)a.hits, a.maxTDiff);
  EXPECT_EQ(a.hard, 0u) << label << ": " << a.firstHard;
  EXPECT_LT(a.maxTDiff, 1e-5) << label;
  return a;
}

// ---- Baked fields ----------------------------------------------------------------------------------

using gputest::FieldCase;
using gputest::caseName;
Result<File> bakeFile(const FieldCase& c) { return gputest::bakeFile(c, false); }

class GpuQuery : public ::testing::TestWithParam<FieldCase> {};

TEST_P(GpuQuery, MatchesCpuNearest) {
  VFF_REQUIRE_GL();
  std::printf("[ gpu ] %s\n", harness::headlessGl().renderer.c_str());
  auto file = bakeFile(GetParam());
  ASSERT_TRUE(file.ok()) << file.error().toString();
  EXPECT_GT(file->layout().sliceCount, 1u);
  const Agreement a = compare(*file, 8192, 1234, caseName(GetParam()));
  EXPECT_GE(a.agree, a.rays * 99 / 100);  // boundary cases are rare
  EXPECT_GT(a.exactDistances, a.rays / 4);
}

std::vector<FieldCase> allCases() {
  std::vector<FieldCase> cases;
  for (auto p : {PositionScheme::kOctaHemi2, PositionScheme::kEqualAreaOctaGrid, PositionScheme::kSphericalFibonacci})
    for (auto d : {DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral})
      for (auto e : {DistanceEncoding::kUnorm8Diameter, DistanceEncoding::kUnorm8Chord,
                     DistanceEncoding::kUnorm16Diameter, DistanceEncoding::kBit1})
        cases.push_back({p, d, e});
  // The 3D target, once per encoding family.
  cases.push_back({PositionScheme::kOctaHemi2, DirectionScheme::kConcentricEqualArea,
                   DistanceEncoding::kUnorm16Diameter, LayoutTarget::kTexture3D});
  cases.push_back({PositionScheme::kSphericalFibonacci, DirectionScheme::kHemiOctahedral, DistanceEncoding::kBit1,
                   LayoutTarget::kTexture3D});
  // bc4-diameter (2D arrays only), once per direction scheme.
  for (auto d : {DirectionScheme::kConcentricEqualArea, DirectionScheme::kHemiOctahedral})
    cases.push_back({PositionScheme::kOctaHemi2, d, DistanceEncoding::kBc4Diameter});
  return cases;
}

INSTANTIATE_TEST_SUITE_P(Fields, GpuQuery, ::testing::ValuesIn(allCases()),
                         [](const ::testing::TestParamInfo<FieldCase>& i) { return caseName(i.param); });

// ---- Conformance vectors ---------------------------------------------------------------------------

std::vector<std::string> validVectors() {
  std::vector<std::string> names;
  const std::filesystem::path dir = std::filesystem::path(VFF_SOURCE_DIR) / "spec/conformance/valid";
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(dir, ec))
    if (e.path().extension() == ".vff") names.push_back(e.path().stem().string());
  std::sort(names.begin(), names.end());
  return names;
}

class GpuConformance : public ::testing::TestWithParam<std::string> {};

TEST_P(GpuConformance, MatchesCpuNearest) {
  VFF_REQUIRE_GL();
  const std::string path = std::string(VFF_SOURCE_DIR) + "/spec/conformance/valid/" + GetParam() + ".vff";
  auto file = File::open(path);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  compare(*file, 4096, 99, GetParam());
}

INSTANTIATE_TEST_SUITE_P(Valid, GpuConformance, ::testing::ValuesIn(validVectors()),
                         [](const ::testing::TestParamInfo<std::string>& i) {
                           std::string s = i.param;
                           for (char& ch : s)
                             if (!std::isalnum(static_cast<unsigned char>(ch))) ch = '_';
                           return s;
                         });

// ---- Building blocks, texel by texel ------------------------------------------------------------

// Runs `body` (GLSL statements that write vec4 res[8] for invocation id < count) after the include;
// returns 8 vec4 per invocation.
std::vector<float> runProbe(const std::string& body, uint32_t count) {
  std::string log;
  const GLuint prog = harness::buildQueryProgram(
      "",
      "layout(local_size_x = 64) in;\n"
      "layout(std430, binding = 4) writeonly buffer ProbeOut { vec4 outs[]; };\n"
      "void main() { uint id = gl_GlobalInvocationID.x; if (id >= " +
          std::to_string(count) + "u) return; vec4 res[8];\n for (int q = 0; q < 8; ++q) res[q] = vec4(0.0);\n" + body +
          "\n for (int q = 0; q < 8; ++q) outs[8u * id + uint(q)] = res[q]; }\n",
      &log);
  EXPECT_NE(prog, 0u) << log;
  GLuint buf;
  glGenBuffers(1, &buf);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, buf);
  std::vector<float> out(size_t(count) * 32);
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(out.size() * 4), nullptr, GL_STREAM_READ);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 4, buf);
  glUseProgram(prog);
  glDispatchCompute((count + 63) / 64, 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(out.size() * 4), out.data());
  glDeleteBuffers(1, &buf);
  glDeleteProgram(prog);
  return out;
}

bool sameBits(float a, float b) { return std::memcmp(&a, &b, 4) == 0; }

TEST(GpuGlsl, TexelCentresAndCosinesWithinFourUlpOfOne) {
  // vffTexelCenter and vffSquareToCosAlpha for every texel of M = 32 and M = 37 in both schemes
  // against vff::texelCenter / texelDirection. They are written to be bit-exact on an IEEE GPU, but
  // a driver may fuse or reassociate despite `precise` (llvmpipe does), so this checks an absolute
  // 4.8e-7 (four ulp of 1; the values lie in [-1, 1]) and reports how many are bit-exact. The query
  // does not depend on it: unorm8-chord reads its decode scales from the table the loader computes.
  VFF_REQUIRE_GL();
  constexpr float kUlp1 = 4.8e-7f;  // four ulp of 1: the values lie in [-1, 1]
  for (uint32_t m : {32u, 37u}) {
    for (uint32_t scheme : {1u, 2u}) {
      const std::string sc = std::to_string(scheme) + "u";
      const std::string body = "int M = " + std::to_string(m) + "; ivec2 ij = ivec2(int(id) % M, int(id) / M);\n"
                               "vec2 c = vffTexelCenter(ij, M);\n"
                               "res[0] = vec4(c, vffSquareToCosAlpha(" + sc + ", c), 0.0);\n"
                               "res[1] = vec4(vffSquareToHemisphere(" + sc + ", c), 0.0);";
      const std::vector<float> out = runProbe(body, m * m);
      uint32_t centres = 0, cosines = 0, close = 0, directions = 0;
      for (uint32_t j = 0; j < m; ++j)
        for (uint32_t i = 0; i < m; ++i) {
          const float* o = &out[size_t(j * m + i) * 32];
          const Vec2 c = texelCenter(i, j, m);
          const Vec3 d = texelDirection(DirectionScheme(scheme), m, i, j);
          centres += sameBits(o[0], c.x) && sameBits(o[1], c.y);
          cosines += sameBits(o[2], d.z);
          close += std::fabs(o[0] - c.x) <= kUlp1 && std::fabs(o[1] - c.y) <= kUlp1 && std::fabs(o[2] - d.z) <= kUlp1;
          directions += std::fabs(o[4] - d.x) < 1e-6f && std::fabs(o[5] - d.y) < 1e-6f && std::fabs(o[6] - d.z) < 1e-6f;
        }
      std::printf("[ gpu ] M %u, direction scheme %u: %u texels; bit-exact: %u centres, %u cosines; %u within 4.8e-7; "
                  "%u directions within 1e-6\n", m, scheme, m * m, centres, cosines, close, directions);
      EXPECT_EQ(close, m * m);
      EXPECT_EQ(directions, m * m);
    }
  }
}

// ---- The loader's limits ---------------------------------------------------------------------------

TEST(GpuLoader, RejectsLayoutBeyondTheContextLimits) {
  VFF_REQUIRE_GL();
  auto file = bakeFile({PositionScheme::kOctaHemi2, DirectionScheme::kConcentricEqualArea,
                        DistanceEncoding::kUnorm8Diameter});
  ASSERT_TRUE(file.ok()) << file.error().toString();
  gl::LoadOptions o;
  o.maxTextureSize = 128;  // the slices are 238 texels wide
  auto r = gl::loadField(*file, o);
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, Code::kUnsupported);
  EXPECT_NE(r.error().message.find("GL_MAX_TEXTURE_SIZE is 128"), std::string::npos) << r.error().message;
  // ...and says which layout would fit, and how to repack into it.
  EXPECT_NE(r.error().message.find("a layout that fits: "), std::string::npos) << r.error().message;
  EXPECT_NE(r.error().message.find("--max-texture-size 128"), std::string::npos) << r.error().message;
  o = {};
  o.maxLayers = 1;
  r = gl::loadField(*file, o);
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message.find("GL_MAX_ARRAY_TEXTURE_LAYERS is 1"), std::string::npos) << r.error().message;
  std::printf("[ gpu ] %s\n", r.error().toString().c_str());
  // Within the limits it loads, and the block mirrors the file.
  auto ok = gl::loadField(*file);
  ASSERT_TRUE(ok.ok()) << ok.error().toString();
  EXPECT_EQ(ok->block().sliceCount, file->layout().sliceCount);
  EXPECT_EQ(ok->block().tileSize, 34u);
  EXPECT_EQ(ok->textureBytes(), file->sliceBytes(Plane::kDistance) * file->layout().sliceCount);
}

}  // namespace
}  // namespace vff
