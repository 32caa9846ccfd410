#!/usr/bin/env bash
# library.sh - vff-library's overhead: a library of at least 50 meshes (the shared meshes when
# present, the procedural ones, subdivided and rotated variants of each) baked
#   1. one after another with plain `vff-bake -j 0` (all cores): the baseline;
#   2. by `vff-library bake` with the local pool;
#   3. by `vff-library bake --slurm` on a Slurm cluster (SLURM_CONF, or a one-node cluster this script
#      starts with scripts/slurm-cluster.sh when none is set), skipped with the reason otherwise;
# then the local bake again with nothing changed (the up-to-date re-run). Prints each one's rays per
# second over the whole library, the ratios to the baseline (target >= 0.9) and the re-run's time
# (target < 2 s), and checks every output against the baseline's bytes.
#
#   bash benchmarks/library.sh [--build DIR] [--quick] [--meshes DIR]   (--quick: 20 procedural meshes, tiny fields)
set -euo pipefail
prog=library.sh
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$root/build" quick=0 meshes="$root/../shared/meshes"
while [[ $# -gt 0 ]]; do
  case $1 in
    --build) build=$2; shift 2 ;;
    --quick) quick=1; shift ;;
    --meshes) meshes=$2; shift 2 ;;
    *) echo "usage: $prog [--build DIR] [--quick] [--meshes DIR]" >&2; exit 1 ;;
  esac
done
bake="$build/tools/vff-bake/vff-bake"
library="$build/tools/vff-library/vff-library"
meshgen="$build/samples/vff-procedural-mesh"
for t in "$bake" "$library" "$meshgen"; do
  [[ -x $t ]] || { echo "$prog: error: $t: not built" >&2; exit 2; }
done
if ((quick)); then
  opts=(-n 4 -m 8) copies=1
else
  opts=(-n 16 -m 32) copies=2  # 1090 maps of 32 x 32 per entry; 5 entries per base mesh
fi

tmp="$(mktemp -d)"
slurm_started=""
cleanup() {
  [[ -z $slurm_started ]] || bash "$root/scripts/slurm-cluster.sh" stop "$tmp/slurm" >/dev/null 2>&1 || true
  rm -rf "$tmp"
}
trap cleanup EXIT

# The library: each base mesh, its 1-to-4 midpoint subdivision, and rotated copies of both.
mkdir -p "$tmp/base" "$tmp/lib"
"$meshgen" --all "$tmp/base" >/dev/null
if ((quick)); then
  :  # the procedural meshes only: a check that the chain works
