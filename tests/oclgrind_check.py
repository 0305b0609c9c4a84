#!/usr/bin/env python3
"""kdray's kernels under Oclgrind, the strict OpenCL 1.2 simulator (the CTest label `oclgrind`).

PoCL checks no memory access, so a kernel that writes past its buffer corrupts a neighbour in
silence there. Oclgrind checks every access, reports races and uninitialised values, and reports
itself as a GPU, so kdray takes its GPU paths (the per-level small stage, no packets unless
`--packets on` asks for them: the packet cases do).

Each case renders a small generated scene (a few hundred triangles, 32x24 pixels) with kdray
under Oclgrind and passes only when
  - Oclgrind reports nothing (its reports go to stderr: "Invalid ...", "... data race ...",
    "Uninitialized ...", API errors) and kdray exits 0,
  - the hit AOV agrees with the CPU reference's (`--builder reference --tracer reference`, run
    natively), by `kdray compare` (conventions.md's rule),
  - the image is within IMAGE_TOLERANCE of the CPU reference's on all but IMAGE_MAX_FRACTION of
    its pixels (the OpenCL and CPU shading differ in float rounding only).

Oclgrind runs with --data-races --check-api (its checks of every memory access are always on),
on the program as drivers compile it (optimised; the packet cases not, see PACKET_BUILD_OPTIONS).
Not with --uninitialized: Oclgrind 21.10's
(Debian 12's) uninitialised-value plugin mishandles shufflevector masks with undefined elements
(Uninitialized.cpp compares the mask value with llvm::Value::UndefValueVal instead of -1), and
clang emits such a shuffle for every float3 stored as four lanes or widened to a float8: in an
optimised program it crashes the simulator, at -cl-opt-disable it reads shadow bytes from before
its buffer and reports garbage. kdray's own uninitialised reads it did find (host writes into
part of a buffer, which the plugin also mis-tracks, and a fill it ignores) are fixed at the root;
see ClPrimitives::fill and ::copy and BuildContext::write.

  tests/oclgrind_check.py KDRAY WORKDIR CASE...      CASE: see CASES below, or `all`
"""
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import zlib
from pathlib import Path

WIDTH, HEIGHT = 32, 24
IMAGE_TOLERANCE = 2.0 / 255.0
IMAGE_MAX_FRACTION = 0.01
MIN_HIT_PIXELS = 40  # of the reference's, per frame
REPORT_MARKERS = ("Invalid ", "data race", "Uninitialized", "Oclgrind - ", "error generated",
                  "errors generated", "Unhandled", "Undefined external", "Work-group divergence",
                  "barrier divergence", "OCLGRIND", "Oclgrind:")


def write(path, text):
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)


def obj_text(triangles, materials=None, mtllib=None, texcoords=None):
    """triangles: [((x, y, z) * 3)]; materials: a material name per triangle (or None)."""
    lines = [f"mtllib {mtllib}"] if mtllib else []
    for tri in triangles:
        for v in tri:
            lines.append("v %.6f %.6f %.6f" % v)
    if texcoords:
        for uv in texcoords:
            lines.append("vt %.6f %.6f" % uv)
    current = None
    for i in range(len(triangles)):
        if materials and materials[i] != current:
            current = materials[i]
            lines.append(f"usemtl {current}")
        a, b, c = 3 * i + 1, 3 * i + 2, 3 * i + 3
        if texcoords:
            lines.append(f"f {a}/{a} {b}/{b} {c}/{c}")
        else:
            lines.append(f"f {a} {b} {c}")
    return "\n".join(lines) + "\n"


def lcg(seed):
    state = seed
    while True:
        state = (state * 6364136223846793005 + 1442695040888963407) % 2**64
        yield (state >> 11) / float(2**53)


def quad(p, u, v):
    """Two triangles of the parallelogram p, p+u, p+u+v, p+v."""
    a = p
    b = tuple(p[i] + u[i] for i in range(3))
    c = tuple(p[i] + u[i] + v[i] for i in range(3))
    d = tuple(p[i] + v[i] for i in range(3))
    return [(a, b, c), (a, c, d)]


