#!/usr/bin/env bash
# mesh_cli_tests.sh - vff-bake on mesh inputs: PLY triangle strips, user spheres that do not enclose
# the mesh, the report of dropped triangles, interrupted bakes.
#
# Every function named test_* is one ctest case (tests/bake/CMakeLists.txt finds them in this file):
# `bash mesh_cli_tests.sh test_NAME` runs one. Environment:
#   VFF_BAKE     the vff-bake executable
#   VFF_INSPECT  the vff-inspect executable
#   MESHGEN      the vff-procedural-mesh executable
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_BAKE:?}" "${VFF_INSPECT:?}" "${MESHGEN:?}" "${WORK:?}"

here="$(dirname "${BASH_SOURCE[0]}")"
source "$here/../common/cli_harness.sh"
bake() { run "$VFF_BAKE" "$@"; }
knot() { "$MESHGEN" torus-knot "$WORK/knot.obj" || fail "mesh generator"; }

# ---- PLY triangle strips -------------------------------------------------------------------------
# The same mesh as a face list and as one `tristrips` list (ply_strips.py), ASCII and binary: the
# same field, byte for byte (the metadata names the file, "m.ply" in each folder, and hashes the
# mesh as read).
test_ply_tristrips_bake_like_the_face_list() {
  knot
  python3 "$here/ply_strips.py" "$WORK/knot.obj" "$WORK" >/dev/null || fail "ply_strips.py"
  for d in faces-ascii strips-ascii faces-binary strips-binary; do
    bake "$WORK/$d/m.ply" -o "$WORK/$d/m.vff" -n 3 -m 16 -q
    expect_rc 0
  done
  for d in strips-ascii faces-binary strips-binary; do
    cmp "$WORK/faces-ascii/m.vff" "$WORK/$d/m.vff" || fail "$d bakes another field than faces-ascii"
  done
  run "$VFF_INSPECT" "$WORK/strips-binary/m.vff" --format json
  expect_out '"triangles": 8192'
}

# A strip list whose length claims more than the file holds: invalid input naming the file and row.
test_ply_tristrips_longer_than_the_file_is_refused() {
  {
    printf 'ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n'
    printf 'property float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n'
    head -c 36 /dev/zero
    printf '\x00\x00\x00\x70\x00\x00\x00\x00\x01\x00\x00\x00\x02\x00\x00\x00'
  } >"$WORK/long.ply"
  bake "$WORK/long.ply" -o "$WORK/x.vff"
  expect_rc 3
  expect_err "long.ply: mesh-parse (10002): element 1 row 0: the file ends inside the body"
  [[ ! -e $WORK/x.vff ]] || fail "output left behind"
  printf 'ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement tristrips 1\nproperty list int int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n4000000000 0 1 2\n' >"$WORK/long_ascii.ply"
  bake "$WORK/long_ascii.ply" -o "$WORK/x.vff"
  expect_rc 3
  expect_err "long_ascii.ply: mesh-parse (10002): element 1 row 0: missing or malformed value"
  [[ ! -e $WORK/x.vff ]] || fail "output left behind"
}

# ---- A user sphere that does not enclose the mesh --------------------------------------------------
# The torus knot's farthest vertex is 1.05 from the origin.
test_user_sphere_cutting_the_mesh_is_a_usage_error() {
  knot
  bake "$WORK/knot.obj" -o "$WORK/x.vff" -n 1 -m 8 --center 0 0 0 --radius 0.5
  expect_rc 1
  expect_err_re "the sphere of radius 0.5 does not enclose .*knot.obj: its farthest vertex is 1.04[0-9]* from the centre"
  expect_err "--allow-clipped-sphere"
  [[ ! -e $WORK/x.vff ]] || fail "output left behind"
  bake "$WORK/knot.obj" -o "$WORK/x.vff" --allow-clipped-sphere
  expect_rc 1
  expect_err "--allow-clipped-sphere needs --center and --radius"
}

