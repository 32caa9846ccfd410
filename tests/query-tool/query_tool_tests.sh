#!/usr/bin/env bash
# query_tool_tests.sh - vff-query against libvff's one-ray answers (vff_query_reference), and its
# diagnostics. Every function named test_* is one ctest case (tests/query-tool/CMakeLists.txt).
#   VFF_QUERY   the vff-query executable
#   REFERENCE   vff_query_reference (reference.cpp): rays, and the one-ray answers as vff-query's CSV
#   VECTORS     spec/conformance/valid
#   WORK        a scratch folder of this test (emptied first)
set -euo pipefail
: "${VFF_QUERY:?}" "${REFERENCE:?}" "${VECTORS:?}" "${WORK:?}"

source "$(dirname "${BASH_SOURCE[0]}")/../common/cli_harness.sh"
query() { run "$VFF_QUERY" "$@"; }
# Fields of every distance encoding, with and without normals.
FIELDS=(u8d-zstd-normals-meta u8c-stored-normals-3d-gutter1 u16d-zstd-normals-gutter2 bit1-stored bc4-zstd-normals-slices)
# same A B: files A and B are identical.
same() { cmp -s "$1" "$2" || { diff "$1" "$2" | head -20 >&2; fail "$1 and $2 differ"; }; }
# has_numpy: python3 with numpy is there (scripts/setup.sh installs it).
has_numpy() { /usr/bin/python3 -c 'import numpy' 2>/dev/null; }

test_help() {
  query --help
  expect_rc 0
  for opt in --ray --input --output --format --interpolated --visibility --tmin --tmax --rotate --translate --scale \
    --threads --checksums --no-sites --columns --ray-origin --refined "Exit codes:" "3  invalid input file"; do expect_out "$opt"; done
}

# Nearest answers, split over threads in batches, equal the one-ray calls on every encoding.
test_nearest_equals_one_ray() {
  for f in "${FIELDS[@]}"; do
    "$REFERENCE" rays "$VECTORS/$f.vff" 600 7 >"$WORK/rays.csv"
    "$REFERENCE" answer "$VECTORS/$f.vff" "$WORK/rays.csv" --visibility >"$WORK/want.csv"
    query "$VECTORS/$f.vff" -i "$WORK/rays.csv" -o "$WORK/got.csv" --visibility -j 3
    expect_rc 0
    same "$WORK/want.csv" "$WORK/got.csv"
    grep -q '^1,' "$WORK/got.csv" || fail "$f: no ray hit"
    grep -q '^0,' "$WORK/got.csv" || fail "$f: every ray hit"
  done
}

test_interpolated_equals_one_ray() {
  for f in "${FIELDS[@]}"; do
    "$REFERENCE" rays "$VECTORS/$f.vff" 400 11 >"$WORK/rays.csv"
    "$REFERENCE" answer "$VECTORS/$f.vff" "$WORK/rays.csv" --interpolated --visibility >"$WORK/want.csv"
    query "$VECTORS/$f.vff" -i "$WORK/rays.csv" --interpolated --visibility -j 2
    expect_rc 0
    same "$WORK/want.csv" "$WORK/out"
  done
}

# --refined answers as the one-ray kRefined calls on the refined vectors (some rays take the exact
# step: the answers differ from nearest's), and is refused where it cannot apply.
test_refined_equals_one_ray() {
  for f in u8d-refined u8c-zstd-normals-meta-refined; do
    "$REFERENCE" rays "$VECTORS/$f.vff" 600 13 >"$WORK/rays.csv"
    "$REFERENCE" answer "$VECTORS/$f.vff" "$WORK/rays.csv" --refined --visibility >"$WORK/want.csv"
    "$REFERENCE" answer "$VECTORS/$f.vff" "$WORK/rays.csv" --visibility >"$WORK/nearest.csv"
    query "$VECTORS/$f.vff" -i "$WORK/rays.csv" -o "$WORK/got.csv" --refined --visibility -j 3
    expect_rc 0
    same "$WORK/want.csv" "$WORK/got.csv"
    ! cmp -s "$WORK/got.csv" "$WORK/nearest.csv" || fail "$f: --refined answered every ray as nearest does"
  done
  query "$VECTORS/u8d-zstd-normals-meta.vff" --ray 0 0 5 0 0 -1 --refined
  expect_rc 1
  expect_err "--refined needs a refined field (vff-bake --refine); $VECTORS/u8d-zstd-normals-meta.vff has no REFN section"
  query "$VECTORS/u8d-refined.vff" --ray 0 0 5 0 0 -1 --refined --interpolated
  expect_rc 1
  expect_err "excludes"
}

