#!/usr/bin/env bash
# ctest case fuzz.js_differential: differential.mjs (the JavaScript decoder against libvff) on the
# conformance vectors and a fixed set of their mutants, with the checksums verified (verify-all,
# lazy; without them the two zstd decoders differ on damaged frames: ../README.md). Without node or
# web/node_modules it prints SKIP and the reason and exits 77 (ctest: skipped).
#   differential.sh HELPER SOURCE_DIR [MUTANTS]
set -u
helper="$1" src="$2" mutants="${3:-24}"
command -v node >/dev/null || { echo "SKIP: node is not installed (scripts/setup.sh installs nodejs)"; exit 77; }
[[ -d $src/web/node_modules/fzstd && -d $src/web/node_modules/hash-wasm ]] ||
  { echo "SKIP: no $src/web/node_modules: run scripts/setup.sh (npm ci in web/)"; exit 77; }
exec node "$src/tests/fuzz/js/differential.mjs" --helper "$helper" --policies verify-all,lazy \
  --mutants "$mutants" --seed 1 \
  "$src/spec/conformance/valid" "$src/spec/conformance/invalid"
