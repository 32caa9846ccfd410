# convert_harness.sh - helpers shared by the vff-convert test scripts (convert_tests.sh, lod_tests.sh,
# vdb_tests.sh; sourced, after they check their environment): tests/common/cli_harness.sh, and
#   convert ARGS...        runs $VFF_CONVERT (cli_harness.sh's run: $WORK/out, $WORK/err, RC)
#   field OUT ENCODING ... writes a test field with $CHECK (convert_check.cpp: every code value,
#                          ~1/8 misses)
#   same A B [--normal-tolerance K]  A and B hold the same field, metadata and maps ($CHECK compare)
#   no_leftovers [FILE...] nothing but FILE... (and out/err) is in $WORK: no temporary, no partial output
#   needs_bake             returns 1, saying why, when $VFF_BAKE or $MESHGEN is not built (the test
#                          then skips: `needs_bake || return 0`)
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"
convert() { run "$VFF_CONVERT" "$@"; }
field() { "$CHECK" write "$@" || fail "convert_check write $*"; }
same() {
  run "$CHECK" compare "$@"
  [[ $RC -eq 0 ]] || { show; fail "fields differ: $*"; }
}
no_leftovers() {
  local f left=""
  for f in "$WORK"/* "$WORK"/.[!.]*; do
    [[ -e $f ]] || continue
    local b=${f##*/} keep=0 k
    for k in out err "$@"; do [[ $b == "$k" ]] && keep=1; done
    [[ $keep -eq 1 ]] || left+=" $b"
  done
  [[ -z $left ]] || fail "files left behind:$left"
}
needs_bake() {
  if [[ ! -x ${VFF_BAKE:-/nonexistent} || ! -x ${MESHGEN:-/nonexistent} ]]; then
    echo "SKIP: vff-bake or vff-procedural-mesh is not built (needs Embree and VFF_BUILD_SAMPLES)"
    return 1
  fi
}
