#!/usr/bin/env bash
# vdb_tests.sh - vff-convert's OpenVDB export (--to vdb) and its import back (--to vff).
#
# Every function named test_* is one ctest case (tests/convert/CMakeLists.txt finds them in this
# file): `bash vdb_tests.sh test_NAME` runs one. Environment:
#   VFF_CONVERT  the vff-convert executable
#   VFF_INSPECT  the vff-inspect executable
#   CHECK        the vff_convert_check executable (writes input fields, compares fields)
#   VDB_CHECK    the vff_vdb_check executable (writes .vdb inputs, checks exports with OpenVDB)
#   VDB_PRINT    OpenVDB's vdb_print, or empty when it is not installed (those tests then skip)
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_CONVERT:?}" "${VFF_INSPECT:?}" "${CHECK:?}" "${VDB_CHECK:?}" "${WORK:?}"

# ---- Helpers ---------------------------------------------------------------------------------------
source "$(dirname "${BASH_SOURCE[0]}")/convert_harness.sh"  # convert, field, same, no_leftovers
# verify FIELD VDB: the export holds exactly the field's slices and metadata (vdb_check.cpp).
verify() {
  run "$VDB_CHECK" verify "$1" "$2"
  [[ $RC -eq 0 ]] || { show; fail "$2 does not hold $1"; }
}
need_vdb_print() {
  if [[ -z ${VDB_PRINT:-} || ! -x ${VDB_PRINT:-} ]]; then
    echo "SKIP: vdb_print not found (Debian package libopenvdb-tools, installed by scripts/setup.sh)"
    exit 0
  fi
}
# vdb_round_trip ENCODING [FIELD ARGS...]: vff -> vdb (checked voxel by voxel) -> vff gives the same bytes.
vdb_round_trip() {
  field "$WORK/a.vff" "$@"
  convert "$WORK/a.vff" --to vdb "$WORK/a.vdb"
  expect_rc 0
  expect_no_err
  verify "$WORK/a.vff" "$WORK/a.vdb"
  convert "$WORK/a.vdb" --to vff "$WORK/b.vff"
  expect_rc 0
  expect_no_err
  same "$WORK/a.vff" "$WORK/b.vff"
  cmp "$WORK/a.vff" "$WORK/b.vff" || fail "the round trip is not byte-identical"
  valid "$WORK/b.vff"
}

# ---- What OpenVDB's own tool sees --------------------------------------------------------------------
# vdb_print lists both grids, their metadata, and as many active voxels as the field has hit texels.
test_vdb_print_lists_grids_metadata_and_hits() {
  need_vdb_print
  field "$WORK/a.vff" unorm8-diameter --n 2 --m 16 --normals
  convert "$WORK/a.vff" --to vdb "$WORK/a.vdb"
  expect_rc 0
  local n
  n=$("$VDB_CHECK" count-hits "$WORK/a.vff") || fail "count-hits"
  [[ $n -gt 0 ]] || fail "no hits in the fixture"
  expect_out "$n active voxels"
  run "$VDB_PRINT" "$WORK/a.vdb" -l -m
  expect_rc 0
  expect_out_re "^Name: distance$"
  expect_out_re "^Name: normal$"
  expect_out_re "Type: +Tree_float_5_4_3"
  expect_out_re "Type: +Tree_vec3s_5_4_3"
  expect_out_re "Background value: +inf"
  # vdb_print groups digits with commas.
  local grouped
  grouped=$(python3 -c 'import sys; print(f"{int(sys.argv[1]):,}")' "$n")
  [[ $(grep -c -E "Number of active voxels: +$grouped\$" "$WORK/out") -eq 2 ]] ||
    { show; fail "vdb_print does not report $grouped active voxels in both grids"; }
  expect_out "vff.field: {\"codec\":\"stored\",\"field\":{"
  expect_out "\"format\":\"vff-convert-vdb/1\""
  expect_out "\"metadata\":{\"n\":2,\"name\":\"convert fixture\"}"
  expect_out_re "vff.plane: distance"
  expect_out_re "vff.plane: normal"
  expect_out_re "vff.provenance: \[\{\"operations\":\[\"to-vdb\"\],\"options\":\{\},\"source\":\{.*\"format\":\"vff\",.*\"name\":\"a.vff\",.*\"xxh3\":\"[0-9a-f]{16}\"\}"
  expect_out "Dimensions of active voxels"
}

# The default vdb_print line (no options): both grids, their bounding boxes in (x, y, slice).
test_vdb_print_short_listing() {
  need_vdb_print
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 16
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --max-texture-size 64
  expect_rc 0
  convert "$WORK/b.vff" "$WORK/b.vdb"
  expect_rc 0
  run "$VDB_PRINT" "$WORK/b.vdb"
  expect_rc 0
  # 26 maps of 16x16 in 64x64 slices: 16 maps per slice, 2 slices (z 0..1).
  expect_out_re "^distance +float \(0,0,0\)->\(63,63,1\)"
}

