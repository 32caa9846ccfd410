// OBJ, PLY, OFF and STL through OpenMesh.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include "mesh_importers.h"

namespace vff::bake::detail {

Result<Mesh> loadWithOpenMesh(const std::string& path, const std::string& ext) {
  using TriMesh = OpenMesh::TriMesh_ArrayKernelT<>;
  // OpenMesh reports through global streams; the importer's own errors carry the message.
  omerr().disable();
  omlog().disable();
  omout().disable();
  TriMesh tm;
  tm.request_vertex_normals();
  OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexNormal;
  bool ok = false;
  try {
    ok = OpenMesh::IO::read_mesh(tm, path, opt);
  } catch (const std::exception& e) {
    return makeError(Code::kMeshParse, path + ": " + e.what());
  }
  if (!ok) return makeError(Code::kMeshParse, path + ": OpenMesh cannot parse this " + ext + " file");
  Mesh m;
  m.positions.reserve(tm.n_vertices() * 3);
  for (auto v : tm.vertices()) {
    const auto& p = tm.point(v);
    m.positions.insert(m.positions.end(), {p[0], p[1], p[2]});
  }
  if (opt.check(OpenMesh::IO::Options::VertexNormal)) {
    m.normals.reserve(tm.n_vertices() * 3);
    for (auto v : tm.vertices()) {
      const auto& n = tm.normal(v);
      m.normals.insert(m.normals.end(), {n[0], n[1], n[2]});
    }
  }
  m.indices.reserve(tm.n_faces() * 3);
  for (auto f : tm.faces())
    for (auto v : tm.fv_range(f)) m.indices.push_back(uint32_t(v.idx()));
  if (m.indices.size() != tm.n_faces() * 3) return makeError(Code::kMeshParse, path + ": a face is not a triangle");
  return m;
}

}  // namespace vff::bake::detail
