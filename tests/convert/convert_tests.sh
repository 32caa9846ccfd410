#!/usr/bin/env bash
# convert_tests.sh - command-line tests of vff-convert: options, EXR export and import, repacking,
# errors. (Re-encoding and level of detail: lod_tests.sh; OpenVDB: vdb_tests.sh.)
#
# Every function named test_* is one ctest case (tests/convert/CMakeLists.txt finds them in this
# file, so a test cannot silently not run): `bash convert_tests.sh test_NAME` runs one. Environment:
#   VFF_CONVERT  the vff-convert executable
#   VFF_INSPECT  the vff-inspect executable
#   CHECK        the vff_convert_check executable (writes input fields, compares fields)
#   VFF_BAKE     the vff-bake executable, or empty when it is not built (that test then skips)
#   MESHGEN      the vff-procedural-mesh executable, or empty
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_CONVERT:?}" "${VFF_INSPECT:?}" "${CHECK:?}" "${WORK:?}"

# ---- Helpers ---------------------------------------------------------------------------------------
source "$(dirname "${BASH_SOURCE[0]}")/convert_harness.sh"
# exr_and_back: $WORK/a.vff -> $WORK/a.exr (FLOAT) -> $WORK/b.vff, both steps clean.
exr_and_back() {
  convert "$WORK/a.vff" --to exr "$WORK/a.exr"
  expect_rc 0
  expect_no_err
  convert "$WORK/a.exr" --to vff "$WORK/b.vff"
  expect_rc 0
  expect_no_err
}
# exr_round_trip ENCODING [FIELD ARGS...]: vff -> FLOAT exr -> vff gives the same bytes.
exr_round_trip() {
  field "$WORK/a.vff" "$@"
  exr_and_back
  same "$WORK/a.vff" "$WORK/b.vff"
  cmp "$WORK/a.vff" "$WORK/b.vff" || fail "the round trip is not byte-identical"
  valid "$WORK/b.vff"
}

# ---- Command line ----------------------------------------------------------------------------------
test_help() {
  convert --help
  expect_rc 0
  expect_out "Exit codes:"
  for opt in --to --half --target --max-texture-size --max-layers --gutter --codec --maps-per-block --threads \
    --version; do
    expect_out "$opt"
  done
}

test_version() {
  convert --version
  expect_rc 0
  grep -q -E '^vff-convert [0-9]+\.[0-9]+\.[0-9]+ ' "$WORK/out" || { show; fail "bad --version line"; }
}

test_usage_errors() {
  field "$WORK/a.vff" unorm8-diameter
  convert "$WORK/a.vff" "$WORK/a.png"
  expect_rc 1
  expect_err "--to"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --half
  expect_rc 1
  expect_err "--half"
  convert "$WORK/a.vff" --to exr "$WORK/b.exr" --gutter 2
  expect_rc 1
  expect_err "--to vff only"
  convert "$WORK/a.vff" --to tiff "$WORK/b.tiff"
  expect_rc 1
  convert "$WORK/a.vff"
  expect_rc 1
  no_leftovers a.vff
}

# ---- EXR round trips (FLOAT: exact for every encoding) ---------------------------------------------
test_exr_round_trip_unorm8_diameter() { exr_round_trip unorm8-diameter --n 2; }
test_exr_round_trip_unorm8_chord() { exr_round_trip unorm8-chord --n 2; }
test_exr_round_trip_unorm16_diameter() { exr_round_trip unorm16-diameter --n 2 --m 16; }
test_exr_round_trip_bit1() { exr_round_trip bit1 --n 2; }
test_exr_round_trip_with_gutter() { exr_round_trip unorm8-chord --n 2 --gutter 2; }
test_exr_round_trip_large_radius() { exr_round_trip unorm16-diameter --radius 12345.678; }
test_exr_round_trip_small_radius() { exr_round_trip unorm8-diameter --radius 0.001; }

