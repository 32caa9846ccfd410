// query_group_kernel.h - the group kernel of query_group.h, written once for any SIMD width.
//
// Included by query_group_sse2.cpp (four-lane vectors), query_group_avx2.cpp (eight-lane vectors)
// and query_group_avx512.cpp (sixteen-lane vectors), each compiled for its instruction set and
// called only where the CPU has it. Everything here sits in an anonymous namespace, so each of
// those files gets its own copy compiled for its own instruction set, and no function compiled
// for AVX2 or AVX-512 can be shared with code that runs on a CPU without it.
//
// The vector type H (a float vector with +, -, *, / and the free functions used below, and static
// load, loadInt, gatherBytes, compressIndex and hitsByRay; AVX2 and AVX-512: gatherSnorm16Pairs)
// and its mask type H::Mask (what comparisons give: band, bor, bandnot, bnot, sel and movemask take
// it; the vector itself, all-ones or zero per lane, in SSE2 and AVX2; a mask register in AVX-512,
// which takes fewer instructions than vector masks) are
// defined by the including file, which runs the kernel on lanes F = Pair<H> or Pair<Pair<H>> (the
// interpolated planner and blend, planWith and blendWith, on H itself, AVX2 and AVX-512 only): two
// or four vectors side by side, so that the CPU overlaps their long dependency chains (the nearest
// sample, then the frame, then the texel). With eight-lane vectors, 32 lanes run 1.2-1.3x faster
// than 8 on the aimed rays of vff-experiments bench and 1.1x on its AO rays; with four-lane
// vectors 8 lanes beat 4 and 16; with sixteen-lane vectors 32 lanes beat 16 by about 1.1x.
// (The in-process A/B figures in the kernel's comments: builds of libvff loaded side by side in
// one process, taking turns over the bench's rays. Two builds of the same code differ there by
// up to 3.5% (code placement), so figures within a few percent of 1 do not tell a change apart.)
// Every line that computes a quantity prepare() also computes mirrors a line
// of FieldQuery::Impl::prepare() or of fast_lookup.h with the same binary32 operations in the
// same order (a ? b : c becomes sel(mask, b, c); no operation is fused or reordered), so that a
// lane computes bit for bit what prepare() computes for that ray. The one quantity of its own, a
// candidate's score, uses the CPU's approximate reciprocal square root, which differs between
// CPU makers and between rsqrtps and AVX-512's rsqrt14ps: it only decides which sample wins when
// the lead is beyond its error bound (closer leads are settled by the reference's own scores), so
// the answers are the same everywhere, and only which lanes are settled that way can differ.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fast_lookup.h"
#include "query_group.h"