# ---- Exact content ---------------------------------------------------------------------------------
# Every voxel of every slice against libvff's composed slices: active exactly at hits, the decoded
# distance and normal; metadata as in the source; several slices, a 3D layout, gutters.
test_vdb_voxels_match_slices() {
  field "$WORK/a.vff" unorm8-chord --n 3 --m 16 --normals
  convert "$WORK/a.vff" --to vff "$WORK/s.vff" --max-texture-size 64
  expect_rc 0
  convert "$WORK/s.vff" --to vdb "$WORK/s.vdb"
  expect_rc 0
  verify "$WORK/s.vff" "$WORK/s.vdb"
  convert "$WORK/a.vff" --to vff "$WORK/g.vff" --gutter 2 --target 3d --max-texture-size 100
  expect_rc 0
  convert "$WORK/g.vff" --to vdb "$WORK/g.vdb"
  expect_rc 0
  verify "$WORK/g.vff" "$WORK/g.vdb"
}

# ---- Round trips back to .vff (lossless for every encoding) ---------------------------------------------
test_vdb_round_trip_unorm8_diameter() { vdb_round_trip unorm8-diameter --n 2 --normals; }
test_vdb_round_trip_unorm8_chord() { vdb_round_trip unorm8-chord --n 2; }
test_vdb_round_trip_unorm16_diameter() { vdb_round_trip unorm16-diameter --n 2 --m 16 --normals; }
test_vdb_round_trip_bit1() { vdb_round_trip bit1 --n 2; }
test_vdb_round_trip_with_gutter() { vdb_round_trip unorm8-diameter --n 2 --gutter 3; }

# The codec and maps per block come back too, and a real bake survives the trip.
test_vdb_round_trip_zstd_and_multi_slice() {
  field "$WORK/a.vff" unorm8-diameter --n 3 --m 16 --normals
  convert "$WORK/a.vff" --to vff "$WORK/z.vff" --codec zstd --maps-per-block 7 --max-texture-size 48
  expect_rc 0
  convert "$WORK/z.vff" "$WORK/z.vdb"
  expect_rc 0
  convert "$WORK/z.vdb" "$WORK/z2.vff"
  expect_rc 0
  cmp "$WORK/z.vff" "$WORK/z2.vff" || fail "zstd multi-slice round trip is not byte-identical"
}

# ---- Determinism and provenance ------------------------------------------------------------------------
# OpenVDB writes a random UUID into every header; vff-convert derives it from the content instead.
test_vdb_same_bytes_every_run() {
  field "$WORK/a.vff" unorm8-diameter --n 2 --normals
  convert "$WORK/a.vff" --to vdb "$WORK/a1.vdb" -j 1
  expect_rc 0
  convert "$WORK/a.vff" --to vdb "$WORK/a2.vdb" -j 2
  expect_rc 0
  cmp "$WORK/a1.vdb" "$WORK/a2.vdb" || fail "two exports differ"
  # Bytes 21..56 hold the UUID: 8-4-4-4-12 hex digits, version 8.
  local uuid
  uuid=$(dd if="$WORK/a1.vdb" bs=1 skip=21 count=36 2>/dev/null)
  [[ $uuid =~ ^[0-9a-f]{8}-[0-9a-f]{4}-8[0-9a-f]{3}-[89ab][0-9a-f]{3}-[0-9a-f]{12}$ ]] || fail "UUID '$uuid'"
  # A different field gives a different UUID.
  field "$WORK/b.vff" unorm8-diameter --n 2
  convert "$WORK/b.vff" --to vdb "$WORK/b.vdb"
  expect_rc 0
  [[ $(dd if="$WORK/b.vdb" bs=1 skip=21 count=36 2>/dev/null) != "$uuid" ]] || fail "same UUID for another field"
}

# The provenance keeps the source's own entries and appends the export's; META itself is unchanged.
test_vdb_provenance_appends_to_source_entries() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 16
  # A source with a provenance entry of its own (re-encoded by vff-convert) when that option exists.
  if "$VFF_CONVERT" --help | grep -q -- "--encoding"; then
    convert "$WORK/a.vff" --to vff "$WORK/r.vff" --encoding unorm8-diameter
    expect_rc 0
  else
    cp "$WORK/a.vff" "$WORK/r.vff"
  fi
  convert "$WORK/r.vff" --to vdb "$WORK/r.vdb"
  expect_rc 0
  verify "$WORK/r.vff" "$WORK/r.vdb"
  # The source's entries, then {"tool":"vff-convert","operations":["to-vdb"],"source":{"name":"r.vff",
  # "format":"vff","xxh3": XXH3-64 of r.vff's bytes, ...}} (checked by vdb_check).
  run "$VDB_CHECK" provenance "$WORK/r.vdb" "$WORK/r.vff"
  [[ $RC -eq 0 ]] || { show; fail "provenance"; }
  expect_out '"operations":["to-vdb"]'
}

