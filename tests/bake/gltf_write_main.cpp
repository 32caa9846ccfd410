// vff_gltf_write - glTF files for gltf_tests.sh and gltf_fields_tests.sh, and a look into the fields
// a glTF file carries.
//
//   vff_gltf_write MESH KIND OUT.glb         one mesh as a glTF binary. MESH: a procedural shape
//       (vff-procedural-mesh's names) or a mesh file (loadMesh). KIND: plain, quantized (16-bit
//       normalized positions), draco (sequential: the vertices in order), draco-edgebreaker,
//       draco-q14 (positions quantized to 14 bits: the vertices move slightly), moved (plain, its
//       vertices moved by +0.5 in x), meshopt (index sequence: the indices in order),
//       meshopt-filters (EXPONENTIAL positions, OCTAHEDRAL normals).
//   vff_gltf_write scene OUT.glb|OUT.gltf A B   two meshes placed by four nodes: A at node 0 and
//       at node 1 (rotated, scaled by 2), B at node 2 and at node 3 (scaled 1, 2, 1: not a
//       similarity). A .gltf gets its buffer in OUT.bin and an image OUT.png beside it.
//   vff_gltf_write read FILE                 readGltfFields' report as JSON on stdout (exit 2 when
//       the file cannot be read)
//   vff_gltf_write extract FILE MESH OUT.vff  the payload of mesh MESH's field
//   vff_gltf_write attach BASE FROM OUT.glb  BASE as a .glb with the fields FROM carries, each on the
//       mesh of the same index (packGlbWithFields)
// Exit 1 on a usage or I/O error.
#include <cstdio>
#include <fstream>
#include <string>

#include "gltf_writer.h"
#include "vff/bake/gltf_fields.h"
#include "vff/bake/procedural.h"

