// The GLSL refined query (gpu/glsl/vff_refine.glsl after vff_query.glsl: vffIntersectRefined,
// vffOccludedRefined; vff/gl/refine_loader.h uploads the refinement) against the CPU's
// Reconstruction::kRefined, on a headless EGL context: the shapes, rays, tolerances and checks of
// refine_cases.h, with the field uploaded by loadField and the refinement by loadRefinement.
// Without a refinement (an empty view) the shader answers every ray as vffIntersect does.
#include <gtest/gtest.h>
#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "dispatch.h"
#include "egl_context.h"
#include "gl_test.h"
#include "refine_cases.h"
#include "vff/gl/loader.h"
#include "vff/gl/refine_loader.h"
#include "vff/refine.h"
#include "vff/vff.h"

namespace vff {
namespace {

using namespace refinetest;

// The main of gpu/vulkan/shaders/vff_vk_refine.comp on GL (no push constant, no #include): the
// same calls, after rayShaderHead has read the ray `r`.
const char* const kMainBody = R"(
  VffHit h = vffIntersectRefined(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
  bool occluded = vffOccludedRefined(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
  bool exact;
  VffHit x = vffQueryRefined(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z, false, exact);
  VffHit n = vffIntersect(r.origin.xyz, r.direction.xyz, r.range.x, r.range.y, r.range.z);
  TestOut o;
  o.refined = vec4(h.hit ? 1.0 : 0.0, h.t, occluded ? 1.0 : 0.0, h.hasNormal ? 1.0 : 0.0);
  o.normal = vec4(h.normal, x.hit == h.hit && (!h.hit || x.t == h.t) ? 1.0 : 0.0);
  o.nearest = vec4(n.hit ? 1.0 : 0.0, n.t, 0.0, 0.0);
  o.lookup = uvec4(exact ? 1u : 0u, x.looked ? x.sampleIndex : 0xffffffffu, x.texel);
)";
const char* const kTestOut = "struct TestOut { vec4 refined; vec4 normal; vec4 nearest; uvec4 lookup; };\n";

const std::string kMain = std::string(kTestOut) + test::rayShaderHead(5, 6) + kMainBody + "  outs[id] = o;\n}\n";

GLuint buildProgram(const std::string& defines) {
  std::string log;
  const GLuint prog = harness::buildQueryProgram(defines, harness::readGlsl("vff_refine.glsl") + kMain, &log);
  EXPECT_NE(prog, 0u) << log;
  return prog;
}

std::vector<GpuOut> runRays(const gl::GpuField& field, const gl::GpuRefinement& refinement, GLuint program,
                            const std::vector<GpuRay>& rays) {
  field.bind();
  refinement.bind();
  glUseProgram(program);
  std::vector<GpuOut> out = test::dispatchRays<GpuOut>(std::span<const GpuRay>(rays), rays.size(), 1, 5, 6);
  EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
  return out;
}

void expectGlMatchesCpu(const std::string& shape) {
  const RefinedShape& s = refinedShape(shape);
  ASSERT_TRUE(s.file.has_value());
  ASSERT_FALSE(s.file->refinement().empty());
  ASSERT_TRUE(s.query.refined());
  const FieldDesc& f = s.file->field();
  auto field = gl::loadField(*s.file);
  ASSERT_TRUE(field.ok()) << field.error().toString();
  auto refinement = gl::loadRefinement(*s.file);
  ASSERT_TRUE(refinement.ok()) << refinement.error().toString();
  ASSERT_GT(refinement->block().triangleCount, 0u);
  const GLuint prog = buildProgram(gl::shaderDefines(f, s.file->layout()) + refinement->shaderDefines());
  ASSERT_NE(prog, 0u);
  constexpr uint32_t kPerSet = 2048;
  const std::vector<GpuRay> rays = makeRays(s, kPerSet, 20261205);
  const std::vector<GpuOut> out = runRays(*field, *refinement, prog, rays);
  glDeleteProgram(prog);
  expectRefinedMatchesCpu("gpu", shape, s, rays, out, kPerSet);
}

TEST(GpuRefine, TorusKnotMatchesCpu) {
  VFF_REQUIRE_GL();
  expectGlMatchesCpu("torus-knot");
}

TEST(GpuRefine, BowlMatchesCpu) {
  VFF_REQUIRE_GL();
  expectGlMatchesCpu("bowl");
}

// An empty refinement: triangleCount 0, and every ray answered as vffIntersect answers it (as the
// CPU's kRefined without a refinement answers as kNearest).
TEST(GpuRefine, EmptyRefinementAnswersAsNearest) {
  VFF_REQUIRE_GL();
  const RefinedShape& s = refinedShape("bowl");
  ASSERT_TRUE(s.file.has_value());
  const FieldDesc& f = s.file->field();
  auto field = gl::loadField(*s.file);
  ASSERT_TRUE(field.ok()) << field.error().toString();
  auto refinement = gl::loadRefinement(f, RefinementView{});
  ASSERT_TRUE(refinement.ok()) << refinement.error().toString();
  EXPECT_EQ(refinement->block().triangleCount, 0u);
  const GLuint prog = buildProgram(gl::shaderDefines(f, s.file->layout()) + refinement->shaderDefines());
  ASSERT_NE(prog, 0u);
  const std::vector<GpuRay> rays = makeRays(s, 512, 7);
  const std::vector<GpuOut> out = runRays(*field, *refinement, prog, rays);
  glDeleteProgram(prog);
  expectAnsweredAsNearest("gpu", rays, out);
}

// The loader refuses a refinement of another field (kInvalidArgument, as FieldQuery::fromMaps).
TEST(GpuRefine, LoaderRefusesAnotherFieldsRefinement) {
  VFF_REQUIRE_GL();
  const RefinedShape& knot = refinedShape("torus-knot");
  ASSERT_TRUE(knot.file.has_value());
  FieldDesc other = knot.file->field();
  other.mapResolution = 32;  // the unsure bits no longer match
  auto r = gl::loadRefinement(other, knot.file->refinement());
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code, Code::kInvalidArgument);
}

}  // namespace
}  // namespace vff
