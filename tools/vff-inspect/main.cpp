// vff-inspect: prints what a .vff file holds, validates it, and renders a preview of its maps.
//
//   vff-inspect bunny.vff                          summary: header, sections, field, payload, layout,
//                                                  hit ratio, distance histogram, metadata
//   vff-inspect bunny.vff --format json            the same as one JSON object (spec/inspect-schema.json)
//   vff-inspect bunny.vff --validate               also every problem the validator finds (exit 3 if any error)
//   vff-inspect bunny.vff --preview maps.png --maps 100
//   cat bunny.vff | vff-inspect -
//   vff-inspect scene.glb [--format json]          the fields a glTF asset's meshes carry (gltf.cpp)
//   vff-inspect scene.glb --extract DIR            their payloads as DIR/scene.meshI.vff
#include <cerrno>
#include <cinttypes>
#include <cstring>
#include <new>
#include <optional>

#include "cli.h"
#include "inspect.h"
#include "vff/version.h"

namespace {

using nlohmann::json;
using namespace vff;
using inspect::kProg;

struct Options {
  std::string input;
  cli::CommonOptions common;
  bool validate = false;
  std::string preview;
  uint32_t previewMaps = 64;
  uint32_t histogramBins = 16;
  std::string extract;
};

// The exit code for a failed validation: 2 when the file could not even be read, 3 otherwise.
int validationExitCode(const Report& report) {
  for (const Issue& i : report.issues)
    if (i.severity == Severity::kError && cli::exitCodeFor(i.code) == cli::kExitIo) return cli::kExitIo;
  return cli::kExitInvalidFile;
}

// Prints the report to stdout. A failed write (a full disk) is reported at exit by the check that
// cli::parse() installs: "vff-inspect: error: stdout: ...", exit 2.
void printDocument(const json& doc, cli::OutputFormat format) {
  if (format == cli::OutputFormat::kJson)
    (void)std::printf("%s\n", doc.dump(2, ' ', false, json::error_handler_t::replace).c_str());
  else
    inspect::printText(doc, stdout);
}

// A glTF input is listed by gltf.cpp (its exit code); --extract is for nothing else. Nothing for
// a .vff input, which run() goes on with.
std::optional<int> inspectGltf(const CLI::App& app, const Options& o) {
  if (!cli::isGltfInput(o.input)) {
    if (!app.count("--extract")) return std::nullopt;
    cli::usageError(kProg, "--extract applies to a glTF input (.gltf, .glb), not to " +
                               (o.input == "-" ? std::string("standard input") : o.input));
    return cli::kExitUsage;
  }
  // What reads or draws one .vff file's maps has no meaning for an asset of several fields.
  std::string refused;
  if (app.count("--preview")) refused += "--preview";
  if (app.count("--maps")) refused += std::string(refused.empty() ? "" : ", ") + "--maps";
  if (!refused.empty()) {
    cli::usageError(kProg, refused + ": not for a glTF input (" + o.input +
                               "); --extract writes its fields out as .vff files, which take them");
    return cli::kExitUsage;
  }
  if (o.extract == "-") {
    cli::usageError(kProg, "--extract needs a folder (the fields are not written to standard output)");
    return cli::kExitUsage;
  }
  return inspect::inspectGltf(o.input, {o.common.format == cli::OutputFormat::kJson, o.histogramBins, o.extract});
}

int run(int argc, char** argv);

}  // namespace

int main(int argc, char** argv) {
  return cli::runGuarded(kProg, run, argc, argv);
}

