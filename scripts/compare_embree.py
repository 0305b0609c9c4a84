#!/usr/bin/env python3
"""Renders the shared scenes with kdray and with the Embree peer and compares the hit AOVs.

For every scene folder under ../shared/scenes with a render.json, each OBJ in it (the first frame
only of an animation, since the peer uses the first camera key) is rendered by
`kdray render --aov` and by `embree_ref --aov`, and `embree_ref --compare` counts the pixels that
disagree (conventions.md). A scene passes when mismatch_fraction <= 1e-4.

Exit status: 0 all agree; 1 some disagree, a run failed, or ../shared is there but has no scene
folder with a render.json and an OBJ, or its Embree peer does not build (each says which); 77
only when ../shared itself is absent, so that CTest reports a skip.

  scripts/compare_embree.py --kdray build/kdray [--builder reference] [--tracer reference]
      [--quality low,medium,high] [--small-stage auto|per-root|per-level]
      [--large-stage auto|chunked|level|depth-first]
                            [--quick] [--peer PATH]
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
# KDRAY_SHARED_DIR points elsewhere (a test of the failures below).
SHARED = os.environ.get("KDRAY_SHARED_DIR") or os.path.normpath(os.path.join(ROOT, "..", "shared"))
SKIP = 77

# Scenes too big for a quick run (seconds of CPU reference build each); --quick leaves them out.
SLOW = {"dragon_res2.obj", "sponza.obj"}


def scene_files(quick):
    scenes_dir = os.path.join(SHARED, "scenes")
    for folder in sorted(os.listdir(scenes_dir)):
        camera = os.path.join(scenes_dir, folder, "render.json")
        if not os.path.isfile(camera):
            continue
        objs = sorted(f for f in os.listdir(os.path.join(scenes_dir, folder)) if f.endswith(".obj"))
        if any(f.startswith("frame_") for f in objs):
            objs = [f for f in objs if f.startswith("frame_")][:1]
        for obj in objs:
            if quick and obj in SLOW:
                continue
            yield folder, os.path.join(scenes_dir, folder, obj), camera


def build_peer(out_dir):
    script = os.path.join(SHARED, "peers", "embree", "build.sh")
    if not os.path.isfile(script):
        return None
    result = subprocess.run(["bash", script, out_dir], capture_output=True, text=True)
    if result.returncode != 0:
        print("compare_embree: cannot build the Embree peer (install libembree-dev: "
              "scripts/install-deps.sh --peer):\n" + result.stderr, file=sys.stderr)
        return None
    return result.stdout.strip().splitlines()[-1]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kdray", required=True)
    parser.add_argument("--builder", default="reference")
    parser.add_argument("--tracer", default="reference")
    parser.add_argument("--peer", help="a built embree_ref (default: build it into a temp dir)")
    parser.add_argument("--peer-dir", help="build the peer into this folder once and reuse it")
    parser.add_argument("--quick", action="store_true", help="leave out the slowest scenes")
    parser.add_argument("--max-mismatch", type=float, default=1e-4)
    parser.add_argument("--quality", default="",
                        help="OpenCL builder: comma-separated build qualities to render each scene "
                             "at, each compared with Embree (default: kdray's default)")
    parser.add_argument("--small-stage", default="",
                        help="OpenCL builder: the small stage's shape (default: kdray's auto); "
                             "a scene whose stats.json names another shape fails")
    parser.add_argument("--large-stage", default="",
                        help="OpenCL builder: the large stage's shape (default: kdray's auto); "
                             "a scene whose stats.json names another shape fails")
    args = parser.parse_args()

    if not os.path.isdir(SHARED):
        print(f"compare_embree: skipped: {SHARED} is absent")
        return SKIP
    scenes = list(scene_files(args.quick)) if os.path.isdir(os.path.join(SHARED, "scenes")) \
        else []
    if not scenes:
        print(f"compare_embree: FAIL: {SHARED} exists but {os.path.join(SHARED, 'scenes')} has no "
              "scene folder with a render.json and an OBJ", file=sys.stderr)
        return 1
    with tempfile.TemporaryDirectory(prefix="kdray-compare-") as tmp:
        peer = args.peer
        if not peer and args.peer_dir:
            built = os.path.join(args.peer_dir, "embree_ref")
            peer = built if os.path.isfile(built) else build_peer(args.peer_dir)
        if not peer:
            peer = build_peer(os.path.join(tmp, "peer"))
        if not peer:
            print(f"compare_embree: FAIL: {SHARED} exists but its Embree peer "
                  "(peers/embree/build.sh) is missing or does not build", file=sys.stderr)
            return 1
        failures = 0
        qualities = [q for q in args.quality.split(",") if q] or [None]
        for folder, obj, camera in scenes:
            stem = os.path.splitext(os.path.basename(obj))[0]
            theirs = os.path.join(tmp, f"{folder}-{stem}.embree.exr")
            subprocess.run([peer, obj, "--camera", camera, "--aov", theirs, "--repeat", "1"],
                           check=True, capture_output=True)
            for quality in qualities:
                name = f"{folder}/{os.path.basename(obj)}" + (f" at {quality}" if quality else "")
                out = os.path.join(tmp, folder)
                start = time.time()
                run = subprocess.run([args.kdray, "render", obj, "--camera", camera, "--aov", "-q",
                                      "--builder", args.builder, "--tracer", args.tracer, "-o", out,
                                      # each quality replaces the one before in the folder
                                      "--overwrite"]
                                     + (["--quality", quality] if quality else [])
                                     + (["--small-stage", args.small_stage]
                                        if args.small_stage else [])
                                     + (["--large-stage", args.large_stage]
                                        if args.large_stage else []),
                                     capture_output=True, text=True)
                if run.returncode != 0:
                    print(f"FAIL {name}: kdray: {run.stderr.strip()}")
                    failures += 1
                    continue
                with open(os.path.join(out, "stats.json")) as f:
                    tree = json.load(f)["frames"][0]["tree"]
                wrong = [f"the {asked} {key.replace('_', ' ')}, stats.json says {tree.get(key)}"
                         for key, asked in (("small_stage", args.small_stage),
                                            ("large_stage", args.large_stage))
                         if asked not in ("", "auto") and tree.get(key) != asked]
                if wrong:
                    print(f"FAIL {name}: asked for " + "; ".join(wrong))
                    failures += 1
                    continue
                kdray_seconds = time.time() - start
                ours = os.path.join(out, stem + ".aov.exr")
                cmp = subprocess.run([peer, "--compare", ours, theirs], check=True,
                                     capture_output=True, text=True)
                counts = json.loads(cmp.stdout)
                ok = counts["mismatch_fraction"] <= args.max_mismatch
                failures += not ok
                print(f"{'ok  ' if ok else 'FAIL'} {name}: mismatch_fraction "
                      f"{counts['mismatch_fraction']:.2e} (hit/miss {counts['hit_miss_mismatch']}, "
                      f"distance {counts['distance_mismatch']}, tie {counts['prim_tie_mismatch']} "
                      f"of {counts['pixels']}), kdray {kdray_seconds:.1f} s")
        print(f"compare_embree: {failures} scene(s) disagree" if failures else
              "compare_embree: every scene agrees with Embree")
        return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
