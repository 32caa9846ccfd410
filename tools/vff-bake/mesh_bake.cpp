// mesh_bake.cpp - vff-bake from a triangle mesh with Embree, and --benchmark: Embree's raw
// throughput on exactly the bake's rays against the whole bake.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>

#include "bake.h"
#include "cli.h"
#include "platform/parallel.h"
#include "vff/bake/mesh.h"

namespace vff::bake_tool {

namespace {

// The distance of the mesh's farthest vertex from the sphere's centre.
double farthestVertex(const bake::Mesh& mesh, const Sphere& s) {
  double far2 = 0;
  for (size_t i = 0; i < mesh.positions.size(); i += 3) {
    const double dx = double(mesh.positions[i]) - s.center[0], dy = double(mesh.positions[i + 1]) - s.center[1],
                 dz = double(mesh.positions[i + 2]) - s.center[2];
    far2 = std::max(far2, dx * dx + dy * dy + dz * dz);
  }
  return std::sqrt(far2);
}

// A --center/--radius sphere must enclose every vertex (distances past it would be clamped into
// the last code): a usage error, unless --allow-clipped-sphere says it is meant, then a warning.
// *clipped: the sphere cuts the mesh. Returns the exit code of a refusal.
std::optional<int> checkUserSphere(const Options& o, const bake::BakeOptions& bo, const bake::Mesh& mesh,
                                   bool* clipped) {
  *clipped = false;
  if (!bo.sphere) return std::nullopt;
  const double far = farthestVertex(mesh, *bo.sphere);
  if (far <= double(bo.sphere->radius)) return std::nullopt;
  auto number = [](double v) {
    char s[32];
    std::snprintf(s, sizeof s, "%.9g", v);
    return std::string(s);
  };
  const std::string what = "the sphere of radius " + number(bo.sphere->radius) + " does not enclose " + o.mesh +
                           ": its farthest vertex is " + number(far) + " from the centre";
  if (!o.allowClippedSphere) {
    cli::usageError(kProg, what + " (a larger --radius, or --allow-clipped-sphere if this is meant)");
    return cli::kExitUsage;
  }
  std::fprintf(stderr, "%s: warning: %s; distances past the sphere are clamped (--allow-clipped-sphere)\n", kProg,
               what.c_str());
  *clipped = true;
  return std::nullopt;
}

// What a mesh bake measured, for the report.
struct Measures {
  double load = 0, build = 0, raw = 0, bake = 0, write = 0;  // seconds (raw, bake: best of --repeat)
  uint64_t fileBytes = 0;
  uint64_t payload = 0;
};

// The --benchmark table on stdout.
void printBenchmark(const Options& o, const bake::Mesh& mesh, const FieldDesc& field, double rays, const Measures& m,
                    double payloadMiB, double meshMiB, double bvhMiB) {
  std::printf("mesh            %s: %s\n", o.mesh.c_str(), cli::count(mesh.triangleCount(), "triangle").c_str());
  std::printf("rays            %u maps x %ux%u = %.0f rays, %u threads\n", field.mapCount, field.mapResolution,
              field.mapResolution, rays, parallel::resolveThreads(o.threads));
  std::printf("embree raw      %8.3f s  %7.2f Mrays/s   (rtcIntersect16, same rays, nothing stored)\n", m.raw,
              rays / m.raw / 1e6);
  std::printf("bake            %8.3f s  %7.2f Mrays/s   (trace + encode%s)\n", m.bake, rays / m.bake / 1e6,
              o.normals ? " + normals" : "");
  std::printf("ratio           %8.3f    (bake throughput / raw throughput; target >= 0.9)\n", m.raw / m.bake);
  std::printf("peak memory     %8.1f MiB (budget: payload %.1f + mesh %.1f + BVH %.1f + 64 = %.1f MiB)\n",
              peakRssMiB(), payloadMiB, meshMiB, bvhMiB, payloadMiB + meshMiB + bvhMiB + 64.0);
}

// The --json summary or the --benchmark table on stdout, or the one-line report on stderr (not
// with --quiet).
void reportMeshBake(const Options& o, const bake::BakeOptions& bo, const bake::Mesh& mesh, const bake::Scene& scene,
                    const FieldDesc& field, const bake::BakeStats& s, const Measures& m, bool wrote) {
  const double rays = double(s.rays);
  const double meshMiB =
      double(mesh.positions.size() * 4 + mesh.normals.size() * 4 + mesh.indices.size() * 4) / 1048576.0;
  const double bvhMiB = double(scene.embreeBytes()) / 1048576.0;
  const double payloadMiB = double(m.payload) / 1048576.0;
  nlohmann::json summary = bakeSummary(bo, field, s, m.payload, m.bake);
  summary.update({{"mesh", o.mesh},
                  {"vertices", mesh.vertexCount()},
                  {"triangles", mesh.triangleCount()},
                  {"droppedDegenerate", mesh.droppedDegenerate},
                  {"seconds", {{"load", m.load}, {"build", m.build}, {"bake", m.bake}, {"write", m.write}}},
                  {"meshMiB", meshMiB},
                  {"bvhMiB", bvhMiB}});
  if (!o.mapRange.empty()) summary["mapRange"] = {bo.mapBegin, bo.mapEnd};  // the maps baked, [begin, end)
  if (wrote) {
    summary["output"] = o.output;
    summary["fileBytes"] = m.fileBytes;
  }
  if (o.benchmark) {
    summary["benchmark"] = {{"embreeRaysPerSecond", rays / m.raw},
                            {"bakeRaysPerSecond", rays / m.bake},
                            {"ratio", m.raw / m.bake},
                            {"memoryBudgetMiB", payloadMiB + meshMiB + bvhMiB + 64.0}};
  }
  if (o.json) {
    std::printf("%s\n", summary.dump(2).c_str());
  } else if (o.benchmark) {
    printBenchmark(o, mesh, field, rays, m, payloadMiB, meshMiB, bvhMiB);
  } else if (!o.quiet) {
    const std::string maps = o.mapRange.empty() ? std::to_string(field.mapCount)
                                                : std::to_string(bo.mapEnd - bo.mapBegin) + " (" + o.mapRange + " of " +
                                                      std::to_string(field.mapCount) + ")";
    std::fprintf(stderr, "%s: %s: %s maps of %ux%u (%.0f rays, %.1f%% hits) in %.2f s (%.1f Mrays/s), %.3f MiB payload -> %s\n",
                 kProg, o.mesh.c_str(), maps.c_str(), field.mapResolution, field.mapResolution, rays,
                 100.0 * double(s.hits) / rays, m.bake, rays / m.bake / 1e6, payloadMiB, o.output.c_str());
  }
}

// Traces and bakes (--repeat times each with --benchmark, keeping the best times in *m); the
// field of the last bake, or the exit code of a failure.
std::optional<int> traceAndBake(const Options& o, bake::BakeOptions bo, const bake::Scene& scene, Measures* m,
                                std::optional<bake::BakedField>* baked) {
  if (o.benchmark) {
    for (int r = 0; r < o.repeat; ++r) {
      auto st = bake::traceOnly(scene, bo);
      if (!st) return cli::reportError(kProg, o.mesh, st.error());
      m->raw = r == 0 ? st->seconds : std::min(m->raw, st->seconds);
    }
  }
  cli::Progress progress(kProg, !o.quiet && !o.json && !o.benchmark && isatty(2), uint64_t(o.mapSize) * o.mapSize);
  bo.progress = [&](uint64_t d, uint64_t t) { progress.update(d, t); };
  for (int r = 0; r < (o.benchmark ? o.repeat : 1); ++r) {
    auto b = bake::bakeField(scene, bo);
    if (!b) return cli::reportError(kProg, o.mesh, b.error());
    m->bake = r == 0 ? b->stats.seconds : std::min(m->bake, b->stats.seconds);
    baked->emplace(std::move(*b));
  }
  return std::nullopt;
}

}  // namespace

// A user sphere that cuts the mesh is recorded (`clipped`); other files keep their bytes.
std::string meshMetadata(const Options& o, const bake::BakeOptions& bo, const bake::Mesh& mesh,
                         const bake::MeshInfo& info, bool clipped, const nlohmann::json& gltf) {
  nlohmann::json meta = {
      {"vff.generator", "vff-bake"},
      {"vff.generatorVersion", kLibraryVersion},
      {"vff.source", {{"name", baseName(o.mesh)}, {"format", info.format}, {"xxh3", cli::hexDigits64(bake::meshHash(mesh))},
                      {"geometryHash", cli::hexDigits64(bake::geometryHash(mesh))},
                      {"vertices", mesh.vertexCount()}, {"triangles", mesh.triangleCount()}}},
      {"vff.bake", {{"rayOrigin", "texel centre"}, {"sphere", bo.sphere ? "user" : "minimal-enclosing"},
                    {"twoSided", true}, {"normals", o.normals ? (mesh.normals.empty() ? "geometric" : "interpolated") : "none"}}}};
  if (clipped) meta["vff.bake"]["sphereEnclosesMesh"] = false;
  if (!gltf.is_null()) meta["vff.source"]["gltf"] = gltf;
  return meta.dump();
}

int reportLoadError(const Error& e, const std::string& input) {
  if (e.code == Code::kInvalidArgument) {  // a --scene the file does not have
    cli::usageError(kProg, e.message);
    return cli::kExitUsage;
  }
  return cli::reportError(kProg, input, e);
}

void noteUnbakedScenes(const Options& o, const bake::MeshInfo& info) {
  // What the bake leaves out of a glTF file (geometry-free extensions, skins, morph targets) is a
  // warning, printed even with --quiet: the field is not what an engine showing the file animates.
  for (const std::string& note : info.gltfNotes)
    std::fprintf(stderr, "%s: warning: %s: %s\n", kProg, o.mesh.c_str(), note.c_str());
  if (o.quiet || info.gltfScenes.size() < 2) return;
  std::string others;
  for (size_t i = 0; i < info.gltfScenes.size(); ++i) {
    if (int(i) == info.gltfScene) continue;
    others += (others.empty() ? "" : ", ") + std::to_string(i);
    if (!info.gltfScenes[i].empty()) others += " '" + info.gltfScenes[i] + "'";
  }
  const std::string& name = info.gltfScenes[size_t(info.gltfScene)];
  std::fprintf(stderr, "%s: note: %s has %zu scenes; baked scene %d%s; not baked: %s (--scene N bakes another)\n",
               kProg, o.mesh.c_str(), info.gltfScenes.size(), info.gltfScene,
               name.empty() ? "" : (" '" + name + "'").c_str(), others.c_str());
}

int bakeFromMesh(const Options& o, bake::BakeOptions bo, WriteOptions wo) {
  // Load and check the mesh, then the parameters, before any output exists.
  Measures m;
  bake::MeshInfo info;
  auto t0 = std::chrono::steady_clock::now();
  auto mesh = bake::loadMesh(o.mesh, &info, {.gltfScene = o.scene});
  if (!mesh) return reportLoadError(mesh.error(), o.mesh);
  noteUnbakedScenes(o, info);
  m.load = secondsSince(t0);
  if (mesh->droppedDegenerate && !o.quiet)
    std::fprintf(stderr, "%s: %s: dropped %llu degenerate (zero-area) triangle%s\n", kProg, o.mesh.c_str(),
                 static_cast<unsigned long long>(mesh->droppedDegenerate), mesh->droppedDegenerate == 1 ? "" : "s");
  auto field = bake::describeBake(*mesh, bo);
  if (auto rc = checkPlan(field, wo.layout, &m.payload)) return *rc;
  bool clipped = false;
  if (auto rc = checkUserSphere(o, bo, *mesh, &clipped)) return *rc;
  std::optional<MapRange> range;
  if (!o.mapRange.empty()) {
    range = parseMapRange(o.mapRange);  // checkOptions made sure it parses
    if (auto rc = checkMapRange(*range, field->mapCount)) return *rc;
    bo.mapBegin = range->begin;
    bo.mapEnd = range->end;
  }

  // The writer creates its temporary file now, so an unwritable destination fails before baking.
  std::optional<Writer> writer;
  wo.metadataJson = meshMetadata(o, bo, *mesh, info, clipped);
  if (range) {
    wo.metadataJson = partialMetadata(wo.metadataJson, wo, *range, field->mapCount);
    wo = partialWriteOptions(wo);
  }
  if (!o.output.empty()) {
    removeStaleTemporaries(o.output);
    auto w = Writer::create(o.output, *field, wo);
    if (!w) return cli::reportError(kProg, o.output, w.error());
    writer.emplace(std::move(*w));
    removeTemporaryOnSignal(o.output);
  }

  t0 = std::chrono::steady_clock::now();
  auto scene = bake::Scene::create(*mesh, o.threads);
  if (!scene) return cli::reportError(kProg, o.mesh, scene.error());
  m.build = secondsSince(t0);

  std::optional<bake::BakedField> baked;
  if (auto rc = traceAndBake(o, bo, *scene, &m, &baked)) return *rc;
  if (writer && range) {
    if (auto rc = writePartial(o, *writer, *field, *range, *baked, &m.write, &m.fileBytes)) return *rc;
  } else if (writer) {
    if (o.refine) {
      t0 = std::chrono::steady_clock::now();
      auto r = makeRefinement(*field, baked->distance, mesh->positions, mesh->indices,
                              {.probe = o.refineProbe, .threads = o.threads});
      if (!r) return cli::reportError(kProg, o.mesh, r.error());
      if (Status st = writer->setRefinement(r->view()); !st) return cli::reportError(kProg, o.output, st.error());
      if (!o.quiet)
        std::fprintf(stderr, "%s: refined: %u of %llu texels unsure (%.2f%%), %zu vertices and %zu triangles for the "
                             "exact step, in %.2f s\n",
                     kProg, r->unsureTexels, static_cast<unsigned long long>(uint64_t(field->mapCount) *
                                                                             field->mapResolution * field->mapResolution),
                     100.0 * r->unsureTexels / (double(field->mapCount) * field->mapResolution * field->mapResolution),
                     mesh->vertexCount(), mesh->triangleCount(), secondsSince(t0));
    }
    if (auto rc = writeBaked(o, o.output, *writer, *baked, &m.write, &m.fileBytes)) return *rc;
  }
  reportMeshBake(o, bo, *mesh, *scene, *field, baked->stats, m, writer.has_value());
  return cli::kExitSuccess;
}

}  // namespace vff::bake_tool
