#!/usr/bin/env bash
# benchmarks_tests.sh - benchmarks/run.sh writes a results file that benchmarks/report.py reads back,
# and the tables of README.md and benchmarks/README.md are the ones the committed results files give.
#
# Every function named test_* is one ctest case (tests/benchmarks/CMakeLists.txt); environment:
#   VFF_SOURCE_DIR, VFF_BUILD_DIR  the source and build folders; PYTHON  python3;
#   MESHGEN  vff-procedural-mesh;  WORK  a scratch folder of this test.
set -euo pipefail
: "${VFF_SOURCE_DIR:?}" "${VFF_BUILD_DIR:?}" "${PYTHON:?}" "${MESHGEN:?}" "${WORK:?}"
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"
report="$VFF_SOURCE_DIR/benchmarks/report.py"

test_quick_run_writes_a_results_file() {
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null
  run bash "$VFF_SOURCE_DIR/benchmarks/run.sh" --quick --build "$VFF_BUILD_DIR" --mesh "$WORK/knot.obj" \
    --out "$WORK/r.md"
  expect_rc 0
  [[ -s $WORK/r.md && ! -e $WORK/r.md.tmp ]] || fail "no results file, or its temporary left behind"
  cpu=$("$PYTHON" "$report" cpu)
  grep -q -F "# vff benchmarks: $cpu, $(date -u +%Y-%m-%d)" "$WORK/r.md" || fail "the heading names another CPU or date"
  for h in "### Bake speed" "### Query speed" "### Accuracy against exact Embree casts" "### Compression" \
           "### Field against a signed distance field at equal memory"; do
    grep -q -F "$h" "$WORK/r.md" || fail "results file lacks '$h'"
  done
  # The query table gives each ray set's share of the memory floor, a percentage.
  for set in ao aimed; do
    grep -q -E "^\| $set \| [0-9.,]+ \| [0-9.,]+ \| [0-9.]+x \| [0-9.,]+ \| [0-9]+% \|" "$WORK/r.md" \
      || fail "no query row with a share of the floor for the $set rays"
  done
  # The GPU bench ran (a table naming the renderer) or the file says why not.
  grep -q -E "^### GPU query \(|^Not run: " "$WORK/r.md" || fail "the results file says nothing of the GPU bench"
  # Through Vulkan, both kernels (from the GLSL and from the generated HLSL), where a Vulkan device
  # answers and spirv-cross is installed.
  if grep -q -F "### GPU query (" "$WORK/r.md" && command -v vulkaninfo >/dev/null && vulkaninfo --summary >/dev/null 2>&1 &&
     command -v spirv-cross >/dev/null; then
    for h in "### GPU query through Vulkan (" "### GPU query through Vulkan, kernel from the generated HLSL ("; do
      grep -q -F "$h" "$WORK/r.md" || fail "results file lacks '$h'"
    done
    [[ $(grep -c -E "^\| (nearest occluded|interpolated visibility) \| 2\^[0-9]+ \| [0-9.,]+ \| [0-9.,]+ \| [0-9]+ \|$" "$WORK/r.md") -ge 4 ]] ||
      fail "fewer than two rows in each Vulkan table"
  fi
  # The WebGPU query ran (both queries, the adapter named) or the file says why not.
  if grep -q -F "### GPU query through WebGPU (" "$WORK/r.md"; then
    for q in "nearest occluded" "interpolated visibility"; do
      grep -q -E "^\| $q \| 2\^[0-9]+ \| [0-9.,]+ \| 0\.[0-9]{4} \|$" "$WORK/r.md" || fail "no WebGPU row '$q'"
    done
  else
    grep -A2 -E "^### webgpu$" "$WORK/r.md" | grep -q "^Not run: " || fail "the results file says nothing of the WebGPU step"
  fi
  # The Python module's step ran (its table, each path against the C++ batch) or the file says why not.
  if grep -q -F "### Python and vff-query against the C++ batch" "$WORK/r.md"; then
    for path in "C++ batch" "vff-query, .npy in and out, end to end" "Python FieldQuery.intersect, numpy in and out"; do
      grep -q -E "^\| ${path//+/\\+}[^|]* \| [0-9.,]+ \| [0-9.]+ \|$" "$WORK/r.md" || fail "no Python table row '$path'"
    done
  else
    grep -q -E "^### python$" "$WORK/r.md" && grep -q "^Not run: the Python module is not built" "$WORK/r.md" ||
      fail "the results file says nothing of the Python step"
  fi
  # No machine path: the commands are shown relative to the build folder.
  ! grep -q -F "$VFF_BUILD_DIR" "$WORK/r.md" || fail "the results file names the build folder"
  ! grep -q -F "$WORK" "$WORK/r.md" || fail "the results file names the scratch folder"
  # The distance-field comparison: the three meshes, both ray sets, a wrong-answer share for each.
  for m in knot box bowl; do for set in ao aimed; do
    grep -q -E "^\| $m\.obj \| [0-9.]+ \| $set \| .* \| [0-9.]+% / [0-9.]+% \| (field|SDF), (field|SDF|tie) \|$" "$WORK/r.md" \
      || fail "no distance-field row for $m, $set"
  done; done
  run "$PYTHON" "$report" check "$WORK/r.md"
  expect_rc 0
  expect_out "bake, query, accuracy-ao, accuracy-intra-ao, accuracy-shadows, accuracy-reflections, scene, triangles, compression, sdf"
}

