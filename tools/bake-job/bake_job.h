// bake_job.h - one bake as vff-bake's command line states it, shared by vff-bake and vff-library:
// the command line (options.cpp), the checks and output every bake makes (common.cpp), and partial
// results of a map range (partial.cpp) and their merge (merge.cpp; spec/partial.md).
#pragma once

#include <nlohmann/json.hpp>

#include <CLI/CLI.hpp>
#include <chrono>
#include <cstdint>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "enum_option.h"
#include "options_codec.h"
#include "options_layout.h"
#include "progress.h"
#include "vff/bake/baker.h"
#include "vff/vff.h"

namespace vff::bake_tool {

inline constexpr const char* kProg = "vff-bake";

// ---- The command line (options.cpp) -------------------------------------------------------------
struct Options {
  std::string mesh;
  std::string output;
  std::string grid;  // .vdb input: the level set grid to bake (empty: the first)
  int scene = -1;     // glTF input: the scene to bake (-1: the file's default scene)
  std::string split;  // glTF input: "mesh" or "node": a field each and a scene description
  bool externalFields = false;  // glTF input, .glb output: the fields beside the .glb, referenced by uri
  cli::EnumOption<PositionScheme> positions{"--positions", vff::kPositionSchemes, PositionScheme::kOctaHemi2};
  uint32_t count = 0;  // 0: the scheme's default
  uint32_t mapSize = 64;
  cli::EnumOption<DirectionScheme> directions{"--directions", vff::kDirectionSchemes,
                                              DirectionScheme::kConcentricEqualArea};
  cli::EnumOption<DistanceEncoding> encoding{"--encoding", vff::kDistanceEncodings,
                                             DistanceEncoding::kUnorm8Diameter};
  bool normals = false;
  bool refine = false;       // --refine: the REFN section (vff/refine.h)
  bool refineProbe = false;  // --refine-probe: RefineOptions::probe
  unsigned threads = 0;
  std::vector<float> center;
  float radius = 0;
  bool allowClippedSphere = false;  // a --center/--radius sphere may cut the mesh
  cli::OptionsCodec codec;
  cli::OptionsLayout layout;
  bool json = false;
  bool quiet = false;
  bool benchmark = false;
  int repeat = 3;
  std::string mapRange;            // --map-range BEGIN:END: a partial result of those maps
  std::vector<std::string> merge;  // --merge PART...: the partial results to assemble into -o
};

// A half-open range of map indices, [begin, end), in the field's sample order.
struct MapRange {
  uint32_t begin = 0;
  uint32_t end = 0;
};

// Adds every option of `o` to `app`.
void addOptions(CLI::App& app, Options& o);
// The usage error of a parsed command line that CLI11 cannot see (an option that needs another, or
// does not apply to the input's kind); nothing when there is none.
std::optional<std::string> checkOptions(const Options& o);
// The usage error of a --merge command line that also gives a bake option (the parts carry them).
std::optional<std::string> checkMergeOptions(const CLI::App& app);
// The baker's options and the writer's, from the command line.
bake::BakeOptions bakeOptions(const Options& o);
WriteOptions writeOptions(const Options& o);
// The input is an OpenVDB file, a glTF file (by its extension).
bool isVdbPath(const std::string& p);
bool isGltfPath(const std::string& p);
// The output is a glTF binary (by its extension): a glTF input then gets its fields attached.
bool isGlbPath(const std::string& p);

// ---- What both bakes share (common.cpp) ---------------------------------------------------------
// Seconds since `t0`.
double secondsSince(std::chrono::steady_clock::time_point t0);
// The last component of a path.
std::string baseName(const std::string& p);
// The process's peak resident memory.
double peakRssMiB();

// Checks a planned field before any output exists: the baker's description of it (`field`), its
// layout under `limits`, its payload under the baker's 16 GiB limit. Each failure is a usage error,
// printed here; returns the exit code then, else nothing, with the payload bytes in *payload.
std::optional<int> checkPlan(const Result<FieldDesc>& field, const LayoutLimits& limits, uint64_t* payload);

// Writes the baked maps (the normals too with o.normals) through `writer` of `output` and finishes
// the file; *seconds: the time it took, *fileBytes: the file's size. Returns the exit code of a
// failure.
std::optional<int> writeBaked(const Options& o, const std::string& output, Writer& writer,
                              const bake::BakedField& baked, double* seconds, uint64_t* fileBytes);

// The --json keys every bake reports (the callers add their input's and timing keys).
nlohmann::json bakeSummary(const bake::BakeOptions& bo, const FieldDesc& field, const bake::BakeStats& s,
                           uint64_t payload, double bakeSeconds);

// ---- Partial results: --map-range (partial.cpp) and --merge (merge.cpp); spec/partial.md -------
// The version of "vff.partial" this vff-bake writes and reads.
inline constexpr int kPartialVersion = 1;
// "BEGIN:END" with BEGIN < END, decimal; nothing when the text is not that.
std::optional<MapRange> parseMapRange(const std::string& text);
// A range that ends past the field's `mapCount` maps is a usage error (printed here, naming the
// count); returns its exit code, else nothing.
std::optional<int> checkMapRange(const MapRange& r, uint32_t mapCount);
// One distance map of misses in the field's encoding: a partial result's filler (for bc4-diameter,
// the BC4 blocks of all-miss codes). A filler's normal map is all zero bytes.
std::vector<uint8_t> missMap(const FieldDesc& f);
// The writer's options of a partial result whose whole bake writes with `whole`.
WriteOptions partialWriteOptions(const WriteOptions& whole);
// META of a partial result: the whole bake's META and "vff.partial".
std::string partialMetadata(const std::string& wholeMetadata, const WriteOptions& whole, const MapRange& r,
                            uint32_t mapCount);
// Writes the partial result: misses, the baked maps of `r` (baked holds only those), misses; then
// the normals likewise; finishes the file. Returns the exit code of a failure.
std::optional<int> writePartial(const Options& o, Writer& writer, const FieldDesc& field, const MapRange& r,
                                const bake::BakedField& baked, double* seconds, uint64_t* fileBytes);

// What a merge leaves to its caller around the output's Writer (vff-bake: its temporaries on a
// signal); either may be empty, as in a fuzz target.
struct MergeHooks {
  std::function<void(const std::string& output)> beforeWrite;    // before the Writer of `output` exists
  std::function<void(const std::string& output)> writerCreated;  // once it exists
};
// --merge: checks the parts o.merge against each other (spec/partial.md, in its order) and writes
// the whole field to o.output through the same Writer and options as a whole bake; prints the
// refusal or the summary. Returns the exit code. Uses o.merge, o.output, o.threads, o.json, o.quiet.
int mergeParts(const Options& o, const MergeHooks& hooks = {});

}  // namespace vff::bake_tool
