// gltf_fields_geometry.cpp - what a VFF_visibility_field is matched against: the mesh's triangles as
// the file ships them, and the nodes that use the mesh (which of them a field can answer).
#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include "gltf_fields_glb.h"
#include "gltf_matrix.h"
#include "mesh_importers.h"
#include "vff/bake/mesh.h"

namespace vff::bake {
namespace detail {
namespace {

using Mat4 = GltfMatrix;

// The numbers of a JSON array of `n` numbers, or nothing.
bool numbers(const nlohmann::json& node, const char* key, size_t n, double* out) {
  const auto it = node.find(key);
  if (it == node.end() || !it->is_array() || it->size() != n) return false;
  for (size_t i = 0; i < n; ++i) {
    if (!(*it)[i].is_number()) return false;
    out[i] = (*it)[i].get<double>();
  }
  return true;
}

Mat4 nodeMatrix(const nlohmann::json& n) {
  Mat4 m = gltfIdentity();
  if (numbers(n, "matrix", 16, m.data())) return m;
  double t[3] = {0, 0, 0}, q[4] = {0, 0, 0, 1}, s[3] = {1, 1, 1};
  numbers(n, "translation", 3, t);
  numbers(n, "rotation", 4, q);
  numbers(n, "scale", 3, s);
  return gltfTrs(t, q, s);
}

// A mesh with morph targets whose weights (the node's, else the mesh's; zero when absent) are not
// all zero.
bool morphed(const nlohmann::json& mesh, const nlohmann::json& node) {
  bool targets = false;
  if (mesh.contains("primitives") && mesh["primitives"].is_array())
    for (const auto& p : mesh["primitives"])
      targets = targets || (p.is_object() && p.contains("targets") && p["targets"].is_array() && !p["targets"].empty());
  if (!targets) return false;
  const nlohmann::json* w = nullptr;
  if (node.contains("weights") && node["weights"].is_array()) w = &node["weights"];
  else if (mesh.contains("weights") && mesh["weights"].is_array()) w = &mesh["weights"];
  if (!w) return false;
  return std::any_of(w->begin(), w->end(), [](const nlohmann::json& v) { return !v.is_number() || v.get<double>() != 0; });
}

int intMember(const nlohmann::json& o, const char* key) {
  const auto it = o.find(key);
  if (it == o.end() || !it->is_number_integer()) return -1;
  const int64_t v = it->get<int64_t>();
  return v < 0 || v > std::numeric_limits<int>::max() ? -1 : int(v);
}

}  // namespace

Result<GltfMeshGeometry> meshGeometry(const tinygltf::Model& model, const std::string& path, int mesh) {
  auto m = importGltfMeshes(model, path, {{mesh, gltfIdentity(), /*skipNonTriangles=*/true}});
  if (!m) return std::move(m).error();
  const std::string name = size_t(mesh) < model.meshes.size() ? model.meshes[size_t(mesh)].name : "";
  if (Status s = checkMesh(&*m, path + ": mesh " + std::to_string(mesh) + (name.empty() ? "" : " '" + name + "'")); !s)
    return std::move(s).error();
  GltfMeshGeometry g;
  g.geometryHash = hex16(geometryHash(*m));
  g.min = {INFINITY, INFINITY, INFINITY};
  g.max = {-INFINITY, -INFINITY, -INFINITY};
  for (uint32_t v : m->indices)
    for (size_t k = 0; k < 3; ++k) {
      g.min[k] = std::min(g.min[k], m->positions[3 * size_t(v) + k]);
      g.max[k] = std::max(g.max[k], m->positions[3 * size_t(v) + k]);
    }
  return g;
}

std::vector<std::vector<GltfFieldNode>> meshInstances(const nlohmann::json& doc) {
  static const nlohmann::json kEmpty = nlohmann::json::array();
  const nlohmann::json& meshes = doc.contains("meshes") && doc["meshes"].is_array() ? doc["meshes"] : kEmpty;
  const nlohmann::json& nodes = doc.contains("nodes") && doc["nodes"].is_array() ? doc["nodes"] : kEmpty;
  const nlohmann::json& scenes = doc.contains("scenes") && doc["scenes"].is_array() ? doc["scenes"] : kEmpty;
  std::vector<std::vector<GltfFieldNode>> out(meshes.size());
  std::vector<int> roots;
  if (!scenes.empty()) {
    int scene = intMember(doc, "scene");
    if (scene < 0 || size_t(scene) >= scenes.size()) scene = 0;
    const nlohmann::json& s = scenes[size_t(scene)];
    if (s.is_object() && s.contains("nodes") && s["nodes"].is_array())
      for (const auto& n : s["nodes"]) roots.push_back(n.is_number_integer() ? int(n.get<int64_t>()) : -1);
  } else {  // every node: the roots of the hierarchy
    std::vector<bool> child(nodes.size(), false);
    for (const auto& n : nodes)
      if (n.is_object() && n.contains("children") && n["children"].is_array())
        for (const auto& c : n["children"])
          if (c.is_number_integer() && c.get<int64_t>() >= 0 && size_t(c.get<int64_t>()) < nodes.size())
            child[size_t(c.get<int64_t>())] = true;
    for (size_t i = 0; i < nodes.size(); ++i)
      if (!child[i]) roots.push_back(int(i));
  }
  struct Frame {
    int node;
    Mat4 parent;
    int depth;
  };
  std::vector<Frame> stack;
  for (auto it = roots.rbegin(); it != roots.rend(); ++it) stack.push_back({*it, gltfIdentity(), 0});
  while (!stack.empty()) {
    const Frame f = stack.back();
    stack.pop_back();
    if (f.node < 0 || size_t(f.node) >= nodes.size() || f.depth > 64 || !nodes[size_t(f.node)].is_object()) continue;
    const nlohmann::json& n = nodes[size_t(f.node)];
    const Mat4 world = gltfMul(f.parent, nodeMatrix(n));
    const int mesh = intMember(n, "mesh");
    if (mesh >= 0 && size_t(mesh) < meshes.size()) {
      GltfFieldNode fn;
      fn.node = f.node;
      if (n.contains("name") && n["name"].is_string()) fn.name = n["name"].get<std::string>();
      if (n.contains("skin")) fn.reason = "skin";
      else if (morphed(meshes[size_t(mesh)], n)) fn.reason = "morph targets";
      else fn.reason = gltfNotSimilarity(world);
      fn.answered = fn.reason.empty();
      out[size_t(mesh)].push_back(std::move(fn));
    }
    if (n.contains("children") && n["children"].is_array())
      for (auto it = n["children"].rbegin(); it != n["children"].rend(); ++it)
        stack.push_back({it->is_number_integer() ? int(it->get<int64_t>()) : -1, world, f.depth + 1});
  }
  return out;
}

}  // namespace detail

Result<GltfMeshGeometry> gltfMeshGeometry(const std::string& path, int mesh) {
  std::vector<uint8_t> head;
  if (std::string e = detail::readRegularFile(path, &head); !e.empty()) return makeError(Code::kIoOpen, path + ": " + e);
  auto model = detail::parseGltf(path, detail::hasGlbMagic(head));
  if (!model) return std::move(model).error();
  return detail::meshGeometry(**model, path, mesh);
}

}  // namespace vff::bake
