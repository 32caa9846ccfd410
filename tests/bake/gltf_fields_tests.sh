#!/usr/bin/env bash
# gltf_fields_tests.sh - vff-bake SCENE -o X.glb: a field per mesh attached with the glTF extension
# VFF_visibility_field (spec/gltf/VFF_visibility_field/README.md), and what readGltfFields reads
# back (through `vff_gltf_write read`, which prints its report as JSON).
#
# Every function named test_* is one ctest case (tests/bake/CMakeLists.txt finds them in this file):
# `bash gltf_fields_tests.sh test_NAME` runs one. Environment:
#   VFF_BAKE     the vff-bake executable
#   VFF_INSPECT  the vff-inspect executable
#   MESHGEN      the vff-procedural-mesh executable (--gltf-scene writes the sample scene)
#   GLTF_WRITE   the vff_gltf_write executable (tests/bake/gltf_write_main.cpp)
#   MESHES       the folder of the shared meshes (suzanne.obj, spot.obj); tests that need them skip
#                with the reason when they are absent
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_BAKE:?}" "${VFF_INSPECT:?}" "${MESHGEN:?}" "${GLTF_WRITE:?}" "${MESHES:?}" "${WORK:?}"

here="$(dirname "${BASH_SOURCE[0]}")"
source "$here/../common/cli_harness.sh"
bake() { run "$VFF_BAKE" "$@"; }
small=(-n 2 -m 8 -q)
# The report of FILE as $WORK/FILE.report.json; py EXPR evaluates EXPR with r bound to it.
report() { "$GLTF_WRITE" read "$1" >"$1.report.json" || fail "vff_gltf_write read $1"; }
check() {  # check FILE PYTHON-EXPR EXPECTED
  local got
  got=$(python3 -c "import json,sys; r=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$1.report.json" "$2")
  [[ $got == "$3" ]] || fail "$1: $2 is $got, expected $3"
}
scene() { "$GLTF_WRITE" scene "$@" || fail "vff_gltf_write scene $*"; }
# No file of this run's temporaries (.NAME.tmp-PID-N) left in $WORK.
no_temporaries() {
  local left
  left=$(find "$WORK" -name '.*.tmp-*' | head -3)
  [[ -z $left ]] || fail "temporaries left: $left"
}
# Checks the container: the binary chunk's data and each field's bufferView at file offsets that
# are multiples of 64, the extension in extensionsUsed and not in extensionsRequired.
check_layout() {
  python3 - "$1" <<'PY' || fail "$1: layout"
import json, struct, sys
b = open(sys.argv[1], 'rb').read()
magic, version, length = struct.unpack_from('<III', b, 0)
assert magic == 0x46546C67 and version == 2 and length == len(b), 'header'
jl, jt = struct.unpack_from('<II', b, 12)
doc = json.loads(b[20:20 + jl])
bl, bt = struct.unpack_from('<II', b, 20 + jl)
start = 28 + jl
assert bt == 0x004E4942 and start % 64 == 0, 'BIN chunk at %d' % start
assert 'VFF_visibility_field' in doc['extensionsUsed']
assert 'VFF_visibility_field' not in doc.get('extensionsRequired', [])
# One buffer with data, the binary chunk; any other is a meshopt fallback without data.
assert all('uri' not in b for b in doc['buffers'])
assert all('EXT_meshopt_compression' in b.get('extensions', {}) for b in doc['buffers'][1:])
for m in doc['meshes']:
    if 'VFF_visibility_field' not in m.get('extensions', {}):
        continue
    e = m['extensions']['VFF_visibility_field']
    v = doc['bufferViews'][e['bufferView']]
    assert (start + v.get('byteOffset', 0)) % 64 == 0, 'payload at %d' % (start + v['byteOffset'])
    assert e['mimeType'] == 'application/vnd.vff' and 'byteStride' not in v
PY
}

