// gltf_write.cpp - glTF 2.0 files from procedural meshes (vff/bake/procedural.h): test inputs for
// the glTF importer and its scene modes, written by the project's own code.
#include <cmath>
#include <cstdio>
#include <cstring>
#include <nlohmann/json.hpp>

#include "vff/bake/procedural.h"

namespace vff::bake {

std::string base64(const std::vector<uint8_t>& in) {
  static const char* t = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  for (size_t i = 0; i < in.size(); i += 3) {
    const uint32_t v = uint32_t(in[i]) << 16 | (i + 1 < in.size() ? uint32_t(in[i + 1]) << 8 : 0) |
                       (i + 2 < in.size() ? in[i + 2] : 0);
    out += t[(v >> 18) & 63];
    out += t[(v >> 12) & 63];
    out += i + 1 < in.size() ? t[(v >> 6) & 63] : '=';
    out += i + 2 < in.size() ? t[v & 63] : '=';
  }
  return out;
}

namespace {

template <typename T>
void append(std::vector<uint8_t>& buf, const std::vector<T>& v) {
  const size_t at = buf.size();
  buf.resize(at + v.size() * sizeof(T));
  if (!v.empty()) std::memcpy(buf.data() + at, v.data(), v.size() * sizeof(T));
  while (buf.size() % 4) buf.push_back(0);
}

}  // namespace

Status writeGltf(const std::string& path, const std::vector<NamedMesh>& meshes, const std::vector<GltfNodeSpec>& nodes,
                 const std::vector<GltfSceneSpec>& scenes, int defaultScene) {
  using nlohmann::json;
  std::vector<uint8_t> buf;
  json accessors = json::array(), views = json::array(), jmeshes = json::array();
  for (const NamedMesh& nm : meshes) {
    const Mesh& m = nm.mesh;
    float lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (size_t i = 0; i < m.positions.size(); ++i) {
      const size_t c = i % 3;
      if (i < 3 || m.positions[i] < lo[c]) lo[c] = m.positions[i];
      if (i < 3 || m.positions[i] > hi[c]) hi[c] = m.positions[i];
    }
    const size_t posOffset = buf.size();
    append(buf, m.positions);
    const size_t idxOffset = buf.size();
    append(buf, m.indices);
    const size_t pos = accessors.size();
    views.push_back({{"buffer", 0}, {"byteOffset", posOffset}, {"byteLength", m.positions.size() * 4}});
    accessors.push_back({{"bufferView", views.size() - 1}, {"componentType", 5126}, {"count", m.vertexCount()},
                         {"type", "VEC3"}, {"min", {lo[0], lo[1], lo[2]}}, {"max", {hi[0], hi[1], hi[2]}}});
    views.push_back({{"buffer", 0}, {"byteOffset", idxOffset}, {"byteLength", m.indices.size() * 4}});
    accessors.push_back(
        {{"bufferView", views.size() - 1}, {"componentType", 5125}, {"count", m.indices.size()}, {"type", "SCALAR"}});
    jmeshes.push_back({{"name", nm.name}, {"primitives", {{{"attributes", {{"POSITION", pos}}}, {"indices", pos + 1}}}}});
  }
  json jnodes = json::array();
  for (const GltfNodeSpec& n : nodes) {
    json j = json::object();
    if (!n.name.empty()) j["name"] = n.name;
    if (n.mesh >= 0) j["mesh"] = n.mesh;
    if (!n.children.empty()) j["children"] = n.children;
    if (!n.translation.empty()) j["translation"] = n.translation;
    if (!n.rotation.empty()) j["rotation"] = n.rotation;
    if (!n.scale.empty()) j["scale"] = n.scale;
    jnodes.push_back(j);
  }
  json jscenes = json::array();
  for (const GltfSceneSpec& s : scenes) jscenes.push_back({{"name", s.name}, {"nodes", s.nodes}});
  json doc = {{"asset", {{"version", "2.0"}, {"generator", "vff procedural"}}},
              {"scenes", jscenes},
              {"nodes", jnodes},
              {"meshes", jmeshes},
              {"accessors", accessors},
              {"bufferViews", views},
              {"buffers", {{{"byteLength", buf.size()}, {"uri", "data:application/octet-stream;base64," + base64(buf)}}}}};
  if (defaultScene >= 0) doc["scene"] = defaultScene;
  const std::string text = doc.dump(1);
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return makeError(Code::kIoWrite, path + ": cannot open for writing");
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  if (std::fclose(f) != 0 || !ok) return makeError(Code::kIoWrite, path + ": write failed");
  return {};
}

Status writeSampleGltfScene(const std::string& path) {
  const double h = 0.5 * std::sqrt(2.0);
  std::vector<NamedMesh> meshes = {{"box", makeBox(0.5f, 0.3f, 0.2f)},
                                   {"knot", makeTorusKnot(2, 3, 0.15f, 64, 8)},
                                   {"bowl", makeBowl(0.1f, 8, 16)}};
  std::vector<GltfNodeSpec> nodes(5);
  nodes[0] = {"boxA", 0, {}, {1, 2, 3}, {0.2, 0.3, 0.1, std::sqrt(1.0 - 0.04 - 0.09 - 0.01)}, {2, 2, 2}};
  nodes[1] = {"boxB", 0, {}, {-3, 0, 0}, {}, {}};
  nodes[2] = {"group", -1, {1, 3}, {0, 1, 0}, {0, h, 0, h}, {}};
  nodes[3] = {"knotStretched", 1, {}, {0, 0, 4}, {}, {1, 2, 1}};
  nodes[4] = {"bowl", 2, {}, {5, 0, 0}, {}, {}};
  return writeGltf(path, meshes, nodes, {{"main", {0, 2}}, {"second", {4}}}, 0);
}

}  // namespace vff::bake