test_allow_clipped_sphere_bakes_warns_and_records_it() {
  knot
  bake "$WORK/knot.obj" -o "$WORK/x.vff" -n 1 -m 8 --center 0 0 0 --radius 0.5 --allow-clipped-sphere -q
  expect_rc 0
  expect_err "vff-bake: warning: the sphere of radius 0.5 does not enclose"
  valid "$WORK/x.vff"
  run "$VFF_INSPECT" "$WORK/x.vff" --format json
  expect_out '"sphereEnclosesMesh": false'
}

# An enclosing sphere, the user's or the default one: no warning, no key (the files of before).
test_enclosing_sphere_is_unchanged() {
  knot
  for sphere in "" "--center 0 0 0 --radius 1.1"; do
    # shellcheck disable=SC2086
    bake "$WORK/knot.obj" -o "$WORK/x.vff" -n 1 -m 8 -q $sphere
    expect_rc 0
    expect_no_err
    run "$VFF_INSPECT" "$WORK/x.vff" --format json
    expect_rc 0
    ! grep -q sphereEnclosesMesh "$WORK/out" || fail "sphereEnclosesMesh written for an enclosing sphere ($sphere)"
  done
}

# ---- Dropped degenerate triangles ------------------------------------------------------------------
# Two of the four triangles have zero area: one line on stderr with the count, not with -q, none
# for a mesh without.
test_dropped_degenerate_triangles_are_reported() {
  printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nv 2 0 0\nv 0 2 0\nv 0 3 0\nf 1 2 3\nf 1 2 5\nf 1 3 4\nf 3 6 7\n' >"$WORK/d.obj"
  bake "$WORK/d.obj" -o "$WORK/d.vff" -n 1 -m 8
  expect_rc 0
  expect_err "vff-bake: $WORK/d.obj: dropped 2 degenerate (zero-area) triangles"
  [[ $(grep -c "zero-area" "$WORK/err") -eq 1 ]] || { show; fail "not one line"; }
  bake "$WORK/d.obj" -o "$WORK/d.vff" -n 1 -m 8 --json
  expect_rc 0
  expect_err "dropped 2 degenerate"
  expect_out '"droppedDegenerate": 2'
  bake "$WORK/d.obj" -o "$WORK/d.vff" -n 1 -m 8 -q
  expect_rc 0
  expect_no_err
  knot
  bake "$WORK/knot.obj" -o "$WORK/k.vff" -n 1 -m 8
  expect_rc 0
  ! grep -q zero-area "$WORK/err" || { show; fail "reported zero dropped triangles"; }
}

# ---- Interrupted bakes -----------------------------------------------------------------------------
# SIGINT, SIGTERM or SIGHUP in the middle of a bake (a few seconds on one thread): the process ends
# killed by the signal, its temporary is gone, the old output is intact. (SIGKILL cannot be caught:
# tests/crash.)
test_interrupted_bake_removes_its_temporary() {
  knot
  local sig num pid rc tmp
  for sig in INT TERM HUP; do
    echo old >"$WORK/out.vff"
    set -m  # job control: the background bake does not start with SIGINT ignored
    "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/out.vff" -m 96 -j 1 -q &
    pid=$!
    set +m
    tmp=""
    for _ in $(seq 400); do
      tmp=$(compgen -G "$WORK/.out.vff.tmp-$pid-*" || true)
      [[ -n $tmp ]] && break
      sleep 0.025
    done
    [[ -n $tmp ]] || fail "SIG$sig: no temporary appeared"
    kill -s "$sig" "$pid"
    rc=0
    wait "$pid" || rc=$?
    num=$(kill -l "$sig")
    [[ $rc -eq $((128 + num)) ]] || fail "SIG$sig: exit status $rc, expected $((128 + num)) (killed by the signal)"
    ! compgen -G "$WORK/.out.vff*.tmp-*" >/dev/null || { ls -la "$WORK"; fail "SIG$sig: a temporary remains"; }
    [[ $(cat "$WORK/out.vff") == old ]] || fail "SIG$sig: the old output changed"
  done
}