# Rays that start off the object (--ray-origin off-object, spec/geometry.md 7.4), nearest and
# interpolated, equal the one-ray calls; the reference's rays start inside the sphere too, and some
# of them answer otherwise than on the object.
test_off_object_equals_one_ray() {
  for f in u8d-zstd-normals-meta u16d-zstd-normals-gutter2 bc4-zstd-normals-slices; do
    "$REFERENCE" rays "$VECTORS/$f.vff" 600 5 >"$WORK/rays.csv"
    for interp in "" --interpolated; do
      "$REFERENCE" answer "$VECTORS/$f.vff" "$WORK/rays.csv" --off-object $interp --visibility >"$WORK/want.csv"
      query "$VECTORS/$f.vff" -i "$WORK/rays.csv" -o "$WORK/got.csv" --ray-origin off-object $interp --visibility -j 2
      expect_rc 0
      same "$WORK/want.csv" "$WORK/got.csv"
      query "$VECTORS/$f.vff" -i "$WORK/rays.csv" -o "$WORK/on.csv" $interp --visibility
      cmp -s "$WORK/got.csv" "$WORK/on.csv" && fail "$f: off-object rays answered as on-object ones"
    done
  done
  query "$VECTORS/u8d-zstd-normals-meta.vff" --ray 0 0 0 1 0 0 --ray-origin floor
  expect_rc 1
  expect_err "--ray-origin"
}

# An instance transform: rays in world space, answered as Instance's one-ray calls.
test_instance_equals_one_ray() {
  local f="$VECTORS/u8d-zstd-normals-meta.vff" place=(--rotate 0 1 0.5 0.7 --translate 2 -1 0.5 --scale 1.5)
  # Rays about the moved sphere: made around the field's own sphere, then moved by the same transform
  # by vff-query itself would be circular; the reference's rays are near enough to the moved sphere.
  "$REFERENCE" rays "$f" 500 3 >"$WORK/rays.csv"
  "$REFERENCE" answer "$f" "$WORK/rays.csv" "${place[@]}" >"$WORK/want.csv"
  query "$f" -i "$WORK/rays.csv" "${place[@]}"
  expect_rc 0
  same "$WORK/want.csv" "$WORK/out"
  grep -q '^1,' "$WORK/out" || fail "no ray hit the moved field"
}

# The same rays as --ray, CSV, JSON lines and .npy give the same answers.
test_input_spellings_agree() {
  local f="$VECTORS/u8d-zstd-normals-meta.vff"
  query "$f" --ray 0.5 -1 5 0 0 -1 --ray 0.5 -1 5 0 0.5 -1 --ray 9 9 9 1 0 0
  expect_rc 0
  cp "$WORK/out" "$WORK/want.csv"
  [[ $(sed -n 2p "$WORK/want.csv") == 1,2.31* ]] || { show; fail "the first ray does not hit at t 2.31"; }
  printf 'ox,oy,oz,dx,dy,dz\n# a comment\n0.5 -1 5 0 0 -1\n\n0.5,-1,5,0,0.5,-1\n+9,9,9,1,0,0\n' >"$WORK/rays.csv"
  query "$f" <"$WORK/rays.csv"
  expect_rc 0
  same "$WORK/want.csv" "$WORK/out"
  printf '{"origin":[0.5,-1,5],"direction":[0,0,-1]}\n[0.5,-1,5,0,0.5,-1,0,1e30]\n{"origin":[9,9,9],"direction":[1,0,0],"tmax":3}\n' \
    >"$WORK/rays.jsonl"
  query "$f" -i "$WORK/rays.jsonl"
  expect_rc 0
  same "$WORK/want.csv" "$WORK/out"
  query "$f" -i "$WORK/rays.jsonl" --format jsonl
  expect_rc 0
  expect_out '{"hit":true,"t":2.31000018,"point":[0.5,-1,2.68999982],"normal":['
  expect_out_re '"inside":false,"sample":[0-9]+,"texel":\[[0-9]+,[0-9]+\]}'
  expect_out '{"hit":false,"t":null,"point":null,"normal":null,"inside":false,"sample":null,"texel":null}'
  # tmax before the surface: a miss.
  query "$f" --ray 0.5 -1 5 0 0 -1 --tmax 2
  expect_rc 0
  [[ $(sed -n 2p "$WORK/out") == 0,inf* ]] || { show; fail "--tmax 2 still hits"; }
}

