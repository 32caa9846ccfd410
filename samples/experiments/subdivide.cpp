// subdivide.cpp - Loop subdivision and quadric decimation through OpenMesh (subdivide.h).
#include "subdivide.h"

#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>
#include <OpenMesh/Tools/Subdivider/Uniform/LoopT.hh>

namespace vffx {

namespace {

using TriMesh = OpenMesh::TriMesh_ArrayKernelT<>;

vff::Result<TriMesh> toOpenMesh(const vff::bake::Mesh& mesh, uint64_t* dropped) {
  TriMesh m;
  m.request_vertex_status();
  m.request_edge_status();
  m.request_halfedge_status();
  m.request_face_status();
  std::vector<TriMesh::VertexHandle> v(mesh.vertexCount());
  for (size_t i = 0; i < v.size(); ++i)
    v[i] = m.add_vertex({mesh.positions[3 * i], mesh.positions[3 * i + 1], mesh.positions[3 * i + 2]});
  uint64_t lost = 0;
  omerr().disable();  // OpenMesh reports each face it cannot add: counted here instead
  for (size_t t = 0; t < mesh.triangleCount(); ++t)
    lost += !m.add_face(v[mesh.indices[3 * t]], v[mesh.indices[3 * t + 1]], v[mesh.indices[3 * t + 2]]).is_valid();
  omerr().enable();
  if (dropped) *dropped = lost;
  if (m.n_faces() == 0)
    return vff::makeError(vff::Code::kInvalidArgument, "no triangle of the mesh could be added to a manifold mesh");
  m.delete_isolated_vertices();
  m.garbage_collection();
  return m;
}

vff::Result<vff::bake::Mesh> fromOpenMesh(TriMesh& m, const char* what) {
  m.garbage_collection();
  vff::bake::Mesh out;
  out.positions.reserve(3 * m.n_vertices());
  for (const auto vh : m.vertices()) {
    const auto& p = m.point(vh);
    out.positions.insert(out.positions.end(), {p[0], p[1], p[2]});
  }
  out.indices.reserve(3 * m.n_faces());
  for (const auto fh : m.faces())
    for (const auto vh : m.fv_range(fh)) out.indices.push_back(uint32_t(vh.idx()));
  if (vff::Status s = vff::bake::checkMesh(&out, what); !s) return std::move(s).error();
  return out;
}

}  // namespace

vff::Result<vff::bake::Mesh> loopSubdivide(const vff::bake::Mesh& mesh, uint64_t* dropped) {
  auto m = toOpenMesh(mesh, dropped);
  if (!m) return std::move(m).error();
  OpenMesh::Subdivider::Uniform::LoopT<TriMesh> loop;
  loop.attach(*m);
  loop(1);
  loop.detach();
  return fromOpenMesh(*m, "the subdivided mesh");
}

vff::Result<vff::bake::Mesh> decimate(const vff::bake::Mesh& mesh, size_t triangles, uint64_t* dropped) {
  auto m = toOpenMesh(mesh, dropped);
  if (!m) return std::move(m).error();
  {
    OpenMesh::Decimater::DecimaterT<TriMesh> decimater(*m);
    OpenMesh::Decimater::ModQuadricT<TriMesh>::Handle quadric;
    decimater.add(quadric);
    decimater.initialize();
    decimater.decimate_to_faces(0, triangles);
  }
  return fromOpenMesh(*m, "the decimated mesh");
}

}  // namespace vffx
