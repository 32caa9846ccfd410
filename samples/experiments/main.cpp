// vff-experiments: the paper's experiments (Figs. 3, 5, 7-9) and the CPU query benchmark.
//
//   vff-experiments ao                     inter-object AO on the plane: exact vs three fields
//   vff-experiments intra-ao               AO of the object on itself (the intra-object test)
//   vff-experiments shadows                soft shadows from three spherical lights
//   vff-experiments reflections            glossy reflection using the normal field
//   vff-experiments bench                  Embree vs FieldQuery throughput on the same rays
//   vff-experiments scene                  a room (exact) and moving objects through their fields (Fig. 6)
//   vff-experiments scene-bench            N moving instances: Embree instancing vs vff::Scene vs hybrid
//   vff-experiments triangle-bench         time per ray against triangles (Loop subdivision to 1M)
//   vff-experiments sdf-bench              field vs signed distance field vs Embree at equal memory, a sweep
//   vff-experiments ao --field lod.vff     also (or only) evaluate field files of the same mesh
//   vff-experiments ao --no-sdf            without the signed-distance-field rows (on by default)
//
// Images (PNG, EXR, error heat maps) and OUT/NAME-table.md go to --out (default out/experiments);
// the table is printed on stdout, progress on stderr. Fields are baked in memory, never written.
#include <CLI/CLI.hpp>

#include <string>
#include <utility>
#include <vector>

#include "cli.h"
#include "common.h"

