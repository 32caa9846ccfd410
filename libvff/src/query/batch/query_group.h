// query_group.h - the nearest lookup of many rays at once, 32 at a time in AVX-512 or AVX2
// vectors or 8 in SSE2 vectors (internal).
//
// FieldQuery's batch functions hand rays to a GroupKernel's sphere() in groups of kGroupRays, and
// the rays that reach the sphere to its lookup() through a LookupQueue. Together they compute, for
// every ray, what FieldQuery::Impl::prepare computes one ray at a time: the sphere entry, the
// nearest positional sample (octa-hemi2: the candidates of PositionSet::candidates, scored without
// reading their positions, fast_lookup.h's kOctaScoreError) and the texel of the lookup direction
// in that sample's map; for occlusion batches over one-byte maps, decode() then reads the
// texels and decodes the hit flags. Where the kernel computes what prepare() computes it performs
// the same binary32 operations in the same order. Where its two best candidates score too close
// to call, it scores that ray's candidates as the reference does (octaBestCandidate, one lane at a
// time). It leaves to the caller (bit `redo`) every ray on which a guard of fast_lookup.h trips or
// whose scheme it does not handle, so that a group gives exactly the texel and the answer
// prepare() and hitsAt() give (tests/unit/test_fast_lookup.cpp checks this ray by ray, with every
// kernel). Interpolated batches then hand 16 of those rays at a time to plan(), which plans
// their lookups (the taps) as FieldQuery::Impl::planInterpolated does, and over unorm8-diameter
// maps to blend(), which sums the taps' weights (and normals) as blendInterpolated does, in
// AVX-512 or AVX2 lanes.
// The kernel itself is query_group_kernel.h.
#pragma once

#include <cstddef>
#include <cstdint>

#include "vff/bc4.h"
#include "vff/direction.h"
#include "vff/format.h"
#include "vff/query.h"

