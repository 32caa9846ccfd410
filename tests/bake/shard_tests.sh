#!/usr/bin/env bash
# shard_tests.sh - vff-bake --map-range and --merge (spec/partial.md): a field baked as ranges of
# maps, on any thread counts, and merged in any order is the whole bake byte for byte; partial
# results are valid files that say they are partial; every refusal of --merge has its exit code,
# names the file and the problem, and leaves no output.
#
# Every function named test_* is one ctest case bake.shard.NAME (tests/bake/CMakeLists.txt):
# `bash shard_tests.sh test_NAME` runs one. Environment:
#   VFF_BAKE     the vff-bake executable
#   VFF_INSPECT  the vff-inspect executable
#   MESHGEN      the vff-procedural-mesh executable
#   VFF_QUERY    the vff-query executable (a partial result answers no rays)
#   EDIT         vff_shard_edit: a copy of a file with one META value changed (shard_edit.cpp)
#   MESHES       the shared meshes' folder (test_shared_mesh skips without it)
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_BAKE:?}" "${VFF_INSPECT:?}" "${MESHGEN:?}" "${EDIT:?}" "${VFF_QUERY:?}" "${WORK:?}"

here="$(dirname "${BASH_SOURCE[0]}")"
source "$here/../common/cli_harness.sh"
bake() { run "$VFF_BAKE" "$@"; }
knot() { "$MESHGEN" torus-knot "$WORK/knot.obj" || fail "mesh generator"; }
# octa-hemi2 n 4: 82 maps.
small=(-n 4 -m 16 -q)

# shards MESH NAME "RANGE..." "OPTIONS...": bakes MESH whole into NAME.vff and as the ranges (each
# with the next -j of 1 2 3) into NAME.partK.vff, merges the parts in reverse order and compares the
# bytes.
shards() {
  local mesh=$1 name=$2 ranges=$3 opts=$4 k=0 parts=()
  # shellcheck disable=SC2086
  bake "$mesh" -o "$WORK/$name.vff" $opts -j 2
  expect_rc 0
  for r in $ranges; do
    # shellcheck disable=SC2086
    bake "$mesh" -o "$WORK/$name.part$k.vff" $opts --map-range "$r" -j $((k % 3 + 1))
    expect_rc 0
    parts=("$WORK/$name.part$k.vff" "${parts[@]}")
    k=$((k + 1))
  done
  bake --merge "${parts[@]}" -o "$WORK/$name.merged.vff" -q
  expect_rc 0
  cmp "$WORK/$name.vff" "$WORK/$name.merged.vff" || fail "$name ($opts, ranges $ranges): merged bytes differ"
}

# ---- Merged bytes are the whole bake's ---------------------------------------------------------------
test_two_ranges_stored() {
  knot
  shards "$WORK/knot.obj" a "0:41 41:82" "${small[*]}"
}

test_three_uneven_ranges_zstd_shuffled() {
  knot
  shards "$WORK/knot.obj" b "0:1 1:70 70:82" "${small[*]} --codec zstd --zstd-level 3"
  # and in a shuffled order, with a range of one map in the middle
  for r in 0:40 40:41 41:82; do
    bake "$WORK/knot.obj" -o "$WORK/c$r.vff" "${small[@]}" --codec zstd --zstd-level 3 --map-range "$r" -j 1
    expect_rc 0
  done
  bake --merge "$WORK/c40:41.vff" "$WORK/c41:82.vff" "$WORK/c0:40.vff" -o "$WORK/c.vff" -j 3
  expect_rc 0
  cmp "$WORK/b.vff" "$WORK/c.vff" || fail "shuffled parts merge to other bytes"
}

test_bc4_with_normals() {
  knot
  shards "$WORK/knot.obj" d "0:30 30:31 31:82" "${small[*]} --encoding bc4-diameter --normals --codec zstd"
}

