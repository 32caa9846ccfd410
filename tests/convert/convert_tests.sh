#!/usr/bin/env bash
# convert_tests.sh - command-line tests of vff-convert.
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
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"
convert() { run "$VFF_CONVERT" "$@"; }
# field OUT ENCODING [ARGS...]: writes a test field (see convert_check.cpp).
field() { "$CHECK" write "$@" || fail "convert_check write $*"; }
# same A B [--normal-tolerance K]: A and B hold the same field, metadata and maps.
same() {
  run "$CHECK" compare "$@"
  [[ $RC -eq 0 ]] || { show; fail "fields differ: $*"; }
}
# no_leftovers: nothing but the listed files (and out/err) is in $WORK: no temporary, no partial output.
no_leftovers() {
  local f left=""
  for f in "$WORK"/* "$WORK"/.[!.]*; do
    [[ -e $f ]] || continue
    local b=${f##*/} keep=0 k
    for k in out err "$@"; do [[ $b == "$k" ]] && keep=1; done
    [[ $keep -eq 1 ]] || left+=" $b"
  done
  [[ -z $left ]] || fail "files left behind:$left"
}
# exr_round_trip ENCODING [FIELD ARGS...]: vff -> FLOAT exr -> vff gives the same bytes.
exr_round_trip() {
  field "$WORK/a.vff" "$@"
  convert "$WORK/a.vff" --to exr "$WORK/a.exr"
  expect_rc 0
  expect_no_err
  convert "$WORK/a.exr" --to vff "$WORK/b.vff"
  expect_rc 0
  expect_no_err
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
  convert "$WORK/a.vff" --to exr "$WORK/a.exr"
  expect_rc 0
  expect_no_err
  convert "$WORK/a.exr" --to vff "$WORK/b.vff"
  expect_rc 0
  expect_no_err
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
  if [[ ! -x ${VFF_BAKE:-/nonexistent} || ! -x ${MESHGEN:-/nonexistent} ]]; then
    echo "SKIP: vff-bake or vff-procedural-mesh is not built (needs Embree and VFF_BUILD_SAMPLES)"
    return 0
  fi
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
  for text in '{not json' '{"format":"vff-convert-exr/1"}' '{"format":"other"}'; do
    "$CHECK" plain-exr "$WORK/bad.exr" "$text" || fail "cannot write bad.exr"
    convert "$WORK/bad.exr" --to vff "$WORK/x.vff"
    expect_rc 3
    expect_err "bad.exr"
    expect_err "vff.field"
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

# ---- Re-encoding and level of detail (--encoding, --map-size, --positions/--count) -------------------
# The tool's "max error X steps" line, as a number.
printed_max_steps() { sed -n 's/.*max error \([0-9.]*\) steps.*/\1/p' "$WORK/out" | head -n 1; }
# le A B: A <= B (decimals).
le() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 <= b + 0) }'; }
needs_bake() {
  if [[ ! -x ${VFF_BAKE:-/nonexistent} || ! -x ${MESHGEN:-/nonexistent} ]]; then
    echo "SKIP: vff-bake or vff-procedural-mesh is not built (needs Embree and VFF_BUILD_SAMPLES)"
    return 1
  fi
}

test_lod_help_lists_options() {
  convert --help
  expect_rc 0
  for opt in --encoding --map-size --downsample --positions --count --resample; do
    expect_out "$opt"
  done
  expect_out "tent"
}

