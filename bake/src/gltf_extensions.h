// gltf_extensions.h - the glTF extensions that vff-bake reads (private): the check of
// extensionsRequired before tinygltf parses anything, and the decoders that turn compressed
// primitives and buffer views back into plain accessors for the importer in mesh_gltf.cpp.
#pragma once

#include <tiny_gltf.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "vff/error.h"

namespace vff::bake::detail {

// gltf_prepare.cpp: reads the file and refuses (kMeshUnsupported, naming the extension and the
// file) any required extension that is not KHR_mesh_quantization, KHR_draco_mesh_compression or
// EXT_meshopt_compression, before a parse error can hide it; except one that changes no geometry
// (KHR_materials_*, KHR_texture_transform, KHR_texture_basisu, EXT_texture_webp and the like:
// isGeometryFreeExtension), which gets a note in *notes and is not read. What tinygltf would refuse in a valid
// compressed file is mended (meshopt fallback buffers without a uri get a placeholder, Draco
// primitives lose indices that have no data); *bytes is then what tinygltf should parse.
// A file whose JSON cannot be read is passed on unchanged: tinygltf reports the error.
Status prepareGltf(const std::string& path, bool binary, std::vector<unsigned char>* bytes,
                   std::vector<std::string>* notes);
// Whether a glTF extension affects only what the baker does not read (materials, textures, lights,
// metadata), so that a file requiring it still has the geometry the baker reads.
bool isGeometryFreeExtension(const std::string& name);

// Parses what prepareGltf gave, external files relative to the file's folder.
bool parsePreparedGltf(tinygltf::TinyGLTF& loader, tinygltf::Model* model, std::string* err, std::string* warn,
                       const std::vector<unsigned char>& bytes, const std::string& path, bool binary);

// gltf_meshopt.cpp: decodes every buffer view compressed with EXT_meshopt_compression (with its
// filter) into a buffer of its own, so that accessors read it as plain data.
Status decodeMeshoptViews(tinygltf::Model* model, const std::string& path);

// gltf_draco.cpp: decodes every KHR_draco_mesh_compression primitive; its indices, POSITION and
// NORMAL then refer to new accessors over the decoded data, in the component types the
// primitive's accessors declare.
Status decodeDracoPrimitives(tinygltf::Model* model, const std::string& path);

// gltf_quantized.cpp: VEC3 data of any component type that KHR_mesh_quantization allows for the
// attribute (POSITION: float, (unsigned) byte or short, normalized or not; NORMAL: float, normalized
// byte or short) as floats; normalized integers map as the glTF specification says.
size_t gltfComponentSize(int componentType);
Status convertVec3(const uint8_t* data, size_t stride, size_t count, int componentType, bool normalized,
                   bool isNormal, const std::string& what, std::vector<float>* xyz);

}  // namespace vff::bake::detail
