// vff/bake/gltf_fields.h - fields inside glTF assets: the glTF extension VFF_visibility_field
// (spec/gltf/VFF_visibility_field/README.md), read and written.
//
// A field is baked in its mesh's own space, so the extension attaches it to a mesh:
//   "meshes": [{ "primitives": [...], "extensions": { "VFF_visibility_field": {
//       "bufferView": 7, "mimeType": "application/vnd.vff",
//       "geometryHash": "0123456789abcdef", "min": [-1, 0, -1], "max": [1, 2, 1] } } }]
// The bufferView (or a `uri`) holds a complete .vff file, the very bytes vff-bake writes for that
// mesh. The nodes that use the mesh are its instances; only nodes whose world transform is a
// similarity (uniform scale, rotation, translation) can be answered by it.
//
// Reading (readGltfFields) checks a file against the extension's rules 14001-14011 in the spec's
// order and matches each field against the geometry the file ships with (14101-14103): a Draco or
// quantized re-encode moves vertices slightly, which the rules tolerate up to one distance step.
//
//   auto r = vff::bake::readGltfFields("scene.glb");
//   if (!r) return fail(r.error());                  // the file is not glTF, or cannot be read
//   for (const auto& p : r->problems) print(p);      // rule, JSON pointer, message
//   for (const auto& f : r->fields)
//     if (f.usable()) auto file = vff::File::openMemory(f.bytes);
//
// Writing (packGlbWithFields) turns a .gltf or .glb asset into one .glb with every field attached.
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "vff/error.h"

