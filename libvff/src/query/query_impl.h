// query_impl.h - FieldQuery::Impl (private): the tables a query reads, built once from a field,
// and the declarations of the query's steps, whose definitions live one concept to a file:
//   query_build.cpp                building a query and its tables (FieldQuery::fromMaps, fromFile)
//   query_ray.cpp                  the reference path, one ray at a time (prepare, nearest, interpolated)
//   query_batch_nearest.cpp        nearest batches through the group kernel (query_group.h)
//   query_batch_interpolated.cpp   interpolated batches through the kernel's planner and blend
//   query_batch.cpp                the batch entry points of FieldQuery, choosing one of the two
//   rigid_transform.cpp            RigidTransform and Instance (world-space rays)
// Everything a query's hot loops call inline (texel decoding, the nearest sample, the group
// pipeline forEachGroup) is defined here, so that each file that runs a loop inlines it as before.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <mutex>
#include <span>
#include <vector>

#include "vff/bc4.h"
#include "vff/encoding.h"
#include "vff/positions.h"
#include "vff/query.h"

#include "query/fast_lookup.h"
#include "refine/wide_bvh.h"
#include "query/batch/query_group.h"

namespace vff {

inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

inline Vec3 normalize(Vec3 v) {
  const float l = std::sqrt(dot(v, v));
  return l > 0 ? v * (1.0f / l) : Vec3{};
}

inline Vec3 toVec(const float c[3]) { return {c[0], c[1], c[2]}; }

namespace detail {

// A RigidTransform's inverse, taken apart once for many rays: what toObjectVector and
// toObjectPoint compute, inlined. The group kernel repeats these operations lane by lane
// (GroupTables::toObject). (Not in the unnamed namespace below: vff::Scene's state, which two
// files share, holds these.)
struct ToObject {
  float r[3][3];  // the inverse rotation is the transpose
  Vec3 translation;
  float invScale;
  explicit ToObject(const RigidTransform& x) noexcept
      : r{{x.rotation[0][0], x.rotation[0][1], x.rotation[0][2]},
          {x.rotation[1][0], x.rotation[1][1], x.rotation[1][2]},
          {x.rotation[2][0], x.rotation[2][1], x.rotation[2][2]}},
        translation(x.translation),
        invScale(1.0f / x.scale) {}
  Vec3 vector(Vec3 v) const noexcept {
    return Vec3{r[0][0] * v.x + r[1][0] * v.y + r[2][0] * v.z, r[0][1] * v.x + r[1][1] * v.y + r[2][1] * v.z,
                r[0][2] * v.x + r[1][2] * v.y + r[2][2] * v.z} *
           invScale;
  }
  Vec3 point(Vec3 p) const noexcept { return vector(p - translation); }
  Ray ray(const Ray& w) const noexcept { return Ray{point(w.origin), vector(w.direction), w.tmin, w.tmax}; }
};

// (An unnamed namespace, as when the query was one file: the functions whose signatures name these
// types, blendResult and the batch templates, are then local to the file that uses them, and the
// compiler inlines them there as it did then. blendResult is defined below for that reason.)
namespace {

// Tables whose kernel takes world-space rays to object space by `to`, lane by lane (none: the
// rays are in object space).
inline GroupTables toObjectTables(GroupTables t, const ToObject* to) noexcept {
  if (to) {
    t.toObject = true;
    std::memcpy(t.objectRotation, to->r, sizeof t.objectRotation);
    t.objectShift = to->translation;
    t.objectInvScale = to->invScale;
  }
  return t;
}

// The field's answer to an object-space ray, in world space (both rays share t).
inline void toWorld(const RigidTransform& x, const Ray& worldRay, QueryHit* h) {
  if (!h->hit) return;
  h->point = worldRay.origin + worldRay.direction * h->t;
  if (h->hasNormal) h->normal = normalize(x.toWorldVector(h->normal));
}

// One decoded texel: a hit at `distance` from the map's sample point, or a miss.
struct Sample {
  bool hit = false;
  float distance = 0;
};

// What one map lookup contributes to the answer: a hit point's parameter t along the ray (in
// distance units) with a weight, or a miss with a weight.
struct Blend {
  float hitWeight = 0, missWeight = 0;
  float tSum = 0;         // sum of weight * t over hits
  Vec3 normalSum;         // sum of weight * normal over hits
  float farWeight = 0;    // hits beyond the visibility range (count as unoccluded)
  float nearWeight = 0;   // hits before the start of the range (ignored for visibility)
};

// fn(r) for each r < n whose bit in `bits` is clear: a loop over the set bits of the rest, with no
// branch per bit (the rays that reach the sphere are random bits of their group).
template <class Fn>
void forEachClear(uint64_t bits, size_t n, Fn&& fn) {
  for (uint64_t m = ~bits & packedBits(n); m != 0; m &= m - 1) fn(size_t(__builtin_ctzll(m)));
}

}  // namespace
}  // namespace detail

struct VFF_HIDDEN FieldQuery::Impl {  // (VFF_HIDDEN: not exported with its class, vff/export.h)
  FieldDesc field;
  PositionSet positions;
  Vec3 center;
  float radius = 0;
  uint32_t m = 0;
  uint64_t distMapBytes = 0, normMapBytes = 0;
  std::vector<const uint8_t*> dist;  // per map
  // GroupTables::byteTexels, and whether the maps lie back to back (GroupTables::texels).
  bool byteTexels = false, contiguous = false;
  // Map indices are exact in binary32 (< 2^24), as the interpolated planner and blend kernels
  // (detail::GroupKernel::plan, blend) hold them.
  bool floatMapIndices = false;
  // What the blend kernel reads (texels null: it cannot blend this field): unorm8-diameter maps
  // back to back, and their normal maps back to back if there are normals.
  detail::BlendTables blendTables;
  std::vector<const uint8_t*> norm;  // per map, empty without normals
  std::vector<Frame> frames;         // frame of map k (inward normal)
  std::vector<float> unit4;          // û_k, float, padded to 4 floats per map (for the group kernel)
  std::vector<uint8_t> octaMasks;    // octa-hemi2: detail::octaCandidateMasks (the group kernel)
  std::vector<uint32_t> octaCornerRows;  // detail::octaCornerRows of octaMasks (n <= 32)
  static constexpr uint32_t kNeighbours = kQueryNeighbours;
  // kNeighbours per map; UINT32_MAX pads. Only the interpolated reconstruction reads them, so
  // they are made by its first call (needNeighbours), not when the query opens.
  mutable std::vector<uint32_t> neighbours;
  mutable std::once_flag neighboursMade;
  void needNeighbours() const noexcept {
    std::call_once(neighboursMade, [this] { neighbours = queryNeighbours(positions); });
  }
  float spacing = 0;                 // mean angular spacing sqrt(4 pi / mapCount)
  float kernelRadius2 = 0;           // squared chord radius of the interpolation kernel
  float defaultBias = 0;             // fraction of R
  // Section 7.4's tolerance near the origin, in object units (2R/255).
  float offTolerance = 0;
  // quantizationStep (encoding.h) of the diameter encodings: a code's distance. build() takes it
  // once, so that every decoder of a texel (texel(), the group kernel's decode and blend) scales
  // by the same value.
  float distanceStep = 0;
  std::vector<float> chordScale;     // unorm8-chord: quantizationStep per texel (M * M)
  uint64_t payload = 0;
  // Reconstruction::kRefined (vff/refine.h): the unsure bits, the margin in object units, the BVH.
  RefinementView refine;
  float refineMargin = 0;
  detail::WideBvh bvh;
  Status setRefinement(const RefinementView& r);
  uint64_t hugePages = 0;  // bytes of the maps on huge pages (build(): adviseMapRuns)