def clusters():
    """Four clusters of 70 small triangles, far apart: several large levels, empty-space cuts."""
    rnd = lcg(7)
    tris = []
    for cx, cy, cz in ((-20, -20, 0), (20, -20, 3), (-20, 20, -4), (20, 20, 1)):
        for _ in range(70):
            base = (cx + 4 * next(rnd), cy + 4 * next(rnd), cz + 4 * next(rnd))
            tris.append(tuple(tuple(base[i] + 0.6 * (next(rnd) - 0.5) for i in range(3))
                              for _ in range(3)))
    return tris


def coplanar():
    """A 12x12 grid of quads in z = 0 and a 6x6 one in x = 0 through it: planar triangles on
    every split plane of the grid's axes."""
    tris = []
    for i in range(12):
        for j in range(12):
            tris += quad((i - 6.0, j - 6.0, 0.0), (1, 0, 0), (0, 1, 0))
    for i in range(6):
        for j in range(6):
            tris += quad((0.0, 2 * i - 6.0, 2 * j - 6.0), (0, 2, 0), (0, 0, 2))
    return tris


def slivers():
    """150 small triangles and, beside them, 80 long slivers that every split cuts: with T = 8 the
    slivers' depth-first subtrees run out of their arenas and are built again, the others' not."""
    rnd = lcg(5)
    tris = []
    for _ in range(150):
        c = (next(rnd), next(rnd), next(rnd))
        tris.append(tuple(tuple(c[i] + 0.1 * (next(rnd) - 0.5) for i in range(3))
                          for _ in range(3)))
    for _ in range(80):
        c = (2 + next(rnd), next(rnd), next(rnd))
        d = [2 * next(rnd) - 1 for _ in range(3)]
        scale = 0.5 / max(1e-3, math.sqrt(sum(x * x for x in d)))
        w = [0.02 * (next(rnd) - 0.5) for _ in range(3)]
        tris.append((tuple(c[i] - scale * d[i] for i in range(3)),
                     tuple(c[i] + scale * d[i] for i in range(3)),
                     tuple(c[i] + w[i] for i in range(3))))
    return tris


def coincident():
    """100 triangles, each twice (coincident faces), and a fan sharing one vertex."""
    rnd = lcg(11)
    tris = []
    for _ in range(100):
        base = (10 * next(rnd) - 5, 10 * next(rnd) - 5, 4 * next(rnd) - 2)
        t = tuple(tuple(base[i] + 1.5 * (next(rnd) - 0.5) for i in range(3)) for _ in range(3))
        tris += [t, t]
    for k in range(40):
        a0, a1 = 2 * math.pi * k / 40, 2 * math.pi * (k + 1) / 40
        tris.append(((0, 0, 3), (3 * math.cos(a0), 3 * math.sin(a0), 3),
                     (3 * math.cos(a1), 3 * math.sin(a1), 3)))
    return tris


def camera(position, look_at, fov=50):
    return {"position": list(position), "look_at": list(look_at), "up": [0, 1, 0], "fov_y": fov}


POINT_LIGHT = {"type": "point", "position": [3, 8, 30], "intensity": [900, 900, 900]}


def render_file(cam, lights=(POINT_LIGHT,), **extra):
    r = {"image": {"width": WIDTH, "height": HEIGHT, "spp": 1}, "camera": cam,
         "lights": list(lights)}
    r.update(extra)
    return r


def png_bytes(width, height, rgb):
    """An 8-bit RGB PNG (standard library only)."""
    raw = b"".join(b"\x00" + bytes(rgb[(y * width + x) * 3 + c] for x in range(width)
                                   for c in range(3)) for y in range(height))

    def chunk(kind, data):
        return (struct.pack(">I", len(data)) + kind + data +
                struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    header = struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0)
    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) +
            chunk(b"IEND", b""))


