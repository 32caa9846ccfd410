// gen_gltf.cpp - vff-gltf-gen OUTDIR: the conformance assets of the glTF extension
// VFF_visibility_field (README.md, spec/gltf/VFF_visibility_field/README.md). Every asset is
// written here byte by byte (JSON by nlohmann, the GLB framing by this file), so the vectors do not
// depend on the writer they test. The fields are tiny bakes of procedural shapes (libvff's writer,
// stored blocks; the partial result with vff-bake's own partial options, zstd blocks), so the bytes
// depend only on libvff, the baker, this file and, for the one partial result, libzstd.
//
// manifest.json lists, for each asset, the problems a reader reports (rule, severity, JSON pointer,
// in check order) and the fields it finds (match, usability, hashes, payload size and XXH3-64).
#include <xxhash.h>
#include <zstd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <limits>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "bake_job.h"
#include "vff/bake/baker.h"
#include "vff/bake/mesh.h"
#include "vff/bake/procedural.h"
#include "vff/validate.h"
#include "vff/writer.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vff::gltf_gen {
namespace {

constexpr const char* kExt = "VFF_visibility_field";
constexpr const char* kMediaType = "application/vnd.vff";
constexpr const char* kExtPath = "/extensions/VFF_visibility_field";

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "vff-gltf-gen: %s\n", what.c_str());
  std::exit(1);
}

std::string hex64(uint64_t v) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(v));
  return s;
}

std::string xxh3(const std::vector<uint8_t>& b) {
  return hex64(XXH3_64bits(b.data(), b.size()));
}

// ---- Meshes and their fields ---------------------------------------------------------------------

// A regular tetrahedron off the origin: 4 vertices, 4 triangles.
bake::Mesh tetrahedron() {
  bake::Mesh m;
  m.positions = {0.75f, 1.0f, 0.5f, 0.75f, 0.0f, -0.5f, -0.25f, 1.0f, -0.5f, -0.25f, 0.0f, 0.5f};
  m.indices = {0, 1, 2, 0, 3, 1, 0, 2, 3, 1, 3, 2};
  return m;
}

bake::Mesh box() {
  bake::Mesh m = bake::makeBox(0.5f, 0.25f, 0.75f);
  m.normals.clear();  // POSITION only: the assets carry no other attribute
  return m;
}

// The box with every vertex on its +x face moved by `dx`: the hash changes, one bound moves by dx.
bake::Mesh movedBox(float dx) {
  bake::Mesh m = box();
  float hi = -std::numeric_limits<float>::infinity();
  for (size_t i = 0; i < m.positions.size(); i += 3) hi = std::max(hi, m.positions[i]);
  for (size_t i = 0; i < m.positions.size(); i += 3)
    if (m.positions[i] == hi) m.positions[i] += dx;
  return m;
}

// The triangles' geometry as a reader of the extension computes it.
struct Geometry {
  std::string hash;
  std::array<float, 3> min{}, max{};
};

Geometry geometryOf(bake::Mesh m) {
  if (Status s = bake::checkMesh(&m, "mesh"); !s) die(s.error().toString());
  Geometry g;
  g.hash = hex64(bake::geometryHash(m));
  g.min.fill(std::numeric_limits<float>::infinity());
  g.max.fill(-std::numeric_limits<float>::infinity());
  for (uint32_t v : m.indices)
    for (int c = 0; c < 3; ++c) {
      g.min[c] = std::min(g.min[c], m.positions[3 * v + c]);
      g.max[c] = std::max(g.max[c], m.positions[3 * v + c]);
    }
  return g;
}

// A baked field: the .vff bytes, the geometry it was baked from and its sphere's radius.
struct Field {
  std::vector<uint8_t> bytes;
  Geometry geometry;
  double radius = 0;
  double tolerance() const { return 2.0 * radius / 255.0; }
};

enum class MetaHash { kSame, kNone };

bake::BakeOptions bakeOptions() {
  bake::BakeOptions bo;
  bo.positionParam = 2;  // the smallest octa-hemi2 field with hits and misses: small assets
  bo.mapResolution = 4;
  bo.threads = 1;
  return bo;
}

// META as vff-bake writes it for a mesh, with a fixed generator version so that the bytes do not
// change with the library's version.
json metadata(const std::string& name, const bake::Mesh& mesh, MetaHash hash) {
  json source = {{"name", name},
                 {"format", "gltf"},
                 {"xxh3", hex64(bake::meshHash(mesh))},
                 {"vertices", mesh.vertexCount()},
                 {"triangles", mesh.triangleCount()}};
  if (hash == MetaHash::kSame) source["geometryHash"] = hex64(bake::geometryHash(mesh));
  return {{"vff.generator", "vff-gltf-gen"},
          {"vff.generatorVersion", "1"},
          {"vff.source", source},
          {"vff.bake",
           {{"rayOrigin", "texel centre"}, {"sphere", "minimal-enclosing"}, {"twoSided", true}, {"normals", "none"}}}};
}

struct Baked {
  FieldDesc field;
  bake::BakedField maps;
  bake::Mesh mesh;
};

