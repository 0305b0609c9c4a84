#!/usr/bin/env bash
# The test command: installs the dependencies, builds, and runs every test with CTest.
# OpenCL tests run on whatever device OpenCL offers (PoCL on a CPU-only machine); they never skip.
# Tests that need ../shared (the real scenes and the Embree peer) skip when it is absent.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/build.sh "$@"
build_dir=${KDRAY_BUILD_DIR:-build}
# PoCL caches compiled kernels; keep that cache somewhere writable even when $HOME is not.
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$PWD/$build_dir/pocl-cache}
mkdir -p "$POCL_CACHE_DIR"
ctest --test-dir "$build_dir" --output-on-failure -j "$(nproc)"
