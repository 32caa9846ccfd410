#!/usr/bin/env bash
# levelset_tests.sh - vff-bake from an OpenVDB level set (.vdb): distances and normals against exact
# geometry, determinism, grid choice, metadata and bad files.
#
# Every function named test_* is one ctest case (tests/bake/CMakeLists.txt finds them in this file):
# `bash levelset_tests.sh test_NAME` runs one. Environment:
#   VFF_BAKE     the vff-bake executable
#   VFF_INSPECT  the vff-inspect executable
#   VDB_CHECK    the vff_vdb_check executable (tests/convert/vdb_check.cpp: writes the .vdb inputs,
#                checks baked fields against the exact sphere)
#   MESHGEN      the vff-procedural-mesh executable, or empty (samples not built: that test skips)
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_BAKE:?}" "${VFF_INSPECT:?}" "${VDB_CHECK:?}" "${WORK:?}"

source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"
bake() { run "$VFF_BAKE" "$@"; }
vdb() { "$VDB_CHECK" write "$@" || fail "vdb_check write $*"; }
# The test sphere: radius 1 at (0.25, -0.5, 0.125), voxels of 0.02 (188,730 active voxels).
C=(0.25 -0.5 0.125)
SPHERE=sphere,ball,1,0.25,-0.5,0.125,0.02
# sphere_error FIELD R H: every texel within the bounds of vdb_check.cpp (sphereError) for the
# sphere (C, R) sampled with voxel size H.
sphere_error() {
  run "$VDB_CHECK" sphere-error "$1" "${C[@]}" "$2" "$3"
  cat "$WORK/out"
  [[ $RC -eq 0 ]] || { show; fail "$1: texels outside the bounds of the exact sphere"; }
}
no_output() { [[ ! -e $1 ]] || fail "output $1 left behind"; }

# ---- Distances and normals against the exact sphere --------------------------------------------------
# unorm16-diameter (a step of 2R / 65535): the check is dominated by the level set's own error, a
# distance between the spheres of radius r -+ eps with eps = (h^2 / 8) * 3 / (r - sqrt(3) h).
test_sphere_unorm16_distances_and_normals() {
  vdb "$WORK/s.vdb" "$SPHERE"
  bake "$WORK/s.vdb" -o "$WORK/s.vff" -n 3 -m 32 --encoding unorm16-diameter --normals -q
  expect_rc 0
  sphere_error "$WORK/s.vff" 1 0.02
  # A user sphere close around the object: more hits, the same bounds.
  bake "$WORK/s.vdb" -o "$WORK/t.vff" -n 3 -m 32 --encoding unorm16-diameter --normals -q \
    --center "${C[@]}" --radius 1.1
  expect_rc 0
  sphere_error "$WORK/t.vff" 1 0.02
  run "$VFF_INSPECT" "$WORK/t.vff" --validate
  expect_rc 0
}

# The paper's encoding (a step of 2R / 255) and chord normalisation.
test_sphere_unorm8_encodings() {
  vdb "$WORK/s.vdb" "$SPHERE"
  bake "$WORK/s.vdb" -o "$WORK/d.vff" -n 4 -m 16 -q
  expect_rc 0
  sphere_error "$WORK/d.vff" 1 0.02
  bake "$WORK/s.vdb" -o "$WORK/c.vff" -n 4 -m 16 --encoding unorm8-chord -q --center "${C[@]}" --radius 1.05
  expect_rc 0
  sphere_error "$WORK/c.vff" 1 0.02
  bake "$WORK/s.vdb" -o "$WORK/b.vff" -n 4 -m 16 --encoding bit1 -q
  expect_rc 0
  sphere_error "$WORK/b.vff" 1 0.02
}

# A grid rotated and shifted against world space: distances from the world-space rays, normals
# taken from index space to world space (inverse transpose of the Jacobian).
test_rotated_grid_world_space_normals() {
  vdb "$WORK/r.vdb" rotsphere,ball,1,0.25,-0.5,0.125,0.03
  bake "$WORK/r.vdb" -o "$WORK/r.vff" -n 3 -m 32 --encoding unorm16-diameter --normals -q --center "${C[@]}" \
    --radius 1.2
  expect_rc 0
  sphere_error "$WORK/r.vff" 1 0.03
}

