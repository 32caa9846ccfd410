#!/usr/bin/env bash
# gltf_tests.sh - vff-bake on glTF files that require extensions: compressed files bake the field of
# the plain one; an extension it cannot read is refused as unsupported (exit 5) with its name and the
# file's, before anything else about the file is judged. (The decoders' other cases are in
# test_gltf_extensions.cpp.)
#
# Every function named test_* is one ctest case bake.gltf.NAME (tests/bake/CMakeLists.txt):
# `bash gltf_tests.sh test_NAME` runs one. Environment:
#   VFF_BAKE     the vff-bake executable
#   VFF_INSPECT  the vff-inspect executable
#   GLTF_WRITE   the vff_gltf_write executable (tests/bake/gltf_write_main.cpp)
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_BAKE:?}" "${VFF_INSPECT:?}" "${GLTF_WRITE:?}" "${WORK:?}"

here="$(dirname "${BASH_SOURCE[0]}")"
source "$here/../common/cli_harness.sh"

# A triangle whose POSITION accessor has no data (as a compressed file's would look without its
# extension): tinygltf alone would fail on it.
gltf_json() {
  printf '{"asset":{"version":"2.0"},"extensionsUsed":[%s],"extensionsRequired":[%s],' "$1" "$1"
  printf '"meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}],'
  printf '"accessors":[{"componentType":5126,"count":3,"type":"VEC3","bufferView":7}],"nodes":[{"mesh":0}],'
  printf '"scenes":[{"nodes":[0]}],"scene":0}'
}

# A GLB holding JSON text $1 (padded with spaces to 4 bytes) and no BIN chunk.
glb_of() {
  local json="$1"
  while (( ${#json} % 4 )); do json+=" "; done
  python3 - "$json" <<'PY'
import struct, sys
j = sys.argv[1].encode()
sys.stdout.buffer.write(struct.pack('<III', 0x46546C67, 2, 20 + len(j)) + struct.pack('<II', len(j), 0x4E4F534A) + j)
PY
}

test_unknown_required_extension_is_unsupported() {
  gltf_json '"KHR_mesh_quantization","EXT_unheard_of"' >"$WORK/m.gltf"
  run "$VFF_BAKE" "$WORK/m.gltf" -o "$WORK/x.vff" -n 1 -m 8
  expect_rc 5
  expect_err "vff-bake: error:"
  expect_err "m.gltf: requires the glTF extension EXT_unheard_of"
  [[ ! -e $WORK/x.vff ]] || fail "output left behind"
  glb_of "$(gltf_json '"KHR_texture_basisu"')" >"$WORK/m.glb"
  run "$VFF_BAKE" "$WORK/m.glb" -o "$WORK/x.vff" -n 1 -m 8
  expect_rc 5
  expect_err "m.glb: requires the glTF extension KHR_texture_basisu"
  [[ ! -e $WORK/x.vff ]] || fail "output left behind"
}

# The supported extensions pass the check: this file then fails on its missing data, as invalid
# input (exit 3), not as an unsupported one.
test_supported_required_extensions_pass_the_check() {
  gltf_json '"KHR_mesh_quantization","KHR_draco_mesh_compression","EXT_meshopt_compression"' >"$WORK/m.gltf"
  run "$VFF_BAKE" "$WORK/m.gltf" -o "$WORK/x.vff" -n 1 -m 8
  expect_rc 3
  [[ ! -e $WORK/x.vff ]] || fail "output left behind"
}

# ---- Supported extensions ------------------------------------------------------------------------
# The torus knot as plain, Draco (sequential) and meshopt (index sequence) files, each "m.glb" in a
# folder of its own: these decoders give back the vertices and triangles in order, so the metadata
# (file name, format, hash of the mesh as read) and the field are the same, byte for byte.
test_compressed_files_bake_like_the_plain_one() {
  for k in plain draco meshopt; do
    mkdir -p "$WORK/$k"
    "$GLTF_WRITE" torus-knot "$k" "$WORK/$k/m.glb" || fail "vff_gltf_write $k"
    run "$VFF_BAKE" "$WORK/$k/m.glb" -o "$WORK/$k/m.vff" -n 66 -m 8 -q
    expect_rc 0
  done
  cmp "$WORK/plain/m.vff" "$WORK/draco/m.vff" || fail "the Draco file bakes another field"
  cmp "$WORK/plain/m.vff" "$WORK/meshopt/m.vff" || fail "the meshopt file bakes another field"
}

# Lossy encodings (16-bit quantization; meshopt's filters) and Draco's edgebreaker (vertices
# reordered) bake valid fields of the same mesh size.
test_lossy_and_reordered_files_bake() {
  for k in quantized draco-edgebreaker meshopt-filters; do
    "$GLTF_WRITE" torus-knot "$k" "$WORK/$k.glb" || fail "vff_gltf_write $k"
    run "$VFF_BAKE" "$WORK/$k.glb" -o "$WORK/$k.vff" -n 66 -m 8 -q
    expect_rc 0
    run "$VFF_INSPECT" "$WORK/$k.vff" --validate --format json
    expect_rc 0
    expect_out '"triangles": 8192'
  done
}

run_test "$1"
