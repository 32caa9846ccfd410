// The refined query of vff/vk/refine.h: the refinement's upload (vff::gl::makeRefinementBuffers'
// words in five host-visible buffers) and the pipeline of the embedded SPIR-V of
// shaders/vff_vk_refine.comp (compute.h's kernel and dispatch, as the query's).
#include "vff/vk/refine.h"

#include <string>
#include <utility>

#include "compute.h"

namespace vff::vk {
namespace detail {
// Generated at build time (gpu/vulkan/CMakeLists.txt, embed_spirv.cmake, make_hlsl.cmake).
VFF_VK_DECLARE_VARIANTS(kRefineSpirv)
#if VFF_VK_HLSL
VFF_VK_DECLARE_VARIANTS(kRefineSpirvHlsl)
#endif

namespace {

constexpr VkDescriptorType kNone = VK_DESCRIPTOR_TYPE_MAX_ENUM, kStorage = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                           kUniform = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
                           kImage = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
// Set 0: the field's bindings 0 to 3, the rays, the answers, nothing at 6 to 9 (vff_query.glsl's
// scene and peer bindings), the refinement's 10 to 14.
constexpr VkDescriptorType kBindings[] = {kUniform, kImage, kStorage, kImage,   kStorage, kStorage, kNone,   kNone,
                                          kNone,    kNone,  kStorage, kStorage, kStorage, kStorage, kUniform};

Spirv spirv(MapsKind kind, ShaderLanguage language) {
#if VFF_VK_HLSL
  if (language == ShaderLanguage::kHlsl) return VFF_VK_VARIANTS(kRefineSpirvHlsl)[kind];
#else
  (void)language;
#endif
  return VFF_VK_VARIANTS(kRefineSpirv)[kind];
}

}  // namespace
}  // namespace detail

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
  if (Status st = detail::requireLanguage(options.language); !st) return st.error();
  RefinedPipeline p;
  p.s_ = std::make_unique<State>();
  State& s = *p.s_;
  s.kind = kind;
  s.language = options.language;
  const detail::Spirv code = detail::spirv(kind, options.language);
  if (Status st = detail::makeKernel(ctx, detail::kBindings, code.code, code.words, &s.kernel); !st) return st.error();
  return p;
}

Result<std::vector<RefinedAnswer>> RefinedPipeline::run(const Context& ctx, const GpuField& field,
                                                        const GpuRefinement& refinement, std::span<const QueryRay> rays,
                                                        const RunOptions& options, double* seconds) const {
  const State& s = *s_;
  const GpuRefinement::State& r = *refinement.s_;
  if (field.kind() != s.kind)
    return makeError(Code::kInvalidArgument, "the field needs another shader variant than this RefinedPipeline's");
  if (r.mapCount != field.block().mapCount || r.mapResolution != field.block().mapResolution)
    return makeError(Code::kInvalidArgument, "the refinement covers " + std::to_string(r.mapCount) + " maps of " +
                                                 std::to_string(r.mapResolution) + "^2 texels, the field has " +
                                                 std::to_string(field.block().mapCount) + " of " +
                                                 std::to_string(field.block().mapResolution) + "^2");
  if (Status st = detail::checkBatch(ctx, rays.size(), sizeof(RefinedAnswer)); !st) return st.error();
  std::vector<RefinedAnswer> out(rays.size());
  if (rays.empty()) return out;
  const detail::Batch batch{.rays = rays.data(),
                            .rayCount = rays.size(),
                            .rayBytes = rays.size_bytes(),
                            .answers = out.data(),
                            .answerBytes = out.size() * sizeof(RefinedAnswer),
                            .repeat = options.repeat};
  auto write = [&](VkDescriptorSet set) {
    field.write(set);
    refinement.write(set);
  };
  if (Status st = detail::runBatch(ctx, s.kernel, batch, write, seconds); !st) return st.error();
  return out;
}

}  // namespace vff::vk
