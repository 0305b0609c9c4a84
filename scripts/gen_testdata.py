#!/usr/bin/env python3
"""Writes kdray's small generated test scenes into testdata/ (stdlib only, deterministic).

  testdata/cornell/room.obj, room.mtl, render.json
      A Cornell-style room: floor, ceiling, back wall, red left and green right walls (subdivided
      quads), an emissive ceiling light quad (Ke), a matte box, a mirror sphere (illum 3, Ks 1) and
      a glass sphere (illum 7, Ni 1.5, Tf), lit by a point light; a 640x480 camera looks in. The
      spheres carry vertex normals (`vn`) and shade smooth; the flat faces have none.
  testdata/anim/frame_000.obj ... frame_011.obj, scene.mtl, render.json
      12 frames of a sphere bouncing and a cube spinning over a ground plane, with a keyframed
      camera (keys at frames 0 and 11) that orbits part way round them.

Run from anywhere:  python3 scripts/gen_testdata.py   (rewrites the files in place).
"""
import json
import math
import os

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
OUT = os.path.join(ROOT, "testdata")


def num(x):
    """Compact, deterministic text for a coordinate (6 significant digits, no '-0')."""
    s = format(round(x, 6), ".6g")
    return "0" if s in ("-0", "0") else s


class Obj:
    """An OBJ being written: vertices are numbered from 1 across the whole file."""

    def __init__(self, header, mtllib):
        self.lines = ["# " + line for line in header] + ["mtllib " + mtllib]
        self.count = 0
        self.normals = 0

    def vertex(self, p):
        self.lines.append("v %s %s %s" % (num(p[0]), num(p[1]), num(p[2])))
        self.count += 1
        return self.count

    def normal(self, n):
        """A `vn` line; returns its number (numbered from 1 across the file, like vertices)."""
        self.lines.append("vn %s %s %s" % (num(n[0]), num(n[1]), num(n[2])))
        self.normals += 1
        return self.normals

    def group(self, name, material):
        self.lines += ["o " + name, "usemtl " + material]

    def face(self, *ids):
        self.lines.append("f " + " ".join(str(i) for i in ids))

    def grid(self, corner, edge_u, edge_v, n):
        """An n x n grid of quads spanning corner + s*edge_u + t*edge_v."""
        ids = [[self.vertex([corner[k] + edge_u[k] * i / n + edge_v[k] * j / n for k in range(3)])
                for i in range(n + 1)] for j in range(n + 1)]
        for j in range(n):
            for i in range(n):
                self.face(ids[j][i], ids[j][i + 1], ids[j + 1][i + 1], ids[j + 1][i])

    def sphere(self, centre, radius, segments, rings):
        """A UV sphere of triangles: fans at the poles, two triangles per quad between; each
        vertex has the sphere's normal there (`v//vn`), so that it shades smooth."""

        def corner(direction):
            v = self.vertex([centre[k] + radius * direction[k] for k in range(3)])
            return "%d//%d" % (v, self.normal(direction))

        top = corner([0, 1, 0])
        ring_ids = []
        for r in range(1, rings):
            theta = math.pi * r / rings
            ids = []
            for s in range(segments):
                phi = 2 * math.pi * s / segments
                ids.append(corner([math.sin(theta) * math.cos(phi), math.cos(theta),
                                   math.sin(theta) * math.sin(phi)]))
            ring_ids.append(ids)
        bottom = corner([0, -1, 0])
        for s in range(segments):
            t = (s + 1) % segments
            self.face(top, ring_ids[0][t], ring_ids[0][s])
            for r in range(rings - 2):
                a, b = ring_ids[r], ring_ids[r + 1]
                self.face(a[s], a[t], b[t])
                self.face(a[s], b[t], b[s])
            self.face(bottom, ring_ids[-1][s], ring_ids[-1][t])

    def box(self, centre, size, angle, n=1):
        """A box of n x n quads per face, turned by `angle` radians about the vertical axis."""
        c, s = math.cos(angle), math.sin(angle)

        def world(x, y, z):
            return [centre[0] + c * x - s * z, centre[1] + y, centre[2] + s * x + c * z]

        hx, hy, hz = size[0] / 2, size[1] / 2, size[2] / 2
        # Each face as a corner and two edges, wound so that its normal points outwards.
        faces = [((-hx, -hy, hz), (2 * hx, 0, 0), (0, 2 * hy, 0)),
                 ((hx, -hy, -hz), (-2 * hx, 0, 0), (0, 2 * hy, 0)),
                 ((hx, -hy, hz), (0, 0, -2 * hz), (0, 2 * hy, 0)),
                 ((-hx, -hy, -hz), (0, 0, 2 * hz), (0, 2 * hy, 0)),
                 ((-hx, hy, hz), (2 * hx, 0, 0), (0, 0, -2 * hz)),
                 ((-hx, -hy, -hz), (2 * hx, 0, 0), (0, 0, 2 * hz))]
        for corner, eu, ev in faces:
            ids = [[self.vertex(world(*[corner[k] + eu[k] * i / n + ev[k] * j / n
                                        for k in range(3)]))
                    for i in range(n + 1)] for j in range(n + 1)]
            for j in range(n):
                for i in range(n):
                    self.face(ids[j][i], ids[j][i + 1], ids[j + 1][i + 1], ids[j + 1][i])

    def write(self, path):
        with open(path, "w", newline="\n") as f:
            f.write("\n".join(self.lines) + "\n")


