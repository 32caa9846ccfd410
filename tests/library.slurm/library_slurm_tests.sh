#!/usr/bin/env bash
# library_slurm_tests.sh - vff-library through Slurm job arrays (cases library.slurm.*), on the
# one-node cluster scripts/test.sh starts (scripts/slurm-cluster.sh; VFF_TEST_SLURM_CONF names its
# slurm.conf): the local cases' checks, and an array task cancelled mid-run completed by the next run.
# Without a cluster each case exits 77, which ctest reports as skipped.
MODE=slurm
source "$(dirname "${BASH_SOURCE[0]}")/../library/library_harness.sh"

if [[ -z ${VFF_TEST_SLURM_CONF:-} || ! -f ${VFF_TEST_SLURM_CONF:-} ]]; then
  echo "SKIP: no Slurm cluster (VFF_TEST_SLURM_CONF unset; scripts/test.sh starts one with scripts/slurm-cluster.sh)"
  exit 77
fi

test_outputs_match_plain_bake() { case_outputs_match_plain_bake; }
test_rerun_submits_nothing() { case_rerun_bakes_nothing; }
test_changed_option_rebakes_only_affected() { case_changed_option_rebakes_only_affected; }
test_sharded_bake_merges_to_whole() { case_sharded_bake_merges_to_whole; }
test_split_scene_matches_plain_bake() { case_split_scene_matches_plain_bake; }
test_split_rerun_submits_nothing() { case_split_rerun_bakes_nothing; }

# cancel_task_1 RETRIES: bakes the library (shared meshes too) as two array tasks, one at a time,
# and cancels task 1 while it runs; the run's exit code in RC, its report in $WORK/report.json.
# Task 1's first bake is held (a vff-bake wrapper that waits) until the cancel: however fast the
# machine, the cancel comes mid-task, after task 0 baked its share.
cancel_task_1() {
  make_library "$WORK/lib" shared
  cat >"$WORK/held-bake.sh" <<EOS
#!/usr/bin/env bash
if [[ \${SLURM_ARRAY_TASK_ID:-} == 1 ]] && mkdir "$WORK/held" 2>/dev/null; then
  for i in \$(seq 1200); do sleep 0.1; done  # the cancel ends this; a bound keeps a lost one finite
fi
exec "$VFF_BAKE" "\$@"
EOS
  chmod +x "$WORK/held-bake.sh"
  SLURM_CONF=$VFF_TEST_SLURM_CONF VFF_BAKE=$WORK/held-bake.sh "$VFF_LIBRARY" bake "$WORK/lib" --out "$WORK/fields" \
    --slurm --poll 0.2 --state "$WORK/state" --tasks 2 --max-running 1 --retries "$1" --json "$WORK/report.json" \
    -q -- "${SLOW[@]}" >"$WORK/first.out" 2>"$WORK/first.err" &
  local pid=$! job i
  for i in $(seq 1200); do
    [[ -d $WORK/held ]] && break
    sleep 0.05
  done
  [[ -d $WORK/held ]] || fail "array task 1 never started a bake"
  job=$(cut -d';' -f1 "$WORK/state/round-0.sbatch.out")
  SLURM_CONF=$VFF_TEST_SLURM_CONF scancel "${job}_1"
  RC=0
  wait $pid || RC=$?
}
SLOW=(-n 8 -m 24)

test_cancelled_task_completed_by_next_run() {
  local good done
  cancel_task_1 0
  good=$(good_count)
  [[ $RC == 4 ]] || { cat "$WORK/first.err" >&2; fail "first run: exit $RC, expected 4 (entries missing)"; }
  grep -q "not baked: its array task" "$WORK/first.err" || { cat "$WORK/first.err" >&2; fail "missing entries not named"; }
  done=$(json 'len(r["baked"])')
  [[ $done -ge 1 && $done -lt $good ]] || fail "the cancel came at $done of $good: cannot show a resume"
  for f in "$WORK"/fields/*.vff; do expect_matches_plain_bake "$(basename "$f" .vff)" "${SLOW[@]}"; done
  rm -rf "$WORK/state"
  lib_bake "$WORK/lib" -- "${SLOW[@]}"
  expect_rc 3
  [[ $(json 'len(r["baked"])') == $((good - done)) ]] || { show; fail "the next run baked other than the missing entries"; }
  [[ $(json 'len(r["slurmJobs"])') == 1 ]] || fail "one array"
  for f in "$WORK"/lib/*.obj; do
    [[ $(basename "$f") == broken.obj ]] || expect_matches_plain_bake "$(basename "$f" .obj)" "${SLOW[@]}"
  done
}

test_cancelled_task_resubmitted() {
  cancel_task_1 1
  # The entries task 1 left are submitted again as a second array; only the broken one fails.
  [[ $RC == 3 ]] || { cat "$WORK/first.err" >&2; fail "exit $RC, expected 3 (the broken mesh only)"; }
  [[ $(json 'len(r["slurmJobs"])') == 2 ]] || fail "no second array"
  [[ $(json 'len(r["baked"])') == $(good_count) ]] || fail "not every good mesh baked"
  local second
  second=$(python3 -c "import json; print(len(json.load(open('$WORK/state/round-1.plan.json'))['entries']))")
  [[ $second -ge 1 && $second -lt $(good_count) ]] || fail "the second array held $second bakes, not only the missing ones"
  for f in "$WORK"/lib/*.obj; do
    [[ $(basename "$f") == broken.obj ]] || expect_matches_plain_bake "$(basename "$f" .obj)" "${SLOW[@]}"
  done
}

run_test "$1"
