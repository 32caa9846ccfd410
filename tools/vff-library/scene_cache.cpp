// scene_cache.cpp - split entries (a glTF scene baked as a field per object, vff-bake --split) in
// the cache: one unit per entry, the scene description and all its fields in one folder,
// CACHE/ab/KEY.scene/, as vff-bake wrote them.
//
// Why one unit and not a cache entry per object: vff-bake --split reads, plans and bakes the
// objects of a scene in one process and writes the description last, naming every field; caching
// the set as a whole keeps a description and its fields from two different bakes from ever being
// installed together, and a scene is installed completely or not at all. A changed object (or
// placement, or name) changes the key of its whole scene, which is baked again.
#include <sys/stat.h>
#include <xxhash.h>

#include <filesystem>
#include <fstream>

#include "cli.h"
#include "library.h"
#include "vff/bake/gltf.h"

namespace fs = std::filesystem;

namespace vff::library {

std::string sceneCachePath(const std::string& cacheDir, const std::string& key) {
  return cacheDir + "/" + key.substr(0, 2) + "/" + key + ".scene";
}

std::optional<std::string> splitGeometry(const Entry& e, int scene, Error* error, uint64_t* objects) {
  bake::MeshInfo info;
  const bake::GltfSplit split = e.split == "node" ? bake::GltfSplit::kNode : bake::GltfSplit::kMesh;
  auto loaded = bake::loadGltfObjects(e.mesh, {.split = split, .scene = scene}, &info);
  if (!loaded) {
    *error = loaded.error();
    return std::nullopt;
  }
  // The file's bytes hold the placements and names the description records (a .gltf's buffers
  // are in each object's hashes).
  auto bytes = fileHash(e.mesh);
  if (!bytes) {
    *error = Error{Code::kIoRead, 0, kNoOffset, "cannot be read"};
    return std::nullopt;
  }
  std::string line = "mesh " + info.format + " split " + e.split + " " + std::to_string(info.gltfScene) + " " + *bytes;
  for (const bake::GltfObject& obj : *loaded)
    line += " " + std::to_string(obj.mesh) + ":" + std::to_string(obj.node) + ":" +
            cli::hexDigits64(bake::geometryHash(obj.geometry)) + ":" + cli::hexDigits64(bake::meshHash(obj.geometry)) +
            ":" + std::to_string(obj.geometry.droppedDegenerate);
  *objects = loaded->size();
  return line + " objects " + std::to_string(loaded->size());
}

uint64_t splitObjects(const std::string& geometry) {
  const size_t at = geometry.rfind(" objects ");
  return at == std::string::npos ? 0 : std::strtoull(geometry.c_str() + at + 9, nullptr, 10);
}

std::optional<std::vector<std::string>> sceneFiles(const std::string& cacheDir, const Entry& e) {
  const std::string description = fs::path(e.output).filename().string();
  auto j = nlohmann::json::parse(readText(sceneCachePath(cacheDir, e.key) + "/" + description), nullptr, false);
  if (j.is_discarded() || !j.contains("fields") || !j["fields"].is_array()) return std::nullopt;
  std::vector<std::string> files;
  for (const auto& f : j["fields"]) {
    if (!f.is_object() || !f.contains("uri") || !f["uri"].is_string()) return std::nullopt;
    const std::string uri = f["uri"].get<std::string>();
    if (uri.empty() || uri.find('/') != std::string::npos) return std::nullopt;  // vff-bake writes names only
    files.push_back(uri);
  }
  files.push_back(description);
  return files;
}

bool sceneUpToDate(const std::string& cacheDir, const Entry& e) {
  auto files = sceneFiles(cacheDir, e);
  if (!files) return false;
  const fs::path dir = fs::path(e.output).parent_path();
  for (const std::string& f : *files)
    if (!sameFile(sceneCachePath(cacheDir, e.key) + "/" + f, (dir / f).string())) return false;
  return true;
}

std::optional<std::string> installScene(const std::string& cacheDir, const Entry& e) {
  auto files = sceneFiles(cacheDir, e);
  if (!files) return sceneCachePath(cacheDir, e.key) + ": not a scene vff-bake --split wrote";
  // The fields first, the description last: while it is missing or old, the new scene is not there.
  const fs::path dir = fs::path(e.output).parent_path();
  for (const std::string& f : *files) {
    const std::string from = sceneCachePath(cacheDir, e.key) + "/" + f, to = (dir / f).string();
    if (sameFile(from, to)) continue;
    if (auto problem = installFile(from, to)) return problem;
  }
  return std::nullopt;
}

}  // namespace vff::library
