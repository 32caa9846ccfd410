#!/usr/bin/env bash
# Command 2: set up a fresh Debian 12 machine, build, and run the whole test suite:
#   1. every ctest case of the Release build (unit, conformance, robustness, cli, bake, limits ...);
#   2. the library suites (unit, conformance, robustness, query) again under AddressSanitizer + UBSan
#      with leak checking (preset asan); VFF_ASAN_ALL=1 runs every case but the SIGKILL tests there;
#   3. a short, reproducible burst of every libFuzzer target (scripts/fuzz.sh: fixed seed and runs).
# Each stage prints its wall time.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh

jobs="$(nproc)"
start=$SECONDS
stage() {
  echo "== $1 (at $((SECONDS - start)) s)"
}
stage "Release build"
cmake --preset release >/dev/null
cmake --build --preset release -j "$jobs"
stage "Tests (Release)"
ctest --preset release -j "$jobs"

cmake --preset asan >/dev/null
if [[ ${VFF_ASAN_ALL:-0} == 1 ]]; then
  # The whole suite under the sanitizers (a full second build of every tool and test).
  stage "AddressSanitizer + UndefinedBehaviorSanitizer build (everything)"
  cmake --build --preset asan -j "$jobs"
  stage "Tests (ASan + UBSan, everything)"
  # Every case but crash.sigkill.*: those kill the tools with SIGKILL, and a killed process runs no
  # sanitizer check (leaks are checked at exit), so under ASan they would only repeat what the
  # Release run checks, one at a time and at about three times the cost (100 s). The preset's
  # environment (CMakePresets.json) turns on leak checking and halts on the first UBSan report.
  ctest --preset asan -j "$jobs" -E '^crash\.sigkill\.'
else
  # By default the library's suites: every decoder, the validator, the writer and the query, on
  # the conformance vectors, hostile files and baked fields (the part that reads untrusted bytes).
  stage "AddressSanitizer + UndefinedBehaviorSanitizer build (library suites)"
  cmake --build --preset asan -j "$jobs" --target vff_unit_tests vff_conformance_tests vff_robustness_tests vff_query_tests
  stage "Tests (ASan + UBSan: unit, conformance, robustness, query)"
  ctest --preset asan -j "$jobs" -L 'unit|conformance|robustness|query'
fi

stage "libFuzzer burst (Clang, ASan + UBSan)"
bash scripts/fuzz.sh 5000
stage "Done"
