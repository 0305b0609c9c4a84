#!/usr/bin/env python3
"""A contact sheet of the scene effects on the shared scenes: Sponza path-traced with its textures,
the Cornell box path-traced, lit by its ceiling panel, the BART Kitchen and Robots with their
ambient term. Each tile is one `kdray render` a user can type: the scene, a render file that is
either the scene's own (../shared/scenes/*/render.json) or one kdray ships for it
(scripts/render-files/*.json, for what the shared file lacks: the path integrator, ambient light),
and command-line options only for the tile's size and samples. The tiles are joined with
`oiiotool --mosaic` into docs/scene-effects.png; the commands, and the effects each frame's
stats.json lists, go to docs/scene-effects.json. Beside them, what each effect costs where a scene
calls for it: the same frame traced with the effect and without it (textures: Sponza, its MTL
without map_Kd and map_Ka; area lights: CornellBox-Original at 16 spp, its MTL without Ke;
ambient: the Kitchen's frame 0 with scripts/render-files/bart-kitchen.json and with its own render
file, which has no ambient light), each the median trace_ms of --repeat runs taken in turn.

  scripts/contact_sheet.py --kdray build/kdray [--out docs/scene-effects] [--repeat 3]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import ROOT, SHARED, median, run_record  # noqa

TILE = "384x288"
RENDER_FILES = os.path.join(ROOT, "scripts", "render-files")
# scene folder, OBJ, render file (None: the scene's own), options beyond the tile's size, what it shows
SHOTS = [
    ("sponza-dabrovic", "sponza.obj", "sponza.json", [],
     "textures (map_Kd), path-traced: the arcades lit by the light the courtyard reflects"),
    ("cornell-box", "CornellBox-Original.obj", "cornell-box-path.json", [],
     "lit by its emissive panel, path-traced: soft shadows, the walls' colours on the boxes"),
    ("bart-kitchen", "frame_000.obj", "bart-kitchen.json", [], "BART's ambient term (Ka)"),
    ("bart-robots", "frame_000.obj", "bart-robots.json", [], "BART's ambient term (Ka)"),
]


def scene_render_file(folder, shipped):
    return os.path.join(RENDER_FILES, shipped) if shipped else \
        os.path.join(SHARED, "scenes", folder, "render.json")


def render_once(kdray, obj, render_file, options, out):
    """One `kdray render` into `out`: its frame record, and the command as a user types it from
    the repository root (the output folder shown as out/)."""
    command = [kdray, "render", obj, "--render-file", render_file, *options, "-o", out, "-q",
               "--overwrite"]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"contact_sheet: {obj}: {result.stderr.strip()}")
    with open(os.path.join(out, "stats.json")) as f:
        frame = json.load(f)["frames"][0]
    shown = [os.path.relpath(a, ROOT) if os.path.isabs(a) else a for a in command[1:]]
    shown[shown.index("-o") + 1] = "out/"
    return frame, "build/kdray " + " ".join(a for a in shown if a not in ("-q", "--overwrite"))


def scene_copy(folder, obj, tmp, drop):
    """The OBJ and its MTL libraries copied to a folder of their own, MTL lines starting with one
    of `drop` left out (textures then resolve to nothing: the untextured scene)."""
    src = os.path.join(SHARED, "scenes", folder)
    dst = os.path.join(tmp, "without-" + folder)
    os.makedirs(dst, exist_ok=True)
    shutil.copy(os.path.join(src, obj), dst)
    for name in os.listdir(src):
        if name.lower().endswith(".mtl"):
            with open(os.path.join(src, name), errors="replace") as f:
                lines = [l for l in f if not l.strip().startswith(drop)]
            with open(os.path.join(dst, name), "w") as f:
                f.writelines(lines)
    return os.path.join(dst, obj)


def effect_costs(kdray, tmp, repeat):
    """Per effect: the trace time of a frame that calls for it, with the effect and without."""
    # effect, folder, OBJ, render file with it, without it (None: the scene's own), options,
    # MTL statements dropped for the frame without it
    cases = [
        ("textures", "sponza-dabrovic", "sponza.obj", None, None, [], ("map_Kd", "map_Ka")),
        ("area_lights", "cornell-box", "CornellBox-Original.obj", None, None, ["--spp", "16"],
         ("Ke",)),
        ("ambient", "bart-kitchen", "frame_000.obj", "bart-kitchen.json", None, [], ()),
    ]
    rows = []
    for effect, folder, obj, with_file, without_file, options, drop in cases:
        with_obj = os.path.join(SHARED, "scenes", folder, obj)
        without_obj = scene_copy(folder, obj, tmp, drop) if drop else with_obj
        with_render = scene_render_file(folder, with_file)
        without_render = scene_render_file(folder, without_file)
        on, off = [], []
        for _ in range(repeat):
            frame, _ = render_once(kdray, with_obj, with_render, options, os.path.join(tmp, "on"))
            if not frame["effects"].get(effect):
                sys.exit(f"contact_sheet: {folder} does not call for {effect}")
            on.append(frame["trace_ms"])
            frame, _ = render_once(kdray, without_obj, without_render, options,
                                   os.path.join(tmp, "off"))
            if frame["effects"].get(effect):
                sys.exit(f"contact_sheet: {folder} still calls for {effect} without it")
            off.append(frame["trace_ms"])
        row = {"effect": effect, "scene": f"{folder}/{obj}", "with_trace_ms": median(on),
               "without_trace_ms": median(off), "ratio": median(on) / median(off)}
        rows.append(row)
        print(f"cost of {effect} on {folder}: {row['with_trace_ms']:.1f} against "
              f"{row['without_trace_ms']:.1f} ms ({row['ratio']:.2f}x)", file=sys.stderr)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "scene-effects"))
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    if not os.path.isdir(os.path.join(SHARED, "scenes")):
        sys.exit("contact_sheet: ../shared/scenes is absent")
    # Taken before the picture is written, which would mark the commit dirty.
    record = run_record(args.kdray)
    tiles, records = [], []
    with tempfile.TemporaryDirectory(prefix="kdray-sheet-") as tmp:
        for folder, obj, shipped, options, why in SHOTS:
            out = os.path.join(tmp, folder)
            frame, command = render_once(
                args.kdray, os.path.join(SHARED, "scenes", folder, obj),
                scene_render_file(folder, shipped), ["--size", TILE, *options], out)
            tiles.append(os.path.join(out, os.path.splitext(obj)[0] + ".png"))
            records.append({"scene": f"{folder}/{obj}", "shows": why, "command": command,
                            "effects": frame["effects"], "rays": frame["rays"],
                            "trace_ms": frame["trace_ms"],
                            "warnings": len(frame["scene"].get("warnings", []))})
            print(f"{folder}: {why}; trace {frame['trace_ms']:.0f} ms", file=sys.stderr)
        subprocess.run(["oiiotool", *tiles, "--mosaic", f"{len(tiles)}x1", "-o",
                        args.out + ".png"], check=True)
        costs = effect_costs(args.kdray, tmp, args.repeat)
    with open(args.out + ".json", "w") as f:
        json.dump({**record, "tile": TILE, "shots": records, "effect_costs": costs}, f, indent=1)
        f.write("\n")
    print(f"wrote {args.out}.png and .json", file=sys.stderr)


if __name__ == "__main__":
    main()
