// gltf.cpp - vff-inspect on a glTF asset: the fields its meshes carry (the extension
// VFF_visibility_field, spec/gltf/VFF_visibility_field/README.md), how each matches its mesh, the
// nodes it answers for, and every problem the reader found; --extract writes the payloads out.
//
// As for a .vff file, the JSON document is the one model of the report and the text is rendered
// from it. The reader is the baker library's (vff/bake/gltf_fields.h): a build without it
// (VFF_BUILD_BAKE=OFF) refuses glTF input as unsupported.
#include <sys/stat.h>

#include <cerrno>
#include <cinttypes>

#include "cli.h"
#include "inspect.h"

#if VFF_INSPECT_HAS_BAKE
#include "vff/bake/gltf_fields.h"
#include "vff/version.h"
#endif

namespace vff::inspect {

using nlohmann::json;

#if !VFF_INSPECT_HAS_BAKE

int inspectGltf(const std::string& path, const GltfInspectOptions&) {
  cli::printError(kProg, path + ": glTF input needs vff built with the baker (VFF_BUILD_BAKE)");
  return cli::kExitUnsupported;
}

#else

namespace {

using bake::GltfField;
using bake::GltfFieldProblem;
using bake::GltfFieldsReport;
using bake::GltfSeverity;

std::string str(const json& j) {
  if (j.is_string()) return j.get<std::string>();
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

std::string gnum(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

json problemJson(const GltfFieldProblem& p) {
  return {{"rule", static_cast<int>(p.rule)},
          {"name", bake::gltfFieldRuleName(p.rule)},
          {"severity", bake::gltfSeverityName(p.severity)},
          {"path", p.path},
          {"message", p.message}};
}

// The payload's summary, as vff-inspect gives it for a .vff file; null when it cannot be opened.
json payloadSummary(const GltfField& f, uint32_t histogramBins) {
  if (!f.valid || f.bytes.empty()) return nullptr;
  auto file = File::openMemory(f.bytes);
  if (!file) return nullptr;
  const auto partial = partialInfo(*file);
  auto stats = distanceStats(*file, histogramBins, /*skipBadBlocks=*/false, partial ? partial->range : MapSpan{});
  if (!stats) return nullptr;
  return summarize(*file, checksumsVerifiedAtOpen(*file), *stats, histogramBins, partial);
}

json fieldJson(const GltfField& f, uint32_t histogramBins) {
  json j;
  j["mesh"] = f.mesh;
  j["name"] = f.meshName;
  j["path"] = f.path;
  if (f.bufferView >= 0) j["bufferView"] = f.bufferView;
  if (!f.uri.empty()) j["uri"] = f.uri;
  j["bytes"] = f.bytes.size();
  j["geometryHash"] = f.geometryHash;
  j["meshGeometryHash"] = f.meshGeometryHash.empty() ? json(nullptr) : json(f.meshGeometryHash);
  j["match"] = bake::gltfFieldMatchName(f.match);
  const bool matched = f.match == bake::GltfFieldMatch::kClose || f.match == bake::GltfFieldMatch::kMismatch ||
                       f.match == bake::GltfFieldMatch::kExact;
  j["tolerance"] = matched ? json(f.tolerance) : json(nullptr);
  j["boundsDifference"] = matched ? json(f.boundsDifference) : json(nullptr);
  j["valid"] = f.valid;
  j["usable"] = f.usable();
  json nodes = json::array();
  for (const auto& n : f.nodes)
    nodes.push_back({{"node", n.node}, {"name", n.name}, {"answered", n.answered}, {"reason", n.reason}});
  j["nodes"] = std::move(nodes);
  j["field"] = payloadSummary(f, histogramBins);
  return j;
}

json reportJson(const std::string& label, const GltfFieldsReport& r, uint32_t histogramBins) {
  json doc;
  doc["file"] = label;
  doc["tool"] = {{"name", kProg}, {"version", kLibraryVersion}};
  doc["meshes"] = r.meshCount;
  json fields = json::array();
  for (const GltfField& f : r.fields) fields.push_back(fieldJson(f, histogramBins));
  doc["fields"] = std::move(fields);
  json problems = json::array();
  for (const GltfFieldProblem& p : r.problems) problems.push_back(problemJson(p));
  doc["problems"] = std::move(problems);
  return doc;
}

// "vff 1.2, 20480 bytes (0.020 MiB): 314 maps of 16x16 (octa-hemi2 n=8), unorm8-diameter, normals
// oct-snorm16, radius 1.5, hit ratio 0.4213" - the payload in one line.
std::string summaryLine(const json& s) {
  const json& f = s["field"];
  char ratio[32];
  std::snprintf(ratio, sizeof ratio, "%.4f", s["statistics"]["hitRatio"].get<double>());
  return "vff " + str(s["format"]["version"]) + ", " + cli::formatBytes(s["format"]["fileSize"].get<uint64_t>()) +
         ": " + std::to_string(f["mapCount"].get<uint64_t>()) + " maps of " + str(f["mapResolution"]) + "x" +
         str(f["mapResolution"]) + " (" + str(f["positionScheme"]) + " n=" + str(f["positionParam"]) + "), " +
         str(f["distanceEncoding"]) + ", normals " + str(f["normalEncoding"]) + ", radius " +
         gnum(f["sphere"]["radius"].get<double>()) + ", hit ratio " + ratio;
}

// "FILE: PATH: name (ID): message", as GltfFieldProblem::format spells it.
std::string problemLine(const std::string& file, const json& p) {
  std::string s = file + ": ";
  if (!str(p["path"]).empty()) s += str(p["path"]) + ": ";
  return s + str(p["name"]) + " (" + std::to_string(p["rule"].get<int>()) + "): " + str(p["message"]);
}

void printGltfText(const json& doc, std::FILE* out) {
  const std::string file = str(doc["file"]);
  std::fprintf(out, "file:        %s\n", file.c_str());
  std::fprintf(out, "meshes:      %s, %s\n", cli::count(doc["meshes"].get<uint64_t>(), "mesh", "meshes").c_str(),
               doc["fields"].size() == 1 ? "1 with a field" : (std::to_string(doc["fields"].size()) + " with a field").c_str());
  for (const json& f : doc["fields"]) {
    std::string source = f.contains("bufferView") ? "bufferView " + str(f["bufferView"]) : "";
    if (f.contains("uri")) source += (source.empty() ? "uri " : ", uri ") + str(f["uri"]);
    if (source.empty()) source = "no source";
    std::fprintf(out, "\nmesh %s \"%s\": %s\n", str(f["mesh"]).c_str(), str(f["name"]).c_str(), str(f["path"]).c_str());
    std::fprintf(out, "  source:       %s, %s\n", source.c_str(), cli::formatBytes(f["bytes"].get<uint64_t>()).c_str());
    std::fprintf(out, "  geometryHash: %s (the mesh as shipped: %s)\n", str(f["geometryHash"]).c_str(),
                 f["meshGeometryHash"].is_null() ? "not computed" : str(f["meshGeometryHash"]).c_str());
    const std::string match = str(f["match"]);
    if (match == "close" || match == "mismatch")
      std::fprintf(out, "  match:        %s (bounds differ by up to %s, tau %s)%s\n", match.c_str(),
                   gnum(f["boundsDifference"].get<double>()).c_str(), gnum(f["tolerance"].get<double>()).c_str(),
                   match == "mismatch" ? ": not used" : "");
    else
      std::fprintf(out, "  match:        %s\n", match.c_str());
    std::fprintf(out, "  valid:        %s\n", f["valid"].get<bool>() ? "yes" : "no (see the problems)");
    if (f["nodes"].empty()) std::fprintf(out, "  nodes:        none uses the mesh\n");
    bool first = true;
    for (const json& n : f["nodes"]) {
      std::string line = str(n["node"]);
      if (!str(n["name"]).empty()) line += " \"" + str(n["name"]) + "\"";
      line += n["answered"].get<bool>() ? ": answered" : ": not answered (" + str(n["reason"]) + ")";
      std::fprintf(out, "  %-14s%s\n", first ? "nodes:" : "", line.c_str());
      first = false;
    }
    std::fprintf(out, "  field:        %s\n", f["field"].is_null() ? "none (not valid)" : summaryLine(f["field"]).c_str());
  }
  std::fprintf(out, "\nproblems:    %s\n", doc["problems"].empty() ? "none" : std::to_string(doc["problems"].size()).c_str());
  for (const json& p : doc["problems"]) std::fprintf(out, "  %s\n", problemLine(file, p).c_str());
}

// The exit code for the report's errors: 0 with none, 2 when every error is a uri file that cannot
// be read, else 3.
int exitCodeFor(const GltfFieldsReport& r) {
  bool error = false, other = false;
  for (const GltfFieldProblem& p : r.problems) {
    if (p.severity != GltfSeverity::kError) continue;
    error = true;
    if (!p.ioError) other = true;
  }
  return !error ? cli::kExitSuccess : other ? cli::kExitInvalidFile : cli::kExitIo;
}

// The first error on stderr, as vff-inspect --validate names a .vff file's first error.
void reportFirstError(const std::string& label, const GltfFieldsReport& r) {
  const GltfFieldProblem* first = nullptr;
  size_t errors = 0;
  for (const GltfFieldProblem& p : r.problems)
    if (p.severity == GltfSeverity::kError && errors++ == 0) first = &p;
  if (!first) return;
  std::string more;
  if (errors > 1) more = " (and " + std::to_string(errors - 1) + " more, see the report)";
  cli::printError(kProg, first->format(label) + more);
}

// The file name without its folder and its .glb / .gltf ending.
std::string stemOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
  if (cli::endsWithNoCase(name, ".glb")) name.resize(name.size() - 4);
  else if (cli::endsWithNoCase(name, ".gltf")) name.resize(name.size() - 5);
  return name;
}

int extract(const std::string& path, const GltfFieldsReport& r, const GltfInspectOptions& o) {
  struct stat st {};
  const bool exists = ::stat(o.extractDir.c_str(), &st) == 0;
  if (!exists || !S_ISDIR(st.st_mode)) {
    cli::printError(kProg, o.extractDir + ": " + (exists ? std::string("not a folder") : std::string(std::strerror(errno))) +
                               " (--extract needs an existing folder)");
    return cli::kExitIo;
  }
  const std::string dir = o.extractDir.back() == '/' ? o.extractDir : o.extractDir + "/";
  const std::string stem = stemOf(path);
  json written = json::array();
  for (const GltfField& f : r.fields) {
    if (!f.valid || f.bytes.empty()) continue;
    const std::string out = dir + stem + ".mesh" + std::to_string(f.mesh) + ".vff";
    if (Status s = cli::writeFileAtomic(out, f.bytes); !s) return cli::reportError(kProg, "", s.error());
    written.push_back({{"mesh", f.mesh}, {"path", out}, {"bytes", f.bytes.size()}});
    if (!o.json) std::printf("%s\n", out.c_str());
  }
  if (o.json)
    std::printf("%s\n", json{{"file", path}, {"extracted", written}}.dump(2, ' ', false, json::error_handler_t::replace).c_str());
  reportFirstError(path, r);
  return exitCodeFor(r);
}

}  // namespace

int inspectGltf(const std::string& path, const GltfInspectOptions& o) {
  if (Status s = cli::checkRegularFile(path); !s) return cli::reportError(kProg, path, s.error());
  auto report = bake::readGltfFields(path);
  if (!report) return cli::reportError(kProg, path, report.error());
  if (!o.extractDir.empty()) return extract(path, *report, o);
  const json doc = reportJson(path, *report, o.histogramBins);
  if (o.json)
    std::printf("%s\n", doc.dump(2, ' ', false, json::error_handler_t::replace).c_str());
  else
    printGltfText(doc, stdout);
  reportFirstError(path, *report);
  return exitCodeFor(*report);
}

#endif

}  // namespace vff::inspect
