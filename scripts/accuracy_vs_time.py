#!/usr/bin/env python3
"""What accuracy costs in time: three sweeps, each measured, tabled and plotted.

1. Tree quality against build time. The OpenCL builder's large-node threshold T (Zhou et al.'s
   T, 1..64), empty-space ratio C_e and large-node split (SAH bins per axis; 0 is the paper's
   spatial median), and the CPU reference full-SAH builder as the far end.
   Per setting: build ms, SAH cost, trace ms of primary + shadow rays (the scene's render file
   with its first light only and max_depth 1), and frame ms: build + trace for a dynamic scene
   (rebuilt every frame), trace alone for a static one (built once, traced many times).
2. Image accuracy against render time. spp and max_depth against a high-quality reference render
   of the same scene (EXR, high spp, max_depth 8): RMSE and PSNR as `oiiotool --diff` prints them.
3. Numerical robustness against speed. The watertight ray–triangle test against Möller–Trumbore
   (`kdray render --intersect`): trace time on ordinary scenes, and the pixels that leak through
   shared edges and vertices of closed meshes whose centre rays pass through mesh vertices, with
   the camera inside (every ray must hit: a miss is a leak), at the origin and 1e5 away from it;
   counted by kdray's hit_pixels and, when the Embree peer builds, by `embree_ref --compare`.

Every figure comes from the runs' stats.json (and oiiotool's diff). Writes CSV files, results.json
(the rows with the commit, machine and command), a Markdown table (tables.md) and PNG plots
into --out. A default run also uses ../shared/scenes when present;
--quick uses testdata only with few settings; --check verifies that every configuration produced a
valid row, that the image error falls as spp rises and that the watertight test never leaks (it
asserts nothing about speed).

  scripts/accuracy_vs_time.py --kdray build/kdray [--out docs/accuracy-vs-time] [--quick]
                              [--check] [--no-shared] [--peer PATH]
"""
import argparse
import csv
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import (ROOT, SHARED, build_peer, median, run_json, run_record,  # noqa: E402
                          write_json)
from bench_render import camera_at  # noqa: E402

import accuracy_plots  # noqa: E402
import accuracy_scenes  # noqa: E402


class Plan:
    """The settings of a run: --quick keeps each sweep to a few points on testdata."""

    def __init__(self, quick, shared):
        self.quick = quick
        td = lambda *p: os.path.join(ROOT, "testdata", *p)  # noqa: E731
        sh = lambda *p: os.path.join(SHARED, "scenes", *p)  # noqa: E731
        anim = [td("anim", f"frame_{i:03d}.obj") for i in range(4 if quick else 12)]
        # (name, kind, objs, render file): dynamic scenes render their frames in order (median
        # frame), static ones one OBJ several times under different names (best of them).
        self.tree_scenes = [("testdata/cornell", "static", [td("cornell", "room.obj")],
                             td("cornell", "render.json")),
                            ("testdata/anim", "dynamic", anim, td("anim", "render.json"))]
        # (name, obj, render file, width, height)
        self.image_scenes = [("testdata/cornell", td("cornell", "room.obj"),
                              td("cornell", "render.json"), 160, 120)]
        self.timing_scenes = [("testdata/cornell", td("cornell", "room.obj"),
                               td("cornell", "render.json"))]
        if quick:
            self.thresholds, self.empty_ratios, self.large_bins = [1, 8, 64], [0.0, 0.5], [0]
            self.static_repeats, self.rounds = 2, 1
            self.spps, self.depths, self.depth_spp = [1, 4, 16], [1, 2, 4, 8], 4
            self.reference_spp = 64
            self.hard_width = 33
            return
        self.thresholds, self.empty_ratios = [1, 2, 4, 8, 16, 32, 64], [0.0, 0.1, 0.5]
        self.large_bins = [0, 8, 16, 64]
        self.static_repeats, self.rounds = 3, 2
        self.spps, self.depths, self.depth_spp = [1, 2, 4, 8, 16, 32, 64], list(range(1, 9)), 16
        self.reference_spp = 256
        self.hard_width = 65
        self.image_scenes[0] = self.image_scenes[0][:3] + (320, 240)
        self.image_scenes.append(("testdata/anim", td("anim", "frame_000.obj"),
                                  td("anim", "render.json"), 320, 180))
        if not shared:
            return
        kitchen = [sh("bart-kitchen", f"frame_{i:03d}.obj") for i in range(4)]
        extra_tree = [("bart-kitchen", "dynamic", kitchen, sh("bart-kitchen", "render.json")),
                      ("bunny", "static", [sh("bunny", "bunny.obj")], sh("bunny", "render.json")),
                      ("sponza", "static", [sh("sponza-dabrovic", "sponza.obj")],
                       sh("sponza-dabrovic", "render.json"))]
        self.tree_scenes += [s for s in extra_tree if all(map(os.path.isfile, s[2] + [s[3]]))]
        for name, obj, render, w, h in [("bart-kitchen", kitchen[0],
                                         sh("bart-kitchen", "render.json"), 256, 192)]:
            if os.path.isfile(obj):
                self.image_scenes.append((name, obj, render, w, h))
        for name, kind, objs, render in self.tree_scenes[2:]:
            self.timing_scenes.append((name, objs[0], render))