namespace vff::bake {

inline constexpr const char* kGltfFieldExtension = "VFF_visibility_field";
inline constexpr const char* kVffMediaType = "application/vnd.vff";

// The extension's rules (the spec's section "Rules"), in check order; 141xx are not errors.
enum class GltfFieldRule : int {
  kContainer = 14001,       // gltf-container: not a glTF 2.0 asset
  kRequired = 14002,        // gltf-required: the extension is in extensionsRequired
  kUsed = 14003,            // gltf-used: a mesh carries it, extensionsUsed does not list it
  kExtensionValue = 14004,  // gltf-extension-value: a member missing or of the wrong type or value
  kFieldSource = 14005,     // gltf-field-source: both or neither of bufferView and uri
  kBufferView = 14006,      // gltf-buffer-view: no such bufferView, byteStride, outside its buffer, no data
  kUri = 14007,             // gltf-uri: a uri the spec does not allow, or a file that cannot be read
  kMimeType = 14008,        // gltf-mime-type: missing with bufferView, or not application/vnd.vff
  kPayload = 14009,         // gltf-payload: not a valid .vff, or a partial result
  kHashConflict = 14010,    // gltf-hash-conflict: META's geometryHash differs from the extension's
  kMeshGeometry = 14011,    // gltf-mesh-geometry: the mesh has no triangles the check can read
  kGeometryExact = 14101,   // gltf-geometry-exact: the shipped triangles hash as declared
  kGeometryClose = 14102,   // gltf-geometry-close (note): bounds within one distance step; used
  kGeometryMismatch = 14103,  // gltf-geometry-mismatch (warning): the field is not used
  kNodeNoField = 14104,     // gltf-node-no-field (note): a node using the mesh cannot be answered
};

// "gltf-container" and so on; "unknown" for other values.
const char* gltfFieldRuleName(GltfFieldRule rule) noexcept;

enum class GltfSeverity { kError, kWarning, kNote };
const char* gltfSeverityName(GltfSeverity s) noexcept;  // "error", "warning", "note"

struct GltfFieldProblem {
  GltfFieldRule rule = GltfFieldRule::kContainer;
  GltfSeverity severity = GltfSeverity::kError;
  std::string path;     // JSON pointer ("/meshes/2/extensions/VFF_visibility_field/bufferView"); "" for the file
  std::string message;  // without the file, the path or the rule
  bool ioError = false;  // a uri's file cannot be read (the tools exit 2 rather than 3)
  // "FILE: PATH: name (ID): message" (the path left out when empty).
  std::string format(const std::string& file) const;
};

enum class GltfFieldMatch { kUnchecked, kExact, kClose, kMismatch };
const char* gltfFieldMatchName(GltfFieldMatch m) noexcept;  // "unchecked", "exact", "close", "mismatch"

// A node that uses the mesh (in the scene read: the default scene, else scene 0; every node when the
// file has no scene).
struct GltfFieldNode {
  int node = -1;
  std::string name;
  bool answered = false;  // its world transform is a similarity, unskinned, unmorphed
  std::string reason;     // why not, when not ("non-uniform scale", "skin", "morph targets", "mirror")
};

struct GltfField {
  int mesh = -1;
  std::string meshName;
  std::string path;      // JSON pointer of the extension object
  int bufferView = -1;   // the payload's bufferView, or -1
  std::string uri;       // the payload's uri as written, or ""
  std::string geometryHash;  // as the extension declares it
  std::array<float, 3> min{}, max{};  // as the extension declares them
  std::vector<uint8_t> bytes;         // the .vff file (empty when the field has an error)
  bool valid = false;                 // no error (14004-14011) on this mesh
  GltfFieldMatch match = GltfFieldMatch::kUnchecked;
  std::string meshGeometryHash;       // of the triangles as shipped ("" when not computed)
  std::array<float, 3> meshMin{}, meshMax{};  // their bounds
  double tolerance = 0;               // tau = 2R/255
  double boundsDifference = 0;        // the largest of the six bound differences
  std::vector<GltfFieldNode> nodes;
  // A reader may answer rays with it: valid, and matched exact or close.
  bool usable() const { return valid && (match == GltfFieldMatch::kExact || match == GltfFieldMatch::kClose); }
};

struct GltfFieldsReport {
  int meshCount = 0;
  std::vector<GltfField> fields;           // one per mesh carrying the extension, in mesh order
  std::vector<GltfFieldProblem> problems;  // in check order
  bool hasError() const;
};

struct GltfFieldReadOptions {
  bool checkGeometry = true;  // decode each mesh and match it (else match stays kUnchecked)
};

// Reads `path` (.gltf or .glb; a GLB by its magic). The Result's error is kept for what stops the
// whole file: it cannot be opened or read (kIoOpen, kIoRead). Every rule of the spec, 14001
// included, is a problem in the report.
Result<GltfFieldsReport> readGltfFields(const std::string& path, const GltfFieldReadOptions& options = {});

// ---- Writing ------------------------------------------------------------------------------------

struct GltfFieldPayload {
  int mesh = -1;
  std::vector<uint8_t> bytes;  // the .vff file; embedded when `uri` is empty
  std::string uri;             // else: referenced by this (already percent-encoded) uri
  std::string geometryHash;    // 16 lowercase hex digits
  std::array<float, 3> min{}, max{};
};

// The mesh's triangles as a reader of the extension matches them: every triangle primitive of mesh
// `mesh` of the file at `path`, in mesh space, checked (zero-area triangles dropped).
struct GltfMeshGeometry {
  std::string geometryHash;
  std::array<float, 3> min{}, max{};
};
Result<GltfMeshGeometry> gltfMeshGeometry(const std::string& path, int mesh);

// The asset at `input` as one .glb with each payload attached to its mesh: every buffer of the
// input packed into the binary chunk, images with a uri embedded as bufferViews, the payloads
// appended; each payload's bufferView starts at a multiple of 64 bytes in the file. extensionsUsed
// lists the extension; an earlier VFF_visibility_field is replaced. Nothing is written: the caller
// writes the bytes (atomically). Deterministic.
Result<std::vector<uint8_t>> packGlbWithFields(const std::string& input, const std::vector<GltfFieldPayload>& payloads);

}  // namespace vff::bake
