// vff-procedural-mesh: writes the procedural test meshes (torus knot, concave bowl, thin rod, ...)
// as OBJ files, to bake them with vff-bake.
//   vff-procedural-mesh torus-knot knot.obj
//   vff-procedural-mesh --all DIR
//   vff-procedural-mesh --gltf-scene scene.gltf   several objects in two glTF scenes
#include <cstdio>
#include <cstring>
#include <string>

#include "vff/bake/procedural.h"

int main(int argc, char** argv) {
  const auto& names = vff::bake::shapeNames();
  auto usage = [&] {
    std::fprintf(stderr, "usage: vff-procedural-mesh SHAPE OUT.obj | --all DIR | --gltf-scene OUT.gltf\nshapes:");
    for (const auto& n : names) std::fprintf(stderr, " %s", n.c_str());
    std::fprintf(stderr, "\n");
    return 1;
  };
  if (argc != 3) return usage();
  if (std::strcmp(argv[1], "--gltf-scene") == 0) {
    if (auto s = vff::bake::writeSampleGltfScene(argv[2]); !s) {
      std::fprintf(stderr, "vff-procedural-mesh: error: %s\n", s.error().message.c_str());
      return 2;
    }
    return 0;
  }
  if (std::strcmp(argv[1], "--all") == 0) {
    for (const auto& n : names) {
      const std::string path = std::string(argv[2]) + "/" + n + ".obj";
      if (auto s = vff::bake::writeObj(vff::bake::makeShape(n), path); !s) {
        std::fprintf(stderr, "vff-procedural-mesh: error: %s\n", s.error().message.c_str());
        return 2;
      }
      std::printf("%s\n", path.c_str());
    }
    return 0;
  }
  vff::bake::Mesh m = vff::bake::makeShape(argv[1]);
  if (m.triangleCount() == 0) return usage();
  if (auto s = vff::bake::writeObj(m, argv[2]); !s) {
    std::fprintf(stderr, "vff-procedural-mesh: error: %s\n", s.error().message.c_str());
    return 2;
  }
  return 0;
}
