#!/usr/bin/env python3
"""The README's pictures, each made by `kdray render` commands a user can type (the commands are
printed and kept in JSON beside them):

0. What scripts/demo.sh renders, with its commands: the bundled glass room and frames 0, 4 and 8
   of the bundled animation: docs/demo.png, docs/demo.json. Needs only the repository.
1. CornellBox-Original rendered by the Whitted integrator (its shared render.json: direct light of
   the panel, no indirect light) beside the path integrator
   (scripts/render-files/cornell-box-path.json): docs/cornell-whitted-path.png.
2. The bunny beside its --heatmap (the kd-tree walk cost of each centre ray):
   docs/bunny-heatmap.png.

    scripts/readme_pictures.py [--kdray build/kdray] [--out docs]

The others (kept in docs/readme-pictures.json) need ../shared (the scenes); without it the script
makes the demo's picture only, says so and exits 77. oiiotool makes the mosaics.
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
    command = [kdray, "render", obj, "--render-file", render_file, *extra, "-o", out, "-q"]
    subprocess.run(command, check=True, capture_output=True, text=True)
    with open(os.path.join(out, "stats.json")) as f:
        frames = json.load(f)["frames"]
    frame = frames[0] if len(frames) == 1 else frames
    shown = [os.path.relpath(a, ROOT) if os.path.isabs(a) else a for a in command[1:]]
    shown[shown.index("-o") + 1] = "out/" + os.path.basename(out)
    shown = [f"'{a}'" if "*" in a else a for a in shown]
    return frame, "build/kdray " + " ".join(a for a in shown if a != "-q")


def mosaic(tiles, path):
    subprocess.run(["oiiotool", *tiles, "--mosaic", f"{len(tiles)}x1", "-o", path], check=True,
                   capture_output=True)


def demo_picture(kdray, out_dir):
    """scripts/demo.sh's two renders (the same commands, run from the repository root) as one
    picture: the room, then frames 0, 4 and 8 of the animation below it."""
    with tempfile.TemporaryDirectory(prefix="kdray-demo-") as tmp:
        cwd = os.getcwd()
        os.chdir(ROOT)
        try:
            room, room_cmd = render(kdray, "testdata/cornell/room.obj",
                                    "testdata/cornell/render.json", os.path.join(tmp, "cornell"),
                                    ["--spp", "16"])
            anim, anim_cmd = render(kdray, "testdata/anim/frame_*.obj",
                                    "testdata/anim/render.json", os.path.join(tmp, "anim"))
        finally:
            os.chdir(cwd)
        strip = os.path.join(tmp, "strip.png")
        subprocess.run(["oiiotool", *[os.path.join(tmp, "anim", anim[i]["image"])
                                      for i in (0, 4, 8)],
                        "--mosaic", "3x1", "--resize", "960x0", "-o", strip],
                       check=True, capture_output=True)
        room_image = os.path.join(tmp, "room.png")
        subprocess.run(["oiiotool", os.path.join(tmp, "cornell", room["image"]), "--resize",
                        "960x0", "-o", room_image], check=True, capture_output=True)
        target = os.path.join(out_dir, "demo.png")
        # A canvas the room is pasted into at the top and the strip below it (oiiotool's
        # --paste takes the foreground first).
        subprocess.run(["oiiotool", room_image, "--create", "960x900", "3", "--paste", "+0+0",
                        strip, "--swap", "--paste", "+0+720", "-o", target],
                       check=True, capture_output=True)
    write_json(os.path.join(out_dir, "demo.json"),
               {**run_record(kdray), "file": os.path.relpath(target, ROOT),
                "commands": [room_cmd, anim_cmd],
                "room_trace_ms": room["trace_ms"],
                "animation_frame_ms": [f["frame_ms"] for f in anim]})
    print(os.path.relpath(target, ROOT), "<-", room_cmd, ";", anim_cmd)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--out", default=os.path.join(ROOT, "docs"))
    args = parser.parse_args()
    demo_picture(os.path.abspath(args.kdray), args.out)
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