# ---- Conversions between the other kinds ----------------------------------------------------------------
test_vdb_from_exr_and_to_exr() {
  field "$WORK/a.vff" unorm8-chord --n 2 --normals
  convert "$WORK/a.vff" "$WORK/a.exr"
  expect_rc 0
  convert "$WORK/a.exr" "$WORK/a.vdb"
  expect_rc 0
  verify "$WORK/a.vff" "$WORK/a.vdb"
  convert "$WORK/a.vdb" "$WORK/b.exr"
  expect_rc 0
  convert "$WORK/b.exr" "$WORK/b.vff"
  expect_rc 0
  cmp "$WORK/a.vff" "$WORK/b.vff" || fail "vff -> exr -> vdb -> exr -> vff is not byte-identical"
}

# ---- Errors ------------------------------------------------------------------------------------------
test_vdb_usage_errors() {
  field "$WORK/a.vff" unorm8-diameter
  convert "$WORK/a.vff" --to vdb "$WORK/a.vdb"
  expect_rc 0
  convert "$WORK/a.vdb" --to vdb "$WORK/b.vdb"
  expect_rc 1
  expect_err "already an OpenVDB file"
  convert "$WORK/a.vff" --to vdb "$WORK/b.vdb" --half
  expect_rc 1
  expect_err "--half"
  convert "$WORK/a.vff" --to vdb "$WORK/b.vdb" --gutter 2
  expect_rc 1
  expect_err "--to vff only"
  convert "$WORK/a.vff" "$WORK/b.VDB2"
  expect_rc 1
  expect_err "exr|vff|vdb"
  no_leftovers a.vff a.vdb
}

# A .vdb that vff-convert did not write (a level set, no vff.field), a truncated one, a file with a
# .vdb name that is not one, a missing one, an unwritable destination: clear errors, nothing left.
test_vdb_bad_inputs() {
  "$VDB_CHECK" write "$WORK/ls.vdb" sphere,ball,1,0,0,0,0.1 || fail "vdb_check write"
  convert "$WORK/ls.vdb" --to vff "$WORK/x.vff"
  expect_rc 3
  expect_err "ls.vdb"
  expect_err "vff.field"
  field "$WORK/a.vff" unorm8-diameter --n 2
  convert "$WORK/a.vff" "$WORK/a.vdb"
  expect_rc 0
  head -c 300 "$WORK/a.vdb" >"$WORK/cut.vdb"
  convert "$WORK/cut.vdb" --to vff "$WORK/x.vff"
  expect_rc 3
  expect_err "cut.vdb"
  echo "not a volume" >"$WORK/text.vdb"
  convert "$WORK/text.vdb" --to vff "$WORK/x.vff"
  expect_rc 3
  expect_err "text.vdb"
  convert "$WORK/missing.vdb" --to vff "$WORK/x.vff"
  expect_rc 2
  expect_err "missing.vdb"
  convert "$WORK/a.vff" --to vdb "$WORK/nodir/x.vdb"
  expect_rc 2
  expect_err "nodir/x.vdb"
  mkdir "$WORK/taken.vdb"
  convert "$WORK/a.vff" --to vdb "$WORK/taken.vdb"
  expect_rc 2
  [[ -d $WORK/taken.vdb ]] || fail "the folder in the way was replaced"
  echo old >"$WORK/keep.vff"
  convert "$WORK/cut.vdb" --to vff "$WORK/keep.vff"
  expect_rc 3
  [[ $(cat "$WORK/keep.vff") == old ]] || fail "the existing output was changed"
  no_leftovers ls.vdb a.vff a.vdb cut.vdb text.vdb taken.vdb keep.vff
}

# Voxels edited outside the slices, a vff.field that is not a field: invalid input, exit 3.
test_vdb_edited_files_are_invalid() {
  field "$WORK/a.vff" unorm8-diameter --n 2
  convert "$WORK/a.vff" "$WORK/a.vdb"
  expect_rc 0
  "$VDB_CHECK" edit "$WORK/a.vdb" "$WORK/out-of-slices.vdb" voxel-outside || fail "edit"
  convert "$WORK/out-of-slices.vdb" --to vff "$WORK/x.vff"
  expect_rc 3
  expect_err "outside"
  "$VDB_CHECK" edit "$WORK/a.vdb" "$WORK/bad-field.vdb" field-json || fail "edit"
  convert "$WORK/bad-field.vdb" --to vff "$WORK/x.vff"
  expect_rc 3
  expect_err "vff.field"
  "$VDB_CHECK" edit "$WORK/a.vdb" "$WORK/scaled.vdb" scale-values || fail "edit"
  convert "$WORK/scaled.vdb" --to vff "$WORK/x.vff"
  expect_rc 0
  expect_err "not hold an exactly decoded distance"
  valid "$WORK/x.vff"
}

# ---- Runner --------------------------------------------------------------------------------------------
[[ $# -eq 1 && $1 == test_* ]] || { echo "usage: $0 test_NAME" >&2; exit 2; }
run_test "$1"
