// The Vulkan loader (vff/vk/field.h): a field's slices into images, its FieldBlock and positions
// into buffers, with the data vff_gl_data computes for the GL loader.
#include "vff/vk/field.h"

#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "compute.h"
#include "upload.h"

namespace vff::vk {

using detail::Buffer;
using detail::Image;
using namespace detail;  // upload.h, compute.h

struct GpuField::State {
  VkDevice device = VK_NULL_HANDLE;
  gl::FieldBlock block;
  MapsKind kind = MapsKind::kArray2D;
  bool normals = false;
  uint64_t textureBytes = 0;
  Image maps, normalImage;
  Buffer fieldBuffer, positions;
  VkSampler sampler = VK_NULL_HANDLE;

  ~State() {
    if (sampler) vkDestroySampler(device, sampler, nullptr);
  }
};

GpuField::GpuField() = default;
GpuField::GpuField(GpuField&&) noexcept = default;
GpuField& GpuField::operator=(GpuField&&) noexcept = default;
GpuField::~GpuField() = default;

const gl::FieldBlock& GpuField::block() const noexcept {
  return s_->block;
}
MapsKind GpuField::kind() const noexcept {
  return s_->kind;
}
bool GpuField::hasNormals() const noexcept {
  return s_->normals;
}
uint64_t GpuField::textureBytes() const noexcept {
  return s_->textureBytes;
}

MapsKind mapsKind(const FieldDesc& field, const LayoutDesc& layout) noexcept {
  if (field.distanceEncoding == DistanceEncoding::kBc4Diameter) return MapsKind::kBc4;
  return layout.target == LayoutTarget::kTexture3D ? MapsKind::kTexture3D : MapsKind::kArray2D;
}

void GpuField::write(VkDescriptorSet set) const noexcept {
  VkDescriptorBufferInfo fieldInfo{s_->fieldBuffer.buffer, 0, sizeof(gl::FieldBlock)};
  VkDescriptorBufferInfo posInfo{s_->positions.buffer, 0, VK_WHOLE_SIZE};
  VkDescriptorImageInfo mapsInfo{s_->sampler, s_->maps.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  VkDescriptorImageInfo normalsInfo{s_->sampler, s_->normalImage.view, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL};
  VkWriteDescriptorSet w[4];
  for (auto& x : w) {
    x = detail::vkStruct<VkWriteDescriptorSet>(VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET);
    x.dstSet = set;
    x.descriptorCount = 1;
  }
  w[0].dstBinding = kFieldBinding;
  w[0].descriptorType = VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER;
  w[0].pBufferInfo = &fieldInfo;
  w[1].dstBinding = kMapsBinding;
  w[1].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  w[1].pImageInfo = &mapsInfo;
  w[2].dstBinding = kPositionsBinding;
  w[2].descriptorType = VK_DESCRIPTOR_TYPE_STORAGE_BUFFER;
  w[2].pBufferInfo = &posInfo;
  w[3].dstBinding = kNormalsBinding;
  w[3].descriptorType = VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER;
  w[3].pImageInfo = &normalsInfo;
  vkUpdateDescriptorSets(s_->device, 4, w, 0, nullptr);
}

namespace detail {
namespace {

// Appends `data` at an offset aligned for any texel block (copies need a multiple of the block
// size and of 4).
VkDeviceSize append(PlaneUpload& u, const uint8_t* data, size_t size) {
  const size_t at = (u.bytes.size() + 15) & ~size_t(15);
  u.bytes.resize(at + size);
  std::memcpy(u.bytes.data() + at, data, size);
  return VkDeviceSize(at);
}

VkBufferImageCopy region(VkDeviceSize offset, uint32_t x, uint32_t y, uint32_t slice, uint32_t w, uint32_t h,
                         bool is3D) {
  VkBufferImageCopy r{};
  r.bufferOffset = offset;
  r.imageSubresource = {VK_IMAGE_ASPECT_COLOR_BIT, 0, is3D ? 0u : slice, 1};
  r.imageOffset = {int32_t(x), int32_t(y), is3D ? int32_t(slice) : 0};
  r.imageExtent = {w, h, 1};
  return r;
}

}  // namespace

// upload.h's (the single field's and the scene's).
Status appendPlane(const File& file, Plane plane, bool perMap, uint32_t width, bool is3D, uint32_t baseSlice,
                   PlaneUpload& u) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  if (perMap) {
    const uint32_t m = field.mapResolution;
    for (uint32_t k = 0; k < field.mapCount; ++k) {
      auto map = file.mapData(plane, k);
      if (!map) return map.error();
      const TilePlacement at = placeMap(layout, k);
      u.regions.push_back(region(append(u, map->data(), map->size()), at.x, at.y, baseSlice + at.slice, m, m, is3D));
    }
    return {};
  }
  std::vector<uint8_t> slice(file.sliceBytes(plane));
  for (uint32_t s = 0; s < layout.sliceCount; ++s) {
    if (Status st = file.readSlice(plane, s, slice); !st) return st.error();
    u.regions.push_back(
        region(append(u, slice.data(), slice.size()), 0, 0, baseSlice + s, width, layout.sliceHeight, is3D));
  }
  return {};
}

// Copies the staged bytes into the image and leaves it ready for the compute shader.
Status uploadImage(const Context& ctx, const Image& image, const PlaneUpload& u) {
  auto staging = detail::makeHostBuffer(ctx, u.bytes.size(), VK_BUFFER_USAGE_TRANSFER_SRC_BIT);
  if (!staging) return staging.error();
  if (!u.bytes.empty()) std::memcpy(staging->mapped, u.bytes.data(), u.bytes.size());
  return ctx.submitAndWait([&](VkCommandBuffer cb) {
    detail::transition(cb, image.image, VK_IMAGE_LAYOUT_UNDEFINED, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL);
    if (!u.regions.empty())
      vkCmdCopyBufferToImage(cb, staging->buffer, image.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL,
                             uint32_t(u.regions.size()), u.regions.data());
    detail::transition(cb, image.image, VK_IMAGE_LAYOUT_TRANSFER_DST_OPTIMAL, VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL);
  });
}

// The layout against the device's image limits (the GL loader checks GL_MAX_TEXTURE_SIZE and
// GL_MAX_ARRAY_TEXTURE_LAYERS the same way).
Status checkLimits(const Context& ctx, const LayoutDesc& layout, uint32_t width) {
  const VkPhysicalDeviceLimits& l = ctx.properties().limits;
  const bool is3D = layout.target == LayoutTarget::kTexture3D;
  const uint32_t maxSize = is3D ? l.maxImageDimension3D : l.maxImageDimension2D;
  const uint32_t maxLayers = is3D ? l.maxImageDimension3D : l.maxImageArrayLayers;
  const char* sizeName = is3D ? "maxImageDimension3D" : "maxImageDimension2D";
  if (width > maxSize || layout.sliceHeight > maxSize)
    return makeError(Code::kUnsupported, std::string("the field's packed layout does not fit this Vulkan device: ") +
                                             sizeName + " is " + std::to_string(maxSize) +
                                             ", the layout needs slices " + std::to_string(width) + "x" +
                                             std::to_string(layout.sliceHeight));
  if (layout.sliceCount > maxLayers)
    return makeError(Code::kUnsupported, std::string("the field's packed layout does not fit this Vulkan device: ") +
                                             (is3D ? "maxImageDimension3D" : "maxImageArrayLayers") + " is " +
                                             std::to_string(maxLayers) + ", the layout needs " +
                                             std::to_string(layout.sliceCount) + " slices");
  return {};
}

Result<VkFormat> mapsFormat(const Context& ctx, const File& file, uint32_t width) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  VkFormat format = VK_FORMAT_R8_UINT;
  uint64_t expect = uint64_t(width) * layout.sliceHeight;
  switch (field.distanceEncoding) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kUnorm8Chord:
    case DistanceEncoding::kBit1:
      break;
    case DistanceEncoding::kUnorm16Diameter:
      format = VK_FORMAT_R16_UINT;
      expect *= 2;
      break;
    case DistanceEncoding::kBc4Diameter:
      format = VK_FORMAT_BC4_UNORM_BLOCK;
      expect /= 2;
      break;
    default:
      return makeError(Code::kUnsupported, "vff_vk cannot upload this distance encoding");
  }
  if (format == VK_FORMAT_BC4_UNORM_BLOCK && (layout.target == LayoutTarget::kTexture3D || layout.gutter != 0))
    return makeError(Code::kUnsupported, "bc4-diameter slices must be a 2D array without gutters");
  if (file.sliceBytes(Plane::kDistance) != expect)
    return makeError(Code::kUnsupported,
                     "unexpected slice size " + std::to_string(file.sliceBytes(Plane::kDistance)) + " bytes");
  VkFormatProperties fp;
  vkGetPhysicalDeviceFormatProperties(ctx.physicalDevice(), format, &fp);
  if (!(fp.optimalTilingFeatures & VK_FORMAT_FEATURE_SAMPLED_IMAGE_BIT))
    return makeError(Code::kUnsupported, format == VK_FORMAT_BC4_UNORM_BLOCK
                                             ? "this Vulkan device cannot sample BC4_UNORM_BLOCK images"
                                             : "this Vulkan device cannot sample the distance format");
  return format;
}

