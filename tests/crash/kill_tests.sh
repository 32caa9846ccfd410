#!/usr/bin/env bash
# Crash safety: a writer killed with SIGKILL at any moment leaves the destination holding either the
# old file, byte for byte, or (when there was none) nothing; never a truncated file under the real
# name. Usage: kill_tests.sh TOOL BAKE CONVERT INSPECT MESHGEN COMPRESS
#   TOOL  bake | convert_exr | convert_repack | compress
set -uo pipefail
tool="$1"; bake="$2"; convert="$3"; inspect="$4"; meshgen="$5"; compress="$6"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
fail() { echo "FAIL: $*"; exit 1; }
"$meshgen" torus-knot knot.obj || fail "mesh generator"
# Jobs that take about a second: the kills land before, during and after the write.
"$bake" knot.obj -o big.vff -n 16 -m 32 --normals -q || fail "baking the input"
case "$tool" in
  bake) dest=out.vff; cmd=("$bake" knot.obj -o out.vff -n 32 -m 64 --normals -q) ;;
  convert_exr) dest=out.exr; cmd=("$convert" big.vff --to exr out.exr) ;;
  convert_repack) dest=out.vff; cmd=("$convert" big.vff --to vff out.vff --codec zstd --max-texture-size 1024) ;;
  compress) dest=out.vff; cmd=("$compress" big.vff out.vff -q) ;;
  *) fail "unknown tool $tool" ;;
esac
echo "old content, not a field" > old.bin
killed=0 finished=0
# Delays spread over the run (deterministic): 0 to ~1.5 s.
for delay in 0 0.02 0.05 0.1 0.15 0.2 0.3 0.4 0.5 0.6 0.7 0.8 0.9 1.0 1.2 1.5 2 3; do
  for start in old none; do
    rm -f "$dest"
    if [ "$start" = old ]; then cp old.bin "$dest"; fi
    "${cmd[@]}" >/dev/null 2>&1 &
    pid=$!
    sleep "$delay"
    if kill -9 "$pid" 2>/dev/null; then killed=$((killed + 1)); else finished=$((finished + 1)); fi
    wait "$pid" 2>/dev/null
    if [ -e "$dest" ] && ! cmp -s "$dest" old.bin; then
      # Not the old file: it must be a complete output.
      case "$dest" in
        *.vff) "$inspect" "$dest" --validate >/dev/null 2>&1 || fail "after kill at ${delay}s ($start): $dest is neither the old file nor a valid field" ;;
        *.exr) "$convert" "$dest" --to vff check.vff >/dev/null 2>&1 || fail "after kill at ${delay}s ($start): $dest is neither the old file nor a complete EXR" ;;
      esac
    fi
    if [ "$start" = none ] && [ -e "$dest" ] && cmp -s "$dest" old.bin; then fail "impossible: old content appeared"; fi
  done
done
echo "PASS: $tool: $killed runs killed mid-way, $finished finished before the kill; the destination was always the old file, nothing, or complete"
[ "$killed" -gt 0 ] || fail "no run was killed: the test did not test anything"
[ "$finished" -gt 0 ] || fail "no run finished before its kill: the kills did not span the whole write"
