// kernel_math.h - the lookup's maths per lane: each function repeats, lane by
// lane, one step of the one-ray query with the same binary32 operations in the same order (the
// step it mirrors is named at each; tests/unit/test_kernel_math.cpp holds them to it).
// Part of the group kernel (query_group_kernel.h, which says what the lane types must provide and
// why every function here sits in an unnamed namespace): included through it only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "query/fast_lookup.h"
#include "query/batch/kernel_lanes.h"
#include "query/batch/query_group.h"

namespace vff::detail {
namespace {

// atanUnit of fast_lookup.h, per lane.
template <class F>
inline F atanUnitV(F t) {
  const F at = vabs(t);
  const auto big = gt(at, F(kTanPi8));
  const F one(1.0f);
  const F x = sel(big, (at - one) / (at + one), at);
  const F y0 = band(big, F(kQuarterPiF));
  const F z = x * x;
  const F p = (((F(kAtanP[0]) * z + F(kAtanP[1])) * z + F(kAtanP[2])) * z + F(kAtanP[3])) * z * x + x;
  const F r = y0 + p;
  return sel(lt(t, F(0.0f)), vneg(r), r);
}

// A world-space ray to object space (GroupTables::toObject), as ToObject in query/query_impl.h:
// (r^T (p - translation)) / scale, each row a left-to-right sum of products, then times 1 / scale.
template <class F>
inline void toObjectLanes(const GroupTables& tb, F* ox, F* oy, F* oz, F* dx, F* dy, F* dz) {
  const auto& r = tb.objectRotation;
  const F s(tb.objectInvScale);
  auto row = [&](int c, F x, F y, F z) { return ((F(r[0][c]) * x + F(r[1][c]) * y) + F(r[2][c]) * z) * s; };
  const F px = *ox - F(tb.objectShift.x), py = *oy - F(tb.objectShift.y), pz = *oz - F(tb.objectShift.z);
  *ox = row(0, px, py, pz);
  *oy = row(1, px, py, pz);
  *oz = row(2, px, py, pz);
  const F vx = *dx, vy = *dy, vz = *dz;
  *dx = row(0, vx, vy, vz);
  *dy = row(1, vx, vy, vz);
  *dz = row(2, vx, vy, vz);
}

// v in the frame of the sample at unit position u: frameFromNormal of its inward normal -u (as
// PositionSet::frame), then toLocal.
template <class F>
inline void toSampleFrame(F ux, F uy, F uz, F vx, F vy, F vz, F* lx, F* ly, F* lz) {
  const F zero(0.0f), one(1.0f);
  const F nx = vneg(ux), ny = vneg(uy), nz = vneg(uz);
  const F fs = sel(ge(nz, zero), one, F(-1.0f));
  const F fA = vneg(one / (fs + nz));
  const F fk = nx * ny * fA;
  const F tx = one + fs * nx * nx * fA, ty = fs * fk, tz = vneg(fs) * nx;
  const F bx = fk, by = fs + ny * ny * fA, bz = vneg(ny);
  *lx = vx * tx + vy * ty + vz * tz;
  *ly = vx * bx + vy * by + vz * bz;
  *lz = vx * nx + vy * ny + vz * nz;
}

// hemisphereToSquareFast (fast_lookup.h) per lane: the square point (a, b) of local direction l
// (finite: the clamps take NaN to -1 or 1, where std::min and std::max keep it).
// kAxis: also its answer (r, 0) for directions with x = y = 0 (the group kernel redoes those
// lanes: they lie on the concentric map's octant diagonals).
template <bool kAxis, class F>
inline void hemisphereToSquareV(DirectionScheme scheme, F lx, F ly, F lz, F* a, F* b) {
  const F zero(0.0f), one(1.0f), mone(-1.0f);
  const F z = vmax(lz, zero);  // std::max(0.0f, z): 0 for NaN and -0
  if (scheme == DirectionScheme::kHemiOctahedral) {
    const F hinv = one / (vabs(lx) + vabs(ly) + z);
    const F x = lx * hinv, y = ly * hinv;
    *a = x + y;
    *b = x - y;
  } else {
    const F r = vsqrt(vmax(one - z, zero));
    const F lax = vabs(lx), lay = vabs(ly);
    const F k = r * F(4.0f / 3.14159265358979323846f);
    const auto bigX = gt(lax, lay);
    const F s = atanUnitV(sel(bigX, ly, lx) / sel(bigX, lx, ly)) * k;
    const auto xNeg = lt(lx, zero), yNeg = lt(ly, zero);
    *a = sel(bigX, sel(xNeg, vneg(r), r), sel(yNeg, vneg(s), s));
    *b = sel(bigX, sel(xNeg, vneg(s), s), sel(yNeg, vneg(r), r));
    if (kAxis) {
      const auto axis = band(eq(lax, zero), eq(lay, zero));
      *a = sel(axis, r, *a);
      *b = sel(axis, zero, *b);
    }
  }
  *a = vmin(vmax(*a, mone), one);
  *b = vmin(vmax(*b, mone), one);
}

// decodeNormal (encoding.cpp) per lane, from the two snorm16 codes (cx, cy) of oct-snorm16.
template <class F>
inline void decodeNormalV(F cx, F cy, F* x, F* y, F* z) {
  const F one(1.0f), mone(-1.0f), zero(0.0f), snorm(32767.0f);
  const F px = maxStd(cx / snorm, mone), py = maxStd(cy / snorm, mone);
  const F nz = (one - vabs(px)) - vabs(py);
  const auto fold = lt(nz, zero);
  const F ox = (one - vabs(py)) * sel(ge(px, zero), one, mone);
  const F oy = (one - vabs(px)) * sel(ge(py, zero), one, mone);
  const F nx = sel(fold, ox, px), ny = sel(fold, oy, py);
  const F len = vsqrt(nx * nx + ny * ny + nz * nz);
  *x = nx / len;
  *y = ny / len;
  *z = nz / len;
}

}  // namespace
}  // namespace vff::detail
