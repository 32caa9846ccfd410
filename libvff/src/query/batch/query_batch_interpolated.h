// query_batch_interpolated.h - FieldQuery::Impl::batchInterpolated: batches of interpolated
// lookups through the group kernel's sphere step, planner and blend (query_group.h). A template
// over what each answer is written to, included only by query_batch.cpp.
#pragma once

#include "query/query_impl.h"

namespace vff {

// Batches of interpolated lookups. The group kernel finds, for 64 rays at a time, those that reach
// the sphere and their nearest samples; they fill blocks of 16, whatever group they came from (a
// third of the AO rays reach the sphere: blocks cut at each group's end would run part-empty), and
// each block is planned together (the kernel's plan(), as planInterpolated() one ray at a time)
// with all its taps' texels requested from memory, then blended, 16 at a time too where the kernel
// can (its blend(), as blendInterpolated() one ray at a time). Rays answered by section 7.3 are
// answered as kNearest (query()); section 7.4's as offInterpolated() says. (Blending a block while the next is planned, so that its texels
// had longer to arrive, gained nothing measurable.)
template <class Emit>
void FieldQuery::Impl::batchInterpolated(std::span<const Ray> rays, const QueryOptions& o, Emit&& emit) const noexcept {
  if (rays.size() == 1) {  // (as batchNearest: a block's fixed cost is larger than one ray's own)
    float vis = 1.0f;
    const QueryHit h = query(rays[0], o, &vis);
    emit(size_t(0), h, vis);
    return;
  }
  constexpr size_t kPlanned = detail::kPlanLanes;
  const detail::GroupKernel* kernel = detail::groupKernel();  // (one for the whole batch)
  needNeighbours();
  Lookup l[kPlanned];
  detail::PlanBlock plan{};  // (zeroed: the blend kernel reads every lane of a slot)
  size_t which[kPlanned];    // the lanes' rays (indices into rays)
  bool live[kPlanned];
  auto finish = [&](size_t count) {
    // The blends of the block's rays from outside the sphere, 16 at once where the kernel can.
    detail::BlendSums sums;
    bool summed = false;
    if (blendTables.texels) {
      bool any = false;
      detail::BlendRays br;
      for (size_t c = 0; c < kPlanned; ++c) {
        const bool blended = c < count && live[c] && !l[c].inside;
        any = any || blended;
        br.lo[c] = blended ? (l[c].off ? l[c].lo - offTolerance : l[c].lo) : 0.0f;  // (offInterpolated's window)
        br.hi[c] = blended ? l[c].hi : 0.0f;
      }
      if (any && kernel && kernel->blend) {
        kernel->blend(blendTables, plan, br, &sums);
        summed = true;
      }
    }
    for (size_t c = 0; c < count; ++c) {
      const Ray& ray = rays[which[c]];
      float vis = 1.0f;
      QueryHit h;
      if (live[c] && l[c].inside) {
        h = nearestHit(ray, l[c], &vis);
      } else if (live[c] && l[c].off) {
        h = offInterpolated(ray, l[c], plan, c, summed ? &sums : nullptr, &vis);
      } else if (live[c] && summed) {
        detail::Blend bl;
        bl.hitWeight = sums.hit[c];
        bl.missWeight = sums.miss[c];
        bl.farWeight = sums.far[c];
        bl.tSum = sums.tSum[c];
        bl.normalSum = {sums.nx[c], sums.ny[c], sums.nz[c]};
        h = blendResult(ray, l[c], bl, &vis);
      } else if (live[c]) {
        h = blendInterpolated(ray, l[c], plan, c, &vis);
      }
      emit(which[c], h, vis);
    }
  };
  // Requests the texels of lane c (planned, where its ray starts outside the sphere).
  auto request = [&](size_t c) {
    if (!live[c]) return;
    if (l[c].inside)
      __builtin_prefetch(texelAddress(l[c].k0, l[c].i, l[c].j));
    else
      prefetchPlan(plan, c);
  };
  if (!kernel) {
    for (size_t base = 0; base < rays.size(); base += kPlanned) {
      const size_t n = std::min(kPlanned, rays.size() - base);
      for (size_t r = 0; r < n; ++r) {
        which[r] = base + r;
        live[r] = prepare(rays[base + r], o, &l[r]);
        if (live[r] && !l[r].inside) planInterpolated(rays[base + r], l[r], &plan, r);
        request(r);
      }
      finish(n);
    }
    return;
  }
  const detail::PlanTables tables = planTables();
  detail::PlanRays in{};  // the block being filled (lanes not planned: zero, inactive)
  size_t count = 0;       // its lanes filled
  auto runBlock = [&] {
    bool any = false;
    for (size_t c = 0; c < count; ++c) any = any || in.active[c] != 0;
    const bool kernelPlans = any && floatMapIndices && kernel->plan;
    if (kernelPlans) {
      kernel->plan(tables, in, &plan);
    } else if (any) {
      for (size_t c = 0; c < count; ++c) {
        if (in.active[c])
          planInterpolated(rays[which[c]], l[c], &plan, c);
        else
          plan.mask[c] = 0;
      }
    }
    // (The kernel's plan has requested the texels of its lanes where it knows where they lie.)
    for (size_t c = 0; c < count; ++c)
      if (!(kernelPlans && tables.texels && in.active[c])) request(c);
    finish(count);
    in = {};
    count = 0;
  };
  forEachGroup(*kernel, rays, groupTables(o, false), [&](size_t base, size_t n, detail::Group& g) {
    detail::forEachClear(g.reached, n, [&](size_t r) { emit(base + r, QueryHit{}, 1.0f); });
    for (uint32_t p = 0; p < g.count; ++p) {
      const size_t c = count;
      const uint32_t r = g.ray[p];
      const Ray& ray = rays[base + r];
      which[c] = base + r;
      if ((g.redo >> p) & 1u) {
        live[c] = prepare(ray, o, &l[c]);
      } else {
        live[c] = true;
        lookupFrom(ray, g.len[r], g.t0[r], (g.inside >> r) & 1u, g.lo[r], g.hi[r], &l[c]);
        l[c].k0 = g.k[p];
        l[c].i = g.i[p];
        l[c].j = g.j[p];
      }
      if (live[c] && !l[c].inside) {
        in.eux[c] = l[c].eu.x;
        in.euy[c] = l[c].eu.y;
        in.euz[c] = l[c].eu.z;
        in.vx[c] = l[c].v.x;
        in.vy[c] = l[c].v.y;
        in.vz[c] = l[c].v.z;
        in.wx[c] = l[c].w.x;
        in.wy[c] = l[c].w.y;
        in.wz[c] = l[c].w.z;
        in.ox[c] = ray.origin.x;
        in.oy[c] = ray.origin.y;
        in.oz[c] = ray.origin.z;
        in.k0[c] = l[c].k0;
        in.active[c] = 1;
      }
      if (++count == kPlanned) runBlock();
    }
  });
  if (count) runBlock();
}

}  // namespace vff
