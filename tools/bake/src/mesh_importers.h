// mesh_importers.h - the importers behind loadMesh (private).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "vff/bake/mesh.h"

namespace vff::bake::detail {
Result<Mesh> loadWithOpenMesh(const std::string& path, const std::string& ext);
Result<Mesh> loadWithTinyGltf(const std::string& path, bool binary);

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
