// vff-bake: bakes a visibility field from a triangle mesh with Embree.
//
//   vff-bake mesh.obj -o field.vff          the paper's configuration: 4226 maps of 64x64, 8 bits, 2R
//   vff-bake mesh.glb -o f.vff --normals --encoding unorm16-diameter --codec zstd
//   vff-bake mesh.obj --benchmark           Embree's raw throughput on the bake's rays vs the bake
//   vff-bake shape.vdb -o f.vff [--grid NAME]   from an OpenVDB level set (vff/bake/levelset.h)
#include <sys/resource.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <cctype>
#include <optional>
#include <thread>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <map>
#include <mutex>

#include "cli.h"
#include "vff/bake/baker.h"
#include "vff/bake/levelset.h"
#include "vff/bake/mesh.h"
#include "vff/vff.h"

namespace {

using vff::bake::BakeOptions;

const char* kProg = "vff-bake";

struct Options {
  std::string mesh;
  std::string output;
  std::string grid;  // .vdb input: the level set grid to bake (empty: the first)
  std::string positions = "octa-hemi2";
  uint32_t count = 0;  // 0: the scheme's default
  uint32_t mapSize = 64;
  std::string directions = "concentric";
  std::string encoding = "unorm8-diameter";
  bool normals = false;
  unsigned threads = 0;
  std::vector<float> center;
  float radius = 0;
  std::string codec = "stored";
  int zstdLevel = 19;
  uint32_t mapsPerBlock = 0;
  std::string target = "2d-array";
  uint32_t maxTextureSize = 2048;
  uint32_t maxLayers = 2048;
  uint32_t gutter = 0;
  bool json = false;
  bool quiet = false;
  bool benchmark = false;
  int repeat = 3;
};

const std::map<std::string, vff::PositionScheme> kPositions = {
    {"octa-hemi2", vff::PositionScheme::kOctaHemi2},
    {"ea-octa-grid", vff::PositionScheme::kEqualAreaOctaGrid},
    {"fibonacci", vff::PositionScheme::kSphericalFibonacci}};
const std::map<std::string, vff::DirectionScheme> kDirections = {
    {"concentric", vff::DirectionScheme::kConcentricEqualArea}, {"hemi-oct", vff::DirectionScheme::kHemiOctahedral}};
const std::map<std::string, vff::DistanceEncoding> kEncodings = {
    {"unorm8-diameter", vff::DistanceEncoding::kUnorm8Diameter},
    {"unorm8-chord", vff::DistanceEncoding::kUnorm8Chord},
    {"unorm16-diameter", vff::DistanceEncoding::kUnorm16Diameter},
    {"bit1", vff::DistanceEncoding::kBit1},
    {"bc4-diameter", vff::DistanceEncoding::kBc4Diameter}};
const std::map<std::string, vff::Codec> kCodecs = {{"stored", vff::Codec::kStored}, {"zstd", vff::Codec::kZstd}};
const std::map<std::string, vff::LayoutTarget> kTargets = {{"2d-array", vff::LayoutTarget::kTexture2DArray},
                                                           {"3d", vff::LayoutTarget::kTexture3D}};

uint32_t defaultCount(vff::PositionScheme s) {
  switch (s) {
    case vff::PositionScheme::kEqualAreaOctaGrid: return 65;    // 4225 maps
    case vff::PositionScheme::kSphericalFibonacci: return 4226;
    default: return 32;                                          // 4226 maps
  }
}

std::string baseName(const std::string& p) {
  const size_t s = p.find_last_of('/');
  return s == std::string::npos ? p : p.substr(s + 1);
}

double peakRssMiB() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return double(ru.ru_maxrss) / 1024.0;  // ru_maxrss is in KiB on Linux
}

