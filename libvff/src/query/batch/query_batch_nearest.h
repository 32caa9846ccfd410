// query_batch_nearest.h - FieldQuery::Impl::batchNearest: batches of nearest lookups through the
// group kernel (query_group.h). A template over what each answer is written to (hits, hit bytes,
// visibilities), included only by query_batch.cpp, which instantiates it for each batch call.
#pragma once

#include "query/query_impl.h"

namespace vff {

// Batches of nearest lookups run in groups: the group kernel (query_group.h) prepares every ray
// of a group, prepare() redoes the few rays the kernel leaves to it, the texels of the group are
// requested from memory together, and then decoded (by the kernel itself where it can). The
// scattered texel reads of a group overlap instead of waiting one after the other.
//
// kHitOnly: emit(base, n, hits) for each run of n <= 64 rays from base, bit r of `hits` saying
// whether ray base + r hits. Otherwise: emit(r, const QueryHit&, float visibility) per ray.
template <bool kHitOnly, class Emit>
void FieldQuery::Impl::batchNearest(std::span<const Ray> rays, const QueryOptions& o, const detail::ToObject* to,
                                    Emit&& emit) const noexcept {
  const bool refined = o.reconstruction == Reconstruction::kRefined && !bvh.empty();
  auto objectRay = [&](size_t r) { return to ? to->ray(rays[r]) : rays[r]; };
  // A batch of one ray (an Embree callback for rtcIntersect1 or rtcOccluded1) takes the reference
  // path: a group's fixed cost is larger than the ray's own, and there are no other texel reads
  // for its read to overlap. (batchInterpolated does the same.) From two rays on, the group
  // kernel's SIMD lanes answer each ray for less than the reference steps do, even for an Embree
  // packet of 16 (vff-experiments bench --batch 16 compares them).
  const detail::GroupKernel* kernel = rays.size() > 1 ? detail::groupKernel() : nullptr;
  if (!kernel) {
    for (size_t base = 0; base < rays.size(); base += detail::kGroupRays) {
      const size_t n = std::min(detail::kGroupRays, rays.size() - base);
      uint64_t hits = 0;
      for (size_t r = 0; r < n; ++r) {
        float vis = 1.0f;
        Lookup l;
        const Ray ray = objectRay(base + r);
        const QueryHit h = !prepare(ray, o, &l) ? QueryHit{}
                           : refined ? refinedAt(ray, l.k0, l.i, l.j, l.t0, l.inside, l.lo, l.hi, l.len, kHitOnly, &vis)
                                     : nearestAnswer(ray, l, &vis);
        if constexpr (kHitOnly) {
          hits |= uint64_t(h.hit) << r;
        } else {
          emit(base + r, h, vis);
        }
      }
      if constexpr (kHitOnly) emit(base, n, hits);
    }
    return;
  }
  // (kRefined reads each lane's texel and window itself: the kernel does not decode its hits.)
  const detail::GroupTables tables = detail::toObjectTables(groupTables(o, kHitOnly && !refined), to);
  forEachGroup(*kernel, rays, tables, [&](size_t base, size_t n, detail::Group& g) {
    // Every ray misses unless it reaches the sphere.
    if constexpr (!kHitOnly) detail::forEachClear(g.reached, n, [&](size_t r) { emit(base + r, QueryHit{}, 1.0f); });
    // The rays the kernel left to the reference.
    uint64_t dead = 0;
    for (uint64_t redo = g.redo; redo != 0; redo &= redo - 1) {
      const uint32_t p = uint32_t(__builtin_ctzll(redo)), r = g.ray[p];
      Lookup l;
      if (!prepare(objectRay(base + r), o, &l)) {
        dead |= uint64_t(1) << p;
        continue;
      }
      g.k[p] = l.k0;
      g.i[p] = l.i;
      g.j[p] = l.j;
      g.t0[r] = l.t0;
      g.lo[r] = l.lo;
      g.hi[r] = l.hi;
      g.len[r] = l.len;
      g.inside = (g.inside & ~(uint64_t(1) << r)) | (uint64_t(l.inside) << r);
    }
    for (uint64_t redo = g.redo; redo != 0; redo &= redo - 1) {  // the kernel prefetched the others
      const uint32_t p = uint32_t(__builtin_ctzll(redo));
      __builtin_prefetch(texelAddress(g.k[p], g.i[p], g.j[p]));
    }
    if constexpr (kHitOnly) {
      // The kernel decoded all but the redone rays, or none of them.
      uint64_t hits = tables.decodeHits ? g.hits : 0;
      const uint64_t left = tables.decodeHits ? g.redo : detail::packedBits(g.count);
      for (uint64_t todo = left & ~dead; todo != 0; todo &= todo - 1) {
        const uint32_t p = uint32_t(__builtin_ctzll(todo)), r = g.ray[p];
        if (refined) {
          if (refinedHitsAt([&] { return objectRay(base + r); }, g.k[p], g.i[p], g.j[p], g.t0[r], (g.inside >> r) & 1u,
                            g.lo[r], g.hi[r], g.len[r]))
            hits |= uint64_t(1) << r;
          continue;
        }
        // (t0 < 0: an off-object ray from inside the sphere, section 7.4)
        const bool hit = g.t0[r] < 0 ? offHitsAt(objectRay(base + r), g.k[p], g.i[p], g.j[p], g.t0[r], g.lo[r], g.hi[r])
                                     : hitsAt(g.k[p], g.i[p], g.j[p], g.t0[r], (g.inside >> r) & 1u, g.lo[r], g.hi[r]);
        if (hit) hits |= uint64_t(1) << r;
      }
      emit(base, n, hits);
    } else {
      for (uint32_t p = 0; p < g.count; ++p) {
        const uint32_t r = g.ray[p];
        float vis = 1.0f;
        QueryHit h;
        if ((dead >> p) & 1u) {
        } else if (refined) {
          h = refinedAt(objectRay(base + r), g.k[p], g.i[p], g.j[p], g.t0[r], (g.inside >> r) & 1u, g.lo[r], g.hi[r],
                        g.len[r], false, &vis);
        } else if (g.t0[r] < 0) {
          h = offHitAt(objectRay(base + r), g.k[p], g.i[p], g.j[p], g.t0[r], g.lo[r], g.hi[r], g.len[r], &vis);
        } else {
          h = hitAt(objectRay(base + r), g.k[p], g.i[p], g.j[p], g.t0[r], (g.inside >> r) & 1u, g.lo[r], g.hi[r],
                    g.len[r], &vis);
        }
        emit(base + r, h, vis);
      }
    }
  });
}

}  // namespace vff
