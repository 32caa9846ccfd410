// glTF 2.0 (.gltf and .glb) through tinygltf: parsing, and the triangles of meshes (which meshes and
// where: gltf_scene.cpp).
#include <fcntl.h>
#include <sys/stat.h>
#include <tiny_gltf.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "gltf_extensions.h"
#include "mesh_importers.h"

namespace vff::bake::detail {
namespace {

using Mat4 = GltfMatrix;

// Inverse transpose of the upper 3x3 (for normals), row-major 3x3.
std::array<double, 9> normalMatrix(const Mat4& m) {
  const double a = m[0], b = m[4], c = m[8], d = m[1], e = m[5], f = m[9], g = m[2], h = m[6], i = m[10];
  const double A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
  const double D = -(b * i - c * h), E = a * i - c * g, F = -(a * h - b * g);
  const double G = b * f - c * e, H = -(a * f - c * d), I = a * e - b * d;
  // inverse = adj / det; transpose of inverse = cofactor matrix / det.
  const double det = a * A + b * B + c * C;
  const double s = det != 0 ? 1.0 / det : 0.0;
  return {A * s, B * s, C * s, D * s, E * s, F * s, G * s, H * s, I * s};
}

class Importer {
 public:
  Importer(const tinygltf::Model& model, const std::string& path) : model_(model), path_(path) {}

  Status mesh(const tinygltf::Mesh& mesh, const Mat4& world, bool skipNonTriangles) {
    for (size_t pi = 0; pi < mesh.primitives.size(); ++pi) {
      const tinygltf::Primitive& p = mesh.primitives[pi];
      const std::string where = path_ + ": mesh '" + mesh.name + "' primitive " + std::to_string(pi);
      const int mode = p.mode < 0 ? TINYGLTF_MODE_TRIANGLES : p.mode;
      const bool triangles =
          mode == TINYGLTF_MODE_TRIANGLES || mode == TINYGLTF_MODE_TRIANGLE_STRIP || mode == TINYGLTF_MODE_TRIANGLE_FAN;
      if (!triangles && skipNonTriangles) continue;
      if (!triangles)
        return makeError(Code::kMeshUnsupported, where + " has mode " + std::to_string(mode) +
                                                     " (points or lines), not triangles");
      auto pos = p.attributes.find("POSITION");
      if (pos == p.attributes.end()) return makeError(Code::kMeshUnsupported, where + " has no POSITION");
      std::vector<float> xyz;
      Status s = readVec3(pos->second, where + " POSITION", &xyz);
      if (!s) return s;
      std::vector<float> nrm;
      auto nit = p.attributes.find("NORMAL");
      if (nit != p.attributes.end()) {
        s = readVec3(nit->second, where + " NORMAL", &nrm, true);
        if (!s) return s;
        if (nrm.size() != xyz.size()) nrm.clear();
      }
      const size_t count = xyz.size() / 3;
      std::vector<uint32_t> idx;
      if (p.indices >= 0) {
        s = readIndices(p.indices, where + " indices", count, &idx);
        if (!s) return s;
      } else {
        idx.resize(count);
        for (size_t i = 0; i < count; ++i) idx[i] = uint32_t(i);
      }
      const uint32_t base = uint32_t(out.positions.size() / 3);
      for (size_t v = 0; v < count; ++v) {
        const double x = xyz[3 * v], y = xyz[3 * v + 1], z = xyz[3 * v + 2];
        out.positions.push_back(float(world[0] * x + world[4] * y + world[8] * z + world[12]));
        out.positions.push_back(float(world[1] * x + world[5] * y + world[9] * z + world[13]));
        out.positions.push_back(float(world[2] * x + world[6] * y + world[10] * z + world[14]));
      }
      if (nrm.empty()) {
        allNormals_ = false;
      } else {
        const auto nm = normalMatrix(world);
        for (size_t v = 0; v < count; ++v) {
          const double x = nrm[3 * v], y = nrm[3 * v + 1], z = nrm[3 * v + 2];
          normals_.push_back(float(nm[0] * x + nm[1] * y + nm[2] * z));
          normals_.push_back(float(nm[3] * x + nm[4] * y + nm[5] * z));
          normals_.push_back(float(nm[6] * x + nm[7] * y + nm[8] * z));
        }
      }
      // Flip winding under a mirroring transform so geometric normals stay outward.
      const bool mirror = (world[0] * (world[5] * world[10] - world[9] * world[6]) -
                           world[4] * (world[1] * world[10] - world[9] * world[2]) +
                           world[8] * (world[1] * world[6] - world[5] * world[2])) < 0;
      auto tri = [&](uint32_t a, uint32_t b, uint32_t c) {
        if (mirror) std::swap(b, c);
        out.indices.insert(out.indices.end(), {base + a, base + b, base + c});
      };
      if (mode == TINYGLTF_MODE_TRIANGLES) {
        for (size_t t = 0; t + 2 < idx.size(); t += 3) tri(idx[t], idx[t + 1], idx[t + 2]);
      } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
        for (size_t t = 0; t + 2 < idx.size(); ++t)
          (t % 2 == 0) ? tri(idx[t], idx[t + 1], idx[t + 2]) : tri(idx[t + 1], idx[t], idx[t + 2]);
      } else {
        for (size_t t = 1; t + 1 < idx.size(); ++t) tri(idx[0], idx[t], idx[t + 1]);
      }
    }
    return {};
  }

