// The group kernel's dispatch (query_group.h): AVX-512 or AVX2 where the CPU has it, SSE2 on
// every other x86-64 CPU, none elsewhere (the batches then call prepare() per ray).
#include "query/batch/query_group.h"

#include <atomic>

#include "platform/cpu_features.h"

namespace vff::detail {

namespace {
std::atomic<uint8_t> gOverride{0};
}  // namespace

void forceGroupKernel(KernelChoice choice) noexcept { gOverride.store(uint8_t(choice), std::memory_order_relaxed); }
KernelChoice kernelOverride() noexcept { return KernelChoice(gOverride.load(std::memory_order_relaxed)); }

#if defined(__x86_64__) || defined(_M_X64)

void sphereGroupSse2(const GroupTables& tables, const Ray* rays, size_t n, Group* g, LookupQueue* q) noexcept;
void lookupQueueSse2(const GroupTables& tables, LookupQueue* q, bool flush) noexcept;
void decodeGroupSse2(const GroupTables& tables, Group* g) noexcept;
#if defined(VFF_HAVE_AVX2_KERNEL)
void sphereGroupAvx2(const GroupTables& tables, const Ray* rays, size_t n, Group* g, LookupQueue* q) noexcept;
void lookupQueueAvx2(const GroupTables& tables, LookupQueue* q, bool flush) noexcept;
void decodeGroupAvx2(const GroupTables& tables, Group* g) noexcept;
void planGroupAvx2(const PlanTables& tables, const PlanRays& rays, PlanBlock* out) noexcept;
void blendGroupAvx2(const BlendTables& tables, const PlanBlock& plans, const BlendRays& rays, BlendSums* out) noexcept;
#endif
#if defined(VFF_HAVE_AVX512_KERNEL)
void sphereGroupAvx512(const GroupTables& tables, const Ray* rays, size_t n, Group* g, LookupQueue* q) noexcept;
void lookupQueueAvx512(const GroupTables& tables, LookupQueue* q, bool flush) noexcept;
void decodeGroupAvx512(const GroupTables& tables, Group* g) noexcept;
void planGroupAvx512(const PlanTables& tables, const PlanRays& rays, PlanBlock* out) noexcept;
void blendGroupAvx512(const BlendTables& tables, const PlanBlock& plans, const BlendRays& rays, BlendSums* out) noexcept;
#endif

namespace {

// (SSE2 batches plan and blend one ray at a time: planning four lanes at a time, and blending
// eight, did not beat the one-ray planner and blend on vff-experiments bench's rays; the AVX2 and
// AVX-512 kernels plan and blend in their lanes.)
constexpr GroupKernel kSse2{"sse2", sphereGroupSse2, lookupQueueSse2, decodeGroupSse2, nullptr, nullptr};
#if defined(VFF_HAVE_AVX2_KERNEL)
constexpr GroupKernel kAvx2{"avx2", sphereGroupAvx2, lookupQueueAvx2, decodeGroupAvx2, planGroupAvx2, blendGroupAvx2};
#endif
#if defined(VFF_HAVE_AVX512_KERNEL)
constexpr GroupKernel kAvx512{"avx512", sphereGroupAvx512, lookupQueueAvx512, decodeGroupAvx512,
                              planGroupAvx512, blendGroupAvx512};
#endif

// The kernels this CPU runs (decided once): null where it has not the instructions (or this
// build not the kernel).
struct Available {
  const GroupKernel* avx2 = nullptr;
  const GroupKernel* avx512 = nullptr;
};
const Available& available() noexcept {
  static const Available a = [] {
    Available r;
    [[maybe_unused]] const CpuFeatures& cpu = cpuFeatures();
#if defined(VFF_HAVE_AVX2_KERNEL)
    if (cpu.avx2) r.avx2 = &kAvx2;
#endif
#if defined(VFF_HAVE_AVX512_KERNEL)
    if (cpu.avx512) r.avx512 = &kAvx512;
#endif
    return r;
  }();
  return a;
}

// The kernel that runs now: the override where this CPU runs it, else the widest.
const GroupKernel& activeKernel() noexcept {
  const Available& a = available();
  switch (kernelOverride()) {
    case KernelChoice::kSse2: return kSse2;
    case KernelChoice::kAvx2:
      if (a.avx2) return *a.avx2;
      break;
    default: break;
  }
  if (a.avx512) return *a.avx512;
  if (a.avx2) return *a.avx2;
  return kSse2;
}

}  // namespace

bool groupKernelAvailable() noexcept { return kernelOverride() != KernelChoice::kNone; }

bool groupKernelRuns(KernelChoice choice) noexcept {
  switch (choice) {
    case KernelChoice::kAvx2: return available().avx2 != nullptr;
    case KernelChoice::kAvx512: return available().avx512 != nullptr;
    default: return true;
  }
}

const char* groupKernelName() noexcept { return groupKernelAvailable() ? activeKernel().name : "scalar"; }

const GroupKernel* groupKernel() noexcept { return groupKernelAvailable() ? &activeKernel() : nullptr; }

#else

bool groupKernelAvailable() noexcept { return false; }
bool groupKernelRuns(KernelChoice choice) noexcept { return choice == KernelChoice::kNone; }
const char* groupKernelName() noexcept { return "scalar"; }
const GroupKernel* groupKernel() noexcept { return nullptr; }

#endif

}  // namespace vff::detail
