// vff-library: bakes an asset library, every entry whose output is missing or stale and nothing
// else, through a content-addressed cache, with a local pool of vff-bake processes or a Slurm job
// array.
//
//   vff-library bake assets/ --out fields/ -- -m 32          every mesh of a folder, vff-bake's options after --
//   vff-library bake library.json --out fields/ --json r.json   a manifest (spec/library.md)
//   vff-library bake library.json --out fields/ --cache /shared/vff-cache --slurm --partition cpu --max-running 50
//   vff-library run-shard PLAN TASK                          one array task (what the batch script runs)
//
// manifest.cpp reads the entries, cache.cpp keys and stores them (scene_cache.cpp: split glTF
// scenes), worker.cpp runs vff-bake for one,
// pool.cpp and slurm.cpp run many, report.cpp tells what happened (library.h).
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <map>
#include <set>

#include "cli.h"
#include "library.h"
#include "platform/parallel.h"

namespace fs = std::filesystem;
using namespace vff;
using namespace vff::library;

namespace {

struct Options {
  std::string input, out, cache, glob = "*.obj,*.ply,*.off,*.stl,*.gltf,*.glb", json;
  std::vector<std::string> bakeArgs;
  unsigned workers = 0, threads = 0;
  uint64_t shardMaps = 0;
  bool slurm = false, dryRun = false, quiet = false, rehash = false;
  cli::OutputFormat format = cli::OutputFormat::kText;
  SlurmOptions slurmOptions;
  std::string planPath;
  unsigned task = 0;
};

void addBakeOptions(CLI::App& bake, Options& o) {
  bake.add_option("input", o.input, "a manifest (.json, spec/library.md) or a folder of meshes")->required();
  bake.add_option("bake-options", o.bakeArgs,
                  "folder input: vff-bake's options for every mesh, after -- (e.g. -- -m 32 --normals)");
  bake.add_option("--out", o.out, "output folder: each entry's field at its name")->required();
  bake.add_option("--cache", o.cache, "the cache folder, shareable between machines (default: OUT/.vff-cache)");
  bake.add_option("--glob", o.glob, "folder input: comma-separated patterns of the files to bake")->capture_default_str();
  bake.add_option("-j,--workers", o.workers, "local: vff-bake processes at a time (0: one per core)")->capture_default_str();
  bake.add_option("--threads", o.threads, "local: threads of each vff-bake (0: the cores shared among the workers)")
      ->capture_default_str();
  bake.add_option("--shard-maps", o.shardMaps,
                  "bake an entry of more maps than this as ranges of at most this many (vff-bake --map-range), in "
                  "parallel, merged into the same bytes (vff-bake --merge); 0: never (a manifest's shardMaps wins)")
      ->capture_default_str();
  bake.add_flag("--slurm", o.slurm, "bake as a Slurm job array (sbatch; the cache must be on a filesystem the nodes share)");
  SlurmOptions& s = o.slurmOptions;
  bake.add_option("--partition", s.partition, "slurm: the partition");
  bake.add_option("--time", s.time, "slurm: each task's time limit");
  bake.add_option("--max-running", s.maxRunning, "slurm: the most array tasks at once (%N)");
  bake.add_option("--tasks", s.tasks,
                  "slurm: array tasks (0: as many as the work fills, --rays-per-task each, at most one per bake and 1000)");
  bake.add_option("--rays-per-task", s.raysPerTask,
                  "slurm: with --tasks 0, the rays of work an array task gets at least (a task waits in the scheduler)")
      ->capture_default_str();
  bake.add_option("--cpus-per-task", s.cpusPerTask, "slurm: CPUs of each task, and vff-bake's threads");
  bake.add_option("--sbatch-arg", s.sbatchArgs, "slurm: another sbatch option (repeatable), e.g. --sbatch-arg=--account=A")
      ->allow_extra_args(false);
  bake.add_option("--state", s.stateDir, "slurm: plans, scripts, logs and reports (default: CACHE/slurm/TIME-PID)");
  bake.add_option("--retries", s.retries, "slurm: resubmissions of what an array left missing")->capture_default_str();
  bake.add_option("--poll", s.pollSeconds, "slurm: seconds between squeue polls")->capture_default_str();
  bake.add_flag("--rehash", o.rehash,
                "read every mesh again, even those whose path, size and time are unchanged since a run noted them");
  bake.add_flag("--dry-run", o.dryRun,
                "print what would be baked (with --slurm: the batch script) and the entries that would fail, bake "
                "nothing, and exit as the bake would");
  cli::addFormatOption(bake, o.format);
  bake.add_option("--json", o.json, "also write the report as JSON to this file (- for stdout)");
  bake.add_flag("-q,--quiet", o.quiet, "no progress line, no report on stderr (errors still)");
}

// The exit code of a run with failures: theirs when they share one, else a runtime error.
int failureExitCode(const std::vector<Entry>& entries, const Report& r) {
  std::set<int> codes;
  const nlohmann::json j = reportJson(entries, r);
  for (const auto& f : j["failed"]) codes.insert(f["exitCode"].get<int>());
  if (codes.size() == 1 && *codes.begin() > 0 && *codes.begin() < 6) return *codes.begin();
  return cli::kExitRuntime;
}

// The kind of input an option may apply to (vff-bake's checks differ for glTF and OpenVDB files).
std::string inputKind(const std::string& mesh) {
  const std::string ext = fs::path(mesh).extension().string();
  return ext == ".vdb" ? ".vdb" : (ext == ".gltf" || ext == ".glb") ? "glTF" : "mesh";
}

// A folder's options after --, checked once for each kind of input the folder has (the same options
// for every entry: one usage error, not one per entry).
std::optional<std::string> checkFolderArgs(const std::vector<Entry>& entries) {
  std::set<std::string> kinds;
  for (const Entry& e : entries)
    if (kinds.insert(inputKind(e.mesh)).second)
      if (auto p = checkBakeArgs(e))
        return ruleLabel(kRuleBakeOption) + ": the options after --: " + *p + " (for " + e.name + ", a " +
               inputKind(e.mesh) + " input)";
  return std::nullopt;
}

// The dry run's listing as JSON: every entry with its state, and the bakes.
nlohmann::json dryRunJson(const std::vector<Entry>& entries, const Report& r, const std::vector<Unit>& units,
                          const std::vector<size_t>& todo) {
  nlohmann::json j = {{"vffLibraryDryRun", 1}, {"entries", nlohmann::json::array()}, {"bakes", nlohmann::json::array()}};
  std::vector<std::string> state(entries.size());
  for (size_t i : r.upToDate) state[i] = "upToDate";
  for (size_t i : todo) state[i] = "bake";
  for (size_t i : r.failed) state[i] = "failed";
  for (size_t i = 0; i < entries.size(); ++i) {
    const Entry& e = entries[i];
    nlohmann::json x = {{"mesh", e.name}, {"output", e.outputName}, {"args", e.args}, {"shardMaps", e.shardMaps},
                        {"split", e.split}, {"state", state[i]}, {"key", e.key}, {"maps", e.maps}, {"rays", e.rays}};
    if (!e.error.empty()) x["error"] = e.error, x["exitCode"] = e.exitCode;
    j["entries"].push_back(x);
  }
  for (const Unit& u : units)
    j["bakes"].push_back({{"entry", u.entry}, {"maps", u.part() ? nlohmann::json::array({u.begin, u.end}) : nlohmann::json("all")}});
  return j;
}

// The dry run's vff-bake command of each bake (a local run's).
void printBakeCommands(const std::vector<Entry>& entries, const std::vector<Unit>& units, const WorkerOptions& wo) {
  for (const Unit& u : units) {
    const Entry& e = entries[u.entry];
    std::printf("%s %s", wo.vffBake.c_str(), e.mesh.c_str());
    for (const auto& a : e.args) std::printf(" %s", a.c_str());
    if (u.part())
      std::printf(" --map-range %u:%u -o %s -j %u  # part of %s\n", u.begin, u.end,
                  partPath(wo.cacheDir, e.key, u.begin, u.end).c_str(), wo.threads, e.output.c_str());
    else if (!e.split.empty())
      std::printf(" -o %s/%s -j %u  # -> %s and its fields\n", sceneCachePath(wo.cacheDir, e.key).c_str(),
                  fs::path(e.output).filename().c_str(), wo.threads, e.output.c_str());
    else
      std::printf(" -o %s -j %u  # -> %s\n", cachePath(wo.cacheDir, e.key).c_str(), wo.threads, e.output.c_str());
  }
}

int bakeLibrary(const Options& o) {
  const auto t0 = std::chrono::steady_clock::now();
  std::vector<Entry> entries;
  std::error_code ec;
  if (fs::is_directory(o.input, ec)) {
    if (std::find(o.bakeArgs.begin(), o.bakeArgs.end(), "--split") != o.bakeArgs.end()) {
      cli::usageError(kProg, "--split names a scene description per entry: give it in a manifest (\"split\": \"mesh\")");
      return cli::kExitUsage;
    }
    if (auto p = readFolder(o.input, o.glob, o.bakeArgs, o.out, &entries)) {
      cli::printError(kProg, *p);
      return cli::kExitIo;
    }
    if (auto p = checkFolderArgs(entries)) {
      cli::usageError(kProg, *p);
      return cli::kExitUsage;
    }
  } else {
    if (!o.bakeArgs.empty()) {
      cli::usageError(kProg, "vff-bake options after -- apply to a folder; a manifest sets them in \"defaults\"");
      return cli::kExitUsage;
    }
    int rc = 0;
    if (auto p = readManifest(o.input, o.out, &entries, &rc)) {
      cli::printError(kProg, *p);
      return rc;
    }
  }
  std::map<std::string, std::string> outputs;  // (a manifest's entries are checked as it is read: rule 13014)
  for (const Entry& e : entries)
    if (auto [it, fresh] = outputs.emplace(e.output, e.name); !fresh) {
      cli::usageError(kProg, e.name + " and " + it->second + " would both be baked to " + e.outputName +
                                 " (name outputs in a manifest)");
      return cli::kExitUsage;
    }
  if (o.format == cli::OutputFormat::kJson && (!o.dryRun || o.slurm)) {
    cli::usageError(kProg, "--format json lists a local --dry-run (a bake's report: --json FILE)");
    return cli::kExitUsage;
  }

  const unsigned cores = parallel::resolveThreads(0);
  WorkerOptions wo;
  wo.vffBake = findVffBake();
  wo.cacheDir = fs::absolute(o.cache.empty() ? o.out + "/.vff-cache" : o.cache).lexically_normal().string();
  fs::create_directories(wo.cacheDir + "/tmp", ec);
  if (ec) {
    cli::printError(kProg, wo.cacheDir + ": " + ec.message());
    return cli::kExitIo;
  }
  removeStalePrivateDirs(wo.cacheDir);
  for (Entry& e : entries)
    if (!e.shardMapsSet) e.shardMaps = o.shardMaps;  // an explicit 0 in a manifest means never
  computeKeys(entries, {.dir = wo.cacheDir, .threads = cores, .statNotes = !o.rehash});

  Report report;
  report.mode = o.slurm ? "slurm" : "local";
  std::vector<size_t> todo;
  for (size_t i = 0; i < entries.size(); ++i) {
    const Entry& e = entries[i];
    if (!e.error.empty()) {
      report.failed.push_back(i);
    } else if (inCache(wo.cacheDir, e)) {
      if (!outputUpToDate(wo.cacheDir, e) && !o.dryRun)
        if (auto p = installOutput(wo.cacheDir, e)) {
          entries[i].error = *p;
          entries[i].exitCode = cli::kExitIo;
          report.failed.push_back(i);
          continue;
        }
      report.upToDate.push_back(i);
    } else {
      todo.push_back(i);
    }
  }

  const bool progress = !o.quiet && !o.dryRun && isatty(2);
  const std::vector<Unit> units = planUnits(entries, todo, wo.cacheDir);
  if (o.slurm) {
    SlurmOptions so = o.slurmOptions;
    so.dryRun = o.dryRun;
    so.progress = progress;
    if (so.stateDir.empty())
      so.stateDir = wo.cacheDir + "/slurm/" + std::to_string(std::time(nullptr)) + "-" + std::to_string(getpid());
    if (!units.empty()) {
      int rc = 0;
      if (auto p = runSlurm(entries, units, wo, so, &report.outcomes, &report.slurmJobs, &rc)) {
        cli::printError(kProg, *p);
        return rc;
      }
    }
  } else {
    report.workers = o.workers ? o.workers : cores;
    report.workers = std::max<unsigned>(1, std::min<unsigned>(report.workers, unsigned(std::max<size_t>(1, units.size()))));
    report.threadsPerWorker = o.threads ? o.threads : std::max(1u, cores / report.workers);
    wo.threads = report.threadsPerWorker;
    if (o.dryRun) {
      if (o.format != cli::OutputFormat::kJson) printBakeCommands(entries, units, wo);
    } else {
      report.outcomes = runPool(entries, units, wo, {.workers = report.workers, .threadsPerWorker = wo.threads,
                                                    .progress = progress});
    }
  }
  if (o.dryRun) {
    // What the bake would report before baking: the entries that fail, and its exit code then.
    if (o.format == cli::OutputFormat::kJson) std::printf("%s\n", dryRunJson(entries, report, units, todo).dump(1).c_str());
    for (size_t i : report.failed)
      std::fprintf(stderr, "%s: error: %s: %s (exit %d)\n", kProg, entries[i].name.c_str(), entries[i].error.c_str(),
                   entries[i].exitCode);
    if (o.format != cli::OutputFormat::kJson)
      std::printf("# %s: %zu to bake, %zu up to date, %zu failing\n", counted(entries.size(), "entry", "entries").c_str(),
                  todo.size(), report.upToDate.size(), report.failed.size());
    return report.failed.empty() ? cli::kExitSuccess : failureExitCode(entries, report);
  }
  report.entryOutcomes = finishEntries(entries, todo, report.outcomes, wo);
  for (const EntryOutcome& out : report.entryOutcomes) (out.result.ok ? report.baked : report.failed).push_back(out.entry);
  std::sort(report.baked.begin(), report.baked.end());
  std::sort(report.failed.begin(), report.failed.end());
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  if (!o.json.empty()) {
    const std::string text = reportJson(entries, report).dump(2) + "\n";
    if (auto st = cli::writeFileAtomic(o.json, {reinterpret_cast<const uint8_t*>(text.data()), text.size()}); !st)
      return cli::reportError(kProg, o.json, st.error());
  }
  if (!o.quiet) printReport(entries, report, stderr);
  else
    for (const nlohmann::json j = reportJson(entries, report); const auto& f : j["failed"])
      std::fprintf(stderr, "%s: error: %s: %s\n", kProg, f["mesh"].get<std::string>().c_str(),
                   f["error"].get<std::string>().c_str());
  return report.failed.empty() ? cli::kExitSuccess : failureExitCode(entries, report);
}

// `vff-library key MESH -- OPTIONS`: the key's text and the key, for finding why a run missed the cache.
int printKey(const std::string& mesh, const std::vector<std::string>& args) {
  if (std::find(args.begin(), args.end(), "--split") != args.end()) {
    cli::usageError(kProg, "a split entry's key also names its output: see bake --dry-run --format json");
    return cli::kExitUsage;
  }
  Entry e;
  e.name = mesh;
  e.mesh = fs::absolute(fs::path(mesh)).lexically_normal().string();
  e.args = args;
  const auto text = keyText(e, {.dir = "", .threads = 1, .statNotes = false});
  if (!text) {
    cli::printError(kProg, mesh + ": " + e.error);
    return e.exitCode;
  }
  std::printf("%skey %s\n", text->c_str(), keyHash(*text).c_str());
  return cli::kExitSuccess;
}

int run(int argc, char** argv) {
  Options o;
  CLI::App app{"Bakes an asset library (a manifest, or a folder and a glob) into visibility fields through a\n"
               "content-addressed cache: only entries whose output is missing or stale are baked, by a local pool\n"
               "of vff-bake processes or as a Slurm job array. Exits non-zero when any entry failed: with the\n"
               "failures' exit code when they share one, else 4; the others are baked all the same.\n" +
               cli::exitCodeHelp()};
  cli::addVersionFlag(app, kProg);
  app.require_subcommand(1);
  CLI::App* bake = app.add_subcommand("bake", "bake every entry whose output is missing or stale");
  addBakeOptions(*bake, o);
  CLI::App* shard = app.add_subcommand("run-shard", "bake one Slurm array task's share of a plan (the batch script runs it)");
  shard->add_option("plan", o.planPath, "the plan (STATE/round-N.plan.json)")->required();
  shard->add_option("task", o.task, "the array task (SLURM_ARRAY_TASK_ID)")->required();
  CLI::App* key = app.add_subcommand("key", "print the cache key of a mesh baked with vff-bake's options: the key's "
                                            "text (spec/library.md section 6), then \"key KEY\"");
  std::string keyMesh;
  key->add_option("mesh", keyMesh, "the input")->required();
  key->add_option("bake-options", o.bakeArgs, "vff-bake's options, after -- (e.g. -- -m 32 --normals)");
  if (auto rc = cli::parse(app, kProg, argc, argv)) return *rc;
  if (shard->parsed()) return runShard(o.planPath, o.task);
  if (key->parsed()) return printKey(keyMesh, o.bakeArgs);
  return bakeLibrary(o);
}

}  // namespace

int main(int argc, char** argv) { return cli::runGuarded(kProg, run, argc, argv); }