namespace vff::detail {

inline constexpr size_t kGroupRays = 64;
static_assert(sizeof(Ray) == 32 && offsetof(Ray, direction) == 12 && offsetof(Ray, tmin) == 24 &&
                  offsetof(Ray, tmax) == 28,
              "the kernels load a Ray as eight packed floats: origin, direction, tmin, tmax");

// What the kernel reads: plain tables owned by FieldQuery::Impl.
struct GroupTables {
  Vec3 center;
  float radius = 0;
  uint32_t octaN = 0;               // octa-hemi2 parameter n; 0: another scheme (every hit ray is redone)
  const float* unit4 = nullptr;     // 4 floats per map: the unit position x, y, z and 0
  // octaCandidateMasks(octaN) (fast_lookup.h), then 3 readable bytes (the AVX2 kernel reads the
  // masks 4 bytes at a time); null: all eight.
  const uint8_t* octaMasks = nullptr;
  // octaCornerRows(octaMasks, octaN) (fast_lookup.h): 32 rows, for octaN <= 32; else null. Lanes
  // whose cells all have clear bits score the four corners without reading octaMasks (AVX-512).
  const uint32_t* octaCornerRows = nullptr;
  DirectionScheme scheme = DirectionScheme::kInvalid;
  uint32_t m = 0;                   // map resolution
  bool bit1 = false;                // the distance encoding has no distances (rays from inside miss)
  float insideLo = 0;               // intra-object bias times the radius (QueryOptions::intraBias)
  bool offObject = false;           // RayOrigin::kOffObject: rays from inside look up forward from a t0 < 0
  float offTolerance = 0;           // section 7.4's tolerance near the origin (object units)
  float gridGuard = 0, texelGuard = 0;  // fast_lookup.h's gridGuard(octaN) and texelGuard(m)
  // The distance maps, to prefetch the texels while the group is being looked up (null: none).
  const uint8_t* const* maps = nullptr;
  DistanceEncoding encoding = DistanceEncoding::kInvalid;
  // The maps hold one byte per texel (kUnorm8Diameter, kUnorm8Chord) and m <= 4096 (so that
  // j m + i is exact in binary32): the kernel fills Group::t.
  bool byteTexels = false;
  // With byteTexels, where the maps lie back to back from maps[0], fewer than 2^31 bytes and at
  // least 4 in all: texels = maps[0], mapBytes = m * m (Group::t then counts from texels). Else null.
  const uint8_t* texels = nullptr;
  int32_t mapBytes = 0;
  // Also decode the hit flags (Group::hits), as FieldQuery::Impl::hitsAt does: kUnorm8Diameter
  // maps with byteTexels only, whose distance is code * distanceScale (code 255: a miss).
  bool decodeHits = false;
  float distanceScale = 0;  // FieldQuery::Impl::distanceStep: quantizationStep (encoding.h) of 2 R
  // The rays are in world space (Instance batches): each lane first goes to object space as
  // RigidTransform::toObjectPoint and toObjectVector take a ray, with the same binary32 operations.
  bool toObject = false;
  float objectRotation[3][3] = {};  // the transform's rotation (applied transposed)
  Vec3 objectShift;                 // its translation
  float objectInvScale = 1.0f;      // 1 / its scale
};

// The state of up to kGroupRays rays. Per ray r (bit r of the masks, entry r of the arrays): the
// sphere. Then, packed (entry p, for p < count): the rays that reach the sphere, in order, with
// their texels. Distances are along the unit direction, as in prepare(): a texel distance d
// gives t = (t0 +- d) / len (minus from inside).
struct Group {
  static constexpr size_t kSlack = 32;  // the kernels store whole vectors (up to 32 lanes) past `count`
  float t0[kGroupRays], lo[kGroupRays], hi[kGroupRays], len[kGroupRays];
  uint64_t inside = 0;   // the origin is inside the sphere (the lookup is reversed)
  uint64_t reached = 0;  // the ray reaches the sphere (all others miss)
  uint32_t count = 0;    // rays that reach the sphere
  uint32_t ray[kGroupRays + kSlack];  // their indices
  uint32_t k[kGroupRays + kSlack], i[kGroupRays + kSlack], j[kGroupRays + kSlack];  // their texels
  // With GroupTables::byteTexels, the texel's byte: j m + i in its map, or k m^2 + j m + i from
  // GroupTables::texels where that is set.
  int32_t t[kGroupRays + kSlack];
  // With GroupTables::decodeHits, the packed rays' t0, lo, hi and inside (a float mask), for
  // GroupKernel::decode.
  float pt0[kGroupRays + kSlack], plo[kGroupRays + kSlack], phi[kGroupRays + kSlack], pinside[kGroupRays + kSlack];
  uint64_t redo = 0;    // bit p: the caller must run the reference prepare() on packed ray p
  // GroupKernel::decode's answer, bit r: ray r hits within its range (hitsAt). Left unset for the
  // rays in `redo`, which the caller answers.
  uint64_t hits = 0;
  uint32_t looked = 0;  // packed rays whose texels are known (k, i, j, t, redo): all when == count
};
static_assert(kGroupRays <= 64, "the masks hold one bit per ray");

// The rays of consecutive groups that reach the sphere and wait for their nearest sample and
// texel, so that the kernel looks them up in full vectors whatever each group's count (AO rays:
// about a third of a group reaches the sphere). Entries are in group order; segment s says which
// packed rays of which group its entries are.
struct LookupQueue {
  // At most a vector's worth (32) left from earlier groups plus one group, and the vectors the
  // kernels store past the end.
  static constexpr size_t kCapacity = kGroupRays + 2 * Group::kSlack;
  static constexpr size_t kMaxSegments = 8;
  float eux[kCapacity], euy[kCapacity], euz[kCapacity];  // the entry point on the unit sphere
  float vx[kCapacity], vy[kCapacity], vz[kCapacity];     // the lookup direction
  uint32_t k[kCapacity], i[kCapacity], j[kCapacity];     // the answers, copied into the groups
  int32_t t[kCapacity];
  uint64_t redo[kCapacity / 64];
  uint32_t size = 0;
  struct Segment {
    Group* group;
    uint32_t first, p0, n;  // entries first .. first + n - 1 are packed rays p0 .. p0 + n - 1 of group
  } segment[kMaxSegments];
  uint32_t segments = 0;
};

// The plans of interpolated lookups (FieldQuery's kInterpolated), up to kPlanLanes rays at once,
// slot by slot: slot 0 is the ray's nearest sample, slot 1 + c its neighbour c (the table of
// PlanTables::neighbours). Bit c of mask[lane] says whether slot c of that ray is a tap (the
// sample has a kernel weight > 0, or is the nearest, and sees the lookup direction); only those
// slots are set. A tap's texel footprint is (ix, iy) .. (ix + 1, iy + 1) before clamping, with
// fractions fx, fy; base is the sample point's distance along the ray. FieldQuery::Impl
// blends the taps in slot order.
inline constexpr size_t kPlanLanes = 16;
inline constexpr size_t kPlanSlots = 1 + kQueryNeighbours;
struct PlanBlock {
  uint32_t mask[kPlanLanes];
  int32_t k[kPlanSlots][kPlanLanes], ix[kPlanSlots][kPlanLanes], iy[kPlanSlots][kPlanLanes];
  float fx[kPlanSlots][kPlanLanes], fy[kPlanSlots][kPlanLanes], weight[kPlanSlots][kPlanLanes],
      base[kPlanSlots][kPlanLanes];
};

// What GroupKernel::plan reads: plain tables owned by FieldQuery::Impl.
struct PlanTables {
  const float* unit4 = nullptr;          // as GroupTables::unit4
  const uint32_t* neighbours = nullptr;  // kQueryNeighbours per map; UINT32_MAX ends a list
  float kernelRadius2 = 0;               // the interpolation kernel's squared chord radius
  Vec3 center;
  float radius = 0;
  uint32_t m = 0;  // map resolution
  DirectionScheme scheme = DirectionScheme::kInvalid;
  // As BlendTables::texels and mapBytes (null: none): the plan requests each tap's two texel rows.
  const uint8_t* texels = nullptr;
  int32_t mapBytes = 0;
};

// The rays to plan, lane by lane (FieldQuery::Impl::Lookup's eu, v, w and k0, and the ray's
// origin); lanes with active[lane] == 0 get mask 0.
struct PlanRays {
  float eux[kPlanLanes], euy[kPlanLanes], euz[kPlanLanes];
  float vx[kPlanLanes], vy[kPlanLanes], vz[kPlanLanes];
  float wx[kPlanLanes], wy[kPlanLanes], wz[kPlanLanes];
  float ox[kPlanLanes], oy[kPlanLanes], oz[kPlanLanes];
  uint32_t k0[kPlanLanes];
  uint32_t active[kPlanLanes];
};

// What GroupKernel::blend reads: the distance maps back to back (GroupTables::texels),
// unorm8-diameter, and the normal maps (oct-snorm16) back to back, or none.
struct BlendTables {
  const uint8_t* texels = nullptr;
  int32_t mapBytes = 0;
  uint32_t m = 0;
  float distanceScale = 0;  // a code's distance: FieldQuery::Impl::distanceStep (quantizationStep)
  const uint8_t* normals = nullptr;  // null: no normal field
  int32_t normalMapBytes = 0;
};

// A block's rays, lane by lane (Lookup::lo and hi: the range of t along the unit direction).
// Only rays from outside the sphere are blended (a tap's t is base + its distance).
struct BlendRays {
  float lo[kPlanLanes], hi[kPlanLanes];
};

// The weight sums of a block's blends, lane by lane: FieldQuery::Impl's Blend without the weight
// of the hits before the range (which no answer reads); the normal sums only with normals.
struct BlendSums {
  float hit[kPlanLanes], miss[kPlanLanes], far[kPlanLanes], tSum[kPlanLanes];
  float nx[kPlanLanes], ny[kPlanLanes], nz[kPlanLanes];
};

namespace {  // (a copy per file: the AVX2 kernel's file must share no inline function with the rest)

// What the kernel fills beyond Group::t and the hit flags. When it decodes the hits, the caller
// needs a Group's per-ray t0, lo, hi, len and inside, and (texels set) its packed k, i and j, only
// for the rays it redoes, which prepare() fills: the kernel leaves them unset.
inline bool perRayState(const GroupTables& t) { return !t.decodeHits; }
inline bool packedIndices(const GroupTables& t) { return !(t.decodeHits && t.texels); }

// The bits of packed rays 0 .. count - 1 (count <= 64).
inline uint64_t packedBits(size_t count) { return count >= 64 ? ~uint64_t(0) : (uint64_t(1) << count) - 1; }

// The byte offset, within a distance map, of the byte that holds texel (i, j).
inline size_t texelByte(DistanceEncoding e, uint32_t m, uint32_t i, uint32_t j) {
  const size_t t = size_t(j) * m + i;
  switch (e) {
    case DistanceEncoding::kUnorm16Diameter: return 2 * t;
    case DistanceEncoding::kBit1: return t / 8;
    case DistanceEncoding::kBc4Diameter: return (size_t(j >> 2) * (m >> 2) + (i >> 2)) * kBc4BlockBytes;  // its block
    default: return t;
  }
}

}  // namespace

// True where the group kernel is implemented (x86-64). Elsewhere the caller uses prepare().
bool groupKernelAvailable() noexcept;
// The group kernel that runs: "avx512" (32 lanes in two AVX-512 vectors, where the CPU has
// AVX-512 F, DQ, VL and BW, and BMI2), "avx2" (32 lanes in four vectors, where it has AVX2),
// "sse2" (8) or "scalar" (none: prepare() per ray).
const char* groupKernelName() noexcept;

// For tests: force a kernel for the whole process. kAuto (the default) takes the widest the CPU
// has; kSse2, kAvx2 and kAvx512 that kernel where the CPU runs it (else the widest); kNone makes
// groupKernelAvailable() false.
enum class KernelChoice : uint8_t { kAuto = 0, kSse2 = 1, kNone = 2, kAvx2 = 3, kAvx512 = 4 };
void forceGroupKernel(KernelChoice choice) noexcept;
KernelChoice kernelOverride() noexcept;
// Whether this build and CPU run that kernel (kAuto, kSse2 and kNone: on x86-64, always).
bool groupKernelRuns(KernelChoice choice) noexcept;

// The entry points of one group kernel. A batch resolves the kernel once (groupKernel()) and
// calls it through this table for all of its groups.
struct GroupKernel {
  const char* name;  // as groupKernelName()
  // Fills g for rays[0, n), n <= kGroupRays: the sphere, and the packed rays that reach it, whose
  // lookups it appends to q (at most LookupQueue::kMaxSegments groups may wait there at once). A
  // group is looked up when g->looked == g->count (at once where the scheme is not octa-hemi2:
  // then every packed ray is in g->redo).
  void (*sphere)(const GroupTables& tables, const Ray* rays, size_t n, Group* g, LookupQueue* q) noexcept;
  // Looks up q's entries in full vectors (with flush: all of them), copies the answers into their
  // groups and requests the texels from memory.
  void (*lookup)(const GroupTables& tables, LookupQueue* q, bool flush) noexcept;
  // With tables.decodeHits, reads the texels of a looked-up group and fills g->hits (else sets it
  // to 0). Best called some time after its lookup (FieldQuery hands a group over only after the
  // lookups of the next group), so that the texels have arrived.
  void (*decode)(const GroupTables& tables, Group* g) noexcept;
  // The plans of rays' interpolated lookups (PlanBlock), as FieldQuery::Impl::planInterpolated
  // computes them one ray at a time, with the same binary32 operations in the same order (the
  // sample's frame from its position, as PositionSet::frame; concentric maps with atanUnit).
  // Null where the kernel has no planner (SSE2): the caller plans the rays one at a time.
  void (*plan)(const PlanTables& tables, const PlanRays& rays, PlanBlock* out) noexcept;
  // The weight sums of a block of plans (PlanBlock; lanes with mask 0 sum to zero), as
  // FieldQuery::Impl::blendInterpolated accumulates them one ray at a time: taps in slot order,
  // each tap's four texels in its order, with the same binary32 operations (normals decoded as
  // decodeNormal does). Null where the kernel has no blend (SSE2): the caller blends the rays
  // one at a time.
  void (*blend)(const BlendTables& tables, const PlanBlock& plans, const BlendRays& rays, BlendSums* out) noexcept;
};

// The group kernel that runs now (see forceGroupKernel), or null where none does
// (groupKernelAvailable() is false: the caller uses prepare() per ray).
const GroupKernel* groupKernel() noexcept;

}  // namespace vff::detail
