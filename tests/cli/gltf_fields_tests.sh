#!/usr/bin/env bash
# gltf_fields_tests.sh - vff-inspect and vff-query on glTF assets whose meshes carry fields (the
# extension VFF_visibility_field, spec/gltf/VFF_visibility_field/README.md).
#
# Every function named test_* is one ctest case (tests/cli/CMakeLists.txt finds them in this file):
# `bash gltf_fields_tests.sh test_NAME` runs one. The assets are baked by vff-bake from the sample
# scene of vff-procedural-mesh, and broken where a test needs it by rewriting the GLB's JSON chunk.
# The environment says where things are:
#   VFF_INSPECT  the vff-inspect executable
#   VFF_QUERY    the vff-query executable
#   VFF_BAKE     the vff-bake executable
#   MESHGEN      the vff-procedural-mesh executable (--gltf-scene writes the sample scene)
#   SCHEMA_CHECK vff_cli_schema_check; GLTF_SCHEMA spec/inspect-gltf-schema.json, SCHEMA spec/inspect-schema.json
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_INSPECT:?}" "${VFF_QUERY:?}" "${VFF_BAKE:?}" "${MESHGEN:?}" "${WORK:?}"
: "${SCHEMA_CHECK:?}" "${GLTF_SCHEMA:?}" "${SCHEMA:?}"

# ---- Helpers ---------------------------------------------------------------------------------------
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"
inspect() { run "$VFF_INSPECT" "$@"; }
query() { run "$VFF_QUERY" "$@"; }

# The sample scene's default scene uses mesh 0 "box" (nodes boxA, boxB: similarities) and mesh 1
# "knot" (node knotStretched: a non-uniform scale); mesh 2 "bowl" is used by the second scene only.
# So the baked asset $WORK/x.glb carries fields on meshes 0 and 1, none on mesh 2.
BAKE_OPTIONS=(-n 2 -m 8)
make_glb() {
  "$MESHGEN" --gltf-scene "$WORK/s.gltf" >/dev/null || fail "vff-procedural-mesh --gltf-scene"
  "$VFF_BAKE" "$WORK/s.gltf" -o "$WORK/x.glb" "${BAKE_OPTIONS[@]}" >/dev/null 2>"$WORK/bake.err" ||
    { cat "$WORK/bake.err" >&2; fail "vff-bake s.gltf -o x.glb"; }
}
# The same scene split per mesh (--split mesh): split/x.mesh0.vff is the field of mesh 0 as the
# asset must carry it, byte for byte.
make_split() {
  mkdir -p "$WORK/split"
  "$VFF_BAKE" "$WORK/s.gltf" --split mesh -o "$WORK/split/x.vffscene.json" "${BAKE_OPTIONS[@]}" >/dev/null 2>&1 ||
    fail "vff-bake --split mesh"
}
# glb_edit IN OUT CODE: OUT is the GLB IN with its JSON document and binary chunk changed by the
# Python statements CODE, which see the document as `j`, the binary chunk as the bytearray `bin_`,
# ext(i) (mesh i's extension object) and move(i, f) (mesh i's positions p replaced by f(k, p), k
# the vertex index; the accessors' min and max follow).
glb_edit() {
  python3 - "$1" "$2" "$3" <<'PY'
import json, struct, sys
src, dst, code = sys.argv[1:]
b = open(src, "rb").read()
assert b[:4] == b"glTF"
n, kind = struct.unpack_from("<I4s", b, 12)
assert kind == b"JSON"
j = json.loads(b[20:20 + n])
m, kind = struct.unpack_from("<I4s", b, 20 + n)
assert kind == b"BIN\0"
bin_ = bytearray(b[28 + n:28 + n + m])
ext = lambda i: j["meshes"][i]["extensions"]["VFF_visibility_field"]
def move(i, f):
    a = j["accessors"][j["meshes"][i]["primitives"][0]["attributes"]["POSITION"]]
    v = j["bufferViews"][a["bufferView"]]
    stride = v.get("byteStride", 12)
    at = v.get("byteOffset", 0) + a.get("byteOffset", 0)
    ps = []
    for k in range(a["count"]):
        p = f(k, struct.unpack_from("<3f", bin_, at + k * stride))
        struct.pack_into("<3f", bin_, at + k * stride, *p)
        ps.append(struct.unpack_from("<3f", bin_, at + k * stride))
    a["min"] = [min(p[c] for p in ps) for c in range(3)]
    a["max"] = [max(p[c] for p in ps) for c in range(3)]
exec(code)
t = json.dumps(j).encode()
t += b" " * (-len(t) % 4)
rest = struct.pack("<I4s", len(bin_), b"BIN\0") + bin_
out = struct.pack("<4sII", b"glTF", 2, 12 + 8 + len(t) + len(rest)) + struct.pack("<I4s", len(t), b"JSON") + t + rest
open(dst, "wb").write(out)
PY
}
# The box (mesh 0) as a re-encode leaves it: its first vertex moved inward by far less than one
# distance step (its corner is held by the vertices of the other faces), so the bounds stay and the
# hash changes: a close match.
NUDGE_BOX="move(0, lambda k, p: [c - 1e-4 * (1 if c > 0 else -1) for c in p] if k == 0 else p)"
# The box twice as large: its bounds move by half its size, far beyond one step: a mismatch.
GROW_BOX="move(0, lambda k, p: [2 * c for c in p])"
# json_check FILE CODE: the Python assertions CODE hold for the JSON document `d` in FILE.
json_check() {
  python3 -c "import json, sys
d = json.load(open(sys.argv[1]))
$2" "$1" || { show; fail "the JSON of $1 fails: $2"; }
}
RAYS=(--ray 0 0 3 0 0 -1 --ray 0.1 0.2 3 0 0 -1 --ray 3 0.1 0 -1 0 0 --ray 0.05 0 0 0 1 0 --ray 2 2 2 -1 -1 -1)

