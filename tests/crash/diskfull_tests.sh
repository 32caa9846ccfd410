#!/usr/bin/env bash
# diskfull_tests.sh - every writer of the tools, with its output on a file system that fills up.
#
# Two ways to make a write fail part-way, each tested for every writer:
#   tmpfs_*  the output folder is a tiny tmpfs (`unshare -rm` + `mount -t tmpfs -o size=...`):
#            write() fails with ENOSPC. Needs user and mount namespaces; exits 77 (ctest: skipped)
#            with the reason when this machine does not allow them.
#   fsize_*  the file size limit (`ulimit -f`, RLIMIT_FSIZE): write() fails with EFBIG. The tools
#            ignore SIGXFSZ (tools/common/cli.cpp, parse()), so the error path runs instead of the
#            signal killing the tool with its temporary file left behind. Works everywhere.
# For each writer the limit is swept over the output's size (from nothing fits to all but the last
# page), with an old file at the destination, and each run must: exit 2, name the destination and
# the cause on stderr, leave the old file byte for byte, and leave no temporary next to it. With
# room for the whole output the same command must succeed and write the same bytes as without a
# limit. Every function named test_* is one ctest case (tests/crash/CMakeLists.txt); environment:
#   VFF_BAKE VFF_CONVERT VFF_COMPRESS VFF_INSPECT MESHGEN  the executables; WORK a scratch folder of this test;
#   VFF_EXPERIMENTS  optional: vff-experiments (the stdout_full_* cases also run it).
set -euo pipefail

# ---- Inside the namespace (called by in_tmpfs below) ------------------------------------------------
# diskfull_tests.sh __tmpfs_run SIZE DIR OLD DEST RESULT CMD...: mounts a SIZE-byte tmpfs on DIR,
# copies OLD to DIR/DEST, runs CMD, and leaves in RESULT/ its exit code (rc), stderr (err), the
# folder's listing (ls) and the destination's final bytes (dest, when there is one): the tmpfs
# goes away with the namespace.
if [[ ${1:-} == __tmpfs_run ]]; then
  shift
  size=$1 dir=$2 old=$3 dest=$4 result=$5
  shift 5
  mount -t tmpfs -o "size=$size" tmpfs "$dir"
  cp "$old" "$dir/$dest"
  set +e
  "$@" >/dev/null 2>"$result/err"
  echo $? >"$result/rc"
  set -e
  ls -A "$dir" >"$result/ls"
  rm -f "$result/dest"
  if [[ -e $dir/$dest ]]; then cp "$dir/$dest" "$result/dest"; fi
  exit 0
fi

: "${VFF_BAKE:?}" "${VFF_CONVERT:?}" "${VFF_COMPRESS:?}" "${VFF_INSPECT:?}" "${MESHGEN:?}" "${WORK:?}"
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"
self="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)/$(basename "${BASH_SOURCE[0]}")"

skip() {
  echo "SKIP: $*"
  exit 77
}

# tmpfs_available: whether this process may make a mount namespace and mount a tmpfs in it.
tmpfs_available() {
  mkdir -p "$WORK/probe"
  unshare -rm sh -c "mount -t tmpfs -o size=65536 tmpfs '$WORK/probe'" 2>"$WORK/probe.err"
}

# The inputs a writer needs (small: every run takes a fraction of a second).
inputs() {
  local kind=$1
  echo "old content, not a field" >"$WORK/old.bin"
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  [[ $kind == bake ]] && return
  "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/in.vff" -n 6 -m 32 --normals -q || fail "baking the input"
  [[ $kind == from_exr ]] || return 0
  "$VFF_CONVERT" "$WORK/in.vff" --to exr "$WORK/in.exr" -q || fail "converting the input to EXR"
}

# The command of each writer, writing to $1 (a path).
writer_cmd() {
  local kind=$1 out=$2
  case "$kind" in
    bake) cmd=("$VFF_BAKE" "$WORK/knot.obj" -o "$out" -n 6 -m 32 --normals -q) ;;
    repack) cmd=("$VFF_CONVERT" "$WORK/in.vff" --to vff "$out" --codec zstd --zstd-level 3 -q) ;;
    to_exr) cmd=("$VFF_CONVERT" "$WORK/in.vff" --to exr "$out" -q) ;;
    from_exr) cmd=("$VFF_CONVERT" "$WORK/in.exr" --to vff "$out" -q) ;;
    preview) cmd=("$VFF_INSPECT" "$WORK/in.vff" --preview "$out" --maps 200) ;;
    compress) cmd=("$VFF_COMPRESS" "$WORK/in.vff" "$out" --level 3 -q) ;;
    *) fail "unknown writer $kind" ;;
  esac
}

