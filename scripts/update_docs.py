#!/usr/bin/env python3
"""Regenerates the figure tables of README.md and docs/ from the JSON the benchmark and sweep
scripts committed under docs/, so that no figure in the docs is typed by hand.

A table lives between two markers in a Markdown file:

    <!-- generated: NAME -->
    ...
    <!-- end generated -->

and is rewritten from its data by TABLES[NAME]. Each table ends with a line naming its data file
and the commit, machine and command the data came from (a JSON written before the scripts
recorded them says so, until the benchmark is re-run).

  scripts/update_docs.py           # rewrite every generated table
  scripts/update_docs.py --check   # exit 1, naming each table that differs from its data
"""
import argparse
import json
import math
import os
import re
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from accuracy_plots import best_tree_settings, read_csv_rows  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DOCS = os.path.join(ROOT, "docs")  # both moved by --root
BLOCK = re.compile(r"(<!-- generated: (?P<name>[\w-]+) -->\n)(?P<body>.*?)(<!-- end generated -->)",
                   re.S)


class Data:
    """One data file: its rows (or object) and the record of the run that wrote it."""

    def __init__(self, path, value, rows_key=None):
        self.path = os.path.relpath(path, ROOT)
        self.value = value
        self.rows = value.get(rows_key, []) if rows_key else []
        self.record = {k: value.get(k) for k in ("date", "commit", "machine", "command")}

    def source(self):
        r = dict(self.record)
        m = r["machine"]
        if isinstance(m, dict):  # scripts/scale.py's: its own fields
            r["date"] = r["date"] or m.get("date")
            r["machine"] = f"{m.get('cpu')}, {m.get('cores')} cores; OpenCL: {m.get('opencl')}"
        if not r["commit"] or not r["command"]:
            known = ", ".join(f"{k} {r[k]}" for k in ("date", "machine") if r[k])
            return (f"From `{self.path}` ({known or 'no run record'}; its commit and command "
                    "were not recorded: measured before the scripts recorded them).")
        return (f"From `{self.path}`: {r['date']} at {r['commit']}, `{r['command']}`, "
                f"on {r['machine']}.")


def load(stem, rows_key="rows", csv_fallback=None):
    """docs/STEM.json; when the script has not written one yet, the CSV it wrote before
    (numbers parsed, no run record)."""
    path = os.path.join(DOCS, stem + ".json")
    if os.path.isfile(path):
        with open(path) as f:
            return Data(path, json.load(f), rows_key)
    if csv_fallback:
        path = os.path.join(DOCS, csv_fallback)
        return Data(path, {rows_key: read_csv_rows(path)}, rows_key)
    raise FileNotFoundError(f"update_docs: {os.path.relpath(path, ROOT)} is missing")


def accuracy(sweep):
    """One sweep of scripts/accuracy_vs_time.py: results.json, or the sweep's CSV."""
    return load("accuracy-vs-time/results", sweep, f"accuracy-vs-time/{sweep}.csv")


def table(header, rows, data):
    """A Markdown table (first column left-aligned, the rest right) and its source line."""
    lines = ["| " + " | ".join(header) + " |",
             "|" + "|".join("---" if i == 0 else "---:" for i in range(len(header))) + "|"]
    lines += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    sources = data if isinstance(data, list) else [data]
    return "\n".join(lines) + "\n\n" + " ".join(d.source() for d in sources) + "\n"


def ms(v):
    return f"{v:.0f}" if v >= 100 else f"{v:.1f}"


def ratio(a, b, digits=2):
    return f"{a / b:.{digits}f}" if a and b else ""


def span(values):
    return f"{min(values):.2f}–{max(values):.2f}"


def short(scene):
    """A scene's name in prose: its OBJ's, or its folder's for an animation's first frame."""
    folder, _, obj = scene.rpartition("/")
    return folder if obj.startswith("frame_") or folder == "testdata" else obj.removesuffix(".obj")


# ---- docs/performance.md, docs/accuracy.md, docs/kd-tree.md, docs/effects.md (once the README) ----