# ---- The sphere from the active voxels ---------------------------------------------------------------
# Default sphere: the minimal sphere around the corners of the active voxels' box. The band reaches
# 3 voxels past the surface, so the box is the cube of half side r + 3h (to the voxel centres)
# around C, and its sphere has radius sqrt(3) (r + 3h) and centre C, within a voxel.
test_default_sphere_from_active_voxels() {
  vdb "$WORK/s.vdb" "$SPHERE"
  bake "$WORK/s.vdb" -o "$WORK/s.vff" -n 1 -m 8 --json
  expect_rc 0
  python3 - "$WORK/out" <<'EOF' || { show; fail "sphere"; }
import json, math, sys
j = json.load(open(sys.argv[1]))
c, r, h = (0.25, -0.5, 0.125), 1.0, 0.02
s = j["sphere"]
assert all(abs(a - b) <= h for a, b in zip(s["center"], c)), s
assert abs(s["radius"] - math.sqrt(3) * (r + 3 * h)) <= math.sqrt(3) * h, s
assert j["grid"] == "ball" and j["activeVoxels"] == 188730 and abs(j["voxelSize"] - h) < 1e-7, j
assert j["maps"] == 10 and j["rays"] == 640 and 0 < j["hits"] < 640, j
EOF
}

# ---- Determinism ------------------------------------------------------------------------------------
test_same_bytes_any_thread_count() {
  vdb "$WORK/s.vdb" "$SPHERE"
  local t
  for t in 1 2 3; do
    bake "$WORK/s.vdb" -o "$WORK/s$t.vff" -n 3 -m 16 --normals -j "$t" -q
    expect_rc 0
  done
  cmp "$WORK/s1.vff" "$WORK/s2.vff" || fail "1 vs 2 threads differ"
  cmp "$WORK/s1.vff" "$WORK/s3.vff" || fail "1 vs 3 threads differ"
}

# ---- A mesh's level set against the mesh ---------------------------------------------------------------
# meshToLevelSet of the procedural torus knot, baked with the mesh bake's sphere: the same field
# within the level set's error (thresholds in vdb_check.cpp, compareMesh).
test_mesh_level_set_matches_mesh_bake() {
  if [[ -z ${MESHGEN:-} ]]; then
    echo "SKIP: vff-procedural-mesh is not built (VFF_BUILD_SAMPLES=OFF)"
    return 0
  fi
  "$MESHGEN" torus-knot "$WORK/knot.obj" || fail "mesh generator"
  vdb "$WORK/knot.vdb" mesh,knot,torus-knot,0.01
  bake "$WORK/knot.obj" -o "$WORK/mesh.vff" -n 3 -m 32 --encoding unorm16-diameter --json
  expect_rc 0
  local sphere
  sphere=$(python3 -c 'import json,sys; s=json.load(open(sys.argv[1]))["sphere"]; print(*s["center"], "--radius", s["radius"])' "$WORK/out")
  # shellcheck disable=SC2086
  bake "$WORK/knot.vdb" -o "$WORK/ls.vff" -n 3 -m 32 --encoding unorm16-diameter -q --center $sphere
  expect_rc 0
  run "$VDB_CHECK" compare-mesh "$WORK/mesh.vff" "$WORK/ls.vff" 0.01
  cat "$WORK/out"
  [[ $RC -eq 0 ]] || { show; fail "the level set's field differs from the mesh's"; }
}

# ---- Choosing the grid -------------------------------------------------------------------------------
# A fog volume first, then two level sets written "small" before "large": the default is the first
# level set in OpenVDB's listing order, which is by name ("large", as vdb_print lists them); --grid
# picks another; --grid naming a fog volume or nothing is an error that lists the grids.
test_grid_option() {
  vdb "$WORK/g.vdb" fog,density sphere,small,0.5,0.25,-0.5,0.125,0.02 sphere,large,1,0.25,-0.5,0.125,0.02
  bake "$WORK/g.vdb" -o "$WORK/default.vff" -n 2 -m 16 --encoding unorm16-diameter --json
  expect_rc 0
  expect_out '"grid": "large"'
  sphere_error "$WORK/default.vff" 1 0.02
  bake "$WORK/g.vdb" -o "$WORK/small.vff" -n 2 -m 16 --encoding unorm16-diameter --grid small -q
  expect_rc 0
  sphere_error "$WORK/small.vff" 0.5 0.02
  bake "$WORK/g.vdb" -o "$WORK/x.vff" --grid density
  expect_rc 5
  expect_err "g.vdb"
  expect_err "fog volume"
  bake "$WORK/g.vdb" -o "$WORK/x.vff" --grid nothere
  expect_rc 1
  expect_err '"nothere"'
  expect_err '"small" (float, level set)'
  no_output "$WORK/x.vff"
}

