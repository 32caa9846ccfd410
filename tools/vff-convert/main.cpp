// vff-convert: converts a visibility field between .vff, OpenEXR and OpenVDB, and repacks .vff files.
//
//   vff-convert field.vff --to exr field.exr [--half]   packed slices as a multi-part EXR
//   vff-convert field.exr --to vff field.vff            back, lossless from a FLOAT export
//   vff-convert a.vff --to vff b.vff --max-texture-size 512 --codec zstd   new layout / codec
//   vff-convert a.vff --to vff b.vff --encoding unorm8-diameter --map-size 32 --count 16   re-encode, LOD
//   vff-convert field.vff --to vdb field.vdb            packed slices as OpenVDB grids (vdb.h), and back
//
// The input's kind is found by its magic number, the output's by --to (or its extension).
#include <OpenEXR/ImfThreading.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <map>
#include <optional>
#include <thread>

#include "cli.h"
#include "convert.h"
#include "resample.h"
#include "vdb.h"
#include "vff/vff.h"

namespace {

using vff::convert::FieldData;

const char* kProg = "vff-convert";

struct Options {
  std::string input, output, to;
  bool half = false;
  bool quiet = false;
  std::optional<std::string> target;
  std::optional<uint32_t> maxTextureSize, maxLayers, gutter, mapsPerBlock;
  std::optional<std::string> codec;
  int zstdLevel = 19;
  unsigned threads = 0;
  // Conversions that change the maps (resample.h).
  std::optional<std::string> encoding, positions, downsample, resample;
  std::optional<uint32_t> mapSize, count;
};

const std::map<std::string, vff::Codec> kCodecs = {{"stored", vff::Codec::kStored}, {"zstd", vff::Codec::kZstd}};
const std::map<std::string, vff::LayoutTarget> kTargets = {{"2d-array", vff::LayoutTarget::kTexture2DArray},
                                                           {"3d", vff::LayoutTarget::kTexture3D}};

const std::map<std::string, vff::DistanceEncoding> kEncodings = {
    {"unorm8-diameter", vff::DistanceEncoding::kUnorm8Diameter},
    {"unorm8-chord", vff::DistanceEncoding::kUnorm8Chord},
    {"unorm16-diameter", vff::DistanceEncoding::kUnorm16Diameter},
    {"bit1", vff::DistanceEncoding::kBit1},
    {"bc4-diameter", vff::DistanceEncoding::kBc4Diameter}};
const std::map<std::string, vff::PositionScheme> kPositions = {
    {"octa-hemi2", vff::PositionScheme::kOctaHemi2},
    {"ea-octa-grid", vff::PositionScheme::kEqualAreaOctaGrid},
    {"fibonacci", vff::PositionScheme::kSphericalFibonacci}};
const std::map<std::string, vff::convert::DownsampleRule> kRules = {
    {"min", vff::convert::DownsampleRule::kMin},
    {"majority", vff::convert::DownsampleRule::kMajority},
    {"centre", vff::convert::DownsampleRule::kCentre},
    {"tent", vff::convert::DownsampleRule::kTent}};
const std::map<std::string, vff::convert::PositionResample> kResamples = {
    {"nearest", vff::convert::PositionResample::kNearest},
    {"interpolated", vff::convert::PositionResample::kInterpolated}};

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

// Reads a whole .vff into memory, with what is needed to write it again as it was.
vff::Result<FieldData> loadVff(const std::string& path) {
  auto f = vff::File::open(path);
  if (!f) return std::move(f).error();
  FieldData d;
  d.field = f->field();
  d.layout = f->layout();
  d.metadata = std::string(f->metadata());
  const vff::PlaneInfo& dist = f->plane(vff::Plane::kDistance);
  d.codec = dist.blocks.empty() ? vff::Codec::kStored : dist.blocks.front().codec;
  // G as a write option: 0 when every plane has the writer's automatic G (it differs per plane),
  // else the distance plane's (the writer gives both planes the same explicit G).
  const auto autoG = [&](const vff::PlaneInfo& p) {
    return std::min<uint64_t>(std::max<uint64_t>(1, (256u << 10) / std::max<uint32_t>(p.mapBytes, 1)),
                              d.field.mapCount);
  };
  const vff::PlaneInfo& norm = f->plane(vff::Plane::kNormal);
  const bool automatic = dist.mapsPerBlock == autoG(dist) && (!norm.present || norm.mapsPerBlock == autoG(norm));
  d.mapsPerBlock = automatic ? 0 : dist.mapsPerBlock;
  for (vff::Plane p : {vff::Plane::kDistance, vff::Plane::kNormal}) {
    if (!f->plane(p).present) continue;
    std::vector<uint8_t>& out = p == vff::Plane::kDistance ? d.distance : d.normals;
    // Decoded straight into the field (File::decodeBlock, not the File's block cache): one copy of
    // the payload, however well it compresses; memory is touched block by block as blocks decode.
    out.reserve(f->plane(p).rawBytes);
    for (uint32_t b = 0; b < f->plane(p).blocks.size(); ++b) {
      const uint64_t at = out.size();
      out.resize(at + f->plane(p).blocks[b].rawSize);
      if (vff::Status s = f->decodeBlock(p, b, std::span<uint8_t>(out).subspan(at)); !s) return std::move(s).error();
    }
  }
  return d;
}

// Writes a .vff: the source's layout limits, codec and G unless the command line overrides them.
int saveVff(const Options& o, const FieldData& d) {
  vff::WriteOptions w;
  w.codec = o.codec ? kCodecs.at(*o.codec) : d.codec;
  w.zstdLevel = o.zstdLevel;
  // The source's G is kept only with the source's codec: a new codec re-picks it unless given.
  w.mapsPerBlock = o.mapsPerBlock ? *o.mapsPerBlock : (w.codec == d.codec ? d.mapsPerBlock : 0);
  w.layout.target = o.target ? kTargets.at(*o.target) : d.layout.target;
  w.layout.maxTextureSize = o.maxTextureSize.value_or(d.layout.maxTextureSize);
  w.layout.maxLayers = o.maxLayers.value_or(d.layout.maxLayers);
  w.layout.gutter = o.gutter.value_or(d.layout.gutter);
  w.metadataJson = d.metadata;
  // A field that does not fit the requested limits is a command-line problem: exit 1, naming the limit.
  auto layout = vff::computeLayout(d.field, w.layout);
  if (!layout) {
    std::fprintf(stderr, "%s\n", vff::cli::formatDiagnostic(kProg, "error", o.output, layout.error()).c_str());
    std::fprintf(stderr,
                 "%s: the field (%u maps of %ux%u) does not fit the layout limits: target %s, "
                 "max texture size %u, max layers %u, gutter %u\n",
                 kProg, d.field.mapCount, d.field.mapResolution, d.field.mapResolution,
                 vff::layoutTargetName(w.layout.target), w.layout.maxTextureSize, w.layout.maxLayers, w.layout.gutter);
    return vff::cli::kExitUsage;
  }
  if (vff::Status s = vff::writeFile(o.output, d.field, d.distance, d.normals, w); !s)
    return vff::cli::reportError(kProg, o.output, s.error());
  if (!o.quiet)
    std::printf("%s: %u maps of %ux%u %s, %u slices of %ux%u (%s, gutter %u), codec %s\n", o.output.c_str(),
                d.field.mapCount, d.field.mapResolution, d.field.mapResolution,
                vff::distanceEncodingName(d.field.distanceEncoding), layout->sliceCount, layout->sliceWidth,
                layout->sliceHeight, vff::layoutTargetName(layout->target), layout->gutter, vff::codecName(w.codec));
  return vff::cli::kExitSuccess;
}

// Re-encoding and level of detail (resample.h): new maps from the source's, with a provenance entry
// appended to META. Returns an exit code; *d becomes the converted field.
int resampleMaps(const Options& o, FieldData* d) {
  vff::convert::ResampleOptions r;
  if (o.encoding) r.encoding = kEncodings.at(*o.encoding);
  if (o.positions) r.positionScheme = kPositions.at(*o.positions);
  r.positionParam = o.count.value_or(0);
  r.mapResolution = o.mapSize.value_or(0);
  if (o.downsample) r.downsample = kRules.at(*o.downsample);
  if (o.resample) r.resample = kResamples.at(*o.resample);
  r.threads = o.threads;
  vff::convert::ResampleReport report;
  auto out = vff::convert::resampleField(*d, r, &report);
  if (!out && out.error().code == vff::Code::kInvalidArgument) {
    vff::cli::usageError(kProg, out.error().message);
    return vff::cli::kExitUsage;
  }
  if (!out) return vff::cli::reportError(kProg, o.input, out.error());
  if (report.positionsChanged || report.mapSizeChanged || report.encodingChanged) {
    auto hash = vff::convert::fileXxh3(o.input);
    if (!hash) return vff::cli::reportError(kProg, o.input, hash.error());
    const size_t slash = o.input.find_last_of('/');
    auto meta = vff::convert::appendProvenance(d->metadata, d->field, out->field, r,
                                               slash == std::string::npos ? o.input : o.input.substr(slash + 1), *hash);
    if (!meta) return vff::cli::reportError(kProg, o.input, meta.error());
    out->metadata = std::move(*meta);
  }
  if (!o.quiet) std::printf("%s", vff::convert::describeResample(d->field, out->field, r, report).c_str());
  *d = std::move(*out);
  return vff::cli::kExitSuccess;
}

int toExr(const Options& o, const FieldData& d) {
  if (o.half && d.field.distanceEncoding == vff::DistanceEncoding::kUnorm16Diameter)
    std::fprintf(stderr,
                 "%s: warning: HALF cannot hold every unorm16-diameter distance exactly; "
                 "converting this EXR back will not reproduce all codes (use FLOAT)\n",
                 kProg);
  if (o.half && d.field.normalEncoding != vff::NormalEncoding::kNone)
    std::fprintf(stderr, "%s: warning: HALF normals are within about 1e-3 but not exact oct-snorm16 values\n", kProg);
  vff::convert::ExrWriteOptions e;
  e.half = o.half;
  if (vff::Status s = vff::convert::writeExr(o.output, d, e); !s)
    return vff::cli::reportError(kProg, o.output, s.error());
  if (!o.quiet)
    std::printf("%s: %u slices of %ux%u (%s)%s, %u maps\n", o.output.c_str(), d.layout.sliceCount, d.layout.sliceWidth,
                d.layout.sliceHeight, o.half ? "HALF" : "FLOAT",
                d.field.normalEncoding != vff::NormalEncoding::kNone ? " with normals" : "", d.field.mapCount);
  return vff::cli::kExitSuccess;
}

// The .vdb export (vdb.h), with a provenance entry naming the input and its XXH3.
int toVdb(const Options& o, const FieldData& d, const char* inputKind) {
  auto hash = vff::convert::fileXxh3(o.input);
  if (!hash) return vff::cli::reportError(kProg, o.input, hash.error());
  vff::convert::VdbWriteOptions v;
  const size_t slash = o.input.find_last_of('/');
  v.sourceName = slash == std::string::npos ? o.input : o.input.substr(slash + 1);
  v.sourceXxh3 = *hash;
  v.sourceFormat = inputKind;
  vff::convert::VdbWriteReport report;
  if (vff::Status s = vff::convert::writeVdb(o.output, d, v, &report); !s)
    return vff::cli::reportError(kProg, o.output, s.error());
  if (!o.quiet)
    std::printf("%s: grid \"distance\"%s, %llu active voxels (hit texels) in %u slices of %ux%u, %u maps\n",
                o.output.c_str(), d.field.normalEncoding != vff::NormalEncoding::kNone ? " and \"normal\"" : "",
                static_cast<unsigned long long>(report.activeVoxels), d.layout.sliceCount, d.layout.sliceWidth,
                d.layout.sliceHeight, d.field.mapCount);
  return vff::cli::kExitSuccess;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{
      "Converts a visibility field (.vff) to OpenEXR or OpenVDB and back, or repacks a .vff with a new layout\n"
      "or codec.\n"
      "EXR: one part \"slice.S\" per packed slice with channels Y (distance in object units; +inf for a\n"
      "miss) and miss (1 miss, 0 hit); with normals, parts \"normal.S\" with R G B (0 0 0 for a miss);\n"
      "the field, layout and metadata in the string attribute vff.field. FLOAT exports convert back\n"
      "losslessly; HALF ones too for unorm8-* and bit1 (not unorm16-diameter, not normals).\n"
      "VDB: the slices as voxels (x, y, slice): FloatGrid \"distance\" (active at hits, background +inf)\n"
      "and with normals Vec3fGrid \"normal\"; string metadata vff.field (as the EXR's) and vff.provenance.\n"
      "Converts back losslessly for every encoding.\n"
      "Outputs are written through a temporary file and a rename: a failure leaves no partial file.\n" +
      vff::cli::exitCodeHelp()};
  vff::cli::addVersionFlag(app, kProg);
  app.add_option("input", o.input, "input .vff, .exr or .vdb (kind found by its magic number)")->required();
  app.add_option("output", o.output, "output file")->required();
  app.add_option("--to", o.to, "output kind (default: from the output's extension)")
      ->check(CLI::IsMember({"exr", "vff", "vdb"}));
  app.add_flag("--half", o.half, "EXR: HALF channels instead of FLOAT (lossy for unorm16-diameter and normals)");
  app.add_option("--target", o.target, "vff: GPU texture target of the packed layout (default: the input's)")
      ->check(CLI::IsMember({"2d-array", "3d"}));
  app.add_option("--max-texture-size", o.maxTextureSize, "vff: largest slice width/height (default: the input's)")
      ->check(CLI::PositiveNumber);
  app.add_option("--max-layers", o.maxLayers, "vff: most array layers or 3D depth (default: the input's)")
      ->check(CLI::PositiveNumber);
  app.add_option("--gutter", o.gutter, "vff: texels of edge replication around each tile (default: the input's)")
      ->check(CLI::Range(0u, 64u));
  app.add_option("--codec", o.codec, "vff: block codec (default: the input's)")
      ->check(CLI::IsMember({"stored", "zstd"}));
  app.add_option("--zstd-level", o.zstdLevel, "vff: zstd level")->check(CLI::Range(1, 22))->capture_default_str();
  app.add_option("--maps-per-block", o.mapsPerBlock,
                 "vff: maps per block (0: about 256 KiB per block; default: the input's)");
  app.add_option("-j,--threads", o.threads,
                 "threads for EXR compression and for re-encoding / LOD (0: all cores); the output does not "
                 "depend on it")
      ->capture_default_str();
  app.add_option("--encoding", o.encoding,
                 "vff: re-encode the distances (prints the largest and RMS error in steps of the new encoding; "
                 "bc4-diameter: lossy GPU block compression, half the size of unorm8; "
                 "from bit1: exit 5)")
      ->check(CLI::IsMember({"unorm8-diameter", "unorm8-chord", "unorm16-diameter", "bit1", "bc4-diameter"}));
  app.add_option("--map-size", o.mapSize, "vff: smaller maps M' (must divide the source's M; bit1: a multiple of 8)")
      ->check(CLI::PositiveNumber);
  app.add_option("--downsample", o.downsample,
                 "vff, with --map-size: how source texels combine into a new texel: tent (within one new texel "
                 "of its centre, tent-weighted; default), majority (those under it: hit if half hit, mean distance), "
                 "centre (the middle one or 2x2), min (hit if any hits, smallest distance)")
      ->check(CLI::IsMember({"min", "majority", "centre", "tent"}));
  app.add_option("--positions", o.positions, "vff: resample to another positional-sample scheme")
      ->check(CLI::IsMember({"octa-hemi2", "ea-octa-grid", "fibonacci"}));
  app.add_option("--count", o.count,
                 "vff: the new scheme parameter n, as vff-bake's --count (octa-hemi2 n: 2(2n^2+2n+1) maps)")
      ->check(CLI::PositiveNumber);
  app.add_option("--resample", o.resample,
                 "vff, with --positions/--count: nearest (nearest source sample, reprojected; default) or "
                 "interpolated (FieldQuery's blend of the neighbouring samples)")
      ->check(CLI::IsMember({"nearest", "interpolated"}));
  app.add_flag("-q,--quiet", o.quiet, "print nothing on success");
  if (auto rc = vff::cli::parse(app, kProg, argc, argv)) return *rc;

  if (o.to.empty()) {
    if (endsWith(o.output, ".exr"))
      o.to = "exr";
    else if (endsWith(o.output, ".vff"))
      o.to = "vff";
    else if (endsWith(o.output, ".vdb"))
      o.to = "vdb";
    else {
      vff::cli::usageError(kProg, "cannot tell the output kind from \"" + o.output + "\": give --to exr|vff|vdb");
      return vff::cli::kExitUsage;
    }
  }
  const bool layoutOptions = o.target || o.maxTextureSize || o.maxLayers || o.gutter || o.codec || o.mapsPerBlock ||
                             app.count("--zstd-level") > 0;
  if (o.to != "vff" && layoutOptions) {
    vff::cli::usageError(kProg,
                         "--target, --max-texture-size, --max-layers, --gutter, --codec, --zstd-level and "
                         "--maps-per-block apply to --to vff only");
    return vff::cli::kExitUsage;
  }
  const bool resampling = o.encoding || o.mapSize || o.downsample || o.positions || o.count || o.resample;
  if (o.to != "vff" && resampling) {
    vff::cli::usageError(kProg, "--encoding, --map-size, --downsample, --positions, --count and --resample apply to "
                                "--to vff only");
    return vff::cli::kExitUsage;
  }
  if ((o.downsample && !o.mapSize) || (o.resample && !o.positions && !o.count)) {
    vff::cli::usageError(kProg, o.downsample && !o.mapSize ? "--downsample applies with --map-size only"
                                                           : "--resample applies with --positions or --count only");
    return vff::cli::kExitUsage;
  }
  if (o.to != "exr" && o.half) {
    vff::cli::usageError(kProg, "--half applies to --to exr only");
    return vff::cli::kExitUsage;
  }

  // OpenEXR's worker threads (de)compress the scanline blocks; a tool may set this process-wide.
  Imf::setGlobalThreadCount(
      static_cast<int>(o.threads ? o.threads : std::max(1u, std::thread::hardware_concurrency())));

  FieldData d;
  const char* inputKind = "vff";
  if (vff::convert::looksLikeExr(o.input)) {
    inputKind = "exr";
    if (o.to == "exr") {
      vff::cli::usageError(kProg, o.input + " is already an EXR file: convert it --to vff");
      return vff::cli::kExitUsage;
    }
    vff::convert::ExrReadReport report;
    auto r = vff::convert::readExr(o.input, &report);
    if (!r) return vff::cli::reportError(kProg, o.input, r.error());
    if (report.inexactTexels)
      std::fprintf(stderr,
                   "%s: warning: %s: %llu hit texels do not hold an exactly decoded distance; they were "
                   "quantised to the nearest code\n",
                   kProg, o.input.c_str(), static_cast<unsigned long long>(report.inexactTexels));
    if (report.ambiguousTexels)
      std::fprintf(stderr,
                   "%s: warning: %s: %llu hit texels are ambiguous: HALF holds the same value for "
                   "neighbouring codes, so the codes may differ from the original (export with FLOAT)\n",
                   kProg, o.input.c_str(), static_cast<unsigned long long>(report.ambiguousTexels));
    if (report.inexactNormals)
      std::fprintf(stderr, "%s: warning: %s: %llu normals are not exact oct-snorm16 values; they were quantised\n",
                   kProg, o.input.c_str(), static_cast<unsigned long long>(report.inexactNormals));
    d = std::move(r).value();
  } else if (vff::convert::looksLikeVdb(o.input)) {
    if (o.to == "vdb") {
      vff::cli::usageError(kProg, o.input + " is already an OpenVDB file: convert it --to vff");
      return vff::cli::kExitUsage;
    }
    vff::convert::VdbReadReport report;
    auto r = vff::convert::readVdb(o.input, &report);
    if (!r) return vff::cli::reportError(kProg, o.input, r.error());
    if (report.inexactTexels)
      std::fprintf(stderr,
                   "%s: warning: %s: %llu active voxels do not hold an exactly decoded distance; they were "
                   "quantised to the nearest code\n",
                   kProg, o.input.c_str(), static_cast<unsigned long long>(report.inexactTexels));
    if (report.inexactNormals)
      std::fprintf(stderr, "%s: warning: %s: %llu normals are not exact oct-snorm16 values; they were quantised\n",
                   kProg, o.input.c_str(), static_cast<unsigned long long>(report.inexactNormals));
    d = std::move(r).value();
    inputKind = "vdb";
  } else {
    auto r = loadVff(o.input);
    if (!r) return vff::cli::reportError(kProg, o.input, r.error());
    d = std::move(r).value();
  }
  if (resampling)
    if (int rc = resampleMaps(o, &d); rc != vff::cli::kExitSuccess) return rc;
  if (o.to == "vdb") return toVdb(o, d, inputKind);
  return o.to == "exr" ? toExr(o, d) : saveVff(o, d);
}
