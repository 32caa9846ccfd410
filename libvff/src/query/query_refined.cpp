// query_refined.cpp - Reconstruction::kRefined (vff/refine.h, spec/geometry.md section 7.5): the
// nearest answer where the field is sure of it, the exact ray cast through the object's triangles
// where it is not.
#include "query/query_impl.h"

namespace vff {
namespace {

// How far around the maps' hit an occlusion query looks first, in margins: the depth steps the
// marking of unsure texels allows (RefineOptions::jumpMargins).
constexpr float kRefineSearchMargins = 4.0f;

}  // namespace

Status FieldQuery::Impl::setRefinement(const RefinementView& r) {
  if (r.empty()) return {};
  refine = r;
  refineMargin = r.margin * radius;
  bvh = detail::TriangleBvh(r.positions, r.indices);
  return {};
}

QueryHit FieldQuery::Impl::exactHit(const Ray& ray, bool anyHit, float* visibility) const noexcept {
  QueryHit out;
  if (visibility) *visibility = 1.0f;
  if (anyHit) {
    out.hit = bvh.occluded(ray.origin, ray.direction, ray.tmin, ray.tmax);
  } else if (float t = 0; bvh.intersect(ray.origin, ray.direction, ray.tmin, ray.tmax, &t, &out.normal)) {
    out.hit = true;
    out.t = t;
    out.point = ray.origin + ray.direction * t;
    out.hasNormal = true;
  }
  if (out.hit && visibility) *visibility = 0.0f;
  return out;
}

QueryHit FieldQuery::Impl::refinedAt(const Ray& ray, uint32_t k, uint32_t i, uint32_t j, float t0, bool inside,
                                     float lo, float hi, float len, bool anyHit, float* visibility) const noexcept {
  auto nearest = [&] {
    return t0 < 0 ? offHitAt(ray, k, i, j, t0, lo, hi, len, visibility)
                  : hitAt(ray, k, i, j, t0, inside, lo, hi, len, visibility);
  };
  if (inside) return nearest();
  const detail::Sample s = texel(k, i, j);
  const float t = t0 + s.distance;  // (along the unit direction, as lo and hi)
  if (!refine.isUnsure((uint64_t(k) * m + j) * m + i)) {
    if (!s.hit) {  // a sure miss: every texel around it misses too
      if (visibility) *visibility = 1.0f;
      return {};
    }
    // Near the start of the range (or behind an origin inside the sphere) or near its end, the
    // hit may lie on the other side of it.
    if (!(t < lo + refineMargin || std::fabs(t - hi) < refineMargin)) return nearest();
  }
  // Occlusion needs any hit in the range: first look where the maps put one, a short stretch of
  // the ray that the BVH culls to a few nodes; only when nothing is there, the whole range. Both
  // are exact casts, so the answer is the whole range's either way.
  if (anyHit && s.hit && s.distance > 0) {
    const float reach = kRefineSearchMargins * refineMargin;
    const float from = std::max(ray.tmin, (t - reach) / len), to = std::min(ray.tmax, (t + reach) / len);
    if (from <= to && bvh.occluded(ray.origin, ray.direction, from, to)) {
      if (visibility) *visibility = 0.0f;
      QueryHit out;
      out.hit = true;
      return out;
    }
  }
  return exactHit(ray, anyHit, visibility);
}

bool FieldQuery::refined() const noexcept { return impl_ && !impl_->bvh.empty(); }

uint64_t FieldQuery::refinementBytes() const noexcept {
  if (!refined()) return 0;
  return impl_->refine.unsure.size() + impl_->refine.positions.size_bytes() + impl_->bvh.bytes();
}

}  // namespace vff