test_unorm8_with_normals_and_small_blocks() {
  knot
  # blocks of 8 maps that the ranges cut through, 3D layout with a gutter
  shards "$WORK/knot.obj" e "0:5 5:61 61:82" \
    "${small[*]} --normals --maps-per-block 8 --codec zstd --target 3d --gutter 1 --max-texture-size 64"
}

test_other_encodings_and_schemes() {
  knot
  shards "$WORK/knot.obj" f "0:20 20:49" "-q --positions ea-octa-grid -n 7 -m 16 --encoding unorm16-diameter"
  shards "$WORK/knot.obj" g "0:33 33:50" "-q --positions fibonacci -n 50 -m 16 --encoding bit1 --directions hemi-oct"
}

# A real mesh, when the shared meshes are there.
test_shared_mesh() {
  local mesh="${MESHES:-}/suzanne.obj"
  if [[ ! -f $mesh ]]; then
    echo "SKIP: no shared meshes at ${MESHES:-(unset)}"
    return 0
  fi
  shards "$mesh" s "0:200 200:201 201:442" "-n 10 -m 16 -q --normals --codec zstd"
}

# ---- Partial results are valid files that say what they are ---------------------------------------
test_partial_is_valid_and_says_so() {
  knot
  bake "$WORK/knot.obj" -o "$WORK/p.vff" "${small[@]}" --normals --codec zstd --zstd-level 5 --map-range 10:30
  expect_rc 0
  valid "$WORK/p.vff"
  run "$VFF_INSPECT" "$WORK/p.vff" --format json
  expect_rc 0
  expect_out '"mapBegin": 10'
  expect_out '"mapEnd": 30'
  expect_out '"mapCount": 82'
  expect_out '"codec": "zstd"'
  expect_out '"zstdLevel": 5'
  run "$VFF_INSPECT" "$WORK/p.vff"
  expect_out 'partial:    maps 10:30 of 82 only'
  # a partial result answers no rays: its other maps are not the field's
  run "$VFF_QUERY" "$WORK/p.vff" --ray 0 0 5 0 0 -1
  expect_rc 5
  expect_err "p.vff: unsupported (9005): the file is a partial result"
  # the maps outside the range are misses: the partial's hits are those of its range in the whole
  bake "$WORK/knot.obj" -o "$WORK/w.vff" "${small[@]}"
  bake "$WORK/knot.obj" -o "$WORK/r.vff" "${small[@]}" --map-range 0:82
  expect_rc 0
  run "$VFF_INSPECT" "$WORK/r.vff" --format json
  expect_out '"mapBegin": 0'
  bake "$WORK/knot.obj" -o "$WORK/j.vff" "${small[@]}" --map-range 3:9 --json
  expect_out '"mapRange": ['
  expect_out '"rays": 1536'
  run "$VFF_INSPECT" "$WORK/w.vff" --format json
  local whole
  whole=$(grep -o '"hits": [0-9]*' "$WORK/out" | head -1)
  run "$VFF_INSPECT" "$WORK/r.vff" --format json
  expect_out "$whole"
  # one part of every map merges to the whole bake
  bake --merge "$WORK/r.vff" -o "$WORK/m.vff" --json
  expect_rc 0
  expect_out '"parts": 1'
  cmp "$WORK/w.vff" "$WORK/m.vff" || fail "a part of every map merges to other bytes"
}

