#!/usr/bin/env bash
# lod_tests.sh - command-line tests of vff-convert's re-encoding and level of detail: --encoding,
# --map-size (--downsample), --positions/--count (--resample), checked against convert_check's
# recomputation and against bakes at the target settings.
#
# Every function named test_* is one ctest case convert.NAME (tests/convert/CMakeLists.txt finds them
# in this file): `bash lod_tests.sh test_NAME` runs one. Environment:
#   VFF_CONVERT  the vff-convert executable
#   VFF_INSPECT  the vff-inspect executable
#   CHECK        the vff_convert_check executable (writes input fields, compares fields)
#   VFF_BAKE     the vff-bake executable, or empty when it is not built (those tests then skip)
#   MESHGEN      the vff-procedural-mesh executable, or empty
#   EXPERIMENTS  the vff-experiments executable, or empty (its test then skips)
#   WORK         a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_CONVERT:?}" "${VFF_INSPECT:?}" "${CHECK:?}" "${WORK:?}"

# ---- Helpers ---------------------------------------------------------------------------------------
source "$(dirname "${BASH_SOURCE[0]}")/convert_harness.sh"
# The tool's "max error X steps" line, as a number.
printed_max_steps() { sed -n 's/.*max error \([0-9.]*\) steps.*/\1/p' "$WORK/out" | head -n 1; }
# le A B: A <= B (decimals).
le() { awk -v a="$1" -v b="$2" 'BEGIN { exit !(a + 0 <= b + 0) }'; }

test_lod_help_lists_options() {
  convert --help
  expect_rc 0
  for opt in --encoding --map-size --downsample --positions --count --resample; do
    expect_out "$opt"
  done
  expect_out "tent"
}

test_reencode_16_to_8_within_half_step() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 16 --normals
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding unorm8-diameter
  expect_rc 0
  expect_out "encoding: unorm16-diameter -> unorm8-diameter: max error"
  local tool
  tool=$(printed_max_steps)
  le "$tool" 0.5005 || { show; fail "the tool reports $tool steps, more than half a step"; }
  valid "$WORK/b.vff"
  # Every texel checked independently: misses stay misses, hits stay hits, within half an 8-bit step,
  # normals untouched; and the checker finds the largest error the tool printed.
  run "$CHECK" texels "$WORK/a.vff" "$WORK/b.vff" --max-steps 0.5005 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "16 -> 8 bit: texels out of bounds"; }
  expect_out "hit->miss 0, miss->hit 0"
  expect_out "hit texels with other normal bytes: 0"
  local checked
  checked=$(sed -n 's/^max error \([0-9.]*\) steps.*/\1/p' "$WORK/out")
  awk -v a="$tool" -v b="$checked" 'BEGIN { exit !((a - b) ^ 2 < 1e-6) }' ||
    fail "the tool printed $tool steps, the checker found $checked"
}

# 8 -> 16 bit is not a plain widening (65534 / 254 = 258.008 is no integer: code 64 becomes 16513,
# not 258 x 64), but it is within half a 16-bit step and converting back gives every code back.
test_reencode_8_to_16_is_reversible() {
  field "$WORK/a.vff" unorm8-diameter --n 2 --m 16 --normals  # every 8-bit code, misses included
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding unorm16-diameter
  expect_rc 0
  expect_out "reversible: converting back to unorm8-diameter gives every code back"
  run "$CHECK" texels "$WORK/a.vff" "$WORK/b.vff" --max-steps 0.5005 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "8 -> 16 bit: texels out of bounds"; }
  convert "$WORK/b.vff" --to vff "$WORK/c.vff" --encoding unorm8-diameter
  expect_rc 0
  run "$CHECK" texels "$WORK/a.vff" "$WORK/c.vff" --max-steps 0 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "8 -> 16 -> 8 bit does not give the original codes"; }
  expect_out "hit texels with other normal bytes: 0"
  valid "$WORK/c.vff"
}