def tree_configs(plan):
    """(label, kdray builder options, T, C_e) from the cheapest trees to the full SAH."""
    configs = [(f"T={t}", ["--large-threshold", str(t)], t, 0.25) for t in plan.thresholds]
    configs += [(f"C_e={c:g}", ["--empty-ratio", str(c)], 64, c) for c in plan.empty_ratios]
    configs += [("median" if b == 0 else f"bins={b}", ["--large-bins", str(b)], 64, 0.25)
                for b in plan.large_bins]
    configs.append(("reference SAH", ["--builder", "reference"], "", ""))
    return configs


def write_render_file(source, path, frame=0, **changes):
    """source with `changes` applied: image (dict merged), lights, max_depth; keyframed cameras
    stay keyframed unless freeze_camera, which keeps only frame's camera (static repeats)."""
    with open(source) as f:
        j = json.load(f)
    if changes.pop("freeze_camera", False) and isinstance(j.get("camera"), list):
        j["camera"] = camera_at(j["camera"], frame)
    j.setdefault("image", {}).update(changes.pop("image", {}))
    j.update(changes)
    with open(path, "w") as f:
        json.dump(j, f)
    return path


def link_copies(obj, folder, count):
    """`count` names for one OBJ (and its MTL files beside it), so that one kdray run traces the
    same static scene several times."""
    os.makedirs(folder, exist_ok=True)
    source_dir = os.path.dirname(os.path.abspath(obj))
    for mtl in (f for f in os.listdir(source_dir) if f.endswith(".mtl")):
        os.symlink(os.path.join(source_dir, mtl), os.path.join(folder, mtl))
    stem = os.path.splitext(os.path.basename(obj))[0]
    names = [os.path.join(folder, f"{stem}_rep{i}.obj") for i in range(count)]
    for name in names:
        os.symlink(os.path.abspath(obj), name)
    return names


def kdray_render(kdray, objs, render_file, out_dir, options=()):
    """One `kdray render` run (with --warm-up, so no program build is timed); its stats.json."""
    command = [kdray, "render", *objs, "--camera", render_file, "-o", out_dir, "-q",
               "--warm-up", *options]
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {result.stderr.strip()}")
    with open(os.path.join(out_dir, "stats.json")) as f:
        return json.load(f)


