// The group kernel's dispatch (query_group.h): AVX2 where the CPU has it, SSE2 on every other
// x86-64 CPU, none elsewhere (the batches then call prepare() per ray).
#include "query_group.h"

#include <atomic>

namespace vff::detail {

namespace {
std::atomic<uint8_t> gOverride{0};
}  // namespace

void forceGroupKernel(KernelChoice choice) noexcept { gOverride.store(uint8_t(choice), std::memory_order_relaxed); }
KernelChoice kernelOverride() noexcept { return KernelChoice(gOverride.load(std::memory_order_relaxed)); }

#if defined(__x86_64__) || defined(_M_X64)

void prepareGroupSse2(const GroupTables& tables, const Ray* rays, size_t n, Group* g) noexcept;
void decodeGroupSse2(const GroupTables& tables, Group* g) noexcept;
#if defined(VFF_HAVE_AVX2_KERNEL)
void prepareGroupAvx2(const GroupTables& tables, const Ray* rays, size_t n, Group* g) noexcept;
void decodeGroupAvx2(const GroupTables& tables, Group* g) noexcept;
#endif

namespace {

using Kernel = void (*)(const GroupTables&, const Ray*, size_t, Group*) noexcept;

// The kernel prepareGroup runs now: the override, else the widest this CPU runs (decided once).
Kernel activeKernel() noexcept {
  static const Kernel widest = [] {
#if defined(VFF_HAVE_AVX2_KERNEL)
    if (__builtin_cpu_supports("avx2")) return prepareGroupAvx2;
#endif
    return prepareGroupSse2;
  }();
  return kernelOverride() == KernelChoice::kSse2 ? prepareGroupSse2 : widest;
}

}  // namespace

bool groupKernelAvailable() noexcept { return kernelOverride() != KernelChoice::kNone; }

const char* groupKernelName() noexcept {
  if (!groupKernelAvailable()) return "scalar";
  return activeKernel() == prepareGroupSse2 ? "sse2" : "avx2";
}

void prepareGroup(const GroupTables& tables, const Ray* rays, size_t n, Group* g) noexcept { activeKernel()(tables, rays, n, g); }

void decodeGroup(const GroupTables& tables, Group* g) noexcept {
#if defined(VFF_HAVE_AVX2_KERNEL)
  if (activeKernel() == prepareGroupAvx2) return decodeGroupAvx2(tables, g);
#endif
  decodeGroupSse2(tables, g);
}

#else

bool groupKernelAvailable() noexcept { return false; }
const char* groupKernelName() noexcept { return "scalar"; }
void prepareGroup(const GroupTables&, const Ray*, size_t, Group*) noexcept {}
void decodeGroup(const GroupTables&, Group*) noexcept {}

#endif

}  // namespace vff::detail
