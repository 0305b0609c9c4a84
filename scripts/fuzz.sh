#!/usr/bin/env bash
# Builds kdray's libFuzzer targets (tests/fuzz) with clang in build-fuzz and runs each on a copy of
# its seed corpus, so the seeds in the repository stay small and hand-written.
#   scripts/fuzz.sh [SECONDS]   run each target this long (default 600)
#   scripts/fuzz.sh --smoke     run each target 5 s (CI: it proves the targets build and run;
#                               the 600-s runs in docs/fuzz-runs.json are the real search)
#   scripts/fuzz.sh 600 --record   and write docs/fuzz-runs.json (scripts/fuzz_record.py), whose
#                               table scripts/update_docs.py puts in docs/reliability.md
#   --parallel N                run N targets at a time (default 1): six targets of 600 s take an
#                               hour one after another, 30 minutes two at a time on 2 cores
#   --only TARGET[,TARGET]      run only these (texture, stats_json, ...): a re-run after a fix
# Runs at the lowest priority with one worker per target: other work on the machine keeps its
# speed. Crash inputs land in build-fuzz/findings/<target>/; the exit status is non-zero if any
# target found one. Logs: build-fuzz/logs/<target>/fuzz-0.log.
set -euo pipefail
cd "$(dirname "$0")/.."

usage() {
    echo "usage: scripts/fuzz.sh [SECONDS | --smoke] [--record] [--parallel N] [--only T,...]" >&2
    exit 2
}
all_targets=(obj render_file mtl tree_file texture stats_json)
seconds=600
record=0
parallel=1
targets=("${all_targets[@]}")
args="$*"
while [[ $# -gt 0 ]]; do
    case "$1" in
        --smoke) seconds=5 ;;
        --record) record=1 ;;
        --parallel) [[ "${2:-}" =~ ^[1-9][0-9]*$ ]] || usage; parallel=$2; shift ;;
        --only) [[ -n "${2:-}" ]] || usage; IFS=, read -r -a targets <<<"$2"; shift ;;
        *[!0-9]* | "") usage ;;
        *) seconds=$1 ;;
    esac
    shift
done
for t in "${targets[@]}"; do
    [[ " ${all_targets[*]} " == *" $t "* ]] || { echo "fuzz.sh: no target fuzz_$t" >&2; exit 2; }
done
# A record is of every target at once: fuzz_record.py reads each one's log.
if [[ $record -eq 1 && ${#targets[@]} -ne ${#all_targets[@]} ]]; then
    echo "fuzz.sh: --record needs every target (no --only)" >&2
    exit 2
fi

scripts/install-deps.sh --fuzz
# The commit the targets are built at: the record names it, though the run ends much later.
commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
git diff --quiet HEAD 2>/dev/null || commit="$commit-dirty"
build_dir=build-fuzz
CC=clang CXX=clang++ cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DKDRAY_FUZZ=ON -DKDRAY_BUILD_TESTS=OFF >/dev/null
nice -n 19 cmake --build "$build_dir" -j "$(nproc)" --target $(printf " fuzz_%s" "${all_targets[@]}")

root=$PWD
# One target's run; its status in $build_dir/logs/<target>/status, since it may run in the
# background beside another.
fuzz_one() {
    local target=$1 seeds corpus findings logs
    # Seeds: tests/fuzz/corpus_obj, corpus_render (render_file), corpus_stats (stats_json), ...
    seeds=$root/tests/fuzz/corpus_${target%_file}
    seeds=${seeds%_json}
    corpus=$root/$build_dir/corpus/$target
    findings=$root/$build_dir/findings/$target
    logs=$root/$build_dir/logs/$target
    mkdir -p "$corpus" "$findings" "$logs"
    rm -f "$logs"/fuzz-*.log "$logs/status"
    cp -n "$seeds"/* "$corpus"/ 2>/dev/null || true
    # A texture file of B bytes may declare up to 16384 B pixels (kMaxPixelsPerFileByte), which
    # kdray decodes within its budget of a quarter of the machine's memory: at 4096 bytes that is
    # 2^26 pixels, 1 GiB of floats, so that the 4 GiB limit below reports only memory kdray
    # should not have taken.
    local max_len=65536
    [[ $target == texture ]] && max_len=4096
    echo "fuzz_$target: ${seconds} s on $corpus (log: $logs/fuzz-0.log)"
    rm -f "$findings"/*
    # With -jobs=1 -workers=1 libFuzzer runs the job in a child process whose output goes to
    # fuzz-0.log in the working folder, hence the cd. detect_leaks=0 unless ASAN_OPTIONS says
    # otherwise: LeakSanitizer needs ptrace, which containers often deny.
    if (cd "$logs" && ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0} nice -n 19 \
        "$root/$build_dir/tests/fuzz/fuzz_$target" "$corpus" -max_total_time="$seconds" -workers=1 -jobs=1 -max_len=$max_len -timeout=25 \
        -rss_limit_mb=4096 -artifact_prefix="$findings/" -print_final_stats=1 >/dev/null 2>&1); then
        echo 0 >"$logs/status"
    else
        echo 1 >"$logs/status"
    fi
}

running=0
for target in "${targets[@]}"; do
    if [[ $parallel -gt 1 ]]; then
        fuzz_one "$target" &
        running=$((running + 1))
        if [[ $running -ge $parallel ]]; then
            wait -n || true
            running=$((running - 1))
        fi
    else
        fuzz_one "$target"
    fi
done
wait
status=0
for target in "${targets[@]}"; do
    logs=$root/$build_dir/logs/$target
    if [[ "$(cat "$logs/status" 2>/dev/null)" != 0 ]]; then
        echo "fuzz_$target: FOUND A BUG; see $logs/fuzz-0.log and $root/$build_dir/findings/$target/" >&2
        status=1
    fi
    echo "fuzz_$target:"
    grep -E '^(#[0-9]+.*DONE|stat::number_of_executed_units|stat::peak_rss_mb)' \
        "$logs/fuzz-0.log" || true
done
if [[ $record -eq 1 ]]; then
    python3 scripts/fuzz_record.py "$seconds" --build-dir "$build_dir" --command "scripts/fuzz.sh $args" \
        --commit "$commit"
fi
exit $status
