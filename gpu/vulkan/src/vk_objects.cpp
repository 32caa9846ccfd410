// Buffers and images with their memory (vk_objects.h).
#include "vk_objects.h"

namespace vff::vk::detail {

void Buffer::reset() noexcept {
  if (!device) return;
  if (mapped) vkUnmapMemory(device, memory);
  if (buffer) vkDestroyBuffer(device, buffer, nullptr);
  if (memory) vkFreeMemory(device, memory, nullptr);
  device = VK_NULL_HANDLE;
  buffer = VK_NULL_HANDLE;
  memory = VK_NULL_HANDLE;
  size = 0;
  mapped = nullptr;
}

void Image::reset() noexcept {
  if (!device) return;
  if (view) vkDestroyImageView(device, view, nullptr);
  if (image) vkDestroyImage(device, image, nullptr);
  if (memory) vkFreeMemory(device, memory, nullptr);
  device = VK_NULL_HANDLE;
  image = VK_NULL_HANDLE;
  view = VK_NULL_HANDLE;
  memory = VK_NULL_HANDLE;
}

namespace {

Result<VkDeviceMemory> allocate(const Context& ctx, const VkMemoryRequirements& req, VkMemoryPropertyFlags flags) {
  const uint32_t type = ctx.memoryType(req.memoryTypeBits, flags);
  if (type == UINT32_MAX) return makeError(Code::kUnsupported, "no Vulkan memory type with the properties needed");
  auto ai = detail::vkStruct<VkMemoryAllocateInfo>(VK_STRUCTURE_TYPE_MEMORY_ALLOCATE_INFO);
  ai.allocationSize = req.size;
  ai.memoryTypeIndex = type;
  VkDeviceMemory mem = VK_NULL_HANDLE;
  if (VkResult r = vkAllocateMemory(ctx.device(), &ai, nullptr, &mem); r != VK_SUCCESS)
    return vkError(r, "vkAllocateMemory");
  return mem;
}

}  // namespace

Result<Buffer> makeHostBuffer(const Context& ctx, VkDeviceSize size, VkBufferUsageFlags usage) {
  Buffer b;
  b.device = ctx.device();
  b.size = size;
  auto ci = detail::vkStruct<VkBufferCreateInfo>(VK_STRUCTURE_TYPE_BUFFER_CREATE_INFO);
  ci.size = size ? size : 4;  // a zero-sized buffer is not allowed; an empty one still binds
  ci.usage = usage;
  ci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  if (VkResult r = vkCreateBuffer(b.device, &ci, nullptr, &b.buffer); r != VK_SUCCESS) {
    b.buffer = VK_NULL_HANDLE;
    return vkError(r, "vkCreateBuffer");
  }
  VkMemoryRequirements req;
  vkGetBufferMemoryRequirements(b.device, b.buffer, &req);
  auto mem = allocate(ctx, req, VK_MEMORY_PROPERTY_HOST_VISIBLE_BIT | VK_MEMORY_PROPERTY_HOST_COHERENT_BIT);
  if (!mem) return mem.error();
  b.memory = *mem;
  if (VkResult r = vkBindBufferMemory(b.device, b.buffer, b.memory, 0); r != VK_SUCCESS)
    return vkError(r, "vkBindBufferMemory");
  if (VkResult r = vkMapMemory(b.device, b.memory, 0, VK_WHOLE_SIZE, 0, &b.mapped); r != VK_SUCCESS) {
    b.mapped = nullptr;
    return vkError(r, "vkMapMemory");
  }
  return b;
}

Result<Image> makeImage(const Context& ctx, const ImageDesc& d) {
  Image im;
  im.device = ctx.device();
  auto ci = detail::vkStruct<VkImageCreateInfo>(VK_STRUCTURE_TYPE_IMAGE_CREATE_INFO);
  ci.imageType = d.is3D ? VK_IMAGE_TYPE_3D : VK_IMAGE_TYPE_2D;
  ci.format = d.format;
  ci.extent = {d.width, d.height, d.is3D ? d.slices : 1u};
  ci.mipLevels = 1;
  ci.arrayLayers = d.is3D ? 1u : d.slices;
  ci.samples = VK_SAMPLE_COUNT_1_BIT;
  ci.tiling = VK_IMAGE_TILING_OPTIMAL;
  ci.usage = VK_IMAGE_USAGE_SAMPLED_BIT | VK_IMAGE_USAGE_TRANSFER_DST_BIT;
  ci.sharingMode = VK_SHARING_MODE_EXCLUSIVE;
  ci.initialLayout = VK_IMAGE_LAYOUT_UNDEFINED;
  if (VkResult r = vkCreateImage(im.device, &ci, nullptr, &im.image); r != VK_SUCCESS) {
    im.image = VK_NULL_HANDLE;
    return vkError(r, "vkCreateImage");
  }
  VkMemoryRequirements req;
  vkGetImageMemoryRequirements(im.device, im.image, &req);
  auto mem = allocate(ctx, req, VK_MEMORY_PROPERTY_DEVICE_LOCAL_BIT);
  if (!mem) mem = allocate(ctx, req, 0);  // (a device without device-local memory for it)
  if (!mem) return mem.error();
  im.memory = *mem;
  if (VkResult r = vkBindImageMemory(im.device, im.image, im.memory, 0); r != VK_SUCCESS)
    return vkError(r, "vkBindImageMemory");
  auto vi = detail::vkStruct<VkImageViewCreateInfo>(VK_STRUCTURE_TYPE_IMAGE_VIEW_CREATE_INFO);
  vi.image = im.image;
  vi.viewType = d.is3D ? VK_IMAGE_VIEW_TYPE_3D : VK_IMAGE_VIEW_TYPE_2D_ARRAY;
  vi.format = d.format;
  vi.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, ci.arrayLayers};
  if (VkResult r = vkCreateImageView(im.device, &vi, nullptr, &im.view); r != VK_SUCCESS) {
    im.view = VK_NULL_HANDLE;
    return vkError(r, "vkCreateImageView");
  }
  return im;
}

void transition(VkCommandBuffer cb, VkImage image, VkImageLayout from, VkImageLayout to) {
  auto b = detail::vkStruct<VkImageMemoryBarrier>(VK_STRUCTURE_TYPE_IMAGE_MEMORY_BARRIER);
  b.oldLayout = from;
  b.newLayout = to;
  b.srcQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.dstQueueFamilyIndex = VK_QUEUE_FAMILY_IGNORED;
  b.image = image;
  b.subresourceRange = {VK_IMAGE_ASPECT_COLOR_BIT, 0, 1, 0, VK_REMAINING_ARRAY_LAYERS};
  VkPipelineStageFlags src = VK_PIPELINE_STAGE_TOP_OF_PIPE_BIT, dst = VK_PIPELINE_STAGE_TRANSFER_BIT;
  if (from == VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL) {
    b.srcAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
    src = VK_PIPELINE_STAGE_TRANSFER_BIT;
  }
  if (to == VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL) b.dstAccessMask = VK_ACCESS_TRANSFER_WRITE_BIT;
  if (to == VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL) {
    b.dstAccessMask = VK_ACCESS_SHADER_READ_BIT;
    dst = VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT;
  }
  vkCmdPipelineBarrier(cb, src, dst, 0, 0, nullptr, 0, nullptr, 1, &b);
}

}  // namespace vff::vk::detail
