// vff-compress: lossless compression of .vff files (zstd with the hits-med filter of format 1.1),
// decompression back to stored blocks, and the compression benchmark.
//
//   vff-compress field.vff small.vff                 zstd -19 + hits-med where it helps
//   vff-compress --decompress small.vff field.vff    stored blocks (zero-copy GPU upload)
//   vff-compress --benchmark a.vff [b.vff ...]       our codec vs zstd -19, xz -9, EXR ZIP/PIZ/DWAA
#include <nlohmann/json.hpp>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "cli.h"
#include "compress.h"
#include "progress.h"
#include "resample.h"
#include "vff/vff.h"

namespace {

const char* kProg = "vff-compress";

struct Options {
  std::vector<std::string> files;
  bool decompress = false;
  bool benchmark = false;
  bool blocks = false;
  bool candidates = false;
  bool quiet = false;
  bool bc4 = false;
  int level = 19;
  std::string filter = "auto";
  uint32_t mapsPerBlock = 0;
  int repeat = 3;
  unsigned threads = 0;
  std::string tmpDir;
  vff::cli::CommonOptions common;
};

double ratio(uint64_t raw, uint64_t stored) { return stored ? double(raw) / double(stored) : 0.0; }

nlohmann::json planeJson(const vff::compress::PlaneReport& r) {
  return {{"rawBytes", r.rawBytes},   {"storedBytes", r.storedBytes}, {"ratio", ratio(r.rawBytes, r.storedBytes)},
          {"blocks", r.blockStored.size()}, {"zstdBlocks", r.zstd}, {"filteredBlocks", r.filtered},
          {"blockStoredBytes", r.blockStored}};
}

void printPlane(const char* name, const vff::compress::PlaneReport& r, bool blocks) {
  std::vector<uint64_t> s = r.blockStored;
  std::sort(s.begin(), s.end());
  std::printf("  %-8s %s raw -> %s stored, ratio %.3f; %s (zstd %u, hits-med %u), block stored bytes "
              "min %llu / median %llu / max %llu\n",
              name, vff::cli::formatBytes(r.rawBytes).c_str(), vff::cli::formatBytes(r.storedBytes).c_str(),
              ratio(r.rawBytes, r.storedBytes), vff::cli::count(r.blockStored.size(), "block").c_str(), r.zstd, r.filtered,
              static_cast<unsigned long long>(s.empty() ? 0 : s.front()),
              static_cast<unsigned long long>(s.empty() ? 0 : s[s.size() / 2]),
              static_cast<unsigned long long>(s.empty() ? 0 : s.back()));
  if (blocks)
    for (size_t b = 0; b < r.blockStored.size(); ++b)
      std::printf("    block %zu: %llu bytes\n", b, static_cast<unsigned long long>(r.blockStored[b]));
}

nlohmann::json bc4Json(const vff::compress::Bc4Report& b) {
  return {{"hits", b.hits},
          {"changedHits", b.changed},
          {"maxErrorCodes", b.maxError},
          {"rmsErrorCodes", b.hits ? std::sqrt(b.sumSquared / double(b.hits)) : 0.0}};
}

// Adds every option of `o` to `app`.
void addOptions(CLI::App& app, Options& o) {
  vff::cli::addCommonOptions(app, kProg, o.common);
  app.add_option("files", o.files, "input and output .vff (with --benchmark: the fields to measure)")->required();
  app.add_flag("-d,--decompress", o.decompress, "write stored (uncompressed, unfiltered) blocks");
  app.add_flag("--benchmark", o.benchmark,
               "measure our codec against zstd -19 and xz -9 on the raw distance payload and OpenEXR ZIP, PIZ "
               "and DWAA on the EXR export, and print the table");
  app.add_option("--level", o.level, "zstd level")->check(CLI::Range(1, 22))->capture_default_str();
  app.add_option("--filter", o.filter, "distance-block filter: auto (hits-med where the encoding allows it), "
                                       "hits-med (an error where it does not), none")
      ->check(CLI::IsMember({"auto", "hits-med", "none"}))
      ->capture_default_str();
  app.add_option("--maps-per-block", o.mapsPerBlock, "maps per block G (0: about 256 KiB per block)")
      ->capture_default_str();
  app.add_flag("--candidates", o.candidates,
               "benchmark: also measure the filters hits-med was chosen over (left, up, gradient, MED on raw bytes)");
  app.add_flag("--bc4", o.bc4,
               "lossy, GPU-native: re-encode an unorm8-diameter distance plane as bc4-diameter (BC4 blocks the "
               "texture unit decodes, half the GPU memory; format 1.2), then compress; prints the code error");
  app.add_flag("--blocks", o.blocks, "also list every block's stored size");
  app.add_option("-j,--threads", o.threads, "compressing threads (0: all cores); the output does not depend on it")
      ->capture_default_str();
  app.add_option("--repeat", o.repeat, "benchmark repetitions (the best time is reported)")
      ->check(CLI::Range(1, 100))
      ->capture_default_str();
  app.add_option("--tmp", o.tmpDir, "benchmark: folder for the EXR files (default: the system's temporary folder)");
  app.add_flag("-q,--quiet", o.quiet, "print nothing on success (and no progress line)");
}

// The field the output will hold, and how the input's maps become its maps.
struct Plan {
  vff::FieldDesc field;   // the input's, or with --bc4 the bc4-diameter one
  bool reencode = false;  // --bc4 re-encodes the distance plane
  bool eightBit = false;  // the output's distances are 8-bit codes (the hits-med filter applies)
};

// Checks that `in` can be rewritten as asked (known roCompatFeatures, --bc4 and --filter hits-med
// on a field they apply to) and warns about the sections that are not copied. Returns the exit
// code of a failure.
std::optional<int> planRewrite(const Options& o, const std::string& input, const vff::File& in, Plan* plan) {
  if (uint64_t unknown = in.info().roCompatFeatures & ~vff::kKnownRoCompatFeatures; unknown != 0) {
    vff::cli::printError(kProg, input + ": roCompatFeatures " + vff::cli::hex(unknown) +
                                    " has bits this tool does not know; such a file must not be rewritten");
    return vff::cli::kExitUnsupported;
  }
  for (const vff::SectionInfo& s : in.info().sections)
    if (!s.known && !o.quiet)
      std::fprintf(stderr, "%s: warning: %s: unknown section '%s' is not copied\n", kProg, input.c_str(),
                   vff::sectionTagName(s.tag).c_str());

  vff::FieldDesc& field = plan->field;
  field = in.field();
  plan->reencode = o.bc4 && field.distanceEncoding != vff::DistanceEncoding::kBc4Diameter;
  if (plan->reencode && field.distanceEncoding != vff::DistanceEncoding::kUnorm8Diameter) {
    vff::cli::printError(kProg, input + ": --bc4 re-encodes unorm8-diameter codes; this field is " +
                                    vff::distanceEncodingName(field.distanceEncoding) +
                                    " (vff-convert --encoding bc4-diameter converts from any encoding with distances)");
    return vff::cli::kExitUnsupported;
  }
  if (plan->reencode && field.mapResolution % 4 != 0) {
    vff::cli::printError(kProg, input + ": --bc4 needs maps whose size is a multiple of 4 (4x4 blocks); this "
                                        "field's are " + std::to_string(field.mapResolution) +
                                        " (vff-convert --map-size makes smaller maps)");
    return vff::cli::kExitUnsupported;
  }
  if (plan->reencode) field.distanceEncoding = vff::DistanceEncoding::kBc4Diameter;
  plan->eightBit = field.distanceEncoding == vff::DistanceEncoding::kUnorm8Diameter ||
                   field.distanceEncoding == vff::DistanceEncoding::kUnorm8Chord;
  if (o.filter == "hits-med" && !plan->eightBit) {
    vff::cli::printError(kProg, input + ": the hits-med filter needs an 8-bit distance encoding (unorm8-diameter or "
                                        "unorm8-chord); this field is " +
                                        vff::distanceEncodingName(field.distanceEncoding) + " (use --filter auto)");
    return vff::cli::kExitUnsupported;
  }
  return std::nullopt;
}

// The writer's options: the input's layout limits and metadata, the codec and filter asked for;
// with --bc4, the layout bc4-diameter needs and a provenance entry in the metadata.
vff::Result<vff::WriteOptions> writeOptions(const Options& o, const std::string& input, const vff::File& in,
                                            const Plan& plan) {
  vff::WriteOptions w;
  w.codec = o.decompress ? vff::Codec::kStored : vff::Codec::kZstd;
  w.zstdLevel = o.level;
  w.filter = !o.decompress && plan.eightBit && o.filter != "none" ? vff::Filter::kHitsMed : vff::Filter::kNone;
  w.mapsPerBlock = o.mapsPerBlock;
  w.threads = o.threads;
  w.layout.target = in.layout().target;
  w.layout.maxTextureSize = in.layout().maxTextureSize;
  w.layout.maxLayers = in.layout().maxLayers;
  w.layout.gutter = in.layout().gutter;
  w.metadataJson = std::string(in.metadata());
  if (plan.reencode) {
    // bc4-diameter slices are a 2D array without gutters (spec rules 7001, 7002).
    w.layout.target = vff::LayoutTarget::kTexture2DArray;
    w.layout.gutter = 0;
    auto hash = vff::convert::fileXxh3(input);
    if (!hash) return std::move(hash).error();
    const size_t slash = input.find_last_of('/');
    vff::convert::ResampleOptions r;
    r.encoding = vff::DistanceEncoding::kBc4Diameter;
    auto meta = vff::convert::appendProvenance(w.metadataJson, in.field(), plan.field, r,
                                               slash == std::string::npos ? input : input.substr(slash + 1), *hash,
                                               kProg);
    if (!meta) return std::move(meta).error();
    w.metadataJson = std::move(*meta);
  }
  return w;
}

// The --format json report, or the text one (not with --quiet), on stdout.
void printReport(const Options& o, const std::string& input, const std::string& output, const vff::File& in,
                 const vff::WriteOptions& w, const vff::compress::Report& report) {
  if (o.common.format == vff::cli::OutputFormat::kJson) {
    nlohmann::json j = {{"input", input},
                        {"output", output},
                        {"inputBytes", in.bytes().size()},
                        {"outputBytes", report.fileBytes},
                        {"codec", vff::codecName(w.codec)},
                        {"filter", vff::filterName(w.filter)},
                        {"seconds", report.seconds},
                        {"distance", planeJson(report.planes[0])}};
    if (report.planes[1].present) j["normal"] = planeJson(report.planes[1]);
    if (report.bc4.done) j["bc4"] = bc4Json(report.bc4);
    if (report.refinement.present)
      j["refinement"] = {{"remade", report.refinement.remade},
                         {"unsureTexelsBefore", report.refinement.unsureBefore},
                         {"unsureTexels", report.refinement.unsureAfter}};
    std::printf("%s\n", j.dump(2).c_str());
  } else if (!o.quiet) {
    std::printf("%s: %s -> %s (%s, filter %s, %.2f s)\n", output.c_str(), vff::cli::formatBytes(in.bytes().size()).c_str(),
                vff::cli::formatBytes(report.fileBytes).c_str(), vff::codecName(w.codec),
                w.filter == vff::Filter::kNone ? "none" : "hits-med where smaller", report.seconds);
    printPlane("distance", report.planes[0], o.blocks);
    if (report.planes[1].present) printPlane("normal", report.planes[1], o.blocks);
    if (report.bc4.done) {
      const auto& b = report.bc4;
      std::printf("  bc4      unorm8-diameter -> bc4-diameter: %llu of %llu hits changed, max error %u codes, RMS "
                  "%.3f codes (a code is 2R/254); every hit and miss kept\n",
                  static_cast<unsigned long long>(b.changed), static_cast<unsigned long long>(b.hits), b.maxError,
                  b.hits ? std::sqrt(b.sumSquared / double(b.hits)) : 0.0);
    }
    if (const auto& r = report.refinement; r.present && r.remade)
      std::printf("  refinement remade for the new maps from its own triangles and margin: %u unsure texels (were %u)\n",
                  r.unsureAfter, r.unsureBefore);
    else if (r.present)
      std::printf("  refinement kept (the maps decode as before): %u unsure texels\n", r.unsureAfter);
  }
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{
      "Compresses a visibility field (.vff) losslessly, decompresses it, or benchmarks the codecs.\n"
      "Compression: every block is one zstd frame (random access per block survives); distance blocks\n"
      "of unorm8-* fields also try the hits-med filter (format 1.1: a hit mask and median-predicted\n"
      "hit codes) and keep it where it is smaller. --decompress writes stored blocks (format 1.0), the\n"
      "form a GPU loader uploads without decoding. Layout, metadata and maps are kept exactly; the\n"
      "refinement (REFN) is kept, or with --bc4 remade for the new maps from its own triangles; the\n"
      "output is written through a temporary file and a rename.\n"
      "  vff-compress in.vff out.vff\n"
      "  vff-compress --decompress in.vff out.vff\n"
      "  vff-compress --benchmark a.vff [b.vff ...]\n" +
      vff::cli::exitCodeHelp()};
  addOptions(app, o);
  if (auto rc = vff::cli::parse(app, kProg, argc, argv)) return *rc;

  if (o.benchmark) {
    if (o.decompress) {
      vff::cli::usageError(kProg, "--benchmark and --decompress do not go together");
      return vff::cli::kExitUsage;
    }
    if (o.tmpDir.empty()) o.tmpDir = std::filesystem::temp_directory_path().string();
    return vff::compress::benchmark(o.files, o.repeat, o.tmpDir, o.candidates);
  }
  if (o.files.size() != 2) {
    vff::cli::usageError(kProg, "give an input and an output file (or --benchmark FILES...)");
    return vff::cli::kExitUsage;
  }
  const std::string& input = o.files[0];
  const std::string& output = o.files[1];
  if (o.decompress && (o.filter != "auto" || app.count("--level") || o.bc4)) {
    vff::cli::usageError(kProg, "--filter, --level and --bc4 apply to compression only");
    return vff::cli::kExitUsage;
  }

  auto in = vff::File::open(input);
  if (!in) return vff::cli::reportError(kProg, input, in.error());
  Plan plan;
  if (auto rc = planRewrite(o, input, *in, &plan)) return *rc;
  auto w = writeOptions(o, input, *in, plan);
  if (!w) return vff::cli::reportError(kProg, input, w.error());
  // The progress line (on a terminal, not with --quiet or --format json), as vff-bake's.
  vff::cli::Progress progress(kProg, !o.quiet && o.common.format != vff::cli::OutputFormat::kJson && isatty(2));
  w->progress = [&](uint64_t done, uint64_t total) { progress.update(done, total); };
  vff::compress::Report report;
  if (vff::Status st = vff::compress::rewrite(*in, output, plan.field, *w, plan.reencode, &report); !st)
    return vff::cli::reportError(kProg, st.error().code == vff::Code::kIoWrite ? output : input, st.error());
  printReport(o, input, output, *in, *w, report);
  return vff::cli::kExitSuccess;
}
