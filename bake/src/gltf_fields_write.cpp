// gltf_fields_write.cpp - packGlbWithFields: a .gltf or .glb asset as one self-contained .glb with a
// VFF_visibility_field on each mesh given one.
//
// Every buffer with data goes into the one binary chunk, each at a multiple of 64 bytes so that the
// alignment its views had within it holds in the file; images with a uri are embedded as
// bufferViews; the payloads follow, each at a multiple of 64. The JSON chunk is padded so the binary
// chunk's data starts at a file offset that is a multiple of 64: a payload's offset in the file is
// then a multiple of 64 too, which lets a reader map it in place. The JSON keeps the input's member
// order (nlohmann's ordered_json), so equal inputs give equal bytes.
#include <algorithm>
#include <cctype>
#include <map>

#include "gltf_fields_glb.h"
#include "vff/bake/gltf_fields.h"

namespace vff::bake {
namespace {

using ojson = nlohmann::ordered_json;

constexpr size_t kAlign = 64;

void padTo(std::vector<uint8_t>* bin, size_t align) {
  while (bin->size() % align) bin->push_back(0);
}

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return s;
}

// The media type of an image file, by its name.
std::string imageMediaType(const std::string& uri) {
  const std::string u = lower(uri);
  const size_t dot = u.find_last_of('.');
  const std::string ext = dot == std::string::npos ? "" : u.substr(dot + 1);
  if (ext == "png") return "image/png";
  if (ext == "jpg" || ext == "jpeg") return "image/jpeg";
  if (ext == "webp") return "image/webp";
  if (ext == "ktx2") return "image/ktx2";
  if (ext == "gif") return "image/gif";
  return "application/octet-stream";
}

Error packError(const std::string& input, const std::string& what) { return makeError(Code::kMeshParse, input + ": " + what); }

bool isIndex(const ojson& v, size_t size) { return v.is_number_unsigned() && v.get<uint64_t>() < size; }

}  // namespace

