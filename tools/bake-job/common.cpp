// common.cpp - what vff-bake's bakes share: the checks of a planned field,
// writing the maps and the summary (see bake.h).
#include <sys/resource.h>

#include <cinttypes>
#include <cstdio>

#include "bake_job.h"
#include "cli.h"

namespace vff::bake_tool {

double secondsSince(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

std::string baseName(const std::string& p) {
  const size_t s = p.find_last_of('/');
  return s == std::string::npos ? p : p.substr(s + 1);
}

double peakRssMiB() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return double(ru.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

std::optional<int> checkPlan(const Result<FieldDesc>& field, const LayoutLimits& limits, uint64_t* payload) {
  if (!field) {
    cli::usageError(kProg, field.error().message);
    return cli::kExitUsage;
  }
  if (auto layout = computeLayout(field.value(), limits); !layout) {
    cli::usageError(kProg, layout.error().message);
    return cli::kExitUsage;
  }
  *payload = field->mapCount * (distanceMapBytes(field->distanceEncoding, field->mapResolution) +
                                normalMapBytes(field->normalEncoding, field->mapResolution));
  if (*payload > (uint64_t{16} << 30)) {
    cli::usageError(kProg, "the field would hold " + std::to_string(*payload) +
                               " bytes, above the baker's 16 GiB limit: fewer maps or a smaller --map-size");
    return cli::kExitUsage;
  }
  return std::nullopt;
}

std::optional<int> writeBaked(const Options& o, const std::string& output, Writer& writer,
                              const bake::BakedField& baked, double* seconds, uint64_t* fileBytes) {
  const auto t0 = std::chrono::steady_clock::now();
  Status st = writer.writeMaps(Plane::kDistance, baked.distance);
  if (st && o.normals) st = writer.writeMaps(Plane::kNormal, baked.normals);
  if (st) st = writer.finish();
  if (!st) return cli::reportError(kProg, output, st.error());
  *seconds = secondsSince(t0);
  if (auto f = File::open(output, {.checksums = ChecksumPolicy::kNone})) *fileBytes = f->info().fileSize;
  return std::nullopt;
}

nlohmann::json bakeSummary(const bake::BakeOptions& bo, const FieldDesc& field, const bake::BakeStats& s,
                           uint64_t payload, double bakeSeconds) {
  const double rays = double(s.rays);
  return {{"sphere", {{"center", {field.sphere.center[0], field.sphere.center[1], field.sphere.center[2]}},
                      {"radius", field.sphere.radius}}},
          {"positions", positionSchemeName(bo.positionScheme)},
          {"positionParam", bo.positionParam},
          {"maps", field.mapCount},
          {"mapResolution", field.mapResolution},
          {"encoding", distanceEncodingName(bo.encoding)},
          {"normals", bo.normals},
          {"rays", s.rays},
          {"hits", s.hits},
          {"hitRatio", rays > 0 ? double(s.hits) / rays : 0.0},
          {"payloadBytes", payload},
          {"raysPerSecond", bakeSeconds > 0 ? rays / bakeSeconds : 0.0},
          {"peakRssMiB", peakRssMiB()}};
}

}  // namespace vff::bake_tool
