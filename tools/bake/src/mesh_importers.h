// mesh_importers.h - the importers behind loadMesh (private).
#pragma once

#include <string>

#include "vff/bake/mesh.h"

namespace vff::bake::detail {
Result<Mesh> loadWithOpenMesh(const std::string& path, const std::string& ext);
Result<Mesh> loadWithTinyGltf(const std::string& path, bool binary);
}  // namespace vff::bake::detail
