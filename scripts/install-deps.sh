#!/usr/bin/env bash
# Installs kdray's build and test dependencies from Debian 12 packages. Idempotent: packages that
# are already installed are left alone and apt is not even asked. Runs as root, or through sudo.
#   scripts/install-deps.sh            build + test dependencies
#   scripts/install-deps.sh --peer     also Embree, for the reference peer in ../shared/peers/embree
#   scripts/install-deps.sh --fuzz     also clang and its sanitizer runtimes, for scripts/fuzz.sh
#   scripts/install-deps.sh --slurm    also Slurm and munge (13 MB installed), for the slurm_render test
set -euo pipefail

packages=(
    build-essential cmake pkg-config python3
    pocl-opencl-icd ocl-icd-opencl-dev opencl-clhpp-headers clinfo
    libopenimageio-dev openimageio-tools
    libstb-dev libtinyexr-dev  # the small image codec: scripts/device-bundle.sh, its tests
    libtinyobjloader-dev libcli11-dev nlohmann-json3-dev doctest-dev libspdlog-dev
    help2man bash-completion python3-jsonschema
    python3-venv                                         # scripts/compare_mitsuba.py makes a venv for PyPI's mitsuba (the peer for light transport)
    oclgrind                                             # the strict second OpenCL implementation (tests label oclgrind)
    clang-14 llvm-14 libclc-14 libclc-14-dev             # compile the kernels for NVIDIA and AMD targets (gpu_compile test)
)
for option in "$@"; do
    case "$option" in
        --peer) packages+=(libembree-dev) ;;
        --fuzz) packages+=(clang libclang-rt-dev) ;;
        --slurm) packages+=(slurmctld slurmd slurm-client munge) ;;
        *) echo "install-deps: unknown option $option" >&2; exit 2 ;;
    esac
done

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
echo "install-deps: installing ${missing[*]}" >&2
"${sudo[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${sudo[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}" >&2
