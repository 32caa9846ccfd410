// The group kernel (query_group_kernel.h) on 32 lanes: four vectors of eight AVX2 lanes. This file alone is compiled with
// -mavx2 (not -mfma: no operation may be fused); query_group.cpp calls it only on a CPU with AVX2.
// It constructs no object of a type declared outside it, so that no inline function compiled here
// can stand in for the baseline copy used elsewhere.
#include "query/batch/query_group.h"

#if defined(__AVX2__)
#include "simd/vfloat8_avx2.h"

#include "query/batch/query_group_kernel.h"

namespace vff::detail {
namespace {
inline uint64_t F8::hitsByRay(const Group& g, uint64_t packed) { return hitsByRayBits<F8>(g, packed); }
}  // namespace
}  // namespace vff::detail

namespace vff::detail {

void sphereGroupAvx2(const GroupTables& tables, const Ray* rays, size_t n, Group* g, LookupQueue* q) noexcept {
  sphereGroupWith<Pair<Pair<F8>>>(tables, rays, n, g, q);  // 32 lanes (query_group_kernel.h)
}

void lookupQueueAvx2(const GroupTables& tables, LookupQueue* q, bool flush) noexcept {
  lookupQueueWith<Pair<Pair<F8>>>(tables, q, flush);
}

void decodeGroupAvx2(const GroupTables& tables, Group* g) noexcept { decodeGroupWith<Pair<Pair<F8>>>(tables, g); }

void planGroupAvx2(const PlanTables& tables, const PlanRays& rays, PlanBlock* out) noexcept {
  planWith<F8>(tables, rays, out);
}

void blendGroupAvx2(const BlendTables& tables, const PlanBlock& plans, const BlendRays& rays, BlendSums* out) noexcept {
  blendWith<F8>(tables, plans, rays, out);
}

}  // namespace vff::detail

#endif
