#!/usr/bin/env python3
"""The build-quality ladder (kdray --quality low|medium|high) against Embree's, in one run.

1. Dynamic frames: the BART Kitchen and Robots, all 8 frames with their keyframed cameras,
   primary rays only (no lights, max_depth 1), 1024x768. kdray renders the sequence in one
   process with --warm-up at each quality; the peer builds and traces each frame at each of its
   qualities (median of 3 in its process). --rounds rounds of every side in turn; a frame's
   figure is its median over the rounds, a sequence's the mean of its frames. Warm on both sides.
2. Builds: BART Kitchen frame 0 and the dragon (res2), `kdray build --repeat` at each quality
   (median after a warm-up) beside Embree's build at each of its qualities, and the SAH of each
   tree against the CPU reference builder's (full SAH, the yardstick).

From those it names the defaults (`choose_defaults`): for a render of several frames the level
with the least mean frame time over the animations; for `build` and a single frame, high.
Writes docs/quality-ladder.json and .md, and the ladder as curves in
docs/accuracy-vs-time/quality_ladder.png (--plot-only redraws them from the JSON).

  scripts/quality_ladder.py --kdray build/kdray [--rounds 3] [--repeat 5] [--no-reference]
  scripts/quality_ladder.py --plot-only
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import ROOT, SHARED, build_peer, median, run_json, run_record  # noqa
from bench_render import primary_only, primary_sequence  # noqa
from accuracy_plots import _pyplot, ensure_matplotlib  # noqa

QUALITIES = ("low", "medium", "high")
THREADS = os.cpu_count()


def animations():
    found = []
    for folder in ("bart-kitchen", "bart-robots"):
        path = os.path.join(SHARED, "scenes", folder)
        if os.path.isdir(path):
            objs = sorted(os.path.join(path, f) for f in os.listdir(path)
                          if f.startswith("frame_") and f.endswith(".obj"))
            found.append((folder, objs, os.path.join(path, "render.json")))
    return found


def static_scenes():
    candidates = [("bart-kitchen/frame_000", "bart-kitchen/frame_000.obj"),
                  ("dragon_res2", "dragon/dragon_res2.obj")]
    return [(name, os.path.join(SHARED, "scenes", rel)) for name, rel in candidates
            if os.path.isfile(os.path.join(SHARED, "scenes", rel))]


def kdray_sequence(kdray, objs, render, out_dir, quality):
    subprocess.run([kdray, "render", *objs, "--camera", render, "-o", out_dir, "-q", "--warm-up",
                    "--quality", quality, "--overwrite"], check=True, capture_output=True, text=True)
    with open(os.path.join(out_dir, "stats.json")) as f:
        frames = json.load(f)["frames"]
    if any(f["tree"].get("quality") != quality for f in frames):
        raise RuntimeError(f"stats.json does not record quality {quality}")
    return frames


def mean_over_frames(runs, value):
    """The mean over frames of each frame's median over the rounds."""
    n = len(runs[0])
    return sum(median([value(r[k]) for r in runs]) for k in range(n)) / n


def dynamic(kdray, peer, rounds, tmp):
    rows = []
    for name, objs, camera in animations():
        render = primary_sequence(camera, os.path.join(tmp, "dynamic.json"))
        peer_cams = [primary_only(camera, os.path.join(tmp, f"peer_{k}.json"), frame=k)
                     for k in range(len(objs))]
        kd = {q: [] for q in QUALITIES}
        em = {q: [] for q in QUALITIES}
        for _ in range(rounds):
            for q in QUALITIES:
                kd[q].append(kdray_sequence(kdray, objs, render, os.path.join(tmp, "dyn"), q))
                if peer:
                    em[q].append([run_json([peer, obj, "--camera", cam, "--quality", q,
                                            "--repeat", "3", "--threads", str(THREADS)])
                                  for obj, cam in zip(objs, peer_cams)])
        for q in QUALITIES:
            runs = kd[q]
            row = {"scene": name, "side": "kdray", "quality": q, "frames": len(objs),
                   "build_ms": mean_over_frames(runs, lambda f: f["build_ms"]),
                   "trace_ms": mean_over_frames(runs, lambda f: f["trace_ms"]),
                   "frame_ms": mean_over_frames(runs, lambda f: f["build_ms"] + f["trace_ms"]),
                   "sah_cost": mean_over_frames(runs, lambda f: f["tree"]["sah_cost"]),
                   "params": runs[0][0]["tree"]["params"]}
            rows.append(row)
            print(f"dynamic {row}", file=sys.stderr)
            if peer:
                runs = em[q]
                row = {"scene": name, "side": "embree", "quality": q, "frames": len(objs),
                       "build_ms": mean_over_frames(runs, lambda f: f["build_ms"]),
                       "trace_ms": mean_over_frames(runs, lambda f: f["trace_ms"]),
                       "frame_ms": mean_over_frames(runs,
                                                    lambda f: f["build_ms"] + f["trace_ms"])}
                rows.append(row)
                print(f"dynamic {row}", file=sys.stderr)
    return rows


