#!/usr/bin/env bash
# lod_error.sh - how much error vff-convert's re-encoding and level of detail add, measured with the
# ground ambient-occlusion experiment (vff-experiments ao --field): every derived field against the
# field baked directly at the same size, in the same run (same exact reference, same rays).
#
#   bash samples/experiments/lod_error.sh [BUILD_DIR] [OUT_DIR] [SIZE]
#
# BUILD_DIR (default build) holds the built tools, OUT_DIR (default out/lod-error) receives the
# fields, the images and ao-table.md; SIZE is the image size (default 512). Uses the bunny of
# Debian's glmark2-data, or the mesh in $MESH.
set -euo pipefail
build=${1:-build}
out=${2:-out/lod-error}
size=${3:-512}
mesh=${MESH:-/usr/share/glmark2/models/bunny.obj}
bake="$build/tools/vff-bake/vff-bake"
convert="$build/tools/vff-convert/vff-convert"
experiments="$build/samples/experiments/vff-experiments"
for t in "$bake" "$convert" "$experiments"; do
  [[ -x $t ]] || { echo "lod_error.sh: $t is not built" >&2; exit 1; }
done
[[ -r $mesh ]] || { echo "lod_error.sh: $mesh is not readable (Debian package glmark2-data)" >&2; exit 2; }
mkdir -p "$out"
set -x
# Direct bakes (octa-hemi2: n 64 = 16642 maps, n 32 = 4226 maps).
"$bake" "$mesh" -o "$out/bake-16642x64.vff" -n 64 -m 64 -q
"$bake" "$mesh" -o "$out/bake-4226x64.vff" -n 32 -m 64 -q
"$bake" "$mesh" -o "$out/bake-4226x64-u16.vff" -n 32 -m 64 --encoding unorm16-diameter -q
"$bake" "$mesh" -o "$out/bake-4226x64-bit1.vff" -n 32 -m 64 --encoding bit1 -q
"$bake" "$mesh" -o "$out/bake-4226x32.vff" -n 32 -m 32 -q
"$bake" "$mesh" -o "$out/bake-4226x16.vff" -n 32 -m 16 -q
# Derived: fewer positional samples, smaller maps (every rule), fewer bits.
"$convert" "$out/bake-16642x64.vff" "$out/lod-4226x64-nearest.vff" --count 32 --resample nearest
"$convert" "$out/bake-16642x64.vff" "$out/lod-4226x64-interpolated.vff" --count 32 --resample interpolated
for rule in tent majority centre min; do
  "$convert" "$out/bake-4226x64.vff" "$out/lod-4226x32-$rule.vff" --map-size 32 --downsample "$rule"
  "$convert" "$out/bake-4226x64.vff" "$out/lod-4226x16-$rule.vff" --map-size 16 --downsample "$rule"
done
"$convert" "$out/bake-4226x64-u16.vff" "$out/enc-4226x64-u16-to-u8.vff" --encoding unorm8-diameter
"$convert" "$out/bake-4226x64.vff" "$out/enc-4226x64-u8-to-bit1.vff" --encoding bit1
# One run: the exact reference, then every field with both reconstructions.
fields=()
for f in bake-16642x64 bake-4226x64 lod-4226x64-nearest lod-4226x64-interpolated \
  bake-4226x32 lod-4226x32-tent lod-4226x32-majority lod-4226x32-centre lod-4226x32-min \
  bake-4226x16 lod-4226x16-tent lod-4226x16-majority lod-4226x16-centre lod-4226x16-min \
  bake-4226x64-u16 enc-4226x64-u16-to-u8 bake-4226x64-bit1 enc-4226x64-u8-to-bit1; do
  fields+=(--field "$out/$f.vff")
done
"$experiments" ao --mesh "$mesh" --size "$size" -o "$out" "${fields[@]}"
