// gltf_fields_read.cpp - readGltfFields: a glTF file checked against the rules of the extension
// VFF_visibility_field (spec/gltf/VFF_visibility_field/README.md), in the spec's order, and each
// field matched against the geometry the file ships with.
#include <tiny_gltf.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <optional>

#include "gltf_fields_glb.h"
#include "mesh_importers.h"
#include "vff/bake/gltf_fields.h"
#include "vff/reader.h"
#include "vff/validate.h"

namespace vff::bake {

const char* gltfFieldRuleName(GltfFieldRule rule) noexcept {
  switch (rule) {
    case GltfFieldRule::kContainer: return "gltf-container";
    case GltfFieldRule::kRequired: return "gltf-required";
    case GltfFieldRule::kUsed: return "gltf-used";
    case GltfFieldRule::kExtensionValue: return "gltf-extension-value";
    case GltfFieldRule::kFieldSource: return "gltf-field-source";
    case GltfFieldRule::kBufferView: return "gltf-buffer-view";
    case GltfFieldRule::kUri: return "gltf-uri";
    case GltfFieldRule::kMimeType: return "gltf-mime-type";
    case GltfFieldRule::kPayload: return "gltf-payload";
    case GltfFieldRule::kHashConflict: return "gltf-hash-conflict";
    case GltfFieldRule::kMeshGeometry: return "gltf-mesh-geometry";
    case GltfFieldRule::kGeometryExact: return "gltf-geometry-exact";
    case GltfFieldRule::kGeometryClose: return "gltf-geometry-close";
    case GltfFieldRule::kGeometryMismatch: return "gltf-geometry-mismatch";
    case GltfFieldRule::kNodeNoField: return "gltf-node-no-field";
  }
  return "unknown";
}

const char* gltfSeverityName(GltfSeverity s) noexcept {
  switch (s) {
    case GltfSeverity::kError: return "error";
    case GltfSeverity::kWarning: return "warning";
    case GltfSeverity::kNote: return "note";
  }
  return "unknown";
}

const char* gltfFieldMatchName(GltfFieldMatch m) noexcept {
  switch (m) {
    case GltfFieldMatch::kUnchecked: return "unchecked";
    case GltfFieldMatch::kExact: return "exact";
    case GltfFieldMatch::kClose: return "close";
    case GltfFieldMatch::kMismatch: return "mismatch";
  }
  return "unknown";
}

std::string GltfFieldProblem::format(const std::string& file) const {
  return file + ": " + (path.empty() ? std::string() : path + ": ") + gltfFieldRuleName(rule) + " (" +
         std::to_string(int(rule)) + "): " + message;
}

bool GltfFieldsReport::hasError() const {
  return std::any_of(problems.begin(), problems.end(), [](const GltfFieldProblem& p) { return p.severity == GltfSeverity::kError; });
}

namespace {

using nlohmann::json;

std::string shown(const json& v) {
  std::string s = v.dump();
  return s.size() > 60 ? s.substr(0, 57) + "..." : s;
}

bool isHash(const std::string& s) {
  return s.size() == 16 && std::all_of(s.begin(), s.end(), [](char c) { return (c >= '0' && c <= '9') || (c >= 'a' && c <= 'f'); });
}

bool listed(const json& doc, const char* key, const std::string& name) {
  const auto it = doc.find(key);
  if (it == doc.end() || !it->is_array()) return false;
  return std::any_of(it->begin(), it->end(), [&](const json& v) { return v.is_string() && v.get<std::string>() == name; });
}

// A message without the file name the importer's errors start with.
std::string withoutFile(const std::string& message, const std::string& path) {
  const std::string prefix = path + ": ";
  return message.compare(0, prefix.size(), prefix) == 0 ? message.substr(prefix.size()) : message;
}

std::string number(double v) {
  char s[32];
  std::snprintf(s, sizeof s, "%.9g", v);
  return s;
}

class Reader {
 public:
  Reader(const std::string& path, const GltfFieldReadOptions& options) : path_(path), options_(options) {}

