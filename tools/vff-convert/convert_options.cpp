// convert_options.cpp - vff-convert's command line (see convert_options.h).
#include "convert_options.h"

namespace vff::convert {

namespace {

bool endsWith(const std::string& s, const std::string& suffix) {
  return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

bool Options::resampling() const {
  return encoding.given() || mapSize || downsample.given() || positions.given() || count || resample.given();
}

void addOptions(CLI::App& app, Options& o) {
  app.add_option("input", o.input, "input .vff, .exr or .vdb (kind found by its magic number)")->required();
  app.add_option("output", o.output, "output file")->required();
  app.add_option("--to", o.to, "output kind (default: from the output's extension)")
      ->check(CLI::IsMember({"exr", "vff", "vdb"}));
  app.add_flag("--half", o.half, "EXR: HALF channels instead of FLOAT (lossy for unorm16-diameter and normals)");
  o.layout.add(app, cli::Defaults::kInput);
  o.codec.add(app, cli::Defaults::kInput);
  app.add_option("-j,--threads", o.threads,
                 "threads for EXR compression and for re-encoding / LOD (0: all cores); the output does not "
                 "depend on it")
      ->capture_default_str();
  o.encoding.add(app,
                 "vff: re-encode the distances (prints the largest and RMS error in steps of the new encoding; "
                 "bc4-diameter: lossy GPU block compression, half the size of unorm8; "
                 "from bit1: exit 5)");
  app.add_option("--map-size", o.mapSize, "vff: smaller maps M' (must divide the source's M; bit1: a multiple of 8)")
      ->check(CLI::PositiveNumber);
  o.downsample.add(app,
                   "vff, with --map-size: how source texels combine into a new texel: tent (within one new texel "
                   "of its centre, tent-weighted; default), majority (those under it: hit if half hit, mean distance), "
                   "centre (the middle one or 2x2), min (hit if any hits, smallest distance)");
  o.positions.add(app, "vff: resample to another positional-sample scheme");
  app.add_option("--count", o.count,
                 "vff: the new scheme parameter n, as vff-bake's --count (octa-hemi2 n: 2(2n^2+2n+1) maps)")
      ->check(CLI::PositiveNumber);
  o.resample.add(app,
                 "vff, with --positions/--count: nearest (nearest source sample, reprojected; default) or "
                 "interpolated (FieldQuery's blend of the neighbouring samples)");
  app.add_flag("-q,--quiet", o.quiet, "print nothing on success");
}

std::optional<std::string> checkOptions(Options* o) {
  if (o->to.empty()) {
    if (endsWith(o->output, ".exr"))
      o->to = "exr";
    else if (endsWith(o->output, ".vff"))
      o->to = "vff";
    else if (endsWith(o->output, ".vdb"))
      o->to = "vdb";
    else
      return "cannot tell the output kind from \"" + o->output + "\": give --to exr|vff|vdb";
  }
  if (o->to != "vff" && (o->layout.given() || o->codec.given()))
    return "--target, --max-texture-size, --max-layers, --gutter, --codec, --zstd-level and "
           "--maps-per-block apply to --to vff only";
  if (o->to != "vff" && o->resampling())
    return "--encoding, --map-size, --downsample, --positions, --count and --resample apply to "
           "--to vff only";
  if (o->downsample.given() && !o->mapSize) return "--downsample applies with --map-size only";
  if (o->resample.given() && !o->positions.given() && !o->count)
    return "--resample applies with --positions or --count only";
  if (o->to != "exr" && o->half) return "--half applies to --to exr only";
  return std::nullopt;
}

}  // namespace vff::convert
