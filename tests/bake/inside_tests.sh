#!/usr/bin/env bash
# inside_tests.sh - rays that start inside the bounding sphere, as spec/geometry.md 7.3 and 7.4 and
# vff-query's --help state them: the default intra bias is the formula of 7.3, the `inside` column
# is 1 exactly for a hit that 7.3's reversed ray found (never for a miss), and a bit1 field answers
# no ray from inside.
#
# Every function named test_* is one ctest case bake.inside.NAME (tests/bake/CMakeLists.txt).
# Environment: VFF_BAKE, VFF_QUERY, MESHGEN (vff-procedural-mesh), WORK (a scratch folder).
set -euo pipefail
: "${VFF_BAKE:?}" "${VFF_QUERY:?}" "${MESHGEN:?}" "${WORK:?}"

here="$(dirname "${BASH_SOURCE[0]}")"
source "$here/../common/cli_harness.sh"

# The torus knot baked as octa-hemi2 n 4 (82 maps) of 16x16 texels, ENCODING (unorm8-diameter).
knot() {
  "$MESHGEN" torus-knot "$WORK/knot.obj" || fail "mesh generator"
  run "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/knot.vff" -n 4 -m 16 -q --encoding "${1:-unorm8-diameter}"
  expect_rc 0
}

# 2000 rays from points inside the knot's sphere (radius about 1.05), in fixed pseudo-random
# directions: CSV ox,oy,oz,dx,dy,dz.
inside_rays() {
  awk 'BEGIN { srand(7); for (k = 0; k < 2000; ++k) {
         printf "%.6f,%.6f,%.6f,%.6f,%.6f,%.6f\n", 1.2*rand()-0.6, 1.2*rand()-0.6, 1.2*rand()-0.6,
                2*rand()-1, 2*rand()-1, 2*rand()-1 + 0.001 } }' >"$WORK/rays.csv"
}

test_inside_is_one_only_for_hits_from_inside() {
  knot
  inside_rays
  # and rays from outside the sphere (x = 3) toward the knot
  printf '3,0,0,-1,0,0\n0,3,0,0,-1,0\n' >>"$WORK/rays.csv"
  run "$VFF_QUERY" "$WORK/knot.vff" -i "$WORK/rays.csv" --columns hit,inside
  expect_rc 0
  # no miss says inside; some hits from inside do, and the two from outside do not
  [[ $(grep -c '^0,1$' "$WORK/out") -eq 0 ]] || fail "a miss has inside 1"
  local inside_hits outside
  inside_hits=$(head -n 2001 "$WORK/out" | grep -c '^1,1$' || true)
  [[ $inside_hits -gt 0 ]] || fail "no hit from inside the sphere has inside 1"
  [[ $(grep -c '^0,0$' "$WORK/out") -gt 0 ]] || fail "no ray from inside misses: the test shows nothing"
  outside=$(tail -n 2 "$WORK/out" | tr '\n' ' ')
  [[ $outside == "1,0 1,0 " ]] || fail "rays from outside: $outside, expected two hits with inside 0"
  run "$VFF_QUERY" --help
  expect_out "inside: 1 for a hit found from inside"
}

# spec/geometry.md 7.3: the default bias is 2 * step + sqrt(4 pi / mapCount) of R, step the
# encoding's quantisation step for R = 1: 2 / 254 for unorm8-diameter.
test_default_intra_bias_is_the_formula() {
  knot
  inside_rays
  local bias
  bias=$(awk 'BEGIN { printf "%.7f", 2 * 2 / 254 + sqrt(4 * 3.14159265358979 / 82) }')
  "$VFF_QUERY" "$WORK/knot.vff" -i "$WORK/rays.csv" --columns hit,t >"$WORK/default.csv" || fail "query"
  "$VFF_QUERY" "$WORK/knot.vff" -i "$WORK/rays.csv" --columns hit,t --intra-bias "$bias" >"$WORK/formula.csv" ||
    fail "query"
  cmp -s "$WORK/default.csv" "$WORK/formula.csv" || fail "the default bias is not $bias of R"
  # a bias a little off answers some rays otherwise, so the comparison above can fail
  local other
  for other in 0.3 0.5; do
    "$VFF_QUERY" "$WORK/knot.vff" -i "$WORK/rays.csv" --columns hit,t --intra-bias "$other" >"$WORK/other.csv"
    ! cmp -s "$WORK/default.csv" "$WORK/other.csv" || fail "bias $other answers as the default $bias"
  done
}

# spec/geometry.md 7.3 and 7.4: a bit1 field stores no distance, so no ray from inside the sphere is
# occluded, on the object or off it; rays from outside still hit.
test_bit1_answers_no_ray_from_inside() {
  knot bit1
  inside_rays
  local origin
  for origin in on-object off-object; do
    run "$VFF_QUERY" "$WORK/knot.vff" -i "$WORK/rays.csv" --columns hit,inside --ray-origin "$origin"
    expect_rc 0
    [[ $(grep -c '^0,0$' "$WORK/out") -eq 2000 ]] || fail "$origin: a ray from inside a bit1 field hit"
  done
  run "$VFF_QUERY" "$WORK/knot.vff" --ray 3 0 0 -1 0 0 --columns hit,inside
  expect_out "1,0"
}

run_test "$1"
