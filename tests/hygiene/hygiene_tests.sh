#!/usr/bin/env bash
# hygiene_tests.sh - properties of the built library that no unit test sees (label hygiene).
#
# Every function named test_* is one ctest case (tests/hygiene/CMakeLists.txt); environment:
#   NM           the toolchain's nm
#   VFF_OBJECTS  libvff's object files, separated by ':'
#   WORK         a scratch folder of this test.
set -euo pipefail
: "${NM:?}" "${VFF_OBJECTS:?}" "${WORK:?}"
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"

# The files compiled for an instruction set beyond the baseline (libvff/src/platform/cpu_features.h: the
# group kernel's query_group_avx2.cpp and query_group_avx512.cpp, the scene traversal's
# scene_bvh_avx512.cpp, the filter's filter_simd_ssse3.cpp) define no weak symbol: an inline or template function emitted there is
# code for that instruction set, and the linker may pick that copy for callers that run on any
# x86-64 CPU (the rule at the top of libvff/src/query/batch/query_group_kernel.h). A std::initializer_list in
# a range-for did so at -O0.
test_kernel_objects_define_no_weak_symbols() {
  local objects o kernels=0 weak
  IFS=':' read -ra objects <<< "$VFF_OBJECTS"
  for o in "${objects[@]}"; do
    case "$o" in
      *query_group_avx2.cpp.o | *query_group_avx512.cpp.o | *scene_bvh_avx512.cpp.o | *filter_simd_ssse3.cpp.o) ;;
      *) continue ;;
    esac
    kernels=$((kernels + 1))
    # (DW.ref.__gxx_personality_v0: a pointer to the C++ runtime's unwinding routine, not code.)
    weak=$("$NM" "$o" | awk 'NF >= 3 && $2 ~ /^[WVu]$/ && $3 != "DW.ref.__gxx_personality_v0" { print $3 }')
    [[ -z $weak ]] || fail "$o defines weak symbols, compiled for its instruction set: $weak"
  done
  # The build has these kernels wherever the compiler takes -mavx2 (libvff/CMakeLists.txt).
  ((kernels > 0)) || fail "no AVX2, AVX-512 or SSSE3 object among: $VFF_OBJECTS"
  echo "checked $kernels kernel objects"
}

run_test "$1"
