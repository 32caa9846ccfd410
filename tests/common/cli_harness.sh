# cli_harness.sh - helpers shared by the command-line test scripts (sourced; needs $WORK).
# run CMD... keeps stdout in $WORK/out, stderr in $WORK/err and the exit code in RC; the expect_*
# functions check them and show both streams when they fail.
fail() {
  echo "FAIL: $*" >&2
  exit 1
}
show() {
  echo "--- stdout:" >&2
  head -c 6000 "$WORK/out" >&2 || true
  echo "--- stderr:" >&2
  head -c 3000 "$WORK/err" >&2 || true
}
run() {
  set +e
  "$@" >"$WORK/out" 2>"$WORK/err"
  RC=$?
  set -e
}
expect_rc() { [[ $RC -eq $1 ]] || { show; fail "exit code $RC, expected $1"; }; }
expect_out() { grep -q -F -e "$1" "$WORK/out" || { show; fail "stdout lacks: $1"; }; }
expect_out_re() { grep -q -E -e "$1" "$WORK/out" || { show; fail "stdout matches no line: $1"; }; }
expect_err() { grep -q -F -e "$1" "$WORK/err" || { show; fail "stderr lacks: $1"; }; }
expect_err_re() { grep -q -E -e "$1" "$WORK/err" || { show; fail "stderr matches no line: $1"; }; }
expect_no_out() { [[ ! -s $WORK/out ]] || { show; fail "stdout is not empty"; }; }
expect_no_err() { [[ ! -s $WORK/err ]] || { show; fail "stderr is not empty"; }; }
# valid FILE: `$VFF_INSPECT FILE --validate` accepts it (exit 0).
valid() {
  run "$VFF_INSPECT" "$1" --validate
  [[ $RC -eq 0 ]] || { show; fail "$1 does not validate"; }
}
# run_test NAME: the last line of every suite (`run_test "$1"`): runs the test function NAME in an
# emptied $WORK and prints "PASS: NAME" when it returns. tests/CMakeLists.txt checks for that line.
run_test() {
  declare -F "$1" >/dev/null || { echo "no such test: $1" >&2; exit 2; }
  rm -rf "$WORK"
  mkdir -p "$WORK"
  "$1"
  echo "PASS: $1"
}
