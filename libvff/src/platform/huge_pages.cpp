#include "platform/huge_pages.h"

#include <cstdint>

#if defined(__linux__)
#include <sys/mman.h>
#ifndef MADV_COLLAPSE
#define MADV_COLLAPSE 25  // (Linux 6.1 and later; glibc 2.36's headers lack it)
#endif
#endif

namespace vff::detail {

size_t adviseHugePages(const void* p, size_t n) noexcept {
#if defined(__linux__)
  constexpr uintptr_t kHuge = uintptr_t(2) << 20;
  const uintptr_t begin = (reinterpret_cast<uintptr_t>(p) + kHuge - 1) & ~(kHuge - 1);
  const uintptr_t end = (reinterpret_cast<uintptr_t>(p) + n) & ~(kHuge - 1);
  if (n == 0 || end <= begin) return 0;
  if (madvise(reinterpret_cast<void*>(begin), end - begin, MADV_COLLAPSE) != 0) return 0;
  return size_t(end - begin);
#else
  (void)p;
  (void)n;
  return 0;
#endif
}

}  // namespace vff::detail
