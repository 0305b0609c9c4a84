#!/usr/bin/env python3
"""check_rooms.py — the include rule of docs/architecture.md: a file includes only files of its own
room or of rooms below it, core/device/ only core/device/ (it compiles as OpenCL C), and no file
includes itself back through a circle of #include "..." lines. With --compile CXX, every
core/device/ header must also compile on its own as C++: a header that only works after another
has defined its types (kd_area_light.h inside kd_render.h, once) is a circle its includes hide.

    scripts/check_rooms.py [REPO_ROOT] [--compile CXX]

Exit 0 when the rule holds, 1 with one line per include that breaks it (or per circle).
"""
import re
import subprocess
import sys
from pathlib import Path

# Rooms from the bottom up: a file may include its own room and those listed before it.
ROOMS = [
    "core/device",
    "core",  # error.h and the generated version.h, which every room may use
    "core/geometry",
    "core/io",
    "core/scene",
    "core/tree",
    "core/render",
    "core/run",
    "cl/runtime",
    "cl/builder",
    "cl/renderer",
    "cl",  # backends: picks a builder and a tracer
    "cli",
    "tests",
    "scripts",
]
RANK = {room: i for i, room in enumerate(ROOMS)}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)
SOURCES = (".h", ".cpp", ".cl")


def room_of(path):
    """The deepest listed room holding path ('core/tree/tree.h' -> 'core/tree')."""
    parts = Path(path).parts
    for n in range(len(parts) - 1, 0, -1):
        room = "/".join(parts[:n])
        if room in RANK:
            return room
    return None


def main():
    args = sys.argv[1:]
    cxx = None
    if "--compile" in args:
        k = args.index("--compile")
        cxx = args[k + 1]
        del args[k:k + 2]
    root = Path(args[0] if args else Path(__file__).resolve().parent.parent)
    files = sorted(p.relative_to(root).as_posix() for top in ("core", "cl", "cli", "tests", "scripts")
                   for p in (root / top).rglob("*") if p.suffix in SOURCES and p.is_file())
    graph, problems = {}, []
    for rel in files:
        text = (root / rel).read_text(encoding="utf-8", errors="replace")
        edges = []
        for inc in INCLUDE.findall(text):
            # Relative includes (tests' own headers) are files of the same folder.
            target = inc if (root / inc).exists() or inc.startswith(("core/", "cl/")) else \
                (Path(rel).parent / inc).as_posix()
            edges.append(target)
            src, dst = room_of(rel), room_of(target)
            if src is None or dst is None:
                problems.append(f"{rel}: includes {inc}: a room of neither is known to check_rooms.py")
            elif src == "core/device" and dst != "core/device":
                problems.append(f"{rel}: includes {inc}: core/device/ includes only core/device/")
            elif RANK[dst] > RANK[src]:
                problems.append(f"{rel}: includes {inc}: {src}/ may not include {dst}/ (above it)")
        graph[rel] = edges

    # Circles: a depth-first walk that meets a file still on its path.
    state, path = {}, []

    def walk(node):
        state[node] = 1
        path.append(node)
        for nxt in graph.get(node, []):
            if state.get(nxt) == 1:
                problems.append("include circle: " + " -> ".join(path[path.index(nxt):] + [nxt]))
            elif nxt in graph and not state.get(nxt):
                walk(nxt)
        path.pop()
        state[node] = 2

    for f in files:
        if not state.get(f):
            walk(f)
    if cxx:
        for rel in files:
            if rel.startswith("core/device/") and rel.endswith(".h"):
                r = subprocess.run([cxx, "-std=c++20", "-fsyntax-only", "-x", "c++", "-I", str(root),
                                    "-"], input=f'#include "{rel}"\n', capture_output=True, text=True)
                if r.returncode != 0:
                    errors = [ln for ln in r.stderr.split("\n") if "error:" in ln] or [r.stderr]
                    problems.append(f"{rel} does not compile on its own: {errors[0][:200]}")
    for p in problems:
        print(f"check_rooms: {p}")
    print(f"check_rooms: {len(files)} files, {sum(map(len, graph.values()))} includes, "
          f"{len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
