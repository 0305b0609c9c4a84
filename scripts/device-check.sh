#!/usr/bin/env bash
# device-check.sh — one call that checks and measures kdray on the machine it runs on, from inside
# a device bundle (scripts/device-bundle.sh copies it to BUNDLE/device-check.sh). Bash and
# coreutils only: no Python, the figures are kdray's own JSON.
#   1. info: kdray's version, the OpenCL platforms and devices (`kdray stats --json`), the machine;
#   2. correctness: every case of cases.txt rendered on the device (the hard scenes at each build
#      quality) against the CPU reference's AOV (conventions.md's agreement, mismatch_fraction at
#      most 1e-4) and, where listed, image (a pixel is off when a channel differs by more than
#      0.02 in linear EXR; at most 0.5% of pixels off), by `kdray compare`;
#   3. bench-build: `kdray build --json --repeat N` of Kitchen, Robots and dragon res2 at each
#      quality (low, medium, high), and Kitchen's at medium with each --large-stage;
#   4. bench-render: `kdray render --warm-up` of the same at each quality, at the render file's
#      size (stats.json).
# Every step has its own time limit and the whole a budget (--budget, 280 s), so one hang cannot
# eat the device time: a step past its limit, or past what is left of the budget, is killed and
# recorded as timed out; steps after the budget are recorded as skipped. Sized for under 5 minutes on a GPU.
#
# Usage: BUNDLE/device-check.sh [--quick] [--budget SECONDS]
#   --quick   bench at 256x192 with one timed build (a CPU device's smoke test, the CTest)
# Writes under $OUT when set, else ./device-check-out: summary.json (every step: name, exit
# status, milliseconds, output file), info/, correctness/ (with the device's image and AOV of a
# case that disagreed), bench/, logs/. Exit status 1 when a step failed, timed out or was
# skipped.
set -uo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
kdray="$here/kdray"
quick=0
budget=280
while [ $# -gt 0 ]; do
    case "$1" in
    --quick) quick=1 ;;
    --budget) budget=$2; shift ;;
    -h | --help) sed -n '2,23p' "$0"; exit 0 ;;
    *) echo "device-check: unknown option $1" >&2; exit 2 ;;
    esac
    shift
done
out=${OUT:-./device-check-out}
mkdir -p "$out"/{info,correctness,bench,logs,work}
out=$(cd "$out" && pwd)
work="$out/work"
steps="$out/logs/steps.jsonl"
: >"$steps"
have_timeout=0
command -v timeout >/dev/null 2>&1 && have_timeout=1
now_ms() { echo $(( $(date +%s%N) / 1000000 )); }
start_ms=$(now_ms)
failures=0

# step NAME LIMIT_S OUTPUT_FILE COMMAND...: runs COMMAND with its stdout into OUTPUT_FILE (or
# logs/NAME.out when "-") and its stderr into logs/NAME.err, records one line of steps.jsonl.
step() {
    local name=$1 limit=$2 file=$3
    shift 3
    [ "$file" = "-" ] && file="$out/logs/$name.out"
    local elapsed=$(( ($(now_ms) - start_ms) / 1000 ))
    if [ "$elapsed" -ge "$budget" ]; then
        echo "{\"name\": \"$name\", \"status\": \"skipped\", \"reason\": \"budget of ${budget} s spent\"}" >>"$steps"
        echo "device-check: $name: skipped (budget spent)" >&2
        failures=$((failures + 1))
        return 1
    fi
    # No step runs past the budget: its limit is at most what is left of it.
    [ "$limit" -le $((budget - elapsed)) ] || limit=$((budget - elapsed))
    local t0 rc status
    t0=$(now_ms)
    if [ "$have_timeout" = 1 ]; then
        timeout -k 5 "$limit" "$@" >"$file" 2>"$out/logs/$name.err"
    else
        "$@" >"$file" 2>"$out/logs/$name.err"
    fi
    rc=$?
    local ms=$(( $(now_ms) - t0 ))
    status=ok
    if [ "$rc" = 124 ] || [ "$rc" = 137 ]; then
        status=timed_out
    elif [ "$rc" != 0 ]; then status=failed; fi
    [ "$status" = ok ] || failures=$((failures + 1))
    echo "{\"name\": \"$name\", \"status\": \"$status\", \"rc\": $rc, \"ms\": $ms, \"limit_s\": $limit, \"output\": \"${file#"$out"/}\"}" >>"$steps"
    echo "device-check: $name: $status ($ms ms)" >&2
    [ "$status" = ok ]
}

# 1. What runs here.
step version 30 "$out/info/version.txt" "$kdray" --version
step devices 60 "$out/info/devices.json" "$kdray" stats --json
{
    uname -a
    grep -m1 "model name" /proc/cpuinfo
    grep -m1 MemTotal /proc/meminfo
    ls /etc/OpenCL/vendors 2>/dev/null
    command -v nvidia-smi >/dev/null && nvidia-smi -L
} >"$out/info/machine.txt" 2>&1

