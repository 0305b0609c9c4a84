#!/usr/bin/env python3
"""The device check's results as docs/bench-gpu.json and docs/bench-gpu.md: what
scripts/device-check.sh wrote on a lent GPU machine (its $OUT folder, or a .tgz of it), condensed
to the figures the builder issue (#28) asks for on a GPU: each scene's build at each quality with
each stage's share, the large stage's shapes, the frames traced, and the correctness cases'
agreement with the CPU reference.

    scripts/device_report.py CHECK_DIR_OR_TGZ --commit COMMIT [--out docs/bench-gpu]

COMMIT is the commit the bundle (scripts/device-bundle.sh) was built from; the bundle itself does
not record it. Reads only kdray's own JSON (stats, `build --json`, `compare`), never edits it.
"""
import argparse
import glob
import json
import os
import sys
import tarfile
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import ROOT, write_json, write_markdown  # noqa: E402

STAGES = ["upload", "aabbs", "large_nodes", "small_nodes", "output", "download"]


def load(path):
    with open(path) as f:
        return json.load(f)


def check_folder(source, tmp):
    """The folder holding summary.json: `source` itself, or where its .tgz unpacks."""
    if os.path.isdir(source):
        root = source
    else:
        with tarfile.open(source) as tar:
            tar.extractall(tmp)
        root = tmp
    found = glob.glob(os.path.join(root, "**", "summary.json"), recursive=True)
    if not found:
        sys.exit(f"device_report: {source}: no summary.json (not a device-check output)")
    return os.path.dirname(found[0])


def scene_name(scene):
    """"folder/file.obj" of the scene record's path (the bundle's scenes/ keeps ../shared's
    folders)."""
    path = scene["path"] if isinstance(scene, dict) else scene
    return "/".join(path.replace("\\", "/").split("/")[-2:])


def bench_files(folder, prefix):
    """(case, data) of each bench/PREFIX-CASE.json the check wrote, by name."""
    for path in sorted(glob.glob(os.path.join(folder, "bench", f"{prefix}-*.json"))):
        yield os.path.basename(path)[len(prefix) + 1:-len(".json")], load(path)


def build_rows(folder):
    rows = []
    for case, d in bench_files(folder, "build"):
        timings = d["timings_ms"]
        stage_sum = sum(timings.get(s, 0.0) for s in STAGES)
        rows.append({
            "case": case,
            "scene": scene_name(d["scene"]), "triangles": d["triangles"], "quality": d["quality"],
            "large_stage": d["large_stage"], "small_stage": d["small_stage"],
            "build_ms": d["build_ms"], "build_ms_samples": d.get("build_ms_samples", [d["build_ms"]]),
            "timings_ms": timings,
            "stage_share": {s: timings.get(s, 0.0) / stage_sum for s in STAGES} if stage_sum else {},
            "sah_cost": d["sah_cost"], "nodes": d["nodes"],
            "kernel_launches": d["kernel_launches"], "device_syncs": d["device_syncs"],
            "device_bytes": d["device_bytes"], "prepare_ms": d["prepare_ms"]})
    return rows


def render_rows(folder):
    rows = []
    for case, d in bench_files(folder, "render"):
        frame = d["frames"][0]
        rows.append({"case": case,
                     "quality": d["quality"], "size": [d["image"]["width"], d["image"]["height"]]
                     if isinstance(d.get("image"), dict) and "width" in d["image"] else None,
                     "build_ms": frame["build_ms"], "trace_ms": frame["trace_ms"],
                     "mrays_per_s": frame["mrays_per_s"], "rays": frame["rays"]})
    return rows