  void problem(GltfFieldRule rule, GltfSeverity sev, std::string where, std::string message, bool io = false) {
    GltfFieldProblem p;
    p.rule = rule;
    p.severity = sev;
    p.path = std::move(where);
    p.message = std::move(message);
    p.ioError = io;
    report.problems.push_back(std::move(p));
  }
  void error(GltfFieldRule rule, const std::string& where, std::string message, bool io = false) {
    problem(rule, GltfSeverity::kError, where, std::move(message), io);
  }

  // Rules 14001-14003; false when the file ends there.
  bool fileLevel(std::span<const uint8_t> bytes) {
    std::string text;
    if (detail::hasGlbMagic(bytes)) {
      glb_.emplace();
      if (std::string e = detail::splitGlb(bytes, &*glb_); !e.empty()) {
        error(GltfFieldRule::kContainer, "", e);
        return false;
      }
      text = glb_->json;
    } else {
      text.assign(reinterpret_cast<const char*>(bytes.data()), bytes.size());
    }
    doc_ = json::parse(text, nullptr, false);
    if (doc_.is_discarded()) {
      error(GltfFieldRule::kContainer, "", glb_ ? "the JSON chunk is not JSON" : "not a GLB and not JSON text");
      return false;
    }
    if (!doc_.is_object()) {
      error(GltfFieldRule::kContainer, "", "the JSON is not an object");
      return false;
    }
    const json* version = nullptr;
    if (doc_.contains("asset") && doc_["asset"].is_object() && doc_["asset"].contains("version"))
      version = &doc_["asset"]["version"];
    if (!version || !version->is_string() || version->get<std::string>().rfind("2.", 0) != 0) {
      error(GltfFieldRule::kContainer, "/asset/version",
            version ? "asset.version is " + shown(*version) + ", not \"2.x\"" : "asset.version is missing");
      return false;
    }
    if (listed(doc_, "extensionsRequired", kGltfFieldExtension)) {
      error(GltfFieldRule::kRequired, "/extensionsRequired",
            std::string(kGltfFieldExtension) + " is listed in extensionsRequired; a field is optional to engines");
      return false;
    }
    if (doc_.contains("meshes") && doc_["meshes"].is_array()) {
      report.meshCount = int(doc_["meshes"].size());
      if (!listed(doc_, "extensionsUsed", kGltfFieldExtension))
        for (size_t m = 0; m < doc_["meshes"].size(); ++m)
          if (extensionOf(m)) {
            error(GltfFieldRule::kUsed, "/extensionsUsed",
                  "mesh " + std::to_string(m) + " carries " + kGltfFieldExtension + " but extensionsUsed does not list it");
            return false;
          }
    }
    return true;
  }

  const json* extensionOf(size_t m) const {
    const json& mesh = doc_["meshes"][m];
    if (!mesh.is_object() || !mesh.contains("extensions") || !mesh["extensions"].is_object()) return nullptr;
    const auto it = mesh["extensions"].find(kGltfFieldExtension);
    return it == mesh["extensions"].end() ? nullptr : &*it;
  }

  void meshes() {
    if (report.meshCount == 0) return;
    std::vector<std::vector<GltfFieldNode>> instances = detail::meshInstances(doc_);
    for (size_t m = 0; m < size_t(report.meshCount); ++m) {
      const json* ext = extensionOf(m);
      if (!ext) continue;
      GltfField f;
      f.mesh = int(m);
      const json& mesh = doc_["meshes"][m];
      if (mesh.contains("name") && mesh["name"].is_string()) f.meshName = mesh["name"].get<std::string>();
      f.path = "/meshes/" + std::to_string(m) + "/extensions/" + kGltfFieldExtension;
      f.nodes = instances[m];
      f.valid = check(*ext, &f);
      if (f.valid)
        for (const GltfFieldNode& n : f.nodes)
          if (!n.answered)
            problem(GltfFieldRule::kNodeNoField, GltfSeverity::kNote, "/nodes/" + std::to_string(n.node),
                    "node " + std::to_string(n.node) + (n.name.empty() ? "" : " '" + n.name + "'") + " uses mesh " +
                        std::to_string(m) + " but has " + (n.reason == "skin" ? "a skin" : n.reason == "mirror" ? "a mirroring transform" : n.reason == "morph targets" ? "morph targets with weights not all zero" : "a transform that is not a similarity (" + n.reason + ")") +
                        ": no field answers for it");
      if (!f.valid) f.bytes.clear();
      report.fields.push_back(std::move(f));
    }
  }

