#!/usr/bin/env bash
# library_tests.sh - vff-library with the local pool (cases library.*): every output byte-identical to
# a plain vff-bake of its entry, a re-run bakes nothing, a changed option re-bakes only what it
# affects, a killed pool loses nothing and the next run completes it, the broken entry reported while
# the others finish; glTF scenes split per object (split entries); manifests, dry runs and the Slurm
# batch script (printed, not submitted).
MODE=local
source "$(dirname "${BASH_SOURCE[0]}")/library_harness.sh"

test_outputs_match_plain_bake() { case_outputs_match_plain_bake; }
test_rerun_bakes_nothing() { case_rerun_bakes_nothing; }
test_changed_option_rebakes_only_affected() { case_changed_option_rebakes_only_affected; }
test_sharded_bake_merges_to_whole() { case_sharded_bake_merges_to_whole; }
test_split_scene_matches_plain_bake() { case_split_scene_matches_plain_bake; }
test_split_rerun_bakes_nothing() { case_split_rerun_bakes_nothing; }

test_killed_pool_loses_nothing_and_resumes() {
  make_library "$WORK/lib" shared
  local opts=(-n 8 -m 24) good
  good=$(good_count)
  "$VFF_LIBRARY" bake "$WORK/lib" --out "$WORK/fields" -j 1 -q -- "${opts[@]}" >/dev/null 2>&1 &
  local pid=$! i
  for i in $(seq 600); do
    [[ $(outputs) -ge 1 ]] && break
    sleep 0.05
  done
  kill -9 $pid
  wait $pid || true
  local done
  done=$(outputs)
  [[ $done -ge 1 && $done -lt $good ]] || fail "the kill came at $done of $good outputs: cannot show a resume"
  # No bake outlives the pool, and nothing partial is left at an output.
  sleep 0.2
  ! pgrep -f "$WORK/fields/.vff-cache/tmp" >/dev/null || fail "a vff-bake outlived the killed pool"
  [[ -z $(find "$WORK/fields" -maxdepth 1 -name '.*tmp*') ]] || fail "a temporary output left"
  for f in "$WORK"/fields/*.vff; do expect_matches_plain_bake "$(basename "$f" .vff)" "${opts[@]}"; done
  lib_bake "$WORK/lib" -- "${opts[@]}"
  expect_rc 3
  [[ $(json 'len(r["baked"]) + len(r["upToDate"])') == "$good" ]] || { show; fail "the next run did not complete"; }
  [[ $(json 'len(r["upToDate"])') -ge $done ]] || fail "finished entries were baked again"
  for f in "$WORK"/fields/*.vff; do expect_matches_plain_bake "$(basename "$f" .vff)" "${opts[@]}"; done
  [[ -z $(ls -A "$WORK/fields/.vff-cache/tmp") ]] || fail "the killed run's private folders were not removed"
}

test_all_good_exits_zero_and_reports() {
  mkdir -p "$WORK/lib"
  "$MESHGEN" box "$WORK/lib/a.obj"
  "$MESHGEN" rod "$WORK/lib/b.obj"
  lib_bake "$WORK/lib" --cache "$WORK/cache" -- -n 4 -m 8
  expect_rc 0
  expect_err "2 entries: 2 baked, 0 up to date, 0 failed"
  [[ $(json 'r["rays"]') == $((2 * 82 * 64)) ]] || fail "rays: $(json 'r["rays"]')"
  [[ $(json 'len(r["tasks"])') == 2 ]] || fail "a time per task"
  # (The cache's own tmp/ holds work in progress: matched from the cache, not as any folder named
  # tmp above it, which a checkout under the system's temporary folder has.)
  [[ $(find "$WORK/cache" -name '*.vff' -not -path "$WORK/cache/tmp/*" | wc -l) == 2 ]] || fail "two fields in the cache"
  # The same geometry under another name is another field (its name is in the file's metadata).
  cp "$WORK/lib/a.obj" "$WORK/lib/c.obj"
  lib_bake "$WORK/lib" --cache "$WORK/cache" -- -n 4 -m 8
  [[ $(json '[b["mesh"] for b in r["baked"]]') == "['c.obj']" ]] || fail "c.obj"
}

test_changed_mesh_rebakes_only_it() {
  make_library "$WORK/lib"
  lib_bake "$WORK/lib" -- "${OPTS[@]}"
  # Another shape in box.obj: baked again; the same bytes written anew: read again, not baked.
  "$MESHGEN" rod "$WORK/lib/box.obj"
  touch "$WORK/lib/bowl.obj"
  lib_bake "$WORK/lib" -- "${OPTS[@]}"
  [[ $(json '[b["mesh"] for b in r["baked"]]') == "['box.obj']" ]] || { show; fail "only box.obj re-baked"; }
  expect_matches_plain_bake box "${OPTS[@]}"
  lib_bake "$WORK/lib" --rehash -- "${OPTS[@]}"
  [[ $(json 'len(r["baked"])') == 0 ]] || fail "--rehash re-baked an unchanged mesh"
}

# A dry run lists what it would bake and the entries that would fail, with their problem, and exits
# as the bake would (the broken mesh: 3).
test_dry_run_bakes_nothing() {
  make_library "$WORK/lib"
  run "$VFF_LIBRARY" bake "$WORK/lib" --out "$WORK/fields" --dry-run -- -m 8
  expect_rc 3
  expect_out "box.obj -m 8 -o"
  expect_out "# 6 entries: 5 to bake, 0 up to date, 1 failing"
  expect_err "vff-library: error: broken.obj: mesh-parse (10002): line 3: face index 7"
  run "$VFF_LIBRARY" bake "$WORK/lib" --out "$WORK/fields" --dry-run --slurm --partition gpu --time 10:00 \
    --max-running 3 --tasks 5 --sbatch-arg=--account=vff -- -m 8
  expect_rc 3
  expect_out "'--array=0-4%3'"  # five good meshes
  expect_out "#SBATCH --partition=gpu"
  expect_out "#SBATCH --time=10:00"
  expect_out "#SBATCH --account=vff"
  expect_out "run-shard"
  [[ -z $(find "$WORK/fields" -name '*.vff') ]] || fail "a dry run baked"
}

test_manifests_match_the_schema() {
  [[ -n ${SCHEMA_CHECK:-} ]] || { echo "SKIP: vff_cli_schema_check is not built"; return 0; }
  mkdir -p "$WORK/lib"
  write_manifest 8
  "$SCHEMA_CHECK" "$SCHEMA" "$WORK/lib/library.json" || fail "a manifest vff-library bakes does not match the schema"
  echo '{"vffLibrary": 1, "entries": [{"mesh": "a.obj", "options": {"threads": 4}}]}' >"$WORK/lib/m.json"
  ! "$SCHEMA_CHECK" "$SCHEMA" "$WORK/lib/m.json" || fail "the schema takes an option vff-library refuses"
  # Every valid conformance vector (spec/conformance/library/valid) matches it too.
  local v
  for v in "$(dirname "$SCHEMA")"/conformance/library/valid/*.json; do
    [[ $v == *.expected.json ]] && continue
    "$SCHEMA_CHECK" "$SCHEMA" "$v" || fail "the valid vector $(basename "$v") does not match the schema"
  done
}

test_manifest_errors() {
  mkdir -p "$WORK/lib"
  echo '{"vffLibrary": 1, "entries": [{"mesh": "a.obj", "options": {"threads": 4}}]}' >"$WORK/lib/m.json"
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields"
  expect_rc 3
  expect_err "vff-library: error: $WORK/lib/m.json: unknown-option (13008): entries[0].options.threads: not a vff-bake option"
  echo '{"entries": []}' >"$WORK/lib/m.json"
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields"
  expect_rc 3
  expect_err "$WORK/lib/m.json: manifest-object (13002): not a vff library manifest"
  run "$VFF_LIBRARY" bake "$WORK/lib/none.json" --out "$WORK/fields"
  expect_rc 2
  echo '{"vffLibrary": 1, "entries": [{"mesh": "a.obj", "options": {"map-size": 0}}]}' >"$WORK/lib/m.json"
  "$MESHGEN" box "$WORK/lib/a.obj"
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields"
  expect_rc 1
  expect_err "vff-library: error: a.obj: bake-option (13015): entries[0].options: --map-size: Value 0 not in range 1 to 4096 (exit 1)"
  run "$VFF_LIBRARY" bake "$WORK/lib" --out "$WORK/fields" --no-such-option
  expect_rc 1
}

# A .gltf whose buffer is a file of its own: a changed buffer is a changed entry, though the .gltf
# itself (path, size, time) is not (the source notes of an up-to-date run also name its files).
test_gltf_external_buffer_change_rebakes() {
  mkdir -p "$WORK/lib"
  "$MESHGEN" --gltf-scene "$WORK/lib/s.gltf"
  # The URI "s+data%2Ebin" names "s data.bin" to tinygltf's loader ('+' is a space there); a decoy
  # "s+data.bin" beside it must not stand in for it in the cache's note.
  python3 - "$WORK/lib/s.gltf" <<'PY'
import base64, json, sys
path = sys.argv[1]
d = json.load(open(path))
assert len(d["buffers"]) == 1 and d["buffers"][0]["uri"].startswith("data:"), d["buffers"]
data = base64.b64decode(d["buffers"][0]["uri"].split(",", 1)[1])
open(path[:-5] + " data.bin", "wb").write(data)
open(path[:-5] + "+data.bin", "wb").write(data)
d["buffers"][0]["uri"] = "s+data%2Ebin"
json.dump(d, open(path, "w"))
PY
  echo '{"vffLibrary": 1, "defaults": {"count": 2, "map-size": 8}, "entries": [{"mesh": "s.gltf", "split": "mesh"}]}' \
    >"$WORK/lib/library.json"
  lib_bake "$WORK/lib/library.json"
  expect_rc 0
  lib_bake "$WORK/lib/library.json"
  [[ $(json 'len(r["upToDate"])') == 1 ]] || { show; fail "an unchanged scene was not up to date"; }
  expect_split_matches_plain_bake mesh s.vffscene.json -n 2 -m 8
  # The positions doubled in the buffer file; the .gltf stays as it was.
  python3 - "$WORK/lib/s data.bin" "$WORK/lib/s.gltf" <<'PY'
import json, struct, sys
d = json.load(open(sys.argv[2]))
pos = [a for m in d["meshes"] for p in m["primitives"] for k, a in p["attributes"].items() if k == "POSITION"]
raw = bytearray(open(sys.argv[1], "rb").read())
for a in pos:
    acc = d["accessors"][a]
    view = d["bufferViews"][acc["bufferView"]]
    start = view.get("byteOffset", 0) + acc.get("byteOffset", 0)
    for i in range(acc["count"] * 3):
        o = start + 4 * i
        raw[o:o + 4] = struct.pack("<f", 2 * struct.unpack("<f", raw[o:o + 4])[0])
open(sys.argv[1], "wb").write(raw)
PY
  lib_bake "$WORK/lib/library.json"
  expect_rc 0
  [[ $(json 'len(r["baked"])') == 1 ]] || { show; fail "a changed buffer did not re-bake the scene"; }
  expect_split_matches_plain_bake mesh s.vffscene.json -n 2 -m 8
}

# A pool killed while a split scene is baked (its files all written in the private folder, not yet
# in the cache) leaves no field and no description at the outputs; the next run completes the scene.
test_killed_split_bake_leaves_no_partial_scene() {
  mkdir -p "$WORK/lib"
  "$MESHGEN" --gltf-scene "$WORK/lib/s.gltf"
  echo '{"vffLibrary": 1, "defaults": {"count": 2, "map-size": 8}, "entries": [{"mesh": "s.gltf", "split": "mesh"}]}' \
    >"$WORK/lib/library.json"
  cat >"$WORK/held-bake.sh" <<EOS
#!/usr/bin/env bash
"$VFF_BAKE" "\$@" || exit
touch "$WORK/baked"
for i in \$(seq 600); do sleep 0.1; done  # the kill ends this; a bound keeps a lost one finite
EOS
  chmod +x "$WORK/held-bake.sh"
  VFF_BAKE="$WORK/held-bake.sh" "$VFF_LIBRARY" bake "$WORK/lib/library.json" --out "$WORK/fields" -q >/dev/null 2>&1 &
  local pid=$! i
  for i in $(seq 600); do
    [[ -e $WORK/baked ]] && break
    sleep 0.05
  done
  [[ -e $WORK/baked ]] || fail "the held bake never finished"
  [[ -n $(find "$WORK/fields/.vff-cache/tmp" -name 's.mesh0.vff') ]] || fail "the scene is not in the private folder"
  kill -9 $pid
  wait $pid || true
  [[ -z $(find "$WORK/fields" -maxdepth 1 -name 's.*') ]] || fail "a killed split bake left outputs: $(ls "$WORK/fields")"
  [[ -z $(find "$WORK/fields/.vff-cache" -name '*.scene') ]] || fail "a killed split bake entered the cache"
  lib_bake "$WORK/lib/library.json"
  expect_rc 0
  [[ $(json 'len(r["baked"])') == 1 ]] || { show; fail "the next run did not bake the scene"; }
  expect_split_matches_plain_bake mesh s.vffscene.json -n 2 -m 8
  [[ -z $(ls -A "$WORK/fields/.vff-cache/tmp") ]] || fail "the killed run's private folder was not removed"
}

test_split_entry_errors() {
  mkdir -p "$WORK/lib"
  "$MESHGEN" box "$WORK/lib/a.obj"
  "$MESHGEN" --gltf-scene "$WORK/lib/s.gltf"
  echo '{"vffLibrary": 1, "entries": [{"mesh": "s.gltf", "split": "triangles"}]}' >"$WORK/lib/m.json"
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields"
  expect_rc 3
  expect_err "split-value (13011): entries[0].split: must be \"mesh\" or \"node\""
  echo '{"vffLibrary": 1, "entries": [{"mesh": "s.gltf", "split": "mesh", "output": "s.vff"}]}' >"$WORK/lib/m.json"
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields"
  expect_rc 3
  expect_err "split-output (13013): entries[0].output: must name the split entry's scene description (.json), not \"s.vff\""
  # vff-bake refuses --split for a mesh that is not glTF: that entry fails (usage), the other bakes.
  echo '{"vffLibrary": 1, "defaults": {"count": 2, "map-size": 8},
         "entries": [{"mesh": "a.obj", "split": "mesh"}, {"mesh": "s.gltf", "split": "node", "options": {"scene": 5}, "output": "five.json"},
                     {"mesh": "s.gltf", "split": "mesh"}]}' >"$WORK/lib/m.json"
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields" --json "$WORK/report.json"
  expect_rc 1
  expect_err "a.obj: bake-option (13015): entries[0].options: --split applies to a glTF input"
  expect_err "there is no scene 5"
  [[ $(json '[f["exitCode"] for f in r["failed"]]') == "[1, 1]" ]] || { show; fail "both refusals: exit 1"; }
  [[ -s $WORK/fields/s.vffscene.json && ! -e $WORK/fields/a.vffscene.json ]] || fail "outputs: $(ls "$WORK/fields")"
  run "$VFF_LIBRARY" bake "$WORK/lib" --out "$WORK/fields" -- -m 8 --split mesh
  expect_rc 1
  expect_err "--split names a scene description per entry: give it in a manifest"
}

# The conformance vectors are what their generator writes (deterministic), and every rule of
# spec/library.md section 8 has an invalid vector.
VECTORS="$(dirname "$SCHEMA")/conformance/library"
test_vectors_match_their_generator() {
  python3 "$VECTORS/gen_vectors.py" "$WORK/gen"
  python3 "$VECTORS/gen_vectors.py" "$WORK/gen2"
  diff -r "$WORK/gen" "$WORK/gen2" || fail "the generator is not deterministic"
  diff -r -x gen_vectors.py -x README.md -x __pycache__ "$WORK/gen" "$VECTORS" || fail "the committed vectors differ from gen_vectors.py's"
}

test_every_rule_has_a_vector() {
  local ids
  ids=$(grep -oE '^\| 13[0-9]{3} ' "$(dirname "$SCHEMA")/library.md" | tr -d '| ' | sort -u)
  [[ $(echo "$ids" | wc -l) == 15 ]] || fail "spec/library.md lists $(echo "$ids" | wc -l) rules: $ids"
  for id in $ids; do
    ls "$VECTORS/invalid/$id/"*.json >/dev/null 2>&1 || fail "rule $id has no invalid vector"
  done
}

# A value of the wrong JSON type is a manifest error naming its key and entry (exit 3), never an
# internal error; a plan of the wrong types is refused as such too.
test_wrong_types_are_manifest_errors() {
  mkdir -p "$WORK/lib"
  local m
  for m in '{"vffLibrary": "1", "entries": []}|vffLibrary' '{"vffLibrary": 1, "shardMaps": "5", "entries": []}|shardMaps' \
           '{"vffLibrary": 1, "entries": [{"mesh": "a.obj", "output": 5}]}|entries[0].output' \
           '{"vffLibrary": 1, "output": 7, "entries": []}|output' \
           '{"vffLibrary": 1, "entries": [{"mesh": "a.obj", "options": {"normals": "yes"}}]}|entries[0].options.normals'; do
    printf '%s' "${m%|*}" >"$WORK/lib/m.json"
    run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields"
    expect_rc 3
    expect_err "$WORK/lib/m.json: "
    expect_err "): ${m##*|}: must be "
    ! grep -q "internal error" "$WORK/err" || fail "internal error for ${m%|*}"
  done
  echo '{"vffLibraryPlan": 1, "vffBake": "vff-bake", "cache": "c", "entries": [{"task": "0"}]}' >"$WORK/plan.json"
  run "$VFF_LIBRARY" run-shard "$WORK/plan.json" 0
  expect_rc 3
  expect_err "$WORK/plan.json: entries[0].index: not an integer >= 0"
  ! grep -q "internal error" "$WORK/err" || fail "internal error for a plan"
}

# The options after -- are checked once, before any mesh is read: one usage error, not one per entry;
# a range without an upper bound is said readably.
test_folder_options_checked_once() {
  mkdir -p "$WORK/lib"
  local n
  for n in 1 2 3 4; do "$MESHGEN" box "$WORK/lib/m$n.obj"; done
  run "$VFF_LIBRARY" bake "$WORK/lib" --out "$WORK/fields" -- --count 0 -m 8
  expect_rc 1
  [[ $(grep -c "error:" "$WORK/err") == 1 ]] || { show; fail "one error line expected"; }
  expect_err "vff-library: error: bake-option (13015): the options after --: --count: Value 0 is not > 0 (for m1.obj, a mesh input)"
  run "$VFF_LIBRARY" bake "$WORK/lib" --out "$WORK/fields" -- --scene -2
  expect_rc 1
  expect_err "--scene: Value -2 is not >= 0"
  ! grep -qE '[0-9]{40}' "$WORK/err" || fail "a 309-digit range"
  [[ -z $(find "$WORK/fields" -name '*.vff' 2>/dev/null) ]] || fail "a refused run baked"
}

# A dry run names the entries that will fail, with their problem, and exits as the bake does; each
# message names the entry's path once.
test_dry_run_lists_failing_entries() {
  mkdir -p "$WORK/lib"
  "$MESHGEN" box "$WORK/lib/a.obj"
  echo '{"vffLibrary": 1, "defaults": {"count": 2, "map-size": 4},
         "entries": [{"mesh": "a.obj"}, {"mesh": "gone.obj"}, {"mesh": "a.obj", "output": "b.vff", "options": {"gutter": 99}}]}' \
    >"$WORK/lib/m.json"
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields" --dry-run
  expect_rc 4  # exits 2 and 1 differ: 4
  expect_out "# 3 entries: 1 to bake, 0 up to date, 2 failing"
  expect_err "vff-library: error: gone.obj: io-open (1001): No such file or directory (exit 2)"
  expect_err "vff-library: error: a.obj: bake-option (13015): entries[2].options: --gutter: Value 99 not in range 0 to 64 (exit 1)"
  [[ $(grep -o "gone.obj" "$WORK/err" | wc -l) == 1 ]] || { show; fail "the path named more than once"; }
  [[ -z $(find "$WORK/fields" -name '*.vff' 2>/dev/null) ]] || fail "a dry run baked"
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields" --dry-run --format json
  expect_rc 4
  [[ $(python3 -c "import json; print([e['state'] for e in json.load(open('$WORK/out'))['entries']])") == "['bake', 'failed', 'failed']" ]] \
    || { show; fail "states"; }
  lib_bake "$WORK/lib/m.json"
  expect_rc 4
  expect_err "vff-library: 3 entries: 1 baked, 0 up to date, 2 failed"
  [[ $(json '[f["exitCode"] for f in r["failed"]]') == "[2, 1]" ]] || { show; fail "failed entries"; }
  echo '{"vffLibrary": 1, "entries": [{"mesh": "gone.obj"}]}' >"$WORK/lib/one.json"
  lib_bake "$WORK/lib/one.json"
  expect_rc 2
  expect_err "vff-library: 1 entry: 0 baked"
}

# spec/library.md section 6's example: the key text and key of tetra.obj, a mesh written here.
test_key_of_the_spec_example() {
  mkdir -p "$WORK/lib"
  printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n' >"$WORK/lib/tetra.obj"
  local key=0925ee93d25dc507d9804a3bdd1707b4 text
  text='vff-library key 1
baker vff-bake 0.1.0
format 1
source tetra.obj
geometry mesh obj f3dff744aca0d090 3c27cbe67ed21652 0 -1
options {"allowClippedSphere":false,"codec":"stored","directions":"concentric-equal-area","encoding":"unorm8-diameter","grid":"","layout":["2d-array",2048,2048,0],"m":4,"mapsPerBlock":0,"n":2,"normals":true,"positions":"octa-hemi2","scene":-1,"zstdLevel":0}'
  run "$VFF_LIBRARY" key "$WORK/lib/tetra.obj" -- --count 2 --map-size 4 --normals
  expect_rc 0
  [[ $(cat "$WORK/out") == "$text"$'\n'"key $key" ]] || { show; fail "the key text differs from spec/library.md's example"; }
  # The text's XXH3-128 is the key, and the spec shows this very text and key.
  grep -qF "$key" "$(dirname "$SCHEMA")/library.md" || fail "spec/library.md lacks the key"
  grep -qF "$(echo "$text" | tail -1)" "$(dirname "$SCHEMA")/library.md" || fail "spec/library.md lacks the options line"
  # Other spellings, and a manifest of the same bake, give the same key.
  run "$VFF_LIBRARY" key "$WORK/lib/tetra.obj" -- -n 2 -m 4 --normals --codec stored --positions octa-hemi2
  expect_out "key $key"
  echo '{"vffLibrary": 1, "entries": [{"mesh": "tetra.obj", "options": {"count": 2, "map-size": 4, "normals": true}}]}' >"$WORK/lib/m.json"
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields" --dry-run --format json
  expect_rc 0
  [[ $(python3 -c "import json; print(json.load(open('$WORK/out'))['entries'][0]['key'])") == "$key" ]] || { show; fail "the bake's key"; }
  lib_bake "$WORK/lib/m.json"
  [[ -f $WORK/fields/.vff-cache/09/$key.vff ]] || fail "the field is not cached at its key"
}

# --shard-maps applies where neither the manifest nor the entry sets shardMaps; an explicit 0 is never.
test_shard_maps_option_under_the_manifest() {
  local v="$VECTORS/valid/shard-maps.json" states
  run "$VFF_LIBRARY" bake "$v" --out "$WORK/fields" --cache "$WORK/cache" --dry-run --format json --shard-maps 3
  expect_rc 0
  [[ $(python3 -c "import json; print([e['shardMaps'] for e in json.load(open('$WORK/out'))['entries']])") == "[10, 0]" ]] \
    || { show; fail "the manifest's shardMaps"; }
  run "$VFF_LIBRARY" bake "$VECTORS/valid/minimal.json" --out "$WORK/fields" --cache "$WORK/cache" --dry-run --format json --shard-maps 3
  states=$(python3 -c "import json; j=json.load(open('$WORK/out')); print(j['entries'][0]['shardMaps'], j['bakes'])")
  # tetra.obj at the default options: 4226 maps in ranges of 3.
  [[ $states == "3 "* && $(python3 -c "import json; print(len(json.load(open('$WORK/out'))['bakes']))") == 1409 ]] \
    || fail "--shard-maps where the manifest sets none: ${states:0:80}"
}

# Slurm arrays are sized by the work: a small library is one task; --rays-per-task and --tasks
# spread it, the largest bakes first, each to the least loaded task (the plan of a dry run).
test_slurm_plan_sized_by_work() {
  mkdir -p "$WORK/lib"
  "$MESHGEN" box "$WORK/lib/a.obj"
  echo '{"vffLibrary": 1, "defaults": {"count": 2, "map-size": 4},
         "entries": [{"mesh": "a.obj", "output": "a.vff"}, {"mesh": "a.obj", "output": "b.vff", "options": {"map-size": 8}},
                     {"mesh": "a.obj", "output": "c.vff", "options": {"map-size": 5}}, {"mesh": "a.obj", "output": "d.vff", "options": {"map-size": 6}}]}' \
    >"$WORK/lib/m.json"
  plan() { python3 -c "import json; p=json.load(open('$WORK/state/round-0.plan.json')); print(p['tasks'], sorted((e['output'][-5:], e['task']) for e in p['entries']))"; }
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields" --slurm --dry-run --state "$WORK/state"
  expect_rc 0
  expect_out "'--array=0-0'"
  [[ $(plan) == "1 [('a.vff', 0), ('b.vff', 0), ('c.vff', 0), ('d.vff', 0)]" ]] || fail "one task: $(plan)"
  # 26 maps each: 416, 1664, 650 and 936 rays; 3666 in all.
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields" --slurm --dry-run --state "$WORK/state" --rays-per-task 1500
  expect_out "'--array=0-2'"
  [[ $(plan) == "3 [('a.vff', 2), ('b.vff', 0), ('c.vff', 2), ('d.vff', 1)]" ]] || fail "three tasks: $(plan)"
  run "$VFF_LIBRARY" bake "$WORK/lib/m.json" --out "$WORK/fields" --slurm --dry-run --state "$WORK/state" --tasks 9
  expect_out "'--array=0-3'"  # at most one per bake
}

run_test "$1"