# ---- vff-inspect -----------------------------------------------------------------------------------
test_gltf_help() {
  inspect --help
  expect_rc 0
  expect_out "--extract"
  expect_out "glTF"
  query --help
  expect_rc 0
  expect_out "--mesh"
}

test_gltf_listing() {
  make_glb
  inspect "$WORK/x.glb"
  expect_rc 0
  expect_out "file:        $WORK/x.glb"
  expect_out "meshes:      3 meshes, 2 with a field"
  expect_out 'mesh 0 "box": /meshes/0/extensions/VFF_visibility_field'
  expect_out 'mesh 1 "knot": /meshes/1/extensions/VFF_visibility_field'
  expect_out_re '^  source:       bufferView [0-9]+, [0-9]+ bytes'
  expect_out "  match:        exact"
  expect_out '  nodes:        0 "boxA": answered'
  expect_out '1 "boxB": answered'
  expect_out_re '^  nodes:        3 "knotStretched": not answered \(.+\)$'
  expect_out "  field:        vff 1."
  expect_out "26 maps of 8x8 (octa-hemi2 n=2), unorm8-diameter, normals none"
  # The node of mesh 1 that no field answers is a note, not an error.
  expect_out_re "^  $WORK/x.glb: /nodes/3[^ ]*: gltf-node-no-field \(14104\): "
  expect_no_err
  # A GLB is known by its magic too.
  cp "$WORK/x.glb" "$WORK/x.bin"
  inspect "$WORK/x.bin"
  expect_rc 0
  expect_out "meshes:      3 meshes, 2 with a field"
}

