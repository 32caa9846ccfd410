// vk_objects.h (private to vff_vk) - owners of the Vulkan objects a GpuField or a query run holds:
// a buffer or an image with its own memory allocation, destroyed with its owner. One allocation per
// object keeps ownership obvious; a field has a handful of objects, far below any allocation limit.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <utility>

#include "vff/error.h"
#include "vff/vk/context.h"

namespace vff::vk::detail {

// A zeroed Vulkan struct with its sType (so that no member is left out, which -Wextra flags for a
// braced initializer that names only the first).
template <class T>
T vkStruct(VkStructureType type) noexcept {
  T v{};
  v.sType = type;
  return v;
}

struct Buffer {
  VkDevice device = VK_NULL_HANDLE;
  VkBuffer buffer = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;
  VkDeviceSize size = 0;
  void* mapped = nullptr;  // host-visible buffers stay mapped for their lifetime

  Buffer() = default;
  Buffer(Buffer&& o) noexcept { *this = std::move(o); }
  Buffer& operator=(Buffer&& o) noexcept {
    if (this != &o) {
      reset();
      device = std::exchange(o.device, VK_NULL_HANDLE);
      buffer = std::exchange(o.buffer, VK_NULL_HANDLE);
      memory = std::exchange(o.memory, VK_NULL_HANDLE);
      size = std::exchange(o.size, 0);
      mapped = std::exchange(o.mapped, nullptr);
    }
    return *this;
  }
  ~Buffer() { reset(); }
  void reset() noexcept;
};

struct Image {
  VkDevice device = VK_NULL_HANDLE;
  VkImage image = VK_NULL_HANDLE;
  VkImageView view = VK_NULL_HANDLE;
  VkDeviceMemory memory = VK_NULL_HANDLE;

  Image() = default;
  Image(Image&& o) noexcept { *this = std::move(o); }
  Image& operator=(Image&& o) noexcept {
    if (this != &o) {
      reset();
      device = std::exchange(o.device, VK_NULL_HANDLE);
      image = std::exchange(o.image, VK_NULL_HANDLE);
      view = std::exchange(o.view, VK_NULL_HANDLE);
      memory = std::exchange(o.memory, VK_NULL_HANDLE);
    }
    return *this;
  }
  ~Image() { reset(); }
  void reset() noexcept;
};

// A buffer of `size` bytes in host-visible, coherent memory, mapped (the field's buffers are small
// and written once; the rays' and answers' buffers are written and read by the host).
Result<Buffer> makeHostBuffer(const Context& ctx, VkDeviceSize size, VkBufferUsageFlags usage);

// What makeImage creates: a 2D array (layers = slices) or a 3D image (depth = slices), one level,
// optimal tiling, usage sampled | transfer destination, and a view of the same dimensionality.
struct ImageDesc {
  VkFormat format = VK_FORMAT_UNDEFINED;
  uint32_t width = 1, height = 1, slices = 1;
  bool is3D = false;
};
Result<Image> makeImage(const Context& ctx, const ImageDesc& desc);

// Records the layout change of a whole image (one level, all layers) with the access masks that
// the two layouts imply (transfer write before, shader read after).
void transition(VkCommandBuffer cb, VkImage image, VkImageLayout from, VkImageLayout to);

}  // namespace vff::vk::detail
