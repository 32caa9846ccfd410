// vff/bake/procedural.h - procedural test meshes: shapes whose visibility is easy to reason about
// or hard for the method (concavities, thin parts), generated deterministically.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "vff/bake/mesh.h"

namespace vff::bake {

// UV sphere of `radius` at the origin, `rings` x `segments` quads split into triangles.
Mesh makeSphere(float radius, uint32_t rings = 32, uint32_t segments = 64);
// Axis-aligned box with half extents (hx, hy, hz): 12 triangles, per-face normals not shared.
Mesh makeBox(float hx, float hy, float hz);
// (p, q) torus knot tube: `tube` radius, `segments` along the curve, `sides` around the tube.
Mesh makeTorusKnot(uint32_t p = 2, uint32_t q = 3, float tube = 0.15f, uint32_t segments = 256, uint32_t sides = 16);
// A concave bowl: a hemispherical shell (outer radius 1, given thickness), open at the top.
Mesh makeBowl(float thickness = 0.1f, uint32_t rings = 24, uint32_t segments = 48);
// A thin elongated capsule-like rod along x: length, radius (the paper's hard case).
Mesh makeRod(float length = 2.0f, float radius = 0.05f, uint32_t segments = 64, uint32_t sides = 12);

// Shapes by name ("sphere", "box", "torus-knot", "bowl", "rod"); an empty mesh for other names.
Mesh makeShape(const std::string& name);
const std::vector<std::string>& shapeNames();

// Writes a mesh as Wavefront OBJ (vertices, normals when present, 1-based faces).
Status writeObj(const Mesh& mesh, const std::string& path);

// ---- glTF scenes (gltf_write.cpp) ---------------------------------------------------------------
struct GltfNodeSpec {
  std::string name;
  int mesh = -1;                         // index into the meshes, -1: none
  std::vector<int> children;             // node indices
  std::vector<double> translation;       // 3 values, or empty
  std::vector<double> rotation;          // quaternion x, y, z, w, or empty
  std::vector<double> scale;             // 3 values, or empty
};
struct GltfSceneSpec {
  std::string name;
  std::vector<int> nodes;  // the scene's root nodes
};
struct NamedMesh {
  std::string name;
  Mesh mesh;
};
// `bytes` as base64 text (RFC 4648, padded): writeGltf's data URIs, and those of the glTF files the
// tests write by hand.
std::string base64(const std::vector<uint8_t>& bytes);
// Writes a glTF 2.0 file: float positions, uint32 indices, one buffer embedded as a base64 data URI
// (.gltf). `defaultScene` is the file's `scene` (-1: none written).
Status writeGltf(const std::string& path, const std::vector<NamedMesh>& meshes, const std::vector<GltfNodeSpec>& nodes,
                 const std::vector<GltfSceneSpec>& scenes, int defaultScene = 0);
// A small scene of several objects for the tests and samples: a box used by two nodes (one rotated
// and scaled, one under a rotated group node), a torus knot under a non-uniform scale, and a bowl
// alone in a second scene; scene 0 is the default.
Status writeSampleGltfScene(const std::string& path);

}  // namespace vff::bake
