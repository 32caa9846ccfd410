// slurm.cpp - a library bake as Slurm job arrays: a plan and a batch script in a state folder, one
// `sbatch --array` whose task K bakes its share of the plan (`vff-library run-shard PLAN K`) into
// the shared cache, polling squeue until the array is gone, collecting the tasks' reports, and
// resubmitting only the entries still missing from the cache.
#include <sys/stat.h>
#include <unistd.h>

#include <chrono>
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
  for (size_t i = 0; i < order.size(); ++i) {
    const Entry& e = entries[order[i].entry];
    plan["entries"].push_back({{"index", order[i].entry}, {"begin", order[i].begin}, {"end", order[i].end},
                               {"task", i % tasks}, {"key", e.key}, {"mesh", e.mesh}, {"args", e.args},
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

}  // namespace

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
    const unsigned tasks = so.tasks ? std::min<unsigned>(so.tasks, unsigned(pending.size()))
                                    : std::min<unsigned>(1000, unsigned(pending.size()));
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
      if (r.is_discarded() || !r.contains("entries")) continue;
      for (const auto& j : r["entries"]) {
        EntryOutcome o;
        o.entry = j.value("index", size_t{0});
        o.unit = {o.entry, j.value("begin", 0u), j.value("end", 0u)};
        o.where = "slurm " + jobId + "_" + std::to_string(t);
        o.result.ok = j.value("ok", false);
        o.result.exitCode = j.value("exitCode", 0);
        o.result.error = j.value("error", std::string());
        o.result.rays = j.value("rays", uint64_t{0});
        o.result.seconds = j.value("seconds", 0.0);
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
  if (plan.is_discarded() || plan.value("vffLibraryPlan", 0) != 1) {
    cli::printError(kProg, planPath + ": not a vff-library plan");
    return cli::kExitInvalidFile;
  }
  WorkerOptions wo;
  wo.vffBake = plan.value("vffBake", std::string("vff-bake"));
  wo.cacheDir = plan.value("cache", std::string());
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
    if (j.value("task", 0u) != task) continue;
    Entry e;
    e.key = j.value("key", std::string());
    e.mesh = j.value("mesh", std::string());
    e.args = j.value("args", std::vector<std::string>{});
    e.split = j.value("split", std::string());
    e.output = j.value("output", std::string());
    const Unit u{0, j.value("begin", 0u), j.value("end", 0u)};
    BakeResult r;
    struct stat st{};
    if (u.part() ? ::stat(partPath(wo.cacheDir, e.key, u.begin, u.end).c_str(), &st) == 0 : inCache(wo.cacheDir, e)) {
      r.ok = true;  // an earlier or concurrent task baked it
    } else {
      r = bakeUnit(e, u, wo);
    }
    if (!r.ok) rc = cli::kExitRuntime;
    out["entries"].push_back({{"index", j.value("index", size_t{0})}, {"begin", u.begin}, {"end", u.end}, {"ok", r.ok}, {"exitCode", r.exitCode},
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
