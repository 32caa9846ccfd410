// gl_test.h - what the GPU tests' GL cases share: VFF_REQUIRE_GL(), which skips a case (saying why)
// where no headless OpenGL 4.3 context opens, and the head of their compute shaders.
#pragma once

#include <gtest/gtest.h>

#include <string>

#include "egl_context.h"

#define VFF_REQUIRE_GL()                                                            \
  do {                                                                              \
    const ::vff::harness::HeadlessGl& gl_ = ::vff::harness::headlessGl();           \
    if (!gl_.ok) GTEST_SKIP() << "no headless OpenGL 4.3 context: " << gl_.error; \
  } while (0)

namespace vff::test {

// The head of a test's compute shader, one ray per invocation: the rays (TestRay: origin, direction,
// range = tmin, tmax, intraBias) at storage binding `rayBinding`, the answers (the test's TestOut,
// declared before this) at `outBinding`, and main() as far as the invocation's ray `r` (index `id`;
// the invocations past the last ray return).
inline std::string rayShaderHead(int rayBinding, int outBinding) {
  return "layout(local_size_x = 64) in;\n"
         "struct TestRay { vec4 origin; vec4 direction; vec4 range; };\n"
         "layout(std430, binding = " + std::to_string(rayBinding) + ") readonly buffer TestRays { TestRay rays[]; };\n"
         "layout(std430, binding = " + std::to_string(outBinding) + ") writeonly buffer TestOuts { TestOut outs[]; };\n"
         "void main() {\n"
         "  uint id = gl_GlobalInvocationID.x;\n"
         "  if (id >= uint(rays.length())) return;\n"
         "  TestRay r = rays[id];\n";
}

}  // namespace vff::test