namespace {

using namespace vff::bake;
using namespace vff::bake::gltftest;

int fail(const std::string& what) {
  std::fprintf(stderr, "vff_gltf_write: error: %s\n", what.c_str());
  return 1;
}

// A mesh file (a name with a '.') or a procedural shape.
bool meshOf(const std::string& name, Mesh* out) {
  if (name.find('.') == std::string::npos) {
    *out = makeShape(name);
    return !out->positions.empty();
  }
  auto m = loadMesh(name);
  if (!m) {
    std::fprintf(stderr, "vff_gltf_write: %s\n", m.error().message.c_str());
    return false;
  }
  *out = std::move(*m);
  return true;
}

bool writeBytes(const std::string& path, const std::vector<uint8_t>& b) {
  std::ofstream out(path, std::ios::binary);
  out.write(reinterpret_cast<const char*>(b.data()), std::streamsize(b.size()));
  return bool(out);
}

int single(const std::string& shape, const std::string& kind, const std::string& out) {
  Mesh mesh;
  if (!meshOf(shape, &mesh)) return fail("no mesh '" + shape + "'");
  GltfDoc doc;
  if (kind == "plain") doc = makeGltf(mesh, {});
  else if (kind == "moved") {
    for (size_t i = 0; i < mesh.positions.size(); i += 3) mesh.positions[i] += 0.5f;
    doc = makeGltf(mesh, {});
  } else if (kind == "quantized") doc = makeGltf(mesh, {kUShort, true, kShort});
  else if (kind == "draco") doc = makeDracoGltf(mesh, true);
  else if (kind == "draco-edgebreaker") doc = makeDracoGltf(mesh, false);
  else if (kind == "draco-q14") doc = makeDracoGltf(mesh, true, 14);
  else if (kind == "meshopt" || kind == "meshopt-filters") {
    Meshopt o;
    o.indexSequence = kind == "meshopt";
    o.exponentialPositions = kind == "meshopt-filters";
    o.normalFilter = kind == "meshopt-filters" ? "OCTAHEDRAL" : "NONE";
    doc = makeMeshoptGltf(mesh, o);
  } else {
    return fail("unknown kind '" + kind + "'");
  }
  if (!save(doc, out, true)) return fail("cannot write " + out);
  return 0;
}

int scene(const std::string& out, const std::string& a, const std::string& b) {
  Mesh ma, mb;
  if (!meshOf(a, &ma) || !meshOf(b, &mb)) return fail("cannot read the meshes");
  GltfDoc doc;
  addMesh(doc, ma, "A");
  addMesh(doc, mb, "B");
  doc.json["nodes"] = {
      {{"name", "A"}, {"mesh", 0}, {"translation", {-3, 0, 0}}},
      {{"name", "A-turned"}, {"mesh", 0}, {"translation", {3, 0, 0}}, {"rotation", {0, 0.70710678, 0, 0.70710678}},
       {"scale", {2, 2, 2}}},
      {{"name", "B"}, {"mesh", 1}, {"translation", {0, 0, 4}}},
      {{"name", "B-stretched"}, {"mesh", 1}, {"translation", {0, 0, -4}}, {"scale", {1, 2, 1}}}};
  doc.json["scenes"] = {{{"nodes", {0, 1, 2, 3}}}};
  doc.json["scene"] = 0;
  const bool glb = out.size() > 4 && out.compare(out.size() - 4, 4, ".glb") == 0;
  if (!glb) {  // an image beside it, which a packed .glb embeds
    const size_t dot = out.find_last_of('.');
    const std::string png = out.substr(0, dot) + ".png";
    const std::vector<uint8_t> bytes = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n', 1, 2, 3, 4, 5};
    if (!writeBytes(png, bytes)) return fail("cannot write " + png);
    const size_t slash = png.find_last_of('/');
    doc.json["images"] = {{{"uri", slash == std::string::npos ? png : png.substr(slash + 1)}}};
  }
  if (!save(doc, out, glb)) return fail("cannot write " + out);
  return 0;
}

int read(const std::string& path) {
  auto r = readGltfFields(path);
  if (!r) {
    std::fprintf(stderr, "vff_gltf_write: %s\n", r.error().message.c_str());
    return 2;
  }
  nlohmann::json j = {{"meshes", r->meshCount}, {"fields", nlohmann::json::array()}, {"problems", nlohmann::json::array()}};
  for (const GltfField& f : r->fields) {
    nlohmann::json nodes = nlohmann::json::array();
    for (const GltfFieldNode& n : f.nodes) nodes.push_back({{"node", n.node}, {"answered", n.answered}, {"reason", n.reason}});
    j["fields"].push_back({{"mesh", f.mesh}, {"name", f.meshName}, {"bufferView", f.bufferView}, {"uri", f.uri},
                           {"valid", f.valid}, {"usable", f.usable()}, {"match", gltfFieldMatchName(f.match)},
                           {"geometryHash", f.geometryHash}, {"meshGeometryHash", f.meshGeometryHash},
                           {"bytes", f.bytes.size()}, {"min", f.min}, {"max", f.max}, {"meshMin", f.meshMin},
                           {"meshMax", f.meshMax}, {"tolerance", f.tolerance}, {"boundsDifference", f.boundsDifference},
                           {"nodes", nodes}});
  }
  for (const GltfFieldProblem& p : r->problems)
    j["problems"].push_back({{"rule", int(p.rule)}, {"name", gltfFieldRuleName(p.rule)},
                             {"severity", gltfSeverityName(p.severity)}, {"path", p.path}, {"message", p.format(path)}});
  std::printf("%s\n", j.dump(1).c_str());
  return 0;
}

int extract(const std::string& path, int mesh, const std::string& out) {
  auto r = readGltfFields(path);
  if (!r) return fail(r.error().message);
  for (const GltfField& f : r->fields)
    if (f.mesh == mesh && f.valid) return writeBytes(out, f.bytes) ? 0 : fail("cannot write " + out);
  return fail(path + ": mesh " + std::to_string(mesh) + " has no valid field");
}

int attach(const std::string& base, const std::string& from, const std::string& out) {
  auto r = readGltfFields(from, {.checkGeometry = false});
  if (!r) return fail(r.error().message);
  std::vector<GltfFieldPayload> payloads;
  for (const GltfField& f : r->fields) {
    if (!f.valid) return fail(from + ": mesh " + std::to_string(f.mesh) + "'s field is not valid");
    payloads.push_back({f.mesh, f.bytes, "", f.geometryHash, f.min, f.max});
  }
  auto glb = packGlbWithFields(base, payloads);
  if (!glb) return fail(glb.error().message);
  return writeBytes(out, *glb) ? 0 : fail("cannot write " + out);
}

}  // namespace

int main(int argc, char** argv) {
  const std::string mode = argc > 1 ? argv[1] : "";
  if (mode == "scene" && argc == 5) return scene(argv[2], argv[3], argv[4]);
  if (mode == "read" && argc == 3) return read(argv[2]);
  if (mode == "extract" && argc == 5) return extract(argv[2], std::atoi(argv[3]), argv[4]);
  if (mode == "attach" && argc == 5) return attach(argv[2], argv[3], argv[4]);
  if (argc == 4 && mode != "scene" && mode != "read" && mode != "extract" && mode != "attach")
    return single(argv[1], argv[2], argv[3]);
  std::fprintf(stderr,
               "usage: vff_gltf_write MESH KIND OUT.glb | scene OUT A B | read FILE | extract FILE MESH OUT.vff | "
               "attach BASE FROM OUT.glb\n");
  return 1;
}
