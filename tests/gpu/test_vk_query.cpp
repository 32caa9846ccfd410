// The Vulkan path of the single-object query (gpu/vulkan, vff_vk): gpu/glsl/vff_query.glsl compiled
// to SPIR-V at build time, the field uploaded by vff::vk::loadField, rays run by
// vff::vk::QueryPipeline, against the CPU query ray by ray, with the Khronos validation layer on.
//
// Every Vulkan case runs twice: with the kernel compiled from GLSL (instantiations Fields, Valid) and
// with the one compiled from the HLSL that spirv-cross generates from it (FieldsHlsl, ValidHlsl;
// vff::vk::ShaderLanguage::kHlsl), same rays, same tolerances. Where the build has no HLSL kernels
// (no spirv-cross) the HLSL cases skip and say why.
//
// The cases, rays and the kNearest comparison are the GL suite's (field_cases.h, nearest_check.h),
// with its tolerances:
// * kNearest: every ray's lookup (sample k, texel (i, j), code, decoded distance) and hit flag are
//   the CPU's, except at the boundaries nearest_check.h allows; where the texel agrees the decoded
//   distance is bit-identical, and t within 1e-5 R. bc4-diameter (where the device samples BC4): a
//   hit's code may be one off the CPU's, its distance then that code's.
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
#include <ostream>
#include <string>
#include <vector>

#include "baked_fields.h"
#include "field_cases.h"
#include "nearest_check.h"
#include "vff/vff.h"
#include "vff/vk/context.h"
#include "vff/vk/field.h"
#include "vff/vk/query.h"
#include "vk_env.h"