  detail::Sample texel(uint32_t k, uint32_t i, uint32_t j) const noexcept {
    const uint8_t* map = dist[k];
    const size_t t = size_t(j) * m + i;
    switch (field.distanceEncoding) {
      case DistanceEncoding::kUnorm8Diameter: {
        const uint32_t c = map[t];
        return {c != 255u, float(c) * distanceStep};
      }
      case DistanceEncoding::kUnorm16Diameter: {
        const uint32_t c = uint32_t(map[2 * t]) | (uint32_t(map[2 * t + 1]) << 8);
        return {c != 65535u, float(c) * distanceStep};
      }
      case DistanceEncoding::kUnorm8Chord: {
        const uint32_t c = map[t];
        return {c != 255u, float(c) * chordScale[t]};
      }
      case DistanceEncoding::kBit1:
        return {((map[t / 8] >> (t % 8)) & 1u) != 0, 0.0f};
      case DistanceEncoding::kBc4Diameter: {
        const uint32_t c = bc4Texel(map + detail::texelByte(DistanceEncoding::kBc4Diameter, m, i, j), (j & 3u) * 4 + (i & 3u));
        return {c != 255u, float(c) * distanceStep};
      }
      case DistanceEncoding::kInvalid: break;
    }
    return {};
  }

  Vec3 normalAt(uint32_t k, uint32_t i, uint32_t j) const noexcept {
    return decodeNormal(norm[k] + 4 * (size_t(j) * m + i));
  }

