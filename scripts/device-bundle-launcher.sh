#!/bin/sh
# kdray launcher of a device bundle (scripts/device-bundle.sh copies this file to BUNDLE/kdray):
# runs BUNDLE/bin/kdray through the bundle's own dynamic loader with the bundle's libraries, so it
# needs nothing from the machine but a kernel and an OpenCL driver, and works under `env -i`.
#
# The OpenCL driver is the machine's, never the bundle's (the bundle carries only the ICD loader,
# ocl-icd's libOpenCL.so.1). In order:
#   1. KDRAY_BUNDLE_ICD: an .icd file, a folder of them, or a driver library (a local smoke test
#      with this machine's PoCL: KDRAY_BUNDLE_ICD=/etc/OpenCL/vendors/pocl.icd);
#   2. OCL_ICD_VENDORS, when the caller set it;
#   3. /etc/OpenCL/vendors, when it holds .icd files;
#   4. NVIDIA's libnvidia-opencl.so.1 wherever a driver mount puts it (LD_LIBRARY_PATH's folders,
#      the usual library folders, ldconfig's cache): a vendors folder in TMPDIR names it.
# With none, it says where it looked and exits 1. `--version` and `--help` need no driver.
# KDRAY_BUNDLE_SYSTEM_VENDORS stands for /etc/OpenCL/vendors (tests/device_bundle_smoke.sh).
set -u

here=$(cd "$(dirname "$0")" && pwd)
loader="$here/lib/ld-linux-x86-64.so.2"
libs="$here/lib"
# A program run with `env -i` has no PATH; PoCL runs the system linker through it.
PATH=${PATH:-/usr/local/bin:/usr/bin:/bin}
export PATH

system_vendors=${KDRAY_BUNDLE_SYSTEM_VENDORS:-/etc/OpenCL/vendors}
needs_driver=1
case "${1:-}" in --version | --help | -h | "") needs_driver=0 ;; esac

driver_dirs="${LD_LIBRARY_PATH:-}"
add_driver_dir() { driver_dirs="${driver_dirs:+$driver_dirs:}$1"; }
# The folders where a driver's libraries may be mounted, LD_LIBRARY_PATH's first.
search_nvidia() {
    old_ifs=$IFS
    IFS=:
    for dir in ${LD_LIBRARY_PATH:-} /usr/lib/x86_64-linux-gnu /usr/lib64 /usr/local/nvidia/lib64 \
        /usr/local/nvidia/lib /usr/lib/nvidia /usr/lib64/nvidia /usr/local/cuda/lib64 \
        /usr/local/cuda/compat /usr/lib /lib64 /lib/x86_64-linux-gnu /usr/lib/wsl/lib; do
        [ -n "$dir" ] || continue
        if [ -e "$dir/libnvidia-opencl.so.1" ]; then
            IFS=$old_ifs
            echo "$dir/libnvidia-opencl.so.1"
            return 0
        fi
    done
    IFS=$old_ifs
    if command -v ldconfig >/dev/null 2>&1; then
        found=$(ldconfig -p 2>/dev/null | sed -n 's/.*libnvidia-opencl\.so\.1 .*=> //p' | head -n 1)
        if [ -n "$found" ] && [ -e "$found" ]; then
            echo "$found"
            return 0
        fi
    fi
    return 1
}

# A vendors folder whose one .icd names $1. Its place is fixed per user and the file replaced
# whole, so that the launcher can exec kdray (a signal, a timeout's, reaches kdray itself) and
# leaves no folder per run behind.
make_vendors() {
    vendors="${TMPDIR:-/tmp}/kdray-bundle-vendors.$(id -u 2>/dev/null || echo 0)"
    mkdir -p "$vendors" || exit 1
    echo "$1" >"$vendors/.kdray-bundle.icd.$$" && mv -f "$vendors/.kdray-bundle.icd.$$" "$vendors/kdray-bundle.icd" || exit 1
    OCL_ICD_VENDORS="$vendors"
    OPENCL_VENDOR_PATH="$vendors"
    export OCL_ICD_VENDORS OPENCL_VENDOR_PATH
}

if [ -n "${KDRAY_BUNDLE_ICD:-}" ]; then
    if [ -d "$KDRAY_BUNDLE_ICD" ]; then
        OCL_ICD_VENDORS="$KDRAY_BUNDLE_ICD"
        OPENCL_VENDOR_PATH="$KDRAY_BUNDLE_ICD"
        export OCL_ICD_VENDORS OPENCL_VENDOR_PATH
    elif [ -f "$KDRAY_BUNDLE_ICD" ]; then
        case "$KDRAY_BUNDLE_ICD" in
        *.icd) make_vendors "$(cat "$KDRAY_BUNDLE_ICD")" ;;
        *) make_vendors "$KDRAY_BUNDLE_ICD" ;;
        esac
    else
        echo "kdray-bundle: KDRAY_BUNDLE_ICD=$KDRAY_BUNDLE_ICD is no .icd file, folder or library" >&2
        exit 1
    fi
elif [ -n "${OCL_ICD_VENDORS:-}" ]; then
    :
elif ls "$system_vendors"/*.icd >/dev/null 2>&1; then
    # An .icd naming libnvidia-opencl.so.1 without a folder resolves through the folders below.
    if nvidia=$(search_nvidia); then add_driver_dir "$(dirname "$nvidia")"; fi
else
    if nvidia=$(search_nvidia); then
        make_vendors "$nvidia"
        add_driver_dir "$(dirname "$nvidia")"
    elif [ "$needs_driver" = 1 ]; then
        echo "kdray-bundle: no OpenCL driver found (looked in $system_vendors/*.icd," \
            "for libnvidia-opencl.so.1 in LD_LIBRARY_PATH, /usr/lib/x86_64-linux-gnu, /usr/lib64," \
            "/usr/local/nvidia/lib64, /usr/local/nvidia/lib, /usr/lib/nvidia, /usr/lib64/nvidia," \
            "/usr/local/cuda/lib64, /usr/local/cuda/compat, /usr/lib, /lib64," \
            "/lib/x86_64-linux-gnu, /usr/lib/wsl/lib and ldconfig -p); set KDRAY_BUNDLE_ICD to" \
            "an .icd file or a driver library" >&2
        exit 1
    fi
fi

# The bundle's libraries first, then the driver's folder (its own dependencies, libcuda.so.1).
exec "$loader" --library-path "$libs${driver_dirs:+:$driver_dirs}" "$here/bin/kdray" "$@"
