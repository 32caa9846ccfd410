// The OpenGL 4.3 loader (vff/gl/loader.h): the GL calls of loadField and GpuField. What it uploads
// is computed without GL in field_block.cpp.
#include "vff/gl/loader.h"

#include <GL/glcorearb.h>

#include "gl_upload.h"

#include <string>
#include <utility>
#include <vector>

namespace vff::gl {
namespace {

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

}  // namespace

namespace detail {

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

SavedState::SavedState() {
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

SavedState::~SavedState() {
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

namespace {

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

// The context: GL 4.3 for compute shaders, storage buffers and texelFetch on integer arrays.
Status checkVersion() {
  glGetError();  // a caller's stale error is not ours
  const uint32_t major = getInt(GL_MAJOR_VERSION), minor = getInt(GL_MINOR_VERSION);
  if (Status s = checkGl("querying the GL version"); !s)
    return makeError(Code::kBadState, s.error().message + " (is a GL context current?)");
  if (major < 4 || (major == 4 && minor < 3))
    return makeError(Code::kUnsupported, "the GL context is version " + std::to_string(major) + "." +
                                             std::to_string(minor) + ", vff_gl needs 4.3");
  return {};
}

// The layout against the context's limits, tightened by the caller's. `width`: the distance
// texture's width in texels.
Status checkLimits(const FieldDesc& field, const LayoutDesc& layout, const LoadOptions& options, uint32_t width) {
  const bool is3D = layout.target == LayoutTarget::kTexture3D;
  const char* sizeName = is3D ? "GL_MAX_3D_TEXTURE_SIZE" : "GL_MAX_TEXTURE_SIZE";
  const char* layerName = is3D ? "GL_MAX_3D_TEXTURE_SIZE" : "GL_MAX_ARRAY_TEXTURE_LAYERS";
  uint32_t maxSize = getInt(is3D ? GL_MAX_3D_TEXTURE_SIZE : GL_MAX_TEXTURE_SIZE);
  uint32_t maxLayers = getInt(is3D ? GL_MAX_3D_TEXTURE_SIZE : GL_MAX_ARRAY_TEXTURE_LAYERS);
  if (options.maxTextureSize && options.maxTextureSize < maxSize) maxSize = options.maxTextureSize;
  if (options.maxLayers && options.maxLayers < maxLayers) maxLayers = options.maxLayers;
  if (width > maxSize)
    return limitError(sizeName, maxSize, "slices " + std::to_string(width) + " texels wide", field, layout, maxSize,
                      maxLayers);
  if (layout.sliceHeight > maxSize)
    return limitError(sizeName, maxSize, "slices " + std::to_string(layout.sliceHeight) + " texels high", field,
                      layout, maxSize, maxLayers);
  if (layout.sliceCount > maxLayers)
    return limitError(layerName, maxLayers, std::to_string(layout.sliceCount) + " slices", field, layout, maxSize,
                      maxLayers);
  return {};
}


Result<MapsFormat> mapsFormat(const File& file, uint32_t width) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  MapsFormat f;
  f.width = width;
  switch (field.distanceEncoding) {
    case DistanceEncoding::kUnorm8Diameter:
    case DistanceEncoding::kUnorm8Chord:
    case DistanceEncoding::kBit1: break;
    case DistanceEncoding::kUnorm16Diameter: f.internalFormat = GL_R16UI; f.type = GL_UNSIGNED_SHORT; break;
    case DistanceEncoding::kBc4Diameter: f.internalFormat = GL_COMPRESSED_RED_RGTC1; break;
    default: return makeError(Code::kUnsupported, "vff_gl cannot upload this distance encoding");
  }
  const bool bc4 = field.distanceEncoding == DistanceEncoding::kBc4Diameter;
  if (bc4 && (layout.target == LayoutTarget::kTexture3D || layout.gutter != 0))  // the file's rules 7001 and 7002
    return makeError(Code::kUnsupported, "bc4-diameter slices must be a 2D array without gutters");
  f.sliceBytes = file.sliceBytes(Plane::kDistance);
  const uint64_t texelBytes = f.type == GL_UNSIGNED_SHORT ? 2 : 1;
  if (f.sliceBytes != (bc4 ? uint64_t(width) * layout.sliceHeight / 2 : uint64_t(width) * layout.sliceHeight * texelBytes))
    return makeError(Code::kUnsupported, "unexpected slice size " + std::to_string(f.sliceBytes) + " bytes");
  return f;
}

// A texture of one level, nearest filtering (integer textures allow nothing else), immutable storage.
Status makeTexture(GLenum target, GLenum internalFormat, uint32_t width, uint32_t height, uint32_t layers,
                   GLuint* texture, const char* what) {
  glGenTextures(1, texture);
  glBindTexture(target, *texture);
  glTexParameteri(target, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(target, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexParameteri(target, GL_TEXTURE_BASE_LEVEL, 0);
  glTexParameteri(target, GL_TEXTURE_MAX_LEVEL, 0);
  glTexStorage3D(target, 1, internalFormat, GLsizei(width), GLsizei(height), GLsizei(layers));
  return checkGl(what);
}

// Tightly packed client memory for the uploads.
void setUnpackDefaults() {
  glBindBuffer(GL_PIXEL_UNPACK_BUFFER, 0);
  glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
  glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
  glPixelStorei(GL_UNPACK_IMAGE_HEIGHT, 0);
  glPixelStorei(GL_UNPACK_SKIP_PIXELS, 0);
  glPixelStorei(GL_UNPACK_SKIP_ROWS, 0);
  glPixelStorei(GL_UNPACK_SKIP_IMAGES, 0);
}

// The distance plane into the bound texture; adds the bytes uploaded to *bytes.
Status uploadDistance(const File& file, GLenum target, const MapsFormat& f, uint32_t firstLayer, uint64_t* bytes) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  const GLsizei m = GLsizei(field.mapResolution);
  if (field.distanceEncoding == DistanceEncoding::kBc4Diameter) {
    // Each map's blocks are its compressed M x M image: upload them as stored. Unused tiles stay
    // undefined; no lookup reads them.
    for (uint32_t k = 0; k < field.mapCount; ++k) {
      auto map = file.mapData(Plane::kDistance, k);
      if (!map) return map.error();
      const TilePlacement at = placeMap(layout, k);
      glCompressedTexSubImage3D(target, 0, GLint(at.x), GLint(at.y), GLint(firstLayer + at.slice), m, m, 1,
                                GL_COMPRESSED_RED_RGTC1, GLsizei(map->size()), map->data());
    }
    if (Status st = checkGl("glCompressedTexSubImage3D (maps)"); !st) return st.error();
    *bytes += f.sliceBytes * layout.sliceCount;
  } else if (layout.gutter == 0 && field.distanceEncoding != DistanceEncoding::kBit1) {
    // Without gutters every map is one rectangle of its slice: upload it straight from the file's
    // bytes (the mapped file itself for stored blocks), with no slice composed on the CPU. Tiles
    // past the last map stay undefined; no lookup reads them.
    for (uint32_t k = 0; k < field.mapCount; ++k) {
      auto map = file.mapData(Plane::kDistance, k);
      if (!map) return map.error();
      const TilePlacement at = placeMap(layout, k);
      glTexSubImage3D(target, 0, GLint(at.x), GLint(at.y), GLint(firstLayer + at.slice), m, m, 1, GL_RED_INTEGER, f.type,
                      map->data());
    }
    if (Status st = checkGl("glTexSubImage3D (maps)"); !st) return st.error();
    *bytes += f.sliceBytes * layout.sliceCount;
  } else {
    std::vector<uint8_t> slice(f.sliceBytes);
    for (uint32_t s = 0; s < layout.sliceCount; ++s) {
      if (Status st = file.readSlice(Plane::kDistance, s, slice); !st) return st.error();
      glTexSubImage3D(target, 0, 0, 0, GLint(firstLayer + s), GLsizei(f.width), GLsizei(layout.sliceHeight), 1, GL_RED_INTEGER,
                      f.type, slice.data());
      if (Status st = checkGl("glTexSubImage3D"); !st) return st.error();
      *bytes += f.sliceBytes;
    }
  }
  return {};
}

Status checkNormals(const File& file) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  if (field.normalEncoding != NormalEncoding::kOctSnorm16)
    return makeError(Code::kUnsupported, "vff_gl cannot upload this normal encoding");
  const uint64_t normalBytes = file.sliceBytes(Plane::kNormal);
  if (normalBytes != uint64_t(layout.sliceWidth) * layout.sliceHeight * 4)
    return makeError(Code::kUnsupported, "unexpected normal slice size " + std::to_string(normalBytes) + " bytes");
  return {};
}

Status uploadNormals(const File& file, GLenum target, uint32_t firstLayer, uint64_t* bytes) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  if (Status s = checkNormals(file); !s) return s;
  const uint64_t normalBytes = file.sliceBytes(Plane::kNormal);
  if (layout.gutter == 0) {
    const GLsizei m = GLsizei(field.mapResolution);
    for (uint32_t k = 0; k < field.mapCount; ++k) {  // straight from the file, as the distances
      auto map = file.mapData(Plane::kNormal, k);
      if (!map) return map.error();
      const TilePlacement at = placeMap(layout, k);
      glTexSubImage3D(target, 0, GLint(at.x), GLint(at.y), GLint(firstLayer + at.slice), m, m, 1, GL_RG_INTEGER, GL_SHORT,
                      map->data());
    }
    if (Status st = checkGl("glTexSubImage3D (normal maps)"); !st) return st.error();
    *bytes += normalBytes * layout.sliceCount;
    return {};
  }
  std::vector<uint8_t> nslice(normalBytes);
  for (uint32_t s = 0; s < layout.sliceCount; ++s) {
    if (Status st = file.readSlice(Plane::kNormal, s, nslice); !st) return st.error();
    glTexSubImage3D(target, 0, 0, 0, GLint(firstLayer + s), GLsizei(layout.sliceWidth), GLsizei(layout.sliceHeight), 1,
                    GL_RG_INTEGER, GL_SHORT, nslice.data());
    if (Status st = checkGl("glTexSubImage3D (normals)"); !st) return st.error();
    *bytes += normalBytes;
  }
  return {};
}

// A new buffer object bound to `target`, holding `size` bytes from `data`.
Status makeBuffer(GLenum target, const void* data, size_t size, GLuint* buffer, const char* what) {
  glGenBuffers(1, buffer);
  glBindBuffer(target, *buffer);
  glBufferData(target, GLsizeiptr(size), data, GL_STATIC_DRAW);
  return checkGl(what);
}

}  // namespace detail

using namespace detail;

void GlName::reset() noexcept {
  if (!name_) return;
  if (kind_ == Kind::kTexture) glDeleteTextures(1, &name_);
  else glDeleteBuffers(1, &name_);
  name_ = 0;
}

void GpuField::bind(const Bindings& b) const noexcept {
  glBindBufferBase(GL_UNIFORM_BUFFER, b.field, s_.fieldBuffer.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b.positions, s_.positionsBuffer.get());
  if (s_.normalsTexture) {
    glActiveTexture(GL_TEXTURE0 + b.normals);
    glBindTexture(s_.mapsTarget ? s_.mapsTarget : GL_TEXTURE_2D_ARRAY, s_.normalsTexture.get());
  }
  glActiveTexture(GL_TEXTURE0 + b.maps);
  glBindTexture(s_.mapsTarget ? s_.mapsTarget : GL_TEXTURE_2D_ARRAY, s_.mapsTexture.get());
}

Result<GpuField> loadField(const File& file, const LoadOptions& options) {
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  auto block = makeFieldBlock(field, layout);
  if (!block) return block.error();
  if (Status s = checkVersion(); !s) return s.error();
  const bool bit1 = field.distanceEncoding == DistanceEncoding::kBit1;
  const uint32_t width = bit1 ? layout.sliceWidth / 8 : layout.sliceWidth;
  if (Status s = checkLimits(field, layout, options, width); !s) return s.error();
  auto format = mapsFormat(file, width);
  if (!format) return format.error();

  SavedState saved;
  GpuField out;
  out.s_.block = *block;
  out.s_.mapsTarget = layout.target == LayoutTarget::kTexture3D ? GL_TEXTURE_3D : GL_TEXTURE_2D_ARRAY;
  if (Status s = makeTexture(out.s_.mapsTarget, format->internalFormat, width, layout.sliceHeight, layout.sliceCount,
                             out.s_.mapsTexture.out(), "glTexStorage3D");
      !s)
    return s.error();
  setUnpackDefaults();
  if (Status s = uploadDistance(file, out.s_.mapsTarget, *format, 0, &out.s_.textureBytes); !s) return s.error();
  if (file.hasNormals()) {
    if (Status s = checkNormals(file); !s) return s.error();
    if (Status s = makeTexture(out.s_.mapsTarget, GL_RG16I, layout.sliceWidth, layout.sliceHeight, layout.sliceCount,
                               out.s_.normalsTexture.out(), "glTexStorage3D (normals)");
        !s)
      return s.error();
    if (Status s = uploadNormals(file, out.s_.mapsTarget, 0, &out.s_.textureBytes); !s) return s.error();
  }
  // The field block (with where the neighbour lists start in the positions buffer).
  if (Status s = makeBuffer(GL_UNIFORM_BUFFER, &out.s_.block, sizeof(FieldBlock), out.s_.fieldBuffer.out(),
                            "uploading the field block");
      !s)
    return s.error();
  // The sample positions, the unorm8-chord decode steps and the neighbour lists.
  auto positions = makePositionsBuffer(field);
  if (!positions) return positions.error();
  if (Status s = makeBuffer(GL_SHADER_STORAGE_BUFFER, positions->data(), positions->size() * sizeof(float),
                            out.s_.positionsBuffer.out(), "uploading the sample positions");
      !s)
    return s.error();
  return out;
}

}  // namespace vff::gl
