// gltf_scene.cpp - which meshes of a glTF file are baked and where: the scene walk behind loadMesh
// (one object) and loadGltfObjects (one object per mesh or node, vff/bake/gltf.h).
#include <sys/stat.h>
#include <tiny_gltf.h>

#include <cmath>
#include <map>

#include "gltf_matrix.h"
#include "mesh_importers.h"
#include "vff/bake/gltf.h"
#include "vff/scene_description.h"

namespace vff::bake {
namespace detail {
namespace {

using Mat4 = GltfMatrix;

Mat4 nodeMatrix(const tinygltf::Node& n) {
  Mat4 m;
  if (n.matrix.size() == 16) {
    std::copy(n.matrix.begin(), n.matrix.end(), m.begin());
    return m;
  }
  double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
  if (n.translation.size() == 3) std::copy(n.translation.begin(), n.translation.end(), t);
  if (n.rotation.size() == 4) std::copy(n.rotation.begin(), n.rotation.end(), q);
  if (n.scale.size() == 3) std::copy(n.scale.begin(), n.scale.end(), s);
  return gltfTrs(t, q, s);
}

// A node that has a mesh, with its world matrix.
struct NodeMesh {
  int node = -1, mesh = -1;
  Mat4 world;
};

// Walks the nodes of scene `sceneIndex` depth first (children in order), collecting those with a
// mesh. Without scenes (sceneIndex -1), every mesh untransformed.
Result<std::vector<NodeMesh>> sceneMeshes(const tinygltf::Model& model, const std::string& path, int sceneIndex) {
  std::vector<NodeMesh> out;
  if (sceneIndex < 0) {
    for (size_t m = 0; m < model.meshes.size(); ++m) out.push_back({-1, int(m), gltfIdentity()});
    return out;
  }
  struct Frame {
    int node;
    Mat4 parent;
    int depth;
  };
  std::vector<Frame> stack;
  const auto& roots = model.scenes[size_t(sceneIndex)].nodes;
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, gltfIdentity(), 0});
  while (!stack.empty()) {
    const Frame f = stack.back();
    stack.pop_back();
    if (f.node < 0 || size_t(f.node) >= model.nodes.size())
      return makeError(Code::kMeshIndex, path + ": node index " + std::to_string(f.node) + " out of range");
    if (f.depth > 64) return makeError(Code::kMeshParse, path + ": node hierarchy deeper than 64 (a cycle?)");
    const tinygltf::Node& n = model.nodes[size_t(f.node)];
    const Mat4 world = gltfMul(f.parent, nodeMatrix(n));
    if (n.mesh >= 0) {
      if (size_t(n.mesh) >= model.meshes.size())
        return makeError(Code::kMeshIndex, path + ": node " + std::to_string(f.node) + " references a missing mesh");
      out.push_back({f.node, n.mesh, world});
    }
    for (auto it = n.children.rbegin(); it != n.children.rend(); ++it) stack.push_back({*it, world, f.depth + 1});
  }
  return out;
}

// Parses the file and picks the scene (`requested` -1: the default one). *info gets the scenes.
Result<std::shared_ptr<const tinygltf::Model>> parseScene(const std::string& path, bool binary, int requested,
                                                          int* sceneIndex, MeshInfo* info) {
  if (info) info->gltfNotes.clear();
  auto model = parseGltf(path, binary, info ? &info->gltfNotes : nullptr);
  if (!model) return model;
  const auto& scenes = (*model)->scenes;
  if (info) {
    info->gltfScenes.clear();
    for (const auto& s : scenes) info->gltfScenes.push_back(s.name);
  }
  if (requested >= 0 && size_t(requested) >= scenes.size())
    return makeError(Code::kInvalidArgument, path + ": there is no scene " + std::to_string(requested) + " (the file has " +
                                                 std::to_string(scenes.size()) + " scene" +
                                                 (scenes.size() == 1 ? "" : "s") + ")");
  *sceneIndex = -1;
  if (!scenes.empty()) {
    *sceneIndex = requested >= 0 ? requested : (*model)->defaultScene >= 0 ? (*model)->defaultScene : 0;
    if (size_t(*sceneIndex) >= scenes.size()) return makeError(Code::kMeshIndex, path + ": default scene out of range");
  }
  if (info) info->gltfScene = *sceneIndex;
  return model;
}

// " 'name'" or nothing.
std::string quoted(const std::string& name) { return name.empty() ? std::string() : " '" + name + "'"; }

// Notes (MeshInfo::gltfNotes) for what the baked nodes animate and the bake leaves out: a skin (the
// mesh is baked in its bind pose: the vertices as stored, under the node's transform, not moved by
// its joints) and morph targets (the base shape; the weights are not applied). Each node and mesh
// once, in the order of the scene walk.
void noteAnimation(const tinygltf::Model& model, const std::vector<NodeMesh>& nodes, MeshInfo* info) {
  if (!info) return;
  std::vector<bool> morphNoted(model.meshes.size(), false);
  for (const NodeMesh& n : nodes) {
    if (n.node >= 0 && model.nodes[size_t(n.node)].skin >= 0) {
      const tinygltf::Node& node = model.nodes[size_t(n.node)];
      info->gltfNotes.push_back("node " + std::to_string(n.node) + quoted(node.name) + " (mesh " + std::to_string(n.mesh) +
                                ") has skin " + std::to_string(node.skin) +
                                ": baked in its bind pose, not posed by its joints");
    }
    const tinygltf::Mesh& mesh = model.meshes[size_t(n.mesh)];
    bool morphed = false;
    for (const tinygltf::Primitive& p : mesh.primitives) morphed = morphed || !p.targets.empty();
    if (morphed && !morphNoted[size_t(n.mesh)]) {
      morphNoted[size_t(n.mesh)] = true;
      info->gltfNotes.push_back("mesh " + std::to_string(n.mesh) + quoted(mesh.name) +
                                " has morph targets: baked as its base shape, its weights not applied");
    }
  }
}

bool isGlb(const std::string& path) {
  return path.size() >= 4 && (path.compare(path.size() - 4, 4, ".glb") == 0 || path.compare(path.size() - 4, 4, ".GLB") == 0);
}

// The world matrix as translation * similarity, when its linear part is one: a positive uniform
// scale times a rotation, within float precision.
bool similarity(const Mat4& m, GltfPlacement* p) {
  double s = 0;
  if (!gltfNotSimilarity(m, &s).empty()) return false;
  const double a[3][3] = {{m[0], m[4], m[8]}, {m[1], m[5], m[9]}, {m[2], m[6], m[10]}};
  float r[3][3];
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) r[i][j] = float(a[i][j] / s);
  p->rotation = quaternionFromRotation(r);
  p->scale = float(s);
  p->translation = {float(m[12]), float(m[13]), float(m[14])};
  return true;
}

}  // namespace