test_npy_in_and_out() {
  has_numpy || { echo "SKIP: python3 with numpy is not installed (scripts/setup.sh installs python3-numpy)"; return 0; }
  local f="$VECTORS/u16d-zstd-normals-gutter2.vff"
  "$REFERENCE" rays "$f" 300 5 >"$WORK/rays.csv"
  /usr/bin/python3 -c "import numpy as np; np.save('$WORK/rays.npy', np.loadtxt('$WORK/rays.csv', delimiter=',', dtype=np.float32))"
  query "$f" -i "$WORK/rays.csv" --visibility
  expect_rc 0
  cp "$WORK/out" "$WORK/want.csv"
  query "$f" -i "$WORK/rays.npy" -o "$WORK/hits.npy" --visibility
  expect_rc 0
  expect_no_out
  /usr/bin/python3 - "$WORK/hits.npy" "$WORK/want.csv" <<'PY' || fail ".npy answers differ from the CSV ones"
import sys, numpy as np
got = np.load(sys.argv[1])
want = np.genfromtxt(sys.argv[2], delimiter=',', names=True)
assert got.dtype == np.float32 and got.shape == (300, 13), (got.dtype, got.shape)
assert want.dtype.names[9:] == ("sample", "i", "j", "visibility"), want.dtype.names
for i, name in enumerate(want.dtype.names):
    assert np.array_equal(got[:, i], want[name].astype(np.float32), equal_nan=True), name
PY
  # Standard input takes .npy too.
  query "$f" --format npy --visibility <"$WORK/rays.npy"
  expect_rc 0
  cmp -s "$WORK/out" "$WORK/hits.npy" || fail ".npy from standard input differs"
}

# The columns sample, i, j: -1 for a ray that makes no lookup (it misses the sphere), a map and a
# texel inside the field otherwise; --no-sites leaves them out of every format.
test_sites_and_no_sites() {
  local f="$VECTORS/u8d-zstd-normals-meta.vff"
  query "$f" --ray 0.5 -1 5 0 0 -1 --ray 9 9 9 1 0 0
  expect_rc 0
  [[ $(sed -n 1p "$WORK/out") == hit,t,x,y,z,nx,ny,nz,inside,sample,i,j ]] || { show; fail "CSV header"; }
  [[ $(sed -n 3p "$WORK/out") == *,0,-1,-1,-1 ]] || { show; fail "a ray missing the sphere has a site"; }
  local maps res
  maps=$("$REFERENCE" describe "$f" | cut -d' ' -f1)
  res=$("$REFERENCE" describe "$f" | cut -d' ' -f2)
  IFS=, read -r -a row < <(sed -n 2p "$WORK/out")
  ((row[9] >= 0 && row[9] < maps && row[10] >= 0 && row[10] < res && row[11] >= 0 && row[11] < res)) ||
    fail "site ${row[9]} (${row[10]}, ${row[11]}) outside $maps maps of $res x $res"
  query "$f" --ray 0.5 -1 5 0 0 -1 --ray 9 9 9 1 0 0 --no-sites --visibility
  expect_rc 0
  [[ $(sed -n 1p "$WORK/out") == hit,t,x,y,z,nx,ny,nz,inside,visibility ]] || { show; fail "--no-sites CSV header"; }
  [[ $(sed -n 3p "$WORK/out") == 0,inf,nan,nan,nan,nan,nan,nan,0,1 ]] || { show; fail "--no-sites row"; }
  query "$f" --ray 9 9 9 1 0 0 --no-sites --format jsonl
  expect_rc 0
  expect_out '{"hit":false,"t":null,"point":null,"normal":null,"inside":false}'
  # No rays at all: the header names the same columns.
  printf '# nothing\n' >"$WORK/none.csv"
  query "$f" -i "$WORK/none.csv" --visibility
  expect_rc 0
  [[ $(cat "$WORK/out") == hit,t,x,y,z,nx,ny,nz,inside,sample,i,j,visibility ]] || { show; fail "empty input's header"; }
  query "$f" -i "$WORK/none.csv" --no-sites
  expect_rc 0
  [[ $(cat "$WORK/out") == hit,t,x,y,z,nx,ny,nz,inside ]] || { show; fail "empty input's --no-sites header"; }
  query "$f" --ray 9 9 9 1 0 0 --no-sites -o "$WORK/h.npy"
  expect_rc 0
  if has_numpy; then
    /usr/bin/python3 -c "import numpy as np; a = np.load('$WORK/h.npy'); assert a.shape == (1, 9), a.shape" ||
      fail "--no-sites .npy shape"
  fi
}