int main(int argc, char** argv) {
  using namespace vffx;
  Options o;
  CLI::App app{"Renders the visibility-field paper's experiments (exact Embree vs field) and benchmarks the "
               "CPU query.\n" +
               vff::cli::exitCodeHelp()};
  vff::cli::addVersionFlag(app, kProg);
  const std::vector<std::pair<std::string, int (*)(const Options&)>> experiments = {
      {"ao", runAo},         {"intra-ao", runIntraAo},       {"shadows", runShadows},
      {"reflections", runReflections}, {"bench", runBench}, {"scene", runScene},
      {"scene-bench", runSceneBench},  {"triangle-bench", runTriangleBench}, {"sdf-bench", runSdfBench}};
  std::vector<std::string> names;
  for (const auto& e : experiments) names.push_back(e.first);
  std::string list;
  for (size_t i = 0; i < names.size(); ++i) list += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  // One option under two names: CLI11 would mark each REQUIRED, as if both were; the check after
  // parsing asks for one of them.
  app.add_option("experiment,--experiment", o.experiment, list + " (required: as the positional or --experiment)")
      ->check(CLI::IsMember(names));
  app.add_option("--mesh", o.mesh, "object mesh (.obj .ply .off .stl .gltf .glb)")->capture_default_str();
  app.add_option("-o,--out", o.out, "output folder for images and tables")->capture_default_str();
  app.add_option("--size", o.size, "image width and height in pixels")->capture_default_str()->check(CLI::Range(1, 8192));
  app.add_option("--rays", o.rays, "rays per pixel (0: ao 256, intra-ao 121, shadows 20, reflections 4)")
      ->capture_default_str()
      ->check(CLI::Range(0, 1 << 16));
  app.add_option("-j,--threads", o.threads, "worker threads (0: all cores); images do not depend on it")
      ->capture_default_str();
  app.add_option("--config", o.configs,
                 "field configuration(s) MAPSxMxM, octa-hemi2 maps (4226 = n 32, 16642 = n 64); "
                 "default per experiment (bench: 4226x64x64)");
  app.add_option("--field", o.fields,
                 "image experiments: also evaluate this .vff of the same mesh (repeatable; e.g. one made by "
                 "vff-convert); its sphere and source mesh must match. With --field and no --config, only the files");
  app.add_option("--ao-distance", o.aoDistance, "AO ray range in multiples of the bounding radius R")
      ->capture_default_str()
      ->check(CLI::PositiveNumber);
  app.add_option("--ao-ranges", o.aoRanges,
                 "ao: render each of these AO ranges (multiples of R, e.g. 0.25 0.5 1 2), each against its own "
                 "exact image; default: --ao-distance")
      ->check(CLI::PositiveNumber);
  app.add_option("--bench-rays", o.benchRays, "bench: rays per ray set")->capture_default_str()
      ->check(CLI::Range(1u, 1u << 26));
  app.add_option("--batch", o.benchBatch, "bench: rays per batch call in (b), (d) and (e) (a renderer's call: a tile, a pixel)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 1u << 26));
  app.add_option("--repeat", o.repeat, "bench, scene-bench, triangle-bench, sdf-bench: repetitions (best is reported)")->capture_default_str()
      ->check(CLI::Range(1, 100));
  app.add_flag("--sdf,!--no-sdf", o.sdf,
               "image experiments: also render the signed distance field (OpenVDB level set, NanoVDB, sphere "
               "tracing) at each field's memory (default: on)");
  // (A string option: CLI11's help cannot print an enum's map.)
  app.add_option_function<std::string>(
         "--sdf-values", [&o](const std::string& v) { o.sdfValues = v == "float" ? SdfValues::kFloat : SdfValues::kFp8; },
         "the distance field's values: fp8 (one byte a voxel) or float")
      ->check(CLI::IsMember({"fp8", "float"}))
      ->default_str("fp8");
  app.add_option("--sdf-band", o.sdfBand, "the distance field's narrow band: half-width in voxels")
      ->capture_default_str()
      ->check(CLI::Range(1.0f, 64.0f));
  app.add_option("--object", o.objects, "scene: a moving object's mesh besides --mesh (repeatable; none: four "
                 "procedural shapes); sdf-bench: a mesh besides --mesh (repeatable)");
  app.add_option("--sdf-memory", o.sdfMemory, "sdf-bench: memory per object in MiB (the field configuration of "
                 "nearest payload; --config instead names them)")
      ->capture_default_str()
      ->check(CLI::Range(0.01, 4096.0));
  app.add_flag("--unsure", o.sdfUnsure, "sdf-bench: a second table, where the field's wrong answers lie: on the rays "
               "whose interpolated visibility is strictly between 0 and 1 (the samples around the ray disagree), or on "
               "the rest");
  app.add_flag("--refined,!--no-refined", o.sdfRefined, "the refined field (vff/refine.h): sdf-bench's table of it at "
               "the distance field's memory, the image experiments' 'refined' row of each baked field (--no-refined: "
               "neither)");
  app.add_option("--refine-margin", o.refineMargin, "sdf-bench: the refined field's margin, in lateral spreads "
                 "(RefineOptions::marginSpreads)")
      ->capture_default_str()
      ->check(CLI::Range(0.0f, 16.0f));
  app.add_flag("--refine-probe", o.refineProbe, "sdf-bench: the refined field's texels whose neighbours disagree stay "
               "unsure only when a ray through a corner of their cell meets the surface otherwise (RefineOptions::probe)");
  app.add_option("--instances", o.instanceCounts, "scene-bench: instance counts (one table row each)")
      ->capture_default_str()
      ->check(CLI::Range(1u, 1u << 20));
  app.add_option("--scene-rays", o.sceneRays, "scene-bench: AO rays per frame")->capture_default_str()
      ->check(CLI::Range(1u, 1u << 26));
  app.add_option("--min-triangles", o.minTriangles,
                 "triangle-bench: the coarsest level (the mesh decimated) has at least this many triangles")
      ->capture_default_str()
      ->check(CLI::Range(1u, 1u << 26));
  app.add_option("--max-triangles", o.maxTriangles,
                 "triangle-bench: subdivide the mesh until it has at least this many triangles")
      ->capture_default_str()
      ->check(CLI::Range(1u, 1u << 26));
  app.add_option("--frames", o.frames, "scene, scene-bench: frames (each moves every object)")->capture_default_str()
      ->check(CLI::Range(1, 1000));
  if (auto rc = vff::cli::parse(app, kProg, argc, argv)) return *rc;
  if (o.experiment.empty()) {
    vff::cli::usageError(kProg, "an experiment is required: " + list + " (the positional EXPERIMENT or --experiment)");
    return vff::cli::kExitUsage;
  }
  if (o.experiment.find("bench") != std::string::npos && !o.fields.empty()) {
    vff::cli::usageError(kProg, "--field applies to the image experiments, not to " + o.experiment);
    return vff::cli::kExitUsage;
  }
  try {
    for (const auto& e : experiments)
      if (e.first == o.experiment) return e.second(o);
    return vff::cli::kExitUsage;  // not reached: CLI11 checked the name
  } catch (const std::bad_alloc&) {
    vff::cli::printError(kProg, "out of memory");
    return vff::cli::kExitRuntime;
  }
}