  Vec3 unit(uint32_t k) const noexcept { return {unit4[size_t(k) * 4], unit4[size_t(k) * 4 + 1], unit4[size_t(k) * 4 + 2]}; }
  Vec3 samplePoint(uint32_t k) const noexcept { return center + unit(k) * radius; }

  // The nearest sample among the O(1) candidates, by binary32 dot products with the table of
  // positions (spec/positions.md section 2 allows a decoder this; it differs from the binary64
  // choice only between samples equally near to within rounding).
  uint32_t nearestSample(Vec3 d) const noexcept {
    uint32_t fast;
    if (positions.scheme() == PositionScheme::kOctaHemi2 && detail::octaNearestFast(positions.param(), unit4.data(), d, &fast))
      return fast;
    uint32_t c[PositionSet::kMaxCandidates];
    const uint32_t n = positions.candidates(d, c);
    uint32_t best = c[0];
    float bestDot = dot(unit(best), d);
    for (uint32_t i = 1; i < n; ++i) {
      const float v = dot(unit(c[i]), d);
      if (v > bestDot || (v == bestDot && c[i] < best)) {
        bestDot = v;
        best = c[i];
      }
    }
    return best;
  }

  void build();
  // A query in two halves, so that a batch can fetch the texels of many rays at once: prepare()
  // does everything up to the texel address (false: the ray misses, *out is final); nearestHit()
  // decodes that texel.
  struct Lookup {
    Vec3 w, v, eu;
    float len = 0, t0 = 0, lo = 0, hi = 0;
    bool inside = false;  // answered by section 7.3: the reversed lookup from the exit point
    bool off = false;     // answered by section 7.4: the origin is inside the sphere, t0 < 0
    uint32_t k0 = 0, i = 0, j = 0;  // i, j: the nearest lookup's texel
  };
  bool prepare(const Ray& ray, const QueryOptions& o, Lookup* l) const noexcept;
  // The part of prepare() after the sphere: everything but k0, i, j, from the sphere's results
  // (the group kernel's, for interpolated batches).
  void lookupFrom(const Ray& ray, float len, float t0, bool inside, float lo, float hi, Lookup* l) const noexcept;
  QueryHit nearestHit(const Ray& ray, const Lookup& l, float* visibility) const noexcept;
  // The kNearest answer of a prepared lookup: nearestHit, or offHitAt for section 7.4.
  QueryHit nearestAnswer(const Ray& ray, const Lookup& l, float* visibility) const noexcept {
    return l.off ? offHitAt(ray, l.k0, l.i, l.j, l.t0, l.lo, l.hi, l.len, visibility) : nearestHit(ray, l, visibility);
  }
  // Section 7.4 (RayOrigin::kOffObject, origin inside the sphere). offHitAt: the nearest answer
  // from the forward lookup's texel (k, i, j) at entry distance t0 < 0 and window [lo, hi];
  // offHitsAt: its hit flag; behindOrigin: step 3, section 7.3 with no bias; offInterpolated: the
  // blend of a planned lane.
  QueryHit offHitAt(const Ray& ray, uint32_t k, uint32_t i, uint32_t j, float t0, float lo, float hi, float len,
                    float* visibility) const noexcept;
  bool offHitsAt(const Ray& ray, uint32_t k, uint32_t i, uint32_t j, float t0, float lo, float hi) const noexcept;
  QueryHit behindOrigin(const Ray& ray, float* visibility) const noexcept;
  // Whether the forward lookup's first surface lies behind the origin by more than the tolerance
  // (step 3 applies).
  bool behindAt(uint32_t k, uint32_t i, uint32_t j, float t0, float lo) const noexcept {
    const detail::Sample s = texel(k, i, j);
    return s.hit && t0 + s.distance < lo - offTolerance;
  }
  QueryHit offInterpolated(const Ray& ray, const Lookup& l, const detail::PlanBlock& plan, size_t lane,
                           const detail::BlendSums* sums, float* visibility) const noexcept;
  // A hit at distance t (along the unit direction) read from texel (i, j) of map k.
  QueryHit hitOf(const Ray& ray, uint32_t k, uint32_t i, uint32_t j, float t, bool inside, float len,
                 float* visibility) const noexcept;
  // The answer of a nearest lookup at texel (i, j) of map k (nearestHit, from its parts).
  QueryHit hitAt(const Ray& ray, uint32_t k, uint32_t i, uint32_t j, float t0, bool inside, float lo, float hi,
                 float len, float* visibility) const noexcept;
  // decodeHits: also decode the hit flags in the kernel, where it can (kUnorm8Diameter).
  detail::GroupTables groupTables(const QueryOptions& o, bool decodeHits) const noexcept;
  QueryHit interpolated(const Ray& ray, const Lookup& l, float* visibility) const noexcept;
  // interpolated() in two halves (see there), for lane `lane` of a block of plans (a batch plans
  // detail::kPlanLanes rays at once: detail::GroupKernel::plan).
  void planInterpolated(const Ray& ray, const Lookup& l, detail::PlanBlock* plan, size_t lane) const noexcept;
  void prefetchPlan(const detail::PlanBlock& plan, size_t lane) const noexcept;
  QueryHit blendInterpolated(const Ray& ray, const Lookup& l, const detail::PlanBlock& plan, size_t lane,
                             float* visibility) const noexcept;
  // The answer of a blend from its weight sums (blendInterpolated's last part).
  QueryHit blendResult(const Ray& ray, const Lookup& l, const detail::Blend& bl, float* visibility) const noexcept;
  detail::PlanTables planTables() const noexcept;
  template <class Emit>
  void batchInterpolated(std::span<const Ray> rays, const QueryOptions& o, Emit&& emit) const noexcept;
  // Runs the group kernel over rays, kGroupRays at a time: each(base, n, group), where bit r of
  // group.reached says whether ray base + r reaches the sphere (the others miss). The rays that
  // reach it wait in a LookupQueue until a full vector of them can be looked up, so groups are
  // looked up together. A group is handed over (and decoded, with tables.decodeHits) in order,
  // once it was looked up before the current group's sphere step and lookups, so that its texels
  // have had that time to arrive from memory.
  template <class Each>
  void forEachGroup(const detail::GroupKernel& kernel, std::span<const Ray> rays, const detail::GroupTables& tables,
                    Each&& each) const noexcept {
    constexpr size_t kRing = 4;  // groups in flight
    static_assert(kRing <= detail::LookupQueue::kMaxSegments, "each group in flight may wait in the queue");
    detail::Group g[kRing];
    size_t base[kRing] = {}, count[kRing] = {};
    detail::LookupQueue q;
    size_t next = 0, made = 0;  // groups handed over, groups prepared
    auto handOver = [&] {
      detail::Group& h = g[next % kRing];
      kernel.decode(tables, &h);
      each(base[next % kRing], count[next % kRing], h);
      ++next;
    };
    // The rays are requested from memory two groups (2 KiB) before the kernel reaches them, and
    // the first two groups at once: the kernel waited for them even with the CPU's own
    // prefetching, most of all at the start of each call. They are requested as non-temporal:
    // read once, they then take less of the cache the texels share with them.
    constexpr size_t kAhead = 2;
    // (many >= 1: an empty span's data() may be null. An early return for many == 0 in here
    // made GCC 12 drop the loops' prefetches altogether.)
    auto requestRays = [&](size_t first, size_t many) {
      const char* p = reinterpret_cast<const char*>(rays.data() + first);
      for (size_t o = 0; o < many * sizeof(Ray); o += 64) __builtin_prefetch(p + o, 0, 0);
    };
    if (!rays.empty()) requestRays(0, std::min(rays.size(), kAhead * detail::kGroupRays));
    for (size_t b = 0; b < rays.size(); b += detail::kGroupRays) {
      const size_t n = std::min(detail::kGroupRays, rays.size() - b);
      if (const size_t a = b + kAhead * detail::kGroupRays; a < rays.size())
        requestRays(a, std::min(detail::kGroupRays, rays.size() - a));
      if (made - next == kRing) {  // no free slot: finish the oldest group now
        kernel.lookup(tables, &q, true);
        handOver();
      }
      const size_t slot = made % kRing;
      kernel.sphere(tables, rays.data() + b, n, &g[slot], &q);
      base[slot] = b;
      count[slot] = n;
      ++made;
      // The groups looked up before this step (in order), handed over after its lookups.
      size_t ready = next;
      while (ready < made - 1 && g[ready % kRing].looked == g[ready % kRing].count) ++ready;
      kernel.lookup(tables, &q, false);
      while (next < ready) handOver();
    }
    kernel.lookup(tables, &q, true);
    while (next < made) handOver();
  }
  QueryHit query(const Ray& ray, const QueryOptions& o, float* visibility) const noexcept;
  // kRefined (query_refined.cpp): the answer of a prepared lookup at texel (i, j) of map k, from
  // the maps where the field is sure, else exact (anyHit: the first hit found, for occlusion).
  QueryHit refinedAt(const Ray& ray, uint32_t k, uint32_t i, uint32_t j, float t0, bool inside, float lo, float hi,
                     float len, bool anyHit, float* visibility) const noexcept;
  QueryHit exactHit(const Ray& ray, float* visibility) const noexcept;  // the first hit
  // The step of kRefined that answers a lookup at texel (i, j) of map k: the maps (as kNearest), a
  // sure miss, or the exact cast. *s: the texel. (Inline, as texel(): the batches' loops call it.)
  enum class RefineStep : uint8_t { kMaps, kMiss, kExact };
  RefineStep refineStep(uint32_t k, uint32_t i, uint32_t j, float t0, bool inside, float lo, float hi,
                        detail::Sample* s) const noexcept {
    *s = texel(k, i, j);
    if (inside) return RefineStep::kMaps;  // section 7.3's rays: the maps' answer
    if (refine.isUnsure((uint64_t(k) * m + j) * m + i)) return RefineStep::kExact;
    if (!s->hit) return RefineStep::kMiss;  // a sure miss: every texel around it misses too
    // Near the start of the range (or behind an origin inside the sphere) or near its end, the hit
    // may lie on the other side of it. (t: along the unit direction, as lo and hi.)
    const float t = t0 + s->distance;
    return t < lo + refineMargin || std::fabs(t - hi) < refineMargin ? RefineStep::kExact : RefineStep::kMaps;
  }
  // How far around the maps' hit an occlusion cast looks first, in margins: the depth steps the
  // marking of unsure texels allows (RefineOptions::jumpMargins).
  static constexpr float kRefineSearchMargins = 4.0f;
  // Whether the exact cast finds any hit in the ray's range. Occlusion needs any hit: first look
  // where the maps put one, a short stretch of the ray that the BVH culls to a few nodes; only when
  // nothing is there, the whole range. Both are exact casts, so the answer is the whole range's.
  bool exactOccluded(const Ray& ray, const detail::Sample& s, float t0, float len) const noexcept {
    if (s.hit && s.distance > 0) {
      const float t = t0 + s.distance, reach = kRefineSearchMargins * refineMargin;
      const float from = std::max(ray.tmin, (t - reach) / len), to = std::min(ray.tmax, (t + reach) / len);
      if (from <= to && bvh.occluded(ray.origin, ray.direction, from, to)) return true;
    }
    return bvh.occluded(ray.origin, ray.direction, ray.tmin, ray.tmax);
  }
  // refinedAt(...).hit for occlusion; objectRay() gives the ray, called only where a step needs it.
  template <class RayFn>
  bool refinedHitsAt(RayFn&& objectRay, uint32_t k, uint32_t i, uint32_t j, float t0, bool inside, float lo, float hi,
                     float len) const noexcept {
    detail::Sample s;
    switch (refineStep(k, i, j, t0, inside, lo, hi, &s)) {
      case RefineStep::kMiss: return false;
      case RefineStep::kExact: return exactOccluded(objectRay(), s, t0, len);
      case RefineStep::kMaps: break;
    }
    return t0 < 0 ? offHitsAt(objectRay(), k, i, j, t0, lo, hi) : hitsAt(k, i, j, t0, inside, lo, hi);
  }
  // Whether the nearest lookup at texel (i, j) of map k hits within [lo, hi] (hitAt(...).hit).
  // *t: the hit's distance along the ray's unit direction.
  bool hitsAt(uint32_t k, uint32_t i, uint32_t j, float t0, bool inside, float lo, float hi,
              float* t = nullptr) const noexcept {
    const detail::Sample s = texel(k, i, j);
    if (!s.hit) return false;
    const float th = inside ? t0 - s.distance : t0 + s.distance;
    if (t) *t = th;
    return !(th < lo || th > hi);
  }
  // kHitOnly: emit(base, n, hits) per run of rays; otherwise emit(r, const QueryHit&, float
  // visibility) per ray (see the definition).
  // With `to`, the rays are in world space: the kernel and prepare() take them to object space.
  // kRefined lookups take its steps (refinedHitsAt for kHitOnly, refinedAt otherwise).
  template <bool kHitOnly, class Emit>
  void batchNearest(std::span<const Ray> rays, const QueryOptions& o, const detail::ToObject* to, Emit&& emit) const noexcept;
  // The batch calls of FieldQuery (x null: object-space rays) and of Instance (world-space rays, x
  // their transform). Nearest batches hand the transform to the group kernel, which applies it
  // lane by lane; interpolated batches take the rays to object space a few hundred at a time.
  // out.size() == rays.size().
  void intersectBatch(std::span<const Ray> rays, std::span<QueryHit> out, const QueryOptions& o,
                      const RigidTransform* x) const noexcept;
  void occludedBatch(std::span<const Ray> rays, std::span<uint8_t> out, const QueryOptions& o,
                     const RigidTransform* x) const noexcept;
  void visibilityBatch(std::span<const Ray> rays, std::span<float> out, const QueryOptions& o,
                       const RigidTransform* x) const noexcept;
  // The lookup sites of a batch (query_site.cpp): the group kernel's first steps, stopped before
  // the texels are read.
  void sitesBatch(std::span<const Ray> rays, std::span<LookupSite> out, const QueryOptions& o,
                  const RigidTransform* x) const noexcept;
  const uint8_t* texelAddress(uint32_t k, uint32_t i, uint32_t j) const noexcept {
    return dist[k] + detail::texelByte(field.distanceEncoding, m, i, j);
  }
};

// (Defined here, inline: see the unnamed namespace above.)
inline QueryHit FieldQuery::Impl::blendResult(const Ray& ray, const Lookup& l, const detail::Blend& bl,
                                       float* visibility) const noexcept {
  QueryHit out;
  // Hits before the range (the origin's own surface from inside, or surfaces behind tmin) are
  // neither occluders nor misses: leave them out of the vote.
  const float total = bl.hitWeight + bl.missWeight + bl.farWeight;
  if (!(total > 0)) return out;
  if (visibility) *visibility = (bl.missWeight + bl.farWeight) / total;
  if (bl.hitWeight <= bl.missWeight + bl.farWeight) return out;
  const float t = bl.tSum / bl.hitWeight;
  out.hit = true;
  out.inside = l.inside;
  out.t = t / l.len;
  out.point = ray.origin + l.w * t;
  if (!norm.empty()) {
    out.normal = normalize(bl.normalSum);
    out.hasNormal = dot(out.normal, out.normal) > 0;
  }
  return out;
}

}  // namespace vff