# vff-inspect's report of a partial result: "partial" gives the range, and the statistics and the
# histogram count the range's maps only, so the parts' counts add up to the whole bake's.
test_inspect_counts_only_the_range() {
  knot
  bake "$WORK/knot.obj" -o "$WORK/w.vff" "${small[@]}"
  bake "$WORK/knot.obj" -o "$WORK/a.vff" "${small[@]}" --map-range 0:30
  bake "$WORK/knot.obj" -o "$WORK/b.vff" "${small[@]}" --map-range 30:82
  expect_rc 0
  local doc
  doc=$("$VFF_INSPECT" "$WORK/a.vff" --format json) || fail "vff-inspect a.vff"
  [[ $doc == *'"partial": {'*'"mapBegin": 0,'*'"mapCount": 82,'*'"mapEnd": 30,'*'"maps": 30'* ]] ||
    fail "no partial range in the report: $doc"
  # 30 maps of 16x16 texels, not 82
  [[ $doc == *'"texels": 7680,'* ]] || fail "the statistics count more than the range's 30 maps"
  "$VFF_INSPECT" "$WORK/w.vff" --format json | grep -q '"partial": null' || fail "a whole field reports partial"
  # hits and misses, and each histogram bin, of the two parts add up to the whole's
  local counts
  counts() { "$VFF_INSPECT" "$1" --format json | grep -oE '"(hits|misses|count)": [0-9]+' | grep -oE '[0-9]+$'; }
  local sum
  sum=$(paste -d+ <(counts "$WORK/a.vff") <(counts "$WORK/b.vff") | bc | tr '\n' ' ')
  [[ $sum == "$(counts "$WORK/w.vff" | tr '\n' ' ')" ]] || fail "parts' counts $sum are not the whole's"
  run "$VFF_INSPECT" "$WORK/b.vff"
  expect_out "(maps 30:82 only: the others are fillers, not the field's)"
  # a "vff.partial" without a usable range is still partial; the statistics then count every map
  "$EDIT" "$WORK/b.vff" "$WORK/norange.vff" /vff.partial/mapEnd 90 || fail "edit"
  run "$VFF_INSPECT" "$WORK/norange.vff" --format json
  expect_rc 0
  expect_out '"mapBegin": null'
  expect_out '"texels": 20992,'
}

# Parts merge only with the same vff.source.geometryHash (12013), which drops exactly the triangles
# of zero area (spec/format.md section 9, "the mesh as baked"): a repeated position, exactly
# collinear vertices; a sliver of nonzero area is kept.
test_geometry_hash_drops_exactly_zero_area_triangles() {
  local tetra='v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 1 0 0\nv 2 0 0\nv 1 1e-30 0\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n'
  printf "$tetra" >"$WORK/t.obj"
  # v2 and v5 share a position; v1 v2 v6 lie on the x axis
  printf "${tetra}f 2 5 3\nf 1 2 6\nf 6 2 1\n" >"$WORK/zero.obj"
  # v1 v6 v7: twice 1e-30 of area, kept
  printf "${tetra}f 1 6 7\n" >"$WORK/sliver.obj"
  local name hash=()
  for name in t zero sliver; do
    bake "$WORK/$name.obj" -o "$WORK/$name.vff" "${small[@]}" --center 0 0 0 --radius 3
    expect_rc 0
    run "$VFF_INSPECT" "$WORK/$name.vff" --format json
    hash+=("$(grep -o '"geometryHash": "[0-9a-f]*"' "$WORK/out")")
    [[ -n ${hash[-1]} ]] || fail "$name.vff has no geometryHash"
  done
  [[ ${hash[0]} == "${hash[1]}" ]] || fail "zero-area triangles changed the geometry hash: ${hash[*]}"
  [[ ${hash[0]} != "${hash[2]}" ]] || fail "a sliver of nonzero area was dropped"
  run "$VFF_INSPECT" "$WORK/zero.vff" --format json
  expect_out '"triangles": 4'
  run "$VFF_INSPECT" "$WORK/sliver.vff" --format json
  expect_out '"triangles": 5'
  # so parts of the two meshes with zero-area triangles merge, and the sliver's do not
  bake "$WORK/t.obj" -o "$WORK/a.vff" "${small[@]}" --center 0 0 0 --radius 3 --map-range 0:41
  bake "$WORK/zero.obj" -o "$WORK/b.vff" "${small[@]}" --center 0 0 0 --radius 3 --map-range 41:82
  bake "$WORK/sliver.obj" -o "$WORK/c.vff" "${small[@]}" --center 0 0 0 --radius 3 --map-range 41:82
  refused 3 "c.vff: merge-geometry (12013)" "$WORK/a.vff" "$WORK/c.vff"
  # the same geometry from another file is another bake (META vff.source.name), not other geometry
  refused 3 "b.vff: merge-meta (12017): different bake: META vff.source" "$WORK/a.vff" "$WORK/b.vff"
}

