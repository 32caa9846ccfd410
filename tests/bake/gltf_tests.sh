#!/usr/bin/env bash
# gltf_tests.sh - vff-bake on glTF files that require extensions: an extension it cannot read is
# refused as unsupported (exit 5) with its name and the file's, before anything else about the file
# is judged. (Decoding of the supported ones is checked in test_gltf_extensions.cpp.)
#
# Every function named test_* is one ctest case bake.gltf.NAME (tests/bake/CMakeLists.txt):
# `bash gltf_tests.sh test_NAME` runs one. Environment:
#   VFF_BAKE     the vff-bake executable
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_BAKE:?}" "${WORK:?}"

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

run_test "$1"
