// glTF extensionsRequired, read with nlohmann-json before tinygltf parses the file: an unsupported
// extension is named as such even when tinygltf would fail on what the extension changes (a
// compressed buffer view, an accessor without data).
#include <nlohmann/json.hpp>

#include <array>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>

#include "gltf_extensions.h"

namespace vff::bake::detail {
namespace {

constexpr std::array<const char*, 3> kSupported = {"KHR_mesh_quantization", "KHR_draco_mesh_compression",
                                                   "EXT_meshopt_compression"};
// Extensions that change materials, textures, lights or metadata, never the triangles: a file that
// requires one is baked from its geometry alone. (KHR_materials_* are matched by prefix.)
constexpr std::array<const char*, 9> kGeometryFree = {
    "KHR_texture_transform", "KHR_texture_basisu",     "EXT_texture_webp", "EXT_texture_avif", "MSFT_texture_dds",
    "KHR_lights_punctual",   "EXT_lights_image_based", "KHR_xmp_json_ld",  "KHR_xmp"};
constexpr uint32_t kGlbMagic = 0x46546C67;  // "glTF"
constexpr uint32_t kChunkJson = 0x4E4F534A;  // "JSON"
constexpr size_t kGlbHeader = 12, kChunkHeader = 8;

uint32_t le32(const unsigned char* p) {
  return uint32_t(p[0]) | uint32_t(p[1]) << 8 | uint32_t(p[2]) << 16 | uint32_t(p[3]) << 24;
}
void put32(std::vector<unsigned char>* v, size_t at, uint32_t x) {
  for (int i = 0; i < 4; ++i) (*v)[at + size_t(i)] = static_cast<unsigned char>(x >> (8 * i));
}

// The JSON chunk of a GLB: its offset and length, or false when the container is malformed (left
// for tinygltf to report).
bool glbJson(const std::vector<unsigned char>& b, size_t* off, size_t* len) {
  if (b.size() < kGlbHeader + kChunkHeader || le32(b.data()) != kGlbMagic) return false;
  const size_t n = le32(b.data() + kGlbHeader);
  if (le32(b.data() + kGlbHeader + 4) != kChunkJson || n > b.size() - kGlbHeader - kChunkHeader) return false;
  *off = kGlbHeader + kChunkHeader;
  *len = n;
  return true;
}

// Meshopt fallback buffers may have no uri (the data exists only compressed); tinygltf would try to
// load them. They get a three-byte placeholder: only compressed views, decoded into buffers of
// their own, refer to them.
bool placeholderFallbacks(nlohmann::json* doc) {
  bool changed = false;
  auto buffers = doc->find("buffers");
  if (buffers == doc->end() || !buffers->is_array()) return false;
  for (auto& b : *buffers) {
    if (!b.is_object() || b.contains("uri")) continue;
    const auto ext = b.find("extensions");
    if (ext == b.end() || !ext->is_object()) continue;
    const auto mo = ext->find("EXT_meshopt_compression");
    if (mo == ext->end() || !mo->is_object() || mo->value("fallback", false) != true) continue;
    b["uri"] = "data:application/octet-stream;base64,AAAA";
    b["byteLength"] = 3;
    changed = true;
  }
  return changed;
}

// tinygltf refuses a primitive whose indices accessor has no buffer view, as a Draco primitive's
// has (its indices exist only compressed): such indices are left out, and the Draco decoder gives
// the primitive the decoded ones.
bool dropDracoIndices(nlohmann::json* doc) {
  bool changed = false;
  auto meshes = doc->find("meshes");
  auto accessors = doc->find("accessors");
  if (meshes == doc->end() || !meshes->is_array() || accessors == doc->end() || !accessors->is_array()) return false;
  for (auto& m : *meshes) {
    if (!m.is_object() || !m.contains("primitives") || !m["primitives"].is_array()) continue;
    for (auto& p : m["primitives"]) {
      if (!p.is_object() || !p.contains("extensions") || !p["extensions"].is_object() ||
          !p["extensions"].contains("KHR_draco_mesh_compression") || !p.contains("indices"))
        continue;
      const auto& i = p["indices"];
      if (!i.is_number_unsigned() || i.get<size_t>() >= accessors->size()) continue;
      const auto& a = (*accessors)[i.get<size_t>()];
      if (a.is_object() && a.contains("bufferView")) continue;
      p.erase("indices");
      changed = true;
    }
  }
  return changed;
}

}  // namespace

bool isGeometryFreeExtension(const std::string& name) {
  if (name.starts_with("KHR_materials_")) return true;
  for (const char* s : kGeometryFree)
    if (name == s) return true;
  return false;
}

Status prepareGltf(const std::string& path, bool binary, std::vector<unsigned char>* bytes,
                   std::vector<std::string>* notes) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(Code::kIoOpen, path + ": cannot be read");
  bytes->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (in.bad()) return makeError(Code::kIoOpen, path + ": read error");
  size_t off = 0, len = bytes->size();
  if (binary && !glbJson(*bytes, &off, &len)) return {};
  nlohmann::json doc = nlohmann::json::parse(bytes->begin() + std::ptrdiff_t(off),
                                             bytes->begin() + std::ptrdiff_t(off + len), nullptr, false);
  if (!doc.is_object()) return {};
  const auto req = doc.find("extensionsRequired");
  if (req != doc.end() && req->is_array()) {
    for (const auto& e : *req) {
      const std::string name = e.is_string() ? e.get<std::string>() : e.dump();
      bool known = false;
      for (const char* s : kSupported) known = known || name == s;
      if (known) continue;
      if (isGeometryFreeExtension(name)) {
        if (notes) notes->push_back("requires the glTF extension " + name + ", which changes no geometry: not read");
        continue;
      }
      return makeError(Code::kMeshUnsupported,
                       path + ": requires the glTF extension " + name +
                           ", which vff cannot read (geometry: KHR_mesh_quantization, KHR_draco_mesh_compression, "
                           "EXT_meshopt_compression; materials, textures and lights are not read)");
    }
  }
  const bool fallbacks = placeholderFallbacks(&doc);
  const bool draco = dropDracoIndices(&doc);
  if (!fallbacks && !draco) return {};
  std::string json = doc.dump();
  if (!binary) {
    bytes->assign(json.begin(), json.end());
    return {};
  }
  while (json.size() % 4) json.push_back(' ');
  // The same GLB with the new JSON chunk: header, JSON chunk, then every chunk after it as it was.
  const size_t rest = off + len;  // the chunk length includes its padding
  std::vector<unsigned char> out(kGlbHeader + kChunkHeader + json.size());
  std::memcpy(out.data(), bytes->data(), 8);
  put32(&out, kGlbHeader, uint32_t(json.size()));
  put32(&out, kGlbHeader + 4, kChunkJson);
  std::memcpy(out.data() + kGlbHeader + kChunkHeader, json.data(), json.size());
  if (rest < bytes->size()) out.insert(out.end(), bytes->begin() + std::ptrdiff_t(rest), bytes->end());
  put32(&out, 8, uint32_t(out.size()));
  *bytes = std::move(out);
  return {};
}

bool parsePreparedGltf(tinygltf::TinyGLTF& loader, tinygltf::Model* model, std::string* err, std::string* warn,
                       const std::vector<unsigned char>& bytes, const std::string& path, bool binary) {
  std::error_code ec;
  std::string dir = std::filesystem::absolute(std::filesystem::path(path), ec).parent_path().string();
  if (ec) dir = std::filesystem::path(path).parent_path().string();
  if (binary)
    return loader.LoadBinaryFromMemory(model, err, warn, bytes.data(), static_cast<unsigned int>(bytes.size()), dir);
  return loader.LoadASCIIFromString(model, err, warn, reinterpret_cast<const char*>(bytes.data()),
                                    static_cast<unsigned int>(bytes.size()), dir);
}

}  // namespace vff::bake::detail
