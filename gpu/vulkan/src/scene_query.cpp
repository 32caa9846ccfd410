// The scene walk's compute pipeline (vff/vk/scene.h): the scene's bindings 1 to 6, rays 7, answers
// 8, the embedded SPIR-V of shaders/vff_vk_scene.comp (or of its generated HLSL), and one run over a
// batch of rays; the pipeline and the dispatch are compute.h's, shared with QueryPipeline.
#include <chrono>
#include <cstring>
#include <string>
#include <utility>

#include "compute.h"
#include "vff/vk/scene.h"

namespace vff::vk {
namespace detail {
// Generated at build time (gpu/vulkan/CMakeLists.txt, embed_spirv.cmake, make_hlsl.cmake).
extern const uint32_t kSceneSpirvArray2D[];
extern const size_t kSceneSpirvArray2DWords;
#if VFF_VK_HLSL
extern const uint32_t kSceneSpirvHlslArray2D[];
extern const size_t kSceneSpirvHlslArray2DWords;
#endif
}  // namespace detail

namespace {

constexpr uint32_t kRaysBinding = 7;
constexpr uint32_t kAnswersBinding = 8;
// Set 0: no binding 0 (the scene's field table replaces the single field's uniform block).
constexpr VkDescriptorType kBindings[9] = {VK_DESCRIPTOR_TYPE_MAX_ENUM,       VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                                           VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                                           VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                           VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                                           VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};

std::pair<const uint32_t*, size_t> spirv(ShaderLanguage language) {
#if VFF_VK_HLSL
  if (language == ShaderLanguage::kHlsl) return {detail::kSceneSpirvHlslArray2D, detail::kSceneSpirvHlslArray2DWords};
#else
  (void)language;
#endif
  return {detail::kSceneSpirvArray2D, detail::kSceneSpirvArray2DWords};
}

}  // namespace

struct ScenePipeline::State {
  ShaderLanguage language = ShaderLanguage::kGlsl;
  detail::Kernel kernel;
};

ScenePipeline::ScenePipeline() = default;
ScenePipeline::ScenePipeline(ScenePipeline&&) noexcept = default;
ScenePipeline& ScenePipeline::operator=(ScenePipeline&&) noexcept = default;
ScenePipeline::~ScenePipeline() = default;
ShaderLanguage ScenePipeline::language() const noexcept {
  return s_->language;
}

Result<ScenePipeline> ScenePipeline::create(const Context& ctx, const PipelineOptions& options) {
  if (!QueryPipeline::available(options.language))
    return makeError(Code::kUnsupported,
                     "vff_vk: this build has no HLSL kernels (spirv-cross was not found when it was configured)");
  ScenePipeline p;
  p.s_ = std::make_unique<State>();
  p.s_->language = options.language;
  const auto [code, words] = spirv(options.language);
  if (Status st = detail::makeKernel(ctx, kBindings, code, words, &p.s_->kernel); !st) return st.error();
  return p;
}

Result<std::vector<SceneAnswer>> ScenePipeline::run(const Context& ctx, const GpuScene& scene,
                                                    std::span<const SceneRay> rays, const SceneRunOptions& options,
                                                    double* seconds) const {
  const State& s = *s_;
  if (Status st = detail::checkBatch(ctx, rays.size(), sizeof(SceneAnswer)); !st) return st.error();
  std::vector<SceneAnswer> out(rays.size());
  if (rays.empty()) return out;
  auto in = detail::makeFilledBuffer(ctx, rays.data(), rays.size_bytes(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!in) return in.error();
  auto answers = detail::makeHostBuffer(ctx, out.size() * sizeof(SceneAnswer), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!answers) return answers.error();
  detail::DescriptorPool pool;
  auto set = detail::allocateSet(s.kernel, pool);
  if (!set) return set.error();
  scene.write(*set);
  detail::writeBuffer(ctx.device(), *set, kRaysBinding, in->buffer);
  detail::writeBuffer(ctx.device(), *set, kAnswersBinding, answers->buffer);
  const uint32_t which = (options.nearest ? 1u : 0u) | (options.interpolated ? 2u : 0u) | (options.occluded ? 4u : 0u) |
                         (options.visibility ? 8u : 0u);
  const auto start = std::chrono::steady_clock::now();
  Status st = detail::dispatchRays(ctx, s.kernel, *set, which, rays.size(), options.repeat);
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!st) return st.error();
  std::memcpy(out.data(), answers->mapped, out.size() * sizeof(SceneAnswer));
  return out;
}

}  // namespace vff::vk
