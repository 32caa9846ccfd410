#!/usr/bin/env bash
# example_tests.sh - each test_NAME is one ctest case web.example.NAME (tests/web/CMakeLists.txt). The
# helpers (skip, need_node, need_chromium, node_test) are web_common.sh's.
source "$(dirname "$0")/web_common.sh"

# The figures the browser cases log (node's test runner prints them as "# " lines).
notes() { grep -E '^# ' "$WORK/out" | grep -vE '^# (tests|suites|pass|fail|cancelled|skipped|todo|duration_ms) ' || true; }

# tools/make-example.mjs: the example's .glb from the shared meshes (or vff-procedural-mesh's shapes,
# said on stderr), a field on each of its five meshes matching exactly; the same bytes twice; a bad
# option is exit 1 and writes nothing.
test_make_example() {
  need_gltf
  need_bake_scene
  [[ -x ${VFF_INSPECT:-} ]] || skip "vff-inspect is not built"
  local args=(--bake "$VFF_BAKE" --procedural "$VFF_PROCEDURAL_MESH" --meshes "${VFF_SHARED_MESHES:-/nonexistent}")
  run node "$WEB/tools/make-example.mjs" "${args[@]}" --out "$WORK/a"
  expect_rc 0
  expect_out "example.glb"
  cat "$WORK/out" "$WORK/err"
  run node "$WEB/tools/make-example.mjs" "${args[@]}" --out "$WORK/b"
  expect_rc 0
  cmp "$WORK/a/example.glb" "$WORK/b/example.glb" || fail "two runs made different bytes"
  run "$VFF_INSPECT" "$WORK/a/example.glb"
  expect_rc 0
  expect_out "5 meshes, 5 with a field"
  [[ $(grep -c "match:        exact" "$WORK/out") -eq 5 ]] || { show; fail "not every field matches its mesh exactly"; }
  # Without the shared meshes: the procedural shapes, and a note saying so.
  run node "$WEB/tools/make-example.mjs" "${args[@]:0:4}" --meshes "$WORK/none" --out "$WORK/c"
  expect_rc 0
  expect_err "using the shapes of vff-procedural-mesh instead"
  expect_out "procedural shapes"
  run node "$WEB/tools/make-example.mjs" "${args[@]}" --out "$WORK/d" -n 0
  expect_rc 1
  expect_err "usage:"
  [[ ! -e $WORK/d ]] || fail "a usage error wrote $WORK/d"
}

# In headless Chromium: the example page loads its .glb, a field on each mesh, the objects on the
# floor; frames render, the objects move, the effect accumulates; the controls work; no console error.
test_browser_page() {
  need_chromium
  need_gltf
  need_bake_scene
  VFF_WORK="$WORK" node_test "$WEB/examples/test/page.browser.js"
  notes
}

# In headless Chromium: the page's own loop (paused: still and accumulating; running: moving, the
# status line's frame time); a still accumulated frame kept as three-example.png; no console error.
test_browser_loop() {
  need_chromium
  need_gltf
  need_bake_scene
  VFF_WORK="$WORK" node_test "$WEB/examples/test/loop.browser.js"
  notes
}

# In headless Chromium: the same frame drawn by the fields and by the exact reference (three-mesh-bvh
# GPU ray casting against the objects' triangles), accumulated: RMS and the share of pixels within 8
# levels, printed; the fields are much closer to the reference than no occlusion is.
test_browser_reference() {
  need_chromium
  need_gltf
  need_bake_scene
  [[ -d $WEB/node_modules/three-mesh-bvh ]] || skip "no three-mesh-bvh in $WEB/node_modules: run scripts/setup.sh"
  VFF_WORK="$WORK" node_test "$WEB/examples/test/reference.browser.js"
  notes
}

# In headless Chromium: phone and desktop sizes, high-DPI: the drawing buffer is the CSS size times
# the pixel ratio (at most 2), the controls stay on screen, a resize follows.
test_browser_sizes() {
  need_chromium
  need_gltf
  need_bake_scene
  VFF_WORK="$WORK" node_test "$WEB/examples/test/phone.browser.js"
  notes
}

# In headless Chromium: without web/node_modules, or without the asset, the page says what is
# missing and the command that fixes it.
test_browser_missing() {
  need_chromium
  VFF_WORK="$WORK" node_test "$WEB/examples/test/missing.browser.js"
}

# tools/shot-example.mjs: a picture of the example's page, whole (a PNG of the asked size) after the
# asked frames; a bad option is exit 1, a missing asset exit 2, and neither writes a file.
test_shot_example() {
  need_chromium
  need_gltf
  need_bake_scene
  run node "$WEB/tools/make-example.mjs" --bake "$VFF_BAKE" --procedural "$VFF_PROCEDURAL_MESH" \
    --meshes "${VFF_SHARED_MESHES:-/nonexistent}" --out "$WORK/a"
  expect_rc 0
  run node "$WEB/tools/shot-example.mjs" --asset "$WORK/a/example.glb" --out "$WORK/a.png" --size 200x120 --frames 2
  expect_rc 0
  expect_out "a.png: 200x120, 3 frames of 4 AO and 4 shadow rays a pixel accumulated (field)"
  [[ $(head -c 8 "$WORK/a.png" | od -An -tx1 | tr -d ' \n') == 89504e470d0a1a0a ]] || fail "not a PNG"
  [[ $(od -An -tu1 -j16 -N8 "$WORK/a.png" | tr -s ' ' | sed 's/^ //') == "0 0 0 200 0 0 0 120" ]] || fail "not 200 x 120"
  [[ ! -e $WORK/a.png.tmp ]] || fail "a temporary file was left"
  run node "$WEB/tools/shot-example.mjs" --asset "$WORK/a/example.glb" --out "$WORK/b.png" --mode wrong
  expect_rc 1
  expect_err "usage:"
  run node "$WEB/tools/shot-example.mjs" --asset "$WORK/none.glb" --out "$WORK/b.png"
  expect_rc 2
  expect_err "none.glb: no such file"
  [[ ! -e $WORK/b.png ]] || fail "a failed run wrote $WORK/b.png"
}

# (test_* functions go above this line)
run_test "$1"
