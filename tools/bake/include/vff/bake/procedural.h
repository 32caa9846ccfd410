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

}  // namespace vff::bake
