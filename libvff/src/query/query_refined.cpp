// query_refined.cpp - Reconstruction::kRefined (vff/refine.h, spec/geometry.md section 7.5): the
// nearest answer where the field is sure of it, the exact ray cast through the object's triangles
// where it is not.
#include "query/query_impl.h"

#include <string>

namespace vff {

Status FieldQuery::Impl::setRefinement(const RefinementView& r) {
  if (r.empty()) return {};
  if (r.indices.size() / 3 >= detail::WideBvh::kMaxTriangles)
    return makeError(Code::kUnsupported, "the refinement holds " + std::to_string(r.indices.size() / 3) +
                                             " triangles; a refined query takes fewer than 2^28");
  refine = r;
  refineMargin = r.margin * radius;
  // The binary BVH is only the wide one's scaffold: the CPU casts through the wide one.
  bvh = detail::WideBvh(detail::TriangleBvh(r.positions, r.indices));
  return {};
}

QueryHit FieldQuery::Impl::exactHit(const Ray& ray, float* visibility) const noexcept {
  QueryHit out;
  if (visibility) *visibility = 1.0f;
  if (float t = 0; bvh.intersect(ray.origin, ray.direction, ray.tmin, ray.tmax, &t, &out.normal)) {
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
  detail::Sample s;
  switch (refineStep(k, i, j, t0, inside, lo, hi, &s)) {
    case RefineStep::kMiss:
      if (visibility) *visibility = 1.0f;
      return {};
    case RefineStep::kMaps:
      return t0 < 0 ? offHitAt(ray, k, i, j, t0, lo, hi, len, visibility)
                    : hitAt(ray, k, i, j, t0, inside, lo, hi, len, visibility);
    case RefineStep::kExact: break;
  }
  if (!anyHit) return exactHit(ray, visibility);
  QueryHit out;
  out.hit = exactOccluded(ray, s, t0, len);
  if (visibility) *visibility = out.hit ? 0.0f : 1.0f;
  return out;
}

bool FieldQuery::refined() const noexcept { return impl_ && !impl_->bvh.empty(); }

uint64_t FieldQuery::refinementBytes() const noexcept {
  if (!refined()) return 0;
  return impl_->refine.unsure.size() + impl_->refine.positions.size_bytes() + impl_->bvh.bytes();
}

}  // namespace vff
