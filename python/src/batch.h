// batch.h - what the query classes of the extension share (query.cpp, scene.cpp): the Python
// objects that own fields and instances, numpy arrays of rays read whatever their layout, batches
// split over threads without the GIL, and the arrays of answers.
#pragma once

#include <pybind11/stl.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <cstdint>
#include <cmath>
#include <cstring>
#include <optional>
#include <string>
#include <type_traits>
#include <vector>

#include "arrays.h"
#include "bindings.h"
#include "errors.h"
#include "platform/parallel.h"

namespace vff::python {

namespace py = pybind11;


// Rays per batch call on one thread: the smallest of the sizes that measured best around the
// copies in and out of numpy (benchmarks/python_query.py), which stream.
inline constexpr size_t kChunk = 16384;

struct PyQuery {
  py::object owner;  // the vff.File whose maps the query borrows
  FieldQuery query;
};

struct PyInstance {
  py::object owner;  // the vff.FieldQuery the instance borrows
  Instance instance;
};

// The (N, 3) float32 array `name`, or a TypeError/ValueError naming what is expected.
inline py::array vectors(const py::object& obj, const char* name) {
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
inline Bound bound(const py::object& obj, const char* name, float fallback, size_t n) {
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

// Why vff-query would refuse the ray (tools/vff-query/rays.cpp, in the same words), or nothing: an
// origin or direction that is not finite, a zero direction, a NaN bound, tmin > tmax. Python refuses
// the same rays (a ValueError), so that a batch and the command answer the same rays or none.
inline std::optional<std::string> rayProblem(const Ray& r) {
  const float v[6] = {r.origin.x, r.origin.y, r.origin.z, r.direction.x, r.direction.y, r.direction.z};
  for (int k = 0; k < 6; ++k)
    if (!std::isfinite(v[k])) return std::string(k < 3 ? "the origin" : "the direction") + " is not finite";
  if (v[3] == 0 && v[4] == 0 && v[5] == 0) return "the direction is zero";
  if (std::isnan(r.tmin) || std::isnan(r.tmax)) return "tmin or tmax is NaN";
  if (r.tmin > r.tmax) return "tmin is greater than tmax";
  return std::nullopt;
}
// rayProblem(r) finds nothing: the test alone, for every ray of a batch.
inline bool rayIsGood(const Ray& r) {
  bool finite = std::isfinite(r.origin.x) & std::isfinite(r.origin.y) & std::isfinite(r.origin.z) &
                std::isfinite(r.direction.x) & std::isfinite(r.direction.y) & std::isfinite(r.direction.z);
  return finite && (r.direction.x != 0 || r.direction.y != 0 || r.direction.z != 0) &&
         r.tmin <= r.tmax;  // (false for a NaN bound)
}
// A one-ray call's ray, or a ValueError saying what is wrong with it.
inline Ray checkedRay(const Ray& r) {
  if (auto p = rayProblem(r)) throw py::value_error("ray: " + *p);
  return r;
}

// The RayOrigin named by `origin`: "on-object" or "off-object" (a ValueError otherwise).
inline RayOrigin rayOriginOf(const std::string& name) {
  if (name == "on-object") return RayOrigin::kOnObject;
  if (name == "off-object") return RayOrigin::kOffObject;
  throw py::value_error("ray_origin: expected 'on-object' or 'off-object', got '" + name + "'");
}

// Runs work(first, rays) over the batch's chunks on its threads, without the GIL; each worker
// turns its chunks into rays in a buffer of its own.
template <class Work>
void parallel(const RayBatch& b, Work work) {
  py::gil_scoped_release unlocked;
  std::vector<std::vector<Ray>> buffers(vff::parallel::workerCount(b.n, kChunk, b.threads));
  vff::parallel::parallelForWorkers(b.n, kChunk, b.threads, [&](unsigned w, size_t first, size_t end) {
    std::vector<Ray>& rays = buffers[w];
    rays.resize(std::min(kChunk, b.n));
    b.fill(first, end - first, rays.data());
    work(first, std::span<const Ray>(rays.data(), end - first));
  });
}

// Raises a ValueError for the first bad ray of the batch ("ray 12: the direction is zero"), before
// anything is answered (an out= array keeps its answers). A pass over the rays of its own, on the
// batch's threads without the GIL: the answers would be lost anyway, and a pass that only reads
// the arrays adds little to one that also answers them.
inline void checkRays(const RayBatch& b) {
  std::atomic<size_t> firstBad{SIZE_MAX};
  parallel(b, [&](size_t first, std::span<const Ray> rays) {
    for (size_t k = 0; k < rays.size(); ++k) {
      if (rayIsGood(rays[k])) continue;
      size_t seen = firstBad.load(std::memory_order_relaxed);
      while (first + k < seen && !firstBad.compare_exchange_weak(seen, first + k, std::memory_order_relaxed)) {
      }
      break;
    }
  });
  const size_t bad = firstBad.load();
  if (bad == SIZE_MAX) return;
  Ray r;
  b.fill(bad, 1, &r);
  throw py::value_error("ray " + std::to_string(bad) + ": " + rayProblem(r).value_or("refused"));
}

// The reconstruction the keywords ask for. refined: Reconstruction::kRefined (vff/refine.h), which
// answers as nearest on a field without a refinement.
inline Reconstruction reconstructionOf(bool interpolated, bool refined) {
  if (interpolated && refined) throw py::value_error("interpolated and refined: give one reconstruction, not both");
  return refined ? Reconstruction::kRefined : interpolated ? Reconstruction::kInterpolated : Reconstruction::kNearest;
}

// (threads is taken as any integer so that a negative one is a ValueError naming it, not pybind11's
// "incompatible function arguments".)
inline RayBatch batchOf(const py::object& origins, const py::object& directions, const py::object& tmin,
                 const py::object& tmax, bool interpolated, bool refined, float intraBias, const std::string& rayOrigin, int64_t threads) {
  if (threads < 0 || threads > int64_t(UINT32_MAX))
    throw py::value_error("threads: expected an integer >= 0 (0: all cores), got " + std::to_string(threads));
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
  b.options.reconstruction = reconstructionOf(interpolated, refined);
  b.options.intraBias = intraBias;
  b.options.origin = rayOriginOf(rayOrigin);
  b.threads = vff::parallel::resolveThreads(unsigned(threads));
  checkRays(b);
  return b;
}

// A target's batch call for the chunk of rays that starts at ray `first` of the batch: the
// target's *At(first, ...) where it has one (a scene with per-ray sources), else its plain call.
template <class Target, class Out>
void intersectChunk(const Target& t, size_t first, std::span<const Ray> rays, Out out, const QueryOptions& qo) {
  if constexpr (requires { t.intersectAt(first, rays, out, qo); }) t.intersectAt(first, rays, out, qo);
  else (void)t.intersect(rays, out, qo);
}
template <class Target>
void occludedChunk(const Target& t, size_t first, std::span<const Ray> rays, std::span<uint8_t> out, const QueryOptions& qo) {
  if constexpr (requires { t.occludedAt(first, rays, out, qo); }) t.occludedAt(first, rays, out, qo);
  else t.occluded(rays, out, qo);
}
template <class Target>
void visibilityChunk(const Target& t, size_t first, std::span<const Ray> rays, std::span<float> out, const QueryOptions& qo) {
  if constexpr (requires { t.visibilityAt(first, rays, out, qo); }) t.visibilityAt(first, rays, out, qo);
  else t.visibility(rays, out, qo);
}

// Hits as numpy arrays.
struct Hits {
  py::array_t<bool> hit;
  py::array_t<float> t, point, normal;
  py::array_t<bool> inside;
  py::object instance = py::none();  // a Scene's: (N,) int32 instance ids, -1 for a miss
};

// The Hits to fill: `out` when given (its arrays must hold n rays), else new arrays.
inline Hits hitsFor(const py::object& out, size_t count) {
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

// Answers the batch into h: Hit is QueryHit (a FieldQuery's or an Instance's answers) or SceneHit (a
// Scene's, whose instance ids go to h.instance).
template <class Hit, class Target>
Hits fillHits(const Target& target, const RayBatch& b, Hits h) {
  bool* hit = h.hit.mutable_data();
  float* t = h.t.mutable_data();
  float* point = h.point.mutable_data();
  float* normal = h.normal.mutable_data();
  bool* inside = h.inside.mutable_data();
  int32_t* instance = nullptr;
  if constexpr (std::is_same_v<Hit, SceneHit>) instance = h.instance.template cast<py::array_t<int32_t>>().mutable_data();
  const QueryOptions qo = b.options;
  parallel(b, [&](size_t first, std::span<const Ray> rays) {
    thread_local std::vector<Hit> out;
    out.resize(rays.size());
    intersectChunk(target, first, rays, std::span<Hit>(out), qo);
    // Selects by bit masks, not branches: whether a ray hit is as good as random, and a
    // mispredicted branch a ray cost more than the rest of this loop.
    const uint32_t nan = 0x7fc00000u;  // the quiet NaN's bits
    auto orNan = [nan](uint32_t mask, float v) {  // v where mask is all ones, else NaN
      return std::bit_cast<float>((std::bit_cast<uint32_t>(v) & mask) | (nan & ~mask));
    };
    for (size_t k = 0; k < rays.size(); ++k) {
      const Hit& q = out[k];
      const size_t i = first + k;
      hit[i] = q.hit, t[i] = q.t, inside[i] = q.inside;
      if constexpr (std::is_same_v<Hit, SceneHit>) instance[i] = q.instance == kNoInstance ? -1 : int32_t(q.instance);
      const uint32_t hm = 0u - uint32_t(q.hit), nm = 0u - uint32_t(q.hasNormal);
      float* p = point + 3 * i;
      float* pn = normal + 3 * i;
      p[0] = orNan(hm, q.point.x), p[1] = orNan(hm, q.point.y), p[2] = orNan(hm, q.point.z);
      pn[0] = orNan(nm, q.normal.x), pn[1] = orNan(nm, q.normal.y), pn[2] = orNan(nm, q.normal.z);
    }
  });
  return h;
}

template <class Target>
Hits intersectBatch(const Target& target, const RayBatch& b, const py::object& reuse) {
  return fillHits<QueryHit>(target, b, hitsFor(reuse, b.n));
}

template <class Target>
py::array_t<bool> occludedBatch(const Target& target, const RayBatch& b) {
  py::array_t<bool> out = ArrayBlock({b.n}).array<bool>(0, {py::ssize_t(b.n)});
  uint8_t* dst = reinterpret_cast<uint8_t*>(out.mutable_data());
  const QueryOptions qo = b.options;
  parallel(b, [&](size_t first, std::span<const Ray> rays) {
    occludedChunk(target, first, rays, std::span<uint8_t>(dst + first, rays.size()), qo);
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
    visibilityChunk(target, first, rays, std::span<float>(dst + first, rays.size()), qo);
  });
  return out;
}

inline Vec3 vec3(const py::object& o, const char* name) {
  auto v = o.cast<std::vector<float>>();
  if (v.size() != 3) throw py::value_error(std::string(name) + ": expected 3 numbers, got " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

inline QueryOptions optionsOf(bool interpolated, bool refined, float intraBias, const std::string& rayOrigin) {
  QueryOptions qo;
  qo.reconstruction = reconstructionOf(interpolated, refined);
  qo.intraBias = intraBias;
  qo.origin = rayOriginOf(rayOrigin);
  return qo;
}

inline py::tuple hitTuple(const QueryHit& h) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  return py::make_tuple(h.hit, h.t, h.hit ? py::make_tuple(h.point.x, h.point.y, h.point.z) : py::make_tuple(nan, nan, nan),
                        h.hasNormal ? py::make_tuple(h.normal.x, h.normal.y, h.normal.z) : py::make_tuple(nan, nan, nan),
                        h.inside);
}

inline constexpr const char* kBatchDoc = R"doc(
Answers a batch of rays. origins, directions: float32 arrays of shape (N, 3), any strides;
directions need not be unit length (t is in multiples of them). tmin, tmax: None (0 and infinity),
a number, or a float32 array of shape (N,). interpolated: the miss-aware blend instead of the
paper's nearest lookup. ray_origin: where rays that start inside a bounding sphere start, 'on-object' (on
the object's own surface: spec/geometry.md section 7.3, the default) or 'off-object' (the ground under
it, another object: section 7.4, which keeps contact shadows at short ranges). intra_bias: for
'on-object' rays, a fraction of R (negative: the field's default). threads: an integer >= 0, 0 for all
cores; the answers do not depend on it. The GIL is released.
Rays are checked as vff-query checks them, before any is answered: an origin or direction that is not
finite, a zero direction, a NaN bound or tmin > tmax raises ValueError naming the first such ray
("ray 12: the direction is zero"; out is left as it was). To answer the good rays of such a batch,
select them first: ok = np.isfinite(o).all(1) & np.isfinite(d).all(1) & d.any(1).)doc";


inline RigidTransform transformOf(const py::object& rotation, const py::object& translation, float scale) {
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


}  // namespace vff::python