// A progress line on stderr, redrawn at most 10 times a second, only on a terminal.
class Progress {
 public:
  Progress(bool enabled, uint64_t raysPerMap) : enabled_(enabled), raysPerMap_(raysPerMap) {}
  void update(uint64_t done, uint64_t total) {
    if (!enabled_) return;
    const auto now = std::chrono::steady_clock::now();
    std::lock_guard<std::mutex> lock(mu_);
    if (done != total && now - last_ < std::chrono::milliseconds(100)) return;
    last_ = now;
    const double secs = std::chrono::duration<double>(now - start_).count();
    const double rate = secs > 0 ? double(done * raysPerMap_) / secs : 0;
    const double eta = done ? secs * double(total - done) / double(done) : 0;
    std::fprintf(stderr, "\r%s: %" PRIu64 "/%" PRIu64 " maps, %.1f Mrays/s, ETA %.1f s   ", kProg, done, total,
                 rate / 1e6, eta);
    if (done == total) std::fputc('\n', stderr);
    std::fflush(stderr);
  }

 private:
  bool enabled_;
  uint64_t raysPerMap_;
  std::mutex mu_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now(), last_{};
};

// The --json keys every bake reports (the callers add their input's and timing keys).
nlohmann::json bakeSummary(const Options& o, const BakeOptions& bo, const vff::FieldDesc& field,
                           const vff::bake::BakeStats& s, uint64_t payload, double bakeSeconds) {
  const double rays = double(s.rays);
  return {{"sphere", {{"center", {field.sphere.center[0], field.sphere.center[1], field.sphere.center[2]}},
                      {"radius", field.sphere.radius}}},
          {"positions", o.positions},
          {"positionParam", bo.positionParam},
          {"maps", field.mapCount},
          {"mapResolution", field.mapResolution},
          {"encoding", o.encoding},
          {"normals", o.normals},
          {"rays", s.rays},
          {"hits", s.hits},
          {"hitRatio", rays > 0 ? double(s.hits) / rays : 0.0},
          {"payloadBytes", payload},
          {"raysPerSecond", bakeSeconds > 0 ? rays / bakeSeconds : 0.0},
          {"peakRssMiB", peakRssMiB()}};
}

bool isVdbPath(const std::string& p) {
  if (p.size() < 4) return false;
  std::string ext = p.substr(p.size() - 4);
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return ext == ".vdb";
}

