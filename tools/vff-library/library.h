// library.h - what vff-library's parts share: the entries of a library (manifest.cpp), their cache
// keys and the cache itself (cache.cpp; split glTF scenes: scene_cache.cpp), baking an entry into
// the cache with vff-bake (worker.cpp), the local pool (pool.cpp), Slurm job arrays (slurm.cpp) and
// the report (report.cpp).
#pragma once

#include <nlohmann/json.hpp>

#include "vff/error.h"

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vff::library {

inline constexpr const char* kProg = "vff-library";

// "1 entry", "2 entries": a count and its noun.
inline std::string counted(uint64_t n, const char* one, const char* many) {
  return std::to_string(n) + " " + (n == 1 ? one : many);
}

// ---- Entries (manifest.cpp) ---------------------------------------------------------------------
// One field to bake: a mesh, the vff-bake options that shape its bytes, and where it goes. A split
// entry (a glTF scene baked as a field per object, vff-bake --split) is a scene description and its
// fields instead, cached and installed as one unit (scene_cache.cpp).
struct Entry {
  std::string mesh;               // the input file, absolute
  std::string name;               // how the report names it (the path as the manifest or folder gives it)
  std::vector<std::string> args;  // vff-bake options, as vff-bake spells them (no -o, -j, --json)
  std::string output;             // the output file, absolute (a split entry's: its scene description)
  std::string outputName;         // the output relative to the output folder, as spec/library.md section 5 makes it
  std::string where;              // a manifest entry's JSON path ("entries[3]"); "" for a folder's
  std::string split;              // "mesh" or "node": vff-bake --split (also in args); "": one field
  uint64_t shardMaps = 0;         // above this many maps, bake in map ranges (0: never)
  bool shardMapsSet = false;      // the manifest or the entry sets shardMaps (--shard-maps applies otherwise)
  // Filled by computeKeys (cache.cpp):
  std::string key;    // 32 hex digits; empty when the entry cannot be baked (error says why)
  std::string error;  // a problem found before baking (unreadable mesh, bad option)
  int exitCode = 0;   // vff-bake's exit code for `error`
  uint64_t rays = 0;  // the rays its field has (maps x M x M), a split entry's all its fields'
  uint64_t maps = 0;  // of one field
};

// The checks of a manifest (spec/library.md section 8): a numeric ID, a name, the exit code.
struct ManifestRule {
  int id;
  const char* name;
  int exitCode;
};
inline constexpr ManifestRule kRuleManifestJson{13001, "manifest-json", 3};
inline constexpr ManifestRule kRuleManifestObject{13002, "manifest-object", 3};
inline constexpr ManifestRule kRuleVersionType{13003, "library-version-type", 3};
inline constexpr ManifestRule kRuleVersion{13004, "library-version", 5};
inline constexpr ManifestRule kRuleUnknownMember{13005, "unknown-member", 3};
inline constexpr ManifestRule kRuleMissingMember{13006, "missing-member", 3};
inline constexpr ManifestRule kRuleMemberType{13007, "member-type", 3};
inline constexpr ManifestRule kRuleUnknownOption{13008, "unknown-option", 3};
inline constexpr ManifestRule kRuleOptionType{13009, "option-type", 3};
inline constexpr ManifestRule kRuleMeshPath{13010, "mesh-path", 3};
inline constexpr ManifestRule kRuleSplitValue{13011, "split-value", 3};
inline constexpr ManifestRule kRuleOutputPath{13012, "output-path", 3};
inline constexpr ManifestRule kRuleSplitOutput{13013, "split-output", 3};
inline constexpr ManifestRule kRuleDuplicateOutput{13014, "duplicate-output", 3};
inline constexpr ManifestRule kRuleBakeOption{13015, "bake-option", 1};
// "name (ID)", as messages print a rule.
std::string ruleLabel(const ManifestRule& rule);

// Reads a manifest (spec/library.md) into entries; outputs under `outDir`. A problem of the
// manifest itself (not JSON, a wrong field) is returned as "FILE: name (ID): PATH: problem"; its
// exit code in *rc. Entries are added only when the whole manifest is valid.
std::optional<std::string> readManifest(const std::string& path, const std::string& outDir,
                                        std::vector<Entry>* entries, int* rc);
// The same, of a manifest's text: `path` names it in messages and its folder is the base of relative
// mesh paths (the file need not exist). Never throws, for any text.
std::optional<std::string> parseManifest(std::string_view text, const std::string& path,
                                         const std::string& outDir, std::vector<Entry>* entries, int* rc);
// Every file under `folder` (recursively, sorted) whose path relative to it matches one of the
// comma-separated `globs`, each baked with `args`, to OUT/RELATIVE-PATH-WITHOUT-EXTENSION.vff.
std::optional<std::string> readFolder(const std::string& folder, const std::string& globs,
                                      const std::vector<std::string>& args, const std::string& outDir,
                                      std::vector<Entry>* entries);

// ---- Cache (cache.cpp) --------------------------------------------------------------------------
struct CacheOptions {
  std::string dir;       // the cache folder
  unsigned threads = 1;  // for reading the meshes
  bool statNotes = true;  // reuse what an earlier run read of an unchanged file (cache.cpp)
};

// XXH3-128 of a file's bytes, as hex (level sets and glTF scenes: what vff-bake reads of them);
// nothing when it cannot be read.
std::optional<std::string> fileHash(const std::string& path);
// The text whose XXH3-128 is the entry's key (spec/library.md section 6); nothing, with the entry's
// error and exit code set, when its options or its mesh cannot be read. Sets its rays and maps.
std::optional<std::string> keyText(Entry& e, const CacheOptions& o);
// XXH3-128 of a key's text, as 32 lower-case hex digits.
std::string keyHash(const std::string& text);
// What vff-bake's parser and checks say against the entry's options (its mesh only by its kind:
// a .gltf, a .vdb or another mesh); nothing when they take them.
std::optional<std::string> checkBakeArgs(const Entry& e);
// Reads every entry's mesh and options and sets its key (or its error), in parallel.
void computeKeys(std::vector<Entry>& entries, const CacheOptions& o);
// CACHE/ab/KEY.vff
std::string cachePath(const std::string& cacheDir, const std::string& key);
// CACHE/ab/KEY.maps-BEGIN-END.vff: a partial result of maps [begin, end) (vff-bake --map-range).
std::string partPath(const std::string& cacheDir, const std::string& key, uint32_t begin, uint32_t end);
// The entry's field (a split entry's scene) is in the cache.
bool inCache(const std::string& cacheDir, const Entry& e);
// The entry's output is the cached field: the same file (a hard link) or a copy of it with its size
// and modification time. A split entry's: its description and every field it names.
bool outputUpToDate(const std::string& cacheDir, const Entry& e);
// Puts the cached field at the entry's output, by a hard link, or a copy when the output is on
// another filesystem, through a temporary and a rename (a split entry: its fields, then its
// description). An error message, or nothing.
std::optional<std::string> installOutput(const std::string& cacheDir, const Entry& e);
// Puts the file `from` at `to` as installOutput does.
std::optional<std::string> installFile(const std::string& from, const std::string& to);
// `to` is the file `from`, or a copy of it with its size and modification time.
bool sameFile(const std::string& from, const std::string& to);

// ---- Split entries in the cache (scene_cache.cpp) -----------------------------------------------
// CACHE/ab/KEY.scene/: a split entry's scene description (named as its output) and its fields, as
// vff-bake --split wrote them; it enters the cache by one rename of the whole folder.
std::string sceneCachePath(const std::string& cacheDir, const std::string& key);
// What a split bake reads of a glTF file as one line (beginning "mesh "): the file's bytes and each
// object's geometry; *objects: how many fields it gives. Nothing, with *error, when it cannot be read.
std::optional<std::string> splitGeometry(const Entry& e, int scene, Error* error, uint64_t* objects);
// The object count a line of splitGeometry records (0 when it records none).
uint64_t splitObjects(const std::string& geometry);
// The files of a cached scene, relative to its folder: its fields, then its description.
std::optional<std::vector<std::string>> sceneFiles(const std::string& cacheDir, const Entry& e);
bool sceneUpToDate(const std::string& cacheDir, const Entry& e);
std::optional<std::string> installScene(const std::string& cacheDir, const Entry& e);
// A fresh private folder under CACHE/tmp for one bake (named by host, process and a counter, so
// processes on several machines never share one).
std::string makePrivateDir(const std::string& cacheDir);
// Removes the private folders of processes of this host that no longer exist.
void removeStalePrivateDirs(const std::string& cacheDir);
// Moves a finished file into the cache as KEY (rename: atomic; a racing writer wrote the same
// bytes). An error message, or nothing.
std::optional<std::string> commitToCache(const std::string& cacheDir, const std::string& key, const std::string& file);

// ---- Baking one entry (worker.cpp) --------------------------------------------------------------
struct BakeResult {
  bool ok = false;
  int exitCode = 0;
  std::string error;  // vff-bake's stderr (its last error line) when it failed
  uint64_t rays = 0;
  double seconds = 0;  // wall time of the bake
};

struct WorkerOptions {
  std::string vffBake;   // the vff-bake program
  std::string cacheDir;
  unsigned threads = 1;  // vff-bake -j
  uint64_t shardMaps = 0;  // unused until the sharded bake is available
};

// One bake: a whole entry, or maps [begin, end) of it (a part, for entries above their shardMaps).
struct Unit {
  size_t entry = 0;
  uint32_t begin = 0, end = 0;  // both 0: the whole field
  bool part() const { return end > begin; }
};

// Bakes `u` of `e` into the cache (a part to its partPath) through vff-bake in a private folder.
// Blocking.
BakeResult bakeUnit(const Entry& e, const Unit& u, const WorkerOptions& o);
// vff-bake --merge of the entry's parts into its cached field (the whole bake's bytes), then the
// parts are removed.
BakeResult mergeParts(const Entry& e, const std::vector<Unit>& parts, const WorkerOptions& o);
// Runs `args` (args[0] looked up in PATH) with stdout and stderr into the files `out` and `err`,
// killed if this thread ends first; its exit code (128 + N when killed by signal N, -1 when it
// could not be started).
int runProcess(const std::vector<std::string>& args, const std::string& out, const std::string& err);
// j[key] when j is an object whose `key` is an integer >= 0, else 0: for JSON this tool wrote
// (vff-bake's summary, a task's report), read without trusting its types.
inline uint64_t jsonCount(const nlohmann::json& j, const char* key) {
  if (!j.is_object()) return 0;
  const auto it = j.find(key);
  return it != j.end() && it->is_number_unsigned() ? it->get<uint64_t>() : 0;
}
// A file's bytes as text ("" when unreadable).
std::string readText(const std::string& path);
// The vff-bake beside this program (or $VFF_BAKE).
std::string findVffBake();
// This program, absolute (for Slurm's batch script).
std::string selfPath();

// ---- Running (shard.cpp, pool.cpp, slurm.cpp) ---------------------------------------------------
// The bakes of the entries `todo`: one unit each, or for an entry with more maps than its
// shardMaps, one per range of at most shardMaps maps not yet in the cache.
std::vector<Unit> planUnits(const std::vector<Entry>& entries, const std::vector<size_t>& todo,
                            const std::string& cacheDir);

struct EntryOutcome {
  size_t entry = 0;  // index into the entries
  Unit unit;
  BakeResult result;
  std::string where;  // "local", or "slurm JOB_TASK"
};
// Each entry of `todo` once its units ran (`units`: their outcomes): whole ones as they ended,
// sharded ones merged and installed when every part is in the cache.
std::vector<EntryOutcome> finishEntries(const std::vector<Entry>& entries, const std::vector<size_t>& todo,
                                        const std::vector<EntryOutcome>& units, const WorkerOptions& wo);


// The rays of one unit.
uint64_t unitRays(const std::vector<Entry>& entries, const Unit& u);

struct PoolOptions {
  unsigned workers = 1;
  unsigned threadsPerWorker = 1;
  bool progress = false;
};
// Bakes the units `todo` with a pool of `workers` vff-bake processes at a time; each finished whole
// entry is installed at its output at once.
std::vector<EntryOutcome> runPool(const std::vector<Entry>& entries, const std::vector<Unit>& todo,
                                  const WorkerOptions& wo, const PoolOptions& po);

// The least work an array task gets by default (spec/library.md section 7): a task waits in the
// scheduler and starts a process, so a small bake alone in a task spends more time there than baking.
inline constexpr uint64_t kRaysPerTask = uint64_t{1} << 30;
// The array tasks for `rays` of work in `units` bakes: `tasks` when given (at most one per bake),
// else one per raysPerTask rays begun; at least 1 and at most 1000.
unsigned arrayTasks(uint64_t rays, size_t units, unsigned tasks, uint64_t raysPerTask);

struct SlurmOptions {
  std::string partition, time;
  unsigned maxRunning = 0;             // the array's %N (0: no cap)
  unsigned tasks = 0;                  // array size (0: by the work, raysPerTask each, at most 1000)
  uint64_t raysPerTask = kRaysPerTask;
  unsigned cpusPerTask = 0;            // --cpus-per-task (0: Slurm's default) and vff-bake -j
  std::vector<std::string> sbatchArgs; // passed through
  std::string stateDir;                // where the plan, script, logs and reports go
  unsigned retries = 1;                // resubmissions of what is missing after an array ends
  double pollSeconds = 1.0;
  bool dryRun = false;
  bool progress = false;
};
// Bakes `todo` as one Slurm job array (and resubmissions of what it left missing); returns the
// outcomes collected from the tasks' reports, or an error message with its exit code in *rc.
std::optional<std::string> runSlurm(const std::vector<Entry>& entries, const std::vector<Unit>& todo,
                                    const WorkerOptions& wo, const SlurmOptions& so,
                                    std::vector<EntryOutcome>* outcomes, std::vector<std::string>* jobIds, int* rc);
// `vff-library run-shard STATE TASK`: bakes the plan's entries of array task TASK into the cache
// and writes STATE/report-JOB-TASK.json. Returns the exit code.
int runShard(const std::string& stateDir, unsigned task);

// ---- Report (report.cpp) ------------------------------------------------------------------------
struct Report {
  std::vector<size_t> upToDate, baked, failed;
  std::vector<EntryOutcome> outcomes;  // each bake that ran (a whole entry or a part), with its time
  std::vector<EntryOutcome> entryOutcomes;  // each entry that was to be baked
  std::vector<std::string> slurmJobs;
  double seconds = 0;  // the whole run
  std::string mode;    // "local" or "slurm"
  unsigned workers = 0, threadsPerWorker = 0;
};
nlohmann::json reportJson(const std::vector<Entry>& entries, const Report& r);
void printReport(const std::vector<Entry>& entries, const Report& r, std::FILE* to);

}  // namespace vff::library