# The fields of `-o x.glb` are the bytes --split mesh writes, mesh by mesh; here the meshes of
# vff_gltf_write's scene (A at two similarity nodes, B at one and at a non-uniform scale).
payloads_equal_split() {  # A B
  scene "$WORK/s.glb" "$1" "$2"
  bake "$WORK/s.glb" -o "$WORK/x.glb" "${small[@]}"
  expect_rc 0
  bake "$WORK/s.glb" --split mesh -o "$WORK/sp.vffscene.json" "${small[@]}"
  expect_rc 0
  for m in 0 1; do
    "$GLTF_WRITE" extract "$WORK/x.glb" $m "$WORK/e$m.vff" || fail "extract mesh $m"
    cmp "$WORK/e$m.vff" "$WORK/sp.mesh$m.vff" || fail "mesh $m: the payload differs from --split mesh's file"
  done
  check_layout "$WORK/x.glb"
}

test_payloads_are_the_split_mesh_files() {
  payloads_equal_split box torus-knot
}

test_payloads_of_shared_meshes_are_the_split_mesh_files() {
  if [[ ! -f $MESHES/suzanne.obj || ! -f $MESHES/spot.obj ]]; then
    echo "SKIP: $MESHES has no suzanne.obj and spot.obj"
    return 0
  fi
  payloads_equal_split "$MESHES/suzanne.obj" "$MESHES/spot.obj"
  report "$WORK/x.glb"
  check "$WORK/x.glb" "[(f['mesh'], f['match'], f['usable']) for f in r['fields']]" "[(0, 'exact', True), (1, 'exact', True)]"
}

test_sample_scene_mesh_under_stretch_only_is_baked_in_its_frame() {
  "$MESHGEN" --gltf-scene "$WORK/s.gltf" || fail "vff-procedural-mesh --gltf-scene"
  bake "$WORK/s.gltf" -o "$WORK/x.glb" "${small[@]}"
  expect_rc 0
  bake "$WORK/s.gltf" --split mesh -o "$WORK/sp.vffscene.json" "${small[@]}"
  "$GLTF_WRITE" extract "$WORK/x.glb" 0 "$WORK/e0.vff" || fail "extract mesh 0"
  cmp "$WORK/e0.vff" "$WORK/sp.mesh0.vff" || fail "the box's payload differs from --split mesh's file"
  # The knot is used by node 3 alone, under a non-uniform scale: --split mesh bakes that in, the
  # .glb never does; its field is in the mesh's frame and matches the mesh exactly.
  "$GLTF_WRITE" extract "$WORK/x.glb" 1 "$WORK/e1.vff" || fail "extract mesh 1"
  ! cmp -s "$WORK/e1.vff" "$WORK/sp.mesh1.node3.vff" || fail "the knot's field has node 3's scale baked in"
  report "$WORK/x.glb"
  check "$WORK/x.glb" "[(f['mesh'], f['match']) for f in r['fields']]" "[(0, 'exact'), (1, 'exact')]"
  check "$WORK/x.glb" "[(n['node'], n['answered'], n['reason']) for n in r['fields'][1]['nodes']]" "[(3, False, 'non-uniform scale')]"
  check "$WORK/x.glb" "[(p['rule'], p['severity'], p['path']) for p in r['problems']]" "[(14104, 'note', '/nodes/3')]"
  check_layout "$WORK/x.glb"
  valid "$WORK/e1.vff"
}

test_reader_finds_every_field_exact_and_the_nodes() {
  scene "$WORK/s.glb" box torus-knot
  bake "$WORK/s.glb" -o "$WORK/x.glb" "${small[@]}"
  expect_rc 0
  report "$WORK/x.glb"
  check "$WORK/x.glb" "r['meshes']" "2"
  check "$WORK/x.glb" "[(f['mesh'], f['name'], f['valid'], f['match'], f['usable']) for f in r['fields']]" \
    "[(0, 'A', True, 'exact', True), (1, 'B', True, 'exact', True)]"
  check "$WORK/x.glb" "all(f['geometryHash'] == f['meshGeometryHash'] and f['min'] == f['meshMin'] and f['max'] == f['meshMax'] for f in r['fields'])" "True"
  check "$WORK/x.glb" "[[(n['node'], n['answered']) for n in f['nodes']] for f in r['fields']]" \
    "[[(0, True), (1, True)], [(2, True), (3, False)]]"
  check "$WORK/x.glb" "[(p['rule'], p['name'], p['severity']) for p in r['problems']]" \
    "[(14104, 'gltf-node-no-field', 'note')]"
  check "$WORK/x.glb" "r['problems'][0]['message'].startswith('$WORK/x.glb: /nodes/3: gltf-node-no-field (14104): node 3')" "True"
  # The payload's META names the same geometry as the extension.
  "$GLTF_WRITE" extract "$WORK/x.glb" 1 "$WORK/e1.vff" || fail "extract"
  valid "$WORK/e1.vff"
  run "$VFF_INSPECT" "$WORK/e1.vff" --format json
  expect_out "$(python3 -c "import json; print(json.load(open('$WORK/x.glb.report.json'))['fields'][1]['geometryHash'])")"
}

