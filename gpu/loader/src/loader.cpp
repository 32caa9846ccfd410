// The OpenGL 4.3 loader (vff/gl/loader.h).
#include "vff/gl/loader.h"

#include <GL/glcorearb.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>
#include <vector>

#include "vff/positions.h"
#include "vff/query.h"

namespace vff::gl {
namespace {

constexpr float kPi = 3.14159265358979323846f;

std::string glErrorName(GLenum e) {
  switch (e) {
    case GL_INVALID_ENUM: return "GL_INVALID_ENUM";
    case GL_INVALID_VALUE: return "GL_INVALID_VALUE";
    case GL_INVALID_OPERATION: return "GL_INVALID_OPERATION";
    case GL_OUT_OF_MEMORY: return "GL_OUT_OF_MEMORY";
    case GL_INVALID_FRAMEBUFFER_OPERATION: return "GL_INVALID_FRAMEBUFFER_OPERATION";
    default: return "GL error 0x" + std::to_string(e);
  }
}

// The first pending GL error as a vff::Error, after draining the queue.
Status checkGl(const char* what) {
  GLenum first = glGetError();
  if (first == GL_NO_ERROR) return {};
  for (int i = 0; i < 16 && glGetError() != GL_NO_ERROR; ++i) {
  }
  return makeError(first == GL_OUT_OF_MEMORY ? Code::kOutOfMemory : Code::kBadState,
                   std::string(what) + " failed: " + glErrorName(first));
}

uint32_t getInt(GLenum name) {
  GLint v = 0;
  glGetIntegerv(name, &v);
  return v > 0 ? uint32_t(v) : 0;
}

// Restores the GL state loadField touches.
struct SavedState {
  GLint unpackAlignment = 4, unpackBuffer = 0, unpackRowLength = 0, unpackImageHeight = 0;
  GLint unpackSkipPixels = 0, unpackSkipRows = 0, unpackSkipImages = 0;
  GLint texture2DArray = 0, texture3D = 0, uniformBuffer = 0, storageBuffer = 0;
  SavedState() {
    glGetIntegerv(GL_UNPACK_ALIGNMENT, &unpackAlignment);
    glGetIntegerv(GL_PIXEL_UNPACK_BUFFER_BINDING, &unpackBuffer);
    glGetIntegerv(GL_UNPACK_ROW_LENGTH, &unpackRowLength);
    glGetIntegerv(GL_UNPACK_IMAGE_HEIGHT, &unpackImageHeight);
    glGetIntegerv(GL_UNPACK_SKIP_PIXELS, &unpackSkipPixels);
    glGetIntegerv(GL_UNPACK_SKIP_ROWS, &unpackSkipRows);
    glGetIntegerv(GL_UNPACK_SKIP_IMAGES, &unpackSkipImages);
    glGetIntegerv(GL_TEXTURE_BINDING_2D_ARRAY, &texture2DArray);
    glGetIntegerv(GL_TEXTURE_BINDING_3D, &texture3D);
    glGetIntegerv(GL_UNIFORM_BUFFER_BINDING, &uniformBuffer);
    glGetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &storageBuffer);
  }
  ~SavedState() {
    glPixelStorei(GL_UNPACK_ALIGNMENT, unpackAlignment);
    glBindBuffer(GL_PIXEL_UNPACK_BUFFER, GLuint(unpackBuffer));
    glPixelStorei(GL_UNPACK_ROW_LENGTH, unpackRowLength);
    glPixelStorei(GL_UNPACK_IMAGE_HEIGHT, unpackImageHeight);
    glPixelStorei(GL_UNPACK_SKIP_PIXELS, unpackSkipPixels);
    glPixelStorei(GL_UNPACK_SKIP_ROWS, unpackSkipRows);
    glPixelStorei(GL_UNPACK_SKIP_IMAGES, unpackSkipImages);
    glBindTexture(GL_TEXTURE_2D_ARRAY, GLuint(texture2DArray));
    glBindTexture(GL_TEXTURE_3D, GLuint(texture3D));
    glBindBuffer(GL_UNIFORM_BUFFER, GLuint(uniformBuffer));
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, GLuint(storageBuffer));
  }
};