test_reencode_chord_and_diameter() {
  field "$WORK/a.vff" unorm8-chord --n 2 --m 16
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding unorm8-diameter
  expect_rc 0
  le "$(printed_max_steps)" 0.5005 || { show; fail "chord -> diameter: more than half a step"; }
  run "$CHECK" texels "$WORK/a.vff" "$WORK/b.vff" --max-steps 0.5005 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "chord -> diameter: texels out of bounds"; }
  # Diameter -> chord: distances longer than the chord (the fixture's codes are random) hold the
  # largest code and are counted; misses stay misses.
  field "$WORK/d.vff" unorm8-diameter --n 2 --m 16
  convert "$WORK/d.vff" --to vff "$WORK/e.vff" --encoding unorm8-chord
  expect_rc 0
  expect_out_re "^clamped: [0-9]+ hits lie beyond the new scale"
  le "$(printed_max_steps)" 0.5005 || { show; fail "diameter -> chord: more than half a step within the scale"; }
  run "$CHECK" texels "$WORK/d.vff" "$WORK/e.vff" --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "diameter -> chord changed a hit or a miss"; }
  valid "$WORK/e.vff"
}

test_reencode_bit1_keeps_hit_and_miss() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 16 --normals --gutter 2
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding bit1
  expect_rc 0
  expect_out "encoding: unorm16-diameter -> bit1: distances dropped, hit or miss kept"
  expect_out "(2d-array, gutter 0)"  # bit1 tiles have no gutter: the source's 2 is dropped
  run "$CHECK" texels "$WORK/a.vff" "$WORK/b.vff" --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "bit1 changed a hit or a miss"; }
  expect_out "hit texels with other normal bytes: 0"
  valid "$WORK/b.vff"
  # bit1 has no distances to convert back: unsupported, no output.
  convert "$WORK/b.vff" --to vff "$WORK/c.vff" --encoding unorm8-chord
  expect_rc 5
  expect_err "b.vff"
  expect_err "bit1, which holds hit or miss and no distance"
  # An explicit gutter cannot hold either, and bit1 maps are multiples of 8 texels.
  convert "$WORK/a.vff" --to vff "$WORK/c.vff" --encoding bit1 --gutter 2
  expect_rc 1
  field "$WORK/m12.vff" unorm8-diameter --m 12
  convert "$WORK/m12.vff" --to vff "$WORK/c.vff" --encoding bit1
  expect_rc 1
  expect_err "bit1 maps need a size that is a multiple of 8, the source's is 12"
  no_leftovers a.vff b.vff m12.vff
}

# bc4-diameter: lossy, but hits and misses are kept, the tool's RMS error is small on a bake, the
# layout becomes a gutterless 2D array, converting back to unorm8-diameter gives the bc4 distances
# exactly, and an EXR of a bc4 field cannot come back (its blocks cannot be rebuilt exactly).
test_reencode_to_bc4_and_back() {
  needs_bake || return 0
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/a.vff" -n 3 -m 32 --normals --gutter 1 -q || fail "bake"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding bc4-diameter
  expect_rc 0
  expect_out "encoding: unorm8-diameter -> bc4-diameter: max error"
  expect_out "(2d-array, gutter 0)"
  local rms
  rms=$(sed -n 's/.*RMS \([0-9.]*\) steps.*/\1/p' "$WORK/out")
  # Measured 1.93 steps on this 32x32 knot (0.85 on the bunny at 64x64).
  awk -v r="$rms" 'BEGIN { exit !(r > 0 && r < 2.5) }' || { show; fail "RMS $rms steps is not in (0, 2.5)"; }
  run "$CHECK" texels "$WORK/a.vff" "$WORK/b.vff" --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "bc4 changed a hit or a miss"; }
  expect_out "hit->miss 0, miss->hit 0"
  expect_out "hit texels with other normal bytes: 0"
  valid "$WORK/b.vff"
  run "$VFF_INSPECT" "$WORK/b.vff"
  expect_out "vff 1.2"
  expect_out "bc4-diameter"
  convert "$WORK/b.vff" --to vff "$WORK/c.vff" --encoding unorm8-diameter
  expect_rc 0
  run "$CHECK" texels "$WORK/b.vff" "$WORK/c.vff" --max-steps 0 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "bc4 -> unorm8-diameter did not keep the decoded codes"; }
  # Maps of 30 texels cannot hold 4x4 blocks.
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/m30.vff" -n 1 -m 30 -q || fail "bake"
  convert "$WORK/m30.vff" --to vff "$WORK/d.vff" --encoding bc4-diameter
  expect_rc 1
  expect_err "multiple of 4"
  # EXR: out yes (decoded distances), back no.
  convert "$WORK/b.vff" --to exr "$WORK/b.exr"
  expect_rc 0
  convert "$WORK/b.exr" --to vff "$WORK/e.vff"
  expect_rc 5
  expect_err "b.exr"
  expect_err "bc4-diameter"
  no_leftovers knot.obj a.vff b.vff c.vff m30.vff b.exr
}

