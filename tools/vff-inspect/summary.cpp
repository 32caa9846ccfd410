// summary.cpp - the report of vff-inspect as one JSON document (spec/inspect-schema.json).
#include <map>

#include "cli.h"
#include "inspect.h"
#include "vff/format.h"

namespace vff::inspect {

using nlohmann::json;

namespace {

const char* statusName(ChecksumStatus s) {
  switch (s) {
    case ChecksumStatus::kVerified:
      return "verified";
    case ChecksumStatus::kFailed:
      return "failed";
    case ChecksumStatus::kNotVerified:
      break;
  }
  return "not-verified";
}

const char* checksumAlgorithmName(ChecksumAlgorithm a) {
  return a == ChecksumAlgorithm::kXxh3_64 ? "xxh3-64" : "unknown";
}

// {"value": bits, "names": [...]}: known bits by name, unknown ones as "bit N".
json featureJson(uint64_t bits, bool incompat) {
  json names = json::array();
  for (int b = 0; b < 64; ++b) {
    const uint64_t bit = uint64_t{1} << b;
    if (!(bits & bit)) continue;
    if (incompat && bit == kFeatureZstd)
      names.push_back("zstd");
    else if (incompat && bit == kFeatureFilters)
      names.push_back("filters");
    else if (incompat && bit == kFeatureBc4)
      names.push_back("bc4");
    else
      names.push_back("bit " + std::to_string(b));
  }
  return {{"value", bits}, {"names", names}};
}

json sectionFlagNames(uint32_t flags) {
  json names = json::array();
  if (flags & kSectionRequired) names.push_back("required");
  if (flags & kSectionCopySafe) names.push_back("copy-safe");
  for (int b = 0; b < 32; ++b) {
    const uint32_t bit = uint32_t{1} << b;
    if ((flags & bit) && !(bit & kKnownSectionFlags)) names.push_back("bit " + std::to_string(b));
  }
  return names;
}

double mib(uint64_t bytes) {
  return static_cast<double>(bytes) / (1024.0 * 1024.0);
}

json planeJson(const File& file, Plane p) {
  const PlaneInfo& pi = file.plane(p);
  if (!pi.present) return nullptr;
  std::map<std::string, uint64_t> codecs, filters;
  uint32_t mapsPerBlock = pi.mapsPerBlock;
  for (const BlockInfo& b : pi.blocks) {
    ++codecs[codecName(b.codec)];
    ++filters[filterName(b.filter)];
  }
  json j;
  j["mapBytes"] = pi.mapBytes;
  j["rawBytes"] = pi.rawBytes;
  j["rawMiB"] = mib(pi.rawBytes);
  j["storedBytes"] = pi.storedBytes;
  j["storedMiB"] = mib(pi.storedBytes);
  j["compressionRatio"] = pi.storedBytes ? double(pi.rawBytes) / double(pi.storedBytes) : 0.0;
  j["blockCount"] = pi.blocks.size();
  j["mapsPerBlock"] = mapsPerBlock;
  j["lastBlockMaps"] = pi.blocks.empty() ? 0u : pi.blocks.back().mapCount;
  j["codecs"] = codecs;
  j["filters"] = filters;
  json blocks = json::array();
  for (const BlockInfo& b : pi.blocks)
    blocks.push_back({{"storedBytes", b.storedSize},
                      {"rawBytes", b.rawSize},
                      {"codec", codecName(b.codec)},
                      {"filter", filterName(b.filter)}});
  j["blocks"] = std::move(blocks);
  j["sliceBytes"] = file.sliceBytes(p);
  return j;
}

}  // namespace

ChecksumState checksumsVerifiedAtOpen(const File& file) {
  ChecksumState s;
  s.header = ChecksumStatus::kVerified;
  s.sections.assign(file.info().sections.size(), ChecksumStatus::kVerified);
  return s;
}

ChecksumState checksumsFromReport(const File& file, const Report& report) {
  ChecksumState s;
  s.header = report.has(Code::kHeaderChecksum) ? ChecksumStatus::kFailed : ChecksumStatus::kVerified;
  const auto& sections = file.info().sections;
  s.sections.assign(sections.size(), ChecksumStatus::kVerified);
  for (const Issue& issue : report.issues) {
    if (issue.code != Code::kSectionChecksum && issue.code != Code::kBlockChecksum) continue;
    for (size_t i = 0; i < sections.size(); ++i)
      if (sections[i].tag == issue.section) s.sections[i] = ChecksumStatus::kFailed;
  }
  return s;
}

json summarize(const File& file, const ChecksumState& checksums, const DistanceStats& stats, uint32_t histogramBins,
               const std::optional<PartialInfo>& partial) {
  const FileInfo& info = file.info();
  const FieldDesc& field = file.field();
  const LayoutDesc& layout = file.layout();
  json doc;

  doc["format"] = {
      {"version", std::to_string(info.versionMajor) + "." + std::to_string(info.versionMinor)},
      {"versionMajor", info.versionMajor},
      {"versionMinor", info.versionMinor},
      {"fileSize", info.fileSize},
      {"incompatFeatures", featureJson(info.incompatFeatures, true)},
      {"roCompatFeatures", featureJson(info.roCompatFeatures, false)},
      {"checksumAlgorithm", checksumAlgorithmName(info.checksumAlgorithm)},
      {"headerChecksum", cli::hex64(info.headerChecksum)},
      {"headerChecksumStatus", statusName(checksums.header)},
  };

  json sections = json::array();
  for (size_t i = 0; i < info.sections.size(); ++i) {
    const SectionInfo& s = info.sections[i];
    sections.push_back({
        {"tag", sectionTagName(s.tag)},
        {"known", s.known},
        {"flags", s.flags},
        {"flagNames", sectionFlagNames(s.flags)},
        {"offset", s.offset},
        {"storedSize", s.storedSize},
        {"rawSize", s.rawSize},
        {"codec", codecName(s.codec)},
        {"sectionVersion", s.sectionVersion},
        {"checksum", cli::hex64(s.checksum)},
        {"checksumStatus",
         statusName(i < checksums.sections.size() ? checksums.sections[i] : ChecksumStatus::kNotVerified)},
    });
  }
  doc["sections"] = sections;

  doc["field"] = {
      {"sphere",
       {{"center", {field.sphere.center[0], field.sphere.center[1], field.sphere.center[2]}},
        {"radius", field.sphere.radius}}},
      {"positionScheme", positionSchemeName(field.positionScheme)},
      {"positionParam", field.positionParam},
      {"mapCount", field.mapCount},
      {"directionScheme", directionSchemeName(field.directionScheme)},
      {"mapResolution", field.mapResolution},
      {"frame", frameConventionName(field.frame)},
      {"distanceEncoding", distanceEncodingName(field.distanceEncoding)},
      {"missCode", missCode(field.distanceEncoding)},
      {"normalEncoding", normalEncodingName(field.normalEncoding)},
  };

  doc["planes"] = {{"distance", planeJson(file, Plane::kDistance)}, {"normal", planeJson(file, Plane::kNormal)}};

  doc["layout"] = {
      {"target", layoutTargetName(layout.target)},
      {"tileSize", layout.tileSize},
      {"gutter", layout.gutter},
      {"tilesPerRow", layout.tilesPerRow},
      {"tilesPerColumn", layout.tilesPerColumn},
      {"tilesPerSlice", uint64_t{layout.tilesPerRow} * layout.tilesPerColumn},
      {"sliceWidth", layout.sliceWidth},
      {"sliceHeight", layout.sliceHeight},
      {"sliceCount", layout.sliceCount},
      {"maxTextureSize", layout.maxTextureSize},
      {"maxLayers", layout.maxLayers},
  };

  // A partial result (spec/partial.md): its range, whose maps alone the statistics count (the others
  // are fillers of misses, not the field's); null bounds when "vff.partial" gives no usable range.
  if (!partial) {
    doc["partial"] = nullptr;
  } else if (partial->known) {
    doc["partial"] = {{"mapBegin", partial->range.begin},
                      {"mapEnd", partial->range.end},
                      {"mapCount", field.mapCount},
                      {"maps", partial->range.end - partial->range.begin}};
  } else {
    doc["partial"] = {{"mapBegin", nullptr}, {"mapEnd", nullptr}, {"mapCount", field.mapCount}, {"maps", nullptr}};
  }

  doc["statistics"] = {
      {"texels", stats.texels},
      {"hits", stats.hits},
      {"misses", stats.misses},
      {"hitRatio", stats.texels ? double(stats.hits) / double(stats.texels) : 0.0},
      {"unreadableBlocks", stats.unreadableBlocks},
  };

  const double diameter = 2.0 * double(field.sphere.radius);
  const bool hitsOnly = field.distanceEncoding == DistanceEncoding::kBit1;
  json bins = json::array();
  if (!hitsOnly) {
    const uint32_t k = static_cast<uint32_t>(stats.bins.size());
    for (uint32_t i = 0; i < k; ++i) {
      const double lo = double(i) / k, hi = double(i + 1) / k;
      bins.push_back({
          {"lower", lo * diameter},
          {"upper", hi * diameter},
          {"lowerFraction", lo},
          {"upperFraction", hi},
          {"count", stats.bins[i]},
          {"share", stats.hits ? double(stats.bins[i]) / double(stats.hits) : 0.0},
      });
    }
  }
  doc["histogram"] = {
      {"hitsOnly", hitsOnly},     {"binCount", hitsOnly ? 0u : histogramBins},
      {"range", {0.0, diameter}}, {"hits", stats.hits},
      {"misses", stats.misses},   {"bins", bins},
  };

  // REFN (format 1.3, vff/refine.h): what the exact step holds.
  if (const RefinementView& r = file.refinement(); r.empty()) {
    doc["refinement"] = nullptr;
  } else {
    const double texels = double(field.mapCount) * field.mapResolution * field.mapResolution;
    doc["refinement"] = {{"margin", r.margin},
                         {"unsureTexels", r.unsureTexels},
                         {"unsureShare", texels > 0 ? double(r.unsureTexels) / texels : 0.0},
                         {"vertices", r.positions.size() / 3},
                         {"triangles", r.indices.size() / 3}};
  }

  const std::string_view meta = file.metadata();
  if (meta.empty()) {
    doc["metadata"] = nullptr;
  } else {
    json parsed = json::parse(meta.begin(), meta.end(), nullptr, /*allow_exceptions=*/false);
    doc["metadata"] = parsed.is_discarded() ? json(std::string(meta)) : parsed;
  }
  return doc;
}

json validationJson(const Report& report) {
  json issues = json::array();
  uint64_t errors = 0, warnings = 0;
  for (const Issue& i : report.issues) {
    (i.severity == Severity::kError ? errors : warnings) += 1;
    issues.push_back({
        {"severity", severityName(i.severity)},
        {"id", static_cast<uint32_t>(i.code)},
        {"name", codeName(i.code)},
        {"section", i.section ? json(sectionTagName(i.section)) : json(nullptr)},
        {"offset", i.offset != kNoOffset ? json(i.offset) : json(nullptr)},
        {"message", i.message},
    });
  }
  return {{"valid", report.valid()}, {"errors", errors}, {"warnings", warnings}, {"issues", issues}};
}

}  // namespace vff::inspect
