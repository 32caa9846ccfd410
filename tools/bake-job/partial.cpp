// partial.cpp - the partial result of a --map-range bake (spec/partial.md): a valid .vff file of the
// whole field whose maps outside the range hold misses, with the range and the whole bake's block
// options in META's "vff.partial".
#include <algorithm>
#include <cstdio>

#include "bake_job.h"
#include "cli.h"
#include "vff/bc4.h"
#include "vff/encoding.h"

namespace vff::bake_tool {

namespace {}  // namespace

std::vector<uint8_t> missMap(const FieldDesc& f) {
  const uint32_t m = f.mapResolution;
  std::vector<uint8_t> map(distanceMapBytes(f.distanceEncoding, m));
  if (f.distanceEncoding == DistanceEncoding::kBc4Diameter) {
    const std::vector<uint8_t> codes(size_t(m) * m, uint8_t(missCode(DistanceEncoding::kUnorm8Diameter)));
    encodeBc4Map(codes, m, map);
    return map;
  }
  for (uint32_t j = 0; j < m; ++j)
    for (uint32_t i = 0; i < m; ++i) storeCode(f.distanceEncoding, map, m, i, j, missCode(f.distanceEncoding));
  return map;
}

namespace {

// Writes `count` copies of `map` to plane `p`, a bounded run at a time.
Status writeCopies(Writer& w, Plane p, const std::vector<uint8_t>& map, uint64_t count) {
  if (count == 0) return {};
  const uint64_t perRun = std::clamp<uint64_t>((uint64_t{1} << 20) / map.size(), 1, count);
  std::vector<uint8_t> run;
  run.reserve(perRun * map.size());
  for (uint64_t i = 0; i < perRun; ++i) run.insert(run.end(), map.begin(), map.end());
  for (uint64_t done = 0; done < count;) {
    const uint64_t n = std::min(perRun, count - done);
    if (Status st = w.writeMaps(p, std::span<const uint8_t>(run.data(), n * map.size())); !st) return st;
    done += n;
  }
  return {};
}

}  // namespace

std::optional<MapRange> parseMapRange(const std::string& text) {
  const size_t colon = text.find(':');
  if (colon == std::string::npos || colon == 0 || colon + 1 == text.size()) return std::nullopt;
  auto number = [](const std::string& s, uint32_t* v) {
    if (s.empty() || s.size() > 10 || !std::all_of(s.begin(), s.end(), [](char c) { return c >= '0' && c <= '9'; }))
      return false;
    const uint64_t x = std::stoull(s);
    if (x > UINT32_MAX) return false;
    *v = uint32_t(x);
    return true;
  };
  MapRange r;
  if (!number(text.substr(0, colon), &r.begin) || !number(text.substr(colon + 1), &r.end) || r.begin >= r.end)
    return std::nullopt;
  return r;
}

std::optional<int> checkMapRange(const MapRange& r, uint32_t mapCount) {
  if (r.end <= mapCount) return std::nullopt;
  cli::usageError(kProg, "--map-range " + std::to_string(r.begin) + ":" + std::to_string(r.end) +
                             " is outside the field: it has " + std::to_string(mapCount) +
                             " maps (0:" + std::to_string(mapCount) + " is the whole field)");
  return cli::kExitUsage;
}

WriteOptions partialWriteOptions(const WriteOptions& whole) {
  WriteOptions wo;
  wo.codec = Codec::kZstd;  // the maps outside the range are all misses: they shrink to almost nothing
  wo.zstdLevel = 1;
  wo.layout = whole.layout;
  wo.metadataJson = whole.metadataJson;
  wo.threads = whole.threads;
  return wo;
}

std::string partialMetadata(const std::string& wholeMetadata, const WriteOptions& whole, const MapRange& r,
                            uint32_t mapCount) {
  nlohmann::json meta = nlohmann::json::parse(wholeMetadata);
  meta["vff.partial"] = {{"version", kPartialVersion},
                         {"mapBegin", r.begin},
                         {"mapEnd", r.end},
                         {"mapCount", mapCount},
                         {"codec", codecName(whole.codec)},
                         {"zstdLevel", whole.zstdLevel},
                         {"mapsPerBlock", whole.mapsPerBlock}};
  return meta.dump();
}

std::optional<int> writePartial(const Options& o, Writer& writer, const FieldDesc& field, const MapRange& r,
                                const bake::BakedField& baked, double* seconds, uint64_t* fileBytes) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::vector<uint8_t> miss = missMap(field);
  Status st = writeCopies(writer, Plane::kDistance, miss, r.begin);
  if (st) st = writer.writeMaps(Plane::kDistance, baked.distance);
  if (st) st = writeCopies(writer, Plane::kDistance, miss, field.mapCount - r.end);
  if (st && o.normals) {
    const std::vector<uint8_t> none(normalMapBytes(field.normalEncoding, field.mapResolution), 0);
    st = writeCopies(writer, Plane::kNormal, none, r.begin);
    if (st) st = writer.writeMaps(Plane::kNormal, baked.normals);
    if (st) st = writeCopies(writer, Plane::kNormal, none, field.mapCount - r.end);
  }
  if (st) st = writer.finish();
  if (!st) return cli::reportError(kProg, o.output, st.error());
  *seconds = secondsSince(t0);
  if (auto f = File::open(o.output, {.checksums = ChecksumPolicy::kNone})) *fileBytes = f->info().fileSize;
  return std::nullopt;
}

}  // namespace vff::bake_tool