test_reencode_16_to_8_within_half_step() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 16 --normals
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding unorm8-diameter
  expect_rc 0
  expect_out "encoding: unorm16-diameter -> unorm8-diameter: max error"
  local tool
  tool=$(printed_max_steps)
  le "$tool" 0.5005 || { show; fail "the tool reports $tool steps, more than half a step"; }
  valid "$WORK/b.vff"
  # Every texel checked independently: misses stay misses, hits stay hits, within half an 8-bit step,
  # normals untouched; and the checker finds the largest error the tool printed.
  run "$CHECK" texels "$WORK/a.vff" "$WORK/b.vff" --max-steps 0.5005 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "16 -> 8 bit: texels out of bounds"; }
  expect_out "hit->miss 0, miss->hit 0"
  expect_out "hit texels with other normal bytes: 0"
  local checked
  checked=$(sed -n 's/^max error \([0-9.]*\) steps.*/\1/p' "$WORK/out")
  awk -v a="$tool" -v b="$checked" 'BEGIN { exit !((a - b) ^ 2 < 1e-6) }' ||
    fail "the tool printed $tool steps, the checker found $checked"
}

# 8 -> 16 bit is not a plain widening (65534 / 254 = 258.008 is no integer: code 64 becomes 16513,
# not 258 x 64), but it is within half a 16-bit step and converting back gives every code back.
test_reencode_8_to_16_is_reversible() {
  field "$WORK/a.vff" unorm8-diameter --n 2 --m 16 --normals  # every 8-bit code, misses included
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding unorm16-diameter
  expect_rc 0
  expect_out "reversible: converting back to unorm8-diameter gives every code back"
  run "$CHECK" texels "$WORK/a.vff" "$WORK/b.vff" --max-steps 0.5005 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "8 -> 16 bit: texels out of bounds"; }
  convert "$WORK/b.vff" --to vff "$WORK/c.vff" --encoding unorm8-diameter
  expect_rc 0
  run "$CHECK" texels "$WORK/a.vff" "$WORK/c.vff" --max-steps 0 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "8 -> 16 -> 8 bit does not give the original codes"; }
  expect_out "hit texels with other normal bytes: 0"
  valid "$WORK/c.vff"
}

test_reencode_chord_and_diameter() {
  field "$WORK/a.vff" unorm8-chord --n 2 --m 16
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding unorm8-diameter
  expect_rc 0
  le "$(printed_max_steps)" 0.5005 || { show; fail "chord -> diameter: more than half a step"; }
  run "$CHECK" texels "$WORK/a.vff" "$WORK/b.vff" --max-steps 0.5005 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "chord -> diameter: texels out of bounds"; }
  # Diameter -> chord: distances longer than the chord (the fixture's codes are random) hold the
  # largest code and are counted; misses stay misses.
  field "$WORK/d.vff" unorm8-diameter --n 2 --m 16
  convert "$WORK/d.vff" --to vff "$WORK/e.vff" --encoding unorm8-chord
  expect_rc 0
  expect_out_re "^clamped: [0-9]+ hits lie beyond the new scale"
  le "$(printed_max_steps)" 0.5005 || { show; fail "diameter -> chord: more than half a step within the scale"; }
  run "$CHECK" texels "$WORK/d.vff" "$WORK/e.vff" --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "diameter -> chord changed a hit or a miss"; }
  valid "$WORK/e.vff"
}

test_reencode_bit1_keeps_hit_and_miss() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 16 --normals --gutter 2
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding bit1
  expect_rc 0
  expect_out "encoding: unorm16-diameter -> bit1: distances dropped, hit or miss kept"
  expect_out "(2d-array, gutter 0)"  # bit1 tiles have no gutter: the source's 2 is dropped
  run "$CHECK" texels "$WORK/a.vff" "$WORK/b.vff" --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "bit1 changed a hit or a miss"; }
  expect_out "hit texels with other normal bytes: 0"
  valid "$WORK/b.vff"
  # bit1 has no distances to convert back: unsupported, no output.
  convert "$WORK/b.vff" --to vff "$WORK/c.vff" --encoding unorm8-chord
  expect_rc 5
  expect_err "b.vff"
  expect_err "bit1, which holds hit or miss and no distance"
  # An explicit gutter cannot hold either, and bit1 maps are multiples of 8 texels.
  convert "$WORK/a.vff" --to vff "$WORK/c.vff" --encoding bit1 --gutter 2
  expect_rc 1
  field "$WORK/m12.vff" unorm8-diameter --m 12
  convert "$WORK/m12.vff" --to vff "$WORK/c.vff" --encoding bit1
  expect_rc 1
  expect_err "bit1 maps need a size that is a multiple of 8, the source's is 12"
  no_leftovers a.vff b.vff m12.vff
}

