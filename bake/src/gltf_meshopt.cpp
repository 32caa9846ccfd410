// EXT_meshopt_compression through Debian's libmeshoptimizer: each compressed buffer view is decoded
// (vertex codec for ATTRIBUTES, index codecs for TRIANGLES and INDICES, then the view's filter) into
// a buffer of its own, and the view is pointed at it; accessors then read it as plain data. The
// view's uncompressed buffer (the fallback, often without data) is not read.
#include <meshoptimizer.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "gltf_extensions.h"

namespace vff::bake::detail {
namespace {

constexpr const char* kMeshopt = "EXT_meshopt_compression";
// Every codec spends some bits on each element: data claiming to expand more than this is corrupt,
// and refused before the allocation it asks for.
constexpr uint64_t kMaxExpansion = 1024;

struct Compressed {
  uint64_t buffer = 0, byteOffset = 0, byteLength = 0, byteStride = 0, count = 0;
  std::string mode, filter = "NONE";
};

bool number(const tinygltf::Value& o, const char* key, bool required, uint64_t* out) {
  if (!o.Has(key)) return !required;
  const tinygltf::Value& v = o.Get(key);
  if (!v.IsNumber()) return false;
  const double d = v.GetNumberAsDouble();
  if (!(d >= 0) || d > 9.0e15 || std::floor(d) != d) return false;
  *out = uint64_t(d);
  return true;
}

bool text(const tinygltf::Value& o, const char* key, bool required, std::string* out) {
  if (!o.Has(key)) return !required;
  if (!o.Get(key).IsString()) return false;
  *out = o.Get(key).Get<std::string>();
  return true;
}

Status decodeView(tinygltf::Model* model, size_t vi, const std::string& what) {
  const tinygltf::Value& ext = model->bufferViews[vi].extensions.at(kMeshopt);
  Compressed c;
  if (!ext.IsObject() || !number(ext, "buffer", true, &c.buffer) || !number(ext, "byteOffset", false, &c.byteOffset) ||
      !number(ext, "byteLength", true, &c.byteLength) || !number(ext, "byteStride", true, &c.byteStride) ||
      !number(ext, "count", true, &c.count) || !text(ext, "mode", true, &c.mode) || !text(ext, "filter", false, &c.filter))
    return makeError(Code::kMeshParse, what + ": " + kMeshopt +
                                           " needs buffer, byteLength, byteStride, count and mode, as numbers and names");
  if (c.buffer >= model->buffers.size())
    return makeError(Code::kMeshIndex, what + ": compressed buffer " + std::to_string(c.buffer) + " out of range");
  const std::vector<unsigned char>& src = model->buffers[c.buffer].data;
  if (c.byteOffset > src.size() || c.byteLength > src.size() - c.byteOffset)
    return makeError(Code::kMeshIndex, what + ": compressed data reaches outside its " + std::to_string(src.size()) +
                                           "-byte buffer");
  const bool attributes = c.mode == "ATTRIBUTES", triangles = c.mode == "TRIANGLES", indices = c.mode == "INDICES";
  if (!attributes && !triangles && !indices)
    return makeError(Code::kMeshUnsupported, what + ": unknown " + kMeshopt + " mode " + c.mode);
  const bool strideOk = attributes ? c.byteStride % 4 == 0 && c.byteStride >= 4 && c.byteStride <= 256
                                   : c.byteStride == 2 || c.byteStride == 4;
  if (!strideOk || (triangles && c.count % 3 != 0))
    return makeError(Code::kMeshParse, what + ": byteStride " + std::to_string(c.byteStride) + " or count " +
                                           std::to_string(c.count) + " is not valid for mode " + c.mode);
  const bool octahedral = c.filter == "OCTAHEDRAL", quaternion = c.filter == "QUATERNION",
             exponential = c.filter == "EXPONENTIAL";
  if (!octahedral && !quaternion && !exponential && c.filter != "NONE")
    return makeError(Code::kMeshUnsupported, what + ": unknown " + kMeshopt + " filter " + c.filter);
  if ((c.filter != "NONE" && !attributes) || (octahedral && c.byteStride != 4 && c.byteStride != 8) ||
      (quaternion && c.byteStride != 8))
    return makeError(Code::kMeshParse, what + ": filter " + c.filter + " does not apply to mode " + c.mode +
                                           " with byteStride " + std::to_string(c.byteStride));
  const uint64_t size = c.count * c.byteStride;  // both below 2^53 / 2^8: no overflow
  if (size > kMaxExpansion * c.byteLength + 4096)
    return makeError(Code::kMeshParse, what + ": " + std::to_string(c.count) + " elements cannot come from " +
                                           std::to_string(c.byteLength) + " compressed bytes");
  std::vector<unsigned char> out(size);
  const unsigned char* in = src.data() + c.byteOffset;
  int rc;
  if (attributes) rc = meshopt_decodeVertexBuffer(out.data(), c.count, c.byteStride, in, c.byteLength);
  else if (triangles) rc = meshopt_decodeIndexBuffer(out.data(), c.count, c.byteStride, in, c.byteLength);
  else rc = meshopt_decodeIndexSequence(out.data(), c.count, c.byteStride, in, c.byteLength);
  if (rc != 0) return makeError(Code::kMeshParse, what + ": meshopt data cannot be decoded (" + c.mode + ")");
  if (octahedral) meshopt_decodeFilterOct(out.data(), c.count, c.byteStride);
  if (quaternion) meshopt_decodeFilterQuat(out.data(), c.count, c.byteStride);
  if (exponential) meshopt_decodeFilterExp(out.data(), c.count, c.byteStride);
  tinygltf::Buffer b;
  b.data = std::move(out);
  model->buffers.push_back(std::move(b));
  tinygltf::BufferView& bv = model->bufferViews[vi];
  bv.buffer = int(model->buffers.size()) - 1;
  bv.byteOffset = 0;
  bv.byteLength = size;
  bv.extensions.erase(kMeshopt);
  return {};
}

}  // namespace

Status decodeMeshoptViews(tinygltf::Model* model, const std::string& path) {
  for (size_t vi = 0; vi < model->bufferViews.size(); ++vi) {
    if (model->bufferViews[vi].extensions.count(kMeshopt) == 0) continue;
    Status s = decodeView(model, vi, path + ": bufferView " + std::to_string(vi));
    if (!s) return s;
  }
  return {};
}

}  // namespace vff::bake::detail
