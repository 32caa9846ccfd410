// The distance-field peer's GLSL sphere tracer (gpu/glsl/vff_sdf.glsl through PNanoVDB, uploaded by
// gpu/sdf/sdf_gl.h) against the CPU tracer (sdf/src/sdf_field.cpp) on the same rays and
// the same grid, on a headless EGL context.
//
// Tolerances and the comparison: sdf_cases.h (shared with the Vulkan suite). The AO images (same
// rays: ao_scene.h) within kAoMax levels of 255 per pixel, RMS kAoRms.
#include <GL/glcorearb.h>
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "ao_gl.h"
#include "sdf_ao.h"
#include "vff/sdf/sdf_field.h"
#include "dispatch.h"
#include "egl_context.h"
#include "gl_test.h"
#include "sdf_cases.h"
#include "sdf_gl.h"
#include "vff/bake/mesh.h"
#include "vff/bake/procedural.h"
#include "vff/bake/sphere.h"

namespace {

using vff::Vec3;

using namespace vff::sdftest;

constexpr double kAoMax = 8.0;  // one ray of 32 answered differently
constexpr double kAoRms = 0.25;

const char* kRayMain = R"(
layout(local_size_x = 64) in;
struct TestRay { vec4 origin; vec4 direction; };  // origin.w tmin, direction.w tmax
layout(std430, binding = 3) readonly buffer TestRays { TestRay rays[]; };
layout(std430, binding = 4) writeonly buffer TestOuts { vec4 outs[]; };
void main() {
  uint id = gl_GlobalInvocationID.x;
  if (id >= uint(rays.length())) return;
  TestRay r = rays[id];
  VffSdfHit h = vffSdfIntersect(r.origin.xyz, r.direction.xyz, r.origin.w, r.direction.w);
  outs[id] = vec4(h.hit ? 1.0 : 0.0, h.t, float(h.steps), vffSdfVisibility(r.origin.xyz, r.direction.xyz, r.origin.w, r.direction.w));
}
)";

GLuint buildSdfProgram(const vffx::SdfField& sdf, const std::string& body) {
  std::string log;
  const std::string src = "#version 430\n" + vffx::gl::sdfShaderDefines(sdf) +
                          vffx::gl::sdfShaderSource(vff::harness::readGlsl("vff_sdf.glsl")) + body;
  const GLuint prog = vff::harness::buildProgram(src, &log);
  EXPECT_NE(prog, 0u) << log;
  return prog;
}

// kRayMain over `rays` with the grid uploaded with `options`: hit, t, steps, visibility per ray.
std::vector<float> runRays(const vffx::SdfField& sdf, const vffx::SdfTraceOptions& options,
                           const std::vector<vff::Ray>& rays) {
  auto gpu = vffx::gl::uploadSdf(sdf, options);
  EXPECT_TRUE(gpu) << gpu.error().toString();
  if (!gpu) return {};
  EXPECT_EQ(gpu->gridBytes(), sdf.nanovdbBytes());
  const GLuint prog = buildSdfProgram(sdf, kRayMain);
  if (!prog) return {};
  const std::vector<float> in = packRays(rays);
  gpu->bind();
  glUseProgram(prog);
  std::vector<float> out = vff::test::dispatchRays<float>(std::span<const float>(in), rays.size(), 4, 3, 4);
  glDeleteProgram(prog);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  return out;
}

// GPU against CPU on `rays` through one grid; prints the counts.
void compareTracers(const char* what, const vffx::SdfField& sdf, const std::vector<vff::Ray>& rays) {
  expectTracerMatches("gpu", what, sdf, rays, runRays(sdf, {}, rays));
}

TEST(GpuSdf, TracerMatchesCpuOnTorusKnot) {
  VFF_REQUIRE_GL();
  const vff::bake::Mesh m = vff::bake::makeShape("torus-knot");
  const auto rays = makeRays(boundingSphere(m), 2048, 11);
  for (vffx::SdfValues v : {vffx::SdfValues::kFloat, vffx::SdfValues::kFp8})
    compareTracers("torus knot", buildSdf(m, 256 << 10, v), rays);
}

