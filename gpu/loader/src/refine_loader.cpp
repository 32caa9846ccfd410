// The GL calls of loadRefinement and GpuRefinement (vff/gl/refine_loader.h). What they upload is
// computed without GL in refine_buffers.cpp.
#include "vff/gl/refine_loader.h"

#include <GL/glcorearb.h>

#include "gl_upload.h"

namespace vff::gl {

using namespace detail;

void GpuRefinement::bind(const RefinementBindings& b) const noexcept {
  glBindBufferBase(GL_UNIFORM_BUFFER, b.block, s_.blockBuffer.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b.unsure, s_.unsure.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b.vertices, s_.vertices.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b.bvh, s_.bvh.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b.triangles, s_.triangles.get());
}

Result<GpuRefinement> loadRefinement(const FieldDesc& field, const RefinementView& refinement) {
  auto buffers = makeRefinementBuffers(field, refinement);
  if (!buffers) return buffers.error();
  if (Status s = checkVersion(); !s) return s.error();
  SavedState saved;
  GpuRefinement out;
  out.s_.block = buffers->block;
  auto upload = [&](GLenum target, const void* data, size_t size, GlName* name, const char* what) {
    out.s_.bytes += size;
    return makeBuffer(target, data, size, name->out(), what);
  };
  if (Status s = upload(GL_UNIFORM_BUFFER, &out.s_.block, sizeof(RefineBlock), &out.s_.blockBuffer,
                        "uploading the refinement block");
      !s)
    return s.error();
  if (Status s = upload(GL_SHADER_STORAGE_BUFFER, buffers->unsure.data(), buffers->unsure.size() * 4, &out.s_.unsure,
                        "uploading the unsure bits");
      !s)
    return s.error();
  if (Status s = upload(GL_SHADER_STORAGE_BUFFER, buffers->vertices.data(), buffers->vertices.size() * 4,
                        &out.s_.vertices, "uploading the refinement's vertices");
      !s)
    return s.error();
  if (Status s = upload(GL_SHADER_STORAGE_BUFFER, buffers->nodes.data(), buffers->nodes.size() * 4, &out.s_.bvh,
                        "uploading the refinement's BVH");
      !s)
    return s.error();
  if (Status s = upload(GL_SHADER_STORAGE_BUFFER, buffers->triangles.data(), buffers->triangles.size() * 4,
                        &out.s_.triangles, "uploading the refinement's triangles");
      !s)
    return s.error();
  return out;
}

Result<GpuRefinement> loadRefinement(const File& file) { return loadRefinement(file.field(), file.refinement()); }

}  // namespace vff::gl