# bc4-diameter: lossy, but hits and misses are kept, the tool's RMS error is small on a bake, the
# layout becomes a gutterless 2D array, converting back to unorm8-diameter gives the bc4 distances
# exactly, and an EXR of a bc4 field cannot come back (its blocks cannot be rebuilt exactly).
test_reencode_to_bc4_and_back() {
  needs_bake || return 0
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/a.vff" -n 3 -m 32 --normals --gutter 1 -q || fail "bake"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding bc4-diameter
  expect_rc 0
  expect_out "encoding: unorm8-diameter -> bc4-diameter: max error"
  expect_out "(2d-array, gutter 0)"
  local rms
  rms=$(sed -n 's/.*RMS \([0-9.]*\) steps.*/\1/p' "$WORK/out")
  # Measured 1.93 steps on this 32x32 knot (0.85 on the bunny at 64x64).
  awk -v r="$rms" 'BEGIN { exit !(r > 0 && r < 2.5) }' || { show; fail "RMS $rms steps is not in (0, 2.5)"; }
  run "$CHECK" texels "$WORK/a.vff" "$WORK/b.vff" --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "bc4 changed a hit or a miss"; }
  expect_out "hit->miss 0, miss->hit 0"
  expect_out "hit texels with other normal bytes: 0"
  valid "$WORK/b.vff"
  run "$VFF_INSPECT" "$WORK/b.vff"
  expect_out "vff 1.2"
  expect_out "bc4-diameter"
  convert "$WORK/b.vff" --to vff "$WORK/c.vff" --encoding unorm8-diameter
  expect_rc 0
  run "$CHECK" texels "$WORK/b.vff" "$WORK/c.vff" --max-steps 0 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "bc4 -> unorm8-diameter did not keep the decoded codes"; }
  # Maps of 30 texels cannot hold 4x4 blocks.
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/m30.vff" -n 1 -m 30 -q || fail "bake"
  convert "$WORK/m30.vff" --to vff "$WORK/d.vff" --encoding bc4-diameter
  expect_rc 1
  expect_err "multiple of 4"
  # EXR: out yes (decoded distances), back no.
  convert "$WORK/b.vff" --to exr "$WORK/b.exr"
  expect_rc 0
  convert "$WORK/b.exr" --to vff "$WORK/e.vff"
  expect_rc 5
  expect_err "b.exr"
  expect_err "bc4-diameter"
  no_leftovers knot.obj a.vff b.vff c.vff m30.vff b.exr
}

# Every rule, even and odd factors, an encoding change on top: each new texel is recomputed by
# convert_check from the source texels (the rules as README.md states them) and must match exactly,
# normals included.
test_lod_map_size_rules() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 24 --normals
  local rule size
  for rule in min majority centre tent; do
    for size in 12 8 6 1; do
      convert "$WORK/a.vff" --to vff "$WORK/$rule$size.vff" --map-size "$size" --downsample "$rule"
      expect_rc 0
      expect_out "map size: 24 -> $size, downsample $rule"
      run "$CHECK" downsample "$WORK/a.vff" "$WORK/$rule$size.vff" "$rule"
      [[ $RC -eq 0 ]] || { show; fail "--map-size $size --downsample $rule: texels differ from the rule"; }
      expect_out "codes differing 0, normals differing 0"
    done
  done
  valid "$WORK/tent6.vff"
  convert "$WORK/a.vff" --to vff "$WORK/c.vff" --map-size 8 --downsample min --encoding unorm8-chord
  expect_rc 0
  run "$CHECK" downsample "$WORK/a.vff" "$WORK/c.vff" min
  [[ $RC -eq 0 ]] || { show; fail "--map-size with --encoding: texels differ from the rule"; }
  # The default rule is tent.
  convert "$WORK/a.vff" --to vff "$WORK/d.vff" --map-size 8
  expect_rc 0
  expect_out "downsample tent"
}

