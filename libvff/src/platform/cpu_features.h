// cpu_features.h - what this CPU runs (private): the one run-time check of the instruction sets
// that libvff's ISA-specific files are compiled for.
//
// libvff selects ISA code one way: each file of code for an instruction set beyond the build's
// baseline is compiled alone with that set's flags (libvff/CMakeLists.txt: query_group_avx2.cpp,
// query_group_avx512.cpp, scene_bvh_avx512.cpp, filter_simd_ssse3.cpp), and its callers reach it
// through a pointer chosen by these flags, so that none of its code runs on a CPU without the set.
#pragma once

namespace vff::detail {

struct CpuFeatures {
  bool ssse3 = false;   // filter_simd_ssse3.cpp
  bool avx2 = false;    // query_group_avx2.cpp
  // query_group_avx512.cpp, scene_bvh_avx512.cpp: AVX-512 F, DQ, VL and BW, and BMI2
  bool avx512 = false;
};

// Checked once (and including the OS's support for the registers: libgcc's and compiler-rt's
// checks do); all false where the CPU is not x86-64.
const CpuFeatures& cpuFeatures() noexcept;

}  // namespace vff::detail