# Every rule, even and odd factors, an encoding change on top: each new texel is recomputed by
# convert_check from the source texels (the rules as README.md states them) and must match exactly,
# normals included.
test_lod_map_size_rules() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 24 --normals
  local rule size
  for rule in min majority centre tent; do
    for size in 12 8 6 1; do
      convert "$WORK/a.vff" --to vff "$WORK/$rule$size.vff" --map-size "$size" --downsample "$rule"
      expect_rc 0
      expect_out "map size: 24 -> $size, downsample $rule"
      run "$CHECK" downsample "$WORK/a.vff" "$WORK/$rule$size.vff" "$rule"
      [[ $RC -eq 0 ]] || { show; fail "--map-size $size --downsample $rule: texels differ from the rule"; }
      expect_out "codes differing 0, normals differing 0"
    done
  done
  valid "$WORK/tent6.vff"
  convert "$WORK/a.vff" --to vff "$WORK/c.vff" --map-size 8 --downsample min --encoding unorm8-chord
  expect_rc 0
  run "$CHECK" downsample "$WORK/a.vff" "$WORK/c.vff" min
  [[ $RC -eq 0 ]] || { show; fail "--map-size with --encoding: texels differ from the rule"; }
  # The default rule is tent.
  convert "$WORK/a.vff" --to vff "$WORK/d.vff" --map-size 8
  expect_rc 0
  expect_out "downsample tent"
}

# An odd factor's centre rule takes the texel whose centre is the new texel's centre: the same ray
# as a bake at the smaller size, so the result is that bake, byte for byte.
test_lod_map_size_centre_odd_factor_is_a_bake() {
  needs_bake || return 0
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/m24.vff" -n 3 -m 24 --normals -q || fail "bake"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/m8.vff" -n 3 -m 8 --normals -q || fail "bake"
  convert "$WORK/m24.vff" --to vff "$WORK/c8.vff" --map-size 8 --downsample centre
  expect_rc 0
  run "$CHECK" texels "$WORK/m8.vff" "$WORK/c8.vff" --max-steps 0 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "centre of a 3x reduction differs from the bake"; }
  expect_out "hit texels with other normal bytes: 0"
}

test_lod_usage_errors() {
  field "$WORK/a.vff" unorm8-diameter --m 16
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --map-size 5
  expect_rc 1
  expect_err "--map-size 5"
  expect_err "allowed: 1, 2, 4, 8, 16"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --map-size 32
  expect_rc 1
  expect_err "must divide the source's 16"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --map-size 4 --encoding bit1
  expect_rc 1
  expect_err "multiple of 8 (bit1); allowed: 8, 16"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --downsample min
  expect_rc 1
  expect_err "--downsample applies with --map-size only"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --resample interpolated
  expect_rc 1
  expect_err "--resample applies with --positions or --count only"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --count 2000
  expect_rc 1
  expect_err "1 <= n <= 1024"
  # 2^24 samples of 16 x 16 texels with normals: 24 GiB of maps, refused before any work.
  field "$WORK/n.vff" unorm16-diameter --m 16 --normals
  convert "$WORK/n.vff" --to vff "$WORK/b.vff" --positions fibonacci --count 16777216
  expect_rc 1
  expect_err "above vff-convert's limit of 17179869184"
  convert "$WORK/a.vff" --to exr "$WORK/b.exr" --encoding unorm8-chord
  expect_rc 1
  expect_err "--to vff only"
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --downsample mode
  expect_rc 1
  no_leftovers a.vff n.vff
}

