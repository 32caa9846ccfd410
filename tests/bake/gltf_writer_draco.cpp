// Draco-compressed glTF (KHR_draco_mesh_compression) for the importer's tests, made with Draco's
// own encoder: float attributes without quantization, so the decoded values are the mesh's.
#include <draco/compression/encode.h>
#include <draco/mesh/mesh.h>

#include "gltf_writer.h"

namespace vff::bake::gltftest {
namespace {

int addFloat3(draco::Mesh* dm, draco::GeometryAttribute::Type type, const std::vector<float>& values) {
  draco::GeometryAttribute ga;
  ga.Init(type, nullptr, 3, draco::DT_FLOAT32, false, 12, 0);
  const int id = dm->AddAttribute(ga, true, uint32_t(values.size() / 3));
  for (uint32_t i = 0; i < values.size() / 3; ++i)
    dm->attribute(id)->SetAttributeValue(draco::AttributeValueIndex(i), &values[3 * size_t(i)]);
  return id;
}

}  // namespace

GltfDoc makeDracoGltf(const Mesh& mesh, bool sequential, int positionBits) {
  draco::Mesh dm;
  dm.set_num_points(uint32_t(mesh.vertexCount()));
  const int pos = addFloat3(&dm, draco::GeometryAttribute::POSITION, mesh.positions);
  const int nrm = mesh.normals.empty() ? -1 : addFloat3(&dm, draco::GeometryAttribute::NORMAL, mesh.normals);
  for (size_t t = 0; t < mesh.indices.size(); t += 3)
    dm.AddFace({draco::PointIndex(mesh.indices[t]), draco::PointIndex(mesh.indices[t + 1]),
                draco::PointIndex(mesh.indices[t + 2])});
  draco::Encoder enc;
  enc.SetEncodingMethod(sequential ? draco::MESH_SEQUENTIAL_ENCODING : draco::MESH_EDGEBREAKER_ENCODING);
  if (positionBits > 0) enc.SetAttributeQuantization(draco::GeometryAttribute::POSITION, positionBits);
  draco::EncoderBuffer out;
  if (!enc.EncodeMeshToBuffer(dm, &out).ok()) return {};
  GltfDoc doc;
  doc.use("KHR_draco_mesh_compression", true);
  const int view = doc.addView(out.data(), out.size(), 0);
  // The accessors describe the decoded data and have no buffer view.
  nlohmann::json prim = {{"attributes", {{"POSITION", doc.addAccessor(-1, kFloat, false, mesh.vertexCount(), "VEC3")}}},
                         {"indices", doc.addAccessor(-1, kUInt, false, mesh.indices.size(), "SCALAR")}};
  nlohmann::json ext = {{"bufferView", view}, {"attributes", {{"POSITION", dm.attribute(pos)->unique_id()}}}};
  if (nrm >= 0) {
    prim["attributes"]["NORMAL"] = doc.addAccessor(-1, kFloat, false, mesh.vertexCount(), "VEC3");
    ext["attributes"]["NORMAL"] = dm.attribute(nrm)->unique_id();
  }
  prim["extensions"] = {{"KHR_draco_mesh_compression", ext}};
  const float t[3] = {0, 0, 0}, s[3] = {1, 1, 1};
  doc.addMeshNode(prim, t, s);
  return doc;
}

}  // namespace vff::bake::gltftest
