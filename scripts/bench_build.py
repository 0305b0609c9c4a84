#!/usr/bin/env python3
"""Build benchmark: the OpenCL builder at each build quality, the CPU reference builder and Embree
(low, medium and high quality BVH builds), side by side in one run, for every testdata and shared
scene. The OpenCL columns without a level are `kdray build`'s default, high.

For each scene and builder: a warm-up build, then the median of --repeat builds (kdray's
`build --repeat`, the peer's `--repeat`), with SAH cost (C_t = 15, C_i = 20) and node counts.
Beside kdray's warm median, its cold figure: --cold fresh processes that each build once, as a
user's single `kdray build` does (the median of their build_ms, and of the whole process's wall
time, which adds the OBJ load, the device opened and the programs built).
Writes docs/bench-build.md, .csv and .json (or --out) with the commit, machine and command.

  scripts/bench_build.py --kdray build/kdray [--repeat 5] [--cold 5] [--no-reference]
                         [--scenes SUBSTR]
  scripts/bench_build.py --cold-only [--out docs/cold-build] [--scenes SUBSTR]

--cold-only measures only kdray's cold and warm builds, in --cold rounds of one fresh single
build and one `build --repeat` process in turn (so that a slow spell of a shared machine hits
both), and writes OUT.json and OUT.md: the medians, the ratio cold / warm, and per stage. Where
kdray pins PoCL's threads, every round also runs both processes with them placed by the OS
(POCL_AFFINITY=0), for what the pinning changes.
"""
import argparse
import json
import os
import resource
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import (ROOT, benchmark_scenes, build_peer, median, run_json,  # noqa
                          run_record, write_json, write_report)

# What `kdray build --json` reports of the process beside the build (absent from older builds),
# and what cold_build measures of it.
PROCESS_KEYS = ("load_ms", "prepare_ms", "compile_ms", "user_ms", "sys_ms", "minor_faults")


