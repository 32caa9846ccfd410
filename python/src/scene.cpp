// scene.cpp - vff.Scene over vff::Scene (vff/scene.h) and vff.load_scene over vff::loadScene
// (vff/scene_description.h): many instances answered together, in batches from numpy arrays split
// over threads without the GIL, as FieldQuery and Instance are.
#include "batch.h"
#include "vff/scene_description.h"

namespace py = pybind11;

namespace vff::python {

namespace {

// A scene built in Python (its fields are vff.FieldQuery objects it keeps alive) or loaded from a
// scene description (the LoadedScene owns its files and fields).
struct PyScene {
  std::vector<py::object> fields;       // what a built scene's instances borrow
  std::unique_ptr<LoadedScene> loaded;  // a loaded scene's files, fields and scene
  Scene built;

  Scene& scene() { return loaded ? loaded->scene : built; }
  const Scene& scene() const { return loaded ? loaded->scene : built; }
};

// The scene's batch queries as the shared batch templates call them; only a committed scene is
// handed to them (every batch call then succeeds).
struct SceneTarget {
  const Scene* scene;
  const uint32_t* sources = nullptr;  // one per ray of the batch, or none
  void intersectAt(size_t first, std::span<const Ray> r, std::span<SceneHit> out, const QueryOptions& qo) const {
    if (sources) (void)scene->intersectFrom(r, std::span<const uint32_t>(sources + first, r.size()), out, qo);
    else (void)scene->intersect(r, out, qo);
  }
  void occludedAt(size_t first, std::span<const Ray> r, std::span<uint8_t> out, const QueryOptions& qo) const {
    if (sources) (void)scene->occludedFrom(r, std::span<const uint32_t>(sources + first, r.size()), out, qo);
    else (void)scene->occluded(r, out, qo);
  }
  void visibilityAt(size_t first, std::span<const Ray> r, std::span<float> out, const QueryOptions& qo) const {
    if (sources) (void)scene->visibilityFrom(r, std::span<const uint32_t>(sources + first, r.size()), out, qo);
    else (void)scene->visibility(r, out, qo);
  }
};

// The per-ray sources of a batch: None, or an (N,) integer array of instance ids, -1 for a ray
// that starts on no instance. Checked here, so that every batch call then succeeds.
std::vector<uint32_t> sourcesOf(const py::object& obj, const Scene& scene, size_t n) {
  std::vector<uint32_t> out;
  if (obj.is_none()) return out;
  if (!py::isinstance<py::array>(obj)) throw py::type_error("sources: expected None or an integer array of shape (N,)");
  py::array a = py::reinterpret_borrow<py::array>(obj);
  if (a.dtype().kind() != 'i' && a.dtype().kind() != 'u')
    throw py::type_error("sources: expected an integer array, got dtype " + std::string(py::str(py::handle(a.dtype()))));
  if (a.ndim() != 1 || size_t(a.shape(0)) != n)
    throw py::value_error("sources: expected shape (" + std::to_string(n) + ",), one instance id (or -1) per ray");
  py::array_t<int64_t, py::array::forcecast> v(a);
  out.resize(n);
  for (size_t i = 0; i < n; ++i) {
    const int64_t s = v.at(py::ssize_t(i));
    if (s < -1 || s >= int64_t(scene.size()))
      throw py::value_error("sources[" + std::to_string(i) + "] = " + std::to_string(s) + ": not an instance id (the scene has " +
                            std::to_string(scene.size()) + "; -1 for none)");
    out[i] = s < 0 ? kNoInstance : uint32_t(s);
  }
  return out;
}

uint32_t sourceOf(const py::object& obj, const Scene& scene) {
  if (obj.is_none()) return kNoInstance;
  const int64_t s = obj.cast<int64_t>();
  if (s < -1 || s >= int64_t(scene.size()))
    throw py::value_error("source = " + std::to_string(s) + ": not an instance id (the scene has " +
                          std::to_string(scene.size()) + "; -1 or None for none)");
  return s < 0 ? kNoInstance : uint32_t(s);
}

const Scene& committedScene(const PyScene& s) {
  if (!s.scene().committed())
    raise(makeError(Code::kBadState, "the scene changed since its last commit(): call commit() before querying"));
  return s.scene();
}

// The Hits to fill with a scene's answers: `out` when given (from an earlier Scene.intersect of
// the same length), else new arrays.
Hits sceneHitsFor(const py::object& out, size_t count) {
  const auto n = py::ssize_t(count);
  if (out.is_none()) {
    const ArrayBlock block({count, 4 * count, 12 * count, 12 * count, count, 4 * count});
    Hits h{block.array<bool>(0, {n}), block.array<float>(1, {n}), block.array<float>(2, {n, 3}),
           block.array<float>(3, {n, 3}), block.array<bool>(4, {n})};
    h.instance = block.array<int32_t>(5, {n});
    return h;
  }
  Hits h = hitsFor(out, count);
  if (h.instance.is_none()) throw py::type_error("out: expected the vff.Hits of an earlier Scene.intersect()");
  return h;
}

Hits sceneIntersect(const SceneTarget& target, const RayBatch& b, const py::object& reuse) {
  return fillHits<SceneHit>(target, b, sceneHitsFor(reuse, b.n));
}

Ray rayOf(const py::object& o, const py::object& d, float tmin, float tmax) {
  return checkedRay(Ray{vec3(o, "origin"), vec3(d, "direction"), tmin, tmax});  // (refused as a batch refuses it)
}

PyInstance instanceOf(const py::object& self, const PyScene& s, uint32_t id) {
  Instance in = take(s.scene().instance(id));
  // A built scene's instance keeps its vff.FieldQuery alive; a loaded one's keeps the scene.
  for (const py::object& f : s.fields)
    if (&f.cast<PyQuery&>().query == in.field) return PyInstance{f, in};
  return PyInstance{self, in};
}

constexpr const char* kSourcesDoc = R"doc(
sources: None, or an (N,) integer array: for each ray the id of the instance it starts on, -1 for
none (the ground, the static world). That instance answers the ray as 'on-object', every other as
'off-object' (ray_origin is then not used): what a renderer wants for rays from its G-buffer.)doc";

// A one-ray query: plain, or with the ray's source (None: the plain call, options.origin for
// every instance; an id or -1: the *From call).
template <class T>
T sceneRay(const PyScene& self, const Ray& ray, const QueryOptions& qo, const py::object& source,
           Result<T> (Scene::*plain)(const Ray&, const QueryOptions&) const,
           Result<T> (Scene::*from)(const Ray&, uint32_t, const QueryOptions&) const) {
  const Scene& scene = committedScene(self);
  if (source.is_none()) return take((scene.*plain)(ray, qo));
  return take((scene.*from)(ray, sourceOf(source, scene), qo));
}

void addSceneQueries(py::class_<PyScene>& c) {
  c.def("intersect", [](const PyScene& self, const py::object& o, const py::object& d, const py::object& tmin,
                        const py::object& tmax, bool interpolated, bool refined, float intraBias, const std::string& rayOrigin,
                        const py::object& sources, int64_t threads, const py::object& out) {
        const Scene& scene = committedScene(self);
        const RayBatch b = batchOf(o, d, tmin, tmax, interpolated, refined, intraBias, rayOrigin, threads);
        const std::vector<uint32_t> src = sourcesOf(sources, scene, b.n);
        return sceneIntersect(SceneTarget{&scene, src.empty() ? nullptr : src.data()}, b, out);
      },
      py::arg("origins"), py::arg("directions"), py::arg("tmin") = py::none(), py::arg("tmax") = py::none(), py::kw_only(),
      py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object", py::arg("sources") = py::none(), py::arg("threads") = 0u, py::arg("out") = py::none(),
      (std::string(kBatchDoc) + kSourcesDoc + "\nReturns a vff.Hits as Instance.intersect does, the nearest hit of any instance (of "
                                "hits at the same t, the lowest id's), with instance: (N,) int32, the id of the "
                                "instance hit, -1 for a miss. out: the Hits of an earlier Scene.intersect of the same "
                                "length, filled again. Raises vff.OperationError (bad-state) before a commit().").c_str());
  c.def("occluded", [](const PyScene& self, const py::object& o, const py::object& d, const py::object& tmin,
                       const py::object& tmax, bool interpolated, bool refined, float intraBias, const std::string& rayOrigin,
                       const py::object& sources, int64_t threads) {
        const Scene& scene = committedScene(self);
        const RayBatch b = batchOf(o, d, tmin, tmax, interpolated, refined, intraBias, rayOrigin, threads);
        const std::vector<uint32_t> src = sourcesOf(sources, scene, b.n);
        return occludedBatch(SceneTarget{&scene, src.empty() ? nullptr : src.data()}, b);
      },
      py::arg("origins"), py::arg("directions"), py::arg("tmin") = py::none(), py::arg("tmax") = py::none(), py::kw_only(),
      py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object", py::arg("sources") = py::none(), py::arg("threads") = 0u,
      (std::string(kBatchDoc) + kSourcesDoc + "\nReturns an (N,) bool array: some instance reports the ray occluded.").c_str());
  c.def("visibility", [](const PyScene& self, const py::object& o, const py::object& d, const py::object& tmin,
                       const py::object& tmax, bool interpolated, bool refined, float intraBias, const std::string& rayOrigin,
                       const py::object& sources, int64_t threads) {
        const Scene& scene = committedScene(self);
        const RayBatch b = batchOf(o, d, tmin, tmax, interpolated, refined, intraBias, rayOrigin, threads);
        const std::vector<uint32_t> src = sourcesOf(sources, scene, b.n);
        return visibilityBatch(SceneTarget{&scene, src.empty() ? nullptr : src.data()}, b);
      },
      py::arg("origins"), py::arg("directions"), py::arg("tmin") = py::none(), py::arg("tmax") = py::none(), py::kw_only(),
      py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object", py::arg("sources") = py::none(), py::arg("threads") = 0u,
      (std::string(kBatchDoc) + kSourcesDoc + "\nReturns an (N,) float32 array: the product, in id order, of the instances' "
                                "visibility (instances the ray never comes near give exactly 1).").c_str());
  c.def("intersect_ray", [](const PyScene& self, const py::object& o, const py::object& d, float tmin, float tmax,
                            bool interpolated, bool refined, float intraBias, const std::string& rayOrigin, const py::object& source) {
        const SceneHit h = sceneRay<SceneHit>(self, rayOf(o, d, tmin, tmax), optionsOf(interpolated, refined, intraBias, rayOrigin), source, &Scene::intersect,
                             &Scene::intersectFrom);
        py::tuple t = hitTuple(h);
        return py::make_tuple(t[0], t[1], t[2], t[3], t[4], h.instance == kNoInstance ? -1 : int64_t(h.instance));
      },
      py::arg("origin"), py::arg("direction"), py::arg("tmin") = 0.0f, py::arg("tmax") = std::numeric_limits<float>::infinity(),
      py::kw_only(), py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object",
      py::arg("source") = py::none(),
      "One ray, through libvff's one-ray call: (hit, t, point, normal, inside, instance), instance -1 for a miss. "
      "source: the instance the ray starts on, -1 for none (see the batch's sources), or None.");
  c.def("occluded_ray", [](const PyScene& self, const py::object& o, const py::object& d, float tmin, float tmax,
                           bool interpolated, bool refined, float intraBias, const std::string& rayOrigin, const py::object& source) {
        return sceneRay<bool>(self, rayOf(o, d, tmin, tmax), optionsOf(interpolated, refined, intraBias, rayOrigin), source, &Scene::occluded,
                             &Scene::occludedFrom);
      },
      py::arg("origin"), py::arg("direction"), py::arg("tmin") = 0.0f, py::arg("tmax") = std::numeric_limits<float>::infinity(),
      py::kw_only(), py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object",
      py::arg("source") = py::none(), "One ray: libvff's one-ray occluded(). source: the instance the ray starts on, -1 for none (see the batch's sources), or None.");
  c.def("visibility_ray", [](const PyScene& self, const py::object& o, const py::object& d, float tmin, float tmax,
                             bool interpolated, bool refined, float intraBias, const std::string& rayOrigin, const py::object& source) {
        return sceneRay<float>(self, rayOf(o, d, tmin, tmax), optionsOf(interpolated, refined, intraBias, rayOrigin), source, &Scene::visibility,
                             &Scene::visibilityFrom);
      },
      py::arg("origin"), py::arg("direction"), py::arg("tmin") = 0.0f, py::arg("tmax") = std::numeric_limits<float>::infinity(),
      py::kw_only(), py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object",
      py::arg("source") = py::none(), "One ray: libvff's one-ray visibility(). source: the instance the ray starts on, -1 for none (see the batch's sources), or None.");
  c.def("candidates", [](const PyScene& self, const py::object& o, const py::object& d, float tmin, float tmax) {
        return take(committedScene(self).candidates(rayOf(o, d, tmin, tmax)));
      },
      py::arg("origin"), py::arg("direction"), py::arg("tmin") = 0.0f, py::arg("tmax") = std::numeric_limits<float>::infinity(),
      "The ids of the instances whose (enlarged) world spheres the ray's [tmin, tmax] reaches, ascending: what the "
      "queries consider.");
}

}  // namespace

