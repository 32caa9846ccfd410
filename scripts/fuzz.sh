#!/usr/bin/env bash
# Builds the libFuzzer targets (preset `fuzz`: Clang, ASan + UBSan; tests/fuzz/) and runs each one
# for a fixed number of executions with a fixed seed, starting from its seeds. A crash, leak,
# timeout or out-of-memory input is copied to tests/fuzz/regressions/TARGET/ (ctest replays that
# folder in every build from then on) and makes the script fail.
#   scripts/fuzz.sh [RUNS]     executions per target (default 20000)
#   VFF_FUZZ_SECONDS=N         run for N seconds per target instead (for longer local sessions)
#   VFF_FUZZ_TARGETS="a b"     only these targets (default: all of them)
#   VFF_FUZZ_JS=N              then the JavaScript decoder against libvff (tests/fuzz/js/differential.mjs)
#                              on the conformance vectors, N mutants of each, and the corpora the
#                              open_validate and decode runs produced (needs node and web/node_modules)
#   VFF_FUZZ_KEEP=DIR          keep each target's corpus and log in DIR/TARGET/ (else a temporary folder)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
runs="${1:-20000}"
all=(open_validate decode scene query_input mesh manifest merge)
read -r -a targets <<<"${VFF_FUZZ_TARGETS:-${all[*]}}"
cmake --preset fuzz >/dev/null
binaries=()
for t in "${targets[@]}"; do binaries+=("vff_fuzz_$t"); done
if [ -n "${VFF_FUZZ_JS:-}" ]; then binaries+=(vff_fuzz_first_error); fi
cmake --build --preset fuzz -j "$(nproc)" --target "${binaries[@]}"

if [ -n "${VFF_FUZZ_KEEP:-}" ]; then
  work="$VFF_FUZZ_KEEP"
  mkdir -p "$work"
else
  work="$(mktemp -d)"
  trap 'rm -rf "$work"' EXIT
fi
status=0
for t in "${targets[@]}"; do
  case "$t" in
    open_validate) seeds=(spec/conformance/valid spec/conformance/invalid); dict=tests/fuzz/vff.dict ;;
    decode) seeds=(spec/conformance/valid); dict=tests/fuzz/vff.dict ;;
    mesh) seeds=(tests/fuzz/seeds/mesh); dict=tests/fuzz/mesh.dict ;;
    scene) seeds=(tests/fuzz/seeds/scene); dict=tests/fuzz/scene.dict ;;
    query_input) seeds=(tests/fuzz/seeds/query_input); dict=tests/fuzz/query_input.dict ;;
    manifest) seeds=(tests/fuzz/seeds/manifest); dict=tests/fuzz/manifest.dict ;;
    merge) seeds=(tests/fuzz/seeds/merge); dict=tests/fuzz/vff.dict ;;
    *) echo "unknown fuzz target $t" >&2; exit 1 ;;
  esac
  # The spec's vectors of the readers, where they exist, seed them too.
  if [ "$t" = scene ] && [ -d spec/conformance/scene ]; then seeds+=(spec/conformance/scene); fi
  if [ "$t" = manifest ] && [ -d spec/conformance/library ]; then seeds+=(spec/conformance/library); fi
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

if [ -n "${VFF_FUZZ_JS:-}" ]; then
  echo "== JavaScript decoder against libvff ($VFF_FUZZ_JS mutants per vector)"
  corpora=()
  for t in open_validate decode; do [ -d "$work/$t/corpus" ] && corpora+=("$work/$t/corpus"); done
  if ! command -v node >/dev/null || [ ! -d web/node_modules/hash-wasm ]; then
    echo "SKIP: needs node and web/node_modules (scripts/setup.sh)"
  elif ! ASAN_OPTIONS=detect_leaks=0 node tests/fuzz/js/differential.mjs --helper build-fuzz/tests/fuzz/vff_fuzz_first_error \
      --mutants "$VFF_FUZZ_JS" --seed 1 spec/conformance/valid spec/conformance/invalid "${corpora[@]}"; then
    status=1
  fi
fi
exit "$status"