def cold_build(kdray, obj, env=None):
    """One fresh `kdray build OBJ --json`: its report, with the process's wall time (wall_ms),
    CPU time (user_ms, sys_ms) and minor page faults, which a shared machine's load disturbs
    less than the times."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    result = subprocess.run([kdray, "build", obj, "--json", "--builder", "opencl"],
                            capture_output=True, text=True, env=env)
    wall_ms = (time.perf_counter() - start) * 1e3
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if result.returncode != 0:
        raise RuntimeError(f"{kdray} build {obj} failed: {result.stderr.strip()}")
    report = json.loads(result.stdout)
    report.update(wall_ms=wall_ms, user_ms=(after.ru_utime - before.ru_utime) * 1e3,
                  sys_ms=(after.ru_stime - before.ru_stime) * 1e3,
                  minor_faults=after.ru_minflt - before.ru_minflt)
    return report


def stage_medians(reports):
    stages = reports[0]["timings_ms"].keys()
    return {s: median([r["timings_ms"][s] for r in reports]) for s in stages}


def cold_and_warm(kdray, obj, rounds, repeat, envs=(None,)):
    """Rounds of one cold single build and one warm `build --repeat` process in turn, each round
    once per environment of `envs` (None: this one), so that a slow spell of a shared machine hits
    every one; a summary per environment, in their order."""
    samples = [([], [], []) for _ in envs]  # per environment: cold reports, warm times, reports
    for _ in range(rounds):
        for env, (cold, warm, warm_reports) in zip(envs, samples):
            cold.append(cold_build(kdray, obj, env))
            report = run_json([kdray, "build", obj, "--json", "--builder", "opencl",
                               "--repeat", str(repeat)], env)
            warm.extend(report["build_ms_samples"])
            warm_reports.append(report)
    return [summarise_cold_and_warm(*s) for s in samples]


def summarise_cold_and_warm(cold, warm, warm_reports):
    out = {"triangles": cold[0]["triangles"],
           "cold_build_ms": median([r["build_ms"] for r in cold]),
           "cold_process_ms": median([r["wall_ms"] for r in cold]),
           "warm_build_ms": median(warm),
           "cold_samples": [{k: r[k] for k in ("build_ms", "wall_ms", *PROCESS_KEYS) if k in r}
                            for r in cold],
           "warm_samples": warm,
           "cold_stages_ms": stage_medians(cold),
           "warm_stages_ms": stage_medians(warm_reports),
           "cold_device_bytes": median([r.get("device_bytes", 0) for r in cold])}
    for key in PROCESS_KEYS:
        if all(key in r for r in cold):
            out[f"cold_{key}"] = median([r[key] for r in cold])
    out["cold_over_warm"] = out["cold_build_ms"] / out["warm_build_ms"]
    return out


def selected(name, scenes):
    """Whether scene `name` contains one of the comma-separated substrings of --scenes."""
    return not scenes or any(part in name for part in scenes.split(","))


def default_device_pins_threads(kdray):
    """Whether the device `kdray build` picks (the first GPU, else the first device) is a CPU
    device whose driver threads kdray had pinned (`kdray stats`)."""
    devices = run_json([kdray, "stats", "--json"]).get("devices", [])
    if not devices or any(d.get("type") == "GPU" for d in devices):
        return False
    return bool(devices[0].get("threads_pinned"))


def cold_only(args):
    """Writes OUT.json and OUT.md: kdray's cold and warm builds of each scene; where kdray pins
    PoCL's threads, also with them placed by the OS (POCL_AFFINITY=0), round by round."""
    envs = [None]
    if default_device_pins_threads(args.kdray):
        envs.append(dict(os.environ, POCL_AFFINITY="0"))
    scenes = {}
    for name, obj, _ in benchmark_scenes():
        if not selected(name, args.scenes):
            continue
        summaries = cold_and_warm(args.kdray, obj, args.cold, args.repeat, envs)
        scenes[name] = summaries[0]
        print(f"{name}: cold {scenes[name]['cold_build_ms']:.1f} ms (process "
              f"{scenes[name]['cold_process_ms']:.0f} ms), warm "
              f"{scenes[name]['warm_build_ms']:.1f} ms", file=sys.stderr)
        if len(summaries) > 1:
            scenes[name]["os_placed"] = {k: summaries[1][k] for k in (
                "cold_build_ms", "warm_build_ms", "cold_over_warm", "cold_samples",
                "warm_samples")}
    result = {**run_record(args.kdray), "kdray": args.kdray, "rounds": args.cold,
              "repeat": args.repeat, "pocl_cache_dir": os.environ.get("POCL_CACHE_DIR", ""),
              "threads_pinned": len(envs) > 1, "scenes": scenes}
    os.makedirs(os.path.dirname(args.out), exist_ok=True)
    write_json(args.out + ".json", result)
    placed_columns = len(envs) > 1
    lines = ["# Cold and warm builds", "",
             f"Run {result['date']} on {result['machine']}.",
             f"{args.cold} rounds, each one fresh `kdray build SCENE --json` (cold: its build_ms, "
             f"and the process's wall time) and one `kdray build --repeat {args.repeat}` process "
             "(warm: its builds after the warm-up); medians. PoCL's kernel cache was warm."
             + (" The last columns: PoCL's threads placed by the OS (POCL_AFFINITY=0) rather "
                "than pinned at kdray's asking (cl/runtime/driver_threads.h), a process of each "
                "in every round after the pinned ones."
                if placed_columns else ""), "",
             "| scene | triangles | cold build ms | warm build ms | cold / warm "
             "| cold process ms | its load, prepare ms | its CPU user, sys ms "
             "| its page faults |" + (" OS-placed threads: cold, warm build ms | cold / warm |"
                                      if placed_columns else ""),
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|" + ("---:|---:|"
                                                                 if placed_columns else "")]

    def pair(r, keys):
        return ", ".join(f"{r[f'cold_{k}']:.0f}" for k in keys if f"cold_{k}" in r)

    for name, r in scenes.items():
        line = (f"| {name} | {r['triangles']} | {r['cold_build_ms']:.1f} | "
                f"{r['warm_build_ms']:.1f} | {r['cold_over_warm']:.2f} | "
                f"{r['cold_process_ms']:.0f} | {pair(r, ('load_ms', 'prepare_ms'))} | "
                f"{pair(r, ('user_ms', 'sys_ms'))} | {pair(r, ('minor_faults',))} |")
        if "os_placed" in r:
            p = r["os_placed"]
            line += (f" {p['cold_build_ms']:.1f}, {p['warm_build_ms']:.1f} | "
                     f"{p['cold_over_warm']:.2f} |")
        lines.append(line)
    with open(args.out + ".md", "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--kdray", default=os.path.join(ROOT, "build", "kdray"))
    parser.add_argument("--repeat", type=int, default=5)
    parser.add_argument("--reference-repeat", type=int, default=3)
    parser.add_argument("--no-reference", action="store_true", help="skip the slow CPU reference")
    parser.add_argument("--scenes", default="",
                        help="only scenes whose name contains this (or one of a,b,...)")
    parser.add_argument("--cold", type=int, default=5,
                        help="fresh single-build processes per scene for the cold figure")
    parser.add_argument("--cold-only", action="store_true",
                        help="only kdray's cold and warm builds, into OUT.json and OUT.md")
    parser.add_argument("--out", default=None,
                        help="default: docs/bench-build (docs/cold-build with --cold-only)")
    args = parser.parse_args()
    if args.out is None:
        args.out = os.path.join(ROOT, "docs", "cold-build" if args.cold_only else "bench-build")
    if args.cold_only:
        return cold_only(args)

    peer = build_peer()
    if not peer:
        print("bench_build: the Embree peer is not available; its columns stay empty",
              file=sys.stderr)
    rows = []
    for name, obj, camera in benchmark_scenes():
        if not selected(name, args.scenes):
            continue
        row = {"scene": name}
        ocl = run_json([args.kdray, "build", obj, "--json", "--builder", "opencl",
                        "--repeat", str(args.repeat)])
        row.update(triangles=ocl["triangles"], opencl_ms=ocl["build_ms"],
                   opencl_sah=ocl["sah_cost"], opencl_nodes=ocl["nodes"],
                   opencl_bytes_per_tri=ocl.get("device_bytes_per_triangle"))
        for quality in ("low", "medium"):
            level = run_json([args.kdray, "build", obj, "--json", "--builder", "opencl",
                              "--quality", quality, "--repeat", str(args.repeat)])
            row[f"opencl_{quality}_ms"] = level["build_ms"]
            row[f"opencl_{quality}_sah"] = level["sah_cost"]
        if args.cold > 0:
            cold = [cold_build(args.kdray, obj) for _ in range(args.cold)]
            row.update(opencl_cold_ms=median([r["build_ms"] for r in cold]),
                       opencl_cold_process_ms=median([r["wall_ms"] for r in cold]))
        if not args.no_reference:
            ref = run_json([args.kdray, "build", obj, "--json", "--builder", "reference",
                            "--repeat", str(args.reference_repeat)])
            row.update(reference_ms=ref["build_ms"], reference_sah=ref["sah_cost"],
                       reference_nodes=ref["nodes"])
        if peer:
            for quality in ("low", "medium", "high"):
                emb = run_json([peer, obj, "--camera", camera, "--quality", quality,
                                "--repeat", str(args.repeat + 1), "--threads", str(os.cpu_count())])
                row[f"embree_{quality}_ms"] = emb["build_ms"]
        rows.append(row)
        print(f"{name}: {row}", file=sys.stderr)

    def ratio(a, b):
        return f"{a / b:.2f}" if a and b else ""

    def fmt(v, digits=1):
        return f"{v:.{digits}f}" if isinstance(v, float) else ("" if v is None else str(v))

    record = run_record(args.kdray)
    lines = [
        "# Build benchmark",
        "",
        f"Run {record['date']} at {record['commit']} on {record['machine']}.",
        f"Median of {args.repeat} builds after a warm-up (reference: {args.reference_repeat}); "
        f"OpenCL cold: the median of {args.cold} fresh processes that build once (the build's "
        "build_ms, and the process's wall time with the load, the device and the programs). "
        "SAH cost with C_t = 15, C_i = 20 (conventions.md). Embree builds a BVH, not a kd-tree: "
        "its column is the time to beat, not a quality comparison.",
        "",
        "| scene | triangles | OpenCL ms | OpenCL cold ms | cold process ms | reference ms "
        "| Embree medium ms | Embree high ms "
        "| OpenCL / Embree medium | reference / OpenCL | SAH OpenCL | SAH reference "
        "| SAH OpenCL / reference | nodes OpenCL | device bytes / tri |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    level_lines = [
        "", "## Build qualities", "",
        "kdray's `--quality` levels (high is the table above's OpenCL column) beside Embree's.",
        "",
        "| scene | OpenCL low ms | medium ms | high ms | Embree low ms | medium ms | high ms "
        "| low / Embree medium | SAH low / reference | SAH medium / reference "
        "| SAH high / reference |",
        "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        level_lines.append(
            f"| {r['scene']} | {fmt(r.get('opencl_low_ms'))} | {fmt(r.get('opencl_medium_ms'))} | "
            f"{fmt(r['opencl_ms'])} | {fmt(r.get('embree_low_ms'))} | "
            f"{fmt(r.get('embree_medium_ms'))} | {fmt(r.get('embree_high_ms'))} | "
            f"{ratio(r.get('opencl_low_ms'), r.get('embree_medium_ms'))} | "
            f"{ratio(r.get('opencl_low_sah'), r.get('reference_sah'))} | "
            f"{ratio(r.get('opencl_medium_sah'), r.get('reference_sah'))} | "
            f"{ratio(r['opencl_sah'], r.get('reference_sah'))} |")
    for r in rows:
        lines.append(
            f"| {r['scene']} | {r['triangles']} | {fmt(r['opencl_ms'])} | "
            f"{fmt(r.get('opencl_cold_ms'))} | {fmt(r.get('opencl_cold_process_ms'), 0)} | "
            f"{fmt(r.get('reference_ms'))} | {fmt(r.get('embree_medium_ms'))} | "
            f"{fmt(r.get('embree_high_ms'))} | {ratio(r['opencl_ms'], r.get('embree_medium_ms'))} | "
            f"{ratio(r.get('reference_ms'), r['opencl_ms'])} | {fmt(r['opencl_sah'])} | "
            f"{fmt(r.get('reference_sah'))} | {ratio(r['opencl_sah'], r.get('reference_sah'))} | "
            f"{r['opencl_nodes']} | {fmt(r.get('opencl_bytes_per_tri'), 0)} |")
    write_report(args.out, lines + level_lines, rows)
    write_json(args.out + ".json", {**record, "repeat": args.repeat,
                                    "reference_repeat": args.reference_repeat,
                                    "cold": args.cold, "rows": rows})
    return 0


if __name__ == "__main__":
    sys.exit(main())