def sweep_tree_quality(kdray, plan, tmp, log):
    """Every scene and setting once per round, rounds one after another, so that a burst of
    other load on the machine slows one measurement of a setting rather than all of them; each
    figure is the best round's."""
    runs = []  # (scene, kind, objs, render file, label, options, T, C_e)
    for scene, kind, objs, render in plan.tree_scenes:
        with open(render) as f:
            lights = json.load(f).get("lights", [])
        name = scene.replace("/", "_")
        render_file = write_render_file(render, os.path.join(tmp, f"tree-{name}.json"), frame=0,
                                        freeze_camera=kind == "static", lights=lights[:1],
                                        max_depth=1, image={"spp": 1})
        if kind == "static":
            objs = link_copies(objs[0], os.path.join(tmp, "static", name), plan.static_repeats)
        runs += [(scene, kind, objs, render_file, *config) for config in tree_configs(plan)]
    best = {}
    for round_number in range(plan.rounds):
        for scene, kind, objs, render_file, label, options, threshold, empty_ratio in runs:
            out = os.path.join(tmp, "tree-out")
            shutil.rmtree(out, ignore_errors=True)
            frames = kdray_render(kdray, objs, render_file, out, options)["frames"]
            # Static: the best of the repeats (the same work each time, so anything above the
            # least is other load on the machine). Dynamic: the median frame.
            pick = min if kind == "static" else median
            build_ms = pick([f["build_ms"] for f in frames])
            trace_ms = pick([f["trace_ms"] for f in frames])
            rays = sum(f["rays"]["primary"] + f["rays"]["shadow"] for f in frames) / len(frames)
            row = {"scene": scene, "kind": kind, "triangles": frames[0]["scene"]["triangles"],
                   "setting": label, "builder": frames[0]["tree"]["builder"],
                   "large_threshold": threshold, "empty_ratio": empty_ratio,
                   "frames": len(frames), "build_ms": build_ms,
                   "sah_cost": median([f["tree"]["sah_cost"] for f in frames]),
                   "nodes": frames[0]["tree"]["nodes"], "trace_ms": trace_ms,
                   "rays": int(rays)}
            kept = best.setdefault((scene, label), row)
            kept["build_ms"] = min(kept["build_ms"], build_ms)
            kept["trace_ms"] = min(kept["trace_ms"], trace_ms)
            kept["frame_ms"] = kept["trace_ms"] + (kept["build_ms"] if kind == "dynamic" else 0)
            log(f"tree  round {round_number + 1} {scene:18s} {label:14s} build {build_ms:8.1f} "
                f"ms  SAH {row['sah_cost']:8.1f}  trace {trace_ms:8.1f} ms")
    return list(best.values())


DIFF_FIELDS = {"rmse": re.compile(r"RMS error\s*=\s*([-+0-9.eEinfa]+)"),
               "psnr": re.compile(r"Peak SNR\s*=\s*([-+0-9.eEinfa]+)")}


def image_error(image, reference):
    """RMSE and PSNR of image against reference, parsed from `oiiotool --diff` (which exits 1
    whenever the images differ at all, so its exit status says nothing here)."""
    result = subprocess.run(["oiiotool", image, reference, "--diff"], capture_output=True,
                            text=True)
    errors = {}
    for key, pattern in DIFF_FIELDS.items():
        match = pattern.search(result.stdout)
        if not match:
            raise RuntimeError(f"oiiotool --diff {image} {reference}: no '{key}' in its output:\n"
                               f"{result.stdout}{result.stderr}")
        errors[key] = float(match.group(1))
    return errors


def sweep_image_accuracy(kdray, plan, tmp, log):
    rows = []
    for scene, obj, render, width, height in plan.image_scenes:
        name = scene.replace("/", "_")
        stem = os.path.splitext(os.path.basename(obj))[0]

        def render_at(spp, depth, tag):
            render_file = write_render_file(
                render, os.path.join(tmp, f"{name}-{tag}.json"), freeze_camera=True,
                image={"width": width, "height": height, "spp": spp}, max_depth=depth)
            out = os.path.join(tmp, "image", name, tag)
            frame = kdray_render(kdray, [obj], render_file, out, ["--format", "exr"])["frames"][0]
            return frame, os.path.join(out, stem + ".exr")

        _, reference = render_at(plan.reference_spp, 8, "reference")
        points = [("spp", spp, 8) for spp in plan.spps]
        points += [("max_depth", depth, plan.depth_spp) for depth in plan.depths]
        for sweep, value, depth in points:
            spp = value if sweep == "spp" else plan.depth_spp
            depth = 8 if sweep == "spp" else value
            frame, image = render_at(spp, depth, f"{sweep}{value}")
            errors = image_error(image, reference)
            rays = frame["rays"]
            rows.append({"scene": scene, "width": width, "height": height, "sweep": sweep,
                         "spp": spp, "max_depth": depth,
                         "reference": f"spp {plan.reference_spp}, max_depth 8",
                         "trace_ms": frame["trace_ms"], "rays": sum(rays.values()),
                         "rmse": errors["rmse"], "psnr": errors["psnr"]})
            log(f"image {scene:18s} spp {spp:3d} depth {depth}  trace {frame['trace_ms']:8.1f} ms"
                f"  RMSE {errors['rmse']:.5f}  PSNR {errors['psnr']:.2f} dB")
    return rows


