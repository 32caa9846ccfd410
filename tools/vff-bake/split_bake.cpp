// split_bake.cpp - vff-bake --split mesh|node: a glTF scene baked as separate rigid objects, a field
// each, and the scene description that places them (spec/scene.md).
//
// The set of fields and the description that names them replace an earlier set as one unit, or not
// at all. Every object is checked and planned before anything is written; each field and then the
// description are written to temporaries beside their outputs (.NAME.tmp-PID-N, the names
// interrupt.cpp knows); only when all of them are complete are they renamed into place, the fields
// first and the description last, with SIGINT, SIGTERM and SIGHUP held back until the renames are
// done. So at every instant an interrupt can stop the run, the description on disk is the old one
// with the old fields it names, or the new one with the new fields. An error or an interrupt before
// that removes this run's temporaries only. Fields of the old description that the new one no longer
// names (another --split) are removed once the new description is in place.
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <optional>
#include <regex>
#include <string_view>
#include <system_error>

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

}  // namespace

// This run's temporary of `path`: DIR/.NAME.tmp-PID-0, the pattern of the Writer's temporaries, so
// that removeStaleTemporaries(path) removes it once this process is gone (killed outright).
std::string temporaryOf(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  const std::string dir = slash == std::string::npos ? "" : path.substr(0, slash + 1);
  return dir + "." + baseName(path) + ".tmp-" + std::to_string(getpid()) + "-0";
}

// Removes what a split bake killed outright (SIGKILL, a crash) left of `path`: its finished
// temporaries (removeStaleTemporaries) and the Writer's temporaries of those, ..NAME.tmp-PID-0.tmp-PID-N,
// whose process no longer exists.
void removeStaleSplitTemporaries(const std::string& path) {
  removeStaleTemporaries(path);
  const std::string prefix = ".." + baseName(path) + ".tmp-";
  std::error_code ec;
  std::vector<std::filesystem::path> dead;
  for (std::filesystem::directory_iterator it(folderOf(path), ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const size_t digits = name.find_first_not_of("0123456789", prefix.size());
    if (digits == prefix.size() || digits == std::string::npos || digits - prefix.size() > 9 || name[digits] != '-')
      continue;
    if (processIsGone(pid_t(std::stol(name.substr(prefix.size(), digits - prefix.size())))))
      dead.push_back(it->path());
  }
  for (const auto& p : dead) std::filesystem::remove(p, ec);
}

void removeAll(const std::vector<std::string>& paths) {
  for (const std::string& p : paths) ::unlink(p.c_str());
}

Error ioError(const std::string& what) { return makeError(Code::kIoWrite, what + ": " + std::strerror(errno)); }

Status writeText(const std::string& path, std::string_view text, bool sync) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) return ioError(path + ": cannot be created");
  size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const Error e = ioError(path + ": write failed");
      ::close(fd);
      return e;
    }
    done += size_t(n);
  }
  if (sync && ::fsync(fd) != 0) {
    const Error e = ioError(path + ": fsync failed");
    ::close(fd);
    return e;
  }
  if (::close(fd) != 0) return ioError(path + ": close failed");
  return {};
}

