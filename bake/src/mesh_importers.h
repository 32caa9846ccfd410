// mesh_importers.h - the importers behind loadMesh (private).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "vff/bake/mesh.h"

namespace tinygltf {
class Model;
}

struct stat;

namespace vff::bake::detail {
// A regular file that can be opened for reading (kIoOpen naming the path otherwise); *st its stat.
Status checkReadable(const std::string& path, struct stat* st);

Result<Mesh> loadWithOpenMesh(const std::string& path, const std::string& ext);

// ---- glTF ---------------------------------------------------------------------------------------
using GltfMatrix = std::array<double, 16>;  // column-major 4x4, as glTF stores it
// Parses a .gltf or .glb file (mesh_gltf.cpp); images are skipped. A required extension the
// importer cannot decode is kMeshUnsupported, naming it; one that changes no geometry gets a note
// in *notes (when given).
Result<std::shared_ptr<const tinygltf::Model>> parseGltf(const std::string& path, bool binary,
                                                         std::vector<std::string>* notes = nullptr);
struct GltfMeshRef {
  int mesh = -1;      // index into model.meshes
  GltfMatrix matrix;  // applied to its positions (normals: the inverse transpose)
  // Points and lines primitives are skipped rather than refused: the glTF extension matches a field
  // against a mesh's triangles only (spec/gltf/VFF_visibility_field, "Matching the geometry").
  bool skipNonTriangles = false;
};
// The triangles of every primitive of the meshes `refs` name, each under its matrix, as one mesh
// (mesh_gltf.cpp); not yet checked (checkMesh).
Result<Mesh> importGltfMeshes(const tinygltf::Model& model, const std::string& path,
                              const std::vector<GltfMeshRef>& refs);
// The default-scene (or options.gltfScene) import behind loadMesh (gltf_scene.cpp).
Result<Mesh> loadWithTinyGltf(const std::string& path, bool binary, const MeshLoadOptions& options, MeshInfo* info);

// What mesh_ply.cpp reads from a PLY whose faces are a `tristrips` element (OpenMesh reads face
// lists only): the vertices, their normals when the file has them, and the triangles (strips with
// the alternating winding, triangles that repeat a vertex skipped; face lists as fans).
struct PlyTriangles {
  std::vector<float> positions, normals;
  std::vector<uint32_t> triangles;
};
// Checks a PLY file before OpenMesh reads it (mesh_ply.cpp); one with a `tristrips` element is
// read whole into *strips.
Status checkPly(const std::string& path, std::optional<PlyTriangles>* strips);
}  // namespace vff::bake::detail
