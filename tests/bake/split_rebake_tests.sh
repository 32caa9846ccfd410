#!/usr/bin/env bash
# split_rebake_tests.sh - vff-bake --split run again over the set of an earlier run: the new fields
# and description replace the old set as one unit. Interrupted (SIGINT, SIGTERM, SIGHUP) while any
# object is baked, the old description and every field it names stay, byte for byte, and no
# temporary is left; a run that completes leaves exactly the new set.
#
# Every function named test_* is one ctest case (tests/bake/CMakeLists.txt finds them in this file):
# `bash split_rebake_tests.sh test_NAME` runs one. Environment:
#   VFF_BAKE     the vff-bake executable
#   VFF_INSPECT  the vff-inspect executable
#   MESHGEN      the vff-procedural-mesh executable (--gltf-scene writes the sample scene)
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_BAKE:?}" "${VFF_INSPECT:?}" "${MESHGEN:?}" "${WORK:?}"

here="$(dirname "${BASH_SOURCE[0]}")"
source "$here/../common/cli_harness.sh"

# The sample scene's default scene has three mesh nodes (0, 1, 3): --split node bakes three objects,
# printing "object K/3" as each is complete. The rebake's options differ from the first bake's, and
# each of its objects takes a while on one thread, so that a signal sent when "object K/3" appears
# arrives while object K+1 is baked.
OLD_OPTIONS=(-n 2 -m 8)
NEW_OPTIONS=(-m 32 -j 1)
SET=""   # the folder of the set (t.vffscene.json and its fields)
PID=""   # the rebake running in the background

sample() { "$MESHGEN" --gltf-scene "$WORK/s.gltf" >/dev/null || fail "vff-procedural-mesh --gltf-scene"; }
# The file names (uri) the description $1 lists, one a line.
uris() {
  python3 -c "import json,sys; print('\n'.join(f['uri'] for f in json.load(open(sys.argv[1]))['fields']))" "$1"
}
# split_bake DIR SPLIT OPTIONS...: DIR/t.vffscene.json and its fields, uninterrupted.
split_bake() {
  local dir=$1 split=$2
  shift 2
  mkdir -p "$dir"
  run "$VFF_BAKE" "$WORK/s.gltf" --split "$split" -o "$dir/t.vffscene.json" "$@"
  expect_rc 0
}
# The names in a folder, hidden ones too, sorted.
listing() { (cd "$1" && find . -mindepth 1 -printf '%P\n' | LC_ALL=C sort); }
# snapshot: a copy of $SET (kept in $WORK/snap) to compare the set with after a rebake.
snapshot() {
  rm -rf "$WORK/snap"
  cp -a "$SET" "$WORK/snap"
}
# difference EXPECTED: prints how $SET differs from the folder EXPECTED: other names (a temporary, a
# leftover of another set), other bytes, a field the description names that is missing or does not
# validate; prints nothing when they are the same.
difference() {
  local expected=$1 f
  if [[ $(listing "$SET") != "$(listing "$expected")" ]]; then
    echo "the folder holds $(listing "$SET" | tr '\n' ' '), expected $(listing "$expected" | tr '\n' ' ')"
    return
  fi
  for f in $(listing "$expected"); do
    cmp -s "$SET/$f" "$expected/$f" || { echo "$f differs"; return; }
  done
  for f in $(uris "$SET/t.vffscene.json"); do
    [[ -f $SET/$f ]] || { echo "the description names $f, which is missing"; return; }
    "$VFF_INSPECT" "$SET/$f" --validate >/dev/null 2>&1 || { echo "$f does not validate"; return; }
  done
}
# same_set EXPECTED WHAT: $SET holds exactly the files of EXPECTED, byte for byte, and they load.
same_set() {
  local why
  why=$(difference "$1")
  [[ -z $why ]] || fail "$2: $why"
}
no_temporaries() {
  local left
  left=$(listing "$SET" | grep -E '\.tmp-' || true)
  [[ -z $left ]] || fail "$1: temporaries left: $left"
}
# start_rebake SPLIT: the rebake of $SET with NEW_OPTIONS, in the background (PID), stderr in
# $WORK/rebake.err.
start_rebake() {
  set -m  # job control: the background bake does not start with SIGINT ignored
  "$VFF_BAKE" "$WORK/s.gltf" --split "$1" -o "$SET/t.vffscene.json" "${NEW_OPTIONS[@]}" 2>"$WORK/rebake.err" &
  PID=$!
  set +m
}
# wait_for K: returns once the rebake has begun object K+1 (K = 0: its first temporary exists; else:
# it printed "object K/3"), or has ended.
wait_for() {
  local k=$1
  for _ in $(seq 3000); do
    if [[ $k -eq 0 ]]; then
      compgen -G "$SET/.*.tmp-$PID-*" >/dev/null && return 0
    else
      grep -q "object $k/3 " "$WORK/rebake.err" && return 0
    fi
    kill -0 "$PID" 2>/dev/null || return 0
    sleep 0.01
  done
  fail "the rebake reached no object $k in 30 s"
}
# interrupt SIG: sends SIG to the rebake (if still running); RC: its exit status.
interrupt() {
  kill -s "$1" "$PID" 2>/dev/null || true
  RC=0
  wait "$PID" || RC=$?
}
# interrupted_at K SIG: the old set (--split node) is intact after a rebake interrupted by SIG while
# object K+1 is baked.
interrupted_at() {
  local k=$1 sig=$2
  sample
  SET=$WORK/set
  split_bake "$SET" node "${OLD_OPTIONS[@]}"
  snapshot
  start_rebake node
  wait_for "$k"
  grep -q "object 3/3 " "$WORK/rebake.err" && fail "SIG$sig at object $k: the rebake finished every object first"
  interrupt "$sig"
  [[ $RC -eq $((128 + $(kill -l "$sig"))) ]] ||
    { cat "$WORK/rebake.err" >&2; fail "SIG$sig at object $k: exit status $RC, expected killed by the signal"; }
  same_set "$WORK/snap" "SIG$sig at object $k"
  no_temporaries "SIG$sig at object $k"
}

