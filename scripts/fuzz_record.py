#!/usr/bin/env python3
"""Records a run of scripts/fuzz.sh as docs/fuzz-runs.json: for each target, the seconds it ran,
libFuzzer's executions, coverage and peak memory from its log, the corpus it grew, and the crash
inputs it left (findings). scripts/update_docs.py makes docs/reliability.md's table of it.

  scripts/fuzz_record.py SECONDS [--build-dir build-fuzz] [--out docs/fuzz-runs.json]
(scripts/fuzz.sh SECONDS --record runs it.)
"""
import argparse
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import ROOT, run_record, write_json  # noqa: E402

TARGETS = ("obj", "render_file", "mtl", "tree_file", "texture", "stats_json")


def target_row(build_dir, target, seconds):
    log_path = os.path.join(build_dir, "logs", target, "fuzz-0.log")
    with open(log_path, errors="replace") as f:
        log = f.read()
    stats = dict(re.findall(r"^stat::(\w+):\s*(\d+)", log, re.M))
    # The last status line: "#123456 DONE cov: 1234 ft: 2345 corp: 345/12Kb ..."
    cov = re.findall(r"^#\d+\s+\w+\s+cov: (\d+) ft: (\d+) corp: (\d+)/", log, re.M)
    findings_dir = os.path.join(build_dir, "findings", target)
    findings = sorted(os.listdir(findings_dir)) if os.path.isdir(findings_dir) else []
    corpus_dir = os.path.join(build_dir, "corpus", target)
    return {
        "target": "fuzz_" + target,
        "seconds": seconds,
        "executions": int(stats.get("number_of_executed_units", 0)),
        "executions_per_second": int(stats.get("average_exec_per_sec", 0)),
        "peak_rss_mb": int(stats.get("peak_rss_mb", 0)),
        "coverage": int(cov[-1][0]) if cov else None,
        "features": int(cov[-1][1]) if cov else None,
        "corpus_files": len(os.listdir(corpus_dir)) if os.path.isdir(corpus_dir) else 0,
        "findings": findings,
    }


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("seconds", type=int)
    parser.add_argument("--build-dir", default=os.path.join(ROOT, "build-fuzz"))
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "fuzz-runs.json"))
    parser.add_argument("--command", help="the command to record (default: this one)")
    parser.add_argument("--commit", help="the commit the fuzz targets were built at (default: "
                                         "the checkout's now)")
    args = parser.parse_args()
    rows = [target_row(args.build_dir, t, args.seconds) for t in TARGETS]
    record = run_record(os.path.join(ROOT, "build", "kdray"))  # the machine's devices, if built
    if args.command:
        record["command"] = args.command
    if args.commit:
        record["commit"] = args.commit
    write_json(args.out, {**record, "rows": rows})
    for r in rows:
        print(f"{r['target']}: {r['executions']} executions in {r['seconds']} s, "
              f"{len(r['findings'])} finding(s)")


if __name__ == "__main__":
    main()