Baked bakeMesh(bake::Mesh mesh, const bake::BakeOptions& bo) {
  if (Status s = bake::checkMesh(&mesh, "mesh"); !s) die(s.error().toString());
  auto desc = bake::describeBake(mesh, bo);
  if (!desc) die(desc.error().toString());
  auto scene = bake::Scene::create(mesh, 1);
  if (!scene) die(scene.error().toString());
  auto maps = bake::bakeField(*scene, bo);
  if (!maps) die(maps.error().toString());
  return {*desc, std::move(*maps), std::move(mesh)};
}

Field bakeField(const bake::Mesh& mesh, const std::string& name, MetaHash hash = MetaHash::kSame) {
  Baked b = bakeMesh(mesh, bakeOptions());
  WriteOptions wo;
  wo.codec = Codec::kStored;
  wo.sync = false;
  wo.threads = 1;
  wo.metadataJson = metadata(name, b.mesh, hash).dump();
  auto bytes = writeMemory(b.field, b.maps.distance, {}, wo);
  if (!bytes) die(name + ": " + bytes.error().toString());
  return {std::move(*bytes), geometryOf(b.mesh), double(b.field.sphere.radius)};
}

// A partial result as `vff-bake --map-range 0:2` writes it: vff-bake's partial options and META,
// the maps outside the range misses.
Field bakePartial(const bake::Mesh& mesh, const std::string& name) {
  bake::BakeOptions bo = bakeOptions();
  bo.mapBegin = 0;
  bo.mapEnd = 2;
  Baked b = bakeMesh(mesh, bo);
  WriteOptions whole;
  whole.codec = Codec::kStored;
  whole.threads = 1;
  whole.metadataJson = metadata(name, b.mesh, MetaHash::kSame).dump();
  WriteOptions wo = bake_tool::partialWriteOptions(whole);
  wo.sync = false;
  wo.metadataJson = bake_tool::partialMetadata(whole.metadataJson, whole, {0, 2}, b.field.mapCount);
  auto w = Writer::createInMemory(b.field, wo);
  if (!w) die(name + ": " + w.error().toString());
  Status st = w->writeMaps(Plane::kDistance, b.maps.distance);
  const std::vector<uint8_t> miss = bake_tool::missMap(b.field);
  for (uint32_t k = 2; st && k < b.field.mapCount; ++k) st = w->writeMaps(Plane::kDistance, miss);
  if (!st) die(name + ": " + st.error().toString());
  auto bytes = w->finishToMemory();
  if (!bytes) die(name + ": " + bytes.error().toString());
  return {std::move(*bytes), geometryOf(b.mesh), double(b.field.sphere.radius)};
}

// The field with one byte of its first distance block changed: the checksums of the block (6009)
// and of the section holding it (4008) no longer match.
std::vector<uint8_t> corruptBlock(const Field& f, const bake::Mesh& mesh) {
  const Baked b = bakeMesh(mesh, bakeOptions());
  std::vector<uint8_t> bytes = f.bytes;
  const auto& d = b.maps.distance;
  auto at = std::search(bytes.begin(), bytes.end(), d.begin(), d.begin() + 64);
  if (at == bytes.end()) die("the first distance block is not in the file");
  at[5] ^= 0x01;
  const Report r = validate(bytes);
  if (r.valid() || !r.has(Code::kBlockChecksum)) die("the changed byte is not a block checksum error");
  return bytes;
}

// Bytes that are never read: the asset breaks a rule checked before the payload (14004-14008). A
// reader that validates the payload first reports 14009 instead and fails the vector.
std::vector<uint8_t> placeholder() {
  const std::string text = "not a .vff file, never read      ";
  return {text.begin(), text.begin() + 32};
}

// ---- Assets --------------------------------------------------------------------------------------

json vec3(const std::array<float, 3>& v) {
  return json::array({v[0], v[1], v[2]});
}

// A glTF asset under construction: its JSON and its one binary buffer.
struct Asset {
  json j = {{"asset", {{"version", "2.0"}, {"generator", "vff-gltf-gen"}}}};
  std::vector<uint8_t> bin;

  // Appends `bytes` at a multiple of `align` as a new bufferView of buffer 0.
  int view(const std::vector<uint8_t>& bytes, size_t align = 4, int target = 0) {
    while (bin.size() % align) bin.push_back(0);
    json v = {{"buffer", 0}, {"byteOffset", bin.size()}, {"byteLength", bytes.size()}};
    if (target) v["target"] = target;
    bin.insert(bin.end(), bytes.begin(), bytes.end());
    j["bufferViews"].push_back(v);
    return int(j["bufferViews"].size()) - 1;
  }
  // A field's payload: at a multiple of 64 bytes, as the spec asks writers to place it.
  int payloadView(const std::vector<uint8_t>& bytes) { return view(bytes, 64); }

  int accessor(json a) {
    j["accessors"].push_back(std::move(a));
    return int(j["accessors"].size()) - 1;
  }

