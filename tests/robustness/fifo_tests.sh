#!/usr/bin/env bash
# fifo_tests.sh - every tool given a named pipe (mkfifo) where it reads a file.
#
# The rule (docs/robustness.md, "Inputs that are not regular files"): a field, a mesh, a level set,
# a part to merge or a library manifest must be a regular file; anything else (a FIFO, a folder, a device) is refused
# before it is read, exit 2, "PATH: ... io-open (1001): not a regular file". A FIFO opened for
# reading waits for a writer, so a tool that opened one the plain way would hang: every command here
# runs under `timeout`, and a hang fails as exit 124 instead of stalling the suite. vff-query's rays
# (-i PATH) are the one input read as a stream, as `cat` reads it: a FIFO there is answered.
#
# Every function named test_* is one ctest case (tests/robustness/CMakeLists.txt); `bash
# fifo_tests.sh test_NAME` runs one. The environment says where things are:
#   VFF_INSPECT VFF_QUERY VFF_CONVERT VFF_COMPRESS VFF_BAKE VFF_LIBRARY   the tools
#   FIELD   a valid .vff (a conformance vector)
#   WORK    a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_INSPECT:?}" "${VFF_QUERY:?}" "${VFF_CONVERT:?}" "${VFF_COMPRESS:?}" "${VFF_BAKE:?}" "${VFF_LIBRARY:?}" "${FIELD:?}" "${WORK:?}"

source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"

# Long enough for a loaded machine, short enough that a hang fails well inside ctest's limit.
LIMIT=20

# refused PROG PATH ARGS...: `PROG ARGS...` exits 2 at once, saying PATH is not a regular file,
# naming PATH once, and writes nothing to stdout nor any file into $WORK/outdir.
refused() {
  local prog=$1 path=$2
  shift 2
  mkdir -p "$WORK/outdir"
  run timeout "$LIMIT" "$@"
  [[ $RC -ne 124 ]] || { show; fail "$prog blocked on the FIFO $path"; }
  expect_rc 2
  expect_no_out
  expect_err "$prog: error: $path: io-open (1001): not a regular file"
  local names
  names=$(grep -o -F -e "$path" "$WORK/err" | wc -l)
  [[ $names -eq 1 ]] || { show; fail "the message names $path $names times, expected once"; }
  [[ -z $(ls -A "$WORK/outdir") ]] || fail "files left behind: $(ls -A "$WORK/outdir")"
}

test_inspect_refuses_fifo() {
  mkfifo "$WORK/field.vff"
  refused vff-inspect "$WORK/field.vff" "$VFF_INSPECT" "$WORK/field.vff"
  # --validate --format json reports the refusal on stdout too, as its one issue.
  run timeout "$LIMIT" "$VFF_INSPECT" "$WORK/field.vff" --validate --format json
  expect_rc 2
  expect_err "vff-inspect: error: $WORK/field.vff: io-open (1001): not a regular file"
  expect_out '"id": 1001'
  expect_out '"message": "'"$WORK"'/field.vff: not a regular file"'
}

test_inspect_help_says_so() {
  run "$VFF_INSPECT" --help
  expect_rc 0
  expect_out "a regular file (a named pipe or folder is refused, exit 2), or - (standard input, read whole)"
}

test_inspect_refuses_folder() {
  mkdir "$WORK/field.vff"
  refused vff-inspect "$WORK/field.vff" "$VFF_INSPECT" "$WORK/field.vff"
}

test_query_refuses_fifo_field() {
  mkfifo "$WORK/field.vff"
  refused vff-query "$WORK/field.vff" "$VFF_QUERY" "$WORK/field.vff" --ray 0 0 5 0 0 -1
  refused vff-query "$WORK/field.vff" "$VFF_QUERY" "$WORK/field.vff" --ray 0 0 5 0 0 -1 -o "$WORK/outdir/a.csv"
}

# Rays from a FIFO given by path are read as a stream (like `cat`, or `-i <(generator)`): the same
# answers as from a regular file.
test_query_reads_fifo_rays() {
  printf '0,0,5,0,0,-1\n5,0,0,-1,0,0\n0,0,5,0,0,1\n' >"$WORK/rays.csv"
  run timeout "$LIMIT" "$VFF_QUERY" "$FIELD" -i "$WORK/rays.csv"
  expect_rc 0
  cp "$WORK/out" "$WORK/expected"
  [[ $(wc -l <"$WORK/expected") -eq 4 ]] || { show; fail "expected a header and 3 answers"; }
  mkfifo "$WORK/rays.fifo"
  timeout "$LIMIT" cp "$WORK/rays.csv" "$WORK/rays.fifo" &
  local writer=$!
  run timeout "$LIMIT" "$VFF_QUERY" "$FIELD" -i "$WORK/rays.fifo"
  wait "$writer" || fail "the writer of the FIFO failed or was never read"
  expect_rc 0
  cmp -s "$WORK/out" "$WORK/expected" || { show; fail "the answers from the FIFO differ from the file's"; }
}

# --help says both: the field is a regular file, a named pipe of rays is read as a stream.
test_query_help_says_so() {
  run "$VFF_QUERY" --help
  expect_rc 0
  expect_out "the .vff field to query (a regular file)"
  expect_out "a named pipe is read as a stream"
}

test_convert_refuses_fifo() {
  mkfifo "$WORK/field.vff" "$WORK/field.exr" "$WORK/field.vdb"
  refused vff-convert "$WORK/field.vff" "$VFF_CONVERT" "$WORK/field.vff" "$WORK/outdir/o.exr"
  refused vff-convert "$WORK/field.exr" "$VFF_CONVERT" "$WORK/field.exr" "$WORK/outdir/o.vff"
  refused vff-convert "$WORK/field.vdb" "$VFF_CONVERT" "$WORK/field.vdb" "$WORK/outdir/o.vff"
}

test_compress_refuses_fifo() {
  mkfifo "$WORK/field.vff"
  refused vff-compress "$WORK/field.vff" "$VFF_COMPRESS" "$WORK/field.vff" "$WORK/outdir/o.vff"
  refused vff-compress "$WORK/field.vff" "$VFF_COMPRESS" --benchmark "$WORK/field.vff"
}

test_bake_refuses_fifo() {
  local ext
  for ext in obj ply stl off gltf glb vdb; do
    mkfifo "$WORK/mesh.$ext"
    refused vff-bake "$WORK/mesh.$ext" "$VFF_BAKE" "$WORK/mesh.$ext" -o "$WORK/outdir/o.vff" -m 4
  done
  refused vff-bake "$WORK/mesh.glb" "$VFF_BAKE" "$WORK/mesh.glb" --split mesh -o "$WORK/outdir/s.vffscene.json" -m 4
  mkfifo "$WORK/part.vff"
  refused vff-bake "$WORK/part.vff" "$VFF_BAKE" --merge "$WORK/part.vff" -o "$WORK/outdir/o.vff"
}

test_library_refuses_fifo_manifest() {
  mkfifo "$WORK/library.json"
  refused vff-library "$WORK/library.json" "$VFF_LIBRARY" bake "$WORK/library.json" --out "$WORK/outdir"
}

run_test "$1"
