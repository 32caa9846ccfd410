#!/usr/bin/env bash
# vff-experiments end to end at a tiny size: images and tables written, exit codes, determinism.
# Usage: run.sh EXPERIMENTS MESHGEN CASE
set -uo pipefail
exp="$1"; meshgen="$2"; case="$3"
work="$(mktemp -d)"
trap 'rm -rf "$work"' EXIT
cd "$work"
fail() { echo "FAIL: $*"; exit 1; }
"$meshgen" torus-knot knot.obj || fail "mesh generator"
small=(--mesh knot.obj --size 40 --config 1090x16x16)

case "$case" in
  ao_writes_images_and_table)
    "$exp" ao "${small[@]}" --rays 16 -o out >stdout.txt 2>stderr.txt || { cat stderr.txt; fail "ao failed"; }
    for f in ao-exact.png ao-exact.exr ao-table.md; do [ -s "out/$f" ] || { ls out; fail "missing out/$f"; }; done
    ls out | grep -q 'error.*\.png\|heat.*\.png' || { ls out; fail "no error heat map"; }
    grep -q '1090x16x16 | nearest' stdout.txt || { cat stdout.txt; fail "table lacks the nearest row"; }
    grep -q '1090x16x16 | interpolated' stdout.txt || fail "table lacks the interpolated row"
    if command -v exrheader >/dev/null; then exrheader out/ao-exact.exr >/dev/null || fail "exrheader rejects the EXR"; fi
    # The contact region's error beside the whole image's, and one pass per AO range.
    grep -q '| RMS contact | RMS outside |' stdout.txt || { cat stdout.txt; fail "table lacks the contact columns"; }
    "$exp" ao "${small[@]}" --rays 16 --ao-ranges 0.5 2 -o ranges >stdout.txt 2>stderr.txt || { cat stderr.txt; fail "ao --ao-ranges failed"; }
    for f in ao-r0.5-exact.png ao-r2-exact.png ao-r0.5-1090x16x16-nearest.png; do [ -s "ranges/$f" ] || { ls ranges; fail "missing ranges/$f"; }; done
    grep -q '1090x16x16 @ 0.5 R | nearest' stdout.txt || { cat stdout.txt; fail "table lacks the 0.5 R row"; }
    grep -q 'exact (Embree, [0-9]* triangles) @ 2 R' stdout.txt || { cat stdout.txt; fail "table lacks the 2 R reference"; }
    ;;
  every_experiment_runs)
    for e in intra-ao shadows reflections; do
      "$exp" "$e" "${small[@]}" --rays 4 -o out >stdout.txt 2>stderr.txt || { cat stderr.txt; fail "$e failed"; }
      [ -s "out/$e-table.md" ] || { ls out; fail "missing out/$e-table.md"; }
    done
    "$exp" bench --mesh knot.obj --config 1090x16x16 --bench-rays 20000 --repeat 1 -j 2 >stdout.txt 2>stderr.txt \
      || { cat stderr.txt; fail "bench failed"; }
    grep -q "Embree rtcOccluded1" stdout.txt || { cat stdout.txt; fail "bench prints no baseline"; }
    # The figures name the machine they came from: the CPU ends the header line.
    cpu=$(sed -n 's/^Query benchmark: .* rays per batch call, //p' stdout.txt)
    [ -n "$cpu" ] || { head -1 stdout.txt; fail "bench header names no CPU"; }
    if [ -r /proc/cpuinfo ]; then
      model=$(sed -n 's/^model name[[:space:]]*: *//p' /proc/cpuinfo | head -1)
      case "$cpu" in "$model"*) ;; *) fail "bench names the CPU '$cpu', /proc/cpuinfo '$model'" ;; esac
    fi
    # Calls of 333 rays (groups and lookup vectors cut anywhere): the same occluded and agreement
    # figures as calls of 4096 (tests/unit/test_fast_lookup.cpp compares the answers ray by ray).
    "$exp" bench --mesh knot.obj --config 1090x16x16 --bench-rays 20000 --repeat 1 --batch 333 >small.txt 2>stderr.txt \
      || { cat stderr.txt; fail "bench --batch 333 failed"; }
    grep -q "333 rays per batch call" small.txt || { cat small.txt; fail "bench does not print its batch size"; }
    # figures FILE ROWS: ray set, occluded and agreement of the rows matching the regex ROWS, in order.
    figures() { grep -E "$2" "$1" | awk -F'|' '{print $2, $6, $7}'; }
    [ "$(figures stdout.txt '\((b|d)\) field' | wc -l)" -eq 4 ] || { cat stdout.txt; fail "bench lacks the (b) and (d) rows"; }
    [ "$(figures stdout.txt '\((b|d)\) field')" = "$(figures small.txt '\((b|d)\) field')" ] \
      || { cat stdout.txt small.txt; fail "batch answers depend on the call size"; }
    # (e) takes the world-space rays to object space in the kernel, with the operations the bench
    # used to make (b)'s rays: the same occluded and agreement figures.
    [ "$(figures stdout.txt '\(e\) instance' | wc -l)" -eq 2 ] || { cat stdout.txt; fail "bench lacks the (e) rows"; }
    [ "$(figures stdout.txt '\(e\) instance')" = "$(figures stdout.txt '\(b\) field')" ] \
      || { cat stdout.txt; fail "instance batches answer otherwise than the field's"; }
    # With two threads, (a) and (b) again on one thread: the same answers.
    [ "$(figures stdout.txt '\(b1\) field' | wc -l)" -eq 2 ] || { cat stdout.txt; fail "bench lacks the one-thread (b1) rows"; }
    [ "$(figures stdout.txt '\(b1\) field')" = "$(figures stdout.txt '\(b\) field')" ] \
      || { cat stdout.txt; fail "one-thread batches answer otherwise"; }
    grep -q '(a1) Embree rtcOccluded1, 1 thread' stdout.txt || { cat stdout.txt; fail "bench lacks the one-thread baseline"; }
    ;;
  scene_bench_prints_a_row_per_count)
    "$exp" scene-bench --mesh knot.obj --config 290x16x16 --instances 1 7 40 --scene-rays 3000 --frames 1 -j 2 \
      >stdout.txt 2>stderr.txt || { cat stderr.txt; fail "scene-bench failed"; }
    grep -q "^Scene benchmark: .* threads, " stdout.txt || { cat stdout.txt; fail "scene-bench header names no CPU"; }
    sed -n '/^| instances | (a)/,/^$/p' stdout.txt >first.txt  # the first table: time per frame
    [ "$(grep -cE '^\| [0-9]+ \|' first.txt)" -eq 3 ] || { cat stdout.txt; fail "scene-bench: not one row per count"; }
    for n in 1 7 40; do grep -qE "^\| $n \|" first.txt || { cat stdout.txt; fail "scene-bench: no row for $n"; }; done
    # The hybrid (c) answers every ray as vff::Scene (b) does: its column "(c) = (b)" is 1.
    [ "$(awk -F'|' '/^\| [0-9]+ \|/ {print $12}' first.txt | tr -d ' ' | sort -u)" = "1.0000" ] \
      || { cat stdout.txt; fail "scene-bench: the hybrid answers otherwise than vff::Scene"; }
    # (b)'s floor (the field's batch on (b)'s pairs, found beforehand) answers as (b) does, and
    # the summary says what finding the pairs costs.
    [ "$(awk -F'|' '/^\| [0-9]+ \|/ {print $15}' first.txt | tr -d ' ' | sort -u)" = "1.0000" ] \
      || { cat stdout.txt; fail "scene-bench: the pairs found beforehand answer otherwise than vff::Scene"; }
    grep -q "^1 instance: finding and preparing the pairs takes " stdout.txt \
      || { cat stdout.txt; fail "scene-bench: no line on what finding the pairs costs"; }
    # The ray forms: per count and ray set, three forms and vff::Scene; the hybrid with ray sources
    # answers every ray as vff::Scene's *From calls do, in every form.
    sed -n '/^| instances | rays | form |/,/^$/p' stdout.txt >forms.txt
    [ "$(grep -cE '^\| [0-9]+ \| (random|tiles) \|' forms.txt)" -eq 24 ] || { cat stdout.txt; fail "scene-bench: not 4 rows a count and set"; }
    [ "$(awk -F'|' '/\| (single|packets of 16|stream) \|/ {print $9}' forms.txt | tr -d ' ' | sort -u)" = "1.0000" ] \
      || { cat stdout.txt; fail "scene-bench: the hybrid with sources answers otherwise than vff::Scene"; }
    awk -F'|' '/packets of 16/ {exit !($8 + 0 >= 1)}' forms.txt || { cat forms.txt; fail "scene-bench: no rays a callback"; }
    sed -n '/^| instances | rays | vff::Scene speed-up/,/^$/p' stdout.txt >twopass.txt
    [ "$(grep -cE '^\| [0-9]+ \| (random|tiles) \|' twopass.txt)" -eq 6 ] || { cat stdout.txt; fail "scene-bench: no two-pass rows"; }
    ;;
  scene_writes_frames_and_table)
    "$exp" scene --mesh knot.obj --config 290x16x16 --size 48 --rays 8 --frames 2 -j 2 -o out >stdout.txt 2>stderr.txt \
      || { cat stderr.txt; fail "scene failed"; }
    grep -q "^Scene: 5 objects" stdout.txt || { cat stdout.txt; fail "scene: not five objects"; }
    for f in 0 1; do for k in exact fields error; do
      [ -s "out/scene-f$f-$k.png" ] || { ls out; fail "missing out/scene-f$f-$k.png"; }
    done; done
    [ "$(grep -cE '^\| [0-9]+ \|' out/scene-table.md)" -eq 2 ] || { cat out/scene-table.md; fail "scene: not one row per frame"; }
    # The distance fields' rows and images, one per frame.
    [ "$(grep -cE '^\| [0-9]+, distance fields \|' out/scene-table.md)" -eq 2 ] \
      || { cat out/scene-table.md; fail "scene: not one distance-field row per frame"; }
    for f in 0 1; do [ -s "out/scene-f$f-sdf.png" ] && [ -s "out/scene-f$f-sdf-error.png" ] || { ls out; fail "scene: no distance-field image"; }; done
    # The fields answer most AO rays as the exact trace: RMS well under 32 on the 8-bit scale.
    awk -F'|' '/^\| [0-9]+ \|/ { if ($3 + 0 >= 32) bad = 1 } END { exit bad }' out/scene-table.md \
      || { cat out/scene-table.md; fail "scene: RMS error too large"; }
    ;;
  sdf_rows_beside_the_fields)
    # Every image experiment renders the distance field at each field's memory: its rows (trace and,
    # but for reflections, cone), its images and error maps; never more memory than the field's.
    for e in ao intra-ao shadows reflections; do
      "$exp" "$e" "${small[@]}" --rays 4 -o out >stdout.txt 2>stderr.txt || { cat stderr.txt; fail "$e failed"; }
      modes="sphere trace cone"; [ "$e" = reflections ] && modes="sphere trace"
      for m in "sphere trace" cone; do
        n=$(grep -c "^| distance field, 1090x16x16's memory .* | $m |" stdout.txt)
        case " $modes " in *" $m "*) want=1 ;; *) want=0 ;; esac
        [ "$n" -eq "$want" ] || { cat stdout.txt; fail "$e: $n '$m' rows, expected $want"; }
      done
      [ -s "out/$e-sdf-1090x16x16-trace.png" ] && [ -s "out/$e-sdf-1090x16x16-trace-error.png" ] \
        || { ls out; fail "$e: missing the distance field's image or error map"; }
      field=$(awk -F'|' '$2 ~ /^ 1090x16x16 $/ {print $4; exit}' stdout.txt)
      awk -F'|' -v f="$field" '$2 ~ /distance field/ { if ($4 + 0 > f + 0 || $4 + 0 < 0.8 * f) bad = 1 } END { exit bad }' stdout.txt \
        || { cat stdout.txt; fail "$e: the distance field's memory is not the field's ($field MiB)"; }
    done
    # The distance field's RMS is a real error: its ao image differs from the exact one.
    awk -F'|' '$2 ~ /distance field/ && $3 ~ /sphere trace/ { if ($5 + 0 <= 0 || $5 + 0 >= 40) bad = 1 } END { exit bad }' stdout.txt \
      || { cat stdout.txt; fail "an implausible RMS for the distance field"; }
    "$exp" ao "${small[@]}" --rays 4 --no-sdf -o none >stdout.txt 2>stderr.txt || { cat stderr.txt; fail "ao --no-sdf failed"; }
    ! grep -q "^| distance field" stdout.txt || { cat stdout.txt; fail "--no-sdf still renders the distance field"; }
    ! ls none | grep -q sdf || { ls none; fail "--no-sdf still writes the distance field's images"; }
    ;;
  sdf_bench_prints_three_way_rows)
    # Field, distance field and Embree on the same rays: a row per mesh, configuration and ray set.
    "$meshgen" bowl bowl.obj || fail "mesh generator"
    "$exp" sdf-bench --mesh knot.obj --object bowl.obj --config 290x16x16 --bench-rays 5000 --repeat 1 -j 2 \
      >stdout.txt 2>stderr.txt || { cat stderr.txt; fail "sdf-bench failed"; }
    grep -q "^Distance-field benchmark: .* $(sed -n 's/^model name[[:space:]]*: *//p' /proc/cpuinfo | head -1)" stdout.txt \
      || { head -1 stdout.txt; fail "sdf-bench header names no CPU"; }
    [ "$(grep -cE '^\| (knot|bowl)\.obj \| 290x16x16 \|' stdout.txt)" -eq 4 ] || { cat stdout.txt; fail "sdf-bench: not four rows"; }
    # Every rate positive; the share of wrong answers a percentage under 50 for both.
    awk -F'|' '/^\| (knot|bowl)\.obj/ && NF == 13 { if ($7 + 0 <= 0 || $8 + 0 <= 0 || $9 + 0 <= 0 || $11 + 0 >= 50 || $12 + 0 >= 50) bad = 1 }
               END { exit bad }' stdout.txt || { cat stdout.txt; fail "sdf-bench: implausible figures"; }
    ;;
  sdf_bench_refined_rows_fit_and_are_right_more_often)
    # The refined field's table: a row per main row; its parts (maps, unsure bits, exact step) fit
    # the distance field's memory, and it is wrong less often than the plain field of the main table.
    "$exp" sdf-bench --mesh knot.obj --config 4226x16x16 --bench-rays 5000 --repeat 1 -j 2 \
      >stdout.txt 2>stderr.txt || { cat stderr.txt; fail "sdf-bench failed"; }
    grep -q "^| mesh | memory MiB | ray set | refined field | maps + unsure bits + exact step MiB |" stdout.txt \
      || { cat stdout.txt; fail "no refined table"; }
    awk -F'|' '
      function n(x) { gsub(/[ %x]/, "", x); return x + 0 }
      /^\| knot\.obj/ && NF == 13 { fw[$6] = n($11); ++main }
      /^\| knot\.obj/ && NF == 14 { ++rows; split($6, p, "+")
        if (n(p[1]) + n(p[2]) + n(p[3]) > n($3) + 0.01 || n($7) <= 0 || n($7) >= 100 || n($8) <= 0 || n($10) <= 0) bad = 1
        if (n($11) >= fw[$4] || fw[$4] <= 0) bad = 1 }
      END { exit bad || main != 2 || rows != 2 }' stdout.txt || { cat stdout.txt; fail "the refined rows do not fit or are not right more often"; }
    ;;
  sdf_bench_unsure_splits_the_wrong_answers)
    # --unsure: a second table, a row per main row; the field's wrong answers on the unsure rays and
    # on the rest add up to its wrong answers of the main table, and the SDF's agree with it.
    "$exp" sdf-bench --mesh knot.obj --config 290x16x16 --bench-rays 5000 --repeat 1 -j 2 --unsure \
      >stdout.txt 2>stderr.txt || { cat stderr.txt; fail "sdf-bench --unsure failed"; }
    grep -q "^| mesh | field | memory MiB | ray set | unsure rays | field wrong, of the unsure |" stdout.txt \
      || { cat stdout.txt; fail "no table of unsure rays"; }
    awk -F'|' '
      function n(x) { gsub(/[ %]/, "", x); return x + 0 }
      /^\| knot\.obj/ && NF == 13 { fw[$6] = n($11); sw[$6] = n($12); ++main }
      /^\| knot\.obj/ && NF == 12 { u = n($6); split_ = u * n($7) / 100 + n($9); ++rows
        if (u <= 0 || u >= 100 || n($11) <= 0) bad = 1
        if (split_ - fw[$5] > 0.02 || fw[$5] - split_ > 0.02 || n($10) != sw[$5]) bad = 1 }
      END { exit bad || main != 2 || rows != 2 }' stdout.txt || { cat stdout.txt; fail "the unsure table does not add up to the main one"; }
    ;;
  small_fields_leave_out_the_distance_field)
    # A field under kSdfMinBudget (sdf_field.h) has no distance field beside it: the image
    # experiments and `scene` leave the distance-field rows out with a note and finish; scene-bench
    # has none; sdf-bench, all of whose rows compare the two, refuses with a usage error.
    tiny=(--mesh knot.obj --config 10x4x4 -j 2)
    "$exp" ao "${tiny[@]}" --size 16 --rays 2 -o ao >stdout.txt 2>stderr.txt || { cat stderr.txt; fail "ao on a tiny field failed"; }
    grep -q "note: no distance-field rows for 10x4x4: its 160 bytes are under the 4096" stderr.txt \
      || { cat stderr.txt; fail "ao: no note about the distance field"; }
    ! grep -q "^| distance field" stdout.txt || { cat stdout.txt; fail "ao: a distance-field row for a tiny field"; }
    "$exp" scene "${tiny[@]}" --size 16 --rays 2 --frames 1 -o sc >stdout.txt 2>stderr.txt \
      || { cat stderr.txt; fail "scene on tiny fields failed"; }
    grep -q "scene: note: no distance-field rows: .* has 160 bytes, under the 4096" stderr.txt \
      || { cat stderr.txt; fail "scene: no note about the distance fields"; }
    [ "$(grep -cE '^\| 0 \|' sc/scene-table.md)" -eq 1 ] || { cat sc/scene-table.md; fail "scene: no row for the frame"; }
    ! grep -q "distance fields" sc/scene-table.md || { cat sc/scene-table.md; fail "scene: distance-field rows"; }
    [ ! -e sc/scene-f0-sdf.png ] || fail "scene: a distance-field image for tiny fields"
    "$exp" scene-bench "${tiny[@]}" --instances 1 3 --scene-rays 300 --frames 1 >stdout.txt 2>stderr.txt \
      || { cat stderr.txt; fail "scene-bench on tiny fields failed"; }
    [ "$(sed -n '/^| instances | (a)/,/^$/p' stdout.txt | grep -cE '^\| [0-9]+ \|')" -eq 2 ] || { cat stdout.txt; fail "scene-bench: not one row per count"; }
    "$exp" sdf-bench "${tiny[@]}" --bench-rays 2000 --repeat 1 >stdout.txt 2>stderr.txt
    rc=$?
    [ "$rc" -eq 1 ] || { cat stderr.txt; fail "sdf-bench on a tiny field: exit $rc, expected 1 (usage)"; }
    grep -q "vff-experiments: error: sdf-bench: knot.obj 10x4x4: the field's 160 bytes are under the 4096 a distance grid needs" \
      stderr.txt || { cat stderr.txt; fail "sdf-bench: the error names no minimum"; }
    ;;
  images_do_not_depend_on_threads)
    "$exp" ao "${small[@]}" --rays 8 -j 1 -o one >/dev/null 2>&1 || fail "ao -j 1 failed"
    "$exp" ao "${small[@]}" --rays 8 -j 2 -o two >/dev/null 2>&1 || fail "ao -j 2 failed"
    for f in one/*.png one/*.exr; do cmp "$f" "two/${f#one/}" || fail "$f differs between 1 and 2 threads"; done
    ;;
  bad_input_exit_codes)
    "$exp" ao --mesh nothere.obj -o out >stdout.txt 2>stderr.txt; rc=$?
    [ "$rc" -eq 2 ] || fail "missing mesh exited $rc, expected 2"
    grep -q nothere.obj stderr.txt || fail "message does not name the mesh"
    "$exp" ao --mesh knot.obj --config 1000x16x16 -o out >/dev/null 2>&1; rc=$?
    [ "$rc" -eq 1 ] || fail "bad --config exited $rc, expected 1"
    "$exp" nosuch >/dev/null 2>&1; rc=$?
    [ "$rc" -eq 1 ] || fail "unknown experiment exited $rc, expected 1"
    ;;
  help_requires_one_experiment)
    # The positional and --experiment are one option: help must not mark both required.
    "$exp" --help >help.txt 2>&1 || fail "--help failed"
    ! grep -q REQUIRED help.txt || { cat help.txt; fail "--help marks an option REQUIRED"; }
    grep -q "required: as the positional or --experiment" help.txt || { cat help.txt; fail "--help does not say one is required"; }
    "$exp" >stdout.txt 2>stderr.txt; rc=$?
    [ "$rc" -eq 1 ] || fail "no experiment exited $rc, expected 1"
    grep -q "an experiment is required" stderr.txt || { cat stderr.txt; fail "no experiment: unclear message"; }
    "$exp" --experiment nosuch >/dev/null 2>&1; rc=$?
    [ "$rc" -eq 1 ] || fail "--experiment nosuch exited $rc, expected 1"
    "$exp" --experiment bench --field x.vff >/dev/null 2>stderr.txt; rc=$?
    [ "$rc" -eq 1 ] && grep -q "not to bench" stderr.txt || fail "--experiment bench is not read as the experiment"
    ;;
  *) fail "unknown case $case" ;;
esac
echo "PASS: $case"
