// gltf_matrix.h - a glTF node's matrix (column-major 4x4, as glTF stores it) and whether it can place
// a field: the one definition that the scene walk of vff-bake (gltf_scene.cpp) and the reader of
// VFF_visibility_field (gltf_fields_geometry.cpp) share, so that both call the same nodes similar.
#pragma once

#include <string>

#include "mesh_importers.h"

namespace vff::bake::detail {

GltfMatrix gltfIdentity();
// a * b.
GltfMatrix gltfMul(const GltfMatrix& a, const GltfMatrix& b);
// T * R * S of a node's translation, rotation (a unit quaternion x, y, z, w) and scale.
GltfMatrix gltfTrs(const double translation[3], const double rotation[4], const double scale[3]);
// Why the linear part of m is not a positive uniform scale times a rotation, within float precision
// ("mirror" or "non-uniform scale"), or "" when it is one; then *scale (when given) is that scale.
std::string gltfNotSimilarity(const GltfMatrix& m, double* scale = nullptr);

}  // namespace vff::bake::detail