  // Rules 14004-14011 and the match of one mesh's extension; false at its first error.
  bool check(const json& ext, GltfField* f) {
    const std::string& at = f->path;
    auto bad = [&](const std::string& member, const std::string& what) {
      error(GltfFieldRule::kExtensionValue, member.empty() ? at : at + "/" + member, what);
      return false;
    };
    // 14004
    if (!ext.is_object()) return bad("", "the extension value is " + shown(ext) + ", not an object");
    if (ext.contains("bufferView")) {
      const json& v = ext["bufferView"];
      if (!v.is_number_integer() || v.get<int64_t>() < 0 || v.get<int64_t>() > INT32_MAX)
        return bad("bufferView", "bufferView is " + shown(v) + ", not an integer >= 0");
    }
    for (const char* member : {"uri", "mimeType", "geometryHash"})
      if (ext.contains(member) && !ext[member].is_string())
        return bad(member, std::string(member) + " is " + shown(ext[member]) + ", not a string");
    if (!ext.contains("geometryHash")) return bad("geometryHash", "geometryHash is missing");
    f->geometryHash = ext["geometryHash"].get<std::string>();
    if (!isHash(f->geometryHash)) return bad("geometryHash", "geometryHash '" + f->geometryHash + "' is not 16 lowercase hex digits");
    for (const char* member : {"min", "max"}) {
      if (!ext.contains(member)) return bad(member, std::string(member) + " is missing");
      const json& v = ext[member];
      if (!v.is_array() || v.size() != 3 || !std::all_of(v.begin(), v.end(), [](const json& x) {
            return x.is_number() && std::isfinite(x.get<double>()) && std::isfinite(float(x.get<double>()));
          }))
        return bad(member, std::string(member) + " is " + shown(v) + ", not 3 finite numbers");
      auto& out = std::string(member) == "min" ? f->min : f->max;
      for (size_t k = 0; k < 3; ++k) out[k] = float(v[k].get<double>());
    }
    for (size_t k = 0; k < 3; ++k)
      if (f->min[k] > f->max[k])
        return bad("min", "min[" + std::to_string(k) + "] " + number(f->min[k]) + " > max[" + std::to_string(k) + "] " +
                              number(f->max[k]));
    // 14005
    const bool hasView = ext.contains("bufferView"), hasUri = ext.contains("uri");
    if (hasView == hasUri) {
      error(GltfFieldRule::kFieldSource, at,
            hasView ? "both bufferView and uri are given; exactly one names the field" : "neither bufferView nor uri is given");
      return false;
    }
    // 14006 / 14007
    if (hasView) {
      f->bufferView = int(ext["bufferView"].get<int64_t>());
      if (!viewBytes(f->bufferView, at + "/bufferView", &f->bytes)) return false;
    } else {
      f->uri = ext["uri"].get<std::string>();
      if (std::string p = detail::checkGltfUri(f->uri); !p.empty()) {
        error(GltfFieldRule::kUri, at + "/uri", "uri '" + shownUri(f->uri) + "' " + p);
        return false;
      }
      if (std::string e = detail::readGltfUri(path_, f->uri, &f->bytes); !e.empty()) {
        error(GltfFieldRule::kUri, at + "/uri", "uri '" + shownUri(f->uri) + "': " + e, !detail::isDataUri(f->uri));
        return false;
      }
    }
    // 14008
    if (!ext.contains("mimeType")) {
      if (hasView) {
        error(GltfFieldRule::kMimeType, at, std::string("mimeType is missing; a bufferView needs \"") + kVffMediaType + "\"");
        return false;
      }
    } else if (ext["mimeType"].get<std::string>() != kVffMediaType) {
      error(GltfFieldRule::kMimeType, at + "/mimeType",
            "mimeType is " + shown(ext["mimeType"]) + ", not \"" + kVffMediaType + "\"");
      return false;
    }
    // 14009
    const Report validation = validate(f->bytes);
    for (const Issue& issue : validation.issues)
      if (issue.severity == Severity::kError) {
        error(GltfFieldRule::kPayload, at,
              "the payload (" + std::to_string(f->bytes.size()) + " bytes) is not a valid .vff: " + codeName(issue.code) +
                  " (" + std::to_string(int(issue.code)) + "): " + issue.message);
        return false;
      }
    auto file = File::openMemory(f->bytes);
    if (!file) {
      error(GltfFieldRule::kPayload, at, "the payload is not a valid .vff: " + file.error().toString());
      return false;
    }
    const json meta = json::parse(file->metadata(), nullptr, false);
    if (meta.is_object() && meta.contains("vff.partial")) {
      error(GltfFieldRule::kPayload, at, "the payload is a partial result (META has vff.partial), not a whole field");
      return false;
    }
    // 14010
    if (meta.is_object() && meta.contains("vff.source") && meta["vff.source"].is_object() &&
        meta["vff.source"].contains("geometryHash")) {
      const json& h = meta["vff.source"]["geometryHash"];
      if (!h.is_string() || h.get<std::string>() != f->geometryHash) {
        error(GltfFieldRule::kHashConflict, at + "/geometryHash",
              "geometryHash '" + f->geometryHash + "' differs from the payload's META vff.source.geometryHash " + shown(h));
        return false;
      }
    }
    f->tolerance = 2.0 * double(file->field().sphere.radius) / 255.0;
    if (!options_.checkGeometry) return true;
    // 14011
    if (!model_ && modelError_.empty()) {
      auto model = detail::parseGltf(path_, glb_.has_value());
      if (model) model_ = *model;
      else modelError_ = withoutFile(model.error().message, path_);
    }
    if (!model_) {
      error(GltfFieldRule::kMeshGeometry, "/meshes/" + std::to_string(f->mesh), "the file's meshes cannot be read: " + modelError_);
      return false;
    }
    auto g = detail::meshGeometry(*model_, path_, f->mesh);
    if (!g) {
      error(GltfFieldRule::kMeshGeometry, "/meshes/" + std::to_string(f->mesh), withoutFile(g.error().message, path_));
      return false;
    }
    f->meshGeometryHash = g->geometryHash;
    f->meshMin = g->min;
    f->meshMax = g->max;
    for (size_t k = 0; k < 3; ++k)
      f->boundsDifference = std::max({f->boundsDifference, std::fabs(double(f->min[k]) - double(g->min[k])),
                                      std::fabs(double(f->max[k]) - double(g->max[k]))});
    const std::string figures = "the largest bound difference is " + number(f->boundsDifference) + ", tau = 2R/255 = " +
                                number(f->tolerance);
    if (g->geometryHash == f->geometryHash) {
      f->match = GltfFieldMatch::kExact;
    } else if (f->boundsDifference <= f->tolerance) {
      f->match = GltfFieldMatch::kClose;
      problem(GltfFieldRule::kGeometryClose, GltfSeverity::kNote, at,
              "mesh " + std::to_string(f->mesh) + "'s triangles hash to " + g->geometryHash + ", not " + f->geometryHash +
                  ", but its bounds are within one distance step: the field is used (" + figures + ")");
    } else {
      f->match = GltfFieldMatch::kMismatch;
      problem(GltfFieldRule::kGeometryMismatch, GltfSeverity::kWarning, at,
              "mesh " + std::to_string(f->mesh) + "'s triangles hash to " + g->geometryHash + ", not " + f->geometryHash +
                  ", and its bounds differ by more than one distance step: the field is not used (" + figures + ")");
    }
    return true;
  }

