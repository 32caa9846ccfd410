// meshopt-compressed glTF (EXT_meshopt_compression) for the importer's tests, made with
// meshoptimizer's own encoders and filters, with an uncompressed fallback buffer that has no uri.
#include <meshoptimizer.h>

#include <cstring>

#include "gltf_writer.h"

namespace vff::bake::gltftest {
namespace {

// A compressed view: its encoded bytes in buffer 0, its place in the fallback buffer (buffer 1).
int addCompressedView(GltfDoc* doc, const std::vector<uint8_t>& encoded, size_t count, size_t stride,
                      const char* mode, const char* filter, size_t* fallbackSize) {
  const size_t at = doc->append(encoded.data(), encoded.size());
  nlohmann::json v = {{"buffer", 1}, {"byteOffset", *fallbackSize}, {"byteLength", count * stride},
                      {"extensions",
                       {{"EXT_meshopt_compression",
                         {{"buffer", 0}, {"byteOffset", at}, {"byteLength", encoded.size()}, {"byteStride", stride},
                          {"count", count}, {"mode", mode}, {"filter", filter}}}}}};
  if (std::strcmp(mode, "ATTRIBUTES") == 0) v["byteStride"] = stride;
  *fallbackSize += (count * stride + 3) / 4 * 4;
  doc->json["bufferViews"].push_back(v);
  return int(doc->json["bufferViews"].size()) - 1;
}

std::vector<uint8_t> encodeVertices(const void* data, size_t count, size_t stride) {
  std::vector<uint8_t> out(meshopt_encodeVertexBufferBound(count, stride));
  out.resize(meshopt_encodeVertexBuffer(out.data(), out.size(), data, count, stride));
  return out;
}

}  // namespace

GltfDoc makeMeshoptGltf(const Mesh& mesh, const Meshopt& o) {
  GltfDoc doc;
  doc.use("EXT_meshopt_compression", true);
  const size_t n = mesh.vertexCount();
  size_t fallback = 0;
  std::vector<uint8_t> raw(n * 12);
  if (o.exponentialPositions) meshopt_encodeFilterExp(raw.data(), n, 12, 16, mesh.positions.data());
  else std::memcpy(raw.data(), mesh.positions.data(), raw.size());
  const int pv = addCompressedView(&doc, encodeVertices(raw.data(), n, 12), n, 12, "ATTRIBUTES",
                                   o.exponentialPositions ? "EXPONENTIAL" : "NONE", &fallback);
  nlohmann::json prim = {{"attributes", {{"POSITION", doc.addAccessor(pv, kFloat, false, n, "VEC3")}}}};
  if (!mesh.normals.empty()) {
    const std::string f = o.normalFilter;
    int accessor;
    if (f == "NONE") {
      const int v = addCompressedView(&doc, encodeVertices(mesh.normals.data(), n, 12), n, 12, "ATTRIBUTES", "NONE",
                                      &fallback);
      accessor = doc.addAccessor(v, kFloat, false, n, "VEC3");
    } else {
      // Octahedral: 8-bit components in 4 bytes; quaternion: a (x, y, z, 0) quaternion in 8 bytes.
      std::vector<float> four(n * 4, 0.0f);
      for (size_t i = 0; i < n; ++i) std::memcpy(&four[4 * i], &mesh.normals[3 * i], 12);
      const size_t stride = f == "OCTAHEDRAL" ? 4 : 8;
      std::vector<uint8_t> filtered(n * stride);
      if (f == "OCTAHEDRAL") meshopt_encodeFilterOct(filtered.data(), n, stride, 8, four.data());
      else meshopt_encodeFilterQuat(filtered.data(), n, stride, 16, four.data());
      const int v = addCompressedView(&doc, encodeVertices(filtered.data(), n, stride), n, stride, "ATTRIBUTES",
                                      o.normalFilter, &fallback);
      accessor = doc.addAccessor(v, f == "OCTAHEDRAL" ? kByte : kShort, true, n, "VEC3");
      doc.use("KHR_mesh_quantization", true);
    }
    prim["attributes"]["NORMAL"] = accessor;
  }
  const size_t ni = mesh.indices.size();
  std::vector<uint8_t> idx(o.indexSequence ? meshopt_encodeIndexSequenceBound(ni, n) : meshopt_encodeIndexBufferBound(ni, n));
  idx.resize(o.indexSequence ? meshopt_encodeIndexSequence(idx.data(), idx.size(), mesh.indices.data(), ni)
                             : meshopt_encodeIndexBuffer(idx.data(), idx.size(), mesh.indices.data(), ni));
  const int iv = addCompressedView(&doc, idx, ni, 4, o.indexSequence ? "INDICES" : "TRIANGLES", "NONE", &fallback);
  prim["indices"] = doc.addAccessor(iv, kUInt, false, ni, "SCALAR");
  doc.json["buffers"].push_back({{"byteLength", fallback}, {"extensions", {{"EXT_meshopt_compression", {{"fallback", true}}}}}});
  const float t[3] = {0, 0, 0}, s[3] = {1, 1, 1};
  doc.addMeshNode(prim, t, s);
  return doc;
}

}  // namespace vff::bake::gltftest
