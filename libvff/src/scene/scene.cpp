// scene.cpp - vff::Scene (vff/scene.h): instances, their checks, the commit and the one-ray
// queries. The batches are in scene_batch.cpp.
#include "scene/scene_impl.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <unordered_map>

namespace vff {

namespace {

bool finite3(Vec3 v) { return std::isfinite(v.x) && std::isfinite(v.y) && std::isfinite(v.z); }

Status checkField(const FieldQuery* field) {
  if (!field) return makeError(Code::kInvalidArgument, "scene: the instance has no field");
  const Sphere& s = field->field().sphere;
  if (!std::isfinite(s.center[0]) || !std::isfinite(s.center[1]) || !std::isfinite(s.center[2]) ||
      !std::isfinite(s.radius) || !(s.radius > 0))
    return makeError(Code::kSphere, "scene: the field's bounding sphere is not finite or its radius is not > 0");
  if (field->field().mapCount == 0) return makeError(Code::kInvalidArgument, "scene: the field has no maps");
  return {};
}

}  // namespace

Status checkTransform(const RigidTransform& x) {
  if (!finite3(x.translation)) return makeError(Code::kInvalidArgument, "transform: the translation is not finite");
  if (!std::isfinite(x.scale) || !(x.scale > 0))
    return makeError(Code::kInvalidArgument, "transform: the scale is not a finite number > 0");
  const auto& r = x.rotation;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) {
      if (!std::isfinite(r[i][j])) return makeError(Code::kInvalidArgument, "transform: the rotation is not finite");
      const double d = double(r[i][0]) * r[j][0] + double(r[i][1]) * r[j][1] + double(r[i][2]) * r[j][2];
      if (std::abs(d - (i == j ? 1.0 : 0.0)) > 1e-3)
        return makeError(Code::kInvalidArgument, "transform: the rotation is not orthonormal (rows " +
                                                     std::to_string(i) + " and " + std::to_string(j) + ")");
    }
  const double det = double(r[0][0]) * (double(r[1][1]) * r[2][2] - double(r[1][2]) * r[2][1]) -
                     double(r[0][1]) * (double(r[1][0]) * r[2][2] - double(r[1][2]) * r[2][0]) +
                     double(r[0][2]) * (double(r[1][0]) * r[2][1] - double(r[1][1]) * r[2][0]);
  if (!(det > 0)) return makeError(Code::kInvalidArgument, "transform: the rotation is a reflection (determinant -1)");
  return {};
}

Scene::Scene() noexcept = default;
Scene::Scene(Scene&&) noexcept = default;
Scene& Scene::operator=(Scene&&) noexcept = default;
Scene::~Scene() = default;

Scene::Impl& Scene::Impl::of(std::unique_ptr<Impl>& p) {
  if (!p) p = std::make_unique<Impl>();
  return *p;
}

Result<uint32_t> Scene::add(const FieldQuery* field, const RigidTransform& transform) {
  if (Status s = checkField(field); !s) return std::move(s).error();
  if (Status s = checkTransform(transform); !s) return std::move(s).error();
  Impl& m = Impl::of(impl_);
  if (m.instances.size() >= kNoInstance - 1) return makeError(Code::kOutOfRange, "scene: too many instances");
  m.instances.push_back(Instance{field, transform});
  m.committed = false;
  return uint32_t(m.instances.size() - 1);
}

Status Scene::setTransform(uint32_t id, const RigidTransform& transform) {
  if (id >= size())
    return makeError(Code::kOutOfRange, "scene: no instance " + std::to_string(id) + " (the scene has " +
                                            std::to_string(size()) + ")");
  if (Status s = checkTransform(transform); !s) return s;
  impl_->instances[id].transform = transform;
  impl_->committed = false;
  return {};
}

Result<Instance> Scene::instance(uint32_t id) const {
  if (id >= size())
    return makeError(Code::kOutOfRange, "scene: no instance " + std::to_string(id) + " (the scene has " +
                                            std::to_string(size()) + ")");
  return impl_->instances[id];
}