Result<Mesh> loadWithTinyGltf(const std::string& path, bool binary, const MeshLoadOptions& options, MeshInfo* info) {
  int sceneIndex = -1;
  auto model = parseScene(path, binary, options.gltfScene, &sceneIndex, info);
  if (!model) return std::move(model).error();
  auto nodes = sceneMeshes(**model, path, sceneIndex);
  if (!nodes) return std::move(nodes).error();
  noteAnimation(**model, *nodes, info);
  std::vector<GltfMeshRef> refs;
  for (const NodeMesh& n : *nodes) refs.push_back({n.mesh, n.world});
  return importGltfMeshes(**model, path, refs);
}

}  // namespace detail

Result<std::vector<GltfObject>> loadGltfObjects(const std::string& path, const GltfObjectOptions& options,
                                                MeshInfo* info) {
  struct stat st {};
  if (Status s = detail::checkReadable(path, &st); !s) return std::move(s).error();
  MeshInfo localInfo;
  MeshInfo* in = info ? info : &localInfo;
  int sceneIndex = -1;
  auto model = detail::parseScene(path, detail::isGlb(path), options.scene, &sceneIndex, in);
  if (!model) return std::move(model).error();
  in->format = detail::isGlb(path) ? "glb" : "gltf";
  auto nodes = detail::sceneMeshes(**model, path, sceneIndex);
  if (!nodes) return std::move(nodes).error();
  detail::noteAnimation(**model, *nodes, in);

  std::vector<GltfObject> objects;
  std::map<int, size_t> sharedObject;  // mesh -> its object in its own frame (kMesh)
  for (const detail::NodeMesh& n : *nodes) {
    GltfPlacement place;
    place.node = n.node;
    if (n.node >= 0) place.name = (*model)->nodes[size_t(n.node)].name;
    const bool similar = detail::similarity(n.world, &place);
    detail::GltfMatrix bakedMatrix = detail::gltfIdentity();
    if (!similar) {  // the linear part goes into the geometry, the translation into the placement
      bakedMatrix = n.world;
      bakedMatrix[12] = bakedMatrix[13] = bakedMatrix[14] = 0;
      place.translation = {float(n.world[12]), float(n.world[13]), float(n.world[14])};
    }
    const bool ownFrame = options.split == GltfSplit::kMesh && options.ownFrame;
    if (ownFrame && !similar) bakedMatrix = detail::gltfIdentity();
    const bool shared = options.split == GltfSplit::kMesh && (similar || ownFrame);
    if (shared && sharedObject.count(n.mesh)) {
      if (similar) objects[sharedObject[n.mesh]].placements.push_back(place);
      continue;
    }
    GltfObject obj;
    obj.mesh = n.mesh;
    obj.node = shared ? -1 : n.node;
    obj.name = options.split == GltfSplit::kNode ? place.name : (*model)->meshes[size_t(n.mesh)].name;
    auto geometry = detail::importGltfMeshes(**model, path, {{n.mesh, bakedMatrix}});
    if (!geometry) return std::move(geometry).error();
    const std::string what = path + ": mesh " + std::to_string(n.mesh) +
                             (obj.name.empty() ? std::string() : " '" + obj.name + "'") +
                             (obj.node >= 0 ? " at node " + std::to_string(obj.node) : std::string());
    Status s = checkMesh(&*geometry, what);
    if (!s) return std::move(s).error();
    obj.geometry = std::move(*geometry);
    if (similar || !ownFrame) obj.placements.push_back(place);
    if (shared) sharedObject[n.mesh] = objects.size();
    objects.push_back(std::move(obj));
  }
  if (objects.empty())
    return makeError(Code::kMeshEmpty, path + ": scene " + std::to_string(sceneIndex) + " has no node with a mesh");
  return objects;
}

}  // namespace vff::bake