  // The bytes an accessor covers, checked against its buffer.
  Status view(int accessor, const std::string& what, size_t elemSize, const uint8_t** data, size_t* stride,
              size_t* count, int* componentType, int* type) {
    if (accessor < 0 || size_t(accessor) >= model_.accessors.size())
      return makeError(Code::kMeshIndex, what + ": accessor " + std::to_string(accessor) + " out of range");
    const tinygltf::Accessor& a = model_.accessors[size_t(accessor)];
    if (a.sparse.isSparse) return makeError(Code::kMeshUnsupported, what + ": sparse accessors are not supported");
    *componentType = a.componentType;
    *type = a.type;
    *count = a.count;
    if (a.bufferView < 0 || size_t(a.bufferView) >= model_.bufferViews.size())
      return makeError(Code::kMeshIndex, what + ": accessor has no valid bufferView");
    const tinygltf::BufferView& bv = model_.bufferViews[size_t(a.bufferView)];
    if (bv.buffer < 0 || size_t(bv.buffer) >= model_.buffers.size())
      return makeError(Code::kMeshIndex, what + ": bufferView references a missing buffer");
    const tinygltf::Buffer& buf = model_.buffers[size_t(bv.buffer)];
    *stride = bv.byteStride ? bv.byteStride : elemSize;
    // Every sum and product is checked for overflow: the counts and offsets are the file's claims
    // (a count of 2^62 + 1 would otherwise wrap to a small byte size).
    uint64_t need = 0;
    const bool huge = a.count != 0 && (__builtin_mul_overflow(uint64_t(*stride), uint64_t(a.count - 1), &need) ||
                                       __builtin_add_overflow(need, uint64_t(elemSize), &need));
    const auto fits = [](uint64_t off, uint64_t size, uint64_t limit) { return off <= limit && size <= limit - off; };
    if (huge || !fits(bv.byteOffset, bv.byteLength, buf.data.size()) || !fits(a.byteOffset, need, bv.byteLength))
      return makeError(Code::kMeshIndex, what + ": accessor of " + std::to_string(a.count) + " elements (stride " +
                                             std::to_string(*stride) + ") reaches outside its " +
                                             std::to_string(buf.data.size()) + "-byte buffer");
    *data = buf.data.data() + bv.byteOffset + a.byteOffset;
    return {};
  }

  Status readVec3(int accessor, const std::string& what, std::vector<float>* out3, bool isNormal = false) {
    const uint8_t* d;
    size_t stride, count;
    int ct, type;
    const bool known = accessor >= 0 && size_t(accessor) < model_.accessors.size();
    const size_t cs = known ? gltfComponentSize(model_.accessors[size_t(accessor)].componentType) : 0;
    Status s = view(accessor, what, 3 * (cs ? cs : 4), &d, &stride, &count, &ct, &type);
    if (!s) return s;
    if (type != TINYGLTF_TYPE_VEC3) return makeError(Code::kMeshUnsupported, what + ": only VEC3 data is supported");
    return convertVec3(d, stride, count, ct, model_.accessors[size_t(accessor)].normalized, isNormal, what, out3);
  }

