#!/usr/bin/python3
"""How the OpenCL builder scales: build time, peak host memory and device memory per triangle for
random-triangle scenes of 10k to 10M triangles, written as docs/scale.md and docs/scale.png.

    scripts/scale.py [--kdray build-rel/kdray] [--max 3000000] [--out docs]

Each scene is N random triangles in the unit cube (numpy's PCG64 with a fixed seed, so the same N
always gives the same scene), each a random point plus two random edge vectors of length about
cube / N^(1/3): the triangles overlap about as much at every N, as the scenes of a real scene
collection do when they grow by tessellation. kdray reads scenes only from OBJ files, so every
scene is written to a temporary folder, built with `kdray build X.obj --json` under
`/usr/bin/time -v` (peak resident set size of the whole process: OBJ text, tinyobjloader's arrays,
the scene, the host side of the build and, on PoCL, the device buffers, which live in host memory)
and deleted. Everything runs at nice 19, so that other work on the machine keeps its speed.

Needs Debian's python3-numpy and python3-matplotlib (apt), hence /usr/bin/python3 rather than
whatever python3 comes first on PATH.
"""

import argparse
import datetime
import json
import os
import platform
import re
import subprocess
import sys
import tempfile
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from bench_common import git_commit  # noqa: E402

SIZES = [10_000, 100_000, 1_000_000, 3_000_000, 10_000_000]
SEED = 20080601  # any fixed number: the scenes must not change between runs
DIGITS = 6  # coordinates as 0.dddddd: 1e-6 of the cube, far below the triangle size at 10M


