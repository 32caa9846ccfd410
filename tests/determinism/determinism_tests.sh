#!/usr/bin/env bash
# determinism_tests.sh - a repeated conversion gives the same bytes: vff-convert run twice on the
# same input, and with 1 and 2 threads (-j), writes byte-identical files (--to vff: repacks with
# zstd, whose blocks the writer compresses on several threads; --to exr: OpenEXR's compression
# threads; EXR back to .vff). The bake's own thread-count determinism is tested in tests/bake
# (bake.cli.same_bytes_any_thread_count).
#
# Every function named test_* is one ctest case (tests/determinism/CMakeLists.txt); environment:
#   VFF_BAKE VFF_CONVERT MESHGEN  the executables; WORK a scratch folder of this test.
set -euo pipefail
: "${VFF_BAKE:?}" "${VFF_CONVERT:?}" "${MESHGEN:?}" "${WORK:?}"
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"

# A baked field with normals: 170 maps of 32x32 in several blocks per plane.
input() {
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/in.vff" -n 6 -m 32 --normals -q || fail "baking the input"
}

# same_output OUT_EXT ARGS...: runs `vff-convert ARGS... OUT` as run a (-j 1), b (-j 1 again) and
# c (-j 2) and checks that the three outputs are byte-identical. ARGS hold the input; OUT is added.
same_output() {
  local ext=$1
  shift
  local r
  for r in a:1 b:1 c:2; do
    run "$VFF_CONVERT" "$@" "$WORK/${r%:*}.$ext" -j "${r#*:}" -q
    expect_rc 0
  done
  cmp "$WORK/a.$ext" "$WORK/b.$ext" || fail "two runs of 'vff-convert $*' with -j 1 differ"
  cmp "$WORK/a.$ext" "$WORK/c.$ext" || fail "'vff-convert $*' with -j 1 and -j 2 differ"
  echo "vff-convert $* -> $(stat -c %s "$WORK/a.$ext") bytes, identical over 3 runs (-j 1, -j 1, -j 2)"
}

test_repack_zstd_twice() {
  input
  same_output vff "$WORK/in.vff" --to vff --codec zstd --zstd-level 3 --maps-per-block 8
}

test_repack_layout_twice() {
  input
  same_output vff "$WORK/in.vff" --to vff --max-texture-size 256 --gutter 1
}

test_to_exr_twice() {
  input
  same_output exr "$WORK/in.vff" --to exr
}

test_to_exr_half_twice() {
  input
  same_output exr "$WORK/in.vff" --to exr --half
}

test_from_exr_twice() {
  input
  "$VFF_CONVERT" "$WORK/in.vff" --to exr "$WORK/in.exr" -q || fail "converting the input to EXR"
  same_output vff "$WORK/in.exr" --to vff
  cmp "$WORK/a.vff" "$WORK/in.vff" || fail "the EXR round trip is not the baked file"
}

# ---- Runner --------------------------------------------------------------------------------------
[[ $# -eq 1 && $1 == test_* ]] || { echo "usage: $0 test_NAME" >&2; exit 2; }
run_test "$1"