# --only runs one step, and the results file says it is a reduced run; check asks for that step only.
test_only_runs_one_step() {
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null
  run bash "$VFF_SOURCE_DIR/benchmarks/run.sh" --quick --only sdf --build "$VFF_BUILD_DIR" --mesh "$WORK/knot.obj" \
    --out "$WORK/s.md"
  expect_rc 0
  grep -q -F -- "--only sdf (a reduced run: those steps alone)" "$WORK/s.md" || fail "the results file does not say it is reduced"
  ! grep -q -F "### Bake speed" "$WORK/s.md" || fail "--only sdf ran the bake"
  run "$PYTHON" "$report" check "$WORK/s.md"
  expect_rc 0
  expect_out ": sdf"
  run bash "$VFF_SOURCE_DIR/benchmarks/run.sh" --only nosuch --build "$VFF_BUILD_DIR" --mesh "$WORK/knot.obj"
  expect_rc 1
}

test_report_rejects_an_output_that_does_not_parse() {
  printf '# vff benchmarks: Some CPU, 2026-01-01\n\n### query\n\n`vff-experiments bench`\n\n```text\nno table\n```\n' \
    >"$WORK/bad.md"
  run "$PYTHON" "$report" check "$WORK/bad.md"
  expect_rc 3
  expect_err "bad.md, query: vff-experiments bench output lacks its header line"
  printf 'no heading\n' >"$WORK/none.md"
  run "$PYTHON" "$report" check "$WORK/none.md"
  expect_rc 3
  expect_err "none.md: no '# vff benchmarks: CPU, DATE' heading"
}

test_run_refuses_a_missing_mesh() {
  run bash "$VFF_SOURCE_DIR/benchmarks/run.sh" --quick --build "$VFF_BUILD_DIR" --mesh "$WORK/nothere.obj" \
    --out "$WORK/r.md"
  expect_rc 2
  expect_err "nothere.obj: cannot read the mesh"
  [[ ! -e $WORK/r.md ]] || fail "a results file was written"
}

# Every figure in README.md and benchmarks/README.md comes from a committed results file: README's
# headline table and the full tables are exactly what report.py makes of benchmarks/results/, and a
# changed figure in either file fails the check, naming that file.
test_readme_tables_match_the_results_files() {
  local f other
  run "$PYTHON" "$report" readme --check "$VFF_SOURCE_DIR/README.md" "$VFF_SOURCE_DIR/benchmarks/README.md"
  expect_rc 0
  for f in README.md benchmarks/README.md; do
    mkdir -p "$WORK/copy/benchmarks"
    cp "$VFF_SOURCE_DIR/README.md" "$WORK/copy/README.md"
    cp "$VFF_SOURCE_DIR/benchmarks/README.md" "$WORK/copy/benchmarks/README.md"
    sed -i '/^<!-- benchmarks:begin/,/^<!-- benchmarks:end/ s/| \([0-9]\+\)\.\([0-9]\+\)x |/| 9\1.\2x |/' "$WORK/copy/$f"
    cmp -s "$VFF_SOURCE_DIR/$f" "$WORK/copy/$f" && fail "the edit of a ratio in $f changed nothing"
    run "$PYTHON" "$report" readme --check "$WORK/copy/README.md" "$WORK/copy/benchmarks/README.md"
    expect_rc 1
    expect_err "$WORK/copy/$f: its "
    expect_err " benchmarks/results/"
    other=README.md; [[ $f == README.md ]] && other=benchmarks/README.md
    ! grep -q -F "$WORK/copy/$other: its " "$WORK/err" || { show; fail "the check names $other, whose tables are unchanged"; }
  done
}

# README.md is a user's manual of at most 12 KiB: the full tables live in benchmarks/README.md,
# details in docs/.
test_readme_is_at_most_12288_bytes() {
  local size
  size=$(wc -c <"$VFF_SOURCE_DIR/README.md")
  echo "README.md: $size bytes"
  ((size <= 12288)) || fail "README.md is $size bytes, over 12288: move details to docs/ or benchmarks/README.md"
}

run_test "$1"
