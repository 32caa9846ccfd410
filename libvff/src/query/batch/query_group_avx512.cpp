// The group kernel (query_group_kernel.h) on 32 lanes: two vectors of sixteen AVX-512 lanes. This
// file alone is compiled with -mavx512f -mavx512dq -mavx512vl -mavx512bw -mbmi2 (not -mfma: no
// operation may be fused); query_group.cpp calls it only on a CPU (and OS) with those. Its 32
// vector registers hold what the AVX2 kernel spills to the stack. It constructs no object of a type declared outside it, so that
// no inline function compiled here can stand in for the baseline copy used elsewhere.
#include "query/batch/query_group.h"

#if defined(__AVX512F__) && defined(__AVX512DQ__) && defined(__AVX512VL__) && defined(__AVX512BW__) && defined(__BMI2__)
#include "simd/vfloat16_avx512.h"

#include "query/batch/query_group_kernel.h"

namespace vff::detail {

void sphereGroupAvx512(const GroupTables& tables, const Ray* rays, size_t n, Group* g, LookupQueue* q) noexcept {
  sphereGroupWith<Pair<F16>>(tables, rays, n, g, q);  // 32 lanes (query_group_kernel.h)
}

void lookupQueueAvx512(const GroupTables& tables, LookupQueue* q, bool flush) noexcept {
  lookupQueueWith<Pair<F16>>(tables, q, flush);
}

void decodeGroupAvx512(const GroupTables& tables, Group* g) noexcept { decodeGroupWith<Pair<F16>>(tables, g); }

void planGroupAvx512(const PlanTables& tables, const PlanRays& rays, PlanBlock* out) noexcept {
  planWith<F16>(tables, rays, out);
}

void blendGroupAvx512(const BlendTables& tables, const PlanBlock& plans, const BlendRays& rays, BlendSums* out) noexcept {
  blendWith<F16>(tables, plans, rays, out);
}

}  // namespace vff::detail

#endif
