#!/usr/bin/env bash
# The demo: installs the dependencies, builds kdray, and renders the bundled scenes into out/:
# the Cornell-style room (matte, mirror and glass) and a 12-frame animation, with stats.json.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$PWD/build/pocl-cache}
mkdir -p "$POCL_CACHE_DIR"
build/kdray render testdata/cornell/room.obj --camera testdata/cornell/render.json -o out/cornell "$@"
build/kdray render 'testdata/anim/frame_*.obj' --camera testdata/anim/render.json -o out/anim "$@"
echo "demo: images and stats.json in out/cornell and out/anim"