def write_text(path, text):
    with open(path, "w", newline="\n") as f:
        f.write(text)


def write_json(path, value):
    write_text(path, json.dumps(value, indent=2) + "\n")


def cornell():
    folder = os.path.join(OUT, "cornell")
    os.makedirs(folder, exist_ok=True)
    obj = Obj(["Cornell-style room for kdray's tests; generated by scripts/gen_testdata.py."],
              "room.mtl")
    n = 8
    obj.group("floor", "white")
    obj.grid([-1, 0, 1], [2, 0, 0], [0, 0, -2], n)
    obj.group("ceiling", "white")
    obj.grid([-1, 2, -1], [2, 0, 0], [0, 0, 2], n)
    obj.group("back_wall", "white")
    obj.grid([-1, 0, -1], [2, 0, 0], [0, 2, 0], n)
    obj.group("left_wall", "red")
    obj.grid([-1, 0, 1], [0, 0, -2], [0, 2, 0], n)
    obj.group("right_wall", "green")
    obj.grid([1, 0, -1], [0, 0, 2], [0, 2, 0], n)
    obj.group("light", "light")
    obj.grid([-0.25, 1.99, -0.25], [0.5, 0, 0], [0, 0, 0.5], 1)
    obj.group("matte_box", "white")
    obj.box([-0.45, 0.6, -0.4], [0.55, 1.2, 0.55], math.radians(18), 2)
    obj.group("mirror_sphere", "mirror")
    obj.sphere([0.45, 0.35, -0.45], 0.35, 24, 16)
    obj.group("glass_sphere", "glass")
    obj.sphere([0.1, 0.3, 0.35], 0.3, 24, 16)
    obj.write(os.path.join(folder, "room.obj"))
    write_text(os.path.join(folder, "room.mtl"), """\
# Materials of room.obj; generated by scripts/gen_testdata.py.
newmtl white
Kd 0.725 0.71 0.68
Ks 0 0 0
Ns 10
illum 2

newmtl red
Kd 0.63 0.065 0.05
illum 2

newmtl green
Kd 0.14 0.45 0.091
illum 2

newmtl light
Kd 0.78 0.78 0.78
Ke 17 12 4
illum 2

newmtl mirror
Kd 0 0 0
Ks 1 1 1
Ns 1000
illum 3

newmtl glass
Kd 0 0 0
Ks 1 1 1
Ns 1000
Ni 1.5
d 1
Tf 1 1 1
illum 7
""")
    write_json(os.path.join(folder, "render.json"), {
        "image": {"width": 640, "height": 480, "spp": 1},
        "camera": {"position": [0, 1, 3.0], "look_at": [0, 1, 0], "up": [0, 1, 0], "fov_y": 40},
        "lights": [{"type": "point", "position": [0, 1.8, 0.2], "intensity": [4, 4, 4]}],
        "background": [0, 0, 0],
        "max_depth": 6,
    })


