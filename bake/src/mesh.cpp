#include "vff/bake/mesh.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>
#include <xxhash.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstring>

#include "mesh_importers.h"

namespace vff::bake {
namespace {

std::string lowerExtension(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string e = path.substr(dot + 1);
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e;
}

}  // namespace

Status checkMesh(Mesh* m, const std::string& what) {
  const size_t nv = m->vertexCount();
  if (m->positions.size() % 3 != 0 || m->indices.size() % 3 != 0 ||
      (!m->normals.empty() && m->normals.size() != m->positions.size()))
    return makeError(Code::kMeshParse, what + ": inconsistent vertex or index arrays");
  for (size_t i = 0; i < m->positions.size(); ++i)
    if (!std::isfinite(m->positions[i]))
      return makeError(Code::kMeshNonFinite, what + ": vertex " + std::to_string(i / 3) + " has a non-finite coordinate");
  for (float& v : m->normals)
    if (!std::isfinite(v)) v = 0;  // a bad normal falls back to the geometric normal when baking
  std::vector<uint32_t> kept;
  kept.reserve(m->indices.size());
  for (size_t t = 0; t < m->indices.size(); t += 3) {
    const uint32_t a = m->indices[t], b = m->indices[t + 1], c = m->indices[t + 2];
    if (a >= nv || b >= nv || c >= nv)
      return makeError(Code::kMeshIndex, what + ": triangle " + std::to_string(t / 3) + " references vertex " +
                                             std::to_string(std::max({a, b, c})) + " of " + std::to_string(nv));
    const float* p = m->positions.data();
    const double ux = double(p[3 * b]) - p[3 * a], uy = double(p[3 * b + 1]) - p[3 * a + 1], uz = double(p[3 * b + 2]) - p[3 * a + 2];
    const double vx = double(p[3 * c]) - p[3 * a], vy = double(p[3 * c + 1]) - p[3 * a + 1], vz = double(p[3 * c + 2]) - p[3 * a + 2];
    const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
    if (cx * cx + cy * cy + cz * cz == 0.0) {
      ++m->droppedDegenerate;
      continue;
    }
    kept.insert(kept.end(), {a, b, c});
  }
  if (m->indices.empty()) return makeError(Code::kMeshEmpty, what + ": the mesh has no triangles");
  if (kept.empty())
    return makeError(Code::kMeshDegenerate, what + (m->indices.size() == 3 ? std::string(": its one triangle has zero area")
                                                                            : ": all " + std::to_string(m->indices.size() / 3) +
                                                                                  " triangles have zero area"));
  m->indices.swap(kept);
  return {};
}

uint64_t meshHash(const Mesh& m) {
  XXH3_state_t* s = XXH3_createState();
  XXH3_64bits_reset(s);
  XXH3_64bits_update(s, m.positions.data(), m.positions.size() * sizeof(float));
  XXH3_64bits_update(s, m.indices.data(), m.indices.size() * sizeof(uint32_t));
  const uint64_t h = XXH3_64bits_digest(s);
  XXH3_freeState(s);
  return h;
}

uint64_t geometryHash(const Mesh& m) {
  using Tri = std::array<float, 9>;
  std::vector<Tri> tris(m.triangleCount());
  for (size_t t = 0; t < tris.size(); ++t) {
    std::array<std::array<float, 3>, 3> v;
    for (size_t k = 0; k < 3; ++k)
      for (size_t c = 0; c < 3; ++c) {
        const float x = m.positions[3 * size_t(m.indices[3 * t + k]) + c];
        v[k][c] = x == 0.0f ? 0.0f : x;  // one spelling of zero
      }
    size_t first = 0;
    for (size_t k = 1; k < 3; ++k)
      if (v[k] < v[first]) first = k;
    for (size_t k = 0; k < 3; ++k)
      for (size_t c = 0; c < 3; ++c) tris[t][3 * k + c] = v[(first + k) % 3][c];
  }
  std::sort(tris.begin(), tris.end());
  std::vector<uint8_t> bytes(tris.size() * 36);
  for (size_t t = 0; t < tris.size(); ++t)
    for (size_t i = 0; i < 9; ++i) {
      uint32_t u;
      std::memcpy(&u, &tris[t][i], 4);
      for (size_t b = 0; b < 4; ++b) bytes[36 * t + 4 * i + b] = uint8_t(u >> (8 * b));  // little-endian
    }
  return XXH3_64bits(bytes.data(), bytes.size());
}

namespace detail {
Status checkReadable(const std::string& path, struct stat* st) {
  // Opened (without blocking: a FIFO's open waits for a writer) and then looked at, so that what is
  // checked is what was opened; the importers open it again by name.
  const int fd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC | O_NONBLOCK);
  if (fd < 0) return makeError(Code::kIoOpen, path + ": " + std::strerror(errno));
  const bool statted = ::fstat(fd, st) == 0;
  const int err = errno;
  ::close(fd);
  if (!statted) return makeError(Code::kIoOpen, path + ": " + std::strerror(err));
  if (!S_ISREG(st->st_mode)) return makeError(Code::kIoOpen, path + ": not a regular file");
  return {};
}
}  // namespace detail

Result<Mesh> loadMesh(const std::string& path, MeshInfo* info, const MeshLoadOptions& options) {
  struct stat st {};
  if (Status s = detail::checkReadable(path, &st); !s) return std::move(s).error();
  const std::string ext = lowerExtension(path);
  Result<Mesh> mesh = makeError(Code::kMeshFormat, "");
  if (ext == "obj" || ext == "ply" || ext == "off" || ext == "stl") {
    if (st.st_size == 0) return makeError(Code::kMeshEmpty, path + ": the file is empty");
    mesh = detail::loadWithOpenMesh(path, ext);
  } else if (ext == "gltf" || ext == "glb") {
    mesh = detail::loadWithTinyGltf(path, ext == "glb", options, info);
  } else {
    return makeError(Code::kMeshFormat, path + ": unknown mesh extension '" + ext +
                                            "' (supported: .obj .ply .off .stl .gltf .glb)");
  }
  if (!mesh) return mesh;
  Status s = checkMesh(&*mesh, path);
  if (!s) return std::move(s).error();
  if (info) info->format = ext;
  return mesh;
}

}  // namespace vff::bake
