#!/usr/bin/env python3
"""A/B benchmark: two kdray binaries (a base revision and the working tree, say) measured in
interleaved rounds in one run, so that the drift of a shared machine falls on both alike.

Per round and side: `kdray build --repeat N --json` on the build scenes (the median of N warm
builds, after kdray's own warm-up build), and `kdray render --warm-up` of whole animations (every
frame's build + trace, primary rays and the scene's lights as its render.json says). The sides
alternate which goes first from round to round. The figure per side is the median over rounds.

  scripts/bench_ab.py --base BASE_BIN --head HEAD_BIN [--rounds 3] [--repeat 5] [--out PREFIX]

Writes PREFIX.json (every round's figures, the commands, the machine) and PREFIX.md.
"""
import argparse
import datetime
import json
import os
import statistics
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import (ROOT, SHARED, git_commit, machine_description, run_json,  # noqa: E402
                          write_markdown)

BUILD_SCENES = ["bart-kitchen/frame_000.obj", "dragon/dragon_res2.obj", "sponza-dabrovic/sponza.obj",
                "bunny/bunny.obj"]
ANIMATIONS = ["bart-kitchen", "bart-robots"]


def render_run(binary, folder):
    """Every frame of ../shared/scenes/FOLDER rendered in one process; per-frame figures."""
    scene_dir = os.path.join(SHARED, "scenes", folder)
    frames = sorted(os.path.join(scene_dir, f) for f in os.listdir(scene_dir)
                    if f.startswith("frame_") and f.endswith(".obj"))
    with tempfile.TemporaryDirectory(prefix="kdray-ab-") as out:
        command = [binary, "render", *frames, "--camera", os.path.join(scene_dir, "render.json"),
                   "-o", out, "--warm-up", "--quiet"]
        result = subprocess.run(command, capture_output=True, text=True)
        if result.returncode != 0:
            raise RuntimeError(f"{' '.join(command)} failed: {result.stderr.strip()}")
        with open(os.path.join(out, "stats.json")) as f:
            stats = json.load(f)
    keys = ("build_ms", "trace_ms", "frame_ms")
    return {k: statistics.median(fr[k] for fr in stats["frames"]) for k in keys}


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--base", required=True, help="the kdray binary measured as 'base'")
    parser.add_argument("--head", required=True, help="the kdray binary measured as 'head'")
    parser.add_argument("--base-label", default="base")
    parser.add_argument("--head-label", default="head")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "bench-ab"))
    parser.add_argument("--builds-only", action="store_true", help="skip the animations")
    args = parser.parse_args()
    if not os.path.isdir(os.path.join(SHARED, "scenes")):
        print("bench_ab: ../shared/scenes is absent: nothing to measure", file=sys.stderr)
        return 1

    sides = {"base": args.base, "head": args.head}
    rounds = []
    for r in range(args.rounds):
        order = ["base", "head"] if r % 2 == 0 else ["head", "base"]
        figures = {side: {"build_ms": {}, "frame": {}} for side in sides}
        for scene in BUILD_SCENES:
            obj = os.path.join(SHARED, "scenes", scene)
            for side in order:
                report = run_json([sides[side], "build", obj, "--json", "--repeat", str(args.repeat)])
                figures[side]["build_ms"][scene] = report["build_ms"]
        for folder in [] if args.builds_only else ANIMATIONS:
            for side in order:
                figures[side]["frame"][folder] = render_run(sides[side], folder)
        rounds.append(figures)
        print(f"bench_ab: round {r + 1}/{args.rounds}: {json.dumps(figures)}", file=sys.stderr)

    def median_of(side, pick):
        return statistics.median(pick(rnd[side]) for rnd in rounds)

    rows = []
    for scene in BUILD_SCENES:
        base = median_of("base", lambda f: f["build_ms"][scene])
        head = median_of("head", lambda f: f["build_ms"][scene])
        rows.append({"what": f"build {scene}", "base_ms": base, "head_ms": head})
    for folder in [] if args.builds_only else ANIMATIONS:
        for key in ("build_ms", "trace_ms", "frame_ms"):
            base = median_of("base", lambda f: f["frame"][folder][key])
            head = median_of("head", lambda f: f["frame"][folder][key])
            rows.append({"what": f"render {folder}: {key} per frame", "base_ms": base,
                         "head_ms": head})
    for row in rows:
        row["head_over_base"] = row["head_ms"] / row["base_ms"] if row["base_ms"] else None

    result = {"date": str(datetime.date.today()), "commit": git_commit(),
              "machine": machine_description(args.head),
              "command": " ".join(sys.argv), "base": args.base_label, "head": args.head_label,
              "rounds": args.rounds, "repeat": args.repeat, "builds_only": args.builds_only, "rows": rows, "raw": rounds}
    with open(args.out + ".json", "w") as f:
        json.dump(result, f, indent=1)
    lines = [f"# A/B benchmark: {args.head_label} against {args.base_label}", "",
             f"Run {result['date']} at {result['commit']} on {result['machine']}; "
             f"{args.rounds} interleaved rounds, each figure the median over rounds "
             f"(builds: the median of {args.repeat} warm builds; renders: the median frame of "
             "every frame after an untimed warm-up frame).", "",
             f"| what | {args.base_label} ms | {args.head_label} ms | "
             f"{args.head_label} / {args.base_label} |", "|---|---:|---:|---:|"]
    for row in rows:
        lines.append(f"| {row['what']} | {row['base_ms']:.1f} | {row['head_ms']:.1f} | "
                     f"{row['head_over_base']:.3f} |")
    write_markdown(args.out, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
