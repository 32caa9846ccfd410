#!/usr/bin/env bash
# limits_tests.sh - hostile inputs that claim huge sizes: every tool that reads them must reject them
# with a clear error (exit 3, the file and the rule named on stderr), write nothing, and stay within
# a bounded peak memory.
#
# The inputs come from vff_limits_gen (gen.cpp: .vff files claiming 2^24 maps, 4 GiB blocks, 2^64
# offsets...; meshes claiming 10^9 faces) and from spec/conformance/invalid. Each tool runs under
# vff_peak_rss (peak_rss.cpp), which reports its exit code, its peak resident memory (ru_maxrss) and
# its time; the test asserts the exit code, the message and PEAK <= VFF_LIMITS_PEAK_MIB. Times are
# reported, not asserted (only a generous kill after 120 s guards against a hang).
#
# Every function named test_* is one ctest case (tests/limits/CMakeLists.txt finds them here);
# `bash limits_tests.sh test_NAME` runs one. Environment:
#   GEN PEAK               vff_limits_gen and vff_peak_rss
#   VFF_INSPECT VFF_CONVERT VFF_BAKE   the tools (VFF_BAKE may be empty: the mesh cases then skip)
#   VFF_LIMITS_PEAK_MIB    the memory bound in MiB (64; more under the sanitizers)
#   CONFORMANCE            spec/conformance
#   WORK                   a scratch folder of this test
#   VFF_LIMITS_REPORT      optional: a file to which each run appends a table row (scripts/limits-report.sh)
#   VFF_LIMITS_ALL         optional: 1 also runs the known issues listed below instead of skipping them
set -euo pipefail
: "${GEN:?}" "${PEAK:?}" "${VFF_INSPECT:?}" "${VFF_CONVERT:?}" "${VFF_LIMITS_PEAK_MIB:?}" "${CONFORMANCE:?}" "${WORK:?}"
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"

# Tool runs that are known to exceed the bound, with the reason; skipped (not run: each takes
# gigabytes and tens of seconds) unless VFF_LIMITS_ALL=1. Delete a line once its cause is fixed.
declare -A KNOWN=(
  ["vff-convert vff-bomb-blocks-4gib.vff"]="a valid field of 4 GiB: vff-convert holds the whole decoded field (one copy: 4 GiB; ReadOptions::maxPayloadBytes bounds it), and re-encodes it (about 4.1 GiB and 16 s with VFF_LIMITS_ALL=1)"
)

# measure EXPECTED_RC EXPECTED_TEXT INPUT CMD...: runs CMD under vff_peak_rss, appends a report row,
# and checks the exit code, that stderr names INPUT and holds EXPECTED_TEXT, and the peak memory
# (at most MEASURE_BOUND_MIB where set, else VFF_LIMITS_PEAK_MIB).
# (Bash builtins only, apart from the run itself: the suite runs a few hundred of these.)
measure() {
  local want_rc=$1 want_text=$2 input=$3
  shift 3
  local tool="${1##*/}" name="${input##*/}"
  local key="$tool $name"
  if [[ -n ${KNOWN[$key]:-} && ${VFF_LIMITS_ALL:-0} != 1 ]]; then
    echo "KNOWN ISSUE, not run: $key: ${KNOWN[$key]}"
    return 0
  fi
  local line rc kib secs err="" first="" id="-"
  line="$("$PEAK" 120 "$WORK/out" "$WORK/err" "$@")" || fail "vff_peak_rss could not run $*"
  read -r rc kib secs <<<"$line"
  IFS= read -r -d '' err <"$WORK/err" || true
  first="${err%%$'\n'*}"
  local mib=$(((kib + 1023) / 1024))
  if [[ $first =~ ([a-z0-9-]+\ \([0-9]+\)) ]]; then id="${BASH_REMATCH[1]}"; fi
  if [[ -n ${VFF_LIMITS_REPORT:-} ]]; then
    local args="${*:2}"
    args="${args//$WORK\//}"
    args="${args//$CONFORMANCE\//}"
    printf '| %s | %s %s | %s | %s | %s | %s |\n' "$name" "$tool" "$args" "$rc" "$mib" "$secs" "$id" \
      >>"$VFF_LIMITS_REPORT"
  fi
  echo "$key: exit $rc, peak $mib MiB, $secs s: ${first:0:300}"
  [[ $rc -eq $want_rc ]] || { echo "$err" >&2; fail "$key: exit code $rc, expected $want_rc"; }
  if [[ $want_rc -ne 0 ]]; then
    [[ $err == *"$name"* ]] || { echo "$err" >&2; fail "$key: stderr does not name the input"; }
    [[ $err == *"$want_text"* ]] || { echo "$err" >&2; fail "$key: stderr lacks '$want_text'"; }
  fi
  local bound=${MEASURE_BOUND_MIB:-$VFF_LIMITS_PEAK_MIB}
  [[ $mib -le $bound ]] || fail "$key: peak memory $mib MiB, above the bound of $bound MiB"
}

# nothing_written: no output file and no temporary in $WORK/o.
nothing_written() {
  local left
  left="$(ls -A "$WORK/o")"
  [[ -z $left ]] || fail "files written: $left"
}

