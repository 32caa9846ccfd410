// The shared compute machinery of vff_vk's kernels (compute.h).
#include "compute.h"

#include <algorithm>
#include <chrono>
#include <cstring>
#include <vector>

namespace vff::vk::detail {

Kernel::~Kernel() {
  if (!device) return;
  if (pipeline) vkDestroyPipeline(device, pipeline, nullptr);
  if (module) vkDestroyShaderModule(device, module, nullptr);
  if (layout) vkDestroyPipelineLayout(device, layout, nullptr);
  if (setLayout) vkDestroyDescriptorSetLayout(device, setLayout, nullptr);
}

Status makeKernel(const Context& ctx, std::span<const VkDescriptorType> bindings, const uint32_t* code, size_t words,
                  Kernel* k) {
  k->device = ctx.device();
  k->bindings = bindings;
  std::vector<VkDescriptorSetLayoutBinding> b;
  for (uint32_t i = 0; i < bindings.size(); ++i)
    if (bindings[i] != VK_DESCRIPTOR_TYPE_MAX_ENUM)
      b.push_back({i, bindings[i], 1, VK_SHADER_STAGE_COMPUTE_BIT, nullptr});
  auto li = vkStruct<VkDescriptorSetLayoutCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_LAYOUT_CREATE_INFO);
  li.bindingCount = uint32_t(b.size());
  li.pBindings = b.data();
  if (VkResult r = vkCreateDescriptorSetLayout(k->device, &li, nullptr, &k->setLayout); r != VK_SUCCESS) {
    k->setLayout = VK_NULL_HANDLE;
    return vkError(r, "vkCreateDescriptorSetLayout");
  }
  VkPushConstantRange push{VK_SHADER_STAGE_COMPUTE_BIT, 0, kPushBytes};
  auto pi = vkStruct<VkPipelineLayoutCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_LAYOUT_CREATE_INFO);
  pi.setLayoutCount = 1;
  pi.pSetLayouts = &k->setLayout;
  pi.pushConstantRangeCount = 1;
  pi.pPushConstantRanges = &push;
  if (VkResult r = vkCreatePipelineLayout(k->device, &pi, nullptr, &k->layout); r != VK_SUCCESS) {
    k->layout = VK_NULL_HANDLE;
    return vkError(r, "vkCreatePipelineLayout");
  }
  auto mi = vkStruct<VkShaderModuleCreateInfo>(VK_STRUCTURE_TYPE_SHADER_MODULE_CREATE_INFO);
  mi.codeSize = words * 4;
  mi.pCode = code;
  if (VkResult r = vkCreateShaderModule(k->device, &mi, nullptr, &k->module); r != VK_SUCCESS) {
    k->module = VK_NULL_HANDLE;
    return vkError(r, "vkCreateShaderModule");
  }
  auto ci = vkStruct<VkComputePipelineCreateInfo>(VK_STRUCTURE_TYPE_COMPUTE_PIPELINE_CREATE_INFO);
  ci.stage = vkStruct<VkPipelineShaderStageCreateInfo>(VK_STRUCTURE_TYPE_PIPELINE_SHADER_STAGE_CREATE_INFO);
  ci.stage.stage = VK_SHADER_STAGE_COMPUTE_BIT;
  ci.stage.module = k->module;
  ci.stage.pName = "main";
  ci.layout = k->layout;
  if (VkResult r = vkCreateComputePipelines(k->device, VK_NULL_HANDLE, 1, &ci, nullptr, &k->pipeline);
      r != VK_SUCCESS) {
    k->pipeline = VK_NULL_HANDLE;
    return vkError(r, "vkCreateComputePipelines");
  }
  return {};
}

DescriptorPool::~DescriptorPool() {
  if (pool) vkDestroyDescriptorPool(device, pool, nullptr);
}

Result<VkDescriptorSet> allocateSet(const Kernel& k, DescriptorPool& pool) {
  // One pool size per descriptor type the layout uses.
  std::vector<VkDescriptorPoolSize> sizes;
  for (VkDescriptorType t : k.bindings) {
    if (t == VK_DESCRIPTOR_TYPE_MAX_ENUM) continue;
    auto it = std::find_if(sizes.begin(), sizes.end(), [&](const VkDescriptorPoolSize& s) { return s.type == t; });
    if (it == sizes.end())
      sizes.push_back({t, 1});
    else
      ++it->descriptorCount;
  }
  auto pi = vkStruct<VkDescriptorPoolCreateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_POOL_CREATE_INFO);
  pi.maxSets = 1;
  pi.poolSizeCount = uint32_t(sizes.size());
  pi.pPoolSizes = sizes.data();
  pool.device = k.device;
  if (VkResult r = vkCreateDescriptorPool(k.device, &pi, nullptr, &pool.pool); r != VK_SUCCESS) {
    pool.pool = VK_NULL_HANDLE;
    return vkError(r, "vkCreateDescriptorPool");
  }
  auto ai = vkStruct<VkDescriptorSetAllocateInfo>(VK_STRUCTURE_TYPE_DESCRIPTOR_SET_ALLOCATE_INFO);
  ai.descriptorPool = pool.pool;
  ai.descriptorSetCount = 1;
  ai.pSetLayouts = &k.setLayout;
  VkDescriptorSet set = VK_NULL_HANDLE;
  if (VkResult r = vkAllocateDescriptorSets(k.device, &ai, &set); r != VK_SUCCESS)
    return vkError(r, "vkAllocateDescriptorSets");
  return set;
}

