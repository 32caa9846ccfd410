// gen_gltf_asset.cpp - a glTF asset under construction: its meshes, nodes, scene, bufferViews and
// the extension's value on a mesh, built up as JSON with one binary buffer.
#include <algorithm>
#include <cstring>
#include <limits>

#include "gen_gltf.h"
#include "vff/bake/procedural.h"

namespace vff::gltf_gen {

json vec3(const std::array<float, 3>& v) {
  return json::array({v[0], v[1], v[2]});
}

int Asset::view(const std::vector<uint8_t>& bytes, size_t align, int target) {
  while (bin.size() % align) bin.push_back(0);
  json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes.size()}};
  if (target) v["target"] = target;
  bin.insert(bin.end(), bytes.begin(), bytes.end());
  j["bufferViews"].push_back(v);
  return int(j["bufferViews"].size()) - 1;
}

int Asset::accessor(json a) {
  j["accessors"].push_back(std::move(a));
  return int(j["accessors"].size()) - 1;
}

int Asset::mesh(const bake::Mesh& m, const std::string& name, int mode) {
  std::vector<uint8_t> pos(m.positions.size() * 4), idx(m.indices.size() * 4);
  std::memcpy(pos.data(), m.positions.data(), pos.size());
  std::memcpy(idx.data(), m.indices.data(), idx.size());
  std::array<float, 3> lo, hi;
  lo.fill(std::numeric_limits<float>::infinity());
  hi.fill(-std::numeric_limits<float>::infinity());
  for (size_t i = 0; i < m.positions.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], m.positions[i]);
    hi[i % 3] = std::max(hi[i % 3], m.positions[i]);
  }
  const int p = accessor({{"bufferView", view(pos, 4, 34962)},
                          {"componentType", 5126},
                          {"count", m.vertexCount()},
                          {"type", "VEC3"},
                          {"min", vec3(lo)},
                          {"max", vec3(hi)}});
  const int i = accessor(
      {{"bufferView", view(idx, 4, 34963)}, {"componentType", 5125}, {"count", m.indices.size()}, {"type", "SCALAR"}});
  json prim = {{"attributes", {{"POSITION", p}}}, {"indices", i}};
  if (mode != 4) prim["mode"] = mode;
  j["meshes"].push_back({{"name", name}, {"primitives", json::array({prim})}});
  return int(j["meshes"].size()) - 1;
}

int Asset::node(int mesh, const std::string& name, json extra) {
  json n = {{"name", name}, {"mesh", mesh}};
  n.update(extra);
  j["nodes"].push_back(n);
  return int(j["nodes"].size()) - 1;
}

void Asset::scene() {
  json roots = json::array();
  for (size_t i = 0; i < j["nodes"].size(); ++i) roots.push_back(i);
  j["scenes"] = json::array({{{"nodes", roots}}});
  j["scene"] = 0;
}

void Asset::attach(int mesh, int v, const Geometry& g) {
  ext(mesh) = {{"bufferView", v}, {"mimeType", kMediaType}, {"geometryHash", g.hash},
               {"min", vec3(g.min)}, {"max", vec3(g.max)}};
}

void Asset::attachUri(int mesh, const std::string& uri, const Geometry& g) {
  ext(mesh) = {{"uri", uri}, {"geometryHash", g.hash}, {"min", vec3(g.min)}, {"max", vec3(g.max)}};
}

void Asset::finishBuffer(bool glb) {
  while (bin.size() % 4) bin.push_back(0);
  if (bin.empty()) return;
  json b = {{"byteLength", bin.size()}};
  if (!glb) b["uri"] = "data:application/octet-stream;base64," + bake::base64(bin);
  j["buffers"] = json::array({b});
}

Asset oneTetra(const Fields& f, const std::vector<uint8_t>& payload, int* meshOut, int* viewOut) {
  Asset a;
  const int m = a.mesh(f.tetra, "tetrahedron");
  a.node(m, "tetrahedron");
  a.scene();
  a.used();
  const int v = a.payloadView(payload);
  a.attach(m, v, f.tetraField.geometry);
  if (meshOut) *meshOut = m;
  if (viewOut) *viewOut = v;
  return a;
}

}  // namespace vff::gltf_gen
