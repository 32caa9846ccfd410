// The CPU query (vff/query.h; spec/geometry.md section 7).
#include "vff/query.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <string>
#include <vector>

#include "vff/bc4.h"
#include "vff/encoding.h"
#include "vff/reader.h"

#include "fast_lookup.h"
#include "huge_pages.h"
#include "query_group.h"

namespace vff {
namespace {

constexpr float kPi = 3.14159265358979323846f;

inline Vec3 operator+(Vec3 a, Vec3 b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline Vec3 operator-(Vec3 a, Vec3 b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline Vec3 operator*(Vec3 a, float s) { return {a.x * s, a.y * s, a.z * s}; }
inline Vec3 operator-(Vec3 a) { return {-a.x, -a.y, -a.z}; }
inline float dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

inline Vec3 normalize(Vec3 v) {
  const float l = std::sqrt(dot(v, v));
  return l > 0 ? v * (1.0f / l) : Vec3{};
}

// A RigidTransform's inverse, taken apart once for many rays: what toObjectVector and
// toObjectPoint compute, inlined. The group kernel repeats these operations lane by lane
// (GroupTables::toObject).
struct ToObject {
  const float (&r)[3][3];  // the inverse rotation is the transpose
  Vec3 translation;
  float invScale;
  explicit ToObject(const RigidTransform& x) noexcept
      : r(x.rotation), translation(x.translation), invScale(1.0f / x.scale) {}
  Vec3 vector(Vec3 v) const noexcept {
    return Vec3{r[0][0] * v.x + r[1][0] * v.y + r[2][0] * v.z, r[0][1] * v.x + r[1][1] * v.y + r[2][1] * v.z,
                r[0][2] * v.x + r[1][2] * v.y + r[2][2] * v.z} *
           invScale;
  }
  Vec3 point(Vec3 p) const noexcept { return vector(p - translation); }
  Ray ray(const Ray& w) const noexcept { return Ray{point(w.origin), vector(w.direction), w.tmin, w.tmax}; }
};

// The field's answer to an object-space ray, in world space (both rays share t).
void toWorld(const RigidTransform& x, const Ray& worldRay, QueryHit* h) {
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

}  // namespace

struct FieldQuery::Impl {
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
  std::vector<uint32_t> neighbours;  // kNeighbours per map; UINT32_MAX pads
  float spacing = 0;                 // mean angular spacing sqrt(4 pi / mapCount)
  float kernelRadius2 = 0;           // squared chord radius of the interpolation kernel
  float defaultBias = 0;             // fraction of R
  std::vector<float> chordScale;     // unorm8-chord: 2R cos(alpha) / 254 per texel (M * M)
  uint64_t payload = 0;
  uint64_t hugePages = 0;  // bytes of the maps on huge pages (build(): adviseMapRuns)

  Sample texel(uint32_t k, uint32_t i, uint32_t j) const noexcept {
    const uint8_t* map = dist[k];
    const size_t t = size_t(j) * m + i;
    switch (field.distanceEncoding) {
      case DistanceEncoding::kUnorm8Diameter: {
        const uint32_t c = map[t];
        return {c != 255u, float(c) * (2.0f * radius / 254.0f)};
      }
      case DistanceEncoding::kUnorm16Diameter: {
        const uint32_t c = uint32_t(map[2 * t]) | (uint32_t(map[2 * t + 1]) << 8);
        return {c != 65535u, float(c) * (2.0f * radius / 65534.0f)};
      }
      case DistanceEncoding::kUnorm8Chord: {
        const uint32_t c = map[t];
        return {c != 255u, float(c) * chordScale[t]};
      }
      case DistanceEncoding::kBit1:
        return {((map[t / 8] >> (t % 8)) & 1u) != 0, 0.0f};
      case DistanceEncoding::kBc4Diameter: {
        const uint32_t c = bc4Texel(map + detail::texelByte(DistanceEncoding::kBc4Diameter, m, i, j), (j & 3u) * 4 + (i & 3u));
        return {c != 255u, float(c) * (2.0f * radius / 254.0f)};
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
    bool inside = false;
    uint32_t k0 = 0, i = 0, j = 0;  // i, j: the nearest lookup's texel
  };
  bool prepare(const Ray& ray, const QueryOptions& o, Lookup* l) const noexcept;
  // The part of prepare() after the sphere: everything but k0, i, j, from the sphere's results
  // (the group kernel's, for interpolated batches).
  void lookupFrom(const Ray& ray, float len, float t0, bool inside, float lo, float hi, Lookup* l) const noexcept;
  QueryHit nearestHit(const Ray& ray, const Lookup& l, float* visibility) const noexcept;
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
  QueryHit blendResult(const Ray& ray, const Lookup& l, const Blend& bl, float* visibility) const noexcept;
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
    // prefetching (vff-experiments bench AO rays, 2 threads: 1.06x; then the first groups of
    // each call, not requested before: 1.44x with calls of 256 rays, 1.01-1.09x with 4096.
    // Four groups ahead made no difference runs could tell from noise). They are requested as
    // non-temporal: read once, they then take less of the cache the texels share with them (AMD
    // Zen 5, the bench's 64 MiB ray sets, in-process A/B (its noise: query_group_kernel.h): AO
    // rays 1.04-1.08x with 2 threads, aimed rays 1.04-1.13x. There the two builds share the cache,
    // so that this change reaches the other build too: README.md gives the bench's figures for
    // this version against the one before, run alternately).
    constexpr size_t kAhead = 2;
    // (many >= 1: an empty span's data() may be null. An early return for many == 0 in here
    // made GCC 12 drop the loops' prefetches altogether: 0.6x.)
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
  // Whether the nearest lookup at texel (i, j) of map k hits within [lo, hi] (hitAt(...).hit).
  // *t: the hit's distance along the ray's unit direction.
  bool hitsAt(uint32_t k, uint32_t i, uint32_t j, float t0, bool inside, float lo, float hi,
              float* t = nullptr) const noexcept {
    const Sample s = texel(k, i, j);
    if (!s.hit) return false;
    const float th = inside ? t0 - s.distance : t0 + s.distance;
    if (t) *t = th;
    return !(th < lo || th > hi);
  }
  // kHitOnly: emit(base, n, hits) per run of rays; otherwise emit(r, const QueryHit&, float
  // visibility) per ray (see the definition).
  // With `to`, the rays are in world space: the kernel and prepare() take them to object space.
  template <bool kHitOnly, class Emit>
  void batchNearest(std::span<const Ray> rays, const QueryOptions& o, const ToObject* to, Emit&& emit) const noexcept;
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
  const uint8_t* texelAddress(uint32_t k, uint32_t i, uint32_t j) const noexcept {
    return dist[k] + detail::texelByte(field.distanceEncoding, m, i, j);
  }
};

namespace {

Vec3 toVec(const float c[3]) { return {c[0], c[1], c[2]}; }

// fn(r) for each r < n whose bit in `bits` is clear: a loop over the set bits of the rest, with no
// branch per bit (the rays that reach the sphere are random bits of their group).
template <class Fn>
void forEachClear(uint64_t bits, size_t n, Fn&& fn) {
  for (uint64_t m = ~bits & detail::packedBits(n); m != 0; m &= m - 1) fn(size_t(__builtin_ctzll(m)));
}

// For every byte value b, the 8 bytes (bit l of b) for l = 0 .. 7, little-endian.
struct BitBytes {
  uint64_t word[256];
  constexpr BitBytes() : word() {
    for (unsigned b = 0; b < 256; ++b)
      for (unsigned l = 0; l < 8; ++l) word[b] |= uint64_t((b >> l) & 1u) << (8 * l);
  }
};
constexpr BitBytes kBitBytes{};

// out[r] = bit r of hits (0 or 1), for r < n <= 64.
void writeHitBytes(uint64_t hits, size_t n, uint8_t* out) {
  size_t r = 0;
  for (; r + 8 <= n; r += 8) {
    const uint64_t w = kBitBytes.word[(hits >> r) & 0xFFu];
    for (unsigned l = 0; l < 8; ++l) out[r + l] = uint8_t(w >> (8 * l));  // one 8-byte store
  }
  for (; r < n; ++r) out[r] = uint8_t((hits >> r) & 1u);
}

// detail::adviseHugePages over each run of maps that lie back to back; the bytes it got.
uint64_t adviseMapRuns(const std::vector<const uint8_t*>& maps, uint64_t mapBytes) {
  uint64_t got = 0;
  for (size_t k = 0; k < maps.size();) {
    size_t end = k + 1;
    while (end < maps.size() && maps[end] == maps[end - 1] + mapBytes) ++end;
    got += detail::adviseHugePages(maps[k], size_t((end - k) * mapBytes));
    k = end;
  }
  return got;
}

}  // namespace

void FieldQuery::Impl::build() {
  const uint32_t n = field.mapCount;
  center = toVec(field.sphere.center);
  radius = field.sphere.radius;
  m = field.mapResolution;
  const uint64_t planeBytes = uint64_t(n) * distMapBytes;
  byteTexels = (field.distanceEncoding == DistanceEncoding::kUnorm8Diameter ||
                field.distanceEncoding == DistanceEncoding::kUnorm8Chord) &&
               m <= 4096 && n > 0;
  contiguous = byteTexels && planeBytes >= 4 && planeBytes < (uint64_t(1) << 31);
  for (uint32_t k = 0; k < n && contiguous; ++k) contiguous = dist[k] == dist[0] + size_t(k) * distMapBytes;
  floatMapIndices = n < (1u << 24);
  bool normalsContiguous = !norm.empty() && uint64_t(n) * normMapBytes < (uint64_t(1) << 31);
  for (uint32_t k = 0; k < n && normalsContiguous; ++k) normalsContiguous = norm[k] == norm[0] + size_t(k) * normMapBytes;
  if (contiguous && field.distanceEncoding == DistanceEncoding::kUnorm8Diameter && floatMapIndices &&
      (norm.empty() || normalsContiguous)) {
    blendTables.texels = dist[0];
    blendTables.mapBytes = int32_t(distMapBytes);
    blendTables.m = m;
    blendTables.distanceScale = 2.0f * radius / 254.0f;  // (texel()'s scale)
    if (!norm.empty()) {
      blendTables.normals = norm[0];
      blendTables.normalMapBytes = int32_t(normMapBytes);
    }
  }
  // The maps are read at random: on huge pages, where the OS gives them (huge_pages.h).
  hugePages = adviseMapRuns(dist, distMapBytes) + adviseMapRuns(norm, normMapBytes);
  frames.resize(n);
  unit4.assign(size_t(n) * 4, 0.0f);
  for (uint32_t k = 0; k < n; ++k) {
    const Vec3 u = positions.position(k);
    unit4[size_t(k) * 4] = u.x;
    unit4[size_t(k) * 4 + 1] = u.y;
    unit4[size_t(k) * 4 + 2] = u.z;
    frames[k] = positions.frame(k);
  }
  if (positions.scheme() == PositionScheme::kOctaHemi2) {
    octaMasks = detail::octaCandidateMasks(positions.param());
    octaCornerRows = detail::octaCornerRows(octaMasks, positions.param());
    if (!octaMasks.empty()) octaMasks.resize(octaMasks.size() + 3, 0);  // GroupTables::octaMasks' padding
  }
  spacing = std::sqrt(4.0f * kPi / float(n));
  // The kernel reaches 1.3 mean spacings (ground AO under the bunny: 1.0 and 1.6 are worse or
  // slower; vff-experiments ao).
  const float r = kQueryKernelSpacings * spacing;
  kernelRadius2 = r * r;
  defaultBias = defaultIntraBias(field);
  if (field.distanceEncoding == DistanceEncoding::kUnorm8Chord) {
    chordScale.resize(size_t(m) * m);
    for (uint32_t j = 0; j < m; ++j)
      for (uint32_t i = 0; i < m; ++i)
        chordScale[size_t(j) * m + i] = 2.0f * radius * texelDirection(field.directionScheme, m, i, j).z / 254.0f;
  }
  neighbours = queryNeighbours(positions);
}

std::vector<uint32_t> queryNeighbours(const PositionSet& positions) {
  // The samples nearest to probe directions on two rings around each sample: this finds the
  // samples whose Voronoi cells border the kernel around it, in every scheme.
  const uint32_t n = positions.count();
  std::vector<uint32_t> out(size_t(n) * kQueryNeighbours, UINT32_MAX);
  if (n == 0) return out;
  const float spacing = std::sqrt(4.0f * kPi / float(n));
  constexpr int kProbes = 12;
  for (uint32_t k = 0; k < n; ++k) {
    uint32_t found[kQueryNeighbours];
    uint32_t count = 0;
    const Vec3 u = positions.position(k);
    const Frame f = positions.frame(k);
    for (float ring : {1.0f, 1.6f}) {
      const float a = ring * spacing;
      for (int p = 0; p < kProbes && count < kQueryNeighbours; ++p) {
        const float phi = 2.0f * kPi * (float(p) + (ring > 1.2f ? 0.5f : 0.0f)) / kProbes;
        const Vec3 d = u * std::cos(a) + (f.t * std::cos(phi) + f.b * std::sin(phi)) * std::sin(a);
        const uint32_t q = positions.nearest(d);
        if (q == k) continue;
        // An octa-hemi2 equator copy has the same position as its twin: keep one of them.
        bool dup = false;
        for (uint32_t c = 0; c < count; ++c) dup = dup || found[c] == q;
        if (!dup) found[count++] = q;
      }
    }
    std::copy(found, found + count, out.begin() + ptrdiff_t(size_t(k) * kQueryNeighbours));
  }
  return out;
}

const char* batchKernelName() noexcept { return detail::groupKernelName(); }

float defaultIntraBias(const FieldDesc& field) noexcept {
  if (field.mapCount == 0 || !(field.sphere.radius > 0)) return 0.0f;
  const float step = quantizationStep(field.distanceEncoding, 1.0f, 1.0f);
  return 2.0f * step + std::sqrt(4.0f * kPi / float(field.mapCount));
}

FieldQuery::FieldQuery() noexcept = default;
FieldQuery::FieldQuery(FieldQuery&&) noexcept = default;
FieldQuery& FieldQuery::operator=(FieldQuery&&) noexcept = default;
FieldQuery::~FieldQuery() = default;

Result<FieldQuery> FieldQuery::fromMaps(const FieldDesc& field, std::span<const uint8_t> distance,
                                        std::span<const uint8_t> normals) {
  if (Status s = checkFieldDesc(field); !s) return s.error();
  auto ps = PositionSet::fromField(field);
  if (!ps) return ps.error();
  const uint64_t db = distanceMapBytes(field.distanceEncoding, field.mapResolution);
  const uint64_t nb = normalMapBytes(field.normalEncoding, field.mapResolution);
  if (distance.size() != db * field.mapCount)
    return makeError(Code::kInvalidArgument, "distance plane holds " + std::to_string(distance.size()) +
                                                 " bytes, the field needs " + std::to_string(db * field.mapCount));
  if (!normals.empty() && (field.normalEncoding == NormalEncoding::kNone || normals.size() != nb * field.mapCount))
    return makeError(Code::kInvalidArgument, "normal plane holds " + std::to_string(normals.size()) +
                                                 " bytes, the field needs " + std::to_string(nb * field.mapCount));
  auto impl = std::make_unique<Impl>();
  impl->field = field;
  impl->positions = *ps;
  impl->distMapBytes = db;
  impl->normMapBytes = nb;
  impl->dist.resize(field.mapCount);
  for (uint32_t k = 0; k < field.mapCount; ++k) impl->dist[k] = distance.data() + k * db;
  impl->payload = distance.size();
  if (!normals.empty()) {
    impl->norm.resize(field.mapCount);
    for (uint32_t k = 0; k < field.mapCount; ++k) impl->norm[k] = normals.data() + k * nb;
    impl->payload += normals.size();
  }
  impl->build();
  FieldQuery q;
  q.impl_ = std::move(impl);
  return q;
}

Result<FieldQuery> FieldQuery::fromFile(const File& file) {
  const FieldDesc& field = file.field();
  auto ps = PositionSet::fromField(field);
  if (!ps) return ps.error();
  auto impl = std::make_unique<Impl>();
  impl->field = field;
  impl->positions = *ps;
  impl->distMapBytes = distanceMapBytes(field.distanceEncoding, field.mapResolution);
  impl->normMapBytes = normalMapBytes(field.normalEncoding, field.mapResolution);
  impl->dist.resize(field.mapCount);
  for (uint32_t k = 0; k < field.mapCount; ++k) {
    auto map = file.mapData(Plane::kDistance, k);
    if (!map) return map.error();
    impl->dist[k] = map->data();
  }
  impl->payload = file.plane(Plane::kDistance).rawBytes;
  if (file.hasNormals()) {
    impl->norm.resize(field.mapCount);
    for (uint32_t k = 0; k < field.mapCount; ++k) {
      auto map = file.mapData(Plane::kNormal, k);
      if (!map) return map.error();
      impl->norm[k] = map->data();
    }
    impl->payload += file.plane(Plane::kNormal).rawBytes;
  }
  impl->build();
  FieldQuery q;
  q.impl_ = std::move(impl);
  return q;
}

const FieldDesc& FieldQuery::field() const noexcept {
  static const FieldDesc kEmpty{};
  return impl_ ? impl_->field : kEmpty;
}
const PositionSet& FieldQuery::positions() const noexcept {
  static const PositionSet kEmpty{};
  return impl_ ? impl_->positions : kEmpty;
}
bool FieldQuery::hasNormals() const noexcept { return impl_ && !impl_->norm.empty(); }
uint64_t FieldQuery::payloadBytes() const noexcept { return impl_ ? impl_->payload : 0; }
uint64_t FieldQuery::hugePageBytes() const noexcept { return impl_ ? impl_->hugePages : 0; }

// The core of every query. Distances below are object-space lengths along the unit direction w;
// the caller's t is that length divided by |direction|.
void FieldQuery::Impl::lookupFrom(const Ray& ray, float len, float t0, bool inside, float lo, float hi,
                                  Lookup* l) const noexcept {
  const Vec3 w = ray.direction * (1.0f / len);
  l->w = w;
  l->len = len;
  l->t0 = t0;
  l->inside = inside;
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
  const bool inside = gamma <= 0;
  // The lookup: the ray enters at `e` looking along `v`. From inside (section 7.3) the reversed
  // ray enters at the exit point, looking back at the origin.
  const float t0 = inside ? t1 : std::max(-beta - sq, 0.0f);  // the lookup's entry point along the ray
  // A hit counts when its t lies in [lo, hi]. From inside, the surface must also be more than the
  // bias in front of the origin (the origin's own surface is not an occluder).
  float lo = tmin;
  if (inside) {
    if (field.distanceEncoding == DistanceEncoding::kBit1) return false;  // no distances: cannot tell
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
  QueryHit out;
  float t = 0;
  if (!hitsAt(k, i, j, t0, inside, lo, hi, &t)) return out;
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
  if (o.reconstruction == Reconstruction::kNearest || l.inside) return nearestHit(ray, l, visibility);
  return interpolated(ray, l, visibility);
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

detail::PlanTables FieldQuery::Impl::planTables() const noexcept {
  detail::PlanTables t;
  t.unit4 = unit4.data();
  t.neighbours = neighbours.data();
  t.kernelRadius2 = kernelRadius2;
  t.center = center;
  t.radius = radius;
  t.m = m;
  t.scheme = field.directionScheme;
  t.texels = blendTables.texels;
  t.mapBytes = blendTables.mapBytes;
  return t;
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
  Blend bl;
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
        const Sample s = texel(k, ti, tj);
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

QueryHit FieldQuery::Impl::blendResult(const Ray& ray, const Lookup& l, const Blend& bl,
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

QueryHit FieldQuery::Impl::interpolated(const Ray& ray, const Lookup& l, float* visibility) const noexcept {
  detail::PlanBlock plan;  // (lane 0 only)
  planInterpolated(ray, l, &plan, 0);
  return blendInterpolated(ray, l, plan, 0, visibility);
}

// Batches of interpolated lookups. The group kernel finds, for 64 rays at a time, those that reach
// the sphere and their nearest samples; they fill blocks of 16, whatever group they came from (a
// third of the AO rays reach the sphere: blocks cut at each group's end would run part-empty), and
// each block is planned together (the kernel's plan(), as planInterpolated() one ray at a time)
// with all its taps' texels requested from memory, then blended, 16 at a time too where the kernel
// can (its blend(), as blendInterpolated() one ray at a time). Rays from inside the sphere are
// answered as kNearest (query()). (Blending a block while the next is planned, so that its texels
// had longer to arrive, gained nothing: in-process A/B on vff-experiments bench rays, 0.96-1.05x.)
template <class Emit>
void FieldQuery::Impl::batchInterpolated(std::span<const Ray> rays, const QueryOptions& o, Emit&& emit) const noexcept {
  constexpr size_t kPlanned = detail::kPlanLanes;
  const detail::GroupKernel* kernel = detail::groupKernel();  // (one for the whole batch)
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
        br.lo[c] = blended ? l[c].lo : 0.0f;
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
      } else if (live[c] && summed) {
        Blend bl;
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
    forEachClear(g.reached, n, [&](size_t r) { emit(base + r, QueryHit{}, 1.0f); });
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

detail::GroupTables FieldQuery::Impl::groupTables(const QueryOptions& o, bool decodeHits) const noexcept {
  detail::GroupTables t;
  t.center = center;
  t.radius = radius;
  t.octaN = positions.scheme() == PositionScheme::kOctaHemi2 ? positions.param() : 0;
  t.unit4 = unit4.data();
  t.octaMasks = octaMasks.empty() ? nullptr : octaMasks.data();
  t.octaCornerRows = octaCornerRows.empty() ? nullptr : octaCornerRows.data();
  t.scheme = field.directionScheme;
  t.m = m;
  t.bit1 = field.distanceEncoding == DistanceEncoding::kBit1;
  t.insideLo = (o.intraBias >= 0 ? o.intraBias : defaultBias) * radius;
  t.gridGuard = detail::gridGuard(t.octaN);
  t.texelGuard = detail::texelGuard(m);
  t.maps = dist.data();
  t.encoding = field.distanceEncoding;
  t.byteTexels = byteTexels;
  if (contiguous) {
    t.texels = dist[0];
    t.mapBytes = int32_t(distMapBytes);
  }
  t.decodeHits = decodeHits && byteTexels && field.distanceEncoding == DistanceEncoding::kUnorm8Diameter;
  t.distanceScale = 2.0f * radius / 254.0f;
  return t;
}

// Batches of nearest lookups run in groups: the group kernel (query_group.h) prepares every ray
// of a group, prepare() redoes the few rays the kernel leaves to it, the texels of the group are
// requested from memory together, and then decoded (by the kernel itself where it can). The
// scattered texel reads of a group overlap instead of waiting one after the other.
//
// kHitOnly: emit(base, n, hits) for each run of n <= 64 rays from base, bit r of `hits` saying
// whether ray base + r hits. Otherwise: emit(r, const QueryHit&, float visibility) per ray.
template <bool kHitOnly, class Emit>
void FieldQuery::Impl::batchNearest(std::span<const Ray> rays, const QueryOptions& o, const ToObject* to,
                                    Emit&& emit) const noexcept {
  auto objectRay = [&](size_t r) { return to ? to->ray(rays[r]) : rays[r]; };
  const detail::GroupKernel* kernel = detail::groupKernel();  // (one for the whole batch)
  if (!kernel) {
    for (size_t base = 0; base < rays.size(); base += detail::kGroupRays) {
      const size_t n = std::min(detail::kGroupRays, rays.size() - base);
      uint64_t hits = 0;
      for (size_t r = 0; r < n; ++r) {
        float vis = 1.0f;
        Lookup l;
        const Ray ray = objectRay(base + r);
        const QueryHit h = prepare(ray, o, &l) ? nearestHit(ray, l, &vis) : QueryHit{};
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
  detail::GroupTables tables = groupTables(o, kHitOnly);
  if (to) {
    tables.toObject = true;
    std::memcpy(tables.objectRotation, to->r, sizeof tables.objectRotation);
    tables.objectShift = to->translation;
    tables.objectInvScale = to->invScale;
  }
  forEachGroup(*kernel, rays, tables, [&](size_t base, size_t n, detail::Group& g) {
    // Every ray misses unless it reaches the sphere.
    if constexpr (!kHitOnly) forEachClear(g.reached, n, [&](size_t r) { emit(base + r, QueryHit{}, 1.0f); });
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
        if (hitsAt(g.k[p], g.i[p], g.j[p], g.t0[r], (g.inside >> r) & 1u, g.lo[r], g.hi[r])) hits |= uint64_t(1) << r;
      }
      emit(base, n, hits);
    } else {
      for (uint32_t p = 0; p < g.count; ++p) {
        const uint32_t r = g.ray[p];
        float vis = 1.0f;
        const QueryHit h = (dead >> p) & 1u ? QueryHit{}
                                            : hitAt(objectRay(base + r), g.k[p], g.i[p], g.j[p], g.t0[r],
                                                    (g.inside >> r) & 1u, g.lo[r], g.hi[r], g.len[r], &vis);
        emit(base + r, h, vis);
      }
    }
  });
}

namespace {

// Calls batch(objectRays, first) for rays in chunks, taken to object space by x (none: the rays
// are in object space, one call).
template <class Batch>
void inObjectSpace(const RigidTransform* x, std::span<const Ray> rays, Batch&& batch) {
  if (!x) {
    batch(rays, size_t(0));
    return;
  }
  constexpr size_t kChunk = 256;
  const ToObject to(*x);
  Ray local[kChunk];
  for (size_t first = 0; first < rays.size(); first += kChunk) {
    const size_t n = std::min(kChunk, rays.size() - first);
    for (size_t r = 0; r < n; ++r) local[r] = to.ray(rays[first + r]);
    batch(std::span<const Ray>(local, n), first);
  }
}

// fn(to) with x taken apart (null for none).
template <class Fn>
void withToObject(const RigidTransform* x, Fn&& fn) {
  if (x) {
    const ToObject to(*x);
    fn(&to);
  } else {
    fn(static_cast<const ToObject*>(nullptr));
  }
}

}  // namespace

void FieldQuery::Impl::intersectBatch(std::span<const Ray> rays, std::span<QueryHit> out, const QueryOptions& o,
                                      const RigidTransform* x) const noexcept {
  if (o.reconstruction == Reconstruction::kNearest) {
    withToObject(x, [&](const ToObject* to) {
      batchNearest<false>(rays, o, to, [&](size_t r, const QueryHit& h, float) {
        out[r] = h;
        if (x) toWorld(*x, rays[r], &out[r]);
      });
    });
    return;
  }
  inObjectSpace(x, rays, [&](std::span<const Ray> objectRays, size_t first) {
    batchInterpolated(objectRays, o, [&](size_t r, const QueryHit& h, float) {
      out[first + r] = h;
      if (x) toWorld(*x, rays[first + r], &out[first + r]);
    });
  });
}

void FieldQuery::Impl::occludedBatch(std::span<const Ray> rays, std::span<uint8_t> out, const QueryOptions& o,
                                     const RigidTransform* x) const noexcept {
  if (o.reconstruction == Reconstruction::kNearest) {
    withToObject(x, [&](const ToObject* to) {
      batchNearest<true>(rays, o, to,
                         [&](size_t base, size_t count, uint64_t hits) { writeHitBytes(hits, count, &out[base]); });
    });
    return;
  }
  inObjectSpace(x, rays, [&](std::span<const Ray> objectRays, size_t first) {
    batchInterpolated(objectRays, o, [&](size_t r, const QueryHit& h, float) { out[first + r] = h.hit ? 1 : 0; });
  });
}

void FieldQuery::Impl::visibilityBatch(std::span<const Ray> rays, std::span<float> out, const QueryOptions& o,
                                       const RigidTransform* x) const noexcept {
  if (o.reconstruction == Reconstruction::kNearest) {
    withToObject(x, [&](const ToObject* to) {
      batchNearest<true>(rays, o, to, [&](size_t base, size_t count, uint64_t hits) {
        for (size_t r = 0; r < count; ++r) out[base + r] = (hits >> r) & 1u ? 0.0f : 1.0f;
      });
    });
    return;
  }
  inObjectSpace(x, rays, [&](std::span<const Ray> objectRays, size_t first) {
    batchInterpolated(objectRays, o, [&](size_t r, const QueryHit&, float v) { out[first + r] = v; });
  });
}

void FieldQuery::intersect(std::span<const Ray> rays, std::span<QueryHit> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(rays.size(), out.size());
  if (impl_) {
    impl_->intersectBatch(rays.first(n), out.first(n), options, nullptr);
  } else {
    std::fill_n(out.begin(), n, QueryHit{});
  }
}

void FieldQuery::occluded(std::span<const Ray> rays, std::span<uint8_t> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(rays.size(), out.size());
  if (impl_) {
    impl_->occludedBatch(rays.first(n), out.first(n), options, nullptr);
  } else {
    std::fill_n(out.begin(), n, uint8_t(0));
  }
}

void FieldQuery::visibility(std::span<const Ray> rays, std::span<float> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(rays.size(), out.size());
  if (impl_) {
    impl_->visibilityBatch(rays.first(n), out.first(n), options, nullptr);
  } else {
    std::fill_n(out.begin(), n, 1.0f);
  }
}

// ---- RigidTransform and Instance ----------------------------------------------------------------

Vec3 RigidTransform::toWorldVector(Vec3 v) const noexcept {
  const auto& r = rotation;
  return Vec3{r[0][0] * v.x + r[0][1] * v.y + r[0][2] * v.z, r[1][0] * v.x + r[1][1] * v.y + r[1][2] * v.z,
              r[2][0] * v.x + r[2][1] * v.y + r[2][2] * v.z} *
         scale;
}

Vec3 RigidTransform::toWorldPoint(Vec3 p) const noexcept { return toWorldVector(p) + translation; }

Vec3 RigidTransform::toObjectVector(Vec3 v) const noexcept { return ToObject(*this).vector(v); }

Vec3 RigidTransform::toObjectPoint(Vec3 p) const noexcept { return ToObject(*this).point(p); }

RigidTransform RigidTransform::fromAxisAngle(Vec3 axis, float radians, Vec3 translation, float scale) noexcept {
  RigidTransform x;
  const Vec3 a = normalize(axis);
  const float c = std::cos(radians), s = std::sin(radians), t = 1.0f - c;
  x.rotation[0][0] = c + a.x * a.x * t;
  x.rotation[0][1] = a.x * a.y * t - a.z * s;
  x.rotation[0][2] = a.x * a.z * t + a.y * s;
  x.rotation[1][0] = a.y * a.x * t + a.z * s;
  x.rotation[1][1] = c + a.y * a.y * t;
  x.rotation[1][2] = a.y * a.z * t - a.x * s;
  x.rotation[2][0] = a.z * a.x * t - a.y * s;
  x.rotation[2][1] = a.z * a.y * t + a.x * s;
  x.rotation[2][2] = c + a.z * a.z * t;
  x.translation = translation;
  x.scale = scale;
  return x;
}

namespace {

Ray toObject(const RigidTransform& x, const Ray& r) { return ToObject(x).ray(r); }

}  // namespace

QueryHit Instance::intersect(const Ray& worldRay, const QueryOptions& options) const noexcept {
  if (!field) return {};
  QueryHit h = field->intersect(toObject(transform, worldRay), options);
  toWorld(transform, worldRay, &h);
  return h;
}

bool Instance::occluded(const Ray& worldRay, const QueryOptions& options) const noexcept {
  return field && field->occluded(toObject(transform, worldRay), options);
}

float Instance::visibility(const Ray& worldRay, const QueryOptions& options) const noexcept {
  return field ? field->visibility(toObject(transform, worldRay), options) : 1.0f;
}

void Instance::intersect(std::span<const Ray> worldRays, std::span<QueryHit> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(worldRays.size(), out.size());
  if (field && field->impl_) {
    field->impl_->intersectBatch(worldRays.first(n), out.first(n), options, &transform);
  } else {
    std::fill_n(out.begin(), n, QueryHit{});
  }
}

void Instance::occluded(std::span<const Ray> worldRays, std::span<uint8_t> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(worldRays.size(), out.size());
  if (field && field->impl_) {
    field->impl_->occludedBatch(worldRays.first(n), out.first(n), options, &transform);
  } else {
    std::fill_n(out.begin(), n, uint8_t(0));
  }
}

void Instance::visibility(std::span<const Ray> worldRays, std::span<float> out, const QueryOptions& options) const noexcept {
  const size_t n = std::min(worldRays.size(), out.size());
  if (field && field->impl_) {
    field->impl_->visibilityBatch(worldRays.first(n), out.first(n), options, &transform);
  } else {
    std::fill_n(out.begin(), n, 1.0f);
  }
}

Sphere Instance::worldSphere() const noexcept {
  if (!field) return {};
  const Sphere& s = field->field().sphere;
  const Vec3 c = transform.toWorldPoint(toVec(s.center));
  return Sphere{{c.x, c.y, c.z}, s.radius * transform.scale};
}

}  // namespace vff
