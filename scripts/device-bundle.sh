#!/usr/bin/env bash
# device-bundle.sh — makes OUTDIR, a self-contained folder that runs kdray and its device check on
# another x86-64 Linux machine that has nothing installed but a GPU driver (no package registry):
#   OUTDIR/kdray            launcher: bin/kdray through the bundled loader (scripts/device-bundle-launcher.sh)
#   OUTDIR/bin/kdray        kdray with the small image codec (the build's kdray-small-codec)
#   OUTDIR/lib/             its shared libraries (ldd closure) and ld-linux-x86-64.so.2; of OpenCL,
#                           only the ICD loader: the driver is the machine's
#   OUTDIR/device-check.sh  the device check (scripts/device-check.sh)
#   OUTDIR/scenes/          BART Kitchen and Robots frame 0, dragon res2, the Cornell boxes, the
#                           glass room (testdata/cornell), the hard scenes, a sphere 1e9 from the
#                           origin and needles (scripts/accuracy_scenes.py)
#   OUTDIR/refs/            their hit AOVs and images rendered here by the CPU reference builder
#                           and tracer, which device-check.sh holds the device's output against
# The whole folder stays under 60 MiB (the device machine carries 64 MiB): OpenImageIO's closure
# alone is 337 MiB (522 libraries, measured with ldd on Debian 12), the small codec's a few MiB.
#
# Usage: scripts/device-bundle.sh OUTDIR [--no-scenes] [--build-dir DIR]
#   --no-scenes   only the binary, its libraries and the scripts (no scenes, no references)
#   --build-dir   the build folder whose kdray-small-codec to bundle (default: $KDRAY_BUILD_DIR or
#                 build/; configured Release and built there when missing: a link of kdray's
#                 objects with the small codec)
# Needs: this repository's build dependencies (scripts/install-deps.sh), ../shared/scenes for the
# scenes, python3 for the hard scenes.
set -euo pipefail

root=$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)
out=""
scenes=1
build_dir="$root/${KDRAY_BUILD_DIR:-build}"
while [ $# -gt 0 ]; do
    case "$1" in
    --no-scenes) scenes=0 ;;
    --build-dir) build_dir=$2; shift ;;
    -h | --help) sed -n '2,23p' "$0"; exit 0 ;;
    -*) echo "device-bundle: unknown option $1" >&2; exit 2 ;;
    *) [ -z "$out" ] || { echo "device-bundle: one OUTDIR only" >&2; exit 2; }; out=$1 ;;
    esac
    shift
done
[ -n "$out" ] || { echo "usage: scripts/device-bundle.sh OUTDIR [--no-scenes] [--build-dir DIR]" >&2; exit 2; }
limit_mib=60
shared_scenes="$root/../shared/scenes"

# 1. kdray with the small codec: beside kdray in the build folder (its objects, linked again).
if [ ! -e "$build_dir/CMakeCache.txt" ]; then
    launcher=()
    command -v ccache >/dev/null && launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
    generator=()
    command -v ninja >/dev/null && generator=(-G Ninja)
    export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$root}"
    cmake -S "$root" -B "$build_dir" "${generator[@]}" -DCMAKE_BUILD_TYPE=Release \
        "${launcher[@]}" >/dev/null
fi
binary=kdray-small-codec
grep -q '^KDRAY_IMAGE_CODEC:STRING=small$' "$build_dir/CMakeCache.txt" && binary=kdray
cmake --build "$build_dir" --target "$binary" -j "${KDRAY_BUILD_JOBS:-2}" >/dev/null

