// vff-bake: bakes a visibility field from a triangle mesh with Embree.
//
//   vff-bake mesh.obj -o field.vff          the paper's configuration: 4226 maps of 64x64, 8 bits, 2R
//   vff-bake mesh.glb -o f.vff --normals --encoding unorm16-diameter --codec zstd
//   vff-bake mesh.obj --benchmark           Embree's raw throughput on the bake's rays vs the bake
//   vff-bake shape.vdb -o f.vff [--grid NAME]   from an OpenVDB level set (vff/bake/levelset.h)
//   vff-bake scene.glb --split mesh -o s.vffscene.json   a field per mesh and a scene description
//   vff-bake scene.gltf -o out.glb          a field per mesh inside the asset (VFF_visibility_field)
//   vff-bake mesh.obj -o p0.vff --map-range 0:2113      a partial result: maps [0, 2113) only
//   vff-bake --merge p1.vff p0.vff -o field.vff         the partial results assembled (spec/partial.md)
//
// options.cpp reads the command line, mesh_bake.cpp, split_bake.cpp, glb_bake.cpp and levelset_bake.cpp bake, common.cpp holds
// what the two bakes share, partial.cpp and merge.cpp the partial results (bake_job.h, bake.h).
#include "bake.h"
#include "cli.h"

int main(int argc, char** argv) {
  using namespace vff::bake_tool;
  Options o;
  CLI::App app{"Bakes a precomputed 4D visibility field (.vff) from a triangle mesh with Embree, or from an\n"
               "OpenVDB level set (rays intersected with its zero crossing, normals from its gradient).\n"
               "Inputs: .obj .ply .off .stl (OpenMesh), .gltf .glb (tinygltf), .vdb (OpenVDB: the first float\n"
               "grid of class level set by name, as vdb_print lists them, or --grid NAME; default sphere: the\n"
               "one around the active voxels' bounding box).\n"
               "One field across tasks: --map-range BEGIN:END bakes those maps into a partial result; --merge\n"
               "PART... -o OUT assembles the parts into the whole bake's bytes (spec/partial.md). Merge refusals\n"
               "print the rule as NAME (ID), 12001-12019: gaps, overlaps, other geometry, options or version, a\n"
               "malformed or corrupt part: exit 3; a part of another vff.partial version or block codec: exit 5;\n"
               "-o naming a part: exit 1.\n"
               "glTF input with -o X.glb: the asset as one .glb with a field attached to each mesh of the scene (the\n"
               "glTF extension VFF_visibility_field), each baked in the mesh's own frame: the bytes --split mesh\n"
               "writes for it; --external-fields writes them beside it as X.meshI.vff, referenced by uri.\n" +
               vff::cli::exitCodeHelp()};
  addOptions(app, o);
  if (auto rc = vff::cli::parse(app, kProg, argc, argv)) return *rc;
  if (!o.merge.empty()) {
    if (auto problem = checkMergeOptions(app)) {
      vff::cli::usageError(kProg, *problem);
      return vff::cli::kExitUsage;
    }
    return mergeParts(o, MergeHooks{removeStaleTemporaries, [](const std::string& out) { removeTemporaryOnSignal(out); }});
  }
  if (auto problem = checkOptions(o)) {
    vff::cli::usageError(kProg, *problem);
    return vff::cli::kExitUsage;
  }
  if (isVdbPath(o.mesh)) return bakeFromLevelSet(o, bakeOptions(o), writeOptions(o));
  if (isGltfPath(o.mesh) && isGlbPath(o.output)) return bakeGltfGlb(o, bakeOptions(o), writeOptions(o));
  if (!o.split.empty()) return bakeGltfSplit(o, bakeOptions(o), writeOptions(o));
  return bakeFromMesh(o, bakeOptions(o), writeOptions(o));
}