def builds(kdray, peer, repeat, reference, tmp):
    rows = []
    for name, obj in static_scenes():
        camera = os.path.join(os.path.dirname(obj), "render.json")
        ref_sah = None
        if reference:
            ref_sah = run_json([kdray, "build", obj, "--json", "--builder", "reference"])["sah_cost"]
        for q in QUALITIES:
            r = run_json([kdray, "build", obj, "--json", "--quality", q, "--repeat", str(repeat)])
            row = {"scene": name, "side": "kdray", "quality": q, "triangles": r["triangles"],
                   "build_ms": r["build_ms"], "sah_cost": r["sah_cost"], "nodes": r["nodes"],
                   "mean_triangles_per_leaf": r["mean_triangles_per_leaf"],
                   "params": r["params"], "reference_sah": ref_sah}
            rows.append(row)
            print(f"build {row}", file=sys.stderr)
            if peer:
                cam = primary_only(camera, os.path.join(tmp, "build_cam.json"), frame=0)
                e = run_json([peer, obj, "--camera", cam, "--quality", q, "--repeat", str(repeat),
                              "--threads", str(THREADS)])
                rows.append({"scene": name, "side": "embree", "quality": q,
                             "build_ms": e["build_ms"]})
    return rows


def choose_defaults(dynamic_rows):
    """The animation default: the level with the least mean frame time (build + trace) over the
    animations. The static default is high: a tree built once for one frame or for `build` is the
    one users keep and trace again, and the best tree is what the device builds at high."""
    kd = [r for r in dynamic_rows if r["side"] == "kdray"]
    if not kd:
        return {"animation": None, "static": "high", "why": "no shared animations"}

    def mean(q, key):
        values = [r[key] for r in kd if r["quality"] == q]
        return sum(values) / len(values)

    return {"animation": min(QUALITIES, key=lambda q: mean(q, "frame_ms")), "static": "high",
            "mean_frame_ms": {q: mean(q, "frame_ms") for q in QUALITIES},
            "mean_build_ms": {q: mean(q, "build_ms") for q in QUALITIES},
            "mean_trace_ms": {q: mean(q, "trace_ms") for q in QUALITIES},
            "why": "the least mean build + trace per frame over the animations"}


def peer_medium(rows, scene, key):
    return next((p[key] for p in rows if p["scene"] == scene and p["side"] == "embree"
                 and p["quality"] == "medium"), None)


def cell(value, fmt):
    return format(value, fmt) if value is not None else ""


def report(result):
    lines = ["# Build-quality ladder", "",
             "![The ladder as curves](accuracy-vs-time/quality_ladder.png)", "",
             f"Run {result['date']} on {result['machine']}; Embree with {THREADS} threads. "
             "Written by scripts/quality_ladder.py with docs/quality-ladder.json.", "",
             "## Dynamic frames (build + trace, primary rays, 1024x768, warm on both sides)", "",
             f"Mean over the frames of each frame's median over {result['rounds']} rounds.", "",
             "| scene | side | quality | build ms | trace ms | frame ms | / Embree medium | SAH |",
             "|---|---|---|---:|---:|---:|---:|---:|"]
    dyn = result["dynamic"]
    for r in dyn:
        peer = peer_medium(dyn, r["scene"], "frame_ms")
        lines.append(f"| {r['scene']} | {r['side']} | {r['quality']} | {r['build_ms']:.1f} | "
                     f"{r['trace_ms']:.1f} | {r['frame_ms']:.1f} | "
                     f"{cell(r['frame_ms'] / peer if peer else None, '.2f')} | "
                     f"{cell(r.get('sah_cost'), '.1f')} |")
    lines += ["", f"## Builds (median of {result['repeat']} after a warm-up)", "",
              "| scene | side | quality | build ms | / Embree medium | SAH | / reference SAH | "
              "triangles per leaf |", "|---|---|---|---:|---:|---:|---:|---:|"]
    bld = result["builds"]
    for r in bld:
        peer = peer_medium(bld, r["scene"], "build_ms")
        ref = r.get("reference_sah")
        sah = r.get("sah_cost")
        lines.append(f"| {r['scene']} | {r['side']} | {r['quality']} | {r['build_ms']:.1f} | "
                     f"{cell(r['build_ms'] / peer if peer else None, '.2f')} | "
                     f"{cell(sah, '.1f')} | {cell(sah / ref if sah and ref else None, '.3f')} | "
                     f"{cell(r.get('mean_triangles_per_leaf'), '.2f')} |")
    d = result["defaults"]
    lines += ["", "## Defaults", "",
              f"- A render of several frames: **{d['animation']}**, {d['why']}.",
              f"- `build` and a single frame: **{d['static']}**, the best tree.", "",
              "The parameters each level sets (every other parameter is the same at each):", ""]
    seen = set()
    for r in bld:
        if r["side"] == "kdray" and r["quality"] not in seen:
            seen.add(r["quality"])
            p = r["params"]
            lines.append(f"- {r['quality']}: large_split_bins {p['large_split_bins']}, "
                         f"small_reclip_refs {p['small_reclip_refs']}, "
                         f"small_leaf_refs {p['small_leaf_refs']}")
    return "\n".join(lines) + "\n"


