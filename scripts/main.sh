#!/usr/bin/env bash
# Command 1: set up, build, bake the Stanford bunny (Debian's glmark2-data copy) with the paper's
# configuration (4226 maps of 64x64, 8 bits per ray, normalised by 2R), inspect the field, write a
# contact sheet of its maps, then render the paper's Fig. 3 comparison (ambient occlusion on the
# ground: exact Embree vs three fields, nearest and interpolated) and print its table. Output goes
# to out/ and out/experiments/; last, the three.js example's asset (web/examples/contact-shadows/assets).
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
cd "$root"
bash scripts/setup.sh
cmake --preset release >/dev/null
# Only what the demo runs (scripts/test.sh builds everything).
cmake --build --preset release -j "$(nproc)" --target vff-bake vff-inspect vff-experiments vff-procedural-mesh

bin="$root/build/tools"
mesh="${1:-/usr/share/glmark2/models/bunny.obj}"
mkdir -p out
echo "== vff-bake $mesh"
"$bin/vff-bake/vff-bake" "$mesh" -o out/bunny.vff
echo "== vff-inspect out/bunny.vff"
"$bin/vff-inspect/vff-inspect" out/bunny.vff --preview out/bunny-maps.png
"$bin/vff-inspect/vff-inspect" out/bunny.vff --validate
echo "== vff-experiments ao (the paper's Fig. 3: exact vs visibility fields)"
"$root/build/samples/experiments/vff-experiments" ao --mesh "$mesh" -o out/experiments
# The three.js example's asset (web/examples/contact-shadows): a floor and four objects with fields.
echo "== the three.js example's asset (node web/tools/make-example.mjs)"
node web/tools/make-example.mjs --bake "$bin/vff-bake/vff-bake" --procedural "$root/build/samples/vff-procedural-mesh"
echo "wrote out/bunny.vff, out/bunny-maps.png and out/experiments/ (images, error heat maps, ao-table.md)"
echo "web: python3 -m http.server -d web 8000, then http://localhost:8000/ (viewer) and /examples/contact-shadows/"