# --columns: the columns named, in that order, with the values of the same columns of the default
# answer, in CSV and .npy; the visibility and the sites computed only when named.
test_columns_pick_and_order() {
  local f="$VECTORS/u8d-zstd-normals-meta.vff"
  "$REFERENCE" rays "$f" 200 3 >"$WORK/rays.csv"
  query "$f" -i "$WORK/rays.csv" --visibility
  expect_rc 0
  cp "$WORK/out" "$WORK/all.csv"
  query "$f" -i "$WORK/rays.csv" --columns visibility,j,t,hit
  expect_rc 0
  [[ $(sed -n 1p "$WORK/out") == visibility,j,t,hit ]] || { show; fail "--columns CSV header"; }
  # hit,t,...,j,visibility are columns 1, 2, 12 and 13 of the full answer.
  same "$WORK/out" <(cut -d, -f13,12,2,1 --output-delimiter=, "$WORK/all.csv" | awk -F, -v OFS=, '{print $4, $3, $2, $1}')
  [[ $(awk -F, 'NR > 1 && $4 == 1' "$WORK/out" | wc -l) -gt 10 ]] || fail "the rays hit too rarely to tell"
  if has_numpy; then
    /usr/bin/python3 -c "import numpy as np; np.save('$WORK/rays.npy', np.loadtxt('$WORK/rays.csv', delimiter=',', dtype=np.float32))"
    query "$f" -i "$WORK/rays.npy" -o "$WORK/all.npy" --visibility
    expect_rc 0
    query "$f" -i "$WORK/rays.npy" -o "$WORK/some.npy" --columns t,sample,nz
    expect_rc 0
    /usr/bin/python3 -c "
import numpy as np
a, s = np.load('$WORK/all.npy'), np.load('$WORK/some.npy')
assert s.shape == (200, 3), s.shape
assert np.array_equal(s, a[:, [1, 9, 7]], equal_nan=True)" || fail "--columns .npy differs from the full answer's columns"
  fi
  query "$f" --ray 0 0 5 0 0 -1 --columns t,speed
  expect_rc 1
  expect_err 'unknown column "speed"'
  query "$f" --ray 0 0 5 0 0 -1 --columns t,t
  expect_rc 1
  expect_err 'column "t" named twice'
  query "$f" --ray 0 0 5 0 0 -1 --columns t --no-sites
  expect_rc 1
  query "$f" --ray 0 0 5 0 0 -1 --columns t --format jsonl
  expect_rc 1
  expect_err "--columns applies to csv and npy"
}

