#!/usr/bin/env bash
# device_bundle_smoke (CTest, label "bundle"): scripts/device-bundle.sh makes a bundle in a
# temporary folder, which must stay under 60 MiB and run with an empty environment (`env -i`)
# through this machine's PoCL: --version, a tiny render, the driver search (libnvidia-opencl.so.1
# in LD_LIBRARY_PATH, here a link to PoCL), the message when no driver is found, and, when
# ../shared/scenes exists, scripts/device-check.sh --quick end to end in under 5 minutes.
# Usage: tests/device_bundle_smoke.sh SOURCE_DIR WORK_DIR BUILD_DIR
set -euo pipefail
src=$1
work=$2
build=$3
rm -rf "$work"
mkdir -p "$work"
fail() { echo "device_bundle_smoke: $*" >&2; exit 1; }

scenes=()
[ -d "$src/../shared/scenes" ] || { scenes=(--no-scenes); echo "device_bundle_smoke: ../shared is absent: no scene parts"; }
# The bundle's kdray is the build's kdray-small-codec, linked with the rest of the build.
"$src/scripts/device-bundle.sh" "$work/bundle" --build-dir "$build" "${scenes[@]}"
b="$work/bundle"
bytes=$(du -sb "$b" | cut -f1)
[ "$bytes" -lt $((60 * 1048576)) ] || fail "the bundle is $bytes bytes, over 60 MiB"

version=$(env -i "$b/kdray" --version)
case "$version" in *"image codec: small"*) ;; *) fail "--version says '$version'" ;; esac

icd=/etc/OpenCL/vendors/pocl.icd
[ -e "$icd" ] || fail "no PoCL ($icd): the OpenCL tests need it (scripts/install-deps.sh)"
pocl_cache=${POCL_CACHE_DIR:-$work/pocl-cache}
pocl=(env -i "KDRAY_BUNDLE_ICD=$icd" "POCL_CACHE_DIR=$pocl_cache")
"${pocl[@]}" "$b/kdray" render "$src/testdata/cornell/room.obj" \
    --camera "$src/testdata/cornell/render.json" --size 64x48 -o "$work/tiny" --quiet --aov
[ -s "$work/tiny/room.png" ] && [ -s "$work/tiny/room.aov.exr" ] || fail "the tiny render wrote no image"

# The driver found by its file name where a driver mount puts it, without /etc/OpenCL/vendors.
mkdir -p "$work/driver"
ln -s "$(ldconfig -p | sed -n 's/.*libpocl\.so\.2 .*=> //p' | head -n 1)" "$work/driver/libnvidia-opencl.so.1"
env -i KDRAY_BUNDLE_SYSTEM_VENDORS=/nonexistent "LD_LIBRARY_PATH=$work/driver" \
    "POCL_CACHE_DIR=$pocl_cache" "$b/kdray" stats --json >"$work/devices.json"
grep -q '"devices"' "$work/devices.json" || fail "no device listed through the searched driver"
# No driver at all: a clear message and exit status 1.
if env -i KDRAY_BUNDLE_SYSTEM_VENDORS=/nonexistent "$b/kdray" stats 2>"$work/none.err"; then
    fail "ran without an OpenCL driver"
fi
grep -q "kdray-bundle: no OpenCL driver found (looked in" "$work/none.err" || fail "no message: $(cat "$work/none.err")"

if [ ${#scenes[@]} = 0 ]; then
    start=$(date +%s)
    "${pocl[@]}" "OUT=$work/check" "$b/device-check.sh" --quick || fail "device-check.sh failed: $(cat "$work/check/summary.json")"
    seconds=$(( $(date +%s) - start ))
    echo "device_bundle_smoke: device-check.sh --quick took $seconds s on PoCL"
    [ "$seconds" -lt 300 ] || fail "device-check.sh --quick took $seconds s, over 5 minutes"
    grep -q '"failures": 0' "$work/check/summary.json" || fail "failures in summary.json"
    # The report docs/bench-gpu is made from such a folder: every build and correctness case the
    # check wrote gets its row.
    python3 "$src/scripts/device_report.py" "$work/check" --commit test --out "$work/report" \
        >/dev/null || fail "device_report.py failed on the check's output"
    builds=$(ls "$work/check/bench"/build-*.json | wc -l)
    rows=$(python3 -c "import json, sys; r = json.load(open(sys.argv[1])); print(len(r['builds']), len(r['correctness']), all(c['agree'] for c in r['correctness']))" "$work/report.json")
    [ "$rows" = "$builds $(ls "$work/check/correctness"/*.json | grep -vc '\.stats\.json$') True" ] ||
        fail "device_report.py: rows '$rows' for $builds builds"
fi
echo "device_bundle_smoke: bundle of $bytes bytes passed"