namespace vff::detail {
namespace {

// Bit g.ray[p] for every bit p set in `packed` (packed ray p), from H::rayBits a vector at a time
// (the hitsByRay of lane types without a bit deposit: AVX2, SSE2).
template <class H>
uint64_t hitsByRayBits(const Group& g, uint64_t packed) {
  uint64_t out = 0;
  for (size_t p = 0; p < g.count; p += H::kLanes)
    out |= H::rayBits(g.ray + p, unsigned(packed >> p) & ((1u << H::kLanes) - 1));
  return out;
}

// Two lane vectors taken as one twice as wide (see the top of the file).
template <class H>
struct Pair {
  static constexpr size_t kLanes = 2 * H::kLanes;
  static constexpr unsigned kHalf = (1u << H::kLanes) - 1;  // the first half's bits of a mask
  using Mask = Pair<typename H::Mask>;
  H a, b;
  Pair() = default;
  Pair(H x, H y) : a(x), b(y) {}
  explicit Pair(float x) : a(x), b(x) {}
  static Pair none() { return {H::none(), H::none()}; }
  static Pair load(const float* p) { return {H::load(p), H::load(p + H::kLanes)}; }
  static Pair loadInt(const int32_t* p) { return {H::loadInt(p), H::loadInt(p + H::kLanes)}; }
  static Pair gatherBytes(const uint8_t* base, const int32_t* at) {
    return {H::gatherBytes(base, at), H::gatherBytes(base, at + H::kLanes)};
  }
  static void compressIndex(uint32_t* dst, uint32_t first, unsigned mask) {
    H::compressIndex(dst, first, mask & kHalf);
    H::compressIndex(dst + __builtin_popcount(mask & kHalf), first + uint32_t(H::kLanes), mask >> H::kLanes);
  }
  static uint64_t hitsByRay(const Group& g, uint64_t packed) { return H::hitsByRay(g, packed); }
};

template <class H> inline Pair<H> operator+(Pair<H> x, Pair<H> y) { return {x.a + y.a, x.b + y.b}; }
template <class H> inline Pair<H> operator-(Pair<H> x, Pair<H> y) { return {x.a - y.a, x.b - y.b}; }
template <class H> inline Pair<H> operator*(Pair<H> x, Pair<H> y) { return {x.a * y.a, x.b * y.b}; }
template <class H> inline Pair<H> operator/(Pair<H> x, Pair<H> y) { return {x.a / y.a, x.b / y.b}; }
// (Lanes or masks: with AVX-512 a comparison gives a mask of another type, and band and bandnot
// also take a mask and lanes.)
#define VFF_PAIR_UNARY(f)                              \
  template <class H>                                   \
  inline auto f(Pair<H> x) -> Pair<decltype(f(x.a))> { \
    return {f(x.a), f(x.b)};                           \
  }
#define VFF_PAIR_BINARY(f)                                             \
  template <class A, class B>                                          \
  inline auto f(Pair<A> x, Pair<B> y) -> Pair<decltype(f(x.a, y.a))> { \
    return {f(x.a, y.a), f(x.b, y.b)};                                 \
  }
VFF_PAIR_UNARY(vsqrt)
VFF_PAIR_UNARY(vrsqrt)
VFF_PAIR_UNARY(bnot)
VFF_PAIR_UNARY(vabs)
VFF_PAIR_UNARY(vneg)
VFF_PAIR_UNARY(floorPos)
VFF_PAIR_UNARY(maskValue)
VFF_PAIR_UNARY(valueMask)
VFF_PAIR_BINARY(vmin)
VFF_PAIR_BINARY(vmax)
VFF_PAIR_BINARY(gt)
VFF_PAIR_BINARY(ge)
VFF_PAIR_BINARY(lt)
VFF_PAIR_BINARY(le)
VFF_PAIR_BINARY(eq)
VFF_PAIR_BINARY(nlt)
VFF_PAIR_BINARY(ngt)
VFF_PAIR_BINARY(band)
VFF_PAIR_BINARY(bor)
VFF_PAIR_BINARY(bandnot)
#undef VFF_PAIR_UNARY
#undef VFF_PAIR_BINARY
template <class M, class H>
inline Pair<H> sel(Pair<M> m, Pair<H> x, Pair<H> y) {
  return {sel(m.a, x.a, y.a), sel(m.b, x.b, y.b)};
}
template <class H>
inline void store(float* p, Pair<H> x) {
  store(p, x.a);
  store(p + H::kLanes, x.b);
}
template <class H>
inline void storeInt(int32_t* p, Pair<H> x) {
  storeInt(p, x.a);
  storeInt(p + H::kLanes, x.b);
}
template <class H>
inline unsigned movemask(Pair<H> x) {
  return movemask(x.a) | (movemask(x.b) << H::kLanes);
}
template <class H>
inline void compress(float* dst, Pair<H> x, unsigned mask) {
  compress(dst, x.a, mask & Pair<H>::kHalf);
  compress(dst + __builtin_popcount(mask & Pair<H>::kHalf), x.b, mask >> H::kLanes);
}
template <class H>
inline void gatherUnit(const float* unit4, Pair<H> k, Pair<H>* x, Pair<H>* y, Pair<H>* z) {
  gatherUnit(unit4, k.a, &x->a, &y->a, &z->a);
  gatherUnit(unit4, k.b, &x->b, &y->b, &z->b);
}
template <class H, class M>
inline unsigned maskUnion(const uint8_t* table, Pair<H> idx, Pair<M> use) {
  return maskUnion(table, idx.a, use.a) | maskUnion(table, idx.b, use.b);
}
template <class H, class M>
inline bool cornersSuffice(const uint32_t* rows, Pair<H> a0, Pair<H> b0, Pair<M> use) {
  return cornersSuffice(rows, a0.a, b0.a, use.a) && cornersSuffice(rows, a0.b, b0.b, use.b);
}
template <class H>
inline void storeTexelIndex(int32_t* dst, Pair<H> k, Pair<H> t, int32_t mapBytes) {
  storeTexelIndex(dst, k.a, t.a, mapBytes);
  storeTexelIndex(dst + H::kLanes, k.b, t.b, mapBytes);
}
template <class H>
inline void loadRays(const float* p, Pair<H>* ox, Pair<H>* oy, Pair<H>* oz, Pair<H>* dx, Pair<H>* dy, Pair<H>* dz,
                     Pair<H>* tmin, Pair<H>* tmax) {
  loadRays(p, &ox->a, &oy->a, &oz->a, &dx->a, &dy->a, &dz->a, &tmin->a, &tmax->a);
  loadRays(p + 8 * H::kLanes, &ox->b, &oy->b, &oz->b, &dx->b, &dy->b, &dz->b, &tmin->b, &tmax->b);
}
// std::max(a, b) as prepare() evaluates it: a < b ? b : a.
template <class F>
inline F maxStd(F a, F b) {
  return sel(lt(a, b), b, a);
}

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

// A world-space ray to object space (GroupTables::toObject), as ToObject in query.cpp:
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

// Step 1 for F::kLanes rays starting at rays[0] (all readable), lanes r0 .. of g: the sphere;
// appends the rays that reach it to g's packed rays and their lookups to q.
template <class F>
void sphereStep(const GroupTables& tb, const Ray* rays, Group* g, size_t r0, LookupQueue* q) {
  F ox, oy, oz, dx, dy, dz, tmin, tmax;
  loadRays(reinterpret_cast<const float*>(rays), &ox, &oy, &oz, &dx, &dy, &dz, &tmin, &tmax);
  if (tb.toObject) toObjectLanes(tb, &ox, &oy, &oz, &dx, &dy, &dz);
  const F zero(0.0f), one(1.0f);

  // prepare(): the ray's length and unit direction.
  const F len = vsqrt(dx * dx + dy * dy + dz * dz);
  typename F::Mask live = band(gt(len, zero), le(len, F(3.40282347e38f)));
  const F inv = one / len;
  const F wx = dx * inv, wy = dy * inv, wz = dz * inv;
  const F tminL = tmin * len, tmaxL = tmax * len;
  // 1. The sphere.
  const F cx(tb.center.x), cy(tb.center.y), cz(tb.center.z);
  const F ex = ox - cx, ey = oy - cy, ez = oz - cz;
  const F beta = ex * wx + ey * wy + ez * wz;
  const F gamma = (ex * ex + ey * ey + ez * ez) - F(tb.radius * tb.radius);
  const F disc = beta * beta - gamma;
  live = band(live, ge(disc, zero));
  const F sq = vsqrt(disc);
  const F nbeta = vneg(beta);
  const F t1 = nbeta + sq;
  live = band(live, nlt(t1, zero));
  const auto inside = le(gamma, zero);
  const F t0 = sel(inside, t1, maxStd(nbeta - sq, zero));
  const F lo = sel(inside, maxStd(tminL, F(tb.insideLo)), tminL);
  if (tb.bit1) live = bandnot(inside, live);
  live = bandnot(bandnot(inside, gt(t0, tmaxL)), live);
  const F vx = sel(inside, vneg(wx), wx), vy = sel(inside, vneg(wy), wy), vz = sel(inside, vneg(wz), wz);
  const F invR(1.0f / tb.radius);
  const F eux = ((ox + wx * t0) - cx) * invR;
  const F euy = ((oy + wy * t0) - cy) * invR;
  const F euz = ((oz + wz * t0) - cz) * invR;
  if (perRayState(tb)) {
    store(g->t0 + r0, t0);
    store(g->lo + r0, lo);
    store(g->hi + r0, tmaxL);
    store(g->len + r0, len);
    g->inside |= uint64_t(movemask(inside)) << r0;
  }
  const unsigned bits = movemask(live);
  if (bits == 0) return;
  g->reached |= uint64_t(bits) << r0;
  const size_t e = q->size;
  compress(q->eux + e, eux, bits);
  compress(q->euy + e, euy, bits);
  compress(q->euz + e, euz, bits);
  compress(q->vx + e, vx, bits);
  compress(q->vy + e, vy, bits);
  compress(q->vz + e, vz, bits);
  q->size += uint32_t(__builtin_popcount(bits));
  const size_t at = g->count;
  if (tb.decodeHits) {
    compress(g->pt0 + at, t0, bits);
    compress(g->plo + at, lo, bits);
    compress(g->phi + at, tmaxL, bits);
    compress(g->pinside + at, maskValue(inside), bits);
  }
  F::compressIndex(g->ray + at, uint32_t(r0), bits);
  g->count += uint32_t(__builtin_popcount(bits));
}

// Steps 2 and 3 for queue entries p .. p + kLanes - 1 (all valid; the caller pads the last ones):
// the nearest sample (octaNearestFast) and the texel (texelFast), into q's k, i, j, t and redo.
template <class F>
void lookupStep(const GroupTables& tb, size_t p, LookupQueue* q) {
  constexpr size_t L = F::kLanes;
  const F zero(0.0f), one(1.0f);
  const F eux = F::load(q->eux + p), euy = F::load(q->euy + p), euz = F::load(q->euz + p);
  const F vx = F::load(q->vx + p), vy = F::load(q->vy + p), vz = F::load(q->vz + p);

  // 2. The nearest sample.
  const float fnS = float(tb.octaN);
  const F fn(fnS);
  const F ax = vabs(eux), ay = vabs(euy), az = vabs(euz);
  const F l1 = ax + ay + az;
  typename F::Mask redo = bnot(band(gt(l1, zero), lt(l1, F(3.0e38f))));
  const F pa = ax / l1 * fn, pb = ay / l1 * fn;
  const F fa = floorPos(pa), fb = floorPos(pb);
  const F gg(tb.gridGuard);
  redo = bor(redo, bor(bor(lt(pa - fa, gg), lt((fa + one) - pa, gg)), bor(lt(pb - fb, gg), lt((fb + one) - pb, gg))));
  const F a0 = vmin(fa, fn - one), b0 = vmin(fb, fn - one);
  const F h = bandnot(ge(euz, zero), one);  // 0 upper, 1 lower hemisphere
  const auto negX = lt(eux, zero), negY = lt(euy, zero);
  const auto use = bnot(redo);
  // The candidates any lane needs (octaCandidateMasks); lanes not in use look up sample 0. Where
  // no lane's cell needs more than its four corners (octaCornerRows), the masks are not read.
  const unsigned needed = !tb.octaMasks ? 0xFFu
                          : tb.octaCornerRows && cornersSuffice(tb.octaCornerRows, a0, b0, use)
                              ? 0x0Fu
                              : maskUnion(tb.octaMasks, b0 * fn + a0, use);
  // Each candidate is scored without its table position: in the quadrant frame it is the grid
  // point g = (a, b, n - |a| - |b|), and its score g.(|x|, |y|, |z|) / |g| is the reference's
  // unit(k).eu (octaNearestFast) to within kOctaScoreError l1 (fast_lookup.h). The best score
  // wins when it leads the second best by more than twice that; otherwise the lane is redone. No
  // position is read until the winner is known.
  F best(-INFINITY), second(-INFINITY), bestA = zero, bestB = zero;
  const F nrHalf(0.5f), nrThreeHalves(1.5f), minusInf(-INFINITY);
  for (unsigned ci = 0; ci < 8; ++ci) {
    if (!((needed >> ci) & 1u)) continue;
    const F a = a0 + F(float(kOctaCandidates[ci][0])), b = b0 + F(float(kOctaCandidates[ci][1]));
    const F sum = vabs(a) + vabs(b);
    const F c = fn - sum;
    const F len2 = (a * a + b * b) + c * c;
    const F y0 = vrsqrt(len2);
    const F y = y0 * (nrThreeHalves - nrHalf * len2 * y0 * y0);  // 1 / |g|: one Newton step
    const F d = sel(le(sum, fn), ((a * ax + b * ay) + c * az) * y, minusInf);
    second = vmax(second, vmin(d, best));
    const auto better = gt(d, best);
    best = vmax(best, d);
    bestA = sel(better, a, bestA);
    bestB = sel(better, b, bestB);
  }
  // No valid candidate (best - second is NaN) or a near tie: the reference's own scores decide
  // (octaBestCandidate, one lane at a time: well under 1% of random lanes); where there is no
  // valid candidate the lane is redone.
  auto tie = ngt(best - second, F(2.0f * kOctaScoreError) * l1);
  if (const unsigned settle = movemask(bandnot(redo, tie)); settle != 0) {
    alignas(64) float sa[L], sb[L], fa0[L], fb0[L];
    alignas(64) int32_t left[L] = {};
    store(sa, bestA);
    store(sb, bestB);
    store(fa0, a0);
    store(fb0, b0);
    for (unsigned bits = settle; bits != 0; bits &= bits - 1) {
      const unsigned l = unsigned(__builtin_ctz(bits));
      uint32_t k;
      int32_t wa, wb;
      const int32_t ca0 = int32_t(fa0[l]), cb0 = int32_t(fb0[l]);
      const unsigned only = tb.octaMasks ? tb.octaMasks[size_t(cb0) * tb.octaN + size_t(ca0)] : 0xFFu;
      if (octaBestCandidate(int32_t(tb.octaN), tb.unit4, q->eux[p + l], q->euy[p + l], q->euz[p + l], ca0, cb0, &k,
                            &wa, &wb, only)) {
        sa[l] = float(wa);
        sb[l] = float(wb);
      } else {
        left[l] = 1;
      }
    }
    bestA = F::load(sa);
    bestB = F::load(sb);
    tie = eq(F::loadInt(left), one);
  }
  redo = bor(redo, tie);
  // The winner's index (octaIndex, as octaNearestFast) and table position.
  const F hemi(float(2 * tb.octaN * tb.octaN + 2 * tb.octaN + 1));
  const F i = sel(negX, vneg(bestA), bestA), j = sel(negY, vneg(bestB), bestB);
  const F hh = bandnot(eq(vabs(bestA) + vabs(bestB), fn), h);
  const F t = fn + j;
  const F tt = t * t;
  const F row = sel(le(j, zero), tt, tt - F(2.0f) * j * (j - one));
  const F w = fn - vabs(j);
  const F bestK = band(bnot(redo), hh * hemi + row + i + w);
  F bestX, bestY, bestZ;
  gatherUnit(tb.unit4, bestK, &bestX, &bestY, &bestZ);

  // 3. The texel: the sample's frame (frameFromNormal of its inward normal, as
  // PositionSet::frame), toLocal, then texelFast.
  F lx, ly, lz, a, b;
  toSampleFrame(bestX, bestY, bestZ, vx, vy, vz, &lx, &ly, &lz);
  hemisphereToSquareV<false>(tb.scheme, lx, ly, lz, &a, &b);
  if (tb.scheme != DirectionScheme::kHemiOctahedral) {
    const F lax = vabs(lx), lay = vabs(ly);
    redo = bor(redo, ngt(vabs(lax - lay), F(1e-5f) * (lax + lay)));  // octant diagonals
  }
  const float fmS = float(tb.m);
  const F fm(fmS), half(0.5f);
  const F x = (a + one) * half * fm, y = (b + one) * half * fm;
  const F fx = floorPos(x), fy = floorPos(y);
  // The guard of texelFast (its nearEdge): only the map's inner texel edges 1 .. m - 1 (0 <= x <= m).
  const F tg(tb.texelGuard), top(fmS - 1.0f);
  auto nearEdge = [&](F v, F fv) {
    return bor(band(lt(v - fv, tg), band(ge(fv, one), le(fv, top))), band(lt((fv + one) - v, tg), le(fv + one, top)));
  };
  redo = bor(redo, bor(nearEdge(x, fx), nearEdge(y, fy)));
  const auto ok = bnot(redo);
  const F ti = band(ok, vmin(vmax(fx, zero), top)), tj = band(ok, vmin(vmax(fy, zero), top));
  if (packedIndices(tb)) {
    storeInt(reinterpret_cast<int32_t*>(q->k + p), band(ok, bestK));
    storeInt(reinterpret_cast<int32_t*>(q->i + p), ti);
    storeInt(reinterpret_cast<int32_t*>(q->j + p), tj);
  }
  q->redo[p / 64] |= uint64_t(movemask(redo)) << (p % 64);
  // Ask for the texels now: they arrive while the next group goes through the sphere and the
  // queue (FieldQuery decodes a group only after that).
  if (tb.texels) {
    storeTexelIndex(q->t + p, band(ok, bestK), tj * fm + ti, tb.mapBytes);
    for (size_t l = 0; l < L; ++l) __builtin_prefetch(tb.texels + q->t[p + l]);
  } else if (tb.byteTexels) {
    storeInt(q->t + p, tj * fm + ti);
    for (size_t l = 0; l < L; ++l) __builtin_prefetch(tb.maps[q->k[p + l]] + q->t[p + l]);
  } else if (tb.maps) {
    for (size_t l = 0; l < L; ++l)
      __builtin_prefetch(tb.maps[q->k[p + l]] + texelByte(tb.encoding, tb.m, q->i[p + l], q->j[p + l]));
  }
}

// GroupKernel::decode (query_group.h) for packed rays p .. p + kLanes - 1, those of `keep` only:
// whether each texel holds a hit within the ray's range, as FieldQuery::Impl::hitsAt decodes a
// kUnorm8Diameter texel: bit l of the answer for packed ray p + l.
template <class F>
unsigned decodeStep(const GroupTables& tb, size_t p, const Group* g) {
  F c;
  if (tb.texels) {
    c = F::gatherBytes(tb.texels, g->t + p);
  } else {
    alignas(32) int32_t code[F::kLanes];
    for (size_t l = 0; l < F::kLanes; ++l) code[l] = tb.maps[g->k[p + l]][g->t[p + l]];
    c = F::loadInt(code);
  }
  const F d = c * F(tb.distanceScale);
  const F t0 = F::load(g->pt0 + p);
  const F th = sel(valueMask(F::load(g->pinside + p)), t0 - d, t0 + d);
  // texel(): a hit unless the code is 255; hitsAt(): !(th < lo || th > hi).
  const auto hit = band(bnot(eq(c, F(255.0f))), band(nlt(th, F::load(g->plo + p)), ngt(th, F::load(g->phi + p))));
  return movemask(hit);
}

// GroupKernel::decode (query_group.h) with lanes F.
template <class F>
void decodeGroupWith(const GroupTables& tb, Group* g) {
  constexpr size_t L = F::kLanes;
  g->hits = 0;
  const size_t count = g->count;
  if (!tb.decodeHits || tb.octaN == 0 || count == 0) return;
  // Not the padded lanes, nor the redone rays (the caller's).
  const uint64_t all = packedBits(count);
  const uint64_t keep = all & ~g->redo;
  if (count % L != 0) {  // lanes past `count`: read, then left out of `keep`
    static_assert(Group::kSlack >= L, "a whole vector fits past the last packed ray");
    // (Arrays, not braced lists: a std::initializer_list's inline accessors, emitted here at -O0,
    // would be copies compiled for this file's instruction set.)
    void* const tails[] = {g->k + count, g->t + count, g->pt0 + count, g->plo + count, g->phi + count, g->pinside + count};
    for (void* a : tails) std::memset(a, 0, L * 4);  // (4-byte entries)
  }
  uint64_t hits = 0;  // by packed ray
  for (size_t p = 0; p < count; p += L) hits |= uint64_t(decodeStep<F>(tb, p, g)) << p;
  g->hits = F::hitsByRay(*g, hits & keep);
}

// GroupKernel::sphere (query_group.h) with lanes F.
template <class F>
void sphereGroupWith(const GroupTables& tb, const Ray* rays, size_t n, Group* g, LookupQueue* q) {
  constexpr size_t L = F::kLanes;
  g->inside = 0;
  g->reached = 0;
  g->count = 0;
  g->redo = 0;
  g->looked = 0;
  const uint32_t first = q->size;
  size_t r = 0;
  for (; r + L <= n; r += L) sphereStep<F>(tb, rays + r, g, r, q);
  if (r < n) {
    // Zero directions are not live. (Floats, not Rays: no Ray constructor is compiled here.)
    alignas(64) float tail[L * 8] = {};
    std::memcpy(tail, rays + r, (n - r) * sizeof(Ray));
    sphereStep<F>(tb, reinterpret_cast<const Ray*>(tail), g, r, q);
  }
  if (g->count == 0) return;
  if (tb.octaN == 0) {  // another scheme: the reference does the rest
    q->size = first;
    g->redo = packedBits(g->count);
    g->looked = g->count;
    return;
  }
  q->segment[q->segments++] = {g, first, 0, g->count};
}

// GroupKernel::lookup (query_group.h) with lanes F.
template <class F>
void lookupQueueWith(const GroupTables& tb, LookupQueue* q, bool flush) {
  constexpr size_t L = F::kLanes;
  const size_t size = q->size;
  size_t done = size / L * L;
  if (flush && done < size) {
    // Pad the last lanes with copies of the last entry (their answers are left out).
    done = size + (L - size % L);
    float* const entries[] = {q->eux, q->euy, q->euz, q->vx, q->vy, q->vz};
    for (float* a : entries)
      for (size_t p = size; p < done; ++p) a[p] = a[size - 1];
  }
  if (done == 0) return;
  for (uint64_t& w : q->redo) w = 0;
  for (size_t p = 0; p < done; p += L) lookupStep<F>(tb, p, q);
  done = done < size ? done : size;
  static_assert(LookupQueue::kCapacity <= 128, "the queue's redo bits fit in 128 bits");
  const unsigned __int128 queueRedo = (static_cast<unsigned __int128>(q->redo[1]) << 64) | q->redo[0];
  // The answers of entries 0 .. done - 1 into their groups.
  uint32_t s = 0;
  for (; s < q->segments; ++s) {
    LookupQueue::Segment& sg = q->segment[s];
    if (sg.first >= done) break;
    const uint32_t n = uint32_t(done - sg.first < sg.n ? done - sg.first : sg.n);
    Group* g = sg.group;
    if (packedIndices(tb)) {
      std::memcpy(g->k + sg.p0, q->k + sg.first, n * sizeof(uint32_t));
      std::memcpy(g->i + sg.p0, q->i + sg.first, n * sizeof(uint32_t));
      std::memcpy(g->j + sg.p0, q->j + sg.first, n * sizeof(uint32_t));
    }
    std::memcpy(g->t + sg.p0, q->t + sg.first, n * sizeof(int32_t));
    g->redo |= (uint64_t(queueRedo >> sg.first) & packedBits(n)) << sg.p0;
    g->looked += n;
    if (n < sg.n) {  // the rest waits: it moves to the front below
      sg.p0 += n;
      sg.n -= n;
      sg.first = 0;
      break;
    }
  }
  // Keep the entries not looked up, and their segments, at the front.
  // (Fewer than L are left, but L are moved: a fixed-size copy compiles to a few vector moves.
  // done + L <= kCapacity.)
  const size_t left = size - done;
  if (left) {
    float* const entries[] = {q->eux, q->euy, q->euz, q->vx, q->vy, q->vz};
    for (float* a : entries) {
      float moved[L];
      std::memcpy(moved, a + done, sizeof moved);
      std::memcpy(a, moved, sizeof moved);
    }
  }
  uint32_t kept = 0;
  for (; s < q->segments; ++s) {
    LookupQueue::Segment sg = q->segment[s];
    if (sg.first >= done) sg.first -= uint32_t(done);
    q->segment[kept++] = sg;
  }
  q->segments = kept;
  q->size = uint32_t(left);
}

// floor(x) per lane, for |x| < 2^31 (floorPos truncates toward zero).
template <class F>
inline F floorV(F x) {
  const F t = floorPos(x);
  return sel(lt(x, t), t - F(1.0f), t);
}

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
