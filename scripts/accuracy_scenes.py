"""Scenes on which a ray–triangle test that is not watertight leaks, for
scripts/accuracy_vs_time.py: closed meshes around the camera, tessellated so that the centre
rays of the pixels pass through mesh vertices and along shared edges.

With the camera inside a closed mesh every ray must hit something, so each pixel that misses is
a leak, without any reference. The camera sits at the centre looking down -z with fov_y 90 and a
square image of odd width W, so that pixel x's centre ray points along ((2x + 1 - W) / W, ...,
-1) (conventions.md):
- box: the cube [-1, 1]^3 with every face cut into a 2W x 2W grid; the face z = -1 has a vertex
  at (i - W) / W, and every odd i is a pixel centre: every centre ray meets a vertex shared by
  six triangles.
- sphere: a UV sphere with its pole on the view axis (the middle pixel's ray meets the pole, a
  vertex of 64 triangles) and 64 meridians, 8 of which lie in the planes of the middle row, the
  middle column and the diagonals: those rays run along the meridians' edges.
Each has a copy 1e5 from the origin (scaled up 100 times, so that its triangles stay far larger
than a float's spacing there), where rounding in the ray's frame is larger.

write_device_scenes adds two cases that only the scene frame (core/scene/scene_frame.h) and the refined
distance make right, for the device check (scripts/device-check-cases.txt):
- sphere-inside-at-1e9: the sphere, scaled up 100 times, 1e9 from the origin, written with 17
  digits: read in float its corners would round to a spacing of 64.
- needles: triangles 1e4 long and 1e-3 wide nearly along x (tests/support.cpp's needle_bundle),
  seen along their length from 1.6 away, where the watertight test's float distance is off by up
  to 1.5e-4 relative, beyond the AOV agreement's 1e-4.
"""
import json
import math
import os
import random


def _box(width):
    """Vertices and faces (0-based) of the cube [-1, 1]^3, each face a (2W)^2 grid of cells."""
    n = 2 * width
    vertices, index, faces = [], {}, []

    def vertex(p):
        key = tuple(p)
        if key not in index:
            index[key] = len(vertices)
            vertices.append(key)
        return index[key]

    # Integer grid coordinates (0..n on each axis) keep the vertices that faces share identical.
    for axis in range(3):
        u_axis, v_axis = (axis + 1) % 3, (axis + 2) % 3
        for side in (0, n):
            for i in range(n):
                for j in range(n):
                    corners = []
                    for di, dj in ((0, 0), (1, 0), (1, 1), (0, 1)):
                        p = [0, 0, 0]
                        p[axis], p[u_axis], p[v_axis] = side, i + di, j + dj
                        corners.append(vertex(p))
                    faces += [(corners[0], corners[1], corners[2]),
                              (corners[0], corners[2], corners[3])]
    return [tuple((c - width) / width for c in v) for v in vertices], faces


def _sphere(meridians=64, parallels=48):
    """A closed UV sphere of radius 1 with its poles on the z axis."""
    vertices = [(0.0, 0.0, 1.0)]
    for p in range(1, parallels):
        theta = math.pi * p / parallels
        for m in range(meridians):
            phi = 2 * math.pi * m / meridians
            vertices.append((math.sin(theta) * math.cos(phi), math.sin(theta) * math.sin(phi),
                             math.cos(theta)))
    vertices.append((0.0, 0.0, -1.0))
    south = len(vertices) - 1
    ring = lambda p, m: 1 + (p - 1) * meridians + m % meridians  # noqa: E731
    faces = [(0, ring(1, m), ring(1, m + 1)) for m in range(meridians)]
    for p in range(1, parallels - 1):
        for m in range(meridians):
            a, b = ring(p, m), ring(p, m + 1)
            c, d = ring(p + 1, m + 1), ring(p + 1, m)
            faces += [(a, d, c), (a, c, b)]
    faces += [(ring(parallels - 1, m + 1), ring(parallels - 1, m), south)
              for m in range(meridians)]
    return vertices, faces


