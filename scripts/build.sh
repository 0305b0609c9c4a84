#!/usr/bin/env bash
# Installs the dependencies (scripts/install-deps.sh) and builds kdray in build/ (Release).
#   scripts/build.sh [extra cmake -D options]
set -euo pipefail
cd "$(dirname "$0")/.."
peer=()
[[ -d ../shared/peers/embree ]] && peer=(--peer)  # the Embree peer, for the comparison tests
scripts/install-deps.sh "${peer[@]}"
build_dir=${KDRAY_BUILD_DIR:-build}
# Tests on: scripts/demo.sh may have configured this folder without them.
cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=Release -DKDRAY_BUILD_TESTS=ON "$@" >/dev/null
cmake --build "$build_dir" -j "$(nproc)"
