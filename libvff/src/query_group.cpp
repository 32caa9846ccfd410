// The group kernel of the nearest lookup (query_group.h): FieldQuery::Impl::prepare, four rays per
// SSE2 register. Every line below mirrors a line of prepare() or of fast_lookup.h, with the same
// binary32 operations in the same order (a ? b : c becomes a mask select), so that a lane computes
// bit for bit what prepare() computes for that ray.
#include "query_group.h"

#include <cmath>
#include <cstddef>
#include <cstring>
#include <algorithm>

#include "fast_lookup.h"

#if defined(__SSE2__)
#include <emmintrin.h>
#endif

namespace vff::detail {

#if defined(__SSE2__)

namespace {

static_assert(sizeof(Ray) == 32 && offsetof(Ray, direction) == 12 && offsetof(Ray, tmin) == 24 &&
                  offsetof(Ray, tmax) == 28,
              "the kernel loads a Ray as eight packed floats");

inline __m128 sel(__m128 mask, __m128 a, __m128 b) {  // mask ? a : b
  return _mm_or_ps(_mm_and_ps(mask, a), _mm_andnot_ps(mask, b));
}
inline __m128 vabs(__m128 x) { return _mm_and_ps(x, _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff))); }
inline __m128 vneg(__m128 x) { return _mm_xor_ps(x, _mm_set1_ps(-0.0f)); }
// floor(x) for 0 <= x < 2^31 (every use below; other lanes are masked off afterwards).
inline __m128 floorPos(__m128 x) { return _mm_cvtepi32_ps(_mm_cvttps_epi32(x)); }
// std::max(a, b) as prepare() evaluates it.
inline __m128 maxStd(__m128 a, __m128 b) { return sel(_mm_cmplt_ps(a, b), b, a); }  // a < b ? b : a

// Loads 4-float rows at base + 4 * stride * index[l] (l = 0..3) and transposes them: out[c] holds
// component c of the four lanes.
inline void gather4(const float* base, size_t stride, const int32_t idx[4], __m128 out[4]) {
  __m128 r0 = _mm_loadu_ps(base + stride * size_t(idx[0])), r1 = _mm_loadu_ps(base + stride * size_t(idx[1]));
  __m128 r2 = _mm_loadu_ps(base + stride * size_t(idx[2])), r3 = _mm_loadu_ps(base + stride * size_t(idx[3]));
  _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
  out[0] = r0;
  out[1] = r1;
  out[2] = r2;
  out[3] = r3;
}

// atanUnit of fast_lookup.h, four lanes.
inline __m128 atanUnit4(__m128 t) {
  const __m128 at = vabs(t);
  const __m128 big = _mm_cmpgt_ps(at, _mm_set1_ps(0.41421356f));
  const __m128 one = _mm_set1_ps(1.0f);
  const __m128 x = sel(big, _mm_div_ps(_mm_sub_ps(at, one), _mm_add_ps(at, one)), at);
  const __m128 y0 = _mm_and_ps(big, _mm_set1_ps(0.78539816f));
  const __m128 z = _mm_mul_ps(x, x);
  __m128 p = _mm_sub_ps(_mm_mul_ps(_mm_set1_ps(8.05374449538e-2f), z), _mm_set1_ps(1.38776856032e-1f));
  p = _mm_add_ps(_mm_mul_ps(p, z), _mm_set1_ps(1.99777106478e-1f));
  p = _mm_sub_ps(_mm_mul_ps(p, z), _mm_set1_ps(3.33329491539e-1f));
  p = _mm_add_ps(_mm_mul_ps(_mm_mul_ps(p, z), x), x);
  const __m128 r = _mm_add_ps(y0, p);
  return sel(_mm_cmplt_ps(t, _mm_setzero_ps()), vneg(r), r);
}

inline void storeMask(uint8_t* out, __m128 mask) {
  const int bits = _mm_movemask_ps(mask);
  for (int l = 0; l < 4; ++l) out[l] = uint8_t((bits >> l) & 1);
}

