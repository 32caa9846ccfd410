// vff/gl/loader.h - uploading a .vff field to OpenGL 4.3 for gpu/glsl/vff_query.glsl.
//
//   vff::Result<vff::File> file = vff::File::open("bunny.vff");
//   vff::Result<vff::gl::GpuField> gpu = vff::gl::loadField(*file);   // a GL 4.3 context is current
//   if (!gpu) { fprintf(stderr, "%s\n", gpu.error().toString().c_str()); return 1; }
//   gpu->bind();                       // UBO 0, texture unit 1, SSBO 2 (the shader's defaults)
//   // shader: #version 430, then the text of vff_query.glsl, then vffIntersect(o, d, 0, tmax, -1)
//
// What loadField creates (all owned by the GpuField, deleted by its destructor):
// * the distance plane's packed slices (spec/format.md section 10), composed by File::readSlice one
//   slice at a time and uploaded with glTexSubImage3D into immutable storage of internal format
//   GL_R8UI (unorm8-diameter, unorm8-chord, bit1: width sliceWidth / 8) or GL_R16UI
//   (unorm16-diameter), target GL_TEXTURE_2D_ARRAY (LAYT target 1) or GL_TEXTURE_3D (target 2),
//   nearest filtering, one level; bc4-diameter: GL_COMPRESSED_RED_RGTC1 (2D array), each map's
//   blocks uploaded as they are stored with glCompressedTexSubImage3D (the texture unit decodes them;
//   the shader needs shaderDefines(field, layout));
// * a uniform buffer holding a FieldBlock (std140, the shader's VffFieldBlock);
// * a shader storage buffer with the binary32 unit vector of every positional sample
//   (vff::PositionSet::position), one vec4 each; for unorm8-chord followed by the decode scale
//   2R cos(alpha) / 254 (vff::quantizationStep) of every texel of a map (M * M floats, padded to a
//   multiple of 4); then, from vec4 FieldBlock::neighbourOffset, the neighbour lists
//   (neighbourLists below) as floats, two vec4 per map, -1 for padding (indices below 2^24 are
//   exact in binary32);
// * when the field has a normal plane (oct-snorm16): its packed slices, same layout and target as
//   the distance slices, internal format GL_RG16I (the raw snorm16 pairs; the shader converts them
//   exactly as vff::decodeNormal does, not through GL's snorm conversion).
//
// Preconditions: an OpenGL 4.3 (or later) context is current on the calling thread, for loadField
// and for the GpuField's destructor. GL entry points come from GLVND's libOpenGL. loadField saves
// and restores the GL state it changes (unpack alignment and buffer, the bound texture and buffers).
//
// Errors (values, never exceptions):
// * kUnsupported when the layout does not fit the context: the message names the limit
//   (GL_MAX_TEXTURE_SIZE, GL_MAX_ARRAY_TEXTURE_LAYERS or GL_MAX_3D_TEXTURE_SIZE), its value and
//   what the file needs; also for a GL version below 4.3 or a field this loader cannot upload;
// * the errors of File::readSlice (kBlockChecksum, kBlockDecode...);
// * kBadState when GL reports an error (glGetError) or no context is current; kOutOfMemory for
//   GL_OUT_OF_MEMORY.
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "vff/error.h"
#include "vff/gl/gl_name.h"
#include "vff/format.h"
#include "vff/query.h"
#include "vff/reader.h"