  // A mesh of one primitive: float positions (with min/max), uint32 indices, mode `mode`.
  int mesh(const bake::Mesh& m, const std::string& name, int mode = 4) {
    std::vector<uint8_t> pos(m.positions.size() * 4), idx(m.indices.size() * 4);
    std::memcpy(pos.data(), m.positions.data(), pos.size());
    std::memcpy(idx.data(), m.indices.data(), idx.size());
    std::array<float, 3> lo, hi;
    lo.fill(std::numeric_limits<float>::infinity());
    hi.fill(-std::numeric_limits<float>::infinity());
    for (size_t i = 0; i < m.positions.size(); ++i) {
      lo[i % 3] = std::min(lo[i % 3], m.positions[i]);
      hi[i % 3] = std::max(hi[i % 3], m.positions[i]);
    }
    const int p = accessor({{"bufferView", view(pos, 4, 34962)},
                            {"componentType", 5126},
                            {"count", m.vertexCount()},
                            {"type", "VEC3"},
                            {"min", vec3(lo)},
                            {"max", vec3(hi)}});
    const int i = accessor(
        {{"bufferView", view(idx, 4, 34963)}, {"componentType", 5125}, {"count", m.indices.size()}, {"type", "SCALAR"}});
    json prim = {{"attributes", {{"POSITION", p}}}, {"indices", i}};
    if (mode != 4) prim["mode"] = mode;
    j["meshes"].push_back({{"name", name}, {"primitives", json::array({prim})}});
    return int(j["meshes"].size()) - 1;
  }

  int node(int mesh, const std::string& name, json extra = json::object()) {
    json n = {{"name", name}, {"mesh", mesh}};
    n.update(extra);
    j["nodes"].push_back(n);
    return int(j["nodes"].size()) - 1;
  }

  // One scene (the default) with every node as a root.
  void scene() {
    json roots = json::array();
    for (size_t i = 0; i < j["nodes"].size(); ++i) roots.push_back(i);
    j["scenes"] = json::array({{{"nodes", roots}}});
    j["scene"] = 0;
  }

  void used() { j["extensionsUsed"] = json::array({kExt}); }

  json& ext(int mesh) { return j["meshes"][size_t(mesh)]["extensions"][kExt]; }

  // The usual extension value of a field in bufferView `v`.
  void attach(int mesh, int v, const Geometry& g) {
    ext(mesh) = {{"bufferView", v}, {"mimeType", kMediaType}, {"geometryHash", g.hash},
                 {"min", vec3(g.min)}, {"max", vec3(g.max)}};
  }
  void attachUri(int mesh, const std::string& uri, const Geometry& g) {
    ext(mesh) = {{"uri", uri}, {"geometryHash", g.hash}, {"min", vec3(g.min)}, {"max", vec3(g.max)}};
  }

  void finishBuffer(bool glb) {
    while (bin.size() % 4) bin.push_back(0);
    if (bin.empty()) return;
    json b = {{"byteLength", bin.size()}};
    if (!glb) b["uri"] = "data:application/octet-stream;base64," + bake::base64(bin);
    j["buffers"] = json::array({b});
  }
};

void put32(std::vector<uint8_t>& out, uint32_t v) {
  for (int i = 0; i < 4; ++i) out.push_back(uint8_t(v >> (8 * i)));
}

// The GLB container (glTF 2.0 section 4.4): header, JSON chunk padded with spaces so that the
// binary chunk's data starts at a multiple of 64 in the file, binary chunk padded with zeros.
std::vector<uint8_t> glbBytes(const std::string& jsonText, const std::vector<uint8_t>* bin) {
  std::string text = jsonText;
  if (bin)
    while ((12 + 8 + text.size() + 8) % 64) text += ' ';
  else
    while (text.size() % 4) text += ' ';
  std::vector<uint8_t> out;
  const size_t binLength = bin ? (bin->size() + 3) / 4 * 4 : 0;
  const size_t total = 12 + 8 + text.size() + (bin ? 8 + binLength : 0);
  put32(out, 0x46546C67);  // "glTF"
  put32(out, 2);
  put32(out, uint32_t(total));
  put32(out, uint32_t(text.size()));
  put32(out, 0x4E4F534A);  // "JSON"
  out.insert(out.end(), text.begin(), text.end());
  if (bin) {
    put32(out, uint32_t(binLength));
    put32(out, 0x004E4942);  // "BIN\0"
    out.insert(out.end(), bin->begin(), bin->end());
    out.resize(total, 0);
  }
  return out;
}

std::vector<uint8_t> asGlb(Asset& a) {
  a.finishBuffer(true);
  return glbBytes(a.j.dump(), a.bin.empty() ? nullptr : &a.bin);
}

std::vector<uint8_t> asGltf(Asset& a) {
  a.finishBuffer(false);
  const std::string text = a.j.dump(1) + "\n";
  return {text.begin(), text.end()};
}

// ---- What a reader must report ---------------------------------------------------------------------

struct Problem {
  int rule;
  const char* severity;
  std::string path;
  bool ioError = false;
  std::vector<int> vffCodes = {};  // 14009 of a payload libvff refuses: the codes its validator reports
};

// The error codes libvff's validator reports for `bytes`, sorted; the message of rule 14009 names one.
std::vector<int> vffErrorCodes(const std::vector<uint8_t>& bytes) {
  std::vector<int> codes;
  for (const Issue& i : validate(bytes).issues)
    if (i.severity == Severity::kError) codes.push_back(int(i.code));
  std::sort(codes.begin(), codes.end());
  codes.erase(std::unique(codes.begin(), codes.end()), codes.end());
  if (codes.empty()) die("the payload meant to be invalid is valid");
  return codes;
}

