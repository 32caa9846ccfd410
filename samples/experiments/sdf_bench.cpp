// sdf_bench.cpp - the field against its production peer at equal memory: vff-experiments sdf-bench.
//
// For each mesh (--mesh, then every --object) and each memory per object (--sdf-memory MiB: the
// field configuration of octa-hemi2 n = 32 whose payload is nearest, power-of-two maps, n = 64
// above 64 x 64; or the --config list), the distance field is built at the field's payload bytes
// (sdf_field.h: its bricks, never more). Both answer bench's two incoherent ray sets (ao, aimed:
// bench.cpp) in world space, on the same threads, in calls of --batch rays, timed and repeated as
// bench does (timedParallelFor, best of --repeat, the three taking turns):
//   Embree   rtcOccluded1 on the mesh (the reference answers)
//   field    Instance::occluded, batch, kNearest
//   SDF      SdfField::occluded, batch: sphere tracing (hit or miss)
// and the share of rays each answers otherwise than Embree. One table, a row per mesh, memory and
// ray set: where the field is faster, and where it is more often right, at the same memory.
//
// --unsure adds a second table: the field's wrong answers split between the rays it is unsure of
// (Instance::visibility with kInterpolated strictly between 0 and 1: the samples and texels around
// the ray disagree, hit against miss) and the rest. The share of all rays wrong on the rest is what
// a field that sent only its unsure rays to an exact step would still get wrong; the unsure share
// is how many rays that step would take. The interpolated lookup's time against nearest's is the
// cost of telling them apart this way.
#include <algorithm>
#include <cmath>
#include <cstdio>

#include <optional>

#include "cli.h"
#include "vff/refine.h"
#include "common.h"

