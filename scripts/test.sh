#!/usr/bin/env bash
# Command 2: set up a fresh Debian 12 machine, build, and run the whole test suite:
#   1. every ctest case of the Release build (unit, conformance, robustness, cli, bake, install ...);
#   2. the library suites (unit, conformance, robustness, query) again under AddressSanitizer + UBSan;
#   3. a short, reproducible burst of every libFuzzer target (scripts/fuzz.sh: fixed seed and runs).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh

jobs="$(nproc)"
echo "== Release build"
cmake --preset release >/dev/null
cmake --build --preset release -j "$jobs"
echo "== Tests (Release)"
ctest --preset release -j "$jobs"

echo "== AddressSanitizer + UndefinedBehaviorSanitizer"
cmake --preset asan >/dev/null
cmake --build --preset asan -j "$jobs" --target vff_unit_tests vff_conformance_tests vff_robustness_tests vff_query_tests
ctest --preset asan -j "$jobs" -L 'unit|conformance|robustness|query'

echo "== libFuzzer burst (Clang, ASan + UBSan)"
bash scripts/fuzz.sh 5000
