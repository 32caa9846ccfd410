#!/usr/bin/env bash
# source_tests.sh - rules the source tree keeps, checked on the files themselves (no build needed):
# files and functions a newcomer can read in one sitting, folders that use only the floors below
# them, and comments that give reasons, not measurements.
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

# ---- Function length -----------------------------------------------------------------------------
# A function a reader takes in at once: over kMaxFunctionLines, split it by concept. The lengths are
# universal-ctags' (its end: field), for every C++ function of kFunctionFolders and every GLSL function
# (read as C) of their *.glsl and *.comp files.
kMaxFunctionLines=150
kFunctionFolders=(libvff bake sdf gpu tools python samples tests spec)

# The universal-ctags program (Debian: universal-ctags), or nothing (status 1): Exuberant Ctags
# has no end: field.
universal_ctags() {
  local c
  for c in ctags-universal universal-ctags ctags; do
    if command -v "$c" >/dev/null 2>&1 && "$c" --version 2>/dev/null | grep -q 'Universal Ctags'; then
      echo "$c"
      return 0
    fi
  done
  return 1
}

# "LENGTH FILE:LINE NAME" for every function under the kFunctionFolders of folder $2 (ctags $1), by
# file and line.
function_lengths() (
  local ctags=$1 folders=() f glsl
  cd "$2"
  for f in "${kFunctionFolders[@]}"; do [[ -d $f ]] && folders+=("$f"); done
  ((${#folders[@]} > 0)) || return 0
  mapfile -d '' glsl < <(find "${folders[@]}" -type f \( -name '*.glsl' -o -name '*.comp' \) -print0 | sort -z)
  {
    "$ctags" -R --sort=no --languages=C++ --kinds-C++=f --fields=+ne --excmd=number -o - "${folders[@]}"
    ((${#glsl[@]} == 0)) ||
      "$ctags" --sort=no --language-force=C --kinds-C=f --fields=+ne --excmd=number -o - "${glsl[@]}"
  } | awk -F'\t' -v OFS='\t' '{
    line = ""; end = ""
    for (i = 4; i <= NF; ++i) {
      if ($i ~ /^line:/) line = substr($i, 6)
      else if ($i ~ /^end:/) end = substr($i, 5)
    }
    if (line != "" && end != "") print $2, line, end - line + 1, $1
  }' | LC_ALL=C sort -t$'\t' -k1,1 -k2,2n | awk -F'\t' '{ print $3, $1 ":" $2, $4 }'
)

# The functions of folder $2 over kMaxFunctionLines, one "FILE:LINE: ..." line each (ctags $1).
long_functions() {
  function_lengths "$1" "$2" | awk -v max="$kMaxFunctionLines" '$1 > max {
    print $2 ": " $3 " is " $1 " lines, over " max ": split it by concept (one function per step)"
  }'
}

test_functions_are_at_most_150_lines() {
  local ctags lengths long
  ctags="$(universal_ctags)" || { echo "SKIP: no universal-ctags (Debian package universal-ctags, scripts/setup.sh)"; return 0; }
  lengths="$(function_lengths "$ctags" "$VFF_SOURCE_DIR")"
  [[ -n $lengths ]] || fail "ctags ($ctags) found no function under $VFF_SOURCE_DIR"
  long="$(long_functions "$ctags" "$VFF_SOURCE_DIR")"
  [[ -z $long ]] || { echo "$long" >&2; fail "$(wc -l <<<"$long") function(s) over $kMaxFunctionLines lines (listed above)"; }
  echo "checked $(wc -l <<<"$lengths") functions; the longest: $(sort -n <<<"$lengths" | tail -1)"
}

# The length check on a tree made here: a C++ function and a GLSL one of kMaxFunctionLines + 1
# lines are listed, with their file and first line; those of kMaxFunctionLines lines are not.
test_function_length_check_flags_long_functions() {
  local ctags tree="$WORK/tree"
  ctags="$(universal_ctags)" || { echo "SKIP: no universal-ctags (Debian package universal-ctags, scripts/setup.sh)"; return 0; }
  mkdir -p "$tree/libvff/src" "$tree/gpu/glsl" "$tree/tests/unit"
  # A function of N lines ($2): its header, N - 2 statements, its closing brace.
  function_of() {
    local i
    echo "$1 {"
    for ((i = 2; i < $2; ++i)); do echo "  x = x + $i;"; done
    echo "}"
  }
  { echo "namespace vff {"; function_of "int longOne(int x)" $((kMaxFunctionLines + 1))
    function_of "int fitsExactly(int x)" "$kMaxFunctionLines"; echo "}  // namespace vff"; } >"$tree/libvff/src/a.cpp"
  { echo "float shortOne(float x) { return x; }"; function_of "float longGlsl(float x)" $((kMaxFunctionLines + 1)); } \
    >"$tree/gpu/glsl/b.glsl"
  function_of "void fitsToo(int x)" "$kMaxFunctionLines" >"$tree/tests/unit/c.cpp"
  long_functions "$ctags" "$tree" >"$WORK/got"
  local why="lines, over $kMaxFunctionLines: split it by concept (one function per step)"
  printf '%s\n' "gpu/glsl/b.glsl:2: longGlsl is $((kMaxFunctionLines + 1)) $why" \
    "libvff/src/a.cpp:2: longOne is $((kMaxFunctionLines + 1)) $why" >"$WORK/want"
  diff "$WORK/want" "$WORK/got" >&2 || fail "the length check lists other functions than the long ones"
  [[ $(function_lengths "$ctags" "$tree" | wc -l) -eq 5 ]] || fail "ctags found other than the 5 functions written"
}

# ---- Include graph -------------------------------------------------------------------------------
# The folders are floors (CONTRIBUTING.md): no #include or CMake source path from a lower floor to a
# higher one, no tool compiling another tools/ folder's sources, no product target compiling a test's
# file. include_graph.py has the floors, the include roots and the rules.
include_graph() { python3 "$here/include_graph.py" "$1"; }

test_include_graph_follows_the_floors() {
  command -v python3 >/dev/null 2>&1 || { echo "SKIP: no python3 (scripts/setup.sh)"; return 0; }
  include_graph "$VFF_SOURCE_DIR" >"$WORK/out" || { cat "$WORK/out" >&2; fail "arrows against the floors (listed above)"; }
  cat "$WORK/out"
}

# The graph check on a tree made here: each kind of broken arrow is listed by file and line (the old
# offenders among them: samples/ and gpu/ including tests/ files), the allowed ones are not.
test_include_graph_check_flags_violations() {
  command -v python3 >/dev/null 2>&1 || { echo "SKIP: no python3 (scripts/setup.sh)"; return 0; }
  local t="$WORK/tree"
  mkdir -p "$t/libvff/include/vff" "$t/libvff/src" "$t/bake/include/vff/bake" "$t/gpu/harness" "$t/gpu/loader/src" \
    "$t/tools/common" "$t/tools/vff-a" "$t/tools/vff-b" "$t/samples/x" "$t/tests/common" "$t/tests/unit"
  touch "$t/libvff/include/vff/query.h" "$t/bake/include/vff/bake/baker.h" "$t/gpu/harness/egl_context.h" \
    "$t/tools/common/cli.h" "$t/tools/common/cli.cpp" "$t/tools/vff-b/b.h" "$t/tools/vff-b/b.cpp" \
    "$t/tests/common/rng.h" "$t/tests/common/fixture.cpp" "$t/samples/x/x.h"
  # Each file: its broken arrows' lines in the comment. Allowed: downwards, the same floor, a tool
  # using the tools' shared libraries' headers, tests using anything, headers outside the tree.
  printf '#include "vff/query.h"\n#include "../../tests/common/rng.h"\n#include "vff/bake/baker.h"\n#include <vector>\n' \
    >"$t/libvff/src/a.cpp"  # 2, 3: up
  printf '#include "vff/query.h"\n#include "egl_context.h"\n' >"$t/gpu/loader/src/l.cpp"  # 2: up (gpu/harness)
  printf '#include "vff/bake/baker.h"\n#include "egl_context.h"\n#include "../../tests/common/rng.h"\n' \
    >"$t/gpu/harness/h.cpp"  # 3: up
  printf '#include "cli.h"\n#include "../vff-b/b.h"\n#include "nanovdb/PNanoVDB.h"\n' \
    >"$t/tools/vff-a/main.cpp"  # 2: another tool's
  printf '#include "../../tests/common/rng.h"\n#include "common/rng.h"\n#include "vff/query.h"\n' \
    >"$t/samples/x/x.cpp"  # 1, 2: up
  printf '#include "vff/bake/baker.h"\n#include "cli.h"\n#include "../../samples/x/x.h"\n#include "common/rng.h"\n' \
    >"$t/tests/unit/t.cpp"
  printf 'add_executable(vff-a main.cpp\n  ../vff-b/b.cpp ${PROJECT_SOURCE_DIR}/tools/common/cli.cpp)\n' \
    >"$t/tools/vff-a/CMakeLists.txt"  # 2: another tool's source, a shared library's source
  printf 'add_library(x STATIC x.cpp ${PROJECT_SOURCE_DIR}/tests/common/fixture.cpp)  # ../y.cpp\n' \
    >"$t/samples/x/CMakeLists.txt"  # 1: up
  printf 'add_executable(t t.cpp ../../tools/vff-b/b.cpp ${PROJECT_SOURCE_DIR}/tools/common/cli.cpp)\n' \
    >"$t/tests/unit/CMakeLists.txt"
  printf 'add_library(y ${PROJECT_SOURCE_DIR}/tests/common/fixture.cpp)\nadd_subdirectory(tests)\n' \
    >"$t/CMakeLists.txt"  # 1: a test's file in a product
  include_graph "$t" >"$WORK/got" && { cat "$WORK/got" >&2; fail "the graph check passes a tree with broken arrows"; }
  grep -v '^checked ' "$WORK/got" | sed -E 's/^([^:]*:[0-9]+): .*/\1/' | LC_ALL=C sort >"$WORK/places"
  printf '%s\n' CMakeLists.txt:1 gpu/harness/h.cpp:3 gpu/loader/src/l.cpp:2 libvff/src/a.cpp:2 libvff/src/a.cpp:3 \
    samples/x/CMakeLists.txt:1 samples/x/x.cpp:1 samples/x/x.cpp:2 tools/vff-a/CMakeLists.txt:2 \
    tools/vff-a/CMakeLists.txt:2 tools/vff-a/main.cpp:2 >"$WORK/want"
  diff "$WORK/want" "$WORK/places" >&2 || { cat "$WORK/got" >&2; fail "the graph check lists other arrows than the broken ones"; }
  grep -qx 'checked 23 arrows in 20 files' "$WORK/got" || { cat "$WORK/got" >&2; fail "the graph check saw other arrows or files"; }
  cat "$WORK/got"
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
