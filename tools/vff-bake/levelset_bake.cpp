// levelset_bake.cpp - vff-bake from an OpenVDB level set (vff/bake/levelset.h): the field, layout,
// output and checks of a mesh bake; the metadata and the summary describe the grid instead of
// triangles.
#include <unistd.h>

#include <cinttypes>
#include <cstdio>

#include "bake.h"
#include "cli.h"
#include "vff/bake/levelset.h"

namespace vff::bake_tool {

namespace {

// vff.source.xxh3 of a level set is the XXH3-64 of the .vdb file's bytes (a mesh's hashes its
// positions and indices); the sphere is the user's or the one around the active voxels' bounds.
std::string levelSetMetadata(const Options& o, const bake::BakeOptions& bo, const bake::LevelSetInfo& info) {
  const nlohmann::json meta = {
      {"vff.generator", "vff-bake"},
      {"vff.generatorVersion", kLibraryVersion},
      {"vff.source", {{"name", baseName(o.mesh)}, {"format", "vdb"}, {"grid", info.grid},
                      {"activeVoxels", info.activeVoxels}, {"xxh3", cli::hexDigits64(info.fileXxh3)}}},
      {"vff.bake", {{"rayOrigin", "texel centre"}, {"sphere", bo.sphere ? "user" : "active-voxel-bounds"},
                    {"surface", "level set zero crossing"}, {"twoSided", true},
                    {"normals", o.normals ? "gradient" : "none"}}}};
  return meta.dump();
}

struct Timings {
  double load = 0, write = 0;
  uint64_t fileBytes = 0;
};

// The --json summary on stdout, or the one-line report on stderr (not with --quiet).
void reportLevelSetBake(const Options& o, const bake::BakeOptions& bo, const bake::LevelSetInfo& info,
                        const FieldDesc& field, const bake::BakeStats& s, uint64_t payload, const Timings& t) {
  const double rays = double(s.rays);
  if (o.json) {
    nlohmann::json summary = bakeSummary(bo, field, s, payload, s.seconds);
    summary.update({{"input", o.mesh},
                    {"grid", info.grid},
                    {"activeVoxels", info.activeVoxels},
                    {"voxelSize", info.voxelSize},
                    {"seconds", {{"load", t.load}, {"bake", s.seconds}, {"write", t.write}}},
                    {"output", o.output},
                    {"fileBytes", t.fileBytes}});
    std::printf("%s\n", summary.dump(2).c_str());
  } else if (!o.quiet) {
    std::fprintf(stderr,
                 "%s: %s: grid \"%s\" (%s of %g): %s of %ux%u (%.0f rays, %.1f%% hits) "
                 "in %.2f s (%.1f Mrays/s), %.3f MiB payload -> %s\n",
                 kProg, o.mesh.c_str(), info.grid.c_str(), cli::count(info.activeVoxels, "active voxel").c_str(),
                 info.voxelSize, cli::count(field.mapCount, "map").c_str(),
                 field.mapResolution, field.mapResolution, rays, 100.0 * double(s.hits) / rays, s.seconds,
                 rays / s.seconds / 1e6, double(payload) / 1048576.0, o.output.c_str());
  }
}

}  // namespace

int bakeFromLevelSet(const Options& o, bake::BakeOptions bo, WriteOptions wo) {
  Timings t;
  const auto t0 = std::chrono::steady_clock::now();
  auto ls = bake::LevelSet::load(o.mesh, {.grid = o.grid});
  if (!ls && ls.error().code == Code::kInvalidArgument) {  // --grid names no grid of the file
    cli::usageError(kProg, ls.error().message);
    return cli::kExitUsage;
  }
  if (!ls) return cli::reportError(kProg, o.mesh, ls.error());
  t.load = secondsSince(t0);
  const bake::LevelSetInfo& info = ls->info();
  auto field = bake::describeLevelSetBake(*ls, bo);
  uint64_t payload = 0;
  if (auto rc = checkPlan(field, wo.layout, &payload)) return *rc;
  wo.metadataJson = levelSetMetadata(o, bo, info);
  // The writer creates its temporary file now, so an unwritable destination fails before baking.
  removeStaleTemporaries(o.output);
  auto writer = Writer::create(o.output, *field, wo);
  if (!writer) return cli::reportError(kProg, o.output, writer.error());
  removeTemporaryOnSignal(o.output);

  cli::Progress progress(kProg, !o.quiet && !o.json && isatty(2), uint64_t(o.mapSize) * o.mapSize);
  bo.progress = [&](uint64_t d, uint64_t total) { progress.update(d, total); };
  auto baked = bake::bakeLevelSet(*ls, bo);
  if (!baked) return cli::reportError(kProg, o.mesh, baked.error());
  if (auto rc = writeBaked(o, o.output, *writer, *baked, &t.write, &t.fileBytes)) return *rc;
  reportLevelSetBake(o, bo, info, *field, baked->stats, payload, t);
  return cli::kExitSuccess;
}

}  // namespace vff::bake_tool
