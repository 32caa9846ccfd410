// The group kernel (query_group_kernel.h) on 8 lanes: two vectors of four SSE2 lanes, which every
// x86-64 CPU has.
#include "query/batch/query_group.h"

#if defined(__SSE2__)
#include "simd/vfloat4_sse2.h"

#include "query/batch/query_group_kernel.h"

namespace vff::detail {
namespace {
inline uint64_t F4::hitsByRay(const Group& g, uint64_t packed) { return hitsByRayBits<F4>(g, packed); }
}  // namespace
}  // namespace vff::detail

namespace vff::detail {

void sphereGroupSse2(const GroupTables& tables, const Ray* rays, size_t n, Group* g, LookupQueue* q) noexcept {
  sphereGroupWith<Pair<F4>>(tables, rays, n, g, q);  // 8 lanes (query_group_kernel.h)
}

void lookupQueueSse2(const GroupTables& tables, LookupQueue* q, bool flush) noexcept {
  lookupQueueWith<Pair<F4>>(tables, q, flush);
}

void decodeGroupSse2(const GroupTables& tables, Group* g) noexcept { decodeGroupWith<Pair<F4>>(tables, g); }

}  // namespace vff::detail

#endif
