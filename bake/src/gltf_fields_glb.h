// gltf_fields_glb.h - what the reader and the writer of VFF_visibility_field share (private): the
// GLB container, the uris a glTF file references (files beside it, data: URIs) and the bytes of its
// buffers.
#pragma once

#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "vff/bake/gltf_fields.h"

namespace tinygltf {
class Model;
}

namespace vff::bake::detail {

// The two chunks of a GLB (glTF 2.0 binary): the JSON text and the binary chunk, when there is one.
struct GlbChunks {
  std::string json;
  std::vector<uint8_t> bin;
  bool hasBin = false;
};

// The file starts with the GLB magic "glTF".
bool hasGlbMagic(std::span<const uint8_t> bytes);
// Splits a GLB; "" on success, else what is wrong (the header, a chunk's length or type).
std::string splitGlb(std::span<const uint8_t> bytes, GlbChunks* out);
// A GLB of `json` and `bin` (no binary chunk when `bin` is empty): the JSON chunk padded with
// spaces so that the binary chunk's data starts at a file offset that is a multiple of 64.
std::vector<uint8_t> joinGlb(const std::string& json, const std::vector<uint8_t>& bin);

// A whole regular file (FIFOs and folders are refused, never waited on); "" or what went wrong.
std::string readRegularFile(const std::string& path, std::vector<uint8_t>* out);

// The problem with a uri a glTF file references (rule 14007): "" when it is a relative reference or
// a data: URI with ;base64, (which need not be well-formed base64 here: decodeDataUri says).
std::string checkGltfUri(const std::string& uri);
bool isDataUri(const std::string& uri);
// The bytes of a data: URI with ;base64, and its media type; "" or what is wrong.
std::string decodeDataUri(const std::string& uri, std::vector<uint8_t>* out, std::string* mediaType);
// The path of a relative uri (percent-decoded) for a glTF file at `gltfPath`.
std::string resolveGltfUri(const std::string& gltfPath, const std::string& uri);
// The bytes a uri (checked: checkGltfUri) names; "" or what went wrong.
std::string readGltfUri(const std::string& gltfPath, const std::string& uri, std::vector<uint8_t>* out,
                        std::string* mediaType = nullptr);

// The bytes of buffer `index` of a parsed glTF document: the GLB binary chunk for a buffer without
// uri at index 0 of a GLB, else its uri's; "" or why there are none.
std::string gltfBufferData(const nlohmann::json& doc, size_t index, const std::string& gltfPath,
                           const GlbChunks* glb, std::vector<uint8_t>* out);

// 16 lowercase hex digits.
std::string hex16(uint64_t v);

// ---- The geometry a field is matched against (gltf_fields_geometry.cpp) -------------------------
// Mesh `mesh` of a parsed model as a reader matches it: its triangle primitives in mesh space,
// checked (zero-area triangles dropped); errors name `path` and the mesh.
Result<GltfMeshGeometry> meshGeometry(const tinygltf::Model& model, const std::string& path, int mesh);

// The nodes that use each mesh (index: the mesh) in the scene a reader reads: the default scene,
// else scene 0, else every node (from the roots of the hierarchy); each answered or not (why).
std::vector<std::vector<GltfFieldNode>> meshInstances(const nlohmann::json& doc);

}  // namespace vff::bake::detail