# 2. Correctness against the references.
qualities=(low medium high)
while read -r name obj camera size spp compare; do
    case "$name" in "" | "#"*) continue ;; esac
    [ -e "$here/refs/$name.aov.exr" ] || continue
    stem=$(basename "$obj" .obj)
    case "$name" in hard-*) levels=("${qualities[@]}") ;; *) levels=(high) ;; esac
    for q in "${levels[@]}"; do
        id="$name-$q"
        args=(render "$here/$obj" --camera "$here/$camera" -o "$work/$id" --quality "$q" --quiet
              --aov --format exr)
        [ "$size" = "-" ] || args+=(--size "$size")
        [ "$spp" = "-" ] || args+=(--spp "$spp")
        step "render-$id" 120 - "$kdray" "${args[@]}" || continue
        cp "$work/$id/stats.json" "$out/correctness/$id.stats.json"
        agree=1
        step "compare-aov-$id" 60 "$out/correctness/$id.aov.json" \
            "$kdray" compare "$work/$id/$stem.aov.exr" "$here/refs/$name.aov.exr" --json || agree=0
        case "$compare" in *image*)
            step "compare-image-$id" 60 "$out/correctness/$id.image.json" \
                "$kdray" compare "$work/$id/$stem.exr" "$here/refs/$name.exr" --json \
                --tolerance 0.02 --max-fraction 0.005 || agree=0 ;;
        esac
        # What disagreed comes back to be looked at.
        [ "$agree" = 1 ] || mv "$work/$id" "$out/correctness/$id.disagreed"
    done
done <"$here/cases.txt"

# 3 and 4. Benchmarks.
bench_scenes=(bart-kitchen/frame_000 bart-robots/frame_000 dragon/dragon_res2)
repeat=5
render_size=()
if [ "$quick" = 1 ]; then
    repeat=1
    render_size=(--size 256x192)
fi
for scene in "${bench_scenes[@]}"; do
    folder=$(dirname "$scene")
    [ -e "$here/scenes/$scene.obj" ] || continue
    for q in "${qualities[@]}"; do
        step "build-$folder-$q" 120 "$out/bench/build-$folder-$q.json" \
            "$kdray" build "$here/scenes/$scene.obj" --json --quality "$q" --repeat "$repeat"
    done
done
# The large stage in each shape (auto runs one of them): what the schedule costs on this device.
kitchen=bart-kitchen/frame_000
if [ -e "$here/scenes/$kitchen.obj" ]; then
    for stage in chunked level depth-first; do
        step "build-bart-kitchen-medium-$stage" 120 \
            "$out/bench/build-bart-kitchen-medium-$stage.json" "$kdray" build \
            "$here/scenes/$kitchen.obj" --json --quality medium --large-stage "$stage" \
            --repeat "$repeat"
    done
fi
for scene in "${bench_scenes[@]}"; do
    folder=$(dirname "$scene")
    [ -e "$here/scenes/$scene.obj" ] || continue
    for q in "${qualities[@]}"; do
        if step "render-$folder-$q" 150 - "$kdray" render "$here/scenes/$scene.obj" \
            --camera "$here/scenes/$folder/render.json" -o "$work/bench-$folder-$q" --quality "$q" \
            --warm-up --quiet "${render_size[@]}"; then
            cp "$work/bench-$folder-$q/stats.json" "$out/bench/render-$folder-$q.json"
        fi
    done
done
rm -rf "$work"

# The summary: the steps, the headline figures of each JSON file (read from kdray's own pretty
# printed JSON: one key a line), then the device list as kdray printed it.
total_ms=$(( $(now_ms) - start_ms ))
field() {  # field FILE KEY: the first value of KEY in FILE, or null
    local v
    v=$(sed -n "s/^ *\"$2\": \(.*[^,]\),\{0,1\}$/\1/p" "$1" | head -n 1)
    echo "${v:-null}"
}
figures() {  # figures FILE KEY...: {"file": ..., KEY: value, ...}
    local file=$1 line key
    shift
    line="{\"file\": \"${file#"$out"/}\""
    for key in "$@"; do line="$line, \"$key\": $(field "$file" "$key")"; done
    echo "$line}"
}
{
    for f in "$out"/correctness/*.json; do
        case "$f" in
        *.aov.json) figures "$f" agree mismatch_fraction mismatches pixels ;;
        *.image.json) figures "$f" agree fraction_over max_abs_difference psnr_db ;;
        esac
    done
} 2>/dev/null >"$out/logs/correctness.jsonl"
{
    for f in "$out"/bench/build-*.json; do
        [ -e "$f" ] && figures "$f" quality large_stage build_ms large_nodes nodes sah_cost
    done
    for f in "$out"/bench/render-*.json; do
        [ -e "$f" ] && figures "$f" mean_frame_ms mean_build_ms mean_trace_ms mean_compile_ms
    done
} 2>/dev/null >"$out/logs/bench.jsonl"
{
    echo "{"
    echo "  \"version\": \"$(tr -d '"\n' <"$out/info/version.txt" 2>/dev/null)\","
    echo "  \"quick\": $([ "$quick" = 1 ] && echo true || echo false),"
    echo "  \"total_ms\": $total_ms,"
    echo "  \"failures\": $failures,"
    echo "  \"steps\": ["
    sed '$!s/$/,/; s/^/    /' "$steps"
    echo "  ],"
    echo "  \"correctness\": ["
    sed '$!s/$/,/; s/^/    /' "$out/logs/correctness.jsonl"
    echo "  ],"
    echo "  \"bench\": ["
    sed '$!s/$/,/; s/^/    /' "$out/logs/bench.jsonl"
    echo "  ],"
    echo "  \"devices\": $( [ -s "$out/info/devices.json" ] && cat "$out/info/devices.json" || echo null)"
    echo "}"
} >"$out/summary.json"
echo "device-check: $failures failed or skipped steps, $total_ms ms; results in $out" >&2
[ "$failures" = 0 ]
