// gl_upload.h - the GL steps of loadField (loader.cpp), shared with the scene loader
// (scene_loader.cpp): error checks, the context's limits, saved state, textures, uploads.
// Private to vff_gl.
#pragma once

#include <GL/glcorearb.h>

#include <cstddef>
#include <cstdint>

#include "vff/gl/loader.h"

namespace vff::gl::detail {

// The first pending GL error as a vff::Error (kOutOfMemory or kBadState), after draining the queue.
Status checkGl(const char* what);
uint32_t getInt(GLenum name);

// Restores the GL state a loader touches (unpack state and buffer, bound textures and buffers).
struct SavedState {
  GLint unpackAlignment = 4, unpackBuffer = 0, unpackRowLength = 0, unpackImageHeight = 0;
  GLint unpackSkipPixels = 0, unpackSkipRows = 0, unpackSkipImages = 0;
  GLint texture2DArray = 0, texture3D = 0, uniformBuffer = 0, storageBuffer = 0;
  SavedState();
  ~SavedState();
  SavedState(const SavedState&) = delete;
  SavedState& operator=(const SavedState&) = delete;
};

// GL 4.3 or kUnsupported; kBadState without a current context.
Status checkVersion();
// The layout against the context's limits, tightened by the caller's. `width`: the distance
// texture's width in texels.
Status checkLimits(const FieldDesc& field, const LayoutDesc& layout, const LoadOptions& options, uint32_t width);

// The distance texture's format, checked against the file's slices.
struct MapsFormat {
  GLenum internalFormat = GL_R8UI, type = GL_UNSIGNED_BYTE;
  uint32_t width = 0;        // texels (bit1: bytes) per slice row
  uint64_t sliceBytes = 0;   // File::sliceBytes(Plane::kDistance)
};
Result<MapsFormat> mapsFormat(const File& file, uint32_t width);

// A texture of one level, nearest filtering, immutable storage, bound to `target`.
Status makeTexture(GLenum target, GLenum internalFormat, uint32_t width, uint32_t height, uint32_t layers,
                   GLuint* texture, const char* what);
// Tightly packed client memory for the uploads.
void setUnpackDefaults();
// The distance plane into the bound texture from slice firstLayer on; adds the bytes to *bytes.
Status uploadDistance(const File& file, GLenum target, const MapsFormat& f, uint32_t firstLayer, uint64_t* bytes);
// The normal plane can be uploaded (oct-snorm16, slices of the expected size).
Status checkNormals(const File& file);
// The normal plane (GL_RG16I) into the bound texture from slice firstLayer on; adds the bytes.
Status uploadNormals(const File& file, GLenum target, uint32_t firstLayer, uint64_t* bytes);
// A new buffer object bound to `target`, holding `size` bytes from `data`.
Status makeBuffer(GLenum target, const void* data, size_t size, GLuint* buffer, const char* what);

}  // namespace vff::gl::detail