test_interrupt_at_object_0_keeps_the_old_set() { interrupted_at 0 INT; }
test_interrupt_at_object_1_keeps_the_old_set() { interrupted_at 1 INT; }
test_interrupt_at_object_2_keeps_the_old_set() { interrupted_at 2 INT; }
test_term_and_hup_keep_the_old_set() {
  interrupted_at 1 TERM
  interrupted_at 2 HUP
}

# SIGINT once the last object is complete: while the description is written (and synced) or the set
# renamed into place, or after. Either the old set is whole or the new one, the same files as an
# uninterrupted rebake. (The two descriptions may be the same bytes: the options are not in them.)
test_interrupt_after_the_last_object_leaves_one_whole_set() {
  sample
  split_bake "$WORK/ref" node "${NEW_OPTIONS[@]}"
  SET=$WORK/set
  local round old new
  for round in 1 2 3; do
    rm -rf "$SET"
    split_bake "$SET" node "${OLD_OPTIONS[@]}"
    snapshot
    start_rebake node
    wait_for 3
    interrupt INT
    [[ $RC -eq 0 || $RC -eq 130 ]] ||
      { cat "$WORK/rebake.err" >&2; fail "round $round: SIGINT after the last object: exit status $RC"; }
    old=$(difference "$WORK/snap")
    new=$(difference "$WORK/ref")
    [[ -z $old || -z $new ]] ||
      fail "round $round: SIGINT after the last object: neither the old set ($old) nor the new one ($new)"
    echo "round $round: exit status $RC, $([[ -z $old ]] && echo "the old set" || echo "the new set")"
  done
}

# A rebake that completes replaces the set: the same files as the same bake into an empty folder,
# nothing else (no temporary).
test_uninterrupted_rebake_replaces_the_set() {
  sample
  split_bake "$WORK/ref" node "${NEW_OPTIONS[@]}"
  SET=$WORK/set
  split_bake "$SET" node "${OLD_OPTIONS[@]}"
  split_bake "$SET" node "${NEW_OPTIONS[@]}"
  same_set "$WORK/ref" "the rebake"
  no_temporaries "the rebake"
}

# Another --split gives other file names: interrupted, the old set stays and none of the new fields
# does; completed, the old fields the new description no longer names are gone, a file no
# description names stays.
test_rebake_with_other_names_replaces_the_set_whole() {
  sample
  split_bake "$WORK/ref" node "${NEW_OPTIONS[@]}"
  SET=$WORK/set
  split_bake "$SET" mesh "${OLD_OPTIONS[@]}"
  [[ $(uris "$SET/t.vffscene.json" | tr '\n' ' ') == "t.mesh0.vff t.mesh1.node3.vff " ]] ||
    fail "the mesh split wrote $(uris "$SET/t.vffscene.json")"
  snapshot
  start_rebake node
  wait_for 2
  interrupt INT
  [[ $RC -eq 130 ]] || fail "exit status $RC, expected 130"
  same_set "$WORK/snap" "SIGINT at object 2 of a node split over a mesh split"
  echo notes >"$SET/t.notes.vff"
  echo notes >"$WORK/ref/t.notes.vff"
  split_bake "$SET" node "${NEW_OPTIONS[@]}"
  same_set "$WORK/ref" "a node split over a mesh split"
  no_temporaries "a node split over a mesh split"
}

# A rebake killed outright (SIGKILL: no handler runs) leaves the old set and its temporaries; the
# next run removes those (their process is gone) and replaces the set.
test_temporaries_of_a_killed_rebake_are_removed_by_the_next() {
  sample
  split_bake "$WORK/ref" node "${NEW_OPTIONS[@]}"
  SET=$WORK/set
  split_bake "$SET" node "${OLD_OPTIONS[@]}"
  snapshot
  start_rebake node
  wait_for 1
  sleep 0.2  # into object 2: a finished temporary and the one being written
  interrupt KILL
  [[ $RC -eq 137 ]] || fail "exit status $RC, expected 137 (SIGKILL)"
  cmp -s "$SET/t.vffscene.json" "$WORK/snap/t.vffscene.json" || fail "SIGKILL: the description changed"
  listing "$SET" | grep -q -E '\.tmp-' || fail "SIGKILL left no temporaries (the test did not test)"
  split_bake "$SET" node "${NEW_OPTIONS[@]}"
  same_set "$WORK/ref" "the run after SIGKILL"
  no_temporaries "the run after SIGKILL"
}

run_test "$1"