FRAMES = 12


def anim():
    folder = os.path.join(OUT, "anim")
    os.makedirs(folder, exist_ok=True)
    for k in range(FRAMES):
        phase = k / (FRAMES - 1)
        obj = Obj(["Frame %d of %d of kdray's animated test scene; generated by "
                   "scripts/gen_testdata.py." % (k, FRAMES)], "scene.mtl")
        obj.group("ground", "ground")
        obj.grid([-4, 0, 4], [8, 0, 0], [0, 0, -8], 24)
        # Two bounces over the sequence; the sphere's lowest point touches the ground.
        height = 0.5 + 1.5 * abs(math.sin(2 * math.pi * phase))
        obj.group("ball", "red")
        obj.sphere([-1.0 + 2.0 * phase, height, 0.5], 0.5, 32, 16)
        obj.group("cube", "mirror")
        obj.box([1.5, 0.6, -1.0], [1.2, 1.2, 1.2], math.radians(90 * phase), 4)
        obj.write(os.path.join(folder, "frame_%03d.obj" % k))
    write_text(os.path.join(folder, "scene.mtl"), """\
# Materials of frame_*.obj; generated by scripts/gen_testdata.py.
newmtl ground
Kd 0.6 0.6 0.6
illum 2

newmtl red
Kd 0.8 0.1 0.1
Ks 0.4 0.4 0.4
Ns 60
illum 2

newmtl mirror
Kd 0 0 0
Ks 0.9 0.9 0.9
Ns 1000
illum 3
""")
    write_json(os.path.join(folder, "render.json"), {
        "image": {"width": 640, "height": 360, "spp": 1},
        "camera": [
            {"frame": 0, "position": [0, 2.5, 8], "look_at": [0, 0.8, 0], "up": [0, 1, 0],
             "fov_y": 45},
            {"frame": FRAMES - 1, "position": [5.5, 3, 5.5], "look_at": [0, 0.8, 0],
             "up": [0, 1, 0], "fov_y": 40},
        ],
        "lights": [
            {"type": "directional", "direction": [-0.4, -1, -0.6], "irradiance": [2, 2, 2]},
            {"type": "point", "position": [0, 5, 3], "intensity": [20, 20, 20]},
        ],
        "background": [0.3, 0.4, 0.6],
        "max_depth": 4,
    })


README = """\
# testdata/

Small generated scenes for kdray's tests and demos. **Do not edit these files by hand**: they are
written by `scripts/gen_testdata.py` (Python 3, standard library only, deterministic). To
regenerate them, run from the repository root:

    python3 scripts/gen_testdata.py

- `cornell/` — `room.obj` + `room.mtl` + `render.json`: a Cornell-style room (red and green side
  walls, an emissive ceiling light quad, a matte box, a mirror sphere with `illum 3`, a glass sphere
  with `illum 7` and `Ni 1.5`; the spheres have vertex normals), a point light, a 640x480 camera.
- `anim/` — `frame_000.obj` ... `frame_011.obj` + `scene.mtl` + `render.json`: a sphere bouncing
  and a cube spinning over a ground plane; the camera is keyframed at frames 0 and 11.
"""


def main():
    cornell()
    anim()
    write_text(os.path.join(OUT, "README.md"), README)


if __name__ == "__main__":
    main()
