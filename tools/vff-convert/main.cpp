// vff-convert: converts a visibility field between .vff, OpenEXR and OpenVDB, and repacks .vff files.
//
//   vff-convert field.vff --to exr field.exr [--half]   packed slices as a multi-part EXR
//   vff-convert field.exr --to vff field.vff            back, lossless from a FLOAT export
//   vff-convert a.vff --to vff b.vff --max-texture-size 512 --codec zstd   new layout / codec
//   vff-convert a.vff --to vff b.vff --encoding unorm8-diameter --map-size 32 --count 16   re-encode, LOD
//   vff-convert field.vff --to vdb field.vdb            packed slices as OpenVDB grids (vdb.h), and back
//
// The input's kind is found by its magic number, the output's by --to (or its extension). The
// command line is convert_options.cpp; here: read the input, change the maps, write the output.
#include <OpenEXR/ImfThreading.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <optional>

#include "cli.h"
#include "convert.h"
#include "convert_options.h"
#include "platform/parallel.h"
#include "resample.h"
#include "vdb.h"
#include "vff/vff.h"

namespace {

using vff::convert::FieldData;
using vff::convert::kProg;
using vff::convert::Options;

// Reads a whole .vff into memory, with what is needed to write it again as it was.
vff::Result<FieldData> loadVff(const std::string& path) {
  auto f = vff::File::open(path);
  if (!f) return std::move(f).error();
  FieldData d;
  d.field = f->field();
  d.layout = f->layout();
  d.metadata = std::string(f->metadata());
  if (const vff::RefinementView& r = f->refinement(); !r.empty())
    d.refinement = {r.margin, {r.unsure.begin(), r.unsure.end()}, r.unsureTexels, {r.positions.begin(), r.positions.end()},
                    {r.indices.begin(), r.indices.end()}};
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
  w.codec = o.codec.codec.ifGiven().value_or(d.codec);
  w.zstdLevel = o.codec.zstdLevel;
  // The source's G is kept only with the source's codec: a new codec re-picks it unless given.
  w.mapsPerBlock = o.codec.mapsPerBlockGiven() ? o.codec.mapsPerBlock : (w.codec == d.codec ? d.mapsPerBlock : 0);
  w.layout = o.layout.limits({d.layout.target, d.layout.maxTextureSize, d.layout.maxLayers, d.layout.gutter});
  w.metadataJson = d.metadata;
  w.refinement = d.refinement.view();
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
    std::printf("%s: %s of %ux%u %s, %s of %ux%u (%s, gutter %u), codec %s\n", o.output.c_str(),
                vff::cli::count(d.field.mapCount, "map").c_str(), d.field.mapResolution, d.field.mapResolution,
                vff::distanceEncodingName(d.field.distanceEncoding), vff::cli::count(layout->sliceCount, "slice").c_str(),
                layout->sliceWidth,
                layout->sliceHeight, vff::layoutTargetName(layout->target), layout->gutter, vff::codecName(w.codec));
  if (!o.quiet && !d.refinement.indices.empty())
    std::printf("%s: refinement: %u unsure texels, %zu triangles\n", o.output.c_str(), d.refinement.unsureTexels,
                d.refinement.indices.size() / 3);
  return vff::cli::kExitSuccess;
}

// A refinement's unsure texels belong to the maps they were marked on: for new maps they are marked
// again, from the refinement's own triangles, with its margin in the same multiple of the field's
// spread. A bit1 field holds no distances to mark (the refinement is left out, with a warning).
int remakeRefinement(const Options& o, const FieldData& from, FieldData* to) {
  if (from.refinement.indices.empty()) return vff::cli::kExitSuccess;
  if (to->field.distanceEncoding == vff::DistanceEncoding::kBit1) {
    std::fprintf(stderr, "%s: warning: %s: the refinement (REFN) is left out: a bit1 field holds no distances to refine\n",
                 kProg, o.input.c_str());
    return vff::cli::kExitSuccess;
  }
  vff::RefineOptions r;
  r.marginSpreads = from.refinement.margin / vff::refineSpread(from.field);
  r.threads = o.threads;
  auto made = vff::makeRefinement(to->field, to->distance, from.refinement.positions, from.refinement.indices, r);
  if (!made) return vff::cli::reportError(kProg, o.input, made.error());
  if (!o.quiet)
    std::printf("refinement remade for the new maps from its own triangles: %u unsure texels (were %u)\n",
                made->unsureTexels, from.refinement.unsureTexels);
  to->refinement = std::move(*made);
  return vff::cli::kExitSuccess;
}

// Re-encoding and level of detail (resample.h): new maps from the source's, with a provenance entry
// appended to META. Returns an exit code; *d becomes the converted field.
int resampleMaps(const Options& o, FieldData* d) {
  vff::convert::ResampleOptions r;
  r.encoding = o.encoding.ifGiven();
  r.positionScheme = o.positions.ifGiven();
  r.positionParam = o.count.value_or(0);
  r.mapResolution = o.mapSize.value_or(0);
  if (o.downsample.given()) r.downsample = o.downsample.value();
  if (o.resample.given()) r.resample = o.resample.value();
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
  if (int rc = remakeRefinement(o, *d, &*out); rc != vff::cli::kExitSuccess) return rc;
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
    std::printf("%s: %s of %ux%u (%s)%s, %s\n", o.output.c_str(), vff::cli::count(d.layout.sliceCount, "slice").c_str(),
                d.layout.sliceWidth, d.layout.sliceHeight, o.half ? "HALF" : "FLOAT",
                d.field.normalEncoding != vff::NormalEncoding::kNone ? " with normals" : "",
                vff::cli::count(d.field.mapCount, "map").c_str());
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
    std::printf("%s: grid \"distance\"%s, %s (hit texels) in %s of %ux%u, %s\n", o.output.c_str(),
                d.field.normalEncoding != vff::NormalEncoding::kNone ? " and \"normal\"" : "",
                vff::cli::count(report.activeVoxels, "active voxel").c_str(),
                vff::cli::count(d.layout.sliceCount, "slice").c_str(), d.layout.sliceWidth, d.layout.sliceHeight,
                vff::cli::count(d.field.mapCount, "map").c_str());
  return vff::cli::kExitSuccess;
}

// "vff-convert: warning: INPUT: COUNT WHAT" when count is not 0.
void warnCount(const Options& o, uint64_t count, const char* what) {
  if (count)
    std::fprintf(stderr, "%s: warning: %s: %llu %s\n", kProg, o.input.c_str(), static_cast<unsigned long long>(count),
                 what);
}

// Reads the input, of the kind its magic number says, into *d and its kind into *kind ("vff",
// "exr", "vdb"), with a warning for each kind of value an EXR or VDB import did not find exact.
// Returns the exit code of a failure (an input of the output's kind is a usage error).
std::optional<int> readInput(const Options& o, FieldData* d, const char** kind) {
  // Before the magic numbers are read: a FIFO would block the reads until a writer came.
  if (vff::Status st = vff::cli::checkRegularFile(o.input); !st) return vff::cli::reportError(kProg, o.input, st.error());
  const bool exr = vff::convert::looksLikeExr(o.input);
  const bool vdb = !exr && vff::convert::looksLikeVdb(o.input);
  *kind = exr ? "exr" : vdb ? "vdb" : "vff";
  if ((exr || vdb) && o.to == *kind) {
    vff::cli::usageError(kProg, o.input + (exr ? " is already an EXR file" : " is already an OpenVDB file") +
                                    ": convert it --to vff");
    return vff::cli::kExitUsage;
  }
  vff::convert::ExrReadReport exrReport;
  vff::convert::VdbReadReport vdbReport;
  auto r = exr   ? vff::convert::readExr(o.input, &exrReport)
           : vdb ? vff::convert::readVdb(o.input, &vdbReport)
                 : loadVff(o.input);
  if (!r) return vff::cli::reportError(kProg, o.input, r.error());
  warnCount(o, exrReport.inexactTexels,
            "hit texels do not hold an exactly decoded distance; they were quantised to the nearest code");
  warnCount(o, exrReport.ambiguousTexels,
            "hit texels are ambiguous: HALF holds the same value for neighbouring codes, so the codes may "
            "differ from the original (export with FLOAT)");
  warnCount(o, vdbReport.inexactTexels,
            "active voxels do not hold an exactly decoded distance; they were quantised to the nearest code");
  warnCount(o, exrReport.inexactNormals + vdbReport.inexactNormals,
            "normals are not exact oct-snorm16 values; they were quantised");
  *d = std::move(r).value();
  return std::nullopt;
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
  addOptions(app, o);
  if (auto rc = vff::cli::parse(app, kProg, argc, argv)) return *rc;
  if (auto problem = checkOptions(&o)) {
    vff::cli::usageError(kProg, *problem);
    return vff::cli::kExitUsage;
  }

  // OpenEXR's worker threads (de)compress the scanline blocks; a tool may set this process-wide.
  Imf::setGlobalThreadCount(static_cast<int>(vff::parallel::resolveThreads(o.threads)));

  FieldData d;
  const char* inputKind = "vff";
  if (auto rc = readInput(o, &d, &inputKind)) return *rc;
  if (o.resampling())
    if (int rc = resampleMaps(o, &d); rc != vff::cli::kExitSuccess) return rc;
  if ((o.to == "exr" || o.to == "vdb") && !d.refinement.indices.empty())
    std::fprintf(stderr, "%s: warning: %s: the refinement (REFN) is not exported: %s holds the maps only\n", kProg,
                 o.input.c_str(), o.to == "vdb" ? "OpenVDB" : "EXR");
  if (o.to == "vdb") return toVdb(o, d, inputKind);
  return o.to == "exr" ? toExr(o, d) : saveVff(o, d);
}
