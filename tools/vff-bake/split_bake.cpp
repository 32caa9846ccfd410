// split_bake.cpp - vff-bake --split mesh|node: a glTF scene baked as separate rigid objects, a field
// each, and the scene description that places them (spec/scene.md).
//
// Every object is checked and planned before anything is written. The fields are written one after
// the other, each atomically; the description last. When a later step fails or the run is
// interrupted, the fields this run wrote are removed again: the output is the whole set or nothing
// new (fields of an earlier run with the same names are replaced only by a run that completes).
#include <unistd.h>

#include <cstdio>
#include <optional>

#include "bake.h"
#include "cli.h"
#include "vff/bake/gltf.h"
#include "vff/bake/mesh.h"
#include "vff/scene_description.h"

namespace vff::bake_tool {

namespace {

// The output path without ".vffscene.json" or ".json".
std::string stemOf(const std::string& output) {
  for (const char* ext : {".vffscene.json", ".json"}) {
    const std::string e = ext;
    if (output.size() > e.size() && output.compare(output.size() - e.size(), e.size(), e) == 0)
      return output.substr(0, output.size() - e.size());
  }
  return output;
}

// STEM.meshI.vff, STEM.meshI.nodeJ.vff (a node whose transform is baked in), STEM.nodeJ.vff.
std::string fieldPath(const std::string& stem, const bake::GltfObject& obj, bake::GltfSplit split) {
  if (split == bake::GltfSplit::kNode) return stem + ".node" + std::to_string(obj.node) + ".vff";
  std::string p = stem + ".mesh" + std::to_string(obj.mesh);
  if (obj.node >= 0) p += ".node" + std::to_string(obj.node);
  return p + ".vff";
}

void removeAll(const std::vector<std::string>& paths) {
  for (const std::string& p : paths) ::unlink(p.c_str());
}

struct Planned {
  std::string path;
  FieldDesc field;
  uint64_t payload = 0;
};

}  // namespace

int bakeGltfSplit(const Options& o, bake::BakeOptions bo, WriteOptions wo) {
  const bake::GltfSplit split = o.split == "node" ? bake::GltfSplit::kNode : bake::GltfSplit::kMesh;
  bake::MeshInfo info;
  const auto t0 = std::chrono::steady_clock::now();
  auto objects = bake::loadGltfObjects(o.mesh, {.split = split, .scene = o.scene}, &info);
  if (!objects) return reportLoadError(objects.error(), o.mesh);
  noteUnbakedScenes(o, info);

  // Plan every field before any output exists.
  const std::string stem = stemOf(o.output);
  std::vector<Planned> plan;
  for (const bake::GltfObject& obj : *objects) {
    Planned p{fieldPath(stem, obj, split), {}, 0};
    auto field = bake::describeBake(obj.geometry, bo);
    if (auto rc = checkPlan(field, wo.layout, &p.payload)) return *rc;
    p.field = *field;
    plan.push_back(std::move(p));
  }

  SceneDescription scene;
  scene.generator = std::string(kProg) + " " + kLibraryVersion;
  std::vector<std::string> written;
  nlohmann::json report = nlohmann::json::array();
  for (size_t i = 0; i < objects->size(); ++i) {
    const bake::GltfObject& obj = (*objects)[i];
    const std::string& out = plan[i].path;
    nlohmann::json where = {{"scene", info.gltfScene}, {"mesh", obj.mesh}};
    if (obj.node >= 0) where["node"] = obj.node;
    WriteOptions fwo = wo;
    fwo.metadataJson = meshMetadata(o, bo, obj.geometry, info, false, where);
    removeStaleTemporaries(out);
    auto writer = Writer::create(out, plan[i].field, fwo);
    if (!writer) {
      removeAll(written);
      return cli::reportError(kProg, out, writer.error());
    }
    removeTemporaryOnSignal(out, written);
    auto embree = bake::Scene::create(obj.geometry, o.threads);
    if (!embree) {
      removeAll(written);
      return cli::reportError(kProg, o.mesh, embree.error());
    }
    cli::Progress progress(kProg, !o.quiet && !o.json && isatty(2), uint64_t(o.mapSize) * o.mapSize);
    bo.progress = [&](uint64_t d, uint64_t t) { progress.update(d, t); };
    auto baked = bake::bakeField(*embree, bo);
    if (!baked) {
      removeAll(written);
      return cli::reportError(kProg, o.mesh, baked.error());
    }
    double writeSeconds = 0;
    uint64_t fileBytes = 0;
    if (auto rc = writeBaked(o, out, *writer, *baked, &writeSeconds, &fileBytes)) {
      removeAll(written);
      return *rc;
    }
    written.push_back(out);

    SceneField f;
    f.uri = baseName(out);
    f.name = obj.name;
    nlohmann::json source = {{"file", baseName(o.mesh)}, {"mesh", obj.mesh}};
    if (obj.node >= 0) source["node"] = obj.node;
    f.sourceJson = source.dump();
    scene.fields.push_back(std::move(f));
    for (const bake::GltfPlacement& pl : obj.placements) {
      SceneInstance inst;
      inst.field = uint32_t(scene.fields.size() - 1);
      inst.name = pl.name;
      inst.translation = pl.translation;
      inst.rotation = pl.rotation;
      inst.scale = pl.scale;
      scene.instances.push_back(std::move(inst));
    }
    nlohmann::json entry = bakeSummary(bo, plan[i].field, baked->stats, plan[i].payload, baked->stats.seconds);
    entry.update({{"output", out}, {"name", obj.name}, {"mesh", obj.mesh}, {"instances", obj.placements.size()},
                  {"triangles", obj.geometry.triangleCount()}, {"fileBytes", fileBytes}});
    report.push_back(entry);
    if (!o.quiet && !o.json)
      std::fprintf(stderr, "%s: %s: object %zu/%zu (mesh %d%s, %zu triangles, %zu instance%s) -> %s\n", kProg,
                   o.mesh.c_str(), i + 1, objects->size(), obj.mesh,
                   obj.name.empty() ? "" : (" '" + obj.name + "'").c_str(), obj.geometry.triangleCount(),
                   obj.placements.size(), obj.placements.size() == 1 ? "" : "s", out.c_str());
  }
  // The description is written last: while it is missing, the scene is not there.
  removeTemporaryOnSignal(o.output, written);
  if (Status s = writeSceneDescription(o.output, scene); !s) {
    removeAll(written);
    return cli::reportError(kProg, o.output, s.error());
  }
  if (o.json) {
    nlohmann::json summary = {{"mesh", o.mesh}, {"scene", info.gltfScene}, {"split", o.split},
                              {"output", o.output}, {"fields", report}, {"instances", scene.instances.size()},
                              {"seconds", secondsSince(t0)}};
    std::printf("%s\n", summary.dump(2).c_str());
  } else if (!o.quiet) {
    std::fprintf(stderr, "%s: %s: %zu fields, %zu instances in %.2f s -> %s\n", kProg, o.mesh.c_str(),
                 scene.fields.size(), scene.instances.size(), secondsSince(t0), o.output.c_str());
  }
  return cli::kExitSuccess;
}

}  // namespace vff::bake_tool
