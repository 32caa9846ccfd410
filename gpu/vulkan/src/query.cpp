// The compute pipeline of vff/vk/query.h: descriptor set layout (the field's bindings 0 to 3, rays
// 4, answers 5), the embedded SPIR-V of shaders/vff_vk_query.comp, and one run over a batch of rays
// (the pipeline and the dispatch are compute.h's, shared with the scene's kernel).
#include "vff/vk/query.h"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <string>
#include <utility>

#include "compute.h"

namespace vff::vk {
namespace detail {
// Generated at build time (gpu/vulkan/CMakeLists.txt, embed_spirv.cmake).
extern const uint32_t kQuerySpirvArray2D[];
extern const size_t kQuerySpirvArray2DWords;
extern const uint32_t kQuerySpirvTexture3D[];
extern const size_t kQuerySpirvTexture3DWords;
extern const uint32_t kQuerySpirvBc4[];
extern const size_t kQuerySpirvBc4Words;
#if VFF_VK_HLSL
// The HLSL kernels (CMakeLists.txt, make_hlsl.cmake): spirv-cross's HLSL of the above, compiled by glslang's HLSL front end.
extern const uint32_t kQuerySpirvHlslArray2D[];
extern const size_t kQuerySpirvHlslArray2DWords;
extern const uint32_t kQuerySpirvHlslTexture3D[];
extern const size_t kQuerySpirvHlslTexture3DWords;
extern const uint32_t kQuerySpirvHlslBc4[];
extern const size_t kQuerySpirvHlslBc4Words;
#endif
}  // namespace detail

namespace {

constexpr uint32_t kRaysBinding = 4;
constexpr uint32_t kAnswersBinding = 5;
// Set 0: the field's bindings 0 to 3 (vff/vk/field.h), the rays, the answers.
constexpr VkDescriptorType kBindings[6] = {
    VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
    VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};

std::pair<const uint32_t*, size_t> spirv(MapsKind kind, ShaderLanguage language) {
#if VFF_VK_HLSL
  if (language == ShaderLanguage::kHlsl) {
    switch (kind) {
      case MapsKind::kTexture3D:
        return {detail::kQuerySpirvHlslTexture3D, detail::kQuerySpirvHlslTexture3DWords};
      case MapsKind::kBc4:
        return {detail::kQuerySpirvHlslBc4, detail::kQuerySpirvHlslBc4Words};
      default:
        return {detail::kQuerySpirvHlslArray2D, detail::kQuerySpirvHlslArray2DWords};
    }
  }
#else
  (void)language;
#endif
  switch (kind) {
    case MapsKind::kTexture3D:
      return {detail::kQuerySpirvTexture3D, detail::kQuerySpirvTexture3DWords};
    case MapsKind::kBc4:
      return {detail::kQuerySpirvBc4, detail::kQuerySpirvBc4Words};
    default:
      return {detail::kQuerySpirvArray2D, detail::kQuerySpirvArray2DWords};
  }
}

}  // namespace

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
  if (!available(options.language))
    return makeError(Code::kUnsupported,
                     "vff_vk: this build has no HLSL kernels (spirv-cross was not found when it was configured)");
  QueryPipeline p;
  p.s_ = std::make_unique<State>();
  State& s = *p.s_;
  s.kind = kind;
  s.language = options.language;
  const auto [code, words] = spirv(kind, options.language);
  if (Status st = detail::makeKernel(ctx, kBindings, code, words, &s.kernel); !st) return st.error();
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
  auto in = detail::makeHostBuffer(ctx, rays.size_bytes(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!in) return in.error();
  std::memcpy(in->mapped, rays.data(), rays.size_bytes());
  auto answers = detail::makeHostBuffer(ctx, out.size() * sizeof(QueryAnswer), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!answers) return answers.error();
  detail::DescriptorPool pool;
  auto set = detail::allocateSet(s.kernel, pool);
  if (!set) return set.error();
  field.write(*set);
  detail::writeBuffer(ctx.device(), *set, kRaysBinding, in->buffer);
  detail::writeBuffer(ctx.device(), *set, kAnswersBinding, answers->buffer);
  const uint32_t which = (options.nearest ? 1u : 0u) | (options.interpolated ? 2u : 0u);
  const auto start = std::chrono::steady_clock::now();
  Status st = detail::dispatchRays(ctx, s.kernel, *set, which, rays.size(), options.repeat);
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!st) return st.error();
  std::memcpy(out.data(), answers->mapped, out.size() * sizeof(QueryAnswer));
  return out;
}

}  // namespace vff::vk
