// vff_gltf_write SHAPE KIND OUT.glb - a procedural mesh (vff-procedural-mesh's shapes) as a glTF
// binary for gltf_tests.sh. KIND: plain, quantized (16-bit normalized positions), draco (sequential:
// the vertices in order), draco-edgebreaker, meshopt (index sequence: the indices in order),
// meshopt-filters (EXPONENTIAL positions, OCTAHEDRAL normals). Exit 1 on a usage or I/O error.
#include <cstdio>
#include <string>

#include "gltf_writer.h"
#include "vff/bake/procedural.h"

int main(int argc, char** argv) {
  using namespace vff::bake::gltftest;
  if (argc != 4) {
    std::fprintf(stderr, "usage: vff_gltf_write SHAPE KIND OUT.glb\n");
    return 1;
  }
  const vff::bake::Mesh mesh = vff::bake::makeShape(argv[1]);
  const std::string kind = argv[2];
  GltfDoc doc;
  if (kind == "plain") doc = makeGltf(mesh, {});
  else if (kind == "quantized") doc = makeGltf(mesh, {kUShort, true, kShort});
  else if (kind == "draco") doc = makeDracoGltf(mesh, true);
  else if (kind == "draco-edgebreaker") doc = makeDracoGltf(mesh, false);
  else if (kind == "meshopt" || kind == "meshopt-filters") {
    Meshopt o;
    o.indexSequence = kind == "meshopt";
    o.exponentialPositions = kind == "meshopt-filters";
    o.normalFilter = kind == "meshopt-filters" ? "OCTAHEDRAL" : "NONE";
    doc = makeMeshoptGltf(mesh, o);
  } else {
    std::fprintf(stderr, "vff_gltf_write: error: unknown kind '%s'\n", kind.c_str());
    return 1;
  }
  if (mesh.positions.empty() || !save(doc, argv[3], true)) {
    std::fprintf(stderr, "vff_gltf_write: error: cannot write %s\n", argv[3]);
    return 1;
  }
  return 0;
}