def icosahedron(centre, r):
    t = (1 + 5**0.5) / 2
    v = [(-1, t, 0), (1, t, 0), (-1, -t, 0), (1, -t, 0), (0, -1, t), (0, 1, t), (0, -1, -t),
         (0, 1, -t), (t, 0, -1), (t, 0, 1), (-t, 0, -1), (-t, 0, 1)]
    v = [tuple(centre[i] + r * p[i] / math.sqrt(1 + t * t) for i in range(3)) for p in v]
    f = [(0, 11, 5), (0, 5, 1), (0, 1, 7), (0, 7, 10), (0, 10, 11), (1, 5, 9), (5, 11, 4),
         (11, 10, 2), (10, 7, 6), (7, 1, 8), (3, 9, 4), (3, 4, 2), (3, 2, 6), (3, 6, 8),
         (3, 8, 9), (4, 9, 5), (2, 4, 11), (6, 2, 10), (8, 6, 7), (9, 8, 1)]
    return [(v[a], v[b], v[c]) for a, b, c in f]


def effects_scene(folder):
    """Every effect kdray compiles: a textured floor (map_Kd, map_Ka with the ambient term), a
    mirror wall (illum 3), a glass icosahedron (illum 7), an emitter (Ke), a point light."""
    parts = [("floor", quad((-3, 0, 3), (6, 0, 0), (0, 0, -6))),
             ("mirror", quad((-3, 0, -3), (6, 0, 0), (0, 4, 0))),
             ("lamp", quad((-1, 3.9, 1), (0, 0, -1), (2, 0, 0))),
             ("glass", icosahedron((0.8, 1.0, 0.5), 0.8)),
             ("matte", icosahedron((-1.2, 0.7, -0.5), 0.7))]
    tris, mats, uvs = [], [], []
    for name, ts in parts:
        for t in ts:
            tris.append(t)
            mats.append(name)
            uvs += [((p[0] + 3) / 6, (p[2] + 3) / 6) for p in t]
    write(folder / "effects.obj", obj_text(tris, mats, "effects.mtl", uvs))
    write(folder / "effects.mtl", "\n".join([
        "newmtl floor", "Kd 0.8 0.8 0.8", "Ka 1 1 1", "map_Kd checker.png", "map_Ka checker.png",
        "newmtl mirror", "Kd 0.05 0.05 0.05", "Ks 0.9 0.9 0.9", "illum 3",
        "newmtl lamp", "Kd 0 0 0", "Ke 4 4 3",
        "newmtl glass", "Kd 0 0 0", "Ks 1 1 1", "Ni 1.5", "illum 7",
        "newmtl matte", "Kd 0.6 0.3 0.2", "Ks 0.3 0.3 0.3", "Ns 20", "illum 2", ""]))
    checker = []
    for y in range(4):
        for x in range(4):
            checker += [230, 200, 60] if (x + y) % 2 else [40, 90, 200]
    (folder / "checker.png").write_bytes(png_bytes(4, 4, checker))
    r = render_file(camera((0, 2, 6), (0, 1, 0), 55), ambient=[0.2, 0.2, 0.2], exposure=0.5,
                    max_depth=3)
    r["image"]["spp"] = 2
    r["lights"] = [{"type": "point", "position": [1, 3.5, 2], "intensity": [8, 8, 8]}]
    write(folder / "effects.json", json.dumps(r))
    return [folder / "effects.obj"], folder / "effects.json"


def path_scene(folder):
    """The effects scene under the path integrator (docs/path-tracing.md): every lobe, the point
    light and the emitter sampled, MIS, Russian roulette past the third segment. Paths of the
    same random numbers follow the same bounces on both sides, so the image tolerance holds."""
    objs, effects_json = effects_scene(folder)
    r = json.loads(effects_json.read_text())
    r.update(integrator="path", max_depth=6)
    del r["ambient"]
    write(folder / "path.json", json.dumps(r))
    return objs, folder / "path.json"


def geometry_scene(folder, name, tris, eye, target, lights=(POINT_LIGHT,), fov=50):
    write(folder / f"{name}.obj", obj_text(tris))
    write(folder / f"{name}.json", json.dumps(render_file(camera(eye, target, fov), lights)))
    return [folder / f"{name}.obj"], folder / f"{name}.json"


