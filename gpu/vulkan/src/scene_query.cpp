// The scene walk's compute pipeline (vff/vk/scene.h): the scene's bindings 1 to 6, rays 7, answers
// 8, the embedded SPIR-V of shaders/vff_vk_scene.comp (or of its generated HLSL), and one run over a
// batch of rays; the pipeline and the dispatch are compute.h's, shared with QueryPipeline.
#include <string>

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

detail::Spirv spirv(ShaderLanguage language) {
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
  if (Status st = detail::requireLanguage(options.language); !st) return st.error();
  ScenePipeline p;
  p.s_ = std::make_unique<State>();
  p.s_->language = options.language;
  const detail::Spirv code = spirv(options.language);
  if (Status st = detail::makeKernel(ctx, kBindings, code.code, code.words, &p.s_->kernel); !st) return st.error();
  return p;
}

Result<std::vector<SceneAnswer>> ScenePipeline::run(const Context& ctx, const GpuScene& scene,
                                                    std::span<const SceneRay> rays, const SceneRunOptions& options,
                                                    double* seconds) const {
  const State& s = *s_;
  if (Status st = detail::checkBatch(ctx, rays.size(), sizeof(SceneAnswer)); !st) return st.error();
  std::vector<SceneAnswer> out(rays.size());
  if (rays.empty()) return out;
  const detail::Batch batch{.rays = rays.data(),
                            .rayCount = rays.size(),
                            .rayBytes = rays.size_bytes(),
                            .answers = out.data(),
                            .answerBytes = out.size() * sizeof(SceneAnswer),
                            .raysBinding = kRaysBinding,
                            .answersBinding = kAnswersBinding,
                            .which = (options.nearest ? 1u : 0u) | (options.interpolated ? 2u : 0u) |
                                     (options.occluded ? 4u : 0u) | (options.visibility ? 8u : 0u),
                            .repeat = options.repeat};
  const auto write = [&](VkDescriptorSet set) { scene.write(set); };
  if (Status st = detail::runBatch(ctx, s.kernel, batch, write, seconds); !st) return st.error();
  return out;
}

}  // namespace vff::vk