# 2. The binary, its ldd closure and the loader. The loader resolves the closure's sonames from
# lib/ alone (--library-path), so every library is copied under the name ldd found it by.
rm -rf "$out"
mkdir -p "$out/bin" "$out/lib"
out=$(cd "$out" && pwd)
cp "$build_dir/$binary" "$out/bin/kdray"
strip "$out/bin/kdray"
ldd "$out/bin/kdray" | while read -r name arrow path _; do
    case "$name" in
    linux-vdso.so.*) continue ;;
    /*) path=$name; name=$(basename "$name") ;;  # the loader: "/lib64/ld-linux-x86-64.so.2 (0x...)"
    *) [ "$arrow" = "=>" ] || continue ;;
    esac
    [ -e "$path" ] || { echo "device-bundle: ldd names $name at $path, which is missing" >&2; exit 1; }
    cp -L "$path" "$out/lib/$name"
done
# glibc's libdl, libpthread and librt (stubs since 2.34): kdray does not link them, but a driver
# may (NVIDIA's libraries do), and one from the machine's older glibc would meet this libc.
libc_dir=$(dirname "$(ldd "$out/bin/kdray" | sed -n 's|.*libc\.so\.6 => \([^ ]*\).*|\1|p')")
for stub in libdl.so.2 libpthread.so.0 librt.so.1; do
    if [ -e "$libc_dir/$stub" ]; then cp -L "$libc_dir/$stub" "$out/lib/$stub"; fi
done
[ -e "$out/lib/ld-linux-x86-64.so.2" ] || { echo "device-bundle: no ld-linux-x86-64.so.2 in ldd's list" >&2; exit 1; }
[ -e "$out/lib/libOpenCL.so.1" ] || { echo "device-bundle: kdray does not link libOpenCL.so.1" >&2; exit 1; }
chmod 755 "$out/lib/ld-linux-x86-64.so.2"
strip --strip-unneeded "$out"/lib/*.so* 2>/dev/null || true
cp "$root/scripts/device-bundle-launcher.sh" "$out/kdray"
cp "$root/scripts/device-check.sh" "$out/device-check.sh"
chmod 755 "$out/kdray" "$out/device-check.sh"
"$out/kdray" --version >/dev/null

# 3. Scenes and the references rendered here by the CPU reference builder and tracer (run with
# this machine's loader and libraries: the same binary).
if [ "$scenes" = 1 ]; then
    if [ ! -d "$shared_scenes" ]; then
        echo "device-bundle: $shared_scenes is missing: no scenes (use --no-scenes)" >&2
        exit 1
    fi
    s="$out/scenes"
    mkdir -p "$s/bart-kitchen" "$s/bart-robots" "$s/dragon" "$s/cornell-box" "$s/glass-room" "$out/refs"
    for scene in bart-kitchen bart-robots; do
        cp "$shared_scenes/$scene/frame_000.obj" "$shared_scenes/$scene/scene.mtl" \
            "$shared_scenes/$scene/render.json" "$s/$scene/"
    done
    cp "$shared_scenes/dragon/dragon_res2.obj" "$shared_scenes/dragon/render.json" "$s/dragon/"
    cp "$shared_scenes/cornell-box/"CornellBox-{Original,Sphere}.{obj,mtl} \
        "$shared_scenes/cornell-box/render.json" "$s/cornell-box/"
    cp "$root/testdata/cornell/"{room.obj,room.mtl,render.json} "$s/glass-room/"
    # The hard scenes: closed meshes around the camera, centre rays through vertices and along
    # edges, at 1e5 from the origin (docs/accuracy.md, robustness): every ray must hit. Beside them the
    # sphere 1e9 from the origin (the scene frame) and needles seen along their length (the
    # refined distance).
    python3 - "$root/scripts" "$s/hard" <<'PY'
import sys
sys.path.insert(0, sys.argv[1])
from accuracy_scenes import write_device_scenes, write_hard_scenes
write_hard_scenes(sys.argv[2], 33)
write_device_scenes(sys.argv[2], 33)
PY
    cp "$root/scripts/device-check-cases.txt" "$out/cases.txt"
    # Each case: name, OBJ and render file (relative to the bundle), size, spp, what to compare.
    tmp=$(mktemp -d)
    trap 'rm -rf "$tmp"' EXIT
    while read -r name obj camera size spp compare; do
        case "$name" in "" | "#"*) continue ;; esac
        args=(render "$out/$obj" --camera "$out/$camera" -o "$tmp/$name" --builder reference
              --tracer reference --quiet --aov --format exr)
        [ "$size" = "-" ] || args+=(--size "$size")
        [ "$spp" = "-" ] || args+=(--spp "$spp")
        # Its warnings (MTL statements not simulated) are the scene's, not the bundle's.
        "$build_dir/kdray" "${args[@]}" >/dev/null 2>"$tmp/$name.err" ||
            { cat "$tmp/$name.err" >&2; echo "device-bundle: the reference render of $name failed" >&2; exit 1; }
        stem=$(basename "$obj" .obj)
        cp "$tmp/$name/$stem.aov.exr" "$out/refs/$name.aov.exr"
        case "$compare" in *image*) cp "$tmp/$name/$stem.exr" "$out/refs/$name.exr" ;; esac
    done <"$out/cases.txt"
fi

# 4. The size limit.
bytes=$(du -sb "$out" | cut -f1)
mib=$(( (bytes + 1048575) / 1048576 ))
echo "device-bundle: $out: $mib MiB ($bytes bytes; limit $limit_mib MiB)"
if [ "$bytes" -ge $(( limit_mib * 1048576 )) ]; then
    echo "device-bundle: the bundle is over $limit_mib MiB" >&2
    du -sh "$out"/* >&2
    exit 1
fi
