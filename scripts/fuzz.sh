#!/usr/bin/env bash
# Builds the libFuzzer targets (preset `fuzz`: Clang, ASan + UBSan; tests/fuzz/) and runs each one
# for a fixed number of executions with a fixed seed, starting from its seeds. A crash, leak,
# timeout or out-of-memory input is copied to tests/fuzz/regressions/TARGET/ (ctest replays that
# folder in every build from then on) and makes the script fail.
#   scripts/fuzz.sh [RUNS]     executions per target (default 20000)
#   VFF_FUZZ_SECONDS=N         run for N seconds per target instead (for longer local sessions)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
runs="${1:-20000}"
cmake --preset fuzz >/dev/null
cmake --build --preset fuzz -j "$(nproc)" --target vff_fuzz_open_validate vff_fuzz_decode vff_fuzz_mesh

work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
status=0
for t in open_validate decode mesh; do
  case "$t" in
    open_validate) seeds=(spec/conformance/valid spec/conformance/invalid); dict=tests/fuzz/vff.dict ;;
    decode) seeds=(spec/conformance/valid); dict=tests/fuzz/vff.dict ;;
    mesh) seeds=(tests/fuzz/seeds/mesh); dict=tests/fuzz/mesh.dict ;;
  esac
  mkdir -p "$work/$t/corpus" "$work/$t/artifacts"
  limit=(-runs="$runs")
  if [ -n "${VFF_FUZZ_SECONDS:-}" ]; then limit=(-max_total_time="$VFF_FUZZ_SECONDS"); fi
  echo "== fuzz $t (${limit[*]})"
  if ! ASAN_OPTIONS=detect_leaks=1 "build-fuzz/tests/fuzz/vff_fuzz_$t" "${limit[@]}" -seed=1 -dict="$dict" \
      -max_len=131072 -timeout=10 -rss_limit_mb=2048 -print_final_stats=1 \
      -artifact_prefix="$work/$t/artifacts/" "$work/$t/corpus" "${seeds[@]}" >"$work/$t/log" 2>&1; then
    status=1
  fi
  grep -E "stat::number_of_executed_units|stat::new_units_added|stat::peak_rss_mb" "$work/$t/log" || true
  for a in "$work/$t/artifacts/"*; do
    [ -e "$a" ] || continue
    dest="tests/fuzz/regressions/$t/$(basename "$a")"
    cp "$a" "$dest"
    echo "FOUND: $dest"
    status=1
  done
  if [ "$status" -ne 0 ]; then tail -40 "$work/$t/log"; fi
done
exit "$status"
