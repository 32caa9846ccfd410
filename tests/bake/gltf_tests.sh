#!/usr/bin/env bash
# gltf_tests.sh - vff-bake on glTF files that require extensions: compressed files bake the field of
# the plain one; an extension that changes geometry it cannot read is refused as unsupported (exit 5)
# with its name and the file's, before anything else about the file is judged; one that changes no
# geometry (materials, textures) is left unread with a warning. Skins and morph targets: warnings. (The decoders' other cases are in
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
  expect_err "vff-bake: error: $WORK/m.gltf: mesh-unsupported (10003): requires the glTF extension EXT_unheard_of,"
  [[ ! -e $WORK/x.vff ]] || fail "output left behind"
  glb_of "$(gltf_json '"KHR_texture_basisu","EXT_mesh_gpu_instancing"')" >"$WORK/m.glb"
  run "$VFF_BAKE" "$WORK/m.glb" -o "$WORK/x.vff" -n 1 -m 8
  expect_rc 5
  expect_err "vff-bake: error: $WORK/m.glb: mesh-unsupported (10003): requires the glTF extension EXT_mesh_gpu_instancing,"
  [[ ! -e $WORK/x.vff ]] || fail "output left behind"
}

# tet_gltf [KEY=VALUE...]: a glTF tetrahedron (mesh 'Tet' at node 0 'Body', positions in a data: URI)
# on stdout. required=NAMES (comma-separated, JSON-quoted) lists extensionsRequired; skin=1 gives
# node 0 a skin with joint node 1; morph=1 gives the primitive a morph target and the mesh a weight;
# uri=NAME makes the buffer the external file NAME; flat=1 puts every vertex at the origin.
tet_gltf() {
  python3 - "$@" <<'PY'
import base64, json, struct, sys
opt = dict(a.split('=', 1) for a in sys.argv[1:])
pos = [0] * 12 if opt.get("flat") == "1" else [0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1]
idx = [0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3]
data = struct.pack('<12f', *pos) + struct.pack('<12H', *idx)
doc = {"asset": {"version": "2.0"},
       "buffers": [{"byteLength": len(data), "uri": "data:application/octet-stream;base64," + base64.b64encode(data).decode()}],
       "bufferViews": [{"buffer": 0, "byteLength": 48}, {"buffer": 0, "byteOffset": 48, "byteLength": 24}],
       "accessors": [{"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [0, 0, 0], "max": [1, 1, 1]},
                     {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}],
       "meshes": [{"name": "Tet", "primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
       "nodes": [{"name": "Body", "mesh": 0}], "scenes": [{"nodes": [0]}], "scene": 0}
if opt.get("required"):
    names = json.loads("[" + opt["required"] + "]")
    doc["extensionsUsed"] = doc["extensionsRequired"] = names
if opt.get("skin") == "1":
    doc["nodes"][0]["skin"] = 0
    doc["nodes"].append({"name": "Root"})
    doc["scenes"][0]["nodes"].append(1)
    doc["skins"] = [{"joints": [1]}]
if opt.get("uri"):
    doc["buffers"][0]["uri"] = opt["uri"]
if opt.get("morph") == "1":
    doc["meshes"][0]["primitives"][0]["targets"] = [{"POSITION": 0}]
    doc["meshes"][0]["weights"] = [0.5]
print(json.dumps(doc))
PY
}

# bake_tet NAME ARGS...: tet_gltf ARGS... as $WORK/NAME/t.gltf baked to $WORK/NAME/t.vff (the same file
# name in every folder, so that the fields' metadata are the same when the geometry is).
bake_tet() {
  local name=$1
  shift
  mkdir -p "$WORK/$name"
  tet_gltf "$@" >"$WORK/$name/t.gltf"
  run "$VFF_BAKE" "$WORK/$name/t.gltf" -o "$WORK/$name/t.vff" -n 1 -m 8 -q
}

# Extensions that change materials or textures only (a real file: SheenCloth.glb requires
# KHR_texture_transform) do not stop the bake: the field is the plain file's, with a warning naming
# each extension left unread.
test_geometry_free_extensions_bake_like_the_plain_file() {
  bake_tet plain
  expect_rc 0
  expect_no_err
  bake_tet ext 'required="KHR_texture_transform","KHR_materials_sheen","KHR_texture_basisu","EXT_texture_webp","KHR_mesh_quantization"'
  expect_rc 0
  local e
  for e in KHR_texture_transform KHR_materials_sheen KHR_texture_basisu EXT_texture_webp; do
    expect_err "vff-bake: warning: $WORK/ext/t.gltf: requires the glTF extension $e, which changes no geometry: not read"
  done
  [[ $(grep -c warning "$WORK/err") -eq 4 ]] || { show; fail "expected 4 warnings (none for KHR_mesh_quantization)"; }
  cmp "$WORK/plain/t.vff" "$WORK/ext/t.vff" || fail "the file requiring material extensions bakes another field"
}

# A skinned node is baked in its bind pose (the field of the same mesh without the skin), with a
# warning naming the node, its mesh and its skin; --split says the same.
test_skinned_node_bakes_its_bind_pose_with_a_warning() {
  bake_tet plain
  bake_tet skin skin=1
  expect_rc 0
  expect_err "vff-bake: warning: $WORK/skin/t.gltf: node 0 'Body' (mesh 0) has skin 0: baked in its bind pose, not posed by its joints"
  [[ $(grep -c warning "$WORK/err") -eq 1 ]] || { show; fail "expected one warning"; }
  cmp "$WORK/plain/t.vff" "$WORK/skin/t.vff" || fail "the skinned file bakes another field than its bind pose"
  run "$VFF_BAKE" "$WORK/skin/t.gltf" --split node -o "$WORK/skin/s.vffscene.json" -n 1 -m 8 -q
  expect_rc 0
  expect_err "vff-bake: warning: $WORK/skin/t.gltf: node 0 'Body' (mesh 0) has skin 0: baked in its bind pose"
}

# A mesh with morph targets is baked as its base shape, with a warning naming the mesh.
test_morph_targets_bake_the_base_shape_with_a_warning() {
  bake_tet plain
  bake_tet morph morph=1
  expect_rc 0
  expect_err "vff-bake: warning: $WORK/morph/t.gltf: mesh 0 'Tet' has morph targets: baked as its base shape, its weights not applied"
  [[ $(grep -c warning "$WORK/err") -eq 1 ]] || { show; fail "expected one warning"; }
  cmp "$WORK/plain/t.vff" "$WORK/morph/t.vff" || fail "the morphed file bakes another field than its base shape"
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

# A buffer uri naming a FIFO is refused as the input itself would be (exit 2, naming both files),
# not waited on: tinygltf reads external files through the baker's reader.
test_fifo_buffer_is_refused() {
  mkdir -p "$WORK/f"
  mkfifo "$WORK/f/buffer.bin"
  tet_gltf uri=buffer.bin >"$WORK/f/t.gltf"
  run timeout 20 "$VFF_BAKE" "$WORK/f/t.gltf" -o "$WORK/f/t.vff" -n 1 -m 8 -q
  [[ $RC -ne 124 ]] || fail "vff-bake blocked on the FIFO buffer"
  expect_rc 2
  expect_err "vff-bake: error: $WORK/f/t.gltf: io-open (1001): $WORK/f/buffer.bin: not a regular file"
  [[ ! -e $WORK/f/t.vff ]] || fail "output left behind"
}

# A mesh of a --split that cannot be baked is named after the file, which is named once.
test_split_names_the_file_once() {
  mkdir -p "$WORK/flat"
  tet_gltf flat=1 >"$WORK/flat/t.gltf"
  run "$VFF_BAKE" "$WORK/flat/t.gltf" --split mesh -o "$WORK/flat/s.vffscene.json" -n 1 -m 8 -q
  expect_rc 3
  expect_err "vff-bake: error: $WORK/flat/t.gltf: mesh-degenerate (10006): mesh 0 'Tet': all 4 triangles have zero area"
  [[ $(grep -o -F "t.gltf" "$WORK/err" | wc -l) -eq 1 ]] || { show; fail "the file is named more than once"; }
  [[ -z $(ls "$WORK/flat" | grep -v t.gltf) ]] || fail "files left behind"
}

run_test "$1"
