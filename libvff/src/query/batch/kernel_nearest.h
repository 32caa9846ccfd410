// kernel_nearest.h - the nearest lookup of a group of rays: the sphere step, the
// lookup step (nearest sample and texel) through the LookupQueue, and the decode of one-byte
// texels; GroupKernel::sphere, lookup and decode (query_group.h) for lanes F.
// Part of the group kernel (query_group_kernel.h, which says what the lane types must provide and
// why every function here sits in an unnamed namespace): included through it only.
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "query/fast_lookup.h"
#include "query/batch/kernel_lanes.h"
#include "query/batch/kernel_math.h"
#include "query/batch/query_group.h"

namespace vff::detail {
namespace {

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
  const auto inSphere = le(gamma, zero);
  const F tIn = nbeta - sq;
  // Off the object (section 7.4) a ray from inside looks up forward from its negative entry
  // distance; on it (section 7.3), backward from the exit point.
  const auto inside = tb.offObject ? band(inSphere, bnot(inSphere)) : inSphere;
  const F t0 = tb.offObject ? sel(inSphere, tIn, maxStd(tIn, zero)) : sel(inside, t1, maxStd(tIn, zero));
  const F lo = sel(inside, maxStd(tminL, F(tb.insideLo)), tminL);
  if (tb.bit1) live = bandnot(inSphere, live);
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
    // (Section 7.4's rays, t0 < 0, count a surface within the tolerance behind lo: decodeStep.)
    compress(g->plo + at, tb.offObject ? sel(lt(t0, zero), lo - F(tb.offTolerance), lo) : lo, bits);
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
// whether each texel holds a hit within the ray's range, as FieldQuery::Impl::hitsAt (and, for
// section 7.4's rays, offHitsAt) decodes a kUnorm8Diameter texel: bit l of the answer for packed
// ray p + l. *behind: the section 7.4 rays whose surface lies behind the origin (step 3: the
// caller's reference path answers them).
template <class F>
unsigned decodeStep(const GroupTables& tb, size_t p, const Group* g, unsigned* behind) {
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
  const auto coded = bnot(eq(c, F(255.0f)));
  const F lo = F::load(g->plo + p);
  const auto hit = band(coded, band(nlt(th, lo), ngt(th, F::load(g->phi + p))));
  *behind = tb.offObject ? movemask(band(coded, band(lt(th, lo), lt(t0, F(0.0f))))) : 0u;
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
  uint64_t hits = 0, behind = 0;  // by packed ray
  for (size_t p = 0; p < count; p += L) {
    unsigned b = 0;
    hits |= uint64_t(decodeStep<F>(tb, p, g, &b)) << p;
    behind |= uint64_t(b) << p;
  }
  g->hits = F::hitsByRay(*g, hits & keep & ~behind);
  g->redo |= behind & keep;  // (section 7.4's step 3: left to the reference, as the kernel's redone rays)
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

}  // namespace
}  // namespace vff::detail
