#!/usr/bin/env bash
# three_tests.sh - each test_NAME is one ctest case web.three.NAME (tests/web/CMakeLists.txt). The
# helpers (skip, need_node, need_chromium, node_test) are web_tests.sh's.
source "$(dirname "$0")/web_common.sh"

need_three() {
  need_node
  local m
  for m in three three-mesh-bvh @vff/three; do
    [[ -e $WEB/node_modules/$m ]] || skip "no $m in $WEB/node_modules: run scripts/setup.sh (npm ci in web/)"
  done
}

# VffField in node: the conformance vectors' uniforms, defines and texture sizes, VffError IDs.
test_field() { need_three; node_test three-vff/test/field.test.js; }

# In Chromium, one case a test of occlusion.browser.js (each bakes its knot and starts a browser):
# the field's floor AO against three-mesh-bvh's exact reference of the same rays (RMS, share within 8
# levels, ms a frame printed); a moving instance; mode 'off'; two fields in one shader, no self-occlusion.
occlusion_case() {
  need_three; need_chromium; need_bake_scene
  VFF_WORK="$WORK" node_test --test-name-pattern="$1" three-vff/test/browser/occlusion.browser.js
  grep -E '^# (floor|knot|ms a frame|[0-9]+x[0-9]+,)' "$WORK/out"
  grep -qE '^# pass 1$' "$WORK/out" || fail "no test of occlusion.browser.js matched '$1'"
}
test_occlusion_reference() { occlusion_case 'matches the three-mesh-bvh reference'; }
test_occlusion_moving() { occlusion_case 'moving the knot'; }
test_occlusion_off() { occlusion_case "mode 'off'"; }
test_occlusion_two_fields() { occlusion_case 'two fields'; }

# In Chromium: GLTFLoader with VffGLTFPlugin on the .glb vff-bake writes for the sample scene.
test_plugin() {
  need_three; need_chromium; need_bake_scene
  VFF_WORK="$WORK" node_test three-vff/test/browser/plugin.browser.js
}

# In Chromium: decodeInWorker on conformance vectors (the same field as VffField.fromBytes) and errors.
test_worker() { need_three; need_chromium; node_test three-vff/test/browser/worker.browser.js; }

# (test_* functions go above this line)
run_test "$1"
