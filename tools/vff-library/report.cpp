// report.cpp - the report at the end of a library bake: entries baked, up to date and failed (with
// their errors), rays per second over the whole run, and the time of each bake.
#include <cinttypes>
#include <cstdio>

#include "library.h"

namespace vff::library {

namespace {

uint64_t bakedRays(const std::vector<Entry>& entries, const Report& r) {
  uint64_t rays = 0;
  for (size_t i : r.baked) rays += entries[i].rays;
  return rays;
}

}  // namespace

nlohmann::json reportJson(const std::vector<Entry>& entries, const Report& r) {
  const uint64_t rays = bakedRays(entries, r);
  nlohmann::json j = {{"mode", r.mode},
                      {"entries", entries.size()},
                      {"baked", nlohmann::json::array()},
                      {"upToDate", nlohmann::json::array()},
                      {"failed", nlohmann::json::array()},
                      {"rays", rays},
                      {"seconds", r.seconds},
                      {"raysPerSecond", r.seconds > 0 ? double(rays) / r.seconds : 0.0},
                      {"tasks", nlohmann::json::array()}};
  if (r.mode == "local") j["workers"] = {{"processes", r.workers}, {"threadsEach", r.threadsPerWorker}};
  if (!r.slurmJobs.empty()) j["slurmJobs"] = r.slurmJobs;
  for (size_t i : r.baked) j["baked"].push_back({{"mesh", entries[i].name}, {"output", entries[i].output}, {"key", entries[i].key}});
  for (size_t i : r.upToDate)
    j["upToDate"].push_back({{"mesh", entries[i].name}, {"output", entries[i].output}, {"key", entries[i].key}});
  for (const EntryOutcome& o : r.outcomes)
    j["tasks"].push_back({{"mesh", entries[o.entry].name}, {"maps", o.unit.part() ? nlohmann::json::array({o.unit.begin, o.unit.end}) : nlohmann::json("all")},
                          {"where", o.where}, {"ok", o.result.ok},
                          {"seconds", o.result.seconds}, {"rays", o.result.rays}});
  for (size_t i : r.failed) {
    std::string error = entries[i].error;
    int code = entries[i].exitCode;
    for (const EntryOutcome& o : r.entryOutcomes)
      if (o.entry == i) error = o.result.error, code = o.result.exitCode;
    j["failed"].push_back({{"mesh", entries[i].name}, {"output", entries[i].output}, {"error", error}, {"exitCode", code}});
  }
  return j;
}

void printReport(const std::vector<Entry>& entries, const Report& r, std::FILE* to) {
  const nlohmann::json j = reportJson(entries, r);
  for (const auto& t : j["tasks"])
    std::fprintf(to, "  %-40s %-14s %8.2f s  %s%s\n", t["mesh"].get<std::string>().c_str(),
                 t["maps"].is_array() ? ("maps " + std::to_string(t["maps"][0].get<unsigned>()) + "-" +
                                         std::to_string(t["maps"][1].get<unsigned>())).c_str() : "",
                 t["seconds"].get<double>(), t["where"].get<std::string>().c_str(), t["ok"].get<bool>() ? "" : "  (failed)");
  for (const auto& f : j["failed"])
    std::fprintf(to, "%s: error: %s: %s (exit %d)\n", kProg, f["mesh"].get<std::string>().c_str(),
                 f["error"].get<std::string>().c_str(), f["exitCode"].get<int>());
  std::fprintf(to, "%s: %s: %zu baked, %zu up to date, %zu failed; %.3g Mrays in %.2f s (%.1f Mrays/s, %s",
               kProg, counted(entries.size(), "entry", "entries").c_str(), r.baked.size(), r.upToDate.size(), r.failed.size(),
               double(j["rays"].get<uint64_t>()) / 1e6, r.seconds, j["raysPerSecond"].get<double>() / 1e6,
               r.mode.c_str());
  if (r.mode == "local") std::fprintf(to, ", %u x %s", r.workers, counted(r.threadsPerWorker, "thread", "threads").c_str());
  for (const auto& id : r.slurmJobs) std::fprintf(to, ", job %s", id.c_str());
  std::fprintf(to, ")\n");
}

}  // namespace vff::library
