// query.cpp - vff.FieldQuery and vff.Instance: batches of rays from numpy arrays, answered by
// libvff's batch functions over threads with the GIL released, and the one-ray calls.
#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <optional>
#include <thread>

#include "arrays.h"
#include "bindings.h"
#include "errors.h"

namespace py = pybind11;

namespace vff::python {

namespace {

constexpr size_t kChunk = 4096;  // rays per batch call on one thread (its rays and answers stay in L2)

struct PyQuery {
  py::object owner;  // the vff.File whose maps the query borrows
  FieldQuery query;
};

struct PyInstance {
  py::object owner;  // the vff.FieldQuery the instance borrows
  Instance instance;
};

// The (N, 3) float32 array `name`, or a TypeError/ValueError naming what is expected.
py::array vectors(const py::object& obj, const char* name) {
  if (!py::isinstance<py::array>(obj))
    throw py::type_error(std::string(name) + ": expected a numpy float32 array of shape (N, 3), got " +
                         std::string(py::str(py::type::of(obj).attr("__name__"))));
  py::array a = py::reinterpret_borrow<py::array>(obj);
  const py::dtype dt = a.dtype();
  const bool f32 = dt.kind() == 'f' && dt.itemsize() == 4 && dt.attr("isnative").cast<bool>();
  std::string shape = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) shape += (i ? ", " : "") + std::to_string(a.shape(i));
  shape += a.ndim() == 1 ? ",)" : ")";
  if (!f32)
    throw py::type_error(std::string(name) + ": expected dtype float32, got " + std::string(py::str(py::handle(dt))) +
                         " (convert with .astype(numpy.float32))");
  if (a.ndim() != 2 || a.shape(1) != 3)
    throw py::value_error(std::string(name) + ": expected shape (N, 3), got " + shape);
  return a;
}

// A per-ray bound: None (the default), a number, or an (N,) float32 array.
struct Bound {
  float value = 0;
  std::optional<py::array> array;
  float at(const uint8_t* base, py::ssize_t stride, size_t i) const {
    return array ? *reinterpret_cast<const float*>(base + py::ssize_t(i) * stride) : value;
  }
};
Bound bound(const py::object& obj, const char* name, float fallback, size_t n) {
  Bound b{fallback, std::nullopt};
  if (obj.is_none()) return b;
  if (!py::isinstance<py::array>(obj)) {
    try {
      b.value = obj.cast<float>();
    } catch (const py::cast_error&) {
      throw py::type_error(std::string(name) + ": expected None, a number or a float32 array of shape (N,)");
    }
    return b;
  }
  py::array a = py::reinterpret_borrow<py::array>(obj);
  const py::dtype dt = a.dtype();
  if (!(dt.kind() == 'f' && dt.itemsize() == 4 && dt.attr("isnative").cast<bool>()))
    throw py::type_error(std::string(name) + ": expected dtype float32, got " + std::string(py::str(py::handle(dt))));
  if (a.ndim() != 1 || size_t(a.shape(0)) != n)
    throw py::value_error(std::string(name) + ": expected shape (" + std::to_string(n) + ",), one per ray");
  b.array = a;
  return b;
}

// The rays of a call, read from the caller's arrays whatever their strides.
struct RayBatch {
  const uint8_t* o;
  const uint8_t* d;
  py::ssize_t os0, os1, ds0, ds1;
  Bound tmin, tmax;
  const uint8_t* tminData = nullptr;
  const uint8_t* tmaxData = nullptr;
  py::ssize_t tminStride = 0, tmaxStride = 0;
  size_t n = 0;
  QueryOptions options;
  unsigned threads = 0;