uint32_t Scene::size() const noexcept { return impl_ ? uint32_t(impl_->instances.size()) : 0; }

bool Scene::committed() const noexcept { return !impl_ || impl_->committed; }

Status Scene::commit() {
  Impl& m = Impl::of(impl_);
  std::vector<detail::Box>& boxes = m.boxes;
  boxes.resize(m.instances.size());
  m.maxRadius = 0;
  for (size_t i = 0; i < boxes.size(); ++i) {
    const Sphere s = m.instances[i].worldSphere();
    const float c[3] = {s.center[0], s.center[1], s.center[2]};
    if (!std::isfinite(c[0]) || !std::isfinite(c[1]) || !std::isfinite(c[2]) || !std::isfinite(s.radius))
      return makeError(Code::kSphere, "scene: instance " + std::to_string(i) + "'s world sphere is not finite");
    // Enlarged a little, so that the float box test never misses a ray the instance's own sphere
    // test (in object space) lets through.
    const float big = std::max({std::abs(c[0]), std::abs(c[1]), std::abs(c[2]), s.radius});
    const float r = s.radius + 1e-3f * s.radius + 1e-5f * big;
    for (int a = 0; a < 3; ++a) {
      boxes[i].lo[a] = c[a] - r;
      boxes[i].hi[a] = c[a] + r;
    }
    m.maxRadius = std::max(m.maxRadius, r);
  }
  m.bvh.build(boxes);
  m.toObject.clear();
  m.toObject.reserve(m.instances.size());
  for (const Instance& x : m.instances) m.toObject.emplace_back(x.transform);
  // Grouped by field, in the order in which each field first appears (so that the grouping does
  // not depend on where the fields lie in memory). Instances are only ever appended and keep their
  // field, so the grouping changes only when instances were added: a frame that only moves them
  // keeps it.
  if (m.byField.size() != m.instances.size()) {
    m.byField.resize(m.instances.size());
    for (uint32_t i = 0; i < m.byField.size(); ++i) m.byField[i] = i;
    std::vector<uint32_t> firstUse(m.instances.size());
    std::unordered_map<const FieldQuery*, uint32_t> first;
    for (uint32_t i = 0; i < firstUse.size(); ++i) firstUse[i] = first.try_emplace(m.instances[i].field, i).first->second;
    std::stable_sort(m.byField.begin(), m.byField.end(), [&](uint32_t a, uint32_t b) { return firstUse[a] < firstUse[b]; });
    m.fieldStart.clear();
    for (uint32_t k = 0; k < m.byField.size(); ++k)
      if (k == 0 || firstUse[m.byField[k]] != firstUse[m.byField[k - 1]]) m.fieldStart.push_back(k);
    m.fieldStart.push_back(uint32_t(m.byField.size()));
  }
  m.committed = true;
  return {};
}

Status Scene::Impl::ready(const Scene::Impl* m) {
  if (m && !m->committed) return makeError(Code::kBadState, "scene: not committed since the last add() or setTransform()");
  return {};
}

float Scene::Impl::margin(const Ray& ray) const noexcept {
  const float len = std::sqrt(ray.direction.x * ray.direction.x + ray.direction.y * ray.direction.y +
                              ray.direction.z * ray.direction.z);
  return len > 0 ? 2.1f * maxRadius / len : std::numeric_limits<float>::infinity();
}

void Scene::Impl::gather(const Ray& ray, std::vector<uint32_t>* ids) const {
  ids->clear();
  bvh.walk(detail::boxRay(ray), [&](uint32_t id) {
    ids->push_back(id);
    return ray.tmax;
  });
  std::sort(ids->begin(), ids->end());
}

