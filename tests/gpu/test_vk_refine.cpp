// The refined query (gpu/glsl/vff_refine.glsl after vff_query.glsl) on Vulkan, as GLSL and as
// HLSL, against the CPU's Reconstruction::kRefined with the GL suite's shapes, rays and checks
// (refine_cases.h), the Khronos validation layer on.
//
// Through the library's API (vff/vk/refine.h): vff::vk::loadField, vff::vk::loadRefinement and
// RefinedPipeline, whose kernels (gpu/vulkan/shaders/vff_vk_refine.comp and spirv-cross's HLSL of
// it) are compiled when vff_vk is built, so a change to vff_refine.glsl or vff_query.glsl reaches
// both languages' tests. Also: a file without a refinement, and a refinement run with another field.
#include <gtest/gtest.h>

#include <cstddef>
#include <cstring>
#include <ostream>
#include <string>
#include <vector>

#include "refine_cases.h"
#include "vff/vk/field.h"
#include "vff/vk/refine.h"
#include "vk_env.h"

namespace vff {
namespace {

using namespace refinetest;
using vk::ShaderLanguage;
using vktest::languageName;
using vktest::vkEnv;

// The test's structs are the API's, byte for byte (refine_cases.h is shared with the GL and WebGPU
// suites, which have no vff::vk).
static_assert(sizeof(GpuRay) == sizeof(vk::QueryRay) && sizeof(GpuOut) == sizeof(vk::RefinedAnswer));
static_assert(offsetof(vk::RefinedAnswer, nearestHit) == offsetof(GpuOut, nearest) &&
              offsetof(vk::RefinedAnswer, exact) == offsetof(GpuOut, lookup));

// vff::vk::RefinedPipeline (shaders/vff_vk_refine.comp, embedded) over the shape's rays in
// `language`; empty after a failure (reported).
std::vector<GpuOut> runRays(const RefinedShape& s, ShaderLanguage language, const std::vector<GpuRay>& rays) {
  const vk::Context& ctx = *vkEnv().ctx;
  auto field = vk::loadField(ctx, *s.file);
  EXPECT_TRUE(field.ok()) << (field.ok() ? "" : field.error().toString());
  auto refinement = vk::loadRefinement(ctx, *s.file);
  EXPECT_TRUE(refinement.ok()) << (refinement.ok() ? "" : refinement.error().toString());
  if (!field.ok() || !refinement.ok()) return {};
  EXPECT_GT(refinement->block().triangleCount, 0u);
  auto pipe = vk::RefinedPipeline::create(ctx, field->kind(), {.language = language});
  EXPECT_TRUE(pipe.ok()) << (pipe.ok() ? "" : pipe.error().toString());
  if (!pipe.ok()) return {};
  EXPECT_EQ(pipe->language(), language);
  std::vector<vk::QueryRay> in(rays.size());
  std::memcpy(in.data(), rays.data(), rays.size() * sizeof(GpuRay));
  auto answers = pipe->run(ctx, *field, *refinement, in);
  EXPECT_TRUE(answers.ok()) << (answers.ok() ? "" : answers.error().toString());
  if (!answers.ok()) return {};
  std::vector<GpuOut> out(answers->size());
  std::memcpy(out.data(), answers->data(), out.size() * sizeof(GpuOut));
  return out;
}

struct Case {
  const char* shape;
  ShaderLanguage language;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.shape << ", " << languageName(c.language); }

class VkRefine : public ::testing::TestWithParam<Case> {};

TEST_P(VkRefine, MatchesCpu) {
  VFF_REQUIRE_VK();
  VFF_REQUIRE_LANGUAGE(GetParam().language);
  const RefinedShape& s = refinedShape(GetParam().shape);
  ASSERT_TRUE(s.file.has_value());
  ASSERT_FALSE(s.file->refinement().empty());
  ASSERT_TRUE(s.query.refined());
  constexpr uint32_t kPerSet = 2048;
  const std::vector<GpuRay> rays = makeRays(s, kPerSet, 20261205);
  const std::vector<GpuOut> out = runRays(s, GetParam().language, rays);
  ASSERT_FALSE(out.empty());
  expectRefinedMatchesCpu(languageName(GetParam().language), GetParam().shape, s, rays, out, kPerSet);
  vktest::expectNoValidationMessages();
}

INSTANTIATE_TEST_SUITE_P(Shapes, VkRefine,
                         ::testing::Values(Case{"torus-knot", ShaderLanguage::kGlsl}, Case{"bowl", ShaderLanguage::kGlsl},
                                           Case{"torus-knot", ShaderLanguage::kHlsl}, Case{"bowl", ShaderLanguage::kHlsl}),
                         [](const ::testing::TestParamInfo<Case>& p) {
                           std::string n = std::string(p.param.shape) + "_" + languageName(p.param.language);
                           for (char& c : n)
                             if (c == '-') c = '_';
                           return n;
                         });

// Without a REFN section the kernel answers every ray as kNearest (triangleCount 0), as the CPU
// query does, and the exact step never runs.
TEST(VkRefineApi, WithoutRefinementEveryRayIsNearest) {
  VFF_REQUIRE_VK();
  const vk::Context& ctx = *vkEnv().ctx;
  const RefinedShape& s = refinedShape("torus-knot");
  const test::BakedShape& b = *s.baked;
  auto bytes = writeMemory(b.field.field, b.field.distance, b.field.normals, WriteOptions{});
  ASSERT_TRUE(bytes.ok()) << bytes.error().toString();
  auto file = File::openBuffer(std::move(*bytes));
  ASSERT_TRUE(file.ok()) << file.error().toString();
  ASSERT_TRUE(file->refinement().empty());
  auto field = vk::loadField(ctx, *file);
  auto refinement = vk::loadRefinement(ctx, *file);
  ASSERT_TRUE(field.ok() && refinement.ok());
  EXPECT_EQ(refinement->block().triangleCount, 0u);
  auto pipe = vk::RefinedPipeline::create(ctx, field->kind());
  ASSERT_TRUE(pipe.ok()) << pipe.error().toString();
  const std::vector<GpuRay> rays = makeRays(s, 512, 20261206);
  std::vector<vk::QueryRay> in(rays.size());
  std::memcpy(in.data(), rays.data(), rays.size() * sizeof(GpuRay));
  auto answers = pipe->run(ctx, *field, *refinement, in);
  ASSERT_TRUE(answers.ok()) << answers.error().toString();
  size_t hits = 0, exact = 0, differ = 0;
  for (const vk::RefinedAnswer& a : *answers) {
    hits += a.hit != 0;
    exact += a.exact;
    differ += a.hit != a.nearestHit || (a.hit != 0 && a.t != a.nearestT);
  }
  EXPECT_GT(hits, rays.size() / 8);
  EXPECT_EQ(exact, 0u);
  EXPECT_EQ(differ, 0u);
  vktest::expectNoValidationMessages();
}

// A refinement run with another field (other maps) is refused with a message, not read out of
// range; so is a field of another variant than the pipeline's.
TEST(VkRefineApi, RefinementOfAnotherFieldIsRefused) {
  VFF_REQUIRE_VK();
  const vk::Context& ctx = *vkEnv().ctx;
  const RefinedShape& s = refinedShape("torus-knot");
  const auto other = test::bakeShape("bowl", 6, 12);
  auto bytes = writeMemory(other->field.field, other->field.distance, other->field.normals, WriteOptions{});
  ASSERT_TRUE(bytes.ok()) << bytes.error().toString();
  auto otherFile = File::openBuffer(std::move(*bytes));
  ASSERT_TRUE(otherFile.ok());
  auto otherField = vk::loadField(ctx, *otherFile);
  auto refinement = vk::loadRefinement(ctx, *s.file);
  ASSERT_TRUE(otherField.ok() && refinement.ok());
  auto pipe = vk::RefinedPipeline::create(ctx, otherField->kind());
  ASSERT_TRUE(pipe.ok()) << pipe.error().toString();
  const std::vector<vk::QueryRay> in(4, vk::QueryRay{{0, 0, 3, 0}, {0, 0, -1, 0}, {0, 100, -1, 0}});
  auto refused = pipe->run(ctx, *otherField, *refinement, in);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code, Code::kInvalidArgument);
  EXPECT_NE(refused.error().message.find("the refinement covers"), std::string::npos) << refused.error().message;
  auto pipe3d = vk::RefinedPipeline::create(ctx, vk::MapsKind::kTexture3D);
  ASSERT_TRUE(pipe3d.ok()) << pipe3d.error().toString();
  auto field = vk::loadField(ctx, *s.file);
  ASSERT_TRUE(field.ok());
  auto wrongVariant = pipe3d->run(ctx, *field, *refinement, in);
  ASSERT_FALSE(wrongVariant.ok());
  EXPECT_EQ(wrongVariant.error().code, Code::kInvalidArgument);
  vktest::expectNoValidationMessages();
}

}  // namespace
}  // namespace vff
