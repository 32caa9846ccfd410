// bake.cpp - vff.bake and vff.bake_file: the Embree baker (bake/) with vff-bake's options as
// keyword arguments. The bake runs on its own threads without the GIL; the calling thread reports
// progress to the callback and checks for Ctrl-C, which cancels the bake (KeyboardInterrupt).
#include <pybind11/stl.h>

#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <future>

#include "bindings.h"
#include "errors.h"
#include "vff/spelling.h"
#include "vff/bake/baker.h"
#include "vff/bake/mesh.h"

namespace py = pybind11;

namespace vff::python {

namespace {

template <class E>
E spelled(const vff::Spellings<E>& s, const std::string& text, const char* name) {
  if (auto v = s.parse(text)) return *v;
  std::string all;
  for (const auto& w : s.all()) all += (all.empty() ? "" : ", ") + w;
  throw py::value_error(std::string(name) + ": expected one of " + all + ", got \"" + text + "\"");
}

uint32_t defaultCount(PositionScheme s) {
  switch (s) {
    case PositionScheme::kEqualAreaOctaGrid: return 65;
    case PositionScheme::kSphericalFibonacci: return 4226;
    default: return 32;
  }
}

// The largest map_size, as vff-bake's -m: a field with larger maps exceeds the readers' default
// ReadOptions::maxMapResolution, so that vff.open and every tool would refuse the file it made.
constexpr int64_t kMaxBakeMapSize = 4096;

// A count without an upper bound of its own, as the option's u32 (larger ones become the largest,
// which the baker or writer then refuses with its own reason).
uint32_t u32(int64_t v) { return uint32_t(std::min<int64_t>(v, UINT32_MAX)); }

// vff-bake's options, from keyword arguments spelled as its long options (--map-size: map_size),
// with its ranges (a ValueError naming the argument and its range, as vff-bake's usage errors).
struct Options {
  bake::BakeOptions bake;
  WriteOptions write;
  bool refine = false, refineProbe = false;  // vff-bake's --refine and --refine-probe
  py::object progress = py::none();
};

Options optionsOf(const py::kwargs& kw) {
  Options o;
  std::string positions = "octa-hemi2", directions = "concentric", encoding = "unorm8-diameter";
  std::string codec = "stored", filter = "none", target = "2d-array";
  uint32_t count = 0;
  std::optional<std::vector<float>> center;
  float radius = 0;
  for (auto [k, v] : kw) {
    const std::string key = py::str(k);
    if (key == "positions") positions = v.cast<std::string>();
    else if (key == "count") count = u32(intArg(v, "count", 0, -1, " (0: the scheme's default)"));
    else if (key == "map_size") o.bake.mapResolution = uint32_t(intArg(v, "map_size", 1, kMaxBakeMapSize));
    else if (key == "directions") directions = v.cast<std::string>();
    else if (key == "encoding") encoding = v.cast<std::string>();
    else if (key == "normals") o.bake.normals = v.cast<bool>();
    else if (key == "threads") o.bake.threads = u32(intArg(v, "threads", 0, -1, " (0: all cores)"));
    else if (key == "center") center = v.cast<std::vector<float>>();
    else if (key == "radius") radius = v.cast<float>();
    else if (key == "codec") codec = v.cast<std::string>();
    else if (key == "zstd_level") o.write.zstdLevel = int(intArg(v, "zstd_level", 1, 22));
    else if (key == "maps_per_block") o.write.mapsPerBlock = u32(intArg(v, "maps_per_block", 0, -1, " (0: about 256 KiB per block)"));
    else if (key == "filter") filter = v.cast<std::string>();
    else if (key == "target") target = v.cast<std::string>();
    else if (key == "max_texture_size") o.write.layout.maxTextureSize = uint32_t(intArg(v, "max_texture_size", 1, 65536));
    else if (key == "max_layers") o.write.layout.maxLayers = uint32_t(intArg(v, "max_layers", 1, 65536));
    else if (key == "gutter") o.write.layout.gutter = uint32_t(intArg(v, "gutter", 0, 64));
    else if (key == "metadata") o.write.metadataJson = py::module_::import("json").attr("dumps")(v).cast<std::string>();
    else if (key == "refine") o.refine = v.cast<bool>();
    else if (key == "refine_probe") o.refineProbe = v.cast<bool>();
    else if (key == "progress") o.progress = py::reinterpret_borrow<py::object>(v);
    else throw py::type_error("bake: unexpected keyword argument '" + key + "'");
  }
  o.bake.positionScheme = spelled(vff::kPositionSchemes, positions, "positions");
  o.bake.positionParam = count ? count : defaultCount(o.bake.positionScheme);
  o.bake.directionScheme = spelled(vff::kDirectionSchemes, directions, "directions");
  o.bake.encoding = spelled(vff::kDistanceEncodings, encoding, "encoding");
  o.write.codec = spelled(vff::kCodecs, codec, "codec");
  if (filter == "hits-med") o.write.filter = Filter::kHitsMed;
  else if (filter != "none") throw py::value_error("filter: expected \"none\" or \"hits-med\", got \"" + filter + "\"");
  o.write.layout.target = spelled(vff::kLayoutTargets, target, "target");
  if (o.refineProbe && !o.refine) throw py::value_error("refine_probe goes with refine=True");
  if (o.refine && o.bake.encoding == DistanceEncoding::kBit1)
    throw py::value_error("refine needs distances; encoding \"bit1\" has none");
  if (center.has_value() != (radius > 0)) throw py::value_error("center and radius go together (radius > 0)");
  if (center) {
    if (center->size() != 3) throw py::value_error("center: expected 3 numbers");
    o.bake.sphere = Sphere{{(*center)[0], (*center)[1], (*center)[2]}, radius};
  }
  return o;
}

// Bakes `mesh` on worker threads. The calling thread holds the GIL only to call the progress
// callback (with maps done, maps total) and to check signals, every tenth of a second.
bake::BakedField bakeMesh(const bake::Mesh& mesh, Options& o) {
  std::atomic<bool> cancel{false};
  std::atomic<uint64_t> done{0}, total{0};
  o.bake.cancel = &cancel;
  o.bake.progress = [&](uint64_t d, uint64_t t) {
    total.store(t, std::memory_order_relaxed);
    uint64_t prev = done.load(std::memory_order_relaxed);
    while (d > prev && !done.compare_exchange_weak(prev, d, std::memory_order_relaxed)) {
    }
  };
  auto job = std::async(std::launch::async, [&]() -> Result<bake::BakedField> {
    auto scene = bake::Scene::create(mesh, o.bake.threads);
    if (!scene) return std::move(scene).error();
    return bake::bakeField(*scene, o.bake);
  });
  uint64_t reported = ~uint64_t{0};
  bool interrupted = false;
  while (true) {
    bool ready;
    {
      py::gil_scoped_release unlocked;
      ready = job.wait_for(std::chrono::milliseconds(100)) == std::future_status::ready;
    }
    if (!interrupted && PyErr_CheckSignals() != 0) {
      interrupted = true;
      cancel = true;
    }
    const uint64_t d = done.load();
    if (!interrupted && !o.progress.is_none() && d != reported && total.load()) {
      reported = d;
      try {
        o.progress(d, total.load());
      } catch (...) {
        cancel = true;
        py::gil_scoped_release unlocked;
        job.wait();
        throw;
      }
    }
    if (ready) break;
  }
  Result<bake::BakedField> r = job.get();
  if (interrupted) throw py::error_already_set();
  return take(std::move(r));
}

bake::Mesh meshOf(const py::object& vertices, const py::object& faces) {
  py::array_t<float, py::array::c_style | py::array::forcecast> v;
  try {
    v = vertices.cast<py::array_t<float, py::array::c_style | py::array::forcecast>>();
  } catch (const py::cast_error&) {
    throw py::type_error("vertices: expected an array of numbers of shape (V, 3)");
  }
  if (v.ndim() != 2 || v.shape(1) != 3) throw py::value_error("vertices: expected shape (V, 3)");
  py::array f = py::array::ensure(faces);
  if (!f || (f.dtype().kind() != 'i' && f.dtype().kind() != 'u'))
    throw py::type_error("faces: expected an integer array of shape (F, 3)");
  if (f.ndim() != 2 || f.shape(1) != 3) throw py::value_error("faces: expected shape (F, 3)");
  auto idx = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(f);
  bake::Mesh mesh;
  mesh.positions.assign(v.data(), v.data() + v.size());
  mesh.indices.reserve(size_t(idx.size()));
  for (py::ssize_t i = 0; i < idx.size(); ++i) {
    const int64_t k = idx.data()[i];
    if (k < 0 || k >= v.shape(0))
      raise(makeError(Code::kMeshIndex, "faces: index " + std::to_string(k) + " at position " + std::to_string(i) +
                                            " is outside the " + std::to_string(v.shape(0)) + " vertices"));
    mesh.indices.push_back(uint32_t(k));
  }
  check(bake::checkMesh(&mesh, "the mesh"));
  return mesh;
}

// Writes the baked field to `out` (atomically), or keeps it in memory; returns it opened. With
// refine, the refinement of `mesh` (makeRefinement) goes with it as REFN.
std::shared_ptr<PyFile> finish(const bake::BakedField& baked, const bake::Mesh& mesh, Options o, const std::string& out) {
  Result<std::vector<uint8_t>> bytes = makeError(Code::kBadState, "not written");
  Status written;
  Result<Refinement> refinement = Refinement{};
  {
    py::gil_scoped_release unlocked;
    if (o.refine) {
      refinement = makeRefinement(baked.field, baked.distance, mesh.positions, mesh.indices,
                                  {.probe = o.refineProbe, .threads = o.bake.threads});
      if (refinement) o.write.refinement = refinement->view();
    }
    if (refinement && out.empty())
      bytes = writeMemory(baked.field, baked.distance, baked.normals, o.write);
    else if (refinement)
      written = writeFile(out, baked.field, baked.distance, baked.normals, o.write);
  }
  if (!refinement) check(refinement.error());
  if (!out.empty()) {
    check(written);
    return openFile(out, "all");
  }
  auto f = File::openBuffer(take(std::move(bytes)));
  return std::make_shared<PyFile>(PyFile{"", take(std::move(f))});
}

constexpr const char* kOptionsDoc = R"doc(
Keyword arguments (vff-bake's options): positions ("octa-hemi2", "ea-octa-grid", "fibonacci"),
count (the scheme's n; 0: its default, 4226 maps), map_size (M in [1, 4096], 64), directions ("concentric",
"hemi-oct"), encoding ("unorm8-diameter", "unorm8-chord", "unorm16-diameter", "bit1",
"bc4-diameter"), normals (False), threads (0: all cores; the output does not depend on it), center
and radius (the bounding sphere; default the minimal enclosing one), codec ("stored", "zstd"),
zstd_level (1 to 22, 19), maps_per_block (0: about 256 KiB per block), filter ("none", "hits-med"),
target ("2d-array", "3d"), max_texture_size (1 to 65536, 2048), max_layers (1 to 65536, 2048), gutter
(0 to 64, 0), metadata (a dict
stored as META), refine (False: also store the refinement, section REFN: unsure texels and the
mesh, for FieldQuery's refined=True), refine_probe (False: with refine, test unsure texels with rays),
progress (a callable taking (maps done, maps total), called on the calling thread).
An integer outside its range (vff-bake's: map_size=0, threads=-1) raises ValueError naming it and
the range. Ctrl-C stops the bake (KeyboardInterrupt); a mesh problem raises vff.MeshError.)doc";

}  // namespace

void bindBake(py::module_& m) {
  m.def("bake", [](const py::object& vertices, const py::object& faces, const py::object& out, const py::kwargs& kw) {
        Options o = optionsOf(kw);
        const bake::Mesh mesh = meshOf(vertices, faces);
        const bake::BakedField baked = bakeMesh(mesh, o);
        return finish(baked, mesh, o, out.is_none() ? std::string() : out.cast<std::string>());
      },
      py::arg("vertices"), py::arg("faces"), py::arg("out") = py::none(),
      (std::string(R"doc(
Bakes a visibility field from a triangle mesh: vertices (V, 3) numbers, faces (F, 3) integer indices.
Writes it to `out` (atomically) when given; returns the field as a vff.File (in memory without out).)doc") + kOptionsDoc).c_str());
  m.def("bake_file", [](const std::string& path, const std::string& out, const py::kwargs& kw) {
        Options o = optionsOf(kw);
        bake::MeshInfo info;
        Result<bake::Mesh> mesh = [&] {
          py::gil_scoped_release unlocked;
          return bake::loadMesh(path, &info);
        }();
        const bake::Mesh loaded = take(std::move(mesh));
        // What the bake leaves out of a glTF file (extensions that change no geometry, skins, morph
        // targets): vff-bake's warnings, as Python warnings.
        for (const std::string& note : info.gltfNotes)
          if (PyErr_WarnEx(PyExc_UserWarning, (path + ": " + note).c_str(), 1) != 0) throw py::error_already_set();
        if (o.write.metadataJson.empty()) {
          const size_t slash = path.find_last_of('/');
          o.write.metadataJson = nlohmann::json{{"vff.generator", "vff (Python)"}, {"vff.generatorVersion", kLibraryVersion},
                                                {"vff.source", {{"name", slash == std::string::npos ? path : path.substr(slash + 1)},
                                                                {"format", info.format}}}}.dump();
        }
        const bake::BakedField baked = bakeMesh(loaded, o);
        return finish(baked, loaded, o, out);
      },
      py::arg("path"), py::arg("out"),
      (std::string(R"doc(
Bakes the mesh file at `path` (.obj, .ply, .off, .stl, .gltf, .glb) into the .vff file `out`, as
vff-bake does; returns the written file opened. What vff-bake warns about in a glTF file (a required
extension that changes no geometry and is not read, a skinned node baked in its bind pose, a mesh
with morph targets baked as its base shape) is a UserWarning naming the file.)doc") + kOptionsDoc).c_str());
}

}  // namespace vff::python