// The rules' names (spec/gltf/VFF_visibility_field/README.md, section "Rules").
const char* ruleName(int rule) {
  static const std::map<int, const char*> names = {
      {14001, "gltf-container"},       {14002, "gltf-required"},         {14003, "gltf-used"},
      {14004, "gltf-extension-value"}, {14005, "gltf-field-source"},     {14006, "gltf-buffer-view"},
      {14007, "gltf-uri"},             {14008, "gltf-mime-type"},        {14009, "gltf-payload"},
      {14010, "gltf-hash-conflict"},   {14011, "gltf-mesh-geometry"},    {14101, "gltf-geometry-exact"},
      {14102, "gltf-geometry-close"},  {14103, "gltf-geometry-mismatch"}, {14104, "gltf-node-no-field"}};
  return names.at(rule);
}

json problemJson(const Problem& p) {
  json j = {{"rule", p.rule},
            {"name", ruleName(p.rule)},
            {"severity", p.severity},
            {"path", p.path}};
  if (p.ioError) j["ioError"] = true;
  if (!p.vffCodes.empty()) j["vffCodes"] = p.vffCodes;
  return j;
}

std::string extPath(int mesh, const std::string& member = "") {
  return "/meshes/" + std::to_string(mesh) + kExtPath + (member.empty() ? "" : "/" + member);
}

// A field with an error: nothing of it is reported but its mesh.
json invalidField(int mesh) {
  return {{"mesh", mesh}, {"valid", false}, {"usable", false}, {"match", "unchecked"}};
}

// A valid field: its payload, the declared and the shipped geometry, the match and its nodes.
json validField(int mesh, const std::string& name, const char* source, const std::vector<uint8_t>& payload,
                const Geometry& declared, const Geometry& shipped, double tolerance,
                const std::vector<std::pair<int, bool>>& nodes) {
  const char* match = "exact";
  double diff = 0;
  if (declared.hash != shipped.hash) {
    for (int c = 0; c < 3; ++c) {
      diff = std::max(diff, std::fabs(double(declared.min[c]) - double(shipped.min[c])));
      diff = std::max(diff, std::fabs(double(declared.max[c]) - double(shipped.max[c])));
    }
    match = diff <= tolerance ? "close" : "mismatch";
  }
  json f = {{"mesh", mesh},
            {"name", name},
            {"valid", true},
            {"usable", std::string(match) != "mismatch"},
            {"match", match},
            {"source", source},
            {"geometryHash", declared.hash},
            {"meshGeometryHash", shipped.hash},
            {"bytes", payload.size()},
            {"xxh3", xxh3(payload)},
            {"nodes", json::array()}};
  if (std::string(match) != "exact") {
    f["tolerance"] = tolerance;
    f["boundsDifference"] = diff;
  }
  for (const auto& [n, answered] : nodes) f["nodes"].push_back({{"node", n}, {"answered", answered}});
  return f;
}

// One asset: its file, the files beside it, and what a reader reports.
struct Output {
  explicit Output(std::string f) : file(std::move(f)) {}
  std::string file;  // "valid/NAME.glb" or "invalid/ID-NAME.gltf"
  std::vector<uint8_t> bytes;
  std::map<std::string, std::vector<uint8_t>> beside;  // other files, by path under OUTDIR
  std::vector<Problem> problems;
  json fields = json::array();
  int meshes = -1;  // the meshes a reader counts; -1: not set
  bool zstd = false;  // a payload has zstd blocks (its bytes depend on libzstd)
};

// The fields every asset is made of, baked once.
struct Fields {
  bake::Mesh tetra = tetrahedron(), box = gltf_gen::box();
  Field tetraField = bakeField(tetra, "tetrahedron");
  Field boxField = bakeField(box, "box");
};

// An asset of one tetrahedron mesh used by one node, its field in a bufferView, the payload given.
Asset oneTetra(const Fields& f, const std::vector<uint8_t>& payload, int* meshOut = nullptr, int* viewOut = nullptr) {
  Asset a;
  const int m = a.mesh(f.tetra, "tetrahedron");
  a.node(m, "tetrahedron");
  a.scene();
  a.used();
  const int v = a.payloadView(payload);
  a.attach(m, v, f.tetraField.geometry);
  if (meshOut) *meshOut = m;
  if (viewOut) *viewOut = v;
  return a;
}

