// scene_load.cpp - a scene description's fields opened and its instances placed (loadScene,
// vff/scene_description.h).
#include "vff/scene_description.h"

namespace vff {

Result<std::unique_ptr<LoadedScene>> loadScene(const std::string& path, const ReadOptions& options) {
  auto description = readSceneDescription(path);
  if (!description) return std::move(description).error();
  auto out = std::make_unique<LoadedScene>();
  out->description = std::move(*description);
  for (size_t i = 0; i < out->description.fields.size(); ++i) {
    const std::string file = resolveSceneUri(path, out->description.fields[i].uri);
    const std::string where = path + ": fields[" + std::to_string(i) + "] (" + file + "): ";
    auto f = File::open(file, options);
    if (!f) {
      Error e = std::move(f).error();
      e.message = where + e.message;
      return e;
    }
    out->files.push_back(std::make_unique<File>(std::move(*f)));
    auto q = FieldQuery::fromFile(*out->files.back());
    if (!q) {
      Error e = std::move(q).error();
      e.message = where + e.message;
      return e;
    }
    out->fields.push_back(std::make_unique<FieldQuery>(std::move(*q)));
  }
  for (size_t i = 0; i < out->description.instances.size(); ++i) {
    const SceneInstance& inst = out->description.instances[i];
    auto id = out->scene.add(out->fields[inst.field].get(), inst.rigidTransform());
    if (!id) {
      Error e = std::move(id).error();
      e.message = path + ": instances[" + std::to_string(i) + "]: " + e.message;
      return e;
    }
  }
  if (Status s = out->scene.commit(); !s) return std::move(s).error();
  return out;
}

}  // namespace vff