# octa-hemi2 n's samples are every other sample of 2n, so the nearest resampling of a 2n bake is
# the n bake, byte for byte; interpolated and a non-nested source stay within the stated bounds
# (tools/vff-convert/README.md).
test_lod_fewer_samples_vs_bake() {
  needs_bake || return 0
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/n8.vff" -n 8 -m 16 --encoding unorm16-diameter --normals -q || fail "bake"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/n4.vff" -n 4 -m 16 --encoding unorm16-diameter --normals -q || fail "bake"
  convert "$WORK/n8.vff" --to vff "$WORK/near.vff" --count 4
  expect_rc 0
  expect_out "positions: octa-hemi2 n=8 (290 maps) -> octa-hemi2 n=4 (82 maps), resample nearest"
  run "$CHECK" texels "$WORK/n4.vff" "$WORK/near.vff" --max-steps 0 --max-flips 0
  [[ $RC -eq 0 ]] || { show; fail "nearest resampling of a nested sample set is not the bake"; }
  expect_out "hit texels with other normal bytes: 0"
  valid "$WORK/near.vff"
  convert "$WORK/n8.vff" --to vff "$WORK/interp.vff" --count 4 --resample interpolated
  expect_rc 0
  run "$CHECK" texels "$WORK/n4.vff" "$WORK/interp.vff" --min-agreement 99 --max-mean-error 0.06
  [[ $RC -eq 0 ]] || { show; fail "interpolated resampling is beyond its bounds"; }
  # Not nested: 1000 Fibonacci samples down to octa-hemi2 n = 4.
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/fib.vff" --positions fibonacci -n 1000 -m 16 --encoding unorm16-diameter \
    --normals -q || fail "bake"
  local r
  for r in nearest interpolated; do
    convert "$WORK/fib.vff" --to vff "$WORK/fib-$r.vff" --positions octa-hemi2 --count 4 --resample "$r"
    expect_rc 0
    run "$CHECK" texels "$WORK/n4.vff" "$WORK/fib-$r.vff" --min-agreement 96 --max-mean-error 0.07
    [[ $RC -eq 0 ]] || { show; fail "fibonacci -> octa-hemi2 ($r) is beyond its bounds"; }
  done
  # A bit1 source can be resampled by nearest only.
  convert "$WORK/n8.vff" --to vff "$WORK/b.vff" --encoding bit1
  expect_rc 0
  convert "$WORK/b.vff" --to vff "$WORK/b4.vff" --count 4 --resample interpolated
  expect_rc 5
  expect_err "a bit1 source has none"
  convert "$WORK/b.vff" --to vff "$WORK/b4.vff" --count 4
  expect_rc 0
}

test_lod_provenance_and_metadata() {
  field "$WORK/a.vff" unorm16-diameter --n 2 --m 16
  convert "$WORK/a.vff" --to vff "$WORK/b.vff" --encoding unorm8-diameter
  expect_rc 0
  local ha hb
  ha=$("$CHECK" xxh3 "$WORK/a.vff")
  hb=$("$CHECK" xxh3 "$WORK/b.vff")
  run "$CHECK" meta "$WORK/b.vff"
  # The source's keys stay; one entry is appended (canonical JSON: sorted keys, no spaces).
  expect_out '"n":2,"name":"convert fixture",'
  local entry1='{"operations":["encoding"],"options":{"encoding":"unorm8-diameter"},"source":{"distanceEncoding":"unorm16-diameter","mapCount":26,"mapResolution":16,"name":"a.vff","positionParam":2,"positionScheme":"octa-hemi2","xxh3":"'$ha'"},"tool":"vff-convert","version":"'
  expect_out "\"vff.provenance\":[$entry1"
  # A second conversion appends a second entry, naming its own source.
  convert "$WORK/b.vff" --to vff "$WORK/c.vff" --map-size 8 --count 1 --resample interpolated
  expect_rc 0
  run "$CHECK" meta "$WORK/c.vff"
  expect_out "\"vff.provenance\":[$entry1"
  expect_out '{"operations":["positions","map-size"],"options":{"count":1,"downsample":"tent","mapSize":8,"positions":"octa-hemi2","resample":"interpolated"},"source":{"distanceEncoding":"unorm8-diameter","mapCount":26,"mapResolution":16,"name":"b.vff","positionParam":2,"positionScheme":"octa-hemi2","xxh3":"'$hb'"},"tool":"vff-convert","version":"'
  [[ $(grep -o '"tool":"vff-convert"' "$WORK/out" | wc -l) -eq 2 ]] || { show; fail "expected two entries"; }
  # Options that change nothing, and a plain repack, keep META byte for byte.
  "$CHECK" meta "$WORK/c.vff" >"$WORK/c.meta"
  convert "$WORK/c.vff" --to vff "$WORK/d.vff" --encoding unorm8-diameter --codec zstd
  expect_rc 0
  expect_out "nothing to resample"
  "$CHECK" meta "$WORK/d.vff" | cmp - "$WORK/c.meta" || fail "META changed without a change of the maps"
  # A source whose vff.provenance is not a list is refused, naming the key.
  field "$WORK/bad.vff" unorm8-diameter --meta '{"vff.provenance":"by hand"}'
  convert "$WORK/bad.vff" --to vff "$WORK/x.vff" --encoding bit1
  expect_rc 3
  expect_err "bad.vff"
  expect_err '"vff.provenance" is not an array'
  [[ ! -e $WORK/x.vff ]] || fail "an output was written"
}