# ---- Usage errors ------------------------------------------------------------------------------------
test_bad_ranges_are_usage_errors() {
  knot
  bake "$WORK/knot.obj" -o "$WORK/x.vff" "${small[@]}" --map-range 80:83
  expect_rc 1
  expect_err "it has 82 maps"
  for r in 5:5 9:3 a:4 4: -1:4; do
    bake "$WORK/knot.obj" -o "$WORK/x.vff" "${small[@]}" --map-range "$r"
    expect_rc 1
    expect_err "--map-range takes BEGIN:END"
  done
  bake "$WORK/knot.obj" -o "$WORK/x.vff" "${small[@]}" --map-range 0:4 --benchmark
  expect_rc 1
  expect_err "--benchmark"
  bake "$WORK/knot.obj" -o "$WORK/x.json" --split mesh --map-range 0:4
  expect_rc 1
  bake "$WORK/shape.vdb" -o "$WORK/x.vff" --map-range 0:4
  expect_rc 1
  expect_err "--map-range applies to a mesh bake"
  bake "$WORK/knot.obj" --merge "$WORK/a.vff" -o "$WORK/x.vff"
  expect_rc 1
  expect_err "--merge takes partial results, not a mesh"
  bake --merge "$WORK/a.vff" "$WORK/b.vff" -o "$WORK/x.vff" --codec zstd
  expect_rc 1
  expect_err "--codec does not apply"
  bake "$WORK/knot.obj" -o "$WORK/a.vff" "${small[@]}" --map-range 0:82
  expect_rc 0
  cp "$WORK/a.vff" "$WORK/a.copy"
  bake --merge "$WORK/a.vff" -o "$WORK/a.vff"
  expect_rc 1
  expect_err "merge-output-is-part (12001): -o $WORK/a.vff is also a part to merge"
  bake --merge "$WORK/a.vff" -o "$WORK/../$(basename "$WORK")/a.vff"
  expect_rc 1
  cmp "$WORK/a.vff" "$WORK/a.copy" || fail "the part was changed"
  bake --merge "$WORK/a.vff"
  expect_rc 1
  expect_err "-o FILE"
  [[ ! -e $WORK/x.vff && ! -e $WORK/x.json ]] || fail "output left behind"
}

# ---- Refusals of --merge: exit code, the file and the problem named, no output -------------------------
# refused RC MESSAGE PART...: --merge of the parts exits RC, says MESSAGE, writes nothing.
refused() {
  local rc=$1 message=$2
  shift 2
  bake --merge "$@" -o "$WORK/out.vff"
  expect_rc "$rc"
  expect_err "$message"
  [[ ! -e $WORK/out.vff ]] || fail "merge left $WORK/out.vff behind"
  [[ -z $(find "$WORK" -name '.out.vff.tmp*') ]] || fail "merge left a temporary behind"
}

# part NAME RANGE [OPTIONS...]: the knot's maps RANGE into NAME.vff.
part() {
  local name=$1 range=$2
  shift 2
  bake "$WORK/knot.obj" -o "$WORK/$name.vff" "${small[@]}" --map-range "$range" "$@"
  expect_rc 0
}

test_merge_refuses_gaps_and_overlaps() {
  knot
  part a 0:41
  part b 50:82
  part c 40:82
  part d 41:82
  refused 3 "b.vff: merge-gap (12018): gap: maps 41:50 are in no part" "$WORK/b.vff" "$WORK/a.vff"
  refused 3 "a.vff: merge-gap (12018): gap: maps 41:82 of the field's 82 are in no part" "$WORK/a.vff"
  refused 3 "d.vff: merge-gap (12018): gap: maps 0:41 are in no part" "$WORK/d.vff"
  refused 3 "c.vff: merge-overlap (12019): overlap: its maps 40:82 overlap" "$WORK/a.vff" "$WORK/c.vff"
  refused 3 "d.vff: merge-overlap (12019): overlap: its maps 41:82 overlap" "$WORK/a.vff" "$WORK/d.vff" "$WORK/d.vff"
  bake --merge "$WORK/d.vff" "$WORK/a.vff" -o "$WORK/ok.vff" -q
  expect_rc 0
}

