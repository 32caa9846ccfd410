// query.cpp - vff.FieldQuery and vff.Instance: batches of rays from numpy arrays, answered by
// libvff's batch functions over threads with the GIL released, and the one-ray calls.
#include "batch.h"

namespace py = pybind11;

namespace vff::python {

namespace {

template <class Target>
py::tuple sitesBatch(const Target& target, const RayBatch& b) {
  const ArrayBlock block({4 * b.n, 8 * b.n});
  py::array_t<int32_t> sample = block.array<int32_t>(0, {py::ssize_t(b.n)});
  py::array_t<int32_t> texel = block.array<int32_t>(1, {py::ssize_t(b.n), py::ssize_t(2)});
  int32_t* ks = sample.mutable_data();
  int32_t* ij = texel.mutable_data();
  const QueryOptions qo = b.options;
  parallel(b, [&](size_t first, std::span<const Ray> rays) {
    thread_local std::vector<LookupSite> out;
    out.resize(rays.size());
    target.sites(rays, out, qo);
    for (size_t k = 0; k < rays.size(); ++k) {
      const LookupSite& s = out[k];
      const size_t i = first + k;
      ks[i] = s.valid ? int32_t(s.sample) : -1;
      ij[2 * i] = s.valid ? int32_t(s.i) : -1;
      ij[2 * i + 1] = s.valid ? int32_t(s.j) : -1;
    }
  });
  return py::make_tuple(sample, texel);
}

// The batch and one-ray methods every query class has.
template <class Py, class Get>
void addQueries(py::class_<Py>& c, Get get) {
  c.def("intersect", [get](const Py& self, const py::object& o, const py::object& d, const py::object& tmin, const py::object& tmax,
                           bool interpolated, bool refined, float intraBias, const std::string& rayOrigin, int64_t threads, const py::object& out) {
        return intersectBatch(get(self), batchOf(o, d, tmin, tmax, interpolated, refined, intraBias, rayOrigin, threads), out);
      },
      py::arg("origins"), py::arg("directions"), py::arg("tmin") = py::none(), py::arg("tmax") = py::none(), py::kw_only(),
      py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object", py::arg("threads") = 0u, py::arg("out") = py::none(),
      (std::string(kBatchDoc) + "\nReturns a vff.Hits: hit (N,) bool, t (N,) float32 (inf for a miss), point (N, 3) and "
                                "normal (N, 3) float32 (NaN where there is none), inside (N,) bool. out: the Hits of an "
                                "earlier call of the same length, filled again instead of new arrays (fresh arrays "
                                "cost the first touch of their memory; a loop over batches saves it).").c_str());
  c.def("occluded", [get](const Py& self, const py::object& o, const py::object& d, const py::object& tmin, const py::object& tmax,
                          bool interpolated, bool refined, float intraBias, const std::string& rayOrigin, int64_t threads) {
        return occludedBatch(get(self), batchOf(o, d, tmin, tmax, interpolated, refined, intraBias, rayOrigin, threads));
      },
      py::arg("origins"), py::arg("directions"), py::arg("tmin") = py::none(), py::arg("tmax") = py::none(), py::kw_only(),
      py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object", py::arg("threads") = 0u,
      (std::string(kBatchDoc) + "\nReturns an (N,) bool array: the ray hits the object within [tmin, tmax].").c_str());
  c.def("visibility", [get](const Py& self, const py::object& o, const py::object& d, const py::object& tmin, const py::object& tmax,
                            bool interpolated, bool refined, float intraBias, const std::string& rayOrigin, int64_t threads) {
        return visibilityBatch(get(self), batchOf(o, d, tmin, tmax, interpolated, refined, intraBias, rayOrigin, threads));
      },
      py::arg("origins"), py::arg("directions"), py::arg("tmin") = py::none(), py::arg("tmax") = py::none(), py::kw_only(),
      py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object", py::arg("threads") = 0u,
      (std::string(kBatchDoc) + "\nReturns an (N,) float32 array: the probability that each ray reaches tmax unoccluded "
                                "(0 or 1 with nearest).").c_str());
  c.def("sites", [get](const Py& self, const py::object& o, const py::object& d, const py::object& tmin, const py::object& tmax,
                       bool interpolated, bool refined, float intraBias, const std::string& rayOrigin, int64_t threads) {
        return sitesBatch(get(self), batchOf(o, d, tmin, tmax, interpolated, refined, intraBias, rayOrigin, threads));
      },
      py::arg("origins"), py::arg("directions"), py::arg("tmin") = py::none(), py::arg("tmax") = py::none(), py::kw_only(),
      py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object", py::arg("threads") = 0u,
      (std::string(kBatchDoc) + "\nWhich map and texel answer each ray (libvff's LookupSite, as vff-query's columns "
                                "sample, i, j): returns (sample, texel), (N,) int32 and (N, 2) int32 [i, j] (texel (i, "
                                "j) is element [j, i] of File.distances(sample)); -1 for a ray that makes no lookup. "
                                "The nearest reconstruction reads exactly that texel; the interpolated one centres "
                                "its blend on it.").c_str());
  c.def("intersect_ray", [get](const Py& self, const py::object& o, const py::object& d, float tmin, float tmax, bool interpolated, bool refined,
                               float intraBias, const std::string& rayOrigin) {
        return hitTuple(get(self).intersect(checkedRay(Ray{vec3(o, "origin"), vec3(d, "direction"), tmin, tmax}), optionsOf(interpolated, refined, intraBias, rayOrigin)));
      },
      py::arg("origin"), py::arg("direction"), py::arg("tmin") = 0.0f, py::arg("tmax") = std::numeric_limits<float>::infinity(),
      py::kw_only(), py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object",
      "One ray, through libvff's one-ray call: (hit, t, point, normal, inside) with point and normal as (x, y, z) tuples.");
  c.def("occluded_ray", [get](const Py& self, const py::object& o, const py::object& d, float tmin, float tmax, bool interpolated, bool refined,
                              float intraBias, const std::string& rayOrigin) {
        return get(self).occluded(checkedRay(Ray{vec3(o, "origin"), vec3(d, "direction"), tmin, tmax}), optionsOf(interpolated, refined, intraBias, rayOrigin));
      },
      py::arg("origin"), py::arg("direction"), py::arg("tmin") = 0.0f, py::arg("tmax") = std::numeric_limits<float>::infinity(),
      py::kw_only(), py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object", "One ray: libvff's one-ray occluded().");
  c.def("visibility_ray", [get](const Py& self, const py::object& o, const py::object& d, float tmin, float tmax, bool interpolated, bool refined,
                                float intraBias, const std::string& rayOrigin) {
        return get(self).visibility(checkedRay(Ray{vec3(o, "origin"), vec3(d, "direction"), tmin, tmax}), optionsOf(interpolated, refined, intraBias, rayOrigin));
      },
      py::arg("origin"), py::arg("direction"), py::arg("tmin") = 0.0f, py::arg("tmax") = std::numeric_limits<float>::infinity(),
      py::kw_only(), py::arg("interpolated") = false, py::arg("refined") = false, py::arg("intra_bias") = -1.0f, py::arg("ray_origin") = "on-object", "One ray: libvff's one-ray visibility().");
}


}  // namespace

void bindQuery(py::module_& m) {
  py::class_<Hits>(m, "Hits", "The answers of a batch intersect(): numpy arrays, one entry per ray.")
      .def_readonly("hit", &Hits::hit, "(N,) bool: the ray hit the object within [tmin, tmax].")
      .def_readonly("t", &Hits::t, "(N,) float32: the hit's distance in multiples of the direction (inf for a miss).")
      .def_readonly("point", &Hits::point, "(N, 3) float32: origin + t * direction (NaN for a miss).")
      .def_readonly("normal", &Hits::normal, "(N, 3) float32: the unit surface normal (NaN without one).")
      .def_readonly("inside", &Hits::inside, "(N,) bool: the origin was inside the bounding sphere.")
      .def_readonly("instance", &Hits::instance,
                    "A vff.Scene's answers: (N,) int32, the id of the instance hit (-1 for a miss); None for a "
                    "FieldQuery's or an Instance's.")
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
      .def_property_readonly("has_normals", [](const PyQuery& q) { return q.query.hasNormals(); }, "The field has normals.")
      .def_property_readonly("refined", [](const PyQuery& q) { return q.query.refined(); },
                             "The field has a refinement (vff-bake --refine): refined=True casts its unsure rays exactly.")
      .def_property_readonly("refinement_bytes", [](const PyQuery& q) { return q.query.refinementBytes(); },
                             "Bytes the refinement takes: unsure bits, positions and the exact step's BVH (0 without one).");
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