# An odd factor's centre rule takes the texel whose centre is the new texel's centre: the same ray
# as a bake at the smaller size, so the result is that bake, byte for byte.
test_lod_map_size_centre_odd_factor_is_a_bake() {
  needs_bake || return 0
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/m24.vff" -n 3 -m 24 --normals -q || fail "bake"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/m8.vff" -n 3 -m 8 --normals -q || fail "bake"
  convert "$WORK/m24.vff" --to vff "$WORK/c8.vff" --map-size 8 --downsample centre
  expect_rc 0
  run "$CHECK" texels "$WORK/m8.vff" "$WORK/c8.vff" --max-steps 0 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "centre of a 3x reduction differs from the bake"; }
  expect_out "hit texels with other normal bytes: 0"
}

test_lod_usage_errors() {
  field "$WORK/a.vff" unorm8-diameter --m 16
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --map-size 5
  expect_rc 1
  expect_err "--map-size 5"
  expect_err "allowed: 1, 2, 4, 8, 16"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --map-size 32
  expect_rc 1
  expect_err "must divide the source's 16"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --map-size 4 --encoding bit1
  expect_rc 1
  expect_err "multiple of 8 (bit1); allowed: 8, 16"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --downsample min
  expect_rc 1
  expect_err "--downsample applies with --map-size only"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --resample interpolated
  expect_rc 1
  expect_err "--resample applies with --positions or --count only"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --count 2000
  expect_rc 1
  expect_err "1 <= n <= 1024"
  # 2^24 samples of 16 x 16 texels with normals: 24 GiB of maps, refused before any work.
  field "$WORK/n.vff" unorm16-diameter --m 16 --normals
  convert "$WORK/n.vff" --to vff "$WORK/b.vff" --positions fibonacci --count 16777216
  expect_rc 1
  expect_err "above vff-convert's limit of 17179869184"
  convert "$WORK/a.vff" --to exr "$WORK/b.exr" --encoding unorm8-chord
  expect_rc 1
  expect_err "--to vff only"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --downsample mode
  expect_rc 1
  no_leftovers a.vff n.vff
}

# octa-hemi2 n's samples are every other sample of 2n, so the nearest resampling of a 2n bake is
# the n bake, byte for byte; interpolated and a non-nested source stay within the stated bounds
# (tools/vff-convert/README.md).
test_lod_fewer_samples_vs_bake() {
  needs_bake || return 0
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/n8.vff" -n 8 -m 16 --encoding unorm16-diameter --normals -q || fail "bake"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/n4.vff" -n 4 -m 16 --encoding unorm16-diameter --normals -q || fail "bake"
  convert "$WORK/n8.vff" --to vff "$WORK/near.vff" --count 4
  expect_rc 0
  expect_out "positions: octa-hemi2 n=8 (290 maps) -> octa-hemi2 n=4 (82 maps), resample nearest"
  run "$CHECK" texels "$WORK/n4.vff" "$WORK/near.vff" --max-steps 0 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "nearest resampling of a nested sample set is not the bake"; }
  expect_out "hit texels with other normal bytes: 0"
  valid "$WORK/near.vff"
  convert "$WORK/n8.vff" --to vff "$WORK/interp.vff" --count 4 --resample interpolated
  expect_rc 0
  run "$CHECK" texels "$WORK/n4.vff" "$WORK/interp.vff" --min-agreement 99 --max-mean-error 0.06
  [[ $RC -eq 0 ]] || { show; fail "interpolated resampling is beyond its bounds"; }
  # Not nested: 1000 Fibonacci samples down to octa-hemi2 n = 4.
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/fib.vff" --positions fibonacci -n 1000 -m 16 --encoding unorm16-diameter \
    --normals -q || fail "bake"
  local r
  for r in nearest interpolated; do
    convert "$WORK/fib.vff" --to vff "$WORK/fib-$r.vff" --positions octa-hemi2 --count 4 --resample "$r"
    expect_rc 0
    run "$CHECK" texels "$WORK/n4.vff" "$WORK/fib-$r.vff" --min-agreement 96 --max-mean-error 0.07
    [[ $RC -eq 0 ]] || { show; fail "fibonacci -> octa-hemi2 ($r) is beyond its bounds"; }
  done
  # A bit1 source can be resampled by nearest only.
  convert "$WORK/n8.vff" --to vff "$WORK/b.vff" --encoding bit1
  expect_rc 0
  convert "$WORK/b.vff" --to vff "$WORK/b4.vff" --count 4 --resample interpolated
  expect_rc 5
  expect_err "a bit1 source has none"
  convert "$WORK/b.vff" --to vff "$WORK/b4.vff" --count 4
  expect_rc 0
}

