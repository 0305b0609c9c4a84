#!/usr/bin/env python3
"""Build benchmark: the OpenCL builder, the CPU reference builder and Embree (medium and high
quality BVH builds), side by side in one run, for every testdata and shared scene.

For each scene and builder: a warm-up build, then the median of --repeat builds (kdray's
`build --repeat`, the peer's `--repeat`), with SAH cost (C_t = 15, C_i = 20) and node counts.
Writes docs/bench-build.md and docs/bench-build.csv (or --out) with the machine it ran on.

  scripts/bench_build.py --kdray build/kdray [--repeat 5] [--no-reference] [--scenes SUBSTR]
"""
import argparse
import datetime
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import (ROOT, benchmark_scenes, build_peer, machine_description, run_json,  # noqa
                          write_report)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--reference-repeat", type=int, default=3)
    parser.add_argument("--no-reference", action="store_true", help="skip the slow CPU reference")
    parser.add_argument("--scenes", default="", help="only scenes whose name contains this")
    parser.add_argument("--out", default=os.path.join(ROOT, "docs", "bench-build"))
    args = parser.parse_args()

    peer = build_peer()
    if not peer:
        print("bench_build: the Embree peer is not available; its columns stay empty",
              file=sys.stderr)
    rows = []
    for name, obj, camera in benchmark_scenes():
        if args.scenes not in name:
            continue
        row = {"scene": name}
        ocl = run_json([args.kdray, "build", obj, "--json", "--builder", "opencl",
                        "--repeat", str(args.repeat)])
        row.update(triangles=ocl["triangles"], opencl_ms=ocl["build_ms"],
                   opencl_sah=ocl["sah_cost"], opencl_nodes=ocl["nodes"],
                   opencl_bytes_per_tri=ocl.get("device_bytes_per_triangle"))
        if not args.no_reference:
            ref = run_json([args.kdray, "build", obj, "--json", "--builder", "reference",
                            "--repeat", str(args.reference_repeat)])
            row.update(reference_ms=ref["build_ms"], reference_sah=ref["sah_cost"],
                       reference_nodes=ref["nodes"])
        if peer:
            for quality in ("medium", "high"):
                emb = run_json([peer, obj, "--camera", camera, "--quality", quality,
                                "--repeat", str(args.repeat + 1), "--threads", str(os.cpu_count())])
                row[f"embree_{quality}_ms"] = emb["build_ms"]
        rows.append(row)
        print(f"{name}: {row}", file=sys.stderr)

    def ratio(a, b):
        return f"{a / b:.2f}" if a and b else ""

    def fmt(v, digits=1):
        return f"{v:.{digits}f}" if isinstance(v, float) else ("" if v is None else str(v))

    lines = [
        "# Build benchmark",
        "",
        f"Run {datetime.date.today()} on {machine_description(args.kdray)}.",
        f"Median of {args.repeat} builds after a warm-up (reference: {args.reference_repeat}); "
        "SAH cost with C_t = 15, C_i = 20 (conventions.md). Embree builds a BVH, not a kd-tree: "
        "its column is the time to beat, not a quality comparison.",
        "",
        "| scene | triangles | OpenCL ms | reference ms | Embree medium ms | Embree high ms "
        "| OpenCL / Embree medium | reference / OpenCL | SAH OpenCL | SAH reference "
        "| SAH OpenCL / reference | nodes OpenCL | device bytes / tri |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        lines.append(
            f"| {r['scene']} | {r['triangles']} | {fmt(r['opencl_ms'])} | "
            f"{fmt(r.get('reference_ms'))} | {fmt(r.get('embree_medium_ms'))} | "
            f"{fmt(r.get('embree_high_ms'))} | {ratio(r['opencl_ms'], r.get('embree_medium_ms'))} | "
            f"{ratio(r.get('reference_ms'), r['opencl_ms'])} | {fmt(r['opencl_sah'])} | "
            f"{fmt(r.get('reference_sah'))} | {ratio(r['opencl_sah'], r.get('reference_sah'))} | "
            f"{r['opencl_nodes']} | {fmt(r.get('opencl_bytes_per_tri'), 0)} |")
    write_report(args.out, lines, rows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
