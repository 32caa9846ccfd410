// kernel_lanes.h - the kernel's lane helpers for any lane type: Pair, two lane
// vectors taken as one twice as wide (so that the CPU overlaps their long dependency chains), and
// the few per-lane helpers built from a lane type's own operations.
// Part of the group kernel (query_group_kernel.h, which says what the lane types must provide and
// why every function here sits in an unnamed namespace): included through it only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "query/batch/query_group.h"

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

// floor(x) per lane, for |x| < 2^31 (floorPos truncates toward zero).
template <class F>
inline F floorV(F x) {
  const F t = floorPos(x);
  return sel(lt(x, t), t - F(1.0f), t);
}

}  // namespace
}  // namespace vff::detail
