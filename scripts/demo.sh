#!/usr/bin/env bash
# The demo: installs what building kdray needs (not the test tools), builds the kdray binary
# only, and renders the bundled scenes into out/: the Cornell-style room (matte, mirror and
# glass, 16 samples per pixel) and a 12-frame animation, each with its stats.json.
#   scripts/demo.sh [extra kdray render options, for both renders]
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh --build-only
build_dir=${KDRAY_BUILD_DIR:-build}
# Tests off unless this folder is already configured with them (scripts/test.sh turns them on).
tests=()
[[ -f "$build_dir/CMakeCache.txt" ]] || tests=(-DKDRAY_BUILD_TESTS=OFF)
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release "${tests[@]}" >/dev/null
echo "demo: building kdray in $build_dir/ (a few minutes the first time)" >&2
if ! cmake --build "$build_dir" --target kdray -j "$(nproc)" >"$build_dir/demo-build.log" 2>&1; then
    tail -n 30 "$build_dir/demo-build.log" >&2
    echo "demo: error: the build failed (its whole output: $build_dir/demo-build.log)" >&2
    exit 1
fi
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$PWD/$build_dir/pocl-cache}
mkdir -p "$POCL_CACHE_DIR"
"$build_dir/kdray" render testdata/cornell/room.obj --render-file testdata/cornell/render.json \
    --spp 16 -o out/cornell "$@"
"$build_dir/kdray" render 'testdata/anim/frame_*.obj' --render-file testdata/anim/render.json \
    -o out/anim "$@"
echo "demo: out/cornell/room.png and out/anim/frame_000.png ... frame_011.png, each folder" \
     "with its stats.json (kdray stats out/anim)"
