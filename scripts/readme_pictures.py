#!/usr/bin/env python3
"""The README's pictures of light transport and of the tree, each made by one `kdray render` a
user can type (the commands are printed and kept in OUT.json):

1. CornellBox-Original rendered by the Whitted integrator (its shared render.json: direct light of
   the panel, no indirect light) beside the path integrator
   (scripts/render-files/cornell-box-path.json): docs/cornell-whitted-path.png.
2. The bunny beside its --heatmap (the kd-tree walk cost of each centre ray):
   docs/bunny-heatmap.png.

    scripts/readme_pictures.py [--kdray build/kdray] [--out docs]

Needs ../shared (the scenes) and oiiotool (the side-by-side mosaics); without ../shared it says
so and exits 77.
"""
import argparse
import json
import os
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import ROOT, SHARED, run_record, write_json  # noqa: E402


def render(kdray, obj, render_file, out, extra=()):
    """One `kdray render` into `out`; its frame record and the command as a user types it from
    the repository root (the output folder shown as out/NAME)."""
    command = [kdray, "render", obj, "--camera", render_file, "-o", out, "-q", *extra]
    subprocess.run(command, check=True, capture_output=True, text=True)
    with open(os.path.join(out, "stats.json")) as f:
        frame = json.load(f)["frames"][0]
    shown = [os.path.relpath(a, ROOT) if os.path.isabs(a) else a for a in command[1:]]
    shown[shown.index("-o") + 1] = "out/" + os.path.basename(out)
    return frame, "build/kdray " + " ".join(shown)


def mosaic(tiles, path):
    subprocess.run(["oiiotool", *tiles, "--mosaic", f"{len(tiles)}x1", "-o", path], check=True,
                   capture_output=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--out", default=os.path.join(ROOT, "docs"))
    args = parser.parse_args()
    scenes = os.path.join(SHARED, "scenes")
    if not os.path.isdir(scenes):
        print(f"readme_pictures: skipped: {scenes} is absent")
        return 77
    pictures = []
    with tempfile.TemporaryDirectory(prefix="kdray-pictures-") as tmp:
        box = os.path.join(scenes, "cornell-box", "CornellBox-Original.obj")
        whitted, whitted_cmd = render(args.kdray, box,
                                      os.path.join(scenes, "cornell-box", "render.json"),
                                      os.path.join(tmp, "whitted"), ["--spp", "64"])
        path, path_cmd = render(args.kdray, box,
                                os.path.join(ROOT, "scripts", "render-files",
                                             "cornell-box-path.json"),
                                os.path.join(tmp, "path"))
        target = os.path.join(args.out, "cornell-whitted-path.png")
        mosaic([os.path.join(tmp, "whitted", whitted["image"]),
                os.path.join(tmp, "path", path["image"])], target)
        pictures.append({"file": os.path.relpath(target, ROOT),
                         "commands": [whitted_cmd, path_cmd],
                         "trace_ms": [whitted["trace_ms"], path["trace_ms"]]})
        bunny = os.path.join(scenes, "bunny", "bunny.obj")
        frame, bunny_cmd = render(args.kdray, bunny, os.path.join(scenes, "bunny", "render.json"),
                                  os.path.join(tmp, "bunny"), ["--heatmap", "--size", "512x384"])
        stem = os.path.splitext(frame["image"])[0]
        target = os.path.join(args.out, "bunny-heatmap.png")
        mosaic([os.path.join(tmp, "bunny", frame["image"]),
                os.path.join(tmp, "bunny", stem + ".cost.png")], target)
        pictures.append({"file": os.path.relpath(target, ROOT), "commands": [bunny_cmd],
                         "heatmap": frame.get("heatmap")})
    write_json(os.path.join(args.out, "readme-pictures.json"),
               {**run_record(args.kdray), "pictures": pictures})
    for p in pictures:
        print(p["file"], "<-", " ; ".join(p["commands"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
