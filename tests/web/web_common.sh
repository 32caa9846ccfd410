# web_common.sh - what the web test scripts (web_tests.sh, three_tests.sh, example_tests.sh) share:
# the harness, where web/ is, and the checks that skip a case (exit 77, ctest: skipped) with the
# reason when node, web/node_modules, chromium or a tool is missing.
source "$(dirname "$0")/../common/cli_harness.sh"
WEB="${VFF_SOURCE_DIR:-$(cd "$(dirname "$0")/../.." && pwd)}/web"

skip() { echo "SKIP: $1"; exit 77; }
need_node() {
  command -v node >/dev/null || skip "node is not installed (scripts/setup.sh installs nodejs)"
  [[ -d $WEB/node_modules/fzstd && -d $WEB/node_modules/hash-wasm ]] || skip "no $WEB/node_modules: run scripts/setup.sh (npm ci in web/)"
}
need_chromium() {
  need_node
  [[ -d $WEB/node_modules/playwright-core ]] || skip "no playwright-core in $WEB/node_modules: run scripts/setup.sh"
  VFF_CHROMIUM_PATH="$(command -v "${VFF_CHROMIUM:-chromium}")" || skip "no chromium (apt-get install chromium)"
  export VFF_CHROMIUM_PATH
}
need_gltf() {
  need_node
  local m
  for m in @gltf-transform/core @gltf-transform/functions gltf-validator draco3dgltf meshoptimizer three; do
    [[ -d $WEB/node_modules/$m ]] || skip "no $m in $WEB/node_modules: run scripts/setup.sh (npm ci in web/)"
  done
}
need_bake_scene() {
  [[ -x ${VFF_BAKE:-} ]] || skip "vff-bake is not built (needs Embree)"
  [[ -x ${VFF_PROCEDURAL_MESH:-} ]] || skip "vff-procedural-mesh is not built"
}
node_test() {
  (cd "$WEB" && node --test "$@") >"$WORK/out" 2>"$WORK/err"
  RC=$?
  grep -E '^# (pass|fail)' "$WORK/out"
  [[ $RC -eq 0 ]] || { show; fail "node --test $* failed"; }
}

