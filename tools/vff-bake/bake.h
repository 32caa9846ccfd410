// bake.h - what vff-bake's parts share beyond one bake's options and output (tools/bake-job,
// bake_job.h, which also holds --merge): the temporary files on a signal (interrupt.cpp), and the bakes,
// from a mesh (mesh_bake.cpp), from an OpenVDB level set (levelset_bake.cpp) and per glTF mesh or
// node (split_bake.cpp).
#pragma once

#include <sys/types.h>

#include <string>
#include <vector>

#include "bake_job.h"

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