def performance():
    build = load("bench-build", csv_fallback="bench-build.csv")
    render = load("bench-render", csv_fallback="bench-render.csv")
    by_scene = {r["scene"]: r for r in build.rows}
    rows = []
    for name, label in (("bart-kitchen/frame_000.obj", "BART Kitchen"),
                        ("dragon/dragon_res2.obj", "dragon res2")):
        r = by_scene.get(name)
        if not r:
            continue
        rows.append([f"build ms, {label} ({r['triangles']} triangles), high",
                     ms(r["opencl_ms"]), ms(r["embree_medium_ms"]),
                     "kdray / Embree medium build time", ratio(r["opencl_ms"],
                                                               r["embree_medium_ms"])])
        rows.append([f"build ms, {label}, kdray's OpenCL builder against its reference builder",
                     ms(r["opencl_ms"]), f"{ms(r['reference_ms'])} (reference)",
                     "reference / OpenCL build time", ratio(r["reference_ms"], r["opencl_ms"])])
    with_ref = [r for r in build.rows if r.get("reference_sah")]
    if with_ref:
        sah = [r["opencl_sah"] / r["reference_sah"] for r in with_ref]
        worst = max(with_ref, key=lambda r: r["opencl_sah"] / r["reference_sah"])
        rows.append([f"SAH cost, high, every scene (highest: {short(worst['scene'])})", "", "",
                     "OpenCL / reference SAH cost", span(sah)])
    per_tri = [r["opencl_bytes_per_tri"] for r in build.rows if r.get("opencl_bytes_per_tri")]
    if per_tri:
        rows.append(["device bytes per triangle, every scene",
                     f"{min(per_tri):.0f}–{max(per_tri):.0f}", "", "", ""])
    primary = [r for r in render.rows if r["kind"] == "primary" and r.get("embree_mrays_per_s")]
    for r in primary:
        if r["scene"] == "bart-kitchen/frame_000.obj":
            rows.append(["primary rays, Mrays/s, BART Kitchen", f"{r['kdray_mrays_per_s']:.2f}",
                         f"{r['embree_mrays_per_s']:.2f}", "kdray / Embree Mrays/s",
                         ratio(r["kdray_mrays_per_s"], r["embree_mrays_per_s"])])
    if primary:
        least = min(primary, key=lambda r: r["kdray_mrays_per_s"] / r["embree_mrays_per_s"])
        rows.append([f"primary rays, every scene (least: {short(least['scene'])})", "", "",
                     "kdray / Embree Mrays/s",
                     span([r["kdray_mrays_per_s"] / r["embree_mrays_per_s"] for r in primary])])
    for r in render.rows:
        if r["kind"] == "dynamic" and r["scene"] in ("bart-kitchen", "bart-robots"):
            rows.append([f"frame ms (build + trace), {r['scene']}, {r['frames']} frames, "
                         "render's default for animations (low)", ms(r["kdray_frame_ms"]),
                         ms(r["embree_frame_ms"]) if r.get("embree_frame_ms") else "",
                         "kdray / Embree medium frame time",
                         ratio(r["kdray_frame_ms"], r.get("embree_frame_ms"))])
    glass = render.value.get("glass_room")
    if glass:
        rows.append(["frame ms, glass room, 640x480, 1 spp, every effect",
                     ms(glass["frame_ms"]), "", "", ""])
    return table(["figure", "kdray", "Embree", "ratio (which way)", "ratio"], rows,
                 [build, render])


def cold_build():
    data = load("cold-build", rows_key=None)
    scenes = data.value["scenes"]
    placed = all("os_placed" in r for r in scenes.values())
    rows = []
    for name, r in scenes.items():
        row = [name, ms(r["cold_build_ms"]), ms(r["warm_build_ms"]), f"{r['cold_over_warm']:.2f}",
               f"{r['cold_minor_faults']:.0f}" if "cold_minor_faults" in r else ""]
        if placed:
            p = r["os_placed"]
            row += [ms(p["warm_build_ms"]), f"{p['cold_over_warm']:.2f}"]
        rows.append(row)
    header = ["scene", "cold build ms", "warm build ms", "cold / warm build time",
              "cold process's page faults"]
    if placed:
        header += ["warm build ms, threads placed by the OS", "cold / warm, placed by the OS"]
    return table(header, rows, data)


