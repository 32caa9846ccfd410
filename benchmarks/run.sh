#!/usr/bin/env bash
# benchmarks/run.sh - runs every benchmark of vff and writes one results file.
#
#   bash benchmarks/run.sh [--build DIR] [--mesh FILE] [--out FILE] [--quick] [--only STEP[,STEP...]]
#                          [--sdf-memory "MiB ..."] [--sdf-rays N]
#
# Without --build it sets up and builds as scripts/main.sh does (Release preset, into build/).
# With the bunny of Debian's glmark2-data (or --mesh) it runs:
#   bake         vff-bake --benchmark: the whole bake against Embree alone on the bake's rays
#   query        vff-experiments bench: field queries against Embree and against the memory floor
#   accuracy     vff-experiments ao (at AO ranges 0.25, 0.5, 1 and 2 R), intra-ao, shadows, reflections:
#                fields against exact casts
#   scene        vff-experiments scene-bench: 1 to 10000 moving instances, Embree instancing vs vff::Scene
#   triangles    vff-experiments triangle-bench: time per ray from about 10k to 1M triangles
#   compression  vff-compress --benchmark: the hits-med codec against zstd, xz and OpenEXR's
#   gpu          vff-gpu-bench, where a headless OpenGL 4.3 context opens (it names the renderer),
#                with --sdf: the ground AO by the field's GLSL and by a distance field's GLSL at
#                equal memory, against the exact image; with --api vulkan where a Vulkan device answers:
#                the same queries through the Vulkan pipeline (gpu/vulkan), and with vulkan-hlsl its
#                kernel from the generated HLSL where spirv-cross is installed
#   python       benchmarks/python_query.py, where the Python module is built: a million rays through
#                vff-query (.npy in and out, end to end) and through the Python batch, each against
#                the C++ batch on the same rays and field in the same run
#   sdf          vff-experiments sdf-bench: the field against a signed distance field at equal
#                memory (--sdf-memory, default 1 4 16 64 MiB per object) and Embree, on three meshes:
#                the bunny (or --mesh), a box (sharp edges, flat faces: the CAD-like case) and a
#                bowl (a thin shell), both from vff-procedural-mesh; --sdf-rays rays per set
#   library      benchmarks/library.sh: vff-library's pool (and Slurm, where SLURM_CONF is set)
#                against the same bakes one after another, and the up-to-date re-run
#   webgpu       web/tools/bench-webgpu.mjs, where node, web/node_modules and chromium are there and
#                chromium offers a WebGPU adapter: the field's queries/s through the WGSL kernel
#                generated from the GLSL (the adapter named: SwiftShader is the CPU)
#   three        web/tools/bench-three.mjs, where node, web/node_modules and chromium are there: the
#                three.js example scene (web/tools/make-example.mjs), one frame drawn by the field
#                effect of @vff/three and by three-mesh-bvh's exact GPU ray casting at the same rays per
#                pixel, ms per frame and their ratio, in headless chromium (the renderer named:
#                SwiftShader is software rendering on the CPU)
# and writes benchmarks/results/<cpu>-<date>.md (or --out): the machine, the commit, a summary in
# rounded tables (README.md and benchmarks/README.md copy it: python3 benchmarks/report.py readme) and the full output of
# every command. --quick runs each at a tiny size: a check that the whole chain works, whose
# figures mean nothing. --only STEP[,STEP...] runs those steps (bake, query, accuracy, scene, triangles,
# compression, gpu, webgpu, sdf, python, library, three): a reduced run, and its results file says so. Run it on
# a quiet machine: the query figures move with the memory's load.
# Exit codes: 0 written, 1 usage, 2 a file cannot be read or written, 4 a benchmark failed.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
prog="benchmarks/run.sh"
build="" mesh="/usr/share/glmark2/models/bunny.obj" out="" quick=0 only="" sdfmemory="1 4 16 64" sdfrays=""
usage() { echo "usage: $prog [--build DIR] [--mesh FILE] [--out FILE] [--quick] [--only STEP[,STEP...]] [--sdf-memory \"MiB ...\"] [--sdf-rays N]" >&2; exit 1; }
while [[ $# -gt 0 ]]; do
  case "$1" in
    --build) [[ $# -ge 2 ]] || usage; build="$2"; shift 2 ;;
    --mesh) [[ $# -ge 2 ]] || usage; mesh="$2"; shift 2 ;;
    --out) [[ $# -ge 2 ]] || usage; out="$2"; shift 2 ;;
    --quick) quick=1; shift ;;
    --only) [[ $# -ge 2 ]] || usage; only="$2"; shift 2
      [[ $only =~ ^((bake|query|accuracy|scene|triangles|compression|gpu|webgpu|sdf|python|library|three)(,|$))+$ ]] || usage ;;
    --sdf-memory) [[ $# -ge 2 ]] || usage; sdfmemory="$2"; shift 2 ;;
    --sdf-rays) [[ $# -ge 2 ]] || usage; sdfrays="$2"; shift 2 ;;
    -h|--help) echo "usage: $prog [--build DIR] [--mesh FILE] [--out FILE] [--quick] [--only STEP[,STEP...]] [--sdf-memory \"MiB ...\"] [--sdf-rays N]"; exit 0 ;;
    *) usage ;;
  esac
done

if [[ -z $build ]]; then
  cd "$root"
  bash scripts/setup.sh
  cmake --preset release >/dev/null
  cmake --build --preset release -j "$(nproc)"
  build="$root/build"
fi
build="$(cd "$build" && pwd)"
[[ -r $mesh ]] || { echo "$prog: error: $mesh: cannot read the mesh (Debian package glmark2-data, or --mesh)" >&2; exit 2; }
mesh="$(cd "$(dirname "$mesh")" && pwd)/$(basename "$mesh")"
bake="$build/tools/vff-bake/vff-bake"
compress="$build/tools/vff-compress/vff-compress"
experiments="$build/samples/experiments/vff-experiments"
meshgen="$build/samples/vff-procedural-mesh"
gpubench="$build/samples/gpu-bench/vff-gpu-bench"
for t in "$bake" "$compress" "$experiments" "$meshgen"; do
  [[ -x $t ]] || { echo "$prog: error: $t: not built" >&2; exit 2; }
done

raw="$(mktemp -d)"
trap 'rm -rf "$raw"' EXIT

if ((quick)); then
  config=(-n 8 -m 16) field=290x16x16 expargs=(--size 48 --rays 8 --config 290x16x16)
  benchargs=(--config 290x16x16 --bench-rays 20000 --repeat 1) bakerepeat=1 compressrepeat=1
  sceneargs=(--config 290x16x16 --instances 1 10 --scene-rays 4096 --frames 1)
  triangleargs=(--config 290x16x16 --bench-rays 4096 --min-triangles 500 --max-triangles 8000 --repeat 1)
  gpuargs=(--size 64 --spp 4) gpusdfargs=() pyargs=(--quick) threeargs=(--size 48x32 --rays 1 --frames 1)
  webgpuargs=(--log2 12 --repeat 1)
  sdfargs=(--config 290x16x16 --bench-rays 20000 --repeat 1)
else
  # The paper's configuration: octa-hemi2 n = 32 (4226 maps) of 64 x 64, unorm8-diameter.
  config=(-n 32 -m 64) field=4226x64x64 expargs=()
  benchargs=(--repeat 5) bakerepeat=3 compressrepeat=3
  sceneargs=(--frames 5) triangleargs=(--repeat 5)
  # The distance field's GLSL at a quarter of the pixels and rays (sphere tracing on llvmpipe).
  gpuargs=() gpusdfargs=(--sdf-size 256 --sdf-spp 64) pyargs=()
  # Software rendering takes seconds a frame for either effect: a small frame.
  threeargs=(--size 160x120 --rays 4 --frames 3)
  webgpuargs=(--log2 20,21 --repeat 2)
  # shellcheck disable=SC2206  # the memory list is words
  sdfargs=(--repeat 3 --sdf-memory $sdfmemory)
fi
[[ -z $sdfrays ]] || sdfargs+=(--bench-rays "$sdfrays")
# want STEP: true when the run includes it (all of them without --only).
want() { [[ -z $only || ,$only, == *",$1,"* ]]; }

# step NAME COMMAND...: runs COMMAND with its output in $raw/NAME.txt and its command line in
# $raw/NAME.cmd (paths relative to the build folder, so that results files name no machine path).
# A command that fails ends the run with exit 4, unless its stderr matches $skip_if: then
# $raw/NAME.skip says why it did not run.
skip_if=""
step() {
  local name="$1"; shift
  local shown="${*//$build\//}"
  shown="${shown//$raw\//}"
  shown="${shown//$root\//}"
  shown="${shown//$raw/.}"
  shown="${shown//$(dirname "$mesh")\//}"
  echo "== $name: $shown" >&2
  local t0=$SECONDS
  if ! "$@" >"$raw/$name.txt" 2>"$raw/$name.err"; then
    rm -f "$raw/$name.txt"
    if [[ -n $skip_if ]] && grep -q "$skip_if" "$raw/$name.err"; then
      grep -m1 "$skip_if" "$raw/$name.err" | sed 's/^[^:]*: //' >"$raw/$name.skip"
      echo "   skipped: $(cat "$raw/$name.skip")" >&2
      return 0
    fi
    cat "$raw/$name.err" >&2
    echo "$prog: error: $name failed: $shown" >&2
    exit 4
  fi
  sed -i -e "s|$build/||g" -e "s|$raw/||g" -e "s|$(dirname "$mesh")/||g" "$raw/$name.txt"
  printf '%s\n' "$shown" >"$raw/$name.cmd"
  echo "   $((SECONDS - t0)) s" >&2
}

want bake && step bake "$bake" "$mesh" --benchmark "${config[@]}" --repeat "$bakerepeat"
want query && step query "$experiments" bench --mesh "$mesh" "${benchargs[@]}"
if want accuracy; then
  for e in ao intra-ao shadows reflections; do
    # ao renders each AO range against its own exact image (the contact shadow at short ranges).
    ranges=(); [[ $e != ao ]] || ranges=(--ao-ranges 0.25 0.5 1 2)
    step "accuracy-$e" "$experiments" "$e" --mesh "$mesh" "${expargs[@]}" "${ranges[@]}" -o "$raw/experiments"
  done
fi
want scene && step scene "$experiments" scene-bench --mesh "$mesh" "${sceneargs[@]}"
want triangles && step triangles "$experiments" triangle-bench --mesh "$mesh" "${triangleargs[@]}"
if want compression || want gpu || want webgpu || want python; then "$bake" "$mesh" -o "$raw/field.vff" "${config[@]}" -q; fi
want compression && step compression "$compress" --benchmark "$raw/field.vff" --repeat "$compressrepeat" --tmp "$raw"
# The GPU bench where it is built and a headless OpenGL 4.3 context opens; otherwise the results
# file says why it did not run.
if ! want gpu; then
  :
elif [[ -x $gpubench ]]; then
  # --sdf where the bench was built with the distance-field peer (its usage names the option).
  gpusdf=()
  if [[ $("$gpubench" --help 2>&1) == *--sdf* ]]; then gpusdf=(--mesh "$mesh" --sdf "${gpusdfargs[@]}"); fi
  # --api vulkan where the bench was built with the Vulkan path and a Vulkan device answers, and
  # vulkan-hlsl beside it where the bench takes a list and spirv-cross (the HLSL's maker) is here.
  if [[ $("$gpubench" --help 2>&1) == *"--api gl|vulkan"* ]] && command -v vulkaninfo >/dev/null &&
    vulkaninfo --summary >/dev/null 2>&1; then
    if [[ $("$gpubench" --help 2>&1) == *"vulkan-hlsl[,...]"* ]] && command -v spirv-cross >/dev/null; then
      gpusdf+=(--api vulkan,vulkan-hlsl)
    else
      gpusdf+=(--api vulkan)
    fi
  fi
  skip_if="no headless OpenGL" step gpu "$gpubench" --field "$raw/field.vff" "${gpusdf[@]}" "${gpuargs[@]}"
else
  echo "vff-gpu-bench is not built (no OpenGL or EGL development files)" >"$raw/gpu.skip"
fi
if want sdf; then
  "$meshgen" box "$raw/box.obj" >/dev/null
  "$meshgen" bowl "$raw/bowl.obj" >/dev/null
  step sdf "$experiments" sdf-bench --mesh "$mesh" --object "$raw/box.obj" --object "$raw/bowl.obj" "${sdfargs[@]}"
fi

# The Python batch and vff-query against the C++ batch, with the interpreter the module was built
# for, where it was built; otherwise the results file says why it did not run.
python="$(sed -n 's/^Python3_EXECUTABLE:[A-Z]*=//p' "$build/CMakeCache.txt" | head -1)"
if ! want python; then
  :
elif compgen -G "$build/python/vff/_vff*.so" >/dev/null && [[ -x $python && -x $build/tools/vff-query/vff-query ]]; then
  step python env PYTHONPATH="$build/python" "$python" "$root/benchmarks/python_query.py" --field "$raw/field.vff" \
    --query "$build/tools/vff-query/vff-query" "${pyargs[@]}"
else
  echo "the Python module is not built (VFF_PYTHON=OFF: pybind11-dev, python3-dev or python3-numpy missing)" >"$raw/python.skip"
fi
# The library bake: the pool and Slurm against the same bakes one after another (benchmarks/library.sh).
want library && step library bash "$root/benchmarks/library.sh" --build "$build" $( ((quick)) && echo --quick)
# The field's queries through WebGPU (the generated WGSL), where node, web/node_modules and chromium
# are there and chromium offers an adapter; otherwise the results file says why it did not run.
if ! want webgpu; then
  :
elif ! command -v node >/dev/null; then
  echo "node is not installed (scripts/setup.sh installs nodejs)" >"$raw/webgpu.skip"
elif [[ ! -d $root/web/node_modules/playwright-core ]]; then
  echo "web/node_modules lacks playwright-core (npm ci in web/)" >"$raw/webgpu.skip"
elif ! chromium="$(command -v "${VFF_CHROMIUM:-chromium}")"; then
  echo "no chromium (apt-get install chromium)" >"$raw/webgpu.skip"
else
  VFF_CHROMIUM_PATH="$chromium" skip_if="^SKIP: " step webgpu node "$root/web/tools/bench-webgpu.mjs" --field "$raw/field.vff" "${webgpuargs[@]}"
fi
# The three.js example's frame time, where node, web/node_modules (with three-mesh-bvh and
# playwright-core) and chromium are there; otherwise the results file says why it did not run.
if ! want three; then
  :
elif ! command -v node >/dev/null; then
  echo "node is not installed (scripts/setup.sh installs nodejs)" >"$raw/three.skip"
elif [[ ! -d $root/web/node_modules/three-mesh-bvh || ! -d $root/web/node_modules/playwright-core ]]; then
  echo "web/node_modules lacks three-mesh-bvh or playwright-core (npm ci in web/)" >"$raw/three.skip"
elif ! chromium="$(command -v "${VFF_CHROMIUM:-chromium}")"; then
  echo "no chromium (apt-get install chromium)" >"$raw/three.skip"
else
  node "$root/web/tools/make-example.mjs" --bake "$bake" --procedural "$meshgen" --out "$raw/three" >&2
  VFF_CHROMIUM_PATH="$chromium" step three node "$root/web/tools/bench-three.mjs" --asset "$raw/three/example.glb" "${threeargs[@]}"
fi

# The machine and the build.
cpu="$(python3 "$root/benchmarks/report.py" cpu)"
commit="$(git -C "$root" rev-parse --short=12 HEAD 2>/dev/null || echo unknown)"
[[ -z "$(git -C "$root" status --porcelain --untracked-files=no 2>/dev/null)" ]] || commit="$commit (with uncommitted changes)"
{
  echo "date=$(date -u +%Y-%m-%d)"
  echo "commit=$commit"
  echo "cpu=$cpu"
  echo "cores=$(nproc)"
  echo "kernel=$(uname -sr)"
  cxx="$(sed -n 's/^CMAKE_CXX_COMPILER:[A-Z]*=//p' "$build/CMakeCache.txt" | head -1)"
  echo "compiler=$("${cxx:-c++}" --version 2>/dev/null | head -1 || echo unknown)"
  echo "build_type=$(sed -n 's/^CMAKE_BUILD_TYPE:[A-Z]*=//p' "$build/CMakeCache.txt" | head -1)"
  echo "embree=$(dpkg-query -W -f='${Version}' libembree3-3 2>/dev/null || echo unknown)"
  echo "mesh=$(basename "$mesh")"
  echo "field=$field"
  echo "quick=$quick"
  [[ -z $only ]] || echo "only=$only"
} >"$raw/machine.txt"
if [[ -z $out ]]; then
  # A reduced run (--only) never replaces the day's full results file.
  out="$root/benchmarks/results/$(python3 "$root/benchmarks/report.py" slug "$raw/machine.txt")${only:+-${only//,/-}}.md"
fi
python3 "$root/benchmarks/report.py" compose "$raw" "$out.tmp"
mv "$out.tmp" "$out"
echo "wrote $out" >&2
