#!/usr/bin/env python3
"""kdray's images against Mitsuba 3's, the peer for light transport as Embree is for hits: the
same scene, camera and render file rendered by both at the same spp, the relative mean squared
error between the two linear EXRs, and each side's render time at equal spp.

    scripts/compare_mitsuba.py [--kdray build/kdray] [--integrator path] [--max-depth 5]
                               [--spp 256] [--size 256] [--quick] [--bound 0.02]
                               [--out docs/mitsuba-compare]

Mitsuba comes from PyPI (`mitsuba`, pinned below) in a virtual environment this script makes once
(build/mitsuba-venv, or --venv), as the Embree peer is built by its own script; its llvm_ad_rgb
variant when Debian's LLVM shared library is there (llvm-14, the gpu_compile test's), else
scalar_rgb. scripts/mitsuba_side.py maps the scene (conventions.md: `path` at the same max_depth,
diffuse/conductor/dielectric BSDFs, area emitters, the camera model).

Scenes: the Cornell boxes of ../shared (Original: diffuse and an area light; Sphere: a mirror and a
glass sphere) and a textured room this script generates (a checker map_Kd floor). The render
files are the scenes' own with the image size, spp, integrator and max_depth set, and the
background black (kdray's background is what a ray that leaves sees, not a light; a black one is
the same in both).

Exit 0 when every scene's relative MSE is under --bound, 1 when one is not (each says which),
77 (a skip, saying why) without ../shared or when the package cannot be installed. --out writes
OUT.json (every figure, the commands, the machine) and OUT.md.
"""
import argparse
import json
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import zlib

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import ROOT, SHARED, run_record, write_json  # noqa: E402

SKIP = 77
MITSUBA = "mitsuba==3.5.2"
LLVM_LIBRARY = "/usr/lib/llvm-14/lib/libLLVM-14.so"
SIDE = os.path.join(os.path.dirname(os.path.abspath(__file__)), "mitsuba_side.py")


def kdray_roulette_depth():
    """The segments kdray's path integrator traces before Russian roulette may end a path
    (KDRAY_PATH_ROULETTE_DEPTH, core/device/kd_path.h), for Mitsuba's rr_depth: at Mitsuba's
    default of 5 no path of max_depth 5 meets roulette there, while kdray's ends most Cornell-box
    paths after 3 segments, so the two timed different work (kdray's trace took 1.33x as long
    with roulette after 5). kdray rolls after the next-event estimate at vertex R, before
    segment R + 1; Mitsuba with rr_depth R rolls after segment R + 1, before its next-event
    estimate: at most one ray more a path on Mitsuba's side."""
    with open(os.path.join(ROOT, "core", "device", "kd_path.h")) as f:
        found = re.search(r"#define KDRAY_PATH_ROULETTE_DEPTH (\d+)u", f.read())
    if not found:
        raise RuntimeError("core/device/kd_path.h defines no KDRAY_PATH_ROULETTE_DEPTH")
    return int(found.group(1))


def venv_python(venv):
    """The venv's interpreter with mitsuba importable, made on first use; None (and why) when
    it cannot be made."""
    python = os.path.join(venv, "bin", "python")
    if os.path.isfile(python) and subprocess.run([python, "-c", "import mitsuba, numpy"],
                                                 capture_output=True).returncode == 0:
        return python, ""
    made = subprocess.run([sys.executable, "-m", "venv", venv], capture_output=True, text=True)
    if made.returncode != 0:
        return None, ("python3 -m venv failed (Debian: apt install python3-venv): "
                      + made.stderr.strip())
    pip = subprocess.run([python, "-m", "pip", "install", "-q", MITSUBA, "numpy"],
                         capture_output=True, text=True)
    if pip.returncode != 0:
        return None, f"pip could not install {MITSUBA}: {pip.stderr.strip().splitlines()[-1:]}"
    return python, ""


def write_png(path, width, height, pixel):
    """An 8-bit RGB PNG of pixel(x, y) -> (r, g, b), written with zlib alone."""
    rows = b"".join(b"\0" + bytes(c for x in range(width) for c in pixel(x, y))
                    for y in range(height))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(rows)))
        f.write(chunk(b"IEND", b""))


