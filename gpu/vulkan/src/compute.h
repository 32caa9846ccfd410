// compute.h (private to vff_vk) - what every vff_vk compute kernel shares: a pipeline made from
// embedded SPIR-V with one descriptor set (its bindings' types given in binding order) and a
// 12-byte push constant (which queries, the first ray of a dispatch, the batch's ray count); a
// one-set descriptor pool; and the batched dispatch of 64-ray work groups. QueryPipeline
// (query.cpp), RefinedPipeline (refine.cpp) and ScenePipeline (scene_query.cpp) are built on it.
#pragma once

#include <vulkan/vulkan.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <span>
#include <string>

#include "vff/error.h"
#include "vff/vk/context.h"
#include "vff/vk/field.h"
#include "vff/vk/query.h"
#include "vk_objects.h"

// The embedded SPIR-V of one kernel source (gpu/vulkan/CMakeLists.txt, embed_spirv.cmake):
// NAME<Variant> and NAME<Variant>Words for the three MapsKind variants, declared (in namespace
// vff::vk::detail) and gathered as a Variants table.
// clang-format off
#define VFF_VK_DECLARE_VARIANTS(NAME)                                    \
  extern const uint32_t NAME##Array2D[], NAME##Texture3D[], NAME##Bc4[]; \
  extern const size_t NAME##Array2D##Words, NAME##Texture3D##Words, NAME##Bc4##Words;
#define VFF_VK_VARIANTS(NAME)                                                                       \
  ::vff::vk::detail::Variants{{{NAME##Array2D, NAME##Array2D##Words},                               \
                               {NAME##Texture3D, NAME##Texture3D##Words},                           \
                               {NAME##Bc4, NAME##Bc4##Words}}}
// clang-format on

namespace vff::vk::detail {

inline constexpr uint32_t kGroupSize = 64;  // local_size_x of every vff_vk kernel
inline constexpr uint32_t kPushBytes = 12;  // uint which, firstRay, rayCount

// A kernel's SPIR-V words, and one per MapsKind (indexed by its value).
struct Spirv {
  const uint32_t* code = nullptr;
  size_t words = 0;
};
struct Variants {
  Spirv byKind[3];
  Spirv operator[](MapsKind kind) const noexcept { return byKind[uint32_t(kind)]; }
};

// kUnsupported when this build has no kernels of `language` (QueryPipeline::available).
Status requireLanguage(ShaderLanguage language);

// One kernel's pipeline and layouts, destroyed with their owner.
struct Kernel {
  VkDevice device = VK_NULL_HANDLE;
  VkDescriptorSetLayout setLayout = VK_NULL_HANDLE;
  VkPipelineLayout layout = VK_NULL_HANDLE;
  VkShaderModule module = VK_NULL_HANDLE;
  VkPipeline pipeline = VK_NULL_HANDLE;
  std::span<const VkDescriptorType> bindings;  // bindings[b]: binding b's type (static storage)

  Kernel() = default;
  Kernel(const Kernel&) = delete;
  Kernel& operator=(const Kernel&) = delete;
  ~Kernel();
};

// Set 0 with bindings[b] at binding b (VK_DESCRIPTOR_TYPE_MAX_ENUM: no binding b), the push
// constant, and the compute pipeline of `words` SPIR-V words (entry point "main"). `bindings` must
// outlive the kernel.
Status makeKernel(const Context& ctx, std::span<const VkDescriptorType> bindings, const uint32_t* code, size_t words,
                  Kernel* kernel);

// A descriptor pool holding one set of a kernel's layout, destroyed with its owner.
struct DescriptorPool {
  VkDevice device = VK_NULL_HANDLE;
  VkDescriptorPool pool = VK_NULL_HANDLE;
  DescriptorPool() = default;
  DescriptorPool(const DescriptorPool&) = delete;
  DescriptorPool& operator=(const DescriptorPool&) = delete;
  ~DescriptorPool();
};
Result<VkDescriptorSet> allocateSet(const Kernel& kernel, DescriptorPool& pool);

// Writes a whole buffer as binding `binding` (STORAGE_BUFFER unless told otherwise).
void writeBuffer(VkDevice device, VkDescriptorSet set, uint32_t binding, VkBuffer buffer,
                 VkDescriptorType type = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, VkDeviceSize range = VK_WHOLE_SIZE);
// Writes a combined image sampler (shader read-only layout) as binding `binding`.
void writeImage(VkDevice device, VkDescriptorSet set, uint32_t binding, VkSampler sampler, VkImageView view);

// A batch's answers against the device's maxStorageBufferRange (kUnsupported: run it in parts).
Status checkBatch(const Context& ctx, size_t rays, size_t answerBytes);

// Records and runs `repeat` rounds of dispatches over `rays` rays with `set` bound, each dispatch
// of at most maxComputeWorkGroupCount[0] groups and told its first ray, then makes the shader's
// writes visible to the host. Waits for the device.
Status dispatchRays(const Context& ctx, const Kernel& kernel, VkDescriptorSet set, uint32_t which, size_t rays,
                    uint32_t repeat);

// One batch through a kernel, as QueryPipeline::run and its siblings do it: the rays (rayBytes in
// all) copied into a host buffer at binding raysBinding, a host buffer of answerBytes at
// answersBinding, the set's other bindings written by writeSet; then dispatchRays (its recording,
// submission and wait timed into *seconds when given) and the answers copied to `answers`.
struct Batch {
  const void* rays = nullptr;
  size_t rayCount = 0, rayBytes = 0;
  void* answers = nullptr;
  size_t answerBytes = 0;
  uint32_t raysBinding = 4, answersBinding = 5;
  uint32_t which = 0, repeat = 1;
};
Status runBatch(const Context& ctx, const Kernel& kernel, const Batch& batch,
                const std::function<void(VkDescriptorSet)>& writeSet, double* seconds);

// A host buffer holding `size` bytes copied from `data`.
Result<Buffer> makeFilledBuffer(const Context& ctx, const void* data, size_t size, VkBufferUsageFlags usage);

}  // namespace vff::vk::detail
