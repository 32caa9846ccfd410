// gen_partial.cpp - vff-partial-gen OUTDIR: the partial-result conformance vectors (README.md,
// spec/partial.md section 4). The parts are written by vff-bake's own partial writer (vff_bake_job:
// partialWriteOptions, partialMetadata, writePartial) from maps made here, so no ray tracer takes
// part and the bytes depend only on libvff, this file and, for zstd blocks, libzstd. Every valid
// set's expected.vff is the whole field as a whole bake writes it; every invalid set breaks one rule.
#include <xxhash.h>
#include <zstd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include "bake_job.h"
#include "partial_rules.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace vff::bake_tool {
namespace {

// A whole bake: its field, its writer options (codec, G, META) and whether it has normals.
struct Bake {
  FieldDesc field;
  WriteOptions whole;
  bool normals = false;
};

Bake baseBake() {
  Bake b;
  b.field.sphere = Sphere{{0.25f, -0.5f, 1.0f}, 1.5f};
  b.field.positionScheme = PositionScheme::kSphericalFibonacci;
  b.field.positionParam = 6;
  b.field.mapCount = 6;
  b.field.directionScheme = DirectionScheme::kConcentricEqualArea;
  b.field.mapResolution = 4;
  b.field.distanceEncoding = DistanceEncoding::kUnorm8Diameter;
  b.whole.codec = Codec::kStored;
  b.whole.sync = false;
  b.whole.threads = 1;
  b.whole.metadataJson = json{{"vff.generator", "vff-partial-gen"},
                              {"vff.generatorVersion", "1"},
                              {"vff.source", {{"geometryHash", "0123456789abcdef"}, {"name", "generated"}}}}
                             .dump();
  return b;
}

Bake withNormals(Bake b) {
  b.field.normalEncoding = NormalEncoding::kOctSnorm16;
  b.normals = true;
  b.whole.codec = Codec::kZstd;
  b.whole.zstdLevel = 3;
  b.whole.mapsPerBlock = 4;
  return b;
}

// The maps of the whole field: a pattern of hits with some misses (unorm8: 255), and normals.
bake::BakedField maps(const Bake& b, MapRange r) {
  bake::BakedField f;
  f.field = b.field;
  const uint32_t texels = b.field.mapResolution * b.field.mapResolution;
  for (uint32_t k = r.begin; k < r.end; ++k)
    for (uint32_t t = 0; t < texels; ++t) {
      f.distance.push_back(uint8_t((k * 37 + t * 11) % 9 == 0 ? 255 : (k * 53 + t * 7) % 250));
      if (!b.normals) continue;
      for (int c = 0; c < 4; ++c) f.normals.push_back(uint8_t((k * 29 + t * 13 + uint32_t(c) * 71) % 256));
    }
  return f;
}

[[noreturn]] void die(const std::string& what) {
  std::fprintf(stderr, "vff-partial-gen: %s\n", what.c_str());
  std::exit(1);
}

std::string hex64(uint64_t v) {
  char s[17];
  std::snprintf(s, sizeof s, "%016llx", static_cast<unsigned long long>(v));
  return s;
}

std::vector<char> readBytes(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

json fileEntry(const fs::path& p, bool zstd) {
  const std::vector<char> b = readBytes(p);
  return {{"bytes", b.size()}, {"xxh3", hex64(XXH3_64bits(b.data(), b.size()))}, {"zstd", zstd}};
}

// Writes the part of `b` of maps `r` to `path`, its META "vff.partial" then changed by `edit`.
void writePart(const fs::path& path, const Bake& b, MapRange r, const std::function<void(json&)>& edit = {}) {
  json meta = json::parse(partialMetadata(b.whole.metadataJson, b.whole, r, b.field.mapCount));
  if (edit) edit(meta);
  WriteOptions wo = partialWriteOptions(b.whole);
  wo.sync = false;
  wo.metadataJson = meta.dump();
  auto w = Writer::create(path.string(), b.field, wo);
  if (!w) die(path.string() + ": " + w.error().toString());
  Options o;
  o.output = path.string();
  o.normals = b.normals;
  double seconds = 0;
  uint64_t bytes = 0;
  if (writePartial(o, *w, b.field, r, maps(b, r), &seconds, &bytes)) die(path.string() + ": writePartial failed");
}

// The whole bake's file, as vff-bake writes it without --map-range.
void writeWhole(const fs::path& path, const Bake& b) {
  auto w = Writer::create(path.string(), b.field, b.whole);
  if (!w) die(path.string() + ": " + w.error().toString());
  const bake::BakedField f = maps(b, {0, b.field.mapCount});
  Status st = w->writeMaps(Plane::kDistance, f.distance);
  if (st && b.normals) st = w->writeMaps(Plane::kNormal, f.normals);
  if (st) st = w->finish();
  if (!st) die(path.string() + ": " + st.error().toString());
}

// One part of a set: its ranges' bake and the edit of its META.
struct PartSpec {
  MapRange range;
  Bake bake = baseBake();
  std::function<void(json&)> edit = {};
};

// A merge set: its parts in argument order (p1.vff, p2.vff, ...), and the rule it breaks (0: none).
struct SetSpec {
  std::string name;
  std::vector<PartSpec> parts;
  PartialRule rule = PartialRule(0);
  int failingPart = 0;  // 1-based: the part the refusal names
};

void setPartial(json& m, const char* key, json v) {
  m["vff.partial"][key] = std::move(v);
}

std::vector<SetSpec> sets() {
  const Bake zn = withNormals(baseBake());
  Bake level0 = baseBake();
  level0.whole.codec = Codec::kZstd;
  level0.whole.zstdLevel = 0;
  Bake wider = baseBake();
  wider.field.sphere.radius = 2.0f;
  Bake blocks = baseBake();
  blocks.whole.mapsPerBlock = 2;
  using R = PartialRule;
  auto ed = [](const char* key, json v) { return [key, v](json& m) { setPartial(m, key, v); }; };
  return {
      {"stored-one-part", {{{0, 6}}}},
      {"stored-two-parts", {{{0, 3}}, {{3, 6}}}},
      {"stored-three-shuffled", {{{4, 6}}, {{0, 1}}, {{1, 4}}}},
      {"zstd-normals-blocks", {{{5, 6}, zn}, {{0, 5}, zn}}},
      {"12002-partial-missing",
       {{{0, 3}}, {{3, 6}, baseBake(), [](json& m) { m.erase("vff.partial"); }}},
       R::kNotPartial,
       2},
      {"12003-partial-object",
       {{{0, 3}}, {{3, 6}, baseBake(), [](json& m) { m["vff.partial"] = "3:6"; }}},
       R::kNotObject,
       2},
      {"12004-partial-version", {{{0, 3}}, {{3, 6}, baseBake(), ed("version", 2)}}, R::kVersion, 2},
      {"12005-partial-key-missing",
       {{{0, 3}}, {{3, 6}, baseBake(), [](json& m) { m["vff.partial"].erase("mapsPerBlock"); }}},
       R::kKeyMissing,
       2},
      {"12006-partial-key-type", {{{0, 3}}, {{3, 6}, baseBake(), ed("codec", 7)}}, R::kKeyType, 2},
      {"12006-partial-key-type-first-part",
       {{{0, 3}, baseBake(), ed("mapEnd", "3")}, {{3, 6}, baseBake(), ed("mapCount", 7)}},
       R::kKeyType,
       1},
      {"12007-partial-key-unknown", {{{0, 3}}, {{3, 6}, baseBake(), ed("filter", "none")}}, R::kKeyUnknown, 2},
      {"12008-partial-map-count", {{{0, 3}}, {{3, 6}, baseBake(), ed("mapCount", 7)}}, R::kMapCount, 2},
      {"12009-partial-range", {{{0, 3}}, {{3, 6}, baseBake(), ed("mapEnd", 7)}}, R::kRange, 2},
      {"12010-partial-codec", {{{0, 3}}, {{3, 6}, baseBake(), ed("codec", "lz4")}}, R::kCodec, 2},
      {"12011-partial-zstd-level", {{{0, 3}, level0}, {{3, 6}, level0}}, R::kZstdLevel, 1},
      // maps 2:6 written, "vff.partial" saying 3:6: map 2 is a field's map where a filler must be
      {"12012-partial-filler", {{{0, 3}}, {{2, 6}, baseBake(), ed("mapBegin", 3)}}, R::kFiller, 2},
      {"12013-merge-geometry",
       {{{0, 3}}, {{3, 6}, baseBake(), [](json& m) { m["vff.source"]["geometryHash"] = "fedcba9876543210"; }}},
       R::kGeometry,
       2},
      {"12013-merge-geometry-before-gap",
       {{{0, 2}}, {{3, 6}, baseBake(), [](json& m) { m["vff.source"]["geometryHash"] = "fedcba9876543210"; }}},
       R::kGeometry,
       2},
      {"12014-merge-version",
       {{{0, 3}}, {{3, 6}, baseBake(), [](json& m) { m["vff.generatorVersion"] = "2"; }}},
       R::kVersionOfBake,
       2},
      {"12015-merge-options", {{{0, 3}}, {{3, 6}, wider}}, R::kFieldOptions, 2},
      {"12016-merge-block-options", {{{0, 3}}, {{3, 6}, blocks}}, R::kBlockOptions, 2},
      {"12017-merge-meta",
       {{{0, 3}}, {{3, 6}, baseBake(), [](json& m) { m["vff.source"]["name"] = "other"; }}},
       R::kMeta,
       2},
      {"12018-merge-gap", {{{4, 6}}, {{0, 3}}}, R::kGap, 1},
      {"12019-merge-overlap", {{{3, 6}}, {{0, 4}}}, R::kOverlap, 1},
  };
}

}  // namespace
}  // namespace vff::bake_tool