namespace vff::gl {

// The shader's uniform block VffFieldBlock, std140 (every member is a 4-byte scalar or the vec3
// at offset 0 followed by a float, so the C++ layout equals std140). Names as in the spec tables.
struct FieldBlock {
  float sphereCenter[3] = {0, 0, 0};
  float sphereRadius = 0;
  uint32_t positionScheme = 0;
  uint32_t positionParam = 0;
  uint32_t mapCount = 0;
  uint32_t directionScheme = 0;
  uint32_t mapResolution = 0;
  uint32_t distanceEncoding = 0;
  uint32_t missCode = 0;
  uint32_t normalEncoding = 0;
  uint32_t target = 0;
  uint32_t gutter = 0;
  uint32_t tileSize = 0;
  uint32_t tilesPerRow = 0;
  uint32_t tilesPerColumn = 0;
  uint32_t sliceWidth = 0;
  uint32_t sliceHeight = 0;
  uint32_t sliceCount = 0;
  float intraBias = 0;      // vff::defaultIntraBias(field), a fraction of R
  float distanceScale = 0;  // vff::quantizationStep: 2R / 254 (unorm8-, bc4-diameter), 2R / 65534
                            // (unorm16-diameter); 0 for unorm8-chord (per texel) and bit1
  float invRadius = 0;      // 1 / R
  float twoRadius = 0;      // 2 R
  // Reconstruction::kInterpolated (libvff/src/query/query_build.cpp, FieldQuery::Impl::build): where the
  // neighbour lists start in the positions buffer (in vec4 units), and the squared chord radius of
  // the kernel, (1.3 sqrt(4 pi / mapCount))^2, computed with the CPU's float expressions.
  uint32_t neighbourOffset = 0;
  float kernelRadius2 = 0;
  uint32_t reserved0 = 0, reserved1 = 0;
};
static_assert(sizeof(FieldBlock) == 112, "FieldBlock must match the std140 block");

// The neighbour lists of Reconstruction::kInterpolated: kNeighbours indices per map (the samples
// nearest to 12 probe directions on each of two rings, 1 and 1.6 mean spacings around the sample,
// duplicates and the sample itself left out), UINT32_MAX padding; the same lists as the CPU query
// uses (vff::queryNeighbours).
// Errors: PositionSet::fromField's.
inline constexpr uint32_t kNeighbours = kQueryNeighbours;
Result<std::vector<uint32_t>> neighbourLists(const FieldDesc& field);

// Fills the block from a field and its layout (no GL calls), as loadField uploads it. Errors:
// checkFieldDesc's and checkLayout's.
Result<FieldBlock> makeFieldBlock(const FieldDesc& field, const LayoutDesc& layout);

// The floats of the positions buffer (VffPositionsBlock, see the top of this file) as loadField
// uploads them (no GL calls): a vec4 per sample, for unorm8-chord the decode step
// vff::quantizationStep of every texel, from vec4 makeFieldBlock(...).neighbourOffset the
// neighbour lists. Errors: PositionSet::fromField's; kUnsupported beyond 2^24 maps.
Result<std::vector<float>> makePositionsBuffer(const FieldDesc& field);

// Limits a caller can tighten below the context's (0: the context's value).
struct LoadOptions {
  uint32_t maxTextureSize = 0;  // clamps GL_MAX_TEXTURE_SIZE
  uint32_t maxLayers = 0;       // clamps GL_MAX_ARRAY_TEXTURE_LAYERS (or GL_MAX_3D_TEXTURE_SIZE)
};

// Where bind() attaches the field; the defaults are those of vff_query.glsl.
struct Bindings {
  uint32_t field = 0;      // uniform buffer binding (VFF_FIELD_BINDING)
  uint32_t maps = 1;       // texture unit (VFF_MAPS_BINDING)
  uint32_t positions = 2;  // shader storage buffer binding (VFF_POSITIONS_BINDING)
  uint32_t normals = 3;    // texture unit (VFF_NORMALS_BINDING)
};

// A field on the GPU. Move-only (a moved-from GpuField is empty); the destructor deletes the GL
// objects (the context must be current).
class GpuField {
 public:
  GpuField() = default;
  GpuField(GpuField&& o) noexcept : s_(std::exchange(o.s_, {})) {}
  GpuField& operator=(GpuField&& o) noexcept {
    s_ = std::exchange(o.s_, {});  // (the objects held before are deleted)
    return *this;
  }

  // Binds the resources (the normal texture only when the field has one). Leaves the active
  // texture unit at `maps`.
  void bind(const Bindings& bindings = {}) const noexcept;
  // Deletes the GL objects now (the context must be current); the object becomes empty.
  void release() noexcept { s_ = {}; }

  const FieldBlock& block() const noexcept { return s_.block; }
  uint32_t mapsTexture() const noexcept { return s_.mapsTexture.get(); }  // GL texture name
  uint32_t mapsTarget() const noexcept { return s_.mapsTarget; }          // GL_TEXTURE_2D_ARRAY or GL_TEXTURE_3D
  uint32_t normalsTexture() const noexcept { return s_.normalsTexture.get(); }  // 0 without a normal plane
  uint32_t fieldBuffer() const noexcept { return s_.fieldBuffer.get(); }
  uint32_t positionsBuffer() const noexcept { return s_.positionsBuffer.get(); }
  uint64_t textureBytes() const noexcept { return s_.textureBytes; }  // bytes uploaded to the texture

 private:
  friend Result<GpuField> loadField(const File& file, const LoadOptions& options);
  struct State {
    FieldBlock block;
    GlName mapsTexture{GlName::Kind::kTexture}, normalsTexture{GlName::Kind::kTexture};
    GlName fieldBuffer{GlName::Kind::kBuffer}, positionsBuffer{GlName::Kind::kBuffer};
    uint32_t mapsTarget = 0;
    uint64_t textureBytes = 0;
  } s_;
};

// Uploads the file's distance plane, field block and sample positions (see the top of this file).
Result<GpuField> loadField(const File& file, const LoadOptions& options = {});

// The #define lines vff_query.glsl needs for a field, to put between `#version 430` and the
// shader's text: "#define VFF_MAPS_3D\n" for the 3d target, "#define VFF_MAPS_BC4\n" for
// bc4-diameter (a float sampler of the compressed slices), else "".
const char* shaderDefines(const FieldDesc& field, const LayoutDesc& layout) noexcept;

}  // namespace vff::gl
