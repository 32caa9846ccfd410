// rigid_transform.cpp - RigidTransform and Instance (vff/query.h): a field placed in the world by a
// rotation, a uniform scale and a translation. An Instance takes world-space rays to the field's
// object space, queries the field, and takes the answer back (both rays share t).
#include <algorithm>
#include <cmath>

#include "query/query_impl.h"

namespace vff {

Vec3 RigidTransform::toWorldVector(Vec3 v) const noexcept {
  const auto& r = rotation;
  return Vec3{r[0][0] * v.x + r[0][1] * v.y + r[0][2] * v.z, r[1][0] * v.x + r[1][1] * v.y + r[1][2] * v.z,
              r[2][0] * v.x + r[2][1] * v.y + r[2][2] * v.z} *
         scale;
}

Vec3 RigidTransform::toWorldPoint(Vec3 p) const noexcept { return toWorldVector(p) + translation; }

Vec3 RigidTransform::toObjectVector(Vec3 v) const noexcept { return detail::ToObject(*this).vector(v); }

Vec3 RigidTransform::toObjectPoint(Vec3 p) const noexcept { return detail::ToObject(*this).point(p); }

RigidTransform RigidTransform::fromAxisAngle(Vec3 axis, float radians, Vec3 translation, float scale) noexcept {
  RigidTransform x;
  const Vec3 a = normalize(axis);
  const float c = std::cos(radians), s = std::sin(radians), t = 1.0f - c;
  x.rotation[0][0] = c + a.x * a.x * t;
  x.rotation[0][1] = a.x * a.y * t - a.z * s;
  x.rotation[0][2] = a.x * a.z * t + a.y * s;
  x.rotation[1][0] = a.y * a.x * t + a.z * s;
  x.rotation[1][1] = c + a.y * a.y * t;
  x.rotation[1][2] = a.y * a.z * t - a.x * s;
  x.rotation[2][0] = a.z * a.x * t - a.y * s;
  x.rotation[2][1] = a.z * a.y * t + a.x * s;
  x.rotation[2][2] = c + a.z * a.z * t;
  x.translation = translation;
  x.scale = scale;
  return x;
}

namespace {

Ray toObject(const RigidTransform& x, const Ray& r) { return detail::ToObject(x).ray(r); }

}  // namespace

QueryHit Instance::intersect(const Ray& worldRay, const QueryOptions& options) const noexcept {
  if (!field) return {};
  QueryHit h = field->intersect(toObject(transform, worldRay), options);
  detail::toWorld(transform, worldRay, &h);
  return h;
}

bool Instance::occluded(const Ray& worldRay, const QueryOptions& options) const noexcept {
  return field && field->occluded(toObject(transform, worldRay), options);
}

float Instance::visibility(const Ray& worldRay, const QueryOptions& options) const noexcept {
  return field ? field->visibility(toObject(transform, worldRay), options) : 1.0f;
}

void Instance::intersect(std::span<const Ray> worldRays, std::span<QueryHit> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(worldRays.size(), out.size());
  if (field && field->impl_) {
    field->impl_->intersectBatch(worldRays.first(n), out.first(n), options, &transform);
  } else {
    std::fill_n(out.begin(), n, QueryHit{});
  }
}

void Instance::occluded(std::span<const Ray> worldRays, std::span<uint8_t> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(worldRays.size(), out.size());
  if (field && field->impl_) {
    field->impl_->occludedBatch(worldRays.first(n), out.first(n), options, &transform);
  } else {
    std::fill_n(out.begin(), n, uint8_t(0));
  }
}

void Instance::visibility(std::span<const Ray> worldRays, std::span<float> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(worldRays.size(), out.size());
  if (field && field->impl_) {
    field->impl_->visibilityBatch(worldRays.first(n), out.first(n), options, &transform);
  } else {
    std::fill_n(out.begin(), n, 1.0f);
  }
}

Sphere Instance::worldSphere() const noexcept {
  if (!field) return {};
  const Sphere& s = field->field().sphere;
  const Vec3 c = transform.toWorldPoint(toVec(s.center));
  return Sphere{{c.x, c.y, c.z}, s.radius * transform.scale};
}

}  // namespace vff