def animation(folder):
    """Three keyframed frames: the clusters moving apart, the camera moving between keys."""
    frames = []
    for k in range(3):
        tris = [tuple(tuple(p[i] * (1 + 0.2 * k) for i in range(3)) for p in t)
                for t in clusters()]
        write(folder / f"frame_{k:03d}.obj", obj_text(tris))
        frames.append(folder / f"frame_{k:03d}.obj")
    # The clusters' camera, scaled with the scene: each frame sees its cluster the same way.
    r = render_file([dict(frame=0, **camera((-18, -18, 5), (-18, -18, 2), 60)),
                     dict(frame=2, **camera((-25.2, -25.2, 7), (-25.2, -25.2, 2.8), 60))])
    write(folder / "anim.json", json.dumps(r))
    return frames, folder / "anim.json"


def scenes(work):
    return {
        # From inside one cluster's box: the others' triangles are too small to hit from afar.
        "clusters": lambda: geometry_scene(work / "clusters", "clusters", clusters(),
                                           (-18, -18, 5), (-18, -18, 2), fov=60),
        "coplanar": lambda: geometry_scene(work / "coplanar", "coplanar", coplanar(), (4, 3, 12),
                                           (0, 0, 0)),
        # No lights: primary packets traced and shaded by one kernel (kd_trace_shade_camera_packets).
        "coplanar-unlit": lambda: geometry_scene(work / "coplanar-unlit", "coplanar", coplanar(),
                                                 (4, 3, 12), (0, 0, 0), lights=()),
        "coincident": lambda: geometry_scene(work / "coincident", "coincident", coincident(),
                                             (0, 2, 14), (0, 0, 0)),
        # Close to the slivers: from afar they and the small triangles are thinner than a pixel.
        "slivers": lambda: geometry_scene(work / "slivers", "slivers", slivers(), (2.5, 0.5, 1.6),
                                          (2.5, 0.5, 0.5), fov=60),
        "effects": lambda: effects_scene(work / "effects"),
        "path": lambda: path_scene(work / "path"),
        "anim": lambda: animation(work / "anim"),
    }


