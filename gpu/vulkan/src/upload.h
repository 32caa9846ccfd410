// upload.h (private to vff_vk) - the steps of a field's upload that the single field (field.cpp)
// and the scene (scene.cpp) share: a plane's slices as copy regions staged in one buffer, the copy
// into an image, the device's limits and formats, the sampler.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <vector>

#include "vff/error.h"
#include "vff/reader.h"
#include "vff/vk/context.h"
#include "vk_objects.h"

namespace vff::vk::detail {

// A plane's upload: the bytes to copy (staged in one buffer) and where each piece goes.
struct PlaneUpload {
  std::vector<uint8_t> bytes;
  std::vector<VkBufferImageCopy> regions;
};

// What the GL loader's uploadDistance / uploadNormals send, appended to `u` as copy regions: each
// map from the file's bytes into its tile when `perMap`, else every composed slice (`width`
// texels wide, at the corner (0, 0) of its layer); slice s goes to layer baseSlice + s.
Status appendPlane(const File& file, Plane plane, bool perMap, uint32_t width, bool is3D, uint32_t baseSlice,
                   PlaneUpload& u);

// Copies the staged bytes into the image (every layer) and leaves it ready for the compute shader.
Status uploadImage(const Context& ctx, const Image& image, const PlaneUpload& u);

// The layout against the device's image limits (kUnsupported naming the limit).
Status checkLimits(const Context& ctx, const LayoutDesc& layout, uint32_t width);

// The distance plane's image format (R8_UINT, R16_UINT, BC4_UNORM_BLOCK), checked against the
// file's slice size and what the device samples.
Result<VkFormat> mapsFormat(const Context& ctx, const File& file, uint32_t width);

// Nearest filtering, clamp to edge (texelFetch ignores it; a combined image sampler needs one).
Status makeSampler(const Context& ctx, VkSampler* sampler);

}  // namespace vff::vk::detail