# Temporaries of the output's name left by dead processes go; a live process's, and another
# output's, stay.
test_stale_temporaries_of_dead_processes_are_removed() {
  knot
  local dead
  sh -c 'exit 0' &
  dead=$!
  wait "$dead"
  touch "$WORK/.out.vff.tmp-$dead-0" "$WORK/.out.vff.tmp-$dead-7" "$WORK/.out.vff.tmp-$$-0" \
    "$WORK/.other.vff.tmp-$dead-0"
  bake "$WORK/knot.obj" -o "$WORK/out.vff" -n 1 -m 8 -q
  expect_rc 0
  [[ ! -e $WORK/.out.vff.tmp-$dead-0 && ! -e $WORK/.out.vff.tmp-$dead-7 ]] || fail "a dead process's temporary remains"
  [[ -e $WORK/.out.vff.tmp-$$-0 ]] || fail "a live process's temporary was removed"
  [[ -e $WORK/.other.vff.tmp-$dead-0 ]] || fail "another output's temporary was removed"
  valid "$WORK/out.vff"
}

# ---- Refined fields (--refine: section REFN, format 1.3) -----------------------------------------
# A refined bake: format 1.3 with a REFN section holding the mesh, the same bytes on 1 and 2 threads
# (with and without probes), the plain bake's maps; and the options that do not go with it.
test_refine_writes_refn_deterministically() {
  knot
  bake "$WORK/knot.obj" -o "$WORK/plain.vff" -n 4 -m 16 -q
  expect_rc 0
  bake "$WORK/knot.obj" -o "$WORK/r1.vff" -n 4 -m 16 --refine -j 1
  expect_rc 0
  expect_err_re "refined: [0-9]+ of 20992 texels unsure \([0-9.]+%\), [0-9]+ vertices and [0-9]+ triangles"
  bake "$WORK/knot.obj" -o "$WORK/r2.vff" -n 4 -m 16 --refine -j 2 -q
  expect_rc 0
  cmp "$WORK/r1.vff" "$WORK/r2.vff" || fail "--refine depends on the thread count"
  bake "$WORK/knot.obj" -o "$WORK/p1.vff" -n 4 -m 16 --refine --refine-probe -j 1 -q
  bake "$WORK/knot.obj" -o "$WORK/p2.vff" -n 4 -m 16 --refine --refine-probe -j 2 -q
  cmp "$WORK/p1.vff" "$WORK/p2.vff" || fail "--refine-probe depends on the thread count"
  cmp -s "$WORK/p1.vff" "$WORK/r1.vff" && fail "--refine-probe marks the same texels as --refine"
  run "$VFF_INSPECT" "$WORK/r1.vff" --format json --validate
  expect_rc 0
  expect_out '"version": "1.3"'
  expect_out '"REFN"'
  run "$VFF_INSPECT" "$WORK/plain.vff" --format json
  expect_out '"version": "1.0"'
  # The refined file's maps are the plain bake's: the same distance plane, byte for byte.
  run "$VFF_INSPECT" "$WORK/plain.vff" --format json
  mv "$WORK/out" "$WORK/plain.json"
  run "$VFF_INSPECT" "$WORK/r1.vff" --format json
  python3 - "$WORK/plain.json" "$WORK/out" <<'PY' || fail "--refine changed the maps"
import json, sys
a, b = (json.load(open(p)) for p in sys.argv[1:])
dist = lambda d: next(s["checksum"] for s in d["sections"] if s["tag"] == "DIST")
assert dist(a) == dist(b) and a["statistics"] == b["statistics"], "maps differ"
assert a["refinement"] is None and b["refinement"]["triangles"] == 8192, b["refinement"]
PY
}

test_refine_with_options_that_do_not_fit_is_a_usage_error() {
  knot
  bake "$WORK/knot.obj" -o "$WORK/x.vff" -n 1 -m 8 --refine-probe
  expect_rc 1
  expect_err "--refine-probe goes with --refine"
  bake "$WORK/knot.obj" -o "$WORK/x.vff" -n 1 -m 8 --refine --encoding bit1
  expect_rc 1
  expect_err "--refine needs distances; --encoding bit1 has none"
  bake "$WORK/knot.obj" -o "$WORK/x.vff" -n 1 -m 8 --refine --map-range 0:4
  expect_rc 1
  expect_err "--refine needs every map"
  [[ ! -e $WORK/x.vff ]] || fail "output left behind"
}

run_test "$1"
