// KHR_draco_mesh_compression through Debian's libdraco (its static library: the shared one exports
// a copy of tinygltf's symbols that would clash with the tinygltf this importer is built against).
// Each compressed primitive is decoded once; its indices and its POSITION and NORMAL attributes
// then refer to new accessors over buffers holding the decoded data, so that the importer reads
// them like any other. The other attributes are not needed for baking and stay as they are.
#include <draco/compression/decode.h>

#include <cstring>

#include "gltf_extensions.h"

namespace vff::bake::detail {
namespace {

constexpr const char* kDraco = "KHR_draco_mesh_compression";

int addBuffer(tinygltf::Model* model, std::vector<unsigned char> bytes) {
  tinygltf::Buffer b;
  b.data = std::move(bytes);
  model->buffers.push_back(std::move(b));
  tinygltf::BufferView v;
  v.buffer = int(model->buffers.size()) - 1;
  v.byteLength = model->buffers.back().data.size();
  model->bufferViews.push_back(v);
  return int(model->bufferViews.size()) - 1;
}

int addAccessor(tinygltf::Model* model, int view, int componentType, bool normalized, size_t count, int type) {
  tinygltf::Accessor a;
  a.bufferView = view;
  a.componentType = componentType;
  a.normalized = normalized;
  a.count = count;
  a.type = type;
  model->accessors.push_back(a);
  return int(model->accessors.size()) - 1;
}

template <typename T>
bool convertPoints(const draco::Mesh& mesh, const draco::PointAttribute& att, std::vector<unsigned char>* out) {
  const size_t n = mesh.num_points();
  out->resize(n * 3 * sizeof(T));
  T v[3];
  for (uint32_t i = 0; i < n; ++i) {
    if (!att.ConvertValue<T>(att.mapped_index(draco::PointIndex(i)), 3, v)) return false;
    std::memcpy(out->data() + size_t(i) * sizeof(v), v, sizeof(v));
  }
  return true;
}

// The decoded VEC3 attribute in the component type its glTF accessor declares.
Status decodeAttribute(tinygltf::Model* model, const draco::Mesh& mesh, const tinygltf::Value& attributes,
                       const std::string& semantic, const std::string& what, tinygltf::Primitive* p) {
  auto it = p->attributes.find(semantic);
  if (it == p->attributes.end() || !attributes.Has(semantic)) return {};
  const tinygltf::Value& id = attributes.Get(semantic);
  if (!id.IsInt() || id.Get<int>() < 0)
    return makeError(Code::kMeshParse, what + ": the Draco attribute id of " + semantic + " is not an integer");
  const draco::PointAttribute* att = mesh.GetAttributeByUniqueId(uint32_t(id.Get<int>()));
  if (!att || att->num_components() < 3)
    return makeError(Code::kMeshParse, what + ": the Draco data has no 3-component attribute " +
                                           std::to_string(id.Get<int>()) + " for " + semantic);
  if (it->second < 0 || size_t(it->second) >= model->accessors.size())
    return makeError(Code::kMeshIndex, what + " " + semantic + ": accessor out of range");
  const tinygltf::Accessor& declared = model->accessors[size_t(it->second)];
  std::vector<unsigned char> bytes;
  bool ok = false;
  switch (declared.componentType) {
    case TINYGLTF_COMPONENT_TYPE_FLOAT: ok = convertPoints<float>(mesh, *att, &bytes); break;
    case TINYGLTF_COMPONENT_TYPE_BYTE: ok = convertPoints<int8_t>(mesh, *att, &bytes); break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE: ok = convertPoints<uint8_t>(mesh, *att, &bytes); break;
    case TINYGLTF_COMPONENT_TYPE_SHORT: ok = convertPoints<int16_t>(mesh, *att, &bytes); break;
    case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: ok = convertPoints<uint16_t>(mesh, *att, &bytes); break;
    default: break;
  }
  if (!ok)
    return makeError(Code::kMeshUnsupported, what + " " + semantic + ": Draco data cannot be read as component type " +
                                                 std::to_string(declared.componentType));
  const int view = addBuffer(model, std::move(bytes));
  it->second = addAccessor(model, view, declared.componentType, declared.normalized, mesh.num_points(),
                           TINYGLTF_TYPE_VEC3);
  return {};
}

Status decodePrimitive(tinygltf::Model* model, tinygltf::Primitive* p, const std::string& what) {
  const tinygltf::Value& ext = p->extensions.at(kDraco);
  const tinygltf::Value& viewValue = ext.Get("bufferView");
  const tinygltf::Value& attributes = ext.Get("attributes");
  if (!ext.IsObject() || !viewValue.IsInt() || !attributes.IsObject())
    return makeError(Code::kMeshParse, what + ": " + kDraco + " needs an integer bufferView and an attributes object");
  const int vi = viewValue.Get<int>();
  if (vi < 0 || size_t(vi) >= model->bufferViews.size())
    return makeError(Code::kMeshIndex, what + ": " + kDraco + " bufferView " + std::to_string(vi) + " out of range");
  const tinygltf::BufferView& bv = model->bufferViews[size_t(vi)];
  if (bv.buffer < 0 || size_t(bv.buffer) >= model->buffers.size())
    return makeError(Code::kMeshIndex, what + ": the Draco bufferView references a missing buffer");
  const std::vector<unsigned char>& data = model->buffers[size_t(bv.buffer)].data;
  if (bv.byteOffset > data.size() || bv.byteLength > data.size() - bv.byteOffset)
    return makeError(Code::kMeshIndex, what + ": the Draco bufferView reaches outside its buffer");
  draco::DecoderBuffer in;
  in.Init(reinterpret_cast<const char*>(data.data() + bv.byteOffset), bv.byteLength);
  draco::Decoder decoder;
  auto decoded = decoder.DecodeMeshFromBuffer(&in);
  if (!decoded.ok())
    return makeError(Code::kMeshParse, what + ": Draco data cannot be decoded: " + decoded.status().error_msg_string());
  const draco::Mesh& mesh = *decoded.value();
  for (const char* semantic : {"POSITION", "NORMAL"}) {
    Status s = decodeAttribute(model, mesh, attributes, semantic, what, p);
    if (!s) return s;
  }
  std::vector<unsigned char> idx(size_t(mesh.num_faces()) * 3 * sizeof(uint32_t));
  for (uint32_t f = 0; f < mesh.num_faces(); ++f)
    for (size_t k = 0; k < 3; ++k) {
      const uint32_t v = mesh.face(draco::FaceIndex(f))[k].value();
      std::memcpy(idx.data() + (size_t(f) * 3 + k) * 4, &v, 4);
    }
  const size_t count = idx.size() / 4;
  p->indices = addAccessor(model, addBuffer(model, std::move(idx)), TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT, false,
                           count, TINYGLTF_TYPE_SCALAR);
  p->mode = TINYGLTF_MODE_TRIANGLES;
  p->extensions.erase(kDraco);
  return {};
}

}  // namespace

Status decodeDracoPrimitives(tinygltf::Model* model, const std::string& path) {
  for (tinygltf::Mesh& m : model->meshes)
    for (size_t pi = 0; pi < m.primitives.size(); ++pi) {
      tinygltf::Primitive& p = m.primitives[pi];
      if (p.extensions.count(kDraco) == 0) continue;
      const std::string what = path + ": mesh '" + m.name + "' primitive " + std::to_string(pi);
      // The Draco stream's own counts size the decoder's allocations: a corrupt one can ask for
      // more than there is, which is the file's fault, not a crash.
      try {
        Status s = decodePrimitive(model, &p, what);
        if (!s) return s;
      } catch (const std::exception& e) {
        return makeError(Code::kMeshParse, what + ": Draco data cannot be decoded: " + e.what());
      }
    }
  return {};
}

}  // namespace vff::bake::detail