  static std::string shownUri(const std::string& uri) { return uri.size() > 80 ? uri.substr(0, 77) + "..." : uri; }

  // Rule 14006: the bytes of bufferView `index`.
  bool viewBytes(int index, const std::string& at, std::vector<uint8_t>* out) {
    auto bad = [&](const std::string& what) {
      error(GltfFieldRule::kBufferView, at, what);
      return false;
    };
    const size_t nviews = doc_.contains("bufferViews") && doc_["bufferViews"].is_array() ? doc_["bufferViews"].size() : 0;
    if (size_t(index) >= nviews)
      return bad("bufferView " + std::to_string(index) + " is not one of the file's " + std::to_string(nviews) + " bufferViews");
    const json& v = doc_["bufferViews"][size_t(index)];
    const std::string name = "bufferView " + std::to_string(index);
    if (!v.is_object()) return bad(name + " is not an object");
    if (v.contains("byteStride")) return bad(name + " has a byteStride; a field's bufferView has none");
    if (!v.contains("buffer") || !v["buffer"].is_number_unsigned()) return bad(name + " has no valid buffer");
    const auto num = [&](const char* k, uint64_t dflt, uint64_t* r) {
      if (!v.contains(k)) return (*r = dflt, true);
      if (!v[k].is_number_unsigned()) return false;
      *r = v[k].get<uint64_t>();
      return true;
    };
    uint64_t offset = 0, length = 0;
    if (!num("byteOffset", 0, &offset) || !v.contains("byteLength") || !num("byteLength", 0, &length))
      return bad(name + " has no valid byteOffset/byteLength");
    const size_t buffer = size_t(v["buffer"].get<uint64_t>());
    std::vector<uint8_t>* data = bufferData(buffer);
    if (!data) return bad(name + ": " + bufferErrors_[buffer]);
    if (offset > data->size() || length > data->size() - offset)
      return bad(name + " (bytes " + std::to_string(offset) + " to " + std::to_string(offset + length) +
                 ") lies outside its buffer " + std::to_string(buffer) + " of " + std::to_string(data->size()) + " bytes");
    out->assign(data->begin() + ptrdiff_t(offset), data->begin() + ptrdiff_t(offset + length));
    return true;
  }