test_lod_provenance_and_metadata() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 16
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding unorm8-diameter
  expect_rc 0
  local ha hb
  ha=$("$CHECK" xxh3 "$WORK/a.vff")
  hb=$("$CHECK" xxh3 "$WORK/b.vff")
  run "$CHECK" meta "$WORK/b.vff"
  # The source's keys stay; one entry is appended (canonical JSON: sorted keys, no spaces).
  expect_out '"n":2,"name":"convert fixture",'
  local entry1='{"operations":["encoding"],"options":{"encoding":"unorm8-diameter"},"source":{"distanceEncoding":"unorm16-diameter","mapCount":26,"mapResolution":16,"name":"a.vff","positionParam":2,"positionScheme":"octa-hemi2","xxh3":"'$ha'"},"tool":"vff-convert","version":"'
  expect_out "\"vff.provenance\":[$entry1"
  # A second conversion appends a second entry, naming its own source.
  convert "$WORK/b.vff" --to vff "$WORK/c.vff" --map-size 8 --count 1 --resample interpolated
  expect_rc 0
  run "$CHECK" meta "$WORK/c.vff"
  expect_out "\"vff.provenance\":[$entry1"
  expect_out '{"operations":["positions","map-size"],"options":{"count":1,"downsample":"tent","mapSize":8,"positions":"octa-hemi2","resample":"interpolated"},"source":{"distanceEncoding":"unorm8-diameter","mapCount":26,"mapResolution":16,"name":"b.vff","positionParam":2,"positionScheme":"octa-hemi2","xxh3":"'$hb'"},"tool":"vff-convert","version":"'
  [[ $(grep -o '"tool":"vff-convert"' "$WORK/out" | wc -l) -eq 2 ]] || { show; fail "expected two entries"; }
  # Options that change nothing, and a plain repack, keep META byte for byte.
  "$CHECK" meta "$WORK/c.vff" >"$WORK/c.meta"
  convert "$WORK/c.vff" --to vff "$WORK/d.vff" --encoding unorm8-diameter --codec zstd
  expect_rc 0
  expect_out "nothing to resample"
  "$CHECK" meta "$WORK/d.vff" | cmp - "$WORK/c.meta" || fail "META changed without a change of the maps"
  # A source whose vff.provenance is not a list is refused, naming the key.
  field "$WORK/bad.vff" unorm8-diameter --meta '{"vff.provenance":"by hand"}'
  convert "$WORK/bad.vff" --to vff "$WORK/x.vff" --encoding bit1
  expect_rc 3
  expect_err "bad.vff"
  expect_err '"vff.provenance" is not an array'
  [[ ! -e $WORK/x.vff ]] || fail "an output was written"
}

