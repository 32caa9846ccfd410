// dispatch.h - how the GPU tests run rays through a compute shader: the rays' array in one shader
// storage buffer, the answers' in another, the program in use (with its resources bound and its
// uniforms set by the caller) dispatched once over them in groups of 64, the answers read back.
// Needs GL_GLEXT_PROTOTYPES and a current context (egl_context.h).
#pragma once

#include <GL/glcorearb.h>

#include <span>
#include <vector>

namespace vff::test {

// `in` at storage binding inBinding; the answers, outPerRay Out values for each of `rays` rays, at
// outBinding.
template <class Out, class In>
std::vector<Out> dispatchRays(std::span<const In> in, size_t rays, size_t outPerRay, GLuint inBinding,
                              GLuint outBinding) {
  std::vector<Out> out(rays * outPerRay);
  GLuint bufs[2];
  glGenBuffers(2, bufs);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, bufs[0]);
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(in.size_bytes()), in.data(), GL_STATIC_DRAW);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, bufs[1]);
  glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(out.size() * sizeof(Out)), nullptr, GL_STREAM_READ);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, inBinding, bufs[0]);
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, outBinding, bufs[1]);
  glDispatchCompute(GLuint((rays + 63) / 64), 1, 1);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, bufs[1]);
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(out.size() * sizeof(Out)), out.data());
  glDeleteBuffers(2, bufs);
  return out;
}

}  // namespace vff::test
