// slurm.cpp - a library bake as Slurm job arrays: a plan and a batch script in a state folder, one
// `sbatch --array` whose task K bakes its share of the plan (`vff-library run-shard PLAN K`) into
// the shared cache, polling squeue until the array is gone, collecting the tasks' reports, and
// resubmitting only the entries still missing from the cache.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <map>
#include <thread>

#include "cli.h"
#include "library.h"
#include "progress.h"

namespace fs = std::filesystem;

namespace vff::library {

namespace {

std::string shellQuote(const std::string& s) {
  std::string q = "'";
  for (char c : s) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Writes `text` to `path` through a temporary and a rename.
std::optional<std::string> writeText(const std::string& path, const std::string& text) {
  const std::string bytes = text;
  if (auto st = cli::writeFileAtomic(path, {reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size()}); !st)
    return st.error().message;
  return std::nullopt;
}

std::string trim(std::string s) {
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r' || s.back() == ' ')) s.pop_back();
  return s;
}

// The plan of one submission: which entries each array task bakes.
nlohmann::json makePlan(const std::vector<Entry>& entries, const std::vector<Unit>& todo, const WorkerOptions& wo,
                        unsigned tasks) {
  std::vector<Unit> order(todo);
  std::stable_sort(order.begin(), order.end(),
                   [&](const Unit& a, const Unit& b) { return unitRays(entries, a) > unitRays(entries, b); });
  nlohmann::json plan = {{"vffLibraryPlan", 1}, {"vffBake", wo.vffBake}, {"cache", wo.cacheDir},
                         {"tasks", tasks}, {"entries", nlohmann::json::array()}};
  // Largest first, each to the task with the least work so far (the lowest such task on a tie).
  std::vector<uint64_t> load(tasks, 0);
  for (size_t i = 0; i < order.size(); ++i) {
    const Entry& e = entries[order[i].entry];
    const unsigned task = unsigned(std::min_element(load.begin(), load.end()) - load.begin());
    load[task] += std::max<uint64_t>(1, unitRays(entries, order[i]));
    plan["entries"].push_back({{"index", order[i].entry}, {"begin", order[i].begin}, {"end", order[i].end},
                               {"task", task}, {"key", e.key}, {"mesh", e.mesh}, {"args", e.args},
                               {"split", e.split}, {"output", e.output},
                               {"rays", unitRays(entries, order[i])}});
  }
  return plan;
}

std::string batchScript(const SlurmOptions& so, const std::string& plan, const std::string& logs) {
  std::string s = "#!/bin/bash\n# vff-library: one array task bakes its share of " + plan + "\n";
  s += "#SBATCH --job-name=vff-library\n#SBATCH --output=" + logs + "\n";
  if (!so.partition.empty()) s += "#SBATCH --partition=" + so.partition + "\n";
  if (!so.time.empty()) s += "#SBATCH --time=" + so.time + "\n";
  if (so.cpusPerTask) s += "#SBATCH --cpus-per-task=" + std::to_string(so.cpusPerTask) + "\n";
  for (const auto& a : so.sbatchArgs) s += "#SBATCH " + a + "\n";
  s += "exec " + shellQuote(selfPath()) + " run-shard " + shellQuote(plan) + " \"$SLURM_ARRAY_TASK_ID\"\n";
  return s;
}

// The array job is still known to squeue.
bool jobActive(const std::string& jobId, const std::string& dir) {
  const int rc = runProcess({"squeue", "-h", "-j", jobId, "-o", "%i"}, dir + "/squeue.out", dir + "/squeue.err");
  if (rc != 0) return false;  // an ended job is no longer a valid id
  return !trim(readText(dir + "/squeue.out")).empty();
}

// A plan's entry as run-shard reads it: every member of its type, else why not.
std::optional<std::string> planEntryProblem(const nlohmann::json& j) {
  if (!j.is_object()) return "not an object";
  for (const char* k : {"index", "begin", "end", "task", "rays"})
    if (!j.contains(k) || !j[k].is_number_unsigned()) return std::string(k) + ": not an integer >= 0";
  for (const char* k : {"key", "mesh", "split", "output"})
    if (!j.contains(k) || !j[k].is_string()) return std::string(k) + ": not a string";
  if (!j.contains("args") || !j["args"].is_array() ||
      !std::all_of(j["args"].begin(), j["args"].end(), [](const nlohmann::json& a) { return a.is_string(); }))
    return "args: not an array of strings";
  if (j["key"].get<std::string>().size() != 32 || j["begin"].get<uint64_t>() > UINT32_MAX || j["end"].get<uint64_t>() > UINT32_MAX)
    return "key or map range out of range";
  return std::nullopt;
}

// The plan's problem (run-shard trusts nothing it reads), or nothing.
std::optional<std::string> planProblem(const nlohmann::json& plan) {
  if (!plan.is_object() || !plan.contains("vffLibraryPlan") || plan["vffLibraryPlan"] != 1) return "not a vff-library plan";
  for (const char* k : {"vffBake", "cache"})
    if (!plan.contains(k) || !plan[k].is_string()) return std::string(k) + ": not a string";
  if (!plan.contains("entries") || !plan["entries"].is_array()) return "entries: not an array";
  for (size_t i = 0; i < plan["entries"].size(); ++i)
    if (auto p = planEntryProblem(plan["entries"][i])) return "entries[" + std::to_string(i) + "]." + *p;
  return std::nullopt;
}

}  // namespace

unsigned arrayTasks(uint64_t rays, size_t units, unsigned tasks, uint64_t raysPerTask) {
  const uint64_t most = std::min<uint64_t>(1000, std::max<size_t>(1, units));
  if (tasks) return unsigned(std::min<uint64_t>(tasks, most));
  const uint64_t byWork = raysPerTask ? rays / raysPerTask + (rays % raysPerTask != 0) : most;
  return unsigned(std::clamp<uint64_t>(byWork, 1, most));
}

std::optional<std::string> runSlurm(const std::vector<Entry>& entries, const std::vector<Unit>& todo,
                                    const WorkerOptions& wo, const SlurmOptions& so,
                                    std::vector<EntryOutcome>* outcomes, std::vector<std::string>* jobIds, int* rc) {
  std::error_code ec;
  fs::create_directories(so.stateDir, ec);
  if (ec) {
    *rc = cli::kExitIo;
    return so.stateDir + ": " + ec.message();
  }
  const std::string state = fs::absolute(so.stateDir).string();
  std::vector<Unit> pending = todo;
  // A unit's file in the cache: the entry's field, or its part.
  auto cached = [&](const Unit& u) {
    const Entry& e = entries[u.entry];
    if (!u.part()) return inCache(wo.cacheDir, e);
    struct stat st{};
    return ::stat(partPath(wo.cacheDir, e.key, u.begin, u.end).c_str(), &st) == 0;
  };
  auto unitId = [](const Unit& u) { return std::to_string(u.entry) + ":" + std::to_string(u.begin) + ":" + std::to_string(u.end); };
  cli::Progress progress(kProg, so.progress, 0, "entries");
  for (unsigned round = 0; !pending.empty(); ++round) {
    uint64_t rays = 0;
    for (const Unit& u : pending) rays += unitRays(entries, u);
    const unsigned tasks = arrayTasks(rays, pending.size(), so.tasks, so.raysPerTask);
    const std::string stem = state + "/round-" + std::to_string(round);
    const std::string plan = stem + ".plan.json", script = stem + ".sh";
    const nlohmann::json planJson = makePlan(entries, pending, wo, tasks);
    std::map<std::string, unsigned> taskOf;
    for (const auto& j : planJson["entries"])
      taskOf[unitId({j["index"].get<size_t>(), j["begin"].get<uint32_t>(), j["end"].get<uint32_t>()})] =
          j["task"].get<unsigned>();
    if (auto p = writeText(plan, planJson.dump(1))) return *rc = cli::kExitIo, *p;
    if (auto p = writeText(script, batchScript(so, plan, stem + ".task-%a.log"))) return *rc = cli::kExitIo, *p;
    std::string array = "--array=0-" + std::to_string(tasks - 1);
    if (so.maxRunning) array += "%" + std::to_string(so.maxRunning);
    const std::vector<std::string> sbatch = {"sbatch", "--parsable", array, script};
    if (so.dryRun) {
      std::printf("# %s\n%s", [&] {
        std::string c;
        for (const auto& a : sbatch) c += (c.empty() ? "" : " ") + shellQuote(a);
        return c;
      }().c_str(), readText(script).c_str());
      return std::nullopt;
    }
    const int src = runProcess(sbatch, stem + ".sbatch.out", stem + ".sbatch.err");
    const std::string jobId = trim(readText(stem + ".sbatch.out")).substr(0, trim(readText(stem + ".sbatch.out")).find(';'));
    if (src != 0 || jobId.empty()) {
      *rc = cli::kExitRuntime;
      return "sbatch failed (exit " + std::to_string(src) + "): " + trim(readText(stem + ".sbatch.err"));
    }
    jobIds->push_back(jobId);
    while (jobActive(jobId, state)) {
      size_t have = 0;
      for (const Unit& u : todo) have += cached(u);
      progress.update(have, todo.size());
      std::this_thread::sleep_for(std::chrono::duration<double>(so.pollSeconds));
    }
    // Collect what the tasks reported; whatever is in the cache is done.
    std::map<std::string, EntryOutcome> reported;
    for (unsigned t = 0; t < tasks; ++t) {
      auto r = nlohmann::json::parse(readText(stem + ".report-" + std::to_string(t) + ".json"), nullptr, false);
      if (!r.is_object() || !r.contains("entries") || !r["entries"].is_array()) continue;
      // A report is read without trusting its types: what it lacks is looked for in the cache.
      for (const auto& j : r["entries"]) {
        if (!j.is_object()) continue;
        EntryOutcome o;
        o.entry = size_t(jsonCount(j, "index"));
        if (o.entry >= entries.size()) continue;
        o.unit = {o.entry, uint32_t(jsonCount(j, "begin")), uint32_t(jsonCount(j, "end"))};
        o.where = "slurm " + jobId + "_" + std::to_string(t);
        o.result.ok = j.contains("ok") && j["ok"].is_boolean() && j["ok"].get<bool>();
        o.result.exitCode = j.contains("exitCode") && j["exitCode"].is_number_integer() ? j["exitCode"].get<int>() : 0;
        o.result.error = j.contains("error") && j["error"].is_string() ? j["error"].get<std::string>() : "";
        o.result.rays = jsonCount(j, "rays");
        if (j.contains("seconds") && j["seconds"].is_number()) o.result.seconds = j["seconds"].get<double>();
        reported[unitId(o.unit)] = o;
      }
    }
    std::vector<Unit> missing;
    for (const Unit& u : pending) {
      auto it = reported.find(unitId(u));
      EntryOutcome o;
      o.entry = u.entry;
      o.unit = u;
      o.where = "slurm " + jobId + "_" + std::to_string(taskOf[unitId(u)]);
      if (it != reported.end()) o = it->second;
      if (cached(u)) {
        o.result.ok = true;
        if (!u.part())
          if (auto problem = installOutput(wo.cacheDir, entries[u.entry])) {
          o.result.ok = false;
          o.result.error = *problem;
          o.result.exitCode = cli::kExitIo;
        }
        outcomes->push_back(o);
      } else if (it != reported.end() && it->second.result.exitCode > 0 && it->second.result.exitCode < 128) {
        outcomes->push_back(o);  // the bake itself failed: resubmitting would fail again
      } else if (round < so.retries) {
        missing.push_back(u);
      } else {
        o.result.ok = false;
        o.result.exitCode = cli::kExitRuntime;
        o.result.error = "not baked: its array task " + o.where + " ended first (killed, pre-empted or out of time); "
                         "the next run bakes it";
        outcomes->push_back(o);
      }
    }
    pending = missing;
  }
  progress.update(todo.size(), todo.size());
  return std::nullopt;
}

int runShard(const std::string& planPath, unsigned task) {
  auto plan = nlohmann::json::parse(readText(planPath), nullptr, false);
  if (auto p = planProblem(plan)) {
    cli::printError(kProg, planPath + ": " + *p);
    return cli::kExitInvalidFile;
  }
  WorkerOptions wo;
  wo.vffBake = plan["vffBake"].get<std::string>();
  wo.cacheDir = plan["cache"].get<std::string>();
  const char* cpus = std::getenv("SLURM_CPUS_PER_TASK");
  wo.threads = cpus && std::atoi(cpus) > 0 ? unsigned(std::atoi(cpus)) : 1;
  removeStalePrivateDirs(wo.cacheDir);
  const std::string report = planPath.substr(0, planPath.size() - std::string(".plan.json").size()) + ".report-" +
                             std::to_string(task) + ".json";
  nlohmann::json out = {{"task", task}, {"host", [] {
                                           char h[256] = {};
                                           gethostname(h, sizeof h - 1);
                                           return std::string(h);
                                         }()},
                        {"entries", nlohmann::json::array()}};
  int rc = cli::kExitSuccess;
  for (const auto& j : plan["entries"]) {
    if (j["task"].get<uint64_t>() != task) continue;
    Entry e;
    e.key = j["key"].get<std::string>();
    e.mesh = j["mesh"].get<std::string>();
    e.args = j["args"].get<std::vector<std::string>>();
    e.split = j["split"].get<std::string>();
    e.output = j["output"].get<std::string>();
    const Unit u{0, uint32_t(j["begin"].get<uint64_t>()), uint32_t(j["end"].get<uint64_t>())};
    BakeResult r;
    struct stat st{};
    if (u.part() ? ::stat(partPath(wo.cacheDir, e.key, u.begin, u.end).c_str(), &st) == 0 : inCache(wo.cacheDir, e)) {
      r.ok = true;  // an earlier or concurrent task baked it
    } else {
      r = bakeUnit(e, u, wo);
    }
    if (!r.ok) rc = cli::kExitRuntime;
    out["entries"].push_back({{"index", j["index"].get<uint64_t>()}, {"begin", u.begin}, {"end", u.end}, {"ok", r.ok}, {"exitCode", r.exitCode},
                              {"error", r.error}, {"rays", r.rays}, {"seconds", r.seconds}});
    // Written after each entry: a task killed later still reports what it did.
    if (auto p = writeText(report, out.dump(1))) cli::printError(kProg, report + ": " + *p);
    std::fprintf(stderr, "%s: %s: %s%s\n", kProg, e.mesh.c_str(), r.ok ? "baked" : "failed: ", r.error.c_str());
  }
  if (out["entries"].empty())
    if (auto p = writeText(report, out.dump(1))) cli::printError(kProg, report + ": " + *p);
  return rc;
}

}  // namespace vff::library