# --checksums: all (the default) refuses a field whose bytes do not match their checksum; none
# answers from it anyway.
test_checksums_policy() {
  local f="$WORK/corrupt.vff"
  cp "$VECTORS/u8c-stored-normals-3d-gutter1.vff" "$f"
  printf '\x5a' | dd of="$f" bs=1 seek=18000 conv=notrunc 2>/dev/null
  query "$f" --ray 0.5 -1 5 0 0 -1
  expect_rc 3
  expect_err "section-checksum (4008)"
  query "$f" --ray 0.5 -1 5 0 0 -1 --checksums lazy
  expect_rc 3
  query "$f" --ray 0.5 -1 5 0 0 -1 --checksums none
  expect_rc 0
  [[ $(sed -n 2p "$WORK/out") == 1,* ]] || { show; fail "--checksums none: no hit"; }
  query "$f" --ray 0.5 -1 5 0 0 -1 --checksums some
  expect_rc 1
}

# A bad row past the first chunk of a large .npy is named by its index, and no output appears; the
# rows written chunk by chunk do not depend on the thread count.
test_npy_bad_row_in_a_later_chunk() {
  has_numpy || { echo "SKIP: python3 with numpy is not installed"; return 0; }
  local f="$VECTORS/u8d-zstd-normals-meta.vff"
  /usr/bin/python3 -c "
import numpy as np
r = np.tile(np.array([[0.5, -1, 5, 0, 0, -1]], np.float32), (40000, 1))
np.save('$WORK/ok.npy', r)
r[33333, 4] = np.nan
np.save('$WORK/bad.npy', r)"
  query "$f" -i "$WORK/ok.npy" -o "$WORK/ok-hits.npy" -j 3
  expect_rc 0
  /usr/bin/python3 -c "
import numpy as np
a = np.load('$WORK/ok-hits.npy')
assert a.shape == (40000, 12) and (a == a[0]).all() and a[0, 0] == 1, a[:2]" || fail "40000 equal rays, unequal answers"
  # Random rays over many chunks: the same bytes on one thread as on four.
  /usr/bin/python3 -c "
import numpy as np
rng = np.random.default_rng(3)
o = rng.uniform(-3, 3, (50000, 3)); d = rng.uniform(0.5, 1.5, (50000, 3)) * np.array([0.5, -1, 2]) - o
np.save('$WORK/random.npy', np.hstack([o, d]).astype(np.float32))"
  query "$f" -i "$WORK/random.npy" -o "$WORK/j1.npy" -j 1 --visibility --interpolated
  expect_rc 0
  query "$f" -i "$WORK/random.npy" -o "$WORK/j4.npy" -j 4 --visibility --interpolated
  expect_rc 0
  cmp -s "$WORK/j1.npy" "$WORK/j4.npy" || fail "the .npy answers depend on the thread count"
  /usr/bin/python3 -c "
import numpy as np
a = np.load('$WORK/j1.npy')
assert a.shape == (50000, 13) and 1000 < a[:, 0].sum() < 49000, a[:, 0].sum()" || fail "the random rays do not hit and miss"
  query "$f" -i "$WORK/bad.npy" -o "$WORK/bad-hits.npy" -j 3
  expect_rc 3
  expect_err "$WORK/bad.npy: row 33333, column 4: "
  [[ ! -e $WORK/bad-hits.npy ]] || fail "an output was written for a bad .npy"
  compgen -G "$WORK/bad-hits.npy.tmp-*" >/dev/null && fail "a temporary file was left behind"
  return 0
}

test_bad_lines_name_line_and_column() {
  local f="$VECTORS/u8d-zstd-normals-meta.vff"
  printf '0.5,-1,5,0,0,-1\n# note\n9,9,9,1,0,0\n0.5,-1,5,0,zero,-1\n0.5,-1,5,0,0,-1\n' >"$WORK/in"
  query "$f" <"$WORK/in"
  expect_rc 3
  expect_err "vff-query: error: <stdin>:4:12: expected a number, found \"zero\""
  [[ $(wc -l <"$WORK/out") -eq 3 ]] || { show; fail "the two rays before the bad line are not answered"; }
  printf '1,2,3,4,5\n' >"$WORK/short.csv"
  query "$f" -i "$WORK/short.csv"
  expect_rc 3
  expect_err "$WORK/short.csv:1:10: found 5 numbers: a ray has 6"
  printf '1,2,3,0,0,0\n' >"$WORK/in"
  query "$f" <"$WORK/in"
  expect_rc 3
  expect_err "<stdin>:1:7: the direction is zero"
  printf '0,0,9,0,0,-1\n{"origin":[1,2],"direction":[0,0,1]}\n' >"$WORK/in"
  query "$f" <"$WORK/in"
  expect_rc 3
  expect_err "<stdin>:2:1: origin must be an array of 3 numbers"
  printf '{"origin":[1,2,3],\n' >"$WORK/in"
  query "$f" <"$WORK/in"
  expect_rc 3
  expect_err_re '<stdin>:1:[0-9]+: invalid JSON'
  printf '[1e400,0,0,0,0,1]\n' >"$WORK/in"
  query "$f" <"$WORK/in"
  expect_rc 3
  expect_err "<stdin>:1:1: invalid JSON: a number is beyond the binary64 range"
}

