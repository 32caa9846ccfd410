// vff/scene_description.h - scene descriptions (spec/scene.md): which fields a scene uses and where
// each copy of them stands.
//
// A scene description is a JSON file that lists fields (`.vff` files, by a reference relative to the
// description) and instances (a field placed by a uniform scale, a rotation and a translation, glTF's
// T * R * S). `vff-bake --split` writes one for the meshes or nodes of a glTF scene. Reading it
// checks every rule of spec/scene.md. loadScene() then opens every field and places the instances
// in a vff::Scene; a tool that loads, decodes or shares fields its own way opens them itself
// (File::open on resolveSceneUri()):
//
//   auto scene = vff::readSceneDescription("courtyard.vffscene.json");
//   if (!scene) { fprintf(stderr, "%s\n", scene.error().toString().c_str()); return; }
//   for (const vff::SceneField& f : scene->fields)
//     open(vff::resolveSceneUri("courtyard.vffscene.json", f.uri));
//   for (const vff::SceneInstance& i : scene->instances)
//     place(i.field, i.rigidTransform());
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "vff/error.h"
#include "vff/export.h"
#include "vff/query.h"
#include "vff/reader.h"
#include "vff/scene.h"

namespace vff {

inline constexpr int kSceneDescriptionVersion = 1;

struct SceneField {
  std::string uri;         // as written: a reference to the .vff file (resolveSceneUri decodes it)
  std::string name;        // may be empty
  std::string sourceJson;  // the `source` object as JSON text, or empty
};

struct VFF_API SceneInstance {
  uint32_t field = 0;                    // index into SceneDescription::fields
  std::string name;                      // may be empty
  Vec3 translation;                      // world = translation + rotate(rotation, scale * p)
  std::array<float, 4> rotation{0, 0, 0, 1};  // unit quaternion x, y, z, w
  float scale = 1.0f;                    // uniform, > 0
  std::string extrasJson;                // the instance's `extras` as JSON text, or empty

  // The same placement as libvff's transform (the quaternion as a rotation matrix).
  RigidTransform rigidTransform() const noexcept;
};

struct SceneDescription {
  std::string generator;  // asset.generator, may be empty
  std::vector<SceneField> fields;
  std::vector<SceneInstance> instances;
  std::string extrasJson;  // the top-level `extras` as JSON text, or empty
};

// Parses a description held in memory; `name` names it in messages. Every rule of spec/scene.md
// section 5 is checked, in the order of its table (the first error is the one that order finds):
// kSceneJson (11001: not one JSON text by section 1's rules, "NAME:LINE:COLUMN: PATH: what"; or not an
// object), kSceneVersion (11002: asset.format is not "vff-scene", or asset.version is not 1),
// kSceneValue (11003: a member missing or of the wrong type, a number not finite in binary32, a
// quaternion not of norm 1 within 1e-3, a scale not positive), kSceneUri (11004: a field's uri is not
// a file reference), kSceneFieldIndex (11005: an instance's field is not an index into fields). Value
// messages read "NAME: PATH: what", PATH the JSON location ("instances[3].rotation"). Numbers of
// translation, rotation and scale are rounded to binary32 first; rotations are normalised.
VFF_API Result<SceneDescription> parseSceneDescription(std::string_view json, const std::string& name);

// Reads and parses a file (kIoOpen, kIoRead; then as above, messages naming the file).
VFF_API Result<SceneDescription> readSceneDescription(const std::string& path);

// The description as JSON text: two-space indented, members in a fixed order, floats written with
// the fewest digits that read back to the same float, so that equal descriptions give equal bytes.
// Empty names, sources and extras are left out. It fails with kSceneValue on what
// parseSceneDescription would refuse (a field index out of range, a non-finite number, ...).
VFF_API Result<std::string> formatSceneDescription(const SceneDescription& scene);

// Writes formatSceneDescription's text to `path` atomically (a temporary file renamed over it):
// either the whole new file or the old one (kIoOpen, kIoWrite).
VFF_API Status writeSceneDescription(const std::string& path, const SceneDescription& scene);

// The path of a field's `uri` for a description read from `descriptionPath`: the uri's %XY escapes
// decoded (spec/scene.md section 3), then an absolute path ('/' first) as it is, a relative one
// joined to the description's folder. `uri` is one the reader accepted.
VFF_API std::string resolveSceneUri(const std::string& descriptionPath, const std::string& uri);

// The `uri` that names `path` (a file name or a relative or absolute path with '/' separators):
// '%', '?', '#', '\\' and control bytes percent-encoded, and a colon that would make a leading
// scheme (a drive letter, "a:b.vff") written %3A, so that the reader resolves it back to `path`.
// Writers of descriptions (vff-bake --split) name their fields with it.
VFF_API std::string encodeSceneUri(const std::string& path);

// A scene description with its fields open and its instances placed in a committed vff::Scene:
// instance i of the scene is description.instances[i]. It owns everything the scene borrows; it
// does not move (held by unique_ptr), so the scene's pointers to its fields stay valid.
struct LoadedScene {
  SceneDescription description;
  std::vector<std::unique_ptr<File>> files;         // one per description field, kept open
  std::vector<std::unique_ptr<FieldQuery>> fields;  // their queries (every block decoded once)
  Scene scene;                                      // committed
};

// Reads the description at `path`, opens every field it lists (resolveSceneUri) with `options`,
// and places the instances. Errors: those of readSceneDescription; those of File::open and
// FieldQuery::fromFile, the message naming the field's uri and the description; those of
// Scene::add for an instance (a transform checkTransform refuses), naming the instance.
VFF_API Result<std::unique_ptr<LoadedScene>> loadScene(const std::string& path, const ReadOptions& options = {});

// The rotation part of a transform as a unit quaternion x, y, z, w (w >= 0); `rotation` must be a
// rotation matrix (orthonormal, determinant +1).
VFF_API std::array<float, 4> quaternionFromRotation(const float rotation[3][3]) noexcept;

}  // namespace vff
