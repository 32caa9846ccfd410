#!/usr/bin/env bash
# source_tests.sh - rules the source tree keeps, checked on the files themselves (no build needed):
# files a newcomer can read in one sitting, and comments that give reasons, not measurements.
#
# Every function named test_* is one ctest case (tests/hygiene/CMakeLists.txt); environment:
#   VFF_SOURCE_DIR  the source tree
#   WORK            a scratch folder of this test.
# A failure lists every offending FILE:LINE (relative to the source tree), then fails.
set -euo pipefail
: "${VFF_SOURCE_DIR:?}" "${WORK:?}"
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
source "$here/../common/cli_harness.sh"

# ---- File length ---------------------------------------------------------------------------------
kMaxLines=700
# The folders and kinds of file the length rule covers.
kLengthFolders=(libvff tools gpu samples tests spec)
kLengthNames=(-name '*.cpp' -o -name '*.h' -o -name '*.glsl' -o -name '*.comp' -o -name '*.sh')
# Files allowed over kMaxLines: generated tables and test data only, never code someone edits by
# hand. Each entry is "PATH # why", PATH relative to the source tree; the test fails on an entry
# without a reason, on a file that is gone, and on one back under the limit (drop the entry then).
# (JSON vectors, fuzz inputs and other data are no source kind above, so they need no entry.)
kLongFileAllowList=(
)

