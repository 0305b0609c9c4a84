#!/usr/bin/env python3
"""Binned small nodes against the exact search (kdray --small-split-bins), beside Embree, in one
run: what dropping the split-candidate masks buys and costs.

For each scene and bin count (0: Zhou et al.'s exact search over masks, the ladder's; else the
binned search of that many bins per axis), `kdray build --quality low --small-bins B --repeat N
--json` (the median of N warm builds after kdray's warm-up build), in --rounds interleaved rounds
(the bin counts' order turns from round to round, so that a shared machine's drift falls on all),
with Embree's medium build (warm, the median of its --repeat) in every round as the yardstick.
A figure is its median over the rounds. It records build and small-stage time, SAH, nodes,
references per triangle and device bytes, and one cold build per bin count and round (a fresh
process, as a user's single `kdray build`).

  scripts/small_bins.py --kdray build/kdray [--bins 0,4,8,16] [--rounds 3] [--repeat 9]

Writes docs/small-bins.json and .md (or --out).
"""
import argparse
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import (ROOT, SHARED, build_peer, median, run_json, run_record,  # noqa: E402
                          write_json, write_markdown)

SCENES = ["bart-kitchen/frame_000.obj", "bunny/bunny.obj", "dragon/dragon_res2.obj"]


def kdray_build(kdray, obj, bins, repeat):
    args = [kdray, "build", obj, "--json", "--builder", "opencl", "--quality", "low",
            "--small-bins", str(bins)]
    return run_json(args + (["--repeat", str(repeat)] if repeat > 1 else []))


def figures(report):
    return {"build_ms": report["build_ms"], "small_nodes_ms": report["timings_ms"]["small_nodes"],
            "sah_cost": report["sah_cost"], "nodes": report["nodes"],
            "references_per_triangle": report["references_per_triangle"],
            "device_bytes": report["device_bytes"]}


def measure(args, peer):
    rows = []
    for rel in SCENES:
        obj = os.path.join(SHARED, "scenes", rel)
        if not os.path.isfile(obj):
            print(f"small_bins: {rel} is absent; skipped", file=sys.stderr)
            continue
        camera = os.path.join(os.path.dirname(obj), "render.json")
        runs = {b: [] for b in args.bins}
        cold = {b: [] for b in args.bins}
        embree = []
        for r in range(args.rounds):
            order = args.bins[r % len(args.bins):] + args.bins[:r % len(args.bins)]
            for b in order:
                runs[b].append(figures(kdray_build(args.kdray, obj, b, args.repeat)))
                cold[b].append(kdray_build(args.kdray, obj, b, 1)["build_ms"])
            if peer:
                embree.append(run_json([peer, obj, "--camera", camera, "--quality", "medium",
                                        "--repeat", str(args.repeat + 1),
                                        "--threads", str(os.cpu_count())])["build_ms"])
        embree_ms = median(embree) if embree else None
        for b in args.bins:
            row = {"scene": rel, "small_split_bins": b,
                   **{k: median([f[k] for f in runs[b]]) for k in runs[b][0]},
                   "cold_build_ms": median(cold[b]), "embree_medium_ms": embree_ms,
                   "rounds": {"build_ms": [f["build_ms"] for f in runs[b]],
                              "embree_medium_ms": embree}}
            rows.append(row)
            print(f"{rel} bins {b}: {row}", file=sys.stderr)
    return rows


def report(data):
    exact = {r["scene"]: r for r in data["rows"] if r["small_split_bins"] == 0}
    lines = ["# Binned small nodes against the exact search", "",
             "`kdray build --quality low --small-bins B`; B = 0 is the ladder's exact search over "
             "split masks. Warm medians over interleaved rounds, Embree medium (warm) in the same "
             "rounds.", "",
             "| scene | bins | build ms | / Embree medium | small stage ms | SAH | nodes | "
             "refs per triangle | device MB | cold build ms |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for r in data["rows"]:
        e = exact.get(r["scene"], r)
        over = f"{r['build_ms'] / r['embree_medium_ms']:.2f}" if r["embree_medium_ms"] else ""
        lines.append(
            f"| {r['scene']} | {r['small_split_bins']} | {r['build_ms']:.1f} | {over} | "
            f"{r['small_nodes_ms']:.1f} | {r['sah_cost']:.1f} ({r['sah_cost'] / e['sah_cost']:.3f})"
            f" | {r['nodes']} ({r['nodes'] / e['nodes']:.2f}) | "
            f"{r['references_per_triangle']:.2f} | {r['device_bytes'] / 1e6:.1f} | "
            f"{r['cold_build_ms']:.1f} |")
    lines += ["", f"Measured {data['date']} at {data['commit']} on {data['machine']}: "
              f"`{data['command']}`."]
    return lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--bins", default="0,4,8,16")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeat", type=int, default=9)
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "small-bins"))
    args = parser.parse_args()
    args.bins = [int(b) for b in args.bins.split(",")]
    peer = build_peer()
    if not peer:
        print("small_bins: the Embree peer is not available; its column stays empty",
              file=sys.stderr)
    data = {**run_record(args.kdray), "repeat": args.repeat, "rounds": args.rounds,
            "rows": measure(args, peer)}
    write_json(args.out + ".json", data)
    write_markdown(args.out, report(data))


if __name__ == "__main__":
    main()