def quality_defaults():
    data = load("quality-ladder", rows_key=None)
    d = data.value["defaults"]
    rows = [[q, ms(d["mean_build_ms"][q]), ms(d["mean_trace_ms"][q]), ms(d["mean_frame_ms"][q]),
             f"{d['mean_frame_ms'][q] / d['mean_frame_ms'][d['animation']]:.2f}"]
            for q in ("low", "medium", "high")]
    return table(["quality", "mean build ms", "mean trace ms", "mean frame ms",
                  f"frame time / {d['animation']}'s"], rows, data)


def effect_costs():
    data = load("scene-effects", rows_key="effect_costs")
    rows = [[r["effect"], r["scene"], ms(r["with_trace_ms"]), ms(r["without_trace_ms"]),
             f"{r['ratio']:.2f}"] for r in data.rows]
    return table(["effect", "scene", "trace ms with it", "trace ms without",
                  "with / without trace time"], rows, data)


def scale():
    data = load("scale")
    rows = [[f"{r['triangles']:,}", f"{r['build_ms']:,.0f}", f"{r['wall_s']:.1f}",
             f"{r['peak_rss_bytes'] / 2**30:.1f}", f"{r['device_bytes_per_triangle']:,.0f}"]
            for r in data.rows if r["status"] == "ok"]
    return table(["triangles", "build ms", "whole command s", "peak host memory GiB",
                  "device bytes per triangle"], rows, data)


# ---- the accuracy-vs-time sweeps -----------------------------------------------------------------

def fastest_frame():
    data = accuracy("tree_quality")
    rows = []
    for b in best_tree_settings(data.rows):
        scene_rows = [r for r in data.rows if r["scene"] == b["scene"]]
        ref = next((r for r in scene_rows if r["builder"] == "reference"), None)
        frames = f", {scene_rows[0]['frames']} frames" if b["kind"] == "dynamic" else ""
        d, fast, traced = b["default"], b["rebuilt"], b["traced"]
        rows.append([f"{b['scene']}{frames} ({b['kind']}, {b['triangles']} tris)",
                     f"{fast['setting']}: {fast['build_ms']:.0f} + {fast['trace_ms']:.0f}",
                     f"{d['build_ms']:.0f} + {d['trace_ms']:.0f}",
                     f"{ref['build_ms']:.0f} + {ref['trace_ms']:.0f}" if ref else "",
                     f"{traced['setting']}: {traced['trace_ms']:.0f}",
                     ratio(traced["trace_ms"], d["trace_ms"])])
    return table(["scene", "fastest build + trace ms", "default (T=64, C_e=0.25, 32 bins) ms",
                  "reference SAH ms", "fastest trace ms", "fastest / default trace time"],
                 rows, data)


def median_split():
    data = accuracy("tree_quality")
    rows = []
    for scene in dict.fromkeys(r["scene"] for r in data.rows):
        by = {r["setting"]: r for r in data.rows if r["scene"] == scene}
        if "median" not in by or "T=64" not in by:
            continue
        m, d = by["median"], by["T=64"]
        rows.append([scene, ratio(m["sah_cost"], d["sah_cost"], 3),
                     ratio(m["trace_ms"], d["trace_ms"]), ratio(m["build_ms"], d["build_ms"])])
    return table(["scene", "median / 32 bins SAH cost", "median / 32 bins trace time",
                  "median / 32 bins build time"], rows, data)


