#!/usr/bin/env python3
"""Render benchmark: kdray's OpenCL build + trace against the Embree peer, side by side in one
run, with the same camera and thread count.

1. Primary rays, per scene: Mrays/s of kdray's OpenCL tracer (render file without lights and
   max_depth 1, materials without emission, so only centre rays are cast: the script checks
   stats.json's ray counts) against embree_ref's, median over --repeat frames.
2. Dynamic scenes (the BART Kitchen and Robots frames, horse poses, testdata/anim): mean frame time
   of kdray (OpenCL build + trace, primary rays, 1024x768) against Embree medium's build + trace of
   the same frames with the same keyframed cameras; three rounds of both sides in turn, each
   frame's figure its median over the rounds.
3. The glass room (testdata/cornell) at 1 spp, 640x480, with every effect.
Writes docs/bench-render.md, .csv and .json with the commit, machine and command.

  scripts/bench_render.py --kdray build/kdray [--repeat 3] [--scenes SUBSTR]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import (ROOT, SHARED, benchmark_scenes, build_peer, median,  # noqa
                          run_json, run_record, write_json, write_report)

THREADS = os.cpu_count()
# Dynamic scenes: rounds of both sides in turn, and the peer's builds and traces per frame in a
# round (it reports their median).
ROUNDS = 3
PEER_REPEAT = 3


def camera_at(keys, frame):
    """conventions.md's keyframed camera: linear between keys, the nearest key held outside."""
    keys = sorted(keys, key=lambda k: k["frame"])
    fields = ("position", "look_at", "up", "fov_y")
    lo = max((k for k in keys if k["frame"] <= frame), key=lambda k: k["frame"], default=keys[0])
    hi = min((k for k in keys if k["frame"] >= frame), key=lambda k: k["frame"], default=keys[-1])
    t = 0.0 if hi["frame"] == lo["frame"] else (frame - lo["frame"]) / (hi["frame"] - lo["frame"])
    out = {}
    for f in fields:
        if f in lo:
            a, b = lo[f], hi.get(f, lo[f])
            out[f] = ([x + (y - x) * t for x, y in zip(a, b)] if isinstance(a, list)
                      else a + (b - a) * t)
    return out


def primary_only(render_json, out_path, frame=None):
    """The render file with no lights and max_depth 1 (and, for a keyframed camera, only the key
    of `frame` so that the peer, which takes the first key, sees the same camera)."""
    with open(render_json) as f:
        j = json.load(f)
    j["lights"] = []
    j["max_depth"] = 1
    j.setdefault("image", {})["spp"] = 1
    if isinstance(j.get("camera"), list):
        j["camera"] = camera_at(j["camera"], frame or 0)
    with open(out_path, "w") as f:
        json.dump(j, f)
    return out_path


def kdray_frames(kdray, objs, render_json, out_dir):
    """Renders the frames in one process; returns the per-frame records of stats.json."""
    subprocess.run([kdray, "render", *objs, "--camera", render_json, "-o", out_dir, "-q",
                    "--warm-up", "--overwrite"],
                   check=True, capture_output=True, text=True)
    with open(os.path.join(out_dir, "stats.json")) as f:
        return json.load(f)["frames"]


def write_without_emission(mtl, out_path):
    """The material library with every Ke zeroed: an emitter would make kdray cast area-light
    shadow rays from each hit, which the peer does not, and the rows compare primary rays only."""
    with open(mtl, errors="replace") as f:
        lines = [("Ke 0 0 0\n" if line.split()[:1] == ["Ke"] else line) for line in f]
    with open(out_path, "w") as f:
        f.writelines(lines)