// The message names the limit, what the file's layout needs, and a layout that fits the context
// (with the vff-convert options that repack the file into it), or says that none does.
Error limitError(const char* limit, uint32_t value, const std::string& need, const FieldDesc& field,
                 const LayoutDesc& layout, uint32_t maxSize, uint32_t maxLayers) {
  std::string msg = std::string("the field's packed layout does not fit this GL context: ") + limit + " is " +
                    std::to_string(value) + ", the layout needs " + need;
  LayoutLimits fit;
  fit.target = layout.target;
  fit.maxTextureSize = maxSize;
  fit.maxLayers = maxLayers;
  fit.gutter = layout.gutter;
  if (auto l = computeLayout(field, fit); l.ok()) {
    msg += "; a layout that fits: " + std::to_string(l->sliceCount) + " slice(s) of " + std::to_string(l->sliceWidth) +
           "x" + std::to_string(l->sliceHeight) + " (vff-convert IN.vff --to vff OUT.vff --max-texture-size " +
           std::to_string(maxSize) + " --max-layers " + std::to_string(maxLayers) + ")";
  } else {
    msg += "; no layout of these maps fits it";
  }
  return makeError(Code::kUnsupported, msg);
}

}  // namespace

Result<FieldBlock> makeFieldBlock(const FieldDesc& field, const LayoutDesc& layout) {
  if (Status s = checkFieldDesc(field); !s) return s.error();
  if (Status s = checkLayout(layout, field); !s) return s.error();
  FieldBlock b;
  for (int i = 0; i < 3; ++i) b.sphereCenter[i] = field.sphere.center[i];
  const float radius = field.sphere.radius;
  b.sphereRadius = radius;
  b.positionScheme = uint32_t(field.positionScheme);
  b.positionParam = field.positionParam;
  b.mapCount = field.mapCount;
  b.directionScheme = uint32_t(field.directionScheme);
  b.mapResolution = field.mapResolution;
  b.distanceEncoding = uint32_t(field.distanceEncoding);
  b.missCode = missCode(field.distanceEncoding);
  b.normalEncoding = uint32_t(field.normalEncoding);
  b.target = uint32_t(layout.target);
  b.gutter = layout.gutter;
  b.tileSize = layout.tileSize;
  b.tilesPerRow = layout.tilesPerRow;
  b.tilesPerColumn = layout.tilesPerColumn;
  b.sliceWidth = layout.sliceWidth;
  b.sliceHeight = layout.sliceHeight;
  b.sliceCount = layout.sliceCount;
  b.intraBias = defaultIntraBias(field);
  // The same float expressions as the CPU query's decode (libvff/src/query.cpp), so that the
  // shader's decoded distances are bit-identical.
  switch (field.distanceEncoding) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kBc4Diameter: b.distanceScale = 2.0f * radius / 254.0f; break;
    case DistanceEncoding::kUnorm16Diameter: b.distanceScale = 2.0f * radius / 65534.0f; break;
    default: b.distanceScale = 0.0f; break;
  }
  b.invRadius = 1.0f / radius;
  b.twoRadius = 2.0f * radius;
  // As FieldQuery::Impl::build.
  const float spacing = std::sqrt(4.0f * kPi / float(field.mapCount));
  const float r = kQueryKernelSpacings * spacing;
  b.kernelRadius2 = r * r;
  return b;
}

Result<std::vector<uint32_t>> neighbourLists(const FieldDesc& field) {
  auto ps = PositionSet::fromField(field);
  if (!ps) return ps.error();
  return queryNeighbours(*ps);
}