test_exr_same_bytes_any_thread_count() {
  field "$WORK/a.vff" unorm8-chord --n 4 --m 32 --normals
  local t
  for t in 1 2 4; do
    convert "$WORK/a.vff" --to exr "$WORK/a$t.exr" -j "$t"
    expect_rc 0
  done
  cmp "$WORK/a1.exr" "$WORK/a2.exr" || fail "1 vs 2 threads differ"
  cmp "$WORK/a1.exr" "$WORK/a4.exr" || fail "1 vs 4 threads differ"
}

test_exr_output_extension_picks_kind() {
  field "$WORK/a.vff" unorm8-diameter
  convert "$WORK/a.vff" "$WORK/a.exr"
  expect_rc 0
  convert "$WORK/a.exr" "$WORK/b.vff"
  expect_rc 0
  cmp "$WORK/a.vff" "$WORK/b.vff" || fail "round trip differs"
}

# The EXR remembers the codec and maps per block: a zstd file comes back as the same zstd file.
test_exr_keeps_codec_and_blocks() {
  field "$WORK/a.vff" unorm8-diameter --n 2 --normals
  convert "$WORK/a.vff" --to vff "$WORK/z.vff" --codec zstd --maps-per-block 5
  expect_rc 0
  convert "$WORK/z.vff" --to exr "$WORK/z.exr"
  expect_rc 0
  convert "$WORK/z.exr" --to vff "$WORK/z2.vff"
  expect_rc 0
  cmp "$WORK/z.vff" "$WORK/z2.vff" || fail "zstd round trip is not byte-identical"
  run "$VFF_INSPECT" "$WORK/z2.vff"
  expect_out "zstd"
}

# ---- HALF: exact for unorm8-* and bit1, lossy (and said so) for unorm16-diameter --------------------
test_half_exact_for_8bit_and_bit1() {
  local e
  for e in unorm8-diameter unorm8-chord bit1; do
    field "$WORK/$e.vff" "$e" --n 2
    convert "$WORK/$e.vff" --to exr "$WORK/$e.exr" --half
    expect_rc 0
    expect_no_err
    convert "$WORK/$e.exr" --to vff "$WORK/$e.back.vff"
    expect_rc 0
    expect_no_err
    cmp "$WORK/$e.vff" "$WORK/$e.back.vff" || fail "$e: HALF round trip is not byte-identical"
  done
  # HALF files are smaller than FLOAT ones.
  convert "$WORK/unorm8-chord.vff" --to exr "$WORK/float.exr"
  expect_rc 0
  (($(stat -c %s "$WORK/unorm8-chord.exr") < $(stat -c %s "$WORK/float.exr"))) || fail "HALF EXR is not smaller"
}

test_half_lossy_for_unorm16() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 16
  convert "$WORK/a.vff" --to exr "$WORK/a.exr" --half
  expect_rc 0
  expect_err "warning: HALF cannot hold every unorm16-diameter distance exactly"
  convert "$WORK/a.exr" --to vff "$WORK/b.vff"
  expect_rc 0
  expect_err "hit texels are ambiguous: HALF holds the same value for neighbouring codes"
  valid "$WORK/b.vff"
  run "$CHECK" compare "$WORK/a.vff" "$WORK/b.vff"
  [[ $RC -eq 1 ]] || { show; fail "a HALF unorm16 round trip was expected to change codes"; }
  expect_out "distance bytes differing:"
}

# ---- Normals ---------------------------------------------------------------------------------------
test_normals_round_trip() {
  field "$WORK/a.vff" unorm8-diameter --n 4 --m 16 --normals
  exr_and_back
  # Within the oct-snorm16 quantisation: at most one code per component; in practice all exact.
  same "$WORK/a.vff" "$WORK/b.vff" --normal-tolerance 1
  expect_out "largest difference 0 codes"
  cmp "$WORK/a.vff" "$WORK/b.vff" || fail "the round trip is not byte-identical"
  valid "$WORK/b.vff"
}