def plot(result, path):
    """Left: each animation's mean frame, build ms against trace ms, kdray's levels joined low to
    high and Embree's beside them (lines of equal build + trace dashed). Right: each build scene's
    SAH against the reference builder's, by build ms."""
    plt = _pyplot()
    fig, (left, right) = plt.subplots(1, 2, figsize=(11, 4.5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    dyn = result["dynamic"]
    for i, scene in enumerate(dict.fromkeys(r["scene"] for r in dyn)):
        for side, marker, style in (("kdray", "o", "-"), ("embree", "s", ":")):
            rows = [r for r in dyn if r["scene"] == scene and r["side"] == side]
            if not rows:
                continue
            left.plot([r["build_ms"] for r in rows], [r["trace_ms"] for r in rows], style,
                      marker=marker, color=colours[i % len(colours)], label=f"{scene}, {side}")
            for r in rows:
                left.annotate(r["quality"], (r["build_ms"], r["trace_ms"]), fontsize=7,
                              textcoords="offset points", xytext=(3, 3))
    left.set_xlabel("build ms per frame")
    left.set_ylabel("trace ms per frame (primary rays)")
    left.set_title("Dynamic frames, 1024x768")
    left.legend(fontsize=7)
    bld = [r for r in result["builds"] if r["side"] == "kdray" and r.get("reference_sah")]
    for i, scene in enumerate(dict.fromkeys(r["scene"] for r in bld)):
        rows = [r for r in bld if r["scene"] == scene]
        right.plot([r["build_ms"] for r in rows], [r["sah_cost"] / r["reference_sah"] for r in rows],
                   "-o", color=colours[i % len(colours)], label=scene)
        for r in rows:
            right.annotate(r["quality"], (r["build_ms"], r["sah_cost"] / r["reference_sah"]),
                           fontsize=7, textcoords="offset points", xytext=(3, 3))
        peer = [r["build_ms"] for r in result["builds"]
                if r["scene"] == scene and r["side"] == "embree" and r["quality"] == "medium"]
        if peer:
            right.axvline(peer[0], color=colours[i % len(colours)], linestyle=":", linewidth=1)
    right.set_xlabel("build ms (dotted: Embree medium)")
    right.set_ylabel("SAH / reference builder's SAH")
    right.set_title("Builds")
    right.legend(fontsize=7)
    fig.suptitle(f"Build-quality ladder ({result['date']}, scripts/quality_ladder.py)")
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--no-reference", action="store_true")
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "quality-ladder"))
    parser.add_argument("--plot", default=os.path.join(ROOT, "docs", "accuracy-vs-time",
                                                       "quality_ladder.png"))
    parser.add_argument("--plot-only", action="store_true", help="redraw the plot from the JSON")
    args = parser.parse_args()
    ensure_matplotlib(sys.argv)
    if args.plot_only:
        with open(args.out + ".json") as f:
            plot(json.load(f), args.plot)
        return
    peer = build_peer()
    with tempfile.TemporaryDirectory(prefix="kdray-ladder-") as tmp:
        dyn = dynamic(args.kdray, peer, args.rounds, tmp)
        bld = builds(args.kdray, peer, args.repeat, not args.no_reference, tmp)
    result = {**run_record(args.kdray), "rounds": args.rounds, "repeat": args.repeat, "dynamic": dyn, "builds": bld,
              "defaults": choose_defaults(dyn)}
    with open(args.out + ".json", "w") as f:
        json.dump(result, f, indent=1)
    with open(args.out + ".md", "w") as f:
        f.write(report(result))
    plot(result, args.plot)
    print(f"wrote {args.out}.json and .md, and {args.plot}", file=sys.stderr)


if __name__ == "__main__":
    main()
