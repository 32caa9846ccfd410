// The compute pipeline of vff/vk/query.h: descriptor set layout (the field's bindings 0 to 3, rays
// 4, answers 5), the embedded SPIR-V of shaders/vff_vk_query.comp, and one run over a batch of rays.
#include "vff/vk/query.h"

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstring>
#include <string>
#include <utility>

#include "vk_objects.h"

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
constexpr uint32_t kGroupSize = 64;  // local_size_x of the shader

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
  VkDevice device = VK_NULL_HANDLE;
  MapsKind kind = MapsKind::kArray2D;
  ShaderLanguage language = ShaderLanguage::kGlsl;
  VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkShaderModule module = VK_NULL_HANDLE;
  VkPipeline pipeline = VK_NULL_HANDLE;

  ~State() {
    if (!device) return;
    if (pipeline) vkDestroyPipeline(device, pipeline, nullptr);
    if (module) vkDestroyShaderModule(device, module, nullptr);
    if (layout) vkDestroyPipelineLayout(device, layout, nullptr);
    if (setLayout) vkDestroyDescriptorSetLayout(device, setLayout, nullptr);
  }
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

namespace {

Status makeLayouts(QueryPipeline::State& s) {
  const VkDescriptorType types[6] = {VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                                     VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                                     VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VK_DESCRIPTOR_TYPE_STORAGE_BUFFER};
  VkDescriptorSetLayoutBinding b[6];
  for (uint32_t i = 0; i < 6; ++i) b[i] = {i, types[i], 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr};
  auto li = detail::vkStruct<VkDescriptorSetLayoutCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO);
  li.bindingCount = 6;
  li.pBindings = b;
  if (VkResult r = vkCreateDescriptorSetLayout(s.device, &li, nullptr, &s.setLayout); r != VK_SUCCESS) {
    s.setLayout = VK_NULL_HANDLE;
    return vkError(r, "vkCreateDescriptorSetLayout");
  }
  VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, 12};  // which, firstRay, rayCount
  auto pi = detail::vkStruct<VkPipelineLayoutCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO);
  pi.setLayoutCount = 1;
  pi.pSetLayouts = &s.setLayout;
  pi.pushConstantRangeCount = 1;
  pi.pPushConstantRanges = &push;
  if (VkResult r = vkCreatePipelineLayout(s.device, &pi, nullptr, &s.layout); r != VK_SUCCESS) {
    s.layout = VK_NULL_HANDLE;
    return vkError(r, "vkCreatePipelineLayout");
  }
  return {};
}

}  // namespace

Result<QueryPipeline> QueryPipeline::create(const Context& ctx, MapsKind kind, const PipelineOptions& options) {
  if (!available(options.language))
    return makeError(Code::kUnsupported,
                     "vff_vk: this build has no HLSL kernels (spirv-cross was not found when it was configured)");
  QueryPipeline p;
  p.s_ = std::make_unique<State>();
  State& s = *p.s_;
  s.device = ctx.device();
  s.kind = kind;
  s.language = options.language;
  if (Status st = makeLayouts(s); !st) return st.error();
  const auto [code, words] = spirv(kind, options.language);
  auto mi = detail::vkStruct<VkShaderModuleCreateInfo>(VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO);
  mi.codeSize = words * 4;
  mi.pCode = code;
  if (VkResult r = vkCreateShaderModule(s.device, &mi, nullptr, &s.module); r != VK_SUCCESS) {
    s.module = VK_NULL_HANDLE;
    return vkError(r, "vkCreateShaderModule");
  }
  auto ci = detail::vkStruct<VkComputePipelineCreateInfo>(VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO);
  ci.stage = detail::vkStruct<VkPipelineShaderStageCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO);
  ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  ci.stage.module = s.module;
  ci.stage.pName = "main";
  ci.layout = s.layout;
  if (VkResult r = vkCreateComputePipelines(s.device, VK_NULL_HANDLE, 1, &ci, nullptr, &s.pipeline); r != VK_SUCCESS) {
    s.pipeline = VK_NULL_HANDLE;
    return vkError(r, "vkCreateComputePipelines");
  }
  return p;
}