# Text input that is not quite text: a UTF-8 byte order mark is skipped (the rays answer as
# without it); a NUL byte is named by line and column; bytes outside printable ASCII are shown as
# \xHH, never raw; a JSON ray with an unknown key is refused.
test_text_input_edges() {
  local f="$VECTORS/u8d-zstd-normals-meta.vff"
  printf '0.5,-1,5,0,0,-1\n9,9,9,1,0,0\n' >"$WORK/plain.csv"
  printf '\xEF\xBB\xBF0.5,-1,5,0,0,-1\n9,9,9,1,0,0\n' >"$WORK/bom.csv"
  query "$f" -i "$WORK/plain.csv" -o "$WORK/plain.out"
  expect_rc 0
  query "$f" -i "$WORK/bom.csv" -o "$WORK/bom.out"
  expect_rc 0
  same "$WORK/plain.out" "$WORK/bom.out"
  printf '0.5,-1,5,0,0,-1\n1,2\0003,4,5,6\n' >"$WORK/nul.csv"
  query "$f" -i "$WORK/nul.csv" -o "$WORK/nul.out"
  expect_rc 3
  expect_err "$WORK/nul.csv:2:4: a NUL byte: the input is not text"
  # (as for every bad text line, the rays before it are answered: README "Errors")
  [[ $(wc -l <"$WORK/nul.out") -eq 2 ]] || fail "the ray before the NUL line is not answered"
  printf '0,0,\x01\xff,0,0,-1\n' >"$WORK/in"
  query "$f" <"$WORK/in"
  expect_rc 3
  expect_err 'expected a number, found "\x01\xFF"'
  LC_ALL=C grep -q $'\xff' "$WORK/err" && fail "a raw byte 0xFF in the message"
  printf '{"origin":[0,0,5],"direction":[0,0,-1],"tmaxx":3}\n' >"$WORK/in"
  query "$f" <"$WORK/in"
  expect_rc 3
  expect_err '<stdin>:1:1: unknown key "tmaxx"'
}

# A .npy header must be the dict numpy writes: a syntax error or another key is refused.
test_npy_header_is_strict() {
  has_numpy || { echo "SKIP: python3 with numpy is not installed"; return 0; }
  local f="$VECTORS/u8d-zstd-normals-meta.vff"
  /usr/bin/python3 - "$WORK" <<'PY'
import struct, sys
import numpy as np
work = sys.argv[1]
np.save(work + "/ok.npy", np.array([[0.5, -1, 5, 0, 0, -1]], np.float32))
raw = open(work + "/ok.npy", "rb").read()
n = struct.unpack("<H", raw[8:10])[0]
for name, text in [("nobrace", "{'descr': '<f4', 'fortran_order': False, 'shape': (1, 6) "),
                   ("extra", "{'descr': '<f4', 'fortran_order': False, 'shape': (1, 6), 'x': 1}"),
                   ("twice", "{'descr': '<f4', 'descr': '<f4', 'fortran_order': False, 'shape': (1, 6)}"),
                   ("bel", "{'descr': '<f\x07', 'fortran_order': False, 'shape': (1, 6)}")]:
    open(work + "/" + name + ".npy", "wb").write(raw[:10] + (text.ljust(n - 1) + "\n").encode() + raw[10 + n:])
PY
  query "$f" -i "$WORK/ok.npy"
  expect_rc 0
  query "$f" -i "$WORK/nobrace.npy"
  expect_rc 3
  expect_err "$WORK/nobrace.npy: the .npy header is not a dict literal"
  query "$f" -i "$WORK/extra.npy"
  expect_rc 3
  expect_err "has a key other than 'descr', 'fortran_order' and 'shape'"
  query "$f" -i "$WORK/twice.npy"
  expect_rc 3
  expect_err "names 'descr' twice"
  # A header value is shown as the ray lines show bytes: never raw control characters.
  query "$f" -i "$WORK/bel.npy"
  expect_rc 3
  expect_err "expected dtype float32 ('<f4'), found '<f\\x07'"
  if grep -q $'\a' "$WORK/err"; then fail "a raw BEL reached the message"; fi
}