test_normals_half_are_close() {
  field "$WORK/a.vff" unorm16-diameter --normals
  convert "$WORK/a.vff" --to exr "$WORK/a.exr" --half
  expect_rc 0
  expect_err "HALF normals"
  convert "$WORK/a.exr" --to vff "$WORK/b.vff"
  expect_rc 0
  valid "$WORK/b.vff"
  # HALF keeps 11 significant bits: about 2^-11 relative error per component, that is at most
  # about 16 snorm16 codes after the octahedral projection.
  run "$CHECK" compare "$WORK/a.vff" "$WORK/b.vff" --normal-tolerance 16
  grep -q "beyond tolerance 0," "$WORK/out" || { show; fail "HALF normals too far off"; }
}

# An edited EXR (values that are no decoded distance) is quantised to the nearest codes, with a warning.
test_edited_exr_is_quantised() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 16
  convert "$WORK/a.vff" --to exr "$WORK/a.exr"
  expect_rc 0
  "$CHECK" perturb-exr "$WORK/a.exr" "$WORK/edited.exr" || fail "cannot write edited.exr"
  convert "$WORK/edited.exr" --to vff "$WORK/b.vff"
  expect_rc 0
  expect_err "hit texels do not hold an exactly decoded distance; they were quantised to the nearest code"
  valid "$WORK/b.vff"
}

test_exr_files_have_default_mode() {
  field "$WORK/a.vff" unorm8-diameter
  (umask 022 && "$VFF_CONVERT" -q "$WORK/a.vff" "$WORK/a.exr") || fail "conversion failed"
  [[ $(stat -c %a "$WORK/a.exr") == 644 ]] || fail "a.exr has mode $(stat -c %a "$WORK/a.exr"), expected 644"
}

# A field baked from a mesh: real seam normals, unorm8-chord, gutters.
test_baked_field_round_trip() {
  needs_bake || return 0
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/a.vff" -n 4 -m 16 --normals --encoding unorm8-chord --gutter 1 -q ||
    fail "bake"
  convert "$WORK/a.vff" --to exr "$WORK/a.exr"
  expect_rc 0
  convert "$WORK/a.exr" --to vff "$WORK/b.vff"
  expect_rc 0
  expect_no_err
  cmp "$WORK/a.vff" "$WORK/b.vff" || fail "the baked field does not round-trip byte-identically"
  convert "$WORK/a.vff" --to exr "$WORK/h.exr" --half
  expect_rc 0
  convert "$WORK/h.exr" --to vff "$WORK/h.vff"
  expect_rc 0
  same "$WORK/a.vff" "$WORK/h.vff" --normal-tolerance 16
  convert "$WORK/a.vff" --to vff "$WORK/r.vff" --target 3d --max-texture-size 64 --codec zstd
  expect_rc 0
  same "$WORK/a.vff" "$WORK/r.vff"
  valid "$WORK/r.vff"
}

# ---- The EXR itself ----------------------------------------------------------------------------------
test_exrheader_accepts() {
  if ! command -v exrheader >/dev/null; then
    echo "SKIP: exrheader is not installed (Debian package openexr)"
    return 0
  fi
  field "$WORK/a.vff" unorm8-diameter --n 2 --normals
  convert "$WORK/a.vff" --to exr "$WORK/a.exr"
  expect_rc 0
  run exrheader "$WORK/a.exr"
  expect_rc 0
  expect_out "vff.field"
  expect_out '"distanceEncoding":"unorm8-diameter"'
  expect_out "slice.0"
  expect_out "normal.0"
  expect_out "miss"
}