namespace {

// The options instance `id` answers a ray with: the caller's, or, for a ray with a source, section
// 7.3's for the instance it starts on and section 7.4's for the rest.
struct OptionsFor {
  const QueryOptions& options;
  const uint32_t* source;  // null: options as given
  QueryOptions operator()(uint32_t id) const noexcept {
    QueryOptions o = options;
    if (source) o.origin = id == *source ? RayOrigin::kOnObject : RayOrigin::kOffObject;
    return o;
  }
};

SceneHit nearest(const Scene::Impl& m, const Ray& ray, OptionsFor options) {
  SceneHit best;
  const float margin = m.margin(ray);
  m.bvh.walk(detail::boxRay(ray), [&](uint32_t id) {
    const QueryHit h = m.instances[id].intersect(ray, options(id));
    if (h.hit && (h.t < best.t || (h.t == best.t && id < best.instance))) {
      static_cast<QueryHit&>(best) = h;
      best.instance = id;
    }
    // A hit of another instance can lie before its sphere's entry by up to its diameter
    // (kInterpolated projects neighbouring samples' hits onto the ray): boxes are skipped only
    // beyond that.
    return best.hit ? std::min(ray.tmax, best.t + margin) : ray.tmax;
  });
  return best;
}

bool anyOccludes(const Scene::Impl& m, const Ray& ray, OptionsFor options) {
  bool any = false;
  m.bvh.walk(detail::boxRay(ray), [&](uint32_t id) {
    any = m.instances[id].occluded(ray, options(id));
    return any ? -1.0f : ray.tmax;
  });
  return any;
}

float product(const Scene::Impl& m, const Ray& ray, OptionsFor options) {
  float v = 1.0f;
  std::vector<uint32_t> ids;
  m.gather(ray, &ids);
  for (uint32_t id : ids) v *= m.instances[id].visibility(ray, options(id));
  return v;
}

Status checkSource(const Scene::Impl* m, uint32_t source) {
  const size_t n = m ? m->instances.size() : 0;
  if (source == kNoInstance || source < n) return {};
  return makeError(Code::kOutOfRange, "scene: source " + std::to_string(source) + " is no instance (the scene has " +
                                          std::to_string(n) + "; kNoInstance for none)");
}

}  // namespace

Result<SceneHit> Scene::intersect(const Ray& ray, const QueryOptions& options) const {
  if (Status s = Impl::ready(impl_.get()); !s) return std::move(s).error();
  return impl_ ? nearest(*impl_, ray, {options, nullptr}) : SceneHit{};
}

Result<bool> Scene::occluded(const Ray& ray, const QueryOptions& options) const {
  if (Status s = Impl::ready(impl_.get()); !s) return std::move(s).error();
  return impl_ && anyOccludes(*impl_, ray, {options, nullptr});
}

Result<float> Scene::visibility(const Ray& ray, const QueryOptions& options) const {
  if (Status s = Impl::ready(impl_.get()); !s) return std::move(s).error();
  return impl_ ? product(*impl_, ray, {options, nullptr}) : 1.0f;
}

Result<SceneHit> Scene::intersectFrom(const Ray& ray, uint32_t source, const QueryOptions& options) const {
  if (Status s = Impl::ready(impl_.get()); !s) return std::move(s).error();
  if (Status s = checkSource(impl_.get(), source); !s) return std::move(s).error();
  return impl_ ? nearest(*impl_, ray, {options, &source}) : SceneHit{};
}

Result<bool> Scene::occludedFrom(const Ray& ray, uint32_t source, const QueryOptions& options) const {
  if (Status s = Impl::ready(impl_.get()); !s) return std::move(s).error();
  if (Status s = checkSource(impl_.get(), source); !s) return std::move(s).error();
  return impl_ && anyOccludes(*impl_, ray, {options, &source});
}

Result<float> Scene::visibilityFrom(const Ray& ray, uint32_t source, const QueryOptions& options) const {
  if (Status s = Impl::ready(impl_.get()); !s) return std::move(s).error();
  if (Status s = checkSource(impl_.get(), source); !s) return std::move(s).error();
  return impl_ ? product(*impl_, ray, {options, &source}) : 1.0f;
}

Result<std::vector<uint32_t>> Scene::candidates(const Ray& ray) const {
  if (Status s = Impl::ready(impl_.get()); !s) return std::move(s).error();
  std::vector<uint32_t> ids;
  if (impl_) impl_->gather(ray, &ids);
  return ids;
}

}  // namespace vff