  void fill(size_t first, size_t count, Ray* out) const {
    if (os0 == 12 && os1 == 4 && ds0 == 12 && ds1 == 4 && !tmin.array && !tmax.array) {
      // C-order arrays, the usual case: straight loads the compiler can vectorise.
      const float* po = reinterpret_cast<const float*>(o) + 3 * first;
      const float* pd = reinterpret_cast<const float*>(d) + 3 * first;
      for (size_t k = 0; k < count; ++k)
        out[k] = Ray{{po[3 * k], po[3 * k + 1], po[3 * k + 2]}, {pd[3 * k], pd[3 * k + 1], pd[3 * k + 2]}, tmin.value,
                     tmax.value};
      return;
    }
    for (size_t k = 0; k < count; ++k) {
      const size_t i = first + k;
      auto f = [](const uint8_t* base, py::ssize_t s0, py::ssize_t s1, size_t r, int c) {
        return *reinterpret_cast<const float*>(base + py::ssize_t(r) * s0 + c * s1);
      };
      out[k] = Ray{{f(o, os0, os1, i, 0), f(o, os0, os1, i, 1), f(o, os0, os1, i, 2)},
                   {f(d, ds0, ds1, i, 0), f(d, ds0, ds1, i, 1), f(d, ds0, ds1, i, 2)},
                   tmin.at(tminData, tminStride, i), tmax.at(tmaxData, tmaxStride, i)};
    }
  }
};

RayBatch batchOf(const py::object& origins, const py::object& directions, const py::object& tmin,
                 const py::object& tmax, bool interpolated, float intraBias, unsigned threads) {
  py::array o = vectors(origins, "origins"), d = vectors(directions, "directions");
  if (o.shape(0) != d.shape(0))
    throw py::value_error("origins and directions differ in length: " + std::to_string(o.shape(0)) + " and " +
                          std::to_string(d.shape(0)) + " rays");
  RayBatch b;
  b.n = size_t(o.shape(0));
  b.o = static_cast<const uint8_t*>(o.data());
  b.d = static_cast<const uint8_t*>(d.data());
  b.os0 = o.strides(0), b.os1 = o.strides(1), b.ds0 = d.strides(0), b.ds1 = d.strides(1);
  b.tmin = bound(tmin, "tmin", 0.0f, b.n);
  b.tmax = bound(tmax, "tmax", std::numeric_limits<float>::infinity(), b.n);
  if (b.tmin.array) b.tminData = static_cast<const uint8_t*>(b.tmin.array->data()), b.tminStride = b.tmin.array->strides(0);
  if (b.tmax.array) b.tmaxData = static_cast<const uint8_t*>(b.tmax.array->data()), b.tmaxStride = b.tmax.array->strides(0);
  b.options.reconstruction = interpolated ? Reconstruction::kInterpolated : Reconstruction::kNearest;
  b.options.intraBias = intraBias;
  b.threads = threads ? threads : std::max(1u, std::thread::hardware_concurrency());
  return b;
}

// Runs work(first, count, rays) over the batch's chunks on its threads, without the GIL.
template <class Work>
void parallel(const RayBatch& b, Work work) {
  py::gil_scoped_release unlocked;
  const size_t chunks = (b.n + kChunk - 1) / kChunk;
  std::atomic<size_t> next{0};
  auto run = [&] {
    std::vector<Ray> rays(std::min(kChunk, b.n));
    for (size_t c; (c = next.fetch_add(1)) < chunks;) {
      const size_t first = c * kChunk, count = std::min(kChunk, b.n - first);
      b.fill(first, count, rays.data());
      work(first, std::span<const Ray>(rays.data(), count));
    }
  };
  const unsigned n = unsigned(std::min<size_t>(b.threads, chunks));
  std::vector<std::thread> pool;
  for (unsigned t = 1; t < n; ++t) pool.emplace_back(run);
  run();
  for (auto& t : pool) t.join();
}

// Hits as numpy arrays.
struct Hits {
  py::array_t<bool> hit;
  py::array_t<float> t, point, normal;
  py::array_t<bool> inside;
};

// The Hits to fill: `out` when given (its arrays must hold n rays), else new arrays.
Hits hitsFor(const py::object& out, size_t count) {
  const auto n = py::ssize_t(count);
  if (out.is_none()) {
    const ArrayBlock block({count, 4 * count, 12 * count, 12 * count, count});
    return Hits{block.array<bool>(0, {n}), block.array<float>(1, {n}), block.array<float>(2, {n, 3}),
                block.array<float>(3, {n, 3}), block.array<bool>(4, {n})};
  }
  if (!py::isinstance<Hits>(out)) throw py::type_error("out: expected a vff.Hits from an earlier intersect()");
  Hits h = out.cast<Hits>();
  if (h.hit.size() != n)
    throw py::value_error("out: holds " + std::to_string(h.hit.size()) + " rays, the call has " + std::to_string(n));
  return h;
}

template <class Target>
Hits intersectBatch(const Target& target, const RayBatch& b, const py::object& reuse) {
  Hits h = hitsFor(reuse, b.n);
  bool* hit = h.hit.mutable_data();
  float* t = h.t.mutable_data();
  float* point = h.point.mutable_data();
  float* normal = h.normal.mutable_data();
  bool* inside = h.inside.mutable_data();
  const QueryOptions qo = b.options;
  parallel(b, [&](size_t first, std::span<const Ray> rays) {
    thread_local std::vector<QueryHit> out;
    out.resize(rays.size());
    target.intersect(rays, out, qo);
    const float nan = std::numeric_limits<float>::quiet_NaN();
    for (size_t k = 0; k < rays.size(); ++k) {
      const QueryHit& q = out[k];
      const size_t i = first + k;
      hit[i] = q.hit, t[i] = q.t, inside[i] = q.inside;
      float* p = point + 3 * i;
      float* nm = normal + 3 * i;
      p[0] = q.hit ? q.point.x : nan, p[1] = q.hit ? q.point.y : nan, p[2] = q.hit ? q.point.z : nan;
      nm[0] = q.hasNormal ? q.normal.x : nan, nm[1] = q.hasNormal ? q.normal.y : nan, nm[2] = q.hasNormal ? q.normal.z : nan;
    }
  });
  return h;
}

template <class Target>
py::array_t<bool> occludedBatch(const Target& target, const RayBatch& b) {
  py::array_t<bool> out = ArrayBlock({b.n}).array<bool>(0, {py::ssize_t(b.n)});
  uint8_t* dst = reinterpret_cast<uint8_t*>(out.mutable_data());
  const QueryOptions qo = b.options;
  parallel(b, [&](size_t first, std::span<const Ray> rays) {
    target.occluded(rays, std::span<uint8_t>(dst + first, rays.size()), qo);
    for (size_t k = 0; k < rays.size(); ++k) dst[first + k] = dst[first + k] ? 1 : 0;  // numpy bools are 0 or 1
  });
  return out;
}

template <class Target>
py::array_t<float> visibilityBatch(const Target& target, const RayBatch& b) {
  py::array_t<float> out = ArrayBlock({4 * b.n}).array<float>(0, {py::ssize_t(b.n)});
  float* dst = out.mutable_data();
  const QueryOptions qo = b.options;
  parallel(b, [&](size_t first, std::span<const Ray> rays) {
    target.visibility(rays, std::span<float>(dst + first, rays.size()), qo);
  });
  return out;
}

Vec3 vec3(const py::object& o, const char* name) {
  auto v = o.cast<std::vector<float>>();
  if (v.size() != 3) throw py::value_error(std::string(name) + ": expected 3 numbers, got " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

QueryOptions optionsOf(bool interpolated, float intraBias) {
  QueryOptions qo;
  qo.reconstruction = interpolated ? Reconstruction::kInterpolated : Reconstruction::kNearest;
  qo.intraBias = intraBias;
  return qo;
}

py::tuple hitTuple(const QueryHit& h) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  return py::make_tuple(h.hit, h.t, h.hit ? py::make_tuple(h.point.x, h.point.y, h.point.z) : py::make_tuple(nan, nan, nan),
                        h.hasNormal ? py::make_tuple(h.normal.x, h.normal.y, h.normal.z) : py::make_tuple(nan, nan, nan),
                        h.inside);
}

constexpr const char* kBatchDoc = R"doc(
Answers a batch of rays. origins, directions: float32 arrays of shape (N, 3), any strides;
directions need not be unit length (t is in multiples of them). tmin, tmax: None (0 and infinity),
a number, or a float32 array of shape (N,). interpolated: the miss-aware blend instead of the
paper's nearest lookup. intra_bias: for rays from inside the sphere, a fraction of R (negative: the
field's default). threads: 0 for all cores; the answers do not depend on it. The GIL is released.)doc";

// The batch and one-ray methods every query class has.
template <class Py, class Get>
void addQueries(py::class_<Py>& c, Get get) {
  c.def("intersect", [get](const Py& self, const py::object& o, const py::object& d, const py::object& tmin, const py::object& tmax,
                           bool interpolated, float intraBias, unsigned threads, const py::object& out) {
        return intersectBatch(get(self), batchOf(o, d, tmin, tmax, interpolated, intraBias, threads), out);
      },
      py::arg("origins"), py::arg("directions"), py::arg("tmin") = py::none(), py::arg("tmax") = py::none(), py::kw_only(),
      py::arg("interpolated") = false, py::arg("intra_bias") = -1.0f, py::arg("threads") = 0u, py::arg("out") = py::none(),
      (std::string(kBatchDoc) + "\nReturns a vff.Hits: hit (N,) bool, t (N,) float32 (inf for a miss), point (N, 3) and "
                                "normal (N, 3) float32 (NaN where there is none), inside (N,) bool. out: the Hits of an "
                                "earlier call of the same length, filled again instead of new arrays (fresh arrays "
                                "cost the first touch of their memory; a loop over batches saves it).").c_str());
  c.def("occluded", [get](const Py& self, const py::object& o, const py::object& d, const py::object& tmin, const py::object& tmax,
                          bool interpolated, float intraBias, unsigned threads) {
        return occludedBatch(get(self), batchOf(o, d, tmin, tmax, interpolated, intraBias, threads));
      },
      py::arg("origins"), py::arg("directions"), py::arg("tmin") = py::none(), py::arg("tmax") = py::none(), py::kw_only(),
      py::arg("interpolated") = false, py::arg("intra_bias") = -1.0f, py::arg("threads") = 0u,
      (std::string(kBatchDoc) + "\nReturns an (N,) bool array: the ray hits the object within [tmin, tmax].").c_str());
  c.def("visibility", [get](const Py& self, const py::object& o, const py::object& d, const py::object& tmin, const py::object& tmax,
                            bool interpolated, float intraBias, unsigned threads) {
        return visibilityBatch(get(self), batchOf(o, d, tmin, tmax, interpolated, intraBias, threads));
      },
      py::arg("origins"), py::arg("directions"), py::arg("tmin") = py::none(), py::arg("tmax") = py::none(), py::kw_only(),
      py::arg("interpolated") = false, py::arg("intra_bias") = -1.0f, py::arg("threads") = 0u,
      (std::string(kBatchDoc) + "\nReturns an (N,) float32 array: the probability that each ray reaches tmax unoccluded "
                                "(0 or 1 with nearest).").c_str());
  c.def("intersect_ray", [get](const Py& self, const py::object& o, const py::object& d, float tmin, float tmax, bool interpolated,
                               float intraBias) {
        return hitTuple(get(self).intersect(Ray{vec3(o, "origin"), vec3(d, "direction"), tmin, tmax}, optionsOf(interpolated, intraBias)));
      },
      py::arg("origin"), py::arg("direction"), py::arg("tmin") = 0.0f, py::arg("tmax") = std::numeric_limits<float>::infinity(),
      py::kw_only(), py::arg("interpolated") = false, py::arg("intra_bias") = -1.0f,
      "One ray, through libvff's one-ray call: (hit, t, point, normal, inside) with point and normal as (x, y, z) tuples.");
  c.def("occluded_ray", [get](const Py& self, const py::object& o, const py::object& d, float tmin, float tmax, bool interpolated,
                              float intraBias) {
        return get(self).occluded(Ray{vec3(o, "origin"), vec3(d, "direction"), tmin, tmax}, optionsOf(interpolated, intraBias));
      },
      py::arg("origin"), py::arg("direction"), py::arg("tmin") = 0.0f, py::arg("tmax") = std::numeric_limits<float>::infinity(),
      py::kw_only(), py::arg("interpolated") = false, py::arg("intra_bias") = -1.0f, "One ray: libvff's one-ray occluded().");
  c.def("visibility_ray", [get](const Py& self, const py::object& o, const py::object& d, float tmin, float tmax, bool interpolated,
                                float intraBias) {
        return get(self).visibility(Ray{vec3(o, "origin"), vec3(d, "direction"), tmin, tmax}, optionsOf(interpolated, intraBias));
      },
      py::arg("origin"), py::arg("direction"), py::arg("tmin") = 0.0f, py::arg("tmax") = std::numeric_limits<float>::infinity(),
      py::kw_only(), py::arg("interpolated") = false, py::arg("intra_bias") = -1.0f, "One ray: libvff's one-ray visibility().");
}

RigidTransform transformOf(const py::object& rotation, const py::object& translation, float scale) {
  RigidTransform t;
  if (!rotation.is_none()) {
    py::array_t<float, py::array::c_style | py::array::forcecast> r(rotation);
    if (r.ndim() != 2 || r.shape(0) != 3 || r.shape(1) != 3) throw py::value_error("rotation: expected a 3 x 3 matrix");
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j) t.rotation[i][j] = r.at(i, j);
  }
  t.translation = vec3(translation, "translation");
  if (!(scale > 0)) throw py::value_error("scale: expected a number > 0");
  t.scale = scale;
  return t;
}

}  // namespace