# The allowed PATHs, one a line; fails on an entry without a reason.
allowed_long_files() {
  local entry path why
  for entry in "${kLongFileAllowList[@]}"; do
    path="${entry%%#*}"
    path="${path%"${path##*[![:space:]]}"}"
    why="${entry#*#}"
    [[ $entry == *#* && $why =~ [[:alpha:]] ]] || fail "allow-list entry without a reason: '$entry'"
    echo "$path"
  done
}

test_no_source_file_over_700_lines() {
  local allowed lines file over=0 checked=0
  allowed="$(allowed_long_files)"
  cd "$VFF_SOURCE_DIR"
  while IFS= read -r -d '' file; do
    file="${file#./}"
    checked=$((checked + 1))
    lines=$(wc -l <"$file")
    ((lines > kMaxLines)) || continue
    grep -qxF -e "$file" <<<"$allowed" && continue
    echo "$file:$((kMaxLines + 1)): $lines lines, over $kMaxLines: split it by concept (one small file per concept)" >&2
    over=$((over + 1))
  done < <(find "${kLengthFolders[@]}" -type f \( "${kLengthNames[@]}" \) -print0 | sort -z)
  ((checked > 0)) || fail "no source file found under $VFF_SOURCE_DIR"
  while IFS= read -r file; do
    [[ -n $file ]] || continue
    [[ -f $file ]] || { echo "$file: on the allow-list, but no such file" >&2; over=$((over + 1)); continue; }
    lines=$(wc -l <"$file")
    ((lines > kMaxLines)) ||
      { echo "$file:1: on the allow-list, but $lines lines: drop its entry" >&2; over=$((over + 1)); }
  done <<<"$allowed"
  ((over == 0)) || fail "$over file(s) over $kMaxLines lines (listed above)"
  echo "checked $checked files"
}

# ---- Performance figures in comments -------------------------------------------------------------
# A comment gives the reason for the code ("read once, the rays then take less of the cache"); a
# measurement ("1.05x", "400 Mrays/s", "3 ms") goes in the commit body, where it never goes stale.
kFigureFolders=(libvff gpu tools)
kFigureNames=(-name '*.cpp' -o -name '*.h' -o -name '*.glsl' -o -name '*.comp' -o -name 'CMakeLists.txt'
  -o -name '*.cmake' -o -name '*.sh')
# NAME|ERE, matched against the comment text of a line (comment_text.awk). Written so that sizes and
# offsets are no figure: "4x4 block", "64x64", "2x2 texels", "0x40" and "8 x 8" do not match.
kSpeedWords='\b(faster|slower|speed|speed-?ups?|quicker|throughput|bench|gains?|gained|beats?|ran|runs)\b'
kFigurePatterns=(
  # A decimal ratio: "1.05x", "0.6x", "1.0-1.05x".
  'ratio|(^|[^0-9A-Za-z_.])[0-9]+\.[0-9]+x([^0-9A-Za-z_]|$)'
  # A whole ratio next to a speed word: "10x faster", "bench: 3x" (not "within 2x").
  "whole ratio|(^|[^0-9A-Za-z_.])[1-9][0-9]*x([^0-9A-Za-z_]|\$).*($kSpeedWords)|($kSpeedWords).*(^|[^0-9A-Za-z_.])[1-9][0-9]*x([^0-9A-Za-z_]|\$)"
  # Rates: "Mrays/s", "GB/s", "MiB/s", "400 queries/s".
  'rate|(^|[^A-Za-z])[kMG]rays/s|(^|[^A-Za-z])[KMGT]i?B/s([^A-Za-z]|$)|[0-9] ?(rays|queries|lookups|maps|texels)/s([^A-Za-z]|$)'
  # Times: "3 ms", "12us", "took 2 s".
  'time|[0-9] ?(ns|us|µs|ms)([^A-Za-z]|$)|(took|takes|taking|ran in|runs in) (about |under |~)?[0-9.]+ ?(s|sec|seconds|minutes)([^A-Za-z]|$)'
  # Comparative figures: "3 times faster", "faster by 10%", "10% faster".
  "comparison|[0-9] times ($kSpeedWords)|($kSpeedWords) by [0-9]|[0-9] ?%.*($kSpeedWords|noise)|($kSpeedWords|noise).*[0-9] ?%"
  # The runs that produce such figures.
  'A/B run|(^|[^A-Za-z])A/B([^A-Za-z]|$)'
  'cycle count|[0-9] ?(cycles|clocks)([^A-Za-z]|$)'
)

test_no_performance_figure_in_comments() {
  local comments="$WORK/comments" entry name pattern found=0 files
  cd "$VFF_SOURCE_DIR"
  mapfile -d '' files < <(find "${kFigureFolders[@]}" -type f \( "${kFigureNames[@]}" \) -print0 | sort -z)
  ((${#files[@]} > 0)) || fail "no source file found under $VFF_SOURCE_DIR"
  awk -f "$here/comment_text.awk" "${files[@]}" >"$comments"
  [[ -s $comments ]] || fail "no comment found in ${#files[@]} files: comment_text.awk is broken"
  for entry in "${kFigurePatterns[@]}"; do
    name="${entry%%|*}"
    pattern="${entry#*|}"
    while IFS= read -r line; do
      echo "${line%%:*}:$(cut -d: -f2 <<<"$line"): ($name) ${line#*:*:}" >&2
      found=$((found + 1))
    done < <(grep -E -e "$pattern" "$comments" || true)
  done
  ((found == 0)) || fail "$found performance figure(s) in comments (listed above): keep the reason, move the figure to the commit body"
  echo "checked $(wc -l <"$comments") comment lines in ${#files[@]} files"
}

# The patterns above, on text that must and must not match (so that a loosened pattern shows here).
test_figure_patterns_flag_figures_only() {
  local entry pattern text hits
  local figures=("runs 1.05x faster" "AO 1.00-1.04x, within" "0.6x.)" "ran 10x faster" "at 400 Mrays/s"
    "XXH3 runs at > 10 GB/s" "16 MiB took 7 ms." "in 12us" "3 times faster" "faster by 10%"
    "in an in-process A/B" "about 40 cycles per ray" "took 2 s")
  local plain=("a 4x4 block" "64x64 maps" "2x2 texels" "the header @0x40" "no \"@0x..\" without" "8 x 8 groups"
    "every count is within 2x" "well under 1% of random rays" "vec3s" "the bench's ray sets" "queries/s of the GPU"
    "at a time: 32 lanes" "a 16x16 map, 3 maps per block")
  for text in "${figures[@]}" "${plain[@]}"; do
    hits=0
    for entry in "${kFigurePatterns[@]}"; do
      pattern="${entry#*|}"
      grep -qE -e "$pattern" <<<"$text" && hits=$((hits + 1))
    done
    echo "$hits pattern(s): $text"
    printf '%s\n' "${figures[@]}" | grep -qxF -e "$text" && { ((hits > 0)) || fail "no pattern flags: $text"; }
    printf '%s\n' "${plain[@]}" | grep -qxF -e "$text" && { ((hits == 0)) || fail "a pattern flags: $text"; }
  done
  # comment_text.awk: comments only, not code or string literals.
  printf '%s\n' 'int a = 1;  // one' 'const char* s = "http://x 3 ms";' '/* two' '   three */ int b;' \
    'x = 1; /* four */ y = "//";' >"$WORK/sample.cpp"
  printf '%s\n' '# five' 'set(A "#x")  # six' 'echo "$#"' >"$WORK/CMakeLists.txt"
  awk -f "$here/comment_text.awk" "$WORK/sample.cpp" "$WORK/CMakeLists.txt" | sed "s|^$WORK/||" >"$WORK/got"
  printf '%s\n' 'sample.cpp:1:  one' 'sample.cpp:3: two' 'sample.cpp:4:   three  ' 'sample.cpp:5: four  ' \
    'CMakeLists.txt:1: five' 'CMakeLists.txt:2: six' >"$WORK/want"
  diff "$WORK/want" "$WORK/got" >&2 || fail "comment_text.awk extracts other text than the comments"
}

run_test "$1"
