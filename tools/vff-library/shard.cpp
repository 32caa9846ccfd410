// shard.cpp - entries too large for one bake: ranges of at most shardMaps maps baked as partial
// results (vff-bake --map-range) by any worker or array task, each cached on its own, then merged
// (vff-bake --merge) into the bytes of the whole bake, which is cached under the entry's key as if
// one process had baked it.
#include <sys/stat.h>

#include <map>

#include "cli.h"
#include "library.h"

namespace vff::library {

namespace {

bool exists(const std::string& path) {
  struct stat st{};
  return ::stat(path.c_str(), &st) == 0 && S_ISREG(st.st_mode);
}

// Every range of the entry's field.
std::vector<Unit> allParts(const Entry& e, size_t index) {
  std::vector<Unit> parts;
  for (uint64_t b = 0; b < e.maps; b += e.shardMaps)
    parts.push_back({index, uint32_t(b), uint32_t(std::min<uint64_t>(e.maps, b + e.shardMaps))});
  return parts;
}

// A split entry is one vff-bake --split, which bakes no map ranges: never sharded.
bool sharded(const Entry& e) { return e.split.empty() && e.shardMaps > 0 && e.maps > e.shardMaps; }

}  // namespace

std::vector<Unit> planUnits(const std::vector<Entry>& entries, const std::vector<size_t>& todo,
                            const std::string& cacheDir) {
  std::vector<Unit> units;
  for (size_t i : todo) {
    const Entry& e = entries[i];
    if (!sharded(e)) {
      units.push_back({i, 0, 0});
      continue;
    }
    for (const Unit& u : allParts(e, i))
      if (!exists(partPath(cacheDir, e.key, u.begin, u.end))) units.push_back(u);  // finished parts stay
  }
  return units;
}

std::vector<EntryOutcome> finishEntries(const std::vector<Entry>& entries, const std::vector<size_t>& todo,
                                        const std::vector<EntryOutcome>& units, const WorkerOptions& wo) {
  std::map<size_t, std::vector<const EntryOutcome*>> byEntry;
  for (const EntryOutcome& u : units) byEntry[u.entry].push_back(&u);
  std::vector<EntryOutcome> out;
  for (size_t i : todo) {
    const Entry& e = entries[i];
    const auto& ran = byEntry[i];
    if (!sharded(e)) {
      if (!ran.empty()) out.push_back(*ran.front());
      continue;
    }
    EntryOutcome o;
    o.entry = i;
    o.where = ran.empty() ? "cache" : ran.front()->where;
    for (const EntryOutcome* u : ran) {
      o.result.seconds += u->result.seconds;
      o.result.rays += u->result.rays;
      if (!u->result.ok && o.result.error.empty()) {
        o.result.error = u->result.error;
        o.result.exitCode = u->result.exitCode;
      }
    }
    const std::vector<Unit> parts = allParts(e, i);
    size_t missing = 0;
    for (const Unit& u : parts) missing += !exists(partPath(wo.cacheDir, e.key, u.begin, u.end));
    if (missing) {
      if (o.result.error.empty()) {
        o.result.error = std::to_string(missing) + " of its " + counted(parts.size(), "map range", "map ranges") +
                         (missing == 1 ? " is" : " are") + " not baked; the next run bakes " + (missing == 1 ? "it" : "them");
        o.result.exitCode = cli::kExitRuntime;
      }
      out.push_back(o);
      continue;
    }
    const BakeResult merged = mergeParts(e, parts, wo);
    o.result.seconds += merged.seconds;
    o.result.ok = merged.ok;
    if (!merged.ok) {
      o.result.error = "merging its " + counted(parts.size(), "map range", "map ranges") + ": " + merged.error;
      o.result.exitCode = merged.exitCode;
    } else if (auto problem = installOutput(wo.cacheDir, e)) {
      o.result.ok = false;
      o.result.error = *problem;
      o.result.exitCode = cli::kExitIo;
    } else {
      o.result.error.clear();
      o.result.exitCode = 0;
    }
    out.push_back(o);
  }
  return out;
}

}  // namespace vff::library