test_json_summary_names_each_field() {
  scene "$WORK/s.glb" box torus-knot
  run "$VFF_BAKE" "$WORK/s.glb" -o "$WORK/x.glb" -n 2 -m 8 --json
  expect_rc 0
  python3 - "$WORK/out" "$WORK/x.glb" <<'PY' || { show; fail "--json summary"; }
import json, sys
s = json.load(open(sys.argv[1]))
assert s['output'] == sys.argv[2] and s['scene'] == 0, s
assert [(f['mesh'], f['name'], f['triangles']) for f in s['fields']] == [(0, 'A', 12), (1, 'B', 8192)], s['fields']
assert all(isinstance(f['bufferView'], int) and len(f['geometryHash']) == 16 and f['fileBytes'] > 0 for f in s['fields'])
PY
}

test_external_fields_are_the_split_mesh_files() {
  scene "$WORK/s.glb" box torus-knot
  bake "$WORK/s.glb" -o "$WORK/x.glb" --external-fields "${small[@]}"
  expect_rc 0
  bake "$WORK/s.glb" --split mesh -o "$WORK/sp.vffscene.json" "${small[@]}"
  for m in 0 1; do
    cmp "$WORK/x.mesh$m.vff" "$WORK/sp.mesh$m.vff" || fail "mesh $m: x.mesh$m.vff differs from --split mesh's file"
  done
  report "$WORK/x.glb"
  check "$WORK/x.glb" "[(f['mesh'], f['uri'], f['bufferView'], f['match']) for f in r['fields']]" \
    "[(0, 'x.mesh0.vff', -1, 'exact'), (1, 'x.mesh1.vff', -1, 'exact')]"
  no_temporaries
  # The uri is relative to the .glb: moved together, they still read.
  mkdir "$WORK/moved"
  mv "$WORK/x.glb" "$WORK/x.mesh0.vff" "$WORK/x.mesh1.vff" "$WORK/moved/"
  report "$WORK/moved/x.glb"
  check "$WORK/moved/x.glb" "[f['usable'] for f in r['fields']]" "[True, True]"
  # Without the field files: gltf-uri, an I/O problem.
  rm "$WORK/moved/x.mesh1.vff"
  report "$WORK/moved/x.glb"
  check "$WORK/moved/x.glb" "[(p['rule'], p['path']) for p in r['problems'] if p['severity'] == 'error']" \
    "[(14007, '/meshes/1/extensions/VFF_visibility_field/uri')]"
}

test_same_bytes_any_thread_count() {
  scene "$WORK/s.glb" box torus-knot
  bake "$WORK/s.glb" -o "$WORK/a.glb" -j1 "${small[@]}"
  expect_rc 0
  bake "$WORK/s.glb" -o "$WORK/b.glb" -j2 "${small[@]}"
  expect_rc 0
  cmp "$WORK/a.glb" "$WORK/b.glb" || fail "-j1 and -j2 give different .glb files"
}