# check_failed MECHANISM DEST RESULTDIR LIMIT: the run in RESULTDIR failed cleanly.
check_failed() {
  local mech=$1 dest=$2 r=$3 limit=$4 cause
  cause=$([[ $mech == tmpfs ]] && echo "No space left on device" || echo "File too large")
  [[ $(cat "$r/rc") == 2 ]] || {
    cat "$r/err" >&2
    fail "$mech limit $limit: exit code $(cat "$r/rc"), expected 2 (I/O error)"
  }
  grep -q -F -e "$dest" "$r/err" || { cat "$r/err" >&2; fail "$mech limit $limit: stderr does not name $dest"; }
  grep -q -F -e "$cause" "$r/err" || { cat "$r/err" >&2; fail "$mech limit $limit: stderr does not say '$cause'"; }
  [[ -e $r/dest ]] && cmp -s "$r/dest" "$WORK/old.bin" || fail "$mech limit $limit: the old $dest was not kept"
  [[ $(cat "$r/ls") == "$(basename "$dest")" ]] || fail "$mech limit $limit: left behind: $(tr '\n' ' ' <"$r/ls")"
}

# sweep MECHANISM WRITER: runs the writer under limits from nothing to all but the last page of its
# output, then with room to spare.
sweep() {
  local mech=$1 kind=$2 ext full size
  case "$kind" in to_exr) ext=exr ;; preview) ext=png ;; *) ext=vff ;; esac
  inputs "$kind"
  # The output without a limit: its size sets the sweep, its bytes are what a limited run must give.
  writer_cmd "$kind" "$WORK/reference.$ext"
  "${cmd[@]}" >/dev/null || fail "the $kind writer fails without a limit"
  full=$(stat -c %s "$WORK/reference.$ext")
  local limits=() f
  for f in 0 1 2 3; do limits+=($((full * f / 4 / 4096 * 4096))); done
  limits+=($(((full - 1) / 4096 * 4096)))
  mapfile -t limits < <(printf '%s\n' "${limits[@]}" | sort -n -u)
  local r="$WORK/result" dir="$WORK/out" failed=0
  mkdir -p "$r" "$dir"
  local dest="$dir/out.$ext"
  writer_cmd "$kind" "$dest"
  for size in "${limits[@]}" big; do
    if [[ $mech == tmpfs ]]; then
      # The old file takes one 4 KiB page of the tmpfs; tmpfs size=0 would mean no limit.
      local bytes
      if [[ $size == big ]]; then bytes=$((2 * full + 65536)); else bytes=$((size + 4096)); fi
      unshare -rm bash "$self" __tmpfs_run "$bytes" "$dir" "$WORK/old.bin" "out.$ext" "$r" "${cmd[@]}"
    else
      rm -rf "$dir"/* "$dir"/.[!.]*
      cp "$WORK/old.bin" "$dest"
      local blocks
      if [[ $size == big ]]; then blocks=$((full / 1024 + 64)); else blocks=$((size / 1024)); fi
      # stderr goes through a pipe: the limit would stop the tool writing it to a file too.
      set +e
      (ulimit -f "$blocks" && exec "${cmd[@]}") 2>&1 >/dev/null | cat >"$r/err"
      echo "${PIPESTATUS[0]}" >"$r/rc"
      set -e
      ls -A "$dir" >"$r/ls"
      rm -f "$r/dest"
      if [[ -e $dest ]]; then cp "$dest" "$r/dest"; fi
    fi
    if [[ $size == big ]]; then
      [[ $(cat "$r/rc") == 0 ]] || { cat "$r/err" >&2; fail "$mech with room for the output: exit code $(cat "$r/rc")"; }
      cmp -s "$r/dest" "$WORK/reference.$ext" || fail "$mech with room for the output: different bytes than without a limit"
      [[ $(cat "$r/ls") == "out.$ext" ]] || fail "$mech with room: left behind: $(tr '\n' ' ' <"$r/ls")"
    else
      check_failed "$mech" "$dest" "$r" "$size"
      failed=$((failed + 1))
    fi
  done
  echo "$kind ($mech): $failed limits from 0 to $((full - 1)) bytes of a $full-byte output failed cleanly" \
       "(exit 2, old file kept, nothing left behind); with room, the same bytes as without a limit"
}

tmpfs_sweep() {
  tmpfs_available || skip "no tmpfs in a private mount namespace here ($(head -c 200 "$WORK/probe.err")); the fsize_* tests cover the same writers"
  sweep tmpfs "$1"
}

test_tmpfs_bake() { tmpfs_sweep bake; }
test_tmpfs_convert_repack() { tmpfs_sweep repack; }
test_tmpfs_convert_to_exr() { tmpfs_sweep to_exr; }
test_tmpfs_convert_from_exr() { tmpfs_sweep from_exr; }
test_tmpfs_inspect_preview() { tmpfs_sweep preview; }
test_tmpfs_compress() { tmpfs_sweep compress; }
test_fsize_bake() { sweep fsize bake; }
test_fsize_convert_repack() { sweep fsize repack; }
test_fsize_convert_to_exr() { sweep fsize to_exr; }
test_fsize_convert_from_exr() { sweep fsize from_exr; }
test_fsize_inspect_preview() { sweep fsize preview; }
test_fsize_compress() { sweep fsize compress; }

# ---- Standard output that cannot be written ----------------------------------------------------------
# A report on stdout that cannot be written (/dev/full: ENOSPC) is an I/O error for every tool: the
# check cli::parse() installs (tools/common/cli.cpp) flushes stdout at exit and turns a failed
# write into "PROG: error: stdout: No space left on device" and exit 2. An output file the tool
# writes is complete by then (written through a temporary and a rename); only the report is lost.

# stdout_full NAME CMD...: CMD prints something to stdout (checked on a pipe first: exit 0), and with
# stdout on /dev/full exits 2 with the diagnostic.
stdout_full() {
  local name=$1
  shift
  [[ -w /dev/full ]] || skip "no writable /dev/full here"
  run "$@"
  expect_rc 0
  [[ -s $WORK/out ]] || { show; fail "$name prints nothing on stdout: the test proves nothing"; }
  set +e
  "$@" >/dev/full 2>"$WORK/err"
  RC=$?
  set -e
  : >"$WORK/out"
  expect_rc 2
  expect_err "$name: error: stdout: No space left on device"
  echo "$name $(printf '%q ' "${@:2}")> /dev/full: exit 2, $(head -n 1 "$WORK/err")"
}

test_stdout_full_inspect() {
  inputs inspect
  stdout_full vff-inspect "$VFF_INSPECT" "$WORK/in.vff" --format json
  stdout_full vff-inspect "$VFF_INSPECT" "$WORK/in.vff"
  stdout_full vff-inspect "$VFF_INSPECT" "$WORK/in.vff" --validate
}

test_stdout_full_bake() {
  inputs bake
  stdout_full vff-bake "$VFF_BAKE" "$WORK/knot.obj" -o "$WORK/baked.vff" -n 6 -m 32 --json
  valid "$WORK/baked.vff"
}

test_stdout_full_convert() {
  inputs inspect
  stdout_full vff-convert "$VFF_CONVERT" "$WORK/in.vff" --to vff "$WORK/repacked.vff" --codec zstd
  valid "$WORK/repacked.vff"
  stdout_full vff-convert "$VFF_CONVERT" "$WORK/in.vff" --to exr "$WORK/in.exr"
  [[ -s $WORK/in.exr ]] || fail "no EXR written"
}

test_stdout_full_compress() {
  inputs inspect
  stdout_full vff-compress "$VFF_COMPRESS" "$WORK/in.vff" "$WORK/small.vff" --level 3
  valid "$WORK/small.vff"
}

# --help and --version print to stdout before any work: the check covers them too.
test_stdout_full_help_version() {
  local tool
  for tool in "$VFF_BAKE" "$VFF_INSPECT" "$VFF_CONVERT" "$VFF_COMPRESS" ${VFF_EXPERIMENTS:+"$VFF_EXPERIMENTS"}; do
    stdout_full "${tool##*/}" "$tool" --help
    stdout_full "${tool##*/}" "$tool" --version
  done
}

test_stdout_full_experiments() {
  [[ -n ${VFF_EXPERIMENTS:-} ]] || skip "vff-experiments is not built"
  "$MESHGEN" torus-knot "$WORK/knot.obj" >/dev/null || fail "mesh generator"
  stdout_full vff-experiments "$VFF_EXPERIMENTS" bench --mesh "$WORK/knot.obj" --config 1090x16x16 --bench-rays 2000 --repeat 1 -j 2
}

# ---- Runner --------------------------------------------------------------------------------------
[[ $# -eq 1 && $1 == test_* ]] || { echo "usage: $0 test_NAME" >&2; exit 2; }
run_test "$1"