test_merge_refuses_other_geometry_and_options() {
  knot
  "$MESHGEN" sphere "$WORK/sphere.obj" || fail "mesh generator"
  part a 0:41
  bake "$WORK/sphere.obj" -o "$WORK/sphere.vff" "${small[@]}" --map-range 41:82
  expect_rc 0
  refused 3 "sphere.vff: merge-geometry (12013): different geometry: vff.source.geometryHash" "$WORK/a.vff" "$WORK/sphere.vff"
  part zstd 41:82 --codec zstd
  refused 3 "zstd.vff: merge-block-options (12016): different options: codec" "$WORK/a.vff" "$WORK/zstd.vff"
  part normals 41:82 --normals
  refused 3 "normals.vff: merge-options (12015): different options:" "$WORK/a.vff" "$WORK/normals.vff"
  part u16 41:82 --encoding unorm16-diameter
  refused 3 "u16.vff: merge-options (12015): different options: encoding" "$WORK/a.vff" "$WORK/u16.vff"
  bake "$WORK/knot.obj" -o "$WORK/fib.vff" -q -m 16 --positions fibonacci -n 82 --map-range 41:82
  refused 3 "fib.vff: merge-options (12015): different options:" "$WORK/a.vff" "$WORK/fib.vff"
  part g 41:82 --maps-per-block 4
  refused 3 "g.vff: merge-block-options (12016): different options: mapsPerBlock" "$WORK/a.vff" "$WORK/g.vff"
  part layers 41:82 --gutter 2
  refused 3 "layers.vff: merge-options (12015): different options: gutter" "$WORK/a.vff" "$WORK/layers.vff"
  part sphere 41:82 --center 0 0 0 --radius 2
  refused 3 "sphere.vff: merge-options (12015): different options: sphere" "$WORK/a.vff" "$WORK/sphere.vff"
  cp "$WORK/knot.obj" "$WORK/renamed.obj"
  bake "$WORK/renamed.obj" -o "$WORK/renamed.vff" "${small[@]}" --map-range 41:82
  refused 3 "renamed.vff: merge-meta (12017): different bake: META vff.source.name" "$WORK/a.vff" "$WORK/renamed.vff"
}