void writeBuffer(VkDevice device, VkDescriptorSet set, uint32_t binding, VkBuffer buffer, VkDescriptorType type,
                 VkDeviceSize range) {
  VkDescriptorBufferInfo info{buffer, 0, range};
  auto w = vkStruct<VkWriteDescriptorSet>(VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET);
  w.dstSet = set;
  w.dstBinding = binding;
  w.descriptorCount = 1;
  w.descriptorType = type;
  w.pBufferInfo = &info;
  vkUpdateDescriptorSets(device, 1, &w, 0, nullptr);
}

void writeImage(VkDevice device, VkDescriptorSet set, uint32_t binding, VkSampler sampler, VkImageView view) {
  VkDescriptorImageInfo info{sampler, view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  auto w = vkStruct<VkWriteDescriptorSet>(VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET);
  w.dstSet = set;
  w.dstBinding = binding;
  w.descriptorCount = 1;
  w.descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  w.pImageInfo = &info;
  vkUpdateDescriptorSets(device, 1, &w, 0, nullptr);
}

Status checkBatch(const Context& ctx, size_t rays, size_t answerBytes) {
  const uint64_t range = ctx.properties().limits.maxStorageBufferRange;
  if (uint64_t(rays) * answerBytes > range || rays > UINT32_MAX)
    return makeError(Code::kUnsupported, "a batch of " + std::to_string(rays) +
                                             " rays exceeds the device's maxStorageBufferRange (" +
                                             std::to_string(range) + " bytes): run it in parts");
  return {};
}

Status dispatchRays(const Context& ctx, const Kernel& k, VkDescriptorSet set, uint32_t which, size_t rays,
                    uint32_t repeat) {
  // Dispatches of at most maxComputeWorkGroupCount[0] groups (65535 guaranteed), each told its
  // first ray.
  const uint64_t maxGroups = ctx.properties().limits.maxComputeWorkGroupCount[0];
  const uint64_t chunk = maxGroups * kGroupSize;
  return ctx.submitAndWait([&](VkCommandBuffer cb) {
    vkCmdBindPipeline(cb, VK_PIPELINE_BIND_POINT_COMPUTE, k.pipeline);
    vkCmdBindDescriptorSets(cb, VK_PIPELINE_BIND_POINT_COMPUTE, k.layout, 0, 1, &set, 0, nullptr);
    for (uint32_t i = 0; i < (repeat ? repeat : 1u); ++i) {
      if (i) {  // each repeat writes the same answers: order the writes
        auto mb = vkStruct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
        mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
        mb.dstAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
        vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, 0, 1, &mb,
                             0, nullptr, 0, nullptr);
      }
      for (uint64_t first = 0; first < rays; first += chunk) {
        // rayCount fits: the answers' buffer is within maxStorageBufferRange (checkBatch).
        const uint32_t push[3] = {which, uint32_t(first), uint32_t(rays)};
        vkCmdPushConstants(cb, k.layout, VK_SHADER_STAGE_COMPUTE_BIT, 0, sizeof(push), push);
        const uint64_t n = std::min<uint64_t>(rays - first, chunk);
        vkCmdDispatch(cb, uint32_t((n + kGroupSize - 1) / kGroupSize), 1, 1);
      }
    }
    // The answers become visible to the host's reads of the mapped memory.
    auto mb = vkStruct<VkMemoryBarrier>(VK_STRUCTURE_TYPE_MEMORY_BARRIER);
    mb.srcAccessMask = VK_ACCESS_SHADER_WRITE_BIT;
    mb.dstAccessMask = VK_ACCESS_HOST_READ_BIT;
    vkCmdPipelineBarrier(cb, VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT, VK_PIPELINE_STAGE_HOST_BIT, 0, 1, &mb, 0, nullptr, 0,
                         nullptr);
  });
}

Status requireLanguage(ShaderLanguage language) {
  if (QueryPipeline::available(language)) return {};
  return makeError(Code::kUnsupported,
                   "vff_vk: this build has no HLSL kernels (spirv-cross was not found when it was configured)");
}

Status runBatch(const Context& ctx, const Kernel& kernel, const Batch& b,
                const std::function<void(VkDescriptorSet)>& writeSet, double* seconds) {
  auto in = makeFilledBuffer(ctx, b.rays, b.rayBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!in) return in.error();
  auto answers = makeHostBuffer(ctx, b.answerBytes, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!answers) return answers.error();
  DescriptorPool pool;
  auto set = allocateSet(kernel, pool);
  if (!set) return set.error();
  writeSet(*set);
  writeBuffer(ctx.device(), *set, b.raysBinding, in->buffer);
  writeBuffer(ctx.device(), *set, b.answersBinding, answers->buffer);
  const auto start = std::chrono::steady_clock::now();
  Status st = dispatchRays(ctx, kernel, *set, b.which, b.rayCount, b.repeat);
  if (seconds) *seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!st) return st;
  std::memcpy(b.answers, answers->mapped, b.answerBytes);
  return {};
}

Result<Buffer> makeFilledBuffer(const Context& ctx, const void* data, size_t size, VkBufferUsageFlags usage) {
  auto b = makeHostBuffer(ctx, size, usage);
  if (!b) return b.error();
  if (size) std::memcpy(b->mapped, data, size);
  return b;
}

}  // namespace vff::vk::detail
