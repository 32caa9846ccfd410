// gen_gltf.h - what the files of vff-gltf-gen share (gen_gltf.cpp says what the tool writes and
// why): the meshes and their baked fields, the glTF asset under construction, what a reader must
// report for an asset, and the writing of the GLB, .gltf and manifest bytes.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <utility>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "vff/bake/mesh.h"

namespace vff::gltf_gen {

using nlohmann::json;

inline constexpr const char* kExt = "VFF_visibility_field";
inline constexpr const char* kMediaType = "application/vnd.vff";
inline constexpr const char* kExtPath = "/extensions/VFF_visibility_field";

// Prints `what` and ends the tool with exit code 1.
[[noreturn]] void die(const std::string& what);
std::string hex64(uint64_t v);
std::string xxh3(const std::vector<uint8_t>& b);

// ---- Meshes and their fields (gen_gltf_fields.cpp) ----------------------------------------------

bake::Mesh tetrahedron();
bake::Mesh box();
// The box with every vertex on its +x face moved by `dx`: the hash changes, one bound moves by dx.
bake::Mesh movedBox(float dx);

// The triangles' geometry as a reader of the extension computes it.
struct Geometry {
  std::string hash;
  std::array<float, 3> min{}, max{};
};

Geometry geometryOf(bake::Mesh m);

// A baked field: the .vff bytes, the geometry it was baked from and its sphere's radius.
struct Field {
  std::vector<uint8_t> bytes;
  Geometry geometry;
  double radius = 0;
  double tolerance() const { return 2.0 * radius / 255.0; }
};

// Whether the field's META carries vff.source.geometryHash.
enum class MetaHash { kSame, kNone };

Field bakeField(const bake::Mesh& mesh, const std::string& name, MetaHash hash = MetaHash::kSame);
// A partial result as `vff-bake --map-range 0:2` writes it.
Field bakePartial(const bake::Mesh& mesh, const std::string& name);
// The field with one byte of its first distance block changed.
std::vector<uint8_t> corruptBlock(const Field& f, const bake::Mesh& mesh);
// Bytes that are never read: the asset breaks a rule checked before the payload.
std::vector<uint8_t> placeholder();

// The fields every asset is made of, baked once.
struct Fields {
  bake::Mesh tetra = tetrahedron(), box = gltf_gen::box();
  Field tetraField = bakeField(tetra, "tetrahedron");
  Field boxField = bakeField(box, "box");
};

// ---- Assets (gen_gltf_asset.cpp) ----------------------------------------------------------------

json vec3(const std::array<float, 3>& v);

// A glTF asset under construction: its JSON and its one binary buffer.
struct Asset {
  json j = {{"asset", {{"version", "2.0"}, {"generator", "vff-gltf-gen"}}}};
  std::vector<uint8_t> bin;

  // Appends `bytes` at a multiple of `align` as a new bufferView of buffer 0.
  int view(const std::vector<uint8_t>& bytes, size_t align = 4, int target = 0);
  // A field's payload: at a multiple of 64 bytes, as the spec asks writers to place it.
  int payloadView(const std::vector<uint8_t>& bytes) { return view(bytes, 64); }
  int accessor(json a);
  // A mesh of one primitive: float positions (with min/max), uint32 indices, mode `mode`.
  int mesh(const bake::Mesh& m, const std::string& name, int mode = 4);
  int node(int mesh, const std::string& name, json extra = json::object());
  // One scene (the default) with every node as a root.
  void scene();
  void used() { j["extensionsUsed"] = json::array({kExt}); }
  json& ext(int mesh) { return j["meshes"][size_t(mesh)]["extensions"][kExt]; }
  // The usual extension value of a field in bufferView `v`.
  void attach(int mesh, int v, const Geometry& g);
  void attachUri(int mesh, const std::string& uri, const Geometry& g);
  void finishBuffer(bool glb);
};

// An asset of one tetrahedron mesh used by one node, its field in a bufferView, the payload given.
Asset oneTetra(const Fields& f, const std::vector<uint8_t>& payload, int* meshOut = nullptr, int* viewOut = nullptr);

// ---- What a reader must report (gen_gltf_report.cpp) --------------------------------------------

struct Problem {
  int rule;
  const char* severity;
  std::string path;
  bool ioError = false;
  std::vector<int> vffCodes = {};  // 14009 of a payload libvff refuses: the codes its validator reports
};

// The error codes libvff's validator reports for `bytes`, sorted; the message of rule 14009 names one.
std::vector<int> vffErrorCodes(const std::vector<uint8_t>& bytes);
json problemJson(const Problem& p);
std::string extPath(int mesh, const std::string& member = "");
// A field with an error: nothing of it is reported but its mesh.
json invalidField(int mesh);
// A valid field: its payload, the declared and the shipped geometry, the match and its nodes.
json validField(int mesh, const std::string& name, const char* source, const std::vector<uint8_t>& payload,
                const Geometry& declared, const Geometry& shipped, double tolerance,
                const std::vector<std::pair<int, bool>>& nodes);

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

// The assets that break no rule (gen_gltf.cpp) and those that break one (gen_gltf_invalid.cpp).
std::vector<Output> validAssets(const Fields& f);
std::vector<Output> invalidAssets(const Fields& f);

// ---- Writing (gen_gltf_write.cpp) ---------------------------------------------------------------

// The GLB container of `jsonText` and, when given, the binary chunk `bin`.
std::vector<uint8_t> glbBytes(const std::string& jsonText, const std::vector<uint8_t>* bin);
std::vector<uint8_t> asGlb(Asset& a);
std::vector<uint8_t> asGltf(Asset& a);
// The manifest with one line per asset and per file.
std::string manifestText(const json& m);
void writeFile(const std::filesystem::path& p, const std::vector<uint8_t>& bytes);

}  // namespace vff::gltf_gen
