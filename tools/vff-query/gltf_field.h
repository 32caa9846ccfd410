// gltf_field.h - vff-query on a glTF asset: the payload of one mesh's field (the extension
// VFF_visibility_field, spec/gltf/VFF_visibility_field/README.md), chosen by --mesh.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vff::query_tool {


// The .vff bytes of mesh `mesh`'s field in the asset at `path` (mesh < 0: the asset's one field)
// into *bytes, read and checked by the baker's reader (vff/bake/gltf_fields.h). Otherwise the exit
// code, its diagnostics printed: 1 for a mesh without a field (naming those that have one) or no
// --mesh where several meshes have one; 3 for a field with an error or a geometry mismatch, or an
// asset that is not glTF 2.0 (2 when the problem is a file that cannot be read); 5 in a build
// without the baker.
std::optional<int> gltfFieldBytes(const std::string& path, int mesh, std::vector<uint8_t>* bytes);

}  // namespace vff::query_tool
