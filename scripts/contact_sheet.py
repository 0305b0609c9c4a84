#!/usr/bin/env python3
"""A contact sheet of the scene effects on the shared scenes: Sponza textured, the Cornell box lit
by its ceiling panel (soft shadows), the BART Kitchen and Robots with their ambient term. Each is
rendered by kdray with the scene's own render.json (plus `ambient` where the scene's materials
call for it, and more samples where area lights are sampled), then tiled with `oiiotool --mosaic`
into docs/scene-effects.png, with the effects each frame's stats.json lists in
docs/scene-effects.json. Beside them, what each effect costs where a scene calls for it: the
same frame traced with the effect and without it (textures: Sponza, its MTL without map_Kd and
map_Ka; area lights: CornellBox-Original at 16 spp, its MTL without Ke; ambient: the Kitchen's
frame 0 with and without `ambient`), each the median trace_ms of --repeat runs taken in turn.

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


def render_once(kdray, obj, render, out):
    result = subprocess.run([kdray, "render", obj, "--camera", render, "-o", out, "-q",
                             "--overwrite"],
                            capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"contact_sheet: {obj}: {result.stderr.strip()}")
    with open(os.path.join(out, "stats.json")) as f:
        return json.load(f)["frames"][0]


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
    def render_file(folder, extra):
        with open(os.path.join(SHARED, "scenes", folder, "render.json")) as f:
            render = json.load(f)
        if isinstance(render.get("camera"), list):
            render["camera"] = {k: v for k, v in render["camera"][0].items() if k != "frame"}
        render = merged(render, extra)
        path = os.path.join(tmp, f"cost-{folder}-{len(os.listdir(tmp))}.json")
        with open(path, "w") as f:
            json.dump(render, f)
        return path

    cases = [
        ("textures", "sponza-dabrovic", "sponza.obj", {}, {}, ("map_Kd", "map_Ka")),
        ("area_lights", "cornell-box", "CornellBox-Original.obj", {"image": {"spp": 16}},
         {"image": {"spp": 16}}, ("Ke",)),
        ("ambient", "bart-kitchen", "frame_000.obj", {"ambient": 0.2}, {}, ()),
    ]
    rows = []
    for effect, folder, obj, with_extra, without_extra, drop in cases:
        with_obj = os.path.join(SHARED, "scenes", folder, obj)
        without_obj = scene_copy(folder, obj, tmp, drop) if drop else with_obj
        with_render, without_render = render_file(folder, with_extra), render_file(folder,
                                                                                   without_extra)
        on, off = [], []
        for _ in range(repeat):
            frame = render_once(kdray, with_obj, with_render, os.path.join(tmp, "on"))
            if not frame["effects"].get(effect):
                sys.exit(f"contact_sheet: {folder} does not call for {effect}")
            on.append(frame["trace_ms"])
            frame = render_once(kdray, without_obj, without_render, os.path.join(tmp, "off"))
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
                                     render_path, "-o", out, "-q", "--overwrite"],
                                    capture_output=True, text=True)
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
        costs = effect_costs(args.kdray, tmp, args.repeat)
    with open(args.out + ".json", "w") as f:
        json.dump({**run_record(args.kdray), "tile": TILE, "shots": records, "effect_costs": costs}, f, indent=1)
        f.write("\n")
    print(f"wrote {args.out}.png and .json", file=sys.stderr)


if __name__ == "__main__":
    main()
