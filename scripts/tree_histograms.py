#!/usr/bin/env python3
"""The kd-trees' shape made visible: histograms of leaf sizes (triangles per leaf) and leaf depths
of kdray's OpenCL trees, from `kdray build --json` (leaf_size_histogram, leaf_depth_histogram),
one row of two panels per scene, at each build quality.

    scripts/tree_histograms.py [--kdray build/kdray] [--out docs/tree-histograms] [OBJ ...]

Default scenes: testdata/cornell and, when ../shared is there, the bunny and the Kitchen's first
frame. Writes OUT.json (the histograms, the commit and the machine) and OUT.png (matplotlib,
installed with apt when missing, as scripts/accuracy_plots.py does).
"""
import argparse
import glob
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from accuracy_plots import ensure_matplotlib  # noqa: E402
from bench_common import ROOT, SHARED, run_json, run_record, write_json  # noqa: E402

QUALITIES = ["low", "medium", "high"]


def default_scenes():
    scenes = sorted(glob.glob(os.path.join(ROOT, "testdata", "cornell", "*.obj")))[:1]
    for shared in ("bunny/bunny.obj", "bart-kitchen/frame_000.obj"):
        path = os.path.join(SHARED, "scenes", shared)
        if os.path.isfile(path):
            scenes.append(path)
    return scenes


def display_name(obj):
    """A scene's name as the docs give it: relative to the repository or to ../shared/scenes."""
    path = os.path.abspath(obj)
    for base in (os.path.join(SHARED, "scenes"), ROOT):
        if path.startswith(base + os.sep):
            return os.path.relpath(path, base)
    return os.path.basename(path)


def main():
    ensure_matplotlib(sys.argv)
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "tree-histograms"))
    parser.add_argument("scenes", nargs="*")
    args = parser.parse_args()
    scenes = args.scenes or default_scenes()
    rows = []
    for obj in scenes:
        for quality in QUALITIES:
            j = run_json([args.kdray, "build", obj, "--json", "--quality", quality])
            rows.append({"scene": display_name(obj),
                         "quality": quality, "triangles": j["triangles"], "leaves": j["leaves"],
                         "sah_cost": j["sah_cost"], "tree_depth_reached": j.get("tree_depth_reached", j.get("max_depth")),
                         "leaf_size_histogram": j["leaf_size_histogram"],
                         "leaf_depth_histogram": j["leaf_depth_histogram"]})
    write_json(args.out + ".json", {**run_record(args.kdray), "rows": rows})

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(len(scenes), 2, figsize=(11, 3.2 * len(scenes)), squeeze=False)
    for s, obj in enumerate(scenes):
        size_ax, depth_ax = axes[s]
        name = display_name(obj)
        for row in (r for r in rows if r["scene"] == name):
            label = f"{row['quality']} (SAH {row['sah_cost']:.0f})"
            sizes = row["leaf_size_histogram"]
            size_ax.step([k for k, _ in sizes], [n for _, n in sizes], where="mid", label=label)
            depths = row["leaf_depth_histogram"]
            depth_ax.step(range(len(depths)), depths, where="mid", label=row["quality"])
        size_ax.set_title(f"{name}: leaves by triangle count")
        size_ax.set_xlabel("triangles in the leaf")
        size_ax.set_ylabel("leaves")
        size_ax.set_yscale("log")
        size_ax.legend(fontsize=8)
        depth_ax.set_title(f"{name}: leaves by depth")
        depth_ax.set_xlabel("depth")
        depth_ax.set_ylabel("leaves")
        depth_ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.out + ".png", dpi=90)
    print(f"wrote {args.out}.json and {args.out}.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
