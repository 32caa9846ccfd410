// bake.h - what vff-bake's parts share beyond one bake's options and output (tools/bake-job,
// bake_job.h, which also holds --merge): the temporary files on a signal (interrupt.cpp), and the bakes,
// from a mesh (mesh_bake.cpp), from an OpenVDB level set (levelset_bake.cpp), per glTF mesh or
// node (split_bake.cpp) and per glTF mesh into a .glb (glb_bake.cpp), the last two sharing how a
// set of outputs is put in place.
#pragma once

#include <sys/types.h>

#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "bake_job.h"
#include "vff/bake/gltf.h"

namespace vff::bake_tool {

// ---- The temporary file (interrupt.cpp) ---------------------------------------------------------
// Removes the temporaries of `output` (.NAME.tmp-PID-N beside it) left by processes that no longer
// exist; those of live processes stay.
void removeStaleTemporaries(const std::string& output);
// The folder of a path ("." for a bare name, "/" at the root).
std::string folderOf(const std::string& path);
// The process `pid` no longer exists (kill(pid, 0) says ESRCH): its temporaries are stale.
bool processIsGone(pid_t pid);
// Once the Writer of `output` exists: on SIGINT, SIGTERM or SIGHUP, its temporary is removed and the
// process ends killed by the signal (the old file at `output`, if any, stays as it was), and so are
// the files `finished` (the outputs this run completed before, which are incomplete without it). A
// signal ignored when this is called stays ignored. Each call replaces the previous one's paths.
void removeTemporaryOnSignal(const std::string& output, const std::vector<std::string>& finished = {});

// ---- The bakes; each returns the tool's exit code -----------------------------------------------
int bakeFromMesh(const Options& o, bake::BakeOptions bo, WriteOptions wo);      // mesh_bake.cpp
int bakeFromLevelSet(const Options& o, bake::BakeOptions bo, WriteOptions wo);  // levelset_bake.cpp
// --split: a field per mesh or node of a glTF scene and a scene description (split_bake.cpp).
int bakeGltfSplit(const Options& o, bake::BakeOptions bo, WriteOptions wo);
// glTF input, -o X.glb: a field per mesh attached to the asset (VFF_visibility_field), or beside it
// with --external-fields (glb_bake.cpp).
int bakeGltfGlb(const Options& o, bake::BakeOptions bo, WriteOptions wo);

// ---- A set of outputs put in place as one unit (split_bake.cpp, shared with glb_bake.cpp) ------
// Each output is written to a temporary beside it (.NAME.tmp-PID-0, the names interrupt.cpp knows);
// only when all of them are complete are they renamed into place, the fields first and the
// description (or .glb) last, with SIGINT, SIGTERM and SIGHUP held back until the renames are done.
struct Planned {
  std::string path;       // the field's file
  std::string temporary;  // where this run writes it until the whole set is complete
  FieldDesc field;
  uint64_t payload = 0;
};
// This run's temporary of `path`: DIR/.NAME.tmp-PID-0.
std::string temporaryOf(const std::string& path);
// Removes what a run killed outright left of `path`: its finished temporaries and the Writer's
// temporaries of those, whose process no longer exists.
void removeStaleSplitTemporaries(const std::string& path);
void removeAll(const std::vector<std::string>& paths);
// Writes `bytes` to `path` (a new file or replacing one of this process's), synced when `sync`.
Status writeText(const std::string& path, std::string_view bytes, bool sync);
// Every output must be a file the set can replace: a folder in the way fails before any baking
// (kIoWrite, exit 2). Returns the exit code then.
std::optional<int> checkOutputs(const std::vector<Planned>& plan, const std::string& output);
// Bakes `obj` into plan.temporary with the META of a field of one glTF object; *written gains the
// temporary; *entry: its --json summary. On a failure every temporary of *written is removed and
// the exit code returned.
std::optional<int> bakeObject(const Options& o, bake::BakeOptions bo, const WriteOptions& wo, const bake::GltfObject& obj,
                              const bake::MeshInfo& info, const Planned& plan, std::vector<std::string>* written,
                              nlohmann::json* entry);
// Renames the complete new set into place, `output` (from `outputTemporary`) last, and removes the
// fields of an earlier description at `output` that the new set does not replace (STEM: `output`
// without its extension). Returns the exit code of a failure.
std::optional<int> commitSet(const std::vector<Planned>& plan, const std::string& output,
                             const std::string& outputTemporary, const std::string& stem, bool sync);

// ---- Shared by the mesh bakes (mesh_bake.cpp) ----------------------------------------------------
// META of a field baked from `mesh` (read from o.mesh); `clipped`: a user sphere cuts it; `gltf`:
// where in a glTF file the object came from (split bakes), or null.
std::string meshMetadata(const Options& o, const bake::BakeOptions& bo, const bake::Mesh& mesh,
                         const bake::MeshInfo& info, bool clipped, const nlohmann::json& gltf = nullptr);
// Reports an error of loading `input`; returns the exit code (a scene the file lacks: usage, 1).
int reportLoadError(const Error& e, const std::string& input);
// The note that a glTF file has scenes this run does not bake (not with --quiet), and the warnings
// of MeshInfo::gltfNotes (always).
void noteUnbakedScenes(const Options& o, const bake::MeshInfo& info);

}  // namespace vff::bake_tool