int main(int argc, char** argv) {
  using namespace vff::bake_tool;
  if (argc != 2) die("usage: vff-partial-gen OUTDIR");
  const fs::path out = argv[1];
  std::error_code ec;
  fs::remove_all(out / "merge", ec);
  json files = json::object(), manifestSets = json::object(), partials = json::object();
  for (const SetSpec& s : sets()) {
    const fs::path dir = out / "merge" / s.name;
    fs::create_directories(dir);
    json set = {{"parts", json::array()}};
    for (size_t i = 0; i < s.parts.size(); ++i) {
      const PartSpec& p = s.parts[i];
      const std::string name = "p" + std::to_string(i + 1) + ".vff";
      writePart(dir / name, p.bake, p.range, p.edit);
      const std::string rel = "merge/" + s.name + "/" + name;
      files[rel] = fileEntry(dir / name, true);  // a partial result's blocks are zstd
      set["parts"].push_back(name);
      if (s.rule == PartialRule(0))
        partials[rel] = {{"mapBegin", p.range.begin}, {"mapEnd", p.range.end}, {"mapCount", p.bake.field.mapCount}};
    }
    if (s.rule == PartialRule(0)) {
      const Bake& b = s.parts.front().bake;
      writeWhole(dir / "expected.vff", b);
      const std::string rel = "merge/" + s.name + "/expected.vff";
      files[rel] = fileEntry(dir / "expected.vff", b.whole.codec == vff::Codec::kZstd);
      set["exit"] = 0;
      set["expected"] = "expected.vff";
    } else {
      const PartialRuleInfo& r = partialRuleInfo(s.rule);
      set["exit"] = r.exitCode;
      set["id"] = int(s.rule);
      set["name"] = r.name;
      set["refused"] = set["parts"][size_t(s.failingPart - 1)];
    }
    manifestSets[s.name] = set;
  }
  const json manifest = {{"generator", "vff-partial-gen"},
                         {"zstdVersion", ZSTD_versionString()},
                         {"files", files},
                         {"sets", manifestSets},
                         {"partials", partials}};
  std::ofstream(out / "manifest.json") << manifest.dump(1) << "\n";
  return 0;
}
