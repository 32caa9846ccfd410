// The refined query (gpu/glsl/vff_refine.glsl after vff_query.glsl) on Vulkan, as GLSL and as
// HLSL, against the CPU's Reconstruction::kRefined with the GL suite's shapes, rays and checks
// (refine_cases.h), the Khronos validation layer on.
//
// The kernel is gpu/vulkan/shaders/vff_vk_refine.comp after the GL loader's defines (shaderDefines,
// refinementShaderDefines), compiled when the case runs (vk_compile.h), so a change to
// vff_refine.glsl or vff_query.glsl reaches both languages' tests. The field is vff::vk::loadField's
// (bindings 0 to 3); the refinement is what vff::gl::loadRefinement uploads (makeRefinementBuffers),
// as storage buffers at bindings 10 to 13 and the VffRefineBlock uniform at 14; the rays and
// answers (refine_cases.h's GpuRay and GpuOut) are storage buffers at bindings 4 and 5.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <memory>
#include <ostream>
#include <string>
#include <vector>

#include "refine_cases.h"
#include "vff/gl/loader.h"
#include "vff/gl/refine_loader.h"
#include "vff/vk/field.h"
#include "vk_compile.h"
#include "vk_env.h"

namespace vff {
namespace {

using namespace refinetest;
using vk::ShaderLanguage;
using vktest::languageName;
using vktest::vkEnv;
namespace d = vk::detail;
using gl::RefinementBuffers;

constexpr VkDescriptorType kNone = VK_DESCRIPTOR_TYPE_MAX_ENUM, kStorage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                           kUniform = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
                           kImage = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
constexpr VkDescriptorType kBindings[] = {kUniform, kImage, kStorage, kImage,   kStorage, kStorage, kNone, kNone,
                                          kNone,    kNone,  kStorage, kStorage, kStorage, kStorage, kUniform};

// A host buffer holding `bytes` (at least 4 bytes: Vulkan has no empty buffer).
Result<d::Buffer> filled(const void* data, size_t bytes, VkBufferUsageFlags usage) {
  static const uint32_t kZero = 0;
  return bytes ? d::makeFilledBuffer(*vkEnv().ctx, data, bytes, usage) : d::makeFilledBuffer(*vkEnv().ctx, &kZero, 4, usage);
}

// vff_vk_refine.comp over the shape's rays in `language`; empty after a failure (reported).
std::vector<GpuOut> runRays(const RefinedShape& s, ShaderLanguage language, const std::vector<GpuRay>& rays) {
  const vk::Context& ctx = *vkEnv().ctx;
  const FieldDesc& f = s.file->field();
  auto field = vk::loadField(ctx, *s.file);
  EXPECT_TRUE(field.ok()) << (field.ok() ? "" : field.error().toString());
  auto buffers = gl::makeRefinementBuffers(f, s.file->refinement());
  EXPECT_TRUE(buffers.ok()) << (buffers.ok() ? "" : buffers.error().toString());
  if (!field.ok() || !buffers.ok()) return {};
  EXPECT_GT(buffers->block.triangleCount, 0u);
  // The kernel with the loader's defines after its #version line.
  std::string glsl = vktest::readText(std::filesystem::path(VFF_VK_SHADERS) / "vff_vk_refine.comp");
  const size_t version = glsl.find("#version 430\n");
  if (version == std::string::npos) {
    ADD_FAILURE() << "vff_vk_refine.comp has no #version 430 line";
    return {};
  }
  glsl.insert(version + 13, gl::shaderDefines(f, s.file->layout()) + gl::refinementShaderDefines(buffers->block));
  const std::unique_ptr<d::Kernel> kernel =
      vktest::makeTestKernel(glsl, language, "refined", "vff_vk_refine.comp", kBindings);
  if (!kernel) return {};
  d::DescriptorPool pool;
  auto set = d::allocateSet(*kernel, pool);
  const RefinementBuffers& b = *buffers;
  auto unsure = filled(b.unsure.data(), b.unsure.size() * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  auto vertices = filled(b.vertices.data(), b.vertices.size() * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  auto nodes = filled(b.nodes.data(), b.nodes.size() * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  auto triangles = filled(b.triangles.data(), b.triangles.size() * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  auto block = filled(&b.block, sizeof b.block, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);
  auto in = filled(rays.data(), rays.size() * sizeof(GpuRay), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  auto out = d::makeHostBuffer(ctx, rays.size() * sizeof(GpuOut), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  for (const Error* e : {set.ok() ? nullptr : &set.error(), unsure.ok() ? nullptr : &unsure.error(),
                         vertices.ok() ? nullptr : &vertices.error(), nodes.ok() ? nullptr : &nodes.error(),
                         triangles.ok() ? nullptr : &triangles.error(), block.ok() ? nullptr : &block.error(),
                         in.ok() ? nullptr : &in.error(), out.ok() ? nullptr : &out.error()})
    if (e) {
      ADD_FAILURE() << e->toString();
      return {};
    }
  field->write(*set);
  d::writeBuffer(ctx.device(), *set, 4, in->buffer);
  d::writeBuffer(ctx.device(), *set, 5, out->buffer);
  d::writeBuffer(ctx.device(), *set, 10, unsure->buffer);
  d::writeBuffer(ctx.device(), *set, 11, vertices->buffer);
  d::writeBuffer(ctx.device(), *set, 12, nodes->buffer);
  d::writeBuffer(ctx.device(), *set, 13, triangles->buffer);
  d::writeBuffer(ctx.device(), *set, 14, block->buffer, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER);
  if (Status st = d::dispatchRays(ctx, *kernel, *set, 0, rays.size(), 1); !st) {
    ADD_FAILURE() << st.error().toString();
    return {};
  }
  std::vector<GpuOut> answers(rays.size());
  std::memcpy(answers.data(), out->mapped, answers.size() * sizeof(GpuOut));
  return answers;
}

struct Case {
  const char* shape;
  ShaderLanguage language;
};

void PrintTo(const Case& c, std::ostream* os) { *os << c.shape << ", " << languageName(c.language); }

class VkRefine : public ::testing::TestWithParam<Case> {};

TEST_P(VkRefine, MatchesCpu) {
  VFF_REQUIRE_VK();
  VFF_REQUIRE_TOOLS(GetParam().language);
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

}  // namespace
}  // namespace vff