namespace {

// A descriptor pool with room for one set of the pipeline's layout, destroyed with its owner.
struct Pool {
  VkDevice device = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  ~Pool() {
    if (pool) vkDestroyDescriptorPool(device, pool, nullptr);
  }
};

Result<VkDescriptorSet> allocateSet(const QueryPipeline::State& s, Pool& pool) {
  const VkDescriptorPoolSize sizes[3] = {{VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER, 1},
                                         {VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, 2},
                                         {VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 3}};
  auto pi = detail::vkStruct<VkDescriptorPoolCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO);
  pi.maxSets = 1;
  pi.poolSizeCount = 3;
  pi.pPoolSizes = sizes;
  pool.device = s.device;
  if (VkResult r = vkCreateDescriptorPool(s.device, &pi, nullptr, &pool.pool); r != VK_SUCCESS) {
    pool.pool = VK_NULL_HANDLE;
    return vkError(r, "vkCreateDescriptorPool");
  }
  auto ai = detail::vkStruct<VkDescriptorSetAllocateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO);
  ai.descriptorPool = pool.pool;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &s.setLayout;
  VkDescriptorSet set = VK_NULL_HANDLE;
  if (VkResult r = vkAllocateDescriptorSets(s.device, &ai, &set); r != VK_SUCCESS)
    return vkError(r, "vkAllocateDescriptorSets");
  return set;
}

void writeBuffer(VkDevice device, VkDescriptorSet set, uint32_t binding, VkBuffer buffer) {
  VkDescriptorBufferInfo info{buffer, 0, VK_WHOLE_SIZE};
  auto w = detail::vkStruct<VkWriteDescriptorSet>(VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET);
  w.dstSet = set;
  w.dstBinding = binding;
  w.descriptorCount = 1;
  w.descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  w.pBufferInfo = &info;
  vkUpdateDescriptorSets(device, 1, &w, 0, nullptr);
}

}  // namespace

Result<std::vector<QueryAnswer>> QueryPipeline::run(const Context& ctx, const GpuField& field,
                                                    std::span<const QueryRay> rays, const RunOptions& options,
                                                    double* seconds) const {
  const State& s = *s_;
  if (field.kind() != s.kind)
    return makeError(Code::kInvalidArgument, "the field needs another shader variant than this QueryPipeline's");
  const uint64_t range = ctx.properties().limits.maxStorageBufferRange;
  if (rays.size() * sizeof(QueryAnswer) > range || rays.size() > UINT32_MAX)
    return makeError(Code::kUnsupported, "a batch of " + std::to_string(rays.size()) +
                                             " rays exceeds the device's maxStorageBufferRange (" +
                                             std::to_string(range) + " bytes): run it in parts");
  std::vector<QueryAnswer> out(rays.size());
  if (rays.empty()) return out;
  auto in = detail::makeHostBuffer(ctx, rays.size_bytes(), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!in) return in.error();
  std::memcpy(in->mapped, rays.data(), rays.size_bytes());
  auto answers = detail::makeHostBuffer(ctx, out.size() * sizeof(QueryAnswer), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!answers) return answers.error();
  Pool pool;
  auto set = allocateSet(s, pool);
  if (!set) return set.error();
  field.write(*set);
  writeBuffer(s.device, *set, kRaysBinding, in->buffer);
  writeBuffer(s.device, *set, kAnswersBinding, answers->buffer);
  const uint32_t which = (options.nearest ? 1u : 0u) | (options.interpolated ? 2u : 0u);
  // Dispatches of at most maxComputeWorkGroupCount[0] groups (65535 guaranteed), each told its
  // first ray.
  const uint64_t maxGroups = ctx.properties().limits.maxComputeWorkGroupCount[0];
  const uint64_t chunk = maxGroups * kGroupSize;
  const auto start = std::chrono::steady_clock::now();
  Status st = ctx.submitAndWait([&](VkCommandBuffer cb) {
    vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE, s.pipeline);
    vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_COMPUTE, s.layout, 0, 1, &*set, 0, nullptr);
    for (uint32_t i = 0; i < (options.repeat ? options.repeat : 1u); ++i) {
      if (i) {  // each repeat writes the same answers: order the writes
        auto mb = detail::vkStruct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
        mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
        mb.dstAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
        vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &mb,
                             0, nullptr, 0, nullptr);
      }
      for (uint64_t first = 0; first < rays.size(); first += chunk) {
        // rayCount fits: the answers' buffer is within maxStorageBufferRange (checked above).
        const uint32_t push[3] = {which, uint32_t(first), uint32_t(rays.size())};
        vkCmdPushConstants(cb, s.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), push);
        const uint64_t n = std::min<uint64_t>(rays.size() - first, chunk);
        vkCmdDispatch(cb, uint32_t((n + kGroupSize - 1) / kGroupSize), 1, 1);
      }
    }
    // The answers become visible to the host's reads of the mapped memory.
    auto mb = detail::vkStruct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
    mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, nullptr, 0,
                         nullptr);
  });
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!st) return st.error();
  std::memcpy(out.data(), answers->mapped, out.size() * sizeof(QueryAnswer));
  return out;
}

}  // namespace vff::vk