test_lod_same_bytes_any_thread_count() {
  field "$WORK/a.vff" unorm16-diameter --n 4 --m 16 --normals
  local t
  for t in 1 2 4; do
    convert "$WORK/a.vff" --to vff "$WORK/a$t.vff" --count 2 --resample interpolated --map-size 8 \
      --downsample tent --encoding unorm8-chord -j "$t"
    expect_rc 0
    cp "$WORK/out" "$WORK/out$t"
  done
  cmp "$WORK/a1.vff" "$WORK/a2.vff" || fail "1 vs 2 threads differ"
  cmp "$WORK/a1.vff" "$WORK/a4.vff" || fail "1 vs 4 threads differ"
  sed -i 's/a[0-9]\.vff:/aN.vff:/' "$WORK/out1" "$WORK/out4"
  cmp "$WORK/out1" "$WORK/out4" || fail "the printed summary depends on the thread count"
}

# vff-experiments ao --field evaluates a file like the same configuration baked in memory, and
# refuses a file of another mesh.
test_lod_ao_field_option() {
  needs_bake || return 0
  if [[ ! -x ${EXPERIMENTS:-/nonexistent} ]]; then
    echo "SKIP: vff-experiments is not built"
    return 0
  fi
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/f.vff" -n 8 -m 16 -q || fail "bake"
  convert "$WORK/f.vff" --to vff "$WORK/g.vff" --map-size 8
  expect_rc 0
  run "$EXPERIMENTS" ao --mesh "$WORK/knot.obj" --size 32 --rays 16 -o "$WORK/ao" --config 290x16x16 \
    --field "$WORK/f.vff" --field "$WORK/g.vff"
  expect_rc 0
  local r baked file
  for r in nearest interpolated; do
    baked=$(grep "^| 290x16x16 | $r |" "$WORK/out" | cut -d'|' -f4-6)
    file=$(grep "^| f.vff (290x16x16 unorm8-diameter) | $r |" "$WORK/out" | cut -d'|' -f4-6)
    [[ -n $baked && $baked == "$file" ]] || { show; fail "$r: the file's row ($file) is not the bake's ($baked)"; }
  done
  expect_out "| g.vff (290x8x8 unorm8-diameter) | nearest |"
  # Another mesh: its sphere differs.
  "$MESHGEN" bowl "$WORK/bowl.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/bowl.obj" -o "$WORK/bowl.vff" -n 2 -m 8 -q || fail "bake"
  run "$EXPERIMENTS" ao --mesh "$WORK/knot.obj" --size 32 --rays 4 -o "$WORK/ao" --field "$WORK/bowl.vff"
  expect_rc 3
  expect_err "bowl.vff"
  expect_err "is not the mesh's minimal enclosing sphere"
  # Another mesh baked in the knot's sphere: the source mesh's XXH3 differs.
  local sphere
  sphere=$(sed -n 's/.*is not the mesh.s minimal enclosing sphere (centre \([^,]*\), radius \([^)]*\)).*/\1 \2/p' "$WORK/err")
  read -r cx cy cz rr <<<"$sphere"
  "$VFF_BAKE" "$WORK/bowl.obj" -o "$WORK/bowl2.vff" -n 2 -m 8 --center "$cx" "$cy" "$cz" --radius "$rr" -q ||
    fail "bake with the knot's sphere"
  run "$EXPERIMENTS" ao --mesh "$WORK/knot.obj" --size 32 --rays 4 -o "$WORK/ao" --field "$WORK/bowl2.vff"
  expect_rc 3
  expect_err "bowl2.vff"
  expect_err "(META vff.source.xxh3), the loaded mesh has"
}

# ---- Runner --------------------------------------------------------------------------------------------
[[ $# -eq 1 && $1 == test_* ]] || { echo "usage: $0 test_NAME" >&2; exit 2; }
run_test "$1"