namespace vff {
namespace {

using vk::QueryAnswer;
using vk::QueryRay;
using vk::ShaderLanguage;
using vktest::expectNoValidationMessages, vktest::languageName, vktest::vkEnv;  // vk_env.h

// Uploads the field and runs the rays; ADD_FAILUREs and returns empty on a setup failure.
std::vector<QueryAnswer> runVk(const File& file, ShaderLanguage language, const std::vector<QueryRay>& rays) {
  const vk::Context& ctx = *vkEnv().ctx;
  auto gpu = vk::loadField(ctx, file);
  EXPECT_TRUE(gpu.ok()) << gpu.error().toString();
  if (!gpu) return {};
  vk::PipelineOptions po;
  po.language = language;
  auto pipe = vk::QueryPipeline::create(ctx, gpu->kind(), po);
  EXPECT_TRUE(pipe.ok()) << pipe.error().toString();
  if (!pipe) return {};
  auto out = pipe->run(ctx, *gpu, rays);
  EXPECT_TRUE(out.ok()) << out.error().toString();
  if (!out) return {};
  return std::move(*out);
}

// ---- kNearest (nearest_check.h) ----------------------------------------------------------------------

gputest::Agreement compareNearest(const File& file, ShaderLanguage language, uint32_t rayCount, uint64_t seed,
                                  const std::string& label) {
  auto cpu = FieldQuery::fromFile(file);
  EXPECT_TRUE(cpu.ok()) << cpu.error().toString();
  if (!cpu) return {};
  const std::vector<QueryRay> rays = gputest::nearestRays<QueryRay>(file.field(), rayCount, seed);
  const std::vector<QueryAnswer> out = runVk(file, language, rays);
  if (out.size() != rays.size()) return {};
  return gputest::compareNearestAnswers(file, *cpu, rays, out,
                                        "[ vk ] " + label + " (" + languageName(language) + "): kNearest", label);
}

// ---- The cases, in each shading language ---------------------------------------------------------

using gputest::caseName;
using gputest::FieldCase;

// A case and the language of the kernel it runs (vk::PipelineOptions::language). The GLSL cases
// keep their names (instantiation "Fields"/"Valid"); the HLSL ones are "FieldsHlsl"/"ValidHlsl".
template <class T>
struct InLanguage {
  T value;
  ShaderLanguage language;
};

template <class T>
std::vector<InLanguage<T>> inLanguage(const std::vector<T>& values, ShaderLanguage language) {
  std::vector<InLanguage<T>> out;
  for (const T& v : values) out.push_back({v, language});
  return out;
}

void PrintTo(const InLanguage<FieldCase>& c, std::ostream* os) {
  *os << caseName(c.value) << " (" << languageName(c.language) << ")";
}
void PrintTo(const InLanguage<std::string>& c, std::ostream* os) {
  *os << c.value << " (" << languageName(c.language) << ")";
}

std::string fieldParamName(const ::testing::TestParamInfo<InLanguage<FieldCase>>& i) {
  return caseName(i.param.value);
}
std::string vectorParamName(const ::testing::TestParamInfo<InLanguage<std::string>>& i) {
  return gputest::vectorName(i.param.value);
}

// BC4 is optional in Vulkan (textureCompressionBC); the loader says so as kUnsupported, and the
// case skips with that message.
#define VFF_SKIP_IF_NO_BC4(file)                                                                            \
  do {                                                                                                      \
    if ((file).field().distanceEncoding == DistanceEncoding::kBc4Diameter) {                                \
      auto probe = vk::loadField(*vkEnv().ctx, (file));                                                     \
      if (!probe && probe.error().code == Code::kUnsupported) GTEST_SKIP() << probe.error().message;        \
    }                                                                                                       \
  } while (0)

// ---- Baked fields, kNearest ---------------------------------------------------------------------------

class VkQuery : public ::testing::TestWithParam<InLanguage<FieldCase>> {};

TEST_P(VkQuery, MatchesCpuNearest) {
  VFF_REQUIRE_VK();
  VFF_REQUIRE_LANGUAGE(GetParam().language);
  auto file = gputest::bakeFile(GetParam().value, false);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  EXPECT_GT(file->layout().sliceCount, 1u);
  VFF_SKIP_IF_NO_BC4(*file);
  const gputest::Agreement a = compareNearest(*file, GetParam().language, 8192, 1234, caseName(GetParam().value));
  gputest::expectBakedAgreement(a, caseName(GetParam().value));
  expectNoValidationMessages();
}

INSTANTIATE_TEST_SUITE_P(Fields, VkQuery, ::testing::ValuesIn(inLanguage(gputest::nearestCases(), ShaderLanguage::kGlsl)),
                         fieldParamName);
INSTANTIATE_TEST_SUITE_P(FieldsHlsl, VkQuery,
                         ::testing::ValuesIn(inLanguage(gputest::nearestCases(), ShaderLanguage::kHlsl)),
                         fieldParamName);

// ---- Conformance vectors, kNearest -------------------------------------------------------------------

class VkConformance : public ::testing::TestWithParam<InLanguage<std::string>> {};

TEST_P(VkConformance, MatchesCpuNearest) {
  VFF_REQUIRE_VK();
  VFF_REQUIRE_LANGUAGE(GetParam().language);
  auto file = File::open(gputest::vectorPath(GetParam().value));
  ASSERT_TRUE(file.ok()) << file.error().toString();
  VFF_SKIP_IF_NO_BC4(*file);
  compareNearest(*file, GetParam().language, 4096, 99, GetParam().value);
  expectNoValidationMessages();
}

INSTANTIATE_TEST_SUITE_P(Valid, VkConformance,
                         ::testing::ValuesIn(inLanguage(gputest::validVectors(), ShaderLanguage::kGlsl)),
                         vectorParamName);
INSTANTIATE_TEST_SUITE_P(ValidHlsl, VkConformance,
                         ::testing::ValuesIn(inLanguage(gputest::validVectors(), ShaderLanguage::kHlsl)),
                         vectorParamName);

// ---- Normals and kInterpolated ----------------------------------------------------------------------

class VkField : public ::testing::TestWithParam<InLanguage<FieldCase>> {};

TEST_P(VkField, NormalsAndInterpolatedMatchCpu) {
  VFF_REQUIRE_VK();
  VFF_REQUIRE_LANGUAGE(GetParam().language);
  auto file = gputest::bakeFile(GetParam().value, true);
  ASSERT_TRUE(file.ok()) << file.error().toString();
  ASSERT_TRUE(file->hasNormals());
  auto cpu = FieldQuery::fromFile(*file);
  ASSERT_TRUE(cpu.ok()) << cpu.error().toString();
  const std::vector<QueryRay> rays = gputest::interpolatedRays<QueryRay>(file->field(), 8192, 77);
  const std::vector<QueryAnswer> out = runVk(*file, GetParam().language, rays);
  ASSERT_EQ(out.size(), rays.size());
  gputest::InterpCounts n;
  for (size_t r = 0; r < rays.size(); ++r)
    gputest::compareInterpolated(*cpu, rays[r], out[r], file->field().sphere.radius, r, n);
  gputest::reportInterpolated(
      n, "[ vk ] " + caseName(GetParam().value) + " (" + languageName(GetParam().language) + ")",
      caseName(GetParam().value));
  expectNoValidationMessages();
}

INSTANTIATE_TEST_SUITE_P(Fields, VkField,
                         ::testing::ValuesIn(inLanguage(gputest::interpolatedCases(), ShaderLanguage::kGlsl)),
                         fieldParamName);
INSTANTIATE_TEST_SUITE_P(FieldsHlsl, VkField,
                         ::testing::ValuesIn(inLanguage(gputest::interpolatedCases(), ShaderLanguage::kHlsl)),
                         fieldParamName);

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
  const std::vector<QueryRay> rays = gputest::nearestRays<QueryRay>(file->field(), 4, 1);
  auto out = pipe->run(ctx, *gpu, rays);
  ASSERT_FALSE(out.ok());
  EXPECT_EQ(out.error().code, Code::kInvalidArgument);
  expectNoValidationMessages();
}

}  // namespace
}  // namespace vff
