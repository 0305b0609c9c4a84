#!/usr/bin/env bash
# Installs kdray's build and test dependencies from Debian 12 packages. Idempotent: packages that
# are already installed are left alone and apt is not even asked. Runs as root, or through sudo.
# Quiet unless it fails: apt's output goes to a log, printed only when apt fails.
#   scripts/install-deps.sh              build + test dependencies
#   scripts/install-deps.sh --build-only only what building and running kdray needs (scripts/demo.sh)
#   scripts/install-deps.sh --peer       also Embree, for the reference peer in ../shared/peers/embree
#   scripts/install-deps.sh --fuzz       also clang and its sanitizer runtimes, for scripts/fuzz.sh
#   scripts/install-deps.sh --slurm      also Slurm and munge (13 MB installed), for the slurm_render test
set -euo pipefail

# Building kdray and running it on the CPU (PoCL); CMake runs Python for the completion.
packages=(
    build-essential cmake pkg-config python3
    pocl-opencl-icd ocl-icd-opencl-dev opencl-clhpp-headers
    libopenimageio-dev
    libtinyobjloader-dev libcli11-dev nlohmann-json3-dev libspdlog-dev
)
test_packages=(
    clinfo openimageio-tools
    libstb-dev libtinyexr-dev  # the small image codec: scripts/device-bundle.sh, its tests
    doctest-dev help2man bash-completion python3-jsonschema
    python3-venv                                         # scripts/compare_mitsuba.py makes a venv for PyPI's mitsuba (the peer for light transport)
    oclgrind                                             # the strict second OpenCL implementation (tests label oclgrind)
    clang-14 llvm-14 libclc-14 libclc-14-dev             # compile the kernels for NVIDIA and AMD targets (gpu_compile test)
)
build_only=0
for option in "$@"; do
    case "$option" in
        --build-only) build_only=1 ;;
        --peer) packages+=(libembree-dev) ;;
        --fuzz) packages+=(clang libclang-rt-dev) ;;
        --slurm) packages+=(slurmctld slurmd slurm-client munge) ;;
        *) echo "install-deps: unknown option $option" >&2; exit 2 ;;
    esac
done

[[ $build_only -eq 1 ]] || packages+=("${test_packages[@]}")
missing=()
for p in "${packages[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [[ ${#missing[@]} -eq 0 ]]; then
    exit 0
fi

sudo=()
if [[ $(id -u) -ne 0 ]]; then
    command -v sudo >/dev/null || { echo "install-deps: run as root or install sudo" >&2; exit 1; }
    sudo=(sudo)
fi
log=$(mktemp "${TMPDIR:-/tmp}/kdray-install-deps.XXXXXX.log")
echo "install-deps: installing ${#missing[@]} Debian package(s): ${missing[*]}" >&2
if ! { "${sudo[@]}" apt-get update -qq &&
       DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends \
           "${missing[@]}"; } >"$log" 2>&1; then
    tail -n 25 "$log" >&2
    echo "install-deps: error: apt-get failed (its whole output: $log)" >&2
    exit 1
fi
rm -f "$log"
