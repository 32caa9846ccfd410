// query_ray.cpp - the CPU query of one ray (vff/query.h; spec/geometry.md section 7): the
// reference path. prepare() finds the sphere entry, the nearest sample and the texel; nearestHit()
// decodes that texel; planInterpolated() and blendInterpolated() blend the kernel's samples. The
// batch paths (query_batch_nearest.h, query_batch_interpolated.h) call these same functions for
// every ray their SIMD kernels leave, and their kernels mirror them operation for operation.
#include "query/query_impl.h"

namespace vff {

// The core of every query. Distances below are object-space lengths along the unit direction w;
// the caller's t is that length divided by |direction|.
void FieldQuery::Impl::lookupFrom(const Ray& ray, float len, float t0, bool inside, float lo, float hi,
                                  Lookup* l) const noexcept {
  const Vec3 w = ray.direction * (1.0f / len);
  l->w = w;
  l->len = len;
  l->t0 = t0;
  l->inside = inside;
  l->off = !inside && t0 < 0;  // (only RayOrigin::kOffObject leaves t0 below 0)
  l->v = inside ? -w : w;
  l->lo = lo;
  l->hi = hi;
  l->eu = (ray.origin + w * t0 - center) * (1.0f / radius);
}

bool FieldQuery::Impl::prepare(const Ray& ray, const QueryOptions& o, Lookup* l) const noexcept {
  const float len = std::sqrt(dot(ray.direction, ray.direction));
  if (!(len > 0) || !std::isfinite(len)) return false;
  const Vec3 w = ray.direction * (1.0f / len);
  const float tmin = ray.tmin * len, tmax = ray.tmax * len;
  // 1. The sphere (section 7.2).
  const Vec3 delta = ray.origin - center;
  const float beta = dot(delta, w);
  const float gamma = dot(delta, delta) - radius * radius;
  const float disc = beta * beta - gamma;
  if (!(disc >= 0)) return false;
  const float sq = std::sqrt(disc);
  const float t1 = -beta + sq;
  if (t1 < 0) return false;
  const bool inSphere = gamma <= 0;
  const bool offObject = o.origin == RayOrigin::kOffObject;
  const bool inside = inSphere && !offObject;
  if (inSphere && field.distanceEncoding == DistanceEncoding::kBit1) return false;  // no distances: cannot tell
  // The lookup: the ray enters at `e` looking along `v`. On the object (section 7.3) the reversed
  // ray enters at the exit point, looking back at the origin; off it (section 7.4) the ray
  // extended backwards enters before the origin, at a negative t0.
  const float tIn = -beta - sq;
  const float t0 = inside ? t1 : (offObject && inSphere ? tIn : std::max(tIn, 0.0f));
  // A hit counts when its t lies in [lo, hi]. On the object, the surface must also be more than
  // the bias in front of the origin (the origin's own surface is not an occluder).
  float lo = tmin;
  if (inside) {
    const float bias = o.intraBias >= 0 ? o.intraBias : defaultBias;
    lo = std::max(lo, bias * radius);
  }
  if (!inside && t0 > tmax) return false;  // the sphere begins beyond the range
  lookupFrom(ray, len, t0, inside, lo, tmax, l);
  l->k0 = nearestSample(l->eu);
  const Vec3 local = toLocal(frames[l->k0], l->v);
  if (!detail::texelFast(field.directionScheme, local, m, &l->i, &l->j))
    squareToTexel(hemisphereToSquare(field.directionScheme, local), m, &l->i, &l->j);
  return true;
}

QueryHit FieldQuery::Impl::nearestHit(const Ray& ray, const Lookup& l, float* visibility) const noexcept {
  return hitAt(ray, l.k0, l.i, l.j, l.t0, l.inside, l.lo, l.hi, l.len, visibility);
}

QueryHit FieldQuery::Impl::hitAt(const Ray& ray, uint32_t k, uint32_t i, uint32_t j, float t0, bool inside, float lo,
                                 float hi, float len, float* visibility) const noexcept {
  float t = 0;
  if (!hitsAt(k, i, j, t0, inside, lo, hi, &t)) return {};
  return hitOf(ray, k, i, j, t, inside, len, visibility);
}

QueryHit FieldQuery::Impl::hitOf(const Ray& ray, uint32_t k, uint32_t i, uint32_t j, float t, bool inside, float len,
                                 float* visibility) const noexcept {
  QueryHit out;
  if (visibility) *visibility = 0.0f;
  out.hit = true;
  out.inside = inside;
  out.t = t / len;
  out.point = ray.origin + ray.direction * (1.0f / len) * t;
  if (!norm.empty()) {
    out.normal = normalAt(k, i, j);
    out.hasNormal = true;
  }
  return out;
}

QueryHit FieldQuery::Impl::query(const Ray& ray, const QueryOptions& o, float* visibility) const noexcept {
  if (visibility) *visibility = 1.0f;
  Lookup l;
  if (!prepare(ray, o, &l)) return {};
  // From inside, kInterpolated answers like kNearest: the blended samples' rays pass beside the
  // origin and take its own surface for an occluder (tests/query, intra-object occlusion).
  if (o.reconstruction == Reconstruction::kRefined && !bvh.empty())
    return refinedAt(ray, l.k0, l.i, l.j, l.t0, l.inside, l.lo, l.hi, l.len, false, visibility);
  if (o.reconstruction != Reconstruction::kInterpolated || l.inside) return nearestAnswer(ray, l, visibility);
  return interpolated(ray, l, visibility);
}

// Section 7.4. Step 1 is the lookup at (k, i, j) from the entry point at t0 < 0; a surface within
// the tolerance behind lo touches the origin and counts as a hit at lo (step 2).
QueryHit FieldQuery::Impl::offHitAt(const Ray& ray, uint32_t k, uint32_t i, uint32_t j, float t0, float lo, float hi,
                                    float len, float* visibility) const noexcept {
  const detail::Sample s = texel(k, i, j);
  if (!s.hit) return {};
  const float t = t0 + s.distance;
  if (t < lo - offTolerance) return behindOrigin(ray, visibility);  // step 3
  if (t > hi) return {};
  return hitOf(ray, k, i, j, std::max(t, lo), false, len, visibility);
}

bool FieldQuery::Impl::offHitsAt(const Ray& ray, uint32_t k, uint32_t i, uint32_t j, float t0, float lo,
                                 float hi) const noexcept {
  const detail::Sample s = texel(k, i, j);
  if (!s.hit) return false;
  const float t = t0 + s.distance;
  if (t < lo - offTolerance) return behindOrigin(ray, nullptr).hit;
  return t <= hi;
}

// Step 3: the origin lies in a hollow of the object (or inside it), so the forward lookup says
// nothing of the part after it; section 7.3 with no bias (the origin has no surface of its own
// here to skip) finds whether any surface lies ahead.
QueryHit FieldQuery::Impl::behindOrigin(const Ray& ray, float* visibility) const noexcept {
  QueryOptions o;
  o.intraBias = 0.0f;
  Lookup l;
  if (!prepare(ray, o, &l)) return {};
  return nearestHit(ray, l, visibility);
}

// Interpolated, section 7.4: step 3 when the nearest sample's lookup lies behind the origin;
// otherwise the blend of the planned lane over [lo - tolerance, hi], its distance clamped to lo
// (sums: the kernel's blend of the lane, already made over that window).
QueryHit FieldQuery::Impl::offInterpolated(const Ray& ray, const Lookup& l, const detail::PlanBlock& plan,
                                           size_t lane, const detail::BlendSums* sums,
                                           float* visibility) const noexcept {
  if (behindAt(l.k0, l.i, l.j, l.t0, l.lo)) return behindOrigin(ray, visibility);
  Lookup wide = l;
  wide.lo = l.lo - offTolerance;
  QueryHit h;
  if (sums) {
    detail::Blend bl;
    bl.hitWeight = sums->hit[lane];
    bl.missWeight = sums->miss[lane];
    bl.farWeight = sums->far[lane];
    bl.tSum = sums->tSum[lane];
    bl.normalSum = {sums->nx[lane], sums->ny[lane], sums->nz[lane]};
    h = blendResult(ray, wide, bl, visibility);
  } else {
    h = blendInterpolated(ray, wide, plan, lane, visibility);
  }
  if (h.hit && h.t * l.len < l.lo) {
    h.t = l.lo / l.len;
    h.point = ray.origin + l.w * l.lo;
  }
  return h;
}

// Interpolated: the kernel's samples, each looked up along v from its own sample point (parallel
// rays) with miss-aware bilinear weights; each hit point is projected onto the ray. In two halves,
// so that a batch can fetch the texels of many rays at once: planInterpolated() finds the samples
// and their texels, blendInterpolated() reads and blends them.
void FieldQuery::Impl::planInterpolated(const Ray& ray, const Lookup& l, detail::PlanBlock* plan,
                                        size_t lane) const noexcept {
  static_assert(detail::kPlanSlots == 1 + kNeighbours, "a slot per candidate sample");
  const Vec3 eu = l.eu, v = l.v, w = l.w;
  auto kernel = [&](uint32_t k) {
    const Vec3 d = eu - unit(k);
    const float x = 1.0f - dot(d, d) / kernelRadius2;
    return x > 0 ? x * x : 0.0f;
  };
  uint32_t mask = 0;
  // Slot 0: the nearest sample, which always contributes; slot 1 + c: its neighbour c.
  const uint32_t* nb = &neighbours[size_t(l.k0) * kNeighbours];
  for (uint32_t c = 0; c < detail::kPlanSlots; ++c) {
    const uint32_t k = c == 0 ? l.k0 : nb[c - 1];
    if (k == UINT32_MAX) break;
    const float weight = c == 0 ? std::max(kernel(k), 1e-6f) : kernel(k);
    if (c > 0 && !(weight > 0)) continue;  // (the nearest sample always contributes)
    const Vec3 local = toLocal(frames[k], v);
    if (local.z <= 0) continue;  // the sample does not see this direction
    const Vec2 uv = detail::hemisphereToSquareFast(field.directionScheme, local);
    const float x = (uv.x + 1.0f) * 0.5f * float(m) - 0.5f;
    const float y = (uv.y + 1.0f) * 0.5f * float(m) - 0.5f;
    const float fx0 = std::floor(x), fy0 = std::floor(y);
    mask |= 1u << c;
    plan->k[c][lane] = int32_t(k);
    plan->weight[c][lane] = weight;
    plan->fx[c][lane] = x - fx0;
    plan->fy[c][lane] = y - fy0;
    plan->ix[c][lane] = int32_t(fx0);
    plan->iy[c][lane] = int32_t(fy0);
    plan->base[c][lane] = dot(samplePoint(k) - ray.origin, w);  // t of the sample point, projected on the ray
  }
  plan->mask[lane] = mask;
}


void FieldQuery::Impl::prefetchPlan(const detail::PlanBlock& plan, size_t lane) const noexcept {
  for (uint32_t bits = plan.mask[lane]; bits != 0; bits &= bits - 1) {
    const unsigned c = unsigned(__builtin_ctz(bits));
    const uint32_t k = uint32_t(plan.k[c][lane]);
    const uint32_t ti = uint32_t(std::clamp(plan.ix[c][lane], 0, int(m) - 1));
    __builtin_prefetch(texelAddress(k, ti, uint32_t(std::clamp(plan.iy[c][lane], 0, int(m) - 1))));
    __builtin_prefetch(texelAddress(k, ti, uint32_t(std::clamp(plan.iy[c][lane] + 1, 0, int(m) - 1))));
  }
}

QueryHit FieldQuery::Impl::blendInterpolated(const Ray& ray, const Lookup& l, const detail::PlanBlock& plan,
                                             size_t lane, float* visibility) const noexcept {
  const float lo = l.lo, hi = l.hi;
  const float along = l.inside ? -1.0f : 1.0f;  // t per unit distance along v
  detail::Blend bl;
  for (uint32_t bits = plan.mask[lane]; bits != 0; bits &= bits - 1) {
    const unsigned c = unsigned(__builtin_ctz(bits));
    const uint32_t k = uint32_t(plan.k[c][lane]);
    const float fx = plan.fx[c][lane], fy = plan.fy[c][lane], weight = plan.weight[c][lane];
    const float base = plan.base[c][lane];
    const int ix = plan.ix[c][lane], iy = plan.iy[c][lane];
    for (int dj = 0; dj < 2; ++dj) {
      for (int di = 0; di < 2; ++di) {
        const float bw = weight * (di ? fx : 1.0f - fx) * (dj ? fy : 1.0f - fy);
        if (bw <= 0) continue;
        const uint32_t ti = uint32_t(std::clamp(ix + di, 0, int(m) - 1));
        const uint32_t tj = uint32_t(std::clamp(iy + dj, 0, int(m) - 1));
        const detail::Sample s = texel(k, ti, tj);
        if (!s.hit) {
          bl.missWeight += bw;
          continue;
        }
        const float t = base + along * s.distance;
        if (t > hi) {
          bl.farWeight += bw;
        } else if (t < lo) {
          bl.nearWeight += bw;
        } else {
          bl.hitWeight += bw;
          bl.tSum += bw * t;
          if (!norm.empty()) bl.normalSum = bl.normalSum + normalAt(k, ti, tj) * bw;
        }
      }
    }
  }
  return blendResult(ray, l, bl, visibility);
}

QueryHit FieldQuery::Impl::interpolated(const Ray& ray, const Lookup& l, float* visibility) const noexcept {
  needNeighbours();
  detail::PlanBlock plan;  // (lane 0 only)
  planInterpolated(ray, l, &plan, 0);
  if (l.off) return offInterpolated(ray, l, plan, 0, nullptr, visibility);
  return blendInterpolated(ray, l, plan, 0, visibility);
}

QueryHit FieldQuery::intersect(const Ray& ray, const QueryOptions& options) const noexcept {
  return impl_ ? impl_->query(ray, options, nullptr) : QueryHit{};
}

bool FieldQuery::occluded(const Ray& ray, const QueryOptions& options) const noexcept {
  return impl_ && impl_->query(ray, options, nullptr).hit;
}

float FieldQuery::visibility(const Ray& ray, const QueryOptions& options) const noexcept {
  if (!impl_) return 1.0f;
  float v = 1.0f;
  impl_->query(ray, options, &v);
  return v;
}

}  // namespace vff
