// vk_compile.h - a compute kernel's SPIR-V made when a Vulkan case runs, in either language, from
// GLSL text that the C++ completes first (defines that only a loader or a grid knows): GLSL ->
// glslangValidator -V -> SPIR-V; for HLSL, that SPIR-V -> spirv-cross through
// gpu/vulkan/make_hlsl.cmake (as vff_vk's HLSL kernels are made at build time) -> glslangValidator
// -D -V (glslang's HLSL front end) -> SPIR-V. Then vff_vk's pipeline (gpu/vulkan/src/compute.h).
// The tools' paths come from CMake (tests/gpu/CMakeLists.txt: VFF_GLSLANG, VFF_SPIRV_CROSS,
// VFF_CMAKE, VFF_MAKE_HLSL, VFF_HLSL_PRELUDE); an empty path means the tool was not found.
#pragma once

#include <gtest/gtest.h>
#include <unistd.h>

#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <span>
#include <sstream>
#include <string>
#include <vector>

#include "compute.h"
#include "vk_env.h"

namespace vff::vktest {

inline std::string readText(const std::filesystem::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

// Runs a command with its output in `log`; *why holds the command and its output when it fails.
inline bool runTool(const std::string& command, const std::filesystem::path& log, std::string* why) {
  const int rc = std::system((command + " > '" + log.string() + "' 2>&1").c_str());
  if (rc == 0) return true;
  *why = command + " failed (" + std::to_string(rc) + "):\n" + readText(log);
  return false;
}

// A scratch folder for one kernel's files, removed with it.
struct Scratch {
  std::filesystem::path dir;
  Scratch() {
    std::string t = (std::filesystem::temp_directory_path() / "vff-vk-kernel-XXXXXX").string();
    if (mkdtemp(t.data())) dir = t;
  }
  Scratch(const Scratch&) = delete;
  Scratch& operator=(const Scratch&) = delete;
  ~Scratch() {
    std::error_code ec;
    if (!dir.empty()) std::filesystem::remove_all(dir, ec);
  }
};

// Why a case cannot compile kernels of `language` here; empty when it can.
inline std::string missingTools(vk::ShaderLanguage language) {
  if (std::string(VFF_GLSLANG).empty()) return "glslangValidator was not found";
  if (language == vk::ShaderLanguage::kHlsl && std::string(VFF_SPIRV_CROSS).empty())
    return "spirv-cross was not found when the tests were configured (the HLSL is made with it)";
  return {};
}

// The SPIR-V words of `glsl` (a whole compute shader; its #include lines found in gpu/glsl) in
// `language`; `variant` and `source` name the HLSL's variant and origin in its header. Empty with
// *why on failure.
inline std::vector<uint32_t> compileKernel(const std::string& glsl, vk::ShaderLanguage language, const std::string& variant,
                                           const std::string& source, std::string* why) {
  namespace fs = std::filesystem;
  Scratch s;
  if (s.dir.empty()) {
    *why = "no scratch folder";
    return {};
  }
  const fs::path comp = s.dir / "kernel.comp", spv = s.dir / "glsl.spv", log = s.dir / "log.txt";
  std::ofstream(comp, std::ios::binary) << glsl;
  if (!runTool(std::string("'") + VFF_GLSLANG + "' -V -S comp -I'" + VFF_GLSL_DIR + "' -o '" + spv.string() + "' '" + comp.string() + "'", log, why))
    return {};
  fs::path words = spv;
  if (language == vk::ShaderLanguage::kHlsl) {
    const fs::path hlsl = s.dir / "kernel.hlsl", hspv = s.dir / "hlsl.spv";
    if (!runTool(std::string("'") + VFF_CMAKE + "' -DSPIRV_CROSS='" + VFF_SPIRV_CROSS + "' -DIN='" + spv.string() +
                     "' -DOUT='" + hlsl.string() + "' -DVARIANT=" + variant + " -DSOURCE=" + source +
                     " -DGLSL=" + source + " -DPRELUDE='" + VFF_HLSL_PRELUDE + "' -P '" + VFF_MAKE_HLSL + "'",
                 log, why))
      return {};
    if (!runTool(std::string("'") + VFF_GLSLANG + "' -D -V -S comp -e main -o '" + hspv.string() + "' '" +
                     hlsl.string() + "'",
                 log, why))
      return {};
    words = hspv;
  }
  const std::string bytes = readText(words);
  std::vector<uint32_t> code(bytes.size() / 4);
  std::memcpy(code.data(), bytes.data(), code.size() * 4);
  if (code.empty()) *why = words.string() + " is empty";
  return code;
}

// The pipeline of `glsl` in `language` with set 0's `bindings` (static storage: compute.h's
// makeKernel keeps the span); null after a failure, which it reports.
inline std::unique_ptr<vk::detail::Kernel> makeTestKernel(const std::string& glsl, vk::ShaderLanguage language,
                                                          const std::string& variant, const std::string& source,
                                                          std::span<const VkDescriptorType> bindings) {
  std::string why;
  const std::vector<uint32_t> code = compileKernel(glsl, language, variant, source, &why);
  EXPECT_FALSE(code.empty()) << why;
  if (code.empty()) return nullptr;
  auto kernel = std::make_unique<vk::detail::Kernel>();
  if (Status st = vk::detail::makeKernel(*vkEnv().ctx, bindings, code.data(), code.size(), kernel.get()); !st) {
    ADD_FAILURE() << st.error().toString();
    return nullptr;
  }
  return kernel;
}

#define VFF_REQUIRE_TOOLS(language)                                                                     \
  do {                                                                                                  \
    if (const std::string missing = ::vff::vktest::missingTools(language); !missing.empty()) GTEST_SKIP() << missing; \
  } while (0)

}  // namespace vff::vktest
