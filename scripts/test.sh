#!/usr/bin/env bash
# The test command: installs the dependencies, builds, and runs every test with CTest.
# OpenCL tests run on whatever device OpenCL offers (PoCL on a CPU-only machine); they never skip.
# Tests that need ../shared (the real scenes and the Embree peer) skip when it is absent.
#
#   scripts/test.sh              Release build in build/, every test
#   scripts/test.sh --sanitize   ASan + UBSan build in build-asan/, the unit and CLI tests (the
#                                Embree comparisons, the accuracy sweep and the device bundle,
#                                whose kdray is a Release build anyway, the checks of docs,
#                                packaging and scripts, the GPU-target compile check (clang, not
#                                kdray), and the Oclgrind runs, whose simulator does not load into
#                                a sanitized process, are left to the first)
set -euo pipefail
cd "$(dirname "$0")/.."
exclude=()
# Slurm and munge for the slurm_render test (about 15 s to install), so that it runs, not skips.
scripts/install-deps.sh --slurm
if [[ "${1:-}" == "--sanitize" ]]; then
    shift
    export KDRAY_BUILD_DIR=${KDRAY_BUILD_DIR:-build-asan}
    # -O1 -g1: line tables for the reports, at a fraction of a full debug build's compile time.
    scripts/build.sh -DKDRAY_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo \
        -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g1" "$@"
    exclude=(-E "embree_agreement|accuracy_vs_time|device_bundle_smoke|docs_figures|readme|install|render_file_schema|slurm_render|oclgrind|gpu_compile|rooms")
    # Two tests at a time, as the Release run. The sanitizer run once went one at a time: with a
    # cold PoCL kernel cache LeakSanitizer's exit-time tracer crashed (SIGSEGV) in 3 of 4 runs.
    # It runs after the Release run, whose kernels fill the shared cache below, and warm it has
    # not crashed (3 whole runs and 8 runs of the longest CLI tests, two at a time); the one
    # failure those runs did show was the buffer ledger's race, since fixed. One at a time the
    # run took 243 s; two at a time, 128 s. On a cold cache (the sanitizer
    # run on its own, first) it still goes one at a time.
    jobs=$(nproc)
    sanitize=1
else
    scripts/build.sh "$@"
    jobs=$(nproc)
fi
build_dir=${KDRAY_BUILD_DIR:-build}
# PoCL caches compiled kernels; keep that cache somewhere writable even when $HOME is not. Both
# builds share one: their kernels are the same sources for the same device, so the sanitizer run
# after the Release run (CI) compiles nothing again (cold, its tests took 405 s here; warm, 261 s).
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$PWD/build/pocl-cache}
mkdir -p "$POCL_CACHE_DIR"
[[ ${sanitize:-0} -eq 1 && -z "$(ls -A "$POCL_CACHE_DIR")" ]] && jobs=1
ctest --test-dir "$build_dir" --output-on-failure -j "$jobs" "${exclude[@]}"