Status makeSampler(const Context& ctx, VkSampler* sampler) {
  auto si = detail::vkStruct<VkSamplerCreateInfo>(VK_STRUCTURE_TYPE_SAMPLER_CREATE_INFO);
  si.magFilter = VK_FILTER_NEAREST;
  si.minFilter = VK_FILTER_NEAREST;
  si.mipmapMode = VK_SAMPLER_MIPMAP_MODE_NEAREST;
  si.addressModeU = si.addressModeV = si.addressModeW = VK_SAMPLER_ADDRESS_MODE_CLAMP_TO_EDGE;
  si.maxLod = 0.0f;
  if (VkResult r = vkCreateSampler(ctx.device(), &si, nullptr, sampler); r != VK_SUCCESS) {
    *sampler = VK_NULL_HANDLE;
    return vkError(r, "vkCreateSampler");
  }
  return {};
}

}  // namespace detail

namespace {

// The normal plane (or the 1 x 1 x 1 placeholder) into s.normalImage.
Status loadNormals(const Context& ctx, const File& file, GpuField::State& s) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  const bool is3D = layout.target == LayoutTarget::kTexture3D;
  detail::ImageDesc d{VK_FORMAT_R16G16_SINT, 1, 1, 1, is3D};
  PlaneUpload u;
  if (s.normals) {
    if (field.normalEncoding != NormalEncoding::kOctSnorm16)
      return makeError(Code::kUnsupported, "vff_vk cannot upload this normal encoding");
    if (file.sliceBytes(Plane::kNormal) != uint64_t(layout.sliceWidth) * layout.sliceHeight * 4)
      return makeError(Code::kUnsupported,
                       "unexpected normal slice size " + std::to_string(file.sliceBytes(Plane::kNormal)) + " bytes");
    d = {VK_FORMAT_R16G16_SINT, layout.sliceWidth, layout.sliceHeight, layout.sliceCount, is3D};
    if (Status st = appendPlane(file, Plane::kNormal, layout.gutter == 0, layout.sliceWidth, is3D, 0, u); !st)
      return st;
    s.textureBytes += file.sliceBytes(Plane::kNormal) * layout.sliceCount;
  }
  auto image = detail::makeImage(ctx, d);
  if (!image) return image.error();
  s.normalImage = std::move(*image);
  return uploadImage(ctx, s.normalImage, u);
}

}  // namespace