test_exrinfo_accepts() {
  if ! command -v exrinfo >/dev/null; then
    echo "SKIP: exrinfo is not installed (Debian package openexr)"
    return 0
  fi
  field "$WORK/a.vff" unorm8-chord --n 3 --gutter 1
  # Small slices so that the field needs several parts.
  convert "$WORK/a.vff" --to vff "$WORK/small.vff" --max-texture-size 40
  expect_rc 0
  convert "$WORK/small.vff" --to exr "$WORK/a.exr" --half
  expect_rc 0
  run exrinfo -v "$WORK/a.exr"
  expect_rc 0
  expect_out "slice.0"
  expect_out "slice.1"
  expect_out "vff.field"
  convert "$WORK/a.exr" --to vff "$WORK/b.vff"
  expect_rc 0
  cmp "$WORK/small.vff" "$WORK/b.vff" || fail "multi-slice round trip differs"
}

# ---- Repacking -----------------------------------------------------------------------------------------
test_repack_round_trip() {
  field "$WORK/a.vff" unorm8-chord --n 3 --normals
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --max-texture-size 24 --max-layers 64 --target 3d --gutter 1 \
    --codec zstd --maps-per-block 7
  expect_rc 0
  same "$WORK/a.vff" "$WORK/b.vff"
  valid "$WORK/b.vff"
  run "$VFF_INSPECT" "$WORK/b.vff" --format json
  grep -q '"3d"' "$WORK/out" || { show; fail "target is not 3d"; }
  grep -q '"zstd"' "$WORK/out" || { show; fail "codec is not zstd"; }
  # And back to the original settings: the original bytes.
  convert "$WORK/b.vff" --to vff "$WORK/c.vff" --max-texture-size 2048 --max-layers 2048 --target 2d-array \
    --gutter 0 --codec stored --maps-per-block 0
  expect_rc 0
  cmp "$WORK/a.vff" "$WORK/c.vff" || fail "repacking back does not give the original bytes"
}

test_repack_keeps_unset_options() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --gutter 3
  convert "$WORK/a.vff" "$WORK/b.vff"
  expect_rc 0
  cmp "$WORK/a.vff" "$WORK/b.vff" || fail "a repack without options changed the file"
}

# ---- Errors ------------------------------------------------------------------------------------------
test_layout_too_small_names_limit() {
  field "$WORK/a.vff" unorm8-diameter --m 8
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --max-texture-size 8 --gutter 1
  expect_rc 1
  expect_err "b.vff"
  expect_err "max texture size 8"
  expect_err "layout-geometry"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --max-texture-size 8 --max-layers 4
  expect_rc 1
  expect_err "max layers 4"
  no_leftovers a.vff
}

test_missing_input_is_io_error() {
  convert "$WORK/nothere.vff" --to exr "$WORK/x.exr"
  expect_rc 2
  expect_err "nothere.vff"
  convert "$WORK/nothere.exr" --to vff "$WORK/x.vff"
  expect_rc 2
  expect_err "nothere.exr"
  no_leftovers
}

test_not_a_field_is_invalid_input() {
  echo "hello" >"$WORK/junk.vff"
  convert "$WORK/junk.vff" --to exr "$WORK/x.exr"
  expect_rc 3
  expect_err "junk.vff"
  no_leftovers junk.vff
}

test_exr_without_field_is_invalid_input() {
  "$CHECK" plain-exr "$WORK/plain.exr" || fail "cannot write plain.exr"
  convert "$WORK/plain.exr" --to vff "$WORK/x.vff"
  expect_rc 3
  expect_err "plain.exr"
  expect_err "vff.field"
  no_leftovers plain.exr
}