def spp_doubling():
    data = accuracy("image_accuracy")
    rows = []
    for scene in dict.fromkeys(r["scene"] for r in data.rows):
        spp = {r["spp"]: r for r in data.rows if r["scene"] == scene and r["sweep"] == "spp"}
        depth = [r for r in data.rows if r["scene"] == scene and r["sweep"] == "max_depth"]
        if 4 not in spp or len(spp) < 2:
            continue
        top = max(spp)
        doublings = math.log2(top / 4)
        slope = (spp[top]["psnr"] - spp[4]["psnr"]) / doublings if doublings else float("nan")
        time_step = (spp[top]["trace_ms"] / spp[4]["trace_ms"]) ** (1 / doublings) \
            if doublings else float("nan")
        # The depth where the error stops falling: the least within 0.1 dB of the deepest.
        enough = ""
        if depth:
            deepest = max(depth, key=lambda r: r["max_depth"])
            enough = min(r["max_depth"] for r in depth if r["psnr"] >= deepest["psnr"] - 0.1)
        rows.append([scene, f"{spp[min(spp)]['psnr']:.1f}", f"{spp[4]['psnr']:.1f}",
                     f"{spp[top]['psnr']:.1f} (spp {top})", f"{slope:.1f}",
                     f"{time_step:.2f}", enough])
    return table(["scene", "PSNR dB at spp 1", "at spp 4", "at the most spp",
                  "dB per doubling of spp from spp 4", "trace time per doubling (x)",
                  "max_depth where the error stops falling"], rows, data)


def robustness_speed():
    data = accuracy("robustness")
    rows = []
    ordinary = [r for r in data.rows if r["pixels"] == ""]
    for scene in dict.fromkeys(r["scene"] for r in ordinary):
        t = {r["intersect"]: r["trace_ms"] for r in ordinary if r["scene"] == scene}
        w, p, m = t.get("watertight"), t.get("watertight, packets"), t.get("moller")
        rows.append([scene, ms(w), ms(p) if p else "", ms(m) if m else "", ratio(p, w),
                     ratio(m, w)])
    return table(["scene", "watertight trace ms", "watertight, packets", "Möller–Trumbore",
                  "packets / one ray trace time", "Möller–Trumbore / watertight trace time"],
                 rows, data)


def robustness_leaks():
    data = accuracy("robustness")
    hard = [r for r in data.rows if r["pixels"] != ""]
    modes = [m for m in ("watertight", "watertight, packets", "moller", "Embree peer")
             if any(r["intersect"] == m for r in hard)]
    rows = []
    for scene in dict.fromkeys(r["scene"] for r in hard):
        by = {r["intersect"]: r for r in hard if r["scene"] == scene}
        pixels = next(iter(by.values()))["pixels"]
        rows.append([scene, pixels, *[by[m]["leaks"] if m in by else "" for m in modes]])
    names = {"moller": "Möller–Trumbore"}
    return table(["closed mesh, camera inside, rays through vertices", "pixels",
                  *[f"{names.get(m, m)} leaks" for m in modes]], rows, data)


# ---- docs/accuracy-vs-time: what the numerics of issue #20 cost ---------------------------------

def numerics_cost():
    """The refined t and the scene frame, each an A/B of two binaries (scripts/bench_ab.py):
    the trace, build and frame time of the animations, head over base."""
    rows, sources = [], []
    for stem, what in (("refined-t-ab", "refined t (against float t)"),
                       ("scene-frame-ab", "scene frame (against coordinates as read)")):
        data = load(stem)
        sources.append(data)
        by_what = {r["what"]: r for r in data.rows}
        for scene in ("bart-kitchen", "bart-robots"):
            cells = []
            for part in ("trace_ms", "build_ms", "frame_ms"):
                r = by_what.get(f"render {scene}: {part} per frame")
                cells.append(f"{r['head_over_base']:.2f}" if r else "")
            rows.append([what, scene, *cells])
    return table(["what it adds", "animation", "trace time", "build time", "frame time"], rows,
                 sources)


# ---- docs/reliability.md: the fuzz runs ----------------------------------------------------------

def fuzz_runs():
    data = load("fuzz-runs")
    rows = [[f"`{r['target']}`", r["seconds"], f"{r['executions']:,}",
             f"{r['executions_per_second']:,}", r["coverage"] if r["coverage"] is not None else "",
             r["corpus_files"], r["peak_rss_mb"], len(r["findings"])] for r in data.rows]
    return table(["target", "seconds", "executions", "per second", "coverage (edges)",
                  "corpus files", "peak RSS MB", "findings"], rows, data)