# Oclgrind 21.10 evaluates some vector compares of optimised programs wrongly: the split masks'
# int8 compare results come out as 1 or -2 in some lanes (a ten-line kernel of
# kd_candidate_sides' formula reproduces it; with -cl-opt-disable it gives PoCL's -1 and 0). The
# masks it computes are then fuller than PoCL's, and the trees built from them stay valid, which
# is what these cases check (hits and images against the CPU reference) beside memory safety;
# the masks' values are checked on PoCL by tests/test_opencl_split_masks.cpp.
#
# Each case: a scene, kdray's options under Oclgrind. The reference is always the CPU builder and
# tracer. Qualities, both small stages and every large stage on the scenes whose large stage runs
# several levels (Oclgrind reports a GPU, so auto picks per-level and level; the CPU shapes are
# asked for by name).
CASES = {
    "clusters-high-per-level": ("clusters", ["--quality", "high", "--small-stage", "per-level"]),
    # The depth-first schedule: the whole scene one deep root (280 triangles, at most 1024 go to
    # it with T = 64), and with T = 8 (deep roots of at most 128) chunked levels handing the
    # clusters to it.
    "clusters-low-per-root": ("clusters", ["--quality", "low", "--small-stage", "per-root",
                                           "--large-stage", "depth-first"]),
    "clusters-depth-first-t8": ("clusters", ["--quality", "high", "--small-stage", "per-root",
                                             "--large-stage", "depth-first",
                                             "--large-node-threshold", "8"]),
    # Depth-first subtrees built again with larger arenas, in a second and third run of only
    # those that ran out (RERUN_CASES checks that they did).
    "slivers-depth-first-t8": ("slivers", ["--quality", "high", "--small-stage", "per-root",
                                           "--large-stage", "depth-first",
                                           "--large-node-threshold", "8"]),
    "coplanar-medium-per-level": ("coplanar", ["--quality", "medium", "--small-stage", "per-level"]),
    "coplanar-high-per-root": ("coplanar", ["--quality", "high", "--small-stage", "per-root",
                                            "--large-stage", "chunked"]),
    "coincident-low-per-level": ("coincident", ["--quality", "low", "--small-stage", "per-level"]),
    "coincident-medium-per-root": ("coincident", ["--quality", "medium", "--small-stage",
                                                  "per-root", "--large-stage", "chunked"]),
    # Binned small nodes (no split masks): per level above the re-clipped tables of long
    # slivers, and per root down to the coincident faces' planar triangles.
    "slivers-binned-per-level": ("slivers", ["--quality", "high", "--small-bins", "8",
                                             "--small-stage", "per-level"]),
    "coincident-binned-per-root": ("coincident", ["--quality", "low", "--small-bins", "16",
                                                  "--small-stage", "per-root"]),
    # Work-groups of 64: the element-parallel large stage walks each 256-reference chunk in four
    # rounds, its scans carried from round to round.
    "clusters-level-groups-of-64": ("clusters", ["--quality", "high", "--large-stage", "level"],
                                    ["--max-wgsize", "64"]),
    "effects": ("effects", []),
    "path": ("path", []),
    "anim": ("anim", ["--quality", "medium"]),
    # Primary rays as packets, which kdray takes by default on CPU devices only: one kernel that
    # traces and shades (no lights), and camera packets, shadow packets and shading in three.
    "packets-trace-and-shade": ("coplanar-unlit", ["--packets", "on", "--quality", "low"]),
    "packets-with-shadows": ("coplanar", ["--packets", "on", "--quality", "low"]),
    "reference-builder": ("coplanar", ["--builder", "reference"]),
    "reference-tracer": ("clusters", ["--tracer", "reference", "--quality", "high"]),
    # A device with NVIDIA's limits (256 work-items a group, 48 KiB of local memory), and one
    # with 32 KiB: the group sizes and local arrays kdray picks must fit both.
    "nvidia-limits": ("effects", ["--small-stage", "per-level"],
                      ["--max-wgsize", "256", "--local-mem-size", "49152"]),
    "local-32k": ("clusters", ["--small-stage", "per-level"],
                  ["--max-wgsize", "256", "--local-mem-size", "32768"]),
}


# Build options Oclgrind adds for the packet cases (OCLGRIND_BUILD_OPTIONS). The packet
# walk's __builtin_reduce_or becomes llvm.vector.reduce.or, which Oclgrind 21.10 cannot run:
# KDRAY_PACKET_PORTABLE_ANY makes it OpenCL's any(). Optimised, the packet kernels also hold
# llvm.experimental.noalias.scope.decl, which the simulator lacks, hence -cl-opt-disable.
PACKET_BUILD_OPTIONS = "-cl-opt-disable -DKDRAY_PACKET_PORTABLE_ANY=1"

# Packet cases (built with PACKET_BUILD_OPTIONS), and whether their shadow rays go as packets
# too: stats.json must say they did.
PACKET_CASES = {"packets-trace-and-shade": False, "packets-with-shadows": True}


def packet_failures(name, stats_path):
    packets = json.loads(stats_path.read_text())["frames"][0]["packets"]
    failures = []
    if not packets.get("primary"):
        failures.append("primary rays did not go as packets")
    if packets.get("shadow", False) != PACKET_CASES[name]:
        failures.append(f"shadow packets {packets.get('shadow')}, the case wants "
                        f"{PACKET_CASES[name]}")
    return failures


# Cases whose depth-first stage must run its kernel again for some subtrees, not all: else the
# case no longer covers those runs.
RERUN_CASES = {"slivers-depth-first-t8"}


def rerun_failures(stats_path):
    """What is wrong with a RERUN_CASES render's depth-first runs, by its stats.json."""
    tree = json.loads(stats_path.read_text())["frames"][0]["tree"]
    rounds, rebuilt = tree.get("depth_first_rounds", 0), tree.get("depth_first_rebuilt", 0)
    subtrees = tree.get("depth_first_subtrees", 0)
    if rounds > 1 and 0 < rebuilt < subtrees * (rounds - 1):
        return []
    return [f"depth-first runs {rounds}, subtrees {subtrees}, rebuilt {rebuilt}: the case "
            "no longer makes some subtrees (and not all) run out of their arenas"]