GpuField::GpuField(GpuField&& o) noexcept
    : block_(o.block_),
      mapsTexture_(std::exchange(o.mapsTexture_, 0)),
      mapsTarget_(std::exchange(o.mapsTarget_, 0)),
      fieldBuffer_(std::exchange(o.fieldBuffer_, 0)),
      positionsBuffer_(std::exchange(o.positionsBuffer_, 0)),
      normalsTexture_(std::exchange(o.normalsTexture_, 0)),
      textureBytes_(std::exchange(o.textureBytes_, 0)) {}

GpuField& GpuField::operator=(GpuField&& o) noexcept {
  if (this != &o) {
    release();
    block_ = o.block_;
    mapsTexture_ = std::exchange(o.mapsTexture_, 0);
    mapsTarget_ = std::exchange(o.mapsTarget_, 0);
    fieldBuffer_ = std::exchange(o.fieldBuffer_, 0);
    positionsBuffer_ = std::exchange(o.positionsBuffer_, 0);
    normalsTexture_ = std::exchange(o.normalsTexture_, 0);
    textureBytes_ = std::exchange(o.textureBytes_, 0);
  }
  return *this;
}

GpuField::~GpuField() { release(); }

void GpuField::release() noexcept {
  if (mapsTexture_) glDeleteTextures(1, &mapsTexture_);
  if (fieldBuffer_) glDeleteBuffers(1, &fieldBuffer_);
  if (positionsBuffer_) glDeleteBuffers(1, &positionsBuffer_);
  if (normalsTexture_) glDeleteTextures(1, &normalsTexture_);
  mapsTexture_ = fieldBuffer_ = positionsBuffer_ = mapsTarget_ = normalsTexture_ = 0;
  textureBytes_ = 0;
}

void GpuField::bind(const Bindings& b) const noexcept {
  glBindBufferBase(GL_UNIFORM_BUFFER, b.field, fieldBuffer_);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b.positions, positionsBuffer_);
  if (normalsTexture_) {
    glActiveTexture(GL_TEXTURE0 + b.normals);
    glBindTexture(mapsTarget_ ? mapsTarget_ : GL_TEXTURE_2D_ARRAY, normalsTexture_);
  }
  glActiveTexture(GL_TEXTURE0 + b.maps);
  glBindTexture(mapsTarget_ ? mapsTarget_ : GL_TEXTURE_2D_ARRAY, mapsTexture_);
}

const char* shaderDefines(const FieldDesc& field, const LayoutDesc& layout) noexcept {
  if (field.distanceEncoding == DistanceEncoding::kBc4Diameter) return "#define VFF_MAPS_BC4\n";
  return layout.target == LayoutTarget::kTexture3D ? "#define VFF_MAPS_3D\n" : "";
}