// The rays of a group that reach the sphere, packed: their entry points and lookup directions.
struct Packed {
  float eux[kGroupRays + 4], euy[kGroupRays + 4], euz[kGroupRays + 4];
  float vx[kGroupRays + 4], vy[kGroupRays + 4], vz[kGroupRays + 4];
  uint32_t ray[kGroupRays + 4];
  size_t count = 0;
};

// Step 1 for four rays starting at rays[0] (all four readable), lanes r0 .. r0 + 3 of g: the
// sphere; appends the live rays to `packed`.
void sphereQuad(const GroupTables& tb, const Ray* rays, Group* g, size_t r0, Packed* packed) {
  const float* p = reinterpret_cast<const float*>(rays);
  __m128 ox = _mm_loadu_ps(p), oy = _mm_loadu_ps(p + 8), oz = _mm_loadu_ps(p + 16), dx = _mm_loadu_ps(p + 24);
  _MM_TRANSPOSE4_PS(ox, oy, oz, dx);
  __m128 dy = _mm_loadu_ps(p + 4), dz = _mm_loadu_ps(p + 12), tmin = _mm_loadu_ps(p + 20), tmax = _mm_loadu_ps(p + 28);
  _MM_TRANSPOSE4_PS(dy, dz, tmin, tmax);
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);

  // prepare(): the ray's length and unit direction.
  const __m128 len = _mm_sqrt_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(dx, dx), _mm_mul_ps(dy, dy)), _mm_mul_ps(dz, dz)));
  __m128 live = _mm_and_ps(_mm_cmpgt_ps(len, zero), _mm_cmple_ps(len, _mm_set1_ps(3.40282347e38f)));
  const __m128 inv = _mm_div_ps(one, len);
  const __m128 wx = _mm_mul_ps(dx, inv), wy = _mm_mul_ps(dy, inv), wz = _mm_mul_ps(dz, inv);
  const __m128 tminL = _mm_mul_ps(tmin, len), tmaxL = _mm_mul_ps(tmax, len);
  // 1. The sphere.
  const __m128 ex = _mm_sub_ps(ox, _mm_set1_ps(tb.center.x)), ey = _mm_sub_ps(oy, _mm_set1_ps(tb.center.y)),
               ez = _mm_sub_ps(oz, _mm_set1_ps(tb.center.z));
  const __m128 beta = _mm_add_ps(_mm_add_ps(_mm_mul_ps(ex, wx), _mm_mul_ps(ey, wy)), _mm_mul_ps(ez, wz));
  const __m128 gamma = _mm_sub_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(ex, ex), _mm_mul_ps(ey, ey)), _mm_mul_ps(ez, ez)),
                                  _mm_set1_ps(tb.radius * tb.radius));
  const __m128 disc = _mm_sub_ps(_mm_mul_ps(beta, beta), gamma);
  live = _mm_and_ps(live, _mm_cmpge_ps(disc, zero));
  const __m128 sq = _mm_sqrt_ps(disc);
  const __m128 nbeta = vneg(beta);
  const __m128 t1 = _mm_add_ps(nbeta, sq);
  live = _mm_and_ps(live, _mm_cmpnlt_ps(t1, zero));
  const __m128 inside = _mm_cmple_ps(gamma, zero);
  const __m128 t0 = sel(inside, t1, maxStd(_mm_sub_ps(nbeta, sq), zero));
  const __m128 lo = sel(inside, maxStd(tminL, _mm_set1_ps(tb.insideLo)), tminL);
  if (tb.bit1) live = _mm_andnot_ps(inside, live);
  live = _mm_andnot_ps(_mm_andnot_ps(inside, _mm_cmpgt_ps(t0, tmaxL)), live);
  const __m128 vx = sel(inside, vneg(wx), wx), vy = sel(inside, vneg(wy), wy), vz = sel(inside, vneg(wz), wz);
  const __m128 invR = _mm_set1_ps(1.0f / tb.radius);
  const __m128 eux = _mm_mul_ps(_mm_sub_ps(_mm_add_ps(ox, _mm_mul_ps(wx, t0)), _mm_set1_ps(tb.center.x)), invR);
  const __m128 euy = _mm_mul_ps(_mm_sub_ps(_mm_add_ps(oy, _mm_mul_ps(wy, t0)), _mm_set1_ps(tb.center.y)), invR);
  const __m128 euz = _mm_mul_ps(_mm_sub_ps(_mm_add_ps(oz, _mm_mul_ps(wz, t0)), _mm_set1_ps(tb.center.z)), invR);
  _mm_storeu_ps(g->t0 + r0, t0);
  _mm_storeu_ps(g->lo + r0, lo);
  _mm_storeu_ps(g->hi + r0, tmaxL);
  _mm_storeu_ps(g->len + r0, len);
  storeMask(g->live + r0, live);
  storeMask(g->inside + r0, inside);
  storeMask(g->redo + r0, _mm_setzero_ps());
  const int bits = _mm_movemask_ps(live);
  if (bits == 0) return;
  alignas(16) float e[6][4];
  _mm_store_ps(e[0], eux);
  _mm_store_ps(e[1], euy);
  _mm_store_ps(e[2], euz);
  _mm_store_ps(e[3], vx);
  _mm_store_ps(e[4], vy);
  _mm_store_ps(e[5], vz);
  for (int l = 0; l < 4; ++l) {
    if (!((bits >> l) & 1)) continue;
    const size_t slot = packed->count++;
    packed->eux[slot] = e[0][l];
    packed->euy[slot] = e[1][l];
    packed->euz[slot] = e[2][l];
    packed->vx[slot] = e[3][l];
    packed->vy[slot] = e[4][l];
    packed->vz[slot] = e[5][l];
    packed->ray[slot] = uint32_t(r0 + size_t(l));
  }
}

