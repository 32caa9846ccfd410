// The distance-field peer's sphere tracer (gpu/glsl/vff_sdf.glsl through PNanoVDB's GLSL path) on
// Vulkan, as GLSL and as HLSL, against the CPU tracer (sdf/src/sdf_field.cpp) with the GL suite's
// rays and tolerances (sdf_cases.h), the Khronos validation layer on.
//
// The kernels are compiled when the case runs (vk_compile.h), from the text the GL path compiles
// (sdfShaderDefines and sdfShaderSource give the grid type and the trace constants from the C++
// side), so a change to vff_sdf.glsl reaches both languages' tests. The grid is a storage buffer at
// binding 8, the block (SdfBlock, std140) a uniform buffer at binding 9, the rays and answers
// storage buffers at bindings 3 and 4.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include "sdf_cases.h"
#include "sdf_gl.h"
#include "vff/bake/mesh.h"
#include "vff/bake/procedural.h"
#include "vk_compile.h"
#include "vk_env.h"

namespace {

namespace fs = std::filesystem;
using namespace vff::sdftest;
using vff::vk::ShaderLanguage;
using vff::vktest::languageName;
using vff::vktest::vkEnv;
using vff::vktest::makeTestKernel;
using vff::vktest::readText;

const char* kVkRayMain = R"(
layout(local_size_x = 64) in;
struct TestRay { vec4 origin; vec4 direction; };  // origin.w tmin, direction.w tmax
layout(std430, binding = 3) readonly buffer TestRays { TestRay rays[]; };
layout(std430, binding = 4) writeonly buffer TestOuts { vec4 outs[]; };
layout(push_constant) uniform VffVkPush { uint which; uint firstRay; uint rayCount; } vffVkPush;
void main() {
  uint id = gl_GlobalInvocationID.x + vffVkPush.firstRay;
  if (id >= vffVkPush.rayCount) return;
  TestRay r = rays[id];
  VffSdfHit h = vffSdfIntersect(r.origin.xyz, r.direction.xyz, r.origin.w, r.direction.w);
  outs[id] = vec4(h.hit ? 1.0 : 0.0, h.t, float(h.steps), vffSdfVisibility(r.origin.xyz, r.direction.xyz, r.origin.w, r.direction.w));
}
)";

namespace d = vff::vk::detail;

// The kernel for grids of `sdf`'s value type in `language`; null after a failure (reported).
std::unique_ptr<d::Kernel> makeSdfKernel(const vffx::SdfField& sdf, ShaderLanguage language) {
  static constexpr VkDescriptorType kBindings[] = {
      VK_DESCRIPTOR_TYPE_MAX_ENUM,       VK_DESCRIPTOR_TYPE_MAX_ENUM,       VK_DESCRIPTOR_TYPE_MAX_ENUM,
      VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_MAX_ENUM,
      VK_DESCRIPTOR_TYPE_MAX_ENUM,       VK_DESCRIPTOR_TYPE_MAX_ENUM,       VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
      VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER};
  const std::string glsl = "#version 450\n" + vffx::gl::sdfShaderDefines(sdf) +
                           vffx::gl::sdfShaderSource(readText(fs::path(VFF_GLSL_DIR) / "vff_sdf.glsl")) + kVkRayMain;
  return makeTestKernel(glsl, language, sdf.values() == vffx::SdfValues::kFp8 ? "fp8" : "float",
                        "gpu/glsl/vff_sdf.glsl", kBindings);
}