Result<GpuField> loadField(const Context& ctx, const File& file) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  auto block = gl::makeFieldBlock(field, layout);
  if (!block) return block.error();
  const bool bit1 = field.distanceEncoding == DistanceEncoding::kBit1;
  const uint32_t width = bit1 ? layout.sliceWidth / 8 : layout.sliceWidth;
  if (Status st = checkLimits(ctx, layout, width); !st) return st.error();
  auto format = mapsFormat(ctx, file, width);
  if (!format) return format.error();
  auto positions = gl::makePositionsBuffer(field);
  if (!positions) return positions.error();

  GpuField out;
  out.s_ = std::make_unique<GpuField::State>();
  GpuField::State& s = *out.s_;
  s.device = ctx.device();
  s.block = *block;
  s.kind = mapsKind(field, layout);
  s.normals = file.hasNormals();
  const bool is3D = layout.target == LayoutTarget::kTexture3D;
  auto maps = detail::makeImage(ctx, {*format, width, layout.sliceHeight, layout.sliceCount, is3D});
  if (!maps) return maps.error();
  s.maps = std::move(*maps);
  // As the GL loader: per map from the file's bytes without gutters (always for bc4-diameter, whose
  // maps are whole blocks), else composed slices (bit1 packs eight texels a byte, so its tiles need
  // not start on a byte).
  const bool perMap = *format == VK_FORMAT_BC4_UNORM_BLOCK || (layout.gutter == 0 && !bit1);
  detail::PlaneUpload upload;
  if (Status st = detail::appendPlane(file, Plane::kDistance, perMap, width, is3D, 0, upload); !st) return st.error();
  if (Status st = detail::uploadImage(ctx, s.maps, upload); !st) return st.error();
  s.textureBytes += file.sliceBytes(Plane::kDistance) * layout.sliceCount;
  if (Status st = loadNormals(ctx, file, s); !st) return st.error();
  auto fieldBuffer = makeFilledBuffer(ctx, &s.block, sizeof(gl::FieldBlock), VK_BUFFER_USAGE_UNIFORM_BUFFER_BIT);
  if (!fieldBuffer) return fieldBuffer.error();
  s.fieldBuffer = std::move(*fieldBuffer);
  auto posBuffer =
      makeFilledBuffer(ctx, positions->data(), positions->size() * sizeof(float), VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!posBuffer) return posBuffer.error();
  s.positions = std::move(*posBuffer);
  if (Status st = makeSampler(ctx, &s.sampler); !st) return st.error();
  return out;
}

}  // namespace vff::vk