# ---- Metadata ----------------------------------------------------------------------------------------
test_metadata_names_the_level_set() {
  vdb "$WORK/s.vdb" "$SPHERE"
  bake "$WORK/s.vdb" -o "$WORK/s.vff" -n 1 -m 8 --normals -q
  expect_rc 0
  run "$VFF_INSPECT" "$WORK/s.vff" --format json
  expect_rc 0
  python3 - "$WORK/out" "$WORK/s.vdb" <<'EOF' || { show; fail "metadata"; }
import json, sys
j = json.load(open(sys.argv[1]))
def find(o, key):
    if isinstance(o, dict):
        if key in o: return o[key]
        for v in o.values():
            r = find(v, key)
            if r is not None: return r
    return None
src, bake = find(j, "vff.source"), find(j, "vff.bake")
assert find(j, "vff.generator") == "vff-bake", j
assert src["name"] == "s.vdb" and src["format"] == "vdb" and src["grid"] == "ball", src
assert src["activeVoxels"] == 188730, src
assert len(src["xxh3"]) == 16 and all(c in "0123456789abcdef" for c in src["xxh3"]), src
assert bake["normals"] == "gradient" and bake["sphere"] == "active-voxel-bounds", bake
assert bake["surface"] == "level set zero crossing", bake
EOF
}

# ---- Bad inputs: clear errors, documented exit codes, no output ----------------------------------------
test_bad_vdb_files() {
  printf 'not a volume at all\n' >"$WORK/text.vdb"
  bake "$WORK/text.vdb" -o "$WORK/x.vff"
  expect_rc 3
  expect_err "text.vdb"
  expect_err "not an OpenVDB file"
  vdb "$WORK/s.vdb" "$SPHERE"
  head -c 2000 "$WORK/s.vdb" >"$WORK/cut.vdb"
  bake "$WORK/cut.vdb" -o "$WORK/x.vff"
  expect_rc 3
  expect_err "cut.vdb"
  vdb "$WORK/none.vdb"
  bake "$WORK/none.vdb" -o "$WORK/x.vff"
  expect_rc 3
  expect_err "no grid"
  vdb "$WORK/emptyls.vdb" emptyls,hollow
  bake "$WORK/emptyls.vdb" -o "$WORK/x.vff"
  expect_rc 3
  expect_err "no active voxel"
  local f
  for f in fog,density vector,v float,plain; do
    vdb "$WORK/u.vdb" "$f"
    bake "$WORK/u.vdb" -o "$WORK/x.vff"
    expect_rc 5
    expect_err "u.vdb"
    expect_err "no float grid of class level set"
  done
  vdb "$WORK/st.vdb" stretched,ball
  bake "$WORK/st.vdb" -o "$WORK/x.vff"
  expect_rc 5
  expect_err "non-cubic voxels"
  bake "$WORK/missing.vdb" -o "$WORK/x.vff"
  expect_rc 2
  expect_err "missing.vdb"
  no_output "$WORK/x.vff"
}

test_options_that_do_not_apply() {
  vdb "$WORK/s.vdb" "$SPHERE"
  bake "$WORK/s.vdb" --benchmark
  expect_rc 1
  expect_err "--benchmark"
  printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' >"$WORK/box.obj"
  bake "$WORK/box.obj" -o "$WORK/x.vff" --grid ball
  expect_rc 1
  expect_err "--grid"
  bake "$WORK/s.vdb" -o "$WORK/x.vff" -n 0
  expect_rc 1
  bake "$WORK/s.vdb" -o "$WORK/x.vff" --center 0 0 0
  expect_rc 1
  no_output "$WORK/x.vff"
  # An unwritable destination: exit 2, naming it, before any baking.
  bake "$WORK/s.vdb" -o "$WORK/no/such/dir/x.vff" -n 1 -m 8
  expect_rc 2
  expect_err "x.vff"
}

# ---- Runner --------------------------------------------------------------------------------------------
[[ $# -eq 1 && $1 == test_* ]] || { echo "usage: $0 test_NAME" >&2; exit 2; }
run_test "$1"
