#!/usr/bin/env bash
# Builds kdray's libFuzzer targets (tests/fuzz) with clang in build-fuzz and runs each on a copy of
# its seed corpus, so the seeds in the repository stay small and hand-written.
#   scripts/fuzz.sh [SECONDS]   run each target this long (default 600)
#   scripts/fuzz.sh --smoke     run each target 5 s (CI: it proves the targets build and run;
#                               the 600-s runs in docs/fuzz-runs.json are the real search)
#   scripts/fuzz.sh 600 --record   and write docs/fuzz-runs.json (scripts/fuzz_record.py), whose
#                               table scripts/update_docs.py puts in docs/reliability.md
# Runs at the lowest priority with one worker: other work on the machine keeps its speed.
# Crash inputs land in build-fuzz/findings/<target>/; the exit status is non-zero if any target
# found one. Logs: build-fuzz/logs/<target>/fuzz-0.log.
set -euo pipefail
cd "$(dirname "$0")/.."

seconds=600
case "${1:-}" in
    --smoke) seconds=5 ;;
    "") ;;
    *[!0-9]*) echo "usage: scripts/fuzz.sh [SECONDS | --smoke] [--record]" >&2; exit 2 ;;
    *) seconds=$1 ;;
esac
record=0
case "${2:-}" in
    --record) record=1 ;;
    "") ;;
    *) echo "usage: scripts/fuzz.sh [SECONDS | --smoke] [--record]" >&2; exit 2 ;;
esac

scripts/install-deps.sh --fuzz
# The commit the targets are built at: the record names it, though the run ends much later.
commit=$(git rev-parse --short HEAD 2>/dev/null || echo unknown)
git diff --quiet HEAD 2>/dev/null || commit="$commit-dirty"
build_dir=build-fuzz
CC=clang CXX=clang++ cmake -S . -B "$build_dir" -DCMAKE_BUILD_TYPE=RelWithDebInfo \
    -DKDRAY_FUZZ=ON -DKDRAY_BUILD_TESTS=OFF >/dev/null
nice -n 19 cmake --build "$build_dir" -j "$(nproc)" --target fuzz_obj fuzz_render_file fuzz_mtl fuzz_tree_file

status=0
root=$PWD
for target in obj render_file mtl tree_file; do
    seeds=$root/tests/fuzz/corpus_${target%_file}
    corpus=$root/$build_dir/corpus/$target
    findings=$root/$build_dir/findings/$target
    logs=$root/$build_dir/logs/$target
    mkdir -p "$corpus" "$findings" "$logs"
    rm -f "$logs"/fuzz-*.log
    cp -n "$seeds"/* "$corpus"/ 2>/dev/null || true
    echo "fuzz_$target: ${seconds} s on $corpus (log: $logs/fuzz-0.log)"
    rm -f "$findings"/*
    # With -jobs=1 -workers=1 libFuzzer runs the job in a child process whose output goes to
    # fuzz-0.log in the working folder, hence the cd. detect_leaks=0 unless ASAN_OPTIONS says
    # otherwise: LeakSanitizer needs ptrace, which containers often deny.
    if ! (cd "$logs" && ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=0} nice -n 19 \
        "$root/$build_dir/tests/fuzz/fuzz_$target" "$corpus" -max_total_time="$seconds" -workers=1 -jobs=1 -max_len=65536 -timeout=25 \
        -rss_limit_mb=4096 -artifact_prefix="$findings/" -print_final_stats=1 >/dev/null 2>&1); then
        echo "fuzz_$target: FOUND A BUG; see $logs/fuzz-0.log and $findings/" >&2
        status=1
    fi
    grep -E '^(#[0-9]+.*DONE|stat::number_of_executed_units|stat::peak_rss_mb)' \
        "$logs/fuzz-0.log" || true
done
if [[ $record -eq 1 ]]; then
    python3 scripts/fuzz_record.py "$seconds" --build-dir "$build_dir" --command "scripts/fuzz.sh $*" \
        --commit "$commit"
fi
exit $status