// Steps 2 and 3 for packed rays p .. p + 3 (all four valid; the caller pads the last quad).
// Writes k, i, j and redo of the first `lanes` of them into g.
void lookupQuad(const GroupTables& tb, const Packed& pk, size_t p, size_t lanes, Group* g) {
  const __m128 zero = _mm_setzero_ps(), one = _mm_set1_ps(1.0f);
  const __m128 eux = _mm_loadu_ps(pk.eux + p), euy = _mm_loadu_ps(pk.euy + p), euz = _mm_loadu_ps(pk.euz + p);
  const __m128 vx = _mm_loadu_ps(pk.vx + p), vy = _mm_loadu_ps(pk.vy + p), vz = _mm_loadu_ps(pk.vz + p);
  const __m128 live = _mm_castsi128_ps(_mm_set1_epi32(-1));

  // 2. The nearest sample: octaNearestFast.
  const float fnS = float(tb.octaN);
  const __m128 fn = _mm_set1_ps(fnS);
  const __m128 ax = vabs(eux), ay = vabs(euy), az = vabs(euz);
  const __m128 l1 = _mm_add_ps(_mm_add_ps(ax, ay), az);
  __m128 redo = _mm_andnot_ps(_mm_and_ps(_mm_cmpgt_ps(l1, zero), _mm_cmplt_ps(l1, _mm_set1_ps(3.0e38f))), live);
  const __m128 pa = _mm_mul_ps(_mm_div_ps(ax, l1), fn), pb = _mm_mul_ps(_mm_div_ps(ay, l1), fn);
  const __m128 fa = floorPos(pa), fb = floorPos(pb);
  const __m128 gg = _mm_set1_ps(kGridGuard);
  const __m128 nearLine =
      _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(_mm_sub_ps(pa, fa), gg), _mm_cmplt_ps(_mm_sub_ps(_mm_add_ps(fa, one), pa), gg)),
                _mm_or_ps(_mm_cmplt_ps(_mm_sub_ps(pb, fb), gg), _mm_cmplt_ps(_mm_sub_ps(_mm_add_ps(fb, one), pb), gg)));
  redo = _mm_or_ps(redo, _mm_and_ps(nearLine, live));
  const __m128 a0 = _mm_min_ps(fa, _mm_sub_ps(fn, one)), b0 = _mm_min_ps(fb, _mm_sub_ps(fn, one));
  const __m128 h = _mm_andnot_ps(_mm_cmpge_ps(euz, zero), one);  // 0 upper, 1 lower hemisphere
  const __m128 negX = _mm_cmplt_ps(eux, zero), negY = _mm_cmplt_ps(euy, zero);
  const __m128 hemi = _mm_set1_ps(float(2 * tb.octaN * tb.octaN + 2 * tb.octaN + 1));
  // Lanes that must not read the tables (dead, or redone) look up sample 0.
  const __m128 use = _mm_andnot_ps(redo, live);
  // The candidates any of the four lanes needs (octaCandidateMasks).
  unsigned needed = 0xFF;
  if (tb.octaMasks) {
    alignas(16) int32_t ca[4], cb[4];
    _mm_store_si128(reinterpret_cast<__m128i*>(ca), _mm_cvttps_epi32(_mm_and_ps(use, a0)));
    _mm_store_si128(reinterpret_cast<__m128i*>(cb), _mm_cvttps_epi32(_mm_and_ps(use, b0)));
    needed = 0;
    const int useBits = _mm_movemask_ps(use);
    for (int l = 0; l < 4; ++l)
      if ((useBits >> l) & 1) needed |= tb.octaMasks[size_t(cb[l]) * tb.octaN + size_t(ca[l])];
  }
  __m128 bestD = _mm_set1_ps(-INFINITY), bestK = _mm_set1_ps(3.0e38f);
  __m128 bestX = zero, bestY = zero, bestZ = one;  // the best candidate's position
  __m128 any = _mm_setzero_ps();
  alignas(16) int32_t idx[4];
  for (unsigned ci = 0; ci < 8; ++ci) {
    if (!((needed >> ci) & 1)) continue;
    const __m128 a = _mm_add_ps(a0, _mm_set1_ps(kOctaCandidates[ci][0]));
    const __m128 b = _mm_add_ps(b0, _mm_set1_ps(kOctaCandidates[ci][1]));
    const __m128 aa = vabs(a), ab = vabs(b), sum = _mm_add_ps(aa, ab);
    const __m128 valid = _mm_and_ps(_mm_cmple_ps(sum, fn), use);
    const __m128 i = sel(negX, vneg(a), a), j = sel(negY, vneg(b), b);
    const __m128 hh = _mm_andnot_ps(_mm_cmpeq_ps(sum, fn), h);
    const __m128 t = _mm_add_ps(fn, j);
    const __m128 tt = _mm_mul_ps(t, t);
    const __m128 row = sel(_mm_cmple_ps(j, zero), tt,
                           _mm_sub_ps(tt, _mm_mul_ps(_mm_mul_ps(_mm_set1_ps(2.0f), j), _mm_sub_ps(j, one))));
    const __m128 w = _mm_sub_ps(fn, vabs(j));
    const __m128 k = _mm_and_ps(valid, _mm_add_ps(_mm_add_ps(_mm_add_ps(_mm_mul_ps(hh, hemi), row), i), w));
    _mm_store_si128(reinterpret_cast<__m128i*>(idx), _mm_cvttps_epi32(k));
    __m128 u[4];
    gather4(tb.unit4, 4, idx, u);
    const __m128 d = _mm_add_ps(_mm_add_ps(_mm_mul_ps(u[0], eux), _mm_mul_ps(u[1], euy)), _mm_mul_ps(u[2], euz));
    const __m128 better = _mm_and_ps(
        valid, _mm_or_ps(_mm_cmpgt_ps(d, bestD), _mm_and_ps(_mm_cmpeq_ps(d, bestD), _mm_cmplt_ps(k, bestK))));
    bestD = sel(better, d, bestD);
    bestK = sel(better, k, bestK);
    bestX = sel(better, u[0], bestX);
    bestY = sel(better, u[1], bestY);
    bestZ = sel(better, u[2], bestZ);
    any = _mm_or_ps(any, valid);
  }
  redo = _mm_or_ps(redo, _mm_andnot_ps(any, use));
  const __m128 kf = _mm_and_ps(_mm_andnot_ps(redo, live), bestK);
  _mm_store_si128(reinterpret_cast<__m128i*>(idx), _mm_cvttps_epi32(kf));

  // 3. The texel: the sample's frame (frameFromNormal of its inward normal, as PositionSet::frame),
  // toLocal, then texelFast.
  const __m128 nx = vneg(bestX), ny = vneg(bestY), nz = vneg(bestZ);
  const __m128 fs = sel(_mm_cmpge_ps(nz, zero), one, _mm_set1_ps(-1.0f));
  const __m128 fA = vneg(_mm_div_ps(one, _mm_add_ps(fs, nz)));
  const __m128 fk = _mm_mul_ps(_mm_mul_ps(nx, ny), fA);
  const __m128 tx = _mm_add_ps(one, _mm_mul_ps(_mm_mul_ps(_mm_mul_ps(fs, nx), nx), fA));
  const __m128 ty = _mm_mul_ps(fs, fk), tz = _mm_mul_ps(vneg(fs), nx);
  const __m128 bx = fk, by = _mm_add_ps(fs, _mm_mul_ps(_mm_mul_ps(ny, ny), fA)), bz = vneg(ny);
  const __m128 lx = _mm_add_ps(_mm_add_ps(_mm_mul_ps(vx, tx), _mm_mul_ps(vy, ty)), _mm_mul_ps(vz, tz));
  const __m128 ly = _mm_add_ps(_mm_add_ps(_mm_mul_ps(vx, bx), _mm_mul_ps(vy, by)), _mm_mul_ps(vz, bz));
  const __m128 lz = _mm_add_ps(_mm_add_ps(_mm_mul_ps(vx, nx), _mm_mul_ps(vy, ny)), _mm_mul_ps(vz, nz));
  const __m128 z = _mm_max_ps(lz, zero);  // std::max(0.0f, z): 0 for NaN and -0
  __m128 a, b;
  if (tb.scheme == DirectionScheme::kHemiOctahedral) {
    const __m128 hinv = _mm_div_ps(one, _mm_add_ps(_mm_add_ps(vabs(lx), vabs(ly)), z));
    const __m128 x = _mm_mul_ps(lx, hinv), y = _mm_mul_ps(ly, hinv);
    a = _mm_add_ps(x, y);
    b = _mm_sub_ps(x, y);
  } else {
    const __m128 r = _mm_sqrt_ps(_mm_max_ps(_mm_sub_ps(one, z), zero));
    const __m128 lax = vabs(lx), lay = vabs(ly);
    const __m128 diagonal = _mm_cmpngt_ps(vabs(_mm_sub_ps(lax, lay)), _mm_mul_ps(_mm_set1_ps(1e-5f), _mm_add_ps(lax, lay)));
    redo = _mm_or_ps(redo, _mm_and_ps(diagonal, live));
    const __m128 k = _mm_mul_ps(r, _mm_set1_ps(4.0f / 3.14159265358979323846f));
    const __m128 bigX = _mm_cmpgt_ps(lax, lay);
    const __m128 s = _mm_mul_ps(atanUnit4(_mm_div_ps(sel(bigX, ly, lx), sel(bigX, lx, ly))), k);
    const __m128 xNeg = _mm_cmplt_ps(lx, zero), yNeg = _mm_cmplt_ps(ly, zero);
    a = sel(bigX, sel(xNeg, vneg(r), r), sel(yNeg, vneg(s), s));
    b = sel(bigX, sel(xNeg, vneg(s), s), sel(yNeg, vneg(r), r));
  }
  const __m128 mone = _mm_set1_ps(-1.0f);
  a = _mm_min_ps(_mm_max_ps(a, mone), one);
  b = _mm_min_ps(_mm_max_ps(b, mone), one);
  const float fmS = float(tb.m);
  const __m128 fm = _mm_set1_ps(fmS), half = _mm_set1_ps(0.5f);
  const __m128 x = _mm_mul_ps(_mm_mul_ps(_mm_add_ps(a, one), half), fm);
  const __m128 y = _mm_mul_ps(_mm_mul_ps(_mm_add_ps(b, one), half), fm);
  const __m128 fx = floorPos(x), fy = floorPos(y);
  const __m128 tg = _mm_set1_ps(kTexelGuard + 2e-6f * fmS);
  const __m128 edge =
      _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(_mm_sub_ps(x, fx), tg), _mm_cmplt_ps(_mm_sub_ps(_mm_add_ps(fx, one), x), tg)),
                _mm_or_ps(_mm_cmplt_ps(_mm_sub_ps(y, fy), tg), _mm_cmplt_ps(_mm_sub_ps(_mm_add_ps(fy, one), y), tg)));
  redo = _mm_or_ps(redo, _mm_and_ps(edge, live));
  const __m128 top = _mm_set1_ps(fmS - 1.0f);
  const __m128 ok = _mm_andnot_ps(redo, live);
  alignas(16) int32_t ti[4], tj[4];
  _mm_store_si128(reinterpret_cast<__m128i*>(ti), _mm_cvttps_epi32(_mm_and_ps(ok, _mm_min_ps(_mm_max_ps(fx, zero), top))));
  _mm_store_si128(reinterpret_cast<__m128i*>(tj), _mm_cvttps_epi32(_mm_and_ps(ok, _mm_min_ps(_mm_max_ps(fy, zero), top))));
  const int redoBits = _mm_movemask_ps(redo);
  for (size_t l = 0; l < lanes; ++l) {
    const uint32_t r = pk.ray[p + l];
    g->k[r] = uint32_t(idx[l]);
    g->i[r] = uint32_t(ti[l]);
    g->j[r] = uint32_t(tj[l]);
    g->redo[r] = uint8_t((redoBits >> l) & 1);
  }
}

}  // namespace

