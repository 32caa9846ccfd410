// vk_env.h - what every Vulkan GPU suite (test_vk_query.cpp, test_vk_scene.cpp) starts from: one
// context per process (a CPU device first, the Khronos validation layer on), the skips where there
// is no Vulkan device, no validation layer or no kernels of a language, and the check that ends
// every case: zero validation errors and warnings.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "vff/error.h"
#include "vff/vk/context.h"
#include "vff/vk/query.h"

namespace vff::vktest {

using vk::ShaderLanguage;

inline const char* languageName(ShaderLanguage l) {
  return l == ShaderLanguage::kHlsl ? "HLSL" : "GLSL";
}

// The case's context: a CPU device first (lavapipe, as the GL tests' llvmpipe), validation on.
// Each gtest case runs in its own process (gtest_discover_tests), so this is one context a case.
struct VkEnv {
  Result<vk::Context> ctx = makeError(Code::kBadState, "not created");
  std::string skip;  // why the case cannot run
};

inline VkEnv& vkEnv() {
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

#define VFF_REQUIRE_VK()                                                                   \
  do {                                                                                     \
    if (!::vff::vktest::vkEnv().skip.empty()) GTEST_SKIP() << ::vff::vktest::vkEnv().skip; \
  } while (0)

// The HLSL kernels are built only where spirv-cross was found (gpu/vulkan/CMakeLists.txt).
#define VFF_REQUIRE_LANGUAGE(language)                                                            \
  do {                                                                                            \
    if (!::vff::vk::QueryPipeline::available(language))                                           \
      GTEST_SKIP() << ::vff::vktest::languageName(language)                                       \
                   << " kernels not built: spirv-cross was not found when vff_vk was configured"; \
  } while (0)

// Every case ends here: nothing reported by the validation layer.
inline void expectNoValidationMessages() {
  const vk::Context& c = *vkEnv().ctx;
  std::printf("[ vk ] validation: %u errors, %u warnings\n", c.validationErrors(), c.validationWarnings());
  EXPECT_EQ(c.validationErrors(), 0u) << c.validationLog();
  EXPECT_EQ(c.validationWarnings(), 0u) << c.validationLog();
}

}  // namespace vff::vktest