test_draco_reencode_is_close_and_lossless_is_exact() {
  "$GLTF_WRITE" torus-knot plain "$WORK/plain.glb" || fail "plain"
  bake "$WORK/plain.glb" -o "$WORK/f.glb" "${small[@]}"
  expect_rc 0
  # The same mesh re-encoded with Draco, with the field of the plain file attached.
  for kind in draco draco-edgebreaker draco-q14; do
    "$GLTF_WRITE" torus-knot $kind "$WORK/$kind.glb" || fail "$kind"
    "$GLTF_WRITE" attach "$WORK/$kind.glb" "$WORK/f.glb" "$WORK/$kind.f.glb" || fail "attach $kind"
    report "$WORK/$kind.f.glb"
  done
  check "$WORK/draco.f.glb" "[(f['match'], f['usable']) for f in r['fields']]" "[('exact', True)]"
  check "$WORK/draco-edgebreaker.f.glb" "[(f['match'], f['usable']) for f in r['fields']]" "[('exact', True)]"
  check "$WORK/draco-q14.f.glb" "[(f['match'], f['usable']) for f in r['fields']]" "[('close', True)]"
  check "$WORK/draco-q14.f.glb" "0 < r['fields'][0]['boundsDifference'] <= r['fields'][0]['tolerance']" "True"
  check "$WORK/draco-q14.f.glb" "[(p['rule'], p['severity']) for p in r['problems']]" "[(14102, 'note')]"
  check_layout "$WORK/draco-q14.f.glb"
}

test_moved_mesh_is_a_mismatch() {
  "$GLTF_WRITE" torus-knot plain "$WORK/plain.glb" || fail "plain"
  bake "$WORK/plain.glb" -o "$WORK/f.glb" "${small[@]}"
  "$GLTF_WRITE" torus-knot moved "$WORK/moved.glb" || fail "moved"
  "$GLTF_WRITE" attach "$WORK/moved.glb" "$WORK/f.glb" "$WORK/moved.f.glb" || fail "attach"
  report "$WORK/moved.f.glb"
  check "$WORK/moved.f.glb" "[(f['valid'], f['match'], f['usable']) for f in r['fields']]" "[(True, 'mismatch', False)]"
  check "$WORK/moved.f.glb" "[(p['rule'], p['severity']) for p in r['problems']]" "[(14103, 'warning')]"
  check "$WORK/moved.f.glb" "abs(r['fields'][0]['boundsDifference'] - 0.5) < 1e-6" "True"
}

test_rebake_replaces_the_earlier_field() {
  scene "$WORK/s.glb" box torus-knot
  bake "$WORK/s.glb" -o "$WORK/x.glb" "${small[@]}"
  bake "$WORK/x.glb" -o "$WORK/y.glb" -n 3 -m 8 -q
  expect_rc 0
  report "$WORK/y.glb"
  check "$WORK/y.glb" "[(f['mesh'], f['match']) for f in r['fields']]" "[(0, 'exact'), (1, 'exact')]"
  python3 - "$WORK/y.glb" <<'PY' || fail "y.glb"
import json, struct, sys
b = open(sys.argv[1], 'rb').read()
jl = struct.unpack_from('<I', b, 12)[0]
doc = json.loads(b[20:20 + jl])
assert doc['extensionsUsed'].count('VFF_visibility_field') == 1
PY
  "$GLTF_WRITE" extract "$WORK/y.glb" 0 "$WORK/y0.vff"
  run "$VFF_INSPECT" "$WORK/y0.vff" --format json
  expect_out '"mapCount": 50'  # -n 3: the new bake, not the old field
}

test_failing_bake_leaves_no_output() {
  scene "$WORK/s.glb" box torus-knot
  # A mesh without triangles (its only primitive is points).
  python3 - "$WORK/s.glb" "$WORK/p.glb" <<'PY'
import json, struct, sys
b = open(sys.argv[1], 'rb').read()
jl = struct.unpack_from('<I', b, 12)[0]
doc = json.loads(b[20:20 + jl])
doc['meshes'][1]['primitives'][0]['mode'] = 0
t = json.dumps(doc).encode()
t += b' ' * (-len(t) % 4)
rest = b[20 + jl:]
open(sys.argv[2], 'wb').write(struct.pack('<III', 0x46546C67, 2, 20 + len(t) + len(rest)) + struct.pack('<II', len(t), 0x4E4F534A) + t + rest)
PY
  bake "$WORK/p.glb" -o "$WORK/x.glb" "${small[@]}"
  [[ $RC -ne 0 ]] || fail "a mesh of points baked"
  expect_err "not triangles"
  [[ ! -e $WORK/x.glb ]] || fail "a failed bake wrote x.glb"
  bake "$WORK/p.glb" -o "$WORK/x.glb" --external-fields "${small[@]}"
  [[ ! -e $WORK/x.glb && ! -e $WORK/x.mesh0.vff ]] || fail "a failed bake wrote its outputs"
  # An output that cannot be written: its folder does not exist; an old output stays as it was.
  bake "$WORK/s.glb" -o "$WORK/none/x.glb" "${small[@]}"
  expect_rc 2
  [[ ! -e $WORK/none ]] || fail "the folder appeared"
  bake "$WORK/s.glb" -o "$WORK/old.glb" "${small[@]}"
  cp "$WORK/old.glb" "$WORK/old.copy"
  mkdir "$WORK/old.mesh1.vff"  # a folder where --external-fields would put mesh 1's field
  bake "$WORK/s.glb" -o "$WORK/old.glb" --external-fields -n 3 -m 8 -q
  expect_rc 2
  cmp "$WORK/old.glb" "$WORK/old.copy" || fail "the old .glb changed"
  [[ ! -e $WORK/old.mesh0.vff ]] || fail "a field of the refused set was put in place"
  no_temporaries
}

