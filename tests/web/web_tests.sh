#!/usr/bin/env bash
# web/ tests: each test_NAME is one ctest case web.NAME (tests/CMakeLists.txt, vff_script_tests).
# Needs node and web/node_modules (scripts/setup.sh runs `npm ci`); the browser cases also need
# Debian's chromium (VFF_CHROMIUM: another command name). A missing piece prints SKIP and the
# reason, and exits 77 (ctest: skipped).
source "$(dirname "$0")/web_common.sh"

# Every valid conformance vector decodes to its expected.json; every invalid one raises its ID.
test_node_conformance() { need_node; node_test test/conformance.test.js; }

# Damaged vectors (cut, single bytes changed): read completely or rejected with a 2xxx-8xxx ID.
test_node_robustness() { need_node; node_test test/robustness.test.js; }

# The page's summary is, line for line, what vff-inspect prints for each valid vector.
test_node_summary() {
  need_node
  [[ -x ${VFF_INSPECT:-} ]] || skip "vff-inspect is not built"
  node_test test/summary.test.js
}

# Partial results (spec/conformance/partial): reported with their range, the summary vff-inspect's.
test_node_partial() {
  need_node
  [[ -x ${VFF_INSPECT:-} ]] || skip "vff-inspect is not built"
  node_test test/partial.test.js
}

# The spec's worked examples: hits-med, BC4, normals, positions, nearest sample, layout.
test_node_units() { need_node; node_test test/units.test.js; }

# Scene descriptions (spec/conformance/scene): web/src/scene_description.js on every vector.
test_node_scene_description() { need_node; node_test test/scene_description.test.js; }

# web/src/vff_query_es.js is exactly what web/tools/gen-glsl-es.mjs makes from gpu/glsl/vff_query.glsl.
test_glsl_es_generated() { need_node; node_test test/glsl.test.js; }

# gpu/wgsl/ and web/src/vff_wgsl.js are exactly what web/tools/gen-wgsl.mjs makes from gpu/glsl and
# the Vulkan kernels; the translator on small GLSL snippets, and its refusals.
test_wgsl_generated() { need_node; node_test test/wgsl.test.js; }

# In headless Chromium's WebGPU (SwiftShader): every generated WGSL file compiles, every kernel makes
# a compute pipeline, and the helpers answer as the CPU. (The query against libvff: gpu-webgpu label.)
test_browser_wgsl_compile() { need_chromium; node_test test/browser/wgsl_compile.browser.js; }

# In headless Chromium with WebGPU: the page draws the ground through WebGPU (the WGSL query), its
# reference view matches the C++ render, its accumulated ground matches the WebGL2 one pixel for
# pixel, and without WebGPU the page falls back to WebGL2.
test_browser_webgpu_view() {
  need_chromium
  [[ -x ${VFF_BAKE:-} ]] || skip "vff-bake is not built (needs Embree)"
  [[ -f /usr/share/glmark2/models/bunny.obj ]] || skip "no /usr/share/glmark2/models/bunny.obj (apt-get install glmark2-data)"
  VFF_WORK="$WORK" node_test test/browser/webgpu_view.browser.js
}

# In headless Chromium: the decoder decodes the conformance vectors as under node.
test_browser_decoder() { need_chromium; node_test test/browser/decoder.browser.js; }

# In headless Chromium: the page loads a baked bunny, renders it with three.js, and its ground AO
# reference view matches the C++ reference render (vff_web_reference) of the same view.
test_browser_render() {
  need_chromium
  [[ -x ${VFF_BAKE:-} ]] || skip "vff-bake is not built (needs Embree)"
  [[ -f /usr/share/glmark2/models/bunny.obj ]] || skip "no /usr/share/glmark2/models/bunny.obj (apt-get install glmark2-data)"
  VFF_WORK="$WORK" node_test test/browser/render.browser.js
}

# In headless Chromium: the viewer page (web/test/browser/viewer.browser.js) driven as a user would,
# in three cases (each page compiles the field's shaders in software, which takes a while):
# viewer: ?file= and a sample, the object on its lowest point, a clean page and every problem after
# a bad file, PNG and JSON downloads (JSON against vff-inspect when built), keyboard and names, the
# message without web/node_modules; viewer_worker: a large field decoded in the Worker with progress
# while the page answers (needs vff-bake, vff-procedural-mesh); viewer_sizes: 1280 and 390 wide, DPR 2.
need_three() {
  need_chromium
  [[ -d $WEB/node_modules/three ]] || skip "no three in $WEB/node_modules: run scripts/setup.sh (npm ci in web/)"
}
test_browser_viewer() {
  need_three
  VFF_WORK="$WORK" node_test --test-name-pattern='opens a sample|bad file|downloads|keyboard|node_modules' test/browser/viewer.browser.js
}
test_browser_viewer_worker() {
  need_three
  need_bake_scene
  VFF_WORK="$WORK" node_test --test-name-pattern='Worker' test/browser/viewer.browser.js
}
test_browser_viewer_sizes() {
  need_three
  VFF_WORK="$WORK" node_test --test-name-pattern='size at' test/browser/viewer.browser.js
}

# glTF extension VFF_visibility_field: the JS reader on spec/conformance/gltf and on assets made
# with glTF-Transform, one case per rule, the match (exact, close, mismatch), quantized positions.
test_node_gltf_fields() { need_gltf; node_test test/gltf_fields.test.js; }

# The glTF-Transform extension: round trip, dedup, prune, draco, meshopt, quantize; unregistered readers.
test_node_gltf_transform() { need_gltf; node_test test/gltf_transform.test.js; }

# vff-bake's .glb (the sample scene; suzanne and spot when shared/meshes has them) passes
# glTF-Validator with no error or warning; the JS reader matches every field exactly.
test_node_gltf_bake() {
  need_gltf
  need_bake_scene
  VFF_WORK="$WORK" node_test test/gltf_bake.test.js
}

# In headless Chromium: three.js's GLTFLoader loads vff-bake's .glb and draws the meshes.
test_browser_gltf_three() {
  need_chromium
  need_gltf
  need_bake_scene
  VFF_WORK="$WORK" node_test test/browser/gltf_three.browser.js
}

run_test "$1"
