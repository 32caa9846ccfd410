// vff/bake/mesh.h - triangle meshes for baking, and their importers.
//
// Supported inputs: OBJ, PLY (face lists, or `tristrips` with -1 restarts), OFF, STL (through
// OpenMesh; polygons are triangulated) and glTF 2.0
// .gltf/.glb (through tinygltf: every triangle primitive of the default scene or a chosen one, node
// transforms applied; quantized, Draco and meshopt compressed data decoded; vff/bake/gltf.h splits a
// scene into its meshes or nodes). Content that cannot be baked is an error, never a silently empty
// mesh:
//   kIoOpen          the file is missing or unreadable
//   kMeshFormat      unknown extension
//   kMeshParse       the importer cannot parse the file
//   kMeshUnsupported points/lines primitives, a required glTF extension that changes geometry
//                    other than KHR_mesh_quantization, KHR_draco_mesh_compression and
//                    EXT_meshopt_compression (one that changes no geometry: materials, textures,
//                    lights, is left unread and listed in MeshInfo::gltfNotes), attribute types
//                    those do not allow, sparse accessors
// What a glTF file animates is not baked: a skinned mesh is baked in its bind pose (the vertices as
// stored, under the node's transform), a mesh with morph targets as its base shape; MeshInfo::gltfNotes
// names each one, for the tools to print as warnings.
//   kMeshIndex       an index or an accessor outside its buffer
//   kMeshEmpty       no triangles; kMeshNonFinite a NaN/Inf coordinate (message names the vertex);
//   kMeshDegenerate  every triangle has zero area
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "vff/error.h"

namespace vff::bake {

struct Mesh {
  std::vector<float> positions;   // x, y, z per vertex (object space)
  std::vector<float> normals;     // x, y, z per vertex, or empty when the input has none
  std::vector<uint32_t> indices;  // three per triangle
  uint64_t droppedDegenerate = 0;  // zero-area triangles removed by checkMesh()
  size_t vertexCount() const { return positions.size() / 3; }
  size_t triangleCount() const { return indices.size() / 3; }
};

struct MeshInfo {
  std::string format;  // "obj", "ply", "off", "stl", "gltf", "glb"
  // glTF: the file's scenes (their names, "" when unnamed) and the one loaded (-1 when the file has
  // no scene and every mesh was loaded untransformed).
  std::vector<std::string> gltfScenes;
  int gltfScene = -1;
  // glTF: what the bake leaves out, one sentence each (no file name): required extensions that
  // change no geometry ("requires KHR_texture_transform, which changes no geometry: not read"),
  // skinned nodes baked in their bind pose, meshes with morph targets baked as their base shape.
  std::vector<std::string> gltfNotes;
};

struct MeshLoadOptions {
  // glTF: the scene to load; -1: the file's default scene (`scene`), else scene 0. A scene that
  // does not exist is kInvalidArgument, naming the scenes there are.
  int gltfScene = -1;
};

// Loads and checks a mesh (see the error list above). Messages name the file.
Result<Mesh> loadMesh(const std::string& path, MeshInfo* info = nullptr, const MeshLoadOptions& options = {});

// Checks a mesh held in memory: finite coordinates, indices in range, drops zero-area triangles,
// and fails when none remain. `what` names the source in messages.
Status checkMesh(Mesh* mesh, const std::string& what);

// Content hash (XXH3-64 of the positions and indices) for provenance metadata: it changes with the
// vertex order, so the same geometry read from two file formats usually has two.
uint64_t meshHash(const Mesh& mesh);

// Canonical hash of the triangles (META vff.source.geometryHash, spec/format.md section 9): XXH3-64
// of the triangles as 9 f32 each (vertex coordinates, -0 written as +0), every triangle rotated so
// that its lexicographically smallest vertex comes first (the winding kept), the triangles sorted
// lexicographically. It depends on the geometry only, not on vertex sharing, vertex order, triangle
// order or file format.
uint64_t geometryHash(const Mesh& mesh);

}  // namespace vff::bake
