// sdf_gl.cpp - uploading an SdfField's NanoVDB grid and its trace block (sdf_gl.h).
#include "sdf_gl.h"

#include <GL/glcorearb.h>

#include <cstdio>
#include <span>
#include <string>
#include <utility>

namespace vffx::gl {

namespace {

// The error `e` (the first glGetError reported) as a value; drains the rest.
vff::Error glError(const char* what, GLenum e) {
  for (int i = 0; i < 16 && glGetError() != GL_NO_ERROR; ++i) {
  }
  char code[16];
  std::snprintf(code, sizeof code, "0x%04x", unsigned(e));
  return vff::makeError(e == GL_OUT_OF_MEMORY ? vff::Code::kOutOfMemory : vff::Code::kBadState,
                        std::string("sdf upload: ") + what + ": GL error " + code);
}

}  // namespace

vff::Status GpuSdf::setTraceOptions(const SdfTraceOptions& options) {
  const SdfBlock b = withTraceOptions(s_.block, options);
  glGetError();
  GLint old = 0;
  glGetIntegerv(GL_UNIFORM_BUFFER_BINDING, &old);
  glBindBuffer(GL_UNIFORM_BUFFER, s_.blockBuffer.get());
  glBufferSubData(GL_UNIFORM_BUFFER, 0, GLsizeiptr(sizeof b), &b);
  glBindBuffer(GL_UNIFORM_BUFFER, GLuint(old));
  if (const GLenum e = glGetError(); e != GL_NO_ERROR) return glError("glBufferSubData", e);
  s_.block = b;
  return {};
}

void GpuSdf::bind(const SdfBindings& bindings) const noexcept {
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, bindings.grid, s_.grid.get());
  glBindBufferBase(GL_UNIFORM_BUFFER, bindings.block, s_.blockBuffer.get());
}

vff::Result<GpuSdf> uploadSdf(const SdfField& sdf, const SdfTraceOptions& options) {
  glGetError();  // a caller's stale error is not ours
  GLint major = 0, minor = 0;
  glGetIntegerv(GL_MAJOR_VERSION, &major);
  glGetIntegerv(GL_MINOR_VERSION, &minor);
  if (glGetError() != GL_NO_ERROR || major == 0)
    return vff::makeError(vff::Code::kBadState, "sdf upload: no OpenGL context is current");
  if (major < 4 || (major == 4 && minor < 3))
    return vff::makeError(vff::Code::kUnsupported, "sdf upload: the GL context is version " + std::to_string(major) +
                                                       "." + std::to_string(minor) + ", 4.3 is needed");
  const std::span<const uint8_t> bytes = sdf.gridBuffer();
  GLint64 maxBlock = 0;
  glGetInteger64v(GL_MAX_SHADER_STORAGE_BLOCK_SIZE, &maxBlock);
  if (bytes.size() > uint64_t(maxBlock) || bytes.size() >= (uint64_t(1) << 32))
    return vff::makeError(vff::Code::kUnsupported, "sdf upload: the grid has " + std::to_string(bytes.size()) +
                                                       " bytes, more than GL_MAX_SHADER_STORAGE_BLOCK_SIZE (" +
                                                       std::to_string(maxBlock) +
                                                       ") or PNanoVDB's 32-bit addresses allow");
  GpuSdf g;
  g.s_.block = makeSdfBlock(sdf, options);
  GLint oldSsbo = 0, oldUbo = 0;
  glGetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &oldSsbo);
  glGetIntegerv(GL_UNIFORM_BUFFER_BINDING, &oldUbo);
  glGenBuffers(1, g.s_.grid.out());
  glGenBuffers(1, g.s_.blockBuffer.out());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, g.s_.grid.get());
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(bytes.size()), bytes.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_UNIFORM_BUFFER, g.s_.blockBuffer.get());
  glBufferData(GL_UNIFORM_BUFFER, GLsizeiptr(sizeof(SdfBlock)), &g.s_.block, GL_STATIC_DRAW);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, GLuint(oldSsbo));
  glBindBuffer(GL_UNIFORM_BUFFER, GLuint(oldUbo));
  if (const GLenum e = glGetError(); e != GL_NO_ERROR) return glError("glBufferData", e);
  g.s_.gridBytes = bytes.size();
  return g;
}

}  // namespace vffx::gl