// kVkRayMain over `rays` through `sdf`'s grid traced with `options`: hit, t, steps, visibility per
// ray (sdf_cases.h).
std::vector<float> runRays(const d::Kernel& kernel, const vffx::SdfField& sdf, const vffx::SdfTraceOptions& options,
                           const std::vector<vff::Ray>& rays) {
  const vff::vk::Context& ctx = *vkEnv().ctx;
  d::DescriptorPool pool;
  auto set = d::allocateSet(kernel, pool);
  const std::span<const uint8_t> grid = sdf.gridBuffer();
  const vffx::gl::SdfBlock block = vffx::gl::makeSdfBlock(sdf, options);
  const std::vector<float> in = packRays(rays);
  auto gridBuffer = d::makeFilledBuffer(ctx, grid.data(), grid.size(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  auto blockBuffer = d::makeFilledBuffer(ctx, &block, sizeof block, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);
  auto rayBuffer = d::makeFilledBuffer(ctx, in.data(), in.size() * 4, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  auto outBuffer = d::makeHostBuffer(ctx, rays.size() * 16, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  const vff::Error* failed = !set           ? &set.error()
                             : !gridBuffer  ? &gridBuffer.error()
                             : !blockBuffer ? &blockBuffer.error()
                             : !rayBuffer   ? &rayBuffer.error()
                             : !outBuffer   ? &outBuffer.error()
                                            : nullptr;
  if (failed) {
    ADD_FAILURE() << failed->toString();
    return {};
  }
  d::writeBuffer(ctx.device(), *set, 3, rayBuffer->buffer);
  d::writeBuffer(ctx.device(), *set, 4, outBuffer->buffer);
  d::writeBuffer(ctx.device(), *set, 8, gridBuffer->buffer);
  d::writeBuffer(ctx.device(), *set, 9, blockBuffer->buffer, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER);
  if (vff::Status st = d::dispatchRays(ctx, kernel, *set, 0, rays.size(), 1); !st) {
    ADD_FAILURE() << st.error().toString();
    return {};
  }
  std::vector<float> out(rays.size() * 4);
  std::memcpy(out.data(), outBuffer->mapped, out.size() * 4);
  return out;
}

// One case a language, so that each kernel is compiled once (lavapipe takes seconds to compile
// PNanoVDB's paths): the GL suite's cases on the float and the Fp8 kernel.
class VkSdf : public ::testing::TestWithParam<ShaderLanguage> {};

TEST_P(VkSdf, TracerAndConeMatchCpu) {
  VFF_REQUIRE_VK();
  VFF_REQUIRE_TOOLS(GetParam());
  const char* api = languageName(GetParam());
  const vff::bake::Mesh m = vff::bake::makeShape("torus-knot");
  const vff::Sphere bs = boundingSphere(m);
  const vffx::SdfField knotFloat = buildSdf(m, 256 << 10, vffx::SdfValues::kFloat);
  const vffx::SdfField knotFp8 = buildSdf(m, 256 << 10, vffx::SdfValues::kFp8);
  const std::unique_ptr<d::Kernel> floatKernel = makeSdfKernel(knotFloat, GetParam());
  const std::unique_ptr<d::Kernel> fp8Kernel = makeSdfKernel(knotFp8, GetParam());
  ASSERT_TRUE(floatKernel && fp8Kernel);

  // The torus knot, both value types.
  const auto rays = makeRays(bs, 2048, 11);
  expectTracerMatches(api, "torus knot", knotFloat, rays, runRays(*floatKernel, knotFloat, {}, rays));
  expectTracerMatches(api, "torus knot", knotFp8, rays, runRays(*fp8Kernel, knotFp8, {}, rays));

  // The cone estimate, both ways of setting the cone.
  const std::vector<vff::Ray> capped = capRays(makeRays(bs, 2048, 13), bs.radius);
  vffx::SdfTraceOptions byTan, byRadius;
  byTan.coneTan = vffx::hemisphereConeTan(32);
  byRadius.coneRadiusAtEnd = 0.2f * bs.radius;
  for (const vffx::SdfTraceOptions& o : {byTan, byRadius})
    expectConeMatches(api, knotFp8, o, capped, runRays(*fp8Kernel, knotFp8, o, capped));

  // The shared Stanford bunny, where present.
  const std::string path = std::string(VFF_SHARED_MESHES) + "/stanford-bunny.obj";
  if (!fs::exists(path)) {
    std::printf("[ %s ] sdf stanford bunny skipped: %s not found (the shared test meshes)\n", api, path.c_str());
  } else {
    auto bunny = vff::bake::loadMesh(path);
    ASSERT_TRUE(bunny) << bunny.error().toString();
    const vffx::SdfField sdf = buildSdf(*bunny, 512 << 10, vffx::SdfValues::kFp8);
    const auto bunnyRays = makeRays(boundingSphere(*bunny), 1024, 12);
    expectTracerMatches(api, "stanford bunny", sdf, bunnyRays, runRays(*fp8Kernel, sdf, {}, bunnyRays));
  }
  vff::vktest::expectNoValidationMessages();
}

INSTANTIATE_TEST_SUITE_P(Languages, VkSdf, ::testing::Values(ShaderLanguage::kGlsl, ShaderLanguage::kHlsl),
                         [](const ::testing::TestParamInfo<ShaderLanguage>& p) {
                           return std::string(languageName(p.param));
                         });

}  // namespace