def obj_lines(rng, count, edge):
    """`count` triangles as OBJ bytes: three `v` lines and `f -3 -2 -1` per triangle (relative
    indices keep every face line the same, so the whole text is built with array operations)."""
    corner = rng.random((count, 1, 3))
    edges = (rng.random((count, 2, 3)) - 0.5) * (2 * edge)
    verts = np.concatenate([corner, corner + edges[:, :1], corner + edges[:, 1:]], axis=1)
    verts = np.clip(verts, 0.0, 1.0 - 10.0**-DIGITS)
    fixed = np.round(verts * 10**DIGITS).astype(np.int64).reshape(count, 9)
    # One number: "0." and DIGITS digits; a vertex line: "v a b c\n".
    number_len = 2 + DIGITS
    vline_len = 2 + 3 * number_len + 2 + 1
    face = b"f -3 -2 -1\n"
    line = np.zeros((count, 3 * vline_len + len(face)), dtype=np.uint8)
    for k in range(3):
        base = k * vline_len
        line[:, base : base + 2] = np.frombuffer(b"v ", np.uint8)
        for axis in range(3):
            start = base + 2 + axis * (number_len + 1)
            line[:, start : start + 2] = np.frombuffer(b"0.", np.uint8)
            value = fixed[:, 3 * k + axis]
            for d in range(DIGITS):
                digit = (value // 10 ** (DIGITS - 1 - d)) % 10
                line[:, start + 2 + d] = (digit + ord("0")).astype(np.uint8)
            line[:, start + number_len] = ord(" " if axis < 2 else "\n")
    line[:, 3 * vline_len :] = np.frombuffer(face, np.uint8)
    return line.tobytes()


def write_scene(path, triangles):
    rng = np.random.Generator(np.random.PCG64(SEED + triangles))
    edge = 2.0 / triangles ** (1.0 / 3.0)
    chunk = 1_000_000
    with open(path, "wb") as out:
        for start in range(0, triangles, chunk):
            out.write(obj_lines(rng, min(chunk, triangles - start), edge))


def build(kdray, obj, timeout):
    """Runs `kdray build OBJ --json` under /usr/bin/time -v; the report and the peak RSS."""
    cmd = ["nice", "-n", "19", "/usr/bin/time", "-v", kdray, "build", obj, "--json"]
    start = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return {"status": "timeout", "wall_s": time.monotonic() - start}
    wall = time.monotonic() - start
    rss = re.search(r"Maximum resident set size \(kbytes\): (\d+)", p.stderr)
    row = {"wall_s": wall, "peak_rss_bytes": int(rss.group(1)) * 1024 if rss else None}
    signal = re.search(r"Command terminated by signal (\d+)", p.stderr)
    exit_status = re.search(r"Exit status: (\d+)", p.stderr)
    if p.returncode != 0:
        errors = [l for l in p.stderr.splitlines() if l.startswith("kdray:")]
        row["status"] = (f"signal {signal.group(1)}" if signal else
                         f"exit {exit_status.group(1) if exit_status else p.returncode}")
        row["error"] = errors[-1] if errors else p.stderr.strip().splitlines()[0]
        return row
    report = json.loads(p.stdout)
    row.update(status="ok", build_ms=report["build_ms"], device_bytes=report.get("device_bytes"),
               device_bytes_per_triangle=report.get("device_bytes_per_triangle"),
               nodes=report.get("nodes"), sah_cost=report.get("sah_cost"),
               timings_ms=report.get("timings_ms"))
    return row


def machine(kdray):
    cpu = platform.processor()
    try:
        with open("/proc/cpuinfo") as f:
            cpu = next(l.split(":", 1)[1].strip() for l in f if l.startswith("model name"))
    except (OSError, StopIteration):
        pass
    mem = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    devices = ""
    try:
        p = subprocess.run([kdray, "stats", "--json"], capture_output=True, text=True, timeout=120)
        info = json.loads(p.stdout)
        found = info.get("devices", info) if isinstance(info, dict) else info
        devices = "; ".join(f'{d.get("name")} ({d.get("version")})' for d in found
                            if isinstance(d, dict) and "name" in d)
    except (subprocess.SubprocessError, json.JSONDecodeError, OSError):
        pass
    return {"cpu": cpu, "cores": os.cpu_count(), "memory_gib": mem / 2**30,
            "os": platform.platform(), "opencl": devices,
            "date": datetime.date.today().isoformat(),
            # Other work on the machine slows the builds down; the report says how busy it was.
            "load_average": os.getloadavg()[0]}


def mib(b):
    return "–" if b is None else f"{b / 2**20:,.0f}"


def write_markdown(path, rows, info):
    lines = [
        "# OpenCL builder: scaling with scene size",
        "",
        "Written by `scripts/scale.py` (random triangles in the unit cube, fixed seed; "
        "`kdray build X.obj --json` under `/usr/bin/time -v`, at nice 19).",
        "",
        f"Machine: {info['cpu']}, {info['cores']} cores, {info['memory_gib']:.1f} GiB; "
        f"{info['os']}; OpenCL device: {info['opencl'] or 'unknown'}. Date: {info['date']}. "
        f"Load average {info.get('load_average', float('nan')):.1f} "
        f"({info.get('load_average_source', 'when the run began')}): other work on the "
        "machine slows the builds down.",
        "",
        "build_ms is the builder's own time (upload to download); peak RSS is the whole process's "
        "(OBJ text, tinyobjloader's arrays, the scene, the build; on PoCL the device buffers are "
        "host memory too). Device bytes are the builder's peak device allocation.",
        "",
        "| triangles | status | build ms | wall s | peak RSS MiB | RSS bytes/tri | device MiB "
        "| device bytes/tri |",
        "|---:|---|---:|---:|---:|---:|---:|---:|",
    ]
    for r in rows:
        n = r["triangles"]
        rss = r.get("peak_rss_bytes")
        dev = r.get("device_bytes")
        per = r.get("device_bytes_per_triangle")
        lines.append(
            f"| {n:,} | {r['status']} | "
            f"{r['build_ms']:,.0f} | " if "build_ms" in r else f"| {n:,} | {r['status']} | – | ")
        lines[-1] += (f"{r.get('wall_s', 0):.1f} | {mib(rss)} | "
                      f"{'–' if rss is None else f'{rss / n:,.0f}'} | {mib(dev)} | "
                      f"{'–' if per is None else f'{per:,.0f}'} |")
    ok = [r for r in rows if r["status"] == "ok"]
    if ok:
        big = max(ok, key=lambda r: r["triangles"])
        lines += ["", f"The largest scene that built, {big['triangles']:,} triangles, peaked at "
                  f"{big['peak_rss_bytes'] / 2**30:.1f} GiB of host memory of the machine's "
                  f"{info['memory_gib']:.1f} GiB."]
    lines += ["", "At the largest sizes the small stage's split-candidate masks (128 bytes per small-root",
              "reference) outgrow the largest allocation PoCL reports on this VM, so the small stage runs in",
              "batches of roots whose masks and first node records fit one allocation each (masks live for one",
              "batch, the last batch's to the end of the build, for the device's BufferPool; records until the",
              "output stage). Scenes that fit are one batch; the batches' tree is the one-batch tree",
              "(tests/test_opencl_builder.cpp)."]
    failures = [r for r in rows if r["status"] != "ok"]
    if failures:
        lines += ["", "Failures:", ""]
        lines += [f"- {r['triangles']:,}: {r['status']}: `{r.get('error', '')}`" for r in failures]
    with open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def write_plot(path, rows):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ok = [r for r in rows if r["status"] == "ok"]
    fig, axes = plt.subplots(1, 2, figsize=(10, 4))
    n = [r["triangles"] for r in ok]
    axes[0].loglog(n, [r["build_ms"] for r in ok], "o-", label="build_ms")
    axes[0].loglog(n, [1000 * r["wall_s"] for r in ok], "s--", label="whole command (ms)")
    axes[0].set_xlabel("triangles")
    axes[0].set_ylabel("ms")
    axes[0].set_title("OpenCL build time")
    axes[1].loglog(n, [r["peak_rss_bytes"] / 2**20 for r in ok], "o-", label="peak host RSS")
    axes[1].loglog(n, [r["device_bytes"] / 2**20 for r in ok], "s--", label="peak device memory")
    axes[1].set_xlabel("triangles")
    axes[1].set_ylabel("MiB")
    axes[1].set_title("memory")
    for ax in axes:
        ax.grid(True, which="both", alpha=0.3)
        ax.legend()
    fig.tight_layout()
    fig.savefig(path, dpi=110)


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kdray", default=os.path.join(root, "build-rel", "kdray"))
    ap.add_argument("--max", type=int, default=SIZES[-1], help="largest scene (triangles)")
    ap.add_argument("--out", default=os.path.join(root, "docs"))
    ap.add_argument("--timeout", type=float, default=3600, help="seconds per build")
    ap.add_argument("--report-only", action="store_true",
                    help="rewrite scale.md and scale.png from OUT/scale.json without building")
    args = ap.parse_args()
    os.nice(19)
    if args.report_only:
        with open(os.path.join(args.out, "scale.json")) as f:
            data = json.load(f)
        write_markdown(os.path.join(args.out, "scale.md"), data["rows"], data["machine"])
        write_plot(os.path.join(args.out, "scale.png"), data["rows"])
        return 0

    info = machine(args.kdray)
    rows = []
    with tempfile.TemporaryDirectory(prefix="kdray-scale-") as tmp:
        for n in [s for s in SIZES if s <= args.max]:
            obj = os.path.join(tmp, f"random_{n}.obj")
            t0 = time.monotonic()
            write_scene(obj, n)
            size = os.path.getsize(obj)
            print(f"{n:>10,} triangles: {size / 2**20:,.0f} MiB OBJ in "
                  f"{time.monotonic() - t0:.1f} s; building ...", flush=True)
            row = {"triangles": n, "obj_bytes": size, **build(args.kdray, obj, args.timeout)}
            os.remove(obj)
            print("            " + json.dumps({k: v for k, v in row.items() if k != "timings_ms"}),
                  flush=True)
            rows.append(row)
    os.makedirs(args.out, exist_ok=True)
    with open(os.path.join(args.out, "scale.json"), "w") as f:
        json.dump({"commit": git_commit(), "command": " ".join(["scripts/scale.py", *sys.argv[1:]]),
                   "machine": info, "rows": rows}, f, indent=2)
    write_markdown(os.path.join(args.out, "scale.md"), rows, info)
    if any(r["status"] == "ok" for r in rows):
        write_plot(os.path.join(args.out, "scale.png"), rows)
    return 0 if all(r["status"] == "ok" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