def sweep_robustness(kdray, plan, tmp, peer, log):
    rows = []
    # Both tests one ray at a time, and the watertight test's packets (CPU devices' default; the
    # same hits): the tests' costs compare only like for like.
    modes = {"watertight": ["--intersect", "watertight", "--packets", "off"],
             "watertight, packets": ["--intersect", "watertight", "--packets", "on"],
             "moller": ["--intersect", "moller"]}
    # Speed: primary + shadow rays (first light, max_depth 1) on ordinary scenes, best of 3.
    for scene, obj, render in plan.timing_scenes:
        with open(render) as f:
            lights = json.load(f).get("lights", [])
        render_file = write_render_file(render, os.path.join(tmp, "speed.json"),
                                        freeze_camera=True, lights=lights[:1], max_depth=1,
                                        image={"spp": 1})
        objs = link_copies(obj, os.path.join(tmp, "speed", scene.replace("/", "_")), 3)
        for mode in modes:
            out = os.path.join(tmp, "speed-out")
            shutil.rmtree(out, ignore_errors=True)
            frames = kdray_render(kdray, objs, render_file, out, modes[mode])["frames"]
            rows.append({"scene": scene, "case": "ordinary", "intersect": mode,
                         "pixels": "", "trace_ms": min(f["trace_ms"] for f in frames),
                         "leaks": "", "embree_hit_miss": ""})
            log(f"robust {scene:26s} {mode:10s} trace {rows[-1]['trace_ms']:8.1f} ms")
    # Leaks: closed meshes around the camera, centre rays through mesh vertices.
    for case, obj, render in accuracy_scenes.write_hard_scenes(os.path.join(tmp, "hard"),
                                                               plan.hard_width):
        embree_aov = None
        if peer:
            # The peer's own count too: Embree's default triangle test is not watertight either.
            embree_aov = os.path.join(tmp, "hard", case + ".embree.exr")
            embree = run_json([peer, obj, "--camera", render, "--aov", embree_aov, "--repeat",
                               "1", "--threads", str(os.cpu_count())])
            rows.append({"scene": case, "case": "closed mesh, camera inside",
                         "intersect": "Embree peer", "pixels": embree["rays"],
                         "trace_ms": embree["trace_ms"],
                         "leaks": embree["rays"] - embree["hit_pixels"], "embree_hit_miss": 0})
        for mode in modes:
            out = os.path.join(tmp, "hard-out", case, mode.replace(", ", "-"))
            frame = kdray_render(kdray, [obj], render, out, modes[mode] + ["--aov"])
            frame = frame["frames"][0]
            pixels = frame["rays"]["primary"]
            mismatch = ""
            if embree_aov:
                compare = subprocess.run([peer, "--compare", os.path.join(out, frame["aov"]),
                                          embree_aov], check=True, capture_output=True, text=True)
                mismatch = json.loads(compare.stdout)["hit_miss_mismatch"]
            rows.append({"scene": case, "case": "closed mesh, camera inside", "intersect": mode,
                         "pixels": pixels, "trace_ms": frame["trace_ms"],
                         "leaks": pixels - frame["hit_pixels"], "embree_hit_miss": mismatch})
            log(f"robust {case:26s} {mode:10s} leaks {rows[-1]['leaks']:5d} of {pixels}"
                f"  (Embree hit/miss mismatches: {mismatch if mismatch != '' else 'no peer'})")
    return rows


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0].keys()))
        writer.writeheader()
        writer.writerows(rows)