void bindScene(py::module_& m) {
  py::class_<PyScene> sc(m, "Scene", R"doc(
Many field instances answered together (vff/scene.h): a hierarchy over their world bounding
spheres, rebuilt by commit(). Its answers equal looping over its instances in id order: intersect
the nearest hit (the lowest id of equal t), occluded any, visibility the product. Instances are
moved with set_transform() between frames; queries need a commit() after any add() or
set_transform(). Keeps the FieldQuery objects of its instances alive.

    scene = vff.Scene()
    ids = [scene.add(q, translation=(2 * i, 0, 0)) for i in range(10)]
    scene.commit()
    hits = scene.intersect(origins, directions)     # hits.instance: which one, -1 for a miss)doc");
  sc.def(py::init([] { return std::make_unique<PyScene>(); }), "An empty scene (committed: every ray misses it).")
      .def("add", [](PyScene& self, const py::object& what, const py::object& rotation, const py::object& translation,
                     float scale) {
            if (self.loaded) throw py::type_error("add: a loaded scene is as its description places it; build a vff.Scene() to add");
            if (py::isinstance<PyInstance>(what)) {
              const PyInstance& in = what.cast<const PyInstance&>();
              if (!rotation.is_none() || scale != 1.0f)
                throw py::type_error("add: an Instance brings its own placement; give rotation, translation and scale "
                                     "only with a FieldQuery");
              const uint32_t id = take(self.built.add(in.instance.field, in.instance.transform));
              self.fields.push_back(in.owner);
              return id;
            }
            if (!py::isinstance<PyQuery>(what)) throw py::type_error("add: expected a vff.FieldQuery or a vff.Instance");
            PyQuery& q = what.cast<PyQuery&>();
            const uint32_t id = take(self.built.add(&q.query, transformOf(rotation, translation, scale)));
            self.fields.push_back(what);
            return id;
          },
          py::arg("field"), py::arg("rotation") = py::none(), py::arg("translation") = py::make_tuple(0, 0, 0),
          py::arg("scale") = 1.0f,
          "Adds an instance, a vff.Instance (its field and placement) or a vff.FieldQuery placed by rotation (3 x 3, "
          "row-major; None: identity), translation and scale as vff.Instance's; returns its id (0, 1, 2...). Raises "
          "vff.InvalidArgumentError for a transform that is not rigid.")
      .def("set_transform", [](PyScene& self, uint32_t id, const py::object& rotation, const py::object& translation, float scale) {
            check(self.scene().setTransform(id, transformOf(rotation, translation, scale)));
          },
          py::arg("id"), py::arg("rotation") = py::none(), py::arg("translation") = py::make_tuple(0, 0, 0),
          py::arg("scale") = 1.0f, "Moves instance `id` (needs a commit() before the next query).")
      .def("commit", [](PyScene& self) { check(self.scene().commit()); }, "Rebuilds the hierarchy over the instances.")
      .def_property_readonly("committed", [](const PyScene& self) { return self.scene().committed(); },
                             "No add() or set_transform() since the last commit().")
      .def("instance", [](const py::object& self, uint32_t id) { return instanceOf(self, self.cast<const PyScene&>(), id); },
           py::arg("id"), "Instance `id` as it stands, as a vff.Instance (raises vff.Error out-of-range).")
      .def("__len__", [](const PyScene& self) { return self.scene().size(); })
      .def_property_readonly("names", [](const PyScene& self) {
            std::vector<std::string> names;
            if (self.loaded)
              for (const SceneInstance& i : self.loaded->description.instances) names.push_back(i.name);
            else
              names.resize(self.scene().size());
            return names;
          }, "The instances' names from the scene description (empty strings for a built scene).");
  addSceneQueries(sc);

  m.def("load_scene", [](const std::string& path, const std::string& checksums) {
        ReadOptions ro;
        ro.checksums = checksumPolicy(checksums);
        Result<std::unique_ptr<LoadedScene>> r = [&] {
          py::gil_scoped_release unlocked;  // opens and decodes every field
          return loadScene(path, ro);
        }();
        auto s = std::make_unique<PyScene>();
        s->loaded = take(std::move(r));
        return s;
      },
      py::arg("path"), py::arg("checksums") = "all", R"doc(
Loads a scene description (spec/scene.md, as vff-bake --split writes): opens every field it lists
(checksums as vff.open's) and places its instances in a committed vff.Scene, instance i being the
description's instances[i]. Raises the vff.Error of the description or field that fails.)doc");
}

}  // namespace vff::python