test_lod_same_bytes_any_thread_count() {
  field "$WORK/a.vff" unorm16-diameter --n 4 --m 16 --normals
  local t
  for t in 1 2 4; do
    convert "$WORK/a.vff" --to vff "$WORK/a$t.vff" --count 2 --resample interpolated --map-size 8 \
      --downsample tent --encoding unorm8-chord -j "$t"
    expect_rc 0
    cp "$WORK/out" "$WORK/out$t"
  done
  cmp "$WORK/a1.vff" "$WORK/a2.vff" || fail "1 vs 2 threads differ"
  cmp "$WORK/a1.vff" "$WORK/a4.vff" || fail "1 vs 4 threads differ"
  sed -i 's/a[0-9]\.vff:/aN.vff:/' "$WORK/out1" "$WORK/out4"
  cmp "$WORK/out1" "$WORK/out4" || fail "the printed summary depends on the thread count"
}

# vff-experiments ao --field evaluates a file like the same configuration baked in memory, and
# refuses a file of another mesh.
test_lod_ao_field_option() {
  needs_bake || return 0
  if [[ ! -x ${EXPERIMENTS:-/nonexistent} ]]; then
    echo "SKIP: vff-experiments is not built"
    return 0
  fi
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/f.vff" -n 8 -m 16 -q || fail "bake"
  convert "$WORK/f.vff" --to vff "$WORK/g.vff" --map-size 8
  expect_rc 0
  run "$EXPERIMENTS" ao --mesh "$WORK/knot.obj" --size 32 --rays 16 -o "$WORK/ao" --config 290x16x16 \
    --field "$WORK/f.vff" --field "$WORK/g.vff"
  expect_rc 0
  local r baked file
  for r in nearest interpolated; do
    baked=$(grep "^| 290x16x16 | $r |" "$WORK/out" | cut -d'|' -f4-6)
    file=$(grep "^| f.vff (290x16x16 unorm8-diameter) | $r |" "$WORK/out" | cut -d'|' -f4-6)
    [[ -n $baked && $baked == "$file" ]] || { show; fail "$r: the file's row ($file) is not the bake's ($baked)"; }
  done
  expect_out "| g.vff (290x8x8 unorm8-diameter) | nearest |"
  # Another mesh: its sphere differs.
  "$MESHGEN" bowl "$WORK/bowl.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/bowl.obj" -o "$WORK/bowl.vff" -n 2 -m 8 -q || fail "bake"
  run "$EXPERIMENTS" ao --mesh "$WORK/knot.obj" --size 32 --rays 4 -o "$WORK/ao" --field "$WORK/bowl.vff"
  expect_rc 3
  expect_err "bowl.vff"
  expect_err "is not the mesh's minimal enclosing sphere"
  # Another mesh baked in the knot's sphere: the source mesh's XXH3 differs.
  local sphere
  sphere=$(sed -n 's/.*is not the mesh.s minimal enclosing sphere (centre \([^,]*\), radius \([^)]*\)).*/\1 \2/p' "$WORK/err")
  read -r cx cy cz rr <<<"$sphere"
  "$VFF_BAKE" "$WORK/bowl.obj" -o "$WORK/bowl2.vff" -n 2 -m 8 --center "$cx" "$cy" "$cz" --radius "$rr" -q ||
    fail "bake with the knot's sphere"
  run "$EXPERIMENTS" ao --mesh "$WORK/knot.obj" --size 32 --rays 4 -o "$WORK/ao" --field "$WORK/bowl2.vff"
  expect_rc 3
  expect_err "bowl2.vff"
  expect_err "META vff.source.geometryHash is"
}