namespace vffx {

namespace {

constexpr uint64_t kChunk = 4096;

// The octa-hemi2 configuration whose payload (maps x m^2 bytes) is nearest `mib`.
FieldConfig configForMemory(double mib) {
  const double maps32 = 4226;
  const double m = std::sqrt(mib * 1048576.0 / maps32);
  uint32_t p = 4;
  while (p < 4096 && double(p) * std::sqrt(2.0) < m) p *= 2;
  FieldConfig c;
  c.n = 32;
  c.mapSize = p;
  if (p > 64) c.n = 64, c.mapSize = p / 2;
  return c;
}

// The refined field for a memory budget (the distance field's bytes): octa-hemi2 of the config's n
// with the largest maps whose bytes, with their unsure bits (one bit a texel) and the exact step's
// `meshBytes` (the vertex positions and the triangle BVH), fit. nullopt: not even 4 x 4 maps fit.
std::optional<FieldConfig> refinedConfig(const FieldConfig& config, uint64_t budget, uint64_t meshBytes) {
  const double maps = double(vff::positionCount(vff::PositionScheme::kOctaHemi2, config.n).value());
  if (budget <= meshBytes) return std::nullopt;
  const auto m = uint32_t(std::floor(std::sqrt(double(budget - meshBytes) / (maps * 1.125))));
  if (m < 4) return std::nullopt;
  FieldConfig c = config;
  c.mapSize = m;
  return c;
}

std::string baseName(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

// The exact step's bytes for the world's object, which do not depend on the maps: those of a
// refinement of the smallest field, less its unsure bits.
vff::Result<uint64_t> exactStepBytes(const World& world, const vff::bake::Scene& scene, const vff::RefineOptions& ro) {
  FieldConfig tiny;
  tiny.n = 4;
  tiny.mapSize = 4;
  auto small = bakeQuery(world, scene, tiny, false, ro.threads);
  if (!small) return std::move(small).error();
  if (vff::Status st = refineQuery(world, small->get(), ro); !st) return st.error();
  return (*small)->query.refinementBytes() - (*small)->refinement.unsure.size();
}

// The refined field at `budget` bytes (refinedConfig), baked and refined; null when none fits.
vff::Result<std::unique_ptr<BakedQuery>> bakeRefined(const World& world, const vff::bake::Scene& scene,
                                                     const FieldConfig& config, uint64_t budget, uint64_t meshBytes,
                                                     const vff::RefineOptions& ro) {
  const auto rc = refinedConfig(config, budget, meshBytes);
  if (!rc) return std::unique_ptr<BakedQuery>();
  auto r = bakeQuery(world, scene, *rc, false, ro.threads);
  if (!r) return std::move(r).error();
  if (vff::Status st = refineQuery(world, r->get(), ro); !st) return st.error();
  return std::move(*r);
}

// One row of the refined field's table: its parts' memory, unsure texels, speed against the
// distance field (both rates in the same unit) and wrong answers against Embree's (`ref`).
std::string refinedRow(const std::string& mesh, const std::string& set, uint64_t sdfBytes, uint64_t meshBytes,
                       const BakedQuery* refined, const std::vector<uint8_t>& ref, const std::vector<uint8_t>& byRefined,
                       uint64_t wrongSdf, double refinedRate, double sdfRate) {
  char row[400];
  const double mib = double(sdfBytes) / 1048576.0;
  if (!refined) {
    std::snprintf(row, sizeof row, "| %s | %.2f | %s | does not fit: the exact step alone needs %.2f MiB | | | | | | | | no |\n",
                  mesh.c_str(), mib, set.c_str(), double(meshBytes) / 1048576.0);
    return row;
  }
  const size_t n = ref.size();
  uint64_t wrong = 0;
  for (size_t i = 0; i < n; ++i) wrong += (byRefined[i] != 0) != (ref[i] != 0);
  const vff::FieldQuery& q = refined->query;
  const vff::FieldDesc& f = q.field();
  const uint64_t bits = refined->refinement.unsure.size();
  std::snprintf(row, sizeof row,
                "| %s | %.2f | %s | %s | %.2f + %.2f + %.2f | %.2f%% | %.2f | %.2f | %.1fx | %.3f%% | %.3f%% | %s |\n",
                mesh.c_str(), mib, set.c_str(), refined->config.name().c_str(), double(q.payloadBytes()) / 1048576.0,
                double(bits) / 1048576.0, double(q.refinementBytes() - bits) / 1048576.0,
                100.0 * double(refined->refinement.unsureTexels) /
                    double(uint64_t(f.mapCount) * f.mapResolution * f.mapResolution),
                refinedRate, sdfRate, refinedRate / sdfRate, 100.0 * double(wrong) / double(n),
                100.0 * double(wrongSdf) / double(n), refinedRate >= 10.0 * sdfRate && wrong <= wrongSdf ? "yes" : "no");
  return row;
}

void printHeader(const Options& o, unsigned threads) {
  std::printf("Distance-field benchmark: %u rays per set, %u threads, best of %d, %u rays per batch call, "
              "distance field %s, %s\n\n",
              o.benchRays, threads, o.repeat, o.benchBatch, o.sdfValues == SdfValues::kFp8 ? "fp8" : "float",
              cpuName().c_str());
  std::printf("| mesh | field | memory MiB | distance field | ray set | Embree Mrays/s | field Mrays/s | SDF Mrays/s | "
              "field / SDF speed | field wrong | SDF wrong |\n");
  std::printf("|---|---|---:|---|---|---:|---:|---:|---:|---:|---:|\n");
  std::fflush(stdout);
}

void printRefinedTable(const std::vector<std::string>& rows) {
  std::printf("\nThe refined field against the distance field at the same memory (the distance field's bytes)\n\n");
  std::printf("| mesh | memory MiB | ray set | refined field | maps + unsure bits + exact step MiB | unsure texels | "
              "refined Mrays/s | SDF Mrays/s | refined / SDF speed | refined wrong | SDF wrong | 10x faster, as often right |\n");
  std::printf("|---|---:|---|---|---|---:|---:|---:|---:|---:|---:|---|\n");
  for (const std::string& row : rows) std::fputs(row.c_str(), stdout);
  std::printf("\nrefined: Reconstruction::kRefined (vff/refine.h): the maps answer the rays they are sure of, an exact "
              "ray cast through the object's triangles the rest. exact step: the vertex positions and the triangle BVH "
              "(nodes and indices).\n");
}

}  // namespace

int runSdfBench(const Options& o) {
  const unsigned threads = resolveThreads(o.threads);
  std::vector<FieldConfig> configs;
  for (const std::string& text : o.configs) {
    FieldConfig c;
    if (!parseFieldConfig(text, &c)) {
      vff::cli::usageError(kProg, "--config " + text + ": expected MAPSxMxM with an octa-hemi2 map count");
      return vff::cli::kExitUsage;
    }
    configs.push_back(c);
  }
  if (configs.empty())
    for (double mib : o.sdfMemory) configs.push_back(configForMemory(mib));
  std::vector<std::string> meshes{o.mesh};
  meshes.insert(meshes.end(), o.objects.begin(), o.objects.end());

  printHeader(o, threads);
  std::vector<std::string> unsureRows;   // --unsure: printed after the main table
  std::vector<std::string> refinedRows;  // --refined: likewise
  const vff::RefineOptions refineOptions{.marginSpreads = o.refineMargin, .probe = o.refineProbe, .threads = threads};
  for (const std::string& path : meshes) {
    Options om = o;
    om.mesh = path;
    auto setup = makeSetup(om, threads);
    if (!setup) return vff::cli::reportError(kProg, path, setup.error());
    const World& world = (*setup)->world;
    const ExactTracer& exact = *(*setup)->exact;
    std::vector<RaySet> sets{makeAoRays(world, o.benchRays, o.aoDistance), makeAimedRays(world, o.benchRays)};
    uint64_t meshBytes = 0;
    if (o.sdfRefined) {
      auto bytes = exactStepBytes(world, *(*setup)->scene, refineOptions);
      if (!bytes) return vff::cli::reportError(kProg, path, bytes.error());
      meshBytes = *bytes;
    }
    for (const FieldConfig& config : configs) {
      auto field = bakeQuery(world, *(*setup)->scene, config, false, threads);
      if (!field) return vff::cli::reportError(kProg, path, field.error());
      const vff::Instance& instance = (*field)->instance;
      // Every row compares the field with its distance field: a field too small for one has no row
      // here (the image experiments leave out their distance-field rows instead).
      if (const uint64_t bytes = (*field)->query.payloadBytes(); bytes < kSdfMinBudget) {
        vff::cli::usageError(kProg, "sdf-bench: " + baseName(path) + " " + config.name() + ": the field's " +
                                        std::to_string(bytes) + " bytes are under the " + std::to_string(kSdfMinBudget) +
                                        " a distance grid needs; choose a larger --config or --sdf-memory");
        return vff::cli::kExitUsage;
      }
      auto built = SdfField::build(world.objectMesh, {.budgetBytes = (*field)->query.payloadBytes(), .values = o.sdfValues, .bandVoxels = o.sdfBand});
      if (!built) return vff::cli::reportError(kProg, path, built.error());
      SdfField& sdf = *built;
      sdf.transform = world.transform;
      std::fprintf(stderr, "%s: sdf-bench: %s %s: field baked in %.2f s, distance field built in %.2f s (%d builds)\n",
                   kProg, baseName(path).c_str(), config.name().c_str(), (*field)->bakeSeconds, sdf.buildSeconds(),
                   sdf.builds());
      // The refined field at the distance field's memory (none where it does not fit).
      std::unique_ptr<BakedQuery> refined;
      if (o.sdfRefined) {
        auto r = bakeRefined(world, *(*setup)->scene, config, sdf.bytes(), meshBytes, refineOptions);
        if (!r) return vff::cli::reportError(kProg, path, r.error());
        refined = std::move(*r);
      }
      char what[160];
      std::snprintf(what, sizeof what, "voxel %.4g R, %.2f MiB (NanoVDB %.2f)", double(sdf.voxelSize() / world.radius),
                    double(sdf.bytes()) / 1048576.0, double(sdf.nanovdbBytes()) / 1048576.0);
      for (const RaySet& set : sets) {
        const size_t n = set.world.size();
        const std::span<const vff::Ray> rays(set.world);
        std::vector<uint8_t> ref(n), byField(n), bySdf(n), byRefined(n);
        // (The rays start on the plane or outside the sphere: off the object, spec/geometry.md 7.4.)
        const vff::QueryOptions qn{.reconstruction = vff::Reconstruction::kNearest, .origin = vff::RayOrigin::kOffObject};
        auto batched = [&](auto&& call) {
          return timedParallelFor(n, kChunk, threads, [&](uint64_t b, uint64_t e) {
            for (uint64_t x = b; x < e; x += o.benchBatch) call(x, std::min<uint64_t>(e, x + o.benchBatch) - x);
          });
        };
        const vff::QueryOptions qr{.reconstruction = vff::Reconstruction::kRefined, .origin = vff::RayOrigin::kOffObject};
        double ta = 1e30, tf = 1e30, ts = 1e30, tr = 1e30;
        for (int rep = 0; rep < o.repeat; ++rep) {
          ta = std::min(ta, timedParallelFor(n, kChunk, threads, [&](uint64_t b, uint64_t e) {
            for (uint64_t i = b; i < e; ++i) ref[i] = exact.occluded(set.world[i]) ? 1 : 0;
          }));
          tf = std::min(tf, batched([&](uint64_t x, uint64_t k) {
            instance.occluded(rays.subspan(x, k), std::span<uint8_t>(byField).subspan(x, k), qn);
          }));
          ts = std::min(ts, batched([&](uint64_t x, uint64_t k) {
            sdf.occluded(rays.subspan(x, k), std::span<uint8_t>(bySdf).subspan(x, k));
          }));
          if (refined)
            tr = std::min(tr, batched([&](uint64_t x, uint64_t k) {
              refined->instance.occluded(rays.subspan(x, k), std::span<uint8_t>(byRefined).subspan(x, k), qr);
            }));
        }
        uint64_t wrongField = 0, wrongSdf = 0;
        for (size_t i = 0; i < n; ++i) {
          wrongField += (byField[i] != 0) != (ref[i] != 0);
          wrongSdf += (bySdf[i] != 0) != (ref[i] != 0);
        }
        if (o.sdfUnsure) {
          std::vector<float> open(n);
          const vff::QueryOptions qi{.reconstruction = vff::Reconstruction::kInterpolated, .origin = vff::RayOrigin::kOffObject};
          double tv = 1e30;
          for (int rep = 0; rep < o.repeat; ++rep)
            tv = std::min(tv, batched([&](uint64_t x, uint64_t k) {
              instance.visibility(rays.subspan(x, k), std::span<float>(open).subspan(x, k), qi);
            }));
          uint64_t unsure = 0, fieldUnsure = 0, fieldRest = 0, sdfUnsure = 0;
          for (size_t i = 0; i < n; ++i) {
            const bool u = open[i] > 0.f && open[i] < 1.f;
            const bool fieldWrong = (byField[i] != 0) != (ref[i] != 0);
            unsure += u;
            (u ? fieldUnsure : fieldRest) += fieldWrong;
            sdfUnsure += u && (bySdf[i] != 0) != (ref[i] != 0);
          }
          const auto pct = [](uint64_t k, uint64_t of) { return of ? 100.0 * double(k) / double(of) : 0.0; };
          char row[320];
          std::snprintf(row, sizeof row, "| %s | %s | %.2f | %s | %.2f%% | %.2f%% | %.2f%% | %.3f%% | %.3f%% | %.1f |\n",
                        baseName(path).c_str(), config.name().c_str(), (*field)->payloadMiB(), set.name.c_str(),
                        pct(unsure, n), pct(fieldUnsure, unsure), pct(sdfUnsure, unsure), pct(fieldRest, n),
                        pct(wrongSdf, n), tv / tf);
          unsureRows.emplace_back(row);
        }
        const double mr = double(n) / 1e6;
        if (o.sdfRefined)
          refinedRows.push_back(refinedRow(baseName(path), set.name, sdf.bytes(), meshBytes, refined.get(), ref, byRefined,
                                           wrongSdf, mr / tr, mr / ts));
        std::printf("| %s | %s | %.2f | %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f%% | %.2f%% |\n", baseName(path).c_str(),
                    config.name().c_str(), (*field)->payloadMiB(), what, set.name.c_str(), mr / ta, mr / tf, mr / ts,
                    ts / tf, 100.0 * double(wrongField) / double(n), 100.0 * double(wrongSdf) / double(n));
        std::fflush(stdout);
      }
    }
  }
  std::printf("\nwrong: the share of rays answered otherwise than Embree (occluded or not). field / SDF speed > 1: the "
              "field is faster. Both at the same memory: the field's payload, the distance field's bricks (sdf_field.h).\n");
  if (o.sdfRefined) printRefinedTable(refinedRows);
  if (o.sdfUnsure) {
    std::printf("\nWhere the field is wrong: on its unsure rays (interpolated visibility strictly between 0 and 1) or "
                "on the rest\n\n");
    std::printf("| mesh | field | memory MiB | ray set | unsure rays | field wrong, of the unsure | SDF wrong, of the "
                "unsure | field wrong on the rest, of all | SDF wrong, of all | interpolated / nearest time |\n");
    std::printf("|---|---|---:|---|---:|---:|---:|---:|---:|---:|\n");
    for (const std::string& row : unsureRows) std::fputs(row.c_str(), stdout);
    std::printf("\nfield wrong on the rest, of all: what a field that sent only its unsure rays to an exact step "
                "would still answer wrongly, against the SDF's wrong answers at the same memory.\n");
  }
  return vff::cli::kExitSuccess;
}

}  // namespace vffx
