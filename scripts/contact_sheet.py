#!/usr/bin/env python3
"""A contact sheet of the scene effects on the shared scenes: Sponza textured, the Cornell box lit
by its ceiling panel (soft shadows), the BART Kitchen and Robots with their ambient term. Each is
rendered by kdray with the scene's own render.json (plus `ambient` where the scene's materials
call for it, and more samples where area lights are sampled), then tiled with `oiiotool --mosaic`
into docs/scene-effects.png, with the effects each frame's stats.json lists in
docs/scene-effects.json.

  scripts/contact_sheet.py --kdray build/kdray [--out docs/scene-effects]
"""
import argparse
import json
import os
import shutil
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import ROOT, SHARED  # noqa

TILE = (384, 288)
# scene folder, OBJ, what the render file gains, why
SHOTS = [
    ("sponza-dabrovic", "sponza.obj", {"ambient": 0.3}, "textures (map_Kd) and ambient"),
    ("cornell-box", "CornellBox-Original.obj", {"image": {"spp": 64}},
     "lit by its emissive panel, soft shadows"),
    ("bart-kitchen", "frame_000.obj", {"ambient": 0.2}, "BART's ambient term (Ka)"),
    ("bart-robots", "frame_000.obj", {"ambient": 0.2}, "BART's ambient term (Ka)"),
]


def merged(base, extra):
    out = dict(base)
    for key, value in extra.items():
        out[key] = merged(out.get(key, {}), value) if isinstance(value, dict) else value
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "scene-effects"))
    args = parser.parse_args()
    if not os.path.isdir(os.path.join(SHARED, "scenes")):
        sys.exit("contact_sheet: ../shared/scenes is absent")
    tiles, records = [], []
    with tempfile.TemporaryDirectory(prefix="kdray-sheet-") as tmp:
        for folder, obj, extra, why in SHOTS:
            path = os.path.join(SHARED, "scenes", folder)
            with open(os.path.join(path, "render.json")) as f:
                render = json.load(f)
            if isinstance(render.get("camera"), list):  # a keyframed camera: its first key
                render["camera"] = {k: v for k, v in render["camera"][0].items() if k != "frame"}
            render = merged(render, extra)
            render.setdefault("image", {}).update(width=TILE[0], height=TILE[1])
            render_path = os.path.join(tmp, f"{folder}.json")
            with open(render_path, "w") as f:
                json.dump(render, f)
            out = os.path.join(tmp, folder)
            result = subprocess.run([args.kdray, "render", os.path.join(path, obj), "--camera",
                                     render_path, "-o", out, "-q"], capture_output=True, text=True)
            if result.returncode != 0:
                sys.exit(f"contact_sheet: {folder}: {result.stderr.strip()}")
            with open(os.path.join(out, "stats.json")) as f:
                frame = json.load(f)["frames"][0]
            stem = os.path.splitext(obj)[0]
            tiles.append(os.path.join(out, stem + ".png"))
            records.append({"scene": f"{folder}/{obj}", "shows": why, "render_file_adds": extra,
                            "effects": frame["effects"], "rays": frame["rays"],
                            "trace_ms": frame["trace_ms"],
                            "warnings": len(frame["scene"].get("warnings", []))})
            print(f"{folder}: {why}; trace {frame['trace_ms']:.0f} ms", file=sys.stderr)
        subprocess.run(["oiiotool", *tiles, "--mosaic", f"{len(tiles)}x1", "-o",
                        args.out + ".png"], check=True)
    with open(args.out + ".json", "w") as f:
        json.dump({"tile": TILE, "shots": records}, f, indent=1)
        f.write("\n")
    print(f"wrote {args.out}.png and .json", file=sys.stderr)


if __name__ == "__main__":
    main()