test_bad_field_attribute_is_invalid_input() {
  local text
  for text in '{not json' '{"format":"vff-convert-exr/1"}' '{"format":"other"}' '{"format":5}' '[1]'; do
    "$CHECK" plain-exr "$WORK/bad.exr" "$text" || fail "cannot write bad.exr"
    convert "$WORK/bad.exr" --to vff "$WORK/x.vff"
    expect_rc 3
    expect_err "bad.exr"
    expect_err "vff.field"
    if grep -q "internal error" "$WORK/err"; then fail "internal error for $text"; fi
  done
  # A well-formed description whose parts are missing.
  field "$WORK/a.vff" unorm8-diameter
  convert "$WORK/a.vff" --to exr "$WORK/a.exr"
  text=$(exrheader "$WORK/a.exr" 2>/dev/null | sed -n 's/^vff.field (type string): "\(.*\)"$/\1/p') || true
  if [[ -n $text ]]; then
    "$CHECK" plain-exr "$WORK/bad.exr" "$text" || fail "cannot write bad.exr"
    convert "$WORK/bad.exr" --to vff "$WORK/x.vff"
    expect_rc 3
    expect_err 'no part "slice.0"'
  else
    echo "SKIP (part): exrheader is not installed"
  fi
  no_leftovers bad.exr a.vff a.exr
}

test_truncated_exr_is_invalid_input() {
  field "$WORK/a.vff" unorm8-diameter --n 2
  convert "$WORK/a.vff" --to exr "$WORK/a.exr"
  expect_rc 0
  head -c $(($(stat -c %s "$WORK/a.exr") - 100)) "$WORK/a.exr" >"$WORK/cut.exr"
  convert "$WORK/cut.exr" --to vff "$WORK/x.vff"
  expect_rc 3
  expect_err "cut.exr"
  no_leftovers a.vff a.exr cut.exr
}

test_exr_input_to_exr_is_usage_error() {
  field "$WORK/a.vff" unorm8-diameter
  convert "$WORK/a.vff" "$WORK/a.exr"
  expect_rc 0
  convert "$WORK/a.exr" --to exr "$WORK/b.exr"
  expect_rc 1
  no_leftovers a.vff a.exr
}

test_unwritable_output_is_io_error() {
  field "$WORK/a.vff" unorm8-diameter
  convert "$WORK/a.vff" --to exr "$WORK/nodir/x.exr"
  expect_rc 2
  expect_err "nodir/x.exr"
  convert "$WORK/a.vff" --to vff "$WORK/nodir/x.vff"
  expect_rc 2
  expect_err "nodir/x.vff"
  # A folder where the output file should be: the rename fails, nothing partial is left.
  mkdir "$WORK/taken.exr"
  convert "$WORK/a.vff" --to exr "$WORK/taken.exr"
  expect_rc 2
  expect_err "taken.exr"
  [[ -d $WORK/taken.exr ]] || fail "the folder in the way was replaced"
  no_leftovers a.vff taken.exr
}

test_failure_keeps_existing_output() {
  field "$WORK/a.vff" unorm8-diameter
  echo "old" >"$WORK/b.vff"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --max-texture-size 4
  expect_rc 1
  [[ $(cat "$WORK/b.vff") == old ]] || fail "the existing output was changed"
  "$CHECK" plain-exr "$WORK/plain.exr" || fail "cannot write plain.exr"
  convert "$WORK/plain.exr" --to vff "$WORK/b.vff"
  expect_rc 3
  [[ $(cat "$WORK/b.vff") == old ]] || fail "the existing output was changed"
  no_leftovers a.vff b.vff plain.exr
}

# ---- Runner --------------------------------------------------------------------------------------------
[[ $# -eq 1 && $1 == test_* ]] || { echo "usage: $0 test_NAME" >&2; exit 2; }
# A valid field whose META holds a number beyond binary64 (rule 8001 allows any magnitude) cannot be
# carried into EXR, OpenVDB or a rewritten .vff, whose writers hold META in nlohmann::json: exit 5
# (unsupported) naming the reason, and no output file.
test_meta_beyond_binary64_is_unsupported() {
  local src
  src="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)/spec/conformance/valid/meta-any-magnitude.vff"
  for out in big.exr big.vdb big.vff; do
    run "$VFF_CONVERT" "$src" --to "${out##*.}" "$WORK/$out"
    expect_rc 5
    expect_err "unsupported (9005)"
    expect_err "beyond the binary64 range"
    [[ ! -e $WORK/$out ]] || fail "$out was written"
  done
}

run_test "$1"
