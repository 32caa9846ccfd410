// gltf_field.cpp - the payload of one mesh's field in a glTF asset (gltf_field.h).
#include "gltf_field.h"

#include "cli.h"

#if VFF_QUERY_HAS_BAKE
#include "vff/bake/gltf_fields.h"
#endif

namespace vff::query_tool {

namespace {

constexpr const char* kProg = "vff-query";

}  // namespace

#if !VFF_QUERY_HAS_BAKE

std::optional<int> gltfFieldBytes(const std::string& path, int, std::vector<uint8_t>*) {
  cli::printError(kProg, path + ": glTF input needs vff built with the baker (VFF_BUILD_BAKE)");
  return cli::kExitUnsupported;
}

#else

namespace {

using bake::GltfField;
using bake::GltfFieldProblem;
using bake::GltfFieldsReport;
using bake::GltfSeverity;

// "0 \"cube\", 2, 3 \"tree\"": the meshes that carry a field.
std::string meshesWithFields(const GltfFieldsReport& r) {
  std::string s;
  for (const GltfField& f : r.fields) {
    s += (s.empty() ? "" : ", ") + std::to_string(f.mesh);
    if (!f.meshName.empty()) s += " \"" + f.meshName + "\"";
  }
  return s;
}

// Prints `problems` as errors; the exit code: 2 when each is a file that cannot be read, else 3.
int reportProblems(const std::string& path, const std::vector<const GltfFieldProblem*>& problems) {
  bool io = !problems.empty();
  for (const GltfFieldProblem* p : problems) {
    cli::printError(kProg, p->format(path));
    io = io && p->ioError;
  }
  return io ? cli::kExitIo : cli::kExitInvalidFile;
}

bool isMeshPath(const std::string& p, int mesh) {
  const std::string prefix = "/meshes/" + std::to_string(mesh);
  return p == prefix || p.rfind(prefix + "/", 0) == 0;
}

}  // namespace

std::optional<int> gltfFieldBytes(const std::string& path, int mesh, std::vector<uint8_t>* bytes) {
  if (Status s = cli::checkRegularFile(path); !s) return cli::reportError(kProg, path, s.error());
  auto report = bake::readGltfFields(path);
  if (!report) return cli::reportError(kProg, path, report.error());
  const GltfFieldsReport& r = *report;

  // A problem of the whole asset (not glTF 2.0, the extension required or not declared) stops it.
  std::vector<const GltfFieldProblem*> fileErrors;
  for (const GltfFieldProblem& p : r.problems)
    if (p.severity == GltfSeverity::kError && p.path.rfind("/meshes/", 0) != 0) fileErrors.push_back(&p);
  if (!fileErrors.empty()) return reportProblems(path, fileErrors);

  if (r.fields.empty()) {
    cli::printError(kProg, path + ": no mesh carries a field (the glTF extension VFF_visibility_field)");
    return cli::kExitInvalidFile;
  }
  const GltfField* field = nullptr;
  if (mesh < 0) {
    if (r.fields.size() > 1) {
      cli::usageError(kProg, path + " has fields on several meshes: choose one with --mesh (" + meshesWithFields(r) + ")");
      return cli::kExitUsage;
    }
    field = &r.fields.front();
  } else {
    for (const GltfField& f : r.fields)
      if (f.mesh == mesh) field = &f;
    if (!field) {
      const std::string which = mesh < r.meshCount ? "mesh " + std::to_string(mesh) + " of " + path + " has no field"
                                                   : path + " has no mesh " + std::to_string(mesh) + " (it has " +
                                                         std::to_string(r.meshCount) + ")";
      cli::usageError(kProg, "--mesh " + std::to_string(mesh) + ": " + which + "; the meshes with a field: " +
                                 meshesWithFields(r));
      return cli::kExitUsage;
    }
  }
  if (!field->usable()) {
    // The mesh's errors, or the mismatch that keeps its field from being used.
    std::vector<const GltfFieldProblem*> why;
    for (const GltfFieldProblem& p : r.problems)
      if (isMeshPath(p.path, field->mesh) &&
          (p.severity == GltfSeverity::kError || p.rule == bake::GltfFieldRule::kGeometryMismatch))
        why.push_back(&p);
    if (why.empty()) {
      cli::printError(kProg, path + ": " + field->path + ": the field of mesh " + std::to_string(field->mesh) +
                                 " cannot be used (match " + bake::gltfFieldMatchName(field->match) + ")");
      return cli::kExitInvalidFile;
    }
    return reportProblems(path, why);
  }
  *bytes = field->bytes;
  return std::nullopt;
}

#endif

}  // namespace vff::query_tool