test_gltf_json() {
  make_glb
  make_split
  inspect "$WORK/x.glb" --format json
  expect_rc 0
  cp "$WORK/out" "$WORK/report.json"
  "$SCHEMA_CHECK" "$GLTF_SCHEMA" "$WORK/report.json" || fail "the report does not match spec/inspect-gltf-schema.json"
  # Each payload's report is the one of a .vff file (spec/inspect-schema.json), less file and tool.
  python3 -c "
import json, sys
d = json.load(open(sys.argv[1]))
for i, f in enumerate(d['fields']):
    json.dump(dict(f['field'], file='x', tool=d['tool']), open(sys.argv[2] + str(i), 'w'))
" "$WORK/report.json" "$WORK/payload"
  "$SCHEMA_CHECK" "$SCHEMA" "$WORK/payload0" && "$SCHEMA_CHECK" "$SCHEMA" "$WORK/payload1" ||
    fail "a payload's report does not match spec/inspect-schema.json"
  local hash
  hash=$(python3 -c "import json,sys; print(json.load(sys.stdin)['metadata']['vff.source']['geometryHash'])" \
    < <("$VFF_INSPECT" "$WORK/split/x.mesh0.vff" --format json))
  json_check "$WORK/report.json" "
assert set(d) == {'file', 'tool', 'meshes', 'fields', 'problems'}, sorted(d)
assert d['file'].endswith('x.glb') and d['meshes'] == 3
assert [f['mesh'] for f in d['fields']] == [0, 1] and [f['name'] for f in d['fields']] == ['box', 'knot']
keys = {'mesh', 'name', 'path', 'bufferView', 'bytes', 'geometryHash', 'meshGeometryHash', 'match', 'tolerance',
        'boundsDifference', 'valid', 'usable', 'nodes', 'field'}
for f in d['fields']:
    assert set(f) == keys, sorted(f)
    assert f['valid'] and f['usable'] and f['match'] == 'exact' and f['geometryHash'] == f['meshGeometryHash']
    assert f['path'] == '/meshes/%d/extensions/VFF_visibility_field' % f['mesh']
    assert f['boundsDifference'] == 0 and f['tolerance'] > 0
    assert f['field']['format']['fileSize'] == f['bytes']
    assert f['field']['field']['mapCount'] == 26 and f['field']['field']['mapResolution'] == 8
    assert f['field']['metadata']['vff.source']['gltf']['mesh'] == f['mesh']
box = d['fields'][0]
assert box['geometryHash'] == '$hash', box['geometryHash']
assert box['bytes'] == $(stat -c %s "$WORK/split/x.mesh0.vff")
assert [(n['node'], n['name'], n['answered'], n['reason']) for n in box['nodes']] == [(0, 'boxA', True, ''), (1, 'boxB', True, '')]
knot = d['fields'][1]['nodes']
assert len(knot) == 1 and knot[0]['node'] == 3 and not knot[0]['answered'] and knot[0]['reason']
assert [(p['rule'], p['name'], p['severity']) for p in d['problems']] == [(14104, 'gltf-node-no-field', 'note')], d['problems']
assert set(d['problems'][0]) == {'rule', 'name', 'severity', 'path', 'message'}
"
}

