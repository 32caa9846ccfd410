// OBJ, PLY, OFF and STL through OpenMesh.
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <OpenMesh/Core/IO/importer/ImporterT.hh>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>
#include <OpenMesh/Core/System/omstream.hh>

#include <cctype>
#include <cstring>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <vector>
#include <sstream>
#include <string>

#include "mesh_importers.h"

namespace vff::bake::detail {
namespace {

// OpenMesh's OBJ reader writes through invalid handles when a face refers to a vertex or normal
// that does not exist, or a face token is malformed (found by tests/fuzz, fuzz_mesh: a heap
// overflow in set_normal). Every face token is checked first: v, v/vt, v//vn or v/vt/vn, integers,
// each index within the elements declared before it (negative indices count back from there),
// counting only the v/vt/vn lines whose numbers parse, as OpenMesh does.
Status checkObjFaces(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(Code::kIoOpen, path + ": cannot open");
  int64_t count[3] = {0, 0, 0};  // v, vt, vn so far
  std::string line;
  auto fail = [&](int64_t n, const std::string& why) {
    return makeError(Code::kMeshParse, path + ": line " + std::to_string(n) + ": " + why);
  };
  for (int64_t n = 1; std::getline(in, line); ++n) {
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    // Count the elements as OpenMesh does: a line whose numbers do not parse adds nothing.
    float x = 0, y = 0, z = 0;
    if (keyword == "v" && (words >> x >> y >> z)) ++count[0];
    else if (keyword == "vt" && (words >> x >> y)) ++count[1];
    else if (keyword == "vn" && (words >> x >> y >> z)) ++count[2];
    if (keyword != "f") continue;
    std::string token;
    int corners = 0;
    while (words >> token) {
      ++corners;
      size_t pos = 0;
      for (int part = 0; part < 3 && pos <= token.size(); ++part) {
        const size_t slash = token.find('/', pos);
        const std::string field = token.substr(pos, slash == std::string::npos ? std::string::npos : slash - pos);
        if (!field.empty() || part == 0) {
          size_t used = 0;
          long long index = 0;
          try {
            index = std::stoll(field, &used);
          } catch (const std::exception&) {
            return fail(n, "face corner '" + token.substr(0, 32) + "' is not v, v/vt, v//vn or v/vt/vn");
          }
          if (used != field.size())
            return fail(n, "face corner '" + token.substr(0, 32) + "' is not v, v/vt, v//vn or v/vt/vn");
          const int64_t resolved = index < 0 ? count[part] + index + 1 : index;
          if (resolved < 1 || resolved > count[part])
            return fail(n, "face index " + std::to_string(index) + " refers to a " +
                               (part == 0 ? "vertex" : part == 1 ? "texture coordinate" : "normal") +
                               " that does not exist (" + std::to_string(count[part]) + " so far)");
        }
        if (slash == std::string::npos) break;
        pos = slash + 1;
        if (part == 2) return fail(n, "face corner '" + token.substr(0, 32) + "' has more than three parts");
      }
    }
    if (corners < 3) return fail(n, "a face needs at least three corners");
  }
  return {};
}

// OpenMesh's OFF reader trusts the counts it reads: a garbled face line can make it allocate
// without bound (found by tests/fuzz, fuzz_mesh: out of memory). The file is checked first: the
// "OFF" keyword (the variants with colours, normals or texture coordinates, and binary OFF, are
// not supported), the counts, every vertex line (three numbers), every face line (a corner count
// from 3 to 1024, then that many indices of existing vertices).
Status checkOff(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(Code::kIoOpen, path + ": cannot open");
  std::string line;
  int64_t n = 0;
  auto bad = [&](const std::string& why) {
    return makeError(Code::kMeshParse, path + ": line " + std::to_string(n) + ": " + why);
  };
  // The next line that is not empty or a comment, split into words.
  auto next = [&](std::vector<std::string>* words) {
    while (std::getline(in, line)) {
      ++n;
      const size_t hash = line.find('#');
      if (hash != std::string::npos) line.resize(hash);
      std::istringstream ws(line);
      words->clear();
      for (std::string w; ws >> w;) words->push_back(w);
      if (!words->empty()) return true;
    }
    return false;
  };
  auto integer = [](const std::string& w, int64_t lo, int64_t hi, int64_t* out) {
    if (w.empty() || w.size() > 12 || w.find_first_not_of("0123456789") != std::string::npos) return false;
    *out = std::stoll(w);
    return *out >= lo && *out <= hi;
  };
  auto number = [](const std::string& w) {
    std::istringstream ws(w);
    float f = 0;
    return bool(ws >> f) && ws.peek() == EOF;
  };
  std::vector<std::string> w;
  if (!next(&w)) return makeError(Code::kMeshEmpty, path + ": empty OFF file");
  if (w[0] != "OFF") {
    if (w[0].size() > 3 && w[0].compare(w[0].size() - 3, 3, "OFF") == 0)
      return makeError(Code::kMeshUnsupported, path + ": line " + std::to_string(n) + ": OFF variant '" +
                                                   w[0].substr(0, 16) + "' is not supported (plain OFF only)");
    return bad("not an OFF file (no 'OFF' keyword)");
  }
  if (w.size() > 1 && w[1] == "BINARY")
    return makeError(Code::kMeshUnsupported, path + ": binary OFF is not supported");
  // OpenMesh reads the counts from the line after the keyword only.
  if (w.size() > 1) return bad("the counts must be on their own line after 'OFF'");
  std::vector<std::string> counts;
  if (!next(&counts)) return bad("missing the vertex and face counts");
  int64_t nv = 0, nf = 0, ne = 0;
  constexpr int64_t kMax = 100000000;
  if (counts.size() < 2 || !integer(counts[0], 0, kMax, &nv) || !integer(counts[1], 0, kMax, &nf) ||
      (counts.size() > 2 && !integer(counts[2], 0, INT64_MAX / 2, &ne)))
    return bad("the counts line is not 'VERTICES FACES EDGES' (non-negative integers up to 10^8)");
  for (int64_t v = 0; v < nv; ++v) {
    if (!next(&w)) return bad("the file ends after " + std::to_string(v) + " of " + std::to_string(nv) + " vertices");
    if (w.size() < 3 || !number(w[0]) || !number(w[1]) || !number(w[2])) return bad("a vertex needs three numbers");
  }
  for (int64_t f = 0; f < nf; ++f) {
    if (!next(&w)) return bad("the file ends after " + std::to_string(f) + " of " + std::to_string(nf) + " faces");
    int64_t corners = 0;
    if (!integer(w[0], 3, 1024, &corners)) return bad("a face must start with its corner count (3 to 1024)");
    if (int64_t(w.size()) < 1 + corners) return bad("the face has fewer indices than its corner count");
    for (int64_t c = 1; c <= corners; ++c) {
      int64_t index = 0;
      if (!integer(w[size_t(c)], 0, nv - 1, &index))
        return bad("face index '" + w[size_t(c)].substr(0, 16) + "' is not a vertex (0 to " + std::to_string(nv - 1) + ")");
    }
  }
  return {};
}

// A binary STL is an 80-byte header, a u32 triangle count N and N records of 50 bytes; OpenMesh
// takes a file whose size is not 84 + 50 N for ASCII and reads no triangle from it, so a header
// that claims 10^9 triangles over a short body would end as "no triangles". A file that does not
// start with "solid" (ASCII) must have the size its count gives.
Status checkStl(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return makeError(Code::kIoOpen, path + ": cannot open");
  unsigned char head[84] = {};
  in.read(reinterpret_cast<char*>(head), sizeof head);
  const uint64_t got = uint64_t(in.gcount());
  size_t first = 0;
  while (first < got && std::isspace(head[first])) ++first;
  if (got - first >= 5 && std::memcmp(head + first, "solid", 5) == 0) return {};  // ASCII (or binary named so)
  if (got < 84)
    return makeError(Code::kMeshParse, path + ": " + std::to_string(got) +
                                           " bytes: not an ASCII STL (no 'solid') and shorter than a binary STL header");
  in.clear();
  in.seekg(0, std::ios::end);
  const uint64_t size = uint64_t(in.tellg());
  const uint64_t n = uint64_t(head[80]) | uint64_t(head[81]) << 8 | uint64_t(head[82]) << 16 | uint64_t(head[83]) << 24;
  if (size != 84 + 50 * n)
    return makeError(Code::kMeshParse, path + ": binary STL header claims " + std::to_string(n) + " triangles (" +
                                           std::to_string(84 + 50 * n) + " bytes), the file has " +
                                           std::to_string(size) + " bytes");
  return {};
}

using TriMesh = OpenMesh::TriMesh_ArrayKernelT<>;

// Builds the mesh of a strip PLY through OpenMesh's importer, as its PLY reader does for a face
// list (a non-manifold face gets its own vertices), so both give the same mesh.
void importTriangles(const PlyTriangles& t, TriMesh* tm, OpenMesh::IO::Options* opt) {
  OpenMesh::IO::ImporterT<TriMesh> importer(*tm);
  const bool normals = !t.normals.empty();
  for (size_t v = 0; v < t.positions.size(); v += 3) {
    const auto vh = importer.add_vertex(OpenMesh::Vec3f(t.positions[v], t.positions[v + 1], t.positions[v + 2]));
    if (normals) importer.set_normal(vh, OpenMesh::Vec3f(t.normals[v], t.normals[v + 1], t.normals[v + 2]));
  }
  OpenMesh::IO::BaseImporter::VHandles face(3);
  for (size_t i = 0; i < t.triangles.size(); i += 3) {
    for (int k = 0; k < 3; ++k) face[size_t(k)] = OpenMesh::VertexHandle(int(t.triangles[i + size_t(k)]));
    importer.add_face(face);
  }
  *opt = normals ? OpenMesh::IO::Options::VertexNormal : OpenMesh::IO::Options::Default;
}

}  // namespace

Result<Mesh> loadWithOpenMesh(const std::string& path, const std::string& ext) {
  // OpenMesh's streams (omerr, omlog, omout: their targets are process-wide vectors) and its reader
  // registry are not thread-safe, and callers load meshes on several threads (vff-library hashes
  // its entries in parallel): one load at a time goes through OpenMesh.
  static std::mutex openMesh;
  const std::lock_guard<std::mutex> lock(openMesh);
  // OpenMesh reports through global streams; the importer's own errors carry the message.
  omerr().disable();
  omlog().disable();
  omout().disable();
  std::optional<PlyTriangles> strips;
  if (ext == "ply") {
    if (Status s = checkPly(path, &strips); !s) return s.error();
  } else if (ext == "obj") {
    if (Status s = checkObjFaces(path); !s) return s.error();
  } else if (ext == "off") {
    if (Status s = checkOff(path); !s) return s.error();
  } else if (ext == "stl") {
    if (Status s = checkStl(path); !s) return s.error();
  }
  TriMesh tm;
  tm.request_vertex_normals();
  OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexNormal;
  bool ok = false;
  try {
    if (strips) {
      importTriangles(*strips, &tm, &opt);
      ok = true;
    } else {
      ok = OpenMesh::IO::read_mesh(tm, path, opt);
    }
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
