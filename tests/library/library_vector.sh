#!/usr/bin/env bash
# library_vector.sh VECTOR - one conformance vector of spec/conformance/library/ (a ctest case each,
# library.vector.*): vff-library bake VECTOR --dry-run --format json, then
#   valid/NAME.json:     the exit code and the entries (mesh, output, args, shardMaps, split) of
#                        NAME.expected.json, in order;
#   invalid/ID/NAME.json: the exit code of the rule, and one error, "name (ID)" followed by the place
#                        NAME.expected.json gives (a JSON path, or LINE:COLUMN of the text).
# Needs VFF_LIBRARY and WORK.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"

check_vector() {
  local vector=$1 expected=${1%.json}.expected.json
  [[ -f $expected ]] || fail "$vector has no $(basename "$expected")"
  run "$VFF_LIBRARY" bake "$vector" --out "$WORK/out" --cache "$WORK/cache" --dry-run --format json
  python3 - "$vector" "$expected" "$RC" "$WORK/out" "$WORK/err" <<'PY' || { show; fail "$vector"; }
import json, re, sys
vector, expected, rc, out, err = sys.argv[1], json.load(open(sys.argv[2])), int(sys.argv[3]), sys.argv[4], sys.argv[5]
errors = open(err, encoding="utf-8", errors="replace").read().splitlines()
if rc != expected["exitCode"]:
    sys.exit(f"exit code {rc}, expected {expected['exitCode']}")
if "/valid/" in vector:
    if errors:
        sys.exit(f"a valid manifest printed errors: {errors}")
    got = [{k: e[k] for k in ("mesh", "output", "args", "shardMaps", "split")} for e in json.load(open(out))["entries"]]
    if got != expected["entries"]:
        sys.exit(f"entries\n  got      {got}\n  expected {expected['entries']}")
    sys.exit(0)
label = f"{expected['name']} ({expected['id']})"
ids = set(re.findall(r"\((13\d\d\d)\)", "\n".join(errors)))
if ids != {str(expected["id"])}:
    sys.exit(f"rule IDs printed: {sorted(ids)}, expected only {expected['id']}")
where = expected["where"]
if re.fullmatch(r"\d+:\d+", where):
    want = f"vff-library: error: {vector}:{where}: {label}: "
elif expected["id"] == 13015:  # an entry's problem: the report names its mesh
    want = f"{label}: {where}: "
else:
    want = f"vff-library: error: {vector}: {label}: " + (f"{where}: " if where else "")
if not any(want in line for line in errors):
    sys.exit(f"no error line holds: {want}")
PY
}

rm -rf "$WORK"
mkdir -p "$WORK"
check_vector "$1"
echo "PASS: $(basename "$1")"
