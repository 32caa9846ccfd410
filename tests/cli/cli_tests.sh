#!/usr/bin/env bash
# cli_tests.sh - command-line tests of vff-inspect.
#
# Every function named test_* is one ctest case (tests/cli/CMakeLists.txt finds them in this file,
# so a test cannot silently not run): `bash cli_tests.sh test_NAME` runs one. The environment says
# where things are:
#   VFF_INSPECT   the vff-inspect executable
#   FIXTURES      the folder vff_cli_fixture wrote (see fixture.cpp for what each file holds)
#   SCHEMA        spec/inspect-schema.json
#   SCHEMA_CHECK  the vff_cli_schema_check executable
#   WORK          a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_INSPECT:?}" "${FIXTURES:?}" "${SCHEMA:?}" "${SCHEMA_CHECK:?}" "${WORK:?}"

# ---- Helpers ---------------------------------------------------------------------------------------
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"
inspect() { run "$VFF_INSPECT" "$@"; }
# conforms FILE: the JSON in FILE conforms to the schema.
conforms() { "$SCHEMA_CHECK" "$SCHEMA" "$1" || fail "$1 does not conform to the schema"; }
# png_size FILE: prints "WIDTH HEIGHT" from the PNG signature and IHDR chunk, or fails.
png_size() {
  local b
  read -r -a b <<<"$(od -An -tu1 -N24 "$1" | tr '\n' ' ')"
  [[ ${#b[@]} -eq 24 ]] || fail "$1 is shorter than a PNG header"
  [[ "${b[*]:0:8}" == "137 80 78 71 13 10 26 10" ]] || fail "$1 has no PNG signature"
  [[ "${b[*]:12:4}" == "73 72 68 82" ]] || fail "$1 does not start with IHDR"
  echo "$(((b[16] << 24) | (b[17] << 16) | (b[18] << 8) | b[19])) $(((b[20] << 24) | (b[21] << 16) | (b[22] << 8) | b[23]))"
}
# no_leftovers DIR: nothing but out/err (this script's captures) is in DIR.
no_leftovers() {
  local left
  left=$(find "$1" -mindepth 1 ! -name out ! -name err)
  [[ -z $left ]] || fail "files left behind: $left"
}

# ---- Command line ----------------------------------------------------------------------------------
test_help() {
  inspect --help
  expect_rc 0
  expect_out "Exit codes:"
  expect_out "0  success"
  expect_out "1  command-line error"
  expect_out "2  I/O error"
  expect_out "3  invalid input file"
  expect_out "4  runtime error"
  expect_out "5  unsupported"
  for opt in --format --validate --preview --maps --histogram-bins --version; do expect_out "$opt"; done
}

# A count of one takes the singular ("1 block", not "1 blocks").
test_counts_take_their_number() {
  inspect "$FIXTURES/small.vff"
  expect_rc 0
  expect_out "           1 block, 10 maps per block (last block 10), codecs: stored 1; filters: none 1"
}

test_version() {
  inspect --version
  expect_rc 0
  expect_out_re '^vff-inspect [0-9]+\.[0-9]+\.[0-9]+ \(libvff [0-9.]+, \.vff format 1\.3\)$'
}

test_unknown_option() {
  inspect "$FIXTURES/known.vff" --no-such-option
  expect_rc 1
  expect_no_out
  expect_err "vff-inspect: error:"
  expect_err "--no-such-option"
  expect_err "--help"
}

test_missing_argument() {
  inspect
  expect_rc 1
  expect_no_out
  expect_err "vff-inspect: error:"
}

test_bad_option_values() {
  inspect "$FIXTURES/known.vff" --format xml
  expect_rc 1
  expect_err "vff-inspect: error:"
  inspect "$FIXTURES/known.vff" --histogram-bins 0
  expect_rc 1
  inspect "$FIXTURES/known.vff" --preview "$WORK/p.png" --maps 0
  expect_rc 1
  inspect "$FIXTURES/known.vff" --maps 4
  expect_rc 1
  expect_err "--preview"
  inspect "$FIXTURES/known.vff" --preview -
  expect_rc 1
  [[ ! -e $WORK/p.png ]] || fail "a preview was written despite a usage error"
}

# ---- Files that cannot be inspected ----------------------------------------------------------------
test_missing_file() {
  inspect "$FIXTURES/does-not-exist.vff"
  expect_rc 2
  expect_no_out
  expect_err "vff-inspect: error: $FIXTURES/does-not-exist.vff"
  expect_err "io-open (1001)"
}

test_missing_file_validate() {
  inspect "$FIXTURES/does-not-exist.vff" --validate
  expect_rc 2
  expect_err "vff-inspect: error: $FIXTURES/does-not-exist.vff"
  expect_out "1001 io-open"
}

test_not_vff() {
  inspect "$FIXTURES/not-vff.txt"
  expect_rc 3
  expect_no_out
  expect_err_re "^vff-inspect: error: .*not-vff\.txt(@0x[0-9a-f]+)?: bad-magic \(2002\): "
}

test_empty_file() {
  inspect "$FIXTURES/empty.vff"
  expect_rc 3
  expect_err "too-small (2001)"
}

test_truncated_file() {
  inspect "$FIXTURES/truncated.vff"
  expect_rc 3
  expect_err "file-size-mismatch (3002)"
}

test_corrupt_without_validate() {
  # File::open verifies every checksum: the diagnostic names the file, the offset and the section.
  inspect "$FIXTURES/corrupt.vff"
  expect_rc 3
  expect_no_out
  expect_err_re '^vff-inspect: error: .*corrupt\.vff@0x[0-9a-f]+ \[DIST\]: (section|block)-checksum \((4008|6009)\): '
}

test_stdout_write_error() {
  [[ -w /dev/full ]] || { echo "no /dev/full here: nothing to test"; return 0; }
  set +e
  "$VFF_INSPECT" "$FIXTURES/known.vff" >/dev/full 2>"$WORK/err"
  RC=$?
  set -e
  expect_rc 2
  expect_err "vff-inspect: error: stdout: No space left on device"
}

# ---- Summary ---------------------------------------------------------------------------------------
test_summary_known() {
  inspect "$FIXTURES/known.vff"
  expect_rc 0
  expect_no_err
  expect_out "file:        $FIXTURES/known.vff"
  expect_out_re '^format: +vff 1\.0, [0-9]+ bytes \([0-9]+\.[0-9]{3} MiB\)$'
  expect_out "incompat 0x0 (none), roCompat 0x0 (none)"
  expect_out_re '^header: +checksum xxh3-64 0x[0-9a-f]{16}, verified OK$'
  expect_out "sections (4):"
  for tag in FDSC LAYT DIST META; do
    expect_out_re "^  $tag  0x[0-9a-f]+ .* stored .* 0x[0-9a-f]{16}  verified OK$"
  done
  expect_out "centre (0.5, -1, 2), radius 1.5"
  expect_out "octa-hemi2, param 1, 10 maps"
  expect_out "concentric-equal-area, map resolution 4 (4x4 texels)"
  expect_out "duff2017"
  expect_out "unorm8-diameter, miss code 255"
  expect_out_re '^  normals: +none$'
  expect_out_re '^  distance +160 bytes \(0\.000 MiB\) raw, 16 bytes per map$'
  expect_out "stored 160 bytes (0.000 MiB), compression ratio 1.000 (raw/stored)"
  expect_out "3 blocks, 4 maps per block (last block 2), codecs: stored 3; filters: none 3"
  expect_out_re '^  normal +absent$'
  expect_out "target:    2d-array"
  expect_out "4 texels (gutter 0), 10 per row x 1 per column = 10 per slice"
  expect_out "40 x 4 texels, 1 slice"
  expect_out "max texture size 2048, max layers 2048"
  expect_out "150 of 160 texels, hit ratio 0.937500 (93.750 %)"
  expect_out "distance histogram (16 bins over [0, 2R] = [0, 3]):"
  expect_out '"name": "known"'
  expect_out '"note": "cli fixture"'
}

test_histogram_known() {
  # Codes 17 t (t = 0..14): 0..119 fall below R, 136..238 above.
  inspect "$FIXTURES/known.vff" --histogram-bins 2
  expect_rc 0
  expect_out "distance histogram (2 bins over [0, 2R] = [0, 3]):"
  expect_out_re '^  \[0\.0000, 1\.5000\) +0\.000-0\.500 +80 +53\.33%'
  expect_out_re '^  \[1\.5000, 3\.0000\) +0\.500-1\.000 +70 +46\.67%'
}

test_big_sizes() {
  # The paper's configuration: 4226 maps of 64x64 unorm8 with 4-byte normals; every map is decoded.
  local start end
  start=$(date +%s%N)
  inspect "$FIXTURES/big.vff"
  end=$(date +%s%N)
  expect_rc 0
  expect_out "octa-hemi2, param 32, 4226 maps"
  expect_out_re '^  distance +17309696 bytes \(16\.508 MiB\) raw, 4096 bytes per map$'
  expect_out_re '^  normal +69238784 bytes \(66\.031 MiB\) raw, 16384 bytes per map$'
  expect_out "stored 17309696 bytes (16.508 MiB), compression ratio 1.000 (raw/stored)"
  expect_out "stored 69238784 bytes (66.031 MiB), compression ratio 1.000 (raw/stored)"
  expect_out "normals:    oct-snorm16"
  expect_out "0 of 17309696 texels, hit ratio 0.000000"
  expect_out "32 per row x 32 per column = 1024 per slice"
  expect_out "2048 x 2048 texels, 5 slices"
  local ms=$(((end - start) / 1000000))
  echo "vff-inspect big.vff: $ms ms"
  ((ms < 10000)) || fail "inspecting big.vff took $ms ms"
}

test_zstd_normals() {
  inspect "$FIXTURES/zstd.vff"
  expect_rc 0
  expect_out "incompat 0x1 (zstd)"
  expect_out "unorm16-diameter, miss code 65535"
  expect_out "normals:    oct-snorm16"
  expect_out_re '^  distance +3328 bytes \(0\.003 MiB\) raw, 128 bytes per map$'
  expect_out_re '^  normal +6656 bytes \(0\.006 MiB\) raw, 256 bytes per map$'
  expect_out "4 blocks, 8 maps per block (last block 2), codecs: zstd 4"
  expect_out_re '^hits: +[1-9][0-9]* of 1664 texels'
}

test_chord() {
  inspect "$FIXTURES/chord.vff" --histogram-bins 4
  expect_rc 0
  expect_out "unorm8-chord, miss code 255"
  expect_out "hemi-octahedral"
  expect_out "distance histogram (4 bins over [0, 2R] = [0, 3]):"
  expect_out_re '^hits: +[1-9][0-9]* of 640 texels'
}

test_bit1() {
  inspect "$FIXTURES/bit1.vff"
  expect_rc 0
  expect_out "bit1, miss code 0"
  expect_out_re '^histogram: +hits only \(bit1 stores no distance\): [1-9][0-9]* hits, [1-9][0-9]* misses$'
  expect_out_re '^  distance +80 bytes \(0\.000 MiB\) raw, 8 bytes per map$'
}

test_stdin() {
  run "$VFF_INSPECT" - <"$FIXTURES/known.vff"
  expect_rc 0
  expect_out "file:        <stdin>"
  expect_out "150 of 160 texels"
  run "$VFF_INSPECT" - --validate <"$FIXTURES/corrupt.vff"
  expect_rc 3
  expect_out "6009 block-checksum"
}

# ---- JSON ------------------------------------------------------------------------------------------
test_json_conforms() {
  local f
  for f in known small zstd chord bit1 big; do
    inspect "$FIXTURES/$f.vff" --format json
    expect_rc 0
    cp "$WORK/out" "$WORK/$f.json"
    conforms "$WORK/$f.json"
  done
}

test_json_bc4_features() {
  # A format 1.2 bc4 file: incompatFeatures zstd | bc4 (5), named as the schema says.
  local v
  v="$(dirname "$SCHEMA")/conformance/valid/bc4-zstd-normals-slices.vff"
  inspect "$v" --format json
  expect_rc 0
  cp "$WORK/out" "$WORK/bc4.json"
  conforms "$WORK/bc4.json"
  tr -d ' \n' <"$WORK/bc4.json" >"$WORK/flat"
  grep -qF '"incompatFeatures":{"names":["zstd","bc4"],"value":5}' "$WORK/flat" || fail "bc4 feature names: $(cat "$WORK/flat" | head -c 600)"
  sed 's/"bc4"/"bc5"/' "$WORK/bc4.json" >"$WORK/bad.json"
  ! "$SCHEMA_CHECK" "$SCHEMA" "$WORK/bad.json" 2>/dev/null || fail "the schema accepted a feature name the tool never prints"
  inspect "$v"
  expect_rc 0
  expect_out "(zstd, bc4)"
}

test_json_values() {
  inspect "$FIXTURES/big.vff" --format json
  expect_rc 0
  expect_out '"rawBytes": 17309696,'
  expect_out '"rawBytes": 69238784,'
  expect_out '"mapCount": 4226,'
  inspect "$FIXTURES/known.vff" --format json --histogram-bins 2
  expect_rc 0
  expect_out '"hits": 150,'
  expect_out '"hitRatio": 0.9375,'
  expect_out '"count": 80,'
  expect_out '"count": 70,'
  expect_out '"headerChecksumStatus": "verified"'
  expect_out '"name": "known"'
}

test_json_validate_conforms() {
  inspect "$FIXTURES/known.vff" --format json --validate
  expect_rc 0
  cp "$WORK/out" "$WORK/valid.json"
  conforms "$WORK/valid.json"
  inspect "$FIXTURES/corrupt.vff" --format json --validate
  expect_rc 3
  cp "$WORK/out" "$WORK/corrupt.json"
  conforms "$WORK/corrupt.json"
  expect_out '"id": 6009,'
  expect_out '"name": "block-checksum",'
  expect_out '"valid": false,'
  expect_out '"checksumStatus": "failed"'
  # Not a .vff at all: only the validation report.
  inspect "$FIXTURES/not-vff.txt" --format json --validate
  expect_rc 3
  cp "$WORK/out" "$WORK/not-vff.json"
  conforms "$WORK/not-vff.json"
  expect_out '"id": 2002,'
}

test_schema_checker_rejects() {
  # The checker used above must catch what it is there to catch.
  echo '{"file": "x.vff", "tool": {"name": "vff-inspect", "version": "0.1.0"}}' >"$WORK/bad1.json"
  ! "$SCHEMA_CHECK" "$SCHEMA" "$WORK/bad1.json" 2>/dev/null || fail "accepted a report with neither summary nor validation"
  inspect "$FIXTURES/known.vff" --format json
  sed 's/"mapCount": 10,/"mapCount": "10",/' "$WORK/out" >"$WORK/bad2.json"
  ! grep -q '"mapCount": 10,' "$WORK/bad2.json" || fail "sed did not change the document"
  ! "$SCHEMA_CHECK" "$SCHEMA" "$WORK/bad2.json" 2>/dev/null || fail "accepted a string mapCount"
  grep -v '"hitRatio"' "$WORK/out" >"$WORK/bad3.json"
  ! "$SCHEMA_CHECK" "$SCHEMA" "$WORK/bad3.json" 2>/dev/null || fail "accepted a report without hitRatio"
}

# ---- Validation ------------------------------------------------------------------------------------
test_validate_good() {
  local f
  for f in known small zstd chord bit1; do
    inspect "$FIXTURES/$f.vff" --validate
    expect_rc 0
    expect_no_err
    expect_out "validation:  valid, 0 errors, 0 warnings"
  done
}

test_validate_corrupt() {
  inspect "$FIXTURES/corrupt.vff" --validate
  expect_rc 3
  expect_out "validation:  INVALID"
  expect_out_re '^  error +6009 block-checksum \[DIST\] @0x[0-9a-f]+: '
  # The summary is still shown, with the damaged section marked.
  expect_out_re '^  DIST .* FAILED$'
  expect_out_re '^  FDSC .* verified OK$'
  expect_err "vff-inspect: error:"
}

test_validate_not_vff() {
  inspect "$FIXTURES/not-vff.txt" --validate
  expect_rc 3
  expect_out "2002 bad-magic"
  expect_err "bad-magic (2002)"
}

# ---- Preview ---------------------------------------------------------------------------------------
test_preview() {
  # 10 maps of 8x8: 4 columns x 3 rows of 9-pixel cells plus the closing separator.
  inspect "$FIXTURES/small.vff" --preview "$WORK/p.png" --maps 10
  expect_rc 0
  [[ "$(png_size "$WORK/p.png")" == "37 28" ]] || fail "preview is $(png_size "$WORK/p.png"), expected 37 28"
  expect_out "preview:     $WORK/p.png, 10 maps in 4 x 3 tiles, 37 x 28 pixels"
}

test_preview_default_maps() {
  # 64 maps of 64x64 by default: 8 x 8 tiles of 65 pixels plus 1.
  inspect "$FIXTURES/big.vff" --preview "$WORK/big.png" --format json
  expect_rc 0
  [[ "$(png_size "$WORK/big.png")" == "521 521" ]] || fail "preview is $(png_size "$WORK/big.png")"
  cp "$WORK/out" "$WORK/big.json"
  conforms "$WORK/big.json"
  expect_out '"width": 521'
}

test_preview_clamped() {
  # Asking for more maps than the field has shows them all: 10 maps of 4x4.
  inspect "$FIXTURES/known.vff" --preview "$WORK/k.png" --maps 1000
  expect_rc 0
  [[ "$(png_size "$WORK/k.png")" == "21 16" ]] || fail "preview is $(png_size "$WORK/k.png")"
  for f in bit1 chord zstd; do
    inspect "$FIXTURES/$f.vff" --preview "$WORK/$f.png" --maps 1
    expect_rc 0
    [[ "$(png_size "$WORK/$f.png")" == "10 10" ]] || fail "$f preview is $(png_size "$WORK/$f.png")"
  done
}

test_preview_no_partial_output() {
  # Invalid input: no PNG, and a file already there stays as it was.
  inspect "$FIXTURES/not-vff.txt" --preview "$WORK/p.png"
  expect_rc 3
  [[ ! -e $WORK/p.png ]] || fail "a preview was written for an invalid file"
  echo "old" >"$WORK/keep.png"
  inspect "$FIXTURES/corrupt.vff" --preview "$WORK/keep.png"
  expect_rc 3
  [[ "$(cat "$WORK/keep.png")" == "old" ]] || fail "an existing file was changed"
  rm "$WORK/keep.png"
  # Unwritable destination: an I/O error naming the file, and no temporary left behind.
  inspect "$FIXTURES/small.vff" --preview "$WORK/no-such-dir/p.png"
  expect_rc 2
  expect_no_out
  expect_err "vff-inspect: error: $WORK/no-such-dir/p.png"
  expect_err "io-write (1003)"
  mkdir "$WORK/ro"
  chmod 0555 "$WORK/ro"
  if ! touch "$WORK/ro/probe" 2>/dev/null; then  # (root ignores the mode)
    inspect "$FIXTURES/small.vff" --preview "$WORK/ro/p.png"
    expect_rc 2
  fi
  rm -f "$WORK/ro/probe"
  chmod 0755 "$WORK/ro"
  rmdir "$WORK/ro"
  no_leftovers "$WORK"
}

# ---- Dispatch --------------------------------------------------------------------------------------
[[ $# -eq 1 ]] || fail "usage: cli_tests.sh test_NAME"
run_test "$1"