Result<GpuField> loadField(const File& file, const LoadOptions& options) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  auto block = makeFieldBlock(field, layout);
  if (!block) return block.error();

  // The context: GL 4.3 for compute shaders, storage buffers and texelFetch on integer arrays.
  glGetError();  // a caller's stale error is not ours
  const uint32_t major = getInt(GL_MAJOR_VERSION), minor = getInt(GL_MINOR_VERSION);
  if (Status s = checkGl("querying the GL version"); !s) return makeError(Code::kBadState, s.error().message + " (is a GL context current?)");
  if (major < 4 || (major == 4 && minor < 3))
    return makeError(Code::kUnsupported, "the GL context is version " + std::to_string(major) + "." +
                                             std::to_string(minor) + ", vff_gl needs 4.3");

  // The limits, tightened by the caller's.
  const bool is3D = layout.target == LayoutTarget::kTexture3D;
  const char* sizeName = is3D ? "GL_MAX_3D_TEXTURE_SIZE" : "GL_MAX_TEXTURE_SIZE";
  const char* layerName = is3D ? "GL_MAX_3D_TEXTURE_SIZE" : "GL_MAX_ARRAY_TEXTURE_LAYERS";
  uint32_t maxSize = getInt(is3D ? GL_MAX_3D_TEXTURE_SIZE : GL_MAX_TEXTURE_SIZE);
  uint32_t maxLayers = getInt(is3D ? GL_MAX_3D_TEXTURE_SIZE : GL_MAX_ARRAY_TEXTURE_LAYERS);
  if (options.maxTextureSize && options.maxTextureSize < maxSize) maxSize = options.maxTextureSize;
  if (options.maxLayers && options.maxLayers < maxLayers) maxLayers = options.maxLayers;
  const bool bit1 = field.distanceEncoding == DistanceEncoding::kBit1;
  const uint32_t width = bit1 ? layout.sliceWidth / 8 : layout.sliceWidth;
  if (width > maxSize)
    return limitError(sizeName, maxSize, "slices " + std::to_string(width) + " texels wide", field, layout, maxSize,
                      maxLayers);
  if (layout.sliceHeight > maxSize)
    return limitError(sizeName, maxSize, "slices " + std::to_string(layout.sliceHeight) + " texels high", field,
                      layout, maxSize, maxLayers);
  if (layout.sliceCount > maxLayers)
    return limitError(layerName, maxLayers, std::to_string(layout.sliceCount) + " slices", field, layout, maxSize,
                      maxLayers);

  GLenum internalFormat = GL_R8UI, type = GL_UNSIGNED_BYTE;
  switch (field.distanceEncoding) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kUnorm8Chord:
    case DistanceEncoding::kBit1: break;
    case DistanceEncoding::kUnorm16Diameter: internalFormat = GL_R16UI; type = GL_UNSIGNED_SHORT; break;
    case DistanceEncoding::kBc4Diameter: internalFormat = GL_COMPRESSED_RED_RGTC1; break;
    default: return makeError(Code::kUnsupported, "vff_gl cannot upload this distance encoding");
  }
  const bool bc4 = field.distanceEncoding == DistanceEncoding::kBc4Diameter;
  if (bc4 && (is3D || layout.gutter != 0))  // the file's rules 7001 and 7002
    return makeError(Code::kUnsupported, "bc4-diameter slices must be a 2D array without gutters");
  const uint64_t sliceBytes = file.sliceBytes(Plane::kDistance);
  const uint64_t texelBytes = type == GL_UNSIGNED_SHORT ? 2 : 1;
  if (sliceBytes != (bc4 ? uint64_t(width) * layout.sliceHeight / 2 : uint64_t(width) * layout.sliceHeight * texelBytes))
    return makeError(Code::kUnsupported, "unexpected slice size " + std::to_string(sliceBytes) + " bytes");

  SavedState saved;
  GpuField out;
  out.block_ = *block;
  out.mapsTarget_ = is3D ? GL_TEXTURE_3D : GL_TEXTURE_2D_ARRAY;

  // The slices.
  glGenTextures(1, &out.mapsTexture_);
  glBindTexture(out.mapsTarget_, out.mapsTexture_);
  glTexParameteri(out.mapsTarget_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);  // integer textures: nearest only
  glTexParameteri(out.mapsTarget_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(out.mapsTarget_, GL_TEXTURE_BASE_LEVEL, 0);
  glTexParameteri(out.mapsTarget_, GL_TEXTURE_MAX_LEVEL, 0);
  glTexStorage3D(out.mapsTarget_, 1, internalFormat, GLsizei(width), GLsizei(layout.sliceHeight),
                 GLsizei(layout.sliceCount));
  if (Status s = checkGl("glTexStorage3D"); !s) return s.error();
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  glPixelStorei(GL_UNPACK_IMAGE_HEIGHT, 0);
  glPixelStorei(GL_UNPACK_SKIP_PIXELS, 0);
  glPixelStorei(GL_UNPACK_SKIP_ROWS, 0);
  glPixelStorei(GL_UNPACK_SKIP_IMAGES, 0);
  if (bc4) {
    // Each map's blocks are its compressed M x M image: upload them as stored. Unused tiles stay
    // undefined; no lookup reads them.
    const GLsizei m = GLsizei(field.mapResolution);
    for (uint32_t k = 0; k < field.mapCount; ++k) {
      auto map = file.mapData(Plane::kDistance, k);
      if (!map) return map.error();
      const TilePlacement at = placeMap(layout, k);
      glCompressedTexSubImage3D(out.mapsTarget_, 0, GLint(at.x), GLint(at.y), GLint(at.slice), m, m, 1,
                                GL_COMPRESSED_RED_RGTC1, GLsizei(map->size()), map->data());
    }
    if (Status st = checkGl("glCompressedTexSubImage3D (maps)"); !st) return st.error();
    out.textureBytes_ += sliceBytes * layout.sliceCount;
  } else if (layout.gutter == 0 && !bit1) {
    // Without gutters every map is one rectangle of its slice: upload it straight from the file's
    // bytes (the mapped file itself for stored blocks), with no slice composed on the CPU. Tiles
    // past the last map stay undefined; no lookup reads them.
    for (uint32_t k = 0; k < field.mapCount; ++k) {
      auto map = file.mapData(Plane::kDistance, k);
      if (!map) return map.error();
      const TilePlacement at = placeMap(layout, k);
      glTexSubImage3D(out.mapsTarget_, 0, GLint(at.x), GLint(at.y), GLint(at.slice), GLsizei(field.mapResolution),
                      GLsizei(field.mapResolution), 1, GL_RED_INTEGER, type, map->data());
    }
    if (Status st = checkGl("glTexSubImage3D (maps)"); !st) return st.error();
    out.textureBytes_ += sliceBytes * layout.sliceCount;
  } else {
    std::vector<uint8_t> slice(sliceBytes);
    for (uint32_t s = 0; s < layout.sliceCount; ++s) {
      if (Status st = file.readSlice(Plane::kDistance, s, slice); !st) return st.error();
      glTexSubImage3D(out.mapsTarget_, 0, 0, 0, GLint(s), GLsizei(width), GLsizei(layout.sliceHeight), 1,
                      GL_RED_INTEGER, type, slice.data());
      if (Status st = checkGl("glTexSubImage3D"); !st) return st.error();
      out.textureBytes_ += sliceBytes;
    }
  }

  // The normal plane: the same layout, two snorm16 per texel as GL_RG16I.
  if (file.hasNormals()) {
    if (field.normalEncoding != NormalEncoding::kOctSnorm16)
      return makeError(Code::kUnsupported, "vff_gl cannot upload this normal encoding");
    const uint64_t normalBytes = file.sliceBytes(Plane::kNormal);
    if (normalBytes != uint64_t(layout.sliceWidth) * layout.sliceHeight * 4)
      return makeError(Code::kUnsupported, "unexpected normal slice size " + std::to_string(normalBytes) + " bytes");
    glGenTextures(1, &out.normalsTexture_);
    glBindTexture(out.mapsTarget_, out.normalsTexture_);
    glTexParameteri(out.mapsTarget_, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
    glTexParameteri(out.mapsTarget_, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
    glTexParameteri(out.mapsTarget_, GL_TEXTURE_BASE_LEVEL, 0);
    glTexParameteri(out.mapsTarget_, GL_TEXTURE_MAX_LEVEL, 0);
    glTexStorage3D(out.mapsTarget_, 1, GL_RG16I, GLsizei(layout.sliceWidth), GLsizei(layout.sliceHeight),
                   GLsizei(layout.sliceCount));
    if (Status s = checkGl("glTexStorage3D (normals)"); !s) return s.error();
    if (layout.gutter == 0) {
      for (uint32_t k = 0; k < field.mapCount; ++k) {  // straight from the file, as the distances
        auto map = file.mapData(Plane::kNormal, k);
        if (!map) return map.error();
        const TilePlacement at = placeMap(layout, k);
        glTexSubImage3D(out.mapsTarget_, 0, GLint(at.x), GLint(at.y), GLint(at.slice), GLsizei(field.mapResolution),
                        GLsizei(field.mapResolution), 1, GL_RG_INTEGER, GL_SHORT, map->data());
      }
      if (Status st = checkGl("glTexSubImage3D (normal maps)"); !st) return st.error();
      out.textureBytes_ += normalBytes * layout.sliceCount;
    } else {
      std::vector<uint8_t> nslice(normalBytes);
      for (uint32_t s = 0; s < layout.sliceCount; ++s) {
        if (Status st = file.readSlice(Plane::kNormal, s, nslice); !st) return st.error();
        glTexSubImage3D(out.mapsTarget_, 0, 0, 0, GLint(s), GLsizei(layout.sliceWidth), GLsizei(layout.sliceHeight),
                        1, GL_RG_INTEGER, GL_SHORT, nslice.data());
        if (Status st = checkGl("glTexSubImage3D (normals)"); !st) return st.error();
        out.textureBytes_ += normalBytes;
      }
    }
  }

  // The field block (with where the neighbour lists start in the positions buffer).
  const bool chordTable = field.distanceEncoding == DistanceEncoding::kUnorm8Chord;
  const size_t mapTexels = size_t(field.mapResolution) * field.mapResolution;
  out.block_.neighbourOffset = uint32_t(field.mapCount + (chordTable ? (mapTexels + 3) / 4 : 0));
  glGenBuffers(1, &out.fieldBuffer_);
  glBindBuffer(GL_UNIFORM_BUFFER, out.fieldBuffer_);
  glBufferData(GL_UNIFORM_BUFFER, sizeof(FieldBlock), &out.block_, GL_STATIC_DRAW);
  if (Status s = checkGl("uploading the field block"); !s) return s.error();

  // The sample positions.
  auto ps = PositionSet::fromField(field);
  if (!ps) return ps.error();
  const bool chord = field.distanceEncoding == DistanceEncoding::kUnorm8Chord;
  std::vector<float> positions(size_t(out.block_.neighbourOffset) * 4 + size_t(field.mapCount) * kNeighbours, 0.0f);
  if (chord) {
    // The decode scale of every texel, as libvff/src/query.cpp computes it.
    float* scale = positions.data() + size_t(field.mapCount) * 4;
    const uint32_t m = field.mapResolution;
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i) {
        const float cosAlpha = texelDirection(field.directionScheme, m, i, j).z;
        scale[size_t(j) * m + i] = 2.0f * field.sphere.radius * cosAlpha / 254.0f;
      }
  }
  for (uint32_t k = 0; k < field.mapCount; ++k) {
    const Vec3 u = ps->position(k);
    positions[4 * size_t(k)] = u.x;
    positions[4 * size_t(k) + 1] = u.y;
    positions[4 * size_t(k) + 2] = u.z;
  }
  if (field.mapCount > (1u << 24))
    return makeError(Code::kUnsupported, "vff_gl stores sample indices as binary32: at most 2^24 maps");
  auto nb = neighbourLists(field);
  if (!nb) return nb.error();
  float* lists = positions.data() + size_t(out.block_.neighbourOffset) * 4;
  for (size_t i = 0; i < nb->size(); ++i) lists[i] = (*nb)[i] == UINT32_MAX ? -1.0f : float((*nb)[i]);
  glGenBuffers(1, &out.positionsBuffer_);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, out.positionsBuffer_);
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(positions.size() * sizeof(float)), positions.data(),
               GL_STATIC_DRAW);
  if (Status s = checkGl("uploading the sample positions"); !s) return s.error();
  return out;
}

}  // namespace vff::gl
