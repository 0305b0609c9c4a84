"""Helpers the benchmark scripts share: the scene list, running kdray and the Embree peer, and a
description of the machine the figures were taken on."""
import csv
import datetime
import json
import os
import platform
import statistics
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SHARED = os.path.normpath(os.path.join(ROOT, "..", "shared"))


def benchmark_scenes(include_shared=True):
    """(name, obj, render.json) for the testdata scenes and, when present, the shared ones: every
    OBJ of a folder, the first frame only of an animation."""
    found = [("testdata/cornell", os.path.join(ROOT, "testdata/cornell/room.obj"),
              os.path.join(ROOT, "testdata/cornell/render.json")),
             ("testdata/anim", os.path.join(ROOT, "testdata/anim/frame_000.obj"),
              os.path.join(ROOT, "testdata/anim/render.json"))]
    scenes_dir = os.path.join(SHARED, "scenes")
    if include_shared and os.path.isdir(scenes_dir):
        for folder in sorted(os.listdir(scenes_dir)):
            camera = os.path.join(scenes_dir, folder, "render.json")
            path = os.path.join(scenes_dir, folder)
            if not os.path.isfile(camera):
                continue
            objs = sorted(f for f in os.listdir(path) if f.endswith(".obj"))
            if any(f.startswith("frame_") for f in objs):
                objs = [f for f in objs if f.startswith("frame_")][:1]
            for obj in objs:
                found.append((f"{folder}/{obj}", os.path.join(path, obj), camera))
    return [s for s in found if os.path.isfile(s[1])]


def run_json(command, env=None):
    """Runs a command that prints one JSON object; raises with its stderr on failure."""
    result = subprocess.run(command, capture_output=True, text=True, env=env)
    if result.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} failed: {result.stderr.strip()}")
    return json.loads(result.stdout.strip().splitlines()[-1] if command[0].endswith("embree_ref")
                      else result.stdout)


def build_peer():
    """Builds ../shared/peers/embree into a temporary folder; returns its path or None."""
    script = os.path.join(SHARED, "peers", "embree", "build.sh")
    if not os.path.isfile(script):
        return None
    out = tempfile.mkdtemp(prefix="kdray-peer-")
    result = subprocess.run(["bash", script, out], capture_output=True, text=True)
    return result.stdout.strip().splitlines()[-1] if result.returncode == 0 else None


def machine_description(kdray):
    cpu = platform.processor() or "unknown CPU"
    try:
        with open("/proc/cpuinfo") as f:
            for line in f:
                if line.startswith("model name"):
                    cpu = line.split(":", 1)[1].strip()
                    break
    except OSError:
        pass
    devices = []
    try:
        info = run_json([kdray, "stats", "--json"])
        devices = [f"{d.get('name')} ({d.get('version')}"
                   f"{'; its threads pinned' if d.get('threads_pinned') else ''})"
                   for d in info.get("devices", []) if "name" in d]
    except (RuntimeError, json.JSONDecodeError):
        pass
    return (f"{cpu}, {os.cpu_count()} cores; OpenCL: {', '.join(devices) or 'none'}; "
            f"{platform.system()} {platform.release()}")


def git_commit():
    """The commit the figures were measured at (with "-dirty" when the tree had changes)."""
    try:
        commit = subprocess.run(["git", "-C", ROOT, "rev-parse", "--short", "HEAD"],
                                capture_output=True, text=True, check=True).stdout.strip()
        dirty = subprocess.run(["git", "-C", ROOT, "status", "--porcelain", "--untracked-files=no"],
                               capture_output=True, text=True, check=True).stdout.strip()
        return commit + ("-dirty" if dirty else "")
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def run_record(kdray):
    """What every benchmark's JSON records of its run, so that scripts/update_docs.py can say
    where a figure came from: the date, the commit, the machine and the command."""
    return {"date": str(datetime.date.today()), "commit": git_commit(),
            "machine": machine_description(kdray),
            "command": " ".join([os.path.relpath(sys.argv[0], ROOT), *sys.argv[1:]])}


def write_json(path, value):
    with open(path, "w") as f:
        json.dump(value, f, indent=1)
        f.write("\n")


def median(values):
    return statistics.median(values) if values else float("nan")


def write_markdown(out, lines):
    """Writes OUT.md (the Markdown lines, one file a benchmark's figures go with) and prints it."""
    with open(out + ".md", "w") as f:
        f.write("\n".join(lines) + "\n")
    print("\n".join(lines))


def write_report(out, lines, rows):
    """Writes OUT.md (the Markdown lines) and OUT.csv (the rows), and prints the Markdown."""
    os.makedirs(os.path.dirname(out), exist_ok=True)
    with open(out + ".md", "w") as f:
        f.write("\n".join(lines) + "\n")
    with open(out + ".csv", "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=sorted({k for r in rows for k in r}))
        writer.writeheader()
        writer.writerows(rows)
    print("\n".join(lines))
