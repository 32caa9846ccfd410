// The plain and quantized glTF writer of the importer's tests, and the container (.gltf + .bin,
// .glb) shared with the compressed writers.
#include "gltf_writer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

namespace vff::bake::gltftest {

GltfDoc::GltfDoc() {
  json = {{"asset", {{"version", "2.0"}}}, {"buffers", nlohmann::json::array()},
          {"bufferViews", nlohmann::json::array()}, {"accessors", nlohmann::json::array()},
          {"meshes", nlohmann::json::array()}, {"nodes", nlohmann::json::array()}};
}

size_t GltfDoc::append(const void* data, size_t n) {
  while (bin.size() % 4) bin.push_back(0);
  const size_t at = bin.size();
  bin.insert(bin.end(), static_cast<const uint8_t*>(data), static_cast<const uint8_t*>(data) + n);
  return at;
}

int GltfDoc::addView(const void* data, size_t n, size_t stride) {
  nlohmann::json v = {{"buffer", 0}, {"byteOffset", append(data, n)}, {"byteLength", n}};
  if (stride) v["byteStride"] = stride;
  json["bufferViews"].push_back(v);
  return int(json["bufferViews"].size()) - 1;
}

int GltfDoc::addAccessor(int view, int componentType, bool normalized, size_t count, const char* type) {
  nlohmann::json a = {{"componentType", componentType}, {"count", count}, {"type", type}};
  if (view >= 0) a["bufferView"] = view;
  if (normalized) a["normalized"] = true;
  json["accessors"].push_back(a);
  return int(json["accessors"].size()) - 1;
}

void GltfDoc::use(const std::string& extension, bool required) {
  json["extensionsUsed"].push_back(extension);
  if (required) json["extensionsRequired"].push_back(extension);
}

void GltfDoc::addMeshNode(const nlohmann::json& primitive, const float translation[3], const float scale[3]) {
  json["meshes"].push_back({{"primitives", {primitive}}});
  json["nodes"].push_back({{"mesh", int(json["meshes"].size()) - 1},
                           {"translation", {translation[0], translation[1], translation[2]}},
                           {"scale", {scale[0], scale[1], scale[2]}}});
  json["scenes"] = {{{"nodes", {0}}}};
  json["scene"] = 0;
}

int addMesh(GltfDoc& doc, const Mesh& mesh, const std::string& name) {
  const size_t n = mesh.vertexCount(), ni = mesh.indices.size();
  nlohmann::json prim = {
      {"attributes", {{"POSITION", doc.addAccessor(doc.addView(mesh.positions.data(), n * 12, 0), kFloat, false, n, "VEC3")}}}};
  // glTF wants a POSITION accessor's min and max.
  std::array<float, 3> lo{1e30f, 1e30f, 1e30f}, hi{-1e30f, -1e30f, -1e30f};
  for (size_t i = 0; i < mesh.positions.size(); ++i) {
    lo[i % 3] = std::min(lo[i % 3], mesh.positions[i]);
    hi[i % 3] = std::max(hi[i % 3], mesh.positions[i]);
  }
  doc.json["accessors"].back()["min"] = lo;
  doc.json["accessors"].back()["max"] = hi;
  if (mesh.normals.size() == mesh.positions.size()) {
    // glTF wants unit normals; an importer's may be area-weighted sums.
    std::vector<float> unit(mesh.normals);
    for (size_t i = 0; i + 2 < unit.size(); i += 3) {
      const float len = std::sqrt(unit[i] * unit[i] + unit[i + 1] * unit[i + 1] + unit[i + 2] * unit[i + 2]);
      if (std::fabs(len - 1.0f) < 1e-3f) continue;  // unit already: kept bit for bit
      for (size_t c = 0; c < 3; ++c) unit[i + c] = len > 0 ? unit[i + c] / len : (c == 2 ? 1.0f : 0.0f);
    }
    prim["attributes"]["NORMAL"] = doc.addAccessor(doc.addView(unit.data(), n * 12, 0), kFloat, false, n, "VEC3");
  }
  prim["indices"] = doc.addAccessor(doc.addView(mesh.indices.data(), ni * 4, 0), kUInt, false, ni, "SCALAR");
  nlohmann::json m = {{"primitives", {prim}}};
  if (!name.empty()) m["name"] = name;
  doc.json["meshes"].push_back(m);
  return int(doc.json["meshes"].size()) - 1;
}

bool save(const GltfDoc& doc, const std::string& path, bool glb) {
  nlohmann::json j = doc.json;
  std::vector<uint8_t> bin = doc.bin;
  while (bin.size() % 4) bin.push_back(0);
  if (!bin.empty()) j["buffers"].insert(j["buffers"].begin(), nlohmann::json{{"byteLength", bin.size()}});
  std::ofstream out(path, std::ios::binary);
  if (!glb) {
    if (!bin.empty()) {
      const std::string name = std::filesystem::path(path).stem().string() + ".bin";
      j["buffers"][0]["uri"] = name;
      std::ofstream b(std::filesystem::path(path).parent_path() / name, std::ios::binary);
      b.write(reinterpret_cast<const char*>(bin.data()), std::streamsize(bin.size()));
      if (!b) return false;
    }
    out << j.dump(1);
    return bool(out);
  }
  std::string text = j.dump();
  while (text.size() % 4) text.push_back(' ');
  auto u32 = [&](uint32_t x) { out.write(reinterpret_cast<const char*>(&x), 4); };
  u32(0x46546C67);
  u32(2);
  u32(uint32_t(12 + 8 + text.size() + (bin.empty() ? 0 : 8 + bin.size())));
  u32(uint32_t(text.size()));
  u32(0x4E4F534A);
  out << text;
  if (!bin.empty()) {
    u32(uint32_t(bin.size()));
    u32(0x004E4942);
    out.write(reinterpret_cast<const char*>(bin.data()), std::streamsize(bin.size()));
  }
  return bool(out);
}

namespace {

struct Range {
  float lo[3], hi[3];
};
Range bounds(const Mesh& m) {
  Range r{{1e30f, 1e30f, 1e30f}, {-1e30f, -1e30f, -1e30f}};
  for (size_t i = 0; i < m.positions.size(); ++i) {
    r.lo[i % 3] = std::min(r.lo[i % 3], m.positions[i]);
    r.hi[i % 3] = std::max(r.hi[i % 3], m.positions[i]);
  }
  return r;
}

size_t componentSize(int t) { return t == kByte || t == kUByte ? 1 : t == kShort || t == kUShort ? 2 : 4; }
bool isSigned(int t) { return t == kByte || t == kShort; }
double maxOf(int t) {
  return t == kByte ? 127 : t == kUByte ? 255 : t == kShort ? 32767 : t == kUShort ? 65535 : 1;
}

// Integer components of type t with stride padded to 4 bytes, as KHR_mesh_quantization requires.
std::vector<uint8_t> packInts(const std::vector<double>& v, int t, size_t* stride) {
  const size_t cs = componentSize(t);
  *stride = (3 * cs + 3) / 4 * 4;
  std::vector<uint8_t> out(v.size() / 3 * *stride);
  for (size_t i = 0; i < v.size(); ++i) {
    const long q = std::lround(v[i]);
    uint8_t* at = out.data() + i / 3 * *stride + i % 3 * cs;
    if (cs == 1) *at = static_cast<uint8_t>(q & 0xff);
    else {
      const uint16_t s = static_cast<uint16_t>(q & 0xffff);
      std::memcpy(at, &s, 2);
    }
  }
  return out;
}

}  // namespace

double quantizationError(const Mesh& mesh, const Quantization& q) {
  if (q.positionType == kFloat) return 0;
  const Range r = bounds(mesh);
  double widest = 0;
  for (int c = 0; c < 3; ++c) widest = std::max(widest, double(r.hi[c]) - r.lo[c]);
  const double steps = isSigned(q.positionType) ? 2 * maxOf(q.positionType) : maxOf(q.positionType);
  return 0.5 * widest / steps;
}

GltfDoc makeGltf(const Mesh& mesh, const Quantization& q) {
  GltfDoc doc;
  const size_t n = mesh.vertexCount();
  float t[3] = {0, 0, 0}, s[3] = {1, 1, 1};
  int pos;
  if (q.positionType == kFloat) {
    pos = doc.addAccessor(doc.addView(mesh.positions.data(), n * 12, 0), kFloat, false, n, "VEC3");
  } else {
    // Integer q stands for t + s * dequantized(q): the node's translation and scale.
    const Range r = bounds(mesh);
    const double m = maxOf(q.positionType);
    const bool sg = isSigned(q.positionType);
    std::vector<double> v(mesh.positions.size());
    for (int c = 0; c < 3; ++c) {
      const double ext = std::max(double(r.hi[c]) - r.lo[c], 1e-6);
      t[c] = sg ? float((double(r.lo[c]) + r.hi[c]) / 2) : r.lo[c];
      const double span = sg ? ext / 2 : ext;  // what the full integer range covers
      s[c] = float(q.positionNormalized ? span : span / m);
    }
    for (size_t i = 0; i < v.size(); ++i) v[i] = (mesh.positions[i] - t[i % 3]) / s[i % 3] * (q.positionNormalized ? m : 1);
    size_t stride;
    const std::vector<uint8_t> b = packInts(v, q.positionType, &stride);
    pos = doc.addAccessor(doc.addView(b.data(), b.size(), stride), q.positionType, q.positionNormalized, n, "VEC3");
    doc.use("KHR_mesh_quantization", true);
  }
  nlohmann::json prim = {{"attributes", {{"POSITION", pos}}}};
  if (!mesh.normals.empty()) {
    int nrm;
    if (q.normalType == kFloat) {
      nrm = doc.addAccessor(doc.addView(mesh.normals.data(), n * 12, 0), kFloat, false, n, "VEC3");
    } else {
      // Normals of the node's local space: the inverse transpose of the node's scale is 1/s.
      std::vector<double> v(mesh.normals.begin(), mesh.normals.end());
      for (size_t i = 0; i < v.size(); i += 3) {
        double len = 0;
        for (size_t c = 0; c < 3; ++c) len += (v[i + c] * s[c]) * (v[i + c] * s[c]);
        len = std::sqrt(len);
        for (size_t c = 0; c < 3; ++c) v[i + c] = len > 0 ? v[i + c] * s[c] / len * maxOf(q.normalType) : 0;
      }
      size_t stride;
      const std::vector<uint8_t> b = packInts(v, q.normalType, &stride);
      nrm = doc.addAccessor(doc.addView(b.data(), b.size(), stride), q.normalType, true, n, "VEC3");
      if (q.positionType == kFloat) doc.use("KHR_mesh_quantization", true);
    }
    prim["attributes"]["NORMAL"] = nrm;
  }
  const size_t ni = mesh.indices.size();
  prim["indices"] = doc.addAccessor(doc.addView(mesh.indices.data(), ni * 4, 0), kUInt, false, ni, "SCALAR");
  doc.addMeshNode(prim, t, s);
  return doc;
}

}  // namespace vff::bake::gltftest