test_gltf_with_external_files_packs_into_one_glb() {
  scene "$WORK/s.gltf" box torus-knot
  [[ -f $WORK/s.bin && -f $WORK/s.png ]] || fail "the scene's .bin and .png"
  bake "$WORK/s.gltf" -o "$WORK/x.glb" "${small[@]}"
  expect_rc 0
  check_layout "$WORK/x.glb"
  # Self-contained: moved away from s.bin and s.png, it reads; its accessors hold the same bytes.
  mkdir "$WORK/away"
  mv "$WORK/x.glb" "$WORK/away/"
  report "$WORK/away/x.glb"
  check "$WORK/away/x.glb" "[(f['mesh'], f['match']) for f in r['fields']]" "[(0, 'exact'), (1, 'exact')]"
  python3 - "$WORK/s.gltf" "$WORK/s.bin" "$WORK/s.png" "$WORK/away/x.glb" <<'PY' || fail "accessors or image differ"
import json, struct, sys
src = json.load(open(sys.argv[1])); sbin = open(sys.argv[2], 'rb').read(); png = open(sys.argv[3], 'rb').read()
b = open(sys.argv[4], 'rb').read()
jl = struct.unpack_from('<I', b, 12)[0]
doc = json.loads(b[20:20 + jl]); gbin = b[28 + jl:]
size = {5120: 1, 5121: 1, 5122: 2, 5123: 2, 5125: 4, 5126: 4}
comps = {'SCALAR': 1, 'VEC2': 2, 'VEC3': 3, 'VEC4': 4}
def data(d, buf, a):
    v = d['bufferViews'][a['bufferView']]
    n = a['count'] * size[a['componentType']] * comps[a['type']]
    o = v.get('byteOffset', 0) + a.get('byteOffset', 0)
    return buf[o:o + n]
assert len(src['accessors']) == len(doc['accessors'])
for a, c in zip(src['accessors'], doc['accessors']):
    assert data(src, sbin, a) == data(doc, gbin, c)
img = doc['images'][0]
assert 'uri' not in img and img['mimeType'] == 'image/png'
v = doc['bufferViews'][img['bufferView']]
assert gbin[v.get('byteOffset', 0):v.get('byteOffset', 0) + v['byteLength']] == png
PY
}

test_compressed_inputs_pack_and_match_exactly() {
  # Draco and meshopt buffers (a meshopt fallback buffer has no data) survive the packing: the
  # packed file's meshes still decode to the triangles the field was baked from.
  for kind in draco meshopt meshopt-filters quantized; do
    "$GLTF_WRITE" torus-knot $kind "$WORK/$kind.glb" || fail "$kind"
    bake "$WORK/$kind.glb" -o "$WORK/$kind.f.glb" "${small[@]}"
    expect_rc 0
    report "$WORK/$kind.f.glb"
    check "$WORK/$kind.f.glb" "[(f['valid'], f['match']) for f in r['fields']]" "[(True, 'exact')]"
    check_layout "$WORK/$kind.f.glb"
  done
  # The quantized file's node undoes the quantization with a non-uniform scale: no field answers it.
  check "$WORK/quantized.f.glb" "[(p['rule'], p['path']) for p in r['problems']]" "[(14104, '/nodes/0')]"
}

