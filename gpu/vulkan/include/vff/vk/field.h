// vff/vk/field.h - uploading a .vff field to Vulkan for gpu/glsl/vff_query.glsl, the same data the
// OpenGL loader (vff/gl/loader.h) uploads, so that one shader source serves both APIs.
//
//   vff::Result<vff::vk::Context> ctx = vff::vk::Context::create();
//   vff::Result<vff::File> file = vff::File::open("bunny.vff");
//   vff::Result<vff::vk::GpuField> gpu = vff::vk::loadField(*ctx, *file);
//   if (!gpu) { fprintf(stderr, "%s\n", gpu.error().toString().c_str()); return 1; }
//   gpu->write(descriptorSet);       // set 0, bindings 0 to 3 (below)
//
// Descriptor set 0 (the bindings are vff_query.glsl's `binding =` defaults, which GL uses as its
// buffer and texture unit numbers):
//
//   binding  type                      shader name (vff_query.glsl)   contents
//   0        UNIFORM_BUFFER            VffFieldBlock vffField         vff::gl::FieldBlock (std140, 112 bytes)
//   1        COMBINED_IMAGE_SAMPLER    vffMaps                        the distance plane's packed slices
//   2        STORAGE_BUFFER            VffPositionsBlock              vff::gl::makePositionsBuffer's floats
//   3        COMBINED_IMAGE_SAMPLER    vffNormals                     the normal plane's packed slices
//
// What loadField creates (owned by the GpuField, destroyed by its destructor):
// * the distance slices (spec/format.md section 10) as an image of one level: a 2D array with one
//   layer per slice (LAYT target 1) or a 3D image with one depth slice per slice (target 2), format
//   R8_UINT (unorm8-diameter, unorm8-chord, bit1: width sliceWidth / 8), R16_UINT
//   (unorm16-diameter) or BC4_UNORM_BLOCK (bc4-diameter, 2D arrays only, where the device samples
//   it; the shader then needs the VFF_MAPS_BC4 variant). As the GL loader: without gutters each map
//   is copied from File::mapData straight into its tile (tiles past the last map stay undefined, no
//   lookup reads them); with gutters, or for bit1, each slice is composed by File::readSlice;
// * the normal slices (oct-snorm16) as R16G16_SINT in the same kind of image (the raw snorm16
//   pairs; the shader converts them as vff::decodeNormal does). A field without a normal plane gets
//   a 1 x 1 x 1 image instead: the shader declares vffNormals either way (it reads it only when
//   normalEncoding says so), and Vulkan wants every declared binding to hold a valid descriptor;
// * the FieldBlock (vff::gl::makeFieldBlock) in a uniform buffer and the positions buffer
//   (vff::gl::makePositionsBuffer: positions, unorm8-chord decode steps, neighbour lists) in a
//   storage buffer, both in host-visible memory;
// * one sampler, nearest filtering, clamp to edge (texelFetch ignores it; Vulkan needs one for a
//   combined image sampler).
// The shader variant: vff::gl::shaderDefines(field, layout) says which (2D array, VFF_MAPS_3D,
// VFF_MAPS_BC4); vff/vk/query.h has them compiled.
//
// Errors (values, never exceptions): makeFieldBlock's and makePositionsBuffer's; kUnsupported when
// the layout exceeds the device's maxImageDimension2D, maxImageDimension3D or maxImageArrayLayers
// (the message names the limit, its value and what the file needs), or the device cannot sample
// the format (BC4 without textureCompressionBC); File::mapData's and readSlice's; a failing Vulkan
// call's (vkError).
//
// Preconditions: the Context outlives the GpuField. The upload has finished when loadField returns.
// Move-only; a moved-from or default-constructed GpuField holds nothing and may only be destroyed
// or assigned to.
#pragma once

#include <vulkan/vulkan.h>

#include <cstdint>
#include <memory>

#include "vff/error.h"
#include "vff/gl/loader.h"
#include "vff/reader.h"
#include "vff/vk/context.h"

namespace vff::vk {

// Set 0's bindings of the field: vff_query.glsl's defaults (the same numbers as vff::gl::Bindings).
inline constexpr uint32_t kFieldBinding = 0;
inline constexpr uint32_t kMapsBinding = 1;
inline constexpr uint32_t kPositionsBinding = 2;
inline constexpr uint32_t kNormalsBinding = 3;

// The shader variant a field needs (vff::gl::shaderDefines: none, VFF_MAPS_3D, VFF_MAPS_BC4).
enum class MapsKind : uint32_t { kArray2D = 0, kTexture3D = 1, kBc4 = 2 };
MapsKind mapsKind(const FieldDesc& field, const LayoutDesc& layout) noexcept;

class GpuField {
 public:
  GpuField();
  GpuField(GpuField&&) noexcept;
  GpuField& operator=(GpuField&&) noexcept;
  ~GpuField();

  // Writes bindings 0 to 3 of `set` (a set of a layout with those four bindings as in the table).
  void write(VkDescriptorSet set) const noexcept;

  const gl::FieldBlock& block() const noexcept;
  MapsKind kind() const noexcept;
  bool hasNormals() const noexcept;        // the field's own normal plane (not the placeholder)
  uint64_t textureBytes() const noexcept;  // bytes copied into the images

  struct State;  // (the implementation's)

 private:
  friend Result<GpuField> loadField(const Context& ctx, const File& file);
  std::unique_ptr<State> s_;
};

// Uploads the file's field (see the top of this file).
Result<GpuField> loadField(const Context& ctx, const File& file);

}  // namespace vff::vk