TEST(GpuSdf, TracerMatchesCpuOnBunny) {
  VFF_REQUIRE_GL();
  const std::string path = std::string(VFF_SHARED_MESHES) + "/stanford-bunny.obj";
  if (!std::filesystem::exists(path)) GTEST_SKIP() << path << " not found (the shared test meshes)";
  auto m = vff::bake::loadMesh(path);
  ASSERT_TRUE(m) << m.error().toString();
  compareTracers("stanford bunny", buildSdf(*m, 512 << 10, vffx::SdfValues::kFp8),
                 makeRays(boundingSphere(*m), 1024, 12));
}

// The cone estimate (vffSdfVisibility with the block's coneTan, then coneRadiusAtEnd) against
// SdfField::visibility on the same rays: the minimum over the same steps of the same expression,
// so within rounding where the traces agree.
TEST(GpuSdf, ConeEstimateMatchesCpu) {
  VFF_REQUIRE_GL();
  const vff::bake::Mesh m = vff::bake::makeShape("torus-knot");
  const vff::Sphere bs = boundingSphere(m);
  const vffx::SdfField sdf = buildSdf(m, 256 << 10, vffx::SdfValues::kFp8);
  const std::vector<vff::Ray> rays = capRays(makeRays(bs, 2048, 13), bs.radius);
  vffx::SdfTraceOptions byTan, byRadius;
  byTan.coneTan = vffx::hemisphereConeTan(32);
  byRadius.coneRadiusAtEnd = 0.2f * bs.radius;
  for (const vffx::SdfTraceOptions& o : {byTan, byRadius}) expectConeMatches("gpu", sdf, o, rays, runRays(sdf, o, rays));
}

// The ground AO (ao_scene.h) under the torus knot through the GLSL tracer and the CPU one: hit or
// miss (kAoShader's nearest path) and the cone estimate (its interpolated path, the experiments'
// options: sdfOptions, hemisphereConeTan).
TEST(GpuSdf, GroundAoMatchesCpu) {
  VFF_REQUIRE_GL();
  const vff::bake::Mesh m = vff::bake::makeShape("torus-knot");
  const vffx::SdfField sdf = buildSdf(m, 256 << 10, vffx::SdfValues::kFp8);
  float minY = INFINITY;
  for (size_t v = 1; v < m.positions.size(); v += 3) minY = std::min(minY, m.positions[v]);
  vff::FieldDesc f;
  f.sphere = boundingSphere(m);
  constexpr int kSize = 32, kRays = 32;
  const vff::harness::AoScene s = vff::harness::makeAoScene(f, minY, kSize);
  auto gpu = vffx::gl::uploadSdf(sdf);
  ASSERT_TRUE(gpu) << gpu.error().toString();
  std::string log;
  const GLuint prog = vff::harness::buildProgram(
      vff::harness::sdfAoShaderSource(sdf, vff::harness::readGlsl("vff_query.glsl"), vff::harness::readGlsl("vff_sdf.glsl")),
      &log);
  ASSERT_NE(prog, 0u) << log;
  const vff::harness::AoBuffers aoBuffers(s);
  for (const bool cone : {false, true}) {
    const vffx::SdfTraceOptions so = vffx::sdfOptions(cone, false, vffx::hemisphereConeTan(kRays));
    ASSERT_TRUE(gpu->setTraceOptions(so));
    gpu->bind();
    glUseProgram(prog);
    std::vector<float> g;
    (void)vff::harness::renderAo(s, aoBuffers, kRays, cone ? 1 : 0, &g);
    ASSERT_EQ(glGetError(), GLenum(GL_NO_ERROR));
    const std::vector<float> c =
        vff::harness::cpuAo(vff::harness::SdfAoQuery{&sdf, so}, s, kRays, vff::Reconstruction::kNearest, 2);
    const vff::harness::AoDiff d = vff::harness::compareAo(c, g);
    std::printf(
        "[ gpu ] sdf ground AO %dx%d, %d rays/px, %s: CPU mean AO %.4f (min %.3f); GPU vs CPU on the 8-bit "
        "scale: max %.0f, RMS %.4f, %llu of %d pixels differ\n",
        kSize, kSize, kRays, cone ? "cone estimate" : "hit or miss", d.meanA, d.minA, d.max, d.rms,
        (unsigned long long)d.differing, kSize * kSize);
    EXPECT_LT(d.minA, 0.9) << "the knot should occlude some of the ground";
    EXPECT_LE(d.max, kAoMax);
    EXPECT_LE(d.rms, kAoRms);
  }
  glDeleteProgram(prog);
}

}  // namespace
