// The group kernel's dispatch (query_group.h): AVX-512 or AVX2 where the CPU has it, SSE2 on
// every other x86-64 CPU, none elsewhere (the batches then call prepare() per ray).
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
#if defined(VFF_HAVE_AVX512_KERNEL)
void prepareGroupAvx512(const GroupTables& tables, const Ray* rays, size_t n, Group* g) noexcept;
void decodeGroupAvx512(const GroupTables& tables, Group* g) noexcept;
#endif

namespace {

struct Kernel {
  const char* name;
  void (*prepare)(const GroupTables&, const Ray*, size_t, Group*) noexcept;
  void (*decode)(const GroupTables&, Group*) noexcept;
};

constexpr Kernel kSse2{"sse2", prepareGroupSse2, decodeGroupSse2};
#if defined(VFF_HAVE_AVX2_KERNEL)
constexpr Kernel kAvx2{"avx2", prepareGroupAvx2, decodeGroupAvx2};
#endif
#if defined(VFF_HAVE_AVX512_KERNEL)
constexpr Kernel kAvx512{"avx512", prepareGroupAvx512, decodeGroupAvx512};
#endif

// The kernels this CPU runs (decided once): null where it has not the instructions (or this
// build not the kernel).
struct Available {
  const Kernel* avx2 = nullptr;
  const Kernel* avx512 = nullptr;
};
const Available& available() noexcept {
  static const Available a = [] {
    Available r;
#if defined(VFF_HAVE_AVX2_KERNEL)
    if (__builtin_cpu_supports("avx2")) r.avx2 = &kAvx2;
#endif
#if defined(VFF_HAVE_AVX512_KERNEL)
    // (libgcc's and compiler-rt's checks include the OS's support for the AVX-512 registers.)
    if (__builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
        __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw"))
      r.avx512 = &kAvx512;
#endif
    return r;
  }();
  return a;
}

// The kernel prepareGroup runs now: the override where this CPU runs it, else the widest.
const Kernel& activeKernel() noexcept {
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

void prepareGroup(const GroupTables& tables, const Ray* rays, size_t n, Group* g) noexcept {
  activeKernel().prepare(tables, rays, n, g);
}

void decodeGroup(const GroupTables& tables, Group* g) noexcept { activeKernel().decode(tables, g); }

#else

bool groupKernelAvailable() noexcept { return false; }
bool groupKernelRuns(KernelChoice choice) noexcept { return choice == KernelChoice::kNone; }
const char* groupKernelName() noexcept { return "scalar"; }
void prepareGroup(const GroupTables&, const Ray*, size_t, Group*) noexcept {}
void decodeGroup(const GroupTables&, Group*) noexcept {}

#endif

}  // namespace vff::detail