  Status readIndices(int accessor, const std::string& what, size_t vertexCount, std::vector<uint32_t>* idx) {
    const uint8_t* d;
    size_t stride, count;
    int ct, type;
    const int ctPeek = accessor >= 0 && size_t(accessor) < model_.accessors.size() ? model_.accessors[size_t(accessor)].componentType : 0;
    const size_t es = ctPeek == TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE ? 1 : ctPeek == TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT ? 2 : 4;
    Status s = view(accessor, what, es, &d, &stride, &count, &ct, &type);
    if (!s) return s;
    if (type != TINYGLTF_TYPE_SCALAR ||
        (ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE && ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT &&
         ct != TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT))
      return makeError(Code::kMeshUnsupported, what + ": indices must be unsigned scalar integers");
    idx->resize(count);
    for (size_t i = 0; i < count; ++i) {
      uint32_t v = 0;
      if (es == 1) v = d[i * stride];
      else if (es == 2) { uint16_t t; std::memcpy(&t, d + i * stride, 2); v = t; }
      else std::memcpy(&v, d + i * stride, 4);
      if (v >= vertexCount)
        return makeError(Code::kMeshIndex, what + ": index " + std::to_string(v) + " >= vertex count " + std::to_string(vertexCount));
      (*idx)[i] = v;
    }
    return {};
  }

  Mesh out;
  std::vector<float> normals_;
  bool allNormals_ = true;

 private:
  const tinygltf::Model& model_;
  std::string path_;
};

// tinygltf reads a .gltf's external files (buffers, images) by name, and its own file system
// functions open them the blocking way: a uri naming a FIFO would hang the bake. These two replace
// them. Its test of a name opens the file (fopen): a stat does not.
bool fileExists(const std::string& path, void*) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0;
}

// Refuses what is not a regular file, as the baker refuses its input (checkReadable), and keeps the
// first such name (user: a std::string) for the error.
bool readRegularFile(std::vector<unsigned char>* out, std::string* err, const std::string& path, void* user) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) {
    if (err) *err += "File open error : " + path + "\n";
    return false;
  }
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
    ::close(fd);
    auto* refused = static_cast<std::string*>(user);
    if (refused && refused->empty()) *refused = path;
    if (err) *err += path + ": not a regular file\n";
    return false;
  }
  out->resize(size_t(st.st_size));
  for (size_t done = 0; done < out->size();) {
    const ssize_t n = ::read(fd, out->data() + done, out->size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      ::close(fd);
      if (err) *err += "File read error : " + path + "\n";
      return false;
    }
    done += size_t(n);
  }
  ::close(fd);
  return true;
}

bool skipImages(tinygltf::Image*, const int, std::string*, std::string*, int, int, const unsigned char*, int, void*) {
  return true;  // images are not needed for baking
}

}  // namespace

Result<std::shared_ptr<const tinygltf::Model>> parseGltf(const std::string& path, bool binary,
                                                         std::vector<std::string>* notes) {
  tinygltf::TinyGLTF loader;
  loader.SetImageLoader(skipImages, nullptr);
  std::string refused;  // an external file that is not a regular file (readRegularFile)
  loader.SetFsCallbacks({&fileExists, &tinygltf::ExpandFilePath, &readRegularFile, &tinygltf::WriteWholeFile,
                         &refused});
  auto model = std::make_shared<tinygltf::Model>();
  std::string err, warn;
  bool ok = false;
  std::vector<unsigned char> bytes;
  if (Status pre = prepareGltf(path, binary, &bytes, notes); !pre) return std::move(pre).error();
  try {
    ok = parsePreparedGltf(loader, model.get(), &err, &warn, bytes, path, binary);
  } catch (const std::exception& e) {
    return makeError(Code::kMeshParse, path + ": " + e.what());
  }
  if (!ok && !refused.empty()) return makeError(Code::kIoOpen, path + ": " + refused + ": not a regular file");
  if (!ok) {
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    return makeError(Code::kMeshParse, path + ": " + (err.empty() ? std::string("cannot parse glTF") : err));
  }
  if (Status s = decodeMeshoptViews(model.get(), path); !s) return std::move(s).error();
  if (Status s = decodeDracoPrimitives(model.get(), path); !s) return std::move(s).error();
  return std::shared_ptr<const tinygltf::Model>(std::move(model));
}

Result<Mesh> importGltfMeshes(const tinygltf::Model& model, const std::string& path,
                              const std::vector<GltfMeshRef>& refs) {
  Importer imp(model, path);
  for (const GltfMeshRef& r : refs) {
    if (r.mesh < 0 || size_t(r.mesh) >= model.meshes.size())
      return makeError(Code::kMeshIndex, path + ": mesh index " + std::to_string(r.mesh) + " out of range");
    Status s = imp.mesh(model.meshes[size_t(r.mesh)], r.matrix, r.skipNonTriangles);
    if (!s) return std::move(s).error();
  }
  if (imp.allNormals_ && imp.normals_.size() == imp.out.positions.size()) imp.out.normals = std::move(imp.normals_);
  return std::move(imp.out);
}

}  // namespace vff::bake::detail
