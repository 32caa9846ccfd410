// gltf_writer.h - glTF files for the importer's tests, made from a Mesh: plain, quantized by hand
// (KHR_mesh_quantization), and compressed with the libraries' own encoders (Draco, meshoptimizer).
#pragma once

#include <nlohmann/json.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "vff/bake/mesh.h"

namespace vff::bake::gltftest {

constexpr int kByte = 5120, kUByte = 5121, kShort = 5122, kUShort = 5123, kUInt = 5125, kFloat = 5126;

// One glTF document being assembled: its JSON and its first buffer's bytes.
struct GltfDoc {
  nlohmann::json json;
  std::vector<uint8_t> bin;
  GltfDoc();
  // Appends bytes to buffer 0 (4-byte aligned); returns their offset.
  size_t append(const void* data, size_t n);
  // A buffer view over bytes appended to buffer 0; stride 0 leaves byteStride out.
  int addView(const void* data, size_t n, size_t stride);
  // An accessor; view -1 leaves bufferView out (a Draco accessor).
  int addAccessor(int view, int componentType, bool normalized, size_t count, const char* type);
  void use(const std::string& extension, bool required);
  // One mesh of one primitive, under one node with a translation and scale.
  void addMeshNode(const nlohmann::json& primitive, const float translation[3], const float scale[3]);
};

// Writes a .glb (one BIN chunk) or a .gltf with its buffer in NAME.bin beside it; false on an I/O error.
bool save(const GltfDoc& doc, const std::string& path, bool glb);

// How makeGltf stores the vertices: float, or an 8- or 16-bit type, normalized or not (the node's
// translation and scale undo the quantization); normals (when the mesh has them) float or BYTE /
// SHORT normalized.
struct Quantization {
  int positionType = kFloat;
  bool positionNormalized = false;
  int normalType = kFloat;
};
GltfDoc makeGltf(const Mesh& mesh, const Quantization& q);
// The largest error per coordinate that quantizing `mesh` as q makes (half a step on the widest axis).
double quantizationError(const Mesh& mesh, const Quantization& q);

// Draco (KHR_draco_mesh_compression) with lossless float attributes: edgebreaker (reorders the
// vertices) or sequential (keeps them in order); with positionBits > 0, positions quantized to that
// many bits by Draco's encoder (the decoded vertices then move slightly).
GltfDoc makeDracoGltf(const Mesh& mesh, bool sequential, int positionBits = 0);

// Appends `mesh` as a mesh of one primitive (float positions, normals when it has them, 32-bit
// indices) named `name`, without a node; returns its index.
int addMesh(GltfDoc& doc, const Mesh& mesh, const std::string& name);

// EXT_meshopt_compression: vertex and index codecs, the filters named, and an uncompressed
// fallback buffer without a uri.
struct Meshopt {
  bool exponentialPositions = false;  // EXPONENTIAL filter on the positions (lossy)
  const char* normalFilter = "NONE";  // "NONE" (float), "OCTAHEDRAL" (BYTE), "QUATERNION" (SHORT)
  bool indexSequence = false;         // INDICES mode instead of TRIANGLES
};
GltfDoc makeMeshoptGltf(const Mesh& mesh, const Meshopt& o);

}  // namespace vff::bake::gltftest
