// kernel_interpolated.h - the interpolated lookup of a block of rays: the planner of
// their taps and the blend of the taps' texels; GroupKernel::plan and blend (query_group.h) for
// lanes F.
// Part of the group kernel (query_group_kernel.h, which says what the lane types must provide and
// why every function here sits in an unnamed namespace): included through it only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "query/batch/kernel_lanes.h"
#include "query/batch/kernel_math.h"
#include "query/batch/query_group.h"

namespace vff::detail {
namespace {

// GroupKernel::plan (query_group.h) with lanes F: each line mirrors a line of
// FieldQuery::Impl::planInterpolated (its kernel weight, toLocal of the sample's frame,
// hemisphereToSquareFast, the footprint and the sample point's distance along the ray) or of
// frameFromNormal, with the same binary32 operations in the same order.
template <class F>
void planWith(const PlanTables& tb, const PlanRays& in, PlanBlock* out) {
  constexpr size_t L = F::kLanes;
  static_assert(kPlanLanes % L == 0, "whole vectors of lanes");
  const F zero(0.0f), one(1.0f), half(0.5f);
  const F kr2(tb.kernelRadius2), minWeight(1e-6f), fm(float(tb.m));
  const F cx(tb.center.x), cy(tb.center.y), cz(tb.center.z), radius(tb.radius);
  for (size_t l = 0; l < kPlanLanes; ++l) out->mask[l] = 0;
  for (size_t c0 = 0; c0 < kPlanLanes; c0 += L) {
    const F eux = F::load(in.eux + c0), euy = F::load(in.euy + c0), euz = F::load(in.euz + c0);
    const F vx = F::load(in.vx + c0), vy = F::load(in.vy + c0), vz = F::load(in.vz + c0);
    const F wx = F::load(in.wx + c0), wy = F::load(in.wy + c0), wz = F::load(in.wz + c0);
    const F ox = F::load(in.ox + c0), oy = F::load(in.oy + c0), oz = F::load(in.oz + c0);
    // (k0 < 2^24: exact as a float.)
    const F k0 = F::loadInt(reinterpret_cast<const int32_t*>(in.k0 + c0));
    const auto planned = eq(F::loadInt(reinterpret_cast<const int32_t*>(in.active + c0)), one);
    auto ended = F::Mask::none();  // lanes whose neighbour list has ended (as planInterpolated's break)
    for (size_t c = 0; c < kPlanSlots; ++c) {
      // The slot's sample (the nearest, or neighbour c - 1 of it) and its position; lanes without
      // one read sample 0 and are left out.
      const auto active = bandnot(ended, planned);
      F k = band(active, k0);
      if (c > 0) k = gatherWord(tb.neighbours, k, int32_t(kQueryNeighbours), int32_t(c - 1), active);
      const auto end = band(active, eq(k, F(-1.0f)));  // UINT32_MAX
      ended = bor(ended, end);
      const auto use = bandnot(end, active);
      k = band(use, k);
      F ux0, uy0, uz0;
      gatherUnit(tb.unit4, k, &ux0, &uy0, &uz0);
      // The kernel weight: (1 - |eu - u|^2 / r^2)^2 where positive; the nearest sample at least 1e-6.
      const F dx = eux - ux0, dy = euy - uy0, dz = euz - uz0;
      const F x = one - (dx * dx + dy * dy + dz * dz) / kr2;
      F weight = sel(gt(x, zero), x * x, zero);
      auto keep = use;
      if (c == 0)
        weight = maxStd(weight, minWeight);
      else
        keep = band(keep, gt(weight, zero));
      if (movemask(keep) == 0) continue;
      // The direction in the sample's frame.
      F lx, ly, lz, a, b;
      toSampleFrame(ux0, uy0, uz0, vx, vy, vz, &lx, &ly, &lz);
      keep = bandnot(le(lz, zero), keep);  // the sample does not see this direction
      const unsigned bits = movemask(keep);
      if (bits == 0) continue;
      hemisphereToSquareV<true>(tb.scheme, lx, ly, lz, &a, &b);
      // The bilinear footprint.
      const F px = (a + one) * half * fm - half, py = (b + one) * half * fm - half;
      const F fx0 = floorV(px), fy0 = floorV(py);
      // The sample point's distance along the ray: (centre + u R - origin) . w.
      const F sx = (cx + ux0 * radius) - ox, sy = (cy + uy0 * radius) - oy, sz = (cz + uz0 * radius) - oz;
      const F base = sx * wx + sy * wy + sz * wz;
      storeInt(out->k[c] + c0, k);
      storeInt(out->ix[c] + c0, fx0);
      storeInt(out->iy[c] + c0, fy0);
      if (tb.texels) {  // the two texel rows of the footprint, as FieldQuery::Impl::prefetchPlan
        const F top = fm - one, col = vmin(vmax(fx0, zero), top);
        alignas(64) int32_t row0[L], row1[L];
        storeTexelIndex(row0, k, vmin(vmax(fy0, zero), top) * fm + col, tb.mapBytes);
        storeTexelIndex(row1, k, vmin(vmax(fy0 + one, zero), top) * fm + col, tb.mapBytes);
        for (unsigned m = bits; m != 0; m &= m - 1) {
          __builtin_prefetch(tb.texels + row0[__builtin_ctz(m)]);
          __builtin_prefetch(tb.texels + row1[__builtin_ctz(m)]);
        }
      }
      store(out->fx[c] + c0, px - fx0);
      store(out->fy[c] + c0, py - fy0);
      store(out->weight[c] + c0, weight);
      store(out->base[c] + c0, base);
      for (unsigned m = bits; m != 0; m &= m - 1) out->mask[c0 + unsigned(__builtin_ctz(m))] |= 1u << c;
    }
  }
}


// GroupKernel::blend (query_group.h) with lanes F: each lane accumulates its taps in slot order and
// each tap's texels (ix, iy), (ix + 1, iy), (ix, iy + 1), (ix + 1, iy + 1) in that order, as
// FieldQuery::Impl::blendInterpolated does, with the same binary32 operations (a texel's weight
// (weight * wx) * wy; t = base + distance, the ray being from outside).
template <class F>
void blendWith(const BlendTables& tb, const PlanBlock& plan, const BlendRays& in, BlendSums* out) {
  constexpr size_t L = F::kLanes;
  static_assert(kPlanLanes % L == 0, "whole vectors of lanes");
  const F zero(0.0f), one(1.0f), fm(float(tb.m)), top(float(tb.m) - 1.0f), scale(tb.distanceScale), missCode(255.0f);
  for (size_t c0 = 0; c0 < kPlanLanes; c0 += L) {
    const F lo = F::load(in.lo + c0), hi = F::load(in.hi + c0);
    F hitW = zero, missW = zero, farW = zero, tSum = zero, nsx = zero, nsy = zero, nsz = zero;
    for (size_t c = 0; c < kPlanSlots; ++c) {
      alignas(64) int32_t tap[L];
      unsigned any = 0;
      for (size_t l = 0; l < L; ++l) {
        tap[l] = int32_t((plan.mask[c0 + l] >> c) & 1u);
        any |= unsigned(tap[l]);
      }
      if (any == 0) continue;
      // Lanes without this tap read texel 0 of map 0 and add nothing.
      const auto inSlot = eq(F::loadInt(tap), one);
      const F k = band(inSlot, F::loadInt(plan.k[c] + c0));
      const F ix = F::loadInt(plan.ix[c] + c0), iy = F::loadInt(plan.iy[c] + c0);
      const F fx = F::load(plan.fx[c] + c0), fy = F::load(plan.fy[c] + c0);
      const F weight = F::load(plan.weight[c] + c0), base = F::load(plan.base[c] + c0);
      const F wx[2] = {one - fx, fx}, wy[2] = {one - fy, fy};
      for (int dj = 0; dj < 2; ++dj) {
        for (int di = 0; di < 2; ++di) {
          const F bw = weight * wx[di] * wy[dj];
          const auto take = bandnot(le(bw, zero), inSlot);  // (blendInterpolated skips bw <= 0)
          const F ti = vmin(vmax(ix + F(float(di)), zero), top), tj = vmin(vmax(iy + F(float(dj)), zero), top);
          const F texel = band(inSlot, tj * fm + ti);
          alignas(64) int32_t at[L];
          storeTexelIndex(at, k, texel, tb.mapBytes);
          const F code = F::gatherBytes(tb.texels, at);
          const auto hit = bandnot(eq(code, missCode), take);
          missW = sel(bandnot(hit, take), missW + bw, missW);
          const F t = base + code * scale;
          const auto far = band(hit, gt(t, hi));  // beyond the range: unoccluded
          farW = sel(far, farW + bw, farW);
          const auto counted = bandnot(bor(far, lt(t, lo)), hit);  // (before the range: left out)
          hitW = sel(counted, hitW + bw, hitW);
          tSum = sel(counted, tSum + bw * t, tSum);
          if (tb.normals) {
            alignas(64) int32_t atNormal[L];
            storeTexelIndex(atNormal, k, texel * F(4.0f), tb.normalMapBytes);  // (4 bytes a texel)
            F cx, cy, nx, ny, nz;
            F::gatherSnorm16Pairs(tb.normals, atNormal, &cx, &cy);
            decodeNormalV(cx, cy, &nx, &ny, &nz);
            nsx = sel(counted, nsx + nx * bw, nsx);
            nsy = sel(counted, nsy + ny * bw, nsy);
            nsz = sel(counted, nsz + nz * bw, nsz);
          }
        }
      }
    }
    store(out->hit + c0, hitW);
    store(out->miss + c0, missW);
    store(out->far + c0, farW);
    store(out->tSum + c0, tSum);
    store(out->nx + c0, nsx);
    store(out->ny + c0, nsy);
    store(out->nz + c0, nsz);
  }
}

}  // namespace
}  // namespace vff::detail
