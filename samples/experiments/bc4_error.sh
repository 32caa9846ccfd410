#!/usr/bin/env bash
# bc4_error.sh - the error the lossy bc4-diameter encoding (BC4 blocks a GPU texture unit decodes, half
# the memory of unorm8-diameter) adds to the ground ambient-occlusion experiment: bc4 and unorm8 bakes
# of the same fields side by side, in one run of `vff-experiments ao` (same exact reference, same rays).
#
#   bash samples/experiments/bc4_error.sh [BUILD_DIR] [OUT_DIR] [SIZE]
#
# BUILD_DIR (default build) holds the built tools, OUT_DIR (default out/bc4-error) receives the fields,
# the images and ao-table.md; SIZE is the image size (default 512). Uses the bunny of Debian's
# glmark2-data, or the mesh in $MESH.
set -euo pipefail
build=${1:-build}
out=${2:-out/bc4-error}
size=${3:-512}
mesh=${MESH:-/usr/share/glmark2/models/bunny.obj}
bake="$build/tools/vff-bake/vff-bake"
experiments="$build/samples/experiments/vff-experiments"
for t in "$bake" "$experiments"; do
  [[ -x $t ]] || { echo "bc4_error.sh: $t is not built" >&2; exit 1; }
done
[[ -r $mesh ]] || { echo "bc4_error.sh: $mesh is not readable (Debian package glmark2-data)" >&2; exit 2; }
mkdir -p "$out"
set -x
# octa-hemi2: n 32 = 4226 maps, n 64 = 16642 maps.
"$bake" "$mesh" -o "$out/bake-4226x64.vff" -n 32 -m 64 -q
"$bake" "$mesh" -o "$out/bake-4226x64-bc4.vff" -n 32 -m 64 --encoding bc4-diameter -q
"$bake" "$mesh" -o "$out/bake-4226x32.vff" -n 32 -m 32 -q
"$bake" "$mesh" -o "$out/bake-4226x32-bc4.vff" -n 32 -m 32 --encoding bc4-diameter -q
"$bake" "$mesh" -o "$out/bake-16642x32.vff" -n 64 -m 32 -q
"$bake" "$mesh" -o "$out/bake-16642x64-bc4.vff" -n 64 -m 64 --encoding bc4-diameter -q
fields=()
for f in bake-4226x64 bake-4226x64-bc4 bake-4226x32 bake-4226x32-bc4 bake-16642x32 bake-16642x64-bc4; do
  fields+=(--field "$out/$f.vff")
done
"$experiments" ao --mesh "$mesh" --size "$size" -o "$out" "${fields[@]}"
