#!/usr/bin/env bash
# vff-bake command-line behaviour: exit codes, messages naming the file, no output left behind on
# failure, byte-identical output whatever the thread count. Usage: cli_bake.sh BAKE INSPECT MESHGEN CASE
set -uo pipefail
bake="$1"; inspect="$2"; meshgen="$3"; case="$4"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
fail() { echo "FAIL: $*"; exit 1; }
# expect CODE CMD...: runs CMD, checks its exit code, keeps stderr in err.txt
expect() {
  local want="$1"; shift
  "$@" >out.txt 2>err.txt
  local got=$?
  [ "$got" -eq "$want" ] || { cat err.txt; fail "'$*' exited $got, expected $want"; }
}
"$meshgen" torus-knot knot.obj || fail "mesh generator"

case "$case" in
  bakes_and_validates)
    expect 0 "$bake" knot.obj -o knot.vff -n 3 -m 16 -q
    expect 0 "$inspect" knot.vff --validate
    ;;
  same_bytes_any_thread_count)
    for t in 1 2 8; do expect 0 "$bake" knot.obj -o "k$t.vff" -n 4 -m 16 --normals -j "$t" -q; done
    cmp k1.vff k2.vff || fail "1 vs 2 threads differ"
    cmp k1.vff k8.vff || fail "1 vs 8 threads differ"
    ;;
  json_summary)
    expect 0 "$bake" knot.obj -o k.vff -n 2 -m 8 --json
    grep -q '"maps": 26' out.txt || { cat out.txt; fail "json summary lacks the map count"; }
    grep -q '"hitRatio"' out.txt || fail "json summary lacks hitRatio"
    ;;
  metadata_follows_spec)
    expect 0 "$bake" knot.obj -o k.vff -n 1 -m 8 -q
    expect 0 "$inspect" k.vff --format json
    grep -Eq '"xxh3": "[0-9a-f]{16}"' out.txt || { grep xxh3 out.txt; fail "vff.source.xxh3 is not 16 lowercase hex digits"; }
    grep -q '"name": "knot.obj"' out.txt || fail "vff.source.name is not the file name"
    grep -q '"vff.generator": "vff-bake"' out.txt || fail "vff.generator missing"
    ;;
  missing_mesh_is_io_error)
    expect 2 "$bake" nothere.obj -o x.vff
    grep -q "nothere.obj" err.txt || fail "message does not name the file"
    [ ! -e x.vff ] || fail "output left behind"
    ;;
  unknown_extension_is_unsupported)
    echo "1 2 3" > mesh.xyz
    expect 5 "$bake" mesh.xyz -o x.vff
    grep -q "mesh.xyz" err.txt || fail "message does not name the file"
    [ ! -e x.vff ] || fail "output left behind"
    ;;
  bad_meshes_are_invalid_input)
    : > empty.obj
    printf 'v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n' > nan.obj
    printf 'v 0 0 0\nv 1 0 0\nv 2 0 0\nf 1 2 3\n' > flat.obj
    printf 'garbage\x00\x01\x02' > junk.glb
    for m in empty.obj nan.obj flat.obj junk.glb; do
      expect 3 "$bake" "$m" -o x.vff
      grep -q "$m" err.txt || { cat err.txt; fail "message does not name $m"; }
      [ ! -e x.vff ] || fail "output left behind for $m"
    done
    ;;
  absurd_parameters_are_usage_errors)
    expect 1 "$bake" knot.obj -o x.vff -n 0
    expect 1 "$bake" knot.obj -o x.vff -m 0
    expect 1 "$bake" knot.obj -o x.vff --encoding bit1 -m 12
    expect 1 "$bake" knot.obj -o x.vff --center 0 0 0
    expect 1 "$bake" knot.obj -o x.vff --max-texture-size 64 --max-layers 2
    expect 1 "$bake" knot.obj
    [ ! -e x.vff ] || fail "output left behind"
    ;;
  unwritable_output_keeps_old_file)
    echo old > keep.vff
    expect 2 "$bake" knot.obj -o no/such/dir/x.vff -n 1 -m 8 -q
    grep -q "x.vff" err.txt || fail "message does not name the output"
    chmod 0555 . 2>/dev/null
    if [ "$(id -u)" -ne 0 ]; then
      expect 2 "$bake" knot.obj -o keep.vff -n 1 -m 8 -q
      grep -q old keep.vff || fail "old file changed"
    fi
    chmod 0755 .
    [ -z "$(ls -A | grep '\.tmp-')" ] || fail "temporary file left behind"
    ;;
  benchmark_prints_ratio)
    expect 0 "$bake" knot.obj --benchmark -n 2 -m 16 --repeat 1
    grep -q "ratio" out.txt || { cat out.txt; fail "no ratio printed"; }
    grep -q "embree raw" out.txt || fail "no baseline printed"
    ;;
  *) fail "unknown case $case" ;;
esac
echo "PASS: $case"