Result<std::vector<uint8_t>> packGlbWithFields(const std::string& input, const std::vector<GltfFieldPayload>& payloads) {
  std::vector<uint8_t> bytes;
  if (std::string e = detail::readRegularFile(input, &bytes); !e.empty()) return makeError(Code::kIoOpen, input + ": " + e);
  detail::GlbChunks glb;
  const bool binary = detail::hasGlbMagic(bytes);
  std::string text;
  if (binary) {
    if (std::string e = detail::splitGlb(bytes, &glb); !e.empty()) return packError(input, e);
    text = glb.json;
  } else {
    text.assign(bytes.begin(), bytes.end());
  }
  ojson doc = ojson::parse(text, nullptr, false);
  if (doc.is_discarded() || !doc.is_object()) return packError(input, "the glTF JSON cannot be parsed");
  const nlohmann::json plain = nlohmann::json::parse(text, nullptr, false);

  // Buffers: those with data are packed into buffer 0, the binary chunk; one without data (a meshopt
  // fallback) stays a buffer of its own, after it.
  std::vector<uint8_t> bin;
  const size_t nbuffers = doc.contains("buffers") && doc["buffers"].is_array() ? doc["buffers"].size() : 0;
  std::vector<int64_t> newIndex(nbuffers, -1);
  std::vector<uint64_t> base(nbuffers, 0);
  ojson buffers = ojson::array();
  buffers.push_back(ojson::object());  // buffer 0: the binary chunk
  for (size_t b = 0; b < nbuffers; ++b) {
    std::vector<uint8_t> data;
    const std::string e = detail::gltfBufferData(plain, b, input, binary ? &glb : nullptr, &data);
    const ojson& old = doc["buffers"][b];
    if (e.empty()) {
      padTo(&bin, kAlign);
      base[b] = bin.size();
      newIndex[b] = 0;
      bin.insert(bin.end(), data.begin(), data.end());
    } else if (old.is_object() && !old.contains("uri") && !(b == 0 && binary)) {
      newIndex[b] = int64_t(buffers.size());
      buffers.push_back(old);
    } else {
      return packError(input, e);
    }
  }
  const auto remap = [&](ojson& view, const std::string& where) -> Status {
    if (!view.contains("buffer") || !isIndex(view["buffer"], nbuffers))
      return packError(input, where + " names no buffer of the file");
    const size_t b = size_t(view["buffer"].get<uint64_t>());
    view["buffer"] = newIndex[b];
    if (newIndex[b] == 0) {
      const uint64_t off = view.contains("byteOffset") && view["byteOffset"].is_number_unsigned() ? view["byteOffset"].get<uint64_t>() : 0;
      view["byteOffset"] = off + base[b];
    }
    return {};
  };
  if (doc.contains("bufferViews") && doc["bufferViews"].is_array()) {
    for (size_t v = 0; v < doc["bufferViews"].size(); ++v) {
      ojson& view = doc["bufferViews"][v];
      const std::string where = "bufferView " + std::to_string(v);
      if (!view.is_object()) return packError(input, where + " is not an object");
      if (Status s = remap(view, where); !s) return std::move(s).error();
      // EXT_meshopt_compression's compressed data lives in a buffer of its own too.
      if (view.contains("extensions") && view["extensions"].is_object() &&
          view["extensions"].contains("EXT_meshopt_compression") && view["extensions"]["EXT_meshopt_compression"].is_object())
        if (Status s = remap(view["extensions"]["EXT_meshopt_compression"], where + "'s EXT_meshopt_compression"); !s)
          return std::move(s).error();
    }
  } else {
    doc["bufferViews"] = ojson::array();
  }
  // (ordered_json keeps members in a vector: a reference to one dies when a member is added, so
  // the views are looked up each time.)
  const auto addView = [&](const std::vector<uint8_t>& data, size_t align) {
    padTo(&bin, align);
    ojson& views = doc["bufferViews"];
    views.push_back({{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", data.size()}});
    bin.insert(bin.end(), data.begin(), data.end());
    return views.size() - 1;
  };

  // Images with a uri: embedded.
  if (doc.contains("images") && doc["images"].is_array())
    for (size_t i = 0; i < doc["images"].size(); ++i) {
      ojson& image = doc["images"][i];
      if (!image.is_object() || !image.contains("uri") || !image["uri"].is_string()) continue;
      const std::string uri = image["uri"].get<std::string>();
      std::vector<uint8_t> data;
      std::string media;
      if (std::string e = detail::readGltfUri(input, uri, &data, &media); !e.empty())
        return makeError(detail::isDataUri(uri) ? Code::kMeshParse : Code::kIoOpen,
                         input + ": image " + std::to_string(i) + "'s uri '" + uri + "': " + e);
      if (!image.contains("mimeType")) image["mimeType"] = detail::isDataUri(uri) && !media.empty() ? media : imageMediaType(uri);
      image.erase("uri");
      image["bufferView"] = addView(data, 4);
    }

  // The fields.
  const size_t nmeshes = doc.contains("meshes") && doc["meshes"].is_array() ? doc["meshes"].size() : 0;
  std::vector<const GltfFieldPayload*> byMesh(nmeshes, nullptr);
  for (const GltfFieldPayload& p : payloads) {
    if (p.mesh < 0 || size_t(p.mesh) >= nmeshes || !doc["meshes"][size_t(p.mesh)].is_object())
      return makeError(Code::kInvalidArgument, input + ": there is no mesh " + std::to_string(p.mesh) + " to attach a field to");
    if (byMesh[size_t(p.mesh)]) return makeError(Code::kInvalidArgument, input + ": two fields for mesh " + std::to_string(p.mesh));
    byMesh[size_t(p.mesh)] = &p;
  }
  for (size_t m = 0; m < nmeshes; ++m) {
    const GltfFieldPayload* p = byMesh[m];
    if (!p) continue;
    ojson ext = ojson::object();
    if (p->uri.empty()) ext["bufferView"] = addView(p->bytes, kAlign);
    else ext["uri"] = p->uri;
    ext["mimeType"] = kVffMediaType;
    ext["geometryHash"] = p->geometryHash;
    ext["min"] = {p->min[0], p->min[1], p->min[2]};
    ext["max"] = {p->max[0], p->max[1], p->max[2]};
    ojson& mesh = doc["meshes"][m];
    if (!mesh.contains("extensions") || !mesh["extensions"].is_object()) mesh["extensions"] = ojson::object();
    mesh["extensions"][kGltfFieldExtension] = std::move(ext);
  }
  if (std::any_of(byMesh.begin(), byMesh.end(), [](const GltfFieldPayload* p) { return p != nullptr; })) {
    if (!doc.contains("extensionsUsed") || !doc["extensionsUsed"].is_array()) doc["extensionsUsed"] = ojson::array();
    ojson& used = doc["extensionsUsed"];
    if (std::find(used.begin(), used.end(), ojson(kGltfFieldExtension)) == used.end()) used.push_back(kGltfFieldExtension);
  }
  // A field is never required (an asset that said so is mended).
  if (doc.contains("extensionsRequired") && doc["extensionsRequired"].is_array()) {
    ojson& req = doc["extensionsRequired"];
    req.erase(std::remove(req.begin(), req.end(), ojson(kGltfFieldExtension)), req.end());
    if (req.empty()) doc.erase("extensionsRequired");
  }

  padTo(&bin, 4);
  if (bin.empty() && buffers.size() == 1) {
    doc.erase("buffers");
  } else {
    buffers[0]["byteLength"] = bin.size();
    doc["buffers"] = std::move(buffers);
  }
  if (doc["bufferViews"].empty()) doc.erase("bufferViews");
  return detail::joinGlb(doc.dump(), bin);
}

}  // namespace vff::bake
