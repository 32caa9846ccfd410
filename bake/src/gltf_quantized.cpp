// KHR_mesh_quantization: VEC3 attributes stored as (normalized) integers, read as floats. A
// normalized value c of n bits maps to c / (2^n - 1) when unsigned and max(c / (2^(n-1) - 1), -1)
// when signed (glTF 2.0, "Animations" and KHR_mesh_quantization); other integers keep their value,
// the node transforms scale them.
#include <algorithm>
#include <limits>
#include <cstring>

#include "gltf_extensions.h"

namespace vff::bake::detail {
namespace {

template <typename T>
void convert(const uint8_t* d, size_t stride, size_t count, bool normalized, std::vector<float>* xyz) {
  constexpr double kMax = double(std::numeric_limits<T>::max());
  xyz->resize(count * 3);
  for (size_t i = 0; i < count; ++i)
    for (size_t c = 0; c < 3; ++c) {
      T v;
      std::memcpy(&v, d + i * stride + c * sizeof(T), sizeof(T));
      double f = double(v);
      if (normalized) f = std::max(f / kMax, -1.0);
      (*xyz)[3 * i + c] = float(f);
    }
}

}  // namespace

size_t gltfComponentSize(int componentType) {
  switch (componentType) {
    case TINYGLTF_COMPONENT_TYPE_BYTE:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: return 1;
    case TINYGLTF_COMPONENT_TYPE_SHORT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: return 2;
    case TINYGLTF_COMPONENT_TYPE_INT:
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT:
    case TINYGLTF_COMPONENT_TYPE_FLOAT: return 4;
    default: return 0;
  }
}

Status convertVec3(const uint8_t* d, size_t stride, size_t count, int ct, bool normalized, bool isNormal,
                   const std::string& what, std::vector<float>* xyz) {
  const bool isFloat = ct == TINYGLTF_COMPONENT_TYPE_FLOAT;
  const bool isSigned = ct == TINYGLTF_COMPONENT_TYPE_BYTE || ct == TINYGLTF_COMPONENT_TYPE_SHORT;
  const bool isUnsigned = ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE || ct == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT;
  // NORMAL allows float and normalized signed bytes and shorts; POSITION every 8- and 16-bit type.
  const bool allowed = isFloat || (isNormal ? isSigned && normalized : isSigned || isUnsigned);
  if (!allowed)
    return makeError(Code::kMeshUnsupported,
                     what + ": component type " + std::to_string(ct) + (normalized ? " (normalized)" : "") +
                         " is not one that glTF or KHR_mesh_quantization allows for this attribute");
  switch (ct) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT:
      xyz->resize(count * 3);
      for (size_t i = 0; i < count; ++i) std::memcpy(&(*xyz)[3 * i], d + i * stride, 12);
      break;
    case TINYGLTF_COMPONENT_TYPE_BYTE: convert<int8_t>(d, stride, count, normalized, xyz); break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: convert<uint8_t>(d, stride, count, normalized, xyz); break;
    case TINYGLTF_COMPONENT_TYPE_SHORT: convert<int16_t>(d, stride, count, normalized, xyz); break;
    default: convert<uint16_t>(d, stride, count, normalized, xyz); break;
  }
  return {};
}

}  // namespace vff::bake::detail
