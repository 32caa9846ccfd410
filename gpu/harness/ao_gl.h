// ao_gl.h - the ground-AO render of ao_scene.h on the GPU, as the benchmark and the GPU tests run
// it: the scene's buffers at the AO shader's bindings, and one frame of a compute program that
// has kAoShader's interface (a single field's, or a vff::gl::GpuScene's). Header-only; needs a
// current GL 4.3 context and the GL entry points declared (GL_GLEXT_PROTOTYPES, as every GL target
// of gpu/ and tests/gpu compiles with).
#pragma once

#include <GL/glcorearb.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <vector>

#include "ao_scene.h"
#include "egl_context.h"
#include "vff/gl/scene_loader.h"

namespace vff::harness {

// The AO scene's G-buffer and directions, and its image, in buffers bound to the shader storage
// bindings 5, 6 and 7 (kAoShader's). Deletes them when it goes.
class AoBuffers {
 public:
  explicit AoBuffers(const AoScene& s) {
    glGenBuffers(3, buf_);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buf_[0]);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(s.gbuffer.size() * 4), s.gbuffer.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buf_[1]);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(s.directions.size() * 4), s.directions.data(), GL_STATIC_DRAW);
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, buf_[2]);
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(size_t(s.size) * size_t(s.size) * 4), nullptr, GL_STREAM_READ);
    bind();
  }
  ~AoBuffers() { glDeleteBuffers(3, buf_); }
  AoBuffers(const AoBuffers&) = delete;
  AoBuffers& operator=(const AoBuffers&) = delete;
  // Binds them again (after something else used 5, 6 or 7).
  void bind() const {
    for (int b = 0; b < 3; ++b) glBindBufferBase(GL_SHADER_STORAGE_BUFFER, GLuint(5 + b), buf_[b]);
  }
  GLuint image() const { return buf_[2]; }

 private:
  GLuint buf_[3] = {0, 0, 0};
};

// One frame of the AO program in use (glUseProgram) at `spp` rays per pixel, `mode` its uniform 2
// (the field's: 1 interpolated; a distance field's: 1 the cone estimate): a warm-up dispatch
// (drivers such as llvmpipe compile the shader at its first use), then bands of 64 rows (single
// dispatches stay short on slow drivers). The image comes back in *image; returns the seconds of
// the bands, from the first dispatch to glFinish.
inline double renderAo(const AoScene& s, const AoBuffers& b, int spp, int mode, std::vector<float>* image) {
  const int size = s.size;
  glUniform1i(0, size);
  glUniform1i(1, spp);
  glUniform1i(2, mode);
  glUniform1f(3, s.eps);
  glUniform1f(4, s.tmax);
  glUniform1i(5, 0);
  glDispatchCompute(1, 1, 1);
  glFinish();
  const auto t0 = std::chrono::steady_clock::now();
  for (int row = 0; row < size; row += 64) {
    glUniform1i(5, row);
    glDispatchCompute(GLuint(size / 8), GLuint(std::min(64, size - row) / 8), 1);
  }
  glFinish();
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  image->assign(size_t(size) * size_t(size), 0.0f);
  glMemoryBarrier(GL_BUFFER_UPDATE_BARRIER_BIT);
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, b.image());
  glGetBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(image->size() * 4), image->data());
  return seconds;
}

// The ground AO of a scene (vff_scene.glsl): the program's source, kAoShader asking the scene's
// visibility and occlusion, with the scene's instances and nodes at storage bindings 10 and 11 (5, 6
// and 7 are AoBuffers'); and the scene and the AO buffers bound at those, the program in use.
inline std::string sceneAoShaderSource() {
  return "#version 430\n#define VFF_SCENE_INSTANCES_BINDING 10\n#define VFF_SCENE_NODES_BINDING 11\n" +
         gl::sceneShaderSource(readGlsl("vff_scene.glsl"), readGlsl("vff_query.glsl")) +
         "#define AO_VISIBILITY(o, d) vffSceneVisibility(o, d, 0.0, aoTmax, VFF_OFF_OBJECT, true)\n"
         "#define AO_OCCLUDED(o, d) vffSceneOccluded(o, d, 0.0, aoTmax, VFF_OFF_OBJECT, false)\n" +
         kAoShader;
}
inline void useSceneAo(const gl::GpuScene& scene, const AoBuffers& buffers, GLuint program) {
  gl::SceneBindings b;
  b.instances = 10;
  b.nodes = 11;
  scene.bind(b);
  buffers.bind();
  glUseProgram(program);
}

}  // namespace vff::harness