def textured_room(folder):
    """A closed room (floor with a checker texture, red and green side walls, a white back wall
    and ceiling, a front wall behind the camera) lit by an emitting quad under the ceiling."""
    os.makedirs(folder, exist_ok=True)
    write_png(os.path.join(folder, "checker.png"), 64, 64,
              lambda x, y: (200, 180, 40) if (x // 8 + y // 8) % 2 else (40, 90, 200))
    with open(os.path.join(folder, "room.mtl"), "w") as f:
        f.write("newmtl floor\nKd 1 1 1\nmap_Kd checker.png\n"
                "newmtl white\nKd 0.7 0.7 0.7\nnewmtl red\nKd 0.6 0.1 0.1\n"
                "newmtl green\nKd 0.1 0.5 0.1\nnewmtl light\nKd 0 0 0\nKe 8 8 8\n")
    v, vt, faces = [], [], []

    def quad(material, corners, uv=False):
        base = len(v)
        v.extend(corners)
        if uv:
            t = len(vt)
            vt.extend([(0, 0), (3, 0), (3, 3), (0, 3)])
            faces.append((material, [f"{base + k + 1}/{t + k + 1}" for k in range(4)]))
        else:
            faces.append((material, [str(base + k + 1) for k in range(4)]))
    # Counter-clockwise seen from inside the room (the emitter faces down).
    quad("floor", [(-1, 0, -1), (-1, 0, 1), (1, 0, 1), (1, 0, -1)], uv=True)
    quad("white", [(-1, 2, -1), (1, 2, -1), (1, 2, 1), (-1, 2, 1)])
    quad("white", [(-1, 0, -1), (1, 0, -1), (1, 2, -1), (-1, 2, -1)])
    quad("white", [(-1, 0, 1), (-1, 2, 1), (1, 2, 1), (1, 0, 1)])
    quad("red", [(-1, 0, -1), (-1, 2, -1), (-1, 2, 1), (-1, 0, 1)])
    quad("green", [(1, 0, -1), (1, 0, 1), (1, 2, 1), (1, 2, -1)])
    quad("light", [(-0.3, 1.99, -0.3), (0.3, 1.99, -0.3), (0.3, 1.99, 0.3), (-0.3, 1.99, 0.3)])
    obj = os.path.join(folder, "room.obj")
    with open(obj, "w") as f:
        f.write("mtllib room.mtl\n")
        f.writelines(f"v {x} {y} {z}\n" for x, y, z in v)
        f.writelines(f"vt {s} {t}\n" for s, t in vt)
        for material, corners in faces:
            f.write(f"usemtl {material}\nf {' '.join(corners)}\n")
    render = {"camera": {"position": [0, 1, 0.95], "look_at": [0, 0.8, -1], "up": [0, 1, 0],
                         "fov_y": 60}}
    return obj, render


def cases(work):
    cornell = os.path.join(SHARED, "scenes", "cornell-box")
    with open(os.path.join(cornell, "render.json")) as f:
        cornell_render = json.load(f)
    room_obj, room_render = textured_room(os.path.join(work, "textured-room"))
    return [("cornell-original", os.path.join(cornell, "CornellBox-Original.obj"), cornell_render),
            ("cornell-sphere", os.path.join(cornell, "CornellBox-Sphere.obj"), cornell_render),
            ("textured-room", room_obj, room_render)]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--venv", default=os.path.join(ROOT, "build", "mitsuba-venv"))
    parser.add_argument("--integrator", default="path", choices=["path", "whitted"])
    parser.add_argument("--max-depth", type=int, default=5,
                        help="path segments, as Mitsuba counts them (conventions.md)")
    parser.add_argument("--spp", type=int, default=256)
    parser.add_argument("--size", type=int, default=256, help="square image side")
    parser.add_argument("--quick", action="store_true", help="128x128 at 256 spp (the test)")
    parser.add_argument("--bound", type=float, default=0.02,
                        help="largest relative MSE that passes")
    parser.add_argument("--out", help="write OUT.json and OUT.md")
    args = parser.parse_args()
    if args.quick:
        args.spp, args.size = 256, 128
    if not os.path.isdir(os.path.join(SHARED, "scenes", "cornell-box")):
        print(f"compare_mitsuba: skipped: {SHARED}/scenes/cornell-box is absent")
        return SKIP
    python, why = venv_python(args.venv)
    if not python:
        print(f"compare_mitsuba: skipped: {why}")
        return SKIP
    variant = "llvm_ad_rgb" if os.path.isfile(LLVM_LIBRARY) else "scalar_rgb"
    rr_depth = kdray_roulette_depth()
    env = dict(os.environ, DRJIT_LIBLLVM_PATH=LLVM_LIBRARY)
    rows, failures = [], 0
    with tempfile.TemporaryDirectory(prefix="kdray-mitsuba-") as work:
        for name, obj, render in cases(work):
            render = json.loads(json.dumps(render))
            render["image"] = {"width": args.size, "height": args.size, "spp": args.spp}
            render["background"] = [0, 0, 0]
            if args.integrator != "whitted":  # the default, which a render file may leave out
                render["integrator"] = args.integrator
            render["max_depth"] = args.max_depth
            render_file = os.path.join(work, f"{name}.json")
            with open(render_file, "w") as f:
                json.dump(render, f)
            out = os.path.join(work, name)
            kdray = subprocess.run([args.kdray, "render", obj, "--camera", render_file, "-o", out,
                                    "--format", "exr", "--warm-up", "-q"],
                                   capture_output=True, text=True)
            if kdray.returncode != 0:
                print(f"FAIL {name}: kdray: {kdray.stderr.strip()}")
                failures += 1
                continue
            with open(os.path.join(out, "stats.json")) as f:
                stats = json.load(f)
            frame = stats["frames"][0]
            ours = os.path.join(out, frame["image"])
            spec = os.path.join(work, f"{name}.spec.json")
            with open(spec, "w") as f:
                json.dump({"obj": obj, "render_file": render, "spp": args.spp,
                           "max_depth": args.max_depth, "rr_depth": rr_depth, "variant": variant,
                           "work": os.path.join(work, name + "-mitsuba")}, f)
            theirs = os.path.join(work, f"{name}.mitsuba.exr")
            # errors="replace": Dr.Jit's shutdown messages may hold raw bytes.
            side = subprocess.run([python, SIDE, "render", spec, theirs], capture_output=True,
                                  text=True, errors="replace", env=env)
            if side.returncode != 0:
                print(f"FAIL {name}: Mitsuba: {side.stderr.strip()[-2000:]}")
                failures += 1
                continue
            mitsuba = json.loads(side.stdout.strip().splitlines()[-1])
            cmp = subprocess.run([python, SIDE, "compare", ours, theirs], capture_output=True,
                                 text=True, errors="replace", env=env)
            result = json.loads(cmp.stdout.strip().splitlines()[-1])
            if "rel_mse" not in result:
                print(f"FAIL {name}: {result.get('error', cmp.stderr.strip())}")
                failures += 1
                continue
            row = {"scene": name, "rel_mse": result["rel_mse"], "mean_kdray": result["mean_a"],
                   "mean_mitsuba": result["mean_b"], "kdray_trace_ms": frame["trace_ms"],
                   "kdray_frame_ms": frame["frame_ms"],
                   "mitsuba_ms": mitsuba["seconds"] * 1000.0,
                   "mitsuba_variant": mitsuba["variant"],
                   "approximations": mitsuba["approximations"],
                   "effects": frame.get("effects", stats.get("effects"))}
            rows.append(row)
            verdict = "ok" if row["rel_mse"] <= args.bound else "FAIL"
            failures += verdict == "FAIL"
            print(f"{verdict} {name}: relative MSE {row['rel_mse']:.5f} (bound {args.bound}); "
                  f"mean {row['mean_kdray']:.4f} vs {row['mean_mitsuba']:.4f}; "
                  f"kdray trace {row['kdray_trace_ms']:.0f} ms, Mitsuba {mitsuba['variant']} "
                  f"{row['mitsuba_ms']:.0f} ms at {args.spp} spp"
                  + (f"; approximations: {row['approximations']}" if row["approximations"] else ""))
    if args.out:
        record = {**run_record(args.kdray), "integrator": args.integrator,
                  "max_depth": args.max_depth, "rr_depth": rr_depth, "spp": args.spp, "size": args.size,
                  "bound": args.bound, "mitsuba": MITSUBA, "scenes": rows}
        write_json(args.out + ".json", record)
        lines = [
            "# kdray against Mitsuba 3",
            "",
            f"Generated by `scripts/compare_mitsuba.py` from `{os.path.basename(args.out)}.json`: "
            f"commit {record['commit']}, {record['date']}, {record['machine']}. Integrator "
            f"`{args.integrator}`, max_depth {args.max_depth} (Mitsuba's rr_depth {rr_depth}: "
            "Russian roulette after as many segments as kdray's, where its default of 5 leaves "
            f"every path of 5 segments whole), {args.size}x{args.size} at "
            f"{args.spp} spp on both sides; {MITSUBA} from PyPI. Relative MSE: the mean over "
            "pixels and channels of (kdray - Mitsuba)^2 / (Mitsuba^2 + 0.01), both linear EXRs, "
            "so it holds both sides' noise. Times: kdray's trace time of the frame (warm: after "
            "`--warm-up`) and Mitsuba's render call after an untimed 1-spp render (its JIT).",
            "",
            "| scene | relative MSE | mean kdray | mean Mitsuba | kdray trace (ms) | "
            "Mitsuba (ms) | Mitsuba / kdray time |",
            "|---|---:|---:|---:|---:|---:|---:|",
        ]
        for r in rows:
            lines.append(f"| {r['scene']} | {r['rel_mse']:.5f} | {r['mean_kdray']:.4f} | "
                         f"{r['mean_mitsuba']:.4f} | {r['kdray_trace_ms']:.0f} | "
                         f"{r['mitsuba_ms']:.0f} ({r['mitsuba_variant']}) | "
                         f"{r['mitsuba_ms'] / r['kdray_trace_ms']:.2f}x |")
        notes = sorted({a for r in rows for a in r["approximations"]})
        if notes:
            lines += ["", "Mapped approximately: " + "; ".join(notes) + "."]
        with open(args.out + ".md", "w") as f:
            f.write("\n".join(lines) + "\n")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
