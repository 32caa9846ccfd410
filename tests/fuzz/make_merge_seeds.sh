#!/usr/bin/env bash
# Writes the seeds of the `merge` fuzz target (tests/fuzz/seeds/merge/) from partial results of a
# tetrahedron that vff-bake --map-range bakes: 4 maps of 4 x 4 texels, so every part is small. The
# same vff-bake gives the same bytes (its output does not depend on the thread count or the time).
#   tests/fuzz/make_merge_seeds.sh VFF_BAKE [OUT_DIR]
# A seed is the fuzz target's input (fuzz_merge.cpp): a byte whose value mod 4 is the part count
# less one, the length of every part but the last as 4 bytes little-endian, then the parts.
set -euo pipefail
bake="$1"
out="${2:-$(cd "$(dirname "$0")" && pwd)/seeds/merge}"
mkdir -p "$out"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cat >"$work/tetra.obj" <<'OBJ'
v 0 0 0
v 1 0 0
v 0 1 0
v 0 0 1
f 1 3 2
f 1 2 4
f 1 4 3
f 2 3 4
OBJ
part() {  # NAME RANGE MAP_SIZE [OPTIONS...]
  local name="$1" range="$2" m="$3"
  shift 3
  (cd "$work" && "$bake" tetra.obj -o "$name.vff" --positions ea-octa-grid -n 2 -m "$m" --map-range "$range" -q -j 1 "$@")
}
part a 0:2 4
part b 2:4 4
part c 0:1 4
part d 1:4 4
part n0 0:3 4 --normals --codec zstd
part n1 3:4 4 --normals --codec zstd
part e 0:2 4 --encoding bc4-diameter
part f 2:4 4 --encoding bc4-diameter
part g 2:4 8
pack() {  # SEED PART...
  local seed="$1"
  shift
  /usr/bin/env python3 - "$out/$seed" "$@" <<'PY'
import struct, sys
parts = [open(p, 'rb').read() for p in sys.argv[2:]]
data = bytes([len(parts) - 1]) + b''.join(struct.pack('<I', len(p)) for p in parts[:-1]) + b''.join(parts)
open(sys.argv[1], 'wb').write(data)
PY
}
pack two-halves.seed "$work/a.vff" "$work/b.vff"
pack reversed.seed "$work/b.vff" "$work/a.vff"
pack three.seed "$work/c.vff" "$work/d.vff" "$work/b.vff"
pack normals-zstd.seed "$work/n0.vff" "$work/n1.vff"
pack bc4.seed "$work/e.vff" "$work/f.vff"
pack gap.seed "$work/a.vff"
pack other-size.seed "$work/a.vff" "$work/g.vff"
pack four-overlap.seed "$work/c.vff" "$work/a.vff" "$work/d.vff" "$work/b.vff"
ls "$out"