def primary_rays(kdray, peer, repeat, scenes, tmp):
    rows = []
    for name, obj, camera in scenes:
        render = primary_only(camera, os.path.join(tmp, "primary.json"), frame=0)
        # The same OBJ under `repeat` names (kdray's --warm-up keeps program builds out).
        frames_dir = os.path.join(tmp, "frames")
        shutil.rmtree(frames_dir, ignore_errors=True)
        os.makedirs(frames_dir)
        for mtl in (f for f in os.listdir(os.path.dirname(obj)) if f.endswith(".mtl")):
            write_without_emission(os.path.join(os.path.dirname(obj), mtl),
                                   os.path.join(frames_dir, mtl))
        objs = []
        for k in range(repeat):
            link = os.path.join(frames_dir, f"f_{k}.obj")
            os.symlink(obj, link)
            objs.append(link)
        frames = kdray_frames(kdray, objs, render, os.path.join(tmp, "out"))
        extra = {k: v for k, v in frames[0]["rays"].items() if k != "primary" and v}
        if extra:
            raise SystemExit(f"bench_render: {name}: kdray cast more than primary rays {extra}")
        row = {"scene": name, "triangles": frames[0]["scene"]["triangles"],
               "kdray_mrays_per_s": median([f["mrays_per_s"] for f in frames]),
               "kdray_trace_ms": median([f["trace_ms"] for f in frames]),
               "kdray_build_ms": median([f["build_ms"] for f in frames])}
        if peer:
            emb = run_json([peer, obj, "--camera", render, "--quality", "medium",
                            "--repeat", str(repeat), "--threads", str(THREADS)])
            row.update(embree_mrays_per_s=emb["mrays_per_s"], embree_trace_ms=emb["trace_ms"],
                       embree_build_ms=emb["build_ms"])
        rows.append(row)
        print(f"primary {name}: {row}", file=sys.stderr)
    return rows


def dynamic_scenes():
    found = []
    for folder in ("bart-kitchen", "bart-robots", "horse-poses"):
        path = os.path.join(SHARED, "scenes", folder)
        if os.path.isdir(path):
            objs = sorted(os.path.join(path, f) for f in os.listdir(path) if f.startswith("frame_"))
            found.append((folder, objs, os.path.join(path, "render.json")))
    anim = os.path.join(ROOT, "testdata", "anim")
    found.append(("testdata/anim", sorted(os.path.join(anim, f) for f in os.listdir(anim)
                                          if f.endswith(".obj")), os.path.join(anim, "render.json")))
    return found


def primary_sequence(render_json, out_path):
    """The render file with no lights and max_depth 1, its keyframed camera kept: primary rays
    of a whole sequence in one kdray run."""
    with open(render_json) as f:
        j = json.load(f)
    j["lights"] = []
    j["max_depth"] = 1
    with open(out_path, "w") as f:
        json.dump(j, f)
    return out_path


def dynamic(kdray, peer, tmp):
    rows = []
    for name, objs, camera in dynamic_scenes():
        render = primary_sequence(camera, os.path.join(tmp, "dynamic.json"))
        # ROUNDS rounds, each of one kdray run of the sequence and the peer's build and trace of
        # every frame (the median of PEER_REPEAT in its process), so that both sides meet the
        # machine's slower and faster minutes alike; a frame's figure is its median over rounds.
        kd_runs, peer_runs = [], []
        for _ in range(ROUNDS):
            kd_runs.append(kdray_frames(kdray, objs, render, os.path.join(tmp, "dyn")))
            if peer:
                em = []
                for k, obj in enumerate(objs):
                    cam = primary_only(camera, os.path.join(tmp, "peer.json"), frame=k)
                    r = run_json([peer, obj, "--camera", cam, "--quality", "medium", "--repeat",
                                  str(PEER_REPEAT), "--threads", str(THREADS)])
                    em.append(r["build_ms"] + r["trace_ms"])
                peer_runs.append(em)
        build = [median([r[k]["build_ms"] for r in kd_runs]) for k in range(len(objs))]
        trace = [median([r[k]["trace_ms"] for r in kd_runs]) for k in range(len(objs))]
        # A frame's figure is the median of its build + trace, as the peer's is.
        frame = [median([r[k]["build_ms"] + r[k]["trace_ms"] for r in kd_runs])
                 for k in range(len(objs))]
        row = {"scene": name, "frames": len(objs), "triangles": kd_runs[0][0]["scene"]["triangles"],
               "kdray_frame_ms": sum(frame) / len(objs),
               "kdray_build_ms": sum(build) / len(objs),
               "kdray_trace_ms": sum(trace) / len(objs)}
        if peer:
            em = [median([r[k] for r in peer_runs]) for k in range(len(objs))]
            row["embree_frame_ms"] = sum(em) / len(em)
        rows.append(row)
        print(f"dynamic {name}: {row}", file=sys.stderr)
    return rows