# ---- docs/gpu-kernels.md: each kernel compiled for NVIDIA and AMD ---------------------------------

def gpu_kernels():
    data = load("gpu-kernels")
    budgets = data.value["budgets"]
    by_kernel = {}
    for r in data.rows:
        by_kernel.setdefault((r["file"], r["kernel"]), {})[r["target"]] = r

    def span(r):
        lo, hi = r["private_min"], r["private"]
        return f"{hi}" if lo == hi else f"{lo}–{hi}"

    rows = []
    for (file, kernel), t in sorted(by_kernel.items()):
        nv, amd = t.get("nvptx", {}), t.get("amdgcn", {})
        budget = budgets["private_bytes_of"].get(kernel, budgets["private_bytes"])
        rows.append([f"`{kernel}`", file, nv.get("programs", amd.get("programs", "")),
                     span(nv) if nv else "", nv.get("local", ""), span(amd) if amd else "",
                     amd.get("local", ""), amd.get("vgprs", ""), amd.get("occupancy", ""),
                     budget])
    problems = data.value.get("problems", [])
    verdict = ("No symbol is left unresolved and every kernel is inside its budgets "
               f"({data.value['programs']} programs, both targets, -O0 and -O2)."
               if not problems else "Problems: " + "; ".join(problems))
    return verdict + "\n\n" + table(
        ["kernel", "file", "programs", "NVIDIA private B", "NVIDIA local B", "AMD private B",
         "AMD local B", "AMD VGPRs", "AMD waves/SIMD", "private budget B"], rows, data)


TABLES = {
    "performance": performance,
    "cold-build": cold_build,
    "quality-defaults": quality_defaults,
    "effect-costs": effect_costs,
    "scale": scale,
    "fastest-frame": fastest_frame,
    "median-split": median_split,
    "spp-doubling": spp_doubling,
    "robustness-speed": robustness_speed,
    "robustness-leaks": robustness_leaks,
    "fuzz-runs": fuzz_runs,
    "numerics-cost": numerics_cost,
    "gpu-kernels": gpu_kernels,
}


def markdown_files():
    found = [os.path.join(ROOT, "README.md")]
    for folder, _, files in os.walk(DOCS):
        found += [os.path.join(folder, f) for f in sorted(files) if f.endswith(".md")]
    return found


def regenerate(text, path):
    """The text with every generated block rewritten; raises on an unknown name."""
    def body(match):
        name = match["name"]
        if name not in TABLES:
            raise KeyError(f"{os.path.relpath(path, ROOT)}: unknown generated table '{name}' "
                           f"(known: {', '.join(TABLES)})")
        return match[1] + TABLES[name]() + match[4]
    return BLOCK.sub(body, text)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--check", action="store_true",
                        help="change nothing; exit 1 naming every table that differs from its data")
    parser.add_argument("--root", help="the repository whose README.md and docs/ to read "
                                        "(default: this script's; tests/update_docs_check.py)")
    args = parser.parse_args()
    if args.root:
        global ROOT, DOCS
        ROOT = os.path.abspath(args.root)
        DOCS = os.path.join(ROOT, "docs")
    stale = []
    try:
        for path in markdown_files():
            with open(path) as f:
                text = f.read()
            new = regenerate(text, path)
            if new == text:
                continue
            old_blocks = {(m["name"], m["body"]) for m in BLOCK.finditer(text)}
            for m in BLOCK.finditer(new):
                if (m["name"], m["body"]) not in old_blocks:
                    stale.append(f"{os.path.relpath(path, ROOT)}: table '{m['name']}'")
            if not args.check:
                with open(path, "w") as f:
                    f.write(new)
    except (KeyError, OSError, ValueError) as e:
        print(f"update_docs: error: {e}", file=sys.stderr)
        return 1
    for s in stale:
        print(f"update_docs: {s} {'differs from its data' if args.check else 'rewritten'}",
              file=sys.stderr)
    return 1 if args.check and stale else 0


if __name__ == "__main__":
    sys.exit(main())