test_missing_image_fails_before_baking() {
  scene "$WORK/s.gltf" box torus-knot
  rm "$WORK/s.png"
  bake "$WORK/s.gltf" -o "$WORK/x.glb" -n 2 -m 8
  expect_rc 2
  expect_err "image 0's uri 's.png'"
  [[ $(grep -c "mesh 1/2" "$WORK/err") -eq 0 ]] || fail "it baked before finding the image missing"
  [[ ! -e $WORK/x.glb ]] || fail "x.glb written"
  no_temporaries
}

test_external_field_names_are_percent_encoded() {
  scene "$WORK/s.glb" box torus-knot
  bake "$WORK/s.glb" -o "$WORK/my scene#1.glb" --external-fields "${small[@]}"
  expect_rc 0
  [[ -f "$WORK/my scene#1.mesh0.vff" ]] || fail "the field file"
  report "$WORK/my scene#1.glb"
  check "$WORK/my scene#1.glb" "[(f['uri'], f['usable']) for f in r['fields']]" \
    "[('my%20scene%231.mesh0.vff', True), ('my%20scene%231.mesh1.vff', True)]"
}

# An interrupted rebake over an earlier .glb (and its external fields): the old files stay as they
# were, no temporary is left. SIG arrives once the first mesh is done, while the second is baked.
interrupted_rebake() {  # SIG [--external-fields]
  local sig=$1 pid
  shift
  scene "$WORK/s.glb" box torus-knot
  mkdir "$WORK/set"
  bake "$WORK/s.glb" -o "$WORK/set/x.glb" "$@" "${small[@]}"
  expect_rc 0
  cp -a "$WORK/set" "$WORK/snap"
  set -m  # job control: the background bake does not start with SIGINT ignored
  "$VFF_BAKE" "$WORK/s.glb" -o "$WORK/set/x.glb" "$@" -m 64 -j 1 2>"$WORK/rebake.err" &
  pid=$!
  set +m
  for _ in $(seq 3000); do
    grep -q "mesh 1/2 " "$WORK/rebake.err" && break
    kill -0 "$pid" 2>/dev/null || break
    sleep 0.01
  done
  grep -q "mesh 2/2 " "$WORK/rebake.err" && fail "the rebake finished before SIG$sig"
  kill -s "$sig" "$pid" 2>/dev/null || true
  RC=0
  wait "$pid" || RC=$?
  [[ $RC -eq $((128 + $(kill -l "$sig"))) ]] || { cat "$WORK/rebake.err" >&2; fail "exit status $RC, expected SIG$sig"; }
  diff -r "$WORK/snap" "$WORK/set" || fail "SIG$sig changed the old outputs"
  no_temporaries
}

test_interrupted_rebake_keeps_the_old_glb() {
  interrupted_rebake INT
}

test_interrupted_rebake_keeps_the_old_external_fields() {
  interrupted_rebake TERM --external-fields
}

test_split_node_with_glb_output_is_a_usage_error() {
  scene "$WORK/s.glb" box torus-knot
  bake "$WORK/s.glb" --split node -o "$WORK/x.glb" "${small[@]}"
  expect_rc 1
  expect_err "--split node"
  bake "$WORK/s.glb" --split mesh -o "$WORK/x.glb" "${small[@]}"
  expect_rc 0
  bake "$WORK/s.glb" --external-fields -o "$WORK/x.vff" "${small[@]}"
  expect_rc 1
  expect_err "--external-fields applies to a glTF input baked into a .glb output"
  run "$VFF_BAKE" --help
  expect_out "--external-fields"
}

test_glb_output_of_a_mesh_that_is_not_gltf_is_a_usage_error() {
  printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n' >"$WORK/t.obj"
  bake "$WORK/t.obj" -o "$WORK/t.glb" "${small[@]}"
  expect_rc 1
  expect_err "a .glb output carries the fields of a glTF input (.gltf, .glb); a field of 't.obj' is a .vff file"
  [[ ! -e $WORK/t.glb ]] || fail "a refused bake wrote its output"
}

run_test "$1"
