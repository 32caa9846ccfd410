// reencode.cpp - stage 3 of a resampling conversion (a texel into its new encoding, with the
// quantisation error it adds), the provenance entry, and the source file's hash.
#include <xxhash.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <nlohmann/json.hpp>

#include "cli.h"
#include "resample.h"
#include "vff/version.h"

namespace vff::convert {

const char* downsampleRuleName(DownsampleRule r) noexcept {
  switch (r) {
    case DownsampleRule::kMin: return "min";
    case DownsampleRule::kMajority: return "majority";
    case DownsampleRule::kCentre: return "centre";
    case DownsampleRule::kTent: return "tent";
    case DownsampleRule::kInvalid: break;
  }
  return "invalid";
}

const char* positionResampleName(PositionResample r) noexcept {
  switch (r) {
    case PositionResample::kNearest: return "nearest";
    case PositionResample::kInterpolated: return "interpolated";
    case PositionResample::kInvalid: break;
  }
  return "invalid";
}

void EncodeStats::merge(const EncodeStats& o) noexcept {
  maxErrorSteps = std::max(maxErrorSteps, o.maxErrorSteps);
  maxErrorRadii = std::max(maxErrorRadii, o.maxErrorRadii);
  sumSquaredSteps += o.sumSquaredSteps;
  maxClampRadii = std::max(maxClampRadii, o.maxClampRadii);
  hits += o.hits;
  clamped += o.clamped;
}

uint32_t encodeTexel(DistanceEncoding to, bool hit, float distance, float radius, float cosAlpha,
                     EncodeStats* stats) noexcept {
  // encodeDistance never turns a hit into the miss code nor a miss into a hit code.
  const uint32_t code = encodeDistance(to, hit, distance, radius, cosAlpha);
  if (!hit) return code;
  ++stats->hits;
  if (to == DistanceEncoding::kBit1) return code;  // no distance kept: nothing to measure
  const float step = quantizationStep(to, radius, cosAlpha);
  const float scale = step * float(maxHitCode(to));
  const double error = std::fabs(double(decodeDistance(to, code, radius, cosAlpha).distance) - double(distance));
  if (distance / scale > 1.0f) {
    // Beyond the encoding's range (a unorm8-diameter distance longer than the unorm8-chord chord,
    // by at most half a source step): stored as the largest code. Not a quantisation error.
    ++stats->clamped;
    stats->maxClampRadii = std::max(stats->maxClampRadii, error / double(radius));
    return code;
  }
  accountError(stats, error, step, radius);
  return code;
}

void accountError(EncodeStats* stats, double error, float step, float radius) noexcept {
  stats->maxErrorSteps = std::max(stats->maxErrorSteps, error / double(step));
  stats->maxErrorRadii = std::max(stats->maxErrorRadii, error / double(radius));
  stats->sumSquaredSteps += (error / double(step)) * (error / double(step));
}

Result<std::string> appendProvenance(const std::string& metadata, const FieldDesc& source, const FieldDesc& result,
                                     const ResampleOptions& options, const std::string& sourceName,
                                     uint64_t sourceXxh3, const char* tool) {
  nlohmann::json meta = nlohmann::json::object();
  if (!metadata.empty()) {
    meta = nlohmann::json::parse(metadata, nullptr, /*allow_exceptions=*/false);
    // The reader has checked META (rule 8001): a text nlohmann cannot hold has a number beyond binary64.
    if (meta.is_discarded())
      return makeError(Code::kUnsupported, "the source's META holds a number beyond the binary64 range");
    if (!meta.is_object()) return makeError(Code::kMetadataNotObject, "the source's META is not a JSON object");
  }
  nlohmann::json& list = meta["vff.provenance"];
  if (list.is_null()) list = nlohmann::json::array();
  if (!list.is_array())
    return makeError(Code::kMetadataJson, "the source's META key \"vff.provenance\" is not an array");

  nlohmann::json ops = nlohmann::json::array(), opts = nlohmann::json::object();
  if (result.positionScheme != source.positionScheme || result.positionParam != source.positionParam) {
    ops.push_back("positions");
    opts["positions"] = positionSchemeName(result.positionScheme);
    opts["count"] = result.positionParam;
    opts["resample"] = positionResampleName(options.resample);
  }
  if (result.mapResolution != source.mapResolution) {
    ops.push_back("map-size");
    opts["mapSize"] = result.mapResolution;
    opts["downsample"] = downsampleRuleName(options.downsample);
  }
  if (result.distanceEncoding != source.distanceEncoding) {
    ops.push_back("encoding");
    opts["encoding"] = distanceEncodingName(result.distanceEncoding);
  }
  list.push_back({{"tool", tool},
                  {"version", kLibraryVersion},
                  {"operations", ops},
                  {"options", opts},
                  {"source",
                   {{"name", sourceName},
                    {"xxh3", cli::hexDigits64(sourceXxh3)},
                    {"positionScheme", positionSchemeName(source.positionScheme)},
                    {"positionParam", source.positionParam},
                    {"mapCount", source.mapCount},
                    {"mapResolution", source.mapResolution},
                    {"distanceEncoding", distanceEncodingName(source.distanceEncoding)}}}});
  return meta.dump();
}

std::string describeResample(const FieldDesc& from, const FieldDesc& to, const ResampleOptions& options,
                             const ResampleReport& r) {
  std::string s;
  char buf[512];
  if (!r.positionsChanged && !r.mapSizeChanged && !r.encodingChanged)
    return "nothing to resample: the options match the source, the maps are unchanged\n";
  if (r.positionsChanged) {
    std::snprintf(buf, sizeof buf, "positions: %s n=%u (%u maps) -> %s n=%u (%u maps), resample %s\n",
                  positionSchemeName(from.positionScheme), from.positionParam, from.mapCount,
                  positionSchemeName(to.positionScheme), to.positionParam, to.mapCount,
                  positionResampleName(options.resample));
    s += buf;
  }
  if (r.mapSizeChanged) {
    std::snprintf(buf, sizeof buf, "map size: %u -> %u, downsample %s (%ux%u source texels under each new texel)\n",
                  from.mapResolution, to.mapResolution, downsampleRuleName(options.downsample), r.factor, r.factor);
    s += buf;
  }
  const char* enc = distanceEncodingName(to.distanceEncoding);
  if (to.distanceEncoding == DistanceEncoding::kBit1) {
    std::snprintf(buf, sizeof buf, "encoding: %s -> bit1: distances dropped, hit or miss kept\n",
                  distanceEncodingName(from.distanceEncoding));
    s += buf;
  } else {
    std::snprintf(buf, sizeof buf, "%s%s%s%s: max error %.3f steps of %s (%.6f R), RMS %.3f steps, over %llu hits\n",
                  r.encodingChanged ? "encoding: " : "quantisation (",
                  r.encodingChanged ? distanceEncodingName(from.distanceEncoding) : enc,
                  r.encodingChanged ? " -> " : ")", r.encodingChanged ? enc : "", r.maxErrorSteps, enc, r.maxErrorRadii,
                  r.rmsErrorSteps, static_cast<unsigned long long>(r.hits));
    s += buf;
    if (r.reverseChecked && r.notReversible == 0) {
      std::snprintf(buf, sizeof buf, "reversible: converting back to %s gives every code back\n",
                    distanceEncodingName(from.distanceEncoding));
      s += buf;
    } else if (r.reverseChecked) {
      std::snprintf(buf, sizeof buf, "not reversible: converting back to %s changes %llu codes\n",
                    distanceEncodingName(from.distanceEncoding), static_cast<unsigned long long>(r.notReversible));
      s += buf;
    }
    if (r.clamped) {
      std::snprintf(buf, sizeof buf,
                    "clamped: %llu hits lie beyond the new scale and hold its largest code (at most %.6f R beyond)\n",
                    static_cast<unsigned long long>(r.clamped), r.maxClampRadii);
      s += buf;
    }
  }
  std::snprintf(buf, sizeof buf, "hits: %llu of %llu texels (%.2f%%) -> %llu of %llu (%.2f%%)\n",
                static_cast<unsigned long long>(r.sourceHits), static_cast<unsigned long long>(r.sourceTexels),
                r.sourceTexels ? 100.0 * double(r.sourceHits) / double(r.sourceTexels) : 0.0,
                static_cast<unsigned long long>(r.hits), static_cast<unsigned long long>(r.texels),
                r.texels ? 100.0 * double(r.hits) / double(r.texels) : 0.0);
  s += buf;
  return s;
}

Result<uint64_t> fileXxh3(const std::string& path) {
  std::unique_ptr<FILE, int (*)(FILE*)> f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) return makeError(Code::kIoOpen, "cannot open the file to hash it");
  std::unique_ptr<XXH3_state_t, XXH_errorcode (*)(XXH3_state_t*)> s(XXH3_createState(), &XXH3_freeState);
  if (!s || XXH3_64bits_reset(s.get()) != XXH_OK) return makeError(Code::kOutOfMemory, "cannot start XXH3");
  std::vector<unsigned char> buf(size_t{1} << 20);
  size_t n = 0;
  while ((n = std::fread(buf.data(), 1, buf.size(), f.get())) > 0) XXH3_64bits_update(s.get(), buf.data(), n);
  if (std::ferror(f.get())) return makeError(Code::kIoRead, "reading the file failed");
  return XXH3_64bits_digest(s.get());
}

}  // namespace vff::convert