void syncFolder(const std::string& path) {
  const int d = ::open(folderOf(path).c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (d < 0) return;
  ::fsync(d);
  ::close(d);
}

namespace {

// SIGINT, SIGTERM and SIGHUP while the new set is renamed into place: noted, not acted on, so that
// the renames are never cut short (from whichever thread takes the signal). finish() re-arms
// interrupt.cpp's handler with no temporaries left and re-raises the signal noted, which then ends
// the process as it would have. A signal the caller ignores stays ignored.
constexpr int kHeldSignals[] = {SIGINT, SIGTERM, SIGHUP};
volatile sig_atomic_t gHeldSignal = 0;
void holdSignal(int sig) { gHeldSignal = sig; }

class HeldSignals {
 public:
  HeldSignals() {
    gHeldSignal = 0;
    for (int sig : kHeldSignals) {
      struct sigaction old {}, act {};
      if (sigaction(sig, nullptr, &old) == 0 && old.sa_handler == SIG_IGN) continue;
      act.sa_handler = holdSignal;
      act.sa_flags = SA_RESTART;
      sigemptyset(&act.sa_mask);
      for (int other : kHeldSignals) sigaddset(&act.sa_mask, other);
      sigaction(sig, &act, nullptr);
    }
  }
  HeldSignals(const HeldSignals&) = delete;
  HeldSignals& operator=(const HeldSignals&) = delete;
  ~HeldSignals() { finish(); }
  // `output`: the description, whose temporaries (none by now) the re-armed handler would remove.
  void finish(const std::string& output = {}) {
    if (done_) return;
    done_ = true;
    if (!output.empty()) removeTemporaryOnSignal(output);
    if (const int sig = gHeldSignal) raise(sig);
  }

 private:
  bool done_ = false;
};

// The fields of the description now at `output` that the new set at `newPaths` does not replace and
// that an earlier split bake to this output wrote (STEM.meshI[.nodeJ].vff, STEM.nodeJ.vff beside
// it): removed once the new description is in place. Files it names otherwise are not this run's.
std::vector<std::string> staleFields(const std::string& output, const std::string& stem,
                                     const std::vector<std::string>& newPaths) {
  std::vector<std::string> stale;
  auto old = readSceneDescription(output);
  if (!old) return stale;
  const std::string own = baseName(stem);
  const std::regex pattern("(mesh[0-9]+(\\.node[0-9]+)?|node[0-9]+)\\.vff");
  auto isNew = [&](const std::string& name) {
    return std::any_of(newPaths.begin(), newPaths.end(), [&](const std::string& p) { return baseName(p) == name; });
  };
  for (const SceneField& f : old->fields) {
    // Only a bare name (beside the description, where the new fields go) of this stem's pattern.
    if (f.uri.find('/') != std::string::npos || f.uri.compare(0, own.size() + 1, own + ".") != 0) continue;
    if (!std::regex_match(f.uri.substr(own.size() + 1), pattern) || isNew(f.uri)) continue;
    const std::string path = resolveSceneUri(output, f.uri);
    if (std::find(stale.begin(), stale.end(), path) == stale.end()) stale.push_back(path);
  }
  return stale;
}

}  // namespace

std::optional<int> commitSet(const std::vector<Planned>& plan, const std::string& output,
                             const std::string& outputTemporary, const std::string& stem, bool sync) {
  std::vector<std::string> newPaths, temporaries;
  for (const Planned& p : plan) {
    newPaths.push_back(p.path);
    temporaries.push_back(p.temporary);
  }
  temporaries.push_back(outputTemporary);
  const std::vector<std::string> stale = staleFields(output, stem, newPaths);
  HeldSignals held;
  for (size_t i = 0; i < plan.size(); ++i) {
    if (::rename(plan[i].temporary.c_str(), plan[i].path.c_str()) != 0) {
      const Error e = ioError("cannot rename the temporary file to " + plan[i].path);
      removeAll(temporaries);
      held.finish(output);
      return cli::reportError(kProg, plan[i].path, e);
    }
  }
  if (sync) syncFolder(output);
  if (::rename(outputTemporary.c_str(), output.c_str()) != 0) {
    const Error e = ioError("cannot rename the temporary file to " + output);
    removeAll(temporaries);
    held.finish(output);
    return cli::reportError(kProg, output, e);
  }
  removeAll(stale);
  if (sync) syncFolder(output);
  held.finish(output);
  return std::nullopt;
}

std::optional<int> checkOutputs(const std::vector<Planned>& plan, const std::string& output) {
  std::vector<std::string> paths = {output};
  for (const Planned& p : plan) paths.push_back(p.path);
  for (const std::string& p : paths) {
    std::error_code ec;  // (a link to a folder is replaced, not followed)
    if (std::filesystem::symlink_status(p, ec).type() == std::filesystem::file_type::directory)
      return cli::reportError(kProg, p,
                              makeError(Code::kIoWrite, "a folder is there, which the output cannot replace"));
  }
  return std::nullopt;
}

std::optional<int> bakeObject(const Options& o, bake::BakeOptions bo, const WriteOptions& wo, const bake::GltfObject& obj,
                              const bake::MeshInfo& info, const Planned& plan, std::vector<std::string>* written,
                              nlohmann::json* entry) {
  const std::string& out = plan.path;
  const std::string& tmp = plan.temporary;
  nlohmann::json where = {{"scene", info.gltfScene}, {"mesh", obj.mesh}};
  if (obj.node >= 0) where["node"] = obj.node;
  WriteOptions fwo = wo;
  fwo.metadataJson = meshMetadata(o, bo, obj.geometry, info, false, where);
  removeStaleSplitTemporaries(out);
  auto writer = Writer::create(tmp, plan.field, fwo);
  if (!writer) {
    removeAll(*written);
    return cli::reportError(kProg, out, writer.error());
  }
  // The Writer renames its own temporary to `tmp` when it finishes: both go on an interrupt.
  written->push_back(tmp);
  removeTemporaryOnSignal(tmp, *written);
  auto embree = bake::Scene::create(obj.geometry, o.threads);
  if (!embree) {
    removeAll(*written);
    return cli::reportError(kProg, o.mesh, embree.error());
  }
  cli::Progress progress(kProg, !o.quiet && !o.json && isatty(2), uint64_t(o.mapSize) * o.mapSize);
  bo.progress = [&](uint64_t d, uint64_t t) { progress.update(d, t); };
  auto baked = bake::bakeField(*embree, bo);
  if (!baked) {
    removeAll(*written);
    return cli::reportError(kProg, o.mesh, baked.error());
  }
  double writeSeconds = 0;
  uint64_t fileBytes = 0;
  if (auto rc = writeBaked(o, tmp, *writer, *baked, &writeSeconds, &fileBytes)) {
    removeAll(*written);
    return *rc;
  }
  *entry = bakeSummary(bo, plan.field, baked->stats, plan.payload, baked->stats.seconds);
  entry->update({{"output", out}, {"name", obj.name}, {"mesh", obj.mesh}, {"instances", obj.placements.size()},
                 {"triangles", obj.geometry.triangleCount()}, {"fileBytes", fileBytes}});
  return std::nullopt;
}

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
    const std::string path = fieldPath(stem, obj, split);
    Planned p{path, temporaryOf(path), {}, 0};
    auto field = bake::describeBake(obj.geometry, bo);
    if (auto rc = checkPlan(field, wo.layout, &p.payload)) return *rc;
    p.field = *field;
    plan.push_back(std::move(p));
  }
  if (auto rc = checkOutputs(plan, o.output)) return *rc;

  SceneDescription scene;
  scene.generator = std::string(kProg) + " " + kLibraryVersion;
  std::vector<std::string> written;  // this run's temporaries, complete or being written
  nlohmann::json report = nlohmann::json::array();
  for (size_t i = 0; i < objects->size(); ++i) {
    const bake::GltfObject& obj = (*objects)[i];
    const std::string& out = plan[i].path;
    nlohmann::json entry;
    if (auto rc = bakeObject(o, bo, wo, obj, info, plan[i], &written, &entry)) return *rc;

    SceneField f;
    f.uri = encodeSceneUri(baseName(out));  // a file name the reader resolves back (spec/scene.md 3)
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
    report.push_back(entry);
    if (!o.quiet && !o.json)
      std::fprintf(stderr, "%s: %s: object %zu/%zu (mesh %d%s, %s, %s) -> %s\n", kProg, o.mesh.c_str(), i + 1,
                   objects->size(), obj.mesh, obj.name.empty() ? "" : (" '" + obj.name + "'").c_str(),
                   cli::count(obj.geometry.triangleCount(), "triangle").c_str(),
                   cli::count(obj.placements.size(), "instance").c_str(), out.c_str());
  }

  // The description, to its temporary too; then the whole set goes into place.
  const std::string descTmp = temporaryOf(o.output);
  removeStaleTemporaries(o.output);
  written.push_back(descTmp);
  removeTemporaryOnSignal(o.output, written);
  auto text = formatSceneDescription(scene);
  Status st = text ? writeText(descTmp, *text, wo.sync) : Status(text.error());
  if (!st) {
    removeAll(written);
    return cli::reportError(kProg, o.output, st.error());
  }
  if (auto rc = commitSet(plan, o.output, descTmp, stem, wo.sync)) return *rc;

  if (o.json) {
    nlohmann::json summary = {{"mesh", o.mesh}, {"scene", info.gltfScene}, {"split", o.split},
                              {"output", o.output}, {"fields", report}, {"instances", scene.instances.size()},
                              {"seconds", secondsSince(t0)}};
    std::printf("%s\n", summary.dump(2).c_str());
  } else if (!o.quiet) {
    std::fprintf(stderr, "%s: %s: %s, %s in %.2f s -> %s\n", kProg, o.mesh.c_str(),
                 cli::count(scene.fields.size(), "field").c_str(), cli::count(scene.instances.size(), "instance").c_str(),
                 secondsSince(t0), o.output.c_str());
  }
  return cli::kExitSuccess;
}

}  // namespace vff::bake_tool
