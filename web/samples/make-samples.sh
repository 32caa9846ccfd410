#!/usr/bin/env bash
# make-samples.sh - remakes the viewer's sample fields with vff's own tools:
#   bash web/samples/make-samples.sh BUILD_DIR   (BUILD_DIR: a build with vff-bake and vff-procedural-mesh)
# The outputs do not depend on the machine or the thread count.
set -euo pipefail
build=${1:?usage: make-samples.sh BUILD_DIR}
here=$(cd "$(dirname "$0")" && pwd)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
"$build/samples/vff-procedural-mesh" torus-knot "$tmp/knot.obj"
"$build/samples/vff-procedural-mesh" bowl "$tmp/bowl.obj"
"$build/tools/vff-bake/vff-bake" "$tmp/knot.obj" -o "$here/knot.vff" -n 16 -m 32 --codec zstd
"$build/tools/vff-bake/vff-bake" "$tmp/bowl.obj" -o "$here/bowl.vff" -n 10 -m 24 --codec zstd --normals