test_gltf_extract_matches_split() {
  make_glb
  make_split
  mkdir "$WORK/out.d"
  inspect "$WORK/x.glb" --extract "$WORK/out.d"
  expect_rc 0
  [[ $(cat "$WORK/out") == "$WORK/out.d/x.mesh0.vff"$'\n'"$WORK/out.d/x.mesh1.vff" ]] || { show; fail "the paths printed"; }
  [[ $(ls -A "$WORK/out.d" | tr '\n' ' ') == "x.mesh0.vff x.mesh1.vff " ]] || fail "out.d holds $(ls -A "$WORK/out.d")"
  # The payload is the very file vff-bake --split mesh writes for the mesh.
  cmp "$WORK/out.d/x.mesh0.vff" "$WORK/split/x.mesh0.vff" || fail "mesh 0's payload differs from the --split mesh file"
  valid "$WORK/out.d/x.mesh1.vff"
  # Each payload is the bufferView's bytes unchanged, in its file.
  python3 - "$WORK/x.glb" "$WORK/out.d" <<'PY' || fail "the extracted bytes are not the bufferViews'"
import json, struct, sys
b = open(sys.argv[1], "rb").read()
n = struct.unpack_from("<I", b, 12)[0]
j = json.loads(b[20:20 + n])
bin0 = 20 + n + 8
for i, m in enumerate(j["meshes"]):
    e = m.get("extensions", {}).get("VFF_visibility_field")
    if not e:
        continue
    v = j["bufferViews"][e["bufferView"]]
    s = bin0 + v.get("byteOffset", 0)
    assert b[s:s + v["byteLength"]] == open("%s/x.mesh%d.vff" % (sys.argv[2], i), "rb").read(), i
PY
  # JSON: the files written.
  rm "$WORK/out.d"/*
  inspect "$WORK/x.glb" --extract "$WORK/out.d" --format json
  expect_rc 0
  json_check "$WORK/out" "assert [e['mesh'] for e in d['extracted']] == [0, 1] and d['extracted'][0]['path'].endswith('/x.mesh0.vff')"
}

test_gltf_extract_usage() {
  make_glb
  # The folder must exist; nothing is written otherwise.
  inspect "$WORK/x.glb" --extract "$WORK/no-such-folder"
  expect_rc 2
  expect_err "no-such-folder"
  [[ ! -e $WORK/no-such-folder ]] || fail "the folder was made"
  # --extract is for glTF input only.
  make_split
  mkdir "$WORK/out.d"
  inspect "$WORK/split/x.mesh0.vff" --extract "$WORK/out.d"
  expect_rc 1
  expect_err "--extract"
  # What one .vff file's maps are drawn with is refused for an asset, by name.
  inspect "$WORK/x.glb" --preview "$WORK/p.png"
  expect_rc 1
  expect_no_out
  expect_err "--preview"
  [[ ! -e $WORK/p.png ]] || fail "a preview was written"
  [[ -z $(ls -A "$WORK/out.d") ]] || fail "files written despite usage errors"
}

# An extension the reader refuses: exit 3, the problem as FILE: PATH: name (ID): message, and the
# field left out of --extract.
test_gltf_error_asset() {
  make_glb
  glb_edit "$WORK/x.glb" "$WORK/bad.glb" "ext(1)['mimeType'] = 'application/octet-stream'"
  inspect "$WORK/bad.glb"
  expect_rc 3
  expect_out "  $WORK/bad.glb: /meshes/1/extensions/VFF_visibility_field/mimeType: gltf-mime-type (14008): "
  expect_out "  valid:        no"
  expect_err "vff-inspect: error: $WORK/bad.glb: /meshes/1/extensions/VFF_visibility_field/mimeType: gltf-mime-type (14008): "
  inspect "$WORK/bad.glb" --format json
  expect_rc 3
  json_check "$WORK/out" "
f = d['fields'][1]
assert not f['valid'] and f['field'] is None and f['bytes'] == 0
assert d['fields'][0]['valid']
assert [p['rule'] for p in d['problems'] if p['severity'] == 'error'] == [14008]"
  mkdir "$WORK/out.d"
  inspect "$WORK/bad.glb" --extract "$WORK/out.d"
  expect_rc 3
  [[ $(ls -A "$WORK/out.d") == "bad.mesh0.vff" ]] || fail "out.d holds $(ls -A "$WORK/out.d")"
  # A bufferView that is not there; a file that is not glTF at all.
  glb_edit "$WORK/x.glb" "$WORK/view.glb" "ext(0)['bufferView'] = 999"
  inspect "$WORK/view.glb"
  expect_rc 3
  expect_out "gltf-buffer-view (14006)"
  printf 'glTF\002\000\000\000garbage' >"$WORK/junk.glb"
  inspect "$WORK/junk.glb"
  expect_rc 3
  expect_out "gltf-container (14001)"
  expect_err "gltf-container (14001)"
  # The extension required: an error of the file.
  glb_edit "$WORK/x.glb" "$WORK/req.glb" "j['extensionsRequired'] = ['VFF_visibility_field']"
  inspect "$WORK/req.glb"
  expect_rc 3
  expect_out "gltf-required (14002)"
}

# A uri whose file cannot be read is an I/O error: exit 2 when it is the only error.
test_gltf_unreadable_uri() {
  make_glb
  glb_edit "$WORK/x.glb" "$WORK/uri.glb" "e = ext(0); del e['bufferView']; e['uri'] = 'missing.vff'"
  inspect "$WORK/uri.glb"
  expect_rc 2
  expect_out "gltf-uri (14007)"
  expect_err "missing.vff"
  # The same uri beside the asset: read, and the field valid.
  mkdir "$WORK/out.d"
  "$VFF_INSPECT" "$WORK/x.glb" --extract "$WORK/out.d" >/dev/null
  cp "$WORK/out.d/x.mesh0.vff" "$WORK/missing.vff"
  inspect "$WORK/uri.glb" --format json
  expect_rc 0
  json_check "$WORK/out" "f = d['fields'][0]; assert f['uri'] == 'missing.vff' and 'bufferView' not in f and f['valid'] and f['match'] == 'exact'"
}

# Geometry that moved: within one distance step the field is used (a note), beyond it not (a warning);
# neither is an error.
test_gltf_close_and_mismatch() {
  make_glb
  glb_edit "$WORK/x.glb" "$WORK/close.glb" "$NUDGE_BOX"
  inspect "$WORK/close.glb"
  expect_rc 0
  expect_out_re '^  match:        close \(bounds differ by up to 0, tau [0-9.e-]+\)$'
  expect_out "gltf-geometry-close (14102)"
  inspect "$WORK/close.glb" --format json
  json_check "$WORK/out" "f = d['fields'][0]; assert f['match'] == 'close' and f['geometryHash'] != f['meshGeometryHash']"
  glb_edit "$WORK/x.glb" "$WORK/far.glb" "$GROW_BOX"
  inspect "$WORK/far.glb"
  expect_rc 0
  expect_out_re '^  match:        mismatch \(bounds differ by up to 0.5, tau [0-9.e-]+\): not used$'
  expect_out "gltf-geometry-mismatch (14103)"
  inspect "$WORK/far.glb" --format json
  json_check "$WORK/out" "f = d['fields'][0]; assert f['match'] == 'mismatch' and f['valid'] and abs(f['boundsDifference'] - 0.5) < 1e-6 and 0 < f['tolerance'] < 0.5"
  # The mismatched field is still a valid payload: --extract writes it.
  mkdir "$WORK/out.d"
  inspect "$WORK/far.glb" --extract "$WORK/out.d"
  expect_rc 0
  [[ -f $WORK/out.d/far.mesh0.vff ]] || fail "the mismatched field was not extracted"
}

# Fields beside the asset (vff-bake --external-fields), and a .gltf that carries none.
test_gltf_external_fields() {
  make_glb
  mkdir "$WORK/ext" "$WORK/out.d"
  "$VFF_BAKE" "$WORK/s.gltf" -o "$WORK/ext/e.glb" --external-fields "${BAKE_OPTIONS[@]}" >/dev/null 2>&1 ||
    fail "vff-bake --external-fields"
  inspect "$WORK/ext/e.glb"
  expect_rc 0
  expect_out_re '^  source:       uri e\.mesh0\.vff, [0-9]+ bytes'
  expect_out "  match:        exact"
  inspect "$WORK/ext/e.glb" --extract "$WORK/out.d"
  expect_rc 0
  cmp "$WORK/out.d/e.mesh0.vff" "$WORK/ext/e.mesh0.vff" || fail "the extracted payload is not the uri's file"
  query "$WORK/ext/e.glb" --mesh 1 "${RAYS[@]}"
  expect_rc 0
  cp "$WORK/out" "$WORK/e.csv"
  query "$WORK/ext/e.mesh1.vff" "${RAYS[@]}"
  cmp "$WORK/e.csv" "$WORK/out" || fail "the uri field answers otherwise than its file"
  # The sample scene itself: a .gltf whose meshes carry no field.
  inspect "$WORK/s.gltf"
  expect_rc 0
  expect_out "meshes:      3 meshes, 0 with a field"
  expect_out "problems:    none"
  query "$WORK/s.gltf" --ray 0 0 3 0 0 -1
  expect_rc 3
  expect_err "no mesh carries a field"
}

# ---- vff-query -------------------------------------------------------------------------------------
test_gltf_query_answers_as_extracted() {
  make_glb
  mkdir "$WORK/out.d"
  "$VFF_INSPECT" "$WORK/x.glb" --extract "$WORK/out.d" >/dev/null
  local mesh
  for mesh in 0 1; do
    query "$WORK/x.glb" --mesh $mesh "${RAYS[@]}" --visibility
    expect_rc 0
    cp "$WORK/out" "$WORK/glb.csv"
    query "$WORK/out.d/x.mesh$mesh.vff" "${RAYS[@]}" --visibility
    expect_rc 0
    cmp "$WORK/glb.csv" "$WORK/out" || fail "mesh $mesh: the answers differ from the extracted file's"
    cp "$WORK/glb.csv" "$WORK/glb$mesh.csv"
    [[ $(grep -c '^1,' "$WORK/out") -ge 1 ]] || { show; fail "mesh $mesh: no ray hits, nothing compared"; }
  done
  # Placed by --rotate, --translate, --scale, and rays from a file.
  printf '0,0,3,0,0,-1\n2,1,3,-0.5,0,-1\n' >"$WORK/rays.csv"
  query "$WORK/x.glb" --mesh 0 -i "$WORK/rays.csv" --rotate 0 1 0 0.5 --translate 2 0 0 --scale 1.5 --format jsonl
  expect_rc 0
  cp "$WORK/out" "$WORK/glb.jsonl"
  query "$WORK/out.d/x.mesh0.vff" -i "$WORK/rays.csv" --rotate 0 1 0 0.5 --translate 2 0 0 --scale 1.5 --format jsonl
  cmp "$WORK/glb.jsonl" "$WORK/out" || fail "placed: the answers differ from the extracted file's"
  # A close match answers too.
  glb_edit "$WORK/x.glb" "$WORK/close.glb" "$NUDGE_BOX"
  query "$WORK/close.glb" --mesh 0 "${RAYS[@]}" --visibility
  expect_rc 0
  cmp "$WORK/glb0.csv" "$WORK/out" || fail "a close match answers otherwise"
}

test_gltf_query_chooses_a_mesh() {
  make_glb
  # Several fields: --mesh is needed, and the message lists the meshes that have one.
  query "$WORK/x.glb" --ray 0 0 3 0 0 -1
  expect_rc 1
  expect_no_out
  expect_err '--mesh (0 "box", 1 "knot")'
  # A mesh without a field, and one that is not there.
  query "$WORK/x.glb" --mesh 2 --ray 0 0 3 0 0 -1
  expect_rc 1
  expect_err 'mesh 2 of '
  expect_err 'the meshes with a field: 0 "box", 1 "knot"'
  query "$WORK/x.glb" --mesh 7 --ray 0 0 3 0 0 -1
  expect_rc 1
  expect_err "has no mesh 7"
  # One field: no --mesh needed.
  glb_edit "$WORK/x.glb" "$WORK/one.glb" "del j['meshes'][1]['extensions']"
  query "$WORK/one.glb" --ray 0 0 3 0 0 -1
  expect_rc 0
  cp "$WORK/out" "$WORK/one.csv"
  query "$WORK/x.glb" --mesh 0 --ray 0 0 3 0 0 -1
  cmp "$WORK/one.csv" "$WORK/out" || fail "the one field is not mesh 0's"
  # --mesh on a .vff file.
  mkdir "$WORK/out.d"
  "$VFF_INSPECT" "$WORK/x.glb" --extract "$WORK/out.d" >/dev/null
  query "$WORK/out.d/x.mesh0.vff" --mesh 0 --ray 0 0 3 0 0 -1
  expect_rc 1
  expect_err "--mesh"
}

test_gltf_query_refuses_bad_fields() {
  make_glb
  glb_edit "$WORK/x.glb" "$WORK/far.glb" "$GROW_BOX"
  query "$WORK/far.glb" --mesh 0 --ray 0 0 3 0 0 -1
  expect_rc 3
  expect_no_out
  expect_err "vff-query: error: $WORK/far.glb: /meshes/0"
  expect_err "gltf-geometry-mismatch (14103)"
  # The other mesh's field is still answered.
  query "$WORK/far.glb" --mesh 1 --ray 0 0 3 0 0 -1
  expect_rc 0
  glb_edit "$WORK/x.glb" "$WORK/bad.glb" "ext(1)['mimeType'] = 'text/plain'"
  query "$WORK/bad.glb" --mesh 1 --ray 0 0 3 0 0 -1
  expect_rc 3
  expect_err "gltf-mime-type (14008)"
  printf 'glTF\002\000\000\000garbage' >"$WORK/junk.glb"
  query "$WORK/junk.glb" --ray 0 0 3 0 0 -1
  expect_rc 3
  expect_err "gltf-container (14001)"
  glb_edit "$WORK/x.glb" "$WORK/uri.glb" "e = ext(0); del e['bufferView']; e['uri'] = 'missing.vff'"
  query "$WORK/uri.glb" --mesh 0 --ray 0 0 3 0 0 -1
  expect_rc 2
  expect_err "gltf-uri (14007)"
}

# ---- Dispatch --------------------------------------------------------------------------------------
[[ $# -eq 1 ]] || fail "usage: gltf_fields_tests.sh test_NAME"
run_test "$1"
