#!/usr/bin/env python3
"""What the packets' width costs on this machine's OpenCL device: warm primary rays (the render
file with no lights, max_depth 1) of the bunny at its render file's size, kdray's OpenCL tracer
with packets of 8 lanes (float8, 4x2 pixels) and of 16 (float16, 4x4), forced by
KDRAY_PACKET_LANES, and Embree's primary rays (the peer, medium quality) in the same run. The
three take turns round by round so that a shared machine's drift falls on all alike; a figure is
the median over rounds of each run's median over --repeat warm frames. Both widths must write
the same image (every lane is the scalar walk).

  scripts/bench_packet_width.py [--kdray build/kdray] [--peer EMBREE_REF] [--rounds 3]
                                [--repeat 5] [--scene bunny/bunny.obj] [--out docs/packet-width]

--scene: another of ../shared's scenes (its folder's render.json): dense meshes of tiny
triangles, such as dragon/dragon_res2.obj, are where the narrower packet may win.

Writes OUT.json (every round's figures, the command, the machine, the device and its native float
width) and OUT.md. Needs ../shared (the scene); without it, says so and exits 77.
"""
import argparse
import filecmp
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import (ROOT, SHARED, build_peer, median, run_json, run_record,  # noqa: E402
                          write_json, write_markdown)
from bench_render import THREADS, primary_only  # noqa: E402

SCENE = "bunny/bunny.obj"
LANES = [8, 16]


def native_float_width():
    """What clinfo says of the first device's float vector width (preferred / native), or None."""
    try:
        out = subprocess.run(["clinfo"], capture_output=True, text=True, check=True).stdout
    except (OSError, subprocess.CalledProcessError):
        return None
    for line in out.splitlines():
        parts = line.split()
        if parts[:1] == ["float"] and "/" in parts:
            return " / ".join(parts[1:4:2])
    return None


