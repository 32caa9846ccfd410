#!/usr/bin/env bash
# Command 2: set up a fresh Debian 12 machine, build, and run the whole test suite:
#   1. every ctest case under AddressSanitizer + UndefinedBehaviorSanitizer with leak checking
#      (preset asan: one build of the library, the tools, the samples and every test), but the
#      SIGKILL cases and the peak-memory bounds;
#   2. those two in a Release build of the tools (preset release): a killed process runs no sanitizer
#      check, and the `limits` cases assert a peak resident memory that ASan's shadow would inflate;
#   3. a short, reproducible burst of every libFuzzer target (scripts/fuzz.sh: fixed seed and runs).
# Each stage prints its wall time. VFF_RELEASE_ONLY=1 runs every case in a Release build instead of
# stages 1 and 2 (quicker, no sanitizers).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh

jobs="$(nproc)"
start=$SECONDS

# A one-node Slurm cluster for the library.slurm cases (scripts/slurm-cluster.sh), stopped however
# this script ends; without it those cases are skipped with the reason.
slurm_dir="$(mktemp -d /tmp/vff-slurm.XXXXXX)"
trap 'bash scripts/slurm-cluster.sh stop "$slurm_dir" || true; rm -rf "$slurm_dir"' EXIT
if slurm_conf="$(bash scripts/slurm-cluster.sh start "$slurm_dir")"; then
  export VFF_TEST_SLURM_CONF="${slurm_conf#SLURM_CONF=}"
else
  echo "test: no Slurm cluster (see $slurm_dir/log): the library.slurm cases are skipped"
fi
stage() {
  echo "== $1 (at $((SECONDS - start)) s)"
}

if [[ ${VFF_RELEASE_ONLY:-0} == 1 ]]; then
  stage "Release build"
  cmake --preset release >/dev/null
  cmake --build --preset release -j "$jobs"
  stage "Tests (Release, every case)"
  ctest --preset release -j "$jobs"
else
  stage "AddressSanitizer + UndefinedBehaviorSanitizer build (everything)"
  cmake --preset asan >/dev/null
  cmake --build --preset asan -j "$jobs"
  stage "Tests (ASan + UBSan: every case but crash.sigkill.* and limits)"
  # The preset's environment (CMakePresets.json) turns on leak checking and halts on the first
  # UBSan report.
  ctest --preset asan -j "$jobs" -E '^crash\.sigkill\.' -LE '^limits$'

  stage "Release build (the tools the SIGKILL and limits cases run)"
  cmake --preset release >/dev/null
  cmake --build --preset release -j "$jobs" --target vff-bake vff-convert vff-compress vff-inspect \
    vff-procedural-mesh vff_limits_gen vff_peak_rss
  stage "Tests (Release: crash.sigkill.* and limits)"
  ctest --preset release -j "$jobs" -R '^crash\.sigkill\.|^limits\.'
fi

stage "libFuzzer burst (Clang, ASan + UBSan)"
bash scripts/fuzz.sh 5000
stage "Done"
