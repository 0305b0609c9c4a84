#!/usr/bin/env bash
# check_same_output.sh — proves that a change altered nothing a user sees: the kdray of BASE_REV
# and the kdray of the working tree build the same trees (tree files byte for byte, OpenCL and
# reference builders) and render the same images and hit AOVs (byte for byte) on testdata and on
# every scene of ../shared/scenes, and write stats.json files that differ only in timings.
#
#   scripts/check_same_output.sh BASE_REV [--quick]
#
# BASE_REV is built in a git worktree under build-same/ (reused when it is already at that
# commit); the working tree's binary is build/kdray, built by scripts/build.sh when missing.
# --quick: testdata and one frame of each shared animation only. Exit 0 when everything is the
# same, 1 with one line per difference otherwise.
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
base_rev=${1:?usage: scripts/check_same_output.sh BASE_REV [--quick]}
quick=0
[[ "${2:-}" == "--quick" ]] && quick=1

base_commit=$(git rev-parse --verify "$base_rev^{commit}")
work=$root/build-same
base_tree=$work/base-src
mkdir -p "$work"
if [[ ! -d $base_tree ]] || [[ "$(git -C "$base_tree" rev-parse HEAD 2>/dev/null)" != "$base_commit" ]]; then
    rm -rf "$base_tree"
    git worktree prune
    git worktree add --detach "$base_tree" "$base_commit" >/dev/null
fi
cmake -S "$base_tree" -B "$work/base-build" -DCMAKE_BUILD_TYPE=Release -DKDRAY_BUILD_TESTS=OFF >/dev/null
cmake --build "$work/base-build" -j "$(nproc)" --target kdray >/dev/null
[[ -x build/kdray ]] || scripts/build.sh >/dev/null
cmake --build build -j "$(nproc)" --target kdray >/dev/null
base_bin=$work/base-build/kdray
head_bin=$root/build/kdray
export POCL_CACHE_DIR=${POCL_CACHE_DIR:-$root/build/pocl-cache}
mkdir -p "$POCL_CACHE_DIR"