bool groupKernelAvailable() noexcept { return true; }

void prepareGroup(const GroupTables& tb, const Ray* rays, size_t n, Group* g) noexcept {
  Packed packed;
  size_t r = 0;
  for (; r + 4 <= n; r += 4) sphereQuad(tb, rays + r, g, r, &packed);
  if (r < n) {
    Ray tail[4] = {};  // zero directions: not live
    std::memcpy(tail, rays + r, (n - r) * sizeof(Ray));
    Group scratch;
    Packed tailPacked;
    sphereQuad(tb, tail, &scratch, 0, &tailPacked);
    for (size_t l = 0; l < tailPacked.count; ++l) {
      const size_t p = packed.count++;
      packed.eux[p] = tailPacked.eux[l];
      packed.euy[p] = tailPacked.euy[l];
      packed.euz[p] = tailPacked.euz[l];
      packed.vx[p] = tailPacked.vx[l];
      packed.vy[p] = tailPacked.vy[l];
      packed.vz[p] = tailPacked.vz[l];
      packed.ray[p] = uint32_t(r + tailPacked.ray[l]);
    }
    for (size_t l = 0; r + l < n; ++l) {
      g->t0[r + l] = scratch.t0[l];
      g->lo[r + l] = scratch.lo[l];
      g->hi[r + l] = scratch.hi[l];
      g->len[r + l] = scratch.len[l];
      g->k[r + l] = scratch.k[l];
      g->i[r + l] = scratch.i[l];
      g->j[r + l] = scratch.j[l];
      g->live[r + l] = scratch.live[l];
      g->inside[r + l] = scratch.inside[l];
      g->redo[r + l] = scratch.redo[l];
    }
  }
  if (packed.count == 0) return;
  if (tb.octaN == 0) {  // another scheme: the reference does the rest
    for (size_t p = 0; p < packed.count; ++p) g->redo[packed.ray[p]] = 1;
    return;
  }
  // Pad the last quad with copies of the last live ray (their answers are not stored).
  const size_t last = packed.count - 1;
  for (size_t p = packed.count; p % 4 != 0; ++p) {
    packed.eux[p] = packed.eux[last];
    packed.euy[p] = packed.euy[last];
    packed.euz[p] = packed.euz[last];
    packed.vx[p] = packed.vx[last];
    packed.vy[p] = packed.vy[last];
    packed.vz[p] = packed.vz[last];
  }
  for (size_t p = 0; p < packed.count; p += 4) lookupQuad(tb, packed, p, std::min<size_t>(4, packed.count - p), g);
}

#else

bool groupKernelAvailable() noexcept { return false; }
void prepareGroup(const GroupTables&, const Ray*, size_t, Group*) noexcept {}

#endif

}  // namespace vff::detail
