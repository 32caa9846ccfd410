// cpu_features.cpp - the run-time CPU check of cpu_features.h, compiled for the baseline.
#include "platform/cpu_features.h"

namespace vff::detail {

const CpuFeatures& cpuFeatures() noexcept {
  static const CpuFeatures f = [] {
    CpuFeatures r;
#if defined(__x86_64__) || defined(_M_X64)
    r.ssse3 = __builtin_cpu_supports("ssse3");
    r.avx2 = __builtin_cpu_supports("avx2");
    r.avx512 = __builtin_cpu_supports("avx512f") && __builtin_cpu_supports("avx512dq") &&
               __builtin_cpu_supports("avx512vl") && __builtin_cpu_supports("avx512bw") &&
               __builtin_cpu_supports("bmi2");
#endif
    return r;
  }();
  return f;
}

}  // namespace vff::detail
