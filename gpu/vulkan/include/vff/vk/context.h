// vff/vk/context.h - a minimal headless Vulkan context for gpu/glsl/vff_query.glsl: an instance, one
// physical device with a compute queue, a logical device, a command pool, and optionally the Khronos
// validation layer with a debug messenger that counts what it reports.
//
//   vff::vk::ContextOptions o;
//   o.validation = true;                           // or run with VFF_VK_VALIDATION=1
//   vff::Result<vff::vk::Context> ctx = vff::vk::Context::create(o);
//   if (!ctx) { fprintf(stderr, "%s\n", ctx.error().toString().c_str()); return 1; }
//   printf("%s\n", ctx->deviceName().c_str());     // "llvmpipe (...)" on Mesa's lavapipe
//   ...                                            // vff/vk/field.h, vff/vk/query.h
//   if (ctx->validationErrors() || ctx->validationWarnings()) { ... ctx->validationLog() ... }
//
// Device choice: the first device of the preferred type that has a compute queue; with
// `preferCpu` a CPU implementation (lavapipe) is taken first, which makes answers reproducible
// across machines with different GPUs; otherwise a discrete GPU, then an integrated one, then any.
//
// Validation: VK_LAYER_KHRONOS_validation is enabled explicitly (not through VK_INSTANCE_LAYERS)
// when `options.validation` is set or the environment has VFF_VK_VALIDATION=1, and the layer and
// VK_EXT_debug_utils are installed. Where they are not, the context is still created without them
// and validationEnabled() is false (validationNote() says why), so a caller that needs the layer
// (the tests) can decide to skip. Reason for enabling it explicitly: lavapipe does not check
// descriptor types itself, so without the layer a wrong descriptor can pass unnoticed.
//
// Errors (values, never exceptions): kUnsupported when no Vulkan loader, instance or device with a
// compute queue is available (the message names the failing call and its VkResult); kOutOfMemory
// for VK_ERROR_OUT_OF_*_MEMORY.
//
// Threading: a Context and everything made from it are used from one thread at a time. Move-only;
// objects made from a Context (GpuField, QueryPipeline, GpuScene, ScenePipeline) must be destroyed
// before it.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "vff/error.h"

namespace vff::vk {

struct ContextOptions {
  bool validation = false;  // enable VK_LAYER_KHRONOS_validation (also: VFF_VK_VALIDATION=1)
  bool preferCpu = false;   // take a CPU device (lavapipe) before any GPU
};

// A VkResult as a vff::Error naming the call ("vkCreateDevice failed: VK_ERROR_...").
Error vkError(VkResult r, const char* what);

class Context {
 public:
  Context();
  Context(Context&&) noexcept;
  Context& operator=(Context&&) noexcept;
  ~Context();

  static Result<Context> create(const ContextOptions& options = {});

  VkInstance instance() const noexcept;
  VkPhysicalDevice physicalDevice() const noexcept;
  VkDevice device() const noexcept;
  VkQueue queue() const noexcept;
  uint32_t queueFamily() const noexcept;
  const VkPhysicalDeviceProperties& properties() const noexcept;
  std::string deviceName() const;

  // Index of a memory type allowed by `typeBits` with all of `flags`, or UINT32_MAX.
  uint32_t memoryType(uint32_t typeBits, VkMemoryPropertyFlags flags) const noexcept;

  // Records `record` into a fresh primary command buffer, submits it to the queue and waits for it
  // to finish. Errors: the failing Vulkan call.
  Status submitAndWait(const std::function<void(VkCommandBuffer)>& record) const;

  // The debug messenger's counts since create() (0 when validation is not enabled).
  bool validationEnabled() const noexcept;
  const std::string& validationNote() const noexcept;  // why it is off, when requested but off
  uint32_t validationErrors() const noexcept;
  uint32_t validationWarnings() const noexcept;
  const std::string& validationLog() const noexcept;  // the messages counted, one a line

  struct State;  // (the implementation's; public so that the messenger callback can reach it)

 private:
  std::unique_ptr<State> s_;  // on the heap: the messenger keeps a pointer to its counters
};

}  // namespace vff::vk