void bindQuery(py::module_& m) {
  py::class_<Hits>(m, "Hits", "The answers of a batch intersect(): numpy arrays, one entry per ray.")
      .def_readonly("hit", &Hits::hit, "(N,) bool: the ray hit the object within [tmin, tmax].")
      .def_readonly("t", &Hits::t, "(N,) float32: the hit's distance in multiples of the direction (inf for a miss).")
      .def_readonly("point", &Hits::point, "(N, 3) float32: origin + t * direction (NaN for a miss).")
      .def_readonly("normal", &Hits::normal, "(N, 3) float32: the unit surface normal (NaN without one).")
      .def_readonly("inside", &Hits::inside, "(N,) bool: the origin was inside the bounding sphere.")
      .def("__len__", [](const Hits& h) { return h.hit.size(); })
      .def("__iter__", [](const Hits& h) { return py::iter(py::make_tuple(h.hit, h.t, h.point, h.normal)); },
           "hit, t, point, normal = query.intersect(...)");

  py::class_<PyQuery> fq(m, "FieldQuery", R"doc(
A query-ready view of one field: answers rays in the object's space (spec/geometry.md section 7).
Keeps its File alive.)doc");
  fq.def(py::init([](const std::shared_ptr<PyFile>& f) {
           Result<FieldQuery> q = [&] {
             py::gil_scoped_release unlocked;  // decodes every compressed block once
             return FieldQuery::fromFile(f->file);
           }();
           return PyQuery{py::cast(f), take(std::move(q))};
         }),
         py::arg("file"), "Makes the query of an open vff.File (decoding its compressed blocks once).")
      .def_property_readonly("file", [](const PyQuery& q) { return q.owner; }, "The vff.File it reads.")
      .def_property_readonly("payload_bytes", [](const PyQuery& q) { return q.query.payloadBytes(); }, "Bytes of the maps it reads.")
      .def_property_readonly("has_normals", [](const PyQuery& q) { return q.query.hasNormals(); }, "The field has normals.");
  addQueries(fq, [](const PyQuery& q) -> const FieldQuery& { return q.query; });

  py::class_<PyInstance> in(m, "Instance", R"doc(
A field placed in a world: world = translation + scale * (rotation @ object). Answers world-space
rays; t is the same parameter as in object space. Keeps its FieldQuery alive.)doc");
  in.def(py::init([](py::object field, const py::object& rotation, const py::object& translation, float scale) {
           auto& q = field.cast<PyQuery&>();
           return PyInstance{field, Instance{&q.query, transformOf(rotation, translation, scale)}};
         }),
         py::arg("field"), py::arg("rotation") = py::none(), py::arg("translation") = py::make_tuple(0, 0, 0),
         py::arg("scale") = 1.0f, "rotation: a 3 x 3 orthonormal matrix (row-major; None: identity).")
      .def_static("from_axis_angle", [](py::object field, const py::object& axis, float radians, const py::object& translation, float scale) {
            auto& q = field.cast<PyQuery&>();
            if (!(scale > 0)) throw py::value_error("scale: expected a number > 0");
            const Vec3 a = vec3(axis, "axis");
            if (a.x == 0 && a.y == 0 && a.z == 0) throw py::value_error("axis: expected a non-zero vector");
            return PyInstance{field, Instance{&q.query, RigidTransform::fromAxisAngle(a, radians, vec3(translation, "translation"), scale)}};
          },
          py::arg("field"), py::arg("axis"), py::arg("radians"), py::arg("translation") = py::make_tuple(0, 0, 0),
          py::arg("scale") = 1.0f, "A rotation of `radians` about `axis`, then the scale, then the translation.")
      .def_property_readonly("field", [](const PyInstance& i) { return i.owner; }, "The vff.FieldQuery it places.")
      .def_property_readonly("rotation", [](const PyInstance& i) {
            py::array_t<float> r({3, 3});
            for (int a = 0; a < 3; ++a)
              for (int b = 0; b < 3; ++b) r.mutable_at(a, b) = i.instance.transform.rotation[a][b];
            return r;
          }, "The 3 x 3 rotation (a copy).")
      .def_property_readonly("translation", [](const PyInstance& i) {
            const Vec3 t = i.instance.transform.translation;
            return py::make_tuple(t.x, t.y, t.z);
          }, "The translation.")
      .def_property_readonly("scale", [](const PyInstance& i) { return i.instance.transform.scale; }, "The uniform scale.")
      .def_property_readonly("world_sphere", [](const PyInstance& i) {
            const Sphere s = i.instance.worldSphere();
            return py::make_tuple(py::make_tuple(s.center[0], s.center[1], s.center[2]), s.radius);
          }, "The bounding sphere in world space: ((x, y, z), radius).");
  addQueries(in, [](const PyInstance& i) -> const Instance& { return i.instance; });
}

}  // namespace vff::python
