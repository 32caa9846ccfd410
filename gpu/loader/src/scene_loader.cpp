// scene_loader.cpp - the GL calls of the scene loader (vff/gl/scene_loader.h): loadScene uploads
// the fields once into shared textures and buffers (laid out by planScene), GpuScene::update the
// instances and the hierarchy per frame.
#include <GL/glcorearb.h>

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "gl_upload.h"
#include "vff/gl/scene_loader.h"

namespace vff::gl {

using namespace detail;

namespace {

// Replaces the contents of *buffer (bound to GL_SHADER_STORAGE_BUFFER), growing it when needed.
Status fillBuffer(GlName* buffer, uint64_t* allocated, const void* data, size_t size, const char* what) {
  if (!*buffer) glGenBuffers(1, buffer->out());
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, buffer->get());
  const size_t want = std::max<size_t>(size, 16);
  if (want > *allocated) {
    glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(want), nullptr, GL_DYNAMIC_DRAW);
    *allocated = want;
  }
  if (size) glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, GLsizeiptr(size), data);
  return checkGl(what);
}

}  // namespace

void GpuScene::bind(const SceneBindings& b) const noexcept {
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b.positions, s_.positions.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b.fields, s_.fields.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b.instances, s_.instances.get());
  glBindBufferBase(GL_SHADER_STORAGE_BUFFER, b.nodes, s_.nodes.get());
  if (s_.normals) {
    glActiveTexture(GL_TEXTURE0 + b.normals);
    glBindTexture(GL_TEXTURE_2D_ARRAY, s_.normals.get());
  }
  glActiveTexture(GL_TEXTURE0 + b.maps);
  glBindTexture(GL_TEXTURE_2D_ARRAY, s_.maps.get());
}

Status GpuScene::update(const Scene& scene) {
  auto h = scene.hierarchy();
  if (!h) return std::move(h).error();
  auto inst = makeSceneInstances(scene, *h, s_.queries);
  if (!inst) return std::move(inst).error();
  auto nodes = makeSceneNodes(*h, uint32_t(inst->size()));
  if (!nodes) return std::move(nodes).error();
  glGetError();  // a caller's stale error is not ours
  GLint saved = 0;
  glGetIntegerv(GL_SHADER_STORAGE_BUFFER_BINDING, &saved);
  Status s = fillBuffer(&s_.instances, &s_.instancesSize, inst->data(), inst->size() * sizeof(SceneInstanceBlock),
                        "uploading the scene's instances");
  if (s) s = fillBuffer(&s_.nodes, &s_.nodesSize, nodes->data(), nodes->size(), "uploading the scene's hierarchy");
  glBindBuffer(GL_SHADER_STORAGE_BUFFER, GLuint(saved));
  if (s) s_.instanceCount = uint32_t(inst->size());
  return s;
}

Result<GpuScene> loadScene(std::span<const SceneField> fields, const LoadOptions& options) {
  if (fields.empty()) return makeError(Code::kInvalidArgument, "scene: no fields");
  std::vector<FieldDesc> descs;
  std::vector<LayoutDesc> layouts;
  GpuScene out;
  for (size_t f = 0; f < fields.size(); ++f) {
    if (!fields[f].file || !fields[f].query)
      return makeError(Code::kInvalidArgument, "scene field " + std::to_string(f) + ": null file or query");
    for (size_t g = 0; g < f; ++g)
      if (fields[g].query == fields[f].query)
        return makeError(Code::kInvalidArgument, "scene field " + std::to_string(f) + ": the same query as field " +
                                                     std::to_string(g));
    descs.push_back(fields[f].file->field());
    layouts.push_back(fields[f].file->layout());
    out.s_.queries.push_back(fields[f].query);
  }
  auto plan = planScene(descs, layouts);
  if (!plan) return plan.error();
  if (Status s = checkVersion(); !s) return s.error();
  // Each field against the context's limits, then the shared texture's layer count.
  for (size_t f = 0; f < fields.size(); ++f) {
    const uint32_t width = descs[f].distanceEncoding == DistanceEncoding::kBit1 ? layouts[f].sliceWidth / 8
                                                                                : layouts[f].sliceWidth;
    if (Status s = checkLimits(descs[f], layouts[f], options, width); !s) return s.error();
  }
  uint32_t maxLayers = getInt(GL_MAX_ARRAY_TEXTURE_LAYERS);
  if (options.maxLayers && options.maxLayers < maxLayers) maxLayers = options.maxLayers;
  if (plan->mapsLayers > maxLayers)
    return makeError(Code::kUnsupported, "the scene's fields need " + std::to_string(plan->mapsLayers) +
                                             " slices in one texture; GL_MAX_ARRAY_TEXTURE_LAYERS is " +
                                             std::to_string(maxLayers));
  out.s_.plan = std::move(*plan);
  const ScenePlan& p = out.s_.plan;

  SavedState saved;
  if (Status s = makeTexture(GL_TEXTURE_2D_ARRAY, p.wideTexels ? GL_R16UI : GL_R8UI, p.mapsWidth, p.mapsHeight,
                             p.mapsLayers, out.s_.maps.out(), "glTexStorage3D (scene maps)");
      !s)
    return s.error();
  setUnpackDefaults();
  for (size_t f = 0; f < fields.size(); ++f) {
    const uint32_t width = descs[f].distanceEncoding == DistanceEncoding::kBit1 ? layouts[f].sliceWidth / 8
                                                                                : layouts[f].sliceWidth;
    auto format = mapsFormat(*fields[f].file, width);
    if (!format) return format.error();
    if (Status s = uploadDistance(*fields[f].file, GL_TEXTURE_2D_ARRAY, *format, p.fields[f].mapsLayer,
                                  &out.s_.textureBytes);
        !s)
      return s.error();
  }
  if (p.normalsLayers > 0) {
    if (Status s = makeTexture(GL_TEXTURE_2D_ARRAY, GL_RG16I, p.normalsWidth, p.normalsHeight, p.normalsLayers,
                               out.s_.normals.out(), "glTexStorage3D (scene normals)");
        !s)
      return s.error();
    for (size_t f = 0; f < fields.size(); ++f) {
      if (!fields[f].file->hasNormals()) continue;
      if (Status s = uploadNormals(*fields[f].file, GL_TEXTURE_2D_ARRAY, p.fields[f].normalsLayer, &out.s_.textureBytes);
          !s)
        return s.error();
    }
  }
  if (Status s = makeBuffer(GL_SHADER_STORAGE_BUFFER, p.positions.data(), p.positions.size() * sizeof(float),
                            out.s_.positions.out(), "uploading the scene's sample positions");
      !s)
    return s.error();
  if (Status s = makeBuffer(GL_SHADER_STORAGE_BUFFER, p.fields.data(), p.fields.size() * sizeof(SceneFieldBlock),
                            out.s_.fields.out(), "uploading the scene's field table");
      !s)
    return s.error();
  return out;
}

}  // namespace vff::gl