  std::vector<uint8_t>* bufferData(size_t index) {
    if (auto it = buffers_.find(index); it != buffers_.end()) return &it->second;
    if (bufferErrors_.count(index)) return nullptr;
    std::vector<uint8_t> bytes;
    if (std::string e = detail::gltfBufferData(doc_, index, path_, glb_ ? &*glb_ : nullptr, &bytes); !e.empty()) {
      bufferErrors_[index] = e;
      return nullptr;
    }
    return &(buffers_[index] = std::move(bytes));
  }

  GltfFieldsReport report;

 private:
  std::string path_;
  GltfFieldReadOptions options_;
  std::optional<detail::GlbChunks> glb_;
  json doc_;
  std::map<size_t, std::vector<uint8_t>> buffers_;
  std::map<size_t, std::string> bufferErrors_;
  std::shared_ptr<const tinygltf::Model> model_;
  std::string modelError_;
};

}  // namespace

Result<GltfFieldsReport> readGltfFields(const std::string& path, const GltfFieldReadOptions& options) {
  std::vector<uint8_t> bytes;
  if (std::string e = detail::readRegularFile(path, &bytes); !e.empty())
    return makeError(e.rfind("cannot be read", 0) == 0 ? Code::kIoRead : Code::kIoOpen, path + ": " + e);
  Reader r(path, options);
  if (r.fileLevel(bytes)) r.meshes();
  return std::move(r.report);
}

}  // namespace vff::bake