def kdray_run(kdray, obj, render, lanes, repeat, out):
    """One kdray process of `repeat` warm frames of the OBJ at the given packet width; returns
    the medians of its frames and the path of the last frame's image."""
    frames_dir = os.path.join(out, "frames")
    os.makedirs(frames_dir, exist_ok=True)
    objs = []
    for k in range(repeat):
        link = os.path.join(frames_dir, f"f_{k}.obj")
        if not os.path.lexists(link):
            os.symlink(obj, link)
        objs.append(link)
    env = dict(os.environ, KDRAY_PACKET_LANES=str(lanes))
    images = os.path.join(out, f"lanes{lanes}")
    subprocess.run([kdray, "render", *objs, "--camera", render, "-o", images, "-q", "--warm-up"],
                   check=True, capture_output=True, text=True, env=env)
    with open(os.path.join(images, "stats.json")) as f:
        frames = json.load(f)["frames"]
    ran = {f["packets"].get("lanes") for f in frames}
    if ran != {lanes} or not all(f["packets"]["primary"] for f in frames):
        raise RuntimeError(f"asked for packets of {lanes} lanes, ran {sorted(map(str, ran))}")
    return ({"trace_ms": median([f["trace_ms"] for f in frames]),
             "mrays_per_s": median([f["mrays_per_s"] for f in frames]),
             "primary_rays": frames[0]["rays"]["primary"],
             "triangles": frames[0]["scene"]["triangles"]},
            os.path.join(images, f"f_{repeat - 1}.png"))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--peer", default="", help="embree_ref (default: build the peer)")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--scene", default=SCENE, help="under ../shared/scenes")
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "packet-width"))
    args = parser.parse_args()
    obj = os.path.join(SHARED, "scenes", args.scene)
    if not os.path.isfile(obj):
        print(f"bench_packet_width: skipped: no {args.scene} under {SHARED}/scenes")
        return 77
    peer = args.peer or build_peer()
    device = run_json([args.kdray, "stats", "--json"]).get("devices", [{}])[0].get("name", "?")
    runs = {"kdray_lanes8": [], "kdray_lanes16": [], "embree": []}
    load_before = os.getloadavg()[0]
    with tempfile.TemporaryDirectory(prefix="kdray-packet-width-") as tmp:
        render = primary_only(os.path.join(os.path.dirname(obj), "render.json"),
                              os.path.join(tmp, "primary.json"))
        for r in range(args.rounds):
            images = {}
            for lanes in LANES if r % 2 == 0 else reversed(LANES):
                row, images[lanes] = kdray_run(args.kdray, obj, render, lanes, args.repeat, tmp)
                runs[f"kdray_lanes{lanes}"].append(row)
            if not filecmp.cmp(images[8], images[16], shallow=False):
                raise RuntimeError("packets of 8 and 16 lanes wrote different images")
            if peer:
                emb = run_json([peer, obj, "--camera", render, "--quality", "medium",
                                "--repeat", str(args.repeat), "--threads", str(THREADS)])
                runs["embree"].append({"trace_ms": emb["trace_ms"],
                                       "mrays_per_s": emb["mrays_per_s"]})
            print(f"round {r}: " + ", ".join(f"{k} {v[-1]['mrays_per_s']:.2f} Mrays/s"
                                             for k, v in runs.items() if v), file=sys.stderr)
    summary = {k: {key: median([run[key] for run in v]) for key in ("trace_ms", "mrays_per_s")}
               for k, v in runs.items() if v}
    # Ratios within each round, whose runs follow one another, drift less than ratios of medians
    # when other work comes and goes on a shared machine.
    def ratio(a, b):
        return median([x["mrays_per_s"] / y["mrays_per_s"] for x, y in zip(runs[a], runs[b])])

    ratios = {"lanes16_over_lanes8": ratio("kdray_lanes16", "kdray_lanes8")}
    if runs["embree"]:
        ratios.update(lanes8_x_embree=ratio("kdray_lanes8", "embree"),
                      lanes16_x_embree=ratio("kdray_lanes16", "embree"))
    first = runs["kdray_lanes16"][0]
    record = dict(run_record(args.kdray), device=device,
                  native_float_width=native_float_width(), scene=args.scene,
                  triangles=first["triangles"], primary_rays=first["primary_rays"],
                  rounds=args.rounds, repeat=args.repeat, threads=THREADS,
                  load_average=[round(load_before, 2), round(os.getloadavg()[0], 2)],
                  runs=runs, summary=summary, ratios=ratios)
    write_json(args.out + ".json", record)

    lines = ["# Packet width: primary rays at 8 and 16 lanes", "",
             f"Run {record['date']} at {record['commit']} on {record['machine']}.", "",
             f"OpenCL device: PoCL '{device}', float vector width (preferred / native, clinfo): "
             f"{record['native_float_width'] or 'unknown'}; kdray's automatic choice there is the "
             "native width (16 on AVX-512, 8 on AVX2).", "",
             f"{args.scene} ({record['triangles']} triangles), its render file's camera and size "
             f"({record['primary_rays']} primary rays, no lights, max_depth 1), warm "
             f"(`--warm-up`); medians over {args.rounds} rounds of each run's median over "
             f"{args.repeat} frames; Embree 3 medium's primary rays in the same rounds "
             f"({THREADS} threads). The machine's 1-minute load average was "
             f"{record['load_average'][0]} before and {record['load_average'][1]} after (other "
             "work shared its cores: the per-round figures in the JSON show the spread). Written "
             "by `scripts/bench_packet_width.py`.", "",
             "| tracer | trace ms | Mrays/s | x Embree Mrays/s, same round |",
             "|---|---:|---:|---:|"]
    names = {"kdray_lanes8": "kdray, packets of 8 (float8, 4x2)",
             "kdray_lanes16": "kdray, packets of 16 (float16, 4x4)", "embree": "Embree 3 medium"}
    x_embree = {"kdray_lanes8": ratios.get("lanes8_x_embree"),
                "kdray_lanes16": ratios.get("lanes16_x_embree"), "embree": 1.0}
    for key, s in summary.items():
        x = f"{x_embree[key]:.2f}" if x_embree[key] else ""
        lines.append(f"| {names[key]} | {s['trace_ms']:.1f} | {s['mrays_per_s']:.2f} | {x} |")
    lines += ["", f"Packets of 16 over packets of 8, Mrays/s in the same round (median): "
              f"{ratios['lanes16_over_lanes8']:.2f}x. Both widths wrote the same image in every "
              "round."]
    write_markdown(args.out, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
