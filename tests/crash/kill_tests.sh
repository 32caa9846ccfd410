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
# One uninterrupted run gives the job's duration T on this machine now; the kills land at fixed
# fractions of T (so a loaded machine, where everything is slower, still sees kills spread over the
# whole write), and the last delays, 1.5 T and 3 T + 1 s, let the job finish.
t0=$(date +%s%N)
"${cmd[@]}" >/dev/null 2>&1 || fail "an uninterrupted run failed: ${cmd[*]}"
T=$(( ($(date +%s%N) - t0) / 1000000 ))  # milliseconds
echo "uninterrupted run: $T ms"
delays=()
for f in 0 2 5 10 15 20 30 40 50 60 70 80 90 100 120 150; do
  delays+=("$(awk -v t="$T" -v f="$f" 'BEGIN { printf "%.3f", t * f / 100000 }')")
done
delays+=("$(awk -v t="$T" 'BEGIN { printf "%.3f", 3 * t / 1000 + 1 }')")
killed=0 finished=0
for delay in "${delays[@]}"; do
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