# The same triangles read from another file format (vertex order and sharing changed) are the same
# object: --field matches them on META vff.source.geometryHash, not on the file.
test_lod_field_of_same_geometry_in_another_format() {
  if [[ ! -x ${EXPERIMENTS:-/nonexistent} ]]; then
    echo "SKIP: vff-experiments is not built"
    return 0
  fi
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  # An ASCII PLY of the OBJ's triangles: every triangle gets its own three vertices, in reverse order.
  python3 - "$WORK/knot.obj" "$WORK/knot.ply" <<'PY' || fail "OBJ to PLY"
import sys
v, f = [], []
for line in open(sys.argv[1]):
    p = line.split()
    if p and p[0] == "v": v.append(p[1:4])
    if p and p[0] == "f": f.append([int(x.split("/")[0]) - 1 for x in p[1:]])
tris = [t[i] for t in f for i in (0, 1, 2)] if all(len(t) == 3 for t in f) else sys.exit("not triangles")
tris = [tris[i:i + 3] for i in range(0, len(tris), 3)][::-1]
with open(sys.argv[2], "w") as o:
    o.write("ply\nformat ascii 1.0\nelement vertex %d\nproperty float x\nproperty float y\nproperty float z\n" % (3 * len(tris)))
    o.write("element face %d\nproperty list uchar int vertex_indices\nend_header\n" % len(tris))
    for t in tris:
        for i in t: o.write(" ".join(v[i]) + "\n")
    for k in range(len(tris)): o.write("3 %d %d %d\n" % (3 * k, 3 * k + 1, 3 * k + 2))
PY
  "$VFF_BAKE" "$WORK/knot.ply" -o "$WORK/ply.vff" -n 2 -m 8 -q || fail "bake the PLY"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/obj.vff" -n 2 -m 8 -q || fail "bake the OBJ"
  local hp ho
  hp=$("$VFF_INSPECT" "$WORK/ply.vff" --format json | grep -o '"geometryHash": *"[0-9a-f]*"')
  ho=$("$VFF_INSPECT" "$WORK/obj.vff" --format json | grep -o '"geometryHash": *"[0-9a-f]*"')
  [[ -n $hp && $hp == "$ho" ]] || fail "geometry hashes differ: PLY '$hp', OBJ '$ho'"
  run "$EXPERIMENTS" ao --mesh "$WORK/knot.obj" --size 16 --rays 4 -o "$WORK/ao" --field "$WORK/ply.vff"
  expect_rc 0
  expect_out "| ply.vff (26x8x8 unorm8-diameter) | nearest |"
}

# A refined field's refinement (REFN) follows its maps: kept by a repack, marked again on new maps
# from its own triangles (for bc4, exactly as a refined bc4 bake marks them; for smaller maps, the
# same bytes on any thread count), left out with a warning where the output cannot hold it.
refn() {  # the refinement's unsure texels and the REFN section's checksum (stored blocks)
  "$VFF_INSPECT" "$1" --format json | python3 -c "import json,sys; d=json.load(sys.stdin); r=d['refinement']; print(r and r['unsureTexels'], [s['checksum'] for s in d['sections'] if s['tag']=='REFN'])"
}
test_refinement_follows_the_maps() {
  needs_bake || return 0
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/r.vff" -n 3 -m 16 --refine -q || fail "bake"
  convert "$WORK/r.vff" "$WORK/g.vff" --gutter 2
  expect_rc 0
  expect_out_re "refinement: [0-9]+ unsure texels, 8192 triangles"
  [[ $(refn "$WORK/g.vff") == "$(refn "$WORK/r.vff")" ]] || fail "a repack changed the refinement"
  convert "$WORK/r.vff" "$WORK/c.vff" --encoding bc4-diameter -q
  expect_rc 0
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/b.vff" -n 3 -m 16 --refine --encoding bc4-diameter -q || fail "bake"
  [[ $(refn "$WORK/c.vff") == "$(refn "$WORK/b.vff")" ]] || fail "bc4: other unsure texels than a refined bc4 bake"
  convert "$WORK/r.vff" "$WORK/l1.vff" --map-size 8 -j 1
  expect_rc 0
  expect_out_re "refinement remade for the new maps from its own triangles: [0-9]+ unsure texels \(were [0-9]+\)"
  valid "$WORK/l1.vff"
  convert "$WORK/r.vff" "$WORK/l2.vff" --map-size 8 -j 2 -q
  cmp "$WORK/l1.vff" "$WORK/l2.vff" || fail "the remade refinement depends on the thread count"
  [[ $(refn "$WORK/l1.vff") != "None []" ]] || fail "the smaller maps lost the refinement"
  convert "$WORK/r.vff" "$WORK/bit.vff" --encoding bit1 -q
  expect_rc 0
  expect_err "the refinement (REFN) is left out: a bit1 field holds no distances to refine"
  [[ $(refn "$WORK/bit.vff") == "None []" ]] || fail "a bit1 field kept a refinement"
  convert "$WORK/r.vff" "$WORK/r.exr" -q
  expect_rc 0
  expect_err "the refinement (REFN) is not exported: EXR holds the maps only"
}

# ---- Runner --------------------------------------------------------------------------------------------
[[ $# -eq 1 && $1 == test_* ]] || { echo "usage: $0 test_NAME" >&2; exit 2; }
run_test "$1"