test_merge_refuses_other_versions_and_bad_parts() {
  knot
  part a 0:41
  part b 41:82
  "$EDIT" "$WORK/b.vff" "$WORK/old.vff" /vff.generatorVersion '"0.0.1"' || fail "edit"
  refused 3 "old.vff: merge-version (12014): different versions: baked by vff-bake \"0.0.1\"" "$WORK/a.vff" "$WORK/old.vff"
  "$EDIT" "$WORK/b.vff" "$WORK/v2.vff" /vff.partial/version 2 || fail "edit"
  refused 5 "v2.vff: partial-version (12004): partial result version 2; this vff-bake reads version 1" "$WORK/a.vff" "$WORK/v2.vff"
  "$EDIT" "$WORK/b.vff" "$WORK/count.vff" /vff.partial/mapCount 90 || fail "edit"
  refused 3 "count.vff: partial-map-count (12008): \"vff.partial\" says 90 maps, the field has 82" "$WORK/a.vff" "$WORK/count.vff"
  "$EDIT" "$WORK/b.vff" "$WORK/end.vff" /vff.partial/mapEnd 83 || fail "edit"
  refused 3 "end.vff: partial-range (12009): map range 41:83 is empty or outside the field's 82 maps" "$WORK/a.vff" "$WORK/end.vff"
  "$EDIT" "$WORK/b.vff" "$WORK/codec.vff" /vff.partial/codec '"lz4"' || fail "edit"
  refused 5 "codec.vff: partial-codec (12010): \"vff.partial\" names an unknown codec 'lz4'" "$WORK/a.vff" "$WORK/codec.vff"
  "$EDIT" "$WORK/b.vff" "$WORK/nolevel.vff" /vff.partial/zstdLevel '"high"' || fail "edit"
  refused 3 "nolevel.vff: partial-key-type (12006): \"vff.partial\" zstdLevel is \"high\", not an integer 0..22" "$WORK/a.vff" "$WORK/nolevel.vff"
  # a value of another type is a malformed partial (3), even where its right type would be unsupported
  "$EDIT" "$WORK/b.vff" "$WORK/codec7.vff" /vff.partial/codec 7 || fail "edit"
  refused 3 "codec7.vff: partial-key-type (12006): \"vff.partial\" codec is 7, not a string" "$WORK/a.vff" "$WORK/codec7.vff"
  "$EDIT" "$WORK/b.vff" "$WORK/negative.vff" /vff.partial/mapBegin -1 || fail "edit"
  refused 3 "negative.vff: partial-key-type (12006): \"vff.partial\" mapBegin is -1" "$WORK/a.vff" "$WORK/negative.vff"
  "$EDIT" "$WORK/b.vff" "$WORK/object.vff" /vff.partial '"0:41"' || fail "edit"
  refused 3 "object.vff: partial-object (12003)" "$WORK/a.vff" "$WORK/object.vff"
  "$EDIT" "$WORK/b.vff" "$WORK/lacks.vff" /vff.partial '{"version":1,"mapBegin":41,"mapEnd":82}' || fail "edit"
  refused 3 "lacks.vff: partial-key-missing (12005): \"vff.partial\" lacks \"mapCount\"" "$WORK/a.vff" "$WORK/lacks.vff"
  # a key version 1 does not define is refused: the merge would drop what it does not understand
  "$EDIT" "$WORK/b.vff" "$WORK/extra.vff" /vff.partial/filter '"shuffle"' || fail "edit"
  refused 3 "extra.vff: partial-key-unknown (12007): \"vff.partial\" has the key \"filter\"" "$WORK/a.vff" "$WORK/extra.vff"
  "$EDIT" "$WORK/b.vff" "$WORK/level0.vff" /vff.partial '{"version":1,"mapBegin":41,"mapEnd":82,"mapCount":82,"codec":"zstd","zstdLevel":0,"mapsPerBlock":0}' || fail "edit"
  refused 3 "level0.vff: partial-zstd-level (12011)" "$WORK/a.vff" "$WORK/level0.vff"
  # the first part in argument order that breaks a rule is the one reported
  refused 3 "count.vff: partial-map-count (12008)" "$WORK/count.vff" "$WORK/codec7.vff"
  refused 3 "codec7.vff: partial-key-type (12006)" "$WORK/codec7.vff" "$WORK/count.vff"
  # a whole field is not a partial result
  bake "$WORK/knot.obj" -o "$WORK/whole.vff" "${small[@]}"
  refused 3 "whole.vff: partial-missing (12002): not a partial result" "$WORK/a.vff" "$WORK/whole.vff"
  # a corrupt part: one byte of its distance plane changed
  cp "$WORK/b.vff" "$WORK/corrupt.vff"
  local size
  size=$(stat -c %s "$WORK/corrupt.vff")
  printf '\x5a' | dd of="$WORK/corrupt.vff" bs=1 seek=$((size - 20)) conv=notrunc status=none
  refused 3 "corrupt.vff" "$WORK/a.vff" "$WORK/corrupt.vff"
  expect_err "checksum"
  # a part that is not there, or not a .vff
  refused 2 "missing.vff" "$WORK/a.vff" "$WORK/missing.vff"
  refused 3 "knot.obj" "$WORK/a.vff" "$WORK/knot.obj"
}

run_test "$1"
