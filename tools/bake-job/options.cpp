// options.cpp - vff-bake's command line: the options, the checks CLI11 cannot make, and the baker's
// and writer's options they give.
#include <algorithm>
#include <cctype>

#include "bake_job.h"
#include "cli.h"

namespace vff::bake_tool {

namespace {

uint32_t defaultCount(PositionScheme s) {
  switch (s) {
    case PositionScheme::kEqualAreaOctaGrid: return 65;  // 4225 maps
    case PositionScheme::kSphericalFibonacci: return 4226;
    default: return 32;  // 4226 maps
  }
}

}  // namespace

void addOptions(CLI::App& app, Options& o) {
  cli::addVersionFlag(app, kProg);
  app.add_option("mesh", o.mesh, "input mesh, or OpenVDB level set (.vdb); none with --merge");
  app.add_option("-o,--output", o.output,
                 "output .vff file (written atomically); for a glTF input, a .glb: the input asset with a field "
                 "attached to each mesh of the scene (the glTF extension VFF_visibility_field), each baked in its "
                 "mesh's own frame, the same bytes --split mesh writes for it");
  app.add_option("--grid", o.grid, ".vdb input: name of the level set grid to bake (default: the first level set by name)");
  app.add_option("--scene", o.scene, "glTF input: the scene to bake (default: the file's default scene)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--split", o.split,
                 "glTF input: bake each mesh (one field per mesh, placed at every node using it) or each node "
                 "into its own field, and write a scene description (spec/scene.md) to -o, which must end in "
                 ".json; the fields go beside it as STEM.meshI.vff / STEM.nodeJ.vff")
      ->check(CLI::IsMember({"mesh", "node"}));
  app.add_flag("--external-fields", o.externalFields,
               "glTF input, -o X.glb: write the fields beside the .glb as X.meshI.vff, referenced by uri, rather "
               "than inside it");
  o.positions.add(app, "positional-sample scheme")->capture_default_str();
  app.add_option("-n,--count", o.count,
                 "scheme parameter: octa-hemi2 n (maps = 2(2n^2+2n+1), default 32 = 4226 maps), "
                 "ea-octa-grid n (n^2 maps, default 65), fibonacci N (default 4226)")
      ->check(CLI::PositiveNumber);
  app.add_option("-m,--map-size", o.mapSize, "map resolution M (M x M rays per sample)")->capture_default_str()
      ->check(CLI::Range(1u, 4096u));
  o.directions.add(app, "hemisphere-to-square map")->capture_default_str();
  o.encoding.add(app, "distance encoding")->capture_default_str();
  app.add_flag("--normals", o.normals, "also store the surface normal at each hit (4 bytes per ray)");
  app.add_flag("--refine", o.refine, "also store the unsure texels and the mesh's triangles (section REFN, format "
               "1.3): a reader answers the rays the maps are unsure of exactly (Reconstruction::kRefined)");
  app.add_flag("--refine-probe", o.refineProbe, "with --refine: keep a texel unsure only when a ray through a corner "
               "of its cell meets the mesh otherwise than the texel says (fewer exact rays, a few more wrong answers)");
  app.add_option("-j,--threads", o.threads, "baking threads (0: all cores); the output does not depend on it")
      ->capture_default_str();
  app.add_option("--center", o.center, "bounding-sphere centre x y z (default: minimal enclosing sphere)")
      ->expected(3);
  app.add_option("--radius", o.radius, "bounding-sphere radius (with --center); it must enclose a mesh's vertices");
  // Level sets are not checked: their active voxels include the band outside the surface.
  app.add_flag("--allow-clipped-sphere", o.allowClippedSphere, "bake with a --center/--radius sphere that cuts the mesh "
               "(distances past it are clamped; a warning, \"sphereEnclosesMesh\": false in the metadata)");
  o.codec.add(app, cli::Defaults::kTool);
  o.layout.add(app, cli::Defaults::kTool);
  app.add_flag("--json", o.json, "print a machine-readable summary on stdout");
  app.add_flag("-q,--quiet", o.quiet, "no progress output");
  app.add_flag("--benchmark", o.benchmark,
               "measure Embree's raw throughput on exactly the bake's rays against the whole bake, and print both");
  app.add_option("--repeat", o.repeat, "benchmark repetitions (best is reported)")->check(CLI::Range(1, 100));
  app.add_option("--map-range", o.mapRange,
                 "bake only maps [BEGIN, END) of the field (indices in its sample order) into a partial result "
                 "(a .vff whose other maps are misses, spec/partial.md); --merge assembles the parts")
      ->type_name("BEGIN:END");
  app.add_option("--merge", o.merge,
                 "assemble partial results (any order; together exactly the field's maps) into -o: the same "
                 "bytes as the whole bake with their options, which they carry (no mesh, no bake options)")
      ->type_name("PART");
}

std::optional<std::string> checkMergeOptions(const CLI::App& app) {
  if (app.count("mesh")) return "--merge takes partial results, not a mesh";
  for (const char* name : {"--grid", "--scene", "--split", "--positions", "--count", "--map-size", "--directions",
                           "--encoding", "--normals", "--refine", "--refine-probe", "--center", "--radius", "--allow-clipped-sphere", "--codec",
                           "--zstd-level", "--maps-per-block", "--target", "--max-texture-size", "--max-layers",
                           "--gutter", "--benchmark", "--repeat", "--map-range"})
    if (app.count(name)) return std::string("--merge takes every bake option from its parts: ") + name + " does not apply";
  if (app.get_option("--output")->count() == 0) return "--merge needs an output file (-o FILE)";
  return std::nullopt;
}

std::optional<std::string> checkOptions(const Options& o) {
  if (o.mesh.empty()) return "an input mesh is required (or --merge PART... -o FILE)";
  if (!o.mapRange.empty()) {
    if (!parseMapRange(o.mapRange)) return "--map-range takes BEGIN:END, map indices with BEGIN < END, not '" + o.mapRange + "'";
    if (o.benchmark) return "--benchmark measures the whole bake; it does not apply to --map-range";
    if (!o.split.empty()) return "--split writes a field per object; it does not apply to --map-range";
    if (isVdbPath(o.mesh)) return "--map-range applies to a mesh bake, not to a .vdb level set";
  }
  if (o.output.empty() && !o.benchmark) return "an output file is required (-o FILE), unless --benchmark is given";
  if (o.refineProbe && !o.refine) return "--refine-probe goes with --refine";
  if (o.refine) {
    if (isVdbPath(o.mesh)) return "--refine stores a mesh's triangles; a .vdb level set has none";
    if (isGltfPath(o.mesh) && (!o.split.empty() || isGlbPath(o.output)))
      return "--refine applies to one field in a .vff file, not to --split or a .glb output";
    if (!o.mapRange.empty()) return "--refine needs every map; it does not apply to --map-range";
    if (o.allowClippedSphere) return "--refine stores the triangles inside the sphere: --allow-clipped-sphere does not apply";
    if (o.encoding.value() == DistanceEncoding::kBit1) return "--refine needs distances; --encoding bit1 has none";
  }
  if ((!o.center.empty()) != (o.radius > 0)) return "--center and --radius go together (radius > 0)";
  if (o.allowClippedSphere && o.center.empty()) return "--allow-clipped-sphere needs --center and --radius";
  if (isVdbPath(o.mesh)) {
    if (o.benchmark) return "--benchmark measures Embree on a mesh; it does not apply to a .vdb level set";
  } else if (!o.grid.empty()) {
    return "--grid applies to a .vdb level set input only";
  }
  if (!isGltfPath(o.mesh) && (o.scene >= 0 || !o.split.empty()))
    return std::string(o.scene >= 0 ? "--scene" : "--split") + " applies to a glTF input (.gltf, .glb) only";
  if (o.externalFields && !(isGltfPath(o.mesh) && isGlbPath(o.output)))
    return "--external-fields applies to a glTF input baked into a .glb output (-o X.glb)";
  if (!isGltfPath(o.mesh) && isGlbPath(o.output))
    return "a .glb output carries the fields of a glTF input (.gltf, .glb); a field of '" + baseName(o.mesh) +
           "' is a .vff file (-o X.vff)";
  if (isGltfPath(o.mesh) && isGlbPath(o.output)) {
    if (o.split == "node")
      return "--split node places a field per node; a .glb output attaches a field to each mesh (--split mesh or "
             "none), in the mesh's own frame";
    if (!o.center.empty()) return "a .glb output bakes each mesh in its own sphere: --center/--radius do not apply";
    if (o.benchmark) return "--benchmark measures one mesh; it does not apply to a .glb output";
    if (!o.mapRange.empty()) return "a .glb output carries whole fields; --map-range does not apply";
    return std::nullopt;
  }
  if (!o.split.empty()) {
    const std::string& out = o.output;
    if (out.size() < 6 || out.compare(out.size() - 5, 5, ".json") != 0)
      return "--split writes a scene description: -o must name a .json file (e.g. scene.vffscene.json)";
    if (!o.center.empty()) return "--split bakes each object in its own sphere: --center/--radius do not apply";
    if (o.benchmark) return "--benchmark measures one mesh; it does not apply to --split";
  }
  return std::nullopt;
}

bake::BakeOptions bakeOptions(const Options& o) {
  bake::BakeOptions bo;
  bo.positionScheme = o.positions.value();
  bo.positionParam = o.count ? o.count : defaultCount(bo.positionScheme);
  bo.directionScheme = o.directions.value();
  bo.mapResolution = o.mapSize;
  bo.encoding = o.encoding.value();
  bo.normals = o.normals;
  bo.threads = o.threads;
  if (!o.center.empty()) bo.sphere = Sphere{{o.center[0], o.center[1], o.center[2]}, o.radius};
  return bo;
}

WriteOptions writeOptions(const Options& o) {
  WriteOptions wo;
  wo.codec = o.codec.codec.value();
  wo.zstdLevel = o.codec.zstdLevel;
  wo.mapsPerBlock = o.codec.mapsPerBlock;
  wo.layout = o.layout.limits(LayoutLimits{});
  return wo;
}

namespace {
bool hasExtension(const std::string& p, const std::string& ext) {
  if (p.size() < ext.size()) return false;
  std::string e = p.substr(p.size() - ext.size());
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return char(std::tolower(c)); });
  return e == ext;
}
}  // namespace

bool isVdbPath(const std::string& p) { return hasExtension(p, ".vdb"); }
bool isGltfPath(const std::string& p) { return hasExtension(p, ".gltf") || hasExtension(p, ".glb"); }
bool isGlbPath(const std::string& p) { return hasExtension(p, ".glb"); }

}  // namespace vff::bake_tool