elif [[ -d $meshes ]]; then
  cp "$meshes"/*.obj "$tmp/base/"
else
  echo "note: no shared meshes at $meshes: procedural ones only"
fi
python3 - "$tmp/base" "$tmp/lib" "$copies" <<'EOF'
import math, os, sys
base, lib, copies = sys.argv[1], sys.argv[2], int(sys.argv[3])
def read(p):
    v, f = [], []
    for line in open(p):
        t = line.split()
        if not t: continue
        if t[0] == "v": v.append(tuple(map(float, t[1:4])))
        elif t[0] == "f":
            idx = [int(x.split("/")[0]) for x in t[1:]]
            idx = [i - 1 if i > 0 else len(v) + i for i in idx]
            for k in range(1, len(idx) - 1): f.append((idx[0], idx[k], idx[k + 1]))
    return v, f
def subdivide(v, f):
    v, mid, out = list(v), {}, []
    def m(a, b):
        k = (min(a, b), max(a, b))
        if k not in mid:
            mid[k] = len(v)
            v.append(tuple((x + y) / 2 for x, y in zip(v[a], v[b])))
        return mid[k]
    for a, b, c in f:
        ab, bc, ca = m(a, b), m(b, c), m(c, a)
        out += [(a, ab, ca), (ab, b, bc), (ca, bc, c), (ab, bc, ca)]
    return v, out
def rotate(v, k):
    a = 0.7 * (k + 1)
    c, s = math.cos(a), math.sin(a)
    return [(c * x + s * z, y, -s * x + c * z) for x, y, z in v]
def write(p, v, f):
    with open(p, "w") as o:
        o.writelines(f"v {x:.6g} {y:.6g} {z:.6g}\n" for x, y, z in v)
        o.writelines(f"f {a+1} {b+1} {c+1}\n" for a, b, c in f)
n = 0
for name in sorted(os.listdir(base)):
    stem = name[:-4]
    v, f = read(os.path.join(base, name))
    sv, sf = subdivide(v, f)
    os.link(os.path.join(base, name), os.path.join(lib, name)); n += 1
    write(os.path.join(lib, stem + "-sub.obj"), sv, sf); n += 1
    for k in range(copies):
        write(os.path.join(lib, f"{stem}-rot{k}.obj"), rotate(v, k), f); n += 1
        if k < copies - 1 or copies == 1:
            write(os.path.join(lib, f"{stem}-sub-rot{k}.obj"), rotate(sv, k), sf); n += 1
print(f"library: {n} meshes", file=sys.stderr)
EOF
mapfile -t files < <(cd "$tmp/lib" && ls *.obj)
count=${#files[@]}

now() { date +%s.%N; }
# Each bake's rays, from vff-bake's summary, summed.
t0=$(now)
rays=0
mkdir -p "$tmp/plain"
for f in "${files[@]}"; do
  r=$("$bake" "$tmp/lib/$f" -o "$tmp/plain/${f%.obj}.vff" -j 0 --json "${opts[@]}" | python3 -c 'import json,sys; print(json.load(sys.stdin)["rays"])')
  rays=$((rays + r))
done
t1=$(now)
plain=$(python3 -c "print($t1 - $t0)")

check() {  # check DIR: every output has the plain bake's bytes
  for f in "${files[@]}"; do
    cmp -s "$tmp/plain/${f%.obj}.vff" "$1/${f%.obj}.vff" || { echo "$prog: error: $1/${f%.obj}.vff differs from vff-bake's" >&2; exit 4; }
  done
}

t0=$(now)
"$library" bake "$tmp/lib" --out "$tmp/local" -q --json "$tmp/local.json" -- "${opts[@]}"
t1=$(now)
local_s=$(python3 -c "print($t1 - $t0)")
check "$tmp/local"
t0=$(now)
"$library" bake "$tmp/lib" --out "$tmp/local" -q --json "$tmp/rerun.json" -- "${opts[@]}"
t1=$(now)
rerun_s=$(python3 -c "print($t1 - $t0)")
python3 -c "import json; r=json.load(open('$tmp/rerun.json')); assert not r['baked'] and len(r['upToDate']) == $count, r" \
  || { echo "$prog: error: the re-run was not all up to date" >&2; exit 4; }
workers=$(python3 -c "import json; w=json.load(open('$tmp/local.json'))['workers']; print(f\"{w['processes']} x {w['threadsEach']} threads\")")

slurm_s="" slurm_why=""
if [[ -z ${SLURM_CONF:-} ]]; then
  if out=$(bash "$root/scripts/slurm-cluster.sh" start "$tmp/slurm" 2>&1); then
    slurm_started=1
    export SLURM_CONF="${out#SLURM_CONF=}"
  else
    slurm_why="no Slurm cluster: $(echo "$out" | tail -1)"
  fi
fi
if [[ -z $slurm_why ]]; then
  cpus=$(sinfo -h -o '%C' | awk -F/ '{print $4}')
  t0=$(now)
  "$library" bake "$tmp/lib" --out "$tmp/slurm-out" --slurm --tasks "$cpus" --poll 0.2 -q -- "${opts[@]}"
  t1=$(now)
  slurm_s=$(python3 -c "print($t1 - $t0)")
  check "$tmp/slurm-out"
fi

python3 - "$count" "$rays" "$plain" "$local_s" "$rerun_s" "$workers" "${slurm_s:-}" "${slurm_why:-}" "${opts[*]}" <<'EOF'
import sys
count, rays = int(sys.argv[1]), int(sys.argv[2])
plain, local, rerun = map(float, sys.argv[3:6])
workers, slurm, why, opts = sys.argv[6], sys.argv[7], sys.argv[8], sys.argv[9]
cpu = "unknown"
for line in open("/proc/cpuinfo"):
    if line.startswith("model name"):
        cpu = line.split(":", 1)[1].strip(); break
import os
print(f"cpu             {cpu}, {os.cpu_count()} cores")
print(f"library         {count} meshes, vff-bake {opts}, {rays} rays in all; every output byte-identical to vff-bake's")
print(f"| run | seconds | Mrays/s | / one after another |")
print(f"|---|---:|---:|---:|")
print(f"| vff-bake -j 0, one after another | {plain:.2f} | {rays / plain / 1e6:.2f} | 1.00 |")
print(f"| vff-library, local pool ({workers}) | {local:.2f} | {rays / local / 1e6:.2f} | {plain / local:.2f} |")
if slurm:
    s = float(slurm)
    print(f"| vff-library --slurm (one-node cluster) | {s:.2f} | {rays / s / 1e6:.2f} | {plain / s:.2f} |")
else:
    print(f"| vff-library --slurm | not run: {why} | | |")
print(f"up-to-date re-run of {count} entries: {rerun:.2f} s (target < 2 s); ratio target >= 0.9")
EOF
