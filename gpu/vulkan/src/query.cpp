// The compute pipeline of vff/vk/query.h: descriptor set layout (the field's bindings 0 to 3, rays
// 4, answers 5), the embedded SPIR-V of shaders/vff_vk_query.comp, and one run over a batch of rays
// (the pipeline and the dispatch are compute.h's, shared with the scene's kernel).
#include "vff/vk/query.h"

#include <cstddef>

#include "compute.h"

namespace vff::vk {
namespace detail {
// Generated at build time (gpu/vulkan/CMakeLists.txt, embed_spirv.cmake; the HLSL kernels by
// make_hlsl.cmake from spirv-cross's HLSL of the GLSL's SPIR-V).
VFF_VK_DECLARE_VARIANTS(kQuerySpirv)
#if VFF_VK_HLSL
VFF_VK_DECLARE_VARIANTS(kQuerySpirvHlsl)
#endif

namespace {

// Set 0: the field's bindings 0 to 3 (vff/vk/field.h), the rays, the answers.
constexpr VkDescriptorType kBindings[6] = {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                                           VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                                           VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};

Spirv spirv(MapsKind kind, ShaderLanguage language) {
#if VFF_VK_HLSL
  if (language == ShaderLanguage::kHlsl) return VFF_VK_VARIANTS(kQuerySpirvHlsl)[kind];
#else
  (void)language;
#endif
  return VFF_VK_VARIANTS(kQuerySpirv)[kind];
}

}  // namespace
}  // namespace detail

struct QueryPipeline::State {
  MapsKind kind = MapsKind::kArray2D;
  ShaderLanguage language = ShaderLanguage::kGlsl;
  detail::Kernel kernel;
};

QueryPipeline::QueryPipeline() = default;
QueryPipeline::QueryPipeline(QueryPipeline&&) noexcept = default;
QueryPipeline& QueryPipeline::operator=(QueryPipeline&&) noexcept = default;
QueryPipeline::~QueryPipeline() = default;
MapsKind QueryPipeline::kind() const noexcept {
  return s_->kind;
}
ShaderLanguage QueryPipeline::language() const noexcept {
  return s_->language;
}

bool QueryPipeline::available(ShaderLanguage language) noexcept {
  if (language == ShaderLanguage::kGlsl) return true;
  return language == ShaderLanguage::kHlsl && VFF_VK_HLSL != 0;
}

Result<QueryPipeline> QueryPipeline::create(const Context& ctx, MapsKind kind, const PipelineOptions& options) {
  if (Status st = detail::requireLanguage(options.language); !st) return st.error();
  QueryPipeline p;
  p.s_ = std::make_unique<State>();
  State& s = *p.s_;
  s.kind = kind;
  s.language = options.language;
  const detail::Spirv code = detail::spirv(kind, options.language);
  if (Status st = detail::makeKernel(ctx, detail::kBindings, code.code, code.words, &s.kernel); !st) return st.error();
  return p;
}

Result<std::vector<QueryAnswer>> QueryPipeline::run(const Context& ctx, const GpuField& field,
                                                    std::span<const QueryRay> rays, const RunOptions& options,
                                                    double* seconds) const {
  const State& s = *s_;
  if (field.kind() != s.kind)
    return makeError(Code::kInvalidArgument, "the field needs another shader variant than this QueryPipeline's");
  if (Status st = detail::checkBatch(ctx, rays.size(), sizeof(QueryAnswer)); !st) return st.error();
  std::vector<QueryAnswer> out(rays.size());
  if (rays.empty()) return out;
  const detail::Batch batch{.rays = rays.data(),
                            .rayCount = rays.size(),
                            .rayBytes = rays.size_bytes(),
                            .answers = out.data(),
                            .answerBytes = out.size() * sizeof(QueryAnswer),
                            .which = (options.nearest ? 1u : 0u) | (options.interpolated ? 2u : 0u),
                            .repeat = options.repeat};
  const auto write = [&](VkDescriptorSet set) { field.write(set); };
  if (Status st = detail::runBatch(ctx, s.kernel, batch, write, seconds); !st) return st.error();
  return out;
}

}  // namespace vff::vk
