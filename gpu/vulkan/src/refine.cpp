// The refined query of vff/vk/refine.h: the refinement's upload (vff::gl::makeRefinementBuffers'
// words in five host-visible buffers) and the pipeline of the embedded SPIR-V of
// shaders/vff_vk_refine.comp (compute.h's kernel and dispatch, as the query's).
#include "vff/vk/refine.h"

#include <chrono>
#include <cstring>
#include <string>
#include <utility>

#include "compute.h"

namespace vff::vk {
namespace detail {
// Generated at build time (gpu/vulkan/CMakeLists.txt, embed_spirv.cmake).
extern const uint32_t kRefineSpirvArray2D[];
extern const size_t kRefineSpirvArray2DWords;
extern const uint32_t kRefineSpirvTexture3D[];
extern const size_t kRefineSpirvTexture3DWords;
extern const uint32_t kRefineSpirvBc4[];
extern const size_t kRefineSpirvBc4Words;
#if VFF_VK_HLSL
extern const uint32_t kRefineSpirvHlslArray2D[];
extern const size_t kRefineSpirvHlslArray2DWords;
extern const uint32_t kRefineSpirvHlslTexture3D[];
extern const size_t kRefineSpirvHlslTexture3DWords;
extern const uint32_t kRefineSpirvHlslBc4[];
extern const size_t kRefineSpirvHlslBc4Words;
#endif
}  // namespace detail

namespace {

constexpr uint32_t kRaysBinding = 4;
constexpr uint32_t kAnswersBinding = 5;
constexpr VkDescriptorType kNone = VK_DESCRIPTOR_TYPE_MAX_ENUM, kStorage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                           kUniform = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
                           kImage = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
// Set 0: the field's bindings 0 to 3, the rays, the answers, nothing at 6 to 9 (vff_query.glsl's
// scene and peer bindings), the refinement's 10 to 14.
constexpr VkDescriptorType kBindings[] = {kUniform, kImage, kStorage, kImage,   kStorage, kStorage, kNone,   kNone,
                                          kNone,    kNone,  kStorage, kStorage, kStorage, kStorage, kUniform};

std::pair<const uint32_t*, size_t> spirv(MapsKind kind, ShaderLanguage language) {
#if VFF_VK_HLSL
  if (language == ShaderLanguage::kHlsl) {
    switch (kind) {
      case MapsKind::kTexture3D:
        return {detail::kRefineSpirvHlslTexture3D, detail::kRefineSpirvHlslTexture3DWords};
      case MapsKind::kBc4:
        return {detail::kRefineSpirvHlslBc4, detail::kRefineSpirvHlslBc4Words};
      default:
        return {detail::kRefineSpirvHlslArray2D, detail::kRefineSpirvHlslArray2DWords};
    }
  }
#else
  (void)language;
#endif
  switch (kind) {
    case MapsKind::kTexture3D:
      return {detail::kRefineSpirvTexture3D, detail::kRefineSpirvTexture3DWords};
    case MapsKind::kBc4:
      return {detail::kRefineSpirvBc4, detail::kRefineSpirvBc4Words};
    default:
      return {detail::kRefineSpirvArray2D, detail::kRefineSpirvArray2DWords};
  }
}

}  // namespace

struct GpuRefinement::State {
  VkDevice device = VK_NULL_HANDLE;
  gl::RefineBlock block;
  uint32_t mapCount = 0, mapResolution = 0;
  uint64_t bytes = 0;
  detail::Buffer unsure, vertices, nodes, triangles, blockBuffer;
};

GpuRefinement::GpuRefinement() = default;
GpuRefinement::GpuRefinement(GpuRefinement&&) noexcept = default;
GpuRefinement& GpuRefinement::operator=(GpuRefinement&&) noexcept = default;
GpuRefinement::~GpuRefinement() = default;
const gl::RefineBlock& GpuRefinement::block() const noexcept {
  return s_->block;
}
uint32_t GpuRefinement::mapCount() const noexcept {
  return s_->mapCount;
}
uint64_t GpuRefinement::bytes() const noexcept {
  return s_->bytes;
}

void GpuRefinement::write(VkDescriptorSet set) const noexcept {
  const State& s = *s_;
  detail::writeBuffer(s.device, set, kUnsureBinding, s.unsure.buffer);
  detail::writeBuffer(s.device, set, kVerticesBinding, s.vertices.buffer);
  detail::writeBuffer(s.device, set, kBvhBinding, s.nodes.buffer);
  detail::writeBuffer(s.device, set, kTrianglesBinding, s.triangles.buffer);
  detail::writeBuffer(s.device, set, kRefineBlockBinding, s.blockBuffer.buffer, VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER);
}

Result<GpuRefinement> loadRefinement(const Context& ctx, const FieldDesc& field, const RefinementView& refinement) {
  auto buffers = gl::makeRefinementBuffers(field, refinement);
  if (!buffers) return buffers.error();
  GpuRefinement out;
  out.s_ = std::make_unique<GpuRefinement::State>();
  GpuRefinement::State& s = *out.s_;
  s.device = ctx.device();
  s.block = buffers->block;
  s.mapCount = field.mapCount;
  s.mapResolution = field.mapResolution;
  // (Vulkan has no empty buffer: an empty vector gets one zero word, which the shader never reads
  // with triangleCount 0.)
  auto upload = [&](const void* data, size_t bytes, VkBufferUsageFlags usage, detail::Buffer* to) -> Status {
    static const uint32_t kZero = 0;
    auto b =
        bytes ? detail::makeFilledBuffer(ctx, data, bytes, usage) : detail::makeFilledBuffer(ctx, &kZero, 4, usage);
    if (!b) return b.error();
    s.bytes += b->size;
    *to = std::move(*b);
    return {};
  };
  const gl::RefinementBuffers& b = *buffers;
  constexpr VkBufferUsageFlags kSsbo = VK_BUFFER_USAGE_STORAGE_BUFFER_BIT;
  for (Status st : {upload(b.unsure.data(), b.unsure.size() * 4, kSsbo, &s.unsure),
                    upload(b.vertices.data(), b.vertices.size() * 4, kSsbo, &s.vertices),
                    upload(b.nodes.data(), b.nodes.size() * 4, kSsbo, &s.nodes),
                    upload(b.triangles.data(), b.triangles.size() * 4, kSsbo, &s.triangles),
                    upload(&b.block, sizeof b.block, VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT, &s.blockBuffer)})
    if (!st) return st.error();
  return out;
}

Result<GpuRefinement> loadRefinement(const Context& ctx, const File& file) {
  return loadRefinement(ctx, file.field(), file.refinement());
}

struct RefinedPipeline::State {
  MapsKind kind = MapsKind::kArray2D;
  ShaderLanguage language = ShaderLanguage::kGlsl;
  detail::Kernel kernel;
};

RefinedPipeline::RefinedPipeline() = default;
RefinedPipeline::RefinedPipeline(RefinedPipeline&&) noexcept = default;
RefinedPipeline& RefinedPipeline::operator=(RefinedPipeline&&) noexcept = default;
RefinedPipeline::~RefinedPipeline() = default;
MapsKind RefinedPipeline::kind() const noexcept {
  return s_->kind;
}
ShaderLanguage RefinedPipeline::language() const noexcept {
  return s_->language;
}

Result<RefinedPipeline> RefinedPipeline::create(const Context& ctx, MapsKind kind, const PipelineOptions& options) {
  if (!QueryPipeline::available(options.language))
    return makeError(Code::kUnsupported,
                     "vff_vk: this build has no HLSL kernels (spirv-cross was not found when it was configured)");
  RefinedPipeline p;
  p.s_ = std::make_unique<State>();
  State& s = *p.s_;
  s.kind = kind;
  s.language = options.language;
  const auto [code, words] = spirv(kind, options.language);
  if (Status st = detail::makeKernel(ctx, kBindings, code, words, &s.kernel); !st) return st.error();
  return p;
}

Result<std::vector<RefinedAnswer>> RefinedPipeline::run(const Context& ctx, const GpuField& field,
                                                        const GpuRefinement& refinement, std::span<const QueryRay> rays,
                                                        const RunOptions& options, double* seconds) const {
  const State& s = *s_;
  if (field.kind() != s.kind)
    return makeError(Code::kInvalidArgument, "the field needs another shader variant than this RefinedPipeline's");
  if (refinement.s_->mapCount != field.block().mapCount || refinement.s_->mapResolution != field.block().mapResolution)
    return makeError(Code::kInvalidArgument, "the refinement covers " + std::to_string(refinement.s_->mapCount) +
                                                 " maps of " + std::to_string(refinement.s_->mapResolution) +
                                                 "^2 texels, the field has " + std::to_string(field.block().mapCount) +
                                                 " of " + std::to_string(field.block().mapResolution) + "^2");
  if (Status st = detail::checkBatch(ctx, rays.size(), sizeof(RefinedAnswer)); !st) return st.error();
  std::vector<RefinedAnswer> out(rays.size());
  if (rays.empty()) return out;
  auto in = detail::makeFilledBuffer(ctx, rays.data(), rays.size_bytes(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!in) return in.error();
  auto answers = detail::makeHostBuffer(ctx, out.size() * sizeof(RefinedAnswer), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!answers) return answers.error();
  detail::DescriptorPool pool;
  auto set = detail::allocateSet(s.kernel, pool);
  if (!set) return set.error();
  field.write(*set);
  refinement.write(*set);
  detail::writeBuffer(ctx.device(), *set, kRaysBinding, in->buffer);
  detail::writeBuffer(ctx.device(), *set, kAnswersBinding, answers->buffer);
  const auto start = std::chrono::steady_clock::now();
  Status st = detail::dispatchRays(ctx, s.kernel, *set, 0, rays.size(), options.repeat);
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!st) return st.error();
  std::memcpy(out.data(), answers->mapped, out.size() * sizeof(RefinedAnswer));
  return out;
}

}  // namespace vff::vk