def check(tree_rows, image_rows, robust_rows, plan):
    """The --check assertions: validity and the direction of image error, never speed."""
    problems = []
    expected = {(s[0], c[0]) for s in plan.tree_scenes for c in tree_configs(plan)}
    got = {(r["scene"], r["setting"]) for r in tree_rows}
    problems += [f"tree sweep: no row for {k}" for k in sorted(expected - got)]
    for r in tree_rows:
        if not (r["build_ms"] > 0 and r["trace_ms"] > 0 and r["sah_cost"] > 0 and r["nodes"] > 0
                and r["rays"] > 0):
            problems.append(f"tree sweep: invalid row {r}")
    for scene, *_ in plan.image_scenes:
        rows = [r for r in image_rows if r["scene"] == scene]
        if len(rows) != len(plan.spps) + len(plan.depths):
            problems.append(f"image sweep {scene}: {len(rows)} rows")
        if any(not (math.isfinite(r["rmse"]) and r["trace_ms"] > 0) for r in rows):
            problems.append(f"image sweep {scene}: an invalid row")
        rmse = [r["rmse"] for r in rows if r["sweep"] == "spp"]
        # Fewer samples alias more: the error at the most samples must be well below one
        # sample's, and no step up in spp may raise it by more than noise.
        if len(rmse) >= 2 and not rmse[-1] < 0.7 * rmse[0]:
            problems.append(f"image sweep {scene}: RMSE does not fall with spp: {rmse}")
        problems += [f"image sweep {scene}: RMSE rises from spp {a} to {b}: {rmse}"
                     for a, b, ea, eb in zip(plan.spps, plan.spps[1:], rmse, rmse[1:])
                     if eb > 1.1 * ea]
    for r in robust_rows:
        if not r["trace_ms"] > 0:
            problems.append(f"robustness: invalid row {r}")
        if r["intersect"].startswith("watertight") and r["leaks"] not in ("", 0):
            problems.append(f"robustness: the watertight test leaks: {r}")
    return problems


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "accuracy-vs-time"))
    parser.add_argument("--quick", action="store_true", help="testdata only, few settings")
    parser.add_argument("--check", action="store_true",
                        help="exit 1 unless every row is valid, image error falls with spp and "
                             "the watertight test never leaks")
    parser.add_argument("--no-shared", action="store_true", help="leave ../shared/scenes out")
    parser.add_argument("--peer", help="a built embree_ref (default: build it when ../shared "
                                       "has the peer; without it leaks are counted by kdray)")
    parser.add_argument("--plot-only", action="store_true",
                        help="redraw the plots of --out from its CSVs, measuring nothing")
    args = parser.parse_args()
    if args.plot_only:
        accuracy_plots.ensure_matplotlib([os.path.abspath(__file__), *sys.argv[1:]])
        rows = [accuracy_plots.read_csv_rows(os.path.join(args.out, f"{name}.csv"))
                for name in ("tree_quality", "image_accuracy", "robustness")]
        accuracy_plots.plot_all(args.out, *rows)
        return 0
    if not shutil.which("oiiotool"):
        sys.exit("accuracy_vs_time: oiiotool is missing (apt-get install openimageio-tools)")
    accuracy_plots.ensure_matplotlib([os.path.abspath(__file__), *sys.argv[1:]])
    kdray = os.path.abspath(args.kdray)
    plan = Plan(args.quick, not args.quick and not args.no_shared
                and os.path.isdir(os.path.join(SHARED, "scenes")))
    os.makedirs(args.out, exist_ok=True)
    # Before the sweeps, which write their CSVs into the work tree as they finish: taken after,
    # the record called every run's commit "-dirty".
    record = run_record(kdray)
    started = time.time()
    log = lambda line: print(f"[{time.time() - started:6.1f} s] {line}", flush=True)  # noqa
    with tempfile.TemporaryDirectory(prefix="kdray-accuracy-") as tmp:
        peer = args.peer or (None if args.quick or args.no_shared else build_peer())
        # Each sweep's CSV is written as soon as it is done, so a failed later sweep keeps them.
        tree_rows = sweep_tree_quality(kdray, plan, tmp, log)
        write_csv(os.path.join(args.out, "tree_quality.csv"), tree_rows)
        image_rows = sweep_image_accuracy(kdray, plan, tmp, log)
        write_csv(os.path.join(args.out, "image_accuracy.csv"), image_rows)
        robust_rows = sweep_robustness(kdray, plan, tmp, peer, log)
        write_csv(os.path.join(args.out, "robustness.csv"), robust_rows)
    header = (f"Measured {record['date']} at {record['commit']} with `{record['command']}` in "
              f"{time.time() - started:.0f} s on {record['machine']}.")
    # The rows again with the run's record: what scripts/update_docs.py generates tables from.
    write_json(os.path.join(args.out, "results.json"),
               {**record, "tree_quality": tree_rows, "image_accuracy": image_rows,
                "robustness": robust_rows})
    with open(os.path.join(args.out, "tables.md"), "w") as f:
        f.write(accuracy_plots.tables_markdown(header, tree_rows, image_rows, robust_rows))
    accuracy_plots.plot_all(args.out, tree_rows, image_rows, robust_rows)
    log(f"wrote {args.out}")
    if args.check:
        problems = check(tree_rows, image_rows, robust_rows, plan)
        for p in problems:
            print("CHECK FAILED: " + p, file=sys.stderr)
        return 1 if problems else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())
