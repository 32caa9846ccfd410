// The GLSL lookup (gpu/glsl/vff_query.glsl), uploaded with vff_gl and run in a compute shader on a
// headless EGL context, against the CPU query (vff::FieldQuery::intersect, kNearest) ray by ray.
//
// For every ray the shader writes the hit flag, t and the lookup it made (sample k, texel (i, j),
// stored code, decoded distance); nearest_check.h classifies each against the CPU's lookup (the
// boundaries where a disagreement is allowed, and what must then be bit-identical). The cases and
// rays are field_cases.h's, which the Vulkan suite (test_vk_query.cpp) runs too.
#include <gtest/gtest.h>
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>
#include <vector>

#include "baked_fields.h"
#include "field_cases.h"
#include "nearest_check.h"
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

// ---- The comparison (nearest_check.h) ---------------------------------------------------------------

gputest::GpuLookup lookupOf(const GpuOut& g) {
  return {(g.flags & 4u) != 0, (g.flags & 1u) != 0, g.t, g.k, g.i, g.j, g.code, g.distance};
}

// Runs the rays on the GPU and compares with the CPU; returns the counts (after ADD_FAILUREs on a
// setup failure).
gputest::Agreement compare(const File& file, uint32_t rayCount, uint64_t seed, const std::string& label) {
  gputest::Agreement a;
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
  const std::vector<GpuRay> rays = gputest::nearestRays<GpuRay>(file.field(), rayCount, seed);
  const std::vector<GpuOut> out = runGpu(*gpu, program, rays);
  glDeleteProgram(program);
  for (size_t r = 0; r < rays.size(); ++r) {
    const gputest::CpuLookup c = gputest::cpuLookup(file, cpu->positions(), rays[r]);
    gputest::expectLookupIsCpuQuery(*cpu, rays[r], c, r);
    gputest::classify(file, cpu->positions(), rays[r], c, lookupOf(out[r]), r, a);
  }
  gputest::reportAgreement(a, "[ gpu ] " + label, label);
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
  const gputest::Agreement a = compare(*file, 8192, 1234, caseName(GetParam()));
  EXPECT_GE(a.agree, a.rays * 99 / 100);  // boundary cases are rare
  EXPECT_GT(a.exactDistances, a.rays / 4);
}

INSTANTIATE_TEST_SUITE_P(Fields, GpuQuery, ::testing::ValuesIn(gputest::nearestCases()), gputest::caseParamName);

// ---- Conformance vectors ---------------------------------------------------------------------------

class GpuConformance : public ::testing::TestWithParam<std::string> {};

TEST_P(GpuConformance, MatchesCpuNearest) {
  VFF_REQUIRE_GL();
  auto file = File::open(gputest::vectorPath(GetParam()));
  ASSERT_TRUE(file.ok()) << file.error().toString();
  compare(*file, 4096, 99, GetParam());
}

INSTANTIATE_TEST_SUITE_P(Valid, GpuConformance, ::testing::ValuesIn(gputest::validVectors()),
                         gputest::vectorParamName);

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
