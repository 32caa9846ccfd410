// merge.cpp - vff-bake --merge: partial results (spec/partial.md) checked against each other and
// assembled into the whole field. The maps go through the same Writer with the same field, options
// and META as the whole bake, so the bytes are the whole bake's by construction. In the library, not
// the tool, so that a fuzz target runs the very checks vff-bake runs.
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <string_view>

#include "bake_job.h"
#include "cli.h"
#include "partial_rules.h"

namespace vff::bake_tool {

namespace {

struct Part {
  std::string path;
  File file;
  nlohmann::json meta;  // META without "vff.partial": the whole bake's
  nlohmann::json partial;
  MapRange range;
};

// A refusal of rule `r` naming the part: "vff-bake: error: PATH: NAME (ID): MESSAGE"; returns the
// rule's exit code.
int refuse(const std::string& path, PartialRule r, const std::string& message) {
  cli::printError(kProg, path + ": " + partialRuleTag(r) + ": " + message);
  return partialRuleInfo(r).exitCode;
}

std::string rangeText(const MapRange& r) {
  return std::to_string(r.begin) + ":" + std::to_string(r.end);
}

// The keys of "vff.partial" version 1 after "version" (spec/partial.md section 2), in the order they
// are checked, with the largest value each may take.
constexpr std::pair<const char*, uint64_t> kPartialKeys[] = {{"mapBegin", UINT32_MAX}, {"mapEnd", UINT32_MAX},
                                                             {"mapCount", UINT32_MAX}, {"codec", 0},
                                                             {"zstdLevel", 22},        {"mapsPerBlock", UINT32_MAX}};

// The keys of `p` ("vff.partial" with an integer version 1): rules 12005, 12006, 12007 in order.
std::optional<int> checkPartialKeys(const std::string& path, const nlohmann::json& p) {
  for (const auto& [key, max] : kPartialKeys)
    if (!p.contains(key))
      return refuse(path, PartialRule::kKeyMissing, std::string("\"vff.partial\" lacks \"") + key + "\"");
  for (const auto& [key, max] : kPartialKeys) {
    const nlohmann::json& v = p[key];
    const bool codec = std::string_view(key) == "codec";
    // A negative or fractional number, a string of digits: the writer makes none of these.
    const bool ok = codec ? v.is_string() : v.is_number_unsigned() && v.get<uint64_t>() <= max;
    if (!ok)
      return refuse(path, PartialRule::kKeyType,
                    std::string("\"vff.partial\" ") + key + " is " + v.dump() + ", not " +
                        (codec ? std::string("a string") : "an integer 0.." + std::to_string(max)));
  }
  for (auto it = p.begin(); it != p.end(); ++it)
    if (it.key() != "version" && std::none_of(std::begin(kPartialKeys), std::end(kPartialKeys),
                                              [&](const auto& k) { return it.key() == k.first; }))
      return refuse(path, PartialRule::kKeyUnknown,
                    "\"vff.partial\" has the key \"" + it.key() + "\", which version " +
                        std::to_string(kPartialVersion) + " does not define (merge with the vff-bake that baked it)");
  return std::nullopt;
}

// Rule 12012: every map of `f` outside `r` is a filler, in both planes. Reads every block once; the
// first map that is not names the rule (a corrupt block is the reader's error).
std::optional<int> checkFillers(const std::string& path, const File& f, const MapRange& r) {
  const std::vector<uint8_t> miss = missMap(f.field());
  std::vector<uint8_t> block;
  for (Plane plane : {Plane::kDistance, Plane::kNormal}) {
    const PlaneInfo& info = f.plane(plane);
    if (!info.present) continue;
    for (uint32_t b = 0; b < info.blocks.size(); ++b) {
      const BlockInfo& bi = info.blocks[b];
      if (bi.firstMap >= r.begin && bi.firstMap + bi.mapCount <= r.end) continue;  // the range's maps only
      block.resize(bi.rawSize);
      if (Status st = f.decodeBlock(plane, b, block); !st) return cli::reportError(kProg, path, st.error());
      for (uint32_t k = 0; k < bi.mapCount; ++k) {
        const uint32_t map = bi.firstMap + k;
        if (map >= r.begin && map < r.end) continue;
        const auto bytes = std::span<const uint8_t>(block).subspan(size_t(k) * info.mapBytes, info.mapBytes);
        const bool filler = plane == Plane::kDistance
                                ? std::equal(bytes.begin(), bytes.end(), miss.begin(), miss.end())
                                : std::all_of(bytes.begin(), bytes.end(), [](uint8_t x) { return x == 0; });
        if (!filler)
          return refuse(path, PartialRule::kFiller,
                        std::string(plane == Plane::kDistance ? "distance" : "normal") + " map " + std::to_string(map) +
                            " lies outside the map range " + rangeText(r) + " but is not a filler (" +
                            (plane == Plane::kDistance ? "every texel a miss" : "every byte zero") + ")");
      }
    }
  }
  return std::nullopt;
}

// Reads `path` as a partial result (rules 12002 to 12012, after the reader's own); returns the exit
// code of a refusal.
std::optional<int> openPart(const std::string& path, std::vector<Part>* parts) {
  auto f = File::open(path);
  if (!f) return cli::reportError(kProg, path, f.error());
  nlohmann::json meta = nlohmann::json::parse(f->metadata(), nullptr, false);
  if (meta.is_discarded() || !meta.is_object() || !meta.contains("vff.partial"))
    return refuse(path, PartialRule::kNotPartial,
                  "not a partial result (its META has no \"vff.partial\"): bake parts with --map-range");
  nlohmann::json p = meta["vff.partial"];
  meta.erase("vff.partial");
  if (!p.is_object() || !p.contains("version") || !p["version"].is_number_integer())
    return refuse(path, PartialRule::kNotObject, "\"vff.partial\" is not an object with an integer \"version\"");
  if (p["version"] != kPartialVersion)
    return refuse(path, PartialRule::kVersion,
                  "partial result version " + p["version"].dump() + "; this vff-bake reads version " +
                      std::to_string(kPartialVersion) + " (merge with the vff-bake that baked it)");
  if (auto rc = checkPartialKeys(path, p)) return rc;
  const uint32_t count = f->field().mapCount;
  const MapRange r{p["mapBegin"].get<uint32_t>(), p["mapEnd"].get<uint32_t>()};
  if (p["mapCount"].get<uint32_t>() != count)
    return refuse(path, PartialRule::kMapCount,
                  "\"vff.partial\" says " + p["mapCount"].dump() + " maps, the field has " + std::to_string(count));
  if (r.begin >= r.end || r.end > count)
    return refuse(path, PartialRule::kRange,
                  "map range " + rangeText(r) + " is empty or outside the field's " + std::to_string(count) + " maps");
  const std::string codec = p["codec"];
  if (codec != codecName(Codec::kStored) && codec != codecName(Codec::kZstd))
    return refuse(path, PartialRule::kCodec, "\"vff.partial\" names an unknown codec '" + codec + "'");
  if (codec == codecName(Codec::kZstd) && p["zstdLevel"].get<int>() < 1)
    return refuse(path, PartialRule::kZstdLevel, "\"vff.partial\" has zstdLevel 0; zstd levels are 1 to 22");
  if (auto rc = checkFillers(path, *f, r)) return rc;
  parts->push_back(Part{path, std::move(*f), std::move(meta), std::move(p), r});
  return std::nullopt;
}

// The field description and layout, item by item, for comparing parts and saying how they differ.
std::vector<std::pair<std::string, std::string>> describe(const FieldDesc& f, const LayoutDesc& l) {
  // %.9g reads well and tells floats apart, but not -0 from +0; %a tells every bit apart.
  char sphere[128], exact[128];
  std::snprintf(sphere, sizeof sphere, "centre %.9g %.9g %.9g radius %.9g", double(f.sphere.center[0]),
                double(f.sphere.center[1]), double(f.sphere.center[2]), double(f.sphere.radius));
  std::snprintf(exact, sizeof exact, "centre %a %a %a radius %a", double(f.sphere.center[0]),
                double(f.sphere.center[1]), double(f.sphere.center[2]), double(f.sphere.radius));
  return {{"sphere", sphere},
          {"sphere", exact},
          {"positions", std::string(positionSchemeName(f.positionScheme)) + " " + std::to_string(f.positionParam)},
          {"directions", directionSchemeName(f.directionScheme)},
          {"map size", std::to_string(f.mapResolution)},
          {"encoding", distanceEncodingName(f.distanceEncoding)},
          {"normals", normalEncodingName(f.normalEncoding)},
          {"layout target", layoutTargetName(l.target)},
          {"gutter", std::to_string(l.gutter)},
          {"max texture size", std::to_string(l.maxTextureSize)},
          {"max layers", std::to_string(l.maxLayers)}};
}

// The first key (one level into objects) where two META objects differ, or "".
std::string firstDifference(const nlohmann::json& a, const nlohmann::json& b) {
  nlohmann::json keys = nlohmann::json::object();
  for (const auto* j : {&a, &b})
    for (auto it = j->begin(); it != j->end(); ++it) keys[it.key()] = true;
  for (auto it = keys.begin(); it != keys.end(); ++it) {
    const std::string& k = it.key();
    const nlohmann::json x = a.value(k, nlohmann::json()), y = b.value(k, nlohmann::json());
    if (x == y) continue;
    if (x.is_object() && y.is_object()) return k + "." + firstDifference(x, y);
    return k;
  }
  return "";
}

std::string metaValue(const nlohmann::json& meta, const std::string& key) {
  const size_t dot = key.find('.', 4);  // past "vff."
  const nlohmann::json::json_pointer ptr(
      "/" + (dot == std::string::npos ? key : key.substr(0, dot) + "/" + key.substr(dot + 1)));
  return meta.contains(ptr) ? meta[ptr].dump() : "(absent)";
}

// Part `p` against the first part `q`: the same bake (geometry, version, field, options)?
std::optional<int> checkSameBake(const Part& p, const Part& q) {
  const nlohmann::json::json_pointer geometry("/vff.source/geometryHash"), version("/vff.generatorVersion");
  auto at = [](const nlohmann::json& j, const nlohmann::json::json_pointer& ptr) {
    return j.contains(ptr) ? j[ptr].dump() : std::string("(absent)");
  };
  if (at(p.meta, geometry) != at(q.meta, geometry))
    return refuse(p.path, PartialRule::kGeometry,
                  "different geometry: vff.source.geometryHash " + at(p.meta, geometry) + ", but " + q.path + " has " +
                      at(q.meta, geometry));
  if (at(p.meta, version) != at(q.meta, version))
    return refuse(p.path, PartialRule::kVersionOfBake,
                  "different versions: baked by vff-bake " + at(p.meta, version) + ", but " + q.path + " by " +
                      at(q.meta, version));
  const auto a = describe(p.file.field(), p.file.layout()), b = describe(q.file.field(), q.file.layout());
  for (size_t i = 0; i < a.size(); ++i)
    if (a[i].second != b[i].second)
      return refuse(p.path, PartialRule::kFieldOptions,
                    "different options: " + a[i].first + " " + a[i].second + ", but " + q.path + " has " + b[i].second);
  for (const char* k : {"codec", "zstdLevel", "mapsPerBlock"})
    if (p.partial[k] != q.partial[k])
      return refuse(p.path, PartialRule::kBlockOptions,
                    std::string("different options: ") + k + " " + p.partial[k].dump() + ", but " + q.path + " has " +
                        q.partial[k].dump());
  if (const std::string k = firstDifference(p.meta, q.meta); !k.empty())
    return refuse(p.path, PartialRule::kMeta,
                  "different bake: META " + k + " is " + metaValue(p.meta, k) + ", but " + q.path + " has " +
                      metaValue(q.meta, k));
  return std::nullopt;
}

// The parts, sorted by range, cover [0, mapCount) exactly once?
std::optional<int> checkCoverage(const std::vector<Part>& parts) {
  const uint32_t count = parts.front().file.field().mapCount;
  uint32_t next = 0;
  const Part* previous = nullptr;
  for (const Part& p : parts) {
    if (p.range.begin > next)
      return refuse(p.path, PartialRule::kGap,
                    "gap: maps " + std::to_string(next) + ":" + std::to_string(p.range.begin) +
                        " are in no part (this part holds " + rangeText(p.range) + ")");
    if (p.range.begin < next)
      return refuse(p.path, PartialRule::kOverlap,
                    "overlap: its maps " + rangeText(p.range) + " overlap " + previous->path + "'s " +
                        rangeText(previous->range));
    next = p.range.end;
    previous = &p;
  }
  if (next != count)
    return refuse(parts.back().path, PartialRule::kGap,
                  "gap: maps " + std::to_string(next) + ":" + std::to_string(count) + " of the field's " +
                      std::to_string(count) + " are in no part");
  return std::nullopt;
}

// Appends maps [r.begin, r.end) of `p`'s plane to the writer, a block at a time.
Status copyMaps(const Part& p, Plane plane, Writer& w) {
  const PlaneInfo& info = p.file.plane(plane);
  std::vector<uint8_t> block;
  for (uint32_t b = p.range.begin / info.mapsPerBlock; b < info.blocks.size(); ++b) {
    const BlockInfo& bi = info.blocks[b];
    if (bi.firstMap >= p.range.end) break;
    block.resize(bi.rawSize);
    if (Status st = p.file.decodeBlock(plane, b, block); !st) return st;
    const uint32_t from = std::max(bi.firstMap, p.range.begin), to = std::min(bi.firstMap + bi.mapCount, p.range.end);
    const auto bytes = std::span<const uint8_t>(block).subspan(size_t(from - bi.firstMap) * info.mapBytes,
                                                               size_t(to - from) * info.mapBytes);
    if (Status st = w.writeMaps(plane, bytes); !st) return st;
  }
  return {};
}

}  // namespace

int mergeParts(const Options& o, const MergeHooks& hooks) {
  std::error_code ec;
  for (const std::string& path : o.merge)
    if (path == o.output || std::filesystem::equivalent(path, o.output, ec)) {
      cli::usageError(kProg, partialRuleTag(PartialRule::kOutputIsPart) + ": -o " + o.output +
                                 " is also a part to merge: write the whole field elsewhere");
      return partialRuleInfo(PartialRule::kOutputIsPart).exitCode;
    }
  std::vector<Part> parts;
  for (const std::string& path : o.merge)
    if (auto rc = openPart(path, &parts)) return *rc;
  for (size_t i = 1; i < parts.size(); ++i)
    if (auto rc = checkSameBake(parts[i], parts[0])) return *rc;
  std::stable_sort(parts.begin(), parts.end(),
                   [](const Part& a, const Part& b) { return a.range.begin < b.range.begin; });
  if (auto rc = checkCoverage(parts)) return *rc;

  // The whole bake's options: its block codec from "vff.partial", its layout limits from LAYT (the
  // writer records the limits it packed for), its META without "vff.partial".
  const Part& first = parts.front();
  const LayoutDesc& l = first.file.layout();
  WriteOptions wo;
  wo.codec = first.partial["codec"] == codecName(Codec::kZstd) ? Codec::kZstd : Codec::kStored;
  wo.zstdLevel = first.partial["zstdLevel"].get<int>();
  wo.mapsPerBlock = first.partial["mapsPerBlock"].get<uint32_t>();
  wo.layout = LayoutLimits{l.target, l.maxTextureSize, l.maxLayers, l.gutter};
  wo.metadataJson = first.meta.dump();
  wo.threads = o.threads;

  const auto t0 = std::chrono::steady_clock::now();
  if (hooks.beforeWrite) hooks.beforeWrite(o.output);
  auto w = Writer::create(o.output, first.file.field(), wo);
  if (!w) return cli::reportError(kProg, o.output, w.error());
  if (hooks.writerCreated) hooks.writerCreated(o.output);
  for (Plane plane : {Plane::kDistance, Plane::kNormal}) {
    if (!first.file.plane(plane).present) continue;
    for (const Part& p : parts)
      if (Status st = copyMaps(p, plane, *w); !st) return cli::reportError(kProg, p.path, st.error());
  }
  if (Status st = w->finish(); !st) return cli::reportError(kProg, o.output, st.error());
  if (o.json) {
    nlohmann::json summary = {{"output", o.output},
                              {"maps", first.file.field().mapCount},
                              {"parts", parts.size()},
                              {"seconds", secondsSince(t0)}};
    std::printf("%s\n", summary.dump(2).c_str());
  } else if (!o.quiet) {
    std::fprintf(stderr, "%s: merged %s, %s -> %s\n", kProg, cli::count(parts.size(), "part").c_str(),
                 cli::count(first.file.field().mapCount, "map").c_str(),
                 o.output.c_str());
  }
  return cli::kExitSuccess;
}

}  // namespace vff::bake_tool
