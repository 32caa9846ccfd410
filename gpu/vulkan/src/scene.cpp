// The Vulkan scene loader (vff/vk/scene.h): every field's slices into shared images, positions and
// the field table into buffers, laid out by vff::gl::planScene; GpuScene::update writes the
// instances (vff::gl::makeSceneInstances) and the hierarchy (makeSceneNodes) per frame.
#include "vff/vk/scene.h"

#include <algorithm>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

#include "compute.h"
#include "upload.h"

namespace vff::vk {

using detail::Buffer;
using detail::Image;

struct GpuScene::State {
  VkDevice device = VK_NULL_HANDLE;
  gl::ScenePlan plan;
  std::vector<const FieldQuery*> queries;
  Image maps, normals;
  Buffer positions, fields, instances, nodes;
  VkSampler sampler = VK_NULL_HANDLE;
  uint32_t instanceCount = 0;
  uint64_t textureBytes = 0;

  ~State() {
    if (sampler) vkDestroySampler(device, sampler, nullptr);
  }
};

GpuScene::GpuScene() = default;
GpuScene::GpuScene(GpuScene&&) noexcept = default;
GpuScene& GpuScene::operator=(GpuScene&&) noexcept = default;
GpuScene::~GpuScene() = default;

const gl::ScenePlan& GpuScene::plan() const noexcept {
  return s_->plan;
}
uint32_t GpuScene::instanceCount() const noexcept {
  return s_->instanceCount;
}
uint64_t GpuScene::textureBytes() const noexcept {
  return s_->textureBytes;
}

void GpuScene::write(VkDescriptorSet set) const noexcept {
  const State& s = *s_;
  detail::writeImage(s.device, set, kSceneMapsBinding, s.sampler, s.maps.view);
  detail::writeBuffer(s.device, set, kScenePositionsBinding, s.positions.buffer);
  detail::writeImage(s.device, set, kSceneNormalsBinding, s.sampler, s.normals.view);
  detail::writeBuffer(s.device, set, kSceneFieldsBinding, s.fields.buffer);
  detail::writeBuffer(s.device, set, kSceneInstancesBinding, s.instances.buffer);
  detail::writeBuffer(s.device, set, kSceneNodesBinding, s.nodes.buffer);
}

namespace {

// Replaces the contents of *buffer, growing it when needed (a storage buffer is never empty: an
// empty scene still binds one).
Status fillBuffer(const Context& ctx, Buffer* buffer, const void* data, size_t size) {
  const size_t want = std::max<size_t>(size, 16);
  if (!buffer->buffer || buffer->size < want) {
    auto b = detail::makeHostBuffer(ctx, want, VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
    if (!b) return b.error();
    *buffer = std::move(*b);
  }
  std::memset(buffer->mapped, 0, buffer->size);
  if (size) std::memcpy(buffer->mapped, data, size);
  return {};
}

uint32_t mapsWidth(const File& file) {
  const LayoutDesc& layout = file.layout();
  return file.field().distanceEncoding == DistanceEncoding::kBit1 ? layout.sliceWidth / 8 : layout.sliceWidth;
}

// The distance slices of every field into one 2D array, as loadField copies a single field's.
Status loadMaps(const Context& ctx, std::span<const gl::SceneField> fields, GpuScene::State& s) {
  const gl::ScenePlan& p = s.plan;
  const VkFormat format = p.wideTexels ? VK_FORMAT_R16_UINT : VK_FORMAT_R8_UINT;
  detail::PlaneUpload upload;
  for (size_t f = 0; f < fields.size(); ++f) {
    const File& file = *fields[f].file;
    auto fieldFormat = detail::mapsFormat(ctx, file, mapsWidth(file));
    if (!fieldFormat) return fieldFormat.error();
    if (*fieldFormat != format)
      return makeError(Code::kUnsupported, "scene field " + std::to_string(f) + ": another texel format");
    const bool perMap = file.layout().gutter == 0 && file.field().distanceEncoding != DistanceEncoding::kBit1;
    if (Status st =
            detail::appendPlane(file, Plane::kDistance, perMap, mapsWidth(file), false, p.fields[f].mapsLayer, upload);
        !st)
      return st;
    s.textureBytes += file.sliceBytes(Plane::kDistance) * file.layout().sliceCount;
  }
  auto maps = detail::makeImage(ctx, {format, p.mapsWidth, p.mapsHeight, p.mapsLayers, false});
  if (!maps) return maps.error();
  s.maps = std::move(*maps);
  return detail::uploadImage(ctx, s.maps, upload);
}

// The normal slices of the fields that have them (or the 1 x 1 x 1 placeholder).
Status loadNormals(const Context& ctx, std::span<const gl::SceneField> fields, GpuScene::State& s) {
  const gl::ScenePlan& p = s.plan;
  detail::ImageDesc d{VK_FORMAT_R16G16_SINT, 1, 1, 1, false};
  detail::PlaneUpload upload;
  if (p.normalsLayers > 0) {
    d = {VK_FORMAT_R16G16_SINT, p.normalsWidth, p.normalsHeight, p.normalsLayers, false};
    for (size_t f = 0; f < fields.size(); ++f) {
      const File& file = *fields[f].file;
      if (!file.hasNormals()) continue;
      const LayoutDesc& layout = file.layout();
      if (file.field().normalEncoding != NormalEncoding::kOctSnorm16 ||
          file.sliceBytes(Plane::kNormal) != uint64_t(layout.sliceWidth) * layout.sliceHeight * 4)
        return makeError(Code::kUnsupported, "scene field " + std::to_string(f) + ": vff_vk cannot upload its normals");
      if (Status st = detail::appendPlane(file, Plane::kNormal, layout.gutter == 0, layout.sliceWidth, false,
                                          p.fields[f].normalsLayer, upload);
          !st)
        return st;
      s.textureBytes += file.sliceBytes(Plane::kNormal) * layout.sliceCount;
    }
  }
  auto image = detail::makeImage(ctx, d);
  if (!image) return image.error();
  s.normals = std::move(*image);
  return detail::uploadImage(ctx, s.normals, upload);
}

// The shared images against the device's limits (each field's own slices are checked by
// checkLimits; together they are one array).
Status checkSceneLimits(const Context& ctx, const gl::ScenePlan& p) {
  const VkPhysicalDeviceLimits& l = ctx.properties().limits;
  if (p.mapsLayers > l.maxImageArrayLayers || p.normalsLayers > l.maxImageArrayLayers)
    return makeError(Code::kUnsupported, "the scene's fields need " + std::to_string(p.mapsLayers) +
                                             " slices in one image; maxImageArrayLayers is " +
                                             std::to_string(l.maxImageArrayLayers));
  return {};
}

}  // namespace

Status GpuScene::update(const Context& ctx, const Scene& scene) {
  auto h = scene.hierarchy();
  if (!h) return std::move(h).error();
  auto inst = gl::makeSceneInstances(scene, *h, s_->queries);
  if (!inst) return std::move(inst).error();
  auto nodes = gl::makeSceneNodes(*h, uint32_t(inst->size()));
  if (!nodes) return std::move(nodes).error();
  if (Status st = fillBuffer(ctx, &s_->instances, inst->data(), inst->size() * sizeof(gl::SceneInstanceBlock)); !st)
    return st;
  if (Status st = fillBuffer(ctx, &s_->nodes, nodes->data(), nodes->size()); !st) return st;
  s_->instanceCount = uint32_t(inst->size());
  return {};
}

Result<GpuScene> loadScene(const Context& ctx, std::span<const gl::SceneField> fields) {
  if (fields.empty()) return makeError(Code::kInvalidArgument, "scene: no fields");
  std::vector<FieldDesc> descs;
  std::vector<LayoutDesc> layouts;
  GpuScene out;
  out.s_ = std::make_unique<GpuScene::State>();
  GpuScene::State& s = *out.s_;
  s.device = ctx.device();
  for (size_t f = 0; f < fields.size(); ++f) {
    if (!fields[f].file || !fields[f].query)
      return makeError(Code::kInvalidArgument, "scene field " + std::to_string(f) + ": null file or query");
    for (size_t g = 0; g < f; ++g)
      if (fields[g].query == fields[f].query)
        return makeError(Code::kInvalidArgument,
                         "scene field " + std::to_string(f) + ": the same query as field " + std::to_string(g));
    descs.push_back(fields[f].file->field());
    layouts.push_back(fields[f].file->layout());
    s.queries.push_back(fields[f].query);
    if (Status st = detail::checkLimits(ctx, layouts.back(), mapsWidth(*fields[f].file)); !st) return st.error();
  }
  auto plan = gl::planScene(descs, layouts);
  if (!plan) return plan.error();
  s.plan = std::move(*plan);
  if (Status st = checkSceneLimits(ctx, s.plan); !st) return st.error();
  if (Status st = loadMaps(ctx, fields, s); !st) return st.error();
  if (Status st = loadNormals(ctx, fields, s); !st) return st.error();
  auto positions = detail::makeFilledBuffer(ctx, s.plan.positions.data(), s.plan.positions.size() * sizeof(float),
                                            VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!positions) return positions.error();
  s.positions = std::move(*positions);
  auto table = detail::makeFilledBuffer(ctx, s.plan.fields.data(), s.plan.fields.size() * sizeof(gl::SceneFieldBlock),
                                        VK_BUFFER_USAGE_STORAGE_BUFFER_BIT);
  if (!table) return table.error();
  s.fields = std::move(*table);
  if (Status st = detail::makeSampler(ctx, &s.sampler); !st) return st.error();
  // An empty scene until the first update: the walk then misses every ray.
  if (Status st = out.update(ctx, Scene{}); !st) return st.error();
  return out;
}

}  // namespace vff::vk