namespace {

int run(int argc, char** argv) {
  Options o;
  CLI::App app{
      "Inspects a precomputed 4D visibility field (.vff): header, sections, field description,\n"
      "payload sizes, packed layout, hit ratio, distance histogram and metadata.\n"
      "Data goes to stdout, diagnostics to stderr.\n\n"
      "A glTF asset (.gltf, .glb, or a file with the GLB magic) is listed instead by the fields its meshes\n"
      "carry (the extension VFF_visibility_field): per field its mesh, source, bytes, geometryHash, how\n"
      "it matches the mesh as shipped (exact, close or mismatch, with the bound difference and tau), the\n"
      "nodes it answers for, and its payload's summary in one line; then every problem as\n"
      "FILE: PATH: name (ID): message. Exit 3 on an error (2 when the only errors are uri files that\n"
      "cannot be read). --extract DIR writes each valid field's payload to DIR/STEM.meshI.vff.\n\n"
      "  vff-inspect field.vff --validate\n"
      "  vff-inspect field.vff --format json --preview maps.png --maps 100\n"
      "  vff-inspect scene.glb --extract fields/\n",
      kProg};
  app.footer(cli::exitCodeHelp());
  cli::addCommonOptions(app, kProg, o.common);
  app.add_option("file", o.input,
                 "the .vff file to inspect: a regular file (a named pipe or folder is refused, exit 2), or - "
                 "(standard input, read whole); or a glTF asset (.gltf, .glb) whose meshes carry fields")
      ->required();
  app.add_option("--extract", o.extract,
                 "glTF input only: write the payload of each valid field to DIR/STEM.meshI.vff (STEM: the input's "
                 "name without .glb/.gltf; each written atomically, its bytes unchanged) and print one path per "
                 "line; DIR must exist")
      ->option_text("DIR");
  app.add_flag("--validate", o.validate,
               "run the full validator and print every issue (severity, ID, name, section, offset, message); "
               "exit 3 if any issue is an error (a glTF input is always checked so)");
  CLI::Option* preview =
      app.add_option("--preview", o.preview,
                     "write a PNG contact sheet of the first maps: grey = distance (near = bright), misses dark blue, "
                     "1-pixel black separators; written atomically")
          ->option_text("OUT.png");
  app.add_option("--maps", o.previewMaps, "number of maps in the preview (the first N)")
      ->needs(preview)
      ->check(CLI::Range(uint32_t{1}, uint32_t{1} << 24))
      ->option_text("N (default 64)");
  app.add_option("--histogram-bins", o.histogramBins, "bins of the distance histogram over [0, 2R]")
      ->check(CLI::Range(1u, 4096u))
      ->option_text("K (default 16)");
  if (auto rc = cli::parse(app, kProg, argc, argv)) return *rc;
  if (auto gltfRc = inspectGltf(app, o)) return *gltfRc;
  if (o.preview == "-") {
    cli::usageError(kProg, "--preview needs a file name (a PNG is not written to standard output)");
    return cli::kExitUsage;
  }

  // The input: a file, or all of standard input for "-".
  const std::string label = o.input == "-" ? "<stdin>" : o.input;
  std::vector<uint8_t> stdinBytes;
  if (o.input == "-") {
    auto bytes = cli::readStdin();
    if (!bytes) return cli::reportError(kProg, label, bytes.error());
    stdinBytes = std::move(*bytes);
    if (stdinBytes.size() >= 4 && std::memcmp(stdinBytes.data(), "glTF", 4) == 0) {
      cli::usageError(kProg, "a glTF asset is read from a file (its buffers may be files beside it), not from standard input");
      return cli::kExitUsage;
    }
  }
  auto openInput = [&](const ReadOptions& ro) {
    return o.input == "-" ? File::openMemory(stdinBytes, ro) : File::open(o.input, ro);
  };

  json doc;
  doc["file"] = label;
  doc["tool"] = {{"name", kProg}, {"version", kLibraryVersion}};
  int rc = cli::kExitSuccess;
  std::optional<File> file;
  inspect::ChecksumState checksums;

  if (o.validate) {
    // The validator reports everything; the summary is still shown when the structure is readable
    // (checksums are then taken from the report instead of being checked at open).
    const Report report = o.input == "-" ? validate(stdinBytes) : validateFile(o.input);
    doc["validation"] = inspect::validationJson(report);
    ReadOptions ro;
    ro.checksums = ChecksumPolicy::kNone;
    auto f = openInput(ro);
    if (f) {
      file.emplace(std::move(*f));
      checksums = inspect::checksumsFromReport(*file, report);
    }
    if (!report.valid()) {
      rc = validationExitCode(report);
      const Issue* first = nullptr;
      size_t errors = 0;
      for (const Issue& i : report.issues)
        if (i.severity == Severity::kError && errors++ == 0) first = &i;
      std::string more;
      if (errors > 1) more = " (and " + std::to_string(errors - 1) + " more, see the validation report)";
      Error e = makeError(first->code, first->message + more, first->section, first->offset);
      cli::reportError(kProg, label, e);
    }
  } else {
    auto f = openInput(ReadOptions{});
    if (!f) return cli::reportError(kProg, label, f.error());
    file.emplace(std::move(*f));
    checksums = inspect::checksumsVerifiedAtOpen(*file);
  }

  if (file) {
    if (!o.preview.empty()) {
      const auto g =
          inspect::previewGeometry(file->field().mapResolution, std::min(o.previewMaps, file->field().mapCount));
      if (g.width * g.height > inspect::kMaxPreviewPixels) {
        cli::usageError(kProg, "a preview of " + std::to_string(g.maps) + " maps would be " + std::to_string(g.width) +
                                   " x " + std::to_string(g.height) + " pixels; ask for fewer with --maps");
        return cli::kExitUsage;
      }
    }
    const auto partial = inspect::partialInfo(*file);
    auto stats = inspect::distanceStats(*file, o.histogramBins, /*skipBadBlocks=*/o.validate,
                                        partial ? partial->range : inspect::MapSpan{});
    if (!stats) return cli::reportError(kProg, label, stats.error());
    doc.update(inspect::summarize(*file, checksums, *stats, o.histogramBins, partial));

    if (!o.preview.empty()) {
      auto g = inspect::writePreview(*file, o.preview, o.previewMaps);
      if (!g) {
        const int prc = cli::reportError(kProg, g.error().code == Code::kIoWrite ? o.preview : label, g.error());
        if (!o.validate) return prc;
        if (rc == cli::kExitSuccess) rc = prc;  // still print the validation report
      } else {
        doc["preview"] = {{"path", o.preview}, {"maps", g->maps},   {"columns", g->columns},
                          {"rows", g->rows},   {"width", g->width}, {"height", g->height}};
      }
    }
  } else if (!o.preview.empty()) {
    cli::printError(kProg, "no preview written: " + label + " cannot be read");
  }

  printDocument(doc, o.common.format);
  return rc;
}

}  // namespace