def oclgrind_reports(stderr):
    return [line for line in stderr.splitlines()
            if any(m in line for m in REPORT_MARKERS) and not line.startswith("kdray:")]


def run(cmd, env=None, timeout=900):
    return subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=timeout)


def check_case(kdray, work, name, built):
    scene, options, *device_limits = CASES[name]
    objs, render_json = built[scene]
    base = [str(kdray), "render", *map(str, objs), "--camera", str(render_json), "--aov"]
    out = work / "out" / name
    failures = []
    ref = out / "reference"
    r = run(base + ["--builder", "reference", "--tracer", "reference", "-o", str(ref)])
    if r.returncode != 0:
        return [f"reference render failed: {r.stderr.strip()}"]
    hits = [f.get("hit_pixels", 0) for f in json.loads((ref / "stats.json").read_text())["frames"]]
    if min(hits) < MIN_HIT_PIXELS:
        return [f"the camera hits {min(hits)} pixels of a frame (at least {MIN_HIT_PIXELS} "
                "wanted): the hit comparison would check next to nothing"]
    env = dict(os.environ)
    packets = name in PACKET_CASES
    runs = [("unoptimised" if packets else "optimised",
             ["--data-races", "--check-api", *sum(device_limits, [])],
             PACKET_BUILD_OPTIONS if packets else "")]
    for label, flags, build_options in runs:
        env["OCLGRIND_BUILD_OPTIONS"] = build_options
        got = out / label
        r = run(["oclgrind", *flags] + base + options + ["-o", str(got)], env=env)
        reports = oclgrind_reports(r.stderr)
        if r.returncode != 0 or reports:
            detail = "\n    ".join((reports or r.stderr.strip().splitlines())[:12])
            failures.append(f"{label}: exit {r.returncode}; Oclgrind said:\n    {detail}")
            continue
        if name in RERUN_CASES:
            failures += [f"{label}: {f}" for f in rerun_failures(got / "stats.json")]
        if packets:
            failures += [f"{label}: {f}" for f in packet_failures(name, got / "stats.json")]
            # Oclgrind reports a GPU: kdray must say that packets are a CPU path there.
            if "--packets on: packets are a CPU path" not in r.stderr:
                failures.append(f"{label}: no warning that packets are a CPU path")
        for obj in objs:
            stem = obj.stem
            c = run([str(kdray), "compare", str(got / f"{stem}.aov.exr"),
                     str(ref / f"{stem}.aov.exr")])
            if c.returncode != 0:
                failures.append(f"{label}: {stem} hits differ from the CPU reference's: "
                                f"{(c.stdout + c.stderr).strip()}")
            c = run([str(kdray), "compare", str(got / f"{stem}.png"), str(ref / f"{stem}.png"),
                     "--tolerance", str(IMAGE_TOLERANCE), "--max-fraction",
                     str(IMAGE_MAX_FRACTION)])
            if c.returncode != 0:
                failures.append(f"{label}: {stem} image differs from the CPU reference's: "
                                f"{(c.stdout + c.stderr).strip()}")
    return failures


def main(argv):
    if len(argv) < 4:
        print(__doc__, file=sys.stderr)
        return 2
    if shutil.which("oclgrind") is None:
        print("oclgrind_check: oclgrind is not installed (scripts/install-deps.sh installs it)",
              file=sys.stderr)
        return 1
    kdray, work = Path(argv[1]).resolve(), Path(argv[2]).resolve()
    names = list(CASES) if argv[3:] == ["all"] else argv[3:]
    unknown = [n for n in names if n not in CASES]
    if unknown:
        print(f"oclgrind_check: unknown case {unknown[0]}", file=sys.stderr)
        return 2
    makers = scenes(work)
    built = {s: makers[s]() for s in {CASES[n][0] for n in names}}
    bad = 0
    for name in names:
        failures = check_case(kdray, work, name, built)
        print(f"{'ok  ' if not failures else 'FAIL'} {name}")
        for f in failures:
            print(f"  {f}")
        bad += bool(failures)
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
