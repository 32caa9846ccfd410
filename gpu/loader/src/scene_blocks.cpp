// scene_blocks.cpp - what the scene loader (vff/gl/scene_loader.h) uploads, computed without GL:
// the field table and shared positions (planScene), the instance table (makeSceneInstances), the
// nodes buffer (makeSceneNodes), and the scene shader's text (sceneShaderSource).
#include <algorithm>
#include <cstring>
#include <string>
#include <unordered_map>
#include <utility>

#include "vff/gl/scene_loader.h"

namespace vff::gl {

Result<ScenePlan> planScene(std::span<const FieldDesc> fields, std::span<const LayoutDesc> layouts) {
  if (fields.empty() || fields.size() != layouts.size())
    return makeError(Code::kInvalidArgument, "scene: needs one layout per field and at least one field");
  ScenePlan plan;
  for (size_t f = 0; f < fields.size(); ++f) {
    const FieldDesc& field = fields[f];
    const LayoutDesc& layout = layouts[f];
    const std::string which = "scene field " + std::to_string(f) + ": ";
    if (layout.target != LayoutTarget::kTexture2DArray)
      return makeError(Code::kUnsupported, which + "the scene loader takes 2D-array layouts only (vff-convert can repack)");
    if (field.distanceEncoding == DistanceEncoding::kBc4Diameter)
      return makeError(Code::kUnsupported, which + "bc4-diameter is not supported in a scene");
    const bool wide = field.distanceEncoding == DistanceEncoding::kUnorm16Diameter;
    if (f == 0) plan.wideTexels = wide;
    if (wide != plan.wideTexels)
      return makeError(Code::kUnsupported, which + "unorm16-diameter fields and 8-bit fields cannot share the maps "
                                                   "texture (convert them to one encoding)");
    auto block = makeFieldBlock(field, layout);
    if (!block) return block.error();
    auto positions = makePositionsBuffer(field);
    if (!positions) return positions.error();
    positions->resize((positions->size() + 3) / 4 * 4, 0.0f);
    SceneFieldBlock b;
    b.field = *block;
    b.mapsLayer = plan.mapsLayers;
    b.positionsBase = uint32_t(plan.positions.size() / 4);
    const uint32_t width = field.distanceEncoding == DistanceEncoding::kBit1 ? layout.sliceWidth / 8 : layout.sliceWidth;
    plan.mapsWidth = std::max(plan.mapsWidth, width);
    plan.mapsHeight = std::max(plan.mapsHeight, layout.sliceHeight);
    plan.mapsLayers += layout.sliceCount;
    if (field.normalEncoding != NormalEncoding::kNone) {
      b.normalsLayer = plan.normalsLayers;
      plan.normalsWidth = std::max(plan.normalsWidth, layout.sliceWidth);
      plan.normalsHeight = std::max(plan.normalsHeight, layout.sliceHeight);
      plan.normalsLayers += layout.sliceCount;
    }
    plan.positions.insert(plan.positions.end(), positions->begin(), positions->end());
    plan.fields.push_back(b);
  }
  return plan;
}

Result<std::vector<SceneInstanceBlock>> makeSceneInstances(const Scene& scene, const SceneHierarchy& hierarchy,
                                                           std::span<const FieldQuery* const> fields) {
  if (!scene.committed()) return makeError(Code::kBadState, "scene: not committed since the last change");
  if (hierarchy.order.size() != scene.size())
    return makeError(Code::kInvalidArgument, "scene: the hierarchy is not the scene's");
  std::unordered_map<const FieldQuery*, uint32_t> index;
  for (size_t f = 0; f < fields.size(); ++f) index.emplace(fields[f], uint32_t(f));
  std::vector<SceneInstanceBlock> out(hierarchy.order.size());
  for (size_t s = 0; s < out.size(); ++s) {
    const uint32_t id = hierarchy.order[s];
    auto in = scene.instance(id);
    if (!in) return in.error();
    const auto it = index.find(in->field);
    if (it == index.end())
      return makeError(Code::kInvalidArgument,
                       "scene: instance " + std::to_string(id) + "'s field was not uploaded by loadScene");
    SceneInstanceBlock& b = out[s];
    const RigidTransform& x = in->transform;
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) b.rotation[r][c] = x.rotation[r][c];
      b.rotation[r][3] = 0;
    }
    b.translation[0] = x.translation.x;
    b.translation[1] = x.translation.y;
    b.translation[2] = x.translation.z;
    b.invScale = 1.0f / x.scale;  // as the CPU's ToObject
    const Sphere w = in->worldSphere();
    b.sphere[0] = w.center[0];
    b.sphere[1] = w.center[1];
    b.sphere[2] = w.center[2];
    b.sphere[3] = w.radius;
    b.id = id;
    b.field = it->second;
    b.scale = x.scale;
  }
  return out;
}

Result<std::vector<uint8_t>> makeSceneNodes(const SceneHierarchy& h, uint32_t instanceCount) {
  if (3 * h.depth + 1 > kSceneStack)
    return makeError(Code::kUnsupported, "scene: the hierarchy has " + std::to_string(h.depth) +
                                             " levels; the shader's stack (VFF_SCENE_STACK " +
                                             std::to_string(kSceneStack) + ") holds " +
                                             std::to_string((kSceneStack - 1) / 3));
  std::vector<uint8_t> nodes(sizeof(SceneNodesHeader) + h.nodes.size() * sizeof(SceneNode));
  SceneNodesHeader head;
  head.nodeCount = uint32_t(h.nodes.size());
  head.maxRadius = h.maxRadius;
  head.instanceCount = instanceCount;
  std::memcpy(nodes.data(), &head, sizeof head);
  if (!h.nodes.empty()) std::memcpy(nodes.data() + sizeof head, h.nodes.data(), h.nodes.size() * sizeof(SceneNode));
  return nodes;
}

std::string sceneShaderSource(const std::string& sceneGlsl, const std::string& queryGlsl) {
  static const std::string kLine = "#include \"vff_query.glsl\"";
  std::string s = sceneGlsl;
  const size_t at = s.find("\n" + kLine);
  if (at == std::string::npos) return s;
  s.replace(at + 1, kLine.size(), queryGlsl);
  return s;
}

}  // namespace vff::gl
