# library_harness.sh - the vff-library cases, run by the local pool (library_tests.sh) and by a
# Slurm cluster (tests/library.slurm): MODE=local or MODE=slurm picks how `lib_bake` bakes.
# Needs VFF_LIBRARY, VFF_BAKE, VFF_INSPECT, MESHGEN; VFF_TEST_MESHES (optional, the shared meshes).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"

# Small fields: 2(2*4^2+2*4+1) = 82 maps of 8x8.
OPTS=(-n 4 -m 8)

# make_library DIR [shared]: the procedural meshes, one broken file, and with `shared` the shared
# meshes (linked) when present.
make_library() {
  mkdir -p "$1"
  "$MESHGEN" --all "$1" >/dev/null
  if [[ ${2:-} != shared ]]; then
    :
  elif [[ -n ${VFF_TEST_MESHES:-} && -d $VFF_TEST_MESHES ]]; then
    for m in "$VFF_TEST_MESHES"/*.obj; do ln -s "$m" "$1/shared-$(basename "$m")"; done
  else
    echo "note: no shared meshes at ${VFF_TEST_MESHES:-(unset)}: procedural ones only"
  fi
  printf 'v 0 0 0\nv 1 0 0\nf 1 2 7\n' >"$1/broken.obj"
}

# lib_bake ARGS...: vff-library bake in MODE, report in $WORK/report.json.
lib_bake() {
  local input=$1
  shift
  if [[ $MODE == slurm ]]; then
    run env SLURM_CONF="$VFF_TEST_SLURM_CONF" "$VFF_LIBRARY" bake "$input" --out "$WORK/fields" --slurm --poll 0.2 \
      --state "$WORK/state" --json "$WORK/report.json" "$@"
  else
    run "$VFF_LIBRARY" bake "$input" --out "$WORK/fields" --json "$WORK/report.json" "$@"
  fi
}

# json EXPR: a value of the last report.
json() { python3 -c "import json,sys; r=json.load(open('$WORK/report.json')); print($1)"; }

# expect_matches_plain_bake NAME OPTS...: out/NAME.vff has the bytes of vff-bake on lib/NAME.obj.
expect_matches_plain_bake() {
  local name=$1
  shift
  "$VFF_BAKE" "$WORK/lib/$name.obj" -o "$WORK/plain.vff" -q "$@"
  cmp "$WORK/plain.vff" "$WORK/fields/$name.vff" || fail "$name.vff differs from a plain vff-bake"
}

# The count of good meshes in lib/.
good_count() { echo $(($(ls "$WORK"/lib/*.obj | wc -l) - 1)); }

case_outputs_match_plain_bake() {
  make_library "$WORK/lib" shared
  lib_bake "$WORK/lib" -- "${OPTS[@]}"
  expect_rc 3  # the broken mesh's exit code: invalid input
  expect_err "broken.obj"
  expect_err "mesh-parse (10002)"
  [[ $(json 'len(r["baked"])') == $(good_count) ]] || { show; fail "not every good mesh baked"; }
  [[ $(json 'r["failed"][0]["mesh"]') == broken.obj ]] || fail "broken.obj not reported"
  [[ $(json 'r["failed"][0]["exitCode"]') == 3 ]] || fail "broken.obj's exit code"
  for f in "$WORK"/lib/*.obj; do
    local n
    n=$(basename "$f" .obj)
    [[ $n == broken ]] && { [[ ! -e $WORK/fields/broken.vff ]] || fail "an output for the broken mesh"; continue; }
    expect_matches_plain_bake "$n" "${OPTS[@]}"
  done
  [[ -z $(find "$WORK/fields" -name '*.tmp*') ]] || fail "temporaries left"
}

case_rerun_bakes_nothing() {
  make_library "$WORK/lib"
  lib_bake "$WORK/lib" -- "${OPTS[@]}"
  local before
  before=$(stat -c '%i %Y' "$WORK"/fields/*.vff)
  # The same options spelled otherwise are the same bake.
  lib_bake "$WORK/lib" -- --map-size 8 --count 4 --positions octa-hemi2 --codec stored
  expect_rc 3
  [[ $(json 'len(r["baked"])') == 0 ]] || { show; fail "a re-run baked something"; }
  [[ $(json 'len(r["upToDate"])') == $(good_count) ]] || fail "not every entry up to date"
  [[ $(json 'r.get("slurmJobs", [])') == "[]" ]] || fail "a re-run submitted a job"
  [[ $(stat -c '%i %Y' "$WORK"/fields/*.vff) == "$before" ]] || fail "outputs were rewritten"
  # A removed output comes back from the cache, without a bake.
  rm "$WORK/fields/box.vff"
  lib_bake "$WORK/lib" -- "${OPTS[@]}"
  [[ $(json 'len(r["baked"])') == 0 ]] || fail "a removed output was baked again"
  expect_matches_plain_bake box "${OPTS[@]}"
}

# A manifest: per-entry options over defaults; changing one entry's option re-bakes that entry only.
write_manifest() {
  cat >"$WORK/lib/library.json" <<JSON
{"vffLibrary": 1, "defaults": {"count": 4, "map-size": 8},
 "entries": [{"mesh": "box.obj"}, {"mesh": "bowl.obj", "options": {"map-size": $1}},
             {"mesh": "rod.obj", "options": {"normals": true}, "output": "thin/rod-n.vff"}]}
JSON
}

case_changed_option_rebakes_only_affected() {
  make_library "$WORK/lib"
  write_manifest 8
  lib_bake "$WORK/lib/library.json"
  expect_rc 0
  [[ $(json 'len(r["baked"])') == 3 ]] || { show; fail "three entries"; }
  write_manifest 12
  lib_bake "$WORK/lib/library.json"
  expect_rc 0
  [[ $(json '[b["mesh"] for b in r["baked"]]') == "['bowl.obj']" ]] || { show; fail "only bowl.obj re-baked"; }
  [[ $(json 'len(r["upToDate"])') == 2 ]] || fail "two up to date"
  expect_matches_plain_bake bowl -n 4 -m 12
  "$VFF_BAKE" "$WORK/lib/rod.obj" -o "$WORK/plain.vff" -q -n 4 -m 8 --normals
  cmp "$WORK/plain.vff" "$WORK/fields/thin/rod-n.vff" || fail "rod with normals differs"
}

# The number of output fields.
outputs() { find "$WORK/fields" -maxdepth 1 -name '*.vff' | wc -l; }

# An entry above --shard-maps is baked in map ranges (vff-bake --map-range) and merged (--merge):
# the same bytes as a whole bake; entries below it are baked whole.
case_sharded_bake_merges_to_whole() {
  mkdir -p "$WORK/lib"
  "$MESHGEN" torus-knot "$WORK/lib/knot.obj"
  "$MESHGEN" box "$WORK/lib/box.obj"
  # knot: 290 maps in ranges of at most 100; box: 82 maps, whole.
  cat >"$WORK/lib/library.json" <<JSON
{"vffLibrary": 1, "defaults": {"count": 4, "map-size": 8},
 "entries": [{"mesh": "knot.obj", "options": {"count": 8}}, {"mesh": "box.obj"}]}
JSON
  lib_bake "$WORK/lib/library.json" --shard-maps 100
  expect_rc 0
  [[ $(json '[t["maps"] for t in r["tasks"] if t["mesh"] == "knot.obj"]') == "[[0, 100], [100, 200], [200, 290]]" ]] \
    || { show; fail "knot.obj not baked as three ranges: $(json '[t["maps"] for t in r["tasks"]]')"; }
  [[ $(json '[t["maps"] for t in r["tasks"] if t["mesh"] == "box.obj"]') == "['all']" ]] || fail "box.obj baked whole"
  "$VFF_BAKE" "$WORK/lib/knot.obj" -o "$WORK/plain.vff" -q -n 8 -m 8
  cmp "$WORK/plain.vff" "$WORK/fields/knot.vff" || fail "the merged field differs from the whole bake"
  expect_matches_plain_bake box -n 4 -m 8
  [[ -z $(find "$WORK/fields/.vff-cache" -name '*.maps-*') ]] || fail "parts left in the cache after the merge"
  # Sharded or not, the same key: nothing to do without sharding.
  lib_bake "$WORK/lib/library.json"
  [[ $(json 'len(r["upToDate"])') == 2 ]] || fail "the merged field is not the whole bake's cache entry"
}

# Split entries (vff-bake --split): a glTF scene as a field per object and a scene description,
# cached and installed as one unit (spec/library.md section 6).
# write_split_manifest: lib/s.gltf (vff-procedural-mesh's sample scene) split by mesh and by node,
# box.obj, and a broken glTF split by mesh.
write_split_manifest() {
  mkdir -p "$WORK/lib"
  [[ -e $WORK/lib/s.gltf ]] || "$MESHGEN" --gltf-scene "$WORK/lib/s.gltf" || fail "vff-procedural-mesh --gltf-scene"
  "$MESHGEN" box "$WORK/lib/box.obj"
  printf '{"asset": {"version": "2.0"}, "meshes": [' >"$WORK/lib/broken.gltf"
  cat >"$WORK/lib/library.json" <<JSON
{"vffLibrary": 1, "defaults": {"count": 2, "map-size": 8},
 "entries": [{"mesh": "s.gltf", "split": "mesh"},
             {"mesh": "s.gltf", "split": "node", "output": "nodes/s-nodes.json", "options": {"map-size": ${1:-8}}},
             {"mesh": "box.obj"}, {"mesh": "broken.gltf", "split": "mesh"}]}
JSON
}

# expect_split_matches_plain_bake SPLIT OUTPUT OPTS...: vff-bake --split SPLIT of lib/s.gltf to a
# scratch folder writes the files of fields/OUTPUT (its description and its fields) byte for byte.
expect_split_matches_plain_bake() {
  local split=$1 out=$2 f n=0
  shift 2
  rm -rf "$WORK/plain" && mkdir -p "$WORK/plain"
  "$VFF_BAKE" "$WORK/lib/s.gltf" --split "$split" -o "$WORK/plain/$(basename "$out")" -q "$@" || fail "plain vff-bake --split"
  for f in "$WORK"/plain/*; do
    cmp "$f" "$WORK/fields/$(dirname "$out")/$(basename "$f")" || fail "$(basename "$f") differs from a plain vff-bake --split $split"
    n=$((n + 1))
  done
  [[ $n -ge 3 ]] || fail "vff-bake --split $split wrote $n files"
}

case_split_scene_matches_plain_bake() {
  write_split_manifest
  if [[ -n ${SCHEMA_CHECK:-} ]]; then
    "$SCHEMA_CHECK" "$SCHEMA" "$WORK/lib/library.json" || fail "a manifest with split entries does not match the schema"
  fi
  lib_bake "$WORK/lib/library.json"
  expect_rc 3  # the broken glTF's exit code, as vff-bake --split gives it
  "$VFF_BAKE" "$WORK/lib/broken.gltf" --split mesh -o "$WORK/x.json" -q 2>/dev/null && fail "vff-bake took the broken glTF"
  [[ $(json 'r["failed"][0]["exitCode"]') == 3 ]] || fail "the broken glTF's exit code"
  [[ $(json '[f["mesh"] for f in r["failed"]]') == "['broken.gltf']" ]] || { show; fail "broken.gltf not reported"; }
  expect_err "mesh-parse (10002)"
  [[ $(json 'sorted(b["mesh"] for b in r["baked"])') == "['box.obj', 's.gltf', 's.gltf']" ]] || { show; fail "baked"; }
  expect_split_matches_plain_bake mesh s.vffscene.json -n 2 -m 8
  expect_split_matches_plain_bake node nodes/s-nodes.json -n 2 -m 8
  expect_matches_plain_bake box -n 2 -m 8
  [[ ! -e $WORK/fields/broken.vffscene.json && -z $(find "$WORK/fields" -maxdepth 1 -name 'broken*') ]] \
    || fail "an output for the broken glTF"
  [[ -z $(find "$WORK/fields" -name '*.tmp*') ]] || fail "temporaries left"
  # The rays of every field of a scene: 3 node fields, 2 mesh fields, the box, 2(2*2^2+2*2+1) = 26
  # maps of 8x8 each.
  [[ $(json 'r["rays"]') == $(((3 + 2 + 1) * 26 * 64)) ]] || fail "rays: $(json 'r["rays"]')"
  if [[ -n ${SCHEMA_CHECK:-} ]]; then
    "$SCHEMA_CHECK" "$(dirname "$SCHEMA")/scene-schema.json" "$WORK/fields/s.vffscene.json" \
      || fail "the installed scene description does not match the schema"
  fi
}

case_split_rerun_bakes_nothing() {
  write_split_manifest
  lib_bake "$WORK/lib/library.json"
  expect_rc 3
  local before
  before=$(stat -c '%i %Y' "$WORK"/fields/s.* "$WORK"/fields/nodes/*)
  lib_bake "$WORK/lib/library.json"
  expect_rc 3
  [[ $(json 'len(r["baked"])') == 0 ]] || { show; fail "a re-run baked something"; }
  [[ $(json 'len(r["upToDate"])') == 3 ]] || fail "not every entry up to date"
  [[ $(json 'r.get("slurmJobs", [])') == "[]" ]] || fail "a re-run submitted a job"
  [[ $(stat -c '%i %Y' "$WORK"/fields/s.* "$WORK"/fields/nodes/*) == "$before" ]] || fail "outputs were rewritten"
  # A removed field of a scene comes back from the cache, without a bake.
  rm "$WORK/fields/s.mesh1.node3.vff"
  lib_bake "$WORK/lib/library.json"
  [[ $(json 'len(r["baked"])') == 0 ]] || fail "a removed field was baked again"
  expect_split_matches_plain_bake mesh s.vffscene.json -n 2 -m 8
  # A changed option re-bakes its scene only.
  write_split_manifest 12
  lib_bake "$WORK/lib/library.json"
  [[ $(json '[b["output"] for b in r["baked"]]') == "['$WORK/fields/nodes/s-nodes.json']" ]] || { show; fail "only the node split re-baked"; }
  expect_split_matches_plain_bake node nodes/s-nodes.json -n 2 -m 12
  # A changed object (the stretched knot stretched further) re-bakes both scenes, not the box.
  python3 - "$WORK/lib/s.gltf" <<'PY'
import json, sys
d = json.load(open(sys.argv[1]))
next(n for n in d["nodes"] if n.get("name") == "knotStretched")["scale"] = [1.0, 3.0, 1.0]
json.dump(d, open(sys.argv[1], "w"))
PY
  lib_bake "$WORK/lib/library.json"
  [[ $(json 'sorted(b["mesh"] for b in r["baked"])') == "['s.gltf', 's.gltf']" ]] || { show; fail "both scenes re-baked"; }
  [[ $(json '[u["mesh"] for u in r["upToDate"]]') == "['box.obj']" ]] || fail "box.obj up to date"
  expect_split_matches_plain_bake mesh s.vffscene.json -n 2 -m 8
  expect_split_matches_plain_bake node nodes/s-nodes.json -n 2 -m 12
}
