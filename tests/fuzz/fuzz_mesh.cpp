// Fuzz target: the mesh front end of vff-bake (OpenMesh for OBJ/PLY/OFF/STL, tinygltf for glTF/GLB)
// and the checks that follow it. The first byte picks the format; the rest is the file. Every input
// must give a mesh that passes checkMesh or an Error, never a crash.
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <string>

#include "vff/bake/mesh.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  static const char* kExt[] = {".obj", ".ply", ".off", ".stl", ".gltf", ".glb"};
  const std::string path = "/tmp/vff-fuzz-mesh-" + std::to_string(getpid()) + kExt[data[0] % 6];
  FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) return 0;
  std::fwrite(data + 1, 1, size - 1, f);
  std::fclose(f);
  vff::Result<vff::bake::Mesh> mesh = vff::bake::loadMesh(path);
  if (mesh.ok()) (void)vff::bake::checkMesh(&*mesh, path);
  std::remove(path.c_str());
  return 0;
}