std::vector<Output> validAssets(const Fields& f) {
  std::vector<Output> out;
  const std::vector<std::pair<int, bool>> node0 = {{0, true}};
  {  // one mesh, its field embedded; matched exactly
    Output o("valid/one-mesh.glb");
    Asset a = oneTetra(f, f.tetraField.bytes);
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.fields.push_back(validField(0, "tetrahedron", "bufferView", f.tetraField.bytes, f.tetraField.geometry,
                                  f.tetraField.geometry, f.tetraField.tolerance(), node0));
    out.push_back(std::move(o));
  }
  // Two meshes, three nodes: a similarity, a plain one, one with a non-uniform scale (14104). The
  // tetrahedron's field is embedded, the box's is box.vff beside the .glb.
  {
    Output o("valid/two-meshes-three-nodes.glb");
    Asset a;
    const int t = a.mesh(f.tetra, "tetrahedron"), b = a.mesh(f.box, "box");
    a.node(t, "turned", {{"rotation", {0.0, 0.6, 0.0, 0.8}}, {"scale", {2.0, 2.0, 2.0}}, {"translation", {1.0, 0.0, -3.0}}});
    a.node(b, "plain");
    a.node(b, "stretched", {{"scale", {1.0, 3.0, 1.0}}});
    a.scene();
    a.used();
    a.attach(t, a.payloadView(f.tetraField.bytes), f.tetraField.geometry);
    a.attachUri(b, "box.vff", f.boxField.geometry);
    o.bytes = asGlb(a);
    o.meshes = 2;
    o.fields.push_back(validField(0, "tetrahedron", "bufferView", f.tetraField.bytes, f.tetraField.geometry,
                                  f.tetraField.geometry, f.tetraField.tolerance(), {{0, true}}));
    o.fields.push_back(validField(1, "box", "uri", f.boxField.bytes, f.boxField.geometry, f.boxField.geometry,
                                  f.boxField.tolerance(), {{1, true}, {2, false}}));
    o.problems.push_back({14104, "note", "/nodes/2"});
    out.push_back(std::move(o));
  }
  {  // a .gltf with the field in a .vff file beside it (the close and mismatch assets share it)
    Output o("valid/external-uri.gltf");
    Asset a;
    const int m = a.mesh(f.box, "box");
    a.node(m, "box");
    a.scene();
    a.used();
    a.attachUri(m, "box.vff", f.boxField.geometry);
    o.bytes = asGltf(a);
    o.beside["valid/box.vff"] = f.boxField.bytes;
    o.meshes = 1;
    o.fields.push_back(validField(0, "box", "uri", f.boxField.bytes, f.boxField.geometry, f.boxField.geometry,
                                  f.boxField.tolerance(), node0));
    out.push_back(std::move(o));
  }
  {  // a .gltf with the field in a data: URI (and a mimeType, optional with uri)
    Output o("valid/data-uri.gltf");
    Asset a;
    const int m = a.mesh(f.box, "box");
    a.node(m, "box");
    a.scene();
    a.used();
    a.attachUri(m, "data:application/vnd.vff;base64," + bake::base64(f.boxField.bytes), f.boxField.geometry);
    a.ext(m)["mimeType"] = kMediaType;
    o.bytes = asGltf(a);
    o.meshes = 1;
    o.fields.push_back(validField(0, "box", "uri", f.boxField.bytes, f.boxField.geometry, f.boxField.geometry,
                                  f.boxField.tolerance(), node0));
    out.push_back(std::move(o));
  }
  // The box shipped with its +x face moved: by a quarter of tau (close, used) and by three tau
  // (mismatch, not used). The field is the one baked from the box as it was.
  for (const auto& [name, steps] : {std::pair<std::string, double>{"close", 0.25}, {"mismatch", 3.0}}) {
    Output o("valid/" + name + ".glb");
    const bake::Mesh moved = movedBox(float(steps * f.boxField.tolerance()));
    const Geometry shipped = geometryOf(moved);
    Asset a;
    const int m = a.mesh(moved, "box");
    a.node(m, "box");
    a.scene();
    a.used();
    a.attachUri(m, "box.vff", f.boxField.geometry);
    o.bytes = asGltf(a);
    o.meshes = 1;
    o.fields.push_back(validField(0, "box", "uri", f.boxField.bytes, f.boxField.geometry, shipped,
                                  f.boxField.tolerance(), node0));
    if (name == "close")
      o.problems.push_back({14102, "note", extPath(0)});
    else
      o.problems.push_back({14103, "warning", extPath(0)});
    out.push_back(std::move(o));
  }
  {  // extensionsUsed lists the extension, no mesh carries it: nothing to report
    Output o("valid/used-without-field.glb");
    Asset a;
    const int m = a.mesh(f.tetra, "tetrahedron");
    a.node(m, "tetrahedron");
    a.scene();
    a.used();
    o.bytes = asGlb(a);
    o.meshes = 1;
    out.push_back(std::move(o));
  }
  {  // the payload's META has no vff.source.geometryHash: the extension's alone is checked
    Output o("valid/meta-without-geometry-hash.glb");
    const Field nohash = bakeField(f.tetra, "tetrahedron", MetaHash::kNone);
    Asset a = oneTetra(f, nohash.bytes);
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.fields.push_back(validField(0, "tetrahedron", "bufferView", nohash.bytes, nohash.geometry, f.tetraField.geometry,
                                  nohash.tolerance(), node0));
    out.push_back(std::move(o));
  }
  return out;
}