def _write_obj(obj, title, vertices, faces, digits=9):
    with open(obj, "w") as f:
        f.write(f"# {title} (scripts/accuracy_scenes.py)\n")
        for v in vertices:
            f.write("v %.*g %.*g %.*g\n" % (digits, v[0], digits, v[1], digits, v[2]))
        for a, b, c in faces:
            f.write(f"f {a + 1} {b + 1} {c + 1}\n")


def _write(folder, case, vertices, faces, width, offset, scale, digits=9):
    obj = os.path.join(folder, case + ".obj")
    _write_obj(obj, f"{case}: closed mesh around the camera",
               [tuple(offset + scale * c for c in v) for v in vertices], faces, digits)
    render = os.path.join(folder, case + ".json")
    centre = [offset] * 3
    with open(render, "w") as f:
        json.dump({"image": {"width": width, "height": width, "spp": 1},
                   "camera": {"position": centre, "look_at": [offset, offset, offset - scale],
                              "up": [0, 1, 0], "fov_y": 90},
                   "lights": [], "background": [0, 0, 0], "max_depth": 1}, f)
    return case, obj, render


def write_hard_scenes(folder, width):
    """Writes the cases into folder; returns (case, obj, render file) for each. width: the
    image's width and height, odd."""
    assert width % 2 == 1, "the middle pixel's centre ray must lie on the view axis"
    os.makedirs(folder, exist_ok=True)
    box, sphere = _box(width), _sphere()
    cases = []
    for name, (vertices, faces) in (("box", box), ("sphere", sphere)):
        cases.append(_write(folder, f"{name}-inside", vertices, faces, width, 0.0, 1.0))
        cases.append(_write(folder, f"{name}-inside-at-1e5", vertices, faces, width, 1e5, 100.0))
    return cases


def _needles(count, seed):
    """tests/support.cpp's needle_bundle (its own random numbers): `count` triangles, a corner
    near x = -5000 and two near x = 5000 1e-3 apart across, their middles in the unit cube, each
    tilted a little in y."""
    rng = random.Random(seed)
    vertices, faces = [], []
    for _ in range(count):
        y, z, rise = rng.random(), rng.random(), 1e-4 * (rng.random() - 0.5)
        vertices += [(-5000 + rng.random(), y - 5000 * rise, z),
                     (5000 + rng.random(), y + 5000 * rise + 1e-3, z),
                     (5000 + rng.random(), y + 5000 * rise, z + 1e-3 * (0.5 + rng.random()))]
        faces.append((len(vertices) - 3, len(vertices) - 2, len(vertices) - 1))
    return vertices, faces


def write_device_scenes(folder, width):
    """Writes the device check's far and needle cases into folder; returns (case, obj, render
    file) for each. width: the sphere's image width and height, odd (as write_hard_scenes)."""
    os.makedirs(folder, exist_ok=True)
    vertices, faces = _sphere()
    cases = [_write(folder, "sphere-inside-at-1e9", vertices, faces, width, 1e9, 100.0, 17)]
    obj, render = os.path.join(folder, "needles.obj"), os.path.join(folder, "needles.json")
    _write_obj(obj, "needles: 1e4 long, 1e-3 wide, seen along their length", *_needles(300, 6),
               digits=17)
    look_at = [0.5, 0.5, 0.5]
    view = [1.0, -0.5, 0.5]
    norm = math.sqrt(sum(c * c for c in view))
    position = [a - 1.6 * c / norm for a, c in zip(look_at, view)]
    with open(render, "w") as f:
        json.dump({"image": {"width": 160, "height": 120, "spp": 1},
                   "camera": {"position": position, "look_at": look_at, "up": [0, 1, 0],
                              "fov_y": 50},
                   "lights": [], "background": [0, 0, 0], "max_depth": 1}, f)
    cases.append(("needles", obj, render))
    return cases