# Each case: a name, the render file ('' for none) and the inputs. Renders run both sides with
# --aov; builds compare the tree file of each builder for the first input.
cases=()
add_case() { cases+=("$1"$'\t'"$2"$'\t'"$3"); }
add_case cornell testdata/cornell/render.json testdata/cornell/room.obj
add_case anim testdata/anim/render.json "$(ls testdata/anim/frame_*.obj | tr '\n' ' ')"
shared=$root/../shared/scenes
if [[ -d $shared ]]; then
    for dir in "$shared"/*/; do
        name=$(basename "$dir")
        [[ -f $dir/render.json ]] || continue
        objs=$(ls "$dir"*.obj 2>/dev/null | tr '\n' ' ')
        [[ -n $objs ]] || continue
        if [[ $name == bart-* || $name == horse-poses ]]; then
            # An animation: its frames in one run (keyframed cameras follow the frame number).
            [[ $quick == 1 ]] && objs=$(ls "$dir"*.obj | head -1)
            add_case "$name" "$dir/render.json" "$objs"
        else
            for obj in $objs; do
                add_case "$name-$(basename "$obj" .obj)" "$dir/render.json" "$obj"
            done
        fi
    done
else
    echo "check_same_output: ../shared is absent: testdata only"
fi

differences=0
differ() { echo "DIFFERENT: $*"; differences=$((differences + 1)); }

# stats.json without what a run cannot reproduce: timings, rates and device memory (which
# depends on the buffer pool's history), the version string, and the device round trips (a
# change that cuts them alters nothing a user sees).
# Paths under the side's own output folder are written as OUT/... .
strip_stats() {
    python3 - "$1" "$2" <<'EOF'
import json, sys
VOLATILE_SUFFIXES = ("_ms", "_per_s", "_per_second", "timings_ms")
# The summary's frames_per_second_after_first is a rate too (1000 / mean frame_ms after each
# run's first); it is not 0 only over two frames or more (testdata/anim), so --quick met it once.
VOLATILE = {"device_bytes", "device_bytes_per_triangle", "kdray_version",
            "frames_per_second_after_first", "device_syncs", "kernel_launches",
            "device_transfers"}
side_dir = sys.argv[2]
def strip(x):
    if isinstance(x, dict):
        return {k: strip(v) for k, v in x.items()
                if k not in VOLATILE and not k.endswith(VOLATILE_SUFFIXES)}
    if isinstance(x, list):
        return [strip(v) for v in x]
    if isinstance(x, str):
        return x.replace(side_dir, "OUT")
    return x
print(json.dumps(strip(json.load(open(sys.argv[1]))), indent=1, sort_keys=True))
EOF
}

# Two image files are the same when their bytes are; OpenEXR files carry the time they were
# written (DateTime), so those are the same when their headers without it and their pixels are.
exr_header() { oiiotool --info -v "$1" | grep -v 'DateTime\|^Reading\|openexr$'; }
same_image() {
    cmp -s "$1" "$2" && return 0
    [[ $1 == *.exr ]] || return 1
    diff -q <(exr_header "$1") <(exr_header "$2") >/dev/null &&
        idiff -fail 0 -warn 0 "$1" "$2" >/dev/null 2>&1
}

out=$work/runs
rm -rf "$out"
checked=0
for entry in "${cases[@]}"; do
    IFS=$'\t' read -r name camera inputs <<<"$entry"
    # shellcheck disable=SC2206
    files=($inputs)
    cam=()
    [[ -n $camera ]] && cam=(--camera "$camera")
    for side in base head; do
        bin=$base_bin
        [[ $side == head ]] && bin=$head_bin
        mkdir -p "$out/$side/$name"
        "$bin" render "${files[@]}" -o "$out/$side/$name/render" "${cam[@]}" --aov --quiet \
            >/dev/null 2>"$out/$side/$name/render.err" || echo "exit $?" >>"$out/$side/$name/render.err"
        for builder in opencl reference; do
            "$bin" build "${files[0]}" --builder "$builder" -o "$out/$side/$name/$builder.kdt" \
                --json >"$out/$side/$name/$builder.json" 2>"$out/$side/$name/$builder.err" ||
                echo "exit $?" >>"$out/$side/$name/$builder.err"
        done
    done
    b=$out/base/$name h=$out/head/$name
    for f in "$b"/render/*.png "$b"/render/*.exr "$b"/*.kdt; do
        [[ -e $f ]] || continue
        rel=${f#"$b"/}
        if [[ ! -e $h/$rel ]]; then differ "$name: $rel missing at HEAD"; continue; fi
        same_image "$f" "$h/$rel" || differ "$name: $rel"
        checked=$((checked + 1))
    done
    for f in "$h"/render/*.png "$h"/render/*.exr "$h"/*.kdt; do
        [[ -e $f ]] || continue
        [[ -e $b/${f#"$h"/} ]] || differ "$name: ${f#"$h"/} only at HEAD"
    done
    for err in render.err opencl.err reference.err; do
        # PoCL's compiler prints "N warnings generated." where a program is first compiled,
        # which depends on the kernel cache, not on kdray.
        diff -q <(grep -v 'warnings\? generated\.$' "$b/$err") \
            <(grep -v 'warnings\? generated\.$' "$h/$err") >/dev/null ||
            differ "$name: $err: $(head -c 300 "$h/$err")"
    done
    if [[ -f $b/render/stats.json && -f $h/render/stats.json ]]; then
        diff <(strip_stats "$b/render/stats.json" "$b") <(strip_stats "$h/render/stats.json" "$h") \
            >"$h/stats.diff" || differ "$name: stats.json beyond timings (see $h/stats.diff)"
    fi
    for builder in opencl reference; do
        if [[ -s $b/$builder.json ]]; then
            diff <(strip_stats "$b/$builder.json" "$b") <(strip_stats "$h/$builder.json" "$h") \
                >"$h/$builder.diff" || differ "$name: build --json ($builder) beyond timings"
        fi
    done
    echo "check_same_output: $name done"
done
echo "check_same_output: $checked files compared over ${#cases[@]} cases, $differences differences" \
    "(base $(git rev-parse --short "$base_commit"), head $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo '+changes'))"
[[ $differences == 0 ]]