def glass_room(kdray, tmp):
    room = os.path.join(ROOT, "testdata", "cornell")
    objs = [os.path.join(room, "room.obj")] * 1
    out = os.path.join(tmp, "glass")
    link_dir = os.path.join(tmp, "glass-in")
    os.makedirs(link_dir, exist_ok=True)
    for f in os.listdir(room):
        if f.endswith(".mtl"):
            os.symlink(os.path.join(room, f), os.path.join(link_dir, f))
    objs = []
    for k in range(4):
        os.symlink(os.path.join(room, "room.obj"), os.path.join(link_dir, f"room_{k}.obj"))
        objs.append(os.path.join(link_dir, f"room_{k}.obj"))
    frames = kdray_frames(kdray, objs, os.path.join(room, "render.json"), out)
    return {"frame_ms": median([f["frame_ms"] for f in frames]),
            "build_ms": median([f["build_ms"] for f in frames]),
            "trace_ms": median([f["trace_ms"] for f in frames]),
            "rays": frames[-1]["rays"], "effects": frames[-1]["effects"]}


def ratio(a, b):
    return f"{a / b:.2f}" if a and b else ""


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--repeat", type=int, default=3)
    parser.add_argument("--scenes", default="")
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "bench-render"))
    args = parser.parse_args()
    peer = build_peer()
    with tempfile.TemporaryDirectory(prefix="kdray-bench-") as tmp:
        scenes = [s for s in benchmark_scenes() if args.scenes in s[0]]
        prim = primary_rays(args.kdray, peer, args.repeat, scenes, tmp)
        dyn = dynamic(args.kdray, peer, tmp)
        glass = glass_room(args.kdray, tmp)

    record = run_record(args.kdray)
    lines = ["# Render benchmark", "",
             f"Run {record['date']} at {record['commit']} on {record['machine']}; "
             f"Embree with {THREADS} threads.", "",
             "## Primary rays (1 per pixel centre, no shading beyond a headlight; emitters "
             "turned off)", "",
             "| scene | triangles | kdray OpenCL Mrays/s | Embree Mrays/s | kdray / Embree |",
             "|---|---:|---:|---:|---:|"]
    for r in prim:
        lines.append(f"| {r['scene']} | {r['triangles']} | {r['kdray_mrays_per_s']:.2f} | "
                     f"{r.get('embree_mrays_per_s', 0):.2f} | "
                     f"{ratio(r['kdray_mrays_per_s'], r.get('embree_mrays_per_s'))} |")
    lines += ["", "## Dynamic scenes: mean frame time, build + trace of primary rays", "",
              f"{ROUNDS} rounds of both sides in turn: per round one kdray run of the sequence "
              "(one process, after a warm-up frame) and, per frame, the peer's median of "
              f"{PEER_REPEAT} builds and traces in one process; a frame's figure is its median "
              "over the rounds, and the build and trace columns are their own medians.", "",
              "| sequence | frames | triangles | kdray build ms | kdray trace ms | kdray frame ms "
              "| Embree medium frame ms | kdray / Embree |", "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for r in dyn:
        lines.append(f"| {r['scene']} | {r['frames']} | {r['triangles']} | {r['kdray_build_ms']:.1f} "
                     f"| {r['kdray_trace_ms']:.1f} | {r['kdray_frame_ms']:.1f} | "
                     f"{r.get('embree_frame_ms', 0):.1f} | "
                     f"{ratio(r['kdray_frame_ms'], r.get('embree_frame_ms'))} |")
    lines += ["", "## Glass room (testdata/cornell), 640x480, 1 spp, shadows + reflection + refraction",
              "", f"Frame {glass['frame_ms']:.0f} ms (build {glass['build_ms']:.1f} ms, trace "
              f"{glass['trace_ms']:.0f} ms); rays {json.dumps(glass['rays'])}."]
    rows = [dict(kind="primary", **r) for r in prim] + [dict(kind="dynamic", **r) for r in dyn]
    write_report(args.out, lines, rows)
    write_json(args.out + ".json", {**record, "threads": THREADS, "rows": rows,
                                    "glass_room": glass})
    return 0


if __name__ == "__main__":
    sys.exit(main())