std::vector<Output> invalidAssets(const Fields& f) {
  std::vector<Output> out;
  const std::vector<uint8_t> ph = placeholder();
  // An asset of one tetrahedron whose extension value `edit` changes, breaking `rule` at `member`.
  auto edited = [&](const std::string& file, int rule, const std::string& member, const std::function<void(Asset&)>& edit,
                    bool glb = true, bool ioError = false) {
    Output o("invalid/" + file);
    Asset a = oneTetra(f, ph);
    edit(a);
    o.bytes = glb ? asGlb(a) : asGltf(a);
    o.meshes = 1;
    o.problems.push_back({rule, "error", extPath(0, member), ioError});
    if (rule >= 14004) o.fields.push_back(invalidField(0));
    return o;
  };
  auto setExt = [](const std::string& key, json v) { return [key, v](Asset& a) { a.ext(0)[key] = v; }; };
  auto eraseExt = [](const std::string& key) { return [key](Asset& a) { a.ext(0).erase(key); }; };

  // 14001: not a glTF 2.0 asset
  {
    Output o("invalid/14001-glb-magic.glb");
    Asset a = oneTetra(f, ph);
    o.bytes = asGlb(a);
    o.bytes[0] = 'G';
    o.problems.push_back({14001, "error", ""});
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14001-glb-length.glb");
    Asset a = oneTetra(f, ph);
    o.bytes = asGlb(a);
    o.bytes.resize(o.bytes.size() - 64);  // the header's length says 64 bytes more
    o.problems.push_back({14001, "error", ""});
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14001-json-syntax.gltf");
    Asset a = oneTetra(f, ph);
    o.bytes = asGltf(a);
    o.bytes.resize(o.bytes.size() / 2);
    o.problems.push_back({14001, "error", ""});
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14001-asset-version.gltf");
    Asset a = oneTetra(f, ph);
    a.j["asset"]["version"] = "1.0";
    o.bytes = asGltf(a);
    o.problems.push_back({14001, "error", "/asset/version"});
    out.push_back(std::move(o));
  }
  {  // two problems: 14001 is checked first
    Output o("invalid/14001-asset-version-before-required.gltf");
    Asset a = oneTetra(f, ph);
    a.j["asset"]["version"] = "3.0";
    a.j["extensionsRequired"] = json::array({kExt});
    o.bytes = asGltf(a);
    o.problems.push_back({14001, "error", "/asset/version"});
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14002-extension-required.glb");
    Asset a = oneTetra(f, ph);
    a.j["extensionsRequired"] = json::array({kExt});
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.problems.push_back({14002, "error", "/extensionsRequired"});
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14003-extension-not-used.glb");
    Asset a = oneTetra(f, ph);
    a.j.erase("extensionsUsed");
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.problems.push_back({14003, "error", "/extensionsUsed"});
    out.push_back(std::move(o));
  }
  {  // two problems: 14003 (file level) ends the check before the extension's value is read
    Output o("invalid/14003-not-used-before-extension-value.glb");
    Asset a = oneTetra(f, ph);
    a.j.erase("extensionsUsed");
    a.ext(0)["geometryHash"] = "not a hash";
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.problems.push_back({14003, "error", "/extensionsUsed"});
    out.push_back(std::move(o));
  }

  // 14004: the extension's value
  out.push_back(edited("14004-not-an-object.glb", 14004, "", [](Asset& a) { a.ext(0) = json::array({1, 2}); }));
  out.push_back(edited("14004-buffer-view-type.glb", 14004, "bufferView", setExt("bufferView", "0")));
  out.push_back(edited("14004-buffer-view-negative.glb", 14004, "bufferView", setExt("bufferView", -1)));
  out.push_back(edited("14004-uri-type.glb", 14004, "uri", [](Asset& a) {
    a.ext(0).erase("bufferView");
    a.ext(0)["uri"] = 7;
  }));
  out.push_back(edited("14004-mime-type-type.glb", 14004, "mimeType", setExt("mimeType", json::array({kMediaType}))));
  out.push_back(edited("14004-geometry-hash-type.glb", 14004, "geometryHash", setExt("geometryHash", 1234)));
  out.push_back(edited("14004-geometry-hash-uppercase.glb", 14004, "geometryHash", [&](Asset& a) {
    std::string h = f.tetraField.geometry.hash;
    for (char& c : h) c = char(std::toupper(static_cast<unsigned char>(c)));
    if (h == f.tetraField.geometry.hash) h[0] = 'A';  // all digits: make it upper case anyway
    a.ext(0)["geometryHash"] = h;
  }));
  out.push_back(edited("14004-geometry-hash-length.glb", 14004, "geometryHash",
                       setExt("geometryHash", f.tetraField.geometry.hash.substr(0, 15))));
  out.push_back(edited("14004-geometry-hash-missing.glb", 14004, "geometryHash", eraseExt("geometryHash")));
  out.push_back(edited("14004-min-type.glb", 14004, "min", setExt("min", "0 0 0")));
  out.push_back(edited("14004-min-two-numbers.glb", 14004, "min", setExt("min", json::array({0.0, 0.0}))));
  out.push_back(edited("14004-max-not-a-number.glb", 14004, "max", setExt("max", json::array({1.0, "1", 1.0}))));
  out.push_back(edited("14004-min-above-max.glb", 14004, "min", [&](Asset& a) {
    std::array<float, 3> lo = f.tetraField.geometry.min;
    lo[1] = f.tetraField.geometry.max[1] + 1.0f;
    a.ext(0)["min"] = vec3(lo);
  }));
  out.push_back(edited("14004-max-missing.glb", 14004, "max", eraseExt("max")));
  {  // two problems: the value (14004) is checked before the bufferView (14006)
    Output o = edited("14004-extension-value-before-buffer-view.glb", 14004, "geometryHash", [](Asset& a) {
      a.ext(0)["geometryHash"] = "0123456789abcdeg";
      a.ext(0)["bufferView"] = 99;
    });
    out.push_back(std::move(o));
  }

  // 14005: both or neither source
  out.push_back(edited("14005-both-sources.glb", 14005, "", setExt("uri", "tetrahedron.vff")));
  out.push_back(edited("14005-no-source.glb", 14005, "", eraseExt("bufferView")));

  // 14006: the bufferView
  out.push_back(edited("14006-buffer-view-index.glb", 14006, "bufferView", setExt("bufferView", 99)));
  out.push_back(edited("14006-buffer-view-stride.glb", 14006, "bufferView",
                       [](Asset& a) { a.j["bufferViews"][size_t(a.ext(0)["bufferView"].get<int>())]["byteStride"] = 4; }));
  out.push_back(edited("14006-buffer-view-out-of-range.glb", 14006, "bufferView", [](Asset& a) {
    json& v = a.j["bufferViews"][size_t(a.ext(0)["bufferView"].get<int>())];
    v["byteLength"] = v["byteLength"].get<size_t>() + 4096;  // past the end of the buffer
  }));
  {  // a .glb whose buffer 0 has no binary chunk; the mesh's data is in a data: URI buffer
    Output o("invalid/14006-no-binary-chunk.glb");
    Asset a = oneTetra(f, ph);
    a.finishBuffer(false);
    json& payload = a.j["bufferViews"][size_t(a.ext(0)["bufferView"].get<int>())];
    a.j["buffers"].insert(a.j["buffers"].begin(), json{{"byteLength", 256}});  // the GLB-stored buffer
    for (json& v : a.j["bufferViews"]) v["buffer"] = 1;
    payload = {{"buffer", 0}, {"byteOffset", 0}, {"byteLength", 128}};
    o.bytes = glbBytes(a.j.dump(), nullptr);
    o.meshes = 1;
    o.problems.push_back({14006, "error", extPath(0, "bufferView")});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  {  // a .gltf whose payload's buffer is a file that does not exist
    Output o("invalid/14006-buffer-uri-missing.gltf");
    Asset a = oneTetra(f, ph);
    a.finishBuffer(false);
    a.j["buffers"].push_back({{"byteLength", 128}, {"uri", "missing.bin"}});
    a.j["bufferViews"][size_t(a.ext(0)["bufferView"].get<int>())] = {{"buffer", 1}, {"byteOffset", 0}, {"byteLength", 128}};
    const std::string text = a.j.dump(1) + "\n";
    o.bytes.assign(text.begin(), text.end());
    o.meshes = 1;
    o.problems.push_back({14006, "error", extPath(0, "bufferView")});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }

  // 14007: the uri (a .gltf each; the field's bufferView replaced by the uri)
  auto uri = [&](const std::string& file, const std::string& u, bool ioError = false) {
    return edited(
        file, 14007, "uri",
        [u](Asset& a) {
          a.ext(0).erase("bufferView");
          a.ext(0).erase("mimeType");
          a.ext(0)["uri"] = u;
        },
        false, ioError);
  };
  out.push_back(uri("14007-uri-absolute-path.gltf", "/fields/tetrahedron.vff"));
  out.push_back(uri("14007-uri-scheme.gltf", "https://example.com/tetrahedron.vff"));
  out.push_back(uri("14007-uri-network-path.gltf", "//example.com/tetrahedron.vff"));
  out.push_back(uri("14007-uri-query.gltf", "tetrahedron.vff?v=1"));
  out.push_back(uri("14007-uri-backslash.gltf", "fields\\tetrahedron.vff"));
  out.push_back(uri("14007-uri-bad-percent.gltf", "tetra%G0hedron.vff"));
  out.push_back(uri("14007-uri-decoded-nul.gltf", "tetrahedron%00.vff"));
  out.push_back(uri("14007-data-uri-not-base64.gltf", "data:application/vnd.vff,VFF"));
  out.push_back(uri("14007-uri-missing-file.gltf", "14007-uri-missing-file.mesh0.vff", true));

  // 14008: the mimeType
  out.push_back(edited("14008-mime-type-missing.glb", 14008, "", eraseExt("mimeType")));
  out.push_back(edited("14008-mime-type-wrong.glb", 14008, "mimeType", setExt("mimeType", "application/octet-stream")));

  // 14009: the payload
  {
    const std::vector<uint8_t> head(f.tetraField.bytes.begin(), f.tetraField.bytes.begin() + 64);
    std::vector<uint8_t> bad = head;
    bad[0] = 'X';
    Output o("invalid/14009-payload-magic.glb");
    Asset a = oneTetra(f, bad);
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.problems.push_back({14009, "error", extPath(0), false, vffErrorCodes(bad)});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14009-payload-checksum.glb");
    const std::vector<uint8_t> corrupt = corruptBlock(f.tetraField, f.tetra);
    Asset a = oneTetra(f, corrupt);
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.problems.push_back({14009, "error", extPath(0), false, vffErrorCodes(corrupt)});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  {
    Output o("invalid/14009-payload-partial.glb");
    const Field partial = bakePartial(f.tetra, "tetrahedron");
    Asset a = oneTetra(f, partial.bytes);
    o.bytes = asGlb(a);
    o.meshes = 1;
    o.zstd = true;
    o.problems.push_back({14009, "error", extPath(0)});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  // The next three share tetrahedron.vff, a valid field, beside them.
  {  // the extension declares another geometryHash than the payload's META
    Output o("invalid/14010-hash-conflict.gltf");
    Asset a;
    const int m = a.mesh(f.tetra, "tetrahedron");
    a.node(m, "tetrahedron");
    a.scene();
    a.used();
    a.attachUri(m, "tetrahedron.vff", f.tetraField.geometry);
    a.ext(m)["geometryHash"] = "0123456789abcdef";
    o.bytes = asGltf(a);
    o.beside["invalid/tetrahedron.vff"] = f.tetraField.bytes;
    o.meshes = 1;
    o.problems.push_back({14010, "error", extPath(0, "geometryHash")});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  {  // the mesh is drawn as lines: no triangle to match the field with
    Output o("invalid/14011-mesh-lines-only.gltf");
    Asset a;
    const int m = a.mesh(f.tetra, "tetrahedron", 1);
    a.node(m, "tetrahedron");
    a.scene();
    a.used();
    a.attachUri(m, "tetrahedron.vff", f.tetraField.geometry);
    o.bytes = asGltf(a);
    o.beside["invalid/tetrahedron.vff"] = f.tetraField.bytes;
    o.meshes = 1;
    o.problems.push_back({14011, "error", "/meshes/0"});
    o.fields.push_back(invalidField(0));
    out.push_back(std::move(o));
  }
  {  // mesh 0 has an error, mesh 1 is still checked and used
    Output o("invalid/14006-first-mesh-second-valid.gltf");
    Asset a;
    const int t = a.mesh(f.tetra, "tetrahedron"), u = a.mesh(f.tetra, "tetrahedron-too");
    a.node(t, "tetrahedron");
    a.node(u, "tetrahedron-too");
    a.scene();
    a.used();
    a.attach(t, 99, f.tetraField.geometry);
    a.attachUri(u, "tetrahedron.vff", f.tetraField.geometry);
    o.bytes = asGltf(a);
    o.beside["invalid/tetrahedron.vff"] = f.tetraField.bytes;
    o.meshes = 2;
    o.problems.push_back({14006, "error", extPath(0, "bufferView")});
    o.fields.push_back(invalidField(0));
    o.fields.push_back(validField(1, "tetrahedron-too", "uri", f.tetraField.bytes, f.tetraField.geometry,
                                  f.tetraField.geometry, f.tetraField.tolerance(), {{1, true}}));
    out.push_back(std::move(o));
  }
  return out;
}

// The manifest with one line per asset and per file, so that a change shows as the lines it changes.
std::string manifestText(const json& m) {
  std::string s = "{\n";
  size_t i = 0;
  for (const auto& [key, value] : m.items()) {
    s += " " + json(key).dump() + ": ";
    if (value.is_object()) {
      s += "{\n";
      size_t k = 0;
      for (const auto& [name, entry] : value.items())
        s += "  " + json(name).dump() + ": " + entry.dump() + (++k < value.size() ? ",\n" : "\n");
      s += " }";
    } else {
      s += value.dump();
    }
    s += ++i < m.size() ? ",\n" : "\n";
  }
  return s + "}\n";
}

void writeFile(const fs::path& p, const std::vector<uint8_t>& bytes) {
  fs::create_directories(p.parent_path());
  std::ofstream o(p, std::ios::binary);
  o.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
  if (!o) die(p.string() + ": cannot write");
}

}  // namespace
}  // namespace vff::gltf_gen

int main(int argc, char** argv) {
  using namespace vff::gltf_gen;
  if (argc != 2) die("usage: vff-gltf-gen OUTDIR");
  const fs::path out = argv[1];
  std::error_code ec;
  fs::remove_all(out / "valid", ec);
  fs::remove_all(out / "invalid", ec);
  const Fields fields;
  std::vector<Output> all = validAssets(fields);
  for (Output& o : invalidAssets(fields)) all.push_back(std::move(o));
  json assets = json::object(), files = json::object();
  for (const Output& o : all) {
    writeFile(out / o.file, o.bytes);
    files[o.file] = {{"bytes", o.bytes.size()}, {"xxh3", xxh3(o.bytes)}, {"zstd", o.zstd}};
    for (const auto& [name, bytes] : o.beside) {
      writeFile(out / name, bytes);
      files[name] = {{"bytes", bytes.size()}, {"xxh3", xxh3(bytes)}, {"zstd", false}};
    }
    json problems = json::array();
    bool error = false;
    for (const Problem& p : o.problems) {
      problems.push_back(problemJson(p));
      error = error || std::string(p.severity) == "error";
    }
    assets[o.file] = {{"hasError", error}, {"problems", problems}, {"fields", o.fields}};
    // A file-level problem (14001-14003) ends the check: how far a reader counted meshes is its own.
    const bool fileLevel = !o.problems.empty() && o.problems.front().rule <= 14003;
    if (o.meshes >= 0 && !fileLevel) assets[o.file]["meshes"] = o.meshes;
  }
  const json manifest = {{"generator", "vff-gltf-gen"},
                         {"extension", kExt},
                         {"zstdVersion", ZSTD_versionString()},
                         {"assets", assets},
                         {"files", files}};
  std::ofstream(out / "manifest.json") << manifestText(manifest);
  return 0;
}
