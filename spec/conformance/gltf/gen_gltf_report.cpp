// gen_gltf_report.cpp - what a reader of the extension must report for an asset: the problems
// (rule, name, severity, JSON pointer) and the fields it finds, as manifest.json lists them.
#include <algorithm>
#include <cmath>

#include "gen_gltf.h"
#include "vff/validate.h"

namespace vff::gltf_gen {
namespace {

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

}  // namespace

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

json problemJson(const Problem& p) {
  json j = {{"rule", p.rule},
            {"name", ruleName(p.rule)},
            {"severity", p.severity},
            {"path", p.path}};
  if (p.ioError) j["ioError"] = true;
  if (!p.vffCodes.empty()) j["vffCodes"] = p.vffCodes;
  return j;
}

std::string extPath(int mesh, const std::string& member) {
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

}  // namespace vff::gltf_gen