# vff_case INPUT ERROR: every reader of .vff files rejects the generated INPUT with the diagnostic
# ERROR (a name and ID such as "block-decode (6010)").
vff_case() {
  local input="$WORK/$1" want=$2
  "$GEN" "$1" "$input" || fail "vff_limits_gen $1"
  mkdir -p "$WORK/o"
  measure 3 "$want" "$input" "$VFF_INSPECT" "$input" --validate
  measure 3 "$want" "$input" "$VFF_INSPECT" "$input" --format json
  measure 3 "$want" "$input" "$VFF_CONVERT" "$input" --to vff "$WORK/o/out.vff"
  measure 3 "$want" "$input" "$VFF_CONVERT" "$input" --to exr "$WORK/o/out.exr"
  nothing_written
}

# mesh_case INPUT ERROR: vff-bake rejects the generated mesh INPUT with the diagnostic ERROR.
mesh_case() {
  [[ -n ${VFF_BAKE:-} ]] || { echo "SKIP: vff-bake is not built"; exit 77; }
  local input="$WORK/$1" want=$2
  "$GEN" "$1" "$input" || fail "vff_limits_gen $1"
  mkdir -p "$WORK/o"
  measure 3 "$want" "$input" "$VFF_BAKE" "$input" -o "$WORK/o/out.vff" -n 1 -m 8 -q
  nothing_written
}