def correctness_rows(folder):
    rows = []
    for path in sorted(glob.glob(os.path.join(folder, "correctness", "*.json"))):
        name = os.path.basename(path)
        if name.endswith(".stats.json"):
            continue
        d = load(path)
        row = {"case": name[:-len(".json")], "kind": d.get("kind"), "agree": d.get("agree")}
        for key in ("mismatch_fraction", "fraction_over", "max_fraction", "pixels", "psnr_db"):
            if key in d:
                row[key] = d[key]
        rows.append(row)
    return rows


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("source")
    parser.add_argument("--commit", required=True)
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "bench-gpu"))
    args = parser.parse_args()
    with tempfile.TemporaryDirectory(prefix="kdray-device-report-") as tmp:
        folder = check_folder(args.source, tmp)
        summary = load(os.path.join(folder, "summary.json"))
        devices = load(os.path.join(folder, "info", "devices.json"))
        with open(os.path.join(folder, "info", "version.txt")) as f:
            version = f.read().strip()
        with open(os.path.join(folder, "info", "machine.txt")) as f:
            machine = f.read().strip().splitlines()
        record = {"commit": args.commit, "kdray": version,
                  "devices": devices.get("devices", devices), "machine": machine,
                  "check_total_ms": summary["total_ms"], "check_failures": summary["failures"],
                  "steps": len(summary["steps"]), "builds": build_rows(folder),
                  "renders": render_rows(folder), "correctness": correctness_rows(folder)}
    write_json(args.out + ".json", record)
    gpu = next((d for d in record["devices"] if d.get("type") == "GPU"), record["devices"][0])
    lines = ["# kdray on a GPU", "",
             f"Generated by `scripts/device_report.py` from `{os.path.basename(args.out)}.json`: "
             f"`scripts/device-check.sh` run from a device bundle (`scripts/device-bundle.sh`) "
             f"built at commit {args.commit}, on **{gpu['name']}** ({gpu['platform']}, "
             f"{gpu['version']}, {gpu['compute_units']} compute units). The check's "
             f"{record['steps']} steps took {record['check_total_ms'] / 1000:.1f} s with "
             f"{record['check_failures']} failed. Builds: `kdray build --json --repeat N`, the "
             "median of the warm builds; each stage's share is of the stages' sum.", "",
             "## Builds", "",
             "| case | scene | quality | large stage | small stage | build ms | " +
             " | ".join(f"{s} share" for s in STAGES) + " | SAH cost | nodes | launches | "
             "host waits |",
             "|---|---|---|---|---|---:|" + "---:|" * len(STAGES) + "---:|---:|---:|---:|"]
    for r in record["builds"]:
        shares = " | ".join(f"{100 * r['stage_share'].get(s, 0):.0f}%" for s in STAGES)
        lines.append(f"| {r['case']} | {r['scene']} | {r['quality']} | {r['large_stage']} | {r['small_stage']} | "
                     f"{r['build_ms']:.1f} | {shares} | {r['sah_cost']:.1f} | {r['nodes']} | "
                     f"{r['kernel_launches']} | {r['device_syncs']} |")
    lines += ["", "## Frames (build + trace, the render file's camera, lights and size)", "",
              "| case | quality | build ms | trace ms | Mrays/s |", "|---|---|---:|---:|---:|"]
    for r in record["renders"]:
        lines.append(f"| {r['case']} | {r['quality']} | {r['build_ms']:.1f} | "
                     f"{r['trace_ms']:.1f} | {r['mrays_per_s']:.0f} |")
    agree = sum(1 for r in record["correctness"] if r["agree"])
    lines += ["", "## Correctness", "",
              f"{agree} of {len(record['correctness'])} comparisons with the CPU reference "
              "agree (`kdray compare`: hit AOVs within conventions.md's mismatch fraction of "
              "1e-4, images within 0.5% of pixels off by more than 0.02).", "",
              "| case | compared | agree | pixels that differ (fraction) |", "|---|---|---|---:|"]
    for r in record["correctness"]:
        fraction = r.get("mismatch_fraction", r.get("fraction_over"))
        shown = f"{fraction:.2e}" if isinstance(fraction, (int, float)) else "-"
        lines.append(f"| {r['case']} | {r['kind']} | {'yes' if r['agree'] else 'NO'} | {shown} |")
    write_markdown(args.out, lines)
    return 0


if __name__ == "__main__":
    sys.exit(main())