// Bakes from an OpenVDB level set (vff/bake/levelset.h): the field, layout, output and checks of a
// mesh bake; the metadata and the summary describe the grid instead of triangles.
int bakeFromLevelSet(const Options& o, BakeOptions bo, vff::WriteOptions wo) {
  auto t0 = std::chrono::steady_clock::now();
  auto ls = vff::bake::LevelSet::load(o.mesh, {.grid = o.grid});
  if (!ls && ls.error().code == vff::Code::kInvalidArgument) {  // --grid names no grid of the file
    vff::cli::usageError(kProg, ls.error().message);
    return vff::cli::kExitUsage;
  }
  if (!ls) return vff::cli::reportError(kProg, o.mesh, ls.error());
  const double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const vff::bake::LevelSetInfo& info = ls->info();
  auto field = vff::bake::describeLevelSetBake(*ls, bo);
  if (!field) {
    vff::cli::usageError(kProg, field.error().message);
    return vff::cli::kExitUsage;
  }
  if (auto layout = vff::computeLayout(*field, wo.layout); !layout) {
    vff::cli::usageError(kProg, layout.error().message);
    return vff::cli::kExitUsage;
  }
  const uint64_t payload = field->mapCount * (vff::distanceMapBytes(field->distanceEncoding, field->mapResolution) +
                                              vff::normalMapBytes(field->normalEncoding, field->mapResolution));
  if (payload > (uint64_t{16} << 30)) {
    vff::cli::usageError(kProg, "the field would hold " + std::to_string(payload) +
                                    " bytes, above the baker's 16 GiB limit: fewer maps or a smaller --map-size");
    return vff::cli::kExitUsage;
  }
  // vff.source.xxh3 of a level set is the XXH3-64 of the .vdb file's bytes (a mesh's hashes its
  // positions and indices); the sphere is the user's or the one around the active voxels' bounds.
  nlohmann::json meta = {
      {"vff.generator", "vff-bake"},
      {"vff.generatorVersion", vff::kLibraryVersion},
      {"vff.source", {{"name", baseName(o.mesh)}, {"format", "vdb"}, {"grid", info.grid},
                      {"activeVoxels", info.activeVoxels}, {"xxh3", vff::cli::hexDigits64(info.fileXxh3)}}},
      {"vff.bake", {{"rayOrigin", "texel centre"}, {"sphere", bo.sphere ? "user" : "active-voxel-bounds"},
                    {"surface", "level set zero crossing"}, {"twoSided", true},
                    {"normals", o.normals ? "gradient" : "none"}}}};
  wo.metadataJson = meta.dump();
  // The writer creates its temporary file now, so an unwritable destination fails before baking.
  auto writer = vff::Writer::create(o.output, *field, wo);
  if (!writer) return vff::cli::reportError(kProg, o.output, writer.error());

  Progress progress(!o.quiet && !o.json && isatty(2), uint64_t(o.mapSize) * o.mapSize);
  bo.progress = [&](uint64_t d, uint64_t t) { progress.update(d, t); };
  auto baked = vff::bake::bakeLevelSet(*ls, bo);
  if (!baked) return vff::cli::reportError(kProg, o.mesh, baked.error());
  t0 = std::chrono::steady_clock::now();
  vff::Status st = writer->writeMaps(vff::Plane::kDistance, baked->distance);
  if (st && o.normals) st = writer->writeMaps(vff::Plane::kNormal, baked->normals);
  if (st) st = writer->finish();
  if (!st) return vff::cli::reportError(kProg, o.output, st.error());
  const double writeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  uint64_t fileBytes = 0;
  if (auto f = vff::File::open(o.output, {.checksums = vff::ChecksumPolicy::kNone})) fileBytes = f->info().fileSize;

  const vff::bake::BakeStats& s = baked->stats;
  const double rays = double(s.rays);
  if (o.json) {
    nlohmann::json summary = bakeSummary(o, bo, *field, s, payload, s.seconds);
    summary.update({{"input", o.mesh},
                    {"grid", info.grid},
                    {"activeVoxels", info.activeVoxels},
                    {"voxelSize", info.voxelSize},
                    {"seconds", {{"load", loadSeconds}, {"bake", s.seconds}, {"write", writeSeconds}}},
                    {"output", o.output},
                    {"fileBytes", fileBytes}});
    std::printf("%s\n", summary.dump(2).c_str());
  } else if (!o.quiet) {
    std::fprintf(stderr,
                 "%s: %s: grid \"%s\" (%" PRIu64 " active voxels of %g): %u maps of %ux%u (%.0f rays, %.1f%% hits) "
                 "in %.2f s (%.1f Mrays/s), %.3f MiB payload -> %s\n",
                 kProg, o.mesh.c_str(), info.grid.c_str(), info.activeVoxels, info.voxelSize, field->mapCount,
                 field->mapResolution, field->mapResolution, rays, 100.0 * double(s.hits) / rays, s.seconds,
                 rays / s.seconds / 1e6, double(payload) / 1048576.0, o.output.c_str());
  }
  return vff::cli::kExitSuccess;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App app{"Bakes a precomputed 4D visibility field (.vff) from a triangle mesh with Embree, or from an\n"
               "OpenVDB level set (rays intersected with its zero crossing, normals from its gradient).\n"
               "Inputs: .obj .ply .off .stl (OpenMesh), .gltf .glb (tinygltf), .vdb (OpenVDB: the first float\n"
               "grid of class level set by name, as vdb_print lists them, or --grid NAME; default sphere: the\n"
               "one around the active voxels' bounding box).\n" +
               vff::cli::exitCodeHelp()};
  vff::cli::addVersionFlag(app, kProg);
  app.add_option("mesh", o.mesh, "input mesh, or OpenVDB level set (.vdb)")->required();
  app.add_option("-o,--output", o.output, "output .vff file (written atomically)");
  app.add_option("--grid", o.grid, ".vdb input: name of the level set grid to bake (default: the first level set by name)");
  app.add_option("--positions", o.positions, "positional-sample scheme")
      ->check(CLI::IsMember({"octa-hemi2", "ea-octa-grid", "fibonacci"}))->capture_default_str();
  app.add_option("-n,--count", o.count,
                 "scheme parameter: octa-hemi2 n (maps = 2(2n^2+2n+1), default 32 = 4226 maps), "
                 "ea-octa-grid n (n^2 maps, default 65), fibonacci N (default 4226)")
      ->check(CLI::PositiveNumber);
  app.add_option("-m,--map-size", o.mapSize, "map resolution M (M x M rays per sample)")->capture_default_str()
      ->check(CLI::Range(1u, 4096u));
  app.add_option("--directions", o.directions, "hemisphere-to-square map")
      ->check(CLI::IsMember({"concentric", "hemi-oct"}))->capture_default_str();
  app.add_option("--encoding", o.encoding, "distance encoding")
      ->check(CLI::IsMember({"unorm8-diameter", "unorm8-chord", "unorm16-diameter", "bit1", "bc4-diameter"}))->capture_default_str();
  app.add_flag("--normals", o.normals, "also store the surface normal at each hit (4 bytes per ray)");
  app.add_option("-j,--threads", o.threads, "baking threads (0: all cores); the output does not depend on it")
      ->capture_default_str();
  app.add_option("--center", o.center, "bounding-sphere centre x y z (default: minimal enclosing sphere)")
      ->expected(3);
  app.add_option("--radius", o.radius, "bounding-sphere radius (with --center)");
  app.add_option("--codec", o.codec, "block codec")->check(CLI::IsMember({"stored", "zstd"}))->capture_default_str();
  app.add_option("--zstd-level", o.zstdLevel, "zstd level")->check(CLI::Range(1, 22))->capture_default_str();
  app.add_option("--maps-per-block", o.mapsPerBlock, "maps per block (0: about 256 KiB per block)");
  app.add_option("--target", o.target, "GPU texture target of the packed layout")
      ->check(CLI::IsMember({"2d-array", "3d"}))->capture_default_str();
  app.add_option("--max-texture-size", o.maxTextureSize, "GPU limit: largest slice width/height")
      ->capture_default_str()->check(CLI::Range(1u, 65536u));
  app.add_option("--max-layers", o.maxLayers, "GPU limit: most array layers / 3D depth")
      ->capture_default_str()->check(CLI::Range(1u, 65536u));
  app.add_option("--gutter", o.gutter, "texels of edge replication around each tile")->capture_default_str()
      ->check(CLI::Range(0u, 64u));
  app.add_flag("--json", o.json, "print a machine-readable summary on stdout");
  app.add_flag("-q,--quiet", o.quiet, "no progress output");
  app.add_flag("--benchmark", o.benchmark,
               "measure Embree's raw throughput on exactly the bake's rays against the whole bake, and print both");
  app.add_option("--repeat", o.repeat, "benchmark repetitions (best is reported)")->check(CLI::Range(1, 100));
  if (auto rc = vff::cli::parse(app, kProg, argc, argv)) return *rc;
  if (o.output.empty() && !o.benchmark) {
    vff::cli::usageError(kProg, "an output file is required (-o FILE), unless --benchmark is given");
    return vff::cli::kExitUsage;
  }
  if ((!o.center.empty()) != (o.radius > 0)) {
    vff::cli::usageError(kProg, "--center and --radius go together (radius > 0)");
    return vff::cli::kExitUsage;
  }

  BakeOptions bo;
  bo.positionScheme = kPositions.at(o.positions);
  bo.positionParam = o.count ? o.count : defaultCount(bo.positionScheme);
  bo.directionScheme = kDirections.at(o.directions);
  bo.mapResolution = o.mapSize;
  bo.encoding = kEncodings.at(o.encoding);
  bo.normals = o.normals;
  bo.threads = o.threads;
  if (!o.center.empty()) bo.sphere = vff::Sphere{{o.center[0], o.center[1], o.center[2]}, o.radius};

  vff::WriteOptions wo;
  wo.codec = kCodecs.at(o.codec);
  wo.zstdLevel = o.zstdLevel;
  wo.mapsPerBlock = o.mapsPerBlock;
  wo.layout.target = kTargets.at(o.target);
  wo.layout.maxTextureSize = o.maxTextureSize;
  wo.layout.maxLayers = o.maxLayers;
  wo.layout.gutter = o.gutter;

  if (isVdbPath(o.mesh)) {
    if (o.benchmark) {
      vff::cli::usageError(kProg, "--benchmark measures Embree on a mesh; it does not apply to a .vdb level set");
      return vff::cli::kExitUsage;
    }
    return bakeFromLevelSet(o, bo, wo);
  }
  if (!o.grid.empty()) {
    vff::cli::usageError(kProg, "--grid applies to a .vdb level set input only");
    return vff::cli::kExitUsage;
  }

  // Load and check the mesh, then the parameters, before any output exists.
  vff::bake::MeshInfo info;
  auto t0 = std::chrono::steady_clock::now();
  auto mesh = vff::bake::loadMesh(o.mesh, &info);
  if (!mesh) return vff::cli::reportError(kProg, o.mesh, mesh.error());
  const double loadSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  auto field = vff::bake::describeBake(*mesh, bo);
  if (!field) {
    vff::cli::usageError(kProg, field.error().message);
    return vff::cli::kExitUsage;
  }
  if (auto layout = vff::computeLayout(*field, wo.layout); !layout) {
    vff::cli::usageError(kProg, layout.error().message);
    return vff::cli::kExitUsage;
  }
  const uint64_t payload =
      field->mapCount * (vff::distanceMapBytes(field->distanceEncoding, field->mapResolution) +
                         vff::normalMapBytes(field->normalEncoding, field->mapResolution));
  if (payload > (uint64_t{16} << 30)) {
    vff::cli::usageError(kProg, "the field would hold " + std::to_string(payload) +
                                    " bytes, above the baker's 16 GiB limit: fewer maps or a smaller --map-size");
    return vff::cli::kExitUsage;
  }

  // The writer creates its temporary file now, so an unwritable destination fails before baking.
  std::optional<vff::Writer> writer;
  nlohmann::json meta = {
      {"vff.generator", "vff-bake"},
      {"vff.generatorVersion", vff::kLibraryVersion},
      {"vff.source", {{"name", baseName(o.mesh)}, {"format", info.format}, {"xxh3", vff::cli::hexDigits64(vff::bake::meshHash(*mesh))},
                      {"vertices", mesh->vertexCount()}, {"triangles", mesh->triangleCount()}}},
      {"vff.bake", {{"rayOrigin", "texel centre"}, {"sphere", bo.sphere ? "user" : "minimal-enclosing"},
                    {"twoSided", true}, {"normals", o.normals ? (mesh->normals.empty() ? "geometric" : "interpolated") : "none"}}}};
  wo.metadataJson = meta.dump();
  if (!o.output.empty()) {
    auto w = vff::Writer::create(o.output, *field, wo);
    if (!w) return vff::cli::reportError(kProg, o.output, w.error());
    writer.emplace(std::move(*w));
  }

  t0 = std::chrono::steady_clock::now();
  auto scene = vff::bake::Scene::create(*mesh, o.threads);
  if (!scene) return vff::cli::reportError(kProg, o.mesh, scene.error());
  const double buildSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();

  double rawBest = 0;
  if (o.benchmark) {
    for (int r = 0; r < o.repeat; ++r) {
      auto st = vff::bake::traceOnly(*scene, bo);
      if (!st) return vff::cli::reportError(kProg, o.mesh, st.error());
      rawBest = r == 0 ? st->seconds : std::min(rawBest, st->seconds);
    }
  }
  Progress progress(!o.quiet && !o.json && !o.benchmark && isatty(2), uint64_t(o.mapSize) * o.mapSize);
  bo.progress = [&](uint64_t d, uint64_t t) { progress.update(d, t); };
  std::optional<vff::bake::BakedField> baked;
  double bakeBest = 0;
  for (int r = 0; r < (o.benchmark ? o.repeat : 1); ++r) {
    auto b = vff::bake::bakeField(*scene, bo);
    if (!b) return vff::cli::reportError(kProg, o.mesh, b.error());
    bakeBest = r == 0 ? b->stats.seconds : std::min(bakeBest, b->stats.seconds);
    baked.emplace(std::move(*b));
  }

  double writeSeconds = 0;
  uint64_t fileBytes = 0;
  if (writer) {
    t0 = std::chrono::steady_clock::now();
    vff::Status st = writer->writeMaps(vff::Plane::kDistance, baked->distance);
    if (st && o.normals) st = writer->writeMaps(vff::Plane::kNormal, baked->normals);
    if (st) st = writer->finish();
    if (!st) return vff::cli::reportError(kProg, o.output, st.error());
    writeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (auto f = vff::File::open(o.output, {.checksums = vff::ChecksumPolicy::kNone})) fileBytes = f->info().fileSize;
  }

  const vff::bake::BakeStats& s = baked->stats;
  const double rays = double(s.rays);
  const double meshMiB = double(mesh->positions.size() * 4 + mesh->normals.size() * 4 + mesh->indices.size() * 4) / 1048576.0;
  const double bvhMiB = double(scene->embreeBytes()) / 1048576.0;
  const double payloadMiB = double(payload) / 1048576.0;
  nlohmann::json summary = bakeSummary(o, bo, *field, s, payload, bakeBest);
  summary.update({{"mesh", o.mesh},
                  {"vertices", mesh->vertexCount()},
                  {"triangles", mesh->triangleCount()},
                  {"droppedDegenerate", mesh->droppedDegenerate},
                  {"seconds", {{"load", loadSeconds}, {"build", buildSeconds}, {"bake", bakeBest}, {"write", writeSeconds}}},
                  {"meshMiB", meshMiB},
                  {"bvhMiB", bvhMiB}});
  if (writer) {
    summary["output"] = o.output;
    summary["fileBytes"] = fileBytes;
  }
  if (o.benchmark) {
    summary["benchmark"] = {{"embreeRaysPerSecond", rays / rawBest},
                            {"bakeRaysPerSecond", rays / bakeBest},
                            {"ratio", rawBest / bakeBest},
                            {"memoryBudgetMiB", payloadMiB + meshMiB + bvhMiB + 64.0}};
  }
  if (o.json) {
    std::printf("%s\n", summary.dump(2).c_str());
  } else if (o.benchmark) {
    std::printf("mesh            %s: %zu triangles\n", o.mesh.c_str(), mesh->triangleCount());
    std::printf("rays            %u maps x %ux%u = %.0f rays, %u threads\n", field->mapCount, field->mapResolution,
                field->mapResolution, rays, o.threads ? o.threads : std::thread::hardware_concurrency());
    std::printf("embree raw      %8.3f s  %7.2f Mrays/s   (rtcIntersect16, same rays, nothing stored)\n", rawBest,
                rays / rawBest / 1e6);
    std::printf("bake            %8.3f s  %7.2f Mrays/s   (trace + encode%s)\n", bakeBest, rays / bakeBest / 1e6,
                o.normals ? " + normals" : "");
    std::printf("ratio           %8.3f    (bake throughput / raw throughput; target >= 0.9)\n", rawBest / bakeBest);
    std::printf("peak memory     %8.1f MiB (budget: payload %.1f + mesh %.1f + BVH %.1f + 64 = %.1f MiB)\n",
                peakRssMiB(), payloadMiB, meshMiB, bvhMiB, payloadMiB + meshMiB + bvhMiB + 64.0);
  } else if (!o.quiet) {
    std::fprintf(stderr, "%s: %s: %u maps of %ux%u (%.0f rays, %.1f%% hits) in %.2f s (%.1f Mrays/s), %.3f MiB payload -> %s\n",
                 kProg, o.mesh.c_str(), field->mapCount, field->mapResolution, field->mapResolution, rays,
                 100.0 * double(s.hits) / rays, bakeBest, rays / bakeBest / 1e6, payloadMiB, o.output.c_str());
  }
  return vff::cli::kExitSuccess;
}