# ---- .vff: header and section table ---------------------------------------------------------------
test_vff_file_size_2e63() { vff_case vff-file-size-2e63.vff "file-size-mismatch (3002)"; }
test_vff_section_count_4e9() { vff_case vff-section-count-4e9.vff "section-count (3007)"; }
test_vff_table_offset_2e64() { vff_case vff-table-offset-2e64.vff "section-table (3006)"; }
test_vff_section_offset_2e64() { vff_case vff-section-offset-2e64.vff "section-bounds (4001)"; }
test_vff_section_size_2e62() { vff_case vff-section-size-2e62.vff "section-bounds (4001)"; }
test_vff_meta_raw_64mib() { vff_case vff-meta-raw-64mib.vff "section-decode (4011)"; }
test_vff_meta_frame_64mib() { vff_case vff-meta-frame-64mib.vff "section-decode (4011)"; }
# ---- .vff: field description ------------------------------------------------------------------------
test_vff_map_count_2e24p1() { vff_case vff-map-count-2e24p1.vff "position-scheme (5002)"; }
test_vff_payload_512tib() { vff_case vff-payload-512tib.vff "decoded-limit (5011)"; }
# ---- .vff: plane and blocks ---------------------------------------------------------------------------
test_vff_blocks_2e24() { vff_case vff-blocks-2e24.vff "block-bounds (6003)"; }
test_vff_block_offset_2e64() { vff_case vff-block-offset-2e64.vff "block-bounds (6003)"; }
test_vff_block_stored_2e63() { vff_case vff-block-stored-2e63.vff "block-bounds (6003)"; }
# (The two 4 GiB blocks meet the block limit, ReadOptions::maxBlockBytes, before their frames are
# looked at; vff-block-frame-stored still reaches the frame check.)
test_vff_block_raw_4gib() { vff_case vff-block-raw-4gib.vff "decoded-limit (5011)"; }
test_vff_block_frame_4gib() { vff_case vff-block-frame-4gib.vff "decoded-limit (5011)"; }
test_vff_block_frame_stored() { vff_case vff-block-frame-stored.vff "block-decode (6010)"; }
# ---- .vff: real zstd bombs (valid frames and checksums) -----------------------------------------------
# One block whose 128 KiB frame really decodes to 4 GiB: refused at open by ReadOptions::maxBlockBytes
# (64 MiB), before anything is decoded.
test_vff_bomb_block_4gib() {
  vff_case vff-bomb-block-4gib.vff "decoded-limit (5011)"
  grep -q -F "block 0 of 1 decodes to 4294963200 bytes, above the reader's limit of 67108864 bytes per block" \
    "$WORK/err" || { cat "$WORK/err" >&2; fail "the diagnostic does not name the block and the limit"; }
}
# A valid all-miss field of 4 GiB in 16384 blocks of 256 KiB (1.5 MiB of file): the readers that
# stream decode one block at a time (the validator, the statistics of the summary), within the bound.
test_vff_bomb_blocks_4gib() {
  local input="$WORK/vff-bomb-blocks-4gib.vff"
  "$GEN" vff-bomb-blocks-4gib.vff "$input" || fail "vff_limits_gen vff-bomb-blocks-4gib.vff"
  mkdir -p "$WORK/o"
  measure 0 "" "$input" "$VFF_INSPECT" "$input" --validate
  measure 0 "" "$input" "$VFF_INSPECT" "$input" --format json
  grep -q -E '"texels": 4294963200' "$WORK/out" || fail "the statistics did not count every texel"
  measure 0 "" "$input" "$VFF_CONVERT" "$input" --to vff "$WORK/o/out.vff"
}
# A valid all-miss field of 128 MiB in 512 zstd blocks: vff-convert holds the decoded field (once)
# while it rewrites it, and nothing of the payload's size besides: the bound is the payload plus the
# usual bound. (Its writer once kept a worst-case-sized buffer for every compressed block until the
# rewrite ended: a second copy of the payload, 304 MiB here.)
test_vff_miss_blocks_128mib() {
  local input="$WORK/vff-miss-blocks-128mib.vff"
  "$GEN" vff-miss-blocks-128mib.vff "$input" || fail "vff_limits_gen vff-miss-blocks-128mib.vff"
  mkdir -p "$WORK/o"
  MEASURE_BOUND_MIB=$((128 + VFF_LIMITS_PEAK_MIB)) measure 0 "" "$input" "$VFF_CONVERT" "$input" --to vff "$WORK/o/out.vff"
  "$VFF_INSPECT" "$WORK/o/out.vff" --validate >"$WORK/validate" 2>&1 || { cat "$WORK/validate" >&2; fail "the rewritten field does not validate"; }
  "$VFF_INSPECT" "$WORK/o/out.vff" --format json >"$WORK/json" || fail "vff-inspect of the rewritten field"
  grep -q -E '"texels": 134217728' "$WORK/json" || fail "the rewritten field does not hold 2^27 texels"
}
# ---- EXR (vff-convert's input) -------------------------------------------------------------------------
test_exr_slice_16k() {
  local input="$WORK/exr-slice-16k.exr"
  "$GEN" exr-slice-16k.exr "$input" || fail "vff_limits_gen exr-slice-16k.exr"
  mkdir -p "$WORK/o"
  measure 3 "section-decode (4011)" "$input" "$VFF_CONVERT" "$input" --to vff "$WORK/o/out.vff"
  # Read in bands of tile rows: the first band already meets the missing pixels.
  grep -q -F "Scan line 0 is missing" "$WORK/err" || fail "the diagnostic does not say what is missing"
  nothing_written
}
# ---- Meshes ---------------------------------------------------------------------------------------------
test_mesh_ply_ascii_1e9_faces() { mesh_case ply-ascii-1e9-faces.ply "mesh-parse (10002)"; }
test_mesh_ply_binary_1e9_faces() { mesh_case ply-binary-1e9-faces.ply "mesh-parse (10002)"; }
test_mesh_ply_binary_1e9_vertices() { mesh_case ply-binary-1e9-vertices.ply "mesh-parse (10002)"; }
test_mesh_off_1e9_faces() { mesh_case off-1e9-faces.off "mesh-parse (10002)"; }
test_mesh_off_1e8_faces() { mesh_case off-1e8-faces.off "mesh-parse (10002)"; }
test_mesh_stl_binary_1e9_faces() { mesh_case stl-binary-1e9-faces.stl "claims 1000000000 triangles"; }
test_mesh_obj_index_1e9() { mesh_case obj-index-1e9.obj "mesh-parse (10002)"; }
test_mesh_gltf_accessor_1e9() { mesh_case gltf-accessor-1e9.gltf "accessor of 1000000000 elements"; }
test_mesh_gltf_indices_1e9() { mesh_case gltf-indices-1e9.gltf "accessor of 1000000000 elements"; }
test_mesh_gltf_accessor_wraps() { mesh_case gltf-accessor-wraps.gltf "accessor of 4611686018427387905 elements"; }
test_mesh_gltf_buffer_1e12() { mesh_case gltf-buffer-1e12.gltf "mesh-parse (10002)"; }
test_mesh_glb_accessor_1e9() { mesh_case glb-accessor-1e9.glb "accessor of 1000000000 elements"; }
test_mesh_glb_chunk_4gib() { mesh_case glb-chunk-4gib.glb "mesh-parse (10002)"; }

# Every input the generator makes has its case above, so none can silently go untested.
test_every_input_has_a_case() {
  local n fn missing=""
  for n in $("$GEN" --list); do
    fn="${n%.*}"
    fn="${fn//-/_}"
    case "$n" in vff-* | exr-*) fn="test_$fn" ;; *) fn="test_mesh_$fn" ;; esac
    declare -F "$fn" >/dev/null || missing+=" $n ($fn)"
  done
  [[ -z $missing ]] || fail "inputs without a test case:$missing"
}

# The conformance suite's invalid vectors: the validator rejects each (exit 3, its ID named) within
# the bound. (vff-convert meets the same reader through File::open; the cases above run it.)
test_conformance_invalid_vectors() {
  local v id count=0
  for v in "$CONFORMANCE"/invalid/*/*.vff; do
    id="${v%/*}"
    id="${id##*/}"
    measure 3 "($id)" "$v" "$VFF_INSPECT" "$v" --validate
    count=$((count + 1))
  done
  [[ $count -ge 50 ]] || fail "only $count invalid vectors found under $CONFORMANCE/invalid"
}

# ---- Runner --------------------------------------------------------------------------------------------
[[ $# -eq 1 && $1 == test_* ]] || { echo "usage: $0 test_NAME" >&2; exit 2; }
run_test "$1"