test_bad_npy_names_expected() {
  has_numpy || { echo "SKIP: python3 with numpy is not installed"; return 0; }
  local f="$VECTORS/u8d-zstd-normals-meta.vff"
  /usr/bin/python3 -c "import numpy as np; np.save('$WORK/f8.npy', np.zeros((4, 6))); np.save('$WORK/n5.npy', np.zeros((4, 5), np.float32)); np.save('$WORK/f.npy', np.zeros((4, 6), np.float32)); np.save('$WORK/fo.npy', np.asfortranarray(np.ones((4, 6), np.float32)))"
  query "$f" -i "$WORK/f8.npy"
  expect_rc 3
  expect_err "vff-query: error: $WORK/f8.npy: expected dtype float32 ('<f4'), found '<f8'"
  query "$f" -i "$WORK/n5.npy"
  expect_rc 3
  expect_err "expected shape (N, 6) or (N, 8), found (4, 5)"
  query "$f" -i "$WORK/f.npy"
  expect_rc 3
  expect_err "row 0, column 3: the direction is zero"
  query "$f" -i "$WORK/fo.npy"
  expect_rc 3
  expect_err "expected a C-order array"
}

test_errors_and_exit_codes() {
  query "$WORK/none.vff" --ray 0 0 5 0 0 -1
  expect_rc 2
  expect_err "vff-query: error: $WORK/none.vff"
  printf 'not a field' >"$WORK/bad.vff"
  query "$WORK/bad.vff" --ray 0 0 5 0 0 -1
  expect_rc 3
  expect_err "vff-query: error: $WORK/bad.vff"
  query "$VECTORS/bit1-stored.vff" --ray 0 0 5 0 0
  expect_rc 1
  query "$VECTORS/bit1-stored.vff" --ray 0 0 5 0 0 0
  expect_rc 1
  expect_err "--ray number 1: the direction is zero"
  query "$VECTORS/bit1-stored.vff" --ray 0 0 5 0 0 -1 -i "$WORK/x.csv"
  expect_rc 1
  query "$VECTORS/bit1-stored.vff" --ray 0 0 5 0 0 -1 --tmin nan
  expect_rc 1
  expect_err "--tmin is not a number (nan)"
  query "$VECTORS/bit1-stored.vff" --ray 0 0 5 0 0 -1 --tmax nan
  expect_rc 1
  expect_err "--tmax is not a number (nan)"
  query "$VECTORS/bit1-stored.vff" -i "$WORK/none.csv"
  expect_rc 2
  expect_err "$WORK/none.csv"
  query "$VECTORS/bit1-stored.vff" --ray 0 0 5 0 0 -1 -o "$WORK/no/such/dir/out.csv"
  expect_rc 2
  # A folder where a file is expected: the field, and the rays.
  mkdir -p "$WORK/folder.vff"
  query "$WORK/folder.vff" --ray 0 0 5 0 0 -1
  expect_rc 2
  expect_err "vff-query: error: $WORK/folder.vff: io-open (1001): not a regular file"
  query "$VECTORS/bit1-stored.vff" -i "$WORK/folder.vff"
  expect_rc 2
  expect_err "vff-query: error: $WORK/folder.vff: io-read (1002): Is a directory"
  # An empty field file is not a field (nothing is read past its end).
  : >"$WORK/empty.vff"
  query "$WORK/empty.vff" --ray 0 0 5 0 0 -1
  expect_rc 3
  expect_err "vff-query: error: $WORK/empty.vff"
}

run_test "$1"
