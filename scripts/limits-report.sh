#!/usr/bin/env bash
# Prints a limits table (docs/robustness.md describes the limits): every hostile input of
# tests/limits (inputs that claim huge sizes: gen.cpp) with each tool that reads it, the tool's exit
# code, its peak resident memory (ru_maxrss, measured by vff_peak_rss) and its time, and a summary of
# the conformance suite's invalid vectors. It runs the test functions of tests/limits/limits_tests.sh
# and lists those that fail.
#   scripts/limits-report.sh [BUILD_DIR]   (default: build, configured as Release when missing)
#   VFF_LIMITS_ALL=1 ...                   also runs the known issues the tests skip (GiBs, minutes)
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
build="${1:-build}"
if [[ ! -f $build/CMakeCache.txt ]]; then
  cmake -S . -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cmake --build "$build" -j "$(nproc)" --target vff_limits_gen vff_peak_rss vff-inspect vff-convert vff-bake \
  >"$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
export GEN="$build/tests/limits/vff_limits_gen" PEAK="$build/tests/limits/vff_peak_rss"
export VFF_INSPECT="$build/tools/vff-inspect/vff-inspect" VFF_CONVERT="$build/tools/vff-convert/vff-convert"
export VFF_BAKE="$build/tools/vff-bake/vff-bake" CONFORMANCE="$root/spec/conformance"
export VFF_LIMITS_PEAK_MIB="${VFF_LIMITS_PEAK_MIB:-64}" VFF_LIMITS_REPORT="$work/rows"
: >"$VFF_LIMITS_REPORT"
failed=()
for t in $(grep -o -E '^test_[a-z0-9_]+' tests/limits/limits_tests.sh); do
  if ! WORK="$work/$t" bash tests/limits/limits_tests.sh "$t" >"$work/$t.log" 2>&1; then failed+=("$t"); fi
done

echo "Peak memory bound asserted by the tests: $VFF_LIMITS_PEAK_MIB MiB. Each cell: exit code, peak resident memory, seconds."
echo
# One row per input, one column per command (rows of limits_tests.sh: | input | tool args | rc | MiB | s | diagnostic |).
table() {
  awk -F' *\\| *' -v cols="$1" '
    BEGIN { n = split(cols, col, ";") }
    { split($3, w, " "); key = w[1]; for (i = 3; i <= length(w); i++) if (w[i] ~ /^--(validate|format|to)$/) {
        key = key " " w[i]; if (w[i] != "--validate") key = key " " w[i + 1] }
      if (!($2 in seen)) { seen[$2] = 1; order[++rows] = $2; diag[$2] = $7 }
      cell[$2, key] = $4 ", " $5 " MiB, " $6 " s" }
    END {
      printf "| input |"; for (c = 1; c <= n; c++) printf " %s |", col[c]; printf " diagnostic |\n"
      printf "| --- |"; for (c = 1; c <= n; c++) printf " --- |"; printf " --- |\n"
      for (r = 1; r <= rows; r++) {
        printf "| %s |", order[r]
        for (c = 1; c <= n; c++) printf " %s |", ((order[r], col[c]) in cell) ? cell[order[r], col[c]] : "not run"
        printf " %s |\n", diag[order[r]] } }'
}
grep -F '| vff-' "$VFF_LIMITS_REPORT" | grep -v -F ' invalid/' | grep -v -F 'vff-bake' |
  table "vff-inspect --validate;vff-inspect --format json;vff-convert --to vff;vff-convert --to exr"
echo
grep -F 'vff-bake' "$VFF_LIMITS_REPORT" | table "vff-bake"
echo
echo "Conformance invalid vectors (spec/conformance/invalid), vff-inspect FILE --validate:"
echo
echo "| vectors | exit codes | diagnostic names its ID | peak MiB (max) | seconds (max) |"
echo "| ---: | --- | --- | ---: | ---: |"
grep -F ' invalid/' "$VFF_LIMITS_REPORT" | awk -F' *\\| *' '
  { n++; codes[$4]++; if ($5 > peak) peak = $5; if ($6 > secs) secs = $6
    split($3, p, "/"); if (index($7, "(" p[2] ")") > 0) named++ }
  END { c = ""; for (k in codes) c = c (c == "" ? "" : ", ") k " (" codes[k] ")"
        printf "| %d | %s | %d of %d | %d | %.3f |\n", n, c, named, n, peak, secs }'
if grep -q -h "KNOWN ISSUE" "$work"/*.log; then
  echo
  grep -h "KNOWN ISSUE" "$work"/*.log | sort -u | sed 's/^/- /'
fi
if [[ ${#failed[@]} -gt 0 ]]; then
  echo
  echo "FAILED: ${failed[*]} (logs: rerun one with WORK=/tmp/x bash tests/limits/limits_tests.sh TEST)"
  exit 1
fi
