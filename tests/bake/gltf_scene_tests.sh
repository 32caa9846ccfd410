#!/usr/bin/env bash
# gltf_scene_tests.sh - vff-bake on glTF scenes: --scene, the note about scenes not baked, and
# --split mesh|node (a field per object and a scene description, spec/scene.md).
#
# Every function named test_* is one ctest case (tests/bake/CMakeLists.txt finds them in this file):
# `bash gltf_scene_tests.sh test_NAME` runs one. Environment:
#   VFF_BAKE      the vff-bake executable
#   VFF_INSPECT   the vff-inspect executable
#   MESHGEN       the vff-procedural-mesh executable (--gltf-scene writes the sample scene)
#   SCHEMA_CHECK  vff_cli_schema_check, SCHEMA spec/scene-schema.json
#   WORK          a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_BAKE:?}" "${VFF_INSPECT:?}" "${MESHGEN:?}" "${SCHEMA_CHECK:?}" "${SCHEMA:?}" "${WORK:?}"

here="$(dirname "${BASH_SOURCE[0]}")"
source "$here/../common/cli_harness.sh"
bake() { run "$VFF_BAKE" "$@"; }
# The sample scene: scene 0 'main' (a box used by nodes boxA and boxB, a knot under a non-uniform
# scale at node 3), scene 1 'second' (a bowl).
sample() { "$MESHGEN" --gltf-scene "$WORK/s.gltf" || fail "vff-procedural-mesh --gltf-scene"; }
json_get() { python3 -c "import json,sys; d=json.load(open(sys.argv[1])); print(eval(sys.argv[2]))" "$@"; }

test_default_scene_is_baked_and_the_others_are_named() {
  sample
  bake "$WORK/s.gltf" -o "$WORK/a.vff" -n 2 -m 8 --json
  expect_rc 0
  expect_err "has 2 scenes; baked scene 0 'main'; not baked: 1 'second' (--scene N bakes another)"
  expect_out '"triangles": 1048'  # box twice (12 each) and the knot (1024)
  bake "$WORK/s.gltf" -o "$WORK/b.vff" -n 2 -m 8 -q
  expect_no_err
}

test_scene_option_bakes_another_scene() {
  sample
  bake "$WORK/s.gltf" --scene 1 -o "$WORK/b.vff" -n 2 -m 8
  expect_rc 0
  expect_err "baked scene 1 'second'; not baked: 0 'main'"
  run "$VFF_INSPECT" "$WORK/b.vff" --format json
  expect_out '"triangles": 544'  # the sample scene's bowl alone
  bake "$WORK/s.gltf" --scene 2 -o "$WORK/c.vff" -n 2 -m 8
  expect_rc 1
  expect_err "there is no scene 2 (the file has 2 scenes)"
  [[ ! -e $WORK/c.vff ]] || fail "a refused bake wrote its output"
}

test_split_mesh_writes_a_field_per_mesh_and_the_scene() {
  sample
  bake "$WORK/s.gltf" --split mesh -o "$WORK/sc.vffscene.json" -n 2 -m 8 -q
  expect_rc 0
  "$SCHEMA_CHECK" "$SCHEMA" "$WORK/sc.vffscene.json" || fail "the scene description does not match the schema"
  local n
  n=$(json_get "$WORK/sc.vffscene.json" "[f['uri'] for f in d['fields']]")
  [[ $n == "['sc.mesh0.vff', 'sc.mesh1.node3.vff']" ]] || fail "fields: $n"
  n=$(json_get "$WORK/sc.vffscene.json" "[(i['field'], i['name']) for i in d['instances']]")
  [[ $n == "[(0, 'boxA'), (0, 'boxB'), (1, 'knotStretched')]" ]] || fail "instances: $n"
  # boxA: the node's own TRS; boxB: under the group (translation (0,1,0), 90 degrees about y).
  n=$(json_get "$WORK/sc.vffscene.json" "[round(float(x), 5) for x in d['instances'][0]['translation'] + d['instances'][0]['rotation'] + [d['instances'][0]['scale']]]")
  [[ $n == "[1.0, 2.0, 3.0, 0.2, 0.3, 0.1, 0.92736, 2.0]" ]] || fail "boxA placement: $n"
  n=$(json_get "$WORK/sc.vffscene.json" "[round(float(x), 5) + 0.0 for x in d['instances'][1]['translation'] + d['instances'][1]['rotation']]")
  [[ $n == "[0.0, 1.0, 3.0, 0.0, 0.70711, 0.0, 0.70711]" ]] || fail "boxB placement: $n"
  for f in sc.mesh0.vff sc.mesh1.node3.vff; do
    run "$VFF_INSPECT" "$WORK/$f" --validate
    expect_rc 0
  done
  run "$VFF_INSPECT" "$WORK/sc.mesh0.vff" --format json
  expect_out '"triangles": 12'
  expect_out '"gltf": {'
  run "$VFF_INSPECT" "$WORK/sc.mesh1.node3.vff" --format json
  expect_out '"node": 3'
}

test_split_node_writes_a_field_per_node() {
  sample
  bake "$WORK/s.gltf" --split node -o "$WORK/n.json" -n 2 -m 8 --json
  expect_rc 0
  expect_out '"instances": 3'
  local n
  n=$(json_get "$WORK/n.json" "[f['uri'] for f in d['fields']]")
  [[ $n == "['n.node0.vff', 'n.node1.vff', 'n.node3.vff']" ]] || fail "fields: $n"
  "$SCHEMA_CHECK" "$SCHEMA" "$WORK/n.json" || fail "the scene description does not match the schema"
  # The same bake of the same nodes gives the same bytes.
  bake "$WORK/s.gltf" --split node -o "$WORK/again.json" -n 2 -m 8 -q -j 1
  expect_rc 0
  cmp "$WORK/n.node1.vff" "$WORK/again.node1.vff" || fail "another run (one thread) wrote another field"
}

# A field that cannot be written: an error naming it, and none of this run's fields stay.
test_split_failure_leaves_no_partial_scene() {
  sample
  mkdir "$WORK/sc.mesh1.node3.vff"
  bake "$WORK/s.gltf" --split mesh -o "$WORK/sc.vffscene.json" -n 2 -m 8 -q
  expect_rc 2
  expect_err "sc.mesh1.node3.vff"
  [[ ! -e $WORK/sc.mesh0.vff && ! -e $WORK/sc.vffscene.json ]] || fail "a failed split left outputs: $(ls "$WORK")"
}

test_split_usage_errors() {
  sample
  "$MESHGEN" box "$WORK/box.obj" || fail "mesh generator"
  bake "$WORK/box.obj" --split mesh -o "$WORK/x.json"
  expect_rc 1
  expect_err "--split applies to a glTF input"
  bake "$WORK/box.obj" --scene 0 -o "$WORK/x.vff"
  expect_rc 1
  expect_err "--scene applies to a glTF input"
  bake "$WORK/s.gltf" --split mesh -o "$WORK/x.vff"
  expect_rc 1
  expect_err "-o must name a .json file"
  bake "$WORK/s.gltf" --split triangles -o "$WORK/x.json"
  expect_rc 1
  bake "$WORK/s.gltf" --split mesh -o "$WORK/x.json" --center 0 0 0 --radius 9
  expect_rc 1
  expect_err "--center/--radius do not apply"
}

run_test "$1"
